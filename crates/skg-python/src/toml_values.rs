//! Python values as TOML and back: a mapping of a scene file's (or a sweep file's)
//! structure becomes a TOML table, its errors naming the field (`<python>:
//! coordinates[3].initial`); a scene's TOML comes back as plain Python values.

use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyList, PyString, PyTuple};

use crate::errors::raise_text;

/// The label of a scene built in Python, in place of a file name in its errors.
pub(crate) const PYTHON_ORIGIN: &str = "<python>";

/// Append `key` to the key path `path` as errors show it (`coordinates[3].initial`).
fn key_path(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    }
}

/// The deepest nesting of dicts and lists accepted in a mapping (a scene needs 3, a
/// sweep 4): deeper input is refused rather than recursed into until the stack
/// overflows.
const MAX_DEPTH: usize = 32;

/// A Python value as a TOML value: dict (string keys; a key whose value is None is left
/// out), list or tuple, str, bool, int, float (NumPy's scalars too). `path` names the
/// value in errors; `depth` is its nesting, at most [`MAX_DEPTH`].
fn toml_value(v: &Bound<'_, PyAny>, path: &str, depth: usize) -> Result<Option<toml::Value>, String> {
    let at = |what: String| format!("{PYTHON_ORIGIN}: {}: {what}", if path.is_empty() { "the scene" } else { path });
    if depth > MAX_DEPTH {
        return Err(at(format!("dicts and lists are nested more than {MAX_DEPTH} deep, deeper than any scene or sweep")));
    }
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
            if let Some(value) = toml_value(&item, &key_path(path, &key), depth + 1)? {
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
            match toml_value(&item, &p, depth + 1)? {
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
pub(crate) fn py_value<'py>(py: Python<'py>, v: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
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
pub(crate) fn toml_table(py: Python<'_>, mapping: &Bound<'_, PyAny>) -> PyResult<toml::Table> {
    match toml_value(mapping, "", 0) {
        Ok(Some(toml::Value::Table(t))) => Ok(t),
        Ok(_) => Err(raise_text(py, "SceneError", format!("{PYTHON_ORIGIN}: a scene is a dict of its tables, got {}", mapping.get_type()))),
        Err(message) => Err(raise_text(py, "SceneError", message)),
    }
}

/// A mapping as TOML text, one key per line (how a sweep given as a mapping is written).
#[pyfunction]
pub(crate) fn toml_text(py: Python<'_>, mapping: &Bound<'_, PyAny>) -> PyResult<String> {
    Ok(skg_core::scene::emit::write_toml(&toml_table(py, mapping)?).text)
}
