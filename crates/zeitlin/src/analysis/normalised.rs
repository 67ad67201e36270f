//! The analysis of a problem scaled to unit size ([`super::analyse_with`]
//! scales it there and back), in steps: the blocks, the search for a
//! definite energy–Casimir–momentum form over the momentum coefficient,
//! `Sigma^2` per block at the choice and its proved bound, and, without a
//! definite form, the search for a growing mode.

use super::block::Block;
use super::{
    hbar, unstable_reason, BlockResult, Choice, ZeitlinAnalysis, ZeitlinError, ZeitlinProblem, ZeitlinSettings,
};
use crate::laplacian::solve_zonal;
use numerics::minimise::{golden_section_until, golden_section_with_ends};
use outcome::{Progress, Verdict, VerificationLevel};
use rayon::prelude::*;
use std::cell::RefCell;

/// The passes over the blocks planned for the energy search of each sign
/// (measured: 126 to 138 for the sign that succeeds, 66 to 76 for the
/// other, at N = 64 to 1024).
const SEARCH_PASSES: u64 = 140;

/// The search's bound on `|b|`, `b = beta / beta_unit`.
const RANGE: f64 = 1e4;

/// The verdict, the choice and `Sigma^2` of a problem at unit scale.
///
/// Progress is counted in block operations (a definiteness test, a
/// `lambda_min`, a bisection for `lambda_max`...), planned per phase at
/// its worst case. Once cancelled, every block operation returns at once
/// with a value that ends the search (not definite, `-inf` margin,
/// infinite `lambda_max`), and [`super::analyse_with`] turns the result into
/// [`ZeitlinError::Cancelled`].
pub(super) fn analyse_normalised(
    problem: &ZeitlinProblem,
    settings: &ZeitlinSettings,
    progress: &Progress,
) -> Result<ZeitlinAnalysis, ZeitlinError> {
    let n = problem.n;
    // Progress counts definiteness tests and inertias of one block (each
    // O(N)). The plan, in passes over the blocks: build them, G's
    // diagonal, the Casimir–momentum tests, the energy search for each sign
    // (SEARCH_PASSES each), then lambda_max everywhere, the drift residual
    // and the proof (19 to 21).
    let per_pass = (n - 1) as u64;
    progress.plan((1 + 1 + 2 + 2 * SEARCH_PASSES + 20) * per_pass);
    let hbar = hbar(n);
    let (blocks, scale_omega) = build_blocks(problem, progress)?;
    let mut analysis = inconclusive(hbar);
    if scale_omega == 0.0 {
        analysis.reason =
            "W_e = 0: every state nearby is an equilibrium of the linearisation only; nothing to certify".into();
        return Ok(analysis);
    }
    let family = Family::new(&blocks, settings.tolerance, progress);
    let estimates = Estimates::new(&family);
    let mut candidates = casimir_momentum_candidates(&family, settings, per_pass);
    let searched = candidates.is_empty() && n <= settings.energy_search_max_n;
    if searched {
        for eps in [1.0, -1.0] {
            let _phase = progress.phase(SEARCH_PASSES * per_pass);
            candidates.extend(energy_search(&estimates, eps, settings.golden_steps));
        }
    }
    match candidates.into_iter().min_by(|x, y| x.sigma2.total_cmp(&y.sigma2)) {
        Some(best) => Ok(with_definite_form(analysis, &estimates, &best)),
        None => Ok(without_definite_form(analysis, &blocks, settings, searched, hbar, progress)),
    }
}

/// The blocks `m = 1..N-1` (one step each) from `omega`, its stream
/// function `pi` (`Delta_0 pi = omega`) and the noise, and `max |omega|`.
fn build_blocks(problem: &ZeitlinProblem, progress: &Progress) -> Result<(Vec<Block>, f64), ZeitlinError> {
    let omega = &problem.omega;
    let pi = solve_zonal(omega).ok_or_else(|| ZeitlinError::Numerical("the zonal Poisson solve failed".into()))?;
    let scale_omega = omega.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    let blocks = (1..problem.n)
        .map(|m| {
            progress.check()?;
            progress.step(1);
            Block::new(problem, &pi, scale_omega, m)
        })
        .collect::<Result<_, ZeitlinError>>()?;
    Ok((blocks, scale_omega))
}

/// The result before anything is found: inconclusive, numerical, empty.
fn inconclusive(hbar: f64) -> ZeitlinAnalysis {
    ZeitlinAnalysis {
        verdict: Verdict::Inconclusive,
        level: VerificationLevel::Numerical,
        reason: String::new(),
        equilibrium_residual: 0.0,
        noise_residual: 0.0,
        choice: None,
        sigma2: None,
        sigma2_upper: None,
        attained: false,
        blocks: vec![],
        drift_residual: 0.0,
        growth_rate: None,
        hbar,
    }
}

/// A definite member of the family: `(eps, b)`, its `Sigma^2` estimate and
/// whether the minimum over `b` is attained there.
struct Candidate {
    energy: f64,
    b: f64,
    sigma2: f64,
    attained: bool,
}

/// The energy–Casimir–momentum family over the blocks. `P` is defined up
/// to a positive factor: the energy coefficient is normalised to eps = +1
/// (Arnold's first theorem), -1 (his second) or 0 (the Casimir–momentum
/// form alone), and b = beta / beta_unit is free.
struct Family<'a> {
    blocks: &'a [Block],
    /// The momentum coefficient's unit, so that (eps, beta) are comparable.
    beta_unit: f64,
    /// `(d pi_j, m beta_unit)` at each pair of equal eigenvalues, which
    /// forces `eps d pi_j + beta m = 0`.
    constraints: Vec<(f64, f64)>,
    /// `diag G` of each block.
    g_diagonals: Vec<Vec<f64>>,
    /// The relative width of each `lambda_max` bracket.
    tol: f64,
    progress: &'a Progress,
}

impl<'a> Family<'a> {
    /// `beta_unit = max_j |d pi_j| / m`, the constraints of equal
    /// eigenvalues, and `diag G` per block (one step each).
    fn new(blocks: &'a [Block], tol: f64, progress: &'a Progress) -> Family<'a> {
        let beta_unit = blocks
            .iter()
            .flat_map(|b| b.d_pi.iter().map(move |x| x.abs() / b.m as f64))
            .fold(0.0f64, f64::max)
            .max(f64::MIN_POSITIVE);
        let constraints: Vec<(f64, f64)> = blocks
            .iter()
            .flat_map(|blk| {
                (0..blk.len()).filter(|&j| blk.degenerate[j]).map(move |j| (blk.d_pi[j], blk.m as f64 * beta_unit))
            })
            .collect();
        // For the necessary condition of `diagonal_interval`.
        let g_diagonals: Vec<Vec<f64>> = blocks
            .par_iter()
            .map(|blk| {
                progress.step(1);
                blk.g_diagonal()
            })
            .collect();
        Family { blocks, beta_unit, constraints, g_diagonals, tol, progress }
    }

    /// `max(|eps| / 2, max_j |c_j(eps, b)|)` over the entries with distinct
    /// eigenvalues: the size of `P`'s Casimir–momentum part.
    fn c_scale(&self, eps: f64, b: f64) -> f64 {
        let beta_unit = self.beta_unit;
        self.blocks
            .iter()
            .flat_map(|blk| (0..blk.len()).filter(|&j| !blk.degenerate[j]).map(move |j| (blk, j)))
            .map(|(blk, j)| ((eps * blk.d_pi[j] + b * beta_unit * blk.m as f64) / blk.d_omega[j]).abs())
            .fold(eps.abs() / 2.0, f64::max)
    }

    /// The functional at `(eps, b)`, with the free curvature `1e3` times
    /// [`Family::c_scale`]. Formed once per point (`c_scale` is a pass
    /// over every block), not per block.
    fn choice_at(&self, eps: f64, b: f64) -> Choice {
        Choice {
            energy: eps,
            momentum: b * self.beta_unit,
            free_curvature: 1e3 * self.c_scale(eps, b).max(f64::MIN_POSITIVE),
        }
    }

    /// Whether `eps d pi_j + beta m = 0` (to 1e-9 relative) at every pair
    /// of equal eigenvalues.
    fn allowed(&self, eps: f64, b: f64) -> bool {
        self.constraints
            .iter()
            .all(|(dp, mu)| (eps * dp + b * mu).abs() <= 1e-9 * (eps.abs() * dp.abs() + b.abs() * mu))
    }

    /// One step of progress, and whether the analysis was cancelled. Once
    /// cancelled: nothing is definite, margins are -inf and lambda_max is
    /// infinite, which ends every loop of the search at once.
    fn stop(&self) -> bool {
        self.progress.step(1);
        self.progress.is_cancelled()
    }

    /// Whether `P(eps, b) ≻ 0` is proved in every block (and allowed).
    fn definite(&self, eps: f64, b: f64) -> bool {
        self.allowed(eps, b) && {
            let choice = self.choice_at(eps, b);
            self.blocks.par_iter().all(|blk| !self.stop() && blk.definite(&choice))
        }
    }

    /// min_m lambda_min(P_m(b)) / scale: concave in b (P is affine in b).
    fn margin(&self, eps: f64, b: f64) -> f64 {
        let choice = self.choice_at(eps, b);
        let tick = || self.progress.step(1);
        self.blocks
            .par_iter()
            .map(|blk| if self.stop() { f64::NEG_INFINITY } else { blk.lambda_min(&choice, &tick) })
            .reduce(|| f64::INFINITY, f64::min)
            / self.c_scale(eps, b).max(eps.abs()).max(f64::MIN_POSITIVE)
    }

    /// `lambda_max(Q_m, P_m)` of one block by bisection from `guess`
    /// (infinite once cancelled).
    fn lambda_max(&self, blk: &Block, choice: &Choice, guess: f64) -> BlockResult {
        if self.stop() {
            return BlockResult { m: blk.m, lambda_max: f64::INFINITY, residual: f64::NAN };
        }
        blk.lambda_max(choice, guess, self.tol, &|| self.progress.step(1))
    }

    /// A necessary condition for P_m(b) ≻ 0, cheap: every diagonal entry
    /// eps G_jj + c_j(b) positive, each linear in b. The interval it leaves
    /// (within [-RANGE, RANGE], widened by 1e-6 against rounding) contains
    /// every definite b; None when it is empty.
    fn diagonal_interval(&self, eps: f64) -> Option<(f64, f64)> {
        let (mut lo, mut hi) = (-RANGE, RANGE);
        for (blk, gd) in self.blocks.iter().zip(&self.g_diagonals) {
            for j in (0..blk.len()).filter(|&j| !blk.degenerate[j]) {
                // alpha + b gamma > 0
                let alpha = eps * gd[j] + eps * blk.d_pi[j] / blk.d_omega[j];
                let gamma = self.beta_unit * blk.m as f64 / blk.d_omega[j];
                let slack = 1e-6 * (alpha.abs() / gamma.abs()).max(1.0);
                if gamma > 0.0 {
                    lo = lo.max(-alpha / gamma - slack);
                } else if gamma < 0.0 {
                    hi = hi.min(-alpha / gamma + slack);
                } else if alpha <= 0.0 {
                    return None;
                }
            }
        }
        (lo < hi).then_some((lo, hi))
    }

    /// The end, towards `outside`, of the definite interval around the
    /// definite `inside`: `outside` itself when definite, else 50
    /// bisection steps.
    fn edge(&self, eps: f64, inside: f64, outside: f64) -> f64 {
        let (mut a, mut c) = (inside, outside);
        if self.definite(eps, c) {
            return c;
        }
        for _ in 0..50 {
            let mid = 0.5 * (a + c);
            if self.definite(eps, mid) {
                a = mid;
            } else {
                c = mid;
            }
        }
        a
    }

    /// The largest relative drift residual `|sym(P A)|` over the blocks.
    fn drift_residual(&self, choice: &Choice) -> f64 {
        self.blocks
            .par_iter()
            .map(|b| {
                self.progress.step(1);
                b.drift_residual(choice)
            })
            .reduce(|| 0.0, f64::max)
    }

    /// A proved bound a little above the bisection estimate: P ≻ 0 is proved
    /// per block (`definite`), then s P - Q ≻ 0 at s = Sigma^2 (1 + r),
    /// r from 1e-10 up by tenfold steps to 1e-2.
    fn proved_sigma2_upper(&self, choice: &Choice, sigma2: f64) -> Option<f64> {
        let base = sigma2.max(f64::MIN_POSITIVE);
        (0..9).map(|i| base * (1.0 + 1e-10 * 10f64.powi(i))).find(|&s| {
            self.blocks.par_iter().all(|blk| !self.stop() && blk.definite(choice) && blk.below(choice, s, true))
        })
    }
}

/// `Sigma^2(eps, b) = max_m lambda_max(Q_m, P_m)` along the search,
/// keeping the last lambda_max of each block as bisection guesses: the
/// search moves b a little at a time.
struct Estimates<'a> {
    family: &'a Family<'a>,
    last: RefCell<Vec<f64>>,
}

impl<'a> Estimates<'a> {
    /// No guesses yet.
    fn new(family: &'a Family<'a>) -> Estimates<'a> {
        Estimates { family, last: RefCell::new(vec![f64::NAN; family.blocks.len()]) }
    }

    /// `lambda_max(Q_m, P_m)` of every block at `(eps, b)`.
    fn every_block(&self, eps: f64, b: f64) -> Vec<BlockResult> {
        let family = self.family;
        let choice = family.choice_at(eps, b);
        let guesses = self.last.borrow().clone();
        let results: Vec<BlockResult> =
            family.blocks.par_iter().zip(&guesses).map(|(blk, g)| family.lambda_max(blk, &choice, *g)).collect();
        *self.last.borrow_mut() = results.iter().map(|r| r.lambda_max).collect();
        results
    }

    /// Sigma^2 alone: the block that was largest first, then one sweep that
    /// tests every block against it (one inertia each), bisecting only the
    /// blocks above it; repeated until none is (a few sweeps, not one
    /// bisection per block).
    fn sigma2_at(&self, eps: f64, b: f64) -> f64 {
        if self.last.borrow().iter().any(|x| x.is_nan()) {
            return largest(&self.every_block(eps, b));
        }
        let family = self.family;
        let blocks = family.blocks;
        let choice = family.choice_at(eps, b);
        let top = self.last.borrow().iter().enumerate().max_by(|x, y| x.1.total_cmp(y.1)).map_or(0, |(i, _)| i);
        let mut s = family.lambda_max(&blocks[top], &choice, self.last.borrow()[top]).lambda_max;
        self.last.borrow_mut()[top] = s;
        for _ in 0..blocks.len() {
            if !s.is_finite() {
                return f64::INFINITY;
            }
            let above: Vec<usize> = (0..blocks.len())
                .into_par_iter()
                .filter(|&i| !family.stop() && !blocks[i].below(&choice, s, false))
                .collect();
            if above.is_empty() {
                break;
            }
            let guesses = self.last.borrow().clone();
            let found: Vec<(usize, f64)> = above
                .par_iter()
                .map(|&i| (i, family.lambda_max(&blocks[i], &choice, guesses[i].max(s)).lambda_max))
                .collect();
            for (i, v) in found {
                self.last.borrow_mut()[i] = v;
                s = s.max(v);
            }
        }
        s
    }
}

/// `max(0, max_m lambda_max)` over the blocks' results.
fn largest(results: &[BlockResult]) -> f64 {
    results.iter().map(|r| r.lambda_max).fold(0.0f64, f64::max)
}

/// eps = 0: the Casimir–momentum form alone at `b = ±1` (Q = 0, so
/// Sigma^2 = 0), when the settings allow it and it is definite.
fn casimir_momentum_candidates(family: &Family, settings: &ZeitlinSettings, per_pass: u64) -> Vec<Candidate> {
    let _phase = family.progress.phase(2 * per_pass);
    let mut candidates = vec![];
    for b in [1.0, -1.0] {
        if settings.casimir_momentum && family.definite(0.0, b) {
            candidates.push(Candidate { energy: 0.0, b, sigma2: 0.0, attained: true });
        }
    }
    candidates
}

/// The best definite `b` for the energy sign `eps`: the one a pair of
/// equal eigenvalues forces, or else a definite `b` by maximising the
/// concave margin `min_m lambda_min(P_m(b))`, then [`minimise_sigma2`].
fn energy_search(estimates: &Estimates, eps: f64, golden_steps: usize) -> Option<Candidate> {
    let family = estimates.family;
    if let Some((dp, mu)) = family.constraints.first().copied() {
        // b is forced.
        let b = -eps * dp / mu;
        if family.definite(eps, b) {
            let s = estimates.sigma2_at(eps, b);
            return Some(Candidate { energy: eps, b, sigma2: s, attained: true });
        }
        return None;
    }
    // P's diagonal must be positive: b in an interval, O(N^2) to find.
    let (lo_b, hi_b) = family.diagonal_interval(eps)?;
    // A definite b: golden section on the concave -margin, stopped
    // at the first definite point (64 steps shrink the range 1e-13).
    let (b0, m0) =
        golden_section_until(|b| -family.margin(eps, b), lo_b, hi_b, 64, |b, m| -m > 1e-9 && family.definite(eps, b));
    if -m0 <= 1e-9 || !family.definite(eps, b0) {
        return None;
    }
    minimise_sigma2(estimates, eps, b0, golden_steps)
}

/// `Sigma^2(b)` (quasiconvex) minimised by golden section over the
/// definite interval around the definite `b0`; attained unless the minimum
/// is at an end of the interval (`b0` itself, unattained, when the
/// minimiser's `b` is not definite).
fn minimise_sigma2(estimates: &Estimates, eps: f64, b0: f64, golden_steps: usize) -> Option<Candidate> {
    let family = estimates.family;
    // The definite interval around b0, then Sigma^2 (quasiconvex) on it.
    let (lo, hi) = (family.edge(eps, b0, -RANGE), family.edge(eps, b0, RANGE));
    let (b, s) = golden_section_with_ends(|b| estimates.sigma2_at(eps, b), lo, hi, golden_steps, 1e-6);
    let at_edge = (b - lo).abs() <= 1e-6 * (hi - lo) || (hi - b).abs() <= 1e-6 * (hi - lo);
    if family.definite(eps, b) {
        Some(Candidate { energy: eps, b, sigma2: s, attained: !at_edge })
    } else if family.definite(eps, b0) {
        Some(Candidate { energy: eps, b: b0, sigma2: estimates.sigma2_at(eps, b0), attained: false })
    } else {
        None
    }
}

/// At the best candidate: `Sigma^2 = max_m lambda_max(Q_m, P_m)`, the
/// drift residual, the verdict (stable) and a proved upper bound on
/// `Sigma^2`, which sets the level.
fn with_definite_form(mut analysis: ZeitlinAnalysis, estimates: &Estimates, best: &Candidate) -> ZeitlinAnalysis {
    let family = estimates.family;
    let (eps, b) = (best.energy, best.b);
    let choice = family.choice_at(eps, b);
    let results = estimates.every_block(eps, b);
    let sigma2 = largest(&results);
    if !sigma2.is_finite() {
        analysis.reason =
            "a definite form was found but a block's lambda_max could not be bracketed (not finite)".into();
        return analysis;
    }
    analysis.drift_residual = family.drift_residual(&choice);
    analysis.verdict = Verdict::Stable;
    analysis.reason = stable_reason(&choice);
    analysis.sigma2_upper = if choice.energy == 0.0 { Some(0.0) } else { family.proved_sigma2_upper(&choice, sigma2) };
    if choice.energy == 0.0 {
        analysis.level = VerificationLevel::ExactStructure;
    } else if analysis.sigma2_upper.is_some() {
        analysis.level = VerificationLevel::VerifiedFloat;
    }
    analysis.choice = Some(choice);
    analysis.sigma2 = Some(sigma2.max(0.0));
    analysis.attained = best.attained;
    analysis.blocks = results;
    analysis
}

/// The stable verdict's sentence for the chosen functional.
fn stable_reason(choice: &Choice) -> String {
    if choice.energy == 0.0 {
        "the Casimir–momentum form alone is definite (the profile is strictly monotone): it is conserved along every path, so Sigma^2 = 0".into()
    } else {
        format!(
            "the energy–Casimir–momentum form (energy coefficient {:+.3}) is definite in every block: formally stable; E|dW_t|_P^2 <= |dW_0|_P^2 e^(Sigma^2 t)",
            choice.energy
        )
    }
}

/// Without a definite form: the search's limit when it was not run, else
/// (up to `instability_max_n`) the drift's fastest growth, [`growth_verdict`].
fn without_definite_form(
    mut analysis: ZeitlinAnalysis,
    blocks: &[Block],
    settings: &ZeitlinSettings,
    searched: bool,
    hbar: f64,
    progress: &Progress,
) -> ZeitlinAnalysis {
    let n = blocks.len() + 1;
    if !searched && n > settings.energy_search_max_n {
        analysis.reason = format!(
            "the Casimir–momentum form is not definite{}, and the energy–Casimir–momentum family is searched only up to N = {} (settings.energy_search_max_n; the search costs about 4x per doubling of N, some 40 s at N = 2048)",
            if settings.casimir_momentum { "" } else { " (not allowed by the settings)" },
            settings.energy_search_max_n
        );
        return analysis;
    }
    // No definite conserved form: look for a growing mode.
    if n <= settings.instability_max_n {
        return growth_verdict(analysis, blocks, hbar, progress);
    }
    analysis.reason = format!(
        "no energy–Casimir–momentum form is definite (the drift's spectrum is computed only up to N = {})",
        settings.instability_max_n
    );
    analysis
}

/// `max Re lambda(A)` over the blocks (each block's drift densely, one
/// step each): linearly unstable above 1e-6 of the drift's scale
/// `max(|d pi|, |d omega|) / hbar`, else spectrally stable only.
fn growth_verdict(mut analysis: ZeitlinAnalysis, blocks: &[Block], hbar: f64, progress: &Progress) -> ZeitlinAnalysis {
    let rate = blocks
        .par_iter()
        .map(|b| {
            progress.step(1);
            b.growth_rate(hbar)
        })
        .reduce(|| 0.0, |a, b| if a.is_nan() || b.is_nan() { f64::NAN } else { a.max(b) });
    if rate.is_nan() {
        analysis.reason = "no energy–Casimir–momentum form is definite, and the drift's spectrum could not be computed (a non-finite value, or the eigenvalue iteration did not converge)".into();
        return analysis;
    }
    let scale = blocks.iter().flat_map(|b| b.d_pi.iter().chain(&b.d_omega)).fold(0.0f64, |a, b| a.max(b.abs())) / hbar;
    analysis.growth_rate = Some(rate);
    if rate > 1e-6 * scale.max(f64::MIN_POSITIVE) {
        analysis.verdict = Verdict::LinearlyUnstable;
        analysis.reason = unstable_reason(rate);
        return analysis;
    }
    analysis.reason = "no energy–Casimir–momentum form is definite, and every eigenvalue of the drift is on the imaginary axis (to the tolerance): spectrally stable only".into();
    analysis
}
