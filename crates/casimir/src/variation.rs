//! First variation (the multiplier family) and second variation at `mu_e`.

use crate::system::System;
use exact::{Matrix, Rational};

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
    /// `Z`: columns form a basis of `ker G^T` (`n × (n - rank G)`).
    pub kernel: Matrix,
    /// Indices of linearly independent columns of `G` spanning its range.
    pub range_columns: Vec<usize>,
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
        let kernel_vectors = gradients.transpose().null_space();
        let kernel = Matrix::from_columns(n, &kernel_vectors);
        let range_columns = gradients.pivot_columns();
        Some(SecondVariation { gradient_h, hessian_h, gradients, hessians, family, kernel, range_columns })
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
        let z = &self.kernel;
        z.transpose().mul(&self.base(multipliers)).mul(z)
    }
}
