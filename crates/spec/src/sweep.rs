//! The optional `sweep` section of a spec: default parameter ranges, analytic
//! boundaries to draw on stability maps, reference constants (the paper's
//! claimed `Sigma^2`) to draw beside the engine's, and a domain restriction.
//!
//! ```json
//! "sweep": {
//!   "ranges": ["p=0:4:41", "mgl=-1:2:31"],
//!   "boundaries": [{"expression": "p^2 - 4*mgl*I1", "label": "p^2 = 4 mgl I1"}],
//!   "reference_sigma2": [{"expression": "sigma^2", "label": "paper: sigma^2"}],
//!   "domain": ["I1 + I2 - 1/2"]
//! }
//! ```
//!
//! Every expression is a polynomial in the spec's parameters (division only
//! by constants), so it is exact and cheap to evaluate on a fine grid. A
//! boundary is the zero set of its expression; a domain entry keeps the
//! points where its expression is `>= 0`.

use crate::document::SweepDoc;
use crate::json::{child, index, Result, SpecError};
use exact::{parse_expression, parse_number, Poly, Rational, Symbols};

/// Largest number of points in one swept range.
pub const MAX_RANGE_COUNT: u64 = 1_000_000_000;

/// One swept parameter: `NAME=START:STOP:COUNT`, `COUNT` points evenly spaced
/// from `START` to `STOP` inclusive (exact rationals).
#[derive(Clone, Debug, PartialEq)]
pub struct ParamRange {
    /// The parameter's name.
    pub name: String,
    /// First value.
    pub start: Rational,
    /// Last value.
    pub stop: Rational,
    /// Number of grid points (at least 1; exactly 1 when `start == stop`).
    pub count: u64,
}

/// Why a range `NAME=START:STOP:COUNT` was refused (the message says what
/// is wrong, without a path: callers add the option or the JSON path).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct RangeError(pub String);

impl ParamRange {
    /// Parse `NAME=START:STOP:COUNT` (`START` and `STOP` are numbers or
    /// rationals such as `3/10`). The error says what is wrong, without a
    /// path: callers add the option or the JSON path.
    ///
    /// ```
    /// let r = spec::ParamRange::parse("p=0:4:41").unwrap();
    /// assert_eq!((r.name.as_str(), r.count), ("p", 41));
    /// assert_eq!(r.value(10).to_string(), "1");
    /// assert!(spec::ParamRange::parse("p=0:4:0").unwrap_err().to_string().contains("COUNT"));
    /// assert!(spec::ParamRange::parse("p=4:0:5").unwrap_err().to_string().contains("START"));
    /// ```
    pub fn parse(text: &str) -> std::result::Result<ParamRange, RangeError> {
        let Some((name, range)) = text.split_once('=') else {
            return Err(RangeError(format!("'{text}': expected NAME=START:STOP:COUNT")));
        };
        let name = name.trim();
        if !crate::parse::is_identifier(name) {
            return Err(RangeError(format!("'{name}' is not a parameter name (letters, digits, '_')")));
        }
        let parts: Vec<&str> = range.split(':').collect();
        if parts.len() != 3 {
            return Err(RangeError(format!(
                "'{text}': expected NAME=START:STOP:COUNT with three ':'-separated fields"
            )));
        }
        let number = |s: &str, what: &str| {
            parse_number(s).map_err(|e| RangeError(format!("'{text}': {what} '{}' is not a number: {e}", s.trim())))
        };
        let start = number(parts[0], "START")?;
        let stop = number(parts[1], "STOP")?;
        let count: u64 = parts[2]
            .trim()
            .parse()
            .map_err(|_| RangeError(format!("'{text}': COUNT '{}' is not a positive integer", parts[2].trim())))?;
        if count == 0 {
            return Err(RangeError(format!("'{text}': COUNT must be at least 1, got 0")));
        }
        if count > MAX_RANGE_COUNT {
            return Err(RangeError(format!("'{text}': COUNT must be at most {MAX_RANGE_COUNT}, got {count}")));
        }
        if start > stop {
            return Err(RangeError(format!(
                "'{text}': START ({start}) exceeds STOP ({stop}); ranges run upwards (swap them: {name}={stop}:{start}:{count})"
            )));
        }
        if start == stop && count != 1 {
            return Err(RangeError(format!("'{text}': START equals STOP, so COUNT must be 1, got {count}")));
        }
        if start != stop && count == 1 {
            return Err(RangeError(format!("'{text}': COUNT 1 needs START equal to STOP (a single value)")));
        }
        Ok(ParamRange { name: name.to_string(), start, stop, count })
    }

    /// The `i`-th grid value `start + i (stop - start)/(count - 1)`, exactly.
    pub fn value(&self, i: u64) -> Rational {
        if self.count == 1 {
            return self.start.clone();
        }
        let step = (&self.stop - &self.start) / Rational::from_integer((self.count - 1).into());
        &self.start + &(step * Rational::from_integer(i.into()))
    }

    /// The value a fraction `k / 2^32` of the way from `start` to `stop`
    /// (random sampling draws `k` uniformly from `0..=2^32`, so the values
    /// are exact rationals with small denominators).
    pub fn fraction(&self, k: u64) -> Rational {
        let span = &self.stop - &self.start;
        &self.start + &(span * Rational::new(k.into(), (1u64 << 32).into()))
    }

    /// `NAME=START:STOP:COUNT` again.
    pub fn to_text(&self) -> String {
        format!("{}={}:{}:{}", self.name, self.start, self.stop, self.count)
    }
}

/// A polynomial in the spec's parameters, with a label for charts.
#[derive(Clone, Debug)]
pub struct Annotation {
    /// What to call it on a chart.
    pub label: String,
    /// The expression as written.
    pub expression: String,
    names: Vec<String>,
    poly: Poly,
}

impl Annotation {
    /// Evaluate at parameter values given by name; missing names take
    /// `defaults` (the spec's own values).
    pub fn eval(&self, value: impl Fn(&str) -> Option<f64>) -> f64 {
        let x: Vec<f64> = self.names.iter().map(|n| value(n).unwrap_or(f64::NAN)).collect();
        self.poly.eval_f64(&x)
    }

    /// Evaluate exactly (every parameter must be given).
    pub fn eval_exact(&self, value: impl Fn(&str) -> Option<Rational>) -> Option<Rational> {
        let x: Option<Vec<Rational>> = self.names.iter().map(|n| value(n)).collect();
        Some(self.poly.eval(&x?))
    }
}

/// The parsed `sweep` section.
#[derive(Clone, Debug, Default)]
pub struct SweepSection {
    /// Default ranges (the command line's `--param` replaces them).
    pub ranges: Vec<ParamRange>,
    /// Analytic stability boundaries: zero sets of their expressions.
    pub boundaries: Vec<Annotation>,
    /// Reference `Sigma^2` formulas (e.g. the paper's claims) to compare with.
    pub reference_sigma2: Vec<Annotation>,
    /// The points kept: every expression `>= 0`.
    pub domain: Vec<Annotation>,
}

impl SweepSection {
    /// Whether the exact parameter values lie in the domain.
    pub fn in_domain(&self, value: impl Fn(&str) -> Option<Rational>) -> bool {
        self.domain.iter().all(|d| d.eval_exact(&value).is_some_and(|v| !v.is_negative()))
    }
}

/// Read the optional `sweep` section; `names` are the spec's parameters.
pub(crate) fn read_sweep_section(doc: Option<&SweepDoc>, path: &str, names: &[String]) -> Result<SweepSection> {
    let Some(doc) = doc else { return Ok(SweepSection::default()) };
    let mut s = SweepSection::default();
    let symbols = Symbols::new(names);
    let poly = |text: &str, p: &str| -> Result<Poly> {
        parse_expression(text, &symbols).map_err(|e| {
            SpecError::new(p, format!("in '{text}': {e} (a polynomial in the parameters {})", names.join(", ")))
        })
    };
    let rpath = child(path, "ranges");
    for (i, e) in doc.ranges.iter().flatten().enumerate() {
        let p = index(&rpath, i);
        let range = ParamRange::parse(e).map_err(|m| SpecError::new(&p, m.0))?;
        if !names.contains(&range.name) {
            return Err(SpecError::new(&p, unknown_parameter(&range.name, names)));
        }
        if s.ranges.iter().any(|q: &ParamRange| q.name == range.name) {
            return Err(SpecError::new(&p, format!("parameter '{}' is swept twice", range.name)));
        }
        s.ranges.push(range);
    }
    for (key, list) in [("boundaries", &doc.boundaries), ("reference_sigma2", &doc.reference_sigma2)] {
        let lpath = child(path, key);
        for (i, e) in list.iter().flatten().enumerate() {
            let epath = child(&index(&lpath, i), "expression");
            let text = &e.expression;
            let label = e.label.clone().unwrap_or_else(|| text.clone());
            let a = Annotation { label, expression: text.clone(), names: names.to_vec(), poly: poly(text, &epath)? };
            if key == "boundaries" {
                s.boundaries.push(a)
            } else {
                s.reference_sigma2.push(a)
            }
        }
    }
    let lpath = child(path, "domain");
    for (i, text) in doc.domain.iter().flatten().enumerate() {
        let p = index(&lpath, i);
        s.domain.push(Annotation {
            label: format!("{text} >= 0"),
            expression: text.clone(),
            names: names.to_vec(),
            poly: poly(text, &p)?,
        });
    }
    Ok(s)
}

/// "unknown parameter" with the known ones listed.
pub fn unknown_parameter(name: &str, names: &[String]) -> String {
    if names.is_empty() {
        format!("unknown parameter '{name}': the spec has no parameters")
    } else {
        format!("unknown parameter '{name}' (the spec's parameters: {})", names.join(", "))
    }
}

/// A rational as a double (for records and charts).
pub fn to_f64(r: &Rational) -> f64 {
    r.to_f64().unwrap_or_else(|| exact::rational_to_f64(r))
}
