//! Symmetric banded matrices: product, Cholesky factorisation and solves.
//!
//! Written here rather than taken from a crate: nalgebra and faer offer dense
//! and general sparse Cholesky, but the y-operators of a spectral-element
//! discretisation are banded with a bandwidth of the element degree, and the
//! plain banded algorithm (O(n b^2) to factor, O(n b) to solve, no fill-in,
//! no symbolic phase) is twenty lines. The dense cross-checks in the tests
//! compare against nalgebra.

/// The inner product of two equally long slices, four partial sums (so the
/// compiler vectorises it). The rounding bounds used here (`gamma_k` times
/// the sum of the terms' magnitudes) hold for any order of summation.
#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for q in 0..4 {
            acc[q] += x[q] * y[q];
        }
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for (x, y) in ra.iter().zip(rb) {
        s += x * y;
    }
    s
}

/// An upper bound on `x + units 2^-1074` (an underflow term), for `x >= 0`
/// and `0 <= units <= 2^100`, computed without arithmetic on subnormal
/// numbers when `x >= 2^-900`: then `fl(x (1 + 4u)) >= x (1 + 4u)(1 - u)
/// >= x (1 + 2u) > x + 2^-60 x >= x + units 2^-1074` (`1 + 4u` is exact).
/// Below that it is `fl(fl(x + units 2^-1074) (1 + 4u))`: `units 2^-1074`
/// is exact, the sum is exact while it is subnormal (and then the product
/// rounds back to it at worst), and otherwise each rounding loses at most
/// a relative `u`, which `1 + 4u` more than restores. (The plain sum is not
/// enough: for `x` above `2^-1021` it can round back down to `x`.) Each
/// subnormal result costs a microcode assist of about a hundred cycles:
/// adding the underflow terms entry by entry in subnormal arithmetic takes
/// 64% of `Bounded::set_with_error`, about 5% of a walls check at
/// ny = 1024 (`perf annotate`).
///
/// The small case is a call the compiler cannot inline: as a plain `if`,
/// LLVM computed both branches and selected one, so the subnormal product
/// was formed every time.
#[inline]
pub fn plus_underflow(x: f64, units: f64) -> f64 {
    // (a NaN `x` passes and propagates: the callers' finiteness tests
    // refuse it; never a panic)
    debug_assert!((x.is_nan() || x >= 0.0) && (0.0..=pow2(100)).contains(&units));
    #[cold]
    #[inline(never)]
    fn small(x: f64, units: f64) -> f64 {
        (x + units * 5e-324) * (1.0 + 2.0 * f64::EPSILON)
    }
    if x >= pow2(-900) {
        x * (1.0 + 2.0 * f64::EPSILON)
    } else {
        small(x, units)
    }
}

/// Higham's `gamma_m = m u / (1 - m u)`, `u = 2^-53`: the relative error
/// bound of `m` successive roundings.
pub fn gamma(m: usize) -> f64 {
    let u = f64::EPSILON / 2.0;
    let m = m as f64;
    m * u / (1.0 - m * u)
}

/// The product of `factors` from left to right, for an entry of a
/// [`Bounded`] matrix: `None` if a partial product before the last one
/// underflows (nonzero and below the normal range, or zero while no factor
/// is). [`Bounded::set`] allows for underflow in an entry's last operation
/// only: an earlier subnormal partial product can carry a relative error up
/// to 100%, which the later factors would carry into a normal-sized entry.
///
/// ```
/// use numerics::banded::product_without_early_underflow as product;
/// assert_eq!(product(&[3.0, 0.5, 2.0]), Some(3.0));
/// // 2^-600 * 2^-600 is below the normal range before the last factor
/// let tiny = 2f64.powi(-600);
/// assert_eq!(product(&[tiny, tiny, 2f64.powi(1000)]), None);
/// // the last operation may underflow: Bounded::set allows for it
/// assert_eq!(product(&[tiny, tiny]), Some(tiny * tiny));
/// // a zero factor makes the product exactly zero
/// assert_eq!(product(&[tiny, 0.0, tiny]), Some(0.0));
/// ```
pub fn product_without_early_underflow(factors: &[f64]) -> Option<f64> {
    let (&last, first) = factors.split_last()?;
    let mut p = 1.0;
    for (i, &f) in first.iter().enumerate() {
        p *= f;
        let exact_zero = first[..=i].contains(&0.0);
        if i > 0 && ((p != 0.0 && p.abs() < f64::MIN_POSITIVE) || (p == 0.0 && !exact_zero)) {
            return None;
        }
    }
    Some(p * last)
}

pub use crate::scaling::pow2;

/// Band buffers kept for reuse within a thread.
///
/// Why. The verified checks allocate several bands of `(J + 3) n` rows a
/// check (the lifted matrix and its bounds, the scaled copy, the factors,
/// `L |D| L^T`, the shifted Cholesky), megabytes each, and the ladder and
/// the modes repeat them. glibc returns such blocks to the kernel when they
/// are freed (`munmap`, or `madvise` in a worker thread's arena), so every
/// new one would page-fault in again: measured at ny = 1024 (mode 1 of
/// `bench/cubic-walls.json`, `fluid_mode`), 29% of a banded check
/// (11.2 ms, against 8.0 ms with glibc told to keep its memory through
/// `MALLOC_MMAP_THRESHOLD_` and `MALLOC_TRIM_THRESHOLD_`). A few freed
/// bands per thread are kept here instead; small ones are left to the
/// allocator. What is kept is at most [`pool::KEEP`] bands a thread, so
/// memory stays linear in the size of the matrices.
mod pool {
    use std::cell::RefCell;

    /// Bands of fewer doubles (256 KB) are left to the allocator.
    const MIN_LEN: usize = 1 << 15;
    /// At most this many free bands are kept a thread.
    pub(super) const KEEP: usize = 6;

    thread_local! {
        static FREE: RefCell<Vec<Vec<f64>>> = const { RefCell::new(Vec::new()) };
    }

    /// A kept buffer of capacity at least `len` if there is one (else the
    /// largest kept, or none), emptied.
    fn take(len: usize) -> Option<Vec<f64>> {
        if len < MIN_LEN {
            return None;
        }
        FREE.try_with(|f| {
            let mut f = f.try_borrow_mut().ok()?;
            let at = f
                .iter()
                .enumerate()
                .filter(|(_, v)| v.capacity() >= len)
                .min_by_key(|(_, v)| v.capacity())
                .or_else(|| f.iter().enumerate().max_by_key(|(_, v)| v.capacity()))
                .map(|(i, _)| i)?;
            let mut v = f.swap_remove(at);
            v.clear();
            Some(v)
        })
        .ok()
        .flatten()
    }

    /// `len` zeros.
    pub(super) fn zeroed(len: usize) -> Vec<f64> {
        match take(len) {
            Some(mut v) => {
                v.resize(len, 0.0);
                v
            }
            None => vec![0.0; len],
        }
    }

    /// A copy of `src`, given back when dropped.
    pub(super) fn copy_of(src: &[f64]) -> Buffer {
        Buffer(match take(src.len()) {
            Some(mut v) => {
                v.extend_from_slice(src);
                v
            }
            None => src.to_vec(),
        })
    }

    /// A buffer that is given back to the pool when dropped.
    pub(super) struct Buffer(Vec<f64>);

    impl std::ops::Deref for Buffer {
        type Target = [f64];
        fn deref(&self) -> &[f64] {
            &self.0
        }
    }

    impl std::ops::DerefMut for Buffer {
        fn deref_mut(&mut self) -> &mut [f64] {
            &mut self.0
        }
    }

    impl Drop for Buffer {
        fn drop(&mut self) {
            give(std::mem::take(&mut self.0));
        }
    }

    /// Keep `v` for reuse (if large, and fewer than [`KEEP`] are kept).
    pub(super) fn give(v: Vec<f64>) {
        if v.capacity() < MIN_LEN {
            return;
        }
        let _ = FREE.try_with(|f| {
            if let Ok(mut f) = f.try_borrow_mut() {
                if f.len() < KEEP {
                    f.push(v);
                }
            }
        });
    }
}

/// A symmetric `n x n` matrix with `a[i][j] = 0` for `|i - j| > bandwidth`,
/// stored by its lower band: `band[i * (b + 1) + d] = a[i][i - d]`.
#[derive(Clone, Debug, PartialEq)]
pub struct SymBanded {
    n: usize,
    b: usize,
    band: Vec<f64>,
}

impl Drop for SymBanded {
    fn drop(&mut self) {
        pool::give(std::mem::take(&mut self.band));
    }
}

/// A banded matrix and an entrywise bound on its rounding, built entry by
/// entry, for the verified inertia tests: `err` bounds `|A_exact - a|`
/// entrywise, where `A_exact` is the matrix of the exact operations on the
/// stored inputs.
///
/// ```
/// use numerics::banded::Bounded;
/// // [[1/3, 1], [1, -2/3]] (1/3 and 2/3 rounded once each): inertia (1, 1)
/// let mut a = Bounded::new(2, 1);
/// a.set(0, 0, 1.0 / 3.0, 1);
/// a.set(1, 0, 1.0, 0);
/// a.set(1, 1, -2.0 / 3.0, 1);
/// assert_eq!(a.inertia(), Some((1, 1)));
/// assert_eq!(a.plain_inertia(), Some((1, 1)));
/// ```
#[derive(Clone, Debug)]
pub struct Bounded {
    /// The matrix as computed.
    a: SymBanded,
    /// The entrywise bound on its rounding (`None`: not tracked).
    err: Option<SymBanded>,
}

impl Bounded {
    /// The zero matrix of size `n` and bandwidth `b`, exact.
    pub fn new(n: usize, b: usize) -> Self {
        Bounded { a: SymBanded::zeros(n, b), err: Some(SymBanded::zeros(n, b)) }
    }

    /// The same without the rounding bounds, for [`Bounded::plain_inertia`]
    /// only ([`Bounded::inertia`] proves nothing and says `None`): a search
    /// that tests many matrices then skips their bookkeeping.
    pub fn untracked(n: usize, b: usize) -> Self {
        Bounded { a: SymBanded::zeros(n, b), err: None }
    }

    /// The matrix as computed.
    pub fn matrix(&self) -> &SymBanded {
        &self.a
    }

    /// Entry `(i, j)` is `v`, computed with at most `rounds` roundings of
    /// nonnegative-magnitude factors (a product of such factors is within
    /// `gamma_rounds |v|` of the exact one), plus underflow in the last
    /// operation only: form a product of several factors with
    /// [`product_without_early_underflow`].
    pub fn set(&mut self, i: usize, j: usize, v: f64, rounds: usize) {
        self.set_with_error(i, j, v, v, rounds);
    }

    /// Entry `(i, j)` is `v`, within `gamma_rounds |scale|` of the exact
    /// value (plus underflow): for a difference that cancels, whose error is
    /// relative to the sum of its terms' magnitudes, not to `v`.
    pub fn set_with_error(&mut self, i: usize, j: usize, v: f64, scale: f64, rounds: usize) {
        if v != 0.0 {
            self.a.add(i, j, v);
        }
        if let (Some(err), true) = (self.err.as_mut(), rounds > 0) {
            let g = gamma(rounds);
            err.add(i, j, plus_underflow(g * scale.abs().max(v.abs()) * (1.0 + 2.0 * g), rounds as f64));
        }
    }

    /// The inertia proved for every matrix within the entrywise bound
    /// ([`SymBanded::power_of_two_scaled_rows`], then
    /// [`SymBanded::verified_inertia_within_rows`]: the bound's row sums,
    /// row by row).
    pub fn inertia(&self) -> Option<(usize, usize)> {
        let (s, r) = self.a.power_of_two_scaled_rows(self.err.as_ref()?);
        s.verified_inertia_within_rows(&r)
    }

    /// The inertia of the computed matrix, unproved ([`SymBanded::inertia`]):
    /// for searches. (No equilibration: scaling by powers of two moves
    /// `L D L^T`'s pivots by exact factors, so the signs are the same.)
    pub fn plain_inertia(&self) -> Option<(usize, usize)> {
        self.a.inertia()
    }
}

/// Why a banded Cholesky failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BandedError {
    /// A pivot was not positive: the matrix is not (numerically) positive definite.
    #[error("not positive definite: pivot {index} is {value:e}")]
    NonPositivePivot {
        /// Row of the failing pivot.
        index: usize,
        /// Its value.
        value: f64,
    },
}

/// Multipliers below this magnitude, `2^-500`, are flushed to zero by
/// `eliminate`: products of two unflushed multipliers and a pivot of order
/// one stay in the normal range, and the flushed entries' backward error,
/// at most `2^-500` times a pivot, is far below the rounding bounds of an
/// equilibrated matrix (and counted in them).
pub const FLUSH: f64 = f64::from_bits(((1023 - 500) as u64) << 52);

/// One right-looking step at pivot `k` of a factorisation held in a lower
/// band `c` (`c[i * (b + 1) + d]` is entry `(i, i - d)`; `n` rows): the
/// pivot's column below the diagonal is divided by `pivot`, then row `k + m`
/// (columns `k + 1 ..= k + m`) loses `l_{k+m,k} fl(l_{j,k} times)`, one
/// `axpy` per row that the compiler vectorises. `times` is `d_k` for
/// `L D L^T` and 1 (exact) for Cholesky. Every entry is its matrix entry
/// minus its products in turn, one order of the inner products whose
/// rounding Higham's Lemma 8.4 bounds for any order. `t` (length `b`) is
/// scratch: `t[b - m]` holds `fl(l_{k+m,k} times)`, reversed so that each
/// row reads a forward slice. `false` at a non-finite quotient.
///
/// A multiplier below [`FLUSH`] in magnitude is stored as 0 and its row
/// skipped: in the factors of a high x-mode's lifted matrix most entries
/// decay far below the normal range, where every operation on a subnormal
/// number is many times slower (docs/status.md). Where a factorisation's
/// rounding is proved ([`SymBanded::verified_inertia_within_rows`],
/// `shifted_cholesky_rows`), the flushed entry's backward error is
/// counted: with `v` the multiplier flushed and `s = v pivot` (up to one
/// rounding) the entry it stood for, Higham's Lemma 8.4 bounds the residual
/// at its position by `gamma_b` times the stored products plus `|s| (1 +
/// gamma_b) <= FLUSH (1 + gamma_b) |pivot|` (`pivot` is `d_k` for
/// `L D L^T`, `r_kk` for Cholesky), and only the last term is new.
fn eliminate(c: &mut [f64], t: &mut [f64], b: usize, k: usize, pivot: f64, times: f64) -> bool {
    let b1 = b + 1;
    let reach = b.min(c.len() / b1 - 1 - k);
    for m in 1..=reach {
        let mut v = c[(k + m) * b1 + m] / pivot;
        if !v.is_finite() {
            return false;
        }
        if v.abs() < FLUSH {
            v = 0.0;
        }
        c[(k + m) * b1 + m] = v;
        t[b - m] = v * times;
    }
    for m in 1..=reach {
        let i = k + m;
        let lik = c[i * b1 + m];
        if lik == 0.0 {
            // nothing to subtract (up to the sign of a zero entry, which
            // no pivot test reads: a zero pivot fails either way)
            continue;
        }
        for (x, y) in c[i * b1..i * b1 + m].iter_mut().zip(&t[b - m..]) {
            *x -= lik * y;
        }
    }
    true
}

impl SymBanded {
    /// The zero matrix of size `n` and bandwidth `b`.
    pub fn zeros(n: usize, b: usize) -> Self {
        SymBanded { n, b, band: pool::zeroed(n * (b + 1)) }
    }

    /// Size.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Bandwidth.
    pub fn bandwidth(&self) -> usize {
        self.b
    }

    /// Entry `(i, j)` (symmetric; zero outside the band).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let (i, j) = if i >= j { (i, j) } else { (j, i) };
        if i - j > self.b {
            0.0
        } else {
            self.band[i * (self.b + 1) + (i - j)]
        }
    }

    /// Add `v` to entries `(i, j)` and `(j, i)` (once if `i == j`).
    ///
    /// # Panics
    /// If `|i - j|` exceeds the bandwidth (a programming error).
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        let (i, j) = if i >= j { (i, j) } else { (j, i) };
        assert!(i - j <= self.b, "entry ({i}, {j}) outside bandwidth {}", self.b);
        self.band[i * (self.b + 1) + (i - j)] += v;
    }

    /// `y = A x`.
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        let b1 = self.b + 1;
        for (i, yi) in y.iter_mut().enumerate().take(self.n) {
            let row = &self.band[i * b1..(i + 1) * b1];
            let mut s = row[0] * x[i];
            for d in 1..=self.b.min(i) {
                s += row[d] * x[i - d];
            }
            *yi = s;
        }
        for i in 0..self.n {
            let row = &self.band[i * b1..(i + 1) * b1];
            for d in 1..=self.b.min(i) {
                y[i - d] += row[d] * x[i];
            }
        }
    }

    /// This matrix stored by full rows, for repeated products ([`BandedRows`]).
    pub fn rows(&self) -> BandedRows {
        let (n, b) = (self.n, self.b);
        let w = 2 * b + 1;
        let mut rows = vec![0.0; n * w];
        for i in 0..n {
            for j in i.saturating_sub(b)..=i {
                let v = self.get(i, j);
                rows[i * w + (j + b - i)] = v;
                rows[j * w + (i + b - j)] = v;
            }
        }
        BandedRows { n, b, rows }
    }

    /// `A diag(w) A`, a symmetric matrix of bandwidth `2b`.
    ///
    /// Entry `(i, j)` is `sum_k A[i][k] w[k] A[k][j]` over `k` within `b`
    /// of both: one forward inner product of row `i` of `A` times `w` with
    /// row `j` of `A`, both held by full rows ([`SymBanded::rows`]'s
    /// layout). Reading each term through [`SymBanded::get`], with its
    /// branch, would make the product a fifth of a periodic mode's Lanczos
    /// run at ny = 1024 (`perf`, docs/fluids.md §5).
    ///
    /// ```
    /// use numerics::banded::SymBanded;
    /// // A = tridiag(-1, 2, -1) of size 3, w = (1, 2, 3): A diag(w) A by hand
    /// let mut a = SymBanded::zeros(3, 1);
    /// for i in 0..3 { a.add(i, i, 2.0); }
    /// for i in 1..3 { a.add(i, i - 1, -1.0); }
    /// let p = a.sandwich(&[1.0, 2.0, 3.0]);
    /// assert_eq!((p.get(0, 0), p.get(1, 0), p.get(2, 0)), (6.0, -6.0, 2.0));
    /// assert_eq!((p.get(1, 1), p.get(2, 1), p.get(2, 2)), (12.0, -10.0, 14.0));
    /// ```
    pub fn sandwich(&self, w: &[f64]) -> Self {
        let (n, b) = (self.n, self.b);
        let width = 2 * b + 1;
        let rows = self.rows().rows;
        // weighted[i * width + (k + b - i)] = A[i][k] w[k]
        let mut weighted = rows.clone();
        for i in 0..n {
            for k in i.saturating_sub(b)..=(i + b).min(n - 1) {
                weighted[i * width + (k + b - i)] *= w[k];
            }
        }
        let mut out = SymBanded::zeros(n, 2 * b);
        for i in 0..n {
            for j in i.saturating_sub(2 * b)..=i {
                // k from max(i - b, 0) to min(j + b, n - 1)
                let (klo, khi) = (i.saturating_sub(b), (j + b).min(n - 1));
                let wi = &weighted[i * width + (klo + b - i)..=i * width + (khi + b - i)];
                let rj = &rows[j * width + (klo + b - j)..=j * width + (khi + b - j)];
                out.band[i * (2 * b + 1) + (i - j)] = dot(wi, rj);
            }
        }
        out
    }

    /// `self + other` (bandwidth the larger of the two).
    pub fn plus(&self, other: &SymBanded) -> Self {
        let b = self.b.max(other.b);
        let mut out = SymBanded::zeros(self.n, b);
        for i in 0..self.n {
            for d in 0..=b.min(i) {
                out.band[i * (b + 1) + d] = self.get(i, i - d) + other.get(i, i - d);
            }
        }
        out
    }

    /// `c * self`.
    pub fn times(&self, c: f64) -> Self {
        SymBanded { n: self.n, b: self.b, band: self.band.iter().map(|v| c * v).collect() }
    }

    /// The dense matrix (for tests and the final dense check).
    pub fn to_dense(&self) -> nalgebra::DMatrix<f64> {
        nalgebra::DMatrix::from_fn(self.n, self.n, |i, j| self.get(i, j))
    }

    /// `s * self - q` formed in floating point, with a radius `r` such that
    /// the exact `s * self - q` is within `r` of the result in the 2-norm:
    /// each entry is rounded by at most `2.01 u (|s a_ij| + |q_ij|)` (one
    /// rounding for the product, one for the difference, `u = 2^-53`, plus
    /// the smallest subnormal for underflow), and the 2-norm of a symmetric
    /// matrix is at most its largest absolute row sum; that row sum is
    /// inflated by `(1 + 4 (2b + 3) u)` for its own rounding.
    pub fn scaled_minus(&self, s: f64, q: &SymBanded) -> (SymBanded, f64) {
        assert_eq!(self.n, q.n);
        let b = self.b.max(q.b);
        let mut out = SymBanded::zeros(self.n, b);
        let mut rows = vec![0.0f64; self.n];
        let u = f64::EPSILON / 2.0;
        for i in 0..self.n {
            for d in 0..=b.min(i) {
                let j = i - d;
                let (a, c) = (s * self.get(i, j), q.get(i, j));
                out.band[i * (b + 1) + d] = a - c;
                let e = 2.01 * u * (a.abs() + c.abs()) + 5e-324;
                rows[i] += e;
                if d > 0 {
                    rows[j] += e;
                }
            }
        }
        let width = (2 * b + 3) as f64;
        let radius = rows.iter().fold(0.0f64, |m, r| m.max(*r)) * (1.0 + 4.0 * width * u);
        (out, radius)
    }

    /// Whether every symmetric `A + E` with `||E||_2 <= radius` is proved
    /// positive definite, `A` this matrix, by a floating-point Cholesky
    /// factorisation with its rounding accounted for a posteriori.
    ///
    /// Written here rather than taken from a crate: the verified test of the
    /// generator crate is dense (`O(n^3)`) and bounds the rounding by the
    /// trace, which grows with `n`; a banded matrix needs the banded
    /// algorithm and a bound that does not. The argument (Demmel's bound,
    /// Higham, *Accuracy and Stability*, Thm 10.3, with the inner products
    /// of a band of width `b` having at most `b` terms): the Cholesky factor
    /// `R` computed for `A' = fl(A - c I)`, if it completes, satisfies
    /// `R^T R = A' + D`, `|D| <= gamma_{b+2} |R^T| |R|`; and
    /// `A' = A - c I + F` with `F` diagonal, `|F_jj| <= u |A'_jj| / (1 - u)`.
    /// So `lambda_min(A + E) >= c - gamma_{b+2} ||R^T| |R||_2 - max |F_jj| - radius`,
    /// and `||R^T| |R||_2` is at most the largest row sum of `|R^T| |R|`,
    /// computed from `R` and inflated for its own rounding. The shift `c`
    /// is chosen from the matrix, then raised once from the first factor's
    /// bound if needed; underflow adds `4 (b + 2)^3` times the smallest
    /// normal number, as in the dense test.
    ///
    /// ```
    /// use numerics::banded::SymBanded;
    /// let mut a = SymBanded::zeros(3, 1); // tridiag(-1, 2, -1): eigenvalues 2 - sqrt 2, 2, 2 + sqrt 2
    /// for i in 0..3 { a.add(i, i, 2.0); }
    /// for i in 1..3 { a.add(i, i - 1, -1.0); }
    /// assert!(a.verified_positive_definite_within(0.5));  // 0.5858 > 0.5
    /// assert!(!a.verified_positive_definite_within(0.6)); // 0.5858 < 0.6
    /// ```
    pub fn verified_positive_definite_within(&self, radius: f64) -> bool {
        let (n, b) = (self.n, self.b);
        if n == 0 || !(radius.is_finite() && radius >= 0.0) || self.band.iter().any(|x| !x.is_finite()) {
            return false;
        }
        let b1 = b + 1;
        if (0..n).any(|i| self.band[i * b1] <= 0.0) {
            return false;
        }
        let u = f64::EPSILON / 2.0;
        let m = (b + 2) as f64;
        let gamma = gamma(b + 2);
        let max_row = (0..n)
            .map(|i| (0..n.min(i + b + 1)).skip(i.saturating_sub(b)).map(|j| self.get(i, j).abs()).sum::<f64>())
            .fold(0.0f64, f64::max);
        let underflow = 4.0 * m.powi(3) * f64::MIN_POSITIVE;
        // The rounding share of the shift: first from the matrix, then (once)
        // twice what the first factor showed was needed; the radius is added
        // as it is, never scaled.
        let mut rounding = 2.0 * gamma * max_row;
        for _ in 0..2 {
            let shift = (rounding + radius + underflow) * (1.0 + 16.0 * u);
            let Some(error) = self.shifted_cholesky_bound(shift, gamma) else { return false };
            let needed = (error + radius + underflow) * (1.0 + 16.0 * u);
            if !needed.is_finite() {
                return false;
            }
            if shift > needed {
                return true;
            }
            rounding = 2.0 * error;
        }
        false
    }

    /// Whether this matrix is nonempty and finite and `rows` holds one
    /// finite nonnegative bound per row: the inputs the row-by-row tests
    /// accept.
    fn finite_with_row_bounds(&self, rows: &[f64]) -> bool {
        self.n > 0
            && rows.len() == self.n
            && rows.iter().all(|r| r.is_finite() && *r >= 0.0)
            && self.band.iter().all(|x| x.is_finite())
    }

    /// `A ≻ diag(f)`, `A` this matrix and `f >= 0`, proved by a
    /// floating-point Cholesky factorisation of `fl(A - diag(s))` with the
    /// rounding bounded row by row: the argument of
    /// [`SymBanded::verified_positive_definite_within`] with
    /// `R^T R = A' + Delta`, `|Delta| <= gamma_{b+2} |R^T| |R|`, and
    /// `|x^T Delta x| <= sum_i (sum_j |Delta_ij|) x_i^2`, so
    /// `x^T (A - diag(f)) x >= x^T R^T R x + sum_i (s_i - f_i - |F_ii| - gamma
    /// (|R^T| |R| 1)_i) x_i^2 > 0` when every row's shift covers its own
    /// rounding. The shifts start at twice `gamma_{b+2}` times the row sums
    /// of `|A|` and are raised once from the first factor's bounds if needed.
    ///
    /// ```
    /// use numerics::banded::SymBanded;
    /// let mut a = SymBanded::zeros(2, 1); // diag(1, 1e-6)
    /// a.add(0, 0, 1.0);
    /// a.add(1, 1, 1e-6);
    /// assert!(a.verified_positive_definite_above(&[0.5, 5e-7]));
    /// assert!(!a.verified_positive_definite_above(&[0.5, 2e-6]));
    /// assert!(!a.verified_positive_definite_within(5e-6)); // one shift for both rows
    /// ```
    pub fn verified_positive_definite_above(&self, f: &[f64]) -> bool {
        self.verified_positive_definite_above_from(f, None)
    }

    /// [`SymBanded::verified_positive_definite_above`], first trying the
    /// rounding shares `first` (one a row) if given. Each attempt is a
    /// complete proof of its own, so a guess can only save work: if it
    /// fails, the usual schedule runs after it. For `P = L |D| L^T` the
    /// caller knows `|R^T| |R|` in advance (it is `|L| |D| |L^T|`, whose row
    /// sums it has computed), which the first share from `|P|` misses where
    /// `P`'s entries cancel: a second factorisation is then needed, a
    /// fifth of a check's time (periodic modes 3 to 8 of Kolmogorov flow at
    /// ny = 1024).
    fn verified_positive_definite_above_from(&self, f: &[f64], first: Option<&[f64]>) -> bool {
        let (n, b) = (self.n, self.b);
        if !self.finite_with_row_bounds(f) {
            return false;
        }
        let b1 = b + 1;
        if (0..n).any(|i| self.band[i * b1] <= 0.0) {
            return false;
        }
        let u = f64::EPSILON / 2.0;
        let gamma = gamma(b + 2);
        let underflow = 4.0 * ((b + 2) as f64).powi(3) * f64::MIN_POSITIVE;
        // One attempt: `Some(error)` if the factor completed, and whether its
        // shifts covered their rows' rounding; `None` if it did not.
        let attempt = |rounding: &[f64]| -> Option<(Vec<f64>, bool)> {
            let shift: Vec<f64> = (0..n).map(|i| ((rounding[i] + f[i]) + underflow) * (1.0 + 16.0 * u)).collect();
            if shift.iter().any(|x| !x.is_finite()) {
                return None;
            }
            let error = self.shifted_cholesky_rows(&shift, gamma)?;
            let mut enough = true;
            for i in 0..n {
                let needed = ((error[i] + f[i]) + underflow) * (1.0 + 16.0 * u);
                if !needed.is_finite() {
                    return None;
                }
                enough &= shift[i] > needed;
            }
            Some((error, enough))
        };
        if let Some(first) = first {
            if first.len() == n && first.iter().all(|r| r.is_finite() && *r >= 0.0) {
                if let Some((_, true)) = attempt(first) {
                    return true;
                }
            }
        }
        let mut rounding: Vec<f64> = (0..n)
            .map(|i| {
                let row = (i.saturating_sub(b)..n.min(i + b + 1)).map(|j| self.get(i, j).abs()).sum::<f64>();
                2.0 * gamma * row
            })
            .collect();
        for _ in 0..2 {
            match attempt(&rounding) {
                None => return false,
                Some((_, true)) => return true,
                Some((error, false)) => rounding = error.iter().map(|e| 2.0 * e).collect(),
            }
        }
        false
    }

    /// Factor `fl(A - shift I)` (Cholesky on the band); if it completes,
    /// the bound `gamma max_i (|R^T| |R| 1)_i + max |F_jj|` of
    /// [`SymBanded::verified_positive_definite_within`], rounded upwards.
    fn shifted_cholesky_bound(&self, shift: f64, gamma: f64) -> Option<f64> {
        let error = self.shifted_cholesky_rows(&vec![shift; self.n], gamma)?;
        Some(error.iter().fold(0.0f64, |m, e| m.max(*e)))
    }

    /// Factor `fl(A - diag(shift))` (Cholesky on the band); if it
    /// completes, each row's `gamma (|R^T| |R| 1)_i + |F_ii|` rounded
    /// upwards, `F` the rounding of the shifted diagonal.
    fn shifted_cholesky_rows(&self, shift: &[f64], gamma: f64) -> Option<Vec<f64>> {
        let (n, b) = (self.n, self.b);
        let b1 = b + 1;
        let u = f64::EPSILON / 2.0;
        // c[i * b1 + d]: a[i][i - d] (the diagonal shifted) until pivot
        // i - d is taken, then L[i][i - d], L = R^T. Right-looking
        // (`eliminate`), like `ldl`.
        let mut c = pool::copy_of(&self.band);
        let mut diag_err = vec![0.0f64; n];
        for i in 0..n {
            let d = c[i * b1] - shift[i];
            diag_err[i] = d.abs() * u / (1.0 - u);
            c[i * b1] = d;
        }
        let mut t = vec![0.0; b];
        for k in 0..n {
            let s = c[k * b1];
            if !(s.is_finite() && s > 0.0) {
                return None;
            }
            let r = s.sqrt();
            c[k * b1] = r;
            // times 1: t = l exactly
            if !eliminate(&mut c, &mut t, b, k, r, 1.0) {
                return None;
            }
        }
        // Row sums of |L| |L^T|: sum_k |l_ik| colsum_k, colsum_k = sum_j |l_jk|.
        let mut colsum = vec![0.0f64; n];
        for i in 0..n {
            for d in 0..=b.min(i) {
                colsum[i - d] += c[i * b1 + d].abs();
            }
        }
        // A quotient l_ij = fl(s / r_jj) that underflows is off by up to
        // 2^-1075, which the entry (i, j) of R^T R carries times r_jj: at
        // most (b + 1) 2^-1074 max r_jj in a row, counting the entries in
        // both rows they touch (row j's own shift covers it many times
        // over, but the bound should not rely on that).
        let max_r = (0..n).fold(0.0f64, |m, k| m.max(c[k * b1]));
        // A multiplier flushed to zero by `eliminate` leaves at most
        // FLUSH (1 + gamma_b) r_kk in R^T R - A' at its entry (`eliminate`'s
        // docs): at most b such entries in row i and b in column i. 2b + 2
        // are counted, times (1 + 4u): the two spare ones cover the
        // 2b gamma_b FLUSH max_r.
        let flushed = (2 * b + 2) as f64 * FLUSH * max_r * (1.0 + 4.0 * u);
        let quotient_underflow = (b + 1) as f64 * 5e-324 * max_r * (1.0 + 2.0 * u) + 5e-324 + flushed;
        // Both sums have at most 2b + 1 terms: inflate for their rounding,
        // and the sums with the diagonal's error and the underflow (a
        // relative u each).
        let inflate = 1.0 + 4.0 * (2 * b + 3) as f64 * u;
        Some(
            (0..n)
                .map(|i| {
                    let mut s = 0.0;
                    for d in 0..=b.min(i) {
                        s += c[i * b1 + d].abs() * colsum[i - d];
                    }
                    ((gamma * (s * inflate) + diag_err[i]) + quotient_underflow) * (1.0 + 4.0 * u)
                })
                .collect(),
        )
    }

    /// This matrix scaled by powers of two, `D A D` with `D = diag(2^-e_i)`
    /// and `2^e_i` the power of two nearest `sqrt |a_ii|` (1 where
    /// `a_ii = 0`), and the 2-norm radius that an entrywise error bound
    /// `err` (`|A_exact - A| <= err`, same pattern) becomes: the largest row
    /// sum of `D err D`, inflated for its own rounding. Scaling by powers of
    /// two is exact in binary floating point unless a result is subnormal,
    /// so an entry that lands below the smallest normal number adds that
    /// number to the radius. `D A D` is congruent to `A`: same inertia, and
    /// definite exactly when `A` is; the verified tests are relative to the
    /// scale of the matrix, which this equilibrates (Demmel: Cholesky is
    /// accurate relative to the diagonally scaled condition number).
    ///
    /// ```
    /// use numerics::banded::SymBanded;
    /// let mut a = SymBanded::zeros(2, 1); // diag(1e6, 1e-6), off-diagonal 1e-3
    /// a.add(0, 0, 1e6); a.add(1, 1, 1e-6); a.add(1, 0, 1e-3);
    /// let mut err = SymBanded::zeros(2, 1);
    /// err.add(1, 0, 1e-10);
    /// let (s, r) = a.power_of_two_scaled(&err);
    /// // sqrt(1e6) = 1000 is scaled by 2^-10, sqrt(1e-6) by 2^10: the product is 1
    /// assert_eq!(s.get(1, 0), 1e-3);
    /// assert!(s.get(0, 0) > 0.5 && s.get(0, 0) < 2.0 && s.get(1, 1) > 0.5 && s.get(1, 1) < 2.0);
    /// assert!(r >= 1e-10 && r < 1.01e-10);
    /// ```
    pub fn power_of_two_scaled(&self, err: &SymBanded) -> (SymBanded, f64) {
        let (out, rows) = self.power_of_two_scaled_rows(err);
        (out, rows.iter().fold(0.0f64, |m, r| m.max(*r)))
    }

    /// [`SymBanded::power_of_two_scaled`] with the row sums of `D err D`
    /// (each inflated for its own rounding) in place of their largest: for
    /// [`SymBanded::verified_inertia_within_rows`].
    ///
    /// ```
    /// use numerics::banded::SymBanded;
    /// let mut a = SymBanded::zeros(2, 1); // diag(4, 1/4)
    /// a.add(0, 0, 4.0); a.add(1, 1, 0.25);
    /// let mut err = SymBanded::zeros(2, 1);
    /// err.add(0, 0, 1e-10); err.add(1, 1, 1e-10);
    /// let (s, rows) = a.power_of_two_scaled_rows(&err);
    /// // scaled by 1/2 and 2: diag(1, 1), the errors by 1/4 and 4
    /// assert_eq!((s.get(0, 0), s.get(1, 1)), (1.0, 1.0));
    /// assert!(rows[0] >= 0.25e-10 && rows[0] < 0.2501e-10);
    /// assert!(rows[1] >= 4e-10 && rows[1] < 4.001e-10);
    /// ```
    pub fn power_of_two_scaled_rows(&self, err: &SymBanded) -> (SymBanded, Vec<f64>) {
        assert_eq!((self.n, self.b), (err.n, err.b), "the error bound must have the matrix's pattern");
        let (n, b1) = (self.n, self.b + 1);
        let d: Vec<f64> = (0..n)
            .map(|i| {
                let a = self.band[i * b1].abs();
                if a > 0.0 && a.is_finite() {
                    // 2^-round(log2 sqrt a), exact
                    let e = (0.5 * a.log2()).round() as i32;
                    pow2(-e)
                } else {
                    1.0
                }
            })
            .collect();
        let mut out = SymBanded::zeros(n, self.b);
        let mut rows = vec![0.0f64; n];
        for i in 0..n {
            for dd in 0..=self.b.min(i) {
                let j = i - dd;
                let f = d[i] * d[j];
                let v = self.band[i * b1 + dd] * f;
                out.band[i * b1 + dd] = v;
                // the product d_i d_j err may itself underflow: round it up
                // (a zero bound stays exactly zero: 0 f = 0)
                let ev = err.band[i * b1 + dd];
                let mut e = if ev == 0.0 { 0.0 } else { plus_underflow(ev * f, 1.0) };
                // and so may the scaled entry, to a subnormal number or to
                // zero (an entry whose own bound is zero, such as a stored
                // L_ab, must still be counted when it underflows to 0)
                if v.abs() < f64::MIN_POSITIVE && self.band[i * b1 + dd] != 0.0 {
                    e += f64::MIN_POSITIVE;
                }
                rows[i] += e;
                if dd > 0 {
                    rows[j] += e;
                }
            }
        }
        let u = f64::EPSILON / 2.0;
        let inflate = 1.0 + 4.0 * (2 * self.b + 3) as f64 * u;
        rows.iter_mut().for_each(|r| *r *= inflate);
        (out, rows)
    }

    /// The inertia `(positive, negative)` of every symmetric `A + E` with
    /// `||E||_2 <= radius`, `A` this matrix, when a floating-point `L D L^T`
    /// factorisation (no pivoting) proves it; `None` otherwise.
    ///
    /// Written here: no crate offers a verified inertia, and the argument is
    /// short. `L` (unit lower triangular, bandwidth `b`) and `D` (diagonal,
    /// no zero) are the computed factors, exact real numbers.
    ///
    /// **The backward error, a priori.** Each entry of the factorisation
    /// is one inner product `fl((a_ij - sum_k t_k l_jk) / d_j)` of at most
    /// `b` terms, `t_k = fl(l_ik d_k)`, so by Higham's Lemma 8.4 (any order
    /// of summation) and one more rounding for `t_k`,
    /// `|A - L D L^T| <= gamma_{b+2} |L| |D| |L^T|` entrywise, plus
    /// underflow: with gradual underflow every product and quotient may add
    /// an absolute `2^-1075` (sums add none), which multiplied through is at
    /// most `2 * 2^-1075 (b + 1 + sum_k |l_jk| + |d_j|)` per entry. So
    /// `||A + E - L D L^T||_2 <= eps`, `eps` the largest row sum of those
    /// bounds plus `radius`. The row sums of `|L| |D| |L^T|` cost `O(n b)`:
    /// `sum_k |l_ik| |d_k| c_k`, `c_k` the column sums of `|L|`. (Computing
    /// the residual `A - L D L^T` entry by entry would be one more
    /// `O(n b^2)` pass, and its bound would carry `gamma_{2b+4}
    /// (|A| + |L||D||L^T|)` for its own rounding besides: never tighter.)
    ///
    /// **The inertia.** With `G = L |D|^{1/2}` and `J = sign(D)`,
    /// `A + E = G (J + F) G^T` where `||F||_2 <= eps / lambda_min(G G^T)`.
    /// If the banded matrix `P = G G^T = L |D| L^T`, formed in floating
    /// point within `gamma_{b+2} |L| |D| |L^T|` (plus underflow, as above),
    /// is proved to have `lambda_min > eps` (the verified Cholesky test of
    /// [`SymBanded::verified_positive_definite_within`] with the formation
    /// error added to the radius), `||F||_2 < 1`, the eigenvalues of
    /// `J + F` keep the signs of `J`'s (Weyl), and by Sylvester's law of
    /// inertia `A + E` has the inertia of `D`. Unlike a bound through
    /// `||L^-1||^2`, this one is as sharp as the definite test: for a
    /// definite `A`, `L |D| L^T` is `A` itself.
    ///
    /// ```
    /// use numerics::banded::SymBanded;
    /// // tridiag(1, 0.5, 1) of size 3: eigenvalues 0.5 - sqrt 2, 0.5, 0.5 + sqrt 2
    /// let mut a = SymBanded::zeros(3, 1);
    /// for i in 0..3 { a.add(i, i, 0.5); }
    /// for i in 1..3 { a.add(i, i - 1, 1.0); }
    /// assert_eq!(a.verified_inertia_within(0.1), Some((2, 1)));
    /// assert_eq!(a.verified_inertia_within(0.6), None); // 0.5 could be 0
    /// ```
    pub fn verified_inertia_within(&self, radius: f64) -> Option<(usize, usize)> {
        if !(radius.is_finite() && radius >= 0.0) {
            return None;
        }
        self.verified_inertia_within_rows(&vec![radius; self.n])
    }

    /// The inertia of every symmetric `A + E` with `|x^T E x| <= sum_i
    /// r_i x_i^2` for all `x` (`r` = `radii`; an entrywise bound on `E`
    /// whose row sums are at most `r_i` gives this, because `|x_i x_j| <=
    /// (x_i^2 + x_j^2)/2`), when a floating-point `L D L^T` proves it;
    /// `None` otherwise. [`SymBanded::verified_inertia_within`] is the case
    /// `r_i = radius`.
    ///
    /// The argument of [`SymBanded::verified_inertia_within`] with every
    /// bound kept row by row: the backward error and the formation error of
    /// `P = L |D| L^T` are entrywise `gamma_{b+2} |L| |D| |L^T|`, so
    /// `|x^T F x| <= sum_i f_i x_i^2` with `f_i` the row sums of those
    /// bounds plus `r_i` (and underflow), and `P ≻ diag(f)`
    /// ([`SymBanded::verified_positive_definite_above`]) gives
    /// `|x^T F x| < x^T G G^T x`, i.e. `||G^-1 F G^-T||_2 < 1`. Where the
    /// growth of the factorisation sits in a few rows, this is sharper than
    /// one shift by the largest row sum for all of them.
    ///
    /// ```
    /// use numerics::banded::SymBanded;
    /// // diag(1, -1e-6): a uniform radius of 1e-5 proves nothing, but
    /// // row radii (1e-5, 1e-7) prove the inertia (1, 1)
    /// let mut a = SymBanded::zeros(2, 1);
    /// a.add(0, 0, 1.0);
    /// a.add(1, 1, -1e-6);
    /// assert_eq!(a.verified_inertia_within(1e-5), None);
    /// assert_eq!(a.verified_inertia_within_rows(&[1e-5, 1e-7]), Some((1, 1)));
    /// ```
    pub fn verified_inertia_within_rows(&self, radii: &[f64]) -> Option<(usize, usize)> {
        let (n, b) = (self.n, self.b);
        if !self.finite_with_row_bounds(radii) {
            return None;
        }
        let b1 = b + 1;
        let (l, dg) = self.ldl()?;
        let u = f64::EPSILON / 2.0;
        // Column sums of |L| (unit diagonal included) and the row sums of
        // |L| |D| |L^T|; row sums of |L| and max |D| for the underflow term.
        let mut colsum = vec![0.0f64; n];
        let mut max_lrow = 0.0f64;
        for i in 0..n {
            let mut r = 0.0;
            for d in 0..=b.min(i) {
                let a = l[i * b1 + d].abs();
                colsum[i - d] += a;
                r += a;
            }
            max_lrow = max_lrow.max(r);
        }
        let max_d = dg.iter().fold(0.0f64, |m, d| m.max(d.abs()));
        // The sums below: at most b + 1 terms each, nested, with two
        // products, so a relative error below gamma_{2b+2}, inflated for by
        // this factor; underflow in the products adds at most 2^-1074 * 2
        // (b + 1 + max_lrow) to a row's sum (counted below).
        let inflate = 1.0 + 4.0 * (2 * b + 3) as f64 * u;
        // Underflow (the docs of `verified_inertia_within`): per entry at
        // most 2^-1074 (b + 1 + max_lrow + max_d) for the factorisation and
        // as much for P's formation, 2b + 1 entries a row; one more such row
        // covers the row sum's own underflow (times gamma < 1/2), and one
        // subnormal step this product's own rounding.
        let underflow = 5e-324 * (2 * b + 2) as f64 * ((b + 1) as f64 + max_lrow + max_d) * inflate + 5e-324;
        // A multiplier flushed to zero by `eliminate` leaves at most
        // FLUSH (1 + gamma_b) |d_k| in A - L D L^T at its entry
        // (`eliminate`'s docs): b in row i and b in column i (2b + 2
        // counted, times inflate >= 1 + gamma_b).
        let underflow = underflow + (2 * b + 2) as f64 * FLUSH * max_d * inflate;
        let mut shift = Vec::with_capacity(n);
        // the first rounding shares to try for P's Cholesky (the docs of
        // `verified_positive_definite_above_from`): twice gamma_{b+2} times
        // the row sums r of |L| |D| |L^T|, which P's factor would repeat
        let mut first = Vec::with_capacity(n);
        for i in 0..n {
            let mut r = 0.0;
            for d in 0..=b.min(i) {
                r += l[i * b1 + d].abs() * (dg[i - d].abs() * colsum[i - d]);
            }
            // The a-priori bound of the backward error in this row, and as
            // much for P's formation, plus the row's radius; each rounded
            // upwards (a relative u, or one subnormal step).
            let per = plus_underflow((gamma(b + 2) * (r * inflate) + underflow) * (1.0 + 4.0 * u), 1.0);
            let f = ((per + radii[i]) + per) * (1.0 + 4.0 * u);
            if !f.is_finite() {
                return None;
            }
            shift.push(f);
            first.push(2.0 * gamma(b + 2) * (r * inflate));
        }
        let p = Self::abs_ldl(&l, &dg, b);
        if !p.verified_positive_definite_above_from(&shift, Some(&first)) {
            return None;
        }
        let pos = dg.iter().filter(|d| **d > 0.0).count();
        Some((pos, n - pos))
    }

    /// The unpivoted `L D L^T` factors in floating point, `l[i * (b + 1) + d]
    /// = L[i][i - d]` (the unit diagonal stored at `d = 0`) and `D`; `None`
    /// at a zero or non-finite pivot.
    ///
    /// Right-looking (`eliminate`, with `times = d_k`). The inner-product
    /// form chains each entry's sum to the next and takes about twice as
    /// long (9.6 ms against this form's 4.6 ms for the lifted matrix of
    /// ny = 2048, two noise fields).
    fn ldl(&self) -> Option<(pool::Buffer, Vec<f64>)> {
        let (n, b) = (self.n, self.b);
        let b1 = b + 1;
        // l[i * b1 + d]: a[i][i - d] until pivot i - d is taken, then L[i][i - d]
        let mut l = pool::copy_of(&self.band);
        let mut dg = vec![0.0; n];
        let mut t = vec![0.0; b];
        for k in 0..n {
            let dk = l[k * b1];
            if !(dk.is_finite() && dk != 0.0) {
                return None;
            }
            dg[k] = dk;
            if !eliminate(&mut l, &mut t, b, k, dk, dk) {
                return None;
            }
        }
        // the unit diagonal stored, so every row is one slice
        for i in 0..n {
            l[i * b1] = 1.0;
        }
        Some((l, dg))
    }

    /// `L |D| L^T` in floating point from the factors of [`SymBanded::ldl`]:
    /// `sum_k |d_k| l_k l_k^T` on the band, right-looking (each entry's sum
    /// in one order, of at most `b + 1` products of two roundings each).
    fn abs_ldl(l: &[f64], dg: &[f64], b: usize) -> SymBanded {
        let (n, b1) = (dg.len(), b + 1);
        let mut p = SymBanded::zeros(n, b);
        // t[b - m] = fl(L[k + m][k] |D[k]|), m = 0..=b
        let mut t = vec![0.0; b1];
        for k in 0..n {
            let reach = b.min(n - 1 - k);
            let ad = dg[k].abs();
            for m in 0..=reach {
                t[b - m] = l[(k + m) * b1 + m] * ad;
            }
            // rows i = k + m, columns j = i - d for d = 0..=m
            for m in 0..=reach {
                let i = k + m;
                let lik = l[i * b1 + m];
                if lik == 0.0 {
                    // flushed (`eliminate`): nothing to add
                    continue;
                }
                for (x, y) in p.band[i * b1..=i * b1 + m].iter_mut().zip(&t[b - m..]) {
                    *x += lik * y;
                }
            }
        }
        p
    }

    /// The inertia `(positive, negative)` of this matrix as an unpivoted
    /// floating-point `L D L^T` counts it (Sylvester), with no proof: for
    /// searches, where a wrong count near a singular matrix only moves the
    /// search. `None` at a zero or non-finite pivot.
    ///
    /// ```
    /// use numerics::banded::SymBanded;
    /// // tridiag(1, 0.5, 1): eigenvalues 0.5 - sqrt 2 < 0 < 0.5 < 0.5 + sqrt 2
    /// let mut a = SymBanded::zeros(3, 1);
    /// for i in 0..3 { a.add(i, i, 0.5); }
    /// for i in 1..3 { a.add(i, i - 1, 1.0); }
    /// assert_eq!(a.inertia(), Some((2, 1)));
    /// ```
    pub fn inertia(&self) -> Option<(usize, usize)> {
        if self.n == 0 || self.band.iter().any(|x| !x.is_finite()) {
            return None;
        }
        let (_, dg) = self.ldl()?;
        let pos = dg.iter().filter(|d| **d > 0.0).count();
        Some((pos, self.n - pos))
    }

    /// Cholesky factor `A = C C^T`, `C` lower triangular with the same bandwidth.
    pub fn cholesky(&self) -> Result<BandedCholesky, BandedError> {
        let mut c = vec![];
        self.factor_into(None, &mut c).map(|()| BandedCholesky::from_band(self.n, self.b, &c))
    }

    /// Whether `self - shift * other` (same size and bandwidth) has a
    /// floating-point Cholesky factor, computed in `work` without forming
    /// the difference: for bisections on a pencil, which would otherwise
    /// allocate two matrices a step. Unproved, like [`SymBanded::cholesky`].
    ///
    /// ```
    /// use numerics::banded::SymBanded;
    /// // tridiag(-1, 2, -1) - l I: definite for l < 2 - sqrt 2 = 0.5858
    /// let mut a = SymBanded::zeros(3, 1);
    /// let mut id = SymBanded::zeros(3, 1);
    /// for i in 0..3 { a.add(i, i, 2.0); id.add(i, i, 1.0); }
    /// for i in 1..3 { a.add(i, i - 1, -1.0); }
    /// let mut work = vec![];
    /// assert!(a.minus_is_positive_definite(0.58, &id, &mut work));
    /// assert!(!a.minus_is_positive_definite(0.59, &id, &mut work));
    /// ```
    ///
    /// # Panics
    /// If the sizes or bandwidths differ (a programming error).
    pub fn minus_is_positive_definite(&self, shift: f64, other: &SymBanded, work: &mut Vec<f64>) -> bool {
        assert!(self.n == other.n && self.b == other.b, "same size and bandwidth");
        self.factor_into(Some((shift, other)), work).is_ok()
    }

    /// The banded Cholesky factor of `self - shift * other` into `c`.
    ///
    /// Right-looking (`eliminate` with `times = 1`), like [`SymBanded::ldl`]:
    /// in the inner-product form this factorisation is an eighth of a
    /// periodic mode's Lanczos run at ny = 1024 (`perf`, docs/fluids.md §5).
    fn factor_into(&self, minus: Option<(f64, &SymBanded)>, c: &mut Vec<f64>) -> Result<(), BandedError> {
        let (n, b) = (self.n, self.b);
        let b1 = b + 1;
        // c[i * b1 + d]: a[i][i - d] until pivot i - d is taken, then C[i][i - d]
        c.clear();
        match minus {
            None => c.extend_from_slice(&self.band),
            Some((shift, other)) => c.extend(self.band.iter().zip(&other.band).map(|(a, o)| a - shift * o)),
        }
        let mut t = vec![0.0; b];
        for k in 0..n {
            let s = c[k * b1];
            if s.is_nan() || s <= 0.0 || !s.is_finite() {
                return Err(BandedError::NonPositivePivot { index: k, value: s });
            }
            let r = s.sqrt();
            c[k * b1] = r;
            if !eliminate(c, &mut t, b, k, r, 1.0) {
                // a non-finite multiplier: the next pivot is not finite either
                let at = (k + 1).min(n - 1);
                return Err(BandedError::NonPositivePivot { index: at, value: f64::NAN });
            }
        }
        Ok(())
    }
}

/// A symmetric banded matrix stored by full rows, for repeated products:
/// `rows[i * (2b + 1) + (j + b - i)] = a[i][j]` (0 outside the matrix), so
/// `(A x)_i` is one forward inner product (four partial sums) of a
/// stored row with `x[i - b ..= i + b]`. [`SymBanded::mul_vec`] reads the
/// lower band only and so walks `x` backwards in one pass and scatters into
/// `y` in a second; this costs twice the memory and is built once.
///
/// ```
/// use numerics::banded::SymBanded;
/// // tridiag(-1, 2, -1) of size 4 times (1, 2, 3, 4) = (0, 0, 0, 5)
/// let mut a = SymBanded::zeros(4, 1);
/// for i in 0..4 { a.add(i, i, 2.0); }
/// for i in 1..4 { a.add(i, i - 1, -1.0); }
/// let mut y = vec![0.0; 4];
/// a.rows().mul_vec(&[1.0, 2.0, 3.0, 4.0], &mut y);
/// assert_eq!(y, vec![0.0, 0.0, 0.0, 5.0]);
/// ```
#[derive(Clone, Debug)]
pub struct BandedRows {
    n: usize,
    b: usize,
    rows: Vec<f64>,
}

impl BandedRows {
    /// `y = A x`.
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        let (n, b) = (self.n, self.b);
        let w = 2 * b + 1;
        for (i, yi) in y.iter_mut().enumerate().take(n) {
            let (lo, hi) = (i.saturating_sub(b), (i + b).min(n - 1));
            let row = &self.rows[i * w + (lo + b - i)..=i * w + (hi + b - i)];
            *yi = dot(row, &x[lo..=hi]);
        }
    }
}

/// A banded Cholesky factor `A = C C^T`, stored for its solves: each row of
/// `C` and each column of `C` (a row of `C^T`) as a forward slice, and the
/// reciprocals of the diagonal.
///
/// Why two copies. A triangular solve is a chain: each unknown needs the one
/// before it. Read from the factorisation's band (`C[i][i - d]` at
/// `d = 1..=b`), the lower solve walks `x` backwards and the upper one
/// scatters into it, so each row waits on its `b` products in turn and on a
/// division. Here each row is one forward inner product of four partial
/// sums (which vectorises), the unknown just solved enters last,
/// and the division is a multiplication by the stored reciprocal: the
/// chain per row is one multiply-add and one product. The solves are not
/// part of any verified claim (Lanczos, conjugate gradients, simulations).
/// Measured at ny = 1024 (`fluid_mode`, mode 1 of `bench/cubic-walls.json`,
/// best of 20): see docs/fluids.md §5.
#[derive(Clone, Debug)]
pub struct BandedCholesky {
    n: usize,
    b: usize,
    /// `lower[i * b + (b - d)] = C[i][i - d]`, `d = 1..=b` (0 before row 0):
    /// row `i` left of the diagonal, in column order.
    lower: Vec<f64>,
    /// `upper[i * b + (d - 1)] = C[i + d][i]`, `d = 1..=b` (0 past row
    /// `n - 1`): column `i` below the diagonal, in row order.
    upper: Vec<f64>,
    /// `1 / C[i][i]`.
    recip: Vec<f64>,
}

impl BandedCholesky {
    /// The solver of the factor held in a lower band (`c[i * (b + 1) + d] = C[i][i - d]`).
    fn from_band(n: usize, b: usize, c: &[f64]) -> Self {
        let b1 = b + 1;
        let mut lower = vec![0.0; n * b];
        let mut upper = vec![0.0; n * b];
        for i in 0..n {
            for d in 1..=b.min(i) {
                let v = c[i * b1 + d];
                lower[i * b + (b - d)] = v;
                upper[(i - d) * b + (d - 1)] = v;
            }
        }
        let recip = (0..n).map(|i| 1.0 / c[i * b1]).collect();
        BandedCholesky { n, b, lower, upper, recip }
    }

    /// Solve `C z = x` in place.
    pub fn solve_lower(&self, x: &mut [f64]) {
        let b = self.b;
        if b == 0 {
            x.iter_mut().zip(&self.recip).for_each(|(x, r)| *x *= r);
            return;
        }
        for i in 0..self.n {
            let row = &self.lower[i * b..(i + 1) * b];
            // columns i - b .. i - 2 first, then i - 1 (the last unknown solved)
            let lo = i.saturating_sub(b);
            let s = if i == 0 {
                x[0]
            } else {
                let far = dot(&row[b - (i - lo)..b - 1], &x[lo..i - 1]);
                (x[i] - far) - row[b - 1] * x[i - 1]
            };
            x[i] = s * self.recip[i];
        }
    }

    /// Solve `C^T z = x` in place.
    pub fn solve_upper(&self, x: &mut [f64]) {
        let (n, b) = (self.n, self.b);
        if b == 0 {
            x.iter_mut().zip(&self.recip).for_each(|(x, r)| *x *= r);
            return;
        }
        for i in (0..n).rev() {
            let col = &self.upper[i * b..(i + 1) * b];
            // rows i + 2 .. i + b first, then i + 1 (the last unknown solved)
            let hi = (i + b).min(n - 1);
            let s = if i + 1 == n {
                x[i]
            } else {
                let far = if hi >= i + 2 { dot(&col[1..hi - i], &x[i + 2..=hi]) } else { 0.0 };
                (x[i] - far) - col[0] * x[i + 1]
            };
            x[i] = s * self.recip[i];
        }
    }

    /// Solve `A z = x` in place.
    pub fn solve(&self, x: &mut [f64]) {
        self.solve_lower(x);
        self.solve_upper(x);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    fn example(n: usize, b: usize) -> SymBanded {
        let mut a = SymBanded::zeros(n, b);
        for i in 0..n {
            a.add(i, i, 4.0 + (i as f64).sin());
            for d in 1..=b.min(i) {
                a.add(i, i - d, 0.5 / (d as f64 + 1.0) * ((i * d) as f64).cos());
            }
        }
        a
    }

    #[test]
    fn banded_operations_match_dense_nalgebra() {
        let (n, b) = (23, 3);
        let a = example(n, b);
        let dense = a.to_dense();
        let x: Vec<f64> = (0..n).map(|i| ((i * 7 % 5) as f64) - 1.5).collect();
        let mut y = vec![0.0; n];
        a.mul_vec(&x, &mut y);
        let yd = &dense * DVector::from_vec(x.clone());
        for i in 0..n {
            assert!((y[i] - yd[i]).abs() < 1e-13 * (1.0 + yd[i].abs()));
        }
        // solve: residual check A z - x
        let f = a.cholesky().unwrap();
        let mut z = x.clone();
        f.solve(&mut z);
        let r = &dense * DVector::from_vec(z) - DVector::from_vec(x.clone());
        assert!(r.norm() < 1e-13 * (n as f64));
        // sandwich A diag(w) A against the dense product
        let w: Vec<f64> = (0..n).map(|i| 1.0 + 0.1 * i as f64).collect();
        let s = a.sandwich(&w).to_dense();
        let sd = &dense * DMatrix::from_diagonal(&DVector::from_vec(w)) * &dense;
        assert!((&s - &sd).norm() < 1e-12 * sd.norm());
    }

    #[test]
    fn cholesky_rejects_an_indefinite_matrix() {
        let mut a = example(10, 2);
        a.add(5, 5, -10.0);
        assert!(matches!(a.cholesky(), Err(BandedError::NonPositivePivot { index: 5, .. })));
    }

    #[test]
    fn a_flushed_multiplier_cannot_hide_a_negative_eigenvalue() {
        // A = [[d, e], [e, c]] with e / d below FLUSH = 2^-500: the multiplier
        // is stored as 0, so the floating-point factors show two positive
        // pivots while det A = d c - e^2 < 0 (exact in rationals below).
        // Each case is built so that only one flush term of the verified
        // bounds stands between these factors and a false answer; removing
        // either term fails its case (checked by zeroing each).
        let q = |x: f64| exact::Rational::from_float(x).unwrap();
        let matrix = |d: f64, e: f64, c: f64| {
            assert!(q(d) * q(c) - q(e) * q(e) < exact::Rational::from(0), "A is indefinite");
            let mut a = SymBanded::zeros(2, 1);
            a.add(0, 0, d);
            a.add(1, 0, e);
            a.add(1, 1, c);
            let (l, dg) = a.ldl().expect("nonzero pivots");
            assert_eq!(l[2 + 1], 0.0, "the multiplier is flushed");
            assert!(dg.iter().all(|d| *d > 0.0), "the flushed factors show no negative pivot");
            a
        };
        // The inertia test: d = 2^1016, e = 2^515 (e / d = 2^-501), c =
        // 2^13 < e^2 / d = 2^14. P = L |D| L^T = diag(2^1016, 2^13), whose
        // own Cholesky (flush term 4 FLUSH max r_kk = 2^10 < c) proves it
        // definite: only the term (2b + 2) FLUSH max |d_k| = 2^518 of
        // `verified_inertia_within_rows` refuses the false (2, 0).
        let a = matrix(pow2(1016), pow2(515), pow2(13));
        for radius in [0.0, 1.0] {
            assert_ne!(a.verified_inertia_within(radius), Some((2, 0)), "radius {radius}");
        }
        // The Cholesky: d = 1, e = 2^-501, c = 2^-1003 < e^2 = 2^-1002,
        // with first shares (2^-40, 2^-1040) that cover every rounding
        // of the flushed factor (gamma c, about 2^-1054, and the underflow
        // share, about 2^-1015) but not the flush term 4 FLUSH = 2^-498 of
        // `shifted_cholesky_rows`. Without that term this attempt is
        // accepted; with it, the fallback's shares from |A| (2 gamma e,
        // about 2^-551 > c) end the factorisation at row 2. The loop after
        // it tries the public entry points, which refuse A for other
        // reasons too (the radius, or shares from |A| above c).
        let a = matrix(1.0, pow2(-501), pow2(-1003));
        assert!(!a.verified_positive_definite_above_from(&[0.0, 0.0], Some(&[pow2(-40), pow2(-1040)])));
        for radius in [0.0, 1e-300] {
            assert_ne!(a.verified_inertia_within(radius), Some((2, 0)), "radius {radius}");
            assert!(!a.verified_positive_definite_within(radius), "radius {radius}");
            assert!(!a.verified_positive_definite_above(&[radius, radius]), "radius {radius}");
        }
    }

    #[test]
    fn multipliers_below_the_flush_threshold_are_zero_and_the_inertia_still_proved() {
        // An indefinite banded matrix whose factor decays below 2^-1022
        // within the band: diagonal +-1 (alternating in pairs), first
        // off-diagonal 2^-300, second 2^-540. The multipliers of size
        // 2^-540 and the products of two 2^-300 ones (2^-600) are below
        // FLUSH = 2^-500: they are stored as exact zeros, so no subnormal
        // number is left in L. The eigenvalues are within 2^-299 of the
        // diagonal (Gershgorin), so the inertia is (n/2, n/2), proved with
        // any radius below 1 - 2^-298 and not with 1.01.
        let n = 40;
        let mut a = SymBanded::zeros(n, 2);
        for i in 0..n {
            a.add(i, i, if (i / 2) % 2 == 0 { 1.0 } else { -1.0 });
            if i >= 1 {
                a.add(i, i - 1, pow2(-300));
            }
            if i >= 2 {
                a.add(i, i - 2, pow2(-540));
            }
        }
        let (l, dg) = a.ldl().expect("nonzero pivots");
        assert!(l.iter().all(|x| *x == 0.0 || x.abs() >= f64::MIN_POSITIVE), "a subnormal entry in L");
        assert!((2..n).all(|i| l[i * 3 + 2] == 0.0), "the second band's multipliers are flushed");
        assert!((1..n).all(|i| l[i * 3 + 1].abs() == pow2(-300)), "the first band's are kept (2^-300 / +-1)");
        assert_eq!(dg.iter().filter(|d| **d > 0.0).count(), n / 2);
        assert_eq!(a.verified_inertia_within(0.9), Some((n / 2, n / 2)));
        assert_eq!(a.verified_inertia_within(1.01), None);
        // the same for the verified Cholesky: diag 1 and 2, the same bands
        let mut p = SymBanded::zeros(n, 2);
        for i in 0..n {
            p.add(i, i, 1.0 + (i % 2) as f64);
            if i >= 1 {
                p.add(i, i - 1, pow2(-300));
            }
            if i >= 2 {
                p.add(i, i - 2, pow2(-540));
            }
        }
        assert!(p.verified_positive_definite_within(0.99));
        assert!(!p.verified_positive_definite_within(1.01));
    }

    #[test]
    fn verified_test_brackets_the_smallest_eigenvalue() {
        // The smallest eigenvalue by nalgebra's dense symmetric eigensolver
        // (independent of the Cholesky test): a radius 1e-6 below it is
        // proved, one 1e-6 above it is not, for several sizes and bands.
        for (n, b) in [(10, 2), (200, 5), (1000, 26)] {
            let mut a = example(n, b);
            let lmin = a.to_dense().symmetric_eigenvalues().min();
            // shift so that lambda_min is 1e-3: a near-singular case
            for i in 0..n {
                a.add(i, i, 1e-3 - lmin);
            }
            assert!(a.verified_positive_definite_within(1e-3 - 1e-6), "n {n} b {b}");
            assert!(!a.verified_positive_definite_within(1e-3 + 1e-6), "n {n} b {b}");
        }
        let mut a = example(10, 2);
        a.add(3, 3, f64::NAN);
        assert!(!a.verified_positive_definite_within(0.0));
    }

    /// A random symmetric matrix of bandwidth `b`, indefinite (diagonal of
    /// random sign, magnitude 2 to 4; off-diagonal within `0.5/b`), every
    /// entry multiplied by `2^e`.
    fn random_indefinite(rng: &mut impl rand::Rng, n: usize, b: usize, e: i32) -> SymBanded {
        let mut a = SymBanded::zeros(n, b);
        let f = 2f64.powi(e / 2) * 2f64.powi(e - e / 2); // 2^e, exact also when subnormal
        for i in 0..n {
            let d = if rng.random::<bool>() { 1.0 } else { -1.0 } * rng.random_range(2.0..4.0);
            a.add(i, i, d * f);
            for j in i.saturating_sub(b)..i {
                a.add(i, j, rng.random_range(-0.5..0.5) / b as f64 * f);
            }
        }
        a
    }

    #[test]
    fn the_factors_are_within_the_a_priori_bounds_exactly() {
        // The bounds `verified_inertia_within` assumes, checked in exact
        // rational arithmetic (the `exact` crate): entrywise on the band,
        // |A - L D L^T| and |fl(L |D| L^T) - L |D| L^T| are at most
        // gamma_{b+2} |L| |D| |L^T| plus 2^-1074 (b + 1 + max row sum of |L|
        // + max |D|), gamma_m = m u / (1 - m u) exactly. Scales: ordinary,
        // large (2^900), and subnormal (2^-1066: the pivots and the products
        // `l d` underflow, so the underflow term is what is tested).
        use exact::Rational;
        use rand::SeedableRng;
        let mut rng = rand::rngs::StdRng::seed_from_u64(27);
        let q = |x: f64| Rational::from_float(x).unwrap();
        let mut underflowed = false;
        for (n, b, e) in [(12, 1, 0), (15, 3, 0), (14, 5, 0), (12, 3, 900), (12, 2, -1066), (14, 4, -1066)] {
            for _ in 0..4 {
                let a = random_indefinite(&mut rng, n, b, e);
                let (l, dg) = a.ldl().unwrap_or_else(|| panic!("nonzero pivots: n {n} b {b} e {e}"));
                let p = SymBanded::abs_ldl(&l, &dg, b);
                let b1 = b + 1;
                let lq = |i: usize, k: usize| if i - k <= b { q(l[i * b1 + (i - k)]) } else { Rational::from(0) };
                let max_lrow =
                    (0..n).map(|i| (0..=b.min(i)).map(|d| l[i * b1 + d].abs()).sum::<f64>()).fold(0.0, f64::max);
                let max_d = dg.iter().fold(0.0f64, |m, d| m.max(d.abs()));
                // the exact slack, from the computed (upward-rounded) sums
                let slack = q(5e-324) * q(((b + 1) as f64 + max_lrow + max_d) * 1.01);
                let m = (b + 2) as i64;
                let gamma = Rational::new(m.into(), ((1i64 << 53) - m).into());
                underflowed |= dg.iter().any(|d| d.abs() < f64::MIN_POSITIVE);
                for i in 0..n {
                    for j in i.saturating_sub(b)..=i {
                        let (mut ldl, mut labs, mut pabs) = (Rational::from(0), Rational::from(0), Rational::from(0));
                        for k in i.saturating_sub(b)..=j {
                            let t = lq(i, k) * q(dg[k]) * lq(j, k);
                            labs += t.abs();
                            ldl += &t;
                            pabs += lq(i, k) * q(dg[k].abs()) * lq(j, k);
                        }
                        let bound = &gamma * &labs + &slack;
                        let x = (q(a.get(i, j)) - &ldl).abs();
                        assert!(x <= bound, "A - LDL^T: n {n} b {b} e {e} ({i}, {j})");
                        let y = (q(p.get(i, j)) - &pabs).abs();
                        assert!(y <= bound, "L|D|L^T: n {n} b {b} e {e} ({i}, {j})");
                    }
                }
            }
        }
        assert!(underflowed, "the subnormal cases reach subnormal pivots");
    }

    #[test]
    fn verified_inertia_is_sound_and_sharp_against_dense_eigenvalues() {
        // nalgebra's dense eigenvalues (independent of the factorisation):
        // with mu the smallest |eigenvalue|, a radius mu/2 proves the true
        // inertia, and a radius just above mu proves nothing (some A + E
        // with ||E|| = mu is singular). Also rows and columns scaled by
        // random powers of two (a congruence: same inertia; soundness only,
        // against the scaled matrix's own eigenvalues).
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        for (n, b) in [(10, 1), (60, 4), (300, 12), (500, 30)] {
            for scaled in [false, true] {
                let mut a = random_indefinite(&mut rng, n, b, 0);
                if scaled {
                    let f: Vec<f64> = (0..n).map(|_| 2f64.powi(rng.random_range(-20..=20))).collect();
                    for i in 0..n {
                        for j in i.saturating_sub(b)..=i {
                            let v = a.get(i, j) * (f[i] * f[j] - 1.0);
                            a.add(i, j, v);
                        }
                    }
                }
                let eig = a.to_dense().symmetric_eigenvalues();
                let mu = eig.iter().fold(f64::INFINITY, |m, x| m.min(x.abs()));
                let pos = eig.iter().filter(|x| **x > 0.0).count();
                assert_eq!(a.verified_inertia_within(mu * (1.0 + 1e-6) + 1e-300), None, "n {n} b {b} scaled {scaled}");
                if !scaled {
                    assert_eq!(a.verified_inertia_within(0.5 * mu), Some((pos, n - pos)), "n {n} b {b}");
                }
            }
        }
    }

    #[test]
    fn row_by_row_bounds_are_sound_and_sharp_against_dense_eigenvalues() {
        // Row weights w_i > 0 (spread over 2^-20..2^20) and t* the smallest
        // |eigenvalue| of W^-1/2 A W^-1/2 (nalgebra, dense): every A + E with
        // |x^T E x| <= t sum w_i x_i^2 keeps A's inertia for t < t*, and
        // A ± t diag(w) is singular for some t <= t* (the eigenvalue of the
        // scaled matrix nearest 0 moves to 0 along ±diag(w)). So radii
        // t* w / 2 prove the inertia, and radii t* w (1 + 1e-6) prove
        // nothing. The same for the definite test: A ≻ t diag(w) iff t <
        // lambda_min(W^-1/2 A W^-1/2).
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(12);
        for (n, b) in [(10, 1), (60, 4), (300, 12)] {
            let w: Vec<f64> = (0..n).map(|_| 2f64.powf(rng.random_range(-20.0..20.0))).collect();
            let scaled = |a: &SymBanded| {
                let d = a.to_dense();
                nalgebra::DMatrix::from_fn(n, n, |i, j| d[(i, j)] / (w[i] * w[j]).sqrt())
            };
            let a = random_indefinite(&mut rng, n, b, 0);
            let eig = scaled(&a).symmetric_eigenvalues();
            let t = eig.iter().fold(f64::INFINITY, |m, x| m.min(x.abs()));
            let pos = eig.iter().filter(|x| **x > 0.0).count();
            let radii = |f: f64| w.iter().map(|wi| wi * t * f).collect::<Vec<f64>>();
            assert_eq!(a.verified_inertia_within_rows(&radii(0.5)), Some((pos, n - pos)), "n {n} b {b}");
            assert_eq!(a.verified_inertia_within_rows(&radii(1.0 + 1e-6)), None, "n {n} b {b}");
            // definite: A = B B^T-like, its lambda_min in the w metric
            let mut spd = SymBanded::zeros(n, b);
            for i in 0..n {
                for j in i.saturating_sub(b)..=i {
                    let v = if i == j { 2.0 * b as f64 + 1.0 } else { rng.random_range(-1.0..1.0) };
                    spd.add(i, j, v * (w[i] * w[j]).sqrt());
                }
            }
            let lmin = scaled(&spd).symmetric_eigenvalues().min();
            assert!(lmin > 0.0);
            let f = |x: f64| w.iter().map(|wi| wi * lmin * x).collect::<Vec<f64>>();
            assert!(spd.verified_positive_definite_above(&f(0.5)), "n {n} b {b}");
            assert!(spd.verified_positive_definite_above(&f(1.0 - 1e-6)), "n {n} b {b}");
            assert!(!spd.verified_positive_definite_above(&f(1.0 + 1e-6)), "n {n} b {b}");
        }
    }
}
