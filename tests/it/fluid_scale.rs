//! Fluid certificates at research resolution: the verified check is banded
//! (`fluid::walls_check`) on walls and periodic grids alike, so ny = 4096
//! with 32 x-modes is accepted and certified; the dense fallback (up to
//! 1023 unknowns) keeps its work limit.
//!
//! The ny = 4096 certifications are heavy (ignored unless asked for: CI's
//! heavy stage runs them); the spec-layer tests always run.

/// `U = y^3 + y/2` on [-1, 1]: `U'' = 6y` vanishes at 0 only, so the
/// Galilean shift `c = -U(0) = 0` is forced and `w = (U + c)/U'' =
/// y^2/6 + 1/12 > 0` (the form `K + M w` is positive, `s = +1`).
fn cubic(ny: usize, boundary: &str) -> String {
    format!(
        r#"{{"name": "cubic-{ny}", "fluid": {{"model": "incompressible", "x_period": "2*pi", "y_interval": [-1, 1],
            "boundary": "{boundary}", "shear_flow": "y^3 + y/2", "noise": ["0.3*sin(y)", "0.1*y"],
            "ny": {ny}, "x_modes": 32}}}}"#
    )
}

#[test]
fn ny_4096_with_32_modes_is_accepted_on_both_boundaries_and_the_dense_fallback_keeps_its_limit() {
    // The banded check is O(ny): the dense work limit applies neither above
    // the dense fallback's 1023 unknowns nor on periodic grids, which have
    // no fallback (fluid::modes::Mode::verify); the banded limits (next
    // test) allow these. (A dense periodic check would be refused here:
    // 32 * 2 * 4096^3 / 3 = 1.5e12 > 1e12 operations.)
    spec::parse_fluid_spec(&cubic(4096, "walls")).expect("walls at ny = 4096 are accepted");
    spec::parse_fluid_spec(&kolmogorov(4096, 32)).expect("periodic at ny = 4096 is accepted");
    spec::parse_fluid_spec(&kolmogorov(1016, 2048)).expect("periodic grids have no dense fallback");
    // Walls at ny = 1024 with 2048 modes: the dense fallback could run on
    // every mode, 2048 * 2 * 1023^3 / 3 = 1.5e12: refused as before.
    let many = cubic(1024, "walls").replace("\"x_modes\": 32", "\"x_modes\": 2048");
    let err = spec::parse_fluid_spec(&many).unwrap_err();
    assert_eq!(err.path, "$.fluid.x_modes", "{err}");
    assert!(err.to_string().contains("dense verified checks"), "{err}");
}

/// `cubic` (walls) or Kolmogorov flow (periodic) with `j` noise fields
/// `0.1 sin(i y)` and `modes` x-modes, of either model.
fn noisy(ny: usize, j: usize, modes: usize, boundary: &str, model: &str) -> String {
    let noise: Vec<String> = (1..=j).map(|i| format!("\"0.1*sin({i}*y)\"")).collect();
    let sound = if model == "compressible" { r#""sound_speed": 2,"# } else { "" };
    // a periodic grid needs periodic data: Kolmogorov flow on [0, 2 pi)
    let (interval, flow) = if boundary == "periodic" { (r#"[0, "2*pi"]"#, "sin(y)") } else { ("[-1, 1]", "y^3 + y/2") };
    format!(
        r#"{{"name": "noisy", "fluid": {{"model": "{model}", {sound} "x_period": "2*pi", "y_interval": {interval},
            "boundary": "{boundary}", "shear_flow": "{flow}", "noise": [{}], "ny": {ny}, "x_modes": {modes}}}}}"#,
        noise.join(", ")
    )
}

#[test]
fn many_noise_fields_on_a_fine_grid_are_refused_with_the_field_named() {
    // The banded check of an incompressible mode factors n (J + 2) rows of
    // bandwidth (J + 2)(p + 1) - 1 (fluid::walls_check::lifted_size; p = 8
    // on walls, 16 on periodic grids): a copy is limited to 2^28 bytes
    // (spec::fluid::MAX_BANDED_BYTES) and x_modes rows (bandwidth + 1)^2 to
    // 1e12 (MAX_BANDED_WORK). Walls at ny = 4096 (4095 unknowns): J = 28
    // gives 122850 rows of width 270, 8 * 122850 * 270 = 2.65e8 bytes, and
    // 4 modes 4 * 122850 * 270^2 = 3.6e10: accepted (certified in 11 s,
    // 3.18 GB). J = 29: 126945 rows of width 279, 2.83e8 bytes.
    let parse = |text: String| spec::parse_fluid_spec(&text);
    parse(noisy(4096, 28, 4, "walls", "incompressible")).expect("28 fields at ny = 4096 fit");
    let err = parse(noisy(4096, 29, 4, "walls", "incompressible")).unwrap_err();
    assert_eq!(err.path, "$.fluid.noise", "{err}");
    assert!(err.to_string().contains("29 noise fields at ny = 4096"), "{err}");
    // 200 modes of J = 28: 200 * 122850 * 270^2 = 1.8e12 operations
    let err = parse(noisy(4096, 28, 200, "walls", "incompressible")).unwrap_err();
    assert_eq!(err.path, "$.fluid.x_modes", "{err}");
    assert!(err.to_string().contains("banded verified checks"), "{err}");
    // Periodic at ny = 4096 (4096 unknowns, p = 16): J = 19 gives 86016
    // rows of width 356, 8 * 86016 * 357 = 2.46e8 bytes; J = 20 90112 rows
    // of width 373, 8 * 90112 * 374 = 2.70e8 > 2^28 = 2.68e8.
    parse(noisy(4096, 19, 4, "periodic", "incompressible")).expect("19 fields at periodic ny = 4096 fit");
    let err = parse(noisy(4096, 20, 4, "periodic", "incompressible")).unwrap_err();
    assert_eq!(err.path, "$.fluid.noise", "{err}");
    // Many fields on a walls grid of at most 1023 unknowns go to the dense
    // check alone where the banded one would cost more
    // (fluid::modes::dense_check_preferred), and the dense work limit
    // applies instead: 256 fields at ny = 16 with 64 modes (banded
    // 64 * 3870 * 2322^2 = 1.3e12) and 100 fields at ny = 1024 (a banded
    // copy of 8 * 104346 * 918 = 7.7e8 bytes) are accepted.
    parse(noisy(16, 256, 64, "walls", "incompressible")).expect("the dense check at ny = 16");
    parse(noisy(1024, 100, 4, "walls", "incompressible")).expect("the dense check at ny = 1024");
    // The compressible model runs the incompressible analysis first (its
    // checks included), so the same limits hold.
    let err = parse(noisy(4096, 64, 32, "walls", "compressible")).unwrap_err();
    assert_eq!(err.path, "$.fluid.noise", "{err}");
    parse(noisy(4096, 28, 4, "walls", "compressible")).expect("28 fields at ny = 4096 fit");
}

#[test]
fn simulating_at_another_ny_keeps_the_work_limits() {
    // `verify simulate --ny` re-runs the analysis at its own grid, so the
    // limits are checked again for that grid. Periodic grids
    // have no dense check: 61 fields at ny = 16 (1008 rows of bandwidth
    // 1070, 8.6e6 bytes a copy) are accepted, but at ny = 512 they make
    // 32256 rows, 8 * 32256 * 1071 = 2.76e8 bytes > 2^28 = 2.68e8; at
    // ny = 256 16128 rows, 1.4e8 bytes, and 8 modes 8 * 16128 * 1071^2 =
    // 1.5e11 operations: within the limits, so that run starts (and stops
    // at once: its progress is cancelled).
    let spec = spec::parse_fluid_spec(&noisy(16, 61, 8, "periodic", "incompressible")).expect("accepted at ny = 16");
    let options = |ny: usize| spec::FluidSimulationOptions {
        mode: None,
        ny: Some(ny),
        paths: Some(2),
        dt: 0.01,
        t_end: None,
        outputs: 10,
        seed: 1,
        force: false,
        threads: 2.0,
    };
    let progress = fluid::analysis::Progress::new();
    progress.cancel();
    let at = |ny: usize| spec::simulate_fluid_with(&spec, &options(ny), &progress, &mut |_| {});
    match at(512) {
        Err(spec::FluidSimulationError::Invalid { field: "ny", message }) => {
            assert!(message.contains("61 noise fields at ny = 512"), "{message}")
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(at(256), Err(spec::FluidSimulationError::Cancelled)), "{:?}", at(256));
}

/// Kolmogorov flow `U = sin y`, periodic on `[0, 2 pi)`, x-period `pi`
/// (`fixtures/fluids/kolmogorov-periodic.json` at another resolution).
fn kolmogorov(ny: usize, modes: usize) -> String {
    format!(
        r#"{{"name": "kolmogorov-{ny}", "fluid": {{"model": "incompressible", "x_period": "pi", "y_interval": [0, "2*pi"],
            "boundary": "periodic", "shear_flow": "sin(y)", "noise": ["0.3*cos(y)"],
            "ny": {ny}, "x_modes": {modes}}}}}"#
    )
}

#[test]
#[ignore = "heavy: run by CI's heavy stage (VERIFY_HEAVY_TESTS=1 ... -- --include-ignored)"]
fn a_periodic_certificate_at_ny_4096_is_verified_and_agrees_with_the_fixture() {
    let fine = spec::certify_fluid(&spec::parse_fluid_spec(&kolmogorov(4096, 32)).unwrap());
    assert_eq!(fine["verdict"], "stable");
    assert_eq!(fine["level"], "verified_float", "{}", fine["checks"]);
    let s = fine["sigma2"].as_f64().unwrap();
    let upper = fine["sigma2_upper"].as_f64().unwrap();
    assert!(upper >= s && upper <= s * (1.0 + 3e-4), "{s} {upper}");
    // Mode 1 (k = 2) sets Sigma^2. Fourier collocation gives
    // 0.012258079762316933 at ny = 256, and the Fourier-Galerkin reference
    // of tests/it/fluid.rs agrees with it to 1e-9: measured, the elements
    // at ny = 4096 differ from it by 1.1e-10 (the Lanczos value at this
    // resolution; 5e-13 at ny = 256).
    assert!((s - 0.012258079762316933).abs() <= 1e-9 * s, "{s}");
    // it sets the overall bound, so it is narrowed from the first rung at
    // 4096 unknowns, 9e-6 (first_rung, tighten_overall_bound;
    // walls_margins shows modes 1 to 3 proving even 3e-7 here)
    let mode1 = &fine["modes"][0];
    assert!(mode1["sigma2_upper"].as_f64().unwrap() <= mode1["sigma2"].as_f64().unwrap() * (1.0 + 1e-5));
    spec::check_certificate_value(&fine).expect("the ny = 4096 certificate re-checks");
}

#[test]
#[ignore = "heavy: run by CI's heavy stage (VERIFY_HEAVY_TESTS=1 ... -- --include-ignored)"]
fn a_walls_certificate_at_ny_4096_is_verified_and_converged() {
    let at =
        |ny: usize| -> serde_json::Value { spec::certify_fluid(&spec::parse_fluid_spec(&cubic(ny, "walls")).unwrap()) };
    let fine = at(4096);
    assert_eq!(fine["verdict"], "stable");
    assert_eq!(fine["level"], "verified_float", "{}", fine["checks"]);
    let s = fine["sigma2"].as_f64().unwrap();
    let upper = fine["sigma2_upper"].as_f64().unwrap();
    // the verified margin of the banded check at this resolution is at most
    // 2.7e-4 relative (constants::VERIFY_*; walls_check docs)
    assert!(upper >= s && upper <= s * (1.0 + 3e-4) + 1e-12, "{s} {upper}");
    // Converged: the Lanczos value at ny = 1024 (where the dense check can
    // still run) agrees to 1e-8; the spectral elements converge much
    // faster than that on this smooth profile.
    let coarse = at(1024);
    let s1024 = coarse["sigma2"].as_f64().unwrap();
    assert!((s - s1024).abs() <= 1e-8 * s, "{s} vs {s1024}");
    // and the certificate re-checks (verify check re-derives every mode)
    spec::check_certificate_value(&fine).expect("the ny = 4096 certificate re-checks");
}

/// `U = sin y` between walls at 0 and pi with the fixture's two noise
/// fields (`fixtures/fluids/channel-sin-walls.json`): `U''` vanishes at both
/// walls, `c = 0` is forced and `w = -1`, so the form is `-(K + M w)`
/// (`s = -1`, Arnold's second theorem). At ny = 4096 the banded check's own
/// ladder (up to `8.1e-3` relative) proves nothing for some modes (measured
/// with `walls_margins`: modes 21, 22, 26 and 28 of 32; the first 22 modes
/// are certified here; at ny = 2048 every mode proves a rung, hence
/// ny = 4096); they are tried on the ladder continued (`Sigma^2_k` times
/// `1.243`, then `8.29`) and then at the largest bound the other modes
/// proved (`fluid::analysis::prove_remaining_modes`), which is all the
/// certificate's claim about `max_k Sigma^2_k` needs.
#[test]
#[ignore = "heavy: run by CI's heavy stage (VERIFY_HEAVY_TESTS=1 ... -- --include-ignored)"]
fn an_arnold_second_theorem_channel_at_ny_4096_is_verified_through_wider_bounds() {
    let text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../fixtures/fluids/channel-sin-walls.json"))
            .unwrap()
            .replace("\"ny\": 1024", "\"ny\": 4096")
            .replace("\"x_modes\": 32", "\"x_modes\": 22")
            .replace("\"convergence_from\": 16", "\"convergence_from\": 2048");
    let spec = spec::parse_fluid_spec(&text).unwrap();
    assert_eq!((spec.problem.ny, spec.problem.x_modes), (4096, 22));
    let cert = spec::certify_fluid(&spec);
    assert_eq!(cert["verdict"], "stable", "{}", cert["reason"]);
    assert_eq!(cert["level"], "verified_float", "{}", cert["checks"]);
    let s = cert["sigma2"].as_f64().unwrap();
    let upper = cert["sigma2_upper"].as_f64().unwrap();
    // Sigma^2 is mode 1's: 0.0266631236686 in docs/fluids.md's convergence
    // table (ny = 32 to 256), which the independent sine-Galerkin
    // computation of `sigma2_matches_an_independent_sine_galerkin_computation_and_converges`
    // confirms to 1e-9; the ladder proves mode 1 within 8.1e-3.
    assert!((s - 0.0266631236686).abs() <= 1e-9, "{s}");
    assert!(upper >= s && upper <= s * (1.0 + 8.1e-3) + 1e-12, "{s} {upper}");
    let modes = cert["modes"].as_array().unwrap();
    // every mode has a proved bound; the loose ones (beyond the ladder's
    // 8.1e-3, with its slack) carry a continued rung or the overall bound,
    // and lie far below the overall bound
    let loose: Vec<u64> = modes
        .iter()
        .filter(|m| m["sigma2_upper"].as_f64().unwrap() > m["sigma2"].as_f64().unwrap() * 1.01)
        .map(|m| m["m"].as_u64().unwrap())
        .collect();
    assert!(!loose.is_empty(), "every mode proved on the ladder: the continued rungs are not exercised");
    for m in modes {
        let (sk, uk) = (m["sigma2"].as_f64().unwrap(), m["sigma2_upper"].as_f64().unwrap());
        assert!(sk <= uk && uk <= upper, "{m}");
    }
    let (m5, m6) = (0.243, 7.29);
    for m in &loose {
        let (sk, uk) = (
            modes[*m as usize - 1]["sigma2"].as_f64().unwrap(),
            modes[*m as usize - 1]["sigma2_upper"].as_f64().unwrap(),
        );
        assert!(sk < 0.1 * upper, "mode {m}: {sk} against {upper}");
        let on_a_rung = [sk * (1.0 + m5), sk * (1.0 + m6), upper].iter().any(|b| (uk - b).abs() <= 1e-12 * b);
        assert!(on_a_rung, "mode {m}: {uk} is neither a continued rung of {sk} nor {upper}");
    }
    // the certificate re-checks, and a loose bound lowered below the mode's
    // own Sigma^2_k is not proved
    spec::check_certificate_value(&cert).expect("the ny = 2048 certificate re-checks");
    let mut forged = cert.clone();
    let i = loose[0] as usize - 1;
    let sk = forged["modes"][i]["sigma2"].as_f64().unwrap();
    forged["modes"][i]["sigma2_upper"] = serde_json::json!(sk * 0.99);
    match spec::check_certificate_value(&forged) {
        Err(spec::CheckError::Failed { path, message }) => {
            assert_eq!(path, format!("$.modes[{i}].sigma2_upper"), "{message}")
        }
        other => panic!("a bound below Sigma^2_k was accepted: {other:?}"),
    }
}
