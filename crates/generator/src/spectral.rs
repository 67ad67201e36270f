//! Exact statements about the spectrum of the linearised drift `A`.
//!
//! At an equilibrium of a Lie–Poisson system the spectrum of `A` is symmetric
//! under `l -> -l`, so the characteristic polynomial satisfies
//! `chi(-l) = (-1)^n chi(l)` and can be written `chi(l) = l^(n mod 2) q(l^2)`.
//! Every eigenvalue lies on the imaginary axis iff every root `nu` of `q`
//! (after removing the roots at 0) is real and negative. Sturm's theorem on
//! the square-free part of `q` counts its distinct real roots in `(-inf, 0)`
//! exactly: if that count is the degree, the spectrum is on the imaginary
//! axis; otherwise some `nu` is positive or non-real, `sqrt(nu)` and
//! `-sqrt(nu)` are both eigenvalues, and one of them has a positive real
//! part. Both conclusions are proofs in rational arithmetic, with no
//! tolerance. Without the symmetry no exact statement is attempted.

use exact::{char_poly, Matrix, Rational, UPoly};
use num_traits::Zero;

/// What exact arithmetic proves about the spectrum of `A`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SpectralProof {
    /// Some eigenvalue has a positive real part.
    Unstable {
        /// Whether the unstable pair is real (`q` has a positive root) or
        /// part of a complex quadruple.
        real_pair: bool,
    },
    /// Every eigenvalue lies on the imaginary axis (spectral stability).
    ImaginaryAxis,
    /// The characteristic polynomial lacks the `l -> -l` symmetry.
    Unknown,
}

impl SpectralProof {
    /// Name used in certificates.
    pub fn as_str(&self) -> &'static str {
        match self {
            SpectralProof::Unstable { .. } => "unstable",
            SpectralProof::ImaginaryAxis => "imaginary_axis",
            SpectralProof::Unknown => "unknown",
        }
    }
}

/// Decide exactly whether `A` has an eigenvalue off the imaginary axis.
///
/// ```
/// use exact::{Matrix, Rational};
/// use generator::{exact_spectrum_test, SpectralProof};
/// let q = |n: i64| Rational::from(n);
/// // A saddle [[0, 1], [2, 0]] (eigenvalues ±sqrt 2) and a centre [[0, 1], [-2, 0]].
/// let saddle = Matrix::from_rows(&[vec![q(0), q(1)], vec![q(2), q(0)]]);
/// assert_eq!(exact_spectrum_test(&saddle), SpectralProof::Unstable { real_pair: true });
/// let centre = Matrix::from_rows(&[vec![q(0), q(1)], vec![q(-2), q(0)]]);
/// assert_eq!(exact_spectrum_test(&centre), SpectralProof::ImaginaryAxis);
/// ```
pub fn exact_spectrum_test(a: &Matrix) -> SpectralProof {
    let n = a.nrows();
    let chi = char_poly(a);
    let c = chi.coefficients();
    // chi(-l) = (-1)^n chi(l) iff c_k = 0 whenever k and n differ in parity.
    if c.iter().enumerate().any(|(k, ck)| (n - k) % 2 == 1 && !ck.is_zero()) {
        return SpectralProof::Unknown;
    }
    let mut q: Vec<Rational> = c.iter().skip(n % 2).step_by(2).cloned().collect();
    // Remove the roots nu = 0 (eigenvalues l = 0, on the axis).
    while q.first().is_some_and(Zero::is_zero) {
        q.remove(0);
    }
    let q = UPoly::new(q).square_free();
    let degree = q.degree().unwrap_or(0);
    if degree == 0 {
        return SpectralProof::ImaginaryAxis;
    }
    let zero = Rational::zero();
    let negative = q.count_real_roots(None, Some(&zero));
    if negative == degree {
        SpectralProof::ImaginaryAxis
    } else {
        SpectralProof::Unstable { real_pair: q.count_real_roots(Some(&zero), None) > 0 }
    }
}
