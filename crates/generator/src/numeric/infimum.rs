//! Step 5 of the numeric level: `Sigma^2 = max(0, lambda_max(sQ, sP))`
//! for the first choice of the Casimir Hessian, the infimum over it (the
//! restricted `lambda_max(Z^T sQ Z, Z^T sP Z)`), and `K` constructed for
//! targets just above the infimum when the first choice does not attain it.

use super::completion::SignedPencil;
use super::condition;
use crate::optimise::{approach_infimum, Approach};
use crate::pencil::largest_generalized_eigenvalue;
use crate::pipeline::Settings;
use nalgebra::DMatrix;

/// The `P` chosen, its `Sigma^2`, and the infimum over the Casimir Hessian.
pub(super) struct Growth {
    /// `sP`.
    pub(super) sp: DMatrix<f64>,
    /// `max(0, lambda_max(sQ, sP))`.
    pub(super) sigma2: f64,
    /// `max(0, restricted lambda_max)`.
    pub(super) infimum: f64,
}

/// The first choice `K' = K0' + D` and the infimum over `K'`.
struct FirstChoice {
    /// `sP` for the first choice.
    p: DMatrix<f64>,
    /// Its `Sigma^2`.
    sigma2: f64,
    /// The restricted `lambda_max` (`-inf` when `k = 0`).
    restricted_max: f64,
    /// `max(0, restricted_max)`.
    infimum: f64,
    /// The scale of `Sigma^2`: the infimum, else the first choice's value.
    scale: f64,
}

impl FirstChoice {
    /// `Sigma^2` at `K' = K0' + D` and the restricted `lambda_max`.
    fn new(pencil: &SignedPencil) -> Result<Self, &'static str> {
        let frame = &pencil.frame;
        let first_k = &frame.k0 + &frame.margin;
        let p = pencil.p_of(&first_k);
        let first_l =
            largest_generalized_eigenvalue(&p, &pencil.sq).ok_or("the generalized eigenproblem of the first choice")?;
        let sigma2 = first_l.max(0.0);
        let restricted_max = if pencil.k == 0 {
            f64::NEG_INFINITY
        } else {
            largest_generalized_eigenvalue(&frame.pz, &frame.qz).ok_or("the restricted generalized eigenproblem")?
        };
        let infimum = restricted_max.max(0.0);
        let scale = if infimum > 0.0 { infimum } else { sigma2 };
        Ok(FirstChoice { p, sigma2, restricted_max, infimum, scale })
    }

    /// Whether the first choice attains the infimum (to the tolerance the
    /// construction in `approach` accepts): nothing to gain. (Its
    /// condition number is within the limit, which is at least 10 times it.)
    fn attained(&self) -> bool {
        self.infimum.max(self.sigma2) <= 0.0 || self.sigma2 <= self.infimum + 1.1e-12 * self.scale
    }
}

/// `Sigma^2` for the first choice, or for `K` built for a target just
/// above the infimum when that is lower (with `settings.optimise`);
/// `Err` when floating point is inconsistent.
pub(super) fn growth(pencil: &SignedPencil, settings: &Settings) -> Result<Growth, &'static str> {
    let first = FirstChoice::new(pencil)?;
    let found = if settings.optimise && !first.attained() {
        approach(pencil, &first, settings.optimisation.tolerance)
    } else {
        None
    };
    let (infimum, scale) = (first.infimum, first.scale);
    let mut best = (first.p, first.sigma2);
    if let Some(f) = found.filter(|f| f.1 <= best.1) {
        best = f;
    }
    let (sp, sigma2) = best;
    if !sigma2.is_finite() {
        return Err("Sigma^2 is not finite in double precision");
    }
    if sigma2 < infimum * (1.0 - 1e-6) - 1e-12 * scale {
        // lambda_max at a finite K is never below the infimum over K: the
        // floating-point pencil is inconsistent (not a proof of anything,
        // but a sign that rounding decided it).
        return Err("Sigma^2 came out below the infimum over the Casimir Hessian");
    }
    Ok(Growth { sp, sigma2, infimum })
}

/// `sP` and `Sigma^2` for `K` built for targets `S = infimum + delta`, as
/// the exact optimiser builds it (`at_multipliers`), screened in floating
/// point only: `cond(sP)` within the limit and `Sigma^2` within the gap.
fn approach(pencil: &SignedPencil, first: &FirstChoice, tolerance: f64) -> Option<(DMatrix<f64>, f64)> {
    let (frame, infimum, scale) = (&pencil.frame, first.infimum, first.scale);
    // lambda_max(sQ, sP) and cond(sP).
    let screen = |sp: &DMatrix<f64>| -> Option<(f64, f64)> {
        Some((largest_generalized_eigenvalue(sp, &pencil.sq)?, condition(sp)))
    };
    let first_cond = condition(&first.p);
    let cond_limit = 1e8f64.max(10.0 * first_cond.min(1e300));
    let passes = |(l, c): (f64, f64), allowed: f64| -> bool {
        c <= 1.1 * cond_limit && l.max(0.0) <= infimum + allowed + c * 1e-15 * scale
    };
    let build = |delta: f64, allowed: f64| -> Option<(DMatrix<f64>, f64)> {
        let kp = frame.k_for(infimum + delta, delta == 0.0)?;
        let p = pencil.p_of(&kp);
        let v = screen(&p)?;
        passes(v, allowed).then_some((p, v.0.max(0.0)))
    };
    let found = if first.restricted_max > 0.0 { build(0.0, 1e-12 * scale) } else { None };
    found.or_else(|| {
        approach_infimum(
            Approach { infimum, ceiling: first.sigma2, scale, tolerance, cond_limit },
            |delta| build(delta, 2.0 * delta + 1e-12 * scale),
            |delta| frame.k_for(infimum + delta, false).and_then(|kp| screen(&pencil.p_of(&kp))).map(|v| v.1),
        )
    })
}
