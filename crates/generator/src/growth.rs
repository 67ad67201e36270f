//! The sharpest growth constant `Sigma^2` from the generalized eigenproblem.

use crate::pencil::{generalized_eigen, symmetric_eigen};
use casimir::Sign;
use exact::{binary_exponent, power_of_two, Matrix, Rational};
use nalgebra::{DMatrix, DVector};
use num_traits::Zero;

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
    /// `cond(sP) = lambda_max / lambda_min` in the algebra's coordinates
    /// (infinite when not resolved above round-off).
    pub condition_number: f64,
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
    /// The data or the result lie outside what doubles represent: entries
    /// spanning more than 2^1000 within `P` or `Q` (small ones would round
    /// to zero), or a `lambda_max` beyond the double range.
    #[error("Sigma^2 or the matrices P, Q lie outside the range of double precision ({detail}); rescale time or the noise amplitudes")]
    OutOfRange {
        /// What is out of range.
        detail: String,
    },
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
/// let g = growth_constant(&p, &qm, casimir::Sign::Positive).unwrap();
/// assert!((g.sigma2 - 3.0).abs() < 1e-14);
/// ```
pub fn growth_constant(p: &Matrix, q: &Matrix, sign: Sign) -> Result<GrowthConstant, GrowthError> {
    // Scale P by 2^-ep (ep even, so the direction rescales by 2^(ep/2)) and
    // Q by 2^-eq before rounding to doubles: the generalized eigenvalues
    // scale by 2^(eq - ep) exactly, and a Q of size 1e-321 (noise 1e-160) no
    // longer rounds to subnormals that carry no digits.
    let (p_lo, p_hi) = exponent_range(p);
    let (q_lo, q_hi) = exponent_range(q);
    for (name, lo, hi) in [("P", p_lo, p_hi), ("Q", q_lo, q_hi)] {
        if hi - lo > 1000 {
            return Err(GrowthError::OutOfRange {
                detail: format!("the entries of {name} span 2^{lo} to 2^{hi}: the small ones would round to zero"),
            });
        }
    }
    let ep = 2 * (p_hi.clamp(-2000, 2000) / 2);
    let eq = q_hi.clamp(-2000, 2000);
    if ep.abs() <= 600 && eq.abs() <= 600 {
        // Far from both ends of the double range: no scaling needed (the
        // common case, kept free of exact scalings).
        return growth_constant_normalised(p, q, sign);
    }
    let g = growth_constant_normalised(&p.scale(&power_of_two(-ep)), &q.scale(&power_of_two(-eq)), sign)?;
    let factor = |e: i64| -> f64 { 2f64.powi(e.clamp(-1100, 1100) as i32) };
    let scale = |x: f64| -> f64 {
        // 2^(eq - ep) may itself be out of range when x is not: apply it in two halves.
        let d = eq - ep;
        x * factor(d / 2) * factor(d - d / 2)
    };
    let largest = scale(g.largest_eigenvalue);
    let log2 = |x: f64| x.abs().log2() + (eq - ep) as f64;
    if !largest.is_finite() || (g.largest_eigenvalue > 0.0 && largest < f64::MIN_POSITIVE) {
        return Err(GrowthError::OutOfRange {
            detail: format!("lambda_max is about 2^{:.0}", log2(g.largest_eigenvalue)),
        });
    }
    let half = factor(-ep / 2);
    Ok(GrowthConstant {
        sigma2: largest.max(0.0),
        largest_eigenvalue: largest,
        eigenvalues: g.eigenvalues.iter().map(|x| scale(*x)).collect(),
        direction: g.direction.iter().map(|x| x * half).collect(),
        relative_residual: g.relative_residual,
        condition_number: g.condition_number,
    })
}

/// `floor(log2)` of the smallest and the largest non-zero entry in
/// magnitude (`(0, 0)` for the zero matrix).
fn exponent_range(m: &Matrix) -> (i64, i64) {
    let mut range: Option<(i64, i64)> = None;
    for i in 0..m.nrows() {
        for j in 0..m.ncols() {
            if let Some(e) = binary_exponent(&m[(i, j)]) {
                range = Some(range.map_or((e, e), |(lo, hi)| (lo.min(e), hi.max(e))));
            }
        }
    }
    range.unwrap_or((0, 0))
}

fn growth_constant_normalised(p: &Matrix, q: &Matrix, sign: Sign) -> Result<GrowthConstant, GrowthError> {
    let s = if !sign.is_positive() { -1.0 } else { 1.0 };
    let n = p.nrows();
    if n == 0 {
        return Ok(GrowthConstant {
            sigma2: 0.0,
            largest_eigenvalue: 0.0,
            eigenvalues: vec![],
            direction: vec![],
            relative_residual: 0.0,
            condition_number: 1.0,
        });
    }
    let pf = p.to_dmatrix() * s;
    let qf = q.to_dmatrix() * s;
    if pf.iter().chain(qf.iter()).any(|x| !x.is_finite()) {
        return Err(GrowthError::NonFinite);
    }
    let condition = condition_number(&pf);
    if condition <= 1e4 {
        // Well conditioned: a floating-point Cholesky factor loses at most
        // cond(P) eps ~ 2e-12 of |l_max|, far inside what `check` allows.
        if let Some(g) = float_pencil(&pf, &qf, condition) {
            return Ok(g);
        }
    }
    // The exact congruence sP = L D L^T, C = L^{-1} sQ L^{-T}: the
    // generalized eigenvalues are those of D^{-1/2} C D^{-1/2}, whose
    // entries are each computed from exact rationals with one rounding, so
    // the eigenvalues are accurate to round-off in |l_max| whatever the
    // condition of P (a floating-point Cholesky of P loses cond(P) eps).
    let (sp, sq) = if !sign.is_positive() {
        (p.scale(&Rational::from(-1)), q.scale(&Rational::from(-1)))
    } else {
        (p.clone(), q.clone())
    };
    let congruence = sp.congruence(&sq).ok_or(GrowthError::NotPositiveDefinite)?;
    let root_d: Vec<f64> = congruence.d.iter().map(|d| exact::rational_to_f64(d).sqrt()).collect();
    let scaled = |i: usize, j: usize| -> f64 {
        let c = &congruence.c[(i, j)];
        if c.is_zero() {
            return 0.0;
        }
        // c / (sqrt(d_i) sqrt(d_j)), one rounding per factor; when a factor
        // leaves the normal range, from the exact c^2 / (d_i d_j) instead.
        let direct = exact::rational_to_f64(c) / (root_d[i] * root_d[j]);
        if direct.is_finite() && direct.abs() >= f64::MIN_POSITIVE && root_d[i] * root_d[j] >= f64::MIN_POSITIVE {
            return direct;
        }
        let r = exact::rational_to_f64(&(c * c / (&congruence.d[i] * &congruence.d[j]))).sqrt();
        if c.is_negative() {
            -r
        } else {
            r
        }
    };
    let c = DMatrix::from_fn(n, n, |i, j| if i <= j { scaled(i, j) } else { scaled(j, i) });
    if c.iter().any(|x| !x.is_finite()) {
        return Err(GrowthError::NonFinite);
    }
    let eig = symmetric_eigen(c).ok_or(GrowthError::NoConvergence)?;
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
    let values: Vec<f64> = order.iter().map(|&i| eig.eigenvalues[i]).collect();
    let w = eig.eigenvectors.column(order[n - 1]).into_owned();
    // v = L^{-T} D^{-1/2} w has v^T sP v = w^T w = 1.
    let lt = congruence.l.to_dmatrix().transpose();
    let v = lt
        .solve_upper_triangular(&DVector::from_fn(n, |i, _| w[i] / root_d[i]))
        .ok_or(GrowthError::NotPositiveDefinite)?;
    assemble(values, v, &pf, &qf, condition)
}

/// The growth constant from the generalized eigenvalues (ascending) and a
/// unit-`P`-norm eigenvector `v` of the largest.
fn assemble(
    eigenvalues: Vec<f64>,
    v: DVector<f64>,
    pf: &DMatrix<f64>,
    qf: &DMatrix<f64>,
    condition: f64,
) -> Result<GrowthConstant, GrowthError> {
    let lmax = *eigenvalues.last().ok_or(GrowthError::NonFinite)?;
    if !lmax.is_finite() {
        return Err(GrowthError::NonFinite);
    }
    if v.iter().any(|x| !x.is_finite()) {
        return Err(GrowthError::NonFinite);
    }
    // Fix the sign: the first entry within 1e-6 of the largest modulus is positive.
    let max_abs = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let pivot = v.iter().find(|x| x.abs() >= max_abs * (1.0 - 1e-6)).copied().unwrap_or(1.0);
    let v = if pivot < 0.0 { -v } else { v };
    let residual = (qf * &v - pf * &v * lmax).norm();
    let scale = qf.norm() + lmax.abs() * pf.norm();
    Ok(GrowthConstant {
        sigma2: lmax.max(0.0),
        largest_eigenvalue: lmax,
        eigenvalues,
        direction: v.iter().copied().collect(),
        relative_residual: if scale > 0.0 { residual / scale } else { 0.0 },
        condition_number: condition,
    })
}

/// The generalized eigenproblem by a floating-point Cholesky factor of
/// `sP` (for a well-conditioned `sP`): `None` if anything fails.
fn float_pencil(pf: &DMatrix<f64>, qf: &DMatrix<f64>, condition: f64) -> Option<GrowthConstant> {
    let g = generalized_eigen(pf, qf)?;
    let v = g.vectors.column(g.values.len() - 1).into_owned();
    assemble(g.values, v, pf, qf, condition).ok()
}

/// `lambda_max / lambda_min` of a positive definite matrix in floating
/// point (Euclidean coordinates of the algebra's basis); infinite when the
/// smallest eigenvalue is not resolved above round-off.
pub fn condition_number(m: &DMatrix<f64>) -> f64 {
    if m.nrows() == 0 {
        return 1.0;
    }
    let Some(e) = symmetric_eigen(m.clone()) else {
        return f64::INFINITY;
    };
    let lo = e.eigenvalues.iter().fold(f64::INFINITY, |a, &b| a.min(b));
    let hi = e.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    if lo > hi * 1e-15 {
        hi / lo
    } else {
        f64::INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn diagonal(d: &[i64]) -> Matrix {
        let n = d.len();
        Matrix::from_fn(n, n, |i, j| if i == j { Rational::from(d[i]) } else { Rational::zero() })
    }

    /// Both paths (floating-point Cholesky for cond(P) <= 1e4, the exact
    /// congruence above) on diagonal pencils, whose generalized eigenvalues
    /// are q_i / p_i by hand, with a congruence by an integer matrix of
    /// determinant 1 so that neither path sees a diagonal matrix.
    #[test]
    fn both_paths_give_the_diagonal_quotients() {
        let t = Matrix::from_rows(&[
            vec![Rational::from(1), Rational::from(2), Rational::from(0)],
            vec![Rational::from(0), Rational::from(1), Rational::from(-3)],
            vec![Rational::from(0), Rational::from(0), Rational::from(1)],
        ]);
        let congruent = |m: &Matrix| t.transpose().mul(m).mul(&t);
        // (P, Q, expected eigenvalues ascending)
        for (p, q, expected) in [
            (diagonal(&[1, 4, 2]), diagonal(&[3, -4, 1]), [-1.0, 0.5, 3.0]),
            (diagonal(&[1, 100_000_000, 2]), diagonal(&[3, -400_000_000, 1]), [-4.0, 0.5, 3.0]),
        ] {
            let g = growth_constant(&congruent(&p), &congruent(&q), Sign::Positive).unwrap();
            for (got, want) in g.eigenvalues.iter().zip(expected) {
                assert!((got - want).abs() <= 1e-9 * 4.0, "{:?} vs {expected:?}", g.eigenvalues);
            }
            assert!((g.sigma2 - 3.0).abs() <= 1e-12 * 3.0);
            // v^T P v = 1 and Q v = 3 P v for the fastest direction.
            let (pf, qf) = (congruent(&p).to_dmatrix(), congruent(&q).to_dmatrix());
            let v = DVector::from_vec(g.direction.clone());
            assert!(((v.transpose() * &pf * &v)[(0, 0)] - 1.0).abs() <= 1e-9);
            assert!((&qf * &v - &pf * &v * 3.0).norm() <= 1e-6 * (qf.norm() + 3.0 * pf.norm()) * v.norm());
        }
    }
}
