//! The best Casimir choice: the first definite choice, or the minimiser of
//! `Sigma^2` over the Casimir freedom when it does as well.

use super::{Analysis, OptimumSummary, Settings};
use crate::form::GeneratorForm;
use crate::growth::GrowthConstant;
use crate::linearise::Linearisation;
use crate::optimise::{optimise_choice, Optimum};
use casimir::CasimirChoice;

/// The chosen `P` with its form and growth, and what the minimisation found.
pub(super) struct Best {
    /// The choice (optimised when possible).
    pub(super) choice: CasimirChoice,
    /// Its generator form.
    pub(super) form: GeneratorForm,
    /// Its `lambda_max(Q, P)`.
    pub(super) growth: GrowthConstant,
    /// What the minimisation found, if it ran and improved.
    pub(super) summary: Option<OptimumSummary>,
}

/// The choice minimising `Sigma^2` over the Casimir freedom (with
/// `settings.optimise`), else the first definite choice.
pub(super) fn best_choice(
    analysis: &Analysis,
    linearisation: &Linearisation,
    choice: &CasimirChoice,
    form: GeneratorForm,
    first_growth: &GrowthConstant,
    settings: &Settings,
) -> Best {
    let variation = analysis.variation.as_ref().expect("set above");
    let optimum = if settings.optimise {
        let noise_conserves_all = analysis.noise_commutation.iter().flatten().all(|&c| c);
        optimise_choice(
            variation,
            linearisation,
            choice,
            &form,
            first_growth,
            noise_conserves_all,
            &settings.optimisation,
        )
    } else {
        None
    };
    match optimum {
        Some(o) => {
            let summary = summary(&o);
            Best { choice: o.choice, form: o.form, growth: o.growth, summary: Some(summary) }
        }
        None => Best { choice: choice.clone(), form, growth: first_growth.clone(), summary: None },
    }
}

/// What the minimisation found, without the choice itself.
fn summary(o: &Optimum) -> OptimumSummary {
    OptimumSummary {
        infimum: o.infimum,
        infimum_lower_bound: o.infimum_lower_bound.clone(),
        infimum_witness: o.infimum_witness.clone(),
        attained: o.attained,
        within_tolerance: o.within_tolerance,
        q_depends_on_m: o.q_depends_on_m,
        method: o.method,
        infimum_parameters: o.infimum_parameters.clone(),
    }
}
