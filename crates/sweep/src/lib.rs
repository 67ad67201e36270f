//! Parameter sweeps and stability maps.
//!
//! A sweep certifies one spec at many parameter values and writes one JSON
//! line per point (parameters, verdict, `Sigma^2`, `T(eps, delta)`, level),
//! so that sweeps can be split into shards, concatenated, and resumed after
//! an interruption.
//!
//! * [`Plan`]: the points — a grid over [`spec::ParamRange`]s or seeded
//!   random samples in their box — numbered so any subset is reproducible.
//! * [`Evaluator`]: certifies the spec at one point ([`Outcome`]);
//!   [`record_line`] writes it.
//! * [`run`]: the points of a [`Shard`] not yet [`Done`], in parallel,
//!   streamed to a writer; [`scan`] reads an output file back for resuming.
//! * [`sweep_id`]: the identity of a sweep (spec, plan, level), written in
//!   every line so that lines of different sweeps are never mixed.
//!
//! ```
//! let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/lagrange-top-fast.json")).unwrap();
//! let spec = spec::parse_any_spec(&text).unwrap();
//! let plan = sweep::Plan::new(vec![spec::ParamRange::parse("p=0:4:5").unwrap()], sweep::Sampling::Grid).unwrap();
//! let id = sweep::sweep_id(&spec, &plan, sweep::Level::Spec);
//! let ev = sweep::Evaluator::new(spec, vec!["p".into()], sweep::Level::Spec).unwrap();
//! let mut out = Vec::new();
//! let summary = sweep::run(&ev, &plan, &id, sweep::Shard::ALL, &sweep::Done::none(), &mut out, &|_| {}).unwrap();
//! assert_eq!(summary.computed, 5);
//! // p = 0, 1: slow top (p^2 < 4 mgl I1 = 4), unstable; p = 2: the threshold; p = 3, 4: stable.
//! let text = String::from_utf8(out).unwrap();
//! let verdict = |p: &str| text.lines().find(|l| l.contains(&format!("\"p\":\"{p}\""))).unwrap().to_string();
//! assert!(verdict("1").contains("linearly_unstable"));
//! assert!(verdict("3").contains("\"stable\""));
//! ```
#![warn(missing_docs)]

mod plan;
mod point;
mod resume;
mod run;

pub use plan::{Plan, PlanError, Sampling, Shard, MAX_POINTS};
pub use point::{
    outcome_from_certificate, outcome_from_line, record_line, Evaluator, Level, Outcome, UnknownParameter, Verdict,
    VerificationLevel,
};
pub use resume::{scan, Existing, ResumeError};
pub use run::{run, Done, Summary};

/// The identity of the swept spec, written in every line: the first 16 hex
/// digits of its SHA-256 ([`spec::spec_digest`]), so that lines met with a
/// spec elsewhere (`verify plot-sweep`) can be told apart from another
/// spec's.
///
/// ```
/// let a = spec::parse_any_spec(r#"{"name": "a", "algebra": "so3", "hamiltonian": "Pi1^2/6 + Pi2^2/4 + Pi3^2/2",
///   "casimirs": ["(Pi1^2 + Pi2^2 + Pi3^2)/2"], "equilibrium": [1, 0, 0], "noise": [[0.3, 0, 0]]}"#).unwrap();
/// let b = spec::parse_any_spec(r#"{"name": "b", "algebra": "so3", "hamiltonian": "Pi1^2/6 + Pi2^2/4 + Pi3^2/2",
///   "casimirs": ["(Pi1^2 + Pi2^2 + Pi3^2)/2"], "equilibrium": [1, 0, 0], "noise": [[0.3, 0, 0]]}"#).unwrap();
/// assert_eq!(sweep::spec_tag(&a).len(), 16);
/// assert_ne!(sweep::spec_tag(&a), sweep::spec_tag(&b));
/// ```
pub fn spec_tag(spec: &spec::AnySpec) -> String {
    spec::spec_digest(spec.raw()).chars().take(16).collect()
}

/// The identity of a sweep: 16 hex digits of SHA-256 over the spec's digest,
/// the plan (ranges and sampling, not the shard) and the level. Shards of one
/// sweep share it; changing anything that changes the records changes it.
pub fn sweep_id(spec: &spec::AnySpec, plan: &Plan, level: Level) -> String {
    use sha2::{Digest, Sha256};
    let text = format!("{}\n{}\n{:?}", spec::spec_digest(spec.raw()), plan.describe(), level);
    let hash = Sha256::digest(text.as_bytes());
    hash.iter().take(8).map(|b| format!("{b:02x}")).collect()
}
