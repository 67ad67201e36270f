//! The linear-instability test of a profile that admits no definite form:
//! growth rates of the drift at two resolutions, refined by doubling where
//! they have not converged (a critical layer thinner than the grid).
//!
//! Each grid gives one candidate eigenvalue `c` of the drift `R` (a phase
//! speed; the mode grows at `k Im c`). Up to
//! [`crate::constants::INSTABILITY_MAX_NY`] (or `instability_ny`, if
//! larger) all eigenvalues are computed (dense) and the candidate is the
//! one of largest `Im c`; beyond it, up to
//! [`crate::constants::INSTABILITY_TRACK_MAX_NY`], the candidate is the
//! eigenvalue nearest the last candidate above the floor, by inverse
//! iteration on the banded pencil ([`super::shift_invert`]). Evidence is
//! the same either way: two grids, the finer twice the coarser, whose
//! candidates' rates are above the floor and agree to
//! [`crate::constants::INSTABILITY_AGREEMENT`]. A tracked candidate is an
//! eigenvalue of that grid's drift (to a relative residual of `1e-9`), not
//! necessarily the one of largest `Im c` there, so the rate reported is
//! that of a growing mode, a lower bound of the grid's largest.
//!
//! Why tracking: the weakly growing modes near a neutral wavenumber need
//! fine grids. The Bickley jet `sech^2 y` on `[-8, 8]` at `k = 1.9`
//! (measured with `examples/instability_rates.rs`): the largest
//! `k Im c` is 0.0351 at ny = 128, 0 at 256 (the mode is not resolved; no
//! other eigenvalue is complex), 0.0175 at 512, 0.02267 at 1024,
//! 0.0220931 at 2048 and 0.0220919 at 4096 (shooting: 0.02209194), with
//! every other eigenvalue real at every ny: no spurious eigenvalue, but
//! agreement only from 2048 to 4096, where the dense eigenvalues take 4 s
//! and 33 s and the banded inverse iteration milliseconds.

use super::shift_invert::nearest_eigenvalue;
use super::*;
use nalgebra::Complex;

/// The eigenvalue of largest imaginary part of the drift `R` of mode `k`
/// at resolution `ny` (all eigenvalues, dense).
pub(super) fn dense_candidate(profile: &Profile, ny: usize, k: f64) -> Option<Complex<f64>> {
    let grid = YGrid::new(profile.boundary, profile.interval.0, profile.interval.1, ny);
    let coef = profile.coefficients(&grid);
    let r = Mode::new(&grid, k).drift_matrix(&coef);
    if r.iter().any(|x| !x.is_finite()) {
        return None; // U or k beyond the range of doubles: no evidence
    }
    let n = r.nrows();
    let m = faer::Mat::<f64>::from_fn(n, n, |i, j| r[(i, j)]);
    let values = m.eigenvalues().ok()?;
    let best = values.iter().map(|z| Complex::new(z.re, z.im)).max_by(|a, b| a.im.total_cmp(&b.im))?;
    (best.re.is_finite() && best.im.is_finite()).then_some(best)
}

/// The eigenvalue of the drift of mode `k` at resolution `ny` nearest the
/// phase speed `seed` ([`nearest_eigenvalue`]).
fn tracked_candidate(profile: &Profile, ny: usize, k: f64, seed: Complex<f64>) -> Option<Complex<f64>> {
    let grid = YGrid::new(profile.boundary, profile.interval.0, profile.interval.1, ny);
    let coef = profile.coefficients(&grid);
    if coef.u.iter().chain(&coef.upp).any(|x| !x.is_finite()) || !(k * k).is_finite() {
        return None;
    }
    nearest_eigenvalue(&grid, &coef, k, seed).map(|(c, _)| c)
}

/// The search of one x-mode (module docs): the grids from `half` and
/// `start` doubling, dense up to `dense_max`, tracked up to `track_max`.
/// Returns the evidence, if the search converged, and its record.
pub(super) fn search_mode(
    profile: &Profile,
    m: usize,
    k: f64,
    floor: f64,
    (half, start): (usize, usize),
    dense_max: usize,
    track_max: usize,
) -> (Option<UnstableMode>, ModeSearch) {
    let mut grids = vec![];
    // the last candidate whose rate was above the floor: the seed of the
    // tracked grids
    let mut seed: Option<Complex<f64>> = None;
    let mut solve = |ny: usize, seed: Option<Complex<f64>>| {
        let tracked = ny > dense_max;
        let c = match (tracked, seed) {
            (false, _) => dense_candidate(profile, ny, k),
            (true, Some(s)) => tracked_candidate(profile, ny, k, s),
            (true, None) => None, // not reached: the search stops first
        };
        grids.push(SearchedGrid { ny, growth_rate: c.map(|c| k * c.im), phase_speed: c.map(|c| c.re), tracked });
        c
    };
    let done = |grids: Vec<SearchedGrid>, outcome: SearchOutcome| ModeSearch { m, k, floor, grids, outcome };
    let Some(mut coarse) = solve(half, None) else { return (None, done(grids, SearchOutcome::SolveFailed)) };
    if k * coarse.im > floor {
        seed = Some(coarse);
    }
    let mut ny = start;
    loop {
        let Some(fine) = solve(ny, seed) else { return (None, done(grids, SearchOutcome::SolveFailed)) };
        let (fine_rate, coarse_rate) = (k * fine.im, k * coarse.im);
        if fine_rate > floor
            && coarse_rate > floor
            && (fine_rate - coarse_rate).abs() <= crate::constants::INSTABILITY_AGREEMENT * fine_rate
        {
            let mode = UnstableMode { m, k, growth_rate: fine_rate, growth_rate_coarse: coarse_rate, ny };
            return (Some(mode), done(grids, SearchOutcome::Converged));
        }
        if fine_rate <= floor && coarse_rate <= floor {
            return (None, done(grids, SearchOutcome::BelowFloor));
        }
        if 2 * ny > track_max {
            return (None, done(grids, SearchOutcome::NotConverged));
        }
        if fine_rate > floor {
            seed = Some(fine);
        }
        coarse = fine;
        ny *= 2;
    }
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
    let dense_max = (crate::constants::INSTABILITY_MAX_NY as usize).max(start);
    let track_max = (crate::constants::INSTABILITY_TRACK_MAX_NY as usize).max(dense_max);
    let ks = wavenumbers(problem);
    let u_scale = profile
        .samples(crate::constants::SCALE_SAMPLES)
        .iter()
        .map(|y| profile.u[0].eval(*y).abs())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    // A growth rate is evidence when it is far above rounding (relative to
    // k max|U|) and converged between two grids, the finer twice the
    // coarser. Start at instability_ny and its half; double while a rate
    // above the floor has not converged.
    let half = (start / 2 - (start / 2) % step).max(16);
    let searched: Vec<(Option<UnstableMode>, ModeSearch)> = ks
        .par_iter()
        .filter_map(|&(m, k)| {
            mode_step(progress, || {
                let floor = crate::constants::INSTABILITY_FLOOR * k * u_scale;
                Some(search_mode(profile, m, k, floor, (half, start), dense_max, track_max))
            })
        })
        .collect();
    let (rates, instability_search): (Vec<Option<UnstableMode>>, Vec<ModeSearch>) = searched.into_iter().unzip();
    let instability = rates.into_iter().flatten().max_by(|a, b| a.growth_rate.total_cmp(&b.growth_rate));
    let (verdict, reason) = match &instability {
        Some(u) => {
            let tracked = instability_search
                .iter()
                .find(|s| s.m == u.m)
                .and_then(|s| s.grids.iter().find(|g| g.tracked))
                .map(|_| format!("; followed by shift-invert beyond ny = {dense_max}"))
                .unwrap_or_default();
            (
                Verdict::LinearlyUnstable,
                format!(
                    "x-mode m = {} (k = {:.6}) grows at rate {:.6e} (ny = {}; {:.6e} at half the resolution{tracked}); {reason}",
                    u.m, u.k, u.growth_rate, u.ny, u.growth_rate_coarse
                ),
            )
        }
        None => (Verdict::Inconclusive, format!("{reason}{}", search_summary(&instability_search))),
    };
    FluidAnalysis {
        verification: (verdict == Verdict::LinearlyUnstable).then_some(VerificationLevel::Float),
        paper_choice_sigma2,
        shift_curve,
        instability,
        instability_search,
        ..FluidAnalysis::without_certificate(verdict, reason, form, paper_bound)
    }
}

/// What an inconclusive search tried, for the reason: the mode whose last
/// grid came nearest to growing, its rate there and why it was not
/// accepted (the certificate's `instability_search` has every mode and
/// grid).
fn search_summary(searches: &[ModeSearch]) -> String {
    let last = |s: &ModeSearch| s.grids.iter().rev().find_map(|g| g.growth_rate.map(|r| (r, g.ny)));
    let best = searches
        .iter()
        .filter_map(|s| last(s).map(|(r, ny)| (s, r, ny)))
        .max_by(|a, b| (a.1 / a.0.floor.max(f64::MIN_POSITIVE)).total_cmp(&(b.1 / b.0.floor.max(f64::MIN_POSITIVE))));
    match best {
        None if searches.is_empty() => String::new(),
        None => "; the instability search found no growth rate on any grid".into(),
        Some((s, rate, ny)) => format!(
            "; no growing mode was confirmed: the instability search's best candidate, x-mode m = {} (k = {:.6}), has growth rate {rate:.3e} at ny = {ny} ({}; floor {:.3e}; every mode and grid in instability_search)",
            s.m,
            s.k,
            match s.outcome {
                SearchOutcome::Converged => "converged",
                SearchOutcome::BelowFloor => "below the floor on the last two grids",
                SearchOutcome::NotConverged => "not converged between two grids up to the resolution limit",
                SearchOutcome::SolveFailed => "the last eigenvalue solve failed",
            },
            s.floor
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Boundary;

    /// The Bickley jet `U = sech^2 y = 4/(e^y + e^-y)^2` between walls at
    /// `y = -8, 8`, one x-mode of wavenumber `k`, no noise, ny = 512.
    fn bickley(k: f64) -> FluidProblem {
        let u = crate::expr::parse("4/(exp(y) + exp(-y))^2", &Default::default()).unwrap();
        FluidProblem {
            model: FluidModel::Incompressible,
            profile: Profile::new(u, vec![], (-8.0, 8.0), Boundary::Walls),
            x_period: 2.0 * std::f64::consts::PI / k,
            ny: 512,
            x_modes: 1,
        }
    }

    /// A search that stopped at ny = 1024 would find the jet
    /// `inconclusive`: the sinuous mode's largest `k Im c` is 0.0351,
    /// 0 (unresolved), 0.0175, 0.02267 at ny = 128 to 1024, and agrees to
    /// `1e-3` only from 2048 (0.0220931) to 4096 (0.0220919), which the
    /// banded shift-invert reaches (module docs).
    ///
    /// The independent value: shooting on Rayleigh's equation
    /// `(U - c)(phi'' - k^2 phi) - U'' phi = 0`, `phi(-8) = 0`, `phi'(0) = 0`,
    /// DOP853 at rtol 1e-13 and the secant method on `c`
    /// (`tests/reference/bickley_shooting.py` of this crate):
    /// `c = 0.649654705078 + 0.011627338319 i`, `k Im c = 0.0220919428`,
    /// the same to 1e-12 at rtol 1e-10 and with the Wronskian match from
    /// both walls; a second-order finite-difference eigenproblem converges
    /// to it (0.02209219 on 2048 intervals, 0.02209203 on 4096). The
    /// engine's value at ny = 4096 is 0.02209194208 (3e-8 relative). Also
    /// nearer the neutral `k = 2`: `k = 1.95` (0.0110727411, the engine
    /// 0.01107274 at 8192) and `k = 1.99` (0.0022166023, the engine
    /// 0.0022166018 at 65536, the finest grid). The tolerance, `1e-4`
    /// relative (and `1e-4 k Im c` for `Re c`), is a tenth of the agreement
    /// the search asks of two grids.
    #[test]
    fn the_bickley_jet_sinuous_mode_is_found() {
        // (k, k Im c and Re c by shooting, the grid where the rates agree)
        let cases = [
            (1.9, 0.0220919428, 0.6496547051, 4096),
            (1.95, 0.0110727411, 0.6581965386, 8192),
            (1.99, 0.0022166023, 0.6649783899, 65536),
        ];
        for (k, shooting, phase_speed, ny) in cases {
            let a = analyse(&bickley(k), &Default::default()).unwrap();
            assert_eq!(a.verdict, Verdict::LinearlyUnstable, "k = {k}: {}", a.reason);
            assert_eq!(a.verification, Some(VerificationLevel::Float));
            let u = a.instability.as_ref().unwrap();
            assert!((u.growth_rate - shooting).abs() <= 1e-4 * shooting, "k = {k}: {} vs {shooting}", u.growth_rate);
            assert!(
                (u.growth_rate - u.growth_rate_coarse).abs() <= crate::constants::INSTABILITY_AGREEMENT * u.growth_rate
            );
            assert_eq!(u.ny, ny, "k = {k}");
            // the search's record: dense 128 .. 1024, tracked beyond
            let [s] = &a.instability_search[..] else { panic!("one x-mode") };
            assert_eq!(s.outcome, SearchOutcome::Converged);
            let nys: Vec<usize> = s.grids.iter().map(|g| g.ny).collect();
            let expected: Vec<usize> = (0..).map(|i| 128 << i).take_while(|n| *n <= ny).collect();
            assert_eq!(nys, expected);
            assert!(s.grids.iter().all(|g| g.tracked == (g.ny > 1024)));
            // at k = 1.9 the mode is not resolved at 256: no complex
            // eigenvalue there
            assert!(k != 1.9 || s.grids[1].growth_rate == Some(0.0));
            let last = s.grids.last().unwrap();
            assert_eq!(last.growth_rate, Some(u.growth_rate));
            assert!((last.phase_speed.unwrap() - phase_speed).abs() <= 1e-4 * shooting, "k = {k}");
        }
    }

    /// At the neutral wavenumber `k = 2` (`c = 2/3`, `Im c = 0`; the
    /// varicose band ends at `k = 1`) the jet is not unstable, and is not
    /// found so: the energy–Casimir form is not definite there, so the
    /// search runs, and stops with both first grids below the floor. Just
    /// inside the band (`k = 1.999`, `k Im c = 2.2168e-4` by shooting, a
    /// hundred times the floor) the grids do not resolve the mode (critical
    /// layer about `1.5e-4` wide): the verdict must not be `stable`, and a
    /// rate, if one is ever reported, must be the shooting one (today the
    /// search stops at 128 and 256, `below_floor`). A mode that does not
    /// converge by the finest tracked grid is reported `not_converged`,
    /// with every grid's candidate.
    #[test]
    fn the_bickley_jet_at_its_neutral_wavenumber_is_not_reported_unstable() {
        let a = analyse(&bickley(2.0), &Default::default()).unwrap();
        assert_eq!(a.verdict, Verdict::Inconclusive, "{}", a.reason);
        assert_eq!((a.verification, &a.instability), (None, &None));
        let [s] = &a.instability_search[..] else { panic!("one x-mode") };
        assert_eq!(s.outcome, SearchOutcome::BelowFloor);
        assert_eq!(s.grids.iter().map(|g| g.ny).collect::<Vec<_>>(), vec![128, 256]);
        assert!(s.grids.iter().all(|g| g.growth_rate.unwrap() <= s.floor && !g.tracked));

        let a = analyse(&bickley(1.999), &Default::default()).unwrap();
        assert_ne!(a.verdict, Verdict::Stable, "{}", a.reason);
        if let Some(u) = &a.instability {
            assert!((u.growth_rate - 2.2167925e-4).abs() <= 1e-3 * 2.2167925e-4, "{}", u.growth_rate);
        } else {
            assert_eq!(a.instability_search[0].outcome, SearchOutcome::BelowFloor);
        }

        // k = 1.99 (k Im c = 0.0022166) with the tracked grids stopped at
        // 16384: 0.0023382 at 8192 and 0.0022073 at 16384 disagree
        let p = bickley(1.99);
        let k = wavenumbers(&p)[0].1;
        let floor = crate::constants::INSTABILITY_FLOOR * k;
        let (found, s) = search_mode(&p.profile, 1, k, floor, (128, 256), 1024, 16384);
        assert_eq!((found, s.outcome), (None, SearchOutcome::NotConverged));
        assert_eq!(s.grids.last().map(|g| (g.ny, g.tracked)), Some((16384, true)));
        let rate = s.grids.last().unwrap().growth_rate.unwrap();
        assert!((rate - 0.0022166).abs() < 0.01 * rate, "{rate}");
    }
}
