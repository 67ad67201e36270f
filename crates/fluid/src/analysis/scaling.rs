//! The noise divided by a power of two before the pipeline runs, and every
//! `Sigma^2` multiplied back (exactly, in binary floating point).

use super::*;

/// The problem with its noise divided by `2^e` (exactly), and `e`: the
/// exponent of the largest noise value on the samples and the nodes of
/// `fine` (0 for no noise).
pub(super) fn normalise_noise(problem: &FluidProblem, fine: &YGrid) -> (FluidProblem, i32) {
    let e = noise_exponent(&problem.profile, fine.nodes());
    if e == 0 {
        return (problem.clone(), 0);
    }
    (FluidProblem { profile: problem.profile.with_noise_factor(pow2(-e)), ..problem.clone() }, e)
}

pub(super) use numerics::scaling::pow2;
use numerics::scaling::{exponent_of, Rescaling};

/// The exponent `e` with `max |eta_k| / 2^e` in `[1/2, 1)` over the samples
/// and the nodes (0 for no noise).
pub(super) fn noise_exponent(profile: &Profile, nodes: &[f64]) -> i32 {
    let ys = profile.samples(crate::constants::PROFILE_SAMPLES);
    let max = profile
        .eta
        .iter()
        .flat_map(|[e, _]| ys.iter().chain(nodes).map(move |y| e.eval(*y).abs()))
        .fold(0.0f64, f64::max);
    exponent_of(max)
}

/// Multiply every `Sigma^2` of an analysis of the normalised noise by
/// `4^e` (and the noise residuals by `2^e`), and refuse what no double holds.
pub(super) fn rescale(a: FluidAnalysis, e: i32) -> FluidAnalysis {
    let r = Rescaling::new(e);
    let f = r.up();
    let sq = |x: f64| r.square(x);
    // An upper bound must stay one (an overflow is caught by the headline's
    // range check below: every bound is at most the headline's).
    let sq_up = |x: f64| r.square_bound(x).unwrap_or(f64::INFINITY);
    let sq_opt = |x: Option<f64>| x.map(sq);
    let paper_bound = a.paper_bound.map(sq).filter(|b| b.is_finite());
    let headline = a.sigma2_upper.or(a.sigma2);
    if let Some(h) = headline {
        let not_representable = r.out_of_range(h);
        if let Some(reason) = not_representable {
            return FluidAnalysis {
                paper_bound,
                ..FluidAnalysis::without_certificate(Verdict::Inconclusive, reason, a.form, 0.0)
            };
        }
    }
    FluidAnalysis {
        sigma2: sq_opt(a.sigma2),
        sigma2_upper: a.sigma2_upper.map(sq_up),
        modes: a
            .modes
            .into_iter()
            .map(|m| ModeResult { sigma2: sq(m.sigma2), sigma2_upper: m.sigma2_upper.map(sq_up), ..m })
            .collect(),
        convergence: a
            .convergence
            .into_iter()
            .map(|r| ConvergenceRow {
                sigma2: sq_opt(r.sigma2),
                sigma2_paper_choice: sq_opt(r.sigma2_paper_choice),
                ..r
            })
            .collect(),
        paper_bound,
        paper_choice_sigma2: sq_opt(a.paper_choice_sigma2),
        shift_curve: a.shift_curve.into_iter().map(|(c, s)| (c, sq(s))).collect(),
        compressible: a.compressible.map(|c| CompressibleReport {
            noise_residuals: c.noise_residuals.iter().map(|r| r * f).collect(),
            incompressible_sigma2: sq_opt(c.incompressible_sigma2),
            generator: c.generator.map(|g| GeneratorReport {
                continuum_bound: g.continuum_bound.map(sq_up),
                casimir_defect: g.casimir_defect.into_iter().map(|(n, d)| (n, sq(d))).collect(),
                discrete_sde: g.discrete_sde.map(|(m, d)| (m, sq(d))),
                ..g
            }),
            ..c
        }),
        ..a
    }
}
