//! Step 3: the family of second variations over the multipliers
//! `lambda(t) = lambda_p + sum_i t_i d_i / |R_i|` (`d_i` spanning the null
//! space of `G`), and Finsler on `ker G^T`: a definite restricted Hessian
//! searched over the family, then (when `Q` does not depend on the Casimir
//! Hessian) the restricted `Sigma^2` minimised over it.

use super::linearise::{generator_form, Linearisation};
use super::multipliers::{Derivatives, Multipliers};
use super::{numerical, LargeSettings};
use crate::system::LargeSystem;
use crate::LargeError;
use nalgebra::{DMatrix, DVector};
use numerics::dense::{symmetric_eigen, symmetric_eigenvalues};
use outcome::Progress;
use std::collections::BTreeMap;

/// A Hessian stored by one entry per unordered pair (as
/// [`crate::SparsePoly::hessian_at_f64`] gives it).
type SparseHessian = BTreeMap<(usize, usize), f64>;

/// `into += scale M` for the symmetric `M` stored by one entry per
/// unordered pair.
fn add_symmetric(m: &SparseHessian, scale: f64, into: &mut DMatrix<f64>) {
    for (&(i, j), &x) in m {
        into[(i, j)] += scale * x;
        if i != j {
            into[(j, i)] += scale * x;
        }
    }
}

/// `[D^2h +] sum_j w_j D^2C_j`, dense `n x n` (`D^2h` when `with_h`).
fn combination(
    n: usize,
    hh: &SparseHessian,
    hessians: &[SparseHessian],
    w: &DVector<f64>,
    with_h: bool,
) -> DMatrix<f64> {
    let mut m = DMatrix::zeros(n, n);
    if with_h {
        add_symmetric(hh, 1.0, &mut m);
    }
    for (j, hj) in hessians.iter().enumerate() {
        if w[j] != 0.0 {
            add_symmetric(hj, w[j], &mut m);
        }
    }
    m
}

/// The second variations `B(t) = B_0 + sum_i t_i B_i / |R_i|` of the
/// multiplier family, and their restrictions `R = Z^T B Z` to `ker G^T`.
pub(super) struct Family {
    /// `B_0 = D^2h + sum_j lambda_p,j D^2C_j`.
    base0: DMatrix<f64>,
    /// `U^T B_0 U`.
    base0_frame: DMatrix<f64>,
    /// `R_0 = Z^T B_0 Z`.
    r0: DMatrix<f64>,
    /// The directions `d_i`: the right singular vectors of `G` past its rank.
    directions: Vec<DVector<f64>>,
    /// `B_i = sum_j d_ij D^2C_j`.
    dir_hessians: Vec<DMatrix<f64>>,
    /// `R_i = Z^T B_i Z`.
    dir_restricted: Vec<DMatrix<f64>>,
    /// `|R_i|_F` (at least the smallest positive double): `t_i` counts in
    /// these units, so that every direction moves `R` alike.
    dir_scales: Vec<f64>,
}

/// The outcome of the search for a definite restricted Hessian.
pub(super) struct Definite {
    /// `+1` or `-1` for a definite form, 0 for none.
    pub(super) sign: f64,
    /// The larger of the two relative margins found.
    pub(super) margin: f64,
    /// The point of the family found for that sign.
    pub(super) t: Vec<f64>,
}

/// The second variation at the chosen point of the family.
pub(super) struct ChosenForm {
    /// `B(t)`.
    pub(super) base: DMatrix<f64>,
    /// `U^T B(t) U`.
    pub(super) base_frame: DMatrix<f64>,
    /// `lambda(t)`.
    pub(super) lambda: DVector<f64>,
    /// The smallest eigenvalue of `s R(t)`.
    pub(super) lo: f64,
    /// The largest magnitude of an eigenvalue of `s R(t)`.
    pub(super) hi: f64,
}

impl Family {
    /// The family through the particular multipliers `lambda_p` along the null
    /// space of `G`, with each matrix formed once.
    pub(super) fn new(system: &LargeSystem, d: &Derivatives, m: &Multipliers) -> Family {
        let (n, r) = d.g.shape();
        let hessians: Vec<SparseHessian> = system.conserved().iter().map(|k| k.hessian_at_f64(&d.mu)).collect();
        let base0 = combination(n, &d.hh, &hessians, &m.lambda, true);
        let base0_frame = m.frame_coordinates(&base0);
        let r0 = m.blocks(&base0_frame).0;
        let directions: Vec<DVector<f64>> = (m.rank..r).map(|j| m.v.column(j).into_owned()).collect();
        let dir_hessians: Vec<DMatrix<f64>> =
            directions.iter().map(|w| combination(n, &d.hh, &hessians, w, false)).collect();
        let dir_restricted: Vec<DMatrix<f64>> = dir_hessians.iter().map(|b| m.restrict(b)).collect();
        let dir_scales: Vec<f64> = dir_restricted.iter().map(|m| m.norm().max(f64::MIN_POSITIVE)).collect();
        Family { base0, base0_frame, r0, directions, dir_hessians, dir_restricted, dir_scales }
    }

    /// The number of free directions, `r - rank G`.
    pub(super) fn dimension(&self) -> usize {
        self.directions.len()
    }

    /// `R(t) = R_0 + sum_i t_i R_i / |R_i|`.
    fn restricted_at(&self, t: &[f64]) -> DMatrix<f64> {
        let mut m = self.r0.clone();
        for ((ti, ri), sc) in t.iter().zip(&self.dir_restricted).zip(&self.dir_scales) {
            m += ri * (*ti / sc);
        }
        m
    }

    /// The smallest eigenvalue of `s R(t)`, its relative margin and a supergradient.
    fn margin_at(&self, t: &[f64], s: f64) -> (f64, f64, Vec<f64>) {
        let m = self.restricted_at(t) * s;
        match symmetric_eigen(&m) {
            Some((values, vecs)) if !values.is_empty() => {
                let top = values.iter().fold(0.0f64, |a, x| a.max(x.abs()));
                let u = vecs.column(0);
                let grad = self
                    .dir_restricted
                    .iter()
                    .zip(&self.dir_scales)
                    .map(|(ri, sc)| s * (u.transpose() * ri * u)[(0, 0)] / sc)
                    .collect();
                (values[0], if top > 0.0 { values[0] / top } else { 0.0 }, grad)
            }
            Some(_) => (1.0, 1.0, vec![0.0; t.len()]),
            None => (f64::NEG_INFINITY, f64::NEG_INFINITY, vec![0.0; t.len()]),
        }
    }

    /// The point of the family and the relative margin of the best
    /// `lambda_min(s R(t))` found for the sign `s`.
    fn search(&self, s: f64, settings: &LargeSettings, progress: &Progress) -> (Vec<f64>, f64) {
        let f = self.dimension();
        // Maximise the concave lambda_min(s R(t)) by the ellipsoid method in a
        // ball grown by 100 while the maximiser sits on its edge (as the exact
        // engine's search does, casimir::search).
        let (_, rel0, _) = self.margin_at(&vec![0.0; f], s);
        let mut best = (vec![0.0; f], rel0);
        if f == 0 {
            return best;
        }
        let mut best_value = f64::NEG_INFINITY;
        let mut radius = 4.0 * self.r0.norm().max(1.0);
        for _ in 0..5 {
            let mut e = casimir::Ellipsoid::ball(&vec![0.0; f], radius);
            for _ in 0..(60 * f).max(60) {
                if progress.is_cancelled() {
                    break;
                }
                let c = e.centre().to_vec();
                let norm = c.iter().map(|x| x * x).sum::<f64>().sqrt();
                let g: Vec<f64> = if norm > radius {
                    c.iter().map(|x| -x / norm).collect()
                } else {
                    let (value, rel, g) = self.margin_at(&c, s);
                    if value > best_value {
                        best_value = value;
                        best = (c.clone(), rel);
                    }
                    g
                };
                if !e.cut(&g) || e.size() < 1e-12 * radius {
                    break;
                }
            }
            let norm = best.0.iter().map(|x| x * x).sum::<f64>().sqrt();
            if best.1 > settings.definiteness_tolerance || norm < 0.5 * radius {
                break;
            }
            radius *= 100.0;
        }
        best
    }

    /// The sign `s` for which `s R(t)` is definite above the tolerance
    /// somewhere on the family (positive tried first), and where.
    pub(super) fn definite_form(&self, settings: &LargeSettings, progress: &Progress) -> Definite {
        let f = self.dimension();
        let (t_plus, plus) = self.search(1.0, settings, progress);
        let (t_minus, minus) = if plus > settings.definiteness_tolerance {
            (vec![0.0; f], f64::NEG_INFINITY)
        } else {
            self.search(-1.0, settings, progress)
        };
        let margin = plus.max(minus);
        let sign = if plus > settings.definiteness_tolerance {
            1.0
        } else if minus > settings.definiteness_tolerance {
            -1.0
        } else {
            0.0
        };
        let t = if sign > 0.0 { t_plus } else { t_minus };
        Definite { sign, margin, t }
    }

    /// `B(t) = B_0 + sum_i t_i B_i / |R_i|`.
    fn base_at(&self, t: &[f64]) -> DMatrix<f64> {
        let mut b = self.base0.clone();
        for ((ti, bi), sc) in t.iter().zip(&self.dir_hessians).zip(&self.dir_scales) {
            b += bi * (*ti / sc);
        }
        b
    }

    /// `B(t)` in both coordinates, `lambda(t)`, and the extreme eigenvalues of
    /// the restricted `s R(t)` (an error when they cannot be computed).
    pub(super) fn chosen(self, m: &Multipliers, sign: f64, t: &[f64]) -> Result<ChosenForm, LargeError> {
        let base = self.base_at(t);
        let base_frame = if t.iter().all(|x| *x == 0.0) { self.base0_frame } else { m.frame_coordinates(&base) };
        let lambda: DVector<f64> = self
            .directions
            .iter()
            .zip(t)
            .zip(&self.dir_scales)
            .fold(m.lambda.clone(), |acc, ((d, ti), sc)| acc + d * (*ti / sc));
        let restricted = m.blocks(&base_frame).0;
        let eig = symmetric_eigenvalues(&(&restricted * sign))
            .ok_or_else(|| numerical("the restricted Hessian's eigenvalues"))?;
        let (lo, hi) = eig.iter().fold((f64::INFINITY, 0.0f64), |(l, h), &x| (l.min(x), h.max(x.abs())));
        Ok(ChosenForm { base, base_frame, lambda, lo, hi })
    }
}

/// The restricted pencil `(Z^T sP(t) Z, Z^T sQ(t) Z)` at `K = 0`, affine in `t`.
pub(super) struct RestrictedPencil<'a> {
    /// `R_0`, scaled by the sign at each point.
    r0: &'a DMatrix<f64>,
    /// `s`.
    sign: f64,
    /// `Z^T Q(s B_0) Z`.
    q0: DMatrix<f64>,
    /// `s R_i / |R_i|`.
    p_dirs: Vec<DMatrix<f64>>,
    /// `Z^T Q(s B_i / |R_i|) Z`.
    q_dirs: Vec<DMatrix<f64>>,
}

impl<'a> RestrictedPencil<'a> {
    /// The pencil's constant part and directions (`Q` is linear in `P`).
    pub(super) fn new(family: &'a Family, m: &Multipliers, lin: &Linearisation, sign: f64) -> RestrictedPencil<'a> {
        let q_dirs: Vec<DMatrix<f64>> = family
            .dir_hessians
            .iter()
            .zip(&family.dir_scales)
            .map(|(bi, sc)| m.restrict(&generator_form(&(bi * (sign / sc)), &lin.a_tilde, &lin.noise)))
            .collect();
        let p_dirs: Vec<DMatrix<f64>> =
            family.dir_restricted.iter().zip(&family.dir_scales).map(|(ri, sc)| ri * (sign / sc)).collect();
        let q0 = m.restrict(&generator_form(&(&family.base0 * sign), &lin.a_tilde, &lin.noise));
        RestrictedPencil { r0: &family.r0, sign, q0, p_dirs, q_dirs }
    }

    /// `(P(t), Q(t))`.
    fn at(&self, t: &[f64]) -> (DMatrix<f64>, DMatrix<f64>) {
        let mut p = self.r0 * self.sign;
        let mut q = self.q0.clone();
        for (i, ti) in t.iter().enumerate() {
            p += &self.p_dirs[i] * *ti;
            q += &self.q_dirs[i] * *ti;
        }
        (p, q)
    }

    /// The ellipsoid cut at `c`: `a_i = S v^T P_i v - v^T Q_i v` where `P(c)`
    /// is definite (`S = lambda_max(Q, P)`, kept in `best` when lower), the
    /// feasibility cut `u^T P_i u` elsewhere.
    fn cut(&self, c: &[f64], best: &mut (Vec<f64>, f64)) -> Vec<f64> {
        let f = self.p_dirs.len();
        let (p, q) = self.at(c);
        let quad = |m: &DMatrix<f64>, v: &DVector<f64>| (v.transpose() * m * v)[(0, 0)];
        match numerics::dense::top_generalized(&p, &q) {
            Ok((l, v)) => {
                if l < best.1 {
                    *best = (c.to_vec(), l);
                }
                (0..f).map(|i| l * quad(&self.p_dirs[i], &v) - quad(&self.q_dirs[i], &v)).collect()
            }
            Err(u) => (0..f).map(|i| quad(&self.p_dirs[i], &u)).collect(),
        }
    }
}

/// The point of the family, from `start`, with the least restricted
/// `lambda_max(Z^T sQ Z, Z^T sP Z)` found (the infimum of `Sigma^2` over `K`).
pub(super) fn minimise_sigma2(pencil: &RestrictedPencil, start: Vec<f64>, progress: &Progress) -> Vec<f64> {
    // Minimise the quasi-convex restricted lambda_max(Z^T sQ Z, Z^T sP Z)
    // over t (its infimum over K at t), by the ellipsoid method with the
    // cut a_i = S v^T P_i v - v^T Q_i v at a definite centre and the
    // feasibility cut u^T P_i u elsewhere (the exact engine's optimiser).
    let f = pencil.p_dirs.len();
    let value = |t: &[f64]| {
        let (p, q) = pencil.at(t);
        numerics::dense::top_generalized(&p, &q).ok().map(|(l, _)| l)
    };
    let mut best = (start.clone(), value(&start).unwrap_or(f64::INFINITY));
    let mut centre = start.clone();
    let mut radius = 10.0 * (1.0 + start.iter().map(|x| x * x).sum::<f64>().sqrt());
    for _ in 0..6 {
        let mut e = casimir::Ellipsoid::ball(&centre, radius);
        for _ in 0..(60 * f).max(60) {
            if progress.is_cancelled() {
                break;
            }
            let c = e.centre().to_vec();
            let dist = c.iter().zip(&centre).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt();
            let g: Vec<f64> = if dist > radius {
                c.iter().zip(&centre).map(|(x, y)| y - x).collect()
            } else {
                pencil.cut(&c, &mut best)
            };
            if !e.cut(&g) || e.size() < 1e-13 * (radius + 1.0) {
                break;
            }
        }
        let dist = best.0.iter().zip(&centre).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt();
        if dist <= 0.9 * radius || best.1 <= 0.0 {
            break;
        }
        centre = best.0.clone();
        radius *= 10.0;
    }
    best.0
}
