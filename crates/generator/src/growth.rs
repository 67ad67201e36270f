//! The sharpest growth constant `Sigma^2` from the generalized eigenproblem.

use exact::Matrix;
use nalgebra::{DVector, SymmetricEigen};

/// The result of the generalized symmetric eigenproblem `Q v = l P v`.
#[derive(Clone, Debug, PartialEq)]
pub struct GrowthConstant {
    /// `Sigma^2 = max(0, l_max)`, the smallest constant with
    /// `x^T (sQ) x <= Sigma^2 x^T (sP) x` for all `x` (`s` the sign of `P`).
    pub sigma2: f64,
    /// The largest generalized eigenvalue before flooring at 0.
    pub largest_eigenvalue: f64,
    /// All generalized eigenvalues, ascending.
    pub eigenvalues: Vec<f64>,
    /// A unit-`P`-norm eigenvector for `l_max`: the perturbation that grows
    /// fastest at `t = 0` (sign fixed so its largest entry is positive; when
    /// `l_max` is multiple, any vector of its eigenspace).
    pub direction: Vec<f64>,
    /// Residual `|Q v - l P v| / (|Q| + |l| |P|)` of that eigenpair.
    pub relative_residual: f64,
}

/// Why the eigenproblem could not be solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum GrowthError {
    /// `sP` is not numerically positive definite (Cholesky failed).
    #[error("the second variation (times its sign) is not positive definite in floating point; Cholesky failed")]
    NotPositiveDefinite,
    /// A non-finite number appeared.
    #[error("non-finite value in the generalized eigenproblem")]
    NonFinite,
    /// The symmetric eigen-iteration did not converge.
    #[error("the symmetric eigenvalue iteration did not converge")]
    NoConvergence,
}

/// `Sigma^2 = max(0, lambda_max(sQ, sP))` with `s = sign` (+1 or -1).
///
/// Reduced to a standard symmetric problem with the Cholesky factor of
/// `sP = L L^T`: the eigenvalues of `L^{-1} (sQ) L^{-T}`.
///
/// ```
/// use exact::{Matrix, Rational};
/// use generator::growth_constant;
/// let q = |n: i64| Rational::from_integer(n.into());
/// let p = Matrix::from_rows(&[vec![q(1), q(0)], vec![q(0), q(4)]]);
/// let qm = Matrix::from_rows(&[vec![q(3), q(0)], vec![q(0), q(-4)]]);
/// let g = growth_constant(&p, &qm, 1).unwrap();
/// assert!((g.sigma2 - 3.0).abs() < 1e-14);
/// ```
pub fn growth_constant(p: &Matrix, q: &Matrix, sign: i8) -> Result<GrowthConstant, GrowthError> {
    let s = if sign < 0 { -1.0 } else { 1.0 };
    let pf = p.to_dmatrix() * s;
    let qf = q.to_dmatrix() * s;
    if pf.iter().chain(qf.iter()).any(|x| !x.is_finite()) {
        return Err(GrowthError::NonFinite);
    }
    let n = pf.nrows();
    if n == 0 {
        return Ok(GrowthConstant {
            sigma2: 0.0,
            largest_eigenvalue: 0.0,
            eigenvalues: vec![],
            direction: vec![],
            relative_residual: 0.0,
        });
    }
    let chol = pf.clone().cholesky().ok_or(GrowthError::NotPositiveDefinite)?;
    let l = chol.l();
    // C = L^{-1} Q L^{-T}
    let linv_q = l.solve_lower_triangular(&qf).ok_or(GrowthError::NotPositiveDefinite)?;
    let c_t = l.solve_lower_triangular(&linv_q.transpose()).ok_or(GrowthError::NotPositiveDefinite)?;
    let c = (&c_t + c_t.transpose()) * 0.5;
    let eig = SymmetricEigen::try_new(c, f64::EPSILON, 1000 * (n + 1)).ok_or(GrowthError::NoConvergence)?;
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
    let eigenvalues: Vec<f64> = order.iter().map(|&i| eig.eigenvalues[i]).collect();
    let imax = *order.last().expect("n > 0");
    let lmax = eig.eigenvalues[imax];
    if !lmax.is_finite() {
        return Err(GrowthError::NonFinite);
    }
    // v = L^{-T} w has v^T sP v = 1.
    let w: DVector<f64> = eig.eigenvectors.column(imax).into_owned();
    let v = l.transpose().solve_upper_triangular(&w).ok_or(GrowthError::NotPositiveDefinite)?;
    // Fix the sign: the first entry within 1e-6 of the largest modulus is positive.
    let max_abs = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let pivot = v.iter().find(|x| x.abs() >= max_abs * (1.0 - 1e-6)).copied().unwrap_or(1.0);
    let v = if pivot < 0.0 { -v } else { v };
    let residual = (&qf * &v - &pf * &v * lmax).norm();
    let scale = qf.norm() + lmax.abs() * pf.norm();
    let relative_residual = if scale > 0.0 { residual / scale } else { 0.0 };
    Ok(GrowthConstant {
        sigma2: lmax.max(0.0),
        largest_eigenvalue: lmax,
        eigenvalues,
        direction: v.iter().copied().collect(),
        relative_residual,
    })
}
