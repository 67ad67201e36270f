//! The fluid pipeline: profile checks, the choice of functional, Sigma^2 per
//! x-mode (Lanczos at every resolution of the convergence table, the dense
//! verified check at the finest), the paper's constants beside ours, the
//! linear-instability test, and the compressible noise-compatibility test.

use crate::choice::{casimir_weight, choose, Choice};
use crate::grid::{Boundary, YGrid};
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

/// The verdicts (as in the finite-dimensional pipeline; a shear flow is
/// always an equilibrium, so `not_an_equilibrium` does not occur).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FluidVerdict {
    /// A definite conserved form with a certified Sigma^2.
    Stable,
    /// An eigenvalue with positive real part, converged under refinement.
    LinearlyUnstable,
    /// Neither.
    Inconclusive,
    /// The noise moves the equilibrium.
    NoiseIncompatible,
}

impl FluidVerdict {
    /// Name in certificates.
    pub fn as_str(&self) -> &'static str {
        match self {
            FluidVerdict::Stable => "stable",
            FluidVerdict::LinearlyUnstable => "linearly_unstable",
            FluidVerdict::Inconclusive => "inconclusive",
            FluidVerdict::NoiseIncompatible => "noise_incompatible",
        }
    }
}

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
    /// Sign making the form positive.
    pub sign: f64,
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
    pub incompressible_verdict: FluidVerdict,
    /// Its Sigma^2.
    pub incompressible_sigma2: Option<f64>,
}

/// Everything the fluid pipeline found.
#[derive(Clone, Debug, PartialEq)]
pub struct FluidAnalysis {
    /// The verdict.
    pub verdict: FluidVerdict,
    /// Why, in a sentence.
    pub reason: String,
    /// The functional.
    pub form: FormSummary,
    /// Sigma^2 (max over modes), if stable.
    pub sigma2: Option<f64>,
    /// Verified upper bound of Sigma^2 (max over modes), if every mode verified.
    pub sigma2_upper: Option<f64>,
    /// How the bound was verified.
    pub verification: &'static str,
    /// Per-mode values at the finest grid.
    pub modes: Vec<ModeResult>,
    /// Sigma^2 under refinement.
    pub convergence: Vec<ConvergenceRow>,
    /// The paper's `sup_y sum_k eta_k'(y)^2`.
    pub paper_bound: f64,
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
    fn without_certificate(verdict: FluidVerdict, reason: String, form: FormSummary, paper_bound: f64) -> Self {
        FluidAnalysis {
            verdict,
            reason,
            form,
            sigma2: None,
            sigma2_upper: None,
            verification: "none",
            modes: vec![],
            convergence: vec![],
            paper_bound,
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
        Choice::Enstrophy => Some(Form { energy: 0.0, w: vec![1.0; grid.n()], sign: 1.0 }),
        Choice::Forced { shift, zeros, sign } => Some(Form {
            energy: 1.0,
            w: grid.nodes().iter().map(|y| casimir_weight(profile, 1.0, *shift, zeros, *y)).collect(),
            sign: *sign,
        }),
        Choice::NoForm { .. } => None,
    }
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
        Some(Form { energy: 1.0, w, sign: 1.0 })
    } else if w.iter().all(|x| *x < 0.0) {
        Some(Form { energy: 1.0, w, sign: -1.0 })
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
pub fn analyse(problem: &FluidProblem, settings: &FluidSettings) -> Result<FluidAnalysis, FluidError> {
    let profile = &problem.profile;
    let fine = YGrid::new(profile.boundary, profile.interval.0, profile.interval.1, problem.ny);
    profile.check(fine.nodes())?;
    let paper_bound = profile.paper_bound();
    if let FluidModel::Compressible { sound_speed } = problem.model {
        return Ok(analyse_compressible(problem, settings, sound_speed, paper_bound));
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
            let samples = profile.samples(4096);
            let us: Vec<f64> = samples.iter().map(|y| profile.u[0].eval(*y)).collect();
            let (umin, umax) = us.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(*v), h.max(*v)));
            let range = (umax - umin).max(1e-12 * umax.abs().max(1.0));
            // U'' > 0 needs U + c > 0 (c > -min U); U'' < 0 needs U + c < 0 (c < -max U)
            (0..8)
                .filter_map(|j| {
                    let d = range * 4f64.powi(j - 2);
                    let c = if *sign > 0.0 { -umin + d } else { -umax - d };
                    let f = shifted_form(&coef, c)?;
                    Some((c, sigma2_all_modes(&fine, &coef, &f, &ks, tol)?))
                })
                .collect()
        }
        _ => vec![],
    };

    let Some(form) = form_for(&choice, profile, &coef, &fine) else {
        let reason = match &choice {
            Choice::NoForm { reason } => reason.clone(),
            _ => unreachable!(),
        };
        return Ok(inconclusive_or_unstable(
            problem,
            settings,
            reason,
            summary,
            paper_bound,
            paper_choice_sigma2,
            shift_curve,
        ));
    };

    // Per mode at the finest grid: Lanczos, then the dense verified check.
    let per_mode: Vec<Option<ModeResult>> = ks
        .par_iter()
        .map(|&(m, k)| {
            let mode = Mode::new(&fine, k);
            let s = mode.sigma2(&form, &coef, tol).ok()?;
            let sigma2 = s.lambda_max.max(0.0);
            let mut upper = None;
            let mut form_verified = false;
            let mut margin = 1e-8;
            for _ in 0..5 {
                let bar = sigma2 * (1.0 + margin) + margin * 1e-3 * s.ritz.scale + s.ritz.residual;
                let (def, ineq) = mode.verify(&form, &coef, bar);
                form_verified = def;
                if !def {
                    break;
                }
                if ineq {
                    upper = Some(bar);
                    break;
                }
                margin *= 30.0;
            }
            Some(ModeResult { m, k, sigma2, sigma2_upper: upper, form_verified, iterations: s.ritz.iterations })
        })
        .collect();
    if let Some(pos) = per_mode.iter().position(|r| r.is_none() || !r.as_ref().is_some_and(|r| r.form_verified)) {
        let (m, k) = ks[pos];
        let reason = format!(
            "{}; the second variation could not be shown definite for x-mode m = {m} (k = {k:.6}){}",
            summary.casimir_weight,
            if summary.sign < 0.0 { ": Arnold's second criterion (K + M w negative definite) fails there" } else { "" }
        );
        return Ok(inconclusive_or_unstable(
            problem,
            settings,
            reason,
            summary,
            paper_bound,
            paper_choice_sigma2,
            shift_curve,
        ));
    }
    let modes: Vec<ModeResult> = per_mode.into_iter().flatten().collect();
    let sigma2 = modes.iter().map(|r| r.sigma2).fold(0.0, f64::max);
    let sigma2_upper = modes.iter().try_fold(0.0f64, |acc, r| r.sigma2_upper.map(|u| acc.max(u)));
    let verification = if form.energy == 0.0 {
        "exact_structure"
    } else if sigma2_upper.is_some() {
        "verified_float"
    } else {
        "float"
    };

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
        let f = form_for(&choice, profile, &coef, &grid).expect("form exists at the finest grid");
        if drift_residual.is_none() {
            let r = ks
                .par_iter()
                .map(|(_, k)| {
                    let mode = Mode::new(&grid, *k);
                    mode.drift_residual(&f, &coef).norm() / mode.form_matrix(&f).norm()
                })
                .reduce(|| 0.0, f64::max);
            drift_residual = Some(r);
        }
        let s = if ny == problem.ny { Some(sigma2) } else { sigma2_all_modes(&grid, &coef, &f, &ks, tol) };
        let p = if ny == problem.ny {
            paper_choice_sigma2
        } else {
            paper_form_at(&grid, &coef).and_then(|pf| sigma2_all_modes(&grid, &coef, &pf, &ks, tol))
        };
        convergence.push(ConvergenceRow { ny, sigma2: s, sigma2_paper_choice: p });
    }

    let reason = match &choice {
        Choice::Pseudomomentum { .. } => "U'' has one sign (Rayleigh): the pseudomomentum int omega^2/U'' (Casimir plus x-momentum, the limit |c| -> infinity of energy + Casimir + c momentum) is conserved by the drift and by every noise field (eta(y), 0), so Sigma^2 = 0".to_string(),
        Choice::Enstrophy => "U'' = 0: the enstrophy int omega^2 is conserved by the drift and the noise, so Sigma^2 = 0".to_string(),
        Choice::Forced { .. } => format!("{}; the form is definite for every x-mode and Sigma^2 is the largest generalised eigenvalue of (Q, V) over the modes", summary.casimir_weight),
        Choice::NoForm { .. } => unreachable!(),
    };
    Ok(FluidAnalysis {
        verdict: FluidVerdict::Stable,
        reason,
        form: summary,
        sigma2: Some(sigma2),
        sigma2_upper,
        verification,
        modes,
        convergence,
        paper_bound,
        paper_choice_sigma2,
        shift_curve,
        drift_residual,
        instability: None,
        compressible: None,
    })
}

fn form_summary(choice: &Choice) -> FormSummary {
    match choice {
        Choice::Pseudomomentum { sign } => FormSummary {
            kind: "pseudomomentum",
            energy: 0.0,
            galilean_shift: None,
            sign: *sign,
            casimir_weight: "Phi''(omega_e) = 1/U'' (Casimir plus momentum, energy coefficient 0)".into(),
        },
        Choice::Enstrophy => FormSummary {
            kind: "enstrophy",
            energy: 0.0,
            galilean_shift: None,
            sign: 1.0,
            casimir_weight: "Phi''(omega_e) = 1 (enstrophy)".into(),
        },
        Choice::Forced { shift, zeros, sign } => FormSummary {
            kind: "energy_casimir",
            energy: 1.0,
            galilean_shift: Some(*shift),
            sign: *sign,
            casimir_weight: format!(
                "U'' vanishes at y = {} so the Galilean shift c = {shift:.6} is forced and Phi''(omega_e) = (U + c)/U''",
                zeros.iter().map(|z| format!("{z:.6}")).collect::<Vec<_>>().join(", ")
            ),
        },
        Choice::NoForm { .. } => FormSummary { kind: "none", energy: 0.0, galilean_shift: None, sign: 0.0, casimir_weight: "none".into() },
    }
}

/// The largest growth rate `k max Im eig(R)` of mode `k` at resolution `ny`.
fn growth_rate(profile: &Profile, ny: usize, k: f64) -> Option<f64> {
    let grid = YGrid::new(profile.boundary, profile.interval.0, profile.interval.1, ny);
    let coef = profile.coefficients(&grid);
    let r = Mode::new(&grid, k).drift_matrix(&coef);
    let n = r.nrows();
    let m = faer::Mat::<f64>::from_fn(n, n, |i, j| r[(i, j)]);
    let values = m.eigenvalues().ok()?;
    // A = -ik R: Re(-ik lambda) = k Im(lambda)
    Some(values.iter().map(|z| k * z.im).fold(f64::NEG_INFINITY, f64::max))
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
    let u_scale =
        profile.samples(1024).iter().map(|y| profile.u[0].eval(*y).abs()).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
    let rates: Vec<Option<UnstableMode>> =
        ks.par_iter()
            .map(|&(m, k)| {
                let fine = growth_rate(profile, ny, k)?;
                let coarse_rate = growth_rate(profile, coarse.max(16), k)?;
                // A growth rate is evidence when it is far above rounding
                // (relative to k max|U|) and converged between the two grids.
                let floor = 1e-6 * k * u_scale;
                (fine > floor && coarse_rate > floor && (fine - coarse_rate).abs() <= 1e-3 * fine)
                    .then_some(UnstableMode { m, k, growth_rate: fine, growth_rate_coarse: coarse_rate, ny })
            })
            .collect();
    let instability = rates.into_iter().flatten().max_by(|a, b| a.growth_rate.total_cmp(&b.growth_rate));
    let (verdict, reason) = match &instability {
        Some(u) => (
            FluidVerdict::LinearlyUnstable,
            format!(
                "x-mode m = {} (k = {:.6}) grows at rate {:.6e} (ny = {}; {:.6e} at half the resolution); {reason}",
                u.m, u.k, u.growth_rate, u.ny, u.growth_rate_coarse
            ),
        ),
        None => (FluidVerdict::Inconclusive, reason),
    };
    FluidAnalysis {
        verification: if verdict == FluidVerdict::LinearlyUnstable { "float" } else { "none" },
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
fn analyse_compressible(
    problem: &FluidProblem,
    settings: &FluidSettings,
    sound_speed: f64,
    paper_bound: f64,
) -> FluidAnalysis {
    let profile = &problem.profile;
    let ys = profile.samples(8192);
    let us: Vec<f64> = ys.iter().map(|y| profile.u[0].eval(*y)).collect();
    let u_abs = us.iter().fold(0.0f64, |m, u| m.max(u.abs()));
    let noise_residuals: Vec<f64> = profile
        .eta
        .iter()
        .map(|[_, d]| ys.iter().zip(&us).map(|(y, u)| (u * d.eval(*y)).abs()).fold(0.0, f64::max))
        .collect();
    let incompressible = analyse(&FluidProblem { model: FluidModel::Incompressible, ..problem.clone() }, settings).ok();
    let (incompressible_verdict, incompressible_sigma2) =
        incompressible.as_ref().map(|a| (a.verdict, a.sigma2)).unwrap_or((FluidVerdict::Inconclusive, None));
    let choice = choose(profile);
    let (umin, umax) = us.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(*v), h.max(*v)));
    let shift_interval = match &choice {
        Choice::Pseudomomentum { sign } => {
            let (lo, hi) = if *sign > 0.0 { (-umin, sound_speed - umax) } else { (-sound_speed - umin, -umax) };
            (lo < hi).then_some((lo, hi))
        }
        Choice::Enstrophy if umax - umin <= 1e-12 * u_abs.max(1.0) => Some((-umin, -umin)),
        Choice::Forced { shift, sign, .. } if *sign > 0.0 => {
            let worst = us.iter().fold(0.0f64, |m, u| m.max((u + shift).abs()));
            (worst < sound_speed).then_some((*shift, *shift))
        }
        _ => None,
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
        ..FluidAnalysis::without_certificate(FluidVerdict::Inconclusive, String::new(), summary.clone(), paper_bound)
    };
    let scale = u_abs.max(f64::MIN_POSITIVE);
    let offending: Vec<usize> =
        noise_residuals.iter().enumerate().filter(|(_, r)| **r > 1e-12 * scale).map(|(i, _)| i).collect();
    if !offending.is_empty() {
        let i = offending[0];
        return FluidAnalysis {
            verdict: FluidVerdict::NoiseIncompatible,
            verification: "float",
            reason: format!(
                "the coadjoint action of noise[{i}] on the momentum rho u contains (grad sigma)^T m = (0, U eta'), of size up to {:.6e} at the equilibrium: in compressible flow no pressure absorbs it (in incompressible flow it is a gradient), so the noise moves the shear flow; compatible noise has U eta' = 0 (constant eta where U != 0)",
                noise_residuals[i]
            ),
            ..base
        };
    }
    let Some((lo, hi)) = shift_interval else {
        let reason = match &choice {
            Choice::NoForm { reason } => reason.clone(),
            Choice::Forced { sign, .. } if *sign < 0.0 => "the forced Casimir weight is negative, and a compressible form cannot be negative definite (the acoustic energy is positive)".into(),
            _ => format!(
                "no Galilean shift c makes the form definite: it needs |U + c| < c_s = {sound_speed} and (U + c)/U'' >= 0 on the whole interval, but U ranges over [{umin:.6}, {umax:.6}]"
            ),
        };
        return FluidAnalysis { reason, ..base };
    };
    let c = 0.5 * (lo + hi);
    summary.energy = 1.0;
    summary.galilean_shift = Some(c);
    summary.sign = 1.0;
    summary.kind = "energy_casimir_momentum";
    let worst = us.iter().fold(0.0f64, |m, u| m.max((u + c).abs()));
    let ks = wavenumbers(problem);
    let modes = ks
        .iter()
        .map(|&(m, k)| ModeResult { m, k, sigma2: 0.0, sigma2_upper: Some(0.0), form_verified: true, iterations: 0 })
        .collect();
    FluidAnalysis {
        verdict: FluidVerdict::Stable,
        reason: format!(
            "every noise field is constant, so B_k = -ik eta_k I commutes with the drift and the form and Sigma^2 = 0; the form with Galilean shift c = {c:.6} (admissible c in [{lo:.6}, {hi:.6}]) is positive definite because max |U + c| = {worst:.6} < c_s = {sound_speed}"
        ),
        form: summary,
        sigma2: Some(0.0),
        sigma2_upper: Some(0.0),
        verification: "exact_structure",
        modes,
        ..base
    }
}
