//! Regression: a badly scaled exact basis of `ker G^T` lost the definite form.
//!
//! On so(3) with
//! `h = |Pi|^2/2 + (Pi2 - Pi3)^2/2 + (2 Pi1 - a Pi2 - a Pi3)^2/2`,
//! `C = c |Pi|^2/2` and `mu_e = (a, 1, 1)` (an equilibrium: `Dh(mu_e) = mu_e`,
//! so `ad*_{Dh} mu_e = mu_e × mu_e = 0`), the echelon basis of
//! `ker G^T = (a, 1, 1)^perp` is `(-1/a, 1, 0)`, `(-1/a, 0, 1)`: nearly
//! parallel and of size `1/a`. The search rounded `Z^T B Z` (entries
//! `4/a^2 + O(1)`) and `Z^T Z` (`1/a^2 + O(1)`) to doubles and whitened with
//! a Cholesky of the rounded Gram matrix: for `a <= 2^-26` the `O(1)`
//! eigenvalues of the restricted Hessian were lost (the Cholesky failed or
//! the whitened form had eigenvalues `[0, 4]`, for `a = 1e-300` the Gram
//! matrix overflowed) and the exact verdict was `inconclusive` while the
//! floating-point route said `stable`. The result also depended on the
//! coordinate order (the cyclically permuted system has a well-scaled
//! echelon basis and was found). The kernel basis now has pivots of
//! maximal volume (`Matrix::bounded_null_space`: coefficients at most 1,
//! here `(1, -a, 0)`, `(0, -1, 1)`), so `Z^T Z` is well conditioned and the
//! forms are whitened without loss.
//!
//! The expected margin, derived independently of the engine: with `u = (0,
//! 1, -1)` and `w = (2, -a, -a)`, `D^2h = I + u u^T + w w^T` and `Dh(mu_e) =
//! mu_e`, so `lambda = -1/c` and `B = D^2h + lambda D^2C = u u^T + w w^T`.
//! `u` and `w` are orthogonal to each other and to `G = c mu_e`, so on the
//! orthonormal basis `(u/|u|, w/|w|)` of `ker G^T` the restricted Hessian
//! is `diag(|u|^2, |w|^2) = diag(2, 4 + 2a^2)`: positive definite with
//! relative margin `2/(4 + 2a^2) = 1/(2 + a^2)` and level scale
//! `sqrt(2 (4 + 2a^2))`, whatever `c`. Cross-checked with mpmath at 1200
//! digits (the eigenvalues of `Q^T B Q`, `Q` the last two columns of a QR
//! of `[G e1 e2]`) for a = 1, 1e-3, 2^-26, 2^-27, 2^-30, 2^-40, 1e-9,
//! 1e-12, 1e-20, 1e-50, 1e-100, 1e-300 and c = 1, 1e-12, 1e12: agreement to
//! all 20 printed digits.

use algebra::builtin;
use casimir::{find_definite_choice, level_scale, SearchSettings, Sign, System};
use exact::{parse_expression, parse_number, rational_to_f64, Rational, Symbols};

/// `a` from 1 down to 1e-300: the first two found the definite form
/// before (for 1/1000 with a margin wrong by 1e-10, `cond(Z^T Z) eps`), the
/// rest, with `1/a^2 >= 2^52`, did not.
const A_VALUES: [&str; 16] = [
    "1",
    "1/1000",
    "1/67108864",         // 2^-26
    "1/134217728",        // 2^-27
    "1/1073741824",       // 2^-30
    "1/1099511627776",    // 2^-40
    "1/4503599627370496", // 2^-52
    "1e-8",
    "1e-9",
    "1e-10",
    "1e-12",
    "1e-20",
    "1e-50",
    "1e-100",
    "1e-200",
    "1e-300",
];

/// The Casimir's scale: the verdict and margin must not depend on it.
const C_VALUES: [&str; 3] = ["1", "1e-12", "1e12"];

/// The system, with its coordinates cyclically permuted `shift` times
/// (`Pi1 -> Pi2 -> Pi3 -> Pi1` preserves the so(3) bracket), and
/// optionally `s h` as a first integral (a free multiplier family).
fn system(a: &str, c: &str, shift: usize, first_integral: Option<&str>) -> System {
    let so3 = builtin("so3").unwrap().algebra;
    let symbols = Symbols::new(so3.coordinates());
    // Coordinate names in the roles of Pi1, Pi2, Pi3 of the unpermuted system.
    let x = |i: usize| format!("Pi{}", (i + shift) % 3 + 1);
    let (p1, p2, p3) = (x(0), x(1), x(2));
    let h = format!("({p1}^2 + {p2}^2 + {p3}^2)/2 + ({p2} - {p3})^2/2 + (2*{p1} - ({a})*{p2} - ({a})*{p3})^2/2");
    let parse = |text: &str| parse_expression(text, &symbols).unwrap();
    let casimir = parse(&format!("({c})*(Pi1^2 + Pi2^2 + Pi3^2)/2"));
    let first: Vec<_> = first_integral.map(|s| parse(&format!("({s})*({h})"))).into_iter().collect();
    let mut mu = vec![Rational::from(1); 3];
    mu[shift % 3] = parse_number(a).unwrap();
    System::new(so3, parse(&h), vec![casimir], first, mu, vec![]).unwrap()
}

/// `1/(2 + a^2)` (see the module comment).
fn expected_margin(a: &str) -> f64 {
    let a = parse_number(a).unwrap();
    rational_to_f64(&(Rational::from(2) + &a * &a).recip())
}

fn assert_definite(a: &str, c: &str, shift: usize, first_integral: Option<&str>) {
    let label = format!("a = {a}, c = {c}, shift = {shift}, first integral {first_integral:?}");
    let variation = system(a, c, shift, first_integral).second_variation().unwrap();
    let outcome = find_definite_choice(&variation, &SearchSettings::default());
    let choice = outcome.definite().unwrap_or_else(|| panic!("{label}: no definite form, {outcome:?}"));
    assert_eq!(choice.sign, Sign::Positive, "{label}");
    // Claimed exactly: the restricted Hessian and P itself (rational LDL^T).
    assert!(variation.restricted(&choice.multipliers).is_definite_with_sign(Sign::Positive), "{label}");
    assert!(choice.p.is_definite_with_sign(Sign::Positive), "{label}");
    assert_eq!(choice.p, variation.second_variation(&choice.multipliers, &choice.m), "{label}");
    let expected = expected_margin(a);
    let error = (choice.relative_margin - expected).abs() / expected;
    assert!(error < 1e-13, "{label}: margin {} against {expected}", choice.relative_margin);
    if first_integral.is_none() {
        // B = u u^T + w w^T at lambda = -1/c: level scale sqrt(2 (4 + 2a^2)).
        let av = rational_to_f64(&parse_number(a).unwrap());
        let expected = (2.0 * (4.0 + 2.0 * av * av)).sqrt();
        let scale = level_scale(&variation, &choice.multipliers, Sign::Positive);
        assert!((scale - expected).abs() < 1e-13 * expected, "{label}: level scale {scale} against {expected}");
    }
}

#[test]
fn a_badly_scaled_kernel_basis_keeps_the_definite_form() {
    for a in A_VALUES {
        for c in C_VALUES {
            assert_definite(a, c, 0, None);
        }
    }
}

#[test]
fn a_badly_scaled_kernel_basis_keeps_the_definite_form_in_any_coordinate_order() {
    for a in A_VALUES {
        for shift in [1, 2] {
            assert_definite(a, "1", shift, None);
        }
    }
}

#[test]
fn a_badly_scaled_kernel_basis_keeps_the_definite_form_over_a_multiplier_family() {
    // With h itself as a first integral (scaled by s), the multipliers form
    // a line and B(t) = (1 + s lambda_F)(u u^T + w w^T): the search runs the
    // ellipsoid method on the whitened pencil and rounds t.
    for a in A_VALUES {
        for (c, s) in [("1", "1"), ("1e-12", "1e12"), ("1e12", "1e-9")] {
            assert_definite(a, c, 0, Some(s));
        }
    }
}
