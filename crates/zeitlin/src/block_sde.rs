//! One off-diagonal block of the linearised stochastic Zeitlin model about a
//! zonal state, simulated beside its certified growth: what `verify
//! simulate ZEITLIN-SPEC` and the Python package's `simulate_zeitlin` run.
//!
//! About `W_e = i diag(omega)` with zonal noise `X_i = i diag(xi_i)`, a
//! perturbation's entries `z_j = dW[j, j + m]` on diagonal `m` evolve by
//! themselves (the blocks decouple):
//!
//! ```text
//! dz = L z dt + sum_i B_i z o dB^i,   L = (i/hbar) (D_pi + D_omega G),   B_i = (i/hbar) D_xi_i,
//! ```
//!
//! with `G = -Delta_m^-1` (the Laplacian's block, [`crate::laplacian::block`]),
//! `D_f = diag(f_j - f_{j+m})` and `P_e = i diag(pi)`, `Delta_N P_e = W_e`.
//! The energy–Casimir–momentum form's block is `M = eps G + D_c`, `c_j =
//! (eps (pi_j - pi_{j+m}) + beta m) / (omega_j - omega_{j+m})` (the free
//! curvature where the two are equal), oriented positive definite; the
//! drift conserves `z^* M z` (`M L + L^* M = 0`). In Ito form `A~ = L +
//! (1/2) sum B_i^2`, and `d E z^* M z / dt = E z^* Q z` with `Q = M A~ +
//! A~^* M + sum B_i^* M B_i`, so `E|z_t|_M^2 <= |z_0|_M^2 exp(lambda_max(Q,
//! M) t)`, the block's share of the certificate's `Sigma^2`.
//!
//! [`BlockSde::monte_carlo`] runs paths by Strang splitting of the exact
//! flows: the drift's `exp(L dt/2)` and each noise field's exact rotation
//! `z_j -> z_j exp(i d_j dB / hbar)`. [`BlockSde::exact_moment`] gives the
//! second moment of that scheme exactly: `S = E z z^*` under the same
//! splitting of the moment equation `dS/dt = L S + S L^* + sum_i (B_i S
//! B_i^* + (B_i^2 S + S B_i^{*2})/2)`, whose noise part is exact entrywise
//! (`S_jk exp(-(d_j - d_k)^2 dt / (2 hbar^2))`), so it is within `O(dt^2)`
//! of the SDE's own moment.

use crate::analysis::{hbar, Choice};
use crate::isospectral::{path_rng, IsospectralError};
use crate::laplacian::{block, solve_zonal};
use nalgebra::{Complex, DMatrix, DVector};
use outcome::Progress;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;

type C = Complex<f64>;

/// The linear SDE of one block (see the module docs).
#[derive(Clone, Debug)]
pub struct BlockSde {
    m: usize,
    hbar: f64,
    /// `L` (complex, `len x len`).
    drift: DMatrix<C>,
    /// `(xi_j - xi_{j+m}) / hbar` per noise field.
    noise: Vec<Vec<f64>>,
    /// `M ≻ 0`.
    form: DMatrix<f64>,
    /// `Q` (real symmetric: `Q = -(eps / (2 hbar^2)) sum [D, [D, G]]`).
    generator: DMatrix<f64>,
}

/// A Monte Carlo's `E|z_t|_M^2 / |z_0|_M^2` at the output times.
#[derive(Clone, Debug, PartialEq)]
pub struct BlockMonteCarlo {
    /// The output times.
    pub times: Vec<f64>,
    /// The mean over the paths.
    pub mean: Vec<f64>,
    /// Its standard error.
    pub std_error: Vec<f64>,
}

fn input(message: String) -> IsospectralError {
    IsospectralError::Input(message)
}

impl BlockSde {
    /// Block `m` (`1 <= m < N`) about `W_e = i diag(omega)` with the noise
    /// fields' diagonals `noise` and the certificate's functional `choice`.
    /// Fails when `m` is out of range, the lengths differ, or the block of
    /// the form is not definite.
    pub fn new(omega: &[f64], noise: &[Vec<f64>], choice: &Choice, m: usize) -> Result<BlockSde, IsospectralError> {
        let n = omega.len();
        if m == 0 || m >= n {
            return Err(input(format!("block {m}: need 1 <= m <= N - 1 = {}", n.saturating_sub(1))));
        }
        if let Some((i, x)) = noise.iter().enumerate().find(|(_, x)| x.len() != n) {
            return Err(input(format!("noise[{i}]: {} entries, N = {n}", x.len())));
        }
        let len = n - m;
        let h = hbar(n);
        let pi = solve_zonal(omega).ok_or_else(|| IsospectralError::Numerical("the zonal Poisson solve".into()))?;
        let diff = |f: &[f64]| -> Vec<f64> { (0..len).map(|j| f[j] - f[j + m]).collect() };
        let (d_pi, d_omega) = (diff(&pi), diff(omega));
        let lap = block(n, m);
        let g = -DMatrix::from_fn(len, len, |i, j| lap.get(i, j))
            .try_inverse()
            .ok_or_else(|| IsospectralError::Numerical(format!("the Laplacian's block {m} is singular")))?;
        let scale = omega.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let c: Vec<f64> = (0..len)
            .map(|j| {
                // (as the analysis decides a repeated eigenvalue)
                if d_omega[j].abs() <= 1e-12 * scale {
                    choice.free_curvature
                } else {
                    (choice.energy * d_pi[j] + choice.momentum * m as f64) / d_omega[j]
                }
            })
            .collect();
        let mut form = &g * choice.energy + DMatrix::from_diagonal(&DVector::from_vec(c));
        let mut orientation = 1.0;
        if form.clone().cholesky().is_none() {
            form = -form;
            orientation = -1.0;
            if form.clone().cholesky().is_none() {
                return Err(IsospectralError::Numerical(format!("the form is not definite on block {m}")));
            }
        }
        let k =
            DMatrix::from_diagonal(&DVector::from_vec(d_pi)) + DMatrix::from_diagonal(&DVector::from_vec(d_omega)) * &g;
        let drift = k.map(|x| C::new(0.0, x / h));
        let noise: Vec<Vec<f64>> = noise.iter().map(|x| diff(x).into_iter().map(|d| d / h).collect()).collect();
        // Q in closed form (the module docs): the drift's terms of
        // M A~ + A~^* M cancel exactly, and formed in floating point they
        // would leave rounding of the size of M L, which swamps a weak
        // noise's Q; D_c commutes with the diagonal noise, so only G's part
        // remains: Q = -(eps / 2) sum [D, [D, G]], D = diag(d / hbar).
        let mut generator = DMatrix::<f64>::zeros(len, len);
        for d in &noise {
            for i in 0..len {
                for j in 0..len {
                    generator[(i, j)] -= 0.5 * choice.energy * orientation * (d[i] - d[j]).powi(2) * g[(i, j)];
                }
            }
        }
        let generator = (&generator + generator.transpose()) * 0.5;
        if generator.iter().chain(form.iter()).any(|x| !x.is_finite())
            || drift.iter().any(|z| !z.re.is_finite() || !z.im.is_finite())
        {
            return Err(IsospectralError::Numerical(format!(
                "block {m}: the form or the generator is beyond the doubles (noise or state too large)"
            )));
        }
        Ok(BlockSde { m, hbar: h, drift, noise, form, generator })
    }

    /// The diagonal `m`.
    pub fn m(&self) -> usize {
        self.m
    }

    /// Its length `N - m`.
    pub fn len(&self) -> usize {
        self.form.nrows()
    }

    /// Whether it is empty (never: `m < N`).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// `hbar`.
    pub fn hbar(&self) -> f64 {
        self.hbar
    }

    /// `lambda_max(Q, M)`, the fastest initial growth of `E|z|_M^2`, and
    /// the real direction `z_0` (`|z_0|_M = 1`) that attains it.
    pub fn top(&self) -> Option<(f64, Vec<f64>)> {
        let l = self.form.clone().cholesky()?.l();
        let li = l.try_inverse()?;
        let s = &li * &self.generator * li.transpose();
        let s = (&s + s.transpose()) * 0.5;
        let e = s.symmetric_eigen();
        let i = e.eigenvalues.imax();
        let v = li.transpose() * e.eigenvectors.column(i);
        let norm = (v.transpose() * &self.form * &v)[(0, 0)].sqrt();
        (norm.is_finite() && norm > 0.0).then(|| (e.eigenvalues[i], v.iter().map(|x| x / norm).collect()))
    }

    /// `|z|_M^2 = z^* M z`.
    pub fn norm2(&self, z: &[C]) -> f64 {
        let len = self.len();
        let mut total = 0.0;
        for i in 0..len {
            let mut row = C::new(0.0, 0.0);
            for j in 0..len {
                row += z[j] * self.form[(i, j)];
            }
            total += (z[i].conj() * row).re;
        }
        total
    }

    fn half_step(&self, dt: f64) -> DMatrix<C> {
        (&self.drift * C::new(dt / 2.0, 0.0)).exp()
    }

    fn record_steps(steps: usize, outputs: usize) -> usize {
        steps.div_ceil(outputs.max(1)).max(1)
    }

    /// `paths` paths from `z0` of `steps` steps of size `dt`, recorded at
    /// `t = 0` and every `ceil(steps / outputs)` steps (and at the end):
    /// `E|z_t|_M^2 / |z_0|_M^2`. Path `p` draws from
    /// [`path_rng`]`(seed, p)`; the sums are taken in path order, so the
    /// numbers do not depend on the threads. `progress` counts paths, and
    /// a cancelled one stops the run ([`IsospectralError::Cancelled`]).
    #[allow(clippy::too_many_arguments)] // the run's settings, each a number
    pub fn monte_carlo(
        &self,
        z0: &[C],
        dt: f64,
        steps: usize,
        outputs: usize,
        paths: usize,
        seed: u64,
        progress: &Progress,
    ) -> Result<BlockMonteCarlo, IsospectralError> {
        self.check_run(z0, dt, paths)?;
        let every = Self::record_steps(steps, outputs);
        let record: Vec<usize> = (0..=steps).filter(|s| s % every == 0 || *s == steps).collect();
        let half = self.half_step(dt);
        let start = self.norm2(z0);
        let sqrt_dt = dt.sqrt();
        let series: Vec<Vec<f64>> = (0..paths)
            .into_par_iter()
            .map(|p| {
                if progress.is_cancelled() {
                    return vec![];
                }
                let mut rng = path_rng(seed, p as u64);
                let mut z = DVector::from_column_slice(z0);
                let mut out = Vec::with_capacity(record.len());
                out.push(1.0);
                for s in 1..=steps {
                    z = &half * z;
                    for d in &self.noise {
                        let normal: f64 = StandardNormal.sample(&mut rng);
                        let db = sqrt_dt * normal;
                        z.iter_mut().zip(d).for_each(|(zj, dj)| *zj *= C::from_polar(1.0, dj * db));
                    }
                    z = &half * z;
                    if s % every == 0 || s == steps {
                        out.push(self.norm2(z.as_slice()) / start);
                    }
                }
                progress.step(1);
                out
            })
            .collect();
        if progress.is_cancelled() {
            return Err(IsospectralError::Cancelled);
        }
        let count = series.len() as f64;
        let mut mean = vec![0.0; record.len()];
        let mut square = vec![0.0; record.len()];
        for path in &series {
            for (k, x) in path.iter().enumerate() {
                mean[k] += x;
                square[k] += x * x;
            }
        }
        let std_error = mean
            .iter()
            .zip(&square)
            .map(|(s, q)| {
                let m = s / count;
                let var = (q / count - m * m).max(0.0) * count / (count - 1.0).max(1.0);
                (var / count).sqrt()
            })
            .collect();
        mean.iter_mut().for_each(|m| *m /= count);
        Ok(BlockMonteCarlo { times: record.iter().map(|&s| s as f64 * dt).collect(), mean, std_error })
    }

    /// The scheme's exact `E|z_t|_M^2 / |z_0|_M^2` at the Monte Carlo's
    /// output times (see the module docs): `O(len^3)` per step. `progress`
    /// counts steps, and a cancelled one stops the run.
    pub fn exact_moment(
        &self,
        z0: &[C],
        dt: f64,
        steps: usize,
        outputs: usize,
        progress: &Progress,
    ) -> Result<Vec<f64>, IsospectralError> {
        self.check_run(z0, dt, 1)?;
        let every = Self::record_steps(steps, outputs);
        let len = self.len();
        let half = self.half_step(dt);
        let half_adjoint = half.adjoint();
        let z = DVector::from_column_slice(z0);
        let mut s = &z * z.adjoint();
        // exp(-(d_j - d_k)^2 dt / 2) over the noise fields, entrywise.
        let damping = DMatrix::from_fn(len, len, |j, k| {
            let sum: f64 = self.noise.iter().map(|d| (d[j] - d[k]).powi(2)).sum();
            (-0.5 * sum * dt).exp()
        });
        let moment = |s: &DMatrix<C>| -> f64 {
            let mut total = 0.0;
            for j in 0..len {
                for k in 0..len {
                    total += self.form[(k, j)] * s[(j, k)].re;
                }
            }
            total
        };
        let start = moment(&s);
        let mut out = vec![1.0];
        for step in 1..=steps {
            if progress.is_cancelled() {
                return Err(IsospectralError::Cancelled);
            }
            progress.step(1);
            s = &half * s * &half_adjoint;
            s.iter_mut().zip(damping.iter()).for_each(|(x, d)| *x *= *d);
            s = &half * s * &half_adjoint;
            if step % every == 0 || step == steps {
                out.push(moment(&s) / start);
            }
        }
        Ok(out)
    }

    fn check_run(&self, z0: &[C], dt: f64, paths: usize) -> Result<(), IsospectralError> {
        if z0.len() != self.len() {
            return Err(input(format!("z0: {} entries, block {} has {}", z0.len(), self.m, self.len())));
        }
        if !(dt.is_finite() && dt > 0.0) {
            return Err(input(format!("dt: {dt} is not a positive number")));
        }
        if paths == 0 {
            return Err(input("paths: at least one".into()));
        }
        let start = self.norm2(z0);
        if !(start.is_finite() && start > 0.0) {
            return Err(input("z0: zero, or not finite".into()));
        }
        Ok(())
    }
}
