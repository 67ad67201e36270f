//! Expressions to [`SparsePoly`]: the exact engine's one parser of the
//! polynomial language ([`exact::parse_polynomial`]), with a symbol table
//! that finds a name among thousands by hashing and the exact engine's size
//! limits.

use crate::poly::SparsePoly;
use exact::{Limits, ParseError, PolynomialArithmetic, Rational, SymbolTable};
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
}

impl SymbolTable for SparseSymbols {
    fn nvars(&self) -> usize {
        self.names.len()
    }
    fn coordinate(&self, name: &str) -> Option<usize> {
        self.index.get(name).copied()
    }
    fn parameter(&self, name: &str) -> Option<&Rational> {
        self.parameters.get(name)
    }
    /// The first coordinates only (a system may have thousands), then the
    /// parameters.
    fn known_names(&self) -> Vec<String> {
        let mut known: Vec<String> = self.names.iter().take(8).cloned().collect();
        if self.names.len() > 8 {
            known.push(format!("... {} coordinates in all", self.names.len()));
        }
        known.extend(self.parameters.keys().cloned());
        known
    }
    fn limits(&self) -> &Limits {
        &self.limits
    }
}

impl PolynomialArithmetic for SparsePoly {
    fn constant(nvars: usize, c: Rational) -> Self {
        SparsePoly::constant(nvars, c)
    }
    fn var(nvars: usize, i: usize) -> Self {
        SparsePoly::var(nvars, i)
    }
    fn add(&self, other: &Self) -> Self {
        SparsePoly::add(self, other)
    }
    fn sub(&self, other: &Self) -> Self {
        SparsePoly::sub(self, other)
    }
    fn mul(&self, other: &Self) -> Self {
        SparsePoly::mul(self, other)
    }
    fn neg(&self) -> Self {
        SparsePoly::neg(self)
    }
    fn scale(&self, s: &Rational) -> Self {
        SparsePoly::scale(self, s)
    }
    fn pow(&self, e: u32) -> Self {
        SparsePoly::pow(self, e)
    }
    fn constant_value(&self) -> Option<Rational> {
        SparsePoly::constant_value(self)
    }
    fn total_degree(&self) -> u32 {
        SparsePoly::total_degree(self)
    }
    fn num_terms(&self) -> usize {
        SparsePoly::num_terms(self)
    }
    fn max_bits(&self) -> u64 {
        SparsePoly::max_bits(self)
    }
    /// `terms^m` (a monomial's power is one term): counting the monomials
    /// of the degree in thousands of variables would bound nothing.
    fn power_terms_bound(&self, m: u32, _degree: u32) -> usize {
        if self.num_terms() <= 1 {
            return 1;
        }
        (0..m).fold(1usize, |acc, _| acc.saturating_mul(self.num_terms()))
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
    exact::parse_polynomial(text, symbols)
}
