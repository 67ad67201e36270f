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

/// The eigenvalues of a symmetric matrix, ascending, without eigenvectors,
/// by the cyclic Jacobi method; `None` if anything is not finite or the
/// sweeps do not converge.
///
/// Written here rather than taken from a library because the numeric level
/// calls it on matrices of dimension at most a few dozen, where the set-up
/// of faer's or nalgebra's tridiagonal solvers costs more than the
/// arithmetic (faer's took 11k instructions on a 6x6 matrix, this about a
/// fifth of that), and nalgebra's eigenvalues-only routine has no
/// iteration limit. Jacobi converges quadratically and is accurate to a
/// small multiple of `eps |M|`; at most 60 sweeps are made (a 64x64 matrix
/// needs about 10).
pub(crate) fn symmetric_eigenvalues(m: &DMatrix<f64>) -> Option<Vec<f64>> {
    let n = m.nrows();
    if m.iter().any(|x| !x.is_finite()) {
        return None;
    }
    // Scaled by a power of two near its largest entry (exact unless an
    // entry becomes subnormal), so that the sums of squares below neither
    // overflow nor underflow; the eigenvalues are scaled back at the end.
    let top = m.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    if top == 0.0 {
        return Some(vec![0.0; n]);
    }
    let e = top.log2().round() as i32;
    let (down, up) = (2f64.powi(-e), 2f64.powi(e));
    let mut a = (m + m.transpose()) * (0.5 * down);
    let norm = a.norm();
    let mut converged = n < 2;
    for _ in 0..60 {
        let off: f64 = (0..n).flat_map(|i| (0..i).map(move |j| (i, j))).map(|(i, j)| a[(i, j)] * a[(i, j)]).sum();
        if off.sqrt() <= 1e-17 * norm {
            converged = true;
            break;
        }
        for p in 0..n {
            for q in (p + 1)..n {
                let apq = a[(p, q)];
                if apq.abs() <= 1e-18 * norm {
                    // Negligible: below the accuracy of every eigenvalue.
                    a[(p, q)] = 0.0;
                    a[(q, p)] = 0.0;
                    continue;
                }
                // The rotation that zeroes a_pq (Golub & Van Loan, Alg. 8.5.1).
                let theta = (a[(q, q)] - a[(p, p)]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let (akp, akq) = (a[(k, p)], a[(k, q)]);
                    a[(k, p)] = c * akp - s * akq;
                    a[(k, q)] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[(p, k)], a[(q, k)]);
                    a[(p, k)] = c * apk - s * aqk;
                    a[(q, k)] = s * apk + c * aqk;
                }
                // The rotation zeroes a_pq; round-off would leave eps |a| there.
                a[(p, q)] = 0.0;
                a[(q, p)] = 0.0;
            }
        }
    }
    if !converged {
        return None;
    }
    let mut values: Vec<f64> = (0..n).map(|i| a[(i, i)] * up).collect();
    values.sort_by(f64::total_cmp);
    values.iter().all(|x| x.is_finite()).then_some(values)
}

/// `lambda_max(Q, P)` alone, by a Cholesky factor of `P`: `None` when `P`
/// is not numerically positive definite or anything is not finite.
pub(crate) fn largest_generalized_eigenvalue(p: &DMatrix<f64>, q: &DMatrix<f64>) -> Option<f64> {
    if p.nrows() == 0 || p.iter().chain(q.iter()).any(|x| !x.is_finite()) {
        return None;
    }
    let l = p.clone().cholesky()?.l();
    let lq = l.solve_lower_triangular(q)?;
    let c = l.solve_lower_triangular(&lq.transpose())?;
    symmetric_eigenvalues(&((&c + c.transpose()) * 0.5))?.last().copied()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Jacobi eigenvalues agree with nalgebra's symmetric eigensolver
    /// (an independent method: Householder tridiagonalisation and implicit
    /// QR) on random symmetric matrices of dimension 1 to 12, and on
    /// matrices with repeated and zero eigenvalues.
    #[test]
    fn jacobi_eigenvalues_agree_with_nalgebra() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        for n in 1..=12 {
            for _ in 0..20 {
                let m =
                    DMatrix::from_fn(n, n, |_, _| rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-3..4)));
                let m = (&m + m.transpose()) * 0.5;
                let ours = symmetric_eigenvalues(&m).unwrap();
                let mut theirs: Vec<f64> = m.clone().symmetric_eigen().eigenvalues.iter().copied().collect();
                theirs.sort_by(f64::total_cmp);
                let scale = m.norm();
                for (a, b) in ours.iter().zip(&theirs) {
                    assert!((a - b).abs() <= 1e-13 * scale, "n = {n}: {ours:?} vs {theirs:?}");
                }
            }
        }
        // diag(2, 2, 0) in a rotated basis; the zero matrix; non-finite input.
        let r = nalgebra::Rotation3::from_euler_angles(0.3, -1.1, 2.0).into_inner();
        let m = DMatrix::from_fn(3, 3, |i, j| r[(i, j)]);
        let d = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![2.0, 2.0, 0.0]));
        let e = symmetric_eigenvalues(&(&m * d * m.transpose())).unwrap();
        assert!(e[0].abs() < 1e-15 && (e[1] - 2.0).abs() < 1e-15 && (e[2] - 2.0).abs() < 1e-15, "{e:?}");
        assert_eq!(symmetric_eigenvalues(&DMatrix::zeros(4, 4)), Some(vec![0.0; 4]));
        // [[s, 2s], [2s, s]] has eigenvalues -s and 3s at every scale (the
        // sums of squares would overflow at 1e160 and underflow at 1e-165).
        for s in [1e160, 1e-165, 1e300, 1e-300] {
            let e = symmetric_eigenvalues(&DMatrix::from_row_slice(2, 2, &[s, 2.0 * s, 2.0 * s, s])).unwrap();
            assert!((e[0] + s).abs() <= 1e-14 * s && (e[1] - 3.0 * s).abs() <= 1e-14 * s, "{s}: {e:?}");
        }
        assert_eq!(symmetric_eigenvalues(&DMatrix::from_element(2, 2, f64::NAN)), None);
    }

    /// `lambda_max` of the pencil below (2/3, derived there) from the
    /// eigenvalues-only path.
    #[test]
    fn largest_generalized_eigenvalue_of_a_two_by_two_pencil() {
        let p = DMatrix::from_row_slice(2, 2, &[2.0, 1.0, 1.0, 2.0]);
        let q = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 0.0]);
        assert!((largest_generalized_eigenvalue(&p, &q).unwrap() - 2.0 / 3.0).abs() < 1e-15);
        assert_eq!(largest_generalized_eigenvalue(&(-p), &q), None);
    }

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
