//! Zeitlin specs through the contract and the `verify` binary: every
//! verdict path, bad input (exit 2, the JSON path named), tampered
//! certificates (exit 1), determinism and scale invariance.

use crate::common;
use serde_json::Value;
use zeitlin::analysis::{analyse, ZeitlinProblem, ZeitlinSettings};
use zeitlin::zonal::quantise;

fn temp_file(name: &str, contents: &str) -> std::path::PathBuf {
    common::temp_file("zeitlin-cli", name, contents)
}

use common::{stderr, verify};

/// A small valid spec (the monotone profile at N = 16), edited by `edit`.
fn spec_with(edit: impl FnOnce(&mut Value)) -> Value {
    let mut v: Value = serde_json::from_str(
        r#"{"name": "t", "parameters": {"a": 0.1},
            "zeitlin": {"N": 16, "equilibrium": "z + 0.3*z^3", "noise": ["a*z^2"]},
            "stopping": {"epsilon": 0.1, "delta": 0.001}}"#,
    )
    .unwrap();
    edit(&mut v);
    v
}

fn certify(v: &Value) -> Value {
    spec::certify_zeitlin(&spec::zeitlin_spec_from_value(v.clone()).expect("valid spec"))
}

#[test]
fn every_verdict_path_and_the_library_agree() {
    let stable = certify(&spec_with(|_| {}));
    assert_eq!(stable["verdict"], "stable");
    assert_eq!(stable["level"], "exact_structure");
    assert_eq!(stable["sigma2"], 0.0);
    assert_eq!(stable["form"]["energy_coefficient"], 0.0);
    assert_eq!(stable["stopping"]["T"], "infinity");
    assert_eq!(stable["model"]["dimension"], 255);

    // The paper's family only: energy forced, Sigma^2 > 0 with a proved
    // upper bound, the same values as the library on the same profile
    // written as a closure (the spec's expression parser and quantisation
    // against Rust code).
    let energy = certify(&spec_with(|v| v["settings"] = serde_json::json!({"casimir_momentum": false})));
    assert_eq!(energy["verdict"], "stable");
    assert_eq!(energy["level"], "verified_float");
    let n = 16;
    let problem = ZeitlinProblem {
        n,
        omega: quantise(n, |z| z + 0.3 * z * z * z).diagonal,
        noise: vec![quantise(n, |z| 0.1 * z * z).diagonal],
    };
    let lib = analyse(&problem, &ZeitlinSettings { casimir_momentum: false, ..Default::default() }).unwrap();
    let s = energy["sigma2"].as_f64().unwrap();
    assert!(s > 0.0 && (s - lib.sigma2.unwrap()).abs() <= 1e-12 * s, "{s} vs {:?}", lib.sigma2);
    assert_eq!(energy["blocks"].as_array().unwrap().len(), n - 1);
    // The bound is above the estimate, by the stated 1e-8 raise plus the
    // verification margin (at most 1e-2 by construction; 1e-10 here).
    let upper = energy["sigma2_upper"].as_f64().unwrap();
    assert_eq!(upper, lib.sigma2_upper.unwrap());
    assert!(upper > s && upper <= s * (1.0 + 1e-7), "{upper} vs {s}");
    assert!(energy["stopping"]["bound"].as_str().unwrap().contains("sigma2_upper (proved)"));
    // T is computed from the proved bound: T = ln(epsilon/delta)/Sigma^2.
    let t = energy["stopping"]["T"].as_f64().unwrap();
    let (epsilon, delta) =
        (energy["stopping"]["epsilon"].as_f64().unwrap(), energy["stopping"]["delta"].as_f64().unwrap());
    assert!((t - (epsilon / delta).ln() / upper).abs() <= 1e-12 * t, "T {t}");

    // A Gaussian jet: linearly unstable; the reason states the rate in the
    // user's units (it once printed the rate of the normalised problem).
    let jet = certify(&spec_with(|v| {
        v["zeitlin"]["N"] = 24.into();
        v["zeitlin"]["equilibrium"] = "3*exp(-(z/0.3)^2)".into();
    }));
    assert_eq!(jet["verdict"], "linearly_unstable");
    let rate = jet["growth_rate"].as_f64().unwrap();
    let problem = ZeitlinProblem {
        n: 24,
        omega: quantise(24, |z| 3.0 * (-(z / 0.3f64).powi(2)).exp()).diagonal,
        noise: vec![quantise(24, |z| 0.1 * z * z).diagonal],
    };
    let lib = analyse(&problem, &ZeitlinSettings::default()).unwrap();
    assert!((rate - lib.growth_rate.unwrap()).abs() <= 1e-12 * rate);
    assert!(jet["reason"].as_str().unwrap().contains(&format!("{rate:.6e}")), "{}", jet["reason"]);
    assert!(jet.get("sigma2").is_none() && jet.get("stopping").is_none());

    // P_2: not monotone, no definite form, spectrum on the axis.
    let p2 = certify(&spec_with(|v| v["zeitlin"]["equilibrium"] = "1.5*z^2 - 0.5".into()));
    assert_eq!(p2["verdict"], "inconclusive");
    assert_eq!(p2["level"], "none");
    assert!(p2.get("sigma2").is_none());

    // Above settings.energy_search_max_n the energy family is not searched:
    // inconclusive, and the reason says why (the monotone profile with the
    // Casimir–momentum form disallowed, which is definite at N = 16).
    let capped = certify(&spec_with(|v| {
        v["settings"] = serde_json::json!({"casimir_momentum": false, "energy_search_max_n": 8})
    }));
    assert_eq!(capped["verdict"], "inconclusive");
    assert!(capped["reason"].as_str().unwrap().contains("energy_search_max_n"), "{}", capped["reason"]);

    // Each re-checks.
    for c in [&stable, &energy, &jet, &p2, &capped] {
        let report = spec::check_certificate_value(c).unwrap_or_else(|e| panic!("{e}: {c}"));
        assert_eq!(report.verdict.as_str(), c["verdict"].as_str().unwrap());
    }
}

#[test]
fn scaling_the_equilibrium_or_the_noise_moves_only_the_units() {
    // omega -> k omega leaves Sigma^2 (a rate set by the noise) unchanged;
    // noise -> k noise multiplies it by k^2 (docs/zeitlin.md).
    let base = certify(&spec_with(|v| v["settings"] = serde_json::json!({"casimir_momentum": false})));
    let s0 = base["sigma2"].as_f64().unwrap();
    for k in ["1e-300", "1e-7", "1e7", "1e300"] {
        let c = certify(&spec_with(|v| {
            v["settings"] = serde_json::json!({"casimir_momentum": false});
            v["zeitlin"]["equilibrium"] = format!("{k}*(z + 0.3*z^3)").into();
        }));
        let s = c["sigma2"].as_f64().unwrap();
        assert!((s - s0).abs() <= 1e-6 * s0, "omega x {k}: {s} vs {s0}");
        let c = certify(&spec_with(|v| {
            v["settings"] = serde_json::json!({"casimir_momentum": false});
            v["parameters"]["a"] = format!("0.1*{k}").into();
        }));
        let kf: f64 = k.parse().unwrap();
        match c["sigma2"].as_f64() {
            Some(s) => assert!((s - s0 * kf * kf).abs() <= 1e-6 * s0 * kf * kf, "noise x {k}: {s}"),
            // k^2 Sigma^2 beyond the range of doubles: never "stable".
            None => assert_eq!(c["verdict"], "inconclusive", "noise x {k}"),
        }
    }
}

#[test]
fn bad_input_names_the_field() {
    let cases: Vec<(Value, &str, &str)> = vec![
        (spec_with(|v| v["zeitlin"]["N"] = 1.into()), "$.zeitlin.N", "between 2 and 4096"),
        (spec_with(|v| v["zeitlin"]["N"] = 5000.into()), "$.zeitlin.N", "between 2 and 4096"),
        (spec_with(|v| v["zeitlin"]["N"] = "16".into()), "$.zeitlin.N", "positive integer"),
        (spec_with(|v| v["zeitlin"]["equilibrium"] = "log(z)".into()), "$.zeitlin.equilibrium", "unknown function"),
        (spec_with(|v| v["zeitlin"]["equilibrium"] = "1/z".into()), "$.zeitlin.equilibrium", "not finite at z = 0"),
        (spec_with(|v| v["zeitlin"]["equilibrium"] = "sqrt(z)".into()), "$.zeitlin.equilibrium", "not finite"),
        (spec_with(|v| v["zeitlin"]["noise"][0] = "y".into()), "$.zeitlin.noise[0]", "unknown symbol 'y'"),
        (spec_with(|v| v["zeitlin"]["noise"] = Value::Null), "$.zeitlin.noise", ""),
        (
            spec_with(|v| {
                v["zeitlin"].as_object_mut().unwrap().remove("noise");
            }),
            "$.zeitlin.noise",
            "required field is missing",
        ),
        (spec_with(|v| v["zeitlin"]["extra"] = 1.into()), "$.zeitlin.extra", "unknown field"),
        (spec_with(|v| v["parameters"]["z"] = 1.into()), "$.parameters.z", "not a valid parameter name"),
        (spec_with(|v| v["settings"] = serde_json::json!({"tolerance": 0})), "$.settings.tolerance", "between"),
        (
            spec_with(|v| v["settings"] = serde_json::json!({"instability_max_n": 100000})),
            "$.settings.instability_max_n",
            "between",
        ),
        (
            spec_with(|v| v["settings"] = serde_json::json!({"energy_search_max_n": 1})),
            "$.settings.energy_search_max_n",
            "between",
        ),
        (spec_with(|v| v["zeitlin"]["equilibrium"] = "1e308*exp(50*z)".into()), "$.zeitlin.equilibrium", ""),
        (spec_with(|v| v["name"] = "".into()), "$.name", "empty"),
    ];
    for (v, path, words) in cases {
        let e = spec::zeitlin_spec_from_value(v.clone()).expect_err(&v.to_string());
        assert_eq!(e.path, path, "{e}");
        assert!(e.message.contains(words), "{e}");
        // Through the binary: exit 2, the path in the message.
        let file = temp_file("bad.json", &v.to_string());
        let out = verify(&["certify", file.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
        assert!(stderr(&out).contains(path), "{}", stderr(&out));
    }
}

#[test]
fn the_cli_certifies_and_checks_and_refuses_tampering() {
    let v = spec_with(|v| v["settings"] = serde_json::json!({"casimir_momentum": false}));
    let spec_file = temp_file("energy.json", &v.to_string());
    let cert_file = spec_file.with_file_name("energy.cert.json");
    let out = verify(&["certify", spec_file.to_str().unwrap(), "-o", cert_file.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(stderr(&out).contains("stable (verified_float)"), "{}", stderr(&out));
    let first = std::fs::read_to_string(&cert_file).unwrap();
    // Two runs on one file give the same certificate.
    let out = verify(&["certify", spec_file.to_str().unwrap(), "-o", cert_file.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(std::fs::read_to_string(&cert_file).unwrap(), first);
    let out = verify(&["check", cert_file.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    // check on the spec itself: bad input with advice.
    let out = verify(&["check", spec_file.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("this is a spec"), "{}", stderr(&out));

    // A sweep over the noise amplitude: Sigma^2 scales as a^2.
    let out = verify(&["sweep", spec_file.to_str().unwrap(), "--param", "a=1/10:1:2"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let lines: Vec<Value> =
        String::from_utf8_lossy(&out.stdout).lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    let s: Vec<f64> = lines.iter().map(|l| l["sigma2"].as_f64().unwrap()).collect();
    assert_eq!(s.len(), 2);
    assert!((s[1] / s[0] - 100.0).abs() < 1e-6, "{s:?}");

    let cert: Value = serde_json::from_str(&first).unwrap();
    let tampered: Vec<(&str, Value)> = vec![
        ("$.sigma2", {
            let mut c = cert.clone();
            c["sigma2"] = (c["sigma2"].as_f64().unwrap() * (1.0 - 1e-7)).into();
            c
        }),
        ("$.sigma2_upper", {
            let mut c = cert.clone();
            c["sigma2_upper"] = (c["sigma2_upper"].as_f64().unwrap() * (1.0 - 1e-7)).into();
            c
        }),
        ("$.blocks[3].lambda_max", {
            let mut c = cert.clone();
            c["blocks"][3]["lambda_max"] = (c["blocks"][3]["lambda_max"].as_f64().unwrap() * (1.0 + 1e-7)).into();
            c
        }),
        ("$.verdict", {
            let mut c = cert.clone();
            c["verdict"] = "linearly_unstable".into();
            c
        }),
        ("$.spec_sha256", {
            let mut c = cert.clone();
            c["spec"]["zeitlin"]["equilibrium"] = "z + 0.31*z^3".into();
            c
        }),
        ("$.form.momentum_coefficient", {
            let mut c = cert.clone();
            c["form"]["momentum_coefficient"] = (c["form"]["momentum_coefficient"].as_f64().unwrap() * 1.001).into();
            c
        }),
    ];
    for (path, c) in tampered {
        let file = temp_file("tampered.json", &c.to_string());
        let out = verify(&["check", file.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(1), "{path}: {}", stderr(&out));
        assert!(stderr(&out).contains(path), "{path}: {}", stderr(&out));
    }
}

/// `verify simulate` on Zeitlin specs: the block's exact second moment
/// under the certificate's proved bound, the Monte Carlo beside it, the
/// outputs written, times per qtime = t / hbar; states with nothing to set
/// a simulation beside, and flags that mean nothing here, refused with
/// exit 2 and named.
#[test]
fn simulate_runs_a_block_beside_the_certified_bound() {
    // Noise 3 z^2: the energy–Casimir form (casimir_momentum false) with a
    // Sigma^2 of about 4e-4.
    let spec = spec_with(|v| {
        v["parameters"]["a"] = 3.0.into();
        v["zeitlin"]["N"] = 8.into();
        v["settings"] = serde_json::json!({"casimir_momentum": false});
    });
    let file = temp_file("sim.json", &spec.to_string());
    let out_dir = file.parent().unwrap().join("sim-out");
    let out = verify(&[
        "simulate",
        file.to_str().unwrap(),
        "--paths",
        "400",
        "--t-end",
        "2",
        "--dt",
        "0.01",
        "--outputs",
        "20",
        "--out",
        out_dir.to_str().unwrap(),
        "--npz",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let cert = certify(&spec);
    // One report, named by the block: t-mM.json.
    let reports: Vec<_> = std::fs::read_dir(&out_dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    assert_eq!(reports.len(), 1, "{reports:?}");
    let report: Value = serde_json::from_str(&std::fs::read_to_string(&reports[0]).unwrap()).unwrap();
    assert_eq!(report["kind"], "zeitlin-simulation");
    let m = report["block"].as_u64().unwrap();
    // The block is the certificate's largest lambda_max, and it is Sigma^2.
    let blocks = cert["blocks"].as_array().unwrap();
    let largest =
        blocks.iter().max_by(|a, b| a["lambda_max"].as_f64().partial_cmp(&b["lambda_max"].as_f64()).unwrap()).unwrap();
    assert_eq!(largest["m"].as_u64().unwrap(), m);
    assert!(
        (report["initial_rate"].as_f64().unwrap() - cert["sigma2"].as_f64().unwrap()).abs()
            <= 1e-8 * cert["sigma2"].as_f64().unwrap()
    );
    let floats = |k: &str| -> Vec<f64> { report[k].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect() };
    let (times, qtimes, exact, bound, mean, se) = (
        floats("times"),
        floats("times_qtime"),
        floats("exact"),
        floats("certified_bound"),
        floats("monte_carlo_mean"),
        floats("monte_carlo_std_error"),
    );
    let hbar = 2.0 / 63.0f64.sqrt(); // N = 8
    let upper = cert["sigma2_upper"].as_f64().unwrap();
    for i in 0..times.len() {
        assert!((qtimes[i] - times[i] / hbar).abs() <= 1e-12 * qtimes[i].max(1.0));
        assert!((bound[i] - (upper * times[i]).exp()).abs() <= 1e-12 * bound[i]);
        assert!(exact[i] <= bound[i] * (1.0 + 1e-6), "t {}: {} > {}", times[i], exact[i], bound[i]);
        assert!(
            (mean[i] - exact[i]).abs() <= 4.0 * se[i] + 1e-3 * exact[i],
            "t {}: {} +- {} vs {}",
            times[i],
            mean[i],
            se[i],
            exact[i]
        );
    }
    // The nonlinear model (a tenth of the paths, on the same increments)
    // beside the linear exact moment, with its Casimirs kept to rounding.
    let nonlinear = &report["nonlinear"];
    assert_eq!(nonlinear["paths"], 40);
    assert_eq!(nonlinear["delta"], 1e-6);
    let nl: Vec<f64> = nonlinear["mean"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    let nl_se: Vec<f64> = nonlinear["std_error"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    assert_eq!(nl.len(), times.len());
    assert!((nl[0] - 1.0).abs() < 1e-9, "{}", nl[0]);
    for i in 0..times.len() {
        assert!(
            (nl[i] - exact[i]).abs() <= 4.0 * nl_se[i] + 1e-3 * exact[i],
            "t {}: {} +- {} vs {}",
            times[i],
            nl[i],
            nl_se[i],
            exact[i]
        );
    }
    assert!(nonlinear["casimir_drift"].as_f64().unwrap() < 1e-12);
    let stem = format!("t-m{m}");
    for ext in [".csv", ".npz", "-growth.svg", "-growth.png"] {
        assert!(out_dir.join(format!("{stem}{ext}")).exists(), "{stem}{ext}");
    }
    // Nothing to compare: a linearly unstable state, and one zonal in no frame.
    let jet = temp_file("jet.json", &std::fs::read_to_string(common::fixture_path("zeitlin/jet-n64.json")).unwrap());
    let out = verify(&["simulate", jet.to_str().unwrap(), "--out", out_dir.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("a simulation is set beside a stable certificate's conserved form"),
        "{}",
        stderr(&out)
    );
    let rh = common::fixture_path("zeitlin/rossby-haurwitz-l2-n7.json");
    let out = verify(&["simulate", rh.to_str().unwrap(), "--out", out_dir.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("only states zonal in some frame are simulated"), "{}", stderr(&out));
    // A noise at 1e150: Sigma^2 near 1e295, and exp(Sigma^2 t) is no double:
    // refused, not drawn as a chart of infinities.
    let huge = spec_with(|v| {
        v["parameters"]["a"] = 1e150.into();
        v["settings"] = serde_json::json!({"casimir_momentum": false});
    });
    let huge = temp_file("huge.json", &huge.to_string());
    let out = verify(&[
        "simulate",
        huge.to_str().unwrap(),
        "--t-end",
        "0.1",
        "--paths",
        "10",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("is beyond the doubles: lower t_end"), "{}", stderr(&out));
    // Flags and options named.
    for (args, named) in [
        (vec!["--shard", "0/2"], "--shard/--merge"),
        (vec!["--observable", "x"], "--observable"),
        (vec!["--ny", "8"], "--ny"),
        (vec!["--epsilon", "0.1"], "--epsilon"),
        (vec!["--delta", "2"], "--delta: the nonlinear start's |dW_0|_P^2 must be in [1e-280, 1]"),
        (vec!["--delta", "1e-320"], "--delta: the nonlinear start's |dW_0|_P^2 must be in [1e-280, 1]"),
        (vec!["--mode", "8"], "--mode: need 1 <= block <= N - 1 = 7, got 8"),
        (vec!["--dt", "0"], "--dt: must be positive"),
        (vec!["--paths", "1"], "--paths: need 2 to"),
        (vec!["--t-end", "1e9", "--dt", "1e-3"], "--t-end/--dt"),
    ] {
        let mut all = vec!["simulate", file.to_str().unwrap(), "--out", out_dir.to_str().unwrap()];
        all.extend(args.iter());
        let out = verify(&all);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(stderr(&out).contains(named), "{args:?}: {}", stderr(&out));
    }
}
