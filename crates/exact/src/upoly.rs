//! Univariate polynomials over the rationals: characteristic polynomials
//! (Hessenberg reduction) and Sturm sequences, for exact statements about
//! where eigenvalues lie.

use crate::matrix::Matrix;
use crate::number::Rational;
use num_bigint::BigInt;
use num_integer::Integer;
use num_traits::{One, Signed, Zero};
use std::cmp::Ordering;

/// A univariate polynomial `sum_k c_k x^k` (coefficients low to high, no
/// trailing zeros; the zero polynomial is empty).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UPoly {
    coefficients: Vec<Rational>,
}

impl UPoly {
    /// From coefficients, low degree first.
    pub fn new(mut coefficients: Vec<Rational>) -> Self {
        while coefficients.last().is_some_and(Zero::is_zero) {
            coefficients.pop();
        }
        UPoly { coefficients }
    }

    /// The zero polynomial.
    pub fn zero() -> Self {
        UPoly { coefficients: vec![] }
    }

    /// The constant 1.
    pub fn one() -> Self {
        UPoly::new(vec![Rational::one()])
    }

    /// `x`.
    pub fn x() -> Self {
        UPoly::new(vec![Rational::zero(), Rational::one()])
    }

    /// Coefficients, low degree first.
    pub fn coefficients(&self) -> &[Rational] {
        &self.coefficients
    }

    /// Degree (`None` for the zero polynomial).
    pub fn degree(&self) -> Option<usize> {
        self.coefficients.len().checked_sub(1)
    }

    /// Whether this is the zero polynomial.
    pub fn is_zero(&self) -> bool {
        self.coefficients.is_empty()
    }

    /// The leading coefficient (0 for the zero polynomial).
    pub fn leading(&self) -> Rational {
        self.coefficients.last().cloned().unwrap_or_else(Rational::zero)
    }

    /// Sum.
    pub fn add(&self, o: &UPoly) -> UPoly {
        let n = self.coefficients.len().max(o.coefficients.len());
        UPoly::new(
            (0..n)
                .map(|i| {
                    let a = self.coefficients.get(i).cloned().unwrap_or_else(Rational::zero);
                    let b = o.coefficients.get(i).cloned().unwrap_or_else(Rational::zero);
                    a + b
                })
                .collect(),
        )
    }

    /// Multiply by a constant.
    pub fn scale(&self, s: &Rational) -> UPoly {
        UPoly::new(self.coefficients.iter().map(|c| c * s).collect())
    }

    /// Difference.
    pub fn sub(&self, o: &UPoly) -> UPoly {
        self.add(&o.scale(&-Rational::one()))
    }

    /// Product.
    pub fn mul(&self, o: &UPoly) -> UPoly {
        if self.is_zero() || o.is_zero() {
            return UPoly::zero();
        }
        let mut c = vec![Rational::zero(); self.coefficients.len() + o.coefficients.len() - 1];
        for (i, a) in self.coefficients.iter().enumerate() {
            if a.is_zero() {
                continue;
            }
            for (j, b) in o.coefficients.iter().enumerate() {
                if !b.is_zero() {
                    c[i + j] += a * b;
                }
            }
        }
        UPoly::new(c)
    }

    /// Derivative.
    pub fn derivative(&self) -> UPoly {
        UPoly::new(self.coefficients.iter().enumerate().skip(1).map(|(k, c)| c * Rational::from(k as i64)).collect())
    }

    /// Quotient and remainder of the division by a nonzero `d`.
    ///
    /// # Panics
    /// If `d` is zero.
    pub fn div_rem(&self, d: &UPoly) -> (UPoly, UPoly) {
        assert!(!d.is_zero(), "division by the zero polynomial");
        let dd = d.coefficients.len() - 1;
        let lead_inv = d.leading().recip();
        let mut r = self.coefficients.clone();
        if r.len() <= dd {
            return (UPoly::zero(), self.clone());
        }
        let mut q = vec![Rational::zero(); r.len() - dd];
        for k in (0..q.len()).rev() {
            let c = &r[k + dd] * &lead_inv;
            if !c.is_zero() {
                for (j, dc) in d.coefficients.iter().enumerate() {
                    let v = &c * dc;
                    r[k + j] -= v;
                }
            }
            q[k] = c;
        }
        r.truncate(dd);
        (UPoly::new(q), UPoly::new(r))
    }

    /// Monic greatest common divisor.
    ///
    /// By the primitive remainder sequence over the integers
    /// (`positive_remainder` below): Euclid's sequence over the rationals
    /// reduces every product to lowest terms, and on a characteristic
    /// polynomial of dimension 63 with 50-bit entries (the su(8) model of
    /// the su(8) comparison in `tests/it/zeitlin_su_n.rs`) it ran for over 15 minutes inside one
    /// gcd; the primitive sequence keeps each remainder's content divided
    /// out and works in integers. Hand-written: no crate on the project's
    /// list has polynomial gcds over big integers.
    ///
    /// ```
    /// use exact::{Rational, UPoly};
    /// let q = |n: i64| Rational::from(n);
    /// // (x - 1)^2 (x + 2) and (x - 1)(x + 3): gcd x - 1
    /// let a = UPoly::new(vec![q(2), q(-3), q(0), q(1)]);
    /// let b = UPoly::new(vec![q(-3), q(2), q(1)]);
    /// assert_eq!(a.gcd(&b), UPoly::new(vec![q(-1), q(1)]));
    /// ```
    pub fn gcd(&self, o: &UPoly) -> UPoly {
        let (mut a, mut b) = (primitive_integer(&self.coefficients), primitive_integer(&o.coefficients));
        while !b.is_empty() {
            let r = positive_remainder(&a, &b);
            a = b;
            b = r;
        }
        let a = UPoly::from_integers(a);
        if a.is_zero() {
            return a;
        }
        let l = a.leading().recip();
        a.scale(&l)
    }

    fn from_integers(c: Vec<BigInt>) -> UPoly {
        UPoly::new(c.into_iter().map(Rational::from_integer).collect())
    }

    /// The square-free part `p / gcd(p, p')` (same roots, all simple).
    pub fn square_free(&self) -> UPoly {
        if self.degree().unwrap_or(0) == 0 {
            return self.clone();
        }
        let g = self.gcd(&self.derivative());
        self.div_rem(&g).0
    }

    /// Value at a rational point.
    pub fn eval(&self, x: &Rational) -> Rational {
        let mut acc = Rational::zero();
        for c in self.coefficients.iter().rev() {
            acc = acc * x + c;
        }
        acc
    }

    /// Number of distinct real roots in the open interval `(a, b)`, by
    /// Sturm's theorem. `None` bounds mean `-inf`/`+inf`. Endpoints that are
    /// roots are not counted.
    ///
    /// ```
    /// use exact::{Rational, UPoly};
    /// // (x - 1)(x + 2)^2 = x^3 + 3x^2 - 4: distinct roots -2 and 1.
    /// let p = UPoly::new(vec![Rational::from(-4), Rational::from(0), Rational::from(3), Rational::from(1)]);
    /// assert_eq!(p.count_real_roots(None, None), 2);
    /// assert_eq!(p.count_real_roots(None, Some(&Rational::from(0))), 1);
    /// assert_eq!(p.count_real_roots(Some(&Rational::from(1)), None), 0); // endpoint excluded
    /// ```
    pub fn count_real_roots(&self, a: Option<&Rational>, b: Option<&Rational>) -> usize {
        let p = self.square_free();
        if p.degree().unwrap_or(0) == 0 {
            return 0;
        }
        // Sturm's sequence up to positive factors (which keep every sign):
        // p, p', then minus a positive multiple of each remainder, in
        // integers ([`UPoly::gcd`] says why).
        let mut ints = vec![primitive_integer(&p.coefficients), primitive_integer(&p.derivative().coefficients)];
        loop {
            let k = ints.len();
            let r = positive_remainder(&ints[k - 2], &ints[k - 1]);
            if r.is_empty() {
                break;
            }
            ints.push(r.into_iter().map(|c| -c).collect());
        }
        // Sign of each member at a point (or at -inf / +inf).
        let sign_at = |x: Option<&Rational>, plus_infinity: bool| -> Vec<Ordering> {
            ints.iter()
                .map(|s| match x {
                    Some(x) => integer_sign_at(s, x),
                    None => {
                        let lead = s.last().map_or(Ordering::Equal, |c| c.sign().cmp(&num_bigint::Sign::NoSign));
                        let odd = s.len().saturating_sub(1) % 2 == 1;
                        if !plus_infinity && odd {
                            lead.reverse()
                        } else {
                            lead
                        }
                    }
                })
                .collect()
        };
        let changes = |signs: Vec<Ordering>| {
            let nz: Vec<Ordering> = signs.into_iter().filter(|s| *s != Ordering::Equal).collect();
            nz.windows(2).filter(|w| w[0] != w[1]).count()
        };
        // Exclude endpoint roots: V(a) - V(b) counts roots in (a, b] when a is
        // not a root; nudge past a root endpoint by counting it out.
        let va = changes(sign_at(a, false));
        let vb = changes(sign_at(b, true));
        let total = va.saturating_sub(vb);
        let b_is_root = b.is_some_and(|b| integer_sign_at(&ints[0], b) == Ordering::Equal);
        total - usize::from(b_is_root && total > 0)
    }
}

/// The coefficients of a positive rational multiple of `c` that are
/// integers with no common factor (the primitive part; empty for zero).
fn primitive_integer(c: &[Rational]) -> Vec<BigInt> {
    let l = c.iter().fold(BigInt::one(), |l, x| l.lcm(&x.denom()));
    primitive(c.iter().map(|x| x.numer() * (&l / x.denom())).collect())
}

/// The sign of the integer polynomial `c` (low degree first) at `x = n/d`,
/// `d > 0`: the sign of the homogeneous `sum_k c_k n^k d^(D - k)` (`D` the
/// degree), by Horner's rule in integers (no gcd per step as in
/// [`UPoly::eval`]).
fn integer_sign_at(c: &[BigInt], x: &Rational) -> Ordering {
    let (n, d) = (x.numer(), x.denom());
    let mut acc = BigInt::zero();
    let mut dpow = BigInt::one();
    for (i, ck) in c.iter().rev().enumerate() {
        if i == 0 {
            acc = ck.clone();
        } else {
            dpow *= &d;
            acc = acc * &n + ck * &dpow;
        }
    }
    acc.sign().cmp(&num_bigint::Sign::NoSign)
}

/// `v` divided by the (positive) gcd of its entries, trailing zeros removed.
fn primitive(mut v: Vec<BigInt>) -> Vec<BigInt> {
    while v.last().is_some_and(Zero::is_zero) {
        v.pop();
    }
    // the gcd from the smallest entry down, each entry reduced modulo it
    // first: num-bigint's binary gcd is slow on numbers of thousands of
    // bits, a division is not
    let Some(mut g) = v.iter().filter(|x| !x.is_zero()).min_by_key(|x| x.bits()).map(|x| x.abs()) else {
        return v;
    };
    for x in &v {
        if g.is_one() {
            return v;
        }
        g = g.gcd(&(x % &g));
    }
    // g > 0: it started as the smallest nonzero entry's magnitude
    if !g.is_one() {
        for x in &mut v {
            *x /= &g;
        }
    }
    v
}

/// A positive multiple of the remainder of `a` divided by a nonzero `b`
/// (integer coefficients, low degree first), made primitive. The pseudo-
/// division `lc(b)^s a = q b + r` (`s` the elimination steps) gives `r =
/// lc(b)^s rem(a, b)`; its sign is flipped when `lc(b)^s < 0`, so the
/// result is a positive multiple and a Sturm sequence built from it keeps
/// its signs.
fn positive_remainder(a: &[BigInt], b: &[BigInt]) -> Vec<BigInt> {
    let db = b.len() - 1;
    let lb = &b[db];
    let mut r = a.to_vec();
    let mut negative = false;
    while r.len() > db {
        let dr = r.len() - 1;
        let lr = r[dr].clone();
        for x in r.iter_mut() {
            *x *= lb;
        }
        for (j, bj) in b.iter().enumerate() {
            r[dr - db + j] -= &lr * bj;
        }
        debug_assert!(r[dr].is_zero());
        while r.last().is_some_and(Zero::is_zero) {
            r.pop();
        }
        negative ^= lb.is_negative();
    }
    if negative {
        for x in &mut r {
            *x = -&*x;
        }
    }
    primitive(r)
}

/// The characteristic polynomial `det(x I - A)` of a square rational matrix,
/// by exact reduction to upper Hessenberg form and the Hessenberg recurrence
/// (Cohen, *A Course in Computational Algebraic Number Theory*, Alg. 2.2.9).
///
/// ```
/// use exact::{char_poly, Matrix, Rational};
/// let q = |n: i64| Rational::from(n);
/// let a = Matrix::from_rows(&[vec![q(0), q(1)], vec![q(-2), q(0)]]);
/// // x^2 + 2
/// assert_eq!(char_poly(&a).coefficients(), &[q(2), q(0), q(1)]);
/// ```
pub fn char_poly(a: &Matrix) -> UPoly {
    let n = a.nrows();
    assert_eq!(n, a.ncols(), "square matrix");
    let mut h = a.clone();
    // Reduce to upper Hessenberg form by similarity transformations.
    for m in 1..n.saturating_sub(1) {
        let Some(i) = (m..n).find(|&i| !h[(i, m - 1)].is_zero()) else { continue };
        if i != m {
            for k in 0..n {
                let t = h[(i, k)].clone();
                h[(i, k)] = h[(m, k)].clone();
                h[(m, k)] = t;
            }
            for k in 0..n {
                let t = h[(k, i)].clone();
                h[(k, i)] = h[(k, m)].clone();
                h[(k, m)] = t;
            }
        }
        let pivot = h[(m, m - 1)].clone();
        for j in (m + 1)..n {
            if h[(j, m - 1)].is_zero() {
                continue;
            }
            let u = &h[(j, m - 1)] / &pivot;
            for k in 0..n {
                let v = &u * &h[(m, k)];
                h[(j, k)] -= v;
            }
            for k in 0..n {
                let v = &u * &h[(k, j)];
                h[(k, m)] += v;
            }
        }
    }
    // p_m = (x - h_mm) p_{m-1} - sum_{i<m} h_im (prod_{j=i+1..m} h_{j,j-1}) p_{i-1}  (1-based)
    let mut p: Vec<UPoly> = vec![UPoly::one()];
    for m in 1..=n {
        let mut pm = UPoly::x().sub(&UPoly::new(vec![h[(m - 1, m - 1)].clone()])).mul(&p[m - 1]);
        let mut t = Rational::one();
        for i in (1..m).rev() {
            t *= &h[(i, i - 1)];
            if t.is_zero() {
                break;
            }
            let c = &h[(i - 1, m - 1)] * &t;
            if !c.is_zero() {
                pm = pm.sub(&p[i - 1].scale(&c));
            }
        }
        p.push(pm);
    }
    p.pop().unwrap_or_else(UPoly::one)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn q(n: i64) -> Rational {
        Rational::from(n)
    }

    /// Cayley–Hamilton: p(A) = 0, checked exactly.
    fn evaluate_at_matrix(p: &UPoly, a: &Matrix) -> Matrix {
        let n = a.nrows();
        let mut acc = Matrix::zeros(n, n);
        for c in p.coefficients().iter().rev() {
            acc = acc.mul(a).add(&Matrix::identity(n).scale(c));
        }
        acc
    }

    #[test]
    fn cayley_hamilton_on_awkward_matrices() {
        // Zero subdiagonal (needs a row swap), repeated eigenvalues, rationals.
        let mats = vec![
            Matrix::from_rows(&[vec![q(0), q(1), q(2)], vec![q(0), q(0), q(3)], vec![q(4), q(0), q(0)]]),
            Matrix::from_rows(&[vec![q(2), q(0), q(0)], vec![q(0), q(2), q(0)], vec![q(0), q(0), q(2)]]),
            Matrix::from_fn(5, 5, |i, j| Rational::new_small((i * 7 + j * 3) as i64 % 5 - 2, (i + j + 1) as i64)),
        ];
        for a in mats {
            let p = char_poly(&a);
            assert_eq!(p.degree(), Some(a.nrows()));
            assert!(p.leading() == q(1));
            assert!(evaluate_at_matrix(&p, &a).is_zero(), "{a:?}");
        }
    }

    /// Euclid's algorithm over the rationals, as `gcd` was before the
    /// integer remainder sequence: the oracle for it.
    fn euclid_gcd(p: &UPoly, o: &UPoly) -> UPoly {
        let (mut a, mut b) = (p.clone(), o.clone());
        while !b.is_zero() {
            let r = a.div_rem(&b).1;
            a = b;
            b = r;
        }
        if a.is_zero() {
            return a;
        }
        let l = a.leading().recip();
        a.scale(&l)
    }

    /// A small deterministic generator (xorshift), enough for test data.
    struct Xs(u64);
    impl Xs {
        fn int(&mut self, lo: i64, hi: i64) -> i64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            lo + (self.0 % (hi - lo + 1) as u64) as i64
        }
    }

    #[test]
    fn the_integer_remainder_sequence_agrees_with_euclid_and_with_roots_known_by_construction() {
        // p = s * prod (x - r_i)^{m_i} * prod (x^2 + c_j), r_i distinct
        // rationals, c_j > 0 (no real root), s a rational of either sign:
        // its distinct real roots are the r_i, so every Sturm count is known
        // without the code under test; gcds are compared with Euclid over
        // the rationals (the monic gcd is unique, so they must be equal).
        let mut rng = Xs(0x9e37_79b9_7f4a_7c15);
        for case in 0..150 {
            let mut roots: Vec<Rational> = vec![];
            while roots.len() < 1 + case % 6 {
                let r = Rational::new_small(rng.int(-40, 40), rng.int(1, 9));
                if !roots.contains(&r) {
                    roots.push(r);
                }
            }
            let mut p = UPoly::new(vec![Rational::new_small(rng.int(-9, 9).max(1) * [1, -1][case % 2], rng.int(1, 7))]);
            let mut other = UPoly::new(vec![Rational::new_small(rng.int(1, 5), rng.int(1, 5))]);
            for (i, r) in roots.iter().enumerate() {
                let lin = UPoly::new(vec![-r.clone(), q(1)]);
                for _ in 0..rng.int(1, 3) {
                    p = p.mul(&lin);
                }
                if i % 2 == 0 {
                    other = other.mul(&lin);
                }
            }
            for _ in 0..case % 3 {
                let quad = UPoly::new(vec![Rational::new_small(rng.int(1, 30), rng.int(1, 4)), q(0), q(1)]);
                p = p.mul(&quad);
                other = other.mul(&quad);
            }
            // gcds, also against a derivative and with a factor of 1/3 shifted in
            let o2 = other.add(&UPoly::new(vec![Rational::new_small(1, 3)]));
            for o in [&other, &p.derivative(), &o2] {
                assert_eq!(p.gcd(o), euclid_gcd(&p, o), "case {case}");
                assert_eq!(o.gcd(&p), euclid_gcd(o, &p), "case {case}");
            }
            assert_eq!(p.gcd(&UPoly::zero()), euclid_gcd(&p, &UPoly::zero()));
            assert_eq!(UPoly::zero().gcd(&p), euclid_gcd(&UPoly::zero(), &p));
            // Sturm counts on open intervals, endpoints roots or not
            let inside = |a: Option<&Rational>, b: Option<&Rational>| {
                roots.iter().filter(|r| a.is_none_or(|a| *r > a) && b.is_none_or(|b| *r < b)).count()
            };
            let mut points: Vec<Rational> = roots.clone();
            points.push(Rational::new_small(rng.int(-50, 50), rng.int(1, 3)));
            points.push(q(0));
            assert_eq!(p.count_real_roots(None, None), roots.len(), "case {case}");
            for a in &points {
                assert_eq!(p.count_real_roots(Some(a), None), inside(Some(a), None), "case {case} ({a}, inf)");
                assert_eq!(p.count_real_roots(None, Some(a)), inside(None, Some(a)), "case {case} (-inf, {a})");
                for b in &points {
                    if a < b {
                        assert_eq!(p.count_real_roots(Some(a), Some(b)), inside(Some(a), Some(b)), "case {case}");
                    }
                }
            }
        }
    }

    #[test]
    fn sturm_counts() {
        // x^2 + 1 has no real root; x^2 - 2 has two; (x-1)^3 one distinct.
        assert_eq!(UPoly::new(vec![q(1), q(0), q(1)]).count_real_roots(None, None), 0);
        assert_eq!(UPoly::new(vec![q(-2), q(0), q(1)]).count_real_roots(None, None), 2);
        let cube = UPoly::new(vec![q(-1), q(3), q(-3), q(1)]);
        assert_eq!(cube.count_real_roots(None, None), 1);
        assert_eq!(cube.count_real_roots(None, Some(&q(0))), 0);
        assert_eq!(cube.count_real_roots(Some(&q(0)), Some(&q(2))), 1);
    }
}
