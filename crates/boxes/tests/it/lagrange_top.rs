//! Box certificates of the Lagrange top with fluctuating gravity, against
//! the closed form `Sigma^2 = 4 sigma^2 / (p^2 - 4 mgl I1)`.

use boxes::{certify_box, parse_box_expression, BoxSettings, BoxSymbols, BoxSystem, BoxVerdict, LeafOutcome, ParamBox};
use exact::Rational;
use std::collections::BTreeMap;

fn q(n: i64, d: i64) -> Rational {
    Rational::new(n.into(), d.into())
}

/// `fixtures/lagrange-top-fluctuating-gravity.json` with `p` and `mgl` the
/// box parameters (`I1 = 1`, `I3 = 1/2`, `sigma = 3/10`).
fn top() -> BoxSystem {
    let built = algebra::builtin("se3").unwrap();
    let algebra = built.algebra;
    let names: Vec<String> = algebra.coordinates().to_vec();
    let mut fixed = BTreeMap::new();
    fixed.insert("I1".to_string(), q(1, 1));
    fixed.insert("I3".to_string(), q(1, 2));
    fixed.insert("sigma".to_string(), q(3, 10));
    let s = BoxSymbols::new(&names, &["p".to_string(), "mgl".to_string()], &fixed);
    let e = |t: &str| parse_box_expression(t, &s).unwrap();
    BoxSystem {
        algebra,
        parameters: vec!["p".into(), "mgl".into()],
        hamiltonian: e("(Pi1^2 + Pi2^2)/(2*I1) + Pi3^2/(2*I3) + mgl*Gamma3"),
        casimirs: built.casimirs.iter().map(|t| e(t)).collect(),
        first_integrals: vec![e("Pi3")],
        equilibrium: ["0", "0", "p", "0", "0", "1"].iter().map(|t| e(t)).collect(),
        divisors: vec![],
        noise: vec![["0", "0", "0", "0", "0", "sigma"].iter().map(|t| e(t)).collect()],
    }
}

/// The closed form (the fixture's description; its certificate's exact
/// `Sigma^2` is 9/125 = 0.072 at p = 3, mgl = 1).
fn closed_form(p: f64, mgl: f64) -> f64 {
    4.0 * 0.09 / (p * p - 4.0 * mgl)
}

#[test]
fn the_fast_top_box_is_stable_with_the_closed_form_sup() {
    // p in [5/2, 7/2], mgl in [1/2, 3/2]: p^2 - 4 mgl >= 25/4 - 6 = 1/4 > 0.
    let range = ParamBox { lo: vec![q(5, 2), q(1, 2)], hi: vec![q(7, 2), q(3, 2)] };
    let report = certify_box(&top(), &range, &BoxSettings::default()).unwrap();
    assert_eq!(report.verdict, BoxVerdict::Stable, "{}", report.reason);
    // Sigma^2 falls with p and grows with mgl: the sup is at (5/2, 3/2), 1.44.
    let expected = closed_form(2.5, 1.5);
    assert!((expected - 1.44).abs() < 1e-12);
    let sup = exact::rational_to_f64(&report.sup_sigma2().unwrap());
    assert!(sup >= expected, "the proved bound {sup} is below the true sup {expected}");
    println!("{} sub-boxes, sup {sup} against {expected}", report.leaves.len());
    for leaf in &report.leaves {
        let LeafOutcome::Stable { sigma2_upper, .. } = &leaf.outcome else { panic!() };
        let worst = closed_form(exact::rational_to_f64(&leaf.range.lo[0]), exact::rational_to_f64(&leaf.range.hi[1]));
        assert!(exact::rational_to_f64(sigma2_upper) >= worst);
    }
}

#[test]
fn a_box_across_p_squared_equal_four_mgl_is_not_stable_whole() {
    // mgl in [9/10, 11/10], p in [3/2, 5/2]: p^2 = 4 mgl crosses the box.
    let range = ParamBox { lo: vec![q(3, 2), q(9, 10)], hi: vec![q(5, 2), q(11, 10)] };
    let settings = BoxSettings { max_depth: 8, ..BoxSettings::default() };
    let report = certify_box(&top(), &range, &settings).unwrap();
    assert_ne!(report.verdict, BoxVerdict::Stable, "{}", report.reason);
    for leaf in &report.leaves {
        if matches!(leaf.outcome, LeafOutcome::Stable { .. }) {
            // p^2 > 4 mgl at the sub-box's worst corner (smallest p, largest mgl)
            let (p, m) = (&leaf.range.lo[0], &leaf.range.hi[1]);
            assert!(p * p > Rational::from(4) * m, "a stable sub-box touches p^2 <= 4 mgl: {:?}", leaf.range);
        }
    }
    println!("{} sub-boxes, {:?}", report.leaves.len(), report.verdict);
}

/// The symbolic forms are the exact pipeline's: at points of a box, with
/// the choice the pipeline makes there, `V` and `sign Q` evaluated from the
/// rational functions equal `sign P` and `sign Q` of
/// `generator::analyse` and `generator::generator_form` at that point,
/// exactly. (The top has a first integral and a free multiplier, so this
/// covers the multipliers' solve with a fixed free part.)
#[test]
fn the_symbolic_forms_are_the_pipelines_at_points() {
    let system = top();
    let sym = system.symbolic().unwrap();
    for theta in [[q(3, 1), q(1, 1)], [q(5, 2), q(3, 2)], [q(17, 5), q(2, 3)]] {
        let (s, a) = boxes::certify::analyse_at(&system, &theta).unwrap();
        let stable = a.stable.as_ref().unwrap();
        let variation = a.variation.as_ref().unwrap();
        let r = variation.num_conserved();
        let free: Vec<usize> = (0..r).filter(|j| !variation.range_columns.contains(j)).collect();
        assert!(!free.is_empty(), "the top's multipliers have a free direction");
        let cols = &variation.range_columns;
        let g = &variation.gradients;
        let sub_t = exact::Matrix::from_fn(cols.len(), 6, |j, i| g[(i, cols[j])].clone());
        let choice = boxes::BoxChoice {
            sign: stable.choice.sign,
            multipliers: stable.choice.multipliers.clone(),
            free,
            pivot_rows: sub_t.pivot_columns(),
            m: stable.choice.m.clone(),
        };
        let forms = sym.forms(&choice).unwrap();
        let sign = Rational::from(choice.sign as i64);
        let v = boxes::symbolic::matrix_at(&forms.v, 6, &theta).unwrap();
        assert_eq!(v, stable.choice.p.scale(&sign));
        let q_pipeline = generator::generator_form(&generator::linearise(&s), &stable.choice.p).q.scale(&sign);
        assert_eq!(boxes::symbolic::matrix_at(&forms.q, 6, &theta).unwrap(), q_pipeline);
        for (l, m) in forms.multipliers.iter().zip(&stable.choice.multipliers) {
            assert_eq!(boxes::symbolic::value_at(l, 6, &theta).unwrap(), *m);
        }
    }
}
