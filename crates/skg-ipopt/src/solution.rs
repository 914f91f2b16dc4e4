//! What [`crate::solve`] returns: a [`Solution`] whenever Ipopt ran (the final point and
//! multipliers, the iteration history, the recomputed constraint violation, the time
//! spent in callbacks ([`EvalTimes`]) and in Ipopt, the callbacks' failures), or a
//! [`SolveError`] when it could not run or a callback's error stopped it. Uses the
//! problem's types ([`crate::problem`]) and [`Status`].

use serde::Serialize;

use crate::problem::{EvalError, IterationStat};
use crate::status::Status;
#[cfg(doc)]
use crate::{solve, Problem};

/// Calls and total wall time of one kind of callback.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct EvalStat {
    /// Number of value evaluations (structure queries are not counted).
    pub calls: u64,
    /// Total seconds spent in the user's code for them.
    pub seconds: f64,
}

/// Time spent in the user's callbacks, per kind.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct EvalTimes {
    /// [`Problem::constraints`], including the final recomputation by [`solve`].
    pub constraints: EvalStat,
    /// [`Problem::jacobian_values`].
    pub jacobian: EvalStat,
    /// [`Problem::hessian_values`].
    pub hessian: EvalStat,
    /// [`Problem::objective`] and [`Problem::objective_gradient`].
    pub objective: EvalStat,
}

impl EvalTimes {
    /// Sum of the seconds of all kinds.
    pub fn total_seconds(&self) -> f64 {
        self.constraints.seconds + self.jacobian.seconds + self.hessian.seconds + self.objective.seconds
    }
}

/// The result of a solve that ran (whatever Ipopt's verdict).
#[derive(Debug, Clone, Serialize)]
pub struct Solution {
    /// Ipopt's return status; check [`Status::is_success`].
    pub status: Status,
    /// The final point.
    pub x: Vec<f64>,
    /// Final multipliers of the constraints (length `m`).
    pub constraint_multipliers: Vec<f64>,
    /// Final multipliers of the lower variable bounds (length `n`).
    pub lower_bound_multipliers: Vec<f64>,
    /// Final multipliers of the upper variable bounds (length `n`).
    pub upper_bound_multipliers: Vec<f64>,
    /// Objective value at `x`, as reported by Ipopt.
    pub objective: f64,
    /// Number of iterations (the last `iter` seen by the intermediate callback).
    pub iterations: usize,
    /// One entry per intermediate-callback call: iteration 0 (the initial point) to the last.
    pub history: Vec<IterationStat>,
    /// Constraint values `c(x)` recomputed by calling [`Problem::constraints`] at the final
    /// `x` (unscaled; NaN-filled if that evaluation failed).
    pub constraint_values: Vec<f64>,
    /// Unscaled max |c(x) − bound|, recomputed by calling [`Problem::constraints`] at the
    /// final `x` (independent of Ipopt's internal scaling).
    ///
    /// Precisely: `max_i max(g_L,i - c_i, c_i - g_U,i, 0)` (for equalities `|c_i - b_i|`);
    /// 0 without constraints; NaN if the recomputation failed or gave a non-finite value.
    pub max_constraint_violation: f64,
    /// Wall time of the solve after the process-wide lock was acquired, in seconds.
    pub total_seconds: f64,
    /// Time spent in the user's callbacks.
    pub eval: EvalTimes,
    /// total_seconds minus the time spent in all callbacks: Ipopt's own time.
    pub ipopt_seconds: f64,
    /// The first `Err` returned by a callback, if any (also when Ipopt recovered from it).
    pub first_eval_error: Option<EvalError>,
    /// How many callbacks returned `Err`.
    pub failed_evaluations: usize,
    /// How many callbacks produced NaN or infinite values (reported to Ipopt as failures).
    pub non_finite_evaluations: usize,
}

/// Why [`solve`] could not produce a [`Solution`].
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    /// `CreateIpoptProblem` or another setup call failed, or a nested solve was attempted.
    #[error("Ipopt problem creation failed: {0}")]
    Create(String),
    /// Ipopt refused an option (unknown name, wrong type or value out of range). Ipopt
    /// itself prints the reason to stdout.
    #[error("Ipopt rejected option {name} = {value}")]
    BadOption {
        /// The option's name.
        name: String,
        /// The value given, as text.
        value: String,
    },
    /// A callback returned `Err` and Ipopt did not succeed; the first error.
    #[error("evaluation failed: {0}")]
    Eval(EvalError),
    /// Inconsistent sizes or indices (starting point, structures, counts).
    #[error("invalid problem size: {0}")]
    Size(String),
    /// Non-finite starting point or NaN bounds.
    #[error("invalid input: {0}")]
    Input(String),
}
