//! Closed intervals of doubles with outward rounding: rigorous enclosures of
//! the range of an expression over a piece of the y-interval.
//!
//! Written here rather than taken from a crate because the interval crates
//! that round outward (inari) need a nightly toolchain and GMP; this module
//! needs only the four operations, `sqrt`, `exp`, `sin`, `cos`, the
//! hyperbolic `sinh`, `cosh`, `tanh`, `sech` and integer powers, and gets correct outward rounding on stable Rust from
//! error-free transformations instead of switching the rounding mode:
//!
//! * `a + b`: TwoSum gives the exact error `e` of `s = fl(a + b)`, so the
//!   exact sum is `s + e` and the bound moves one ulp only when `e != 0`;
//! * `a * b`: `e = fma(a, b, -p)` is the exact error of `p = fl(a b)`;
//! * `a / b`: `r = fma(-q, b, a) = a - q b` exactly, whose sign (times the
//!   sign of `b`) tells on which side of `q` the quotient lies;
//! * `sqrt a`: `r = fma(-s, s, a) = a - s^2` exactly.
//!
//! These identities are exact unless the result is near the underflow
//! threshold, where the bounds are simply widened by one ulp both ways. So
//! exact results stay exact (an interval `[0, 0]` stays `[0, 0]`), which is
//! what lets the fluid crate's expressions *prove* that `U'' = 0` for an affine profile.
//! `exp`, `sin`, `cos`, `sinh`, `cosh` and `tanh` come from the platform's
//! libm, whose error is below one ulp for `exp`, `sin`, `cos` on the
//! platforms Rust supports (glibc documents at most 1 ulp) and at most 3
//! ulps for `sinh`, `cosh`, `tanh` (glibc's `libm-test-ulps` tables list
//! 1 to 3 for them in double); the bounds are widened by [`LIBM_ULPS`] ulps. Overflow gives infinite
//! bounds, and an operation that is undefined on part of its argument
//! (division by an interval holding 0, `sqrt` of negatives) gives the whole
//! line: such an enclosure never proves a sign.

/// Ulps by which results of `exp`, `sin`, `cos`, `sinh`, `cosh` and `tanh` are widened.
pub const LIBM_ULPS: u32 = 4;

/// Below this magnitude the error-free transformations may be inexact
/// (their error terms can underflow), so bounds are widened regardless.
const TINY: f64 = 1e-290;

/// A closed interval `[lo, hi]` (`lo <= hi`; infinite bounds allowed).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    /// Lower bound.
    pub lo: f64,
    /// Upper bound.
    pub hi: f64,
}

fn down(x: f64, n: u32) -> f64 {
    (0..n).fold(x, |v, _| v.next_down())
}

fn up(x: f64, n: u32) -> f64 {
    (0..n).fold(x, |v, _| v.next_up())
}

/// Lower and upper bounds of the exact `a + b`.
fn add_bounds(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    if !s.is_finite() {
        return (if s == f64::INFINITY { f64::MAX } else { s }, if s == f64::NEG_INFINITY { f64::MIN } else { s });
    }
    let bb = s - a;
    let e = (a - (s - bb)) + (b - bb);
    if s.abs() < TINY && e != 0.0 {
        return (s.next_down(), s.next_up());
    }
    (if e < 0.0 { s.next_down() } else { s }, if e > 0.0 { s.next_up() } else { s })
}

/// Lower and upper bounds of the exact `a * b`.
fn mul_bounds(a: f64, b: f64) -> (f64, f64) {
    if a == 0.0 || b == 0.0 {
        return (0.0, 0.0);
    }
    let p = a * b;
    if !p.is_finite() {
        return (if p == f64::INFINITY { f64::MAX } else { p }, if p == f64::NEG_INFINITY { f64::MIN } else { p });
    }
    if p.abs() < TINY {
        return (p.next_down(), p.next_up());
    }
    let e = a.mul_add(b, -p);
    (if e < 0.0 { p.next_down() } else { p }, if e > 0.0 { p.next_up() } else { p })
}

/// Lower and upper bounds of the exact `a / b` (`b != 0`).
fn div_bounds(a: f64, b: f64) -> (f64, f64) {
    if a == 0.0 {
        return (0.0, 0.0);
    }
    let q = a / b;
    if !q.is_finite() {
        return (if q == f64::INFINITY { f64::MAX } else { q }, if q == f64::NEG_INFINITY { f64::MIN } else { q });
    }
    if q.abs() < TINY || b.abs() < TINY {
        return (q.next_down(), q.next_up());
    }
    let r = (-q).mul_add(b, a); // a - q b, exactly
    let above = (r > 0.0) == (b > 0.0) && r != 0.0; // the quotient exceeds q
    let below = r != 0.0 && !above;
    (if below { q.next_down() } else { q }, if above { q.next_up() } else { q })
}

impl Interval {
    /// The whole real line: nothing is known.
    pub const ENTIRE: Interval = Interval { lo: f64::NEG_INFINITY, hi: f64::INFINITY };

    /// The point `x` (the whole line for NaN).
    pub fn point(x: f64) -> Interval {
        if x.is_nan() {
            Interval::ENTIRE
        } else {
            Interval { lo: x, hi: x }
        }
    }

    /// `[lo, hi]` (the whole line if either bound is NaN or `lo > hi`).
    pub fn new(lo: f64, hi: f64) -> Interval {
        if lo.is_nan() || hi.is_nan() || lo > hi {
            Interval::ENTIRE
        } else {
            Interval { lo, hi }
        }
    }

    /// Whether `0` is in the interval.
    pub fn contains_zero(&self) -> bool {
        self.lo <= 0.0 && self.hi >= 0.0
    }

    /// Whether the interval is exactly `[0, 0]`.
    pub fn is_zero(&self) -> bool {
        self.lo == 0.0 && self.hi == 0.0
    }

    /// The intersection (`self` if they do not meet, which cannot happen for
    /// two enclosures of the same quantity).
    pub fn intersect(&self, o: &Interval) -> Interval {
        let (lo, hi) = (self.lo.max(o.lo), self.hi.min(o.hi));
        if lo <= hi {
            Interval { lo, hi }
        } else {
            *self
        }
    }

    /// The smallest interval holding both.
    pub fn hull(&self, o: &Interval) -> Interval {
        Interval { lo: self.lo.min(o.lo), hi: self.hi.max(o.hi) }
    }

    /// Square root (the whole line if the interval reaches below 0).
    pub fn sqrt(self) -> Interval {
        if self.lo < 0.0 {
            return Interval::ENTIRE;
        }
        let bound = |a: f64| -> (f64, f64) {
            let s = a.sqrt();
            if a == 0.0 || !s.is_finite() {
                return (s, s);
            }
            if a < TINY {
                return (s.next_down().max(0.0), s.next_up());
            }
            let r = (-s).mul_add(s, a); // a - s^2, exactly
            (if r < 0.0 { s.next_down() } else { s }, if r > 0.0 { s.next_up() } else { s })
        };
        Interval::new(bound(self.lo).0, bound(self.hi).1)
    }

    /// `exp`, widened by [`LIBM_ULPS`].
    pub fn exp(self) -> Interval {
        let lo = if self.lo == f64::NEG_INFINITY { 0.0 } else { down(self.lo.exp(), LIBM_ULPS).max(0.0) };
        let hi = if self.hi == 0.0 { 1.0 } else { up(self.hi.exp(), LIBM_ULPS) };
        Interval::new(if self.lo == 0.0 { 1.0 } else { lo }, hi)
    }

    /// `sinh`: increasing, so the image of the ends, each widened by
    /// [`LIBM_ULPS`]. An end that overflows gives an infinite bound (its
    /// outer side, `-inf` below or `+inf` above) or [`f64::MAX`] pulled in
    /// by the widening (its inner side): never a tighter one.
    pub fn sinh(self) -> Interval {
        let lo = if self.lo == 0.0 { 0.0 } else { down(self.lo.sinh(), LIBM_ULPS) };
        let hi = if self.hi == 0.0 { 0.0 } else { up(self.hi.sinh(), LIBM_ULPS) };
        Interval::new(lo, hi)
    }

    /// `cosh`: even, decreasing on `x <= 0` and increasing on `x >= 0`, so
    /// its minimum is at the end nearer 0 (exactly `1` when the interval
    /// holds 0) and its maximum at the end farther from 0; at least 1. An
    /// overflowing `cosh` is `+inf` above and `f64::MAX` (widened down)
    /// below, both true bounds.
    pub fn cosh(self) -> Interval {
        let (near, far) = self.magnitudes();
        let lo = if self.contains_zero() || near == 0.0 { 1.0 } else { down(near.cosh(), LIBM_ULPS).max(1.0) };
        let hi = if far == 0.0 { 1.0 } else { up(far.cosh(), LIBM_ULPS) };
        Interval::new(lo, hi)
    }

    /// `tanh`: increasing, so the image of the ends widened by
    /// [`LIBM_ULPS`], within `[-1, 1]` (it saturates: `tanh 20` rounds to
    /// 1, and the widened lower bound `1 - 4 ulp` is still below the true
    /// `1 - 8.5e-18`).
    pub fn tanh(self) -> Interval {
        let lo = if self.lo == 0.0 { 0.0 } else { down(self.lo.tanh(), LIBM_ULPS).max(-1.0) };
        let hi = if self.hi == 0.0 { 0.0 } else { up(self.hi.tanh(), LIBM_ULPS).min(1.0) };
        Interval::new(lo, hi)
    }

    /// `sech = 1 / cosh`, by the outward division of 1 by [`Interval::cosh`]
    /// (never 0 in it), within `[0, 1]`: even, largest (1) at 0. Where
    /// `cosh` overflows, its bounds `[f64::MAX, inf]` give `sech` the true
    /// bounds `[0, 1/f64::MAX]` (rounded up), never a tighter one.
    pub fn sech(self) -> Interval {
        let s = Interval::point(1.0) / self.cosh();
        Interval::new(s.lo.max(0.0), s.hi.min(1.0))
    }

    /// `(min |x|, max |x|)` over the interval.
    fn magnitudes(&self) -> (f64, f64) {
        let (a, b) = (self.lo.abs(), self.hi.abs());
        if self.contains_zero() {
            (0.0, a.max(b))
        } else {
            (a.min(b), a.max(b))
        }
    }

    /// `sin`.
    pub fn sin(self) -> Interval {
        // sin x = cos(x - pi/2): the extrema of sin at pi/2 + 2k pi.
        periodic(self, f64::sin, std::f64::consts::FRAC_PI_2)
    }

    /// `cos`.
    pub fn cos(self) -> Interval {
        periodic(self, f64::cos, 0.0)
    }

    /// Integer power (`n` in `-64..=64`), tight for even powers.
    pub fn powi(self, n: i32) -> Interval {
        if n == 0 {
            return Interval::point(1.0);
        }
        if n < 0 {
            return Interval::point(1.0) / self.powi(-n);
        }
        let n = n as u32;
        // Power of a non-negative interval, bound by bound, by squaring.
        let pow_nonneg = |lo: f64, hi: f64| -> Interval {
            let mut base = Interval::new(lo, hi);
            let mut acc = Interval::point(1.0);
            let mut e = n;
            while e > 0 {
                if e & 1 == 1 {
                    acc = acc * base;
                }
                base = base * base;
                e >>= 1;
            }
            // acc * acc of non-negative intervals keeps lo >= 0 up to rounding.
            Interval::new(acc.lo.max(0.0), acc.hi)
        };
        if self.lo >= 0.0 {
            return pow_nonneg(self.lo, self.hi);
        }
        if self.hi <= 0.0 {
            let p = pow_nonneg(-self.hi, -self.lo);
            return if n.is_multiple_of(2) { p } else { -p };
        }
        // Straddles 0.
        let m = pow_nonneg(0.0, (-self.lo).max(self.hi));
        if n.is_multiple_of(2) {
            Interval::new(0.0, m.hi)
        } else {
            let neg = pow_nonneg(0.0, -self.lo);
            let pos = pow_nonneg(0.0, self.hi);
            Interval::new(-neg.hi, pos.hi)
        }
    }
}

impl std::ops::Add for Interval {
    type Output = Interval;
    /// Sum, rounded outward.
    fn add(self, o: Interval) -> Interval {
        Interval::new(add_bounds(self.lo, o.lo).0, add_bounds(self.hi, o.hi).1)
    }
}

impl std::ops::Sub for Interval {
    type Output = Interval;
    /// Difference, rounded outward.
    fn sub(self, o: Interval) -> Interval {
        self + -o
    }
}

impl std::ops::Neg for Interval {
    type Output = Interval;
    /// Negation (exact).
    fn neg(self) -> Interval {
        Interval { lo: -self.hi, hi: -self.lo }
    }
}

impl std::ops::Mul for Interval {
    type Output = Interval;
    /// Product, rounded outward.
    fn mul(self, o: Interval) -> Interval {
        if self.is_zero() || o.is_zero() {
            return Interval::point(0.0);
        }
        if self.lo.is_infinite() || self.hi.is_infinite() || o.lo.is_infinite() || o.hi.is_infinite() {
            // 0 * inf is undefined: give up on exactness rather than reason about it.
            if self.contains_zero() || o.contains_zero() {
                return Interval::ENTIRE;
            }
        }
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for a in [self.lo, self.hi] {
            for b in [o.lo, o.hi] {
                let (l, h) = mul_bounds(a, b);
                lo = lo.min(l);
                hi = hi.max(h);
            }
        }
        Interval::new(lo, hi)
    }
}

impl std::ops::Div for Interval {
    type Output = Interval;
    /// Quotient, rounded outward (the whole line if `o` holds 0).
    fn div(self, o: Interval) -> Interval {
        if o.contains_zero() {
            return Interval::ENTIRE;
        }
        if self.is_zero() {
            return Interval::point(0.0);
        }
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for a in [self.lo, self.hi] {
            for b in [o.lo, o.hi] {
                if a.is_infinite() && b.is_infinite() {
                    return Interval::ENTIRE;
                }
                let (l, h) = div_bounds(a, b);
                lo = lo.min(l);
                hi = hi.max(h);
            }
        }
        Interval::new(lo, hi)
    }
}

/// Range of `f` (`sin` or `cos`) over `x`: the values at the ends, widened,
/// and `+1` / `-1` wherever the interval may hold a maximum `phase + 2k pi` or
/// a minimum `phase + pi + 2k pi`, with a margin for the rounding of the
/// arguments (including too many extrema only loosens the enclosure).
fn periodic(x: Interval, f: fn(f64) -> f64, phase: f64) -> Interval {
    let full = Interval::new(-1.0, 1.0);
    if !(x.lo.is_finite() && x.hi.is_finite()) || x.hi - x.lo >= 6.0 || x.lo.abs().max(x.hi.abs()) > 1e12 {
        return full;
    }
    let (a, b) = (f(x.lo), f(x.hi));
    let mut lo = down(a.min(b), LIBM_ULPS);
    let mut hi = up(a.max(b), LIBM_ULPS);
    let two_pi = 2.0 * std::f64::consts::PI;
    let margin = 1e-9 + 1e-15 * x.lo.abs().max(x.hi.abs());
    let holds = |centre: f64| -> bool {
        let k_lo = ((x.lo - centre) / two_pi - margin).ceil();
        let k_hi = ((x.hi - centre) / two_pi + margin).floor();
        k_lo <= k_hi
    };
    if holds(phase) {
        hi = 1.0;
    }
    if holds(phase + std::f64::consts::PI) {
        lo = -1.0;
    }
    Interval::new(lo.max(-1.0), hi.min(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn contains(i: Interval, x: f64) -> bool {
        i.lo <= x && x <= i.hi
    }

    #[test]
    fn exact_results_stay_exact() {
        let z = Interval::point(0.0);
        let three = Interval::point(3.0);
        assert_eq!(three * z, z);
        assert_eq!(z + z, z);
        assert_eq!(three - three, z);
        assert_eq!(Interval::point(0.5) + Interval::point(0.25), Interval::point(0.75));
        // 0.1 + 0.2 is not exact: the enclosure must be one ulp wide and hold 0.3's double and the true sum
        let s = Interval::point(0.1) + Interval::point(0.2);
        assert!(s.lo < s.hi && s.hi == s.lo.next_up(), "{s:?}");
    }

    #[test]
    fn division_and_sqrt_by_remainders() {
        let third = Interval::point(1.0) / Interval::point(3.0);
        assert!(third.lo < third.hi && third.hi == third.lo.next_up());
        assert_eq!(Interval::point(1.0) / Interval::point(4.0), Interval::point(0.25));
        assert_eq!(Interval::point(4.0).sqrt(), Interval::point(2.0));
        let r2 = Interval::point(2.0).sqrt();
        assert!(r2.lo < std::f64::consts::SQRT_2 + 1e-16 && r2.hi >= std::f64::consts::SQRT_2);
        assert_eq!(Interval::new(-1.0, 1.0) / Interval::new(-1.0, 1.0), Interval::ENTIRE);
        assert_eq!(Interval::new(-1.0, 1.0).sqrt(), Interval::ENTIRE);
    }

    #[test]
    fn trigonometric_extrema_are_included() {
        let s = Interval::new(1.0, 2.0).sin(); // holds pi/2: max 1
        assert_eq!(s.hi, 1.0);
        assert!(s.lo <= 1f64.sin() && s.lo > 0.8);
        let c = Interval::new(3.0, 3.3).cos(); // holds pi: min -1
        assert_eq!(c.lo, -1.0);
        let c2 = Interval::new(0.1, 0.2).cos(); // monotone: no extremum inside
        assert!(c2.hi < 1.0 && contains(c2, 0.15f64.cos()));
    }

    #[test]
    fn even_powers_of_straddling_intervals_are_non_negative() {
        let p = Interval::new(-1.0, 2.0).powi(2);
        assert_eq!(p, Interval::new(0.0, 4.0));
        let q = Interval::new(-1.0, 2.0).powi(3);
        assert!(contains(q, -1.0) && contains(q, 8.0) && q.lo >= -1.0 && q.hi <= 8.0);
        assert_eq!(Interval::new(-2.0, -1.0).powi(3), Interval::new(-8.0, -1.0));
    }

    #[test]
    fn overflow_gives_infinite_bounds_not_wrong_ones() {
        let big = Interval::point(1e300);
        let p = big * big;
        assert!(p.hi == f64::INFINITY && p.lo >= 1e300);
        assert!(Interval::point(1000.0).exp().hi.is_infinite());
    }

    /// Sampled points of `[lo, hi]`: the ends, 0 when inside, and 30
    /// points between.
    fn samples(lo: f64, hi: f64) -> Vec<f64> {
        let mut out = vec![lo, hi];
        if lo < 0.0 && hi > 0.0 {
            out.push(0.0);
        }
        out.extend((1..30).map(|i| lo + (hi - lo) * (i as f64 / 30.0)).filter(|x| *x > lo && *x < hi));
        out
    }

    /// The hyperbolic enclosures hold `f64`'s value at sampled points
    /// (its error is a few ulps, within the widening) on intervals near 0,
    /// straddling it, where `cosh` and `sinh` overflow (`|x| > 710.48`),
    /// at `±700`, `±1e308` and the infinite ends; `tanh` and `sech` stay
    /// within `[-1, 1]` and `[0, 1]`, `cosh` at or above 1.
    #[test]
    fn hyperbolic_enclosures_hold_sampled_values() {
        let tiny = f64::MIN_POSITIVE;
        let intervals = [
            (-1e-300, 1e-300),
            (0.0, 1e-300),
            (-tiny, 0.0),
            (-5e-324, 5e-324),
            (0.0, 0.0),
            (-0.3, 0.2),
            (0.1, 0.7),
            (-2.5, -1.0),
            (19.0, 21.0),
            (-21.0, 19.5),
            (700.0, 700.0),
            (-700.0, -700.0),
            (-700.0, 700.0),
            (699.0, 712.0),
            (-712.0, -705.0),
            (710.0, 711.0),
            (1e308, 1e308),
            (-1e308, -1e308),
            (-1e308, 1e308),
            (f64::MAX, f64::MAX),
            (1.0, f64::INFINITY),
            (f64::NEG_INFINITY, 3.0),
        ];
        for (lo, hi) in intervals {
            let x = Interval::new(lo, hi);
            let (sh, ch, th, se) = (x.sinh(), x.cosh(), x.tanh(), x.sech());
            for p in samples(lo, hi) {
                assert!(contains(sh, p.sinh()), "sinh {p} not in {sh:?} for [{lo}, {hi}]");
                assert!(contains(ch, p.cosh()), "cosh {p} not in {ch:?} for [{lo}, {hi}]");
                assert!(contains(th, p.tanh()), "tanh {p} not in {th:?} for [{lo}, {hi}]");
                // sech as 1/cosh (0 where cosh overflows) and as 2 e^-|p| (its
                // value there, a subnormal down to 745)
                assert!(contains(se, 1.0 / p.cosh()), "sech {p} not in {se:?} for [{lo}, {hi}]");
                if p.abs() > 20.0 {
                    assert!(contains(se, 2.0 * (-p.abs()).exp()), "sech {p} not in {se:?} for [{lo}, {hi}]");
                }
            }
            assert!(th.lo >= -1.0 && th.hi <= 1.0, "{th:?}");
            assert!(se.lo >= 0.0 && se.hi <= 1.0, "{se:?}");
            assert!(ch.lo >= 1.0, "{ch:?}");
        }
        // Overflow never tightens: cosh and sinh of 1e308 are infinite above,
        // huge below; sech of it is at most 1/f64::MAX (rounded up), at least 0.
        let big = Interval::point(1e308);
        assert_eq!(big.cosh().hi, f64::INFINITY);
        assert!(big.cosh().lo >= 1e307);
        assert_eq!(big.sinh().hi, f64::INFINITY);
        assert_eq!((-big).sinh().lo, f64::NEG_INFINITY);
        assert!(big.sech().lo == 0.0 && big.sech().hi > 0.0 && big.sech().hi < 1e-307, "{:?}", big.sech());
        // Saturation: tanh 20 rounds to 1, the enclosure reaches below the true 1 - 8.5e-18.
        let t = Interval::point(20.0).tanh();
        assert!(t.hi == 1.0 && t.lo < 1.0 - 8.5e-18 && t.lo > 1.0 - 1e-15, "{t:?}");
        // Extremum at 0: an interval straddling 0 has cosh down to exactly 1
        // and sech up to exactly 1, not the values at its ends.
        let s = Interval::new(-0.5, 2.0);
        assert_eq!(s.cosh().lo, 1.0);
        assert_eq!(s.sech().hi, 1.0);
        assert!(s.cosh().hi >= 2f64.cosh() && s.cosh().hi < 2f64.cosh() * (1.0 + 1e-15));
        assert!(s.sech().lo <= 1.0 / 2f64.cosh() && s.sech().lo > (1.0 / 2f64.cosh()) * (1.0 - 1e-15));
        // A positive interval: cosh from its near end, not 1.
        let p = Interval::new(1.0, 2.0).cosh();
        assert!(p.lo <= 1f64.cosh() && p.lo > 1.5);
        // Exact zeros stay exact (as for exp at 0).
        let z = Interval::point(0.0);
        assert_eq!((z.sinh(), z.cosh(), z.tanh(), z.sech()), (z, Interval::point(1.0), z, Interval::point(1.0)));
        // The whole line: the functions' ranges.
        let e = Interval::ENTIRE;
        assert_eq!((e.sinh(), e.cosh(), e.tanh()), (e, Interval::new(1.0, f64::INFINITY), Interval::new(-1.0, 1.0)));
        assert_eq!(e.sech(), Interval::new(0.0, 1.0));
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]
        /// Every operation's enclosure holds the double-precision result of
        /// the same operation on points inside the operands (a necessary
        /// condition of rigour that does not rely on the error analysis).
        #[test]
        fn enclosures_hold_sampled_values(a in -50.0f64..50.0, w in 0.0f64..3.0, t in 0.0f64..1.0, b in 0.5f64..20.0) {
            let x = Interval::new(a, a + w);
            let p = a + w * t;
            let y = Interval::point(b);
            prop_assert!(contains(x + y, p + b));
            prop_assert!(contains(x * y, p * b));
            prop_assert!(contains(x / y, p / b));
            prop_assert!(contains(x.sin(), p.sin()));
            prop_assert!(contains(x.cos(), p.cos()));
            prop_assert!(contains(x.powi(3), p.powi(3)));
            prop_assert!(contains(x.powi(2), p * p));
            if a > 0.0 {
                prop_assert!(contains(x.sqrt(), p.sqrt()));
            }
            if a + w < 40.0 {
                prop_assert!(contains(x.exp(), p.exp()));
            }
            prop_assert!(contains(x.sinh(), p.sinh()));
            prop_assert!(contains(x.cosh(), p.cosh()));
            prop_assert!(contains(x.tanh(), p.tanh()));
            prop_assert!(contains(x.sech(), 1.0 / p.cosh()));
        }
    }
}
