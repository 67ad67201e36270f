//! Exact second moments of the linearised SDE (independent evidence).
//!
//! For `dx = A~ x dt + sum_i B_i x dW^i` (Itô), `S(t) = E[x x^T]` solves the
//! linear ODE `dS/dt = A~ S + S A~^T + sum_i B_i S B_i^T` exactly, so
//! `E|x_t|_P^2 = tr(P S(t))` can be computed without sampling: vectorised,
//! `vec S(t) = exp(L t) vec S(0)` with `L = I ⊗ A~ + A~ ⊗ I + sum_i B_i ⊗ B_i`.

use crate::linearise::Linearisation;
use nalgebra::DMatrix;

/// The second-moment propagator of a linearisation.
#[derive(Clone, Debug)]
pub struct SecondMoments {
    n: usize,
    operator: DMatrix<f64>,
}

impl SecondMoments {
    /// Build `L` (size `n^2 × n^2`, column-major `vec`).
    pub fn new(linearisation: &Linearisation) -> Self {
        let a = linearisation.a_tilde.to_dmatrix();
        let n = a.nrows();
        let id = DMatrix::<f64>::identity(n, n);
        let mut op = id.kronecker(&a) + a.kronecker(&id);
        for b in &linearisation.noise {
            let bf = b.to_dmatrix();
            op += bf.kronecker(&bf);
        }
        SecondMoments { n, operator: op }
    }

    /// The operator `L` acting on `vec S`.
    pub fn operator(&self) -> &DMatrix<f64> {
        &self.operator
    }

    /// `S(t)` from `S(0)`.
    pub fn evolve(&self, s0: &DMatrix<f64>, t: f64) -> DMatrix<f64> {
        let n = self.n;
        let propagator = (&self.operator * t).exp();
        let v = DMatrix::from_column_slice(n * n, 1, s0.as_slice());
        let out = propagator * v;
        DMatrix::from_column_slice(n, n, out.as_slice())
    }

    /// `d/dt E|x_t|_P^2` at `t = 0` from a deterministic start `x_0`:
    /// `tr(P L(x_0 x_0^T))`, read off the moment equation itself (no finite
    /// differences), so it is independent of the engine's `Q`.
    pub fn rate_at_zero(&self, p: &DMatrix<f64>, x0: &[f64]) -> f64 {
        let n = self.n;
        let x = DMatrix::from_column_slice(n, 1, x0);
        let s0 = &x * x.transpose();
        let v = DMatrix::from_column_slice(n * n, 1, s0.as_slice());
        let ds = &self.operator * v;
        (p * DMatrix::from_column_slice(n, n, ds.as_slice())).trace()
    }

    /// `E|x_t|_P^2 = tr(P S(t))` for a deterministic start `x_0`.
    ///
    /// ```
    /// use exact::{Matrix, Rational};
    /// use generator::{Linearisation, SecondMoments};
    /// use nalgebra::DMatrix;
    /// let q = |n: i64| Rational::from_integer(n.into());
    /// // Geometric Brownian motion dx = x o dW (Stratonovich): E x_t^2 = e^{2t}.
    /// let b = Matrix::from_rows(&[vec![q(1)]]);
    /// let lin = Linearisation { a: Matrix::zeros(1, 1), a_tilde: b.scale(&Rational::new(1.into(), 2.into())), noise: vec![b] };
    /// let m = SecondMoments::new(&lin);
    /// let v = m.expected_norm(&DMatrix::identity(1, 1), &[1.0], 0.5);
    /// assert!((v - 1f64.exp()).abs() < 1e-12);
    /// ```
    pub fn expected_norm(&self, p: &DMatrix<f64>, x0: &[f64], t: f64) -> f64 {
        let x = DMatrix::from_column_slice(self.n, 1, x0);
        let s0 = &x * x.transpose();
        let s = self.evolve(&s0, t);
        (p * s).trace()
    }
}
