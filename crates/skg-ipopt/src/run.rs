//! One solve: the checks of the problem's sizes, structures, starting point and bounds,
//! the creation of the Ipopt problem under the process-wide lock, the run of
//! `IpoptSolve` with the callbacks, and the [`Solution`] with the constraint violation
//! recomputed at the final point.

use std::panic::resume_unwind;
use std::ptr::{self, NonNull};
use std::time::Instant;

use crate::callbacks::{eval_f, eval_g, eval_grad_f, eval_h, eval_jac_g, intermediate, Context};
use crate::ffi::{self, Index, UserDataPtr};
use crate::handle::Handle;
use crate::lock::{lock_ipopt, NestGuard};
use crate::options::Options;
use crate::problem::{Problem, INFINITY_BOUND};
use crate::solution::{EvalTimes, Solution, SolveError};
use crate::status::Status;
use crate::FALSE;

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
