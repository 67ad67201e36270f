//! Symmetric banded matrices: product, Cholesky factorisation and solves.
//!
//! Written here rather than taken from a crate: nalgebra and faer offer dense
//! and general sparse Cholesky, but the y-operators of a spectral-element
//! discretisation are banded with a bandwidth of the element degree, and the
//! plain banded algorithm (O(n b^2) to factor, O(n b) to solve, no fill-in,
//! no symbolic phase) is twenty lines. The dense cross-checks in the tests
//! compare against nalgebra.

/// A symmetric `n x n` matrix with `a[i][j] = 0` for `|i - j| > bandwidth`,
/// stored by its lower band: `band[i * (b + 1) + d] = a[i][i - d]`.
#[derive(Clone, Debug, PartialEq)]
pub struct SymBanded {
    n: usize,
    b: usize,
    band: Vec<f64>,
}

/// Why a banded Cholesky failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BandedError {
    /// A pivot was not positive: the matrix is not (numerically) positive definite.
    #[error("not positive definite: pivot {index} is {value:e}")]
    NonPositivePivot {
        /// Row of the failing pivot.
        index: usize,
        /// Its value.
        value: f64,
    },
}

impl SymBanded {
    /// The zero matrix of size `n` and bandwidth `b`.
    pub fn zeros(n: usize, b: usize) -> Self {
        SymBanded { n, b, band: vec![0.0; n * (b + 1)] }
    }

    /// Size.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Bandwidth.
    pub fn bandwidth(&self) -> usize {
        self.b
    }

    /// Entry `(i, j)` (symmetric; zero outside the band).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let (i, j) = if i >= j { (i, j) } else { (j, i) };
        if i - j > self.b {
            0.0
        } else {
            self.band[i * (self.b + 1) + (i - j)]
        }
    }

    /// Add `v` to entries `(i, j)` and `(j, i)` (once if `i == j`).
    ///
    /// # Panics
    /// If `|i - j|` exceeds the bandwidth (a programming error).
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        let (i, j) = if i >= j { (i, j) } else { (j, i) };
        assert!(i - j <= self.b, "entry ({i}, {j}) outside bandwidth {}", self.b);
        self.band[i * (self.b + 1) + (i - j)] += v;
    }

    /// `y = A x`.
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        let b1 = self.b + 1;
        for (i, yi) in y.iter_mut().enumerate().take(self.n) {
            let row = &self.band[i * b1..(i + 1) * b1];
            let mut s = row[0] * x[i];
            for d in 1..=self.b.min(i) {
                s += row[d] * x[i - d];
            }
            *yi = s;
        }
        for i in 0..self.n {
            let row = &self.band[i * b1..(i + 1) * b1];
            for d in 1..=self.b.min(i) {
                y[i - d] += row[d] * x[i];
            }
        }
    }

    /// `A diag(w) A`, a symmetric matrix of bandwidth `2b`.
    pub fn sandwich(&self, w: &[f64]) -> Self {
        let b = self.b;
        let mut out = SymBanded::zeros(self.n, 2 * b);
        for i in 0..self.n {
            let jlo = i.saturating_sub(2 * b);
            for j in jlo..=i {
                // sum_k A[i][k] w[k] A[k][j], k within b of both.
                let klo = i.saturating_sub(b).max(j.saturating_sub(b));
                let khi = (j + b).min(self.n - 1);
                let mut s = 0.0;
                for k in klo..=khi {
                    s += self.get(i, k) * w[k] * self.get(k, j);
                }
                if s != 0.0 {
                    out.band[i * (2 * b + 1) + (i - j)] = s;
                }
            }
        }
        out
    }

    /// `self + other` (bandwidth the larger of the two).
    pub fn plus(&self, other: &SymBanded) -> Self {
        let b = self.b.max(other.b);
        let mut out = SymBanded::zeros(self.n, b);
        for i in 0..self.n {
            for d in 0..=b.min(i) {
                out.band[i * (b + 1) + d] = self.get(i, i - d) + other.get(i, i - d);
            }
        }
        out
    }

    /// `c * self`.
    pub fn times(&self, c: f64) -> Self {
        SymBanded { n: self.n, b: self.b, band: self.band.iter().map(|v| c * v).collect() }
    }

    /// The dense matrix (for tests and the final dense check).
    pub fn to_dense(&self) -> nalgebra::DMatrix<f64> {
        nalgebra::DMatrix::from_fn(self.n, self.n, |i, j| self.get(i, j))
    }

    /// Cholesky factor `A = C C^T`, `C` lower triangular with the same bandwidth.
    pub fn cholesky(&self) -> Result<BandedCholesky, BandedError> {
        let (n, b) = (self.n, self.b);
        let b1 = b + 1;
        // c[i * b1 + d] = C[i][i - d]
        let mut c = vec![0.0; n * b1];
        for i in 0..n {
            for j in i.saturating_sub(b)..=i {
                let mut s = self.band[i * b1 + (i - j)];
                for k in i.saturating_sub(b)..j {
                    s -= c[i * b1 + (i - k)] * c[j * b1 + (j - k)];
                }
                if i == j {
                    if s.is_nan() || s <= 0.0 || !s.is_finite() {
                        return Err(BandedError::NonPositivePivot { index: i, value: s });
                    }
                    c[i * b1] = s.sqrt();
                } else {
                    c[i * b1 + (i - j)] = s / c[j * b1];
                }
            }
        }
        Ok(BandedCholesky { n, b, c })
    }
}

/// A banded Cholesky factor `A = C C^T`.
#[derive(Clone, Debug)]
pub struct BandedCholesky {
    n: usize,
    b: usize,
    c: Vec<f64>,
}

impl BandedCholesky {
    /// Solve `C z = x` in place.
    pub fn solve_lower(&self, x: &mut [f64]) {
        let b1 = self.b + 1;
        for i in 0..self.n {
            let mut s = x[i];
            for d in 1..=self.b.min(i) {
                s -= self.c[i * b1 + d] * x[i - d];
            }
            x[i] = s / self.c[i * b1];
        }
    }

    /// Solve `C^T z = x` in place.
    pub fn solve_upper(&self, x: &mut [f64]) {
        let b1 = self.b + 1;
        for i in (0..self.n).rev() {
            let xi = x[i] / self.c[i * b1];
            x[i] = xi;
            for d in 1..=self.b.min(i) {
                x[i - d] -= self.c[i * b1 + d] * xi;
            }
        }
    }

    /// Solve `A z = x` in place.
    pub fn solve(&self, x: &mut [f64]) {
        self.solve_lower(x);
        self.solve_upper(x);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    fn example(n: usize, b: usize) -> SymBanded {
        let mut a = SymBanded::zeros(n, b);
        for i in 0..n {
            a.add(i, i, 4.0 + (i as f64).sin());
            for d in 1..=b.min(i) {
                a.add(i, i - d, 0.5 / (d as f64 + 1.0) * ((i * d) as f64).cos());
            }
        }
        a
    }

    #[test]
    fn banded_operations_match_dense_nalgebra() {
        let (n, b) = (23, 3);
        let a = example(n, b);
        let dense = a.to_dense();
        let x: Vec<f64> = (0..n).map(|i| ((i * 7 % 5) as f64) - 1.5).collect();
        let mut y = vec![0.0; n];
        a.mul_vec(&x, &mut y);
        let yd = &dense * DVector::from_vec(x.clone());
        for i in 0..n {
            assert!((y[i] - yd[i]).abs() < 1e-13 * (1.0 + yd[i].abs()));
        }
        // solve: residual check A z - x
        let f = a.cholesky().unwrap();
        let mut z = x.clone();
        f.solve(&mut z);
        let r = &dense * DVector::from_vec(z) - DVector::from_vec(x.clone());
        assert!(r.norm() < 1e-13 * (n as f64));
        // sandwich A diag(w) A against the dense product
        let w: Vec<f64> = (0..n).map(|i| 1.0 + 0.1 * i as f64).collect();
        let s = a.sandwich(&w).to_dense();
        let sd = &dense * DMatrix::from_diagonal(&DVector::from_vec(w)) * &dense;
        assert!((&s - &sd).norm() < 1e-12 * sd.norm());
    }

    #[test]
    fn cholesky_rejects_an_indefinite_matrix() {
        let mut a = example(10, 2);
        a.add(5, 5, -10.0);
        assert!(matches!(a.cholesky(), Err(BandedError::NonPositivePivot { index: 5, .. })));
    }
}
