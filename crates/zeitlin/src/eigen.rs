//! Eigenvalues of dense real matrices, by faer.
//!
//! nalgebra's `complex_eigenvalues` runs its Schur iteration with no limit:
//! on some finite matrices (a dense Zeitlin drift at N = 8 was one) it never
//! returns. faer's QR algorithm reports non-convergence instead, so a hostile
//! or unlucky input gives an error, not a hang.

use nalgebra::{Complex, DMatrix};

pub(crate) use numerics::dense::{real_eigenvalues, symmetric_eigenvalues};

type C = Complex<f64>;

fn to_faer_c(m: &DMatrix<C>) -> faer::Mat<C> {
    faer::Mat::<C>::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)])
}

fn from_faer_c(m: faer::MatRef<'_, C>) -> DMatrix<C> {
    DMatrix::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)])
}

/// The product of two complex matrices by faer (nalgebra multiplies complex
/// matrices without a blocked kernel: at N = 1024 some ten times slower).
pub fn complex_product(a: &DMatrix<C>, b: &DMatrix<C>) -> DMatrix<C> {
    assert_eq!(a.ncols(), b.nrows(), "dimension mismatch in product");
    let c = to_faer_c(a) * to_faer_c(b);
    from_faer_c(c.as_ref())
}

/// The eigen-decomposition of a Hermitian matrix (its lower triangle) by
/// faer: eigenvalues ascending and the unitary `U` with `H = U diag U^*`;
/// `None` when an entry is not finite or the iteration did not converge.
pub fn hermitian_eigen(h: &DMatrix<C>) -> Option<(Vec<f64>, DMatrix<C>)> {
    let n = h.nrows();
    if n != h.ncols() || h.iter().any(|z| !(z.re.is_finite() && z.im.is_finite())) {
        return None;
    }
    if n == 0 {
        return Some((vec![], DMatrix::zeros(0, 0)));
    }
    let e = to_faer_c(h).self_adjoint_eigen(faer::Side::Lower).ok()?;
    let values: Vec<f64> = (0..n).map(|i| e.S()[i].re).collect();
    Some((values, from_faer_c(e.U())))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// faer's product is nalgebra's (to rounding).
    #[test]
    fn the_product_is_the_product() {
        let a = DMatrix::from_fn(3, 2, |i, j| C::new(i as f64, j as f64));
        let b = DMatrix::from_fn(2, 4, |i, j| C::new(1.0 + j as f64, -(i as f64)));
        assert!((complex_product(&a, &b) - &a * &b).norm() < 1e-14);
    }

    /// [[2, i], [-i, 2]] has eigenvalues 1 and 3 (its characteristic
    /// polynomial is (2 - l)^2 - 1), and `U diag U^*` gives it back.
    #[test]
    fn a_hermitian_matrix_is_decomposed() {
        let h =
            DMatrix::from_row_slice(2, 2, &[C::new(2.0, 0.0), C::new(0.0, 1.0), C::new(0.0, -1.0), C::new(2.0, 0.0)]);
        let (values, u) = hermitian_eigen(&h).unwrap();
        assert!((values[0] - 1.0).abs() < 1e-14 && (values[1] - 3.0).abs() < 1e-14);
        let d = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(values.iter().map(|v| C::new(*v, 0.0)).collect()));
        assert!((&u * d * u.adjoint() - h).norm() < 1e-14);
    }
}
