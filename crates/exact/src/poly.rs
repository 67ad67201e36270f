//! Sparse multivariate polynomials with exact rational coefficients.

use crate::number::{one, rational_to_f64, Rational};
use num_traits::{One, Zero};
use smallvec::{smallvec, SmallVec};
use std::fmt::Write as _;

/// Exponent vector of a monomial: `x_0^e_0 x_1^e_1 ...`, stored inline for up
/// to eight variables so that building and comparing monomials of the
/// engine's small algebras does not allocate.
pub type Monomial = SmallVec<[u16; 8]>;

/// A polynomial in a fixed number of variables with rational coefficients.
///
/// Terms are kept in a vector sorted by monomial (lexicographic order on the
/// exponents), without zero coefficients, so iteration order (and hence
/// printing and certificates) is deterministic and sums are linear merges.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Poly {
    nvars: usize,
    terms: Vec<(Monomial, Rational)>,
}

/// First and second derivatives at a point in floating point
/// ([`Poly::derivatives_at_f64`]), with the sums of the magnitudes of the
/// terms behind each entry.
#[derive(Clone, Debug, PartialEq)]
pub struct Derivatives {
    /// The gradient.
    pub gradient: Vec<f64>,
    /// The Hessian, row-major `n x n`.
    pub hessian: Vec<f64>,
    /// `sum |term|` of each gradient entry.
    pub gradient_size: Vec<f64>,
    /// `sum |term|` of each Hessian entry.
    pub hessian_size: Vec<f64>,
}

impl Poly {
    /// The zero polynomial in `nvars` variables.
    pub fn zero(nvars: usize) -> Self {
        Poly { nvars, terms: Vec::new() }
    }

    /// A constant.
    pub fn constant(nvars: usize, c: Rational) -> Self {
        let mut p = Self::zero(nvars);
        if !c.is_zero() {
            p.terms.push((smallvec![0; nvars], c));
        }
        p
    }

    /// The variable `x_i`.
    ///
    /// # Panics
    /// If `i >= nvars`.
    pub fn var(nvars: usize, i: usize) -> Self {
        assert!(i < nvars, "variable index out of range");
        let mut m: Monomial = smallvec![0; nvars];
        m[i] = 1;
        Poly { nvars, terms: vec![(m, one())] }
    }

    /// A single term `c x^m`.
    pub fn monomial(c: Rational, m: Monomial) -> Self {
        let nvars = m.len();
        let mut p = Self::zero(nvars);
        if !c.is_zero() {
            p.terms.push((m, c));
        }
        p
    }

    /// The linear form `sum_i c_i x_i`.
    pub fn linear(coefficients: &[Rational]) -> Self {
        let n = coefficients.len();
        let mut p = Self::zero(n);
        // x_0 > x_1 > ... in lexicographic order of exponents, so push in reverse.
        for (i, c) in coefficients.iter().enumerate().rev() {
            if !c.is_zero() {
                let mut m: Monomial = smallvec![0; n];
                m[i] = 1;
                p.terms.push((m, c.clone()));
            }
        }
        p
    }

    /// Number of variables.
    pub fn nvars(&self) -> usize {
        self.nvars
    }

    /// Number of nonzero terms.
    pub fn num_terms(&self) -> usize {
        self.terms.len()
    }

    /// The terms, in a deterministic order.
    pub fn terms(&self) -> impl Iterator<Item = (&Monomial, &Rational)> {
        self.terms.iter().map(|(m, c)| (m, c))
    }

    /// Whether this is the zero polynomial.
    pub fn is_zero(&self) -> bool {
        self.terms.is_empty()
    }

    /// The value if the polynomial is a constant, else `None`.
    pub fn constant_value(&self) -> Option<Rational> {
        match self.terms.len() {
            0 => Some(Rational::zero()),
            1 => {
                let (m, c) = self.terms.first()?;
                m.iter().all(|&e| e == 0).then(|| c.clone())
            }
            _ => None,
        }
    }

    /// Total degree (`0` for constants and for the zero polynomial).
    pub fn total_degree(&self) -> u32 {
        self.terms.iter().map(|(m, _)| m.iter().map(|&e| e as u32).sum()).max().unwrap_or(0)
    }

    /// The coefficient of a monomial.
    pub fn coefficient(&self, m: &[u16]) -> Rational {
        match self.terms.binary_search_by(|(x, _)| x.as_slice().cmp(m)) {
            Ok(i) => self.terms[i].1.clone(),
            Err(_) => Rational::zero(),
        }
    }

    /// Sorted merge of two term lists with `sign` applied to the second.
    fn merge(&self, other: &Poly, negate: bool) -> Poly {
        assert_eq!(self.nvars, other.nvars);
        let mut out = Vec::with_capacity(self.terms.len() + other.terms.len());
        let (mut i, mut j) = (0, 0);
        let (a, b) = (&self.terms, &other.terms);
        let sign = |c: &Rational| if negate { -c } else { c.clone() };
        while i < a.len() && j < b.len() {
            match a[i].0.cmp(&b[j].0) {
                std::cmp::Ordering::Less => {
                    out.push(a[i].clone());
                    i += 1;
                }
                std::cmp::Ordering::Greater => {
                    out.push((b[j].0.clone(), sign(&b[j].1)));
                    j += 1;
                }
                std::cmp::Ordering::Equal => {
                    let c = if negate { &a[i].1 - &b[j].1 } else { &a[i].1 + &b[j].1 };
                    if !c.is_zero() {
                        out.push((a[i].0.clone(), c));
                    }
                    i += 1;
                    j += 1;
                }
            }
        }
        out.extend(a[i..].iter().cloned());
        out.extend(b[j..].iter().map(|(m, c)| (m.clone(), sign(c))));
        Poly { nvars: self.nvars, terms: out }
    }

    /// Sort and combine an unsorted list of terms.
    fn from_unsorted(nvars: usize, mut terms: Vec<(Monomial, Rational)>) -> Poly {
        terms.sort_unstable_by(|x, y| x.0.cmp(&y.0));
        let mut out: Vec<(Monomial, Rational)> = Vec::with_capacity(terms.len());
        for (m, c) in terms {
            match out.last_mut() {
                Some((lm, lc)) if *lm == m => *lc += c,
                _ => out.push((m, c)),
            }
        }
        out.retain(|(_, c)| !c.is_zero());
        Poly { nvars, terms: out }
    }

    /// Sum.
    pub fn add(&self, other: &Poly) -> Poly {
        self.merge(other, false)
    }

    /// Difference.
    pub fn sub(&self, other: &Poly) -> Poly {
        self.merge(other, true)
    }

    /// Negation.
    pub fn neg(&self) -> Poly {
        Poly { nvars: self.nvars, terms: self.terms.iter().map(|(m, c)| (m.clone(), -c)).collect() }
    }

    /// Multiply by a rational.
    pub fn scale(&self, s: &Rational) -> Poly {
        if s.is_zero() {
            return Poly::zero(self.nvars);
        }
        Poly { nvars: self.nvars, terms: self.terms.iter().map(|(m, c)| (m.clone(), c * s)).collect() }
    }

    /// Product.
    pub fn mul(&self, other: &Poly) -> Poly {
        assert_eq!(self.nvars, other.nvars);
        if self.terms.is_empty() || other.terms.is_empty() {
            return Poly::zero(self.nvars);
        }
        let mut terms = Vec::with_capacity(self.terms.len() * other.terms.len());
        for (m1, c1) in &self.terms {
            for (m2, c2) in &other.terms {
                let m: Monomial = m1.iter().zip(m2).map(|(a, b)| a.saturating_add(*b)).collect();
                terms.push((m, c1 * c2));
            }
        }
        Poly::from_unsorted(self.nvars, terms)
    }

    /// Power by repeated squaring.
    pub fn pow(&self, mut e: u32) -> Poly {
        let mut base = self.clone();
        let mut acc = Poly::constant(self.nvars, one());
        while e > 0 {
            if e & 1 == 1 {
                acc = acc.mul(&base);
            }
            e >>= 1;
            if e > 0 {
                base = base.mul(&base);
            }
        }
        acc
    }

    /// Partial derivative with respect to `x_i`.
    pub fn derivative(&self, i: usize) -> Poly {
        // Decrementing one exponent keeps the lexicographic order and is
        // injective on the terms that survive, so no re-sorting is needed.
        let terms = self
            .terms
            .iter()
            .filter(|(m, _)| m[i] > 0)
            .map(|(m, c)| {
                let mut m2 = m.clone();
                m2[i] -= 1;
                (m2, c * Rational::from(m[i] as i64))
            })
            .collect();
        Poly { nvars: self.nvars, terms }
    }

    /// The gradient `(∂_0 p, ..., ∂_{n-1} p)`.
    pub fn gradient(&self) -> Vec<Poly> {
        (0..self.nvars).map(|i| self.derivative(i)).collect()
    }

    /// The Hessian `∂_i ∂_j p`.
    pub fn hessian(&self) -> Vec<Vec<Poly>> {
        let g = self.gradient();
        g.iter().map(|gi| (0..self.nvars).map(|j| gi.derivative(j)).collect()).collect()
    }

    /// The gradient evaluated at a rational point, without forming the
    /// derivative polynomials.
    pub fn gradient_at(&self, x: &[Rational]) -> Vec<Rational> {
        assert_eq!(x.len(), self.nvars);
        let mut g = vec![Rational::zero(); self.nvars];
        for (m, c) in &self.terms {
            for i in 0..self.nvars {
                if m[i] == 0 {
                    continue;
                }
                let mut t = c * Rational::from(m[i] as i64);
                for (k, &e) in m.iter().enumerate() {
                    let e = if k == i { e - 1 } else { e };
                    if e > 0 {
                        t *= x[k].pow(e as u32);
                    }
                }
                g[i] += t;
            }
        }
        g
    }

    /// The Hessian evaluated at a rational point, without forming the
    /// derivative polynomials.
    pub fn hessian_at(&self, x: &[Rational]) -> Vec<Vec<Rational>> {
        assert_eq!(x.len(), self.nvars);
        let n = self.nvars;
        let mut h = vec![vec![Rational::zero(); n]; n];
        let mut reduced: Monomial = smallvec![0; n];
        for (m, c) in &self.terms {
            for i in 0..n {
                if m[i] == 0 {
                    continue;
                }
                for j in i..n {
                    let factor = if i == j { m[i] as i64 * (m[i] as i64 - 1) } else { m[i] as i64 * m[j] as i64 };
                    if factor == 0 {
                        continue;
                    }
                    reduced.copy_from_slice(m);
                    reduced[i] -= 1;
                    reduced[j] -= 1;
                    let mut t = c * Rational::from(factor);
                    for (k, &e) in reduced.iter().enumerate() {
                        if e > 0 {
                            if x[k].is_zero() {
                                t = Rational::zero();
                                break;
                            }
                            t *= x[k].pow(e as u32);
                        }
                    }
                    if !t.is_zero() {
                        h[i][j] += &t;
                        if i != j {
                            h[j][i] += t;
                        }
                    }
                }
            }
        }
        h
    }

    /// The gradient and the Hessian (row-major, `n x n`) at a point, in
    /// floating point, without forming the derivative polynomials: the
    /// floating-point counterpart of [`Self::gradient_at`] and
    /// [`Self::hessian_at`] for the engine's numeric level. With each, the
    /// sum of the magnitudes of its terms (`Derivatives::gradient_size`,
    /// `hessian_size`): the rounding of an entry is a small multiple of
    /// `eps` times that size, so an entry that is zero exactly but not in
    /// floating point (terms that cancel) can be told from a small one.
    ///
    /// ```
    /// use exact::{parse_expression, Symbols};
    /// let s = Symbols::new(&["x".to_string(), "y".to_string()]);
    /// let p = parse_expression("x^2*y + y^3/3", &s).unwrap();
    /// let d = p.derivatives_at_f64(&[2.0, 3.0]);
    /// // d/dx = 2xy = 12, d/dy = x^2 + y^2 = 13; Hessian [[2y, 2x], [2x, 2y]]
    /// assert_eq!(d.gradient, vec![12.0, 13.0]);
    /// assert_eq!(d.hessian, vec![6.0, 4.0, 4.0, 6.0]);
    /// // x^2 - 2x at x = 1: the gradient's terms 2 and -2 cancel
    /// let q = parse_expression("x^2 - 2*x", &s).unwrap().derivatives_at_f64(&[1.0, 0.0]);
    /// assert_eq!((q.gradient[0], q.gradient_size[0]), (0.0, 4.0));
    /// ```
    pub fn derivatives_at_f64(&self, x: &[f64]) -> Derivatives {
        assert_eq!(x.len(), self.nvars);
        let n = self.nvars;
        let mut d = Derivatives {
            gradient: vec![0.0; n],
            hessian: vec![0.0; n * n],
            gradient_size: vec![0.0; n],
            hessian_size: vec![0.0; n * n],
        };
        // x_k^e, with x^0 = 1 also for x = 0.
        let power = |k: usize, e: u16| if e == 0 { 1.0 } else { x[k].powi(e as i32) };
        for (m, c) in &self.terms {
            let c = rational_to_f64(c);
            for i in 0..n {
                if m[i] == 0 {
                    continue;
                }
                let mut t = c * m[i] as f64;
                for (k, &e) in m.iter().enumerate() {
                    t *= power(k, if k == i { e - 1 } else { e });
                }
                d.gradient[i] += t;
                d.gradient_size[i] += t.abs();
                for j in i..n {
                    let factor = if i == j { m[i] as f64 * (m[i] as f64 - 1.0) } else { m[i] as f64 * m[j] as f64 };
                    if factor == 0.0 {
                        continue;
                    }
                    let mut t = c * factor;
                    for (k, &e) in m.iter().enumerate() {
                        let e = e - u16::from(k == i) - u16::from(k == j);
                        t *= power(k, e);
                    }
                    d.hessian[i * n + j] += t;
                    d.hessian_size[i * n + j] += t.abs();
                    if i != j {
                        d.hessian[j * n + i] += t;
                        d.hessian_size[j * n + i] += t.abs();
                    }
                }
            }
        }
        d
    }

    /// Exact value at a rational point.
    pub fn eval(&self, x: &[Rational]) -> Rational {
        assert_eq!(x.len(), self.nvars);
        let mut s = Rational::zero();
        for (m, c) in &self.terms {
            let mut t = c.clone();
            for (xi, &e) in x.iter().zip(m) {
                if e > 0 {
                    if xi.is_zero() {
                        t = Rational::zero();
                        break;
                    }
                    t *= xi.pow(e as u32);
                }
            }
            s += t;
        }
        s
    }

    /// Value in floating point.
    pub fn eval_f64(&self, x: &[f64]) -> f64 {
        assert_eq!(x.len(), self.nvars);
        self.terms
            .iter()
            .map(|(m, c)| rational_to_f64(c) * m.iter().zip(x).map(|(&e, &xi)| xi.powi(e as i32)).product::<f64>())
            .sum()
    }

    /// Human-readable form using the given variable names, e.g.
    /// `1/2*Pi1^2 + 1/4*Pi2^2`.
    pub fn to_string_with(&self, names: &[String]) -> String {
        if self.terms.is_empty() {
            return "0".to_string();
        }
        let mut s = String::new();
        // Print higher degree first, then by the map order.
        let mut terms: Vec<_> = self.terms.iter().map(|(m, c)| (m, c)).collect();
        // Highest degree first; within a degree, earlier variables first.
        terms.sort_by(|(a, _), (b, _)| {
            let da: u32 = a.iter().map(|&e| e as u32).sum();
            let db: u32 = b.iter().map(|&e| e as u32).sum();
            db.cmp(&da).then_with(|| b.cmp(a))
        });
        for (k, (m, c)) in terms.into_iter().enumerate() {
            let negative = c.is_negative();
            let abs = c.abs();
            if k == 0 {
                if negative {
                    s.push('-');
                }
            } else {
                s.push_str(if negative { " - " } else { " + " });
            }
            let vars: Vec<String> = m
                .iter()
                .enumerate()
                .filter(|(_, &e)| e > 0)
                .map(|(i, &e)| if e == 1 { names[i].clone() } else { format!("{}^{}", names[i], e) })
                .collect();
            if vars.is_empty() {
                let _ = write!(s, "{abs}");
            } else if abs.is_one() {
                s.push_str(&vars.join("*"));
            } else {
                let _ = write!(s, "{}*{}", abs, vars.join("*"));
            }
        }
        s
    }
}

/// The number of monomials of degree exactly `d` in `n` variables,
/// `C(n + d - 1, d)`, saturating at `u128::MAX`: what
/// [`monomials_of_degree`] would list, counted without listing it (60
/// variables of degree 8 are 6.5e9 monomials). Monomials of degree *at most*
/// `d` in `n` variables are `monomial_count(n + 1, d)`.
///
/// ```
/// // x^2, y^2, z^2, xy, xz, yz
/// assert_eq!(exact::monomial_count(3, 2), 6);
/// assert_eq!(exact::monomial_count(3, 2) as usize, exact::monomials_of_degree(3, 2).len());
/// // C(67, 8) = 6,522,361,560 (Python's math.comb)
/// assert_eq!(exact::monomial_count(60, 8), 6_522_361_560);
/// assert_eq!(exact::monomial_count(64, 200), u128::MAX);
/// ```
pub fn monomial_count(n: usize, d: u32) -> u128 {
    if n == 0 {
        return u128::from(d == 0);
    }
    let mut c: u128 = 1;
    for i in 1..=d as u128 {
        // c * (n - 1 + i) / i stays an integer at every step
        match c.checked_mul(n as u128 - 1 + i) {
            Some(v) => c = v / i,
            None => return u128::MAX,
        }
    }
    c
}

/// All exponent vectors of total degree `d` in `n` variables, in a fixed order.
pub fn monomials_of_degree(n: usize, d: u16) -> Vec<Monomial> {
    fn rec(n: usize, d: u16, i: usize, cur: &mut Monomial, out: &mut Vec<Monomial>) {
        if i == n - 1 {
            cur[i] = d;
            out.push(cur.clone());
            cur[i] = 0;
            return;
        }
        for e in (0..=d).rev() {
            cur[i] = e;
            rec(n, d - e, i + 1, cur, out);
        }
        cur[i] = 0;
    }
    let mut out = Vec::new();
    if n == 0 {
        if d == 0 {
            out.push(Monomial::new());
        }
        return out;
    }
    let mut cur: Monomial = smallvec![0; n];
    rec(n, d, 0, &mut cur, &mut out);
    out
}

impl Poly {
    /// All exponent vectors of total degree `d` in `n` variables.
    pub fn monomials_of_degree(n: usize, d: u16) -> Vec<Monomial> {
        monomials_of_degree(n, d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn q(n: i64) -> Rational {
        Rational::from_integer(n.into())
    }

    #[test]
    fn product_and_derivative() {
        let x = Poly::var(2, 0);
        let y = Poly::var(2, 1);
        let p = x.add(&y).pow(2); // x^2 + 2xy + y^2
        assert_eq!(p.coefficient(&[1, 1]), q(2));
        assert_eq!(p.derivative(0), x.scale(&q(2)).add(&y.scale(&q(2))));
        assert_eq!(p.eval(&[q(1), q(2)]), q(9));
        assert_eq!(p.total_degree(), 2);
    }

    #[test]
    fn cancellation_leaves_zero() {
        let x = Poly::var(1, 0);
        assert!(x.sub(&x).is_zero());
        assert_eq!(x.sub(&x).constant_value(), Some(q(0)));
    }

    #[test]
    fn monomial_count_is_binomial() {
        // C(n + d - 1, d) monomials of degree d in n variables.
        assert_eq!(monomials_of_degree(3, 2).len(), 6);
        assert_eq!(monomials_of_degree(6, 4).len(), 126);
        assert_eq!(monomials_of_degree(1, 0).len(), 1);
    }
}
