//! The results file, `results.csv`: its columns, one row per point, and reading it back
//! (with its schema version checked).

use std::collections::{BTreeSet, HashSet};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use skg_core::output;
use skg_core::scene::provenance;
use skg_core::scene::Location;

use crate::error::{open_err, read_err, write_err};
use crate::{Method, Point, PointStatus, Record, SweepError, UnknownStatus};

/// A results file that this skg-solve does not read: written before results.csv had a
/// schema version, with a row of another schema version, or not a results file at all.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SchemaError {
    /// The header has a `status` column but no `schema_version` (results schema 1).
    #[error(
        "has no `schema_version` column: it was written before results.csv had a schema version (results schema 1), \
         and this skg-solve {} reads results schema {} only: run the sweep again into a new directory",
        provenance::VERSION,
        provenance::SCHEMA_VERSION
    )]
    Unversioned,
    /// The header has no `status` column.
    #[error("no `status` column (columns: {}): not a sweep's results.csv", columns.join(", "))]
    NotResults {
        /// The header's columns.
        columns: Vec<String>,
    },
    /// A row of another schema version.
    #[error(
        "row of results schema {found}; this skg-solve {} reads results schema {} only: run the sweep again into a new \
         directory, or read it with the skg-solve that wrote it",
        provenance::VERSION,
        provenance::SCHEMA_VERSION
    )]
    OtherVersion {
        /// The row's `schema_version` cell.
        found: String,
    },
}

/// Where a sweep's rows come from. Every row of `results.csv` carries these three
/// columns, and `sweep.json` records them too.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Provenance {
    /// The skg-solve version that computed the row ([`provenance::VERSION`]).
    pub skg_solve_version: String,
    /// Layout version of `results.csv` and `sweep.json` ([`provenance::SCHEMA_VERSION`]).
    pub schema_version: u32,
    /// SHA-256 of the base scene file's content, `sha256:<64 hex digits>`.
    pub scene_hash: String,
    /// SHA-256 of the reference file's content when errors are measured against a file
    /// (empty otherwise).
    pub reference_hash: String,
}

impl Provenance {
    /// This skg-solve's version and schema, with the hashes of a base scene's and a
    /// reference file's content.
    pub fn current(scene_hash: String, reference_hash: Option<String>) -> Provenance {
        Provenance {
            skg_solve_version: provenance::VERSION.to_string(),
            schema_version: provenance::SCHEMA_VERSION,
            scene_hash,
            reference_hash: reference_hash.unwrap_or_default(),
        }
    }

    /// Why rows of `row` (the provenance cells of a row) cannot join rows of `self`:
    /// another base scene content or another reference content.
    pub fn conflict(&self, row: &Provenance) -> Option<String> {
        if row.scene_hash != self.scene_hash {
            Some(format!("a base scene with content {} (this one is {})", row.scene_hash, self.scene_hash))
        } else if row.reference_hash != self.reference_hash {
            let name = |h: &str| if h.is_empty() { "no reference file".to_string() } else { format!("a reference file with content {h}") };
            Some(format!("{} (this one has {})", name(&row.reference_hash), name(&self.reference_hash)))
        } else {
            None
        }
    }
}

/// Columns before the axes: the point's identity and its resolved settings.
pub const LEADING_COLUMNS: &[&str] = &["id", "index", "method", "rtol", "nodes", "operator", "formulation"];

/// Result columns after the axes.
pub const RESULT_COLUMNS: &[&str] = &[
    "converged",
    "status",
    "solver_status",
    "verification",
    "verify_error",
    "solved_as",
    "iterations",
    "wall_s",
    "lu_analysis",
    "error_max",
    "error_rms",
    "error_column",
    "energy_drift",
    "energy_artifact",
    "artifacts",
    "max_residual",
    "message",
];

/// Provenance columns, last in every row (see [`Provenance`]).
pub const PROVENANCE_COLUMNS: &[&str] = &["skg_solve_version", "schema_version", "scene_hash", "reference_hash"];

/// Suffix of the column that keeps an axis's values as written: `sigma` → `sigma_expr`.
pub const EXPR_SUFFIX: &str = "_expr";

/// A column of `results.csv`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Column {
    /// One of [`LEADING_COLUMNS`], [`RESULT_COLUMNS`] or [`PROVENANCE_COLUMNS`].
    Fixed(&'static str),
    /// A grid axis: for a scene parameter the value the resolved scene has (a number),
    /// for a setting (`max_iter`, `hessian`, …) the value as written.
    Axis(String),
    /// `<axis>_expr`: a parameter axis's value as written in the sweep file (`1/110`).
    AxisExpr(String),
}

impl Column {
    /// The column's name in the header.
    pub fn name(&self) -> String {
        match self {
            Column::Fixed(name) => name.to_string(),
            Column::Axis(axis) => axis.clone(),
            Column::AxisExpr(axis) => format!("{axis}{EXPR_SUFFIX}"),
        }
    }
}

/// The columns of `results.csv` for a sweep with these grid axes, of which
/// `expression_axes` have some value written as an expression: the leading columns,
/// each axis (followed by its `_expr` column if it has one), the results, the provenance.
///
/// **`results.csv`** is a plain CSV (one header line, no comments: `pd.read_csv` reads
/// it). Its columns, in order:
///
/// * `id`, `index`, `method` (`skg` or `ode`), `rtol` (the peer's tolerance), `nodes`,
///   `operator`, `formulation`: the point and its resolved settings;
/// * one column per grid axis. A scene parameter's column holds the **number** the
///   resolved scene has (`sigma = "1/110"` gives `0.00909090909090909`, the shortest text
///   that reads back to the same double, as in every numeric column); a setting's column
///   (`max_iter`, `hessian`, `backend`) holds the value as written. A parameter axis with at least
///   one value written as an expression also gets the column **`<axis>_expr`**, right
///   after it, with every value as written in the sweep file (`1/110`, and `0.005` for a
///   plain number); an axis whose values are all plain numbers gets none;
/// * `converged` (`true`/`false`), `status` (the stable name of the [`PointStatus`]:
///   `converged`, `not_verified`, `not_converged`, `error`, `crashed`, `timeout`),
///   `solver_status` (the finishing backend's status name, Ipopt's or `Newton_…`,
///   `ODE_Succeeded` for a peer point, empty when the solver did not finish), then
///   `verification`, `verify_error`, `solved_as`, `iterations`, `wall_s`, `lu_analysis`
///   (`computed` or `reused`: the Newton backend's symbolic LU analysis, made for this
///   point or taken over from the worker's previous point of equal structure; empty
///   when Newton did not run), `error_max`, `error_rms`, `error_column`,
///   `energy_drift`, `energy_artifact` (empty unless the energy is conserved:
///   [`skg_core::tune::conserves_energy`]), `artifacts`, `max_residual`, `message`;
/// * the provenance ([`Provenance`]): `skg_solve_version`, `schema_version` and
///   `scene_hash` (`sha256:…` of the base scene file's content, as the worker read it),
///   `reference_hash` (of the reference file's content; empty without one).
///
/// [`Results::read`] refuses a file of another schema version (or one without the
/// `schema_version` column, written before it existed) with a message naming the file.
pub fn results_columns(axes: &[String], expression_axes: &[String]) -> Vec<Column> {
    let mut columns: Vec<Column> = LEADING_COLUMNS.iter().map(|c| Column::Fixed(c)).collect();
    for axis in axes.iter().filter(|a| !LEADING_COLUMNS.contains(&a.as_str())) {
        columns.push(Column::Axis(axis.clone()));
        if expression_axes.contains(axis) {
            columns.push(Column::AxisExpr(axis.clone()));
        }
    }
    columns.extend(RESULT_COLUMNS.iter().chain(PROVENANCE_COLUMNS).map(|c| Column::Fixed(c)));
    columns
}

/// The header line's names of `columns`.
pub fn header_names(columns: &[Column]) -> Vec<String> {
    columns.iter().map(Column::name).collect()
}

/// A number as every numeric cell of results.csv writes it: the shortest text that
/// reads back to the same double.
fn number_text(x: f64) -> String {
    format!("{x:?}")
}

fn optional_number(x: Option<f64>) -> String {
    x.map_or(String::new(), number_text)
}

/// Text of an axis cell: the evaluated number for a parameter axis, else as written.
fn axis_text(point: &Point, axis: &str) -> String {
    match point.evaluated(axis) {
        Some(x) => number_text(x),
        None => point.value(axis).unwrap_or("").to_string(),
    }
}

/// One row of `results.csv` (one line: newlines in messages are replaced).
pub fn results_row(columns: &[Column], point: &Point, rec: &Record, artifact_tol: f64, provenance: &Provenance) -> Vec<String> {
    columns
        .iter()
        .map(|col| match col {
            Column::Axis(axis) => axis_text(point, axis),
            Column::AxisExpr(axis) => point.value(axis).unwrap_or("").to_string(),
            Column::Fixed(name) => fixed_cell(name, point, rec, artifact_tol, provenance),
        })
        .collect()
}

fn fixed_cell(name: &str, point: &Point, rec: &Record, artifact_tol: f64, provenance: &Provenance) -> String {
    let written = |axis: &str| point.value(axis).unwrap_or("").to_string();
    match name {
        "id" => point.id(),
        "index" => point.index.to_string(),
        "method" => point.method.name().to_string(),
        "rtol" => match point.method {
            Method::Ode { rtol } => number_text(rtol),
            Method::Skg => String::new(),
        },
        "nodes" => rec.nodes.map_or_else(|| written("nodes"), |n| n.to_string()),
        "operator" => rec.operator.clone().unwrap_or_else(|| written("operator")),
        "formulation" => rec.formulation.clone().unwrap_or_else(|| written("formulation")),
        "converged" => rec.status.is_converged().to_string(),
        "status" => rec.status.name().to_string(),
        "solver_status" => rec.solver_status.clone(),
        "verification" => rec.verification.clone(),
        "verify_error" => optional_number(rec.verify_error),
        "solved_as" => rec.solved_as.clone(),
        "iterations" => rec.iterations.map_or(String::new(), |i| i.to_string()),
        "wall_s" => optional_number(rec.wall_s),
        "lu_analysis" => rec.lu_analysis.clone(),
        "error_max" => optional_number(rec.error_max),
        "error_rms" => optional_number(rec.error_rms),
        "error_column" => rec.error_column.clone().unwrap_or_default(),
        "energy_drift" => optional_number(rec.energy_drift),
        "energy_artifact" => optional_number(rec.energy_artifact),
        "artifacts" => match rec.energy_artifact {
            Some(a) if rec.status.is_converged() => (a > artifact_tol).to_string(),
            _ => String::new(),
        },
        "max_residual" => optional_number(rec.max_residual),
        "message" => rec.message.replace(['\n', '\r'], " | "),
        "skg_solve_version" => provenance.skg_solve_version.clone(),
        "schema_version" => provenance.schema_version.to_string(),
        "scene_hash" => rec.scene_hash.clone().unwrap_or_else(|| provenance.scene_hash.clone()),
        "reference_hash" => provenance.reference_hash.clone(),
        other => unreachable!("`{other}` is not a fixed column of results.csv"),
    }
}

/// Encode one CSV record as a single line ending in `\n`.
pub fn csv_line(fields: &[String]) -> Vec<u8> {
    let mut w = csv::WriterBuilder::new().terminator(csv::Terminator::Any(b'\n')).from_writer(Vec::new());
    // Writing to a Vec cannot fail.
    let _ = w.write_record(fields);
    w.into_inner().unwrap_or_default()
}

/// A results file read back: header and rows of text fields. Reading checks the schema
/// version and every row's status, so [`Results::status`] of a row read from a file
/// cannot fail.
#[derive(Debug, Clone, Default)]
pub struct Results {
    /// The file read (for messages).
    pub path: PathBuf,
    /// Column names.
    pub header: Vec<String>,
    /// Rows, each with one field per column.
    pub rows: Vec<Vec<String>>,
}

impl Results {
    /// Position of the column `name`.
    pub fn column_index(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    /// Read a results.csv (or a directory holding one).
    pub fn read(path: &Path) -> Result<Results, SweepError> {
        let path = if path.is_dir() { path.join("results.csv") } else { path.to_path_buf() };
        let text = std::fs::read_to_string(&path).map_err(read_err(&path))?;
        Self::parse(&text, &path)
    }

    /// Read a results file written by a sweep driver (or its directory's) up to its last
    /// newline: a row is in the file once its newline is, so a partial last line (a driver
    /// killed while writing it) is not a row and is left out, as a resume cuts it off.
    pub fn read_whole_rows(path: &Path) -> Result<Results, SweepError> {
        let path = if path.is_dir() { path.join("results.csv") } else { path.to_path_buf() };
        let mut text = std::fs::read_to_string(&path).map_err(read_err(&path))?;
        text.truncate(text.rfind('\n').map_or(0, |i| i + 1));
        Self::parse(&text, &path)
    }

    /// Parse the text of a results file; `path` labels error messages.
    pub fn parse(text: &str, path: &Path) -> Result<Results, SweepError> {
        let bad = |m: String| SweepError::Results { path: path.to_path_buf(), message: m };
        // Every line the driver writes ends in a newline: a last line without one was
        // cut by a kill in the middle of the write.
        if !text.is_empty() && !text.ends_with('\n') {
            return Err(bad(CUT_LINE.to_string()));
        }
        let mut r = csv::ReaderBuilder::new().has_headers(true).flexible(false).from_reader(text.as_bytes());
        let header: Vec<String> = r.headers().map_err(|e| bad(e.to_string()))?.iter().map(str::to_string).collect();
        let file = Location::file(path.display().to_string());
        let (schema, status) = schema_and_status_columns(&header).map_err(|error| SweepError::Schema { location: file, error })?;
        let mut rows = Vec::new();
        for rec in r.records() {
            let rec = rec.map_err(|e| bad(e.to_string()))?;
            let location =
                Location { file: path.display().to_string(), line: rec.position().map(|p| p.line() as usize), col: None, field: None };
            check_schema_version(&rec[schema]).map_err(|error| SweepError::Schema { location: location.clone(), error })?;
            rec[status].parse::<PointStatus>().map_err(|error| SweepError::Status { location, error })?;
            rows.push(rec.iter().map(str::to_string).collect());
        }
        Ok(Results { path: path.to_path_buf(), header, rows })
    }

    /// The column `name`, or an error naming the file.
    pub fn require_column(&self, name: &str) -> Result<usize, SweepError> {
        self.column_index(name).ok_or_else(|| SweepError::Results {
            path: self.path.clone(),
            message: format!("no `{name}` column (columns: {})", self.header.join(", ")),
        })
    }

    /// How the point of a row ended (its `status` cell).
    pub fn status(&self, row: &[String]) -> Result<PointStatus, SweepError> {
        let i = self.require_column("status")?;
        row[i]
            .parse()
            .map_err(|error: UnknownStatus| SweepError::Status { location: Location::file(self.path.display().to_string()), error })
    }

    /// The `<column>_expr` column that keeps `column`'s values as written, if any.
    pub fn expr_column(&self, column: &str) -> Option<usize> {
        self.column_index(&format!("{column}{EXPR_SUFFIX}"))
    }

    /// Whether `column` is the `_expr` column of another column.
    pub fn is_expr_column(&self, column: usize) -> bool {
        self.header[column].strip_suffix(EXPR_SUFFIX).is_some_and(|axis| self.column_index(axis).is_some())
    }

    /// A cell as the sweep file wrote it: the `_expr` cell where there is one (`1/110`),
    /// else the cell itself.
    pub fn written<'a>(&self, row: &'a [String], column: usize) -> &'a str {
        match self.expr_column(&self.header[column]) {
            Some(e) if !row[e].is_empty() => &row[e],
            _ => &row[column],
        }
    }

    /// Ids present (column `id`).
    pub fn ids(&self) -> HashSet<String> {
        match self.column_index("id") {
            Some(i) => self.rows.iter().map(|r| r[i].clone()).collect(),
            None => HashSet::new(),
        }
    }

    /// The distinct provenances of the rows (which skg-solve version computed a row
    /// does not matter: it is set to this one's).
    pub fn provenances(&self) -> BTreeSet<Provenance> {
        let cell = |row: &[String], name: &str| self.column_index(name).map_or(String::new(), |i| row[i].clone());
        self.rows
            .iter()
            .map(|r| Provenance {
                scene_hash: cell(r, "scene_hash"),
                reference_hash: cell(r, "reference_hash"),
                ..Provenance::current(String::new(), None)
            })
            .collect()
    }

    /// The first row provenance that conflicts with `expected` ([`Provenance::conflict`]).
    pub fn conflict(&self, expected: &Provenance) -> Option<String> {
        self.provenances().iter().find_map(|p| expected.conflict(p))
    }
}

/// Positions of the `schema_version` and `status` columns; a file without them predates
/// the schema versions of results.csv.
fn schema_and_status_columns(header: &[String]) -> Result<(usize, usize), SchemaError> {
    let find = |name: &str| header.iter().position(|h| h == name);
    match (find("schema_version"), find("status")) {
        (Some(schema), Some(status)) => Ok((schema, status)),
        (None, Some(_)) => Err(SchemaError::Unversioned),
        _ => Err(SchemaError::NotResults { columns: header.to_vec() }),
    }
}

fn check_schema_version(cell: &str) -> Result<(), SchemaError> {
    if cell == provenance::SCHEMA_VERSION.to_string() {
        Ok(())
    } else {
        Err(SchemaError::OtherVersion { found: cell.to_string() })
    }
}

/// Why a results file whose last line has no newline is refused, and the remedy.
pub const CUT_LINE: &str = "its last line is cut off (the run that wrote it was killed in the middle of writing a row): \
     run the same sweep command again, which repairs the file (a resumed run cuts the partial line and computes that \
     point again)";

/// Open `results.csv` for appending, recovering from an interrupted run: a trailing
/// partial line is cut off; the header must match and every row must come from the
/// same inputs (`expected`'s scene and reference content). With `retry_failed`, the rows
/// of points that did not converge are removed first (the file is rewritten
/// atomically), so that those points run again. Returns the file and the ids present.
pub(crate) fn open_results(
    path: &Path,
    header: &[String],
    expected: &Provenance,
    retry_failed: bool,
) -> Result<(std::fs::File, HashSet<String>), SweepError> {
    let mut f = std::fs::OpenOptions::new().read(true).append(true).create(true).open(path).map_err(open_err(path))?;
    let mut text = Vec::new();
    f.read_to_end(&mut text).map_err(read_err(path))?;
    let complete = text.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
    if complete < text.len() {
        f.set_len(complete as u64).map_err(write_err(path))?;
        f.seek(SeekFrom::End(0)).map_err(write_err(path))?;
        text.truncate(complete);
    }
    if text.is_empty() {
        append(&mut f, path, &csv_line(header))?;
        return Ok((f, HashSet::new()));
    }
    let text = String::from_utf8_lossy(&text);
    let mut existing = Results::parse(&text, path)?;
    if existing.header != header {
        return Err(SweepError::Results {
            path: path.to_path_buf(),
            message: format!(
                "has other columns than this sweep writes ({}): it was written by a different sweep or by another \
                 skg-solve version. Use another output directory, or start a new result set with --new-results (the old \
                 results are kept in a subdirectory)",
                column_difference(&existing.header, header)
            ),
        });
    }
    if let Some(other) = existing.conflict(expected) {
        return Err(SweepError::Results {
            path: path.to_path_buf(),
            message: format!(
                "holds points computed from {other}: the inputs changed since. Restore them, use another output \
                 directory, or start a new result set with --new-results (the old results are kept in a subdirectory)"
            ),
        });
    }
    if retry_failed {
        let status = existing.require_column("status")?;
        let before = existing.rows.len();
        existing.rows.retain(|row| row[status] == PointStatus::Converged.name());
        if existing.rows.len() < before {
            drop(f);
            output::write_atomic(path, |w| {
                w.write_all(&csv_line(header))?;
                existing.rows.iter().try_for_each(|row| w.write_all(&csv_line(row)))
            })?;
            f = std::fs::OpenOptions::new().append(true).open(path).map_err(open_err(path))?;
        }
    }
    Ok((f, existing.ids()))
}

/// Append `bytes` (whole lines) to the results file `path`, open as `file`, and flush
/// them to disk: a row is in results.csv once this returns (a failure, such as a full
/// disk, is an error naming the file as written to).
pub(crate) fn append(file: &mut std::fs::File, path: &Path, bytes: &[u8]) -> Result<(), SweepError> {
    file.write_all(bytes).map_err(write_err(path))?;
    file.sync_data().map_err(write_err(path))
}

/// How the columns `found` differ from `expected`: the missing ones, the extra ones,
/// or that they are in another order.
fn column_difference(found: &[String], expected: &[String]) -> String {
    let absent = |a: &[String], b: &[String]| a.iter().filter(|c| !b.contains(c)).cloned().collect::<Vec<_>>().join(", ");
    let (missing, extra) = (absent(expected, found), absent(found, expected));
    match (missing.is_empty(), extra.is_empty()) {
        (true, true) => "the same columns in another order".into(),
        (false, true) => format!("it lacks {missing}"),
        (true, false) => format!("it has {extra} besides"),
        (false, false) => format!("it lacks {missing} and has {extra} besides"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_of_another_schema_or_with_unknown_statuses_are_refused_with_their_line() {
        let now = provenance::SCHEMA_VERSION;
        let good = format!("id,sigma,sigma_expr,status,schema_version\na,0.5,1/2,converged,{now}\n");
        let r = Results::parse(&good, Path::new("r.csv")).unwrap();
        assert_eq!(r.status(&r.rows[0]).unwrap(), PointStatus::Converged);
        assert_eq!(r.written(&r.rows[0], 1), "1/2");
        assert_eq!(r.written(&r.rows[0], 0), "a");
        let cases = [
            (format!("{good}b,1.0,1,converged,{}\n", now + 1), format!("r.csv:3: row of results schema {}", now + 1)),
            (format!("{good}b,1.0,1,Solve_Succeeded,{now}\n"), "r.csv:3: unknown point status `Solve_Succeeded`".to_string()),
            ("id,sigma,status\na,1/2,converged\n".to_string(), "r.csv: has no `schema_version` column".to_string()),
        ];
        for (text, expected) in cases {
            let e = Results::parse(&text, Path::new("r.csv")).unwrap_err().to_string();
            assert!(e.starts_with(&expected), "expected `{expected}…`, got: {e}");
        }
    }

    /// A full disk while a row is appended is reported as a failed write of results.csv
    /// (`/dev/full` fails every write with ENOSPC).
    #[cfg(target_os = "linux")]
    #[test]
    fn a_failed_append_is_reported_as_a_write() {
        let mut full = std::fs::OpenOptions::new().append(true).open("/dev/full").expect("/dev/full");
        let path = Path::new("out/sweeps/demo/results.csv");
        let err = append(&mut full, path, b"a,b\n").unwrap_err();
        let SweepError::Write { path: named, error } = &err else { panic!("expected a write error, got {err:?}") };
        assert_eq!(named, path);
        assert_eq!(error.kind(), std::io::ErrorKind::StorageFull, "{err}");
        assert!(err.to_string().starts_with("cannot write out/sweeps/demo/results.csv: "), "{err}");
    }
}
