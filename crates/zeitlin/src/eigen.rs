//! Eigenvalues of dense real matrices, by faer.
//!
//! nalgebra's `complex_eigenvalues` runs its Schur iteration with no limit:
//! on some finite matrices (a dense Zeitlin drift at N = 8 was one) it never
//! returns. faer's QR algorithm reports non-convergence instead, so a hostile
//! or unlucky input gives an error, not a hang.

use nalgebra::{Complex, DMatrix};

/// The eigenvalues of a square real matrix, or `None` when an entry is not
/// finite or the iteration did not converge.
///
/// ```
/// // [[0, -2], [2, 0]]: eigenvalues ±2i
/// let k = nalgebra::DMatrix::from_row_slice(2, 2, &[0.0, -2.0, 2.0, 0.0]);
/// let ev = zeitlin::eigen::real_eigenvalues(&k).unwrap();
/// assert!(ev.iter().all(|z| z.re.abs() < 1e-15 && (z.im.abs() - 2.0).abs() < 1e-15));
/// assert!(zeitlin::eigen::real_eigenvalues(&(k * f64::NAN)).is_none());
/// ```
pub fn real_eigenvalues(k: &DMatrix<f64>) -> Option<Vec<Complex<f64>>> {
    let n = k.nrows();
    if n != k.ncols() || k.iter().any(|x| !x.is_finite()) {
        return None;
    }
    if n == 0 {
        return Some(vec![]);
    }
    let m = faer::Mat::<f64>::from_fn(n, n, |i, j| k[(i, j)]);
    let values = m.eigenvalues().ok()?;
    Some(values.iter().map(|z| Complex::new(z.re, z.im)).collect())
}
