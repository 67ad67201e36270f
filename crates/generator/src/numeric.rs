//! The numeric level in floating point throughout: the pipeline of
//! [`crate::analyse`] without exact proofs, for sweeps at the numeric level
//! and for library users who want the verdict and `Sigma^2` fast.
//!
//! docs/architecture.md §3 allows a `numerical` level with "eigenvalues only, no
//! proof". [`crate::analyse`] with `exact = false` still proves `P` definite
//! in rational arithmetic and forms `P` and `Q` exactly (the certificate
//! contract); [`analyse_numeric`] does none of that. What stays exact is
//! what is cheap and decides the two early verdicts: the equilibrium and
//! noise residuals, and whether the noise conserves every first integral.
//!
//! The steps, with the exact pipeline's conventions and tolerances:
//!
//! 1. `Dh` and `D^2h` at `mu_e` (exact in the [`System`], rounded), the
//!    conserved gradients `G` at `mu_e` exactly (whether multipliers exist
//!    and the rank of `G` are decided in rational arithmetic, as the exact
//!    pipeline decides them), the conserved Hessians in floating point;
//! 2. the multipliers `G lambda = -Dh` by the SVD of `G` (rounded, unit
//!    columns), and from it an orthonormal frame `[Z W]`: `Z` spans
//!    `ker G^T`, `W` the range of `G`;
//! 3. the restricted Hessian `Z^T B Z` (`B = D^2h + sum lambda_j D^2K_j`)
//!    definite of sign `s` with a relative margin above
//!    [`casimir::SearchSettings::definiteness_tolerance`] (the positive sign
//!    first);
//! 4. the Casimir Hessian by the Schur completion on the conserved
//!    directions, `sK = K0' + c I` with `c` the level scale `sqrt(l_min
//!    l_max)` of the restricted Hessian, as [`casimir::find_definite_choice`]
//!    constructs it;
//! 5. `Q = sum_i (B_i^T P B_i + sym(P B_i^2))` (the generator form with
//!    the drift part `P A + A^T P`, zero for an energy–Casimir `P`, left
//!    out rather than formed as rounding) and `Sigma^2 =
//!    max(0, lambda_max(sQ, sP))`; the infimum over the Casimir Hessian is
//!    the restricted `lambda_max(Z^T sQ Z, Z^T sP Z)` (the noise conserves
//!    every conserved quantity, so `Q` does not depend on it), and when the
//!    first choice does not attain it, `K` is constructed for targets just
//!    above it, as the exact optimiser does, while `cond(P) <= 1e8`;
//! 6. the spectrum of the drift `A` decides `linearly_unstable` (real part
//!    above [`crate::Settings::instability_tolerance`]) or `inconclusive`
//!    when no definite form exists; a claimed instability is dropped when
//!    the exact spectral test ([`crate::exact_spectrum_test`]) proves every
//!    eigenvalue on the imaginary axis (round-off off a Jordan block), as
//!    in the exact pipeline.
//!
//! Systems outside that scope take [`crate::analyse`] at the numeric level
//! instead, and the result says so ([`NumericRoute::ExactPipeline`]): free
//! multipliers (a family to optimise over), noise that does not conserve a
//! first integral (`Q` then depends on the Casimir Hessian), data whose
//! magnitudes leave `2^±100` (products could leave the double range),
//! conserved gradients that are independent but nearly dependent (`cond(G)`
//! above 1e7), a restricted Hessian whose sign is within its rounding (bounded from the
//! magnitudes of the derivatives' terms and the multipliers' accuracy) of
//! the definiteness tolerance, and any eigen-solver failure.

mod completion;
mod derivatives;
mod drift;
mod infimum;
mod multipliers;
mod restricted;
mod scope;

use crate::pencil::symmetric_eigenvalues;
use crate::pipeline::{analyse, margin_reason, Analysis, Settings, NO_MULTIPLIERS};
use casimir::{Sign, System};
use derivatives::Derivatives;
use drift::{conclude, drift_spectrum};
use nalgebra::{Complex, DMatrix};
use outcome::{Verdict, VerificationLevel};
use restricted::{Definiteness, Restricted};

/// How a numeric analysis was computed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum NumericRoute {
    /// The floating-point pipeline of this module.
    FloatingPoint,
    /// [`crate::analyse`] with `exact = false`, because the system lies
    /// outside the floating-point pipeline's scope (the reason).
    ExactPipeline(&'static str),
}

/// What the numeric level found.
#[derive(Clone, Debug)]
pub struct NumericAnalysis {
    /// The verdict.
    pub verdict: Verdict,
    /// One sentence explaining it.
    pub reason: String,
    /// How it was computed.
    pub route: NumericRoute,
    /// The sign of the definite second variation, when one was found.
    pub sign: Option<Sign>,
    /// The multipliers `lambda` of the conserved quantities (Casimirs, then
    /// first integrals), when they exist.
    pub multipliers: Vec<f64>,
    /// `lambda_min(s Z^T B Z) / max|eig|` at the multipliers (`Z`
    /// orthonormal), for the sign found (or the larger of the two).
    pub restricted_margin: Option<f64>,
    /// `P`, when stable.
    pub p: Option<DMatrix<f64>>,
    /// `Q`, when stable.
    pub q: Option<DMatrix<f64>>,
    /// `Sigma^2 = max(0, lambda_max(sQ, sP))` for that `P`, when stable.
    pub sigma2: Option<f64>,
    /// The infimum of `Sigma^2` over the Casimir Hessian (approached or
    /// attained), when stable.
    pub infimum: Option<f64>,
    /// The eigenvalues of `A`, largest real part first (empty when not
    /// computed).
    pub spectrum: Vec<Complex<f64>>,
    /// The eigenvalue of `A` with the largest real part, when that real
    /// part is above the instability tolerance.
    pub instability: Option<Complex<f64>>,
}

impl NumericAnalysis {
    /// `exact` for the two early verdicts (exact residuals), else
    /// `numerical`.
    pub fn level(&self) -> VerificationLevel {
        match self.verdict {
            Verdict::NotAnEquilibrium | Verdict::NoiseIncompatible => VerificationLevel::Exact,
            _ => VerificationLevel::Numerical,
        }
    }

    fn early(verdict: Verdict, reason: String) -> Self {
        NumericAnalysis {
            verdict,
            reason,
            route: NumericRoute::FloatingPoint,
            sign: None,
            multipliers: vec![],
            restricted_margin: None,
            p: None,
            q: None,
            sigma2: None,
            infimum: None,
            spectrum: vec![],
            instability: None,
        }
    }

    /// The numeric analysis read off the exact pipeline's.
    fn from_analysis(a: Analysis, why: &'static str) -> Self {
        let stable = a.stable.as_ref();
        NumericAnalysis {
            verdict: a.verdict,
            reason: a.reason.clone(),
            route: NumericRoute::ExactPipeline(why),
            sign: stable.map(|s| s.choice.sign),
            multipliers: stable
                .map_or_else(Vec::new, |s| s.choice.multipliers.iter().map(exact::rational_to_f64).collect()),
            restricted_margin: stable.map(|s| s.choice.relative_margin),
            p: stable.map(|s| s.choice.p.to_dmatrix()),
            q: stable.map(|s| s.form.q.to_dmatrix()),
            sigma2: a.sigma2(),
            infimum: stable.map(|s| s.optimum.as_ref().map_or(s.growth.sigma2, |o| o.infimum)),
            instability: a.instability.as_ref().map(|i| i.eigenvalue),
            spectrum: a.spectrum,
        }
    }
}

/// The numeric level: the verdict and `Sigma^2` in floating point (see the
/// module documentation for the steps and the scope; outside it,
/// [`crate::analyse`] with `exact = false`).
///
/// ```
/// use algebra::builtin;
/// use casimir::System;
/// use exact::{parse_expression, Rational, Symbols};
/// use generator::{analyse_numeric, NumericRoute, Settings, Verdict};
/// let so3 = builtin("so3").unwrap().algebra;
/// let s = Symbols::new(so3.coordinates());
/// let h = parse_expression("Pi1^2/6 + Pi2^2/4 + Pi3^2/2", &s).unwrap(); // I = (3, 2, 1)
/// let c = parse_expression("(Pi1^2 + Pi2^2 + Pi3^2)/2", &s).unwrap();
/// let q = |n: i64, d: i64| Rational::new(n.into(), d.into());
/// let system = System::new(so3, h, vec![c], vec![], vec![q(1, 1), q(0, 1), q(0, 1)],
///                          vec![vec![q(3, 10), q(0, 1), q(0, 1)]]).unwrap();
/// let a = analyse_numeric(&system, &Settings::default());
/// assert_eq!(a.verdict, Verdict::Stable);
/// assert_eq!(a.route, NumericRoute::FloatingPoint);
/// // Sigma^2 = sigma^2 I1 (I2 - I3) / (I3 (I1 - I2)) = 0.09 * 3 = 0.27
/// assert!((a.sigma2.unwrap() - 0.27).abs() < 1e-12);
/// ```
pub fn analyse_numeric(system: &System, settings: &Settings) -> NumericAnalysis {
    match float_pipeline(system, settings) {
        Ok(a) => a,
        Err(why) => {
            let settings = Settings { exact: false, ..settings.clone() };
            NumericAnalysis::from_analysis(analyse(system, &settings), why)
        }
    }
}

/// `(M + M^T) / 2`.
fn symmetric(m: DMatrix<f64>) -> DMatrix<f64> {
    (&m + m.transpose()) * 0.5
}

/// The Frobenius norm of a vector (or of a matrix's entries).
fn frobenius(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// `lambda_max / lambda_min` of a symmetric positive definite matrix
/// (infinite when the smallest eigenvalue is not resolved above round-off,
/// as [`crate::growth::condition_number`]).
fn condition(m: &DMatrix<f64>) -> f64 {
    let Some(e) = symmetric_eigenvalues(m) else { return f64::INFINITY };
    let (Some(&lo), Some(&hi)) = (e.first(), e.last()) else { return 1.0 };
    let hi = hi.max(-lo);
    if lo > hi * 1e-15 {
        hi / lo
    } else {
        f64::INFINITY
    }
}

/// The floating-point pipeline, or why the system is outside its scope.
fn float_pipeline(system: &System, settings: &Settings) -> Result<NumericAnalysis, &'static str> {
    // The early verdicts, exactly (cheap, and decisive), then the scope.
    if let Some(early) = scope::early_verdict(system) {
        return Ok(early);
    }
    scope::check_scope(system)?;
    // 1. Derivatives at mu_e.
    let d = Derivatives::at_equilibrium(system)?;
    // 2. Multipliers and the frame, by the SVD of G (n x m).
    let frame = multipliers::multipliers_and_frame(system, &d)?;
    // 6. The spectrum of A, before the form: it decides the verdict when no
    // form exists, and contradicts a definite one.
    let mut out = drift_spectrum(system, &d.a, settings.instability_tolerance)?;
    let Some(frame) = frame else {
        return Ok(conclude(out, NO_MULTIPLIERS));
    };
    out.multipliers = frame.lambda.iter().copied().collect();

    // 3. The restricted Hessian's sign and margin.
    let (b, b_error) = restricted::second_variation(&d, &frame);
    let restricted = Restricted::new(&b, &frame.z)?;
    let tol = settings.search.definiteness_tolerance;
    let sign = match restricted.decide(&b, b_error, frame.theta, tol)? {
        Definiteness::Definite(sign) => sign,
        Definiteness::NotDefinite(best) => {
            out.restricted_margin = Some(best);
            return Ok(conclude(out, &margin_reason(best, tol)));
        }
    };
    out.restricted_margin = Some(restricted.margin(sign));
    if out.instability.is_some() {
        out.verdict = Verdict::Inconclusive;
        out.reason =
            "contradictory evidence: a definite second variation was found, yet A appears to have an unstable eigenvalue"
                .into();
        return Ok(out);
    }

    // 4. The Casimir Hessian by the Schur completion in the frame [Z W].
    let pencil = completion::schur_completion(&b, &frame.z, frame.w, &restricted, sign, &d.noise)?;
    // 5. Sigma^2, and the infimum over the Casimir Hessian.
    let growth = infimum::growth(&pencil, settings)?;
    Ok(stable(out, sign, &pencil, growth))
}

/// The `stable` verdict with `P`, `Q`, `Sigma^2` and the infimum, unsigned.
fn stable(
    mut out: NumericAnalysis,
    sign: Sign,
    pencil: &completion::SignedPencil,
    growth: infimum::Growth,
) -> NumericAnalysis {
    let s = sign.as_f64();
    out.verdict = Verdict::Stable;
    out.reason = format!(
        "the second variation is {sign} definite (floating point, no proof): formally stable; E|dmu_t|_P^2 <= |dmu_0|_P^2 e^(Sigma^2 t)"
    );
    out.sign = Some(sign);
    out.q = Some(&pencil.sq * s);
    out.p = Some(growth.sp * s);
    out.sigma2 = Some(growth.sigma2);
    out.infimum = Some(if pencil.k == 0 { 0.0 } else { growth.infimum });
    out
}
