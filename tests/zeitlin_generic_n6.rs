//! The Zeitlin model at N = 6 through the generic finite-dimensional
//! engine: su(6), dimension 35, by the construction of
//! `tests/zeitlin_generic_n4.rs` (shared in `tests/common/su_n.rs`), with
//! the Casimirs `tr W^2` to `tr W^6` (real part for even `k`, imaginary for
//! odd) and the momentum `J`.
//!
//! What differs from N = 4 and 5:
//! * The system is given through the library API (`su_n::Route::Library`:
//!   `LieAlgebra::from_structure_constants`, `casimir::System::new`, which
//!   checks the Casimirs and `{J, h} = 0` exactly as the spec parser does,
//!   and `generator::analyse`, what `spec::certify` runs), not as a spec:
//!   `tr W^5` has 8114 terms (227 kB of text) and `tr W^6` 46679 terms
//!   (1.5 MB), beyond the spec's limits of 5000 terms and 100,000 bytes per
//!   expression.
//! * Diagonals 1, 2 and 3 of the Laplacian are irrational, and their
//!   energy blocks rounded.
//! * The exact level takes 15 s (release) on the two states; those two
//!   tests run with `--features heavy-tests`. A linearly unstable state,
//!   `(-1, 4/5, -3/5, 1, -1/5, 0)`, took 86 s (the exact level 42 s,
//!   `analyse_numeric` 42 s) and is not a test: both engines said
//!   `linearly_unstable`, with growth rates 5.827090639661572e-2 and
//!   5.827090639661553e-2 (3e-15 relative).

#[path = "common/su_n.rs"]
mod su_n;

use su_n::{degree_two_noise, fifths, Route};

const N: usize = 6;

/// A strictly monotone profile, not equally spaced: `omega = (-1, -3/5,
/// -1/5, 0, 4/5, 1)`, trace zero.
fn monotone() -> Vec<exact::Rational> {
    fifths(&[-5, -3, -1, 0, 4, 5])
}

/// The block formula is the Laplacian's definition and its spectrum is
/// `-l(l+1)`; at N = 6 diagonals 1, 2 and 3 are irrational.
#[test]
fn su6_laplacian_blocks_match_the_spin_matrix_definition() {
    su_n::check_laplacian_blocks(N);
    // The products under the roots, `j(N-j)(j+m)(N-j-m)`: diagonal 1 has
    // 1*5*2*4 = 40, diagonal 2 1*5*3*3 = 45, diagonal 3 1*5*4*2 = 40 (not
    // squares); diagonal 4 has only 1*5*5*1 = 25, diagonal 5 no
    // off-diagonal entry, diagonal 0 `j(N-j)` squared.
    assert_eq!(su_n::irrational_diagonals(N), vec![1, 2, 3]);
}

/// The system's polynomials are the model's functionals
/// (`su_n::check_spec_polynomials`). Tolerance 1e-13 relative, as at N = 4
/// and 5: `cond(Delta) = 30/2 = 15`, and the differences seen were below
/// 5e-15.
#[test]
fn su6_polynomials_are_the_models_functionals() {
    su_n::check_spec_polynomials(&monotone(), &degree_two_noise(N), 1e-13, Route::Library);
}

/// The monotone state (`su_n::check_monotone`, the assertions of N = 4 and
/// 5 on the exact level's analysis): both `stable`, the infimum 0
/// approached by both, and at the Zeitlin pipeline's `(eps, beta)` the
/// generic engine's exact `P`, `Q` give the Zeitlin `lambda_max` of blocks
/// `m = 1..5`. Tolerance 1e-9 relative, as at N = 4 (the Zeitlin bracket's
/// width, `blocks[].residual`, 7.1e-11 at most here; the differences seen
/// were 6.2e-11 at most). 18 s in release, 38 s in debug.
#[cfg(feature = "heavy-tests")]
#[test]
fn su6_monotone_state_agrees_with_the_generic_engine() {
    let report = su_n::check_monotone(&monotone(), &degree_two_noise(N), 1e-9, Route::Library);
    println!("su(6) monotone: {report:#?}");
}

/// A state that is not monotone, `omega = (-1, -1/5, -3/5, 4/5, 0, 1)`: no
/// definite form and the spectrum on the imaginary axis in both engines.
/// (Of the 120 orderings of the monotone state's values with `omega_0 =
/// -1`, the Zeitlin pipeline found 8 `inconclusive`, 1 `stable` and the
/// rest `linearly_unstable` when this test was written.) 17 s in release.
#[cfg(feature = "heavy-tests")]
#[test]
fn su6_non_monotone_state_is_inconclusive_in_both() {
    su_n::check_non_monotone(&fifths(&[-5, -1, -3, 4, 0, 5]), &degree_two_noise(N), Route::Library);
}

/// The perturbations that must fail (`su_n::check_perturbations_fail`): a
/// coupling of 2^-60 between `mu0` and the first Cartan coordinate `mu30`
/// gives `not_an_equilibrium`, a change of 2^-60 on the real part of
/// diagonal 1 alone a system refused by `System::new` (`{J, h} != 0`).
#[test]
fn su6_perturbing_the_rounded_energy_off_its_blocks_fails() {
    su_n::check_perturbations_fail(&monotone(), &degree_two_noise(N), Route::Library);
}
