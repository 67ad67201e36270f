//! One time step of the stochastic Lie–Poisson equation, and of its
//! linearisation.

use crate::model::Model;
use generator::Linearisation;

/// The integration scheme.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scheme {
    /// Heun in the Lie algebra, moved by `exp(ad*)`: stays on the coadjoint
    /// orbit (Casimirs conserved to round-off).
    LieHeun,
    /// Stratonovich Heun in the vector space (the reference; drifts off the
    /// orbit).
    Heun,
}

impl Scheme {
    /// Parse `lie` / `heun`.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "lie" | "lie-heun" => Some(Scheme::LieHeun),
            "heun" => Some(Scheme::Heun),
            _ => None,
        }
    }

    /// Name used in outputs.
    pub fn as_str(&self) -> &'static str {
        match self {
            Scheme::LieHeun => "lie-heun",
            Scheme::Heun => "heun",
        }
    }
}

/// A stepper with its scratch buffers (no allocation per step for `so3`,
/// `se3` and every quadratic Hamiltonian).
pub struct Stepper<'a> {
    model: &'a Model,
    scheme: Scheme,
    g: Vec<f64>,
    noise: Vec<f64>,
    xi: Vec<f64>,
    stage: Vec<f64>,
    f1: Vec<f64>,
    f2: Vec<f64>,
}

impl<'a> Stepper<'a> {
    /// A stepper for `model`.
    pub fn new(model: &'a Model, scheme: Scheme) -> Self {
        let n = model.dim();
        Stepper {
            model,
            scheme,
            g: vec![0.0; n],
            noise: vec![0.0; n],
            xi: vec![0.0; n],
            stage: vec![0.0; n],
            f1: vec![0.0; n],
            f2: vec![0.0; n],
        }
    }

    /// Advance `mu` by `dt` with Brownian increments `dw` (`dw_i ~ N(0, dt)`).
    ///
    /// ```
    /// use simulate::{Model, Scheme, Stepper};
    /// # use algebra::builtin; use casimir::System; use exact::{parse_expression, Rational, Symbols};
    /// # let so3 = builtin("so3").unwrap().algebra;
    /// # let s = Symbols::new(so3.coordinates());
    /// # let h = parse_expression("Pi1^2/6 + Pi2^2/4 + Pi3^2/2", &s).unwrap();
    /// # let c = parse_expression("(Pi1^2 + Pi2^2 + Pi3^2)/2", &s).unwrap();
    /// # let q = |n: i64| Rational::from(n);
    /// # let system = System::new(so3, h, vec![c], vec![], vec![q(1), q(0), q(0)], vec![vec![q(1), q(0), q(0)]]).unwrap();
    /// let model = Model::new(&system);
    /// let mut stepper = Stepper::new(&model, Scheme::LieHeun);
    /// let mut mu = [0.6, 0.8, 0.0];
    /// for k in 0..1000 {
    ///     stepper.step(&mut mu, 0.01, &[0.1 * ((k as f64) * 0.7).sin()]);
    /// }
    /// // |Pi| is a Casimir: kept to round-off.
    /// let r = (mu[0] * mu[0] + mu[1] * mu[1] + mu[2] * mu[2]).sqrt();
    /// assert!((r - 1.0).abs() < 1e-13);
    /// ```
    pub fn step(&mut self, mu: &mut [f64], dt: f64, dw: &[f64]) {
        let m = self.model;
        let n = m.dim();
        // The noise generator sum_i sigma_i dW_i (the same at both stages).
        self.noise.iter_mut().for_each(|x| *x = 0.0);
        for (sigma, w) in m.noise().iter().zip(dw) {
            for i in 0..n {
                self.noise[i] += sigma[i] * w;
            }
        }
        match self.scheme {
            Scheme::LieHeun => {
                m.gradient(mu, &mut self.g);
                for i in 0..n {
                    self.xi[i] = self.g[i] * dt + self.noise[i];
                }
                // Predictor: an Euler step is enough, since the predicted point
                // only enters through Dh (an O(dt^2) change of the generator);
                // the corrector below is a group action, so the orbit is kept.
                m.coad(&self.xi, mu, &mut self.stage);
                for i in 0..n {
                    self.stage[i] += mu[i];
                }
                m.gradient(&self.stage, &mut self.f1);
                for i in 0..n {
                    self.xi[i] = 0.5 * (self.g[i] + self.f1[i]) * dt + self.noise[i];
                }
                m.exp_coad(&self.xi, mu, &mut self.stage);
                mu.copy_from_slice(&self.stage);
            }
            Scheme::Heun => {
                // F(mu) = ad*_{Dh(mu) dt + sum sigma_i dW_i} mu
                m.gradient(mu, &mut self.g);
                for i in 0..n {
                    self.xi[i] = self.g[i] * dt + self.noise[i];
                }
                m.coad(&self.xi, mu, &mut self.f1);
                for i in 0..n {
                    self.stage[i] = mu[i] + self.f1[i];
                }
                m.gradient(&self.stage, &mut self.g);
                for i in 0..n {
                    self.xi[i] = self.g[i] * dt + self.noise[i];
                }
                m.coad(&self.xi, &self.stage, &mut self.f2);
                for i in 0..n {
                    mu[i] += 0.5 * (self.f1[i] + self.f2[i]);
                }
            }
        }
    }
}

/// The linearised SDE `dx = A x dt + sum_i B_i x o dW^i` in floating point.
#[derive(Clone, Debug)]
pub struct LinearModel {
    n: usize,
    /// Row-major `A`.
    a: Vec<f64>,
    /// Row-major `B_i`.
    b: Vec<Vec<f64>>,
}

impl LinearModel {
    /// From the exact linearisation.
    pub fn new(lin: &Linearisation) -> Self {
        let n = lin.a.nrows();
        LinearModel { n, a: lin.a.to_f64_vec(), b: lin.noise.iter().map(|m| m.to_f64_vec()).collect() }
    }

    /// Dimension.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Number of noise fields.
    pub fn noise_count(&self) -> usize {
        self.b.len()
    }

    /// One step `x <- exp(K) x` with `K = A dt + sum_i B_i dW_i` (the first
    /// Magnus term; the exponential by its Taylor series to order 8, far
    /// below round-off at the step sizes used). Consistent with the
    /// Stratonovich equation (weak order 1; exact when `A` and the `B_i`
    /// commute, e.g. the Kubo body and the Lagrange top, where it conserves
    /// the `P`-norm path by path as the SDE does). `k` and `y` are scratch
    /// space (`n^2` and `2n` long).
    pub fn step(&self, x: &mut [f64], dt: f64, dw: &[f64], k: &mut [f64], y: &mut [f64]) {
        let n = self.n;
        for (kk, a) in k.iter_mut().zip(&self.a) {
            *kk = a * dt;
        }
        for (b, w) in self.b.iter().zip(dw) {
            for (kk, bb) in k.iter_mut().zip(b) {
                *kk += bb * w;
            }
        }
        let (term, next) = y.split_at_mut(n);
        term.copy_from_slice(x);
        for order in 1..=8 {
            for i in 0..n {
                let row = &k[i * n..(i + 1) * n];
                next[i] = row.iter().zip(term.iter()).map(|(r, v)| r * v).sum::<f64>() / order as f64;
            }
            term.copy_from_slice(next);
            for i in 0..n {
                x[i] += term[i];
            }
        }
    }
}
