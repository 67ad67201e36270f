//! The whole finite-dimensional pipeline: from a validated [`System`] to a
//! verdict with its evidence.

mod optimum;
mod proof;
mod spectrum;

use crate::bound::InfimumWitness;
use crate::certify::ExactSigma2;
use crate::form::{generator_form, GeneratorForm};
use crate::growth::{growth_constant, GrowthConstant};
use crate::instability::Instability;
use crate::linearise::{linearise, Linearisation};
use crate::optimise::OptimiseSettings;
use crate::spectral::SpectralProof;
use casimir::{find_definite_choice, CasimirChoice, SearchOutcome, SearchSettings, SecondVariation, System};
use exact::Rational;
use nalgebra::Complex;
use num_traits::Zero;

/// Settings of the pipeline, with documented defaults. Every certificate
/// records the settings it was made with.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// The search over the Casimir freedom for a first definite choice.
    pub search: SearchSettings,
    /// Whether to minimise `Sigma^2` over the Casimir freedom (default true).
    pub optimise: bool,
    /// Whether to prove the claims exactly (default true): the rational
    /// `Sigma^2` bound and the exact spectral test. Without it the verdicts
    /// rest on floating point and the level is `numerical`.
    pub exact: bool,
    /// The minimisation.
    pub optimisation: OptimiseSettings,
    /// An eigenvalue of `A` proves linear instability only if its real part
    /// exceeds this times `max(1, |A|_F)`. Default `1e-6`: round-off moves a
    /// defective zero eigenvalue (Jordan block of size `k`) by about
    /// `eps^{1/k} |A|`, which stays below this for `k <= 2`.
    pub instability_tolerance: f64,
    /// Whether to prove `Sigma^2` exactly when `exact` is set (default
    /// true): the rational bound and, with free multipliers, the certified
    /// lower bound over the family. Off, a stable verdict keeps its exact
    /// `P` and spectral test but states `Sigma^2` in floating point only: a
    /// box certificate takes only the choice from a sub-box's point and
    /// proves its own bound over the sub-box.
    pub prove_bound: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            search: SearchSettings::default(),
            optimise: true,
            exact: true,
            optimisation: OptimiseSettings::default(),
            instability_tolerance: 1e-6,
            prove_bound: true,
        }
    }
}

pub use outcome::Verdict;

/// The evidence of a `stable` verdict.
#[derive(Clone, Debug)]
pub struct StableEvidence {
    /// The Casimir choice (optimised when possible) and the exact `P`.
    pub choice: CasimirChoice,
    /// `Q`, the drift residual and the paper's formula, exactly.
    pub form: GeneratorForm,
    /// `lambda_max(Q, P)` in floating point and the fastest-growing direction.
    pub growth: GrowthConstant,
    /// The certified rational `Sigma^2`, when the exact test succeeded.
    pub exact: Option<ExactSigma2>,
    /// The first definite choice found and its `Sigma^2` (floating point).
    pub first_choice: CasimirChoice,
    /// `max(0, lambda_max)` for the first definite choice.
    pub first_sigma2: f64,
    /// What the minimisation over the freedom found (`None` if it was not run
    /// or did not improve on the first choice).
    pub optimum: Option<OptimumSummary>,
}

/// What the minimisation over the Casimir freedom found.
#[derive(Clone, Debug, PartialEq)]
pub struct OptimumSummary {
    /// Floating-point infimum of `Sigma^2` over the freedom.
    pub infimum: f64,
    /// A certified lower bound on `Sigma^2` for every choice in the family,
    /// when one could be proved (see [`crate::Optimum::infimum_lower_bound`]).
    pub infimum_lower_bound: Option<Rational>,
    /// What proves it.
    pub infimum_witness: Option<InfimumWitness>,
    /// Whether the chosen `P` attains it.
    pub attained: bool,
    /// Whether the chosen `P` is within the tolerance of it.
    pub within_tolerance: bool,
    /// Whether `Q` depends on `M`.
    pub q_depends_on_m: bool,
    /// How it was found.
    pub method: &'static str,
    /// Where the free multipliers' infimum was found (floating point).
    pub infimum_parameters: Option<Vec<f64>>,
}

impl StableEvidence {
    /// The certified `Sigma^2`: the exact rational when available, else the
    /// floating-point `max(0, lambda_max)`.
    pub fn sigma2(&self) -> f64 {
        match &self.exact {
            Some(e) => exact::rational_to_f64(&e.value),
            None => self.growth.sigma2,
        }
    }

    /// `Sigma^2` as a double at or above the certified rational (the
    /// nearest double may lie below it): what a stopping time, a guarantee,
    /// is computed from. The floating-point value when nothing is certified.
    pub fn sigma2_bound(&self) -> f64 {
        match &self.exact {
            Some(e) => exact::rational_to_f64_up(&e.value),
            None => self.growth.sigma2,
        }
    }
}

/// Everything the pipeline found.
#[derive(Clone, Debug)]
pub struct Analysis {
    /// The verdict.
    pub verdict: Verdict,
    /// One sentence explaining it.
    pub reason: String,
    /// `ad*_{Dh(mu_e)} mu_e`.
    pub equilibrium_residual: Vec<Rational>,
    /// `ad*_{sigma_i} mu_e` for each noise field.
    pub noise_residuals: Vec<Vec<Rational>>,
    /// A basis of the isotropy algebra of `mu_e` (the compatible noise).
    pub isotropy_basis: Vec<Vec<Rational>>,
    /// For each conserved quantity and noise field, whether they commute.
    pub noise_commutation: Vec<Vec<bool>>,
    /// The linearisation (when `mu_e` is an equilibrium with compatible noise).
    pub linearisation: Option<Linearisation>,
    /// The spectrum of `A`, largest real part first.
    pub spectrum: Vec<Complex<f64>>,
    /// An unstable eigenpair, if one was found.
    pub instability: Option<Instability>,
    /// Why the spectrum of `A` could not be computed, if it could not.
    pub spectrum_error: Option<String>,
    /// What exact arithmetic proves about the spectrum of `A`.
    pub spectral_proof: Option<SpectralProof>,
    /// The second variation data (when multipliers exist).
    pub variation: Option<SecondVariation>,
    /// The outcome of the search over the Casimir freedom.
    pub search: Option<SearchOutcome>,
    /// The evidence for `stable`.
    pub stable: Option<StableEvidence>,
}

impl Analysis {
    /// `Sigma^2` when the verdict is `stable` (the certified value).
    pub fn sigma2(&self) -> Option<f64> {
        self.stable.as_ref().map(StableEvidence::sigma2)
    }

    /// [`StableEvidence::sigma2_bound`], if stable.
    pub fn sigma2_bound(&self) -> Option<f64> {
        self.stable.as_ref().map(StableEvidence::sigma2_bound)
    }
}

/// Run the pipeline (docs/architecture.md §2, steps 2–8).
///
/// ```
/// use algebra::builtin;
/// use casimir::System;
/// use exact::{parse_expression, Rational, Symbols};
/// use generator::{analyse, Settings, Verdict};
/// let so3 = builtin("so3").unwrap().algebra;
/// let s = Symbols::new(so3.coordinates());
/// let h = parse_expression("Pi1^2/6 + Pi2^2/4 + Pi3^2/2", &s).unwrap(); // I = (3, 2, 1)
/// let c = parse_expression("(Pi1^2 + Pi2^2 + Pi3^2)/2", &s).unwrap();
/// let q = |n: i64, d: i64| Rational::new(n.into(), d.into());
/// let system = System::new(so3, h, vec![c], vec![], vec![q(1, 1), q(0, 1), q(0, 1)],
///                          vec![vec![q(3, 10), q(0, 1), q(0, 1)]]).unwrap();
/// let analysis = analyse(&system, &Settings::default());
/// assert_eq!(analysis.verdict, Verdict::Stable);
/// // Sigma^2 = sigma^2 I1 (I2 - I3) / (I3 (I1 - I2)) = 0.09 * 3 = 0.27
/// assert!((analysis.sigma2().unwrap() - 0.27).abs() < 1e-14);
/// ```
pub fn analyse(system: &System, settings: &Settings) -> Analysis {
    let mut analysis = residuals(system);
    if early_verdict(&mut analysis) {
        return analysis;
    }
    let linearisation = linearise(system);
    spectrum::spectral_evidence(&mut analysis, &linearisation, settings);
    let choice = match definite_choice(system, settings, &mut analysis) {
        Ok(choice) => choice,
        Err(why) => return conclude_without_form(analysis, &why),
    };
    if matches!(analysis.spectral_proof, Some(SpectralProof::Unstable { .. })) || analysis.instability.is_some() {
        // A conserved definite form rules out eigenvalues off the imaginary
        // axis; both at once means a breakdown somewhere. Claim nothing.
        analysis.verdict = Verdict::Inconclusive;
        analysis.reason =
            "contradictory evidence: a definite second variation was found, yet A appears to have an unstable eigenvalue".into();
        return analysis;
    }
    stable(analysis, &linearisation, &choice, settings)
}

/// The exact residuals `ad*_{Dh(mu_e)} mu_e` and `ad*_{sigma_i} mu_e`, the
/// isotropy algebra and the noise's commutation with the conserved
/// quantities; the verdict not yet decided.
fn residuals(system: &System) -> Analysis {
    let equilibrium_residual = system.equilibrium_residual();
    let noise_residuals = system.noise_residuals();
    let isotropy_basis = system.isotropy_basis();
    let noise_commutation = system.noise_commutation();
    Analysis {
        verdict: Verdict::Inconclusive,
        reason: String::new(),
        equilibrium_residual,
        noise_residuals,
        isotropy_basis,
        noise_commutation,
        linearisation: None,
        spectrum: vec![],
        instability: None,
        spectrum_error: None,
        spectral_proof: None,
        variation: None,
        search: None,
        stable: None,
    }
}

/// Decides `not_an_equilibrium` or `noise_incompatible` from the exact
/// residuals; whether it did.
fn early_verdict(analysis: &mut Analysis) -> bool {
    if analysis.equilibrium_residual.iter().any(|r| !r.is_zero()) {
        analysis.verdict = Verdict::NotAnEquilibrium;
        analysis.reason = NOT_AN_EQUILIBRIUM.into();
        return true;
    }
    let incompatible = incompatible_noise(&analysis.noise_residuals);
    if !incompatible.is_empty() {
        analysis.verdict = Verdict::NoiseIncompatible;
        analysis.reason = incompatible_reason(&incompatible);
        return true;
    }
    false
}

/// A definite second variation from the search over the Casimir freedom
/// (the variation and the search recorded), or why there is none.
fn definite_choice(system: &System, settings: &Settings, analysis: &mut Analysis) -> Result<CasimirChoice, String> {
    let Some(variation) = system.second_variation() else {
        return Err(NO_MULTIPLIERS.into());
    };
    let outcome = find_definite_choice(&variation, &settings.search);
    analysis.variation = Some(variation);
    analysis.search = Some(outcome.clone());
    match outcome.definite() {
        Some(choice) => Ok(choice.clone()),
        None => Err(not_definite_reason(&outcome, settings.search.definiteness_tolerance)),
    }
}

/// The `stable` verdict with its evidence: `Q` and `Sigma^2` for the first
/// definite choice, the best choice over the freedom, and the exact claims
/// (or `inconclusive` when `Sigma^2` cannot be computed or stated).
fn stable(
    mut analysis: Analysis,
    linearisation: &Linearisation,
    choice: &CasimirChoice,
    settings: &Settings,
) -> Analysis {
    let form = generator_form(linearisation, &choice.p);
    let first_growth = match growth_constant(&choice.p, &form.q, choice.sign) {
        Ok(g) => g,
        Err(e) => {
            analysis.verdict = Verdict::Inconclusive;
            analysis.reason = format!("a definite second variation was found but Sigma^2 could not be computed: {e}");
            return analysis;
        }
    };
    let mut best = optimum::best_choice(&analysis, linearisation, choice, form, &first_growth, settings);
    let exact = proof::certify(&analysis, &mut best, settings);
    if let Some(reason) = exact.as_ref().and_then(proof::out_of_double_range) {
        analysis.verdict = Verdict::Inconclusive;
        analysis.reason = reason;
        return analysis;
    }
    analysis.verdict = Verdict::Stable;
    analysis.reason = format!(
        "the second variation is {} definite: formally stable; E|dmu_t|_P^2 <= |dmu_0|_P^2 e^(Sigma^2 t)",
        best.choice.sign
    );
    analysis.stable = Some(StableEvidence {
        choice: best.choice,
        form: best.form,
        growth: best.growth,
        exact,
        first_choice: choice.clone(),
        first_sigma2: first_growth.sigma2,
        optimum: best.summary,
    });
    analysis
}

/// Why `mu_e` is not an equilibrium.
pub(crate) const NOT_AN_EQUILIBRIUM: &str = "ad*_{Dh(mu_e)} mu_e is not zero: mu_e is not an equilibrium";

/// Why no energy–Casimir form exists when the multipliers do not.
pub(crate) const NO_MULTIPLIERS: &str = "no multipliers make mu_e a critical point of h + sum lambda_j K_j (Dh(mu_e) is not in the span of the conserved gradients)";

/// The noise fields whose residual `ad*_sigma mu_e` is not zero.
pub(crate) fn incompatible_noise(residuals: &[Vec<Rational>]) -> Vec<usize> {
    (0..residuals.len()).filter(|&i| residuals[i].iter().any(|x| !x.is_zero())).collect()
}

/// Why the noise is incompatible.
pub(crate) fn incompatible_reason(fields: &[usize]) -> String {
    format!(
        "ad*_sigma mu_e is not zero for noise field(s) {fields:?}: the noise moves the equilibrium; compatible noise lies in the isotropy algebra of mu_e"
    )
}

/// Why the search found no definite form: none at all (every relative
/// margin at most 0), or one too close to singular to certify (a positive
/// margin below the tolerance: a conditioning limit, not a proof that none
/// exists).
pub fn not_definite_reason(outcome: &casimir::SearchOutcome, tolerance: f64) -> String {
    let best = match outcome {
        casimir::SearchOutcome::NotFound { best_positive_margin, best_negative_margin, .. } => {
            best_positive_margin.max(*best_negative_margin)
        }
        casimir::SearchOutcome::Definite(_) => f64::NAN,
    };
    margin_reason(best, tolerance)
}

/// [`not_definite_reason`] from the best relative margin found.
pub fn margin_reason(best: f64, tolerance: f64) -> String {
    if best > 0.0 {
        format!(
            "the best choice of multipliers and Casimir function found makes the second variation definite only with relative margin {best:.3e} (smallest over largest eigenvalue of the restricted Hessian), below settings.search.definiteness_tolerance = {tolerance:e}: a conditioning limit, so it is not certified (this does not show that no definite form exists)"
        )
    } else {
        "no choice of multipliers and Casimir function makes the second variation definite".to_string()
    }
}

fn conclude_without_form(mut analysis: Analysis, why: &str) -> Analysis {
    match (&analysis.spectral_proof, &analysis.instability) {
        (Some(SpectralProof::Unstable { real_pair }), _) => {
            analysis.verdict = Verdict::LinearlyUnstable;
            analysis.reason = format!(
                "A has an eigenvalue with positive real part ({}; proved exactly by a Sturm sequence on its characteristic polynomial)",
                if *real_pair { "a real pair ±l" } else { "a complex quadruple ±l, ±conj(l)" }
            );
        }
        (Some(SpectralProof::ImaginaryAxis), _) => {
            analysis.verdict = Verdict::Inconclusive;
            analysis.reason = format!(
                "{why}; every eigenvalue of A lies on the imaginary axis (proved exactly), so the equilibrium is spectrally stable, but that does not imply stability"
            );
        }
        (_, Some(inst)) => {
            analysis.verdict = Verdict::LinearlyUnstable;
            analysis.reason = format!(
                "A has the eigenvalue {:.6e} {:+.6e}i with positive real part",
                inst.eigenvalue.re, inst.eigenvalue.im
            );
        }
        _ => {
            analysis.verdict = Verdict::Inconclusive;
            analysis.reason = format!("{why}, and no eigenvalue of A has a real part above the tolerance");
        }
    }
    analysis
}
