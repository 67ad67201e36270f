//! Certificates from Rust without JSON text. A system built in
//! code is written out as a spec (structure constants when the algebra is
//! not a builtin one), certified, and re-checked like a file.

use exact::{parse_expression, parse_number, Rational, Symbols};

fn q(s: &str) -> Rational {
    parse_number(s).unwrap()
}

/// The rigid body `I = (3, 2, 1)` about its major axis with noise
/// `(3/10) e1`, written in the rescaled basis `e'_a = s_a e_a` with
/// `s = (2, 3, 5)`: coordinates `mu'_a = s_a mu_a`, noise components
/// `sigma_a / s_a`. `Sigma^2` does not depend on the basis: the closed form
/// `sigma^2 I1 (I2 - I3) / (I3 (I1 - I2)) = 0.09 * 3 = 27/100`
/// (`generator::closed_forms::rigid_body_sigma2`).
#[test]
fn a_system_in_a_basis_of_its_own_certifies_and_checks_from_rust() {
    let so3 = algebra::builtin("so3").unwrap().algebra;
    let scaled = so3.rescaled(&[q("2"), q("3"), q("5")]);
    let s = Symbols::new(scaled.coordinates());
    let e = |t: &str| parse_expression(t, &s).unwrap();
    let h = e("(Pi1/2)^2/6 + (Pi2/3)^2/4 + (Pi3/5)^2/2");
    let c = e("((Pi1/2)^2 + (Pi2/3)^2 + (Pi3/5)^2)/2");
    let noise = vec![vec![q("3/20"), q("0"), q("0")]];
    let system = casimir::System::new(scaled, h, vec![c], vec![], vec![q("2"), q("0"), q("0")], noise).unwrap();
    let stopping = spec::Stopping { epsilon: 0.1, delta: 0.001 };
    let settings = spec::EngineSettings::default();
    let spec = spec::spec_of_system("rescaled-rigid-body", &system, &settings, Some(stopping)).unwrap();
    // Not the builtin so3 any more: written by its structure constants.
    assert!(spec.raw["algebra"]["structure_constants"].is_array(), "{}", spec.raw["algebra"]);
    let cert = spec::certify_lie(&spec);
    assert_eq!(cert.verdict(), spec::Verdict::Stable);
    assert_eq!(cert.level(), spec::VerificationLevel::Exact);
    assert_eq!(cert.sigma2_exact().unwrap(), q("27/100"));
    // T = ln(eps/delta) / Sigma^2 = ln(100) / 0.27, rounded down.
    let t = cert.json["stopping"]["T"].as_f64().unwrap();
    assert!(t <= 100f64.ln() / 0.27 && t >= 100f64.ln() / 0.27 * (1.0 - 1e-12), "T = {t}");
    let report = cert.check().unwrap();
    assert_eq!((report.verdict, report.level), (spec::Verdict::Stable, Some(spec::VerificationLevel::Exact)));
    // The same certificate through JSON text, and a tampered one.
    spec::check_certificate(&cert.json.to_string()).unwrap();
    let mut bad = cert.json.clone();
    bad["spec"]["noise"][0][0] = "1/5".into();
    assert!(spec::check_certificate(&bad.to_string()).is_err());
}

/// The other verdicts come through the library path too: the intermediate
/// axis is linearly unstable (proved by a Sturm sequence), and an
/// off-equilibrium state is refused as one.
#[test]
fn unstable_and_off_equilibrium_systems_from_rust() {
    let so3 = algebra::builtin("so3").unwrap().algebra;
    let s = Symbols::new(so3.coordinates());
    let e = |t: &str| parse_expression(t, &s).unwrap();
    let build = |mu: [&str; 3]| {
        casimir::System::new(
            so3.clone(),
            e("Pi1^2/6 + Pi2^2/4 + Pi3^2/2"),
            vec![e("(Pi1^2 + Pi2^2 + Pi3^2)/2")],
            vec![],
            mu.map(q).to_vec(),
            vec![],
        )
        .unwrap()
    };
    let settings = spec::EngineSettings::default();
    let middle = spec::certify_system("middle", &build(["0", "1", "0"]), &settings, None).unwrap();
    assert_eq!(middle.verdict(), spec::Verdict::LinearlyUnstable);
    assert_eq!(middle.check().unwrap().level, Some(spec::VerificationLevel::Exact));
    let off = spec::certify_system("off", &build(["1", "1", "0"]), &settings, None).unwrap();
    assert_eq!(off.verdict(), spec::Verdict::NotAnEquilibrium);
    off.check().unwrap();
    // A name is part of the contract.
    let err = spec::spec_of_system("", &build(["1", "0", "0"]), &settings, None).unwrap_err();
    assert_eq!(err.path, "$.name", "{err}");
}

/// Fluids through the library: the Rayleigh-stable channel `U = -cos y`
/// (`U'' > 0`: the pseudomomentum is conserved by the drift and by every
/// noise field, so `Sigma^2 = 0` by structure). The certificate records the
/// pipeline's fixed constants; editing one fails the check.
#[test]
fn fluid_certificates_from_rust_record_their_constants() {
    let text = r#"{"name": "rayleigh", "fluid": {"model": "incompressible", "x_period": "2*pi",
        "y_interval": [-1, 1], "boundary": "walls", "shear_flow": "-cos(y)",
        "noise": ["0.3*sin(y)", "0.1*y"], "ny": 32, "x_modes": 2}}"#;
    let cert = spec::certify_fluid_spec(&spec::parse_fluid_spec(text).unwrap());
    assert_eq!((cert.verdict(), cert.level()), (spec::Verdict::Stable, Some(spec::VerificationLevel::ExactStructure)));
    assert_eq!(cert.sigma2(), Some(0.0));
    let report = cert.check().unwrap();
    assert_eq!(report.level, Some(spec::VerificationLevel::ExactStructure));
    assert_eq!(cert.json["constants"]["verify_margin_growth"], 30.0);
    let mut edited = cert.json.clone();
    edited["constants"]["verify_margin_growth"] = 10.0.into();
    assert!(spec::check_certificate_value(&edited).is_err());
}
