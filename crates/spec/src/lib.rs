//! The engine's public contract: spec in, certificate out (docs/architecture.md §4).
//!
//! Three functions serve every kind of spec (finite-dimensional, box,
//! large, fluid, Zeitlin), each taking [`Options`] (progress and
//! cancellation, the folder a spec's files are relative to):
//!
//! * [`parse`] reads any spec; every error is a [`SpecError`] naming the
//!   JSON path (`$.noise[0][1]`) and what is wrong;
//! * [`certify`] runs the matching pipeline and returns an
//!   [`AnyCertificate`]: one [`Header`] for every kind (format version,
//!   engine, [`CertificateKind`], name, [`AnyVerdict`], level, the spec's
//!   SHA-256, settings) and the certificate JSON;
//! * [`check`] re-derives every claim from the embedded spec and compares;
//!   any altered number fails with the path of the field ([`check_json`]
//!   for a certificate read from a file).
//!
//! ```
//! use spec::{certify, check, parse, Options, Verdict};
//! let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/rigid-body-major-axis.json")).unwrap();
//! let cert = certify(&parse(&text, &Options::default()).unwrap(), &Options::default()).unwrap();
//! assert_eq!(check(&cert, &Options::default()).unwrap().verdict, Verdict::Stable);
//! // Tampering with Sigma^2 is caught.
//! let mut bad = cert.json().clone();
//! bad["sigma2"] = serde_json::json!(0.09);
//! assert!(spec::check_json(&bad.to_string(), &Options::default()).is_err());
//! ```
//!
//! Underneath, per kind:
//!
//! * [`parse_spec`] reads the JSON spec (algebra, parameters, Hamiltonian,
//!   Casimirs, first integrals, equilibrium, noise, stopping, settings) into a
//!   validated [`casimir::System`]. Every error is a [`SpecError`] naming the
//!   JSON path (`$.noise[0][1]`) and what is wrong.
//! * [`certify_lie`] runs the finite-dimensional pipeline and builds the
//!   certificate JSON and its typed [`Certificate`]: verdict, `sigma2`,
//!   level, the Casimir choice, exact `P` and `Q` (rational strings),
//!   residuals, the stopping time, the settings, the engine version and the
//!   spec itself.
//! * [`document`] and [`record`]: the contract as serde-derived types
//!   (specs, fluid specs, settings, certificates, fluid certificates). Every
//!   spec is read into a document first (unknown fields, missing fields and
//!   wrong types refused with the JSON path), and every certificate is
//!   written from a record; the JSON Schemas in `schema/` are generated from
//!   these types (`verify schema`).
//! * From Rust without JSON: [`certify_system`] certifies a
//!   [`casimir::System`] built in code, and [`Certificate::check`] re-checks
//!   the result (a heavy top in twelve lines in the docs of [`certify_system`]).
//!
//! The fluid contract (shear flows, [`AnySpec::Fluid`]) is behind the
//! default feature `fluid`; without it the crate does not build the fluid
//! stack (the `fluid` crate and rayon), and a fluid spec or certificate is
//! refused with a message naming the feature.
#![warn(missing_docs)]

pub mod box_cert;
mod certificate;
mod check;
mod claims;
pub mod document;
mod envelope;
#[cfg(feature = "fluid")]
mod fluid;
#[cfg(feature = "fluid")]
mod fluid_simulation;
mod json;
#[cfg(feature = "fluid")]
mod large;
mod library;
mod parse;
mod pretty;
pub mod record;
#[cfg(feature = "fluid")]
mod run_options;
mod settings;
mod sweep;
pub mod theorem;
#[cfg(feature = "fluid")]
mod zeitlin;
#[cfg(feature = "fluid")]
mod zeitlin_fields;
#[cfg(feature = "fluid")]
mod zeitlin_simulation;

pub use certificate::{
    certificate_json, certify_lie, spec_digest, verification_level, Certificate, CERTIFICATE_VERSION, ENGINE_VERSION,
};
pub use check::{check_certificate, check_certificate_value, check_document, CheckError, CheckReport, FLOAT_TOLERANCE};
pub use claims::{verify_claims, ClaimFailure};
pub use envelope::{certify, check, check_json, parse, AnyCertificate, AnyVerdict, CertifyError, Header, Options};
#[cfg(feature = "fluid")]
pub use fluid::{
    certify_fluid, certify_fluid_spec, fluid_certificate_json, fluid_spec_from_value, parse_fluid_spec,
    FluidCertificate, FluidSpec, FLUID_TOLERANCE, MAX_X_MODES, NY_RANGE,
};
pub use outcome::{BoxVerdict, CertificateKind};

#[cfg(feature = "fluid")]
pub use fluid_simulation::{
    simulate_fluid, simulate_fluid_with, FluidSimulation, FluidSimulationError, FluidSimulationOptions, Notes,
    FLUID_EXACT_SECONDS, FLUID_SIMULATION_DEFAULT_NY, FLUID_SIMULATION_DEFAULT_PATHS, FLUID_SIMULATION_DEFAULT_SECONDS,
    FLUID_SIMULATION_GROWTH_TIMES, FLUID_SIMULATION_MAX_NY, FLUID_SIMULATION_MIN_T_END,
    FLUID_SIMULATION_NO_GROWTH_T_END, FLUID_SIMULATION_SECONDS,
};

#[cfg(feature = "fluid")]
pub use zeitlin::{
    analyse_zeitlin, certify_zeitlin, parse_zeitlin_spec, zeitlin_certificate_document, zeitlin_spec_from_value,
    zeitlin_spec_from_value_in, ZeitlinInput, ZeitlinOutcome, ZeitlinSpec, HARMONICS_MAX_N, N_RANGE, ZEITLIN_TOLERANCE,
};

#[cfg(feature = "fluid")]
pub use zeitlin_fields::{zeitlin_fields, ZeitlinFields, ZeitlinFieldsError, ZeitlinMode, ZEITLIN_FIELDS_MAX_N};

#[cfg(feature = "fluid")]
pub use zeitlin_simulation::{
    simulate_zeitlin, ZeitlinSimulationError, ZeitlinSimulationOptions, ZEITLIN_EXACT_SECONDS,
    ZEITLIN_NONLINEAR_DEFAULT_DELTA, ZEITLIN_NONLINEAR_MAX_N, ZEITLIN_NONLINEAR_PATH_SHARE,
    ZEITLIN_SIMULATION_DEFAULT_PATHS, ZEITLIN_SIMULATION_DEFAULT_SECONDS, ZEITLIN_SIMULATION_MAX_N,
    ZEITLIN_SIMULATION_NO_GROWTH_T_END, ZEITLIN_SIMULATION_SECONDS,
};

#[cfg(feature = "fluid")]
pub use large::{
    certify_large, is_large_spec, large_certificate_document, large_spec_from_value, LargeSpec, LARGE_MAX_DIMENSION,
    LARGE_TOLERANCE,
};

/// Whether a spec value is a Zeitlin spec (has a `zeitlin` object at the top).
pub fn is_zeitlin_spec(v: &serde_json::Value) -> bool {
    v.get("zeitlin").is_some()
}

/// Whether a spec value is a fluid spec (has a `fluid` object at the top).
pub fn is_fluid_spec(v: &serde_json::Value) -> bool {
    v.get("fluid").is_some()
}

/// The error for a fluid spec in a build without the `fluid` feature.
#[cfg(not(feature = "fluid"))]
fn fluid_unavailable() -> SpecError {
    SpecError::new("$.fluid", "fluid specs need the `fluid` feature of the spec crate (on by default)")
}
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
    #[cfg(feature = "fluid")]
    Fluid(Box<FluidSpec>),
    /// The stochastic Zeitlin model on the sphere.
    #[cfg(feature = "fluid")]
    Zeitlin(Box<ZeitlinSpec>),
    /// A finite-dimensional system above `algebra::MAX_DIMENSION`
    /// coordinates (the large, floating-point pipeline).
    #[cfg(feature = "fluid")]
    Large(Box<LargeSpec>),
}

impl AnySpec {
    /// The spec's name.
    pub fn name(&self) -> &str {
        match self {
            AnySpec::Lie(s) => &s.name,
            #[cfg(feature = "fluid")]
            AnySpec::Fluid(s) => &s.name,
            #[cfg(feature = "fluid")]
            AnySpec::Zeitlin(s) => &s.name,
            #[cfg(feature = "fluid")]
            AnySpec::Large(s) => &s.name,
        }
    }

    /// The optional `sweep` section.
    pub fn sweep(&self) -> &SweepSection {
        match self {
            AnySpec::Lie(s) => &s.sweep,
            #[cfg(feature = "fluid")]
            AnySpec::Fluid(s) => &s.sweep,
            #[cfg(feature = "fluid")]
            AnySpec::Zeitlin(s) => &s.sweep,
            #[cfg(feature = "fluid")]
            AnySpec::Large(s) => &s.sweep,
        }
    }

    /// The stopping question, if the spec asks it.
    pub fn stopping(&self) -> Option<Stopping> {
        match self {
            AnySpec::Lie(s) => s.stopping,
            #[cfg(feature = "fluid")]
            AnySpec::Fluid(s) => s.stopping,
            #[cfg(feature = "fluid")]
            AnySpec::Zeitlin(s) => s.stopping,
            #[cfg(feature = "fluid")]
            AnySpec::Large(s) => s.stopping,
        }
    }

    /// The spec's parameter values, exactly (a fluid spec's constant
    /// expressions that are not plain numbers are left out).
    pub fn parameters(&self) -> std::collections::BTreeMap<String, exact::Rational> {
        match self {
            AnySpec::Lie(s) => s.parameters.clone(),
            #[cfg(feature = "fluid")]
            AnySpec::Large(s) => s.parameters.clone(),
            #[cfg(feature = "fluid")]
            AnySpec::Fluid(_) | AnySpec::Zeitlin(_) => self
                .raw()
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
            #[cfg(feature = "fluid")]
            AnySpec::Fluid(s) => &s.raw,
            #[cfg(feature = "fluid")]
            AnySpec::Zeitlin(s) => &s.raw,
            #[cfg(feature = "fluid")]
            AnySpec::Large(s) => &s.raw,
        }
    }

    /// Run the matching pipeline and return the certificate JSON,
    /// reporting progress and stopping soon after
    /// [`outcome::Progress::cancel`] (then `Err`, and no certificate): the
    /// body of [`crate::certify`].
    pub(crate) fn certify_with(
        &self,
        progress: &outcome::Progress,
    ) -> std::result::Result<serde_json::Value, outcome::Cancelled> {
        match self {
            AnySpec::Lie(s) => {
                progress.plan(1);
                progress.check()?;
                let json = if s.parameter_box.is_some() { box_cert::certify_box_spec(s) } else { certify_lie(s).json };
                progress.settle();
                Ok(json)
            }
            #[cfg(feature = "fluid")]
            AnySpec::Fluid(s) => Ok(fluid::certify_fluid_with(s, progress)?.json),
            #[cfg(feature = "fluid")]
            AnySpec::Zeitlin(s) => zeitlin::certify_zeitlin_with(s, progress),
            #[cfg(feature = "fluid")]
            AnySpec::Large(s) => large::certify_large_with(s, progress),
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
    parse_any_spec_in(text, None)
}

/// [`parse_any_spec`] for a spec in the folder `base`: the files it names
/// (a Zeitlin field's `.npy`) are relative to it (to the current folder
/// when `None`).
pub(crate) fn parse_any_spec_in(text: &str, base: Option<&std::path::Path>) -> Result<AnySpec, SpecError> {
    // Only a Zeitlin spec reads files (and needs the folder).
    #[cfg(not(feature = "fluid"))]
    let _ = base;
    let value: serde_json::Value = json::parse_json(text)?;
    if is_fluid_spec(&value) {
        #[cfg(feature = "fluid")]
        return fluid_spec_from_value(value).map(|s| AnySpec::Fluid(Box::new(s)));
        #[cfg(not(feature = "fluid"))]
        return Err(fluid_unavailable());
    } else if is_zeitlin_spec(&value) {
        #[cfg(feature = "fluid")]
        return zeitlin_spec_from_value_in(value, base).map(|s| AnySpec::Zeitlin(Box::new(s)));
        #[cfg(not(feature = "fluid"))]
        return Err(SpecError::new(
            "$.zeitlin",
            "Zeitlin specs need the `fluid` feature of the spec crate (on by default)",
        ));
    } else {
        #[cfg(feature = "fluid")]
        if is_large_spec(&value) {
            return large_spec_from_value(value).map(|s| AnySpec::Large(Box::new(s)));
        }
        spec_from_value(value).map(|s| AnySpec::Lie(Box::new(s)))
    }
}

#[cfg(test)]
mod tests {
    /// Without the `fluid` feature a fluid spec or certificate is refused
    /// with a path and the reason; with it, it parses.
    #[test]
    fn fluid_specs_follow_the_feature() {
        let text = r#"{"name": "f", "fluid": {"model": "incompressible", "x_period": 6.283185307179586,
            "y_interval": [-1, 1], "boundary": "walls", "shear_flow": "y^2", "noise": ["y"], "ny": 16, "x_modes": 2}}"#;
        let parsed = super::parse_any_spec(text);
        if cfg!(feature = "fluid") {
            assert!(parsed.is_ok(), "{parsed:?}");
        } else {
            let e = parsed.unwrap_err();
            assert_eq!(e.path, "$.fluid");
            assert!(e.message.contains("`fluid` feature"), "{e}");
            let cert = format!(r#"{{"spec": {text}}}"#);
            assert!(super::check_certificate(&cert).unwrap_err().to_string().contains("`fluid` feature"));
        }
    }
}
