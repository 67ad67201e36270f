//! Exact rational numbers and their exact parsing from text.

use num_bigint::BigInt;
use num_traits::{One, Zero};

pub use crate::rational::Rational;

/// Largest decimal exponent accepted in a literal such as `1e300`.
///
/// Bounded so that a literal like `1e999999999` cannot make the parser build
/// a gigantic integer (a hang on bad input); 10^400 is already far outside the
/// range of `f64`, so nothing physical is lost.
pub const MAX_DECIMAL_EXPONENT: i64 = 400;

/// Most digits accepted in one literal of a spec (`parse_number`). Reading a
/// decimal costs time quadratic in its digits; a thousand digits is far
/// beyond any physical constant, and a 100,000-digit parameter took seconds
/// per use before this limit.
pub const MAX_LITERAL_DIGITS: usize = 1000;

/// Why a piece of text is not an exact number.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum NumberError {
    /// The text is empty.
    #[error("empty number")]
    Empty,
    /// The text is not an integer, a decimal literal or `p/q`.
    #[error(
        "'{text}' is not a number (expected an integer, a decimal such as 0.3 or 1e-3, or a rational such as 3/10)"
    )]
    Malformed {
        /// The offending text.
        text: String,
    },
    /// `p/0`.
    #[error("'{text}' has a zero denominator")]
    ZeroDenominator {
        /// The offending text.
        text: String,
    },
    /// `nan`, `inf`, or an exponent so large that the value is not a finite double.
    #[error("'{text}' is not a finite number")]
    NotFinite {
        /// The offending text.
        text: String,
    },
    /// More digits than allowed (the cost of reading a number grows with
    /// the square of its digits).
    #[error("a number of {digits} digits is longer than the limit of {limit}")]
    TooLong {
        /// Digits found.
        digits: usize,
        /// The limit.
        limit: usize,
    },
}

/// Parse an integer, a decimal literal (with optional exponent) or a rational
/// `p/q` into an exact [`Rational`].
///
/// Decimal literals are read exactly: `0.3` is `3/10`, not the double nearest
/// to it. Values whose magnitude does not fit a finite `f64` are rejected,
/// because every number the engine certifies must also be usable in floating
/// point.
///
/// ```
/// use exact::{parse_number, Rational};
/// assert_eq!(parse_number("0.3").unwrap(), Rational::new(3.into(), 10.into()));
/// assert_eq!(parse_number("-3/6").unwrap(), Rational::new((-1).into(), 2.into()));
/// assert_eq!(parse_number("2.5e-1").unwrap(), Rational::new(1.into(), 4.into()));
/// assert!(parse_number("1e999").is_err());
/// assert!(parse_number("NaN").is_err());
/// ```
pub fn parse_number(text: &str) -> Result<Rational, NumberError> {
    let t = text.trim();
    if t.is_empty() {
        return Err(NumberError::Empty);
    }
    let digits = t.bytes().filter(u8::is_ascii_digit).count();
    if digits > MAX_LITERAL_DIGITS {
        return Err(NumberError::TooLong { digits, limit: MAX_LITERAL_DIGITS });
    }
    let lower = t.to_ascii_lowercase();
    let stripped = lower.trim_start_matches(['+', '-']);
    if stripped.starts_with("nan") || stripped.starts_with("inf") {
        return Err(NumberError::NotFinite { text: crate::quote(t, 60) });
    }
    let value = if let Some((num, den)) = t.split_once('/') {
        let n = parse_decimal(num.trim(), t)?;
        let d = parse_decimal(den.trim(), t)?;
        if d.is_zero() {
            return Err(NumberError::ZeroDenominator { text: crate::quote(t, 60) });
        }
        n / d
    } else {
        parse_decimal(t, t)?
    };
    if !rational_to_f64(&value).is_finite() {
        return Err(NumberError::NotFinite { text: crate::quote(t, 60) });
    }
    Ok(value)
}

/// Parse `[+-]digits[.digits][(e|E)[+-]digits]` exactly.
fn parse_decimal(s: &str, whole: &str) -> Result<Rational, NumberError> {
    let malformed = || NumberError::Malformed { text: crate::quote(whole, 60) };
    let bytes = s.as_bytes();
    let mut i = 0;
    let mut negative = false;
    if i < bytes.len() && (bytes[i] == b'+' || bytes[i] == b'-') {
        negative = bytes[i] == b'-';
        i += 1;
    }
    let int_start = i;
    while i < bytes.len() && bytes[i].is_ascii_digit() {
        i += 1;
    }
    let int_digits = &s[int_start..i];
    let mut frac_digits = "";
    if i < bytes.len() && bytes[i] == b'.' {
        i += 1;
        let frac_start = i;
        while i < bytes.len() && bytes[i].is_ascii_digit() {
            i += 1;
        }
        frac_digits = &s[frac_start..i];
    }
    if int_digits.is_empty() && frac_digits.is_empty() {
        return Err(malformed());
    }
    let mut exponent: i64 = 0;
    if i < bytes.len() && (bytes[i] == b'e' || bytes[i] == b'E') {
        i += 1;
        let mut exp_negative = false;
        if i < bytes.len() && (bytes[i] == b'+' || bytes[i] == b'-') {
            exp_negative = bytes[i] == b'-';
            i += 1;
        }
        let exp_start = i;
        while i < bytes.len() && bytes[i].is_ascii_digit() {
            i += 1;
        }
        let exp_digits = &s[exp_start..i];
        if exp_digits.is_empty() {
            return Err(malformed());
        }
        // Long digit strings are rejected before conversion, so no overflow.
        if exp_digits.trim_start_matches('0').len() > 6 {
            return Err(NumberError::NotFinite { text: crate::quote(whole, 60) });
        }
        exponent = exp_digits.parse::<i64>().map_err(|_| malformed())?;
        if exp_negative {
            exponent = -exponent;
        }
    }
    if i != bytes.len() {
        return Err(malformed());
    }
    // Fast path: short literals (the common case) never touch big integers.
    if exponent == 0 && int_digits.len() + frac_digits.len() <= 18 {
        let mut m: i64 = 0;
        for b in int_digits.bytes().chain(frac_digits.bytes()) {
            m = m * 10 + (b - b'0') as i64;
        }
        let d = 10i64.pow(frac_digits.len() as u32);
        let value = Rational::new_small(if negative { -m } else { m }, d);
        return Ok(value);
    }
    let digits = format!("{int_digits}{frac_digits}");
    let mantissa: BigInt = digits.parse().map_err(|_| malformed())?;
    if mantissa.is_zero() {
        return Ok(Rational::zero());
    }
    let total_exponent = exponent - frac_digits.len() as i64;
    // The decimal point position plus the digit count bounds the magnitude.
    let magnitude = total_exponent + digits.trim_start_matches('0').len() as i64;
    if !(-MAX_DECIMAL_EXPONENT..=MAX_DECIMAL_EXPONENT).contains(&magnitude) {
        return Err(NumberError::NotFinite { text: crate::quote(whole, 60) });
    }
    let ten = BigInt::from(10);
    let value = if total_exponent >= 0 {
        Rational::from_integer(mantissa * num_traits::pow(ten, total_exponent as usize))
    } else {
        Rational::new(mantissa, num_traits::pow(ten, (-total_exponent) as usize))
    };
    Ok(if negative { -value } else { value })
}

/// The double nearest to a rational (correctly rounded for moderate sizes).
///
/// ```
/// use exact::{rational_to_f64, Rational};
/// assert_eq!(rational_to_f64(&Rational::new(1.into(), 3.into())), 1.0 / 3.0);
/// ```
#[inline]
pub fn rational_to_f64(r: &Rational) -> f64 {
    if let Some(v) = r.to_f64().filter(|v| v.is_finite()) {
        return v;
    }
    // Beyond the double range (or a big-integer corner case): compare bit
    // lengths to return a signed infinity or the scaled ratio.
    let (n, d) = (r.numer(), r.denom());
    let shift = n.bits() as i64 - d.bits() as i64;
    if shift > 1100 {
        return if r.is_negative() { f64::NEG_INFINITY } else { f64::INFINITY };
    }
    if shift < -1100 {
        return 0.0;
    }
    let scaled = if shift > 60 {
        Rational::new(n, d << (shift - 60) as usize)
    } else {
        Rational::new(n << (-shift + 60).max(0) as usize, d)
    };
    let v = scaled.to_f64().unwrap_or(0.0);
    if shift > 60 {
        v * 2f64.powi((shift - 60) as i32)
    } else {
        v * 2f64.powi((shift - 60).min(0) as i32)
    }
}

/// The exact rational value of a finite double, or `None` for NaN/infinity.
///
/// ```
/// use exact::{rational_from_f64, Rational};
/// assert_eq!(rational_from_f64(0.25).unwrap(), Rational::new(1.into(), 4.into()));
/// assert!(rational_from_f64(f64::NAN).is_none());
/// ```
pub fn rational_from_f64(x: f64) -> Option<Rational> {
    if !x.is_finite() {
        return None;
    }
    Rational::from_float(x)
}

/// A short decimal approximation with a rational's exact value chosen to be
/// simple: the best rational approximation with denominator at most
/// `max_denominator` (continued fractions).
///
/// Used to round numerically chosen free parameters to rationals that are
/// pleasant to read in a certificate.
pub fn best_rational_approximation(x: f64, max_denominator: u64) -> Option<Rational> {
    if !x.is_finite() {
        return None;
    }
    let negative = x < 0.0;
    let mut v = x.abs();
    let (mut p0, mut q0, mut p1, mut q1): (u128, u128, u128, u128) = (0, 1, 1, 0);
    for _ in 0..64 {
        let a = v.floor();
        if a > 1e18 {
            break;
        }
        let a_int = a as u128;
        let p2 = a_int.checked_mul(p1)?.checked_add(p0)?;
        let q2 = a_int.checked_mul(q1)?.checked_add(q0)?;
        if q2 > max_denominator as u128 {
            break;
        }
        p0 = p1;
        q0 = q1;
        p1 = p2;
        q1 = q2;
        let frac = v - a;
        if frac < 1e-15 {
            break;
        }
        v = 1.0 / frac;
    }
    if q1 == 0 {
        return None;
    }
    let r = match (i64::try_from(p1), i64::try_from(q1)) {
        (Ok(p), Ok(q)) => Rational::new_small(p, q),
        _ => Rational::new(BigInt::from(p1), BigInt::from(q1)),
    };
    Some(if negative { -r } else { r })
}

/// The smallest decimal with `digits` significant digits that is `>= x`, as
/// an exact rational (checked exactly against the double `x`). `None` for a
/// non-finite or non-positive `x` or `digits` outside `1..=17`.
///
/// ```
/// use exact::{decimal_at_least, Rational};
/// assert_eq!(decimal_at_least(0.25, 3).unwrap(), Rational::new_small(1, 4));
/// // The double nearest 0.27 is slightly above 27/100, so the bound is 0.271.
/// assert_eq!(decimal_at_least(0.27, 3).unwrap(), Rational::new_small(271, 1000));
/// assert_eq!(decimal_at_least(1234.5, 2).unwrap(), Rational::from(1300));
/// assert!(decimal_at_least(1.0 / 3.0, 5).unwrap() >= exact::rational_from_f64(1.0 / 3.0).unwrap());
/// ```
pub fn decimal_at_least(x: f64, digits: u32) -> Option<Rational> {
    if !x.is_finite() || x <= 0.0 || !(1..=17).contains(&digits) {
        return None;
    }
    let e = x.log10().floor() as i32 - (digits as i32 - 1);
    if let Some(r) = decimal_ceiling_fast(x, e, digits) {
        return Some(r);
    }
    let exact_x = Rational::from_float(x)?;
    let ten = BigInt::from(10);
    let unit = if e >= 0 {
        Rational::from_integer(num_traits::pow(ten, e as usize))
    } else {
        Rational::new(BigInt::from(1), num_traits::pow(ten, (-e) as usize))
    };
    // ceil(x / unit) computed exactly.
    let q = &exact_x / &unit;
    let mut n = q.to_integer();
    if Rational::from_integer(n.clone()) < q {
        n += 1;
    }
    Some(Rational::from_integer(n) * unit)
}

/// `ceil(x / 10^e) 10^e` without big integers, when `digits <= 15` and
/// `|e| <= 18` and the comparison fits `i128` (a hand-written shortcut:
/// this runs for every entry of every rounded matrix, and the big-rational
/// path costs microseconds). `y = x / 10^e` is one correctly rounded
/// operation (`10^|e|` is an exact double) and `y < 1e15 < 2^50`, so it is
/// within 1/16 of the true quotient `t`; with `n = round(y)`, `ceil(t)` is
/// `n` if `x <= n 10^e` and `n + 1` otherwise, decided exactly in integers
/// from `x = m 2^k`.
fn decimal_ceiling_fast(x: f64, e: i32, digits: u32) -> Option<Rational> {
    if digits > 15 || !(-18..=18).contains(&e) {
        return None;
    }
    let p = 10i64.pow(e.unsigned_abs());
    let y = if e >= 0 { x / p as f64 } else { x * p as f64 };
    if y.is_nan() || y >= 1e15 {
        return None;
    }
    let n = y.round() as i64;
    // x = m 2^k exactly (x is positive and normal or subnormal).
    let bits = x.to_bits();
    let exponent = ((bits >> 52) & 0x7ff) as i32;
    let (m, k) = if exponent == 0 {
        ((bits & ((1u64 << 52) - 1)) as i128, -1074)
    } else {
        (((bits & ((1u64 << 52) - 1)) | (1u64 << 52)) as i128, exponent - 1075)
    };
    // a 2^s for s >= 0, if it fits.
    let shifted =
        |a: i128, s: i32| -> Option<i128> { (s < 126 && (a == 0 || a.leading_zeros() as i32 > s + 1)).then(|| a << s) };
    // x <= n 10^e, as `lhs <= rhs` in integers.
    let (lhs, rhs) = if e >= 0 {
        let rhs = n as i128 * p as i128;
        if k >= 0 {
            (shifted(m, k)?, rhs)
        } else {
            (m, shifted(rhs, -k)?)
        }
    } else {
        let lhs = m * p as i128;
        if k >= 0 {
            (shifted(lhs, k)?, n as i128)
        } else {
            (lhs, shifted(n as i128, -k)?)
        }
    };
    let ceiling = if lhs <= rhs { n } else { n + 1 };
    if e >= 0 {
        ceiling.checked_mul(p).map(Rational::from)
    } else {
        Some(Rational::new_small(ceiling, p))
    }
}

/// `x` rounded to a decimal with `digits` significant digits (away from
/// zero), as an exact rational; `0` for `0`, `None` for a non-finite `x` or
/// `digits` outside `1..=17`. Short denominators (powers of ten) for
/// numbers that only need to be near a floating-point value.
///
/// ```
/// use exact::{decimal_near, Rational};
/// assert_eq!(decimal_near(-0.25, 3).unwrap(), Rational::new_small(-1, 4));
/// assert_eq!(decimal_near(0.0, 3).unwrap(), Rational::from(0));
/// let r = decimal_near(-1.0 / 3.0, 15).unwrap();
/// assert!((exact::rational_to_f64(&r) + 1.0 / 3.0).abs() < 1e-15);
/// ```
pub fn decimal_near(x: f64, digits: u32) -> Option<Rational> {
    if x == 0.0 {
        return (x.is_finite() && (1..=17).contains(&digits)).then(Rational::zero);
    }
    if x > 0.0 {
        decimal_at_least(x, digits)
    } else {
        decimal_at_least(-x, digits).map(|r| -r)
    }
}

/// `floor(log2 |r|)` for `r != 0` (exact, from the bit lengths and one
/// comparison), `None` for zero.
///
/// ```
/// use exact::{binary_exponent, Rational};
/// assert_eq!(binary_exponent(&Rational::new_small(3, 1)), Some(1));
/// assert_eq!(binary_exponent(&Rational::new_small(1, 4)), Some(-2));
/// assert_eq!(binary_exponent(&Rational::new_small(-5, 16)), Some(-2)); // 5/16 = 0.3125 in [1/4, 1/2)
/// assert_eq!(binary_exponent(&Rational::new_small(0, 1)), None);
/// ```
pub fn binary_exponent(r: &Rational) -> Option<i64> {
    r.log2_floor()
}

/// `2^e` as an exact rational.
///
/// ```
/// use exact::{power_of_two, Rational};
/// assert_eq!(power_of_two(-3), Rational::new_small(1, 8));
/// assert_eq!(power_of_two(10), Rational::from(1024));
/// ```
pub fn power_of_two(e: i64) -> Rational {
    let big = BigInt::from(1) << e.unsigned_abs() as usize;
    if e >= 0 {
        Rational::from_integer(big)
    } else {
        Rational::new(BigInt::from(1), big)
    }
}

/// The smallest double `>= r` (`f64::INFINITY` beyond the largest double).
///
/// ```
/// use exact::{rational_to_f64_up, Rational};
/// let third = Rational::new_small(1, 3);
/// let x = rational_to_f64_up(&third);
/// assert!(Rational::from_float(x).unwrap() >= third && x == 1.0 / 3.0 || x == (1.0f64 / 3.0).next_up());
/// assert_eq!(rational_to_f64_up(&Rational::new_small(1, 4)), 0.25);
/// ```
pub fn rational_to_f64_up(r: &Rational) -> f64 {
    let x = rational_to_f64(r);
    if !x.is_finite() {
        return if r.is_negative() { f64::MIN } else { f64::INFINITY };
    }
    // `rational_to_f64` may be off by more than one unit in the last place
    // either way (a quotient of two rounded integers): step up until the
    // exact value of the double is at least `r`, then down while the next
    // double below still is, so the result is the smallest double >= r.
    let mut x = x;
    while x.is_finite() {
        match Rational::from_float(x) {
            Some(exact_x) if &exact_x < r => x = x.next_up(),
            _ => break,
        }
    }
    while x.is_finite() {
        match Rational::from_float(x.next_down()) {
            Some(below) if &below >= r => x = x.next_down(),
            _ => break,
        }
    }
    if x.is_finite() {
        x
    } else {
        f64::INFINITY
    }
}

/// Largest number of digits in a rational read by [`parse_certificate_rational`].
pub const MAX_CERTIFICATE_DIGITS: usize = 20_000;

/// Read a rational written by the engine into a certificate: an integer or
/// `p/q` with integers `p`, `q` (no decimal point, no exponent), exactly,
/// whatever its size up to [`MAX_CERTIFICATE_DIGITS`] digits in all. Unlike
/// [`parse_number`], which reads a *spec*'s numbers and insists that they are
/// finite doubles, this reads what exact arithmetic produced: `Q` entries of
/// `1/10^600` are legitimate there and must re-check.
///
/// ```
/// use exact::{parse_certificate_rational, Rational};
/// let tiny = format!("1/1{}", "0".repeat(600));
/// assert!(parse_certificate_rational(&tiny).unwrap() > Rational::new_small(0, 1));
/// assert_eq!(parse_certificate_rational("-3/6").unwrap(), Rational::new_small(-1, 2));
/// assert!(parse_certificate_rational("0.5").is_err());
/// assert!(parse_certificate_rational(&"9".repeat(30_000)).is_err());
/// ```
pub fn parse_certificate_rational(text: &str) -> Result<Rational, NumberError> {
    let t = text.trim();
    let malformed = || NumberError::Malformed { text: crate::quote(t, 60) };
    let digits = t.bytes().filter(u8::is_ascii_digit).count();
    if digits > MAX_CERTIFICATE_DIGITS {
        return Err(NumberError::TooLong { digits, limit: MAX_CERTIFICATE_DIGITS });
    }
    let integer = |s: &str| -> Result<BigInt, NumberError> {
        let body = s.strip_prefix('-').or_else(|| s.strip_prefix('+')).unwrap_or(s);
        if body.is_empty() || !body.bytes().all(|b| b.is_ascii_digit()) {
            return Err(malformed());
        }
        s.parse::<BigInt>().map_err(|_| malformed())
    };
    match t.split_once('/') {
        Some((n, d)) => {
            let (n, d) = (integer(n)?, integer(d)?);
            if d.is_zero() {
                return Err(NumberError::ZeroDenominator { text: crate::quote(t, 60) });
            }
            Ok(Rational::new(n, d))
        }
        None => Ok(Rational::from_integer(integer(t)?)),
    }
}

/// `1` as a rational (convenience).
pub(crate) fn one() -> Rational {
    Rational::one()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// `rational_to_f64` divides two rounded integers, which can land two
    /// units below the quotient; one step up was not always enough (a
    /// review found this quotient 2e-17 relative below after one step).
    #[test]
    fn rounding_up_is_at_least_the_rational() {
        let r = Rational::new(2604018746780635317i64.into(), 1456756553584590308i64.into());
        let x = rational_to_f64_up(&r);
        assert!(Rational::from_float(x).unwrap() >= r);
        assert!(Rational::from_float(x.next_down()).unwrap() < r, "the smallest double above");
    }

    proptest! {
        #[test]
        fn rounding_up_never_falls_below(n in 1i64..i64::MAX, d in 1i64..i64::MAX) {
            let r = Rational::new(n.into(), d.into());
            let x = rational_to_f64_up(&r);
            prop_assert!(Rational::from_float(x).unwrap() >= r);
            prop_assert!(Rational::from_float(x.next_down()).unwrap() < r);
        }
    }

    /// The definition, by big integers only: the smallest multiple of
    /// `10^e` that is `>= x`.
    fn decimal_at_least_by_definition(x: f64, digits: u32) -> Rational {
        let exact_x = Rational::from_float(x).unwrap();
        let e = x.log10().floor() as i32 - (digits as i32 - 1);
        let unit = if e >= 0 {
            Rational::from_integer(num_traits::pow(BigInt::from(10), e as usize))
        } else {
            Rational::new(BigInt::from(1), num_traits::pow(BigInt::from(10), (-e) as usize))
        };
        let q = &exact_x / &unit;
        let mut n = q.to_integer();
        if Rational::from_integer(n.clone()) < q {
            n += 1;
        }
        Rational::from_integer(n) * unit
    }

    proptest! {
        /// The floating-point fast path of `decimal_at_least` gives the
        /// same decimal as the definition, across magnitudes and digits.
        #[test]
        fn decimal_fast_path_is_exact(mantissa in 1.0f64..10.0, exponent in -25i32..25, digits in 1u32..=17) {
            let x = mantissa * 10f64.powi(exponent);
            prop_assert_eq!(decimal_at_least(x, digits).unwrap(), decimal_at_least_by_definition(x, digits));
        }

        /// Short decimals, where `x / 10^e` is at or next to an integer
        /// (the case the fast path decides by an exact comparison).
        #[test]
        fn decimal_fast_path_at_short_decimals(n in 1i64..200_000, exponent in -20i32..20, digits in 1u32..=17) {
            let x = n as f64 * 10f64.powi(exponent);
            prop_assert_eq!(decimal_at_least(x, digits).unwrap(), decimal_at_least_by_definition(x, digits));
            let below = f64::from_bits(x.to_bits() - 1);
            prop_assert_eq!(decimal_at_least(below, digits).unwrap(), decimal_at_least_by_definition(below, digits));
        }
    }

    fn q(n: i64, d: i64) -> Rational {
        Rational::new(n.into(), d.into())
    }

    #[test]
    fn decimal_literals_are_exact() {
        assert_eq!(parse_number("0.3").unwrap(), q(3, 10));
        assert_eq!(parse_number("-.5").unwrap(), q(-1, 2));
        assert_eq!(parse_number("12").unwrap(), q(12, 1));
        assert_eq!(parse_number("1e-3").unwrap(), q(1, 1000));
        assert_eq!(parse_number("1.25E+2").unwrap(), q(125, 1));
        assert_eq!(parse_number("3/10").unwrap(), q(3, 10));
        assert_eq!(parse_number(" 0.5/0.25 ").unwrap(), q(2, 1));
    }

    #[test]
    fn bad_numbers_are_rejected_with_reason() {
        assert!(matches!(parse_number(""), Err(NumberError::Empty)));
        assert!(matches!(parse_number("abc"), Err(NumberError::Malformed { .. })));
        assert!(matches!(parse_number("1/0"), Err(NumberError::ZeroDenominator { .. })));
        assert!(matches!(parse_number("inf"), Err(NumberError::NotFinite { .. })));
        assert!(matches!(parse_number("-Infinity"), Err(NumberError::NotFinite { .. })));
        assert!(matches!(parse_number("1e400"), Err(NumberError::NotFinite { .. })));
        assert!(matches!(parse_number("1e99999999999999"), Err(NumberError::NotFinite { .. })));
        assert!(matches!(parse_number("1.2.3"), Err(NumberError::Malformed { .. })));
        assert!(matches!(parse_number("e5"), Err(NumberError::Malformed { .. })));
    }

    #[test]
    fn long_literals_are_refused_with_their_length_not_echoed() {
        // Regression: a 100,000-digit parameter took time quadratic in its
        // digits, and error messages echoed the whole literal.
        let long = "1".repeat(100_000);
        assert!(matches!(parse_number(&long), Err(NumberError::TooLong { digits: 100_000, .. })));
        let junk = format!("{}x", "1".repeat(500));
        let message = parse_number(&junk).unwrap_err().to_string();
        assert!(message.len() < 200, "{message}");
        assert!(parse_number(&format!("0.{}", "1".repeat(MAX_LITERAL_DIGITS - 1))).is_ok());
    }

    #[test]
    fn continued_fraction_rounding() {
        assert_eq!(best_rational_approximation(0.333333333333, 1000).unwrap(), q(1, 3));
        assert_eq!(best_rational_approximation(-2.5, 10).unwrap(), q(-5, 2));
        assert_eq!(best_rational_approximation(std::f64::consts::PI, 1000).unwrap(), q(355, 113));
    }
}
