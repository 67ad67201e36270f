//! Certificates: the verdict, the evidence, the settings and the spec, as JSON.

use crate::parse::Spec;
use exact::{Matrix, Rational};
use generator::{analyse, Analysis, StoppingTime, Verdict};
use nalgebra::Complex;
use outcome::VerificationLevel;
use serde_json::{json, Map, Value};

/// Version of the certificate format.
pub const CERTIFICATE_VERSION: u64 = 2;

/// The engine version written into certificates.
pub const ENGINE_VERSION: &str = env!("CARGO_PKG_VERSION");

/// A certificate and the analysis it was made from.
#[derive(Clone, Debug)]
pub struct Certificate {
    /// The certificate JSON.
    pub json: Value,
    /// The analysis behind it.
    pub analysis: Analysis,
}

/// Build a JSON object by moving the values in (the `json!` macro would
/// re-serialise every embedded `Value`, a deep copy per field).
macro_rules! obj {
    ($($k:expr => $v:expr),* $(,)?) => {{
        #[allow(unused_mut)]
        let mut m = Map::new();
        $( m.insert($k.to_string(), Value::from($v)); )*
        Value::Object(m)
    }};
}

fn rationals(v: &[Rational]) -> Value {
    Value::Array(v.iter().map(|r| Value::String(r.to_string())).collect())
}

fn matrix(m: &Matrix) -> Value {
    Value::Array(
        (0..m.nrows())
            .map(|i| Value::Array((0..m.ncols()).map(|j| Value::String(m[(i, j)].to_string())).collect()))
            .collect(),
    )
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

fn complex(z: &Complex<f64>) -> Value {
    obj! { "re" => float_json(z.re), "im" => float_json(z.im) }
}

/// The verification level of a verdict and what each part rests on.
fn level_and_checks(a: &Analysis) -> (VerificationLevel, Value) {
    (verification_level(a), checks(a))
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
fn checks(a: &Analysis) -> Value {
    match a.verdict {
        Verdict::Stable => match a.stable.as_ref().and_then(|s| s.exact.as_ref()) {
            Some(e) => obj! {
                "P_definite" => "exact (rational LDL^T)",
                "first_variation" => "exact (rational)",
                "drift_residual" => "exact (rational)",
                "sigma2" => if e.sharp {
                    "exact: sigma2 * sP - sQ is positive semidefinite and singular (sigma2 = lambda_max)"
                } else {
                    "exact: sigma2 * sP - sQ is positive semidefinite (sigma2 is an upper bound within 1e-10 of lambda_max)"
                },
            },
            None => obj! {
                "P_definite" => "exact (rational LDL^T)",
                "drift_residual" => "exact (rational)",
                "sigma2" => "floating point only (exact certification switched off, or it failed at every candidate)",
            },
        },
        Verdict::LinearlyUnstable => match a.spectral_proof {
            Some(generator::SpectralProof::Unstable { .. }) => obj! {
                "instability" => "exact: Sturm sequence on the characteristic polynomial of A",
                "eigenpair" => "floating point (faer), for information",
            },
            _ => json!({ "eigenvalue": "floating point (faer), real part above tolerance" }),
        },
        Verdict::NotAnEquilibrium => json!({ "equilibrium_residual": "exact (rational)" }),
        Verdict::NoiseIncompatible => json!({ "noise_residuals": "exact (rational)" }),
        Verdict::Inconclusive => json!({ "search": "floating point search; no claim is made" }),
    }
}

fn choice_json(ch: &casimir::CasimirChoice) -> Value {
    obj! {
        "sign" => ch.sign.as_i8() as i64,
        "family_parameters" => rationals(&ch.family_parameters),
        "multipliers" => rationals(&ch.multipliers),
        "M" => matrix(&ch.m),
        "relative_margin" => float_json(ch.relative_margin),
    }
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
pub fn certify(spec: &Spec) -> Certificate {
    let analysis = analyse(&spec.system, &spec.settings.pipeline);
    let json = certificate_json(spec, &analysis);
    Certificate { json, analysis }
}

/// Build the certificate JSON from a spec and its analysis.
pub fn certificate_json(spec: &Spec, a: &Analysis) -> Value {
    let system = &spec.system;
    let coords = system.algebra().coordinates();
    let (level, checks) = level_and_checks(a);
    let mut c = Map::new();
    let mut put = |k: &str, v: Value| {
        c.insert(k.to_string(), v);
    };
    put("certificate_version", Value::from(CERTIFICATE_VERSION));
    put("engine", obj! { "name" => "verify", "version" => ENGINE_VERSION });
    put("name", Value::from(spec.name.as_str()));
    put("verdict", Value::from(a.verdict.as_str()));
    put("reason", Value::from(a.reason.as_str()));
    put("level", Value::from(level.as_str()));
    put("checks", checks);
    if let Some(s2) = a.sigma2() {
        put("sigma2", float_json(s2));
    }
    // T is a guarantee: computed from Sigma^2 rounded up (the exact rational
    // when there is one), and rounded down itself (see StoppingTime::time).
    if let (Some(stop), Some(s2)) = (spec.stopping, a.sigma2_bound()) {
        let st = StoppingTime::new(stop.epsilon, stop.delta, s2);
        put(
            "stopping",
            obj! {
                "epsilon" => stop.epsilon,
                "delta" => stop.delta,
                "T" => st.time().map_or(Value::String("infinity".into()), float_json),
                "bound" => "P(|dmu_t|_P^2 > epsilon) <= (delta/epsilon) exp(Sigma^2 t) for |dmu_0|_P^2 = delta",
            },
        );
    }
    put("spec_sha256", Value::from(spec_digest(&spec.raw)));
    put("hamiltonian", Value::from(system.hamiltonian().to_string_with(coords)));
    put("coordinates", Value::Array(coords.iter().map(|c| Value::from(c.as_str())).collect()));
    put(
        "equilibrium",
        obj! { "point" => rationals(system.equilibrium()), "residual" => rationals(&a.equilibrium_residual) },
    );
    put(
        "noise",
        obj! {
            "fields" => Value::Array(system.noise().iter().map(|s| rationals(s)).collect()),
            "residuals" => Value::Array(a.noise_residuals.iter().map(|r| rationals(r)).collect()),
            "isotropy_basis" => Value::Array(a.isotropy_basis.iter().map(|r| rationals(r)).collect()),
        },
    );
    let conserved: Vec<Value> = system
        .conserved()
        .iter()
        .zip(&a.noise_commutation)
        .map(|((kind, poly), commutes)| {
            let (kind, source) = match kind {
                casimir::ConservedKind::Casimir => ("casimir", spec.casimir_source.as_str()),
                casimir::ConservedKind::FirstIntegral => ("first_integral", "spec"),
            };
            obj! {
                "kind" => kind,
                "source" => source,
                "expression" => poly.to_string_with(coords),
                "commutes_with_noise" => Value::Array(commutes.iter().map(|b| Value::Bool(*b)).collect()),
            }
        })
        .collect();
    put("conserved", Value::Array(conserved));
    if let Some(d) = &spec.discovery {
        put("casimir_discovery", json!({ "degree_searched": d.degree_searched, "skipped_degrees": d.skipped_degrees }));
    }
    if let Some(v) = &a.variation {
        put(
            "multipliers",
            obj! {
                "particular" => rationals(&v.family.particular),
                "directions" => Value::Array(v.family.directions.iter().map(|d| rationals(d)).collect()),
            },
        );
    }
    if let Some(lin) = &a.linearisation {
        put(
            "linearisation",
            obj! {
                "A" => matrix(&lin.a),
                "B" => Value::Array(lin.noise.iter().map(matrix).collect()),
                "spectrum" => Value::Array(a.spectrum.iter().map(complex).collect()),
            },
        );
    }
    if let Some(p) = &a.spectral_proof {
        put("spectrum_proof", Value::from(p.as_str()));
    }
    if let Some(e) = &a.spectrum_error {
        put("spectrum_error", Value::from(e.as_str()));
    }
    if let Some(inst) = &a.instability {
        put(
            "instability",
            obj! {
                "eigenvalue" => complex(&inst.eigenvalue),
                "eigenvector" => Value::Array(inst.eigenvector.iter().map(complex).collect()),
                "tolerance" => float_json(inst.tolerance),
            },
        );
    }
    if let Some(casimir::SearchOutcome::NotFound { best_positive_margin, best_negative_margin, restricted_dimension }) =
        &a.search
    {
        put(
            "search",
            obj! {
                "best_positive_margin" => float_json(*best_positive_margin),
                "best_negative_margin" => float_json(*best_negative_margin),
                "restricted_dimension" => *restricted_dimension as u64,
            },
        );
    }
    if let Some(s) = &a.stable {
        put("casimir_choice", choice_json(&s.choice));
        if let Some(e) = &s.exact {
            put("sigma2_exact", Value::from(e.value.to_string()));
            put("sigma2_sharp", Value::Bool(e.sharp));
        }
        let mut opt = Map::new();
        opt.insert("first_definite_choice".into(), choice_json(&s.first_choice));
        opt.insert("first_definite_sigma2".into(), float_json(s.first_sigma2));
        match &s.optimum {
            Some(o) => {
                opt.insert("optimised".into(), Value::Bool(true));
                opt.insert("infimum".into(), float_json(o.infimum));
                if let (Some(lb), Some(w)) = (&o.infimum_lower_bound, &o.infimum_witness) {
                    opt.insert("infimum_lower_bound".into(), Value::from(lb.to_string()));
                    match w {
                        generator::InfimumWitness::Vector(x) => opt.insert(
                            "infimum_witness".into(),
                            Value::Array(x.iter().map(|r| Value::from(r.to_string())).collect()),
                        ),
                        generator::InfimumWitness::Matrix(x) => opt.insert("infimum_witness_matrix".into(), matrix(x)),
                    };
                }
                opt.insert("gap".into(), float_json((s.growth.sigma2 - o.infimum).max(0.0)));
                opt.insert("attained".into(), Value::Bool(o.attained));
                opt.insert("within_tolerance".into(), Value::Bool(o.within_tolerance));
                opt.insert("q_depends_on_M".into(), Value::Bool(o.q_depends_on_m));
                opt.insert("method".into(), Value::from(o.method));
                opt.insert("tolerance".into(), float_json(spec.settings.pipeline.optimisation.tolerance));
            }
            None => {
                opt.insert("optimised".into(), Value::Bool(false));
            }
        }
        put("optimisation", Value::Object(opt));
        put("P", matrix(&s.choice.p));
        put("Q", matrix(&s.form.q));
        put(
            "residuals",
            obj! {
                "drift" => matrix(&s.form.drift_residual),
                "paper_formula_3_3_equals_Q" => s.form.q == s.form.paper_formula,
            },
        );
        put(
            "growth",
            obj! {
                "largest_generalized_eigenvalue" => float_json(s.growth.largest_eigenvalue),
                "condition_number_P" => float_json(s.growth.condition_number),
                "generalized_eigenvalues" => Value::Array(s.growth.eigenvalues.iter().map(|x| float_json(*x)).collect()),
                "fastest_direction" => Value::Array(s.growth.direction.iter().map(|x| float_json(*x)).collect()),
            },
        );
    }
    put("settings", spec.settings.to_json());
    put("spec", spec.raw.clone());
    Value::Object(c)
}
