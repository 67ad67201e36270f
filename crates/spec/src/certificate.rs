//! Certificates: the verdict, the evidence, the settings and the spec, as JSON.

use crate::parse::Spec;
use crate::record::{
    CertificateDocument, ChoiceRecord, ComplexRecord, ConservedRecord, DiscoveryRecord, Engine, EquilibriumRecord,
    ExactRational, Float, GrowthRecord, InstabilityRecord, LinearisationRecord, MultipliersRecord, NoiseRecord,
    OptimisationRecord, RationalMatrix, ResidualsRecord, SearchRecord, StoppingRecord,
};
use exact::{Matrix, Rational};
use generator::{analyse, Analysis, StoppingTime, Verdict};
use nalgebra::Complex;
use outcome::VerificationLevel;
use serde_json::Value;
use std::collections::BTreeMap;

/// Version of the certificate format.
pub const CERTIFICATE_VERSION: u64 = 5;

/// The engine version written into certificates.
pub const ENGINE_VERSION: &str = env!("CARGO_PKG_VERSION");

/// A certificate and the analysis it was made from.
#[derive(Clone, Debug)]
pub struct Certificate {
    /// The certificate JSON (typed: [`Certificate::document`]).
    pub json: Value,
    /// The analysis behind it.
    pub analysis: Analysis,
}

fn rationals(v: &[Rational]) -> Vec<ExactRational> {
    v.iter().map(|r| ExactRational(r.clone())).collect()
}

fn matrix(m: &Matrix) -> RationalMatrix {
    (0..m.nrows()).map(|i| (0..m.ncols()).map(|j| ExactRational(m[(i, j)].clone())).collect()).collect()
}

/// A float as JSON (non-finite values as strings).
pub(crate) fn float_json(x: f64) -> Value {
    if x.is_finite() {
        Value::from(x)
    } else {
        Value::String(if x > 0.0 {
            "infinity".into()
        } else if x < 0.0 {
            "-infinity".into()
        } else {
            "nan".into()
        })
    }
}

fn complex(z: &Complex<f64>) -> ComplexRecord {
    ComplexRecord { re: Float(z.re), im: Float(z.im) }
}

/// The verification level of an analysis: `exact` when the verdict is
/// proved in rational arithmetic (the stable `Sigma^2` bound, the Sturm
/// proof of instability, the residuals of the two early verdicts), else
/// `numerical`.
pub fn verification_level(a: &Analysis) -> VerificationLevel {
    let exact = match a.verdict {
        Verdict::Stable => a.stable.as_ref().is_some_and(|s| s.exact.is_some()),
        Verdict::LinearlyUnstable => matches!(a.spectral_proof, Some(generator::SpectralProof::Unstable { .. })),
        Verdict::NotAnEquilibrium | Verdict::NoiseIncompatible => true,
        Verdict::Inconclusive => false,
    };
    if exact {
        VerificationLevel::Exact
    } else {
        VerificationLevel::Numerical
    }
}

/// What each part of the verdict rests on.
fn checks(a: &Analysis) -> BTreeMap<String, String> {
    let parts: &[(&str, &str)] = match a.verdict {
        Verdict::Stable => match a.stable.as_ref().and_then(|s| s.exact.as_ref()) {
            Some(e) => &[
                ("P_definite", "exact (rational LDL^T)"),
                ("first_variation", "exact (rational)"),
                ("drift_residual", "exact (rational)"),
                (
                    "sigma2",
                    if e.sharp {
                        "exact: sigma2 * sP - sQ is positive semidefinite and singular (sigma2 = lambda_max)"
                    } else {
                        "exact: sigma2 * sP - sQ is positive semidefinite (sigma2 is an upper bound within 1e-10 of lambda_max)"
                    },
                ),
            ],
            None => &[
                ("P_definite", "exact (rational LDL^T)"),
                ("drift_residual", "exact (rational)"),
                ("sigma2", "floating point only (exact certification switched off, or it failed at every candidate)"),
            ],
        },
        Verdict::LinearlyUnstable => match a.spectral_proof {
            Some(generator::SpectralProof::Unstable { .. }) => &[
                ("instability", "exact: Sturm sequence on the characteristic polynomial of A"),
                ("eigenpair", "floating point (faer), for information"),
            ],
            _ => &[("eigenvalue", "floating point (faer), real part above tolerance")],
        },
        Verdict::NotAnEquilibrium => &[("equilibrium_residual", "exact (rational)")],
        Verdict::NoiseIncompatible => &[("noise_residuals", "exact (rational)")],
        Verdict::Inconclusive => &[("search", "floating point search; no claim is made")],
    };
    parts.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
}

fn choice_record(ch: &casimir::CasimirChoice) -> ChoiceRecord {
    ChoiceRecord {
        sign: ch.sign.as_i8() as i64,
        family_parameters: rationals(&ch.family_parameters),
        multipliers: rationals(&ch.multipliers),
        m: matrix(&ch.m),
        relative_margin: Float(ch.relative_margin),
    }
}

/// The stopping-time record of a certificate, when the spec asks and there
/// is an upper bound `sigma2_bound` of `Sigma^2` to give a guaranteed `T`.
pub(crate) fn stopping_record(
    stopping: Option<crate::parse::Stopping>,
    sigma2_bound: Option<f64>,
    bound: &str,
) -> Option<StoppingRecord> {
    let (stop, s2) = (stopping?, sigma2_bound?);
    let t = StoppingTime::new(stop.epsilon, stop.delta, s2).time().unwrap_or(f64::INFINITY);
    Some(StoppingRecord { epsilon: Float(stop.epsilon), delta: Float(stop.delta), t: Float(t), bound: bound.into() })
}

/// SHA-256 of the spec's compact JSON (keys sorted), in hex: any edit of the
/// embedded spec changes it, so `check` notices a spec that was altered even
/// where the altered spec would make the same claims true.
pub fn spec_digest(spec: &Value) -> String {
    use sha2::{Digest, Sha256};
    let hash = Sha256::digest(spec.to_string().as_bytes());
    hash.iter().map(|b| format!("{b:02x}")).collect()
}

/// Run the pipeline on a parsed spec and build the certificate.
pub fn certify_lie(spec: &Spec) -> Certificate {
    let analysis = analyse(&spec.system, &spec.settings.pipeline);
    let document = certificate_document(spec, &analysis);
    let json = serde_json::to_value(&document).unwrap_or_default();
    Certificate { json, analysis }
}

/// Build the certificate JSON from a spec and its analysis.
pub fn certificate_json(spec: &Spec, a: &Analysis) -> Value {
    serde_json::to_value(certificate_document(spec, a)).unwrap_or_default()
}

/// Build the typed certificate from a spec and its analysis.
pub fn certificate_document(spec: &Spec, a: &Analysis) -> CertificateDocument {
    let system = &spec.system;
    let coords = system.algebra().coordinates();
    let rows = |v: &[Vec<Rational>]| v.iter().map(|r| rationals(r)).collect::<Vec<_>>();
    // T is a guarantee: computed from Sigma^2 rounded up (the exact rational
    // when there is one), and rounded down itself (see StoppingTime::time).
    let stopping = stopping_record(
        spec.stopping,
        a.sigma2_bound(),
        "P(|dmu_t|_P^2 > epsilon) <= (delta/epsilon) exp(Sigma^2 t) for |dmu_0|_P^2 = delta",
    );
    let conserved = conserved_records(spec, a);
    let search = match &a.search {
        Some(casimir::SearchOutcome::NotFound { best_positive_margin, best_negative_margin, restricted_dimension }) => {
            Some(SearchRecord {
                best_positive_margin: Float(*best_positive_margin),
                best_negative_margin: Float(*best_negative_margin),
                restricted_dimension: *restricted_dimension as u64,
            })
        }
        _ => None,
    };
    let optimisation = a.stable.as_ref().map(|s| optimisation_record(spec, s));
    let exact = a.stable.as_ref().and_then(|s| s.exact.as_ref());
    let theorem = lie_theorem(spec, a, stopping.as_ref());
    CertificateDocument {
        certificate_version: CERTIFICATE_VERSION,
        engine: Engine { name: "verify".into(), version: ENGINE_VERSION.into() },
        name: spec.name.clone(),
        verdict: a.verdict,
        reason: a.reason.clone(),
        level: verification_level(a),
        theorem,
        checks: checks(a),
        sigma2: a.sigma2().map(Float),
        sigma2_exact: exact.map(|e| e.value.to_string()),
        sigma2_sharp: exact.map(|e| e.sharp),
        stopping,
        spec_sha256: spec_digest(&spec.raw),
        hamiltonian: system.hamiltonian().to_string_with(coords),
        coordinates: coords.to_vec(),
        equilibrium: EquilibriumRecord {
            point: rationals(system.equilibrium()),
            residual: rationals(&a.equilibrium_residual),
        },
        noise: NoiseRecord {
            fields: rows(system.noise()),
            residuals: rows(&a.noise_residuals),
            isotropy_basis: rows(&a.isotropy_basis),
        },
        conserved,
        casimir_discovery: spec.discovery.as_ref().map(|d| DiscoveryRecord {
            degree_searched: d.degree_searched,
            skipped_degrees: d.skipped_degrees.clone(),
        }),
        multipliers: a.variation.as_ref().map(|v| MultipliersRecord {
            particular: rationals(&v.family.particular),
            directions: rows(&v.family.directions),
        }),
        linearisation: a.linearisation.as_ref().map(|lin| LinearisationRecord {
            a: matrix(&lin.a),
            b: lin.noise.iter().map(matrix).collect(),
            spectrum: a.spectrum.iter().map(complex).collect(),
        }),
        spectrum_proof: a.spectral_proof.as_ref().map(|p| p.as_str().to_string()),
        spectrum_error: a.spectrum_error.clone(),
        instability: a.instability.as_ref().map(|inst| InstabilityRecord {
            eigenvalue: complex(&inst.eigenvalue),
            eigenvector: inst.eigenvector.iter().map(complex).collect(),
            tolerance: Float(inst.tolerance),
        }),
        search,
        casimir_choice: a.stable.as_ref().map(|s| choice_record(&s.choice)),
        optimisation,
        p: a.stable.as_ref().map(|s| matrix(&s.choice.p)),
        q: a.stable.as_ref().map(|s| matrix(&s.form.q)),
        residuals: a.stable.as_ref().map(|s| ResidualsRecord {
            drift: matrix(&s.form.drift_residual),
            paper_formula_3_3_equals_q: s.form.q == s.form.paper_formula,
        }),
        growth: a.stable.as_ref().map(|s| GrowthRecord {
            largest_generalized_eigenvalue: Float(s.growth.largest_eigenvalue),
            condition_number_p: Float(s.growth.condition_number),
            generalized_eigenvalues: s.growth.eigenvalues.iter().map(|x| Float(*x)).collect(),
            fastest_direction: s.growth.direction.iter().map(|x| Float(*x)).collect(),
        }),
        settings: spec.settings.to_document(),
        route: crate::record::RouteRecord {
            route: crate::record::Route::DenseExact,
            why: format!(
                "{} coordinates, at most {}: dense matrices in rational arithmetic",
                system.dim(),
                algebra::MAX_DIMENSION
            ),
            settings_not_honoured: BTreeMap::new(),
        },
        spec: spec.raw.clone(),
    }
}

/// The conserved quantities: each Casimir (where it came from) and first
/// integral, with whether it commutes with each noise field.
fn conserved_records(spec: &Spec, a: &Analysis) -> Vec<ConservedRecord> {
    let coords = spec.system.algebra().coordinates();
    spec.system
        .conserved()
        .iter()
        .zip(&a.noise_commutation)
        .map(|((kind, poly), commutes)| {
            let (kind, source) = match kind {
                casimir::ConservedKind::Casimir => ("casimir", spec.casimir_source.as_str()),
                casimir::ConservedKind::FirstIntegral => ("first_integral", "spec"),
            };
            ConservedRecord {
                kind: kind.into(),
                source: source.into(),
                expression: poly.to_string_with(coords),
                commutes_with_noise: commutes.clone(),
            }
        })
        .collect()
}

/// The minimisation of `Sigma^2` over the Casimir freedom, from the first
/// definite choice to the infimum and its proved lower bound.
fn optimisation_record(spec: &Spec, s: &generator::StableEvidence) -> OptimisationRecord {
    let mut opt = OptimisationRecord {
        optimised: s.optimum.is_some(),
        first_definite_choice: choice_record(&s.first_choice),
        first_definite_sigma2: Float(s.first_sigma2),
        infimum: None,
        infimum_lower_bound: None,
        infimum_witness: None,
        infimum_witness_matrix: None,
        gap: None,
        attained: None,
        within_tolerance: None,
        q_depends_on_m: None,
        method: None,
        tolerance: None,
    };
    if let Some(o) = &s.optimum {
        opt.infimum = Some(Float(o.infimum));
        if let (Some(lb), Some(w)) = (&o.infimum_lower_bound, &o.infimum_witness) {
            opt.infimum_lower_bound = Some(lb.to_string());
            match w {
                generator::InfimumWitness::Vector(x) => opt.infimum_witness = Some(rationals(x)),
                generator::InfimumWitness::Matrix(x) => opt.infimum_witness_matrix = Some(matrix(x)),
            }
        }
        opt.gap = Some(Float((s.growth.sigma2 - o.infimum).max(0.0)));
        opt.attained = Some(o.attained);
        opt.within_tolerance = Some(o.within_tolerance);
        opt.q_depends_on_m = Some(o.q_depends_on_m);
        opt.method = Some(o.method.to_string());
        opt.tolerance = Some(Float(spec.settings.pipeline.optimisation.tolerance));
    }
    opt
}

/// The statement proved (or estimated), generated from the data.
fn lie_theorem(spec: &Spec, a: &Analysis, stopping: Option<&StoppingRecord>) -> crate::theorem::TheoremRecord {
    let system = &spec.system;
    let algebra = spec.builtin.clone().unwrap_or_else(|| "an algebra given by structure constants".into());
    let subject = crate::theorem::finite_subject(
        &spec.name,
        &algebra,
        system.dim(),
        &crate::theorem::listed(system.equilibrium(), "the spec's equilibrium"),
        system.noise().len(),
    );
    let bound = a.stable.as_ref().map(|s| crate::theorem::Bound {
        sigma2: match &s.exact {
            Some(e) if e.value.to_string().len() <= 40 => e.value.to_string(),
            _ => crate::theorem::significant(s.sigma2_bound(), true),
        },
        zero: s.sigma2_bound() == 0.0,
        stopping: stopping.map(|st| (st.epsilon.0, st.delta.0, Some(st.t.0).filter(|t| t.is_finite()))),
    });
    crate::theorem::theorem(
        &subject,
        a.verdict,
        Some(verification_level(a)),
        bound.as_ref(),
        a.instability.as_ref().map(|i| i.eigenvalue.re),
    )
}
