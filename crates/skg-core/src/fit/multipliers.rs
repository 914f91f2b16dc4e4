//! The multipliers a fit's Ipopt run starts from ([`starting_multipliers`]): Ipopt's own
//! least-squares estimate, computed here from one sparse LU of the square `∂R/∂P`
//! instead of by Ipopt from a factorization of `[I Jᵀ; J 0]`.
//!
//! **Why not Ipopt's.** Ipopt estimates the constraints' multipliers `y` of its
//! Lagrangian `f + yᵀR` at the start by least squares, `min ‖∇f − z + Jᵀy‖` (`z` the
//! bound multipliers, 1 at the start), from one factorization of `[I Jᵀ; J 0]` with MUMPS.
//! On the rolling disk that factorization was the costliest of the run (0.23 of Ipopt's
//! 0.44 CPU s at N = 512: MUMPS's fill 2.3 M doubles against 1.0 M for an iteration's
//! KKT matrix), and it failed (its inertia one negative eigenvalue short), so Ipopt
//! started from `y = 0` after paying for it; starting from `y = 0` everywhere (skipping
//! the estimate) led the one-point pendulum fit of tests/fit.rs to another minimum
//! (docs/benchmarks.md#fitting). Here the same least-squares problem is solved exactly
//! with `J = (J_P, J_θ)`, `J_P = ∂R/∂P` square and nonsingular (a solve's Jacobian):
//! with `B = J_P⁻¹ J_θ`, the gradient `g = ∇f − z` split as `(g_P, g_θ)` and `u = J_Pᵀy`,
//! the residual is `ρ = g + Jᵀy = (g_P + u, g_θ + Bᵀu)`, least where
//! `g_P + u = −B r` with `r = g_θ + Bᵀu`:
//!
//! ```text
//! r = (I + BᵀB)⁻¹ (g_θ − Bᵀ g_P),   y = −J_P⁻ᵀ (g_P + B r),
//! ```
//!
//! a `k × k` system for `k` free parameters. As Ipopt does, multipliers larger than its
//! `constr_mult_init_max` are replaced by zero.

use nalgebra::{DMatrix, DVector};
use skg_ipopt::Multipliers;

use super::free::FreeParameter;
use super::observe::Observations;
use super::problem::Plans;
use super::statistics::factored_sensitivities;
use crate::discrete::Action;
use crate::model::Workspace;

/// Ipopt's default `constr_mult_init_max`: a least-squares estimate larger than this is
/// replaced by zero.
pub(super) const CONSTR_MULT_INIT_MAX: f64 = 1e3;

/// Ipopt's default `bound_mult_init_val`: the bound multipliers at a cold start.
const BOUND_MULT_INIT_VAL: f64 = 1.0;

/// The starting multipliers of a fit at the starting point `x0 = (P, θ)` (module
/// documentation): bound multipliers 1 on the bounded parameters, the constraints'
/// least-squares estimate, or zero when it exceeds `largest` (or `∂R/∂P` is singular).
pub(super) fn starting_multipliers(
    action: &mut Action,
    plans: &Plans,
    observations: &Observations,
    free: &[FreeParameter],
    x0: &[f64],
    largest: f64,
) -> Multipliers {
    let n_p = action.layout.n_p;
    let n = x0.len();
    let (mut lower, mut upper) = (vec![0.0; n], vec![0.0; n]);
    let mut g = vec![0.0; n];
    observations.gradient(x0, &mut g);
    for (j, p) in free.iter().enumerate() {
        if p.lower.is_some() {
            lower[n_p + j] = BOUND_MULT_INIT_VAL;
            g[n_p + j] -= BOUND_MULT_INIT_VAL;
        }
        if p.upper.is_some() {
            upper[n_p + j] = BOUND_MULT_INIT_VAL;
            g[n_p + j] += BOUND_MULT_INIT_VAL;
        }
    }
    let constraints = match least_squares(action, plans, x0, &g) {
        Some(y) if y.iter().all(|v| v.abs() <= largest) => y,
        _ => vec![0.0; action.layout.n_m],
    };
    Multipliers { constraints, lower, upper }
}

/// `y` minimizing `‖g + Jᵀy‖` at `x0` (module documentation), with `B = −S`, the
/// trajectory's sensitivities; `None` when `∂R/∂P` is singular or a solve is not finite.
fn least_squares(action: &mut Action, plans: &Plans, x0: &[f64], g: &[f64]) -> Option<Vec<f64>> {
    let n_p = action.layout.n_p;
    let k = x0.len() - n_p;
    let mut ws: Workspace = action.model.workspace();
    action.set_parameters(&x0[n_p..], &mut ws);
    let mut z = vec![0.0; action.layout.len()];
    z[..n_p].copy_from_slice(&x0[..n_p]);
    let (s, mut jp, _) = factored_sensitivities(action, plans, &z, &mut ws)?;
    let b = -s;
    let (g_p, g_theta) = (DVector::from_column_slice(&g[..n_p]), DVector::from_column_slice(&g[n_p..]));
    let normal = DMatrix::identity(k, k) + b.transpose() * &b;
    let r = normal.lu().solve(&(g_theta - b.transpose() * &g_p))?;
    let mut y: Vec<f64> = (-(g_p + &b * r)).iter().copied().collect();
    jp.solve_transposed(&mut y).then_some(y)
}
