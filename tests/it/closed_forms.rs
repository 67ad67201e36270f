//! The engine against the closed forms derived in `generator::closed_forms`
//! (derivations in that module's docs; independently re-derived with sympy in
//! `bench/check_closed_forms.py`). Reference values are computed exactly in
//! rationals here, so the 1e-12 tolerance measures only the engine's
//! floating-point eigen-solve.

use crate::common;

use common::*;
use exact::Rational;
use num_traits::Zero;
use proptest::prelude::*;

fn certify(text: &str) -> spec::Certificate {
    spec::certify_lie(&spec::parse_spec(text).expect("valid spec"))
}

/// sigma^2 (max(|a2|,|a3|)/min(|a2|,|a3|) - 1), a_i = 1/I_i - 1/I1, exactly.
fn rigid_body_reference(i1: &Rational, i2: &Rational, i3: &Rational, sigma: &Rational) -> Option<Rational> {
    let a2 = i2.recip() - i1.recip();
    let a3 = i3.recip() - i1.recip();
    if (&a2 * &a3) <= Rational::zero() {
        return None;
    }
    let (lo, hi) = if a2.abs() < a3.abs() { (a2.abs(), a3.abs()) } else { (a3.abs(), a2.abs()) };
    Some(sigma * sigma * (hi / lo - Rational::from_integer(1.into())))
}

/// sigma^2 (|I1-I2|/I_min) I3 (p^2 - mgl I3) / (p^2 (I3 - I_max) - mgl I3^2), exactly.
fn heavy_top_reference(
    i1: &Rational,
    i2: &Rational,
    i3: &Rational,
    mgl: &Rational,
    p: &Rational,
    sigma: &Rational,
) -> Rational {
    let (imin, imax) = if i1 < i2 { (i1, i2) } else { (i2, i1) };
    let p2 = p * p;
    sigma * sigma * ((imax - imin) / imin) * i3 * (&p2 - mgl * i3) / (&p2 * (i3 - imax) - mgl * i3 * i3)
}

fn distinct_triple() -> impl Strategy<Value = [Rational; 3]> {
    (hundredths(10, 1000), hundredths(10, 1000), hundredths(10, 1000))
        .prop_filter("distinct", |(a, b, c)| a != b && b != c && a != c)
        .prop_map(|(a, b, c)| [a, b, c])
}

proptest! {
    #![proptest_config(proptest_config(128, 4096, module_path!()))]

    /// Every ordering of three distinct inertias: major and minor axes are
    /// stable with the closed-form Sigma^2, the intermediate axis is unstable.
    #[test]
    fn rigid_body_sigma2_matches_closed_form(i in distinct_triple(), sigma in hundredths(1, 200)) {
        let cert = certify(&rigid_body_spec([&i[0], &i[1], &i[2]], &sigma));
        match rigid_body_reference(&i[0], &i[1], &i[2], &sigma) {
            Some(expected) => {
                prop_assert_eq!(cert.json["verdict"].as_str(), Some("stable"));
                let got = cert.analysis.sigma2().unwrap();
                prop_assert!(rel(got, f(&expected)) <= 1e-12 || (got - f(&expected)).abs() < 1e-300,
                    "engine {} closed form {}", got, f(&expected));
            }
            None => {
                // Intermediate axis: the linearisation has the real eigenvalues
                // ±sqrt(-a2 a3) (A = Lambda^T P restricted to the (2,3) block).
                prop_assert_eq!(cert.json["verdict"].as_str(), Some("linearly_unstable"));
                let a2 = f(&i[1]).recip() - f(&i[0]).recip();
                let a3 = f(&i[2]).recip() - f(&i[0]).recip();
                let rate = (-a2 * a3).sqrt();
                let inst = cert.analysis.instability.as_ref().unwrap();
                prop_assert!(rel(inst.eigenvalue.re, rate) < 1e-9, "{} vs {}", inst.eigenvalue.re, rate);
            }
        }
    }

    /// The asymmetric heavy top, upright or hanging, above its threshold.
    #[test]
    fn heavy_top_sigma2_matches_closed_form(
        i1 in hundredths(10, 500), i2 in hundredths(10, 500), extra in hundredths(1, 500),
        mgl in (-200i64..=200).prop_map(|k| q(k, 100)), factor in hundredths(110, 400), sigma in hundredths(1, 200),
    ) {
        let i3 = if i1 > i2 { &i1 + &extra } else { &i2 + &extra };
        // p^2 > mgl I3^2/(I3 - I_i) for i = 1, 2; pick p^2 = factor * max(that, I3) and p rational.
        let need = [&i1, &i2].iter().map(|ii| f(&mgl) * f(&i3).powi(2) / (f(&i3) - f(ii))).fold(f(&i3), f64::max);
        let p = exact::best_rational_approximation((f(&factor) * need).sqrt(), 1000).unwrap();
        let stable = [&i1, &i2].iter().all(|ii| &p * &p * (&i3 - *ii) > &mgl * &i3 * &i3);
        prop_assume!(stable);
        let cert = certify(&heavy_top_spec([&i1, &i2, &i3], &mgl, &p, &sigma, false));
        prop_assert_eq!(cert.json["verdict"].as_str(), Some("stable"));
        let expected = f(&heavy_top_reference(&i1, &i2, &i3, &mgl, &p, &sigma));
        let got = cert.analysis.sigma2().unwrap();
        prop_assert!(rel(got, expected) <= 1e-12 || (i1 == i2 && got == 0.0), "engine {} closed form {}", got, expected);
    }

    /// The Lagrange top with the first integral Pi3: Sigma^2 = 0 above the
    /// fast-top threshold p^2 > 4 mgl I1; below it the growth rate is
    /// (1/2) sqrt(4 mgl/I1 - p^2/I1^2).
    #[test]
    fn lagrange_top_threshold_and_sigma2(
        i1 in hundredths(10, 500), i3 in hundredths(10, 500), mgl in hundredths(10, 300),
        ratio in prop_oneof![hundredths(105, 400), hundredths(5, 95)], sigma in hundredths(1, 200),
    ) {
        // p^2 = ratio * 4 mgl I1
        let p = exact::best_rational_approximation((f(&ratio) * 4.0 * f(&mgl) * f(&i1)).sqrt(), 10_000).unwrap();
        let fast = &p * &p > Rational::from_integer(4.into()) * &mgl * &i1;
        let cert = certify(&heavy_top_spec([&i1, &i1, &i3], &mgl, &p, &sigma, true));
        if fast {
            prop_assert_eq!(cert.json["verdict"].as_str(), Some("stable"));
            prop_assert_eq!(cert.analysis.sigma2(), Some(0.0));
        } else {
            prop_assert_eq!(cert.json["verdict"].as_str(), Some("linearly_unstable"));
            let rate = generator::closed_forms::lagrange_top_growth_rate(f(&i1), f(&mgl), f(&p)).unwrap();
            let got = cert.analysis.instability.as_ref().unwrap().eigenvalue.re;
            prop_assert!(rel(got, rate) < 1e-9, "engine {} closed form {}", got, rate);
        }
    }

    /// The so(2,1) rigid body about its timelike axis (custom structure
    /// constants, Casimir discovered): Sigma^2 = sigma^2 (max(q1,q2)/min(q1,q2) - 1)
    /// with q_i = 1/I_i + 1/I3 (same computation as the so3 body with a_i -> q_i).
    #[test]
    fn so21_rigid_body_matches_closed_form(i in distinct_triple(), sigma in hundredths(1, 200)) {
        let text = format!(
            r#"{{"name": "so21", "algebra": {{"coordinates": ["M1", "M2", "M3"],
                 "structure_constants": [[0, 1, 2, -1], [1, 2, 0, 1], [2, 0, 1, 1]]}},
                "parameters": {{"I1": "{}", "I2": "{}", "I3": "{}", "sigma": "{}"}},
                "hamiltonian": "M1^2/(2*I1) + M2^2/(2*I2) + M3^2/(2*I3)",
                "equilibrium": [0, 0, 1], "noise": [[0, 0, "sigma"]]}}"#,
            i[0], i[1], i[2], sigma
        );
        let cert = certify(&text);
        prop_assert_eq!(cert.json["verdict"].as_str(), Some("stable"));
        let q1 = i[0].recip() + i[2].recip();
        let q2 = i[1].recip() + i[2].recip();
        let (lo, hi) = if q1 < q2 { (q1, q2) } else { (q2, q1) };
        let expected = f(&(&sigma * &sigma * (hi / lo - Rational::from_integer(1.into()))));
        prop_assert!(rel(cert.analysis.sigma2().unwrap(), expected) <= 1e-12);
    }
}

/// The paper states Sigma^2 = sigma^2 for the rigid body; for I = (3, 2, 1)
/// the sharp constant is 3 sigma^2 (docs/errata.md), and a perturbation along
/// Pi2 exceeds the paper's rate: L|x|_P^2 / |x|_P^2 = sigma^2 (a3 - a2)/a2 = 3 sigma^2.
#[test]
fn paper_rigid_body_constant_is_not_an_upper_bound() {
    let cert = certify(&fixture("rigid-body-major-axis.json"));
    let s = cert.analysis.stable.as_ref().unwrap();
    let x = [0.0, 1.0, 0.0];
    let p = s.choice.p.to_dmatrix();
    let qm = s.form.q.to_dmatrix();
    let v = nalgebra::DVector::from_column_slice(&x);
    let ratio = (v.transpose() * &qm * &v)[(0, 0)] / (v.transpose() * &p * &v)[(0, 0)];
    let sigma2_paper = 0.09;
    assert!((ratio - 3.0 * sigma2_paper).abs() < 1e-15, "ratio {ratio}");
    assert!(ratio > sigma2_paper);
}

/// A deterministic system (empty noise) is certified stable with Sigma^2 = 0
/// and an infinite stopping time.
#[test]
fn empty_noise_gives_zero_sigma2() {
    let text = fixture("rigid-body-major-axis.json").replace(r#"[["sigma", 0, 0]]"#, "[]");
    let cert = certify(&text);
    assert_eq!(cert.json["verdict"], "stable");
    assert_eq!(cert.analysis.sigma2(), Some(0.0));
    assert_eq!(cert.json["stopping"]["T"], "infinity");
}

/// Regression: nalgebra's real Schur form (no iteration limit) looped forever
/// on this slow Lagrange top's linearisation; the spectrum now comes from
/// faer. Expected growth rate (1/2) sqrt(4 mgl/I1 - p^2/I1^2) (closed_forms).
#[test]
fn regression_schur_hang_on_slow_lagrange_top() {
    let text = heavy_top_spec([&q(1, 10), &q(1, 10), &q(23, 100)], &q(271, 100), &q(1835, 3941), &q(3, 10), true);
    let cert = certify(&text);
    assert_eq!(cert.json["verdict"], "linearly_unstable");
    let rate = generator::closed_forms::lagrange_top_growth_rate(0.1, 2.71, 1835.0 / 3941.0).unwrap();
    assert!(rel(cert.analysis.instability.as_ref().unwrap().eigenvalue.re, rate) < 1e-9);
}

/// Sigma^2 is additive over noise fields (the generator is a sum of one
/// quadratic form per field, each proportional to sigma_i^2), so two parallel
/// fields sigma and 2 sigma act like one of amplitude sqrt(5) sigma:
/// Sigma^2 = 5 * 0.27 = 1.35 for the major-axis body. It does not depend on
/// |Pi_e| either (a_i and B do not), so Pi_e = (2, 0, 0) gives the same.
#[test]
fn sigma2_adds_over_parallel_noise_and_ignores_the_equilibrium_size() {
    let base = fixture("rigid-body-major-axis.json");
    let two_fields = base.replace(r#"[["sigma", 0, 0]]"#, r#"[["sigma", 0, 0], ["2*sigma", 0, 0]]"#);
    let got = certify(&two_fields).analysis.sigma2().unwrap();
    assert!(rel(got, 5.0 * 0.27) < 1e-13, "{got}");
    let bigger = base.replace("[1, 0, 0]", "[2, 0, 0]");
    let got = certify(&bigger).analysis.sigma2().unwrap();
    assert!(rel(got, 0.27) < 1e-13, "{got}");
}

/// The optimiser against a closed form where the Casimir freedom matters:
/// the Lagrange top under a fluctuating potential (noise sigma (0, e3)) has
/// Sigma^2 = 4 sigma^2 / (p^2 - 4 mgl I1) at the optimal multiplier
/// (derivation in generator::closed_forms; bench/numpy_pipeline.py, which
/// minimises the restricted problem independently, gives 0.0719999999999999
/// for the fixture), while the first definite choice is strictly worse.
#[test]
fn optimiser_finds_the_closed_form_for_the_fluctuating_lagrange_top() {
    let cert = certify(&fixture("lagrange-top-fluctuating-gravity.json"));
    assert_eq!(cert.json["sigma2_exact"], "9/125"); // 4 * 0.09 / (9 - 4)
    assert_eq!(cert.json["sigma2_sharp"], true);
    let first = cert.json["optimisation"]["first_definite_sigma2"].as_f64().unwrap();
    assert!(first > 0.072 * 1.1, "first choice {first}");
}

fn fluctuating_gravity_spec(i1: &Rational, i3: &Rational, mgl: &Rational, p: &Rational, sigma: &Rational) -> String {
    format!(
        r#"{{"name": "lt-grav", "algebra": "se3",
            "parameters": {{"I1": "{i1}", "I3": "{i3}", "mgl": "{mgl}", "p": "{p}", "sigma": "{sigma}"}},
            "hamiltonian": "(Pi1^2 + Pi2^2)/(2*I1) + Pi3^2/(2*I3) + mgl*Gamma3",
            "first_integrals": ["Pi3"],
            "equilibrium": [0, 0, "p", 0, 0, 1], "noise": [[0, 0, 0, 0, 0, "sigma"]]}}"#
    )
}

proptest! {
    #![proptest_config(proptest_config(48, 1024, module_path!()))]

    #[test]
    fn fluctuating_lagrange_top_matches_closed_form(
        i1 in hundredths(20, 300), i3 in hundredths(20, 300), mgl in hundredths(10, 200),
        ratio in hundredths(120, 400), sigma in hundredths(5, 100),
    ) {
        let p = exact::best_rational_approximation((f(&ratio) * 4.0 * f(&mgl) * f(&i1)).sqrt(), 1000).unwrap();
        let excess = &p * &p - Rational::from(4) * &mgl * &i1;
        prop_assume!(excess > Rational::zero());
        let cert = certify(&fluctuating_gravity_spec(&i1, &i3, &mgl, &p, &sigma));
        prop_assert_eq!(cert.json["verdict"].as_str(), Some("stable"));
        // Exact reference 4 sigma^2 / (p^2 - 4 mgl I1).
        let expected = Rational::from(4) * &sigma * &sigma / excess;
        let got = cert.analysis.sigma2().unwrap();
        // Within the optimiser's stated tolerance (1e-9 relative) of the infimum.
        prop_assert!(rel(got, f(&expected)) < 1e-9, "engine {} closed form {}", got, f(&expected));
    }
}

/// An infimum that is approached but not attained: on this rescaled so3
/// system (found by tests/it/random_systems.rs) Sigma^2 -> 0 as the Casimir
/// term M grows, so no finite choice attains it. The certificate must say so,
/// certify a value far below the first choice's, and still pass the check.
#[test]
fn infimum_approached_but_not_attained_is_reported() {
    let text = r#"{"name": "so3-rescaled", "algebra": {"coordinates": ["x0", "x1", "x2"],
        "structure_constants": [[0, 1, 2, "9"], [0, 2, 1, "-1"], [1, 2, 0, "1"]]},
        "hamiltonian": "(5/2)*x0*x0 + (-3)*x0*x1 + (-2)*x0*x2 + (-7)*x0 + (1/2)*x1*x1 + (2)*x1*x2 + (3)*x1 + (4)*x2",
        "equilibrium": ["1", "-1", "0"], "noise": [["-1", "1", "0"]]}"#;
    let cert = certify(text);
    assert_eq!(cert.json["verdict"], "stable");
    let opt = &cert.json["optimisation"];
    assert_eq!(opt["attained"], false);
    assert_eq!(opt["infimum"].as_f64(), Some(0.0));
    let first = opt["first_definite_sigma2"].as_f64().unwrap();
    let got = cert.analysis.sigma2().unwrap();
    assert!(got > 0.0 && got < 1e-3 * first, "{got} vs first {first}");
    assert!(spec::check_certificate_value(&cert.json).is_ok());
}
