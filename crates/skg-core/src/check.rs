//! Comparing a trajectory CSV with a reference CSV: reading the tables, bringing the
//! reference onto the solution's times, and the per-column errors.
//!
//! A table is the CSV the tool writes: optional comment lines starting with `#`, one
//! header line whose first column is `t`, then one row of numbers per time, times
//! strictly increasing.
//!
//! The reference is evaluated at the solution's times:
//! * where a solution time equals a reference time (to `1e-12` relative to the time
//!   span), the reference row is used as is — references are normally generated on the
//!   solution's grid, so nothing is interpolated;
//! * otherwise a column `c` with a velocity column `c_dot` in the reference is
//!   interpolated with the cubic Hermite polynomial of the bracketing pair (values and
//!   derivatives: error `O(Δt⁴)`), and every other column with the cubic Lagrange
//!   polynomial through the four nearest reference rows (also `O(Δt⁴)`).
//!
//! Solution times outside the reference's time range are an error: nothing is
//! extrapolated.
//!
//! **Place in the flow.** A consumer of results, after the output: it uses
//! [`scene`](crate::scene), [`discrete`](crate::discrete) (the trajectory's columns and
//! its cubic Hermite interpolation) and [`output`](crate::output) (the pairing rule
//! every reader checks).

// `!(a <= b)` on purpose: a NaN must fail every check, not pass it.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::discrete::interpolate::{segment, Hermite};
use crate::discrete::trajectory::Trajectory;
use crate::scene::Scene;

/// Errors of reading or comparing tables.
#[derive(Debug, thiserror::Error)]
pub enum CheckError {
    /// The file cannot be read.
    #[error("cannot read {path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why (part of the message, not its `source`).
        error: std::io::Error,
    },
    /// A line of the table is malformed.
    #[error("{path}:{line}: {message}")]
    Parse {
        /// The file.
        path: String,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The table as a whole is unusable (no header, no rows).
    #[error("{path}: {message}")]
    Invalid {
        /// The file.
        path: String,
        /// What is wrong.
        message: String,
    },
    /// The two tables cannot be compared (no shared column, times out of range, …).
    #[error("cannot compare: {0}")]
    Mismatch(String),
    /// The file does not belong to the `summary.json` beside it
    /// ([`crate::output::verify_pairing`]).
    #[error(transparent)]
    Unpaired(#[from] crate::output::OutputError),
}

/// A numeric table read from CSV. The first column is `t`; `#` lines are comments.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// Column names, `t` first.
    pub columns: Vec<String>,
    /// Comment lines without their leading `#` and one following space.
    pub comments: Vec<String>,
    /// One row per time, in the order of `columns`.
    pub rows: Vec<Vec<f64>>,
}

impl Table {
    /// A trajectory as the table its CSV would hold (no comments).
    pub fn of_trajectory(scene: &Scene, tr: &Trajectory) -> Table {
        Table {
            columns: crate::discrete::trajectory::trajectory_header(scene),
            comments: Vec::new(),
            rows: crate::discrete::trajectory::trajectory_rows(tr),
        }
    }

    /// Read a table; errors name the file and line. A file that the `summary.json`
    /// beside it lists must be the one it lists (the pairing rule of [`crate::output`]).
    pub fn read(path: &Path) -> Result<Table, CheckError> {
        Ok(Table::read_paired(path)?.0)
    }

    /// Read a table as [`Table::read`] does, with how it stands to the `summary.json`
    /// beside it: a reader of a run's solution warns when it is not
    /// [`Pairing::Listed`](crate::output::Pairing) ([`Pairing::warning`](crate::output::Pairing::warning)).
    pub fn read_paired(path: &Path) -> Result<(Table, crate::output::Pairing), CheckError> {
        let text = std::fs::read_to_string(path).map_err(|error| CheckError::Io { path: path.to_path_buf(), error })?;
        let pairing = crate::output::verify_pairing(path, text.as_bytes())?;
        Ok((Table::parse(&text, &path.display().to_string())?, pairing))
    }

    /// Parse the text of a table (`origin` names it in errors).
    pub fn parse(text: &str, origin: &str) -> Result<Table, CheckError> {
        let perr = |line: usize, message: String| CheckError::Parse { path: origin.to_string(), line, message };
        let mut comments = Vec::new();
        let mut columns: Option<Vec<String>> = None;
        let mut rows: Vec<Vec<f64>> = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line_no = i + 1;
            let line = raw.trim_end_matches('\r');
            if let Some(c) = line.strip_prefix('#') {
                comments.push(c.strip_prefix(' ').unwrap_or(c).to_string());
                continue;
            }
            if line.trim().is_empty() {
                continue;
            }
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            match &columns {
                None => {
                    if fields[0] != "t" {
                        return Err(perr(line_no, format!("the first column must be `t`, found `{}`", fields[0])));
                    }
                    for (k, f) in fields.iter().enumerate() {
                        if f.is_empty() {
                            return Err(perr(line_no, format!("column {} has an empty name", k + 1)));
                        }
                        if fields[..k].contains(f) {
                            return Err(perr(line_no, format!("column `{f}` appears twice")));
                        }
                    }
                    columns = Some(fields.iter().map(|s| s.to_string()).collect());
                }
                Some(cols) => {
                    if fields.len() != cols.len() {
                        return Err(perr(line_no, format!("{} fields, but the header has {} columns", fields.len(), cols.len())));
                    }
                    let mut row = Vec::with_capacity(fields.len());
                    for (k, f) in fields.iter().enumerate() {
                        let x: f64 = f.parse().map_err(|_| perr(line_no, format!("column `{}`: `{f}` is not a number", cols[k])))?;
                        row.push(x);
                    }
                    if !row[0].is_finite() {
                        return Err(perr(line_no, format!("time `{}` is not finite", fields[0])));
                    }
                    if let Some(prev) = rows.last() {
                        if !(row[0] > prev[0]) {
                            return Err(perr(line_no, format!("times must increase strictly: t = {} follows t = {}", row[0], prev[0])));
                        }
                    }
                    rows.push(row);
                }
            }
        }
        let columns =
            columns.ok_or_else(|| CheckError::Invalid { path: origin.to_string(), message: "no header line (expected `t,...`)".into() })?;
        if rows.is_empty() {
            return Err(CheckError::Invalid { path: origin.to_string(), message: "no data rows".into() });
        }
        Ok(Table { columns, comments, rows })
    }

    /// The values of column `name`, if present.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let k = self.index(name)?;
        Some(self.rows.iter().map(|r| r[k]).collect())
    }

    /// Position of column `name`.
    pub fn index(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }

    /// The times (first column).
    pub fn times(&self) -> Vec<f64> {
        self.rows.iter().map(|r| r[0]).collect()
    }
}

/// What to compare.
#[derive(Debug, Clone, Default, Serialize)]
pub struct CheckOptions {
    /// Leave out the last `skip_last` rows of the solution (e.g. the end nodes whose
    /// constraint is not enforced, docs/solver.md).
    pub skip_last: usize,
    /// Columns to compare; `None` = every column both tables share except `t`.
    pub columns: Option<Vec<String>>,
}

/// Error of one column.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ColumnError {
    /// The column's name.
    pub column: String,
    /// max |solution − reference| over the compared rows.
    pub max_abs: f64,
    /// Root mean square of the difference over the compared rows.
    pub rms: f64,
    /// Time of the largest difference.
    pub at_t: f64,
}

/// Result of [`compare`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Comparison {
    /// Errors of each compared column.
    pub columns: Vec<ColumnError>,
    /// Largest `max_abs` over the compared columns.
    pub max_abs: f64,
    /// Column of the largest error.
    pub worst_column: String,
    /// Solution rows compared (after `skip_last`).
    pub rows_compared: usize,
    /// Last solution rows left out.
    pub skipped_last: usize,
    /// Rows where the reference had to be interpolated (0 when the grids coincide).
    pub rows_interpolated: usize,
    /// Solution columns absent from the reference (not compared).
    pub missing_in_reference: Vec<String>,
}

/// Acceptance thresholds for a [`Comparison`].
#[derive(Debug, Clone, Default, Serialize)]
pub struct Tolerances {
    /// Bound on every compared column's max |error|.
    pub max_abs: Option<f64>,
    /// Bound on every compared column's RMS error.
    pub rms: Option<f64>,
    /// Per-column bounds on max |error| (take precedence over `max_abs`).
    pub per_column: Vec<(String, f64)>,
}

impl Comparison {
    /// Human-readable list of the exceeded tolerances (empty: passed). A per-column
    /// tolerance naming a column that was not compared is reported too.
    pub fn violations(&self, tol: &Tolerances) -> Result<Vec<String>, CheckError> {
        for (name, _) in &tol.per_column {
            if !self.columns.iter().any(|c| &c.column == name) {
                let compared: Vec<&str> = self.columns.iter().map(|c| c.column.as_str()).collect();
                return Err(CheckError::Mismatch(format!(
                    "a tolerance is given for column `{name}`, which is not compared (compared: {})",
                    compared.join(", ")
                )));
            }
        }
        let mut out = Vec::new();
        for c in &self.columns {
            let bound = tol.per_column.iter().find(|(n, _)| n == &c.column).map(|(_, b)| *b).or(tol.max_abs);
            if let Some(b) = bound {
                if !(c.max_abs <= b) {
                    out.push(format!("{}: max error {:.3e} at t = {} exceeds {:.3e}", c.column, c.max_abs, c.at_t, b));
                }
            }
            if let Some(b) = tol.rms {
                if !(c.rms <= b) {
                    out.push(format!("{}: RMS error {:.3e} exceeds {:.3e}", c.column, c.rms, b));
                }
            }
        }
        Ok(out)
    }
}

/// Compare `solution` with `reference` evaluated at the solution's times.
pub fn compare(solution: &Table, reference: &Table, opts: &CheckOptions) -> Result<Comparison, CheckError> {
    let names = compared_columns(solution, reference, opts)?;
    let missing_in_reference = solution.columns[1..].iter().filter(|c| reference.index(c).is_none()).cloned().collect();
    let (rows, eps) = compared_rows(solution, reference, opts)?;
    let (columns, rows_interpolated) = column_errors(solution, reference, &names, rows, eps);
    let worst = columns
        .iter()
        .max_by(|a, b| {
            // NaN sorts as the largest.
            a.max_abs.partial_cmp(&b.max_abs).unwrap_or(if a.max_abs.is_nan() {
                std::cmp::Ordering::Greater
            } else {
                std::cmp::Ordering::Less
            })
        })
        .expect("at least one column");
    Ok(Comparison {
        max_abs: worst.max_abs,
        worst_column: worst.column.clone(),
        rows_compared: rows.len(),
        skipped_last: opts.skip_last,
        rows_interpolated,
        missing_in_reference,
        columns,
    })
}

/// The columns to compare: those asked for, each in both tables and not `t`, or every
/// column both share besides `t`; at least one.
fn compared_columns(solution: &Table, reference: &Table, opts: &CheckOptions) -> Result<Vec<String>, CheckError> {
    let names: Vec<String> = match &opts.columns {
        Some(cols) => {
            if cols.is_empty() {
                return Err(CheckError::Mismatch("the list of columns to compare is empty".into()));
            }
            for c in cols {
                if c == "t" {
                    return Err(CheckError::Mismatch("`t` is the abscissa and cannot be compared".into()));
                }
                if solution.index(c).is_none() {
                    return Err(CheckError::Mismatch(format!(
                        "column `{c}` is not in the solution (its columns: {})",
                        solution.columns.join(", ")
                    )));
                }
                if reference.index(c).is_none() {
                    return Err(CheckError::Mismatch(format!(
                        "column `{c}` is not in the reference (its columns: {})",
                        reference.columns.join(", ")
                    )));
                }
            }
            cols.clone()
        }
        None => solution.columns[1..].iter().filter(|c| reference.index(c).is_some()).cloned().collect(),
    };
    if names.is_empty() {
        return Err(CheckError::Mismatch(format!(
            "the tables share no column besides t (solution: {}; reference: {})",
            solution.columns.join(", "),
            reference.columns.join(", ")
        )));
    }
    Ok(names)
}

/// The solution's rows to compare (the last `skip_last` left out, at least one left),
/// each inside the reference's time range, and the tolerance `eps` within which two
/// times are the same (`1e-12` relative to the time span).
fn compared_rows<'a>(solution: &'a Table, reference: &Table, opts: &CheckOptions) -> Result<(&'a [Vec<f64>], f64), CheckError> {
    let n_rows = solution.rows.len();
    if opts.skip_last >= n_rows {
        return Err(CheckError::Mismatch(format!(
            "skipping the last {} rows leaves nothing of the solution's {} rows",
            opts.skip_last, n_rows
        )));
    }
    let rows = &solution.rows[..n_rows - opts.skip_last];
    let rt = reference.times();
    let (r0, r1) = (rt[0], rt[rt.len() - 1]);
    let span = (r1 - r0).abs().max(rows[rows.len() - 1][0].abs()).max(1.0);
    let eps = 1e-12 * span;
    if let Some(bad) = rows.iter().find(|r| r[0] < r0 - eps || r[0] > r1 + eps) {
        return Err(CheckError::Mismatch(format!(
            "solution time t = {} lies outside the reference's time range [{r0}, {r1}] (nothing is extrapolated)",
            bad[0]
        )));
    }
    Ok((rows, eps))
}

/// The error of each column `names` over the solution's `rows` against the reference
/// evaluated at their times, and how many rows needed the reference interpolated.
fn column_errors(solution: &Table, reference: &Table, names: &[String], rows: &[Vec<f64>], eps: f64) -> (Vec<ColumnError>, usize) {
    let rt = reference.times();
    let cols_ref: Vec<usize> = names.iter().map(|c| reference.index(c).expect("checked")).collect();
    let cols_sol: Vec<usize> = names.iter().map(|c| solution.index(c).expect("checked")).collect();
    let derivs: Vec<Option<usize>> = names.iter().map(|c| reference.index(&format!("{c}_dot"))).collect();
    let mut max_abs = vec![0.0_f64; names.len()];
    let mut at_t = vec![rows[0][0]; names.len()];
    let mut sum_sq = vec![0.0_f64; names.len()];
    let mut rows_interpolated = 0;
    for row in rows {
        let t = row[0];
        let (j, exact) = reference_rows_at(&rt, t, eps);
        if exact.is_none() {
            rows_interpolated += 1;
        }
        for (c, (&kr, &ks)) in cols_ref.iter().zip(&cols_sol).enumerate() {
            let r = match exact {
                Some(i) => reference.rows[i][kr],
                None => match derivs[c] {
                    Some(kd) => hermite(reference, j, kr, kd, t),
                    None => lagrange4(reference, j, kr, t),
                },
            };
            let e = row[ks] - r;
            let ae = e.abs();
            // NaN counts as the worst error.
            if ae > max_abs[c] || (ae.is_nan() && !max_abs[c].is_nan()) {
                max_abs[c] = ae;
                at_t[c] = t;
            }
            sum_sq[c] += e * e;
        }
    }
    let m = rows.len() as f64;
    let columns = names
        .iter()
        .enumerate()
        .map(|(c, name)| ColumnError { column: name.clone(), max_abs: max_abs[c], rms: (sum_sq[c] / m).sqrt(), at_t: at_t[c] })
        .collect();
    (columns, rows_interpolated)
}

/// The reference interval `[rt[j], rt[j+1]]` that holds `t`, and the reference row at
/// `t` itself (within `eps`), if there is one.
fn reference_rows_at(rt: &[f64], t: f64, eps: f64) -> (usize, Option<usize>) {
    let j = segment(rt, t);
    let exact = if (rt[j] - t).abs() <= eps {
        Some(j)
    } else if j + 1 < rt.len() && (rt[j + 1] - t).abs() <= eps {
        Some(j + 1)
    } else {
        None
    };
    (j, exact)
}

/// Cubic Hermite interpolation of column `k` (derivative column `kd`) on the reference
/// interval starting at row `j`.
fn hermite(tab: &Table, j: usize, k: usize, kd: usize, t: f64) -> f64 {
    let (a, b) = (&tab.rows[j], &tab.rows[j + 1]);
    Hermite::new(a[0], b[0], t).eval(a[k], a[kd], b[k], b[kd])
}

/// Cubic Lagrange interpolation of column `k` through the four reference rows nearest
/// to the interval starting at row `j` (fewer rows: the polynomial through all of them).
fn lagrange4(tab: &Table, j: usize, k: usize, t: f64) -> f64 {
    let n = tab.rows.len();
    let m = n.min(4);
    let start = j.saturating_sub(1).min(n - m);
    let pts = &tab.rows[start..start + m];
    let mut acc = 0.0;
    for (i, pi) in pts.iter().enumerate() {
        let mut w = 1.0;
        for (l, pl) in pts.iter().enumerate() {
            if l != i {
                w *= (t - pl[0]) / (pi[0] - pl[0]);
            }
        }
        acc += w * pi[k];
    }
    acc
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(cols: &[&str], f: impl Fn(f64) -> Vec<f64>, times: &[f64]) -> Table {
        Table {
            columns: cols.iter().map(|s| s.to_string()).collect(),
            comments: vec![],
            rows: times
                .iter()
                .map(|&t| {
                    let mut r = vec![t];
                    r.extend(f(t));
                    r
                })
                .collect(),
        }
    }

    fn lin(a: f64, b: f64, n: usize) -> Vec<f64> {
        (0..n).map(|k| a + (b - a) * k as f64 / (n - 1) as f64).collect()
    }

    #[test]
    fn parse_comments_and_errors() {
        let t = Table::parse("# provenance: x\n#y\nt,x,x_dot\n0,1,2\n0.5,1.5,2.5\n", "mem").unwrap();
        assert_eq!(t.comments, vec!["provenance: x", "y"]);
        assert_eq!(t.columns, vec!["t", "x", "x_dot"]);
        assert_eq!(t.column("x_dot"), Some(vec![2.0, 2.5]));
        assert_eq!(t.column("y"), None);
        let e = Table::parse("t,x\n0,1\n0,2\n", "f.csv").unwrap_err().to_string();
        assert!(e.contains("f.csv:3") && e.contains("increase strictly"), "{e}");
        let e = Table::parse("t,x\n0,1,3\n", "f.csv").unwrap_err().to_string();
        assert!(e.contains("f.csv:2") && e.contains("3 fields"), "{e}");
        let e = Table::parse("t,x\n0,abc\n", "f.csv").unwrap_err().to_string();
        assert!(e.contains("`abc` is not a number"), "{e}");
        let e = Table::parse("x,t\n0,1\n", "f.csv").unwrap_err().to_string();
        assert!(e.contains("first column must be `t`"), "{e}");
        assert!(Table::parse("# only\n", "f.csv").unwrap_err().to_string().contains("no header"));
        assert!(Table::parse("t,x\n", "f.csv").unwrap_err().to_string().contains("no data rows"));
        assert!(Table::parse("t,x,x\n0,1,1\n", "f.csv").unwrap_err().to_string().contains("twice"));
        let e = Table::read(Path::new("/nonexistent/ref.csv")).unwrap_err();
        // The operating system's reason is said once: in the message, not again as a source.
        assert!(e.to_string().contains("/nonexistent/ref.csv: No such file"), "{e}");
        assert!(std::error::Error::source(&e).is_none(), "{e}");
    }

    #[test]
    fn same_grid_is_exact_and_errors_are_per_column() {
        let times = lin(0.0, 1.0, 11);
        let r = table(&["t", "x", "x_dot", "energy"], |t| vec![t.sin(), t.cos(), 1.0], &times);
        let s = table(&["t", "x", "x_dot", "energy", "extra"], |t| vec![t.sin() + 1e-3 * t, t.cos(), 1.0 + 2e-6, 0.0], &times);
        let c = compare(&s, &r, &CheckOptions::default()).unwrap();
        assert_eq!(c.rows_interpolated, 0);
        assert_eq!(c.missing_in_reference, vec!["extra"]);
        let names: Vec<_> = c.columns.iter().map(|c| c.column.as_str()).collect();
        assert_eq!(names, vec!["x", "x_dot", "energy"]);
        assert!((c.columns[0].max_abs - 1e-3).abs() < 1e-15);
        assert_eq!(c.columns[0].at_t, 1.0);
        let rms: f64 = (times.iter().map(|t| (1e-3 * t).powi(2)).sum::<f64>() / 11.0).sqrt();
        assert!((c.columns[0].rms - rms).abs() < 1e-15);
        assert_eq!(c.columns[1].max_abs, 0.0);
        assert_eq!(c.worst_column, "x");
        // Skipping the last row moves the maximum.
        let c2 = compare(&s, &r, &CheckOptions { skip_last: 1, columns: Some(vec!["x".into()]) }).unwrap();
        assert_eq!(c2.columns.len(), 1);
        assert!((c2.columns[0].at_t - 0.9).abs() < 1e-15);
        assert_eq!(c2.rows_compared, 10);
        // Tolerances.
        let tol = Tolerances { max_abs: Some(1e-6), rms: None, per_column: vec![("x".into(), 2e-3)] };
        let v = c.violations(&tol).unwrap();
        assert_eq!(v.len(), 1, "{v:?}");
        assert!(v[0].starts_with("energy"), "{v:?}");
        assert!(c.violations(&Tolerances { max_abs: Some(1e-2), ..Default::default() }).unwrap().is_empty());
        assert_eq!(c.violations(&Tolerances { rms: Some(1e-4), ..Default::default() }).unwrap().len(), 1);
        // A tolerance for a column that is not compared is an error, not a violation.
        let unknown = Tolerances { per_column: vec![("y".into(), 1e-3)], ..Default::default() };
        let e = c.violations(&unknown).unwrap_err().to_string();
        assert!(e.contains("`y`") && e.contains("x, x_dot, energy"), "{e}");
    }

    #[test]
    fn interpolation_is_fourth_order() {
        // Reference on a coarse grid, solution on a finer, offset grid: the error of the
        // interpolant must shrink ~16x per halving of the reference spacing.
        let f = |t: f64| vec![(3.0 * t).sin(), 3.0 * (3.0 * t).cos(), (2.0 * t).exp()];
        let sol_t = lin(0.0, 1.0, 37);
        let sol = table(&["t", "x", "x_dot", "energy"], f, &sol_t);
        let mut prev: Option<(f64, f64)> = None;
        for n in [11, 21, 41, 81] {
            let r = table(&["t", "x", "x_dot", "energy"], f, &lin(0.0, 1.0, n));
            let c = compare(&sol, &r, &CheckOptions::default()).unwrap();
            assert!(c.rows_interpolated > 0);
            let (ex, ee) = (c.columns[0].max_abs, c.columns[2].max_abs);
            if let Some((px, pe)) = prev {
                assert!(px / ex > 12.0, "hermite ratio {}", px / ex);
                assert!(pe / ee > 12.0, "lagrange ratio {}", pe / ee);
            }
            prev = Some((ex, ee));
        }
        assert!(prev.unwrap().0 < 1e-7);
    }

    #[test]
    fn mismatches_are_errors() {
        let r = table(&["t", "x"], |t| vec![t], &lin(0.0, 1.0, 5));
        let s = table(&["t", "y"], |t| vec![t], &lin(0.0, 1.0, 5));
        assert!(compare(&s, &r, &CheckOptions::default()).unwrap_err().to_string().contains("share no column"));
        let s = table(&["t", "x"], |t| vec![t], &lin(0.0, 1.5, 5));
        assert!(compare(&s, &r, &CheckOptions::default()).unwrap_err().to_string().contains("outside"));
        let s = table(&["t", "x"], |t| vec![t], &lin(0.0, 1.0, 5));
        let e = compare(&s, &r, &CheckOptions { skip_last: 0, columns: Some(vec!["z".into()]) }).unwrap_err();
        assert!(e.to_string().contains("`z` is not in the solution"), "{e}");
        assert!(compare(&s, &r, &CheckOptions { skip_last: 5, columns: None }).is_err());
        // NaN in the solution is the worst error, not silently ignored.
        let mut s2 = s.clone();
        s2.rows[2][1] = f64::NAN;
        let c = compare(&s2, &r, &CheckOptions::default()).unwrap();
        assert!(c.max_abs.is_nan());
        assert_eq!(c.violations(&Tolerances { max_abs: Some(1.0), ..Default::default() }).unwrap().len(), 1);
    }
}
