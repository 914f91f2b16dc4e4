//! The `extern "C"` callbacks Ipopt calls during `IpoptSolve` and the [`Context`] they
//! reach through Ipopt's `user_data` pointer: each callback checks Ipopt's arrays, runs
//! the user's [`Problem`] method timed and inside `catch_unwind`, and records errors,
//! non-finite values, panics and the iteration history, so that no panic crosses the C
//! boundary and every failure reaches [`crate::solve`].

use std::any::Any;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::time::Instant;

use crate::ffi::{self, Bool, Index, Number, UserDataPtr};
use crate::problem::IterationStat;
use crate::problem::{EvalError, Problem};
use crate::solution::EvalTimes;
use crate::{FALSE, TRUE};

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
pub(crate) struct Context<'p, P: Problem> {
    problem: &'p mut P,
    n: usize,
    m: usize,
    nnz_jac: usize,
    nnz_hess: usize,
    /// First panic payload; once set, every callback returns false without running user code.
    panic: Option<Box<dyn Any + Send + 'static>>,
    record: Record,
}

/// What the callbacks recorded during a solve, besides a panic.
pub(crate) struct Record {
    /// The first `Err` a callback returned.
    pub(crate) first_error: Option<EvalError>,
    /// How many callbacks returned `Err`.
    pub(crate) failed_evaluations: usize,
    /// How many callbacks produced NaN or infinite values.
    pub(crate) non_finite_evaluations: usize,
    /// One entry per call of the intermediate callback.
    pub(crate) history: Vec<IterationStat>,
    /// Calls and time per kind of evaluation.
    pub(crate) eval: EvalTimes,
    /// All time spent in callbacks (user code), including structure queries.
    pub(crate) callback_seconds: f64,
}

/// Outcome of a user evaluation as seen by [`Context::run`].
enum Outcome {
    Finite,
    NonFinite,
}

impl<'p, P: Problem> Context<'p, P> {
    /// A context for a problem of `n` variables and `m` constraints with the given
    /// numbers of Jacobian and Hessian entries, its history allocated for
    /// `history_capacity` iterations.
    pub(crate) fn new(problem: &'p mut P, n: usize, m: usize, nnz_jac: usize, nnz_hess: usize, history_capacity: usize) -> Self {
        let record = Record {
            first_error: None,
            failed_evaluations: 0,
            non_finite_evaluations: 0,
            history: Vec::with_capacity(history_capacity),
            eval: EvalTimes::default(),
            callback_seconds: 0.0,
        };
        Context { problem, n, m, nnz_jac, nnz_hess, panic: None, record }
    }

    /// What the callbacks recorded, or the payload of the first panic of a callback.
    pub(crate) fn finish(self) -> Result<Record, Box<dyn Any + Send + 'static>> {
        match self.panic {
            Some(payload) => Err(payload),
            None => Ok(self.record),
        }
    }

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
        self.record.callback_seconds += seconds;
        let stat = match kind {
            Kind::Objective => Some(&mut self.record.eval.objective),
            Kind::Constraints => Some(&mut self.record.eval.constraints),
            Kind::Jacobian => Some(&mut self.record.eval.jacobian),
            Kind::Hessian => Some(&mut self.record.eval.hessian),
            Kind::Other => None,
        };
        if let Some(stat) = stat {
            stat.calls += 1;
            stat.seconds += seconds;
        }
        match result {
            Ok(Ok(Outcome::Finite)) => TRUE,
            Ok(Ok(Outcome::NonFinite)) => {
                self.record.non_finite_evaluations += 1;
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
        self.record.failed_evaluations += 1;
        if self.record.first_error.is_none() {
            self.record.first_error = Some(e);
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
/// `user_data` must be the `*mut Context<P>` that the solve (`run_ipopt`) passed to
/// `IpoptSolve`, and the call must happen during that `IpoptSolve` (the context is alive
/// and not otherwise borrowed then).
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
/// [`crate::solve`] validated (the structure must not change during a solve).
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

pub(crate) unsafe extern "C" fn eval_f<P: Problem>(
    n: Index,
    x: *mut Number,
    _new_x: Bool,
    obj_value: *mut Number,
    user_data: UserDataPtr,
) -> Bool {
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

pub(crate) unsafe extern "C" fn eval_grad_f<P: Problem>(
    n: Index,
    x: *mut Number,
    _new_x: Bool,
    grad_f: *mut Number,
    user_data: UserDataPtr,
) -> Bool {
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

pub(crate) unsafe extern "C" fn eval_g<P: Problem>(
    n: Index,
    x: *mut Number,
    _new_x: Bool,
    m: Index,
    g: *mut Number,
    user_data: UserDataPtr,
) -> Bool {
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
pub(crate) unsafe extern "C" fn eval_jac_g<P: Problem>(
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
pub(crate) unsafe extern "C" fn eval_h<P: Problem>(
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
pub(crate) unsafe extern "C" fn intermediate<P: Problem>(
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
    ctx.record.history.push(stat);
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
