//! The errors of a sweep: [`SweepError`] (the sweep file, the results files, the
//! driver, the merge), [`SweepSceneError`] (an invalid scene of a sweep), [`AxisError`]
//! (a value of a setting axis), and the helpers that the other modules use to build
//! them (`read_err` and its siblings for I/O errors naming the file, [`list_points`]
//! for the points a message lists). It uses only the types its variants carry.
//!
//! Each message is said once in a chain: a variant prints the error it wraps in its own
//! message, as a plain field (named `error`, not `source`, so that it is not also the
//! variant's `source`); `transparent` variants are their inner error.

use std::fmt;
use std::path::{Path, PathBuf};

use skg_core::output;
use skg_core::sbp::ParseOperatorKindError;
use skg_core::scene::{
    Location, ParseBackendError, ParseFormulationError, ParseGridChoiceError, ParseInitialVelocityError, ParseStepperError, SceneError,
};

use crate::shards;
use crate::{SchemaError, UnknownStatus, CONFIRM_ABOVE};

/// Errors of a sweep file, a results file or the sweep driver.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    /// A file could not be read.
    #[error("cannot read {path}: {error}")]
    Read {
        /// The file.
        path: PathBuf,
        /// What the system said.
        error: std::io::Error,
    },
    /// `results.csv` could not be opened to append rows to it.
    #[error("cannot open {path} for appending: {error}")]
    Open {
        /// The file.
        path: PathBuf,
        /// What the system said.
        error: std::io::Error,
    },
    /// A file could not be written, cut back or flushed to disk (a full disk, …).
    #[error("cannot write {path}: {error}")]
    Write {
        /// The file.
        path: PathBuf,
        /// What the system said.
        error: std::io::Error,
    },
    /// A directory could not be created.
    #[error("cannot create directory {path}: {error}")]
    CreateDir {
        /// The directory.
        path: PathBuf,
        /// What the system said.
        error: std::io::Error,
    },
    /// A file or directory could not be moved (`--new-results` moving earlier results aside).
    #[error("cannot move {from} to {to}: {error}")]
    Move {
        /// What was moved.
        from: PathBuf,
        /// Where to.
        to: PathBuf,
        /// What the system said.
        error: std::io::Error,
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
    /// values), is invalid ([`SweepSceneError`]; boxed, to keep every result small). The
    /// scene's own error, with its location in the scene file, is
    /// [`SweepError::scene_error`].
    #[error(transparent)]
    Scene(Box<SweepSceneError>),
    /// A value of a setting axis (`nodes`, `operator`, …) that is not a valid setting.
    #[error("{location}: {error}")]
    Axis {
        /// The table of the point in the sweep file.
        location: Location,
        /// What is wrong with the value.
        error: AxisError,
    },
    /// A results file of another schema version, or without the columns every results
    /// file has.
    #[error("{location}: {error}")]
    Schema {
        /// The results file, and the row's line for a row of another schema version.
        location: Location,
        /// What is wrong.
        error: SchemaError,
    },
    /// A `status` cell of a results file that is no point status.
    #[error("{location}: {error}")]
    Status {
        /// The results file, and the row's line where known.
        location: Location,
        /// The cell.
        error: UnknownStatus,
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
    #[error("cannot start a worker process ({exe}): {error}")]
    Spawn {
        /// The worker executable.
        exe: PathBuf,
        /// What the system said.
        error: std::io::Error,
    },
    /// Writing `sweep.json`, a job file or `results.csv` failed.
    #[error(transparent)]
    Output(#[from] output::OutputError),
    /// More than [`CONFIRM_ABOVE`] points would run and the run was not confirmed.
    #[error("{plan}: more than {CONFIRM_ABOVE} points start only with --yes (or split the sweep with --shard)")]
    Unconfirmed {
        /// What the run would do ([`Plan::text`](crate::Plan::text)).
        plan: String,
    },
    /// The driver received SIGTERM or SIGINT after [`stop_on_signals`](crate::stop_on_signals): it killed its
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
    /// The shards given to [`merge`](crate::merge()) do not hold every point of the sweep.
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
            SweepError::Scene(e) => Some(&e.error),
            _ => None,
        }
    }

    pub(crate) fn scene(location: Location, of: SceneOf, error: SceneError) -> SweepError {
        SweepError::Scene(Box::new(SweepSceneError { location, of, error }))
    }
}

/// An invalid scene of a sweep: where the sweep file asks for it, which scene it is, and
/// the scene's own error (printed in the message; typed, with its location in the scene
/// file, through [`SweepError::scene_error`]).
#[derive(Debug, thiserror::Error)]
#[error("{location}: {of}: {error}")]
pub struct SweepSceneError {
    /// Where in the sweep file: the `scene` key, or the table of the point.
    pub location: Location,
    /// Which scene: the base scene or a point's.
    pub of: SceneOf,
    /// The scene's error (its location is in the scene file).
    pub error: SceneError,
}

/// Which scene of a sweep a [`SweepError::Scene`] is about.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SceneOf {
    /// The sweep file's `scene`, as written.
    Base,
    /// The base scene with the values of the point with this canonical text
    /// ([`Point::canonical`](crate::Point::canonical)).
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

/// A value of a setting axis of a sweep that is not a valid setting ([`Point::overrides`](crate::Point::overrides)).
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
    #[error("operator = {value}: {error}")]
    Operator {
        /// The value as written.
        value: String,
        /// The operator parser's error.
        error: ParseOperatorKindError,
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
    /// An unknown stepper.
    #[error(transparent)]
    Stepper(#[from] ParseStepperError),
    /// An unknown grid.
    #[error(transparent)]
    Grid(#[from] ParseGridChoiceError),
}

/// `SIGTERM`, `SIGINT` or `signal N`.
fn signal_name(signal: i32) -> String {
    match signal {
        libc::SIGTERM => "SIGTERM".into(),
        libc::SIGINT => "SIGINT".into(),
        s => format!("signal {s}"),
    }
}

pub(crate) fn read_err(path: &Path) -> impl FnOnce(std::io::Error) -> SweepError + '_ {
    move |error| SweepError::Read { path: path.to_path_buf(), error }
}

pub(crate) fn open_err(path: &Path) -> impl FnOnce(std::io::Error) -> SweepError + '_ {
    move |error| SweepError::Open { path: path.to_path_buf(), error }
}

pub(crate) fn write_err(path: &Path) -> impl FnOnce(std::io::Error) -> SweepError + '_ {
    move |error| SweepError::Write { path: path.to_path_buf(), error }
}

pub(crate) fn create_dir_err(path: &Path) -> impl FnOnce(std::io::Error) -> SweepError + '_ {
    move |error| SweepError::CreateDir { path: path.to_path_buf(), error }
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
