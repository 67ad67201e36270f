//! The general case, where `Q` depends on the Casimir Hessian `M`: the
//! ellipsoid method over `theta = (t, K)`.

use super::{
    casimir_directions, direction_scales, exact_choice, minimise_normalised, signed, AffinePencil, OptimiseSettings,
    Optimum, SIMPLE_DENOMINATOR,
};
use crate::form::generator_form;
use crate::growth::{growth_constant, GrowthConstant};
use crate::linearise::Linearisation;
use casimir::{CasimirChoice, SecondVariation};
use exact::Matrix;
use nalgebra::DMatrix;

/// Minimise `lambda_max(sQ, sP)` over `theta = (t, K entries)` (the
/// directions normalised in the metric of the first `P`), then make the
/// minimiser exact: `None` when that fails or does worse than the first
/// choice.
pub(super) fn optimise_over_t_and_m(
    variation: &SecondVariation,
    linearisation: &Linearisation,
    (first, first_growth): (&CasimirChoice, &GrowthConstant),
    base0: &Matrix,
    t_dirs: &[Matrix],
    t0: Vec<f64>,
    settings: &OptimiseSettings,
) -> Option<Optimum> {
    let sign = first.sign;
    let f = variation.family.directions.len();
    let cols = &variation.range_columns;
    let rk = cols.len();
    let lq = |p: &Matrix| generator_form(linearisation, p).q;
    let k_dirs = casimir_directions(variation);
    // K of the first choice, on the independent columns.
    let k_first = Matrix::from_fn(rk, rk, |a, b| first.m[(cols[a], cols[b])].clone());

    // General case: Q depends on K. Minimise over theta = (t, K entries),
    // the directions normalised in the metric of the first P.
    let mut p_dirs: Vec<DMatrix<f64>> = t_dirs.iter().map(|d| signed(d, sign)).collect();
    let mut q_dirs: Vec<DMatrix<f64>> = t_dirs.iter().map(|d| signed(&lq(d), sign)).collect();
    for (_, _, d) in &k_dirs {
        p_dirs.push(signed(d, sign));
        q_dirs.push(signed(&lq(d), sign));
    }
    let pencil = AffinePencil {
        p0: signed(base0, sign),
        q0: signed(&lq(base0), sign),
        p_dirs,
        q_dirs,
        cond_limit: f64::INFINITY,
    };
    let mut theta0 = t0.clone();
    for (a, b, _) in &k_dirs {
        theta0.push(exact::rational_to_f64(&k_first[(*a, *b)]));
    }
    let (p_start, q_start) = pencil.at(&theta0);
    let scales = direction_scales(&p_start, &q_start, &pencil.p_dirs, &pencil.q_dirs);
    let (theta, value, on_boundary) = minimise_normalised(&pencil, &theta0, &scales, settings.max_iterations);
    let infimum = value.max(0.0);
    let t = casimir::round_family_parameters(variation, sign, &theta[..f], &scales[..f], SIMPLE_DENOMINATOR, None)?;
    let mut k = Matrix::zeros(rk, rk);
    for (i, (a, b, _)) in k_dirs.iter().enumerate() {
        let r = exact::decimal_near(theta[f + i], 15)?;
        k[(*a, *b)] = r.clone();
        k[(*b, *a)] = r;
    }
    let choice = exact_choice(variation, sign, t, &k, first.relative_margin)?;
    let form = generator_form(linearisation, &choice.p);
    let growth = growth_constant(&choice.p, &form.q, sign).ok()?;
    if growth.sigma2 > first_growth.sigma2 {
        return None;
    }
    Some(Optimum {
        choice,
        form,
        attained: !on_boundary,
        within_tolerance: !on_boundary,
        growth,
        infimum,
        infimum_lower_bound: None,
        infimum_witness: None,
        infimum_parameters: None,
        q_depends_on_m: true,
        method: "ellipsoid over (t, M)",
    })
}
