//! The spec's expression language, parsed straight into exact polynomials.
//!
//! The grammar is the one front end's, [`crate::syntax`] (shared with the
//! fluid expressions in `y`); this module gives it its polynomial meaning.
//! Identifiers are coordinates (the polynomial's variables) or parameters
//! (substituted by their exact rational values). Division is allowed only by
//! a nonzero constant and powers only with constant integer exponents (a
//! negative exponent only on a constant), so that every expression is a
//! polynomial with rational coefficients; anything else is rejected with the
//! position and the reason.

use crate::number::{parse_number, Rational};
use crate::poly::Poly;
use crate::syntax::{Op, Semantics, SyntaxError, SyntaxErrorKind};
use num_traits::{ToPrimitive, Zero};
use std::collections::BTreeMap;

/// The names an expression may use: coordinates (variables) and parameters
/// (known rational constants).
#[derive(Clone, Debug, Default)]
pub struct Symbols {
    coordinates: Vec<String>,
    parameters: BTreeMap<String, Rational>,
    limits: Limits,
}

/// Size limits that keep parsing fast on hostile input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Largest exponent allowed in `^` (default 64).
    pub max_exponent: u32,
    /// Largest total degree of any intermediate polynomial (default 64).
    pub max_degree: u32,
    /// Largest number of terms of any intermediate polynomial (default 20,000).
    pub max_terms: usize,
    /// Deepest nesting of parentheses and unary operators (default 200).
    pub max_depth: usize,
    /// Longest expression text in bytes (default 100,000).
    pub max_length: usize,
    /// Largest size in bits of the numerator or denominator of any
    /// coefficient, intermediate ones included (default 4096, about 1233
    /// decimal digits: far beyond physical constants, and it keeps
    /// `((10^64)^64)^64` from building a 870,000-bit integer).
    pub max_coefficient_bits: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_exponent: 64,
            max_degree: 64,
            max_terms: 20_000,
            max_depth: 200,
            max_length: 100_000,
            max_coefficient_bits: 4096,
        }
    }
}

impl Symbols {
    /// Symbols with the given coordinate names and no parameters.
    pub fn new<S: AsRef<str>>(coordinates: &[S]) -> Self {
        Symbols {
            coordinates: coordinates.iter().map(|s| s.as_ref().to_string()).collect(),
            parameters: BTreeMap::new(),
            limits: Limits::default(),
        }
    }

    /// Define (or redefine) a parameter.
    pub fn set_parameter(&mut self, name: &str, value: Rational) {
        self.parameters.insert(name.to_string(), value);
    }

    /// Replace the size limits.
    pub fn with_limits(mut self, limits: Limits) -> Self {
        self.limits = limits;
        self
    }

    /// The coordinate names.
    pub fn coordinates(&self) -> &[String] {
        &self.coordinates
    }

    /// The parameters.
    pub fn parameters(&self) -> &BTreeMap<String, Rational> {
        &self.parameters
    }
}

/// What went wrong in an expression.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ParseErrorKind {
    /// A syntax error, found by the shared front end ([`crate::syntax`]).
    #[error(transparent)]
    Syntax(#[from] SyntaxErrorKind),
    /// An identifier that is neither a coordinate nor a parameter.
    #[error("unknown symbol '{name}' (known: {})", known.join(", "))]
    UnknownSymbol {
        /// The unknown name.
        name: String,
        /// The names that are defined.
        known: Vec<String>,
    },
    /// A function call: only polynomials are allowed here.
    #[error(
        "'{0}(...)' is a function call; expressions here must be polynomials (use only + - * / ^ and parentheses)"
    )]
    FunctionCall(String),
    /// Division by something that is not a constant.
    #[error("division by a polynomial that is not a constant; expressions must be polynomials")]
    DivisionByPolynomial,
    /// Division by zero.
    #[error("division by zero")]
    DivisionByZero,
    /// An exponent that is not a constant integer.
    #[error("the exponent must be a constant integer")]
    NonIntegerExponent,
    /// A negative power of a non-constant polynomial.
    #[error("negative power of a non-constant polynomial; expressions must be polynomials")]
    NegativePowerOfPolynomial,
    /// Zero to a negative power.
    #[error("zero raised to a negative power")]
    ZeroToNegativePower,
    /// An exponent above the limit.
    #[error("exponent {0} is too large (limit {1})")]
    ExponentTooLarge(String, u32),
    /// A number literal that is not a finite number.
    #[error("{0}")]
    BadNumber(String),
    /// The polynomial grew beyond the size limits.
    #[error("the expression expands to a polynomial beyond the size limits (degree {degree} > {max_degree} or {terms} > {max_terms} terms)")]
    TooLarge {
        /// Degree reached.
        degree: u32,
        /// Degree limit.
        max_degree: u32,
        /// Terms reached.
        terms: usize,
        /// Term limit.
        max_terms: usize,
    },
    /// A coefficient beyond the size limit.
    #[error("a coefficient of about {bits} bits is beyond the limit of {limit} bits (about {} decimal digits)", limit * 3 / 10)]
    CoefficientTooLarge {
        /// Bits reached (or an upper bound, when refused before computing).
        bits: u64,
        /// The limit.
        limit: u64,
    },
}

/// An expression error with the character position where it was found.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{kind} (at character {position})")]
pub struct ParseError {
    /// What went wrong.
    pub kind: ParseErrorKind,
    /// 0-based character offset into the expression.
    pub position: usize,
}

/// What the polynomial language needs of a polynomial type, so that one
/// parser serves the dense [`Poly`] (up to 64 coordinates) and the large
/// pipeline's sparse polynomials (thousands): arithmetic, and the sizes the
/// limits are checked against before a result is formed.
pub trait PolynomialArithmetic: Sized {
    /// The constant `c` in `nvars` variables.
    fn constant(nvars: usize, c: Rational) -> Self;
    /// The variable `x_i`.
    fn var(nvars: usize, i: usize) -> Self;
    /// `self + other`.
    fn add(&self, other: &Self) -> Self;
    /// `self - other`.
    fn sub(&self, other: &Self) -> Self;
    /// `self * other`.
    fn mul(&self, other: &Self) -> Self;
    /// `-self`.
    fn neg(&self) -> Self;
    /// `s * self`.
    fn scale(&self, s: &Rational) -> Self;
    /// `self^e`.
    fn pow(&self, e: u32) -> Self;
    /// The value, when the polynomial is a constant.
    fn constant_value(&self) -> Option<Rational>;
    /// The total degree.
    fn total_degree(&self) -> u32;
    /// The number of terms.
    fn num_terms(&self) -> usize;
    /// The largest coefficient size in bits.
    fn max_bits(&self) -> u64;
    /// An upper bound on the number of terms of `self^m`, of total degree
    /// `degree`, known before it is formed.
    fn power_terms_bound(&self, m: u32, degree: u32) -> usize;
}

impl PolynomialArithmetic for Poly {
    fn constant(nvars: usize, c: Rational) -> Self {
        Poly::constant(nvars, c)
    }
    fn var(nvars: usize, i: usize) -> Self {
        Poly::var(nvars, i)
    }
    fn add(&self, other: &Self) -> Self {
        Poly::add(self, other)
    }
    fn sub(&self, other: &Self) -> Self {
        Poly::sub(self, other)
    }
    fn mul(&self, other: &Self) -> Self {
        Poly::mul(self, other)
    }
    fn neg(&self) -> Self {
        Poly::neg(self)
    }
    fn scale(&self, s: &Rational) -> Self {
        Poly::scale(self, s)
    }
    fn pow(&self, e: u32) -> Self {
        Poly::pow(self, e)
    }
    fn constant_value(&self) -> Option<Rational> {
        Poly::constant_value(self)
    }
    fn total_degree(&self) -> u32 {
        Poly::total_degree(self)
    }
    fn num_terms(&self) -> usize {
        Poly::num_terms(self)
    }
    fn max_bits(&self) -> u64 {
        self.terms().map(|(_, c)| c.size_bits()).max().unwrap_or(1)
    }
    /// At most the monomials of degree `<= degree` in the variables the
    /// base uses, and at most `terms^m`.
    fn power_terms_bound(&self, m: u32, degree: u32) -> usize {
        let vars = (0..self.nvars()).filter(|&i| self.terms().any(|(mono, _)| mono[i] > 0)).count();
        let at_most = crate::poly::monomial_count(vars + 1, degree).min(usize::MAX as u128) as usize;
        at_most.min(saturating_pow(self.num_terms(), m))
    }
}

/// The names an expression may use, as the parser looks them up: the
/// coordinates (variables), the parameters (exact constants) and the size
/// limits.
pub trait SymbolTable {
    /// The number of coordinates.
    fn nvars(&self) -> usize;
    /// The index of the coordinate `name`.
    fn coordinate(&self, name: &str) -> Option<usize>;
    /// The value of the parameter `name`.
    fn parameter(&self, name: &str) -> Option<&Rational>;
    /// The names an unknown symbol's error lists.
    fn known_names(&self) -> Vec<String>;
    /// The size limits.
    fn limits(&self) -> &Limits;
}

impl SymbolTable for Symbols {
    fn nvars(&self) -> usize {
        self.coordinates.len()
    }
    fn coordinate(&self, name: &str) -> Option<usize> {
        self.coordinates.iter().position(|c| c == name)
    }
    fn parameter(&self, name: &str) -> Option<&Rational> {
        self.parameters.get(name)
    }
    fn known_names(&self) -> Vec<String> {
        self.coordinates.iter().cloned().chain(self.parameters.keys().cloned()).collect()
    }
    fn limits(&self) -> &Limits {
        &self.limits
    }
}

/// The polynomial language: numbers are exact, symbols are coordinates or
/// parameters, no function calls, division only by nonzero constants,
/// constant integer exponents; every step is checked against the size
/// limits before the polynomial it would make is formed.
struct Polynomials<'a, S, P> {
    symbols: &'a S,
    value: std::marker::PhantomData<P>,
}

/// Parse an expression into an exact polynomial in the coordinates, with
/// parameters substituted (the grammar is [`crate::syntax`]'s).
///
/// ```
/// use exact::{parse_expression, Rational, Symbols, ParseErrorKind};
/// let s = Symbols::new(&["x", "y"]);
/// let p = parse_expression("(x + y)^2 - 2*x*y", &s).unwrap();
/// assert_eq!(p, parse_expression("x^2 + y^2", &s).unwrap());
/// let e = parse_expression("x / y", &s).unwrap_err();
/// assert_eq!(e.kind, ParseErrorKind::DivisionByPolynomial);
/// ```
pub fn parse_expression(text: &str, symbols: &Symbols) -> Result<Poly, ParseError> {
    parse_polynomial(text, symbols)
}

/// [`parse_expression`] into any polynomial type, with any symbol table:
/// the one parser of the polynomial language at every size.
pub fn parse_polynomial<S: SymbolTable, P: PolynomialArithmetic>(text: &str, symbols: &S) -> Result<P, ParseError> {
    let l = symbols.limits();
    crate::syntax::parse(text, &mut Polynomials { symbols, value: std::marker::PhantomData }, l.max_depth, l.max_length)
}

fn saturating_pow(b: usize, e: u32) -> usize {
    (0..e).fold(1usize, |acc, _| acc.saturating_mul(b))
}

fn fail<T>(kind: ParseErrorKind, position: usize) -> Result<T, ParseError> {
    Err(ParseError { kind, position })
}

impl<S: SymbolTable, P: PolynomialArithmetic> Polynomials<'_, S, P> {
    fn nvars(&self) -> usize {
        self.symbols.nvars()
    }

    fn check_size(&self, p: P, position: usize) -> Result<P, ParseError> {
        let l = self.symbols.limits();
        let bits = p.max_bits();
        if bits > l.max_coefficient_bits {
            return fail(ParseErrorKind::CoefficientTooLarge { bits, limit: l.max_coefficient_bits }, position);
        }
        let degree = p.total_degree();
        if degree > l.max_degree || p.num_terms() > l.max_terms {
            return fail(
                ParseErrorKind::TooLarge {
                    degree,
                    max_degree: l.max_degree,
                    terms: p.num_terms(),
                    max_terms: l.max_terms,
                },
                position,
            );
        }
        Ok(p)
    }

    /// Refuse `base^m` before computing it when its coefficients would
    /// exceed the size limit: each is a sum of products of `m` coefficients
    /// (with multinomial weights below `terms^m`).
    fn bound_power_bits(&self, base: &P, m: u32, at: usize) -> Result<(), ParseError> {
        let l = self.symbols.limits();
        let per_factor = base.max_bits() + (usize::BITS - base.num_terms().leading_zeros()) as u64;
        let bits = per_factor.saturating_mul(m as u64);
        if bits > 2 * l.max_coefficient_bits {
            return fail(ParseErrorKind::CoefficientTooLarge { bits, limit: l.max_coefficient_bits }, at);
        }
        Ok(())
    }
}

impl<S: SymbolTable, P: PolynomialArithmetic> Semantics for Polynomials<'_, S, P> {
    type Value = P;
    type Function = std::convert::Infallible;
    type Error = ParseError;

    fn syntax(&self, e: SyntaxError) -> ParseError {
        ParseError { kind: ParseErrorKind::Syntax(e.kind), position: e.position }
    }

    fn number(&mut self, text: &str, at: usize) -> Result<P, ParseError> {
        match parse_number(text) {
            Ok(v) => Ok(P::constant(self.nvars(), v)),
            Err(e) => fail(ParseErrorKind::BadNumber(e.to_string()), at),
        }
    }

    fn symbol(&mut self, name: &str, at: usize) -> Result<P, ParseError> {
        if let Some(i) = self.symbols.coordinate(name) {
            return Ok(P::var(self.nvars(), i));
        }
        if let Some(v) = self.symbols.parameter(name) {
            return Ok(P::constant(self.nvars(), v.clone()));
        }
        fail(ParseErrorKind::UnknownSymbol { name: name.to_string(), known: self.symbols.known_names() }, at)
    }

    fn function(&mut self, name: &str, at: usize) -> Result<Self::Function, ParseError> {
        fail(ParseErrorKind::FunctionCall(name.to_string()), at)
    }

    fn call(&mut self, f: Self::Function, _: P, _: usize) -> Result<P, ParseError> {
        match f {}
    }

    fn binary(&mut self, op: Op, acc: P, rhs: P, at: usize, rhs_at: usize) -> Result<P, ParseError> {
        match op {
            Op::Add => self.check_size(acc.add(&rhs), at),
            Op::Sub => self.check_size(acc.sub(&rhs), at),
            Op::Mul => {
                // Bound the product before forming it.
                let l = self.symbols.limits();
                let degree = acc.total_degree() + rhs.total_degree();
                let terms = acc.num_terms().saturating_mul(rhs.num_terms());
                if degree > l.max_degree || terms > l.max_terms.saturating_mul(4) {
                    return fail(
                        ParseErrorKind::TooLarge { degree, max_degree: l.max_degree, terms, max_terms: l.max_terms },
                        at,
                    );
                }
                // Each coefficient of the product is a sum of at most
                // `terms` products: its size is bounded before it is formed.
                let bits = 2 * (acc.max_bits() + rhs.max_bits()) + 64;
                if bits > 4 * l.max_coefficient_bits {
                    return fail(ParseErrorKind::CoefficientTooLarge { bits, limit: l.max_coefficient_bits }, at);
                }
                self.check_size(acc.mul(&rhs), at)
            }
            Op::Div => {
                let Some(d) = rhs.constant_value() else {
                    return fail(ParseErrorKind::DivisionByPolynomial, rhs_at);
                };
                if d.is_zero() {
                    return fail(ParseErrorKind::DivisionByZero, rhs_at);
                }
                self.check_size(acc.scale(&d.recip()), at)
            }
        }
    }

    fn negate(&mut self, a: P, _: usize) -> Result<P, ParseError> {
        Ok(a.neg())
    }

    fn power(&mut self, base: P, exponent: P, at: usize, exp_at: usize) -> Result<P, ParseError> {
        let Some(e) = exponent.constant_value() else {
            return fail(ParseErrorKind::NonIntegerExponent, exp_at);
        };
        if !e.is_integer() {
            return fail(ParseErrorKind::NonIntegerExponent, exp_at);
        }
        let max = self.symbols.limits().max_exponent;
        let magnitude = e.abs().to_integer().to_u32().filter(|&m| m <= max);
        let Some(m) = magnitude else {
            return fail(ParseErrorKind::ExponentTooLarge(e.to_string(), max), exp_at);
        };
        if e.is_negative() {
            let Some(b) = base.constant_value() else {
                return fail(ParseErrorKind::NegativePowerOfPolynomial, at);
            };
            if b.is_zero() {
                return fail(ParseErrorKind::ZeroToNegativePower, at);
            }
            self.bound_power_bits(&base, m, at)?;
            return self.check_size(P::constant(self.nvars(), b.recip().pow(m)), at);
        }
        let l = self.symbols.limits();
        let degree = base.total_degree().saturating_mul(m);
        if degree > l.max_degree {
            return fail(
                ParseErrorKind::TooLarge {
                    degree,
                    max_degree: l.max_degree,
                    terms: base.num_terms(),
                    max_terms: l.max_terms,
                },
                at,
            );
        }
        self.bound_power_bits(&base, m, at)?;
        if let Some(b) = base.constant_value() {
            return self.check_size(P::constant(self.nvars(), b.pow(m)), at);
        }
        // Terms of base^m, refused before they are formed.
        let terms = base.power_terms_bound(m, degree);
        if terms > l.max_terms.saturating_mul(4) {
            return fail(
                ParseErrorKind::TooLarge { degree, max_degree: l.max_degree, terms, max_terms: l.max_terms },
                at,
            );
        }
        self.check_size(base.pow(m), at)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn syms() -> Symbols {
        let mut s = Symbols::new(&["x", "y"]);
        s.set_parameter("a", Rational::new(3.into(), 10.into()));
        s
    }

    fn q(n: i64, d: i64) -> Rational {
        Rational::new(n.into(), d.into())
    }

    #[test]
    fn precedence_and_associativity() {
        let s = syms();
        let p = parse_expression("-x^2", &s).unwrap();
        assert_eq!(p.coefficient(&[2, 0]), q(-1, 1));
        let p = parse_expression("2^3^2", &s).unwrap();
        assert_eq!(p.constant_value().unwrap(), q(512, 1));
        let p = parse_expression("1 - 2 - 3", &s).unwrap();
        assert_eq!(p.constant_value().unwrap(), q(-4, 1));
        let p = parse_expression("12/2/3", &s).unwrap();
        assert_eq!(p.constant_value().unwrap(), q(2, 1));
        let p = parse_expression("a*x/(2*a)", &s).unwrap();
        assert_eq!(p.coefficient(&[1, 0]), q(1, 2));
        let p = parse_expression("2^-2 + 0.3", &s).unwrap();
        assert_eq!(p.constant_value().unwrap(), q(11, 20));
    }

    #[test]
    fn errors_name_the_problem() {
        let s = syms();
        let kind = |t: &str| parse_expression(t, &s).unwrap_err().kind;
        assert!(matches!(kind("x + z"), ParseErrorKind::UnknownSymbol { .. }));
        assert_eq!(kind("1/x"), ParseErrorKind::DivisionByPolynomial);
        assert_eq!(kind("1/(a - 0.3)"), ParseErrorKind::DivisionByZero);
        assert_eq!(kind("x^y"), ParseErrorKind::NonIntegerExponent);
        assert_eq!(kind("x^(1/2)"), ParseErrorKind::NonIntegerExponent);
        assert_eq!(kind("x^-1"), ParseErrorKind::NegativePowerOfPolynomial);
        assert!(matches!(kind("sin(x)"), ParseErrorKind::FunctionCall(_)));
        assert!(matches!(kind("x^100"), ParseErrorKind::ExponentTooLarge(..)));
        assert!(matches!(kind("(x+y)^40*(x+y)^40"), ParseErrorKind::TooLarge { .. }));
        assert_eq!(kind("(x"), ParseErrorKind::Syntax(SyntaxErrorKind::UnexpectedEnd));
        assert!(matches!(kind("x y"), ParseErrorKind::Syntax(SyntaxErrorKind::UnexpectedToken(_))));
        assert!(matches!(kind("x $ y"), ParseErrorKind::Syntax(SyntaxErrorKind::UnexpectedChar('$'))));
        assert_eq!(kind("   "), ParseErrorKind::Syntax(SyntaxErrorKind::Empty));
        assert_eq!(kind("0^-1"), ParseErrorKind::ZeroToNegativePower);
        let deep = "(".repeat(500) + "x" + &")".repeat(500);
        assert!(matches!(kind(&deep), ParseErrorKind::Syntax(SyntaxErrorKind::TooDeep(_))));
        let minus = "-".repeat(500) + "x";
        assert!(matches!(kind(&minus), ParseErrorKind::Syntax(SyntaxErrorKind::TooDeep(_))));
    }

    #[test]
    fn huge_coefficients_are_refused_before_they_are_built() {
        // Regression: ((10^64)^64)^64 * x^2 built a 870,000-bit integer and
        // the pipeline then ran for minutes on it.
        let s = syms();
        let kind = |t: &str| parse_expression(t, &s).unwrap_err().kind;
        assert!(matches!(kind("((10^64)^64)^64*x^2"), ParseErrorKind::CoefficientTooLarge { .. }));
        assert!(matches!(kind("(x + 10^60)^60"), ParseErrorKind::CoefficientTooLarge { .. }));
        // 10^1200 is 3987 bits: below the default 4096, accepted; its square is not.
        assert!(parse_expression("(10^60)^20*x", &s).is_ok());
        assert!(matches!(kind("(10^60)^20*(10^60)^20*x"), ParseErrorKind::CoefficientTooLarge { .. }));
        // an ordinary quartic with rational coefficients is far below the limit
        assert!(parse_expression("(x/3 + 2*y/7)^16", &s).is_ok());
    }

    #[test]
    fn error_positions_point_at_the_culprit() {
        let s = syms();
        let e = parse_expression("x + 2*zz", &s).unwrap_err();
        assert_eq!(e.position, 6);
    }
}
