//! A certified lower bound on `Sigma^2` over the whole Casimir family when
//! the multipliers are free.
//!
//! When `Q` does not depend on `M`, every choice `(t, M)` with `sP ≻ 0` has
//! `lambda_max(sQ, sP) >= <X, sQ> / <X, sP>` for any `X ⪰ 0`, `X ≠ 0`
//! (because `sQ - lambda_max sP ⪯ 0`). Take `X` with its columns in
//! `ker G^T`: then `<X, G M G^T> = 0`, and `<X, Q>` does not see `M` either
//! when `G^T B_i X B_i^T G = 0` for every noise matrix (the drift terms vanish
//! as `X G = 0`). Both forms are affine in `t`: `P(t) = P_0 + sum t_j D_j`,
//! `Q(t) = Q_0 + sum t_j L(D_j)`. If moreover
//!
//! * `<X, L(D_j)> = rho <X, D_j>` for every family direction `D_j`, and
//! * `<X, sQ - rho sP> >= 0` at one choice (then at all of them),
//!
//! the quotient is at least `rho` for every `t` and `M` with `sP ≻ 0`:
//! `rho` is a lower bound on what any choice of the family *with the same
//! sign* can give (the dual of the quasi-convex minimisation over `t`, which
//! is also over one sign). Choices where `P` is definite with the other
//! sign, when the family has any, are not covered: there `<X, -sP>` is
//! positive and the inequality can fail.
//!
//! The witness is `X = Z (sum_i c_i v_i v_i^T) Z^T` with weights `c >= 0`
//! (positive semidefinite by construction) on rational vectors `v_i` of
//! `ker G^T` coordinates, found as a vertex of the small polyhedron of
//! feasible weights (at most `f + 1` non-zero). The vectors are first the
//! exact eigenspace `ker(Qz(t_q) - rho_q Pz(t_q))` at short rationals
//! `t_q`, `rho_q` near the floating-point optimum (the bound is then sharp:
//! the inequality holds with equality there), then rounded generalized
//! eigenvectors at `t*` with `rho` a little below the estimate (`1e-12` to
//! `1e-4` relative). Each is completed by Schur combinations of pairs, so
//! that vectors of both signs exist for the equalities. Every condition is
//! exact; `verify check` re-derives them on its own path.

use crate::form::generator_form;
use crate::linearise::Linearisation;
use crate::pencil::generalized_eigen;
use casimir::{SecondVariation, Sign};
use exact::{Matrix, Rational};
use nalgebra::DMatrix;
use num_traits::{One, Zero};

/// The witness of a certified lower bound on `Sigma^2` over the family.
#[derive(Clone, Debug, PartialEq)]
pub enum InfimumWitness {
    /// No free multipliers: `x` in `ker G^T` with `G^T B_i x = 0`; the bound
    /// is `max(0, x^T sQ x / x^T sP x)`, the same for every `M`.
    Vector(Vec<Rational>),
    /// Free multipliers: `X ⪰ 0` (`n × n`) with the properties in the
    /// module docs; the bound `rho` satisfies them.
    Matrix(Matrix),
}

/// The columns of `v` (`k × r`) scaled to integers: `round(10^digits v / |v|_inf)`.
fn integer_columns(v: &DMatrix<f64>, digits: i32) -> Option<Matrix> {
    let mut out = Matrix::zeros(v.nrows(), v.ncols());
    for j in 0..v.ncols() {
        let top = v.column(j).iter().fold(0.0f64, |m, x| m.max(x.abs()));
        if !top.is_finite() || top <= 0.0 {
            return None;
        }
        for i in 0..v.nrows() {
            // 10^15 < 2^53: the rounded values are exact integers.
            out[(i, j)] = Rational::from((v[(i, j)] / top * 10f64.powi(digits)).round() as i64);
        }
    }
    Some(out)
}

/// A certified lower bound `rho` on `Sigma^2 = lambda_max(sQ, sP)` for every
/// choice of the multipliers and of `M` with `sP ≻ 0`, and its witness `X`
/// in the algebra's coordinates, built at the floating-point minimiser
/// `t_star` of the restricted problem. `None` when no bound could be proved
/// (never a false one: every condition is checked exactly here, and again
/// by `verify check`).
///
/// Requires `Q` not to depend on `M` (the caller checks it); the noise
/// condition on `X` is checked here regardless.
pub fn family_lower_bound(
    variation: &SecondVariation,
    linearisation: &Linearisation,
    sign: Sign,
    t_star: &[f64],
) -> Option<(Rational, Matrix)> {
    let f = variation.family.directions.len();
    let z = &variation.kernel;
    let k = z.ncols();
    if f == 0 || k == 0 || t_star.len() != f {
        return None;
    }
    let s = if sign.is_positive() { Rational::one() } else { -Rational::one() };
    let restrict = |m: &Matrix| z.transpose().mul(m).mul(z).scale(&s);
    let base0 = variation.base(&variation.family.particular);
    let dirs: Vec<Matrix> = (0..f)
        .map(|j| {
            let mut t = vec![Rational::zero(); f];
            t[j] = Rational::one();
            variation.base(&variation.family.at(&t)).sub(&base0)
        })
        .collect();
    let q_of = |m: &Matrix| generator_form(linearisation, m).q;
    let (p0, q0) = (restrict(&base0), restrict(&q_of(&base0)));
    let pd: Vec<Matrix> = dirs.iter().map(&restrict).collect();
    let qd: Vec<Matrix> = dirs.iter().map(|d| restrict(&q_of(d))).collect();
    // The restricted pencil at t*, in floating point.
    let at = |m0: &Matrix, ms: &[Matrix]| {
        let mut a = m0.to_dmatrix();
        for (t, m) in t_star.iter().zip(ms) {
            a += m.to_dmatrix() * *t;
        }
        (&a + a.transpose()) * 0.5
    };
    let eig = generalized_eigen(&at(&p0, &pd), &at(&q0, &qd))?;
    let rho_star = *eig.values.last()?;
    if !rho_star.is_finite() || rho_star <= 0.0 {
        return None; // a bound of 0 holds trivially
    }
    // 1. Sharp: at rational multipliers t_q near t* and a short rational
    // rho_q near the top eigenvalue, the exact eigenspace
    // N = ker(Qz(t_q) - rho_q Pz(t_q)); on it <X, F(t_q)> = 0, so the
    // inequality holds with equality and only the f equalities remain.
    let restricted_at = |t: &[Rational], m0: &Matrix, ms: &[Matrix]| {
        let mut m = m0.clone();
        for (ti, mi) in t.iter().zip(ms) {
            if !ti.is_zero() {
                m.add_scaled_assign(ti, mi);
            }
        }
        m
    };
    let candidates_t: Vec<Vec<Rational>> = [1u64, 10, 100, 1000, 1_000_000]
        .into_iter()
        .filter_map(|d| t_star.iter().map(|&x| exact::best_rational_approximation(x, d)).collect())
        .chain([9u32, 15].into_iter().filter_map(|d| t_star.iter().map(|&x| exact::decimal_near(x, d)).collect()))
        .collect();
    for t_q in &candidates_t {
        // decimal_near rounds away from zero: a value a few ulps above a
        // short decimal (0.0720000000000001) would give 0.0720001, so the
        // estimate lowered by one unit of the last digit is rounded too.
        let short = [6i32, 9, 12, 15].into_iter().flat_map(|d| {
            [rho_star, rho_star * (1.0 - 10f64.powi(-d))]
                .into_iter()
                .filter_map(move |x| exact::decimal_near(x, d as u32))
        });
        let mut tried: Vec<Rational> = Vec::new();
        for rho in short {
            if tried.contains(&rho) {
                continue;
            }
            tried.push(rho.clone());
            let fz = restricted_at(t_q, &q0, &qd).sub(&restricted_at(t_q, &p0, &pd).scale(&rho));
            let null = fz.null_space();
            if null.is_empty() {
                continue;
            }
            let fj: Vec<Matrix> = qd.iter().zip(&pd).map(|(q, p)| q.sub(&p.scale(&rho))).collect();
            let cands = with_mixed_pairs(null, &fj);
            let f0 = q0.sub(&p0.scale(&rho));
            if let Some(x) = witness(variation, linearisation, &cands, &fj, &f0) {
                return Some((rho, x));
            }
        }
    }
    // 2. Slightly below: rounded generalized eigenvectors at t*, all k of
    // them, and rho a little under the estimate (a relative margin of 1e-12
    // to 1e-4, less the rounding of rho itself) so that the inequality has
    // room for the rounding of the vectors.
    // Largest first.
    let v = DMatrix::from_fn(k, k, |i, j| eig.vectors[(i, k - 1 - j)]);
    let vq = integer_columns(&v, 15)?;
    for margin in [1e-12, 1e-9, 1e-6, 1e-4] {
        // decimal_near rounds away from zero (up, here) by less than
        // 10^(1-d) relative: the shortest that stays below half the margin.
        let Some(rho) = [6u32, 9, 12, 15].into_iter().find_map(|d| {
            let x = exact::decimal_near(rho_star * (1.0 - margin), d)?;
            (exact::rational_to_f64(&x) <= rho_star * (1.0 - margin / 2.0)).then_some(x)
        }) else {
            continue;
        };
        let fj: Vec<Matrix> = qd.iter().zip(&pd).map(|(q, p)| q.sub(&p.scale(&rho))).collect();
        let cands = with_mixed_pairs((0..k).map(|i| vq.column(i)).collect(), &fj);
        let f0 = q0.sub(&p0.scale(&rho));
        if let Some(x) = witness(variation, linearisation, &cands, &fj, &f0) {
            return Some((rho, x));
        }
    }
    None
}

/// `x^T M x`, exactly.
fn quad(m: &Matrix, x: &[Rational]) -> Rational {
    x.iter().zip(m.mul_vec(x)).fold(Rational::zero(), |acc, (a, b)| if a.is_zero() { acc } else { acc + a * &b })
}

/// The vectors, plus for each pair `(u, w)` and each form `F` with
/// `u^T F u`, `w^T F w` of one sign but `F` indefinite on their span, the
/// vector `u - (u^T F w / w^T F w) w` on which `F` has the other sign (the
/// Schur complement): rational vectors of both signs for the equalities.
fn with_mixed_pairs(vectors: Vec<Vec<Rational>>, forms: &[Matrix]) -> Vec<Vec<Rational>> {
    let mut out = vectors.clone();
    for f in forms {
        for (i, u) in vectors.iter().enumerate() {
            for w in vectors.iter().skip(i + 1) {
                let (uu, ww) = (quad(f, u), quad(f, w));
                if ww.is_zero() || uu.is_zero() || uu.is_negative() != ww.is_negative() {
                    continue;
                }
                let uw = u.iter().zip(f.mul_vec(w)).fold(Rational::zero(), |acc, (a, b)| acc + a * &b);
                let x = &uw / &ww;
                let v: Vec<Rational> = u.iter().zip(w).map(|(a, b)| a - &(&x * b)).collect();
                let vv = quad(f, &v);
                if !vv.is_zero() && vv.is_negative() != uu.is_negative() {
                    out.push(v);
                }
            }
        }
    }
    out
}

/// `X = Z (sum_i c_i v_i v_i^T) Z^T` with weights `c >= 0` (so `X ⪰ 0` by
/// construction) meeting the equalities `sum_i c_i v_i^T F_j v_i = 0` and
/// the inequality `sum_i c_i v_i^T F_0 v_i >= 0`: a feasible `c` with at most
/// `f + 1` non-zero weights exists if any does (a vertex of the
/// polyhedron), so subsets of that size are enumerated. `None` also when
/// the noise would carry `X` off `ker G^T`.
fn witness(
    variation: &SecondVariation,
    linearisation: &Linearisation,
    vectors: &[Vec<Rational>],
    fj: &[Matrix],
    f0: &Matrix,
) -> Option<Matrix> {
    let f = fj.len();
    let a: Vec<Vec<Rational>> = fj.iter().map(|m| vectors.iter().map(|x| quad(m, x)).collect()).collect();
    let b: Vec<Rational> = vectors.iter().map(|x| quad(f0, x)).collect();
    // Bounded work: at most a few thousand small null spaces.
    for subset in subsets(vectors.len(), f + 1).into_iter().take(4096) {
        let system = Matrix::from_fn(f, subset.len(), |j, i| a[j][subset[i]].clone());
        let null = system.null_space();
        if null.len() != 1 {
            continue;
        }
        let mut c = null[0].clone();
        if c.iter().any(Rational::is_negative) {
            c.iter_mut().for_each(|x| *x = -x.clone());
        }
        if c.iter().any(Rational::is_negative) || c.iter().all(Zero::is_zero) {
            continue;
        }
        let value = c.iter().zip(&subset).fold(Rational::zero(), |acc, (ci, &i)| acc + ci * &b[i]);
        if value.is_negative() {
            continue;
        }
        let n = variation.dim();
        let mut x = Matrix::zeros(n, n);
        for (ci, &i) in c.iter().zip(&subset) {
            if ci.is_zero() {
                continue;
            }
            let w = variation.kernel.mul_vec(&vectors[i]);
            x.add_scaled_assign(ci, &Matrix::from_fn(n, n, |p, q| &w[p] * &w[q]));
        }
        let g = &variation.gradients;
        let noise_free =
            linearisation.noise.iter().all(|bm| g.transpose().mul(bm).mul(&x).mul(&bm.transpose()).mul(g).is_zero());
        return noise_free.then_some(x);
    }
    None
}

/// The subsets of `{0, .., k-1}` of sizes 1 to `max`, smallest first.
fn subsets(k: usize, max: usize) -> Vec<Vec<usize>> {
    fn grow(start: usize, k: usize, size: usize, current: &mut Vec<usize>, out: &mut Vec<Vec<usize>>) {
        if current.len() == size {
            out.push(current.clone());
            return;
        }
        for i in start..k {
            current.push(i);
            grow(i + 1, k, size, current, out);
            current.pop();
        }
    }
    let mut out = Vec::new();
    for size in 1..=max.min(k) {
        grow(0, k, size, &mut Vec::new(), &mut out);
    }
    out
}
