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

/// An exception of `skg._errors` (`kind` names its class) with the message `text`.
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

/// The integer keyword argument `name` (None when not given), or a `SceneError` naming
/// the keyword and its value when it is not an integer from 0 to `max` (Python's own
/// `OverflowError` for `-1` or `2**64` names neither). The message states the range
/// `stated`, which the scene's resolution checks itself within `max`.
pub(crate) fn int_keyword(
    py: Python<'_>,
    name: &str,
    value: Option<&Bound<'_, PyAny>>,
    stated: (u64, u64),
    max: u64,
) -> PyResult<Option<u64>> {
    let Some(value) = value else { return Ok(None) };
    match value.extract::<u64>() {
        Ok(n) if n <= max => Ok(Some(n)),
        _ => {
            let shown = value.repr().map_or_else(|_| "?".into(), |r| r.to_string());
            let shown = match shown.char_indices().nth(40) {
                Some((cut, _)) => format!("{}… ({} characters)", &shown[..cut], shown.chars().count()),
                None => shown,
            };
            Err(raise_text(py, "SceneError", format!("{name}: must be an integer from {} to {}, got {shown}", stated.0, stated.1)))
        }
    }
}
