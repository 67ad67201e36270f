//! Shared helpers and proptest generators for the workspace tests.
#![allow(dead_code)]

use exact::Rational;
use proptest::prelude::*;
use std::path::PathBuf;

/// Path of a file under `fixtures/`.
pub fn fixture_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..").join("fixtures").join(name)
}

/// Text of a fixture spec.
pub fn fixture(name: &str) -> String {
    std::fs::read_to_string(fixture_path(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Every fixture spec (not certificates), sorted.
pub fn fixture_specs() -> Vec<String> {
    let dir = fixture_path("");
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".json") && !n.ends_with(".cert.json"))
        .collect();
    names.sort();
    names
}

/// `n/d` as an exact rational.
pub fn q(n: i64, d: i64) -> Rational {
    Rational::new(n.into(), d.into())
}

/// A positive rational `k/100` with `k` in `lo..=hi` (so values in `[lo/100, hi/100]`).
pub fn hundredths(lo: i64, hi: i64) -> impl Strategy<Value = Rational> {
    (lo..=hi).prop_map(|k| q(k, 100))
}

/// A rigid-body spec on so3 about the e1 axis with noise sigma e1.
pub fn rigid_body_spec(i: [&Rational; 3], sigma: &Rational) -> String {
    format!(
        r#"{{"name": "rb", "algebra": "so3",
            "parameters": {{"I1": "{}", "I2": "{}", "I3": "{}", "sigma": "{}"}},
            "hamiltonian": "Pi1^2/(2*I1) + Pi2^2/(2*I2) + Pi3^2/(2*I3)",
            "equilibrium": [1, 0, 0], "noise": [["sigma", 0, 0]],
            "stopping": {{"epsilon": 0.1, "delta": 0.001}}}}"#,
        i[0], i[1], i[2], sigma
    )
}

/// A sleeping heavy top on se3 (builtin Casimirs), with an optional first
/// integral `Pi3`.
pub fn heavy_top_spec(i: [&Rational; 3], mgl: &Rational, p: &Rational, sigma: &Rational, with_pi3: bool) -> String {
    format!(
        r#"{{"name": "ht", "algebra": "se3",
            "parameters": {{"I1": "{}", "I2": "{}", "I3": "{}", "mgl": "{}", "p": "{}", "sigma": "{}"}},
            "hamiltonian": "Pi1^2/(2*I1) + Pi2^2/(2*I2) + Pi3^2/(2*I3) + mgl*Gamma3",
            "first_integrals": {},
            "equilibrium": [0, 0, "p", 0, 0, 1], "noise": [[0, 0, "sigma", 0, 0, 0]]}}"#,
        i[0],
        i[1],
        i[2],
        mgl,
        p,
        sigma,
        if with_pi3 { r#"["Pi3"]"# } else { "[]" }
    )
}

/// Relative difference.
pub fn rel(a: f64, b: f64) -> f64 {
    if a == b {
        0.0
    } else {
        (a - b).abs() / a.abs().max(b.abs())
    }
}

/// Exact rational to double.
pub fn f(r: &Rational) -> f64 {
    exact::rational_to_f64(r)
}

/// Whether this is the heavy run: `VERIFY_HEAVY_TESTS=1` in the environment
/// (CI's heavy stage). It is read at run time, not a cargo feature, so the
/// heavy run reuses the test binary `./test.sh` built.
pub fn heavy() -> bool {
    std::env::var_os("VERIFY_HEAVY_TESTS").is_some_and(|v| v == "1")
}

/// Proptest settings with a fixed seed (reproducible runs; the failure
/// persistence file still records any counterexample), `cases` cases, or
/// `heavy` cases in the heavy run ([`heavy`]). `module` is the caller's
/// `module_path!()`: its counterexamples are kept in, and replayed from,
/// `tests/it/proptest-regressions/MODULE.txt`.
pub fn proptest_config(cases: u32, heavy_cases: u32, module: &str) -> ProptestConfig {
    ProptestConfig {
        cases: if heavy() { heavy_cases } else { cases },
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x5EC_CA51),
        // The tests live outside the package's src/, so name the file directly.
        failure_persistence: Some(Box::new(proptest::test_runner::FileFailurePersistence::Direct(Box::leak(
            regressions_file(module).into_boxed_str(),
        )))),
        ..ProptestConfig::default()
    }
}

/// The proptest regressions file of a test module (`it::trust` ->
/// `tests/it/proptest-regressions/trust.txt`).
pub fn regressions_file(module: &str) -> String {
    let name = module.rsplit("::").next().unwrap_or(module);
    format!("{}/../tests/it/proptest-regressions/{name}.txt", env!("CARGO_MANIFEST_DIR"))
}

/// The committed counterexamples are where the property tests read them.
#[test]
fn the_committed_proptest_regressions_are_replayed() {
    for module in ["it::closed_forms", "it::numeric_level", "it::random_systems", "it::trust"] {
        let path = regressions_file(module);
        assert!(std::path::Path::new(&path).is_file(), "{path}");
    }
}

/// The `verify` binary with `args`.
pub fn verify(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_verify")).args(args).output().expect("run verify")
}

/// A file `name` with `contents` in a temporary folder of this process,
/// `tag` keeping the modules' files apart.
pub fn temp_file(tag: &str, name: &str, contents: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("verify-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, contents).unwrap();
    path
}

/// `verify simulate ARGS` with `RAYON_NUM_THREADS=threads`.
pub fn simulate(args: &[&str], threads: &str) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_verify"))
        .arg("simulate")
        .args(args)
        .env("RAYON_NUM_THREADS", threads)
        .output()
        .expect("run verify")
}

/// A process's stderr as text.
pub fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}
