//! Steps 5 and 6: the chosen form in the frame `[Z W]`, the Casimir Hessian
//! `K`, `Sigma^2 = lambda_max(sQ, sP)`, and the drift residual of the final `P`.

use super::form::ChosenForm;
use super::linearise::{generator_form, Linearisation, Sparse};
use super::multipliers::Multipliers;
use super::{numerical, LargeSettings};
use crate::LargeError;
use nalgebra::DMatrix;
use numerics::dense::{largest_generalized, product, symmetric_eigen, FramePencil};

/// The final pencil and what it gave.
pub(super) struct FinalPencil {
    /// `s B(t)`: `P` without the Casimir Hessian.
    pub(super) sp: DMatrix<f64>,
    /// The blocks of `sP` and `sQ` in the frame.
    pub(super) frame: FramePencil,
    /// The Casimir Hessian in the frame (`rank x rank`).
    pub(super) k: DMatrix<f64>,
    /// `Sigma^2` at `P = sB + W K W^T`.
    pub(super) sigma2: f64,
    /// Its infimum over `K` (when `Q` does not depend on `K`).
    pub(super) infimum: Option<f64>,
    /// `cond(sP)`.
    pub(super) condition: f64,
}

/// The pencil `(sP, sQ)` in the frame, `K` by the Schur completion when `Q`
/// does not depend on it (else the reference choice), and `Sigma^2` there.
pub(super) fn final_pencil(
    form: &ChosenForm,
    m: &Multipliers,
    lin: &Linearisation,
    sign: f64,
    q_depends_on_casimirs: bool,
    settings: &LargeSettings,
) -> Result<FinalPencil, LargeError> {
    // The frame [Z W] = U (orthonormal, from the SVD) and the Casimir
    // Hessian: each matrix is carried to the frame by one congruence
    // U^T M U, whose blocks are the Z and W parts.
    let sp = &form.base * sign;
    let sq = generator_form(&sp, &lin.a_tilde, &lin.noise);
    let (pz, pzw, pw) = m.blocks(&(&form.base_frame * sign));
    let (qz, qzw, qw) = m.blocks(&m.frame_coordinates(&sq));
    // (the geometric mean as a product of roots: lo * hi underflows for
    // a system scaled by 1e-180)
    let level = (form.lo.abs().sqrt() * form.hi.sqrt()).max(f64::MIN_POSITIVE);
    let frame = FramePencil { pz, pzw, pw, qz, qzw, qw };
    let (k, sigma2, infimum, condition) = if q_depends_on_casimirs {
        // Q moves with K: the reference choice, unoptimised.
        let (k, s2, condition) = reference_choice(&frame, &sp, m, lin, level)?;
        (k, s2, None, condition)
    } else {
        let c = frame
            .complete(level, settings.condition_limit)
            .ok_or_else(|| numerical("no Casimir Hessian made P definite"))?;
        (c.k, c.sigma2, Some(c.infimum), c.condition_number)
    };
    Ok(FinalPencil { sp, frame, k, sigma2, infimum, condition })
}

/// The reference Casimir Hessian `K = (K0)_+ + level I` with the Schur bound
/// `K0 = Pzw^T Pz^-1 Pzw - Pw`, and `Sigma^2`, `cond(P)` of the full pencil.
fn reference_choice(
    frame: &FramePencil,
    sp: &DMatrix<f64>,
    m: &Multipliers,
    lin: &Linearisation,
    level: f64,
) -> Result<(DMatrix<f64>, f64, f64), LargeError> {
    let (rank, w) = (m.rank, &m.w);
    let l = frame.pz.clone().cholesky().ok_or_else(|| numerical("the restricted Hessian's Cholesky factor"))?;
    let k0 = frame.pzw.transpose() * l.solve(&frame.pzw) - &frame.pw;
    let (values, vecs) = symmetric_eigen(&k0).ok_or_else(|| numerical("the Schur bound's eigenvalues"))?;
    let mut positive = DMatrix::zeros(rank, rank);
    for (j, x) in values.iter().enumerate() {
        if *x > 0.0 {
            positive += vecs.column(j) * vecs.column(j).transpose() * *x;
        }
    }
    let k = positive + DMatrix::identity(rank, rank) * level;
    let p_full = sp + product(&product(w, &k), &w.transpose());
    let q_full = generator_form(&p_full, &lin.a_tilde, &lin.noise);
    let s2 = largest_generalized(&p_full, &q_full).ok_or_else(|| numerical("the generalized eigenproblem"))?;
    Ok((k, s2, numerics::dense::condition_number(&p_full)))
}

/// `|P A + A^T P|_F / (|P|_F |A|_F)` for `P = sB + W K W^T` and sparse `A`:
/// `O(nnz n)` plus the rank-sized part, no dense product.
pub(super) fn drift_residual(
    a: &Sparse,
    sp: &DMatrix<f64>,
    m: &Multipliers,
    k: &DMatrix<f64>,
    frame: &FramePencil,
) -> f64 {
    let (rank, w) = (m.rank, &m.w);
    let n = sp.nrows();
    let mut pa = DMatrix::zeros(n, n);
    for (&(r0, c0), &x) in &a.entries {
        let col = sp.column(r0) * x;
        let mut target = pa.column_mut(c0);
        target += col;
    }
    let mut wta = DMatrix::zeros(rank, n); // W^T A
    for (&(r0, c0), &x) in &a.entries {
        for i in 0..rank {
            wta[(i, c0)] += w[(r0, i)] * x;
        }
    }
    pa += w * (k * wta);
    let drift = &pa + pa.transpose();
    // |P|_F from the frame (U is orthogonal): the off-diagonal block twice.
    let p_norm = {
        let mut pf = frame.pz.norm_squared() + 2.0 * frame.pzw.norm_squared();
        pf += (&frame.pw + k).norm_squared();
        pf.sqrt()
    };
    let a_norm = a.entries.values().map(|x| x * x).sum::<f64>().sqrt();
    let scale = p_norm * a_norm;
    if scale > 0.0 {
        drift.norm() / scale
    } else {
        0.0
    }
}
