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
//!
//! ```
//! let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/rigid-body-major-axis.json")).unwrap();
//! let spec = spec::parse_spec(&text).unwrap();
//! let cert = spec::certify(&spec);
//! assert_eq!(cert.json["verdict"], "stable");
//! let report = spec::check_certificate(&cert.json.to_string()).unwrap();
//! assert_eq!(report.verdict, "stable");
//! // Tampering with Sigma^2 is caught.
//! let mut bad = cert.json.clone();
//! bad["sigma2"] = serde_json::json!(0.09);
//! assert!(spec::check_certificate(&bad.to_string()).is_err());
//! ```
#![warn(missing_docs)]

mod certificate;
mod check;
mod claims;
mod json;
mod parse;
mod pretty;
mod settings;

pub use certificate::{certificate_json, certify, spec_digest, Certificate, CERTIFICATE_VERSION, ENGINE_VERSION};
pub use check::{check_certificate, check_certificate_value, CheckError, CheckReport, FLOAT_TOLERANCE};
pub use claims::{verify_claims, ClaimFailure};
pub use json::SpecError;
pub use parse::{parse_spec, spec_from_value, CasimirSource, Spec, Stopping, MAX_NOISE_FIELDS};
pub use pretty::to_pretty_json;
pub use settings::EngineSettings;
