//! `solve`: a scene solved as `skg-solve SCENE` does (into a directory with `out=`, as
//! `skg-solve SCENE -o OUT`), and `NativeSolution`, the outcome that `skg.Solution` wraps
//! (its trajectory, summary and statuses, and the writing of its files).

use std::path::PathBuf;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use skg_core::output;
use skg_core::scene::{Backend, Formulation, HessianMode, InitialVelocity, Overrides, Scene};
use skg_core::solve::{self, Outcome};

use crate::arrays::trajectory_dict;
use crate::errors::{output_err, solve_err, solve_into_err};
use crate::scene::{assignments, load, SceneArg};

/// The result of [`solve`]: the outcome, the scene it solved and the files last written,
/// so that `write` produces exactly the files of the command line and `summary` lists them.
#[pyclass(module = "skg._skg", frozen)]
pub(crate) struct NativeSolution {
    scene: Scene,
    state: std::sync::Mutex<(Outcome, Option<output::Written>)>,
}

#[pymethods]
impl NativeSolution {
    /// The trajectory as a dict of arrays ([`trajectory_dict`]).
    fn trajectory<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (o, _) = &*self.state.lock().expect("not poisoned");
        trajectory_dict(py, &self.scene, &o.trajectory)
    }

    /// The verification's time-stepping reference at the same nodes, or None.
    fn reference<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let (o, _) = &*self.state.lock().expect("not poisoned");
        o.verification.reference_trajectory.as_ref().map(|r| trajectory_dict(py, &self.scene, r)).transpose()
    }

    /// summary.json's content as a dict, its keys in the file's order (`files`: those of
    /// the last write, else empty).
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let (o, written) = &*self.state.lock().expect("not poisoned");
        let text = output::summary_json(o, &self.scene, written.as_ref()).map_err(|e| PyValueError::new_err(e.to_string()))?;
        py.import("json")?.call_method1("loads", (text,))
    }

    /// Whether the solve converged.
    #[getter]
    fn converged(&self) -> bool {
        self.state.lock().expect("not poisoned").0.converged()
    }

    /// Converged and verified (exit status 0 of the command line).
    #[getter]
    fn trusted(&self) -> bool {
        self.state.lock().expect("not poisoned").0.trusted()
    }

    /// Write trajectory.csv, reference.csv and summary.json into `dir` as the command line
    /// does, holding the directory's lock meanwhile; returns the paths written.
    fn write(&self, py: Python<'_>, dir: PathBuf) -> PyResult<Vec<PathBuf>> {
        let written = py.detach(|| {
            let _lock = output::OutputDir::lock(&dir)?;
            let (o, written) = &mut *self.state.lock().expect("not poisoned");
            let w = output::write_outcome(&dir, o, &self.scene)?;
            Ok::<_, output::OutputError>(written.insert(w).paths().cloned().collect())
        });
        written.map_err(|e| output_err(py, &e))
    }
}

/// Solve a scene file (or a [`NativeScene`]) as `skg-solve SCENE` does; with `out`, into that directory as
/// `skg-solve SCENE -o OUT` does ([`output::solve_into`]), else without writing files.
#[pyfunction]
#[pyo3(signature = (path, *, out=None, nodes=None, set=None, operator=None, formulation=None, initial_velocity=None,
    hessian=None, max_iter=None, backend=None, window=None, overlap=None, verify_tol=None, no_verify=false, no_fallback=false,
    refine=false, max_nodes=None, time_limit=None))]
#[pyo3(name = "solve")]
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve_scene(
    py: Python<'_>,
    path: SceneArg,
    out: Option<PathBuf>,
    nodes: Option<usize>,
    set: Option<&Bound<'_, PyDict>>,
    operator: Option<&str>,
    formulation: Option<&str>,
    initial_velocity: Option<&str>,
    hessian: Option<&str>,
    max_iter: Option<u32>,
    backend: Option<&str>,
    window: Option<f64>,
    overlap: Option<f64>,
    verify_tol: Option<f64>,
    no_verify: bool,
    no_fallback: bool,
    refine: bool,
    max_nodes: Option<usize>,
    time_limit: Option<f64>,
) -> PyResult<NativeSolution> {
    let auto_operator = operator.is_some_and(|s| s.trim().eq_ignore_ascii_case("auto"));
    let operator = operator
        .filter(|_| !auto_operator)
        .map(|s| s.parse().map_err(|e| PyValueError::new_err(format!("operator: {e}, or \"auto\""))))
        .transpose()?;
    if max_nodes.is_some_and(|n| n < 2) {
        return Err(PyValueError::new_err("max_nodes: must be at least 2"));
    }
    if time_limit.is_some_and(|t| !(t > 0.0 && t.is_finite())) {
        return Err(PyValueError::new_err("time_limit: must be a positive number of seconds"));
    }
    let formulation: Option<Formulation> =
        formulation.map(|s| s.parse().map_err(|e| PyValueError::new_err(format!("formulation: {e}")))).transpose()?;
    let initial_velocity: Option<InitialVelocity> =
        initial_velocity.map(|s| s.parse().map_err(|e| PyValueError::new_err(format!("initial_velocity: {e}")))).transpose()?;
    let hessian = match hessian {
        None => None,
        Some("zero") => Some(HessianMode::Zero),
        Some("exact") => Some(HessianMode::Exact),
        Some(other) => return Err(PyValueError::new_err(format!("hessian: expected \"zero\" or \"exact\", got \"{other}\""))),
    };
    let backend: Option<Backend> = backend.map(|s| s.parse().map_err(|e| PyValueError::new_err(format!("backend: {e}")))).transpose()?;
    let ov = Overrides {
        set: assignments(set)?,
        backend,
        nodes,
        operator,
        formulation,
        initial_velocity,
        hessian,
        max_iter,
        window,
        overlap,
        verify_tol,
        no_verify,
        no_fallback,
        auto_operator,
        refine,
        max_nodes,
        time_limit,
    };
    let mut scene = load(py, &path, &ov)?;
    let state = match out {
        Some(dir) => {
            let (outcome, written) = py.detach(|| output::solve_into(&dir, &mut scene)).map_err(|e| solve_into_err(py, &e))?;
            (outcome, Some(written))
        }
        None => {
            // Ipopt's log is relative to an output directory, and there is none: a solve
            // that owns no directory writes no log.
            let mut outcome = py.detach(|| solve::solve_scene(&scene)).map_err(|e| solve_err(py, &e))?;
            if let Some(name) = &scene.solver.log_file {
                outcome
                    .warnings
                    .push(format!("the scene's [solver] log_file ({}) is written only by a solve into a directory (out=)", name.display()));
            }
            (outcome, None)
        }
    };
    Ok(NativeSolution { scene, state: std::sync::Mutex::new(state) })
}
