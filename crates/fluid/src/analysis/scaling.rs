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

pub(super) use crate::banded::pow2;

/// The exponent `e` with `max |eta_k| / 2^e` in `[1/2, 1)` over the samples
/// and the nodes (0 for no noise).
pub(super) fn noise_exponent(profile: &Profile, nodes: &[f64]) -> i32 {
    let ys = profile.samples(crate::constants::PROFILE_SAMPLES);
    let max = profile
        .eta
        .iter()
        .flat_map(|[e, _]| ys.iter().chain(nodes).map(move |y| e.eval(*y).abs()))
        .fold(0.0f64, f64::max);
    if !(max.is_finite() && max > 0.0) {
        return 0;
    }
    // floor(log2 max) + 1, exactly from the bits for normal numbers
    let exponent = if max >= f64::MIN_POSITIVE { ((max.to_bits() >> 52) & 0x7ff) as i32 - 1022 } else { -1022 };
    exponent.clamp(-1000, 1000)
}

/// Multiply every `Sigma^2` of an analysis of the normalised noise by
/// `4^e` (and the noise residuals by `2^e`), and refuse what no double holds.
pub(super) fn rescale(a: FluidAnalysis, e: i32) -> FluidAnalysis {
    let f = pow2(e);
    let sq = |x: f64| x * f * f;
    // An upper bound must stay one: round a subnormal result up.
    let sq_up = |x: f64| {
        let y = x * f * f;
        if x > 0.0 && y < f64::MIN_POSITIVE {
            f64::MIN_POSITIVE
        } else {
            y
        }
    };
    let sq_opt = |x: Option<f64>| x.map(sq);
    let paper_bound = a.paper_bound.map(sq).filter(|b| b.is_finite());
    let headline = a.sigma2_upper.or(a.sigma2);
    if let Some(h) = headline {
        let y = h * f * f;
        let not_representable = if !y.is_finite() {
            Some(format!(
                "Sigma^2 is about 10^{:.1} with this noise, beyond the largest double (1.8e308): rescale time or the noise amplitudes",
                h.log10() + 2.0 * e as f64 * std::f64::consts::LOG10_2
            ))
        } else if h > 0.0 && y < f64::MIN_POSITIVE {
            Some(format!(
                "Sigma^2 is about 10^{:.1} with this noise, below the smallest normal double (2.2e-308): rescale time or the noise amplitudes",
                h.log10() + 2.0 * e as f64 * std::f64::consts::LOG10_2
            ))
        } else {
            None
        };
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
