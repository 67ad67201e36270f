//! Fluid certificates at research resolution: the walls check is banded
//! (`fluid::walls_check`), so ny = 4096 with 32 x-modes is accepted and
//! certified; the dense check (periodic grids) keeps its work limit.
//!
//! The ny = 4096 certification runs with `--features heavy-tests` (CI, in
//! release mode: about 15 s there); the spec-layer tests always run.

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
fn walls_at_ny_4096_with_32_modes_are_accepted_and_periodic_ones_are_refused() {
    // Walls: the banded check is O(ny), no work limit applies.
    spec::parse_fluid_spec(&cubic(4096, "walls")).expect("walls at ny = 4096 are accepted");
    // Periodic: the dense check, 32 * 2 * 4096^3 / 3 = 1.5e12 > 1e12 operations.
    let err = spec::parse_fluid_spec(&cubic(4096, "periodic")).unwrap_err();
    assert_eq!(err.path, "$.fluid.x_modes", "{err}");
    assert!(err.to_string().contains("dense verified checks"), "{err}");
    // Walls at ny = 1024 with 2048 modes: the dense fallback could run on
    // every mode, 2048 * 2 * 1023^3 / 3 = 1.5e12: refused as before.
    let many = cubic(1024, "walls").replace("\"x_modes\": 32", "\"x_modes\": 2048");
    assert_eq!(spec::parse_fluid_spec(&many).unwrap_err().path, "$.fluid.x_modes");
}

#[cfg(feature = "heavy-tests")]
#[test]
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
    spec::check_fluid_certificate(&fine).expect("the ny = 4096 certificate re-checks");
}
