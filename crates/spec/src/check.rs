//! Re-checking a certificate.
//!
//! The checker re-derives the whole certificate from the embedded spec and
//! the recorded settings, and compares field by field: strings, rationals and
//! integers must match exactly, floating-point numbers to a relative `1e-12`
//! (with an absolute floor of `1e-12` times the largest entry of the enclosing
//! array, so round-off zeros compare against their vector's scale). The
//! re-derivation is deterministic, so the tolerance only absorbs another
//! CPU's last bits; a `Sigma^2` lowered by `1e-9` (accepted while this was
//! `1e-9`) now fails. Numbers
//! whose representation is arbitrary are verified instead of compared: the
//! spectrum as a multiset, the unstable eigenvector by its residual
//! `|A v - lambda v|` against the re-derived `A`, and the fastest-growing
//! direction by `v^T P v = 1` and `v^T Q v = l_max`. Nothing stored is
//! trusted, so changing the verdict, `Sigma^2`, a matrix entry, the Casimir
//! choice or the spec makes the check fail and names the field.

use crate::certificate::certify_lie;
use crate::json::{as_object, required, SpecError};
use crate::parse::spec_from_value;
use crate::record::CertificateDocument;
use crate::settings::EngineSettings;
use outcome::{Verdict, VerificationLevel};
use serde_json::Value;

/// Relative tolerance for floating-point fields.
pub const FLOAT_TOLERANCE: f64 = 1e-12;

/// Tolerance for the spectrum of `A`, relative to its spectral radius:
/// eigenvalues of a defective `A` (a Jordan block, as at the fast-top
/// threshold) are determined by floating point only to about `sqrt(eps)`, so
/// another CPU's rounding may move them that far; the claims that rest on
/// the spectrum are proved exactly (Sturm sequences) or re-verified by
/// residual, not read from it.
pub const SPECTRUM_TOLERANCE: f64 = 1e-9;

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
    /// The re-derivation was stopped through its [`outcome::Progress`]:
    /// nothing was established either way.
    #[error("the check was cancelled before it finished")]
    Cancelled,
}

impl From<outcome::Cancelled> for CheckError {
    fn from(_: outcome::Cancelled) -> CheckError {
        CheckError::Cancelled
    }
}

/// What a successful check established.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckReport {
    /// The spec's name.
    pub name: String,
    /// The verdict confirmed.
    pub verdict: Verdict,
    /// The verification level established (`None`: no claim is made).
    pub level: Option<VerificationLevel>,
    /// `Sigma^2`, if stable.
    pub sigma2: Option<f64>,
}

/// Check a certificate given as JSON text ([`crate::check_json`] with the
/// default [`crate::Options`]).
pub fn check_certificate(text: &str) -> Result<CheckReport, CheckError> {
    crate::check_json(text, &crate::Options::default())
}

/// Check a typed certificate (one built in Rust or read with
/// [`crate::document::from_value`]).
///
/// ```
/// let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/rigid-body-major-axis.json")).unwrap();
/// let mut doc = spec::certify_lie(&spec::parse_spec(&text).unwrap()).document().unwrap();
/// assert_eq!(spec::check_document(&doc).unwrap().verdict, spec::Verdict::Stable);
/// doc.sigma2_exact = Some("1/4".into()); // below the true 27/100
/// assert!(spec::check_document(&doc).is_err());
/// ```
pub fn check_document(doc: &CertificateDocument) -> Result<CheckReport, CheckError> {
    let value = serde_json::to_value(doc).map_err(|e| CheckError::BadInput(SpecError::new("$", e.to_string())))?;
    check_certificate_value(&value)
}

/// Check a certificate given as a JSON value.
pub fn check_certificate_value(cert: &Value) -> Result<CheckReport, CheckError> {
    check_value_with(cert, None, &outcome::Progress::new())
}

pub(crate) fn check_value_with(
    cert: &Value,
    base: Option<&std::path::Path>,
    progress: &outcome::Progress,
) -> Result<CheckReport, CheckError> {
    // Only the Zeitlin check reads files (and needs the folder).
    #[cfg(not(feature = "fluid"))]
    let _ = base;
    let map = as_object(cert, "$").map_err(CheckError::BadInput)?;
    // Another format is said first: its fields are not this engine's, and
    // the way out is to certify again, not to edit the file.
    if let Some(v) = map.get("certificate_version").and_then(Value::as_u64) {
        let current = crate::certificate::CERTIFICATE_VERSION;
        if v != current {
            return Err(fail(
                "$.certificate_version",
                format!("the certificate is in format {v}, this checker reads format {current}: certify the spec again with this engine (`verify certify SPEC -o CERT`)"),
            ));
        }
    }
    if crate::box_cert::is_box_certificate(cert) {
        return crate::box_cert::check_box_certificate(cert);
    }
    if map.get("spec").is_some_and(crate::is_fluid_spec) {
        #[cfg(feature = "fluid")]
        return crate::fluid::check_fluid_certificate_with(cert, progress);
        #[cfg(not(feature = "fluid"))]
        return Err(CheckError::BadInput(SpecError::new(
            "$.spec.fluid",
            "fluid certificates need the `fluid` feature of the spec crate (on by default)",
        )));
    }
    if map.get("spec").is_some_and(crate::is_zeitlin_spec) {
        #[cfg(feature = "fluid")]
        return crate::zeitlin::check_zeitlin_certificate_with(cert, base, progress);
        #[cfg(not(feature = "fluid"))]
        return Err(CheckError::BadInput(SpecError::new(
            "$.spec.zeitlin",
            "Zeitlin certificates need the `fluid` feature of the spec crate (on by default)",
        )));
    }
    // A large certificate says so (`kind`): the sparse route certifies any
    // size when called directly (`certify_large`), and its certificate is
    // re-derived on that route; without the field, the spec's size decides.
    #[cfg(feature = "fluid")]
    if map.get("kind").and_then(Value::as_str) == Some("large") || map.get("spec").is_some_and(crate::is_large_spec) {
        return crate::large::check_large_certificate_with(cert, progress);
    }
    // A finite-dimensional certificate is checked in micro- to
    // milliseconds: one step.
    progress.plan(1);
    let report = check_lie_certificate(cert, map)?;
    progress.settle();
    Ok(report)
}

fn check_lie_certificate(cert: &Value, map: &serde_json::Map<String, Value>) -> Result<CheckReport, CheckError> {
    let spec_value = required(map, "spec", "$").map_err(CheckError::BadInput)?.clone();
    check_engine(map)?;
    // The shape first: every field of the certificate type, no other.
    crate::document::from_value::<CertificateDocument>(cert)
        .map_err(|e| fail(&e.path, format!("not a certificate as this engine writes them: {}", e.message)))?;
    // From here on the file is a certificate: an embedded spec or settings
    // that the engine rejects (a Casimir edited into a non-Casimir) make the
    // certificate fail (exit 1), they are not bad input to the checker.
    let mut spec = spec_from_value(spec_value).map_err(|e| {
        fail(
            &format!("$.spec{}", e.path.trim_start_matches('$')),
            format!("the embedded spec is not valid: {}", e.message),
        )
    })?;
    // The recorded settings are the ones to reproduce.
    let settings = map.get("settings");
    spec.settings = EngineSettings::from_json(settings, "$.settings")
        .map_err(|e| fail(&e.path, format!("the recorded settings are not valid: {}", e.message)))?;
    // 1. The claims, exactly, along the checker's own path.
    let level = crate::claims::verify_claims(&spec, cert)
        .map_err(|f| fail(&f.path, format!("claim does not hold: {}", f.message)))?;
    // 2. Everything else, by re-deriving the certificate and comparing.
    let rederived = certify_lie(&spec);
    let mut expected = rederived.json.clone();
    let mut found = cert.clone();
    // Representation-dependent numbers are verified, not compared.
    let spectrum =
        (take(&mut expected, &["linearisation", "spectrum"]), take(&mut found, &["linearisation", "spectrum"]));
    let eigenvector =
        (take(&mut expected, &["instability", "eigenvector"]), take(&mut found, &["instability", "eigenvector"]));
    let direction =
        (take(&mut expected, &["growth", "fastest_direction"]), take(&mut found, &["growth", "fastest_direction"]));
    compare(&expected, &found, "$", 0.0)?;
    let bound = match cert.get("sigma2_exact").and_then(Value::as_str) {
        Some(e) => Some(
            exact::parse_number(e)
                .map(|r| exact::rational_to_f64_up(&r))
                .map_err(|_| fail("$.sigma2_exact", "not a rational".into()))?,
        ),
        None => cert.get("sigma2").and_then(Value::as_f64),
    };
    check_stopping(cert, spec.stopping, bound)?;
    check_spectrum(spectrum)?;
    check_eigenvector(eigenvector, &rederived.analysis)?;
    check_direction(direction, &rederived.analysis)?;
    Ok(CheckReport {
        name: spec.name.clone(),
        verdict: rederived.analysis.verdict,
        level: Some(level),
        sigma2: rederived.analysis.sigma2(),
    })
}

/// The one rule for a stated stopping time, for every kind of certificate:
/// `epsilon` and `delta` are the spec's, and `T` is `ln(epsilon/delta)/S`
/// rounded down ([`generator::StoppingTime::time`]), where `S` is the
/// certificate's own stated bound on `Sigma^2` (its proved `sigma2_upper`,
/// its exact `Sigma^2` rounded up, or, where it proves none and says so in
/// `stopping.bound`, its estimate): never above that time, and not below it
/// by more than a relative `1e-12`; infinite exactly when `S = 0`. `bound`
/// is `S` as the certificate states it (`None`: no stopping time may be
/// stated).
pub(crate) fn check_stopping(
    cert: &Value,
    stopping: Option<crate::parse::Stopping>,
    bound: Option<f64>,
) -> Result<(), CheckError> {
    let stated = cert.get("stopping").filter(|v| !v.is_null());
    let (stop, st, s) = match (stopping, stated, bound) {
        (_, None, _) | (None, Some(_), _) | (_, Some(_), None) => {
            // whether one must be there is the re-derivation's to compare
            return match (stopping.zip(bound), stated) {
                (Some(_), None) => Err(fail("$.stopping", "missing: the spec asks for a stopping time".into())),
                (None, Some(_)) => Err(fail("$.stopping", "the spec asks for none, or nothing bounds Sigma^2".into())),
                _ => Ok(()),
            };
        }
        (Some(stop), Some(st), Some(s)) => (stop, st, s),
    };
    for (key, value) in [("epsilon", stop.epsilon), ("delta", stop.delta)] {
        if st.get(key).and_then(Value::as_f64) != Some(value) {
            return Err(fail(&format!("$.stopping.{key}"), format!("is not the spec's {key} = {value:e}")));
        }
    }
    let guaranteed = generator::StoppingTime::new(stop.epsilon, stop.delta, s).time();
    match (st.get("T"), guaranteed) {
        (Some(Value::String(t)), None) if t == "infinity" => Ok(()),
        (Some(Value::String(_)), _) => {
            Err(fail("$.stopping.T", format!("infinite, but the bound on Sigma^2 is {s:e}")))
        }
        (Some(t), Some(g)) => {
            let t = t.as_f64().ok_or_else(|| fail("$.stopping.T", "expected a number or \"infinity\"".into()))?;
            if t > g {
                Err(fail(
                    "$.stopping.T",
                    format!(
                        "{t:e} exceeds ln(epsilon/delta)/S = {g:e} (S = {s:e}), the time the stated bound guarantees"
                    ),
                ))
            } else if t < g * (1.0 - 1e-12) {
                Err(fail("$.stopping.T", format!("{t:e} is not ln(epsilon/delta)/S = {g:e} rounded down (S = {s:e})")))
            } else {
                Ok(())
            }
        }
        (Some(_), None) => Err(fail("$.stopping.T", "finite, but the bound on Sigma^2 is 0: T is infinite".into())),
        (None, _) => Err(fail("$.stopping.T", "missing".into())),
    }
}

/// The certificate must name this engine and version: every number in it
/// is re-derived by this engine, and a certificate from another version is
/// re-certified (`verify --write`), not trusted for having parsed.
pub(crate) fn check_engine(map: &serde_json::Map<String, Value>) -> Result<(), CheckError> {
    let engine = map.get("engine").ok_or_else(|| fail("$.engine", "missing in the certificate".into()))?;
    let name = engine.get("name").and_then(Value::as_str);
    let version = engine.get("version").and_then(Value::as_str);
    if name != Some("verify") {
        return Err(fail("$.engine.name", "expected \"verify\"".into()));
    }
    if version != Some(crate::certificate::ENGINE_VERSION) {
        return Err(fail(
            "$.engine.version",
            format!(
                "the certificate was written by engine version {}, this checker is {}: re-certify it with this version",
                exact::quote(version.unwrap_or("(not a string)"), 40),
                crate::certificate::ENGINE_VERSION
            ),
        ));
    }
    Ok(())
}

pub(crate) fn fail(path: &str, message: String) -> CheckError {
    // Messages quote certificate values, which may be anything a forger wrote.
    CheckError::Failed { path: exact::cut(path, 300), message: exact::cut(&message, crate::json::MAX_MESSAGE_BYTES) }
}

/// Remove `v[path]` and return it.
fn take(v: &mut Value, path: &[&str]) -> Option<Value> {
    let (last, parents) = path.split_last()?;
    let mut cur = v;
    for p in parents {
        cur = cur.get_mut(*p)?;
    }
    cur.as_object_mut()?.remove(*last)
}

fn max_abs_number(v: &Value) -> f64 {
    match v {
        Value::Number(n) => n.as_f64().map_or(0.0, f64::abs),
        Value::Array(a) => a.iter().map(max_abs_number).fold(0.0, f64::max),
        Value::Object(m) => m.values().map(max_abs_number).fold(0.0, f64::max),
        _ => 0.0,
    }
}

fn complex_list(v: &Value, path: &str) -> Result<Vec<(f64, f64)>, CheckError> {
    let items = v.as_array().ok_or_else(|| fail(path, "expected an array of {re, im}".into()))?;
    items
        .iter()
        .enumerate()
        .map(|(i, z)| match (z.get("re").and_then(Value::as_f64), z.get("im").and_then(Value::as_f64)) {
            (Some(re), Some(im)) if re.is_finite() && im.is_finite() => Ok((re, im)),
            _ => Err(fail(&format!("{path}[{i}]"), "expected {re, im} with finite numbers".into())),
        })
        .collect()
}

/// The spectrum is compared as a multiset, to `1e-9` of the spectral radius
/// (round-off decides the order of eigenvalues with equal real parts).
fn check_spectrum(pair: (Option<Value>, Option<Value>)) -> Result<(), CheckError> {
    let path = "$.linearisation.spectrum";
    let (expected, found) = match pair {
        (None, None) => return Ok(()),
        (Some(e), Some(f)) => (complex_list(&e, path)?, complex_list(&f, path)?),
        (Some(_), None) => return Err(fail(path, "missing in the certificate".into())),
        (None, Some(_)) => return Err(fail(path, "not produced by the engine for this spec".into())),
    };
    if expected.len() != found.len() {
        return Err(fail(path, format!("re-derived {} eigenvalues, certificate has {}", expected.len(), found.len())));
    }
    let radius = expected.iter().map(|(a, b)| a.hypot(*b)).fold(0.0, f64::max);
    let tol = SPECTRUM_TOLERANCE * radius.max(f64::MIN_POSITIVE);
    let mut used = vec![false; found.len()];
    for (i, e) in expected.iter().enumerate() {
        let hit = (0..found.len()).find(|&j| !used[j] && (found[j].0 - e.0).hypot(found[j].1 - e.1) <= tol);
        match hit {
            Some(j) => used[j] = true,
            None => {
                return Err(fail(
                    path,
                    format!("re-derived eigenvalue {} {:+}i (#{i}) is not in the certificate", e.0, e.1),
                ))
            }
        }
    }
    Ok(())
}

/// The stored eigenvector must be a unit eigenvector of the re-derived `A`
/// for the re-derived unstable eigenvalue.
fn check_eigenvector(pair: (Option<Value>, Option<Value>), analysis: &generator::Analysis) -> Result<(), CheckError> {
    let path = "$.instability.eigenvector";
    let found = match pair {
        (None, None) => return Ok(()),
        (Some(_), Some(f)) => complex_list(&f, path)?,
        (Some(_), None) => return Err(fail(path, "missing in the certificate".into())),
        (None, Some(_)) => return Err(fail(path, "not produced by the engine for this spec".into())),
    };
    let (Some(inst), Some(lin)) = (&analysis.instability, &analysis.linearisation) else {
        return Err(fail(path, "no instability was re-derived".into()));
    };
    let a = lin.a.to_dmatrix();
    let n = a.nrows();
    if found.len() != n {
        return Err(fail(path, format!("expected {n} components, got {}", found.len())));
    }
    let norm = found.iter().map(|(x, y)| x * x + y * y).sum::<f64>().sqrt();
    if (norm - 1.0).abs() > 1e-9 {
        return Err(fail(path, format!("not a unit vector (norm {norm})")));
    }
    let lambda = inst.eigenvalue;
    let mut residual = 0.0;
    for i in 0..n {
        let (mut re, mut im) = (0.0, 0.0);
        for j in 0..n {
            re += a[(i, j)] * found[j].0;
            im += a[(i, j)] * found[j].1;
        }
        re -= lambda.re * found[i].0 - lambda.im * found[i].1;
        im -= lambda.re * found[i].1 + lambda.im * found[i].0;
        residual += re * re + im * im;
    }
    let residual = residual.sqrt();
    let scale = a.norm().max(lambda.norm()).max(f64::MIN_POSITIVE);
    if residual > 1e-8 * scale {
        return Err(fail(path, format!("|A v - lambda v| = {residual:e} is not small: not an eigenvector")));
    }
    Ok(())
}

/// The stored fastest direction must have unit `P`-norm and attain the
/// largest generalized eigenvalue: `v^T (sQ) v = l_max`.
fn check_direction(pair: (Option<Value>, Option<Value>), analysis: &generator::Analysis) -> Result<(), CheckError> {
    let path = "$.growth.fastest_direction";
    let found = match pair {
        (None, None) => return Ok(()),
        (Some(_), Some(f)) => f,
        (Some(_), None) => return Err(fail(path, "missing in the certificate".into())),
        (None, Some(_)) => return Err(fail(path, "not produced by the engine for this spec".into())),
    };
    let Some(stable) = &analysis.stable else {
        return Err(fail(path, "no stable evidence was re-derived".into()));
    };
    let v: Vec<f64> = found
        .as_array()
        .ok_or_else(|| fail(path, "expected an array".into()))?
        .iter()
        .map(|x| x.as_f64().filter(|x| x.is_finite()).ok_or_else(|| fail(path, "expected finite numbers".into())))
        .collect::<Result<_, _>>()?;
    let s = stable.choice.sign.as_f64();
    let p = stable.choice.p.to_dmatrix() * s;
    let q = stable.form.q.to_dmatrix() * s;
    if v.len() != p.nrows() {
        return Err(fail(path, format!("expected {} components, got {}", p.nrows(), v.len())));
    }
    let x = nalgebra::DVector::from_column_slice(&v);
    let pn = (x.transpose() * &p * &x)[(0, 0)];
    let qn = (x.transpose() * &q * &x)[(0, 0)];
    let lmax = stable.growth.largest_eigenvalue;
    // A simple top eigenvalue fixes the direction up to the sign convention,
    // so it is compared with the re-derived one (to 1e-9 of its largest
    // entry; a component moved from 0 to 5e-8 changes v^T P v only at second
    // order, which the residual tests below cannot see). A multiple one
    // leaves an eigenspace: then only the residuals are tested.
    let eigenvalues = &stable.growth.eigenvalues;
    let spread = eigenvalues.iter().fold(0.0f64, |m, e| m.max(e.abs())).max(f64::MIN_POSITIVE);
    let second = eigenvalues.iter().rev().nth(1).copied();
    let simple = second.is_none_or(|l2| lmax - l2 > 1e-6 * spread);
    if simple {
        let expected = &stable.growth.direction;
        let scale = expected.iter().fold(0.0f64, |m, e| m.max(e.abs())).max(f64::MIN_POSITIVE);
        if let Some(i) = (0..v.len()).find(|&i| (v[i] - expected[i]).abs() > 1e-9 * scale) {
            return Err(fail(
                &format!("{path}[{i}]"),
                format!("re-derived {:e}, certificate says {:e} (the top eigenvalue is simple)", expected[i], v[i]),
            ));
        }
    }
    // The direction comes from a floating-point solve whose accuracy degrades
    // with the conditioning of P (large Casimir terms): test it relative to
    // that scale, up to round-off (1e-8 of the norms involved).
    let scale = (q.norm() + lmax.abs() * p.norm()) * x.norm_squared();
    // v^T P v = 1 to the accuracy a floating solve with this P allows
    // (relative to |P| |v|^2, which is about the condition of P along v).
    if (pn - 1.0).abs() > 1e-9 * (p.norm() * x.norm_squared()).max(1.0) {
        return Err(fail(path, format!("v^T P v = {pn}, expected 1")));
    }
    if (qn - lmax * pn).abs() > 1e-8 * scale.max(f64::MIN_POSITIVE) {
        return Err(fail(path, format!("v^T Q v = {qn}, expected lambda_max v^T P v = {}", lmax * pn)));
    }
    // The residual vector is first-order sensitive to a change of v away
    // from the eigenspace (the quadratic forms above are not).
    let residual = (&q * &x - &p * &x * lmax).norm();
    let bound = 1e-9 * (q.norm() + lmax.abs() * p.norm()) * x.norm();
    if residual > bound.max(f64::MIN_POSITIVE) {
        return Err(fail(
            path,
            format!("|Q v - lambda_max P v| = {residual:e} is above {bound:e}: not an eigenvector"),
        ));
    }
    Ok(())
}

/// Compare field by field. `floor` is an absolute tolerance for numbers,
/// `1e-9` of the largest number in the enclosing array (round-off zeros in a
/// vector are compared against the vector's scale, not their own).
fn compare(expected: &Value, found: &Value, path: &str, floor: f64) -> Result<(), CheckError> {
    compare_with(expected, found, path, floor, FLOAT_TOLERANCE)
}

/// [`compare`] with relative tolerance `tol` for floating-point numbers.
pub(crate) fn compare_with(
    expected: &Value,
    found: &Value,
    path: &str,
    floor: f64,
    tol: f64,
) -> Result<(), CheckError> {
    match (expected, found) {
        (Value::Object(e), Value::Object(f)) => {
            for (k, ev) in e {
                let p = format!("{path}.{k}");
                match f.get(k) {
                    Some(fv) => compare_with(ev, fv, &p, floor, tol)?,
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
            // A vector or matrix shares one scale (round-off zeros compare
            // against it); a list of records does not (a resolution `ny` is
            // not the scale of a growth constant beside it).
            let floor = if e.iter().any(Value::is_object) { floor } else { floor.max(tol * max_abs_number(expected)) };
            for (i, (ev, fv)) in e.iter().zip(f).enumerate() {
                compare_with(ev, fv, &format!("{path}[{i}]"), floor, tol)?;
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
            if !y.is_finite() || (x - y).abs() > (tol * x.abs().max(y.abs())).max(floor) {
                return Err(fail(path, format!("re-derived {x:e}, certificate says {y:e}")));
            }
            Ok(())
        }
        (e, f) if e == f => Ok(()),
        (e, f) => Err(fail(path, format!("re-derived {e}, certificate says {f}"))),
    }
}
