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
//! restarts). Until 2026-11-28 the periodic modes formed `V` and `Q`
//! densely (`modes.rs`), where a dense eigensolver would also have served;
//! now both boundaries apply banded operators. The
//! Ritz values of the small tridiagonal matrix come from nalgebra's
//! symmetric eigensolver.

use nalgebra::{DMatrix, SymmetricEigen};

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
/// use fluid::lanczos::largest_eigenvalue;
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
/// use fluid::lanczos::largest_generalized_eigenvalue;
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
        // V-orthogonalise against the basis, twice
        for _ in 0..2 {
            for (b, vb) in basis.iter().zip(&vbasis) {
                let c = dot(vb, &p);
                axpy(-c, b, &mut p);
            }
        }
        apply_v(&p, &mut vp);
        let b = dot(&p, &vp).max(0.0).sqrt();
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
/// a dense eigenproblem of size `steps` (`O(steps^3)`): cheap beside a step
/// while the basis is short, and the walls' modes converge within 7 to 20
/// steps, so looking only every eighth step ran up to seven steps too many.
/// Measured 2026-11-27 (fifth session) at ny = 1024 (`fluid_mode`, mode 1 of
/// `bench/cubic-walls.json`): 9 steps instead of 16 (docs/fluids.md §5).
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
    // the walls' V-solves converge in one step, and a preconditioned
    // residual computed after the last step is never used (until
    // 2026-11-28 it was, at a third of the preconditioner's work; the
    // iterate is the same).
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
fn top_ritz(alpha: &[f64], beta: &[f64], b: f64) -> (Vec<f64>, f64, f64, f64) {
    let steps = alpha.len();
    let t = DMatrix::from_fn(steps, steps, |r, c| {
        if r == c {
            alpha[r]
        } else if r + 1 == c || c + 1 == r {
            beta[r.min(c)]
        } else {
            0.0
        }
    });
    // Bounded iterations: nalgebra's `new` iterates without limit, and a NaN
    // entry would never converge.
    let nan = (vec![f64::NAN; steps], f64::NAN, f64::INFINITY, f64::NAN);
    if t.iter().any(|x| !x.is_finite()) || !b.is_finite() {
        return nan;
    }
    let Some(eig) = SymmetricEigen::try_new(t, f64::EPSILON, 1000 * (steps + 1)) else { return nan };
    let Some((imax, &theta)) = eig.eigenvalues.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)) else {
        return nan;
    };
    let scale = eig.eigenvalues.iter().fold(0.0f64, |s, x| s.max(x.abs()));
    let residual = (b * eig.eigenvectors[(steps - 1, imax)]).abs();
    (eig.eigenvectors.column(imax).iter().copied().collect(), theta, residual, scale)
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
