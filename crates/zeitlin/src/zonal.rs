//! Zonal (diagonal) states: the quantised zonal harmonics `T_{l0}` and the
//! map from a profile `omega(z)` on the sphere to the vorticity matrix.
//!
//! Conventions (those of quflow): `W = i diag(omega_0, ..., omega_{N-1})`,
//! index `j = N - 1` at the north pole; the inner product is
//! `<A, B> = Re tr(A B^*) / N`; `T_{l0} = i sqrt(N) diag(u_l)` with `u_l` the
//! orthonormal eigenvector of the zonal Laplacian for `-l (l + 1)`, signed so
//! that its last entry is positive, so `<T_{l0}, T_{l0}> = 1`. A function on
//! the sphere is expanded in `sqrt(2l + 1) P_l(z)` (unit mean square, as
//! quflow's `shr`), `omega(z) = sum_l a_l sqrt(2l + 1) P_l(z)`, and quantised
//! to `W = sum_l a_l T_{l0}`.
//!
//! The `u_l` are the discrete Chebyshev (Gram) polynomials: the diagonal
//! matrices of spin `l` are the polynomials of degree `l` in `S_3`
//! orthogonal in the trace to those of lower degree. They are computed by
//! their three-term recurrence, `x u_l = b_{l+1} u_{l+1} + b_l u_{l-1}` with
//! `x = j - (N - 1)/2` and `b_l^2 = l^2 (N^2 - l^2) / (4 (4 l^2 - 1))`; the
//! tests check orthonormality and the eigenvalue equation independently.

/// The orthonormal zonal harmonics `u_0, ..., u_{lmax}` on `N` points (each of length `N`).
///
/// ```
/// let u = zeitlin::zonal::harmonics(4, 3);
/// // u_1 is proportional to j - 3/2, unit length, last entry positive
/// let norm = (0.25f64 * 2.0 + 2.25 * 2.0).sqrt();
/// assert!((u[1][3] - 1.5 / norm).abs() < 1e-15);
/// ```
pub fn harmonics(n: usize, lmax: usize) -> Vec<Vec<f64>> {
    assert!(lmax < n);
    let nf = n as f64;
    let x: Vec<f64> = (0..n).map(|j| j as f64 - (nf - 1.0) / 2.0).collect();
    let b = |l: usize| {
        let l = l as f64;
        (l * l * (nf * nf - l * l) / (4.0 * (4.0 * l * l - 1.0))).sqrt()
    };
    let mut u: Vec<Vec<f64>> = vec![vec![1.0 / nf.sqrt(); n]];
    for l in 0..lmax {
        let mut next: Vec<f64> = x.iter().zip(&u[l]).map(|(x, p)| x * p).collect();
        if l > 0 {
            let bl = b(l);
            for (v, p) in next.iter_mut().zip(&u[l - 1]) {
                *v -= bl * p;
            }
        }
        let bn = b(l + 1);
        next.iter_mut().for_each(|v| *v /= bn);
        u.push(next);
    }
    // The forward recurrence loses accuracy at high degree (by n = 64,
    // l = 46 its eigen-residual is 4e-6; at n = 256, l = 255 it overflows):
    // where its vector is not an eigenvector to 1e-12, it is replaced by
    // inverse iteration with the known eigenvalue `-l (l + 1)`, shifted off
    // it by a relative 1e-10 so the tridiagonal solve is not singular, from a
    // fixed start vector (the gaps are at least 2 (l + 1), so each step
    // gains a factor 1e10 over every other eigenvector; four steps).
    let lap = crate::laplacian::block(n, 0);
    let sub = lap.off.clone();
    let mut y = vec![0.0; n];
    for (l, v) in u.iter_mut().enumerate().skip(1) {
        let lambda = -((l * (l + 1)) as f64);
        lap.mul(v, &mut y);
        let residual = y.iter().zip(v.iter()).map(|(a, b)| (a - lambda * b).abs()).fold(0.0f64, f64::max);
        if residual.is_finite() && residual <= 1e-12 * lambda.abs() {
            continue;
        }
        // (A factor singular in floating point at the first shift, which an
        // exact integer matrix makes all but impossible, retries further off.)
        let Some(factor) = [1e-10, 1e-8].iter().find_map(|rel| {
            let diag: Vec<f64> = lap.diag.iter().map(|d| d - lambda * (1.0 + rel)).collect();
            crate::laplacian::GeneralTridiagonalFactor::new(&sub, &diag, &sub)
        }) else {
            continue;
        };
        for (j, x) in v.iter_mut().enumerate() {
            *x = 1.0 + 0.5 * ((j as f64) * 0.7548776662).sin();
        }
        for _ in 0..4 {
            if !factor.solve(v) {
                break;
            }
            let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            v.iter_mut().for_each(|x| *x /= norm);
        }
        if v[n - 1] < 0.0 {
            v.iter_mut().for_each(|x| *x = -*x);
        }
    }
    u
}

/// Gauss–Legendre nodes and weights on `[-1, 1]` (Newton's method on
/// `P_q` from Tricomi's initial guesses; exact for polynomials of degree
/// `2q - 1`).
///
/// Written here rather than taken from a crate: it is twenty lines, and the
/// crates that offer it (`gauss-quad`) compute nodes by an eigenproblem
/// that costs `O(q^3)` at the thousands of points a fine sphere needs.
pub fn gauss_legendre(q: usize) -> (Vec<f64>, Vec<f64>) {
    let mut nodes = vec![0.0; q];
    let mut weights = vec![0.0; q];
    let qf = q as f64;
    for i in 0..q.div_ceil(2) {
        let theta = std::f64::consts::PI * (i as f64 + 0.75) / (qf + 0.5);
        let mut z = theta.cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, z);
            for k in 2..=q {
                let kf = k as f64;
                let p2 = ((2.0 * kf - 1.0) * z * p1 - (kf - 1.0) * p0) / kf;
                p0 = p1;
                p1 = p2;
            }
            let pq = if q == 0 { 1.0 } else { p1 };
            let pq1 = if q <= 1 { 1.0 } else { p0 };
            dp = qf * (z * pq - pq1) / (z * z - 1.0);
            let dz = pq / dp;
            z -= dz;
            if dz.abs() <= 1e-16 * z.abs().max(1.0) {
                break;
            }
        }
        nodes[i] = z;
        nodes[q - 1 - i] = -z;
        let w = 2.0 / ((1.0 - z * z) * dp * dp);
        weights[i] = w;
        weights[q - 1 - i] = w;
    }
    (nodes, weights)
}

/// A zonal state quantised from a profile.
#[derive(Clone, Debug, PartialEq)]
pub struct Quantised {
    /// `omega_j`: `W = i diag(omega)`, trace-free.
    pub diagonal: Vec<f64>,
    /// The coefficients `a_l`, `l = 0..N-1`, before `a_0` was dropped.
    pub coefficients: Vec<f64>,
}

/// `omega_j` from the coefficients `a_l` (`a_0`, the mean, is dropped: a
/// vorticity on the closed sphere has zero mean, and `W` is trace-free).
///
/// ```
/// // omega = z is a_1 = 1/sqrt(3): W = T_10 / sqrt 3
/// let w = zeitlin::zonal::from_coefficients(3, &[0.0, 1.0 / 3f64.sqrt()]);
/// // u_1 = (-1, 0, 1)/sqrt 2, times sqrt(N) = sqrt 3, over sqrt 3
/// assert!((w[2] - 1.0 / 2f64.sqrt()).abs() < 1e-15 && w[1].abs() < 1e-15);
/// ```
pub fn from_coefficients(n: usize, a: &[f64]) -> Vec<f64> {
    let lmax = a.len().min(n).saturating_sub(1);
    let u = harmonics(n, lmax);
    let scale = (n as f64).sqrt();
    let mut w = vec![0.0; n];
    for (al, ul) in a.iter().zip(&u).skip(1) {
        for (wj, uj) in w.iter_mut().zip(ul) {
            *wj += scale * al * uj;
        }
    }
    w
}

/// Quantise a zonal profile `f(z)`: `a_l = 1/2 int_{-1}^{1} f(z) sqrt(2l+1) P_l(z) dz`
/// by Gauss–Legendre quadrature on `2N + 32` nodes (exact for a polynomial
/// profile of degree up to `N + 32`), then [`from_coefficients`].
///
/// ```
/// let q = zeitlin::zonal::quantise(3, |z| z);
/// assert!((q.coefficients[1] - 1.0 / 3f64.sqrt()).abs() < 1e-14);
/// assert!(q.coefficients[0].abs() < 1e-15 && q.coefficients[2].abs() < 1e-14);
/// ```
pub fn quantise(n: usize, f: impl Fn(f64) -> f64) -> Quantised {
    let q = 2 * n + 32;
    let (z, w) = gauss_legendre(q);
    let values: Vec<f64> = z.iter().map(|&z| f(z)).collect();
    let mut a = vec![0.0; n];
    // Normalised Legendre recurrence, node by node.
    for ((&zi, &wi), &fi) in z.iter().zip(&w).zip(&values) {
        let (mut p0, mut p1) = (1.0, zi);
        a[0] += 0.5 * wi * fi;
        if n > 1 {
            a[1] += 0.5 * wi * fi * 3f64.sqrt() * zi;
        }
        for l in 2..n {
            let lf = l as f64;
            let p2 = ((2.0 * lf - 1.0) * zi * p1 - (lf - 1.0) * p0) / lf;
            p0 = p1;
            p1 = p2;
            a[l] += 0.5 * wi * fi * (2.0 * lf + 1.0).sqrt() * p2;
        }
    }
    Quantised { diagonal: from_coefficients(n, &a), coefficients: a }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::laplacian::block;

    #[test]
    fn harmonics_are_orthonormal_eigenvectors_of_the_zonal_laplacian() {
        for n in [2usize, 3, 7, 16, 64, 256] {
            let u = harmonics(n, n - 1);
            let lap = block(n, 0);
            let mut worst: f64 = 0.0;
            for l in 0..n {
                for k in 0..n {
                    let d: f64 = u[l].iter().zip(&u[k]).map(|(a, b)| a * b).sum();
                    worst = worst.max((d - if l == k { 1.0 } else { 0.0 }).abs());
                }
                let mut y = vec![0.0; n];
                lap.mul(&u[l], &mut y);
                let lambda = -((l * (l + 1)) as f64);
                let res: f64 = y.iter().zip(&u[l]).map(|(a, b)| (a - lambda * b).abs()).fold(0.0, f64::max);
                assert!(res < 1e-9 * (1.0 + lambda.abs()), "n {n} l {l}: {res}");
                assert!(u[l][n - 1] > 0.0, "n {n} l {l}: last entry not positive");
            }
            assert!(worst < 1e-10, "n {n}: orthonormality off by {worst}");
        }
    }

    #[test]
    fn gauss_legendre_integrates_polynomials() {
        let (z, w) = gauss_legendre(10);
        // int z^18 = 2/19, int z^2 = 2/3
        let i18: f64 = z.iter().zip(&w).map(|(z, w)| w * z.powi(18)).sum();
        assert!((i18 - 2.0 / 19.0).abs() < 1e-14);
        assert!((w.iter().sum::<f64>() - 2.0).abs() < 1e-14);
    }

    #[test]
    fn a_cubic_profile_has_the_legendre_coefficients() {
        // z^3 = (3/5) P_1 + (2/5) P_3: a_1 = (3/5)/sqrt 3, a_3 = (2/5)/sqrt 7.
        let q = quantise(8, |z| z * z * z);
        assert!((q.coefficients[1] - 0.6 / 3f64.sqrt()).abs() < 1e-14);
        assert!((q.coefficients[3] - 0.4 / 7f64.sqrt()).abs() < 1e-14);
        for l in [0, 2, 4, 5, 6, 7] {
            assert!(q.coefficients[l].abs() < 1e-14, "a_{l} = {}", q.coefficients[l]);
        }
        assert!(q.diagonal.iter().sum::<f64>().abs() < 1e-12);
    }
}
