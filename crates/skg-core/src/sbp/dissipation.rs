//! The dissipative operators `SBP…-AD`, built exactly from the centred ones.
//!
//! A dissipative operator is a centred operator `(H, D)` plus SBP-compatible artificial
//! dissipation in the style of Mattsson, Svärd & Nordström (2004):
//!
//! ```text
//! D+ = D − ε H⁻¹ D_pᵀ D_p,        D− = D + ε H⁻¹ D_pᵀ D_p   (its partner),
//! ```
//!
//! with `ε` = [`EPSILON`] = 1/10 and `D_p` the `(N − p) × N` matrix of undivided `p`-th
//! differences, `(D_p u)_k = Σ_{l=0..p} (−1)^{p−l} C(p, l) u_{k+l}`, and `p` one more than
//! the boundary order ([`OperatorKind::dissipation_order`](super::OperatorKind::dissipation_order)). MSN2004 write the dissipation as
//! `H⁻¹ D_pᵀ B_p D_p` with a boundary-aware weight `B_p`; here `B_p = I` and `D_p` has no
//! boundary rows, a simplification measured to keep every property below
//! (docs/mathematics.md §3).
//!
//! Every property the solver relies on follows from the form of the added term:
//!
//! * `H(D+ − D−)/2 = −ε D_pᵀ D_p` is symmetric and negative semidefinite, so
//!   `(H, D+, D−)` is an upwind SBP pair (Mattsson 2017): `H D+ + (H D−)ᵀ = B`;
//! * `(D+ + D−)/2 = D` exactly;
//! * `D_p` annihilates the polynomials of degree `< p`, and away from the ends
//!   `D_pᵀ D_p = (−1)^p δ^{2p}` those of degree `< 2p`: `D±` are exact to the same degree
//!   as `D` in every row (the boundary order) and in the interior rows (the interior
//!   order); the added interior term is `ε Δt^{2p−1} u^{(2p)}`;
//! * the norm `H` is the centred operator's; `D_pᵀ D_p` is persymmetric, so the right
//!   closure of `D+` is `−` (mirror of `D`'s left closure) `−` (mirror of the left
//!   dissipation): it is no longer the negated mirror of `D+`'s left closure, and the
//!   operator stores both (and `D− = −J D+ J`, `J` the flip).
//!
//! The closures are independent of N once `N ≥ 2·max(boundary rows of D, p)`; they are
//! computed here in exact rational arithmetic from the centred tables, the binomial
//! coefficients and ε, and rounded to `f64` once, like the centred fractions.

use super::Frac;

/// The dissipation coefficient ε of every `-AD` operator (1/10: the measured error is
/// flat within 2× over 1/24 … 1/4, docs/mathematics.md §3).
pub const EPSILON: Frac = (1, 10);

/// An exact fraction with a positive denominator, in lowest terms.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Ratio {
    n: i128,
    d: i128,
}

fn gcd(a: i128, b: i128) -> i128 {
    let (mut a, mut b) = (a.abs(), b.abs());
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

impl Ratio {
    fn new(n: i128, d: i128) -> Ratio {
        let g = gcd(n, d).max(1) * d.signum();
        Ratio { n: n / g, d: d / g }
    }
    fn from_frac(f: Frac) -> Ratio {
        Ratio::new(f.0 as i128, f.1 as i128)
    }
    fn add(self, o: Ratio) -> Ratio {
        Ratio::new(self.n * o.d + o.n * self.d, self.d * o.d)
    }
    fn mul(self, o: Ratio) -> Ratio {
        Ratio::new(self.n * o.n, self.d * o.d)
    }
    fn neg(self) -> Ratio {
        Ratio { n: -self.n, d: self.d }
    }
    fn recip(self) -> Ratio {
        Ratio::new(self.d, self.n)
    }
    /// As an `i64` fraction. Every entry of the four operators fits (the largest
    /// denominator is about 3·10⁸); a failure is a bug in the tables, which the tests
    /// catch for every kind.
    fn to_frac(self) -> Frac {
        (i64::try_from(self.n).expect("numerator fits in i64"), i64::try_from(self.d).expect("denominator fits in i64"))
    }
}

fn binomial(n: usize, k: usize) -> i128 {
    (0..k).fold(1i128, |acc, i| acc * (n - i) as i128 / (i + 1) as i128)
}

/// The stencil of one row of `D_p`: `c_l = (−1)^{p−l} C(p, l)`, `l = 0..=p`.
fn difference_stencil(p: usize) -> Vec<i128> {
    (0..=p).map(|l| if (p - l).is_multiple_of(2) { binomial(p, l) } else { -binomial(p, l) }).collect()
}

/// The closures and the interior stencil of `Δt·D+`, as exact fractions.
pub(super) struct Blocks {
    /// Row `i` of the left closure, columns `0, 1, …`.
    pub left: Vec<Vec<Frac>>,
    /// Row `N−1−i` of the right closure, entry `j` for column `N−1−j`.
    pub right: Vec<Vec<Frac>>,
    /// The interior stencil at offsets `−w..=w`.
    pub interior: Vec<Frac>,
}

/// `Δt·D+` of the dissipative operator of order `p` built on the centred operator with
/// norm weights `norm` (`H/Δt` at the left end; 1 beyond), left closure `boundary` and
/// interior stencil `interior` (offsets `−r..=r`).
pub(super) fn blocks(norm: &[Frac], boundary: &[&[Frac]], interior: &[Frac], p: usize) -> Blocks {
    let eps = Ratio::from_frac(EPSILON);
    let r = interior.len() / 2;
    let c = difference_stencil(p);
    let rows = boundary.len().max(p);
    let zero = Ratio::new(0, 1);
    // Row i of Δt·D at the left end, dense from column 0.
    let centred_row = |i: usize| -> Vec<Ratio> {
        match boundary.get(i) {
            Some(row) => row.iter().map(|&f| Ratio::from_frac(f)).collect(),
            None => {
                let mut row = vec![zero; i + r + 1];
                for (o, &f) in interior.iter().enumerate() {
                    row[i + o - r] = Ratio::from_frac(f);
                }
                row
            }
        }
    };
    // Row i of Δt·ε H⁻¹ D_pᵀ D_p = (ε / w_i) D_pᵀ D_p at the left end, dense from column
    // 0: (D_pᵀ D_p)[i, j] sums over the rows k ≥ 0 of D_p that touch both columns (the
    // right end does not reach rows i < `rows` when N ≥ 2·rows).
    let dissipation_row = |i: usize| -> Vec<Ratio> {
        let weight = norm.get(i).map_or(Ratio::new(1, 1), |&w| Ratio::from_frac(w));
        let scale = eps.mul(weight.recip());
        (0..=i + p)
            .map(|j| {
                let sum: i128 = (i.saturating_sub(p)..=i).filter(|&k| j >= k && j - k <= p).map(|k| c[i - k] * c[j - k]).sum();
                scale.mul(Ratio::new(sum, 1))
            })
            .collect()
    };
    let combine = |d: &[Ratio], e: &[Ratio], sign: i128| -> Vec<Frac> {
        let len = d.len().max(e.len());
        let mut row: Vec<Frac> = (0..len)
            .map(|j| {
                let dj = d.get(j).copied().unwrap_or(zero);
                let ej = e.get(j).copied().unwrap_or(zero);
                let dj = if sign < 0 { dj.neg() } else { dj };
                dj.add(ej.neg()).to_frac()
            })
            .collect();
        while row.last().is_some_and(|f| f.0 == 0) {
            row.pop();
        }
        row
    };
    let mut left = Vec::with_capacity(rows);
    let mut right = Vec::with_capacity(rows);
    for i in 0..rows {
        let (d, e) = (centred_row(i), dissipation_row(i));
        left.push(combine(&d, &e, 1));
        right.push(combine(&d, &e, -1));
    }
    // Interior: D's stencil minus ε times the autocorrelation of c (the row of D_pᵀ D_p
    // away from the ends), both at offsets −w..=w.
    let w = r.max(p);
    let interior = (0..=2 * w)
        .map(|o| {
            let offset = o as isize - w as isize;
            let d = usize::try_from(offset + r as isize).ok().and_then(|k| interior.get(k)).map_or(zero, |&f| Ratio::from_frac(f));
            let auto: i128 =
                (0..=p).filter_map(|l| usize::try_from(l as isize + offset).ok().filter(|&m| m <= p).map(|m| c[l] * c[m])).sum();
            d.add(eps.mul(Ratio::new(auto, 1)).neg()).to_frac()
        })
        .collect();
    Blocks { left, right, interior }
}
