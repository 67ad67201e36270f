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

    /// The quadratic form `M(t)` with `E|x_t|_P^2 = x_0^T M(t) x_0` for every
    /// start: the adjoint (backward Kolmogorov) evolution
    /// `dM/dt = A~^T M + M A~ + sum_i B_i^T M B_i`, `M(0) = P`, i.e.
    /// `vec M(t) = exp(L^T t) vec P`.
    pub fn form_at(&self, p: &DMatrix<f64>, t: f64) -> DMatrix<f64> {
        let n = self.n;
        let propagator = (self.operator.transpose() * t).exp();
        let v = DMatrix::from_column_slice(n * n, 1, p.as_slice());
        let m = propagator * v;
        let m = DMatrix::from_column_slice(n, n, m.as_slice());
        (&m + m.transpose()) * 0.5
    }

    /// The worst case over initial perturbations of unit `P`-norm:
    /// `max_{|x_0|_P = 1} E|x_t|_P^2 = lambda_max(M(t), P)` (`P` positive
    /// definite). `None` if `P` is not.
    ///
    /// ```
    /// use exact::{Matrix, Rational};
    /// use generator::{Linearisation, SecondMoments};
    /// use nalgebra::DMatrix;
    /// // dx = x o dW in 1D: E x_t^2 = x_0^2 e^{2t}, so the worst case is e^{2t}.
    /// let b = Matrix::from_rows(&[vec![Rational::from(1)]]);
    /// let lin = Linearisation { a: Matrix::zeros(1, 1), a_tilde: b.scale(&Rational::new_small(1, 2)), noise: vec![b] };
    /// let w = SecondMoments::new(&lin).worst_case_growth(&DMatrix::identity(1, 1), 0.5).unwrap();
    /// assert!((w - 1f64.exp()).abs() < 1e-12);
    /// ```
    pub fn worst_case_growth(&self, p: &DMatrix<f64>, t: f64) -> Option<f64> {
        let m = self.form_at(p, t);
        crate::pencil::generalized_eigen(p, &m)?.values.last().copied()
    }

    /// The moment Lyapunov exponent `lim (1/t) log E|x_t|^2` (for a generic
    /// start): the largest real part of the spectrum of `L` on symmetric
    /// matrices (the invariant subspace second moments live in). `None` if
    /// the eigenvalue iteration fails.
    pub fn lyapunov_exponent(&self) -> Option<f64> {
        let n = self.n;
        // Basis E_ij (i <= j) of the symmetric matrices; coordinates s_ij = S_ij.
        let pairs: Vec<(usize, usize)> = (0..n).flat_map(|i| (i..n).map(move |j| (i, j))).collect();
        let m = pairs.len();
        let mut l_sym = faer::Mat::<f64>::zeros(m, m);
        for (c, &(i, j)) in pairs.iter().enumerate() {
            let mut e = DMatrix::<f64>::zeros(n, n);
            e[(i, j)] = 1.0;
            e[(j, i)] = 1.0;
            let v = DMatrix::from_column_slice(n * n, 1, e.as_slice());
            let image = &self.operator * v;
            let image = DMatrix::from_column_slice(n, n, image.as_slice());
            for (r, &(a, b)) in pairs.iter().enumerate() {
                l_sym[(r, c)] = image[(a, b)];
            }
        }
        let ev = l_sym.eigenvalues().ok()?;
        Some(ev.iter().map(|z| z.re).fold(f64::NEG_INFINITY, f64::max))
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
