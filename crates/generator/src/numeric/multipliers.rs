//! Step 2 of the numeric level: the multipliers `G lambda = -Dh` and the
//! orthonormal frame `[Z W]` (`Z` spanning `ker G^T`, `W` the range of
//! `G`), by the SVD of the gradient matrix `G` (n x m); whether they exist
//! and the rank of `G` decided exactly (step 1's exact gradients).

use super::derivatives::Derivatives;
use super::frobenius;
use casimir::System;
use exact::Rational;
use nalgebra::{DMatrix, DVector};

/// The multipliers and the frame, with what bounds their accuracy.
pub(super) struct Frame {
    /// The multipliers `lambda` (Casimirs, then first integrals).
    pub(super) lambda: DVector<f64>,
    /// An orthonormal basis of `ker G^T`.
    pub(super) z: DMatrix<f64>,
    /// An orthonormal basis of the range of `G`.
    pub(super) w: DMatrix<f64>,
    /// The angle within which the computed range of `G` lies of the exact one.
    pub(super) theta: f64,
    /// `cond(G)` for the columns of unit length.
    pub(super) g_condition: f64,
    /// The lengths `|g_j|` of the rounded gradients.
    pub(super) lengths: Vec<f64>,
}

/// The multipliers and the frame; `None` when no multipliers exist.
/// Whether they exist and the rank of `G` are decided exactly.
pub(super) fn multipliers_and_frame(system: &System, d: &Derivatives) -> Result<Option<Frame>, &'static str> {
    let n = system.dim();
    let m = d.conserved.len();
    // (None: no multipliers exist.) The scope checks come first, so that a
    // system outside the scope costs nothing more here.
    if m == 0 {
        return Ok(d.dh.iter().all(|x| *x == 0.0).then(|| Frame {
            lambda: DVector::zeros(0),
            z: DMatrix::identity(n, n),
            w: DMatrix::zeros(n, 0),
            theta: 0.0,
            g_condition: 1.0,
            lengths: vec![],
        }));
    }
    // The gradients exactly (cheap at mu_e): whether multipliers exist
    // and the rank of G are decided in rational arithmetic, as the exact
    // pipeline decides them. (Floating point cannot tell a residual
    // `G lambda + Dh` of 1e-16 from rounding, nor a zero gradient from
    // one computed as 1e-17: reviews found false `stable` verdicts from
    // both.)
    let exact_g: Vec<Vec<Rational>> =
        system.casimirs().iter().chain(system.first_integrals()).map(|p| p.gradient_at(system.equilibrium())).collect();
    let g_matrix = exact::Matrix::from_fn(n, m, |i, j| exact_g[j][i].clone());
    let rank = g_matrix.rank();
    let with_dh = exact::Matrix::from_fn(n, m + 1, |i, j| {
        if j < m {
            exact_g[j][i].clone()
        } else {
            system.hamiltonian_gradient()[i].clone()
        }
    });
    if with_dh.rank() > rank {
        // Dh is not in the span of the conserved gradients: no multipliers.
        Ok(None)
    } else if rank < m {
        Err("free multipliers (a family to optimise over)")
    } else {
        svd_frame(&exact_g, &d.dh, rank).map(Some)
    }
}

/// The least-squares multipliers `lambda = -G^+ Dh` and the frame from the
/// SVD `G = U S V^T` of the rounded gradients (columns of unit length):
/// `Z`, `W` the last `n - rank` and the first `rank` columns of `U`.
fn svd_frame(exact_g: &[Vec<Rational>], dh: &[f64], rank: usize) -> Result<Frame, &'static str> {
    let (n, m) = (dh.len(), exact_g.len());
    let dh_v = DVector::from_column_slice(dh);
    // Columns of unit length: the range and the multipliers'
    // combination do not depend on how the conserved quantities
    // are scaled. Each column is the rounded exact gradient.
    let columns: Vec<Vec<f64>> = exact_g.iter().map(|g| g.iter().map(exact::rational_to_f64).collect()).collect();
    let lengths: Vec<f64> = columns.iter().map(|g| frobenius(g)).collect();
    let g = DMatrix::from_fn(n, m, |i, j| columns[j][i] / lengths[j]);
    // The relative accuracy of the unit columns (rounding to doubles
    // and the normalisation) and of the SVD.
    let accuracy = 64.0 * (n as f64 + 4.0) * f64::EPSILON;
    let gf = faer::Mat::<f64>::from_fn(n, m, |i, j| g[(i, j)]);
    let svd = gf.svd().map_err(|_| "the SVD of the gradient matrix")?;
    let s: Vec<f64> = (0..m.min(n)).map(|i| svd.S()[i]).collect();
    let top = s.iter().fold(0.0f64, |a, x| a.max(*x));
    // Independent exactly, but nearly dependent in floating point:
    // the computed ker G^T would be too far off the exact one.
    if s[m - 1].is_nan() || s[m - 1] <= 1e-7 * top {
        return Err("the conserved gradients are independent but nearly dependent (cond(G) above 1e7)");
    }
    let u = DMatrix::from_fn(n, n, |i, j| svd.U()[(i, j)]);
    let v = DMatrix::from_fn(m, m, |i, j| svd.V()[(i, j)]);
    let mut lambda = DVector::zeros(m);
    for i in 0..rank {
        lambda += v.column(i) * (-u.column(i).dot(&dh_v) / s[i]);
    }
    let residual = (&g * &lambda + &dh_v).norm();
    if residual > 1e-6 * dh_v.norm() {
        // Exactly in the span, yet not solved in floating point.
        return Err("the multipliers are not resolved in floating point");
    }
    for (l, len) in lambda.iter_mut().zip(&lengths) {
        *l /= len;
    }
    // The computed range of G (and its complement ker G^T) is within
    // the angle theta of the exact one (Wedin: the columns' error
    // over the smallest singular value, the columns of unit length).
    let theta = 2.0 * (m as f64).sqrt() * accuracy / s[m - 1];
    let frame = (u.columns(rank, n - rank).into_owned(), u.columns(0, rank).into_owned());
    Ok(Frame { lambda, z: frame.0, w: frame.1, theta, g_condition: top / s[m - 1], lengths })
}
