//! Results as NumPy arrays: a node series as an N×d matrix, a vector, and a trajectory
//! as the dict of arrays and names that `skg.Trajectory` is made from.

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use skg_core::discrete::trajectory::{trajectory_header, trajectory_rows, NodeSeries, Trajectory};
use skg_core::scene::{ConstraintKind, Scene};

/// A `NodeSeries` (`rows[k][i]`) as an N×d array (d may be 0).
pub(crate) fn matrix<'py>(py: Python<'py>, rows: &NodeSeries, width: usize) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = rows.iter().flat_map(|r| r.iter().copied()).collect();
    Array2::from_shape_vec((rows.len(), width), flat).expect("rows of equal width").into_pyarray(py)
}

pub(crate) fn vector<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, v)
}

/// A trajectory of `scene` as a dict: the arrays `t`, `q`, `v`, `lambda`, `energy`,
/// `wall_energy`, `g`, `drift`, `h`; the names `coordinates`, `constraints`,
/// `positions` (the position constraints), `walls`; and `columns` with `table`, the
/// trajectory CSV's header and rows (N×C).
pub(crate) fn trajectory_dict<'py>(py: Python<'py>, scene: &Scene, tr: &Trajectory) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let (nq, nc, nw) = (scene.coordinates.len(), scene.constraints.len(), scene.walls.len());
    let positions: Vec<&str> = scene.constraints.iter().filter(|c| c.kind == ConstraintKind::Position).map(|c| c.name.as_str()).collect();
    d.set_item("t", vector(py, &tr.t))?;
    d.set_item("q", matrix(py, &tr.q, nq))?;
    d.set_item("v", matrix(py, &tr.v, nq))?;
    d.set_item("lambda", matrix(py, &tr.lambda, nc))?;
    d.set_item("energy", vector(py, &tr.energy))?;
    d.set_item("wall_energy", vector(py, &tr.wall_energy))?;
    d.set_item("g", matrix(py, &tr.g, nc))?;
    d.set_item("drift", matrix(py, &tr.drift, positions.len()))?;
    d.set_item("h", matrix(py, &tr.h, nw))?;
    d.set_item("coordinates", PyList::new(py, &scene.coordinates)?)?;
    d.set_item("constraints", PyList::new(py, scene.constraints.iter().map(|c| c.name.as_str()))?)?;
    d.set_item("positions", PyList::new(py, positions)?)?;
    d.set_item("walls", PyList::new(py, scene.walls.iter().map(|w| w.name.as_str()))?)?;
    let header = trajectory_header(scene);
    let rows = trajectory_rows(tr);
    d.set_item("table", matrix(py, &rows, header.len()))?;
    d.set_item("columns", PyList::new(py, header)?)?;
    d.set_item("scene", &scene.name)?;
    Ok(d)
}
