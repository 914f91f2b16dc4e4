//! The linear algebra of a square sparse system `F(x) = 0`: what solves the discrete
//! action's system and knows nothing of scenes, models or actions.
//!
//! * [`SquareSystem`]: the project's own description of a square system (its residual,
//!   and its Jacobian on a fixed sparsity structure). The action's systems implement it
//!   ([`backend`](super::backend)); Newton's method solves it; one generic adapter hands
//!   it to Ipopt (with the `ipopt` feature).
//! * [`newton`]: Newton's method ([`SystemSolver`]): the iteration, the Newton step with
//!   its line search, the chord step, and their statuses and counts.
//! * `lu.rs`: the sparse LU of one structure (faer's symbolic analysis kept for any
//!   number of factorizations), in double precision or in single precision refined in
//!   double, and [`SparseFactorization`], one factorization for several right-hand
//!   sides; `pattern.rs`: the compressed-column pattern of a structure.
//! * [`roundoff`]: the round-off level of a residual, the stopping test below the
//!   tolerance that every backend shares.
//! * [`band`]: Gaussian elimination of banded systems (the prediction's proxies).
//!
//! **Place in the flow.** It uses nothing of the crate; everything that solves a system
//! uses it.

pub mod band;
mod lu;
pub mod newton;
mod pattern;
pub mod roundoff;

use serde::Serialize;

pub use lu::{LuStats, SparseFactorization};
pub use newton::{NewtonError, NewtonOptions, NewtonSolution, NewtonStats, NewtonStatus, SystemSolver};

/// A square system `F(x) = 0` of `size` unknowns and equations with a sparse Jacobian
/// whose structure does not depend on `x`.
pub trait SquareSystem {
    /// The number of unknowns, which is the number of equations.
    fn size(&self) -> usize;

    /// `F(x)` into `f`.
    fn residual(&mut self, x: &[f64], f: &mut [f64]) -> Result<(), EvalError>;

    /// The Jacobian's entries as (row, column) pairs, 0-based; duplicates are summed.
    fn jacobian_structure(&self) -> &[(u32, u32)];

    /// The Jacobian's values at `x`, in the order of [`SquareSystem::jacobian_structure`].
    fn jacobian_values(&mut self, x: &[f64], values: &mut [f64]) -> Result<(), EvalError>;

    /// The entries of the Hessian of `Σ_i λ_i F_i` (lower triangle) for an optimizer
    /// that asks for it (Ipopt's exact Hessian); none by default.
    fn hessian_structure(&self) -> &[(u32, u32)] {
        &[]
    }

    /// The values of that Hessian at `x` with the weights `lambda`, in the order of
    /// [`SquareSystem::hessian_structure`].
    fn hessian_values(&mut self, _x: &[f64], _lambda: &[f64], _values: &mut [f64]) -> Result<(), EvalError> {
        Ok(())
    }
}

/// A residual or Jacobian that cannot be evaluated at a point (the solver then treats
/// the point as unusable: a line search shortens its step).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct EvalError(pub String);

/// One row of a solver's iteration table: Newton's, or Ipopt's as its intermediate
/// callback reports it. Newton fills `inf_pr` (`max |F|`), `d_norm` (the step's
/// max-norm), `alpha_pr` (the step length) and `ls_trials` (the residual evaluations
/// from that iteration's point); the other fields are Ipopt's and 0 for Newton.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct IterationStat {
    /// Iteration number (0 = initial point); Ipopt's continues counting in restoration.
    pub iter: i32,
    /// Objective value (of the restoration problem while `restoration`).
    pub objective: f64,
    /// Primal infeasibility: the largest residual.
    pub inf_pr: f64,
    /// Dual infeasibility.
    pub inf_du: f64,
    /// Barrier parameter.
    pub mu: f64,
    /// Max-norm of the step.
    pub d_norm: f64,
    /// Hessian regularization added, 0 if none.
    pub regularization: f64,
    /// Primal step size.
    pub alpha_pr: f64,
    /// Dual step size.
    pub alpha_du: f64,
    /// Number of line-search trials.
    pub ls_trials: i32,
    /// Whether Ipopt is in its restoration phase.
    pub restoration: bool,
}

/// The largest absolute value of `v`; NaN if `v` holds one.
pub(crate) fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0_f64, |m, x| if x.is_nan() { f64::NAN } else { m.max(x.abs()) })
}
