//! The statistics of a fit at its solution: the trajectory's sensitivities to the
//! parameters, the Gauss–Newton curvature of the misfit, the covariance and standard
//! errors of the parameters, and whether the data determine them.
//!
//! At a solution `R(P(θ); θ) = 0`, so the trajectory's sensitivities are
//! `S = dP/dθ = −(∂R/∂P)⁻¹ ∂R/∂θ` (one sparse LU, one solve per parameter), and the
//! model's values at the data change by `A = W^{1/2} E S` (`E` the observations' rows,
//! `W = diag(1/σ_i²)`). The Gauss–Newton approximation of the misfit's curvature in the
//! parameters is `F = AᵀA` (the exact curvature adds `Σ w_i r_i ∇²y_i`, which vanishes
//! with the residuals), and the covariance of the estimates is `F⁻¹` when the data give
//! standard deviations (taken as absolute, scipy's `absolute_sigma=True`), and
//! `s² F⁻¹` with the residual variance `s² = Σ r_i²/(m − p)` when they do not (all
//! weights 1): what `scipy.optimize.curve_fit` returns by default.
//!
//! **Identifiability.** The data determine the parameters when `F` is nonsingular. `F`
//! is judged after scaling each parameter to unit curvature, `C = D⁻¹ F D⁻¹` with
//! `D = diag(√F_jj)` (so that units and the parameters' sizes do not matter; `C` has a
//! unit diagonal and its eigenvalues are at most the number of parameters): a parameter
//! the model's values at the data do not depend on (`F_jj = 0`), or an eigenvalue of `C`
//! below [`SINGULAR`] of its largest, is a direction of the parameters that the data do
//! not determine, reported in words ([`undetermined`]).

use std::cell::RefMut;

use nalgebra::{DMatrix, DVector};

use super::observe::Observations;
use super::problem::Plans;
use crate::discrete::Action;
use crate::model::Workspace;
use crate::solve::linalg::roundoff::residual_roundoff_level;
use crate::solve::linalg::SparseFactorization;

/// An eigenvalue of the scaled curvature `C` below this fraction of its largest makes
/// the curvature singular: the standard errors along its direction would be more than
/// 10⁵ times those of a parameter alone (exactly undetermined combinations come out at
/// the round-off level, about 1e-16 to 1e-20; docs/fitting.md#identifiability).
pub const SINGULAR: f64 = 1e-10;

/// The Gauss–Newton curvature `F = AᵀA` of the misfit in the parameters at `z` (the
/// whole unknown vector of the action, minus block ignored) and the workspace's
/// parameters (module documentation); `None` when `∂R/∂P` is singular.
pub(super) fn curvature(
    action: &Action,
    plans: &Plans,
    observations: &Observations,
    z: &[f64],
    ws: &mut Workspace,
) -> Option<DMatrix<f64>> {
    let (s, _, _) = factored_sensitivities(action, plans, z, ws)?;
    let a = weighted_sensitivities(observations, &s);
    Some(a.transpose() * &a)
}

/// The trajectory's sensitivities `dP/dθ` (one column per parameter) at `z` and the
/// workspace's parameters, the factorization of `∂R/∂P` they were solved with (the
/// fit's starting multipliers solve with its transpose too) and the round-off level
/// `4 ε maxᵢ Σⱼ |∂Rᵢ/∂Pⱼ| |Pⱼ|` of `R` there (the reduced fit's solves stop at it);
/// `None` when `∂R/∂P` is singular.
pub(super) fn factored_sensitivities<'p>(
    action: &Action,
    plans: &'p Plans,
    z: &[f64],
    ws: &mut Workspace,
) -> Option<(DMatrix<f64>, RefMut<'p, SparseFactorization>, f64)> {
    let lay = &action.layout;
    let mut zp = z.to_vec();
    zp[lay.n_p..].fill(0.0);
    let mut values = vec![0.0; plans.jacobian.structure.len()];
    action.matrix_values(&plans.jacobian, &zp, &mut values, ws);
    let entries = plans.jacobian.structure.iter().zip(&values).map(|(&(r, c), &v)| (r as usize, c as usize, v));
    let roundoff = residual_roundoff_level(entries, &zp[..lay.n_p], lay.n_m);
    let mut lu = plans.factor_jacobian(lay.n_p, &values)?;
    let free = action.model.parameters.as_ref().map_or(0, |p| p.names.len());
    let mut dr = vec![0.0; plans.parameters.jacobian.len()];
    action.parameter_jacobian(&plans.parameters, &zp, &mut dr, ws);
    let mut s = DMatrix::zeros(lay.n_p, free);
    for j in 0..free {
        let mut column = vec![0.0; lay.n_m];
        for (&(r, jj), v) in plans.parameters.jacobian.iter().zip(&dr) {
            if jj as usize == j {
                column[r as usize] -= v;
            }
        }
        if !lu.solve(&mut column) {
            return None;
        }
        s.set_column(j, &DVector::from_vec(column));
    }
    Some((s, lu, roundoff))
}

/// The misfit's gradient in the parameters along the motions, `∇F = Sᵀ ∇_P f`, from the
/// sensitivities `s` at `x = (P, θ)`, and its gradient `∇_P f` in the trajectory (the
/// reduced fit's adjoint needs it too).
pub(super) fn misfit_gradient(observations: &Observations, s: &DMatrix<f64>, x: &[f64]) -> (DVector<f64>, Vec<f64>) {
    let mut grad = vec![0.0; x.len()];
    observations.gradient(x, &mut grad);
    grad.truncate(s.nrows());
    (s.tr_mul(&DVector::from_column_slice(&grad)), grad)
}

/// The misfit's gradient along the motions and its Gauss–Newton curvature `AᵀA` at
/// `x = (P, θ)` and the workspace's parameters: one sparse LU of `∂R/∂P` (the fit's
/// stopping test away from `μ ≤ tol`); `None` when that is singular.
pub(super) fn reduced_gradient(
    action: &Action,
    plans: &Plans,
    observations: &Observations,
    x: &[f64],
    ws: &mut Workspace,
) -> Option<(DVector<f64>, DMatrix<f64>)> {
    let mut z = vec![0.0; action.layout.len()];
    z[..action.layout.n_p].copy_from_slice(&x[..action.layout.n_p]);
    let (s, _, _) = factored_sensitivities(action, plans, &z, ws)?;
    let a = weighted_sensitivities(observations, &s);
    Some((misfit_gradient(observations, &s, x).0, a.transpose() * &a))
}

/// `A = W^{1/2} E S`: the weighted change of the model's values at the data per unit
/// change of each parameter.
fn weighted_sensitivities(observations: &Observations, s: &DMatrix<f64>) -> DMatrix<f64> {
    let mut a = DMatrix::zeros(observations.rows.len(), s.ncols());
    for (i, (row, w)) in observations.rows.iter().zip(&observations.weights).enumerate() {
        let sw = w.sqrt();
        for j in 0..s.ncols() {
            a[(i, j)] = sw * row.iter().map(|&(p, e)| e * s[(p as usize, j)]).sum::<f64>();
        }
    }
    a
}

/// The combination of parameters the data do not determine, in words, when the
/// curvature `f` (`F = AᵀA`) is singular (module documentation); `None` otherwise.
/// `values` are the parameters' values (to state the direction in relative changes).
pub fn undetermined(f: &DMatrix<f64>, names: &[String], values: &[f64]) -> Option<String> {
    undetermined_where(f, names, values, " from the data")
}

/// [`undetermined`], saying `whence` they cannot be determined (" from the data", or
/// "" at the fitted values, which the message then names).
pub(super) fn undetermined_where(f: &DMatrix<f64>, names: &[String], values: &[f64], whence: &str) -> Option<String> {
    let n = f.nrows();
    if let Some(j) = (0..n).find(|&j| !(f[(j, j)] > 0.0 && f[(j, j)].is_finite())) {
        return Some(format!(
            "`{}` cannot be determined{whence}: the model's values at the data times do not depend on it \
             (check that the data observe a coordinate it moves)",
            names[j]
        ));
    }
    let d: Vec<f64> = (0..n).map(|j| f[(j, j)].sqrt()).collect();
    let c = DMatrix::from_fn(n, n, |i, j| f[(i, j)] / (d[i] * d[j]));
    let eig = c.symmetric_eigen();
    let (imin, &smallest) = eig.eigenvalues.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1))?;
    let largest = eig.eigenvalues.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if smallest > SINGULAR * largest {
        return None;
    }
    // The direction in the parameters, as relative changes where a value is not zero.
    let u = eig.eigenvectors.column(imin);
    let change: Vec<f64> = (0..n).map(|j| u[j] / d[j] / if values[j] != 0.0 { values[j].abs() } else { 1.0 }).collect();
    let top = change.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    // The first of the largest changes (to rounding) positive, whatever the eigenvector's sign.
    let sign = if change.iter().find(|x| x.abs() >= top * (1.0 - 1e-9)).is_some_and(|x| *x < 0.0) { -1.0 } else { 1.0 };
    let parts: Vec<(usize, f64)> = change.iter().enumerate().map(|(j, x)| (j, sign * x / top)).filter(|(_, x)| x.abs() >= 1e-3).collect();
    let term = |&(j, x): &(usize, f64)| {
        let name = &names[j];
        if values[j] != 0.0 {
            format!("δ{name}/{name} = {x:.3}")
        } else {
            format!("δ{name} = {x:.3}")
        }
    };
    let involved: Vec<String> = parts.iter().map(|&(j, _)| format!("`{}`", names[j])).collect();
    let who = match involved.len() {
        1 => format!("{} cannot be determined{whence}", involved[0]),
        _ => format!("{} cannot all be determined{whence}", involved.join(", ")),
    };
    Some(format!(
        "{who}: changing the parameters along {} leaves the model's values at the data times unchanged to first order \
         (the misfit's curvature in that direction is {:.1e} of the largest; the data determine only the combinations across it)",
        parts.iter().map(term).collect::<Vec<_>>().join(", "),
        (smallest / largest).max(0.0)
    ))
}

/// The covariance of the estimates from the curvature `f`: `F⁻¹`, times
/// `residual_variance` when the data give no standard deviations; `None` when `F` cannot
/// be inverted.
pub fn covariance(f: &DMatrix<f64>, residual_variance: Option<f64>) -> Option<DMatrix<f64>> {
    let inv = f.clone().try_inverse()?;
    Some(match residual_variance {
        Some(s2) => inv * s2,
        None => inv,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A model `y = a·b·t` determines only the product: the direction δa/a = −δb/b.
    #[test]
    fn a_product_of_two_parameters_is_undetermined_and_said_so() {
        let (a, b) = (2.0, 3.0);
        let t = [0.1, 0.5, 1.0, 2.0];
        let jac = DMatrix::from_fn(4, 2, |i, j| if j == 0 { b * t[i] } else { a * t[i] });
        let f = jac.transpose() * &jac;
        let names = ["a".to_string(), "b".to_string()];
        let message = undetermined(&f, &names, &[a, b]).expect("singular");
        assert!(message.contains("`a`, `b` cannot all be determined from the data"), "{message}");
        assert!(message.contains("δa/a = 1.000, δb/b = -1.000"), "{message}");
        // A third parameter with its own effect is determined; the pair still is not.
        let jac3 = DMatrix::from_fn(4, 3, |i, j| match j {
            0 => b * t[i],
            1 => a * t[i],
            _ => t[i] * t[i],
        });
        let m3 = undetermined(&(jac3.transpose() * &jac3), &["a".into(), "b".into(), "c".into()], &[a, b, 1.0]).unwrap();
        assert!(m3.contains("δa/a = 1.000, δb/b = -1.000 leaves"), "{m3}");
        // Independent effects: determined.
        let ok = DMatrix::from_fn(4, 2, |i, j| if j == 0 { t[i] } else { t[i] * t[i] });
        assert_eq!(undetermined(&(ok.transpose() * &ok), &names, &[a, b]), None);
        // No effect at all.
        let none = DMatrix::from_fn(4, 2, |i, j| if j == 0 { t[i] } else { 0.0 });
        let m = undetermined(&(none.transpose() * &none), &names, &[a, b]).unwrap();
        assert!(m.starts_with("`b` cannot be determined from the data: the model's values"), "{m}");
    }

    /// The covariance of a straight-line fit `y = p₀ + p₁ t` with unit weights, scaled by
    /// the residual variance, is curve_fit's: `s² (AᵀA)⁻¹`.
    #[test]
    fn the_covariance_of_a_line_is_the_textbook_one() {
        let t = [0.0, 1.0, 2.0, 3.0];
        let a = DMatrix::from_fn(4, 2, |i, j| if j == 0 { 1.0 } else { t[i] });
        let f = a.transpose() * &a;
        let cov = covariance(&f, Some(0.5)).unwrap();
        // (AᵀA)⁻¹ = [[7/10, −3/10], [−3/10, 1/5]] for t = 0, 1, 2, 3.
        let exact = DMatrix::from_row_slice(2, 2, &[0.35, -0.15, -0.15, 0.1]);
        assert!((cov - exact).amax() < 1e-15);
    }
}
