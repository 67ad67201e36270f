//! The stochastic energy–Casimir–momentum analysis of a zonal Zeitlin
//! equilibrium, block by block (see `docs/zeitlin.md` for the derivation).
//!
//! Model: `dW = [P, W]/hbar dt + sum_i [X_i, W]/hbar o dB^i`, `Delta_N P = W`,
//! `hbar = 2/sqrt(N^2 - 1)`, with `W_e = i diag(omega)` and zonal noise
//! `X_i = i diag(xi_i)`. A perturbation `w` splits by its diagonal `m`; on
//! diagonal `m >= 1` (entries `v_j = w[j, j+m]`, write `d f_j = f_j - f_{j+m}`)
//!
//! * drift `v' = (i/hbar) (D_{d pi} + D_{d omega} G) v`, `G = -Delta_m^{-1}`;
//! * noise `B_i = (i/hbar) D_{d xi_i}`;
//! * the conserved functional `L = eps H + tr Phi(W)/N + beta J`
//!   (`J = <W, T_10>`-type momentum, `tau_j = j - (N-1)/2`) has, up to the
//!   factor `2/N`, the Hessian `P = eps G + D_c`,
//!   `c_j = (eps d pi_j + beta m) / d omega_j` (the first variation fixes
//!   `Phi'(omega_j) = eps pi_j - beta tau_j` + const);
//! * the generator form is `Q = -(eps / (2 hbar^2)) sum_i [D_i, [D_i, G]]`:
//!   the Casimir and momentum parts commute with the diagonal noise.
//!
//! The diagonal `m = 0` carries neither drift nor noise (`Q = 0`), and its
//! Hessian `eps G_0 + diag(Phi''(omega_j))` is made definite by `Phi''`.
//! `Sigma^2 = max_m lambda_max(Q_m, P_m)` over the blocks, minimised over
//! the direction `(eps, beta)` of the family (a circle: `P` is defined up to a
//! positive factor). With `eps = 0` (a strictly monotone profile makes the
//! Casimir–momentum form alone definite) `Q = 0` and `Sigma^2 = 0`.

use crate::laplacian::{block, solve_zonal, Tridiagonal, TridiagonalFactor};
use numerics::banded::{Bounded, SymBanded};
use numerics::definite::{positive_definite, Symmetric};
use numerics::minimise::{golden_section_until, golden_section_with_ends};
use numerics::scaling::{nearest_power_of_two, Rescaling};
use outcome::{Cancelled, Progress, Verdict, VerificationLevel};
use rayon::prelude::*;

/// `hbar = 2 / sqrt(N^2 - 1)`, the time scale of quflow's bracket.
pub fn hbar(n: usize) -> f64 {
    2.0 / (((n * n) as f64) - 1.0).sqrt()
}

/// A zonal Zeitlin equilibrium with zonal noise.
#[derive(Clone, Debug, PartialEq)]
pub struct ZeitlinProblem {
    /// `N >= 2`.
    pub n: usize,
    /// `omega_j`, `W_e = i diag(omega)` (trace-free).
    pub omega: Vec<f64>,
    /// The noise stream matrices' diagonals: `X_i = i diag(xi_i)`.
    pub noise: Vec<Vec<f64>>,
}

/// Settings, with documented defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct ZeitlinSettings {
    /// Relative width of the bisection bracket of each block's
    /// `lambda_max`. Default 1e-10.
    pub tolerance: f64,
    /// Golden-section steps of the minimisation over the direction. Default 40.
    pub golden_steps: usize,
    /// Largest `N` for which, without a definite form, the drift's
    /// eigenvalues are computed densely per block. Default 128.
    pub instability_max_n: usize,
    /// Largest `N` for which the energy–Casimir–momentum family (`eps = ±1`)
    /// is searched when the Casimir–momentum form is not definite (about
    /// 100 to 200 sweeps over the blocks, `O(N^2)` each: some 10 s at
    /// N = 1024 and 40 s at N = 2048 on two cores, about 4x per doubling).
    /// Default 1024; above it the verdict is `inconclusive` and says so.
    pub energy_search_max_n: usize,
    /// Whether the Casimir–momentum form alone (`eps = 0`, no energy) may
    /// be chosen. Default true; false restricts the family to the paper's
    /// energy–Casimir(–momentum) functionals `±H + C + beta J`.
    pub casimir_momentum: bool,
}

impl Default for ZeitlinSettings {
    fn default() -> Self {
        ZeitlinSettings {
            tolerance: 1e-10,
            golden_steps: 40,
            instability_max_n: 128,
            energy_search_max_n: 1024,
            casimir_momentum: true,
        }
    }
}

/// Why the analysis could not run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ZeitlinError {
    /// The input is malformed (the message names the field).
    #[error("{0}")]
    Input(String),
    /// A solve failed in floating point.
    #[error("numerical breakdown: {0}")]
    Numerical(String),
    /// The analysis was stopped through its [`Progress`] before it ended.
    #[error(transparent)]
    Cancelled(#[from] Cancelled),
}

/// The conserved functional `eps H + C_Phi + beta J` whose Hessian is `P`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Choice {
    /// The energy coefficient `eps`.
    pub energy: f64,
    /// The momentum coefficient `beta`.
    pub momentum: f64,
    /// `Phi''` at a repeated eigenvalue of `W_e` pairing two entries of one
    /// block (`c_j` there is free), and on the diagonal block.
    pub free_curvature: f64,
}

/// One block's result.
#[derive(Clone, Debug, PartialEq)]
pub struct BlockResult {
    /// The diagonal `m`.
    pub m: usize,
    /// `lambda_max(Q_m, P_m)`: the upper end of a bisection bracket on the
    /// inertia of the lifting (floating point, unproved; not floored).
    pub lambda_max: f64,
    /// The bracket's relative width.
    pub residual: f64,
}

/// What the analysis found.
#[derive(Clone, Debug, PartialEq)]
pub struct ZeitlinAnalysis {
    /// The verdict.
    pub verdict: Verdict,
    /// What the verdict rests on.
    pub level: VerificationLevel,
    /// One sentence.
    pub reason: String,
    /// `|[P_e, W_e]| / hbar` (zero: both diagonal).
    pub equilibrium_residual: f64,
    /// `max_i |[X_i, W_e]| / hbar` (zero: both diagonal).
    pub noise_residual: f64,
    /// The chosen functional, when one is definite.
    pub choice: Option<Choice>,
    /// `Sigma^2 = max(0, max_m lambda_max)` at the choice (the bisection
    /// estimates: upper ends of floating-point brackets, unproved).
    pub sigma2: Option<f64>,
    /// A proved upper bound on `Sigma^2` (`verified_float`): `s P_m - Q_m`
    /// is shown positive definite in every block by a verified inertia test
    /// of a banded lifting (docs/zeitlin.md, "Sigma^2"). `Some(0)` under exact
    /// structure (`Q = 0`).
    pub sigma2_upper: Option<f64>,
    /// Whether the minimum over the family is attained (false when it is
    /// approached at the edge of the definite arc, or at the search's bound on
    /// `beta`, as for monotone profiles, whose infimum over `eps = ±1` is 0).
    pub attained: bool,
    /// Per block (`m = 1..N-1`), at the choice.
    pub blocks: Vec<BlockResult>,
    /// The largest relative drift residual `|sym(P A)|` seen on random probes.
    pub drift_residual: f64,
    /// The fastest growth rate `max Re(lambda(A))` when computed.
    pub growth_rate: Option<f64>,
    /// `hbar`.
    pub hbar: f64,
}

/// Per-block data independent of the choice.
struct Block {
    m: usize,
    lap: Tridiagonal,
    factor: TridiagonalFactor,
    d_pi: Vec<f64>,
    d_omega: Vec<f64>,
    d_xi: Vec<Vec<f64>>,
    /// Entries whose two eigenvalues coincide (`d omega = 0`).
    degenerate: Vec<bool>,
    /// `-Delta ≻ 0` proved (a tridiagonal verified Cholesky), once per
    /// block: Haynsworth's count in [`Block::lifted`] needs it.
    laplacian_definite: bool,
}

impl Block {
    fn len(&self) -> usize {
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
    fn definite(&self, choice: &Choice) -> bool {
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
    fn lambda_min(&self, choice: &Choice, tick: &(dyn Fn() + Sync)) -> f64 {
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
    fn g_diagonal(&self) -> Vec<f64> {
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
    fn below(&self, choice: &Choice, s: f64, verified: bool) -> bool {
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
    fn lambda_max(&self, choice: &Choice, guess: f64, tol: f64, tick: &(dyn Fn() + Sync)) -> BlockResult {
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
    fn drift_residual(&self, choice: &Choice) -> f64 {
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
    fn growth_rate(&self, hbar: f64) -> f64 {
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

/// Run the analysis.
///
/// ```
/// use zeitlin::analysis::{analyse, ZeitlinProblem, ZeitlinSettings};
/// use zeitlin::zonal::quantise;
/// // omega = z + 0.3 z^3 (strictly monotone) with zonal noise 0.1 z^2:
/// // the Casimir–momentum form alone is definite, and Sigma^2 = 0.
/// let n = 16;
/// let omega = quantise(n, |z| z + 0.3 * z * z * z).diagonal;
/// let noise = vec![quantise(n, |z| 0.1 * z * z).diagonal];
/// let a = analyse(&ZeitlinProblem { n, omega, noise }, &ZeitlinSettings::default()).unwrap();
/// assert_eq!(a.verdict, outcome::Verdict::Stable);
/// assert_eq!(a.sigma2, Some(0.0));
/// ```
pub fn analyse(problem: &ZeitlinProblem, settings: &ZeitlinSettings) -> Result<ZeitlinAnalysis, ZeitlinError> {
    analyse_with(problem, settings, &Progress::new())
}

/// [`analyse`], counting block operations in `progress` and stopping with
/// [`ZeitlinError::Cancelled`] soon after [`Progress::cancel`].
///
/// ```
/// use outcome::Progress;
/// use zeitlin::analysis::{analyse_with, ZeitlinError, ZeitlinProblem, ZeitlinSettings};
/// use zeitlin::zonal::quantise;
/// let n = 16;
/// let problem = ZeitlinProblem { n, omega: quantise(n, |z| z + 0.3 * z * z * z).diagonal, noise: vec![] };
/// let progress = Progress::new();
/// assert!(analyse_with(&problem, &ZeitlinSettings::default(), &progress).is_ok());
/// let (done, total) = progress.snapshot();
/// assert!(done > 0 && done == total);
/// let stopped = Progress::new();
/// stopped.cancel();
/// assert!(matches!(analyse_with(&problem, &ZeitlinSettings::default(), &stopped), Err(ZeitlinError::Cancelled(_))));
/// ```
pub fn analyse_with(
    problem: &ZeitlinProblem,
    settings: &ZeitlinSettings,
    progress: &Progress,
) -> Result<ZeitlinAnalysis, ZeitlinError> {
    validate(problem)?;
    // The problem is homogeneous: omega -> k omega scales the drift's rates
    // by k (and the momentum coefficient by k) and leaves Sigma^2 alone;
    // xi -> k xi scales Sigma^2 by k^2. Solve it with both scaled to unit
    // size (values near 1e308 would overflow in the solves), then scale back.
    let max_abs = |v: &[f64]| v.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    // Powers of two, so that the scaling is exact and a bound proved for the
    // scaled problem is one for the problem as given.
    let r_omega = Rescaling::nearest(max_abs(&problem.omega));
    let r_xi = Rescaling::nearest(problem.noise.iter().map(|x| max_abs(x)).fold(0.0f64, f64::max));
    let scaled = ZeitlinProblem {
        n: problem.n,
        omega: problem.omega.iter().map(|x| x * r_omega.down()).collect(),
        noise: problem.noise.iter().map(|xi| xi.iter().map(|x| x * r_xi.down()).collect()).collect(),
    };
    // (unless an entry fell below the normal range: then it was rounded)
    let exact = |v: &[f64], w: &[f64], f: f64| v.iter().zip(w).all(|(x, y)| y * f == *x);
    let exact_scaling = exact(&problem.omega, &scaled.omega, r_omega.up())
        && problem.noise.iter().zip(&scaled.noise).all(|(x, y)| exact(x, y, r_xi.up()));
    let mut a = analyse_normalised(&scaled, settings, progress)?;
    // A cancelled search ends early with meaningless values: never a result.
    progress.check()?;
    progress.settle();
    for b in &mut a.blocks {
        b.lambda_max = r_xi.square(b.lambda_max);
    }
    if let Some(c) = a.choice.as_mut() {
        c.momentum *= r_omega.up();
    }
    a.growth_rate = a.growth_rate.map(|r| r * r_omega.up());
    if let (Verdict::LinearlyUnstable, Some(rate)) = (a.verdict, a.growth_rate) {
        // The reason was written in the normalised units.
        a.reason = unstable_reason(rate);
    }
    // The stated bound is the proved one raised by 1e-8 (rounded up): a
    // certificate's value edited within the check's tolerance (1e-9) is
    // still at least the proved bound, so still true. A bound that left
    // the normal range is not stated.
    a.sigma2_upper = a
        .sigma2_upper
        .map(|u| if u == 0.0 { 0.0 } else { r_xi.square(u * (1.0 + 1e-8)).next_up() })
        .filter(|u| exact_scaling && u.is_finite() && (*u == 0.0 || *u >= f64::MIN_POSITIVE));
    if a.level == VerificationLevel::VerifiedFloat && a.sigma2_upper.is_none() {
        a.level = VerificationLevel::Numerical;
    }
    if let Some(s) = a.sigma2 {
        if r_xi.out_of_range(s).is_some() {
            a.verdict = Verdict::Inconclusive;
            a.reason =
                "a definite form was found, but Sigma^2 lies outside the range of double precision: rescale the noise"
                    .into();
            a.sigma2 = None;
            a.sigma2_upper = None;
            a.level = VerificationLevel::Numerical;
        } else {
            a.sigma2 = Some(r_xi.square(s));
        }
    }
    Ok(a)
}

fn unstable_reason(rate: f64) -> String {
    format!("no energy–Casimir–momentum form is definite, and the drift has an eigenvalue with real part {rate:.6e}")
}

fn validate(problem: &ZeitlinProblem) -> Result<(), ZeitlinError> {
    let n = problem.n;
    if n < 2 {
        return Err(ZeitlinError::Input(format!("$.zeitlin.N: must be at least 2, got {n}")));
    }
    if problem.omega.len() != n {
        return Err(ZeitlinError::Input(format!("$.zeitlin.equilibrium: {} values for N = {n}", problem.omega.len())));
    }
    for (i, xi) in problem.noise.iter().enumerate() {
        if xi.len() != n {
            return Err(ZeitlinError::Input(format!("$.zeitlin.noise[{i}]: {} values for N = {n}", xi.len())));
        }
    }
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    if !finite(&problem.omega) || !problem.noise.iter().all(|x| finite(x)) {
        return Err(ZeitlinError::Input("$.zeitlin: a value is not finite".into()));
    }
    Ok(())
}

/// Progress is counted in block operations (a definiteness test, a
/// `lambda_min`, a bisection for `lambda_max`...), planned per phase at
/// its worst case. Once cancelled, every block operation returns at once
/// with a value that ends the search (not definite, `-inf` margin,
/// infinite `lambda_max`), and [`analyse_with`] turns the result into
/// [`ZeitlinError::Cancelled`].
fn analyse_normalised(
    problem: &ZeitlinProblem,
    settings: &ZeitlinSettings,
    progress: &Progress,
) -> Result<ZeitlinAnalysis, ZeitlinError> {
    let n = problem.n;
    // Progress counts definiteness tests and inertias of one block (each
    // O(N)). The plan, in passes over the blocks: build them, G's
    // diagonal, the Casimir–momentum tests, the energy search for each sign
    // (measured: 126 to 138 passes for the sign that succeeds, 66 to 76 for
    // the other, at N = 64 to 1024), then lambda_max everywhere, the drift
    // residual and the proof (19 to 21).
    let per_pass = (n - 1) as u64;
    let search_passes = 140;
    progress.plan((1 + 1 + 2 + 2 * search_passes + 20) * per_pass);
    let hbar = hbar(n);
    let omega = &problem.omega;
    let pi = solve_zonal(omega).ok_or_else(|| ZeitlinError::Numerical("the zonal Poisson solve failed".into()))?;
    let scale_omega = omega.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    let blocks: Vec<Block> = (1..n)
        .map(|m| {
            progress.check()?;
            progress.step(1);
            let lap = block(n, m);
            let factor =
                lap.factor().ok_or_else(|| ZeitlinError::Numerical(format!("the Laplacian of diagonal {m}")))?;
            let len = n - m;
            let d = |f: &[f64]| -> Vec<f64> { (0..len).map(|j| f[j] - f[j + m]).collect() };
            let d_omega = d(omega);
            let degenerate = d_omega.iter().map(|x| x.abs() <= 1e-12 * scale_omega).collect();
            Ok(Block {
                m,
                factor,
                d_pi: d(&pi),
                d_omega,
                d_xi: problem.noise.iter().map(|x| d(x)).collect(),
                degenerate,
                laplacian_definite: minus_laplacian_is_definite(&lap),
                lap,
            })
        })
        .collect::<Result<_, ZeitlinError>>()?;
    let mut analysis = ZeitlinAnalysis {
        verdict: Verdict::Inconclusive,
        level: VerificationLevel::Numerical,
        reason: String::new(),
        equilibrium_residual: 0.0,
        noise_residual: 0.0,
        choice: None,
        sigma2: None,
        sigma2_upper: None,
        attained: false,
        blocks: vec![],
        drift_residual: 0.0,
        growth_rate: None,
        hbar,
    };
    if scale_omega == 0.0 {
        analysis.reason =
            "W_e = 0: every state nearby is an equilibrium of the linearisation only; nothing to certify".into();
        return Ok(analysis);
    }
    // The momentum coefficient's unit, so that (eps, beta) are comparable.
    let beta_unit = blocks
        .iter()
        .flat_map(|b| b.d_pi.iter().map(move |x| x.abs() / b.m as f64))
        .fold(0.0f64, f64::max)
        .max(f64::MIN_POSITIVE);
    // P is defined up to a positive factor: the energy coefficient is
    // normalised to eps = +1 (Arnold's first theorem), -1 (his second) or 0
    // (the Casimir–momentum form alone), and b = beta / beta_unit is free.
    let c_scale = |eps: f64, b: f64| -> f64 {
        blocks
            .iter()
            .flat_map(|blk| (0..blk.len()).filter(|&j| !blk.degenerate[j]).map(move |j| (blk, j)))
            .map(|(blk, j)| ((eps * blk.d_pi[j] + b * beta_unit * blk.m as f64) / blk.d_omega[j]).abs())
            .fold(eps.abs() / 2.0, f64::max)
    };
    let choice_at = |eps: f64, b: f64| -> Choice {
        Choice { energy: eps, momentum: b * beta_unit, free_curvature: 1e3 * c_scale(eps, b).max(f64::MIN_POSITIVE) }
    };
    // Pairs of equal eigenvalues force eps d pi_j + beta m = 0.
    let constraints: Vec<(f64, f64)> = blocks
        .iter()
        .flat_map(|blk| {
            (0..blk.len()).filter(|&j| blk.degenerate[j]).map(move |j| (blk.d_pi[j], blk.m as f64 * beta_unit))
        })
        .collect();
    let allowed = |eps: f64, b: f64| -> bool {
        constraints.iter().all(|(dp, mu)| (eps * dp + b * mu).abs() <= 1e-9 * (eps.abs() * dp.abs() + b.abs() * mu))
    };
    // The choice is formed once (c_scale is a pass over every block), not per block.
    // Once cancelled: nothing is definite, margins are -inf and lambda_max
    // is infinite, which ends every loop of the search at once.
    let stop = || -> bool {
        progress.step(1);
        progress.is_cancelled()
    };
    let tick = || progress.step(1);
    let definite = |eps: f64, b: f64| -> bool {
        allowed(eps, b) && {
            let choice = choice_at(eps, b);
            blocks.par_iter().all(|blk| !stop() && blk.definite(&choice))
        }
    };
    // min_m lambda_min(P_m(b)) / scale: concave in b (P is affine in b).
    let margin = |eps: f64, b: f64| -> f64 {
        let choice = choice_at(eps, b);
        blocks
            .par_iter()
            .map(|blk| if stop() { f64::NEG_INFINITY } else { blk.lambda_min(&choice, &tick) })
            .reduce(|| f64::INFINITY, f64::min)
            / c_scale(eps, b).max(eps.abs()).max(f64::MIN_POSITIVE)
    };
    // The last lambda_max of each block, as bisection guesses: the search
    // moves b a little at a time.
    let last: std::cell::RefCell<Vec<f64>> = std::cell::RefCell::new(vec![f64::NAN; blocks.len()]);
    let tol = settings.tolerance;
    let lambda_max = |blk: &Block, choice: &Choice, guess: f64| -> BlockResult {
        if stop() {
            return BlockResult { m: blk.m, lambda_max: f64::INFINITY, residual: f64::NAN };
        }
        blk.lambda_max(choice, guess, tol, &tick)
    };
    let every_block = |eps: f64, b: f64| -> Vec<BlockResult> {
        let choice = choice_at(eps, b);
        let guesses = last.borrow().clone();
        let results: Vec<BlockResult> =
            blocks.par_iter().zip(&guesses).map(|(blk, g)| lambda_max(blk, &choice, *g)).collect();
        *last.borrow_mut() = results.iter().map(|r| r.lambda_max).collect();
        results
    };
    let largest = |results: &[BlockResult]| -> f64 { results.iter().map(|r| r.lambda_max).fold(0.0f64, f64::max) };
    // Sigma^2 alone: the block that was largest first, then one sweep that
    // tests every block against it (one inertia each), bisecting only the
    // blocks above it; repeated until none is (a few sweeps, not one
    // bisection per block).
    let sigma2_at = |eps: f64, b: f64| -> f64 {
        if last.borrow().iter().any(|x| x.is_nan()) {
            return largest(&every_block(eps, b));
        }
        let choice = choice_at(eps, b);
        let top = last.borrow().iter().enumerate().max_by(|x, y| x.1.total_cmp(y.1)).map_or(0, |(i, _)| i);
        let mut s = lambda_max(&blocks[top], &choice, last.borrow()[top]).lambda_max;
        last.borrow_mut()[top] = s;
        for _ in 0..blocks.len() {
            if !s.is_finite() {
                return f64::INFINITY;
            }
            let above: Vec<usize> =
                (0..blocks.len()).into_par_iter().filter(|&i| !stop() && !blocks[i].below(&choice, s, false)).collect();
            if above.is_empty() {
                break;
            }
            let guesses = last.borrow().clone();
            let found: Vec<(usize, f64)> =
                above.par_iter().map(|&i| (i, lambda_max(&blocks[i], &choice, guesses[i].max(s)).lambda_max)).collect();
            for (i, v) in found {
                last.borrow_mut()[i] = v;
                s = s.max(v);
            }
        }
        s
    };
    const RANGE: f64 = 1e4;
    // A necessary condition for P_m(b) ≻ 0, cheap: every diagonal entry
    // eps G_jj + c_j(b) positive, each linear in b. The interval it leaves
    // (within [-RANGE, RANGE], widened by 1e-6 against rounding) contains
    // every definite b; None when it is empty.
    let g_diagonals: Vec<Vec<f64>> = blocks
        .par_iter()
        .map(|blk| {
            progress.step(1);
            blk.g_diagonal()
        })
        .collect();
    let diagonal_interval = |eps: f64| -> Option<(f64, f64)> {
        let (mut lo, mut hi) = (-RANGE, RANGE);
        for (blk, gd) in blocks.iter().zip(&g_diagonals) {
            for j in (0..blk.len()).filter(|&j| !blk.degenerate[j]) {
                // alpha + b gamma > 0
                let alpha = eps * gd[j] + eps * blk.d_pi[j] / blk.d_omega[j];
                let gamma = beta_unit * blk.m as f64 / blk.d_omega[j];
                let slack = 1e-6 * (alpha.abs() / gamma.abs()).max(1.0);
                if gamma > 0.0 {
                    lo = lo.max(-alpha / gamma - slack);
                } else if gamma < 0.0 {
                    hi = hi.min(-alpha / gamma + slack);
                } else if alpha <= 0.0 {
                    return None;
                }
            }
        }
        (lo < hi).then_some((lo, hi))
    };
    let mut candidates: Vec<(f64, f64, f64, bool)> = vec![]; // (eps, b, sigma2, attained)
                                                             // eps = 0: the Casimir–momentum form, Q = 0.
    {
        let _phase = progress.phase(2 * per_pass);
        for b in [1.0, -1.0] {
            if settings.casimir_momentum && definite(0.0, b) {
                candidates.push((0.0, b, 0.0, true));
            }
        }
    }
    let searched = candidates.is_empty() && n <= settings.energy_search_max_n;
    if searched {
        for eps in [1.0, -1.0] {
            let _phase = progress.phase(search_passes * per_pass);
            if let Some((dp, mu)) = constraints.first().copied() {
                // b is forced.
                let b = -eps * dp / mu;
                if definite(eps, b) {
                    let s = sigma2_at(eps, b);
                    candidates.push((eps, b, s, true));
                }
                continue;
            }
            // P's diagonal must be positive: b in an interval, O(N^2) to find.
            let Some((lo_b, hi_b)) = diagonal_interval(eps) else { continue };
            // A definite b: golden section on the concave -margin, stopped
            // at the first definite point (64 steps shrink the range 1e-13).
            let (b0, m0) =
                golden_section_until(|b| -margin(eps, b), lo_b, hi_b, 64, |b, m| -m > 1e-9 && definite(eps, b));
            if -m0 <= 1e-9 || !definite(eps, b0) {
                continue;
            }
            // The definite interval around b0, then Sigma^2 (quasiconvex) on it.
            let edge = |outside: f64| -> f64 {
                let (mut a, mut c) = (b0, outside);
                if definite(eps, c) {
                    return c;
                }
                for _ in 0..50 {
                    let mid = 0.5 * (a + c);
                    if definite(eps, mid) {
                        a = mid;
                    } else {
                        c = mid;
                    }
                }
                a
            };
            let (lo, hi) = (edge(-RANGE), edge(RANGE));
            let (b, s) = golden_section_with_ends(|b| sigma2_at(eps, b), lo, hi, settings.golden_steps, 1e-6);
            let at_edge = (b - lo).abs() <= 1e-6 * (hi - lo) || (hi - b).abs() <= 1e-6 * (hi - lo);
            if definite(eps, b) {
                candidates.push((eps, b, s, !at_edge));
            } else if definite(eps, b0) {
                candidates.push((eps, b0, sigma2_at(eps, b0), false));
            }
        }
    }
    let best_theta = candidates.into_iter().min_by(|x, y| x.2.total_cmp(&y.2)).map(|(e, b, _, att)| ((e, b), att));
    let Some(((eps, b), attained)) = best_theta else {
        if !searched && n > settings.energy_search_max_n {
            analysis.reason = format!(
                "the Casimir–momentum form is not definite{}, and the energy–Casimir–momentum family is searched only up to N = {} (settings.energy_search_max_n; the search costs about 4x per doubling of N, some 40 s at N = 2048)",
                if settings.casimir_momentum { "" } else { " (not allowed by the settings)" },
                settings.energy_search_max_n
            );
            return Ok(analysis);
        }
        // No definite conserved form: look for a growing mode.
        if n <= settings.instability_max_n {
            let rate = blocks
                .par_iter()
                .map(|b| {
                    progress.step(1);
                    b.growth_rate(hbar)
                })
                .reduce(|| 0.0, |a, b| if a.is_nan() || b.is_nan() { f64::NAN } else { a.max(b) });
            if rate.is_nan() {
                analysis.reason = "no energy–Casimir–momentum form is definite, and the drift's spectrum could not be computed (a non-finite value, or the eigenvalue iteration did not converge)".into();
                return Ok(analysis);
            }
            let scale =
                blocks.iter().flat_map(|b| b.d_pi.iter().chain(&b.d_omega)).fold(0.0f64, |a, b| a.max(b.abs())) / hbar;
            analysis.growth_rate = Some(rate);
            if rate > 1e-6 * scale.max(f64::MIN_POSITIVE) {
                analysis.verdict = Verdict::LinearlyUnstable;
                analysis.reason = unstable_reason(rate);
                return Ok(analysis);
            }
            analysis.reason = "no energy–Casimir–momentum form is definite, and every eigenvalue of the drift is on the imaginary axis (to the tolerance): spectrally stable only".into();
        } else {
            analysis.reason = format!(
                "no energy–Casimir–momentum form is definite (the drift's spectrum is computed only up to N = {})",
                settings.instability_max_n
            );
        }
        return Ok(analysis);
    };
    let choice = choice_at(eps, b);
    let results = every_block(eps, b);
    let sigma2 = largest(&results);
    if !sigma2.is_finite() {
        analysis.reason =
            "a definite form was found but a block's lambda_max could not be bracketed (not finite)".into();
        return Ok(analysis);
    }
    analysis.drift_residual = blocks
        .par_iter()
        .map(|b| {
            progress.step(1);
            b.drift_residual(&choice)
        })
        .reduce(|| 0.0, f64::max);
    analysis.verdict = Verdict::Stable;
    analysis.reason = if choice.energy == 0.0 {
        "the Casimir–momentum form alone is definite (the profile is strictly monotone): it is conserved along every path, so Sigma^2 = 0".into()
    } else {
        format!(
            "the energy–Casimir–momentum form (energy coefficient {:+.3}) is definite in every block: formally stable; E|dW_t|_P^2 <= |dW_0|_P^2 e^(Sigma^2 t)",
            choice.energy
        )
    };
    analysis.sigma2_upper = if choice.energy == 0.0 {
        Some(0.0)
    } else {
        // A proved bound a little above the bisection estimate: P ≻ 0 is proved
        // per block (`definite`), then s P - Q ≻ 0 at s = Sigma^2 (1 + r),
        // r from 1e-10 up by tenfold steps to 1e-2.
        let base = sigma2.max(f64::MIN_POSITIVE);
        (0..9)
            .map(|i| base * (1.0 + 1e-10 * 10f64.powi(i)))
            .find(|&s| blocks.par_iter().all(|blk| !stop() && blk.definite(&choice) && blk.below(&choice, s, true)))
    };
    if choice.energy == 0.0 {
        analysis.level = VerificationLevel::ExactStructure;
    } else if analysis.sigma2_upper.is_some() {
        analysis.level = VerificationLevel::VerifiedFloat;
    }
    analysis.choice = Some(choice);
    analysis.sigma2 = Some(sigma2.max(0.0));
    analysis.attained = attained;
    analysis.blocks = results;
    Ok(analysis)
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
