//! Solving one scene: build the discrete action, make a physical initial guess, hand
//! the square system to the backend ([`crate::backend`]: Ipopt, or Newton with a
//! sparse LU), and turn the critical point into a trajectory.
//!
//! Initial guess: the Lagrange–d'Alembert equations of the same scene are integrated
//! by [`crate::stepping::equations`] (adaptive high-order Runge–Kutta, index-reduced:
//! accelerations and multipliers from `[W Gᵀ; G 0]`, see [`Model::accelerations`]) at a
//! moderate tolerance and sampled at the nodes; the minus variables start at zero and the
//! boundary multipliers at the values that make their rows vanish. A global-in-time
//! Newton solve started there converges in a few iterations (docs/solver.md: constant
//! velocity extrapolation did not converge on the disk). If time stepping fails, the
//! guess falls back to constant-velocity extrapolation and the summary says so.

use std::fmt;
use std::time::Instant;

use indexmap::IndexMap;
use serde::Serialize;

use crate::backend::{BackendError, BackendReport, SolverStatus, SquareSolver};
use crate::discrete::action::Action;
use crate::discrete::contact;
use crate::discrete::trajectory::{NodeSeries, States, Trajectory};
use crate::model::Model;
use crate::sbp::{SbpError, SbpOperator};
use crate::scene::{Backend, ConstraintKind, Formulation, HessianMode, InitialVelocity, Scene, SceneError, Wall};
use crate::stepping::equations::{integrate_model, min_spacing, step_budget};
use crate::stepping::ode::OdeOptions;
use crate::stepping::verify::{self, Verification, VerifyStatus};
use skg_ipopt as ipopt;

/// A solution farther than this fraction of the coordinates' range from the
/// time-stepping solution gets a warning. Discretization errors of usable grids are
/// below 1 % (disk N=32 SBP242: 0.4 %); the spurious solutions seen were 35 % (tumbler
/// N=48) and 100 %+ (knife edge on SBP121, an odd-even mode).
const FAR_FROM_TIME_STEPPING: f64 = 0.1;

/// Why a solve could not be attempted or completed (a non-converged run is not an
/// error: it is an [`Outcome`] whose [`SolveStatus`] says so).
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    /// The scene's model cannot be built (an expression, the initial state).
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The SBP operator cannot be built on the scene's grid.
    #[error(transparent)]
    Sbp(#[from] SbpError),
    /// The backend could not be run (Ipopt's options, sizes, a callback error it did not
    /// recover from; Newton's structure).
    #[error(transparent)]
    Backend(#[from] BackendError),
    /// The scene's windows do not fit its grid.
    #[error("{}: [time] window: {message}", .scene)]
    Windows {
        /// The scene file.
        scene: String,
        /// Why.
        message: String,
    },
}

/// Where a solve's wall time went, in seconds.
#[derive(Debug, Clone, Serialize)]
pub struct Timings {
    /// Parsing, symbolic derivatives, tapes, sparsity structure.
    pub setup_s: f64,
    /// Time stepping for the initial guess.
    pub initial_guess_s: f64,
    /// Wall time of the backend (Ipopt, or Newton and Ipopt after a hand-over), split
    /// into time in our callbacks and inside the solver.
    pub solver_s: f64,
    /// Time in our callbacks (residual, Jacobian, Hessian).
    pub evaluation_s: f64,
    /// Time inside the solver: Ipopt's own time (mostly MUMPS), Newton's LU analysis,
    /// factorizations and solves.
    pub solver_internal_s: f64,
    /// Trajectory, end multipliers and diagnostics from the solution.
    pub postprocess_s: f64,
    /// Verification against time stepping ([`crate::stepping::verify`]).
    pub verification_s: f64,
    /// Fallback attempts whose result is not the one reported ([`crate::ladder`]).
    pub other_attempts_s: f64,
    /// Writing files (filled in by the output module).
    pub output_s: f64,
}

impl Timings {
    /// No time spent yet.
    pub fn zero() -> Timings {
        Timings {
            setup_s: 0.0,
            initial_guess_s: 0.0,
            solver_s: 0.0,
            evaluation_s: 0.0,
            solver_internal_s: 0.0,
            postprocess_s: 0.0,
            verification_s: 0.0,
            other_attempts_s: 0.0,
            output_s: 0.0,
        }
    }

    /// Add another part's times (the pieces of a windowed solve).
    pub fn add(&mut self, other: &Timings) {
        self.setup_s += other.setup_s;
        self.initial_guess_s += other.initial_guess_s;
        self.solver_s += other.solver_s;
        self.evaluation_s += other.evaluation_s;
        self.solver_internal_s += other.solver_internal_s;
        self.postprocess_s += other.postprocess_s;
        self.verification_s += other.verification_s;
        self.other_attempts_s += other.other_attempts_s;
        self.output_s += other.output_s;
    }

    /// The whole wall time of the solve, fallback attempts included.
    pub fn total(&self) -> f64 {
        self.setup_s
            + self.initial_guess_s
            + self.solver_s
            + self.postprocess_s
            + self.verification_s
            + self.other_attempts_s
            + self.output_s
    }
}

/// The sizes of the problem handed to the backend.
#[derive(Debug, Clone, Serialize)]
pub struct Sizes {
    /// Grid nodes N.
    pub nodes: usize,
    /// Coordinates d.
    pub coordinates: usize,
    /// Velocity constraints n.
    pub constraints: usize,
    /// Walls.
    pub walls: usize,
    /// Unknowns of the system (P for the reduced formulation, Z for the full one).
    pub variables: usize,
    /// Equations (as many as unknowns: the system is square).
    pub equations: usize,
    /// Nonzeros of the Jacobian's structure.
    pub jacobian_nonzeros: usize,
    /// Nonzeros of the Hessian's structure (0 unless the exact Hessian is used).
    pub hessian_nonzeros: usize,
    /// Instructions of the residual and Jacobian tapes.
    pub tape_instructions: usize,
}

/// Checks of the solution: residuals, energy, walls, distance from time stepping.
#[derive(Debug, Clone, Serialize)]
pub struct Diagnostics {
    /// max |c| of the system handed to the backend (unscaled), at the returned point.
    pub max_residual: f64,
    /// max |equation of motion| at interior nodes, unweighted (force units).
    pub max_eom_residual: f64,
    /// max |g^a| over interior nodes.
    pub max_constraint_interior: f64,
    /// max |g^a| at the last node, where the constraints are not enforced.
    pub constraint_last_node: f64,
    /// max |h| over all nodes of each position constraint `h(q, t) = 0` (keyed by its
    /// name): the drift of a constraint enforced through its time derivative.
    pub max_position_drift: IndexMap<String, f64>,
    /// Whether the scene depends on the time `t` explicitly; the energy is then not
    /// conserved, and `energy_drift` measures the work of the time dependence.
    pub depends_on_time: bool,
    /// max |E_k − E_1| of the total energy E = energy + wall_energy over nodes 1..N−2
    /// (the last two excluded: their equations are the boundary closure). Conserved up
    /// to the discretization error unless friction or other non-conservative forces act
    /// or the scene depends on `t` explicitly.
    pub energy_drift: f64,
    /// The same over all nodes.
    pub energy_drift_all: f64,
    /// Largest wall gap h (positive = penetration), per wall (keyed by the wall's name).
    pub max_wall_gap: IndexMap<String, f64>,
    /// max over nodes and coordinates of |q − q_time-stepping|: a large value hints at a
    /// spurious critical point or a too coarse grid.
    pub distance_from_time_stepping: Option<f64>,
    /// Contact episodes per wall (maximal runs of nodes in contact, [`contact`]; keyed by
    /// the wall's name) in the solution. A difference from the time-stepping solution
    /// means an extra or a missing bounce: a spurious critical point (docs/solver.md) or
    /// a too coarse grid; the solve then adds a warning.
    pub contact_episodes: IndexMap<String, usize>,
    /// The same for the time-stepping solution on the same nodes (if time stepping
    /// succeeded).
    pub contact_episodes_time_stepping: Option<IndexMap<String, usize>>,
    /// max |q-|, |λ-| of the full formulation's solution (0 in the physical limit).
    pub max_minus_variable: Option<f64>,
    /// The first node at which the kinetic matrix ∂²L/∂q̇² of the solution is not
    /// positive definite (the Lagrangian stops describing a mechanical system there: a
    /// mass or inertia turned zero or negative); `null` if it is positive definite at
    /// every node. A converged solve with such a node fails verification.
    pub kinetic_loss: Option<KineticLoss>,
}

/// Where the solution's kinetic matrix stops being positive definite.
#[derive(Debug, Clone, Serialize)]
pub struct KineticLoss {
    /// The node (0-based).
    pub node: usize,
    /// Its time.
    pub t: f64,
    /// The smallest eigenvalue of ∂²L/∂q̇² there (≤ 0 or NaN).
    pub min_eigenvalue: f64,
}

impl fmt::Display for KineticLoss {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "the kinetic matrix ∂²L/∂q̇² is not positive definite at node {} (t = {}, smallest eigenvalue {:.3e}): \
             the Lagrangian stops describing a mechanical system there (a mass or inertia turned zero or negative), \
             so the solution is not physical from there on",
            self.node, self.t, self.min_eigenvalue
        )
    }
}

/// The settings a solve ran with.
#[derive(Debug, Clone, Serialize)]
pub struct Settings {
    /// The SBP operator's name.
    pub operator: String,
    /// Grid nodes N.
    pub nodes: usize,
    /// Start time.
    pub t_start: f64,
    /// End time.
    pub t_end: f64,
    /// The formulation.
    pub formulation: Formulation,
    /// How the initial velocity was imposed.
    pub initial_velocity: InitialVelocity,
    /// The backend asked for (what ran: [`Outcome::backend`]).
    pub backend: Backend,
    /// The Hessian given to Ipopt.
    pub hessian: HessianMode,
    /// The tolerance on max |c| (Ipopt's `tol` and `constr_viol_tol`, Newton's stop).
    pub tol: f64,
    /// The iteration limit (Ipopt's, and Newton's).
    pub max_iter: u32,
    /// The scene's parameter values.
    pub parameters: IndexMap<String, f64>,
    /// How the initial guess was made.
    pub initial_guess: String,
}

/// The largest unscaled residual max |c| of the discrete system at which a solve counts
/// as converged (Ipopt's own tolerance applies to its possibly scaled problem), unless the
/// backend stopped at the round-off level and every equation is within its own round-off
/// level ([`SolveStatus::classify`]).
pub const CONVERGED_RESIDUAL: f64 = 1e-8;

/// How a solve ended: the backend's verdict, checked against the unscaled residual.
///
/// `Display` gives readable text; [`SolveStatus::name`] a stable name. Serialized (into
/// `summary.json`) as four fields: `"converged"` (true or false), `"status"` (the
/// status name of the backend that finished, e.g. Ipopt's `"Solve_Succeeded"` or
/// `"Newton_Converged"`), `"status_text"` (the readable text) and `"solve_status"` (the
/// stable name).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SolveStatus {
    /// The backend succeeded and the unscaled residual is at most [`CONVERGED_RESIDUAL`],
    /// or the backend stopped at the round-off level and every equation is within its
    /// own round-off level.
    Converged {
        /// The backend's status (Ipopt's `Solve_Succeeded` or
        /// `Solved_To_Acceptable_Level`, or `Newton_Converged`).
        solver: SolverStatus,
    },
    /// The backend reported success, but the unscaled residual exceeds
    /// [`CONVERGED_RESIDUAL`] (or is not a number): not counted as converged.
    ResidualTooLarge {
        /// The backend's status (a success).
        solver: SolverStatus,
        /// The unscaled residual max |c|.
        residual: f64,
    },
    /// The backend stopped without success.
    NotConverged {
        /// The backend's status, which says why.
        solver: SolverStatus,
    },
}

impl SolveStatus {
    /// The status of a solve that ended with the backend's status `solver` at an
    /// unscaled residual `residual`; `equations_at_round_off` says whether every
    /// equation is within [`CONVERGED_RESIDUAL`] or its own round-off level
    /// ([`SquareSolver::equations_at_round_off`]). A residual above `CONVERGED_RESIDUAL`
    /// counts only after a round-off stop that holds equation by equation: the scale of
    /// a scene's numbers (θ ≈ 600 rad after 20 revolutions, `SBP484`'s closure
    /// coefficients up to 130/Δt) can put the rounding error of its equations above 1e-8.
    pub fn classify(solver: SolverStatus, residual: f64, equations_at_round_off: bool) -> SolveStatus {
        let small = residual <= CONVERGED_RESIDUAL || (solver.is_round_off() && residual.is_finite() && equations_at_round_off);
        match (solver.is_success(), small) {
            (true, true) => SolveStatus::Converged { solver },
            (true, false) => SolveStatus::ResidualTooLarge { solver, residual },
            (false, _) => SolveStatus::NotConverged { solver },
        }
    }

    /// Whether the solve converged.
    pub fn is_converged(&self) -> bool {
        matches!(self, SolveStatus::Converged { .. })
    }

    /// The status of the backend that finished.
    pub fn solver(&self) -> SolverStatus {
        match *self {
            SolveStatus::Converged { solver } | SolveStatus::ResidualTooLarge { solver, .. } | SolveStatus::NotConverged { solver } => {
                solver
            }
        }
    }

    /// A stable name: `"converged"`, `"residual_too_large"` or `"not_converged"`.
    pub fn name(&self) -> &'static str {
        match self {
            SolveStatus::Converged { .. } => "converged",
            SolveStatus::ResidualTooLarge { .. } => "residual_too_large",
            SolveStatus::NotConverged { .. } => "not_converged",
        }
    }
}

impl fmt::Display for SolveStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SolveStatus::Converged { solver } | SolveStatus::NotConverged { solver } => write!(f, "{solver}"),
            SolveStatus::ResidualTooLarge { solver, residual } => {
                write!(
                    f,
                    "the solver reported success ({solver}) but the unscaled residual {residual:.3e} exceeds {CONVERGED_RESIDUAL:e}"
                )?;
                if solver.is_round_off() {
                    f.write_str(" and the round-off level of some equation")?;
                }
                Ok(())
            }
        }
    }
}

impl Serialize for SolveStatus {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = serializer.serialize_map(Some(4))?;
        map.serialize_entry("converged", &self.is_converged())?;
        map.serialize_entry("status", &self.solver())?;
        map.serialize_entry("status_text", &self.to_string())?;
        map.serialize_entry("solve_status", self.name())?;
        map.end()
    }
}

/// Everything a solve produced.
#[derive(Debug, Clone, Serialize)]
pub struct Outcome {
    /// The scene's name.
    pub scene: String,
    /// How the solve ended (serialized as the fields `converged`, `status`,
    /// `status_text` and `solve_status`).
    #[serde(flatten)]
    pub status: SolveStatus,
    /// The trajectory checked against time stepping of the same scene ([`verify`]).
    pub verification: Verification,
    /// How the reported trajectory covered the span (one solve, or windows).
    pub method: Method,
    /// The Ipopt version the tool was built against.
    pub ipopt_version: String,
    /// Which backend ran: the one asked for, Newton's own outcome, a hand-over to Ipopt.
    pub backend: BackendReport,
    /// Iterations of the backend that finished.
    pub iterations: usize,
    /// The settings the solve ran with.
    pub settings: Settings,
    /// The sizes of the problem.
    pub sizes: Sizes,
    /// Where the time went.
    pub timings: Timings,
    /// Checks of the solution.
    pub diagnostics: Diagnostics,
    /// Suspicions about the solution (spurious critical point, residual too large, …).
    pub warnings: Vec<String>,
    /// Every run tried ([`crate::ladder`]): the scene's own, then the fallbacks; the
    /// one reported is marked `chosen`.
    pub attempts: Vec<Attempt>,
    /// What to do when the result cannot be trusted (not converged, or not verified).
    pub remedy: Option<String>,
    /// The iteration table of the backend that finished (Ipopt's, or Newton's in the
    /// same layout).
    pub history: Vec<ipopt::IterationStat>,
    /// The solution at the nodes (written as trajectory.csv, not into the summary).
    #[serde(skip)]
    pub trajectory: Trajectory,
}

impl Outcome {
    /// Whether the solve converged ([`SolveStatus::is_converged`]).
    pub fn converged(&self) -> bool {
        self.status.is_converged()
    }

    /// Converged, every number finite, and verified (or verification switched off):
    /// the result a user may act on (exit status 0).
    pub fn trusted(&self) -> bool {
        self.converged() && self.verification.is_acceptable()
    }
}

/// One run tried by the ladder, as recorded in `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Attempt {
    /// What was tried (method and initial guess).
    pub method: String,
    /// How it ended, in words (convergence and verification).
    pub result: String,
    /// Whether it converged.
    pub converged: bool,
    /// Its verification verdict, when it converged.
    pub verification: Option<VerifyStatus>,
    /// Its max |q − q_reference|, when verified.
    pub max_error: Option<f64>,
    /// Iterations of the backend that finished.
    pub iterations: usize,
    /// Wall time, seconds.
    pub wall_s: f64,
    /// Whether its trajectory is the one reported.
    pub chosen: bool,
}

/// Node times of a scene's grid.
pub fn grid(scene: &Scene) -> (Vec<f64>, f64) {
    let n = scene.nodes;
    let dt = (scene.t_end - scene.t_start) / (n as f64 - 1.0);
    ((0..n).map(|k| scene.t_start + k as f64 * dt).collect(), dt)
}

/// Build the discrete action of a resolved scene on its whole grid.
pub fn build_action(scene: &Scene) -> Result<Action, SolveError> {
    let (_, dt) = grid(scene);
    build_action_on(scene, scene.nodes, dt)
}

/// Build the discrete action of a scene on `nodes` nodes of spacing `dt`, from the scene's
/// initial state (a window re-targets it with [`Action::set_window`]).
pub fn build_action_on(scene: &Scene, nodes: usize, dt: f64) -> Result<Action, SolveError> {
    let model = Model::build(scene)?;
    let op = SbpOperator::new(scene.operator, nodes, dt)?;
    Ok(Action::new(model, op, scene.initial_velocity, scene.t_start, scene.initial_q.clone(), scene.initial_v.clone()))
}

/// Solve a resolved scene: the solve the scene asks for (in one piece or in windows),
/// verified against time stepping ([`crate::stepping::verify`]) and, when it fails to converge or
/// to verify, the fallback ladder ([`crate::ladder`]).
///
/// Refused before anything is allocated if its memory estimate exceeds the available
/// memory ([`crate::memory`]).
pub fn solve_scene(scene: &Scene) -> Result<Outcome, SolveError> {
    solve_scene_with_progress(scene, &mut |_| {})
}

/// [`solve_scene`], telling `progress` what each attempt of the fallback ladder is
/// about to do ([`crate::ladder::solve_with_progress`]).
pub fn solve_scene_with_progress(scene: &Scene, progress: &mut dyn FnMut(&str)) -> Result<Outcome, SolveError> {
    crate::memory::check(scene, "the solve", scene.nodes, crate::memory::solve_bytes(scene))?;
    crate::ladder::solve_with_progress(scene, progress)
}

/// How the initial guess of one solve is made.
#[derive(Debug, Clone)]
pub enum Guess {
    /// Time stepping of the Lagrange–d'Alembert equations from the action's initial
    /// state, sampled at its nodes.
    TimeStepping,
    /// Coordinates and multipliers at the action's nodes, e.g. a coarser solve
    /// interpolated onto this grid, or the solve of a wider wall.
    States {
        /// `q[k][i]` at the action's nodes.
        q: NodeSeries,
        /// `λ[k][a]` at the action's nodes.
        lambda: NodeSeries,
        /// Where they came from (for the summary).
        description: String,
    },
}

/// One solve of one action's discrete system: the whole span, or one window of it.
#[derive(Debug, Clone)]
pub struct Piece {
    /// How the backend ended, checked against the unscaled residual.
    pub status: SolveStatus,
    /// Iterations of the backend that finished.
    pub iterations: usize,
    /// Its iteration table.
    pub history: Vec<ipopt::IterationStat>,
    /// Which backend ran, and Newton's own outcome.
    pub backend: BackendReport,
    /// The solution at the action's nodes.
    pub trajectory: Trajectory,
    /// max |c| of the system (unscaled) at the returned point.
    pub max_residual: f64,
    /// max |equation of motion| at interior nodes.
    pub max_eom_residual: f64,
    /// max |q-|, |λ-| for the full formulation.
    pub max_minus_variable: Option<f64>,
    /// The time-stepping coordinates at the nodes, when the guess made them.
    pub time_stepping_q: Option<NodeSeries>,
    /// How the initial guess was made.
    pub guess: String,
    /// Time of the guess and of the backend (setup and output are not a piece's).
    pub timings: Timings,
}

/// Solve the discrete system of `action` (nodes at `times`) from `guess` with `solver`,
/// which was built for this action (or one of equal structure) and keeps its sparsity
/// plans and LU analysis for the next piece.
pub fn solve_piece(scene: &Scene, action: &Action, solver: &mut SquareSolver, times: &[f64], guess: &Guess) -> Result<Piece, SolveError> {
    let t_guess = Instant::now();
    let mut warnings = Vec::new();
    let (z0, guess_desc, ts_q) = initial_guess(action, times, guess, &mut warnings);
    check_initial_guess(scene, action, times, &z0, &guess_desc, &warnings)?;
    let initial_guess_s = t_guess.elapsed().as_secs_f64();

    let solution = solver.solve(action, &z0).map_err(|e| rejected_option(scene, e.into()))?;
    if solution.status == SolverStatus::Ipopt(ipopt::Status::InvalidOption) {
        return Err(unusable_option(scene));
    }
    let z = &solution.z;

    let t_post = Instant::now();
    let (trajectory, max_eom_residual) = evaluate(action, times, z);
    let lay = &action.layout;
    let max_minus_variable = (scene.formulation == Formulation::Full)
        .then(|| lay.qm.iter().chain(&lay.lm).map(|&i| z[i as usize].abs()).fold(0.0_f64, f64::max));
    let max_residual = solution.max_residual;
    // Only a round-off stop above CONVERGED_RESIDUAL needs the equation-by-equation test.
    let at_round_off =
        solution.status.is_round_off() && max_residual > CONVERGED_RESIDUAL && solver.equations_at_round_off(action, z, CONVERGED_RESIDUAL);
    Ok(Piece {
        status: SolveStatus::classify(solution.status, max_residual, at_round_off),
        iterations: solution.iterations,
        history: solution.history,
        backend: solution.report,
        trajectory,
        max_residual,
        max_eom_residual,
        max_minus_variable,
        time_stepping_q: ts_q,
        guess: match warnings.first() {
            Some(w) => format!("{guess_desc} ({w})"),
            None => guess_desc,
        },
        timings: Timings {
            initial_guess_s,
            solver_s: solution.total_s,
            evaluation_s: solution.evaluation_s,
            solver_internal_s: solution.total_s - solution.evaluation_s,
            postprocess_s: t_post.elapsed().as_secs_f64(),
            ..Timings::zero()
        },
    })
}

/// Initial point Z0 and a description of how it was made; also the time-stepping
/// coordinates when the guess made them (for the spurious-solution check).
fn initial_guess(action: &Action, times: &[f64], guess: &Guess, warnings: &mut Vec<String>) -> (Vec<f64>, String, Option<NodeSeries>) {
    let (d, n) = (action.layout.d, action.layout.n);
    let (q, lambda, desc, ts_q) = match guess {
        Guess::States { q, lambda, description } => (q.clone(), lambda.clone(), description.clone(), None),
        Guess::TimeStepping => {
            // With walls, steps at most the node spacing: a larger step can jump across a
            // thin wall that the error estimate never sees (free flight is integrated
            // exactly). Without walls the step is left to the error control: at
            // N = 16384 the capped guess cost as much as the whole Newton solve, the
            // uncapped one a tenth, with the same Newton iterations on every shipped
            // scene (docs/benchmarks.md#the-initial-guess).
            let max_step = if action.model.walls.is_empty() { None } else { min_spacing(times) };
            let opts = OdeOptions { rtol: 1e-8, atol: 1e-10, max_step, max_steps: step_budget(times.len()), ..OdeOptions::default() };
            let (q0, v0) = (action.q0(), action.v0());
            match integrate_model(&action.model, q0, v0, times, &opts) {
                Ok((States { q, lambda, .. }, _)) => (
                    q.clone(),
                    lambda,
                    "time stepping of the Lagrange–d'Alembert equations (adaptive Runge–Kutta, rtol 1e-8) sampled at the nodes".to_string(),
                    Some(q),
                ),
                Err(e) => {
                    warnings.push(format!("time stepping for the initial guess failed ({e}); using constant-velocity extrapolation"));
                    let q: NodeSeries = times.iter().map(|t| (0..d).map(|i| q0[i] + v0[i] * (t - times[0])).collect()).collect();
                    (q, vec![vec![0.0; n]; times.len()], "constant-velocity extrapolation".to_string(), None)
                }
            }
        }
    };
    (point_from_states(action, &q, &lambda), desc, ts_q)
}

/// Refuse an initial guess with a value that is not finite, naming the node, the state
/// and the scene's expression that is undefined there (Ipopt would only say "starting
/// point x0[i] = NaN").
/// `guess` says how the guess was made and `notes` why (a failed time stepping).
fn check_initial_guess(scene: &Scene, action: &Action, times: &[f64], z0: &[f64], guess: &str, notes: &[String]) -> Result<(), SolveError> {
    let Some(bad) = z0.iter().position(|x| !x.is_finite()) else { return Ok(()) };
    let names: Vec<String> = scene.constraints.iter().map(|c| c.name.clone()).collect();
    let (k, what) = action.layout.describe(bad, &scene.coordinates, &names);
    let q = action.layout.coordinates(z0);
    let v = apply_d(&action.op, &q);
    let source = action.model.non_finite_expression(scene, times[k], &q[k], &v[k]);
    let state = |xs: &[f64]| xs.iter().map(|x| format!("{x:.6e}")).collect::<Vec<_>>().join(", ");
    let message = format!(
        "the initial guess ({guess}) is not finite: {what} at node {k} (t = {}) is {}; \
         at that node q = ({}), q̇ = ({}){}{}",
        times[k],
        z0[bad],
        state(&q[k]),
        state(&v[k]),
        match &source {
            Some((expr, _)) => format!(", where {expr} is not finite (e.g. sqrt or log of a negative number, a division by zero)"),
            None => String::new(),
        },
        notes.iter().map(|n| format!("; {n}")).collect::<String>()
    );
    let location = source.map_or_else(|| scene.file.origin.whole(), |(_, at)| at);
    Err(SceneError::Invalid { location, message }.into())
}

/// An option Ipopt refused when it was set, as an input error at the option's place in
/// the scene file; other errors pass through.
fn rejected_option(scene: &Scene, e: SolveError) -> SolveError {
    let SolveError::Backend(BackendError::Ipopt(ipopt::SolveError::BadOption { name, value })) = &e else { return e };
    let message = format!(
        "Ipopt refused the option {name} = {value}: it has no such option, or the value has the wrong type or is outside \
         the option's range (Ipopt prints its reason on stdout)"
    );
    SceneError::Invalid { location: scene.file.solver_option_location(name), message }.into()
}

/// Ipopt's `Invalid_Option` at the start of a solve (an option value it accepted but
/// cannot use, e.g. a linear solver whose library it cannot load), as an input error.
fn unusable_option(scene: &Scene) -> SolveError {
    let (location, message) = match &scene.solver.linear_solver {
        Some(solver) => (
            scene.file.solver_option_location("linear_solver"),
            format!(
                "Ipopt cannot use linear_solver = \"{solver}\" (Invalid_Option: its library could not be loaded); Debian's \
                 Ipopt has only MUMPS: use linear_solver = \"mumps\" or remove the key"
            ),
        ),
        None => {
            (scene.file.origin.whole(), "Ipopt stopped with Invalid_Option: an option of [solver.ipopt] has a value it cannot use".into())
        }
    };
    SceneError::Invalid { location, message }.into()
}

/// The unknown vector Z with the given coordinates and multipliers at the nodes, the
/// minus variables at zero and the boundary multipliers at the values that make their
/// rows vanish.
fn point_from_states(action: &Action, q: &[Vec<f64>], lambda: &[Vec<f64>]) -> Vec<f64> {
    let lay = &action.layout;
    let (d, n) = (lay.d, lay.n);
    let mut z = vec![0.0; lay.len()];
    for k in 0..lay.nodes {
        for i in 0..d {
            z[lay.qp[k * d + i] as usize] = q[k][i];
        }
        for a in 0..n {
            let zi = lay.lp[k * n + a];
            if zi != u32::MAX {
                z[zi as usize] = lambda[k][a];
            }
        }
    }
    let mut ws = action.model.workspace();
    let mut r = vec![0.0; lay.n_m];
    action.gradient(&z, true, &mut r, &mut ws);
    let last = lay.nodes - 1;
    let row = |zi: u32| zi as usize - lay.n_p;
    for i in 0..d {
        z[lay.nu_qn[i] as usize] = -r[row(lay.qm[last * d + i])];
    }
    for a in 0..n {
        z[lay.nu_ln[a] as usize] = -r[row(lay.lm[last * n + a])];
    }
    // The first node's multipliers (strong initial velocity only).
    for (i, &nu) in lay.nu_q1.iter().enumerate() {
        z[nu as usize] = -r[row(lay.qm[i])];
    }
    for (a, &nu) in lay.nu_l1.iter().enumerate() {
        z[nu as usize] = -r[row(lay.lm[a])];
    }
    z
}

/// The settings a scene is solved with on the grid `times`.
fn settings(scene: &Scene, times: &[f64], initial_guess: String) -> Settings {
    Settings {
        operator: scene.operator.name().to_string(),
        nodes: scene.nodes,
        t_start: times[0],
        t_end: times[times.len() - 1],
        formulation: scene.formulation,
        initial_velocity: scene.initial_velocity,
        backend: scene.solver.backend,
        hessian: scene.solver.hessian,
        tol: scene.solver.tol,
        max_iter: scene.solver.max_iter,
        parameters: scene.parameters.clone(),
        initial_guess,
    }
}

/// The sizes of the system handed to the backend for one piece (the whole span, or one
/// window).
pub fn sizes(scene: &Scene, action: &Action, solver: &SquareSolver) -> Sizes {
    let (lay, model) = (&action.layout, &action.model);
    let (variables, equations) = match scene.formulation {
        Formulation::Reduced => (lay.n_p, lay.n_m),
        Formulation::Full => (lay.len(), lay.len()),
    };
    Sizes {
        nodes: lay.nodes,
        coordinates: lay.d,
        constraints: lay.n,
        walls: model.walls.len(),
        variables,
        equations,
        jacobian_nonzeros: solver.jacobian_plan().structure.len(),
        hessian_nonzeros: solver.hessian_plan().map_or(0, |h| h.structure.len()),
        tape_instructions: model.minus_gradient.len() + model.mixed.tape.len(),
    }
}

/// How a run covered the scene's span.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Method {
    /// One solve over the whole span.
    Global,
    /// Successive windows ([`crate::window`]).
    Windows {
        /// Length of each window's solve, seconds.
        length: f64,
        /// Length discarded at the end of each window, seconds.
        overlap: f64,
        /// Nodes of each window's solve.
        nodes_per_window: usize,
        /// Number of windows.
        count: usize,
    },
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Method::Global => write!(f, "one solve over the whole span"),
            Method::Windows { length, overlap, nodes_per_window, count } => {
                write!(f, "{count} windows of {length:.4} s ({nodes_per_window} nodes), each discarding its last {overlap:.4} s")
            }
        }
    }
}

/// One attempt at the whole span: a global solve or a sequence of windows, on the
/// scene's grid.
#[derive(Debug, Clone)]
pub struct Run {
    /// How the span was covered.
    pub method: Method,
    /// The sizes of one piece's system.
    pub sizes: Sizes,
    /// The solution over the whole span. For windows, the pieces joined: converged only
    /// if every window converged (else the status of the first that did not),
    /// iterations, iteration tables and times one after the other, residuals maximized.
    pub solution: Piece,
}

/// Solve the scene's whole span in one piece from `guess`.
pub fn solve_global(scene: &Scene, guess: &Guess) -> Result<Run, SolveError> {
    let t_setup = Instant::now();
    let action = build_action(scene)?;
    let mut solver = SquareSolver::new(scene, &action);
    let setup_s = t_setup.elapsed().as_secs_f64();
    let (times, _) = grid(scene);
    let mut solution = solve_piece(scene, &action, &mut solver, &times, guess)?;
    solution.timings.setup_s = setup_s;
    Ok(Run { method: Method::Global, sizes: sizes(scene, &action, &solver), solution })
}

/// The outcome of a run: its diagnostics, verification and warnings (the ladder adds
/// the attempts and a remedy).
pub fn outcome(scene: &Scene, model: &Model, run: Run) -> Outcome {
    let Run { method, sizes, solution: run } = run;
    let t = Instant::now();
    let mut verification = verify::verify(scene, model, &run.trajectory);
    let mut timings = run.timings.clone();
    timings.verification_s = t.elapsed().as_secs_f64();
    let diagnostics = diagnose(model, &run);
    let mut warnings = suspicions(&diagnostics, run.time_stepping_q.as_deref(), run.status);
    if let Some(newton) = run.backend.newton.as_ref().filter(|_| run.backend.handed_over_to_ipopt) {
        warnings.push(format!(
            "Newton's method did not converge ({}, {} iterations, residual {:.3e}); Ipopt solved the system from the same initial guess",
            newton.status.name(),
            newton.iterations,
            newton.max_residual
        ));
    }
    if let Some(loss) = &diagnostics.kinetic_loss {
        verification.fail(loss.to_string());
        warnings.push(loss.to_string());
    }
    Outcome {
        scene: scene.name.clone(),
        status: run.status,
        verification,
        method,
        ipopt_version: ipopt::ipopt_version().to_string(),
        backend: run.backend,
        iterations: run.iterations,
        settings: settings(scene, &run.trajectory.t, run.guess),
        sizes,
        timings,
        diagnostics,
        warnings,
        attempts: Vec::new(),
        remedy: None,
        history: run.history,
        trajectory: run.trajectory,
    }
}

/// Warnings about a solution: far from time stepping, a contact episode more or less
/// than time stepping (a spurious critical point or a grid too coarse), or the backend's
/// success contradicted by the unscaled residual.
fn suspicions(diagnostics: &Diagnostics, ts_q: Option<&[Vec<f64>]>, status: SolveStatus) -> Vec<String> {
    let mut warnings = Vec::new();
    if let (Some(dist), Some(ts)) = (diagnostics.distance_from_time_stepping, ts_q) {
        let scale = verify::coordinate_scale(ts);
        if dist > FAR_FROM_TIME_STEPPING * scale {
            warnings.push(format!(
                "the solution is {dist:.3e} away from time stepping of the same scene ({:.0} % of the coordinates' range): \
                 a spurious critical point, an odd-even mode of the operator, or a grid too coarse (refine N or change the operator)",
                100.0 * dist / scale
            ));
        }
    }
    if let Some(ts) = &diagnostics.contact_episodes_time_stepping {
        for ((wall, a), b) in diagnostics.contact_episodes.iter().zip(ts.values()) {
            if a != b {
                warnings.push(format!(
                    "wall `{wall}`: the solution has {a} contact episode(s), time stepping of the same scene has {b}: \
                     possibly a spurious critical point or a grid too coarse for the wall width (refine N)"
                ));
            }
        }
    }
    if let SolveStatus::ResidualTooLarge { residual, .. } = status {
        warnings
            .push(format!("the solver reported success but the unscaled residual is {residual:.3e} (> 1e-8): not counted as converged"));
    }
    warnings
}

/// The trajectory and the largest equation-of-motion residual
/// |f + F − Dp − Gᵀλ| over interior nodes (force units).
fn evaluate(action: &Action, times: &[f64], z: &[f64]) -> (Trajectory, f64) {
    let lay = &action.layout;
    let (d, n, nodes) = (lay.d, lay.n, lay.nodes);
    let model = &action.model;
    let mut ws = model.workspace();
    let q: Vec<Vec<f64>> = (0..nodes).map(|k| (0..d).map(|i| z[lay.qp[k * d + i] as usize]).collect()).collect();
    let v = apply_d(&action.op, &q);
    let phys: Vec<_> = (0..nodes).map(|k| model.physical(times[k], &q[k], &v[k], &mut ws)).collect();
    let p: Vec<Vec<f64>> = phys.iter().map(|ph| ph.p.clone()).collect();
    let dp = apply_d(&action.op, &p);
    let mut lambda = vec![vec![0.0; n]; nodes];
    let mut max_eom = 0.0_f64;
    for k in 0..nodes {
        // λ+ is pinned where the node's row was absorbed: the last node, and the first
        // one with the strong initial velocity.
        let pinned = n > 0 && lay.lp[k * n] == u32::MAX;
        if pinned {
            lambda[k] = end_multipliers(&phys[k], &dp[k]);
        } else {
            for a in 0..n {
                lambda[k][a] = z[lay.lp[k * n + a] as usize];
            }
        }
        if k == 0 || k + 1 == nodes {
            continue;
        }
        for i in 0..d {
            let gl: f64 = (0..n).map(|a| lambda[k][a] * phys[k].gv[(a, i)]).sum();
            max_eom = max_eom.max((phys[k].force[i] - dp[k][i] - gl).abs());
        }
    }
    (Trajectory::from_physical(times, States { q, v, lambda }, &phys), max_eom)
}

/// D applied to each component of a node-major series.
fn apply_d(op: &SbpOperator, series: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let nodes = series.len();
    let d = series.first().map_or(0, Vec::len);
    let mut out = vec![vec![0.0; d]; nodes];
    let mut col = vec![0.0; nodes];
    let mut dcol = vec![0.0; nodes];
    for i in 0..d {
        for k in 0..nodes {
            col[k] = series[k][i];
        }
        op.apply(&col, &mut dcol);
        for k in 0..nodes {
            out[k][i] = dcol[k];
        }
    }
    out
}

/// λ at an end node: least-squares solution of that node's equation of motion
/// `Gᵀ λ = f + F − (Dp)` (its row of ∂S/∂q- was absorbed by a boundary multiplier).
fn end_multipliers(ph: &crate::model::Physical, dp: &[f64]) -> Vec<f64> {
    let rhs = nalgebra::DVector::from_iterator(dp.len(), ph.force.iter().zip(dp).map(|(f, d)| f - d));
    let g = &ph.gv; // n×d
    let normal = g * g.transpose();
    match normal.lu().solve(&(g * rhs)) {
        Some(l) => l.iter().copied().collect(),
        None => vec![f64::NAN; g.nrows()],
    }
}

fn diagnose(model: &Model, run: &Piece) -> Diagnostics {
    let tr = &run.trajectory;
    let nodes = tr.t.len();
    let max_abs = |rows: &[Vec<f64>]| rows.iter().flatten().fold(0.0_f64, |m, x| m.max(x.abs()));
    let max_constraint_interior = if nodes > 2 { max_abs(&tr.g[1..nodes - 1]) } else { 0.0 };
    let constraint_last_node = max_abs(&tr.g[nodes - 1..]);
    let total: Vec<f64> = tr.energy.iter().zip(&tr.wall_energy).map(|(e, w)| e + w).collect();
    let drift = |es: &[f64]| es.iter().fold(0.0_f64, |m, e| m.max((e - total[0]).abs()));
    let positions = model.constraints.iter().filter(|c| c.kind == ConstraintKind::Position);
    let max_wall_gap = per_wall(model, |j, _| tr.h.iter().map(|h| h[j]).fold(f64::NEG_INFINITY, f64::max));
    let ts_q = run.time_stepping_q.as_deref();
    let contact_episodes_time_stepping = ts_q.map(|qs| {
        let h: Vec<Vec<f64>> = qs.iter().zip(&tr.t).map(|(q, &t)| model.wall_gaps(t, q)).collect();
        contact_episodes(model, &h)
    });
    let distance_from_time_stepping =
        ts_q.map(|qs| qs.iter().zip(&tr.q).flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs())).fold(0.0_f64, f64::max));
    Diagnostics {
        max_residual: run.max_residual,
        max_eom_residual: run.max_eom_residual,
        max_constraint_interior,
        constraint_last_node,
        max_position_drift: positions.map(|c| c.name.clone()).zip(tr.max_drift()).collect(),
        depends_on_time: model.depends_on_time,
        energy_drift: drift(&total[..nodes.saturating_sub(2).max(1)]),
        energy_drift_all: drift(&total),
        max_wall_gap,
        distance_from_time_stepping,
        contact_episodes: contact_episodes(model, &tr.h),
        contact_episodes_time_stepping,
        max_minus_variable: run.max_minus_variable,
        kinetic_loss: model.kinetic_loss(&tr.t, &tr.q, &tr.v).map(|(node, min_eigenvalue)| KineticLoss {
            node,
            t: tr.t[node],
            min_eigenvalue,
        }),
    }
}

/// `value(j, wall)` for every wall of the model, keyed by the wall's name in the scene's order.
fn per_wall<T>(model: &Model, mut value: impl FnMut(usize, &Wall) -> T) -> IndexMap<String, T> {
    model.walls.iter().enumerate().map(|(j, w)| (w.name.clone(), value(j, w))).collect()
}

/// Number of contact episodes ([`contact::episodes`]) per wall, given the gaps `h[k][j]`.
fn contact_episodes(model: &Model, h: &[Vec<f64>]) -> IndexMap<String, usize> {
    per_wall(model, |j, w| contact::episodes(h.iter().map(|hk| hk[j]), w.width).len())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::newton::NewtonStatus;
    use ipopt::Status;

    #[test]
    fn solve_status_from_ipopt_and_residual() {
        let ok = SolveStatus::classify(SolverStatus::Ipopt(Status::SolveSucceeded), 1e-12, false);
        assert_eq!(ok, SolveStatus::Converged { solver: SolverStatus::Ipopt(Status::SolveSucceeded) });
        assert!(ok.is_converged());
        assert_eq!((ok.name(), ok.to_string().as_str()), ("converged", "solved to the requested tolerance"));

        let loose = SolveStatus::classify(SolverStatus::Ipopt(Status::SolvedToAcceptableLevel), 2e-5, true);
        assert!(!loose.is_converged());
        assert_eq!(loose.solver(), SolverStatus::Ipopt(Status::SolvedToAcceptableLevel));
        assert_eq!(loose.name(), "residual_too_large");
        assert!(loose.to_string().contains("2.000e-5") && loose.to_string().contains("exceeds 1e-8"), "{loose}");
        assert!(!SolveStatus::classify(SolverStatus::Ipopt(Status::SolveSucceeded), f64::NAN, true).is_converged());

        let failed = SolveStatus::classify(SolverStatus::Ipopt(Status::MaximumIterationsExceeded), 1e-12, false);
        assert_eq!(failed, SolveStatus::NotConverged { solver: SolverStatus::Ipopt(Status::MaximumIterationsExceeded) });
        assert_eq!(failed.to_string(), "maximum number of iterations exceeded");

        let json = serde_json::to_value(loose).unwrap();
        assert_eq!(json["converged"], false);
        assert_eq!(json["status"], "Solved_To_Acceptable_Level");
        assert_eq!(json["solve_status"], "residual_too_large");
        assert_eq!(json["status_text"], loose.to_string());

        // Newton's own statuses classify the same way and keep their names.
        let newton = SolveStatus::classify(SolverStatus::Newton(NewtonStatus::Converged), 1e-12, false);
        assert!(newton.is_converged());
        assert_eq!(serde_json::to_value(newton).unwrap()["status"], "Newton_Converged");
        let stuck = SolveStatus::classify(SolverStatus::Newton(NewtonStatus::LineSearchFailed), 1e-12, false);
        assert_eq!((stuck.name(), stuck.solver().name()), ("not_converged", "Newton_Line_Search_Failed"));

        // A round-off stop above 1e-8 counts when every equation is at its own round-off
        // level, and only after a round-off stop (not after Ipopt's acceptable level).
        for solver in [SolverStatus::IpoptConvergedToRoundOff, SolverStatus::Newton(NewtonStatus::ConvergedToRoundOff)] {
            assert!(SolveStatus::classify(solver, 3e-8, true).is_converged(), "{solver}");
            let refused = SolveStatus::classify(solver, 3e-8, false);
            assert_eq!(refused.name(), "residual_too_large");
            assert!(refused.to_string().ends_with("exceeds 1e-8 and the round-off level of some equation"), "{refused}");
            assert!(!SolveStatus::classify(solver, f64::NAN, true).is_converged());
        }
        assert!(!SolveStatus::classify(SolverStatus::Newton(NewtonStatus::Converged), 3e-8, true).is_converged());
    }
}
