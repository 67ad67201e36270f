//! Step 6 of the numeric level: the spectrum of the drift `A`, which
//! decides `linearly_unstable`, or `inconclusive` when no definite form
//! exists.

use super::NumericAnalysis;
use crate::instability::spectrum_f64;
use crate::spectral::{exact_spectrum_test, SpectralProof};
use casimir::System;
use nalgebra::DMatrix;
use outcome::Verdict;

/// The eigenvalues of `A`, largest real part first, and the first of them
/// when its real part is above `tolerance * max(1, |A|_F)` and exact
/// arithmetic does not put every eigenvalue on the imaginary axis; the
/// analysis so far (`inconclusive`, no reason yet).
pub(super) fn drift_spectrum(
    system: &System,
    a: &DMatrix<f64>,
    tolerance: f64,
) -> Result<NumericAnalysis, &'static str> {
    // The spectrum of A (instability, and a consistency check of a definite form).
    let spectrum = spectrum_f64(a).map_err(|_| "the eigenvalues of A")?;
    let tolerance = tolerance * a.norm().max(1.0);
    let mut instability = spectrum.first().copied().filter(|z| z.re > tolerance);
    if instability.is_some() && exact_spectrum_test(&crate::linearise(system).a) == SpectralProof::ImaginaryAxis {
        // Round-off off a defective eigenvalue on the imaginary axis (a
        // Jordan block of size k moves by eps^(1/k) |A|, above the
        // tolerance for k >= 3): exact arithmetic rules the instability
        // out, as in the exact pipeline. Only a claimed instability pays
        // for the exact linearisation and the Sturm sequence.
        instability = None;
    }
    Ok(NumericAnalysis { spectrum, instability, ..NumericAnalysis::early(Verdict::Inconclusive, String::new()) })
}

/// The verdict without a definite form (`why` none exists):
/// `linearly_unstable` with an unstable eigenvalue, else `inconclusive`.
pub(super) fn conclude(mut out: NumericAnalysis, why: &str) -> NumericAnalysis {
    match out.instability {
        Some(z) => {
            out.verdict = Verdict::LinearlyUnstable;
            out.reason = format!("A has the eigenvalue {:.6e} {:+.6e}i with positive real part", z.re, z.im);
        }
        None => {
            out.verdict = Verdict::Inconclusive;
            out.reason = format!("{why}, and no eigenvalue of A has a real part above the tolerance");
        }
    }
    out
}
