//! What a new user tripped over: the Bickley jet written with `sech`; `-o -`
//! as standard output (and `-` refused where the output is a directory);
//! the fluid simulation's default end time and its run-time estimate; the
//! compatible noise in the summary of an incompatible spec.

use crate::common;

use common::fixture_path;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// `verify ARGS` run in the folder `cwd`.
fn verify_in(cwd: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_verify")).current_dir(cwd).args(args).output().expect("run verify")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A new empty folder for one test.
fn fresh_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("verify-newcomer-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn fixture_arg(name: &str) -> String {
    fixture_path(name).to_str().unwrap().to_string()
}

/// The Bickley jet `U = sech^2 y` between walls at `±8` with transport
/// noise `a tanh y`, x-period `2 pi / k`, `U` written as `shear_flow`.
fn bickley(shear_flow: &str, period: &str, noise: &str) -> Value {
    json!({"name": "bickley-jet", "fluid": {"model": "incompressible", "x_period": period,
        "y_interval": [-8, 8], "boundary": "walls", "shear_flow": shear_flow,
        "noise": [noise], "ny": 128, "x_modes": 2}})
}

/// Every number of `a` against the same place in `b`: equal to `rel` of
/// their size. Strings must be equal except where `skip` says (the spec's
/// own text, its digest and the statement quoting it). Phase speeds of
/// neutral modes are eigenvalue noise near 0 (about 1e-6 on these grids
/// either way): compared to `1e-5` absolutely; so are residuals, rounding
/// errors of a vanishing quantity (1.3e-23 and 1.4e-23 here), to `1e-15`.
fn same_numbers(a: &Value, b: &Value, at: &str, rel: f64, skip: &dyn Fn(&str) -> bool) {
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            let keys: std::collections::BTreeSet<_> = x.keys().chain(y.keys()).collect();
            for k in keys {
                let path = format!("{at}.{k}");
                match (x.get(k), y.get(k)) {
                    (Some(u), Some(v)) => same_numbers(u, v, &path, rel, skip),
                    _ => assert!(skip(&path), "{path}: present in one certificate only"),
                }
            }
        }
        (Value::Array(x), Value::Array(y)) => {
            assert_eq!(x.len(), y.len(), "{at}: lengths differ");
            for (i, (u, v)) in x.iter().zip(y).enumerate() {
                same_numbers(u, v, &format!("{at}[{i}]"), rel, skip);
            }
        }
        (Value::Number(_), Value::Number(_)) => {
            let (u, v) = (a.as_f64().unwrap(), b.as_f64().unwrap());
            let ok = if at.ends_with("phase_speed") {
                (u - v).abs() <= 1e-5
            } else if at.ends_with("residual") {
                (u - v).abs() <= 1e-15
            } else {
                (u - v).abs() <= rel * u.abs().max(v.abs())
            };
            assert!(ok, "{at}: {u} vs {v}");
        }
        _ => assert!(a == b || skip(at), "{at}: {a} vs {b}"),
    }
}

/// The Bickley jet was written `4/(exp(y) + exp(-y))^2` for want of
/// `sech`. Written `sech(y)^2` it certifies to the same numbers through
/// the CLI: stable at k = 3 (with `Sigma^2` and its verified bound, the
/// per-mode table and the convergence), linearly unstable at k = 1.9 (the
/// growth rate 0.0220919, independent shooting: `tests/it/statements.rs`).
/// The two spellings differ by rounding only (`sech y = 2 / (e^y + e^-y)`
/// exactly), which moves the numbers by about 1e-10 relative (measured
/// 6e-11 on the growth rate): 1e-8 is asked. A third spelling that is a
/// different profile (`sech(y)` alone) must not pass.
#[test]
fn the_bickley_jet_written_with_sech_certifies_as_the_exp_form() {
    let dir = fresh_dir("bickley");
    let certify = |name: &str, spec: &Value| -> Value {
        let path = dir.join(name);
        std::fs::write(&path, spec.to_string()).unwrap();
        let out = verify_in(&dir, &["certify", path.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let skip = |p: &str| {
        p == "$.spec.fluid.shear_flow" || p == "$.spec_sha256" || p == "$.theorem.statement" || p == "$.reason"
    };
    for (period, verdict) in [("2*pi/3", "stable"), ("2*pi/1.9", "linearly_unstable")] {
        let exp = certify("exp.json", &bickley("4/(exp(y) + exp(-y))^2", period, "0.1*tanh(y)"));
        let sech = certify("sech.json", &bickley("sech(y)^2", period, "0.1*tanh(y)"));
        assert_eq!(exp["verdict"], verdict, "{}", exp["reason"]);
        assert_eq!(sech["verdict"], verdict, "{}", sech["reason"]);
        same_numbers(&exp, &sech, "$", 1e-8, &skip);
        assert!(sech["theorem"]["statement"].as_str().unwrap().contains("sech(y)^2"));
        if verdict == "stable" {
            assert!(sech["sigma2"].as_f64().unwrap() > 0.0 && sech["sigma2_upper"].as_f64().is_some());
        } else {
            let rate = sech["instability"]["growth_rate"].as_f64().unwrap();
            assert!((rate / 0.0220919428 - 1.0).abs() < 1e-4, "{rate}");
        }
        // and the certificate checks
        let path = dir.join("sech.cert.json");
        std::fs::write(&path, sech.to_string()).unwrap();
        let out = verify_in(&dir, &["check", path.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    }
    // the perturbed profile sech(y) is another flow: its numbers differ
    let other = certify("other.json", &bickley("sech(y)", "2*pi/3", "0.1*tanh(y)"));
    let exp = certify("exp.json", &bickley("4/(exp(y) + exp(-y))^2", "2*pi/3", "0.1*tanh(y)"));
    let (a, b) = (other["sigma2"].as_f64().unwrap_or(0.0), exp["sigma2"].as_f64().unwrap());
    assert!((a - b).abs() > 1e-3 * b, "{a} {b}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `-o -` wrote a file literally named `-`. Now it is standard output for
/// every single-file output (certify, certify-box, sweep, merge, report,
/// and `--npz` of sweep and merge), byte for byte what the file holds, and
/// no file `-` appears; an output that is a directory (`simulate --out`,
/// `plot-fluid --out`, `plot-sweep --out`, `sweep --plot`, `merge
/// --plot`) refuses `-` with exit status 2, as do the options that read
/// `-o`'s file back (`--resume`, `--plot`, `--npz` of sweep), and two
/// outputs both on `-`.
#[test]
fn dash_is_standard_output_for_files_and_refused_for_directories() {
    let dir = fresh_dir("dash");
    let run = |args: &[&str]| verify_in(&dir, args);
    let major = fixture_arg("rigid-body-major-axis.json");
    let no_dash = || assert!(!dir.join("-").exists(), "a file named '-' was created");
    // (stdout, and the file the same command writes)
    let same_as_file = |args: &[&str], flag: &str, file: &str| {
        let mut to_stdout = args.to_vec();
        to_stdout.extend([flag, "-"]);
        let out = run(&to_stdout);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {}", stderr(&out));
        no_dash();
        let mut to_file = args.to_vec();
        to_file.extend([flag, file]);
        let written = run(&to_file);
        assert_eq!(written.status.code(), Some(0), "{args:?}: {}", stderr(&written));
        let bytes = std::fs::read(dir.join(file)).unwrap();
        assert!(!out.stdout.is_empty(), "{args:?}: nothing on stdout");
        assert!(out.stdout == bytes, "{args:?} {flag} -: stdout differs from the file");
    };
    same_as_file(&["certify", &major], "-o", "cert.json");
    same_as_file(&["certify-box", &major, "--param", "I2=3/2:5/2"], "-o", "box.json");
    let grid = ["--param", "I2=3/2:5/2:3", "--param", "I3=1/2:1:2"];
    let mut sweep = vec!["sweep", major.as_str()];
    sweep.extend(grid);
    same_as_file(&sweep, "-o", "lines.jsonl");
    // --npz - with -o FILE: the archive on stdout
    let mut npz = sweep.clone();
    npz.extend(["-o", "lines.jsonl"]);
    same_as_file(&npz, "--npz", "lines.npz");
    assert!(std::fs::read(dir.join("lines.npz")).unwrap().starts_with(b"PK"), "a ZIP archive");
    let mut merge = vec!["merge", major.as_str()];
    merge.extend(grid);
    merge.extend(["--lines", "lines.jsonl"]);
    same_as_file(&merge, "-o", "merged.jsonl");
    let mut merge_npz = merge.clone();
    merge_npz.extend(["-o", "merged.jsonl"]);
    same_as_file(&merge_npz, "--npz", "merged.npz");
    same_as_file(&["report", "cert.json"], "-o", "report.html");

    // Directories and read-backs refuse it, naming the flag.
    let fluid = fixture_arg("fluids/arnold-boundary-sin.cert.json");
    let refused: [(Vec<&str>, &str); 10] = [
        (vec!["simulate", &major, "--out", "-"], "--out -"),
        (vec!["plot-fluid", &fluid, "--out", "-"], "--out -"),
        (vec!["plot-sweep", "lines.jsonl", "--spec", &major, "--out", "-"], "--out -"),
        ([sweep.clone(), vec!["-o", "x.jsonl", "--plot", "-"]].concat(), "--plot -"),
        ([sweep.clone(), vec!["-o", "-", "--resume"]].concat(), "--resume"),
        ([sweep.clone(), vec!["-o", "-", "--plot", "charts"]].concat(), "--plot"),
        ([sweep.clone(), vec!["-o", "-", "--npz", "x.npz"]].concat(), "--npz"),
        ([merge.clone(), vec!["-o", "-", "--plot", "charts"]].concat(), "--plot"),
        ([merge.clone(), vec!["-o", "-", "--npz", "-"]].concat(), "only one output"),
        ([merge.clone(), vec!["-o", "m.jsonl", "--plot", "-"]].concat(), "--plot -"),
    ];
    for (args, says) in &refused {
        let out = run(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(stderr(&out).contains(says), "{args:?}: {}", stderr(&out));
        assert!(!stderr(&out).contains("panicked"), "{}", stderr(&out));
        assert!(out.stdout.is_empty(), "{args:?}: wrote to stdout before refusing");
        no_dash();
    }
    // `./-` is the way to name a file called '-'
    let out = run(&["certify", &major, "-o", "./-"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(dir.join("-").is_file() && out.stdout.is_empty());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The incompressible channel `U = sin y` with its noise `0.3 cos y, 0.2
/// sin 2y` (the `channel-sin-walls` fixture) simulated at ny = 16.
fn channel() -> spec::FluidSpec {
    spec::parse_fluid_spec(&common::fixture("fluids/channel-sin-walls.json")).unwrap()
}

fn options(ny: usize, paths: usize, t_end: Option<f64>, outputs: usize) -> spec::FluidSimulationOptions {
    spec::FluidSimulationOptions {
        mode: None,
        ny: Some(ny),
        paths: Some(paths),
        dt: 0.01,
        t_end,
        outputs,
        seed: 1,
        force: false,
        threads: rayon::current_num_threads() as f64,
    }
}

/// The default end time was `1/Sigma_k^2` capped at 10: with `1/Sigma_k^2`
/// near 784 the certified `exp(Sigma_k^2 t)` reached 1.013 and the chart
/// was flat. Now it is one growth time `1/Sigma_k^2` (the bound grows by
/// e by definition of that time), at least 1, and 10 when `Sigma_k^2 = 0`.
/// The channel's mode 1 has `1/Sigma_k^2 = 37.5` (certified 0.026663 on
/// the fixture's grid): the old default ended at 10, where the bound is
/// exp(0.27) = 1.31. The rule that shortens an expensive default to the
/// time budget is tested in the spec crate (`default_t_end`).
#[test]
fn the_fluid_simulations_default_end_is_one_growth_time() {
    let run = spec::simulate_fluid(&channel(), &options(16, 20, None, 50), &mut |_| {}).unwrap();
    let growth_time = 1.0 / run.certified;
    assert!(growth_time > 30.0, "{growth_time}");
    // the run ends at the first output time at or after 1/Sigma^2: within
    // one output interval (t_end / 50)
    assert!(run.t_end >= growth_time * (1.0 - 1e-12) && run.t_end <= growth_time * (1.0 + 1.0 / 50.0), "{}", run.t_end);
    let e = std::f64::consts::E;
    let last = *run.bound.last().unwrap();
    assert!(last >= e * (1.0 - 1e-9) && last <= e * (1.0 + 0.03), "{last}");
    // the exact moment stays under the bound, and grows past the old end
    let exact = run.exact.as_ref().unwrap();
    let at_10 = run.times.iter().position(|t| *t >= 10.0).unwrap();
    assert!(exact.last().unwrap() > &exact[at_10]);
    assert!(exact.iter().zip(&run.bound).all(|(x, b)| *x <= b * (1.0 + 1e-9)));

    // Sigma_k^2 = 0 (rayleigh-cos-walls): no time scale, the end is 10
    let quiet = spec::parse_fluid_spec(&common::fixture("fluids/rayleigh-cos-walls.json")).unwrap();
    let run = spec::simulate_fluid(&quiet, &options(16, 10, None, 10), &mut |_| {}).unwrap();
    assert_eq!(run.certified, 0.0);
    assert!((run.t_end - spec::FLUID_SIMULATION_NO_GROWTH_T_END).abs() < 1e-9, "{}", run.t_end);
    // Sigma_k^2 above 1 (noise 3 cos y: 100 times the fixture's 0.3 cos y
    // squared): the end is the floor 1, not 1/Sigma^2 < 1
    let mut loud: Value = serde_json::from_str(&common::fixture("fluids/arnold-boundary-sin.json")).unwrap();
    loud["fluid"]["noise"] = json!(["3*y"]);
    let loud = spec::parse_fluid_spec(&loud.to_string()).unwrap();
    let run = spec::simulate_fluid(&loud, &options(16, 10, None, 10), &mut |_| {}).unwrap();
    assert!(run.certified > 1.0, "{}", run.certified);
    assert!((run.t_end - spec::FLUID_SIMULATION_MIN_T_END).abs() < 1e-9, "{}", run.t_end);
    // not stable: nothing to simulate beside, whatever the end
    let unstable = spec::parse_fluid_spec(&common::fixture("fluids/sin2y-unstable.json")).unwrap();
    let err = spec::simulate_fluid(&unstable, &options(16, 10, None, 10), &mut |_| {}).unwrap_err();
    assert!(matches!(err, spec::FluidSimulationError::NoGrowth { .. }), "{err:?}");
}

/// The estimate said 41 s for a run that took 132 s (a constant rate per
/// flop, blind to the machine, its load and the noise's phases; measured
/// here: 13 s said for 68 s). Now a pilot of the run's own stepping times
/// it. Two runs of a few seconds: the channel's Monte Carlo (600 paths to
/// t = 10) and the compressible fixture's exact moment (stiff: it is most
/// of that run). The estimate must be within a factor 2 of the measured
/// time; a timing outlier on a loaded machine gets one more try (a 3x
/// error in the estimate fails both).
#[test]
fn the_fluid_simulations_time_estimate_is_within_twice_the_run() {
    let compressible = spec::parse_fluid_spec(&common::fixture("fluids/compressible-compatible-noise.json")).unwrap();
    let cases = [(channel(), options(32, 600, Some(10.0), 200)), (compressible, options(16, 2, Some(2.0), 20))];
    for (spec, options) in &cases {
        let ratio = || {
            let run = spec::simulate_fluid(spec, options, &mut |_| {}).unwrap();
            assert!(run.run_seconds > 0.5, "{}: too short to time ({} s)", spec.name, run.run_seconds);
            (run.estimated_seconds / run.run_seconds, run.estimated_seconds, run.run_seconds)
        };
        let within = |r: f64| (0.5..=2.0).contains(&r);
        let first = ratio();
        let (r, estimated, measured) = if within(first.0) { first } else { ratio() };
        eprintln!("{}: estimated {estimated:.2} s, took {measured:.2} s", spec.name);
        assert!(within(r), "{}: estimated {estimated:.2} s, took {measured:.2} s (first try {first:?})", spec.name);
    }
}

/// With incompatible noise, the compatible noise (the isotropy algebra of
/// `mu_e`, `noise.isotropy_basis`) was only in the certificate. The summary
/// prints it as rows to paste as `noise`. For the rigid body at `(1, 0,
/// 0)` it is the rotations about e1 (the basis `[1, 0, 0]`); for the
/// spherical body at `(3, 2, 0)` every `sigma` parallel to `mu_e`
/// (`ad*_sigma mu = mu x sigma = 0`), written by the engine as `[3/2, 1,
/// 0]`. A compatible spec prints no such line.
#[test]
fn the_summary_names_the_compatible_noise() {
    let dir = fresh_dir("isotropy");
    let out = verify_in(&dir, &["certify", &fixture_arg("rigid-body-isotropic-noise.json")]);
    assert_eq!(out.status.code(), Some(0));
    let text = stderr(&out);
    assert!(text.contains("noise_incompatible"), "{text}");
    assert!(text.contains("compatible noise (ad*_sigma mu_e = 0)"), "{text}");
    assert!(text.contains("a = Pi1, Pi2, Pi3; paste rows as noise): [[1, 0, 0]]"), "{text}");
    let tilted = dir.join("tilted.json");
    std::fs::write(
        &tilted,
        r#"{"name": "tilted", "algebra": "so3", "hamiltonian": "(Pi1^2 + Pi2^2 + Pi3^2)/2",
            "equilibrium": [3, 2, 0], "noise": [[0, "1/10", 0]]}"#,
    )
    .unwrap();
    let out = verify_in(&dir, &["certify", tilted.to_str().unwrap()]);
    let text = stderr(&out);
    assert!(text.contains(r#"[["3/2", 1, 0]]"#), "{text}");
    // the rows are what the certificate states, and pasted they are compatible
    let cert: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(cert["noise"]["isotropy_basis"], json!([["3/2", "1", "0"]]));
    std::fs::write(
        &tilted,
        r#"{"name": "tilted", "algebra": "so3", "hamiltonian": "(Pi1^2 + Pi2^2 + Pi3^2)/2",
            "equilibrium": [3, 2, 0], "noise": [["3/2", 1, 0]]}"#,
    )
    .unwrap();
    let out = verify_in(&dir, &["certify", tilted.to_str().unwrap()]);
    let text = stderr(&out);
    assert!(!text.contains("noise_incompatible") && !text.contains("compatible noise ("), "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A Zeitlin spec naming a `.npy` file, read without a folder of its own
/// (as from Python with a dict), said the file was "relative to the
/// spec's folder"; it now says which folder was used. (The Python message
/// that names `base_dir=` is tested in `python/tests/test_base_dir.py`.)
#[test]
fn a_missing_npy_names_the_folder_it_was_read_from() {
    let text = common::fixture("zeitlin/quflow-tilted-n16.json");
    let Err(err) = spec::parse(&text, &spec::Options::relative_to(None)) else {
        panic!("no .npy in the current folder")
    };
    assert_eq!(err.path, "$.zeitlin.equilibrium.npy", "{err}");
    assert!(err.message.contains("the current folder: the spec came as text"), "{err}");
    let elsewhere = fresh_dir("npy");
    let Err(err) = spec::parse(&text, &spec::Options::relative_to(Some(&elsewhere))) else { panic!("no .npy there") };
    assert!(err.message.contains("the spec's folder") && err.message.contains("verify-newcomer"), "{err}");
    // the right folder reads it
    assert!(spec::parse(&text, &spec::Options::default().with_base_dir(&fixture_path("zeitlin"))).is_ok());
    std::fs::remove_dir_all(&elsewhere).unwrap();
}
