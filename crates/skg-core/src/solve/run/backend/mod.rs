//! The solvers of the square system: Ipopt (the default, with the `ipopt` feature) and
//! Newton's method with a sparse LU ([`newton`](crate::solve::linalg::newton)), behind one
//! interface, [`SquareSolver`].
//!
//! Both see the system as a [`SquareSystem`] (`systems.rs`: `Reduced`,
//! `R(P) = ∂S/∂M = 0`, and `Full`, `∇S(Z) = 0`); Ipopt through one generic adapter
//! (`ipopt.rs`, which also says how Ipopt is stopped). A [`SquareSolver`] is built once
//! per action and keeps what does not change between solves of the same structure: the
//! sparsity plans of the Jacobian (and Hessian) and, for Newton, the symbolic LU
//! analysis. [`SquareSolver::solve`] can then be called for any number of starting
//! points or actions of the same model and grid (only the initial state `q0`, `v0` may
//! differ): the time windows of one run share one solver.
//!
//! **The kept analysis.** When a Newton solver is dropped, its symbolic LU analysis (a
//! [`SystemSolver`]) is kept, one per thread, and the next [`SquareSolver`] of the same
//! thread with `backend = "newton"` takes it over. It is used only if the new system's
//! Jacobian structure is the same (size and every (row, column) entry in the same order,
//! [`SystemSolver::fits`]); otherwise it is dropped and the structure analysed anew. So
//! every path that solves several systems of equal structure one after the other reuses
//! it without being told: the attempts of the fallback ladder, the points a sweep worker
//! runs one after the other, and repeated `skg.solve` calls from one Python thread; a
//! fit factors its Jacobian on it ([`factorization_on_kept_analysis`]). The
//! slot is per thread, not one process-wide mutex, so solves on parallel threads (e.g.
//! `cargo test`) neither wait for each other nor take each other's analysis, and a
//! report's `analysis_reused` depends only on what ran before on the same thread. The
//! kept value holds the memory of its last factorization until the next Newton solve on
//! the thread replaces it, or [`discard_kept_analysis`] frees it. Ipopt keeps doing its
//! own MUMPS analysis in every solve (its C interface offers no way to keep one).
//!
//! **Hand-over.** When Newton does not converge (and was not stopped at the deadline,
//! [`SquareSolver::set_deadline`]), the same system is solved by Ipopt (when the crate
//! is built with it) from the same starting point, so a Newton solve
//! never ends worse than an Ipopt solve; the [`BackendReport`] records Newton's own
//! outcome and that Ipopt finished.

use std::cell::RefCell;
use std::fmt;

use serde::Serialize;

use crate::discrete::action::{Action, Block, MatrixPlan};
use crate::scene::{Backend, Formulation, HessianMode, Scene};
use crate::solve::linalg::roundoff::row_roundoff_levels;
use crate::solve::linalg::{
    IterationStat, NewtonError, NewtonOptions, NewtonStats, NewtonStatus, SparseFactorization, SquareSystem, SystemSolver,
};
use crate::solve::run::deadline::{self, Bound, Deadline};
#[cfg(feature = "ipopt")]
use skg_ipopt as ipopt;

#[cfg(feature = "ipopt")]
mod ipopt_square;
mod systems;
pub(crate) use systems::Reduced;

#[cfg(feature = "ipopt")]
pub use ipopt_square::mumps_options;
use systems::Full;

/// The status of the backend that ended a solve: Ipopt's or Newton's own.
///
/// Serialized as its name (`"Solve_Succeeded"`, `"Newton_Converged"`, …).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SolverStatus {
    /// Ipopt's return status.
    #[cfg(feature = "ipopt")]
    Ipopt(ipopt::Status),
    /// Ipopt stopped by its intermediate callback (`StopWhenSolved`) with `max |c|` above
    /// the tolerance but at the residual's round-off level (`Ipopt_Converged_To_Round_Off`):
    /// a success.
    #[cfg(feature = "ipopt")]
    IpoptConvergedToRoundOff,
    /// Ipopt stopped by its intermediate callback in its restoration phase, where `max |c|`
    /// made no progress above the converged residual (`Ipopt_Stalled`): not converged.
    #[cfg(feature = "ipopt")]
    IpoptStalled,
    /// Newton's status.
    Newton(NewtonStatus),
    /// The backend was stopped at a [`Deadline`] (the time limit or a budget) before it
    /// converged: Ipopt from its intermediate callback, Newton before its next step.
    TimeLimitReached {
        /// The backend that was stopped.
        backend: Backend,
        /// What set the deadline.
        bound: Bound,
        /// The deadline, seconds from the start of what it bounds.
        limit_s: f64,
        /// The seconds since that start, when it was stopped.
        elapsed_s: f64,
    },
}

impl SolverStatus {
    /// Whether the backend reports success (Ipopt: [`ipopt::Status::is_success`]).
    pub fn is_success(&self) -> bool {
        match self {
            #[cfg(feature = "ipopt")]
            SolverStatus::Ipopt(s) => s.is_success(),
            #[cfg(feature = "ipopt")]
            SolverStatus::IpoptConvergedToRoundOff => true,
            #[cfg(feature = "ipopt")]
            SolverStatus::IpoptStalled => false,
            SolverStatus::Newton(s) => s.is_success(),
            SolverStatus::TimeLimitReached { .. } => false,
        }
    }

    /// The status's stable name: Ipopt's identifier or Newton's `Newton_…` name.
    pub fn name(&self) -> &'static str {
        match self {
            #[cfg(feature = "ipopt")]
            SolverStatus::Ipopt(s) => s.name(),
            #[cfg(feature = "ipopt")]
            SolverStatus::IpoptConvergedToRoundOff => "Ipopt_Converged_To_Round_Off",
            #[cfg(feature = "ipopt")]
            SolverStatus::IpoptStalled => "Ipopt_Stalled",
            SolverStatus::Newton(s) => s.name(),
            SolverStatus::TimeLimitReached { backend: Backend::Ipopt, .. } => "Ipopt_Time_Limit_Reached",
            SolverStatus::TimeLimitReached { backend: Backend::Newton, .. } => "Newton_Time_Limit_Reached",
        }
    }
}

impl fmt::Display for SolverStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            #[cfg(feature = "ipopt")]
            SolverStatus::Ipopt(s) => write!(f, "{s}"),
            #[cfg(feature = "ipopt")]
            SolverStatus::IpoptConvergedToRoundOff => {
                f.write_str("Ipopt converged to the round-off level of the residual (above the requested tolerance)")
            }
            #[cfg(feature = "ipopt")]
            SolverStatus::IpoptStalled => {
                f.write_str("Ipopt stalled in its restoration phase: the residual made no progress above the converged level")
            }
            SolverStatus::Newton(s) => write!(f, "{s}"),
            SolverStatus::TimeLimitReached { backend, bound, limit_s, elapsed_s } => {
                let who = match backend {
                    Backend::Ipopt => "Ipopt",
                    Backend::Newton => "Newton's method",
                };
                let (what, start) = (deadline::describe(*bound, *limit_s), deadline::start_of(*bound));
                write!(f, "{who} was stopped at {what}, {elapsed_s:.1} s after {start} started")
            }
        }
    }
}

impl Serialize for SolverStatus {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match self {
            #[cfg(feature = "ipopt")]
            SolverStatus::Ipopt(s) => s.serialize(serializer),
            #[cfg(feature = "ipopt")]
            SolverStatus::IpoptConvergedToRoundOff | SolverStatus::IpoptStalled => serializer.serialize_str(self.name()),
            SolverStatus::Newton(s) => s.serialize(serializer),
            SolverStatus::TimeLimitReached { .. } => serializer.serialize_str(self.name()),
        }
    }
}

/// What Newton's method did in a solve with `backend = "newton"`.
#[derive(Debug, Clone, Serialize)]
pub struct NewtonReport {
    /// How Newton ended (`Newton_Converged` or why not).
    pub status: NewtonStatus,
    /// Newton steps.
    pub iterations: usize,
    /// max |F| where Newton stopped.
    pub max_residual: f64,
    /// Seconds of the symbolic LU analysis in this solve (0 when it was reused).
    pub analysis_s: f64,
    /// Whether the symbolic analysis of an earlier solve of equal structure was reused.
    pub analysis_reused: bool,
    /// Evaluations, factorizations and their times.
    #[serde(flatten)]
    pub stats: NewtonStats,
}

impl NewtonReport {
    /// `computed` or `reused`: whether this solve made its symbolic LU analysis or took
    /// over one of an earlier solve of equal structure (results.csv's `lu_analysis`).
    pub fn lu_analysis(&self) -> &'static str {
        if self.analysis_reused {
            "reused"
        } else {
            "computed"
        }
    }
}

/// What Ipopt did in a solve (with `backend = "ipopt"`, or after Newton handed over):
/// its iterations and the evaluations of our callbacks it asked for.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct IpoptReport {
    /// Ipopt's iterations.
    pub iterations: usize,
    /// Residual evaluations (Ipopt's constraint callback; the recomputation of the
    /// residual at the returned point included).
    pub residual_evaluations: usize,
    /// Evaluations of the Jacobian's values.
    pub jacobian_evaluations: usize,
    /// Evaluations of the Hessian's values (0 unless the exact Hessian is given).
    pub hessian_evaluations: usize,
    /// Seconds of Ipopt's own work (its linear algebra, mostly MUMPS's factorizations of
    /// the KKT matrix): the solve's time outside our callbacks.
    pub internal_s: f64,
    /// Seconds of one numeric factorization of the same Jacobian by the Newton backend's
    /// sparse LU, timed at Ipopt's last point after the solve; only when Ipopt was asked
    /// for and its own work took most of a long solve ([`NEWTON_LU_TIMED_FROM_S`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub newton_lu_s: Option<f64>,
}

/// Ipopt's own work, in seconds, from which a solve also times the Newton backend's
/// factorization of the same Jacobian ([`IpoptReport::newton_lu_s`]), when that work is
/// at least [`NEWTON_LU_TIMED_SHARE`] of the solve: the comparison is then worth its
/// cost (one analysis and one factorization, a small fraction of Ipopt's time).
pub const NEWTON_LU_TIMED_FROM_S: f64 = 1.0;

/// See [`NEWTON_LU_TIMED_FROM_S`].
pub const NEWTON_LU_TIMED_SHARE: f64 = 0.75;

/// Which backend ran, and how.
#[derive(Debug, Clone, Serialize)]
pub struct BackendReport {
    /// The backend the settings asked for.
    pub requested: Backend,
    /// Newton's own outcome (only with `backend = "newton"`).
    pub newton: Option<NewtonReport>,
    /// Whether Newton failed and Ipopt solved the system from the same start.
    pub handed_over_to_ipopt: bool,
    /// Ipopt's iterations and evaluations, when Ipopt ran.
    pub ipopt: Option<IpoptReport>,
}

/// The root of the square system as a backend found it (whatever its status).
#[derive(Debug, Clone)]
pub struct SystemSolution {
    /// The status of the backend that finished (Ipopt's after a hand-over).
    pub status: SolverStatus,
    /// The whole unknown vector Z (the minus block zero for the reduced formulation).
    pub z: Vec<f64>,
    /// Unscaled max |c| of the system at `z`.
    pub max_residual: f64,
    /// Iterations of the backend that finished.
    pub iterations: usize,
    /// Its iteration table.
    pub history: Vec<IterationStat>,
    /// Wall time of all backends, in seconds.
    pub total_s: f64,
    /// Of that, time in the residual, Jacobian and Hessian evaluations.
    pub evaluation_s: f64,
    /// Which backend ran, and Newton's own outcome.
    pub report: BackendReport,
}

/// Why the system could not be solved at all (a non-converged run is a
/// [`SystemSolution`] with a failure status).
#[derive(Debug, thiserror::Error)]
pub enum BackendError {
    /// Ipopt could not be run (options, sizes, a callback error it did not recover from).
    #[cfg(feature = "ipopt")]
    #[error(transparent)]
    Ipopt(#[from] ipopt::SolveError),
    /// An Ipopt solve was asked of a build without Ipopt.
    #[cfg(not(feature = "ipopt"))]
    #[error("this build of skg-solve has no Ipopt (it was built without the `ipopt` feature)")]
    NoIpopt,
    /// The Newton backend could not be set up (structure, analysis).
    #[error(transparent)]
    Newton(#[from] NewtonError),
}

/// The backend and its options.
struct Settings {
    backend: Backend,
    /// When the solve must end, if ever (Newton's options hold the same moment).
    deadline: Option<Deadline>,
    newton: NewtonOptions,
    #[cfg(feature = "ipopt")]
    ipopt: ipopt::Options,
}

/// The solver of one action's square system, keeping its sparsity plans and (Newton)
/// its symbolic LU analysis between solves.
pub struct SquareSolver {
    formulation: Formulation,
    settings: Settings,
    jac: MatrixPlan,
    hess: Option<MatrixPlan>,
    lu: Option<SystemSolver>,
    /// Seconds of the analysis in `lu` made by [`SquareSolver::analyse`] and not yet
    /// reported by a solve.
    unreported_analysis_s: Option<f64>,
}

impl SquareSolver {
    /// The solver of `action`'s system with `scene`'s formulation and solver settings:
    /// the sparsity plans and, with `backend = "newton"`, the thread's kept LU analysis
    /// (see the module documentation; used by the first solve if its structure fits).
    pub fn new(scene: &Scene, action: &Action) -> SquareSolver {
        let jac_block = match scene.formulation {
            Formulation::Reduced => Block::ReducedJacobian,
            Formulation::Full => Block::FullJacobian,
        };
        let exact_hessian = scene.formulation == Formulation::Reduced && scene.solver.hessian == HessianMode::Exact;
        SquareSolver {
            formulation: scene.formulation,
            settings: Settings {
                backend: scene.solver.backend,
                deadline: None,
                newton: NewtonOptions {
                    tol: scene.solver.tol,
                    max_iter: scene.solver.max_iter,
                    chord: true,
                    single_precision: single_precision_pays(scene, action),
                    deadline: None,
                },
                #[cfg(feature = "ipopt")]
                ipopt: ipopt_square::options(scene),
            },
            jac: action.plan(jac_block),
            hess: exact_hessian.then(|| action.plan(Block::ReducedHessian)),
            lu: if scene.solver.backend == Backend::Newton { KEPT_ANALYSIS.take() } else { None },
            unreported_analysis_s: None,
        }
    }

    /// Stop every later solve at `deadline` (none: no limit), as not converged with
    /// [`SolverStatus::TimeLimitReached`].
    pub fn set_deadline(&mut self, deadline: Option<Deadline>) {
        self.settings.deadline = deadline;
        self.settings.newton.deadline = deadline.map(|d| d.at);
    }

    /// The deadline of every later solve, if any ([`SquareSolver::set_deadline`]).
    pub fn deadline(&self) -> Option<Deadline> {
        self.settings.deadline
    }

    /// The Jacobian's sparsity plan.
    pub fn jacobian_plan(&self) -> &MatrixPlan {
        &self.jac
    }

    /// The Hessian's sparsity plan (reduced formulation with the exact Hessian only).
    pub fn hessian_plan(&self) -> Option<&MatrixPlan> {
        self.hess.as_ref()
    }

    /// Whether a Newton solve of `action`'s system would make a new LU analysis (the
    /// backend is Newton and the solver holds none of this structure).
    pub fn needs_analysis(&self, action: &Action) -> bool {
        let n = unknowns(self.formulation, action);
        self.settings.backend == Backend::Newton && !self.lu.as_ref().is_some_and(|lu| lu.fits(n, &self.jac.structure))
    }

    /// Make the Newton backend's LU analysis of `action`'s system now, if
    /// [`SquareSolver::needs_analysis`]: it needs only the structure, so that a caller
    /// can run it beside the initial guess. The next [`SquareSolver::solve`] uses it and
    /// reports it as made for that solve.
    pub fn analyse(&mut self, action: &Action) -> Result<(), BackendError> {
        if !self.needs_analysis(action) {
            return Ok(());
        }
        self.lu = None;
        let analysed = SystemSolver::new(unknowns(self.formulation, action), &self.jac.structure)?;
        self.unreported_analysis_s = Some(analysed.analysis_seconds());
        self.lu = Some(analysed);
        Ok(())
    }

    /// Solve the system of `action` (the model and grid this solver was built for) from
    /// the whole unknown vector `z0` with the configured backend.
    pub fn solve(&mut self, action: &Action, z0: &[f64]) -> Result<SystemSolution, BackendError> {
        // Newton's analysis, unless one of this structure is in hand (made beside the
        // guess, or kept from an earlier solve).
        self.analyse(action)?;
        let analysis_s = self.unreported_analysis_s.take();
        let lu = self.lu.as_mut();
        let n_p = action.layout.n_p;
        match self.formulation {
            Formulation::Reduced => {
                let mut p = Reduced::new(action, z0, &self.jac, self.hess.as_ref());
                let mut solution = solve_system(&self.settings, lu, analysis_s, &mut p, &z0[..n_p])?;
                let mut z = vec![0.0; action.layout.len()];
                z[..n_p].copy_from_slice(&solution.z);
                solution.z = z;
                Ok(solution)
            }
            Formulation::Full => {
                let mut p = Full::new(action, &self.jac);
                solve_system(&self.settings, lu, analysis_s, &mut p, z0)
            }
        }
    }
}

/// Whether Newton factors the Jacobian in single precision first and refines in double
/// (docs/solver.md#mixed-precision): for systems of at least
/// [`SINGLE_PRECISION_MIN_UNKNOWNS`] unknowns with at least
/// [`SINGLE_PRECISION_MIN_PER_NODE`] per node.
fn single_precision_pays(scene: &Scene, action: &Action) -> bool {
    let n = unknowns(scene.formulation, action);
    n >= SINGLE_PRECISION_MIN_UNKNOWNS && n >= SINGLE_PRECISION_MIN_PER_NODE * action.layout.nodes
}

/// The unknowns of `action`'s square system in `formulation`.
fn unknowns(formulation: Formulation, action: &Action) -> usize {
    match formulation {
        Formulation::Reduced => action.layout.n_p,
        Formulation::Full => action.layout.len(),
    }
}

/// Below this many unknowns a factorization costs too little for its precision to
/// matter (a chain of 3 rods at N = 1024, 9 unknowns per node: 0.018 s in single
/// precision against 0.014 s in double).
const SINGLE_PRECISION_MIN_UNKNOWNS: usize = 10_000;

/// Unknowns per node from which single precision pays: where the sparse LU works on
/// dense blocks (faer's supernodal LU; a chain of 8 rods has 24 unknowns per node),
/// single precision halves the bytes moved and doubles the numbers per SIMD
/// instruction. Measured (numeric LU, first factorization, single against double
/// precision): chains of 8, 16 and 32 rods 0.041/0.063, 0.17/0.24 and 0.30/0.37 s. The
/// band-like systems of a few unknowns per node are factored column by column (faer's
/// simplicial LU), where single precision gains little or loses, and refines worse.
/// Measured with single precision allowed there: the rolling disk at N = 16384 (6 per
/// node) factored in 0.057 s against 0.067 s in double precision, and the whole solve
/// took 0.62 s against 0.60 s (more refinement solves); the tumbler at N = 65536 (2 per
/// node) factored in 0.066 s against 0.044 s, and a refinement with its Jacobian
/// diverged after the first correction; the knife edge at N = 32768 (4 per node) did
/// not refine and was factored again in double precision (0.157 s of factorizations
/// against 0.081 s).
const SINGLE_PRECISION_MIN_PER_NODE: usize = 24;

impl SquareSolver {
    /// Whether every equation of `action`'s system at `z` (the whole unknown vector) is
    /// within `floor` or within its own round-off level `ROUNDOFF · ε · Σ_j |J_ij| |x_j|`
    /// ([`row_roundoff_levels`]). The round-off stop of both backends compares
    /// `max |c|` with the *largest* row's level; this checks each equation against its own,
    /// so that an equation with small terms cannot hide behind one with large terms.
    pub fn equations_at_round_off(&self, action: &Action, z: &[f64], floor: f64) -> bool {
        match self.formulation {
            Formulation::Reduced => rows_at_round_off(&mut Reduced::new(action, z, &self.jac, None), &z[..action.layout.n_p], floor),
            Formulation::Full => rows_at_round_off(&mut Full::new(action, &self.jac), z, floor),
        }
    }
}

/// Whether every residual row of `problem` at `x` is within `floor` or its own round-off
/// level (see [`SquareSolver::equations_at_round_off`]).
fn rows_at_round_off<S: SquareSystem>(system: &mut S, x: &[f64], floor: f64) -> bool {
    let mut c = vec![0.0; system.size()];
    let mut values = vec![0.0; system.jacobian_structure().len()];
    if system.residual(x, &mut c).is_err() || system.jacobian_values(x, &mut values).is_err() {
        return false;
    }
    let entries = system.jacobian_structure().iter().zip(&values).map(|(&(r, col), &v)| (r as usize, col as usize, v));
    let levels = row_roundoff_levels(entries, x, c.len());
    c.iter().zip(&levels).all(|(ci, level)| ci.abs() <= floor.max(*level))
}

impl Drop for SquareSolver {
    /// Keep the LU analysis for the next solver of this thread.
    fn drop(&mut self) {
        if let Some(lu) = self.lu.take() {
            KEPT_ANALYSIS.set(Some(lu));
        }
    }
}

thread_local! {
    /// The LU analysis of the last Newton solver dropped on this thread (module docs).
    static KEPT_ANALYSIS: RefCell<Option<SystemSolver>> = const { RefCell::new(None) };
}

/// The factorization of the `n × n` matrix of `structure` with `entries` on the LU
/// analysis kept on this thread, if it is of that structure ([`SystemSolver::fits`]),
/// which stays kept: a fit factors `∂R/∂P` of the structure its start solve analysed,
/// and its verification solves with it again. `None` when none fits or the matrix is
/// singular.
pub fn factorization_on_kept_analysis(n: usize, structure: &[(u32, u32)], entries: &[f64]) -> Option<SparseFactorization> {
    KEPT_ANALYSIS.with_borrow(|kept| kept.as_ref().filter(|lu| lu.fits(n, structure)).and_then(|lu| lu.factorization(entries)))
}

/// Free the LU analysis kept for the next Newton solve of this thread (its memory; the
/// next solve analyses its structure anew).
pub fn discard_kept_analysis() {
    KEPT_ANALYSIS.take();
}

/// Solve one system from `x0` (its unknowns): Newton first with `lu`, the analysis of
/// its structure (present exactly when the backend is Newton; `analysis_s` the seconds
/// it took when it was made for this solve, `None` when it was reused), Ipopt when
/// Newton was not asked for or failed (and the crate has Ipopt).
fn solve_system<S: SquareSystem>(
    settings: &Settings,
    lu: Option<&mut SystemSolver>,
    analysis_s: Option<f64>,
    system: &mut S,
    x0: &[f64],
) -> Result<SystemSolution, BackendError> {
    let mut report = BackendReport { requested: settings.backend, newton: None, handed_over_to_ipopt: false, ipopt: None };
    let Some(lu) = lu else { return solve_by_ipopt(settings, report, 0.0, 0.0, system, x0) };
    let (reusable, analysis_s) = (analysis_s.is_none(), analysis_s.unwrap_or(0.0));
    let sol = lu.solve(system, x0, &settings.newton)?;
    let (total_s, evaluation_s) = (analysis_s + sol.total_s, sol.stats.evaluation_s);
    report.newton = Some(NewtonReport {
        status: sol.status,
        iterations: sol.iterations,
        max_residual: sol.max_residual,
        analysis_s,
        analysis_reused: reusable,
        stats: sol.stats,
    });
    let timed_out = sol.status == NewtonStatus::TimeLimitReached;
    if sol.status.is_success() || timed_out || !cfg!(feature = "ipopt") {
        let status = match settings.deadline.filter(|_| timed_out) {
            Some(d) => d.stopped(Backend::Newton),
            None => SolverStatus::Newton(sol.status),
        };
        return Ok(SystemSolution {
            status,
            z: sol.x,
            max_residual: sol.max_residual,
            iterations: sol.iterations,
            history: sol.history,
            total_s,
            evaluation_s,
            report,
        });
    }
    report.handed_over_to_ipopt = true;
    solve_by_ipopt(settings, report, total_s, evaluation_s, system, x0)
}

/// Ipopt's solve of `system` from `x0`, after a Newton solve that took `total_s` and
/// `evaluation_s` seconds (0 when none ran).
#[cfg(feature = "ipopt")]
fn solve_by_ipopt<S: SquareSystem>(
    settings: &Settings,
    mut report: BackendReport,
    total_s: f64,
    evaluation_s: f64,
    system: &mut S,
    x0: &[f64],
) -> Result<SystemSolution, BackendError> {
    let sol = ipopt_square::solve(system, x0, &settings.ipopt, settings.deadline)?;
    let mut ipopt_report = sol.report;
    let internal_s = ipopt_report.internal_s;
    // Not after a solve a deadline stopped: the note is for a solve that ran its course,
    // and the factorization would take the solve further past the deadline.
    let stopped = matches!(sol.status, SolverStatus::TimeLimitReached { .. }) || deadline::passed(settings.deadline);
    if report.requested == Backend::Ipopt
        && !stopped
        && internal_s >= NEWTON_LU_TIMED_FROM_S
        && internal_s >= NEWTON_LU_TIMED_SHARE * sol.total_s
    {
        ipopt_report.newton_lu_s = time_newton_lu(system, &sol.x);
    }
    report.ipopt = Some(ipopt_report);
    Ok(SystemSolution {
        status: sol.status,
        max_residual: sol.max_residual,
        iterations: sol.iterations,
        total_s: total_s + sol.total_s,
        evaluation_s: evaluation_s + sol.evaluation_s,
        history: sol.history,
        z: sol.x,
        report,
    })
}

/// Seconds of one numeric factorization of `system`'s Jacobian at `x` by the Newton
/// backend's sparse LU (its analysis made first, not counted); `None` when it fails.
#[cfg(feature = "ipopt")]
fn time_newton_lu<S: SquareSystem>(system: &mut S, x: &[f64]) -> Option<f64> {
    let mut lu = SystemSolver::new(system.size(), system.jacobian_structure()).ok()?;
    lu.time_factorization(system, x)
}

/// Without Ipopt every solve is Newton's (the scene's backend is checked when it is
/// resolved), so there is nothing to hand over to.
#[cfg(not(feature = "ipopt"))]
fn solve_by_ipopt<S: SquareSystem>(
    _: &Settings,
    _: BackendReport,
    _: f64,
    _: f64,
    _: &mut S,
    _: &[f64],
) -> Result<SystemSolution, BackendError> {
    Err(BackendError::NoIpopt)
}
