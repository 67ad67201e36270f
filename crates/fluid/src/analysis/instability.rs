//! The linear-instability test of a profile that admits no definite form:
//! growth rates of the drift at two resolutions, refined by doubling where
//! they have not converged (a critical layer thinner than the grid), up to
//! [`crate::constants::INSTABILITY_MAX_NY`], whatever the spec's `ny`.

use super::*;

/// The largest growth rate `k max Im eig(R)` of mode `k` at resolution `ny`.
pub(super) fn growth_rate(profile: &Profile, ny: usize, k: f64) -> Option<f64> {
    let grid = YGrid::new(profile.boundary, profile.interval.0, profile.interval.1, ny);
    let coef = profile.coefficients(&grid);
    let r = Mode::new(&grid, k).drift_matrix(&coef);
    if r.iter().any(|x| !x.is_finite()) {
        return None; // U or k beyond the range of doubles: no evidence
    }
    let n = r.nrows();
    let m = faer::Mat::<f64>::from_fn(n, n, |i, j| r[(i, j)]);
    let values = m.eigenvalues().ok()?;
    // A = -ik R: Re(-ik lambda) = k Im(lambda)
    let rate = values.iter().map(|z| k * z.im).fold(f64::NEG_INFINITY, f64::max);
    rate.is_finite().then_some(rate)
}

pub(super) fn inconclusive_or_unstable(
    problem: &FluidProblem,
    settings: &FluidSettings,
    reason: String,
    form: FormSummary,
    paper_bound: f64,
    paper_choice_sigma2: Option<f64>,
    shift_curve: Vec<(f64, f64)>,
    progress: &Progress,
) -> FluidAnalysis {
    let profile = &problem.profile;
    let step = crate::grid::ELEMENT_DEGREE;
    let start = settings.instability_ny - settings.instability_ny % step;
    let max_ny = (crate::constants::INSTABILITY_MAX_NY as usize).max(start);
    let ks = wavenumbers(problem);
    let u_scale = profile
        .samples(crate::constants::SCALE_SAMPLES)
        .iter()
        .map(|y| profile.u[0].eval(*y).abs())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let rates: Vec<Option<UnstableMode>> = ks
        .par_iter()
        .map(|&(m, k)| {
            mode_step(progress, || {
                // A growth rate is evidence when it is far above rounding
                // (relative to k max|U|) and converged between two grids, the
                // finer twice the coarser. Start at instability_ny and its half;
                // double while a rate above the floor has not converged.
                let floor = crate::constants::INSTABILITY_FLOOR * k * u_scale;
                let half = (start / 2 - (start / 2) % step).max(16);
                let mut coarse_rate = growth_rate(profile, half, k)?;
                let mut ny = start;
                loop {
                    let fine = growth_rate(profile, ny, k)?;
                    if fine > floor
                        && coarse_rate > floor
                        && (fine - coarse_rate).abs() <= crate::constants::INSTABILITY_AGREEMENT * fine
                    {
                        return Some(UnstableMode { m, k, growth_rate: fine, growth_rate_coarse: coarse_rate, ny });
                    }
                    if fine <= floor && coarse_rate <= floor || 2 * ny > max_ny {
                        return None;
                    }
                    coarse_rate = fine;
                    ny *= 2;
                }
            })
        })
        .collect();
    let instability = rates.into_iter().flatten().max_by(|a, b| a.growth_rate.total_cmp(&b.growth_rate));
    let (verdict, reason) = match &instability {
        Some(u) => (
            Verdict::LinearlyUnstable,
            format!(
                "x-mode m = {} (k = {:.6}) grows at rate {:.6e} (ny = {}; {:.6e} at half the resolution); {reason}",
                u.m, u.k, u.growth_rate, u.ny, u.growth_rate_coarse
            ),
        ),
        None => (Verdict::Inconclusive, reason),
    };
    FluidAnalysis {
        verification: (verdict == Verdict::LinearlyUnstable).then_some(VerificationLevel::Float),
        paper_choice_sigma2,
        shift_curve,
        instability,
        ..FluidAnalysis::without_certificate(verdict, reason, form, paper_bound)
    }
}
