//! The compressible (barotropic) model: the noise-compatibility test and
//! the structural `Sigma^2 = 0` with the shifted energy–Casimir form.

use super::*;
use crate::profile::Potential;

/// `sup |U eta_j' + r_j'|` on the samples `ys` (where `U = us`) for each
/// noise field: how far its coadjoint action moves the equilibrium momentum.
fn noise_residuals(profile: &Profile, ys: &[f64], us: &[f64]) -> Vec<f64> {
    // The compatible completion makes the residual zero by construction
    // (r' = -U eta' exactly), so it is not sampled.
    profile
        .eta
        .iter()
        .zip(&profile.potential)
        .map(|([_, d], p)| match p {
            Potential::Compatible => 0.0,
            _ => ys
                .iter()
                .zip(us)
                .map(|(y, u)| {
                    let ep = d.eval(*y);
                    (u * ep + p.gradient(*y, *u, ep)).abs()
                })
                .fold(0.0, f64::max),
        })
        .collect()
}

/// For each noise field, whether `eta' = 0` and `r' = 0` are proved on the
/// closed interval (interval arithmetic).
fn constant_noise(profile: &Profile) -> Vec<bool> {
    let (a, b) = profile.interval;
    let proved_zero = |d: &crate::expr::Derivative| {
        d.expr().constant().is_some() || d.sign_on(a, b, crate::choice::SIGN_PROOF_BUDGET) == SignProof::Zero
    };
    // Constant eta and no potential force (r' = 0 proved, or r' = -U eta' = 0).
    profile
        .eta
        .iter()
        .zip(&profile.potential)
        .map(|([_, d], p)| {
            proved_zero(d)
                && match p {
                    Potential::None | Potential::Compatible => true,
                    Potential::Given([_, rp]) => proved_zero(rp),
                }
        })
        .collect()
}

/// The admissible Galilean shifts `[lo, hi]`: `w = (U + c)/U'' >= 0` and
/// `|U + c| < c_s` for `U` in `range`, and whether the weight's sign is proved.
fn admissible_shifts(choice: &Choice, range: Interval, uniform: bool, sound_speed: f64) -> (Option<(f64, f64)>, bool) {
    let c_s = Interval::point(sound_speed);
    // The largest c with c + U_hi < c_s (exactly, through the interval's lower bound).
    let below_cs = |u_hi: f64| (c_s - Interval::point(u_hi)).lo;
    let above = |x: f64| -x; // negation is exact
    if !(range.lo.is_finite() && range.hi.is_finite()) {
        return (None, false);
    }
    match choice {
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
}

/// Why no admissible Galilean shift exists for `choice` with `U` in `range`.
fn no_shift_reason(choice: &Choice, range: Interval, sound_speed: f64) -> String {
    match choice {
        Choice::NoForm { reason } => reason.clone(),
        Choice::Forced { sign, .. } if !sign.is_positive() => "the forced Casimir weight is negative, and a compressible form cannot be negative definite (the acoustic energy is positive)".into(),
        _ => format!(
            "no Galilean shift c makes the form definite: it needs |U + c| < c_s = {} and (U + c)/U'' >= 0 on the whole interval, but U ranges over [{:.6}, {:.6}] (a rigorous enclosure)",
            readable(sound_speed),
            range.lo, range.hi
        ),
    }
}

/// What the compressible steps share once the noise and the shifts are
/// known: the functional, whether `U` is uniform, the enclosure of `U`
/// and whether the weight's sign is proved.
struct Shifts<'a> {
    choice: &'a Choice,
    uniform: bool,
    range: Interval,
    sound_speed: f64,
    proved_weight: bool,
}

/// `Sigma^2 = 0` for constant noise: the form with the Galilean shift `c`
/// in the middle of `[lo, hi]` is positive definite, every mode's bound 0.
fn constant_noise_stable(
    problem: &FluidProblem,
    shifts: &Shifts,
    (lo, hi): (f64, f64),
    mut summary: FormSummary,
    base: FluidAnalysis,
) -> FluidAnalysis {
    let Shifts { choice, uniform, range, sound_speed, proved_weight } = *shifts;
    let c = if lo == hi { lo } else { 0.5 * lo + 0.5 * hi };
    summary.energy = 1.0;
    summary.galilean_shift = Some(c);
    summary.sign = Some(Sign::Positive);
    summary.kind = "energy_casimir_momentum";
    summary.casimir_weight = if uniform {
        format!("none needed: U is uniform and the shift c = {c:.6} brings it to rest (energy coefficient 1, plus momentum and mass)")
    } else {
        format!("Phi''(q_e) = (U + c)/U'' with c = {c:.6} (energy coefficient 1, plus momentum and mass)")
    };
    // Which ends of the admissible interval are admissible: the sonic end
    // |U + c| = c_s never (the acoustic part is then only semidefinite), the
    // end where the weight (U + c)/U'' touches 0 always (w >= 0 suffices).
    let shown = match choice {
        _ if lo == hi => format!("c = {lo:.6} is the only admissible shift"),
        Choice::Pseudomomentum { sign } if sign.is_positive() => {
            format!("admissible c in [{lo:.6}, {hi:.6}), the sonic end excluded")
        }
        _ => format!("admissible c in ({lo:.6}, {hi:.6}], the sonic end excluded"),
    };
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
            "every noise field is constant (eta' = 0 proved), so B_k = -ik eta_k I commutes with the drift and the form and Sigma^2 = 0; the form with Galilean shift c = {c:.6} ({shown}) is positive definite because |U + c| <= {worst:.6} < c_s = {} on the whole interval (a rigorous enclosure of U){}",
            readable(sound_speed),
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

/// The compressible model (see `docs/fluids.md`): the coadjoint action of
/// the noise element `((eta(y), 0), r(y))` on the equilibrium momentum
/// `m = rho u` is `-(0, U eta' + r')`: the transport part alone puts the
/// y-momentum `U eta'` into the equilibrium, which no pressure can absorb
/// (the density is not constrained), and the potential part `r` adds
/// `rho_e r'`. So the equilibrium is kept by constant `eta` where the flow
/// is non-zero (no potential needed), or by any `eta` with its compatible
/// completion `r' = -U eta'` (`"potential": "compatible"`). For constant
/// `eta` without potential, `B_k = -ik eta_k I` commutes with the drift and
/// with the form, so `Sigma^2 = 0`; the form
/// `|du|^2 + 2(U + c) drho du_x + c_s^2 drho^2 + w (curl du + U' drho)^2`
/// is positive definite iff `w >= 0` and `|U + c| < c_s` on the interval.
/// Compatible noise with non-constant `eta` goes to the discretised
/// compressible generator ([`crate::barotropic`], walls only).
///
/// What `stable` rests on is proved, not sampled: every `eta_k'` vanishes
/// identically (interval arithmetic, [`crate::expr::Derivative::sign_on`]),
/// and the range of `U` over the closed interval is enclosed rigorously, so
/// that `|U + c| < c_s` holds everywhere for the chosen `c`. The weight's
/// sign is proved for the pseudomomentum and the uniform flow (level
/// `exact_structure`) and only sampled for a forced shift (level `float`).
/// Noise whose residual `sup |U eta' + r'|` is far above rounding on the
/// samples is `noise_incompatible` (level `float`); noise in between,
/// neither proved compatible nor clearly not, is `inconclusive`.
pub(super) fn analyse_compressible(
    problem: &FluidProblem,
    settings: &FluidSettings,
    sound_speed: f64,
    paper_bound: f64,
    progress: &Progress,
) -> FluidAnalysis {
    let profile = &problem.profile;
    let (a, b) = profile.interval;
    let ys = profile.samples(crate::constants::FINE_SAMPLES);
    let us: Vec<f64> = ys.iter().map(|y| profile.u[0].eval(*y)).collect();
    let u_abs = us.iter().fold(0.0f64, |m, u| m.max(u.abs()));
    let noise_residuals = noise_residuals(profile, &ys, &us);
    let constant_noise = constant_noise(profile);
    let incompressible =
        analyse_steps(&FluidProblem { model: FluidModel::Incompressible, ..problem.clone() }, settings, progress).ok();
    let (incompressible_verdict, incompressible_sigma2) =
        incompressible.as_ref().map(|a| (a.verdict, a.sigma2)).unwrap_or((Verdict::Inconclusive, None));
    let choice = choose(profile);
    // A rigorous enclosure of the range of U over the closed interval.
    let range = profile.u[0].range_on(a, b, 1024);
    let uniform = profile.u[1].sign_on(a, b, crate::choice::SIGN_PROOF_BUDGET) == SignProof::Zero;
    let (shift_interval, proved_weight) = admissible_shifts(&choice, range, uniform, sound_speed);
    let summary = form_summary(&choice);
    let scale = u_abs.max(f64::MIN_POSITIVE);
    let incompatible: Vec<usize> =
        (0..noise_residuals.len()).filter(|&i| !constant_noise[i] && noise_residuals[i] > 1e-12 * scale).collect();
    let compressible = CompressibleReport {
        sound_speed,
        noise_residuals: noise_residuals.clone(),
        incompatible: incompatible.clone(),
        shift_interval,
        incompressible_verdict,
        incompressible_sigma2,
        generator: None,
    };
    let base = FluidAnalysis {
        compressible: Some(compressible),
        ..FluidAnalysis::without_certificate(Verdict::Inconclusive, String::new(), summary.clone(), paper_bound)
    };
    if let Some(&i) = incompatible.first() {
        return FluidAnalysis {
            verdict: Verdict::NoiseIncompatible,
            verification: Some(VerificationLevel::Float),
            reason: format!(
                "the coadjoint action of noise[{i}] on the momentum rho u contains (grad sigma)^T m + rho grad r = (0, U eta' + r'), which is not zero at the equilibrium (compressible.noise_residuals gives sup |U eta' + r'|): in compressible flow no pressure absorbs it (in incompressible flow it is a gradient), so the noise moves the shear flow; it is compatible with the potential part r' = -U eta', i.e. r = -int U eta' dy (compressible.compatible_completion: the noise list with {{\"transport\": eta, \"potential\": \"compatible\"}} where needed)"
            ),
            ..base
        };
    }
    // Noise neither constant nor carrying the compatible completion: its
    // residual is below rounding but nothing is proved.
    let unproved = (0..constant_noise.len())
        .find(|&i| !constant_noise[i] && !matches!(profile.potential[i], Potential::Compatible));
    if let Some(i) = unproved {
        return FluidAnalysis {
            reason: format!(
                "noise[{i}]: U eta' + r' is below 1e-12 of max|U| on every sample, but eta' (and r') could not be proved identically zero, so neither compatibility with B_k a multiple of the identity nor incompatibility is established (write the potential as \"compatible\" to have r' = -U eta' exactly)"
            ),
            ..base
        };
    }
    let needs_generator = constant_noise.iter().any(|c| !c);
    let Some((lo, hi)) = shift_interval else {
        return FluidAnalysis { reason: no_shift_reason(&choice, range, sound_speed), ..base };
    };
    if needs_generator {
        if profile.boundary != Boundary::Walls {
            return FluidAnalysis {
                reason: "the noise is compatible through its potential part, but the discretised compressible generator is built for walls only (a periodic y is not implemented): no Sigma^2 is claimed".into(),
                ..base
            };
        }
        let sonic_at_hi = !matches!(&choice, Choice::Pseudomomentum { sign } if !sign.is_positive());
        return analyse_generator(
            problem,
            settings,
            sound_speed,
            &choice,
            uniform,
            ShiftFreedom { lo, hi, sonic_at_hi },
            proved_weight,
            summary,
            base,
            progress,
        );
    }
    let shifts = Shifts { choice: &choice, uniform, range, sound_speed, proved_weight };
    constant_noise_stable(problem, &shifts, (lo, hi), summary, base)
}

/// `x` as Rust prints it where that is short (`2`, `0.35`), in exponent
/// form outside `[1e-4, 1e15)` (`1e-308`, not 308 zeros).
fn readable(x: f64) -> String {
    if x == 0.0 || (1e-4..1e15).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}
