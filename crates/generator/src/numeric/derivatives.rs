//! Step 1 of the numeric level (the module documentation's numbering): the
//! derivatives at `mu_e` and the linearised dynamics, in floating point.

use casimir::System;
use nalgebra::DMatrix;

/// The derivatives at `mu_e` and the linearisation, in floating point.
pub(super) struct Derivatives {
    /// `Dh(mu_e)`, rounded from the exact gradient.
    pub(super) dh: Vec<f64>,
    /// `D^2h(mu_e)`, rounded from the exact Hessian.
    pub(super) hh: DMatrix<f64>,
    /// The conserved quantities' derivatives at `mu_e` (Casimirs, then
    /// first integrals), with the magnitudes of their terms.
    pub(super) conserved: Vec<exact::Derivatives>,
    /// A bound on the rounding of one derivative entry relative to the sum
    /// of the magnitudes of its terms.
    pub(super) rounding: f64,
    /// The drift `A`.
    pub(super) a: DMatrix<f64>,
    /// The noise operators `B_i = ad*_{sigma_i}`.
    pub(super) noise: Vec<DMatrix<f64>>,
}

impl Derivatives {
    /// `Dh`, `D^2h` and the conserved quantities' derivatives at `mu_e`,
    /// with `A` and the `B_i`; `Err` when one is not a finite double.
    pub(super) fn at_equilibrium(system: &System) -> Result<Self, &'static str> {
        let n = system.dim();
        let mu: Vec<f64> = system.equilibrium().iter().map(exact::rational_to_f64).collect();
        // Dh and D^2h at mu_e are exact in the system already (computed once):
        // an exactly zero gradient stays zero.
        let dh: Vec<f64> = system.hamiltonian_gradient().iter().map(exact::rational_to_f64).collect();
        let hh = system.hamiltonian_hessian().to_dmatrix();
        let conserved: Vec<exact::Derivatives> =
            system.casimirs().iter().chain(system.first_integrals()).map(|p| p.derivatives_at_f64(&mu)).collect();
        // A bound on the rounding of one derivative entry relative to the sum of
        // the magnitudes of its terms (a few roundings per term, n terms and
        // more per entry; generous).
        let rounding = 64.0 * (n as f64 + 4.0) * f64::EPSILON;
        let (a, noise) = linearise_f64(system, &mu, &dh, &hh);
        if a.iter().chain(noise.iter().flatten()).chain(hh.iter()).chain(&dh).any(|x| !x.is_finite()) {
            return Err("a derivative is not finite in double precision");
        }
        Ok(Derivatives { dh, hh, conserved, rounding, a, noise })
    }
}

/// The drift `A` and the noise operators `B_i` in
/// floating point (the same formulas as [`crate::linearise()`]).
fn linearise_f64(system: &System, mu: &[f64], dh: &[f64], hh: &DMatrix<f64>) -> (DMatrix<f64>, Vec<DMatrix<f64>>) {
    let algebra = system.algebra();
    let n = algebra.dim();
    let mut lambda = DMatrix::zeros(n, n); // Lambda(mu)_ab = c^k_ab mu_k
    let mut a = DMatrix::zeros(n, n); // ad*_{Dh}: (b, k) += c^k_ab Dh_a
    let noise_f: Vec<Vec<f64>> =
        system.noise().iter().map(|s| s.iter().map(exact::rational_to_f64).collect()).collect();
    let mut noise = vec![DMatrix::zeros(n, n); noise_f.len()];
    for ai in 0..n {
        for b in 0..n {
            for (k, c) in algebra.bracket_of_basis(ai, b) {
                let c = exact::rational_to_f64(c);
                lambda[(ai, b)] += c * mu[*k];
                a[(b, *k)] += c * dh[ai];
                for (bm, s) in noise.iter_mut().zip(&noise_f) {
                    bm[(b, *k)] += c * s[ai];
                }
            }
        }
    }
    a += lambda.transpose() * hh;
    (a, noise)
}
