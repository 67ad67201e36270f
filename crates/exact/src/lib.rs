//! Exact rational arithmetic for the stochastic energy–Casimir engine.
//!
//! Everything the engine certifies starts from polynomials with rational
//! coefficients: the Hamiltonian `h`, the Casimirs `C_j`, the equilibrium
//! `mu_e` and the noise `sigma_i`. This crate holds the exact layer:
//!
//! * [`Rational`] numbers and [`parse_number`], which reads integers, decimal
//!   literals (`0.3` is the rational `3/10`, `1e-3` is `1/1000`) and rational
//!   strings (`"3/10"`) exactly;
//! * [`Matrix`], dense rational matrices with exact Gaussian elimination
//!   (rank, null space, affine solution sets);
//! * [`Poly`], sparse multivariate polynomials with rational coefficients, with
//!   exact gradients and Hessians;
//! * [`parse_expression`], the parser for the spec's expressions
//!   (`+ - * / ^`, parentheses, coordinates and parameters).
//!
//! ```
//! use exact::{parse_expression, Rational, Symbols};
//! let mut symbols = Symbols::new(&["Pi1", "Pi2", "Pi3"]);
//! symbols.set_parameter("I1", Rational::from_integer(3.into()));
//! let h = parse_expression("Pi1^2/(2*I1) + 0.5*Pi2^2", &symbols).unwrap();
//! // d^2 h / dPi1^2 = 1/I1 = 1/3, exactly.
//! let hess = h.hessian();
//! assert_eq!(hess[0][0].constant_value().unwrap(), Rational::new(1.into(), 3.into()));
//! assert_eq!(hess[1][1].constant_value().unwrap(), Rational::from_integer(1.into()));
//! ```
#![warn(missing_docs)]

mod matrix;
mod modular;
mod number;
mod parse;
mod poly;
mod rational;
pub mod syntax;
mod text;
mod upoly;

pub use matrix::{AffineSolution, Congruence, Inertia, Matrix};
pub use modular::{sparse_null_space, SparseRow};
pub use num_bigint::BigInt;
pub use number::{
    best_rational_approximation, binary_exponent, decimal_at_least, decimal_near, parse_certificate_rational,
    parse_number, power_of_two, rational_from_f64, rational_to_f64, rational_to_f64_up, NumberError, Rational,
    MAX_CERTIFICATE_DIGITS, MAX_LITERAL_DIGITS,
};
pub use parse::{
    parse_expression, parse_polynomial, Limits, ParseError, ParseErrorKind, PolynomialArithmetic, SymbolTable, Symbols,
};
pub use poly::{monomial_count, monomials_of_degree, Derivatives, Monomial, Poly};
pub use rational::integer_scale;
pub use text::{cut, quote};
pub use upoly::{char_poly, UPoly};
