//! The energy–Casimir method for large systems, in floating point.
//!
//! Steps (docs/architecture.md §2, with the exact engine's choices where they carry
//! over; every dense operation by faer):
//!
//! 1. the equilibrium and noise residuals, exactly ([`LargeSystem`]);
//! 2. the multipliers: `G lambda = -Dh` by the SVD of the gradient matrix
//!    `G` (`n x r`), with its relative residual; the family is `lambda_p +
//!    sum t_i d_i` over the null space of `G`;
//! 3. Finsler: the restricted Hessian `R(t) = Z^T B(t) Z` on `ker G^T` (`Z`
//!    from the SVD, orthonormal), definite of one sign `s` with a relative
//!    margin above the tolerance, `lambda_min(s R(t))` maximised over the
//!    family by the ellipsoid method (then, when `Q` does not depend on the
//!    Casimir Hessian, the restricted `lambda_max` minimised over it);
//! 4. the linearisation `A` and the noise operators `B_i` as sparse
//!    matrices, and `Q(P) = sym(P A~ + A~^T P + sum_i B_i^T P B_i)` with
//!    `A~ = A + 1/2 sum B_i^2`, in `O(nnz n)`;
//! 5. in the frame `[Z W]` (`W` orthonormal on the range of `G`) the
//!    Casimir Hessian by the Schur completion
//!    ([`numerics::dense::FramePencil::complete`]) when the noise keeps every
//!    conserved quantity (then `Q` does not depend on it and the infimum over
//!    it is `lambda_max` restricted to `ker G^T`); otherwise the reference
//!    choice `K = (K0)_+ + m I`, unoptimised;
//! 6. `Sigma^2 = lambda_max(sQ, sP)` by a dense generalized eigenproblem;
//! 7. without a definite form, the eigenvalues of the dense drift decide
//!    `linearly_unstable` (real part above `1e-6` of the spectral radius)
//!    or `inconclusive`.
//!
//! The steps are private submodules: `multipliers` (the derivatives and step
//! 2), `form` (step 3), `linearise` (step 4) and `frame` (steps 5 and 6); the
//! verdicts (step 7 and the verified check) are here.

mod form;
mod frame;
mod linearise;
mod multipliers;

use crate::system::LargeSystem;
use crate::verified::{Choice, VerifiedPencil};
use crate::LargeError;
use exact::Rational;
use form::{minimise_sigma2, Family, RestrictedPencil};
use frame::{drift_residual, final_pencil};
use linearise::{Linearisation, Sparse};
use multipliers::{derivatives, Multipliers};
use numerics::scaling::Rescaling;
use outcome::{Progress, Verdict, VerificationLevel};
use std::collections::BTreeMap;
use std::sync::Arc;

/// Settings, with documented defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct LargeSettings {
    /// A restricted Hessian counts as definite only above this relative
    /// margin `lambda_min(sR)/max|eig R|`. Default 1e-9 (the exact engine's).
    pub definiteness_tolerance: f64,
    /// Largest relative residual `|G lambda + Dh| / |Dh|` for multipliers to
    /// exist. Default 1e-9.
    pub multiplier_tolerance: f64,
    /// An eigenvalue of `A` proves linear instability only above this times
    /// the spectral radius. Default 1e-6.
    pub instability_tolerance: f64,
    /// The Casimir Hessian is grown only while `cond(P)` stays at most this.
    /// Default 1e10.
    pub condition_limit: f64,
    /// Largest dimension for the dense spectrum of the drift. Default 2048.
    pub instability_max_dim: usize,
    /// Largest dimension for the `verified_float` final check (two dense
    /// verified Cholesky factorisations, `n^3/3` each). Default 2500.
    pub verified_max_dim: usize,
}

impl Default for LargeSettings {
    fn default() -> Self {
        LargeSettings {
            definiteness_tolerance: 1e-9,
            multiplier_tolerance: 1e-9,
            instability_tolerance: 1e-6,
            condition_limit: 1e10,
            instability_max_dim: 2048,
            verified_max_dim: 2500,
        }
    }
}

/// Everything the pipeline found.
#[derive(Clone, Debug)]
pub struct LargeAnalysis {
    /// The verdict.
    pub verdict: Verdict,
    /// The verification level (`exact` for the two early verdicts).
    pub level: VerificationLevel,
    /// One sentence explaining it.
    pub reason: String,
    /// `ad*_{Dh(mu_e)} mu_e`, exactly (nonzero entries).
    pub equilibrium_residual: BTreeMap<usize, Rational>,
    /// `ad*_{sigma_i} mu_e` per noise field (nonzero entries).
    pub noise_residuals: Vec<BTreeMap<usize, Rational>>,
    /// The multipliers (Casimirs, then first integrals).
    pub multipliers: Vec<f64>,
    /// `|G lambda + Dh| / |Dh|`.
    pub multiplier_residual: f64,
    /// `r - rank G`: free multiplier directions (searched).
    pub family_dimension: usize,
    /// `dim ker G^T`.
    pub restricted_dimension: usize,
    /// `+1` or `-1` for a definite form, 0 for none.
    pub sign: f64,
    /// The larger of the two relative margins.
    pub restricted_margin: f64,
    /// Whether `Q` depends on the Casimir Hessian (the noise does not keep
    /// every conserved quantity).
    pub q_depends_on_casimirs: bool,
    /// `Sigma^2` at the chosen form.
    pub sigma2: Option<f64>,
    /// A proved upper bound on `Sigma^2` (level `verified_float`,
    /// [`crate::VerifiedPencil`]).
    pub sigma2_upper: Option<f64>,
    /// The exact multipliers of the verified functional.
    pub exact_multipliers: Option<Vec<Rational>>,
    /// Why a stable verdict stays `numerical` (no verified check), if so.
    pub verification: Option<String>,
    /// The verified check's matrices, to prove other bounds (a stated
    /// `sigma2_upper` when a certificate is checked).
    pub pencil: Option<Arc<VerifiedPencil>>,
    /// `Sigma^2` of the system as given is the pencil's times `4^e`, with
    /// `2^e` the exact power-of-two rescaling of the noise.
    pub pencil_rescaling: Rescaling,
    /// Its infimum over the Casimir Hessian (when `Q` does not depend on it).
    pub infimum: Option<f64>,
    /// `cond(sP)`.
    pub condition_number: Option<f64>,
    /// `|P A + A^T P|_F / (|P|_F |A|_F)` at the chosen `P`.
    pub drift_residual: f64,
    /// The largest real part of the drift's eigenvalues (without a form).
    pub growth_rate: Option<f64>,
}

/// The relative margins tried, in order, for the verified bound
/// `sigma2 (1 + m)`.
pub const VERIFIED_MARGINS: [f64; 4] = [1e-8, 1e-6, 1e-4, 1e-2];

impl LargeAnalysis {
    /// Whether `bar` (for the system as given) is proved an upper bound on
    /// `Sigma^2` by the verified check ([`crate::VerifiedPencil`]); `false` when
    /// there is no verified check.
    pub fn proves_upper(&self, bar: f64) -> bool {
        match &self.pencil {
            // (rounded down in the pencil's units: proving less proves bar)
            Some(p) => p.proves(self.pencil_rescaling.square_down(bar)),
            _ => false,
        }
    }
}

/// Run the pipeline (see the module docs).
///
/// ```
/// use large::SparseAlgebra;
/// use large::{parse_sparse, SparseSymbols};
/// use large::LargeSystem;
/// use large::{analyse_large, LargeSettings};
/// use exact::Rational;
/// // The rigid body about its major axis (I = 3, 2, 1), noise 3/10 along it:
/// // Sigma^2 = sigma^2 I1 (I2 - I3)/(I3 (I1 - I2)) = 0.27.
/// let names: Vec<String> = ["P1", "P2", "P3"].iter().map(|s| s.to_string()).collect();
/// let one = Rational::from(1);
/// let rows = vec![(0, 1, 2, one.clone()), (1, 2, 0, one.clone()), (2, 0, 1, one.clone())];
/// let g = SparseAlgebra::new(&names, &rows).unwrap();
/// let s = SparseSymbols::new(&names, &Default::default());
/// let h = parse_sparse("P1^2/6 + P2^2/4 + P3^2/2", &s).unwrap();
/// let c = parse_sparse("(P1^2 + P2^2 + P3^2)/2", &s).unwrap();
/// let q = |n: i64, d: i64| Rational::new_small(n, d);
/// let system = LargeSystem::new(g, h, vec![c], vec![], vec![q(1, 1), q(0, 1), q(0, 1)], vec![vec![q(3, 10), q(0, 1), q(0, 1)]]).unwrap();
/// let a = analyse_large(&system, &LargeSettings::default()).unwrap();
/// assert_eq!(a.verdict, outcome::Verdict::Stable);
/// assert!((a.sigma2.unwrap() - 0.27).abs() < 1e-7 * 0.27);
/// ```
pub fn analyse_large(system: &LargeSystem, settings: &LargeSettings) -> Result<LargeAnalysis, LargeError> {
    analyse_large_with(system, settings, &Progress::new())
}

/// [`analyse_large`] with progress in four steps (the derivatives and
/// multipliers, the search for a definite form, the minimisation of
/// `Sigma^2`, the final eigenproblems), stopping with
/// [`LargeError::Cancelled`] soon after [`Progress::cancel`]: between the
/// steps and between the iterations of the search and of the minimisation.
pub fn analyse_large_with(
    system: &LargeSystem,
    settings: &LargeSettings,
    progress: &Progress,
) -> Result<LargeAnalysis, LargeError> {
    progress.plan(4);
    let a = analyse_scaled(system, settings, progress)?;
    // A cancelled run ends early with meaningless values: never a result.
    progress.check()?;
    progress.settle();
    Ok(a)
}

fn analyse_scaled(
    system: &LargeSystem,
    settings: &LargeSettings,
    progress: &Progress,
) -> Result<LargeAnalysis, LargeError> {
    // Sigma^2 scales as the noise squared: the noise is brought to unit size
    // by a power of two (exact), analysed, and the result scaled back, so
    // that noise near 1e-200 or 1e200 neither underflows to a false
    // Sigma^2 = 0 nor overflows. A result outside the double range is
    // inconclusive, never stable.
    // (The largest magnitude exactly: an entry of 1e-400 is not zero.)
    let exponent = system.noise().iter().flatten().filter_map(exact::binary_exponent).max();
    let Some(exponent) = exponent.filter(|e| *e != 0) else {
        return analyse_normalised(system, settings, progress);
    };
    let scale = exact::power_of_two(-exponent);
    let scaled = system.with_noise(system.noise().iter().map(|f| f.iter().map(|x| x * &scale).collect()).collect());
    let mut a = analyse_normalised(&scaled, settings, progress)?;
    // Residuals are exact and scale-free in their verdict; Sigma^2 scales
    // by 4^exponent (beyond 2^±1000 no double holds the result).
    let rescaling = (exponent.unsigned_abs() <= 1000).then(|| Rescaling::new(exponent as i32));
    if let Some(s) = a.sigma2 {
        match rescaling.filter(|r| r.out_of_range(s).is_none()) {
            None => {
                a.verdict = Verdict::Inconclusive;
                a.reason = "a definite form was found, but Sigma^2 lies outside the range of double precision: rescale the noise"
                    .into();
                a.sigma2 = None;
                a.infimum = None;
                a.sigma2_upper = None;
                a.pencil = None;
                a.level = VerificationLevel::Numerical;
            }
            Some(r) => {
                a.sigma2 = Some(r.square(s));
                a.infimum = a.infimum.map(|x| r.square(x));
                a.pencil_rescaling = r;
                if let Some(upper) = a.sigma2_upper {
                    match r.square_bound(upper) {
                        Some(u) => a.sigma2_upper = Some(u),
                        None => {
                            a.sigma2_upper = None;
                            a.level = VerificationLevel::Numerical;
                            a.verification = Some(
                                "the verified bound lies outside the normal double range after rescaling the noise"
                                    .into(),
                            );
                            a.pencil = None;
                        }
                    }
                }
            }
        }
    }
    a.noise_residuals = system.noise_residuals();
    Ok(a)
}

/// A step's floating-point failure.
fn numerical(what: &str) -> LargeError {
    LargeError::Numerical(what.to_string())
}

/// The analysis before any step: the exact residuals, nothing decided.
fn unanalysed(system: &LargeSystem) -> LargeAnalysis {
    LargeAnalysis {
        verdict: Verdict::Inconclusive,
        level: VerificationLevel::Numerical,
        reason: String::new(),
        equilibrium_residual: system.equilibrium_residual(),
        noise_residuals: system.noise_residuals(),
        multipliers: vec![],
        multiplier_residual: 0.0,
        family_dimension: 0,
        restricted_dimension: 0,
        sign: 0.0,
        restricted_margin: f64::NEG_INFINITY,
        q_depends_on_casimirs: false,
        sigma2: None,
        sigma2_upper: None,
        exact_multipliers: None,
        verification: None,
        pencil: None,
        pencil_rescaling: Rescaling::identity(),
        infimum: None,
        condition_number: None,
        drift_residual: 0.0,
        growth_rate: None,
    }
}

/// The two exact verdicts: `ad*_{Dh(mu_e)} mu_e != 0` (not an equilibrium),
/// else `ad*_{sigma_i} mu_e != 0` for some `i` (the noise moves it). Whether one was given.
fn early_verdict(out: &mut LargeAnalysis) -> bool {
    if !out.equilibrium_residual.is_empty() {
        out.verdict = Verdict::NotAnEquilibrium;
        out.level = VerificationLevel::Exact;
        out.reason = format!(
            "ad*_{{Dh(mu_e)}} mu_e is not zero ({} nonzero components, proved exactly): mu_e is not an equilibrium",
            out.equilibrium_residual.len()
        );
        return true;
    }
    let incompatible: Vec<usize> =
        (0..out.noise_residuals.len()).filter(|&i| !out.noise_residuals[i].is_empty()).collect();
    if !incompatible.is_empty() {
        out.verdict = Verdict::NoiseIncompatible;
        out.level = VerificationLevel::Exact;
        let shown: Vec<usize> = incompatible.iter().take(16).copied().collect();
        out.reason = format!(
            "ad*_sigma mu_e is not zero for {} noise field(s) (the first: {shown:?}; proved exactly): the noise moves the equilibrium",
            incompatible.len()
        );
        return true;
    }
    false
}

/// Without a definite form, the dense spectrum of the drift `A` decides:
/// linearly unstable when an eigenvalue's real part exceeds the tolerance
/// times the spectral radius, else inconclusive (spectrally stable only).
fn no_form(
    out: &mut LargeAnalysis,
    why: &str,
    a: &Sparse,
    n: usize,
    settings: &LargeSettings,
) -> Result<(), LargeError> {
    if n > settings.instability_max_dim {
        out.reason = format!(
            "{why}; the drift's spectrum is computed only up to dimension {} (settings), so nothing more is known",
            settings.instability_max_dim
        );
        return Ok(());
    }
    let values = numerics::dense::real_eigenvalues(&a.dense(n)).ok_or_else(|| numerical("the drift's eigenvalues"))?;
    let rate = values.iter().map(|z| z.re).fold(f64::NEG_INFINITY, f64::max);
    let radius = values.iter().map(|z| z.norm()).fold(0.0f64, f64::max);
    if rate > settings.instability_tolerance * radius.max(f64::MIN_POSITIVE) {
        out.verdict = Verdict::LinearlyUnstable;
        out.growth_rate = Some(rate);
        out.reason = format!("{why}, and the drift has an eigenvalue with real part {rate:.6e} (dense, dimension {n})");
    } else {
        out.growth_rate = Some(0.0);
        out.reason =
            format!("{why}, and every eigenvalue of the drift is on the imaginary axis (to the tolerance): spectrally stable only");
    }
    Ok(())
}

/// The pipeline on noise of unit size (see the module docs), with progress
/// after the multipliers, the search for a form, the minimisation of `Sigma^2`.
fn analyse_normalised(
    system: &LargeSystem,
    settings: &LargeSettings,
    progress: &Progress,
) -> Result<LargeAnalysis, LargeError> {
    let n = system.dim();
    let mut out = unanalysed(system);
    if early_verdict(&mut out) {
        return Ok(out);
    }
    let d = derivatives(system)?;
    // 2. Multipliers by the SVD of G.
    let m = Multipliers::by_svd(&d)?;
    out.multiplier_residual = m.relative_residual;
    out.multipliers = m.lambda.iter().copied().collect();
    out.family_dimension = d.g.ncols() - m.rank;
    out.restricted_dimension = n - m.rank;
    // The linearisation and the noise, sparse.
    let lin = Linearisation::new(system, &d);
    if out.multiplier_residual > settings.multiplier_tolerance {
        let why = format!(
            "no multipliers make mu_e critical (relative residual {:.3e}: Dh(mu_e) is not in the span of the conserved gradients)",
            out.multiplier_residual
        );
        no_form(&mut out, &why, &lin.a, n, settings)?;
        return Ok(out);
    }
    progress.check()?;
    progress.step(1);
    // 3. Finsler on ker G^T, over the family lambda(t) = lambda_p + sum t_i d_i.
    let family = Family::new(system, &d, &m);
    let definite = family.definite_form(settings, progress);
    out.restricted_margin = definite.margin;
    progress.check()?;
    progress.step(1);
    let sign = definite.sign;
    if sign == 0.0 {
        let why = format!(
            "the second variation is not definite on ker G^T for any multipliers searched (best relative margin {:.3e})",
            out.restricted_margin
        );
        no_form(&mut out, &why, &lin.a, n, settings)?;
        return Ok(out);
    }
    out.sign = sign;
    out.q_depends_on_casimirs = !system.noise_conserves_all();
    let mut t = definite.t;
    if family.dimension() > 0 && !out.q_depends_on_casimirs {
        t = minimise_sigma2(&RestrictedPencil::new(&family, &m, &lin, sign), t, progress);
    }
    let form = family.chosen(&m, sign, &t)?;
    out.multipliers = form.lambda.iter().copied().collect();
    progress.check()?;
    progress.step(1);
    // 5. The frame [Z W] = U and the Casimir Hessian (frame::final_pencil).
    let pencil = final_pencil(&form, &m, &lin, sign, out.q_depends_on_casimirs, settings)?;
    // cond(P) is the same in the frame (U is orthogonal).
    out.condition_number = Some(pencil.condition);
    out.drift_residual = drift_residual(&lin.a, &pencil.sp, &m, &pencil.k, &pencil.frame);
    out.sigma2 = Some(pencil.sigma2.max(0.0));
    out.infimum = pencil.infimum;
    out.verdict = Verdict::Stable;
    // The verified_float final check (crate::verified).
    progress.check()?;
    let choice = Choice {
        sign,
        multipliers: form.lambda.as_slice(),
        rank: m.rank,
        u: &m.u,
        v: &m.v,
        singular_values: &m.s_values,
        k: &pencil.k,
    };
    verified_check(&mut out, system, settings, &choice, pencil.sigma2);
    out.reason = format!(
        "the second variation is {} definite on ker G^T (relative margin {:.3e}): formally stable; E|dmu_t|_P^2 <= |dmu_0|_P^2 e^(Sigma^2 t), Sigma^2 by a dense generalized eigenproblem in dimension {n}{}",
        if sign > 0.0 { "positive" } else { "negative" },
        out.restricted_margin,
        if out.q_depends_on_casimirs { " (Q depends on the Casimir Hessian: not optimised)" } else { "" },
    );
    Ok(out)
}

/// The `verified_float` check of the chosen form: `P` and `bar P - Q` proved
/// definite at `bar = sigma2 (1 + m)` for the first margin `m` of
/// [`VERIFIED_MARGINS`] that succeeds; otherwise why not, in `verification`.
fn verified_check(
    out: &mut LargeAnalysis,
    system: &LargeSystem,
    settings: &LargeSettings,
    choice: &Choice,
    sigma2: f64,
) {
    if system.dim() > settings.verified_max_dim {
        out.verification =
            Some(format!("the verified check runs up to dimension {} (settings)", settings.verified_max_dim));
    } else if sigma2.is_nan() || sigma2 <= 0.0 {
        out.verification = Some("Sigma^2 is not positive: no bound above it is tried".into());
    } else {
        match VerifiedPencil::build(system, choice) {
            Err(why) => out.verification = Some(why),
            Ok(pencil) => {
                out.exact_multipliers = Some(pencil.multipliers.clone());
                if !pencil.form_is_definite() {
                    out.verification = Some("P is not proved definite by the verified Cholesky test".into());
                } else {
                    let proved = VERIFIED_MARGINS.iter().map(|m| sigma2 * (1.0 + m)).find(|bar| pencil.proves(*bar));
                    match proved {
                        Some(bar) => {
                            out.sigma2_upper = Some(bar);
                            out.level = VerificationLevel::VerifiedFloat;
                        }
                        None => {
                            out.verification = Some(format!(
                                "bar P - Q is not proved positive definite at sigma2 (1 + m) for m up to {:e}",
                                VERIFIED_MARGINS[VERIFIED_MARGINS.len() - 1]
                            ))
                        }
                    }
                }
                out.pencil = Some(Arc::new(pencil));
            }
        }
    }
}
