//! Verified numerics shared by the model crates (`fluid`, `zeitlin`,
//! `large`): the linear algebra whose results a certificate rests on, with
//! the rounding of every step accounted for, and the small numerical tools
//! around it.
//!
//! * [`banded`]: symmetric banded matrices (the spectral-element
//!   y-operators, the Zeitlin blocks' liftings): products, Cholesky and
//!   `L D L^T` factorisations, solves, and the *verified* definiteness and
//!   inertia tests: with Higham's `gamma_k = k u / (1 - k u)` bound on the
//!   rounding of each pivot, a positive computed pivot that exceeds its
//!   error bound proves the exact pivot positive, so the matrix *as stored*
//!   (the doubles given) is positive definite, or has the counted inertia
//!   (Sylvester, Haynsworth for Schur complements).
//! * [`definite`]: verified positive definiteness, dense or banded, behind
//!   one entry point ([`definite::positive_definite`]) that says which test
//!   ran and states exactly what it proves.
//! * [`dense`]: dense symmetric and real eigenproblems by faer, generalized
//!   pencils `(Q, P)`, condition numbers, and the completion of a Casimir
//!   Hessian by a Schur complement (`FramePencil`): floating point, the
//!   estimates a proof is then made for.
//! * [`lanczos`]: the largest eigenvalue of a symmetric operator given only
//!   by its action (Lanczos with full reorthogonalisation), floating point.
//! * [`interval`]: closed intervals of doubles with outward rounding and
//!   Taylor jets: rigorous enclosures of an expression's range over an
//!   interval.
//! * [`scaling`]: power-of-two rescaling: data brought to unit size
//!   without rounding, and `Sigma^2` (of degree two in the noise) scaled
//!   back so that a bound stays a bound.
//! * [`minimise`]: golden-section search on a closure (the fluid Galilean
//!   shift, the Zeitlin momentum coefficient).
//!
//! ```
//! use numerics::banded::SymBanded;
//! // tridiag(-1, 2, -1) has eigenvalues 2 - sqrt 2, 2, 2 + sqrt 2: the
//! // verified test proves lambda_min > 0.5 for the doubles as stored, and
//! // refuses 0.6.
//! let mut a = SymBanded::zeros(3, 1);
//! for i in 0..3 { a.add(i, i, 2.0); }
//! for i in 1..3 { a.add(i, i - 1, -1.0); }
//! assert!(a.verified_positive_definite_within(0.5));
//! assert!(!a.verified_positive_definite_within(0.6));
//! ```
#![warn(missing_docs)]

pub mod banded;
pub mod definite;
pub mod dense;
pub mod interval;
pub mod lanczos;
pub mod minimise;
pub mod scaling;
