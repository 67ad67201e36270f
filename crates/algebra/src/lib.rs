//! Finite-dimensional Lie algebras for the stochastic energy–Casimir engine.
//!
//! A Lie algebra `g` is given by a basis `e_a` and structure constants
//! `[e_a, e_b] = c^k_ab e_k` (exact rationals). Coordinates `mu_k` on `g*` are
//! taken in the dual basis. The conventions of the whole engine are fixed
//! here:
//!
//! * `(ad_xi eta)^k = c^k_ab xi^a eta^b`;
//! * `(ad*_xi mu)_b = c^k_ab xi^a mu_k`, so that `<ad*_xi mu, eta> = <mu, ad_xi eta>`;
//!   as matrices `ad*_xi = (ad_xi)^T`;
//! * the Lie–Poisson tensor `Lambda(mu)_ab = c^k_ab mu_k`, with which
//!   `ad*_xi mu = Lambda(mu)^T xi`.
//!
//! For `so3` with `c^k_ab = eps_abk`, `ad*_xi mu = mu x xi`, so the stochastic
//! Lie–Poisson equation `d mu = ad*_{Dh} mu dt + ad*_sigma mu o dW` is the
//! rigid body `dPi = Pi x Omega dt + Pi x sigma o dW`.
//!
//! [`LieAlgebra::from_structure_constants`] checks antisymmetry and the Jacobi
//! identity exactly and names the failing indices. Builtins ([`builtin`]):
//! `so3`, `se3` (= `so3 ⋉ R^3`, the heavy top), `sl2` (non-compact), `se2`,
//! `heisenberg`; constructions: [`LieAlgebra::semidirect`] (`g ⋉ V` from a
//! representation) and [`LieAlgebra::direct_sum`].
//!
//! ```
//! use algebra::{builtin, LieAlgebra};
//! use exact::Rational;
//! let so3 = builtin("so3").unwrap().algebra;
//! let q = |n: i64| Rational::from_integer(n.into());
//! // [e1, e2] = e3
//! assert_eq!(so3.bracket(&[q(1), q(0), q(0)], &[q(0), q(1), q(0)]), vec![q(0), q(0), q(1)]);
//! // ad*_xi mu = mu x xi: e1 x e2 = e3
//! assert_eq!(so3.coad(&[q(0), q(1), q(0)], &[q(1), q(0), q(0)]), vec![q(0), q(0), q(1)]);
//! // The isotropy algebra of (1,0,0) is spanned by e1.
//! assert_eq!(so3.isotropy_basis(&[q(1), q(0), q(0)]), vec![vec![q(1), q(0), q(0)]]);
//! ```
#![warn(missing_docs)]

mod builtins;
mod error;
mod lie;

pub use builtins::{builtin, builtin_names, Builtin};
pub use error::AlgebraError;
pub use lie::{LieAlgebra, MAX_DIMENSION};
