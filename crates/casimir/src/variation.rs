//! First variation (the multiplier family) and second variation at `mu_e`.

use crate::system::System;
use exact::{Matrix, Rational};
use nalgebra::DMatrix;

/// The affine family of multipliers `lambda = particular + sum_i t_i directions[i]`
/// solving `Dh(mu_e) + sum_j lambda_j DK_j(mu_e) = 0`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MultiplierFamily {
    /// One solution.
    pub particular: Vec<Rational>,
    /// A basis of the free directions (null space of `G`).
    pub directions: Vec<Vec<Rational>>,
}

impl MultiplierFamily {
    /// The multipliers at family parameters `t`.
    ///
    /// # Panics
    /// If `t` has the wrong length.
    pub fn at(&self, t: &[Rational]) -> Vec<Rational> {
        assert_eq!(t.len(), self.directions.len(), "family parameter count");
        let mut lambda = self.particular.clone();
        for (ti, d) in t.iter().zip(&self.directions) {
            for (l, di) in lambda.iter_mut().zip(d) {
                *l += ti * di;
            }
        }
        lambda
    }
}

/// Everything needed to form `P = D^2h + sum_j lambda_j D^2K_j + G M G^T` at
/// `mu_e`, exactly.
#[derive(Clone, Debug)]
pub struct SecondVariation {
    /// `Dh(mu_e)`.
    pub gradient_h: Vec<Rational>,
    /// `D^2h(mu_e)`.
    pub hessian_h: Matrix,
    /// `G`: column `j` is `DK_j(mu_e)` (`n × r`).
    pub gradients: Matrix,
    /// `D^2K_j(mu_e)`.
    pub hessians: Vec<Matrix>,
    /// The multipliers.
    pub family: MultiplierFamily,
    /// `Z`: columns form a basis of `ker G^T` (`n × (n - rank G)`), with
    /// every coefficient at most 1 in magnitude
    /// ([`Matrix::bounded_null_space`]), so `Z^T Z` has its eigenvalues in
    /// `[1, 1 + rank G * (n - rank G)]`. The plain echelon basis can be badly
    /// scaled and nearly parallel (`(-1/a, 1, 0)`, `(-1/a, 0, 1)` for
    /// `G = (a, 1, 1)`), and a form restricted with it, rounded to doubles,
    /// loses the `O(1)` part of the restricted Hessian. With this basis
    /// [`Self::orthonormal`] gives the restricted forms in orthonormal
    /// coordinates to double precision, whatever the scale of `G`; the
    /// basis does not change when a conserved quantity is rescaled (or the
    /// conserved quantities are recombined).
    pub kernel: Matrix,
    /// Indices of linearly independent columns of `G` spanning its range.
    pub range_columns: Vec<usize>,
    /// `Y`, `(Y^T Y)^{-1}` and `W = Y (Y^T Y)^{-1}` (see
    /// [`Self::complement`]), computed once: the search, the Schur bound
    /// and the optimiser each need them.
    frame: Frame,
}

/// The fixed parts of the frame `[Z W]`.
#[derive(Clone, Debug)]
struct Frame {
    y: Matrix,
    gram_inverse: Matrix,
    w: Matrix,
    z_transpose: Matrix,
    /// `L^{-1}`, `L L^T` the Cholesky factorisation of `Z^T Z` (formed
    /// exactly, then rounded): `Z L^{-T}` is orthonormal. Its norm is at
    /// most 1, as `Z^T Z >= I`.
    kernel_whitening: DMatrix<f64>,
}

impl SecondVariation {
    pub(crate) fn new(system: &System) -> Option<Self> {
        let n = system.dim();
        let mu = system.equilibrium();
        let gradient_h = system.hamiltonian_gradient().to_vec();
        let hessian_h = system.hamiltonian_hessian().clone();
        let conserved = system.conserved();
        let columns: Vec<Vec<Rational>> = conserved.iter().map(|(_, k)| k.gradient_at(mu)).collect();
        let gradients = Matrix::from_columns(n, &columns);
        let hessians = conserved.iter().map(|(_, k)| Matrix::from_rows(&k.hessian_at(mu))).collect();
        let minus_grad: Vec<Rational> = gradient_h.iter().map(|g| -g.clone()).collect();
        let solution = gradients.solve_affine(&minus_grad)?;
        let family = MultiplierFamily { particular: solution.particular, directions: solution.directions };
        let kernel_vectors = gradients.transpose().bounded_null_space();
        let kernel = Matrix::from_columns(n, &kernel_vectors);
        let range_columns = gradients.pivot_columns();
        let y = Matrix::from_fn(n, range_columns.len(), |i, j| gradients[(i, range_columns[j])].clone());
        let gram_inverse = y.transpose().mul(&y).inverse().expect("independent columns have an invertible Gram matrix");
        let w = y.mul(&gram_inverse);
        let z_transpose = kernel.transpose();
        // Z^T Z >= I is well conditioned (see `kernel`): its Cholesky factor
        // in doubles cannot fail but for a kernel of dimension near 1e8.
        let k = kernel.ncols();
        let kernel_whitening = z_transpose
            .mul(&kernel)
            .to_dmatrix()
            .cholesky()
            .and_then(|c| c.l().try_inverse())
            .unwrap_or_else(|| DMatrix::identity(k, k));
        let frame = Frame { y, gram_inverse, w, z_transpose, kernel_whitening };
        Some(SecondVariation { gradient_h, hessian_h, gradients, hessians, family, kernel, range_columns, frame })
    }

    /// Dimension of the algebra.
    pub fn dim(&self) -> usize {
        self.hessian_h.nrows()
    }

    /// Number of conserved quantities.
    pub fn num_conserved(&self) -> usize {
        self.hessians.len()
    }

    /// `D^2h + sum_j lambda_j D^2K_j`.
    pub fn base(&self, multipliers: &[Rational]) -> Matrix {
        assert_eq!(multipliers.len(), self.hessians.len());
        let mut p = self.hessian_h.clone();
        for (l, hk) in multipliers.iter().zip(&self.hessians) {
            p.add_scaled_assign(l, hk);
        }
        p
    }

    /// `D^2h + sum_j lambda_j D^2K_j + G M G^T`.
    pub fn second_variation(&self, multipliers: &[Rational], m: &Matrix) -> Matrix {
        let g = &self.gradients;
        self.base(multipliers).add(&g.mul(m).mul(&g.transpose()))
    }

    /// The restricted Hessian `Z^T (D^2h + sum_j lambda_j D^2K_j) Z` on `ker G^T`.
    pub fn restricted(&self, multipliers: &[Rational]) -> Matrix {
        self.frame.z_transpose.mul(&self.base(multipliers)).mul(&self.kernel)
    }

    /// A form on `ker G^T` given in the basis `Z` (such as
    /// [`Self::restricted`]), in orthonormal coordinates of `ker G^T`, in
    /// floating point: `L^{-1} R L^{-T}` (`Z^T Z = L L^T`), symmetrised. Its
    /// eigenvalues are the Euclidean Rayleigh quotients of the form on
    /// `ker G^T`: they do not depend on the basis, nor on how the conserved
    /// quantities are scaled. `R` is formed exactly and rounded once, and
    /// `Z` is well conditioned (see [`Self::kernel`]), so the result is
    /// accurate to about `(1 + rank G * k) * k` units of the last place
    /// relative to `|R|` (`k` the dimension of `ker G^T`).
    ///
    /// # Panics
    /// If `r` is not `k × k`.
    pub fn orthonormal(&self, r: &Matrix) -> DMatrix<f64> {
        let linv = &self.frame.kernel_whitening;
        let k = linv.nrows();
        assert_eq!((r.nrows(), r.ncols()), (k, k), "a form on ker G^T");
        let m = linv * r.to_dmatrix() * linv.transpose();
        (&m + m.transpose()) * 0.5
    }

    /// `Y`: the independent conserved gradients (columns
    /// [`Self::range_columns`] of `G`), `n × rk`.
    pub fn independent_gradients(&self) -> &Matrix {
        &self.frame.y
    }

    /// `(Y^T Y)^{-1}`.
    pub fn gram_inverse(&self) -> &Matrix {
        &self.frame.gram_inverse
    }

    /// `W = Y (Y^T Y)^{-1}`, so that `Y^T W = I`: with the kernel `Z`, the
    /// frame `T = [Z W]` splits a perturbation into its part along the
    /// level set (`a`) and its conserved-quantity increments `b = Y^T v`,
    /// and `T^T (Y K Y^T) T = diag(0, K)`.
    pub fn complement(&self) -> &Matrix {
        &self.frame.w
    }

    /// The blocks `(Z^T S Z, Z^T S W, W^T S W)` of a symmetric form `S` in
    /// the frame `T = [Z W]` (see [`Self::complement`]).
    pub fn frame_blocks(&self, s: &Matrix) -> (Matrix, Matrix, Matrix) {
        let (z, w, zt) = (&self.kernel, &self.frame.w, &self.frame.z_transpose);
        let sz = s.mul(z);
        let sw = s.mul(w);
        (zt.mul(&sz), zt.mul(&sw), w.transpose().mul(&sw))
    }

    /// The `M` (`r × r`) with `G M G^T = Y K Y^T`: `K` placed on the
    /// independent columns.
    pub fn m_from_k(&self, k: &Matrix) -> Matrix {
        let r = self.num_conserved();
        let cols = &self.range_columns;
        let mut m = Matrix::zeros(r, r);
        for (a, &ca) in cols.iter().enumerate() {
            for (b, &cb) in cols.iter().enumerate() {
                m[(ca, cb)] = k[(a, b)].clone();
            }
        }
        m
    }

    /// The exact Schur bound `K0 = B_wz B_zz^{-1} B_zw - B_ww` (blocks of
    /// `B = D^2h + sum lambda_j D^2K_j` in the frame `[Z W]`): for `s = ±1`,
    /// `s (B + Y K Y^T)` is positive definite iff `s B_zz` is and
    /// `s (K - K0)` is (the Schur complement of the `Z` block). `None` when
    /// `B_zz` is singular. This bound is intrinsic: it is the quadratic form
    /// `b -> -min {v^T B v : Y^T v = b}` and does not depend on the choice of
    /// `Z` or `W`; rescaling a conserved quantity rescales its row and column.
    pub fn schur_bound(&self, multipliers: &[Rational]) -> Option<Matrix> {
        Self::schur_bound_of_blocks(&self.frame_blocks(&self.base(multipliers)))
    }

    /// [`Self::schur_bound`] from the [`Self::frame_blocks`] of `B`.
    pub fn schur_bound_of_blocks((bzz, bzw, bww): &(Matrix, Matrix, Matrix)) -> Option<Matrix> {
        if bzz.nrows() == 0 {
            return Some(bww.scale(&-Rational::from(1)));
        }
        let inv = bzz.inverse()?;
        Some(bzw.transpose().mul(&inv).mul(bzw).sub(bww))
    }
}
