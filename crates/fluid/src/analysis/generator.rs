//! The compressible pipeline for compatible noise with non-constant
//! transport: the discretised generator of [`crate::barotropic`], `Sigma^2`
//! per x-mode optimised over the Galilean shift, the verified check, the
//! convergence table, the continuum bound and the evidence.

use super::*;
use crate::barotropic::{BarotropicCoefficients, BarotropicMode, WallGrid};
use crate::profile::Potential;

/// What the compressible generator needs from the choice of functional.
pub(super) struct ShiftFreedom {
    /// The admissible shifts `[lo, hi]` (one end sonic, excluded).
    pub lo: f64,
    pub hi: f64,
    /// Whether the sonic end is `hi` (`U'' > 0`, `U + c > 0`) or `lo`.
    pub sonic_at_hi: bool,
}

/// The Casimir weight `w = Phi''(q_e)` at `y` for shift `c`.
fn weight(profile: &Profile, choice: &Choice, uniform: bool, c: f64, y: f64) -> f64 {
    if uniform {
        return 0.0; // U uniform: no Casimir needed (docs/fluids.md §1b)
    }
    match choice {
        Choice::Forced { shift, zeros, .. } => casimir_weight(profile, 1.0, *shift, zeros, y),
        _ => (profile.u[0].eval(y) + c) / profile.u[2].eval(y),
    }
}

pub(super) fn coefficients(
    profile: &Profile,
    choice: &Choice,
    uniform: bool,
    grid: &WallGrid,
    c: f64,
) -> BarotropicCoefficients {
    let y = grid.nodes();
    let u: Vec<f64> = y.iter().map(|y| profile.u[0].eval(*y)).collect();
    let eta_prime: Vec<Vec<f64>> = profile.eta.iter().map(|[_, d]| y.iter().map(|y| d.eval(*y)).collect()).collect();
    let r_prime = profile
        .potential
        .iter()
        .zip(&eta_prime)
        .map(|(p, ep)| y.iter().zip(&u).zip(ep).map(|((y, u), e)| p.gradient(*y, *u, *e)).collect())
        .collect();
    BarotropicCoefficients {
        up: y.iter().map(|y| profile.u[1].eval(*y)).collect(),
        w: y.iter().map(|y| weight(profile, choice, uniform, c, *y)).collect(),
        eta: profile.eta.iter().map(|[e, _]| y.iter().map(|y| e.eval(*y)).collect()).collect(),
        eta_prime,
        r_prime,
        u,
    }
}

/// `max_k lambda_max(Q, K)` at one resolution and shift (`None`: some mode failed).
fn sigma2_over_modes(
    coef: &BarotropicCoefficients,
    grid: &WallGrid,
    ks: &[(usize, f64)],
    sound_speed: f64,
    c: f64,
    tol: f64,
    progress: &Progress,
) -> Option<f64> {
    if !coef.usable() {
        return None;
    }
    let values: Vec<Option<f64>> = ks
        .par_iter()
        .map(|&(_, k)| {
            mode_step(progress, || {
                BarotropicMode::new(grid, coef, k, sound_speed, c).sigma2(tol).map(|s| s.lambda_max.max(0.0))
            })
        })
        .collect();
    values.into_iter().try_fold(0.0f64, |acc, v| v.map(|v| acc.max(v)))
}

/// A rigorous enclosure of `sup_y sum_j eta_j'^2 c_s^2 / (c_s^2 - (U + c)^2)`
/// over the closed interval (every noise field compatible or constant).
fn continuum_bound(profile: &Profile, sound_speed: f64, c: f64) -> Option<f64> {
    let (a, b) = profile.interval;
    let pieces = crate::constants::FINE_SAMPLES.max(1024);
    let cs2 = Interval::point(sound_speed) * Interval::point(sound_speed);
    let mut worst = 0.0f64;
    for i in 0..pieces {
        let lo = if i == 0 { a } else { (a + (b - a) * (i as f64 / pieces as f64)).next_down() };
        let hi = if i + 1 == pieces { b } else { a + (b - a) * ((i + 1) as f64 / pieces as f64) };
        let shifted = profile.u[0].enclose(lo, hi) + Interval::point(c);
        let denominator = cs2 - shifted * shifted;
        if denominator.lo.is_nan() || denominator.lo <= 0.0 {
            return None;
        }
        let mut sum = Interval::point(0.0);
        for [_, d] in &profile.eta {
            let e = d.enclose(lo, hi);
            sum = sum + e * e;
        }
        let v = sum * cs2 / denominator;
        if !v.hi.is_finite() {
            return None;
        }
        worst = worst.max(v.hi);
    }
    Some(worst)
}

/// What the steps of `analyse_generator` share: the (normalised) profile,
/// its functional, the x-modes, the Lanczos tolerance and the progress.
struct Generator<'a> {
    profile: &'a Profile,
    choice: &'a Choice,
    uniform: bool,
    sound_speed: f64,
    ks: Vec<(usize, f64)>,
    tol: f64,
    progress: &'a Progress,
}

/// The per-mode results on the finest grid: `Sigma^2` and its verified
/// upper bound over the modes, and the discretised SDE's growth.
struct FinestGrid {
    modes: Vec<ModeResult>,
    sigma2: f64,
    sigma2_upper: Option<f64>,
    discrete_sde: Option<(usize, f64)>,
}

impl Generator<'_> {
    /// The generator's coefficients on `grid` at the Galilean shift `c`.
    fn at(&self, grid: &WallGrid, c: f64) -> BarotropicCoefficients {
        coefficients(self.profile, self.choice, self.uniform, grid, c)
    }

    /// `max_k lambda_max(Q, K)` over the x-modes on `grid` at shift `c`
    /// (`None`: some mode failed).
    fn sigma2_on(&self, coef: &BarotropicCoefficients, grid: &WallGrid, c: f64) -> Option<f64> {
        sigma2_over_modes(coef, grid, &self.ks, self.sound_speed, c, self.tol, self.progress)
    }

    /// The shift `c` minimising `Sigma^2` on the coarse grid, with the
    /// curve `(c, Sigma^2)` of the points tried (`None`: none could be
    /// evaluated).
    fn best_shift(&self, coarse: &WallGrid, freedom: ShiftFreedom) -> Option<(f64, Vec<(f64, f64)>)> {
        // The shift: a scan of the admissible interval at the coarsest grid
        // (the sonic end kept 1e-3 of the width away), then golden-section
        // refinement about the best point.
        let ShiftFreedom { lo, hi, sonic_at_hi } = freedom;
        let width = hi - lo;
        let (lo_s, hi_s) = if width == 0.0 {
            (lo, hi)
        } else if sonic_at_hi {
            (lo, hi - 1e-3 * width)
        } else {
            (lo + 1e-3 * width, hi)
        };
        let f = |c: f64| self.sigma2_on(&self.at(coarse, c), coarse, c);
        let mut curve: Vec<(f64, f64)> = vec![];
        // The phases of the plan (see `planned_steps`); the guard ends this
        // one on every return.
        let modes = self.ks.len() as u64;
        let _phase = self.progress.phase(21 * modes);
        if width == 0.0 {
            return Some((lo, curve));
        }
        let scan = 9;
        for i in 0..scan {
            let c = lo_s + (hi_s - lo_s) * i as f64 / (scan - 1) as f64;
            if let Some(s) = f(c) {
                curve.push((c, s));
            }
        }
        let best = curve.iter().copied().min_by(|x, y| x.1.total_cmp(&y.1))?;
        let step = (hi_s - lo_s) / (scan - 1) as f64;
        let (x0, x1) = ((best.0 - step).max(lo_s), (best.0 + step).min(hi_s));
        let (c, s) = crate::minimise::golden_section(|c| f(c).unwrap_or(f64::INFINITY), x0, x1, 12);
        if s.is_finite() {
            curve.push((c, s));
        }
        curve.sort_by(|x, y| x.0.total_cmp(&y.0));
        let c = curve.iter().copied().min_by(|x, y| x.1.total_cmp(&y.1)).map_or(best.0, |x| x.0);
        Some((c, curve))
    }

    /// Per x-mode on the finest grid at shift `c`: `lambda_max(Q, K)` by
    /// Lanczos and its verified upper bound, then the discretised SDE's
    /// growth; `Err` with the reason when the form is not proved definite.
    fn finest_grid(&self, fine: &WallGrid, c: f64) -> Result<FinestGrid, String> {
        let (ks, tol, progress, sound_speed) = (&self.ks, self.tol, self.progress, self.sound_speed);
        // The finest grid: per mode Lanczos and the verified check.
        let coef = self.at(fine, c);
        if !coef.usable() {
            return Err(format!(
                "the Casimir weight (U + c)/U'' with c = {c:.6} is negative or not finite at a node of the finest grid"
            ));
        }
        let per_mode: Vec<Option<ModeResult>> = ks
            .par_iter()
            .map(|&(m, k)| {
                mode_step(progress, || {
                    let mode = BarotropicMode::new(fine, &coef, k, sound_speed, c);
                    let s = mode.sigma2(tol)?;
                    let sigma2 = s.lambda_max.max(0.0);
                    let (upper, form_verified) = verified_upper(sigma2, &s.ritz, 0, |bar| mode.verify(bar));
                    Some(ModeResult { m, k, sigma2, sigma2_upper: upper, form_verified, iterations: s.ritz.iterations })
                })
            })
            .collect();
        if let Some(pos) = per_mode.iter().position(|r| !r.as_ref().is_some_and(|r| r.form_verified)) {
            let (m, k) = ks[pos];
            return Err(format!("the compressible energy-Casimir-momentum form with c = {c:.6} could not be shown positive definite for x-mode m = {m} (k = {k:.6}) on the finest grid"));
        }
        let mut modes: Vec<ModeResult> = per_mode.into_iter().flatten().collect();
        prove_remaining_modes(&mut modes, progress, |k, bar| {
            BarotropicMode::new(fine, &coef, k, sound_speed, c).verify(bar).1
        });
        // The discretised SDE's own growth constant per mode, lambda_max(Q_B, K):
        // Q_B differs from Q by the Casimir defect, which grows with k (about
        // k^3 h^2 here), so short waves on a given grid can outgrow Sigma^2.
        let discrete_sde = ks
            .par_iter()
            .map(|&(m, k)| {
                mode_step(progress, || {
                    BarotropicMode::new(fine, &coef, k, sound_speed, c).pointwise_noise_sigma2(tol).map(|d| (m, d))
                })
            })
            .collect::<Option<Vec<(usize, f64)>>>()
            .and_then(|d| d.into_iter().max_by(|a, b| a.1.total_cmp(&b.1)));
        let sigma2 = modes.iter().map(|r| r.sigma2).fold(0.0, f64::max);
        let sigma2_upper = modes.iter().try_fold(0.0f64, |acc, r| r.sigma2_upper.map(|u| acc.max(u)));
        Ok(FinestGrid { modes, sigma2, sigma2_upper, discrete_sde })
    }

    /// The convergence table of `Sigma^2` over `resolutions` (the finest
    /// row is `sigma2`) and the Casimir defect of the gravest mode at each.
    fn convergence(
        &self,
        (a, b): (f64, f64),
        resolutions: &[usize],
        finest: (usize, f64),
        c: f64,
    ) -> (Vec<ConvergenceRow>, Vec<(usize, f64)>) {
        let (finest_ny, sigma2) = finest;
        let (_, k1) = self.ks[0];
        let mut convergence = vec![];
        let mut casimir_defect = vec![];
        for &ny in resolutions {
            let grid = WallGrid::new(a, b, ny);
            let cf = self.at(&grid, c);
            let s = if ny == finest_ny { Some(sigma2) } else { self.sigma2_on(&cf, &grid, c) };
            convergence.push(ConvergenceRow { ny, sigma2: s, sigma2_paper_choice: None });
            if cf.usable() {
                if let Some(d) = BarotropicMode::new(&grid, &cf, k1, self.sound_speed, c).casimir_defect(1e-8) {
                    casimir_defect.push((ny, d));
                }
            }
        }
        (convergence, casimir_defect)
    }

    /// `|K A + A^* K| / (|K| |A|)` (max norms) for the gravest mode on
    /// `grid`: how far the drift `A` is from `K`-skew (`None`: not finite).
    fn drift_residual(&self, grid: &WallGrid, c: f64) -> Option<f64> {
        let (_, k1) = self.ks[0];
        let cf = self.at(grid, c);
        let mode = BarotropicMode::new(grid, &cf, k1, self.sound_speed, c);
        let (am, km) = (mode.drift(), mode.form_complex());
        let norm = |m: &nalgebra::DMatrix<nalgebra::Complex<f64>>| m.iter().fold(0.0f64, |x, z| x.max(z.norm()));
        let r = norm(&(&km * &am + am.adjoint() * &km)) / (norm(&km) * norm(&am));
        r.is_finite().then_some(r)
    }
}

/// The reason no compressible form can be assembled when `4 s^2`
/// overflows, `s` the largest of `c_s`, `|U|` and the admissible shifts.
fn overflow_reason(profile: &Profile, sound_speed: f64, freedom: &ShiftFreedom) -> Option<String> {
    let (a, b) = profile.interval;
    // c_s^2 enters K: beyond sqrt(f64::MAX) it overflows, and the form would
    // look indefinite for a reason that is not the physics.
    let largest = profile.u[0].range_on(a, b, 64);
    let speed = sound_speed.max(largest.lo.abs()).max(largest.hi.abs()).max(freedom.lo.abs()).max(freedom.hi.abs());
    (!(speed * speed * 4.0).is_finite()).then(|| {
        format!(
            "the sound speed or the flow ({speed:e}) squared overflows a double, so the compressible form cannot be assembled: rescale the units of velocity"
        )
    })
}

/// The summary of the energy–Casimir–momentum form with Galilean shift `c`
/// and weight `(U + c)/U''` (none for a uniform `U`).
fn shifted_summary(mut summary: FormSummary, c: f64, uniform: bool) -> FormSummary {
    summary.energy = 1.0;
    summary.galilean_shift = Some(c);
    summary.sign = Some(Sign::Positive);
    summary.kind = "energy_casimir_momentum";
    summary.casimir_weight = if uniform {
        format!("none: U is uniform and the shift c = {c:.6} brings it to rest (energy coefficient 1, plus momentum and mass)")
    } else {
        format!("Phi''(q_e) = (U + c)/U'' with c = {c:.6} (energy coefficient 1, plus momentum and mass)")
    };
    summary
}

/// Why the generator's `Sigma^2` is the claim: the compatible noise, the
/// form `(Q, K)` at shift `c` and what the report adds.
fn stable_reason(
    profile: &Profile,
    c: f64,
    only_shift: bool,
    bound: bool,
    discrete_sde: bool,
    proved_weight: bool,
) -> String {
    let compatible: Vec<usize> =
        (0..profile.potential.len()).filter(|&i| matches!(profile.potential[i], Potential::Compatible)).collect();
    format!(
        "noise {compatible:?} is compatible through its potential part r' = -U eta' (the equilibrium is kept exactly), so the potential vorticity is transported (B dq = -ik eta dq) and the generator form is Q = sum_j int eta_j'^2 |du1|^2, du1 = dm1 - U drho; Sigma^2 is the largest generalised eigenvalue of (Q, K) over the x-modes, K the energy-Casimir-momentum form with Galilean shift c = {c:.6} ({}), positive definite on every mode{}{}{}",
        if only_shift { "the only admissible shift" } else { "the best of a scan of the admissible shifts" },
        if bound {
            "; compressible.generator.continuum_bound bounds the continuum Sigma^2 of every x-mode (interval arithmetic)"
        } else {
            ""
        },
        if discrete_sde {
            "; the claims are about (Q, K): the discretised SDE with the pointwise noise differs from Q by the Casimir defect, and compressible.generator.discrete_sde gives its growth"
        } else {
            ""
        },
        if proved_weight { "" } else { "; the Casimir weight's sign is sampled, not proved (level float)" }
    )
}

/// `Sigma^2` of the discretised compressible generator: the Galilean shift
/// chosen on the coarse grid, the verified check per x-mode on the finest,
/// the convergence table, the drift residual and the continuum bound.
#[allow(clippy::too_many_arguments)]
pub(super) fn analyse_generator(
    problem: &FluidProblem,
    settings: &FluidSettings,
    sound_speed: f64,
    choice: &Choice,
    uniform: bool,
    freedom: ShiftFreedom,
    proved_weight: bool,
    summary: FormSummary,
    base: FluidAnalysis,
    progress: &Progress,
) -> FluidAnalysis {
    let profile = &problem.profile;
    let (a, b) = profile.interval;
    let run = Generator {
        profile,
        choice,
        uniform,
        sound_speed,
        ks: wavenumbers(problem),
        tol: settings.lanczos_tolerance,
        progress,
    };
    let resolutions = table_resolutions(problem.ny, settings.convergence_from);
    let coarse_ny = resolutions[0];
    let coarse = WallGrid::new(a, b, coarse_ny);
    if let Some(reason) = overflow_reason(profile, sound_speed, &freedom) {
        return FluidAnalysis { reason, ..base };
    }
    let only_shift = freedom.hi - freedom.lo == 0.0;
    let Some((c, curve)) = run.best_shift(&coarse, freedom) else {
        return FluidAnalysis {
            reason: "the compressible generator could not be evaluated at any admissible Galilean shift (the form was not positive definite on the coarsest grid)".into(),
            ..base
        };
    };
    let fine = WallGrid::new(a, b, problem.ny);
    let FinestGrid { modes, sigma2, sigma2_upper, discrete_sde } = match run.finest_grid(&fine, c) {
        Ok(x) => x,
        Err(reason) => return FluidAnalysis { reason, ..base },
    };

    // The table, the Casimir defect of the gravest mode, the drift residual.
    let (convergence, casimir_defect) = run.convergence((a, b), &resolutions, (problem.ny, sigma2), c);
    let drift_residual = run.drift_residual(&WallGrid::new(a, b, coarse_ny.min(64)), c);
    let bound = continuum_bound(profile, sound_speed, c);

    let verification = if sigma2_upper.is_some() && proved_weight {
        VerificationLevel::VerifiedFloat
    } else {
        VerificationLevel::Float
    };
    let reason = stable_reason(profile, c, only_shift, bound.is_some(), discrete_sde.is_some(), proved_weight);
    let report = base.compressible.clone().map(|r| CompressibleReport {
        generator: Some(GeneratorReport {
            shift: c,
            continuum_bound: bound,
            casimir_defect,
            discrete_sde,
            drift_residual,
        }),
        ..r
    });
    FluidAnalysis {
        verdict: Verdict::Stable,
        reason,
        form: shifted_summary(summary, c, uniform),
        sigma2: Some(sigma2),
        sigma2_upper,
        verification: Some(verification),
        modes,
        convergence,
        shift_curve: curve,
        drift_residual,
        compressible: report,
        ..base
    }
}

/// Whether each stated `(m, bound)` is proved for the compressible
/// generator at shift `c` on the finest grid (see [`prove_mode_bounds`]).
pub(super) fn prove_generator_bounds(problem: &FluidProblem, c: f64, bounds: &[(usize, f64)]) -> Vec<bool> {
    let FluidModel::Compressible { sound_speed } = problem.model else { return vec![false; bounds.len()] };
    let p = &problem.profile;
    if p.boundary != Boundary::Walls {
        return vec![false; bounds.len()];
    }
    let (a, b) = p.interval;
    let fine = YGrid::new(p.boundary, a, b, problem.ny);
    let (scaled, e) = normalise_noise(problem, &fine);
    let profile = scaled.profile;
    let choice = choose(&profile);
    let uniform = profile.u[1].sign_on(a, b, crate::choice::SIGN_PROOF_BUDGET) == SignProof::Zero;
    let grid = WallGrid::new(a, b, problem.ny);
    let coef = coefficients(&profile, &choice, uniform, &grid, c);
    if !coef.usable() {
        return vec![false; bounds.len()];
    }
    let ks = wavenumbers(problem);
    bounds
        .par_iter()
        .map(|&(m, bound)| {
            let Some(&(_, k)) = ks.iter().find(|(mm, _)| *mm == m) else { return false };
            let normalised = normalised_bound(bound, e);
            BarotropicMode::new(&grid, &coef, k, sound_speed, c).verify(normalised) == (true, true)
        })
        .collect()
}
