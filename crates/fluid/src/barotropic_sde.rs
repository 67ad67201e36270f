//! The discretised linear SDE of one compressible x-mode
//! (`dX = A X dt + sum_j B_j X o dW^j`, [`crate::barotropic`]): its exact
//! second moment and a Monte Carlo of it, to set beside the certified
//! growth (docs/fluids.md §1b, "Second moments").
//!
//! **What the certificate predicts.** With `V(X) = X^H K X`, Itô's formula
//! gives `d E V / dt = E X^H Q_B X`, where
//! `Q_B = K A~ + A~^H K + sum_j B_j^H K B_j`, `A~ = A + (1/2) sum_j B_j^2`,
//! is the generator form of the pointwise noise on the discrete `K`. So
//! `E V(t) <= e^{lambda_B t} V(0)` with `lambda_B = lambda_max(Q_B, K)`, and
//! `lambda_B <= Sigma^2 + defect`, where `Sigma^2 = lambda_max(Q, K)` is the
//! mode's certified value for the continuum `Q` and `defect` is
//! [`BarotropicMode::casimir_defect`] (`max |lambda(Q_B - Q, K)|`; Weyl).
//!
//! **The exact second moment.** `E V(t) = x0^H G(t) x0` for every start
//! `x0`, where `G` solves the backward moment equation
//! `G' = A~^H G + G A~ + sum_j B_j^H G B_j`, `G(0) = K`. In the coordinates
//! `L^H X` (`K = L L^H`) the drift `A^ = L^H A L^-H` is skew-Hermitian
//! (`K A + A^H K = 0`), so the equation for `G^ = L^-1 G L^-H`,
//! `G^(0) = I`, has an operator norm of about `2 |A^|`, the largest acoustic
//! frequency, however ill-conditioned `K` is. It is integrated by the Taylor
//! series of the exponential in steps of norm at most 4, each summed until a
//! term falls below `1e-17` of the sum (the truncation error of a step is
//! below `4^m / m!` of its norm, `m` the number of terms, no stiffness
//! damping). The largest eigenvalue of `G^(t)` is the worst growth over all
//! starts: `sup_x0 E V(t) / V(0)`.
//!
//! **Monte Carlo.** The noise operators commute and their off-diagonal parts
//! square to zero (`B_j = D_j + O_j`, `D_j = -ik diag(eta_j)` constant on a
//! node, `O_j` the node-local coupling of `dm1` and `drho` into `dm2`,
//! `O_i O_j = 0`), so the noise flow over a step is exact:
//! `X -> exp(sum_j D_j dW_j) (I + sum_j O_j dW_j) X`. The drift flow
//! `exp(A h)` is exact from the eigenbasis of the skew-Hermitian `A^`.
//! Strang splitting of the two (half drift, noise, half drift) is weakly of
//! second order for the Stratonovich equation.

use crate::barotropic::BarotropicMode;
use crate::simulate::{strang_ensemble, EnsembleRow, StrangRun, Ticks};
use nalgebra::{Complex, DMatrix, DVector};
use outcome::{Cancelled, Progress};

type C = Complex<f64>;

/// One compressible mode's linear SDE in dense form (for moderate `ny`).
///
/// ```
/// use fluid::barotropic::{BarotropicCoefficients, BarotropicMode, WallGrid};
/// use fluid::barotropic_sde::BarotropicSde;
/// // U = -cos y on [-1, 1], c_s = 2, shift c = 1.2, noise 0.3 sin y with
/// // its compatible potential r' = -U eta'.
/// let grid = WallGrid::new(-1.0, 1.0, 16);
/// let y = grid.nodes();
/// let u: Vec<f64> = y.iter().map(|y| -y.cos()).collect();
/// let coef = BarotropicCoefficients {
///     up: y.iter().map(|y| y.sin()).collect(),
///     w: y.iter().zip(&u).map(|(y, u)| (u + 1.2) / y.cos()).collect(),
///     eta: vec![y.iter().map(|y| 0.3 * y.sin()).collect()],
///     eta_prime: vec![y.iter().map(|y| 0.3 * y.cos()).collect()],
///     r_prime: vec![y.iter().zip(&u).map(|(y, u)| -u * 0.3 * y.cos()).collect()],
///     u,
/// };
/// let mode = BarotropicMode::new(&grid, &coef, 1.0, 2.0, 1.2);
/// let sde = BarotropicSde::new(&mode).unwrap();
/// let (sigma2_b, _) = sde.pointwise_generator_rate();
/// // the banded Lanczos estimate agrees with the dense eigenvalue
/// assert!((mode.pointwise_noise_sigma2(1e-12).unwrap() - sigma2_b).abs() < 1e-9);
/// // and the exact second moment grows no faster, from any start
/// let m = &sde.exact_moments(0.05, 1)[0];
/// assert!(m.worst_growth > 1.0 && m.worst_growth <= (sigma2_b * m.t).exp() * (1.0 + 1e-12));
/// ```
#[derive(Clone, Debug)]
pub struct BarotropicSde {
    /// `K` (complex Hermitian, in `(dm1, dm2, drho)`).
    k: DMatrix<C>,
    /// The lower Cholesky factor of `K`.
    l: DMatrix<C>,
    /// `L^-1`.
    l_inv: DMatrix<C>,
    /// `A^ = L^H A L^-H` (skew-Hermitian).
    a_hat: DMatrix<C>,
    /// `B^_j = L^H B_j L^-H`.
    b_hat: Vec<DMatrix<C>>,
    /// `B_j` in `(dm1, dm2, drho)`.
    b: Vec<DMatrix<C>>,
}

/// The exact second moment at one time.
#[derive(Clone, Debug)]
pub struct ExactMoment {
    /// Time.
    pub t: f64,
    /// `sup_x0 E V(t) / V(0)`, the largest eigenvalue of `G^(t)`.
    pub worst_growth: f64,
    /// `G(t)`, with `E V(t) = x0^H G(t) x0`.
    pub g: DMatrix<C>,
}

fn hermitian_part(m: &DMatrix<C>) -> DMatrix<C> {
    (m + m.adjoint()) * C::new(0.5, 0.0)
}

fn largest_hermitian_eigenvalue(m: &DMatrix<C>) -> f64 {
    nalgebra::SymmetricEigen::new(hermitian_part(m)).eigenvalues.max()
}

impl BarotropicSde {
    /// The SDE of `mode`, dense; `None` if `K` is not numerically positive
    /// definite.
    pub fn new(mode: &BarotropicMode) -> Option<Self> {
        let k = hermitian_part(&mode.form_complex());
        let a = mode.drift();
        let b: Vec<DMatrix<C>> = (0..mode.noise_fields()).map(|j| mode.noise(j)).collect();
        let l = nalgebra::Cholesky::new(k.clone())?.l();
        let l_inv = l.clone().try_inverse()?;
        let hat = |m: &DMatrix<C>| l.adjoint() * m * l_inv.adjoint();
        let a_hat = hat(&a);
        // Skew-Hermitian to rounding; its anti-Hermitian part is the drift.
        let a_hat = (&a_hat - a_hat.adjoint()) * C::new(0.5, 0.0);
        let b_hat = b.iter().map(hat).collect();
        Some(BarotropicSde { k, l, l_inv, a_hat, b_hat, b })
    }

    /// Unknowns.
    pub fn n(&self) -> usize {
        self.k.nrows()
    }

    /// Noise fields.
    pub fn fields(&self) -> usize {
        self.b.len()
    }

    /// `V(x) = x^H K x`.
    pub fn energy(&self, x: &DVector<C>) -> f64 {
        x.dotc(&(&self.k * x)).re
    }

    /// `lambda_B = lambda_max(Q_B, K)` and its eigenvector (the start whose
    /// `E V` grows fastest at `t = 0`), in `(dm1, dm2, drho)`.
    pub fn pointwise_generator_rate(&self) -> (f64, DVector<C>) {
        let q_hat = hermitian_part(&self.q_hat());
        let eig = nalgebra::SymmetricEigen::new(q_hat);
        let top = eig.eigenvalues.imax();
        let v = eig.eigenvectors.column(top).into_owned();
        // X = L^-H X^
        (eig.eigenvalues[top], self.l_inv.adjoint() * v)
    }

    /// `Q^ = A~^ + A~^H + sum_j B^_j^H B^_j`, the generator form in hat coordinates.
    fn q_hat(&self) -> DMatrix<C> {
        self.backward_rate(&DMatrix::identity(self.n(), self.n()))
    }

    /// `G^ -> A~^H G^ + G^ A~ + sum_j B^_j^H G^ B^_j` for Hermitian `G^`.
    fn backward_rate(&self, g: &DMatrix<C>) -> DMatrix<C> {
        let half = C::new(0.5, 0.0);
        // A~^ = A^ + (1/2) sum B^_j^2
        let mut ga = g * &self.a_hat;
        let mut out = DMatrix::zeros(self.n(), self.n());
        for bj in &self.b_hat {
            let gb = g * bj;
            ga += &gb * bj * half;
            out += bj.adjoint() * &gb;
        }
        out += &ga + ga.adjoint();
        out
    }

    /// The exact second moment at `t = j t_end / samples`, `j = 1..=samples`
    /// (none unless `t_end` is positive and finite and the steps are at
    /// most [`crate::simulate::MAX_TAYLOR_STEPS`] per sample).
    pub fn exact_moments(&self, t_end: f64, samples: usize) -> Vec<ExactMoment> {
        // A fresh `Progress` is never cancelled.
        self.exact_moments_ticked(t_end, samples, Ticks { progress: &Progress::new(), weight: 1 }).unwrap_or_default()
    }

    /// [`Self::exact_moments`], its Taylor steps reported to `ticks`.
    pub(crate) fn exact_moments_ticked(
        &self,
        t_end: f64,
        samples: usize,
        ticks: Ticks<'_>,
    ) -> Result<Vec<ExactMoment>, Cancelled> {
        if !(t_end.is_finite() && t_end > 0.0) || samples == 0 {
            return Ok(vec![]);
        }
        let n = self.n();
        let dt = t_end / samples as f64;
        let Some(sub) = self.taylor_steps(dt) else { return Ok(vec![]) };
        let h = dt / sub as f64;
        let mut g = DMatrix::<C>::identity(n, n);
        let mut out = Vec::with_capacity(samples);
        for j in 1..=samples {
            for _ in 0..sub {
                g = self.taylor_step(&g, h, ticks.progress)?;
                ticks.step(1);
            }
            let worst = largest_hermitian_eigenvalue(&g);
            let g_orig = &self.l * &g * self.l.adjoint();
            out.push(ExactMoment { t: j as f64 * dt, worst_growth: worst, g: g_orig });
        }
        Ok(out)
    }

    /// The Taylor steps over a time `dt`: each of norm at most 4 against
    /// `|backward_rate| <= 2 |A~^|_2 + sum |B^_j|_2^2` (operator norms on the
    /// Frobenius space).
    /// `None` when that is not finite or above
    /// [`crate::simulate::MAX_TAYLOR_STEPS`].
    fn taylor_steps(&self, dt: f64) -> Option<usize> {
        let mut a_tilde = self.a_hat.clone();
        for bj in &self.b_hat {
            a_tilde += bj * bj * C::new(0.5, 0.0);
        }
        let spectral = |m: &DMatrix<C>| m.clone().singular_values().max();
        let op_norm = 2.0 * spectral(&a_tilde) + self.b_hat.iter().map(|b| spectral(b).powi(2)).sum::<f64>();
        crate::simulate::taylor_step_count(op_norm * dt)
    }

    /// The flops of each sample's eigenvalue problem and products in that
    /// estimate.
    pub(crate) fn per_sample_flops(&self) -> f64 {
        30.0 * (self.n() as f64).powi(3)
    }

    /// The Taylor steps [`Self::exact_moments`] takes in all (0 when it has
    /// nothing to do); `None` when they would be too many.
    pub(crate) fn exact_taylor_steps(&self, t_end: f64, samples: usize) -> Option<usize> {
        if !(t_end.is_finite() && t_end > 0.0) || samples == 0 {
            return Some(0);
        }
        self.taylor_steps(t_end / samples as f64)?.checked_mul(samples)
    }

    /// The flops of one Taylor step in that estimate.
    pub(crate) fn taylor_step_flops(&self) -> f64 {
        40.0 * (1.0 + 3.0 * self.b_hat.len() as f64) * 8.0 * (self.n() as f64).powi(3)
    }

    /// `exp(h L) G^` by its Taylor series ([`crate::simulate::taylor_exp`]),
    /// each term kept Hermitian.
    fn taylor_step(&self, g: &DMatrix<C>, h: f64, progress: &Progress) -> Result<DMatrix<C>, Cancelled> {
        crate::simulate::taylor_exp(g, h, |t| hermitian_part(&self.backward_rate(t)), progress)
    }

    /// `exp(A h)`, exact from the eigenbasis of the Hermitian `-i A^`.
    fn drift_propagator(&self, h: f64) -> DMatrix<C> {
        let eig = nalgebra::SymmetricEigen::new(hermitian_part(&(&self.a_hat * C::new(0.0, -1.0))));
        let u = &eig.eigenvectors;
        let phase = DMatrix::from_diagonal(&eig.eigenvalues.map(|lam| C::from_polar(1.0, lam * h)));
        // exp(A h) = L^-H exp(A^ h) L^H
        self.l_inv.adjoint() * (u * phase * u.adjoint()) * self.l.adjoint()
    }

    /// Simulate `paths` paths from `x0` with step `dt` (Strang splitting of
    /// the exact drift and noise flows), recording `E V` at every multiple of
    /// `record_every` steps. Deterministic in `seed` whatever the thread count.
    pub fn ensemble(
        &self,
        x0: &DVector<C>,
        dt: f64,
        steps: usize,
        record_every: usize,
        paths: usize,
        seed: u64,
    ) -> Vec<EnsembleRow> {
        let run = StrangRun { dt, steps, record_every, paths, seed };
        // A fresh `Progress` is never cancelled.
        self.ensemble_ticked(x0, &run, Ticks { progress: &Progress::new(), weight: 1 }).unwrap_or_default()
    }

    /// [`Self::ensemble`], its path-steps reported to `ticks`.
    pub(crate) fn ensemble_ticked(
        &self,
        x0: &DVector<C>,
        run: &StrangRun,
        ticks: Ticks<'_>,
    ) -> Result<Vec<EnsembleRow>, Cancelled> {
        self.ensemble_from(&self.drift_propagator(run.dt / 2.0), x0, run, ticks)
    }

    /// Wall-clock seconds of a run of [`Self::ensemble`] of these sizes:
    /// `(setup, stepping)`, the drift propagator's once per run and the
    /// paths' steps (on the thread pool, as a run takes them).
    pub(crate) fn time_ensemble(&self, x0: &DVector<C>, run: &StrangRun) -> (f64, f64) {
        let started = std::time::Instant::now();
        let half = self.drift_propagator(run.dt / 2.0);
        let setup = started.elapsed().as_secs_f64();
        let stepping = std::time::Instant::now();
        // (a fresh `Progress` is never cancelled)
        let _ = self.ensemble_from(&half, x0, run, Ticks { progress: &Progress::new(), weight: 1 });
        (setup, stepping.elapsed().as_secs_f64())
    }

    /// Wall-clock seconds of the first Taylor step of
    /// [`Self::exact_moments`] for `(t_end, samples)`. `None` when the run
    /// has no step or too many.
    pub(crate) fn time_taylor_step(&self, t_end: f64, samples: usize) -> Option<f64> {
        if !(t_end.is_finite() && t_end > 0.0) || samples == 0 {
            return None;
        }
        let dt = t_end / samples as f64;
        let h = dt / self.taylor_steps(dt)? as f64;
        let g = DMatrix::<C>::identity(self.n(), self.n());
        // (the step count's singular values, once per run, are not timed)
        let started = std::time::Instant::now();
        self.taylor_step(&g, h, &Progress::new()).ok()?;
        Some(started.elapsed().as_secs_f64())
    }

    /// The ensemble with the half-step drift propagator `half`.
    fn ensemble_from(
        &self,
        half: &DMatrix<C>,
        x0: &DVector<C>,
        run: &StrangRun,
        ticks: Ticks<'_>,
    ) -> Result<Vec<EnsembleRow>, Cancelled> {
        let n = self.n();
        let diag: Vec<Vec<C>> = self.b.iter().map(|b| (0..n).map(|i| b[(i, i)]).collect()).collect();
        let off: Vec<DMatrix<C>> = self
            .b
            .iter()
            .map(|b| {
                let mut o = b.clone();
                o.fill_diagonal(C::new(0.0, 0.0));
                o
            })
            .collect();
        // exp(sum D_j dW_j) (I + sum O_j dW_j) y
        let noise = |y: &DVector<C>, dws: &[f64], z: &mut DVector<C>| {
            z.copy_from(y);
            for (o, dw) in off.iter().zip(dws) {
                z.gemv(C::new(*dw, 0.0), o, y, C::new(1.0, 0.0));
            }
            for i in 0..n {
                let e: C = diag.iter().zip(dws).map(|(d, dw)| d[i] * *dw).sum();
                z[i] *= e.exp();
            }
        };
        strang_ensemble(x0, half, self.b.len(), run, ticks, noise, |x| self.energy(x))
    }
}
