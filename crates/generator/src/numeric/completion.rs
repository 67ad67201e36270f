//! Step 4 of the numeric level: the Casimir Hessian by the Schur
//! completion in the frame `[Z W]`, and the generator form `Q` of step 5.

use super::restricted::Restricted;
use super::symmetric;
use crate::optimise::FramePencil;
use crate::pencil::symmetric_eigenvalues;
use casimir::Sign;
use nalgebra::DMatrix;

/// The signed pencil `(sP, sQ)` at the multipliers: `sP = sB + W K' W^T`
/// over the Casimir Hessian `K'`, `sQ` not depending on it.
pub(super) struct SignedPencil {
    /// The dimension `k` of `ker G^T`.
    pub(super) k: usize,
    /// `sB`.
    pub(super) sb: DMatrix<f64>,
    /// The orthonormal basis `W` of the range of `G`.
    pub(super) w: DMatrix<f64>,
    /// `sQ`, the generator form of `sB`.
    pub(super) sq: DMatrix<f64>,
    /// The blocks of `(sP, sQ)` in the frame `[Z W]`, with the Schur bound
    /// `K0'` and the margin `D`.
    pub(super) frame: FramePencil,
}

impl SignedPencil {
    /// `sP = sym(sB + W K' W^T)`.
    pub(super) fn p_of(&self, kp: &DMatrix<f64>) -> DMatrix<f64> {
        symmetric(&self.sb + &self.w * kp * self.w.transpose())
    }
}

/// The pencil of `sB` for the definite sign: `K0' = Pzw^T Pz^{-1} Pzw - Pw`
/// (`sP ≻ 0` iff `K' ≻ K0'`), the margin `D = c I` with `c` the level scale,
/// and `sQ`.
pub(super) fn schur_completion(
    b: &DMatrix<f64>,
    z: &DMatrix<f64>,
    w: DMatrix<f64>,
    restricted: &Restricted,
    sign: Sign,
    noise: &[DMatrix<f64>],
) -> Result<SignedPencil, &'static str> {
    let s = sign.as_f64();
    let k = restricted.k;
    let sb = b * s;
    let pz = &restricted.bzz * s;
    let pzw = z.transpose() * &sb * &w;
    let pw = symmetric(w.transpose() * &sb * &w);
    let rk = w.ncols();
    let k0 = if k == 0 {
        -&pw
    } else {
        let ch = pz.clone().cholesky().ok_or("the Cholesky factor of the restricted Hessian")?;
        symmetric(pzw.transpose() * ch.solve(&pzw) - &pw)
    };
    let level = level_scale(restricted, sign, &sb);
    let margin_d = DMatrix::<f64>::identity(rk, rk) * level;
    // Q does not depend on the Casimir Hessian (the noise and the drift
    // conserve every conserved quantity): the form of B serves.
    let sq = generator_form_f64(noise, &sb);
    let frame = FramePencil {
        qz: symmetric(z.transpose() * &sq * z),
        qzw: z.transpose() * &sq * &w,
        qw: symmetric(w.transpose() * &sq * &w),
        pz,
        pzw,
        pw,
        k0,
        margin: margin_d,
    };
    Ok(SignedPencil { k, sb, w, sq, frame })
}

/// The level scale: `sqrt(l_min l_max)` of `s Z^T B Z`, else `|B|_2`,
/// else 1.
fn level_scale(restricted: &Restricted, sign: Sign, sb: &DMatrix<f64>) -> f64 {
    let level = if restricted.k > 0 {
        let (lo, hi) = if sign.is_positive() {
            (restricted.eig_lo, restricted.eig_hi)
        } else {
            (-restricted.eig_hi, -restricted.eig_lo)
        };
        (lo.max(0.0) * hi.max(0.0)).sqrt()
    } else {
        symmetric_eigenvalues(sb).map_or(1.0, |e| e.iter().fold(0.0f64, |a, &x| a.max(x.abs())))
    };
    if level.is_finite() && level > 0.0 {
        level
    } else {
        1.0
    }
}

/// `Q = sum_i (B_i^T P B_i + sym(P B_i^2))`, the generator form of `P`
/// without its drift part.
///
/// `Q = sym(P A~ + A~^T P) + sum B^T P B` is, for an energy–Casimir `P`,
/// exactly the paper's formula: the drift part `P A + A^T P` vanishes. It
/// is formed that way, so that its rounding (about eps |P| |A|, which
/// swamped Sigma^2 when the noise is small beside the drift: a review
/// found values 6000 times too low) is not added.
fn generator_form_f64(noise: &[DMatrix<f64>], p: &DMatrix<f64>) -> DMatrix<f64> {
    let n = p.nrows();
    let mut q = DMatrix::zeros(n, n);
    for bm in noise {
        let pb = p * bm;
        q += bm.transpose() * &pb;
        q += symmetric(&pb * bm);
    }
    symmetric(q)
}
