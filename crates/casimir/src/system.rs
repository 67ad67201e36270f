//! A stochastic Lie–Poisson system with one equilibrium, validated exactly.

use crate::bracket::lie_poisson_bracket;
use crate::error::SystemError;
use crate::variation::SecondVariation;
use algebra::LieAlgebra;
use exact::{Poly, Rational};

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
#[derive(Clone, Debug)]
pub struct System {
    /// The Lie algebra.
    pub algebra: LieAlgebra,
    /// The Hamiltonian `h`.
    pub hamiltonian: Poly,
    /// Casimirs `C_j` (checked).
    pub casimirs: Vec<Poly>,
    /// First integrals `F_j` (checked: `{F_j, h} = 0`).
    pub first_integrals: Vec<Poly>,
    /// The candidate equilibrium `mu_e`.
    pub equilibrium: Vec<Rational>,
    /// The noise fields `sigma_i` in `g`, in components on `e_a`.
    pub noise: Vec<Vec<Rational>>,
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
            for j in 0..n {
                let b = lie_poisson_bracket(&algebra, c, &Poly::var(n, j));
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
        Ok(System { algebra, hamiltonian, casimirs, first_integrals, equilibrium, noise })
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
    pub fn hamiltonian_gradient(&self) -> Vec<Rational> {
        self.hamiltonian.gradient().iter().map(|g| g.eval(&self.equilibrium)).collect()
    }

    /// The equilibrium residual `ad*_{Dh(mu_e)} mu_e` (zero iff `mu_e` is an
    /// equilibrium of the deterministic flow).
    pub fn equilibrium_residual(&self) -> Vec<Rational> {
        self.algebra.coad(&self.hamiltonian_gradient(), &self.equilibrium)
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
            .map(|(_, k)| {
                self.noise.iter().map(|s| lie_poisson_bracket(&self.algebra, k, &Poly::linear(s)).is_zero()).collect()
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
