//! The spec's expression language with the box parameters kept as
//! variables: the grammar of [`exact::syntax`], the meaning of
//! [`exact::parse_expression`], except that a box parameter is a variable
//! and division by an expression of the parameters (not of the
//! coordinates) gives a rational function ([`Frac`]).

use crate::frac::Frac;
use exact::syntax::{Op, Semantics, SyntaxError};
use exact::{parse_number, Limits, ParseError, ParseErrorKind, Poly, Rational};
use num_traits::ToPrimitive;
use std::collections::BTreeMap;

/// The names an expression may use: coordinates, box parameters (kept as
/// variables `n..n+p`) and the other parameters (their values).
#[derive(Clone, Debug)]
pub struct BoxSymbols {
    coordinates: Vec<String>,
    box_parameters: Vec<String>,
    fixed: BTreeMap<String, Rational>,
    limits: Limits,
}

impl BoxSymbols {
    /// Symbols for the coordinates, the box parameters and the fixed ones.
    pub fn new(coordinates: &[String], box_parameters: &[String], fixed: &BTreeMap<String, Rational>) -> Self {
        // The spec's limits on an expression (spec::parse), which keep
        // derivatives cheap.
        let limits = Limits { max_degree: 16, max_terms: 5000, ..Limits::default() };
        BoxSymbols {
            coordinates: coordinates.to_vec(),
            box_parameters: box_parameters.to_vec(),
            fixed: fixed.clone(),
            limits,
        }
    }

    /// Number of variables (coordinates, then box parameters).
    pub fn nvars(&self) -> usize {
        self.coordinates.len() + self.box_parameters.len()
    }

    /// Number of coordinates.
    pub fn ncoordinates(&self) -> usize {
        self.coordinates.len()
    }

    fn known(&self) -> Vec<String> {
        self.coordinates.iter().chain(&self.box_parameters).chain(self.fixed.keys()).cloned().collect()
    }
}

/// Whether a polynomial involves the first `n` variables (the coordinates).
pub fn has_coordinates(p: &Poly, n: usize) -> bool {
    p.terms().any(|(m, _)| m[..n].iter().any(|&e| e > 0))
}

struct Fractions<'a> {
    symbols: &'a BoxSymbols,
    /// Every divisor's numerator (a polynomial in the parameters), before
    /// any cancellation: where one vanishes the expression is undefined.
    divisors: Vec<Poly>,
}

fn fail<T>(kind: ParseErrorKind, position: usize) -> Result<T, ParseError> {
    Err(ParseError { kind, position })
}

impl Fractions<'_> {
    fn check(&self, f: Frac, at: usize) -> Result<Frac, ParseError> {
        let l = &self.symbols.limits;
        let polys = std::iter::once(f.num()).chain(f.den().iter().map(|(p, _)| p));
        let mut degree = 0;
        let mut terms = 0;
        let mut bits = 0;
        for p in polys {
            degree = degree.max(p.total_degree());
            terms = terms.max(p.num_terms());
            bits = bits.max(p.terms().map(|(_, c)| c.size_bits()).max().unwrap_or(1));
        }
        let exponents: u32 = f.den().iter().map(|(_, e)| *e).sum();
        if bits > l.max_coefficient_bits {
            return fail(ParseErrorKind::CoefficientTooLarge { bits, limit: l.max_coefficient_bits }, at);
        }
        if degree > l.max_degree || terms > l.max_terms || exponents > l.max_degree {
            return fail(
                ParseErrorKind::TooLarge { degree, max_degree: l.max_degree, terms, max_terms: l.max_terms },
                at,
            );
        }
        Ok(f)
    }
}

impl Semantics for Fractions<'_> {
    type Value = Frac;
    type Function = std::convert::Infallible;
    type Error = ParseError;

    fn syntax(&self, e: SyntaxError) -> ParseError {
        ParseError { kind: ParseErrorKind::Syntax(e.kind), position: e.position }
    }

    fn number(&mut self, text: &str, at: usize) -> Result<Frac, ParseError> {
        match parse_number(text) {
            Ok(v) => Ok(Frac::constant(self.symbols.nvars(), v)),
            Err(e) => fail(ParseErrorKind::BadNumber(e.to_string()), at),
        }
    }

    fn symbol(&mut self, name: &str, at: usize) -> Result<Frac, ParseError> {
        let s = self.symbols;
        let nv = s.nvars();
        if let Some(i) = s.coordinates.iter().position(|c| c == name) {
            return Ok(Frac::from_poly(Poly::var(nv, i)));
        }
        if let Some(j) = s.box_parameters.iter().position(|c| c == name) {
            return Ok(Frac::from_poly(Poly::var(nv, s.coordinates.len() + j)));
        }
        if let Some(v) = s.fixed.get(name) {
            return Ok(Frac::constant(nv, v.clone()));
        }
        fail(ParseErrorKind::UnknownSymbol { name: name.to_string(), known: s.known() }, at)
    }

    fn function(&mut self, name: &str, at: usize) -> Result<Self::Function, ParseError> {
        fail(ParseErrorKind::FunctionCall(name.to_string()), at)
    }

    fn call(&mut self, f: Self::Function, _: Frac, _: usize) -> Result<Frac, ParseError> {
        match f {}
    }

    fn binary(&mut self, op: Op, a: Frac, b: Frac, at: usize, rhs_at: usize) -> Result<Frac, ParseError> {
        let l = &self.symbols.limits;
        match op {
            Op::Add => self.check(a.add(&b), at),
            Op::Sub => self.check(a.sub(&b), at),
            Op::Mul => {
                let degree = a.num().total_degree() + b.num().total_degree();
                let terms = a.num().num_terms().saturating_mul(b.num().num_terms());
                if degree > l.max_degree || terms > l.max_terms.saturating_mul(4) {
                    return fail(
                        ParseErrorKind::TooLarge { degree, max_degree: l.max_degree, terms, max_terms: l.max_terms },
                        at,
                    );
                }
                self.check(a.mul(&b), at)
            }
            Op::Div => {
                if has_coordinates(b.num(), self.symbols.ncoordinates()) {
                    return fail(ParseErrorKind::DivisionByPolynomial, rhs_at);
                }
                self.divisors.push(b.num().clone());
                self.divisors.extend(b.den().iter().map(|(f, _)| f.clone()));
                match a.div(&b) {
                    Some(f) => self.check(f, at),
                    None => fail(ParseErrorKind::DivisionByZero, rhs_at),
                }
            }
        }
    }

    fn negate(&mut self, a: Frac, _: usize) -> Result<Frac, ParseError> {
        Ok(a.neg())
    }

    fn power(&mut self, base: Frac, exponent: Frac, at: usize, exp_at: usize) -> Result<Frac, ParseError> {
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
        let degree = base.num().total_degree().saturating_mul(m);
        if degree > self.symbols.limits.max_degree {
            return fail(
                ParseErrorKind::TooLarge {
                    degree,
                    max_degree: self.symbols.limits.max_degree,
                    terms: base.num().num_terms(),
                    max_terms: self.symbols.limits.max_terms,
                },
                at,
            );
        }
        if e.is_negative() {
            if has_coordinates(base.num(), self.symbols.ncoordinates()) {
                return fail(ParseErrorKind::NegativePowerOfPolynomial, at);
            }
            self.divisors.push(base.num().clone());
            self.divisors.extend(base.den().iter().map(|(f, _)| f.clone()));
            let one = Frac::constant(self.symbols.nvars(), Rational::from(1));
            return match one.div(&base) {
                Some(r) => self.check(r.pow(m), at),
                None => fail(ParseErrorKind::ZeroToNegativePower, at),
            };
        }
        self.check(base.pow(m), at)
    }
}

/// Parse `text` with the box parameters as variables.
///
/// ```
/// use boxes::{parse_box_expression, BoxSymbols};
/// use exact::Rational;
/// use std::collections::BTreeMap;
/// let mut fixed = BTreeMap::new();
/// fixed.insert("I3".to_string(), Rational::from(1));
/// let s = BoxSymbols::new(&["Pi1".into(), "Pi2".into()], &["I1".into()], &fixed);
/// let h = parse_box_expression("Pi1^2/(2*I1) + Pi2^2/(2*I3)", &s).unwrap();
/// // at Pi = (1, 1), I1 = 4: 1/8 + 1/2
/// let at = [Rational::from(1), Rational::from(1), Rational::from(4)];
/// assert_eq!(h.eval(&at), Some(Rational::new(5.into(), 8.into())));
/// assert!(parse_box_expression("1/Pi1", &s).is_err());
/// ```
pub fn parse_box_expression(text: &str, symbols: &BoxSymbols) -> Result<Frac, ParseError> {
    parse_box_expression_with_divisors(text, symbols).map(|(f, _)| f)
}

/// [`parse_box_expression`], with the numerators of every divisor met on
/// the way (before any cancellation: `q/q` is 1 but undefined at `q = 0`).
pub fn parse_box_expression_with_divisors(text: &str, symbols: &BoxSymbols) -> Result<(Frac, Vec<Poly>), ParseError> {
    let l = &symbols.limits;
    let mut semantics = Fractions { symbols, divisors: vec![] };
    let f = exact::syntax::parse(text, &mut semantics, l.max_depth, l.max_length)?;
    Ok((f, semantics.divisors))
}
