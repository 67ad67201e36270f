//! Stopping times and the Markov-inequality bound.

/// `T(eps, delta) = ln(eps/delta) / Sigma^2` and the bound
/// `P(|dmu_t|_P^2 > eps) <= (delta/eps) e^{Sigma^2 t}` for `|dmu_0|_P^2 = delta`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StoppingTime {
    /// Threshold `eps` on `|dmu_t|_P^2`.
    pub epsilon: f64,
    /// Initial size `delta = |dmu_0|_P^2`.
    pub delta: f64,
    /// The growth constant used.
    pub sigma2: f64,
}

impl StoppingTime {
    /// Bundle the inputs; `epsilon > delta > 0` is the caller's to check.
    pub fn new(epsilon: f64, delta: f64, sigma2: f64) -> Self {
        StoppingTime { epsilon, delta, sigma2 }
    }

    /// `T = ln(eps/delta)/Sigma^2`, or `None` when `Sigma^2 = 0` (no finite
    /// stopping time: the bound never reaches 1).
    ///
    /// `T` is a guarantee (stable in probability up to `T`), so it is
    /// rounded *down*: `ln(eps/delta)` is formed without overflow or
    /// cancellation (`ln_1p` for ratios up to 2, `ln eps - ln delta` when
    /// the ratio overflows, as for `eps = 1e308, delta = 1e-308`, which gave
    /// `T = infinity` before), each step is within a few ulps, and the result
    /// is lowered by a relative `8 eps`. A `T` beyond the largest double is
    /// reported as the largest double, still a true lower bound. A
    /// `Sigma^2` that is negative or NaN gives `T = 0`, which is always true:
    /// a broken input never turns into an infinite guarantee.
    ///
    /// ```
    /// let t = generator::StoppingTime::new(0.1, 0.001, 0.27);
    /// let exact = (100f64).ln() / 0.27;
    /// assert!(t.time().unwrap() <= exact && t.time().unwrap() > exact * (1.0 - 1e-14));
    /// assert_eq!(generator::StoppingTime::new(0.1, 0.001, 0.0).time(), None);
    /// // eps/delta overflows: ln(1e308) - ln(1e-308) = 1418.3...
    /// let far = generator::StoppingTime::new(1e308, 1e-308, 0.27).time().unwrap();
    /// assert!((far - 2.0 * 308.0 * 10f64.ln() / 0.27).abs() < 1e-9 * far);
    /// assert_eq!(generator::StoppingTime::new(0.1, 0.001, f64::NAN).time(), Some(0.0));
    /// ```
    pub fn time(&self) -> Option<f64> {
        let s = self.sigma2;
        if s == 0.0 {
            return None;
        }
        if s.is_nan() || s < 0.0 || s.is_infinite() {
            return Some(0.0);
        }
        let l = log_ratio(self.epsilon, self.delta);
        if l.is_nan() || l <= 0.0 {
            return Some(0.0);
        }
        let t = (l / s) * (1.0 - 8.0 * f64::EPSILON);
        Some(if t.is_finite() { t } else { f64::MAX })
    }
}

/// `ln(eps/delta)` for `eps > delta > 0`, accurate to a few ulps: no
/// cancellation for ratios near 1 and no overflow for ratios beyond the
/// double range.
fn log_ratio(epsilon: f64, delta: f64) -> f64 {
    let r = epsilon / delta;
    if !r.is_finite() {
        return epsilon.ln() - delta.ln();
    }
    if r <= 2.0 {
        // eps - delta is exact for delta <= eps <= 2 delta (Sterbenz)
        return ((epsilon - delta) / delta).ln_1p();
    }
    r.ln()
}
