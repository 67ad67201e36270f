//! Sparse polynomials with exact rational coefficients, for systems with
//! thousands of coordinates.
//!
//! The exact engine's [`exact::Poly`] stores every exponent of every
//! variable in each monomial, which suits its algebras of at most 64
//! coordinates; at 1,500 coordinates a sum of a few thousand terms would
//! cost billions of operations to build. Here a monomial lists only its
//! variables with nonzero exponents, sorted, and the terms live in a
//! `BTreeMap` (deterministic order, `O(log n)` insertion).

use exact::Rational;
use num_traits::Zero;
use std::collections::BTreeMap;

/// A monomial: `(variable, exponent)` pairs, sorted by variable, exponents
/// positive.
pub type SparseMonomial = Vec<(u32, u16)>;

/// A polynomial in `nvars` variables with rational coefficients.
///
/// ```
/// use large::SparsePoly;
/// use exact::Rational;
/// let n = 1000;
/// let x = SparsePoly::var(n, 3);
/// let y = SparsePoly::var(n, 998);
/// let p = x.mul(&y).add(&x.scale(&Rational::from(2)));
/// assert_eq!(p.num_terms(), 2);
/// assert_eq!(p.total_degree(), 2);
/// let at = |i: usize| if i == 3 { 2.0 } else if i == 998 { 5.0 } else { 0.0 };
/// let point: Vec<f64> = (0..n).map(at).collect();
/// assert_eq!(p.eval_f64(&point), 14.0);
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SparsePoly {
    nvars: usize,
    terms: BTreeMap<SparseMonomial, Rational>,
}

fn monomial_product(a: &SparseMonomial, b: &SparseMonomial) -> SparseMonomial {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() || j < b.len() {
        if j == b.len() || (i < a.len() && a[i].0 < b[j].0) {
            out.push(a[i]);
            i += 1;
        } else if i == a.len() || b[j].0 < a[i].0 {
            out.push(b[j]);
            j += 1;
        } else {
            out.push((a[i].0, a[i].1.saturating_add(b[j].1)));
            i += 1;
            j += 1;
        }
    }
    out
}

impl SparsePoly {
    /// The zero polynomial.
    pub fn zero(nvars: usize) -> Self {
        SparsePoly { nvars, terms: BTreeMap::new() }
    }

    /// A constant.
    pub fn constant(nvars: usize, c: Rational) -> Self {
        let mut p = Self::zero(nvars);
        if !c.is_zero() {
            p.terms.insert(vec![], c);
        }
        p
    }

    /// The variable `x_i`.
    ///
    /// # Panics
    /// If `i >= nvars`.
    pub fn var(nvars: usize, i: usize) -> Self {
        assert!(i < nvars, "variable index out of range");
        let mut p = Self::zero(nvars);
        p.terms.insert(vec![(i as u32, 1)], Rational::from(1));
        p
    }

    /// The same polynomial from the exact engine's dense-monomial form.
    ///
    /// ```
    /// let s = exact::Symbols::new(&["x", "y"]);
    /// let p = exact::parse_expression("x^2*y - 3/4", &s).unwrap();
    /// let q = large::SparsePoly::from_poly(&p);
    /// assert_eq!(q.num_terms(), 2);
    /// assert_eq!(q.eval_f64(&[2.0, 3.0]), 11.25);
    /// ```
    pub fn from_poly(p: &exact::Poly) -> SparsePoly {
        let mut out = Self::zero(p.nvars());
        for (m, c) in p.terms() {
            let sparse: SparseMonomial =
                m.iter().enumerate().filter(|(_, e)| **e > 0).map(|(i, e)| (i as u32, *e)).collect();
            out.add_term(sparse, c.clone());
        }
        out
    }

    /// Number of variables.
    pub fn nvars(&self) -> usize {
        self.nvars
    }

    /// Number of nonzero terms.
    pub fn num_terms(&self) -> usize {
        self.terms.len()
    }

    /// The terms, in a fixed order.
    pub fn terms(&self) -> impl Iterator<Item = (&SparseMonomial, &Rational)> {
        self.terms.iter()
    }

    /// Whether it is the zero polynomial.
    pub fn is_zero(&self) -> bool {
        self.terms.is_empty()
    }

    /// The value if constant.
    pub fn constant_value(&self) -> Option<Rational> {
        match self.terms.len() {
            0 => Some(Rational::zero()),
            1 => self.terms.get(&vec![]).cloned(),
            _ => None,
        }
    }

    /// The largest total degree (0 for constants and zero).
    pub fn total_degree(&self) -> u32 {
        self.terms.keys().map(|m| m.iter().map(|(_, e)| *e as u32).sum::<u32>()).max().unwrap_or(0)
    }

    /// The largest coefficient size in bits.
    pub fn max_bits(&self) -> u64 {
        self.terms.values().map(Rational::size_bits).max().unwrap_or(1)
    }

    fn add_term(&mut self, m: SparseMonomial, c: Rational) {
        if c.is_zero() {
            return;
        }
        match self.terms.entry(m) {
            std::collections::btree_map::Entry::Vacant(v) => {
                v.insert(c);
            }
            std::collections::btree_map::Entry::Occupied(mut o) => {
                let s = o.get() + &c;
                if s.is_zero() {
                    o.remove();
                } else {
                    *o.get_mut() = s;
                }
            }
        }
    }

    /// `self + other`.
    pub fn add(&self, other: &SparsePoly) -> SparsePoly {
        let (mut big, small) =
            if self.terms.len() >= other.terms.len() { (self.clone(), other) } else { (other.clone(), self) };
        for (m, c) in &small.terms {
            big.add_term(m.clone(), c.clone());
        }
        big
    }

    /// `self - other`.
    pub fn sub(&self, other: &SparsePoly) -> SparsePoly {
        self.add(&other.neg())
    }

    /// `-self`.
    pub fn neg(&self) -> SparsePoly {
        SparsePoly { nvars: self.nvars, terms: self.terms.iter().map(|(m, c)| (m.clone(), -c.clone())).collect() }
    }

    /// `s * self`.
    pub fn scale(&self, s: &Rational) -> SparsePoly {
        if s.is_zero() {
            return Self::zero(self.nvars);
        }
        SparsePoly { nvars: self.nvars, terms: self.terms.iter().map(|(m, c)| (m.clone(), c * s)).collect() }
    }

    /// `self * other`.
    pub fn mul(&self, other: &SparsePoly) -> SparsePoly {
        let mut out = Self::zero(self.nvars);
        for (ma, ca) in &self.terms {
            for (mb, cb) in &other.terms {
                out.add_term(monomial_product(ma, mb), ca * cb);
            }
        }
        out
    }

    /// `self^e` by repeated squaring.
    pub fn pow(&self, mut e: u32) -> SparsePoly {
        let mut base = self.clone();
        let mut acc = Self::constant(self.nvars, Rational::from(1));
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

    /// `d/dx_i`.
    pub fn derivative(&self, i: usize) -> SparsePoly {
        let mut out = Self::zero(self.nvars);
        for (m, c) in &self.terms {
            if let Some(pos) = m.iter().position(|(v, _)| *v as usize == i) {
                let e = m[pos].1;
                let mut d = m.clone();
                if e == 1 {
                    d.remove(pos);
                } else {
                    d[pos].1 = e - 1;
                }
                out.add_term(d, c * &Rational::from(e as i64));
            }
        }
        out
    }

    /// The variables that occur.
    pub fn variables(&self) -> Vec<usize> {
        let mut v: Vec<usize> = self.terms.keys().flat_map(|m| m.iter().map(|(i, _)| *i as usize)).collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// The value at a rational point, exactly.
    pub fn eval(&self, x: &[Rational]) -> Rational {
        let mut s = Rational::zero();
        for (m, c) in &self.terms {
            let mut t = c.clone();
            for (i, e) in m {
                for _ in 0..*e {
                    t = &t * &x[*i as usize];
                }
            }
            s += t;
        }
        s
    }

    /// The value at a point in floating point.
    pub fn eval_f64(&self, x: &[f64]) -> f64 {
        self.terms
            .iter()
            .map(|(m, c)| {
                exact::rational_to_f64(c) * m.iter().map(|(i, e)| x[*i as usize].powi(*e as i32)).product::<f64>()
            })
            .sum()
    }

    /// The gradient at a rational point, exactly, as `(variable, value)` for
    /// the nonzero entries.
    pub fn gradient_at(&self, x: &[Rational]) -> BTreeMap<usize, Rational> {
        let mut g: BTreeMap<usize, Rational> = BTreeMap::new();
        for (m, c) in &self.terms {
            for (k, (i, e)) in m.iter().enumerate() {
                // c * e * x_i^(e-1) * prod_{others} x_j^e_j
                let mut t = c * &Rational::from(*e as i64);
                for (l, (j, f)) in m.iter().enumerate() {
                    let power = if l == k { f - 1 } else { *f };
                    for _ in 0..power {
                        t = &t * &x[*j as usize];
                    }
                }
                if !t.is_zero() {
                    let entry = g.entry(*i as usize).or_insert_with(Rational::zero);
                    *entry += t;
                }
            }
        }
        g.retain(|_, v| !v.is_zero());
        g
    }

    /// The Hessian at a rational point, exactly, as `(i, j) -> value` with
    /// `i <= j` (each symmetric pair once; the diagonal once), the nonzero
    /// entries only.
    ///
    /// ```
    /// use large::SparsePoly;
    /// use exact::Rational;
    /// // p = x0^2 x1 / 3 at (2, 5): d00 = 2 x1 / 3 = 10/3, d01 = 2 x0 / 3 = 4/3, d11 = 0
    /// let (x0, x1) = (SparsePoly::var(2, 0), SparsePoly::var(2, 1));
    /// let p = x0.mul(&x0).mul(&x1).scale(&Rational::new_small(1, 3));
    /// let h = p.hessian_at(&[Rational::from(2), Rational::from(5)]);
    /// assert_eq!(h[&(0, 0)], Rational::new_small(10, 3));
    /// assert_eq!(h[&(0, 1)], Rational::new_small(4, 3));
    /// assert_eq!(h.len(), 2);
    /// ```
    pub fn hessian_at(&self, x: &[Rational]) -> BTreeMap<(usize, usize), Rational> {
        let mut h: BTreeMap<(usize, usize), Rational> = BTreeMap::new();
        for (m, c) in &self.terms {
            for (k, (i, ei)) in m.iter().enumerate() {
                for (l, (j, ej)) in m.iter().enumerate().skip(k) {
                    let factor = if k == l {
                        if *ei < 2 {
                            continue;
                        }
                        i64::from(*ei) * (i64::from(*ei) - 1)
                    } else {
                        i64::from(*ei) * i64::from(*ej)
                    };
                    let mut t = c * &Rational::from(factor);
                    for (q, (v, f)) in m.iter().enumerate() {
                        let power = i64::from(*f) - i64::from(q == k) - i64::from(q == l);
                        for _ in 0..power {
                            t = &t * &x[*v as usize];
                        }
                    }
                    if !t.is_zero() {
                        *h.entry((*i as usize, *j as usize)).or_insert_with(Rational::zero) += t;
                    }
                }
            }
        }
        h.retain(|_, v| !v.is_zero());
        h
    }

    /// The Hessian at a point in floating point, as `(i, j, value)` with
    /// `i <= j` (each symmetric pair once; the diagonal once).
    pub fn hessian_at_f64(&self, x: &[f64]) -> BTreeMap<(usize, usize), f64> {
        let mut h: BTreeMap<(usize, usize), f64> = BTreeMap::new();
        for (m, c) in &self.terms {
            let c = exact::rational_to_f64(c);
            for (k, (i, ei)) in m.iter().enumerate() {
                for (l, (j, ej)) in m.iter().enumerate().skip(k) {
                    let mut t = c;
                    if k == l {
                        if *ei < 2 {
                            continue;
                        }
                        t *= (*ei as f64) * (*ei as f64 - 1.0);
                    } else {
                        t *= (*ei as f64) * (*ej as f64);
                    }
                    for (q, (v, f)) in m.iter().enumerate() {
                        let power = *f as i32 - (q == k) as i32 - (q == l) as i32;
                        t *= x[*v as usize].powi(power);
                    }
                    *h.entry((*i as usize, *j as usize)).or_insert(0.0) += t;
                }
            }
        }
        h
    }
}
