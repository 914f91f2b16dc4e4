//! Safe wrapper around Ipopt's C interface, shaped for this crate's use: a square system
//! of equality constraints `c(x) = 0` with a zero objective, though general problems
//! (objective, bounds, inequalities, exact Hessian) work too.
//!
//! # Usage
//! Implement [`Problem`] (only sizes, constraints and the sparse Jacobian are required),
//! then call [`solve`]:
//!
//! ```
//! use skg_ipopt::{solve, EvalError, Options, Problem};
//!
//! struct Circle { jac: Vec<(u32, u32)> }
//! impl Problem for Circle {
//!     fn num_variables(&self) -> usize { 2 }
//!     fn num_constraints(&self) -> usize { 2 }
//!     fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
//!         c[0] = x[0] * x[0] + x[1] * x[1] - 4.0;
//!         c[1] = x[0] - x[1];
//!         Ok(())
//!     }
//!     fn jacobian_structure(&self) -> &[(u32, u32)] { &self.jac }
//!     fn jacobian_values(&mut self, x: &[f64], v: &mut [f64]) -> Result<(), EvalError> {
//!         v.copy_from_slice(&[2.0 * x[0], 2.0 * x[1], 1.0, -1.0]);
//!         Ok(())
//!     }
//! }
//! let mut p = Circle { jac: vec![(0, 0), (0, 1), (1, 0), (1, 1)] };
//! let sol = solve(&mut p, &[1.0, 0.5], &Options::default()).expect("setup ok");
//! assert!(sol.status.is_success() && sol.max_constraint_violation < 1e-10);
//! ```
//!
//! # What the wrapper guarantees (facts about Debian's Ipopt 3.11.9)
//! * **One solve at a time per process.** Ipopt 3.11 with sequential MUMPS keeps
//!   process-global state, so creation, [`ffi::IpoptSolve`] and freeing all run under one
//!   process-wide mutex. Concurrent [`solve`] calls from several threads are safe but
//!   serialized. Calling [`solve`] from inside a callback of another solve returns
//!   [`SolveError::Create`] instead of deadlocking.
//! * **Options are ours only.** `option_file_name ""` is always set, so a stray
//!   `ipopt.opt` in the working directory cannot silently change options (an entry in
//!   [`Options::extra`] may still name one deliberately). `print_level 0` comes with
//!   `sb yes`, so a default solve prints nothing.
//! * **No hidden scaling by default.** `nlp_scaling_method none` unless
//!   [`Options::scaling`]; either way [`Solution::max_constraint_violation`] is the
//!   unscaled violation recomputed by calling [`Problem::constraints`] at the final point.
//! * **NaN/Inf safety.** `check_derivatives_for_naninf yes` is set by default, and any
//!   non-finite value a callback produces makes it report failure to Ipopt (which then
//!   cuts the step, or stops with `Invalid_Number_Detected` at the starting point).
//!   One exception, measured: Ipopt 3.11.9 segfaults when the *constraints* callback
//!   returns FALSE, so a failed constraint evaluation (`Err`, non-finite value or panic)
//!   is reported as TRUE with all values NaN, which Ipopt handles as the same evaluation
//!   error.
//! * **Panics never cross the C boundary.** Each callback runs the user code inside
//!   `catch_unwind`; on a panic the callback and all later ones report failure, Ipopt is
//!   asked to stop, the problem is freed, the lock released, and the panic is re-raised
//!   from [`solve`] with its original payload.
//! * **Errors from callbacks.** A callback returning `Err` reports failure to Ipopt,
//!   which may recover by cutting the step. The first such error is kept: if Ipopt did
//!   not succeed ([`Status::is_success`]) [`solve`] returns [`SolveError::Eval`] with it
//!   (like cyipopt); if Ipopt recovered and converged anyway, or the intermediate
//!   callback stopped it ([`Status::UserRequestedStop`]: the caller's verdict on the
//!   iterate), [`solve`] returns `Ok` and the error is only recorded in
//!   [`Solution::first_eval_error`].
//! * **A non-converged Ipopt status is not an `Err`**: it is a [`Solution`] whose
//!   [`Solution::status`] tells what happened; the caller decides.
#![warn(missing_docs, unsafe_op_in_unsafe_fn)]

// The modules, each using only those before it: `ffi` (the generated bindings), `problem`
// (the `Problem` trait, `IterationStat` and `EvalError`), `options` (`Options`), `status`
// (`Status`), `solution` (what a solve returns: `Solution`, `SolveError`), `lock` (the
// process-wide lock and the guard against nested solves), `handle` (the problem handle
// that owns the lock and applies the options), `callbacks` (the `extern "C"` callbacks and
// their context) and `run` (`solve` in its phases). The public items are re-exported here.
pub mod ffi;

mod callbacks;
mod handle;
mod lock;
mod options;
mod problem;
mod run;
mod solution;
mod status;
#[cfg(test)]
mod tests;

pub use options::{OptionValue, Options};
pub use problem::{EvalError, IterationStat, Problem, INFINITY_BOUND};
pub use run::{solve, solve_warm, Multipliers};
pub use solution::{EvalStat, EvalTimes, Solution, SolveError};
pub use status::Status;

use ffi::Bool;

/// Ipopt's `TRUE`.
const TRUE: Bool = 1;
/// Ipopt's `FALSE`.
const FALSE: Bool = 0;

/// The version of Ipopt this crate was built against (from pkg-config), e.g. `"3.11.9"`.
pub fn ipopt_version() -> &'static str {
    env!("SKG_IPOPT_VERSION")
}
