//! Box certificates (docs/boxes.md): a spec with a `box` section is
//! certified for every parameter value in the box, by the `boxes` crate,
//! and the certificate is re-checked exactly by `check`.
//!
//! ```
//! let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/rigid-body-major-axis.json")).unwrap();
//! let mut value: serde_json::Value = serde_json::from_str(&text).unwrap();
//! value["box"] = serde_json::json!({"parameters": {"I2": ["3/2", "5/2"]}});
//! let spec = spec::spec_from_value(value).unwrap();
//! let cert = spec::box_cert::certify_box_spec(&spec);
//! assert_eq!(cert["verdict"], "stable");
//! assert_eq!(spec::check_certificate_value(&cert).unwrap().verdict, spec::Verdict::Stable);
//! ```

use crate::certificate::{spec_digest, CERTIFICATE_VERSION, ENGINE_VERSION};
use crate::check::{fail, CheckError, CheckReport};
use crate::document::BoxDoc;
use crate::json::{child, Result, SpecError};
use crate::parse::{spec_from_value, Spec};
use crate::record::{Engine, ExactRational, Float};
use ::boxes::certify::sampled_bound;
use ::boxes::symbolic::value_at;
use ::boxes::{BoxChoice, BoxReport, BoxSettings, BoxVerdict, Leaf, LeafOutcome, ParamBox};
use exact::{Matrix, Rational};
use num_traits::{One, Zero};
use outcome::CertificateKind;
use outcome::{Sign, Verdict};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;

/// Largest `max_depth` accepted.
pub const MAX_BOX_DEPTH: u64 = 40;
/// Largest `max_boxes` accepted.
pub const MAX_BOX_COUNT: u64 = 1_000_000;
/// The start of the reason of a box whose system is refused.
const REFUSED: &str = "the system is not the same for every parameter in the box";
/// The start of the reason of a box whose expressions cannot be kept
/// symbolic in the box parameters (a size limit of the symbolic parser).
const NOT_SYMBOLIC: &str = "the expressions cannot be kept symbolic in the box parameters";

/// Largest number of box parameters.
pub const MAX_BOX_PARAMETERS: usize = 8;

/// A spec's `box` section, validated.
#[derive(Clone, Debug, PartialEq)]
pub struct BoxSection {
    /// The box parameters, in name order.
    pub names: Vec<String>,
    /// Their intervals.
    pub range: ParamBox,
    /// The bisection's bounds and the margin.
    pub settings: BoxSettings,
}

/// Read and validate the `box` section (`path` is its JSON path).
pub(crate) fn read_box_section(
    doc: &BoxDoc,
    path: &str,
    parameters: &BTreeMap<String, Rational>,
) -> Result<BoxSection> {
    let ppath = child(path, "parameters");
    if doc.parameters.is_empty() {
        return Err(SpecError::new(&ppath, "name at least one parameter"));
    }
    if doc.parameters.len() > MAX_BOX_PARAMETERS {
        return Err(SpecError::new(
            &ppath,
            format!(
                "at most {MAX_BOX_PARAMETERS} box parameters (2^p corners are sampled per sub-box), got {}",
                doc.parameters.len()
            ),
        ));
    }
    let mut names = Vec::new();
    let mut lo = Vec::new();
    let mut hi = Vec::new();
    for (name, [a, b]) in &doc.parameters {
        let p = child(&ppath, name);
        let Some(value) = parameters.get(name) else {
            let known: Vec<String> = parameters.keys().cloned().collect();
            return Err(SpecError::new(&p, crate::sweep::unknown_parameter(name, &known)));
        };
        if a.0 >= b.0 {
            return Err(SpecError::new(
                &p,
                format!(
                    "the interval [{}, {}] is empty: LO must be below HI",
                    exact::cut(&a.0.to_string(), 40),
                    exact::cut(&b.0.to_string(), 40)
                ),
            ));
        }
        // The box is about the spec: its own values lie inside, so what
        // `check` reports under the spec's name holds for the spec itself.
        if *value < a.0 || *value > b.0 {
            return Err(SpecError::new(
                &p,
                format!(
                    "the spec's own value {name} = {} lies outside the interval [{}, {}]",
                    exact::cut(&value.to_string(), 40),
                    exact::cut(&a.0.to_string(), 40),
                    exact::cut(&b.0.to_string(), 40)
                ),
            ));
        }
        names.push(name.clone());
        lo.push(a.0.clone());
        hi.push(b.0.clone());
    }
    let mut settings = BoxSettings::default();
    if let Some(d) = doc.max_depth {
        if d > MAX_BOX_DEPTH {
            return Err(SpecError::new(child(path, "max_depth"), format!("at most {MAX_BOX_DEPTH}, got {d}")));
        }
        settings.max_depth = d as u32;
    }
    if let Some(m) = doc.max_boxes {
        if m == 0 || m > MAX_BOX_COUNT {
            return Err(SpecError::new(child(path, "max_boxes"), format!("from 1 to {MAX_BOX_COUNT}, got {m}")));
        }
        settings.max_boxes = m as usize;
    }
    if let Some(m) = &doc.margin {
        if !(m.0 > Rational::zero() && m.0 <= Rational::one()) {
            return Err(SpecError::new(child(path, "margin"), format!("must be above 0 and at most 1, got {}", m.0)));
        }
        settings.margin = m.0.clone();
    }
    if let Some(t) = &doc.sup_tolerance {
        if !(t.0 > Rational::zero() && t.0 <= Rational::from(1000)) {
            return Err(SpecError::new(
                child(path, "sup_tolerance"),
                format!("must be above 0 and at most 1000, got {}", t.0),
            ));
        }
        settings.sup_tolerance = t.0.clone();
    }
    Ok(BoxSection { names, range: ParamBox { lo, hi }, settings })
}

/// A box certificate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(title = "verify: certificate over a box of parameters")]
pub struct BoxCertificateDocument {
    /// Version of the certificate format.
    pub certificate_version: u64,
    /// The engine that wrote it.
    pub engine: Engine,
    /// The spec's name.
    pub name: String,
    /// `box`.
    pub kind: CertificateKind,
    /// `stable` (every sub-box), `linearly_unstable` (every sub-box),
    /// `partly_stable` (some stable), `partly_unstable` (none stable, some
    /// unstable), `undecided`, `not_an_equilibrium` or `noise_incompatible`
    /// (every sub-box), `partly_not_an_equilibrium` or
    /// `partly_noise_incompatible` (some sub-boxes, the others undecided).
    pub verdict: BoxVerdict,
    /// Why, in a sentence.
    pub reason: String,
    /// The statement proved, generated from the data.
    pub theorem: crate::theorem::TheoremRecord,
    /// The box parameters, in name order (the spec's `box` section).
    pub parameters: Vec<String>,
    /// A proved upper bound on `Sigma^2` over the stable sub-boxes (the
    /// largest of their `sigma2_upper`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sup_sigma2: Option<Float>,
    /// The same, exactly.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sup_sigma2_exact: Option<ExactRational>,
    /// The largest `Sigma^2` sampled (at sub-box corners and centres, for
    /// the sub-box's functional): where the sup is approached.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sampled_max: Option<SampleRecord>,
    /// The undecided sub-boxes' share of the box's volume.
    pub undecided_fraction: Float,
    /// The share of the sub-boxes proved linearly unstable.
    pub unstable_fraction: Float,
    /// The share proved not an equilibrium or noise-incompatible (present
    /// when `mu_e` is not an equilibrium, or the noise moves it, for some
    /// parameter of the box).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub excluded_fraction: Option<Float>,
    /// Which bound stopped the bisection (`max_depth`, `max_boxes`), if one did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub limit: Option<String>,
    /// The partition of the box.
    pub sub_boxes: Vec<SubBoxRecord>,
    /// SHA-256 of the embedded spec's compact JSON.
    pub spec_sha256: String,
    /// The spec exactly as given (with its `box` section).
    pub spec: Value,
}

/// A sampled `Sigma^2` and where.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SampleRecord {
    /// The value (floating point).
    pub sigma2: Float,
    /// The parameters, in the order of `parameters`.
    pub at: Vec<ExactRational>,
}

/// One sub-box: what is proved on it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SubBoxRecord {
    /// Lower corner.
    pub lo: Vec<ExactRational>,
    /// Upper corner.
    pub hi: Vec<ExactRational>,
    /// Bisections from the box.
    pub depth: u64,
    /// `stable`, `linearly_unstable`, `not_an_equilibrium`,
    /// `noise_incompatible` or `undecided` (what is proved on this
    /// sub-box; never a `partly_` verdict).
    pub verdict: BoxVerdict,
    /// Why undecided, or what proves the sub-box's verdict (not stable).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// The pointwise verdict at the sub-box's anchor (undecided sub-boxes):
    /// per side, the simplest rational of its middle half.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub anchor_verdict: Option<Verdict>,
    /// Stable: the sign of `P`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sign: Option<i64>,
    /// Stable: the multipliers at the anchor (Casimirs, then first integrals).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub multipliers: Option<Vec<ExactRational>>,
    /// Stable: the conserved quantities whose multipliers stay fixed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub free: Option<Vec<u64>>,
    /// Stable: the rows of `G` solved for the other multipliers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pivot_rows: Option<Vec<u64>>,
    /// Stable: the Casimir function's Hessian `M`.
    #[serde(rename = "M", default, skip_serializing_if = "Option::is_none")]
    pub m: Option<Vec<Vec<ExactRational>>>,
    /// Stable: the proved bound `S` (`S V - sign Q` positive definite on the sub-box).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma2_upper: Option<ExactRational>,
    /// Stable: the largest `Sigma^2` sampled on the sub-box.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma2_sampled: Option<Float>,
}

/// The JSON Schema of box certificates.
pub fn box_certificate_schema() -> Value {
    serde_json::to_value(schemars::schema_for!(BoxCertificateDocument)).unwrap_or(Value::Null)
}

fn exact_vec(v: &[Rational]) -> Vec<ExactRational> {
    v.iter().cloned().map(ExactRational).collect()
}

fn leaf_record(leaf: &Leaf) -> SubBoxRecord {
    let mut r = SubBoxRecord {
        lo: exact_vec(&leaf.range.lo),
        hi: exact_vec(&leaf.range.hi),
        depth: leaf.depth as u64,
        verdict: leaf.outcome.verdict(),
        reason: None,
        anchor_verdict: None,
        sign: None,
        multipliers: None,
        free: None,
        pivot_rows: None,
        m: None,
        sigma2_upper: None,
        sigma2_sampled: None,
    };
    match &leaf.outcome {
        LeafOutcome::Stable { choice, sigma2_upper, sampled, .. } => {
            r.sign = Some(choice.sign as i64);
            r.multipliers = Some(exact_vec(&choice.multipliers));
            r.free = Some(choice.free.iter().map(|&j| j as u64).collect());
            r.pivot_rows = Some(choice.pivot_rows.iter().map(|&j| j as u64).collect());
            r.m = Some(choice.m.to_rows().iter().map(|row| exact_vec(row)).collect());
            r.sigma2_upper = Some(ExactRational(sigma2_upper.clone()));
            r.sigma2_sampled = Some(Float(*sampled));
        }
        LeafOutcome::LinearlyUnstable { criterion }
        | LeafOutcome::NotAnEquilibrium { criterion }
        | LeafOutcome::NoiseIncompatible { criterion } => {
            r.reason = Some(criterion.clone());
        }
        LeafOutcome::Undecided { reason, anchor } => {
            r.reason = Some(reason.clone());
            r.anchor_verdict = *anchor;
        }
    }
    r
}

fn fraction(part: &Rational, whole: &Rational) -> f64 {
    if whole.is_zero() {
        return 0.0;
    }
    exact::rational_to_f64(&(part / whole))
}

/// The statement of a box certificate from what its sub-boxes prove
/// (`volumes`: stable, linearly unstable, excluded, undecided).
fn statement(
    spec: &Spec,
    section: &BoxSection,
    verdict: BoxVerdict,
    volumes: [&Rational; 4],
    sup: Option<&Rational>,
) -> crate::theorem::TheoremRecord {
    // Bounds too long to print are referred to, not cut: a cut number
    // would read as another box.
    let sides: Vec<(String, String)> =
        (0..section.names.len()).map(|i| (section.range.lo[i].to_string(), section.range.hi[i].to_string())).collect();
    let range = if sides.iter().any(|(a, b)| a.len() > 40 || b.len() > 40) {
        "of the spec's box section (its bounds are too long to print here)".to_string()
    } else {
        section
            .names
            .iter()
            .zip(&sides)
            .map(|(n, (a, b))| format!("{} in [{a}, {b}]", exact::cut(n, 40)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let equilibrium = spec
        .raw
        .get("equilibrium")
        .and_then(Value::as_array)
        .map(|v| {
            format!(
                "({})",
                v.iter()
                    .map(|x| x.as_str().map_or_else(|| x.to_string(), str::to_string))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
        .unwrap_or_else(|| "the spec's equilibrium".into());
    let whole = section.range.volume();
    crate::theorem::box_theorem(&crate::theorem::BoxParts {
        name: &spec.name,
        range,
        equilibrium,
        verdict: verdict.as_str(),
        shares: volumes.map(|v| fraction(v, &whole)),
        sup: sup.map(|s| s.to_string()),
    })
}

/// The certificate of a report (`excluded`: whether the equilibrium or the
/// noise fails for some parameter, so the excluded share is stated).
fn document(spec: &Spec, section: &BoxSection, report: &BoxReport, excluded: bool) -> BoxCertificateDocument {
    let sup = report.sup_sigma2();
    let sampled_max = report
        .leaves
        .iter()
        .filter_map(|l| match &l.outcome {
            LeafOutcome::Stable { sampled, sampled_at, .. } => Some((*sampled, sampled_at.clone())),
            _ => None,
        })
        .fold(None::<(f64, Vec<Rational>)>, |best, x| match best {
            Some(b) if b.0 >= x.0 => Some(b),
            _ => Some(x),
        })
        .map(|(v, at)| SampleRecord { sigma2: Float(v), at: exact_vec(&at) });
    let volumes = (report.unstable_volume(), report.excluded_volume(), report.undecided_volume());
    let stable = section.range.volume() - &volumes.0 - &volumes.1 - &volumes.2;
    let theorem = statement(spec, section, report.verdict, [&stable, &volumes.0, &volumes.1, &volumes.2], sup.as_ref());
    BoxCertificateDocument {
        certificate_version: CERTIFICATE_VERSION,
        engine: Engine { name: "verify".into(), version: ENGINE_VERSION.into() },
        name: spec.name.clone(),
        kind: CertificateKind::Box,
        verdict: report.verdict,
        reason: report.reason.clone(),
        theorem,
        parameters: section.names.clone(),
        sup_sigma2: sup.as_ref().map(|s| Float(exact::rational_to_f64_up(s))),
        sup_sigma2_exact: sup.map(ExactRational),
        sampled_max,
        undecided_fraction: Float(fraction(&report.undecided_volume(), &section.range.volume())),
        unstable_fraction: Float(fraction(&report.unstable_volume(), &section.range.volume())),
        excluded_fraction: excluded.then(|| Float(fraction(&report.excluded_volume(), &section.range.volume()))),
        limit: report.limit.map(str::to_string),
        sub_boxes: report.leaves.iter().map(leaf_record).collect(),
        spec_sha256: spec_digest(&spec.raw),
        spec: spec.raw.clone(),
    }
}

/// Certify a spec with a `box` section: the box certificate's JSON. A spec
/// without one, or whose system the box refuses (a Casimir or first
/// integral that holds at the spec's values but not for every parameter,
/// or expressions too large to keep symbolic), gets a certificate with
/// verdict `undecided`, no sub-boxes, and the reason.
pub fn certify_box_spec(spec: &Spec) -> Value {
    let Some(section) = &spec.parameter_box else {
        return serde_json::json!({"error": "the spec has no box section"});
    };
    let refused = |reason: String| BoxReport { verdict: BoxVerdict::Undecided, reason, leaves: vec![], limit: None };
    let (report, excluded) = match spec.box_system(&section.names) {
        Err(e) => (refused(format!("{NOT_SYMBOLIC}: {e}")), false),
        Ok(system) => match system.symbolic() {
            Err(e) => (refused(format!("{REFUSED}: {e}")), false),
            Ok(sym) => {
                let excluded = !sym.equilibrium_holds() || !sym.incompatible_noise().is_empty();
                match ::boxes::certify_box(&system, &section.range, &section.settings) {
                    Ok(r) => (r, excluded),
                    Err(e) => (refused(format!("{REFUSED}: {e}")), false),
                }
            }
        },
    };
    serde_json::to_value(document(spec, section, &report, excluded)).unwrap_or(Value::Null)
}

/// Whether a certificate is a box certificate.
pub fn is_box_certificate(cert: &Value) -> bool {
    cert.get("kind").and_then(Value::as_str) == Some("box")
}

fn rationals(v: &[ExactRational]) -> Vec<Rational> {
    v.iter().map(|x| x.0.clone()).collect()
}

/// Re-check a box certificate: the partition, every sub-box's proof
/// (exactly, from the embedded spec and the recorded choice and bound),
/// every undecided sub-box's reason, and every derived number and sentence
/// (the verdict, the reason, the sup, the fractions, the samples, the
/// limit). Nothing stored is trusted; the choices are only the proofs'
/// inputs. Every field and how it is verified: docs/ci.md.
pub(crate) fn check_box_certificate(cert: &Value) -> std::result::Result<CheckReport, CheckError> {
    let (doc, spec) = read_box_certificate(cert)?;
    let Some(section) = &spec.parameter_box else {
        return Err(fail("$.spec.box", "a box certificate's spec must have a box section".into()));
    };
    if doc.parameters != section.names {
        return Err(fail("$.parameters", "differs from the spec's box section".into()));
    }
    let system = match spec.box_system(&section.names) {
        Ok(s) => s,
        Err(e) => return check_refused(&doc, &spec, section, format!("{NOT_SYMBOLIC}: {e}")),
    };
    let sym = match system.symbolic() {
        Ok(s) => s,
        Err(e) => return check_refused(&doc, &spec, section, format!("{REFUSED}: {e}")),
    };
    let order = check_partition(&doc, &section.range, section.names.len())?;
    let leaves = LeafCheck::new(&system, &sym, section);
    let mut tally = Tally::new();
    for (i, r) in doc.sub_boxes.iter().enumerate() {
        let outcome = leaves.check(r, &format!("$.sub_boxes[{i}]"), &mut tally)?;
        tally.counts.add(&outcome);
    }
    let limit = check_budget(&doc, &order, &leaves, &tally)?;
    if doc.limit.as_deref() != limit {
        return Err(fail(
            "$.limit",
            format!("the sub-boxes show that {} stopped the bisection", limit.unwrap_or("no limit")),
        ));
    }
    check_totals(&doc, &spec, section, leaves.excluded, tally)
}

/// The certificate's shape, version, embedded spec, digest, name and kind:
/// the typed document and the spec it embeds.
fn read_box_certificate(cert: &Value) -> std::result::Result<(BoxCertificateDocument, Spec), CheckError> {
    let map = crate::json::as_object(cert, "$").map_err(CheckError::BadInput)?;
    crate::check::check_engine(map)?;
    let doc: BoxCertificateDocument = crate::document::from_value(cert)
        .map_err(|e| fail(&e.path, format!("not a box certificate as this engine writes them: {}", e.message)))?;
    if doc.certificate_version != CERTIFICATE_VERSION {
        return Err(fail(
            "$.certificate_version",
            format!("is {}, this checker reads version {CERTIFICATE_VERSION}", doc.certificate_version),
        ));
    }
    let spec = spec_from_value(doc.spec.clone()).map_err(|e| {
        fail(
            &format!("$.spec{}", e.path.trim_start_matches('$')),
            format!("the embedded spec is not valid: {}", e.message),
        )
    })?;
    if doc.spec_sha256 != spec_digest(&spec.raw) {
        return Err(fail("$.spec_sha256", "does not match the embedded spec".into()));
    }
    if doc.name != spec.name {
        return Err(fail("$.name", "is not the embedded spec's name".into()));
    }
    if doc.kind != CertificateKind::Box {
        return Err(fail("$.kind", "expected \"box\"".into()));
    }
    Ok((doc, spec))
}

/// A system the box refuses (certify's `undecided` with no sub-boxes, and
/// that reason) claims nothing: the certificate must be exactly that.
fn check_refused(
    doc: &BoxCertificateDocument,
    spec: &Spec,
    section: &BoxSection,
    reason: String,
) -> std::result::Result<CheckReport, CheckError> {
    let expected = BoxCertificateDocument {
        certificate_version: CERTIFICATE_VERSION,
        engine: doc.engine.clone(),
        name: spec.name.clone(),
        kind: CertificateKind::Box,
        verdict: BoxVerdict::Undecided,
        reason: reason.clone(),
        theorem: crate::theorem::box_theorem(&crate::theorem::BoxParts {
            name: &spec.name,
            range: String::new(),
            equilibrium: String::new(),
            verdict: "undecided",
            shares: [0.0; 4],
            sup: None,
        }),
        parameters: section.names.clone(),
        sup_sigma2: None,
        sup_sigma2_exact: None,
        sampled_max: None,
        undecided_fraction: Float(0.0),
        unstable_fraction: Float(0.0),
        excluded_fraction: None,
        limit: None,
        sub_boxes: vec![],
        spec_sha256: doc.spec_sha256.clone(),
        spec: doc.spec.clone(),
    };
    if *doc == expected {
        Ok(CheckReport { name: spec.name.clone(), verdict: Verdict::Inconclusive, level: None, sigma2: None })
    } else {
        Err(fail(
            "$",
            format!(
                "the box refuses the system, so the certificate can only be undecided, with no sub-boxes and the reason '{}'",
                exact::cut(&reason, 200)
            ),
        ))
    }
}

/// What the sub-boxes add up to, as they are checked.
struct Tally {
    /// The largest proved bound over the stable sub-boxes.
    sup: Option<Rational>,
    /// Volumes: undecided, proved unstable, proved excluded.
    undecided: Rational,
    unstable: Rational,
    excluded: Rational,
    counts: ::boxes::LeafCounts,
    /// Sub-boxes left by the budget, and at the largest depth.
    budget: usize,
    at_depth_limit: usize,
    /// The largest re-derived sample, and where.
    sampled_max: Option<(f64, Vec<Rational>)>,
}

impl Tally {
    fn new() -> Self {
        Tally {
            sup: None,
            undecided: Rational::zero(),
            unstable: Rational::zero(),
            excluded: Rational::zero(),
            counts: ::boxes::LeafCounts::default(),
            budget: 0,
            at_depth_limit: 0,
            sampled_max: None,
        }
    }
}

/// The system and the box's settings, for re-proving one sub-box at a time.
struct LeafCheck<'a> {
    system: &'a ::boxes::BoxSystem,
    sym: &'a ::boxes::symbolic::Symbolic,
    settings: &'a BoxSettings,
    n: usize,
    /// The budget of sub-boxes, scaled down for long numbers as certify
    /// does, and the reason a sub-box left by it gives.
    budget_size: usize,
    spent_reason: String,
    /// `mu_e` is not an equilibrium, or the noise moves it, for some
    /// parameter of the box; and the reason a sub-box at the largest depth
    /// then gives.
    excluded: bool,
    unresolved: &'static str,
    charpoly: std::cell::OnceCell<Vec<::boxes::frac::Frac>>,
}

impl<'a> LeafCheck<'a> {
    fn new(system: &'a ::boxes::BoxSystem, sym: &'a ::boxes::symbolic::Symbolic, section: &'a BoxSection) -> Self {
        let settings = &section.settings;
        let (budget_size, bits) = ::boxes::certify::sub_box_budget(system, &section.range, settings.max_boxes);
        LeafCheck {
            system,
            sym,
            settings,
            n: system.dim(),
            budget_size,
            spent_reason: ::boxes::certify::budget_reason(budget_size, settings.max_boxes, bits),
            excluded: !sym.equilibrium_holds() || !sym.incompatible_noise().is_empty(),
            unresolved: if sym.equilibrium_holds() {
                ::boxes::certify::NOISE_UNRESOLVED
            } else {
                ::boxes::certify::EQUILIBRIUM_UNRESOLVED
            },
            charpoly: std::cell::OnceCell::new(),
        }
    }

    /// Re-prove the sub-box recorded at `path` and add it to the tally.
    fn check(&self, r: &SubBoxRecord, path: &str, tally: &mut Tally) -> std::result::Result<LeafOutcome, CheckError> {
        let b = ParamBox { lo: rationals(&r.lo), hi: rationals(&r.hi) };
        match r.verdict {
            BoxVerdict::Stable if self.excluded => Err(fail(
                &format!("{path}.verdict"),
                "mu_e is not an equilibrium (or the noise moves it) for some parameters of the box, so no sub-box is stable".into(),
            )),
            BoxVerdict::Stable => self.stable(r, &b, path, tally),
            BoxVerdict::LinearlyUnstable => {
                let outcome = self.unstable(r, &b, path)?;
                tally.unstable += b.volume();
                Ok(outcome)
            }
            BoxVerdict::NotAnEquilibrium | BoxVerdict::NoiseIncompatible => {
                let outcome = self.excluded(r, &b, path)?;
                tally.excluded += b.volume();
                Ok(outcome)
            }
            BoxVerdict::Undecided => {
                let outcome = self.undecided(r, &b, path, tally)?;
                tally.undecided += b.volume();
                Ok(outcome)
            }
            other => Err(fail(
                &format!("{path}.verdict"),
                format!("'{}' is not a sub-box verdict", exact::cut(other.as_str(), 40)),
            )),
        }
    }

    /// The choice and bound fields belong to stable sub-boxes only.
    fn proved_only(r: &SubBoxRecord, path: &str, what: &str) -> std::result::Result<(), CheckError> {
        if r.sign.is_some()
            || r.multipliers.is_some()
            || r.free.is_some()
            || r.pivot_rows.is_some()
            || r.m.is_some()
            || r.sigma2_upper.is_some()
            || r.sigma2_sampled.is_some()
        {
            return Err(fail(path, format!("a {what} sub-box records no choice or bound")));
        }
        Ok(())
    }

    /// A stable sub-box: the recorded choice proves `sigma2_upper` on the
    /// whole sub-box, its multipliers are the anchor's, and its sample is
    /// re-derived.
    fn stable(
        &self,
        r: &SubBoxRecord,
        b: &ParamBox,
        path: &str,
        tally: &mut Tally,
    ) -> std::result::Result<LeafOutcome, CheckError> {
        let choice = record_choice(r, path)?;
        let s = r.sigma2_upper.as_ref().map(|x| x.0.clone()).ok_or_else(|| fail(path, "no sigma2_upper".into()))?;
        let forms = ::boxes::prove_leaf(self.sym, b, &choice, &s)
            .map_err(|e| fail(&format!("{path}.sigma2_upper"), format!("not proved: {e}")))?;
        // The recorded multipliers are the anchor's: the free ones are used
        // as given, the solved ones must be the solution there (nothing
        // stated goes unchecked).
        let anchor = b.anchor();
        for (j, (l, stated)) in forms.multipliers.iter().zip(&choice.multipliers).enumerate() {
            if value_at(l, self.n, &anchor).as_ref() != Some(stated) {
                return Err(fail(
                    &format!("{path}.multipliers[{j}]"),
                    "is not the multiplier at the sub-box's anchor".into(),
                ));
            }
        }
        let (_, sampled, at) = sampled_bound(&forms, self.n, b, &self.settings.margin)
            .ok_or_else(|| fail(path, "the samples could not be re-derived".into()))?;
        let stated = r.sigma2_sampled.map(|x| x.0).unwrap_or(f64::NAN);
        if !close(stated, sampled) {
            return Err(fail(
                &format!("{path}.sigma2_sampled"),
                format!("{stated:e} differs from the re-derived {sampled:e}"),
            ));
        }
        if r.reason.is_some() || r.anchor_verdict.is_some() {
            return Err(fail(path, "a stable sub-box has no reason or anchor_verdict".into()));
        }
        if tally.sampled_max.as_ref().is_none_or(|m| sampled > m.0) {
            tally.sampled_max = Some((sampled, at.clone()));
        }
        tally.sup = Some(tally.sup.take().map_or(s.clone(), |x: Rational| x.max(s.clone())));
        Ok(LeafOutcome::Stable { choice, sigma2_upper: s, sampled, sampled_at: at })
    }

    /// A linearly unstable sub-box: the recorded criterion proves it.
    fn unstable(&self, r: &SubBoxRecord, b: &ParamBox, path: &str) -> std::result::Result<LeafOutcome, CheckError> {
        if self.excluded {
            return Err(fail(
                &format!("{path}.verdict"),
                "mu_e is not an equilibrium (or the noise moves it) for some parameters of the box: only not_an_equilibrium, noise_incompatible or undecided sub-boxes".into(),
            ));
        }
        let charpoly = self.charpoly.get_or_init(|| self.sym.characteristic_polynomial());
        let criterion = ::boxes::certify::prove_unstable(self.sym, charpoly, b).ok_or_else(|| {
            fail(&format!("{path}.verdict"), "linear instability is not proved on this sub-box".into())
        })?;
        if r.reason.as_deref() != Some(criterion.as_str()) {
            return Err(fail(&format!("{path}.reason"), "is not the criterion that proves it".into()));
        }
        Self::proved_only(r, path, "linearly unstable")?;
        if r.anchor_verdict.is_some() {
            return Err(fail(&format!("{path}.anchor_verdict"), "only undecided sub-boxes state one".into()));
        }
        Ok(LeafOutcome::LinearlyUnstable { criterion })
    }

    /// A sub-box where `mu_e` is proved not an equilibrium, or the noise
    /// proved to move it, by the recorded criterion.
    fn excluded(&self, r: &SubBoxRecord, b: &ParamBox, path: &str) -> std::result::Result<LeafOutcome, CheckError> {
        let outcome = ::boxes::prove_excluded(self.sym, b).filter(|o| o.verdict() == r.verdict).ok_or_else(|| {
            fail(&format!("{path}.verdict"), format!("'{}' is not proved on this sub-box", r.verdict))
        })?;
        let (LeafOutcome::NotAnEquilibrium { criterion } | LeafOutcome::NoiseIncompatible { criterion }) = &outcome
        else {
            unreachable!("prove_excluded proves only these two")
        };
        if r.reason.as_deref() != Some(criterion.as_str()) {
            return Err(fail(&format!("{path}.reason"), "is not the criterion that proves it".into()));
        }
        Self::proved_only(r, path, "not stable")?;
        if r.anchor_verdict.is_some() {
            return Err(fail(&format!("{path}.anchor_verdict"), "only undecided sub-boxes state one".into()));
        }
        Ok(outcome)
    }

    /// An undecided sub-box: its reason is a statement about how the
    /// bisection ended there, checked as one, and the pointwise verdict it
    /// states at its anchor is the pipeline's.
    fn undecided(
        &self,
        r: &SubBoxRecord,
        b: &ParamBox,
        path: &str,
        tally: &mut Tally,
    ) -> std::result::Result<LeafOutcome, CheckError> {
        Self::proved_only(r, path, "undecided")?;
        let reason = r.reason.clone().unwrap_or_default();
        let rpath = format!("{path}.reason");
        match reason.as_str() {
            x if x == self.spent_reason => tally.budget += 1,
            ::boxes::certify::LARGEST_DEPTH
            | ::boxes::certify::EQUILIBRIUM_UNRESOLVED
            | ::boxes::certify::NOISE_UNRESOLVED => {
                let expected = if self.excluded { self.unresolved } else { ::boxes::certify::LARGEST_DEPTH };
                if reason != expected {
                    return Err(fail(&rpath, format!("expected '{expected}' for this system")));
                }
                if r.depth != self.settings.max_depth as u64 {
                    return Err(fail(
                        &rpath,
                        format!(
                            "says the largest depth, but the sub-box is at depth {} of {}",
                            r.depth, self.settings.max_depth
                        ),
                    ));
                }
                tally.at_depth_limit += 1;
            }
            ::boxes::certify::UNSTABLE_CORNERS => {
                if self.excluded || !::boxes::certify::unstable_at_anchor_and_corners(self.system, b) {
                    return Err(fail(
                        &rpath,
                        "the pipeline does not prove A unstable at the sub-box's anchor and every corner".into(),
                    ));
                }
            }
            _ => return Err(fail(&rpath, "is not a reason this engine gives for an undecided sub-box".into())),
        }
        // the pointwise verdict stated at the anchor is the pipeline's;
        // sub-boxes left by the budget or bisected for a failing
        // equilibrium or noise state none
        if self.excluded || reason == self.spent_reason {
            if r.anchor_verdict.is_some() {
                return Err(fail(
                    &format!("{path}.anchor_verdict"),
                    "this sub-box was not analysed at its anchor".into(),
                ));
            }
        } else {
            let derived = ::boxes::certify::analyse_at(self.system, &b.anchor()).map(|(_, a)| a.verdict);
            if r.anchor_verdict != derived {
                return Err(fail(
                    &format!("{path}.anchor_verdict"),
                    format!(
                        "is not the pipeline's verdict at the anchor ({})",
                        derived.map_or("none: the pipeline could not run there", |v| v.as_str())
                    ),
                ));
            }
        }
        Ok(LeafOutcome::Undecided { reason, anchor: r.anchor_verdict })
    }
}

/// The budget: the bisection analyses every node of its binary tree but
/// the sub-boxes left by the budget, `2 L - 1` nodes for `L` sub-boxes.
/// Sub-boxes left by the budget mean that exactly `max_boxes` were
/// analysed, and they are the last sub-boxes of the breadth-first order
/// (no tightening follows a spent budget). Returns the limit that stopped
/// the bisection, if any.
fn check_budget(
    doc: &BoxCertificateDocument,
    order: &[usize],
    leaves: &LeafCheck<'_>,
    tally: &Tally,
) -> std::result::Result<Option<&'static str>, CheckError> {
    let (budget, budget_size) = (tally.budget, leaves.budget_size);
    let nodes = (2 * doc.sub_boxes.len()).saturating_sub(1);
    let spent = |i: usize| doc.sub_boxes[i].reason.as_deref() == Some(leaves.spent_reason.as_str());
    if let Some(first) = order.iter().position(|&i| spent(i)) {
        if let Some(&i) = order[first..].iter().find(|&&i| !spent(i)) {
            return Err(fail(
                &format!("$.sub_boxes[{i}]"),
                "comes after a sub-box left by the budget in the bisection's order, so it was not analysed".into(),
            ));
        }
    }
    if budget > 0 && nodes - budget != budget_size {
        return Err(fail(
            "$.sub_boxes",
            format!(
                "{budget} sub-boxes say the budget was spent, but {} were analysed, not the budget of {}",
                nodes - budget,
                budget_size
            ),
        ));
    }
    if nodes > budget_size + budget {
        return Err(fail(
            "$.sub_boxes",
            format!("{} sub-boxes need more than the budget of {budget_size} analysed", doc.sub_boxes.len()),
        ));
    }
    Ok(if budget > 0 {
        Some("max_boxes")
    } else if tally.at_depth_limit > 0 {
        Some("max_depth")
    } else {
        None
    })
}

/// Every number and sentence derived from the sub-boxes: the verdict and
/// its reason, the sup (exact and rounded up), the shares (exact volumes
/// rounded once, compared exactly), the largest sample and the theorem.
fn check_totals(
    doc: &BoxCertificateDocument,
    spec: &Spec,
    section: &BoxSection,
    excluded: bool,
    tally: Tally,
) -> std::result::Result<CheckReport, CheckError> {
    let range = &section.range;
    let (verdict, reason) = ::boxes::verdict_of(&tally.counts);
    if doc.verdict != verdict {
        return Err(fail(
            "$.verdict",
            format!("the sub-boxes prove '{}', not '{}'", verdict.as_str(), doc.verdict.as_str()),
        ));
    }
    if doc.reason != reason {
        return Err(fail(
            "$.reason",
            format!("is not the sentence for what the sub-boxes prove ('{}')", exact::cut(&reason, 200)),
        ));
    }
    let sup = tally.sup;
    let stated_sup = doc.sup_sigma2_exact.as_ref().map(|x| x.0.clone());
    if stated_sup != sup {
        return Err(fail("$.sup_sigma2_exact", "is not the largest sub-box bound".into()));
    }
    let sup_f = sup.as_ref().map(exact::rational_to_f64_up);
    if doc.sup_sigma2.map(|x| x.0) != sup_f {
        return Err(fail("$.sup_sigma2", "is not the exact bound rounded up".into()));
    }
    if doc.undecided_fraction.0 != fraction(&tally.undecided, &range.volume()) {
        return Err(fail("$.undecided_fraction", "is not the undecided sub-boxes' share".into()));
    }
    if doc.unstable_fraction.0 != fraction(&tally.unstable, &range.volume()) {
        return Err(fail("$.unstable_fraction", "is not the unstable sub-boxes' share".into()));
    }
    let excluded_fraction = excluded.then(|| fraction(&tally.excluded, &range.volume()));
    match (doc.excluded_fraction, excluded_fraction) {
        (None, None) => {}
        (Some(x), Some(y)) if x.0 == y => {}
        _ => return Err(fail("$.excluded_fraction", "is not the excluded sub-boxes' share (present exactly when the equilibrium or the noise fails for some parameter)".into())),
    }
    match (&doc.sampled_max, &tally.sampled_max) {
        (None, None) => {}
        (Some(stated), Some((v, at))) if close(stated.sigma2.0, *v) && &rationals(&stated.at) == at => {}
        _ => return Err(fail("$.sampled_max", "is not the largest re-derived sample".into())),
    }
    let stable_volume = range.volume() - &tally.unstable - &tally.excluded - &tally.undecided;
    let derived = statement(
        spec,
        section,
        verdict,
        [&stable_volume, &tally.unstable, &tally.excluded, &tally.undecided],
        sup.as_ref(),
    );
    if doc.theorem != derived {
        return Err(fail("$.theorem", "is not the statement of what the sub-boxes prove".into()));
    }
    let verdict = verdict.at_every_point().unwrap_or(Verdict::Inconclusive);
    let sigma2 = doc.sup_sigma2.map(|x| x.0).filter(|_| verdict == Verdict::Stable);
    Ok(CheckReport { name: spec.name.clone(), verdict, level: None, sigma2 })
}

fn close(a: f64, b: f64) -> bool {
    a == b || (a - b).abs() <= 1e-9 * a.abs().max(b.abs())
}

/// The sub-boxes are the leaves of the bisection tree of the box: starting
/// from the box, a node that is not a recorded sub-box is halved along
/// [`::boxes::certify::bisection_side`], exactly as certify and its
/// tightening split, and every recorded sub-box must be reached, at its
/// recorded depth. So they lie in the box, their interiors are disjoint and
/// they cover it, and their corners and depths are what the bisection
/// gives. Returns the indices of the sub-boxes in the tree's breadth-first
/// order (the bisection's order of analysis, when no tightening followed).
fn check_partition(
    doc: &BoxCertificateDocument,
    range: &ParamBox,
    np: usize,
) -> std::result::Result<Vec<usize>, CheckError> {
    let mut index: std::collections::HashMap<(Vec<Rational>, Vec<Rational>), usize> = Default::default();
    for (i, r) in doc.sub_boxes.iter().enumerate() {
        let path = format!("$.sub_boxes[{i}]");
        let b = ParamBox { lo: rationals(&r.lo), hi: rationals(&r.hi) };
        if b.lo.len() != np || b.hi.len() != np {
            return Err(fail(&path, format!("expected {np} bounds per corner")));
        }
        if (0..np).any(|k| b.lo[k] >= b.hi[k]) || !range.contains_box(&b) {
            return Err(fail(&path, "not a non-empty sub-box of the box".into()));
        }
        if r.depth > MAX_BOX_DEPTH {
            return Err(fail(&format!("{path}.depth"), format!("at most {MAX_BOX_DEPTH}")));
        }
        if index.insert((b.lo, b.hi), i).is_some() {
            return Err(fail(&path, "the same sub-box is recorded twice".into()));
        }
    }
    // Breadth first; a tree with L leaves has 2 L - 1 nodes, so a walk
    // past that many (or below the largest depth) is not this partition's.
    let leaves = doc.sub_boxes.len();
    let mut order = Vec::with_capacity(leaves);
    let mut queue = std::collections::VecDeque::from([(range.clone(), 0u64)]);
    let mut nodes = 0usize;
    while let Some((b, depth)) = queue.pop_front() {
        nodes += 1;
        if nodes > 2 * leaves {
            break;
        }
        match index.remove(&(b.lo.clone(), b.hi.clone())) {
            Some(i) => {
                if doc.sub_boxes[i].depth != depth {
                    return Err(fail(
                        &format!("$.sub_boxes[{i}].depth"),
                        format!("is not the number of bisections that gives this sub-box ({depth})"),
                    ));
                }
                order.push(i);
            }
            None if depth < MAX_BOX_DEPTH => {
                let (lo, hi) = b.split(::boxes::certify::bisection_side(&b, range));
                queue.push_back((lo, depth + 1));
                queue.push_back((hi, depth + 1));
            }
            None => break,
        }
    }
    if let Some(&i) = index.values().min() {
        return Err(fail(
            &format!("$.sub_boxes[{i}]"),
            "is not a sub-box of the box's bisection, or the sub-boxes do not cover the box".into(),
        ));
    }
    if !queue.is_empty() || order.len() != leaves {
        return Err(fail("$.sub_boxes", "the sub-boxes do not cover the box".into()));
    }
    Ok(order)
}

fn record_choice(r: &SubBoxRecord, path: &str) -> std::result::Result<BoxChoice, CheckError> {
    let missing = |what: &str| fail(path, format!("a stable sub-box needs '{what}'"));
    let sign = match r.sign.ok_or_else(|| missing("sign"))? {
        1 => Sign::Positive,
        -1 => Sign::Negative,
        s => return Err(fail(&format!("{path}.sign"), format!("must be 1 or -1, got {s}"))),
    };
    let m_rows = r.m.as_ref().ok_or_else(|| missing("M"))?;
    let k = m_rows.len();
    if m_rows.iter().any(|row| row.len() != k) {
        return Err(fail(&format!("{path}.M"), "must be square".into()));
    }
    let m = Matrix::from_rows(&m_rows.iter().map(|row| rationals(row)).collect::<Vec<_>>());
    if !m.is_symmetric() {
        return Err(fail(&format!("{path}.M"), "must be symmetric".into()));
    }
    let to_usize = |v: &Vec<u64>| v.iter().map(|&x| usize::try_from(x).unwrap_or(usize::MAX)).collect::<Vec<_>>();
    Ok(BoxChoice {
        sign,
        multipliers: rationals(r.multipliers.as_ref().ok_or_else(|| missing("multipliers"))?),
        free: to_usize(r.free.as_ref().ok_or_else(|| missing("free"))?),
        pivot_rows: to_usize(r.pivot_rows.as_ref().ok_or_else(|| missing("pivot_rows"))?),
        m,
    })
}
