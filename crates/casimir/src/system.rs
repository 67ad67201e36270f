//! A stochastic Lie–Poisson system with one equilibrium, validated exactly.

use crate::bracket::{lie_poisson_bracket, poisson_tensor_entry};
use crate::error::SystemError;
use crate::variation::SecondVariation;
use algebra::LieAlgebra;
use exact::{Matrix, Poly, Rational};

/// Whether a conserved quantity is a Casimir or a first integral of `h`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConservedKind {
    /// Commutes with every function: `{C, mu_j} = 0` for all `j`.
    Casimir,
    /// Conserved by the deterministic flow only: `{F, h} = 0`.
    FirstIntegral,
}

/// A stochastic Lie–Poisson system
/// `d mu = ad*_{Dh(mu)} mu dt + sum_i ad*_{sigma_i} mu o dW^i`
/// with its conserved quantities and one candidate equilibrium.
///
/// The data are validated on construction and read through accessors, so
/// the derivatives of `h` at `mu_e` (computed once) cannot go stale.
#[derive(Clone, Debug)]
pub struct System {
    algebra: LieAlgebra,
    hamiltonian: Poly,
    casimirs: Vec<Poly>,
    first_integrals: Vec<Poly>,
    equilibrium: Vec<Rational>,
    noise: Vec<Vec<Rational>>,
    gradient_h: Vec<Rational>,
    hessian_h: Matrix,
}

/// `{K, mu_j}` for every coordinate `j`: `sum_a ∂_a K Lambda_aj(mu)`, with the
/// gradient computed once.
fn brackets_with_coordinates<'a>(algebra: &'a LieAlgebra, k: &Poly) -> impl Iterator<Item = (usize, Poly)> + 'a {
    let n = algebra.dim();
    let nv = k.nvars();
    let grad: Vec<Poly> = (0..n).map(|a| k.derivative(a)).collect();
    (0..n).map(move |j| {
        let mut out = Poly::zero(nv);
        for (a, ga) in grad.iter().enumerate() {
            if ga.is_zero() {
                continue;
            }
            if let Some(lambda_aj) = poisson_tensor_entry(algebra, a, j, nv) {
                out = out.add(&ga.mul(&lambda_aj));
            }
        }
        (j, out)
    })
}

impl System {
    /// Build a system, checking dimensions and, exactly, that every Casimir
    /// commutes with every coordinate and every first integral with `h`.
    pub fn new(
        algebra: LieAlgebra,
        hamiltonian: Poly,
        casimirs: Vec<Poly>,
        first_integrals: Vec<Poly>,
        equilibrium: Vec<Rational>,
        noise: Vec<Vec<Rational>>,
    ) -> Result<Self, SystemError> {
        let n = algebra.dim();
        let check_vars = |what: String, p: &Poly| {
            if p.nvars() != n {
                Err(SystemError::WrongVariables { what, expected: n, got: p.nvars() })
            } else {
                Ok(())
            }
        };
        check_vars("the hamiltonian".into(), &hamiltonian)?;
        for (i, c) in casimirs.iter().enumerate() {
            check_vars(format!("casimir {i}"), c)?;
        }
        for (i, f) in first_integrals.iter().enumerate() {
            check_vars(format!("first integral {i}"), f)?;
        }
        if equilibrium.len() != n {
            return Err(SystemError::WrongLength {
                what: "the equilibrium".into(),
                expected: n,
                got: equilibrium.len(),
            });
        }
        for (i, s) in noise.iter().enumerate() {
            if s.len() != n {
                return Err(SystemError::WrongLength { what: format!("noise {i}"), expected: n, got: s.len() });
            }
        }
        for (index, c) in casimirs.iter().enumerate() {
            if c.constant_value().is_some() {
                return Err(SystemError::ConstantQuantity { what: "casimir", index });
            }
            for (j, b) in brackets_with_coordinates(&algebra, c) {
                if !b.is_zero() {
                    return Err(SystemError::NotACasimir {
                        index,
                        coordinate: algebra.coordinates()[j].clone(),
                        bracket: b.to_string_with(algebra.coordinates()),
                        bracket_poly: b,
                    });
                }
            }
        }
        for (index, f) in first_integrals.iter().enumerate() {
            if f.constant_value().is_some() {
                return Err(SystemError::ConstantQuantity { what: "first integral", index });
            }
            let b = lie_poisson_bracket(&algebra, f, &hamiltonian);
            if !b.is_zero() {
                return Err(SystemError::NotConserved { index, bracket: b.to_string_with(algebra.coordinates()) });
            }
        }
        let gradient_h = hamiltonian.gradient_at(&equilibrium);
        let hessian_h = Matrix::from_rows(&hamiltonian.hessian_at(&equilibrium));
        Ok(System { algebra, hamiltonian, casimirs, first_integrals, equilibrium, noise, gradient_h, hessian_h })
    }

    /// The Lie algebra.
    pub fn algebra(&self) -> &LieAlgebra {
        &self.algebra
    }

    /// The Hamiltonian `h`.
    pub fn hamiltonian(&self) -> &Poly {
        &self.hamiltonian
    }

    /// The Casimirs `C_j` (checked exactly).
    pub fn casimirs(&self) -> &[Poly] {
        &self.casimirs
    }

    /// The first integrals `F_j` (checked: `{F_j, h} = 0`).
    pub fn first_integrals(&self) -> &[Poly] {
        &self.first_integrals
    }

    /// The candidate equilibrium `mu_e`.
    pub fn equilibrium(&self) -> &[Rational] {
        &self.equilibrium
    }

    /// The noise fields `sigma_i` in `g`, in components on `e_a`.
    pub fn noise(&self) -> &[Vec<Rational>] {
        &self.noise
    }

    /// `D^2h(mu_e)`, exactly.
    pub fn hamiltonian_hessian(&self) -> &Matrix {
        &self.hessian_h
    }

    /// Dimension of the algebra.
    pub fn dim(&self) -> usize {
        self.algebra.dim()
    }

    /// All conserved quantities: the Casimirs, then the first integrals.
    pub fn conserved(&self) -> Vec<(ConservedKind, &Poly)> {
        self.casimirs
            .iter()
            .map(|c| (ConservedKind::Casimir, c))
            .chain(self.first_integrals.iter().map(|f| (ConservedKind::FirstIntegral, f)))
            .collect()
    }

    /// `Dh(mu_e)`, exactly.
    pub fn hamiltonian_gradient(&self) -> &[Rational] {
        &self.gradient_h
    }

    /// The equilibrium residual `ad*_{Dh(mu_e)} mu_e` (zero iff `mu_e` is an
    /// equilibrium of the deterministic flow).
    pub fn equilibrium_residual(&self) -> Vec<Rational> {
        self.algebra.coad(&self.gradient_h, &self.equilibrium)
    }

    /// The noise residuals `ad*_{sigma_i} mu_e` (all zero iff the noise is
    /// compatible with the equilibrium).
    pub fn noise_residuals(&self) -> Vec<Vec<Rational>> {
        self.noise.iter().map(|s| self.algebra.coad(s, &self.equilibrium)).collect()
    }

    /// A basis of the isotropy algebra of `mu_e`: the noise fields that would
    /// be compatible.
    pub fn isotropy_basis(&self) -> Vec<Vec<Rational>> {
        self.algebra.isotropy_basis(&self.equilibrium)
    }

    /// For each conserved quantity (Casimirs then first integrals) and each
    /// noise field: whether `{K, <sigma_i, mu>} = 0`, i.e. whether the noise
    /// also conserves it. Casimirs always do.
    pub fn noise_commutation(&self) -> Vec<Vec<bool>> {
        self.conserved()
            .iter()
            .map(|(kind, k)| match kind {
                // A Casimir commutes with every function (checked in `new`).
                ConservedKind::Casimir => vec![true; self.noise.len()],
                ConservedKind::FirstIntegral => self
                    .noise
                    .iter()
                    .map(|s| lie_poisson_bracket(&self.algebra, k, &Poly::linear(s)).is_zero())
                    .collect(),
            })
            .collect()
    }

    /// Whether `{K, h} = 0` for every conserved quantity is already known; the
    /// deterministic flow conserves all of them. Build the first and second
    /// variation at `mu_e`; `None` when no multipliers make `mu_e` a critical
    /// point of `h + sum lambda_j K_j`.
    pub fn second_variation(&self) -> Option<SecondVariation> {
        SecondVariation::new(self)
    }
}
