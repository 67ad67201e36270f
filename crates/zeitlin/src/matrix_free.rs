//! The analysis of a Zeitlin equilibrium that is zonal in no frame, without
//! forming any `(N^2 - 1) x (N^2 - 1)` matrix.
//!
//! Every operator of the dense analysis ([`crate::general::dense_analysis`])
//! is applied to an `N x N` matrix at the cost of a few `N x N` products and
//! one `O(N^2)` stream solve ([`crate::laplacian::StreamSolver`]):
//!
//! * the drift `A X = ([P_e, X] + [Delta^-1 X, W_e]) / hbar`;
//! * the restricted Hessian of `H + C_Phi` on the orbit's tangent space, in
//!   the eigenbasis `U` of `-i W_e`: `R X = offdiag(U^* (-Delta^-1 (U X U^*))
//!   U) + c o X`, with the Daleckii–Krein weights `c_jk = (pi_j - pi_k) /
//!   (omega_j - omega_k)` (the criticality condition fixes them; see
//!   [`crate::general::dense_analysis`]).
//!
//! **The energy–Casimir test.** Lanczos on `R` (full reorthogonalisation)
//! gives Ritz values, each of which lies in `[lambda_min(R), lambda_max(R)]`
//! (Cauchy interlacing). A negative and a positive Ritz value therefore
//! *prove* (to rounding) that `R` is indefinite, so no sign of the energy
//! makes the form definite. That is what every state zonal in no frame has
//! given (`docs/zeitlin.md`: without a momentum multiplier Arnold's
//! conditions fail on the sphere). When every Ritz value has one sign the
//! form may be definite; the matrix-free analysis then does not compute
//! `Sigma^2` and says so (the dense analysis does, up to `N = 48`).
//!
//! **The instability search.** It works in the eigenbasis `F` of `-i P_e`,
//! where the drift splits as `A = D + K`: the transport `D Z = i (pi_j -
//! pi_k) Z_jk / hbar` is elementwise and reaches `|pi_j - pi_k| / hbar`, of
//! order `N`; the coupling `K Z = [Delta^-1 Z, W_e] / hbar` is bounded by a
//! constant of order `|W_e|` whatever `N` (the commutator of smooth
//! matrices is `O(hbar)`, and `Delta^-1` smooths). The eigenvalues of `A`
//! lie near the imaginary axis over that wide interval, so Krylov methods on
//! `A` itself find the few with positive real part slowly.
//!
//! 1. **Arnoldi on a propagator** `S ~ exp(tau A)`, which maps growing
//!    eigenvalues outside the unit circle and neutral ones onto it: Strang
//!    splitting, `exp(tau D / 2)` exactly (elementwise) around classical
//!    Runge–Kutta steps of `K`, `tau = 2 / max(|W_e|_op, |K|_est)`. The
//!    splitting moves eigenvalues by a few per cent, so `S` only supplies a
//!    subspace: a Rayleigh–Ritz projection of `A` on its Krylov basis gives
//!    the candidate eigenvalues (one of each conjugate pair, largest real
//!    part first).
//! 2. **Davidson on `A`** from each of the first three candidates, with the
//!    correction `(D - theta)^-1 r` of the residual `r`: `D` is diagonal and
//!    carries the size of `A`, `K` is bounded, which is Davidson's setting.
//!    It stops at a relative residual `1e-8` (or after `davidson_steps`
//!    applications of `A`).
//!
//! The reported eigenpair `(lambda, v)` has its residual computed again
//! with `A` in the spin basis (the formula of [`crate::general`]):
//! `lambda` is an exact eigenvalue of `A + E` with `|E|_F = |A v - lambda
//! v| / |v|` (a backward error). It is accepted as a growing mode when that
//! is at most `residual_tolerance` times `|A|_est = max |pi_j - pi_k| /
//! hbar + |K|_est` and at most `1e-3` of its real part. The level is
//! `numerical`: for a non-normal `A` a backward error is evidence, not a
//! proof, and a search that finds nothing proves nothing either.

use crate::analysis::{hbar, ZeitlinError};
use crate::eigen::hermitian_eigen;
use crate::laplacian::StreamSolver;
use nalgebra::{Complex, DMatrix};
use outcome::Progress;
use std::cell::Cell;

type C = Complex<f64>;

/// An eigenvalue of a projected matrix and its coefficient vector.
type RitzPair = (C, Vec<C>);

/// Settings of the matrix-free analysis, with documented defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct MatrixFreeSettings {
    /// Lanczos steps for the restricted Hessian's extreme Ritz values.
    /// Default 60.
    pub lanczos_steps: usize,
    /// Arnoldi vectors per cycle on the propagator. Default 30.
    pub krylov: usize,
    /// Arnoldi cycles (explicit restarts from the leading Ritz vectors).
    /// Default 2.
    pub cycles: usize,
    /// Applications of `A` per Davidson run. Default 150.
    pub davidson_steps: usize,
    /// Smallest growth rate reported as an instability, relative to
    /// `|W_e|_op`: slower growth is below the search's resolution. Default
    /// `1e-4`.
    pub rate_tolerance: f64,
    /// Largest backward error `|A v - lambda v| / (|A|_est |v|)` accepted
    /// for a growing eigenpair. Default `1e-6`.
    pub residual_tolerance: f64,
}

impl Default for MatrixFreeSettings {
    fn default() -> Self {
        MatrixFreeSettings {
            lanczos_steps: 60,
            krylov: 30,
            cycles: 2,
            davidson_steps: 150,
            rate_tolerance: 1e-4,
            residual_tolerance: 1e-6,
        }
    }
}

/// What the matrix-free analysis found.
#[derive(Clone, Debug, PartialEq)]
pub struct MatrixFreeAnalysis {
    /// `N^2 - 1`.
    pub dimension: usize,
    /// Whether the eigenvalues of `W_e` are distinct (else no energy–Casimir
    /// test is made).
    pub distinct_eigenvalues: bool,
    /// The smallest and largest Ritz values of the restricted Hessian `R`
    /// (bounds: `lambda_min(R) <= first`, `lambda_max(R) >= second`); one
    /// within `1e-12` of the larger in size is rounding and given as 0.
    pub restricted_ritz: Option<(f64, f64)>,
    /// Whether those Ritz values prove `R` indefinite (one negative, one
    /// positive, each beyond `1e-9` of the larger in size).
    pub indefinite: bool,
    /// `max |<R X, A Y> + <A X, R Y>| / (|R X| |A Y| + |A X| |R Y|)` over
    /// three random pairs, with `R` the full Hessian `G + C` on su(N): zero
    /// to rounding for the Hessian of a conserved functional.
    pub drift_residual: f64,
    /// `|A|_est = max |pi_j - pi_k| / hbar + |K|_est`.
    pub drift_norm: f64,
    /// The growing eigenvalue found (real part, imaginary part), when one
    /// was accepted.
    pub eigenvalue: Option<(f64, f64)>,
    /// Its backward error `|A v - lambda v|_F / |v|_F`, computed in the
    /// spin basis.
    pub backward_error: Option<f64>,
    /// The converged eigenvalue of largest real part, accepted or not (a
    /// rate below the resolution, for example), with its backward error.
    pub best: Option<(f64, f64, f64)>,
    /// The resolution `rate_tolerance |W_e|_op`: real parts below it are not
    /// told apart from zero (a neutral eigenvalue's real part is rounding).
    pub resolution: f64,
    /// The propagator's time step `tau`.
    pub tau: f64,
    /// `N x N` products spent (the work, in units of `O(N^3)`).
    pub products: usize,
}

/// The drift in the eigenbasis `F` of `-i P_e` (see the module docs).
struct Frame<'a> {
    solver: &'a StreamSolver,
    f: DMatrix<C>,
    pi: Vec<f64>,
    wf: DMatrix<C>,
    w_diagonal: bool,
    hb: f64,
    products: Cell<usize>,
}

/// `a b` by faer, its columns split among rayon's threads (the workspace
/// builds faer without its own rayon feature, so that every other product
/// stays sequential), reading nalgebra's column-major storage in place.
/// Each column block is an independent product with the same summation
/// order per entry, so the result does not depend on the number of threads
/// (a certificate is re-derived bit for bit; `crates/zeitlin/tests/it/general.rs`
/// compares one thread with two).
fn product(a: &DMatrix<C>, b: &DMatrix<C>) -> DMatrix<C> {
    use rayon::prelude::*;
    let (m, k, n) = (a.nrows(), a.ncols(), b.ncols());
    assert_eq!(k, b.nrows(), "dimension mismatch in product");
    let mut out = DMatrix::zeros(m, n);
    let lhs = faer::MatRef::from_column_major_slice(a.as_slice(), m, k);
    // Blocks of 64 columns: enough work per task, and the split is the
    // same whatever the thread count.
    let width = 64;
    out.as_mut_slice().par_chunks_mut(m * width).zip(b.as_slice().par_chunks(k * width)).for_each(|(dst, rhs)| {
        let cols = rhs.len() / k.max(1);
        faer::linalg::matmul::matmul(
            faer::MatMut::from_column_major_slice_mut(dst, m, cols),
            faer::Accum::Replace,
            lhs,
            faer::MatRef::from_column_major_slice(rhs, k, cols),
            C::new(1.0, 0.0),
            faer::Par::Seq,
        );
    });
    out
}

fn commutator(a: &DMatrix<C>, b: &DMatrix<C>) -> DMatrix<C> {
    product(a, b) - product(b, a)
}

/// `<X, Y> = Re tr(X Y^*)` (the real inner product of su(N) up to `1/N`).
fn dot(x: &DMatrix<C>, y: &DMatrix<C>) -> f64 {
    x.iter().zip(y.iter()).map(|(a, b)| a.re * b.re + a.im * b.im).sum()
}

/// `<X, Y> = tr(X Y^*)`, Hermitian, for complex matrices.
fn cdot(x: &DMatrix<C>, y: &DMatrix<C>) -> C {
    x.iter().zip(y.iter()).map(|(a, b)| a * b.conj()).sum()
}

/// `x <= y`, or `x` NaN: a breakdown test that a NaN cannot pass.
fn not_above(x: f64, y: f64) -> bool {
    x.partial_cmp(&y) != Some(std::cmp::Ordering::Greater)
}

fn numerical(what: impl std::fmt::Display) -> ZeitlinError {
    ZeitlinError::Numerical(what.to_string())
}

fn sandwich(a: &DMatrix<C>, x: &DMatrix<C>, b: &DMatrix<C>) -> DMatrix<C> {
    product(&product(a, x), b)
}

impl<'a> Frame<'a> {
    /// The frame of the eigenbasis `f` of `-i P_e` (eigenvalues `pi`):
    /// `F^* W_e F` and whether it is diagonal (two products).
    fn new(solver: &'a StreamSolver, f: DMatrix<C>, pi: Vec<f64>, w: &DMatrix<C>, hb: f64) -> Frame<'a> {
        let n = w.nrows();
        let wf = sandwich(&f.adjoint(), w, &f);
        let w_diagonal = {
            let diag: f64 = (0..n).map(|j| wf[(j, j)].norm_sqr()).sum();
            (wf.norm_squared() - diag).max(0.0).sqrt() <= 1e-14 * wf.norm()
        };
        // Two products so far: F^* W_e F.
        Frame { solver, f, pi, wf, w_diagonal, hb, products: Cell::new(2) }
    }
    fn count(&self, k: usize) {
        self.products.set(self.products.get() + k);
    }
    /// `i (pi_j - pi_k) / hbar`.
    fn transport_rate(&self, j: usize, k: usize) -> f64 {
        (self.pi[j] - self.pi[k]) / self.hb
    }
    /// The coupling `K Z = [Delta^-1 Z, W_e] / hbar`, in the frame.
    fn coupling(&self, z: &DMatrix<C>) -> Result<DMatrix<C>, ZeitlinError> {
        let psi = self.solver.solve(&sandwich(&self.f, z, &self.f.adjoint())).map_err(numerical)?;
        let psi = sandwich(&self.f.adjoint(), &psi, &self.f);
        self.count(4);
        if self.w_diagonal {
            let n = z.nrows();
            Ok(DMatrix::from_fn(n, n, |j, k| psi[(j, k)] * (self.wf[(k, k)] - self.wf[(j, j)]) / self.hb))
        } else {
            self.count(2);
            Ok(commutator(&psi, &self.wf) / C::new(self.hb, 0.0))
        }
    }
    /// The drift `A = D + K`, in the frame.
    fn drift(&self, z: &DMatrix<C>) -> Result<DMatrix<C>, ZeitlinError> {
        let n = z.nrows();
        let d = DMatrix::from_fn(n, n, |j, k| z[(j, k)] * C::new(0.0, self.transport_rate(j, k)));
        Ok(d + self.coupling(z)?)
    }
    /// `exp(t D) Z`.
    fn transport(&self, z: &DMatrix<C>, t: f64) -> DMatrix<C> {
        let n = z.nrows();
        DMatrix::from_fn(n, n, |j, k| z[(j, k)] * C::from_polar(1.0, t * self.transport_rate(j, k)))
    }
    /// One Strang step `exp(t D / 2) RK4(K)^steps exp(t D / 2)`.
    fn strang(&self, z: &DMatrix<C>, t: f64, steps: usize) -> Result<DMatrix<C>, ZeitlinError> {
        let h = t / steps as f64;
        let mut y = self.transport(z, t / 2.0);
        for _ in 0..steps {
            let k1 = self.coupling(&y)?;
            let k2 = self.coupling(&(&y + &k1 * C::new(h / 2.0, 0.0)))?;
            let k3 = self.coupling(&(&y + &k2 * C::new(h / 2.0, 0.0)))?;
            let k4 = self.coupling(&(&y + &k3 * C::new(h, 0.0)))?;
            y += (k1 + (k2 + k3) * C::new(2.0, 0.0) + k4) * C::new(h / 6.0, 0.0);
        }
        Ok(self.transport(&y, t / 2.0))
    }
}

/// Orthonormalise `x` against the orthonormal `basis` (real inner product;
/// Gram–Schmidt, twice); returns the coefficients and the norm left.
fn orthogonalise(basis: &[DMatrix<C>], x: &mut DMatrix<C>) -> (Vec<f64>, f64) {
    let mut h = vec![0.0; basis.len()];
    for _ in 0..2 {
        for (j, v) in basis.iter().enumerate() {
            let c = dot(x, v);
            h[j] += c;
            *x -= v * C::new(c, 0.0);
        }
    }
    let norm = dot(x, x).sqrt();
    (h, norm)
}

/// A random skew-Hermitian trace-free matrix of unit Frobenius norm, from a
/// fixed seed (the analysis is deterministic).
fn random_element(n: usize, seed: u64) -> DMatrix<C> {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut x = DMatrix::from_fn(n, n, |_, _| C::new(rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5));
    x = (&x - x.adjoint()) * C::new(0.5, 0.0);
    let mean = x.trace() / n as f64;
    for j in 0..n {
        x[(j, j)] -= mean;
    }
    let norm = dot(&x, &x).sqrt();
    x / C::new(norm, 0.0)
}

/// Eigenvalues and eigenvectors of a small matrix (real or complex), by
/// faer.
fn small_eigen<T>(h: &DMatrix<T>) -> Result<Vec<RitzPair>, ZeitlinError>
where
    T: nalgebra::Scalar + faer::traits::ComplexField<Real = f64> + faer::traits::Conjugate<Canonical = T>,
{
    let m = h.nrows();
    let f = faer::Mat::<T>::from_fn(m, m, |i, j| h[(i, j)].clone());
    let e = f.eigen().map_err(|_| numerical("a projected eigenproblem did not converge"))?;
    let (s, u) = (e.S(), e.U());
    Ok((0..m)
        .map(|i| (C::new(s[i].re, s[i].im), (0..m).map(|r| C::new(u[(r, i)].re, u[(r, i)].im)).collect()))
        .collect())
}

/// `sum_j y_j V_j`.
fn combine(basis: &[DMatrix<C>], y: &[C]) -> DMatrix<C> {
    let n = basis[0].nrows();
    let mut out = DMatrix::zeros(n, n);
    for (v, c) in basis.iter().zip(y) {
        out += v * *c;
    }
    out
}

/// Davidson on `A` from `(theta, u, A u)`: the Ritz value nearest the
/// previous one is followed, the correction is `(D - theta)^-1 r`, the
/// basis restarts at 30 vectors from the 6 Ritz vectors nearest `theta`.
/// Returns the final `(theta, u, relative residual)`.
fn davidson(
    frame: &Frame,
    start: (C, DMatrix<C>, DMatrix<C>),
    scale: f64,
    steps: usize,
    progress: &Progress,
) -> Result<(C, DMatrix<C>, f64), ZeitlinError> {
    let (mut theta, u0, au0) = start;
    let n = u0.nrows();
    let norm = u0.norm();
    let mut basis = vec![u0 / C::new(norm, 0.0)];
    let mut images = vec![au0 / C::new(norm, 0.0)];
    let mut best = (theta, basis[0].clone(), f64::INFINITY);
    for _ in 0..steps {
        progress.check()?;
        progress.step(1);
        let k = basis.len();
        let h = DMatrix::from_fn(k, k, |i, j| cdot(&images[j], &basis[i]));
        let mut pairs = small_eigen(&h)?;
        pairs.sort_by(|a, b| (a.0 - theta).norm().total_cmp(&(b.0 - theta).norm()));
        theta = pairs[0].0;
        let u = combine(&basis, &pairs[0].1);
        let au = combine(&images, &pairs[0].1);
        let un = u.norm();
        if not_above(un, 0.0) {
            break;
        }
        let r = &au - &u * theta;
        let residual = r.norm() / (scale * un);
        if !residual.is_finite() {
            break;
        }
        if residual < best.2 {
            best = (theta, &u / C::new(un, 0.0), residual);
        }
        if residual <= 1e-8 {
            break;
        }
        let mut t = DMatrix::from_fn(n, n, |j, k| r[(j, k)] / (C::new(0.0, frame.transport_rate(j, k)) - theta));
        if basis.len() >= 30 {
            // Thick restart: the Ritz vectors nearest theta, orthonormalised
            // with their images alongside.
            let (mut kept, mut kept_images): (Vec<DMatrix<C>>, Vec<DMatrix<C>>) = (vec![], vec![]);
            for (_, y) in pairs.iter().take(6) {
                let (mut v, mut av) = (combine(&basis, y), combine(&images, y));
                for _ in 0..2 {
                    for (b, ab) in kept.iter().zip(&kept_images) {
                        let c = cdot(&v, b);
                        v -= b * c;
                        av -= ab * c;
                    }
                }
                let vn = v.norm();
                if vn > 1e-8 {
                    kept.push(v / C::new(vn, 0.0));
                    kept_images.push(av / C::new(vn, 0.0));
                }
            }
            basis = kept;
            images = kept_images;
        }
        for _ in 0..2 {
            for v in &basis {
                let c = cdot(&t, v);
                t -= v * c;
            }
        }
        let tn = t.norm();
        if not_above(tn, 1e-14) {
            break;
        }
        let t = t / C::new(tn, 0.0);
        images.push(frame.drift(&t)?);
        basis.push(t);
    }
    Ok(best)
}

/// The matrix-free analysis of a steady `W_e` (unit size, skew-Hermitian,
/// trace-free) with stream matrix `P_e`; see the module docs.
///
/// ```
/// use zeitlin::laplacian::StreamSolver;
/// use zeitlin::matrix_free::{matrix_free_analysis, MatrixFreeSettings};
/// use zeitlin::sphere::from_harmonics;
/// // The degree-3 Rossby–Haurwitz state of fixtures/zeitlin/rossby-haurwitz-l3-n8 at N = 8.
/// let w = from_harmonics(8, &[(3, 1, 1.0), (3, -2, 0.6), (3, 0, -0.2)]).unwrap();
/// let solver = StreamSolver::new(8).unwrap();
/// let p = solver.solve(&w).unwrap();
/// let a = matrix_free_analysis(&solver, &w, &p, &MatrixFreeSettings::default(), &outcome::Progress::new()).unwrap();
/// assert!(a.indefinite);
/// // The fixture's dense growth rate (faer's eigenvalues of the 63 x 63 drift).
/// let (rate, _) = a.eigenvalue.unwrap();
/// assert!((rate - 0.1838226221867269).abs() < 1e-7);
/// ```
pub fn matrix_free_analysis(
    solver: &StreamSolver,
    w: &DMatrix<C>,
    p_e: &DMatrix<C>,
    settings: &MatrixFreeSettings,
    progress: &Progress,
) -> Result<MatrixFreeAnalysis, ZeitlinError> {
    let n = w.nrows();
    let hb = hbar(n);
    // One step per operator iteration: Lanczos, Arnoldi, the projection,
    // and up to three Davidson runs (a run that converges early leaves its
    // budget to the final settle).
    let budget = settings.lanczos_steps + (settings.cycles.max(1) + 1) * settings.krylov + 3 * settings.davidson_steps;
    progress.plan(budget as u64);
    let h = w * C::new(0.0, -1.0);
    let (omega, u) = hermitian_eigen(&((&h + h.adjoint()) * C::new(0.5, 0.0)))
        .ok_or_else(|| numerical("the eigenvalues of -i W_e did not converge"))?;
    let spread = omega.last().copied().unwrap_or(0.0) - omega.first().copied().unwrap_or(0.0);
    let w_op = omega.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let distinct = omega.windows(2).all(|p| p[1] - p[0] > 1e-8 * spread);
    let (pvals, f) = hermitian_eigen(&(p_e * C::new(0.0, -1.0)))
        .ok_or_else(|| numerical("the eigenvalues of -i P_e did not converge"))?;
    let frame = Frame::new(solver, f, pvals, w, hb);
    let mut out = MatrixFreeAnalysis {
        dimension: n * n - 1,
        distinct_eigenvalues: distinct,
        restricted_ritz: None,
        indefinite: false,
        drift_residual: 0.0,
        drift_norm: 0.0,
        eigenvalue: None,
        backward_error: None,
        best: None,
        resolution: settings.rate_tolerance * w_op,
        tau: 0.0,
        products: 0,
    };
    let spin = SpinDrift { frame: &frame, w, p_e };
    if distinct {
        let hessian = Hessian::new(&frame, &u, &omega, p_e);
        out.drift_residual = conservation_residual(&hessian, &spin, progress)?;
        let (ritz, indefinite) = restricted_ritz(&hessian, settings.lanczos_steps, progress)?;
        out.restricted_ritz = Some(ritz);
        out.indefinite = indefinite;
    }

    // 1. Arnoldi on the split propagator.
    progress.check()?;
    let coupling_norm = coupling_norm(&frame)?;
    let transport_norm = (frame.pi.last().copied().unwrap_or(0.0) - frame.pi.first().copied().unwrap_or(0.0)) / hb;
    out.drift_norm = transport_norm + coupling_norm;
    let scale = out.drift_norm;
    if !(scale > 0.0 && scale.is_finite()) {
        out.products = frame.products.get();
        return Ok(out);
    }
    let tau = 2.0 / w_op.max(coupling_norm);
    let rk_steps = ((tau * coupling_norm / 0.5).ceil() as usize).max(1);
    out.tau = tau;
    let basis = arnoldi(&frame, settings, tau, rk_steps, progress)?;
    let (images, pairs) = rayleigh_ritz(&frame, &basis, settings, w_op, progress)?;
    // 2. Davidson from each of the first three.
    let mut found: Vec<(C, DMatrix<C>)> = vec![];
    for (theta, y) in pairs.iter().take(3) {
        let u = combine(&basis, y);
        let au = combine(&images, y);
        let (t, v, r) = davidson(&frame, (*theta, u, au), scale, settings.davidson_steps, progress)?;
        if r <= settings.residual_tolerance {
            found.push((t, v));
        }
    }
    accept(&mut out, &spin, &found, settings, (scale, w_op), progress)?;
    out.products = frame.products.get();
    Ok(out)
}

/// The drift in the spin basis, as the dense analysis forms it:
/// `A X = ([P_e, X] + [Delta^-1 X, W_e]) / hbar`.
struct SpinDrift<'a> {
    frame: &'a Frame<'a>,
    w: &'a DMatrix<C>,
    p_e: &'a DMatrix<C>,
}

impl SpinDrift<'_> {
    /// `A X`, four products.
    fn apply(&self, x: &DMatrix<C>) -> Result<DMatrix<C>, ZeitlinError> {
        let psi = self.frame.solver.solve(x).map_err(numerical)?;
        self.frame.count(4);
        Ok((commutator(self.p_e, x) + commutator(&psi, self.w)) / C::new(self.frame.hb, 0.0))
    }
}

/// The Hessian of `H + C_Phi` and its restriction `R` to the orbit's
/// tangent space, in the eigenbasis `U` of `-i W_e` (see the module docs).
struct Hessian<'a> {
    frame: &'a Frame<'a>,
    u: &'a DMatrix<C>,
    omega: &'a [f64],
    /// The diagonal of `U^* (-i P_e) U`.
    pi: Vec<f64>,
}

impl<'a> Hessian<'a> {
    /// `pi_j = (U^* (-i P_e) U)_jj` (two products).
    fn new(frame: &'a Frame<'a>, u: &'a DMatrix<C>, omega: &'a [f64], p_e: &DMatrix<C>) -> Hessian<'a> {
        let n = u.nrows();
        let pi: Vec<f64> = {
            let t = sandwich(&u.adjoint(), &(p_e * C::new(0.0, -1.0)), u);
            (0..n).map(|j| t[(j, j)].re).collect()
        };
        frame.count(2);
        Hessian { frame, u, omega, pi }
    }

    /// The Daleckii–Krein weight `c_jk = (pi_j - pi_k) / (omega_j - omega_k)`.
    fn c(&self, j: usize, k: usize) -> f64 {
        (self.pi[j] - self.pi[k]) / (self.omega[j] - self.omega[k])
    }

    /// `U^* X U`.
    fn in_eigenbasis(&self, x: &DMatrix<C>) -> DMatrix<C> {
        sandwich(&self.u.adjoint(), x, self.u)
    }

    /// `U X U^*`.
    fn in_spin_basis(&self, x: &DMatrix<C>) -> DMatrix<C> {
        sandwich(self.u, x, &self.u.adjoint())
    }

    /// The full Hessian G + C on su(N), in the spin basis (C off the
    /// eigenbasis diagonal only).
    fn full(&self, x: &DMatrix<C>) -> Result<DMatrix<C>, ZeitlinError> {
        let n = x.nrows();
        let psi = self.frame.solver.solve(x).map_err(numerical)?;
        let t = self.in_eigenbasis(x);
        let t = DMatrix::from_fn(n, n, |j, k| if j == k { C::new(0.0, 0.0) } else { t[(j, k)] * self.c(j, k) });
        self.frame.count(4);
        Ok(self.in_spin_basis(&t) - psi)
    }

    /// `R X = offdiag(U^* (-Delta^-1 (U X U^*)) U) + c o X`, in the
    /// eigenbasis.
    fn restricted(&self, x: &DMatrix<C>) -> Result<DMatrix<C>, ZeitlinError> {
        let n = x.nrows();
        let t = self.in_eigenbasis(&-self.frame.solver.solve(&self.in_spin_basis(x)).map_err(numerical)?);
        self.frame.count(4);
        Ok(DMatrix::from_fn(n, n, |j, k| if j == k { C::new(0.0, 0.0) } else { t[(j, k)] + x[(j, k)] * self.c(j, k) }))
    }
}

/// `max |<R X, A Y> + <A X, R Y>| / (|R X| |A Y| + |A X| |R Y|)` over three
/// random pairs, `R` the full Hessian: zero to rounding when it is conserved.
fn conservation_residual(hessian: &Hessian, spin: &SpinDrift, progress: &Progress) -> Result<f64, ZeitlinError> {
    let n = hessian.u.nrows();
    let mut residual: f64 = 0.0;
    for s in 0..3 {
        progress.check()?;
        let x = random_element(n, 2 * s + 1);
        let y = random_element(n, 2 * s + 2);
        let (rx, ry, ax, ay) = (hessian.full(&x)?, hessian.full(&y)?, spin.apply(&x)?, spin.apply(&y)?);
        let num = (dot(&rx, &ay) + dot(&ax, &ry)).abs();
        let den = rx.norm() * ay.norm() + ax.norm() * ry.norm();
        if den > 0.0 {
            residual = residual.max(num / den);
        }
    }
    Ok(residual)
}

/// The extreme Ritz values `(lo, hi)` of `R` (bounds on its extreme
/// eigenvalues), and whether they prove it indefinite.
fn restricted_ritz(hessian: &Hessian, steps: usize, progress: &Progress) -> Result<((f64, f64), bool), ZeitlinError> {
    let n = hessian.u.nrows();
    // Lanczos on R, restricted to the tangent space (off-diagonal in
    // the eigenbasis), with full reorthogonalisation.
    let start = hessian.in_eigenbasis(&random_element(n, 99));
    let mut start = DMatrix::from_fn(n, n, |j, k| if j == k { C::new(0.0, 0.0) } else { start[(j, k)] });
    start /= C::new(start.norm(), 0.0);
    let mut basis = vec![start];
    let (mut alpha, mut beta) = (vec![], vec![]);
    for _ in 0..steps.clamp(1, n * n - n) {
        progress.check()?;
        progress.step(1);
        let mut x = hessian.restricted(basis.last().expect("a vector"))?;
        let (coef, norm) = orthogonalise(&basis, &mut x);
        alpha.push(coef[coef.len() - 1]);
        let size = alpha.iter().chain(&beta).fold(0.0f64, |a, v| a.max(v.abs()));
        if not_above(norm, 1e-12 * size) {
            break;
        }
        beta.push(norm);
        basis.push(x / C::new(norm, 0.0));
    }
    let k = alpha.len();
    let t = DMatrix::from_fn(k, k, |i, j| match i.abs_diff(j) {
        0 => alpha[i],
        1 => beta[i.min(j)],
        _ => 0.0,
    });
    let ritz = crate::eigen::symmetric_eigenvalues(&t).ok_or_else(|| numerical("the Lanczos matrix"))?;
    // A Ritz value within 1e-12 of the larger in size is rounding (its
    // digits differ between machines): it is recorded as 0.
    let size = ritz[0].abs().max(ritz[k - 1].abs());
    let snap = |x: f64| if x.abs() <= 1e-12 * size { 0.0 } else { x };
    let (lo, hi) = (snap(ritz[0]), snap(ritz[k - 1]));
    Ok(((lo, hi), lo < -1e-9 * size && hi > 1e-9 * size))
}

/// `|K|_est`: six steps of the power iteration on the coupling `K`, from
/// a fixed random start.
fn coupling_norm(frame: &Frame) -> Result<f64, ZeitlinError> {
    let n = frame.wf.nrows();
    let mut x = sandwich(&frame.f.adjoint(), &random_element(n, 7), &frame.f);
    let mut coupling_norm = 0.0f64;
    for _ in 0..6 {
        let y = frame.coupling(&x)?;
        coupling_norm = y.norm();
        if not_above(coupling_norm, 0.0) {
            break;
        }
        x = y / C::new(coupling_norm, 0.0);
    }
    Ok(coupling_norm)
}

/// Arnoldi on the propagator `S ~ exp(tau A)` (Strang splitting, `rk_steps`
/// Runge–Kutta steps of `K`), restarted `cycles - 1` times: the last
/// cycle's orthonormal Krylov basis, in the frame.
fn arnoldi(
    frame: &Frame,
    settings: &MatrixFreeSettings,
    tau: f64,
    rk_steps: usize,
    progress: &Progress,
) -> Result<Vec<DMatrix<C>>, ZeitlinError> {
    let n = frame.wf.nrows();
    let m = settings.krylov.clamp(2, n * n - 1);
    let mut start = sandwich(&frame.f.adjoint(), &random_element(n, 11), &frame.f);
    let mut basis = vec![];
    for cycle in 0..settings.cycles.max(1) {
        progress.check()?;
        let (cycle_basis, hmat) = arnoldi_cycle(frame, start.clone(), m, (tau, rk_steps), progress)?;
        basis = cycle_basis;
        if cycle + 1 == settings.cycles.max(1) {
            break;
        }
        match restart(&hmat, &basis)? {
            Some(next) => start = next,
            None => break,
        }
    }
    Ok(basis)
}

/// One Arnoldi cycle of up to `m` steps of `S` from the unit `start`:
/// the basis (ended early at a breakdown) and the Hessenberg matrix
/// `(m + 1) x m`, whose leading square of the basis's size is the
/// projection of `S`.
fn arnoldi_cycle(
    frame: &Frame,
    start: DMatrix<C>,
    m: usize,
    (tau, rk_steps): (f64, usize),
    progress: &Progress,
) -> Result<(Vec<DMatrix<C>>, DMatrix<f64>), ZeitlinError> {
    let mut basis = vec![start];
    let mut hmat = DMatrix::<f64>::zeros(m + 1, m);
    let mut size = m;
    for j in 0..m {
        progress.check()?;
        progress.step(1);
        let mut y = frame.strang(&basis[j], tau, rk_steps)?;
        let (coef, norm) = orthogonalise(&basis, &mut y);
        for (i, c) in coef.iter().enumerate() {
            hmat[(i, j)] = *c;
        }
        hmat[(j + 1, j)] = norm;
        if not_above(norm, 1e-13) {
            size = j + 1;
            break;
        }
        basis.push(y / C::new(norm, 0.0));
    }
    basis.truncate(size);
    Ok((basis, hmat))
}

/// The next cycle's start: the real parts of the four leading Ritz
/// vectors of the projected `S` (largest `|mu|` first), summed and
/// normalised; `None` when that sum vanishes.
fn restart(hmat: &DMatrix<f64>, basis: &[DMatrix<C>]) -> Result<Option<DMatrix<C>>, ZeitlinError> {
    let n = basis[0].nrows();
    // (The basis has the size of the projection: `arnoldi_cycle` truncates it.)
    let size = basis.len();
    // Restart from the leading Ritz vectors (real and imaginary parts:
    // the propagator is real on su(N)).
    let hm = hmat.view((0, 0), (size, size)).into_owned();
    let mut pairs = small_eigen(&hm)?;
    pairs.sort_by(|a, b| b.0.norm().total_cmp(&a.0.norm()));
    // Real combinations of the basis: Re and Im of the coefficient
    // vectors, so the restart stays in su(N).
    let restart: DMatrix<C> = pairs.iter().take(4).fold(DMatrix::zeros(n, n), |a, (_, y)| {
        let re: Vec<C> = y.iter().map(|z| C::new(z.re + z.im, 0.0)).collect();
        a + combine(basis, &re)
    });
    let norm = restart.norm();
    if not_above(norm, 0.0) {
        return Ok(None);
    }
    Ok(Some(restart / C::new(norm, 0.0)))
}

/// Rayleigh–Ritz of A on the Krylov basis: the images `A v` and the
/// candidates, the Ritz pairs with `Im >= 0` and real part above the
/// resolution, largest real part first.
fn rayleigh_ritz(
    frame: &Frame,
    basis: &[DMatrix<C>],
    settings: &MatrixFreeSettings,
    w_op: f64,
    progress: &Progress,
) -> Result<(Vec<DMatrix<C>>, Vec<RitzPair>), ZeitlinError> {
    progress.check()?;
    let av: Vec<DMatrix<C>> = basis.iter().map(|v| frame.drift(v)).collect::<Result<_, _>>()?;
    progress.step(settings.krylov as u64);
    let k = basis.len();
    let ha = DMatrix::from_fn(k, k, |i, j| dot(&basis[i], &av[j]));
    let mut pairs = small_eigen(&ha)?;
    pairs.retain(|(t, _)| t.im >= 0.0 && t.re > settings.rate_tolerance * w_op);
    pairs.sort_by(|a, b| b.0.re.total_cmp(&a.0.re));
    Ok((av, pairs))
}

/// The backward error in the spin basis, for the converged pairs: the
/// rightmost is `best`, and the rightmost whose backward error is within
/// `residual_tolerance |A|_est` and `1e-3` of its real part (above the
/// resolution) is the growing eigenvalue. `scales` is `(|A|_est, |W_e|_op)`.
fn accept(
    out: &mut MatrixFreeAnalysis,
    spin: &SpinDrift,
    found: &[(C, DMatrix<C>)],
    settings: &MatrixFreeSettings,
    (scale, w_op): (f64, f64),
    progress: &Progress,
) -> Result<(), ZeitlinError> {
    let frame = spin.frame;
    for (theta, v) in found {
        progress.check()?;
        let spin_v = sandwich(&frame.f, v, &frame.f.adjoint());
        frame.count(2);
        let backward = (spin.apply(&spin_v)? - &spin_v * *theta).norm() / spin_v.norm();
        if out.best.is_none_or(|(re, _, _)| theta.re > re) {
            out.best = Some((theta.re, theta.im.abs(), backward));
        }
        let accepted = backward <= settings.residual_tolerance * scale
            && backward <= 1e-3 * theta.re
            && theta.re > settings.rate_tolerance * w_op;
        if accepted && out.eigenvalue.is_none_or(|(re, _)| theta.re > re) {
            out.eigenvalue = Some((theta.re, theta.im.abs()));
            out.backward_error = Some(backward);
        }
    }
    Ok(())
}
