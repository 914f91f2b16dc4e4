//! `skg._skg`: the native part of the Python package `skg` (python/skg wraps it).
//!
//! Every function here calls the same code as the `skg-solve` command line: a scene is
//! loaded and resolved by `skg_core::scene`, solved by `skg_core::solve::solve_scene`
//! (verification and fallback ladder included), integrated by `skg_core::stepping::reference`,
//! written (into a locked directory) by `skg_core::output`, planned and swept by
//! `skg_sweep::plan` and `skg_sweep::run_sweep` (split into shards for an executor by
//! `skg_sweep::shards`). Errors are raised as
//! the exceptions of `skg._errors` with the command line's message
//! ([`skg_core::error_text`]). The GIL is released while Rust computes.
//!
//! Trajectories cross into Python as a dict of NumPy arrays (`trajectory_dict`); the
//! Python classes (`skg.Trajectory`, `skg.Solution`, …) are written in Python.

#![warn(missing_docs)]

use std::path::PathBuf;

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use skg_core::check::Table;
use skg_core::discrete::trajectory::{trajectory_header, trajectory_rows, NodeSeries, Trajectory};
use skg_core::scene::provenance;
use skg_core::scene::{Backend, ConstraintKind, Formulation, HessianMode, InitialVelocity, Overrides, Scene, SceneError, SceneFile};
use skg_core::solve::{self, Outcome, SolveError};
use skg_core::stepping::reference::{self, Reference, ReferenceError, ReferenceOptions};
use skg_core::{error_text, output};
use skg_sweep as sweep;

/// An exception of `skg._errors` (`kind` names its class) with the error's text.
fn raise(py: Python<'_>, kind: &str, e: &(dyn std::error::Error + 'static)) -> PyErr {
    raise_text(py, kind, error_text(e))
}

fn raise_text(py: Python<'_>, kind: &str, text: String) -> PyErr {
    match py.import("skg._errors").and_then(|m| m.getattr(kind)).and_then(|c| c.call1((text.clone(),))) {
        Ok(exc) => PyErr::from_value(exc),
        Err(e) => e,
    }
}

fn scene_err(py: Python<'_>, e: &SceneError) -> PyErr {
    raise(py, "SceneError", e)
}

fn solve_err(py: Python<'_>, e: &SolveError) -> PyErr {
    match e {
        SolveError::Scene(s) => scene_err(py, s),
        other => raise(py, "SolveError", other),
    }
}

fn reference_err(py: Python<'_>, e: &ReferenceError) -> PyErr {
    match e {
        ReferenceError::Scene(s) => scene_err(py, s),
        other => raise(py, "IntegrationError", other),
    }
}

fn output_err(py: Python<'_>, e: &output::OutputError) -> PyErr {
    raise(py, "OutputError", e)
}

fn solve_into_err(py: Python<'_>, e: &output::SolveIntoError) -> PyErr {
    match e {
        output::SolveIntoError::Solve(e) => solve_err(py, e),
        output::SolveIntoError::Output(e) => output_err(py, e),
    }
}

fn sweep_err(py: Python<'_>, e: &sweep::SweepError) -> PyErr {
    raise(py, "SweepError", e)
}

/// `set={"sigma": 1/200, "V0": "2*g"}` as `--set` assignments: a number by its shortest
/// round-trip text, a string as written.
fn assignments(set: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<(String, String)>> {
    let mut out = Vec::new();
    let Some(set) = set else { return Ok(out) };
    let py = set.py();
    for (k, v) in set.iter() {
        let name: String = k.extract().map_err(|_| PyValueError::new_err(format!("set: parameter names must be strings, got {k}")))?;
        let value = if let Ok(s) = v.extract::<String>() {
            s
        } else if let Ok(i) = v.extract::<i64>() {
            i.to_string()
        } else if let Ok(x) = v.extract::<f64>() {
            format!("{x:?}")
        } else {
            return Err(PyValueError::new_err(format!("set: the value of `{name}` must be a number or an expression string, got {v}")));
        };
        out.push(Overrides::parse_assignment(&format!("{name}={value}")).map_err(|e| scene_err(py, &e))?);
    }
    Ok(out)
}

/// Load a scene file and resolve it with the overrides (what the command line's `load` does).
fn load(py: Python<'_>, path: &std::path::Path, ov: &Overrides) -> PyResult<Scene> {
    py.detach(|| SceneFile::load(path).and_then(|f| f.resolve(ov))).map_err(|e| scene_err(py, &e))
}

/// A `NodeSeries` (`rows[k][i]`) as an N×d array (d may be 0).
fn matrix<'py>(py: Python<'py>, rows: &NodeSeries, width: usize) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = rows.iter().flat_map(|r| r.iter().copied()).collect();
    Array2::from_shape_vec((rows.len(), width), flat).expect("rows of equal width").into_pyarray(py)
}

fn vector<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, v)
}

/// A trajectory of `scene` as a dict: the arrays `t`, `q`, `v`, `lambda`, `energy`,
/// `wall_energy`, `g`, `drift`, `h`; the names `coordinates`, `constraints`,
/// `positions` (the position constraints), `walls`; and `columns` with `table`, the
/// trajectory CSV's header and rows (N×C).
fn trajectory_dict<'py>(py: Python<'py>, scene: &Scene, tr: &Trajectory) -> PyResult<Bound<'py, PyDict>> {
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

/// The result of [`solve`]: the outcome, the scene it solved and the files last written,
/// so that `write` produces exactly the files of the command line and `summary` lists them.
#[pyclass(module = "skg._skg", frozen)]
struct NativeSolution {
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

/// Solve a scene file as `skg-solve SCENE` does; with `out`, into that directory as
/// `skg-solve SCENE -o OUT` does ([`output::solve_into`]), else without writing files.
#[pyfunction]
#[pyo3(signature = (path, *, out=None, nodes=None, set=None, operator=None, formulation=None, initial_velocity=None,
    hessian=None, max_iter=None, backend=None, window=None, overlap=None, verify_tol=None, no_verify=false, no_fallback=false,
    refine=false, max_nodes=None, time_limit=None))]
#[pyo3(name = "solve")]
#[allow(clippy::too_many_arguments)]
fn solve_scene(
    py: Python<'_>,
    path: PathBuf,
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

/// A reference of a scene and what `write` needs to write the command line's CSV.
#[pyclass(module = "skg._skg", frozen)]
struct NativeReference {
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

/// Integrate a scene as `skg-solve reference` does (without writing the CSV).
#[pyfunction]
#[pyo3(signature = (path, *, nodes=None, set=None, hard_walls=false, rtol=1e-12, atol=None, times=None))]
#[pyo3(name = "reference")]
#[allow(clippy::too_many_arguments)]
fn integrate_reference(
    py: Python<'_>,
    path: PathBuf,
    nodes: Option<usize>,
    set: Option<&Bound<'_, PyDict>>,
    hard_walls: bool,
    rtol: f64,
    atol: Option<f64>,
    times: Option<Vec<f64>>,
) -> PyResult<NativeReference> {
    if !(rtol > 0.0 && rtol.is_finite()) {
        return Err(PyValueError::new_err(format!("rtol must be a positive number, got {rtol}")));
    }
    let ov = Overrides { set: assignments(set)?, nodes, ..Overrides::default() };
    let scene = load(py, &path, &ov)?;
    let times = times.unwrap_or_else(|| solve::grid(&scene).0);
    let opts = ReferenceOptions { rtol, atol: atol.unwrap_or(rtol) };
    let r = py
        .detach(|| if hard_walls { reference::hard_wall(&scene, &times, &opts) } else { reference::regularized(&scene, &times, &opts) })
        .map_err(|e| reference_err(py, &e))?;
    Ok(NativeReference { scene, path: path.display().to_string(), reference: r })
}

/// A sweep about to run: what [`plan_sweep`] found and what `run` needs.
#[pyclass(module = "skg._skg", frozen)]
struct NativeSweepPlan {
    file: sweep::SweepFile,
    plan: sweep::Plan,
    opts: sweep::SweepOptions,
}

#[pymethods]
impl NativeSweepPlan {
    /// The line `skg-solve sweep` prints before it starts.
    #[getter]
    fn text(&self) -> &str {
        &self.plan.text
    }

    /// Run (or resume) the sweep; returns the run's report as a dict.
    fn run<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = py.detach(|| sweep::run_sweep(&self.file, &self.plan.expanded, &self.opts)).map_err(|e| sweep_err(py, &e))?;
        let d = PyDict::new(py);
        d.set_item("name", self.file.name())?;
        d.set_item("total", r.total)?;
        d.set_item("in_shard", r.in_shard)?;
        d.set_item("skipped", r.skipped)?;
        d.set_item("ran", r.ran)?;
        d.set_item("failed", r.failed)?;
        d.set_item("duplicates", r.duplicates)?;
        d.set_item("results", r.results)?;
        d.set_item("superseded", r.superseded)?;
        d.set_item("wall_s", r.wall_s)?;
        d.set_item("estimate_s", self.plan.estimate_s)?;
        d.set_item("jobs", self.opts.jobs)?;
        Ok(d)
    }
}

/// Load and expand a sweep file as `skg-solve sweep` does before it starts
/// ([`sweep::plan`]): its points run in worker processes of the `skg-solve` executable
/// `exe`.
#[pyfunction]
#[pyo3(signature = (path, *, exe, out=None, jobs=None, shard=None, retry_failed=false, new_results=false, yes=false, progress=true))]
#[allow(clippy::too_many_arguments)]
fn plan_sweep(
    py: Python<'_>,
    path: PathBuf,
    exe: PathBuf,
    out: Option<PathBuf>,
    jobs: Option<usize>,
    shard: Option<&str>,
    retry_failed: bool,
    new_results: bool,
    yes: bool,
    progress: bool,
) -> PyResult<NativeSweepPlan> {
    let shard = shard.map(|s| s.parse::<sweep::Shard>().map_err(|e| PyValueError::new_err(format!("shard: {e}")))).transpose()?;
    let file = py.detach(|| sweep::SweepFile::load(&path)).map_err(|e| sweep_err(py, &e))?;
    let opts = sweep::SweepOptions {
        out_dir: out.unwrap_or_else(|| sweep::default_out_dir(&file)),
        jobs: jobs.unwrap_or_else(sweep::default_jobs).max(1),
        shard,
        worker_exe: exe,
        progress,
        retry_failed,
        new_results,
    };
    let plan = py.detach(|| sweep::plan(&file, &opts, yes)).map_err(|e| sweep_err(py, &e))?;
    Ok(NativeSweepPlan { file, plan, opts })
}

/// Make (or check) the sharded directory of a sweep whose shards an executor runs
/// ([`sweep::shards::prepare`], under the directory's lock): a dict with the directory,
/// the sweep's name and file, the number of shards and points, the plan's line and each
/// shard's state (`k`, `points`, `converged`, `failed`, `missing`).
#[pyfunction]
#[pyo3(signature = (path, *, out=None, shards=None, yes=false))]
fn plan_shards<'py>(
    py: Python<'py>,
    path: PathBuf,
    out: Option<PathBuf>,
    shards: Option<usize>,
    yes: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let file = py.detach(|| sweep::SweepFile::load(&path)).map_err(|e| sweep_err(py, &e))?;
    let out = out.unwrap_or_else(|| sweep::default_out_dir(&file));
    let dir = std::path::absolute(&out).map_err(|e| raise(py, "OutputError", &e))?;
    let opts = sweep::SweepOptions {
        out_dir: dir.clone(),
        jobs: 1,
        shard: None,
        worker_exe: PathBuf::from("skg-solve"),
        progress: false,
        retry_failed: false,
        new_results: false,
    };
    let prepare = sweep::shards::PrepareOptions { shards, runner: sweep::shards::Runner::Executor };
    let (plan, layout, states) = py
        .detach(|| {
            let plan = sweep::plan(&file, &opts, yes)?;
            let lock = output::OutputDir::lock(&dir)?;
            let (layout, states) = sweep::shards::prepare(&file, &plan.expanded, &dir, &prepare)?;
            drop(lock);
            Ok((plan, layout, states))
        })
        .map_err(|e: sweep::SweepError| sweep_err(py, &e))?;
    let d = PyDict::new(py);
    d.set_item("dir", &dir)?;
    d.set_item("name", &layout.name)?;
    d.set_item("sweep_file", &layout.sweep_file)?;
    d.set_item("shards", layout.shards)?;
    d.set_item("total", layout.total_points)?;
    d.set_item("text", &plan.text)?;
    let list = PyList::empty(py);
    for s in &states {
        let e = PyDict::new(py);
        e.set_item("k", s.k)?;
        e.set_item("points", s.points)?;
        e.set_item("converged", s.converged)?;
        e.set_item("failed", s.failed)?;
        e.set_item("missing", s.missing)?;
        e.set_item("dir", sweep::shards::shard_dir(&dir, s.k))?;
        list.append(e)?;
    }
    d.set_item("states", list)?;
    Ok(d)
}

/// Merge the shards of a sharded directory into its results.csv
/// ([`sweep::shards::merge_shards`]: nothing is written unless every point is there);
/// returns `rows`, `total` and `duplicates`.
#[pyfunction]
fn merge_shards<'py>(py: Python<'py>, dir: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let r = py.detach(|| sweep::shards::merge_shards(&dir)).map_err(|e| sweep_err(py, &e))?;
    let d = PyDict::new(py);
    d.set_item("rows", r.rows)?;
    d.set_item("total", r.total)?;
    d.set_item("duplicates", r.duplicates)?;
    Ok(d)
}

/// A sweep's results.csv (or its directory), checked as `plot` and `merge` read it:
/// `(header, rows)` with every cell as text.
#[pyfunction]
fn read_results(py: Python<'_>, path: PathBuf) -> PyResult<(Vec<String>, Vec<Vec<String>>)> {
    let r = py.detach(|| sweep::Results::read(&path)).map_err(|e| sweep_err(py, &e))?;
    Ok((r.header, r.rows))
}

/// A trajectory CSV (trajectory.csv, reference.csv, a reference from `skg-solve
/// reference`) as `(columns, table)`, read as `check` and `plot` read it.
#[pyfunction]
fn read_table<'py>(py: Python<'py>, path: PathBuf) -> PyResult<(Vec<String>, Bound<'py, PyArray2<f64>>)> {
    let t = py.detach(|| Table::read(&path)).map_err(|e| raise(py, "InputError", &e))?;
    let width = t.columns.len();
    Ok((t.columns, matrix(py, &t.rows, width)))
}

/// The native module.
#[pymodule]
fn _skg(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(solve_scene, m)?)?;
    m.add_function(wrap_pyfunction!(integrate_reference, m)?)?;
    m.add_function(wrap_pyfunction!(plan_sweep, m)?)?;
    m.add_function(wrap_pyfunction!(plan_shards, m)?)?;
    m.add_function(wrap_pyfunction!(merge_shards, m)?)?;
    m.add_function(wrap_pyfunction!(read_results, m)?)?;
    m.add_function(wrap_pyfunction!(read_table, m)?)?;
    m.add_class::<NativeSolution>()?;
    m.add_class::<NativeReference>()?;
    m.add_class::<NativeSweepPlan>()?;
    m.add("VERSION", provenance::VERSION)?;
    m.add("SCHEMA_VERSION", provenance::SCHEMA_VERSION)?;
    // Where this module was built from: the workspace's target directory holds an
    // `skg-solve` built from the same sources (one of the places `skg.sweep` looks).
    m.add("TARGET_DIR", concat!(env!("CARGO_MANIFEST_DIR"), "/../../target"))?;
    Ok(())
}
