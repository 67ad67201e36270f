//! The fluid pipeline: profile checks, the choice of functional, Sigma^2 per
//! x-mode (Lanczos at every resolution of the convergence table, the dense
//! verified check at the finest), the paper's constants beside ours, the
//! linear-instability test, and the compressible noise-compatibility test.

use crate::choice::{casimir_weight, choose, Choice};
use crate::constants::{VERIFY_ATTEMPTS, VERIFY_MARGIN_GROWTH, VERIFY_MARGIN_START, VERIFY_RITZ_WEIGHT};
use crate::expr::SignProof;
use crate::grid::{Boundary, YGrid};
use crate::interval::Interval;
use crate::modes::{Coefficients, Form, Mode};
use crate::profile::{Profile, ProfileError};
use rayon::prelude::*;

/// Incompressible or compressible (barotropic, `rho_e = 1`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FluidModel {
    /// 2D incompressible Euler (vorticity form).
    Incompressible,
    /// 2D compressible barotropic Euler with sound speed `c_s` at `rho = 1`.
    Compressible {
        /// `c_s`.
        sound_speed: f64,
    },
}

impl FluidModel {
    /// Name as in the spec.
    pub fn as_str(&self) -> &'static str {
        match self {
            FluidModel::Incompressible => "incompressible",
            FluidModel::Compressible { .. } => "compressible",
        }
    }
}

/// A shear-flow stability problem.
#[derive(Clone, Debug)]
pub struct FluidProblem {
    /// The model.
    pub model: FluidModel,
    /// Profile, noise, interval, boundary.
    pub profile: Profile,
    /// Period in x.
    pub x_period: f64,
    /// Finest y-resolution.
    pub ny: usize,
    /// Number of x-modes `m = 1..=x_modes` (`k = 2 pi m / x_period`).
    pub x_modes: usize,
}

/// Numerical settings of the fluid pipeline.
#[derive(Clone, Debug, PartialEq)]
pub struct FluidSettings {
    /// Relative residual at which a Lanczos run stops (default `1e-10`).
    pub lanczos_tolerance: f64,
    /// Coarsest `ny` of the convergence table (default 64); the table doubles up to `ny`.
    pub convergence_from: usize,
    /// Resolution of the dense eigenvalue test for linear instability (default 256).
    pub instability_ny: usize,
}

impl Default for FluidSettings {
    fn default() -> Self {
        FluidSettings { lanczos_tolerance: 1e-10, convergence_from: 64, instability_ny: 256 }
    }
}

/// The verdicts are the finite-dimensional pipeline's [`Verdict`] (a shear
/// flow is always an equilibrium, so `NotAnEquilibrium` does not occur).
pub use outcome::{Sign, Verdict, VerificationLevel};

/// Sigma^2 of one x-mode at the finest grid.
#[derive(Clone, Debug, PartialEq)]
pub struct ModeResult {
    /// Index `m` (`k = 2 pi m / x_period`).
    pub m: usize,
    /// Wavenumber.
    pub k: f64,
    /// `max(lambda_max, 0)`.
    pub sigma2: f64,
    /// The verified upper bound (`None` if the dense check failed).
    pub sigma2_upper: Option<f64>,
    /// `V ≻ 0` verified by the dense check.
    pub form_verified: bool,
    /// Lanczos steps.
    pub iterations: usize,
}

/// One row of the convergence table.
#[derive(Clone, Debug, PartialEq)]
pub struct ConvergenceRow {
    /// Resolution.
    pub ny: usize,
    /// Sigma^2 (max over modes) of the chosen functional.
    pub sigma2: Option<f64>,
    /// Sigma^2 with the paper's Casimir (`c = 0`), if admissible.
    pub sigma2_paper_choice: Option<f64>,
}

/// The functional used, for the certificate.
#[derive(Clone, Debug, PartialEq)]
pub struct FormSummary {
    /// `pseudomomentum`, `enstrophy`, `energy_casimir` or `none`.
    pub kind: &'static str,
    /// Coefficient of the energy.
    pub energy: f64,
    /// The Galilean shift `c` (`None` for the pseudomomentum: the limit `|c| -> infinity`).
    pub galilean_shift: Option<f64>,
    /// Sign making the form positive (`None`: no form).
    pub sign: Option<Sign>,
    /// The Casimir weight as a formula in words.
    pub casimir_weight: String,
}

/// Evidence of linear instability.
#[derive(Clone, Debug, PartialEq)]
pub struct UnstableMode {
    /// Index `m`.
    pub m: usize,
    /// Wavenumber.
    pub k: f64,
    /// Growth rate at the test resolution.
    pub growth_rate: f64,
    /// Growth rate at half that resolution (agreement shows convergence).
    pub growth_rate_coarse: f64,
    /// The test resolution.
    pub ny: usize,
}

/// The compressible noise-compatibility test.
#[derive(Clone, Debug, PartialEq)]
pub struct CompressibleReport {
    /// `c_s`.
    pub sound_speed: f64,
    /// `sup_y |U eta_k'|` per noise field: the y-momentum the noise puts into
    /// the equilibrium (zero iff compatible).
    pub noise_residuals: Vec<f64>,
    /// The admissible Galilean shifts `(c_lo, c_hi)` making the form definite, if any.
    pub shift_interval: Option<(f64, f64)>,
    /// The verdict of the same profile and noise in the incompressible model.
    pub incompressible_verdict: Verdict,
    /// Its Sigma^2.
    pub incompressible_sigma2: Option<f64>,
}

/// Everything the fluid pipeline found.
#[derive(Clone, Debug, PartialEq)]
pub struct FluidAnalysis {
    /// The verdict.
    pub verdict: Verdict,
    /// Why, in a sentence.
    pub reason: String,
    /// The functional.
    pub form: FormSummary,
    /// Sigma^2 (max over modes), if stable.
    pub sigma2: Option<f64>,
    /// Verified upper bound of Sigma^2 (max over modes), if every mode verified.
    pub sigma2_upper: Option<f64>,
    /// How the bound was verified.
    pub verification: Option<VerificationLevel>,
    /// Per-mode values at the finest grid.
    pub modes: Vec<ModeResult>,
    /// Sigma^2 under refinement.
    pub convergence: Vec<ConvergenceRow>,
    /// The paper's `sup_y sum_k eta_k'(y)^2` (`None` where it exceeds the
    /// range of doubles).
    pub paper_bound: Option<f64>,
    /// Sigma^2 with the paper's functional (`c = 0`), if it is definite.
    pub paper_choice_sigma2: Option<f64>,
    /// Sigma^2 of `H + C + cM` for shifts `c` moving away from the
    /// admissible edge: `(c, Sigma^2)`, decreasing to the pseudomomentum's 0.
    pub shift_curve: Vec<(f64, f64)>,
    /// `max_k ||sym(V A)||_F / ||V||_F` at the coarsest table resolution.
    pub drift_residual: Option<f64>,
    /// Evidence of linear instability, if found.
    pub instability: Option<UnstableMode>,
    /// The compressible part, if the model is compressible.
    pub compressible: Option<CompressibleReport>,
}

impl FluidAnalysis {
    /// A result with no Sigma^2 and no evidence beyond the verdict and reason.
    fn without_certificate(verdict: Verdict, reason: String, form: FormSummary, paper_bound: f64) -> Self {
        FluidAnalysis {
            verdict,
            reason,
            form,
            sigma2: None,
            sigma2_upper: None,
            verification: None,
            modes: vec![],
            convergence: vec![],
            paper_bound: Some(paper_bound),
            paper_choice_sigma2: None,
            shift_curve: vec![],
            drift_residual: None,
            instability: None,
            compressible: None,
        }
    }
}

/// Bad input found while analysing (the spec layer maps these to JSON paths).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum FluidError {
    /// The profile or noise is unusable.
    #[error(transparent)]
    Profile(#[from] ProfileError),
}

/// The wavenumbers `k_m = 2 pi m / x_period`, `m = 1..=x_modes`.
pub fn wavenumbers(problem: &FluidProblem) -> Vec<(usize, f64)> {
    (1..=problem.x_modes).map(|m| (m, 2.0 * std::f64::consts::PI * m as f64 / problem.x_period)).collect()
}

/// The resolutions of the convergence table: `from, 2 from, ...` below `ny`, then `ny`.
pub fn table_resolutions(ny: usize, from: usize) -> Vec<usize> {
    let mut out = vec![];
    let mut r = from.max(16);
    while r < ny {
        out.push(r);
        r *= 2;
    }
    out.push(ny);
    out
}

fn form_for(choice: &Choice, profile: &Profile, coef: &Coefficients, grid: &YGrid) -> Option<Form> {
    match choice {
        Choice::Pseudomomentum { sign } => {
            Some(Form { energy: 0.0, w: coef.upp.iter().map(|p| 1.0 / p).collect(), sign: *sign })
        }
        Choice::Enstrophy => Some(Form { energy: 0.0, w: vec![1.0; grid.n()], sign: Sign::Positive }),
        Choice::Forced { shift, zeros, sign } => Some(Form {
            energy: 1.0,
            w: grid.nodes().iter().map(|y| casimir_weight(profile, 1.0, *shift, zeros, *y)).collect(),
            sign: *sign,
        }),
        Choice::NoForm { .. } => None,
    }
}

/// The form of a choice and the sentence saying why it gives stability, or
/// why there is no form (`Err`, with the choice's own reason).
fn form_and_reason(
    choice: &Choice,
    profile: &Profile,
    coef: &Coefficients,
    grid: &YGrid,
    summary: &FormSummary,
) -> Result<(Form, String), String> {
    let reason = match choice {
        Choice::Pseudomomentum { .. } => "U'' has one sign (Rayleigh): the pseudomomentum int omega^2/U'' (Casimir plus x-momentum, the limit |c| -> infinity of energy + Casimir + c momentum) is conserved by the drift and by every noise field (eta(y), 0), so Sigma^2 = 0".to_string(),
        Choice::Enstrophy => "U'' = 0: the enstrophy int omega^2 is conserved by the drift and the noise, so Sigma^2 = 0".to_string(),
        Choice::Forced { .. } => format!("{}; the form is definite for every x-mode and Sigma^2 is the largest generalised eigenvalue of (Q, V) over the modes", summary.casimir_weight),
        Choice::NoForm { reason } => return Err(reason.clone()),
    };
    let form = form_for(choice, profile, coef, grid).ok_or("no form could be built for the chosen functional")?;
    Ok((form, reason))
}

/// The grid at the problem's `ny`, the coefficients, and the form the
/// pipeline uses (`None` when the profile admits none): for benchmarks and
/// for users who want the per-mode operators themselves.
///
/// ```
/// use fluid::{analysis::{chosen_form, FluidModel, FluidProblem}, expr::parse, grid::Boundary, profile::Profile, modes::Mode};
/// let p = |s: &str| parse(s, &Default::default()).unwrap();
/// let profile = Profile::new(p("sin(y)"), vec![p("0.3*cos(y)")], (0.0, std::f64::consts::PI), Boundary::Walls);
/// let problem = FluidProblem { model: FluidModel::Incompressible, profile, x_period: 6.283185307179586, ny: 32, x_modes: 1 };
/// let (grid, coef, form) = chosen_form(&problem).unwrap();
/// let s = Mode::new(&grid, 1.0).sigma2(&form, &coef, 1e-12).unwrap();
/// assert!((s.lambda_max - 0.0142173139187).abs() < 1e-10); // the sine-Galerkin value (tests/fluid.rs)
/// ```
pub fn chosen_form(problem: &FluidProblem) -> Option<(YGrid, Coefficients, Form)> {
    let profile = &problem.profile;
    let grid = YGrid::new(profile.boundary, profile.interval.0, profile.interval.1, problem.ny);
    let coef = profile.coefficients(&grid);
    let form = form_for(&choose(profile), profile, &coef, &grid)?;
    Some((grid, coef, form))
}

/// The energy–Casimir–momentum form with Galilean shift `c`, if its weight
/// `(U + c)/U''` has one sign at the nodes (`U''` must not vanish there).
fn shifted_form(coef: &Coefficients, shift: f64) -> Option<Form> {
    let w: Vec<f64> = coef.u.iter().zip(&coef.upp).map(|(u, p)| (u + shift) / p).collect();
    if w.iter().any(|x| !x.is_finite()) {
        return None;
    }
    if w.iter().all(|x| *x > 0.0) {
        Some(Form { energy: 1.0, w, sign: Sign::Positive })
    } else if w.iter().all(|x| *x < 0.0) {
        Some(Form { energy: 1.0, w, sign: Sign::Negative })
    } else {
        None
    }
}

/// Sigma^2 (max over modes) of a form at one resolution, by Lanczos; `None`
/// if the form is not definite for some mode.
fn sigma2_all_modes(grid: &YGrid, coef: &Coefficients, form: &Form, ks: &[(usize, f64)], tol: f64) -> Option<f64> {
    let values: Vec<Option<f64>> = ks
        .par_iter()
        .map(|(_, k)| Mode::new(grid, *k).sigma2(form, coef, tol).ok().map(|s| s.lambda_max.max(0.0)))
        .collect();
    values.into_iter().try_fold(0.0f64, |acc, v| v.map(|v| acc.max(v)))
}

/// Run the pipeline.
///
/// The noise enters `Q` quadratically and nowhere else, so the pipeline runs
/// on the noise divided by a power of two `2^e` close to its largest value
/// (exactly, in binary floating point) and multiplies every `Sigma^2` by
/// `4^e` at the end. An amplitude of `1e160` then gives `Sigma^2` near
/// `1e318`, which no double holds: the verdict is `inconclusive` with that
/// reason, never a `Sigma^2` rounded to 0 or to infinity (the squares
/// overflowed to NaN before, which was floored to 0).
pub fn analyse(problem: &FluidProblem, settings: &FluidSettings) -> Result<FluidAnalysis, FluidError> {
    let profile = &problem.profile;
    let fine = YGrid::new(profile.boundary, profile.interval.0, profile.interval.1, problem.ny);
    profile.check(fine.nodes())?;
    let (scaled, e) = normalise_noise(problem, &fine);
    let a = analyse_normalised(&scaled, settings, &fine);
    Ok(if e == 0 { a } else { rescale(a, e) })
}

/// The problem with its noise divided by `2^e` (exactly), and `e`: the
/// exponent of the largest noise value on the samples and the nodes of
/// `fine` (0 for no noise).
fn normalise_noise(problem: &FluidProblem, fine: &YGrid) -> (FluidProblem, i32) {
    let e = noise_exponent(&problem.profile, fine.nodes());
    if e == 0 {
        return (problem.clone(), 0);
    }
    (FluidProblem { profile: problem.profile.with_noise_factor(pow2(-e)), ..problem.clone() }, e)
}

/// `2^e` for `-1022 <= e <= 1023`.
fn pow2(e: i32) -> f64 {
    f64::from_bits(((e.clamp(-1022, 1023) + 1023) as u64) << 52)
}

/// The exponent `e` with `max |eta_k| / 2^e` in `[1/2, 1)` over the samples
/// and the nodes (0 for no noise).
fn noise_exponent(profile: &Profile, nodes: &[f64]) -> i32 {
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
fn rescale(a: FluidAnalysis, e: i32) -> FluidAnalysis {
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
            ..c
        }),
        ..a
    }
}

/// Whether `bound V - Q ⪰ 0` (with `V ≻ 0`) is proved by the verified
/// Cholesky test for each `(m, bound)`: x-mode `m` of the finest grid, with
/// the matrices built exactly as [`analyse`] builds them (the same noise
/// normalisation, choice of functional and form). `false` for a mode that
/// does not exist, for a profile that admits no form, and for the
/// compressible model (which has no matrices: its `Sigma^2 = 0` is
/// structural). This is what `verify check` runs on a stated bound below the
/// one it re-derives: a stated number is accepted only when it is proved.
pub fn prove_mode_bounds(problem: &FluidProblem, bounds: &[(usize, f64)]) -> Vec<bool> {
    if matches!(problem.model, FluidModel::Compressible { .. }) || bounds.is_empty() {
        return vec![false; bounds.len()];
    }
    let p = &problem.profile;
    let fine = YGrid::new(p.boundary, p.interval.0, p.interval.1, problem.ny);
    let (scaled, e) = normalise_noise(problem, &fine);
    let profile = scaled.profile;
    let coef = profile.coefficients(&fine);
    let Some(form) = form_for(&choose(&profile), &profile, &coef, &fine) else { return vec![false; bounds.len()] };
    let ks = wavenumbers(problem);
    let f = pow2(-e);
    bounds
        .par_iter()
        .map(|&(m, bound)| {
            let Some(&(_, k)) = ks.iter().find(|(mm, _)| *mm == m) else { return false };
            // bound / 4^e, rounded down if it underflows: proving a smaller
            // bound proves the larger one (V ≻ 0).
            let normalised = bound * f * f;
            let normalised = if normalised < f64::MIN_POSITIVE { normalised.next_down().max(0.0) } else { normalised };
            Mode::new(&fine, k).verify(&form, &coef, normalised) == (true, true)
        })
        .collect()
}

fn analyse_normalised(problem: &FluidProblem, settings: &FluidSettings, fine: &YGrid) -> FluidAnalysis {
    let profile = &problem.profile;
    let fine = fine.clone();
    let paper_bound = profile.paper_bound();
    if let FluidModel::Compressible { sound_speed } = problem.model {
        return analyse_compressible(problem, settings, sound_speed, paper_bound);
    }
    let ks = wavenumbers(problem);
    let choice = choose(profile);
    let coef = profile.coefficients(&fine);
    let summary = form_summary(&choice);
    let tol = settings.lanczos_tolerance;

    // The paper's functional (c = 0) and the Galilean-shift curve.
    let paper_form_at = |grid: &YGrid, coef: &Coefficients| -> Option<Form> {
        match &choice {
            Choice::Forced { shift, .. } if shift.abs() == 0.0 => form_for(&choice, profile, coef, grid),
            Choice::Forced { .. } | Choice::Enstrophy | Choice::NoForm { .. } => None,
            Choice::Pseudomomentum { .. } => shifted_form(coef, 0.0),
        }
    };
    let paper_choice_sigma2 = paper_form_at(&fine, &coef).and_then(|f| sigma2_all_modes(&fine, &coef, &f, &ks, tol));
    let shift_curve = match &choice {
        Choice::Pseudomomentum { sign } => {
            let samples = profile.samples(crate::constants::PROFILE_SAMPLES);
            let us: Vec<f64> = samples.iter().map(|y| profile.u[0].eval(*y)).collect();
            let (umin, umax) = us.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(*v), h.max(*v)));
            let range = (umax - umin).max(1e-12 * umax.abs().max(1.0));
            // U'' > 0 needs U + c > 0 (c > -min U); U'' < 0 needs U + c < 0 (c < -max U)
            (0..8)
                .filter_map(|j| {
                    let d = range * 4f64.powi(j - 2);
                    let c = if sign.is_positive() { -umin + d } else { -umax - d };
                    let f = shifted_form(&coef, c)?;
                    Some((c, sigma2_all_modes(&fine, &coef, &f, &ks, tol)?))
                })
                .collect()
        }
        _ => vec![],
    };

    let (form, stable_reason) = match form_and_reason(&choice, profile, &coef, &fine, &summary) {
        Ok(x) => x,
        Err(reason) => {
            return inconclusive_or_unstable(
                problem,
                settings,
                reason,
                summary,
                paper_bound,
                paper_choice_sigma2,
                shift_curve,
            )
        }
    };

    // Per mode at the finest grid: Lanczos, then the dense verified check.
    let per_mode: Vec<Option<ModeResult>> = ks
        .par_iter()
        .map(|&(m, k)| {
            let mode = Mode::new(&fine, k);
            let s = mode.sigma2(&form, &coef, tol).ok()?;
            // Mode::sigma2 never returns a non-finite value; flooring NaN at 0
            // would round towards "stable".
            let sigma2 = s.lambda_max.max(0.0);
            let mut upper = None;
            let mut form_verified = false;
            let mut margin = VERIFY_MARGIN_START;
            for _ in 0..VERIFY_ATTEMPTS {
                let bar = sigma2 * (1.0 + margin) + margin * VERIFY_RITZ_WEIGHT * s.ritz.scale + s.ritz.residual;
                let (def, ineq) = mode.verify(&form, &coef, bar);
                form_verified = def;
                if !def {
                    break;
                }
                if ineq {
                    upper = Some(bar);
                    break;
                }
                margin *= VERIFY_MARGIN_GROWTH;
            }
            Some(ModeResult { m, k, sigma2, sigma2_upper: upper, form_verified, iterations: s.ritz.iterations })
        })
        .collect();
    if let Some(pos) = per_mode.iter().position(|r| r.is_none() || !r.as_ref().is_some_and(|r| r.form_verified)) {
        let (m, k) = ks[pos];
        let reason = format!(
            "{}; the second variation could not be shown definite for x-mode m = {m} (k = {k:.6}){}",
            summary.casimir_weight,
            if summary.sign == Some(Sign::Negative) {
                ": Arnold's second criterion (K + M w negative definite) fails there"
            } else {
                ""
            }
        );
        return inconclusive_or_unstable(
            problem,
            settings,
            reason,
            summary,
            paper_bound,
            paper_choice_sigma2,
            shift_curve,
        );
    }
    let modes: Vec<ModeResult> = per_mode.into_iter().flatten().collect();
    let sigma2 = modes.iter().map(|r| r.sigma2).fold(0.0, f64::max);
    let sigma2_upper = modes.iter().try_fold(0.0f64, |acc, r| r.sigma2_upper.map(|u| acc.max(u)));
    let verification = Some(if form.energy == 0.0 {
        VerificationLevel::ExactStructure
    } else if sigma2_upper.is_some() {
        VerificationLevel::VerifiedFloat
    } else {
        VerificationLevel::Float
    });

    // Convergence table (Lanczos at each resolution).
    let mut convergence = vec![];
    let mut drift_residual = None;
    for ny in table_resolutions(problem.ny, settings.convergence_from) {
        let (grid, coef) = if ny == problem.ny {
            (fine.clone(), coef.clone())
        } else {
            let g = YGrid::new(profile.boundary, profile.interval.0, profile.interval.1, ny);
            let c = profile.coefficients(&g);
            (g, c)
        };
        let Some(f) = form_for(&choice, profile, &coef, &grid) else { continue };
        if drift_residual.is_none() {
            // |sym(V A)| / (|V| |A|), A = -ik R: dimensionless, so it does not
            // grow with the size of U (it did when divided by |V| alone).
            let r = ks
                .par_iter()
                .map(|(_, k)| {
                    let mode = Mode::new(&grid, *k);
                    let scale = mode.form_matrix(&f).norm() * k * mode.drift_matrix(&coef).norm();
                    mode.drift_residual(&f, &coef).norm() / scale
                })
                .reduce(|| 0.0, |a, b| if a.is_nan() || b.is_nan() { f64::NAN } else { a.max(b) });
            drift_residual = r.is_finite().then_some(r);
        }
        let s = if ny == problem.ny { Some(sigma2) } else { sigma2_all_modes(&grid, &coef, &f, &ks, tol) };
        let p = if ny == problem.ny {
            paper_choice_sigma2
        } else {
            paper_form_at(&grid, &coef).and_then(|pf| sigma2_all_modes(&grid, &coef, &pf, &ks, tol))
        };
        convergence.push(ConvergenceRow { ny, sigma2: s, sigma2_paper_choice: p });
    }

    let reason = stable_reason;
    FluidAnalysis {
        verdict: Verdict::Stable,
        reason,
        form: summary,
        sigma2: Some(sigma2),
        sigma2_upper,
        verification,
        modes,
        convergence,
        paper_bound: Some(paper_bound),
        paper_choice_sigma2,
        shift_curve,
        drift_residual,
        instability: None,
        compressible: None,
    }
}

fn form_summary(choice: &Choice) -> FormSummary {
    match choice {
        Choice::Pseudomomentum { sign } => FormSummary {
            kind: "pseudomomentum",
            energy: 0.0,
            galilean_shift: None,
            sign: Some(*sign),
            casimir_weight: "Phi''(omega_e) = 1/U'' (Casimir plus momentum, energy coefficient 0)".into(),
        },
        Choice::Enstrophy => FormSummary {
            kind: "enstrophy",
            energy: 0.0,
            galilean_shift: None,
            sign: Some(Sign::Positive),
            casimir_weight: "Phi''(omega_e) = 1 (enstrophy)".into(),
        },
        Choice::Forced { shift, zeros, sign } => FormSummary {
            kind: "energy_casimir",
            energy: 1.0,
            galilean_shift: Some(*shift),
            sign: Some(*sign),
            casimir_weight: format!(
                "U'' vanishes at y = {} so the Galilean shift c = {shift:.6} is forced and Phi''(omega_e) = (U + c)/U''",
                zeros.iter().map(|z| format!("{z:.6}")).collect::<Vec<_>>().join(", ")
            ),
        },
        Choice::NoForm { .. } => FormSummary { kind: "none", energy: 0.0, galilean_shift: None, sign: None, casimir_weight: "none".into() },
    }
}

/// The largest growth rate `k max Im eig(R)` of mode `k` at resolution `ny`.
fn growth_rate(profile: &Profile, ny: usize, k: f64) -> Option<f64> {
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

fn inconclusive_or_unstable(
    problem: &FluidProblem,
    settings: &FluidSettings,
    reason: String,
    form: FormSummary,
    paper_bound: f64,
    paper_choice_sigma2: Option<f64>,
    shift_curve: Vec<(f64, f64)>,
) -> FluidAnalysis {
    let profile = &problem.profile;
    let mut ny = settings.instability_ny.min(problem.ny);
    if profile.boundary == Boundary::Walls {
        ny -= ny % crate::grid::ELEMENT_DEGREE;
    }
    let coarse = ny / 2 - (ny / 2) % if profile.boundary == Boundary::Walls { crate::grid::ELEMENT_DEGREE } else { 1 };
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
            let fine = growth_rate(profile, ny, k)?;
            let coarse_rate = growth_rate(profile, coarse.max(16), k)?;
            // A growth rate is evidence when it is far above rounding
            // (relative to k max|U|) and converged between the two grids.
            let floor = crate::constants::INSTABILITY_FLOOR * k * u_scale;
            (fine > floor
                && coarse_rate > floor
                && (fine - coarse_rate).abs() <= crate::constants::INSTABILITY_AGREEMENT * fine)
                .then_some(UnstableMode { m, k, growth_rate: fine, growth_rate_coarse: coarse_rate, ny })
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

/// The compressible model (see `docs/fluids.md`): the coadjoint action of
/// the noise `(eta(y), 0)` on the momentum `m = rho u` contains
/// `(grad sigma)^T m = (0, U eta')`, a y-momentum source at the equilibrium
/// that no pressure can absorb (the density is not constrained), so the
/// equilibrium is kept only by noise with `U eta' = 0`, i.e. constant
/// `eta` where the flow is non-zero. For such noise `B_k = -ik eta_k I`
/// commutes with the drift and with the form, so `Sigma^2 = 0`; the form
/// `|du|^2 + 2(U + c) drho du_x + c_s^2 drho^2 + w (curl du + U' drho)^2`
/// is positive definite iff `w >= 0` and `|U + c| < c_s` on the interval.
///
/// What `stable` rests on is proved, not sampled: every `eta_k'` vanishes
/// identically (interval arithmetic, [`crate::expr::Derivative::sign_on`]),
/// and the range of `U` over the closed interval is enclosed rigorously, so
/// that `|U + c| < c_s` holds everywhere for the chosen `c`. The weight's
/// sign is proved for the pseudomomentum and the uniform flow (level
/// `exact_structure`) and only sampled for a forced shift (level `float`).
/// Noise whose residual `sup |U eta'|` is far above rounding on the samples
/// is `noise_incompatible` (level `float`); noise in between, neither proved
/// compatible nor clearly not, is `inconclusive`.
fn analyse_compressible(
    problem: &FluidProblem,
    settings: &FluidSettings,
    sound_speed: f64,
    paper_bound: f64,
) -> FluidAnalysis {
    let profile = &problem.profile;
    let (a, b) = profile.interval;
    let ys = profile.samples(crate::constants::FINE_SAMPLES);
    let us: Vec<f64> = ys.iter().map(|y| profile.u[0].eval(*y)).collect();
    let u_abs = us.iter().fold(0.0f64, |m, u| m.max(u.abs()));
    let noise_residuals: Vec<f64> = profile
        .eta
        .iter()
        .map(|[_, d]| ys.iter().zip(&us).map(|(y, u)| (u * d.eval(*y)).abs()).fold(0.0, f64::max))
        .collect();
    let constant_noise: Vec<bool> = profile
        .eta
        .iter()
        .map(|[_, d]| {
            d.expr().constant().is_some() || d.sign_on(a, b, crate::choice::SIGN_PROOF_BUDGET) == SignProof::Zero
        })
        .collect();
    let incompressible = analyse(&FluidProblem { model: FluidModel::Incompressible, ..problem.clone() }, settings).ok();
    let (incompressible_verdict, incompressible_sigma2) =
        incompressible.as_ref().map(|a| (a.verdict, a.sigma2)).unwrap_or((Verdict::Inconclusive, None));
    let choice = choose(profile);
    // A rigorous enclosure of the range of U over the closed interval.
    let range = profile.u[0].range_on(a, b, 1024);
    let uniform = profile.u[1].sign_on(a, b, crate::choice::SIGN_PROOF_BUDGET) == SignProof::Zero;
    let c_s = Interval::point(sound_speed);
    // The largest c with c + U_hi < c_s (exactly, through the interval's lower bound).
    let below_cs = |u_hi: f64| (c_s - Interval::point(u_hi)).lo;
    let above = |x: f64| -x; // negation is exact
    let (shift_interval, proved_weight) = if !(range.lo.is_finite() && range.hi.is_finite()) {
        (None, false)
    } else {
        match &choice {
            Choice::Pseudomomentum { sign } if sign.is_positive() => {
                // U + c > 0 (w = (U + c)/U'' >= 0) and U + c < c_s
                let (lo, hi) = (above(range.lo), below_cs(range.hi));
                ((lo < hi).then_some((lo, hi)), true)
            }
            Choice::Pseudomomentum { .. } => {
                // U'' < 0: U + c < 0 and U + c > -c_s
                let (lo, hi) = ((Interval::point(-sound_speed) - Interval::point(range.lo)).hi, above(range.hi));
                ((lo < hi).then_some((lo, hi)), true)
            }
            _ if uniform => {
                // U constant (U' = 0 proved): c = -U brings the flow to rest
                let c = -(0.5 * range.lo + 0.5 * range.hi);
                let w = Interval::point(c) + range;
                ((w.hi < sound_speed && w.lo > -sound_speed).then_some((c, c)), true)
            }
            Choice::Forced { shift, sign, .. } if sign.is_positive() => {
                let worst = Interval::point(*shift) + range;
                ((worst.hi < sound_speed && worst.lo > -sound_speed).then_some((*shift, *shift)), false)
            }
            _ => (None, false),
        }
    };
    let mut summary = form_summary(&choice);
    let compressible = CompressibleReport {
        sound_speed,
        noise_residuals: noise_residuals.clone(),
        shift_interval,
        incompressible_verdict,
        incompressible_sigma2,
    };
    let base = FluidAnalysis {
        compressible: Some(compressible),
        ..FluidAnalysis::without_certificate(Verdict::Inconclusive, String::new(), summary.clone(), paper_bound)
    };
    let scale = u_abs.max(f64::MIN_POSITIVE);
    if let Some(i) = (0..noise_residuals.len()).find(|&i| !constant_noise[i] && noise_residuals[i] > 1e-12 * scale) {
        return FluidAnalysis {
            verdict: Verdict::NoiseIncompatible,
            verification: Some(VerificationLevel::Float),
            reason: format!(
                "the coadjoint action of noise[{i}] on the momentum rho u contains (grad sigma)^T m = (0, U eta'), which is not zero at the equilibrium (compressible.noise_residuals gives sup |U eta'|): in compressible flow no pressure absorbs it (in incompressible flow it is a gradient), so the noise moves the shear flow; compatible noise has U eta' = 0 (constant eta where U != 0)"
            ),
            ..base
        };
    }
    if let Some(i) = constant_noise.iter().position(|c| !c) {
        return FluidAnalysis {
            reason: format!(
                "noise[{i}]: U eta' is below 1e-12 of max|U| on every sample, but eta' could not be proved identically zero, so neither compatibility (B_k a multiple of the identity) nor incompatibility is established"
            ),
            ..base
        };
    }
    let Some((lo, hi)) = shift_interval else {
        let reason = match &choice {
            Choice::NoForm { reason } => reason.clone(),
            Choice::Forced { sign, .. } if !sign.is_positive() => "the forced Casimir weight is negative, and a compressible form cannot be negative definite (the acoustic energy is positive)".into(),
            _ => format!(
                "no Galilean shift c makes the form definite: it needs |U + c| < c_s = {sound_speed} and (U + c)/U'' >= 0 on the whole interval, but U ranges over [{:.6}, {:.6}] (a rigorous enclosure)",
                range.lo, range.hi
            ),
        };
        return FluidAnalysis { reason, ..base };
    };
    let c = if lo == hi { lo } else { 0.5 * lo + 0.5 * hi };
    summary.energy = 1.0;
    summary.galilean_shift = Some(c);
    summary.sign = Some(Sign::Positive);
    summary.kind = "energy_casimir_momentum";
    let worst = Interval::point(c) + range;
    let worst = worst.hi.abs().max(worst.lo.abs());
    let ks = wavenumbers(problem);
    let modes = ks
        .iter()
        .map(|&(m, k)| ModeResult { m, k, sigma2: 0.0, sigma2_upper: Some(0.0), form_verified: true, iterations: 0 })
        .collect();
    FluidAnalysis {
        verdict: Verdict::Stable,
        reason: format!(
            "every noise field is constant (eta' = 0 proved), so B_k = -ik eta_k I commutes with the drift and the form and Sigma^2 = 0; the form with Galilean shift c = {c:.6} (admissible c in [{lo:.6}, {hi:.6}]) is positive definite because |U + c| <= {worst:.6} < c_s = {sound_speed} on the whole interval (a rigorous enclosure of U){}",
            if proved_weight { "" } else { ", with the Casimir weight (U + c)/U'' non-negative on a fine sample (not proved: level float)" }
        ),
        form: summary,
        sigma2: Some(0.0),
        sigma2_upper: Some(0.0),
        verification: Some(if proved_weight { VerificationLevel::ExactStructure } else { VerificationLevel::Float }),
        modes,
        ..base
    }
}
