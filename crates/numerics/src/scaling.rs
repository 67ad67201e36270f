//! Power-of-two rescaling: data brought to unit size without rounding, and
//! results scaled back.
//!
//! The pipelines' answers are homogeneous in their data: `Sigma^2` is of
//! degree two in the noise (the generator's form `Q` is quadratic in the
//! noise fields and `P` does not see them), and the drift's rates are of
//! degree one in the state. Data near `1e308` or `1e-308` would overflow or
//! underflow in the solves, so each pipeline divides its data by a power of
//! two `s = 2^e`, runs on data of size about one, and multiplies the
//! results back (`Sigma^2` by `s^2`).
//!
//! Multiplying a double by a power of two is exact while the result stays
//! in the normal range (`[2^-1022, 2^1024)`), so a bound proved for the
//! scaled problem is a bound for the problem as given, provided that
//! neither the scaling nor the scaling back left that range.
//! [`Rescaling::square_bound`] scales an upper bound back and keeps it an
//! upper bound (a result below the normal range is rounded up), and
//! [`Rescaling::out_of_range`] says when a result cannot be stated in a
//! double at all (then the verdict is `inconclusive`, never `stable`).
//!
//! ```
//! use numerics::scaling::{exponent_of, Rescaling};
//! // Noise of size 3e-100: divided by 2^e with 3e-100 / 2^e in [1/2, 1).
//! let r = Rescaling::new(exponent_of(3e-100));
//! let unit = 3e-100 * r.down();
//! assert!((0.5..1.0).contains(&unit));
//! // A Sigma^2 of 0.25 for the unit-size noise is 0.25 * 4^e for the noise as given, exactly.
//! let back = r.square(0.25);
//! assert_eq!(back / (r.up() * r.up()), 0.25);
//! assert_eq!(r.square_bound(0.25), Some(back));
//! // Noise 1e200 would give a Sigma^2 near 1e400: no double holds it.
//! assert!(Rescaling::new(exponent_of(1e200)).out_of_range(1.0).is_some());
//! ```

/// `2^e` for `-1022 <= e <= 1023` (clamped), exactly.
///
/// ```
/// assert_eq!(numerics::scaling::pow2(10), 1024.0);
/// assert_eq!(numerics::scaling::pow2(-1022), f64::MIN_POSITIVE);
/// ```
pub fn pow2(e: i32) -> f64 {
    f64::from_bits(((e.clamp(-1022, 1023) + 1023) as u64) << 52)
}

/// The exponent `e` with `max / 2^e` in `[1/2, 1)`, that is
/// `floor(log2 max) + 1`, read off the bits (no `log2` rounding), clamped
/// to `[-1000, 1000]`; 0 for zero or a value that is not finite. A
/// subnormal `max` gives `-1022`.
///
/// ```
/// use numerics::scaling::exponent_of;
/// assert_eq!(exponent_of(1.0), 1); // 1 / 2 = 0.5
/// assert_eq!(exponent_of(0.75), 0);
/// assert_eq!(exponent_of(0.0), 0);
/// assert_eq!(exponent_of(f64::NAN), 0);
/// ```
pub fn exponent_of(max: f64) -> i32 {
    let max = max.abs();
    if !(max.is_finite() && max > 0.0) {
        return 0;
    }
    let exponent = if max >= f64::MIN_POSITIVE { ((max.to_bits() >> 52) & 0x7ff) as i32 - 1022 } else { -1022 };
    exponent.clamp(-1000, 1000)
}

/// The power of two nearest to `x` on a logarithmic scale,
/// `2^round(log2 x)` (clamped to the normal range); 1 for `x <= 0` or a
/// value that is not finite. Dividing by it brings `x` into
/// `[1/sqrt 2, sqrt 2]` (up to the rounding of `log2`) without rounding.
///
/// ```
/// use numerics::scaling::nearest_power_of_two;
/// assert_eq!(nearest_power_of_two(3.0), 4.0);
/// assert_eq!(nearest_power_of_two(0.3), 0.25);
/// assert_eq!(nearest_power_of_two(0.0), 1.0);
/// ```
pub fn nearest_power_of_two(x: f64) -> f64 {
    if x > 0.0 && x.is_finite() {
        pow2(x.log2().round() as i32)
    } else {
        1.0
    }
}

/// Data divided by `2^e`: the factor down, and the scaling back of results
/// homogeneous of degree two (`Sigma^2`, eigenvalues of `Q` against `P`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rescaling {
    exponent: i32,
}

impl Rescaling {
    /// Data divided by `2^exponent` (clamped to `[-1022, 1022]`, so that
    /// both `2^e` and `2^-e` are normal doubles).
    pub fn new(exponent: i32) -> Self {
        Rescaling { exponent: exponent.clamp(-1022, 1022) }
    }

    /// Data divided by the power of two nearest to `size`
    /// ([`nearest_power_of_two`]; none for zero or a value that is not
    /// finite).
    pub fn nearest(size: f64) -> Self {
        if size > 0.0 && size.is_finite() {
            Rescaling::new(size.log2().round() as i32)
        } else {
            Rescaling::identity()
        }
    }

    /// No rescaling.
    pub fn identity() -> Self {
        Rescaling { exponent: 0 }
    }

    /// The exponent `e`.
    pub fn exponent(&self) -> i32 {
        self.exponent
    }

    /// `2^-e`: the factor that brings the data to unit size.
    pub fn down(&self) -> f64 {
        pow2(-self.exponent)
    }

    /// `2^e`: the factor that takes a result of degree one back.
    pub fn up(&self) -> f64 {
        pow2(self.exponent)
    }

    /// A result of degree two scaled back, `x * 4^e`, as two exact
    /// multiplications (exact while the result is a normal double; an
    /// estimate, not a bound, otherwise).
    pub fn square(&self, x: f64) -> f64 {
        let f = self.up();
        x * f * f
    }

    /// An upper bound of degree two scaled back, still an upper bound:
    /// `x * 4^e` exactly when it is a normal double, `f64::MIN_POSITIVE`
    /// when a positive result fell below the normal range (the exact
    /// product is smaller), and `None` when it overflowed.
    pub fn square_bound(&self, x: f64) -> Option<f64> {
        let y = self.square(x);
        if !y.is_finite() {
            None
        } else if x > 0.0 && y < f64::MIN_POSITIVE {
            Some(f64::MIN_POSITIVE)
        } else {
            Some(y)
        }
    }

    /// A bound stated for the data as given, in the units of the scaled
    /// data (`bound / 4^e`), rounded down if it fell below the normal range:
    /// proving the smaller bound proves the stated one.
    pub fn square_down(&self, bound: f64) -> f64 {
        let f = self.down();
        let y = bound * f * f;
        if y < f64::MIN_POSITIVE {
            y.next_down().max(0.0)
        } else {
            y
        }
    }

    /// Why the degree-two result `x` (of the scaled data) cannot be stated
    /// for the data as given: `x * 4^e` beyond the largest double, or
    /// positive and below the smallest normal one. `None` when it can.
    pub fn out_of_range(&self, x: f64) -> Option<String> {
        let y = self.square(x);
        let size = || x.log10() + 2.0 * self.exponent as f64 * std::f64::consts::LOG10_2;
        if !y.is_finite() {
            Some(format!(
                "Sigma^2 is about 10^{:.1} with this noise, beyond the largest double (1.8e308): rescale time or the noise amplitudes",
                size()
            ))
        } else if x > 0.0 && y < f64::MIN_POSITIVE {
            Some(format!(
                "Sigma^2 is about 10^{:.1} with this noise, below the smallest normal double (2.2e-308): rescale time or the noise amplitudes",
                size()
            ))
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exponent rule: max / 2^e in [1/2, 1) for normal values across the
    /// range (checked against the definition), and the clamp.
    #[test]
    fn the_exponent_brings_the_maximum_into_a_half_open_octave() {
        for x in [1e-300, 3e-200, 1e-10, 0.5, 0.999, 1.0, 7.0, 1e10, 1e300] {
            let e = exponent_of(x);
            let unit = x * pow2(-e);
            assert!((0.5..1.0).contains(&unit), "{x}: {unit}");
        }
        assert_eq!(exponent_of(1e-310), -1000);
        assert_eq!(exponent_of(-0.75), 0);
    }

    /// Scaling back is exact for normal results (the quotient by 4^e gives
    /// the input back), rounds a subnormal bound up, and refuses overflow.
    #[test]
    fn bounds_stay_bounds_when_scaled_back() {
        let r = Rescaling::new(-600);
        assert_eq!(r.square_bound(1.0), Some(f64::MIN_POSITIVE));
        assert!(r.out_of_range(1.0).unwrap().contains("below the smallest normal"));
        let r = Rescaling::new(600);
        assert_eq!(r.square_bound(1.0), None);
        assert!(r.out_of_range(1.0).unwrap().contains("beyond the largest double"));
        let r = Rescaling::new(100);
        let y = r.square_bound(0.3).unwrap();
        assert_eq!(y * pow2(-100) * pow2(-100), 0.3);
        assert_eq!(r.square_down(y), 0.3);
        assert_eq!(r.out_of_range(0.3), None);
        assert_eq!(Rescaling::nearest(3.0).up(), 4.0);
        assert_eq!(Rescaling::nearest(0.0), Rescaling::identity());
        for r in [Rescaling::nearest(f64::MAX), Rescaling::nearest(1e-310), Rescaling::new(5000)] {
            assert_eq!(r.up() * r.down(), 1.0, "{r:?}");
        }
    }
}
