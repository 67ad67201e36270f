//! Verified positive definiteness of symmetric matrices of doubles: the
//! tests every `verified_float` claim rests on, behind one entry point,
//! [`positive_definite`], which picks the test by the matrix's storage and
//! says which it ran.
//!
//! What a `true` proves, for either test: every symmetric `A + E` with
//! `||E||_2 <= radius` is positive definite, where `A` is the matrix *as
//! stored* (the doubles given), under IEEE double arithmetic with rounding
//! to nearest (unit roundoff `u = 2^-53`), underflow included. Callers that
//! formed `A` in floating point from the matrix a claim is about pass the
//! rounding of that formation as `radius`. A `false` means "not proved",
//! never "indefinite".
//!
//! * [`Method::DenseCholesky`] (a `nalgebra::DMatrix`): the dense test
//!   below.
//! * [`Method::BandedCholesky`] (a [`SymBanded`]): the banded test of
//!   [`SymBanded::verified_positive_definite_within`], the same argument
//!   with `gamma_{b+2}` for bandwidth `b` in place of `gamma_{n+1}`.
//!
//! ```
//! use nalgebra::DMatrix;
//! use numerics::banded::SymBanded;
//! use numerics::definite::{positive_definite, Method, Symmetric};
//! // tridiag(-1, 2, -1) of order 3: eigenvalues 2 - sqrt 2, 2, 2 + sqrt 2.
//! let dense = DMatrix::from_row_slice(3, 3, &[2.0, -1.0, 0.0, -1.0, 2.0, -1.0, 0.0, -1.0, 2.0]);
//! let mut banded = SymBanded::zeros(3, 1);
//! for i in 0..3 { banded.add(i, i, 2.0); }
//! for i in 1..3 { banded.add(i, i - 1, -1.0); }
//! let d = positive_definite(Symmetric::Dense(&dense), 0.5);
//! let b = positive_definite(Symmetric::Banded(&banded), 0.5);
//! assert!(d.proved && b.proved);
//! assert_eq!((d.method, b.method), (Method::DenseCholesky, Method::BandedCholesky));
//! // 0.6 exceeds lambda_min = 0.586: neither test proves it.
//! assert!(!positive_definite(Symmetric::Dense(&dense), 0.6).proved);
//! assert!(!positive_definite(Symmetric::Banded(&banded), 0.6).proved);
//! ```
//!
//! # The dense test
//!
//! Criterion, in the spirit of Rump, *Verification of positive definiteness*
//! (BIT 46, 2006), derived here from the standard backward error of the
//! Cholesky factorisation (Higham, *Accuracy and Stability of Numerical
//! Algorithms*, Thm 10.3): if floating-point Cholesky of `A~ = fl(A - cI)`
//! (rounding to nearest, unit roundoff `u = 2^-53`) runs to completion, the
//! computed factor satisfies `R^T R = A~ + dA` with
//! `|dA| <= g |R^T||R|`, `g = gamma_{n+1} = (n+1)u / (1 - (n+1)u)`. Since
//! `R^T R ⪰ 0` and `|| |R^T||R| ||_2 <= sum_i |r_i|^2 <= sum_i a~_ii / (1 - g)`,
//!
//! ```text
//! A = A~ - D + cI ⪰ (c - g/(1-g) sum_i a~_ii - max_i |D_ii|) I,   |D_ii| <= u |a_ii - c|,
//! ```
//!
//! where `D` is the rounding of the shifted diagonal. So `A ≻ 0` whenever
//! `c > g/(1-g) (1+u) sum_i a_ii + u (max_i a_ii + c)`. The shift used below
//! exceeds that bound by a factor absorbing the rounding in computing `c`
//! itself, plus `4 (n+1)^3` times the smallest normal number to cover
//! underflow (Higham's bound assumes none; each entry of `R^T R` is a sum of
//! at most `n` products, each off by at most that much). The test is
//! sufficient, never necessary: `false` means "not verified", not
//! "indefinite".

use crate::banded::SymBanded;
use nalgebra::DMatrix;

/// A symmetric matrix in one of the storages the tests read.
#[derive(Clone, Copy, Debug)]
pub enum Symmetric<'a> {
    /// Dense; both triangles are read and must agree.
    Dense(&'a DMatrix<f64>),
    /// Banded (the lower band).
    Banded(&'a SymBanded),
}

/// The test that ran.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Cholesky of the whole matrix with an a-priori shift (module docs).
    DenseCholesky,
    /// Banded Cholesky with the shift from the band's rounding bound.
    BandedCholesky,
}

impl Method {
    /// A short name for reports: `dense Cholesky` or `banded Cholesky`.
    pub fn name(&self) -> &'static str {
        match self {
            Method::DenseCholesky => "dense Cholesky",
            Method::BandedCholesky => "banded Cholesky",
        }
    }
}

/// The outcome of [`positive_definite`]: whether it proved the claim, and
/// by which test.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Definiteness {
    /// Every symmetric `A + E` with `||E||_2 <= radius` is positive
    /// definite (module docs); `false`: not proved.
    pub proved: bool,
    /// The test that ran.
    pub method: Method,
}

/// Whether every symmetric `a + E` with `||E||_2 <= radius` is proved
/// positive definite, by the test for `a`'s storage (module docs).
pub fn positive_definite(a: Symmetric<'_>, radius: f64) -> Definiteness {
    match a {
        Symmetric::Dense(m) => {
            Definiteness { proved: verified_positive_definite_within(m, radius), method: Method::DenseCholesky }
        }
        Symmetric::Banded(m) => {
            Definiteness { proved: m.verified_positive_definite_within(radius), method: Method::BandedCholesky }
        }
    }
}

/// The inner product of two equally long slices in sixteen interleaved
/// partial sums (any order of summation satisfies the bound the test relies
/// on; independent sums let the compiler keep several vector additions in
/// flight).
#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f64; 16];
    let (ca, cb) = (a.chunks_exact(16), b.chunks_exact(16));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for q in 0..16 {
            acc[q] += x[q] * y[q];
        }
    }
    let mut s = acc.iter().sum::<f64>();
    for (x, y) in ra.iter().zip(rb) {
        s += x * y;
    }
    s
}

/// Whether `a` (symmetric) is proved positive definite by a floating-point
/// Cholesky of `a - cI` with the a-priori shift `c` of the module docs.
///
/// ```
/// use nalgebra::DMatrix;
/// use numerics::definite::verified_positive_definite;
/// let a = DMatrix::from_row_slice(2, 2, &[2.0, 1.0, 1.0, 2.0]);
/// assert!(verified_positive_definite(&a));
/// let b = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0 - 1e-20]);
/// assert!(!verified_positive_definite(&b)); // singular to working precision
/// ```
pub fn verified_positive_definite(a: &DMatrix<f64>) -> bool {
    verified_positive_definite_within(a, 0.0)
}

/// Whether every symmetric `a + E` with `||E||_2 <= radius` is proved
/// positive definite: the test of [`verified_positive_definite`] with the
/// shift raised by `radius` (`lambda_min(a + E) >= lambda_min(a) - radius`,
/// Weyl). Use it when `a` was formed in floating point from the matrix the
/// claim is about, with `radius` bounding the rounding of that formation.
///
/// ```
/// use nalgebra::DMatrix;
/// use numerics::definite::verified_positive_definite_within;
/// let a = DMatrix::from_row_slice(2, 2, &[2.0, 1.0, 1.0, 2.0]); // eigenvalues 1 and 3
/// assert!(verified_positive_definite_within(&a, 0.5));
/// assert!(!verified_positive_definite_within(&a, 1.5));
/// ```
pub fn verified_positive_definite_within(a: &DMatrix<f64>, radius: f64) -> bool {
    if !(radius.is_finite() && radius >= 0.0) {
        return false;
    }
    let n = a.nrows();
    if n == 0 || a.ncols() != n || a.iter().any(|x| !x.is_finite()) {
        return false;
    }
    for i in 0..n {
        for j in 0..i {
            if a[(i, j)] != a[(j, i)] {
                return false;
            }
        }
        if a[(i, i)] <= 0.0 {
            return false;
        }
    }
    let u = f64::EPSILON / 2.0;
    let nn = (n + 1) as f64;
    if nn * u >= 0.01 {
        return false; // the error bounds below assume (n+1)u is small
    }
    let g = nn * u / (1.0 - nn * u);
    // (the sum of n terms, inflated for its own rounding, gamma_n < 2 n u)
    let trace: f64 = (0..n).map(|i| a[(i, i)]).sum::<f64>() * (1.0 + 2.0 * nn * u);
    let max_diag = (0..n).map(|i| a[(i, i)]).fold(0.0, f64::max);
    // c0 >= g/(1-g) (1+u) trace + u max_diag, then c = c0 / (1 - u) so that
    // c >= c0 + u c; inflate by (1 + 16 u) per rounded operation above.
    let c0 = (g / (1.0 - g)) * (1.0 + u) * trace + u * max_diag;
    let underflow = 4.0 * nn.powi(3) * f64::MIN_POSITIVE;
    let c = (c0 / (1.0 - u) + underflow + radius) * (1.0 + 16.0 * u);
    if !c.is_finite() {
        return false;
    }
    // Plain Cholesky (inner-product form), the algorithm the bound is about,
    // on R^T stored by columns: r[j * n + k] = R[k][j], so the inner
    // products read two contiguous columns. Higham's bound holds for any
    // order of summation in each inner product, so `dot` may sum in sixteen
    // interleaved parts (which lets the compiler vectorise it; the large
    // pipeline runs this test at dimension 2016).
    let mut r = vec![0.0f64; n * n];
    for j in 0..n {
        let s = a[(j, j)] - c - dot(&r[j * n..j * n + j], &r[j * n..j * n + j]);
        if s.is_nan() || s <= 0.0 || !s.is_finite() {
            return false;
        }
        let d = s.sqrt();
        r[j * n + j] = d;
        for i in (j + 1)..n {
            let t = a[(j, i)] - dot(&r[j * n..j * n + j], &r[i * n..i * n + j]);
            let v = t / d;
            if !v.is_finite() {
                return false;
            }
            r[i * n + j] = v;
        }
    }
    true
}
