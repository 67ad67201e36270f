//! Monte Carlo for the full nonlinear stochastic Zeitlin model with an
//! isospectral (Casimir-preserving) integrator.
//!
//! The model (docs/zeitlin.md), on `N x N` skew-Hermitian matrices:
//!
//! ```text
//! dW = [P, W]/hbar dt + sum_i [X_i, W]/hbar o dB^i,   Delta_N P = W,   X_i = i diag(xi_i),
//! ```
//!
//! with `hbar = 2/sqrt(N^2 - 1)` and Stratonovich noise.
//!
//! * **Stream function** ([`StreamSolver`]): `Delta_N` maps every diagonal
//!   of a matrix to itself, and on the entries `w[j, j + m]` of diagonal
//!   `m >= 0` (and, since `Delta_N(P^T) = Delta_N(P)^T`, on the entries
//!   `w[j + m, j]` of diagonal `-m`) it is the tridiagonal
//!   [`crate::laplacian::block`]`(N, m)`. So `P = Delta_N^{-1} W` costs
//!   `O(N^2)`: one factored tridiagonal solve per diagonal. On the main
//!   diagonal the kernel (the identity) is dropped: `W`'s trace is removed and
//!   `P` is trace-free (the identity commutes with everything, so `[P, W]`
//!   does not see it).
//! * **Step** ([`ZeitlinModel::step`]): the stochastic isospectral midpoint
//!   (Modin & Viviani, "A Casimir preserving scheme for long-time simulation
//!   of spherical ideal hydrodynamics", JFM 884, 2020; the stochastic form
//!   adds the noise increments to the Hamiltonian matrix, as in the
//!   stochastic-Zeitlin work of Ephrati, Luesink, Cifani and Geurts). With
//!   `B(W~) = (h P(W~) + sum_i X_i dB_i)/hbar`:
//!
//!   ```text
//!   W_n = (I - B/2) W~ (I + B/2),    W_{n+1} = (I + B/2) W~ (I - B/2) = W_n + [B, W~].
//!   ```
//!
//!   Eliminating `W~`, `W_{n+1} = Cay(B) W_n Cay(B)^{-1}` with the Cayley
//!   transform `Cay(B) = (I + B/2)(I - B/2)^{-1}`, unitary for skew-Hermitian
//!   `B`: the spectrum of `W`, hence every Casimir `tr f(W)`, is kept
//!   whatever `h` and the increments (up to the fixed-point tolerance and
//!   rounding). Expanding, `W_{n+1} = W_n + h [P, W]/hbar + sum_i [X_i, W]
//!   dB_i/hbar + (1/2) sum_ij [X_i, [X_j, W]] dB_i dB_j/hbar^2 + ...`: the
//!   midpoint is consistent with the Stratonovich equation (the tests check
//!   both terms).
//! * **Invariants** ([`Invariants`], [`DriftMonitor`]): the Casimirs
//!   `tr H^k` of the Hermitian `H = -iW` (`k = 2, 3`), relative to
//!   `sum_j |lambda_j(H_0)|^k`, and the momentum `J = <W, i diag(tau)>`,
//!   `tau_j = j - (N - 1)/2`, which zonal noise conserves too.
//!
//! The random increments come from xoshiro256++ seeded per path
//! ([`path_rng`]), so every run is reproducible.
//!
//! ```
//! use zeitlin::isospectral::{zonal_state, Invariants, MidpointSettings, ZeitlinModel};
//! let n = 8;
//! // Solid-body rotation plus an l = 2 zonal flow, and one zonal noise field.
//! let omega = zeitlin::zonal::quantise(n, |z| z + 0.5 * z * z).diagonal;
//! let noise = vec![zeitlin::zonal::quantise(n, |z| 0.3 * z * z).diagonal];
//! let model = ZeitlinModel::new(n, noise).unwrap();
//! // A zonal state commutes with P and with the zonal noise: a fixed point.
//! let w = zonal_state(&omega);
//! let next = model.step(&w, 0.1, &[0.7], &MidpointSettings::default()).unwrap().state;
//! assert!((&next - &w).norm() <= 1e-14 * w.norm());
//! // Off the equilibrium the state moves, and its Casimirs do not.
//! let mut w1 = w.clone();
//! w1[(0, 3)] = nalgebra::Complex::new(0.2, 0.1);
//! w1[(3, 0)] = nalgebra::Complex::new(-0.2, 0.1);
//! let next = model.step(&w1, 0.1, &[0.7], &MidpointSettings::default()).unwrap().state;
//! assert!((&next - &w1).norm() > 1e-3);
//! let (before, after) = (Invariants::of(&w1), Invariants::of(&next));
//! assert!((before.trace2 - after.trace2).abs() <= 1e-13 * before.trace2);
//! ```

use crate::analysis::hbar;
use crate::laplacian::{solve_zonal, StreamError, StreamSolver};
use nalgebra::{Complex, DMatrix};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

type C = Complex<f64>;

/// Why a solve, a step or a run could not be done.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum IsospectralError {
    /// The input is malformed (the message says which).
    #[error("{0}")]
    Input(String),
    /// The implicit midpoint equation's fixed-point iteration did not reach
    /// the tolerance (the step is too large for the contraction).
    #[error("the midpoint equation did not converge in {iterations} iterations (last relative change {change:e})")]
    NotConverged {
        /// Iterations run.
        iterations: usize,
        /// The last relative change `|W~_{k+1} - W~_k|_F / |W_n|_F`.
        change: f64,
    },
    /// A value became non-finite, or a factorisation failed.
    #[error("numerical breakdown: {0}")]
    Numerical(String),
    /// The run was stopped through its `Progress` before it ended.
    #[error("cancelled")]
    Cancelled,
}

impl From<StreamError> for IsospectralError {
    fn from(e: StreamError) -> Self {
        match e {
            StreamError::Input(m) => IsospectralError::Input(m),
            StreamError::Numerical(m) => IsospectralError::Numerical(m),
        }
    }
}

/// `W = i diag(omega)`.
pub fn zonal_state(omega: &[f64]) -> DMatrix<C> {
    let n = omega.len();
    DMatrix::from_fn(n, n, |i, j| if i == j { C::new(0.0, omega[i]) } else { C::new(0.0, 0.0) })
}

/// The skew-Hermitian matrix with `w[j, j + m] = v_j` and
/// `w[j + m, j] = -conj(v_j)`: a perturbation on diagonal `m >= 1`.
pub fn diagonal_perturbation(n: usize, m: usize, v: &[C]) -> Result<DMatrix<C>, IsospectralError> {
    if m == 0 || m >= n || v.len() != n - m {
        return Err(IsospectralError::Input(format!(
            "a perturbation on diagonal {m} of an {n} x {n} matrix needs 1 <= m < N and N - m = {} values, got {}",
            n.saturating_sub(m),
            v.len()
        )));
    }
    let mut w = DMatrix::zeros(n, n);
    for (j, z) in v.iter().enumerate() {
        w[(j, j + m)] = *z;
        w[(j + m, j)] = -z.conj();
    }
    Ok(w)
}

/// `A B` through four real products: nalgebra multiplies `f64` matrices
/// with matrixmultiply's kernels but complex ones with a generic loop, 6x
/// slower at N = 128 (measured).
fn mul(a: &DMatrix<C>, b: &DMatrix<C>) -> DMatrix<C> {
    let (ar, ai) = (a.map(|z| z.re), a.map(|z| z.im));
    let (br, bi) = (b.map(|z| z.re), b.map(|z| z.im));
    let mut re = &ar * &br;
    re.gemm(-1.0, &ai, &bi, 1.0);
    let mut im = &ar * &bi;
    im.gemm(1.0, &ai, &br, 1.0);
    re.zip_map(&im, C::new)
}

/// `(A - A^*)/2`: keeps iterates in u(N) against rounding (the
/// `W~ F = (F W~)^*` shortcut below needs exact skew-Hermitian factors).
fn skew_part(a: &mut DMatrix<C>) {
    let n = a.nrows();
    for j in 0..n {
        a[(j, j)].re = 0.0;
        for i in j + 1..n {
            let s = (a[(i, j)] - a[(j, i)].conj()) * 0.5;
            a[(i, j)] = s;
            a[(j, i)] = -s.conj();
        }
    }
}

/// Settings of the implicit midpoint solve, with documented defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct MidpointSettings {
    /// Stop when `|W~_{k+1} - W~_k|_F <= tolerance |W_n|_F`, or when the
    /// change is within 100 tolerances and no longer halves (stalled at
    /// the products' rounding, about `eps |B| |W|`: `z + 0.3 z^3` at N = 64,
    /// `h = 0.05` stalls at 1.5e-14). Default 1e-14, a few units of
    /// rounding of the `O(N^3)` products at N <= 128: the Casimirs then
    /// move by about 1e-14 per 1000 steps (measured).
    pub tolerance: f64,
    /// Iterations at most before [`IsospectralError::NotConverged`]. Default 100.
    pub max_iterations: usize,
}

impl Default for MidpointSettings {
    fn default() -> Self {
        MidpointSettings { tolerance: 1e-14, max_iterations: 100 }
    }
}

/// One step's result.
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    /// `W_{n+1}`.
    pub state: DMatrix<C>,
    /// Fixed-point iterations used.
    pub iterations: usize,
}

/// The stochastic Zeitlin model with zonal noise `X_i = i diag(xi_i)`.
#[derive(Clone, Debug)]
pub struct ZeitlinModel {
    stream: StreamSolver,
    hbar: f64,
    noise: Vec<Vec<f64>>,
}

impl ZeitlinModel {
    /// The model at `N` with the noise fields' diagonals `xi_i` (each of length `N`, finite).
    pub fn new(n: usize, noise: Vec<Vec<f64>>) -> Result<Self, IsospectralError> {
        let stream = StreamSolver::new(n)?;
        for (i, xi) in noise.iter().enumerate() {
            if xi.len() != n {
                return Err(IsospectralError::Input(format!("noise[{i}]: {} values for N = {n}", xi.len())));
            }
            if xi.iter().any(|x| !x.is_finite()) {
                return Err(IsospectralError::Input(format!("noise[{i}]: a value is not finite")));
            }
        }
        Ok(ZeitlinModel { stream, hbar: hbar(n), noise })
    }

    /// `N`.
    pub fn n(&self) -> usize {
        self.stream.n()
    }

    /// `hbar = 2/sqrt(N^2 - 1)`.
    pub fn hbar(&self) -> f64 {
        self.hbar
    }

    /// The number of noise fields.
    pub fn noise_count(&self) -> usize {
        self.noise.len()
    }

    /// The stream solver.
    pub fn stream(&self) -> &StreamSolver {
        &self.stream
    }

    /// `W` must be `N x N`, finite and skew-Hermitian (to `1e-12` relative).
    fn check_state(&self, w: &DMatrix<C>) -> Result<(), IsospectralError> {
        self.stream.check(w, "W")?;
        if w.iter().any(|z| !(z.re.is_finite() && z.im.is_finite())) {
            return Err(IsospectralError::Input("W has a value that is not finite".into()));
        }
        let off = (w + w.adjoint()).norm();
        if off > 1e-12 * w.norm() {
            return Err(IsospectralError::Input(format!(
                "W is not skew-Hermitian: |W + W^*|_F = {off:e}, |W|_F = {:e}",
                w.norm()
            )));
        }
        Ok(())
    }

    /// The deterministic drift `[P, W]/hbar`.
    pub fn drift(&self, w: &DMatrix<C>) -> Result<DMatrix<C>, IsospectralError> {
        self.stream.check(w, "W")?;
        let p = self.stream.solve(w)?;
        Ok((mul(&p, w) - mul(w, &p)) / C::new(self.hbar, 0.0))
    }

    /// One step of the stochastic isospectral midpoint from `W_n = w`, with
    /// time step `h >= 0` and Brownian increments `dB_i` (one per noise
    /// field; `N(0, h)` for a Monte Carlo path, any values for a
    /// deterministic check).
    ///
    /// `W~` solves `W_n = (I - B/2) W~ (I + B/2)` by fixed-point
    /// iteration. The diagonal of `B`, `i diag(lambda)` (the noise, and the
    /// stream function's diagonal), makes `(I - B/2) W~ (I + B/2)` act
    /// entrywise, so it is inverted exactly inside each iteration; only the
    /// off-diagonal part `F` of `h P(W~)/hbar`, and the dependence of
    /// `lambda` on `W~`, are iterated on. Iterating on all of `B` contracts
    /// by `|ad B|/2` an iteration: about 0.5 for `z + 0.3 z^3` at N = 64,
    /// `h = 0.05` (its solid-body part makes `h |P|/hbar` about 1), and not
    /// at all for a large Gaussian increment. Near a zonal state `F` is
    /// small and the iteration converges in a few steps. With `a_j = 1 -
    /// i lambda_j/2` the equation reads
    ///
    /// ```text
    /// a_j W~_jl conj(a_l) = [W_n + (F/2) W~ (I + Lambda/2) - (I - Lambda/2) W~ (F/2) + (F/2) W~ (F/2)]_jl,
    /// ```
    ///
    /// and each iteration costs two complex products (`Y = F W~`, `Y F`;
    /// for skew-Hermitian factors `W~ F = Y^*`) and one stream solve.
    pub fn step(
        &self,
        w: &DMatrix<C>,
        h: f64,
        increments: &[f64],
        settings: &MidpointSettings,
    ) -> Result<Step, IsospectralError> {
        self.check_state(w)?;
        if !(h.is_finite() && h >= 0.0) {
            return Err(IsospectralError::Input(format!("the time step must be finite and >= 0, got {h}")));
        }
        if increments.len() != self.noise.len() {
            return Err(IsospectralError::Input(format!(
                "{} increments for {} noise fields",
                increments.len(),
                self.noise.len()
            )));
        }
        if increments.iter().any(|x| !x.is_finite()) {
            return Err(IsospectralError::Input("an increment is not finite".into()));
        }
        let n = self.n();
        // The noise's part of B: D = i diag(d).
        let d: Vec<f64> = (0..n)
            .map(|j| self.noise.iter().zip(increments).map(|(xi, db)| xi[j] * db).sum::<f64>() / self.hbar)
            .collect();
        let scale = w.norm();
        if scale == 0.0 {
            // P(0) = 0 and [D, 0] = 0.
            return Ok(Step { state: w.clone(), iterations: 0 });
        }
        let e_factor = h / self.hbar;
        let mut wt = w.clone();
        skew_part(&mut wt);
        let mut change = f64::INFINITY;
        let mut previous = f64::INFINITY;
        for k in 0..settings.max_iterations {
            // B = i diag(lambda) + F: the diagonal (noise and the stream's
            // diagonal) and the stream's off-diagonal part.
            let mut f = self.stream.solve(&wt)?;
            let lambda: Vec<f64> = (0..n).map(|j| d[j] + e_factor * f[(j, j)].im).collect();
            f.iter_mut().for_each(|z| *z *= e_factor);
            for j in 0..n {
                f[(j, j)] = C::new(0.0, 0.0);
            }
            // Diagonal of I - Lambda/2; that of I + Lambda/2 is its conjugate.
            let a: Vec<C> = lambda.iter().map(|l| C::new(1.0, -0.5 * l)).collect();
            let y = mul(&f, &wt);
            let z = mul(&y, &f);
            let mut next = DMatrix::from_fn(n, n, |j, l| {
                let (aj, bl) = (a[j], a[l].conj());
                (w[(j, l)] - aj * y[(l, j)].conj() * 0.5 + y[(j, l)] * bl * 0.5 + z[(j, l)] * 0.25) / (aj * bl)
            });
            skew_part(&mut next);
            change = (&next - &wt).norm() / scale;
            if !change.is_finite() {
                return Err(IsospectralError::Numerical(format!("the midpoint iterate is not finite (iteration {k})")));
            }
            // Converged, or stalled at rounding: within 100 tolerances and
            // no longer halving (the products' rounding, about eps |B| |W|,
            // sets a floor that grows with |B|).
            let stalled = change <= 100.0 * settings.tolerance && change > 0.5 * previous;
            if change <= settings.tolerance || stalled {
                // W_{n+1} = W_n + [F, W~] + [i Lambda, W~], with B = B(W~)
                // for this W~ (the pair the last iteration used): the
                // update is then conjugation by Cay(B) up to the equation's
                // residual, which is the last change.
                let mut out = DMatrix::from_fn(n, n, |j, l| {
                    w[(j, l)] + y[(j, l)] - y[(l, j)].conj() + C::new(0.0, lambda[j] - lambda[l]) * wt[(j, l)]
                });
                skew_part(&mut out);
                return Ok(Step { state: out, iterations: k + 1 });
            }
            previous = change;
            wt = next;
        }
        Err(IsospectralError::NotConverged { iterations: settings.max_iterations, change })
    }

    /// The linearisation at the zonal state `W_e = i diag(omega)` on the
    /// diagonal `m >= 1` (which it maps to itself): `v' = (i/hbar) K v` with
    /// the real `K = D_{d pi} + D_{d omega} G`, `G = -Delta_m^{-1}`,
    /// `d f_j = f_j - f_{j+m}` (docs/zeitlin.md). Returned: `K`.
    pub fn block_drift(&self, omega: &[f64], m: usize) -> Result<DMatrix<f64>, IsospectralError> {
        let n = self.n();
        if omega.len() != n || omega.iter().any(|x| !x.is_finite()) {
            return Err(IsospectralError::Input(format!("omega: {} values for N = {n}, all finite", omega.len())));
        }
        if m == 0 || m >= n {
            return Err(IsospectralError::Input(format!("diagonal {m}: need 1 <= m < N = {n}")));
        }
        let pi = solve_zonal(omega).ok_or_else(|| IsospectralError::Numerical("the zonal Poisson solve".into()))?;
        let len = n - m;
        let f = &self.stream.factors[m - 1];
        let mut k = DMatrix::zeros(len, len);
        let mut col = vec![0.0; len];
        for j in 0..len {
            col.iter_mut().for_each(|x| *x = 0.0);
            col[j] = 1.0;
            f.solve(&mut col);
            for i in 0..len {
                k[(i, j)] = -(omega[i] - omega[i + m]) * col[i] + if i == j { pi[i] - pi[i + m] } else { 0.0 };
            }
        }
        Ok(k)
    }

    /// The fastest-growing mode of the linearisation at `W_e = i diag(omega)`:
    /// over the diagonals `m >= 1`, the eigenvalue `mu = i k / hbar` (`k` an
    /// eigenvalue of [`ZeitlinModel::block_drift`]) with the largest real
    /// part, and its eigenvector (by inverse iteration), unit length.
    /// `O(N^4)` (a dense real Schur per diagonal): for seeding runs at
    /// `N <= 128`, as [`crate::analysis::analyse`] is.
    pub fn fastest_growing_mode(&self, omega: &[f64]) -> Result<GrowingMode, IsospectralError> {
        let n = self.n();
        let mut best: Option<(usize, Complex<f64>)> = None;
        for m in 1..n {
            let k = self.block_drift(omega, m)?;
            let values = crate::eigen::real_eigenvalues(&k).ok_or_else(|| {
                IsospectralError::Numerical(format!("the drift on diagonal {m}: not finite, or no eigenvalues"))
            })?;
            for ev in values.iter() {
                if best.is_none_or(|(_, b)| -ev.im > -b.im) {
                    best = Some((m, *ev));
                }
            }
        }
        let (m, k) = best.ok_or_else(|| IsospectralError::Numerical("no eigenvalue".into()))?;
        let len = n - m;
        let kc = self.block_drift(omega, m)?.map(|x| C::new(x, 0.0));
        // Shifted off k by a relative 1e-10 so the LU is not singular; each
        // step then gains about 1e10 over the other eigenvectors.
        let shift = k * (1.0 + 1e-10) + C::new(1e-300, 0.0);
        let lu = (kc - DMatrix::identity(len, len) * shift).lu();
        let mut v = DMatrix::from_fn(len, 1, |j, _| C::new(1.0 + 0.5 * (j as f64 * 0.754_877_666).sin(), 0.0));
        for _ in 0..4 {
            v = lu.solve(&v).ok_or_else(|| IsospectralError::Numerical("inverse iteration: singular".into()))?;
            let norm = v.norm();
            if !(norm.is_finite() && norm > 0.0) {
                return Err(IsospectralError::Numerical("inverse iteration: not finite".into()));
            }
            v /= C::new(norm, 0.0);
        }
        let mu = C::new(0.0, 1.0) * k / self.hbar;
        Ok(GrowingMode { m, rate: mu.re, frequency: mu.im, vector: v.iter().copied().collect() })
    }

    /// Run one path of `steps` steps of size `h` from `w0`, drawing the
    /// increments `dB_i ~ N(0, h)` from `rng`. `observe(step, t, W)` is
    /// called at `t = 0` and after every step. Casimir and momentum drifts
    /// are tracked at every step.
    pub fn run<R: rand::Rng>(
        &self,
        w0: &DMatrix<C>,
        h: f64,
        steps: usize,
        rng: &mut R,
        settings: &MidpointSettings,
        mut observe: impl FnMut(usize, f64, &DMatrix<C>),
    ) -> Result<RunSummary, IsospectralError> {
        self.check_state(w0)?;
        let mut monitor = DriftMonitor::new(w0);
        let mut w = w0.clone();
        observe(0, 0.0, &w);
        let (mut iterations_max, mut iterations_total) = (0, 0usize);
        let sqrt_h = h.max(0.0).sqrt();
        let mut db = vec![0.0; self.noise.len()];
        for s in 1..=steps {
            for x in db.iter_mut() {
                let z: f64 = StandardNormal.sample(rng);
                *x = sqrt_h * z;
            }
            let step = self.step(&w, h, &db, settings)?;
            w = step.state;
            iterations_max = iterations_max.max(step.iterations);
            iterations_total += step.iterations;
            monitor.observe(&w);
            observe(s, s as f64 * h, &w);
        }
        Ok(RunSummary {
            state: w,
            casimir_drift: monitor.casimir_drift(),
            momentum_drift: monitor.momentum_drift(),
            iterations_max,
            iterations_mean: if steps > 0 { iterations_total as f64 / steps as f64 } else { 0.0 },
        })
    }
}

/// The fastest-growing linear mode at a zonal state.
#[derive(Clone, Debug, PartialEq)]
pub struct GrowingMode {
    /// Its diagonal.
    pub m: usize,
    /// `Re mu`, the growth rate.
    pub rate: f64,
    /// `Im mu`.
    pub frequency: f64,
    /// `v_j` (unit length): the perturbation is
    /// [`diagonal_perturbation`]`(N, m, v)`.
    pub vector: Vec<C>,
}

/// What a path did.
#[derive(Clone, Debug, PartialEq)]
pub struct RunSummary {
    /// The final state.
    pub state: DMatrix<C>,
    /// [`DriftMonitor::casimir_drift`] over the path.
    pub casimir_drift: f64,
    /// [`DriftMonitor::momentum_drift`] over the path.
    pub momentum_drift: f64,
    /// The most fixed-point iterations of a step.
    pub iterations_max: usize,
    /// Their mean.
    pub iterations_mean: f64,
}

/// The conserved quantities of a state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Invariants {
    /// `tr H^2`, `H = -iW` Hermitian (`= |W|_F^2`).
    pub trace2: f64,
    /// `tr H^3`.
    pub trace3: f64,
    /// `J = <W, i diag(tau)> = Re tr(W (i D_tau)^*)/N = sum_j Im(W_jj) tau_j / N`,
    /// `tau_j = j - (N - 1)/2`.
    pub momentum: f64,
}

impl Invariants {
    /// Of `W` (`O(N^3)`: one product for `tr H^3`).
    pub fn of(w: &DMatrix<C>) -> Invariants {
        let n = w.nrows();
        let h = w.map(|z| C::new(z.im, -z.re));
        let h2 = mul(&h, &h);
        let trace3: f64 =
            (0..n).flat_map(|i| (0..n).map(move |j| (i, j))).map(|(i, j)| (h2[(i, j)] * h[(j, i)]).re).sum();
        let tau = |j: usize| j as f64 - (n as f64 - 1.0) / 2.0;
        let momentum = (0..n).map(|j| w[(j, j)].im * tau(j)).sum::<f64>() / n as f64;
        Invariants { trace2: w.norm_squared(), trace3, momentum }
    }
}

/// The eigenvalues of `-iW` (Hermitian), ascending.
pub fn spectrum(w: &DMatrix<C>) -> Vec<f64> {
    let h = w.map(|z| C::new(z.im, -z.re));
    let hh = (&h + h.adjoint()) * C::new(0.5, 0.0);
    let mut ev: Vec<f64> = nalgebra::SymmetricEigen::new(hh).eigenvalues.iter().copied().collect();
    ev.sort_by(f64::total_cmp);
    ev
}

/// The largest relative drift of the invariants along a path.
///
/// * Casimirs: `max_k |tr H_t^k - tr H_0^k| / sum_j |lambda_j(H_0)|^k`,
///   `k = 2, 3` (`H = -iW`). The scale is what the trace sums, so a
///   vanishing `tr H^3` (an odd spectrum) does not inflate the ratio.
/// * Momentum: `|J_t - J_0| / (|W_0|_F |tau| / N)`, the Cauchy–Schwarz
///   bound on `|J|`.
#[derive(Clone, Debug)]
pub struct DriftMonitor {
    initial: Invariants,
    scale2: f64,
    scale3: f64,
    momentum_scale: f64,
    casimir: f64,
    momentum: f64,
}

impl DriftMonitor {
    /// Start at `W_0` (`O(N^3)`: its spectrum).
    pub fn new(w0: &DMatrix<C>) -> DriftMonitor {
        let n = w0.nrows();
        let ev = spectrum(w0);
        let tau2: f64 = (0..n).map(|j| (j as f64 - (n as f64 - 1.0) / 2.0).powi(2)).sum();
        let positive = |x: f64| if x > 0.0 { x } else { 1.0 };
        DriftMonitor {
            initial: Invariants::of(w0),
            scale2: positive(ev.iter().map(|x| x * x).sum()),
            scale3: positive(ev.iter().map(|x| x.abs().powi(3)).sum()),
            momentum_scale: positive(w0.norm() * tau2.sqrt() / n as f64),
            casimir: 0.0,
            momentum: 0.0,
        }
    }

    /// Record `W_t`. A non-finite value makes the drift NaN for good
    /// (`f64::max` would drop it).
    pub fn observe(&mut self, w: &DMatrix<C>) {
        let now = Invariants::of(w);
        let worst = |so_far: f64, x: f64| if so_far.is_nan() || x.is_nan() { f64::NAN } else { so_far.max(x) };
        let c2 = (now.trace2 - self.initial.trace2).abs() / self.scale2;
        let c3 = (now.trace3 - self.initial.trace3).abs() / self.scale3;
        self.casimir = worst(worst(self.casimir, c2), c3);
        self.momentum = worst(self.momentum, (now.momentum - self.initial.momentum).abs() / self.momentum_scale);
    }

    /// The largest relative Casimir drift so far.
    pub fn casimir_drift(&self) -> f64 {
        self.casimir
    }

    /// The largest relative momentum drift so far.
    pub fn momentum_drift(&self) -> f64 {
        self.momentum
    }
}

/// The random stream of one path: xoshiro256++ seeded (through SplitMix64,
/// as `seed_from_u64` does) from the seed and the path index, so a path
/// does not depend on which others ran (the `simulate` crate's scheme).
pub fn path_rng(seed: u64, path: u64) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(seed ^ path.wrapping_mul(0x9E37_79B9_7F4A_7C15).rotate_left(17))
}

/// The least-squares slope of `log y` against `t` over the samples with
/// `lo <= y <= hi` (`None` with fewer than three).
///
/// ```
/// let t: Vec<f64> = (0..50).map(|i| i as f64 * 0.5).collect();
/// let y: Vec<f64> = t.iter().map(|t| 1e-9 * (0.3 * t).exp()).collect();
/// let r = zeitlin::isospectral::fit_rate(&t, &y, 1e-9, 1e-4).unwrap();
/// assert!((r - 0.3).abs() < 1e-12);
/// ```
pub fn fit_rate(t: &[f64], y: &[f64], lo: f64, hi: f64) -> Option<f64> {
    let pts: Vec<(f64, f64)> =
        t.iter().zip(y).filter(|(_, y)| **y >= lo && **y <= hi && y.is_finite()).map(|(t, y)| (*t, y.ln())).collect();
    if pts.len() < 3 {
        return None;
    }
    let k = pts.len() as f64;
    let (mt, my) = (pts.iter().map(|p| p.0).sum::<f64>() / k, pts.iter().map(|p| p.1).sum::<f64>() / k);
    let (sxy, sxx) = pts.iter().fold((0.0, 0.0), |(a, b), (t, y)| (a + (t - mt) * (y - my), b + (t - mt) * (t - mt)));
    (sxx > 0.0).then(|| sxy / sxx)
}
