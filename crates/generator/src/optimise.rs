//! The best Casimir choice: minimise `Sigma^2 = lambda_max(Q, P)` over the
//! free multipliers `t` and the Casimir Hessian `M`.
//!
//! `P(theta)` is affine in `theta = (t, K)` (with `M = E K E^T` on a set of
//! independent conserved quantities, so `G M G^T = Y K Y^T`) and
//! `Q(theta) = L(P(theta))` with the linear map
//! `L(P) = P A~ + A~^T P + sum_i B_i^T P B_i`. On `{theta : sP(theta) ≻ 0}`,
//! `g(theta) = lambda_max(sQ, sP)` is quasi-convex (its sublevel sets
//! `{S sP - sQ ⪰ 0}` are convex), so the ellipsoid method with the cut
//! `v^T (g(c) sP(theta) - sQ(theta)) v >= 0` (`v` the top generalized
//! eigenvector at the centre `c`) converges to the global minimum; a centre
//! where `sP` is not definite gets the feasibility cut `u^T sP(theta) u > 0`.
//! One dimension is plain bisection.
//!
//! When every conserved quantity also commutes with the noise (and with the
//! drift, which conserves it), `L(Y K Y^T) = 0`: `Q` does not depend on `K`,
//! growing `K` only increases `P` on the range of `G`, and `Sigma^2(K)` is
//! non-increasing. The infimum over `K` is then the restricted problem on
//! `ker G^T`, `lambda_max(Z^T sQ Z, Z^T sP Z)`, minimised over `t` alone; a
//! finite `K` attains it or approaches it within the tolerance, and the
//! certificate says which.

use crate::form::generator_form;
use crate::growth::{growth_constant, GrowthConstant};
use crate::linearise::Linearisation;
use casimir::{CasimirChoice, Ellipsoid, SecondVariation};
use exact::{Matrix, Rational};
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use num_traits::Zero;

/// Settings of the optimisation, with documented defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct OptimiseSettings {
    /// Tolerance on `Sigma^2` between the certified value and the infimum
    /// over the freedom when the infimum is only approached as `M` grows,
    /// relative to the larger of the infimum and the first definite
    /// choice's constant. Default `1e-6`: closing the gap costs a
    /// conditioning of `P` of about `1/tolerance`, and floating point must
    /// still resolve it.
    pub tolerance: f64,
    /// Iterations of the ellipsoid method. Default 3000.
    pub max_iterations: usize,
}

impl Default for OptimiseSettings {
    fn default() -> Self {
        OptimiseSettings { tolerance: 1e-6, max_iterations: 3000 }
    }
}

/// The optimised choice and what is known about the infimum.
#[derive(Clone, Debug)]
pub struct Optimum {
    /// The choice (rational multipliers and `M`, exact `P`).
    pub choice: CasimirChoice,
    /// `Q` etc. for this choice.
    pub growth: GrowthConstant,
    /// The floating-point infimum of `max(0, lambda_max)` over the freedom.
    pub infimum: f64,
    /// A certified rational lower bound on `Sigma^2` for every choice in the
    /// family (when it can be proved: no free multipliers and `Q`
    /// independent of `M`).
    pub infimum_lower_bound: Option<Rational>,
    /// The vector `x` of `ker G^T` proving it: the bound is
    /// `max(0, x^T sQ x / x^T sP x)`, the same for every `M`.
    pub infimum_witness: Option<Vec<Rational>>,
    /// Whether the choice attains the infimum (to round-off) rather than
    /// approaching it within the tolerance.
    pub attained: bool,
    /// Whether the certified value is within the tolerance of the infimum
    /// (false when reaching it would make `P` too ill-conditioned).
    pub within_tolerance: bool,
    /// Whether `Q` depends on `M` (a conserved quantity that the noise does
    /// not conserve).
    pub q_depends_on_m: bool,
    /// How the optimum was found.
    pub method: &'static str,
}

fn sym_eigen(m: DMatrix<f64>) -> Option<SymmetricEigen<f64, nalgebra::Dyn>> {
    if m.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let n = m.nrows();
    SymmetricEigen::try_new(m, f64::EPSILON, 1000 * (n + 1))
}

/// `lambda_max(Q, P)` with its `P`-normalised eigenvector, or `None` when
/// `P` is not numerically positive definite (then the eigenvector of
/// `lambda_min(P)` is returned as the second member for a feasibility cut).
fn top_generalized(p: &DMatrix<f64>, q: &DMatrix<f64>) -> Result<(f64, DVector<f64>), DVector<f64>> {
    let n = p.nrows();
    if let Some(chol) = p.clone().cholesky() {
        let l = chol.l();
        if let Some(lq) = l.solve_lower_triangular(q) {
            if let Some(ct) = l.solve_lower_triangular(&lq.transpose()) {
                let c = (&ct + ct.transpose()) * 0.5;
                if let Some(eig) = sym_eigen(c) {
                    let imax = (0..n).max_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j])).unwrap_or(0);
                    let w = eig.eigenvectors.column(imax).into_owned();
                    if let Some(v) = l.transpose().solve_upper_triangular(&w) {
                        return Ok((eig.eigenvalues[imax], v));
                    }
                }
            }
        }
    }
    let u = sym_eigen(p.clone())
        .map(|e| {
            let imin = (0..n).min_by(|&i, &j| e.eigenvalues[i].total_cmp(&e.eigenvalues[j])).unwrap_or(0);
            e.eigenvectors.column(imin).into_owned()
        })
        .unwrap_or_else(|| DVector::zeros(n));
    Err(u)
}

/// An affine pencil `(P(theta), Q(theta))` in floating point, already
/// multiplied by the sign of `P`.
struct AffinePencil {
    p0: DMatrix<f64>,
    q0: DMatrix<f64>,
    p_dirs: Vec<DMatrix<f64>>,
    q_dirs: Vec<DMatrix<f64>>,
}

enum Cut {
    /// Infeasible centre: keep `{theta : a . (theta - c) >= 0}`.
    Feasibility(Vec<f64>),
    /// Objective value at the centre and the cut direction.
    Objective(f64, Vec<f64>),
}

impl AffinePencil {
    fn at(&self, theta: &[f64]) -> (DMatrix<f64>, DMatrix<f64>) {
        let mut p = self.p0.clone();
        let mut q = self.q0.clone();
        for (i, x) in theta.iter().enumerate() {
            p += &self.p_dirs[i] * *x;
            q += &self.q_dirs[i] * *x;
        }
        (p, q)
    }

    fn value(&self, theta: &[f64]) -> Option<f64> {
        let (p, q) = self.at(theta);
        top_generalized(&p, &q).ok().map(|(l, _)| l)
    }

    fn cut(&self, theta: &[f64]) -> Cut {
        let (p, q) = self.at(theta);
        let quad = |m: &DMatrix<f64>, v: &DVector<f64>| (v.transpose() * m * v)[(0, 0)];
        match top_generalized(&p, &q) {
            Ok((s, v)) => {
                let a =
                    (0..self.p_dirs.len()).map(|i| s * quad(&self.p_dirs[i], &v) - quad(&self.q_dirs[i], &v)).collect();
                Cut::Objective(s, a)
            }
            Err(u) => Cut::Feasibility((0..self.p_dirs.len()).map(|i| quad(&self.p_dirs[i], &u)).collect()),
        }
    }

    /// Minimise `lambda_max` by the ellipsoid method (bisection in one
    /// dimension) over the ball of the given radius around `start`.
    fn minimise(&self, start: &[f64], radius: f64, iterations: usize) -> (Vec<f64>, f64) {
        let d = start.len();
        let mut best_theta = start.to_vec();
        let mut best = self.value(start).unwrap_or(f64::INFINITY);
        if d == 0 {
            return (best_theta, best);
        }
        let mut ellipsoid = Ellipsoid::ball(start, radius);
        for _ in 0..iterations {
            let c = ellipsoid.centre().to_vec();
            let dist = c.iter().zip(start).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt();
            // Keep {x : g . (x - c) >= 0}.
            let g: Vec<f64> = if dist > radius {
                c.iter().zip(start).map(|(x, y)| y - x).collect()
            } else {
                match self.cut(&c) {
                    Cut::Feasibility(a) => a,
                    Cut::Objective(s, a) => {
                        if s < best {
                            best = s;
                            best_theta = c.clone();
                        }
                        if s <= 0.0 {
                            break; // Sigma^2 is floored at 0: nothing to gain
                        }
                        a
                    }
                }
            };
            if !ellipsoid.cut(&g) || ellipsoid.size() < 1e-14 * (radius + 1.0) {
                break;
            }
        }
        (best_theta, best)
    }
}

/// Largest denominator of the simple rationals tried for the optimised
/// multipliers (the search's default `max_denominator`).
const SIMPLE_DENOMINATOR: u64 = 1_000_000;

fn signed(m: &Matrix, sign: i8) -> DMatrix<f64> {
    m.to_dmatrix() * (sign as f64)
}

/// The exact choice at rational parameters `t` and rational `K` (on the
/// independent conserved gradients), if `P` is exactly definite.
fn exact_choice(
    variation: &SecondVariation,
    sign: i8,
    t: Vec<Rational>,
    k: &Matrix,
    relative_margin: f64,
) -> Option<CasimirChoice> {
    let multipliers = variation.family.at(&t);
    let m = variation.m_from_k(k);
    let p = variation.second_variation(&multipliers, &m);
    p.is_definite_with_sign(sign).then_some(CasimirChoice {
        sign,
        family_parameters: t,
        multipliers,
        m,
        p,
        relative_margin,
    })
}

/// Scales that make the directions of an affine pencil comparable and
/// independent of how the user wrote the conserved quantities and the
/// algebra's basis: the size of each direction in the metric of the
/// starting `P` (`|L^{-1} dP L^{-T}|_F`, congruence-invariant), plus its
/// `Q` part relative to the starting `Q`.
fn direction_scales(
    p_start: &DMatrix<f64>,
    q_start: &DMatrix<f64>,
    p_dirs: &[DMatrix<f64>],
    q_dirs: &[DMatrix<f64>],
) -> Vec<f64> {
    let Some(l_inv) = p_start.clone().cholesky().and_then(|c| c.l().try_inverse()) else {
        return vec![1.0; p_dirs.len()];
    };
    let size = |m: &DMatrix<f64>| (&l_inv * m * l_inv.transpose()).norm();
    let q_size = size(q_start).max(f64::MIN_POSITIVE);
    p_dirs
        .iter()
        .zip(q_dirs)
        .map(|(dp, dq)| {
            let s = size(dp) + size(dq) / q_size;
            if s.is_finite() && s > 0.0 {
                s
            } else {
                1.0
            }
        })
        .collect()
}

/// Minimise the pencil over `theta = start + u / scales` with `u` in balls
/// of radius 10, 100, ... (grown while the minimiser sits on the edge).
fn minimise_normalised(
    pencil: &AffinePencil,
    start: &[f64],
    scales: &[f64],
    iterations: usize,
) -> (Vec<f64>, f64, bool) {
    let d = start.len();
    let normalised = AffinePencil {
        p0: pencil.at(start).0,
        q0: pencil.at(start).1,
        p_dirs: pencil.p_dirs.iter().zip(scales).map(|(m, s)| m / *s).collect(),
        q_dirs: pencil.q_dirs.iter().zip(scales).map(|(m, s)| m / *s).collect(),
    };
    let mut centre = vec![0.0; d];
    let mut best = (centre.clone(), normalised.value(&centre).unwrap_or(f64::INFINITY));
    let mut radius = 10.0;
    let mut on_boundary = false;
    for _ in 0..6 {
        let (u, v) = normalised.minimise(&centre, radius, iterations);
        if v < best.1 {
            best = (u.clone(), v);
        }
        let dist = u.iter().zip(&centre).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt();
        on_boundary = dist > 0.9 * radius;
        if !on_boundary || v <= 0.0 {
            break;
        }
        centre = u;
        radius *= 10.0;
    }
    let theta = start.iter().zip(&best.0).zip(scales).map(|((x, u), s)| x + u / s).collect();
    (theta, best.1, on_boundary)
}

/// The positive part of a symmetric matrix (its negative eigenvalues set to 0).
fn positive_part(m: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    if m.nrows() == 0 {
        return Some(m.clone()); // nalgebra's eigen-solver panics on an empty matrix
    }
    let e = sym_eigen((m + m.transpose()) * 0.5)?;
    let d = DMatrix::from_diagonal(&e.eigenvalues.map(|x| x.max(0.0)));
    Some(&e.eigenvectors * d * e.eigenvectors.transpose())
}

/// The pair `(sP, sQ)` in the frame `T = [Z W]` at fixed multipliers, when
/// `Q` does not depend on `K`: `sP = [[Pz, Pzw], [Pzw^T, Pw + K']]` with
/// `K' = sK`, `sQ = [[Qz, Qzw], [Qzw^T, Qw]]`.
struct FramePencil {
    pz: DMatrix<f64>,
    pzw: DMatrix<f64>,
    pw: DMatrix<f64>,
    qz: DMatrix<f64>,
    qzw: DMatrix<f64>,
    qw: DMatrix<f64>,
    /// `K0'`: `sP ≻ 0` iff `K' ≻ K0'` (the Schur bound, signed).
    k0: DMatrix<f64>,
    /// The margin `D` added along the conserved directions.
    margin: DMatrix<f64>,
}

impl FramePencil {
    /// The smallest `K'` (in the positive semidefinite order) with
    /// `S sP - sQ ⪰ 0`: by the Schur complement of the `Z` block
    /// (`X = S Pz - Qz ≻ 0` for `S` above the restricted `lambda_max`),
    /// `K1 = (Qw + C^T X^{-1} C) / S - Pw` with `C = S Pzw - Qzw`. Then
    /// `K' = K1 + (K0' - K1)_+ + D` also makes `P` definite, and adding the
    /// positive `D` to `P` never raises a positive `lambda_max` (`Q` does
    /// not depend on `K`). So `Sigma^2 <= S` up to rounding.
    fn k_for(&self, s: f64) -> Option<DMatrix<f64>> {
        if s.is_nan() || s <= 0.0 {
            return None;
        }
        let k1 = if self.pz.nrows() == 0 {
            &self.qw / s - &self.pw
        } else {
            let x = &self.pz * s - &self.qz;
            let c = &self.pzw * s - &self.qzw;
            let xc = match x.clone().cholesky() {
                Some(ch) => ch.solve(&c),
                None => {
                    // At S = lambda_max itself X is singular: the pseudo-
                    // inverse (eigenvalues below 1e-12 |X| dropped) gives the
                    // K that attains it when the top eigenvectors do not
                    // couple to the conserved directions (C^T v = 0).
                    let e = sym_eigen((&x + x.transpose()) * 0.5)?;
                    let top = e.eigenvalues.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                    if e.eigenvalues.iter().any(|&v| v < -1e-12 * top) {
                        return None;
                    }
                    let inv = e.eigenvalues.map(|v| if v > 1e-12 * top { 1.0 / v } else { 0.0 });
                    &e.eigenvectors * DMatrix::from_diagonal(&inv) * e.eigenvectors.transpose() * c.clone()
                }
            };
            (&self.qw + c.transpose() * xc) / s - &self.pw
        };
        let k = &k1 + positive_part(&(&self.k0 - &k1))? + &self.margin;
        let k = (&k + k.transpose()) * 0.5;
        k.iter().all(|x| x.is_finite()).then_some(k)
    }
}

/// Minimise `Sigma^2` over the Casimir freedom, starting from a definite
/// choice. Returns `None` only if no better-or-equal exact choice could be
/// built (then the first choice stands).
///
/// Everything the optimiser sees is invariant under rescaling a conserved
/// quantity and under a change of basis of the algebra: the multiplier
/// directions are normalised in the metric of the starting `P`, and when
/// `Q` does not depend on `M` the Casimir Hessian is not searched at all
/// but constructed ([`FramePencil::k_for`]) for a target `S` just above the
/// infimum, in the frame `[Z W]` where it is a Schur complement.
///
/// `noise_conserves_all` says that every conserved quantity Poisson-commutes
/// with every noise potential (exactly, as computed by
/// [`casimir::System::noise_commutation`]); then `Q` cannot depend on `M`
/// (the drift conserves them too), and the check of that is skipped.
pub fn optimise_choice(
    variation: &SecondVariation,
    linearisation: &Linearisation,
    first: &CasimirChoice,
    first_growth: &GrowthConstant,
    noise_conserves_all: bool,
    settings: &OptimiseSettings,
) -> Option<Optimum> {
    let sign = first.sign;
    let f = variation.family.directions.len();
    let cols = &variation.range_columns;
    let rk = cols.len();
    let lq = |p: &Matrix| generator_form(linearisation, p).q;
    // Basis of the affine structure, exactly.
    let base0 = variation.base(&variation.family.particular);
    let zero_t = vec![Rational::zero(); f];
    let t_dirs: Vec<Matrix> = (0..f)
        .map(|i| {
            let mut t = zero_t.clone();
            t[i] = Rational::from(1);
            variation.base(&variation.family.at(&t)).sub(&base0)
        })
        .collect();
    let y = variation.independent_gradients();
    let mut k_dirs: Vec<(usize, usize, Matrix)> = Vec::new();
    for a in 0..rk {
        for b in a..rk {
            let mut e = Matrix::zeros(rk, rk);
            e[(a, b)] = Rational::from(1);
            e[(b, a)] = Rational::from(1);
            k_dirs.push((a, b, y.mul(&e).mul(&y.transpose())));
        }
    }
    // L(Y K Y^T) = Y K Y^T A~ + A~^T Y K Y^T + sum B^T Y K Y^T B vanishes when
    // Y^T A = 0 (the drift conserves the quantities: always) and B^T Y = 0
    // (the noise conserves them).
    let q_depends_on_m = !noise_conserves_all && k_dirs.iter().any(|(_, _, d)| !lq(d).is_zero());
    let t0: Vec<f64> = first.family_parameters.iter().map(exact::rational_to_f64).collect();
    // K of the first choice, on the independent columns.
    let k_first = Matrix::from_fn(rk, rk, |a, b| first.m[(cols[a], cols[b])].clone());

    if !q_depends_on_m {
        return optimise_restricted(variation, &lq, first, first_growth, &t0, &t_dirs, settings);
    }

    // General case: Q depends on K. Minimise over theta = (t, K entries),
    // the directions normalised in the metric of the first P.
    let mut p_dirs: Vec<DMatrix<f64>> = t_dirs.iter().map(|d| signed(d, sign)).collect();
    let mut q_dirs: Vec<DMatrix<f64>> = t_dirs.iter().map(|d| signed(&lq(d), sign)).collect();
    for (_, _, d) in &k_dirs {
        p_dirs.push(signed(d, sign));
        q_dirs.push(signed(&lq(d), sign));
    }
    let pencil = AffinePencil { p0: signed(&base0, sign), q0: signed(&lq(&base0), sign), p_dirs, q_dirs };
    let mut theta0 = t0.clone();
    for (a, b, _) in &k_dirs {
        theta0.push(exact::rational_to_f64(&k_first[(*a, *b)]));
    }
    let (p_start, q_start) = pencil.at(&theta0);
    let scales = direction_scales(&p_start, &q_start, &pencil.p_dirs, &pencil.q_dirs);
    let (theta, value, on_boundary) = minimise_normalised(&pencil, &theta0, &scales, settings.max_iterations);
    let infimum = value.max(0.0);
    let t = casimir::round_family_parameters(variation, sign, &theta[..f], &scales[..f], SIMPLE_DENOMINATOR, None)?;
    let mut k = Matrix::zeros(rk, rk);
    for (i, (a, b, _)) in k_dirs.iter().enumerate() {
        let r = exact::decimal_near(theta[f + i], 15)?;
        k[(*a, *b)] = r.clone();
        k[(*b, *a)] = r;
    }
    let choice = exact_choice(variation, sign, t, &k, first.relative_margin)?;
    let growth = growth_constant(&choice.p, &lq(&choice.p), sign).ok()?;
    if growth.sigma2 > first_growth.sigma2 {
        return None;
    }
    Some(Optimum {
        choice,
        attained: !on_boundary,
        within_tolerance: !on_boundary,
        growth,
        infimum,
        infimum_lower_bound: None,
        infimum_witness: None,
        q_depends_on_m,
        method: "ellipsoid over (t, M)",
    })
}

/// The case where `Q` does not depend on `M`: minimise the restricted
/// `lambda_max(Z^T sQ Z, Z^T sP Z)` over the free multipliers, then
/// construct `K` for a target just above that infimum.
fn optimise_restricted(
    variation: &SecondVariation,
    lq: &dyn Fn(&Matrix) -> Matrix,
    first: &CasimirChoice,
    first_growth: &GrowthConstant,
    t0: &[f64],
    t_dirs: &[Matrix],
    settings: &OptimiseSettings,
) -> Option<Optimum> {
    let sign = first.sign;
    let f = t0.len();
    let z = &variation.kernel;
    let k = z.ncols();
    let zt = z.transpose();
    let restrict = |m: &Matrix| zt.mul(m).mul(z);
    // 1. The multipliers: the restricted infimum over t.
    let t_rational = if f == 0 || k == 0 {
        first.family_parameters.clone()
    } else {
        let base0 = variation.base(&variation.family.particular);
        let pencil = AffinePencil {
            p0: signed(&restrict(&base0), sign),
            q0: signed(&restrict(&lq(&base0)), sign),
            p_dirs: t_dirs.iter().map(|d| signed(&restrict(d), sign)).collect(),
            q_dirs: t_dirs.iter().map(|d| signed(&restrict(&lq(d)), sign)).collect(),
        };
        let (p_start, q_start) = pencil.at(t0);
        let scales = direction_scales(&p_start, &q_start, &pencil.p_dirs, &pencil.q_dirs);
        let (t, value, _) = minimise_normalised(&pencil, t0, &scales, settings.max_iterations);
        let restricted_max = |t: &[Rational]| -> Option<f64> {
            let b = variation.base(&variation.family.at(t));
            top_generalized(&signed(&restrict(&b), sign), &signed(&restrict(&lq(&b)), sign)).ok().map(|(l, _)| l)
        };
        let limit = value + 1e-12 * value.abs().max(first_growth.sigma2);
        casimir::round_family_parameters(
            variation,
            sign,
            &t,
            &scales,
            SIMPLE_DENOMINATOR,
            Some((&restricted_max, limit)),
        )
        .or_else(|| casimir::round_family_parameters(variation, sign, &t, &scales, SIMPLE_DENOMINATOR, None))
        .unwrap_or_else(|| first.family_parameters.clone())
    };
    let multipliers = variation.family.at(&t_rational);
    // 2. The frame blocks at those multipliers.
    let base = variation.base(&multipliers);
    let q_base = lq(&base);
    let w = variation.complement();
    let (bzz, bzw, bww) = variation.frame_blocks(&base, &w);
    let (qzz, qzw, qww) = variation.frame_blocks(&q_base, &w);
    let s = sign as f64;
    let pz = bzz.to_dmatrix() * s;
    let pzw = bzw.to_dmatrix() * s;
    let qz = qzz.to_dmatrix() * s;
    let k0 = if k == 0 {
        -bww.to_dmatrix() * s
    } else {
        let ch = pz.clone().cholesky()?;
        pzw.transpose() * ch.solve(&pzw) - bww.to_dmatrix() * s
    };
    let margin = casimir::conserved_margin(variation, &multipliers, sign)?.to_dmatrix();
    let frame = FramePencil {
        pz,
        pzw,
        pw: bww.to_dmatrix() * s,
        qz,
        qzw: qzw.to_dmatrix() * s,
        qw: qww.to_dmatrix() * s,
        k0,
        margin,
    };
    // The restricted lambda_max: the infimum over K at these multipliers
    // (K -> infinity along the conserved directions leaves only ker G^T).
    let (restricted_max, top) = if k == 0 {
        (f64::NEG_INFINITY, None)
    } else {
        match top_generalized(&frame.pz, &frame.qz) {
            Ok((l, v)) => (l, Some(v)),
            Err(_) => return None,
        }
    };
    let infimum = restricted_max.max(0.0);
    // A certified lower bound on every choice's Sigma^2 (no free
    // multipliers: the bound holds for every K): the exact Rayleigh
    // quotient of a rational vector of ker G^T.
    let witness = if f == 0 { top.as_ref().and_then(|v| rayleigh_lower_bound(&bzz, &qzz, sign, v)) } else { None };
    let (infimum_lower_bound, infimum_witness) = match witness {
        Some((bound, a)) => (Some(bound), Some(z.mul_vec(&a))),
        None => (None, None),
    };
    let scale = infimum.max(first_growth.sigma2);
    if scale <= 0.0 {
        // The first choice already has Sigma^2 = 0, the floor.
        return Some(Optimum {
            choice: first.clone(),
            growth: first_growth.clone(),
            infimum: 0.0,
            infimum_lower_bound: None,
            infimum_witness: None,
            attained: true,
            within_tolerance: true,
            q_depends_on_m: false,
            method: "the first choice attains Sigma^2 = 0",
        });
    }
    // 3. K for a target S = infimum + delta: first delta = 1e-12 scale (the
    // infimum attained by a finite K keeps P well conditioned), then half
    // the tolerance, then larger gaps until cond(P) is acceptable.
    let cond_limit = 1e8f64.max(10.0 * first_growth.condition_number.min(1e300));
    // K rounded to the fewest digits (3, 6, 9, then 15) that keep P
    // definite and Sigma^2 at the target: short numbers in the certificate.
    let build = |delta: f64| -> Option<(CasimirChoice, GrowthConstant)> {
        let target = restricted_max.max(0.0) + delta;
        let kf = frame.k_for(target)? * s;
        let mut last = None;
        for digits in [3u32, 6, 9, 15] {
            let Some(k_short) = (0..kf.nrows())
                .flat_map(|i| (0..kf.ncols()).map(move |j| (i, j)))
                .map(|(i, j)| exact::decimal_near(kf[(i, j)], digits))
                .collect::<Option<Vec<Rational>>>()
                .map(|entries| Matrix::from_fn(kf.nrows(), kf.ncols(), |i, j| entries[i * kf.ncols() + j].clone()))
            else {
                continue;
            };
            let Some(choice) = exact_choice(variation, sign, t_rational.clone(), &k_short, first.relative_margin)
            else {
                continue;
            };
            let Ok(growth) = growth_constant(&choice.p, &lq(&choice.p), sign) else { continue };
            let on_target = growth.sigma2 <= target + 1e-13 * scale;
            last = Some((choice, growth));
            if on_target {
                break;
            }
        }
        last
    };
    let mut best: Option<(CasimirChoice, GrowthConstant)> = None;
    // delta = 0 first: when the infimum is attained, S = lambda_max itself
    // (exactly singular S P - Q: a sharp certificate).
    if restricted_max > 0.0 {
        if let Some((choice, growth)) = build(0.0) {
            if growth.condition_number <= cond_limit && growth.sigma2 <= infimum + 1e-12 * scale {
                best = Some((choice, growth));
            }
        }
    }
    let mut delta = if best.is_some() { f64::INFINITY } else { 1e-12 * scale };
    let mut tried_half = false;
    while delta <= 1e3 * scale {
        if let Some((choice, growth)) = build(delta) {
            let conditioned = growth.condition_number <= cond_limit;
            let better = best.as_ref().is_none_or(|(_, b)| growth.sigma2 < b.sigma2);
            if conditioned {
                if better {
                    best = Some((choice, growth));
                }
                break;
            }
        }
        if !tried_half && delta < 0.5 * settings.tolerance * scale {
            delta = 0.5 * settings.tolerance * scale;
            tried_half = true;
        } else {
            delta *= 4.0;
        }
    }
    let (choice, growth) = match best {
        Some(b) if b.1.sigma2 <= first_growth.sigma2 => b,
        _ => (first.clone(), first_growth.clone()),
    };
    let attained = growth.sigma2 <= infimum + 1e-10 * scale;
    let within_tolerance = growth.sigma2 <= infimum + settings.tolerance * scale;
    let method = if f == 0 {
        "Schur complement on the conserved directions (no free multipliers)"
    } else {
        "restricted to ker G^T, ellipsoid over t, then the Schur complement on the conserved directions"
    };
    Some(Optimum {
        choice,
        growth,
        infimum,
        infimum_lower_bound,
        infimum_witness,
        attained,
        within_tolerance,
        q_depends_on_m: false,
        method,
    })
}

/// `max(0, v^T sQ v / v^T sP v)` exactly, for `v` the floating-point top
/// eigenvector rounded to 15 digits: a lower bound on `lambda_max(sQ, sP)`,
/// with the rounded vector.
fn rayleigh_lower_bound(p: &Matrix, q: &Matrix, sign: i8, v: &DVector<f64>) -> Option<(Rational, Vec<Rational>)> {
    let top = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if top.is_nan() || top <= 0.0 || !top.is_finite() {
        return None;
    }
    let bound = |v: Vec<Rational>| -> Option<(Rational, Vec<Rational>)> {
        let quad = |m: &Matrix| v.iter().zip(m.mul_vec(&v)).fold(Rational::zero(), |acc, (a, b)| acc + a * b);
        let (pv, qv) = (quad(p), quad(q));
        let (pv, qv) = if sign < 0 { (-pv, -qv) } else { (pv, qv) };
        if !pv.is_positive() {
            return None;
        }
        let rho = qv / pv;
        Some((if rho.is_positive() { rho } else { Rational::zero() }, v))
    };
    // Short digits first (an eigenvector with simple entries gives the
    // sharp value as a short rational); 15 digits as the fallback.
    let rounded = |digits: u32| v.iter().map(|x| exact::decimal_near(x / top, digits)).collect::<Option<Vec<_>>>();
    let fifteen = bound(rounded(15)?)?;
    let target = exact::rational_to_f64(&fifteen.0);
    for digits in [2u32, 4, 6, 9, 12] {
        if let Some(b) = rounded(digits).and_then(bound) {
            if exact::rational_to_f64(&b.0) >= target * (1.0 - 1e-15) {
                return Some(b);
            }
        }
    }
    Some(fifteen)
}
