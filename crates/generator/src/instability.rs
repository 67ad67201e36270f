//! Spectrum of the linearised drift and the linear-instability test.

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

/// Eigenvalues of `A` (floating point, from the real Schur form).
pub fn spectrum(a: &Matrix) -> Vec<Complex<f64>> {
    let af = a.to_dmatrix();
    if af.nrows() == 0 {
        return vec![];
    }
    let mut ev: Vec<Complex<f64>> = af.complex_eigenvalues().iter().copied().collect();
    ev.sort_by(|x, y| y.re.total_cmp(&x.re).then(y.im.total_cmp(&x.im)));
    ev
}

/// The eigenvalue of largest real part if that real part exceeds
/// `relative_tolerance * max(1, |A|)`.
///
/// The tolerance matters: a defective zero eigenvalue (a Jordan block of
/// size `k`, common at equilibria with symmetry) is perturbed by round-off to
/// about `eps^{1/k} |A|`, so real parts below the tolerance are not evidence of
/// instability and the verdict stays inconclusive.
pub fn find_instability(a: &Matrix, relative_tolerance: f64) -> Option<Instability> {
    let af = a.to_dmatrix();
    let ev = spectrum(a);
    let top = *ev.first()?;
    let tolerance = relative_tolerance * af.norm().max(1.0);
    if top.re <= tolerance {
        return None;
    }
    let n = af.nrows();
    let shifted = DMatrix::from_fn(n, n, |i, j| {
        Complex::new(af[(i, j)], 0.0) - if i == j { top } else { Complex::new(0.0, 0.0) }
    });
    let svd = shifted.clone().svd(false, true);
    let v_t = svd.v_t.as_ref()?;
    let mut imin = 0;
    for i in 1..svd.singular_values.len() {
        if svd.singular_values[i] < svd.singular_values[imin] {
            imin = i;
        }
    }
    let v: Vec<Complex<f64>> = v_t.row(imin).iter().map(|z| z.conj()).collect();
    let vm = DMatrix::from_column_slice(n, 1, &v);
    let residual = (&shifted * &vm).norm();
    Some(Instability { eigenvalue: top, eigenvector: v, residual, tolerance })
}
