//! Zeitlin fields given by spherical harmonics, through the contract and
//! the `verify` binary: every verdict path of the general pipeline, a tilted
//! state against its zonal original, the compatible part pasted back, bad
//! input (exit 2, the JSON path named) and tampering (exit 1).

use serde_json::{json, Value};
use std::io::Write;
use std::process::{Command, Output};

fn verify(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_verify")).args(args).output().expect("run verify")
}

fn temp_file(name: &str, contents: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("verify-zeitlin-harmonics-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::File::create(&path).unwrap().write_all(contents.as_bytes()).unwrap();
    path
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn fixture(name: &str) -> Value {
    let path = format!("{}/../fixtures/zeitlin/{name}.json", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn certify(v: &Value) -> Value {
    spec::certify_zeitlin(&spec::zeitlin_spec_from_value(v.clone()).expect("valid spec"))
}

#[test]
fn every_verdict_path_of_the_general_pipeline() {
    let cases = [
        ("tilted-energy-casimir-n32", "stable", "rotated"),
        ("rossby-haurwitz-l3-n8", "linearly_unstable", "general"),
        ("rossby-haurwitz-l2-n7", "inconclusive", "general"),
        ("mixed-degrees-n8", "not_an_equilibrium", ""),
        ("tesseral-noise-n16", "noise_incompatible", ""),
    ];
    for (name, verdict, frame) in cases {
        let cert = certify(&fixture(name));
        assert_eq!(cert["verdict"], verdict, "{name}: {}", cert["reason"]);
        if !frame.is_empty() {
            assert_eq!(cert["frame"]["kind"], frame, "{name}");
        }
        assert_eq!(spec::check_zeitlin_certificate(&cert).unwrap().verdict.as_str(), verdict, "{name}");
    }
    // The tilted state is the zonal fixture's state rotated: the same
    // Sigma^2 and proved bound (the model is rotation invariant).
    let (tilted, zonal) = (certify(&fixture("tilted-energy-casimir-n32")), certify(&fixture("energy-casimir-n32")));
    for key in ["sigma2", "sigma2_upper"] {
        let (a, b) = (tilted[key].as_f64().unwrap(), zonal[key].as_f64().unwrap());
        assert!((a - b).abs() <= 1e-12 * b, "{key}: {a} vs {b}");
    }
    let axis: Vec<f64> = tilted["frame"]["axis"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    for (a, b) in axis.iter().zip([0.48, -0.6, 0.64]) {
        assert!((a - b).abs() < 1e-12, "axis {axis:?}");
    }
    // The unstable state's rate is positive, the spectrally stable one has none.
    assert!(certify(&fixture("rossby-haurwitz-l3-n8"))["growth_rate"].as_f64().unwrap() > 0.1);
    let l2 = certify(&fixture("rossby-haurwitz-l2-n7"));
    assert!(l2.get("growth_rate").is_none());
    assert!(l2["dense"]["restricted_margin"].as_f64().unwrap() < 0.0);
}

/// The compatible part that an incompatible certificate gives, pasted back
/// as the noise, is compatible: here the zonal part of the noise on a
/// monotone zonal state, which the Casimir–momentum form makes stable with
/// Sigma^2 = 0.
#[test]
fn the_compatible_part_pasted_back_is_compatible() {
    let mut spec = fixture("tesseral-noise-n16");
    let cert = certify(&spec);
    let rows = cert["compatible_noise"][0].clone();
    assert_eq!(rows.as_array().unwrap().len(), 1, "{rows}");
    // 0.1 T_20: quflow's basis is orthonormal, so the projection keeps the coefficient.
    assert_eq!(rows[0][0], 2);
    assert_eq!(rows[0][1], 0);
    assert!((rows[0][2].as_f64().unwrap() - 0.1).abs() < 1e-14);
    spec["zeitlin"]["noise"] = json!([{"harmonics": rows}]);
    let again = certify(&spec);
    assert_eq!(again["verdict"], "stable", "{}", again["reason"]);
    assert_eq!(again["sigma2"], 0.0);
    assert_eq!(again["frame"]["kind"], "zonal");
}

#[test]
fn bad_harmonics_name_the_field_and_exit_2() {
    let with = |rows: Value| json!({"name": "b", "zeitlin": {"N": 8, "equilibrium": {"harmonics": rows}, "noise": []}});
    let cases: Vec<(Value, &str, &str)> = vec![
        (with(json!([[1, 0]])), "$.zeitlin.equilibrium.harmonics[0]", "expected [l, m, value]"),
        (with(json!([[0, 0, 1.0]])), "$.zeitlin.equilibrium.harmonics[0][0]", "l must be between 1 and N - 1"),
        (with(json!([[8, 0, 1.0]])), "$.zeitlin.equilibrium.harmonics[0][0]", "l must be between 1 and N - 1"),
        (with(json!([[2, 3, 1.0]])), "$.zeitlin.equilibrium.harmonics[0][1]", "|m| must be at most l"),
        (with(json!([[2, 1, 1.0], [2, 1, 0.5]])), "$.zeitlin.equilibrium.harmonics[1]", "appears twice"),
        (with(json!([[1.5, 0, 1.0]])), "$.zeitlin.equilibrium.harmonics[0][0]", "must be an integer"),
        (with(json!([[1, 0, "1/0"]])), "$.zeitlin.equilibrium.harmonics[0][2]", "not finite"),
        (with(json!([[1, 0, "z"]])), "$.zeitlin.equilibrium.harmonics[0][2]", "constant"),
        (with(json!([[1, 0, 1e308], [2, 0, 1e308], [3, 0, 1e308]])), "$.zeitlin.equilibrium.harmonics", "overflows"),
        (
            json!({"name": "b", "zeitlin": {"N": 8, "equilibrium": {"harmonic": [[1, 0, 1]]}, "noise": []}}),
            "$.zeitlin.equilibrium",
            "unknown field",
        ),
        (
            json!({"name": "b", "zeitlin": {"N": 8, "equilibrium": [1, 0, 1], "noise": []}}),
            "$.zeitlin.equilibrium",
            "expected a zonal profile",
        ),
        (
            json!({"name": "b", "zeitlin": {"N": 2048, "equilibrium": {"harmonics": [[1, 0, 1]]}, "noise": []}}),
            "$.zeitlin.equilibrium",
            "up to N = 1024",
        ),
        (
            json!({"name": "b", "zeitlin": {"N": 8, "equilibrium": "z", "noise": [{"harmonics": [[9, 0, 1]]}]}}),
            "$.zeitlin.noise[0].harmonics[0][0]",
            "l must be between",
        ),
        (
            json!({"name": "b", "zeitlin": {"N": 8, "equilibrium": "z", "noise": []}, "settings": {"dense_max_n": 100}}),
            "$.settings.dense_max_n",
            "between 2 and 48",
        ),
        (
            json!({"name": "b", "zeitlin": {"N": 8, "equilibrium": "z", "noise": []}, "settings": {"equilibrium_tolerance": 0}}),
            "$.settings.equilibrium_tolerance",
            "between 1e-15 and 1e-3",
        ),
    ];
    for (v, path, words) in cases {
        let e = spec::zeitlin_spec_from_value(v.clone()).expect_err(&v.to_string());
        assert_eq!(e.path, path, "{e}");
        assert!(e.message.contains(words), "{e}");
        let file = temp_file("bad.json", &v.to_string());
        let out = verify(&["certify", file.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
        assert!(stderr(&out).contains(path), "{}", stderr(&out));
    }
}

#[test]
fn the_cli_certifies_checks_and_refuses_tampering() {
    for name in ["tesseral-noise-n16", "rossby-haurwitz-l3-n8", "rossby-haurwitz-l2-n7", "tilted-energy-casimir-n32"] {
        let spec_file = temp_file(&format!("{name}.json"), &fixture(name).to_string());
        let cert_file = spec_file.with_file_name(format!("{name}.cert.json"));
        let out = verify(&["certify", spec_file.to_str().unwrap(), "-o", cert_file.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        let first = std::fs::read_to_string(&cert_file).unwrap();
        // Two runs on one file give the same certificate.
        let out = verify(&["certify", spec_file.to_str().unwrap(), "-o", cert_file.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(0));
        assert_eq!(std::fs::read_to_string(&cert_file).unwrap(), first, "{name}");
        let out = verify(&["check", cert_file.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(0), "{name}: {}", stderr(&out));
        if name == "tesseral-noise-n16" {
            assert!(stderr(&verify(&["certify", spec_file.to_str().unwrap()])).contains("compatible part of noise[0]"));
        }
    }
    let edit = |name: &str, f: &dyn Fn(&mut Value)| -> Value {
        let mut c = certify(&fixture(name));
        f(&mut c);
        c
    };
    let scale = |v: &mut Value, by: f64| *v = (v.as_f64().unwrap() * by).into();
    let tampered: Vec<(&str, Value)> = vec![
        (
            "$.compatible_noise[0][0][2]",
            edit("tesseral-noise-n16", &|c| scale(&mut c["compatible_noise"][0][0][2], 1.0 + 1e-7)),
        ),
        ("$.residuals.noise", edit("tesseral-noise-n16", &|c| scale(&mut c["residuals"]["noise"], 1.0 - 1e-7))),
        ("$.frame.axis[0]", edit("tilted-energy-casimir-n32", &|c| scale(&mut c["frame"]["axis"][0], 1.0 + 1e-7))),
        ("$.sigma2_upper", edit("tilted-energy-casimir-n32", &|c| scale(&mut c["sigma2_upper"], 1.0 - 1e-7))),
        ("$.growth_rate", edit("rossby-haurwitz-l3-n8", &|c| scale(&mut c["growth_rate"], 1.0 - 1e-7))),
        (
            "$.dense.restricted_margin",
            edit("rossby-haurwitz-l2-n7", &|c| scale(&mut c["dense"]["restricted_margin"], 1.0 + 1e-7)),
        ),
        (
            "$.residuals.equilibrium",
            edit("mixed-degrees-n8", &|c| scale(&mut c["residuals"]["equilibrium"], 1.0 - 1e-7)),
        ),
        ("$.verdict", edit("mixed-degrees-n8", &|c| c["verdict"] = "stable".into())),
        (
            "$.spec_sha256",
            edit("rossby-haurwitz-l3-n8", &|c| c["spec"]["zeitlin"]["equilibrium"]["harmonics"][0][2] = 1.1.into()),
        ),
    ];
    for (path, c) in tampered {
        let file = temp_file("tampered.json", &c.to_string());
        let out = verify(&["check", file.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(1), "{path}: {}", stderr(&out));
        assert!(stderr(&out).contains(path), "{path}: {}", stderr(&out));
    }
}
