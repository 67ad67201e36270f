//! Before the steps of the numeric level: the two early verdicts, decided
//! exactly, and the scope of the floating-point pipeline (outside it, the
//! exact pipeline at the numeric level).

use super::NumericAnalysis;
use crate::pipeline::{incompatible_noise, incompatible_reason, NOT_AN_EQUILIBRIUM};
use casimir::System;
use exact::Rational;
use num_traits::Zero;
use outcome::Verdict;

/// Inputs whose magnitudes stay within `2^±LIMIT` keep every product the
/// pipeline forms (a few factors each) far inside the double range.
const MAGNITUDE_LIMIT: i64 = 100;

fn in_range(x: &Rational) -> bool {
    x.is_zero() || exact::binary_exponent(x).is_some_and(|e| e.abs() <= MAGNITUDE_LIMIT)
}

/// `not_an_equilibrium` when `ad*_{Dh(mu_e)} mu_e != 0`, `noise_incompatible`
/// when some `ad*_{sigma_i} mu_e != 0` (exact residuals), else `None`.
pub(super) fn early_verdict(system: &System) -> Option<NumericAnalysis> {
    if system.equilibrium_residual().iter().any(|r| !r.is_zero()) {
        return Some(NumericAnalysis::early(Verdict::NotAnEquilibrium, NOT_AN_EQUILIBRIUM.into()));
    }
    let incompatible = incompatible_noise(&system.noise_residuals());
    if !incompatible.is_empty() {
        return Some(NumericAnalysis::early(Verdict::NoiseIncompatible, incompatible_reason(&incompatible)));
    }
    None
}

/// Whether the floating-point pipeline applies: every input's magnitude
/// within `2^±100`, and noise that conserves every first integral (else
/// `Q` depends on the Casimir Hessian); `Err` says which fails.
pub(super) fn check_scope(system: &System) -> Result<(), &'static str> {
    let n = system.dim();
    let algebra = system.algebra();
    let polys = std::iter::once(system.hamiltonian()).chain(system.casimirs()).chain(system.first_integrals());
    let magnitudes_ok = system.equilibrium().iter().chain(system.noise().iter().flatten()).all(in_range)
        && (0..n).all(|a| (0..n).all(|b| algebra.bracket_of_basis(a, b).iter().all(|(_, c)| in_range(c))))
        && polys.clone().all(|p| p.terms().all(|(_, c)| in_range(c)));
    if !magnitudes_ok {
        return Err("an input's magnitude lies outside 2^-100 to 2^100");
    }
    if !system.noise_commutation().iter().flatten().all(|&c| c) {
        return Err("the noise does not conserve every first integral (Q depends on the Casimir Hessian)");
    }
    Ok(())
}
