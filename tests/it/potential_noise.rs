//! Fluid noise in the whole semidirect-product algebra:
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
    spec::check_certificate_value(&cert).unwrap();
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
    // The compressible generator certifies it (tests/it/barotropic.rs checks
    // its numbers against an independent computation). Its continuum bound
    // S(c) = sup eta'^2 c_s^2/(c_s^2 - (U + c)^2) is at least the value at
    // y = 0, 0.09 c_s^2/(c_s^2 - (c - 1)^2) >= 0.09, and above Sigma^2.
    assert_eq!(again["verdict"], "stable");
    assert_eq!(again["level"], "verified_float");
    let sigma2 = again["sigma2"].as_f64().unwrap();
    let bound = again["compressible"]["generator"]["continuum_bound"].as_f64().unwrap();
    assert!(sigma2 > 0.0 && sigma2 < bound && bound >= 0.09, "{sigma2} {bound}");
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

/// The compressible generator is built for walls: compatible noise with
/// non-constant transport in a periodic channel is `inconclusive`, with no
/// Sigma^2 claimed, and says why.
#[test]
fn a_periodic_compressible_generator_is_not_claimed() {
    let mut v = spec("compressible", json!([{"transport": "0.3*sin(y)", "potential": "compatible"}]));
    v["fluid"]["y_interval"] = json!([0, "2*pi"]);
    v["fluid"]["boundary"] = json!("periodic");
    v["fluid"]["shear_flow"] = json!("2"); // uniform (a periodic U'' integrates to 0, so it changes sign)
    let cert = certify(&v);
    assert_eq!(cert["verdict"], "inconclusive");
    assert!(cert.get("sigma2").is_none());
    assert!(cert["reason"].as_str().unwrap().contains("walls only"), "{}", cert["reason"]);
}

/// Uniform flow between walls with compatible noise: the shift c = -U brings
/// the flow to rest, no Casimir is needed (w = 0), and K and Q are both
/// pointwise, so Sigma^2 = max over the nodes of eta'^2 c_s^2/(c_s^2 - 0) =
/// max eta'^2 = 0.09 (eta' = 0.3 cos y, attained at the node y = 0), for
/// every x-mode; the continuum bound is the same number.
#[test]
fn uniform_flow_with_compatible_noise_has_the_pointwise_sigma2() {
    let mut v = spec("compressible", json!([{"transport": "0.3*sin(y)", "potential": "compatible"}]));
    v["fluid"]["shear_flow"] = json!("0.5");
    let cert = certify(&v);
    assert_eq!(cert["verdict"], "stable");
    let sigma2 = cert["sigma2"].as_f64().unwrap();
    assert!((sigma2 - 0.09).abs() < 1e-12, "{sigma2}");
    let bound = cert["compressible"]["generator"]["continuum_bound"].as_f64().unwrap();
    assert!((0.09..0.09 * (1.0 + 1e-9)).contains(&bound), "{bound}");
    assert_eq!(cert["form"]["galilean_shift"].as_f64(), Some(-0.5));
}

fn compatible_channel() -> Value {
    spec("compressible", json!([{"transport": "0.3*sin(y)", "potential": "compatible"}]))
}

/// A compressible generator certificate whose per-mode bound is lowered by
/// 1e-7 (relative) is refused: the stated number is below the Ritz value,
/// so `bound K - Q` is not positive definite and the check cannot prove it.
#[test]
fn a_generator_bound_edited_down_by_1e_7_is_refused() {
    let cert = certify(&compatible_channel());
    let mut edited = cert.clone();
    let upper = cert["modes"][0]["sigma2_upper"].as_f64().unwrap();
    edited["modes"][0]["sigma2_upper"] = json!(upper * (1.0 - 1e-7));
    let err = spec::check_certificate_value(&edited).unwrap_err();
    assert!(format!("{err:?}").contains("modes[0].sigma2_upper"), "{err:?}");
}

/// Sigma^2 is quadratic in the noise: the noise times 1e3 gives Sigma^2
/// times 1e6, and the same shift (the form does not see the noise).
#[test]
fn generator_sigma2_scales_with_the_square_of_the_noise() {
    let base = certify(&compatible_channel());
    let loud = certify(&spec("compressible", json!([{"transport": "300*sin(y)", "potential": "compatible"}])));
    let (s0, s1) = (base["sigma2"].as_f64().unwrap(), loud["sigma2"].as_f64().unwrap());
    assert!((s1 / s0 / 1e6 - 1.0).abs() < 1e-9, "{s0} {s1}");
    assert_eq!(base["form"]["galilean_shift"], loud["form"]["galilean_shift"]);
}

/// Units of velocity: U -> lambda U, c_s -> lambda c_s (with drho -> drho /
/// lambda and c -> lambda c) leaves the quotient Q/K unchanged, since w =
/// (U + c)/U'' and dq = ik du2 - du1' + U' drho are invariant
/// (docs/fluids.md §1b). So Sigma^2 must not move, whatever lambda; the
/// scan's shifts scale with lambda exactly (powers of two here).
#[test]
fn generator_sigma2_does_not_depend_on_the_units_of_velocity() {
    let base = certify(&compatible_channel());
    for lambda in [1024.0, 1.0 / 1024.0] {
        let mut v = compatible_channel();
        v["fluid"]["shear_flow"] = json!(format!("-{lambda}*cos(y)"));
        v["fluid"]["sound_speed"] = json!(2.0 * lambda);
        v["fluid"]["noise"] = json!([{"transport": "0.3*sin(y)", "potential": "compatible"}]);
        let scaled = certify(&v);
        let (s0, s1) = (base["sigma2"].as_f64().unwrap(), scaled["sigma2"].as_f64().unwrap());
        assert!((s1 / s0 - 1.0).abs() < 1e-8, "lambda {lambda}: {s0} {s1}");
    }
}

/// Sound speeds at the ends of the doubles: never `stable` by overflow, and
/// a reason that says what happened.
#[test]
fn extreme_sound_speeds_are_inconclusive_with_their_reason() {
    for (cs, says) in [(1e308, "overflows"), (1e-308, "c_s = 1e-308")] {
        let mut v = compatible_channel();
        v["fluid"]["sound_speed"] = json!(cs);
        let cert = certify(&v);
        assert_eq!(cert["verdict"], "inconclusive", "{cs}");
        assert!(cert["reason"].as_str().unwrap().contains(says), "{}", cert["reason"]);
    }
}
