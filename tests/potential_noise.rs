//! Fluid noise in the whole semidirect-product algebra (issue 13, part 1):
//! a noise element `((eta(y), 0), r(y))` acts on the compressible
//! equilibrium `(m, rho) = ((U, 0), 1)` by `-(0, U eta' + r')` (the paper's
//! `ad*` with the term `rho grad r` of the density part; derivation in
//! docs/fluids.md), so the potential `r' = -U eta'` completes incompatible
//! transport noise. In incompressible flow a potential force is a gradient
//! and does not act on the vorticity.

use serde_json::{json, Value};

fn spec(model: &str, noise: Value) -> Value {
    let mut v = json!({"name": "t", "fluid": {"model": model, "x_period": "2*pi", "y_interval": [-1, 1],
        "boundary": "walls", "shear_flow": "-cos(y)", "noise": noise, "ny": 64, "x_modes": 2}});
    if model == "compressible" {
        v["fluid"]["sound_speed"] = json!(2);
    }
    v
}

fn certify(v: &Value) -> Value {
    let s = spec::fluid_spec_from_value(v.clone()).unwrap();
    let cert = spec::certify_fluid(&s);
    // Every certificate, whatever its verdict, re-checks.
    spec::check_fluid_certificate(&cert).unwrap();
    cert
}

/// The paper's noise (0.3 sin y, 0) on U = -cos y: incompatible, and the
/// certificate's completion, pasted back, is compatible.
#[test]
fn the_completion_pasted_back_keeps_the_equilibrium() {
    let cert = certify(&spec("compressible", json!(["0.3*sin(y)"])));
    assert_eq!(cert["verdict"], "noise_incompatible");
    // sup_{[-1,1]} |U eta'| = sup 0.3 cos^2 y = 0.3 (at y = 0).
    let r = cert["compressible"]["noise_residuals"][0].as_f64().unwrap();
    assert!((r - 0.3).abs() < 1e-12, "{r}");
    let completion = cert["compressible"]["compatible_completion"].clone();
    assert_eq!(completion, json!([{"transport": "0.3*sin(y)", "potential": "compatible"}]));
    let again = certify(&spec("compressible", completion));
    assert_ne!(again["verdict"], "noise_incompatible");
    assert_eq!(again["compressible"]["noise_residuals"][0].as_f64(), Some(0.0));
    assert!(again["compressible"].get("compatible_completion").is_none());
    // No Sigma^2 is claimed without the compressible generator.
    assert_eq!(again["verdict"], "inconclusive");
    assert!(again.get("sigma2").is_none());
}

/// An explicit potential: the residual is sup |U eta' + r'|, computed here
/// by hand. For r = 0.3 cos^2(y)/2, r' = -0.3 sin y cos y and
/// U eta' + r' = -0.3 cos y (cos y + sin y) = -0.3 (1/2 + sin(2y + pi/4)/sqrt 2),
/// whose largest modulus on [-1, 1] is 0.3 (1/2 + 1/sqrt 2) at y = pi/8.
#[test]
fn an_explicit_potential_enters_the_residual() {
    let cert = certify(&spec("compressible", json!([{"transport": "0.3*sin(y)", "potential": "0.3*cos(y)^2/2"}])));
    assert_eq!(cert["verdict"], "noise_incompatible");
    let r = cert["compressible"]["noise_residuals"][0].as_f64().unwrap();
    let expected = 0.3 * (0.5 + std::f64::consts::FRAC_1_SQRT_2);
    // The residual is a maximum over samples: at most the supremum, and
    // within the sampling error of it.
    assert!(r <= expected * (1.0 + 1e-12) && r > expected * (1.0 - 1e-5), "{r} vs {expected}");
    // The exact antiderivative r = 0.3 (y/2 + sin(2y)/4) of -U eta' is
    // compatible to rounding, but not provably identically so: no verdict.
    let exact =
        certify(&spec("compressible", json!([{"transport": "0.3*sin(y)", "potential": "0.3*(y/2 + sin(2*y)/4)"}])));
    assert_eq!(exact["verdict"], "inconclusive");
    assert!(exact["compressible"]["noise_residuals"][0].as_f64().unwrap() < 1e-14);
}

/// Constant transport with the compatible completion (r' = -U * 0 = 0) is
/// the constant noise the engine already certifies: Sigma^2 = 0.
#[test]
fn constant_transport_with_its_completion_is_stable_with_sigma2_zero() {
    let plain = certify(&spec("compressible", json!([0.5])));
    let completed = certify(&spec("compressible", json!([{"transport": 0.5, "potential": "compatible"}])));
    assert_eq!(plain["verdict"], completed["verdict"]);
    assert_eq!(completed["sigma2"], json!(0.0));
}

/// In incompressible flow a potential force is a gradient: the vorticity
/// certificate is the same with or without it.
#[test]
fn a_potential_does_not_act_on_incompressible_flow() {
    let plain = certify(&spec("incompressible", json!(["0.3*sin(y)"])));
    let with = certify(&spec("incompressible", json!([{"transport": "0.3*sin(y)", "potential": "y^3 - 7"}])));
    assert_eq!(plain["verdict"], with["verdict"]);
    assert_eq!(plain["sigma2"], with["sigma2"]);
    assert_eq!(plain["modes"], with["modes"]);
}

#[test]
fn malformed_noise_entries_name_the_field() {
    let cases = [
        (json!([{"transport": "0.3*sin(y)"}]), "$.fluid.noise[0].potential", "required field is missing"),
        (json!([{"potential": "compatible"}]), "$.fluid.noise[0].transport", "required field is missing"),
        (json!([{"transport": "1", "potential": "1", "force": 2}]), "$.fluid.noise[0].force", "unknown field"),
        (json!([{"transport": "1", "potential": "log(y)"}]), "$.fluid.noise[0].potential", "unknown function"),
        (json!([{"transport": "z", "potential": "1"}]), "$.fluid.noise[0].transport", "unknown symbol"),
        (json!([["1"]]), "$.fluid.noise[0]", "expected an expression or an object"),
    ];
    for (noise, path, words) in cases {
        let e = spec::fluid_spec_from_value(spec("compressible", noise.clone())).unwrap_err();
        assert_eq!(e.path, path, "{noise}: {e}");
        assert!(e.message.contains(words), "{noise}: {e}");
    }
    let mut v = spec("compressible", json!(["1"]));
    v["parameters"] = json!({"compatible": 1});
    assert_eq!(spec::fluid_spec_from_value(v).unwrap_err().path, "$.parameters.compatible");
}
