//! Summation-by-parts (SBP) first-derivative operators on uniform and mapped time grids.
//!
//! The grid is `t_k = t_i + k·Δt`, `k = 0, …, N−1` (the paper counts from 1). An SBP
//! operator is a pair of a diagonal norm `H` (quadrature weights, `∫ f g dt ≈ fᵀ H g`,
//! Δt included) and a derivative matrix `D = H⁻¹ Q` whose `Q` satisfies the discrete
//! integration-by-parts identity
//!
//! ```text
//! Q + Qᵀ = B = diag(−1, 0, …, 0, 1).
//! ```
//!
//! Four diagonal-norm operators are provided, named `SBP<boundary order><interior
//! order><boundary order>` as in the paper:
//!
//! | kind | interior order | boundary order | `H` integrates exactly | boundary rows | min. nodes |
//! |------|----------------|----------------|------------------------|---------------|-----------|
//! | [`OperatorKind::Sbp121`] | 2 | 1 | degree 1 (trapezoid rule) | 1 | 2 |
//! | [`OperatorKind::Sbp242`] | 4 | 2 | degree 3 | 4 | 8 |
//! | [`OperatorKind::Sbp363`] | 6 | 3 | degree 5 | 6 | 12 |
//! | [`OperatorKind::Sbp484`] | 8 | 4 | degree 7 | 8 | 16 |
//!
//! The fourth-order operator is called SBP242 here and in the code; the paper's text
//! calls the same operator SBP424, so `"SBP424"` is accepted as an alias when parsing.
//!
//! The coefficients are kept apart from the construction as exact fractions (module
//! [`coefficients`]); every one of them was checked in exact rational arithmetic to satisfy
//! the SBP identity and the accuracy conditions (see the documentation there); the tests
//! are in `sbp/tests.rs`.
//!
//! # Dissipative operators
//!
//! Each centred operator has a dissipative sibling, `SBP121-AD`, `SBP242-AD`,
//! `SBP363-AD`, `SBP484-AD` ([`OperatorKind::DISSIPATIVE`]): the centred `D` plus
//! SBP-compatible artificial dissipation (Mattsson, Svärd & Nordström, *Stable and
//! accurate artificial dissipation*, J. Sci. Comput. 21 (2004) 57–79),
//!
//! ```text
//! D+ = D − ε H⁻¹ D_pᵀ D_p,   D− = D + ε H⁻¹ D_pᵀ D_p,   ε = 1/10,  p = boundary order + 1,
//! ```
//!
//! `D_p` the undivided `p`-th difference (with `B_p = I`, a simplification of MSN2004's
//! `D_pᵀ B_p D_p`; module [`dissipation`]). `(H, D+, D−)` is an upwind SBP pair
//! (Mattsson, *Diagonal-norm upwind SBP operators*, J. Comput. Phys. 335 (2017)
//! 283–310):
//!
//! ```text
//! H D+ + (H D−)ᵀ = B,   (D+ + D−)/2 = D,   H (D+ − D−) = −2ε D_pᵀ D_p ≤ 0.
//! ```
//!
//! The norm, the orders, the quadrature and the exactness degrees are the centred
//! operator's; the stencils are wider (interior half-width `p` instead of the centred
//! radius), and `SBP121-AD` has two boundary rows instead of one (min. 4 nodes). The
//! [`SbpOperator`] of a dissipative kind is `D+`, the operator of every time derivative in
//! the action; [`SbpOperator::partner`] is `D−`, which summation by parts puts into the
//! equations of motion (docs/mathematics.md §3). `D+` damps the odd-even mode of the
//! centred stencils that damping or contraction amplifies. Its coefficients are not
//! tabulated: they are built in exact rational arithmetic from the centred tables, the
//! binomial coefficients and ε, and the tests compare them with an independent table.
//!
//! [`OperatorKind::ALL`] lists all eight kinds (parsing, listings);
//! [`OperatorKind::CENTRED`] the centred family, an order ladder from SBP121 to SBP484.
//!
//! # Mapped grids
//!
//! [`SbpOperator::on_times`] builds any kind on nodes `t_k = t(ξ_k)` of a smooth
//! increasing map of a uniform grid in `ξ`: `D_t = J⁻¹ D_ξ` and `H_t = H_ξ J` with the
//! stretch `J = diag(D_ξ t)`. `H_t D_t = H_ξ D_ξ`, so every identity above holds as on the
//! uniform grid (Svärd & Nordström's coordinate transforms; SummationByPartsOperators.jl
//! treats them the same way); the derivation is in docs/mathematics.md#mapped-time-grids.
//!
//! **Place in the flow.** The first stage: the operators are numbers on a grid and use
//! nothing else of this crate (their tests fit observed orders with
//! [`convergence`](crate::convergence), which is as low). The scene names its operator
//! ([`OperatorKind`]), so everything after it may use this module.

use std::fmt;
use std::str::FromStr;

/// A fraction `numerator / denominator` of two integers.
pub type Frac = (i64, i64);

pub mod coefficients;
pub mod dissipation;

/// The centred coefficient set of one operator kind (a dissipative kind's is its centred
/// operator's).
struct Coefficients {
    norm: &'static [Frac],
    boundary: &'static [&'static [Frac]],
    interior: &'static [Frac],
}

/// The coefficients of `Δt·D` (for a dissipative kind `Δt·D+`) as exact fractions.
struct Blocks {
    norm: &'static [Frac],
    /// Row `i` of the left closure, from column 0.
    left: Vec<Vec<Frac>>,
    /// Row `N−1−i` of the right closure, entry `j` for column `N−1−j`.
    right: Vec<Vec<Frac>>,
    /// The interior stencil at offsets `−r..=r`.
    interior: Vec<Frac>,
}

fn frac(f: Frac) -> f64 {
    f.0 as f64 / f.1 as f64
}

/// Which SBP first-derivative operator to use.
///
/// Serialized as its canonical name (`"SBP121"`, `"SBP242"`, `"SBP363"`, `"SBP484"`,
/// `"SBP121-AD"`, `"SBP242-AD"`, `"SBP363-AD"`, `"SBP484-AD"`); deserialization also takes
/// the lower-case names and the alias `"SBP424"` of SBP242. [`FromStr`] is
/// case-insensitive and also takes the dissipative names without the hyphen
/// (`"SBP242AD"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum OperatorKind {
    /// Second order inside, first order at the boundary; trapezoid-rule norm.
    #[serde(rename = "SBP121", alias = "sbp121", alias = "Sbp121")]
    Sbp121,
    /// Fourth order inside, second order at the boundary (the paper's text calls it SBP424).
    #[serde(rename = "SBP242", alias = "sbp242", alias = "Sbp242", alias = "SBP424", alias = "sbp424")]
    Sbp242,
    /// Sixth order inside, third order at the boundary.
    #[serde(rename = "SBP363", alias = "sbp363", alias = "Sbp363")]
    Sbp363,
    /// Eighth order inside, fourth order at the boundary.
    #[serde(rename = "SBP484", alias = "sbp484", alias = "Sbp484")]
    Sbp484,
    /// SBP121 with artificial dissipation of order 2 (see the module documentation).
    #[serde(rename = "SBP121-AD", alias = "sbp121-ad")]
    Sbp121Ad,
    /// SBP242 with artificial dissipation of order 3.
    #[serde(rename = "SBP242-AD", alias = "sbp242-ad")]
    Sbp242Ad,
    /// SBP363 with artificial dissipation of order 4.
    #[serde(rename = "SBP363-AD", alias = "sbp363-ad")]
    Sbp363Ad,
    /// SBP484 with artificial dissipation of order 5.
    #[serde(rename = "SBP484-AD", alias = "sbp484-ad")]
    Sbp484Ad,
}

impl OperatorKind {
    /// The centred operators, from lowest to highest order: the order ladder
    /// (a remedy's "higher-order operator" climbs it).
    pub const CENTRED: [OperatorKind; 4] = [OperatorKind::Sbp121, OperatorKind::Sbp242, OperatorKind::Sbp363, OperatorKind::Sbp484];

    /// The dissipative operators, from lowest to highest order, in the order of their
    /// centred operators.
    pub const DISSIPATIVE: [OperatorKind; 4] =
        [OperatorKind::Sbp121Ad, OperatorKind::Sbp242Ad, OperatorKind::Sbp363Ad, OperatorKind::Sbp484Ad];

    /// Every operator kind: the centred ones from lowest to highest order, then the
    /// dissipative ones in the same order (for parsing and listing; an order ladder
    /// iterates [`CENTRED`](Self::CENTRED) or [`DISSIPATIVE`](Self::DISSIPATIVE)).
    pub const ALL: [OperatorKind; 8] = [
        OperatorKind::Sbp121,
        OperatorKind::Sbp242,
        OperatorKind::Sbp363,
        OperatorKind::Sbp484,
        OperatorKind::Sbp121Ad,
        OperatorKind::Sbp242Ad,
        OperatorKind::Sbp363Ad,
        OperatorKind::Sbp484Ad,
    ];

    /// Canonical name: `"SBP121"`, `"SBP242"`, `"SBP363"`, `"SBP484"`, `"SBP121-AD"`,
    /// `"SBP242-AD"`, `"SBP363-AD"`, `"SBP484-AD"`.
    pub fn name(self) -> &'static str {
        match self {
            OperatorKind::Sbp121 => "SBP121",
            OperatorKind::Sbp242 => "SBP242",
            OperatorKind::Sbp363 => "SBP363",
            OperatorKind::Sbp484 => "SBP484",
            OperatorKind::Sbp121Ad => "SBP121-AD",
            OperatorKind::Sbp242Ad => "SBP242-AD",
            OperatorKind::Sbp363Ad => "SBP363-AD",
            OperatorKind::Sbp484Ad => "SBP484-AD",
        }
    }

    /// The centred operator: the kind itself, or the one a dissipative kind is built on.
    pub fn centred(self) -> OperatorKind {
        match self {
            OperatorKind::Sbp121Ad => OperatorKind::Sbp121,
            OperatorKind::Sbp242Ad => OperatorKind::Sbp242,
            OperatorKind::Sbp363Ad => OperatorKind::Sbp363,
            OperatorKind::Sbp484Ad => OperatorKind::Sbp484,
            centred => centred,
        }
    }

    /// The dissipative operator built on this kind's centred operator (a dissipative
    /// kind is its own).
    pub fn dissipative(self) -> OperatorKind {
        match self.centred() {
            OperatorKind::Sbp121 => OperatorKind::Sbp121Ad,
            OperatorKind::Sbp242 => OperatorKind::Sbp242Ad,
            OperatorKind::Sbp363 => OperatorKind::Sbp363Ad,
            _ => OperatorKind::Sbp484Ad,
        }
    }

    /// Whether the operator carries artificial dissipation (`D+ ≠ D−`).
    pub fn is_dissipative(self) -> bool {
        self != self.centred()
    }

    /// The order `p` of the dissipation `ε H⁻¹ D_pᵀ D_p` (boundary order + 1: 2, 3, 4, 5),
    /// or `None` for a centred operator.
    pub fn dissipation_order(self) -> Option<usize> {
        self.is_dissipative().then(|| self.boundary_order() + 1)
    }

    /// Order of accuracy of the interior stencil: 2, 4, 6, 8 (a dissipative kind's is
    /// its centred operator's: the dissipation is of higher order there).
    pub fn interior_order(self) -> usize {
        match self.centred() {
            OperatorKind::Sbp121 => 2,
            OperatorKind::Sbp242 => 4,
            OperatorKind::Sbp363 => 6,
            _ => 8,
        }
    }

    /// Order of accuracy of the boundary rows: 1, 2, 3, 4.
    pub fn boundary_order(self) -> usize {
        self.interior_order() / 2
    }

    /// Highest polynomial degree the norm `H` integrates exactly: `2·boundary_order − 1`
    /// (1 for the trapezoid rule of SBP121, 3 for SBP242, 5 for SBP363, 7 for SBP484).
    pub fn quadrature_degree(self) -> usize {
        2 * self.boundary_order() - 1
    }

    /// Number of rows at each end of the grid whose stencil is a boundary closure
    /// (1, 4, 6, 8; 2, 4, 6, 8 for the dissipative kinds); the rows in between use the
    /// interior stencil.
    pub fn boundary_rows(self) -> usize {
        let centred = self.coefficients().boundary.len();
        self.dissipation_order().map_or(centred, |p| centred.max(p))
    }

    /// Literature reference for the coefficients.
    pub fn source(self) -> &'static str {
        match self {
            OperatorKind::Sbp121 => {
                "classic second-order SBP operator (trapezoid norm); B. Strand, J. Comput. Phys. 110 (1994) 47-67"
            }
            OperatorKind::Sbp242 => {
                "B. Strand, J. Comput. Phys. 110 (1994) 47-67; K. Mattsson and J. Nordstrom, J. Comput. Phys. 199 (2004) 503-540"
            }
            OperatorKind::Sbp363 => {
                "K. Mattsson and J. Nordstrom, J. Comput. Phys. 199 (2004) 503-540 (exact fractions as in SummationByPartsOperators.jl, MattssonNordstrom2004)"
            }
            OperatorKind::Sbp484 => {
                "K. Mattsson and J. Nordstrom, J. Comput. Phys. 199 (2004) 503-540, order 8 (exact fractions as in SummationByPartsOperators.jl, MattssonNordstrom2004)"
            }
            _ => {
                "the centred operator plus artificial dissipation -eps H^-1 D_p^T D_p (eps = 1/10, B_p = I): K. Mattsson, M. Svard and \
                 J. Nordstrom, J. Sci. Comput. 21 (2004) 57-79; an upwind SBP pair as in K. Mattsson, J. Comput. Phys. 335 (2017) 283-310"
            }
        }
    }

    /// Smallest number of grid nodes for which the operator is defined (the two boundary
    /// blocks must not overlap): 2 for SBP121, 4 for SBP121-AD, 8 for SBP242(-AD), 12 for
    /// SBP363(-AD), 16 for SBP484(-AD).
    pub fn min_nodes(self) -> usize {
        2 * self.boundary_rows()
    }

    /// The centred coefficient tables of this kind's centred operator.
    fn coefficients(self) -> Coefficients {
        use coefficients::*;
        match self.centred() {
            OperatorKind::Sbp121 => Coefficients { norm: &H_121, boundary: &D_121, interior: &INTERIOR_121 },
            OperatorKind::Sbp242 => Coefficients { norm: &H_242, boundary: &D_242, interior: &INTERIOR_242 },
            OperatorKind::Sbp363 => Coefficients { norm: &H_363, boundary: &D_363, interior: &INTERIOR_363 },
            _ => Coefficients { norm: &H_484, boundary: &D_484, interior: &INTERIOR_484 },
        }
    }

    /// The exact coefficients of `Δt·D` (`Δt·D+` for a dissipative kind): the centred
    /// tables with the right closure the negated mirror of the left one, or the
    /// construction of [`dissipation`].
    fn blocks(self) -> Blocks {
        let c = self.coefficients();
        match self.dissipation_order() {
            None => {
                let left: Vec<Vec<Frac>> = c.boundary.iter().map(|row| row.to_vec()).collect();
                let right = left.iter().map(|row| row.iter().map(|&(a, b)| (-a, b)).collect()).collect();
                Blocks { norm: c.norm, left, right, interior: c.interior.to_vec() }
            }
            Some(p) => {
                let b = dissipation::blocks(c.norm, c.boundary, c.interior, p);
                Blocks { norm: c.norm, left: b.left, right: b.right, interior: b.interior }
            }
        }
    }
}

impl fmt::Display for OperatorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Error of parsing an [`OperatorKind`] from a string.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown SBP operator `{input}`: expected one of SBP121, SBP242 (alias SBP424), SBP363, SBP484, or a dissipative SBP121-AD, \
     SBP242-AD, SBP363-AD, SBP484-AD (case-insensitive)"
)]
pub struct ParseOperatorKindError {
    /// The rejected input.
    pub input: String,
}

impl FromStr for OperatorKind {
    type Err = ParseOperatorKindError;

    /// Case-insensitive; surrounding whitespace is ignored. `"SBP424"` (the paper's name
    /// for the fourth-order operator) is an alias of `"SBP242"`; a dissipative kind is
    /// its centred name with the suffix `-AD` (or `AD`).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let upper = s.trim().to_ascii_uppercase();
        let (centred, dissipative) = match upper.strip_suffix("-AD").or_else(|| upper.strip_suffix("AD")) {
            Some(base) => (base, true),
            None => (upper.as_str(), false),
        };
        let kind = match centred {
            "SBP121" => OperatorKind::Sbp121,
            "SBP242" | "SBP424" => OperatorKind::Sbp242,
            "SBP363" => OperatorKind::Sbp363,
            "SBP484" => OperatorKind::Sbp484,
            _ => return Err(ParseOperatorKindError { input: s.to_string() }),
        };
        Ok(if dissipative { kind.dissipative() } else { kind })
    }
}

/// Error of building an [`SbpOperator`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SbpError {
    /// The grid has fewer nodes than the operator's two boundary blocks need.
    #[error("{kind} needs at least {min} grid nodes, got {nodes}")]
    TooFewNodes {
        /// The operator.
        kind: OperatorKind,
        /// The nodes asked for.
        nodes: usize,
        /// The operator's minimum ([`OperatorKind::min_nodes`]).
        min: usize,
    },
    /// The time step is not finite and positive.
    #[error("the time step must be finite and positive, got {0}")]
    BadStep(f64),
    /// A mapped grid's nodes are not finite and strictly increasing.
    #[error("the grid's nodes must increase: node {node} is at t = {time}, after t = {previous}")]
    NotIncreasing {
        /// The node (from 0).
        node: usize,
        /// Its time.
        time: f64,
        /// The time of the node before it.
        previous: f64,
    },
    /// A mapped grid's nodes are not increasing smoothly enough: the stretch `D_ξ t` is
    /// not positive at a node. (A high-order operator's boundary closure is the most
    /// sensitive: an adaptive grid that `SBP363` takes can be too uneven for `SBP484`.)
    #[error(
        "the grid's nodes are spread too unevenly for {}: at node {node} (t = {time:.6}) its stretch D t is {stretch:.3}, where it must be positive; more nodes, a lower-order operator or the uniform grid avoid this",
        kind.name()
    )]
    BadStretch {
        /// The operator.
        kind: OperatorKind,
        /// The node (from 0).
        node: usize,
        /// Its time.
        time: f64,
        /// Its stretch.
        stretch: f64,
    },
}

/// An SBP first-derivative operator on a uniform grid of `n` nodes with step `dt`,
/// applied matrix-free (as SummationByPartsOperators.jl does): the left boundary
/// closure rows, the interior stencil on every row in between, and the right closure.
/// For a centred kind the right closure mirrors the left one with the opposite sign
/// (`D[N−1−i, N−1−j] = −D[i, j]`, 0-based); for a dissipative kind it does not, and
/// the operator is `D+` ([`partner`](Self::partner) gives `D−`). Only the nonzero
/// coefficients (Δt included) are stored.
#[derive(Debug, Clone)]
pub struct SbpOperator {
    kind: OperatorKind,
    n: usize,
    dt: f64,
    h: Vec<f64>,
    /// Nonzero entries `(column, D[i, column])` of each left boundary row `i`, columns ascending.
    left: Vec<Vec<(usize, f64)>>,
    /// Nonzero entries `(j, D[N−1−i, N−1−j])` of each right boundary row `N−1−i`, `j` ascending.
    right: Vec<Vec<(usize, f64)>>,
    /// Nonzero entries `(k, D[i, i − r + k])` of the interior stencil of half-width `r`.
    interior: Vec<(usize, f64)>,
    /// Half-width `r` of the interior stencil.
    radius: usize,
    /// Whether this is the partner `D−` of the kind's operator `D+` (for a centred kind
    /// the two are equal).
    minus: bool,
    /// On a mapped grid ([`SbpOperator::on_times`]), the stretch `J_k = (D_ξ t)_k` of each
    /// node: the rows above are those of the uniform grid in `ξ`, and row `k` of the
    /// operator is theirs divided by `J_k` (the norm, above, already includes it).
    stretch: Option<Vec<f64>>,
}

/// Which part of the operator row `i` belongs to.
enum Part {
    /// A left boundary row (its index in the closure).
    Left(usize),
    /// An interior row.
    Interior,
    /// A right boundary row: row `N−1−m`.
    Right(usize),
}

impl SbpOperator {
    /// Build the operator of `kind` on `n` nodes with step `dt` (finite, `> 0`).
    pub fn new(kind: OperatorKind, n: usize, dt: f64) -> Result<Self, SbpError> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(SbpError::BadStep(dt));
        }
        let min = kind.min_nodes();
        if n < min {
            return Err(SbpError::TooFewNodes { kind, nodes: n, min });
        }
        let c = kind.blocks();
        let mut h = vec![dt; n];
        for (i, &w) in c.norm.iter().enumerate() {
            h[i] = frac(w) * dt;
            h[n - 1 - i] = frac(w) * dt;
        }
        // Structural zeros are left out, so that rows list exactly the nonzero entries.
        let nonzero = |row: &[Frac]| -> Vec<(usize, f64)> {
            row.iter().enumerate().filter(|(_, v)| v.0 != 0).map(|(j, &v)| (j, frac(v) / dt)).collect()
        };
        let left = c.left.iter().map(|row| nonzero(row)).collect();
        let right = c.right.iter().map(|row| nonzero(row)).collect();
        let interior = nonzero(&c.interior);
        Ok(SbpOperator { kind, n, dt, h, left, right, interior, radius: c.interior.len() / 2, minus: false, stretch: None })
    }

    /// Build the operator of `kind` on the nodes `times` (strictly increasing), a smooth
    /// map `t(ξ)` of a uniform grid in `ξ` whose step is their mean spacing: with `D_ξ`,
    /// `H_ξ` the operator on that uniform grid and the stretch `J = diag(D_ξ t)` (the
    /// centred operator's, for both members of a dissipative pair),
    ///
    /// ```text
    /// D_t = J⁻¹ D_ξ,   H_t = H_ξ J,   so   H_t D_t = H_ξ D_ξ = Q_ξ:
    /// ```
    ///
    /// the summation-by-parts identity, the boundary matrix `B` and the partner relation
    /// are the uniform grid's, and the orders of accuracy are too on a smooth map
    /// (docs/mathematics.md#mapped-time-grids). `D_t` differentiates linear functions of
    /// `t` exactly, as on a uniform grid (a dissipative `D±_t` to its order: its
    /// dissipation does not vanish on the map). Fails where the nodes are too few, not
    /// finite and increasing, or so unevenly spread that some `J_k` is not positive.
    pub fn on_times(kind: OperatorKind, times: &[f64]) -> Result<Self, SbpError> {
        let n = times.len();
        let min = kind.min_nodes();
        if n < min {
            return Err(SbpError::TooFewNodes { kind, nodes: n, min });
        }
        if let Some(k) = (1..n).find(|&k| !(times[k].is_finite() && times[k] > times[k - 1])) {
            return Err(SbpError::NotIncreasing { node: k, time: times[k], previous: times[k - 1] });
        }
        let dt = (times[n - 1] - times[0]) / (n - 1) as f64;
        let mut op = SbpOperator::new(kind, n, dt)?;
        // Relative to the first node, so that the stretch does not carry the rounding of
        // a large start time.
        let relative: Vec<f64> = times.iter().map(|t| t - times[0]).collect();
        let mut stretch = vec![0.0; n];
        SbpOperator::new(kind.centred(), n, dt)?.apply(&relative, &mut stretch);
        if let Some(k) = stretch.iter().position(|j| !(j.is_finite() && *j > 0.0)) {
            return Err(SbpError::BadStretch { kind, node: k, time: times[k], stretch: stretch[k] });
        }
        for (h, j) in op.h.iter_mut().zip(&stretch) {
            *h *= j;
        }
        op.stretch = Some(stretch);
        Ok(op)
    }

    /// The stretch `J_k = dt/dξ` of each node on a mapped grid, `None` on a uniform one.
    pub fn stretch(&self) -> Option<&[f64]> {
        self.stretch.as_deref()
    }

    /// The SBP partner `D− = −J D J` (`J` the flip of the grid): `H D + (H D−)ᵀ = B`.
    /// For a centred kind it is the operator itself; for a dissipative kind's `D+` it is
    /// `D−`, the operator of the equations of motion (and the partner of `D−` is `D+`).
    pub fn partner(&self) -> SbpOperator {
        let negated = |rows: &[Vec<(usize, f64)>]| -> Vec<Vec<(usize, f64)>> {
            rows.iter().map(|row| row.iter().map(|&(j, c)| (j, -c)).collect()).collect()
        };
        let width = 2 * self.radius;
        let interior = self.interior.iter().rev().map(|&(k, c)| (width - k, -c)).collect();
        SbpOperator {
            left: negated(&self.right),
            right: negated(&self.left),
            interior,
            minus: !self.minus && self.kind.is_dissipative(),
            ..self.clone()
        }
    }

    /// Whether this is the partner `D−` of a dissipative kind ([`partner`](Self::partner)).
    pub fn is_partner(&self) -> bool {
        self.minus
    }

    /// The operator kind.
    pub fn kind(&self) -> OperatorKind {
        self.kind
    }

    /// Number of grid nodes `N`.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Always `false`: an operator has at least [`OperatorKind::min_nodes`] nodes.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The time step Δt of the uniform grid (on a mapped grid, of the uniform grid in ξ:
    /// the mean spacing).
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Diagonal of the norm `H` (quadrature weights, Δt included).
    pub fn norm(&self) -> &[f64] {
        &self.h
    }

    fn part(&self, i: usize) -> Part {
        let b = self.left.len();
        if i < b {
            Part::Left(i)
        } else if i >= self.n - b {
            Part::Right(self.n - 1 - i)
        } else {
            Part::Interior
        }
    }

    /// The nonzero entries `(column, D[i, column])` of row `i` of `D`, sorted by column.
    ///
    /// # Panics
    /// If `i >= self.len()`.
    pub fn row(&self, i: usize) -> Vec<(usize, f64)> {
        let mut row = Vec::new();
        self.push_row(i, &mut row);
        row
    }

    /// [`row`](Self::row) appended to `out`, without allocating beyond `out`'s growth.
    ///
    /// # Panics
    /// If `i >= self.len()`.
    pub fn push_row(&self, i: usize, out: &mut Vec<(usize, f64)>) {
        assert!(i < self.n, "SbpOperator::row: row {i} of an operator on {} nodes", self.n);
        let start = out.len();
        match self.part(i) {
            Part::Left(m) => out.extend_from_slice(&self.left[m]),
            Part::Interior => out.extend(self.interior.iter().map(|&(k, c)| (i + k - self.radius, c))),
            Part::Right(m) => out.extend(self.right[m].iter().rev().map(|&(j, c)| (self.n - 1 - j, c))),
        }
        if let Some(stretch) = &self.stretch {
            out[start..].iter_mut().for_each(|(_, c)| *c /= stretch[i]);
        }
    }

    /// `out = D u` without allocating.
    ///
    /// # Panics
    /// If `u` or `out` does not have [`len`](Self::len) entries.
    pub fn apply(&self, u: &[f64], out: &mut [f64]) {
        assert_eq!(u.len(), self.n, "SbpOperator::apply: u has the wrong length");
        assert_eq!(out.len(), self.n, "SbpOperator::apply: out has the wrong length");
        self.apply_strided(u, 1, 0, out);
    }

    /// `out[i] = Σ_j D[i, j] · u[offset + j·stride]`: `D` applied to one component of
    /// node-major interleaved data (e.g. `stride` = number of coordinates). Each row sums
    /// its nonzero entries in ascending column order.
    ///
    /// # Panics
    /// If `stride == 0`, `out.len() != self.len()`, or `u` is too short for the last node.
    pub fn apply_strided(&self, u: &[f64], stride: usize, offset: usize, out: &mut [f64]) {
        assert!(stride > 0, "SbpOperator::apply_strided: stride must be positive");
        assert_eq!(out.len(), self.n, "SbpOperator::apply_strided: out has the wrong length");
        assert!(offset + (self.n - 1) * stride < u.len(), "SbpOperator::apply_strided: u is too short");
        let at = |j: usize| u[offset + j * stride];
        for (i, o) in out.iter_mut().enumerate() {
            *o = match self.part(i) {
                Part::Left(m) => self.left[m].iter().fold(0.0, |acc, &(j, c)| acc + c * at(j)),
                Part::Interior => self.interior.iter().fold(0.0, |acc, &(k, c)| acc + c * at(i + k - self.radius)),
                Part::Right(m) => self.right[m].iter().rev().fold(0.0, |acc, &(j, c)| acc + c * at(self.n - 1 - j)),
            };
        }
        if let Some(stretch) = &self.stretch {
            out.iter_mut().zip(stretch).for_each(|(o, j)| *o /= j);
        }
    }
}

#[cfg(test)]
mod tests;
