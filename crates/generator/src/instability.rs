//! Spectrum of the linearised drift and the linear-instability test.
//!
//! The general (non-symmetric) eigenproblem is solved with faer's
//! Hessenberg–QR eigensolver, which uses exceptional shifts and reports
//! non-convergence instead of iterating forever (nalgebra's real Schur form
//! has no iteration limit by default and was seen to loop on a Lagrange-top
//! linearisation).

use exact::Matrix;
use nalgebra::{Complex, DMatrix};

/// An eigenvalue of `A` with positive real part, with an eigenvector.
#[derive(Clone, Debug, PartialEq)]
pub struct Instability {
    /// The eigenvalue with the largest real part.
    pub eigenvalue: Complex<f64>,
    /// A unit eigenvector (complex).
    pub eigenvector: Vec<Complex<f64>>,
    /// `|A v - l v|` for that eigenpair.
    pub residual: f64,
    /// The tolerance the real part was compared with.
    pub tolerance: f64,
}

/// Why the spectrum of `A` is not available.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum SpectrumError {
    /// The eigensolver did not converge.
    #[error("the eigenvalue iteration for A did not converge")]
    NoConvergence,
    /// `A` has a non-finite entry in floating point.
    #[error("A has a non-finite entry in floating point")]
    NonFinite,
}

struct Eigen {
    values: Vec<Complex<f64>>,
    vectors: Vec<Vec<Complex<f64>>>,
}

fn eigen(a: &Matrix) -> Result<Eigen, SpectrumError> {
    let n = a.nrows();
    let af = a.to_dmatrix();
    if af.iter().any(|x| !x.is_finite()) {
        return Err(SpectrumError::NonFinite);
    }
    if n == 0 {
        return Ok(Eigen { values: vec![], vectors: vec![] });
    }
    let m = faer::Mat::<f64>::from_fn(n, n, |i, j| af[(i, j)]);
    let e = m.eigen().map_err(|_| SpectrumError::NoConvergence)?;
    let s = e.S();
    let u = e.U();
    let values = (0..n).map(|i| Complex::new(s[i].re, s[i].im)).collect();
    let vectors = (0..n).map(|j| (0..n).map(|i| Complex::new(u[(i, j)].re, u[(i, j)].im)).collect()).collect();
    Ok(Eigen { values, vectors })
}

/// Eigenvalues of `A`, largest real part first.
pub fn spectrum(a: &Matrix) -> Result<Vec<Complex<f64>>, SpectrumError> {
    spectrum_f64(&a.to_dmatrix())
}

/// [`spectrum`] of a floating-point matrix (the numeric level's drift).
pub(crate) fn spectrum_f64(af: &DMatrix<f64>) -> Result<Vec<Complex<f64>>, SpectrumError> {
    let n = af.nrows();
    if af.iter().any(|x| !x.is_finite()) {
        return Err(SpectrumError::NonFinite);
    }
    if n == 0 {
        return Ok(vec![]);
    }
    let m = faer::Mat::<f64>::from_fn(n, n, |i, j| af[(i, j)]);
    let values = m.eigenvalues().map_err(|_| SpectrumError::NoConvergence)?;
    let mut ev: Vec<Complex<f64>> = values.iter().map(|z| Complex::new(z.re, z.im)).collect();
    ev.sort_by(|x, y| y.re.total_cmp(&x.re).then(y.im.total_cmp(&x.im)));
    Ok(ev)
}

/// The eigenvalue of largest real part if that real part exceeds
/// `relative_tolerance * max(1, |A|_F)`, with a unit eigenvector.
///
/// The tolerance matters: a defective zero eigenvalue (a Jordan block of
/// size `k`, common at equilibria with symmetry) is perturbed by round-off to
/// about `eps^{1/k} |A|`, so real parts below the tolerance are not evidence of
/// instability and the verdict stays inconclusive.
pub fn find_instability(a: &Matrix, relative_tolerance: f64) -> Result<Option<Instability>, SpectrumError> {
    let values = spectrum(a)?;
    instability_from_spectrum(a, &values, relative_tolerance)
}

/// As [`find_instability`], reusing a spectrum already computed; the
/// eigenvector is computed only when an unstable eigenvalue is found.
pub fn instability_from_spectrum(
    a: &Matrix,
    spectrum: &[Complex<f64>],
    relative_tolerance: f64,
) -> Result<Option<Instability>, SpectrumError> {
    let Some(top) = spectrum.iter().copied().max_by(|x, y| x.re.total_cmp(&y.re)) else {
        return Ok(None);
    };
    let af = a.to_dmatrix();
    let tolerance = relative_tolerance * af.norm().max(1.0);
    if top.re <= tolerance {
        return Ok(None);
    }
    let e = eigen(a)?;
    // The decomposition's eigenvalue closest to the one found.
    let Some(k) =
        (0..e.values.len()).min_by(|&i, &j| (e.values[i] - top).norm().total_cmp(&(e.values[j] - top).norm()))
    else {
        return Ok(None);
    };
    let eigenvalue = e.values[k];
    let v = &e.vectors[k];
    let norm = v.iter().map(|z| z.norm_sqr()).sum::<f64>().sqrt();
    // Fix the arbitrary phase: the first component whose modulus is within
    // 1e-6 of the largest is made real and positive, so the vector does not
    // depend on the solver's rounding.
    let max_mod = v.iter().map(|z| z.norm()).fold(0.0, f64::max);
    let pivot = v.iter().find(|z| z.norm() >= max_mod * (1.0 - 1e-6)).copied().unwrap_or(Complex::new(1.0, 0.0));
    let phase = pivot.conj() / pivot.norm();
    let v: Vec<Complex<f64>> = v.iter().map(|z| z * phase / norm).collect();
    let n = v.len();
    let residual = (0..n)
        .map(|i| {
            let av: Complex<f64> = (0..n).map(|j| v[j] * af[(i, j)]).sum();
            (av - eigenvalue * v[i]).norm_sqr()
        })
        .sum::<f64>()
        .sqrt();
    Ok(Some(Instability { eigenvalue, eigenvector: v, residual, tolerance }))
}
