//! Step 3 of the numeric level: the second variation
//! `B = D^2h + sum lambda_j D^2K_j` with a bound on its rounding, and the
//! sign and relative margin of the restricted Hessian `Z^T B Z`.

use super::derivatives::Derivatives;
use super::multipliers::Frame;
use super::{frobenius, symmetric};
use crate::pencil::symmetric_eigenvalues;
use casimir::Sign;
use nalgebra::DMatrix;

/// `B = D^2h + sum lambda_j D^2K_j` (symmetrised) and a bound on its
/// rounding in the 2-norm.
pub(super) fn second_variation(d: &Derivatives, frame: &Frame) -> (DMatrix<f64>, f64) {
    let n = d.hh.nrows();
    let (lambda, lengths) = (&frame.lambda, &frame.lengths);
    let mut b = d.hh.clone();
    // A bound on the rounding of B = D^2h + sum lambda_j D^2K_j (2-norm, by
    // the Frobenius norm): D^2h rounded from exact, each Hessian to its
    // terms' rounding, and the multipliers of the unit columns (`lambda_j
    // |g_j|`, which do not depend on how a quantity is scaled) to about
    // (theta + eps cond(G)) of their norm (the least-squares solve with the
    // gradients' own error); `lambda_j` itself then errs by that over
    // `|g_j|`.
    let mut b_error = 4.0 * f64::EPSILON * d.hh.norm();
    let unit_multipliers = lambda.iter().zip(lengths).map(|(l, len)| (l * len).powi(2)).sum::<f64>().sqrt();
    let lambda_error = unit_multipliers * (frame.theta + d.rounding * frame.g_condition);
    for (j, dk) in d.conserved.iter().enumerate() {
        let hk = DMatrix::from_row_slice(n, n, &dk.hessian);
        let spread = if lengths[j] > 0.0 { lambda_error / lengths[j] } else { 0.0 };
        b_error += lambda[j].abs() * d.rounding * frobenius(&dk.hessian_size) + spread * hk.norm();
        b += hk * lambda[j];
    }
    (symmetric(b), b_error)
}

/// The restricted Hessian `Z^T B Z` and its extreme eigenvalues.
pub(super) struct Restricted {
    /// `Z^T B Z` (symmetrised).
    pub(super) bzz: DMatrix<f64>,
    /// The dimension `k` of `ker G^T`.
    pub(super) k: usize,
    /// The smallest eigenvalue (`+inf` when `k = 0`).
    pub(super) eig_lo: f64,
    /// The largest eigenvalue (`-inf` when `k = 0`).
    pub(super) eig_hi: f64,
    /// The largest eigenvalue magnitude (0 when `k = 0`).
    pub(super) max_abs: f64,
}

/// What the restricted Hessian's eigenvalues decide.
pub(super) enum Definiteness {
    /// Definite of this sign, with a margin above the tolerance.
    Definite(Sign),
    /// Neither sign has a margin above the tolerance; the larger margin.
    NotDefinite(f64),
}

impl Restricted {
    /// `Z^T B Z` and its extreme eigenvalues.
    pub(super) fn new(b: &DMatrix<f64>, z: &DMatrix<f64>) -> Result<Self, &'static str> {
        let k = z.ncols();
        let bzz = symmetric(z.transpose() * b * z);
        let (eig_lo, eig_hi, max_abs) = if k == 0 {
            (f64::INFINITY, f64::NEG_INFINITY, 0.0)
        } else {
            let e = symmetric_eigenvalues(&bzz).ok_or("the eigenvalues of the restricted Hessian")?;
            let (lo, hi) = (e[0], e[k - 1]);
            (lo, hi, lo.abs().max(hi.abs()))
        };
        Ok(Restricted { bzz, k, eig_lo, eig_hi, max_abs })
    }

    /// The relative margin `lambda_min(s Z^T B Z) / max|eig|` for the sign `s`.
    pub(super) fn margin(&self, sign: Sign) -> f64 {
        if self.k == 0 {
            return 1.0; // the empty form is vacuously definite
        }
        let lo = if sign.is_positive() { self.eig_lo } else { -self.eig_hi };
        if self.max_abs > 0.0 {
            lo / self.max_abs
        } else {
            0.0
        }
    }

    /// The sign whose margin exceeds `tol` (the positive sign first), or
    /// `Err` when the rounding of `B` could decide it.
    pub(super) fn decide(
        &self,
        b: &DMatrix<f64>,
        b_error: f64,
        theta: f64,
        tol: f64,
    ) -> Result<Definiteness, &'static str> {
        let n = b.nrows();
        // The restricted Hessian's eigenvalues move by at most the rounding of
        // B (Weyl; Z has orthonormal columns, and its own rounding adds a few
        // eps |B|): a sign that this rounding could decide is not decided here.
        // (The computed ker G^T is within the angle theta of the exact one,
        // which moves the restricted eigenvalues by up to 2 theta |B| + theta^2
        // |B|: a review found false `stable` verdicts without this term.)
        let eig_error = b_error + (16.0 * (n as f64) * f64::EPSILON + 3.0 * theta) * b.norm();
        if self.k > 0
            && [Sign::Positive, Sign::Negative]
                .iter()
                .any(|&s| (self.margin(s) - tol).abs() * self.max_abs <= eig_error)
        {
            return Err("the restricted Hessian's sign is within its rounding of the definiteness tolerance");
        }
        Ok(match [Sign::Positive, Sign::Negative].into_iter().find(|&s| self.margin(s) > tol) {
            Some(sign) => Definiteness::Definite(sign),
            None => Definiteness::NotDefinite(self.margin(Sign::Positive).max(self.margin(Sign::Negative))),
        })
    }
}
