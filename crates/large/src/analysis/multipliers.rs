//! Steps 1 and 2 in floating point: the derivatives at the equilibrium, and
//! the multipliers by the SVD of the gradient matrix `G = U S V^T`, with the
//! orthonormal frame `U = [W Z]` it gives (`W` the range of `G`, `Z` its
//! complement `ker G^T`).

use super::numerical;
use crate::system::LargeSystem;
use crate::LargeError;
use exact::Rational;
use nalgebra::{DMatrix, DVector};
use numerics::dense::product;
use std::collections::BTreeMap;

/// `Dh`, `D^2h` and `G` at the equilibrium, in doubles.
pub(super) struct Derivatives {
    /// `mu_e`.
    pub(super) mu: Vec<f64>,
    /// `Dh(mu_e)`.
    pub(super) dh: DVector<f64>,
    /// `D^2h(mu_e)`, sparse (one entry per unordered pair).
    pub(super) hh: BTreeMap<(usize, usize), f64>,
    /// `G` (`n x r`): the gradients of the Casimirs, then of the first
    /// integrals, as columns.
    pub(super) g: DMatrix<f64>,
}

fn to_f64(v: &[Rational]) -> Vec<f64> {
    v.iter().map(exact::rational_to_f64).collect()
}

/// The dense vector of length `n` with the (rounded) entries of a sparse
/// exact gradient.
fn sparse_gradient(n: usize, g: BTreeMap<usize, Rational>) -> DVector<f64> {
    let mut v = DVector::zeros(n);
    for (i, x) in g {
        v[i] = exact::rational_to_f64(&x);
    }
    v
}

/// `Dh(mu_e)`, `D^2h(mu_e)` and `G = [DC_j(mu_e)]`: the gradients exactly
/// then rounded, the Hessian in doubles; an error when one is not finite.
pub(super) fn derivatives(system: &LargeSystem) -> Result<Derivatives, LargeError> {
    let n = system.dim();
    let mu_q = system.equilibrium();
    let mu = to_f64(mu_q);
    let dh = sparse_gradient(n, system.hamiltonian().gradient_at(mu_q));
    let hh = system.hamiltonian().hessian_at_f64(&mu);
    let conserved = system.conserved();
    let r = conserved.len();
    let mut g = DMatrix::zeros(n, r);
    for (j, k) in conserved.iter().enumerate() {
        g.set_column(j, &sparse_gradient(n, k.gradient_at(mu_q)));
    }
    if dh.iter().chain(g.iter()).chain(hh.values()).any(|x| !x.is_finite()) {
        return Err(numerical("a derivative at the equilibrium is not finite in double precision: rescale the system"));
    }
    Ok(Derivatives { mu, dh, hh, g })
}

/// The least-squares multipliers `G lambda = -Dh` and the SVD they come from.
pub(super) struct Multipliers {
    /// The singular values of `G`, decreasing.
    pub(super) s_values: Vec<f64>,
    /// The numerical rank of `G` (singular values above `1e-12` of the largest).
    pub(super) rank: usize,
    /// The left singular vectors (`n x n`): the frame `[W Z]`.
    pub(super) u: DMatrix<f64>,
    /// The right singular vectors (`r x r`); past the rank, the null space of `G`.
    pub(super) v: DMatrix<f64>,
    /// The minimum-norm solution `lambda_p` (Casimirs, then first integrals).
    pub(super) lambda: DVector<f64>,
    /// `|G lambda + Dh| / |Dh|` (the absolute residual when `Dh = 0`).
    pub(super) relative_residual: f64,
    /// `ker G^T` (`n x (n - rank)`, orthonormal).
    pub(super) z: DMatrix<f64>,
    /// The range of `G` (`n x rank`, orthonormal).
    pub(super) w: DMatrix<f64>,
}

impl Multipliers {
    /// `lambda_p = -sum_{i < rank} (u_i . Dh / s_i) v_i` from the SVD
    /// `G = U S V^T`, with its relative residual and the frame `U = [W Z]`.
    pub(super) fn by_svd(d: &Derivatives) -> Result<Multipliers, LargeError> {
        let (g, dh) = (&d.g, &d.dh);
        let (n, r) = g.shape();
        let gf = faer::Mat::<f64>::from_fn(n, r, |i, j| g[(i, j)]);
        let svd = gf.svd().map_err(|_| numerical("the SVD of the gradient matrix"))?;
        let s_values: Vec<f64> = (0..r.min(n)).map(|i| svd.S()[i]).collect();
        let top = s_values.iter().fold(0.0f64, |a, x| a.max(*x));
        let rank = s_values.iter().filter(|&&x| x > 1e-12 * top && x > 0.0).count();
        let u = DMatrix::from_fn(n, n, |i, j| svd.U()[(i, j)]);
        let v = DMatrix::from_fn(r, r, |i, j| svd.V()[(i, j)]);
        let mut lambda = DVector::zeros(r);
        for i in 0..rank {
            let coefficient = -u.column(i).dot(dh) / s_values[i];
            lambda += v.column(i) * coefficient;
        }
        let residual = (g * &lambda + dh).norm();
        let relative_residual = if dh.norm() > 0.0 { residual / dh.norm() } else { residual };
        let z = u.columns(rank, n - rank).into_owned();
        let w = u.columns(0, rank).into_owned();
        Ok(Multipliers { s_values, rank, u, v, lambda, relative_residual, z, w })
    }

    /// `sym(Z^T M Z)`: `M` restricted to `ker G^T`.
    pub(super) fn restrict(&self, m: &DMatrix<f64>) -> DMatrix<f64> {
        let r = product(&self.z.transpose(), &product(m, &self.z));
        (&r + r.transpose()) * 0.5
    }

    /// `sym(U^T M U)`: `M` in the frame, by one congruence.
    pub(super) fn frame_coordinates(&self, m: &DMatrix<f64>) -> DMatrix<f64> {
        let t = product(&self.u.transpose(), &product(m, &self.u));
        (&t + t.transpose()) * 0.5
    }

    /// The blocks `(Z^T M Z, Z^T M W, W^T M W)` of a matrix `t = U^T M U` in
    /// the frame.
    pub(super) fn blocks(&self, t: &DMatrix<f64>) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
        // U = [W Z]: the range of G first (rank columns), then ker G^T.
        let (n, rank) = (self.u.nrows(), self.rank);
        let nz = n - rank;
        (
            t.view((rank, rank), (nz, nz)).into_owned(),
            t.view((rank, 0), (nz, rank)).into_owned(),
            t.view((0, 0), (rank, rank)).into_owned(),
        )
    }
}
