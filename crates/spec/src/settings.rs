//! Engine settings: defaults, reading from a spec's optional `settings`
//! object, and writing them into certificates.

use crate::json::{as_object, check_keys, child, float, index_value, Result, SpecError};
use casimir::SearchSettings;
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

const KEYS: &[&str] = &[
    "definiteness_tolerance",
    "search_iterations",
    "search_expansions",
    "max_denominator",
    "instability_tolerance",
    "discovery_degree",
    "discovery_max_unknowns",
    "optimise",
    "exact",
    "optimisation_tolerance",
    "optimisation_iterations",
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
        check_keys(map, KEYS, path)?;
        for (key, v) in map {
            let p = child(path, key);
            match key.as_str() {
                "definiteness_tolerance" => {
                    s.pipeline.search.definiteness_tolerance = in_range(float(v, &p)?, 1e-15, 0.5, &p)?
                }
                "search_iterations" => {
                    s.pipeline.search.max_iterations = in_range(index_value(v, &p)?, 1, 100_000, &p)?
                }
                "search_expansions" => s.pipeline.search.max_expansions = in_range(index_value(v, &p)?, 0, 10, &p)?,
                "max_denominator" => {
                    s.pipeline.search.max_denominator = in_range(index_value(v, &p)? as u64, 16, 1_000_000_000_000, &p)?
                }
                "instability_tolerance" => s.pipeline.instability_tolerance = in_range(float(v, &p)?, 1e-15, 0.5, &p)?,
                "discovery_degree" => s.discovery_degree = in_range(index_value(v, &p)?, 0, 8, &p)? as u32,
                "discovery_max_unknowns" => s.discovery_max_unknowns = in_range(index_value(v, &p)?, 1, 20_000, &p)?,
                "optimise" => {
                    s.pipeline.optimise = v.as_bool().ok_or_else(|| SpecError::new(&p, "expected true or false"))?;
                }
                "exact" => {
                    s.pipeline.exact = v.as_bool().ok_or_else(|| SpecError::new(&p, "expected true or false"))?;
                }
                "optimisation_tolerance" => {
                    s.pipeline.optimisation.tolerance = in_range(float(v, &p)?, 1e-14, 0.1, &p)?
                }
                "optimisation_iterations" => {
                    s.pipeline.optimisation.max_iterations = in_range(index_value(v, &p)?, 1, 100_000, &p)?
                }
                other => return Err(SpecError::new(&p, format!("unknown setting '{other}'"))),
            }
        }
        Ok(s)
    }

    /// The settings as a JSON object (all keys).
    pub fn to_json(&self) -> Value {
        let SearchSettings { definiteness_tolerance, max_iterations, max_expansions, max_denominator } =
            self.pipeline.search.clone();
        json!({
            "definiteness_tolerance": definiteness_tolerance,
            "search_iterations": max_iterations,
            "search_expansions": max_expansions,
            "max_denominator": max_denominator,
            "instability_tolerance": self.pipeline.instability_tolerance,
            "discovery_degree": self.discovery_degree,
            "discovery_max_unknowns": self.discovery_max_unknowns,
            "optimise": self.pipeline.optimise,
            "exact": self.pipeline.exact,
            "optimisation_tolerance": self.pipeline.optimisation.tolerance,
            "optimisation_iterations": self.pipeline.optimisation.max_iterations,
        })
    }
}
