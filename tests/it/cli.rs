//! End-to-end tests of the `verify` binary: every verdict path, bad input
//! (exit status 2 and the JSON path in the message), the fixture table, and
//! tampered certificates (exit status 1).

use crate::common;

use common::*;
use serde_json::Value;
use std::io::Write;
use std::process::{Command, Output};

fn verify(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_verify")).args(args).output().expect("run verify")
}

fn temp_file(name: &str, contents: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("verify-cli-tests-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::File::create(&path).unwrap().write_all(contents.as_bytes()).unwrap();
    path
}

fn certify_text(name: &str, text: &str) -> Output {
    let path = temp_file(name, text);
    verify(&["certify", path.to_str().unwrap()])
}

/// Certify a fixture through the CLI and return the certificate.
fn certify_fixture(name: &str) -> Value {
    let out = verify(&["certify", fixture_path(name).to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{name}: {}", stderr(&out));
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn every_verdict_path_through_the_cli() {
    let cases = [
        ("rigid-body-major-axis.json", "stable"),
        ("rigid-body-minor-axis.json", "stable"),
        ("rigid-body-intermediate-axis.json", "linearly_unstable"),
        ("rigid-body-spherical.json", "inconclusive"),
        ("rigid-body-not-equilibrium.json", "not_an_equilibrium"),
        ("rigid-body-isotropic-noise.json", "noise_incompatible"),
        ("lagrange-top-slow.json", "linearly_unstable"),
    ];
    for (name, verdict) in cases {
        let cert = certify_fixture(name);
        assert_eq!(cert["verdict"], verdict, "{name}");
        assert!(cert.get("sigma2").is_some() == (verdict == "stable"), "{name}: sigma2 present iff stable");
    }
}

#[test]
fn minor_axis_is_negative_definite() {
    let cert = certify_fixture("rigid-body-minor-axis.json");
    assert_eq!(cert["casimir_choice"]["sign"], -1);
    // Sigma^2 = sigma^2 I1 (I2 - I3)/(I3 (I1 - I2)) = 0.09 * 1 * (-1) / (3 * (-1)) = 0.03
    assert!(rel(cert["sigma2"].as_f64().unwrap(), 0.03) < 1e-13);
}

#[test]
fn not_an_equilibrium_reports_the_residual() {
    let cert = certify_fixture("rigid-body-not-equilibrium.json");
    // Pi = (1,1,0), Omega = (1/3, 1/2, 0): Pi x Omega = (0, 0, 1/2 - 1/3) = (0, 0, 1/6)
    assert_eq!(cert["equilibrium"]["residual"], serde_json::json!(["0", "0", "1/6"]));
}

#[test]
fn incompatible_noise_reports_residuals_and_the_compatible_noise() {
    let cert = certify_fixture("rigid-body-isotropic-noise.json");
    // ad*_{sigma e2} (1,0,0) = (1,0,0) x (0, 3/10, 0) = (0, 0, 3/10); e3 gives (0, -3/10, 0).
    assert_eq!(cert["noise"]["residuals"][0], serde_json::json!(["0", "0", "0"]));
    assert_eq!(cert["noise"]["residuals"][1], serde_json::json!(["0", "0", "3/10"]));
    assert_eq!(cert["noise"]["residuals"][2], serde_json::json!(["0", "-3/10", "0"]));
    assert_eq!(cert["noise"]["isotropy_basis"], serde_json::json!([["1", "0", "0"]]));
}

#[test]
fn unstable_certificate_carries_the_eigenpair() {
    let cert = certify_fixture("rigid-body-intermediate-axis.json");
    // I = (2, 3, 1): a2 = 1/3 - 1/2 = -1/6, a3 = 1 - 1/2 = 1/2, rate sqrt(1/12).
    let re = cert["instability"]["eigenvalue"]["re"].as_f64().unwrap();
    assert!(rel(re, (1.0f64 / 12.0).sqrt()) < 1e-12, "{re}");
    assert_eq!(cert["instability"]["eigenvector"].as_array().unwrap().len(), 3);
}

#[test]
fn summary_goes_to_stderr_and_output_file_is_written() {
    let out_path = std::env::temp_dir().join(format!("verify-cli-out-{}.json", std::process::id()));
    let out = verify(&[
        "certify",
        fixture_path("rigid-body-major-axis.json").to_str().unwrap(),
        "-o",
        out_path.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0));
    assert!(out.stdout.is_empty());
    let err = stderr(&out);
    assert!(err.contains("rigid-body-major-axis: stable") && err.contains("Sigma^2 = 0.27"), "{err}");
    let cert: Value = serde_json::from_str(&std::fs::read_to_string(&out_path).unwrap()).unwrap();
    assert_eq!(cert["verdict"], "stable");
    let check = verify(&["check", out_path.to_str().unwrap()]);
    assert_eq!(check.status.code(), Some(0), "{}", stderr(&check));
}

#[test]
#[ignore = "heavy: run by CI's heavy stage (VERIFY_HEAVY_TESTS=1 ... -- --include-ignored)"]
fn fixture_table_lists_every_fixture() {
    let out = verify(&["--fixtures", fixture_path("").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let table = String::from_utf8_lossy(&out.stdout);
    for name in fixture_specs() {
        let stem = name.trim_end_matches(".json");
        let line = table.lines().find(|l| l.starts_with(stem)).unwrap_or_else(|| panic!("{stem} missing:\n{table}"));
        assert!(line.ends_with("checked"), "{line}");
    }
}

/// Each bad input: exit 2 and a message naming the JSON path.
#[test]
fn bad_input_is_exit_2_with_the_json_path() {
    let good = fixture("rigid-body-major-axis.json");
    let structure =
        r#"{"coordinates": ["a", "b", "c"], "structure_constants": [[0, 1, 1, 1], [0, 2, 1, 1], [1, 2, 0, 1]]}"#;
    let cases: Vec<(&str, String, &str, &str)> = vec![
        ("malformed JSON", r#"{"name": "x", "#.into(), "$:", "malformed JSON"),
        ("unknown field", good.replacen(r#""name""#, r#""nmae""#, 1), "$.nmae", "unknown field"),
        ("unknown algebra", good.replace(r#""so3""#, r#""so5""#), "$.algebra", "unknown algebra 'so5'"),
        ("equilibrium length", good.replace("[1, 0, 0]", "[1, 0]"), "$.equilibrium", "expected 3 components"),
        (
            "noise length",
            good.replace(r#"[["sigma", 0, 0]]"#, r#"[["sigma", 0, 0, 0]]"#),
            "$.noise[0]",
            "expected 3 components",
        ),
        ("non-finite string", good.replace(r#""I1": 3"#, r#""I1": "inf""#), "$.parameters.I1", "not a finite number"),
        ("non-finite literal", good.replace(r#""I1": 3"#, r#""I1": 1e999"#), "$.parameters.I1", "not a finite number"),
        (
            "nan in expression",
            good.replace("[1, 0, 0]", r#"["NaN", 0, 0]"#),
            "$.equilibrium[0]",
            "unknown symbol 'NaN'",
        ),
        ("unknown symbol", good.replace("Pi3^2/(2*I3)", "Pi3^2/(2*I4)"), "$.hamiltonian", "unknown symbol 'I4'"),
        (
            "division by a polynomial",
            good.replace("Pi3^2/(2*I3)", "1/Pi3"),
            "$.hamiltonian",
            "division by a polynomial",
        ),
        ("non-polynomial", good.replace("Pi3^2/(2*I3)", "sin(Pi3)"), "$.hamiltonian", "function call"),
        (
            "Jacobi",
            good.replace(r#""so3""#, structure),
            "$.algebra.structure_constants",
            "Jacobi identity fails for (e_0, e_1, e_2)",
        ),
        (
            "missing field",
            good.replace(r#""hamiltonian": "Pi1^2/(2*I1) + Pi2^2/(2*I2) + Pi3^2/(2*I3)","#, ""),
            "$.hamiltonian",
            "missing",
        ),
        ("wrong type", good.replace(r#"[["sigma", 0, 0]]"#, r#""sigma""#), "$.noise", "expected an array"),
        (
            "false Casimir",
            good.replace(r#""(Pi1^2 + Pi2^2 + Pi3^2)/2""#, r#""Pi1^2""#),
            "$.casimirs[0]",
            "is not a Casimir",
        ),
        (
            "false first integral",
            good.replace(r#""first_integrals": []"#, r#""first_integrals": ["Pi1"]"#),
            "$.first_integrals[0]",
            "not conserved",
        ),
        (
            "epsilon below delta",
            good.replace(r#""epsilon": 0.1"#, r#""epsilon": 0.0001"#),
            "$.stopping.epsilon",
            "must exceed delta",
        ),
        (
            "parameter named like a coordinate",
            good.replace(r#""I1": 3"#, r#""Pi1": 3, "I1": 3"#),
            "$.parameters.Pi1",
            "name of a coordinate",
        ),
        (
            "coordinate in the equilibrium",
            good.replace("[1, 0, 0]", r#"[1, "Pi2", 0]"#),
            "$.equilibrium[1]",
            "must be a constant",
        ),
        (
            "diagonal structure constant",
            good.replace(r#""so3""#, r#"{"coordinates": ["a", "b"], "structure_constants": [[1, 1, 0, 2]]}"#),
            "$.algebra.structure_constants[0]",
            "antisymmetry",
        ),
        (
            "index out of range",
            good.replace(r#""so3""#, r#"{"coordinates": ["a", "b"], "structure_constants": [[0, 1, 5, 1]]}"#),
            "$.algebra.structure_constants[0]",
            "out of range",
        ),
        ("not an object", "[1, 2, 3]".into(), "$:", "expected an object"),
        ("exponent too large", good.replace("Pi1^2/(2*I1)", "Pi1^200"), "$.hamiltonian", "too large"),
        (
            "bad setting",
            good.replace(
                r#""name": "rigid-body-major-axis","#,
                r#""name": "x", "settings": {"definiteness_tolerance": 2},"#,
            ),
            "$.settings.definiteness_tolerance",
            "must be between",
        ),
    ];
    for (what, text, path, message) in cases {
        let out = certify_text(&format!("{}.json", what.replace(' ', "-")), &text);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{what}: status {:?}, stderr {err}", out.status);
        assert!(err.contains(path), "{what}: stderr lacks the path {path}: {err}");
        assert!(err.contains(message), "{what}: stderr lacks '{message}': {err}");
        assert!(!err.contains("panicked"), "{what}: {err}");
        assert!(out.stdout.is_empty(), "{what}: no certificate on bad input");
    }
}

#[test]
fn missing_file_is_bad_input() {
    let out = verify(&["certify", "/nonexistent/spec.json"]);
    assert_eq!(out.status.code(), Some(2));
    let out = verify(&["check", "/nonexistent/cert.json"]);
    assert_eq!(out.status.code(), Some(2));
}

/// Single-number alterations of a certificate each fail `check` with exit 1.
#[test]
fn tampered_certificates_fail_check() {
    let cert = certify_fixture("heavy-top-asymmetric.json");
    let sigma2 = cert["sigma2"].as_f64().unwrap();
    let mut tampers: Vec<(&str, Value)> = Vec::new();
    let mut c = cert.clone();
    c["sigma2"] = serde_json::json!(sigma2 * (1.0 - 1e-6));
    tampers.push(("sigma2 lowered", c));
    let mut c = cert.clone();
    c["verdict"] = serde_json::json!("linearly_unstable");
    tampers.push(("verdict flipped", c));
    let mut c = cert.clone();
    c["P"][0][0] = serde_json::json!("2");
    tampers.push(("P entry", c));
    let mut c = cert.clone();
    c["Q"][0][0] = serde_json::json!("0");
    tampers.push(("Q entry", c));
    let mut c = cert.clone();
    c["casimir_choice"]["multipliers"][0] = serde_json::json!("4");
    tampers.push(("multiplier", c));
    let mut c = cert.clone();
    c["spec"]["parameters"]["mgl"] = serde_json::json!(2);
    tampers.push(("spec parameter", c));
    let mut c = cert.clone();
    c["stopping"]["T"] = serde_json::json!(100.0);
    tampers.push(("stopping time", c));
    for (what, c) in tampers {
        let path = temp_file(&format!("tampered-{}.json", what.replace(' ', "-")), &c.to_string());
        let out = verify(&["check", path.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(1), "{what}: {}", stderr(&out));
        assert!(stderr(&out).contains("check failed at $."), "{what}: {}", stderr(&out));
    }
    // The untouched certificate passes.
    let path = temp_file("untouched.json", &cert.to_string());
    assert_eq!(verify(&["check", path.to_str().unwrap()]).status.code(), Some(0));
}

#[test]
fn malformed_certificate_is_bad_input() {
    let path = temp_file("not-a-cert.json", r#"{"verdict": "stable"}"#);
    let out = verify(&["check", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("$.spec"));
}

/// Numbers that are verified rather than compared (eigenvector, spectrum,
/// fastest direction) still fail `check` when altered.
#[test]
fn tampered_verified_numbers_fail_check() {
    let unstable = certify_fixture("rigid-body-intermediate-axis.json");
    let stable = certify_fixture("rigid-body-major-axis.json");
    let mut tampers: Vec<(&str, Value)> = Vec::new();
    let mut c = unstable.clone();
    let x = c["instability"]["eigenvector"][1]["re"].as_f64().unwrap();
    c["instability"]["eigenvector"][1]["re"] = serde_json::json!(x + 1e-3);
    tampers.push(("eigenvector entry", c));
    let mut c = unstable.clone();
    let x = c["linearisation"]["spectrum"][0]["re"].as_f64().unwrap();
    c["linearisation"]["spectrum"][0]["re"] = serde_json::json!(x * (1.0 + 1e-6));
    tampers.push(("spectrum entry", c));
    let mut c = stable.clone();
    let x = c["growth"]["fastest_direction"][1].as_f64().unwrap();
    c["growth"]["fastest_direction"][1] = serde_json::json!(x * (1.0 + 1e-6));
    tampers.push(("fastest direction", c));
    let mut c = stable.clone();
    c["growth"]["generalized_eigenvalues"][0] = serde_json::json!(-1.0);
    tampers.push(("generalized eigenvalue", c));
    for (what, c) in tampers {
        let path = temp_file(&format!("tampered-verified-{}.json", what.replace(' ', "-")), &c.to_string());
        let out = verify(&["check", path.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(1), "{what}: {}", stderr(&out));
    }
}

/// `verify simulate` writes the charts and the numbers; the same seed gives
/// the same numbers on 1 and 2 threads.
#[test]
fn simulate_writes_charts_and_is_thread_independent() {
    let base = std::env::temp_dir().join(format!("verify-sim-{}", std::process::id()));
    let spec = fixture_path("rigid-body-major-axis.json");
    let mut reports = Vec::new();
    for threads in ["1", "2"] {
        let out = base.join(threads);
        let o = simulate(
            &[
                spec.to_str().unwrap(),
                "--paths",
                "300",
                "--dt",
                "0.05",
                "--t-end",
                "5",
                "--outputs",
                "20",
                "--out",
                out.to_str().unwrap(),
            ],
            threads,
        );
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        for f in ["-density.svg", "-density.png", "-growth.svg", "-growth.png", ".json", ".csv"] {
            let p = out.join(format!("rigid-body-major-axis{f}"));
            assert!(p.metadata().map(|m| m.len() > 100).unwrap_or(false), "{} missing", p.display());
        }
        let mut report: Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("rigid-body-major-axis.json")).unwrap()).unwrap();
        report["parameters"]["threads"] = Value::Null;
        reports.push(report);
    }
    assert_eq!(reports[0], reports[1], "1 and 2 threads differ");
}

/// Bad simulation parameters: exit 2 with the option named, never a hang.
#[test]
fn simulate_rejects_bad_parameters() {
    let spec = fixture_path("rigid-body-major-axis.json");
    let s = spec.to_str().unwrap();
    let cases: [(&[&str], &str); 6] = [
        (&[s, "--dt", "-0.1"], "--dt"),
        (&[s, "--t-end", "1e9", "--dt", "1e-6"], "beyond reason"),
        (&[s, "--paths", "0"], "--paths"),
        (&[s, "--observable", "Pi9"], "--observable: unknown coordinate 'Pi9'"),
        (&[s, "--t-end", "1e5", "--dt", "1e-4"], "would take about"),
        (&[s, "--scheme", "rk4"], "--scheme"),
    ];
    for (args, message) in cases {
        let o = simulate(args, "2");
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(message), "{args:?}: {}", stderr(&o));
    }
}

/// Regression: `simulate --bins 0` was reported as an `--observable` error
/// and the t-end errors said `--t_end`. Each message must name the flag the
/// user typed.
#[test]
fn simulate_errors_name_the_flag_that_was_given() {
    let spec = fixture_path("rigid-body-major-axis.json");
    let s = spec.to_str().unwrap();
    let cases: [(&[&str], &str); 6] = [
        (&[s, "--bins", "0"], "--bins:"),
        (&[s, "--t-end", "-1"], "--t-end:"),
        (&[s, "--t-end", "nan"], "--t-end:"),
        (&[s, "--outputs", "0"], "--outputs:"),
        (&[s, "--dt", "0"], "--dt:"),
        (&[s, "--paths", "0"], "--paths:"),
    ];
    for (args, flag) in cases {
        let o = simulate(args, "2");
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.starts_with(&format!("error: {flag}")), "{args:?}: {err}");
        assert!(!err.contains("t_end") && !err.contains("--observable"), "{args:?}: {err}");
    }
}

/// Regression: `simulate --bins 1000000000` allocated outputs x bins
/// counters per block of paths, past 4 GB. Bins, outputs, their product and
/// the statistics held per block are now limited, and a run beyond a limit
/// is refused before any work with the flag and the limit named.
#[test]
fn simulate_refuses_huge_histograms_up_front() {
    let spec = fixture_path("rigid-body-major-axis.json");
    let s = spec.to_str().unwrap();
    // (arguments, the flag, the limit quoted: 10 000 bins, 100 000 outputs,
    // 10^7 histogram cells, 2^31 bytes = 2.1 GB of statistics)
    let cases: [(&[&str], &str, &str); 4] = [
        (&[s, "--bins", "1000000000"], "--bins", "at most 10000 bins"),
        (&[s, "--outputs", "1000000"], "--outputs", "at most 100000 output times"),
        (&[s, "--outputs", "10000", "--bins", "10000"], "--outputs/--bins", "limit of 10000000"),
        // Within each limit, but 391 blocks of 256 paths x ~1000 times x
        // 10^4 bins would hold 33 GB.
        (&[s, "--paths", "100000", "--outputs", "1000", "--bins", "10000"], "--paths/--outputs/--bins", "limit 2.1 GB"),
    ];
    for (args, flag, limit) in cases {
        let started = std::time::Instant::now();
        let o = simulate(args, "2");
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.starts_with(&format!("error: {flag}:")) && err.contains(limit), "{args:?}: {err}");
        // Nothing is simulated: a certify of the rigid body takes
        // milliseconds, so 10 s only allows for a loaded machine.
        assert!(started.elapsed().as_secs_f64() < 10.0, "{args:?}: took {:?}", started.elapsed());
    }
}

/// Regression: `RAYON_NUM_THREADS=10000 simulate` started 10 000 threads
/// (97 s and 1.2 GB for a small run). The pool is capped at 4 x the
/// available cores (at most 256), with a note; an invalid value falls back
/// to the cores, with a note.
#[test]
fn huge_thread_counts_are_capped() {
    let spec = fixture_path("rigid-body-major-axis.json");
    let base = std::env::temp_dir().join(format!("verify-threads-{}", std::process::id()));
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let cap = (4 * cores).min(256);
    for (value, note, threads) in [("10000", "capped at", cap), ("many", "not a positive integer", cores)] {
        let out = base.join(value);
        let args = [
            spec.to_str().unwrap(),
            "--paths",
            "200",
            "--t-end",
            "2",
            "--outputs",
            "10",
            "--out",
            out.to_str().unwrap(),
        ];
        let started = std::time::Instant::now();
        let o = simulate(&args, value);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(0), "{value}: {err}");
        assert!(err.contains("RAYON_NUM_THREADS") && err.contains(note), "{value}: {err}");
        // 400 paths x 200 steps take milliseconds; 30 s is far below the
        // 97 s of 10 000 threads and leaves room for a loaded machine.
        assert!(started.elapsed().as_secs_f64() < 30.0, "{value}: took {:?}", started.elapsed());
        let report: Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("rigid-body-major-axis.json")).unwrap()).unwrap();
        assert_eq!(report["parameters"]["threads"].as_u64(), Some(threads as u64), "{value}");
    }
}

/// Regression: exit-2 messages echoed the whole offending input. Values are
/// now quoted as 100-character excerpts with their length, and any message
/// is cut to about 2000 bytes. A command-line argument cannot exceed 128 KiB
/// on Linux (MAX_ARG_STRLEN), so options get 120 000 bytes; the spec's name
/// gets 50 MB.
#[test]
fn huge_inputs_are_quoted_as_excerpts() {
    let spec = fixture_path("rigid-body-major-axis.json");
    let s = spec.to_str().unwrap();
    let big = "x".repeat(120_000);
    let param = format!("I2={big}");
    let named = format!("{big}=1:2:3");
    let flag = format!("--{big}");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["simulate", s, "--observable", &big], "--observable"),
        (vec!["simulate", s, "--scheme", &big], "--scheme"),
        (vec!["simulate", s, "--paths", &big], "--paths"),
        (vec!["simulate", s, &flag], "unexpected argument"),
        (vec!["sweep", s, "--param", &param], "--param"),
        (vec!["sweep", s, "--param", &named], "--param"),
        (vec!["sweep", s, "--param", "I2=1:2:3", "--shard", &big], "--shard"),
        (vec!["plot-sweep", s, "--spec", s, "--shade", &big], "--shade"),
    ];
    for (args, what) in cases {
        let o = verify(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{what}: {}", &err[..err.len().min(300)]);
        assert!(err.contains(what), "{what}: {}", &err[..err.len().min(300)]);
        // An excerpt is 100 characters and the message's own text about
        // 150; the safety net alone would allow 2000.
        assert!(err.len() < 1000, "{what}: {} bytes of stderr", err.len());
    }

    // A spec whose name is 50 MB: certify's summary and an error quote the
    // name as an excerpt (the certificate on stdout carries it whole).
    let mut v: Value = serde_json::from_str(&fixture("rigid-body-major-axis.json")).unwrap();
    v["name"] = Value::from("n".repeat(50_000_000));
    let good = temp_file("huge-name.json", &v.to_string());
    let o = verify(&["certify", good.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", &stderr(&o)[..stderr(&o).len().min(300)]);
    assert!(stderr(&o).contains("(50000000 bytes): stable"), "{}", &stderr(&o)[..stderr(&o).len().min(300)]);
    // the summary carries the certificate's statement and what it does not
    // check (about 1,300 bytes, the name cut to 80 characters in them)
    assert!(o.stderr.len() < 2500, "{} bytes of stderr", o.stderr.len());
    v["noise"] = serde_json::json!([["sigma", 0]]);
    let bad = temp_file("huge-name-bad.json", &v.to_string());
    for args in [vec!["certify", bad.to_str().unwrap()], vec!["simulate", bad.to_str().unwrap()]] {
        let o = verify(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(stderr(&o).contains("$.noise[0]"), "{args:?}: {}", &stderr(&o)[..stderr(&o).len().min(300)]);
        assert!(o.stderr.len() < 4000, "{args:?}: {} bytes of stderr", o.stderr.len());
    }
}

/// `check` on a spec says what it is and what to run, once.
#[test]
fn check_on_a_spec_says_to_certify_first() {
    let spec = fixture_path("rigid-body-major-axis.json");
    let out = verify(&["check", spec.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert!(err.contains("this is a spec, not a certificate") && err.contains("verify certify"), "{err}");
    assert_eq!(err.matches("this is a spec").count(), 1, "printed once: {err}");
    // A file that cannot be read is reported once too, beside a good certificate.
    let cert = fixture_path("rigid-body-major-axis.cert.json");
    let out = verify(&["check", "/nonexistent/cert.json", cert.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert_eq!(err.matches("/nonexistent/cert.json").count(), 1, "{err}");
    assert!(err.contains("1 of 2 file(s) could not be checked"), "{err}");
    assert!(String::from_utf8_lossy(&out.stdout).contains("ok   "), "the good one is still checked");
}

/// The help says what the bare command does; the fixture options belong to it alone.
#[test]
fn help_describes_the_no_argument_run_and_subcommands_do_not_offer_fixtures() {
    let top = String::from_utf8_lossy(&verify(&["--help"]).stdout).to_string();
    assert!(top.contains("With no subcommand") && top.contains("--fixtures"), "{top}");
    for sub in ["certify", "check", "simulate", "sweep", "plot-sweep", "plot-fluid", "schema"] {
        let help = String::from_utf8_lossy(&verify(&[sub, "--help"]).stdout).to_string();
        assert!(!help.contains("--fixtures"), "{sub}: {help}");
    }
}

/// The default final time is clamped to [1, 200], and the run says so; the
/// exceedance lines say "not exceeded" rather than printing null.
#[test]
fn simulate_says_when_the_default_final_time_was_clamped() {
    // Sigma^2 = 0.072 for this fixture (4 sigma^2 / (p^2 - 4 mgl I1), the
    // closed form of tests/it/closed_forms.rs), so T(0.1, 0.001) = ln(100)/0.072
    // = 63.9607 and the default 8 T = 511.685576 is clamped to 200; the
    // level alpha = 0.1 is certified until ln(alpha eps/delta)/Sigma^2 =
    // ln(10)/0.072 = 31.980349.
    let spec = fixture_path("lagrange-top-fluctuating-gravity.json");
    let dir = std::env::temp_dir().join(format!("verify-cli-clamp-{}", std::process::id()));
    let out = simulate(
        &[spec.to_str().unwrap(), "--paths", "20", "--dt", "0.1", "--outputs", "20", "--out", dir.to_str().unwrap()],
        "2",
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("note: t_end = 200 (the default 8 T(eps, delta) = 511.685576"), "{err}");
    assert!(!err.contains("null"), "{err}");
    assert!(err.contains("certified until t = 31.980349"), "{err}");
}
