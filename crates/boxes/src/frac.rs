//! Rational functions of the box parameters, exactly.
//!
//! A [`Frac`] is `num / prod_f f^e`: a numerator polynomial in the
//! variables `(mu_0, ..., mu_{n-1}, theta_0, ..., theta_{p-1})` (coordinates
//! first, then the box parameters) and a denominator kept as a list of
//! factors in the parameters alone. The list is what makes sums cheap
//! without a multivariate gcd (which no crate offers over the rationals):
//! the common denominator of `a/f` and `b/f` is `f`, not `f^2`, because
//! equal factors are recognised by equality of their normalised
//! polynomials. A factor that is a single variable `theta_i` is cancelled
//! against the numerator whenever the numerator is divisible by it, which
//! keeps the inertia-like parameters (`Pi1^2/(2*I1)`) from piling up.
//!
//! Every value is exact. Where a denominator factor vanishes the function
//! is undefined; the proofs in [`crate::certify::prove_leaf`] show each factor has one
//! strict sign on a box before they use a value there.

use exact::{Monomial, Poly, Rational};
use num_traits::{One, Zero};

/// A rational function `num / den` with the denominator as factors.
///
/// ```
/// use boxes::Frac;
/// use exact::{Poly, Rational};
/// // in two variables (x, t): x / t + x / t = 2 x / t, with one factor t
/// let x = Frac::from_poly(Poly::var(2, 0));
/// let t = Frac::from_poly(Poly::var(2, 1));
/// let a = x.div(&t).unwrap();
/// let s = a.add(&a);
/// assert_eq!(s.den().len(), 1);
/// assert_eq!(s.eval(&[Rational::from(3), Rational::from(2)]), Some(Rational::from(3)));
/// // t * (x / t) = x: the variable factor cancels
/// assert!(a.mul(&t).den().is_empty());
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Frac {
    num: Poly,
    den: Vec<(Poly, u32)>,
}

/// The leading coefficient: that of the largest monomial (the terms are
/// sorted, so the last).
fn leading(p: &Poly) -> Option<Rational> {
    p.terms().last().map(|(_, c)| c.clone())
}

/// `p = c * prod f^e` with each `f` monic (leading coefficient 1), a
/// monomial split into its variables. `p` must not be zero.
fn factorise(p: &Poly) -> (Rational, Vec<(Poly, u32)>) {
    let c = leading(p).expect("a nonzero polynomial");
    let nv = p.nvars();
    if p.num_terms() == 1 {
        let (m, _) = p.terms().next().expect("one term");
        let factors =
            m.iter().enumerate().filter(|(_, e)| **e > 0).map(|(i, e)| (Poly::var(nv, i), *e as u32)).collect();
        return (c, factors);
    }
    let monic = p.scale(&c.recip());
    (c, vec![(monic, 1)])
}

/// The product of the factors.
fn product(nv: usize, factors: &[(Poly, u32)]) -> Poly {
    factors.iter().fold(Poly::constant(nv, Rational::one()), |acc, (f, e)| acc.mul(&f.pow(*e)))
}

/// The single variable a factor is, if it is one.
fn variable_of(f: &Poly) -> Option<usize> {
    if f.num_terms() != 1 {
        return None;
    }
    let (m, c) = f.terms().next()?;
    if !c.is_one() || m.iter().map(|&e| e as u32).sum::<u32>() != 1 {
        return None;
    }
    m.iter().position(|&e| e == 1)
}

/// `p / x_i` if every term of `p` has `x_i`.
fn divide_by_variable(p: &Poly, i: usize) -> Option<Poly> {
    if p.is_zero() || p.terms().any(|(m, _)| m[i] == 0) {
        return None;
    }
    let nv = p.nvars();
    let mut out = Poly::zero(nv);
    for (m, c) in p.terms() {
        let mut m2: Monomial = m.clone();
        m2[i] -= 1;
        out = out.add(&Poly::monomial(c.clone(), m2));
    }
    Some(out)
}

fn merge_max(a: &[(Poly, u32)], b: &[(Poly, u32)]) -> Vec<(Poly, u32)> {
    let mut out: Vec<(Poly, u32)> = a.to_vec();
    for (f, e) in b {
        match out.iter_mut().find(|(g, _)| g == f) {
            Some((_, x)) => *x = (*x).max(*e),
            None => out.push((f.clone(), *e)),
        }
    }
    out
}

fn merge_add(a: &[(Poly, u32)], b: &[(Poly, u32)]) -> Vec<(Poly, u32)> {
    let mut out: Vec<(Poly, u32)> = a.to_vec();
    for (f, e) in b {
        match out.iter_mut().find(|(g, _)| g == f) {
            Some((_, x)) => *x += *e,
            None => out.push((f.clone(), *e)),
        }
    }
    out
}

/// `lcm / part` as a polynomial (every factor of `part` is in `lcm` with at
/// least its exponent).
fn cofactor(nv: usize, lcm: &[(Poly, u32)], part: &[(Poly, u32)]) -> Poly {
    let rest: Vec<(Poly, u32)> = lcm
        .iter()
        .map(|(f, e)| {
            let used = part.iter().find(|(g, _)| g == f).map_or(0, |(_, x)| *x);
            (f.clone(), e - used)
        })
        .filter(|(_, e)| *e > 0)
        .collect();
    product(nv, &rest)
}

impl Frac {
    /// The polynomial `p` (denominator 1).
    pub fn from_poly(p: Poly) -> Self {
        Frac { num: p, den: vec![] }
    }

    /// The constant `c` in `nv` variables.
    pub fn constant(nv: usize, c: Rational) -> Self {
        Frac::from_poly(Poly::constant(nv, c))
    }

    /// Zero in `nv` variables.
    pub fn zero(nv: usize) -> Self {
        Frac::from_poly(Poly::zero(nv))
    }

    /// The numerator.
    pub fn num(&self) -> &Poly {
        &self.num
    }

    /// The denominator's factors and exponents (each factor monic, in the
    /// parameters only).
    pub fn den(&self) -> &[(Poly, u32)] {
        &self.den
    }

    /// The denominator as one polynomial.
    pub fn den_poly(&self) -> Poly {
        product(self.num.nvars(), &self.den)
    }

    /// Number of variables.
    pub fn nvars(&self) -> usize {
        self.num.nvars()
    }

    /// Whether this is identically zero.
    pub fn is_zero(&self) -> bool {
        self.num.is_zero()
    }

    /// The value if this is a constant.
    pub fn constant_value(&self) -> Option<Rational> {
        if self.den.is_empty() {
            self.num.constant_value()
        } else if self.num.is_zero() {
            Some(Rational::zero())
        } else {
            None
        }
    }

    /// Cancel variable factors the numerator is divisible by; drop the
    /// denominator of zero.
    fn reduce(mut self) -> Self {
        if self.num.is_zero() {
            self.den.clear();
            return self;
        }
        let mut k = 0;
        while k < self.den.len() {
            if let Some(i) = variable_of(&self.den[k].0) {
                while self.den[k].1 > 0 {
                    match divide_by_variable(&self.num, i) {
                        Some(q) => {
                            self.num = q;
                            self.den[k].1 -= 1;
                        }
                        None => break,
                    }
                }
            }
            if self.den[k].1 == 0 {
                self.den.remove(k);
            } else {
                k += 1;
            }
        }
        self
    }

    /// Sum.
    pub fn add(&self, o: &Frac) -> Frac {
        if o.is_zero() {
            return self.clone();
        }
        if self.is_zero() {
            return o.clone();
        }
        let nv = self.nvars();
        let lcm = merge_max(&self.den, &o.den);
        let a = self.num.mul(&cofactor(nv, &lcm, &self.den));
        let b = o.num.mul(&cofactor(nv, &lcm, &o.den));
        Frac { num: a.add(&b), den: lcm }.reduce()
    }

    /// Difference.
    pub fn sub(&self, o: &Frac) -> Frac {
        self.add(&o.neg())
    }

    /// Negation.
    pub fn neg(&self) -> Frac {
        Frac { num: self.num.neg(), den: self.den.clone() }
    }

    /// Multiply by a rational.
    pub fn scale(&self, s: &Rational) -> Frac {
        Frac { num: self.num.scale(s), den: self.den.clone() }.reduce()
    }

    /// Product.
    pub fn mul(&self, o: &Frac) -> Frac {
        if self.is_zero() || o.is_zero() {
            return Frac::zero(self.nvars());
        }
        Frac { num: self.num.mul(&o.num), den: merge_add(&self.den, &o.den) }.reduce()
    }

    /// `self / o`; `None` if `o` is identically zero. `o` must not contain
    /// the coordinates (the caller checks; a denominator is a function of
    /// the parameters alone).
    pub fn div(&self, o: &Frac) -> Option<Frac> {
        if o.is_zero() {
            return None;
        }
        let nv = self.nvars();
        let (c, factors) = factorise(&o.num);
        let num = self.num.mul(&product(nv, &o.den)).scale(&c.recip());
        Some(Frac { num, den: merge_add(&self.den, &factors) }.reduce())
    }

    /// `self^e`.
    pub fn pow(&self, e: u32) -> Frac {
        Frac { num: self.num.pow(e), den: self.den.iter().map(|(f, x)| (f.clone(), x * e)).collect() }.reduce()
    }

    /// The value at a point (all `nvars` coordinates); `None` where the
    /// denominator vanishes.
    pub fn eval(&self, x: &[Rational]) -> Option<Rational> {
        let d = self.den_poly().eval(x);
        if d.is_zero() {
            return None;
        }
        Some(self.num.eval(x) / d)
    }
}

/// The least common multiple of the denominators of `entries` (as factor
/// lists).
pub fn common_denominator<'a>(entries: impl IntoIterator<Item = &'a Frac>) -> Vec<(Poly, u32)> {
    entries.into_iter().fold(vec![], |acc, f| merge_max(&acc, &f.den))
}

/// `entry * lcm` as a polynomial, for `lcm` a multiple of the entry's
/// denominator (from [`common_denominator`]).
pub fn times_denominator(entry: &Frac, lcm: &[(Poly, u32)]) -> Poly {
    entry.num.mul(&cofactor(entry.nvars(), lcm, &entry.den))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn q(n: i64, d: i64) -> Rational {
        Rational::new(n.into(), d.into())
    }

    #[test]
    fn arithmetic_agrees_with_evaluation() {
        // variables (x, s, t): f = x/(s + t) + 1/(2 s), g = s/t
        let nv = 3;
        let x = Frac::from_poly(Poly::var(nv, 0));
        let s = Frac::from_poly(Poly::var(nv, 1));
        let t = Frac::from_poly(Poly::var(nv, 2));
        let st = s.add(&t);
        let f = x.div(&st).unwrap().add(&Frac::constant(nv, q(1, 1)).div(&s.scale(&q(2, 1))).unwrap());
        let g = s.div(&t).unwrap();
        let h = f.mul(&g).sub(&f.pow(2)).add(&g.div(&st.pow(3)).unwrap());
        for point in [[q(1, 2), q(3, 1), q(-5, 7)], [q(-2, 1), q(1, 9), q(4, 1)]] {
            let (xv, sv, tv) = (&point[0], &point[1], &point[2]);
            let fv = xv / (sv + tv) + q(1, 1) / (q(2, 1) * sv);
            let gv = sv / tv;
            let stv = sv + tv;
            let hv = &fv * &gv - &fv * &fv + &gv / (&stv * &stv * &stv);
            assert_eq!(h.eval(&point), Some(hv));
        }
        // (s + t) appears once in f's denominator, to power 1, and twice in h's (f^2)
        assert_eq!(f.den().iter().filter(|(p, _)| p.num_terms() == 2).map(|(_, e)| *e).sum::<u32>(), 1);
        // a zero denominator is reported, not divided by
        assert_eq!(f.eval(&[q(1, 1), q(1, 1), q(-1, 1)]), None);
        assert!(x.div(&Frac::zero(nv)).is_none());
    }

    #[test]
    fn common_denominators_clear_every_entry() {
        let nv = 2;
        let s = Frac::from_poly(Poly::var(nv, 0));
        let t = Frac::from_poly(Poly::var(nv, 1));
        let one = Frac::constant(nv, q(1, 1));
        let a = one.div(&s.add(&t)).unwrap();
        let b = one.div(&s.mul(&s)).unwrap();
        let lcm = common_denominator([&a, &b]);
        let point = [q(2, 1), q(3, 1)];
        let l = product(nv, &lcm).eval(&point);
        assert_eq!(times_denominator(&a, &lcm).eval(&point), &a.eval(&point).unwrap() * &l);
        assert_eq!(times_denominator(&b, &lcm).eval(&point), &b.eval(&point).unwrap() * &l);
    }
}
