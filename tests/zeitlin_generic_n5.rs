//! The Zeitlin model at N = 5 through the generic finite-dimensional
//! engine: su(5), dimension 24, by the construction of
//! `tests/zeitlin_generic_n4.rs` (shared in `tests/common/su_n.rs`), with
//! the Casimirs `Re tr W^2`, `Im tr W^3`, `Re tr W^4`, `Im tr W^5` (`W = i
//! A` with `A` Hermitian, so `tr W^k = i^k tr A^k`: real for even `k`,
//! imaginary for odd `k`; the other part is asserted zero) and the momentum
//! `J`, given as a spec (the largest expression, `tr W^5`, has 2848 terms
//! and 83 kB of text, within the spec's limits of 5000 terms and 100 kB).
//!
//! What is new at N = 5: two diagonals of the Laplacian are irrational
//! (1 and 2, entries `sqrt 24`), so the energy's blocks on both are
//! rounded, each the same doubles on its real and imaginary part; the
//! equilibrium and `{J, h} = 0` stay exact for the reasons given at N = 4,
//! and the same perturbations break them. The checks are those of N = 4,
//! plus a linearly unstable state, where the growth rates agree.

#[path = "common/su_n.rs"]
mod su_n;

use su_n::{degree_two_noise, fifths, Route};

const N: usize = 5;

/// A strictly monotone profile, not equally spaced (equal spacing is the
/// momentum itself): `omega = (-1, -2/5, 0, 3/5, 4/5)`, trace zero.
fn monotone() -> Vec<exact::Rational> {
    fifths(&[-5, -2, 0, 3, 4])
}

/// The block formula is the Laplacian's definition and its spectrum is
/// `-l(l+1)`; at N = 5 diagonals 1 and 2 are irrational.
#[test]
fn su5_laplacian_blocks_match_the_spin_matrix_definition() {
    su_n::check_laplacian_blocks(N);
    // The products under the roots, `j(N-j)(j+m)(N-j-m)` for `j = 1..N-m-1`:
    // diagonal 1: 1*4*2*3 = 24, 2*3*3*2 = 36, 3*2*4*1 = 24; diagonal 2:
    // 1*4*3*2 = 24, 2*3*4*1 = 24; diagonal 3: 1*4*4*1 = 16; diagonal 4 has
    // no off-diagonal entry, diagonal 0 `j(N-j)` squared. So the energy's
    // coefficients on diagonals 1 and 2 are rounded.
    assert_eq!(su_n::irrational_diagonals(N), vec![1, 2]);
}

/// The spec's polynomials are the model's functionals
/// (`su_n::check_spec_polynomials`). Tolerance 1e-13 relative to each
/// functional's scale, as at N = 4: the energy's coefficients carry a few
/// units of round-off, the dense solve loses about `cond(Delta) = 20/2 =
/// 10` times the round-off (eigenvalues `-l(l+1)`, `l = 1..4`), and `tr
/// W^5` sums about 3000 terms; the differences seen were below 3e-15.
#[test]
fn su5_spec_polynomials_are_the_models_functionals() {
    su_n::check_spec_polynomials(&monotone(), &degree_two_noise(N), 1e-13, Route::Spec);
}

/// The monotone state (`su_n::check_monotone`): `stable` in both engines
/// (the generic one at the exact level, zero equilibrium and noise
/// residuals), the infimum 0 approached by both and attained by neither,
/// the Casimir–momentum form with `Q = 0` exactly, and at the Zeitlin
/// pipeline's own `(eps, beta)` the generic engine's exact `P`, `Q` give the
/// Zeitlin `lambda_max` of every block (`m = 1..4`). Tolerance 1e-9
/// relative to the Zeitlin `Sigma^2`, as at N = 4: the Zeitlin value is the
/// upper end of a bisection bracket of relative width at most 1e-10
/// (`blocks[].residual`, 7.4e-11 at most here); the generic side carries
/// the energy's rounding (about 1e-16 relative per coefficient) and a
/// floating-point eigensolve; the differences seen were 6.7e-11 at most,
/// within the bracket.
#[test]
fn su5_monotone_state_agrees_with_the_generic_engine() {
    let report = su_n::check_monotone(&monotone(), &degree_two_noise(N), 1e-9, Route::Spec);
    println!("su(5) monotone: {report:#?}");
}

/// A state that is not monotone, `omega = (-1, 4/5, -2/5, 3/5, 0)`: no
/// definite form and the spectrum on the imaginary axis in both engines
/// (the generic engine proves it exactly). Of the 24 orderings of the
/// monotone state's values with `omega_0 = -1`, run through both engines
/// when this test was written, 1 was `stable` (the monotone one), 3
/// `inconclusive` (this one, `(-1, 0, -2/5, 4/5, 3/5)`, `(-1, 3/5, -2/5,
/// 4/5, 0)`) and 20 `linearly_unstable`, with the same verdict in the
/// exact level, `analyse_numeric` and both Zeitlin families.
#[test]
fn su5_non_monotone_state_is_inconclusive_in_both() {
    su_n::check_non_monotone(&fifths(&[-5, 4, -2, 3, 0]), &degree_two_noise(N), Route::Spec);
}

/// A linearly unstable state, `omega = (-1, 0, -2/5, 3/5, 4/5)` (one swap
/// from the monotone state): `linearly_unstable` in both engines, proved
/// exactly in the generic one (a complex quadruple, by a Sturm sequence),
/// and the growth rates agree (`su_n::check_unstable`; the generic rate is
/// in units of `1/hbar`). Tolerance 1e-9 relative: both are double-precision
/// eigenvalues of the same linearised drift, assembled independently (the
/// dense 24 x 24 `A` from the polynomials, the Zeitlin pipeline from its
/// blocks) and differing by the energy's rounding (about 1e-16 relative);
/// the difference seen was 1.4e-13 (6.5265817915e-3 in both, the smallest
/// rate of the 20 unstable orderings, all of which agreed to that), and a
/// wrong time unit would be off by `hbar = 0.41`.
#[test]
fn su5_unstable_state_has_the_same_growth_rate_in_both() {
    su_n::check_unstable(&fifths(&[-5, 0, -2, 3, 4]), &degree_two_noise(N), 1e-9, Route::Spec);
}

/// The perturbations that must fail (`su_n::check_perturbations_fail`): a
/// coupling of 2^-60 between `mu0` and the first Cartan coordinate `mu20`
/// gives `not_an_equilibrium`, a change of 2^-60 on the real part of
/// diagonal 1 alone a refused spec (`{J, h} != 0`).
#[test]
fn su5_perturbing_the_rounded_energy_off_its_blocks_fails() {
    su_n::check_perturbations_fail(&monotone(), &degree_two_noise(N), Route::Spec);
}
