//! Re-checking a certificate.
//!
//! The checker re-derives the whole certificate from the embedded spec and
//! the recorded settings, and compares field by field: strings, rationals and
//! integers must match exactly, floating-point numbers to a relative `1e-9`.
//! Nothing stored in the certificate is trusted, so changing any number, the
//! verdict, a matrix, the Casimir choice or the spec makes the check fail and
//! names the field.

use crate::certificate::certify;
use crate::json::{as_object, required, SpecError};
use crate::parse::spec_from_value;
use crate::settings::EngineSettings;
use serde_json::Value;

/// Relative tolerance for floating-point fields.
pub const FLOAT_TOLERANCE: f64 = 1e-9;

/// Why a certificate failed its check.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum CheckError {
    /// The certificate (or its embedded spec) is not valid input.
    #[error("bad certificate: {0}")]
    BadInput(SpecError),
    /// A claim does not hold.
    #[error("check failed at {path}: {message}")]
    Failed {
        /// JSON path of the first differing field.
        path: String,
        /// What differs.
        message: String,
    },
}

/// What a successful check established.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckReport {
    /// The spec's name.
    pub name: String,
    /// The verdict confirmed.
    pub verdict: String,
    /// `Sigma^2`, if stable.
    pub sigma2: Option<f64>,
}

/// Check a certificate given as JSON text.
pub fn check_certificate(text: &str) -> Result<CheckReport, CheckError> {
    let value: Value = serde_json::from_str(text)
        .map_err(|e| CheckError::BadInput(SpecError::new("$", format!("malformed JSON: {e}"))))?;
    check_certificate_value(&value)
}

/// Check a certificate given as a JSON value.
pub fn check_certificate_value(cert: &Value) -> Result<CheckReport, CheckError> {
    let map = as_object(cert, "$").map_err(CheckError::BadInput)?;
    let spec_value = required(map, "spec", "$").map_err(CheckError::BadInput)?.clone();
    let mut spec = spec_from_value(spec_value).map_err(|e| {
        CheckError::BadInput(SpecError::new(format!("$.spec{}", e.path.trim_start_matches('$')), e.message))
    })?;
    // The recorded settings are the ones to reproduce.
    let settings = map.get("settings");
    spec.settings = EngineSettings::from_json(settings, "$.settings").map_err(CheckError::BadInput)?;
    let rederived = certify(&spec);
    compare(&rederived.json, cert, "$")?;
    Ok(CheckReport {
        name: spec.name.clone(),
        verdict: rederived.analysis.verdict.as_str().to_string(),
        sigma2: rederived.analysis.sigma2(),
    })
}

fn fail(path: &str, message: String) -> CheckError {
    CheckError::Failed { path: path.to_string(), message }
}

fn compare(expected: &Value, found: &Value, path: &str) -> Result<(), CheckError> {
    match (expected, found) {
        (Value::Object(e), Value::Object(f)) => {
            for (k, ev) in e {
                let p = format!("{path}.{k}");
                if path == "$" && k == "engine" {
                    continue; // a newer engine may re-check an older certificate
                }
                match f.get(k) {
                    Some(fv) => compare(ev, fv, &p)?,
                    None => return Err(fail(&p, "missing in the certificate".into())),
                }
            }
            for k in f.keys() {
                if !e.contains_key(k) {
                    return Err(fail(&format!("{path}.{k}"), "not produced by the engine for this spec".into()));
                }
            }
            Ok(())
        }
        (Value::Array(e), Value::Array(f)) => {
            if e.len() != f.len() {
                return Err(fail(path, format!("re-derived {} entries, certificate has {}", e.len(), f.len())));
            }
            for (i, (ev, fv)) in e.iter().zip(f).enumerate() {
                compare(ev, fv, &format!("{path}[{i}]"))?;
            }
            Ok(())
        }
        (Value::Number(e), Value::Number(f)) => {
            let (Some(x), Some(y)) = (e.as_f64(), f.as_f64()) else {
                return Err(fail(path, "not a finite number".into()));
            };
            let is_integer = |n: &serde_json::Number| n.is_i64() || n.is_u64();
            if is_integer(e) && is_integer(f) {
                if e.to_string() != f.to_string() {
                    return Err(fail(path, format!("re-derived {e}, certificate says {f}")));
                }
                return Ok(());
            }
            let scale = x.abs().max(y.abs());
            if (x - y).abs() > FLOAT_TOLERANCE * scale.max(f64::MIN_POSITIVE) && (x - y).abs() > 1e-300 {
                return Err(fail(path, format!("re-derived {x:e}, certificate says {y:e}")));
            }
            Ok(())
        }
        (e, f) if e == f => Ok(()),
        (e, f) => Err(fail(path, format!("re-derived {e}, certificate says {f}"))),
    }
}
