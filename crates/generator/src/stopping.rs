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
    /// ```
    /// let t = generator::StoppingTime::new(0.1, 0.001, 0.27);
    /// assert!((t.time().unwrap() - (100f64).ln() / 0.27).abs() < 1e-12);
    /// assert_eq!(generator::StoppingTime::new(0.1, 0.001, 0.0).time(), None);
    /// ```
    pub fn time(&self) -> Option<f64> {
        (self.sigma2 > 0.0).then(|| (self.epsilon / self.delta).ln() / self.sigma2)
    }

    /// The bound `(delta/eps) e^{Sigma^2 t}` on `P(|dmu_t|_P^2 > eps)`.
    pub fn probability_bound(&self, t: f64) -> f64 {
        (self.delta / self.epsilon) * (self.sigma2 * t).exp()
    }
}
