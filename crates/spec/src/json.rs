//! Small helpers that read a `serde_json::Value` while tracking the JSON path,
//! so every input error names the field it is about.

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

/// Longest path and message kept in a [`SpecError`]: both quote input (a
/// key, an expression, a literal), and a 50 MB literal must not become 50 MB
/// of stderr.
pub const MAX_MESSAGE_BYTES: usize = 1000;

impl SpecError {
    /// An error at `path`; an over-long path or message is cut to an excerpt
    /// that says how much was left out.
    pub fn new(path: impl Into<String>, message: impl Into<String>) -> Self {
        SpecError { path: exact::cut(&path.into(), 300), message: exact::cut(&message.into(), MAX_MESSAGE_BYTES) }
    }
}

/// Parse JSON text, rejecting an object with the same key twice (serde_json
/// keeps the last, so a certificate with two `"verdict"`s would be read as
/// whichever came second, and a human reading the first would be misled).
/// The error names the JSON path of the repeated key.
///
/// ```
/// let e = spec::parse_json(r#"{"a": {"b": 1, "b": 2}}"#).unwrap_err();
/// assert_eq!(e.path, "$.a.b");
/// assert!(spec::parse_json(r#"{"a": [{"b": 1}, {"b": 2}]}"#).is_ok());
/// // escapes are decoded first: "\u0062" is "b"
/// assert!(spec::parse_json(r#"{"b": 1, "\u0062": 2}"#).is_err());
/// ```
pub fn parse_json(text: &str) -> Result<Value> {
    let value: Value = serde_json::from_str(text).map_err(|e| SpecError::new("$", format!("malformed JSON: {e}")))?;
    if let Some((path, key)) = duplicate_key(text) {
        return Err(SpecError::new(
            path,
            format!("the key '{key}' appears twice in this object; a key may appear once"),
        ));
    }
    Ok(value)
}

enum Frame {
    Object { path: String, keys: std::collections::HashSet<String>, expecting_key: bool, last: String },
    Array { path: String, index: usize },
}

/// The path of the first repeated key of an object in valid JSON text.
fn duplicate_key(text: &str) -> Option<(String, String)> {
    let bytes = text.as_bytes();
    let mut stack: Vec<Frame> = Vec::new();
    let value_path = |stack: &Vec<Frame>| -> String {
        match stack.last() {
            None => "$".to_string(),
            Some(Frame::Object { path, last, .. }) => child(path, last),
            Some(Frame::Array { path, index }) => index_path(path, *index),
        }
    };
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'{' => {
                let path = value_path(&stack);
                stack.push(Frame::Object { path, keys: Default::default(), expecting_key: true, last: String::new() });
            }
            b'[' => {
                let path = value_path(&stack);
                stack.push(Frame::Array { path, index: 0 });
            }
            b'}' | b']' => {
                stack.pop();
            }
            b',' => match stack.last_mut() {
                Some(Frame::Object { expecting_key, .. }) => *expecting_key = true,
                Some(Frame::Array { index, .. }) => *index += 1,
                None => {}
            },
            b'"' => {
                let start = i;
                i += 1;
                while i < bytes.len() && bytes[i] != b'"' {
                    if bytes[i] == b'\\' {
                        i += 1;
                    }
                    i += 1;
                }
                if let Some(Frame::Object { path, keys, expecting_key, last }) = stack.last_mut() {
                    if *expecting_key {
                        let raw = &text[start..=i.min(bytes.len() - 1)];
                        let key: String = serde_json::from_str(raw).unwrap_or_else(|_| raw.to_string());
                        if !keys.insert(key.clone()) {
                            let shown = exact::quote(&key, 100);
                            return Some((child(path, &shown), shown));
                        }
                        *last = key;
                        *expecting_key = false;
                    }
                }
            }
            _ => {}
        }
        i += 1;
    }
    None
}

fn index_path(path: &str, i: usize) -> String {
    format!("{path}[{i}]")
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

pub(crate) fn required<'a>(map: &'a Map<String, Value>, key: &str, path: &str) -> Result<&'a Value> {
    map.get(key).ok_or_else(|| SpecError::new(child(path, key), "required field is missing"))
}
