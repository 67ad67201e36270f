//! The fluid pipeline: profile checks, the choice of functional, Sigma^2 per
//! x-mode (Lanczos at every resolution of the convergence table, the dense
//! verified check at the finest), the paper's constants beside ours, the
//! linear-instability test, and the compressible noise-compatibility test.

use crate::choice::{casimir_weight, choose, Choice};
use crate::constants::{ladder_margin, VERIFY_ATTEMPTS, VERIFY_MARGIN_GROWTH, VERIFY_RITZ_WEIGHT};
use crate::expr::SignProof;
use crate::grid::{Boundary, YGrid};
use crate::interval::Interval;
use crate::modes::{Coefficients, Form, Mode};
use crate::profile::{Profile, ProfileError};
use rayon::prelude::*;

mod compressible;
mod forms;
mod generator;
mod incompressible;
mod instability;
mod pseudomomentum;
mod scaling;
mod shift_invert;
mod simulation;

use compressible::*;
use forms::*;
use generator::*;
use incompressible::*;
use instability::*;
use scaling::*;

pub use forms::chosen_form;
pub use incompressible::prove_mode_bounds;
pub use pseudomomentum::{discrete_pseudomomentum, DiscretePseudomomentum, PseudomomentumRow};
pub use simulation::{mode_study, EnsembleTiming, ModeStudy};

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
pub use outcome::{Cancelled, Progress, Sign, Verdict, VerificationLevel};

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

/// What the linear-instability search tried for one x-mode
/// ([`FluidAnalysis::instability_search`]): each grid's best candidate and
/// why the search stopped.
#[derive(Clone, Debug, PartialEq)]
pub struct ModeSearch {
    /// Index `m`.
    pub m: usize,
    /// Wavenumber.
    pub k: f64,
    /// The floor a growth rate must exceed to count:
    /// [`crate::constants::INSTABILITY_FLOOR`] `k max |U|`.
    pub floor: f64,
    /// The grids tried, in order (each twice the one before, from half of
    /// `instability_ny`).
    pub grids: Vec<SearchedGrid>,
    /// Why the search stopped.
    pub outcome: SearchOutcome,
}

/// One grid of the instability search and its best candidate.
#[derive(Clone, Debug, PartialEq)]
pub struct SearchedGrid {
    /// Resolution.
    pub ny: usize,
    /// The candidate's growth rate `k Im c` (`c` an eigenvalue of the drift
    /// `R`, the phase speed); `None` if the eigenvalue solve failed.
    pub growth_rate: Option<f64>,
    /// Its phase speed `Re c`.
    pub phase_speed: Option<f64>,
    /// `false`: the eigenvalue of largest `Im c` of all (dense, up to
    /// [`crate::constants::INSTABILITY_MAX_NY`]); `true`: the eigenvalue
    /// nearest the previous grids' candidate (shift-invert on the banded
    /// pencil, beyond it, up to [`crate::constants::INSTABILITY_TRACK_MAX_NY`]).
    pub tracked: bool,
}

/// Why the instability search of one x-mode stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SearchOutcome {
    /// The rates of the last two grids are above the floor and agree to
    /// [`crate::constants::INSTABILITY_AGREEMENT`]: evidence of
    /// instability (the fastest such mode is [`FluidAnalysis::instability`]).
    Converged,
    /// The rates of the last two grids are both at or below the floor.
    BelowFloor,
    /// A rate above the floor never agreed with the previous grid's, up to
    /// the finest grid allowed (the resolution limit,
    /// [`crate::constants::INSTABILITY_TRACK_MAX_NY`]).
    NotConverged,
    /// The last grid's eigenvalue solve failed: the operator is not finite
    /// (`U` or `k` beyond doubles), the dense eigensolver failed, or the
    /// inverse iteration did not converge to a small residual (two
    /// eigenvalues about as near the candidate).
    SolveFailed,
}

impl SearchOutcome {
    /// Name, for certificates: `converged`, `below_floor`,
    /// `not_converged`, `solve_failed`.
    pub fn as_str(&self) -> &'static str {
        match self {
            SearchOutcome::Converged => "converged",
            SearchOutcome::BelowFloor => "below_floor",
            SearchOutcome::NotConverged => "not_converged",
            SearchOutcome::SolveFailed => "solve_failed",
        }
    }
}

/// The compressible noise-compatibility test.
#[derive(Clone, Debug, PartialEq)]
pub struct CompressibleReport {
    /// `c_s`.
    pub sound_speed: f64,
    /// `sup_y |U eta_k' + r_k'|` per noise field (`r_k` its potential part):
    /// the y-momentum the noise puts into the equilibrium (zero iff
    /// compatible; exactly zero for the compatible completion).
    pub noise_residuals: Vec<f64>,
    /// The noise fields whose residual is clearly above rounding: they move
    /// the equilibrium; `{"transport": eta, "potential": "compatible"}`
    /// would not.
    pub incompatible: Vec<usize>,
    /// The admissible Galilean shifts making the form definite, if any: the
    /// ends `(c_lo, c_hi)`, of which the sonic end (`|U + c| = c_s`
    /// somewhere) is excluded and the other included.
    pub shift_interval: Option<(f64, f64)>,
    /// The verdict of the same profile and noise in the incompressible model.
    pub incompressible_verdict: Verdict,
    /// Its Sigma^2.
    pub incompressible_sigma2: Option<f64>,
    /// The discretised compressible generator, when compatible noise with
    /// non-constant transport needed it.
    pub generator: Option<GeneratorReport>,
}

/// What the compressible generator found (module [`crate::barotropic`]).
#[derive(Clone, Debug, PartialEq)]
pub struct GeneratorReport {
    /// The Galilean shift `c` used (the best of the scan at the coarsest grid).
    pub shift: f64,
    /// A rigorous upper bound of the continuum `Sigma^2` over every x-mode:
    /// `sup_y sum_j eta_j'(y)^2 c_s^2 / (c_s^2 - (U + c)^2)` by interval
    /// arithmetic (`None` if not enclosed).
    pub continuum_bound: Option<f64>,
    /// `(ny, |lambda|_max(Q_B - Q, K))` of the gravest mode at each resolution
    /// of the table: the pointwise noise's discrete defect (zero in the continuum).
    pub casimir_defect: Vec<(usize, f64)>,
    /// `(m, sigma2_B)`: the largest `lambda_max(Q_B, K)` over the certified
    /// x-modes at the spec's `ny` and its mode, `Q_B` the generator form of
    /// the pointwise noise on the discrete `K` (`None` if one could not be
    /// computed): the growth constant of the discretised SDE itself,
    /// `E V(t) <= e^{sigma2_B t} V(0)`. A Lanczos estimate.
    pub discrete_sde: Option<(usize, f64)>,
    /// `|K A + A^H K| / (|K| |A|)` of the gravest mode at the coarsest grid
    /// of at most 64 (dense).
    pub drift_residual: Option<f64>,
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
    /// What the instability search tried, per x-mode (empty where it did
    /// not run: a definite form was found, or the model is compressible).
    pub instability_search: Vec<ModeSearch>,
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
            instability_search: vec![],
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
    /// The analysis was stopped through its [`Progress`] before it ended.
    #[error(transparent)]
    Cancelled(#[from] Cancelled),
}

/// The wavenumbers `k_m = 2 pi m / x_period`, `m = 1..=x_modes`.
pub fn wavenumbers(problem: &FluidProblem) -> Vec<(usize, f64)> {
    (1..=problem.x_modes).map(|m| (m, 2.0 * std::f64::consts::PI * m as f64 / problem.x_period)).collect()
}

/// The bound of rung `r` of the margin ladder for a mode with Lanczos value
/// `sigma2` and Ritz data `ritz`: `sigma2 (1 + m) + m w |T| + residual`,
/// `m` = [`crate::constants::ladder_margin`]`(r)`.
pub(super) fn ladder_bar(sigma2: f64, ritz: &crate::lanczos::Ritz, rung: usize) -> f64 {
    let margin = ladder_margin(rung);
    sigma2 * (1.0 + margin) + margin * VERIFY_RITZ_WEIGHT * ritz.scale + ritz.residual
}

/// The verified bound of one mode: try [`ladder_bar`] for the rungs
/// `r = first_rung .. VERIFY_ATTEMPTS` in turn (so the widest margin tried
/// is the same whatever the first rung), with
/// `verify(bar) = (form definite, bar V - Q definite)`. Returns
/// `(sigma2_upper, form_verified)`.
pub(super) fn verified_upper(
    sigma2: f64,
    ritz: &crate::lanczos::Ritz,
    first_rung: usize,
    verify: impl Fn(f64) -> (bool, bool),
) -> (Option<f64>, bool) {
    let mut form_verified = false;
    for rung in first_rung.min(VERIFY_ATTEMPTS - 1)..VERIFY_ATTEMPTS {
        let bar = ladder_bar(sigma2, ritz, rung);
        let (def, ineq) = verify(bar);
        form_verified = def;
        if !def {
            break;
        }
        if ineq {
            return (Some(bar), true);
        }
    }
    (None, form_verified)
}

/// The rung of the ladder whose bound a mode holds (`None`: a bound from
/// elsewhere, or none).
fn held_rung(r: &ModeResult, ritz: &crate::lanczos::Ritz) -> Option<usize> {
    let upper = r.sigma2_upper?;
    (0..VERIFY_ATTEMPTS).find(|&rung| ladder_bar(r.sigma2, ritz, rung) == upper)
}

/// Narrows the overall bound `max_k sigma2_upper_k` where it is set: the
/// mode holding it climbs the ladder again from rung `narrowest`, up to the
/// rung below its own, and keeps the first bound `prove(index, bar)` proves;
/// then the mode holding the new overall bound does the same, until the
/// mode holding it has been narrowed (or holds a bound that is not a rung
/// of the ladder). `ritz[i]` is mode `i`'s Ritz data.
///
/// Why. Each mode first proves the widest rung
/// ([`verified_mode_bound`]), one check, where a ladder from the
/// narrowest rung takes one check per failed rung: at ny = 1024 most modes
/// need two or three (measured with `walls_margins`: of 32 modes,
/// 19 of `U = y^3 + y/2`, 26 of `channel-sin-walls`, 27 of
/// `kolmogorov-4096`; at 4096 nearly all fail one or two). The
/// certificate's claim is about `Sigma^2 = max_k Sigma^2_k`, so only the
/// modes that set it need narrow bounds; the others keep a verified bound
/// at most `8.1e-3` above their `Sigma^2_k` (the widest rung), below the
/// overall one. When the ladder's outcome is monotone in the rung (a
/// bound proved stays proved when widened), the overall bound is the one
/// the ladder from the narrowest rung gave every mode: the mode that
/// holds it at the end holds its narrowest proved rung, and every other
/// mode's narrowest proved bound is at most its own bound, which is at
/// most the overall one. (Without monotonicity the bounds stay proved, but
/// a mode whose widest rung fails and a narrower one would pass is left to
/// the dense fallback and the continued ladder (`prove_remaining_modes`).)
///
/// # Panics
/// If `ritz` and `modes` differ in length (a programming error).
///
/// ```
/// use fluid::analysis::{tighten_overall_bound, ModeResult, Progress};
/// use fluid::lanczos::Ritz;
/// let ritz = Ritz { value: 1.0, residual: 0.0, iterations: 1, scale: 1.0 };
/// // the widest rung (margin 8.1e-3, plus 1e-3 of it for |T| = 1)
/// let wide = |s: f64| s * (1.0 + 8.1e-3) + 8.1e-3 * 1e-3;
/// let mode = |m: usize, s: f64| ModeResult {
///     m, k: m as f64, sigma2: s, sigma2_upper: Some(wide(s)), form_verified: true, iterations: 1,
/// };
/// let mut modes = vec![mode(1, 1.0), mode(2, 0.5)];
/// // a check that proves every bound at least 1e-7 above Sigma^2_k
/// let prove = |i: usize, bar: f64| bar >= [1.0, 0.5][i] + 1e-7;
/// tighten_overall_bound(&mut modes, &[ritz, ritz], 0, &Progress::new(), prove);
/// // mode 1 set the overall bound: narrowed to the first rung proved,
/// // 3e-7 (1e-8 is below 1e-7); mode 2, far below, keeps its wide bound
/// let narrowed = modes[0].sigma2_upper.unwrap();
/// assert!((narrowed - (1.0 + 3e-7 + 3e-10)).abs() < 1e-15);
/// assert!((modes[1].sigma2_upper.unwrap() - wide(0.5)).abs() < 1e-15);
/// ```
pub fn tighten_overall_bound(
    modes: &mut [ModeResult],
    ritz: &[crate::lanczos::Ritz],
    narrowest: usize,
    progress: &Progress,
    prove: impl Fn(usize, f64) -> bool,
) {
    assert_eq!(ritz.len(), modes.len(), "one Ritz record per mode");
    let mut narrowed = vec![false; modes.len()];
    loop {
        if progress.is_cancelled() {
            return;
        }
        let Some((j, _)) = modes
            .iter()
            .enumerate()
            .filter_map(|(i, r)| r.sigma2_upper.map(|u| (i, u)))
            .max_by(|a, b| a.1.total_cmp(&b.1))
        else {
            return;
        };
        if narrowed[j] {
            return;
        }
        narrowed[j] = true;
        let Some(held) = held_rung(&modes[j], &ritz[j]) else { return };
        for rung in narrowest..held {
            if progress.is_cancelled() {
                return;
            }
            let bar = ladder_bar(modes[j].sigma2, &ritz[j], rung);
            if prove(j, bar) {
                modes[j].sigma2_upper = Some(bar);
                break;
            }
        }
    }
}

/// The modes whose own ladder ([`verified_upper`]) proved no bound, tried
/// again with wider bounds: the ladder continued (`Sigma^2_k (1 + m)`, the
/// margin `m` growing by [`VERIFY_MARGIN_GROWTH`] past the widest rung,
/// `0.243` then `7.29`) while the bound stays below the overall one, then
/// the overall bound itself (the largest bound the other modes proved).
/// `prove(k, bar)` is the verified check of `bar V - Q ≻ 0` for the mode
/// of wavenumber `k`.
///
/// The certificate's claim is about `Sigma^2 = max_k Sigma^2_k`, so a mode
/// needs only a proved bound no larger than the overall one, not a sharp
/// one; the continued ladder gives it its own bound where it can, a few
/// times `Sigma^2_k` rather than the overall bound's tens or hundreds. On
/// walls grids above the dense fallback's size the banded check cannot
/// prove narrow margins for some modes of `s = -1` forms (the unpivoted
/// factorisation's growth; `walls_check` docs), and the ladder's widest
/// rung, `8.1e-3`, is not enough there: measured for
/// `fluid-channel-sin-walls` at ny = 4096 (`examples/walls_margins.rs` of
/// `verify`), modes 16 to 19 prove `2 Sigma^2_k` and 20 to 32 prove nothing
/// up to twice their `Sigma^2_k` but prove ten times it, while the overall
/// bound is 35 to 124 times it. A mode whose checks all fail keeps `None`
/// and the level stays `float`. Nothing is tried when no mode has a bound,
/// and a mode whose `sigma2` is not below the overall bound is left alone
/// (it would have to set that bound itself).
/// How many rungs [`prove_remaining_modes`] continues the ladder by.
const CONTINUED_RUNGS: usize = 2;

pub(super) fn prove_remaining_modes(
    modes: &mut [ModeResult],
    progress: &Progress,
    prove: impl Fn(f64, f64) -> bool + Sync,
) {
    let Some(overall) = modes.iter().filter_map(|r| r.sigma2_upper).reduce(f64::max) else { return };
    modes.par_iter_mut().filter(|r| r.sigma2_upper.is_none() && r.form_verified && r.sigma2 < overall).for_each(|r| {
        // no progress steps (the phase's count was fixed before): a
        // cancelled run only stops trying
        let mut margin = ladder_margin(VERIFY_ATTEMPTS);
        for _ in 0..CONTINUED_RUNGS {
            let bar = r.sigma2 * (1.0 + margin);
            if progress.is_cancelled() {
                return;
            }
            // (a bound not above Sigma^2_k, or at the overall one, is left
            // to the overall bound's try)
            if !(bar > r.sigma2 && bar < overall) {
                break;
            }
            if prove(r.k, bar) {
                r.sigma2_upper = Some(bar);
                return;
            }
            margin *= VERIFY_MARGIN_GROWTH;
        }
        if !progress.is_cancelled() && prove(r.k, overall) {
            r.sigma2_upper = Some(overall);
        }
    });
}

/// Up to this many unknowns (ny = 512: 511 unknowns on walls, 512 on a
/// periodic grid) the banded check proves the narrowest rung, `1e-8`:
/// measured with `walls_margins` for `U = y^3 + y/2` (`s = +1`) and
/// `channel-sin-walls` (`s = -1`), the low modes at ny = 128, 256 and 512
/// prove every rung; at ny = 1024 none of the 32 modes of either proves
/// `1e-8`. For `kolmogorov-periodic` (`s = -1`) mode 1 proves `1e-8` at
/// ny = 512 and none does at 1024.
pub const BANDED_NARROWEST_UNKNOWNS: usize = 512;

/// The first rung of the margin ladder that [`tighten_overall_bound`]
/// climbs with the banded check, on a grid with `unknowns` unknowns, for
/// the modes that set the overall bound (every mode first proves the
/// widest rung): the margin it can prove grows like `h^-2` (`walls_check`
/// docs), so rungs that cannot succeed are skipped. The bottom up to
/// [`BANDED_NARROWEST_UNKNOWNS`], `3e-7` up to 2048 unknowns, then one rung
/// higher per doubling (the thresholds are those of ny, so that walls,
/// `ny - 1` unknowns, and periodic grids, `ny`, start alike). Measured for `U = y^3 + y/2`
/// (`s = +1`) and the `channel-sin-walls` fixture (`s = -1`), 32 modes
/// each, with `walls_margins`: at ny = 1024, 13 and 6 of the 32 modes prove
/// `3e-7` and none `1e-8`; at ny = 2048, 10 and 5 prove `3e-7`; at
/// ny = 4096, 0 and 1 (the ladder starts at `9e-6` there). For
/// `kolmogorov-periodic` (`s = -1`) modes 1 to 3 of 16 prove `3e-7` at
/// ny = 1024, 2048 and 4096. The claim is the same kind either way (a
/// verified bound, or none); only its width can differ, and the widest rung
/// tried does not change.
pub fn first_rung(unknowns: usize) -> usize {
    if unknowns <= BANDED_NARROWEST_UNKNOWNS {
        return 0;
    }
    let mut rung = 1;
    let mut size = 4 * BANDED_NARROWEST_UNKNOWNS; // 2048
    while unknowns > size && rung + 1 < VERIFY_ATTEMPTS {
        rung += 1;
        size *= 2;
    }
    rung.min(VERIFY_ATTEMPTS - 1)
}

/// The verified bound of one mode as the analysis first finds it:
/// `verified_upper` with the check for its grid. The banded check
/// ([`crate::walls_check`], `O(ny)`, about the exact pencil of the stored
/// operators) tries the widest rung of the ladder, one check (the modes
/// that set the overall bound are narrowed afterwards by
/// [`tighten_overall_bound`], from [`first_rung`]); only a mode it does
/// not prove, on a walls grid of at most [`crate::modes::DENSE_FALLBACK_UNKNOWNS`]
/// unknowns ([`Mode::dense_fallback`]), climbs the ladder with the dense
/// check from the bottom. Periodic grids take the banded path without the
/// fallback ([`Mode::verify`]).
/// Returns `(sigma2_upper, form_verified)`.
///
/// The dense check is not tried for each rung the banded check fails: it
/// would prove `1e-8` there, a narrower bound, but at about 150 ms a mode
/// at ny = 1024 against 5 ms for a banded rung, and with a weaker claim
/// (about `K` as computed, docs/fluids.md §5b). Most modes at ny = 1024
/// prove `3e-7` or `9e-6` with the banded check alone.
pub fn verified_mode_bound(
    mode: &Mode,
    form: &Form,
    coef: &Coefficients,
    sigma2: f64,
    ritz: &crate::lanczos::Ritz,
) -> (Option<f64>, bool) {
    // many noise fields on a coarse walls grid: the dense check alone,
    // from the narrowest rung (`crate::modes::dense_check_preferred`)
    let dense_only = mode.prefers_dense(coef);
    let first = if dense_only { 0 } else { VERIFY_ATTEMPTS - 1 };
    let banded = verified_upper(sigma2, ritz, first, |bar| mode.ladder_check(form, coef, bar));
    if banded.0.is_some() || dense_only || !mode.dense_fallback() {
        return banded;
    }
    let dense = verified_upper(sigma2, ritz, 0, |bar| mode.verify_dense(form, coef, bar));
    (dense.0, banded.1 || dense.1)
}

/// A stated bound in the units of the normalised noise (divided by `4^e`),
/// rounded down if it underflows: proving a smaller bound proves the larger
/// one (`V ≻ 0`).
pub(super) fn normalised_bound(bound: f64, e: i32) -> f64 {
    numerics::scaling::Rescaling::new(e).square_down(bound)
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
    analyse_with(problem, settings, &Progress::new())
}

/// [`analyse`], counting x-mode computations in `progress` and stopping
/// with [`FluidError::Cancelled`] soon after [`Progress::cancel`] (each
/// mode's solve checks it before it starts).
///
/// ```
/// use fluid::analysis::{analyse_with, FluidError, FluidModel, FluidProblem, Progress, Verdict};
/// use fluid::{expr::parse, grid::Boundary, profile::Profile};
/// let p = |s: &str| parse(s, &Default::default()).unwrap();
/// let profile = Profile::new(p("sin(y)"), vec![p("0.3*cos(y)")], (0.0, std::f64::consts::PI), Boundary::Walls);
/// let problem = FluidProblem { model: FluidModel::Incompressible, profile, x_period: 6.283185307179586, ny: 32, x_modes: 2 };
/// let progress = Progress::new();
/// let a = analyse_with(&problem, &Default::default(), &progress).unwrap();
/// assert_eq!(a.verdict, Verdict::Stable);
/// let (done, total) = progress.snapshot();
/// assert!(done > 0 && done == total);
/// let stopped = Progress::new();
/// stopped.cancel();
/// assert!(matches!(analyse_with(&problem, &Default::default(), &stopped), Err(FluidError::Cancelled(_))));
/// ```
pub fn analyse_with(
    problem: &FluidProblem,
    settings: &FluidSettings,
    progress: &Progress,
) -> Result<FluidAnalysis, FluidError> {
    progress.plan(planned_steps(problem, settings));
    let threads = check_threads(problem);
    let limited = (threads < rayon::current_num_threads())
        .then(|| rayon::ThreadPoolBuilder::new().num_threads(threads).build().ok())
        .flatten();
    let a = match limited {
        Some(pool) => pool.install(|| analyse_steps(problem, settings, progress))?,
        None => analyse_steps(problem, settings, progress)?,
    };
    // A cancelled run ends early with meaningless values: never a result.
    progress.check()?;
    progress.settle();
    Ok(a)
}

/// Memory the banded checks of the modes running at once may hold, in
/// bytes: 4 GiB.
pub const CHECK_MEMORY_BUDGET: f64 = 4_294_967_296.0;

/// How many modes [`analyse_with`] runs at once: as many as rayon has
/// threads, unless their banded checks would hold more than
/// [`CHECK_MEMORY_BUDGET`] together (a check holds about six copies of its
/// matrix, [`crate::walls_check::lifted_size`], for every noise field
/// given). With two or three noise fields this never binds (4.7 MB a copy
/// at `ny = 4096`); with 28 at `ny = 4096` (265 MB a copy, the most the
/// spec layer accepts) it allows two, so a machine with many cores runs
/// such a spec in about 3 GiB instead of 1.6 GB a core. Where the dense
/// check runs instead (`crate::modes::dense_check_preferred`) nothing
/// binds. The compressible model runs the incompressible analysis first,
/// so it counts the same.
pub fn check_threads(problem: &FluidProblem) -> usize {
    let boundary = problem.profile.boundary;
    let (n, fields) = (crate::grid::unknowns(boundary, problem.ny), problem.profile.eta.len());
    if crate::modes::dense_check_preferred(boundary, n, fields) {
        // no banded check runs (the dense one holds a few n x n matrices)
        return CHECK_THREADS_MAX;
    }
    let (rows, width) = crate::walls_check::lifted_size(n, crate::grid::stiffness_bandwidth(boundary), fields);
    let per_mode = 6.0 * 8.0 * rows as f64 * (width + 1) as f64;
    (CHECK_MEMORY_BUDGET / per_mode).floor().clamp(1.0, CHECK_THREADS_MAX as f64) as usize
}

/// [`check_threads`] when nothing binds.
const CHECK_THREADS_MAX: usize = 4096;

/// The steps [`analyse_with`] plans: one per x-mode solve (the paper's
/// choice, the eight shifts, the finest grid, two per row of the
/// convergence table and the drift residual; when the paper's functional
/// is the chosen one its solves are not run, and the bar settles at the
/// end), and for the compressible
/// model the incompressible analysis plus the shift scan (nine points and
/// twelve golden-section steps), the finest grid, the discrete SDE and
/// one per row.
fn planned_steps(problem: &FluidProblem, settings: &FluidSettings) -> u64 {
    let modes = problem.x_modes as u64;
    let rows = table_resolutions(problem.ny, settings.convergence_from).len() as u64;
    let incompressible = modes * (1 + 8 + 1 + 2 * rows + 1);
    match problem.model {
        FluidModel::Incompressible => incompressible,
        FluidModel::Compressible { .. } => incompressible + modes * (9 + 12 + 2 + rows),
    }
}

/// The pipeline without planning or settling the progress (the
/// compressible analysis runs the incompressible one inside its own plan).
fn analyse_steps(
    problem: &FluidProblem,
    settings: &FluidSettings,
    progress: &Progress,
) -> Result<FluidAnalysis, FluidError> {
    let profile = &problem.profile;
    let fine = YGrid::new(profile.boundary, profile.interval.0, profile.interval.1, problem.ny);
    profile.check(fine.nodes())?;
    let (scaled, e) = normalise_noise(problem, &fine);
    let a = analyse_normalised(&scaled, settings, &fine, progress);
    Ok(if e == 0 { a } else { rescale(a, e) })
}

/// Runs `work` unless the analysis was cancelled (then `None`), and counts
/// one step: the per-mode solves' cancellation point.
fn mode_step<T>(progress: &Progress, work: impl FnOnce() -> Option<T>) -> Option<T> {
    if progress.is_cancelled() {
        return None;
    }
    let out = work();
    progress.step(1);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constants::VERIFY_MARGIN_START;

    fn mode(m: usize, sigma2: f64, upper: Option<f64>, form_verified: bool) -> ModeResult {
        ModeResult { m, k: m as f64, sigma2, sigma2_upper: upper, form_verified, iterations: 1 }
    }

    #[test]
    fn the_modes_at_once_keep_their_checks_within_the_budget() {
        // check_threads = floor(4 GiB / (6 * 8 * rows * (bandwidth + 1))),
        // rows and bandwidth from walls_check::lifted_size (walls: p = 8).
        // J = 2 at ny = 4096: 4095 * 4 rows, bandwidth 35: 2^32 / (48 *
        // 16380 * 36) = 151.7. J = 28: 4095 * 30 rows, bandwidth 269:
        // 2^32 / (48 * 122850 * 270) = 2.70. J = 64 at ny = 1024: the dense
        // check runs instead (modes::dense_check_preferred), nothing binds.
        let p = |s: &str| crate::expr::parse(s, &Default::default()).unwrap();
        let problem = |ny: usize, fields: usize| FluidProblem {
            model: FluidModel::Incompressible,
            profile: Profile::new(
                p("y^3"),
                (1..=fields).map(|j| p(&format!("sin({j}*y)"))).collect(),
                (-1.0, 1.0),
                Boundary::Walls,
            ),
            x_period: 6.0,
            ny,
            x_modes: 4,
        };
        assert_eq!(check_threads(&problem(4096, 2)), 151);
        assert_eq!(check_threads(&problem(4096, 28)), 2);
        assert_eq!(check_threads(&problem(1024, 64)), CHECK_THREADS_MAX);
    }

    #[test]
    fn the_ladder_skips_the_rungs_the_banded_check_never_proves_on_large_grids() {
        // first_rung's rule: the bottom up to 512 unknowns, `3e-7` (rung 1)
        // up to 2048, then one rung per doubling (4096, 8192), never past
        // the widest rung (4). Walls grids have ny - 1 unknowns, periodic
        // ones ny: both start alike.
        let cases = [
            (1, 0),
            (511, 0),
            (512, 0),
            (513, 1),
            (1023, 1),
            (1024, 1),
            (2047, 1),
            (2048, 1),
            (2049, 2),
            (4095, 2),
            (4096, 2),
            (4097, 3),
            (8192, 3),
            (8193, 4),
        ];
        for (unknowns, rung) in cases {
            assert_eq!(first_rung(unknowns), rung, "{unknowns} unknowns");
        }
        assert_eq!(first_rung(usize::MAX), VERIFY_ATTEMPTS - 1);
    }

    #[test]
    fn a_mode_the_banded_check_cannot_prove_falls_back_to_the_dense_check_up_to_1023_unknowns() {
        // The banded lifting is written for the energy coefficient 1 and
        // proves nothing for another (walls_check docs); the dense check
        // takes any. A form with energy 2 therefore reaches the dense branch
        // of verified_mode_bound on walls grids, which proves the bottom
        // rung (its own ladder starts there) on 255 unknowns; above
        // DENSE_FALLBACK_UNKNOWNS (ny = 1032: 1031) and on periodic grids
        // (no fallback, Mode::verify docs) nothing is proved.
        use crate::grid::{Boundary, YGrid};
        use crate::modes::{Coefficients, Form, Mode};
        use outcome::Sign;
        for (boundary, ny, fallback) in
            [(Boundary::Walls, 256, true), (Boundary::Periodic, 256, false), (Boundary::Walls, 1032, false)]
        {
            let g = YGrid::new(boundary, 0.0, std::f64::consts::PI, ny);
            let y = g.nodes();
            let coef = Coefficients {
                u: y.iter().map(|y| 0.5 * y * y).collect(),
                upp: vec![1.0; g.n()],
                eta: vec![y.iter().map(|y| 0.3 * y.sin()).collect()],
            };
            let form = Form { energy: 2.0, w: coef.u.iter().map(|u| u + 2.0).collect(), sign: Sign::Positive };
            let k = 1.5;
            let mode = Mode::new(&g, k);
            let r = mode.sigma2(&form, &coef, 1e-12).unwrap();
            assert!(r.lambda_max > 0.0);
            // the banded check alone proves nothing, even at twice the value
            let banded = crate::walls_check::verify_walls(&g, k, &form, &coef, 2.0 * r.lambda_max);
            assert_eq!(banded, (false, false), "{boundary:?} {ny}");
            let (bound, definite) = verified_mode_bound(&mode, &form, &coef, r.lambda_max, &r.ritz);
            if fallback {
                let bottom = r.lambda_max * (1.0 + VERIFY_MARGIN_START)
                    + VERIFY_MARGIN_START * VERIFY_RITZ_WEIGHT * r.ritz.scale
                    + r.ritz.residual;
                assert_eq!((bound, definite), (Some(bottom), true), "{boundary:?} {ny}");
            } else {
                assert_eq!(bound, None, "{boundary:?} {ny}");
            }
        }
    }

    #[test]
    fn the_overall_bound_is_narrowed_where_it_is_set_and_nowhere_else() {
        use crate::lanczos::Ritz;
        let ritz = |scale: f64| Ritz { value: 0.0, residual: 1e-12, iterations: 1, scale };
        let rz = [ritz(1.0), ritz(2.0), ritz(1.0), ritz(1.0), ritz(1.0)];
        let sigma2 = [1.0, 0.9999, 0.5, 0.99995, 0.1];
        let wide = VERIFY_ATTEMPTS - 1;
        let at = |i: usize, rung: usize| ladder_bar(sigma2[i], &rz[i], rung);
        let new = || -> Vec<ModeResult> { (0..5).map(|i| mode(i + 1, sigma2[i], Some(at(i, wide)), true)).collect() };
        // the rungs each mode's check proves: 2 and up, 1 and up, all, 3
        // and up, all (a monotone check)
        let lowest = [2, 1, 0, 3, 0];
        let tried = std::sync::Mutex::new(vec![]);
        let prove = |i: usize, bar: f64| {
            tried.lock().unwrap().push((i, bar));
            (0..VERIFY_ATTEMPTS).any(|r| r >= lowest[i] && at(i, r) == bar)
        };
        let mut modes = new();
        tighten_overall_bound(&mut modes, &rz, 1, &Progress::new(), prove);
        // Mode 0 holds the overall bound: rung 1 fails, rung 2 holds. Mode
        // 3's wide bound is now the largest: rungs 1 and 2 fail, 3 holds.
        // Then mode 1's (its |T| is larger): rung 1 holds. Mode 3 holds the
        // largest bound again, already narrowed: the narrowing stops.
        // Modes 2 and 4, far below, keep their wide bounds.
        let expected = vec![(0, at(0, 1)), (0, at(0, 2)), (3, at(3, 1)), (3, at(3, 2)), (3, at(3, 3)), (1, at(1, 1))];
        assert_eq!(*tried.lock().unwrap(), expected);
        let uppers: Vec<f64> = modes.iter().map(|r| r.sigma2_upper.unwrap()).collect();
        assert_eq!(uppers, vec![at(0, 2), at(1, 1), at(2, wide), at(3, 3), at(4, wide)]);
        // The overall bound is the one the ladder from rung 1 gives every
        // mode (its first proved rung at or above 1): the max of these.
        let ladder_max = (0..5).map(|i| at(i, lowest[i].max(1))).fold(0.0, f64::max);
        assert_eq!(uppers.iter().copied().fold(0.0, f64::max), ladder_max);
        // a mode holding a bound that is not a rung (the continued ladder's
        // or the overall one) stops the narrowing; so does a cancelled run
        let mut off = new();
        off[0].sigma2_upper = Some(2.0);
        tighten_overall_bound(&mut off, &rz, 0, &Progress::new(), |_, _| panic!("tried"));
        assert_eq!(off[0].sigma2_upper, Some(2.0));
        let p = Progress::new();
        p.cancel();
        let mut cancelled = new();
        tighten_overall_bound(&mut cancelled, &rz, 0, &p, |_, _| panic!("tried"));
        assert_eq!(cancelled, new());
        // no bound at all: nothing to narrow
        let mut none = vec![mode(1, 1.0, None, true)];
        tighten_overall_bound(&mut none, &rz[..1], 0, &Progress::new(), |_, _| panic!("tried"));
    }

    /// The pipeline's overall bound against the one the ladder from
    /// `first_rung` gives every mode with the banded check (computed here
    /// mode by mode, independently of `tighten_overall_bound`): equal, on
    /// walls (`s = -1`, where modes prove rungs from `3e-7` to `2.7e-4` at
    /// ny = 1024) and periodic grids, while most modes' own bounds are
    /// wider.
    #[test]
    fn the_narrowed_overall_bound_is_the_one_the_full_ladder_gives() {
        use crate::grid::Boundary;
        use crate::profile::Profile;
        let p = |s: &str| crate::expr::parse(s, &Default::default()).unwrap();
        let pi = std::f64::consts::PI;
        for (boundary, interval, x_period, noise) in [
            (Boundary::Walls, (0.0, pi), 2.0 * pi, vec!["0.3*cos(y)", "0.2*sin(2*y)"]),
            (Boundary::Periodic, (0.0, 2.0 * pi), pi, vec!["0.3*cos(y)"]),
        ] {
            let problem = FluidProblem {
                model: FluidModel::Incompressible,
                profile: Profile::new(p("sin(y)"), noise.iter().map(|s| p(s)).collect(), interval, boundary),
                x_period,
                ny: 1024,
                x_modes: 12,
            };
            let settings = FluidSettings { convergence_from: 1024, ..Default::default() };
            let a = analyse(&problem, &settings).unwrap();
            assert_eq!(a.verdict, Verdict::Stable, "{boundary:?}: {}", a.reason);
            let (grid, coef, form) = chosen_form(&problem).unwrap();
            let ladder: Vec<Option<f64>> = a
                .modes
                .iter()
                .map(|r| {
                    let mode = Mode::new(&grid, r.k);
                    let s = mode.sigma2(&form, &coef, settings.lanczos_tolerance).unwrap();
                    assert_eq!(s.lambda_max.max(0.0), r.sigma2);
                    verified_upper(r.sigma2, &s.ritz, first_rung(grid.n()), |bar| {
                        crate::walls_check::verify_walls(&grid, r.k, &form, &coef, bar)
                    })
                    .0
                })
                .collect();
            let full = ladder.iter().map(|u| u.unwrap()).fold(0.0, f64::max);
            assert_eq!(a.sigma2_upper, Some(full), "{boundary:?}");
            let wider = a.modes.iter().zip(&ladder).filter(|(r, l)| r.sigma2_upper > **l).count();
            assert!(wider >= a.modes.len() / 2, "{boundary:?}: {wider} wider");
            for (r, l) in a.modes.iter().zip(&ladder) {
                assert!(r.sigma2_upper >= *l && r.sigma2_upper <= a.sigma2_upper, "{boundary:?} mode {}", r.m);
            }
        }
    }

    #[test]
    fn a_mode_without_a_bound_is_tried_on_the_continued_ladder_then_at_the_overall_bound() {
        let mut modes = vec![
            mode(1, 1.0, Some(1.01), true),
            mode(2, 0.5, Some(0.6), true),
            mode(3, 0.1, None, true),  // proved on the second continued rung
            mode(4, 0.1, None, true),  // its check fails everywhere
            mode(5, 0.1, None, false), // V not definite: never tried
            mode(6, 1.02, None, true), // above the overall bound: never tried
            mode(7, 0.9, None, true),  // its first continued rung is above 1.01
            mode(8, 0.0, None, true),  // Sigma^2_k = 0: no rung above it
        ];
        let tried = std::sync::Mutex::new(vec![]);
        // the check proves bounds from 0.5 up, except for mode 4
        prove_remaining_modes(&mut modes, &Progress::new(), |k, bar| {
            tried.lock().unwrap().push((k as usize, bar));
            k != 4.0 && bar >= 0.5
        });
        let mut tried = tried.into_inner().unwrap();
        // stable: each mode's tries stay in order
        tried.sort_by_key(|t| t.0);
        // the continued margins: past the widest rung 8.1e-3, 0.243 and 7.29
        let m5 = VERIFY_MARGIN_START * VERIFY_MARGIN_GROWTH.powi(VERIFY_ATTEMPTS as i32);
        let m6 = m5 * VERIFY_MARGIN_GROWTH;
        assert!((m5 - 0.243).abs() < 1e-12 && (m6 - 7.29).abs() < 1e-12);
        let (r1, r2) = (0.1 * (1.0 + m5), 0.1 * (1.0 + m6));
        assert_eq!(tried, vec![(3, r1), (3, r2), (4, r1), (4, r2), (4, 1.01), (7, 1.01), (8, 1.01)]);
        let uppers: Vec<Option<f64>> = modes.iter().map(|r| r.sigma2_upper).collect();
        assert_eq!(uppers, vec![Some(1.01), Some(0.6), Some(r2), None, None, None, Some(1.01), Some(1.01)]);
        // no mode with a bound: nothing is tried
        let mut none = vec![mode(1, 1.0, None, true)];
        prove_remaining_modes(&mut none, &Progress::new(), |_, _| panic!("tried"));
        assert_eq!(none[0].sigma2_upper, None);
        // a cancelled run stops trying
        let p = Progress::new();
        p.cancel();
        let mut left = vec![mode(1, 1.0, Some(1.0), true), mode(2, 0.1, None, true)];
        prove_remaining_modes(&mut left, &p, |_, _| true);
        assert_eq!(left[1].sigma2_upper, None);
    }
}
