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

mod at_multipliers;
mod general;
mod restricted;

use crate::bound::InfimumWitness;
use crate::form::{generator_form, GeneratorForm};
use crate::growth::GrowthConstant;
use crate::linearise::Linearisation;
use crate::pencil::{generalized_eigen, symmetric_eigen};
use casimir::Sign;
use casimir::{CasimirChoice, Ellipsoid, SecondVariation};
use exact::{Matrix, Rational};
use nalgebra::{DMatrix, DVector};
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
    /// `Q`, the drift residual and the paper's formula for this choice.
    pub form: GeneratorForm,
    /// `lambda_max(Q, P)` etc. for this choice.
    pub growth: GrowthConstant,
    /// The floating-point infimum of `max(0, lambda_max)` over the freedom.
    pub infimum: f64,
    /// A certified rational lower bound on `Sigma^2` for every choice in the
    /// family with `P` definite of the choice's sign (when it can be proved,
    /// with `Q` independent of `M`; with free
    /// multipliers the pipeline adds it at the exact level, see
    /// [`crate::family_lower_bound`]).
    pub infimum_lower_bound: Option<Rational>,
    /// What proves it.
    pub infimum_witness: Option<InfimumWitness>,
    /// The free multipliers where the floating-point infimum was found (with
    /// free multipliers and `Q` independent of `M`).
    pub infimum_parameters: Option<Vec<f64>>,
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

/// `lambda_max(Q, P)` with its `P`-normalised eigenvector, or `None` when
/// `P` is not numerically positive definite (then the eigenvector of
/// `lambda_min(P)` is returned as the second member for a feasibility cut).
pub(crate) fn top_generalized(p: &DMatrix<f64>, q: &DMatrix<f64>) -> Result<(f64, DVector<f64>), DVector<f64>> {
    let n = p.nrows();
    if let Some(g) = generalized_eigen(p, q).filter(|g| !g.values.is_empty()) {
        return Ok((g.values[n - 1], g.vectors.column(n - 1).into_owned()));
    }
    let u = symmetric_eigen(p.clone())
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
    /// Keep `cond(P) <= cond_limit` (infinite: no limit). The set is
    /// convex: `c lambda_min(P) - lambda_max(P)` is concave in `theta`.
    cond_limit: f64,
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
        if self.cond_limit.is_finite() {
            if let Some(e) = symmetric_eigen(p.clone()) {
                let n = p.nrows();
                let imin = (0..n).min_by(|&i, &j| e.eigenvalues[i].total_cmp(&e.eigenvalues[j])).unwrap_or(0);
                let imax = (0..n).max_by(|&i, &j| e.eigenvalues[i].total_cmp(&e.eigenvalues[j])).unwrap_or(0);
                let (lo, hi) = (e.eigenvalues[imin], e.eigenvalues[imax]);
                if lo > 0.0 && hi > self.cond_limit * lo {
                    // Supergradient of c lambda_min - lambda_max.
                    let (umin, umax) =
                        (e.eigenvectors.column(imin).into_owned(), e.eigenvectors.column(imax).into_owned());
                    return Cut::Feasibility(
                        self.p_dirs.iter().map(|d| self.cond_limit * quad(d, &umin) - quad(d, &umax)).collect(),
                    );
                }
            }
        }
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

fn signed(m: &Matrix, sign: Sign) -> DMatrix<f64> {
    m.to_dmatrix() * sign.as_f64()
}

/// The exact choice at rational parameters `t` and rational `K` (on the
/// independent conserved gradients), if `P` is exactly definite.
fn exact_choice(
    variation: &SecondVariation,
    sign: Sign,
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
        cond_limit: pencil.cond_limit,
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
    let e = symmetric_eigen((m + m.transpose()) * 0.5)?;
    let d = DMatrix::from_diagonal(&e.eigenvalues.map(|x| x.max(0.0)));
    Some(&e.eigenvectors * d * e.eigenvectors.transpose())
}

/// The pair `(sP, sQ)` in the frame `T = [Z W]` at fixed multipliers, when
/// `Q` does not depend on `K`: `sP = [[Pz, Pzw], [Pzw^T, Pw + K']]` with
/// `K' = sK`, `sQ = [[Qz, Qzw], [Qzw^T, Qw]]`.
pub(crate) struct FramePencil {
    pub(crate) pz: DMatrix<f64>,
    pub(crate) pzw: DMatrix<f64>,
    pub(crate) pw: DMatrix<f64>,
    pub(crate) qz: DMatrix<f64>,
    pub(crate) qzw: DMatrix<f64>,
    pub(crate) qw: DMatrix<f64>,
    /// `K0'`: `sP ≻ 0` iff `K' ≻ K0'` (the Schur bound, signed).
    pub(crate) k0: DMatrix<f64>,
    /// The margin `D` added along the conserved directions.
    pub(crate) margin: DMatrix<f64>,
}

impl FramePencil {
    /// The smallest `K'` (in the positive semidefinite order) with
    /// `S sP - sQ ⪰ 0`: by the Schur complement of the `Z` block
    /// (`X = S Pz - Qz ≻ 0` for `S` above the restricted `lambda_max`),
    /// `K1 = (Qw + C^T X^{-1} C) / S - Pw` with `C = S Pzw - Qzw`. Then
    /// `K' = K1 + (K0' - K1)_+ + D` also makes `P` definite, and adding the
    /// positive `D` to `P` never raises a positive `lambda_max` (`Q` does
    /// not depend on `K`). So `Sigma^2 <= S` up to rounding.
    pub(crate) fn k_for(&self, s: f64, singular: bool) -> Option<DMatrix<f64>> {
        if s.is_nan() || s <= 0.0 {
            return None;
        }
        let k1 = if self.pz.nrows() == 0 {
            &self.qw / s - &self.pw
        } else {
            let x = &self.pz * s - &self.qz;
            let c = &self.pzw * s - &self.qzw;
            // At S = lambda_max itself (`singular`) X is singular: the
            // pseudo-inverse (eigenvalues below 1e-12 |X| dropped) gives the
            // K that attains it when the top eigenvectors do not couple to
            // the conserved directions (C^T v = 0). A Cholesky factor of a
            // numerically singular X would give garbage along v.
            let pseudo = || -> Option<DMatrix<f64>> {
                let e = symmetric_eigen((&x + x.transpose()) * 0.5)?;
                let top = e.eigenvalues.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                if e.eigenvalues.iter().any(|&v| v < -1e-12 * top) {
                    return None;
                }
                let inv = e.eigenvalues.map(|v| if v > 1e-12 * top { 1.0 / v } else { 0.0 });
                Some(&e.eigenvectors * DMatrix::from_diagonal(&inv) * e.eigenvectors.transpose() * c.clone())
            };
            let xc = if singular {
                pseudo()?
            } else {
                match x.clone().cholesky() {
                    Some(ch) => ch.solve(&c),
                    None => pseudo()?,
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
/// but constructed (as a Schur complement, `FramePencil::k_for`) for a target `S` just above the
/// infimum, in the frame `[Z W]` where it is a Schur complement.
///
/// `noise_conserves_all` says that every conserved quantity Poisson-commutes
/// with every noise potential (exactly, as computed by
/// [`casimir::System::noise_commutation`]); then `Q` cannot depend on `M`
/// (the drift conserves them too), and the check of that is skipped.
///
/// `first_form` is the generator form of the first choice's `P`.
pub fn optimise_choice(
    variation: &SecondVariation,
    linearisation: &Linearisation,
    first: &CasimirChoice,
    first_form: &GeneratorForm,
    first_growth: &GrowthConstant,
    noise_conserves_all: bool,
    settings: &OptimiseSettings,
) -> Option<Optimum> {
    let lq = |p: &Matrix| generator_form(linearisation, p).q;
    // Basis of the affine structure, exactly.
    let (base0, t_dirs) = multiplier_directions(variation);
    // L(Y K Y^T) = Y K Y^T A~ + A~^T Y K Y^T + sum B^T Y K Y^T B vanishes when
    // Y^T A = 0 (the drift conserves the quantities: always) and B^T Y = 0
    // (the noise conserves them).
    let q_depends_on_m = !noise_conserves_all && casimir_directions(variation).iter().any(|(_, _, d)| !lq(d).is_zero());
    let t0: Vec<f64> = first.family_parameters.iter().map(exact::rational_to_f64).collect();

    if !q_depends_on_m {
        return restricted::optimise_q_free_of_m(
            variation,
            linearisation,
            (first, first_form, first_growth),
            &t0,
            &t_dirs,
            settings,
        );
    }
    general::optimise_over_t_and_m(variation, linearisation, (first, first_growth), &base0, &t_dirs, t0, settings)
}

/// The affine structure of `B(t)` in the free multipliers, exactly: `B(0)`
/// and the directions `B(e_i) - B(0)`.
fn multiplier_directions(variation: &SecondVariation) -> (Matrix, Vec<Matrix>) {
    let f = variation.family.directions.len();
    let base0 = variation.base(&variation.family.particular);
    let zero_t = vec![Rational::zero(); f];
    let t_dirs: Vec<Matrix> = (0..f)
        .map(|i| {
            let mut t = zero_t.clone();
            t[i] = Rational::from(1);
            variation.base(&variation.family.at(&t)).sub(&base0)
        })
        .collect();
    (base0, t_dirs)
}

/// The directions `Y E_ab Y^T` (`a <= b`, `E_ab` the symmetric unit) of the
/// Casimir Hessian `M = E K E^T` on the independent conserved gradients `Y`.
fn casimir_directions(variation: &SecondVariation) -> Vec<(usize, usize, Matrix)> {
    let rk = variation.range_columns.len();
    let y = variation.independent_gradients();
    let mut k_dirs = Vec::new();
    for a in 0..rk {
        for b in a..rk {
            let mut e = Matrix::zeros(rk, rk);
            e[(a, b)] = Rational::from(1);
            e[(b, a)] = Rational::from(1);
            k_dirs.push((a, b, y.mul(&e).mul(&y.transpose())));
        }
    }
    k_dirs
}

/// The generator forms when `Q` does not depend on `M`: affine in the
/// multipliers `t` alone.
struct Forms<'a> {
    /// The form of `B(t)`, exactly.
    at: &'a dyn Fn(&[Rational]) -> GeneratorForm,
    /// The first choice's form.
    first: &'a GeneratorForm,
    /// The forms of the multiplier directions.
    t_dirs: &'a [GeneratorForm],
    /// `Y^T A = 0`: the drift part does not depend on `K` either, so the
    /// form of `B(t) + Y K Y^T` is the form of `B(t)`.
    drift_free: bool,
    linearisation: &'a Linearisation,
}

impl Forms<'_> {
    /// The form of `P = B(t) + Y K Y^T` given the form of `B(t)`.
    fn of(&self, base_form: &GeneratorForm, p: &Matrix) -> GeneratorForm {
        if self.drift_free {
            base_form.clone()
        } else {
            generator_form(self.linearisation, p)
        }
    }
}

/// `R^{-1}` for the thin QR factorisation `Z = U R` of a kernel basis, so
/// that `Z R^{-1}` is orthonormal (the identity if `R` is singular).
fn orthonormalising(z: &Matrix) -> DMatrix<f64> {
    let k = z.ncols();
    if k == 0 || z.nrows() < k {
        return DMatrix::identity(k, k);
    }
    z.to_dmatrix().qr().r().try_inverse().unwrap_or_else(|| DMatrix::identity(k, k))
}

/// `R^T M R` (symmetrised).
fn congruent(m: &DMatrix<f64>, r: &DMatrix<f64>) -> DMatrix<f64> {
    let c = r.transpose() * m * r;
    (&c + c.transpose()) * 0.5
}

/// Where [`approach_infimum`] may look.
pub(crate) struct Approach {
    /// The infimum of `Sigma^2` over `K` (at fixed multipliers).
    pub infimum: f64,
    /// The first choice's `Sigma^2`: no target above it is worth building.
    pub ceiling: f64,
    /// The scale of `Sigma^2` (the infimum, or the first choice's value).
    pub scale: f64,
    /// The optimisation tolerance, relative to the scale.
    pub tolerance: f64,
    /// The largest `cond(P)` accepted.
    pub cond_limit: f64,
}

/// `K` for targets `S = infimum + delta` when the infimum is approached
/// but not attained: delta from 1e-12 of the scale growing by 4 (half the
/// tolerance is always tried), jumping once to a gap predicted from the
/// condition number seen (`cond(P)` grows like `1/delta` while `K` must
/// grow), then refined by three geometric bisections between the last gap
/// that failed and the first that succeeded. `attempt(delta)` builds and
/// screens the choice; `condition_at(delta)` is `cond(P)` of the `K` built
/// for that target, unscreened. Shared by the exact optimiser and the
/// numeric level, so both stop at the same point.
pub(crate) fn approach_infimum<T>(
    a: Approach,
    mut attempt: impl FnMut(f64) -> Option<T>,
    mut condition_at: impl FnMut(f64) -> Option<f64>,
) -> Option<T> {
    let half = 0.5 * a.tolerance * a.scale;
    let mut delta = 1e-12 * a.scale;
    if !(delta > 0.0 && delta.is_finite()) {
        // A scale near the bottom of the double range (or not finite):
        // the gaps would not grow, and the loop would not end.
        return None;
    }
    let mut failed = 0.0;
    let mut predicted = false;
    let mut best = None;
    while best.is_none() && a.infimum + delta < a.ceiling.max(a.infimum + 1e3 * a.scale) {
        let mut next = delta * 4.0;
        best = attempt(delta);
        if best.is_some() && failed > 0.0 {
            // Geometric bisection between the last gap that failed and this.
            let (mut lo, mut hi) = (failed, delta);
            for _ in 0..3 {
                let mid = (lo * hi).sqrt();
                match attempt(mid) {
                    Some(b) => {
                        best = Some(b);
                        hi = mid;
                    }
                    None => lo = mid,
                }
            }
            break;
        }
        failed = delta;
        if best.is_none() && !predicted {
            if let Some(c) = condition_at(delta) {
                if c.is_finite() && c > a.cond_limit {
                    // cond(P) ~ 1/delta while K must grow: aim just inside the limit.
                    next = next.max(2.0 * delta * c / a.cond_limit);
                    predicted = true;
                }
            }
        }
        if delta < half && next > half {
            next = half;
        }
        delta = next;
    }
    best
}
