//! Reading a sweep's results for the charts: a cell as a number ([`cell_value`]), the
//! rows that pass the `--where` filters, the columns by name, an axis's distinct values
//! with their labels, the converged SKG points grouped into lines, and the kept
//! trajectories of a sweep ([`sweep_solutions`]). Uses `skg_sweep::Results` and
//! `skg_core::check::Table`; draws nothing.

use std::collections::BTreeMap;
use std::path::Path;

use skg_core::check::Table;
use skg_sweep::Results;

use crate::PlotError;

/// Numeric value of a results cell: a number or a constant expression (`1/110`, `pi/6`).
pub fn cell_value(s: &str) -> Option<f64> {
    let s = s.trim();
    if s.is_empty() {
        return None;
    }
    s.parse::<f64>().ok().or_else(|| skg_core::scene::eval_constant(s, &indexmap::IndexMap::new()).ok()).filter(|x| x.is_finite())
}

/// Whether two numbers are equal to a relative tolerance of 1e-12.
fn same_number(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * a.abs().max(b.abs())
}

/// Whether a row's cell in `column` matches a `--where` value: equal as text, as written
/// in the sweep file (the `<column>_expr` cell), or as numbers (the value may be a
/// constant expression: `sigma=1/110` matches the cell 0.00909090909090909).
fn cell_matches(res: &Results, row: &[String], column: usize, value: &str) -> bool {
    let cell = &row[column];
    cell == value
        || res.written(row, column) == value
        || matches!((cell_value(cell), cell_value(value)), (Some(a), Some(b)) if same_number(a, b))
}

/// Rows of a results table that satisfy every `column=value` filter ([`cell_matches`]).
/// A row that leaves the column blank is kept: the peer rows have no scene parameters,
/// and they belong on every chart of the same scene.
pub(crate) fn filtered<'a>(res: &'a Results, filters: &[(String, String)]) -> Result<Vec<&'a Vec<String>>, PlotError> {
    let mut idx = Vec::new();
    for (k, v) in filters {
        let i = res
            .column_index(k)
            .ok_or_else(|| PlotError::Data(format!("--where {k}={v}: no column `{k}` (columns: {})", res.header.join(", "))))?;
        idx.push((i, v.as_str()));
    }
    Ok(res.rows.iter().filter(|r| idx.iter().all(|&(i, v)| r[i].is_empty() || cell_matches(res, r, i, v))).collect())
}

pub(crate) fn col(res: &Results, name: &str) -> Result<usize, PlotError> {
    res.column_index(name).ok_or_else(|| PlotError::Data(format!("the results have no `{name}` column: not a sweep's results.csv?")))
}

/// Points (x, y, N) of each line, by label.
pub(crate) type Groups = BTreeMap<String, Vec<(f64, f64, f64)>>;

/// Group the converged SKG rows by "operator formulation", by the initial velocity
/// condition when the sweep has that axis, and with `by_backend` also by backend when the
/// sweep has that axis: (label, [(x, y, nodes)]).
pub(crate) fn skg_groups(res: &Results, rows: &[&Vec<String>], x: &str, y: &str, by_backend: bool) -> Result<Groups, PlotError> {
    let (im, io, ifm, inodes, ix, iy) =
        (col(res, "method")?, col(res, "operator")?, col(res, "formulation")?, col(res, "nodes")?, col(res, x)?, col(res, y)?);
    let ib = col(res, "backend").ok().filter(|_| by_backend);
    let iv = col(res, "initial_velocity").ok();
    let mut groups: Groups = BTreeMap::new();
    for r in rows {
        if r[im] != "skg" || !res.status(r)?.is_converged() {
            continue;
        }
        if let (Some(xv), Some(yv), Some(n)) = (cell_value(&r[ix]), cell_value(&r[iy]), cell_value(&r[inodes])) {
            let optional = |i: Option<usize>| i.map_or(String::new(), |i| format!(" {}", r[i]));
            let label = format!("{} {}{}{}", r[io], r[ifm], optional(iv), optional(ib));
            groups.entry(label).or_default().push((xv, yv, n));
        }
    }
    for v in groups.values_mut() {
        v.sort_by(|a, b| a.2.total_cmp(&b.2));
    }
    Ok(groups)
}

/// The distinct values of a column among `rows` as (cell, label): the label is the
/// value as the sweep file wrote it (`1/110` for the cell 0.00909090909090909). Sorted
/// numerically where the cells are numbers.
pub(crate) fn axis_values(res: &Results, rows: &[&Vec<String>], column: usize) -> Vec<(String, String)> {
    let mut v: Vec<(String, String)> = rows.iter().map(|r| (r[column].clone(), res.written(r, column).to_string())).collect();
    v.sort();
    v.dedup_by(|a, b| a.0 == b.0);
    v.sort_by(|a, b| match (cell_value(&a.0), cell_value(&b.0)) {
        (Some(x), Some(y)) => x.total_cmp(&y),
        _ => a.0.cmp(&b.0),
    });
    v
}

/// The kept trajectories of a sweep (`sweep.keep_trajectories = true`), each labelled
/// with the values of the columns that vary between points (ODE peer points excluded).
pub fn sweep_solutions(dir: &Path) -> Result<Vec<(String, Table)>, PlotError> {
    let res = Results::read(dir)?;
    let (id, im) = (col(&res, "id")?, col(&res, "method")?);
    let first = col(&res, "nodes")?;
    let last = col(&res, "converged")?;
    let rows: Vec<&Vec<String>> = res.rows.iter().filter(|r| r[im] == "skg").collect();
    // The settings and axes that vary (an axis's `_expr` column varies with it).
    let varying: Vec<usize> = (first..last).filter(|&c| !res.is_expr_column(c) && rows.iter().any(|r| r[c] != rows[0][c])).collect();
    let mut out = Vec::new();
    for r in rows {
        let file = dir.join("points").join(&r[id]).join("trajectory.csv");
        if !file.is_file() {
            continue;
        }
        let t = Table::read(&file)?;
        let label = varying.iter().map(|&c| format!("{}={}", res.header[c], res.written(r, c))).collect::<Vec<_>>().join(", ");
        out.push((if label.is_empty() { r[id].clone() } else { label }, t));
    }
    if out.is_empty() {
        return Err(PlotError::Data(format!("{} has no kept trajectories (set `keep_trajectories = true` under [sweep])", dir.display())));
    }
    Ok(out)
}
