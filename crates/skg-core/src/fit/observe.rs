//! The trajectory at the data's times, consistently with the operator, and the misfit
//! ([`Observations`]).
//!
//! A coordinate at a time `t` between the nodes `t_k ≤ t < t_{k+1}` is the cubic Hermite
//! polynomial of its values at the two nodes and of its velocities there, the SBP
//! derivative `v = D q` of the action ([`interpolate`](crate::discrete::interpolate),
//! as `check` and the coarse-to-fine guess interpolate a trajectory):
//!
//! ```text
//! q(t) = w₀ q_k + w₁ (D q)_k + w₂ q_{k+1} + w₃ (D q)_{k+1},
//! ```
//!
//! linear in the plus block `P`, so each observation is a sparse row `e_i` of weights
//! over `P` (the two nodes and the stencils of `D` at them), exact at a node's own time
//! (`w = (1, 0, 0, 0)`). With the data `d_i` and weights `w_i = 1/σ_i²` the misfit is
//! `f(P) = ½ Σ_i w_i (e_i·P − d_i)²`, with gradient `Σ_i w_i r_i e_i` and the constant
//! Hessian `Σ_i w_i e_i e_iᵀ`.

use rustc_hash::FxHashMap;

use super::data::Data;
use crate::discrete::interpolate::{segment, Hermite};
use crate::discrete::Action;

/// The observations as linear functions of the plus block, with the data and weights
/// (module documentation).
pub struct Observations {
    /// Per observation: the entries `(index in P, weight)` of its row `e_i`.
    pub rows: Vec<Vec<(u32, f64)>>,
    /// The measured values `d_i`.
    pub values: Vec<f64>,
    /// The weights `w_i = 1/σ_i²` (1 without standard deviations).
    pub weights: Vec<f64>,
    /// The entries of the misfit's Hessian `Σ w_i e_i e_iᵀ` (lower triangle, in `P`'s
    /// numbering) and their values.
    pub hessian: Vec<(u32, u32)>,
    hessian_values: Vec<f64>,
}

impl Observations {
    /// The observations of `data` on the grid of `action` (nodes at `times`).
    pub fn new(action: &Action, times: &[f64], data: &Data) -> Observations {
        let lay = &action.layout;
        let d = lay.d;
        let mut rows = Vec::with_capacity(data.observations.len());
        for o in &data.observations {
            let k = segment(times, o.t);
            let w = Hermite::new(times[k], times[k + 1], o.t).weights();
            let mut row: Vec<(u32, f64)> = Vec::new();
            let mut add = |node: usize, weight: f64| {
                if weight != 0.0 {
                    let z = lay.qp[node * d + o.coordinate];
                    match row.iter_mut().find(|(i, _)| *i == z) {
                        Some(entry) => entry.1 += weight,
                        None => row.push((z, weight)),
                    }
                }
            };
            add(k, w[0]);
            add(k + 1, w[2]);
            for (node, wv) in [(k, w[1]), (k + 1, w[3])] {
                if wv != 0.0 {
                    for (j, c) in action.op.row(node) {
                        add(j, wv * c);
                    }
                }
            }
            rows.push(row);
        }
        let values = data.observations.iter().map(|o| o.value).collect();
        let weights: Vec<f64> = data.observations.iter().map(|o| 1.0 / (o.sigma * o.sigma)).collect();
        let (hessian, hessian_values) = misfit_hessian(&rows, &weights);
        Observations { rows, values, weights, hessian, hessian_values }
    }

    /// The trajectory's values `e_i·P` at the observations, from the unknowns `x`
    /// (whose first entries are `P`).
    pub fn predict(&self, x: &[f64]) -> Vec<f64> {
        self.rows.iter().map(|row| row.iter().map(|&(i, w)| w * x[i as usize]).sum()).collect()
    }

    /// The residuals `e_i·P − d_i`.
    pub fn residuals(&self, x: &[f64]) -> Vec<f64> {
        self.predict(x).iter().zip(&self.values).map(|(y, d)| y - d).collect()
    }

    /// The misfit `½ Σ w_i r_i²`.
    pub fn misfit(&self, x: &[f64]) -> f64 {
        0.5 * self.residuals(x).iter().zip(&self.weights).map(|(r, w)| w * r * r).sum::<f64>()
    }

    /// The misfit's gradient into `grad` (length of `x`; zero beyond `P`).
    pub fn gradient(&self, x: &[f64], grad: &mut [f64]) {
        grad.fill(0.0);
        for ((row, r), w) in self.rows.iter().zip(self.residuals(x)).zip(&self.weights) {
            for &(i, e) in row {
                grad[i as usize] += w * r * e;
            }
        }
    }

    /// The misfit's Hessian times `factor`, in the order of [`Observations::hessian`].
    pub fn hessian_values(&self, factor: f64, values: &mut [f64]) {
        for (v, h) in values.iter_mut().zip(&self.hessian_values) {
            *v = factor * h;
        }
    }
}

/// The lower triangle of `Σ w_i e_i e_iᵀ`: its entries and values.
fn misfit_hessian(rows: &[Vec<(u32, f64)>], weights: &[f64]) -> (Vec<(u32, u32)>, Vec<f64>) {
    let mut index: FxHashMap<(u32, u32), usize> = FxHashMap::default();
    let (mut entries, mut values) = (Vec::new(), Vec::new());
    for (row, w) in rows.iter().zip(weights) {
        for &(a, ea) in row {
            for &(b, eb) in row {
                if a < b {
                    continue;
                }
                let slot = *index.entry((a, b)).or_insert_with(|| {
                    entries.push((a, b));
                    values.push(0.0);
                    entries.len() - 1
                });
                values[slot] += w * ea * eb;
            }
        }
    }
    (entries, values)
}
