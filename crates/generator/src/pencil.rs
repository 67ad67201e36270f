//! The generalized symmetric eigenproblem `Q v = l P v` with `P ≻ 0`, in
//! floating point: the one helper behind the growth constant, the
//! optimiser and the family lower bound.
//!
//! With the Cholesky factor `P = L L^T`, the eigenvalues are those of the
//! symmetric `C = L^{-1} Q L^{-T}` and the eigenvectors `v = L^{-T} w` are
//! `P`-orthonormal. A floating-point factor loses about `cond(P) eps` of
//! `|l|`; where that matters (`cond(P) > 1e4`) the growth constant uses the
//! exact congruence instead (`growth.rs`).

use nalgebra::{DMatrix, SymmetricEigen};

/// Eigenvalues ascending, with `P`-orthonormal eigenvectors as the columns
/// of `vectors` in the same order.
#[derive(Clone, Debug)]
pub(crate) struct GeneralizedEigen {
    pub values: Vec<f64>,
    pub vectors: DMatrix<f64>,
}

/// Symmetric eigen-decomposition with an iteration limit (nalgebra's
/// default has none), `None` if it does not converge or the input is not
/// finite.
pub(crate) fn symmetric_eigen(m: DMatrix<f64>) -> Option<SymmetricEigen<f64, nalgebra::Dyn>> {
    if m.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let n = m.nrows();
    SymmetricEigen::try_new(m, f64::EPSILON, 1000 * (n + 1))
}

/// `Q v = l P v` by a Cholesky factor of `P`: `None` when `P` is not
/// numerically positive definite or anything is not finite.
pub(crate) fn generalized_eigen(p: &DMatrix<f64>, q: &DMatrix<f64>) -> Option<GeneralizedEigen> {
    let n = p.nrows();
    if p.iter().chain(q.iter()).any(|x| !x.is_finite()) {
        return None;
    }
    let l = p.clone().cholesky()?.l();
    let lq = l.solve_lower_triangular(q)?;
    let c = l.solve_lower_triangular(&lq.transpose())?;
    let eig = symmetric_eigen((&c + c.transpose()) * 0.5)?;
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
    let w = DMatrix::from_fn(n, n, |i, j| eig.eigenvectors[(i, order[j])]);
    let vectors = l.transpose().solve_upper_triangular(&w)?;
    Some(GeneralizedEigen { values: order.iter().map(|&i| eig.eigenvalues[i]).collect(), vectors })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `P = [[2, 1], [1, 2]]`, `Q = [[1, 0], [0, 0]]`: `det(Q - l P) =
    /// (1 - 2l)(-2l) - l^2 = 3l^2 - 2l`, so `l = 0` and `l = 2/3`; the
    /// eigenvectors are `P`-orthonormal and satisfy `Q v = l P v`.
    #[test]
    fn a_two_by_two_pencil() {
        let p = DMatrix::from_row_slice(2, 2, &[2.0, 1.0, 1.0, 2.0]);
        let q = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 0.0]);
        let g = generalized_eigen(&p, &q).unwrap();
        assert!((g.values[0] - 0.0).abs() < 1e-15 && (g.values[1] - 2.0 / 3.0).abs() < 1e-15, "{:?}", g.values);
        let gram = g.vectors.transpose() * &p * &g.vectors;
        assert!((gram - DMatrix::identity(2, 2)).norm() < 1e-14);
        for k in 0..2 {
            let v = g.vectors.column(k);
            assert!((&q * v - &p * v * g.values[k]).norm() < 1e-14);
        }
        // Not positive definite: no decomposition.
        assert!(generalized_eigen(&(-p), &q).is_none());
    }
}
