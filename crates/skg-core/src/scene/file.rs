//! The scene file as written: [`SceneFile`], the TOML document, made of one part per
//! table (`[scene]`, `[[coordinates]]`, `[[constraints]]`, `[[walls]]`, `[time]`,
//! `[discretization]`, `[solver]`, `[verify]`, `[fit]`), each named after what it holds. Values
//! keep their byte spans, so that later errors point into the file.

use std::fmt;
use std::path::Path;

use indexmap::IndexMap;
use serde::{Deserialize, Serialize};
use skg_expr::ParseError;
use toml::Spanned;

use super::emit::write_toml;
use super::error::SceneError;
use super::location::{parse_origin, parse_toml, read_toml, Location, Origin};
use super::settings::{Backend, Formulation, GridChoice, HessianMode, InitialVelocity, Stepper};

/// A number or an expression of the scene's parameters, e.g. `0.5` or `"pi/6"`.
/// (Deserialized by hand rather than as an untagged enum, so that a value of another
/// type is refused with what was expected instead of serde's "did not match any
/// variant".)
#[derive(Debug, Clone, Serialize, PartialEq)]
#[serde(untagged)]
pub enum NumOrExpr {
    /// A number.
    Num(f64),
    /// An expression of the parameters and `pi`.
    Expr(String),
}

impl<'de> Deserialize<'de> for NumOrExpr {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = NumOrExpr;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a number or an expression in quotes")
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<NumOrExpr, E> {
                Ok(NumOrExpr::Num(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<NumOrExpr, E> {
                Ok(NumOrExpr::Num(v as f64))
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<NumOrExpr, E> {
                Ok(NumOrExpr::Num(v))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<NumOrExpr, E> {
                Ok(NumOrExpr::Expr(v.to_string()))
            }
        }
        deserializer.deserialize_any(Visitor)
    }
}

impl fmt::Display for NumOrExpr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            NumOrExpr::Num(x) => write!(f, "{x}"),
            NumOrExpr::Expr(s) => write!(f, "{s}"),
        }
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

/// One `[[constraints]]` entry: a velocity or a position constraint ([`ConstraintKind`](super::ConstraintKind)).
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
    /// Refine the grid until the verification passes (default false).
    #[serde(default)]
    pub refine: Option<bool>,
    /// The largest grid refinement may use (default: what the memory allows, at most 2²⁰).
    #[serde(default)]
    pub max_nodes: Option<Spanned<i64>>,
    /// Which integrator steps the verification, the guess and the predictions
    /// (`auto`, `dop853` or `implicit`; default `auto`).
    #[serde(default)]
    pub stepper: Option<Stepper>,
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
    /// Where the nodes are (default uniform; chosen with the operator when it is).
    #[serde(default)]
    pub grid: Option<GridChoice>,
}

/// The `[solver]` table: the backend and Ipopt's settings.
#[derive(Debug, Clone, Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// The solver of the square system (default ipopt).
    pub backend: Option<Backend>,
    /// Ipopt's `tol` and `constr_viol_tol` (default 1e-11).
    pub tol: Option<Spanned<f64>>,
    /// Ipopt's `max_iter` (default 100), at most [`MAX_ITER`](crate::scene::MAX_ITER).
    pub max_iter: Option<Spanned<u32>>,
    /// Ipopt's console `print_level` (default 0: silent).
    pub print_level: Option<Spanned<i32>>,
    /// Ipopt's `linear_solver` (default: Ipopt's).
    pub linear_solver: Option<Spanned<String>>,
    /// The Hessian given to Ipopt (default zero).
    pub hessian: Option<Spanned<HessianMode>>,
    /// Ipopt log file, relative to the output directory (and confined to it).
    pub log_file: Option<Spanned<String>>,
    /// Further Ipopt options passed through verbatim, e.g. `mumps_pivot_order = 0`.
    #[serde(default)]
    pub ipopt: IndexMap<String, Spanned<IpoptValue>>,
    /// When the solve fails or is not verified, try the fallback ladder (default true).
    pub fallback: Option<bool>,
    /// Seconds the whole solve may take, fallback ladder and refinement included.
    #[serde(default)]
    pub time_limit: Option<Spanned<f64>>,
}

/// The `[fit]` table: what `skg-solve fit SCENE` fits when its command line does not say
/// (read by the fit, `skg_core::fit`, which checks the entries; docs/fitting.md).
#[derive(Debug, Clone, Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
pub struct FitSpec {
    /// The free parameters, each `NAME`, `NAME>=LO`, `NAME<=HI` or `NAME in [LO, HI]`
    /// as `--free` takes them.
    #[serde(default)]
    pub free: Vec<Spanned<String>>,
    /// The data file (CSV), relative to the scene file's directory.
    #[serde(default)]
    pub data: Option<Spanned<String>>,
}

/// The value of a pass-through Ipopt option: integer, number or string, as Ipopt's
/// option has that type. An integer outside Ipopt's `int` range is a number.
#[derive(Debug, Clone, Serialize, PartialEq)]
#[serde(untagged)]
pub enum IpoptValue {
    /// An integer option.
    Int(i32),
    /// A numeric option.
    Num(f64),
    /// A string option.
    Str(String),
}

impl<'de> Deserialize<'de> for IpoptValue {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = IpoptValue;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("an integer, a number or a string in quotes (the type of the Ipopt option)")
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<IpoptValue, E> {
                Ok(i32::try_from(v).map_or(IpoptValue::Num(v as f64), IpoptValue::Int))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<IpoptValue, E> {
                Ok(i32::try_from(v).map_or(IpoptValue::Num(v as f64), IpoptValue::Int))
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<IpoptValue, E> {
                Ok(IpoptValue::Num(v))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<IpoptValue, E> {
                Ok(IpoptValue::Str(v.to_string()))
            }
        }
        deserializer.deserialize_any(Visitor)
    }
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
    /// `[fit]`: the free parameters and the data of `skg-solve fit SCENE`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fit: Option<FitSpec>,
    /// Path and source text, for error positions.
    #[serde(skip)]
    pub origin: Origin,
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

    /// Deserialize a scene built in code as a TOML table (Python's `skg.Scene(mapping)`).
    /// Its text is written by [`write_toml`] (one key per line) and parsed as a file's
    /// would be, so that it is validated alike and its provenance hashes that text;
    /// errors name the field (`<python>: coordinates[3].initial: …`, with `name` as the
    /// label in place of a file).
    pub fn from_table(table: &toml::Table, name: &str) -> Result<SceneFile, SceneError> {
        let generated = write_toml(table);
        let origin = Origin { path: name.to_string(), text: generated.text, fields: Some(generated.fields.into()) };
        let (mut file, origin): (SceneFile, Origin) = parse_origin(origin)?;
        file.origin = origin;
        Ok(file)
    }

    /// An error at a value of the file.
    pub(super) fn invalid<T>(&self, v: &Spanned<T>, message: impl Into<String>) -> SceneError {
        SceneError::Invalid { location: self.origin.locate_in(v, None), message: message.into() }
    }

    /// Error for an expression at a spanned string value.
    pub fn expression_error(&self, v: &Spanned<String>, key: &str, error: ParseError) -> SceneError {
        SceneError::Expression { location: self.origin.locate_in(v, Some(error.position)), key: key.to_string(), error: Box::new(error) }
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

    /// An error of the file as a whole (no single key is at fault).
    pub(super) fn toml_error(&self, message: String) -> SceneError {
        SceneError::Invalid { location: self.origin.whole(), message }
    }
}
