//! Boxes of parameters and Bernstein expansions on them, exactly.
//!
//! On a box `[lo, hi]` (one interval per parameter), a polynomial of degree
//! at most `d_i` in parameter `i` is `sum_alpha b_alpha B_alpha(t)`, with
//! `theta_i = lo_i + (hi_i - lo_i) t_i`, `t` in the unit cube and
//! `B_alpha(t) = prod_i C(d_i, alpha_i) t_i^alpha_i (1 - t_i)^(d_i - alpha_i)`.
//! The `B_alpha` are nonnegative on the cube and sum to 1, so the values
//! of the polynomial on the box lie in the convex hull of the coefficients
//! `b_alpha` (Bernstein's enclosure). The same holds for a matrix of
//! polynomials, entry by entry with common degrees: the matrix at every
//! point of the box is a convex combination of the coefficient matrices
//! `M_alpha`, so if every `M_alpha` is positive definite, so is the
//! matrix everywhere on the box (the positive definite cone is convex).
//! Subdividing a box makes the enclosure converge to the range (Garloff),
//! which is what [`crate::certify`]'s bisection relies on.
//!
//! Written here: no crate offers exact multivariate Bernstein expansions;
//! the algorithm is the textbook one (Garloff 1986; Ray and Nataraj 2009):
//! expand in `t`, then convert each dimension with
//! `b_j = sum_{k <= j} C(j, k) / C(d, k) a_k`.

use exact::{Matrix, Poly, Rational};
use num_traits::{One, Zero};
use outcome::Sign;

/// A box `prod_i [lo_i, hi_i]` of parameter values, `lo_i <= hi_i`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParamBox {
    /// Lower bounds.
    pub lo: Vec<Rational>,
    /// Upper bounds.
    pub hi: Vec<Rational>,
}

impl ParamBox {
    /// Number of parameters.
    pub fn dim(&self) -> usize {
        self.lo.len()
    }

    /// The centre.
    pub fn centre(&self) -> Vec<Rational> {
        let half = Rational::new(1.into(), 2.into());
        self.lo.iter().zip(&self.hi).map(|(a, b)| (a + b) * &half).collect()
    }

    /// The anchor: the point where the pipeline runs to choose a sub-box's
    /// functional. The centre, unless one of its coordinates is longer than
    /// 128 bits (numerator or denominator); then, per side, the simplest
    /// rational (smallest denominator, then smallest magnitude) of the
    /// side's middle half `[lo + w/4, hi - w/4]`: as good a place to choose
    /// from, with short numbers (the centres of `[1e-308, 7/2]` carry its
    /// 10^308 denominator and made the exact pipeline there hundreds of
    /// times slower; its anchors do not).
    ///
    /// ```
    /// use boxes::ParamBox;
    /// use exact::Rational;
    /// let r = |n: i64, d: i64| Rational::new(n.into(), d.into());
    /// let b = ParamBox { lo: vec![r(3, 2), r(-1, 3)], hi: vec![r(5, 2), r(1, 7)] };
    /// assert_eq!(b.anchor(), b.centre());
    /// let tiny = Rational::new(1.into(), exact::BigInt::from(10).pow(308));
    /// let b = ParamBox { lo: vec![tiny], hi: vec![r(7, 2)] };
    /// assert_eq!(b.anchor(), vec![r(1, 1)]);
    /// ```
    pub fn anchor(&self) -> Vec<Rational> {
        let centre = self.centre();
        if centre.iter().all(|c| c.numer().bits() <= 128 && c.denom().bits() <= 128) {
            return centre;
        }
        let quarter = Rational::new(1.into(), 4.into());
        self.lo
            .iter()
            .zip(&self.hi)
            .map(|(a, b)| {
                let w = (b - a) * &quarter;
                simplest_between(&(a + &w), &(b - &w))
            })
            .collect()
    }

    /// The `2^p` corners.
    pub fn corners(&self) -> Vec<Vec<Rational>> {
        let p = self.dim();
        (0..1usize << p)
            .map(|mask| {
                (0..p).map(|i| if mask >> i & 1 == 1 { self.hi[i].clone() } else { self.lo[i].clone() }).collect()
            })
            .collect()
    }

    /// The two halves along dimension `i`.
    pub fn split(&self, i: usize) -> (ParamBox, ParamBox) {
        let mid = self.centre()[i].clone();
        let mut a = self.clone();
        let mut b = self.clone();
        a.hi[i] = mid.clone();
        b.lo[i] = mid;
        (a, b)
    }

    /// `prod (hi_i - lo_i)`.
    pub fn volume(&self) -> Rational {
        self.lo.iter().zip(&self.hi).fold(Rational::one(), |acc, (a, b)| acc * (b - a))
    }

    /// Whether `other` lies inside this box.
    pub fn contains_box(&self, other: &ParamBox) -> bool {
        (0..self.dim()).all(|i| self.lo[i] <= other.lo[i] && other.hi[i] <= self.hi[i])
    }

    /// Whether the interiors of the two boxes meet.
    pub fn interiors_meet(&self, other: &ParamBox) -> bool {
        (0..self.dim()).all(|i| (&self.lo[i]).max(&other.lo[i]) < (&self.hi[i]).min(&other.hi[i]))
    }

    /// Whether the point lies in the (closed) box.
    pub fn contains(&self, x: &[Rational]) -> bool {
        (0..self.dim()).all(|i| self.lo[i] <= x[i] && x[i] <= self.hi[i])
    }
}

/// The simplest rational in `[a, b]` (`a <= b`): the smallest
/// denominator, then the smallest magnitude (by continued fractions).
pub fn simplest_between(a: &Rational, b: &Rational) -> Rational {
    let zero = Rational::zero();
    if a <= &zero && &zero <= b {
        return zero;
    }
    if b < &zero {
        return -simplest_between(&-b.clone(), &-a.clone());
    }
    // 0 < a <= b: the floor of a is its integer part
    let fa = Rational::from_integer(a.to_integer());
    if &fa == a {
        return fa;
    }
    let next = &fa + Rational::one();
    if &next <= b {
        return next;
    }
    // a, b in (fa, fa + 1): fa + 1/x with x the simplest in [1/(b - fa), 1/(a - fa)]
    let x = simplest_between(&(b - &fa).recip(), &(a - &fa).recip());
    fa + x.recip()
}

/// The degree of `p` in each parameter (variables `offset..offset + p`).
pub fn degrees(p: &Poly, offset: usize, np: usize) -> Vec<u32> {
    let mut d = vec![0u32; np];
    for (m, _) in p.terms() {
        for i in 0..np {
            d[i] = d[i].max(m[offset + i] as u32);
        }
    }
    d
}

fn binomials(n: u32) -> Vec<Rational> {
    let mut row = vec![Rational::one()];
    for k in 1..=n {
        let prev = row[k as usize - 1].clone();
        row.push(prev * Rational::from((n - k + 1) as i64) / Rational::from(k as i64));
    }
    row
}

/// The Bernstein coefficients of `p` (a polynomial in the parameters
/// only, variables `offset..offset + b.dim()`) on the box `b` with degrees
/// `deg` (at least `p`'s), as a dense array, the last parameter fastest.
///
/// ```
/// use boxes::bernstein::{bernstein_coefficients, ParamBox};
/// use exact::{Poly, Rational};
/// // t^2 on [0, 1] with degree 2: coefficients 0, 0, 1
/// let t = Poly::var(1, 0);
/// let b = ParamBox { lo: vec![Rational::from(0)], hi: vec![Rational::from(1)] };
/// let c = bernstein_coefficients(&t.mul(&t), 0, &b, &[2]);
/// assert_eq!(c, vec![Rational::from(0), Rational::from(0), Rational::from(1)]);
/// ```
pub fn bernstein_coefficients(p: &Poly, offset: usize, b: &ParamBox, deg: &[u32]) -> Vec<Rational> {
    let np = b.dim();
    let size: usize = deg.iter().map(|d| *d as usize + 1).product();
    let mut stride = vec![1usize; np];
    for i in (0..np.saturating_sub(1)).rev() {
        stride[i] = stride[i + 1] * (deg[i + 1] as usize + 1);
    }
    let width: Vec<Rational> = (0..np).map(|i| &b.hi[i] - &b.lo[i]).collect();
    // Power coefficients in t: theta_i^a = sum_k C(a, k) lo^(a-k) w^k t^k.
    let mut a = vec![Rational::zero(); size];
    for (m, c) in p.terms() {
        let expansions: Vec<Vec<Rational>> = (0..np)
            .map(|i| {
                let e = m[offset + i] as u32;
                assert!(e <= deg[i], "degree above the expansion's");
                let bin = binomials(e);
                (0..=e).map(|k| &bin[k as usize] * b.lo[i].pow(e - k) * width[i].pow(k)).collect()
            })
            .collect();
        // every combination of k, the last parameter fastest
        let total: usize = expansions.iter().map(Vec::len).product();
        for flat in 0..total {
            let mut rest = flat;
            let mut v = c.clone();
            let mut at = 0;
            for i in (0..np).rev() {
                let len = expansions[i].len();
                let k = rest % len;
                rest /= len;
                v *= &expansions[i][k];
                at += k * stride[i];
            }
            a[at] += v;
        }
    }
    // Convert each dimension: b_j = sum_{k <= j} C(j, k) / C(d, k) a_k.
    for i in 0..np {
        let d = deg[i] as usize;
        let bin_d = binomials(d as u32);
        let bins: Vec<Vec<Rational>> = (0..=d as u32).map(binomials).collect();
        let s = stride[i];
        for start in 0..size {
            // the first index of each fiber along i: digit i is zero
            if (start / s) % (d + 1) != 0 {
                continue;
            }
            let fiber: Vec<Rational> = (0..=d).map(|k| a[start + k * s].clone()).collect();
            for j in 0..=d {
                let mut v = Rational::zero();
                for k in 0..=j {
                    if !fiber[k].is_zero() {
                        v += &fiber[k] * &bins[j][k] / &bin_d[k];
                    }
                }
                a[start + j * s] = v;
            }
        }
    }
    a
}

/// Largest number of Bernstein coefficients expanded for one polynomial:
/// beyond it nothing is proved (a bound on the work, not a claim).
pub const MAX_COEFFICIENTS: usize = 1 << 20;

/// `prod (d_i + 1)`, if at most [`MAX_COEFFICIENTS`].
fn coefficient_count(deg: &[u32]) -> Option<usize> {
    deg.iter().try_fold(1usize, |acc, d| acc.checked_mul(*d as usize + 1)).filter(|n| *n <= MAX_COEFFICIENTS)
}

/// The strict sign of `p` on the whole box, if its Bernstein coefficients
/// prove one (all positive or all negative).
///
/// ```
/// use boxes::bernstein::{sign_on_box, ParamBox};
/// use exact::{Poly, Rational};
/// use outcome::Sign;
/// let t = Poly::var(1, 0);
/// let b = |lo: i64, hi: i64| ParamBox { lo: vec![Rational::from(lo)], hi: vec![Rational::from(hi)] };
/// assert_eq!(sign_on_box(&t, 0, &b(1, 2)), Some(Sign::Positive));
/// assert_eq!(sign_on_box(&t, 0, &b(-1, 2)), None);
/// ```
pub fn sign_on_box(p: &Poly, offset: usize, b: &ParamBox) -> Option<Sign> {
    let deg = degrees(p, offset, b.dim());
    coefficient_count(&deg)?;
    let c = bernstein_coefficients(p, offset, b, &deg);
    if c.iter().all(|x| x > &Rational::zero()) {
        Some(Sign::Positive)
    } else if c.iter().all(|x| x < &Rational::zero()) {
        Some(Sign::Negative)
    } else {
        None
    }
}

/// Whether the symmetric matrix of polynomials `m` (in the parameters
/// only) is positive definite at every point of the box, proved by its
/// Bernstein coefficient matrices (module docs). `false` means not proved.
pub fn matrix_positive_on_box(m: &[Vec<Poly>], offset: usize, b: &ParamBox) -> bool {
    let n = m.len();
    let np = b.dim();
    let mut deg = vec![0u32; np];
    for row in m {
        for e in row {
            for (d, x) in deg.iter_mut().zip(degrees(e, offset, np)) {
                *d = (*d).max(x);
            }
        }
    }
    if coefficient_count(&deg).is_none() {
        return false;
    }
    let coefficients: Vec<Vec<Vec<Rational>>> =
        m.iter().map(|row| row.iter().map(|e| bernstein_coefficients(e, offset, b, &deg)).collect()).collect();
    let size: usize = deg.iter().map(|d| *d as usize + 1).product();
    (0..size).all(|alpha| {
        let ma = Matrix::from_fn(n, n, |i, j| coefficients[i][j][alpha].clone());
        ma.is_symmetric() && ma.is_definite_with_sign(Sign::Positive)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn r(n: i64, d: i64) -> Rational {
        Rational::new(n.into(), d.into())
    }

    /// The Bernstein form is the polynomial: `sum b_alpha B_alpha(t)` at
    /// sample points equals `p(theta)`, computed independently term by term.
    #[test]
    fn the_expansion_reproduces_the_polynomial() {
        // p(s, t) = 3 s^2 t - 2 s t^2 + 5 t - 7 in variables (x, s, t), offset 1
        let nv = 3;
        let s = Poly::var(nv, 1);
        let t = Poly::var(nv, 2);
        let c = |v: i64| Poly::constant(nv, Rational::from(v));
        let p = c(3).mul(&s).mul(&s).mul(&t).sub(&c(2).mul(&s).mul(&t).mul(&t)).add(&c(5).mul(&t)).sub(&c(7));
        let b = ParamBox { lo: vec![r(-1, 2), r(1, 3)], hi: vec![r(2, 1), r(5, 4)] };
        let deg = [3u32, 2u32]; // above p's degrees (2, 2)
        let coef = bernstein_coefficients(&p, 1, &b, &deg);
        for (u, v) in [(r(0, 1), r(0, 1)), (r(1, 3), r(3, 4)), (r(1, 1), r(1, 2)), (r(2, 7), r(1, 1))] {
            let bern = |d: u32, k: u32, x: &Rational| {
                let bin = binomials(d);
                &bin[k as usize] * x.pow(k) * (Rational::one() - x).pow(d - k)
            };
            let mut sum = Rational::zero();
            for i in 0..=deg[0] {
                for j in 0..=deg[1] {
                    sum += &coef[(i * (deg[1] + 1) + j) as usize] * bern(deg[0], i, &u) * bern(deg[1], j, &v);
                }
            }
            let theta = [r(0, 1), &b.lo[0] + &u * (&b.hi[0] - &b.lo[0]), &b.lo[1] + &v * (&b.hi[1] - &b.lo[1])];
            assert_eq!(sum, p.eval(&theta));
        }
    }

    /// A matrix definite on the box is proved after subdivision, and one
    /// that is singular at a point of the box never is.
    #[test]
    fn matrices_are_proved_definite_only_where_they_are() {
        // [[t, 1], [1, t]] in one variable: definite iff t > 1
        let t = Poly::var(1, 0);
        let one = Poly::constant(1, Rational::one());
        let m = vec![vec![t.clone(), one.clone()], vec![one, t]];
        let b = |lo: Rational, hi: Rational| ParamBox { lo: vec![lo], hi: vec![hi] };
        assert!(matrix_positive_on_box(&m, 0, &b(r(11, 10), r(3, 1))));
        assert!(!matrix_positive_on_box(&m, 0, &b(r(1, 1), r(3, 1))));
        assert!(!matrix_positive_on_box(&m, 0, &b(r(1, 2), r(3, 1))));
    }
}
