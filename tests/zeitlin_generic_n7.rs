//! The Zeitlin model at N = 7 through the generic finite-dimensional
//! engine: su(7), dimension 48, by the construction of
//! `tests/zeitlin_generic_n4.rs` (shared in `tests/common/su_n.rs`), with
//! the Casimirs `tr W^2` to `tr W^7` (real part for even `k`, imaginary for
//! odd) and the momentum `J`, given through the library API
//! (`su_n::Route::Library`) as at N = 6.
//!
//! What differs from N = 6:
//! * The polynomials are larger: `tr W^2` to `tr W^7` have 63, 448, 3171,
//!   21714, 147483 and 968160 terms. Building them takes 41 s (release),
//!   `casimir::System::new`'s exact checks (every Casimir against every
//!   coordinate, `{J, h} = 0`) 46 s more, so every system costs about 90 s;
//!   the peak memory of one test was 2.4 GB (the perturbations), 1.9 GB for
//!   the others.
//! * Diagonals 1 to 4 of the Laplacian are irrational, and their energy
//!   blocks rounded.
//! * Every test but the Laplacian's runs with `--features
//!   very-heavy-tests` (release), which CI does not run: the file would add
//!   some 8 to 9 minutes to CI's heavy stage with both cores free, and took
//!   17 minutes beside another job. Run it by hand with `cargo test
//!   --release -p verify --features very-heavy-tests --test
//!   zeitlin_generic_n7`. Measured in release, one test at a time, on the 2-core
//!   machine with another job running: the monotone state 318 s (the system
//!   88 s, `generator::analyse` 218 s, `analyse_numeric` 6 s), the
//!   non-monotone state 292 s (exact level 180 s), the polynomials 84 s, the
//!   perturbations 269 s (three systems). All five at once (`cargo test`'s
//!   two threads, the other job holding about a core) took 1047 s, the
//!   monotone state 636 s of it.
//! * N = 8 (dimension 63, `tr W^8`) was not tried: the exact level alone
//!   takes over 3 minutes here.

#[path = "common/su_n.rs"]
mod su_n;

#[cfg(feature = "very-heavy-tests")]
use su_n::{degree_two_noise, fifths, Route};

const N: usize = 7;

/// A strictly monotone profile, not equally spaced: `omega = (-1, -3/5,
/// -2/5, 0, 1/5, 4/5, 1)`, trace zero.
#[cfg(feature = "very-heavy-tests")]
fn monotone() -> Vec<exact::Rational> {
    fifths(&[-5, -3, -2, 0, 1, 4, 5])
}

/// The block formula is the Laplacian's definition and its spectrum is
/// `-l(l+1)`; at N = 7 diagonals 1 to 4 are irrational.
#[test]
fn su7_laplacian_blocks_match_the_spin_matrix_definition() {
    su_n::check_laplacian_blocks(N);
    // The products under the roots, `j(N-j)(j+m)(N-j-m)` for `j = 1..N-m-1`
    // (by hand): diagonal 1 has 1*6*2*5 = 60, diagonal 2 1*6*3*4 = 72,
    // diagonal 3 1*6*4*3 = 72, diagonal 4 1*6*5*2 = 60 (not squares);
    // diagonal 5 has only 1*6*6*1 = 36, diagonal 6 no off-diagonal entry,
    // diagonal 0 `j(N-j)` squared.
    assert_eq!(su_n::irrational_diagonals(N), vec![1, 2, 3, 4]);
}

/// The system's polynomials are the model's functionals
/// (`su_n::check_spec_polynomials`). Tolerance 1e-13 relative, as at N = 4
/// to 6: `cond(Delta) = 42/2 = 21` (eigenvalues `-l(l+1)`, `l = 1..6`), and
/// `tr W^7` sums about 10^6 terms; the differences seen were 3.3e-14 at
/// most. 84 s in release.
#[cfg(feature = "very-heavy-tests")]
#[test]
fn su7_polynomials_are_the_models_functionals() {
    su_n::check_spec_polynomials(&monotone(), &degree_two_noise(N), 1e-13, Route::Library);
}

/// The monotone state (`su_n::check_monotone`, the assertions of N = 4 to
/// 6 on the exact level's analysis): both `stable`, the infimum 0
/// approached by both, and at the Zeitlin pipeline's `(eps, beta)` the
/// generic engine's exact `P`, `Q` give the Zeitlin `lambda_max` of blocks
/// `m = 1..6`. Tolerance 1e-9 relative, as at N = 4 (the Zeitlin bracket's
/// width, `blocks[].residual`, 7.6e-11 at most here; the differences seen,
/// relative to the Zeitlin `Sigma^2` 4.36e-6, were 5.6e-11, 1.2e-11,
/// 4.3e-12, 2.1e-13, 5.8e-12 and 0 on blocks 1 to 6). 318 s in release.
#[cfg(feature = "very-heavy-tests")]
#[test]
fn su7_monotone_state_agrees_with_the_generic_engine() {
    let report = su_n::check_monotone(&monotone(), &degree_two_noise(N), 1e-9, Route::Library);
    println!("su(7) monotone: {report:#?}");
}

/// A state that is not monotone, `omega = (-1, 0, 1, 1/5, 4/5, -3/5,
/// -2/5)`: no definite form and the spectrum on the imaginary axis in both
/// engines. (Of the 720 orderings of the monotone state's values with
/// `omega_0 = -1`, the Zeitlin pipeline found 9 `inconclusive`, 1 `stable`
/// and 710 `linearly_unstable`, in both of its families, when this test was
/// written.) 292 s in release.
#[cfg(feature = "very-heavy-tests")]
#[test]
fn su7_non_monotone_state_is_inconclusive_in_both() {
    su_n::check_non_monotone(&fifths(&[-5, 0, 5, 1, 4, -3, -2]), &degree_two_noise(N), Route::Library);
}

/// The perturbations that must fail (`su_n::check_perturbations_fail`): a
/// coupling of 2^-60 between `mu0` and the first Cartan coordinate `mu42`
/// gives `not_an_equilibrium`, a change of 2^-60 on the real part of
/// diagonal 1 alone a system refused by `System::new` (`{J, h} != 0`).
/// 269 s in release (three systems).
#[cfg(feature = "very-heavy-tests")]
#[test]
fn su7_perturbing_the_rounded_energy_off_its_blocks_fails() {
    su_n::check_perturbations_fail(&monotone(), &degree_two_noise(N), Route::Library);
}
