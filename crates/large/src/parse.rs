//! Expressions to [`SparsePoly`], with the shared front end
//! ([`exact::syntax`]) and the exact engine's size limits.

use crate::poly::SparsePoly;
use exact::syntax::{Op, Semantics, SyntaxError};
use exact::{Limits, ParseError, ParseErrorKind, Rational};
use num_traits::{ToPrimitive, Zero};
use std::collections::{BTreeMap, HashMap};

/// Coordinates (by name, for fast lookup among thousands), parameters and
/// limits.
#[derive(Clone, Debug)]
pub struct SparseSymbols {
    names: Vec<String>,
    index: HashMap<String, usize>,
    parameters: BTreeMap<String, Rational>,
    limits: Limits,
}

impl SparseSymbols {
    /// Coordinates and parameters, with the exact engine's default limits
    /// except the number of terms (1,000,000: a coupled chain of a thousand
    /// bodies has tens of thousands of terms).
    pub fn new(names: &[String], parameters: &BTreeMap<String, Rational>) -> Self {
        let index = names.iter().enumerate().map(|(i, n)| (n.clone(), i)).collect();
        let limits = Limits { max_terms: 1_000_000, max_length: 50_000_000, ..Limits::default() };
        SparseSymbols { names: names.to_vec(), index, parameters: parameters.clone(), limits }
    }

    fn nvars(&self) -> usize {
        self.names.len()
    }
}

struct Polynomials<'s> {
    symbols: &'s SparseSymbols,
}

fn fail<T>(kind: ParseErrorKind, position: usize) -> Result<T, ParseError> {
    Err(ParseError { kind, position })
}

impl Polynomials<'_> {
    fn check(&self, p: SparsePoly, at: usize) -> Result<SparsePoly, ParseError> {
        let l = &self.symbols.limits;
        let bits = p.max_bits();
        if bits > l.max_coefficient_bits {
            return fail(ParseErrorKind::CoefficientTooLarge { bits, limit: l.max_coefficient_bits }, at);
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
                at,
            );
        }
        Ok(p)
    }
}

impl Semantics for Polynomials<'_> {
    type Value = SparsePoly;
    type Function = std::convert::Infallible;
    type Error = ParseError;

    fn syntax(&self, e: SyntaxError) -> ParseError {
        ParseError { kind: ParseErrorKind::Syntax(e.kind), position: e.position }
    }

    fn number(&mut self, text: &str, at: usize) -> Result<SparsePoly, ParseError> {
        match exact::parse_number(text) {
            Ok(v) => Ok(SparsePoly::constant(self.symbols.nvars(), v)),
            Err(e) => fail(ParseErrorKind::BadNumber(e.to_string()), at),
        }
    }

    fn symbol(&mut self, name: &str, at: usize) -> Result<SparsePoly, ParseError> {
        if let Some(&i) = self.symbols.index.get(name) {
            return Ok(SparsePoly::var(self.symbols.nvars(), i));
        }
        if let Some(v) = self.symbols.parameters.get(name) {
            return Ok(SparsePoly::constant(self.symbols.nvars(), v.clone()));
        }
        // (The first names only: a system may have thousands.)
        let mut known: Vec<String> = self.symbols.names.iter().take(8).cloned().collect();
        if self.symbols.names.len() > 8 {
            known.push(format!("... {} coordinates in all", self.symbols.names.len()));
        }
        known.extend(self.symbols.parameters.keys().cloned());
        fail(ParseErrorKind::UnknownSymbol { name: name.to_string(), known }, at)
    }

    fn function(&mut self, name: &str, at: usize) -> Result<Self::Function, ParseError> {
        fail(ParseErrorKind::FunctionCall(name.to_string()), at)
    }

    fn call(&mut self, f: Self::Function, _: SparsePoly, _: usize) -> Result<SparsePoly, ParseError> {
        match f {}
    }

    fn binary(
        &mut self,
        op: Op,
        a: SparsePoly,
        b: SparsePoly,
        at: usize,
        rhs_at: usize,
    ) -> Result<SparsePoly, ParseError> {
        match op {
            Op::Add => self.check(a.add(&b), at),
            Op::Sub => self.check(a.sub(&b), at),
            Op::Mul => {
                let l = &self.symbols.limits;
                let degree = a.total_degree() + b.total_degree();
                let terms = a.num_terms().saturating_mul(b.num_terms());
                if degree > l.max_degree || terms > l.max_terms.saturating_mul(4) {
                    return fail(
                        ParseErrorKind::TooLarge { degree, max_degree: l.max_degree, terms, max_terms: l.max_terms },
                        at,
                    );
                }
                let bits = 2 * (a.max_bits() + b.max_bits()) + 64;
                if bits > 4 * l.max_coefficient_bits {
                    return fail(ParseErrorKind::CoefficientTooLarge { bits, limit: l.max_coefficient_bits }, at);
                }
                self.check(a.mul(&b), at)
            }
            Op::Div => {
                let Some(d) = b.constant_value() else {
                    return fail(ParseErrorKind::DivisionByPolynomial, rhs_at);
                };
                if d.is_zero() {
                    return fail(ParseErrorKind::DivisionByZero, rhs_at);
                }
                self.check(a.scale(&d.recip()), at)
            }
        }
    }

    fn negate(&mut self, a: SparsePoly, _: usize) -> Result<SparsePoly, ParseError> {
        Ok(a.neg())
    }

    fn power(
        &mut self,
        base: SparsePoly,
        exponent: SparsePoly,
        at: usize,
        exp_at: usize,
    ) -> Result<SparsePoly, ParseError> {
        let Some(e) = exponent.constant_value() else {
            return fail(ParseErrorKind::NonIntegerExponent, exp_at);
        };
        if !e.is_integer() {
            return fail(ParseErrorKind::NonIntegerExponent, exp_at);
        }
        let max = self.symbols.limits.max_exponent;
        let Some(m) = e.abs().to_integer().to_u32().filter(|&m| m <= max) else {
            return fail(ParseErrorKind::ExponentTooLarge(e.to_string(), max), exp_at);
        };
        if e.is_negative() {
            let Some(c) = base.constant_value() else {
                return fail(ParseErrorKind::NegativePowerOfPolynomial, at);
            };
            if c.is_zero() {
                return fail(ParseErrorKind::ZeroToNegativePower, at);
            }
            let l = &self.symbols.limits;
            if c.size_bits().saturating_mul(m as u64) > 2 * l.max_coefficient_bits {
                return fail(
                    ParseErrorKind::CoefficientTooLarge {
                        bits: c.size_bits() * m as u64,
                        limit: l.max_coefficient_bits,
                    },
                    at,
                );
            }
            return self.check(SparsePoly::constant(base.nvars(), c.recip()).pow(m), at);
        }
        let l = &self.symbols.limits;
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
        let per_factor = base.max_bits() + (usize::BITS - base.num_terms().leading_zeros()) as u64;
        if per_factor.saturating_mul(m as u64) > 2 * l.max_coefficient_bits {
            return fail(
                ParseErrorKind::CoefficientTooLarge { bits: per_factor * m as u64, limit: l.max_coefficient_bits },
                at,
            );
        }
        let terms_bound = (0..m).fold(1usize, |acc, _| acc.saturating_mul(base.num_terms().max(1)));
        if terms_bound > l.max_terms.saturating_mul(4) && base.num_terms() > 1 {
            return fail(
                ParseErrorKind::TooLarge {
                    degree,
                    max_degree: l.max_degree,
                    terms: terms_bound,
                    max_terms: l.max_terms,
                },
                at,
            );
        }
        self.check(base.pow(m), at)
    }
}

/// Parse an expression in the coordinates and parameters.
///
/// ```
/// use large::{parse_sparse, SparseSymbols};
/// let names: Vec<String> = (0..1500).map(|i| format!("x{i}")).collect();
/// let s = SparseSymbols::new(&names, &Default::default());
/// let p = parse_sparse("x0^2/2 + 3*x1499*x7 - 1/4", &s).unwrap();
/// assert_eq!(p.num_terms(), 3);
/// assert!(parse_sparse("x0 + y", &s).unwrap_err().to_string().contains("unknown symbol 'y'"));
/// ```
pub fn parse_sparse(text: &str, symbols: &SparseSymbols) -> Result<SparsePoly, ParseError> {
    let l = &symbols.limits;
    exact::syntax::parse(text, &mut Polynomials { symbols }, l.max_depth, l.max_length)
}
