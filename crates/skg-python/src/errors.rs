//! The exceptions raised: each Rust error becomes the exception of `skg._errors` that
//! its kind names (`SceneError`, `SolveError`, `IntegrationError`, `OutputError`,
//! `SweepError`, `InputError`), with the command line's message
//! ([`skg_core::error_text`]: the error and its causes, each said once).

use pyo3::prelude::*;

use skg_core::scene::SceneError;
use skg_core::solve::SolveError;
use skg_core::stepping::reference::ReferenceError;
use skg_core::{error_text, output};
use skg_sweep as sweep;

/// An exception of `skg._errors` (`kind` names its class) with the error's text.
pub(crate) fn raise(py: Python<'_>, kind: &str, e: &(dyn std::error::Error + 'static)) -> PyErr {
    raise_text(py, kind, error_text(e))
}

pub(crate) fn raise_text(py: Python<'_>, kind: &str, text: String) -> PyErr {
    match py.import("skg._errors").and_then(|m| m.getattr(kind)).and_then(|c| c.call1((text.clone(),))) {
        Ok(exc) => PyErr::from_value(exc),
        Err(e) => e,
    }
}

pub(crate) fn scene_err(py: Python<'_>, e: &SceneError) -> PyErr {
    raise(py, "SceneError", e)
}

pub(crate) fn solve_err(py: Python<'_>, e: &SolveError) -> PyErr {
    match e {
        SolveError::Scene(s) => scene_err(py, s),
        other => raise(py, "SolveError", other),
    }
}

pub(crate) fn reference_err(py: Python<'_>, e: &ReferenceError) -> PyErr {
    match e {
        ReferenceError::Scene(s) => scene_err(py, s),
        other => raise(py, "IntegrationError", other),
    }
}

pub(crate) fn output_err(py: Python<'_>, e: &output::OutputError) -> PyErr {
    raise(py, "OutputError", e)
}

pub(crate) fn solve_into_err(py: Python<'_>, e: &output::SolveIntoError) -> PyErr {
    match e {
        output::SolveIntoError::Solve(e) => solve_err(py, e),
        output::SolveIntoError::Output(e) => output_err(py, e),
    }
}

pub(crate) fn sweep_err(py: Python<'_>, e: &sweep::SweepError) -> PyErr {
    raise(py, "SweepError", e)
}
