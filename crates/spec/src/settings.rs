//! Engine settings: defaults, reading from a spec's optional `settings`
//! object ([`SettingsDoc`]), and writing them into certificates.
//!
//! Each setting is named once, as a field of [`SettingsDoc`]; its default is
//! the engine's `Default` and its range is in [`RANGES`]. The JSON Schema
//! (`schema/spec.schema.json`) takes both from here.

use crate::document::{Index, Real, SettingsDoc};
use crate::json::{Result, SpecError};
use serde_json::Value;

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

/// The accepted range `[min, max]` of every numeric setting.
pub const RANGES: &[(&str, f64, f64)] = &[
    ("definiteness_tolerance", 1e-15, 0.5),
    ("search_iterations", 1.0, 100_000.0),
    ("search_expansions", 0.0, 10.0),
    ("max_denominator", 16.0, 1e12),
    ("instability_tolerance", 1e-15, 0.5),
    ("discovery_degree", 0.0, 8.0),
    ("discovery_max_unknowns", 1.0, 20_000.0),
    ("optimisation_tolerance", 1e-14, 0.1),
    ("optimisation_iterations", 1.0, 100_000.0),
];

/// The range of a numeric setting.
pub fn range_of(name: &str) -> Option<(f64, f64)> {
    RANGES.iter().find(|r| r.0 == name).map(|r| (r.1, r.2))
}

/// The value of a setting, checked against its range (integers are exact
/// as doubles far beyond these ranges).
fn in_range(x: f64, name: &str, path: &str) -> Result<f64> {
    let (lo, hi) = range_of(name).unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
    if !(lo..=hi).contains(&x) {
        return Err(SpecError::new(format!("{path}.{name}"), format!("must be between {lo} and {hi}, got {x}")));
    }
    Ok(x)
}

impl EngineSettings {
    /// The defaults with the document's settings applied, each checked
    /// against its range; `path` is the JSON path of the settings object.
    pub fn from_document(doc: &SettingsDoc, path: &str) -> Result<Self> {
        let mut s = EngineSettings::default();
        let real = |x: Option<Real>, name: &str| x.map(|r| in_range(r.0, name, path)).transpose();
        let int =
            |x: Option<Index>, name: &str| x.map(|r| in_range(r.0 as f64, name, path).map(|v| v as u64)).transpose();
        if let Some(x) = real(doc.definiteness_tolerance, "definiteness_tolerance")? {
            s.pipeline.search.definiteness_tolerance = x;
        }
        if let Some(x) = int(doc.search_iterations, "search_iterations")? {
            s.pipeline.search.max_iterations = x as usize;
        }
        if let Some(x) = int(doc.search_expansions, "search_expansions")? {
            s.pipeline.search.max_expansions = x as usize;
        }
        if let Some(x) = int(doc.max_denominator, "max_denominator")? {
            s.pipeline.search.max_denominator = x;
        }
        if let Some(x) = real(doc.instability_tolerance, "instability_tolerance")? {
            s.pipeline.instability_tolerance = x;
        }
        if let Some(x) = int(doc.discovery_degree, "discovery_degree")? {
            s.discovery_degree = x as u32;
        }
        if let Some(x) = int(doc.discovery_max_unknowns, "discovery_max_unknowns")? {
            s.discovery_max_unknowns = x as usize;
        }
        if let Some(x) = doc.optimise {
            s.pipeline.optimise = x;
        }
        if let Some(x) = doc.exact {
            s.pipeline.exact = x;
        }
        if let Some(x) = real(doc.optimisation_tolerance, "optimisation_tolerance")? {
            s.pipeline.optimisation.tolerance = x;
        }
        if let Some(x) = int(doc.optimisation_iterations, "optimisation_iterations")? {
            s.pipeline.optimisation.max_iterations = x as usize;
        }
        Ok(s)
    }

    /// Every setting, as the document a certificate records.
    pub fn to_document(&self) -> SettingsDoc {
        let p = &self.pipeline;
        SettingsDoc {
            definiteness_tolerance: Some(Real(p.search.definiteness_tolerance)),
            search_iterations: Some(Index(p.search.max_iterations as u64)),
            search_expansions: Some(Index(p.search.max_expansions as u64)),
            max_denominator: Some(Index(p.search.max_denominator)),
            instability_tolerance: Some(Real(p.instability_tolerance)),
            discovery_degree: Some(Index(self.discovery_degree as u64)),
            discovery_max_unknowns: Some(Index(self.discovery_max_unknowns as u64)),
            optimise: Some(p.optimise),
            exact: Some(p.exact),
            optimisation_tolerance: Some(Real(p.optimisation.tolerance)),
            optimisation_iterations: Some(Index(p.optimisation.max_iterations as u64)),
        }
    }

    /// Read from an optional JSON object at `path`; absent keys keep their
    /// defaults.
    pub fn from_json(value: Option<&Value>, path: &str) -> Result<Self> {
        match value {
            None => Ok(EngineSettings::default()),
            Some(v) => Self::from_document(&crate::document::from_value_at(v, path)?, path),
        }
    }

    /// The settings as a JSON object (all keys).
    pub fn to_json(&self) -> Value {
        serde_json::to_value(self.to_document()).unwrap_or_default()
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
        // Every numeric setting has a range, every setting is written.
        let all = EngineSettings::default().to_json();
        let numeric = all.as_object().unwrap().iter().filter(|(_, v)| v.is_number()).count();
        assert_eq!(numeric, RANGES.len());
        assert!(RANGES.iter().all(|r| all.get(r.0).is_some()));
        let bad: Value = serde_json::from_str(r#"{"search_expansions": 11}"#).unwrap();
        let e = EngineSettings::from_json(Some(&bad), "$.settings").unwrap_err();
        assert_eq!(e.path, "$.settings.search_expansions");
        assert!(e.message.contains("between 0 and 10"), "{e}");
        let unknown: Value = serde_json::from_str(r#"{"max_doublings": 3}"#).unwrap();
        let e = EngineSettings::from_json(Some(&unknown), "$.settings").unwrap_err();
        assert_eq!(e.path, "$.settings.max_doublings");
    }
}
