//! Scenes from Python: `NativeScene` (`skg.Scene`'s native part: a scene file read, or
//! built from a mapping), the argument `solve` and `reference` take (a path or a
//! `NativeScene`) and its loading with the overrides, and `set=` as `--set` assignments.

use std::path::PathBuf;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use skg_core::model::Model;
use skg_core::scene::{Overrides, Scene, SceneFile};

use crate::errors::scene_err;
use crate::toml_values::{py_value, toml_table, PYTHON_ORIGIN};

/// `set={"sigma": 1/200, "V0": "2*g"}` as `--set` assignments: a number by its shortest
/// round-trip text, a string as written.
pub(crate) fn assignments(set: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<(String, String)>> {
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
pub(crate) enum SceneArg {
    /// A scene read or built in Python.
    Scene(Py<NativeScene>),
    /// A scene file.
    Path(PathBuf),
}

impl SceneArg {
    /// The scene's origin as the provenance of a reference names it: the file as given, or
    /// a Scene's origin (the file it was read from, or `<python>`).
    pub(crate) fn label(&self) -> String {
        match self {
            SceneArg::Scene(s) => s.get().file.origin.path.clone(),
            SceneArg::Path(p) => p.display().to_string(),
        }
    }
}

/// Load a scene file (or take a Scene's) and resolve it with the overrides (what the
/// command line's `load` does).
pub(crate) fn load(py: Python<'_>, scene: &SceneArg, ov: &Overrides) -> PyResult<Scene> {
    let resolved = match scene {
        SceneArg::Path(path) => py.detach(|| SceneFile::load(path).and_then(|f| f.resolve(ov))),
        SceneArg::Scene(s) => {
            let file = s.get().file.clone();
            py.detach(|| file.resolve(ov))
        }
    };
    resolved.map_err(|e| scene_err(py, &e))
}

/// A scene as Python holds it (`skg.Scene`): its file as read, or as built from a
/// mapping ([`SceneFile::from_table`]), unresolved (parameters, overrides and checks are
/// applied when it is solved, as for a file).
#[pyclass(module = "skg._skg", frozen)]
pub(crate) struct NativeScene {
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
