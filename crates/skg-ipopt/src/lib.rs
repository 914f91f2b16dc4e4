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
//!   (like cyipopt); if Ipopt recovered and converged anyway, [`solve`] returns `Ok` and
//!   the error is only recorded in [`Solution::first_eval_error`].
//! * **A non-converged Ipopt status is not an `Err`**: it is a [`Solution`] whose
//!   [`Solution::status`] tells what happened; the caller decides.
#![warn(missing_docs, unsafe_op_in_unsafe_fn)]

pub mod ffi;

use std::any::Any;
use std::cell::Cell;
use std::ffi::CString;
use std::fmt;
use std::os::raw::c_char;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::ptr::{self, NonNull};
use std::sync::{Mutex, MutexGuard};
use std::time::Instant;

use serde::{Deserialize, Serialize};

use ffi::{Bool, Index, Number, UserDataPtr};

/// Ipopt's `TRUE`.
const TRUE: Bool = 1;
/// Ipopt's `FALSE`.
const FALSE: Bool = 0;
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

/// A value of an Ipopt option, matching Ipopt's typed setters.
///
/// (De)serializes untagged: a string, an integer or a float.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum OptionValue {
    /// String option (`AddIpoptStrOption`).
    Str(String),
    /// Integer option (`AddIpoptIntOption`).
    Int(i32),
    /// Floating-point option (`AddIpoptNumOption`).
    Num(f64),
}

/// Solver options. [`Default`] gives the values documented on each field.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default)]
pub struct Options {
    /// Ipopt `tol` (overall NLP error tolerance). Default 1e-11.
    pub tol: f64,
    /// Ipopt `constr_viol_tol` (absolute, unscaled constraint violation). Default 1e-11.
    pub constr_viol_tol: f64,
    /// Ipopt `max_iter`. Default 100.
    pub max_iter: u32,
    /// Ipopt `print_level` for the console (0..=12). Default 0, which also sets `sb yes`
    /// so nothing at all is printed.
    pub print_level: i32,
    /// Write Ipopt's log to this file (`OpenIpoptOutputFile`). Default none.
    pub output_file: Option<PathBuf>,
    /// Print level of [`Options::output_file`]. Default 5 (the usual iteration table).
    pub output_file_level: i32,
    /// Ipopt `linear_solver`, e.g. `"mumps"` (Debian's build has only MUMPS).
    /// Default none = Ipopt's default.
    pub linear_solver: Option<String>,
    /// `false` (default) sets `nlp_scaling_method none`; `true` keeps Ipopt's
    /// gradient-based scaling.
    pub scaling: bool,
    /// Further options passed through verbatim, after all of the above (so they can
    /// override them, e.g. `("check_derivatives_for_naninf", Str("no"))`).
    pub extra: Vec<(String, OptionValue)>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            tol: 1e-11,
            constr_viol_tol: 1e-11,
            max_iter: 100,
            print_level: 0,
            output_file: None,
            output_file_level: 5,
            linear_solver: None,
            scaling: false,
            extra: Vec::new(),
        }
    }
}

/// Ipopt's `ApplicationReturnStatus`.
///
/// `Display` gives readable text, [`Status::name`] Ipopt's identifier and
/// [`Status::code`] its integer value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Status {
    /// `Solve_Succeeded` (0).
    SolveSucceeded,
    /// `Solved_To_Acceptable_Level` (1).
    SolvedToAcceptableLevel,
    /// `Infeasible_Problem_Detected` (2).
    InfeasibleProblemDetected,
    /// `Search_Direction_Becomes_Too_Small` (3).
    SearchDirectionBecomesTooSmall,
    /// `Diverging_Iterates` (4).
    DivergingIterates,
    /// `User_Requested_Stop` (5).
    UserRequestedStop,
    /// `Feasible_Point_Found` (6). Not counted as success.
    FeasiblePointFound,
    /// `Maximum_Iterations_Exceeded` (-1).
    MaximumIterationsExceeded,
    /// `Restoration_Failed` (-2).
    RestorationFailed,
    /// `Error_In_Step_Computation` (-3).
    ErrorInStepComputation,
    /// `Maximum_CpuTime_Exceeded` (-4).
    MaximumCpuTimeExceeded,
    /// `Not_Enough_Degrees_Of_Freedom` (-10).
    NotEnoughDegreesOfFreedom,
    /// `Invalid_Problem_Definition` (-11).
    InvalidProblemDefinition,
    /// `Invalid_Option` (-12).
    InvalidOption,
    /// `Invalid_Number_Detected` (-13).
    InvalidNumberDetected,
    /// `Unrecoverable_Exception` (-100).
    UnrecoverableException,
    /// `NonIpopt_Exception_Thrown` (-101).
    NonIpoptExceptionThrown,
    /// `Insufficient_Memory` (-102).
    InsufficientMemory,
    /// `Internal_Error` (-199).
    InternalError,
    /// A code this crate does not know.
    Unknown(i32),
}

/// Every known status, for iteration (tests, documentation).
const KNOWN_STATUSES: [Status; 19] = [
    Status::SolveSucceeded,
    Status::SolvedToAcceptableLevel,
    Status::InfeasibleProblemDetected,
    Status::SearchDirectionBecomesTooSmall,
    Status::DivergingIterates,
    Status::UserRequestedStop,
    Status::FeasiblePointFound,
    Status::MaximumIterationsExceeded,
    Status::RestorationFailed,
    Status::ErrorInStepComputation,
    Status::MaximumCpuTimeExceeded,
    Status::NotEnoughDegreesOfFreedom,
    Status::InvalidProblemDefinition,
    Status::InvalidOption,
    Status::InvalidNumberDetected,
    Status::UnrecoverableException,
    Status::NonIpoptExceptionThrown,
    Status::InsufficientMemory,
    Status::InternalError,
];

impl Status {
    /// The status for Ipopt's integer code.
    pub fn from_code(code: i32) -> Self {
        KNOWN_STATUSES.iter().copied().find(|s| s.code() == code).unwrap_or(Status::Unknown(code))
    }

    /// Ipopt's integer code.
    pub fn code(&self) -> i32 {
        type S = ffi::ApplicationReturnStatus;
        match self {
            Status::SolveSucceeded => S::Solve_Succeeded.0,
            Status::SolvedToAcceptableLevel => S::Solved_To_Acceptable_Level.0,
            Status::InfeasibleProblemDetected => S::Infeasible_Problem_Detected.0,
            Status::SearchDirectionBecomesTooSmall => S::Search_Direction_Becomes_Too_Small.0,
            Status::DivergingIterates => S::Diverging_Iterates.0,
            Status::UserRequestedStop => S::User_Requested_Stop.0,
            Status::FeasiblePointFound => S::Feasible_Point_Found.0,
            Status::MaximumIterationsExceeded => S::Maximum_Iterations_Exceeded.0,
            Status::RestorationFailed => S::Restoration_Failed.0,
            Status::ErrorInStepComputation => S::Error_In_Step_Computation.0,
            Status::MaximumCpuTimeExceeded => S::Maximum_CpuTime_Exceeded.0,
            Status::NotEnoughDegreesOfFreedom => S::Not_Enough_Degrees_Of_Freedom.0,
            Status::InvalidProblemDefinition => S::Invalid_Problem_Definition.0,
            Status::InvalidOption => S::Invalid_Option.0,
            Status::InvalidNumberDetected => S::Invalid_Number_Detected.0,
            Status::UnrecoverableException => S::Unrecoverable_Exception.0,
            Status::NonIpoptExceptionThrown => S::NonIpopt_Exception_Thrown.0,
            Status::InsufficientMemory => S::Insufficient_Memory.0,
            Status::InternalError => S::Internal_Error.0,
            Status::Unknown(code) => *code,
        }
    }

    /// `true` for `Solve_Succeeded` and `Solved_To_Acceptable_Level` only
    /// (`Feasible_Point_Found` is deliberately not a success).
    pub fn is_success(&self) -> bool {
        matches!(self, Status::SolveSucceeded | Status::SolvedToAcceptableLevel)
    }

    /// Ipopt's identifier, e.g. `"Solve_Succeeded"`; `"Unknown"` for unknown codes.
    pub fn name(&self) -> &'static str {
        match self {
            Status::SolveSucceeded => "Solve_Succeeded",
            Status::SolvedToAcceptableLevel => "Solved_To_Acceptable_Level",
            Status::InfeasibleProblemDetected => "Infeasible_Problem_Detected",
            Status::SearchDirectionBecomesTooSmall => "Search_Direction_Becomes_Too_Small",
            Status::DivergingIterates => "Diverging_Iterates",
            Status::UserRequestedStop => "User_Requested_Stop",
            Status::FeasiblePointFound => "Feasible_Point_Found",
            Status::MaximumIterationsExceeded => "Maximum_Iterations_Exceeded",
            Status::RestorationFailed => "Restoration_Failed",
            Status::ErrorInStepComputation => "Error_In_Step_Computation",
            Status::MaximumCpuTimeExceeded => "Maximum_CpuTime_Exceeded",
            Status::NotEnoughDegreesOfFreedom => "Not_Enough_Degrees_Of_Freedom",
            Status::InvalidProblemDefinition => "Invalid_Problem_Definition",
            Status::InvalidOption => "Invalid_Option",
            Status::InvalidNumberDetected => "Invalid_Number_Detected",
            Status::UnrecoverableException => "Unrecoverable_Exception",
            Status::NonIpoptExceptionThrown => "NonIpopt_Exception_Thrown",
            Status::InsufficientMemory => "Insufficient_Memory",
            Status::InternalError => "Internal_Error",
            Status::Unknown(_) => "Unknown",
        }
    }
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let text = match self {
            Status::SolveSucceeded => "solved to the requested tolerance",
            Status::SolvedToAcceptableLevel => "solved to an acceptable level only (not the requested tolerance)",
            Status::InfeasibleProblemDetected => "converged to a point of local infeasibility (the problem may be infeasible)",
            Status::SearchDirectionBecomesTooSmall => "search direction became too small",
            Status::DivergingIterates => "iterates diverged",
            Status::UserRequestedStop => "stopped on request of the intermediate callback",
            Status::FeasiblePointFound => "feasible point found (not a converged solution)",
            Status::MaximumIterationsExceeded => "maximum number of iterations exceeded",
            Status::RestorationFailed => "restoration phase failed",
            Status::ErrorInStepComputation => "error in step computation (singular or ill-conditioned linear system)",
            Status::MaximumCpuTimeExceeded => "maximum CPU time exceeded",
            Status::NotEnoughDegreesOfFreedom => "not enough degrees of freedom (more equality constraints than free variables)",
            Status::InvalidProblemDefinition => "invalid problem definition",
            Status::InvalidOption => "invalid option",
            Status::InvalidNumberDetected => "invalid number (NaN or infinity) in a function or derivative value",
            Status::UnrecoverableException => "unrecoverable exception inside Ipopt",
            Status::NonIpoptExceptionThrown => "non-Ipopt exception thrown inside Ipopt",
            Status::InsufficientMemory => "insufficient memory",
            Status::InternalError => "internal error in Ipopt",
            Status::Unknown(code) => return write!(f, "unknown Ipopt return status {code}"),
        };
        f.write_str(text)
    }
}

/// Serializes as Ipopt's identifier (`"Solve_Succeeded"`, ...; `"Unknown(<code>)"`).
impl Serialize for Status {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match self {
            Status::Unknown(code) => serializer.collect_str(&format_args!("Unknown({code})")),
            known => serializer.serialize_str(known.name()),
        }
    }
}

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

/// The version of Ipopt this crate was built against (from pkg-config), e.g. `"3.11.9"`.
pub fn ipopt_version() -> &'static str {
    env!("SKG_IPOPT_VERSION")
}

// ---------------------------------------------------------------------------------------
// Process-wide lock and the RAII problem handle
// ---------------------------------------------------------------------------------------

/// Serializes every use of Ipopt in the process (it is not thread-safe).
static IPOPT_LOCK: Mutex<()> = Mutex::new(());

thread_local! {
    /// Whether this thread is inside [`solve`] (to refuse nested solves instead of
    /// deadlocking on [`IPOPT_LOCK`]).
    static IN_SOLVE: Cell<bool> = const { Cell::new(false) };
}

/// Marks this thread as inside [`solve`] while alive.
struct NestGuard;

impl NestGuard {
    fn enter() -> Option<Self> {
        IN_SOLVE.with(|flag| if flag.replace(true) { None } else { Some(NestGuard) })
    }
}

impl Drop for NestGuard {
    fn drop(&mut self) {
        IN_SOLVE.with(|flag| flag.set(false));
    }
}

/// Acquires [`IPOPT_LOCK`], recovering from poisoning (the guarded data is `()`, and a
/// panic never leaves Ipopt itself half-way: callbacks catch them).
fn lock_ipopt() -> MutexGuard<'static, ()> {
    IPOPT_LOCK.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// An `IpoptProblem` that owns the process-wide lock; freed (under the lock) on drop.
struct Handle {
    raw: NonNull<ffi::IpoptProblemInfo>,
    /// Dropped after `Drop::drop` has freed the problem.
    _lock: MutexGuard<'static, ()>,
}

impl Drop for Handle {
    fn drop(&mut self) {
        // SAFETY: `raw` came from a successful CreateIpoptProblem, is freed exactly once
        // (here), and the lock is still held because fields drop after this body.
        unsafe { ffi::FreeIpoptProblem(self.raw.as_ptr()) };
    }
}

impl Handle {
    fn raw(&self) -> ffi::IpoptProblem {
        self.raw.as_ptr()
    }

    fn c_name(name: &str, value: &dyn fmt::Display) -> Result<CString, SolveError> {
        CString::new(name).map_err(|_| Self::bad(name, value))
    }

    fn bad(name: &str, value: &dyn fmt::Display) -> SolveError {
        SolveError::BadOption { name: name.to_owned(), value: value.to_string() }
    }

    fn set_str(&self, name: &str, value: &str) -> Result<(), SolveError> {
        let key = Self::c_name(name, &value)?;
        let val = CString::new(value).map_err(|_| Self::bad(name, &value))?;
        // SAFETY: valid problem; both strings are NUL-terminated and outlive the call;
        // Ipopt only reads them (the C prototype lacks `const`) and copies them.
        let ok = unsafe { ffi::AddIpoptStrOption(self.raw(), key.as_ptr() as *mut c_char, val.as_ptr() as *mut c_char) };
        Self::check(ok, name, &format!("{value:?}"))
    }

    fn set_num(&self, name: &str, value: f64) -> Result<(), SolveError> {
        let key = Self::c_name(name, &value)?;
        // SAFETY: valid problem; NUL-terminated key that outlives the call, only read.
        let ok = unsafe { ffi::AddIpoptNumOption(self.raw(), key.as_ptr() as *mut c_char, value) };
        Self::check(ok, name, &value)
    }

    fn set_int(&self, name: &str, value: i32) -> Result<(), SolveError> {
        let key = Self::c_name(name, &value)?;
        // SAFETY: valid problem; NUL-terminated key that outlives the call, only read.
        let ok = unsafe { ffi::AddIpoptIntOption(self.raw(), key.as_ptr() as *mut c_char, value) };
        Self::check(ok, name, &value)
    }

    fn set(&self, name: &str, value: &OptionValue) -> Result<(), SolveError> {
        match value {
            OptionValue::Str(s) => self.set_str(name, s),
            OptionValue::Num(v) => self.set_num(name, *v),
            OptionValue::Int(v) => self.set_int(name, *v),
        }
    }

    fn check(ok: Bool, name: &str, value: &dyn fmt::Display) -> Result<(), SolveError> {
        if ok == FALSE {
            Err(Self::bad(name, value))
        } else {
            Ok(())
        }
    }

    fn open_output_file(&self, path: &Path, level: i32) -> Result<(), SolveError> {
        let bytes = path_bytes(path)?;
        let c_path =
            CString::new(bytes).map_err(|_| SolveError::Create(format!("output file path {} contains a NUL byte", path.display())))?;
        // SAFETY: valid problem; NUL-terminated path that outlives the call, only read.
        let ok = unsafe { ffi::OpenIpoptOutputFile(self.raw(), c_path.as_ptr() as *mut c_char, level) };
        if ok == FALSE {
            return Err(SolveError::Create(format!("cannot open Ipopt output file {} (print level {level})", path.display())));
        }
        Ok(())
    }

    /// Applies `options` in a fixed order; [`Options::extra`] last.
    fn apply(&self, options: &Options) -> Result<(), SolveError> {
        self.set_str("option_file_name", "")?;
        self.set_int("print_level", options.print_level)?;
        if options.print_level == 0 {
            self.set_str("sb", "yes")?;
        }
        self.set_num("tol", options.tol)?;
        self.set_num("constr_viol_tol", options.constr_viol_tol)?;
        let max_iter = i32::try_from(options.max_iter).map_err(|_| Self::bad("max_iter", &options.max_iter))?;
        self.set_int("max_iter", max_iter)?;
        if !options.scaling {
            self.set_str("nlp_scaling_method", "none")?;
        }
        self.set_str("check_derivatives_for_naninf", "yes")?;
        if let Some(solver) = &options.linear_solver {
            self.set_str("linear_solver", solver)?;
        }
        if let Some(path) = &options.output_file {
            self.open_output_file(path, options.output_file_level)?;
        }
        for (name, value) in &options.extra {
            self.set(name, value)?;
        }
        Ok(())
    }
}

#[cfg(unix)]
fn path_bytes(path: &Path) -> Result<Vec<u8>, SolveError> {
    use std::os::unix::ffi::OsStrExt;
    Ok(path.as_os_str().as_bytes().to_vec())
}

#[cfg(not(unix))]
fn path_bytes(path: &Path) -> Result<Vec<u8>, SolveError> {
    path.to_str()
        .map(|s| s.as_bytes().to_vec())
        .ok_or_else(|| SolveError::Create(format!("output file path {} is not UTF-8", path.display())))
}

// ---------------------------------------------------------------------------------------
// Callback context and the extern "C" trampolines
// ---------------------------------------------------------------------------------------

/// Which statistics a callback's time goes to.
#[derive(Clone, Copy)]
enum Kind {
    Objective,
    Constraints,
    Jacobian,
    Hessian,
    /// Structure queries and the intermediate callback: time counted, calls not.
    Other,
}

/// What the trampolines reach through Ipopt's `user_data` pointer.
struct Context<'p, P: Problem> {
    problem: &'p mut P,
    n: usize,
    m: usize,
    nnz_jac: usize,
    nnz_hess: usize,
    /// First panic payload; once set, every callback returns false without running user code.
    panic: Option<Box<dyn Any + Send + 'static>>,
    first_error: Option<EvalError>,
    failed_evaluations: usize,
    non_finite_evaluations: usize,
    history: Vec<IterationStat>,
    eval: EvalTimes,
    /// All time spent in callbacks (user code), including structure queries.
    callback_seconds: f64,
}

/// Outcome of a user evaluation as seen by [`Context::run`].
enum Outcome {
    Finite,
    NonFinite,
}

impl<P: Problem> Context<'_, P> {
    /// Runs user code `f` for one callback: skipped after a panic, timed, panics caught,
    /// `Err` and non-finite output recorded. Returns Ipopt's success flag.
    fn run(&mut self, kind: Kind, f: impl FnOnce(&mut P) -> Result<Outcome, EvalError>) -> Bool {
        if self.panic.is_some() {
            return FALSE;
        }
        let start = Instant::now();
        let problem = &mut *self.problem;
        let result = catch_unwind(AssertUnwindSafe(|| f(problem)));
        let seconds = start.elapsed().as_secs_f64();
        self.callback_seconds += seconds;
        let stat = match kind {
            Kind::Objective => Some(&mut self.eval.objective),
            Kind::Constraints => Some(&mut self.eval.constraints),
            Kind::Jacobian => Some(&mut self.eval.jacobian),
            Kind::Hessian => Some(&mut self.eval.hessian),
            Kind::Other => None,
        };
        if let Some(stat) = stat {
            stat.calls += 1;
            stat.seconds += seconds;
        }
        match result {
            Ok(Ok(Outcome::Finite)) => TRUE,
            Ok(Ok(Outcome::NonFinite)) => {
                self.non_finite_evaluations += 1;
                FALSE
            }
            Ok(Err(e)) => self.fail(e),
            Err(payload) => {
                self.panic = Some(payload);
                FALSE
            }
        }
    }

    /// Records an evaluation error and returns `FALSE`.
    fn fail(&mut self, e: EvalError) -> Bool {
        self.failed_evaluations += 1;
        if self.first_error.is_none() {
            self.first_error = Some(e);
        }
        FALSE
    }

    /// Records that Ipopt called `what` with arguments we did not expect.
    fn bad_call(&mut self, what: &str) -> Bool {
        self.fail(EvalError(format!("internal error: Ipopt called {what} with unexpected sizes or null pointers")))
    }
}

/// Reinterprets Ipopt's `user_data` as our context.
///
/// # Safety
/// `user_data` must be the `*mut Context<P>` that [`solve`] passed to `IpoptSolve`, and
/// the call must happen during that `IpoptSolve` (the context is alive and not otherwise
/// borrowed then).
unsafe fn context<'a, 'p, P: Problem>(user_data: UserDataPtr) -> &'a mut Context<'p, P> {
    // SAFETY: guaranteed by the caller (see above); Ipopt calls back on the solving thread
    // only, one callback at a time.
    unsafe { &mut *(user_data as *mut Context<'p, P>) }
}

/// A shared slice from an Ipopt array pointer, or `None` if `len` is not the expected
/// length or the pointer is null while `len > 0`.
///
/// # Safety
/// If non-null, `ptr` must point to `len` initialized values valid for the returned lifetime.
unsafe fn slice_in<'a, T>(ptr: *const T, len: Index, expected: usize) -> Option<&'a [T]> {
    let len = usize::try_from(len).ok().filter(|&l| l == expected)?;
    if len == 0 {
        return Some(&[]);
    }
    if ptr.is_null() {
        return None;
    }
    // SAFETY: non-null, and the caller guarantees `len` valid elements.
    Some(unsafe { std::slice::from_raw_parts(ptr, len) })
}

/// Mutable counterpart of [`slice_in`].
///
/// # Safety
/// If non-null, `ptr` must point to `len` writable values, not aliased elsewhere, valid
/// for the returned lifetime.
unsafe fn slice_out<'a, T>(ptr: *mut T, len: Index, expected: usize) -> Option<&'a mut [T]> {
    let len = usize::try_from(len).ok().filter(|&l| l == expected)?;
    if len == 0 {
        return Some(&mut []);
    }
    if ptr.is_null() {
        return None;
    }
    // SAFETY: non-null, and the caller guarantees `len` writable, unaliased elements.
    Some(unsafe { std::slice::from_raw_parts_mut(ptr, len) })
}

fn finite(values: &[f64]) -> Outcome {
    if values.iter().all(|v| v.is_finite()) {
        Outcome::Finite
    } else {
        Outcome::NonFinite
    }
}

/// Copies a sparsity structure into Ipopt's 0-based index arrays, re-checking what
/// [`solve`] validated (the structure must not change during a solve).
fn copy_structure(
    structure: &[(u32, u32)],
    shape: (usize, usize),
    rows: &mut [Index],
    cols: &mut [Index],
    what: &str,
) -> Result<Outcome, EvalError> {
    if structure.len() != rows.len() {
        return Err(EvalError(format!(
            "{what} changed length during the solve ({} entries, Ipopt expects {})",
            structure.len(),
            rows.len()
        )));
    }
    for ((&(r, c), row), col) in structure.iter().zip(rows.iter_mut()).zip(cols.iter_mut()) {
        let in_range = (r as usize) < shape.0 && (c as usize) < shape.1;
        match (Index::try_from(r), Index::try_from(c)) {
            (Ok(r), Ok(c)) if in_range => {
                *row = r;
                *col = c;
            }
            _ => return Err(EvalError(format!("{what} entry ({r}, {c}) is outside the {} x {} matrix", shape.0, shape.1))),
        }
    }
    Ok(Outcome::Finite)
}

unsafe extern "C" fn eval_f<P: Problem>(n: Index, x: *mut Number, _new_x: Bool, obj_value: *mut Number, user_data: UserDataPtr) -> Bool {
    // SAFETY: called by Ipopt during our IpoptSolve with our user_data.
    let ctx = unsafe { context::<P>(user_data) };
    // SAFETY: Ipopt passes x with n entries.
    let x = unsafe { slice_in(x, n, ctx.n) };
    let (Some(x), false) = (x, obj_value.is_null()) else {
        return ctx.bad_call("eval_f");
    };
    ctx.run(Kind::Objective, |p| {
        let value = p.objective(x)?;
        // SAFETY: obj_value is non-null (checked) and points to one writable Number.
        unsafe { *obj_value = value };
        Ok(if value.is_finite() { Outcome::Finite } else { Outcome::NonFinite })
    })
}

unsafe extern "C" fn eval_grad_f<P: Problem>(n: Index, x: *mut Number, _new_x: Bool, grad_f: *mut Number, user_data: UserDataPtr) -> Bool {
    // SAFETY: called by Ipopt during our IpoptSolve with our user_data.
    let ctx = unsafe { context::<P>(user_data) };
    // SAFETY: Ipopt passes x and grad_f with n entries each, distinct arrays.
    let (x, grad) = unsafe { (slice_in(x, n, ctx.n), slice_out(grad_f, n, ctx.n)) };
    let (Some(x), Some(grad)) = (x, grad) else {
        return ctx.bad_call("eval_grad_f");
    };
    ctx.run(Kind::Objective, |p| {
        p.objective_gradient(x, grad)?;
        Ok(finite(grad))
    })
}

unsafe extern "C" fn eval_g<P: Problem>(n: Index, x: *mut Number, _new_x: Bool, m: Index, g: *mut Number, user_data: UserDataPtr) -> Bool {
    // SAFETY: called by Ipopt during our IpoptSolve with our user_data.
    let ctx = unsafe { context::<P>(user_data) };
    // SAFETY: Ipopt passes x with n and g with m entries, distinct arrays.
    let (x, g) = unsafe { (slice_in(x, n, ctx.n), slice_out(g, m, ctx.m)) };
    let (Some(x), Some(g)) = (x, g) else {
        return ctx.bad_call("eval_g");
    };
    let ok = ctx.run(Kind::Constraints, |p| {
        p.constraints(x, g)?;
        Ok(finite(g))
    });
    if ok == FALSE {
        // Ipopt 3.11.9 dereferences the never-filled constraint vector when eval_g
        // returns FALSE (segfault in dnrm2, measured). NaN values with TRUE take Ipopt's
        // own invalid-number path instead, which is handled exactly like a failed
        // evaluation: the step is cut, or Invalid_Number_Detected at the start point.
        g.fill(f64::NAN);
    }
    TRUE
}

#[allow(clippy::too_many_arguments)]
unsafe extern "C" fn eval_jac_g<P: Problem>(
    n: Index,
    x: *mut Number,
    _new_x: Bool,
    m: Index,
    nele_jac: Index,
    i_row: *mut Index,
    j_col: *mut Index,
    values: *mut Number,
    user_data: UserDataPtr,
) -> Bool {
    // SAFETY: called by Ipopt during our IpoptSolve with our user_data.
    let ctx = unsafe { context::<P>(user_data) };
    if usize::try_from(m).ok() != Some(ctx.m) {
        return ctx.bad_call("eval_jac_g");
    }
    let (nnz, ctx_n, ctx_m) = (ctx.nnz_jac, ctx.n, ctx.m);
    if values.is_null() {
        // Structure query: Ipopt passes iRow/jCol arrays of nele_jac entries.
        // SAFETY: iRow and jCol are distinct writable arrays of nele_jac entries.
        let (rows, cols) = unsafe { (slice_out(i_row, nele_jac, nnz), slice_out(j_col, nele_jac, nnz)) };
        let (Some(rows), Some(cols)) = (rows, cols) else {
            return ctx.bad_call("eval_jac_g (structure)");
        };
        return ctx.run(Kind::Other, |p| copy_structure(p.jacobian_structure(), (ctx_m, ctx_n), rows, cols, "jacobian_structure"));
    }
    // SAFETY: x has n entries and values nele_jac entries, distinct arrays.
    let (x, values) = unsafe { (slice_in(x, n, ctx.n), slice_out(values, nele_jac, nnz)) };
    let (Some(x), Some(values)) = (x, values) else {
        return ctx.bad_call("eval_jac_g");
    };
    ctx.run(Kind::Jacobian, |p| {
        p.jacobian_values(x, values)?;
        Ok(finite(values))
    })
}

#[allow(clippy::too_many_arguments)]
unsafe extern "C" fn eval_h<P: Problem>(
    n: Index,
    x: *mut Number,
    _new_x: Bool,
    obj_factor: Number,
    m: Index,
    lambda: *mut Number,
    _new_lambda: Bool,
    nele_hess: Index,
    i_row: *mut Index,
    j_col: *mut Index,
    values: *mut Number,
    user_data: UserDataPtr,
) -> Bool {
    // SAFETY: called by Ipopt during our IpoptSolve with our user_data.
    let ctx = unsafe { context::<P>(user_data) };
    let (nnz, ctx_n) = (ctx.nnz_hess, ctx.n);
    if values.is_null() {
        // SAFETY: iRow and jCol are distinct writable arrays of nele_hess entries.
        let (rows, cols) = unsafe { (slice_out(i_row, nele_hess, nnz), slice_out(j_col, nele_hess, nnz)) };
        let (Some(rows), Some(cols)) = (rows, cols) else {
            return ctx.bad_call("eval_h (structure)");
        };
        if nnz == 0 {
            return TRUE;
        }
        return ctx.run(Kind::Other, |p| copy_structure(p.hessian_structure(), (ctx_n, ctx_n), rows, cols, "hessian_structure"));
    }
    if nnz == 0 {
        return TRUE;
    }
    // SAFETY: x has n entries, lambda m entries, values nele_hess entries; values is
    // distinct from the two inputs.
    let (x, lambda, values) = unsafe { (slice_in(x, n, ctx.n), slice_in(lambda, m, ctx.m), slice_out(values, nele_hess, nnz)) };
    let (Some(x), Some(lambda), Some(values)) = (x, lambda, values) else {
        return ctx.bad_call("eval_h");
    };
    ctx.run(Kind::Hessian, |p| {
        p.hessian_values(x, obj_factor, lambda, values)?;
        Ok(finite(values))
    })
}

#[allow(clippy::too_many_arguments)]
unsafe extern "C" fn intermediate<P: Problem>(
    alg_mod: Index,
    iter_count: Index,
    obj_value: Number,
    inf_pr: Number,
    inf_du: Number,
    mu: Number,
    d_norm: Number,
    regularization_size: Number,
    alpha_du: Number,
    alpha_pr: Number,
    ls_trials: Index,
    user_data: UserDataPtr,
) -> Bool {
    // SAFETY: called by Ipopt during our IpoptSolve with our user_data.
    let ctx = unsafe { context::<P>(user_data) };
    if ctx.panic.is_some() {
        // A callback panicked: ask Ipopt to stop as soon as it lets us.
        return FALSE;
    }
    let stat = IterationStat {
        iter: iter_count,
        objective: obj_value,
        inf_pr,
        inf_du,
        mu,
        d_norm,
        regularization: regularization_size,
        alpha_pr,
        alpha_du,
        ls_trials,
        restoration: alg_mod == ffi::AlgorithmMode::RestorationPhaseMode.0 as Index,
    };
    ctx.history.push(stat);
    let mut keep_going = true;
    let ok = ctx.run(Kind::Other, |p| {
        keep_going = p.intermediate(&stat);
        Ok(Outcome::Finite)
    });
    if ok == TRUE && keep_going {
        TRUE
    } else {
        FALSE
    }
}

// ---------------------------------------------------------------------------------------
// solve
// ---------------------------------------------------------------------------------------

/// Checks a sparsity structure: length fits Ipopt's `Index`, rows < `rows`, cols < `cols`,
/// and for the Hessian `row >= col`.
fn validate_structure(structure: &[(u32, u32)], rows: usize, cols: usize, lower_triangle: bool, what: &str) -> Result<usize, SolveError> {
    if Index::try_from(structure.len()).is_err() {
        return Err(SolveError::Size(format!("{what} has {} entries, more than Ipopt's index type allows", structure.len())));
    }
    for (k, &(r, c)) in structure.iter().enumerate() {
        if r as usize >= rows || c as usize >= cols {
            return Err(SolveError::Size(format!("{what} entry {k} is ({r}, {c}), outside the {rows} x {cols} matrix")));
        }
        if lower_triangle && r < c {
            return Err(SolveError::Size(format!("{what} entry {k} is ({r}, {c}), but only the lower triangle (row >= col) may be given")));
        }
    }
    Ok(structure.len())
}

fn to_index(value: usize, what: &str) -> Result<Index, SolveError> {
    Index::try_from(value).map_err(|_| SolveError::Size(format!("{what} = {value} exceeds Ipopt's index range")))
}

/// Solves `problem` with Ipopt from the starting point `x0`.
///
/// Returns `Ok(Solution)` whenever Ipopt ran, whatever its [`Status`] (check
/// [`Status::is_success`]). Returns `Err` for size/index errors, bad options, a failure to
/// create the problem, or when a callback returned `Err` and Ipopt did not succeed (the
/// first such error). A panic in a callback is re-raised after Ipopt returned and the
/// problem was freed. Holds the process-wide Ipopt lock for the whole run.
pub fn solve<P: Problem>(problem: &mut P, x0: &[f64], options: &Options) -> Result<Solution, SolveError> {
    let Some(_nest) = NestGuard::enter() else {
        return Err(SolveError::Create("ipopt::solve called from inside an Ipopt callback; nested solves are not supported".to_owned()));
    };

    // ---- sizes, structures, bounds ----
    let n = problem.num_variables();
    let m = problem.num_constraints();
    if n == 0 {
        return Err(SolveError::Size("the problem has no variables (Ipopt needs n >= 1)".to_owned()));
    }
    let n_c = to_index(n, "number of variables")?;
    let m_c = to_index(m, "number of constraints")?;
    if x0.len() != n {
        return Err(SolveError::Size(format!("starting point has {} entries, the problem has {n} variables", x0.len())));
    }
    if let Some(i) = x0.iter().position(|v| !v.is_finite()) {
        return Err(SolveError::Input(format!("starting point x0[{i}] = {} is not finite", x0[i])));
    }
    let nnz_jac = validate_structure(problem.jacobian_structure(), m, n, false, "jacobian_structure")?;
    let nnz_hess = validate_structure(problem.hessian_structure(), n, n, true, "hessian_structure")?;
    if m > 0 && nnz_jac == 0 {
        return Err(SolveError::Size(format!(
            "the problem has {m} constraints but an empty Jacobian structure (Ipopt needs at least one entry)"
        )));
    }
    let nnz_jac_c = to_index(nnz_jac, "Jacobian nonzeros")?;
    let nnz_hess_c = to_index(nnz_hess, "Hessian nonzeros")?;

    let mut x_l = vec![-INFINITY_BOUND; n];
    let mut x_u = vec![INFINITY_BOUND; n];
    let mut g_l = vec![0.0; m];
    let mut g_u = vec![0.0; m];
    problem.variable_bounds(&mut x_l, &mut x_u);
    problem.constraint_bounds(&mut g_l, &mut g_u);
    for (what, v) in [("variable lower", &x_l), ("variable upper", &x_u), ("constraint lower", &g_l), ("constraint upper", &g_u)] {
        if let Some(i) = v.iter().position(|b| b.is_nan()) {
            return Err(SolveError::Input(format!("{what} bound {i} is NaN")));
        }
    }

    // ---- create the problem (takes the process-wide lock) ----
    let lock = lock_ipopt();
    let start = Instant::now();
    let null_if_empty = |v: &mut Vec<f64>| {
        if v.is_empty() {
            ptr::null_mut()
        } else {
            v.as_mut_ptr()
        }
    };
    // SAFETY: we hold the lock; the bound arrays have n resp. m entries (or are null when
    // m == 0) and are copied by Ipopt; the callbacks match the C typedefs.
    let raw = unsafe {
        ffi::CreateIpoptProblem(
            n_c,
            x_l.as_mut_ptr(),
            x_u.as_mut_ptr(),
            m_c,
            null_if_empty(&mut g_l),
            null_if_empty(&mut g_u),
            nnz_jac_c,
            nnz_hess_c,
            0, // C-style 0-based indices
            Some(eval_f::<P>),
            Some(eval_g::<P>),
            Some(eval_grad_f::<P>),
            Some(eval_jac_g::<P>),
            Some(eval_h::<P>),
        )
    };
    let Some(raw) = NonNull::new(raw) else {
        return Err(SolveError::Create(format!(
            "CreateIpoptProblem returned NULL (n = {n}, m = {m}, Jacobian nonzeros = {nnz_jac}, Hessian nonzeros = {nnz_hess})"
        )));
    };
    let handle = Handle { raw, _lock: lock };
    handle.apply(options)?;
    // SAFETY: valid problem; the callback matches the Intermediate_CB typedef.
    let ok = unsafe { ffi::SetIntermediateCallback(handle.raw(), Some(intermediate::<P>)) };
    if ok == FALSE {
        return Err(SolveError::Create("SetIntermediateCallback failed".to_owned()));
    }

    // ---- solve ----
    let mut x = x0.to_vec();
    let mut g = vec![0.0; m];
    let mut mult_g = vec![0.0; m];
    let mut mult_x_l = vec![0.0; n];
    let mut mult_x_u = vec![0.0; n];
    let mut objective = 0.0;
    let mut ctx = Context {
        problem: &mut *problem,
        n,
        m,
        nnz_jac,
        nnz_hess,
        panic: None,
        first_error: None,
        failed_evaluations: 0,
        non_finite_evaluations: 0,
        history: Vec::with_capacity((options.max_iter as usize).saturating_add(1).min(1024)),
        eval: EvalTimes::default(),
        callback_seconds: 0.0,
    };
    let user_data = &mut ctx as *mut Context<'_, P> as UserDataPtr;
    // SAFETY: valid problem, lock held; x has n entries, g and mult_g m entries (or are
    // null when m == 0), mult_x_* n entries; `user_data` points to `ctx`, which outlives
    // the call and is not touched by Rust code until IpoptSolve returns; the callbacks
    // were instantiated for this same `P`.
    let raw_status = unsafe {
        ffi::IpoptSolve(
            handle.raw(),
            x.as_mut_ptr(),
            null_if_empty(&mut g),
            &mut objective,
            null_if_empty(&mut mult_g),
            mult_x_l.as_mut_ptr(),
            mult_x_u.as_mut_ptr(),
            user_data,
        )
    };
    drop(handle); // FreeIpoptProblem under the lock, then unlock
    let status = Status::from_code(raw_status.0);

    let Context { panic, first_error, failed_evaluations, non_finite_evaluations, history, mut eval, mut callback_seconds, .. } = ctx;
    if let Some(payload) = panic {
        resume_unwind(payload);
    }

    // ---- unscaled constraint violation at the final point ----
    let mut constraint_values = vec![0.0; m];
    let t = Instant::now();
    let recomputed = problem.constraints(&x, &mut constraint_values);
    let seconds = t.elapsed().as_secs_f64();
    eval.constraints.calls += 1;
    eval.constraints.seconds += seconds;
    callback_seconds += seconds;
    let mut first_error = first_error;
    let max_constraint_violation = match recomputed {
        Ok(()) => constraint_violation(&constraint_values, &g_l, &g_u),
        Err(e) => {
            constraint_values.fill(f64::NAN);
            first_error.get_or_insert(e);
            f64::NAN
        }
    };

    if !status.is_success() {
        if let Some(e) = first_error {
            return Err(SolveError::Eval(e));
        }
    }
    let total_seconds = start.elapsed().as_secs_f64();
    let iterations = history.last().map_or(0, |s| usize::try_from(s.iter).unwrap_or(0));
    Ok(Solution {
        status,
        x,
        constraint_multipliers: mult_g,
        lower_bound_multipliers: mult_x_l,
        upper_bound_multipliers: mult_x_u,
        objective,
        iterations,
        history,
        constraint_values,
        max_constraint_violation,
        total_seconds,
        eval,
        ipopt_seconds: (total_seconds - callback_seconds).max(0.0),
        first_eval_error: first_error,
        failed_evaluations,
        non_finite_evaluations,
    })
}

/// `max_i max(lower_i - c_i, c_i - upper_i, 0)`; NaN if any `c_i` is not finite.
fn constraint_violation(c: &[f64], lower: &[f64], upper: &[f64]) -> f64 {
    let mut worst = 0.0_f64;
    for ((&ci, &lo), &up) in c.iter().zip(lower).zip(upper) {
        if !ci.is_finite() {
            return f64::NAN;
        }
        let below = if lo > -INFINITY_BOUND / 10.0 { lo - ci } else { 0.0 };
        let above = if up < INFINITY_BOUND / 10.0 { ci - up } else { 0.0 };
        worst = worst.max(below).max(above);
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// How a [`Circle`] misbehaves.
    #[derive(Clone, Copy, PartialEq)]
    enum Mode {
        Normal,
        /// `jacobian_values` panics on its second call.
        PanicInJacobian,
        /// `constraints` panics on its first call (at the starting point).
        PanicInConstraints,
        /// `constraints` always yields NaN.
        NanConstraints,
        /// `constraints` always returns `Err`.
        ErrAlways,
        /// `constraints` returns `Err` for x[0] > 3 (outside its "domain").
        DomainError,
    }

    /// x² + y² − r² = 0, x − y = 0; root (r/√2, r/√2) from a positive start.
    struct Circle {
        r: f64,
        mode: Mode,
        jac: Vec<(u32, u32)>,
        jac_calls: usize,
    }

    impl Circle {
        fn new(r: f64, mode: Mode) -> Self {
            Self { r, mode, jac: vec![(0, 0), (0, 1), (1, 0), (1, 1)], jac_calls: 0 }
        }
    }

    impl Problem for Circle {
        fn num_variables(&self) -> usize {
            2
        }
        fn num_constraints(&self) -> usize {
            2
        }
        fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
            match self.mode {
                Mode::PanicInConstraints => panic!("boom in constraints"),
                Mode::ErrAlways => return Err(EvalError("constraints unavailable".into())),
                Mode::DomainError if x[0] > 3.0 => return Err(EvalError(format!("x = {} outside the domain", x[0]))),
                _ => {}
            }
            c[0] = x[0] * x[0] + x[1] * x[1] - self.r * self.r;
            c[1] = x[0] - x[1];
            if self.mode == Mode::NanConstraints {
                c[0] = f64::NAN;
            }
            Ok(())
        }
        fn jacobian_structure(&self) -> &[(u32, u32)] {
            &self.jac
        }
        fn jacobian_values(&mut self, x: &[f64], v: &mut [f64]) -> Result<(), EvalError> {
            self.jac_calls += 1;
            if self.mode == Mode::PanicInJacobian && self.jac_calls == 2 {
                panic!("boom in jacobian");
            }
            v.copy_from_slice(&[2.0 * x[0], 2.0 * x[1], 1.0, -1.0]);
            Ok(())
        }
    }

    #[test]
    fn square_system_converges_with_zero_hessian() {
        let mut p = Circle::new(2.0, Mode::Normal);
        let sol = solve(&mut p, &[1.0, 0.5], &Options::default()).expect("solve runs");
        assert_eq!(sol.status, Status::SolveSucceeded, "{}", sol.status);
        let root = 2.0_f64.sqrt();
        assert!((sol.x[0] - root).abs() < 1e-12 && (sol.x[1] - root).abs() < 1e-12, "x = {:?}", sol.x);
        assert!(sol.max_constraint_violation < 1e-12, "viol = {}", sol.max_constraint_violation);
        assert!(sol.iterations >= 1 && sol.iterations <= 10, "iterations = {}", sol.iterations);
        assert_eq!(sol.history.len(), sol.iterations + 1);
        assert_eq!(sol.history[0].iter, 0);
        assert!(sol.history.iter().all(|s| !s.restoration));
        assert_eq!(sol.eval.hessian.calls, 0);
        assert!(sol.eval.constraints.calls >= 2 && sol.eval.jacobian.calls >= 1);
        assert!(sol.first_eval_error.is_none() && sol.failed_evaluations == 0);
        assert!(sol.ipopt_seconds <= sol.total_seconds);
        assert_eq!(sol.constraint_values.len(), 2);
        assert_eq!(sol.constraint_multipliers.len(), 2);
    }

    /// Hock–Schittkowski problem 71, Ipopt's standard example.
    struct Hs071 {
        jac: Vec<(u32, u32)>,
        hess: Vec<(u32, u32)>,
    }

    impl Hs071 {
        fn new() -> Self {
            let jac = (0..2).flat_map(|r| (0..4).map(move |c| (r, c))).collect();
            let hess = (0..4).flat_map(|r| (0..=r).map(move |c| (r, c))).collect();
            Self { jac, hess }
        }
    }

    impl Problem for Hs071 {
        fn num_variables(&self) -> usize {
            4
        }
        fn num_constraints(&self) -> usize {
            2
        }
        fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
            lower.fill(1.0);
            upper.fill(5.0);
        }
        fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
            lower.copy_from_slice(&[25.0, 40.0]);
            upper.copy_from_slice(&[2e19, 40.0]);
        }
        fn objective(&mut self, x: &[f64]) -> Result<f64, EvalError> {
            Ok(x[0] * x[3] * (x[0] + x[1] + x[2]) + x[2])
        }
        fn objective_gradient(&mut self, x: &[f64], g: &mut [f64]) -> Result<(), EvalError> {
            g[0] = x[0] * x[3] + x[3] * (x[0] + x[1] + x[2]);
            g[1] = x[0] * x[3];
            g[2] = x[0] * x[3] + 1.0;
            g[3] = x[0] * (x[0] + x[1] + x[2]);
            Ok(())
        }
        fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
            c[0] = x[0] * x[1] * x[2] * x[3];
            c[1] = x.iter().map(|v| v * v).sum();
            Ok(())
        }
        fn jacobian_structure(&self) -> &[(u32, u32)] {
            &self.jac
        }
        fn jacobian_values(&mut self, x: &[f64], v: &mut [f64]) -> Result<(), EvalError> {
            v[0] = x[1] * x[2] * x[3];
            v[1] = x[0] * x[2] * x[3];
            v[2] = x[0] * x[1] * x[3];
            v[3] = x[0] * x[1] * x[2];
            for i in 0..4 {
                v[4 + i] = 2.0 * x[i];
            }
            Ok(())
        }
        fn hessian_structure(&self) -> &[(u32, u32)] {
            &self.hess
        }
        fn hessian_values(&mut self, x: &[f64], s: f64, l: &[f64], h: &mut [f64]) -> Result<(), EvalError> {
            // order: (0,0) (1,0) (1,1) (2,0) (2,1) (2,2) (3,0) (3,1) (3,2) (3,3)
            h[0] = s * 2.0 * x[3] + 2.0 * l[1];
            h[1] = s * x[3] + l[0] * x[2] * x[3];
            h[2] = 2.0 * l[1];
            h[3] = s * x[3] + l[0] * x[1] * x[3];
            h[4] = l[0] * x[0] * x[3];
            h[5] = 2.0 * l[1];
            h[6] = s * (2.0 * x[0] + x[1] + x[2]) + l[0] * x[1] * x[2];
            h[7] = s * x[0] + l[0] * x[0] * x[2];
            h[8] = s * x[0] + l[0] * x[0] * x[1];
            h[9] = 2.0 * l[1];
            Ok(())
        }
    }

    #[test]
    fn hs071_reaches_known_optimum() {
        let mut p = Hs071::new();
        let opts = Options { tol: 1e-9, constr_viol_tol: 1e-9, ..Options::default() };
        let sol = solve(&mut p, &[1.0, 5.0, 5.0, 1.0], &opts).expect("solve runs");
        assert_eq!(sol.status, Status::SolveSucceeded);
        assert!((sol.objective - 17.014_017_3).abs() < 1e-6, "f = {}", sol.objective);
        let expected = [1.0, 4.742_999_63, 3.821_149_98, 1.379_408_29];
        for (a, b) in sol.x.iter().zip(expected) {
            assert!((a - b).abs() < 1e-6, "x = {:?}", sol.x);
        }
        assert!(sol.eval.hessian.calls > 0 && sol.eval.objective.calls > 0);
        // The active inequality x0 x1 x2 x3 >= 25 may be violated by Ipopt's bound
        // relaxation (bound_relax_factor 1e-8, relative): up to 25e-8.
        assert!(sol.max_constraint_violation < 1e-6, "viol = {}", sol.max_constraint_violation);
        assert!(sol.lower_bound_multipliers[0] > 0.1, "x0 sits on its lower bound");
    }

    #[test]
    fn panic_in_callback_is_reraised_after_the_solve() {
        let mut p = Circle::new(2.0, Mode::PanicInJacobian);
        let caught = catch_unwind(AssertUnwindSafe(|| solve(&mut p, &[1.0, 0.5], &Options::default())));
        let payload = match caught {
            Ok(result) => panic!("expected the panic to be re-raised, got {:?}", result.map(|s| s.status)),
            Err(payload) => payload,
        };
        let message = payload.downcast_ref::<&str>().copied().unwrap_or("<not a &str>");
        assert_eq!(message, "boom in jacobian");
        // Same from the constraints callback, whose failure path differs (see eval_g).
        let mut p = Circle::new(2.0, Mode::PanicInConstraints);
        let caught = catch_unwind(AssertUnwindSafe(|| solve(&mut p, &[1.0, 0.5], &Options::default())));
        let payload = caught.expect_err("panic re-raised");
        assert_eq!(payload.downcast_ref::<&str>().copied(), Some("boom in constraints"));
        // The problem was freed and the lock released: the next solve works.
        let sol = solve(&mut Circle::new(2.0, Mode::Normal), &[1.0, 0.5], &Options::default()).expect("runs");
        assert!(sol.status.is_success());
    }

    #[test]
    fn nan_constraints_give_a_failure_status_not_a_crash() {
        let mut p = Circle::new(2.0, Mode::NanConstraints);
        let sol = solve(&mut p, &[1.0, 0.5], &Options::default()).expect("NaN is not an Err");
        assert!(!sol.status.is_success(), "status {}", sol.status);
        assert!(sol.non_finite_evaluations > 0);
        assert!(sol.max_constraint_violation.is_nan());
    }

    #[test]
    fn callback_error_is_returned_when_ipopt_fails() {
        let mut p = Circle::new(2.0, Mode::ErrAlways);
        match solve(&mut p, &[1.0, 0.5], &Options::default()) {
            Err(SolveError::Eval(e)) => assert_eq!(e.0, "constraints unavailable"),
            other => panic!("expected SolveError::Eval, got {:?}", other.map(|s| s.status)),
        }
    }

    #[test]
    fn callback_error_at_a_trial_point_is_recorded_when_ipopt_recovers() {
        // The first Newton step from (0.3, 0.3) lands at x ≈ 3.48, outside the domain.
        let mut p = Circle::new(2.0, Mode::DomainError);
        let sol = solve(&mut p, &[0.3, 0.3], &Options::default()).expect("Ipopt recovers");
        assert!(sol.status.is_success(), "status {}", sol.status);
        assert!(sol.failed_evaluations >= 1);
        let err = sol.first_eval_error.as_ref().expect("error recorded");
        assert!(err.0.contains("outside the domain"), "{err}");
        assert!((sol.x[0] - 2.0_f64.sqrt()).abs() < 1e-10);
    }

    #[test]
    fn concurrent_solves_are_serialized_and_correct() {
        let failures = AtomicUsize::new(0);
        std::thread::scope(|scope| {
            for t in 0..4 {
                let failures = &failures;
                scope.spawn(move || {
                    for k in 0..20 {
                        let r = 1.0 + t as f64 + 0.1 * k as f64;
                        let mut p = Circle::new(r, Mode::Normal);
                        let ok = match solve(&mut p, &[r, 0.5 * r], &Options::default()) {
                            Ok(sol) => {
                                sol.status.is_success()
                                    && (sol.x[0] - r / 2.0_f64.sqrt()).abs() < 1e-10
                                    && (sol.x[1] - r / 2.0_f64.sqrt()).abs() < 1e-10
                            }
                            Err(_) => false,
                        };
                        if !ok {
                            failures.fetch_add(1, Ordering::Relaxed);
                        }
                    }
                });
            }
        });
        assert_eq!(failures.load(Ordering::Relaxed), 0);
    }

    const CHILD_ENV: &str = "SKG_IPOPT_TEST_STRAY_OPT_CHILD";

    /// The current directory is process-global, so the check runs in a child process (this
    /// same test binary, filtered to this test) started inside a temporary directory that
    /// holds an `ipopt.opt` with `max_iter 0`. The child also checks that the file does
    /// bite when named explicitly; the parent checks that the child printed nothing.
    #[test]
    fn stray_ipopt_opt_file_is_ignored() {
        let module = module_path!();
        let test_name = format!("{}::stray_ipopt_opt_file_is_ignored", module.split_once("::").map_or(module, |(_, rest)| rest));
        if std::env::var_os(CHILD_ENV).is_some() {
            assert!(Path::new("ipopt.opt").is_file(), "child runs next to ipopt.opt");
            let sol = solve(&mut Circle::new(2.0, Mode::Normal), &[1.0, 0.5], &Options::default()).expect("runs");
            assert_eq!(sol.status, Status::SolveSucceeded);
            assert!(sol.iterations > 0);
            let naming_it =
                Options { extra: vec![("option_file_name".into(), OptionValue::Str("ipopt.opt".into()))], ..Options::default() };
            let sol = solve(&mut Circle::new(2.0, Mode::Normal), &[1.0, 0.5], &naming_it).expect("runs");
            assert_eq!(sol.status, Status::MaximumIterationsExceeded, "the file is read when named");
            println!("CHILD-CHECKS-PASSED");
            return;
        }
        let dir = tempfile::tempdir().expect("temp dir");
        std::fs::write(dir.path().join("ipopt.opt"), "max_iter 0\n").expect("write ipopt.opt");
        let exe = std::env::current_exe().expect("test binary path");
        let out = std::process::Command::new(exe)
            .args([test_name.as_str(), "--exact", "--nocapture", "--test-threads=1"])
            .env(CHILD_ENV, "1")
            .current_dir(dir.path())
            .output()
            .expect("spawn child test");
        let stdout = String::from_utf8_lossy(&out.stdout);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "child failed:\n{stdout}\n{stderr}");
        assert!(stdout.contains("CHILD-CHECKS-PASSED"), "child did not run the checks:\n{stdout}");
        // print_level 0 + sb yes: Ipopt printed nothing at all (banner included).
        assert!(!stdout.contains("Ipopt") && !stdout.contains("EXIT"), "Ipopt printed:\n{stdout}");
    }

    #[test]
    fn output_file_gets_a_log() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("ipopt.log");
        let opts = Options { output_file: Some(path.clone()), ..Options::default() };
        let sol = solve(&mut Circle::new(2.0, Mode::Normal), &[1.0, 0.5], &opts).expect("runs");
        assert!(sol.status.is_success());
        let log = std::fs::read_to_string(&path).expect("log written");
        assert!(!log.is_empty());
        assert!(log.contains("EXIT"), "log:\n{log}");
        let bad = Options { output_file: Some(dir.path().join("missing-dir").join("x.log")), ..Options::default() };
        assert!(matches!(solve(&mut Circle::new(2.0, Mode::Normal), &[1.0, 0.5], &bad), Err(SolveError::Create(_))));
    }

    #[test]
    fn sizes_and_structures_are_validated() {
        let mut p = Circle::new(2.0, Mode::Normal);
        assert!(matches!(solve(&mut p, &[1.0], &Options::default()), Err(SolveError::Size(_))));
        assert!(matches!(solve(&mut p, &[1.0, f64::NAN], &Options::default()), Err(SolveError::Input(_))));
        p.jac.push((2, 0)); // row out of range
        match solve(&mut p, &[1.0, 0.5], &Options::default()) {
            Err(SolveError::Size(msg)) => assert!(msg.contains("(2, 0)"), "{msg}"),
            other => panic!("expected Size error, got {:?}", other.map(|s| s.status)),
        }
        let mut h = Hs071::new();
        h.hess[1] = (0, 1); // upper triangle
        assert!(matches!(solve(&mut h, &[1.0, 5.0, 5.0, 1.0], &Options::default()), Err(SolveError::Size(_))));
    }

    #[test]
    fn bad_options_are_rejected() {
        let mut p = Circle::new(2.0, Mode::Normal);
        let opts = Options { extra: vec![("no_such_option".into(), OptionValue::Int(3))], ..Options::default() };
        match solve(&mut p, &[1.0, 0.5], &opts) {
            Err(SolveError::BadOption { name, .. }) => assert_eq!(name, "no_such_option"),
            other => panic!("expected BadOption, got {:?}", other.map(|s| s.status)),
        }
        let opts = Options { print_level: 99, ..Options::default() };
        assert!(matches!(solve(&mut p, &[1.0, 0.5], &opts), Err(SolveError::BadOption { .. })));
        // Options pass through: max_iter 1 stops early.
        let opts = Options { max_iter: 1, ..Options::default() };
        let sol = solve(&mut p, &[1.0, 0.5], &opts).expect("runs");
        assert_eq!(sol.status, Status::MaximumIterationsExceeded);
        assert_eq!(sol.iterations, 1);
    }

    /// Stops via the intermediate callback; and a nested solve is refused, not deadlocked.
    struct Stopper {
        inner: Circle,
        /// What the solve started inside the callback returned (its status, or the error).
        nested: Option<Result<Status, SolveError>>,
    }

    impl Problem for Stopper {
        fn num_variables(&self) -> usize {
            2
        }
        fn num_constraints(&self) -> usize {
            2
        }
        fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
            self.inner.constraints(x, c)
        }
        fn jacobian_structure(&self) -> &[(u32, u32)] {
            self.inner.jacobian_structure()
        }
        fn jacobian_values(&mut self, x: &[f64], v: &mut [f64]) -> Result<(), EvalError> {
            self.inner.jacobian_values(x, v)
        }
        fn intermediate(&mut self, stat: &IterationStat) -> bool {
            if self.nested.is_none() {
                let mut other = Circle::new(1.0, Mode::Normal);
                self.nested = Some(solve(&mut other, &[1.0, 0.5], &Options::default()).map(|s| s.status));
            }
            stat.iter < 1
        }
    }

    #[test]
    fn intermediate_callback_can_stop_and_nesting_is_refused() {
        let mut p = Stopper { inner: Circle::new(2.0, Mode::Normal), nested: None };
        let sol = solve(&mut p, &[1.0, 0.5], &Options::default()).expect("runs");
        assert_eq!(sol.status, Status::UserRequestedStop);
        assert_eq!(sol.iterations, 1);
        assert!(matches!(p.nested, Some(Err(SolveError::Create(_)))), "{:?}", p.nested);
    }

    #[test]
    fn status_codes_round_trip() {
        for s in KNOWN_STATUSES {
            assert_eq!(Status::from_code(s.code()), s);
            assert!(!s.to_string().is_empty() && s.name() != "Unknown");
        }
        assert_eq!(Status::from_code(-13), Status::InvalidNumberDetected);
        assert_eq!(Status::from_code(42), Status::Unknown(42));
        assert!(Status::SolvedToAcceptableLevel.is_success());
        assert!(!Status::FeasiblePointFound.is_success());
        assert_eq!(Status::MaximumIterationsExceeded.to_string(), "maximum number of iterations exceeded");
        assert_eq!(serde_json::to_string(&Status::SolveSucceeded).ok().as_deref(), Some("\"Solve_Succeeded\""));
        assert!(ipopt_version().starts_with("3."), "{}", ipopt_version());
    }
}
