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

mod block;
mod normalised;

use normalised::analyse_normalised;
use numerics::scaling::Rescaling;
use outcome::{Cancelled, Progress, Verdict, VerificationLevel};

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
