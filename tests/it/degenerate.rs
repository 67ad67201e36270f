//! Near-degenerate inputs give `inconclusive` or a correct certificate,
//! never a false one: moments of inertia equal to 1e-12 relative, a nearly
//! singular P, the fast-top threshold approached to 1e-12.

use crate::common;

use common::*;
use exact::Rational;

/// Certify, then insist that the certificate passes the exact check and is
/// either inconclusive or stable with the closed-form Sigma^2.
fn certify_checked(text: &str) -> spec::Certificate {
    let cert = spec::certify_lie(&spec::parse_spec(text).unwrap());
    let checked = spec::check_certificate_value(&cert.json);
    assert!(checked.is_ok(), "{checked:?}");
    cert
}

fn one_minus(eps: i64) -> Rational {
    // 1 - 10^-eps
    Rational::from(1) - Rational::new(1.into(), num_traits::pow(exact::BigInt::from(10), eps as usize))
}

#[test]
fn rigid_body_with_major_and_intermediate_inertia_equal_to_1e12() {
    // I1 = 3, I2 = 3 (1 - 1e-12), I3 = 1: a2 = 1/I2 - 1/I1 ~ 1e-12/3, so P is
    // nearly singular and Sigma^2 = sigma^2 (a3/a2 - 1) ~ 1e12 sigma^2.
    let i1 = Rational::from(3);
    let i2 = &i1 * one_minus(12);
    let i3 = Rational::from(1);
    let sigma = Rational::new_small(3, 10);
    let cert = certify_checked(&rigid_body_spec([&i1, &i2, &i3], &sigma));
    let verdict = cert.json["verdict"].as_str().unwrap();
    eprintln!("I2 = I1 (1 - 1e-12): {verdict} ({})", cert.json["reason"]);
    assert!(verdict == "inconclusive" || verdict == "stable", "{verdict}");
    if verdict == "stable" {
        let a2 = i2.recip() - i1.recip();
        let a3 = i3.recip() - i1.recip();
        let expected = &sigma * &sigma * (a3 / a2 - Rational::from(1));
        assert!(rel(cert.analysis.sigma2().unwrap(), f(&expected)) < 1e-9);
    }
}

#[test]
fn rigid_body_nearly_kubo() {
    // I2 = I3 (1 + 1e-12): Sigma^2 = sigma^2 (a3/a2 - 1) is tiny but positive,
    // and the exact certificate must capture it (0 would be false).
    let i1 = Rational::from(3);
    let i3 = Rational::from(2);
    let i2 = &i3 * (Rational::from(2) - one_minus(12));
    let sigma = Rational::new_small(3, 10);
    let cert = certify_checked(&rigid_body_spec([&i1, &i2, &i3], &sigma));
    assert_eq!(cert.json["verdict"], "stable");
    let a2 = i2.recip() - i1.recip();
    let a3 = i3.recip() - i1.recip();
    let expected = &sigma * &sigma * (a3 / a2 - Rational::from(1));
    let got = cert.analysis.sigma2().unwrap();
    assert!(got > 0.0, "Sigma^2 = 0 would be false here");
    assert!(rel(got, f(&expected)) < 1e-6, "{got} vs {}", f(&expected));
}

#[test]
fn rigid_body_with_two_equal_inertias_on_the_axis() {
    // I1 = I2 exactly: a circle of equilibria; the energy-Casimir form is
    // singular, and the spectrum of A is exactly on the imaginary axis.
    let q = Rational::from;
    let cert = certify_checked(&rigid_body_spec([&q(2), &q(2), &q(1)], &Rational::new_small(3, 10)));
    assert_eq!(cert.json["verdict"], "inconclusive");
    assert_eq!(cert.json["spectrum_proof"], "imaginary_axis");
}

#[test]
fn lagrange_top_just_above_and_at_the_threshold() {
    // p^2 = 4 mgl I1 (1 + 1e-12) and exactly at the threshold.
    let q = Rational::from;
    let i1 = q(1);
    let mgl = q(1);
    let sigma = Rational::new_small(3, 10);
    // p = 2 + 2e-12 gives p^2 = 4 (1 + 2e-12 + O(1e-24)).
    let p_above = q(2) + (q(1) - one_minus(12)) * q(2);
    for p in [p_above, q(2)] {
        let cert = certify_checked(&heavy_top_spec([&i1, &i1, &Rational::new_small(1, 2)], &mgl, &p, &sigma, true));
        let verdict = cert.json["verdict"].as_str().unwrap().to_string();
        eprintln!("p = {p}: {verdict} ({})", cert.json["reason"]);
        assert!(["stable", "inconclusive"].contains(&verdict.as_str()), "p = {p}: {verdict}");
        if verdict == "stable" {
            assert_eq!(cert.analysis.sigma2(), Some(0.0)); // closed form: Sigma^2 = 0
        }
    }
}
