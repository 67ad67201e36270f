//! Certificates: the verdict, the evidence, the settings and the spec, as JSON.

use crate::parse::Spec;
use exact::{Matrix, Rational};
use generator::{analyse, Analysis, StoppingTime, Verdict};
use nalgebra::Complex;
use serde_json::{json, Map, Value};

/// Version of the certificate format.
pub const CERTIFICATE_VERSION: u64 = 1;

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

fn rationals(v: &[Rational]) -> Value {
    Value::Array(v.iter().map(|r| Value::String(r.to_string())).collect())
}

fn matrix(m: &Matrix) -> Value {
    json!(m.to_string_rows())
}

fn float(x: f64) -> Value {
    if x.is_finite() {
        json!(x)
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
    json!({ "re": float(z.re), "im": float(z.im) })
}

/// The verification level of a verdict.
///
/// At this stage `P`'s definiteness and all residuals are exact (rational),
/// while `Sigma^2` and the unstable eigenvalue come from floating-point
/// eigensolvers: the level is `numerical`, and `checks` says which part is
/// exact.
fn level_and_checks(a: &Analysis) -> (&'static str, Value) {
    match a.verdict {
        Verdict::Stable => (
            "numerical",
            json!({
                "P_definite": "exact (rational LDL^T)",
                "drift_residual": "exact (rational)",
                "sigma2": "floating point (generalized symmetric eigenproblem)"
            }),
        ),
        Verdict::LinearlyUnstable => {
            ("numerical", json!({ "eigenvalue": "floating point (Schur form), real part above tolerance" }))
        }
        Verdict::NotAnEquilibrium => ("exact", json!({ "equilibrium_residual": "exact (rational)" })),
        Verdict::NoiseIncompatible => ("exact", json!({ "noise_residuals": "exact (rational)" })),
        Verdict::Inconclusive => ("numerical", json!({ "search": "floating point search; no claim is made" })),
    }
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
    let coords = system.algebra.coordinates();
    let (level, checks) = level_and_checks(a);
    let mut c = Map::new();
    c.insert("certificate_version".into(), json!(CERTIFICATE_VERSION));
    c.insert("engine".into(), json!({ "name": "verify", "version": ENGINE_VERSION }));
    c.insert("name".into(), json!(spec.name));
    c.insert("verdict".into(), json!(a.verdict.as_str()));
    c.insert("reason".into(), json!(a.reason));
    c.insert("level".into(), json!(level));
    c.insert("checks".into(), checks);
    if let Some(s2) = a.sigma2() {
        c.insert("sigma2".into(), float(s2));
    }
    if let (Some(stop), Some(s2)) = (spec.stopping, a.sigma2()) {
        let st = StoppingTime::new(stop.epsilon, stop.delta, s2);
        c.insert(
            "stopping".into(),
            json!({
                "epsilon": stop.epsilon,
                "delta": stop.delta,
                "T": st.time().map_or(Value::String("infinity".into()), float),
                "bound": "P(|dmu_t|_P^2 > epsilon) <= (delta/epsilon) exp(Sigma^2 t) for |dmu_0|_P^2 = delta",
            }),
        );
    }
    c.insert("coordinates".into(), json!(coords));
    c.insert(
        "equilibrium".into(),
        json!({
            "point": rationals(&system.equilibrium),
            "residual": rationals(&a.equilibrium_residual),
        }),
    );
    c.insert(
        "noise".into(),
        json!({
            "fields": system.noise.iter().map(|s| rationals(s)).collect::<Vec<_>>(),
            "residuals": a.noise_residuals.iter().map(|r| rationals(r)).collect::<Vec<_>>(),
            "isotropy_basis": a.isotropy_basis.iter().map(|r| rationals(r)).collect::<Vec<_>>(),
        }),
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
            json!({
                "kind": kind,
                "source": source,
                "expression": poly.to_string_with(coords),
                "commutes_with_noise": commutes,
            })
        })
        .collect();
    c.insert("conserved".into(), Value::Array(conserved));
    if let Some(d) = &spec.discovery {
        c.insert(
            "casimir_discovery".into(),
            json!({ "degree_searched": d.degree_searched, "skipped_degrees": d.skipped_degrees }),
        );
    }
    if let Some(v) = &a.variation {
        c.insert(
            "multipliers".into(),
            json!({
                "particular": rationals(&v.family.particular),
                "directions": v.family.directions.iter().map(|d| rationals(d)).collect::<Vec<_>>(),
            }),
        );
        c.insert("hessian_h".into(), matrix(&v.hessian_h));
    }
    if let Some(lin) = &a.linearisation {
        c.insert(
            "linearisation".into(),
            json!({
                "A": matrix(&lin.a),
                "B": lin.noise.iter().map(matrix).collect::<Vec<_>>(),
                "spectrum": a.spectrum.iter().map(complex).collect::<Vec<_>>(),
            }),
        );
    }
    if let Some(inst) = &a.instability {
        c.insert(
            "instability".into(),
            json!({
                "eigenvalue": complex(&inst.eigenvalue),
                "eigenvector": inst.eigenvector.iter().map(complex).collect::<Vec<_>>(),
                "residual": float(inst.residual),
                "tolerance": float(inst.tolerance),
            }),
        );
    }
    if let Some(casimir::SearchOutcome::NotFound { best_positive_margin, best_negative_margin, restricted_dimension }) =
        &a.search
    {
        c.insert(
            "search".into(),
            json!({
                "best_positive_margin": float(*best_positive_margin),
                "best_negative_margin": float(*best_negative_margin),
                "restricted_dimension": restricted_dimension,
            }),
        );
    }
    if let Some(s) = &a.stable {
        let ch = &s.choice;
        c.insert(
            "casimir_choice".into(),
            json!({
                "sign": ch.sign,
                "family_parameters": rationals(&ch.family_parameters),
                "multipliers": rationals(&ch.multipliers),
                "M": matrix(&ch.m),
                "relative_margin": float(ch.relative_margin),
                "note": "first definite choice found (maximal Finsler margin); optimisation over the freedom is not yet done",
            }),
        );
        c.insert("P".into(), matrix(&ch.p));
        c.insert("Q".into(), matrix(&s.form.q));
        c.insert(
            "residuals".into(),
            json!({
                "drift": matrix(&s.form.drift_residual),
                "Q_minus_paper_formula": matrix(&s.form.q.sub(&s.form.paper_formula)),
            }),
        );
        c.insert(
            "growth".into(),
            json!({
                "sigma2": float(s.growth.sigma2),
                "largest_generalized_eigenvalue": float(s.growth.largest_eigenvalue),
                "generalized_eigenvalues": s.growth.eigenvalues.iter().map(|x| float(*x)).collect::<Vec<_>>(),
                "fastest_direction": s.growth.direction.iter().map(|x| float(*x)).collect::<Vec<_>>(),
                "relative_residual": float(s.growth.relative_residual),
            }),
        );
    }
    c.insert("settings".into(), spec.settings.to_json());
    c.insert("spec".into(), spec.raw.clone());
    Value::Object(c)
}
