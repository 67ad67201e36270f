//! Finite-dimensional specs above `algebra::MAX_DIMENSION` coordinates: the
//! same spec format, read sparsely and certified by the large pipeline
//! (`large` crate, level `numerical`), with their own certificate and
//! re-check.
//!
//! ```
//! // Two so(3) bodies (6 coordinates) read by the large path directly.
//! let v = serde_json::json!({
//!   "name": "two",
//!   "algebra": {"coordinates": ["a1", "a2", "a3", "b1", "b2", "b3"],
//!               "structure_constants": [[0, 1, 2, 1], [1, 2, 0, 1], [2, 0, 1, 1], [3, 4, 5, 1], [4, 5, 3, 1], [5, 3, 4, 1]]},
//!   "hamiltonian": "a1^2/6 + a2^2/4 + a3^2/2 + b1^2/6 + b2^2/4 + b3^2/2",
//!   "casimirs": ["a1^2 + a2^2 + a3^2", "b1^2 + b2^2 + b3^2"],
//!   "equilibrium": [1, 0, 0, 1, 0, 0],
//!   "noise": [["3/10", 0, 0, 0, 0, 0]]
//! });
//! let spec = spec::large_spec_from_value(v).unwrap();
//! let cert = spec::certify_large(&spec);
//! assert_eq!(cert["verdict"], "stable");
//! // The first body's rigid-body constant 0.27; the second has no noise.
//! assert!((cert["sigma2"].as_f64().unwrap() - 0.27).abs() < 1e-7);
//! assert_eq!(spec::check_certificate_value(&cert).unwrap().verdict, spec::Verdict::Stable);
//! ```

use crate::certificate::{spec_digest, stopping_record, CERTIFICATE_VERSION, ENGINE_VERSION};
use crate::check::{compare_with, fail, CheckError, CheckReport};
use crate::document::{AlgebraDoc, SpecDocument};
use crate::json::{child, index, Result, SpecError};
use crate::parse::Stopping;
use crate::record::{
    Engine, ExactRational, Float, LargeAnalysisRecord, LargeCertificateDocument, LevelOrNone, Route, RouteRecord,
};
use exact::Rational;
use large::LargeError;
use large::LargeSystem;
use large::SparseAlgebra;
use large::SparsePoly;
use large::{analyse_large, analyse_large_with, LargeAnalysis, LargeSettings};
use large::{parse_sparse, SparseSymbols};
use outcome::{Cancelled, Progress, Verdict, VerificationLevel};
use serde_json::Value;
use std::collections::BTreeMap;

/// Largest dimension of a large spec (dense `n x n` floating-point work).
pub const LARGE_MAX_DIMENSION: usize = 4096;

/// Relative tolerance of the re-check of a large certificate's numbers:
/// the computation is deterministic, so this only absorbs another CPU's
/// rounding.
pub const LARGE_TOLERANCE: f64 = 1e-9;

/// A parsed large spec.
#[derive(Clone, Debug)]
pub struct LargeSpec {
    /// `name`.
    pub name: String,
    /// The spec as given.
    pub raw: Value,
    /// The validated system.
    pub system: LargeSystem,
    /// Parameter values.
    pub parameters: BTreeMap<String, Rational>,
    /// The stopping question.
    pub stopping: Option<Stopping>,
    /// The pipeline's settings: the defaults, with the spec's settings
    /// that this route honours.
    pub settings: LargeSettings,
    /// The spec's `settings` object, as given.
    pub settings_given: Option<Value>,
    /// The settings the spec gives that this route does not honour, with
    /// the reason each.
    pub settings_not_honoured: BTreeMap<String, String>,
    /// The optional `sweep` section.
    pub sweep: crate::sweep::SweepSection,
}

/// Whether a spec value goes to the large pipeline: an algebra given by
/// more than `algebra::MAX_DIMENSION` coordinates.
pub fn is_large_spec(v: &Value) -> bool {
    v.pointer("/algebra/coordinates").and_then(Value::as_array).is_some_and(|c| c.len() > algebra::MAX_DIMENSION)
}

fn expression(text: &str, path: &str, symbols: &SparseSymbols) -> Result<SparsePoly> {
    parse_sparse(text, symbols).map_err(|e| SpecError::new(path, format!("in '{}': {e}", exact::quote(text, 60))))
}

fn constant(text: &str, path: &str, symbols: &SparseSymbols) -> Result<Rational> {
    expression(text, path, symbols)?
        .constant_value()
        .ok_or_else(|| SpecError::new(path, "must be a constant (it may use parameters, not coordinates)"))
}

/// Read a large spec (any dimension; [`crate::parse_any_spec`] sends the
/// specs above 64 coordinates here).
pub fn large_spec_from_value(value: Value) -> Result<LargeSpec> {
    let root = "$";
    let doc: SpecDocument = crate::document::from_value(&value)?;
    if doc.name.trim().is_empty() {
        return Err(SpecError::new(child(root, "name"), "must not be empty"));
    }
    let apath = child(root, "algebra");
    let AlgebraDoc::Custom(custom) = &doc.algebra else {
        return Err(SpecError::new(&apath, "a large system gives its algebra by coordinates and structure_constants"));
    };
    let n = custom.coordinates.len();
    if n > LARGE_MAX_DIMENSION {
        return Err(SpecError::new(
            child(&apath, "coordinates"),
            format!("at most {LARGE_MAX_DIMENSION} coordinates (dense n x n floating-point work), got {n}"),
        ));
    }
    if doc.parameter_box.is_some() {
        return Err(SpecError::new(
            child(root, "box"),
            format!("box certificates run the exact pipeline: at most {} coordinates", algebra::MAX_DIMENSION),
        ));
    }
    let settings_given = value.get("settings").cloned();
    let (settings, settings_not_honoured) = sparse_route_settings(settings_given.as_ref())?;
    let spath = child(&apath, "structure_constants");
    let rows = crate::parse::structure_rows(custom, &spath)?;
    let algebra = SparseAlgebra::new(&custom.coordinates, &rows).map_err(|e| SpecError::new(&apath, e.to_string()))?;
    let mut parameters = BTreeMap::new();
    let ppath = child(root, "parameters");
    let names: std::collections::HashSet<&String> = custom.coordinates.iter().collect();
    for (key, v) in &doc.parameters {
        if names.contains(key) {
            return Err(SpecError::new(child(&ppath, key), format!("parameter '{key}' has the name of a coordinate")));
        }
        parameters.insert(key.clone(), v.0.clone());
    }
    let symbols = SparseSymbols::new(&custom.coordinates, &parameters);
    let hamiltonian = expression(&doc.hamiltonian.0, &child(root, "hamiltonian"), &symbols)?;
    let cpath = child(root, "casimirs");
    let Some(casimir_texts) = &doc.casimirs else {
        return Err(SpecError::new(
            cpath,
            format!("required above {} coordinates (Casimirs are not discovered there)", algebra::MAX_DIMENSION),
        ));
    };
    let casimirs = casimir_texts
        .iter()
        .enumerate()
        .map(|(i, e)| expression(&e.0, &index(&cpath, i), &symbols))
        .collect::<Result<Vec<_>>>()?;
    let fpath = child(root, "first_integrals");
    let first_integrals = doc
        .first_integrals
        .iter()
        .flatten()
        .enumerate()
        .map(|(i, e)| expression(&e.0, &index(&fpath, i), &symbols))
        .collect::<Result<Vec<_>>>()?;
    let epath = child(root, "equilibrium");
    if doc.equilibrium.len() != n {
        return Err(SpecError::new(
            &epath,
            format!("expected {n} components (the algebra's dimension), got {}", doc.equilibrium.len()),
        ));
    }
    let equilibrium = doc
        .equilibrium
        .iter()
        .enumerate()
        .map(|(i, e)| constant(&e.0, &index(&epath, i), &symbols))
        .collect::<Result<Vec<_>>>()?;
    let npath = child(root, "noise");
    let noise = read_noise(&doc.noise, &npath, n, &symbols)?;
    let system =
        LargeSystem::new(algebra, hamiltonian, casimirs, first_integrals, equilibrium, noise).map_err(|e| {
            let at = match &e {
                LargeError::System(m) if m.starts_with("casimirs[") => cpath.clone(),
                LargeError::System(m) if m.starts_with("first_integrals[") => fpath.clone(),
                _ => root.to_string(),
            };
            SpecError::new(at, e.to_string())
        })?;
    let stopping =
        doc.stopping.as_ref().map(|s| crate::parse::read_stopping(s, &child(root, "stopping"))).transpose()?;
    let pnames: Vec<String> = parameters.keys().cloned().collect();
    let sweep = crate::sweep::read_sweep_section(doc.sweep.as_ref(), &child(root, "sweep"), &pnames)?;
    Ok(LargeSpec {
        name: doc.name,
        raw: value,
        system,
        parameters,
        stopping,
        settings,
        settings_given,
        settings_not_honoured,
        sweep,
    })
}

/// The noise fields: at most `MAX_NOISE_FIELDS`, each of `n` constants.
fn read_noise(
    given: &[Vec<crate::document::Expression>],
    npath: &str,
    n: usize,
    symbols: &SparseSymbols,
) -> Result<Vec<Vec<Rational>>> {
    if given.len() > crate::parse::MAX_NOISE_FIELDS {
        return Err(SpecError::new(
            npath,
            format!("at most {} noise fields are supported", crate::parse::MAX_NOISE_FIELDS),
        ));
    }
    let mut noise = Vec::with_capacity(given.len());
    for (i, field) in given.iter().enumerate() {
        let fpath = index(npath, i);
        if field.len() != n {
            return Err(SpecError::new(
                &fpath,
                format!("expected {n} components (the algebra's dimension), got {}", field.len()),
            ));
        }
        noise.push(
            field
                .iter()
                .enumerate()
                .map(|(j, e)| constant(&e.0, &index(&fpath, j), symbols))
                .collect::<Result<Vec<_>>>()?,
        );
    }
    Ok(noise)
}

/// Why the sparse route was taken, for a system of `n` coordinates.
pub(crate) fn sparse_route_reason(n: usize) -> String {
    format!(
        "{n} coordinates, more than {}: dense rational matrices would hold n^2 entries of unbounded size, so the structure is checked exactly on its sparse form and the method runs in floating point, with a verified floating-point final check",
        algebra::MAX_DIMENSION
    )
}

/// The spec's settings on the sparse route. They are read and checked as
/// on the dense exact route (the same names, ranges and JSON paths), so a
/// spec keeps its meaning at every size; `definiteness_tolerance` is
/// honoured (the same relative margin of the restricted second variation),
/// and every other setting given is reported with the reason the route
/// runs with its own value.
fn sparse_route_settings(given: Option<&Value>) -> Result<(LargeSettings, BTreeMap<String, String>)> {
    let engine = crate::settings::EngineSettings::from_json(given, "$.settings")?;
    let mut settings = LargeSettings::default();
    let mut not_honoured = BTreeMap::new();
    for key in given.and_then(Value::as_object).map(|m| m.keys().collect::<Vec<_>>()).unwrap_or_default() {
        let why = match key.as_str() {
            "definiteness_tolerance" => {
                settings.definiteness_tolerance = engine.pipeline.search.definiteness_tolerance;
                continue;
            }
            "exact" => "the sparse route has no rational certification to switch on or off: its claims are verified floating point (level verified_float) or numerical, as the certificate's level says",
            "search_iterations" | "search_expansions" => "the sparse route searches the multiplier family by the ellipsoid method with its own iteration limits",
            "max_denominator" => "the sparse route rounds no choice to rationals: its multipliers are solved exactly from the floating-point ones",
            "instability_tolerance" => "the sparse route's instability threshold is 1e-6 times the spectral radius of A (the dense route's is the setting times max(1, |A|_F))",
            "discovery_degree" | "discovery_max_unknowns" => "Casimirs are not discovered on the sparse route: the spec gives them",
            "optimise" | "optimisation_tolerance" | "optimisation_iterations" => "the sparse route's minimisation of Sigma^2 over the Casimir Hessian runs with its own schedule",
            _ => "not a setting of the sparse route",
        };
        not_honoured.insert(key.clone(), why.to_string());
    }
    Ok((settings, not_honoured))
}

/// The typed certificate of a large spec.
pub fn large_certificate_document(
    spec: &LargeSpec,
    analysis: &std::result::Result<LargeAnalysis, LargeError>,
) -> LargeCertificateDocument {
    let mut doc = LargeCertificateDocument {
        certificate_version: CERTIFICATE_VERSION,
        engine: Engine { name: "verify".into(), version: ENGINE_VERSION.into() },
        name: spec.name.clone(),
        kind: outcome::CertificateKind::Large,
        verdict: Verdict::Inconclusive,
        reason: String::new(),
        level: LevelOrNone(None),
        theorem: crate::theorem::nothing(crate::theorem::FINITE_NOT_CHECKED),
        checks: BTreeMap::new(),
        sigma2: None,
        sigma2_upper: None,
        infimum: None,
        stopping: None,
        spec_sha256: spec_digest(&spec.raw),
        dimension: spec.system.dim() as u64,
        settings: spec.settings_given.clone(),
        route: RouteRecord {
            route: Route::SparseFloat,
            why: sparse_route_reason(spec.system.dim()),
            settings_not_honoured: spec.settings_not_honoured.clone(),
        },
        analysis: LargeAnalysisRecord {
            equilibrium_residual: vec![],
            incompatible_noise: vec![],
            multipliers: vec![],
            multiplier_residual: Float(0.0),
            family_dimension: 0,
            restricted_dimension: 0,
            sign: Float(0.0),
            restricted_margin: None,
            q_depends_on_casimirs: false,
            condition_number: None,
            drift_residual: Float(0.0),
            growth_rate: None,
            exact_multipliers: None,
            verification: None,
        },
        spec: spec.raw.clone(),
    };
    let mut checks = BTreeMap::new();
    checks.insert(
        "system".to_string(),
        "exact (sparse): antisymmetry and the Jacobi identity on every triple where a bracket is nonzero; each Casimir Poisson-commutes with every coordinate and each first integral with the Hamiltonian, as polynomial identities".to_string(),
    );
    let a = match analysis {
        Ok(a) => a,
        Err(e) => {
            doc.reason = format!("the analysis could not run: {e}");
            doc.checks = checks;
            return doc;
        }
    };
    doc.verdict = a.verdict;
    doc.reason = a.reason.clone();
    doc.level = LevelOrNone((a.verdict != Verdict::Inconclusive).then_some(a.level));
    fill_analysis_record(&mut doc.analysis, a);
    match a.verdict {
        Verdict::NotAnEquilibrium | Verdict::NoiseIncompatible => {
            checks.insert("residuals".to_string(), "exact: the residuals are computed in rational arithmetic from the sparse structure constants and polynomials".to_string());
        }
        Verdict::Stable => fill_stable(&mut doc, &mut checks, spec, a),
        Verdict::LinearlyUnstable => {
            checks.insert(
                "instability".to_string(),
                "numerical: the eigenvalues of the dense drift (faer), the largest real part above 1e-6 of the spectral radius".to_string(),
            );
        }
        Verdict::Inconclusive => {}
    }
    doc.checks = checks;
    let subject = crate::theorem::finite_subject(
        &spec.name,
        "an algebra given by structure constants",
        spec.system.dim(),
        "the spec's equilibrium",
        spec.raw.get("noise").and_then(Value::as_array).map_or(0, Vec::len),
    );
    doc.theorem = crate::theorem::from_doubles(
        &subject,
        doc.verdict,
        doc.level.0,
        doc.sigma2_upper.map(|x| x.0),
        doc.sigma2.map(|x| x.0),
        doc.stopping.as_ref(),
        doc.analysis.growth_rate.map(|x| x.0),
    );
    doc
}

/// The pipeline's intermediate results, as the certificate records them.
fn fill_analysis_record(r: &mut LargeAnalysisRecord, a: &LargeAnalysis) {
    r.equilibrium_residual =
        a.equilibrium_residual.iter().take(64).map(|(i, v)| (*i as u64, ExactRational(v.clone()))).collect();
    r.incompatible_noise =
        (0..a.noise_residuals.len()).filter(|&i| !a.noise_residuals[i].is_empty()).map(|i| i as u64).collect();
    r.multipliers = a.multipliers.iter().map(|x| Float(*x)).collect();
    r.multiplier_residual = Float(a.multiplier_residual);
    r.family_dimension = a.family_dimension as u64;
    r.restricted_dimension = a.restricted_dimension as u64;
    r.sign = Float(a.sign);
    r.restricted_margin = a.restricted_margin.is_finite().then_some(Float(a.restricted_margin));
    r.q_depends_on_casimirs = a.q_depends_on_casimirs;
    r.condition_number = a.condition_number.map(Float);
    r.drift_residual = Float(a.drift_residual);
    r.growth_rate = a.growth_rate.filter(|_| a.verdict == Verdict::LinearlyUnstable).map(Float);
}

/// A stable verdict's numbers, stopping time and checks: proved
/// (`verified_float`, at `sigma2_upper`) or numerical (at `sigma2`).
fn fill_stable(
    doc: &mut LargeCertificateDocument,
    checks: &mut BTreeMap<String, String>,
    spec: &LargeSpec,
    a: &LargeAnalysis,
) {
    doc.analysis.exact_multipliers =
        a.exact_multipliers.as_ref().map(|m| m.iter().map(|x| ExactRational(x.clone())).collect());
    doc.analysis.verification = a.verification.clone();
    doc.sigma2 = a.sigma2.map(Float);
    doc.infimum = a.infimum.map(Float);
    if let (Some(upper), Some(VerificationLevel::VerifiedFloat)) = (a.sigma2_upper, doc.level.0) {
        checks.insert(
            "form".to_string(),
            "verified_float: the multipliers are exact rationals with G lambda + Dh = 0 proved in rational arithmetic (analysis.exact_multipliers), so the functional s (h + lambda.C) + (C - C_e)^T K' (C - C_e)/2 is conserved and exactly critical; its exact Hessian P is proved positive definite by a floating-point Cholesky test with every rounding between the exact data and the tested matrix bounded (Rump-style)".to_string(),
        );
        checks.insert(
            "sigma2".to_string(),
            "verified_float: sigma2_upper P - Q is proved positive definite for the exact P and the exact Q = sum_i (B_i^T P B_i + sym(P B_i^2)) (the drift part is exactly zero for a conserved critical functional), roundings bounded; sigma2 is lambda_max(sQ, sP) by a dense generalized eigenproblem (faer), an estimate; infimum: lambda_max restricted to ker G^T".to_string(),
        );
        doc.sigma2_upper = Some(Float(upper));
        doc.stopping = stopping_record(
            spec.stopping,
            Some(upper),
            "P(|dmu_t|_P^2 > epsilon) <= (delta/epsilon) exp(Sigma^2 t) for |dmu_0|_P^2 = delta, with Sigma^2 = sigma2_upper, for the linearised SDE",
        );
    } else {
        checks.insert(
            "form".to_string(),
            "numerical: the multipliers by least squares (analysis.multiplier_residual), the restricted Hessian's eigenvalues on ker G^T (analysis.restricted_margin), the Casimir Hessian by a Schur completion; nothing is proved (analysis.verification says why)".to_string(),
        );
        checks.insert(
            "sigma2".to_string(),
            "numerical: lambda_max(sQ, sP) by a dense generalized eigenproblem (faer); infimum: lambda_max restricted to ker G^T".to_string(),
        );
        doc.stopping = stopping_record(
            spec.stopping,
            a.sigma2,
            "P(|dmu_t|_P^2 > epsilon) <= (delta/epsilon) exp(Sigma^2 t) for |dmu_0|_P^2 = delta, with the numerical Sigma^2: an estimate, not a guarantee",
        );
    }
}

/// Certify a large spec: the certificate JSON.
pub fn certify_large(spec: &LargeSpec) -> Value {
    let analysis = analyse_large(&spec.system, &spec.settings);
    serde_json::to_value(large_certificate_document(spec, &analysis)).unwrap_or_default()
}

/// [`certify_large`] with progress; `Err` when it was cancelled (no
/// certificate is built from a cancelled run).
pub(crate) fn certify_large_with(spec: &LargeSpec, progress: &Progress) -> std::result::Result<Value, Cancelled> {
    let analysis = analyse_large_with(&spec.system, &spec.settings, progress);
    progress.check()?;
    Ok(serde_json::to_value(large_certificate_document(spec, &analysis)).unwrap_or_default())
}

/// Re-check a large certificate: the embedded spec and its digest, then
/// re-derivation and comparison (numbers to [`LARGE_TOLERANCE`]), with
/// progress and cancellation.
pub(crate) fn check_large_certificate_with(
    cert: &Value,
    progress: &Progress,
) -> std::result::Result<CheckReport, CheckError> {
    let map = crate::json::as_object(cert, "$").map_err(CheckError::BadInput)?;
    let spec_value = crate::json::required(map, "spec", "$").map_err(CheckError::BadInput)?.clone();
    crate::check::check_engine(map)?;
    crate::document::from_value::<LargeCertificateDocument>(cert)
        .map_err(|e| fail(&e.path, format!("not a certificate as this engine writes them: {}", e.message)))?;
    let spec = large_spec_from_value(spec_value).map_err(|e| {
        fail(
            &format!("$.spec{}", e.path.trim_start_matches('$')),
            format!("the embedded spec is not valid: {}", e.message),
        )
    })?;
    if cert.get("spec_sha256").and_then(Value::as_str) != Some(spec_digest(&spec.raw).as_str()) {
        return Err(fail("$.spec_sha256", "does not match the embedded spec".into()));
    }
    let mut analysis = analyse_large_with(&spec.system, &spec.settings, progress);
    progress.check()?;
    // A stated sigma2_upper below the re-derived one stands only if the
    // verified check proves it; then the rest is compared at that bound.
    if let (Ok(a), Some(stated)) = (&mut analysis, cert.get("sigma2_upper").and_then(Value::as_f64)) {
        if let Some(derived) = a.sigma2_upper {
            if stated < derived {
                if !(stated.is_finite() && stated > 0.0 && a.proves_upper(stated)) {
                    return Err(fail(
                        "$.sigma2_upper",
                        format!("{stated:e} is not proved: sigma2_upper P - Q is not verified positive definite there (the engine proves {derived:e})"),
                    ));
                }
                a.sigma2_upper = Some(stated);
            }
        }
    }
    let expected = serde_json::to_value(large_certificate_document(&spec, &analysis)).unwrap_or_default();
    compare_with(&expected, cert, "$", 0.0, LARGE_TOLERANCE)?;
    // T by the one rule, at the stated bound (proved, or the estimate the
    // certificate says it is).
    let bound = cert.get("sigma2_upper").or(cert.get("sigma2")).and_then(Value::as_f64);
    crate::check::check_stopping(cert, spec.stopping, bound)?;
    let level = expected.get("level").and_then(Value::as_str).and_then(|s| s.parse::<VerificationLevel>().ok());
    let (verdict, sigma2) = match &analysis {
        Ok(a) => (a.verdict, a.sigma2),
        Err(_) => (Verdict::Inconclusive, None),
    };
    Ok(CheckReport { name: spec.name.clone(), verdict, level, sigma2 })
}
