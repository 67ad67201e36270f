//! The spectrum of the drift `A`: an unstable eigenvalue in floating
//! point, and what exact arithmetic proves about the spectrum.

use super::{Analysis, Settings};
use crate::instability::{instability_from_spectrum, spectrum};
use crate::linearise::Linearisation;
use crate::spectral::{exact_spectrum_test, SpectralProof};

/// The spectrum of `A` and an eigenvalue with real part above the
/// tolerance (or why the spectrum could not be computed), then the exact
/// spectral test: at the exact level recorded, and either way an
/// instability ruled out when every eigenvalue is on the imaginary axis.
pub(super) fn spectral_evidence(analysis: &mut Analysis, linearisation: &Linearisation, settings: &Settings) {
    let spectral = spectrum(&linearisation.a).and_then(|s| {
        let instability = instability_from_spectrum(&linearisation.a, &s, settings.instability_tolerance)?;
        Ok((s, instability))
    });
    analysis.linearisation = Some(linearisation.clone());
    match spectral {
        Ok((s, instability)) => {
            analysis.spectrum = s;
            analysis.instability = instability;
        }
        Err(e) => {
            // Without a spectrum nothing about A can be claimed; the energy-
            // Casimir test below does not need it.
            analysis.spectrum_error = Some(e.to_string());
        }
    }

    if settings.exact {
        let proof = exact_spectrum_test(&linearisation.a);
        if proof == SpectralProof::ImaginaryAxis {
            // Exact arithmetic rules out an unstable eigenvalue: any numerical
            // one above the tolerance was round-off.
            analysis.instability = None;
        }
        analysis.spectral_proof = Some(proof);
    } else if analysis.instability.is_some() && exact_spectrum_test(&linearisation.a) == SpectralProof::ImaginaryAxis {
        // Without exact proofs a floating-point instability is still
        // confirmed: round-off off a defective eigenvalue on the imaginary
        // axis (a Jordan block of size k >= 3 moves by eps^(1/k) |A|) is not
        // reported as linear instability. (Only a claimed instability pays
        // for the Sturm sequence; nothing is recorded as proved.)
        analysis.instability = None;
    }
}
