//! Exact sums of doubles, so that an ensemble's statistics do not depend on
//! how its paths were split between threads, processes or machines.
//!
//! Every finite double is an integer multiple of `2^-1074`, so a sum of
//! doubles is one too: [`ExactSum`] keeps that integer in 32-bit chunks held
//! in `i64` (the "small superaccumulator" of Neal, *Fast exact summation
//! using small and large superaccumulators*, arXiv:1505.05571), adds a
//! double in three integer additions, and is merged with another by adding
//! chunks. Its value is written and read as an exact rational (`p/q` with
//! `q` a power of two), so shards computed in separate processes merge into
//! exactly the sum one process would have found, in any order; the double
//! reported is a function of that exact value alone.
//!
//! Written here rather than taken from the `xsum` crate: that crate returns
//! only the rounded sum, and a shard must hand over its exact state.

use exact::Rational;
use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{One, Zero};

/// Bits per chunk.
const CHUNK_BITS: u32 = 32;
/// The exponent of the least significant bit of chunk 0: every double is an
/// integer times `2^-1074`.
const SCALE: i64 = 1074;
/// Additions a chunk absorbs before carries are propagated: each adds less
/// than `2^32` in magnitude, so `2^30` of them stay below `2^62`.
const ADDS_BEFORE_CARRY: u32 = 1 << 30;

/// An exact sum of doubles (see the module docs). Non-finite terms are
/// remembered as such: the sum is NaN if a NaN or both infinities were
/// added, else infinite if one infinity was.
#[derive(Clone, Debug, Default)]
pub struct ExactSum {
    /// Index of the chunk `chunks[0]` (chunk `i` weighs `2^(32 i - 1074)`).
    base: i32,
    /// Signed chunks, not normalised (each below `2^62` in magnitude).
    chunks: Vec<i64>,
    /// Additions since the last carry propagation.
    adds: u32,
    nan: bool,
    pos_inf: bool,
    neg_inf: bool,
}

/// Equal values (not equal representations: chunks are kept unnormalised).
impl PartialEq for ExactSum {
    fn eq(&self, other: &ExactSum) -> bool {
        self.to_text() == other.to_text()
    }
}

impl ExactSum {
    /// The empty sum (zero).
    pub fn new() -> Self {
        ExactSum::default()
    }

    /// Make room for chunks `lo..=hi`.
    fn cover(&mut self, lo: i32, hi: i32) {
        if self.chunks.is_empty() {
            self.base = lo;
            self.chunks = vec![0; (hi - lo + 1) as usize];
            return;
        }
        if lo < self.base {
            let extra = (self.base - lo) as usize;
            self.chunks.splice(0..0, std::iter::repeat_n(0, extra));
            self.base = lo;
        }
        let top = self.base + self.chunks.len() as i32 - 1;
        if hi > top {
            self.chunks.extend(std::iter::repeat_n(0, (hi - top) as usize));
        }
    }

    /// Propagate carries so that every chunk but the last lies in
    /// `[0, 2^32)` (the last keeps the sign).
    fn carry(&mut self) {
        let mut carry = 0i64;
        let last = self.chunks.len().saturating_sub(1);
        for (i, c) in self.chunks.iter_mut().enumerate() {
            let v = *c + carry;
            if i == last {
                *c = v;
            } else {
                carry = v >> CHUNK_BITS;
                *c = v - (carry << CHUNK_BITS);
            }
        }
        self.adds = 0;
        // The last chunk may now exceed 2^32: give it room to carry next time.
        if self.chunks.last().is_some_and(|c| c.unsigned_abs() >= 1 << CHUNK_BITS) {
            self.chunks.push(0);
            self.carry();
        }
    }

    /// Add a double exactly.
    pub fn add(&mut self, x: f64) {
        if x == 0.0 {
            return;
        }
        if !x.is_finite() {
            if x.is_nan() {
                self.nan = true;
            } else if x > 0.0 {
                self.pos_inf = true;
            } else {
                self.neg_inf = true;
            }
            return;
        }
        let bits = x.to_bits();
        let exponent = ((bits >> 52) & 0x7ff) as i64;
        let fraction = bits & ((1u64 << 52) - 1);
        // x = m 2^e exactly, with the position of m's lowest bit above 2^-1074.
        let (m, position) = if exponent == 0 { (fraction, 0) } else { (fraction | (1 << 52), exponent - 1) };
        let index = (position / CHUNK_BITS as i64) as i32;
        let shift = (position % CHUNK_BITS as i64) as u32;
        let wide = (m as u128) << shift; // below 2^(53 + 31)
        let parts = [
            (wide & 0xffff_ffff) as i64,
            ((wide >> CHUNK_BITS) & 0xffff_ffff) as i64,
            (wide >> (2 * CHUNK_BITS)) as i64,
        ];
        self.cover(index, index + 2);
        let at = (index - self.base) as usize;
        let negative = x < 0.0;
        for (k, p) in parts.into_iter().enumerate() {
            if negative {
                self.chunks[at + k] -= p;
            } else {
                self.chunks[at + k] += p;
            }
        }
        self.adds += 1;
        if self.adds >= ADDS_BEFORE_CARRY {
            self.carry();
        }
    }

    /// Add another exact sum.
    pub fn merge(&mut self, other: &ExactSum) {
        self.nan |= other.nan;
        self.pos_inf |= other.pos_inf;
        self.neg_inf |= other.neg_inf;
        if other.chunks.is_empty() {
            return;
        }
        // Both normalised: every chunk then absorbs at most one more term.
        self.carry();
        let mut o = other.clone();
        o.carry();
        let top = o.base + o.chunks.len() as i32 - 1;
        self.cover(o.base, top + 1);
        for (i, c) in o.chunks.iter().enumerate() {
            let at = (o.base - self.base) as usize + i;
            self.chunks[at] += c;
        }
        self.carry();
    }

    /// The integer `N` with `sum = N 2^-1074` (finite part).
    fn integer(&self) -> BigInt {
        let mut n = BigInt::zero();
        for c in self.chunks.iter().rev() {
            n = (n << CHUNK_BITS) + BigInt::from(*c);
        }
        if self.chunks.is_empty() {
            return n;
        }
        let low = self.base as i64 * CHUNK_BITS as i64;
        // low >= 0: chunk indices are never negative.
        n << low as usize
    }

    /// The exact value: `Ok(rational)` when every term was finite, else
    /// `Err(nan_or_infinity)`.
    pub fn value(&self) -> Result<Rational, f64> {
        if self.nan || (self.pos_inf && self.neg_inf) {
            return Err(f64::NAN);
        }
        if self.pos_inf {
            return Err(f64::INFINITY);
        }
        if self.neg_inf {
            return Err(f64::NEG_INFINITY);
        }
        let n = self.integer();
        if n.is_zero() {
            return Ok(Rational::zero());
        }
        // N / 2^1074 reduced by hand (the power of two is the only common
        // factor): a gcd of 1100-bit integers per statistic would dominate
        // the cost of a small run.
        let tz = n.trailing_zeros().unwrap_or(0).min(SCALE as u64);
        let reduced = BigRational::new_raw(n >> tz as usize, BigInt::one() << (SCALE as u64 - tz) as usize);
        Ok(Rational::from(reduced))
    }

    /// The sum as a double: a function of the exact value alone, so the same
    /// however the terms were grouped.
    pub fn to_f64(&self) -> f64 {
        match self.value() {
            Ok(r) => exact::rational_to_f64(&r),
            Err(x) => x,
        }
    }

    /// The exact value as text: `p/q` (or an integer), `nan`, `inf` or
    /// `-inf`.
    pub fn to_text(&self) -> String {
        match self.value() {
            Ok(r) => r.to_string(),
            Err(x) if x.is_nan() => "nan".into(),
            Err(x) if x > 0.0 => "inf".into(),
            Err(_) => "-inf".into(),
        }
    }

    /// Read [`Self::to_text`]; `None` unless the text is a sum of doubles
    /// (a rational whose denominator is a power of two at most `2^1074`),
    /// `nan`, `inf` or `-inf`.
    pub fn from_text(text: &str) -> Option<ExactSum> {
        let mut s = ExactSum::new();
        match text {
            "nan" => s.nan = true,
            "inf" => s.pos_inf = true,
            "-inf" => s.neg_inf = true,
            _ => {
                let r = exact::parse_certificate_rational(text).ok()?;
                let scaled = r * Rational::new(BigInt::one() << SCALE as usize, BigInt::one());
                if !scaled.is_integer() {
                    return None;
                }
                let n = scaled.numer();
                // Bounded: a sum of at most 2^64 doubles stays below 2^(1024 + 64).
                if n.bits() > (SCALE as u64 + 1024 + 64) {
                    return None;
                }
                let negative = n < BigInt::zero();
                let digits = n.magnitude().to_u32_digits();
                s.base = 0;
                s.chunks = digits.iter().map(|d| if negative { -(*d as i64) } else { *d as i64 }).collect();
                s.chunks.push(0);
                s.carry();
            }
        }
        Some(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The exact value of a list of doubles, by rationals.
    fn exact_sum(xs: &[f64]) -> Rational {
        xs.iter().fold(Rational::zero(), |acc, x| acc + Rational::from_float(*x).unwrap())
    }

    proptest! {
        /// Any grouping of any finite doubles (across the whole exponent
        /// range, both signs, subnormals) gives the exact rational sum, and
        /// the text round-trips.
        #[test]
        fn sums_are_exact_in_any_grouping(
            xs in proptest::collection::vec(
                prop_oneof![any::<f64>().prop_filter("finite", |x| x.is_finite()), -1e3f64..1e3, Just(f64::MIN_POSITIVE / 8.0)],
                0..40),
            split in 0usize..40,
        ) {
            let split = split.min(xs.len());
            let mut whole = ExactSum::new();
            xs.iter().for_each(|x| whole.add(*x));
            let (mut a, mut b) = (ExactSum::new(), ExactSum::new());
            xs[..split].iter().for_each(|x| a.add(*x));
            xs[split..].iter().rev().for_each(|x| b.add(*x));
            b.merge(&a);
            let want = exact_sum(&xs);
            prop_assert_eq!(whole.value().unwrap(), want.clone());
            prop_assert_eq!(b.value().unwrap(), want.clone());
            let back = ExactSum::from_text(&whole.to_text()).unwrap();
            prop_assert_eq!(back.value().unwrap(), want);
            prop_assert_eq!(back.to_f64().to_bits(), whole.to_f64().to_bits());
        }
    }

    /// 0.1 + 0.2 - 0.3 is not zero in floating point but is exactly
    /// 2^-54 + 2^-56 ... : the exact sum of the three doubles, and
    /// cancelling sums end exactly at zero.
    #[test]
    fn cancellation_is_exact() {
        let mut s = ExactSum::new();
        for x in [1e300, 1.0, -1e300] {
            s.add(x);
        }
        assert_eq!(s.to_f64(), 1.0);
        let mut z = ExactSum::new();
        for x in [0.1, 0.2, -0.1, -0.2] {
            z.add(x);
        }
        assert_eq!(z.value().unwrap(), Rational::zero());
        assert_eq!(z.to_text(), "0");
        assert_eq!(ExactSum::from_text("0").unwrap().to_f64(), 0.0);
    }

    /// Many additions pass the carry threshold without losing anything.
    #[test]
    fn carries_keep_the_value() {
        let mut s = ExactSum::new();
        s.adds = ADDS_BEFORE_CARRY - 3;
        for _ in 0..10 {
            s.add(f64::MAX / 4.0);
            s.add(-3.5);
        }
        let want = (Rational::from_float(f64::MAX / 4.0).unwrap() - Rational::new_small(7, 2)) * Rational::from(10);
        assert_eq!(s.value().unwrap(), want);
    }

    /// Non-finite terms: NaN wins, opposite infinities make NaN, and the
    /// text names them; text that no sum of doubles has is refused.
    #[test]
    fn non_finite_and_bad_text() {
        let mut s = ExactSum::new();
        s.add(f64::INFINITY);
        assert_eq!(s.to_f64(), f64::INFINITY);
        assert_eq!(s.to_text(), "inf");
        s.add(f64::NEG_INFINITY);
        assert!(s.to_f64().is_nan());
        assert_eq!(s.to_text(), "nan");
        assert!(ExactSum::from_text("-inf").unwrap().to_f64() == f64::NEG_INFINITY);
        for bad in ["1/3", "0.5", "x", "", "1/0"] {
            assert!(ExactSum::from_text(bad).is_none(), "{bad}");
        }
        let too_big = format!("{}", BigInt::one() << 1200usize);
        assert!(ExactSum::from_text(&too_big).is_none());
    }
}
