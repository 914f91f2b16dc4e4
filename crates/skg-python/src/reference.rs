//! `reference`: a scene integrated by time stepping as `skg-solve reference` does, and
//! `NativeReference`, the result that `skg.Reference` wraps (its trajectory, what was
//! computed, and the writing of its CSV).

use std::path::PathBuf;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use skg_core::output;
use skg_core::scene::{Overrides, Scene, Stepper};
use skg_core::solve;
use skg_core::stepping::reference::{self, Reference, ReferenceOptions};

use crate::arrays::{trajectory_dict, vector};
use crate::errors::{output_err, reference_err};
use crate::scene::{assignments, load, SceneArg};

/// A reference of a scene and what `write` needs to write the command line's CSV.
#[pyclass(module = "skg._skg", frozen)]
pub(crate) struct NativeReference {
    scene: Scene,
    path: String,
    reference: Reference,
}

#[pymethods]
impl NativeReference {
    /// The reference trajectory as a dict of arrays.
    fn trajectory<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        trajectory_dict(py, &self.scene, &self.reference.trajectory)
    }

    /// What was computed: kind, integrator statistics, drifts, impacts, provenance text.
    fn info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = &self.reference;
        let d = PyDict::new(py);
        d.set_item("kind", r.kind.to_string())?;
        d.set_item("rtol", r.options.rtol)?;
        d.set_item("atol", r.options.atol)?;
        d.set_item("steps", r.stats.accepted)?;
        d.set_item("rejected", r.stats.rejected)?;
        d.set_item("constraint_drift", r.constraint_drift)?;
        d.set_item("energy_drift", r.energy_drift)?;
        let impacts = PyList::empty(py);
        for i in &r.impacts {
            let e = PyDict::new(py);
            e.set_item("t", i.t)?;
            e.set_item("wall", &i.wall)?;
            e.set_item("normal_speed", i.normal_speed)?;
            e.set_item("q", vector(py, &i.q))?;
            impacts.append(e)?;
        }
        d.set_item("impacts", impacts)?;
        d.set_item("provenance", reference::provenance(&self.scene, &self.path, r))?;
        Ok(d)
    }

    /// Write the reference CSV (with its `#` provenance lines) as `skg-solve reference` does.
    fn write(&self, py: Python<'_>, path: PathBuf) -> PyResult<PathBuf> {
        py.detach(|| output::write_reference(&path, &self.scene, &self.path, &self.reference)).map_err(|e| output_err(py, &e))?;
        Ok(path)
    }
}

/// Integrate a scene (a file or a [`NativeScene`]) as `skg-solve reference` does (without writing the CSV).
#[pyfunction]
#[pyo3(signature = (path, *, nodes=None, set=None, hard_walls=false, rtol=1e-12, atol=None, times=None, stepper=None))]
#[pyo3(name = "reference")]
#[allow(clippy::too_many_arguments)]
pub(crate) fn integrate_reference(
    py: Python<'_>,
    path: SceneArg,
    nodes: Option<&Bound<'_, PyAny>>,
    set: Option<&Bound<'_, PyDict>>,
    hard_walls: bool,
    rtol: f64,
    atol: Option<f64>,
    times: Option<Vec<f64>>,
    stepper: Option<&str>,
) -> PyResult<NativeReference> {
    if !(rtol > 0.0 && rtol.is_finite()) {
        return Err(PyValueError::new_err(format!("rtol must be a positive number, got {rtol}")));
    }
    let stepper = stepper.map(|s| s.parse::<Stepper>().map_err(|e| PyValueError::new_err(format!("stepper: {e}")))).transpose()?;
    let ov = Overrides { set: assignments(set)?, nodes: crate::solve::node_count(py, "nodes", nodes)?, stepper, ..Overrides::default() };
    let scene = load(py, &path, &ov)?;
    let times = times.unwrap_or_else(|| solve::grid(&scene).0);
    let opts = ReferenceOptions { rtol, atol: atol.unwrap_or(rtol), stepper: scene.verify.stepper };
    let r = py
        .detach(|| if hard_walls { reference::hard_wall(&scene, &times, &opts) } else { reference::regularized(&scene, &times, &opts) })
        .map_err(|e| reference_err(py, &e))?;
    Ok(NativeReference { scene, path: path.label(), reference: r })
}
