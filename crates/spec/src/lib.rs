//! The engine's public contract: spec in, certificate out (DESIGN.md §5).
//!
//! * [`parse_spec`] reads the JSON spec (algebra, parameters, Hamiltonian,
//!   Casimirs, first integrals, equilibrium, noise, stopping, settings) into a
//!   validated [`casimir::System`]. Every error is a [`SpecError`] naming the
//!   JSON path (`$.noise[0][1]`) and what is wrong.
//! * [`certify`] runs the pipeline and builds the certificate JSON: verdict,
//!   `sigma2`, level, the Casimir choice, exact `P` and `Q` (rational strings),
//!   residuals, the stopping time, the settings, the engine version and the
//!   spec itself.
//! * [`check_certificate`] re-derives everything from the embedded spec and
//!   compares; any altered number fails with the path of the field.
//! * From Rust without JSON: [`certify_system`] certifies a
//!   [`casimir::System`] built in code, and [`Certificate::check`] re-checks
//!   the result (a heavy top in twelve lines in the docs of [`certify_system`]).
//!
//! ```
//! let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/rigid-body-major-axis.json")).unwrap();
//! let spec = spec::parse_spec(&text).unwrap();
//! let cert = spec::certify(&spec);
//! assert_eq!(cert.json["verdict"], "stable");
//! let report = spec::check_certificate(&cert.json.to_string()).unwrap();
//! assert_eq!(report.verdict, spec::Verdict::Stable);
//! // Tampering with Sigma^2 is caught.
//! let mut bad = cert.json.clone();
//! bad["sigma2"] = serde_json::json!(0.09);
//! assert!(spec::check_certificate(&bad.to_string()).is_err());
//! ```
#![warn(missing_docs)]

mod certificate;
mod check;
mod claims;
mod fluid;
mod json;
mod library;
mod parse;
mod pretty;
mod settings;
mod sweep;

pub use certificate::{
    certificate_json, certify, spec_digest, verification_level, Certificate, CERTIFICATE_VERSION, ENGINE_VERSION,
};
pub use check::{check_certificate, check_certificate_value, CheckError, CheckReport, FLOAT_TOLERANCE};
pub use claims::{verify_claims, ClaimFailure};
pub use fluid::{
    certify_fluid, check_fluid_certificate, fluid_certificate_json, fluid_spec_from_value, is_fluid_spec,
    parse_fluid_spec, FluidSpec, FLUID_TOLERANCE, MAX_X_MODES, NY_RANGE,
};
pub use json::{parse_json, SpecError, MAX_MESSAGE_BYTES};
pub use library::{certify_system, spec_of_system};
pub use outcome::{Sign, Verdict, VerificationLevel};
pub use parse::{parse_spec, spec_from_value, CasimirSource, Spec, Stopping, MAX_NOISE_FIELDS};
pub use pretty::to_pretty_json;
pub use settings::EngineSettings;
pub use sweep::{to_f64, unknown_parameter, Annotation, ParamRange, RangeError, SweepSection, MAX_RANGE_COUNT};

/// A spec of either kind: a Lie–Poisson system (finite-dimensional) or a
/// shear flow (`"fluid": {...}`).
#[derive(Clone, Debug)]
pub enum AnySpec {
    /// A finite-dimensional system.
    Lie(Box<Spec>),
    /// A fluid.
    Fluid(Box<FluidSpec>),
}

impl AnySpec {
    /// The spec's name.
    pub fn name(&self) -> &str {
        match self {
            AnySpec::Lie(s) => &s.name,
            AnySpec::Fluid(s) => &s.name,
        }
    }

    /// The optional `sweep` section.
    pub fn sweep(&self) -> &SweepSection {
        match self {
            AnySpec::Lie(s) => &s.sweep,
            AnySpec::Fluid(s) => &s.sweep,
        }
    }

    /// The spec's parameter values, exactly (a fluid spec's constant
    /// expressions that are not plain numbers are left out).
    pub fn parameters(&self) -> std::collections::BTreeMap<String, exact::Rational> {
        match self {
            AnySpec::Lie(s) => s.parameters.clone(),
            AnySpec::Fluid(s) => s
                .raw
                .get("parameters")
                .and_then(serde_json::Value::as_object)
                .map(|m| {
                    m.iter()
                        .filter_map(|(k, v)| {
                            let text = v.as_str().map(str::to_string).unwrap_or_else(|| v.to_string());
                            exact::parse_number(&text).ok().map(|r| (k.clone(), r))
                        })
                        .collect()
                })
                .unwrap_or_default(),
        }
    }

    /// The names of the spec's parameters.
    pub fn parameter_names(&self) -> Vec<String> {
        match self.raw().get("parameters").and_then(serde_json::Value::as_object) {
            Some(m) => m.keys().cloned().collect(),
            None => vec![],
        }
    }

    /// The spec as given.
    pub fn raw(&self) -> &serde_json::Value {
        match self {
            AnySpec::Lie(s) => &s.raw,
            AnySpec::Fluid(s) => &s.raw,
        }
    }

    /// Run the matching pipeline and return the certificate JSON.
    pub fn certify(&self) -> serde_json::Value {
        match self {
            AnySpec::Lie(s) => certify(s).json,
            AnySpec::Fluid(s) => certify_fluid(s),
        }
    }
}

/// Parse either kind of spec from JSON text (a top-level `fluid` object
/// selects the fluid pipeline).
///
/// ```
/// let fluid = r#"{"name": "f", "fluid": {"model": "incompressible", "x_period": 6.283185307179586,
///   "y_interval": [-1, 1], "boundary": "walls", "shear_flow": "y^2", "noise": ["y"], "ny": 16, "x_modes": 2}}"#;
/// assert!(matches!(spec::parse_any_spec(fluid).unwrap(), spec::AnySpec::Fluid(_)));
/// ```
pub fn parse_any_spec(text: &str) -> Result<AnySpec, SpecError> {
    let value: serde_json::Value = json::parse_json(text)?;
    if is_fluid_spec(&value) {
        fluid_spec_from_value(value).map(|s| AnySpec::Fluid(Box::new(s)))
    } else {
        spec_from_value(value).map(|s| AnySpec::Lie(Box::new(s)))
    }
}
