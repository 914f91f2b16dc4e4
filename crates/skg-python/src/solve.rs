//! `solve`: a scene solved as `skg-solve SCENE` does (into a directory with `out=`, as
//! `skg-solve SCENE -o OUT`), and `NativeSolution`, the outcome that `skg.Solution` wraps
//! (its trajectory, summary and statuses, and the writing of its files).

use std::path::PathBuf;
use std::str::FromStr;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use skg_core::output;
use skg_core::scene::{HessianMode, Overrides, Scene, MAX_NODES};
use skg_core::solve::{self, Outcome};

use crate::arrays::trajectory_dict;
use crate::errors::{int_keyword, output_err, solve_err, solve_into_err};
use crate::scene::{assignments, load, SceneArg};

/// The result of [`solve`]: the outcome, the scene it solved and the files last written,
/// so that `write` produces exactly the files of the command line and `summary` lists them.
#[pyclass(module = "skg._skg", frozen)]
pub(crate) struct NativeSolution {
    scene: Scene,
    state: std::sync::Mutex<(Outcome, Option<output::Written>)>,
}

impl NativeSolution {
    /// A solution of `scene` (a fit's fitted motion), with the files it was written to.
    pub(crate) fn new(scene: Scene, outcome: Outcome, written: Option<output::Written>) -> NativeSolution {
        NativeSolution { scene, state: std::sync::Mutex::new((outcome, written)) }
    }
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
    refine=false, max_nodes=None, time_limit=None, stepper=None, grid=None))]
#[pyo3(name = "solve")]
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve_scene(
    py: Python<'_>,
    path: SceneArg,
    out: Option<PathBuf>,
    nodes: Option<&Bound<'_, PyAny>>,
    set: Option<&Bound<'_, PyDict>>,
    operator: Option<&str>,
    formulation: Option<&str>,
    initial_velocity: Option<&str>,
    hessian: Option<&str>,
    max_iter: Option<&Bound<'_, PyAny>>,
    backend: Option<&str>,
    window: Option<f64>,
    overlap: Option<f64>,
    verify_tol: Option<f64>,
    no_verify: bool,
    no_fallback: bool,
    refine: bool,
    max_nodes: Option<&Bound<'_, PyAny>>,
    time_limit: Option<f64>,
    stepper: Option<&str>,
    grid: Option<&str>,
) -> PyResult<NativeSolution> {
    let mut ov = Overrides {
        nodes: node_count(py, "nodes", nodes)?,
        max_iter: int_keyword(py, "max_iter", max_iter, (0, i32::MAX as u64), i32::MAX as u64)?.map(|n| n as u32),
        window,
        overlap,
        verify_tol,
        no_verify,
        no_fallback,
        refine,
        max_nodes: node_count(py, "max_nodes", max_nodes)?,
        time_limit,
        ..Overrides::default()
    };
    parse_choices(&mut ov, Choices { operator, formulation, initial_velocity, hessian, backend, stepper, grid })?;
    ov.set = assignments(set)?;
    let mut scene = load(py, &path, &ov)?;
    let state = run(py, &mut scene, out)?;
    Ok(NativeSolution { scene, state: std::sync::Mutex::new(state) })
}

/// A node count given as the keyword `name` (`nodes`, `max_nodes`): any count that fits
/// goes to the scene's own check of its range; one that does not fit (negative, beyond
/// 64 bits) is refused here, naming the keyword.
pub(crate) fn node_count(py: Python<'_>, name: &str, value: Option<&Bound<'_, PyAny>>) -> PyResult<Option<usize>> {
    Ok(int_keyword(py, name, value, (2, MAX_NODES as u64), usize::MAX as u64)?.map(|n| n as usize))
}

/// The options of [`solve_scene`] given as text, parsed as the command line parses them.
struct Choices<'a> {
    operator: Option<&'a str>,
    formulation: Option<&'a str>,
    initial_velocity: Option<&'a str>,
    hessian: Option<&'a str>,
    backend: Option<&'a str>,
    stepper: Option<&'a str>,
    grid: Option<&'a str>,
}

/// Set the overrides given as text (`operator="auto"` asks for the operator predicted to
/// be cheapest) after checking the limits `max_nodes` and `time_limit` already set; a
/// `ValueError` names the first argument that is wrong.
fn parse_choices(ov: &mut Overrides, text: Choices<'_>) -> PyResult<()> {
    ov.auto_operator = text.operator.is_some_and(|s| s.trim().eq_ignore_ascii_case("auto"));
    ov.operator = text
        .operator
        .filter(|_| !ov.auto_operator)
        .map(|s| s.parse().map_err(|e| PyValueError::new_err(format!("operator: {e}, or \"auto\""))))
        .transpose()?;
    if ov.max_nodes.is_some_and(|n| n < 2) {
        return Err(PyValueError::new_err("max_nodes: must be at least 2"));
    }
    if ov.time_limit.is_some_and(|t| !(t > 0.0 && t.is_finite())) {
        return Err(PyValueError::new_err("time_limit: must be a positive number of seconds"));
    }
    ov.formulation = parsed("formulation", text.formulation)?;
    ov.initial_velocity = parsed("initial_velocity", text.initial_velocity)?;
    ov.hessian = match text.hessian {
        None => None,
        Some("zero") => Some(HessianMode::Zero),
        Some("exact") => Some(HessianMode::Exact),
        Some(other) => return Err(PyValueError::new_err(format!("hessian: expected \"zero\" or \"exact\", got \"{other}\""))),
    };
    ov.backend = parsed("backend", text.backend)?;
    ov.stepper = parsed("stepper", text.stepper)?;
    ov.grid = parsed("grid", text.grid)?;
    Ok(())
}

/// The option `name` parsed from its text, or a `ValueError` (`name: why`).
fn parsed<T: FromStr<Err: std::fmt::Display>>(name: &str, text: Option<&str>) -> PyResult<Option<T>> {
    text.map(|s| s.parse().map_err(|e| PyValueError::new_err(format!("{name}: {e}")))).transpose()
}

/// Solve the scene: into the directory `out` as `skg-solve SCENE -o OUT` does, else
/// without writing a file (then a scene's Ipopt log, which is relative to an output
/// directory, is not written either: a warning says so).
fn run(py: Python<'_>, scene: &mut Scene, out: Option<PathBuf>) -> PyResult<(Outcome, Option<output::Written>)> {
    match out {
        Some(dir) => {
            let (outcome, written) = py.detach(|| output::solve_into(&dir, scene)).map_err(|e| solve_into_err(py, &e))?;
            Ok((outcome, Some(written)))
        }
        None => {
            let mut outcome = py.detach(|| solve::solve_scene(scene)).map_err(|e| solve_err(py, &e))?;
            if let Some(name) = &scene.solver.log_file {
                outcome
                    .warnings
                    .push(format!("the scene's [solver] log_file ({}) is written only by a solve into a directory (out=)", name.display()));
            }
            Ok((outcome, None))
        }
    }
}
