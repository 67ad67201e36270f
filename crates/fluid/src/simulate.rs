//! Monte Carlo of one x-mode of the discretised linear SDE, and its exact
//! second moment, to set beside the certified growth `E V(t) <= e^{Sigma^2 t} V(0)`.
//!
//! The noise operators `B_j = -ik diag(eta_j)` commute with each other, so
//! the noise flow over a step is exact: `w -> diag(exp(-ik sum_j eta_j dW_j)) w`.
//! The drift flow `exp(-ik R h)` is exact too: `R` is self-adjoint for the
//! definite form `V` (`V R = R^T V`, see [`crate::modes`]), so it has a
//! `V`-orthonormal real eigenbasis. Strang splitting of the two exact
//! flows (half drift, noise, half drift) is a weak second-order scheme for
//! the Stratonovich equation.
//!
//! The exact second moment `S(t) = E[w w^H]` solves the Itô moment equation
//! `S' = A~ S + S A~^H + sum_j B_j S B_j^H`, `A~ = A + 1/2 sum_j B_j^2`, and
//! `E V(t) = tr(V S(t))`; it is integrated by the Taylor series of the
//! exponential (classical Runge–Kutta, which needs `h |A~|_F <= 0.01`, is
//! about 300 times slower at ny = 128).

use crate::grid::YGrid;
use crate::modes::{Coefficients, Form, Mode};
use nalgebra::{Complex, DMatrix, DVector};
use outcome::{Cancelled, Progress};
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;

type C = Complex<f64>;

/// The most Taylor steps per output time the exact second moments take
/// (noise near `1e100` would ask for more than any run could finish).
pub const MAX_TAYLOR_STEPS: usize = 1 << 30;

/// Steps of norm at most 4 over an interval where the operator's norm bound
/// times the length is `norm_dt`; `None` if not finite or too many.
pub(crate) fn taylor_step_count(norm_dt: f64) -> Option<usize> {
    let steps = (norm_dt / 4.0).ceil().max(1.0);
    (steps.is_finite() && steps <= MAX_TAYLOR_STEPS as f64).then_some(steps as usize)
}

/// `exp(h L) s` by the Taylor series of the exponential, summed until a
/// term falls below `1e-17` of the sum (at least 4 terms, at most 200): one
/// step of the exact second moments here and in [`crate::barotropic_sde`],
/// `apply` being `L`. `progress` is looked at before each term (a step of
/// the compressible model at ny = 256 can take a minute).
pub(crate) fn taylor_exp(
    s: &DMatrix<C>,
    h: f64,
    apply: impl Fn(&DMatrix<C>) -> DMatrix<C>,
    progress: &Progress,
) -> Result<DMatrix<C>, Cancelled> {
    let mut sum = s.clone();
    let mut term = s.clone();
    for m in 1..=200 {
        progress.check()?;
        term = apply(&term) * C::new(h / m as f64, 0.0);
        sum += &term;
        if term.norm() <= 1e-17 * sum.norm() && m >= 4 {
            break;
        }
    }
    Ok(sum)
}

/// One x-mode's linear SDE, ready to simulate.
#[derive(Clone, Debug)]
pub struct ModeSde {
    k: f64,
    v: DMatrix<f64>,
    /// `v` as a complex matrix, for `V(w) = w^H V w` without a conversion per call.
    vc: DMatrix<C>,
    r: DMatrix<f64>,
    eta: Vec<Vec<f64>>,
}

/// Steps of a long run reported to a [`Progress`] (`weight` of its units
/// each: [`crate::analysis::ModeStudy`] counts thousands of flops, so an
/// ensemble and an exact moment share one bar), and its cancel flag.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ticks<'a> {
    pub progress: &'a Progress,
    pub weight: u64,
}

impl Ticks<'_> {
    pub(crate) fn step(&self, steps: u64) {
        self.progress.step(steps.saturating_mul(self.weight));
    }

    pub(crate) fn check(&self) -> Result<(), Cancelled> {
        self.progress.check()
    }
}

/// The sizes of a Strang-splitting ensemble.
#[derive(Clone, Copy, Debug)]
pub(crate) struct StrangRun {
    pub dt: f64,
    pub steps: usize,
    pub record_every: usize,
    pub paths: usize,
    pub seed: u64,
}

/// `paths` paths from `x0` of the Strang splitting half drift (`half`),
/// noise flow (`noise(y, dW, z)` writes the flow of `y` under the increments
/// `dW`, one per field, each of variance `dt`), half drift; `energy` recorded
/// every `record_every` steps. One random stream per path
/// ([`simulate::path_rng`]), so the numbers do not depend on the threads.
/// Each path reports its steps to `ticks` every `chunk` steps (about 1e7
/// flops, at most an output interval) and stops there once the run is
/// cancelled.
pub(crate) fn strang_ensemble(
    x0: &DVector<C>,
    half: &DMatrix<C>,
    fields: usize,
    run: &StrangRun,
    ticks: Ticks<'_>,
    noise: impl Fn(&DVector<C>, &[f64], &mut DVector<C>) + Sync,
    energy: impl Fn(&DVector<C>) -> f64 + Sync,
) -> Result<Vec<EnsembleRow>, Cancelled> {
    let &StrangRun { dt, steps, record_every, paths, seed } = run;
    let n = x0.len();
    // Steps between two looks at `ticks`: about 1e7 flops (two products
    // with the dense `half`, `16 n^2` flops), at most an output interval,
    // so that a cancel is seen within milliseconds however few the outputs.
    let chunk = ((1e7 / (16.0 * (n * n).max(1) as f64)) as usize).clamp(1, record_every.max(1));
    let v0 = energy(x0);
    let records = steps / record_every;
    let (one, zero) = (C::new(1.0, 0.0), C::new(0.0, 0.0));
    let sq = dt.sqrt();
    let per_path: Vec<Vec<f64>> = (0..paths)
        .into_par_iter()
        .map(|p| -> Result<Vec<f64>, Cancelled> {
            ticks.check()?;
            let mut rng = simulate::path_rng(seed, p as u64);
            let mut counted = 0;
            let mut x = x0.clone();
            let (mut y, mut z) = (DVector::<C>::zeros(n), DVector::<C>::zeros(n));
            let mut dws = vec![0.0; fields];
            let mut out = Vec::with_capacity(records);
            for s in 1..=steps {
                y.gemv(one, half, &x, zero);
                for dw in dws.iter_mut() {
                    *dw = sq * <StandardNormal as Distribution<f64>>::sample(&StandardNormal, &mut rng);
                }
                noise(&y, &dws, &mut z);
                x.gemv(one, half, &z, zero);
                if s % record_every == 0 {
                    out.push(energy(&x));
                }
                if s % chunk == 0 || s == steps {
                    ticks.step((s - counted) as u64);
                    counted = s;
                    ticks.check()?;
                }
            }
            Ok(out)
        })
        .collect::<Result<_, _>>()?;
    let max_path_drift = per_path.iter().flatten().map(|e| (e - v0).abs() / v0).fold(0.0, f64::max);
    Ok((0..records)
        .map(|r| {
            let vals: Vec<f64> = per_path.iter().map(|v| v[r]).collect();
            let mean = vals.iter().sum::<f64>() / paths as f64;
            let var = vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (paths as f64 - 1.0).max(1.0);
            EnsembleRow {
                t: dt * ((r + 1) * record_every) as f64,
                mean,
                std_error: (var / paths as f64).sqrt(),
                max_path_drift,
            }
        })
        .collect())
}

/// `E V(t)` at the requested times, with its Monte Carlo standard error.
#[derive(Clone, Debug, PartialEq)]
pub struct EnsembleRow {
    /// Time.
    pub t: f64,
    /// Sample mean of `V(w_t)`.
    pub mean: f64,
    /// Its standard error.
    pub std_error: f64,
    /// Largest relative change of `V` along any single path (0 when `V` is a pathwise invariant).
    pub max_path_drift: f64,
}

impl ModeSde {
    /// The SDE of mode `k` with the form `V` (dense, vorticity coordinates).
    pub fn new(grid: &YGrid, coef: &Coefficients, form: &Form, k: f64) -> Self {
        let mode = Mode::new(grid, k);
        let v = mode.form_matrix(form);
        let vc = v.map(|x| C::new(x, 0.0));
        ModeSde { k, v, vc, r: mode.drift_matrix(coef), eta: coef.eta.clone() }
    }

    /// Noise fields.
    pub fn fields(&self) -> usize {
        self.eta.len()
    }

    /// `V(w) = w^H V w`.
    pub fn energy(&self, w: &DVector<C>) -> f64 {
        w.dotc(&(&self.vc * w)).re
    }

    /// `exp(-ik R h)` from the `V`-orthonormal eigenbasis of `R`.
    fn drift_propagator(&self, h: f64) -> Option<DMatrix<C>> {
        let chol = nalgebra::Cholesky::new(self.v.clone())?;
        let l = chol.l();
        let linv = l.clone().try_inverse()?;
        // T = L^-1 (V R) L^-T is symmetric when V R is
        let vr = &self.v * &self.r;
        let t = &linv * ((&vr + vr.transpose()) * 0.5) * linv.transpose();
        let eig = nalgebra::SymmetricEigen::new(t);
        let x = linv.transpose() * &eig.eigenvectors; // R X = X diag(lambda), X^T V X = I
        let xinv = x.transpose() * &self.v;
        let phase = DMatrix::from_diagonal(&eig.eigenvalues.map(|lam| C::from_polar(1.0, -self.k * lam * h)));
        Some(x.map(|a| C::new(a, 0.0)) * phase * xinv.map(|a| C::new(a, 0.0)))
    }

    /// Simulate `paths` paths from `w0` with step `dt`, recording `E V` at
    /// every multiple of `record_every` steps. Deterministic in `seed`.
    pub fn ensemble(
        &self,
        w0: &[f64],
        dt: f64,
        steps: usize,
        record_every: usize,
        paths: usize,
        seed: u64,
    ) -> Option<Vec<EnsembleRow>> {
        let run = StrangRun { dt, steps, record_every, paths, seed };
        // A fresh `Progress` is never cancelled.
        self.ensemble_ticked(w0, &run, Ticks { progress: &Progress::new(), weight: 1 }).ok().flatten()
    }

    /// [`Self::ensemble`], its path-steps reported to `ticks`.
    pub(crate) fn ensemble_ticked(
        &self,
        w0: &[f64],
        run: &StrangRun,
        ticks: Ticks<'_>,
    ) -> Result<Option<Vec<EnsembleRow>>, Cancelled> {
        let Some(half) = self.drift_propagator(run.dt / 2.0) else { return Ok(None) };
        self.ensemble_from(&half, w0, run, ticks).map(Some)
    }

    /// Wall-clock seconds of a run of [`Self::ensemble`] of these sizes:
    /// `(setup, stepping)`, the drift propagator's once per run and the
    /// paths' steps (on the thread pool, as a run takes them). `None` if
    /// the propagator could not be formed.
    pub(crate) fn time_ensemble(&self, w0: &[f64], run: &StrangRun) -> Option<(f64, f64)> {
        let started = std::time::Instant::now();
        let half = self.drift_propagator(run.dt / 2.0)?;
        let setup = started.elapsed().as_secs_f64();
        let stepping = std::time::Instant::now();
        self.ensemble_from(&half, w0, run, Ticks { progress: &Progress::new(), weight: 1 }).ok()?;
        Some((setup, stepping.elapsed().as_secs_f64()))
    }

    /// The ensemble with the half-step drift propagator `half`.
    fn ensemble_from(
        &self,
        half: &DMatrix<C>,
        w0: &[f64],
        run: &StrangRun,
        ticks: Ticks<'_>,
    ) -> Result<Vec<EnsembleRow>, Cancelled> {
        let x0 = DVector::from_iterator(w0.len(), w0.iter().map(|x| C::new(*x, 0.0)));
        // The noise operators commute and are diagonal: the flow is a phase per node.
        let noise = |y: &DVector<C>, dws: &[f64], z: &mut DVector<C>| {
            for a in 0..y.len() {
                let phase: f64 = self.eta.iter().zip(dws).map(|(e, dw)| e[a] * dw).sum();
                z[a] = y[a] * C::from_polar(1.0, -self.k * phase);
            }
        };
        strang_ensemble(&x0, half, self.eta.len(), run, ticks, noise, |x| self.energy(x))
    }

    /// `A~ = A + (1/2) sum_j B_j^2` and the diagonals `-ik eta_j` of the
    /// `B_j` of the Itô moment equation.
    fn moment_operators(&self) -> (DMatrix<C>, Vec<Vec<C>>) {
        let minus_ik = C::new(0.0, -self.k);
        let bs: Vec<Vec<C>> = self.eta.iter().map(|e| e.iter().map(|x| minus_ik * x).collect()).collect();
        let mut a_tilde = self.r.map(|x| minus_ik * x);
        for b in &bs {
            for (a, d) in b.iter().enumerate() {
                a_tilde[(a, a)] += d * d * 0.5;
            }
        }
        (a_tilde, bs)
    }

    /// `L S = A~ S + S A~^H + sum_j B_j S B_j^H` (the `B_j` diagonal), the
    /// rate of the Itô moment equation.
    fn moment_rate<'a>(a_tilde: &'a DMatrix<C>, bs: &'a [Vec<C>]) -> impl Fn(&DMatrix<C>) -> DMatrix<C> + 'a {
        let a_adjoint = a_tilde.adjoint();
        move |s: &DMatrix<C>| -> DMatrix<C> {
            let n = s.nrows();
            let mut out = a_tilde * s + s * &a_adjoint;
            for b in bs {
                for c in 0..n {
                    for r in 0..n {
                        out[(r, c)] += b[r] * s[(r, c)] * b[c].conj();
                    }
                }
            }
            out
        }
    }

    /// Wall-clock seconds of the first Taylor step of
    /// [`Self::exact_mean_energy`] for `(t_end, samples)` (every step has
    /// the same length; the terms it sums vary little). `None` when the
    /// run has no step or too many.
    pub(crate) fn time_taylor_step(&self, w0: &[f64], t_end: f64, samples: usize) -> Option<f64> {
        if !(t_end.is_finite() && t_end > 0.0) || samples == 0 {
            return None;
        }
        let (a_tilde, bs) = self.moment_operators();
        let apply = Self::moment_rate(&a_tilde, &bs);
        let dt = t_end / samples as f64;
        let h = dt / Self::taylor_steps(&a_tilde, &bs, dt)? as f64;
        let x0 = DVector::from_iterator(w0.len(), w0.iter().map(|x| C::new(*x, 0.0)));
        let s = &x0 * x0.adjoint();
        let started = std::time::Instant::now();
        taylor_exp(&s, h, apply, &Progress::new()).ok()?;
        Some(started.elapsed().as_secs_f64())
    }

    /// Taylor steps over a time `dt`, each of norm at most 4 against
    /// `|S -> A~ S + S A~^H + sum_j B_j S B_j^H| <= 2 |A~|_2 + sum_j |B_j|_2^2`
    /// on the Frobenius space, with `|A~|_2 <= sqrt(|A~|_1) sqrt(|A~|_inf)` (two roots: the product may overflow).
    /// `None` when that is not finite or above [`MAX_TAYLOR_STEPS`] (the
    /// integration would not end in any useful time).
    fn taylor_steps(a_tilde: &DMatrix<C>, bs: &[Vec<C>], dt: f64) -> Option<usize> {
        let col =
            (0..a_tilde.ncols()).map(|j| a_tilde.column(j).iter().map(|x| x.norm()).sum::<f64>()).fold(0.0, f64::max);
        let row =
            (0..a_tilde.nrows()).map(|i| a_tilde.row(i).iter().map(|x| x.norm()).sum::<f64>()).fold(0.0, f64::max);
        let noise: f64 = bs.iter().map(|b| b.iter().map(|x| x.norm_sqr()).fold(0.0, f64::max)).sum();
        let op_norm = 2.0 * col.sqrt() * row.sqrt() + noise;
        taylor_step_count(op_norm * dt)
    }

    /// The Taylor steps [`Self::exact_mean_energy`] takes in all (0 when it
    /// has nothing to do); `None` when they would be too many.
    pub(crate) fn exact_taylor_steps(&self, t_end: f64, samples: usize) -> Option<usize> {
        if !(t_end.is_finite() && t_end > 0.0) || samples == 0 {
            return Some(0);
        }
        let (a_tilde, bs) = self.moment_operators();
        Self::taylor_steps(&a_tilde, &bs, t_end / samples as f64)?.checked_mul(samples)
    }

    /// The flops of one Taylor step in that estimate.
    pub(crate) fn taylor_step_flops(&self) -> f64 {
        12.0 * 16.0 * (self.r.nrows() as f64).powi(3)
    }

    /// The exact `E V(t)` from `w0`, at `t = j * t_end / samples`, `j = 1..=samples`
    /// (none when the steps would be too many: [`MAX_TAYLOR_STEPS`]):
    /// `S(t) = exp(t L) S(0)` by the Taylor series of the exponential in
    /// steps of norm at most 4, each summed until a term falls below `1e-17`
    /// of the sum (the truncation error of a step is below `4^m / m!` of its
    /// norm, `m` the number of terms; at most 200).
    pub fn exact_mean_energy(&self, w0: &[f64], t_end: f64, samples: usize) -> Vec<(f64, f64)> {
        // A fresh `Progress` is never cancelled.
        self.exact_mean_energy_ticked(w0, t_end, samples, Ticks { progress: &Progress::new(), weight: 1 })
            .unwrap_or_default()
    }

    /// [`Self::exact_mean_energy`], its Taylor steps reported to `ticks`.
    pub(crate) fn exact_mean_energy_ticked(
        &self,
        w0: &[f64],
        t_end: f64,
        samples: usize,
        ticks: Ticks<'_>,
    ) -> Result<Vec<(f64, f64)>, Cancelled> {
        if !(t_end.is_finite() && t_end > 0.0) || samples == 0 {
            return Ok(vec![]);
        }
        let n = w0.len();
        let (a_tilde, bs) = self.moment_operators();
        let apply = Self::moment_rate(&a_tilde, &bs);
        let x0 = DVector::from_iterator(n, w0.iter().map(|x| C::new(*x, 0.0)));
        let mut s = &x0 * x0.adjoint();
        let vc = &self.vc;
        let dt = t_end / samples as f64;
        let Some(sub) = Self::taylor_steps(&a_tilde, &bs, dt) else { return Ok(vec![]) };
        let h = dt / sub as f64;
        let mut out = vec![];
        for j in 1..=samples {
            for _ in 0..sub {
                s = taylor_exp(&s, h, &apply, ticks.progress)?;
                ticks.step(1);
            }
            // tr(V S) = sum_ab V_ab S_ba, without the product
            out.push((j as f64 * dt, vc.iter().zip(s.transpose().iter()).map(|(v, x)| (v * x).re).sum()));
        }
        Ok(out)
    }
}
