//! The incompressible pipeline: `Sigma^2` per x-mode at every resolution of
//! the convergence table, the verified check at the finest, the paper's
//! constants beside ours, and the proof of stated per-mode bounds.

use super::*;

/// Whether `bound V - Q ⪰ 0` (with `V ≻ 0`) is proved by the verified
/// Cholesky test for each `(m, bound)`: x-mode `m` of the finest grid, with
/// the matrices built exactly as [`analyse`] builds them (the same noise
/// normalisation, choice of functional and form). `false` for a mode that
/// does not exist and for a profile that admits no form. In the
/// compressible model the matrices are the generator's
/// ([`crate::barotropic`]) at the Galilean shift `shift` (the analysis's
/// `form.galilean_shift`; `None`: nothing is proved). This is what
/// `verify check` runs on a stated bound below the one it re-derives: a
/// stated number is accepted only when it is proved.
pub fn prove_mode_bounds(problem: &FluidProblem, shift: Option<f64>, bounds: &[(usize, f64)]) -> Vec<bool> {
    if bounds.is_empty() {
        return vec![];
    }
    if matches!(problem.model, FluidModel::Compressible { .. }) {
        return match shift {
            Some(c) => prove_generator_bounds(problem, c, bounds),
            None => vec![false; bounds.len()],
        };
    }
    let p = &problem.profile;
    let fine = YGrid::new(p.boundary, p.interval.0, p.interval.1, problem.ny);
    let (scaled, e) = normalise_noise(problem, &fine);
    let profile = scaled.profile;
    let coef = profile.coefficients(&fine);
    let Some(form) = form_for(&choose(&profile), &profile, &coef, &fine) else { return vec![false; bounds.len()] };
    let ks = wavenumbers(problem);
    bounds
        .par_iter()
        .map(|&(m, bound)| {
            let Some(&(_, k)) = ks.iter().find(|(mm, _)| *mm == m) else { return false };
            let normalised = normalised_bound(bound, e);
            Mode::new(&fine, k).verify(&form, &coef, normalised) == (true, true)
        })
        .collect()
}

/// What the steps of `analyse_normalised` share: the (normalised) profile,
/// its functional, the finest grid with its coefficients, the x-modes, the
/// Lanczos tolerance and the progress.
struct Incompressible<'a> {
    profile: &'a Profile,
    choice: Choice,
    fine: YGrid,
    coef: Coefficients,
    ks: Vec<(usize, f64)>,
    tol: f64,
    progress: &'a Progress,
    /// The paper's functional (c = 0) is the chosen one (a forced shift of 0).
    paper_is_chosen: bool,
}

/// The modes of the finest grid with their verified bounds: `Sigma^2` over
/// them, its verified upper bound and the level of the claim.
struct ProvedModes {
    modes: Vec<ModeResult>,
    sigma2: f64,
    sigma2_upper: Option<f64>,
    verification: Option<VerificationLevel>,
}

impl Incompressible<'_> {
    /// The paper's functional (`c = 0`) on `grid`, if the profile has one.
    fn paper_form_at(&self, grid: &YGrid, coef: &Coefficients) -> Option<Form> {
        match &self.choice {
            Choice::Forced { .. } if self.paper_is_chosen => form_for(&self.choice, self.profile, coef, grid),
            Choice::Forced { .. } | Choice::Enstrophy | Choice::NoForm { .. } => None,
            Choice::Pseudomomentum { .. } => shifted_form(coef, 0.0),
        }
    }

    /// `Sigma^2` of `form` over the x-modes on `grid` (`None`: some mode failed).
    fn sigma2_on(&self, grid: &YGrid, coef: &Coefficients, form: &Form) -> Option<f64> {
        sigma2_all_modes(grid, coef, form, &self.ks, self.tol, self.progress)
    }

    /// `Sigma^2` of the paper's functional on the finest grid, when it is
    /// not the chosen one (whose run gives it otherwise).
    fn paper_at_fine(&self) -> Option<f64> {
        // Each phase of the plan (see `planned_steps`) counts as done when it
        // ends, whether or not it ran: the bar moves on at once past a part
        // this profile does not need.
        let _phase = self.progress.phase(self.ks.len() as u64);
        if self.paper_is_chosen {
            None
        } else {
            self.paper_form_at(&self.fine, &self.coef).and_then(|f| self.sigma2_on(&self.fine, &self.coef, &f))
        }
    }

    /// The Galilean-shift curve `(c, Sigma^2)` of the energy–Casimir–momentum
    /// forms with weight `(U + c)/U''` at eight shifts beyond the range of `U`
    /// (pseudomomentum only; empty otherwise).
    fn shift_curve(&self) -> Vec<(f64, f64)> {
        let _phase = self.progress.phase(8 * self.ks.len() as u64);
        let profile = self.profile;
        match &self.choice {
            Choice::Pseudomomentum { sign } => {
                let samples = profile.samples(crate::constants::PROFILE_SAMPLES);
                let us: Vec<f64> = samples.iter().map(|y| profile.u[0].eval(*y)).collect();
                let (umin, umax) =
                    us.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(*v), h.max(*v)));
                let range = (umax - umin).max(1e-12 * umax.abs().max(1.0));
                // U'' > 0 needs U + c > 0 (c > -min U); U'' < 0 needs U + c < 0 (c < -max U)
                (0..8)
                    .filter_map(|j| {
                        let d = range * 4f64.powi(j - 2);
                        let c = if sign.is_positive() { -umin + d } else { -umax - d };
                        let f = shifted_form(&self.coef, c)?;
                        Some((c, self.sigma2_on(&self.fine, &self.coef, &f)?))
                    })
                    .collect()
            }
            _ => vec![],
        }
    }

    /// Per x-mode on the finest grid: `lambda_max(Q, V)` by Lanczos, then
    /// the verified bound (`None` where the mode's solve failed).
    fn finest_modes(&self, form: &Form) -> Vec<Option<(ModeResult, crate::lanczos::Ritz)>> {
        let (fine, coef, tol, progress) = (&self.fine, &self.coef, self.tol, self.progress);
        let _phase = progress.phase(self.ks.len() as u64);
        self.ks
            .par_iter()
            .map(|&(m, k)| {
                mode_step(progress, || {
                    let mode = Mode::new(fine, k);
                    let s = mode.sigma2(form, coef, tol).ok()?;
                    // Mode::sigma2 never returns a non-finite value; flooring NaN at 0
                    // would round towards "stable".
                    let sigma2 = s.lambda_max.max(0.0);
                    let (upper, form_verified) = verified_mode_bound(&mode, form, coef, sigma2, &s.ritz);
                    let result =
                        ModeResult { m, k, sigma2, sigma2_upper: upper, form_verified, iterations: s.ritz.iterations };
                    Some((result, s.ritz))
                })
            })
            .collect()
    }

    /// The overall bound tightened and every mode's bound proved: `Sigma^2`
    /// and its verified upper bound are the largest over the modes.
    fn prove_modes(&self, form: &Form, mut modes: Vec<ModeResult>, ritz: &[crate::lanczos::Ritz]) -> ProvedModes {
        let (fine, coef, ks) = (&self.fine, &self.coef, &self.ks);
        // the banded check alone, as the ladder of `verified_mode_bound` climbs
        // it (or the dense one alone where it is preferred, from the narrowest
        // rung: `crate::modes::dense_check_preferred`)
        let dense_only = Mode::new(fine, ks[0].1).prefers_dense(coef);
        let narrowest = if dense_only { 0 } else { first_rung(fine.n()) };
        tighten_overall_bound(&mut modes, ritz, narrowest, self.progress, |i, bar| {
            Mode::new(fine, ks[i].1).ladder_check(form, coef, bar).1
        });
        prove_remaining_modes(&mut modes, self.progress, |k, bar| Mode::new(fine, k).verify(form, coef, bar).1);
        let sigma2 = modes.iter().map(|r| r.sigma2).fold(0.0, f64::max);
        let sigma2_upper = modes.iter().try_fold(0.0f64, |acc, r| r.sigma2_upper.map(|u| acc.max(u)));
        let verification = Some(if form.energy == 0.0 {
            VerificationLevel::ExactStructure
        } else if sigma2_upper.is_some() {
            VerificationLevel::VerifiedFloat
        } else {
            VerificationLevel::Float
        });
        ProvedModes { modes, sigma2, sigma2_upper, verification }
    }

    /// The convergence table (Lanczos at each resolution, the finest row
    /// from `finest = (sigma2, paper_choice_sigma2)`) and the drift residual
    /// of the coarsest grid that has a form.
    fn convergence(
        &self,
        problem: &FluidProblem,
        settings: &FluidSettings,
        finest: (f64, Option<f64>),
    ) -> (Vec<ConvergenceRow>, Option<f64>) {
        let (profile, fine) = (self.profile, &self.fine);
        let (sigma2, paper_choice_sigma2) = finest;
        let mut convergence = vec![];
        let mut drift_residual = None;
        for ny in table_resolutions(problem.ny, settings.convergence_from) {
            let (grid, coef) = if ny == problem.ny {
                (fine.clone(), self.coef.clone())
            } else {
                let g = YGrid::new(profile.boundary, profile.interval.0, profile.interval.1, ny);
                let c = profile.coefficients(&g);
                (g, c)
            };
            let Some(f) = form_for(&self.choice, profile, &coef, &grid) else { continue };
            if drift_residual.is_none() {
                drift_residual = self.drift_residual(&grid, &coef, &f);
            }
            let s = if ny == problem.ny { Some(sigma2) } else { self.sigma2_on(&grid, &coef, &f) };
            let p = if ny == problem.ny {
                paper_choice_sigma2
            } else if self.paper_is_chosen {
                s
            } else {
                self.paper_form_at(&grid, &coef).and_then(|pf| self.sigma2_on(&grid, &coef, &pf))
            };
            convergence.push(ConvergenceRow { ny, sigma2: s, sigma2_paper_choice: p });
        }
        (convergence, drift_residual)
    }

    /// `max_k |sym(V A)| / (|V| |A|)` over the x-modes on `grid`: how far
    /// the drift is from `V`-skew (`None`: not finite).
    fn drift_residual(&self, grid: &YGrid, coef: &Coefficients, f: &Form) -> Option<f64> {
        // |sym(V A)| / (|V| |A|), A = -ik R: dimensionless, so it does not
        // grow with the size of U (it did when divided by |V| alone).
        let r = self
            .ks
            .par_iter()
            .map(|(_, k)| {
                mode_step(self.progress, || {
                    let mode = Mode::new(grid, *k);
                    let scale = mode.form_matrix(f).norm() * k * mode.drift_matrix(coef).norm();
                    Some(mode.drift_residual(f, coef).norm() / scale)
                })
                .unwrap_or(f64::NAN)
            })
            .reduce(|| 0.0, |a, b| if a.is_nan() || b.is_nan() { f64::NAN } else { a.max(b) });
        r.is_finite().then_some(r)
    }
}

/// Why the second variation is not proved definite: x-mode `m` (wavenumber
/// `k`) failed the verified check.
fn unverified_reason(summary: &FormSummary, (m, k): (usize, f64)) -> String {
    format!(
        "{}; the second variation could not be shown definite for x-mode m = {m} (k = {k:.6}){}",
        summary.casimir_weight,
        if summary.sign == Some(Sign::Negative) {
            ": Arnold's second criterion (K + M w negative definite) fails there"
        } else {
            ""
        }
    )
}

/// The incompressible analysis on the normalised noise (the compressible
/// model goes to `analyse_compressible`): the chosen functional's `Sigma^2`
/// per x-mode, verified, with the paper's functional and the table beside.
pub(super) fn analyse_normalised(
    problem: &FluidProblem,
    settings: &FluidSettings,
    fine: &YGrid,
    progress: &Progress,
) -> FluidAnalysis {
    let profile = &problem.profile;
    let fine = fine.clone();
    let paper_bound = profile.paper_bound();
    if let FluidModel::Compressible { sound_speed } = problem.model {
        return analyse_compressible(problem, settings, sound_speed, paper_bound, progress);
    }
    let ks = wavenumbers(problem);
    let choice = choose(profile);
    let coef = profile.coefficients(&fine);
    let summary = form_summary(&choice);
    let tol = settings.lanczos_tolerance;

    // The paper's functional (c = 0) and the Galilean-shift curve.
    // When the forced shift is 0 the paper's functional is the chosen one,
    // built by the same call: its Sigma^2 is the chosen form's, at every
    // resolution, and is taken from that run instead of a second Lanczos
    // pass over every mode (at the finest grid and in each row of the
    // convergence table).
    let paper_is_chosen = matches!(&choice, Choice::Forced { shift, .. } if shift.abs() == 0.0);
    let run = Incompressible { profile, choice, fine, coef, ks, tol, progress, paper_is_chosen };
    let paper_at_fine = run.paper_at_fine();
    let shift_curve = run.shift_curve();

    let (form, stable_reason) = match form_and_reason(&run.choice, profile, &run.coef, &run.fine, &summary) {
        Ok(x) => x,
        Err(reason) => {
            // (no form: the paper's functional, if it is the chosen one,
            // has none either)
            return inconclusive_or_unstable(
                problem,
                settings,
                reason,
                summary,
                paper_bound,
                paper_at_fine,
                shift_curve,
                progress,
            );
        }
    };

    // Per mode at the finest grid: Lanczos, then the verified bound.
    let per_mode = run.finest_modes(&form);
    // the Lanczos values of every mode, as `sigma2_all_modes` gives them
    // (`None` if one failed)
    let paper_choice_sigma2 = if paper_is_chosen {
        per_mode.iter().try_fold(0.0f64, |acc, r| r.as_ref().map(|(r, _)| acc.max(r.sigma2)))
    } else {
        paper_at_fine
    };
    if let Some(pos) = per_mode.iter().position(|r| !r.as_ref().is_some_and(|(r, _)| r.form_verified)) {
        return inconclusive_or_unstable(
            problem,
            settings,
            unverified_reason(&summary, run.ks[pos]),
            summary,
            paper_bound,
            paper_choice_sigma2,
            shift_curve,
            progress,
        );
    }
    let (modes, ritz): (Vec<ModeResult>, Vec<crate::lanczos::Ritz>) = per_mode.into_iter().flatten().unzip();
    let ProvedModes { modes, sigma2, sigma2_upper, verification } = run.prove_modes(&form, modes, &ritz);

    // Convergence table (Lanczos at each resolution).
    let (convergence, drift_residual) = run.convergence(problem, settings, (sigma2, paper_choice_sigma2));

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
        instability_search: vec![],
        compressible: None,
    }
}

pub(super) fn form_summary(choice: &Choice) -> FormSummary {
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
