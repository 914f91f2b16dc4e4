//! [`Scene`]: a scene file resolved to numbers, with its parts (walls, constraints,
//! solver settings, windows, verification settings).

use std::path::PathBuf;

use indexmap::IndexMap;
use serde::Serialize;

use super::file::{IpoptValue, NumOrExpr, SceneFile};
use super::settings::{Backend, Formulation, GridChoice, HessianMode, InitialVelocity, Stepper};
use crate::sbp::OperatorKind;

/// Settings of the solve, resolved.
#[derive(Debug, Clone, Serialize)]
pub struct SolverSettings {
    /// The solver of the square system.
    pub backend: Backend,
    /// Ipopt's `tol` and `constr_viol_tol`.
    pub tol: f64,
    /// Ipopt's `max_iter`.
    pub max_iter: u32,
    /// Ipopt's console `print_level`.
    pub print_level: i32,
    /// Ipopt's `linear_solver`, if set.
    pub linear_solver: Option<String>,
    /// The Hessian given to Ipopt.
    pub hessian: HessianMode,
    /// Ipopt's log file as the scene names it: a relative path that stays inside the
    /// output directory (checked when the scene is resolved). Only a solve into an output
    /// directory writes it, by setting [`SolverSettings::ipopt_log`].
    pub log_file: Option<PathBuf>,
    /// Where Ipopt writes its log in this process, if anywhere: never set from a scene
    /// file, only by the caller that owns the output directory (a solve into a locked
    /// directory stages the scene's `log_file` there).
    #[serde(skip)]
    pub ipopt_log: Option<PathBuf>,
    /// Further Ipopt options, passed through verbatim.
    pub ipopt: IndexMap<String, IpoptValue>,
    /// Whether a failed or unverified solve tries the fallback ladder (the solve's last
    /// stage).
    pub fallback: bool,
    /// Seconds the whole solve may take (fallback ladder and refinement included):
    /// checked between attempts; the best attempt so far is reported.
    pub time_limit: Option<f64>,
}

/// Successive time windows: each solves `length` seconds from the state the previous
/// one reached, and keeps all but its last `overlap` seconds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Windows {
    /// Length of each window's solve, seconds.
    pub length: f64,
    /// Length discarded at the end of each window, seconds (0 ≤ overlap < length).
    pub overlap: f64,
}

/// How a solve is verified against time stepping of the same scene.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct VerifySettings {
    /// Whether to verify at all (`--no-verify` turns it off).
    pub enabled: bool,
    /// The absolute tolerance on max |q − q_reference|, if the scene or the command line
    /// gives one (otherwise the verification's default, relative to each coordinate's
    /// range).
    pub tol: Option<f64>,
    /// Solve on finer grids (and, when chosen, other operators) until the verification
    /// passes (`[verify] refine`, `--refine`).
    pub refine: bool,
    /// The largest grid refinement may use, if given (`[verify] max_nodes`,
    /// `--max-nodes`).
    pub max_nodes: Option<usize>,
    /// Which integrator steps the verification, the initial guess and the refinement's
    /// predictions (`[verify] stepper`, `--stepper`; default `auto`).
    pub stepper: Stepper,
}

/// A wall, resolved to numbers (its `h` and friction direction expressions are parsed
/// by the model).
#[derive(Debug, Clone, Serialize)]
pub struct Wall {
    /// The wall's name.
    pub name: String,
    /// A in F_N = −A δ_σ(h) ∇h (≥ 0).
    pub strength: f64,
    /// σ, the width of the Gaussian δ_σ (> 0).
    pub width: f64,
    /// Kinetic friction coefficient μ (≥ 0; 0 = no friction force).
    pub friction: f64,
    /// ε in |v∥| ≈ sqrt(|v∥|² + ε²) (> 0; default 1e-3).
    pub friction_velocity: f64,
}

/// What a `[[constraints]]` expression constrains, decided by whether it depends on the
/// velocities (docs/mathematics.md §1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConstraintKind {
    /// `g(q, q̇, t) = 0`: depends on the velocities (linearly or not).
    Velocity,
    /// `h(q, t) = 0`: no velocities (a holonomic constraint). Enforced through its total
    /// time derivative `∇h·q̇ + ∂h/∂t = 0`, a velocity constraint linear in `q̇`, together
    /// with the check `h(q₀, t₀) = 0`; its drift `h` is reported.
    Position,
}

/// A declared constraint, classified.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Constraint {
    /// The constraint's name.
    pub name: String,
    /// Velocity or position constraint.
    pub kind: ConstraintKind,
}

/// A validated scene: every number resolved, every name checked.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The file it was resolved from (expressions, spans, origin).
    pub file: SceneFile,
    /// The scene's name.
    pub name: String,
    /// Parameter values, in declaration order, overrides applied.
    pub parameters: IndexMap<String, f64>,
    /// The definition each value was evaluated from: the file's, or the override's
    /// (`--set`), in declaration order. A fit, whose free parameters are variables,
    /// rebuilds the parameters that depend on them from these.
    pub definitions: IndexMap<String, NumOrExpr>,
    /// Coordinate names, in order.
    pub coordinates: Vec<String>,
    /// Initial coordinates q(t_start).
    pub initial_q: Vec<f64>,
    /// Initial velocities q̇(t_start).
    pub initial_v: Vec<f64>,
    /// Constraints, in order.
    pub constraints: Vec<Constraint>,
    /// Walls, in order.
    pub walls: Vec<Wall>,
    /// Start time.
    pub t_start: f64,
    /// End time (> start).
    pub t_end: f64,
    /// Number of grid nodes N (at least the operator's minimum).
    pub nodes: usize,
    /// The SBP operator (the one chosen by the solve when `choose_operator`).
    pub operator: OperatorKind,
    /// The solve chooses the operator by predicted cost: `operator = "auto"`, or a
    /// refinement with no operator named in the scene or on the command line.
    pub choose_operator: bool,
    /// The solve chooses the initial-velocity condition too (it chooses the operator,
    /// and no condition is named).
    pub choose_initial_velocity: bool,
    /// Where the nodes are: uniform or adaptive (the one chosen by the solve when
    /// `choose_grid`).
    pub grid: GridChoice,
    /// The solve chooses the grid with the operator: `grid = "auto"`, or the operator
    /// chosen and no grid named.
    pub choose_grid: bool,
    /// Whether the scene or the command line names the initial-velocity condition (else
    /// the solve may choose the natural one for a fast initial layer).
    pub initial_velocity_named: bool,
    /// The formulation.
    pub formulation: Formulation,
    /// How the initial velocity is imposed.
    pub initial_velocity: InitialVelocity,
    /// Ipopt's settings.
    pub solver: SolverSettings,
    /// Solve in windows (`[time] window`), or in one piece (None).
    pub windows: Option<Windows>,
    /// How the solve is verified.
    pub verify: VerifySettings,
    /// What the user should know about how the scene was read, though nothing is wrong
    /// (a window not shorter than the span, which makes the solve one piece); the
    /// command line prints them as notes. Each starts with where its setting is
    /// (`file:line:column: ` or the command-line option).
    pub notes: Vec<String>,
}

impl Scene {
    /// Whether the scene declares forces (`[forces]`) or wall friction: either keeps its
    /// energy from being conserved (so does an explicit time dependence, a property of
    /// its model).
    pub fn has_non_conservative_forces(&self) -> bool {
        !self.file.forces.is_empty() || self.walls.iter().any(|w| w.friction != 0.0)
    }
}
