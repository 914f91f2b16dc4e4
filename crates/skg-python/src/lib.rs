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
use pyo3::types::{PyBool, PyDict, PyList, PyString, PyTuple};

use skg_core::check::Table;
use skg_core::discrete::trajectory::{trajectory_header, trajectory_rows, NodeSeries, Trajectory};
use skg_core::model::Model;
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

/// What `solve` and `reference` take: a scene file's path or a [`NativeScene`].
#[derive(FromPyObject)]
enum SceneArg {
    /// A scene read or built in Python.
    Scene(Py<NativeScene>),
    /// A scene file.
    Path(PathBuf),
}

impl SceneArg {
    /// The scene's origin as the provenance of a reference names it: the file as given, or
    /// a Scene's origin (the file it was read from, or `<python>`).
    fn label(&self) -> String {
        match self {
            SceneArg::Scene(s) => s.get().file.origin.path.clone(),
            SceneArg::Path(p) => p.display().to_string(),
        }
    }
}

/// Load a scene file (or take a Scene's) and resolve it with the overrides (what the
/// command line's `load` does).
fn load(py: Python<'_>, scene: &SceneArg, ov: &Overrides) -> PyResult<Scene> {
    let resolved = match scene {
        SceneArg::Path(path) => py.detach(|| SceneFile::load(path).and_then(|f| f.resolve(ov))),
        SceneArg::Scene(s) => {
            let file = s.get().file.clone();
            py.detach(|| file.resolve(ov))
        }
    };
    resolved.map_err(|e| scene_err(py, &e))
}

/// The label of a scene built in Python, in place of a file name in its errors.
const PYTHON_ORIGIN: &str = "<python>";

/// Append `key` to the key path `path` as errors show it (`coordinates[3].initial`).
fn key_path(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    }
}

/// A Python value as a TOML value: dict (string keys; a key whose value is None is left
/// out), list or tuple, str, bool, int, float (NumPy's scalars too). `path` names the
/// value in errors.
fn toml_value(v: &Bound<'_, PyAny>, path: &str) -> Result<Option<toml::Value>, String> {
    let at = |what: String| format!("{PYTHON_ORIGIN}: {}: {what}", if path.is_empty() { "the scene" } else { path });
    if v.is_none() {
        return Ok(None);
    }
    if let Ok(b) = v.cast::<PyBool>() {
        return Ok(Some(toml::Value::Boolean(b.is_true())));
    }
    if let Ok(s) = v.cast::<PyString>() {
        return Ok(Some(toml::Value::String(s.to_cow().map_err(|e| at(e.to_string()))?.into_owned())));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut table = toml::Table::new();
        for (k, item) in d.iter() {
            let key: String = k
                .extract()
                .map_err(|_| at(format!("keys must be strings, got {}", k.repr().map_or_else(|_| "?".into(), |r| r.to_string()))))?;
            if let Some(value) = toml_value(&item, &key_path(path, &key))? {
                table.insert(key, value);
            }
        }
        return Ok(Some(toml::Value::Table(table)));
    }
    if v.cast::<PyList>().is_ok() || v.cast::<PyTuple>().is_ok() {
        let mut items = Vec::new();
        for (i, item) in v.try_iter().map_err(|e| at(e.to_string()))?.enumerate() {
            let item = item.map_err(|e| at(e.to_string()))?;
            let p = format!("{path}[{i}]");
            match toml_value(&item, &p)? {
                Some(value) => items.push(value),
                None => return Err(format!("{PYTHON_ORIGIN}: {p}: None is not a value (TOML has no null)")),
            }
        }
        return Ok(Some(toml::Value::Array(items)));
    }
    let type_name = v.get_type().name().map_or_else(|_| "?".into(), |n| n.to_string());
    // Integers (int and NumPy's integers, by __index__) before floats.
    if v.hasattr("__index__").unwrap_or(false) {
        return match v.extract::<i64>() {
            Ok(i) => Ok(Some(toml::Value::Integer(i))),
            Err(_) => {
                Err(at(format!("the integer {} is out of TOML's range (64-bit)", v.str().map_or_else(|_| "?".into(), |r| r.to_string()))))
            }
        };
    }
    if let Ok(x) = v.extract::<f64>() {
        return Ok(Some(toml::Value::Float(x)));
    }
    Err(at(format!(
        "a value of type {type_name} is not one a scene holds (a number, a string, a boolean, a list or a dict; a SymPy expression where an expression is expected)"
    )))
}

/// A TOML value as a Python object (dict, list, str, int, float, bool; a date as text).
fn py_value<'py>(py: Python<'py>, v: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        toml::Value::String(s) => s.into_pyobject(py)?.into_any(),
        toml::Value::Integer(i) => i.into_pyobject(py)?.into_any(),
        toml::Value::Float(x) => x.into_pyobject(py)?.into_any(),
        toml::Value::Boolean(b) => b.into_pyobject(py)?.to_owned().into_any(),
        toml::Value::Datetime(d) => d.to_string().into_pyobject(py)?.into_any(),
        toml::Value::Array(items) => PyList::new(py, items.iter().map(|i| py_value(py, i)).collect::<PyResult<Vec<_>>>()?)?.into_any(),
        toml::Value::Table(t) => {
            let d = PyDict::new(py);
            for (k, item) in t {
                d.set_item(k, py_value(py, item)?)?;
            }
            d.into_any()
        }
    })
}

/// A mapping as a TOML table ([`toml_value`]), or the error `SceneError` names.
fn toml_table(py: Python<'_>, mapping: &Bound<'_, PyAny>) -> PyResult<toml::Table> {
    match toml_value(mapping, "") {
        Ok(Some(toml::Value::Table(t))) => Ok(t),
        Ok(_) => Err(raise_text(py, "SceneError", format!("{PYTHON_ORIGIN}: a scene is a dict of its tables, got {}", mapping.get_type()))),
        Err(message) => Err(raise_text(py, "SceneError", message)),
    }
}

/// A scene as Python holds it (`skg.Scene`): its file as read, or as built from a
/// mapping ([`SceneFile::from_table`]), unresolved (parameters, overrides and checks are
/// applied when it is solved, as for a file).
#[pyclass(module = "skg._skg", frozen)]
struct NativeScene {
    file: SceneFile,
}

#[pymethods]
impl NativeScene {
    /// A scene built in code: `mapping` has the scene file's structure. Its TOML text is
    /// written one key per line; errors name the field (`<python>: coordinates[3].initial`).
    #[staticmethod]
    fn from_mapping(py: Python<'_>, mapping: &Bound<'_, PyAny>) -> PyResult<NativeScene> {
        let table = toml_table(py, mapping)?;
        let file = py.detach(|| SceneFile::from_table(&table, PYTHON_ORIGIN)).map_err(|e| scene_err(py, &e))?;
        Ok(NativeScene { file })
    }

    /// A scene from its TOML text; `name` labels errors (`name:line:column`).
    #[staticmethod]
    fn from_toml(py: Python<'_>, text: &str, name: &str) -> PyResult<NativeScene> {
        let file = py.detach(|| SceneFile::parse(text, name)).map_err(|e| scene_err(py, &e))?;
        Ok(NativeScene { file })
    }

    /// A scene file.
    #[staticmethod]
    fn read(py: Python<'_>, path: PathBuf) -> PyResult<NativeScene> {
        let file = py.detach(|| SceneFile::load(&path)).map_err(|e| scene_err(py, &e))?;
        Ok(NativeScene { file })
    }

    /// The scene's TOML text: the file's as read, or the one written for a mapping.
    #[getter]
    fn text(&self) -> &str {
        &self.file.origin.text
    }

    /// Where it came from: the file, the name given to `from_toml`, or `<python>`.
    #[getter]
    fn origin(&self) -> &str {
        &self.file.origin.path
    }

    /// `[scene] name`.
    #[getter]
    fn name(&self) -> &str {
        &self.file.scene.name
    }

    /// The hash of the TOML text, as summary.json's `scene_hash` gives it.
    #[getter]
    fn hash(&self) -> String {
        self.file.origin.content_hash()
    }

    /// The scene's structure as a dict (the TOML text read back as plain values).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let table: toml::Table = self.file.origin.text.parse().map_err(|e: toml::de::Error| PyValueError::new_err(e.to_string()))?;
        py_value(py, &toml::Value::Table(table))
    }

    /// Resolve the scene with `set` and build its model (its expressions parsed and
    /// differentiated), as a solve begins, without solving: raises the scene's first
    /// error; returns the coordinates' names.
    #[pyo3(signature = (*, set=None))]
    fn check(&self, py: Python<'_>, set: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<String>> {
        let ov = Overrides { set: assignments(set)?, ..Overrides::default() };
        let file = self.file.clone();
        let scene = py.detach(|| file.resolve(&ov).and_then(|s| Model::build(&s).map(|_| s))).map_err(|e| scene_err(py, &e))?;
        Ok(scene.coordinates)
    }
}

/// A mapping as TOML text, one key per line (how a sweep given as a mapping is written).
#[pyfunction]
fn toml_text(py: Python<'_>, mapping: &Bound<'_, PyAny>) -> PyResult<String> {
    Ok(skg_core::scene::emit::write_toml(&toml_table(py, mapping)?).text)
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

/// Solve a scene file (or a [`NativeScene`]) as `skg-solve SCENE` does; with `out`, into that directory as
/// `skg-solve SCENE -o OUT` does ([`output::solve_into`]), else without writing files.
#[pyfunction]
#[pyo3(signature = (path, *, out=None, nodes=None, set=None, operator=None, formulation=None, initial_velocity=None,
    hessian=None, max_iter=None, backend=None, window=None, overlap=None, verify_tol=None, no_verify=false, no_fallback=false,
    refine=false, max_nodes=None, time_limit=None))]
#[pyo3(name = "solve")]
#[allow(clippy::too_many_arguments)]
fn solve_scene(
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

/// Integrate a scene (a file or a [`NativeScene`]) as `skg-solve reference` does (without writing the CSV).
#[pyfunction]
#[pyo3(signature = (path, *, nodes=None, set=None, hard_walls=false, rtol=1e-12, atol=None, times=None))]
#[pyo3(name = "reference")]
#[allow(clippy::too_many_arguments)]
fn integrate_reference(
    py: Python<'_>,
    path: SceneArg,
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
    Ok(NativeReference { scene, path: path.label(), reference: r })
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
    m.add_function(wrap_pyfunction!(toml_text, m)?)?;
    m.add_class::<NativeScene>()?;
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
