//! The problem Ipopt solves, as the caller describes it: the [`Problem`] trait (sizes,
//! bounds, the objective, the constraints and their derivatives, the intermediate
//! callback), what its callbacks receive and return ([`IterationStat`], one row of
//! Ipopt's iteration table; [`EvalError`], a failed evaluation) and the magnitude that
//! stands for an infinite bound ([`INFINITY_BOUND`]). Uses nothing else of the crate.

use serde::Serialize;

#[cfg(doc)]
use crate::{Solution, Status};

/// Magnitude Ipopt treats as infinite for bounds (its default `nlp_*_bound_inf` is 1e19).
pub const INFINITY_BOUND: f64 = 1e20;

/// The problem Ipopt solves. Defaults describe our use: zero objective, no variable bounds,
/// all constraints equalities c(x) = 0.
///
/// Minimize `f(x)` subject to `x_L <= x <= x_U` and `g_L <= c(x) <= g_U`. Bounds at or
/// beyond ±1e19 are infinite. All indices are 0-based.
pub trait Problem {
    /// Number of variables `n` (must be at least 1).
    fn num_variables(&self) -> usize;
    /// Number of constraints `m`.
    fn num_constraints(&self) -> usize;
    /// Fills the variable bounds (`lower`, `upper` have length `n`). Default: unbounded.
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.fill(-INFINITY_BOUND);
        upper.fill(INFINITY_BOUND);
    }
    /// Fills the constraint bounds (length `m`). Default: equalities `c(x) = 0`.
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.fill(0.0);
        upper.fill(0.0);
    }
    /// Objective value `f(x)`. Default: 0.
    fn objective(&mut self, x: &[f64]) -> Result<f64, EvalError> {
        let _ = x;
        Ok(0.0)
    }
    /// Gradient of the objective into `grad` (length `n`). Default: zero.
    fn objective_gradient(&mut self, x: &[f64], grad: &mut [f64]) -> Result<(), EvalError> {
        let _ = x;
        grad.fill(0.0);
        Ok(())
    }
    /// Constraint values `c(x)` into `c` (length `m`).
    fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError>;
    /// (row, col) of every Jacobian nonzero, 0-based; computed once by the problem.
    ///
    /// Must not change during a solve. Duplicate entries are summed by Ipopt.
    fn jacobian_structure(&self) -> &[(u32, u32)];
    /// Jacobian values in the order of [`Problem::jacobian_structure`].
    fn jacobian_values(&mut self, x: &[f64], values: &mut [f64]) -> Result<(), EvalError>;
    /// Lower triangle (row >= col) of the Hessian of the Lagrangian; empty slice = no Hessian entries (nele_hess = 0).
    ///
    /// With no entries Ipopt uses a zero Hessian, which for a square system with a
    /// nonsingular Jacobian still gives exact Newton steps.
    fn hessian_structure(&self) -> &[(u32, u32)] {
        &[]
    }
    /// Values of `obj_factor * ∇²f(x) + Σ_i lambda_i ∇²c_i(x)` in the order of
    /// [`Problem::hessian_structure`]. Not called when that structure is empty.
    fn hessian_values(&mut self, x: &[f64], obj_factor: f64, lambda: &[f64], values: &mut [f64]) -> Result<(), EvalError> {
        let _ = (x, obj_factor, lambda, values);
        Ok(())
    }
    /// Called once per Ipopt iteration (also in the restoration phase) with its
    /// statistics; return `false` to stop Ipopt ([`Status::UserRequestedStop`]).
    /// Default: continue. The statistics are also collected in [`Solution::history`].
    fn intermediate(&mut self, stat: &IterationStat) -> bool {
        let _ = stat;
        true
    }
}

/// An evaluation failure reported by a [`Problem`] callback.
#[derive(Debug, Clone, PartialEq, Serialize, thiserror::Error)]
#[error("{0}")]
pub struct EvalError(pub String);

/// One row of Ipopt's iteration table, as passed to the intermediate callback.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct IterationStat {
    /// Iteration number (0 = initial point); continues counting in restoration.
    pub iter: i32,
    /// Objective value (of the restoration problem while `restoration`).
    pub objective: f64,
    /// Primal infeasibility (max constraint violation of the scaled problem).
    pub inf_pr: f64,
    /// Dual infeasibility.
    pub inf_du: f64,
    /// Barrier parameter.
    pub mu: f64,
    /// Max-norm of the primal step.
    pub d_norm: f64,
    /// Hessian regularization added (`lg(rg)` column), 0 if none.
    pub regularization: f64,
    /// Primal step size.
    pub alpha_pr: f64,
    /// Dual step size.
    pub alpha_du: f64,
    /// Number of backtracking line-search trials.
    pub ls_trials: i32,
    /// Whether Ipopt is in the restoration phase.
    pub restoration: bool,
}
