//! Reading the files skg-solve writes, as the command line reads them: a sweep's
//! results.csv (`read_results`) and a trajectory CSV (`read_table`).

use std::path::PathBuf;

use numpy::PyArray2;
use pyo3::prelude::*;

use skg_core::check::Table;
use skg_sweep as sweep;

use crate::arrays::matrix;
use crate::errors::{raise, sweep_err};

/// A sweep's results.csv (or its directory), checked as `plot` and `merge` read it:
/// `(header, rows)` with every cell as text.
#[pyfunction]
pub(crate) fn read_results(py: Python<'_>, path: PathBuf) -> PyResult<(Vec<String>, Vec<Vec<String>>)> {
    let r = py.detach(|| sweep::Results::read(&path)).map_err(|e| sweep_err(py, &e))?;
    Ok((r.header, r.rows))
}

/// A trajectory CSV (trajectory.csv, reference.csv, a reference from `skg-solve
/// reference`) as `(columns, table)`, read as `check` and `plot` read it.
#[pyfunction]
pub(crate) fn read_table<'py>(py: Python<'py>, path: PathBuf) -> PyResult<(Vec<String>, Bound<'py, PyArray2<f64>>)> {
    let t = py.detach(|| Table::read(&path)).map_err(|e| raise(py, "InputError", &e))?;
    let width = t.columns.len();
    Ok((t.columns, matrix(py, &t.rows, width)))
}
