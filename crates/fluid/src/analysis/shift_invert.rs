//! One eigenvalue of the drift `R = U + U'' M^-1 K` of an x-mode on a fine
//! grid, the one nearest a given phase speed, without forming `R`: the
//! instability search's refinement past the dense grids
//! ([`super::instability`]).
//!
//! `K = M L^-1 M` with `L = S + k^2 M` banded, so with `omega = M^-1 L psi`
//! the eigenproblem `R omega = c omega` is the banded pencil
//! `(diag(U) L + diag(U'' m)) psi = c L psi` (`M = diag(m)` commutes with
//! `diag(U)`): the same eigenvalues, and both sides have the bandwidth of
//! `L`. Inverse iteration with the fixed shift `sigma` on it,
//! `(A - sigma L) x_{j+1} = L x_j`, converges to the eigenvalue nearest
//! `sigma` (ratio `|c_1 - sigma| / |c_2 - sigma|` a step), each step a
//! banded solve: `O(n b^2)` to factor once and `O(n b)` a step, where the
//! dense eigenvalues cost `O(n^3)` (ny = 2048: 4 s, 4096: 33 s; measured
//! with `examples/instability_rates.rs`).
//!
//! Written here rather than taken from a crate for the reason of
//! [`crate::banded`]: a complex banded LU with partial pivoting is forty
//! lines.

use crate::grid::YGrid;
use crate::modes::Coefficients;
use nalgebra::Complex;

type C = Complex<f64>;

/// A complex `n x n` band matrix with `p` sub- and super-diagonals,
/// factored `P A = L U` by Gaussian elimination with partial pivoting (the
/// scheme of LAPACK's `gbtrf`: `U` has `2p` super-diagonals, the
/// multipliers of step `i` stay where step `i` left them and the solve
/// applies the interchanges in turn).
struct BandLu {
    n: usize,
    p: usize,
    /// Row `i` holds the columns `i - p ..= i + 2p` at `i * (3p + 1) + (j + p - i)`.
    a: Vec<C>,
    pivot: Vec<usize>,
}

impl BandLu {
    fn at(&self, i: usize, j: usize) -> usize {
        i * (3 * self.p + 1) + (j + self.p - i)
    }

    /// Factors the matrix with entries `entry(i, j)` for `|i - j| <= p`
    /// (`None` on an exactly zero pivot, or a non-finite entry).
    fn factor(n: usize, p: usize, entry: impl Fn(usize, usize) -> C) -> Option<Self> {
        let mut lu = BandLu { n, p, a: vec![C::new(0.0, 0.0); n * (3 * p + 1)], pivot: vec![0; n] };
        for i in 0..n {
            for j in i.saturating_sub(p)..=(i + p).min(n - 1) {
                let at = lu.at(i, j);
                lu.a[at] = entry(i, j);
            }
        }
        if lu.a.iter().any(|z| !(z.re.is_finite() && z.im.is_finite())) {
            return None;
        }
        for i in 0..n {
            let last = (i + p).min(n - 1);
            let right = (i + 2 * p).min(n - 1);
            let q = (i..=last).max_by(|&r, &s| lu.a[lu.at(r, i)].norm().total_cmp(&lu.a[lu.at(s, i)].norm()))?;
            if q != i {
                for j in i..=right {
                    let (x, y) = (lu.at(i, j), lu.at(q, j));
                    lu.a.swap(x, y);
                }
            }
            lu.pivot[i] = q;
            let d = lu.a[lu.at(i, i)];
            if d.norm() == 0.0 {
                return None;
            }
            for r in i + 1..=last {
                let ri = lu.at(r, i);
                let l = lu.a[ri] / d;
                lu.a[ri] = l;
                if l.norm() != 0.0 {
                    for j in i + 1..=right {
                        let (x, y) = (lu.at(r, j), lu.at(i, j));
                        let v = lu.a[y];
                        lu.a[x] -= l * v;
                    }
                }
            }
        }
        Some(lu)
    }

    /// `b := A^-1 b`.
    fn solve(&self, b: &mut [C]) {
        let (n, p) = (self.n, self.p);
        for i in 0..n {
            b.swap(i, self.pivot[i]);
            let bi = b[i];
            for r in i + 1..=(i + p).min(n - 1) {
                b[r] -= self.a[self.at(r, i)] * bi;
            }
        }
        for i in (0..n).rev() {
            let mut s = b[i];
            for j in i + 1..=(i + 2 * p).min(n - 1) {
                s -= self.a[self.at(i, j)] * b[j];
            }
            b[i] = s / self.a[self.at(i, i)];
        }
    }
}

/// Inverse iteration stops when the estimate moves by at most this times
/// `max(|c|, max |U|)` ...
const CONVERGED: f64 = 1e-12;
/// ... or after this many steps (then no eigenvalue is returned).
const MAX_STEPS: usize = 200;
/// The eigenpair is returned only if `|A x - c L x| <= RESIDUAL (|A| + |c| |L|) |x|`
/// (infinity norms): an eigenvalue of the discretisation up to rounding.
const RESIDUAL: f64 = 1e-9;

/// The eigenvalue `c` of the drift of mode `k` on `grid` (coefficients
/// `coef`) nearest the phase speed `sigma`, by inverse iteration on the
/// banded pencil of the module docs, with its relative residual; `None` if
/// the iteration does not converge (two eigenvalues about as near `sigma`,
/// or `sigma` an eigenvalue to the last bit) or its residual is not small.
///
/// The start vector is a fixed pseudo-random one (a constant one has no
/// odd part, and a symmetric jet's varicose modes are odd).
pub(super) fn nearest_eigenvalue(grid: &YGrid, coef: &Coefficients, k: f64, sigma: C) -> Option<(C, f64)> {
    let l = grid.helmholtz(k);
    let (n, p) = (l.n(), l.bandwidth());
    let u = grid.to_banded(&coef.u);
    let upp = grid.to_banded(&coef.upp);
    let m = grid.to_banded(grid.weights());
    let a = |i: usize, j: usize| u[i] * l.get(i, j) + if i == j { upp[i] * m[i] } else { 0.0 };
    let lu = BandLu::factor(n, p, |i, j| C::new(a(i, j), 0.0) - sigma * l.get(i, j))?;
    let l_times = |x: &[C]| -> Vec<C> {
        (0..n).map(|i| (i.saturating_sub(p)..=(i + p).min(n - 1)).map(|j| x[j] * l.get(i, j)).sum()).collect()
    };
    let u_scale = u.iter().fold(0.0f64, |s, v| s.max(v.abs()));
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let mut x: Vec<C> = (0..n)
        .map(|_| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            C::new((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5, 0.0)
        })
        .collect();
    let norm = |x: &[C]| x.iter().map(|z| z.norm_sqr()).sum::<f64>().sqrt();
    let mut c = sigma;
    let mut converged = false;
    for _ in 0..MAX_STEPS {
        let mut y = l_times(&x);
        lu.solve(&mut y);
        // y = (A - sigma L)^-1 L x = x / (c - sigma) for an eigenvector x
        let theta: C =
            x.iter().zip(&y).map(|(x, y)| x.conj() * y).sum::<C>() / x.iter().map(|z| z.norm_sqr()).sum::<f64>();
        let ny = norm(&y);
        if !(ny.is_finite() && ny > 0.0 && theta.norm() > 0.0) {
            return None;
        }
        let next = sigma + theta.inv();
        x = y.iter().map(|z| z / ny).collect();
        let moved = (next - c).norm();
        c = next;
        if moved <= CONVERGED * c.norm().max(u_scale) {
            converged = true;
            break;
        }
    }
    if !converged {
        return None;
    }
    // residual |A x - c L x|, relative to (|A| + |c| |L|) |x| (infinity norms)
    let lx = l_times(&x);
    let ax: Vec<C> = (0..n).map(|i| (i.saturating_sub(p)..=(i + p).min(n - 1)).map(|j| x[j] * a(i, j)).sum()).collect();
    let r = ax.iter().zip(&lx).map(|(a, b)| (a - c * b).norm()).fold(0.0, f64::max);
    let row_sum = |f: &dyn Fn(usize, usize) -> f64| {
        (0..n)
            .map(|i| (i.saturating_sub(p)..=(i + p).min(n - 1)).map(|j| f(i, j).abs()).sum::<f64>())
            .fold(0.0, f64::max)
    };
    let scale = row_sum(&a) + c.norm() * row_sum(&|i, j| l.get(i, j));
    let x_max = x.iter().map(|z| z.norm()).fold(0.0, f64::max);
    let relative = r / (scale * x_max);
    (relative.is_finite() && relative <= RESIDUAL).then_some((c, relative))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Boundary;
    use crate::modes::Mode;

    /// The nearest eigenvalue of the pencil is the dense drift's, on walls
    /// and periodic grids: from a shift near each complex eigenvalue of
    /// `R` (and near a real one) it returns that eigenvalue.
    #[test]
    fn the_pencil_has_the_eigenvalues_of_the_dense_drift() {
        let p = |s: &str| crate::expr::parse(s, &Default::default()).unwrap();
        for (boundary, u, (a, b), k) in [
            (Boundary::Walls, "4/(exp(y) + exp(-y))^2", (-8.0, 8.0), 1.5),
            (Boundary::Walls, "(exp(y) - exp(-y))/(exp(y) + exp(-y))", (-6.0, 6.0), 0.8),
            (Boundary::Periodic, "sin(2*y)", (0.0, 2.0 * std::f64::consts::PI), 1.0),
        ] {
            let profile = crate::profile::Profile::new(p(u), vec![], (a, b), boundary);
            let grid = YGrid::new(boundary, a, b, 256);
            let coef = profile.coefficients(&grid);
            let r = Mode::new(&grid, k).drift_matrix(&coef);
            let n = r.nrows();
            let values = faer::Mat::<f64>::from_fn(n, n, |i, j| r[(i, j)]).eigenvalues().unwrap();
            let values: Vec<C> = values.iter().map(|z| C::new(z.re, z.im)).collect();
            let mut tried = 0;
            for &target in values.iter().filter(|z| z.im > 1e-3) {
                // the shift: 1% of the distance to the next eigenvalue away
                let gap =
                    values.iter().filter(|z| **z != target).map(|z| (z - target).norm()).fold(f64::INFINITY, f64::min);
                let (c, residual) = nearest_eigenvalue(&grid, &coef, k, target + C::new(0.01 * gap, 0.0)).unwrap();
                assert!((c - target).norm() <= 1e-9 * target.norm().max(1.0), "{u}: {c} vs {target}");
                assert!(residual <= RESIDUAL);
                tried += 1;
            }
            assert!(tried > 0, "{u}: no complex eigenvalue");
        }
    }

    #[test]
    fn a_band_lu_solves_a_system_needing_pivots() {
        // [[0, 1, 0], [1, 0, 2], [0, 3, 1]] (p = 1): a zero first pivot
        let m = [[0.0, 1.0, 0.0], [1.0, 0.0, 2.0], [0.0, 3.0, 1.0]];
        let lu = BandLu::factor(3, 1, |i, j| C::new(m[i][j], 0.0)).unwrap();
        let x = [C::new(1.0, 2.0), C::new(-1.0, 0.5), C::new(0.25, -3.0)];
        let mut b: Vec<C> = (0..3).map(|i| (0..3).map(|j| x[j] * m[i][j]).sum()).collect();
        lu.solve(&mut b);
        for (got, want) in b.iter().zip(&x) {
            assert!((got - want).norm() < 1e-14, "{got} vs {want}");
        }
        assert!(BandLu::factor(2, 1, |_, _| C::new(0.0, 0.0)).is_none());
    }
}
