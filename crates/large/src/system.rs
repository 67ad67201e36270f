//! A large Lie–Poisson system and its exact sparse checks.

use crate::algebra::SparseAlgebra;
use crate::poly::SparsePoly;
use crate::LargeError;
use exact::Rational;
use num_traits::Zero;
use std::collections::BTreeMap;

/// A stochastic Lie–Poisson system on the dual of a sparse algebra:
/// `d mu = ad*_{Dh(mu)} mu dt + sum_i ad*_{sigma_i} mu o dW^i`
/// (`(ad*_xi mu)_b = c^k_ab xi^a mu_k`, docs/architecture.md §1).
#[derive(Clone, Debug)]
pub struct LargeSystem {
    algebra: SparseAlgebra,
    hamiltonian: SparsePoly,
    casimirs: Vec<SparsePoly>,
    first_integrals: Vec<SparsePoly>,
    equilibrium: Vec<Rational>,
    noise: Vec<Vec<Rational>>,
}

/// `sum_{a,b,k} c^k_ab x_k (d_a f) g_b` for polynomial `g_b` given per `b`
/// (a Poisson bracket `{f, g}` when `g_b = d_b g`).
fn bracket_with(algebra: &SparseAlgebra, f: &SparsePoly, g: &mut dyn FnMut(usize) -> SparsePoly) -> SparsePoly {
    let n = algebra.dim();
    let mut out = SparsePoly::zero(n);
    for a in f.variables() {
        let da = f.derivative(a);
        for &b in algebra.partners(a) {
            let gb = g(b);
            if gb.is_zero() {
                continue;
            }
            let mut lin = SparsePoly::zero(n);
            for (k, c) in algebra.bracket(a, b) {
                lin = lin.add(&SparsePoly::var(n, *k).scale(c));
            }
            out = out.add(&lin.mul(&da).mul(&gb));
        }
    }
    out
}

impl LargeSystem {
    /// Build and check, exactly: sizes, every Casimir commutes with every
    /// coordinate (`{C, x_j} = sum_{a,k} c^k_aj x_k d_a C = 0` as a
    /// polynomial), every first integral with the Hamiltonian.
    pub fn new(
        algebra: SparseAlgebra,
        hamiltonian: SparsePoly,
        casimirs: Vec<SparsePoly>,
        first_integrals: Vec<SparsePoly>,
        equilibrium: Vec<Rational>,
        noise: Vec<Vec<Rational>>,
    ) -> Result<Self, LargeError> {
        let n = algebra.dim();
        if equilibrium.len() != n {
            return Err(LargeError::System(format!("equilibrium: {} components, expected {n}", equilibrium.len())));
        }
        if let Some(i) = noise.iter().position(|s| s.len() != n) {
            return Err(LargeError::System(format!("noise[{i}]: {} components, expected {n}", noise[i].len())));
        }
        for (j, c) in casimirs.iter().enumerate() {
            // {C, x_j} for every j at once: accumulate per j.
            let mut per: BTreeMap<usize, SparsePoly> = BTreeMap::new();
            for a in c.variables() {
                let da = c.derivative(a);
                for &b in algebra.partners(a) {
                    for (k, coefficient) in algebra.bracket(a, b) {
                        let term = SparsePoly::var(n, *k).mul(&da).scale(coefficient);
                        let e = per.entry(b).or_insert_with(|| SparsePoly::zero(n));
                        *e = e.add(&term);
                    }
                }
            }
            if let Some((b, p)) = per.iter().find(|(_, p)| !p.is_zero()) {
                return Err(LargeError::System(format!(
                    "casimirs[{j}] is not a Casimir: its Poisson bracket with coordinate {b} ({}) is not zero ({} terms)",
                    algebra.names()[*b],
                    p.num_terms()
                )));
            }
        }
        let mut dh: BTreeMap<usize, SparsePoly> = BTreeMap::new();
        for (j, f) in first_integrals.iter().enumerate() {
            let b =
                bracket_with(&algebra, f, &mut |b| dh.entry(b).or_insert_with(|| hamiltonian.derivative(b)).clone());
            if !b.is_zero() {
                return Err(LargeError::System(format!(
                    "first_integrals[{j}] does not Poisson-commute with the Hamiltonian ({} terms remain)",
                    b.num_terms()
                )));
            }
        }
        Ok(LargeSystem { algebra, hamiltonian, casimirs, first_integrals, equilibrium, noise })
    }

    /// The exact engine's system, for the large pipeline (to compare the
    /// two on the same data, or to run a small system in floating point).
    pub fn from_exact(system: &casimir::System) -> Result<LargeSystem, LargeError> {
        let algebra = system.algebra();
        let sparse = SparseAlgebra::new(algebra.coordinates(), &algebra.structure_constant_rows())?;
        LargeSystem::new(
            sparse,
            SparsePoly::from_poly(system.hamiltonian()),
            system.casimirs().iter().map(SparsePoly::from_poly).collect(),
            system.first_integrals().iter().map(SparsePoly::from_poly).collect(),
            system.equilibrium().to_vec(),
            system.noise().to_vec(),
        )
    }

    /// The same system with other noise fields (of the same length; the
    /// checks above do not involve the noise).
    ///
    /// # Panics
    /// If a field has the wrong length.
    pub fn with_noise(&self, noise: Vec<Vec<Rational>>) -> LargeSystem {
        assert!(noise.iter().all(|f| f.len() == self.dim()), "noise field length");
        LargeSystem { noise, ..self.clone() }
    }

    /// The algebra.
    pub fn algebra(&self) -> &SparseAlgebra {
        &self.algebra
    }

    /// The dimension.
    pub fn dim(&self) -> usize {
        self.algebra.dim()
    }

    /// The Hamiltonian.
    pub fn hamiltonian(&self) -> &SparsePoly {
        &self.hamiltonian
    }

    /// The Casimirs, then the first integrals.
    pub fn conserved(&self) -> Vec<&SparsePoly> {
        self.casimirs.iter().chain(&self.first_integrals).collect()
    }

    /// The equilibrium.
    pub fn equilibrium(&self) -> &[Rational] {
        &self.equilibrium
    }

    /// The noise fields.
    pub fn noise(&self) -> &[Vec<Rational>] {
        &self.noise
    }

    /// `(ad*_xi mu)_b = c^k_ab xi^a mu_k`, exactly, as the nonzero entries.
    pub fn coadjoint(&self, xi: &BTreeMap<usize, Rational>, mu: &[Rational]) -> BTreeMap<usize, Rational> {
        let mut out: BTreeMap<usize, Rational> = BTreeMap::new();
        for (&a, x) in xi {
            for &b in self.algebra.partners(a) {
                for (k, c) in self.algebra.bracket(a, b) {
                    if !mu[*k].is_zero() {
                        let e = out.entry(b).or_insert_with(Rational::zero);
                        *e += &(x * c) * &mu[*k];
                    }
                }
            }
        }
        out.retain(|_, v| !v.is_zero());
        out
    }

    /// `ad*_{Dh(mu_e)} mu_e`, exactly (nonzero entries).
    pub fn equilibrium_residual(&self) -> BTreeMap<usize, Rational> {
        self.coadjoint(&self.hamiltonian.gradient_at(&self.equilibrium), &self.equilibrium)
    }

    /// `ad*_{sigma_i} mu_e` per noise field, exactly (nonzero entries).
    pub fn noise_residuals(&self) -> Vec<BTreeMap<usize, Rational>> {
        self.noise
            .iter()
            .map(|s| {
                let xi: BTreeMap<usize, Rational> =
                    s.iter().enumerate().filter(|(_, v)| !v.is_zero()).map(|(i, v)| (i, v.clone())).collect();
                self.coadjoint(&xi, &self.equilibrium)
            })
            .collect()
    }

    /// Whether every conserved quantity Poisson-commutes with every noise
    /// potential `<sigma_i, mu>`, exactly: then `Q` does not depend on the
    /// Casimir Hessian.
    pub fn noise_conserves_all(&self) -> bool {
        self.conserved().iter().all(|k| {
            self.noise.iter().all(|s| {
                bracket_with(&self.algebra, k, &mut |b| SparsePoly::constant(self.dim(), s[b].clone())).is_zero()
            })
        })
    }
}
