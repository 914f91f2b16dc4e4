//! One solve, in its phases: the checks of the problem's sizes, structures and starting
//! point ([`Dimensions`]) and of its bounds ([`Bounds`]), the creation of the Ipopt problem
//! under the process-wide lock with the options applied ([`create_problem`]), the run of
//! `IpoptSolve` with the callbacks ([`run_ipopt`]), and the [`Solution`] with the
//! constraints recomputed at the final point ([`recompute_constraints`]). Uses every
//! other module of the crate.

use std::marker::PhantomData;
use std::panic::resume_unwind;
use std::ptr::{self, NonNull};
use std::sync::MutexGuard;
use std::time::Instant;

use crate::callbacks::{eval_f, eval_g, eval_grad_f, eval_h, eval_jac_g, intermediate, Context, Record};
use crate::ffi::{self, Index, Number, UserDataPtr};
use crate::handle::Handle;
use crate::lock::{lock_ipopt, NestGuard};
use crate::options::{OptionValue, Options};
use crate::problem::{Problem, INFINITY_BOUND};
use crate::solution::{Solution, SolveError};
use crate::status::Status;
use crate::FALSE;

/// Solves `problem` with Ipopt from the starting point `x0`.
///
/// Returns `Ok(Solution)` whenever Ipopt ran, whatever its [`Status`] (check
/// [`Status::is_success`]). Returns `Err` for size/index errors, bad options, a failure to
/// create the problem, or when a callback returned `Err` and Ipopt did not succeed (the
/// first such error). A panic in a callback is re-raised after Ipopt returned and the
/// problem was freed. Holds the process-wide Ipopt lock for the whole run.
pub fn solve<P: Problem>(problem: &mut P, x0: &[f64], options: &Options) -> Result<Solution, SolveError> {
    solve_from(problem, x0, None, options)
}

/// The multipliers a warm-started solve starts from: of the constraints (length `m`), of
/// the variables' lower and upper bounds (length `n` each; those of an infinite bound
/// are ignored).
#[derive(Debug, Clone, PartialEq)]
pub struct Multipliers {
    /// `y`, of Ipopt's Lagrangian `f + yᵀc`.
    pub constraints: Vec<f64>,
    /// `z_L`.
    pub lower: Vec<f64>,
    /// `z_U`.
    pub upper: Vec<f64>,
}

/// [`solve`] from `x0` and the starting `multipliers` (Ipopt's `warm_start_init_point
/// yes`, which skips its own estimate of the constraints' multipliers; the options'
/// `warm_start_*` entries push the point into its bounds as for any warm start).
pub fn solve_warm<P: Problem>(problem: &mut P, x0: &[f64], multipliers: &Multipliers, options: &Options) -> Result<Solution, SolveError> {
    let (n, m) = (problem.num_variables(), problem.num_constraints());
    let Multipliers { constraints, lower, upper } = multipliers;
    if (constraints.len(), lower.len(), upper.len()) != (m, n, n) {
        return Err(SolveError::Size(format!(
            "starting multipliers have {}, {} and {} entries, the problem has {m} constraints and {n} variables",
            constraints.len(),
            lower.len(),
            upper.len()
        )));
    }
    if let Some(v) = constraints.iter().chain(lower).chain(upper).find(|v| !v.is_finite()) {
        return Err(SolveError::Input(format!("a starting multiplier ({v}) is not finite")));
    }
    let mut options = options.clone();
    options.extra.insert(0, ("warm_start_init_point".to_owned(), OptionValue::Str("yes".to_owned())));
    solve_from(problem, x0, Some(multipliers), &options)
}

/// [`solve`], from `multipliers` too when given.
fn solve_from<P: Problem>(
    problem: &mut P,
    x0: &[f64],
    multipliers: Option<&Multipliers>,
    options: &Options,
) -> Result<Solution, SolveError> {
    let Some(_nest) = NestGuard::enter() else {
        return Err(SolveError::Create("ipopt::solve called from inside an Ipopt callback; nested solves are not supported".to_owned()));
    };
    let dims = Dimensions::check(problem, x0)?;
    let mut bounds = Bounds::of(problem, &dims)?;
    let lock = lock_ipopt();
    let start = Instant::now();
    let created = create_problem::<P>(&dims, &mut bounds, options, lock)?;
    let mut run = run_ipopt(created, problem, x0, multipliers, &dims, options.max_iter);
    let (constraint_values, max_constraint_violation) = recompute_constraints(problem, &run.x, &bounds, &mut run.record);
    // A stop the caller's intermediate callback asked for is the caller's verdict on the
    // iterate, which it needs, whatever failed on the way.
    if !run.status.is_success() && run.status != Status::UserRequestedStop {
        if let Some(e) = run.record.first_error {
            return Err(SolveError::Eval(e));
        }
    }
    let total_seconds = start.elapsed().as_secs_f64();
    Ok(run.into_solution(constraint_values, max_constraint_violation, total_seconds))
}

/// The sizes of a problem whose starting point and sparsity structures were checked, as
/// `usize` and as Ipopt's `Index` (each checked to fit).
struct Dimensions {
    n: usize,
    m: usize,
    nnz_jac: usize,
    nnz_hess: usize,
    n_c: Index,
    m_c: Index,
    nnz_jac_c: Index,
    nnz_hess_c: Index,
}

impl Dimensions {
    /// Checks the sizes, the starting point (length, finite) and the Jacobian's and
    /// Hessian's structures.
    fn check<P: Problem>(problem: &P, x0: &[f64]) -> Result<Self, SolveError> {
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
        Ok(Dimensions { n, m, nnz_jac, nnz_hess, n_c, m_c, nnz_jac_c, nnz_hess_c })
    }
}

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

/// The variable bounds (length `n`) and constraint bounds (length `m`) the problem gives,
/// none of them NaN.
struct Bounds {
    x_l: Vec<f64>,
    x_u: Vec<f64>,
    g_l: Vec<f64>,
    g_u: Vec<f64>,
}

impl Bounds {
    /// Asks the problem for its bounds and checks that none is NaN.
    fn of<P: Problem>(problem: &P, dims: &Dimensions) -> Result<Self, SolveError> {
        let mut x_l = vec![-INFINITY_BOUND; dims.n];
        let mut x_u = vec![INFINITY_BOUND; dims.n];
        let mut g_l = vec![0.0; dims.m];
        let mut g_u = vec![0.0; dims.m];
        problem.variable_bounds(&mut x_l, &mut x_u);
        problem.constraint_bounds(&mut g_l, &mut g_u);
        for (what, v) in [("variable lower", &x_l), ("variable upper", &x_u), ("constraint lower", &g_l), ("constraint upper", &g_u)] {
            if let Some(i) = v.iter().position(|b| b.is_nan()) {
                return Err(SolveError::Input(format!("{what} bound {i} is NaN")));
            }
        }
        Ok(Bounds { x_l, x_u, g_l, g_u })
    }
}

/// A pointer to the array's first entry, or null for an empty array (Ipopt's convention
/// for the constraint arrays when `m == 0`).
fn null_if_empty(v: &mut [f64]) -> *mut Number {
    if v.is_empty() {
        ptr::null_mut()
    } else {
        v.as_mut_ptr()
    }
}

/// An Ipopt problem whose callbacks were instantiated for `P`, so that `IpoptSolve` on it
/// may be given a `Context<P>` as its user data.
struct ProblemFor<P: Problem> {
    handle: Handle,
    callbacks_for: PhantomData<fn(&mut P)>,
}

/// Creates the Ipopt problem with the callbacks for `P` while `lock` (the process-wide
/// lock) is held, applies `options` and sets the intermediate callback.
fn create_problem<P: Problem>(
    dims: &Dimensions,
    bounds: &mut Bounds,
    options: &Options,
    lock: MutexGuard<'static, ()>,
) -> Result<ProblemFor<P>, SolveError> {
    // SAFETY: we hold the lock; the bound arrays have n resp. m entries (or are null when
    // m == 0) and are copied by Ipopt; the callbacks match the C typedefs.
    let raw = unsafe {
        ffi::CreateIpoptProblem(
            dims.n_c,
            bounds.x_l.as_mut_ptr(),
            bounds.x_u.as_mut_ptr(),
            dims.m_c,
            null_if_empty(&mut bounds.g_l),
            null_if_empty(&mut bounds.g_u),
            dims.nnz_jac_c,
            dims.nnz_hess_c,
            0, // C-style 0-based indices
            Some(eval_f::<P>),
            Some(eval_g::<P>),
            Some(eval_grad_f::<P>),
            Some(eval_jac_g::<P>),
            Some(eval_h::<P>),
        )
    };
    let Some(raw) = NonNull::new(raw) else {
        let Dimensions { n, m, nnz_jac, nnz_hess, .. } = *dims;
        return Err(SolveError::Create(format!(
            "CreateIpoptProblem returned NULL (n = {n}, m = {m}, Jacobian nonzeros = {nnz_jac}, Hessian nonzeros = {nnz_hess})"
        )));
    };
    // SAFETY: `raw` is the result of the successful CreateIpoptProblem above, made while
    // `lock` was held, and only the handle frees it.
    let handle = unsafe { Handle::new(raw, lock) };
    handle.apply(options)?;
    // SAFETY: valid problem; the callback matches the Intermediate_CB typedef.
    let ok = unsafe { ffi::SetIntermediateCallback(handle.raw(), Some(intermediate::<P>)) };
    if ok == FALSE {
        return Err(SolveError::Create("SetIntermediateCallback failed".to_owned()));
    }
    Ok(ProblemFor { handle, callbacks_for: PhantomData })
}

/// What `IpoptSolve` left: its status, the final point, multipliers and objective, and
/// what the callbacks recorded.
struct Run {
    status: Status,
    x: Vec<f64>,
    mult_g: Vec<f64>,
    mult_x_l: Vec<f64>,
    mult_x_u: Vec<f64>,
    objective: f64,
    record: Record,
}

/// Runs `IpoptSolve` from `x0` (and `multipliers`, read by a warm start), then frees the problem and releases the lock. A panic of
/// a callback is re-raised here, after the problem was freed.
fn run_ipopt<P: Problem>(
    created: ProblemFor<P>,
    problem: &mut P,
    x0: &[f64],
    multipliers: Option<&Multipliers>,
    dims: &Dimensions,
    max_iter: u32,
) -> Run {
    let (n, m) = (dims.n, dims.m);
    let mut x = x0.to_vec();
    let mut g = vec![0.0; m];
    let (mut mult_g, mut mult_x_l, mut mult_x_u) = match multipliers {
        Some(start) => (start.constraints.clone(), start.lower.clone(), start.upper.clone()),
        None => (vec![0.0; m], vec![0.0; n], vec![0.0; n]),
    };
    let mut objective = 0.0;
    let history_capacity = (max_iter as usize).saturating_add(1).min(1024);
    let mut ctx = Context::new(&mut *problem, n, m, dims.nnz_jac, dims.nnz_hess, history_capacity);
    let user_data = &mut ctx as *mut Context<'_, P> as UserDataPtr;
    // SAFETY: valid problem, lock held (both owned by the handle); x has n entries, g and
    // mult_g m entries (or are null when m == 0), mult_x_* n entries; `user_data` points
    // to `ctx`, which outlives the call and is not touched by Rust code until IpoptSolve
    // returns; the callbacks were instantiated for this same `P` (`ProblemFor<P>`).
    let raw_status = unsafe {
        ffi::IpoptSolve(
            created.handle.raw(),
            x.as_mut_ptr(),
            null_if_empty(&mut g),
            &mut objective,
            null_if_empty(&mut mult_g),
            mult_x_l.as_mut_ptr(),
            mult_x_u.as_mut_ptr(),
            user_data,
        )
    };
    drop(created); // FreeIpoptProblem under the lock, then unlock
    let status = Status::from_code(raw_status.0);
    let record = match ctx.finish() {
        Ok(record) => record,
        Err(payload) => resume_unwind(payload),
    };
    Run { status, x, mult_g, mult_x_l, mult_x_u, objective, record }
}

/// Calls [`Problem::constraints`] at the final point `x`, counted and timed as a
/// constraints evaluation in `record`: the constraint values and their unscaled violation
/// of the bounds. If the evaluation fails, the values are NaN, the violation is NaN and
/// the error is recorded unless an earlier one was.
fn recompute_constraints<P: Problem>(problem: &mut P, x: &[f64], bounds: &Bounds, record: &mut Record) -> (Vec<f64>, f64) {
    let mut constraint_values = vec![0.0; bounds.g_l.len()];
    let t = Instant::now();
    let recomputed = problem.constraints(x, &mut constraint_values);
    let seconds = t.elapsed().as_secs_f64();
    record.eval.constraints.calls += 1;
    record.eval.constraints.seconds += seconds;
    record.callback_seconds += seconds;
    let max_constraint_violation = match recomputed {
        Ok(()) => constraint_violation(&constraint_values, &bounds.g_l, &bounds.g_u),
        Err(e) => {
            constraint_values.fill(f64::NAN);
            record.first_error.get_or_insert(e);
            f64::NAN
        }
    };
    (constraint_values, max_constraint_violation)
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

impl Run {
    /// The solution of this run, with the constraints recomputed at its final point and
    /// the wall time since the lock was taken.
    fn into_solution(self, constraint_values: Vec<f64>, max_constraint_violation: f64, total_seconds: f64) -> Solution {
        let Record { first_error, failed_evaluations, non_finite_evaluations, history, eval, callback_seconds } = self.record;
        let iterations = history.last().map_or(0, |s| usize::try_from(s.iter).unwrap_or(0));
        Solution {
            status: self.status,
            x: self.x,
            constraint_multipliers: self.mult_g,
            lower_bound_multipliers: self.mult_x_l,
            upper_bound_multipliers: self.mult_x_u,
            objective: self.objective,
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
        }
    }
}
