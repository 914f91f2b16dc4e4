//! `fit`: a scene's parameters fitted to measured motion as `skg-solve fit` does (into a
//! directory with `out=`), and `NativeFit`, the result `skg.FitResult` wraps: the `fit`
//! object of summary.json, the fitted motion as a solution, the fitted scene's text.

use std::path::PathBuf;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use skg_core::fit::{self, Data, Fit, FitError, FitIntoError, FitSettings, FreeParameter};
use skg_core::scene::Overrides;

use crate::errors::{output_err, raise, raise_text, scene_err, solve_err};
use crate::scene::{assignments, load, SceneArg};
use crate::solve::NativeSolution;

/// The result of [`fit_scene`].
#[pyclass(module = "skg._skg", frozen)]
pub(crate) struct NativeFit {
    report: String,
    fitted_toml: String,
    solution: Py<NativeSolution>,
}

#[pymethods]
impl NativeFit {
    /// The `fit` object of summary.json as a dict.
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        py.import("json")?.call_method1("loads", (self.report.as_str(),))
    }

    /// The text of fitted.toml: the scene with the fitted values.
    #[getter]
    fn fitted_toml(&self) -> &str {
        &self.fitted_toml
    }

    /// The fitted motion: the solve of the fitted scene, verified.
    #[getter]
    fn solution(&self, py: Python<'_>) -> Py<NativeSolution> {
        self.solution.clone_ref(py)
    }
}

/// Where the data come from: a CSV file, or columns (name, values; NaN not observed).
#[derive(FromPyObject)]
pub(crate) enum DataArg {
    /// Columns of numbers.
    Columns(Vec<(String, Vec<f64>)>),
    /// A CSV file.
    Path(PathBuf),
}

/// Fit `free` parameters of a scene to `data` as `skg-solve fit` does (each, when `None`,
/// from the scene's `[fit]` table); with `out`, into that directory.
#[pyfunction]
#[pyo3(signature = (path, data=None, free=None, *, out=None, nodes=None, set=None, operator=None, refine=false, method=None, hessian=None, start=None, tol=None, max_iter=None, time_limit=None))]
#[pyo3(name = "fit")]
#[allow(clippy::too_many_arguments)]
pub(crate) fn fit_scene(
    py: Python<'_>,
    path: SceneArg,
    data: Option<DataArg>,
    free: Option<Vec<String>>,
    out: Option<PathBuf>,
    nodes: Option<usize>,
    set: Option<&Bound<'_, PyDict>>,
    operator: Option<&str>,
    refine: bool,
    method: Option<&str>,
    hessian: Option<&str>,
    start: Option<&str>,
    tol: Option<f64>,
    max_iter: Option<u32>,
    time_limit: Option<f64>,
) -> PyResult<NativeFit> {
    let mut ov = Overrides { nodes, set: assignments(set)?, refine, time_limit, ..Overrides::default() };
    ov.auto_operator = operator.is_some_and(|s| s.trim().eq_ignore_ascii_case("auto"));
    ov.operator = operator
        .filter(|_| !ov.auto_operator)
        .map(|s| s.parse().map_err(|e| PyValueError::new_err(format!("operator: {e}"))))
        .transpose()?;
    let free = free.map(|items| parse_free(&items)).transpose()?;
    let mut scene = load(py, &path, &ov)?;
    let free = match free {
        Some(free) => free,
        None => fit::free_of_scene(&scene.file).map_err(|e| scene_err(py, &e))?,
    };
    let settings = settings(free, method, hessian, start, tol, max_iter)?;
    let data = match data {
        Some(data) => data,
        None => match fit::data_of_scene(&scene.file).map_err(|e| scene_err(py, &e))? {
            Some(path) => DataArg::Path(path),
            None => return Err(PyValueError::new_err("data: give the data, or data = \"FILE.csv\" in the scene's [fit] table")),
        },
    };
    let data = match data {
        DataArg::Path(p) => py.detach(|| Data::read(&p, &scene)),
        DataArg::Columns(c) => Data::from_columns("<python>", &c, &scene),
    }
    .map_err(|e| raise(py, "InputError", &e))?;
    let fitted = match out {
        Some(dir) => py.detach(|| fit::fit_into(&dir, &mut scene, &ov, &data, &settings).map(|(f, _)| f)),
        None => py.detach(|| fit::fit(&scene, &ov, &data, &settings)).map_err(FitIntoError::Fit),
    };
    let fitted = fitted.map_err(|e| fit_err(py, &e))?;
    native(py, fitted)
}

/// The free parameters as given, each item read as `--free` reads it (a `ValueError`
/// names a malformed one).
fn parse_free(items: &[String]) -> PyResult<Vec<FreeParameter>> {
    items
        .iter()
        .flat_map(|s| fit::split_list(s))
        .map(|s| FreeParameter::parse(&s).map_err(|e| PyValueError::new_err(e.to_string())))
        .collect()
}

/// The settings from the keyword arguments (a `ValueError` names the wrong one).
fn settings(
    free: Vec<FreeParameter>,
    method: Option<&str>,
    hessian: Option<&str>,
    start: Option<&str>,
    tol: Option<f64>,
    max_iter: Option<u32>,
) -> PyResult<FitSettings> {
    let mut settings = FitSettings::new(free);
    if let Some(m) = method {
        settings.method = m.parse().map_err(|e| PyValueError::new_err(format!("method: {e}")))?;
    }
    if let Some(h) = hessian {
        settings.hessian = h.parse().map_err(|e| PyValueError::new_err(format!("hessian: {e}")))?;
    }
    if let Some(s) = start {
        settings.start = s.parse().map_err(|e| PyValueError::new_err(format!("start: {e}")))?;
    }
    if let Some(t) = tol {
        settings.tol = t;
    }
    if let Some(n) = max_iter {
        settings.max_iter = n;
    }
    Ok(settings)
}

/// The Python object of a fit.
fn native(py: Python<'_>, f: Fit) -> PyResult<NativeFit> {
    let report = serde_json::to_string(&f.report).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let solution = Py::new(py, NativeSolution::new(f.fitted, f.outcome, None))?;
    Ok(NativeFit { report, fitted_toml: f.fitted_toml, solution })
}

/// The exception of a fit's error: the scene's, the data's (`InputError`), a solve's or
/// an output's, else `FitError`.
fn fit_err(py: Python<'_>, e: &FitIntoError) -> PyErr {
    match e {
        FitIntoError::Output(o) => output_err(py, o),
        FitIntoError::Fit(FitError::Scene(s)) => scene_err(py, s),
        FitIntoError::Fit(FitError::Data(d)) => raise(py, "InputError", d),
        FitIntoError::Fit(FitError::Solve(s)) => solve_err(py, s),
        FitIntoError::Fit(other) => match other.not_converged() {
            Some(why) => raise_text(py, "FitError", format!("the fit did not converge: {why}")),
            None => raise(py, "FitError", other),
        },
    }
}
