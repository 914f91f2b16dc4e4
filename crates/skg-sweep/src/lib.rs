//! Parameter sweeps: a sweep file (TOML) names a base scene and a grid of values; the
//! points of the grid are solved in worker processes, each worker running one point after
//! another ([`workers`]), and each is appended to `results.csv` as soon as it finishes.
//!
//! * **Grid expansion** ([`SweepFile::expand`]): each `[[grid]]` table is a Cartesian
//!   product of its axes (the first axis varies slowest); `[[points]]` tables are explicit
//!   points; `[peer]` adds the time-stepping reference integrator at a ladder of
//!   tolerances (the peer line of the work-precision chart). Points are numbered in that
//!   order; a point's **id** is a hash of its canonical string (axis names sorted,
//!   `name=value` joined by `;`), so it does not depend on the order of the file.
//! * **Before a run** ([`plan`]): the points this run owns, a rough time estimate and
//!   the line saying so; more than [`CONFIRM_ABOVE`] points are refused unless confirmed
//!   (the command line's `--yes`, the Python module's `yes=True`).
//! * **Workers** ([`workers`]): Debian's Ipopt/MUMPS is not thread-safe
//!   (docs/solver.md), so points run in child processes (`skg-solve sweep-worker
//!   WORK`), at most `jobs` at once, the points with the largest [`estimated_cost`]
//!   first. A worker runs one point after another, handed to it through its stdin, so
//!   points of equal structure ([`Expanded::structures`]) in a row share the process
//!   and, with the Newton backend, the symbolic LU analysis (`lu_analysis` column). A
//!   crash or a timeout costs only the point in flight; a fresh worker takes the next.
//!   A worker dies with the driver (`PR_SET_PDEATHSIG`), and Ctrl-C reaches the whole
//!   process group.
//! * **Results**: the driver alone appends to `results.csv`, one whole line per
//!   finished point, flushed and fsync'd, and holds the output directory's lock
//!   ([`output::OutputDir`]) meanwhile, so a second sweep into it is refused. On a rerun
//!   a trailing partial line (from a kill in the middle of a write) is cut off and points
//!   whose id is present are skipped: no row is lost or duplicated; with
//!   [`SweepOptions::retry_failed`] the rows of points that did not converge are removed
//!   first, so they run again.
//! * **Identity of the inputs**: rows carry the hashes of the base scene and of the
//!   reference file, `sweep.json` the [`RowSettings`]; a rerun with other inputs is
//!   refused ([`SweepOptions::new_results`] moves the old result set aside instead).
//! * **Shards**: `--shard k/n` keeps the points whose index is `k−1 mod n`; [`merge`]
//!   joins the shards' `results.csv` files (of one sweep, one input content and one
//!   schema) and refuses an incomplete set unless asked for a partial merge.
//!
//! **`results.csv`** is a plain CSV (one header line, no comments: `pd.read_csv` reads
//! it). Its columns ([`results_columns`]), in order:
//!
//! * `id`, `index`, `method` (`skg` or `ode`), `rtol` (the peer's tolerance), `nodes`,
//!   `operator`, `formulation`: the point and its resolved settings;
//! * one column per grid axis. A scene parameter's column holds the **number** the
//!   resolved scene has (`sigma = "1/110"` gives `0.00909090909090909`, the shortest text
//!   that reads back to the same double, as in every numeric column); a setting's column
//!   (`max_iter`, `hessian`, `backend`) holds the value as written. A parameter axis with at least
//!   one value written as an expression also gets the column **`<axis>_expr`**, right
//!   after it, with every value as written in the sweep file (`1/110`, and `0.005` for a
//!   plain number); an axis whose values are all plain numbers gets none;
//! * `converged` (`true`/`false`), `status` (the stable name of the [`PointStatus`]:
//!   `converged`, `not_verified`, `not_converged`, `error`, `crashed`, `timeout`),
//!   `solver_status` (the finishing backend's status name, Ipopt's or `Newton_…`,
//!   `ODE_Succeeded` for a peer point, empty when the solver did not finish), then
//!   `verification`, `verify_error`, `solved_as`, `iterations`, `wall_s`, `lu_analysis`
//!   (`computed` or `reused`: the Newton backend's symbolic LU analysis, made for this
//!   point or taken over from the worker's previous point of equal structure; empty
//!   when Newton did not run), `error_max`, `error_rms`, `error_column`,
//!   `energy_drift`, `energy_artifact` (empty unless the energy is conserved:
//!   [`skg_core::tune::conserves_energy`]), `artifacts`, `max_residual`, `message`;
//! * the provenance ([`Provenance`]): `skg_solve_version`, `schema_version` and
//!   `scene_hash` (`sha256:…` of the base scene file's content, as the worker read it),
//!   `reference_hash` (of the reference file's content; empty without one).
//!
//! [`Results::read`] refuses a file of another schema version (or one without the
//! `schema_version` column, written before it existed) with a message naming the file.
//!
//! **`sweep.json`**, beside `results.csv` ([`SweepInfo`]): the sweep's name, the sweep
//! file, the base scene, the provenance, the row settings, the number of points of the
//! whole sweep, the shard, the ids of this run's points and of every point.

#![warn(missing_docs)]
// Errors carry file:line:column text, as in the core modules.
#![allow(clippy::result_large_err)]

mod results;
pub mod shards;
pub mod slurm;
mod status;
pub mod workers;

pub use results::{
    csv_line, header_names, results_columns, results_row, Column, Provenance, Results, SchemaError, CUT_LINE, EXPR_SUFFIX, LEADING_COLUMNS,
    PROVENANCE_COLUMNS, RESULT_COLUMNS,
};
pub use status::{PointStatus, UnknownStatus};
pub use workers::{die_of, serve_points, stop_on_signals, stop_signal};

use std::collections::{BTreeMap, BTreeSet, HashSet, VecDeque};
use std::fmt;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use indexmap::IndexMap;
use serde::{Deserialize, Serialize};
use toml::Spanned;

use skg_core::check::{self, CheckOptions, Comparison, Table};
use skg_core::output;
use skg_core::sbp::{OperatorKind, ParseOperatorKindError};
use skg_core::scene::provenance;
use skg_core::scene::{
    parse_toml, read_toml, readable_number, Backend, Formulation, HessianMode, InitialVelocity, Location, Origin, Overrides,
    ParseBackendError, ParseFormulationError, ParseInitialVelocityError, Scene, SceneError, SceneFile, TomlError,
};

/// Errors of a sweep file, a results file or the sweep driver.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    /// A file could not be read.
    #[error("cannot read {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// `results.csv` could not be opened to append rows to it.
    #[error("cannot open {path} for appending: {source}")]
    Open {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// A file could not be written, cut back or flushed to disk (a full disk, …).
    #[error("cannot write {path}: {source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// A directory could not be created.
    #[error("cannot create directory {path}: {source}")]
    CreateDir {
        /// The directory.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// A file or directory could not be moved (`--new-results` moving earlier results aside).
    #[error("cannot move {from} to {to}: {source}")]
    Move {
        /// What was moved.
        from: PathBuf,
        /// Where to.
        to: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// Bad input at a place in a file (sweep file, or a row of a results file).
    #[error("{location}: {message}")]
    Invalid {
        /// File, line and column where known.
        location: Location,
        /// What is wrong.
        message: String,
    },
    /// The base scene, or the scene of one point (the base scene with the point's
    /// values), is invalid ([`SweepSceneError`]; boxed, to keep every result small). Its
    /// [`source`](std::error::Error::source) is the scene's own error, with its location
    /// in the scene file.
    #[error(transparent)]
    Scene(Box<SweepSceneError>),
    /// A value of a setting axis (`nodes`, `operator`, …) that is not a valid setting.
    #[error("{location}: {source}")]
    Axis {
        /// The table of the point in the sweep file.
        location: Location,
        /// What is wrong with the value.
        #[source]
        source: AxisError,
    },
    /// A results file of another schema version, or without the columns every results
    /// file has.
    #[error("{location}: {source}")]
    Schema {
        /// The results file, and the row's line for a row of another schema version.
        location: Location,
        /// What is wrong.
        #[source]
        source: SchemaError,
    },
    /// A `status` cell of a results file that is no point status.
    #[error("{location}: {source}")]
    Status {
        /// The results file, and the row's line where known.
        location: Location,
        /// The cell.
        #[source]
        source: UnknownStatus,
    },
    /// A results file that cannot be used as asked (layout, other sweep).
    #[error("{path}: {message}")]
    Results {
        /// The results file (or output directory).
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A worker process could not be started or waited for.
    #[error("cannot start a worker process ({exe}): {source}")]
    Spawn {
        /// The worker executable.
        exe: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// Writing `sweep.json`, a job file or `results.csv` failed.
    #[error(transparent)]
    Output(#[from] output::OutputError),
    /// More than [`CONFIRM_ABOVE`] points would run and the run was not confirmed.
    #[error("{plan}: more than {CONFIRM_ABOVE} points start only with --yes (or split the sweep with --shard)")]
    Unconfirmed {
        /// What the run would do ([`Plan::text`]).
        plan: String,
    },
    /// The driver received SIGTERM or SIGINT after [`stop_on_signals`]: it killed its
    /// workers and stopped with whole rows in results.csv.
    #[error(
        "stopped by signal {signal} ({}) after {recorded} new row(s); {results} holds whole rows only: run the same command again to resume",
        signal_name(*signal)
    )]
    Stopped {
        /// The signal.
        signal: i32,
        /// Rows this run appended before it stopped.
        recorded: usize,
        /// The results file.
        results: PathBuf,
    },
    /// The shards given to [`merge`] do not hold every point of the sweep.
    #[error(
        "the shards hold {present} of the sweep's {total} points{}; missing: {}. Run the missing shards, or merge what there is with --partial",
        if shards.is_empty() { String::new() } else { format!(" (shards given: {})", shards.join(", ")) },
        list_points(missing)
    )]
    Incomplete {
        /// Points present.
        present: usize,
        /// Points of the sweep.
        total: usize,
        /// The shards given (`k/n`).
        shards: Vec<String>,
        /// (index, id) of every missing point.
        missing: Vec<(usize, String)>,
    },
    /// The shards of a sharded directory ([`shards::merge_shards`]) do not hold every
    /// point of the sweep.
    #[error(
        "{}: the shards hold {present} of the sweep's {total} points, so nothing was merged; incomplete shards: {incomplete}{}. \
         Run the sweep again to run only these (they resume), or see `skg-solve status {}`",
        dir.display(),
        if missing.is_empty() { String::new() } else { format!("; missing: {}", list_points(missing)) },
        dir.display()
    )]
    IncompleteShards {
        /// The sharded directory.
        dir: PathBuf,
        /// Points present.
        present: usize,
        /// Points of the sweep.
        total: usize,
        /// The incomplete shards.
        incomplete: shards::Incomplete,
        /// (index, id) of every missing point (empty when no shard has results yet).
        missing: Vec<(usize, String)>,
    },
}

impl SweepError {
    /// The scene error this error wraps ([`SweepError::Scene`]), with its location in the
    /// scene file.
    pub fn scene_error(&self) -> Option<&SceneError> {
        match self {
            SweepError::Scene(e) => Some(&e.source),
            _ => None,
        }
    }

    fn scene(location: Location, of: SceneOf, source: SceneError) -> SweepError {
        SweepError::Scene(Box::new(SweepSceneError { location, of, source }))
    }
}

/// An invalid scene of a sweep: where the sweep file asks for it, which scene it is, and
/// the scene's own error.
#[derive(Debug, thiserror::Error)]
#[error("{location}: {of}: {source}")]
pub struct SweepSceneError {
    /// Where in the sweep file: the `scene` key, or the table of the point.
    pub location: Location,
    /// Which scene: the base scene or a point's.
    pub of: SceneOf,
    /// The scene's error (its location is in the scene file).
    #[source]
    pub source: SceneError,
}

/// Which scene of a sweep a [`SweepError::Scene`] is about.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SceneOf {
    /// The sweep file's `scene`, as written.
    Base,
    /// The base scene with the values of the point with this canonical text
    /// ([`Point::canonical`]).
    Point(String),
}

impl fmt::Display for SceneOf {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SceneOf::Base => f.write_str("base scene"),
            SceneOf::Point(p) => write!(f, "point {p}"),
        }
    }
}

/// A value of a setting axis of a sweep that is not a valid setting ([`Point::overrides`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum AxisError {
    /// `nodes` or `max_iter` is not a whole number.
    #[error("{axis} = {value}: expected a whole number")]
    WholeNumber {
        /// The axis.
        axis: &'static str,
        /// The value as written.
        value: String,
    },
    /// An unknown SBP operator.
    #[error("operator = {value}: {source}")]
    Operator {
        /// The value as written.
        value: String,
        /// The operator parser's error.
        source: ParseOperatorKindError,
    },
    /// An unknown formulation.
    #[error(transparent)]
    Formulation(#[from] ParseFormulationError),
    /// An unknown initial-velocity condition.
    #[error(transparent)]
    InitialVelocity(#[from] ParseInitialVelocityError),
    /// A verification tolerance that is not a positive number.
    #[error("verify_tol = {value}: expected a positive number")]
    VerifyTol {
        /// The value as written.
        value: String,
    },
    /// A Hessian mode other than `zero` and `exact`.
    #[error("hessian = {value}: expected `zero` or `exact`")]
    Hessian {
        /// The value as written.
        value: String,
    },
    /// An unknown backend.
    #[error(transparent)]
    Backend(#[from] ParseBackendError),
}

/// `SIGTERM`, `SIGINT` or `signal N`.
fn signal_name(signal: i32) -> String {
    match signal {
        libc::SIGTERM => "SIGTERM".into(),
        libc::SIGINT => "SIGINT".into(),
        s => format!("signal {s}"),
    }
}

fn read_err(path: &Path) -> impl FnOnce(std::io::Error) -> SweepError + '_ {
    move |source| SweepError::Read { path: path.to_path_buf(), source }
}

fn open_err(path: &Path) -> impl FnOnce(std::io::Error) -> SweepError + '_ {
    move |source| SweepError::Open { path: path.to_path_buf(), source }
}

fn write_err(path: &Path) -> impl FnOnce(std::io::Error) -> SweepError + '_ {
    move |source| SweepError::Write { path: path.to_path_buf(), source }
}

fn create_dir_err(path: &Path) -> impl FnOnce(std::io::Error) -> SweepError + '_ {
    move |source| SweepError::CreateDir { path: path.to_path_buf(), source }
}

/// One value in a grid: a number, an integer or a string (an expression, an operator
/// or formulation name).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(untagged)]
pub enum AxisValue {
    /// A whole number (`nodes = 64`).
    Int(i64),
    /// A number (`sigma = 0.005`).
    Num(f64),
    /// A string: an expression (`"1/110"`), an operator or formulation name.
    Str(String),
}

impl fmt::Display for AxisValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AxisValue::Int(i) => write!(f, "{i}"),
            AxisValue::Num(x) => write!(f, "{x:?}"),
            AxisValue::Str(s) => f.write_str(s.trim()),
        }
    }
}

/// A grid axis: one value or a list of values.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(untagged)]
pub enum AxisValues {
    /// A single value (`sigma = "1/110"`).
    One(AxisValue),
    /// A list of values (`nodes = [64, 128]`).
    Many(Vec<AxisValue>),
}

impl AxisValues {
    fn values(&self) -> Vec<AxisValue> {
        match self {
            AxisValues::One(v) => vec![v.clone()],
            AxisValues::Many(v) => v.clone(),
        }
    }
}

/// Where the errors of a point are measured against.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub enum ReferenceSpec {
    /// A reference CSV (`skg-solve reference`), compared by time.
    File(PathBuf),
    /// The scene's Lagrange–d'Alembert equations integrated on the point's own grid at
    /// a tight tolerance ([`skg_core::stepping::reference::regularized`], rtol = atol = 1e-12).
    Integrate,
}

/// `[sweep]`: what is swept and how results are judged.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SweepMeta {
    /// Base scene file, relative to the sweep file.
    pub scene: Spanned<String>,
    /// Name (default: the sweep file's name); a plain file name, since it names the
    /// default output directory `out/sweeps/<name>`.
    #[serde(default)]
    pub name: Option<Spanned<String>>,
    /// Reference to measure errors against: a CSV path relative to the sweep file, or
    /// `"integrate"`. Without it the error columns stay empty.
    #[serde(default)]
    pub reference: Option<Spanned<String>>,
    /// Columns compared with the reference (default: the scene's coordinates).
    #[serde(default)]
    pub compare: Option<Spanned<Vec<String>>>,
    /// Nodes at the end excluded from errors and the energy artifact (default 2: the
    /// benign boundary nodes, docs/solver.md).
    #[serde(default)]
    pub skip_last: Option<usize>,
    /// Tolerance on the energy artifact: above it a converged point counts as
    /// "converged with energy artifacts" (default 1e-5, relative; see [`skg_core::tune`]).
    #[serde(default)]
    pub artifact_tol: Option<Spanned<f64>>,
    /// Keep each point's `trajectory.csv` and `summary.json` under `points/<id>/`.
    #[serde(default)]
    pub keep_trajectories: bool,
    /// Let each point use the fallback ladder as `skg-solve SCENE` does (default false:
    /// a sweep measures the scene's own solve at every point).
    #[serde(default)]
    pub fallback: bool,
    /// Solve each point to the verification's tolerance as `skg-solve SCENE --refine`
    /// does: finer grids (and, unless the point or the scene names one, the operator)
    /// until it verifies (default false). A point's row then holds the grid and operator
    /// it ended on.
    #[serde(default)]
    pub refine: bool,
    /// Wall-time limit of one point in seconds: a worker still running then is killed and
    /// the point recorded as [`PointStatus::TimedOut`] (default: no limit).
    #[serde(default)]
    pub timeout: Option<Spanned<f64>>,
}

/// `[peer]`: the time-stepping reference integrator at a ladder of tolerances.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PeerSpec {
    /// Relative tolerances (the absolute tolerance is the same).
    pub tolerances: Vec<f64>,
    /// Output grid of the peer runs (default: the base scene's nodes).
    #[serde(default)]
    pub nodes: Option<usize>,
}

/// The sweep file as written.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    /// `[sweep]`.
    pub sweep: SweepMeta,
    /// Cartesian products (one per `[[grid]]` table).
    #[serde(default)]
    pub grid: Vec<Spanned<IndexMap<String, AxisValues>>>,
    /// Explicit points (one per `[[points]]` table).
    #[serde(default)]
    pub points: Vec<Spanned<IndexMap<String, AxisValue>>>,
    /// `[peer]`, the time-stepping ladder.
    #[serde(default)]
    pub peer: Option<Spanned<PeerSpec>>,
    /// Path and text of the sweep file, for error positions.
    #[serde(skip)]
    pub origin: Origin,
}

/// The most points one sweep file may expand to (a larger grid is refused before it is
/// materialized).
pub const MAX_POINTS: usize = 10_000_000;

/// Above this many points to run, a sweep starts only when confirmed (`--yes`).
pub const CONFIRM_ABOVE: usize = 10_000;

/// Axes that are not scene parameters.
pub const SETTING_AXES: &[&str] = &["nodes", "operator", "formulation", "initial_velocity", "hessian", "max_iter", "backend", "verify_tol"];

/// How a point is computed.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub enum Method {
    /// The SKG action solved by the scene's backend (Ipopt by default).
    Skg,
    /// The time-stepping reference integrator (DOP853, [`skg_core::stepping::reference::regularized`])
    /// at a relative tolerance (absolute tolerance the same).
    Ode {
        /// Relative (and absolute) tolerance.
        rtol: f64,
    },
}

impl Method {
    /// The `method` column: `skg` or `ode`.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Skg => "skg",
            Method::Ode { .. } => "ode",
        }
    }
}

/// One point of a sweep.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Point {
    /// Position in the expanded sweep (0-based).
    pub index: usize,
    /// Axis name → value as written (canonical text).
    pub values: Vec<(String, String)>,
    /// Axis name → value in the resolved scene, for the scene-parameter axes (`1/110` →
    /// 0.00909…), filled by [`SweepFile::expand`]. Not part of the id.
    #[serde(default)]
    pub evaluated: Vec<(String, f64)>,
    /// How the point is computed.
    pub method: Method,
}

impl Point {
    /// Canonical text: `method` first, then the axes sorted by name.
    pub fn canonical(&self) -> String {
        let mut parts = vec![match &self.method {
            Method::Skg => format!("method={}", self.method.name()),
            Method::Ode { rtol } => format!("method={};rtol={rtol:?}", self.method.name()),
        }];
        let sorted: BTreeMap<&str, &str> = self.values.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect();
        parts.extend(sorted.iter().map(|(k, v)| format!("{k}={v}")));
        parts.join(";")
    }

    /// Stable id: FNV-1a 64 of the canonical text, as 16 hex digits.
    pub fn id(&self) -> String {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for b in self.canonical().bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
        format!("{h:016x}")
    }

    /// The value of an axis as written, if the point sets it.
    pub fn value(&self, axis: &str) -> Option<&str> {
        self.values.iter().find(|(k, _)| k == axis).map(|(_, v)| v.as_str())
    }

    /// The value of a scene-parameter axis in the resolved scene (see [`Point::evaluated`]).
    pub fn evaluated(&self, axis: &str) -> Option<f64> {
        self.evaluated.iter().find(|(k, _)| k == axis).map(|&(_, v)| v)
    }

    /// The scene overrides this point stands for.
    pub fn overrides(&self) -> Result<Overrides, AxisError> {
        let mut ov = Overrides::default();
        for (k, v) in &self.values {
            let whole = |axis: &'static str| move |_| AxisError::WholeNumber { axis, value: v.clone() };
            match k.as_str() {
                "nodes" => ov.nodes = Some(v.parse().map_err(whole("nodes"))?),
                "operator" if v.trim().eq_ignore_ascii_case("auto") => ov.auto_operator = true,
                "operator" => ov.operator = Some(v.parse().map_err(|source| AxisError::Operator { value: v.clone(), source })?),
                "verify_tol" => {
                    let tol: f64 = v.trim().parse().map_err(|_| AxisError::VerifyTol { value: v.clone() })?;
                    if !(tol > 0.0 && tol.is_finite()) {
                        return Err(AxisError::VerifyTol { value: v.clone() });
                    }
                    ov.verify_tol = Some(tol);
                }
                "formulation" => ov.formulation = Some(v.parse::<Formulation>()?),
                "initial_velocity" => ov.initial_velocity = Some(v.parse::<InitialVelocity>()?),
                "hessian" => {
                    ov.hessian = Some(match v.to_ascii_lowercase().as_str() {
                        "zero" => HessianMode::Zero,
                        "exact" => HessianMode::Exact,
                        _ => return Err(AxisError::Hessian { value: v.clone() }),
                    })
                }
                "max_iter" => ov.max_iter = Some(v.parse().map_err(whole("max_iter"))?),
                "backend" => ov.backend = Some(v.parse::<Backend>()?),
                _ => ov.set.push((k.clone(), v.clone())),
            }
        }
        Ok(ov)
    }
}

/// A shard `k/n` (1-based k).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This shard's number, 1 ≤ k ≤ n.
    pub k: usize,
    /// The number of shards.
    pub n: usize,
}

/// A shard that is not `k/n` with 1 ≤ k ≤ n.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("bad shard `{input}`: expected k/n with 1 ≤ k ≤ n, e.g. 2/8")]
pub struct ParseShardError {
    /// The rejected input.
    pub input: String,
}

impl std::str::FromStr for Shard {
    type Err = ParseShardError;
    fn from_str(s: &str) -> Result<Self, ParseShardError> {
        let bad = || ParseShardError { input: s.to_string() };
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (k, n): (usize, usize) = (k.trim().parse().map_err(|_| bad())?, n.trim().parse().map_err(|_| bad())?);
        if n == 0 || k == 0 || k > n {
            return Err(bad());
        }
        Ok(Shard { k, n })
    }
}

impl Shard {
    /// Whether the point with this index belongs to the shard.
    pub fn contains(&self, index: usize) -> bool {
        index % self.n == self.k - 1
    }
}

/// The expanded sweep.
#[derive(Debug, Clone)]
pub struct Expanded {
    /// The points, in order (grids, explicit points, peer ladder).
    pub points: Vec<Point>,
    /// Rough relative cost of each point (see [`estimated_cost`]), by index.
    pub costs: Vec<f64>,
    /// Each point's structure key ([`structure_key`]), by index: points with equal keys
    /// are run one after the other by one worker where the order allows.
    pub structures: Vec<String>,
    /// Grid axes in order of first appearance.
    pub axes: Vec<String>,
    /// The scene-parameter axes with some value written as an expression (they get an
    /// `<axis>_expr` column), in the order of `axes`.
    pub expression_axes: Vec<String>,
    /// Identical points given twice (their later copies were dropped).
    pub duplicates: usize,
    /// SHA-256 of the base scene file's content (`sha256:…`).
    pub scene_hash: String,
    /// SHA-256 of the reference file's content, when errors are measured against a file.
    pub reference_hash: Option<String>,
}

impl Expanded {
    /// The columns of this sweep's `results.csv`.
    pub fn columns(&self) -> Vec<Column> {
        results_columns(&self.axes, &self.expression_axes)
    }
}

/// Whether an axis value as written is a plain number (not an expression).
fn is_plain_number(written: &str) -> bool {
    written.trim().parse::<f64>().is_ok()
}

/// The scene-parameter axes (in `axes` order) with some value that is not a plain number.
fn expression_axes(axes: &[String], points: &[Point]) -> Vec<String> {
    let written_as_expression =
        |axis: &str| points.iter().any(|p| p.evaluated(axis).is_some() && p.value(axis).is_some_and(|v| !is_plain_number(v)));
    axes.iter().filter(|a| written_as_expression(a)).cloned().collect()
}

/// Values of the scene-parameter axes of `point` in its resolved scene.
fn evaluated_parameters(point: &Point, scene: &Scene) -> Vec<(String, f64)> {
    point.values.iter().filter_map(|(axis, _)| scene.parameters.get(axis).map(|&v| (axis.clone(), v))).collect()
}

impl SweepFile {
    /// Read and deserialize a sweep file.
    pub fn load(path: &Path) -> Result<SweepFile, SweepError> {
        Self::from_toml(read_toml(path))
    }

    /// Deserialize a sweep file; `path` labels error messages and anchors relative paths.
    pub fn parse(text: &str, path: &str) -> Result<SweepFile, SweepError> {
        Self::from_toml(parse_toml(text, path))
    }

    fn from_toml(read: Result<(SweepFile, Origin), TomlError>) -> Result<SweepFile, SweepError> {
        match read {
            Ok((mut f, origin)) => {
                f.origin = origin;
                Ok(f)
            }
            Err(TomlError::Io { path, error }) => Err(SweepError::Read { path, source: error }),
            Err(TomlError::Parse { location, mut message }) => {
                // A table where an array of tables belongs (`[grid]` for `[[grid]]`):
                // the reader's type error, in serde's or the scene reader's words.
                if message.contains("expected a sequence") || message.contains("must be an array") {
                    message.push_str(" (write each grid as `[[grid]]` and each explicit point as `[[points]]`)");
                }
                Err(SweepError::Invalid { location, message })
            }
        }
    }

    fn dir(&self) -> PathBuf {
        Path::new(&self.origin.path).parent().map_or(PathBuf::from("."), Path::to_path_buf)
    }

    fn invalid<T>(&self, v: &Spanned<T>, message: impl Into<String>) -> SweepError {
        SweepError::Invalid { location: self.origin.locate_in(v, None), message: message.into() }
    }

    /// Location of `key = …` inside the table spanned by `table` (falls back to the
    /// table's own location).
    fn locate_key<T>(&self, table: &Spanned<T>, key: &str) -> Location {
        let start = table.span().start.min(self.origin.text.len());
        let end = table.span().end.min(self.origin.text.len()).max(start);
        let body = &self.origin.text[start..end];
        let mut offset = 0;
        for line in body.split_inclusive('\n') {
            let t = line.trim_start();
            let bare = t.strip_prefix(key).is_some_and(|r| r.trim_start().starts_with('='));
            let quoted = t.strip_prefix(&format!("\"{key}\"")).is_some_and(|r| r.trim_start().starts_with('='));
            if bare || quoted {
                return self.origin.locate(start + offset + (line.len() - t.len()));
            }
            offset += line.len();
        }
        self.origin.locate_in(table, None)
    }

    /// Path of the base scene.
    pub fn scene_path(&self) -> PathBuf {
        self.dir().join(self.sweep.scene.get_ref())
    }

    /// The sweep's name: `[sweep] name`, else the sweep file's name without `.toml`.
    pub fn name(&self) -> String {
        match &self.sweep.name {
            Some(name) => name.get_ref().clone(),
            None => Path::new(&self.origin.path).file_stem().map_or("sweep".into(), |s| s.to_string_lossy().into_owned()),
        }
    }

    /// Refuse a `[sweep] name` that is not a plain file name: it names the default
    /// output directory `out/sweeps/<name>`, which must not be the parent directory or
    /// lie outside.
    fn check_name(&self) -> Result<(), SweepError> {
        let Some(name) = &self.sweep.name else { return Ok(()) };
        let n = name.get_ref();
        let plain = !n.trim().is_empty() && n != "." && n != ".." && !n.contains(['/', '\\', '\0']);
        if plain {
            return Ok(());
        }
        Err(self.invalid(name, format!("sweep.name = {n:?} must be a plain file name (no `/`, not empty, not `.` or `..`): it names the output directory out/sweeps/<name>")))
    }

    /// Refuse `compare` columns that a trajectory of the base scene, or the reference
    /// file, does not have, before any point runs.
    fn check_compare_columns(&self, scene: &Scene) -> Result<(), SweepError> {
        let Some(compare) = &self.sweep.compare else { return Ok(()) };
        let produced = skg_core::discrete::trajectory::trajectory_header(scene);
        let reference = match self.reference() {
            Some(ReferenceSpec::File(p)) => Some((
                Table::read(&p).map_err(|e| self.invalid(self.sweep.reference.as_ref().expect("a file reference"), e.to_string()))?.columns,
                p,
            )),
            _ => None,
        };
        if compare.get_ref().is_empty() {
            return Err(self.invalid(compare, "sweep.compare is empty: name at least one column (default: the coordinates)"));
        }
        for c in compare.get_ref() {
            if c == "t" || !produced.contains(c) {
                let choices: Vec<&str> = produced.iter().skip(1).map(String::as_str).collect();
                return Err(self.invalid(
                    compare,
                    format!("sweep.compare: a trajectory of this scene has no column `{c}` (columns: {})", choices.join(", ")),
                ));
            }
            if let Some((columns, path)) = &reference {
                if !columns.contains(c) {
                    return Err(self.invalid(
                        compare,
                        format!("sweep.compare: the reference {} has no column `{c}` (columns: {})", path.display(), columns.join(", ")),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Where errors are measured against, if anywhere (`[sweep] reference`).
    pub fn reference(&self) -> Option<ReferenceSpec> {
        self.sweep.reference.as_ref().map(|r| {
            if r.get_ref().eq_ignore_ascii_case("integrate") {
                ReferenceSpec::Integrate
            } else {
                ReferenceSpec::File(self.dir().join(r.get_ref()))
            }
        })
    }

    /// End nodes left out of errors and the energy artifact (default 2).
    pub fn skip_last(&self) -> usize {
        self.sweep.skip_last.unwrap_or(2)
    }

    /// Tolerance on the energy artifact (default [`skg_core::tune::DEFAULT_ARTIFACT_TOL`]).
    pub fn artifact_tol(&self) -> f64 {
        self.sweep.artifact_tol.as_ref().map_or(skg_core::tune::DEFAULT_ARTIFACT_TOL, |t| *t.get_ref())
    }

    /// The number of points the file lists, counted without expanding anything: the
    /// product of each grid's axis lengths, the explicit points and the peer ladder's
    /// tolerances (identical points given twice count twice). `None` beyond `usize`.
    pub fn listed_points(&self) -> Option<usize> {
        let mut grid_points = self.grid.iter().map(|g| g.get_ref().values().map(|v| v.values().len()).try_fold(1usize, usize::checked_mul));
        let peer = self.peer.as_ref().map_or(0, |p| p.get_ref().tolerances.len());
        grid_points.try_fold(self.points.len().checked_add(peer)?, |sum, n| n.and_then(|n| sum.checked_add(n)))
    }

    /// Expand the grids, explicit points and peer ladder, and check every point against
    /// the base scene (parameter names, values, node counts) before anything runs.
    pub fn expand(&self) -> Result<Expanded, SweepError> {
        self.check_name()?;
        let base = SceneFile::load(&self.scene_path())
            .map_err(|e| SweepError::scene(self.origin.locate_in(&self.sweep.scene, None), SceneOf::Base, e))?;
        if let Some(tol) = &self.sweep.artifact_tol {
            if !(*tol.get_ref() > 0.0 && tol.get_ref().is_finite()) {
                return Err(
                    self.invalid(tol, format!("sweep.artifact_tol must be a positive number, got {}", readable_number(*tol.get_ref())))
                );
            }
        }
        if let Some(t) = &self.sweep.timeout {
            if !(*t.get_ref() > 0.0 && t.get_ref().is_finite()) {
                return Err(
                    self.invalid(t, format!("sweep.timeout must be a positive number of seconds, got {}", readable_number(*t.get_ref())))
                );
            }
        }
        let mut reference_hash = None;
        if let Some(ReferenceSpec::File(p)) = self.reference() {
            reference_hash = std::fs::read(&p).ok().map(|bytes| provenance::content_hash(&bytes));
            if !p.is_file() {
                let r = self.sweep.reference.as_ref().expect("reference given");
                return Err(self.invalid(
                    r,
                    format!(
                        "reference file {} does not exist (give a CSV written by `skg-solve reference`, or \"integrate\")",
                        p.display()
                    ),
                ));
            }
        }
        // (axis values, method, location in the sweep file) of each point, in order.
        type Raw = (Vec<(String, String)>, Method, Location);
        let mut raw: Vec<Raw> = Vec::new();
        let mut axes: Vec<String> = Vec::new();
        let check_axis = |name: &str, at: &dyn Fn(String) -> SweepError| -> Result<(), SweepError> {
            if SETTING_AXES.contains(&name) || base.parameters.contains_key(name) {
                Ok(())
            } else {
                let params: Vec<&str> = base.parameters.keys().map(String::as_str).collect();
                Err(at(format!(
                    "`{name}` is neither a setting ({}) nor a parameter of the base scene (parameters: {})",
                    SETTING_AXES.join(", "),
                    if params.is_empty() { "none".into() } else { params.join(", ") }
                )))
            }
        };
        let listed = self.listed_points();
        if listed.is_none_or(|n| n > MAX_POINTS) {
            return Err(SweepError::Invalid {
                location: self.origin.whole(),
                message: format!(
                    "the sweep has {} points, more than the {MAX_POINTS} one sweep file may have: split it into several sweep files",
                    listed.map_or("more than 2^64".to_string(), |n| n.to_string())
                ),
            });
        }
        for g in &self.grid {
            let mut combos: Vec<Vec<(String, String)>> = vec![Vec::new()];
            for (axis, values) in g.get_ref() {
                let at = |m: String| SweepError::Invalid { location: self.locate_key(g, axis), message: format!("[[grid]]: {m}") };
                check_axis(axis, &at)?;
                let vals = values.values();
                if vals.is_empty() {
                    return Err(at(format!("axis `{axis}` has no values")));
                }
                if !axes.contains(axis) {
                    axes.push(axis.clone());
                }
                combos = combos
                    .into_iter()
                    .flat_map(|c| {
                        vals.iter().map(move |v| {
                            let mut c = c.clone();
                            c.push((axis.clone(), v.to_string()));
                            c
                        })
                    })
                    .collect();
            }
            let loc = self.origin.locate_in(g, None);
            raw.extend(combos.into_iter().map(|c| (c, Method::Skg, loc.clone())));
        }
        for p in &self.points {
            let mut c = Vec::new();
            for (axis, v) in p.get_ref() {
                let at = |m: String| SweepError::Invalid { location: self.locate_key(p, axis), message: format!("[[points]]: {m}") };
                check_axis(axis, &at)?;
                if !axes.contains(axis) {
                    axes.push(axis.clone());
                }
                c.push((axis.clone(), v.to_string()));
            }
            raw.push((c, Method::Skg, self.origin.locate_in(p, None)));
        }
        if let Some(spanned) = &self.peer {
            let peer = spanned.get_ref();
            for &rtol in &peer.tolerances {
                if !(rtol > 0.0 && rtol < 1.0) {
                    return Err(SweepError::Invalid {
                        location: self.locate_key(spanned, "tolerances"),
                        message: format!("peer.tolerances: {rtol} is not in (0, 1)"),
                    });
                }
                let mut c = Vec::new();
                if let Some(n) = peer.nodes {
                    c.push(("nodes".to_string(), n.to_string()));
                }
                raw.push((c, Method::Ode { rtol }, self.origin.locate_in(spanned, None)));
            }
        }
        if raw.is_empty() {
            return Err(SweepError::Invalid {
                location: self.origin.whole(),
                message: "the sweep has no points: add a [[grid]], [[points]] or [peer] table".into(),
            });
        }
        let mut points = Vec::new();
        let mut costs = Vec::new();
        let mut structures = Vec::new();
        let mut seen = HashSet::new();
        // The available memory, read once for all points (not once per point).
        let limit = skg_core::memory::available_bytes();
        use skg_core::memory;
        let mut duplicates = 0;
        for (values, method, loc) in raw {
            let mut p = Point { index: points.len(), values, evaluated: Vec::new(), method };
            // Validate by resolving the scene with the point's overrides (cheap: no model).
            let ov = p.overrides().map_err(|source| SweepError::Axis { location: loc.clone(), source })?;
            let scene_of_point = |e| SweepError::scene(loc.clone(), SceneOf::Point(p.canonical()), e);
            let scene = base.clone().resolve(&ov).map_err(scene_of_point)?;
            let memory = match p.method {
                Method::Skg => memory::check_against(&scene, "the solve", scene.nodes, memory::solve_bytes(&scene), limit),
                Method::Ode { .. } => {
                    memory::check_against(&scene, "the reference", scene.nodes, memory::reference_bytes(&scene, scene.nodes), limit)
                }
            };
            memory.map_err(scene_of_point)?;
            if seen.insert(p.id()) {
                p.evaluated = evaluated_parameters(&p, &scene);
                costs.push(estimated_cost(&scene, &p.method));
                structures.push(structure_key(&scene, &p.method));
                points.push(p);
            } else {
                duplicates += 1;
            }
        }
        let first = base
            .clone()
            .resolve(&points[0].overrides().unwrap_or_default())
            .map_err(|e| SweepError::scene(self.origin.whole(), SceneOf::Point(points[0].canonical()), e))?;
        self.check_compare_columns(&first)?;
        let expression_axes = expression_axes(&axes, &points);
        let expanded = Expanded {
            points,
            costs,
            structures,
            axes,
            expression_axes,
            duplicates,
            scene_hash: base.origin.content_hash(),
            reference_hash,
        };
        self.check_column_names(&expanded.columns())?;
        Ok(expanded)
    }

    /// Refuse axes whose column would share its name with another column of
    /// results.csv (e.g. a parameter `sigma_expr` beside the expressions of `sigma`).
    fn check_column_names(&self, columns: &[Column]) -> Result<(), SweepError> {
        let mut seen = HashSet::new();
        for name in header_names(columns) {
            if !seen.insert(name.clone()) {
                return Err(SweepError::Invalid {
                    location: self.origin.whole(),
                    message: format!("two columns of results.csv would be called `{name}`: rename that scene parameter"),
                });
            }
        }
        Ok(())
    }
}

/// Rough relative cost of a point, used only to start the expensive points first (so
/// that a sweep does not end with one long point running alone): N × the operator's
/// stencil width × 2 for the full formulation; a time-stepping peer point counts N/10.
pub fn estimated_cost(scene: &Scene, method: &Method) -> f64 {
    let n = scene.nodes as f64;
    match method {
        Method::Ode { .. } => n / 10.0,
        Method::Skg => {
            let width = match scene.operator {
                OperatorKind::Sbp121 => 1.0,
                OperatorKind::Sbp242 | OperatorKind::Sbp121Ad => 2.0,
                OperatorKind::Sbp363 | OperatorKind::Sbp484 | OperatorKind::Sbp242Ad => 3.0,
                OperatorKind::Sbp363Ad | OperatorKind::Sbp484Ad => 4.0,
            };
            let full = if scene.formulation == Formulation::Full { 2.0 } else { 1.0 };
            n * width * full
        }
    }
}

/// What decides the sparsity structure of a point's system (the same base scene
/// throughout): the method, node count, operator, formulation, initial velocity condition
/// and backend. Points with
/// equal keys usually have equal Jacobian structures (a parameter value that makes a
/// term vanish can still change it: the solver compares the structures themselves).
pub fn structure_key(scene: &Scene, method: &Method) -> String {
    match method {
        Method::Ode { .. } => "ode".into(),
        Method::Skg => format!(
            "skg N={} {} {} {} {}",
            scene.nodes,
            scene.operator.name(),
            scene.formulation,
            scene.initial_velocity,
            scene.solver.backend
        ),
    }
}

/// Seconds of one worker per unit of [`estimated_cost`], and per point (process start,
/// scene setup): a rough fit to the release-build timings of docs/benchmarks.md. It
/// gives 0.08 s for the tumbler at N = 256 (measured: 0.01 s plus the process start),
/// 3.3 s at N = 16384 (1.5 s) and 0.85 s for the rolling disk at N = 4096 (1.7 s: the
/// cost of a scene with more unknowns per node grows faster), so within a factor of
/// about 2 for the shipped scenes: enough to tell minutes from days.
const SECONDS_PER_COST: f64 = 1.0e-4;
const SECONDS_PER_POINT: f64 = 0.03;

/// A rough estimate of the wall time of running `points` with `jobs` workers (only to
/// tell the user what a sweep will take before it starts).
pub fn estimated_wall_s(expanded: &Expanded, points: &[&Point], jobs: usize) -> f64 {
    let serial: f64 = points.iter().map(|p| SECONDS_PER_POINT + SECONDS_PER_COST * expanded.costs[p.index]).sum();
    serial / jobs.max(1) as f64
}

/// A sweep's output directory when none is given: `out/sweeps/<name>`.
pub fn default_out_dir(file: &SweepFile) -> PathBuf {
    PathBuf::from("out/sweeps").join(file.name())
}

/// Worker processes when no number is given: one per core.
pub fn default_jobs() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// What a run of a sweep will do, known before it starts ([`plan`]).
#[derive(Debug)]
pub struct Plan {
    /// The sweep's points, for [`run_sweep`].
    pub expanded: Expanded,
    /// A rough estimate of the run's wall time in seconds ([`estimated_wall_s`]).
    pub estimate_s: f64,
    /// One line for the user: the points, the estimate, where the results go.
    pub text: String,
}

/// Expand a sweep and say what a run with `opts` will do. More than [`CONFIRM_ABOVE`]
/// points are refused ([`SweepError::Unconfirmed`]) unless `confirmed`.
pub fn plan(file: &SweepFile, opts: &SweepOptions, confirmed: bool) -> Result<Plan, SweepError> {
    // Count first: a sweep too large to start unconfirmed is refused at once, not after
    // every point's scene was resolved and its memory checked (30 s for 10⁶ points).
    if let (false, Some(listed)) = (confirmed, file.listed_points()) {
        let mine = opts.shard.map_or(listed, |s| listed / s.n + usize::from(s.k - 1 < listed % s.n));
        if mine > CONFIRM_ABOVE && listed <= MAX_POINTS {
            let text = format!(
                "{}: {mine} points{} as listed (not yet checked), roughly at least {} with {} worker(s)",
                file.name(),
                opts.shard.map_or(String::new(), |s| format!(" in shard {}/{} of {listed}", s.k, s.n)),
                duration_text(SECONDS_PER_POINT * mine as f64 / opts.jobs.max(1) as f64),
                opts.jobs.max(1)
            );
            return Err(SweepError::Unconfirmed { plan: text });
        }
    }
    let expanded = file.expand()?;
    let mine: Vec<&Point> = expanded.points.iter().filter(|p| opts.shard.is_none_or(|s| s.contains(p.index))).collect();
    let estimate_s = estimated_wall_s(&expanded, &mine, opts.jobs);
    let text = format!(
        "{}: {} points{}, roughly {} with {} worker(s) (points already in {} are skipped)",
        file.name(),
        mine.len(),
        opts.shard.map_or(String::new(), |s| format!(" in shard {}/{} of {}", s.k, s.n, expanded.points.len())),
        duration_text(estimate_s),
        opts.jobs.max(1),
        opts.out_dir.join("results.csv").display()
    );
    if mine.len() > CONFIRM_ABOVE && !confirmed {
        return Err(SweepError::Unconfirmed { plan: text });
    }
    Ok(Plan { expanded, estimate_s, text })
}

/// A duration in seconds as `12 s`, `3.5 min` or `2.1 h`.
fn duration_text(s: f64) -> String {
    if s < 120.0 {
        format!("{s:.0} s")
    } else if s < 7200.0 {
        format!("{:.1} min", s / 60.0)
    } else {
        format!("{:.1} h", s / 3600.0)
    }
}

// ---------------------------------------------------------------------------------------
// Worker side.

/// What a worker process is asked to do.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Job {
    /// The base scene file (absolute path).
    pub scene: PathBuf,
    /// The point to compute.
    pub point: Point,
    /// Where errors are measured against, if anywhere.
    pub reference: Option<ReferenceSpec>,
    /// Columns compared with the reference (None: the scene's coordinates).
    pub compare: Option<Vec<String>>,
    /// End nodes left out of errors and the energy artifact.
    pub skip_last: usize,
    /// Where to keep trajectory.csv and summary.json (None: not kept).
    pub keep_dir: Option<PathBuf>,
    /// Whether the point may use the fallback ladder.
    pub fallback: bool,
    /// Whether the point is solved to its tolerance (`[sweep] refine`).
    #[serde(default)]
    pub refine: bool,
}

/// What a worker reports about one point (the columns of its row in results.csv).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Record {
    /// How the point ended.
    pub status: PointStatus,
    /// The solver's own status name: the finishing backend's (Ipopt's `Solve_Succeeded`,
    /// `Maximum_Iterations_Exceeded`, …, or `Newton_…`) or `ODE_Succeeded` for the
    /// time-stepping peer;
    /// empty when the solver did not finish.
    pub solver_status: String,
    /// Iterations of the backend that finished.
    pub iterations: Option<usize>,
    /// Wall time of the computation inside the worker (scene setup, guess, solve).
    pub wall_s: Option<f64>,
    /// The Newton backend's symbolic LU analysis: `computed` for this point, `reused`
    /// from the worker's previous solve of equal structure, empty when Newton did not
    /// run ([`skg_core::solve::backend::NewtonReport::lu_analysis`]).
    #[serde(default)]
    pub lu_analysis: String,
    /// Node count of the resolved scene.
    pub nodes: Option<usize>,
    /// SBP operator of the resolved scene (SKG points).
    pub operator: Option<String>,
    /// Formulation of the resolved scene (SKG points).
    pub formulation: Option<String>,
    /// Largest max-abs error against the reference over the compared columns.
    pub error_max: Option<f64>,
    /// RMS error of that column.
    pub error_rms: Option<f64>,
    /// The column with the largest error.
    pub error_column: Option<String>,
    /// max |E_k − E_1| over all but the last two nodes.
    pub energy_drift: Option<f64>,
    /// The relative energy artifact ([`skg_core::tune::energy_artifact`]).
    pub energy_artifact: Option<f64>,
    /// Unscaled max residual of the square system.
    pub max_residual: Option<f64>,
    /// SHA-256 of the base scene file as the worker read it (None: not read).
    pub scene_hash: Option<String>,
    /// The verification verdict of a converged SKG point (`passed`, `failed`,
    /// `unverified`), empty otherwise.
    #[serde(default)]
    pub verification: String,
    /// Its max |q − q_reference| against time stepping of the same scene.
    #[serde(default)]
    pub verify_error: Option<f64>,
    /// How the reported trajectory covered the span (`global`, or `windows L s`).
    #[serde(default)]
    pub solved_as: String,
    /// Warnings and errors.
    pub message: String,
}

impl Record {
    /// A record with this status and nothing measured yet.
    pub fn new(status: PointStatus, message: String) -> Record {
        Record {
            status,
            solver_status: String::new(),
            iterations: None,
            wall_s: None,
            lu_analysis: String::new(),
            nodes: None,
            operator: None,
            formulation: None,
            error_max: None,
            error_rms: None,
            error_column: None,
            energy_drift: None,
            energy_artifact: None,
            max_residual: None,
            scene_hash: None,
            verification: String::new(),
            verify_error: None,
            solved_as: String::new(),
            message,
        }
    }
}

/// Run one point in this process (the body of `skg-solve sweep-worker`).
pub fn run_job(job: &Job) -> Record {
    match run_job_inner(job) {
        Ok(r) => r,
        Err(e) => Record::new(PointStatus::Error, skg_core::error_text(&e)),
    }
}

/// Why one point could not be computed (the message of its `error` row), or why its
/// errors against the reference could not be measured.
#[derive(Debug, thiserror::Error)]
enum PointError {
    #[error(transparent)]
    Axis(#[from] AxisError),
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Solve(#[from] skg_core::solve::SolveError),
    #[error(transparent)]
    Reference(#[from] skg_core::stepping::reference::ReferenceError),
    #[error(transparent)]
    Check(#[from] skg_core::check::CheckError),
    #[error(transparent)]
    Output(#[from] output::OutputError),
}

fn run_job_inner(job: &Job) -> Result<Record, PointError> {
    let mut ov = job.point.overrides()?;
    ov.refine |= job.refine;
    let start = Instant::now();
    let file = SceneFile::load(&job.scene)?;
    let scene_hash = file.origin.content_hash();
    let mut scene = file.resolve(&ov)?;
    scene.solver.fallback &= job.fallback;
    let mut rec = Record { nodes: Some(scene.nodes), scene_hash: Some(scene_hash), ..Record::new(PointStatus::Error, String::new()) };
    let compare_cols = job.compare.clone().unwrap_or_else(|| scene.coordinates.clone());
    let (trajectory, ode_csv) = match job.point.method {
        Method::Skg => {
            rec.operator = Some(scene.operator.name().to_string());
            rec.formulation = Some(scene.formulation.to_string());
            let mut outcome = skg_core::solve::solve_scene(&scene)?;
            rec.wall_s = Some(start.elapsed().as_secs_f64());
            if outcome.refinement.is_some() {
                // The grid and operator the solve ended on, for the row and the errors.
                scene.nodes = outcome.settings.nodes;
                scene.operator = outcome.settings.operator.parse().unwrap_or(scene.operator);
                scene.initial_velocity = outcome.settings.initial_velocity;
                rec.nodes = Some(scene.nodes);
                rec.operator = Some(outcome.settings.operator.clone());
            }
            rec.status = match (outcome.converged(), outcome.trusted()) {
                (true, true) => PointStatus::Converged,
                (true, false) => PointStatus::NotVerified,
                (false, _) => PointStatus::NotConverged,
            };
            rec.solver_status = outcome.status.solver().name().to_string();
            if outcome.converged() {
                rec.verification = outcome.verification.status.to_string();
                rec.verify_error = outcome.verification.max_error;
            }
            rec.solved_as = match outcome.method {
                skg_core::solve::Method::Global => "global".into(),
                skg_core::solve::Method::Windows { length, .. } => format!("windows {length:.4} s"),
            };
            rec.iterations = Some(outcome.iterations);
            rec.lu_analysis = outcome.backend.newton.as_ref().map_or("", |n| n.lu_analysis()).to_string();
            let d = &outcome.diagnostics;
            rec.energy_drift = Some(d.energy_drift);
            rec.max_residual = Some(d.max_residual);
            rec.message = outcome.warnings.join(" | ");
            if let Some(dir) = &job.keep_dir {
                output::write_outcome(dir, &mut outcome, &scene)?;
            }
            (outcome.trajectory, None)
        }
        Method::Ode { rtol } => {
            let (times, _) = skg_core::solve::grid(&scene);
            let opts = skg_core::stepping::reference::ReferenceOptions { rtol, atol: rtol };
            let r = skg_core::stepping::reference::regularized(&scene, &times, &opts)?;
            rec.wall_s = Some(start.elapsed().as_secs_f64());
            rec.status = PointStatus::Converged;
            rec.solver_status = "ODE_Succeeded".into();
            (r.trajectory, Some(format!("time stepping, rtol {rtol:e}")))
        }
    };
    let model = skg_core::model::Model::build(&scene)?;
    if skg_core::tune::conserves_energy(&scene, &model) {
        rec.energy_artifact = Some(skg_core::tune::energy_artifact(&scene, &trajectory, job.skip_last).value);
    }
    let solution = Table::of_trajectory(&scene, &trajectory);
    if let Some(r) = &job.reference {
        match reference_errors(&scene, r, &solution, &compare_cols, job.skip_last) {
            Ok(c) => {
                rec.error_max = Some(c.max_abs);
                rec.error_rms = c.columns.iter().find(|e| e.column == c.worst_column).map(|e| e.rms);
                rec.error_column = Some(c.worst_column);
            }
            Err(e) => {
                if !rec.message.is_empty() {
                    rec.message.push_str(" | ");
                }
                rec.message.push_str(&format!("reference comparison failed: {}", skg_core::error_text(&e)));
            }
        }
    }
    if let (Some(dir), Some(comment)) = (&job.keep_dir, ode_csv) {
        output::write_csv(&dir.join("trajectory.csv"), Some(&comment), &solution.columns, &solution.rows)?;
    }
    Ok(rec)
}

/// Errors of a solution against the sweep's reference on `columns`, the last
/// `skip_last` nodes excluded (errors go into the record's message, never abort the
/// point).
fn reference_errors(
    scene: &Scene,
    reference: &ReferenceSpec,
    solution: &Table,
    columns: &[String],
    skip_last: usize,
) -> Result<Comparison, PointError> {
    let reference = match reference {
        ReferenceSpec::File(p) => Table::read(p)?,
        ReferenceSpec::Integrate => {
            let r = skg_core::stepping::reference::regularized(
                scene,
                &solution.times(),
                &skg_core::stepping::reference::ReferenceOptions::default(),
            )?;
            Table::of_trajectory(scene, &r.trajectory)
        }
    };
    let opts = CheckOptions { skip_last, columns: Some(columns.to_vec()) };
    Ok(check::compare(solution, &reference, &opts)?)
}

// ---------------------------------------------------------------------------------------
// Driver.

/// Options of [`run_sweep`].
#[derive(Debug, Clone)]
pub struct SweepOptions {
    /// Output directory (results.csv, sweep.json, points/).
    pub out_dir: PathBuf,
    /// Worker processes at once.
    pub jobs: usize,
    /// Run only this shard's points.
    pub shard: Option<Shard>,
    /// The executable that runs `sweep-worker WORK` (the skg-solve binary, [`workers`]).
    pub worker_exe: PathBuf,
    /// Show a progress bar (hidden anyway when stderr is not a terminal).
    pub progress: bool,
    /// Run again the points whose rows say they did not converge (crashed, timed out,
    /// failed): their rows are replaced.
    pub retry_failed: bool,
    /// Start a new result set: move the output directory's results (results.csv,
    /// sweep.json, points/) into `superseded-<unix time>/` first.
    pub new_results: bool,
}

/// Summary of a sweep run.
#[derive(Debug, Clone, Default)]
pub struct SweepReport {
    /// Points of the whole sweep.
    pub total: usize,
    /// Points of this shard (all points without a shard).
    pub in_shard: usize,
    /// Already in results.csv when the run started.
    pub skipped: usize,
    /// Points computed by this run.
    pub ran: usize,
    /// Points of this run that did not converge (any status but converged).
    pub failed: usize,
    /// Identical points given twice in the sweep file (run once).
    pub duplicates: usize,
    /// The results file.
    pub results: PathBuf,
    /// Wall time of the run in seconds.
    pub wall_s: f64,
    /// Where the previous results went (`--new-results`).
    pub superseded: Option<PathBuf>,
}

/// The settings of `[sweep]` that change the values of a row (recorded in `sweep.json`;
/// a resumed run with other settings is refused).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RowSettings {
    /// `reference` as written.
    pub reference: Option<String>,
    /// `compare` as written.
    pub compare: Option<Vec<String>>,
    /// `skip_last`, resolved.
    pub skip_last: usize,
    /// `artifact_tol`, resolved.
    pub artifact_tol: f64,
}

/// `sweep.json`, written beside results.csv: what was swept, from which scene content,
/// by which skg-solve (read by [`merge`] to find missing points).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SweepInfo {
    /// The sweep's name.
    pub name: String,
    /// The sweep file as given.
    pub sweep_file: String,
    /// The base scene file.
    pub scene: String,
    /// skg-solve version, schema version and the base scene's content hash.
    #[serde(flatten)]
    pub provenance: Provenance,
    /// Points of the whole sweep.
    pub total_points: usize,
    /// `k/n` when run as a shard.
    pub shard: Option<String>,
    /// The settings that change a row's values.
    pub settings: RowSettings,
    /// Ids of this run's points (the shard's, or all).
    pub ids: Vec<String>,
    /// Ids of every point of the whole sweep, in index order (what [`merge`] checks for
    /// completeness).
    pub all_ids: Vec<String>,
}

impl SweepInfo {
    /// Read `sweep.json` from a results directory.
    pub fn read(dir: &Path) -> Result<SweepInfo, SweepError> {
        let path = dir.join("sweep.json");
        let text = std::fs::read_to_string(&path).map_err(read_err(&path))?;
        serde_json::from_str(&text).map_err(|e| SweepError::Results { path, message: format!("not a sweep.json of this skg-solve: {e}") })
    }
}

impl SweepFile {
    /// The settings of this file that change a row's values.
    pub fn row_settings(&self) -> RowSettings {
        RowSettings {
            reference: self.sweep.reference.as_ref().map(|r| r.get_ref().clone()),
            compare: self.sweep.compare.as_ref().map(|c| c.get_ref().clone()),
            skip_last: self.skip_last(),
            artifact_tol: self.artifact_tol(),
        }
    }
}

/// Refuse to resume into `dir` when its `sweep.json` (if any) records other row settings.
fn check_row_settings(dir: &Path, settings: &RowSettings) -> Result<(), SweepError> {
    if !dir.join("sweep.json").is_file() {
        return Ok(());
    }
    let old = SweepInfo::read(dir)?;
    if old.settings == *settings {
        return Ok(());
    }
    Err(SweepError::Results {
        path: dir.join("sweep.json"),
        message: format!(
            "the results here were computed with other [sweep] settings ({}; now {}): restore them, use another output \
             directory, or start a new result set with --new-results",
            serde_json::to_string(&old.settings).unwrap_or_default(),
            serde_json::to_string(settings).unwrap_or_default()
        ),
    })
}

/// Move the results of `dir` (results.csv, sweep.json, points/) into
/// `dir/superseded-<unix time>/`; returns that directory if there was anything to move.
fn supersede_results(dir: &Path) -> Result<Option<PathBuf>, SweepError> {
    let present: Vec<&str> = ["results.csv", "sweep.json", "points"].into_iter().filter(|n| dir.join(n).exists()).collect();
    if present.is_empty() {
        return Ok(None);
    }
    let secs = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs());
    let target = dir.join(format!("superseded-{secs}"));
    std::fs::create_dir_all(&target).map_err(create_dir_err(&target))?;
    for name in present {
        let (from, to) = (dir.join(name), target.join(name));
        std::fs::rename(&from, &to).map_err(|source| SweepError::Move { from, to, source })?;
    }
    Ok(Some(target))
}

/// Run (or resume) a sweep whose points `expanded` are ([`SweepFile::expand`]).
pub fn run_sweep(file: &SweepFile, expanded: &Expanded, opts: &SweepOptions) -> Result<SweepReport, SweepError> {
    let started = Instant::now();
    let columns = expanded.columns();
    let provenance = Provenance::current(expanded.scene_hash.clone(), expanded.reference_hash.clone());
    let dir = &opts.out_dir;
    let _lock = output::OutputDir::lock(dir)?;
    if dir.join(shards::LAYOUT_FILE).exists() {
        return Err(SweepError::Results {
            path: dir.clone(),
            message: format!(
                "is the directory of a sweep split into shards ({}): its results.csv is written only by the merge of \
                 its shards. Run it as it was started (`skg-solve sweep FILE --slurm -o DIR`, or skg.sweep(..., \
                 executor=...)), see `skg-solve status DIR`, or use another output directory",
                shards::LAYOUT_FILE
            ),
        });
    }
    let superseded = if opts.new_results { supersede_results(dir)? } else { None };
    let settings = file.row_settings();
    check_row_settings(dir, &settings)?;
    // Worker files left by an interrupted run are stale: start from an empty .work.
    let work = dir.join(".work");
    let _ = std::fs::remove_dir_all(&work);
    std::fs::create_dir_all(&work).map_err(create_dir_err(&work))?;
    let results_path = dir.join("results.csv");
    let (mut results, done) = results::open_results(&results_path, &header_names(&columns), &provenance, opts.retry_failed)?;

    let mine: Vec<&Point> = expanded.points.iter().filter(|p| opts.shard.is_none_or(|s| s.contains(p.index))).collect();
    let info = SweepInfo {
        name: file.name(),
        sweep_file: file.origin.path.clone(),
        scene: file.scene_path().display().to_string(),
        provenance: provenance.clone(),
        total_points: expanded.points.len(),
        shard: opts.shard.map(|s| format!("{}/{}", s.k, s.n)),
        settings,
        ids: mine.iter().map(|p| p.id()).collect(),
        all_ids: expanded.points.iter().map(Point::id).collect(),
    };
    output::write_json(&dir.join("sweep.json"), &info)?;
    // Largest first, equal structures together (stable: the file's order otherwise);
    // rows carry their index.
    let mut todo: Vec<Point> = mine.iter().filter(|p| !done.contains(&p.id())).map(|&p| p.clone()).collect();
    let (costs, structures) = (&expanded.costs, &expanded.structures);
    todo.sort_by(|a, b| costs[b.index].total_cmp(&costs[a.index]).then_with(|| structures[a.index].cmp(&structures[b.index])));
    let mut queue: VecDeque<Point> = todo.into();
    let mut report = SweepReport {
        total: expanded.points.len(),
        in_shard: mine.len(),
        skipped: mine.len() - queue.len(),
        duplicates: expanded.duplicates,
        results: results_path.clone(),
        superseded,
        ..SweepReport::default()
    };
    let bar = progress_bar(opts.progress, mine.len(), report.skipped);
    let artifact_tol = file.artifact_tol();
    let reference = file.reference();
    let scene_path = std::path::absolute(file.scene_path()).unwrap_or(file.scene_path());
    let job_of = |point: Point| Job {
        scene: scene_path.clone(),
        keep_dir: file.sweep.keep_trajectories.then(|| dir.join("points").join(point.id())),
        point,
        reference: reference.clone(),
        compare: file.sweep.compare.as_ref().map(|c| c.get_ref().clone()),
        skip_last: file.skip_last(),
        fallback: file.sweep.fallback,
        refine: file.sweep.refine,
    };
    let mut pool = workers::Pool::new(&opts.worker_exe, &work, opts.jobs, file.sweep.timeout.as_ref().map(|t| *t.get_ref()));
    // For the rows of points whose worker crashed or timed out (see fill_point_settings).
    let base = SceneFile::load(&scene_path).ok();
    loop {
        if let Some(signal) = stop_signal() {
            // Every row written is whole; the points in flight are lost with their workers.
            drop(pool);
            bar.finish_and_clear();
            return Err(SweepError::Stopped { signal, recorded: report.ran, results: results_path });
        }
        while pool.hand_out(&mut queue, expanded, job_of)? {}
        if queue.is_empty() {
            pool.close_idle();
            if pool.busy() == 0 {
                break;
            }
        }
        std::thread::sleep(Duration::from_millis(5));
        for (point, mut rec) in pool.finished()? {
            fill_point_settings(&mut rec, &point, base.as_ref());
            let line = csv_line(&results_row(&columns, &point, &rec, artifact_tol, &provenance));
            results::append(&mut results, &results_path, &line)?;
            report.ran += 1;
            if !rec.status.is_converged() {
                report.failed += 1;
                bar.set_message(format!("{} failed", report.failed));
            }
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    let _ = std::fs::remove_dir(&work);
    report.wall_s = started.elapsed().as_secs_f64();
    Ok(report)
}

/// The progress bar of a run over `len` points of which `done` are already done.
fn progress_bar(visible: bool, len: usize, done: usize) -> indicatif::ProgressBar {
    let bar = if visible { indicatif::ProgressBar::new(len as u64) } else { indicatif::ProgressBar::hidden() };
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} points, {msg}, {elapsed} elapsed, ETA {eta}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_position(done as u64);
    bar.reset_eta();
    bar.set_message("0 failed");
    bar
}

// ---------------------------------------------------------------------------------------
// Merge.

/// Summary of [`merge`].
#[derive(Debug, Clone, Default)]
pub struct MergeReport {
    /// Rows written.
    pub rows: usize,
    /// Rows whose id appeared in an earlier input (dropped).
    pub duplicates: usize,
    /// Points of the whole sweep.
    pub total: usize,
    /// Points of the sweep without a row (index, id), in index order; empty unless
    /// merged with `partial`.
    pub missing: Vec<(usize, String)>,
}

/// Join shards' results (each a results.csv or a directory holding one, with the
/// `sweep.json` beside it) into `output_dir` (writes `results.csv` and `sweep.json`
/// there), sorted by point index. The inputs must be shards of one sweep (same columns,
/// same inputs, same points) and together hold every point, else nothing is written and
/// the error lists the missing points; with `partial` the rows present are merged
/// anyway and [`MergeReport::missing`] lists the others.
pub fn merge(inputs: &[PathBuf], output_dir: &Path, partial: bool) -> Result<MergeReport, SweepError> {
    let merged = collect_rows(inputs, output_dir)?;
    if !merged.report.missing.is_empty() && !partial {
        return Err(merged.incomplete());
    }
    let lock = output::OutputDir::lock(output_dir)?;
    merged.write(&lock, output_dir)
}

/// The rows of shards read for a merge, not yet written.
struct Merged {
    /// The first input's results (its header and path; its rows are in `rows`).
    first: Results,
    /// The first input's sweep.json.
    info: SweepInfo,
    /// Every distinct row, sorted by point index.
    rows: Vec<Vec<String>>,
    /// The shards given (`k/n`).
    shards: BTreeSet<String>,
    report: MergeReport,
}

impl Merged {
    /// The error of a merge with points missing.
    fn incomplete(self) -> SweepError {
        SweepError::Incomplete {
            present: self.report.total - self.report.missing.len(),
            total: self.report.total,
            shards: self.shards.into_iter().collect(),
            missing: self.report.missing,
        }
    }

    /// Write `results.csv` and `sweep.json` into `output_dir`, whose lock the caller holds.
    fn write(self, _lock: &output::OutputDir, output_dir: &Path) -> Result<MergeReport, SweepError> {
        let Merged { first, info, rows, mut report, .. } = self;
        report.rows = rows.len();
        output::write_atomic(&output_dir.join("results.csv"), |w| {
            w.write_all(&csv_line(&first.header))?;
            rows.iter().try_for_each(|r| w.write_all(&csv_line(r)))
        })?;
        let id_col = first.require_column("id")?;
        let merged = SweepInfo { shard: None, ids: rows.iter().map(|r| r[id_col].clone()).collect(), ..info };
        output::write_json(&output_dir.join("sweep.json"), &merged)?;
        Ok(report)
    }
}

/// Read the whole rows of the shards `inputs` (each a results.csv or its directory, with
/// its sweep.json), check that they are shards of one sweep, drop duplicate rows and sort
/// the rest by point index; `output_dir` names the merge in an error about no input.
fn collect_rows(inputs: &[PathBuf], output_dir: &Path) -> Result<Merged, SweepError> {
    let mut first: Option<(Results, SweepInfo)> = None;
    let mut rows: Vec<Vec<String>> = Vec::new();
    let mut ids = HashSet::new();
    let mut shards = BTreeSet::new();
    let mut report = MergeReport::default();
    // The output may not be one of the inputs: its sweep.json and results.csv would be
    // replaced by the merge, and the shard's own files lost.
    let output_id = std::fs::canonicalize(output_dir).ok();
    for input in inputs {
        let dir = if input.is_dir() { input.clone() } else { input.parent().map(Path::to_path_buf).unwrap_or_default() };
        if output_id.is_some() && std::fs::canonicalize(&dir).ok() == output_id {
            return Err(SweepError::Results {
                path: output_dir.to_path_buf(),
                message: format!(
                    "is also an input of the merge ({}): merging into it would replace that shard's results.csv and \
                     sweep.json; merge into a new directory",
                    input.display()
                ),
            });
        }
    }
    for input in inputs {
        // A shard's torn last line (its run killed mid-write) is left out: that point is
        // missing from the merge, and the shard's rerun computes it.
        let res = Results::read_whole_rows(input)?;
        let path = res.path.clone();
        let info = SweepInfo::read(path.parent().unwrap_or(Path::new(".")))?;
        let not_shards =
            |message: String| SweepError::Results { path: path.clone(), message: format!("{message}: not shards of one sweep") };
        if let Some((r0, i0)) = &first {
            if let Some(other) = res.conflict(&i0.provenance).or_else(|| r0.conflict(&info.provenance)) {
                return Err(not_shards(format!("has rows computed from {other}")));
            }
            if r0.header != res.header {
                return Err(not_shards("its columns differ from the first input's".into()));
            }
            if i0.all_ids != info.all_ids {
                return Err(not_shards(format!("its sweep.json lists other points than {}'s", r0.path.display())));
            }
            if i0.settings != info.settings {
                return Err(not_shards(format!("its sweep.json records other [sweep] settings than {}'s", r0.path.display())));
            }
        } else if let Some(other) = res.conflict(&info.provenance) {
            return Err(SweepError::Results { path, message: format!("has rows computed from {other}, unlike its sweep.json") });
        }
        shards.extend(info.shard.clone());
        let id_col = res.require_column("id")?;
        for row in &res.rows {
            if ids.insert(row[id_col].clone()) {
                rows.push(row.clone());
            } else {
                report.duplicates += 1;
            }
        }
        first.get_or_insert((res, info));
    }
    let (first, info) = first.ok_or_else(|| SweepError::Results { path: output_dir.to_path_buf(), message: "nothing to merge".into() })?;
    report.total = info.all_ids.len();
    report.missing = info.all_ids.iter().enumerate().filter(|(_, id)| !ids.contains(*id)).map(|(k, id)| (k, id.clone())).collect();
    let idx = first.require_column("index")?;
    rows.sort_by_key(|r| r[idx].parse::<usize>().unwrap_or(usize::MAX));
    report.rows = rows.len();
    Ok(Merged { first, info, rows, shards, report })
}

/// The node count, operator and formulation of a point whose record lacks them (its
/// worker crashed or timed out before it said), from its scene resolved here as the
/// expansion resolved it, so that no row leaves these columns blank.
fn fill_point_settings(rec: &mut Record, point: &Point, base: Option<&SceneFile>) {
    if rec.nodes.is_some() && rec.operator.is_some() && rec.formulation.is_some() {
        return;
    }
    let Some(scene) = base.and_then(|b| b.clone().resolve(&point.overrides().ok()?).ok()) else { return };
    rec.nodes.get_or_insert(scene.nodes);
    if point.method == Method::Skg {
        rec.operator.get_or_insert_with(|| scene.operator.name().to_string());
        rec.formulation.get_or_insert_with(|| scene.formulation.to_string());
    }
}

/// At most this many missing points are listed in a message.
const LISTED_MISSING: usize = 10;

/// `index 3 (id …), …` for a message: the first ten (index, id) pairs and how many more.
pub fn list_points(points: &[(usize, String)]) -> String {
    let mut text: Vec<String> = points.iter().take(LISTED_MISSING).map(|(k, id)| format!("index {k} (id {id})")).collect();
    if points.len() > LISTED_MISSING {
        text.push(format!("and {} more", points.len() - LISTED_MISSING));
    }
    text.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shard_parsing() {
        assert_eq!("2/8".parse::<Shard>(), Ok(Shard { k: 2, n: 8 }));
        for bad in ["0/3", "4/3", "1/0", "x/2", "3"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
        let s = Shard { k: 2, n: 3 };
        assert!(s.contains(1) && s.contains(4) && !s.contains(0));
    }

    #[test]
    fn id_ignores_axis_order_and_csv_line_is_one_line() {
        let values = vec![("nodes".into(), "64".into()), ("sigma".into(), "1/110".into())];
        let a = Point { index: 0, values, evaluated: vec![("sigma".into(), 1.0 / 110.0)], method: Method::Skg };
        let mut b = a.clone();
        b.values.reverse();
        b.index = 7;
        assert_eq!(a.id(), b.id());
        assert_eq!(a.canonical(), "method=skg;nodes=64;sigma=1/110");
        let line = csv_line(&["a,b".into(), "x\"y".into(), "".into()]);
        assert_eq!(String::from_utf8(line).unwrap(), "\"a,b\",\"x\"\"y\",\n");
    }
}
