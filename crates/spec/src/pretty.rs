//! A JSON printer that keeps certificates readable: vectors on one line,
//! matrices one row per line.
//!
//! `serde_json`'s pretty printer puts every array element on its own line,
//! which turns a 6×6 matrix into 48 lines; this small printer is the
//! difference between a certificate a person can read and one they cannot.

use serde_json::Value;

fn is_scalar(v: &Value) -> bool {
    !matches!(v, Value::Array(_) | Value::Object(_))
}

fn scalar(v: &Value) -> String {
    // serde_json prints scalars (strings escaped, numbers as parsed) correctly.
    v.to_string()
}

fn write(v: &Value, indent: usize, out: &mut String) {
    let pad = "  ".repeat(indent);
    let pad_in = "  ".repeat(indent + 1);
    match v {
        Value::Object(map) if map.is_empty() => out.push_str("{}"),
        Value::Object(map) => {
            out.push_str("{\n");
            for (i, (k, val)) in map.iter().enumerate() {
                out.push_str(&pad_in);
                out.push_str(&Value::String(k.clone()).to_string());
                out.push_str(": ");
                write(val, indent + 1, out);
                if i + 1 < map.len() {
                    out.push(',');
                }
                out.push('\n');
            }
            out.push_str(&pad);
            out.push('}');
        }
        Value::Array(items) if items.iter().all(is_scalar) => {
            out.push('[');
            out.push_str(&items.iter().map(scalar).collect::<Vec<_>>().join(", "));
            out.push(']');
        }
        Value::Array(items) => {
            out.push_str("[\n");
            for (i, item) in items.iter().enumerate() {
                out.push_str(&pad_in);
                write(item, indent + 1, out);
                if i + 1 < items.len() {
                    out.push(',');
                }
                out.push('\n');
            }
            out.push_str(&pad);
            out.push(']');
        }
        other => out.push_str(&scalar(other)),
    }
}

/// Print JSON with vectors inline and matrices one row per line, ending in a
/// newline. The output parses back to the same value.
///
/// ```
/// let v = serde_json::json!({"P": [["1", "0"], ["0", "2"]], "x": [1, 2]});
/// let s = spec::to_pretty_json(&v);
/// assert_eq!(s, "{\n  \"P\": [\n    [\"1\", \"0\"],\n    [\"0\", \"2\"]\n  ],\n  \"x\": [1, 2]\n}\n");
/// assert_eq!(serde_json::from_str::<serde_json::Value>(&s).unwrap(), v);
/// ```
pub fn to_pretty_json(v: &Value) -> String {
    let mut out = String::new();
    write(v, 0, &mut out);
    out.push('\n');
    out
}
