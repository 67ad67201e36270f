//! The case where `Q` does not depend on `M`: the free multipliers chosen
//! by minimising the restricted `lambda_max(Z^T sQ Z, Z^T sP Z)`, then `K`
//! constructed at them ([`super::at_multipliers`]).

use super::at_multipliers::{at_multipliers, AtMultipliers};
use super::{
    congruent, direction_scales, minimise_normalised, orthonormalising, signed, top_generalized, AffinePencil, Forms,
    OptimiseSettings, Optimum, SIMPLE_DENOMINATOR,
};
use crate::form::{generator_form, GeneratorForm};
use crate::growth::{condition_number, GrowthConstant};
use crate::linearise::Linearisation;
use casimir::{CasimirChoice, SecondVariation, Sign};
use exact::{Matrix, Rational};
use nalgebra::DMatrix;
use num_traits::Zero;

/// The case where `Q` does not depend on `M`, with the generator forms
/// affine in the multipliers alone: [`optimise_restricted`].
pub(super) fn optimise_q_free_of_m(
    variation: &SecondVariation,
    linearisation: &Linearisation,
    (first, first_form, first_growth): (&CasimirChoice, &GeneratorForm, &GrowthConstant),
    t0: &[f64],
    t_dirs: &[Matrix],
    settings: &OptimiseSettings,
) -> Option<Optimum> {
    // The whole generator form of P = B(t) + Y K Y^T is then that of
    // B(t), affine in t: the first choice's form plus (t - t0) times the
    // forms of the directions, exact, with no products per candidate.
    // (Its drift part P A + A^T P does not depend on K when Y^T A = 0,
    // which conservation implies; checked, else formed afresh.)
    let t_forms: Vec<GeneratorForm> = t_dirs.iter().map(|d| generator_form(linearisation, d)).collect();
    let y = variation.independent_gradients();
    let drift_free = y.transpose().mul(&linearisation.a).is_zero();
    let form_at = |t: &[Rational]| -> GeneratorForm {
        let mut form = first_form.clone();
        for ((ti, t0i), d) in t.iter().zip(&first.family_parameters).zip(&t_forms) {
            let step = ti - t0i;
            if !step.is_zero() {
                form.q.add_scaled_assign(&step, &d.q);
                form.drift_residual.add_scaled_assign(&step, &d.drift_residual);
                form.paper_formula.add_scaled_assign(&step, &d.paper_formula);
            }
        }
        form
    };
    let forms = Forms { at: &form_at, first: first_form, t_dirs: &t_forms, drift_free, linearisation };
    optimise_restricted(variation, &forms, first, first_growth, t0, t_dirs, settings)
}

/// The case where `Q` does not depend on `M`: minimise the restricted
/// `lambda_max(Z^T sQ Z, Z^T sP Z)` over the free multipliers, then
/// construct `K` for a target just above that infimum.
///
/// The restricted infimum over the multipliers may be approached at the
/// edge of the region where `Z^T sP Z` is definite, where `P` is singular.
/// Then the multipliers are chosen by the same minimisation with the
/// condition number of `Z^T sP Z` limited (a convex constraint), tightened
/// until `cond(P)` is within the limit; the certificate states the gap that
/// costs.
fn optimise_restricted(
    variation: &SecondVariation,
    forms: &Forms,
    first: &CasimirChoice,
    first_growth: &GrowthConstant,
    t0: &[f64],
    t_dirs: &[Matrix],
    settings: &OptimiseSettings,
) -> Option<Optimum> {
    let f = t0.len();
    let k = variation.kernel.ncols();
    let cond_limit = 1e8f64.max(10.0 * first_growth.condition_number.min(1e300));
    if f == 0 || k == 0 {
        let found =
            at_multipliers(variation, forms, first, first_growth, &first.family_parameters, cond_limit, settings)?;
        let infimum = found.restricted_max.max(0.0);
        return Some(found.into_optimum(first, forms.first, first_growth, infimum, false, f, settings));
    }
    // 1. The multipliers: the restricted infimum over t, in orthonormal
    // coordinates of ker G^T (`Z R^{-1}`; the exact kernel basis can be
    // badly scaled, and the values do not depend on the basis).
    let search =
        RestrictedSearch::new(Context { variation, forms, first, first_growth, settings, cond_limit }, t0, t_dirs);
    let (t_inf, value, on_edge) = minimise_normalised(&search.pencil, t0, &search.scales, settings.max_iterations);
    let found = search.conditioned(&t_inf);
    // The infimum estimate: the value at the unconstrained minimiser when P
    // is resolved there (cond <= 1e12); at a nearly singular point the
    // floating-point lambda_max is not to be trusted, and the estimate is
    // the best certified value (flagged: the infimum may be lower).
    const RESOLVED: f64 = 1e12;
    let found = found?;
    let resolved = search.restricted_condition(&t_inf) <= RESOLVED;
    let infimum = if resolved { value } else { found.sigma2() };
    let mut optimum =
        found.into_optimum(first, forms.first, first_growth, infimum.max(0.0), on_edge || !resolved, f, settings);
    // Where the infimum was found, for a certified bound over the family
    // (tried even where P is nearly singular: every claim is exact).
    optimum.infimum_parameters = Some(t_inf);
    Some(optimum)
}

/// What the construction at given multipliers needs, fixed for the search.
struct Context<'a> {
    variation: &'a SecondVariation,
    forms: &'a Forms<'a>,
    first: &'a CasimirChoice,
    first_growth: &'a GrowthConstant,
    settings: &'a OptimiseSettings,
    /// The largest `cond(P)` accepted.
    cond_limit: f64,
}

/// The compression `R^{-T} (s Z^T M Z) R^{-1}` of `sM` to `ker G^T`, in
/// the orthonormal coordinates `Z R^{-1}`.
struct Compression<'a> {
    /// The exact kernel basis `Z`.
    z: &'a Matrix,
    /// `Z^T`, exactly.
    zt: Matrix,
    /// `R^{-1}`, with `Z R^{-1}` orthonormal.
    r_inv: DMatrix<f64>,
    /// The sign of `P`.
    sign: Sign,
}

impl Compression<'_> {
    /// `R^{-T} (s Z^T M Z) R^{-1}` (symmetrised).
    fn of(&self, m: &Matrix) -> DMatrix<f64> {
        congruent(&signed(&self.zt.mul(m).mul(self.z), self.sign), &self.r_inv)
    }
}

/// The restricted pencil `(Z^T sP Z, Z^T sQ Z)(t)` in orthonormal
/// coordinates of `ker G^T`, and the search over `t` for multipliers where
/// `K` can be built with `cond(P)` within the limit.
struct RestrictedSearch<'a> {
    c: Context<'a>,
    /// The starting multipliers (the first choice's).
    t0: &'a [f64],
    /// The compression to `ker G^T`.
    restrict: Compression<'a>,
    /// The restricted pencil, affine in `t`.
    pencil: AffinePencil,
    /// The scales of the multiplier directions.
    scales: Vec<f64>,
    /// `cond(Z^T sP Z)` at the starting multipliers.
    start_condition: f64,
}

impl<'a> RestrictedSearch<'a> {
    /// The restricted pencil, affine in `t`, with its directions' scales.
    fn new(c: Context<'a>, t0: &'a [f64], t_dirs: &[Matrix]) -> Self {
        let (variation, forms) = (c.variation, c.forms);
        let f = t0.len();
        let z = &variation.kernel;
        let restrict = Compression { z, zt: z.transpose(), r_inv: orthonormalising(z), sign: c.first.sign };
        let zero_t = vec![Rational::zero(); f];
        let base0 = variation.base(&variation.family.particular);
        let pencil = AffinePencil {
            p0: restrict.of(&base0),
            q0: restrict.of(&(forms.at)(&zero_t).q),
            p_dirs: t_dirs.iter().map(|m| restrict.of(m)).collect(),
            q_dirs: forms.t_dirs.iter().map(|d| restrict.of(&d.q)).collect(),
            cond_limit: f64::INFINITY,
        };
        let (p_start, q_start) = pencil.at(t0);
        let scales = direction_scales(&p_start, &q_start, &pencil.p_dirs, &pencil.q_dirs);
        let start_condition = condition_number(&pencil.at(t0).0);
        RestrictedSearch { c, t0, restrict, pencil, scales, start_condition }
    }

    /// The construction at rational multipliers `t`.
    fn at(&self, t: &[Rational]) -> Option<AtMultipliers> {
        let c = &self.c;
        at_multipliers(c.variation, c.forms, c.first, c.first_growth, t, c.cond_limit, c.settings)
    }

    /// The condition number of the compression of sP to ker G^T in
    /// orthonormal coordinates is a lower bound on cond(sP) (its eigenvalues
    /// interlace): a cheap screen before the exact construction.
    fn restricted_condition(&self, t: &[f64]) -> f64 {
        condition_number(&self.pencil.at(t).0)
    }

    /// The restricted `lambda_max` at rational multipliers.
    fn restricted_max(&self, t: &[Rational]) -> Option<f64> {
        let variation = self.c.variation;
        let b = variation.base(&variation.family.at(t));
        top_generalized(&self.restrict.of(&b), &self.restrict.of(&(self.c.forms.at)(t).q)).ok().map(|(l, _)| l)
    }

    /// The construction at rational multipliers near t (t itself if the
    /// screen lets it through).
    fn candidate(&self, t: &[f64]) -> Option<AtMultipliers> {
        if self.restricted_condition(t) > self.c.cond_limit {
            return None;
        }
        let v = self.pencil.value(t)?;
        let limit = v + 1e-12 * v.abs().max(self.c.first_growth.sigma2);
        let (variation, sign) = (self.c.variation, self.c.first.sign);
        let restricted_max = |t: &[Rational]| self.restricted_max(t);
        let t_rational = casimir::round_family_parameters(
            variation,
            sign,
            t,
            &self.scales,
            SIMPLE_DENOMINATOR,
            Some((&restricted_max, limit)),
        )
        .or_else(|| casimir::round_family_parameters(variation, sign, t, &self.scales, SIMPLE_DENOMINATOR, None))?;
        self.at(&t_rational)
    }

    /// The minimiser with cond(Z^T sP Z) <= limit (a convex constraint).
    fn limited(&self, limit: f64) -> Vec<f64> {
        let pencil = AffinePencil {
            cond_limit: limit.max(2.0 * self.start_condition),
            p0: self.pencil.p0.clone(),
            q0: self.pencil.q0.clone(),
            p_dirs: self.pencil.p_dirs.clone(),
            q_dirs: self.pencil.q_dirs.clone(),
        };
        minimise_normalised(&pencil, self.t0, &self.scales, self.c.settings.max_iterations).0
    }

    /// The best construction found (lowest `Sigma^2`, preferring one with
    /// `cond(P)` within the limit): at the unconstrained minimiser `t_inf`
    /// first, then at condition-limited minimisers, then at the start.
    fn conditioned(&self, t_inf: &[f64]) -> Option<AtMultipliers> {
        let cond_limit = self.c.cond_limit;
        let mut found: Option<AtMultipliers> = None;
        let keep = |here: AtMultipliers, found: &mut Option<AtMultipliers>| -> bool {
            let conditioned = here.best.is_some();
            if found.as_ref().is_none_or(|b| here.sigma2() < b.sigma2()) {
                *found = Some(here);
            }
            conditioned
        };
        // The unconstrained minimiser first; where P is nearly singular there,
        // the minimiser with cond(Z^T sP Z) limited to 1e-1, 1e-2, ... of the
        // limit (the rest of P adds to the condition number), refined by
        // geometric bisection between the last limit that failed and the first
        // that succeeded; the starting multipliers last.
        if !self.candidate(t_inf).is_some_and(|here| keep(here, &mut found)) {
            let mut failed = cond_limit;
            for fraction in [1e-1, 1e-2, 1e-3, 1e-4, 1e-5] {
                let limit = fraction * cond_limit;
                if limit < 2.0 * self.start_condition {
                    break;
                }
                if self.candidate(&self.limited(limit)).is_some_and(|here| keep(here, &mut found)) {
                    let (mut lo, mut hi) = (limit, failed);
                    for _ in 0..3 {
                        let mid = (lo * hi).sqrt();
                        if self.candidate(&self.limited(mid)).is_some_and(|here| keep(here, &mut found)) {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    break;
                }
                failed = limit;
            }
            if found.as_ref().is_none_or(|b| b.best.is_none()) {
                if let Some(here) = self.at(&self.c.first.family_parameters) {
                    keep(here, &mut found);
                }
            }
        }
        found
    }
}
