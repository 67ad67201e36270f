//! Zeitlin equilibria and noise given as matrices, zonal or not.
//!
//! The checks come first, for any state `W_e` in su(N) and noise `X_i`:
//!
//! * **equilibrium**: `[P_e, W_e] = 0` with `Delta_N P_e = W_e`, measured by
//!   `|[P_e, W_e]|_F / (|P_e|_F |W_e|_F)` against a tolerance (floating
//!   point: a state read from a simulation is steady only to its solver's
//!   accuracy);
//! * **noise**: `[X_i, W_e] = 0`, measured likewise. Incompatible noise gets
//!   its compatible part: the projection onto the commutant of `W_e`
//!   (in `W_e`'s eigenbasis, the entries between equal eigenvalues), which
//!   for distinct eigenvalues is the diagonal, i.e. the functions of `W_e`.
//!
//! Then the state is brought to a frame where the zonal pipeline
//! ([`crate::analysis`]) applies, if there is one:
//!
//! * **zonal**: `W_e` and every `X_i` are diagonal;
//! * **rotated**: `W_e` commutes with `n.S` for an axis `n` (the null vector
//!   of the Gram matrix of `[S_a, W_e]`). Then `V^* W_e V` is diagonal for
//!   the rotation `V` that takes `n` to the pole
//!   ([`crate::sphere::rotation_to_axis`]). The Laplacian commutes with
//!   `Ad_V`, and so does the inner product, so the stochastic system in the
//!   rotated frame is the same system: every quantity of the analysis
//!   (verdict, `Sigma^2`, growth rate) is the same. The axis is reported
//!   in quflow's frame ([`crate::sphere::quflow_axis`]). The noise must be
//!   diagonal in that frame too (it is when it commutes with `W_e` and the
//!   eigenvalues are distinct).
//!
//! Otherwise (**general**), up to `dense_max_n`, the energy–Casimir method
//! is run densely in real orthonormal coordinates of su(N) (dimension
//! `N^2 - 1`) in the eigenbasis `U` of `-i W_e = U diag(omega) U^*`
//! ([`dense_analysis`]).

mod dense;

pub use dense::dense_analysis;

use crate::analysis::{analyse_with, hbar, ZeitlinAnalysis, ZeitlinError, ZeitlinProblem, ZeitlinSettings};
use crate::laplacian::StreamSolver;
use crate::matrix_free::{matrix_free_analysis, MatrixFreeAnalysis, MatrixFreeSettings};
use crate::sphere::{quflow_axis, rotation_to_axis};
use nalgebra::{Complex, DMatrix};
use outcome::{Progress, Verdict, VerificationLevel};

type C = Complex<f64>;

/// A Zeitlin equilibrium and noise given as matrices (skew-Hermitian; the
/// trace is irrelevant and removed).
#[derive(Clone, Debug, PartialEq)]
pub struct GeneralProblem {
    /// `N`.
    pub n: usize,
    /// `W_e`.
    pub w: DMatrix<C>,
    /// The noise stream matrices `X_i`.
    pub noise: Vec<DMatrix<C>>,
}

/// Settings of the general pipeline, with documented defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct GeneralSettings {
    /// The zonal pipeline's settings, for states it can take.
    pub zonal: ZeitlinSettings,
    /// Largest relative `|[P_e, W_e]|_F / (|P_e|_F |W_e|_F)` for `W_e` to
    /// count as an equilibrium, and largest relative off-diagonal part for
    /// a matrix to count as zonal in a frame. Default `1e-10`.
    pub equilibrium_tolerance: f64,
    /// Largest relative `|[X_i, W_e]|_F / (|X_i|_F |W_e|_F)` for compatible
    /// noise. Default `1e-10`.
    pub noise_tolerance: f64,
    /// Largest `N` for the dense analysis of a state that is zonal in no
    /// frame (`N^2 - 1` unknowns, `O(N^6)` work). Default 32.
    pub dense_max_n: usize,
    /// Largest `N` for the matrix-free analysis
    /// ([`crate::matrix_free`]) of such a state above `dense_max_n`
    /// (`O(N^3)` per operator application, a few thousand applications).
    /// Default 256.
    pub matrix_free_max_n: usize,
    /// The matrix-free analysis's settings.
    pub matrix_free: MatrixFreeSettings,
}

impl Default for GeneralSettings {
    fn default() -> Self {
        GeneralSettings {
            zonal: ZeitlinSettings::default(),
            equilibrium_tolerance: 1e-10,
            noise_tolerance: 1e-10,
            dense_max_n: 32,
            matrix_free_max_n: 256,
            matrix_free: MatrixFreeSettings::default(),
        }
    }
}

/// The frame in which the state was analysed.
#[derive(Clone, Debug, PartialEq)]
pub enum Frame {
    /// `W_e` and the noise are diagonal as given.
    Zonal,
    /// Zonal about this unit axis, in quflow's frame
    /// ([`crate::sphere::quflow_axis`]: the direction of a zonal state's
    /// `l = 1` coefficients `(v_{1,1}, v_{1,-1}, v_{1,0})`), largest
    /// component positive.
    Rotated {
        /// The axis `n`.
        axis: [f64; 3],
    },
    /// Zonal in no frame: the dense analysis.
    General,
}

/// A state brought to a zonal frame, and the zonal pipeline's analysis.
#[derive(Clone, Debug)]
pub struct ZonalReduction {
    /// `omega` (`W = i diag(omega)` in the frame).
    pub omega: Vec<f64>,
    /// The noise fields' diagonals in the frame.
    pub noise: Vec<Vec<f64>>,
    /// The largest relative off-diagonal part dropped (rounding of the
    /// rotation, or of the input).
    pub off_diagonal: f64,
    /// The zonal pipeline's result.
    pub analysis: ZeitlinAnalysis,
}

/// The dense energy–Casimir analysis of a state that is zonal in no frame.
#[derive(Clone, Debug, PartialEq)]
pub struct DenseAnalysis {
    /// `N^2 - 1`.
    pub dimension: usize,
    /// Whether the eigenvalues of `W_e` are distinct (else no energy–Casimir
    /// test is made: the Casimir directions are not the eigenbasis diagonal).
    pub distinct_eigenvalues: bool,
    /// The energy coefficient `eps` of a definite form (`+1` or `-1`), or 0.
    pub energy: f64,
    /// `max over eps of lambda_min(eps R) / max |eig R|` for the restricted
    /// Hessian `R` on the orbit's tangent space (positive: definite).
    pub restricted_margin: f64,
    /// `lambda_max(Q, P)` at the chosen Casimir Hessian.
    pub sigma2: Option<f64>,
    /// The infimum over the Casimir Hessian: `max(0, lambda_max)` of the
    /// pencil restricted to the orbit's tangent space (approached as the
    /// Casimir Hessian grows, not attained).
    pub infimum: Option<f64>,
    /// `cond(P)` of the chosen form.
    pub condition_number: Option<f64>,
    /// `|P A + A^T P|_F / (|P|_F |A|_F)`: zero for a conserved form.
    pub drift_residual: f64,
    /// The largest real part of the drift's eigenvalues (when no form is
    /// definite).
    pub growth_rate: Option<f64>,
}

/// Everything the general pipeline found.
#[derive(Clone, Debug)]
pub struct GeneralAnalysis {
    /// The verdict.
    pub verdict: Verdict,
    /// The verification level.
    pub level: VerificationLevel,
    /// One sentence explaining it.
    pub reason: String,
    /// `|[P_e, W_e]|_F / (|P_e|_F |W_e|_F)`.
    pub equilibrium_residual: f64,
    /// `|[X_i, W_e]|_F / (|X_i|_F |W_e|_F)` per noise field.
    pub noise_residuals: Vec<f64>,
    /// For incompatible noise: each field's projection onto the commutant of
    /// `W_e` (the compatible part), in the given frame.
    pub compatible_noise: Vec<DMatrix<C>>,
    /// The frame, once the checks passed.
    pub frame: Option<Frame>,
    /// The zonal pipeline's result in that frame.
    pub zonal: Option<ZonalReduction>,
    /// The dense analysis.
    pub dense: Option<DenseAnalysis>,
    /// The matrix-free analysis (zonal in no frame, above `dense_max_n`).
    pub matrix_free: Option<MatrixFreeAnalysis>,
    /// `hbar = 2/sqrt(N^2 - 1)`.
    pub hbar: f64,
}

fn finite(m: &DMatrix<C>) -> bool {
    m.iter().all(|z| z.re.is_finite() && z.im.is_finite())
}

/// The skew-Hermitian, trace-free part of a matrix that must be
/// skew-Hermitian (to a relative 1e-12), scaled by a power of two to unit
/// size: `(matrix, scale)`.
fn normalised(m: &DMatrix<C>, n: usize, what: &str) -> Result<(DMatrix<C>, f64), ZeitlinError> {
    if m.nrows() != n || m.ncols() != n {
        return Err(ZeitlinError::Input(format!("{what}: expected {n} x {n}, got {} x {}", m.nrows(), m.ncols())));
    }
    if !finite(m) {
        return Err(ZeitlinError::Input(format!("{what}: an entry is not finite")));
    }
    let top = m.iter().fold(0.0f64, |a, z| a.max(z.re.abs()).max(z.im.abs()));
    if top == 0.0 {
        return Ok((m.clone(), 1.0));
    }
    let scale = numerics::scaling::nearest_power_of_two(top);
    let x = m.map(|z| z / scale);
    let hermitian_part = (&x + x.adjoint()).norm() / 2.0;
    if hermitian_part > 1e-12 * x.norm() {
        return Err(ZeitlinError::Input(format!(
            "{what}: not skew-Hermitian (relative Hermitian part {:.3e}; su(N) states and noise are skew-Hermitian, as quflow's W)",
            hermitian_part / x.norm()
        )));
    }
    let mut x = (&x - x.adjoint()) * C::new(0.5, 0.0);
    let mean = x.trace() / n as f64;
    for j in 0..n {
        x[(j, j)] -= mean;
    }
    Ok((x, scale))
}

fn commutator(a: &DMatrix<C>, b: &DMatrix<C>) -> DMatrix<C> {
    crate::eigen::complex_product(a, b) - crate::eigen::complex_product(b, a)
}

/// `[S_a, W]` for `a = 1, 2, 3` in `O(N^2)`: `S_3 = diag(s - j)` and the
/// ladder `S_+` has only its first superdiagonal, `sqrt(j (N - j))` at
/// `(j - 1, j)` ([`crate::sphere::spin`]).
fn spin_commutators(w: &DMatrix<C>) -> [DMatrix<C>; 3] {
    let n = w.nrows();
    let ladder = |j: usize| ((j * (n - j)) as f64).sqrt(); // S_+[j - 1, j]
    let zero = C::new(0.0, 0.0);
    // [S_+, W] and [S_-, W] with S_- = S_+^T.
    let plus = DMatrix::from_fn(n, n, |j, k| {
        let left = if j + 1 < n { w[(j + 1, k)] * ladder(j + 1) } else { zero };
        let right = if k > 0 { w[(j, k - 1)] * ladder(k) } else { zero };
        left - right
    });
    let minus = DMatrix::from_fn(n, n, |j, k| {
        let left = if j > 0 { w[(j - 1, k)] * ladder(j) } else { zero };
        let right = if k + 1 < n { w[(j, k + 1)] * ladder(k + 1) } else { zero };
        left - right
    });
    let c1 = (&plus + &minus) * C::new(0.5, 0.0);
    let c2 = (&plus - &minus) * C::new(0.0, -0.5);
    let s = (n as f64 - 1.0) / 2.0;
    let c3 = DMatrix::from_fn(n, n, |j, k| w[(j, k)] * ((s - j as f64) - (s - k as f64)));
    [c1, c2, c3]
}

/// `|[a, b]|_F / (|a|_F |b|_F)`, 0 when either is 0.
fn relative_commutator(a: &DMatrix<C>, b: &DMatrix<C>) -> f64 {
    let d = a.norm() * b.norm();
    if d > 0.0 {
        commutator(a, b).norm() / d
    } else {
        0.0
    }
}

/// The relative off-diagonal part `|offdiag M|_F / |M|_F` (0 for 0).
fn off_diagonal(m: &DMatrix<C>) -> f64 {
    let total = m.norm();
    if total == 0.0 {
        return 0.0;
    }
    let diag: f64 = (0..m.nrows()).map(|j| m[(j, j)].norm_sqr()).sum();
    (m.norm_squared() - diag).max(0.0).sqrt() / total
}

/// The Hermitian eigen-decomposition of `-i W`: eigenvalues ascending and
/// the unitary `U` (`-i W = U diag U^*`).
fn eigenbasis(w: &DMatrix<C>) -> Result<(Vec<f64>, DMatrix<C>), ZeitlinError> {
    let n = w.nrows();
    if off_diagonal(w) == 0.0 {
        // Diagonal: the eigenbasis is the sorting permutation, exactly.
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&i, &j| w[(i, i)].im.total_cmp(&w[(j, j)].im));
        let values = order.iter().map(|&i| w[(i, i)].im).collect();
        let u = DMatrix::from_fn(n, n, |i, j| C::new(if order[j] == i { 1.0 } else { 0.0 }, 0.0));
        return Ok((values, u));
    }
    let h = w * C::new(0.0, -1.0);
    let h = (&h + h.adjoint()) * C::new(0.5, 0.0);
    crate::eigen::hermitian_eigen(&h)
        .ok_or_else(|| ZeitlinError::Numerical("the eigenvalues of -i W_e did not converge".into()))
}

/// Cluster labels of sorted eigenvalues: consecutive values closer than
/// `1e-8` of the spread share a cluster.
fn clusters(values: &[f64]) -> Vec<usize> {
    let spread = values.last().copied().unwrap_or(0.0) - values.first().copied().unwrap_or(0.0);
    let gap = 1e-8 * spread.abs().max(f64::MIN_POSITIVE);
    let mut label = 0;
    values
        .iter()
        .enumerate()
        .map(|(j, v)| {
            if j > 0 && v - values[j - 1] > gap {
                label += 1;
            }
            label
        })
        .collect()
}

/// The projection of `x` onto the commutant of `W` (eigenbasis `u`, cluster
/// labels `cl`): the entries of `U^* x U` between equal eigenvalues.
fn compatible_part(x: &DMatrix<C>, u: &DMatrix<C>, cl: &[usize]) -> DMatrix<C> {
    let product = crate::eigen::complex_product;
    let mut t = product(&product(&u.adjoint(), x), u);
    let n = t.nrows();
    for j in 0..n {
        for k in 0..n {
            if cl[j] != cl[k] {
                t[(j, k)] = C::new(0.0, 0.0);
            }
        }
    }
    let p = product(&product(u, &t), &u.adjoint());
    (&p - p.adjoint()) * C::new(0.5, 0.0)
}

/// Run the general pipeline (see the module docs).
///
/// ```
/// use zeitlin::general::{analyse_general, Frame, GeneralProblem, GeneralSettings};
/// use zeitlin::sphere::{from_harmonics, rotation_to_axis};
/// // A zonal state, z + 0.3 z^3-like, with zonal noise, tilted to the spin
/// // axis (0.6, 0, 0.8): quflow's axis (-0.6, 0, 0.8) (`quflow_axis`).
/// let n = 8;
/// let w = from_harmonics(n, &[(1, 0, 1.0), (3, 0, 0.2)]).unwrap();
/// let x = from_harmonics(n, &[(2, 0, 0.1)]).unwrap();
/// let v = rotation_to_axis(n, [0.6, 0.0, 0.8]).unwrap();
/// let tilt = |m: &nalgebra::DMatrix<nalgebra::Complex<f64>>| &v * m * v.adjoint();
/// let a = analyse_general(&GeneralProblem { n, w: tilt(&w), noise: vec![tilt(&x)] }, &GeneralSettings::default()).unwrap();
/// assert_eq!(a.verdict, outcome::Verdict::Stable);
/// match a.frame { Some(Frame::Rotated { axis }) => assert!((axis[0] + 0.6).abs() < 1e-9 && (axis[2] - 0.8).abs() < 1e-9), _ => panic!() }
/// ```
pub fn analyse_general(problem: &GeneralProblem, settings: &GeneralSettings) -> Result<GeneralAnalysis, ZeitlinError> {
    analyse_general_with(problem, settings, &Progress::new())
}

/// [`analyse_general`] with progress and cancellation: a zonal state
/// reports the zonal analysis's block operations
/// ([`crate::analysis::analyse_with`]); the dense analysis counts as one
/// step per solve and is cancelled between its solves; the matrix-free one
/// counts one step per operator iteration and is cancelled between them.
pub fn analyse_general_with(
    problem: &GeneralProblem,
    settings: &GeneralSettings,
    progress: &Progress,
) -> Result<GeneralAnalysis, ZeitlinError> {
    let n = problem.n;
    let input = Scaled::new(problem)?;
    let solver = StreamSolver::new(n).map_err(|e| ZeitlinError::Numerical(e.to_string()))?;
    let hb = hbar(n);
    let mut out = GeneralAnalysis {
        verdict: Verdict::Inconclusive,
        level: VerificationLevel::Numerical,
        reason: String::new(),
        equilibrium_residual: 0.0,
        noise_residuals: vec![0.0; input.noise.len()],
        compatible_noise: vec![],
        frame: None,
        zonal: None,
        dense: None,
        matrix_free: None,
        hbar: hb,
    };
    let p = solver.solve(&input.w).map_err(|e| ZeitlinError::Numerical(e.to_string()))?;
    if !is_equilibrium(&mut out, &p, &input.w, settings) || !noise_is_compatible(&mut out, &input, settings)? {
        return Ok(out);
    }
    if let Some((frame, reduced)) = zonal_frame(&input, settings.equilibrium_tolerance)? {
        analyse_zonal_frame(&mut out, &input, frame, reduced, &settings.zonal, progress)?;
        return Ok(out);
    }
    out.frame = Some(Frame::General);
    if n > settings.dense_max_n && n > settings.matrix_free_max_n {
        out.reason = format!(
            "W_e is zonal about no axis, and such states are analysed densely up to N = {} (settings.dense_max_n; N^2 - 1 unknowns, O(N^6) work) and matrix-free up to N = {} (settings.matrix_free_max_n)",
            settings.dense_max_n, settings.matrix_free_max_n
        );
        return Ok(out);
    }
    if n > settings.dense_max_n {
        let m = matrix_free_in_units(&solver, &input, &p, &settings.matrix_free, progress)?;
        out.reason = matrix_free_reason(&m, n);
        if m.eigenvalue.is_some() {
            out.verdict = Verdict::LinearlyUnstable;
        }
        out.matrix_free = Some(m);
        return Ok(out);
    }
    let d = dense_in_units(&solver, &input, &p, progress)?;
    dense_verdict(&mut out, d);
    Ok(out)
}

/// The input at unit size: `W_e` and each noise field, skew-Hermitian and
/// trace-free, divided by a power of two (`s_w`, and each field's own).
struct Scaled {
    n: usize,
    w: DMatrix<C>,
    s_w: f64,
    noise: Vec<(DMatrix<C>, f64)>,
}

impl Scaled {
    /// [`normalised`] for `W_e` and each noise field, after checking `N`.
    fn new(problem: &GeneralProblem) -> Result<Scaled, ZeitlinError> {
        let n = problem.n;
        if !(2..=4096).contains(&n) {
            return Err(ZeitlinError::Input(format!("N must be between 2 and 4096, got {n}")));
        }
        let (w, s_w) = normalised(&problem.w, n, "equilibrium")?;
        let noise: Vec<(DMatrix<C>, f64)> = problem
            .noise
            .iter()
            .enumerate()
            .map(|(i, x)| normalised(x, n, &format!("noise[{i}]")))
            .collect::<Result<_, _>>()?;
        Ok(Scaled { n, w, s_w, noise })
    }
}

/// Whether `|[P_e, W_e]|_F / (|P_e|_F |W_e|_F)` (stored in `out`) is within
/// the tolerance; if not, the verdict says `W_e` is not steady.
fn is_equilibrium(out: &mut GeneralAnalysis, p: &DMatrix<C>, w: &DMatrix<C>, settings: &GeneralSettings) -> bool {
    out.equilibrium_residual = relative_commutator(p, w);
    if out.equilibrium_residual > settings.equilibrium_tolerance {
        out.verdict = Verdict::NotAnEquilibrium;
        out.reason = format!(
            "[P_e, W_e] is not zero: |[P_e, W_e]|_F / (|P_e|_F |W_e|_F) = {:.3e} > {:.0e} (settings.equilibrium_tolerance): W_e is not a steady state",
            out.equilibrium_residual, settings.equilibrium_tolerance
        );
        return false;
    }
    true
}

/// Whether every `|[X_i, W_e]|_F / (|X_i|_F |W_e|_F)` (stored in `out`) is
/// within the tolerance; if not, the verdict says so and gives each
/// field's projection onto the commutant of `W_e`, in the user's units.
fn noise_is_compatible(
    out: &mut GeneralAnalysis,
    input: &Scaled,
    settings: &GeneralSettings,
) -> Result<bool, ZeitlinError> {
    let noise = &input.noise;
    out.noise_residuals = noise.iter().map(|(x, _)| relative_commutator(x, &input.w)).collect();
    let incompatible: Vec<usize> =
        (0..noise.len()).filter(|&i| out.noise_residuals[i] > settings.noise_tolerance).collect();
    if incompatible.is_empty() {
        return Ok(true);
    }
    let (values, u) = eigenbasis(&input.w)?;
    let cl = clusters(&values);
    out.compatible_noise = noise.iter().map(|(x, s)| compatible_part(x, &u, &cl) * C::new(*s, 0.0)).collect();
    out.verdict = Verdict::NoiseIncompatible;
    out.reason = format!(
        "[X_i, W_e] is not zero for noise field(s) {incompatible:?} (relative {:.3e} > {:.0e}): the noise moves the equilibrium; compatible noise commutes with W_e (for distinct eigenvalues: the functions of W_e), and compatible_noise gives each field's compatible part",
        incompatible.iter().map(|&i| out.noise_residuals[i]).fold(0.0f64, f64::max),
        settings.noise_tolerance
    );
    Ok(false)
}

/// `W_e` and the noise in a frame `V` (`V^* M V`), with the largest
/// relative off-diagonal part among them.
struct InFrame {
    w: DMatrix<C>,
    noise: Vec<DMatrix<C>>,
    off_diagonal: f64,
}

/// The state and noise in the frame `v` (as given for `None`), when every
/// one of them is diagonal there to the tolerance.
fn zonal_in(input: &Scaled, v: Option<&DMatrix<C>>, tol: f64) -> Option<InFrame> {
    let product = crate::eigen::complex_product;
    let frame = |m: &DMatrix<C>| match v {
        Some(v) => product(&product(&v.adjoint(), m), v),
        None => m.clone(),
    };
    let wf = frame(&input.w);
    let xs: Vec<DMatrix<C>> = input.noise.iter().map(|(x, _)| frame(x)).collect();
    let off = xs.iter().map(off_diagonal).fold(off_diagonal(&wf), f64::max);
    (off <= tol).then_some(InFrame { w: wf, noise: xs, off_diagonal: off })
}

/// A frame in which the state and noise are zonal: as given, or rotated
/// from the symmetry axis of `W_e` to the pole.
fn zonal_frame(input: &Scaled, tol: f64) -> Result<Option<(Frame, InFrame)>, ZeitlinError> {
    // Zonal as given, or about some axis.
    let mut reduced = zonal_in(input, None, tol).map(|r| (Frame::Zonal, r));
    if reduced.is_none() {
        if let Some(axis) = symmetry_axis(&input.w, tol) {
            let v = rotation_to_axis(input.n, axis).map_err(|e| ZeitlinError::Numerical(e.to_string()))?;
            reduced = zonal_in(input, Some(&v), tol).map(|r| (Frame::Rotated { axis: quflow_axis(axis) }, r));
        }
    }
    Ok(reduced)
}

/// The zonal pipeline on the diagonals in the zonal frame, in the user's
/// units; its verdict is the pipeline's.
fn analyse_zonal_frame(
    out: &mut GeneralAnalysis,
    input: &Scaled,
    frame: Frame,
    reduced: InFrame,
    settings: &ZeitlinSettings,
    progress: &Progress,
) -> Result<(), ZeitlinError> {
    let n = input.n;
    let diagonal = |m: &DMatrix<C>, s: f64| -> Vec<f64> { (0..n).map(|j| m[(j, j)].im * s).collect() };
    let omega = diagonal(&reduced.w, input.s_w);
    let noise_diag: Vec<Vec<f64>> = reduced.noise.iter().zip(&input.noise).map(|(x, (_, s))| diagonal(x, *s)).collect();
    let a = analyse_with(&ZeitlinProblem { n, omega: omega.clone(), noise: noise_diag.clone() }, settings, progress)?;
    out.verdict = a.verdict;
    out.level = a.level;
    out.reason = match &frame {
        Frame::Zonal => a.reason.clone(),
        Frame::Rotated { axis } => format!(
            "zonal about the axis ({:.6}, {:.6}, {:.6}), analysed in the rotated frame (the model is rotation invariant): {}",
            axis[0], axis[1], axis[2], a.reason
        ),
        Frame::General => unreachable!("a zonal frame"),
    };
    out.frame = Some(frame);
    out.zonal = Some(ZonalReduction { omega, noise: noise_diag, off_diagonal: reduced.off_diagonal, analysis: a });
    Ok(())
}

/// The matrix-free analysis of the unit-size state, in the user's units.
fn matrix_free_in_units(
    solver: &StreamSolver,
    input: &Scaled,
    p: &DMatrix<C>,
    settings: &MatrixFreeSettings,
    progress: &Progress,
) -> Result<MatrixFreeAnalysis, ZeitlinError> {
    let s_w = input.s_w;
    let mut m = matrix_free_analysis(solver, &input.w, p, settings, progress)?;
    progress.settle();
    // Back to the user's units: the drift is linear in W_e.
    m.eigenvalue = m.eigenvalue.map(|(re, im)| (re * s_w, im * s_w));
    m.backward_error = m.backward_error.map(|e| e * s_w);
    m.best = m.best.map(|(re, im, e)| (re * s_w, im * s_w, e * s_w));
    m.drift_norm *= s_w;
    m.resolution *= s_w;
    m.tau /= s_w;
    Ok(m)
}

/// The dense analysis of the unit-size state, in the user's units: at the
/// noise fields' common scale (a second run when their scales differ).
fn dense_in_units(
    solver: &StreamSolver,
    input: &Scaled,
    p: &DMatrix<C>,
    progress: &Progress,
) -> Result<DenseAnalysis, ZeitlinError> {
    let (w, noise) = (&input.w, &input.noise);
    let xs: Vec<DMatrix<C>> = noise.iter().map(|(x, _)| x.clone()).collect();
    progress.plan(2);
    progress.check()?;
    let mut d = dense_analysis(solver, w, p, &xs)?;
    progress.step(1);
    // Back to the user's units: Sigma^2 scales as the noise squared (the
    // fields were each scaled to unit size: one common factor only when
    // they share a scale, else the fields were rescaled relative to each
    // other and the analysis is redone at the common scale).
    let common = noise.iter().map(|(_, s)| *s).fold(0.0f64, f64::max);
    if noise.iter().any(|(_, s)| *s != common) {
        let xs: Vec<DMatrix<C>> = noise.iter().map(|(x, s)| x * C::new(s / common, 0.0)).collect();
        progress.check()?;
        d = dense_analysis(solver, w, p, &xs)?;
    }
    progress.settle();
    let k2 = common * common;
    let unscale = |x: f64| x * k2;
    d.sigma2 = d.sigma2.map(unscale);
    d.infimum = d.infimum.map(unscale);
    d.growth_rate = d.growth_rate.map(|g| g * input.s_w);
    Ok(d)
}

/// The verdict and its sentence from the dense analysis: stable with a
/// definite form and a finite `Sigma^2`, unstable with a growing mode,
/// else inconclusive.
fn dense_verdict(out: &mut GeneralAnalysis, d: DenseAnalysis) {
    match (d.energy != 0.0, d.sigma2, d.growth_rate) {
        (true, Some(s2), _) if s2.is_finite() => {
            out.verdict = Verdict::Stable;
            out.reason = format!(
                "the energy–Casimir form (energy coefficient {:+}) is definite on the orbit's tangent space: formally stable; E|dW_t|_P^2 <= |dW_0|_P^2 e^(Sigma^2 t), Sigma^2 by a dense generalized eigenproblem in dimension {}",
                d.energy, d.dimension
            );
        }
        (true, _, _) => {
            out.reason = "a definite energy–Casimir form was found, but Sigma^2 could not be computed".into();
        }
        (false, _, Some(rate)) if rate > 0.0 => {
            out.verdict = Verdict::LinearlyUnstable;
            out.reason = format!(
                "no energy–Casimir form is definite, and the drift has an eigenvalue with real part {rate:.6e} (dense, dimension {})",
                d.dimension
            );
        }
        (false, _, _) if !d.distinct_eigenvalues => {
            out.reason = "W_e has repeated eigenvalues, for which no energy–Casimir test is made, and every eigenvalue of the drift is on the imaginary axis (to the tolerance): spectrally stable only".into();
        }
        (false, _, _) => {
            out.reason = format!(
                "no energy–Casimir form is definite (best restricted margin {:.3e}), and every eigenvalue of the drift is on the imaginary axis (to the tolerance): spectrally stable only",
                d.restricted_margin
            );
        }
    }
    out.dense = Some(d);
}

/// `x` with the significant digits a backward error `e` supports: the
/// last printed digit is the first at or above `e` (an eigenvalue of a
/// matrix within `e` of `A` moves about that far when it is well
/// conditioned; a non-normal `A` can move it further, which the sentence's
/// "numerical" says). At least 1 and at most 9 digits.
///
/// ```
/// // the Rossby–Haurwitz N = 64 growth rate, backward error 8.5e-8: the
/// // printed digits are those of the true 1.927101643e-1
/// assert_eq!(zeitlin::general::supported_digits(1.9271016504435295e-1, 8.499851366887463e-8), "1.92710e-1");
/// ```
pub fn supported_digits(x: f64, e: f64) -> String {
    let digits = if x == 0.0 || e.is_nan() || e <= 0.0 || !x.is_finite() {
        9
    } else {
        ((x.abs() / e).log10().floor() as i64).clamp(1, 9) as usize
    };
    format!("{x:.*e}", digits - 1)
}

/// The verdict's sentence for a matrix-free analysis (the verdict is
/// `linearly_unstable` when a growing eigenpair was accepted, else
/// `inconclusive`).
fn matrix_free_reason(m: &MatrixFreeAnalysis, n: usize) -> String {
    let form = match (m.distinct_eigenvalues, m.restricted_ritz, m.indefinite) {
        (false, _, _) => "W_e has repeated eigenvalues, for which no energy–Casimir test is made".to_string(),
        (true, Some((lo, hi)), true) => format!(
            "no energy–Casimir form is definite (Lanczos Ritz values {lo:.6e} and {hi:.6e} of the restricted Hessian prove it indefinite)"
        ),
        (true, Some((lo, hi)), false) => format!(
            "the restricted Hessian's Ritz values ({lo:.6e} to {hi:.6e}) do not prove it indefinite (that needs one beyond 1e-9 of the largest on each side), so a definite form may exist, but the matrix-free analysis does not compute Sigma^2 (the dense one does, up to N = 48)"
        ),
        (true, None, _) => "no energy–Casimir test was made".to_string(),
    };
    match (m.eigenvalue, m.backward_error) {
        (Some((re, im)), Some(e)) => format!(
            "{form}, and the drift has the eigenvalue {} ± {} i, found matrix-free (Arnoldi on a split propagator, then Davidson; dimension {}), with backward error |A v - lambda v|_F / |v|_F = {e:.3e}: linearly unstable (numerical)",
            supported_digits(re, e),
            supported_digits(im, e),
            m.dimension
        ),
        _ => {
            // A real part below the resolution is rounding (it differs
            // between machines): only its bound is printed.
            let best = match m.best {
                Some((re, im, e)) if re > m.resolution => format!(
                    "; the rightmost converged eigenvalue, {re:.6e} ± {im:.6e} i, has the backward error {e:.3e}, too large to accept"
                ),
                Some(_) => format!(
                    "; every converged eigenvalue has a real part below the resolution {:.3e} (1e-4 |W_e|_op)",
                    m.resolution
                ),
                None => String::new(),
            };
            format!(
                "{form}, and the matrix-free search (N = {n}, dimension {}) found no growing eigenvalue of the drift{best}: no verdict (a search that finds nothing proves nothing)",
                m.dimension
            )
        }
    }
}

/// A unit axis `n` with `[n.S, W] = 0` (relative to `|S_3|_F |W|_F`, within
/// `tol`): the eigenvector of the Gram matrix `<[S_a, W], [S_b, W]>` for its
/// smallest eigenvalue, if that is small enough.
fn symmetry_axis(w: &DMatrix<C>, tol: f64) -> Option<[f64; 3]> {
    let n = w.nrows();
    let c = spin_commutators(w);
    let gram: nalgebra::Matrix3<f64> =
        nalgebra::Matrix3::from_fn(|a, b| c[a].iter().zip(c[b].iter()).map(|(x, y)| (x * y.conj()).re).sum());
    let e = nalgebra::linalg::SymmetricEigen::try_new(gram, f64::EPSILON, 1000)?;
    let i = (0..3).min_by(|&i, &j| e.eigenvalues[i].total_cmp(&e.eigenvalues[j]))?;
    // Components at rounding level (1e-13) are set to zero, and the sign
    // fixed (largest component positive), so the axis a certificate records
    // does not carry rounding noise.
    let mut axis = [e.eigenvectors[(0, i)], e.eigenvectors[(1, i)], e.eigenvectors[(2, i)]];
    axis.iter_mut().for_each(|x| {
        if x.abs() < 1e-13 {
            *x = 0.0
        }
    });
    let norm = axis.iter().map(|x| x * x).sum::<f64>().sqrt();
    let big = axis.iter().copied().fold(0.0f64, |a, x| if x.abs() > a.abs() { x } else { a });
    axis.iter_mut().for_each(|x| *x *= big.signum() / norm);
    // Measured directly: the smallest eigenvalue of the Gram matrix carries
    // rounding of about eps |g|, whose square root (1e-8 relative) would
    // hide a true zero.
    let commutes = &c[0] * C::new(axis[0], 0.0) + &c[1] * C::new(axis[1], 0.0) + &c[2] * C::new(axis[2], 0.0);
    // |S_3|_F = sqrt(sum_j (s - j)^2) = sqrt(N (N^2 - 1) / 12).
    let nf = n as f64;
    let scale = (nf * (nf * nf - 1.0) / 12.0).sqrt() * w.norm();
    (scale > 0.0 && commutes.norm() <= tol * scale).then_some(axis)
}
