//! Certifying one point of a sweep and writing it as one JSON line.

use exact::Rational;
use generator::StoppingTime;
pub use outcome::{Verdict, VerificationLevel};
use serde_json::Value;
use spec::{AnySpec, SpecError, Stopping};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// The level the points are certified at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    /// As the spec's settings say (exact proofs unless `settings.exact` is
    /// false).
    Spec,
    /// Floating point only (`settings.exact = false`): the verdicts and
    /// `Sigma^2` come from eigensolvers, and records say `numerical`.
    Numeric,
}

/// What a sweep records about one point.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    /// The verdict, or `None` when the spec is invalid at this point
    /// (`error` says why).
    pub verdict: Option<Verdict>,
    /// How firmly the verdict is established (`None`: no claim).
    pub level: Option<VerificationLevel>,
    /// `Sigma^2` when stable.
    pub sigma2: Option<f64>,
    /// `T(eps, delta)` when stable and the spec asks the stopping question
    /// (`Some(None)`: infinite).
    pub stopping_time: Option<Option<f64>>,
    /// The largest real part of an unstable eigenvalue, when unstable.
    pub growth_rate: Option<f64>,
    /// Why the spec is invalid at this point.
    pub error: Option<String>,
}

impl Outcome {
    fn invalid(e: SpecError) -> Outcome {
        Outcome {
            verdict: None,
            level: None,
            sigma2: None,
            stopping_time: None,
            growth_rate: None,
            error: Some(e.to_string()),
        }
    }
}

/// A swept name that is not a parameter of the spec.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{message}")]
pub struct UnknownParameter {
    /// The name given.
    pub name: String,
    /// What to say, with the spec's parameters.
    pub message: String,
}

/// Certifies a spec at swept parameter values.
pub struct Evaluator {
    spec: AnySpec,
    names: Vec<String>,
    level: Level,
    /// The spec's own parameter values (the ones not swept stay at these).
    fixed: BTreeMap<String, Rational>,
}

impl Evaluator {
    /// The swept spec's [`crate::spec_tag`].
    pub fn spec_tag(&self) -> String {
        crate::spec_tag(&self.spec)
    }

    /// An evaluator for the parameters `names` of `spec`; every name must be
    /// a parameter of the spec.
    ///
    /// ```
    /// let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/rigid-body-major-axis.json")).unwrap();
    /// let spec = spec::parse_any_spec(&text).unwrap();
    /// let ev = sweep::Evaluator::new(spec, vec!["I2".into()], sweep::Level::Spec).unwrap();
    /// let two = exact::parse_number("5/2").unwrap();
    /// // I = (3, 5/2, 1): Sigma^2 = sigma^2 I1 (I2 - I3) / (I3 (I1 - I2)) = 0.09 * 9 = 0.81
    /// let out = ev.evaluate(&[two]);
    /// assert_eq!(out.verdict, Some(sweep::Verdict::Stable));
    /// assert!((out.sigma2.unwrap() - 0.81).abs() < 1e-12);
    /// assert!(sweep::Evaluator::new(spec::parse_any_spec(&text).unwrap(), vec!["J".into()], sweep::Level::Spec).is_err());
    /// ```
    pub fn new(spec: AnySpec, names: Vec<String>, level: Level) -> Result<Evaluator, UnknownParameter> {
        let known = spec.parameter_names();
        for n in &names {
            if !known.contains(n) {
                return Err(UnknownParameter { message: spec::unknown_parameter(n, &known), name: n.clone() });
            }
        }
        let fixed = spec.parameters();
        Ok(Evaluator { spec, names, level, fixed })
    }

    /// The swept parameter names.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The spec.
    pub fn spec(&self) -> &AnySpec {
        &self.spec
    }

    /// The level points are certified at.
    pub fn level(&self) -> Level {
        self.level
    }

    /// Whether the point lies in the spec's sweep domain.
    pub fn in_domain(&self, values: &[Rational]) -> bool {
        let section = self.spec.sweep();
        if section.domain.is_empty() {
            return true;
        }
        section.in_domain(|n| match self.names.iter().position(|m| m == n) {
            Some(i) => Some(values[i].clone()),
            None => self.fixed.get(n).cloned(),
        })
    }

    /// Certify the spec with the swept parameters set to `values`.
    ///
    /// Finite-dimensional specs take a short path: the system is rebuilt
    /// from the expressions read once ([`spec::Spec::system_with`]) and the
    /// record comes straight from the analysis. Fluid and Zeitlin specs are
    /// re-read from their JSON and certified whole.
    pub fn evaluate(&self, values: &[Rational]) -> Outcome {
        match &self.spec {
            AnySpec::Lie(s) => {
                let mut parameters = self.fixed.clone();
                for (n, v) in self.names.iter().zip(values) {
                    parameters.insert(n.clone(), v.clone());
                }
                let system = match s.system_with(&parameters) {
                    Ok(system) => system,
                    Err(e) => return Outcome::invalid(e),
                };
                if self.level == Level::Numeric {
                    // The numeric level in floating point throughout
                    // (`generator::analyse_numeric`: no exact P, no proof).
                    let a = generator::analyse_numeric(&system, &s.settings.pipeline);
                    return Outcome {
                        verdict: Some(a.verdict),
                        level: Some(a.level()),
                        sigma2: a.sigma2,
                        stopping_time: stopping_time(s.stopping, a.sigma2),
                        growth_rate: a.instability.map(|z| z.re),
                        error: None,
                    };
                }
                let a = generator::analyse(&system, &s.settings.pipeline);
                let sigma2 = a.sigma2();
                Outcome {
                    verdict: Some(a.verdict),
                    level: Some(spec::verification_level(&a)),
                    sigma2,
                    // T from Sigma^2 rounded up, as in the certificate
                    stopping_time: stopping_time(s.stopping, a.sigma2_bound()),
                    growth_rate: a.instability.as_ref().map(|i| i.eigenvalue.re),
                    error: None,
                }
            }
            AnySpec::Fluid(s) => {
                let mut raw = s.raw.clone();
                for (n, v) in self.names.iter().zip(values) {
                    raw["parameters"][n.as_str()] = Value::String(v.to_string());
                }
                match spec::fluid_spec_from_value(raw) {
                    Ok(f) => outcome_from_certificate(&spec::certify_fluid(&f)),
                    Err(e) => Outcome::invalid(e),
                }
            }
            AnySpec::Zeitlin(s) => {
                let mut raw = s.raw.clone();
                for (n, v) in self.names.iter().zip(values) {
                    raw["parameters"][n.as_str()] = Value::String(v.to_string());
                }
                match spec::zeitlin_spec_from_value_in(raw, s.base_dir.as_deref()) {
                    Ok(z) => outcome_from_certificate(&spec::certify_zeitlin(&z)),
                    Err(e) => Outcome::invalid(e),
                }
            }
            AnySpec::Large(s) => {
                let mut raw = s.raw.clone();
                for (n, v) in self.names.iter().zip(values) {
                    raw["parameters"][n.as_str()] = Value::String(v.to_string());
                }
                match spec::large_spec_from_value(raw) {
                    Ok(l) => outcome_from_certificate(&spec::certify_large(&l)),
                    Err(e) => Outcome::invalid(e),
                }
            }
        }
    }
}

fn stopping_time(stopping: Option<Stopping>, sigma2: Option<f64>) -> Option<Option<f64>> {
    let (stop, s2) = (stopping?, sigma2?);
    Some(StoppingTime::new(stop.epsilon, stop.delta, s2).time())
}

/// The record of a point read off a full certificate (fluids, and the
/// cross-check of the short path).
pub fn outcome_from_certificate(cert: &Value) -> Outcome {
    let verdict = cert["verdict"].as_str().and_then(Verdict::from_name);
    // Every level is kept as the certificate states it (`none`: no claim).
    let level = cert["level"].as_str().and_then(VerificationLevel::from_name);
    let number = |v: &Value| v.as_f64().or_else(|| v.as_str().and_then(|s| s.parse().ok()));
    let sigma2 = cert.get("sigma2").and_then(number);
    let stopping_time = match (cert.get("stopping"), sigma2) {
        (Some(st), Some(_)) => Some(if st["T"] == "infinity" { None } else { number(&st["T"]) }),
        _ => None,
    };
    let growth_rate = cert
        .get("instability")
        .and_then(|i| i.get("growth_rate").and_then(number).or_else(|| i["eigenvalue"].get("re").and_then(number)))
        .or_else(|| cert.get("growth_rate").and_then(number)); // Zeitlin certificates
    Outcome { verdict, level, sigma2, stopping_time, growth_rate, error: None }
}

/// The record a sweep line states, read back: `None` when a field is not
/// one [`record_line`] writes (an unknown verdict or level, a number where
/// a string belongs). With [`record_line`] this gives the line's canonical
/// form: `verify merge` re-renders every line from its index's plan point
/// and its own results and refuses one that differs (float parameters that
/// are not the exact ones rounded, a key added, a level misspelt).
///
/// ```
/// let line = r#"{"sweep":"ab12","spec":"cd34","index":0,"parameters":{"I2":2.0},"exact_parameters":{"I2":"2"},"verdict":"stable","level":"exact","sigma2":0.27,"T":17.05}"#;
/// let v: serde_json::Value = serde_json::from_str(line).unwrap();
/// let o = sweep::outcome_from_line(&v).unwrap();
/// assert_eq!(o.verdict, Some(sweep::Verdict::Stable));
/// let again = sweep::record_line("ab12", "cd34", 0, &["I2".to_string()], &[exact::parse_number("2").unwrap()], &o);
/// assert_eq!(again.trim_end(), line);
/// ```
pub fn outcome_from_line(v: &Value) -> Option<Outcome> {
    let number = |key: &str| -> Option<Option<f64>> {
        match v.get(key) {
            None => Some(None),
            Some(x) => x.as_f64().map(Some),
        }
    };
    if let Some(e) = v.get("error") {
        return Some(Outcome {
            verdict: None,
            level: None,
            sigma2: None,
            stopping_time: None,
            growth_rate: None,
            error: Some(e.as_str()?.to_string()),
        });
    }
    let verdict = Verdict::from_name(v.get("verdict")?.as_str()?)?;
    let level = match v.get("level")?.as_str()? {
        "none" => None,
        name => Some(VerificationLevel::from_name(name)?),
    };
    let stopping_time = match v.get("T") {
        None => None,
        Some(Value::String(t)) if t == "infinity" => Some(None),
        Some(t) => Some(Some(t.as_f64()?)),
    };
    Some(Outcome {
        verdict: Some(verdict),
        level,
        sigma2: number("sigma2")?,
        stopping_time,
        growth_rate: number("growth_rate")?,
        error: None,
    })
}

/// A double as JSON (`null` if not finite).
fn number(out: &mut String, x: f64) {
    if x.is_finite() {
        // `{:?}` prints the shortest text that reads back to the same double.
        let _ = write!(out, "{x:?}");
    } else {
        out.push_str("null");
    }
}

fn string(out: &mut String, s: &str) {
    out.push_str(&Value::String(s.to_string()).to_string());
}

/// One JSON line (with its newline) for point `index` of sweep `id` over the
/// spec whose [`crate::spec_tag`] is `spec_tag`.
///
/// Keys: `sweep` (the sweep's id), `spec` (the spec's tag), `index`, `parameters` (doubles),
/// `exact_parameters` (rational strings), then `verdict`, `level`, `sigma2`,
/// `T` (a number, or `"infinity"`), `growth_rate`, or `error` for a point
/// where the spec is invalid. Written by hand: it is the hot path of a
/// sweep, and the layout is fixed.
///
/// ```
/// let out = sweep::Outcome { verdict: Some(sweep::Verdict::Stable), level: Some(sweep::VerificationLevel::Exact), sigma2: Some(0.27),
///     stopping_time: Some(Some(17.05)), growth_rate: None, error: None };
/// let line = sweep::record_line("ab12", "cd34", 3, &["I1".to_string()], &[exact::parse_number("3").unwrap()], &out);
/// let v: serde_json::Value = serde_json::from_str(&line).unwrap();
/// assert_eq!(v["sigma2"], 0.27);
/// assert_eq!(v["exact_parameters"]["I1"], "3");
/// assert_eq!(v["spec"], "cd34");
/// assert!(line.ends_with('\n'));
/// ```
pub fn record_line(id: &str, spec_tag: &str, index: u64, names: &[String], values: &[Rational], o: &Outcome) -> String {
    let mut s = String::with_capacity(256);
    let _ = write!(s, "{{\"sweep\":\"{id}\",\"spec\":\"{spec_tag}\",\"index\":{index},\"parameters\":{{");
    for (i, (n, v)) in names.iter().zip(values).enumerate() {
        if i > 0 {
            s.push(',');
        }
        string(&mut s, n);
        s.push(':');
        number(&mut s, spec::to_f64(v));
    }
    s.push_str("},\"exact_parameters\":{");
    for (i, (n, v)) in names.iter().zip(values).enumerate() {
        if i > 0 {
            s.push(',');
        }
        string(&mut s, n);
        let _ = write!(s, ":\"{v}\"");
    }
    s.push('}');
    match (&o.verdict, &o.error) {
        (Some(v), _) => {
            let _ = write!(s, ",\"verdict\":\"{v}\",\"level\":\"{}\"", VerificationLevel::name_of(o.level));
            if let Some(x) = o.sigma2 {
                s.push_str(",\"sigma2\":");
                number(&mut s, x);
            }
            match o.stopping_time {
                Some(Some(t)) => {
                    s.push_str(",\"T\":");
                    number(&mut s, t);
                }
                Some(None) => s.push_str(",\"T\":\"infinity\""),
                None => {}
            }
            if let Some(g) = o.growth_rate {
                s.push_str(",\"growth_rate\":");
                number(&mut s, g);
            }
        }
        (None, e) => {
            s.push_str(",\"error\":");
            string(&mut s, e.as_deref().unwrap_or("invalid"));
        }
    }
    s.push_str("}\n");
    s
}
