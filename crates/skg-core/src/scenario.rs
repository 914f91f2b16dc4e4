//! Scene files: the TOML a user writes, its validation, and the resolved scene.
//!
//! A scene file is read in two steps. [`SceneFile::parse`] deserializes the TOML
//! (unknown keys and type errors are reported with file, line and column by the
//! `toml` crate, through [`parse_toml`], which sweep files use too). [`SceneFile::resolve`] then evaluates the parameters (numbers or
//! expressions of other parameters), applies command-line overrides and checks
//! every number a solve depends on. Expressions of the model itself (Lagrangian,
//! constraints, forces, walls) are parsed later by [`crate::model`], which reports
//! errors through [`SceneError::Expression`] with the position in the file.
//!
//! The format is documented key by key in the README ("The scene file, key by key").

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

use indexmap::IndexMap;
use serde::{Deserialize, Serialize};
use toml::Spanned;

use crate::sbp::OperatorKind;
use skg_expr::{ExprId, Graph, ParseError, ParseErrorKind, Symbol};

/// Errors in a scene file or its overrides. Each names the file and, where it can,
/// the line and column.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file cannot be read.
    #[error("cannot read scene file {path}: {source}")]
    Io {
        /// The file as given.
        path: PathBuf,
        /// Why it cannot be read.
        source: std::io::Error,
    },
    /// The file is not valid TOML, or has unknown keys or values of the wrong type.
    #[error("{location}: {message}")]
    Toml {
        /// Where.
        location: Location,
        /// The `toml` crate's message.
        message: String,
    },
    /// An expression (Lagrangian, constraint, force, wall, parameter) does not parse or
    /// names something unknown.
    #[error("{location}: in `{key}`: {error}\n{caret}")]
    Expression {
        /// Where the error is, inside the expression's string.
        location: Location,
        /// The key holding the expression, e.g. `constraints.g1.expression`.
        key: String,
        /// The parser's error.
        error: Box<ParseError>,
        /// The expression with a caret under the error's position.
        caret: String,
    },
    /// A value is out of range, a name clashes, the initial state is inadmissible, ….
    #[error("{location}: {message}")]
    Invalid {
        /// Where.
        location: Location,
        /// What is wrong.
        message: String,
    },
    /// A setting given outside the scene file (a command-line option such as
    /// `--verify-tol`, or the same argument of the Python API) is out of range.
    #[error("{setting}: {message}")]
    Setting {
        /// The setting and its value as given, e.g. `--verify-tol -1`.
        setting: String,
        /// What is wrong.
        message: String,
    },
    /// A `--set` (or sweep) assignment is malformed or names no parameter.
    #[error("--set {assignment}: {message}")]
    Override {
        /// The assignment as given.
        assignment: String,
        /// What is wrong.
        message: String,
    },
}

/// A number or an expression of the scene's parameters, e.g. `0.5` or `"pi/6"`.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(untagged)]
pub enum NumOrExpr {
    /// A number.
    Num(f64),
    /// An expression of the parameters and `pi`.
    Expr(String),
}

impl fmt::Display for NumOrExpr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            NumOrExpr::Num(x) => write!(f, "{x}"),
            NumOrExpr::Expr(s) => write!(f, "{s}"),
        }
    }
}

/// How the discrete action is posed to Ipopt (docs/mathematics.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Formulation {
    /// Only the equations ∂S/∂(q-, λ-) = 0 in the unknowns (q+, λ+): half the size.
    #[default]
    Reduced,
    /// The paper's formulation: all doubled unknowns, the square system ∇S = 0.
    Full,
}

/// Error of parsing a [`Formulation`] from a string.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown formulation `{input}` (expected `reduced` or `full`)")]
pub struct ParseFormulationError {
    /// The rejected input.
    pub input: String,
}

impl std::str::FromStr for Formulation {
    type Err = ParseFormulationError;

    /// Case-insensitive: `reduced` or `full`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "reduced" => Ok(Formulation::Reduced),
            "full" => Ok(Formulation::Full),
            _ => Err(ParseFormulationError { input: s.to_string() }),
        }
    }
}

impl fmt::Display for Formulation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Formulation::Reduced => "reduced",
            Formulation::Full => "full",
        })
    }
}

/// How the initial velocity enters the discrete action (docs/mathematics.md §5). The
/// initial position is imposed the same way by both (`q+[1] = q_i`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum InitialVelocity {
    /// `(D q+)[1] = q̇_i` through a multiplier, with `q-[1] = 0`: the velocity of the
    /// first node is the initial velocity exactly (the condition set the paper's figures
    /// and the independent implementation use).
    #[default]
    Strong,
    /// The initial momentum `p_i = ∂L/∂q̇(q_i, q̇_i, t_i)` enters the action as the
    /// boundary term `p_i·q-[1]`, and `q-[1]` is free: its row makes the discrete momentum
    /// at the first node equal `p_i` up to the first node's weighted equation of motion
    /// (the action's natural boundary condition; an SBP-SAT term). The first node's
    /// equation of motion and constraints are then imposed too. More accurate for the
    /// higher-order operators (the rolling disk on SBP484: 9× at N = 256).
    Natural,
}

/// Error of parsing an [`InitialVelocity`] from a string.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown initial velocity condition `{input}` (expected `strong` or `natural`)")]
pub struct ParseInitialVelocityError {
    /// The rejected input.
    pub input: String,
}

impl std::str::FromStr for InitialVelocity {
    type Err = ParseInitialVelocityError;

    /// Case-insensitive: `strong` or `natural`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "strong" => Ok(InitialVelocity::Strong),
            "natural" => Ok(InitialVelocity::Natural),
            _ => Err(ParseInitialVelocityError { input: s.to_string() }),
        }
    }
}

impl fmt::Display for InitialVelocity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            InitialVelocity::Strong => "strong",
            InitialVelocity::Natural => "natural",
        })
    }
}

/// What Ipopt is given as the Hessian of its Lagrangian. For the square systems
/// solved here the Newton step does not depend on it (docs/mathematics.md, docs/solver.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum HessianMode {
    /// No Hessian entries (nele_hess = 0): the step is the plain Newton step.
    #[default]
    Zero,
    /// The exact Hessian (reduced formulation only: it is the (q+,λ+) block of ∇²S
    /// evaluated with the minus variables set to Ipopt's multipliers).
    Exact,
}

/// Which solver finds the root of the square system (docs/solver.md#choosing-the-backend).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Backend {
    /// Ipopt with MUMPS on the KKT system (the default).
    #[default]
    Ipopt,
    /// Newton's method with a sparse LU of the square Jacobian and a line search on the
    /// residual norm; hands over to Ipopt when it fails.
    Newton,
}

/// Error of parsing a [`Backend`] from a string.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown backend `{input}` (expected `ipopt` or `newton`)")]
pub struct ParseBackendError {
    /// The rejected input.
    pub input: String,
}

impl std::str::FromStr for Backend {
    type Err = ParseBackendError;

    /// Case-insensitive: `ipopt` or `newton`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "ipopt" => Ok(Backend::Ipopt),
            "newton" => Ok(Backend::Newton),
            _ => Err(ParseBackendError { input: s.to_string() }),
        }
    }
}

impl fmt::Display for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Backend::Ipopt => "ipopt",
            Backend::Newton => "newton",
        })
    }
}

/// The `[scene]` table.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneMeta {
    /// The scene's name (in summaries and provenance).
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// L(q, q̇, t) in terms of coordinates `x`, velocities `x_dot`, the time `t` and
    /// parameters.
    pub lagrangian: Spanned<String>,
}

/// One `[[coordinates]]` entry.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CoordinateSpec {
    /// The coordinate's name; `<name>_dot` is its velocity in expressions.
    pub name: Spanned<String>,
    /// Initial value q_i(t_start).
    pub initial: Spanned<NumOrExpr>,
    /// Initial velocity q̇_i(t_start).
    pub velocity: Spanned<NumOrExpr>,
}

/// One `[[constraints]]` entry: a velocity or a position constraint ([`ConstraintKind`]).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ConstraintSpec {
    /// The constraint's name (columns `lambda_<name>`, `residual_<name>` and, for a
    /// position constraint, `drift_<name>`).
    pub name: Spanned<String>,
    /// g(q, q̇, t) = 0, linear or nonlinear in the velocities, or h(q, t) = 0 without
    /// velocities.
    pub expression: Spanned<String>,
}

/// One `[[walls]]` entry: a regularized wall with optional friction.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct WallSpec {
    /// The wall's name (column `gap_<name>`, keys of per-wall diagnostics).
    pub name: Spanned<String>,
    /// h(q, t): the allowed side is h ≤ 0.
    pub h: Spanned<String>,
    /// A in F_N = -A δ_σ(h) ∇h.
    pub strength: Spanned<NumOrExpr>,
    /// σ, the width of the Gaussian δ_σ.
    pub width: Spanned<NumOrExpr>,
    /// Kinetic friction coefficient μ (0 = no friction term at all).
    #[serde(default)]
    pub friction: Option<Spanned<NumOrExpr>>,
    /// Friction direction, one expression per coordinate of the parameters,
    /// coordinates, velocities and `t` (normalized by the tool); when absent the friction
    /// opposes the tangential velocity.
    #[serde(default)]
    pub friction_direction: Option<Vec<Spanned<String>>>,
    /// ε in |v∥| ≈ sqrt(|v∥|² + ε²), which keeps friction differentiable at rest.
    #[serde(default)]
    pub friction_velocity: Option<Spanned<NumOrExpr>>,
}

/// The `[time]` table: the time grid.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    /// Start time t_i (where the initial state is given).
    pub start: Spanned<NumOrExpr>,
    /// End time t_f.
    pub end: Spanned<NumOrExpr>,
    /// Number of grid nodes N.
    pub nodes: Spanned<i64>,
    /// Solve in successive windows of this length (seconds) instead of one global solve.
    #[serde(default)]
    pub window: Option<Spanned<NumOrExpr>>,
    /// Length (seconds) discarded at the end of each window (default: a quarter window).
    #[serde(default)]
    pub overlap: Option<Spanned<NumOrExpr>>,
}

/// The `[verify]` table: how a solve is checked against time stepping of the same scene.
#[derive(Debug, Clone, Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
pub struct VerifySpec {
    /// Absolute tolerance on max |q − q_reference| (coordinate units).
    #[serde(default)]
    pub tol: Option<Spanned<NumOrExpr>>,
}

/// The `[discretization]` table.
#[derive(Debug, Clone, Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
pub struct DiscretizationSpec {
    /// The SBP operator's name (default SBP242).
    #[serde(default)]
    pub operator: Option<Spanned<String>>,
    /// The formulation (default reduced).
    #[serde(default)]
    pub formulation: Option<Formulation>,
    /// How the initial velocity is imposed (default strong).
    #[serde(default)]
    pub initial_velocity: Option<InitialVelocity>,
}

/// The `[solver]` table: the backend and Ipopt's settings.
#[derive(Debug, Clone, Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// The solver of the square system (default ipopt).
    pub backend: Option<Backend>,
    /// Ipopt's `tol` and `constr_viol_tol` (default 1e-11).
    pub tol: Option<Spanned<f64>>,
    /// Ipopt's `max_iter` (default 100).
    pub max_iter: Option<u32>,
    /// Ipopt's console `print_level` (default 0: silent).
    pub print_level: Option<Spanned<i32>>,
    /// Ipopt's `linear_solver` (default: Ipopt's).
    pub linear_solver: Option<Spanned<String>>,
    /// The Hessian given to Ipopt (default zero).
    pub hessian: Option<Spanned<HessianMode>>,
    /// Ipopt log file, relative to the output directory.
    pub log_file: Option<String>,
    /// Further Ipopt options passed through verbatim, e.g. `mumps_pivot_order = 0`.
    #[serde(default)]
    pub ipopt: IndexMap<String, Spanned<IpoptValue>>,
    /// When the solve fails or is not verified, try the fallback ladder (default true).
    pub fallback: Option<bool>,
}

/// The value of a pass-through Ipopt option: integer, number or string, as Ipopt's
/// option has that type.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(untagged)]
pub enum IpoptValue {
    /// An integer option.
    Int(i32),
    /// A numeric option.
    Num(f64),
    /// A string option.
    Str(String),
}

/// The TOML document as written.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// `[scene]`: name, description, Lagrangian.
    pub scene: SceneMeta,
    /// `[parameters]`: named numbers or expressions of other parameters.
    #[serde(default)]
    pub parameters: IndexMap<String, Spanned<NumOrExpr>>,
    /// `[[coordinates]]`, in order.
    pub coordinates: Vec<CoordinateSpec>,
    /// `[[constraints]]`, in order.
    #[serde(default)]
    pub constraints: Vec<ConstraintSpec>,
    /// Generalized forces, one expression per coordinate name.
    #[serde(default)]
    pub forces: IndexMap<String, Spanned<String>>,
    /// `[[walls]]`, in order.
    #[serde(default)]
    pub walls: Vec<WallSpec>,
    /// `[time]`.
    pub time: TimeSpec,
    /// `[discretization]`.
    #[serde(default)]
    pub discretization: DiscretizationSpec,
    /// `[solver]`.
    #[serde(default)]
    pub solver: SolverSpec,
    /// `[verify]`.
    #[serde(default)]
    pub verify: VerifySpec,
    /// Path and source text, for error positions.
    #[serde(skip)]
    pub origin: Origin,
}

/// A place in an input file: the file and, where known, the line and column (both
/// 1-based, columns counted in characters). Displayed as `file:line:col`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Location {
    /// The file, as the user named it.
    pub file: String,
    /// 1-based line, if known.
    pub line: Option<usize>,
    /// 1-based column in characters, if known.
    pub col: Option<usize>,
}

impl Location {
    /// The file as a whole (no line or column).
    pub fn file(path: impl Into<String>) -> Location {
        Location { file: path.into(), line: None, col: None }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(col) = self.col {
                write!(f, ":{col}")?;
            }
        }
        Ok(())
    }
}

/// Where a scene came from, to turn byte spans into `file:line:column`.
#[derive(Debug, Clone, Default)]
pub struct Origin {
    /// The file, as the user named it.
    pub path: String,
    /// Its whole text.
    pub text: String,
}

impl Origin {
    /// `file:line:column` of a byte offset (1-based line and column, columns in chars).
    pub fn locate(&self, offset: usize) -> Location {
        let offset = offset.min(self.text.len());
        let before = &self.text[..offset];
        let line = before.matches('\n').count() + 1;
        let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        Location { file: self.path.clone(), line: Some(line), col: Some(col) }
    }

    /// The file as a whole, for errors that belong to no single key.
    pub fn whole(&self) -> Location {
        Location::file(self.path.clone())
    }

    /// Hash of the scene file's text ([`crate::provenance::content_hash`]).
    pub fn content_hash(&self) -> String {
        crate::provenance::content_hash(self.text.as_bytes())
    }

    /// Location of a spanned value. For a string value the span starts at the opening
    /// quote; `inner` is a char offset inside the string.
    pub fn locate_in<T>(&self, v: &Spanned<T>, inner: Option<usize>) -> Location {
        let start = v.span().start;
        match inner {
            Some(k) => {
                let quote = self.text[start..].chars().next().map_or(0, |c| c.len_utf8());
                let body = &self.text[(start + quote).min(self.text.len())..];
                let byte: usize = body.chars().take(k).map(char::len_utf8).sum();
                self.locate(start + quote + byte)
            }
            None => self.locate(start),
        }
    }
}

/// Command-line and sweep overrides applied on top of a scene file.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Overrides {
    /// `name=value` parameter assignments (value: number or expression).
    pub set: Vec<(String, String)>,
    /// Number of nodes N.
    pub nodes: Option<usize>,
    /// SBP operator.
    pub operator: Option<OperatorKind>,
    /// Formulation.
    pub formulation: Option<Formulation>,
    /// How the initial velocity is imposed.
    pub initial_velocity: Option<InitialVelocity>,
    /// Hessian given to Ipopt.
    pub hessian: Option<HessianMode>,
    /// The iteration limit (Ipopt's, and Newton's).
    pub max_iter: Option<u32>,
    /// The solver of the square system.
    pub backend: Option<Backend>,
    /// Window length in seconds (`--window`; 0 turns windows off).
    pub window: Option<f64>,
    /// Window overlap in seconds (`--overlap`).
    pub overlap: Option<f64>,
    /// Verification tolerance (`--verify-tol`).
    pub verify_tol: Option<f64>,
    /// Skip verification (`--no-verify`).
    pub no_verify: bool,
    /// Do not try the fallback ladder (`--no-fallback`).
    pub no_fallback: bool,
}

impl Overrides {
    /// Parse one `name=value` assignment of `--set`.
    pub fn parse_assignment(s: &str) -> Result<(String, String), SceneError> {
        let bad = |m: &str| SceneError::Override { assignment: s.to_string(), message: m.to_string() };
        let (name, value) = s.split_once('=').ok_or_else(|| bad("expected name=value"))?;
        let name = name.trim();
        if name.is_empty() || value.trim().is_empty() {
            return Err(bad("expected name=value"));
        }
        Ok((name.to_string(), value.trim().to_string()))
    }
}

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
    /// Ipopt's log file; the scene gives it relative to the output directory and the
    /// caller of the solve joins it to that directory.
    pub log_file: Option<PathBuf>,
    /// Further Ipopt options, passed through verbatim.
    pub ipopt: IndexMap<String, IpoptValue>,
    /// Whether a failed or unverified solve tries the fallback ladder ([`crate::ladder`]).
    pub fallback: bool,
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

/// How a solve is verified ([`crate::verify`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct VerifySettings {
    /// Whether to verify at all (`--no-verify` turns it off).
    pub enabled: bool,
    /// The absolute tolerance on max |q − q_reference|, if the scene or the command line
    /// gives one (otherwise the default of [`crate::verify`]).
    pub tol: Option<f64>,
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
    /// The SBP operator.
    pub operator: OperatorKind,
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
}

impl Scene {
    /// Whether the scene declares forces (`[forces]`) or wall friction: either keeps its
    /// energy from being conserved (so does an explicit time dependence, a property of
    /// its model).
    pub fn has_non_conservative_forces(&self) -> bool {
        !self.file.forces.is_empty() || self.walls.iter().any(|w| w.friction != 0.0)
    }
}

/// The largest node count a scene may have (far above what fits in memory for a
/// solve; the solve and the reference check their memory estimate separately).
pub const MAX_NODES: usize = 100_000_000;

/// The smallest time step a grid may have (1/Δt and its powers must stay finite).
const MIN_TIME_STEP: f64 = 1e-100;

/// Check that `nodes` equally spaced times from `t_start` to `t_end` are distinct and
/// increasing in floating point: the step must exceed a few units in the last place of
/// the larger end.
fn check_time_resolution(t_start: f64, t_end: f64, nodes: usize) -> Result<(), String> {
    let dt = (t_end - t_start) / (nodes as f64 - 1.0);
    let ulp = t_start.abs().max(t_end.abs()) * f64::EPSILON;
    if dt > 4.0 * ulp && dt > MIN_TIME_STEP && dt.is_finite() {
        return Ok(());
    }
    if dt == 0.0 {
        return Err(format!(
            "the time span end − start = {:e} divided into {} steps gives a zero time step: lengthen the span or use fewer nodes",
            t_end - t_start,
            nodes - 1
        ));
    }
    if dt <= MIN_TIME_STEP && dt > 4.0 * ulp {
        return Err(format!(
            "the time step Δt = {dt:e} is below {MIN_TIME_STEP:e}: the SBP derivative (∝ 1/Δt) would overflow; rescale time"
        ));
    }
    Err(format!(
        "the time step Δt = ({t_end:e} − {t_start:e})/{} = {dt:e} is not resolved by floating-point numbers near {:e} \
         (their spacing there is {ulp:e}), so the {nodes} node times would not be distinct: measure time from 0 (shift start \
         and end), or use a longer span or fewer nodes",
        nodes - 1,
        t_start.abs().max(t_end.abs())
    ))
}

/// Names the expression language reserves.
pub const RESERVED: &[&str] = &["pi", "sin", "cos", "tan", "exp", "log", "sqrt", "abs", "sinh", "cosh", "tanh", "atan"];

/// Suffix that turns a coordinate name into its velocity: `x` → `x_dot`.
pub const VELOCITY_SUFFIX: &str = "_dot";

/// The name of the time in the model's expressions (Lagrangian, constraints, forces,
/// walls); no parameter or coordinate may take it.
pub const TIME: &str = "t";

/// What the names of a scene's model expressions mean: coordinate `i` is variable `i`,
/// its velocity `<name>_dot` variable `d + i`, the time `t` variable `time`, and a
/// parameter its value.
#[derive(Debug, Clone, Copy)]
pub struct ExpressionNames<'a> {
    /// Coordinate names, in order.
    pub coordinates: &'a [String],
    /// Parameter values.
    pub parameters: &'a IndexMap<String, f64>,
    /// The variable index of the time `t`.
    pub time: usize,
}

impl ExpressionNames<'_> {
    /// What `name` means, or `None` if it is unknown.
    pub fn resolve(&self, name: &str) -> Option<Symbol> {
        let coordinate = |c: &str| self.coordinates.iter().position(|x| x == c);
        if let Some(i) = coordinate(name) {
            return Some(Symbol::Var(i));
        }
        if let Some(i) = name.strip_suffix(VELOCITY_SUFFIX).and_then(coordinate) {
            return Some(Symbol::Var(self.coordinates.len() + i));
        }
        if name == TIME {
            return Some(Symbol::Var(self.time));
        }
        self.parameters.get(name).map(|v| Symbol::Const(*v))
    }

    /// The list of valid names, for the hint of an unknown-name error.
    fn hint(&self) -> String {
        let mut names: Vec<String> = Vec::new();
        for c in self.coordinates {
            names.push(c.clone());
            names.push(format!("{c}{VELOCITY_SUFFIX}"));
        }
        names.push(TIME.to_string());
        names.extend(self.parameters.keys().cloned());
        format!("known names: {}, pi", names.join(", "))
    }
}

/// Errors of reading a TOML input file ([`read_toml`], [`parse_toml`]).
#[derive(Debug, thiserror::Error)]
pub enum TomlError {
    /// The file cannot be read.
    #[error("cannot read {path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        error: std::io::Error,
    },
    /// The text is not valid TOML or does not have the expected keys and types.
    #[error("{location}: {message}")]
    Parse {
        /// Where, as precisely as the `toml` crate says.
        location: Location,
        /// The `toml` crate's message.
        message: String,
    },
}

/// Read a TOML file and deserialize it. Returns the value and its [`Origin`] (the path
/// as given and the text), with which later errors can be located in the file.
pub fn read_toml<T: serde::de::DeserializeOwned>(path: &Path) -> Result<(T, Origin), TomlError> {
    let text = std::fs::read_to_string(path).map_err(|error| TomlError::Io { path: path.to_path_buf(), error })?;
    parse_toml(&text, &path.display().to_string())
}

/// Deserialize TOML text; `path` only labels error locations (`file:line:col`).
pub fn parse_toml<T: serde::de::DeserializeOwned>(text: &str, path: &str) -> Result<(T, Origin), TomlError> {
    let origin = Origin { path: path.to_string(), text: text.to_string() };
    match toml::from_str(text) {
        Ok(value) => Ok((value, origin)),
        Err(e) => {
            let location = e.span().map_or_else(|| origin.whole(), |span| origin.locate(span.start));
            Err(TomlError::Parse { location, message: e.message().trim_end().to_string() })
        }
    }
}

impl From<TomlError> for SceneError {
    fn from(e: TomlError) -> Self {
        match e {
            TomlError::Io { path, error } => SceneError::Io { path, source: error },
            TomlError::Parse { location, message } => SceneError::Toml { location, message },
        }
    }
}

impl SceneFile {
    /// Read and deserialize a scene file.
    pub fn load(path: &Path) -> Result<SceneFile, SceneError> {
        let (mut file, origin): (SceneFile, Origin) = read_toml(path)?;
        file.origin = origin;
        Ok(file)
    }

    /// Deserialize a scene from its text; `path` only labels error messages.
    pub fn parse(text: &str, path: &str) -> Result<SceneFile, SceneError> {
        let (mut file, origin): (SceneFile, Origin) = parse_toml(text, path)?;
        file.origin = origin;
        Ok(file)
    }

    fn invalid<T>(&self, v: &Spanned<T>, message: impl Into<String>) -> SceneError {
        SceneError::Invalid { location: self.origin.locate_in(v, None), message: message.into() }
    }

    /// Error for an expression at a spanned string value.
    pub fn expression_error(&self, v: &Spanned<String>, key: &str, error: ParseError) -> SceneError {
        let caret = error.caret_line();
        SceneError::Expression {
            location: self.origin.locate_in(v, Some(error.position)),
            key: key.to_string(),
            error: Box::new(error),
            caret,
        }
    }

    /// Parse a model expression (Lagrangian, constraint, force, wall) at the spanned
    /// string `src` into `graph`, with the meaning of names given by `names`. An error
    /// carries its position in the file and, for an unknown name, the list of known ones.
    pub fn parse_expression(
        &self,
        graph: &mut Graph,
        src: &Spanned<String>,
        key: &str,
        names: &ExpressionNames,
    ) -> Result<ExprId, SceneError> {
        graph.parse(src.get_ref(), &mut |name| names.resolve(name)).map_err(|mut e| {
            if e.kind == ParseErrorKind::UnknownSymbol {
                e.hint = Some(names.hint());
            }
            self.expression_error(src, key, e)
        })
    }

    /// Whether a constraint depends on the velocities (a velocity constraint) or only
    /// on the coordinates and `t` (a position constraint); one that depends on neither
    /// coordinates nor velocities constrains nothing and is an error.
    fn constraint_kind(&self, c: &ConstraintSpec, names: &ExpressionNames) -> Result<ConstraintKind, SceneError> {
        let name = c.name.get_ref();
        let mut graph = Graph::new();
        let e = self.parse_expression(&mut graph, &c.expression, &format!("constraints.{name}.expression"), names)?;
        let d = names.coordinates.len();
        let vars = graph.variables(e);
        if vars.iter().any(|&k| (d..2 * d).contains(&k)) {
            Ok(ConstraintKind::Velocity)
        } else if vars.iter().any(|&k| k < d) {
            Ok(ConstraintKind::Position)
        } else {
            Err(self.invalid(
                &c.expression,
                format!("constraint `{name}` depends on neither the coordinates nor the velocities: it constrains nothing"),
            ))
        }
    }

    /// Evaluate a number-or-expression in terms of resolved parameters.
    pub fn eval_value(&self, v: &Spanned<NumOrExpr>, key: &str, params: &IndexMap<String, f64>) -> Result<f64, SceneError> {
        let value = match v.get_ref() {
            NumOrExpr::Num(x) => *x,
            NumOrExpr::Expr(s) => {
                let spanned = Spanned::new(v.span(), s.clone());
                eval_constant(s, params).map_err(|e| self.expression_error(&spanned, key, e))?
            }
        };
        if !value.is_finite() {
            return Err(self.invalid(v, format!("`{key}` is not finite ({value})")));
        }
        Ok(value)
    }

    /// Resolve parameters, overrides and every number; check names and ranges.
    pub fn resolve(self, ov: &Overrides) -> Result<Scene, SceneError> {
        let params = self.resolve_parameters(&ov.set)?;

        // Names: coordinates, velocities, parameters and built-ins must not collide.
        let mut seen: BTreeMap<String, &str> = BTreeMap::new();
        for r in RESERVED {
            seen.insert(r.to_string(), "a built-in name");
        }
        seen.insert(TIME.to_string(), "the time `t`, a reserved name in expressions");
        for p in params.keys() {
            let at = |message: String| match self.parameters.get(p) {
                Some(v) => self.invalid(v, message),
                None => self.toml_error(message),
            };
            check_identifier(p).map_err(|e| at(format!("parameter `{p}`: {e}")))?;
            if let Some(what) = seen.insert(p.clone(), "a parameter") {
                return Err(at(format!("parameter `{p}` clashes with {what}")));
            }
        }
        if self.coordinates.is_empty() {
            return Err(self.toml_error("the scene declares no coordinates".into()));
        }
        let mut coordinates = Vec::new();
        for c in &self.coordinates {
            let name = c.name.get_ref();
            check_identifier(name).map_err(|e| self.invalid(&c.name, e.to_string()))?;
            for key in [name.clone(), format!("{name}{VELOCITY_SUFFIX}")] {
                if let Some(what) = seen.insert(key.clone(), "a coordinate or velocity") {
                    return Err(self.invalid(&c.name, format!("`{key}` clashes with {what}")));
                }
            }
            coordinates.push(name.clone());
        }
        let mut initial_q = Vec::new();
        let mut initial_v = Vec::new();
        for c in &self.coordinates {
            let n = c.name.get_ref();
            initial_q.push(self.eval_value(&c.initial, &format!("coordinates.{n}.initial"), &params)?);
            initial_v.push(self.eval_value(&c.velocity, &format!("coordinates.{n}.velocity"), &params)?);
        }
        let names = ExpressionNames { coordinates: &coordinates, parameters: &params, time: 2 * coordinates.len() };
        let mut constraints: Vec<Constraint> = Vec::new();
        for c in &self.constraints {
            let name = c.name.get_ref();
            check_identifier(name).map_err(|e| self.invalid(&c.name, e.to_string()))?;
            if constraints.iter().any(|x| &x.name == name) {
                return Err(self.invalid(&c.name, format!("constraint `{name}` declared twice")));
            }
            constraints.push(Constraint { name: name.clone(), kind: self.constraint_kind(c, &names)? });
        }
        for (name, v) in &self.forces {
            if !coordinates.contains(name) {
                return Err(
                    self.invalid(v, format!("force on `{name}`, which is not a coordinate (coordinates: {})", coordinates.join(", ")))
                );
            }
        }
        let mut walls: Vec<Wall> = Vec::new();
        for w in &self.walls {
            let name = w.name.get_ref().clone();
            check_identifier(&name).map_err(|e| self.invalid(&w.name, e.to_string()))?;
            if walls.iter().any(|other| other.name == name) {
                return Err(self.invalid(&w.name, format!("wall `{name}` declared twice (each wall names its column gap_{name})")));
            }
            let strength = self.eval_value(&w.strength, &format!("walls.{name}.strength"), &params)?;
            if strength < 0.0 {
                return Err(self.invalid(&w.strength, format!("wall `{name}`: strength must be ≥ 0, got {strength}")));
            }
            let width = self.eval_value(&w.width, &format!("walls.{name}.width"), &params)?;
            if width <= 0.0 {
                return Err(self.invalid(&w.width, format!("wall `{name}`: width σ must be > 0, got {width}")));
            }
            let friction = match &w.friction {
                Some(v) => self.eval_value(v, &format!("walls.{name}.friction"), &params)?,
                None => 0.0,
            };
            if friction < 0.0 {
                let v = w.friction.as_ref().expect("friction present when negative");
                return Err(self.invalid(v, format!("wall `{name}`: friction μ must be ≥ 0, got {friction}")));
            }
            let friction_velocity = match &w.friction_velocity {
                Some(v) => {
                    let e = self.eval_value(v, &format!("walls.{name}.friction_velocity"), &params)?;
                    if e <= 0.0 {
                        return Err(self.invalid(v, format!("wall `{name}`: friction_velocity must be > 0, got {e}")));
                    }
                    e
                }
                None => 1e-3,
            };
            if let Some(dir) = &w.friction_direction {
                if dir.len() != coordinates.len() {
                    let message = format!(
                        "wall `{name}`: friction_direction has {} components, the scene has {} coordinates ({})",
                        dir.len(),
                        coordinates.len(),
                        coordinates.join(", ")
                    );
                    return Err(match dir.first() {
                        Some(first) => self.invalid(first, message),
                        None => self.invalid(&w.name, message),
                    });
                }
            }
            walls.push(Wall { name, strength, width, friction, friction_velocity });
        }

        let t_start = self.eval_value(&self.time.start, "time.start", &params)?;
        let t_end = self.eval_value(&self.time.end, "time.end", &params)?;
        if t_end <= t_start {
            return Err(self.invalid(&self.time.end, format!("the time span must be positive: end ({t_end}) ≤ start ({t_start})")));
        }
        let operator = match (&ov.operator, &self.discretization.operator) {
            (Some(k), _) => *k,
            (None, Some(s)) => s.get_ref().parse::<OperatorKind>().map_err(|e| self.invalid(s, e.to_string()))?,
            (None, None) => OperatorKind::Sbp242,
        };
        let nodes_raw = match ov.nodes {
            Some(n) => n as i128,
            None => *self.time.nodes.get_ref() as i128,
        };
        let nodes_origin = if ov.nodes.is_some() { " (set by --nodes or a sweep point)" } else { "" };
        if nodes_raw < operator.min_nodes() as i128 {
            return Err(self.invalid(
                &self.time.nodes,
                format!("{} needs at least {} nodes, got {nodes_raw}{nodes_origin}", operator.name(), operator.min_nodes()),
            ));
        }
        if nodes_raw > MAX_NODES as i128 {
            return Err(self.invalid(&self.time.nodes, format!("at most {MAX_NODES} nodes are supported, got {nodes_raw}{nodes_origin}")));
        }
        let nodes = nodes_raw as usize;
        check_time_resolution(t_start, t_end, nodes).map_err(|m| self.invalid(&self.time.end, format!("{m}{nodes_origin}")))?;
        let formulation = ov.formulation.or(self.discretization.formulation).unwrap_or_default();
        let initial_velocity = ov.initial_velocity.or(self.discretization.initial_velocity).unwrap_or_default();
        let s = &self.solver;
        let tol = s.tol.as_ref().map_or(1e-11, |t| *t.get_ref());
        if !(tol > 0.0 && tol.is_finite()) {
            let t = s.tol.as_ref().expect("the default is positive");
            return Err(self.invalid(t, format!("solver.tol must be a positive number, got {tol}")));
        }
        let hessian = ov.hessian.or(s.hessian.as_ref().map(|h| *h.get_ref())).unwrap_or_default();
        if hessian == HessianMode::Exact && formulation == Formulation::Full {
            let message = "solver.hessian = \"exact\" is available for the reduced formulation only \
                 (the full formulation's Lagrangian Hessian would need fourth derivatives of L; \
                 for a square system Ipopt's step does not depend on it)";
            return Err(match (&s.hessian, ov.hessian) {
                (Some(h), None) => self.invalid(h, message),
                _ => self.toml_error(format!("{message} (the exact Hessian or the full formulation was asked for on the command line)")),
            });
        }
        let print_level = s.print_level.as_ref().map_or(0, |p| *p.get_ref());
        if !(0..=12).contains(&print_level) {
            let p = s.print_level.as_ref().expect("the default is in range");
            return Err(self.invalid(p, format!("solver.print_level must be 0 (silent) … 12 (Ipopt's range), got {print_level}")));
        }
        let solver = SolverSettings {
            backend: ov.backend.or(s.backend).unwrap_or_default(),
            tol,
            max_iter: ov.max_iter.or(s.max_iter).unwrap_or(100),
            print_level,
            linear_solver: s.linear_solver.as_ref().map(|l| l.get_ref().clone()),
            hessian,
            log_file: s.log_file.as_ref().map(PathBuf::from),
            ipopt: s.ipopt.iter().map(|(k, v)| (k.clone(), v.get_ref().clone())).collect(),
            fallback: !ov.no_fallback && s.fallback.unwrap_or(true),
        };
        let windows = self.resolve_windows(ov, &params, t_end - t_start)?;
        let verify = self.resolve_verify(ov, &params)?;
        Ok(Scene {
            name: self.scene.name.clone(),
            parameters: params,
            coordinates,
            initial_q,
            initial_v,
            constraints,
            walls,
            t_start,
            t_end,
            nodes,
            operator,
            formulation,
            initial_velocity,
            solver,
            windows,
            verify,
            file: self,
        })
    }

    /// `[time] window` and `overlap`, with the command line's overrides (a window of 0
    /// from the command line turns windows off). A window as long as the span or longer
    /// is one global solve.
    fn resolve_windows(&self, ov: &Overrides, params: &IndexMap<String, f64>, span: f64) -> Result<Option<Windows>, SceneError> {
        let from_file = |v: &Option<Spanned<NumOrExpr>>, key: &str| v.as_ref().map(|v| self.eval_value(v, key, params)).transpose();
        let length = match ov.window {
            Some(w) => Some(w),
            None => from_file(&self.time.window, "time.window")?,
        };
        let overlap = match ov.overlap {
            Some(o) => Some(o),
            None => from_file(&self.time.overlap, "time.overlap")?,
        };
        // The value's origin: the scene file's line, or the command line.
        let here = |key: &Option<Spanned<NumOrExpr>>, from_cli: Option<f64>, option: &str, message: String| match (key, from_cli) {
            (Some(v), None) => self.invalid(v, message),
            (_, given) => SceneError::Setting { setting: format!("{option} {}", given.map_or("?".into(), |g| g.to_string())), message },
        };
        let Some(length) = length.filter(|&w| w != 0.0 || ov.window.is_none()) else {
            return Ok(None);
        };
        if !(length > 0.0 && length.is_finite()) {
            return Err(here(
                &self.time.window,
                ov.window,
                "--window",
                format!("time.window must be a positive number of seconds, got {length}"),
            ));
        }
        let overlap = overlap.unwrap_or(length / 4.0);
        if !(0.0..length).contains(&overlap) {
            return Err(here(
                &self.time.overlap,
                ov.overlap,
                "--overlap",
                format!("time.overlap must be ≥ 0 and shorter than the window ({length} s), got {overlap}"),
            ));
        }
        Ok((length < span).then_some(Windows { length, overlap }))
    }

    /// `[verify] tol` with the command line's overrides.
    fn resolve_verify(&self, ov: &Overrides, params: &IndexMap<String, f64>) -> Result<VerifySettings, SceneError> {
        let tol = match (ov.verify_tol, &self.verify.tol) {
            (Some(t), _) => Some(t),
            (None, Some(v)) => Some(self.eval_value(v, "verify.tol", params)?),
            (None, None) => None,
        };
        if let Some(t) = tol {
            if t.is_nan() || t <= 0.0 {
                let message = format!("the verification tolerance must be a positive number, got {t}");
                return Err(match (&self.verify.tol, ov.verify_tol) {
                    (Some(v), None) => self.invalid(v, message),
                    _ => SceneError::Setting { setting: format!("--verify-tol {t}"), message },
                });
            }
        }
        Ok(VerifySettings { enabled: !ov.no_verify, tol })
    }

    /// Where the scene sets the Ipopt option `name` (`[solver]` or `[solver.ipopt]`);
    /// the whole file if it does not (an option skg-solve sets itself).
    pub fn solver_option_location(&self, name: &str) -> Location {
        let s = &self.solver;
        let spanned = match name {
            "tol" | "constr_viol_tol" => s.tol.as_ref().map(|v| v.span()),
            "print_level" => s.print_level.as_ref().map(|v| v.span()),
            "linear_solver" => s.linear_solver.as_ref().map(|v| v.span()),
            _ => None,
        };
        match spanned.or_else(|| s.ipopt.get(name).map(|v| v.span())) {
            Some(span) => self.origin.locate(span.start),
            None => self.origin.whole(),
        }
    }

    fn toml_error(&self, message: String) -> SceneError {
        SceneError::Invalid { location: self.origin.whole(), message }
    }

    /// Evaluate parameters in dependency order (each may use the others); overrides
    /// replace a declared parameter's definition.
    fn resolve_parameters(&self, set: &[(String, String)]) -> Result<IndexMap<String, f64>, SceneError> {
        let mut defs: IndexMap<String, (NumOrExpr, Option<&Spanned<NumOrExpr>>)> =
            self.parameters.iter().map(|(k, v)| (k.clone(), (v.get_ref().clone(), Some(v)))).collect();
        for (name, value) in set {
            if !defs.contains_key(name) {
                let known: Vec<&str> = self.parameters.keys().map(String::as_str).collect();
                return Err(SceneError::Override {
                    assignment: format!("{name}={value}"),
                    message: format!(
                        "the scene has no parameter `{name}` (parameters: {})",
                        if known.is_empty() { "none".to_string() } else { known.join(", ") }
                    ),
                });
            }
            let v = match value.parse::<f64>() {
                Ok(x) => NumOrExpr::Num(x),
                Err(_) => NumOrExpr::Expr(value.clone()),
            };
            defs.insert(name.clone(), (v, None));
        }
        let mut values: IndexMap<String, f64> = IndexMap::new();
        let mut pending: Vec<&String> = defs.keys().collect();
        while !pending.is_empty() {
            let mut progressed = false;
            let mut still = Vec::new();
            for name in pending {
                let (def, spanned) = &defs[name];
                let result = match def {
                    NumOrExpr::Num(x) => Ok(*x),
                    NumOrExpr::Expr(s) => eval_constant(s, &values),
                };
                match result {
                    Ok(x) => {
                        if !x.is_finite() {
                            return Err(self.param_error(name, spanned, format!("parameter `{name}` is not finite ({x})")));
                        }
                        values.insert(name.clone(), x);
                        progressed = true;
                    }
                    Err(_) => still.push(name),
                }
            }
            if !progressed {
                // Report the first failing one with its real error (unknown name or syntax).
                let name = still[0];
                let (def, spanned) = &defs[name];
                let NumOrExpr::Expr(s) = def else { unreachable!("numbers always resolve") };
                let mut err = match eval_constant(s, &values) {
                    Err(e) => e,
                    Ok(_) => unreachable!("expression failed a moment ago"),
                };
                let names: Vec<&str> = defs.keys().map(String::as_str).collect();
                // A cycle when the unknown symbol is itself an unresolved parameter.
                if err.message.contains("unknown") && still.iter().any(|n| err.message.contains(&format!("`{n}`"))) {
                    err.message = format!(
                        "{} (parameters that depend on each other in a cycle: {})",
                        err.message,
                        still.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", ")
                    );
                } else if err.message.contains("unknown") {
                    err.message = format!("{} (parameters: {})", err.message, names.join(", "));
                }
                return Err(match spanned {
                    Some(v) => {
                        let sp = Spanned::new(v.span(), s.clone());
                        self.expression_error(&sp, &format!("parameters.{name}"), err)
                    }
                    None => SceneError::Override { assignment: format!("{name}={s}"), message: format!("{}\n{}", err, err.caret_line()) },
                });
            }
            pending = still;
        }
        // Keep the declaration order.
        Ok(defs.keys().map(|k| (k.clone(), values[k])).collect())
    }

    fn param_error(&self, name: &str, spanned: &Option<&Spanned<NumOrExpr>>, message: String) -> SceneError {
        match spanned {
            Some(v) => self.invalid(v, message),
            None => SceneError::Override { assignment: name.to_string(), message },
        }
    }
}

/// Evaluate an expression that may use only parameters (already resolved) and `pi`.
/// The time `t` is unknown here, with a hint that says why.
pub fn eval_constant(src: &str, params: &IndexMap<String, f64>) -> Result<f64, ParseError> {
    let mut g = Graph::new();
    let mut asked_for_time = false;
    let e = g
        .parse(src, &mut |name| {
            asked_for_time |= name == TIME;
            params.get(name).map(|v| Symbol::Const(*v))
        })
        .map_err(|e| {
            // An unknown name stops the parse at once, so the time was the unknown name.
            if asked_for_time {
                e.with_hint(
                    "the time `t` may appear in the Lagrangian, constraints, forces and walls only; \
                     parameters, initial values and the numbers of [[walls]] and [time] are constants",
                )
            } else {
                e
            }
        })?;
    Ok(g.eval(e, &[]))
}

/// A name that cannot be a parameter, coordinate, constraint or wall.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("`{name}` is not a valid name (letters, digits and _, not starting with a digit)")]
pub struct InvalidName {
    /// The rejected name.
    pub name: String,
}

/// Check that `name` is an identifier of the expression language: ASCII letters, digits
/// and `_`, not starting with a digit.
fn check_identifier(name: &str) -> Result<(), InvalidName> {
    let mut chars = name.chars();
    let ok = matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_') && chars.all(|c| c.is_ascii_alphanumeric() || c == '_');
    if ok {
        Ok(())
    } else {
        Err(InvalidName { name: name.to_string() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = r#"
[scene]
name = "free fall"
lagrangian = "1/2*m*x_dot^2 - m*g*x"

[parameters]
m = 1
g = 9.8
h0 = "2*g"

[[coordinates]]
name = "x"
initial = "h0"
velocity = 0

[time]
start = 0
end = 1
nodes = 16
"#;

    #[test]
    fn parameters_resolve_in_dependency_order_and_overrides_apply() {
        let f = SceneFile::parse(MINIMAL, "mem.toml").unwrap();
        let s = f.clone().resolve(&Overrides::default()).unwrap();
        assert_eq!(s.initial_q, vec![19.6]);
        let ov = Overrides { set: vec![("g".into(), "pi".into())], ..Default::default() };
        let s = f.resolve(&ov).unwrap();
        assert!((s.initial_q[0] - 2.0 * std::f64::consts::PI).abs() < 1e-15);
        assert_eq!(s.operator, OperatorKind::Sbp242);
        assert_eq!(s.formulation, Formulation::Reduced);
    }

    #[test]
    fn unknown_key_reports_line_and_column() {
        let text = MINIMAL.replace("velocity = 0", "velocity = 0\nmass = 3");
        let err = SceneFile::parse(&text, "mem.toml").unwrap_err().to_string();
        assert!(err.contains("mem.toml:15:1"), "{err}");
        assert!(err.contains("mass"), "{err}");
    }

    #[test]
    fn cyclic_and_unknown_parameters_are_errors() {
        let text = MINIMAL.replace("h0 = \"2*g\"", "h0 = \"2*k\"\nk = \"h0\"");
        let err = SceneFile::parse(&text, "mem.toml").unwrap().resolve(&Overrides::default()).unwrap_err();
        assert!(err.to_string().contains("cycle"), "{err}");
        let text = MINIMAL.replace("h0 = \"2*g\"", "h0 = \"2*gg\"");
        let err = SceneFile::parse(&text, "mem.toml").unwrap().resolve(&Overrides::default()).unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains("mem.toml:9:"), "{msg}");
        assert!(msg.contains("gg"), "{msg}");
    }

    #[test]
    fn constraints_are_classified_by_whether_they_use_velocities() {
        let with = |expr: &str| {
            let text = MINIMAL.replace("[time]", &format!("[[constraints]]\nname = \"c\"\nexpression = \"{expr}\"\n\n[time]"));
            SceneFile::parse(&text, "mem.toml").unwrap().resolve(&Overrides::default())
        };
        assert_eq!(with("x_dot - t").unwrap().constraints[0].kind, ConstraintKind::Velocity);
        assert_eq!(with("x - sin(t)").unwrap().constraints[0].kind, ConstraintKind::Position);
        // x_dot − x_dot simplifies to 0: no coordinate, no velocity.
        let msg = with("x_dot - x_dot + t").unwrap_err().to_string();
        assert!(msg.contains("mem.toml:18:14") && msg.contains("depends on neither"), "{msg}");
        let msg = with("x + tt").unwrap_err().to_string();
        assert!(msg.contains("unknown symbol `tt`") && msg.contains("known names: x, x_dot, t, m, g, h0"), "{msg}");
    }

    #[test]
    fn override_of_unknown_parameter_is_an_error() {
        let f = SceneFile::parse(MINIMAL, "mem.toml").unwrap();
        let ov = Overrides { set: vec![("nope".into(), "1".into())], ..Default::default() };
        let msg = f.resolve(&ov).unwrap_err().to_string();
        assert!(msg.contains("no parameter `nope`") && msg.contains("m, g, h0"), "{msg}");
    }
}
