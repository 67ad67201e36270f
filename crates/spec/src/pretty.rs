//! A JSON printer that keeps certificates readable: vectors on one line,
//! matrices one row per line.
//!
//! `serde_json`'s pretty printer puts every array element on its own line,
//! which turns a 6×6 matrix into 48 lines; this small printer is the
//! difference between a certificate a person can read and one they cannot.

use serde_json::Value;

/// Keys printed first, in this order, wherever they occur; other keys follow
/// alphabetically. (Maps are stored sorted, which is fast; this restores a
/// reading order: verdict before evidence, spec fields in the spec's order.)
const KEY_ORDER: &[&str] = &[
    "certificate_version",
    "engine",
    "name",
    "description",
    "verdict",
    "reason",
    "level",
    "checks",
    "sigma2",
    "sigma2_exact",
    "sigma2_sharp",
    "sigma2_upper",
    "stopping",
    "spec_sha256",
    "kind",
    "model",
    "formulation",
    "discretisation",
    "form",
    "paper",
    "optimisation",
    "modes",
    "convergence",
    "drift_residual",
    "compressible",
    "hamiltonian",
    "coordinates",
    "equilibrium",
    "noise",
    "conserved",
    "casimir_discovery",
    "multipliers",
    "casimir_choice",
    "P",
    "Q",
    "residuals",
    "growth",
    "linearisation",
    "instability",
    "search",
    "settings",
    "spec",
    "fluid",
    "x_period",
    "y_interval",
    "boundary",
    "shear_flow",
    "sound_speed",
    "ny",
    "x_modes",
    "m",
    "k",
    "algebra",
    "parameters",
    "hamiltonian",
    "casimirs",
    "first_integrals",
    "epsilon",
    "delta",
    "T",
    "bound",
    "re",
    "im",
];

fn key_rank(k: &str) -> usize {
    KEY_ORDER.iter().position(|x| *x == k).unwrap_or(KEY_ORDER.len())
}

fn is_scalar(v: &Value) -> bool {
    !matches!(v, Value::Array(_) | Value::Object(_))
}

fn scalar(v: &Value, out: &mut String) {
    use std::fmt::Write as _;
    // serde_json prints scalars (strings escaped, numbers as parsed) correctly.
    let _ = write!(out, "{v}");
}

fn write(v: &Value, indent: usize, out: &mut String) {
    let pad = "  ".repeat(indent);
    let pad_in = "  ".repeat(indent + 1);
    match v {
        Value::Object(map) if map.is_empty() => out.push_str("{}"),
        Value::Object(map) => {
            out.push_str("{\n");
            let mut entries: Vec<(&String, &Value)> = map.iter().collect();
            entries.sort_by(|(a, _), (b, _)| key_rank(a).cmp(&key_rank(b)).then_with(|| a.cmp(b)));
            for (i, (k, val)) in entries.into_iter().enumerate() {
                out.push_str(&pad_in);
                scalar(&Value::String(k.clone()), out);
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
            for (i, item) in items.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                scalar(item, out);
            }
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
        other => scalar(other, out),
    }
}

/// Print JSON with vectors inline and matrices one row per line, ending in a
/// newline. The output parses back to the same value.
///
/// ```
/// let v = serde_json::json!({"x": [1, 2], "P": [["1", "0"], ["0", "2"]]});
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
