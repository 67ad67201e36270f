//! Errors raised when a system's data is inconsistent.

use exact::Poly;

/// Why a [`crate::System`] cannot be built.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum SystemError {
    /// A polynomial is in the wrong number of variables.
    #[error("{what} has {got} variables, the algebra has dimension {expected}")]
    WrongVariables {
        /// Which input.
        what: String,
        /// Expected count.
        expected: usize,
        /// Count found.
        got: usize,
    },
    /// A vector has the wrong length.
    #[error("{what} has length {got}, the algebra has dimension {expected}")]
    WrongLength {
        /// Which input.
        what: String,
        /// Expected length.
        expected: usize,
        /// Length found.
        got: usize,
    },
    /// A claimed Casimir does not Poisson-commute with a coordinate.
    #[error("casimir {index} is not a Casimir: {{C, {coordinate}}} = {bracket} is not zero")]
    NotACasimir {
        /// Index in the Casimir list.
        index: usize,
        /// Coordinate it fails to commute with.
        coordinate: String,
        /// The bracket, printed.
        bracket: String,
        /// The bracket polynomial.
        bracket_poly: Poly,
    },
    /// A claimed first integral is not conserved by `h`.
    #[error("first integral {index} is not conserved: {{F, h}} = {bracket} is not zero")]
    NotConserved {
        /// Index in the first-integral list.
        index: usize,
        /// The bracket, printed.
        bracket: String,
    },
    /// A conserved quantity is a constant (its gradient vanishes identically).
    #[error("{what} {index} is a constant; it carries no information")]
    ConstantQuantity {
        /// "casimir" or "first integral".
        what: &'static str,
        /// Index in its list.
        index: usize,
    },
}
