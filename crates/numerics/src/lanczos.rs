//! The largest eigenvalue of a symmetric operator given only by its action,
//! by the Lanczos process with full reorthogonalisation.
//!
//! Why not a library solver. faer 0.24 has a matrix-free one,
//! `faer::matrix_free::eigen::partial_self_adjoint_eigen` over a `LinOp`
//! (thick-restart Lanczos), and it was considered (faer-0.24.4,
//! `src/operator/eigen/mod.rs` and `src/linalg/evd/self_adjoint_eigen`):
//!
//! * it returns the eigenvalues of largest *magnitude*; `Sigma^2` is the
//!   largest *algebraic* eigenvalue, often beside a larger negative one (a
//!   shift `A + sI` would need a first solve for `s` and a second one);
//! * it solves standard problems only; the walls' pencil `(Q, V)` is worked
//!   in the `V` inner product with a banded solve (`largest_generalized_eigenvalue`);
//! * it panics for `n <= 64` (its Krylov space is at least 64), and the
//!   convergence tables start at `ny = 64`;
//! * its stopping test is absolute and it reports no residual, while the
//!   certificates state the Ritz residual relative to the spectrum's scale;
//! * its operator must be `Sync`, and the walls' operator reuses scratch in
//!   a `RefCell`.
//!
//! So this is the plain Lanczos process with full reorthogonalisation (at
//! most a few hundred vectors for sizes of a few thousand, robust without
//! restarts), applying banded operators on both boundaries (a dense
//! eigensolver would need `V` and `Q` formed densely). The top Ritz pair of
//! the small tridiagonal matrix comes from bisection and inverse iteration
//! on the tridiagonal itself (`top_ritz`: nalgebra's symmetric eigensolver
//! first reduces a dense matrix to tridiagonal form, `O(steps^3)` at every
//! look).

/// The converged top Ritz pair's value and its residual.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ritz {
    /// The largest Ritz value.
    pub value: f64,
    /// `||T v - value v||` for its Ritz vector `v` (unit): by the
    /// Bauer–Fike/Weyl argument for symmetric `T`, some eigenvalue of `T`
    /// lies within this distance of `value`.
    pub residual: f64,
    /// Lanczos steps taken.
    pub iterations: usize,
    /// Largest magnitude among the Ritz values (a scale for `T`).
    pub scale: f64,
}

impl Ritz {
    /// The result of a breakdown after `steps` steps: a value of NaN, which
    /// callers must not floor (`NaN.max(0.0)` is `0`).
    fn breakdown(steps: usize) -> Ritz {
        Ritz { value: f64::NAN, residual: f64::INFINITY, iterations: steps, scale: f64::NAN }
    }
}

/// Largest eigenvalue of the symmetric `n x n` operator `apply` (`y = T x`),
/// to relative accuracy `tol` (with respect to the spectrum's scale).
///
/// A numerical breakdown (a non-finite number in the recurrence, which
/// overflowing data produce) gives a Ritz value of NaN: callers must not
/// floor it (`NaN.max(0.0)` is `0`).
///
/// ```
/// use numerics::lanczos::largest_eigenvalue;
/// // T = diag(1..=100): largest eigenvalue 100
/// let r = largest_eigenvalue(100, |x, y| for i in 0..100 { y[i] = (i + 1) as f64 * x[i] }, 1e-12, 200);
/// assert!((r.value - 100.0).abs() < 1e-9);
/// ```
pub fn largest_eigenvalue(n: usize, mut apply: impl FnMut(&[f64], &mut [f64]), tol: f64, max_iter: usize) -> Ritz {
    assert!(n > 0);
    let m_max = max_iter.min(n).max(1);
    // A fixed start vector with components in every direction that a smooth
    // or a grid-scale eigenvector could have (deterministic: certificates
    // must be reproducible).
    let mut v: Vec<f64> = (0..n)
        .map(|i| 1.0 + 0.5 * ((i as f64) * 0.7548776662).sin() + 0.25 * ((i * i) as f64 * 0.5698402910).cos())
        .collect();
    normalise(&mut v);
    let mut basis: Vec<Vec<f64>> = Vec::with_capacity(m_max);
    let mut alpha: Vec<f64> = Vec::with_capacity(m_max);
    let mut beta: Vec<f64> = Vec::with_capacity(m_max);
    let mut w = vec![0.0; n];
    let mut last = Ritz::breakdown(0);
    for j in 0..m_max {
        apply(&v, &mut w);
        let a = dot(&v, &w);
        if !a.is_finite() {
            return Ritz::breakdown(j);
        }
        basis.push(v.clone());
        alpha.push(a);
        // full reorthogonalisation, twice ("twice is enough", Parlett)
        for _ in 0..2 {
            for q in &basis {
                let c = dot(q, &w);
                axpy(-c, q, &mut w);
            }
        }
        let b = norm(&w);
        let steps = j + 1;
        if !b.is_finite() {
            return Ritz::breakdown(steps);
        }
        let check = check_now(steps, m_max) || b <= 1e-300;
        if check {
            let (_, theta, residual, scale) = top_ritz(&alpha, &beta, b);
            last = Ritz { value: theta, residual, iterations: steps, scale };
            if residual <= tol * scale.max(f64::MIN_POSITIVE) || b <= 1e-14 * scale.max(f64::MIN_POSITIVE) || steps == n
            {
                return last;
            }
        }
        if b == 0.0 {
            break;
        }
        beta.push(b);
        v = w.iter().map(|x| x / b).collect();
    }
    last
}

/// Largest eigenvalue of the symmetric-definite pencil `(Q, V)` by Lanczos
/// on `V^-1 Q` in the `V` inner product: `apply_q`, `apply_v` give `Q x`,
/// `V x`, and `solve_v` solves `V x = b` (it may be inexact: the reported
/// value is the Rayleigh quotient `x^T Q x / x^T V x` of the final Ritz
/// vector, computed with `apply_q` and `apply_v` directly, so it is a lower
/// estimate of the largest eigenvalue up to rounding in those products).
/// A numerical breakdown gives a value of NaN, as in [`largest_eigenvalue`].
///
/// ```
/// use numerics::lanczos::largest_generalized_eigenvalue;
/// // Q = diag(1..=50), V = diag(2): eigenvalues i/2, largest 25
/// let r = largest_generalized_eigenvalue(
///     50,
///     |x, y| for i in 0..50 { y[i] = (i + 1) as f64 * x[i] },
///     |x, y| for i in 0..50 { y[i] = 2.0 * x[i] },
///     |b, x| for i in 0..50 { x[i] = b[i] / 2.0 },
///     1e-12,
///     100,
/// );
/// assert!((r.value - 25.0).abs() < 1e-9);
/// ```
pub fn largest_generalized_eigenvalue(
    n: usize,
    mut apply_q: impl FnMut(&[f64], &mut [f64]),
    mut apply_v: impl FnMut(&[f64], &mut [f64]),
    mut solve_v: impl FnMut(&[f64], &mut [f64]),
    tol: f64,
    max_iter: usize,
) -> Ritz {
    assert!(n > 0);
    let m_max = max_iter.min(n).max(1);
    let mut q: Vec<f64> = (0..n)
        .map(|i| 1.0 + 0.5 * ((i as f64) * 0.7548776662).sin() + 0.25 * ((i * i) as f64 * 0.5698402910).cos())
        .collect();
    let mut vq = vec![0.0; n];
    apply_v(&q, &mut vq);
    let nrm = dot(&q, &vq).sqrt();
    if !(nrm.is_finite() && nrm > 0.0) {
        return Ritz::breakdown(0);
    }
    q.iter_mut().for_each(|x| *x /= nrm);
    vq.iter_mut().for_each(|x| *x /= nrm);
    let mut basis: Vec<Vec<f64>> = vec![];
    let mut vbasis: Vec<Vec<f64>> = vec![];
    let mut alpha: Vec<f64> = vec![];
    let mut beta: Vec<f64> = vec![];
    let (mut qx, mut p, mut vp) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut best: Option<(Vec<f64>, f64, f64, usize, f64)> = None; // (coefficients, theta, residual, steps, scale)
    for j in 0..m_max {
        apply_q(&q, &mut qx);
        let a = dot(&q, &qx);
        if !a.is_finite() {
            return Ritz::breakdown(j);
        }
        basis.push(q.clone());
        vbasis.push(vq.clone());
        alpha.push(a);
        solve_v(&qx, &mut p);
        // The three-term recurrence first (`p - alpha q_j - beta q_{j-1}`),
        // then V-orthogonalisation against the whole basis, which now removes
        // only what rounding left, and a second time only where the first
        // removed more than half of `p`'s squared V-norm (Daniel, Gragg,
        // Kaufman and Stewart's test; "twice is enough", Parlett). Always
        // running both passes would, with hundreds of steps (the high
        // x-modes of a fine grid), be two thirds of the run, reading the
        // whole basis twice a step.
        axpy(-a, &basis[j], &mut p);
        if j > 0 {
            axpy(-beta[j - 1], &basis[j - 1], &mut p);
        }
        let mut removed = 0.0;
        for (b, vb) in basis.iter().zip(&vbasis) {
            let c = dot(vb, &p);
            axpy(-c, b, &mut p);
            removed += c * c;
        }
        apply_v(&p, &mut vp);
        let mut b2 = dot(&p, &vp);
        if removed > b2 || removed.is_nan() || b2.is_nan() {
            for (b, vb) in basis.iter().zip(&vbasis) {
                let c = dot(vb, &p);
                axpy(-c, b, &mut p);
            }
            apply_v(&p, &mut vp);
            b2 = dot(&p, &vp);
        }
        if b2.is_nan() {
            // a NaN from the solve is a breakdown, not convergence (b = 0)
            return Ritz::breakdown(j + 1);
        }
        let b = b2.max(0.0).sqrt();
        let steps = j + 1;
        if !b.is_finite() {
            return Ritz::breakdown(steps);
        }
        if check_now(steps, m_max) || b <= 1e-300 {
            let (coefficients, theta, residual, scale) = top_ritz(&alpha, &beta, b);
            best = Some((coefficients, theta, residual, steps, scale));
            if residual <= tol * scale.max(f64::MIN_POSITIVE) || b <= 1e-14 * scale.max(f64::MIN_POSITIVE) || steps == n
            {
                break;
            }
        }
        if b == 0.0 || !b.is_finite() {
            break;
        }
        beta.push(b);
        q = p.iter().map(|x| x / b).collect();
        vq = vp.iter().map(|x| x / b).collect();
    }
    // The last step always checks (steps == m_max), and every early exit
    // above returned: `best` is set unless the recurrence broke down.
    let Some((coefficients, theta, residual, steps, scale)) = best else { return Ritz::breakdown(0) };
    // The Ritz vector and its Rayleigh quotient, from Q and V directly.
    let mut x = vec![0.0; n];
    for (c, b) in coefficients.iter().zip(&basis) {
        axpy(*c, b, &mut x);
    }
    apply_q(&x, &mut qx);
    apply_v(&x, &mut vp);
    let (num, den) = (dot(&x, &qx), dot(&x, &vp));
    let value = if den > 0.0 { num / den } else { theta };
    Ritz { value, residual, iterations: steps, scale }
}

/// Whether to look at the Ritz values after `steps` steps: every step from
/// the fourth to the 31st, then every eighth, and at the last. Each look is
/// the top eigenpair of the tridiagonal `T` ([`top_ritz`]: bisection and
/// inverse iteration, `O(steps)` per Sturm count), cheap beside a step,
/// and the walls' modes converge within 7 to 20 steps, so looking only
/// every eighth step would run up to seven steps too many.
/// Measured at ny = 1024 (`fluid_mode`, mode 1 of `bench/cubic-walls.json`):
/// 9 steps instead of 16 (docs/fluids.md §5).
fn check_now(steps: usize, m_max: usize) -> bool {
    steps == m_max || (steps >= 4 && (steps < 32 || steps % 8 == 0))
}

/// Solve `A x = b` for symmetric positive definite `A` by conjugate
/// gradients with a preconditioner `apply_pinv` (`z = P^-1 r`), to relative
/// residual `tol`; returns the number of iterations, or `None` if a
/// direction of non-positive curvature shows `A` is not positive definite.
pub fn conjugate_gradients(
    b: &[f64],
    x: &mut [f64],
    mut apply_a: impl FnMut(&[f64], &mut [f64]),
    mut apply_pinv: impl FnMut(&[f64], &mut [f64]),
    tol: f64,
    max_iter: usize,
) -> Option<usize> {
    let n = b.len();
    let bnorm = norm(b);
    if bnorm == 0.0 {
        x.iter_mut().for_each(|v| *v = 0.0);
        return Some(0);
    }
    apply_pinv(b, x); // start from the preconditioner's answer
    let mut ax = vec![0.0; n];
    apply_a(x, &mut ax);
    let mut r: Vec<f64> = b.iter().zip(&ax).map(|(b, a)| b - a).collect();
    // The residual is tested before the preconditioner is applied to it:
    // the V-solves take few iterations (their preconditioner is V's inverse
    // up to rounding; counted at tol = 1e-15: 2 on the walls modes of
    // `bench/cubic-walls.json` and `channel-sin-walls` at ny = 1024 and
    // 4096, 1 or 0 on periodic ones), and no preconditioned residual is
    // computed after the last step, where it would go unused (a third of
    // the preconditioner's work; the iterate is the same).
    if norm(&r) <= tol * bnorm {
        return Some(0);
    }
    let mut z = vec![0.0; n];
    apply_pinv(&r, &mut z);
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut ap = vec![0.0; n];
    for it in 0..max_iter {
        apply_a(&p, &mut ap);
        let pap = dot(&p, &ap);
        if pap.is_nan() || pap <= 0.0 {
            return None;
        }
        let step = rz / pap;
        axpy(step, &p, x);
        axpy(-step, &ap, &mut r);
        if norm(&r) <= tol * bnorm {
            return Some(it + 1);
        }
        apply_pinv(&r, &mut z);
        let rz_new = dot(&r, &z);
        let ratio = rz_new / rz;
        rz = rz_new;
        for (pi, zi) in p.iter_mut().zip(&z) {
            *pi = zi + ratio * *pi;
        }
    }
    Some(max_iter)
}

/// The top eigenpair of the Lanczos tridiagonal matrix (diagonal `alpha`,
/// off-diagonal `beta`, one shorter) as `(eigenvector, theta, residual,
/// scale)`: the residual `|b s_last|` of the Ritz pair, with `b` the next
/// off-diagonal, and the largest Ritz value in magnitude.
///
/// Written here rather than taken from nalgebra: its `SymmetricEigen`
/// takes a dense matrix, reduces it to tridiagonal form by Householder
/// reflections (`O(steps^3)`, though this one is tridiagonal already) and
/// returns every eigenpair. The high x-modes of a fine grid take hundreds
/// of Lanczos steps, and there it would be a third of the run (`perf`,
/// mode 2048 of the Kolmogorov spec at ny = 4096). Here the two
/// extreme eigenvalues come from bisection on the Sturm count
/// ([`sturm_below`], to a few ulps of the spectrum's scale) and the top
/// eigenvector from inverse iteration with a pivoted tridiagonal solve
/// ([`solve_shifted`]): `O(steps)` each. Like any eigensolver here, it
/// only steers the iteration: the reported value is the Rayleigh quotient
/// of the Ritz vector, and every bound is proved by the verified checks.
fn top_ritz(alpha: &[f64], beta: &[f64], b: f64) -> (Vec<f64>, f64, f64, f64) {
    let steps = alpha.len();
    let nan = (vec![f64::NAN; steps], f64::NAN, f64::INFINITY, f64::NAN);
    if steps == 0 || beta.len() + 1 != steps || alpha.iter().chain(beta).any(|x| !x.is_finite()) || !b.is_finite() {
        return nan;
    }
    if steps == 1 {
        // T = [alpha_0]: its eigenvector is e_1 (and T = 0, the pencil of
        // a noise-free or constant-noise mode, must give 0, not a solve
        // with a zero pivot)
        return (vec![1.0], alpha[0], b.abs(), alpha[0].abs());
    }
    // Scaled by a power of two to entries of order one (exact, and the
    // results scale back exactly): the Sturm count squares the
    // off-diagonal, which underflows for a spectrum near 1e-160. The
    // eigenvector does not change.
    let top = alpha.iter().chain(beta).fold(0.0f64, |m, x| m.max(x.abs()));
    if top > 0.0 && !(2f64.powi(-200)..=2f64.powi(200)).contains(&top) {
        let r = crate::scaling::Rescaling::nearest(top);
        let (down, up) = (r.down(), r.up());
        let a: Vec<f64> = alpha.iter().map(|x| x * down).collect();
        let c: Vec<f64> = beta.iter().map(|x| x * down).collect();
        let (v, theta, residual, scale) = top_ritz(&a, &c, b);
        return (v, theta * up, residual, scale * up);
    }
    // Gershgorin's interval holds the spectrum.
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..steps {
        let r = if i > 0 { beta[i - 1].abs() } else { 0.0 } + if i + 1 < steps { beta[i].abs() } else { 0.0 };
        lo = lo.min(alpha[i] - r);
        hi = hi.max(alpha[i] + r);
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return nan;
    }
    // LAPACK's dstebz: pivots below this are replaced by it
    let pivmin = f64::MIN_POSITIVE * beta.iter().fold(1.0f64, |m, x| m.max(x * x));
    // Bisection stops at a few ulps of the spectrum's scale (Gershgorin's
    // bound on it), not of the interval's ends: near a zero eigenvalue the
    // latter would take up to about a thousand more Sturm sweeps for an
    // accuracy the Ritz value does not need
    let width = 2.0 * f64::EPSILON * lo.abs().max(hi.abs());
    let bisect = |top: bool| -> f64 {
        // top: the largest x with fewer than `steps` eigenvalues below it;
        // else the smallest x with at least one below it
        let (mut a, mut c) = (lo, hi);
        for _ in 0..2100 {
            let mid = 0.5 * a + 0.5 * c;
            if mid <= a || mid >= c || c - a <= width {
                break;
            }
            let below = sturm_below(alpha, beta, mid, pivmin);
            let right = if top { below == steps } else { below >= 1 };
            if right {
                c = mid;
            } else {
                a = mid;
            }
        }
        0.5 * a + 0.5 * c
    };
    let theta = bisect(true);
    let scale = theta.abs().max(bisect(false).abs());
    if scale == 0.0 {
        // T = 0 (every Gershgorin disc is {0}): every vector is an eigenvector
        let mut v = vec![0.0; steps];
        v[steps - 1] = 1.0;
        return (v, 0.0, b.abs(), 0.0);
    }
    // Inverse iteration from a fixed smooth positive vector. It could in
    // principle be orthogonal to the top eigenvector (only e_1 is sure not
    // to be, for an unreduced T); that would only slow the steering, since
    // the value reported is the Rayleigh quotient of the Ritz vector and
    // every bound is proved by the verified checks. Each step multiplies
    // the top component by the gap over theta's error, a few ulps.
    let mut v: Vec<f64> = (0..steps).map(|i| 1.0 + 0.5 * ((i as f64) * 0.7548776662).sin()).collect();
    let tiny = f64::EPSILON * scale.max(f64::MIN_POSITIVE);
    for _ in 0..3 {
        solve_shifted(alpha, beta, theta, tiny, &mut v);
        let mut n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if !n.is_finite() {
            // the squares overflowed (a spectrum below about 1e-139): scale
            // by the largest entry first
            let top = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            if top.is_finite() && top > 0.0 {
                v.iter_mut().for_each(|x| *x /= top);
                n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            }
        }
        if !(n.is_finite() && n > 0.0) {
            return nan;
        }
        v.iter_mut().for_each(|x| *x /= n);
    }
    let residual = (b * v[steps - 1]).abs();
    (v, theta, residual, scale)
}

/// The number of eigenvalues of the symmetric tridiagonal `T` (diagonal
/// `alpha`, off-diagonal `beta`) below `x`: the negative pivots of the
/// `L D L^T` of `T - x I` (Sylvester), a pivot smaller than `pivmin` in
/// magnitude taken as `-pivmin` (LAPACK's dstebz).
fn sturm_below(alpha: &[f64], beta: &[f64], x: f64, pivmin: f64) -> usize {
    let mut count = 0;
    let mut d = 1.0;
    for (i, a) in alpha.iter().enumerate() {
        let coupling = if i == 0 { 0.0 } else { beta[i - 1] * beta[i - 1] / d };
        d = (a - x) - coupling;
        if d.abs() < pivmin || d.is_nan() {
            d = -pivmin;
        }
        count += usize::from(d < 0.0);
    }
    count
}

/// Solve `(T - theta I) y = v` in place, `T` symmetric tridiagonal, by
/// Gaussian elimination with partial pivoting (LAPACK's dgtsv), a zero
/// pivot replaced by `tiny`: the solve of inverse iteration, where
/// `T - theta I` is singular to working precision on purpose.
fn solve_shifted(alpha: &[f64], beta: &[f64], theta: f64, tiny: f64, v: &mut [f64]) {
    let n = alpha.len();
    let mut d: Vec<f64> = alpha.iter().map(|a| a - theta).collect();
    if n == 1 {
        v[0] /= if d[0] == 0.0 { tiny } else { d[0] };
        return;
    }
    let mut dl = beta.to_vec();
    let mut du = beta.to_vec();
    let mut du2 = vec![0.0; n.saturating_sub(2)];
    for i in 0..n - 1 {
        if d[i].abs() >= dl[i].abs() {
            if d[i] == 0.0 {
                d[i] = tiny;
            }
            let fact = dl[i] / d[i];
            d[i + 1] -= fact * du[i];
            v[i + 1] -= fact * v[i];
        } else {
            // rows i and i + 1 interchanged
            let fact = d[i] / dl[i];
            d[i] = dl[i];
            let temp = d[i + 1];
            d[i + 1] = du[i] - fact * temp;
            if i + 2 < n {
                du2[i] = du[i + 1];
                du[i + 1] = -fact * du2[i];
            }
            du[i] = temp;
            let vi = v[i];
            v[i] = v[i + 1];
            v[i + 1] = vi - fact * v[i + 1];
        }
        dl[i] = 0.0;
    }
    if d[n - 1] == 0.0 {
        d[n - 1] = tiny;
    }
    v[n - 1] /= d[n - 1];
    v[n - 2] = (v[n - 2] - du[n - 2] * v[n - 1]) / d[n - 2];
    for i in (0..n.saturating_sub(2)).rev() {
        v[i] = (v[i] - du[i] * v[i + 1] - du2[i] * v[i + 2]) / d[i];
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

fn normalise(a: &mut [f64]) {
    let n = norm(a);
    a.iter_mut().for_each(|x| *x /= n);
}

fn axpy(c: f64, x: &[f64], y: &mut [f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += c * xi;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, SymmetricEigen};

    #[test]
    fn top_ritz_agrees_with_nalgebra_on_random_tridiagonal_matrices() {
        // The extreme eigenvalues and the top eigenvector's last component
        // (the residual's factor) against nalgebra's dense symmetric
        // eigensolver: sizes 1 to 300, entries of mixed signs and scales,
        // and a case with a nearly double top eigenvalue (two copies of one
        // block joined weakly).
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        for case in 0..60 {
            let steps = [1, 2, 3, 10, 37, 120, 300][case % 7];
            let scale = 10f64.powi(rng.random_range(-8..8));
            let mut alpha: Vec<f64> = (0..steps).map(|_| scale * rng.random_range(-1.0..1.0)).collect();
            let mut beta: Vec<f64> = (1..steps).map(|_| scale * rng.random_range(0.01..1.0)).collect();
            if case % 5 == 4 && steps >= 10 {
                let h = steps / 2;
                for i in 0..h {
                    alpha[steps - 1 - i] = alpha[i];
                }
                for i in 0..h.saturating_sub(1) {
                    beta[steps - 2 - i] = beta[i];
                }
                beta[h - 1] = scale * 1e-9;
            }
            let b = scale * 0.3;
            let t = DMatrix::from_fn(steps, steps, |r, c| {
                if r == c {
                    alpha[r]
                } else if r + 1 == c || c + 1 == r {
                    beta[r.min(c)]
                } else {
                    0.0
                }
            });
            let eig = SymmetricEigen::new(t.clone());
            let (imax, &lmax) = eig.eigenvalues.iter().enumerate().max_by(|x, y| x.1.total_cmp(y.1)).unwrap();
            let lmin = eig.eigenvalues.min();
            let (v, theta, residual, sc) = top_ritz(&alpha, &beta, b);
            let norm = lmax.abs().max(lmin.abs());
            assert!((theta - lmax).abs() <= 1e-13 * norm, "case {case}: {theta} vs {lmax}");
            assert!((sc - norm).abs() <= 1e-13 * norm, "case {case}: scale {sc} vs {norm}");
            // T v = theta v to rounding, v a unit vector
            let tv = &t * nalgebra::DVector::from_column_slice(&v);
            let res = (0..steps).map(|i| (tv[i] - theta * v[i]).powi(2)).sum::<f64>().sqrt();
            assert!(res <= 1e-12 * norm, "case {case}: ||T v - theta v|| = {res:e}");
            // the residual factor, where the top eigenvalue is well separated
            let gap = eig.eigenvalues.iter().filter(|x| **x < lmax).fold(f64::NEG_INFINITY, |m, x| m.max(*x));
            if lmax - gap > 1e-6 * norm {
                let expect = (b * eig.eigenvectors[(steps - 1, imax)]).abs();
                assert!((residual - expect).abs() <= 1e-9 * b, "case {case}: residual {residual:e} vs {expect:e}");
            }
        }
    }

    #[test]
    fn a_zero_operator_gives_zero_not_nan() {
        // Q = 0 (no noise, or constant noise): the largest generalised
        // eigenvalue is 0 (found in review: the first top_ritz divided by a
        // zero pivot and gave NaN). Also a tiny spectrum (1e-200 times
        // [[1, 1, 0], [1, 3, 1], [0, 1, 2]], scaled by a power of two before
        // the Sturm count): its top eigenvalue 3.879385241571817 times
        // 1e-200 (numpy's eigvalsh of the unscaled matrix).
        let r = largest_generalized_eigenvalue(
            20,
            |_, y| y.iter_mut().for_each(|v| *v = 0.0),
            |x, y| y.copy_from_slice(x),
            |b, x| x.copy_from_slice(b),
            1e-12,
            50,
        );
        assert_eq!(r.value, 0.0);
        let (_, theta, _, scale) = top_ritz(&[0.0], &[], 0.0);
        assert_eq!((theta, scale), (0.0, 0.0));
        let (_, theta, _, scale) = top_ritz(&[0.0, 0.0, 0.0], &[0.0, 0.0], 0.0);
        assert_eq!((theta, scale), (0.0, 0.0));
        let (v, theta, _, _) = top_ritz(&[1e-200, 3e-200, 2e-200], &[1e-200, 1e-200], 1e-200);
        assert!(v.iter().all(|x| x.is_finite()), "{v:?}");
        assert!((theta / 3.879385241571817e-200 - 1.0).abs() < 1e-13, "{theta:e}");
    }

    #[test]
    fn agrees_with_dense_eigenvalues_on_a_random_symmetric_matrix() {
        let n = 60;
        let a = DMatrix::from_fn(n, n, |i, j| {
            (((i * 31 + j * 17) % 23) as f64 - 11.0) + (((j * 31 + i * 17) % 23) as f64 - 11.0)
        });
        let dense = SymmetricEigen::new(a.clone()).eigenvalues.max();
        let r = largest_eigenvalue(
            n,
            |x, y| y.copy_from_slice((&a * nalgebra::DVector::from_column_slice(x)).as_slice()),
            1e-12,
            200,
        );
        assert!((r.value - dense).abs() < 1e-9 * dense.abs(), "{} vs {dense}", r.value);
        // a shifted matrix has a different top eigenvalue: the comparison can fail
        let b = &a + DMatrix::<f64>::identity(n, n) * 5.0;
        let r2 = largest_eigenvalue(
            n,
            |x, y| y.copy_from_slice((&b * nalgebra::DVector::from_column_slice(x)).as_slice()),
            1e-12,
            200,
        );
        assert!((r2.value - dense - 5.0).abs() < 1e-9 * dense.abs());
    }
}
