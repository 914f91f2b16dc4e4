//! What a solve produced: the [`Outcome`] with its diagnostics, settings, sizes, timings
//! and attempts, and the [`Method`] by which a run covered the span.

use std::fmt;

use indexmap::IndexMap;
use serde::Serialize;

use super::backend::BackendReport;
use super::status::SolveStatus;
use crate::discrete::Trajectory;
use crate::scene::{Backend, Formulation, HessianMode, InitialVelocity};
use crate::solve::linalg::IterationStat;
use crate::stepping::ode::OdeStats;
use crate::stepping::verify::{Verification, VerifyStatus};

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
    /// Verification against time stepping ([`verify`](crate::stepping::verify)).
    pub verification_s: f64,
    /// Fallback attempts whose result is not the one reported (the ladder's other rungs).
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

/// Counts of the work a solve did: how many systems it solved, the backends'
/// iterations and evaluations, and the steps of its time steppings. Unlike the
/// [`Timings`] they do not depend on the machine's speed, and for the same build they
/// are the same from run to run (Ipopt with MUMPS's AMF ordering is deterministic,
/// docs/solver.md), so a change that makes a solve do more work shows in them; the
/// snapshot test `crates/skg-core/tests/solver_work.rs` pins them for the shipped
/// scenes. (`summary.json`: `work`, and `work` of each attempt.)
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Work {
    /// Discrete systems solved: 1 for a global solve, one per window.
    pub systems: usize,
    /// Newton steps (`backend = "newton"`).
    pub newton_iterations: usize,
    /// Ipopt iterations (`backend = "ipopt"`, or after Newton handed over).
    pub ipopt_iterations: usize,
    /// Residual evaluations of both backends (Newton's line-search trials and Ipopt's
    /// recomputation at the returned point included).
    pub residual_evaluations: usize,
    /// Jacobian evaluations of both backends (each of Newton's is followed by one numeric
    /// LU factorization).
    pub jacobian_evaluations: usize,
    /// Hessian evaluations (Ipopt with `hessian = "exact"`).
    pub hessian_evaluations: usize,
    /// The time stepping of the initial guesses: accepted and rejected steps and
    /// right-hand-side evaluations (not counted when it failed and the guess fell back to
    /// constant-velocity extrapolation).
    pub guess_steps: OdeStats,
    /// The time stepping of the verification's reference (not counted when it failed or
    /// verification was off).
    pub verification_steps: OdeStats,
}

impl Work {
    /// The work of one solve of a system: its backends' counts (Newton's and, when it
    /// ran, Ipopt's) and the time stepping of its initial guess.
    pub fn of_system(backend: &BackendReport, guess_steps: OdeStats) -> Work {
        let mut work = Work { systems: 1, guess_steps, ..Work::default() };
        if let Some(n) = &backend.newton {
            work.newton_iterations = n.iterations;
            work.residual_evaluations += n.stats.residual_evaluations;
            work.jacobian_evaluations += n.stats.jacobian_evaluations;
        }
        if let Some(i) = &backend.ipopt {
            work.ipopt_iterations = i.iterations;
            work.residual_evaluations += i.residual_evaluations;
            work.jacobian_evaluations += i.jacobian_evaluations;
            work.hessian_evaluations += i.hessian_evaluations;
        }
        work
    }

    /// Add another part's work (the windows of a run, the attempts of a ladder).
    pub fn add(&mut self, other: &Work) {
        self.systems += other.systems;
        self.newton_iterations += other.newton_iterations;
        self.ipopt_iterations += other.ipopt_iterations;
        self.residual_evaluations += other.residual_evaluations;
        self.jacobian_evaluations += other.jacobian_evaluations;
        self.hessian_evaluations += other.hessian_evaluations;
        self.guess_steps.add(&other.guess_steps);
        self.verification_steps.add(&other.verification_steps);
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
    /// max |E_k − E_1| of the total energy E = energy + wall_energy over all nodes but
    /// the last [`energy_drift_skip`](Self::energy_drift_skip) (the last two: their
    /// equations are the boundary closure; for a dissipative operator its boundary rows,
    /// where `D+`'s end closure carries a layer in the velocity). Conserved up to the
    /// discretization error unless friction or other non-conservative forces act or the
    /// scene depends on `t` explicitly.
    pub energy_drift: f64,
    /// End nodes left out of `energy_drift` ([`energy_drift_skip`](crate::solve::energy_drift_skip)).
    pub energy_drift_skip: usize,
    /// The same over all nodes.
    pub energy_drift_all: f64,
    /// Largest wall gap h (positive = penetration), per wall (keyed by the wall's name).
    pub max_wall_gap: IndexMap<String, f64>,
    /// max over nodes and coordinates of |q − q_time-stepping|: a large value hints at a
    /// spurious critical point or a too coarse grid.
    pub distance_from_time_stepping: Option<f64>,
    /// Contact episodes per wall (maximal runs of nodes in contact, [`contact`](crate::discrete::contact); keyed by
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
    /// Where the nodes are: `uniform`, or `adaptive` (along the motion; the trajectory
    /// lists each node's time).
    pub grid: &'static str,
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

/// Everything a solve produced.
#[derive(Debug, Clone, Serialize)]
pub struct Outcome {
    /// The scene's name.
    pub scene: String,
    /// How the solve ended (serialized as the fields `converged`, `status`,
    /// `status_text` and `solve_status`).
    #[serde(flatten)]
    pub status: SolveStatus,
    /// The trajectory checked against time stepping of the same scene ([`verify`](crate::stepping::verify)).
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
    /// The work of the whole solve: every attempt of the fallback ladder (each attempt's
    /// own is in [`Attempt::work`]) and the preliminary solves the ladder ran without
    /// listing them as attempts (a coarse grid or wider walls that did not converge).
    pub work: Work,
    /// Checks of the solution.
    pub diagnostics: Diagnostics,
    /// Suspicions about the solution (spurious critical point, residual too large, …).
    pub warnings: Vec<String>,
    /// What the solve chose by itself and why (the natural initial-velocity condition
    /// for a fast initial layer).
    pub notes: Vec<String>,
    /// Every run tried by the fallback ladder: the scene's own, then the fallbacks; the
    /// one reported is marked `chosen`.
    pub attempts: Vec<Attempt>,
    /// What to do when the result cannot be trusted (not converged, or not verified).
    pub remedy: Option<String>,
    /// The grids and operators a refinement or an operator choice tried (`null` when the
    /// scene's own discretization was solved as given).
    pub refinement: Option<Refinement>,
    /// The iteration table of the backend that finished (Ipopt's, or Newton's in the
    /// same layout).
    pub history: Vec<IterationStat>,
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
    /// Its work: its run, the verification, and the preliminary solves it started from
    /// (the coarse grid of coarse to fine, the wider walls of the continuation).
    pub work: Work,
    /// Wall time, seconds.
    pub wall_s: f64,
    /// Whether its trajectory is the one reported.
    pub chosen: bool,
}

/// What a refinement ([`refine`](crate::solve::choice::refine)) did: every discretization it solved,
/// and why it stopped (`summary.json`: `refinement`).
#[derive(Debug, Clone, Serialize)]
pub struct Refinement {
    /// Whether the grid was refined (`--refine`), or only the operator chosen for the
    /// scene's grid (`--operator auto`).
    pub refine: bool,
    /// Whether the operator (and the initial-velocity condition) was chosen.
    pub operator_chosen: bool,
    /// The verification's tolerance and where it came from.
    pub tolerance: String,
    /// The largest grid the refinement could use, and why.
    pub max_nodes: usize,
    /// Where `max_nodes` came from.
    pub max_nodes_source: String,
    /// Every discretization solved, in order; the last one trusted is the reported one.
    pub grids: Vec<RefinedGrid>,
    /// Why the refinement stopped, in words.
    pub result: String,
    /// Seconds spent predicting errors (the time-stepping references of the proxy).
    pub prediction_s: f64,
}

/// One discretization a refinement solved.
#[derive(Debug, Clone, Serialize)]
pub struct RefinedGrid {
    /// Grid nodes N.
    pub nodes: usize,
    /// The operator.
    pub operator: String,
    /// The initial-velocity condition.
    pub initial_velocity: InitialVelocity,
    /// `uniform` or `adaptive`.
    pub grid: &'static str,
    /// The predicted error relative to the tolerance (max over coordinates of error /
    /// tolerance), when a prediction was made.
    pub predicted: Option<f64>,
    /// The verification's error relative to the tolerance, when it could be measured.
    pub measured: Option<f64>,
    /// The verification's max |q − q_reference|.
    pub max_error: Option<f64>,
    /// How it ended: `verified`, `not verified`, `not converged`, `unverified`.
    pub verdict: String,
    /// Wall time of its solve, fallback ladder included, seconds.
    pub wall_s: f64,
}

/// How a run covered the scene's span.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Method {
    /// One solve over the whole span.
    Global,
    /// Successive windows, each a solve from the state the previous one reached.
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
                let windows = counted(*count, "window");
                write!(f, "{windows} of {length:.4} s ({nodes_per_window} nodes), each discarding its last {overlap:.4} s")
            }
        }
    }
}

/// `n` and the noun, plural unless `n` is 1: "1 window", "3 windows".
pub(crate) fn counted(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// "solved as 1 windows of …" was printed for a single window.
    #[test]
    fn a_method_counts_its_windows_in_the_singular_or_the_plural() {
        let one = Method::Windows { length: 7.87891, overlap: 0.5, nodes_per_window: 64, count: 1 };
        assert_eq!(one.to_string(), "1 window of 7.8789 s (64 nodes), each discarding its last 0.5000 s");
        let three = Method::Windows { length: 7.87891, overlap: 0.5, nodes_per_window: 64, count: 3 };
        assert_eq!(three.to_string(), "3 windows of 7.8789 s (64 nodes), each discarding its last 0.5000 s");
        assert_eq!(Method::Global.to_string(), "one solve over the whole span");
        assert_eq!(
            (counted(0, "episode"), counted(1, "episode"), counted(2, "episode")),
            ("0 episodes".into(), "1 episode".into(), "2 episodes".into())
        );
    }
}
