//! Conserved quantities and the energy–Casimir second variation.
//!
//! For a Lie–Poisson system on `g*` with Hamiltonian `h`, Casimirs `C_j` and
//! first integrals `F_j` (conserved by `h` only), and an equilibrium `mu_e`,
//! this crate implements steps 1–3 of the method (docs/architecture.md §2):
//!
//! 1. **Conserved quantities.** The Lie–Poisson bracket
//!    `{F, G}(mu) = <mu, [DF, DG]> = c^k_ab mu_k ∂_a F ∂_b G` as an exact
//!    polynomial ([`lie_poisson_bracket`]); a Casimir must satisfy
//!    `{C, mu_j} = 0` for every coordinate and a first integral `{F, h} = 0`.
//!    Polynomial Casimirs can be discovered up to a degree by exact linear
//!    algebra ([`discover_casimirs`]).
//! 2. **First variation.** All multipliers with
//!    `Dh(mu_e) + sum_j lambda_j DK_j(mu_e) = 0` (`K_j` the Casimirs then the
//!    first integrals): an affine family `lambda0 + N t` ([`MultiplierFamily`]).
//! 3. **Second variation.** `P = D^2h + sum_j lambda_j D^2K_j + G M G^T` with
//!    `G = [DK_j(mu_e)]` and `M` free symmetric (the Hessian of the Casimir
//!    function `Phi`). By Finsler's lemma some `M` makes `P` definite iff the
//!    restricted Hessian `Z^T (D^2h + sum lambda_j D^2K_j) Z` is definite, `Z` a
//!    basis of `ker G^T`. [`find_definite_choice`] maximises the smallest
//!    eigenvalue of the restricted Hessian over the family (a concave function
//!    of `t`), for either sign, then picks `M` by a Schur-complement bound and
//!    confirms that `P` is definite by an exact LDLᵀ test.
//!
//! ```
//! use algebra::builtin;
//! use casimir::{System, find_definite_choice, SearchSettings};
//! use exact::{parse_expression, Rational, Symbols};
//! let so3 = builtin("so3").unwrap().algebra;
//! let s = Symbols::new(so3.coordinates());
//! let h = parse_expression("Pi1^2/6 + Pi2^2/4 + Pi3^2/2", &s).unwrap(); // I = (3, 2, 1)
//! let c = parse_expression("(Pi1^2 + Pi2^2 + Pi3^2)/2", &s).unwrap();
//! let q = |n: i64| Rational::from_integer(n.into());
//! let system = System::new(so3, h, vec![c], vec![], vec![q(1), q(0), q(0)], vec![]).unwrap();
//! let variation = system.second_variation().unwrap();
//! // lambda = -1/I1 = -1/3 is the only multiplier.
//! assert_eq!(variation.family.particular, vec![Rational::new((-1).into(), 3.into())]);
//! let outcome = find_definite_choice(&variation, &SearchSettings::default());
//! let choice = outcome.definite().expect("the major axis is formally stable");
//! assert_eq!(choice.sign, casimir::Sign::Positive);
//! // P = diag(mu, 1/I2 - 1/I1, 1/I3 - 1/I1) = diag(mu, 1/6, 2/3)
//! assert_eq!(choice.p[(1, 1)], Rational::new(1.into(), 6.into()));
//! assert_eq!(choice.p[(2, 2)], Rational::new(2.into(), 3.into()));
//! ```
#![warn(missing_docs)]

mod bracket;
mod discover;
mod ellipsoid;
mod error;
mod search;
mod system;
mod variation;

pub use bracket::lie_poisson_bracket;
pub use discover::{discover_casimirs, DiscoveryReport};
pub use ellipsoid::Ellipsoid;
pub use error::SystemError;
pub use search::{
    conserved_margin, find_definite_choice, level_scale, round_family_parameters, short_entries, CasimirChoice,
    Objective, SearchOutcome, SearchSettings, Sign,
};
pub use system::{ConservedKind, System};
pub use variation::{MultiplierFamily, SecondVariation};
