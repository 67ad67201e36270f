//! Engine settings: defaults, reading from a spec's optional `settings`
//! object, and writing them into certificates.

use crate::json::{as_object, check_keys, child, float, index_value, Result, SpecError};
use serde_json::{json, Value};

/// All settings that influence a certificate, with documented defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct EngineSettings {
    /// Pipeline settings (search over the Casimir freedom, instability test).
    pub pipeline: generator::Settings,
    /// Highest degree searched when Casimirs are discovered. Default 4.
    pub discovery_degree: u32,
    /// Largest number of monomials (unknowns) per degree in discovery.
    /// Default 2000; larger degrees are skipped and reported.
    pub discovery_max_unknowns: usize,
}

impl Default for EngineSettings {
    fn default() -> Self {
        EngineSettings { pipeline: generator::Settings::default(), discovery_degree: 4, discovery_max_unknowns: 2000 }
    }
}

/// One setting: its key in `settings`, how it is read (with its range) and
/// how it is written into certificates, in one place.
struct Setting {
    name: &'static str,
    read: fn(&Value, &str, &mut EngineSettings) -> Result<()>,
    write: fn(&EngineSettings) -> Value,
}

fn boolean(v: &Value, path: &str) -> Result<bool> {
    v.as_bool().ok_or_else(|| SpecError::new(path, "expected true or false"))
}

/// Every setting that influences a certificate. The defaults live in
/// [`EngineSettings::default`] and the documented `Default`s of the
/// pipeline's settings.
const SETTINGS: &[Setting] = &[
    Setting {
        name: "definiteness_tolerance",
        read: |v, p, s| {
            s.pipeline.search.definiteness_tolerance = in_range(float(v, p)?, 1e-15, 0.5, p)?;
            Ok(())
        },
        write: |s| json!(s.pipeline.search.definiteness_tolerance),
    },
    Setting {
        name: "search_iterations",
        read: |v, p, s| {
            s.pipeline.search.max_iterations = in_range(index_value(v, p)?, 1, 100_000, p)?;
            Ok(())
        },
        write: |s| json!(s.pipeline.search.max_iterations),
    },
    Setting {
        name: "search_expansions",
        read: |v, p, s| {
            s.pipeline.search.max_expansions = in_range(index_value(v, p)?, 0, 10, p)?;
            Ok(())
        },
        write: |s| json!(s.pipeline.search.max_expansions),
    },
    Setting {
        name: "max_denominator",
        read: |v, p, s| {
            s.pipeline.search.max_denominator = in_range(index_value(v, p)? as u64, 16, 1_000_000_000_000, p)?;
            Ok(())
        },
        write: |s| json!(s.pipeline.search.max_denominator),
    },
    Setting {
        name: "instability_tolerance",
        read: |v, p, s| {
            s.pipeline.instability_tolerance = in_range(float(v, p)?, 1e-15, 0.5, p)?;
            Ok(())
        },
        write: |s| json!(s.pipeline.instability_tolerance),
    },
    Setting {
        name: "discovery_degree",
        read: |v, p, s| {
            s.discovery_degree = in_range(index_value(v, p)?, 0, 8, p)? as u32;
            Ok(())
        },
        write: |s| json!(s.discovery_degree),
    },
    Setting {
        name: "discovery_max_unknowns",
        read: |v, p, s| {
            s.discovery_max_unknowns = in_range(index_value(v, p)?, 1, 20_000, p)?;
            Ok(())
        },
        write: |s| json!(s.discovery_max_unknowns),
    },
    Setting {
        name: "optimise",
        read: |v, p, s| {
            s.pipeline.optimise = boolean(v, p)?;
            Ok(())
        },
        write: |s| json!(s.pipeline.optimise),
    },
    Setting {
        name: "exact",
        read: |v, p, s| {
            s.pipeline.exact = boolean(v, p)?;
            Ok(())
        },
        write: |s| json!(s.pipeline.exact),
    },
    Setting {
        name: "optimisation_tolerance",
        read: |v, p, s| {
            s.pipeline.optimisation.tolerance = in_range(float(v, p)?, 1e-14, 0.1, p)?;
            Ok(())
        },
        write: |s| json!(s.pipeline.optimisation.tolerance),
    },
    Setting {
        name: "optimisation_iterations",
        read: |v, p, s| {
            s.pipeline.optimisation.max_iterations = in_range(index_value(v, p)?, 1, 100_000, p)?;
            Ok(())
        },
        write: |s| json!(s.pipeline.optimisation.max_iterations),
    },
];

fn in_range<T: PartialOrd + std::fmt::Display>(v: T, lo: T, hi: T, path: &str) -> Result<T> {
    if v < lo || v > hi {
        return Err(SpecError::new(path, format!("must be between {lo} and {hi}, got {v}")));
    }
    Ok(v)
}

impl EngineSettings {
    /// Read from an optional JSON object; absent keys keep their defaults.
    pub fn from_json(value: Option<&Value>, path: &str) -> Result<Self> {
        let mut s = EngineSettings::default();
        let Some(value) = value else { return Ok(s) };
        let map = as_object(value, path)?;
        let keys: Vec<&str> = SETTINGS.iter().map(|k| k.name).collect();
        check_keys(map, &keys, path)?;
        for (key, v) in map {
            let p = child(path, key);
            match SETTINGS.iter().find(|k| k.name == key) {
                Some(setting) => (setting.read)(v, &p, &mut s)?,
                None => return Err(SpecError::new(&p, format!("unknown setting '{key}'"))),
            }
        }
        Ok(s)
    }

    /// The settings as a JSON object (all keys).
    pub fn to_json(&self) -> Value {
        Value::Object(SETTINGS.iter().map(|k| (k.name.to_string(), (k.write)(self))).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every setting that can be read is written into certificates and
    /// reads back to the same value (non-default values, so a setting that
    /// is dropped on either side is noticed); a bad value names its path.
    #[test]
    fn settings_round_trip_through_certificates() {
        let text = r#"{"definiteness_tolerance": 1e-7, "search_iterations": 50, "search_expansions": 2,
            "max_denominator": 1000, "instability_tolerance": 1e-5, "discovery_degree": 3,
            "discovery_max_unknowns": 500, "optimise": false, "exact": false,
            "optimisation_tolerance": 1e-4, "optimisation_iterations": 77}"#;
        let v: Value = serde_json::from_str(text).unwrap();
        let s = EngineSettings::from_json(Some(&v), "$.settings").unwrap();
        assert_ne!(s, EngineSettings::default());
        let (written, given) = (s.to_json(), v.clone());
        for (k, x) in given.as_object().unwrap() {
            let y = &written[k.as_str()];
            assert!(x.as_f64() == y.as_f64() && x.as_bool() == y.as_bool(), "{k}: {x} written as {y}");
        }
        assert_eq!(EngineSettings::from_json(Some(&s.to_json()), "$.settings").unwrap(), s);
        assert_eq!(EngineSettings::default().to_json().as_object().unwrap().len(), SETTINGS.len());
        let bad: Value = serde_json::from_str(r#"{"search_expansions": 11}"#).unwrap();
        let e = EngineSettings::from_json(Some(&bad), "$.settings").unwrap_err();
        assert_eq!(e.path, "$.settings.search_expansions");
        assert!(e.message.contains("between 0 and 10"), "{e}");
        let unknown: Value = serde_json::from_str(r#"{"max_doublings": 3}"#).unwrap();
        assert!(EngineSettings::from_json(Some(&unknown), "$.settings").is_err());
    }
}
