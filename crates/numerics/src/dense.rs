//! Dense symmetric eigenproblems by faer, and the completion of a
//! Casimir Hessian by a Schur complement: shared by the Zeitlin model's
//! dense analysis and the large-system pipeline.
//!
//! **The completion.** In an orthonormal frame `T = [Z W]` with `Z` a basis
//! of the level set's tangent space (`ker G^T`) and `W` of the conserved
//! directions, a second variation is `sP = [[Pz, Pzw], [Pzw^T, Pw + K]]`,
//! `K` the free Casimir Hessian, and `sQ = [[Qz, Qzw], [Qzw^T, Qw]]` does
//! not depend on `K` when the noise keeps every conserved quantity. Then:
//!
//! * `P ≻ 0` iff `Pz ≻ 0` and `K ≻ K0 = Pzw^T Pz^-1 Pzw - Pw`;
//! * for `S` above `lambda_max(Qz, Pz)`, `X = S Pz - Qz ≻ 0` and `S P - Q ⪰ 0`
//!   iff `K ⪰ K1 = (Qw + C^T X^-1 C)/S - Pw`, `C = S Pzw - Qzw`;
//! * so `K = K1 + (K0 - K1)_+ + m I` (`m > 0`) makes `P` definite with
//!   `lambda_max(Q, P) <= S`, and the infimum of `lambda_max` over `K` is
//!   `max(0, lambda_max(Qz, Pz))`, approached as `K` grows.

use nalgebra::DMatrix;

fn to_faer(m: &DMatrix<f64>) -> faer::Mat<f64> {
    faer::Mat::<f64>::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)])
}

fn from_faer(m: faer::MatRef<'_, f64>) -> DMatrix<f64> {
    DMatrix::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)])
}

/// The product of two dense matrices by faer.
///
/// ```
/// let a = nalgebra::DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 3.0, 4.0]);
/// assert_eq!(numerics::dense::product(&a, &a), &a * &a);
/// ```
pub fn product(a: &DMatrix<f64>, b: &DMatrix<f64>) -> DMatrix<f64> {
    assert_eq!(a.ncols(), b.nrows(), "dimension mismatch in product");
    from_faer((to_faer(a) * to_faer(b)).as_ref())
}

/// The power of two `s` that brings the largest entry of `m` into `[1, 2)`
/// (1 for a zero matrix; at most `2^1000`, so a largest entry below
/// `2^-1000` lands in `[2^-74, 1)`), or `None` when an entry is not finite.
///
/// Multiplying by a power of two is exact (short of underflow of entries
/// some 1e-308 below the largest, which are negligible beside it), so a
/// spectrum computed for `s m` and divided by `s` is that of `m`. It keeps
/// faer's iterations away from the ends of the exponent range: its real
/// Schur iteration indexed out of bounds on a large-system drift whose
/// entries were near 1e-308 (a fuzzed inertia `1e-308`).
///
/// ```
/// let m = nalgebra::DMatrix::from_row_slice(1, 2, &[3e-300, -1e-310]);
/// let s = numerics::dense::unit_scale(&m).unwrap();
/// assert!((3e-300 * s >= 1.0) && (3e-300 * s < 2.0));
/// assert_eq!(s.log2().fract(), 0.0);
/// assert!(numerics::dense::unit_scale(&(m * f64::NAN)).is_none());
/// ```
pub fn unit_scale(m: &DMatrix<f64>) -> Option<f64> {
    let mut largest = 0.0f64;
    for &x in m.iter() {
        if !x.is_finite() {
            return None;
        }
        largest = largest.max(x.abs());
    }
    if largest == 0.0 {
        return Some(1.0);
    }
    // log2 is within one of the exponent e; correct it on the scaled value,
    // applying 2^-e in two halves so that neither overflows (|e| <= 1075)
    let mut exponent = largest.log2().floor() as i32;
    loop {
        let t = largest * 2f64.powi(-exponent / 2) * 2f64.powi(-exponent + exponent / 2);
        if t >= 2.0 {
            exponent += 1;
        } else if t < 1.0 {
            exponent -= 1;
        } else {
            break;
        }
    }
    // 2^1000 is the largest scale used (2^1074 is not a double): a largest
    // entry below 2^-1000 is brought to at least 2^-74, far from underflow
    Some(2f64.powi(-exponent.max(-1000)))
}

/// The eigenvalues of a square real matrix (complex, in no particular
/// order), or `None` when an entry is not finite or the iteration did not
/// converge. The matrix is first scaled by [`unit_scale`].
///
/// ```
/// // [[0, -2], [2, 0]] times 1e-300: eigenvalues ±2e-300 i
/// let k = nalgebra::DMatrix::from_row_slice(2, 2, &[0.0, -2e-300, 2e-300, 0.0]);
/// let ev = numerics::dense::real_eigenvalues(&k).unwrap();
/// assert!(ev.iter().all(|z| z.re.abs() < 1e-315 && (z.im.abs() / 2e-300 - 1.0).abs() < 1e-15));
/// assert!(numerics::dense::real_eigenvalues(&(k * f64::NAN)).is_none());
/// ```
pub fn real_eigenvalues(k: &DMatrix<f64>) -> Option<Vec<nalgebra::Complex<f64>>> {
    let n = k.nrows();
    if n != k.ncols() {
        return None;
    }
    let s = unit_scale(k)?;
    if n == 0 {
        return Some(vec![]);
    }
    let m = faer::Mat::<f64>::from_fn(n, n, |i, j| k[(i, j)] * s);
    let values = m.eigenvalues().ok()?;
    let values: Vec<_> = values.iter().map(|z| nalgebra::Complex::new(z.re / s, z.im / s)).collect();
    values.iter().all(|z| z.re.is_finite() && z.im.is_finite()).then_some(values)
}

/// The eigenvalues of a symmetric matrix (its lower triangle), ascending;
/// `None` when an entry is not finite or the iteration did not converge.
/// The matrix is first scaled by [`unit_scale`].
///
/// ```
/// let m = nalgebra::DMatrix::from_row_slice(2, 2, &[2.0, 1.0, 1.0, 2.0]);
/// let ev = numerics::dense::symmetric_eigenvalues(&m).unwrap();
/// assert!((ev[0] - 1.0).abs() < 1e-15 && (ev[1] - 3.0).abs() < 1e-15);
/// ```
pub fn symmetric_eigenvalues(m: &DMatrix<f64>) -> Option<Vec<f64>> {
    if m.nrows() != m.ncols() {
        return None;
    }
    let s = unit_scale(m)?;
    if m.nrows() == 0 {
        return Some(vec![]);
    }
    let values = to_faer(&(m * s)).self_adjoint_eigenvalues(faer::Side::Lower).ok()?;
    let values: Vec<f64> = values.iter().map(|x| x / s).collect();
    values.iter().all(|x| x.is_finite()).then_some(values)
}

/// The eigen-decomposition of a symmetric matrix: eigenvalues ascending and
/// orthonormal eigenvectors as columns.
///
/// ```
/// let m = nalgebra::DMatrix::from_row_slice(2, 2, &[2.0, 1.0, 1.0, 2.0]);
/// let (values, v) = numerics::dense::symmetric_eigen(&m).unwrap();
/// let d = nalgebra::DMatrix::from_diagonal(&nalgebra::DVector::from_vec(values));
/// assert!((&v * d * v.transpose() - m).norm() < 1e-14);
/// ```
pub fn symmetric_eigen(m: &DMatrix<f64>) -> Option<(Vec<f64>, DMatrix<f64>)> {
    if m.nrows() != m.ncols() {
        return None;
    }
    let s = unit_scale(m)?;
    if m.nrows() == 0 {
        return Some((vec![], DMatrix::zeros(0, 0)));
    }
    let e = to_faer(&(m * s)).self_adjoint_eigen(faer::Side::Lower).ok()?;
    let values: Vec<f64> = (0..m.nrows()).map(|i| e.S()[i] / s).collect();
    values.iter().all(|x| x.is_finite()).then(|| (values, from_faer(e.U())))
}

/// `L` with `P = L L^T` (faer), or `None` when `P` is not numerically
/// positive definite.
fn cholesky(p: &DMatrix<f64>) -> Option<faer::Mat<f64>> {
    if p.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let llt = to_faer(p).llt(faer::Side::Lower).ok()?;
    Some(llt.L().to_owned())
}

/// `X` with `P X = B`, by the Cholesky factor of `P`.
fn cholesky_solve(l: &faer::Mat<f64>, b: &DMatrix<f64>) -> DMatrix<f64> {
    use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
    let mut x = to_faer(b);
    solve_lower_triangular_in_place(l.as_ref(), x.as_mut(), faer::Par::Seq);
    solve_upper_triangular_in_place(l.transpose(), x.as_mut(), faer::Par::Seq);
    from_faer(x.as_ref())
}

/// `lambda_max(Q, P)` for symmetric `Q` and `P ≻ 0`, by the Cholesky factor
/// of `P` (`C = L^-1 Q L^-T`); `None` when `P` is not numerically positive
/// definite or a value is not finite.
///
/// ```
/// // P = [[2, 1], [1, 2]], Q = [[1, 0], [0, 0]]: det(Q - l P) = 3 l^2 - 2 l, l = 2/3
/// let p = nalgebra::DMatrix::from_row_slice(2, 2, &[2.0, 1.0, 1.0, 2.0]);
/// let q = nalgebra::DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 0.0]);
/// assert!((numerics::dense::largest_generalized(&p, &q).unwrap() - 2.0 / 3.0).abs() < 1e-15);
/// ```
pub fn largest_generalized(p: &DMatrix<f64>, q: &DMatrix<f64>) -> Option<f64> {
    use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
    if p.nrows() == 0 || q.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let l = cholesky(p)?;
    let mut c = to_faer(q);
    solve_lower_triangular_in_place(l.as_ref(), c.as_mut(), faer::Par::Seq);
    let mut ct = c.transpose().to_owned();
    solve_lower_triangular_in_place(l.as_ref(), ct.as_mut(), faer::Par::Seq);
    let c = from_faer(ct.as_ref());
    let c = (&c + c.transpose()) * 0.5;
    symmetric_eigenvalues(&c)?.last().copied()
}

/// `lambda_max / lambda_min` of a symmetric positive definite matrix
/// (infinite when the smallest eigenvalue is not resolved above rounding).
///
/// ```
/// let m = nalgebra::DMatrix::from_row_slice(2, 2, &[4.0, 0.0, 0.0, 1.0]);
/// assert!((numerics::dense::condition_number(&m) - 4.0).abs() < 1e-14);
/// ```
pub fn condition_number(m: &DMatrix<f64>) -> f64 {
    match symmetric_eigenvalues(m) {
        Some(ev) if !ev.is_empty() => {
            let (lo, hi) = (ev[0], ev.iter().fold(0.0f64, |a, x| a.max(x.abs())));
            if lo > hi * 1e-15 {
                hi / lo
            } else {
                f64::INFINITY
            }
        }
        _ => f64::INFINITY,
    }
}

/// The positive part of a symmetric matrix (its negative eigenvalues set to 0).
fn positive_part(m: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let (values, v) = symmetric_eigen(&((m + m.transpose()) * 0.5))?;
    let mut scaled = v.clone();
    for (j, x) in values.iter().enumerate() {
        scaled.column_mut(j).iter_mut().for_each(|e| *e *= x.max(0.0));
    }
    Some(product(&scaled, &v.transpose()))
}

/// The blocks of `sP` (without `K`) and `sQ` in an orthonormal frame `[Z W]`
/// (see the module docs).
#[derive(Clone, Debug)]
pub struct FramePencil {
    /// `Z^T sP Z`.
    pub pz: DMatrix<f64>,
    /// `Z^T sP W`.
    pub pzw: DMatrix<f64>,
    /// `W^T sP W` without `K`.
    pub pw: DMatrix<f64>,
    /// `Z^T sQ Z`.
    pub qz: DMatrix<f64>,
    /// `Z^T sQ W`.
    pub qzw: DMatrix<f64>,
    /// `W^T sQ W`.
    pub qw: DMatrix<f64>,
}

/// A Casimir Hessian built for a target just above the infimum.
#[derive(Clone, Debug, PartialEq)]
pub struct Completion {
    /// `max(0, lambda_max(Qz, Pz))`: the infimum over `K`.
    pub infimum: f64,
    /// The `K` chosen.
    pub k: DMatrix<f64>,
    /// `lambda_max(Q, P)` at that `K` (not floored).
    pub sigma2: f64,
    /// `cond(sP)` at that `K`.
    pub condition_number: f64,
}

impl FramePencil {
    /// The full `sP` at `K`.
    pub fn p_at(&self, k: &DMatrix<f64>) -> DMatrix<f64> {
        let (nz, nw) = (self.pz.nrows(), self.pw.nrows());
        let mut p = DMatrix::zeros(nz + nw, nz + nw);
        p.view_mut((0, 0), (nz, nz)).copy_from(&self.pz);
        p.view_mut((0, nz), (nz, nw)).copy_from(&self.pzw);
        p.view_mut((nz, 0), (nw, nz)).copy_from(&self.pzw.transpose());
        p.view_mut((nz, nz), (nw, nw)).copy_from(&(&self.pw + k));
        p
    }

    /// The full `sQ`.
    pub fn q(&self) -> DMatrix<f64> {
        let (nz, nw) = (self.qz.nrows(), self.qw.nrows());
        let mut q = DMatrix::zeros(nz + nw, nz + nw);
        q.view_mut((0, 0), (nz, nz)).copy_from(&self.qz);
        q.view_mut((0, nz), (nz, nw)).copy_from(&self.qzw);
        q.view_mut((nz, 0), (nw, nz)).copy_from(&self.qzw.transpose());
        q.view_mut((nz, nz), (nw, nw)).copy_from(&self.qw);
        q
    }

    /// Build `K` for targets `S = infimum (1 + delta)`, `delta = 1e-8,
    /// 1e-7, ..., 1e-1` (for a zero infimum, `delta` times the `Sigma^2` of
    /// the reference `K = K0_+ + m I`), the first whose `cond(sP)` is at
    /// most `cond_limit`, else the one with the smallest `Sigma^2`. `m` is
    /// the margin added along the conserved directions. `None` when `Pz`
    /// is not positive definite.
    ///
    /// ```
    /// use nalgebra::DMatrix;
    /// use numerics::dense::FramePencil;
    /// // One tangent and one conserved direction; Q is only along the tangent:
    /// // the infimum is Qz/Pz = 0.5, approached as K grows.
    /// let m = |x: f64| DMatrix::from_element(1, 1, x);
    /// let f = FramePencil { pz: m(2.0), pzw: m(1.0), pw: m(0.0), qz: m(1.0), qzw: m(0.0), qw: m(0.0) };
    /// let c = f.complete(1.0, 1e10).unwrap();
    /// assert!((c.infimum - 0.5).abs() < 1e-15);
    /// assert!(c.sigma2 >= 0.5 && c.sigma2 <= 0.5 * (1.0 + 1e-7), "{}", c.sigma2);
    /// ```
    pub fn complete(&self, margin: f64, cond_limit: f64) -> Option<Completion> {
        let nw = self.pw.nrows();
        let l = cholesky(&self.pz)?;
        let restricted = if self.pz.nrows() == 0 { 0.0 } else { largest_generalized(&self.pz, &self.qz)? };
        let infimum = restricted.max(0.0);
        let k0 = self.pzw.transpose() * cholesky_solve(&l, &self.pzw) - &self.pw;
        let margin_id = DMatrix::identity(nw, nw) * margin;
        let q = self.q();
        let evaluate = |k: DMatrix<f64>| -> Option<Completion> {
            let k = (&k + k.transpose()) * 0.5;
            let p = self.p_at(&k);
            let sigma2 = largest_generalized(&p, &q)?;
            Some(Completion { infimum, condition_number: condition_number(&p), sigma2, k })
        };
        // The reference choice K = (K0)_+ + m I: the fallback, and the scale
        // of the targets when the infimum is 0 (formed only when needed).
        let reference = || evaluate(positive_part(&k0)? + &margin_id);
        let k_for = |s: f64| -> Option<DMatrix<f64>> {
            let x = &self.pz * s - &self.qz;
            let c = &self.pzw * s - &self.qzw;
            let xc = cholesky_solve(&cholesky(&x)?, &c);
            let k1 = (&self.qw + c.transpose() * xc) / s - &self.pw;
            Some(&k1 + positive_part(&(&k0 - &k1))? + &margin_id)
        };
        let mut fallback: Option<Completion> = None;
        let scale = if infimum > 0.0 {
            infimum
        } else {
            let r = reference()?;
            let s = r.sigma2.max(0.0);
            if s <= 0.0 {
                // Q ⪯ 0 at the reference: Sigma^2 = 0 is attained there.
                return Some(r);
            }
            fallback = Some(r);
            s
        };
        let mut best: Option<Completion> = None;
        for delta in [1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1] {
            let s = if infimum > 0.0 { infimum * (1.0 + delta) } else { delta * scale };
            let Some(c) = k_for(s).and_then(&evaluate) else { continue };
            let conditioned = c.condition_number <= cond_limit;
            if best.as_ref().is_none_or(|b| c.sigma2 < b.sigma2) {
                best = Some(c);
            }
            if conditioned {
                return best;
            }
        }
        // No target was conditioned: the best of them, or the reference.
        let fallback = match fallback {
            Some(f) => Some(f),
            None => reference(),
        };
        match (best, fallback) {
            (Some(b), Some(f)) => Some(if b.sigma2 <= f.sigma2 { b } else { f }),
            (b, f) => b.or(f),
        }
    }
}

/// `lambda_max(Q, P)` with a `P`-normalised eigenvector (for `P ≻ 0`), or,
/// when `P` is not numerically positive definite, `Err` with a unit
/// eigenvector of `lambda_min(P)` (the direction of a feasibility cut).
///
/// ```
/// use nalgebra::DMatrix;
/// let p = DMatrix::from_row_slice(2, 2, &[2.0, 0.0, 0.0, 1.0]);
/// let q = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 3.0]);
/// let (l, v) = numerics::dense::top_generalized(&p, &q).unwrap();
/// assert!((l - 3.0).abs() < 1e-14 && (v[1].abs() - 1.0).abs() < 1e-14);
/// let u = numerics::dense::top_generalized(&(-p), &q).unwrap_err();
/// assert!((u.norm() - 1.0).abs() < 1e-14);
/// ```
pub fn top_generalized(
    p: &DMatrix<f64>,
    q: &DMatrix<f64>,
) -> Result<(f64, nalgebra::DVector<f64>), nalgebra::DVector<f64>> {
    use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
    let n = p.nrows();
    let fallback = || {
        symmetric_eigen(&((p + p.transpose()) * 0.5))
            .and_then(|(_, v)| (n > 0).then(|| v.column(0).into_owned()))
            .unwrap_or_else(|| nalgebra::DVector::zeros(n))
    };
    let Some(l) = (n > 0).then(|| cholesky(p)).flatten() else { return Err(fallback()) };
    let mut c = to_faer(q);
    solve_lower_triangular_in_place(l.as_ref(), c.as_mut(), faer::Par::Seq);
    let mut ct = c.transpose().to_owned();
    solve_lower_triangular_in_place(l.as_ref(), ct.as_mut(), faer::Par::Seq);
    let c = from_faer(ct.as_ref());
    let Some((values, w)) = symmetric_eigen(&((&c + c.transpose()) * 0.5)) else { return Err(fallback()) };
    let top = values[n - 1];
    let mut v = faer::Mat::<f64>::from_fn(n, 1, |i, _| w[(i, n - 1)]);
    solve_upper_triangular_in_place(l.transpose(), v.as_mut(), faer::Par::Seq);
    Ok((top, nalgebra::DVector::from_fn(n, |i, _| v[(i, 0)])))
}
