//! The numeric level in floating point throughout
//! (`generator::analyse_numeric`, used by `verify sweep --numeric`) against
//! the exact pipeline and against closed forms: the same verdicts, the same
//! `Sigma^2`, the same answer whatever the scaling of the Casimirs, and the
//! exact pipeline taken where floating point cannot decide.

use crate::common;

use common::*;
use generator::{analyse, analyse_numeric, NumericRoute, Verdict};
use proptest::prelude::*;

/// A rational from text such as `1/1000` or `1e30` (the spec's number syntax).
struct Num(exact::Rational);

impl std::str::FromStr for Num {
    type Err = exact::NumberError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        exact::parse_number(s).map(Num)
    }
}

fn parse(text: &str) -> spec::Spec {
    spec::parse_spec(text).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// Every finite-dimensional fixture: the verdict of the exact pipeline,
/// `Sigma^2` within 1e-9 (relative, or 1e-12 absolute near 0), and the
/// floating-point route for every fixture without free multipliers (the
/// verdict paths stable, linearly unstable, not an equilibrium and
/// incompatible noise). The Lagrange tops (one free multiplier) and the
/// spherical body (a restricted Hessian that is 0) take the exact pipeline
/// and say why.
#[test]
fn every_fixture_agrees_with_the_exact_pipeline() {
    let mut verdicts = std::collections::BTreeSet::new();
    for name in fixture_specs() {
        let spec = parse(&fixture(&name));
        let exact = analyse(&spec.system, &spec.settings.pipeline);
        let numeric = analyse_numeric(&spec.system, &spec.settings.pipeline);
        assert_eq!(numeric.verdict, exact.verdict, "{name}: {}", numeric.reason);
        if let (Some(a), Some(b)) = (numeric.sigma2, exact.sigma2()) {
            assert!((a - b).abs() <= 1e-9 * b.abs() + 1e-12, "{name}: Sigma^2 {a} vs exact {b}");
        }
        assert_eq!(numeric.sigma2.is_some(), exact.sigma2().is_some(), "{name}");
        if name.starts_with("lagrange-top") {
            assert_eq!(
                numeric.route,
                NumericRoute::ExactPipeline("free multipliers (a family to optimise over)"),
                "{name}"
            );
        } else if name == "rigid-body-spherical.json" {
            // The restricted Hessian is 0 exactly: within its rounding of
            // the tolerance, so floating point does not decide it.
            assert_eq!(
                numeric.route,
                NumericRoute::ExactPipeline(
                    "the restricted Hessian's sign is within its rounding of the definiteness tolerance"
                ),
                "{name}"
            );
        } else {
            assert_eq!(numeric.route, NumericRoute::FloatingPoint, "{name}");
            verdicts.insert(numeric.verdict.as_str());
        }
        if numeric.verdict == Verdict::LinearlyUnstable {
            let rate = numeric.instability.expect("an unstable eigenvalue").re;
            let exact_rate = exact.instability.as_ref().expect("exact pipeline's eigenvalue").eigenvalue.re;
            assert!((rate - exact_rate).abs() <= 1e-9 * exact_rate.abs(), "{name}: {rate} vs {exact_rate}");
        }
    }
    // The floating-point route itself reached four verdicts (all but
    // `inconclusive`, which the random systems of tests/it/random_systems.rs
    // reach on it).
    assert_eq!(verdicts.len(), 4, "{verdicts:?}");
}

proptest! {
    #![proptest_config(proptest_config(64, 2000, module_path!()))]

    /// The rigid body about `e1`: `Sigma^2 = sigma^2 (hi - lo)/lo` with
    /// `a_i = 1/I_i - 1/I1` (`generator::closed_forms::rigid_body_sigma2`,
    /// derived in docs/errata.md), `inconclusive` or `linearly_unstable`
    /// on the intermediate axis, never `stable` there.
    #[test]
    fn the_rigid_body_matches_its_closed_form(
        i1 in hundredths(10, 600), i2 in hundredths(10, 600), i3 in hundredths(10, 600), s in hundredths(1, 200)
    ) {
        let spec = parse(&rigid_body_spec([&i1, &i2, &i3], &s));
        let a = analyse_numeric(&spec.system, &spec.settings.pipeline);
        match generator::closed_forms::rigid_body_sigma2(f(&i1), f(&i2), f(&i3), f(&s)) {
            Some(expected) => {
                prop_assert_eq!(&a.route, &NumericRoute::FloatingPoint);
                prop_assert_eq!(a.verdict, Verdict::Stable, "{}", a.reason);
                let got = a.sigma2.unwrap();
                prop_assert!((got - expected).abs() <= 1e-9 * expected + 1e-13, "{} vs {}", got, expected);
            }
            None => prop_assert_ne!(a.verdict, Verdict::Stable),
        }
    }

    /// The asymmetric sleeping heavy top with noise `sigma e3`:
    /// `generator::closed_forms::heavy_top_sigma2` where the second
    /// variation is definite (with a margin: at the boundary the
    /// definiteness tolerance decides), never `stable` where it is not.
    #[test]
    fn the_heavy_top_matches_its_closed_form(
        i1 in hundredths(50, 400), i2 in hundredths(50, 400), i3 in hundredths(50, 800),
        mgl in hundredths(1, 300), p in hundredths(1, 800), s in hundredths(1, 100)
    ) {
        let spec = parse(&heavy_top_spec([&i1, &i2, &i3], &mgl, &p, &s, false));
        let a = analyse_numeric(&spec.system, &spec.settings.pipeline);
        prop_assert_eq!(&a.route, &NumericRoute::FloatingPoint);
        let (fi1, fi2, fi3, fm, fp, fs) = (f(&i1), f(&i2), f(&i3), f(&mgl), f(&p), f(&s));
        let margin = [fi1, fi2].iter().map(|&ii| fp * fp * (fi3 - ii) - fm * fi3 * fi3).fold(f64::INFINITY, f64::min);
        match generator::closed_forms::heavy_top_sigma2(fi1, fi2, fi3, fm, fp, fs) {
            Some(expected) if margin > 1e-3 * fp * fp * fi3 => {
                prop_assert_eq!(a.verdict, Verdict::Stable, "{}", a.reason);
                let got = a.sigma2.unwrap();
                prop_assert!((got - expected).abs() <= 1e-8 * expected + 1e-13, "{} vs {}", got, expected);
                // And the exact pipeline's certified value.
                let exact = analyse(&spec.system, &spec.settings.pipeline).sigma2().unwrap();
                prop_assert!((got - exact).abs() <= 1e-8 * exact + 1e-13, "{} vs exact {}", got, exact);
            }
            Some(_) => {}
            None => prop_assert_ne!(a.verdict, Verdict::Stable, "{}", a.reason),
        }
    }

    /// The Casimirs of the heavy top written with factors `c1, c2` in
    /// [1e-6, 1e6] (the same constraints): the verdict and `Sigma^2` do not
    /// change (to 1e-9).
    #[test]
    fn casimir_scaling_does_not_change_the_numeric_level(e1 in -6i32..=6, e2 in -6i32..=6, m1 in 1i64..10, m2 in 1i64..10) {
        let scale = |e: i32, m: i64| if e >= 0 { q(m * 10i64.pow(e as u32), 1) } else { q(m, 10i64.pow((-e) as u32)) };
        let base = fixture("heavy-top-asymmetric.json");
        let with = |c1: &exact::Rational, c2: &exact::Rational| {
            base.replacen(
                r#""equilibrium""#,
                &format!(r#""casimirs": ["({c1})*(Gamma1^2 + Gamma2^2 + Gamma3^2)", "({c2})*(Pi1*Gamma1 + Pi2*Gamma2 + Pi3*Gamma3)"], "equilibrium""#),
                1,
            )
        };
        let reference = parse(&with(&q(1, 1), &q(1, 1)));
        let scaled = parse(&with(&scale(e1, m1), &scale(e2, m2)));
        let a = analyse_numeric(&reference.system, &reference.settings.pipeline);
        let b = analyse_numeric(&scaled.system, &scaled.settings.pipeline);
        prop_assert_eq!(a.verdict, b.verdict);
        prop_assert_eq!(&b.route, &NumericRoute::FloatingPoint);
        let (x, y) = (a.sigma2.unwrap(), b.sigma2.unwrap());
        prop_assert!((x - y).abs() <= 1e-9 * x, "{} vs {}", x, y);
    }
}

/// Inputs near the ends of the double range take the exact pipeline (its
/// scaling keeps them), so that no product under- or overflows into a
/// wrong `Sigma^2`: noise `1e-150` gives `Sigma^2 = 0.27e-300`, not 0, and
/// noise `1e-200` (`Sigma^2` about 1e-400, beyond doubles) is not `stable`
/// with a made-up number.
#[test]
fn extreme_magnitudes_take_the_exact_pipeline() {
    let tiny = |s: &str| {
        let spec = parse(&rigid_body_spec([&q(3, 1), &q(2, 1), &q(1, 1)], &s.parse::<Num>().unwrap().0));
        analyse_numeric(&spec.system, &spec.settings.pipeline)
    };
    let a = tiny(&format!("1/1{}", "0".repeat(150)));
    assert_eq!(a.route, NumericRoute::ExactPipeline("an input's magnitude lies outside 2^-100 to 2^100"));
    assert_eq!(a.verdict, Verdict::Stable);
    // Sigma^2 = sigma^2 * 3 = 0.27e-300 / 0.09... = 3e-300 (I = 3, 2, 1).
    let s2 = a.sigma2.unwrap();
    assert!((s2 - 3e-300).abs() <= 1e-9 * 3e-300, "{s2}");
    let b = tiny(&format!("1/1{}", "0".repeat(200)));
    assert_ne!(b.verdict, Verdict::Stable, "{}", b.reason);
    // Inertias of 1e20 are within range: floating point throughout, and
    // Sigma^2 does not depend on a common scale of the inertias.
    let big = parse(&rigid_body_spec(
        [
            &format!("3{}", "0".repeat(20)).parse::<Num>().unwrap().0,
            &format!("2{}", "0".repeat(20)).parse::<Num>().unwrap().0,
            &format!("1{}", "0".repeat(20)).parse::<Num>().unwrap().0,
        ],
        &q(3, 10),
    ));
    let c = analyse_numeric(&big.system, &big.settings.pipeline);
    assert_eq!(c.route, NumericRoute::FloatingPoint);
    assert!((c.sigma2.unwrap() - 0.27).abs() < 1e-12, "{:?}", c.sigma2);
}

/// Systems that reviews found earlier versions of the numeric level
/// calling `stable`, where the exact pipeline does not (the first four it
/// proves linearly unstable by a Sturm sequence): the numeric level must
/// not say `stable` on any.
///
/// * A Casimir `(|Pi|^2 - 1/4)^2` whose gradient at `mu_e` (`|mu_e|^2 =
///   1/4`) is zero exactly but about 1e-17 in floating point (its terms
///   cancel): scaled to a unit column it made the rank wrong. Now the
///   gradients at `mu_e` are evaluated exactly, and the rank of `G` and
///   the existence of multipliers decided in rational arithmetic.
/// * A nearly spherical body (`I2` and `I3` within 1e-8 of `I1`, axis 1
///   intermediate by 1e-20) with the Casimir scaled by 7/9: the restricted
///   Hessian is a difference of nearly equal terms, and its rounding
///   exceeded the 1e-9 relative tolerance. Now that rounding is bounded and
///   a sign within it goes to the exact pipeline.
#[test]
fn cancellations_never_give_a_false_stable() {
    let zero_gradient = r#"{"name":"s","algebra":"so3","parameters":{"j1":1,"j2":"999999999999/1000000000000","j3":2,"sigma":"3/10"},
        "hamiltonian":"(9*j1+16*j2)/25*Pi1^2/2 + (16*j1+9*j2)/25*Pi2^2/2 + 12*(j1-j2)/25*Pi1*Pi2 + j3*Pi3^2/2",
        "casimirs":["(Pi1^2+Pi2^2+Pi3^2)/2","(Pi1^2+Pi2^2+Pi3^2-1/4)^2"],
        "equilibrium":["3/10","4/10",0],"noise":[["3*sigma/10","4*sigma/10",0]]}"#;
    let near_sphere = r#"{"name":"n","algebra":"so3","parameters":{"j1":1,"j2":"99999999999999999999/100000000000000000000",
        "j3":"100000001/100000000","c":"7/9","sigma":"3/10"},
        "hamiltonian":"j1*Pi1^2/2 + j2*Pi2^2/2 + j3*Pi3^2/2","casimirs":["c*(Pi1^2+Pi2^2+Pi3^2)/2"],
        "equilibrium":[1,0,0],"noise":[["sigma",0,0]]}"#;
    // A second review: the computed ker G^T is rotated by the gradients'
    // rounding times cond(G), which moves the restricted eigenvalues by up
    // to about 2 theta |B| (now part of the bound). A Casimir whose terms
    // cancel by about 1e4 at a non-dyadic mu_e with a large coupling B_zw,
    // and two nearly dependent Casimirs (cond(G) about 1e6) on so3 + so3.
    let rotated = r#"{"name": "zrot", "algebra": "so3",
        "parameters": {"p": "11/29", "q": "21/31", "m": 5000, "eps1": "1/10000", "beta": "100", "gamma": 1, "e0": "-1/1000000000000", "sigma": "3/10"},
        "hamiltonian": "(eps1*Pi3^2 + 2*beta*(-q*(Pi1-p) + p*(Pi2-q))*(p*(Pi1-p) + q*(Pi2-q))/(p^2+q^2)^2 + gamma*((p*(Pi1-p) + q*(Pi2-q))/(p^2+q^2))^2 + e0*((-q*(Pi1-p) + p*(Pi2-q))/(p^2+q^2))^2)/2",
        "casimirs": ["(Pi1^2 + Pi2^2 + Pi3^2 - (p^2+q^2)*(1 - 1/m))^2/4"],
        "equilibrium": ["p", "q", 0], "noise": [["sigma*p", "sigma*q", 0]]}"#;
    let dependent = r#"{"name": "cond", "algebra": {"coordinates": ["x1","x2","x3","x4","x5","x6"], "structure_constants": [[0,1,2,1],[1,2,0,1],[2,0,1,1],[3,4,5,1],[4,5,3,1],[5,3,4,1]]},
        "parameters": {"p": "25/35", "q": "11/53", "p2": "5/13", "q2": "39/17", "d": "1/1000000", "eps1": "1/100", "beta": "1", "e0": "-1/10000000000000"},
        "hamiltonian": "(eps1*(x3^2 + x6^2 + ((-q2*(x4-p2) + p2*(x5-q2))/(p2^2+q2^2))^2) + 2*beta*((-q*(x1-p) + p*(x2-q))/(p^2+q^2))*((p*(x1-p) + q*(x2-q))/(p^2+q^2)) + ((p*(x1-p) + q*(x2-q))/(p^2+q^2))^2 + ((p2*(x4-p2) + q2*(x5-q2))/(p2^2+q2^2))^2 + e0*((-q*(x1-p) + p*(x2-q))/(p^2+q^2))^2)/2",
        "casimirs": ["(x1^2+x2^2+x3^2 + x4^2+x5^2+x6^2)/2", "(x1^2+x2^2+x3^2 + (1+d)*(x4^2+x5^2+x6^2))/2"],
        "equilibrium": ["p", "q", 0, "p2", "q2", 0], "noise": [["p/3", "q/3", 0, 0, 0, 0]]}"#;
    // A third: Dh = (1e-11, 0, 1) is not in the span of G = (0, 0, 1) (no
    // multipliers: the exact pipeline says inconclusive, the spectrum
    // proved on the imaginary axis), but a relative residual of 1e-11 was
    // taken for rounding. Now the existence of multipliers and the rank of
    // G are decided exactly.
    let residual = r#"{"name": "heis", "algebra": "heisenberg", "parameters": {"eps": "1/100000000000"},
        "hamiltonian": "eps*muX + muZ + 3*muX^2/7 + muY^2/3 + muX*muY/5",
        "equilibrium": [0, 0, 0], "noise": [["1/10", "1/7", 0], [0, 0, "1/3"]]}"#;
    for (name, text) in [
        ("zero gradient", zero_gradient),
        ("near sphere", near_sphere),
        ("rotated kernel", rotated),
        ("dependent", dependent),
        ("residual", residual),
    ] {
        let spec = parse(text);
        let exact = analyse(&spec.system, &spec.settings.pipeline);
        assert_ne!(exact.verdict, Verdict::Stable, "{name}: {}", exact.reason);
        let a = analyse_numeric(&spec.system, &spec.settings.pipeline);
        assert_ne!(a.verdict, Verdict::Stable, "{name}: {} ({:?})", a.reason, a.route);
    }
}

/// `Q` is formed as the paper's formula, without the drift part `P A + A^T
/// P` (zero for an energy–Casimir `P`): formed in floating point, its
/// rounding (about eps |P| |A|) swamped `Sigma^2` when the noise is small
/// beside the drift. A review's case (|A| about 3e13, noise 0.3 mu_e) gave
/// 9.5e3 against the exact pipeline's certified 5.98e7; now the two agree
/// to 1e-6.
#[test]
fn a_large_drift_does_not_swamp_sigma2() {
    let text = r#"{"name": "tol#339", "algebra": "so3", "hamiltonian": "(4230917085412471280242792478015488/4558452880859375)*Pi1*Pi1 + (-3337167325670313264796032565248/11658447265625)*Pi1*Pi2 + (99061177299147114525498430980096/198193603515625)*Pi1*Pi3 + (11447165090824834465117144875008/15773193359375)*Pi2*Pi2 + (-3016285848056518889397691613184/11658447265625)*Pi2*Pi3 + (4000186418193510242437375755026432/4558452880859375)*Pi3*Pi3",
        "equilibrium": ["-18571/54060", "-196/265", "-196/4505"], "noise": [["-18571/180200", "-294/1325", "-294/22525"]]}"#;
    let spec = parse(text);
    let exact = analyse(&spec.system, &spec.settings.pipeline).sigma2().unwrap();
    let a = analyse_numeric(&spec.system, &spec.settings.pipeline);
    assert_eq!(a.verdict, Verdict::Stable, "{}", a.reason);
    let got = a.sigma2.unwrap();
    assert!((got - exact).abs() <= 1e-6 * exact, "{got} vs exact {exact} ({:?})", a.route);
}
