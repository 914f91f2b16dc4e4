//! Summation-by-parts (SBP) first-derivative operators on a uniform time grid.
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
//! **Place in the flow.** The first stage: the operators are numbers on a grid and use
//! nothing else of this crate (their tests fit observed orders with
//! [`convergence`](crate::convergence), which is as low). The scene names its operator
//! ([`OperatorKind`]), so everything after it may use this module.

use std::fmt;
use std::str::FromStr;

/// A fraction `numerator / denominator` of two integers.
pub type Frac = (i64, i64);

pub mod coefficients;

/// The coefficient set of one operator kind.
struct Coefficients {
    norm: &'static [Frac],
    boundary: &'static [&'static [Frac]],
    interior: &'static [Frac],
}

fn frac(f: Frac) -> f64 {
    f.0 as f64 / f.1 as f64
}

/// Which SBP first-derivative operator to use.
///
/// Serialized as its canonical name (`"SBP121"`, `"SBP242"`, `"SBP363"`, `"SBP484"`); deserialization
/// also takes the lower-case names and the alias `"SBP424"` of SBP242. [`FromStr`] is
/// case-insensitive.
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
}

impl OperatorKind {
    /// Every operator kind, from lowest to highest order.
    pub const ALL: [OperatorKind; 4] = [OperatorKind::Sbp121, OperatorKind::Sbp242, OperatorKind::Sbp363, OperatorKind::Sbp484];

    /// Canonical name: `"SBP121"`, `"SBP242"`, `"SBP363"`, `"SBP484"`.
    pub fn name(self) -> &'static str {
        match self {
            OperatorKind::Sbp121 => "SBP121",
            OperatorKind::Sbp242 => "SBP242",
            OperatorKind::Sbp363 => "SBP363",
            OperatorKind::Sbp484 => "SBP484",
        }
    }

    /// Order of accuracy of the interior (central) stencil: 2, 4, 6, 8.
    pub fn interior_order(self) -> usize {
        match self {
            OperatorKind::Sbp121 => 2,
            OperatorKind::Sbp242 => 4,
            OperatorKind::Sbp363 => 6,
            OperatorKind::Sbp484 => 8,
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
    /// (1, 4, 6, 8); the rows in between use the interior stencil.
    pub fn boundary_rows(self) -> usize {
        self.coefficients().boundary.len()
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
        }
    }

    /// Smallest number of grid nodes for which the operator is defined (the two boundary
    /// blocks must not overlap): 2 for SBP121, 8 for SBP242, 12 for SBP363, 16 for SBP484.
    pub fn min_nodes(self) -> usize {
        2 * self.boundary_rows()
    }

    fn coefficients(self) -> Coefficients {
        use coefficients::*;
        match self {
            OperatorKind::Sbp121 => Coefficients { norm: &H_121, boundary: &D_121, interior: &INTERIOR_121 },
            OperatorKind::Sbp242 => Coefficients { norm: &H_242, boundary: &D_242, interior: &INTERIOR_242 },
            OperatorKind::Sbp363 => Coefficients { norm: &H_363, boundary: &D_363, interior: &INTERIOR_363 },
            OperatorKind::Sbp484 => Coefficients { norm: &H_484, boundary: &D_484, interior: &INTERIOR_484 },
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
#[error("unknown SBP operator `{input}`: expected one of SBP121, SBP242 (alias SBP424), SBP363, SBP484 (case-insensitive)")]
pub struct ParseOperatorKindError {
    /// The rejected input.
    pub input: String,
}

impl FromStr for OperatorKind {
    type Err = ParseOperatorKindError;

    /// Case-insensitive; surrounding whitespace is ignored. `"SBP424"` (the paper's name
    /// for the fourth-order operator) is an alias of `"SBP242"`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_uppercase().as_str() {
            "SBP121" => Ok(OperatorKind::Sbp121),
            "SBP242" | "SBP424" => Ok(OperatorKind::Sbp242),
            "SBP363" => Ok(OperatorKind::Sbp363),
            "SBP484" => Ok(OperatorKind::Sbp484),
            _ => Err(ParseOperatorKindError { input: s.to_string() }),
        }
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
}

/// An SBP first-derivative operator on a uniform grid of `n` nodes with step `dt`,
/// applied matrix-free (as SummationByPartsOperators.jl does): the left boundary
/// closure rows, the interior stencil on every row in between, and the right closure,
/// which mirrors the left one with the opposite sign
/// (`D[N−1−i, N−1−j] = −D[i, j]`, 0-based). Only the nonzero coefficients of `D`
/// (Δt included) are stored.
#[derive(Debug, Clone)]
pub struct SbpOperator {
    kind: OperatorKind,
    n: usize,
    dt: f64,
    h: Vec<f64>,
    /// Nonzero entries `(column, D[i, column])` of each left boundary row `i`, columns ascending.
    left: Vec<Vec<(usize, f64)>>,
    /// Nonzero entries `(k, D[i, i − r + k])` of the interior stencil of half-width `r`.
    interior: Vec<(usize, f64)>,
    /// Half-width `r` of the interior stencil.
    radius: usize,
}

/// Which part of the operator row `i` belongs to.
enum Part {
    /// A left boundary row (its index in the closure).
    Left(usize),
    /// An interior row.
    Interior,
    /// A right boundary row: the mirror of left boundary row `m`.
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
        let c = kind.coefficients();
        let mut h = vec![dt; n];
        for (i, &w) in c.norm.iter().enumerate() {
            h[i] = frac(w) * dt;
            h[n - 1 - i] = frac(w) * dt;
        }
        // Structural zeros are left out, so that rows list exactly the nonzero entries.
        let nonzero = |row: &[Frac]| -> Vec<(usize, f64)> {
            row.iter().enumerate().filter(|(_, v)| v.0 != 0).map(|(j, &v)| (j, frac(v) / dt)).collect()
        };
        let left = c.boundary.iter().map(|row| nonzero(row)).collect();
        let interior = nonzero(c.interior);
        Ok(SbpOperator { kind, n, dt, h, left, interior, radius: c.interior.len() / 2 })
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

    /// The time step Δt.
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
        assert!(i < self.n, "SbpOperator::row: row {i} of an operator on {} nodes", self.n);
        match self.part(i) {
            Part::Left(m) => self.left[m].clone(),
            Part::Interior => self.interior.iter().map(|&(k, c)| (i + k - self.radius, c)).collect(),
            Part::Right(m) => self.left[m].iter().rev().map(|&(j, c)| (self.n - 1 - j, -c)).collect(),
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
                Part::Right(m) => self.left[m].iter().rev().fold(0.0, |acc, &(j, c)| acc + -c * at(self.n - 1 - j)),
            };
        }
    }
}

#[cfg(test)]
mod tests;
