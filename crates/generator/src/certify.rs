//! Exact certification of `Sigma^2`: a rational `S` with `S (sP) - (sQ) ⪰ 0`.
//!
//! The floating-point `lambda_max` only locates the constant. The claim
//! `L|x|_P^2 <= S |x|_P^2` is the exact matrix inequality `S sP - sQ ⪰ 0`
//! (with `sP ≻ 0` proved separately), checked by the exact
//! semidefiniteness test of [`exact::Matrix::is_positive_semidefinite`],
//! which handles singular matrices without tolerance. When `S sP - sQ` is
//! also singular, `S` is a generalized eigenvalue and hence equals
//! `lambda_max`: the constant is then certified *sharp*, not just an upper
//! bound.

use casimir::Sign;
use exact::{best_rational_approximation, decimal_at_least, power_of_two, rational_from_f64, Matrix, Rational};
use num_traits::Zero;

/// A certified rational `Sigma^2`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ExactSigma2 {
    /// `S >= 0` with `S sP - sQ ⪰ 0`, exactly.
    pub value: Rational,
    /// Whether `S` is proved equal to `max(0, lambda_max)`: `S sP - sQ` is
    /// singular, or `S = 0` (the floor).
    pub sharp: bool,
}

/// `S sP - sQ`.
pub fn sigma2_gap(p: &Matrix, q: &Matrix, sign: Sign, s: &Rational) -> Matrix {
    let sp = if !sign.is_positive() { p.scale(&Rational::from(-1)) } else { p.clone() };
    let sq = if !sign.is_positive() { q.scale(&Rational::from(-1)) } else { q.clone() };
    sp.scale(s).sub(&sq)
}

/// Whether `S sP - sQ ⪰ 0` exactly (`S >= 0` required).
pub fn sigma2_bound_holds(p: &Matrix, q: &Matrix, sign: Sign, s: &Rational) -> bool {
    !s.is_negative() && sigma2_gap(p, q, sign, s).is_positive_semidefinite()
}

/// Find a rational `S >= max(0, lambda_max)` as close to it as the exact
/// test allows, trying in turn: `0` (when the estimate is not positive),
/// simple rationals near the estimate (which certify the sharp value when
/// `lambda_max` is rational), decimals just above it (relative margins
/// `1e-14 .. 1e-10`), and, when none of those is both a bound and within
/// `1e-10` of `lambda_max` (an ill-conditioned `P`, or a constant outside the
/// range of doubles, where the floating-point estimate means nothing), an
/// exact search that needs no estimate: powers of two bracket `lambda_max`
/// by galloping over the exponent, then bisection on the exponent and on
/// the value brackets it to a relative `1e-13`, every step decided by the
/// exact test and every comparison made in rational arithmetic. So the
/// result is always within `1e-10` of `lambda_max` when it exists (`sharp`
/// or not), whatever the scale: `Sigma^2 = 3e-321` (noise `1e-160`) is found
/// as exactly as `0.27`. `None` only if no power of two between `2^-8000`
/// and `2^8000` bounds `Q`.
///
/// ```
/// use exact::{Matrix, Rational};
/// use generator::certify_sigma2;
/// let q = |n: i64, d: i64| Rational::new_small(n, d);
/// // P = diag(1, 1/6, 2/3), Q = diag(0, 9/200, -9/200): lambda_max = 27/100 exactly.
/// let p = Matrix::from_rows(&[vec![q(1, 1), q(0, 1), q(0, 1)], vec![q(0, 1), q(1, 6), q(0, 1)], vec![q(0, 1), q(0, 1), q(2, 3)]]);
/// let qm = Matrix::from_rows(&[vec![q(0, 1), q(0, 1), q(0, 1)], vec![q(0, 1), q(9, 200), q(0, 1)], vec![q(0, 1), q(0, 1), q(-9, 200)]]);
/// let s = certify_sigma2(&p, &qm, casimir::Sign::Positive, 0.27000000000000002).unwrap();
/// assert_eq!(s.value, q(27, 100));
/// assert!(s.sharp);
/// // The same Q times 2^-1200: no double holds lambda_max, the estimate is 0,
/// // and the exact search still finds 27/100 * 2^-1200.
/// let tiny = exact::power_of_two(-1200);
/// let s = certify_sigma2(&p, &qm.scale(&tiny), casimir::Sign::Positive, 0.0).unwrap();
/// assert_eq!(s.value, q(27, 100) * tiny);
/// ```
pub fn certify_sigma2(p: &Matrix, q: &Matrix, sign: Sign, estimate: f64) -> Option<ExactSigma2> {
    let accept = |s: &Rational| -> Option<ExactSigma2> {
        let gap = sigma2_gap(p, q, sign, s);
        if s.is_negative() || !gap.is_positive_semidefinite() {
            return None;
        }
        // S = 0 is the floored constant max(0, lambda_max) exactly.
        let sharp = s.is_zero() || (gap.nrows() > 0 && gap.rank() < gap.nrows());
        Some(ExactSigma2 { value: s.clone(), sharp })
    };
    // Tight: sharp, or (1 - 1e-10) S no longer bounds Q.
    let tight = |e: &ExactSigma2| {
        e.sharp || !sigma2_bound_holds(p, q, sign, &(&e.value * Rational::new_small(9_999_999_999, 10_000_000_000)))
    };
    // Candidates near a usable estimate (a normal positive double), tried
    // lazily: most certificates accept the first.
    if estimate.is_finite() && estimate >= f64::MIN_POSITIVE {
        let simple = [1u64, 10, 100, 1000, 10_000, 100_000, 1_000_000, 1 << 20, 1 << 30];
        let margins = [1e-14, 1e-13, 1e-12, 1e-11, 1e-10];
        let candidates = simple
            .into_iter()
            .filter_map(|denominator| {
                let r = best_rational_approximation(estimate, denominator)?;
                ((exact::rational_to_f64(&r) - estimate).abs() <= 1e-13 * estimate).then_some(r)
            })
            // the estimate rounded to 15 significant digits: the exact value
            // when Sigma^2 is a short decimal at any scale (3e-300, 3e300)
            .chain(exact::parse_number(&format!("{estimate:.14e}")).ok())
            .chain(rational_from_f64(estimate))
            .chain(margins.into_iter().filter_map(|m| decimal_at_least(estimate * (1.0 + m), 16)));
        let mut tried: Vec<Rational> = Vec::new();
        for s in candidates {
            if tried.contains(&s) {
                continue;
            }
            tried.push(s.clone());
            if let Some(e) = accept(&s) {
                if tight(&e) {
                    return Some(e);
                }
                break; // a bound, but loose: the estimate is off; search exactly
            }
        }
    }
    if sigma2_bound_holds(p, q, sign, &Rational::zero()) {
        return accept(&Rational::zero());
    }
    let (lo, hi, e) = exact_search(p, q, sign, estimate)?;
    // A simple rational in the bracket (scaled by 2^e) is lambda_max itself
    // when the bound is also singular there: the sharp value, at any scale.
    let mantissa = exact::rational_to_f64(&(&hi / &power_of_two(e)));
    for denominator in [1u64, 10, 100, 1000, 10_000, 100_000, 1_000_000] {
        let Some(r) = best_rational_approximation(mantissa, denominator) else { continue };
        let candidate = r * power_of_two(e);
        if candidate > lo && candidate <= hi {
            if let Some(found) = accept(&candidate).filter(|f| f.sharp) {
                return Some(found);
            }
        }
    }
    accept(&hi)
}

/// The exact search of [`certify_sigma2`]: `(lo, hi, e)` with the bound
/// failing at `lo`, holding at `hi`, `hi - lo <= 1e-13 hi` (so `hi` is within
/// `1e-13` of `lambda_max`) and `2^e <= lo < hi <= 2^(e+1)`, assuming the
/// bound fails at 0.
fn exact_search(p: &Matrix, q: &Matrix, sign: Sign, estimate: f64) -> Option<(Rational, Rational, i64)> {
    const MAX_EXPONENT: i64 = 8000;
    let holds = |e: i64| sigma2_bound_holds(p, q, sign, &power_of_two(e));
    // Start at the estimate's exponent when it has one.
    let start = if estimate.is_finite() && estimate > 0.0 { estimate.log2().floor() as i64 } else { 0 };
    let start = start.clamp(-MAX_EXPONENT, MAX_EXPONENT);
    // Gallop to a bracket 2^lo_e (fails) < lambda_max <= 2^hi_e (holds).
    let (mut lo_e, mut hi_e);
    if holds(start) {
        hi_e = start;
        let mut step = 1;
        loop {
            let e = hi_e - step;
            if e < -MAX_EXPONENT {
                return None;
            }
            if holds(e) {
                hi_e = e;
                step *= 2;
            } else {
                lo_e = e;
                break;
            }
        }
    } else {
        lo_e = start;
        let mut step = 1;
        loop {
            let e = lo_e + step;
            if e > MAX_EXPONENT {
                return None;
            }
            if holds(e) {
                hi_e = e;
                break;
            }
            lo_e = e;
            step *= 2;
        }
    }
    // Bisect the exponent down to consecutive powers of two.
    while hi_e - lo_e > 1 {
        let mid = lo_e + (hi_e - lo_e) / 2;
        if holds(mid) {
            hi_e = mid;
        } else {
            lo_e = mid;
        }
    }
    // Bisect the value in [2^lo_e, 2^hi_e]: dyadic midpoints stay short.
    let mut lo = power_of_two(lo_e);
    let mut hi = power_of_two(hi_e);
    let tolerance = Rational::new_small(1, 10_000_000_000_000);
    let half = Rational::new_small(1, 2);
    while &hi - &lo > &hi * &tolerance {
        let mid = (&lo + &hi) * &half;
        if sigma2_bound_holds(p, q, sign, &mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Some((lo, hi, lo_e))
}
