//! An exact rational number that stays on the stack while it is small.
//!
//! The engine's rationals are almost always small (structure constants,
//! inertias, `3/10`), and `num_rational::BigRational` allocates and runs a
//! big-integer gcd on every operation, which made the exact pipeline several
//! times slower than its floating-point part. This type keeps numerator and
//! denominator in `i64` while they fit, computes in `i128`, and falls back to
//! `BigRational` only on overflow; every value has one canonical
//! representation (reduced, positive denominator, small whenever it fits), so
//! equality and hashing are structural.

use num_bigint::BigInt;
use num_integer::Integer;
use num_traits::{One, Signed, ToPrimitive, Zero};
use std::cmp::Ordering;
use std::fmt;
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

type Big = num_rational::BigRational;

#[derive(PartialEq, Eq, Hash)]
enum Repr {
    /// `n / d` with `d > 0`, `gcd(n, d) = 1`.
    Small(i64, i64),
    /// Only values that do not fit `Small` (boxed, so the common small case
    /// stays 24 bytes).
    Big(Box<Big>),
}

/// An exact rational number (see the module docs for the representation).
#[derive(PartialEq, Eq, Hash)]
pub struct Rational(Repr);

impl Clone for Rational {
    /// Written out so that the small case inlines into the caller (the
    /// derived clone was an out-of-line call, 8% of a certification).
    #[inline]
    fn clone(&self) -> Rational {
        match &self.0 {
            Repr::Small(n, d) => Rational(Repr::Small(*n, *d)),
            Repr::Big(b) => Rational(Repr::Big(b.clone())),
        }
    }
}

impl Rational {
    /// The zero rational as a constant (no call).
    pub const ZERO: Rational = Rational(Repr::Small(0, 1));
}

impl Rational {
    /// From an `i128` fraction (any signs, `d != 0`), reduced.
    fn from_i128(n: i128, d: i128) -> Rational {
        debug_assert!(d != 0);
        let (mut n, mut d) = if d < 0 {
            match (n.checked_neg(), d.checked_neg()) {
                (Some(n), Some(d)) => (n, d),
                _ => return Rational::from_big(Big::new(BigInt::from(n), BigInt::from(d))),
            }
        } else {
            (n, d)
        };
        if n == 0 {
            return Rational(Repr::Small(0, 1));
        }
        let na = n.unsigned_abs();
        let g = if d == 1 {
            1
        } else if na <= u64::MAX as u128 && d <= u64::MAX as i128 {
            // num-integer's gcd is Stein's binary algorithm; u64 is faster than u128.
            (na as u64).gcd(&(d as u64)) as i128
        } else {
            na.gcd(&(d as u128)) as i128
        };
        if g > 1 {
            n /= g;
            d /= g;
        }
        match (i64::try_from(n), i64::try_from(d)) {
            (Ok(n), Ok(d)) => Rational(Repr::Small(n, d)),
            _ => Rational(Repr::Big(Box::new(Big::new_raw(BigInt::from(n), BigInt::from(d))))),
        }
    }

    /// From a reduced big rational, demoted to small if it fits.
    fn from_big(b: Big) -> Rational {
        match (b.numer().to_i64(), b.denom().to_i64()) {
            (Some(n), Some(d)) => Rational(Repr::Small(n, d)),
            _ => Rational(Repr::Big(Box::new(b))),
        }
    }

    fn to_big(&self) -> Big {
        match &self.0 {
            Repr::Small(n, d) => Big::new_raw(BigInt::from(*n), BigInt::from(*d)),
            Repr::Big(b) => (**b).clone(),
        }
    }

    /// `n / d`, reduced.
    ///
    /// # Panics
    /// If `d` is zero.
    pub fn new(n: BigInt, d: BigInt) -> Rational {
        assert!(!d.is_zero(), "zero denominator");
        Rational::from_big(Big::new(n, d))
    }

    /// `n / d` for machine integers, reduced.
    ///
    /// # Panics
    /// If `d` is zero.
    pub fn new_small(n: i64, d: i64) -> Rational {
        assert!(d != 0, "zero denominator");
        Rational::from_i128(n as i128, d as i128)
    }

    /// An integer.
    pub fn from_integer(n: BigInt) -> Rational {
        match n.to_i64() {
            Some(v) => Rational(Repr::Small(v, 1)),
            None => Rational(Repr::Big(Box::new(Big::from_integer(n)))),
        }
    }

    /// The exact value of a finite double.
    pub fn from_float(x: f64) -> Option<Rational> {
        Big::from_float(x).map(Rational::from_big)
    }

    /// The numerator (the sign is carried here).
    pub fn numer(&self) -> BigInt {
        match &self.0 {
            Repr::Small(n, _) => BigInt::from(*n),
            Repr::Big(b) => b.numer().clone(),
        }
    }

    /// The denominator (positive).
    pub fn denom(&self) -> BigInt {
        match &self.0 {
            Repr::Small(_, d) => BigInt::from(*d),
            Repr::Big(b) => b.denom().clone(),
        }
    }

    /// `1 / self`.
    ///
    /// # Panics
    /// If `self` is zero.
    pub fn recip(&self) -> Rational {
        match &self.0 {
            Repr::Small(n, d) => {
                assert!(*n != 0, "reciprocal of zero");
                Rational::from_i128(*d as i128, *n as i128)
            }
            Repr::Big(b) => Rational::from_big(b.recip()),
        }
    }

    /// Whether the denominator is 1.
    pub fn is_integer(&self) -> bool {
        match &self.0 {
            Repr::Small(_, d) => *d == 1,
            Repr::Big(b) => b.is_integer(),
        }
    }

    /// The integer part, truncated toward zero.
    pub fn to_integer(&self) -> BigInt {
        match &self.0 {
            Repr::Small(n, d) => BigInt::from(n / d),
            Repr::Big(b) => b.to_integer(),
        }
    }

    /// Absolute value.
    pub fn abs(&self) -> Rational {
        if self.is_negative() {
            -self
        } else {
            self.clone()
        }
    }

    /// Whether `< 0`.
    pub fn is_negative(&self) -> bool {
        match &self.0 {
            Repr::Small(n, _) => *n < 0,
            Repr::Big(b) => b.is_negative(),
        }
    }

    /// Whether `> 0`.
    pub fn is_positive(&self) -> bool {
        match &self.0 {
            Repr::Small(n, _) => *n > 0,
            Repr::Big(b) => b.is_positive(),
        }
    }

    /// The nearest double (within one ulp).
    #[inline]
    pub fn to_f64(&self) -> Option<f64> {
        match &self.0 {
            Repr::Small(n, d) => Some(*n as f64 / *d as f64),
            Repr::Big(b) => b.to_f64(),
        }
    }

    /// The larger bit length of numerator and denominator (without
    /// allocating): the size that the cost of arithmetic grows with.
    ///
    /// ```
    /// use exact::Rational;
    /// assert_eq!(Rational::new_small(3, 8).size_bits(), 4);
    /// assert_eq!(Rational::new_small(0, 1).size_bits(), 1);
    /// ```
    pub fn size_bits(&self) -> u64 {
        match &self.0 {
            Repr::Small(n, d) => {
                let bits = |x: u64| (64 - x.leading_zeros() as u64).max(1);
                bits(n.unsigned_abs()).max(bits(*d as u64))
            }
            Repr::Big(b) => b.numer().bits().max(b.denom().bits()).max(1),
        }
    }

    /// `floor(log2 |self|)`, `None` for zero (no allocation for small values).
    pub(crate) fn log2_floor(&self) -> Option<i64> {
        match &self.0 {
            Repr::Small(0, _) => None,
            Repr::Small(n, d) => {
                let (n, d) = (n.unsigned_abs() as u128, *d as u128);
                let e = (127 - n.leading_zeros() as i64) - (127 - d.leading_zeros() as i64);
                // |n/d| >= 2^e iff n >= d 2^e (shifts stay below 2^127: both < 2^64)
                let at_least = if e >= 0 { n >= d << e } else { n << (-e) >= d };
                Some(if at_least { e } else { e - 1 })
            }
            Repr::Big(b) => {
                let (n, d) = (b.numer().magnitude(), b.denom().magnitude());
                let e = n.bits() as i64 - d.bits() as i64;
                let at_least = if e >= 0 { n >= &(d << e as usize) } else { &(n << (-e) as usize) >= d };
                Some(if at_least { e } else { e - 1 })
            }
        }
    }

    /// `self^e` for a non-negative exponent.
    pub fn pow(&self, e: u32) -> Rational {
        num_traits::pow(self.clone(), e as usize)
    }

    #[inline]
    fn op(
        &self,
        other: &Rational,
        small: fn(i64, i64, i64, i64) -> Option<Rational>,
        big: fn(Big, Big) -> Big,
    ) -> Rational {
        if let (Repr::Small(a, b), Repr::Small(c, d)) = (&self.0, &other.0) {
            if let Some(r) = small(*a, *b, *c, *d) {
                return r;
            }
        }
        Rational::from_big(big(self.to_big(), other.to_big()))
    }
}

fn small_add(a: i64, b: i64, c: i64, d: i64) -> Option<Rational> {
    // Either term zero: the other is already canonical (sums into a zero
    // accumulator are the common case in products of matrices).
    if a == 0 {
        return Some(Rational(Repr::Small(c, d)));
    }
    if c == 0 {
        return Some(Rational(Repr::Small(a, b)));
    }
    if b == 1 && d == 1 {
        return a.checked_add(c).map(|n| Rational(Repr::Small(n, 1)));
    }
    if b == d {
        return Some(Rational::from_i128(a as i128 + c as i128, b as i128));
    }
    let n = (a as i128).checked_mul(d as i128)?.checked_add((c as i128).checked_mul(b as i128)?)?;
    Some(Rational::from_i128(n, (b as i128).checked_mul(d as i128)?))
}

fn small_sub(a: i64, b: i64, c: i64, d: i64) -> Option<Rational> {
    small_add(a, b, c.checked_neg()?, d)
}

fn small_mul(a: i64, b: i64, c: i64, d: i64) -> Option<Rational> {
    if a == 0 || c == 0 {
        return Some(Rational(Repr::Small(0, 1)));
    }
    if b == 1 && d == 1 {
        return a.checked_mul(c).map(|n| Rational(Repr::Small(n, 1)));
    }
    Some(Rational::from_i128((a as i128).checked_mul(c as i128)?, (b as i128).checked_mul(d as i128)?))
}

fn small_div(a: i64, b: i64, c: i64, d: i64) -> Option<Rational> {
    assert!(c != 0, "division by zero");
    Some(Rational::from_i128((a as i128).checked_mul(d as i128)?, (b as i128).checked_mul(c as i128)?))
}

macro_rules! binop {
    ($Tr:ident, $m:ident, $small:ident, $bigop:tt, $TrA:ident, $ma:ident) => {
        impl $Tr<&Rational> for &Rational {
            type Output = Rational;
            fn $m(self, o: &Rational) -> Rational {
                self.op(o, $small, |x, y| x $bigop y)
            }
        }
        impl $Tr<Rational> for &Rational {
            type Output = Rational;
            fn $m(self, o: Rational) -> Rational {
                self.op(&o, $small, |x, y| x $bigop y)
            }
        }
        impl $Tr<&Rational> for Rational {
            type Output = Rational;
            fn $m(self, o: &Rational) -> Rational {
                self.op(o, $small, |x, y| x $bigop y)
            }
        }
        impl $Tr<Rational> for Rational {
            type Output = Rational;
            fn $m(self, o: Rational) -> Rational {
                self.op(&o, $small, |x, y| x $bigop y)
            }
        }
        impl $TrA<&Rational> for Rational {
            fn $ma(&mut self, o: &Rational) {
                *self = self.op(o, $small, |x, y| x $bigop y);
            }
        }
        impl $TrA<Rational> for Rational {
            fn $ma(&mut self, o: Rational) {
                *self = self.op(&o, $small, |x, y| x $bigop y);
            }
        }
    };
}

binop!(Add, add, small_add, +, AddAssign, add_assign);
binop!(Sub, sub, small_sub, -, SubAssign, sub_assign);
binop!(Mul, mul, small_mul, *, MulAssign, mul_assign);
binop!(Div, div, small_div, /, DivAssign, div_assign);

impl Neg for &Rational {
    type Output = Rational;
    fn neg(self) -> Rational {
        match &self.0 {
            Repr::Small(n, d) => match n.checked_neg() {
                Some(m) => Rational(Repr::Small(m, *d)),
                None => Rational::from_big(-self.to_big()),
            },
            Repr::Big(b) => Rational::from_big(-(**b).clone()),
        }
    }
}

impl Neg for Rational {
    type Output = Rational;
    fn neg(self) -> Rational {
        -&self
    }
}

impl Zero for Rational {
    #[inline]
    fn zero() -> Rational {
        Rational(Repr::Small(0, 1))
    }
    #[inline]
    fn is_zero(&self) -> bool {
        matches!(self.0, Repr::Small(0, _))
    }
}

impl One for Rational {
    #[inline]
    fn one() -> Rational {
        Rational(Repr::Small(1, 1))
    }
    #[inline]
    fn is_one(&self) -> bool {
        matches!(self.0, Repr::Small(1, 1))
    }
}

impl Ord for Rational {
    fn cmp(&self, other: &Rational) -> Ordering {
        match (&self.0, &other.0) {
            (Repr::Small(a, b), Repr::Small(c, d)) => ((*a as i128) * (*d as i128)).cmp(&((*c as i128) * (*b as i128))),
            _ => self.to_big().cmp(&other.to_big()),
        }
    }
}

impl PartialOrd for Rational {
    fn partial_cmp(&self, other: &Rational) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl fmt::Display for Rational {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.0 {
            Repr::Small(n, 1) => write!(f, "{n}"),
            Repr::Small(n, d) => write!(f, "{n}/{d}"),
            Repr::Big(b) => write!(f, "{b}"),
        }
    }
}

impl fmt::Debug for Rational {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}

impl From<i64> for Rational {
    fn from(v: i64) -> Rational {
        Rational(Repr::Small(v, 1))
    }
}

impl From<Big> for Rational {
    fn from(b: Big) -> Rational {
        Rational::from_big(b)
    }
}

/// Least common multiple of denominators and gcd of numerators, for scaling
/// a list of rationals to coprime integers.
pub fn integer_scale(values: &[Rational]) -> Rational {
    let mut lcm = BigInt::one();
    let mut gcd = BigInt::zero();
    for v in values {
        lcm = lcm.lcm(&v.denom());
        gcd = gcd.gcd(&v.numer());
    }
    if gcd.is_zero() {
        return Rational::one();
    }
    Rational::new(lcm, gcd)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn big(n: i64, d: i64) -> Big {
        Big::new(n.into(), d.into())
    }

    proptest! {
        /// Every operation agrees with num-rational, including across the
        /// small/big boundary (values near i64::MAX force the fallback).
        #[test]
        fn agrees_with_big_rational(
            a in prop_oneof![-1000i64..1000, Just(i64::MAX), Just(i64::MIN + 1), any::<i64>()],
            b in prop_oneof![1i64..1000, Just(i64::MAX), any::<i64>().prop_filter("nonzero", |x| *x != 0)],
            c in prop_oneof![-1000i64..1000, Just(i64::MAX), any::<i64>()],
            d in prop_oneof![1i64..1000, Just(i64::MAX), any::<i64>().prop_filter("nonzero", |x| *x != 0)],
        ) {
            let (x, y) = (Rational::from(big(a, b)), Rational::from(big(c, d)));
            let (bx, by) = (big(a, b), big(c, d));
            prop_assert_eq!(&x + &y, Rational::from(&bx + &by));
            prop_assert_eq!(&x - &y, Rational::from(&bx - &by));
            prop_assert_eq!(&x * &y, Rational::from(&bx * &by));
            if c != 0 {
                prop_assert_eq!(&x / &y, Rational::from(&bx / &by));
            }
            prop_assert_eq!(x.cmp(&y), bx.cmp(&by));
            prop_assert_eq!(-&x, Rational::from(-bx.clone()));
            prop_assert_eq!(x.to_string(), bx.to_string());
        }
    }

    #[test]
    fn canonical_forms() {
        assert_eq!(Rational::new(2.into(), (-4).into()).to_string(), "-1/2");
        assert!(Rational::new(0.into(), 5.into()).is_zero());
        assert!(Rational::new(3.into(), 3.into()).is_one());
        let huge = Rational::from_integer(BigInt::from(i64::MAX) * 4);
        assert_eq!((&huge / &Rational::from(4)), Rational::from(i64::MAX));
    }
}
