//! Lie–Poisson systems beyond the exact engine's 64 dimensions.
//!
//! The exact engine (`casimir`, `generator`) proves everything in rational
//! arithmetic on dense matrices; its cost grows like `n^4` and it stops at
//! `algebra::MAX_DIMENSION = 64`. Here the same method runs for systems of
//! thousands of coordinates given by sparse data:
//!
//! * [`SparseAlgebra`]: structure constants stored sparsely, antisymmetry
//!   and the Jacobi identity checked exactly on the triples where a bracket
//!   is nonzero;
//! * [`SparsePoly`], [`parse_sparse`]: sparse polynomials (a monomial lists
//!   only its variables), parsed with the shared front end and the exact
//!   limits;
//! * [`LargeSystem`]: the system, with exact sparse checks: each Casimir
//!   Poisson-commutes with every coordinate, each first integral with the
//!   Hamiltonian, the equilibrium and the noise residuals, and which
//!   conserved quantities the noise keeps;
//! * [`analyse_large`]: the energy–Casimir method in floating point (faer):
//!   multipliers by least squares, the Finsler test on `ker G^T`, the
//!   Casimir Hessian by the Schur completion ([`numerics::dense::FramePencil`]),
//!   `Q` from sparse drift and noise operators, `Sigma^2` by a dense
//!   generalized eigenproblem, and the drift's spectrum when no form is
//!   definite. Level `numerical` until the final check:
//! * [`VerifiedPencil`]: the `verified_float` final check, for the exact
//!   second variation of an exactly critical conserved functional (exact
//!   rational multipliers) with every rounding bounded.
//!
//! The modules are private; everything a caller uses is exported here:
//! the data ([`SparseAlgebra`], [`SparsePoly`], [`SparseSymbols`],
//! [`LargeSystem`]), the analysis ([`analyse_large`],
//! [`analyse_large_with`], [`LargeSettings`], [`LargeAnalysis`]) and its
//! proof ([`VerifiedPencil`]).

#![warn(missing_docs)]

mod algebra;
mod analysis;
mod parse;
mod poly;
mod system;
mod verified;

pub use algebra::SparseAlgebra;
pub use analysis::{analyse_large, analyse_large_with, LargeAnalysis, LargeSettings, VERIFIED_MARGINS};
pub use parse::{parse_sparse, SparseSymbols};
pub use poly::{SparseMonomial, SparsePoly};
pub use system::LargeSystem;
pub use verified::{exact_multipliers, Choice, VerifiedPencil};

/// Why a large system could not be built or analysed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LargeError {
    /// The algebra is malformed (the message says how).
    #[error("{0}")]
    Algebra(String),
    /// The system is malformed (the message says which part).
    #[error("{0}")]
    System(String),
    /// A floating-point step failed.
    #[error("numerical breakdown: {0}")]
    Numerical(String),
    /// The analysis was stopped through its [`outcome::Progress`] before it ended.
    #[error(transparent)]
    Cancelled(#[from] outcome::Cancelled),
}
