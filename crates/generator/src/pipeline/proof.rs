//! The exact claims on `Sigma^2`: the certified rational bound for the
//! chosen `P`, and with free multipliers a certified bound over the family.

use super::optimum::Best;
use super::{Analysis, Settings};
use crate::bound::{family_lower_bound, InfimumWitness};
use crate::certify::{certify_sigma2, ExactSigma2};
use num_traits::Zero;

/// The certified rational `Sigma^2 >= lambda_max(Q, P)` of the chosen `P`
/// (with `exact` and `prove_bound`), and a certified lower bound over the
/// family added to the summary when one is proved and consistent with it.
pub(super) fn certify(analysis: &Analysis, best: &mut Best, settings: &Settings) -> Option<ExactSigma2> {
    let exact = if settings.exact && settings.prove_bound {
        certify_sigma2(&best.choice.p, &best.form.q, best.choice.sign, best.growth.largest_eigenvalue.max(0.0))
    } else {
        None
    };
    if let (Some(e), Some(o)) = (&exact, best.summary.as_mut()) {
        // With free multipliers, a certified bound over the whole family
        // (exact work, so at the exact level only), kept if consistent with
        // the certified value.
        if let (None, false, Some(t)) = (&o.infimum_lower_bound, o.q_depends_on_m, &o.infimum_parameters) {
            let variation = analysis.variation.as_ref().expect("set above");
            let lin = analysis.linearisation.as_ref().expect("set above");
            if let Some((rho, x)) = family_lower_bound(variation, lin, best.choice.sign, t) {
                if rho <= e.value {
                    o.infimum_lower_bound = Some(rho);
                    o.infimum_witness = Some(InfimumWitness::Matrix(x));
                }
            }
        }
    }
    exact
}

/// Why a certified `Sigma^2` is not stated: nonzero, yet no double holds
/// it (it is not rounded to 0, towards "stable").
pub(super) fn out_of_double_range(e: &ExactSigma2) -> Option<String> {
    // The certificate states Sigma^2 as a double beside the rational:
    // one that no double holds is not rounded to 0 (towards "stable").
    let f = exact::rational_to_f64(&e.value);
    let representable = f.is_finite() && f >= f64::MIN_POSITIVE;
    (!e.value.is_zero() && !representable).then(|| {
        format!(
            "a definite second variation was found, but Sigma^2 = 2^{} (about, proved exactly) lies outside the range of double precision: rescale time or the noise amplitudes",
            exact::binary_exponent(&e.value).unwrap_or(0)
        )
    })
}
