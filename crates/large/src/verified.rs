//! The `verified_float` final check of the large pipeline: `P ≻ 0` and
//! `bar P - Q(P) ≻ 0` proved by the rigorous floating-point Cholesky test
//! ([`numerics::definite::positive_definite`]) for the **exact**
//! second variation of an exactly conserved functional, with every
//! rounding between the exact data and the tested matrices bounded.
//!
//! **The functional.** The floating-point multipliers are rounded to nearby
//! simple rationals `lambda*` (continued fractions), kept only when
//! `G lambda* + Dh(mu_e) = 0` holds exactly (sparse rational arithmetic).
//! The Casimir Hessian `K` of the frame `[Z W]` becomes `K' = V_r S^-1 K
//! S^-1 V_r^T` from the SVD `G = U S V^T` (so that `W K W^T = G K' G^T` up
//! to rounding), and `K'`, a matrix of doubles, is taken as it is. Then
//!
//! ```text
//! H = s (h + sum_j lambda*_j C_j) + 1/2 (C - C(mu_e))^T K' (C - C(mu_e))
//! ```
//!
//! (`C` the Casimirs and first integrals) is conserved by the drift, it is
//! critical at `mu_e` exactly, and its Hessian there is
//! `P* = s (D^2h + sum_j lambda*_j D^2C_j) + G K' G^T` with the exact `G`.
//!
//! **The generator form.** Since `H` is conserved and critical, the
//! linearised drift keeps `P*` exactly: `P* A + A^T P* = 0` (the second
//! order of `d/dt H = 0`). So the Itô generator of `x^T P* x` for the
//! linearised SDE `dx = A x dt + sum_i B_i x o dW^i` is `x^T Q* x` with
//!
//! ```text
//! Q* = sum_i ( B_i^T P* B_i + (P* B_i^2 + (B_i^2)^T P*) / 2 ),
//! ```
//!
//! the drift term dropped because it is exactly zero (formed in floating
//! point it would only add rounding). `Q*` is homogeneous of degree two in
//! the noise, so the pipeline's exact power-of-two rescaling of the noise
//! carries over to the bound exactly. `B_i` and `B_i^2` are formed in
//! rational arithmetic (sparse) and rounded once.
//!
//! **What is proved.** `P_f`, `X_f = fl(bar P_f - Q_f)` are the matrices
//! formed in floating point; `r_P`, `r_X` bound `||P* - P_f||_2` and
//! `||(bar P* - Q*) - X_f||_2` (Frobenius norms of entrywise bounds, each
//! rounding of the formation counted with Higham's `gamma_k`, valid for any
//! order of summation). The verified Cholesky test of `P_f` within `r_P`
//! and of `X_f` within `r_X` then proves `P* ≻ 0` and `bar P* - Q* ≻ 0`, so
//! `E x_t^T P* x_t <= e^(bar t) x_0^T P* x_0` for the linearised SDE, and the
//! energy–Casimir form of an exactly conserved, exactly critical functional
//! is definite.

use crate::system::LargeSystem;
use exact::Rational;
use nalgebra::DMatrix;
use num_traits::Zero;
use numerics::definite::{positive_definite, Symmetric};
// Higham's gamma_k = k u / (1 - k u), shared with the banded checks.
use numerics::banded::gamma;
use std::collections::BTreeMap;

/// Unit roundoff.
const U: f64 = f64::EPSILON / 2.0;

/// A sparse rational matrix, `(row, column) -> value`.
type Exact = BTreeMap<(usize, usize), Rational>;

/// `x` rounded to a double, with an upper bound on `|x - fl(x)|` (computed
/// exactly, then rounded up).
fn rounded(x: &Rational) -> Option<(f64, f64)> {
    let f = exact::rational_to_f64(x);
    if !f.is_finite() {
        return None;
    }
    let back = Rational::from_float(f)?;
    let err = exact::rational_to_f64_up(&(x - &back).abs());
    err.is_finite().then_some((f, err))
}

/// An upper bound on `sqrt(sum x_i^2)` that neither underflows nor
/// overflows: the terms are scaled by the power of two near the largest
/// magnitude (exact, except for terms that become subnormal: their error,
/// and that of squares below the normal range, is covered by the absolute
/// term `sqrt(count) 2^-500` in the scaled units), summed, and scaled back.
/// Squaring every error bound without scaling lost every bound below about
/// 1e-162 (a review found radii of 7e-305 for errors of 1e-196).
fn norm_up<I: Iterator<Item = f64> + Clone>(values: I) -> f64 {
    let m = values.clone().fold(0.0f64, |a, x| a.max(x.abs()));
    if m == 0.0 {
        return 0.0;
    }
    if !m.is_finite() {
        return f64::INFINITY;
    }
    // 2^-e with 2^e <= m < 2^(e+1) (m / 2^e in [1, 2), up to the clamp of
    // `exponent_of` at 2^±1000)
    let scale = numerics::scaling::pow2(1 - numerics::scaling::exponent_of(m));
    let (mut sum, mut count) = (0.0f64, 0usize);
    for x in values {
        let y = x * scale;
        sum += y * y;
        count += 1;
    }
    let count = count as f64;
    let scaled = sum.sqrt() * (1.0 + 4.0 * (count + 4.0) * U) + count.sqrt() * numerics::scaling::pow2(-500);
    // dividing by a power of two is exact unless the result leaves the
    // normal range (then it rounds by less than MIN_POSITIVE)
    scaled / scale + f64::MIN_POSITIVE
}

/// A sparse matrix of doubles with the Frobenius norm of its entrywise
/// rounding bound, and the largest number of entries in a column.
struct Rounded {
    entries: Vec<(usize, usize, f64)>,
    error: f64,
    norm: f64,
    column_count: usize,
}

fn round_matrix(m: &Exact, n: usize) -> Option<Rounded> {
    let mut entries = Vec::with_capacity(m.len());
    let mut errors = Vec::with_capacity(m.len());
    let mut counts = vec![0usize; n];
    for (&(r, c), x) in m {
        let (f, e) = rounded(x)?;
        if f != 0.0 || e != 0.0 {
            entries.push((r, c, f));
            errors.push(e);
            counts[c] += 1;
        }
    }
    Some(Rounded {
        error: norm_up(errors.iter().copied()),
        norm: norm_up(entries.iter().map(|e| e.2)),
        entries,
        column_count: counts.into_iter().max().unwrap_or(0),
    })
}

fn sparse_product(a: &Exact, b: &Exact) -> Exact {
    let mut rows: BTreeMap<usize, Vec<(usize, &Rational)>> = BTreeMap::new();
    for (&(r, c), x) in b {
        rows.entry(r).or_default().push((c, x));
    }
    let mut out = Exact::new();
    for (&(r, m), x) in a {
        if let Some(row) = rows.get(&m) {
            for &(c, y) in row {
                *out.entry((r, c)).or_insert_with(Rational::zero) += x * y;
            }
        }
    }
    out.retain(|_, v| !v.is_zero());
    out
}

/// The Frobenius norm of a dense matrix, rounded upwards.
fn frobenius_up(m: &DMatrix<f64>) -> f64 {
    norm_up(m.iter().copied())
}

/// Copy the lower triangle onto the upper one, so the matrix is exactly
/// symmetric (each entry keeps the bound of the one it copies).
fn mirror(m: &mut DMatrix<f64>) {
    let n = m.nrows();
    for j in 0..n {
        for i in (j + 1)..n {
            m[(j, i)] = m[(i, j)];
        }
    }
}

/// What the pipeline chose, handed to [`VerifiedPencil::build`].
pub struct Choice<'a> {
    /// `s`, `+1` or `-1`.
    pub sign: f64,
    /// The floating-point multipliers (Casimirs, then first integrals).
    pub multipliers: &'a [f64],
    /// The rank of `G`.
    pub rank: usize,
    /// The left singular vectors of `G` (`n x n`, the range of `G` first).
    pub u: &'a DMatrix<f64>,
    /// The right singular vectors of `G` (`r x r`).
    pub v: &'a DMatrix<f64>,
    /// The singular values of `G`.
    pub singular_values: &'a [f64],
    /// The Casimir Hessian in the frame (`rank x rank`).
    pub k: &'a DMatrix<f64>,
}

/// The matrices of the verified check and their rounding bounds; see the
/// module docs.
pub struct VerifiedPencil {
    p: DMatrix<f64>,
    p_radius: f64,
    p_norm: f64,
    q: DMatrix<f64>,
    /// `||Q*(Delta)||_2 <= q_gain ||Delta||_2`.
    q_gain: f64,
    /// Bound on `||Q* (P_f) - Q_f||_2` (the noise's rounding and the
    /// formation's).
    q_error: f64,
    /// The exact multipliers.
    pub multipliers: Vec<Rational>,
    p_definite: bool,
}

impl std::fmt::Debug for VerifiedPencil {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("VerifiedPencil")
            .field("dimension", &self.p.nrows())
            .field("p_radius", &self.p_radius)
            .field("q_gain", &self.q_gain)
            .field("q_error", &self.q_error)
            .field("p_definite", &self.p_definite)
            .finish()
    }
}

/// The exact multipliers: the floating-point ones rounded to the simplest
/// rationals with denominators up to `2^10, 2^20, ..., 2^50`, the first
/// vector with `G lambda* + Dh(mu_e) = 0` exactly; `None` if none is.
pub fn exact_multipliers(system: &LargeSystem, multipliers: &[f64]) -> Option<Vec<Rational>> {
    let mu = system.equilibrium();
    let dh = system.hamiltonian().gradient_at(mu);
    let gradients: Vec<BTreeMap<usize, Rational>> = system.conserved().iter().map(|c| c.gradient_at(mu)).collect();
    if gradients.len() != multipliers.len() {
        return None;
    }
    for bits in [10u32, 20, 30, 40, 50] {
        let candidate: Option<Vec<Rational>> =
            multipliers.iter().map(|x| exact::best_rational_approximation(*x, 1u64 << bits)).collect();
        let Some(candidate) = candidate else { continue };
        let mut residual = dh.clone();
        for (l, g) in candidate.iter().zip(&gradients) {
            if l.is_zero() {
                continue;
            }
            for (i, x) in g {
                *residual.entry(*i).or_insert_with(Rational::zero) += l * x;
            }
        }
        if residual.values().all(Zero::is_zero) {
            return Some(candidate);
        }
    }
    None
}

impl VerifiedPencil {
    /// Build `P_f`, `Q_f` and their bounds for the pipeline's choice, on the
    /// system as given (the pipeline passes its noise-normalised system).
    /// `Err` says why no verified check is possible.
    pub fn build(system: &LargeSystem, choice: &Choice) -> Result<VerifiedPencil, String> {
        let n = system.dim();
        let conserved = system.conserved();
        let r = conserved.len();
        let mu = system.equilibrium();
        let multipliers = exact_multipliers(system, choice.multipliers).ok_or_else(|| {
            "the multipliers could not be written as rationals with G lambda + Dh = 0 exactly (denominators up to 2^50 tried)"
                .to_string()
        })?;
        // S* = D^2h + sum lambda*_j D^2C_j, exactly (upper triangle).
        let mut s_exact = system.hamiltonian().hessian_at(mu);
        for (l, c) in multipliers.iter().zip(&conserved) {
            if l.is_zero() {
                continue;
            }
            for (ij, x) in c.hessian_at(mu) {
                *s_exact.entry(ij).or_insert_with(Rational::zero) += l * &x;
            }
        }
        let mut p = DMatrix::<f64>::zeros(n, n);
        // each entry's error, twice for an off-diagonal one (both triangles)
        let mut s_errors = Vec::with_capacity(2 * s_exact.len());
        for (&(i, j), x) in &s_exact {
            let (f, e) = rounded(x).ok_or("an entry of the Hessian is beyond the double range")?;
            p[(j.max(i), j.min(i))] = choice.sign * f;
            s_errors.push(e);
            if i != j {
                s_errors.push(e);
            }
        }
        let s_error = norm_up(s_errors.into_iter());
        let rank = choice.rank;
        // G rounded, with each column's rounding bound; the bounds below are
        // taken with the columns scaled to unit size (D = diag |g_j|), so
        // that rescaling a Casimir (which scales its column and the
        // matching row and column of K') leaves them unchanged:
        // || |G| |K'| |G|^T || <= ||G D^-1||_F^2 ||D K' D||_F.
        let mut g = DMatrix::<f64>::zeros(n, r);
        let mut col_errors = vec![Vec::new(); r];
        for (j, c) in conserved.iter().enumerate() {
            for (i, x) in c.gradient_at(mu) {
                let (f, e) = rounded(&x).ok_or("a conserved gradient is beyond the double range")?;
                g[(i, j)] = f;
                col_errors[j].push(e);
            }
        }
        // d_j: an upper bound on |g_j| (a zero gradient keeps the scale 1:
        // its column adds nothing), so |g_j| / d_j <= 1.
        let d: Vec<f64> =
            (0..r).map(|j| norm_up(g.column(j).iter().copied())).map(|x| if x > 0.0 { x } else { 1.0 }).collect();
        if d.iter().any(|x| !x.is_finite()) {
            return Err("a conserved gradient is not finite in double precision".into());
        }
        // ||G D^-1||_F <= sqrt r, and ||E_G D^-1||_F, rounded upwards.
        let g_hat = (r as f64).sqrt() * (1.0 + 4.0 * U);
        let e_hat = norm_up((0..r).map(|j| norm_up(col_errors[j].iter().copied()) / d[j] * (1.0 + 2.0 * U)));
        if rank > 0 {
            let mut vs = DMatrix::<f64>::zeros(r, rank);
            for i in 0..rank {
                let s = choice.singular_values[i];
                for a in 0..r {
                    vs[(a, i)] = choice.v[(a, i)] / s;
                }
            }
            let mut kp = numerics::dense::product(&vs, &numerics::dense::product(choice.k, &vs.transpose()));
            mirror(&mut kp);
            if kp.iter().any(|x| !x.is_finite()) {
                return Err("the Casimir Hessian is not finite in the gradients' coordinates".into());
            }
            let t = numerics::dense::product(&g, &numerics::dense::product(&kp, &g.transpose()));
            // ||D K' D||_F: each entry two products (relative error 2u)
            let k_hat =
                norm_up((0..r).flat_map(|a| (0..r).map(move |b| (a, b))).map(|(a, b)| d[a] * kp[(a, b)] * d[b]))
                    * (1.0 + 4.0 * U);
            for j in 0..n {
                for i in j..n {
                    p[(i, j)] += t[(i, j)];
                }
            }
            mirror(&mut p);
            // |G* K' G*^T - fl(G_f K' G_f^T)|: the rounding of G, then the two
            // products (inner dimension r each), then the sum with s S_f.
            // Plus, per entry, 2r + 4 operations' worth of underflow, the
            // inner product's carried through the outer one: an underflowed
            // (K' G^T)_aj is multiplied by g_ia, and sum_a |g_ia| <= sum_j
            // d_j, so the underflow is charged times 1 + sum_j d_j.
            let amplify = (1.0 + d.iter().sum::<f64>()) * (1.0 + 4.0 * (r as f64 + 1.0) * U);
            let t_error = k_hat * (2.0 * g_hat * e_hat + e_hat * e_hat + gamma(2 * r + 2) * g_hat * g_hat)
                + ((2 * r + 4) * n) as f64 * f64::MIN_POSITIVE * amplify;
            let p_norm = frobenius_up(&p);
            let p_radius = (s_error + t_error + U * p_norm) * (1.0 + 1e-6);
            return Self::finish(system, p, p_radius, p_norm, multipliers);
        }
        mirror(&mut p);
        let p_norm = frobenius_up(&p);
        let p_radius = (s_error + U * p_norm) * (1.0 + 1e-6);
        Self::finish(system, p, p_radius, p_norm, multipliers)
    }

    fn finish(
        system: &LargeSystem,
        p: DMatrix<f64>,
        p_radius: f64,
        p_norm: f64,
        multipliers: Vec<Rational>,
    ) -> Result<VerifiedPencil, String> {
        let n = system.dim();
        if p.iter().any(|x| !x.is_finite()) || !p_radius.is_finite() {
            return Err("the form is not finite in double precision".into());
        }
        let algebra = system.algebra();
        let mut q = DMatrix::<f64>::zeros(n, n);
        // inner: the longest inner product of one product; accumulated: how
        // many terms each entry of Q_f sums over all noise fields.
        let (mut q_gain, mut q_error, mut inner, mut accumulated) = (0.0f64, 0.0f64, 0usize, 0usize);
        let mut magnitudes = 0.0f64;
        for sigma in system.noise() {
            // B (row b, column k) += c^k_{a b} sigma_a, exactly.
            let mut b_exact = Exact::new();
            for (ai, s) in sigma.iter().enumerate() {
                if s.is_zero() {
                    continue;
                }
                for &b in algebra.partners(ai) {
                    for (k, c) in algebra.bracket(ai, b) {
                        *b_exact.entry((b, *k)).or_insert_with(Rational::zero) += c * s;
                    }
                }
            }
            b_exact.retain(|_, v| !v.is_zero());
            if b_exact.is_empty() {
                continue;
            }
            let b2_exact = sparse_product(&b_exact, &b_exact);
            let b = round_matrix(&b_exact, n).ok_or("a noise operator is beyond the double range")?;
            let b2 = round_matrix(&b2_exact, n).ok_or("a noise operator is beyond the double range")?;
            // sym(P B^2): column c0 of P B^2 gains v P[:, r0] for each entry
            // (r0, c0, v) of B^2; half of it goes to column c0 of Q and, P
            // being symmetric, half to row c0.
            for &(r0, c0, v) in &b2.entries {
                let half = 0.5 * v;
                for i in 0..n {
                    let t = half * p[(i, r0)];
                    q[(i, c0)] += t;
                    q[(c0, i)] += t;
                }
            }
            // B^T P B: M = P B lives in the columns that hold entries of B;
            // then (B^T M)[x, y] gains B[u][x] M[u, y].
            let mut columns: Vec<usize> = b.entries.iter().map(|e| e.1).collect();
            columns.sort_unstable();
            columns.dedup();
            let slot: BTreeMap<usize, usize> = columns.iter().enumerate().map(|(k, c)| (*c, k)).collect();
            let mut m = DMatrix::<f64>::zeros(n, columns.len());
            for &(r0, c0, v) in &b.entries {
                let col = p.column(r0) * v;
                let mut target = m.column_mut(slot[&c0]);
                target += col;
            }
            for &(u0, x, v) in &b.entries {
                for (k, &y) in columns.iter().enumerate() {
                    q[(x, y)] += v * m[(u0, k)];
                }
            }
            // ||Q*_i(D)|| <= (||B^2|| + ||B||^2) ||D|| with the exact B.
            let (bn, b2n) = (b.norm + b.error, b2.norm + b2.error);
            q_gain += b2n + bn * bn;
            // Q_i with the exact B against the rounded B, on P_f.
            q_error += p_norm * (b2.error + 2.0 * b.norm * b.error + b.error * b.error);
            // The formation: each product's inner length is a column count.
            // each term of Q_f: one product, or a product with an entry of M
            // (itself a sum of at most column_count terms)
            inner = inner.max(b.column_count + 2);
            accumulated += 2 * b2.column_count + b.column_count;
            magnitudes += p_norm * (b2.norm + b.norm * b.norm);
        }
        // Q_f is symmetric up to the order of its sums: keep its lower
        // triangle (each entry's bound holds for either order).
        mirror(&mut q);
        let q_norm = frobenius_up(&q);
        // Each entry of Q_f: products with inner length `inner`, summed in
        // `accumulated` steps, then the exact halving (subnormal results
        // are covered by the absolute term).
        let steps = inner + accumulated + 4;
        q_error += gamma(steps) * magnitudes + U * q_norm + (n * steps) as f64 * f64::MIN_POSITIVE;
        if q.iter().any(|x| !x.is_finite()) || !q_error.is_finite() {
            return Err("Q is not finite in double precision".into());
        }
        let p_definite = positive_definite(Symmetric::Dense(&p), p_radius).proved;
        Ok(VerifiedPencil { p, p_radius, p_norm, q, q_gain, q_error: q_error * (1.0 + 1e-6), multipliers, p_definite })
    }

    /// Whether `P* ≻ 0` was proved.
    pub fn form_is_definite(&self) -> bool {
        self.p_definite
    }

    /// Whether `P* ≻ 0` and `bar P* - Q* ≻ 0` are proved (module docs).
    pub fn proves(&self, bar: f64) -> bool {
        if !(self.p_definite && bar.is_finite() && bar > 0.0) {
            return false;
        }
        let mut x = &self.p * bar - &self.q;
        mirror(&mut x);
        let x_norm = frobenius_up(&x);
        // bar (P* - P_f), Q*(P* - P_f), Q*(P_f) - Q_f, and the rounding of
        // bar P_f - Q_f (the product and the difference).
        let radius = (bar * self.p_radius
            + self.q_gain * self.p_radius
            + self.q_error
            + 2.0 * U * (bar * self.p_norm + x_norm)
            + (4 * self.p.nrows()) as f64 * f64::MIN_POSITIVE)
            * (1.0 + 1e-6);
        radius.is_finite() && positive_definite(Symmetric::Dense(&x), radius).proved
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_bounds_are_exact_errors() {
        // 1/3 is not a double: the bound is the exact distance, about u/3.
        let (f, e) = rounded(&Rational::new_small(1, 3)).unwrap();
        assert_eq!(f, 1.0 / 3.0);
        assert!(e > 0.0 && e < 1e-16);
        // 3/4 is a double: no error.
        assert_eq!(rounded(&Rational::new_small(3, 4)), Some((0.75, 0.0)));
    }
}
