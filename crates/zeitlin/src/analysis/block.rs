//! One off-diagonal block `m` of the linearisation: its data independent of
//! the choice of functional, the definiteness of `P_m`, `lambda_min(P_m)`,
//! `lambda_max(Q_m, P_m)` by the inertia of a banded lifting, the drift
//! residual and the drift's growth rate (see the parent module's docs).

use super::{BlockResult, Choice, ZeitlinError, ZeitlinProblem};
use crate::laplacian::{block, Tridiagonal, TridiagonalFactor};
use numerics::banded::{Bounded, SymBanded};
use numerics::definite::{positive_definite, Symmetric};
use numerics::scaling::nearest_power_of_two;

/// Per-block data independent of the choice.
pub(super) struct Block {
    pub(super) m: usize,
    lap: Tridiagonal,
    factor: TridiagonalFactor,
    pub(super) d_pi: Vec<f64>,
    pub(super) d_omega: Vec<f64>,
    d_xi: Vec<Vec<f64>>,
    /// Entries whose two eigenvalues coincide (`d omega = 0`).
    pub(super) degenerate: Vec<bool>,
    /// `-Delta ≻ 0` proved (a tridiagonal verified Cholesky), once per
    /// block: Haynsworth's count in [`Block::lifted`] needs it.
    laplacian_definite: bool,
}

impl Block {
    /// Diagonal `m` of the problem: its Laplacian `Delta_m` (factored),
    /// the differences `d f_j = f_j - f_{j+m}` of `pi`, `omega` and each
    /// `xi_i`, and the entries with `|d omega_j| <= 1e-12 max |omega|`.
    pub(super) fn new(problem: &ZeitlinProblem, pi: &[f64], scale_omega: f64, m: usize) -> Result<Block, ZeitlinError> {
        let n = problem.n;
        let omega = &problem.omega;
        let lap = block(n, m);
        let factor = lap.factor().ok_or_else(|| ZeitlinError::Numerical(format!("the Laplacian of diagonal {m}")))?;
        let len = n - m;
        let d = |f: &[f64]| -> Vec<f64> { (0..len).map(|j| f[j] - f[j + m]).collect() };
        let d_omega = d(omega);
        let degenerate = d_omega.iter().map(|x| x.abs() <= 1e-12 * scale_omega).collect();
        Ok(Block {
            m,
            factor,
            d_pi: d(pi),
            d_omega,
            d_xi: problem.noise.iter().map(|x| d(x)).collect(),
            degenerate,
            laplacian_definite: minus_laplacian_is_definite(&lap),
            lap,
        })
    }

    pub(super) fn len(&self) -> usize {
        self.lap.len()
    }

    /// `G x = -Delta^{-1} x`.
    fn g(&self, x: &[f64], out: &mut [f64]) {
        out.copy_from_slice(x);
        self.factor.solve(out);
        out.iter_mut().for_each(|v| *v = -*v);
    }

    fn c(&self, choice: &Choice) -> Vec<f64> {
        (0..self.len())
            .map(|j| {
                if self.degenerate[j] {
                    choice.free_curvature
                } else {
                    (choice.energy * self.d_pi[j] + choice.momentum * self.m as f64) / self.d_omega[j]
                }
            })
            .collect()
    }

    /// `Delta P Delta = -eps Delta + Delta D_c Delta` (pentadiagonal; same
    /// inertia as `P`).
    fn congruent_p(&self, c: &[f64], eps: f64) -> SymBanded {
        let n = self.len();
        let mut out = SymBanded::zeros(n, 2);
        let t = &self.lap;
        for i in 0..n {
            out.add(i, i, -eps * t.diag[i]);
            if i > 0 {
                out.add(i, i - 1, -eps * t.off[i - 1]);
            }
            // (Delta D Delta)_{ij} = sum_k Delta_ik c_k Delta_kj
            for j in i.saturating_sub(2)..=i {
                let s: f64 = (j.saturating_sub(1)..=(i + 1).min(n - 1)).map(|k| t.get(i, k) * c[k] * t.get(k, j)).sum();
                out.add(i, j, s);
            }
        }
        out
    }

    /// Whether `P` is positive definite ([`congruent_form_is_definite`]).
    pub(super) fn definite(&self, choice: &Choice) -> bool {
        congruent_form_is_definite(&self.lap, &self.c(choice), choice.energy)
    }

    /// `lambda_min(P)`, from below, to about 1e-10 of the bracket: by
    /// bisection on the pencil `(Delta P Delta, Delta^2)`, which has the
    /// eigenvalues of `P` (`P y = l y` with `y = Delta x`). `Delta P Delta -
    /// l Delta^2` is pentadiagonal, so each step is a banded Cholesky,
    /// `O(n)`: Lanczos on `P` converged slowly (the eigenvalues of `G`
    /// cluster at 0) and cost `O(k^2 n)` with reorthogonalisation. Used by
    /// the search only; definiteness is claimed by [`Block::definite`].
    ///
    /// `tick` is called once per definiteness test (the unit of progress).
    pub(super) fn lambda_min(&self, choice: &Choice, tick: &(dyn Fn() + Sync)) -> f64 {
        let n = self.len();
        let c = self.c(choice);
        if c.iter().any(|x| !x.is_finite()) {
            return f64::NEG_INFINITY;
        }
        let pp = self.congruent_p(&c, choice.energy);
        let d2 = self.laplacian_squared();
        let mut work = vec![];
        let mut above = |l: f64| {
            tick();
            pp.minus_is_positive_definite(l, &d2, &mut work)
        };
        // The Rayleigh quotient of each e_j in the pencil bounds lambda_min above.
        let mut hi = (0..n).map(|j| pp.get(j, j) / d2.get(j, j)).fold(f64::INFINITY, f64::min);
        let width0 = (choice.energy.abs() + c.iter().fold(0.0f64, |a, x| a.max(x.abs()))).max(f64::MIN_POSITIVE);
        let mut width = width0;
        let mut lo = hi - width;
        let mut tries = 0;
        while !above(lo) {
            hi = lo;
            width *= 2.0;
            lo = hi - width;
            tries += 1;
            if tries > 64 || !lo.is_finite() {
                return f64::NEG_INFINITY;
            }
        }
        for _ in 0..60 {
            if hi - lo <= 1e-10 * width0 {
                break;
            }
            let mid = 0.5 * (lo + hi);
            if above(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    }

    /// The diagonal of `G = (-Delta)^-1`, by the two pivot recurrences of
    /// the tridiagonal `T = -Delta`: `(T^-1)_jj = 1/(f_j + g_j - T_jj)` with
    /// `f` the forward and `g` the backward elimination pivots.
    pub(super) fn g_diagonal(&self) -> Vec<f64> {
        let n = self.len();
        let d: Vec<f64> = self.lap.diag.iter().map(|x| -x).collect();
        let e = &self.lap.off; // (-e)^2 = e^2
        let mut f = vec![0.0; n];
        let mut g = vec![0.0; n];
        for j in 0..n {
            f[j] = if j == 0 { d[0] } else { d[j] - e[j - 1] * e[j - 1] / f[j - 1] };
        }
        for j in (0..n).rev() {
            g[j] = if j + 1 == n { d[j] } else { d[j] - e[j] * e[j] / g[j + 1] };
        }
        (0..n).map(|j| 1.0 / (f[j] + g[j] - d[j])).collect()
    }

    /// `Delta^2` (pentadiagonal).
    fn laplacian_squared(&self) -> SymBanded {
        let n = self.len();
        let t = &self.lap;
        let mut out = SymBanded::zeros(n, 2);
        for i in 0..n {
            for j in i.saturating_sub(2)..=i {
                let s: f64 = (j.saturating_sub(1)..=(i + 1).min(n - 1)).map(|k| t.get(i, k) * t.get(k, j)).sum();
                out.add(i, j, s);
            }
        }
        out
    }

    /// The banded lifting whose inertia decides `s P - Q ≻ 0` (with
    /// `P ≻ 0`, that is `lambda_max(Q, P) < s`), and the inertia it must
    /// have; `None` when `s` is not positive or a value is not finite.
    ///
    /// With `L = -Delta ≻ 0` (tridiagonal), `G = L^-1`, `k2 = eps/(2 hbar^2)
    /// = eps (N^2 - 1)/8` (exact in binary), the noise differences `e_i = d
    /// xi_i` less their mean on the block (`[E - mu, [E - mu, G]] = [E, [E,
    /// G]]`), `S2 = sum_i E_i^2` and `t` a power of two near `max S2`:
    ///
    /// ```text
    /// s P - Q = s D_c + sum_k g_k U_k L^-1 U_k,
    /// (g, U) = (s eps, I), (k2/(2t), S2 + t), (-k2/(2t), S2 - t), (-2 k2, E_i)
    /// ```
    ///
    /// using `S2 G + G S2 = ((S2 + t) G (S2 + t) - (S2 - t) G (S2 - t))/(2t)`.
    /// Every `U` is diagonal, so this is the Schur complement of the lower
    /// block in `B = [[s D_c, U_1, ...], [U_1, -L/g_1, ...], ...]`, and by
    /// Haynsworth `s P - Q ≻ 0` iff `B` has `n + n #{g < 0}` positive and
    /// `n #{g > 0}` negative eigenvalues (`-L/g` has the sign of `-g`). The
    /// unknowns are interleaved per entry (the lifted ones first), so `B` is
    /// banded. The lifting is chosen over the congruence by `Delta` (which
    /// squares `L`'s condition) after measurement; `fluid::walls_check`
    /// folds the `eps` Gram into the two squares instead, one unknown per
    /// entry fewer. The claim is about
    /// the exact `B` built from the stored `c`, `Delta` and noise values:
    /// each entry's rounding is bounded.
    fn lifted(&self, c: &[f64], eps: f64, s: f64, tracked: bool) -> Option<(Bounded, (usize, usize))> {
        let n = self.len();
        if !(s.is_finite() && s > 0.0) || c.iter().any(|x| !x.is_finite()) {
            return None;
        }
        let big_n = (n + self.m) as f64;
        let k2 = eps * (big_n * big_n - 1.0) / 8.0;
        // The noise fields that are not constant on the block, centred
        // (a constant field commutes with G: no term).
        let centred: Vec<Vec<f64>> = self
            .d_xi
            .iter()
            .filter(|d| d.iter().any(|x| *x != d[0]))
            .map(|d| {
                let mu = d.iter().sum::<f64>() / n as f64;
                d.iter().map(|x| x - mu).collect()
            })
            .collect();
        let k = centred.len();
        let s2: Vec<f64> = (0..n).map(|j| centred.iter().map(|e| e[j] * e[j]).sum()).collect();
        if s2.iter().any(|x| !x.is_finite()) {
            return None;
        }
        let s2max = s2.iter().fold(0.0f64, |a, x| a.max(*x));
        let t = nearest_power_of_two(s2max);
        // (g_k, whether U_k is S2 + t, S2 - t, I or E_i)
        let mut g = vec![s * eps];
        if k > 0 {
            g.push(k2 / (2.0 * t));
            g.push(-k2 / (2.0 * t));
            g.extend(std::iter::repeat_n(-2.0 * k2, k));
        }
        // Each g must be exact (k2 is, t is a power of two): a quotient
        // below the normal range is rounded, so nothing is claimed then.
        if g.iter().any(|x| !(x.is_finite() && x.abs() >= f64::MIN_POSITIVE)) {
            return None;
        }
        // Haynsworth's count needs the stored L = -Delta ≻ 0: proved once
        // per block, not assumed.
        if !self.laplacian_definite {
            return None;
        }
        let lifted = g.len();
        let stride = lifted + 1;
        let idx = |j: usize, v: usize| j * stride + v; // v = lifted: the unknown x_j itself
        let mut b = if tracked { Bounded::new(n * stride, stride) } else { Bounded::untracked(n * stride, stride) };
        // S2 +- t: k squares, their sum and t; a square below the normal
        // range is off by at most 2^-1075 while t >= 2^-1022 (`pow2`
        // clamps), so underflow adds at most k u relative: k more roundings.
        let sum_rounds = 2 * k + 4;
        for j in 0..n {
            b.set(idx(j, lifted), idx(j, lifted), s * c[j], 1);
            b.set(idx(j, 0), idx(j, lifted), 1.0, 0);
            if k > 0 {
                b.set(idx(j, 1), idx(j, lifted), s2[j] + t, sum_rounds);
                b.set_with_error(idx(j, 2), idx(j, lifted), s2[j] - t, s2[j] + t, sum_rounds);
                for (i, e) in centred.iter().enumerate() {
                    b.set(idx(j, 3 + i), idx(j, lifted), e[j], 1);
                }
            }
            // -L/g = Delta/g (tridiagonal)
            for l in j.saturating_sub(1)..=j {
                let delta = self.lap.get(j, l);
                for (v, gv) in g.iter().enumerate() {
                    b.set(idx(j, v), idx(l, v), delta / gv, 1);
                }
            }
        }
        let positive_g = g.iter().filter(|x| **x > 0.0).count();
        let target = (n + n * (lifted - positive_g), n * positive_g);
        Some((b, target))
    }

    /// Whether `lambda_max(Q, P) < s` in this block, given `P ≻ 0`: proved
    /// (`verified`) or as floating point counts it (for the search).
    pub(super) fn below(&self, choice: &Choice, s: f64, verified: bool) -> bool {
        if choice.energy == 0.0 || self.d_xi.iter().all(|d| d.iter().all(|x| *x == d[0])) {
            // Q = 0 on this block (no energy, or every field constant on it).
            return s > 0.0;
        }
        let c = self.c(choice);
        let Some((b, target)) = self.lifted(&c, choice.energy, s, verified) else { return false };
        let inertia = if verified { b.inertia() } else { b.plain_inertia() };
        inertia == Some(target)
    }

    /// `lambda_max(Q, P)` by bisection on `s` with the floating-point
    /// inertia of the lifting ([`Block::lifted`]), from `guess`, to the
    /// relative width `tol`: `O(n)` a step, against Lanczos' `O(k n)` with
    /// reorthogonalisation and a dense Ritz problem (at N = 1024 Lanczos
    /// took 17 s a sweep). The upper end of the bracket is returned; it is
    /// the starting point of the verified bound.
    ///
    /// `tick` is called once per inertia (the unit of progress).
    pub(super) fn lambda_max(&self, choice: &Choice, guess: f64, tol: f64, tick: &(dyn Fn() + Sync)) -> BlockResult {
        let done = |lambda_max: f64, residual: f64| BlockResult { m: self.m, lambda_max, residual };
        if choice.energy == 0.0 || self.d_xi.iter().all(|d| d.iter().all(|x| *x == d[0])) {
            return done(0.0, 0.0); // Q = 0
        }
        let below = |s: f64| {
            tick();
            self.below(choice, s, false)
        };
        let mut hi = if guess.is_finite() && guess > 0.0 { guess } else { 1.0 };
        let mut lo;
        // A bracket from the guess, 1e-6 wide at first (the search moves
        // the guess little), widened sixteenfold a step up to halving.
        let mut width = 1e-6;
        if below(hi) {
            loop {
                lo = hi * (1.0 - width);
                if !below(lo) {
                    break;
                }
                hi = lo;
                width = (16.0 * width).min(0.5);
                if lo < f64::MIN_POSITIVE {
                    // (Q has trace 0 and is not 0 here: lambda_max > 0.)
                    return done(hi, 1.0);
                }
            }
        } else {
            loop {
                lo = hi;
                hi *= 1.0 + width;
                if below(hi) {
                    break;
                }
                width = (16.0 * width).min(1.0);
                if !hi.is_finite() {
                    return done(f64::INFINITY, f64::INFINITY);
                }
            }
        }
        while hi - lo > tol * hi {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if below(mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        done(hi, (hi - lo) / hi)
    }

    /// `max |x.(P K y) - y.(P K x)|` relative, `K = D_{d pi} + D_{d omega} G`,
    /// over a few fixed probe pairs: `P A` is skew exactly when this is 0.
    pub(super) fn drift_residual(&self, choice: &Choice) -> f64 {
        let n = self.len();
        let c = self.c(choice);
        let eps = choice.energy;
        let pk = |x: &[f64]| -> Vec<f64> {
            let mut g = vec![0.0; n];
            self.g(x, &mut g);
            let kx: Vec<f64> = (0..n).map(|j| self.d_pi[j] * x[j] + self.d_omega[j] * g[j]).collect();
            let mut gk = vec![0.0; n];
            self.g(&kx, &mut gk);
            (0..n).map(|j| eps * gk[j] + c[j] * kx[j]).collect()
        };
        let mut worst: f64 = 0.0;
        for p in 0..3 {
            let x: Vec<f64> = (0..n).map(|j| ((j * 7 + p * 13) as f64 * 0.61803).sin()).collect();
            let y: Vec<f64> = (0..n).map(|j| ((j * 3 + p * 5 + 1) as f64 * 1.3).cos()).collect();
            let (pkx, pky) = (pk(&x), pk(&y));
            let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(a, b)| a * b).sum::<f64>();
            let norm = |a: &[f64]| dot(a, a).sqrt();
            let scale = norm(&x) * norm(&pky) + norm(&y) * norm(&pkx);
            if scale > 0.0 {
                worst = worst.max((dot(&x, &pky) - dot(&y, &pkx)).abs() / scale);
            }
        }
        worst
    }

    /// The largest real part of the drift's eigenvalues, `max |Im mu| / hbar`
    /// over the eigenvalues `mu` of `K` (dense).
    pub(super) fn growth_rate(&self, hbar: f64) -> f64 {
        let n = self.len();
        let mut k = nalgebra::DMatrix::zeros(n, n);
        let mut e = vec![0.0; n];
        let mut col = vec![0.0; n];
        for j in 0..n {
            e.iter_mut().for_each(|v| *v = 0.0);
            e[j] = 1.0;
            self.g(&e, &mut col);
            for i in 0..n {
                k[(i, j)] = self.d_omega[i] * col[i] + if i == j { self.d_pi[i] } else { 0.0 };
            }
        }
        match crate::eigen::real_eigenvalues(&k) {
            Some(ev) => ev.iter().map(|z| z.im.abs()).fold(0.0, f64::max) / hbar,
            None => f64::NAN,
        }
    }
}

/// Whether `-Delta ≻ 0` is proved for the stored `Delta` (a tridiagonal
/// verified Cholesky).
fn minus_laplacian_is_definite(t: &Tridiagonal) -> bool {
    let n = t.len();
    let mut minus = SymBanded::zeros(n, 1);
    for j in 0..n {
        minus.add(j, j, -t.diag[j]);
        if j > 0 {
            minus.add(j, j - 1, -t.off[j - 1]);
        }
    }
    positive_definite(Symmetric::Banded(&minus), 0.0).proved
}

/// Whether `P = -eps Delta^-1 + D_c` (`eps` 0 or ±1) is positive
/// definite, proved for the exact congruent `Delta P Delta = -eps Delta +
/// Delta D_c Delta` (pentadiagonal, the inertia of `P`) of the stored `c`
/// and `Delta`: each entry's rounding is bounded (three products of three
/// factors and a sum of four terms: `gamma_5` of the terms' magnitudes; a
/// product whose partial product underflows before its last factor proves
/// nothing), and the verified inertia test of `numerics::banded::Bounded`
/// decides. False when unsure. A test of the matrix as computed, with no
/// radius, would not prove the stated claim: it passes a 2 x 2 case that
/// exact arithmetic refutes (the test below).
fn congruent_form_is_definite(t: &Tridiagonal, c: &[f64], eps: f64) -> bool {
    let n = t.len();
    if n == 0 || c.len() != n || !(eps == 0.0 || eps.abs() == 1.0) {
        return false;
    }
    let mut b = Bounded::new(n, 2);
    for i in 0..n {
        for j in i.saturating_sub(2)..=i {
            let first = -eps * t.get(i, j); // eps is 0 or ±1: exact
            let (mut v, mut scale) = (first, first.abs());
            for k in j.saturating_sub(1)..=(i + 1).min(n - 1) {
                let Some(p) = numerics::banded::product_without_early_underflow(&[t.get(i, k), c[k], t.get(k, j)])
                else {
                    return false;
                };
                v += p;
                scale += p.abs();
            }
            if !(v.is_finite() && scale.is_finite()) {
                return false;
            }
            b.set_with_error(i, j, v, scale, 5);
        }
    }
    b.inertia() == Some((n, 0))
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_definiteness_of_p_is_proved_for_the_exact_congruent_matrix() {
        // The float test of the computed Delta P Delta says definite;
        // exact arithmetic says indefinite.
        let t = Tridiagonal { diag: vec![-34.106100004537396, -2.1503007814110386], off: vec![0.5492700821132699] };
        let c = [-0.029321712938786146, 0.005637516160197854];
        let q = |x: f64| exact::Rational::from_float(x).unwrap();
        let delta = exact::Matrix::from_fn(2, 2, |i, j| q(t.get(i, j)));
        let dc = exact::Matrix::from_fn(2, 2, |i, j| if i == j { q(c[i]) } else { q(0.0) });
        let exact_p = delta.mul(&dc).mul(&delta).sub(&delta);
        let inertia = exact_p.inertia();
        assert_eq!((inertia.positive, inertia.negative), (1, 1));
        assert!(!congruent_form_is_definite(&t, &c, 1.0));
        // and a clearly definite one is proved: c = 1, eps = 0 gives Delta^2
        assert!(congruent_form_is_definite(&t, &[1.0, 1.0], 0.0));
    }

    use super::*;
    use crate::analysis::hbar;
    use nalgebra::DMatrix;

    /// A block of `N` with noise differences `d` (the equilibrium data are
    /// not used by the lifting, which takes `c` directly).
    fn test_block(n: usize, m: usize, d: Vec<Vec<f64>>) -> Block {
        let lap = block(n, m);
        let len = n - m;
        Block {
            m,
            factor: lap.factor().unwrap(),
            d_pi: vec![0.0; len],
            d_omega: vec![1.0; len],
            d_xi: d,
            degenerate: vec![false; len],
            laplacian_definite: minus_laplacian_is_definite(&lap),
            lap,
        }
    }

    /// `lambda_max(Q, P)` densely from the block formulas (`P = eps G + D_c`,
    /// `Q = -(eps/(2 hbar^2)) sum [D, [D, G]]`, `G = -Delta^-1` by nalgebra's
    /// inverse), through the Cholesky factor of `P`.
    fn dense_lambda_max(blk: &Block, c: &[f64], eps: f64) -> f64 {
        let len = blk.len();
        let n = len + blk.m;
        let delta = DMatrix::from_fn(len, len, |i, j| blk.lap.get(i, j));
        let g = -delta.try_inverse().unwrap();
        let p = &g * eps + DMatrix::from_diagonal(&nalgebra::DVector::from_vec(c.to_vec()));
        let k2 = eps / (2.0 * hbar(n) * hbar(n));
        let mut q = DMatrix::zeros(len, len);
        for d in &blk.d_xi {
            let dd = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(d.clone()));
            let inner = &dd * &g - &g * &dd;
            q -= (&dd * &inner - &inner * &dd) * k2;
        }
        let l = p.cholesky().expect("P positive definite").l();
        let li = l.try_inverse().unwrap();
        let m = &li * q * li.transpose();
        let m = (&m + m.transpose()) * 0.5;
        m.symmetric_eigenvalues().iter().copied().fold(f64::NEG_INFINITY, f64::max)
    }

    /// The lifting decides `lambda_max(Q, P) < s` sharply, against the dense
    /// eigenvalue: proved at `s = lambda (1 + 1e-9)`, refused (proved or
    /// not) at `lambda (1 - 1e-9)`, for both signs of the energy and one or
    /// two noise fields, on a well-conditioned `P` (`c` of the size of `G`'s
    /// diagonal; the dense eigenvalue is then accurate to about 1e-14).
    #[test]
    fn the_lifting_decides_lambda_max_against_the_dense_eigenvalue() {
        let n = 12;
        for m in [1usize, 3, 7] {
            let len = n - m;
            let d1: Vec<f64> = (0..len).map(|j| (0.7 * j as f64).sin()).collect();
            let d2: Vec<f64> = (0..len).map(|j| 0.3 * (j as f64 / len as f64).powi(2)).collect();
            for noise in [vec![d1.clone()], vec![d1.clone(), d2.clone()]] {
                let blk = test_block(n, m, noise);
                let gmax = 1.0 / (m * (m + 1)) as f64; // G's largest eigenvalue, 1/l(l+1) at l = m
                for (eps, c) in [
                    (1.0, (0..len).map(|j| 0.01 * gmax * (1.0 + (j % 3) as f64)).collect::<Vec<f64>>()),
                    (-1.0, (0..len).map(|j| 2.0 * gmax * (1.0 + 0.1 * j as f64)).collect()),
                ] {
                    let lambda = dense_lambda_max(&blk, &c, eps);
                    assert!(lambda > 0.0, "m {m}: Q has trace 0, so a positive eigenvalue");
                    let (b_hi, target) = blk.lifted(&c, eps, lambda * (1.0 + 1e-9), true).unwrap();
                    assert_eq!(b_hi.inertia(), Some(target), "m {m}, eps {eps}: lambda {lambda}");
                    let (b_lo, target) = blk.lifted(&c, eps, lambda * (1.0 - 1e-9), true).unwrap();
                    assert_ne!(b_lo.inertia(), Some(target), "m {m}, eps {eps}");
                    assert_ne!(b_lo.plain_inertia(), Some(target), "m {m}, eps {eps}");
                }
            }
        }
    }

    /// The pivot recurrences give the diagonal of `G = -Delta^-1` (nalgebra's
    /// dense inverse as the reference).
    #[test]
    fn g_diagonal_matches_the_dense_inverse() {
        for (n, m) in [(9usize, 1usize), (16, 5), (33, 32)] {
            let blk = test_block(n, m, vec![]);
            let len = n - m;
            let g = -DMatrix::from_fn(len, len, |i, j| blk.lap.get(i, j)).try_inverse().unwrap();
            for (j, x) in blk.g_diagonal().iter().enumerate() {
                assert!((x - g[(j, j)]).abs() <= 1e-13 * g[(j, j)].abs(), "N {n}, m {m}, j {j}");
            }
        }
    }

    /// A field constant on the block has `[D, G] = 0`: no term, and with no
    /// other field `Q = 0`, so every `s > 0` is above `lambda_max`.
    #[test]
    fn a_constant_field_adds_nothing() {
        let blk = test_block(10, 2, vec![vec![0.5; 8]]);
        let choice = Choice { energy: 1.0, momentum: 0.0, free_curvature: 1.0 };
        assert!(blk.below(&choice, 1e-300, true));
        assert!(!blk.below(&choice, 0.0, true));
    }
}
