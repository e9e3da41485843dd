//! Python values ↔ the scene description.
//!
//! A scene dictionary (the TOML scene's tables as nested dicts) becomes a
//! JSON value — numbers, strings, booleans, lists and tables; numpy scalars
//! and arrays through `tolist()` — and then a [`SceneDesc`] by serde, so
//! unknown keys and wrong types are refused with the key's path
//! (`transfer.colormap_ponts: unknown field`). A view (the keyword
//! arguments of a render) is merged over a volume's stored description: its
//! tables merge key by key, and `None` removes a key (back to the default).

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::{Map, Number, Value};
use voxless::{SceneDesc, SceneFlags};

use crate::errors;

/// `obj` as a JSON value; `path` names it in errors (`camera.eye[1]`).
pub fn to_json(obj: &Bound<'_, PyAny>, path: &str) -> PyResult<Value> {
    let py = obj.py();
    if obj.is_none() {
        return Ok(Value::Null);
    }
    // bool before int: Python's bool is an int.
    if obj.is_instance_of::<PyBool>() {
        return Ok(Value::Bool(obj.extract::<bool>()?));
    }
    if obj.is_instance_of::<PyInt>() {
        if let Ok(v) = obj.extract::<i64>() {
            return Ok(Value::from(v));
        }
        if let Ok(v) = obj.extract::<u64>() {
            return Ok(Value::from(v));
        }
        return Err(errors::value(py, format!("{path}: {obj} is out of range")));
    }
    if obj.is_instance_of::<PyFloat>() {
        let v = obj.extract::<f64>()?;
        return Number::from_f64(v)
            .map(Value::Number)
            .ok_or_else(|| errors::value(py, format!("{path}: {v} is not a finite number")));
    }
    if obj.is_instance_of::<PyString>() {
        return Ok(Value::String(obj.extract::<String>()?));
    }
    if let Ok(dict) = obj.cast::<PyDict>() {
        let mut map = Map::new();
        for (k, v) in dict.iter() {
            let Ok(key) = k.extract::<String>() else {
                return Err(PyTypeError::new_err(format!(
                    "{path}: table keys must be strings, not {}",
                    type_name(&k)
                )));
            };
            let sub = if path.is_empty() {
                key.clone()
            } else {
                format!("{path}.{key}")
            };
            map.insert(key, to_json(&v, &sub)?);
        }
        return Ok(Value::Object(map));
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let mut items = Vec::new();
        for (i, v) in obj.try_iter()?.enumerate() {
            items.push(to_json(&v?, &format!("{path}[{i}]"))?);
        }
        return Ok(Value::Array(items));
    }
    // numpy scalars and arrays (and anything else with tolist, such as
    // unyt quantities): their plain Python value.
    if obj.hasattr("tolist")? {
        let plain = obj.call_method0("tolist")?;
        if !plain.is(obj) {
            return to_json(&plain, path);
        }
    }
    Err(PyTypeError::new_err(format!(
        "{path}: {} is not a number, string, bool, list or dict",
        type_name(obj)
    )))
}

fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "this value".into())
}

/// A JSON value as `T` (a scene description or flags); errors name the key
/// path, after `what` (`scene` or `flags`).
fn from_json<T: serde::de::DeserializeOwned>(
    py: Python<'_>,
    value: Value,
    what: &str,
) -> PyResult<T> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let path = e.path().to_string();
        let field = (path != ".").then_some(path.as_str());
        let inner = e.inner().to_string();
        let (message, field) = match field {
            Some(p) => (format!("{what} {p}: {inner}"), Some(p.to_string())),
            // The library's flags name the flag at fault themselves.
            None if what == "flags" => {
                let flag = inner.split(':').next().filter(|f| !f.contains(' '));
                (inner.clone(), flag.map(str::to_string))
            }
            None => (format!("{what}: {inner}"), None),
        };
        errors::with_field(py, message, field.as_deref())
    })
}

/// A JSON value as a scene description; errors name the key path.
pub fn desc_from_json(py: Python<'_>, value: Value) -> PyResult<SceneDesc> {
    from_json(py, value, "scene")
}

/// A dict of keyword arguments as the library's flags (named as the CLI's,
/// `-` as `_`); errors name the keyword.
pub fn flags(obj: &Bound<'_, PyAny>) -> PyResult<SceneFlags> {
    let value = to_json(obj, "")?;
    if !value.is_object() {
        return Err(PyTypeError::new_err(format!(
            "flags: expected a dict of keyword arguments, not {}",
            type_name(obj)
        )));
    }
    from_json(obj.py(), value, "flags")
}

/// A scene dictionary as a scene description.
pub fn scene_desc(obj: &Bound<'_, PyAny>) -> PyResult<SceneDesc> {
    let value = to_json(obj, "")?;
    if !value.is_object() {
        return Err(PyTypeError::new_err(format!(
            "the scene must be a dict of tables, not {}",
            type_name(obj)
        )));
    }
    desc_from_json(obj.py(), value)
}

/// `desc` with the view `overlay` merged over it (see the module docs). The
/// data tables cannot change once a volume is built, so the overlay may not
/// name them.
pub fn with_view(desc: &SceneDesc, overlay: &Bound<'_, PyAny>) -> PyResult<SceneDesc> {
    let py = overlay.py();
    let over = to_json(overlay, "")?;
    let Value::Object(over) = over else {
        return Err(PyTypeError::new_err(
            "the view must be a dict of scene tables",
        ));
    };
    if let Some(k) = ["particles", "amr", "tets"]
        .into_iter()
        .find(|k| over.contains_key(*k))
    {
        return Err(errors::with_field(
            py,
            format!(
                "[{k}] describes the data, which is fixed when the volume is made; \
                 render, project and sample take the view (camera, image, transfer, \
                 render, light)"
            ),
            Some(k),
        ));
    }
    let mut base =
        serde_json::to_value(desc).map_err(|e| errors::value(py, format!("scene: {e}")))?;
    merge(&mut base, Value::Object(over));
    desc_from_json(py, base)
}

/// Merges `over` into `base`: tables key by key, `null` removes the key,
/// anything else replaces.
fn merge(base: &mut Value, over: Value) {
    match (base, over) {
        (Value::Object(b), Value::Object(o)) => {
            for (k, v) in o {
                match v {
                    Value::Null => {
                        b.remove(&k);
                    }
                    Value::Object(_) => match b.get_mut(&k) {
                        Some(slot @ Value::Object(_)) => merge(slot, v),
                        _ => {
                            let mut fresh = Value::Object(Map::new());
                            merge(&mut fresh, v);
                            b.insert(k, fresh);
                        }
                    },
                    v => {
                        b.insert(k, v);
                    }
                }
            }
        }
        (b, o) => *b = o,
    }
}

/// A JSON value as a Python object (tables as dicts, arrays as lists).
pub fn to_python<'py>(py: Python<'py>, value: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match value {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Number(n) => match (n.as_i64(), n.as_u64()) {
            (Some(i), _) => i.into_pyobject(py)?.into_any(),
            (None, Some(u)) => u.into_pyobject(py)?.into_any(),
            _ => n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any(),
        },
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Array(a) => {
            let items = a
                .iter()
                .map(|v| to_python(py, v))
                .collect::<PyResult<Vec<_>>>()?;
            PyList::new(py, items)?.into_any()
        }
        Value::Object(m) => {
            let d = PyDict::new(py);
            for (k, v) in m {
                // Unset options are left out: the dict reads like a scene file.
                if !v.is_null() {
                    d.set_item(k, to_python(py, v)?)?;
                }
            }
            d.into_any()
        }
    })
}

/// A scene description as a Python dict (unset options left out).
pub fn desc_to_python<'py>(py: Python<'py>, desc: &SceneDesc) -> PyResult<Bound<'py, PyAny>> {
    let value = serde_json::to_value(desc).map_err(|e| errors::value(py, format!("scene: {e}")))?;
    to_python(py, &value)
}
