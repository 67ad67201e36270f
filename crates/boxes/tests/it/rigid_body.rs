//! Box certificates of the free rigid body about its major axis, against
//! the closed form.

use boxes::{certify_box, parse_box_expression, BoxSettings, BoxSymbols, BoxSystem, BoxVerdict, LeafOutcome, ParamBox};
use exact::Rational;
use std::collections::BTreeMap;

fn q(n: i64, d: i64) -> Rational {
    Rational::new(n.into(), d.into())
}

/// The rigid body `h = sum Pi_i^2 / (2 I_i)` about `Pi = (1, 0, 0)` with
/// noise `sigma e_1`, `I1 = 3` and `sigma = 3/10` fixed, `I2` and `I3` the
/// box parameters.
fn rigid_body() -> BoxSystem {
    let algebra = algebra::builtin("so3").unwrap().algebra;
    let names: Vec<String> = algebra.coordinates().to_vec();
    let mut fixed = BTreeMap::new();
    fixed.insert("I1".to_string(), q(3, 1));
    fixed.insert("sigma".to_string(), q(3, 10));
    let s = BoxSymbols::new(&names, &["I2".to_string(), "I3".to_string()], &fixed);
    let e = |t: &str| parse_box_expression(t, &s).unwrap();
    BoxSystem {
        algebra,
        parameters: vec!["I2".into(), "I3".into()],
        hamiltonian: e("Pi1^2/(2*I1) + Pi2^2/(2*I2) + Pi3^2/(2*I3)"),
        casimirs: vec![e("(Pi1^2 + Pi2^2 + Pi3^2)/2")],
        first_integrals: vec![],
        equilibrium: vec![e("1"), e("0"), e("0")],
        divisors: vec![],
        noise: vec![vec![e("sigma"), e("0"), e("0")]],
    }
}

/// `Sigma^2 = sigma^2 (max(a, b) / min(a, b) - 1)`, `a = 1/I2 - 1/I1`,
/// `b = 1/I3 - 1/I1` (the rigid body's closed form; `generator`'s doctest
/// checks it at I = (3, 2, 1): 0.27).
fn closed_form(i2: f64, i3: f64) -> f64 {
    let a = 1.0 / i2 - 1.0 / 3.0;
    let b = 1.0 / i3 - 1.0 / 3.0;
    0.09 * (a.max(b) / a.min(b) - 1.0)
}

#[test]
fn a_box_about_the_major_axis_is_stable_with_the_closed_form_sup() {
    let range = ParamBox { lo: vec![q(3, 2), q(4, 5)], hi: vec![q(5, 2), q(6, 5)] };
    let report = certify_box(&rigid_body(), &range, &BoxSettings::default()).unwrap();
    assert_eq!(report.verdict, BoxVerdict::Stable, "{}", report.reason);
    // b > a on the whole box (b >= 1/1.2 - 1/3 = 1/2 > 1/3 >= a), so
    // Sigma^2 = 0.09 (b/a - 1) grows with I2 and falls with I3: its sup is
    // at the corner (5/2, 4/5), 0.09 (55/4 - 1) = 1.1475.
    let sup = exact::rational_to_f64(&report.sup_sigma2().unwrap());
    let expected = closed_form(2.5, 0.8);
    assert!((expected - 1.1475).abs() < 1e-12);
    assert!(sup >= expected, "the proved bound {sup} is below the true sup {expected}");
    assert!(sup <= expected * 1.002, "the proved bound {sup} is loose against {expected}");
    for leaf in &report.leaves {
        let LeafOutcome::Stable { sigma2_upper, sampled, .. } = &leaf.outcome else { panic!("undecided leaf") };
        // every sub-box's bound is above the closed form at its worst corner
        let worst = closed_form(exact::rational_to_f64(&leaf.range.hi[0]), exact::rational_to_f64(&leaf.range.lo[1]));
        assert!(exact::rational_to_f64(sigma2_upper) >= worst);
        assert!((sampled - worst).abs() <= 1e-9 * worst);
    }
    println!("{} sub-boxes, sup {sup}", report.leaves.len());
}

#[test]
fn a_box_across_i2_equal_i1_is_not_stable_whole() {
    // I2 from 2 to 4 crosses I1 = 3: beyond it the axis is intermediate
    // (linearly unstable) and at I2 = 3 the form is degenerate.
    let range = ParamBox { lo: vec![q(2, 1), q(4, 5)], hi: vec![q(4, 1), q(6, 5)] };
    let settings = BoxSettings { max_depth: 8, ..BoxSettings::default() };
    let report = certify_box(&rigid_body(), &range, &settings).unwrap();
    assert_eq!(report.verdict, BoxVerdict::PartlyStable, "{}", report.reason);
    for leaf in &report.leaves {
        match &leaf.outcome {
            LeafOutcome::Stable { .. } => {
                assert!(leaf.range.hi[0] < q(3, 1), "a stable sub-box reaches I2 >= I1: {:?}", leaf.range)
            }
            // I2 > I1 > I3: the intermediate axis, a real pair of
            // eigenvalues; at I2 = I1 the spectrum is on the axis, so no
            // sub-box proved unstable may touch it.
            LeafOutcome::LinearlyUnstable { .. } => {
                assert!(leaf.range.lo[0] > q(3, 1), "an unstable sub-box reaches I2 <= I1: {:?}", leaf.range)
            }
            LeafOutcome::Undecided { .. } => {}
            other => panic!("mu_e is an equilibrium and the noise keeps it: {other:?}"),
        }
    }
    // Depth 8 is 4 halvings of each side: the sub-boxes touching I2 = 3
    // (a strip of width 2 * 2/16) stay undecided, 1/8 of the box, and the
    // rest is proved on each side: 7/16 stable, 7/16 unstable.
    let fraction = |v: exact::Rational| v / range.volume();
    assert_eq!(fraction(report.undecided_volume()), q(1, 8));
    assert_eq!(fraction(report.unstable_volume()), q(7, 16));
}

#[test]
fn a_box_about_the_intermediate_axis_is_linearly_unstable_throughout() {
    // I2 in [7/2, 4] > I1 = 3 > I3 in [4/5, 6/5]
    let range = ParamBox { lo: vec![q(7, 2), q(4, 5)], hi: vec![q(4, 1), q(6, 5)] };
    let report = certify_box(&rigid_body(), &range, &BoxSettings::default()).unwrap();
    assert_eq!(report.verdict, BoxVerdict::LinearlyUnstable, "{}", report.reason);
    assert!(report.sup_sigma2().is_none());
}
