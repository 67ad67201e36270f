//! Zeitlin fields given by spherical harmonics, through the contract and
//! the `verify` binary: every verdict path of the general pipeline, a tilted
//! state against its zonal original, the compatible part pasted back, bad
//! input (exit 2, the JSON path named) and tampering (exit 1).

use crate::common;
use serde_json::{json, Value};
use std::io::Write;
use std::process::Command;

fn temp_file(name: &str, contents: &str) -> std::path::PathBuf {
    common::temp_file("zeitlin-harmonics", name, contents)
}

use common::{stderr, verify};

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
        assert_eq!(spec::check_certificate_value(&cert).unwrap().verdict.as_str(), verdict, "{name}");
    }
    // The tilted state is the zonal fixture's state rotated: the same
    // Sigma^2 and proved bound (the model is rotation invariant).
    let (tilted, zonal) = (certify(&fixture("tilted-energy-casimir-n32")), certify(&fixture("energy-casimir-n32")));
    for key in ["sigma2", "sigma2_upper"] {
        let (a, b) = (tilted[key].as_f64().unwrap(), zonal[key].as_f64().unwrap());
        assert!((a - b).abs() <= 1e-12 * b, "{key}: {a} vs {b}");
    }
    // The axis is quflow's: the direction of the spec's own l = 1
    // coefficients (omega_11, omega_1-1, omega_10), largest component
    // positive (here (-0.48, 0.6, 0.64), as the fixture's description says).
    let rows = tilted["spec"]["zeitlin"]["equilibrium"]["harmonics"].as_array().unwrap().clone();
    let l1 = |m: i64| rows.iter().find(|r| r[0] == 1 && r[1] == m).map_or(0.0, |r| r[2].as_f64().unwrap());
    let direction = [l1(1), l1(-1), l1(0)];
    let length = direction.iter().map(|x| x * x).sum::<f64>().sqrt();
    let axis: Vec<f64> = tilted["frame"]["axis"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    for (a, b) in axis.iter().zip(direction) {
        assert!((a - b / length).abs() < 1e-12, "axis {axis:?} against the l = 1 part {direction:?}");
    }
    assert!((axis[0] + 0.48).abs() < 1e-12 && (axis[1] - 0.6).abs() < 1e-12, "{axis:?}");
    // Rates and the stopping time per unit qtime = t / hbar beside those per
    // unit t, hbar = 2 / sqrt(N^2 - 1) computed here: rates times hbar,
    // times divided by it; bounds rounded outward by at most 1e-15.
    let hbar = 2.0 / (32.0f64 * 32.0 - 1.0).sqrt();
    let per = &tilted["time"]["per_qtime"];
    assert_eq!(tilted["time"]["unit"], "t");
    let (s, s_q) = (tilted["sigma2"].as_f64().unwrap(), per["sigma2"].as_f64().unwrap());
    assert!((s_q - s * hbar).abs() <= 1e-15 * s * hbar, "{s_q} vs {}", s * hbar);
    let (u, u_q) = (tilted["sigma2_upper"].as_f64().unwrap(), per["sigma2_upper"].as_f64().unwrap());
    assert!(u_q >= u * hbar && u_q <= u * hbar * (1.0 + 2e-15), "{u_q} vs {}", u * hbar);
    let (t, t_q) = (tilted["stopping"]["T"].as_f64().unwrap(), per["T"].as_f64().unwrap());
    assert!(t_q <= t / hbar && t_q >= t / hbar * (1.0 - 2e-15), "{t_q} vs {}", t / hbar);
    let unstable = certify(&fixture("rossby-haurwitz-l3-n8"));
    let hbar8 = 2.0 / 63.0f64.sqrt();
    let g = unstable["growth_rate"].as_f64().unwrap();
    assert!((unstable["time"]["per_qtime"]["growth_rate"].as_f64().unwrap() - g * hbar8).abs() <= 1e-15 * g);
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
            json!({"name": "b", "zeitlin": {"N": 8, "equilibrium": "z", "noise": []}, "settings": {"matrix_free_max_n": 2048}}),
            "$.settings.matrix_free_max_n",
            "between 2 and 1024",
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
#[ignore = "heavy: run by CI's heavy stage (VERIFY_HEAVY_TESTS=1 ... -- --include-ignored)"]
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
        (
            "$.time.per_qtime.sigma2_upper",
            edit("tilted-energy-casimir-n32", &|c| scale(&mut c["time"]["per_qtime"]["sigma2_upper"], 1.0 - 1e-7)),
        ),
        (
            "$.time.per_qtime.T",
            edit("tilted-energy-casimir-n32", &|c| scale(&mut c["time"]["per_qtime"]["T"], 1.0 + 1e-7)),
        ),
        ("$.growth_rate", edit("rossby-haurwitz-l3-n8", &|c| scale(&mut c["growth_rate"], 1.0 - 1e-7))),
        (
            "$.matrix_free.eigenvalue[0]",
            edit("rossby-haurwitz-l3-n64", &|c| scale(&mut c["matrix_free"]["eigenvalue"][0], 1.0 + 1e-7)),
        ),
        (
            "$.matrix_free.backward_error",
            edit("rossby-haurwitz-l3-n64", &|c| scale(&mut c["matrix_free"]["backward_error"], 1.0 - 1e-7)),
        ),
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

/// A state zonal in no frame above `dense_max_n` is analysed matrix-free:
/// the same verdict and growth rate as the dense analysis of the same spec
/// with `dense_max_n` raised to N (1e-8 relative), the limit recorded in
/// the certificate's settings, and above `matrix_free_max_n` an
/// `inconclusive` that names the setting.
#[test]
fn a_state_above_dense_max_n_is_analysed_matrix_free() {
    let state = json!({"harmonics": [[3, 1, 1.0], [3, -2, 0.6], [3, 0, -0.2]]});
    let spec = |settings: Value| json!({"name": "rh", "zeitlin": {"N": 20, "equilibrium": state, "noise": []}, "settings": settings});
    let free = certify(&spec(json!({"dense_max_n": 16})));
    let dense = certify(&spec(json!({"dense_max_n": 20})));
    assert_eq!(free["verdict"], "linearly_unstable", "{}", free["reason"]);
    assert_eq!(dense["verdict"], "linearly_unstable", "{}", dense["reason"]);
    assert!(dense.get("matrix_free").is_none() && free.get("dense").is_none());
    assert_eq!(free["settings"]["matrix_free_max_n"], 256);
    assert!(dense["settings"].get("matrix_free_max_n").is_none());
    let (a, b) = (free["growth_rate"].as_f64().unwrap(), dense["growth_rate"].as_f64().unwrap());
    assert!((a - b).abs() <= 1e-8 * b, "matrix-free {a}, dense {b}");
    assert_eq!(free["matrix_free"]["indefinite"], true);
    assert_eq!(spec::check_certificate_value(&free).unwrap().verdict.as_str(), "linearly_unstable");
    let capped = certify(&spec(json!({"dense_max_n": 16, "matrix_free_max_n": 18})));
    assert_eq!(capped["verdict"], "inconclusive");
    assert!(capped["reason"].as_str().unwrap().contains("settings.matrix_free_max_n"), "{}", capped["reason"]);
}

/// A `.npy` file as NumPy writes it (format 1.0: magic, header length,
/// the header dict padded with spaces to a multiple of 64 bytes and ended
/// by a newline, then the little-endian data), written here by hand rather
/// than by the crate the engine reads with.
fn npy_bytes(w: &nalgebra::DMatrix<nalgebra::Complex<f64>>, fortran: bool, descr: &str) -> Vec<u8> {
    let (r, c) = w.shape();
    let mut header = format!(
        "{{'descr': '{descr}', 'fortran_order': {}, 'shape': ({r}, {c}), }}",
        if fortran { "True" } else { "False" }
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    let at = |k: usize| if fortran { w[(k % r, k / r)] } else { w[(k / c, k % c)] };
    for k in 0..r * c {
        let z = at(k);
        out.extend_from_slice(&z.re.to_le_bytes());
        if descr == "<c16" {
            out.extend_from_slice(&z.im.to_le_bytes());
        }
    }
    out
}

fn write_bytes(dir: &std::path::Path, name: &str, bytes: &[u8]) {
    std::fs::File::create(dir.join(name)).unwrap().write_all(bytes).unwrap();
}

/// A state and noise read from `.npy` files (C and Fortran order) give the
/// certificate of the same fields given by harmonics; the files are read
/// relative to the spec's folder (and the certificate's, by check), a
/// changed file fails the check, and paths that leave the folder, missing
/// files, wrong shapes, real arrays, Hermitian matrices and non-npy bytes
/// are bad input naming the field.
#[test]
fn npy_fields_read_relative_to_the_spec_and_are_pinned_by_their_hash() {
    let n = 12;
    let rows = json!([[1, 0, 0.8], [1, 1, 0.6], [3, 2, 0.0]]);
    let noise_rows = json!([[1, 0, 0.08], [1, 1, 0.06]]);
    let to_rows = |v: &Value| -> Vec<(usize, i64, f64)> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|r| (r[0].as_u64().unwrap() as usize, r[1].as_i64().unwrap(), r[2].as_f64().unwrap()))
            .collect()
    };
    let w = zeitlin::sphere::from_harmonics(n, &to_rows(&rows)).unwrap();
    let x = zeitlin::sphere::from_harmonics(n, &to_rows(&noise_rows)).unwrap();
    let dir = std::env::temp_dir().join(format!("verify-zeitlin-npy-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("states")).unwrap();
    write_bytes(&dir, "states/w.npy", &npy_bytes(&w, false, "<c16"));
    write_bytes(&dir, "states/wf.npy", &npy_bytes(&w, true, "<c16"));
    write_bytes(&dir, "states/x.npy", &npy_bytes(&x, false, "<c16"));
    let by_harmonics = certify(
        &json!({"name": "h", "zeitlin": {"N": n, "equilibrium": {"harmonics": rows}, "noise": [{"harmonics": noise_rows}]}}),
    );
    for file in ["states/w.npy", "states/wf.npy"] {
        let spec =
            json!({"name": "h", "zeitlin": {"N": n, "equilibrium": {"npy": file}, "noise": [{"npy": "states/x.npy"}]}});
        let spec_file = dir.join("spec.json");
        std::fs::write(&spec_file, spec.to_string()).unwrap();
        let cert_file = dir.join("spec.cert.json");
        // From another working directory: the paths are the spec's.
        let out = Command::new(env!("CARGO_BIN_EXE_verify"))
            .args(["certify", spec_file.to_str().unwrap(), "-o", cert_file.to_str().unwrap()])
            .current_dir(std::env::temp_dir())
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        let cert: Value = serde_json::from_str(&std::fs::read_to_string(&cert_file).unwrap()).unwrap();
        for key in ["verdict", "level", "sigma2", "frame", "form"] {
            assert_eq!(cert[key], by_harmonics[key], "{file}: {key}");
        }
        assert_eq!(cert["model"]["files"][0]["path"], file);
        assert_eq!(cert["model"]["files"][0]["sha256"].as_str().unwrap().len(), 64);
        let out = verify(&["check", cert_file.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    }
    // The file changes after the certificate was written: check fails.
    let cert_file = dir.join("spec.cert.json");
    write_bytes(&dir, "states/wf.npy", &npy_bytes(&(&w * nalgebra::Complex::new(1.0 + 1e-7, 0.0)), true, "<c16"));
    let out = verify(&["check", cert_file.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("$.model.files[0].sha256"), "{}", stderr(&out));
    // Bad files and paths.
    let hermitian = &w * nalgebra::Complex::new(0.0, 1.0);
    write_bytes(&dir, "states/hermitian.npy", &npy_bytes(&hermitian, false, "<c16"));
    write_bytes(&dir, "states/real.npy", &npy_bytes(&w, false, "<f8"));
    write_bytes(&dir, "states/small.npy", &npy_bytes(&zeitlin::sphere::harmonic(4, 1, 0).unwrap(), false, "<c16"));
    write_bytes(&dir, "states/junk.npy", b"not an array");
    let cases = [
        ("../w.npy", "no '..'"),
        ("/etc/passwd.npy", "not absolute"),
        ("states/w.txt", "relative path to a .npy file"),
        ("states/missing.npy", "cannot read"),
        ("states", "relative path to a .npy file"),
        ("states/small.npy", "expected [12, 12]"),
        ("states/real.npy", "complex128"),
        ("states/hermitian.npy", "not skew-Hermitian"),
        ("states/junk.npy", "not a .npy file"),
    ];
    for (file, words) in cases {
        let spec = json!({"name": "h", "zeitlin": {"N": n, "equilibrium": {"npy": file}, "noise": []}});
        let e = spec::zeitlin_spec_from_value_in(spec.clone(), Some(&dir)).expect_err(file);
        assert_eq!(e.path, "$.zeitlin.equilibrium.npy", "{e}");
        assert!(e.message.contains(words), "{file}: {e}");
        let spec_file = dir.join("bad.json");
        std::fs::write(&spec_file, spec.to_string()).unwrap();
        let out = verify(&["certify", spec_file.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
        assert!(stderr(&out).contains("$.zeitlin.equilibrium.npy"), "{}", stderr(&out));
    }
}
