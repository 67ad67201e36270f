//! Small helpers that read a `serde_json::Value` while tracking the JSON path,
//! so every input error names the field it is about.

use exact::{parse_number, Rational};
use serde_json::{Map, Value};

/// A spec or certificate input error: the JSON path and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{path}: {message}")]
pub struct SpecError {
    /// JSON path of the offending field, e.g. `$.noise[0][1]`.
    pub path: String,
    /// What is wrong with it.
    pub message: String,
}

impl SpecError {
    /// An error at `path`.
    pub fn new(path: impl Into<String>, message: impl Into<String>) -> Self {
        SpecError { path: path.into(), message: message.into() }
    }
}

pub(crate) type Result<T> = std::result::Result<T, SpecError>;

/// `path.key`
pub(crate) fn child(path: &str, key: &str) -> String {
    format!("{path}.{key}")
}

/// `path[i]`
pub(crate) fn index(path: &str, i: usize) -> String {
    format!("{path}[{i}]")
}

pub(crate) fn type_name(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

pub(crate) fn as_object<'a>(v: &'a Value, path: &str) -> Result<&'a Map<String, Value>> {
    v.as_object().ok_or_else(|| SpecError::new(path, format!("expected an object, found {}", type_name(v))))
}

pub(crate) fn as_array<'a>(v: &'a Value, path: &str) -> Result<&'a Vec<Value>> {
    v.as_array().ok_or_else(|| SpecError::new(path, format!("expected an array, found {}", type_name(v))))
}

pub(crate) fn as_str<'a>(v: &'a Value, path: &str) -> Result<&'a str> {
    v.as_str().ok_or_else(|| SpecError::new(path, format!("expected a string, found {}", type_name(v))))
}

/// Reject keys outside `allowed`.
pub(crate) fn check_keys(map: &Map<String, Value>, allowed: &[&str], path: &str) -> Result<()> {
    for key in map.keys() {
        if !allowed.contains(&key.as_str()) {
            return Err(SpecError::new(
                child(path, key),
                format!("unknown field '{key}' (allowed here: {})", allowed.join(", ")),
            ));
        }
    }
    Ok(())
}

pub(crate) fn required<'a>(map: &'a Map<String, Value>, key: &str, path: &str) -> Result<&'a Value> {
    map.get(key).ok_or_else(|| SpecError::new(child(path, key), "required field is missing"))
}

/// An exact rational from a JSON number or a string such as `"3/10"`.
pub(crate) fn rational(v: &Value, path: &str) -> Result<Rational> {
    let text = match v {
        Value::Number(n) => n.to_string(),
        Value::String(s) => s.clone(),
        other => {
            return Err(SpecError::new(
                path,
                format!("expected a number or a rational string, found {}", type_name(other)),
            ))
        }
    };
    parse_number(&text).map_err(|e| SpecError::new(path, e.to_string()))
}

/// A non-negative integer.
pub(crate) fn index_value(v: &Value, path: &str) -> Result<usize> {
    let r = rational(v, path)?;
    if !r.is_integer() || r < Rational::from_integer(0.into()) {
        return Err(SpecError::new(path, format!("expected a non-negative integer index, found {r}")));
    }
    num_traits::ToPrimitive::to_usize(&r.to_integer()).ok_or_else(|| SpecError::new(path, "index is too large"))
}

/// A finite double from a JSON number or numeric string.
pub(crate) fn float(v: &Value, path: &str) -> Result<f64> {
    Ok(exact::rational_to_f64(&rational(v, path)?))
}

/// The text of an expression: a string, or a number used as a constant.
pub(crate) fn expression_text(v: &Value, path: &str) -> Result<String> {
    match v {
        Value::String(s) => Ok(s.clone()),
        Value::Number(n) => Ok(n.to_string()),
        other => Err(SpecError::new(
            path,
            format!("expected an expression (a string or a number), found {}", type_name(other)),
        )),
    }
}

/// The spec's `name` (a non-empty string), after checking that an optional
/// `description` is a string.
pub(crate) fn read_name(map: &Map<String, Value>, root: &str) -> Result<String> {
    let name = as_str(required(map, "name", root)?, &child(root, "name"))?.to_string();
    if name.trim().is_empty() {
        return Err(SpecError::new(child(root, "name"), "must not be empty"));
    }
    if let Some(d) = map.get("description") {
        as_str(d, &child(root, "description"))?;
    }
    Ok(name)
}
