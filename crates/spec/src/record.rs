//! The certificate of a finite-dimensional spec as a typed document
//! ([`CertificateDocument`]): the engine builds its certificates from this
//! type, [`check_certificate`](crate::check_certificate) reads a certificate
//! into it before re-deriving it (so a malformed one is refused with the
//! JSON path of the field), and a Rust user reads the claims from it with
//! their types: exact rationals for `P`, `Q` and the Casimir choice,
//! [`Verdict`] and [`VerificationLevel`] for the outcome.
//!
//! ```
//! let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/rigid-body-major-axis.cert.json")).unwrap();
//! let value: serde_json::Value = serde_json::from_str(&text).unwrap();
//! let doc: spec::record::CertificateDocument = spec::document::from_value(&value).unwrap();
//! assert_eq!(doc.verdict, spec::Verdict::Stable);
//! // The rigid body about its major axis (I = 3, 2, 1, sigma = 3/10):
//! // Sigma^2 = sigma^2 I1 (I2 - I3) / (I3 (I1 - I2)) = 27/100 (tests/it/library.rs).
//! assert_eq!(doc.sigma2_exact.as_deref(), Some("27/100"));
//! assert_eq!(doc.p.unwrap().len(), 3);
//! ```

use crate::document::SettingsDoc;
use outcome::CertificateKind;
use outcome::{Verdict, VerificationLevel};
use schemars::{json_schema, JsonSchema, Schema, SchemaGenerator};
use serde::de::{self, Deserializer};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::borrow::Cow;
use std::collections::BTreeMap;

/// A double as certificates write it: a JSON number, or `"infinity"`,
/// `"-infinity"`, `"nan"` for the values JSON has no number for.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Float(pub f64);

impl Serialize for Float {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        crate::certificate::float_json(self.0).serialize(s)
    }
}

impl<'de> Deserialize<'de> for Float {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        match Value::deserialize(d)? {
            Value::Number(n) => n.as_f64().map(Float).ok_or_else(|| de::Error::custom("not a double")),
            Value::String(s) if s == "infinity" => Ok(Float(f64::INFINITY)),
            Value::String(s) if s == "-infinity" => Ok(Float(f64::NEG_INFINITY)),
            Value::String(s) if s == "nan" => Ok(Float(f64::NAN)),
            other => Err(de::Error::custom(format!(
                "expected a number (or \"infinity\", \"-infinity\", \"nan\"), found {}",
                crate::json::type_name(&other)
            ))),
        }
    }
}

impl JsonSchema for Float {
    fn schema_name() -> Cow<'static, str> {
        "Float".into()
    }
    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        json_schema!({"anyOf": [{"type": "number"}, {"enum": ["infinity", "-infinity", "nan"]}]})
    }
}

/// An exact rational as the engine writes it into certificates: `p/q` with
/// integers of any size up to [`exact::MAX_CERTIFICATE_DIGITS`] digits
/// (exact arithmetic produces entries such as `1/10^600` that no double
/// holds), or a number as a spec writes it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ExactRational(pub exact::Rational);

impl Serialize for ExactRational {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.0.to_string())
    }
}

impl<'de> Deserialize<'de> for ExactRational {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let text = crate::document::number_text(d, "a rational")?;
        exact::parse_certificate_rational(&text)
            .or_else(|_| exact::parse_number(&text))
            .map(ExactRational)
            .map_err(de::Error::custom)
    }
}

impl JsonSchema for ExactRational {
    fn schema_name() -> Cow<'static, str> {
        "ExactRational".into()
    }
    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        json_schema!({
            "description": "An exact rational written by the engine: an integer or p/q of integers (any size), as a string.",
            "type": ["string", "number"]
        })
    }
}

/// A matrix of exact rationals, by rows.
pub type RationalMatrix = Vec<Vec<ExactRational>>;

/// The certificate of a finite-dimensional spec (docs/architecture.md §4). Optional
/// parts are present when the verdict has them: `casimir_choice`, `P`, `Q`,
/// `growth`, `optimisation` for `stable`; `instability` for a floating-point
/// `linearly_unstable`; `search` for `inconclusive`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(title = "verify: certificate of a stochastic Lie-Poisson system")]
pub struct CertificateDocument {
    /// Format version ([`crate::CERTIFICATE_VERSION`]).
    pub certificate_version: u64,
    /// The engine that wrote it.
    pub engine: Engine,
    /// The spec's name.
    pub name: String,
    /// The verdict.
    pub verdict: Verdict,
    /// Why, in a sentence.
    pub reason: String,
    /// What the verdict rests on.
    pub level: VerificationLevel,
    /// The statement proved (or estimated), generated from the data.
    pub theorem: crate::theorem::TheoremRecord,
    /// What each part of the verdict rests on, part by part.
    pub checks: BTreeMap<String, String>,
    /// `Sigma^2` (stable verdicts).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma2: Option<Float>,
    /// `Sigma^2` as an exact rational upper bound.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma2_exact: Option<String>,
    /// Whether `sigma2_exact` equals the largest generalized eigenvalue.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma2_sharp: Option<bool>,
    /// The stopping-time bound, when the spec asks.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopping: Option<StoppingRecord>,
    /// SHA-256 of the embedded spec's compact JSON.
    pub spec_sha256: String,
    /// The Hamiltonian as read.
    pub hamiltonian: String,
    /// The coordinates.
    pub coordinates: Vec<String>,
    /// The equilibrium and its exact residual.
    pub equilibrium: EquilibriumRecord,
    /// The noise fields, their residuals and the isotropy algebra.
    pub noise: NoiseRecord,
    /// The conserved quantities.
    pub conserved: Vec<ConservedRecord>,
    /// How far Casimir discovery looked, when it ran.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub casimir_discovery: Option<DiscoveryRecord>,
    /// The multipliers that make the first variation vanish.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub multipliers: Option<MultipliersRecord>,
    /// `A`, the `B_k` and the spectrum of `A`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub linearisation: Option<LinearisationRecord>,
    /// How the spectral claim was proved.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spectrum_proof: Option<String>,
    /// Why the spectrum could not be computed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spectrum_error: Option<String>,
    /// The unstable eigenpair (floating point).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub instability: Option<InstabilityRecord>,
    /// How close the search for a definite form came.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub search: Option<SearchRecord>,
    /// The Casimir choice that makes `P` definite.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub casimir_choice: Option<ChoiceRecord>,
    /// The optimisation of `Sigma^2` over the Casimir freedom.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub optimisation: Option<OptimisationRecord>,
    /// The second variation `P` (exact).
    #[serde(default, skip_serializing_if = "Option::is_none", rename = "P")]
    pub p: Option<RationalMatrix>,
    /// The noise form `Q` (exact).
    #[serde(default, skip_serializing_if = "Option::is_none", rename = "Q")]
    pub q: Option<RationalMatrix>,
    /// Exact residuals of the stable verdict.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub residuals: Option<ResidualsRecord>,
    /// The generalized eigenproblem `Q v = l P v` in floating point.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub growth: Option<GrowthRecord>,
    /// The settings in force (all of them).
    pub settings: SettingsDoc,
    /// Which route certified the system, and why.
    pub route: RouteRecord,
    /// The spec exactly as given.
    pub spec: Value,
}

/// The two routes of a finite-dimensional spec: the size decides which,
/// never the meaning of the spec.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Route {
    /// Dense matrices in rational arithmetic (at most 64 coordinates).
    DenseExact,
    /// Sparse exact structure checks, the method in floating point, and a
    /// verified floating-point final check (above 64 coordinates).
    SparseFloat,
}

/// Which route certified a finite-dimensional spec, why, and the settings
/// it could not honour.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RouteRecord {
    /// The route.
    pub route: Route,
    /// Why this route (the spec's size).
    pub why: String,
    /// The settings the spec gives that this route does not honour, each
    /// with the reason (the route runs with its own value instead).
    pub settings_not_honoured: BTreeMap<String, String>,
}

/// The engine's name and version.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Engine {
    /// `verify`.
    pub name: String,
    /// The crate version.
    pub version: String,
}

/// `P(|dmu_t|_P^2 > epsilon) <= (delta/epsilon) exp(Sigma^2 t)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct StoppingRecord {
    /// The threshold.
    pub epsilon: Float,
    /// The initial size.
    pub delta: Float,
    /// `ln(epsilon/delta)/Sigma^2`, rounded down (`"infinity"` when `Sigma^2 = 0`).
    #[serde(rename = "T")]
    pub t: Float,
    /// The bound in words.
    pub bound: String,
}

/// The equilibrium and its residual `ad*_{dH} mu_e` (exact).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct EquilibriumRecord {
    /// The point.
    pub point: Vec<ExactRational>,
    /// The residual (zero at an equilibrium).
    pub residual: Vec<ExactRational>,
}

/// The noise fields, `ad*_{xi_k} mu_e`, and the isotropy algebra of `mu_e`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NoiseRecord {
    /// The fields `xi_k`.
    pub fields: Vec<Vec<ExactRational>>,
    /// `ad*_{xi_k} mu_e` (zero for compatible noise).
    pub residuals: Vec<Vec<ExactRational>>,
    /// A basis of the noise that would be compatible.
    pub isotropy_basis: Vec<Vec<ExactRational>>,
}

/// A conserved quantity.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ConservedRecord {
    /// `casimir` or `first_integral`.
    pub kind: String,
    /// `spec`, `builtin` or `discovered`.
    pub source: String,
    /// The polynomial.
    pub expression: String,
    /// Whether it Poisson-commutes with each noise field's momentum map.
    pub commutes_with_noise: Vec<bool>,
}

/// How far Casimir discovery looked.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DiscoveryRecord {
    /// Highest degree searched.
    pub degree_searched: u32,
    /// Degrees skipped for size.
    pub skipped_degrees: Vec<u32>,
}

/// The affine family of multipliers with a vanishing first variation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MultipliersRecord {
    /// A particular solution.
    pub particular: Vec<ExactRational>,
    /// Free directions.
    pub directions: Vec<Vec<ExactRational>>,
}

/// The linearisation at the equilibrium.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LinearisationRecord {
    /// The drift `A`.
    #[serde(rename = "A")]
    pub a: RationalMatrix,
    /// The noise matrices `B_k`.
    #[serde(rename = "B")]
    pub b: Vec<RationalMatrix>,
    /// Eigenvalues of `A` (floating point).
    pub spectrum: Vec<ComplexRecord>,
}

/// A complex number.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ComplexRecord {
    /// Real part.
    pub re: Float,
    /// Imaginary part.
    pub im: Float,
}

/// An eigenvalue of `A` with positive real part, and its eigenvector.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct InstabilityRecord {
    /// The eigenvalue.
    pub eigenvalue: ComplexRecord,
    /// The eigenvector.
    pub eigenvector: Vec<ComplexRecord>,
    /// The tolerance it exceeds.
    pub tolerance: Float,
}

/// The best margins of a search that found no definite form.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SearchRecord {
    /// Best relative margin towards a positive definite `P`.
    pub best_positive_margin: Float,
    /// Best relative margin towards a negative definite `P`.
    pub best_negative_margin: Float,
    /// Dimension of the space the form was restricted to.
    pub restricted_dimension: u64,
}

/// A Casimir choice: multipliers, family parameters and `M`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ChoiceRecord {
    /// The sign of `P` (+1 or -1).
    pub sign: i64,
    /// Coordinates along the free multiplier directions.
    pub family_parameters: Vec<ExactRational>,
    /// The multipliers.
    pub multipliers: Vec<ExactRational>,
    /// The symmetric matrix of the quadratic Casimir terms.
    #[serde(rename = "M")]
    pub m: RationalMatrix,
    /// The smallest eigenvalue of `sP` relative to the largest.
    pub relative_margin: Float,
}

/// The optimisation of `Sigma^2` over the Casimir freedom.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OptimisationRecord {
    /// Whether the optimiser ran.
    pub optimised: bool,
    /// The first definite choice found.
    pub first_definite_choice: ChoiceRecord,
    /// Its `Sigma^2`.
    pub first_definite_sigma2: Float,
    /// Estimated infimum over the family.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub infimum: Option<Float>,
    /// A certified lower bound on `Sigma^2` over the family (exact).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub infimum_lower_bound: Option<String>,
    /// The vector that certifies the lower bound.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub infimum_witness: Option<Vec<ExactRational>>,
    /// The matrix that certifies the lower bound (free multipliers).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub infimum_witness_matrix: Option<RationalMatrix>,
    /// `sigma2 - infimum`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gap: Option<Float>,
    /// Whether the infimum is attained.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub attained: Option<bool>,
    /// Whether the gap is within the tolerance.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub within_tolerance: Option<bool>,
    /// Whether `Q` depends on `M`.
    #[serde(default, skip_serializing_if = "Option::is_none", rename = "q_depends_on_M")]
    pub q_depends_on_m: Option<bool>,
    /// The method.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub method: Option<String>,
    /// The optimiser's tolerance.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<Float>,
}

/// Exact residuals of a stable verdict.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ResidualsRecord {
    /// `A^T P + P A` (zero: the energy-Casimir form is conserved by the drift).
    pub drift: RationalMatrix,
    /// Whether the paper's formula (3.3) gives the same `Q`.
    #[serde(rename = "paper_formula_3_3_equals_Q")]
    pub paper_formula_3_3_equals_q: bool,
}

/// The generalized eigenproblem `Q v = l P v` in floating point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GrowthRecord {
    /// The largest eigenvalue.
    pub largest_generalized_eigenvalue: Float,
    /// The condition number of `P`.
    #[serde(rename = "condition_number_P")]
    pub condition_number_p: Float,
    /// All eigenvalues.
    pub generalized_eigenvalues: Vec<Float>,
    /// The eigenvector of the largest, `v^T P v = 1`.
    pub fastest_direction: Vec<Float>,
}

/// The JSON Schema of certificates of finite-dimensional specs, generated
/// from [`CertificateDocument`] (committed as
/// `schema/certificate.schema.json`).
pub fn certificate_schema() -> Value {
    serde_json::to_value(schemars::schema_for!(CertificateDocument)).unwrap_or(Value::Null)
}

/// A verification level, or `"none"` when no claim is made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LevelOrNone(pub Option<VerificationLevel>);

impl Serialize for LevelOrNone {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(VerificationLevel::name_of(self.0))
    }
}

impl<'de> Deserialize<'de> for LevelOrNone {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        if s == "none" {
            return Ok(LevelOrNone(None));
        }
        VerificationLevel::deserialize(de::value::StrDeserializer::<D::Error>::new(&s)).map(|l| LevelOrNone(Some(l)))
    }
}

impl JsonSchema for LevelOrNone {
    fn schema_name() -> Cow<'static, str> {
        "LevelOrNone".into()
    }
    fn json_schema(g: &mut SchemaGenerator) -> Schema {
        let level = g.subschema_for::<VerificationLevel>();
        json_schema!({"anyOf": [level, {"const": "none"}]})
    }
}

/// The certificate of a fluid spec (docs/fluid-guide.md, "Fluids"): the claims are about
/// the discretised linear SDE, per x-mode, with the convergence table beside
/// them. When the profile cannot be discretised (a singularity at a grid
/// node) the verdict is `inconclusive` and the analysis parts are absent.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(title = "verify: certificate of a stochastic shear flow")]
pub struct FluidCertificateDocument {
    /// Format version ([`crate::CERTIFICATE_VERSION`]).
    pub certificate_version: u64,
    /// The engine that wrote it.
    pub engine: Engine,
    /// The spec's name.
    pub name: String,
    /// `fluid`.
    pub kind: CertificateKind,
    /// The verdict.
    pub verdict: Verdict,
    /// Why, in a sentence.
    pub reason: String,
    /// What the verdict rests on (`none`: no claim).
    pub level: LevelOrNone,
    /// The statement proved (or estimated), generated from the data.
    pub theorem: crate::theorem::TheoremRecord,
    /// What each part rests on.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checks: Option<BTreeMap<String, String>>,
    /// `Sigma^2`, the largest per-mode Lanczos value (a lower estimate).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma2: Option<Float>,
    /// A proved upper bound of `Sigma^2` (verified per mode).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma2_upper: Option<Float>,
    /// The stopping-time bound, from `sigma2_upper`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopping: Option<StoppingRecord>,
    /// SHA-256 of the embedded spec's compact JSON.
    pub spec_sha256: String,
    /// `incompressible` or `compressible`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<String>,
    /// The equations, in words.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub formulation: Option<String>,
    /// The discretisation in x and y.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub discretisation: Option<DiscretisationRecord>,
    /// The conserved form used.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub form: Option<FluidFormRecord>,
    /// Per x-mode results.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub modes: Option<Vec<ModeRecord>>,
    /// `Sigma^2` at every resolution of the convergence table.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub convergence: Option<Vec<ConvergenceRecord>>,
    /// The paper's bound and choice beside ours.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub paper: Option<PaperRecord>,
    /// The optimisation over the Galilean shift.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub optimisation: Option<FluidOptimisationRecord>,
    /// `max |A^T V + V A|` relative, for the form used.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub drift_residual: Option<Float>,
    /// The growing mode, when linearly unstable.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub instability: Option<UnstableModeRecord>,
    /// What the instability search tried, per x-mode, when no definite form
    /// was found: the grids, the candidate on each and why it stopped.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub instability_search: Option<Vec<ModeSearchRecord>>,
    /// The compressible model's noise-compatibility test.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub compressible: Option<CompressibleRecord>,
    /// The settings in force (all of them).
    pub settings: crate::document::FluidSettingsDoc,
    /// The pipeline's fixed constants (`fluid::constants`).
    pub constants: BTreeMap<String, Float>,
    /// The spec exactly as given.
    pub spec: Value,
}

/// The discretisation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DiscretisationRecord {
    /// In x.
    pub x: String,
    /// In y.
    pub y: String,
    /// Grid points in y.
    pub ny: u64,
    /// Unknowns per x-mode.
    pub unknowns_per_mode: u64,
    /// x-modes.
    pub x_modes: u64,
}

/// The conserved form `e H + C_Phi + c M`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FluidFormRecord {
    /// `energy_casimir`, `pseudomomentum`, `enstrophy` or `none`.
    pub kind: String,
    /// `e`.
    pub energy_coefficient: Float,
    /// `c` (null: none).
    pub galilean_shift: Option<Float>,
    /// `+1`, `-1`, or `0` when there is no form.
    pub sign: Float,
    /// `Phi''(omega_e)` in words.
    pub casimir_weight: String,
}

/// One x-mode.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ModeRecord {
    /// Mode number.
    pub m: u64,
    /// Wavenumber `2 pi m / x_period`.
    pub k: Float,
    /// Lanczos value (lower estimate).
    pub sigma2: Float,
    /// Verified upper bound (null: not verified).
    pub sigma2_upper: Option<Float>,
    /// Whether `V` was verified definite.
    pub form_verified: bool,
    /// Lanczos iterations.
    pub lanczos_iterations: u64,
}

/// One row of the convergence table.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ConvergenceRecord {
    /// Resolution.
    pub ny: u64,
    /// `Sigma^2` at this resolution.
    pub sigma2: Option<Float>,
    /// `Sigma^2` of the paper's choice at this resolution.
    pub sigma2_paper_choice: Option<Float>,
}

/// The paper's constants.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PaperRecord {
    /// The paper's bound.
    pub bound: Option<Float>,
    /// Its formula.
    pub bound_formula: String,
    /// `Sigma^2` of the paper's choice.
    pub choice_sigma2: Option<Float>,
    /// The paper's choice in words.
    pub choice: String,
}

/// A point of the shift curve.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ShiftPoint {
    /// Galilean shift `c`.
    pub c: Float,
    /// `Sigma^2` at `c`.
    pub sigma2: Float,
}

/// The optimisation over the conserved form.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FluidOptimisationRecord {
    /// What is optimised over.
    pub over: String,
    /// `Sigma^2` against the shift.
    pub shift_curve: Vec<ShiftPoint>,
    /// The infimum found.
    pub infimum: Option<Float>,
    /// The form that attains it.
    pub attained_by: String,
    /// A form outside that family that gives `Sigma^2 = 0` on this grid but
    /// has no continuum limit (`U''` vanishing only at the walls).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub discrete_pseudomomentum: Option<DiscretePseudomomentumRecord>,
}

/// The discrete pseudomomentum `V = diag(m_a / |U''(y_a)|)`: conserved by the
/// discretised linear SDE, degenerate under refinement.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DiscretePseudomomentumRecord {
    /// What it is and why it is not the headline.
    pub meaning: String,
    /// Its `Sigma^2` (zero: `Q = 0`).
    pub sigma2: Float,
    /// Under refinement, coarsest first.
    pub rows: Vec<PseudomomentumRowRecord>,
}

/// The discrete pseudomomentum at one resolution.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PseudomomentumRowRecord {
    /// Resolution.
    pub ny: u64,
    /// `cond(V)`.
    pub condition_number: Float,
    /// `sum_a m_a / |U''(y_a)|`: the squared `V`-norm of `omega = 1`.
    pub norm_of_one: Float,
}

/// The fastest-growing mode whose rate converged between two grids (on a
/// grid past the dense ones, the eigenvalue followed from the coarser grids:
/// a lower bound on that grid's fastest growth).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct UnstableModeRecord {
    /// Mode number.
    pub m: u64,
    /// Wavenumber.
    pub k: Float,
    /// Growth rate at `ny`.
    pub growth_rate: Float,
    /// Growth rate at half the resolution.
    pub growth_rate_half_resolution: Float,
    /// Resolution.
    pub ny: u64,
}

/// The instability search of one x-mode.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ModeSearchRecord {
    /// Mode number.
    pub m: u64,
    /// Wavenumber.
    pub k: Float,
    /// The growth rate a candidate must exceed to count.
    pub floor: Float,
    /// The grids tried, in order, each twice the one before.
    pub grids: Vec<SearchedGridRecord>,
    /// `converged`, `below_floor`, `not_converged` (up to the resolution
    /// limit) or `solve_failed`.
    pub outcome: String,
}

/// One grid of an instability search and its candidate eigenvalue
/// `c` of the drift (`exp(ik(x - c t))`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SearchedGridRecord {
    /// Resolution.
    pub ny: u64,
    /// The candidate's growth rate `k Im c` (absent: the solve failed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub growth_rate: Option<Float>,
    /// Its phase speed `Re c`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub phase_speed: Option<Float>,
    /// `false`: the eigenvalue of largest `Im c` (dense); `true`: the one
    /// nearest the coarser grids' candidate (shift-invert on the banded
    /// pencil).
    pub tracked: bool,
}

/// The compressible model's noise-compatibility test.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CompressibleRecord {
    /// The sound speed.
    pub sound_speed: Float,
    /// `sup |U eta_k' + r_k'|` per noise field.
    pub noise_residuals: Vec<Float>,
    /// The formula.
    pub noise_residual_formula: String,
    /// Which noise is compatible.
    pub compatible_noise: String,
    /// When some noise field is incompatible: the spec's noise list with
    /// each such field completed by its compatible potential, ready to paste
    /// as `fluid.noise`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub compatible_completion: Option<Vec<Value>>,
    /// The ends `[c_lo, c_hi]` of the admissible shifts (null: none); the
    /// sonic end (`|U + c| = c_s` somewhere) is excluded, the other included.
    pub galilean_shift_interval: Option<Vec<Float>>,
    /// The incompressible verdict of the same flow.
    pub incompressible_verdict: Verdict,
    /// Its `Sigma^2`.
    pub incompressible_sigma2: Option<Float>,
    /// The discretised compressible generator, when compatible noise with
    /// non-constant transport needed it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub generator: Option<GeneratorRecord>,
}

/// The compressible generator's evidence (docs/fluids.md §1b).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GeneratorRecord {
    /// The formulation and the generator form.
    pub formulation: String,
    /// The Galilean shift `c` of the form.
    pub galilean_shift: Float,
    /// A rigorous upper bound of the continuum `Sigma^2` of every x-mode
    /// (null: not enclosed).
    pub continuum_bound: Option<Float>,
    /// Its formula.
    pub continuum_bound_formula: String,
    /// What the Casimir defect measures.
    pub casimir_defect_meaning: String,
    /// The Casimir defect of the gravest mode at each resolution of the table.
    pub casimir_defect: Vec<DefectPoint>,
    /// The discretised linear SDE itself, with the pointwise noise (null:
    /// a defect could not be computed).
    pub discrete_sde: Option<DiscreteSdeRecord>,
    /// `|K A + A^H K| / (|K| |A|)` of the gravest mode (dense, at the coarsest
    /// grid of at most 64).
    pub drift_residual: Option<Float>,
}

/// What the certificate gives for the discretised SDE with the pointwise noise.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DiscreteSdeRecord {
    /// What the fields mean.
    pub meaning: String,
    /// The resolution (the spec's `ny`).
    pub ny: u64,
    /// The x-mode where `sigma2` is attained.
    pub m: u64,
    /// The largest `lambda_max(Q_B, K)` over the certified x-modes.
    pub sigma2: Float,
}

/// The Casimir defect at one resolution.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DefectPoint {
    /// Resolution.
    pub ny: u64,
    /// `|lambda|_max(Q_B - Q, K)`.
    pub defect: Float,
}

/// The JSON Schema of fluid certificates (committed as
/// `schema/fluid-certificate.schema.json`).
pub fn fluid_certificate_schema() -> Value {
    serde_json::to_value(schemars::schema_for!(FluidCertificateDocument)).unwrap_or(Value::Null)
}

/// A Zeitlin certificate (`kind: "zeitlin"`): the stochastic su(N) model
/// about a zonal equilibrium (docs/zeitlin.md).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(title = "verify: certificate of a stochastic Zeitlin model")]
pub struct ZeitlinCertificateDocument {
    /// Format version ([`crate::CERTIFICATE_VERSION`]).
    pub certificate_version: u64,
    /// The engine that wrote it.
    pub engine: Engine,
    /// The spec's name.
    pub name: String,
    /// `zeitlin`.
    pub kind: CertificateKind,
    /// The verdict.
    pub verdict: Verdict,
    /// Why, in a sentence.
    pub reason: String,
    /// What the verdict rests on (`none`: no claim).
    pub level: LevelOrNone,
    /// The statement proved (or estimated), generated from the data.
    pub theorem: crate::theorem::TheoremRecord,
    /// What each part rests on.
    pub checks: BTreeMap<String, String>,
    /// `Sigma^2 = max(0, max_m lambda_max(Q_m, P_m))` at the chosen form.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma2: Option<Float>,
    /// A proved upper bound on `Sigma^2` (`verified_float`), from which the
    /// stopping time is computed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma2_upper: Option<Float>,
    /// The stopping-time bound from `sigma2_upper` (or `sigma2` under exact
    /// structure, or when no bound was proved).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopping: Option<StoppingRecord>,
    /// Which time the rates and the stopping time are per: quflow's `t`,
    /// with the same quantities per unit `qtime` beside them.
    pub time: ZeitlinTimeRecord,
    /// SHA-256 of the embedded spec's compact JSON.
    pub spec_sha256: String,
    /// The model and its conventions.
    pub model: ZeitlinModelRecord,
    /// The conserved functional, when one is definite.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub form: Option<ZeitlinFormRecord>,
    /// `lambda_max(Q_m, P_m)` per off-diagonal block `m = 1..N-1`, when
    /// stable with the energy in the form (empty under exact structure:
    /// `Q = 0`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub blocks: Vec<ZeitlinBlockRecord>,
    /// `|[P_e, W_e]| / hbar`, `max_i |[X_i, W_e]| / hbar` and the largest
    /// relative `|sym(P A)|` on random probes.
    pub residuals: ZeitlinResidualsRecord,
    /// The fastest growth rate `max Re lambda(A)` over the blocks, when the
    /// drift's spectrum was computed (no definite form).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub growth_rate: Option<Float>,
    /// Fields given by harmonics: the frame of the analysis.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame: Option<ZeitlinFrameRecord>,
    /// Fields given by harmonics, incompatible noise: each field's
    /// compatible part (its projection onto the matrices that commute with
    /// `W_e`), as harmonics `[l, m, value]` to paste back into the spec.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub compatible_noise: Vec<Vec<(u64, i64, Float)>>,
    /// Fields given by harmonics, zonal in no frame: the dense analysis.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dense: Option<ZeitlinDenseRecord>,
    /// Fields given by harmonics, zonal in no frame, above `dense_max_n`:
    /// the matrix-free analysis.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub matrix_free: Option<ZeitlinMatrixFreeRecord>,
    /// The settings in force (all of them).
    pub settings: crate::document::ZeitlinSettingsDoc,
    /// The spec exactly as given.
    pub spec: Value,
}

/// The time a Zeitlin certificate's rates are per.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ZeitlinTimeRecord {
    /// `t`: the model's time, quflow's `time` dataset.
    pub unit: String,
    /// What that means for a quflow user, in words.
    pub meaning: String,
    /// `sigma2`, `sigma2_upper`, `growth_rate` and the stopping time `T`
    /// per unit `qtime = t / hbar`, the unit of quflow's integrator steps.
    pub per_qtime: ZeitlinPerQtimeRecord,
}

/// A Zeitlin certificate's rates and stopping time per unit `qtime`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ZeitlinPerQtimeRecord {
    /// `hbar sigma2` (an estimate, as `sigma2` is).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma2: Option<Float>,
    /// `hbar sigma2_upper`, rounded up (still a bound).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma2_upper: Option<Float>,
    /// `hbar growth_rate`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub growth_rate: Option<Float>,
    /// `stopping.T / hbar`, rounded down (still a time the bound holds to).
    #[serde(default, rename = "T", skip_serializing_if = "Option::is_none")]
    pub stopping_time: Option<Float>,
}

/// The Zeitlin model's conventions.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ZeitlinModelRecord {
    /// `N`.
    #[serde(rename = "N")]
    pub n: u64,
    /// `N^2 - 1`, the dimension of su(N).
    pub dimension: u64,
    /// `hbar = 2 / sqrt(N^2 - 1)`.
    pub hbar: Float,
    /// The equations, in words.
    pub formulation: String,
    /// How the zonal functions become matrices.
    pub quantisation: String,
    /// The Legendre coefficients `a_1..a_L` of the equilibrium (quflow's
    /// normalisation), up to the last nonzero one and at most 64 of them.
    pub equilibrium_coefficients: Vec<Float>,
    /// The same for each noise field's stream function.
    pub noise_coefficients: Vec<Vec<Float>>,
    /// The `.npy` files read, with their SHA-256 (a changed file no longer
    /// matches its certificate).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub files: Vec<ZeitlinFileRecord>,
}

/// A `.npy` file a Zeitlin spec read.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ZeitlinFileRecord {
    /// The spec field (`$.zeitlin.equilibrium`, `$.zeitlin.noise[0]`).
    pub field: String,
    /// The path as the spec gives it.
    pub path: String,
    /// SHA-256 of the file's bytes, hex.
    pub sha256: String,
}

/// The conserved functional `eps H + C_Phi + beta J`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ZeitlinFormRecord {
    /// What the family is and what was searched.
    pub family: String,
    /// The energy coefficient `eps` (`+1`, `-1` or `0`).
    pub energy_coefficient: Float,
    /// The momentum coefficient `beta`.
    pub momentum_coefficient: Float,
    /// `Phi''` where it is free (repeated eigenvalues, the diagonal block).
    pub free_curvature: Float,
    /// Whether the minimum of `Sigma^2` over the family is attained (false
    /// when approached at the edge of the definite arc, or at the search's
    /// bound on `beta`: monotone profiles, whose infimum over `eps = ±1` is 0).
    pub attained: bool,
}

/// One off-diagonal block.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ZeitlinBlockRecord {
    /// The diagonal `m`.
    pub m: u64,
    /// `lambda_max(Q_m, P_m)` (Lanczos; not floored).
    pub lambda_max: Float,
}

/// The residuals of a Zeitlin analysis.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ZeitlinResidualsRecord {
    /// `|[P_e, W_e]| / hbar` (zero: both diagonal).
    pub equilibrium: Float,
    /// `max_i |[X_i, W_e]| / hbar` (zero: both diagonal).
    pub noise: Float,
    /// The largest relative `|sym(P A)|` on random probes (zero up to
    /// rounding for a conserved form).
    pub drift: Float,
}

/// The frame in which a state given by harmonics was analysed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ZeitlinFrameRecord {
    /// `zonal` (diagonal as given), `rotated` (zonal about `axis`) or
    /// `general` (zonal in no frame).
    pub kind: String,
    /// The axis `n` with `[n.S, W_e] = 0`, for `rotated`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis: Option<[Float; 3]>,
    /// The largest relative off-diagonal part dropped in the zonal frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub off_diagonal: Option<Float>,
    /// How the frame was found and what it implies.
    pub meaning: String,
}

/// The dense energy–Casimir analysis of a state zonal in no frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ZeitlinDenseRecord {
    /// `N^2 - 1`.
    pub dimension: u64,
    /// Whether the eigenvalues of `W_e` are distinct (else no
    /// energy–Casimir test is made).
    pub distinct_eigenvalues: bool,
    /// `max over eps = ±1 of lambda_min(eps R) / max |eig R|`, `R` the
    /// Hessian of `H + C_Phi` restricted to the orbit's tangent space
    /// (positive: definite; null when no test was made).
    pub restricted_margin: Option<Float>,
    /// The energy coefficient of a definite form (0: none).
    pub energy_coefficient: Float,
    /// The infimum of `Sigma^2` over the Casimir Hessian, when definite.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub infimum: Option<Float>,
    /// `cond(P)` of the chosen form, when definite.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub condition_number: Option<Float>,
    /// `|P A + A^T P|_F / (|P|_F |A|_F)` for `P` the Hessian of `H + C_Phi`.
    pub drift_residual: Float,
}

/// The matrix-free analysis of a state zonal in no frame
/// (`zeitlin::matrix_free`): operators applied to `N x N` matrices, never
/// formed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ZeitlinMatrixFreeRecord {
    /// `N^2 - 1`.
    pub dimension: u64,
    /// Whether the eigenvalues of `W_e` are distinct (else no
    /// energy–Casimir test is made).
    pub distinct_eigenvalues: bool,
    /// The smallest and largest Lanczos Ritz values of the Hessian of `H +
    /// C_Phi` restricted to the orbit's tangent space (each lies within the
    /// spectrum: a negative and a positive one prove it indefinite); one
    /// within 1e-12 of the larger in size is rounding and given as 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub restricted_ritz: Option<[Float; 2]>,
    /// Whether the Ritz values prove the restricted Hessian indefinite.
    pub indefinite: bool,
    /// `max |<R X, A Y> + <A X, R Y>| / (|R X| |A Y| + |A X| |R Y|)` over
    /// three random pairs (zero to rounding for a conserved form).
    pub drift_residual: Float,
    /// `|A|_est = max |pi_j - pi_k| / hbar + |K|_est` (the scale of the
    /// backward error).
    pub drift_norm: Float,
    /// The growing eigenvalue `[real part, imaginary part]`, when accepted.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eigenvalue: Option<[Float; 2]>,
    /// Its backward error `|A v - lambda v|_F / |v|_F`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub backward_error: Option<Float>,
    /// The rightmost converged eigenvalue `[real part, imaginary part,
    /// backward error]` when its real part is above `resolution` but it
    /// was not accepted (below the resolution a real part is rounding, and
    /// is not recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub best: Option<[Float; 3]>,
    /// Real parts below `1e-4 |W_e|_op` are not told apart from zero.
    pub resolution: Float,
}

/// The JSON Schema of a Zeitlin certificate.
pub fn zeitlin_certificate_schema() -> Value {
    serde_json::to_value(schemars::schema_for!(ZeitlinCertificateDocument)).unwrap_or(Value::Null)
}

/// The certificate of a finite-dimensional spec above
/// `algebra::MAX_DIMENSION` coordinates, from the large pipeline (floating
/// point: the matrices are not listed, `check` re-derives them).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(title = "verify: certificate of a large finite-dimensional system")]
pub struct LargeCertificateDocument {
    /// Version of the certificate format.
    pub certificate_version: u64,
    /// The engine that wrote it.
    pub engine: Engine,
    /// The spec's name.
    pub name: String,
    /// `large`.
    pub kind: CertificateKind,
    /// The verdict.
    pub verdict: Verdict,
    /// Why, in a sentence.
    pub reason: String,
    /// What the verdict rests on (`none`: no claim).
    pub level: LevelOrNone,
    /// The statement proved (or estimated), generated from the data.
    pub theorem: crate::theorem::TheoremRecord,
    /// What each part rests on.
    pub checks: BTreeMap<String, String>,
    /// `Sigma^2` at the chosen form, when stable.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma2: Option<Float>,
    /// A proved upper bound on `Sigma^2` (level `verified_float`): `P ≻ 0`
    /// and `sigma2_upper P - Q ≻ 0` for the exact second variation
    /// (docs/large.md). `check` accepts a smaller value only if it proves it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma2_upper: Option<Float>,
    /// The infimum of `Sigma^2` over the Casimir Hessian, when `Q` does not
    /// depend on it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub infimum: Option<Float>,
    /// The stopping time.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopping: Option<StoppingRecord>,
    /// SHA-256 of the embedded spec's compact JSON.
    pub spec_sha256: String,
    /// The dimension.
    pub dimension: u64,
    /// What the pipeline computed on the way.
    pub analysis: LargeAnalysisRecord,
    /// The settings the spec gives, as given (absent when it gives none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub settings: Option<Value>,
    /// Which route certified the system, why, and the settings it did not
    /// honour.
    pub route: RouteRecord,
    /// The spec exactly as given.
    pub spec: Value,
}

/// The large pipeline's intermediate results.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LargeAnalysisRecord {
    /// Nonzero components `[index, value]` of `ad*_{Dh} mu_e` (exact).
    pub equilibrium_residual: Vec<(u64, ExactRational)>,
    /// The noise fields that move the equilibrium.
    pub incompatible_noise: Vec<u64>,
    /// The multipliers (Casimirs, then first integrals).
    pub multipliers: Vec<Float>,
    /// `|G lambda + Dh| / |Dh|`.
    pub multiplier_residual: Float,
    /// Free multiplier directions (searched by the ellipsoid method).
    pub family_dimension: u64,
    /// `dim ker G^T`.
    pub restricted_dimension: u64,
    /// `+1`, `-1`, or 0 for no definite form.
    pub sign: Float,
    /// The larger relative margin of `±R` on `ker G^T` (null when not computed).
    pub restricted_margin: Option<Float>,
    /// Whether `Q` depends on the Casimir Hessian.
    pub q_depends_on_casimirs: bool,
    /// `cond(sP)` of the chosen form.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub condition_number: Option<Float>,
    /// `|P A + A^T P|_F / (|P|_F |A|_F)`.
    pub drift_residual: Float,
    /// The drift's largest real part, when its spectrum was computed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub growth_rate: Option<Float>,
    /// The exact multipliers of the verified functional (`G lambda + Dh = 0`
    /// exactly), when the verified check ran.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exact_multipliers: Option<Vec<ExactRational>>,
    /// Why a stable verdict has no verified bound, when it has none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub verification: Option<String>,
}

/// The JSON Schema of a large system's certificate.
pub fn large_certificate_schema() -> Value {
    serde_json::to_value(schemars::schema_for!(LargeCertificateDocument)).unwrap_or(Value::Null)
}
