//! Ipopt as a solver of a [`SquareSystem`] (the `ipopt` feature): one generic adapter,
//! [`IpoptSquare`], poses the system as equality constraints `F(x) = 0` with a zero
//! objective and no bounds, with skg-solve's stopping test in Ipopt's intermediate
//! callback; and the options Ipopt is given for a scene.
//!
//! **Stopping Ipopt.** Ipopt is stopped from its intermediate callback as soon as
//! `max |c|` meets the tolerance (status `Solve_Succeeded`: the multipliers of a square
//! system are not used, so the residual is the whole convergence test, as it is for
//! Newton) or the residual's round-off level ([`roundoff`](crate::solve::linalg::roundoff);
//! status `Ipopt_Converged_To_Round_Off`; also where it stalls below the residual a
//! converged solve needs, [`STALLED`]). This saves two costs Ipopt would otherwise
//! pay: after converging on a square problem it factors the KKT matrix once more to
//! "recompute multipliers for the feasibility problem" (it prints that this fails; the
//! multipliers are unused here), and at large `N`, where round-off keeps `max |c|` just
//! above the tolerance, it iterates on until its acceptable-level test (disk,
//! N = 16384: 11 iterations instead of 1). It is also stopped there at the whole solve's
//! deadline (`--time-limit`), as not converged.

use std::time::Instant;

use skg_ipopt::{self as ipopt, Problem};

use super::{IpoptReport, SolverStatus};
use crate::scene::{Backend, ConstraintKind, IpoptValue, Scene};
use crate::solve::linalg::roundoff::residual_roundoff_level;
use crate::solve::linalg::{max_abs, EvalError, IterationStat, SquareSystem};
use crate::solve::run::deadline::Deadline;
use crate::solve::run::status::CONVERGED_RESIDUAL;

/// What an Ipopt solve of a square system found.
pub(super) struct IpoptOutcome {
    /// Ipopt's status, or the stopping test's.
    pub status: SolverStatus,
    /// The last point.
    pub x: Vec<f64>,
    /// The unscaled `max |F|` there, recomputed.
    pub max_residual: f64,
    /// Ipopt's iterations.
    pub iterations: usize,
    /// Its iteration table.
    pub history: Vec<IterationStat>,
    /// Wall time of the solve, and of it, the time in the system's evaluations.
    pub total_s: f64,
    pub evaluation_s: f64,
    /// Its iterations and the evaluations it asked for.
    pub report: IpoptReport,
}

/// Solve `system` from `x0` with Ipopt and `options`, stopped by the tolerance
/// `options.tol`, the round-off level or `deadline` (module docs).
pub(super) fn solve<S: SquareSystem + ?Sized>(
    system: &mut S,
    x0: &[f64],
    options: &ipopt::Options,
    deadline: Option<Deadline>,
) -> Result<IpoptOutcome, ipopt::SolveError> {
    if let Some(d) = deadline.filter(|d| d.passed()) {
        return Ok(not_started(system, x0, d));
    }
    let mut square = IpoptSquare::new(system, options.tol, deadline);
    let sol = ipopt::solve(&mut square, x0, options)?;
    let calls = |stat: ipopt::EvalStat| stat.calls as usize;
    Ok(IpoptOutcome {
        status: square.status(sol.status),
        max_residual: sol.max_constraint_violation,
        iterations: sol.iterations,
        total_s: sol.total_seconds,
        evaluation_s: sol.total_seconds - sol.ipopt_seconds,
        history: sol.history.iter().map(iteration_stat).collect(),
        x: sol.x,
        report: IpoptReport {
            iterations: sol.iterations,
            residual_evaluations: calls(sol.eval.constraints),
            jacobian_evaluations: calls(sol.eval.jacobian),
            hessian_evaluations: calls(sol.eval.hessian),
            internal_s: sol.ipopt_seconds,
            newton_lu_s: None,
        },
    })
}

/// The outcome of a solve not started because `deadline` had passed (Ipopt's analysis
/// and initialization alone may take longer than a whole iteration): the start, as it is.
fn not_started<S: SquareSystem + ?Sized>(system: &mut S, x0: &[f64], deadline: Deadline) -> IpoptOutcome {
    let mut c = vec![0.0; x0.len()];
    let max_residual = match system.residual(x0, &mut c) {
        Ok(()) => max_abs(&c),
        Err(_) => f64::NAN,
    };
    IpoptOutcome {
        status: deadline.stopped(Backend::Ipopt),
        x: x0.to_vec(),
        max_residual,
        iterations: 0,
        history: Vec::new(),
        total_s: 0.0,
        evaluation_s: 0.0,
        report: IpoptReport {
            iterations: 0,
            residual_evaluations: 1,
            jacobian_evaluations: 0,
            hessian_evaluations: 0,
            internal_s: 0.0,
            newton_lu_s: None,
        },
    }
}

/// Why [`IpoptSquare`] stopped Ipopt.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Stop {
    /// `max |c| ≤ tol`.
    Tolerance,
    /// `max |c|` at the round-off level of the last Jacobian, or at most
    /// [`CONVERGED_RESIDUAL`] and no longer falling ([`STALLED`]) or falling ever
    /// slower ([`DECELERATED`]).
    RoundOff,
    /// The deadline (reached, or to be passed by the next iteration), this many seconds
    /// after the start of what it bounds.
    TimeLimit(f64),
    /// `max |c|` rose to [`DIVERGED`] times the least it had been.
    Diverged,
    /// `max |c|` made no progress in the restoration phase just above
    /// [`CONVERGED_RESIDUAL`] ([`RESTORATION_STALLED_ITERATIONS`]).
    Stalled,
}

/// A solve whose `max |c|` rises to this many times the least it had been (or the
/// tolerance, if larger) is stopped as diverged. With a zero objective, Ipopt's filter
/// accepts a step of its main phase only if it lowers `max |c|`: such a rise happens in
/// the restoration phase, once it has lost the way. (The chain on stiff springs with
/// `SBP242` and the natural condition on 512 nodes: from 1.8e-4 at the time stepping
/// down to 3.0e-8 in the restoration phase, then up to 0.23 at its iteration 19 and to
/// 1e4 at its limit of 100 iterations, 3 s later.)
const DIVERGED: f64 = 1e3;

/// An iteration whose `max |c|`, at most [`CONVERGED_RESIDUAL`], is above this fraction
/// of the least before it made no progress; after [`STALLED_ITERATIONS`] such in a row
/// Ipopt is stopped, in any phase, as converged to its round-off level. The equations
/// of a stiff spring sum terms of size k·x, whose rounding the estimate `4 ε Σⱼ |Jᵢⱼ|
/// |xⱼ|` does not always reach: on the stiff dumbbell (k = 1e6, `SBP242`, natural
/// condition, 256 nodes) `max |c|` stays at 8.12e-10 from Ipopt's sixth iteration on,
/// in its restoration phase, until the restoration fails at the 11th to the 22nd
/// (depending on the guess's last digits); stopped at the 8th, the solve is the same
/// (Ipopt returns the restoration phase's point, whose residual and error are those of
/// the 22nd iteration's) at a third of the time.
const STALLED: f64 = 0.5;
/// See [`STALLED`].
const STALLED_ITERATIONS: usize = 2;

/// After this many iterations in a row of the restoration phase with `max |c|` above
/// [`CONVERGED_RESIDUAL`], at most [`STALLED_BAND`] times it, and above [`STALLED`]
/// times the least before it, Ipopt is stopped as stalled (not converged): the
/// restoration phase has come close to a solution it cannot reach, the floor of a nearly
/// singular system. On the chain on stiff springs with `SBP242`, the natural condition
/// and 512 nodes `max |c|` stayed at 3.0e-8 to 4.4e-8 from the restoration phase's
/// fourth iteration to its 17th, and rose to 3.4e-2 at the 18th (stopped there as
/// diverged): 0.65 CPU s to the same verdict, not converged.
const RESTORATION_STALLED_ITERATIONS: usize = 5;

/// See [`RESTORATION_STALLED_ITERATIONS`]. Far from a solution the restoration phase
/// may wander without progress and still find one: the tumbler on 48 nodes (too coarse
/// for its contacts) stayed at `max |c|` of 1.2 to 6 for its first 20 restoration
/// iterations, then converged in 7 more.
const STALLED_BAND: f64 = 100.0;

/// A full step of Ipopt's main phase that brings `max |c|` to at most
/// [`CONVERGED_RESIDUAL`] but contracts it by a factor more than this many times the
/// full step before it did stops Ipopt as converged to the floor of its equations:
/// Newton's steps accelerate on a regular system (each factor at most the one before
/// it, down to round-off), and the next iteration of one that decelerates has not made
/// progress on the shipped and test scenes, only cost. The chain on stiff springs
/// (`SBP242-AD`, natural condition, 512 nodes, a nearly singular Jacobian on which
/// Ipopt regularizes its steps) falls from 3.8e-4 to 2.1e-9 (a factor 5.5e-6) and to
/// 6.9e-11 (0.033) above its tolerance of 1e-11; its third iteration, 0.55 of the
/// solve's 0.66 s, failed its line search in 22 trials with 11 factorizations of the
/// KKT matrix before Ipopt stopped at its acceptable level at the same point.
const DECELERATED: f64 = 100.0;

/// A square system seen by Ipopt, with skg-solve's stopping test in the intermediate
/// callback (module docs): outside the restoration phase, stop once `max |c| ≤ tol`,
/// or, after at least one step, once it is at the round-off level of the last Jacobian
/// Ipopt asked for (as Newton does: the round-off test says that steps no longer reduce
/// the residual, which a starting point alone cannot show). `max |c|` is Ipopt's
/// `inf_pr`: unscaled, since skg-solve turns Ipopt's NLP scaling off (a scene that turns
/// it on under `[solver.ipopt]` is stopped on the scaled value, as Ipopt's own test
/// would be; convergence is judged on the recomputed unscaled residual either way). In
/// any phase, stop once `max |c|` has stalled below [`CONVERGED_RESIDUAL`] ([`STALLED`]),
/// has risen [`DIVERGED`] times above its least, or once the deadline has passed, or
/// would be by an iteration as long as the last one
/// ([`deadline`](crate::solve::run::deadline)).
pub(super) struct IpoptSquare<'p, S: SquareSystem + ?Sized> {
    system: &'p mut S,
    tol: f64,
    /// Round-off level of the residual from the last Jacobian (0 before the first).
    roundoff: f64,
    /// When to stop without converging, if ever.
    deadline: Option<Deadline>,
    /// When the intermediate callback was last called.
    last_callback: Option<Instant>,
    /// The least `max |c|` so far.
    least_inf_pr: f64,
    stalled: usize,
    /// Restoration iterations in a row without progress above [`CONVERGED_RESIDUAL`].
    stalled_above: usize,
    /// `max |c|` at the last callback (infinite before the first).
    last_inf_pr: f64,
    /// The factor by which the last iteration's step contracted `max |c|`, if it was a
    /// full step of the main phase ([`DECELERATED`]).
    contraction: Option<f64>,
    stopped: Option<Stop>,
}

impl<'p, S: SquareSystem + ?Sized> IpoptSquare<'p, S> {
    /// `system` before Ipopt's first iteration, to be stopped at `tol` or at `deadline`.
    fn new(system: &'p mut S, tol: f64, deadline: Option<Deadline>) -> Self {
        IpoptSquare {
            system,
            tol,
            roundoff: 0.0,
            deadline,
            last_callback: None,
            least_inf_pr: f64::INFINITY,
            stalled: 0,
            stalled_above: 0,
            last_inf_pr: f64::INFINITY,
            contraction: None,
            stopped: None,
        }
    }

    /// The solve's status: Ipopt's, unless the stopping test stopped it.
    fn status(&self, ipopt_status: ipopt::Status) -> SolverStatus {
        match (ipopt_status, self.stopped) {
            (ipopt::Status::UserRequestedStop, Some(Stop::Tolerance)) => SolverStatus::Ipopt(ipopt::Status::SolveSucceeded),
            (ipopt::Status::UserRequestedStop, Some(Stop::RoundOff)) => SolverStatus::IpoptConvergedToRoundOff,
            (ipopt::Status::UserRequestedStop, Some(Stop::Diverged)) => SolverStatus::Ipopt(ipopt::Status::DivergingIterates),
            (ipopt::Status::UserRequestedStop, Some(Stop::Stalled)) => SolverStatus::IpoptStalled,
            (ipopt::Status::UserRequestedStop, Some(Stop::TimeLimit(elapsed_s))) => match self.deadline {
                Some(d) => SolverStatus::TimeLimitReached { backend: Backend::Ipopt, bound: d.bound, limit_s: d.limit_s, elapsed_s },
                None => SolverStatus::Ipopt(ipopt::Status::UserRequestedStop),
            },
            (status, _) => SolverStatus::Ipopt(status),
        }
    }

    /// The stop for a lack of progress shown by the iteration `stat` (called once per
    /// iteration, before `least_inf_pr` takes it in): stalled below
    /// [`CONVERGED_RESIDUAL`] in any phase ([`STALLED`]), stalled just above it in the
    /// restoration phase ([`RESTORATION_STALLED_ITERATIONS`]), or a full step of the main
    /// phase that contracted far less than the full step before it ([`DECELERATED`]).
    fn without_progress(&mut self, stat: &ipopt::IterationStat) -> Option<Stop> {
        let r = stat.inf_pr;
        let no_progress = r > STALLED * self.least_inf_pr;
        self.stalled = if r <= CONVERGED_RESIDUAL && no_progress { self.stalled + 1 } else { 0 };
        let near = r > CONVERGED_RESIDUAL && r <= STALLED_BAND * CONVERGED_RESIDUAL;
        self.stalled_above = if stat.restoration && near && no_progress { self.stalled_above + 1 } else { 0 };
        let full_step = !stat.restoration && stat.iter >= 1 && stat.alpha_pr == 1.0 && self.last_inf_pr.is_finite();
        let contraction = full_step.then(|| r / self.last_inf_pr);
        let decelerated =
            matches!((contraction, self.contraction), (Some(now), Some(before)) if r <= CONVERGED_RESIDUAL && now > DECELERATED * before);
        (self.contraction, self.last_inf_pr) = (contraction, r);
        if self.stalled >= STALLED_ITERATIONS || decelerated {
            Some(Stop::RoundOff)
        } else if self.stalled_above >= RESTORATION_STALLED_ITERATIONS {
            Some(Stop::Stalled)
        } else {
            None
        }
    }
}

/// Our evaluation error as Ipopt's (the wrapper keeps the first for its report).
fn to_ipopt(e: EvalError) -> ipopt::EvalError {
    ipopt::EvalError(e.0)
}

impl<S: SquareSystem + ?Sized> Problem for IpoptSquare<'_, S> {
    fn num_variables(&self) -> usize {
        self.system.size()
    }
    fn num_constraints(&self) -> usize {
        self.system.size()
    }
    fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), ipopt::EvalError> {
        self.system.residual(x, c).map_err(to_ipopt)
    }
    fn jacobian_structure(&self) -> &[(u32, u32)] {
        self.system.jacobian_structure()
    }
    fn jacobian_values(&mut self, x: &[f64], values: &mut [f64]) -> Result<(), ipopt::EvalError> {
        self.system.jacobian_values(x, values).map_err(to_ipopt)?;
        flush_subnormals(values);
        let entries = self.system.jacobian_structure().iter().zip(values.iter()).map(|(&(r, c), &v)| (r as usize, c as usize, v));
        self.roundoff = residual_roundoff_level(entries, x, self.system.size());
        Ok(())
    }
    fn hessian_structure(&self) -> &[(u32, u32)] {
        self.system.hessian_structure()
    }
    fn hessian_values(&mut self, x: &[f64], _obj_factor: f64, lambda: &[f64], values: &mut [f64]) -> Result<(), ipopt::EvalError> {
        self.system.hessian_values(x, lambda, values).map_err(to_ipopt)?;
        flush_subnormals(values);
        Ok(())
    }
    fn intermediate(&mut self, stat: &ipopt::IterationStat) -> bool {
        if !stat.restoration {
            if stat.inf_pr <= self.tol {
                self.stopped = Some(Stop::Tolerance);
            } else if stat.iter >= 1 && stat.inf_pr <= self.roundoff {
                self.stopped = Some(Stop::RoundOff);
            }
        }
        // (Evaluated at every iteration: it counts them.)
        self.stopped = self.stopped.or(self.without_progress(stat));
        if stat.inf_pr > DIVERGED * self.least_inf_pr.max(self.tol) {
            self.stopped = Some(Stop::Diverged);
        }
        self.least_inf_pr = self.least_inf_pr.min(stat.inf_pr);
        // The time of the iteration just ended (none for the initialization's).
        let now = Instant::now();
        let iteration_s = self.last_callback.replace(now).map(|last| now.duration_since(last).as_secs_f64());
        if let Some(d) = self.deadline.filter(|d| self.stopped.is_none() && (d.passed() || iteration_s.is_some_and(|s| d.would_pass(s)))) {
            self.stopped = Some(Stop::TimeLimit(d.elapsed_s()));
        }
        self.stopped.is_none()
    }
}

/// Set the subnormal entries of a matrix handed to Ipopt to zero. Debian's MUMPS 5.5
/// corrupts its memory in the analysis of a KKT matrix with subnormal entries (a
/// pendulum of length 1e-320, found by the fuzz run, or 1e-307: "double free or
/// corruption", or a segmentation fault); an entry below the smallest normal number, 2.2e-308, is zero to
/// any factorization's precision next to the others.
fn flush_subnormals(values: &mut [f64]) {
    values.iter_mut().filter(|v| v.is_subnormal()).for_each(|v| *v = 0.0);
}

/// One row of Ipopt's iteration table as the crate's own record.
fn iteration_stat(s: &ipopt::IterationStat) -> IterationStat {
    IterationStat {
        iter: s.iter,
        objective: s.objective,
        inf_pr: s.inf_pr,
        inf_du: s.inf_du,
        mu: s.mu,
        d_norm: s.d_norm,
        regularization: s.regularization,
        alpha_pr: s.alpha_pr,
        alpha_du: s.alpha_du,
        ls_trials: s.ls_trials,
        restoration: s.restoration,
    }
}

/// MUMPS's options for a scene's KKT matrices, chosen by the scene's constraints:
///
/// * **position constraints**: QAMD (6) with MUMPS's permutation and scaling option 6
///   and its scaling 7. Measured on Debian's MUMPS, release build, no verification, CPU
///   seconds: a chain of 8 rods (Cartesian coordinates) at N = 1024 10.7 s → 0.7 s, at
///   N = 4096 over 150 s → 2.3 s (41 s without the scaling), a chain of 16 rods at
///   N = 1024 27 s → 3.3 s, the pendulum at N = 8192 over 5 minutes → 0.2 s (11.7 s
///   without the scaling); without position constraints QAMD is not a gain (the knife
///   edge at N = 4096 0.13 s → 0.50 s).
/// * **velocity constraints only**: AMF (2) with MUMPS's scaling 7. Unscaled, MUMPS's
///   threshold pivoting on these KKT matrices (zero diagonal blocks) delayed more pivots
///   the larger N, and the factor grew faster than N: the knife edge had 290, 553, 696,
///   828 and 1183 factor entries per node at N = 4096, 8192, 16384, 32768 and 65536.
///   Scaled (rows and columns equilibrated), it has 288 at every N from 16384 to 10⁵,
///   and the solve at N = 65536 takes 4.3 s instead of 28 s.
/// * **no constraints**: AMF and no scaling.
///
/// Each is deterministic (SCOTCH, MUMPS's automatic choice, was not).
pub fn mumps_options(scene: &Scene) -> Vec<(&'static str, i32)> {
    let has = |kind: ConstraintKind| scene.constraints.iter().any(|c| c.kind == kind);
    if has(ConstraintKind::Position) {
        vec![("mumps_scaling", 7), ("mumps_pivot_order", 6), ("mumps_permuting_scaling", 6)]
    } else if has(ConstraintKind::Velocity) {
        vec![("mumps_scaling", 7), ("mumps_pivot_order", 2)]
    } else {
        vec![("mumps_scaling", 0), ("mumps_pivot_order", 2)]
    }
}

/// Ipopt's options for a scene: its `[solver]` settings, then the pass-through options.
pub(super) fn options(scene: &Scene) -> ipopt::Options {
    let solver = &scene.solver;
    let pass_through = solver.ipopt.iter().map(|(k, v)| {
        let v = match v {
            IpoptValue::Int(i) => ipopt::OptionValue::Int(*i),
            IpoptValue::Num(x) => ipopt::OptionValue::Num(*x),
            IpoptValue::Str(s) => ipopt::OptionValue::Str(s.clone()),
        };
        (k.clone(), v)
    });
    ipopt::Options {
        tol: solver.tol,
        constr_viol_tol: solver.tol,
        max_iter: solver.max_iter,
        print_level: solver.print_level,
        linear_solver: solver.linear_solver.clone(),
        output_file: solver.ipopt_log.clone(),
        // MUMPS's default scaling (77, automatic) made the very first factorization of
        // the tumbler's KKT matrix take minutes at N ≥ 2048 (0.06 s without it; measured
        // on Debian's MUMPS 5.5). MUMPS's automatic pivot order picks SCOTCH, whose
        // ordering of the same matrix varied from run to run (different fill): the same
        // solve gave different trajectories (in the last digits) and, on hard wall
        // scenes, different iteration counts and exit codes from run to run. AMF (2) is
        // deterministic and was faster on every scene without position constraints
        // measured; with constraints, see [`mumps_options`] (docs/solver.md, "Posing the
        // system"). The scene's own [solver.ipopt] options come after and override these.
        extra: mumps_options(scene).into_iter().map(|(k, v)| (k.to_string(), ipopt::OptionValue::Int(v))).chain(pass_through).collect(),
        ..ipopt::Options::default()
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;
    use std::time::Duration;

    use super::*;
    use crate::scene::{Overrides, SceneFile};
    use crate::solve::run::deadline::Bound;

    /// `F(x) = x − 1`, which the test below never lets Ipopt solve.
    struct Shift;
    impl SquareSystem for Shift {
        fn size(&self) -> usize {
            1
        }
        fn residual(&mut self, x: &[f64], f: &mut [f64]) -> Result<(), EvalError> {
            f[0] = x[0] - 1.0;
            Ok(())
        }
        fn jacobian_structure(&self) -> &[(u32, u32)] {
            &[(0, 0)]
        }
        fn jacobian_values(&mut self, _: &[f64], v: &mut [f64]) -> Result<(), EvalError> {
            v[0] = 1.0;
            Ok(())
        }
    }

    /// Ipopt's report of iteration `iter` with `max |c|` = `inf_pr`, in its restoration
    /// phase or not.
    fn stat(iter: i32, inf_pr: f64, restoration: bool) -> ipopt::IterationStat {
        ipopt::IterationStat {
            iter,
            objective: 0.0,
            inf_pr,
            inf_du: 0.0,
            mu: 0.0,
            d_norm: 0.0,
            regularization: 0.0,
            alpha_pr: 0.0,
            alpha_du: 0.0,
            ls_trials: 1,
            restoration,
        }
    }

    /// Iterations of 0.3 s against a deadline 1.05 s away: the callback stops Ipopt
    /// before the iteration that would end past the deadline (at iteration 3, at 0.9 s,
    /// at the latest; a loaded machine, whose iterations take longer, stops earlier), not
    /// at the first callback past it (iteration 4, 1.2 s).
    #[test]
    fn ipopt_is_stopped_before_an_iteration_that_would_pass_the_deadline() {
        let mut system = Shift;
        let deadline = Deadline::from(Instant::now(), 1.05, Bound::TimeLimit);
        let mut square = IpoptSquare::new(&mut system, 1e-12, deadline);
        let stopped_at = (0..10).find(|&iter| {
            if iter > 0 {
                std::thread::sleep(Duration::from_millis(300));
            }
            !square.intermediate(&stat(iter, 1.0, false))
        });
        let stopped_at = stopped_at.expect("stopped");
        assert!((1..=3).contains(&stopped_at), "stopped at iteration {stopped_at}");
        assert!(matches!(square.stopped, Some(Stop::TimeLimit(_))));
        assert!(matches!(square.status(ipopt::Status::UserRequestedStop), SolverStatus::TimeLimitReached { backend: Backend::Ipopt, .. }));
    }

    /// `max |c|` falling to 1e-8 and rising again: stopped as diverged at 1e3 times its
    /// least (1e-5), not before (a rise to 9e-6 goes on).
    #[test]
    fn ipopt_is_stopped_once_the_residual_rises_a_thousandfold_above_its_least() {
        let mut system = Shift;
        let mut square = IpoptSquare::new(&mut system, 1e-12, None);
        for (iter, inf_pr) in [1e-4, 1e-6, 1e-8, 9e-6, 1e-7].into_iter().enumerate() {
            assert!(square.intermediate(&stat(iter as i32, inf_pr, true)), "stopped at {inf_pr:e}");
        }
        assert!(!square.intermediate(&stat(5, 1.1e-5, true)));
        assert_eq!(square.status(ipopt::Status::UserRequestedStop), SolverStatus::Ipopt(ipopt::Status::DivergingIterates));
    }

    /// `max |c|` stalling below 1e-8 in the restoration phase (the stiff dumbbell's
    /// 8.12e-10): stopped at the second iteration without progress, as converged to the
    /// round-off level; a residual that keeps halving, or stalls above 1e-8, goes on.
    #[test]
    fn ipopt_is_stopped_once_the_residual_stalls_below_the_converged_level() {
        let mut system = Shift;
        let mut square = IpoptSquare::new(&mut system, 1e-12, None);
        for (iter, inf_pr) in [2e-4, 4e-8, 8.12e-10].into_iter().enumerate() {
            assert!(square.intermediate(&stat(iter as i32, inf_pr, true)), "stopped at {inf_pr:e}");
        }
        assert!(square.intermediate(&stat(3, 8.13e-10, true)));
        assert!(!square.intermediate(&stat(4, 8.12e-10, true)));
        assert_eq!(square.status(ipopt::Status::UserRequestedStop), SolverStatus::IpoptConvergedToRoundOff);

        let mut system = Shift;
        let mut square = IpoptSquare::new(&mut system, 1e-12, None);
        let falling = [1e-6, 4e-9, 1.9e-9, 0.9e-9, 0.4e-9, 0.19e-9];
        let above = [2e-8, 2e-8, 2e-8, 2e-8];
        for (iter, inf_pr) in falling.into_iter().chain(above).enumerate() {
            assert!(square.intermediate(&stat(iter as i32, inf_pr, true)), "stopped at iteration {iter}");
        }
    }

    /// The stiff chain's restoration phase (`SBP242`, natural, 512 nodes): `max |c|` at
    /// 3.0e-8 to 4.4e-8 from its fourth iteration on: stopped as stalled at the fifth
    /// iteration in a row without progress, not converged. A restoration phase that stalls
    /// for four iterations and then progresses goes on, as does one that wanders far from a
    /// solution (the tumbler on 48 nodes) before it finds one.
    #[test]
    fn ipopt_is_stopped_once_its_restoration_phase_stalls_above_the_converged_level() {
        let mut system = Shift;
        let mut square = IpoptSquare::new(&mut system, 1e-12, None);
        let chain = [1.76e-4, 1.76e-4, 4.44e-5, 3.68e-7, 3.07e-8, 2.99e-8, 3.12e-8, 4.17e-8, 4.04e-8];
        for (iter, inf_pr) in chain.into_iter().enumerate() {
            assert!(square.intermediate(&stat(iter as i32, inf_pr, iter > 0)), "stopped at iteration {iter}");
        }
        assert!(!square.intermediate(&stat(9, 4.03e-8, true)));
        assert_eq!(square.status(ipopt::Status::UserRequestedStop), SolverStatus::IpoptStalled);
        assert!(!square.status(ipopt::Status::UserRequestedStop).is_success());

        let mut system = Shift;
        let mut square = IpoptSquare::new(&mut system, 1e-12, None);
        let recovering = [1e-4, 4e-8, 4e-8, 4e-8, 4e-8, 4e-8, 1.9e-8, 1.9e-8, 1.9e-8, 1.9e-8, 0.9e-8];
        for (iter, inf_pr) in recovering.into_iter().enumerate() {
            assert!(square.intermediate(&stat(iter as i32, inf_pr, true)), "stopped at iteration {iter}");
        }

        // The tumbler on 48 nodes: 20 restoration iterations at 1.2 to 6, then a solution.
        let mut system = Shift;
        let mut square = IpoptSquare::new(&mut system, 1e-12, None);
        let wandering = [1.04, 6.03, 5.99, 5.86, 1.77, 1.87, 1.31, 2.63, 1.20, 5.45, 4.62, 4.30, 1.74, 1.20, 1.18, 4.97, 3.73, 2.80];
        let found = [1.56, 8.9e-2, 2.0e-3, 9.2e-7, 3.8e-7, 1.1e-8];
        for (iter, inf_pr) in wandering.into_iter().chain(found).enumerate() {
            assert!(square.intermediate(&stat(iter as i32, inf_pr, true)), "stopped at iteration {iter}");
        }
    }

    /// Ipopt's report of a full step of its main phase to `max |c|` = `inf_pr`.
    fn full_step(iter: i32, inf_pr: f64) -> ipopt::IterationStat {
        ipopt::IterationStat { alpha_pr: 1.0, ..stat(iter, inf_pr, false) }
    }

    /// Full steps whose contraction worsens a hundredfold below 1e-8 (the stiff chain's
    /// 3.8e-4 → 2.1e-9 → 6.9e-11): stopped as converged to the round-off level at once.
    /// Steps that accelerate (Newton's on a regular system), that contract steadily, that
    /// decelerate above 1e-8, or that the line search cut, go on.
    #[test]
    fn ipopt_is_stopped_once_its_full_steps_decelerate_below_the_converged_level() {
        let mut system = Shift;
        let mut square = IpoptSquare::new(&mut system, 1e-12, None);
        assert!(square.intermediate(&stat(0, 3.8e-4, false)));
        assert!(square.intermediate(&full_step(1, 2.09e-9)));
        assert!(!square.intermediate(&full_step(2, 6.85e-11)));
        assert_eq!(square.status(ipopt::Status::UserRequestedStop), SolverStatus::IpoptConvergedToRoundOff);

        let goes_on = |residuals: &[f64], cut: Option<usize>| {
            let mut system = Shift;
            let mut square = IpoptSquare::new(&mut system, 1e-14, None);
            residuals.iter().enumerate().all(|(i, &r)| {
                let step = if i == 0 { stat(0, r, false) } else { full_step(i as i32, r) };
                square.intermediate(&ipopt::IterationStat { alpha_pr: if Some(i) == cut { 0.5 } else { step.alpha_pr }, ..step })
            })
        };
        assert!(goes_on(&[1e-2, 1e-5, 1e-10, 1e-13], None), "accelerating");
        assert!(goes_on(&[1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13], None), "steady");
        assert!(goes_on(&[1e-1, 1e-6, 1e-7, 1e-9, 1e-13], None), "decelerating above 1e-8");
        assert!(goes_on(&[3.8e-4, 2.09e-9, 6.85e-11, 1e-13], Some(2)), "a step cut by the line search");
    }

    /// A shipped scene of `scenarios/`.
    fn shipped(name: &str) -> Scene {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios").join(name);
        SceneFile::load(&path).unwrap().resolve(&Overrides::default()).unwrap()
    }

    /// The value of MUMPS option `name` among `options`, the last one if repeated (as
    /// Ipopt sets them in order).
    fn last(options: &[(String, ipopt::OptionValue)], name: &str) -> Option<ipopt::OptionValue> {
        options.iter().rev().find(|(k, _)| k == name).map(|(_, v)| v.clone())
    }

    #[test]
    fn mumps_options_follow_the_scene_s_constraints() {
        let chosen = |name: &str| {
            let o = mumps_options(&shipped(name));
            let get = |key: &str| o.iter().find(|(k, _)| *k == key).map(|&(_, v)| v);
            (get("mumps_scaling"), get("mumps_pivot_order"), get("mumps_permuting_scaling"))
        };
        // Velocity constraints only (a blade; a rolling contact): scaled, AMF.
        assert_eq!(chosen("knife_edge.toml"), (Some(7), Some(2), None));
        assert_eq!(chosen("rolling_disk.toml"), (Some(7), Some(2), None));
        // A position constraint: scaled, QAMD with the permutation and scaling 6.
        assert_eq!(chosen("pendulum.toml"), (Some(7), Some(6), Some(6)));
        // No constraints: unscaled, AMF.
        assert_eq!(chosen("free_fall.toml"), (Some(0), Some(2), None));
    }

    #[test]
    fn a_scene_s_own_mumps_options_override_the_chosen_ones() {
        let mut scene = shipped("knife_edge.toml");
        assert_eq!(last(&options(&scene).extra, "mumps_scaling"), Some(ipopt::OptionValue::Int(7)));
        scene.solver.ipopt.insert("mumps_scaling".into(), IpoptValue::Int(0));
        assert_eq!(last(&options(&scene).extra, "mumps_scaling"), Some(ipopt::OptionValue::Int(0)));
    }
}
