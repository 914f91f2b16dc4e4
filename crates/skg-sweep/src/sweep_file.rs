//! The sweep file as written (TOML, docs/sweeps.md): [`SweepFile`] with its `[sweep]`
//! table ([`SweepMeta`]), its `[[grid]]` and `[[points]]` tables of [`AxisValues`] and
//! its `[peer]` table ([`PeerSpec`]); reading it with positions for error messages, and
//! what it says before any point is expanded (the base scene's path, the sweep's name,
//! the reference, the number of points it lists). The expansion into points is in
//! `expand.rs`.

use std::fmt;
use std::path::{Path, PathBuf};

use indexmap::IndexMap;
use serde::{Deserialize, Serialize};
use toml::Spanned;

use skg_core::check::Table;
use skg_core::scene::{parse_toml, read_toml, Location, Origin, Scene, TomlError};

use crate::SweepError;

/// One value in a grid: a number, an integer or a string (an expression, an operator
/// or formulation name).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(untagged, expecting = "a grid value is a number or a string in quotes (an expression, an operator's name)")]
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
#[serde(
    untagged,
    expecting = "a grid axis is a value (a number, or a string in quotes) or an array of them, like nodes = [64, 128] or \
                 sigma = \"1/110\""
)]
pub enum AxisValues {
    /// A single value (`sigma = "1/110"`).
    One(AxisValue),
    /// A list of values (`nodes = [64, 128]`).
    Many(Vec<AxisValue>),
}

impl AxisValues {
    pub(crate) fn values(&self) -> Vec<AxisValue> {
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
    /// The scene's event-driven hard-wall reference (every wall ideal and elastic, the
    /// σ → 0 limit; [`skg_core::stepping::reference::hard_wall`], rtol = atol = 1e-12) on
    /// the point's own grid: the errors are the point's *model error* (the wall's width
    /// against the ideal wall), beside its discretization error `verify_error`.
    HardWalls,
}

/// `[sweep] reference` naming the regularized reference integrated on each point's grid.
pub const REFERENCE_INTEGRATE: &str = "integrate";

/// `[sweep] reference` naming the hard-wall reference on each point's grid.
pub const REFERENCE_HARD_WALLS: &str = "hard_walls";

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
    /// Reference to measure errors against: a CSV path relative to the sweep file,
    /// `"integrate"` or `"hard_walls"`. Without it the error columns stay empty.
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
    /// the point recorded as [`PointStatus::TimedOut`](crate::PointStatus::TimedOut) (default: no limit).
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
            Err(TomlError::Io { path, error }) => Err(SweepError::Read { path, error }),
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

    pub(crate) fn dir(&self) -> PathBuf {
        Path::new(&self.origin.path).parent().map_or(PathBuf::from("."), Path::to_path_buf)
    }

    pub(crate) fn invalid<T>(&self, v: &Spanned<T>, message: impl Into<String>) -> SweepError {
        SweepError::Invalid { location: self.origin.locate_in(v, None), message: message.into() }
    }

    /// Location of `key = …` inside the table spanned by `table` (falls back to the
    /// table's own location).
    pub(crate) fn locate_key<T>(&self, table: &Spanned<T>, key: &str) -> Location {
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

    /// Refuse a sweep's name (`[sweep] name`, else the sweep file's name) that is not a
    /// plain, printable file name: it names the default output directory
    /// `out/sweeps/<name>`, which must not be the parent directory or lie outside, and it
    /// is data that reaches the terminal, `sweep.json`, Slurm's job names and the
    /// comments of the Slurm scripts, where a line break would start a command (a sweep
    /// file is shared and downloaded like a scene).
    pub(crate) fn check_name(&self) -> Result<(), SweepError> {
        let name = self.name();
        let Some(problem) = name_problem(&name) else { return Ok(()) };
        let message =
            format!("the sweep's name {name:?} {problem}; it must be a plain file name of printable characters: it names the output directory out/sweeps/<name>");
        Err(match &self.sweep.name {
            Some(spanned) => self.invalid(spanned, format!("sweep.name: {message}")),
            None => SweepError::Invalid {
                location: self.origin.whole(),
                message: format!("{message}; the name is the sweep file's, so give the file another name or set `[sweep] name`"),
            },
        })
    }

    /// Refuse `compare` columns that a trajectory of the base scene, or the reference
    /// file, does not have, before any point runs.
    pub(crate) fn check_compare_columns(&self, scene: &Scene) -> Result<(), SweepError> {
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
            let r = r.get_ref();
            if r.eq_ignore_ascii_case(REFERENCE_INTEGRATE) {
                ReferenceSpec::Integrate
            } else if r.eq_ignore_ascii_case(REFERENCE_HARD_WALLS) {
                ReferenceSpec::HardWalls
            } else {
                ReferenceSpec::File(self.dir().join(r))
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
}

/// The longest sweep name, in bytes (a file name may have 255).
pub const MAX_NAME_BYTES: usize = 200;

/// Why `name` cannot name a sweep, if it cannot: it must be a plain file name (not
/// empty, not `.` or `..`, no `/` or `\`, not hidden: the output directory's lock and
/// temporary files start with a dot) of printable characters (no line break, tab, escape
/// or other control character) and at most [`MAX_NAME_BYTES`] bytes.
pub fn name_problem(name: &str) -> Option<&'static str> {
    if name.trim().is_empty() || name == "." || name == ".." {
        Some("is empty, `.` or `..`")
    } else if name.contains(['/', '\\']) {
        Some("contains `/` or `\\`")
    } else if name.chars().any(char::is_control) {
        Some("contains a control character (a line break, a tab, an escape)")
    } else if name.starts_with('.') {
        Some("starts with `.` (a hidden file)")
    } else if name.len() > MAX_NAME_BYTES {
        Some("is longer than 200 bytes")
    } else {
        None
    }
}
