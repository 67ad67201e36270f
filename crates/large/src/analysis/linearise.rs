//! Step 4: the linearisation `A` and the noise operators `B_i` as sparse
//! matrices, the Itô drift `A~ = A + 1/2 sum B_i^2`, and
//! `Q(P) = sym(P A~ + A~^T P + sum_i B_i^T P B_i)` in `O(nnz n)`.

use super::multipliers::Derivatives;
use crate::algebra::SparseAlgebra;
use crate::system::LargeSystem;
use exact::Rational;
use nalgebra::DMatrix;
use std::collections::BTreeMap;

/// A sparse matrix as a map of its nonzero entries.
#[derive(Clone, Debug, Default)]
pub(super) struct Sparse {
    pub(super) entries: BTreeMap<(usize, usize), f64>,
}

impl Sparse {
    fn add(&mut self, r: usize, c: usize, v: f64) {
        if v != 0.0 {
            *self.entries.entry((r, c)).or_insert(0.0) += v;
        }
    }

    fn rows(&self, n: usize) -> Vec<Vec<(usize, f64)>> {
        let mut rows = vec![Vec::new(); n];
        for (&(r, c), &v) in &self.entries {
            rows[r].push((c, v));
        }
        rows
    }

    /// `self * other`.
    fn mul(&self, other: &Sparse, n: usize) -> Sparse {
        let rows = other.rows(n);
        let mut out = Sparse::default();
        for (&(r, m), &v) in &self.entries {
            for &(c, w) in &rows[m] {
                out.add(r, c, v * w);
            }
        }
        out
    }

    pub(super) fn dense(&self, n: usize) -> DMatrix<f64> {
        let mut d = DMatrix::zeros(n, n);
        for (&(r, c), &v) in &self.entries {
            d[(r, c)] += v;
        }
        d
    }
}

/// `sym(P A~ + A~^T P + sum_i B_i^T P B_i)` for symmetric `P`, with sparse
/// `A~` and `B_i`.
pub(super) fn generator_form(p: &DMatrix<f64>, a_tilde: &Sparse, noise: &[Sparse]) -> DMatrix<f64> {
    let n = p.nrows();
    // P A~: column c gains v P[:, r] for each entry (r, c, v).
    let mut pa = DMatrix::zeros(n, n);
    for (&(r, c), &v) in &a_tilde.entries {
        let col = p.column(r) * v;
        let mut target = pa.column_mut(c);
        target += col;
    }
    let mut q = &pa + pa.transpose();
    for b in noise {
        // (B^T P B)_xy = sum over entries (u, x, b1), (v, y, b2) of b1 b2 P_uv.
        let list: Vec<(usize, usize, f64)> = b.entries.iter().map(|(&(u, x), &v)| (u, x, v)).collect();
        for &(u, x, b1) in &list {
            for &(v, y, b2) in &list {
                q[(x, y)] += b1 * b2 * p[(u, v)];
            }
        }
    }
    (&q + q.transpose()) * 0.5
}

/// The linearised SDE `dx = A x dt + sum_i B_i x o dW^i`, sparse.
pub(super) struct Linearisation {
    /// The drift `A`.
    pub(super) a: Sparse,
    /// The noise operators `B_i = ad*_{sigma_i}`.
    pub(super) noise: Vec<Sparse>,
    /// The Itô drift `A~ = A + 1/2 sum_i B_i^2`.
    pub(super) a_tilde: Sparse,
}

impl Linearisation {
    /// `A`, the `B_i` and `A~` at the equilibrium.
    pub(super) fn new(system: &LargeSystem, d: &Derivatives) -> Linearisation {
        let n = system.dim();
        let a = drift(system.algebra(), d);
        let noise: Vec<Sparse> = system.noise().iter().map(|sigma| noise_operator(system.algebra(), sigma)).collect();
        let mut a_tilde = a.clone();
        for b in &noise {
            for (&(r0, c0), &x) in &b.mul(b, n).entries {
                a_tilde.add(r0, c0, 0.5 * x);
            }
        }
        Linearisation { a, noise, a_tilde }
    }
}

/// `A`, the Jacobian of `mu -> ad*_{Dh(mu)} mu` at the equilibrium:
/// `A_bm = sum c^k_ab (Hh_am mu_k + Dh_a delta_km)`.
fn drift(algebra: &SparseAlgebra, d: &Derivatives) -> Sparse {
    let (mu, dh, hh) = (&d.mu, &d.dh, &d.hh);
    let n = mu.len();
    let mut a = Sparse::default();
    let hh_rows = {
        let mut rows: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
        for (&(i, j), &x) in hh {
            rows[i].push((j, x));
            if i != j {
                rows[j].push((i, x));
            }
        }
        rows
    };
    for (ai, b, k, c) in algebra.entries() {
        let c = exact::rational_to_f64(c);
        // d/dmu_m of c^k_ab Dh_a(mu) mu_k = c (Hh_am mu_k + Dh_a delta_km)
        if mu[k] != 0.0 {
            for &(m, x) in &hh_rows[ai] {
                a.add(b, m, c * x * mu[k]);
            }
        }
        a.add(b, k, c * dh[ai]);
    }
    a
}

/// `B = ad*_sigma`: `B_bk = sum_a c^k_ab sigma_a`.
fn noise_operator(algebra: &SparseAlgebra, sigma: &[Rational]) -> Sparse {
    let mut bm = Sparse::default();
    for (ai, s) in sigma.iter().enumerate() {
        let s = exact::rational_to_f64(s);
        if s == 0.0 {
            continue;
        }
        for &b in algebra.partners(ai) {
            for (k, c) in algebra.bracket(ai, b) {
                bm.add(b, *k, exact::rational_to_f64(c) * s);
            }
        }
    }
    bm
}
