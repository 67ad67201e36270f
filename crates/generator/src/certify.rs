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

use exact::{best_rational_approximation, decimal_at_least, rational_from_f64, Matrix, Rational};
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
pub fn sigma2_gap(p: &Matrix, q: &Matrix, sign: i8, s: &Rational) -> Matrix {
    let sp = if sign < 0 { p.scale(&Rational::from(-1)) } else { p.clone() };
    let sq = if sign < 0 { q.scale(&Rational::from(-1)) } else { q.clone() };
    sp.scale(s).sub(&sq)
}

/// Whether `S sP - sQ ⪰ 0` exactly (`S >= 0` required).
pub fn sigma2_bound_holds(p: &Matrix, q: &Matrix, sign: i8, s: &Rational) -> bool {
    !s.is_negative() && sigma2_gap(p, q, sign, s).is_positive_semidefinite()
}

/// Find a rational `S >= max(0, lambda_max)` as close to it as the exact
/// test allows, trying in turn: `0` (when the estimate is not positive),
/// simple rationals near the estimate (which certify the sharp value when
/// `lambda_max` is rational), decimals just above it (relative margins
/// `1e-14 .. 1e-10`), and, when the floating-point estimate is off (an
/// ill-conditioned `P`), an exact bisection that brackets `lambda_max` to
/// `1e-13` relative with the exact test alone. `None` only if no finite
/// bracket is found.
///
/// ```
/// use exact::{Matrix, Rational};
/// use generator::certify_sigma2;
/// let q = |n: i64, d: i64| Rational::new_small(n, d);
/// // P = diag(1, 1/6, 2/3), Q = diag(0, 9/200, -9/200): lambda_max = 27/100 exactly.
/// let p = Matrix::from_rows(&[vec![q(1, 1), q(0, 1), q(0, 1)], vec![q(0, 1), q(1, 6), q(0, 1)], vec![q(0, 1), q(0, 1), q(2, 3)]]);
/// let qm = Matrix::from_rows(&[vec![q(0, 1), q(0, 1), q(0, 1)], vec![q(0, 1), q(9, 200), q(0, 1)], vec![q(0, 1), q(0, 1), q(-9, 200)]]);
/// let s = certify_sigma2(&p, &qm, 1, 0.27000000000000002).unwrap();
/// assert_eq!(s.value, q(27, 100));
/// assert!(s.sharp);
/// ```
pub fn certify_sigma2(p: &Matrix, q: &Matrix, sign: i8, estimate: f64) -> Option<ExactSigma2> {
    if !estimate.is_finite() {
        return None;
    }
    // Candidates, generated lazily (most certificates accept the first).
    let simple = [1u64, 10, 100, 1000, 10_000, 100_000, 1_000_000, 1 << 20, 1 << 30];
    let margins = [1e-14, 1e-13, 1e-12, 1e-11, 1e-10];
    let candidates = (estimate <= 1e-12)
        .then(Rational::zero)
        .into_iter()
        .chain(simple.into_iter().filter(|_| estimate > 0.0).filter_map(|denominator| {
            let r = best_rational_approximation(estimate, denominator)?;
            ((exact::rational_to_f64(&r) - estimate).abs() <= 1e-13 * estimate).then_some(r)
        }))
        .chain((estimate > 0.0).then(|| rational_from_f64(estimate)).flatten())
        .chain(
            margins.into_iter().filter(|_| estimate > 0.0).filter_map(|m| decimal_at_least(estimate * (1.0 + m), 16)),
        );
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
    let mut upper: Option<Rational> = None;
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
            upper = Some(e.value);
            break;
        }
    }
    // The floating-point estimate was off (an ill-conditioned P): bracket
    // lambda_max exactly and bisect with the exact test, on short decimals.
    let mut hi = match upper {
        Some(u) => u,
        None => {
            let mut hi = decimal_at_least(estimate.max(1e-300) * 2.0 + 1e-12, 16)?;
            let mut grow = 0;
            while !sigma2_bound_holds(p, q, sign, &hi) {
                hi = &hi * Rational::from(4) + Rational::new_small(1, 1_000_000);
                grow += 1;
                if grow > 60 {
                    return None;
                }
            }
            hi
        }
    };
    let mut lo = Rational::zero();
    if sigma2_bound_holds(p, q, sign, &lo) {
        return accept(&lo);
    }
    for _ in 0..100 {
        let (lf, hf) = (exact::rational_to_f64(&lo), exact::rational_to_f64(&hi));
        if hf - lf <= 1e-13 * hf {
            break;
        }
        let mid = decimal_at_least(0.5 * (lf + hf), 16)
            .filter(|m| m > &lo && m < &hi)
            .unwrap_or_else(|| (&lo + &hi) / Rational::from(2));
        if sigma2_bound_holds(p, q, sign, &mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    accept(&hi)
}
