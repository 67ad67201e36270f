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

use crate::bound::InfimumWitness;
use crate::form::{generator_form, GeneratorForm};
use crate::growth::{condition_number, growth_constant, GrowthConstant};
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
    let k_dirs = || -> Vec<(usize, usize, Matrix)> {
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
    };
    // L(Y K Y^T) = Y K Y^T A~ + A~^T Y K Y^T + sum B^T Y K Y^T B vanishes when
    // Y^T A = 0 (the drift conserves the quantities: always) and B^T Y = 0
    // (the noise conserves them).
    let q_depends_on_m = !noise_conserves_all && k_dirs().iter().any(|(_, _, d)| !lq(d).is_zero());
    let t0: Vec<f64> = first.family_parameters.iter().map(exact::rational_to_f64).collect();

    if !q_depends_on_m {
        // The whole generator form of P = B(t) + Y K Y^T is then that of
        // B(t), affine in t: the first choice's form plus (t - t0) times the
        // forms of the directions, exact, with no products per candidate.
        // (Its drift part P A + A^T P does not depend on K when Y^T A = 0,
        // which conservation implies; checked, else formed afresh.)
        let t_forms: Vec<GeneratorForm> = t_dirs.iter().map(|d| generator_form(linearisation, d)).collect();
        let drift_free = y.transpose().mul(&linearisation.a).is_zero();
        let form_at = |t: &[Rational]| -> GeneratorForm {
            let mut form = first_form.clone();
            for ((ti, t0i), d) in t.iter().zip(&first.family_parameters).zip(&t_forms) {
                let step = ti - t0i;
                if !step.is_zero() {
                    form.q.add_scaled_assign(&step, &d.q);
                    form.drift_residual.add_scaled_assign(&step, &d.drift_residual);
                    form.paper_formula.add_scaled_assign(&step, &d.paper_formula);
                }
            }
            form
        };
        let forms = Forms { at: &form_at, first: first_form, t_dirs: &t_forms, drift_free, linearisation };
        return optimise_restricted(variation, &forms, first, first_growth, &t0, &t_dirs, settings);
    }
    let k_dirs = k_dirs();
    // K of the first choice, on the independent columns.
    let k_first = Matrix::from_fn(rk, rk, |a, b| first.m[(cols[a], cols[b])].clone());

    // General case: Q depends on K. Minimise over theta = (t, K entries),
    // the directions normalised in the metric of the first P.
    let mut p_dirs: Vec<DMatrix<f64>> = t_dirs.iter().map(|d| signed(d, sign)).collect();
    let mut q_dirs: Vec<DMatrix<f64>> = t_dirs.iter().map(|d| signed(&lq(d), sign)).collect();
    for (_, _, d) in &k_dirs {
        p_dirs.push(signed(d, sign));
        q_dirs.push(signed(&lq(d), sign));
    }
    let pencil = AffinePencil {
        p0: signed(&base0, sign),
        q0: signed(&lq(&base0), sign),
        p_dirs,
        q_dirs,
        cond_limit: f64::INFINITY,
    };
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
    let form = generator_form(linearisation, &choice.p);
    let growth = growth_constant(&choice.p, &form.q, sign).ok()?;
    if growth.sigma2 > first_growth.sigma2 {
        return None;
    }
    Some(Optimum {
        choice,
        form,
        attained: !on_boundary,
        within_tolerance: !on_boundary,
        growth,
        infimum,
        infimum_lower_bound: None,
        infimum_witness: None,
        infimum_parameters: None,
        q_depends_on_m,
        method: "ellipsoid over (t, M)",
    })
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

/// The case where `Q` does not depend on `M`: minimise the restricted
/// `lambda_max(Z^T sQ Z, Z^T sP Z)` over the free multipliers, then
/// construct `K` for a target just above that infimum.
///
/// The restricted infimum over the multipliers may be approached at the
/// edge of the region where `Z^T sP Z` is definite, where `P` is singular.
/// Then the multipliers are chosen by the same minimisation with the
/// condition number of `Z^T sP Z` limited (a convex constraint), tightened
/// until `cond(P)` is within the limit; the certificate states the gap that
/// costs.
fn optimise_restricted(
    variation: &SecondVariation,
    forms: &Forms,
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
    let cond_limit = 1e8f64.max(10.0 * first_growth.condition_number.min(1e300));
    let at = |t: &[Rational]| at_multipliers(variation, forms, first, first_growth, t, cond_limit, settings);
    if f == 0 || k == 0 {
        let found = at(&first.family_parameters)?;
        let infimum = found.restricted_max.max(0.0);
        return Some(found.into_optimum(first, forms.first, first_growth, infimum, false, f, settings));
    }
    // 1. The multipliers: the restricted infimum over t, in orthonormal
    // coordinates of ker G^T (`Z R^{-1}`; the exact kernel basis can be
    // badly scaled, and the values do not depend on the basis).
    let zt = z.transpose();
    let r_inv = orthonormalising(z);
    let restrict = |m: &Matrix| congruent(&signed(&zt.mul(m).mul(z), sign), &r_inv);
    let zero_t = vec![Rational::zero(); f];
    let base0 = variation.base(&variation.family.particular);
    let pencil = AffinePencil {
        p0: restrict(&base0),
        q0: restrict(&(forms.at)(&zero_t).q),
        p_dirs: t_dirs.iter().map(&restrict).collect(),
        q_dirs: forms.t_dirs.iter().map(|d| restrict(&d.q)).collect(),
        cond_limit: f64::INFINITY,
    };
    let (p_start, q_start) = pencil.at(t0);
    let scales = direction_scales(&p_start, &q_start, &pencil.p_dirs, &pencil.q_dirs);
    let (t_inf, value, on_edge) = minimise_normalised(&pencil, t0, &scales, settings.max_iterations);
    // The condition number of the compression of sP to ker G^T in
    // orthonormal coordinates is a lower bound on cond(sP) (its eigenvalues
    // interlace): a cheap screen before the exact construction.
    let restricted_condition = |t: &[f64]| condition_number(&pencil.at(t).0);
    let restricted_max = |t: &[Rational]| -> Option<f64> {
        let b = variation.base(&variation.family.at(t));
        top_generalized(&restrict(&b), &restrict(&(forms.at)(t).q)).ok().map(|(l, _)| l)
    };
    // The construction at rational multipliers near t (t itself if the
    // screen lets it through).
    let candidate = |t: &[f64]| -> Option<AtMultipliers> {
        if restricted_condition(t) > cond_limit {
            return None;
        }
        let v = pencil.value(t)?;
        let limit = v + 1e-12 * v.abs().max(first_growth.sigma2);
        let t_rational = casimir::round_family_parameters(
            variation,
            sign,
            t,
            &scales,
            SIMPLE_DENOMINATOR,
            Some((&restricted_max, limit)),
        )
        .or_else(|| casimir::round_family_parameters(variation, sign, t, &scales, SIMPLE_DENOMINATOR, None))?;
        at(&t_rational)
    };
    // The minimiser with cond(Z^T sP Z) <= limit (a convex constraint).
    let start_condition = restricted_condition(t0);
    let limited = |limit: f64| -> Vec<f64> {
        let pencil = AffinePencil {
            cond_limit: limit.max(2.0 * start_condition),
            p0: pencil.p0.clone(),
            q0: pencil.q0.clone(),
            p_dirs: pencil.p_dirs.clone(),
            q_dirs: pencil.q_dirs.clone(),
        };
        minimise_normalised(&pencil, t0, &scales, settings.max_iterations).0
    };
    let mut found: Option<AtMultipliers> = None;
    let keep = |here: AtMultipliers, found: &mut Option<AtMultipliers>| -> bool {
        let conditioned = here.best.is_some();
        if found.as_ref().is_none_or(|b| here.sigma2() < b.sigma2()) {
            *found = Some(here);
        }
        conditioned
    };
    // The unconstrained minimiser first; where P is nearly singular there,
    // the minimiser with cond(Z^T sP Z) limited to 1e-1, 1e-2, ... of the
    // limit (the rest of P adds to the condition number), refined by
    // geometric bisection between the last limit that failed and the first
    // that succeeded; the starting multipliers last.
    if !candidate(&t_inf).is_some_and(|here| keep(here, &mut found)) {
        let mut failed = cond_limit;
        for fraction in [1e-1, 1e-2, 1e-3, 1e-4, 1e-5] {
            let limit = fraction * cond_limit;
            if limit < 2.0 * start_condition {
                break;
            }
            if candidate(&limited(limit)).is_some_and(|here| keep(here, &mut found)) {
                let (mut lo, mut hi) = (limit, failed);
                for _ in 0..3 {
                    let mid = (lo * hi).sqrt();
                    if candidate(&limited(mid)).is_some_and(|here| keep(here, &mut found)) {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                break;
            }
            failed = limit;
        }
        if found.as_ref().is_none_or(|b| b.best.is_none()) {
            if let Some(here) = at(&first.family_parameters) {
                keep(here, &mut found);
            }
        }
    }
    // The infimum estimate: the value at the unconstrained minimiser when P
    // is resolved there (cond <= 1e12); at a nearly singular point the
    // floating-point lambda_max is not to be trusted, and the estimate is
    // the best certified value (flagged: the infimum may be lower).
    const RESOLVED: f64 = 1e12;
    let found = found?;
    let resolved = restricted_condition(&t_inf) <= RESOLVED;
    let infimum = if resolved { value } else { found.sigma2() };
    let mut optimum =
        found.into_optimum(first, forms.first, first_growth, infimum.max(0.0), on_edge || !resolved, f, settings);
    // Where the infimum was found, for a certified bound over the family
    // (tried even where P is nearly singular: every claim is exact).
    optimum.infimum_parameters = Some(t_inf);
    Some(optimum)
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

/// What the construction of `K` gives at fixed rational multipliers.
struct AtMultipliers {
    /// The restricted `lambda_max` at these multipliers (the infimum over
    /// `K`); `-inf` when `ker G^T` is trivial.
    restricted_max: f64,
    /// A certified lower bound on `lambda_max` for every `K` at these
    /// multipliers, with its witness in the algebra's coordinates.
    witness: Option<(Rational, Vec<Rational>)>,
    /// The exact choice built, if any, with its form: it has `cond(P)`
    /// within the limit (only such a choice is kept).
    best: Option<(CasimirChoice, GeneratorForm, GrowthConstant)>,
}

impl AtMultipliers {
    fn sigma2(&self) -> f64 {
        self.best.as_ref().map_or(f64::INFINITY, |b| b.2.sigma2)
    }

    /// The optimum over the family, given the infimum estimate over the
    /// multipliers (`on_edge`: the search ran to the edge of its region, so
    /// the infimum may be lower still).
    #[allow(clippy::too_many_arguments)]
    fn into_optimum(
        self,
        first: &CasimirChoice,
        first_form: &GeneratorForm,
        first_growth: &GrowthConstant,
        infimum: f64,
        on_edge: bool,
        f: usize,
        settings: &OptimiseSettings,
    ) -> Optimum {
        let (choice, form, growth) = match self.best {
            Some(b) if b.2.sigma2 <= first_growth.sigma2 => b,
            _ => (first.clone(), first_form.clone(), first_growth.clone()),
        };
        // The bound is certified only without free multipliers (it holds
        // for every K at the given multipliers, and then that is the family).
        let (infimum_lower_bound, infimum_witness) = match self.witness {
            Some((bound, x)) if f == 0 => (Some(bound), Some(InfimumWitness::Vector(x))),
            _ => (None, None),
        };
        let scale = if infimum > 0.0 { infimum } else { first_growth.sigma2 };
        let attained = !on_edge && growth.sigma2 <= infimum + 1e-10 * scale;
        let within_tolerance = !on_edge && growth.sigma2 <= infimum + settings.tolerance * scale;
        let method = if f == 0 {
            "Schur complement on the conserved directions (no free multipliers)"
        } else if on_edge {
            "restricted to ker G^T, ellipsoid over t (ran to the edge of its region: the infimum may be lower), then the Schur complement on the conserved directions"
        } else {
            "restricted to ker G^T, ellipsoid over t, then the Schur complement on the conserved directions"
        };
        Optimum {
            choice,
            form,
            growth,
            infimum,
            infimum_lower_bound,
            infimum_witness,
            infimum_parameters: None,
            attained,
            within_tolerance,
            q_depends_on_m: false,
            method,
        }
    }
}

/// At fixed rational multipliers `t`: the frame blocks, the restricted
/// `lambda_max`, and `K` constructed for targets `S` = infimum + delta,
/// first delta = 0 (sharp when the infimum is attained by a finite `K`),
/// then 1e-12 of the scale, then a gap predicted from the condition number
/// seen (it grows like 1/delta when `K` must grow), then half the
/// tolerance, then larger gaps until `cond(P)` is within the limit.
fn at_multipliers(
    variation: &SecondVariation,
    forms: &Forms,
    first: &CasimirChoice,
    first_growth: &GrowthConstant,
    t_rational: &[Rational],
    cond_limit: f64,
    settings: &OptimiseSettings,
) -> Option<AtMultipliers> {
    let sign = first.sign;
    let k = variation.kernel.ncols();
    let multipliers = variation.family.at(t_rational);
    let base = variation.base(&multipliers);
    let base_form = (forms.at)(t_rational);
    let q_base = &base_form.q;
    let s = sign.as_f64();
    // The frame blocks in floating point (everything here is a floating-point
    // screen; only the K finally chosen is made exact, and the witness below
    // is evaluated exactly in the algebra's coordinates).
    let b_f = base.to_dmatrix() * s;
    let q_f = q_base.to_dmatrix() * s;
    let z_f = variation.kernel.to_dmatrix();
    let w_f = variation.complement().to_dmatrix();
    // Orthonormal coordinates of ker G^T (Z R^{-1}): K1 below is invariant
    // under a change of basis of ker G^T, its rounding is not.
    let r_inv = orthonormalising(&variation.kernel);
    let zo = &z_f * &r_inv;
    let pz = congruent(&b_f, &zo);
    let qz = congruent(&q_f, &zo);
    // The restricted lambda_max: the infimum over K at these multipliers
    // (K -> infinity along the conserved directions leaves only ker G^T).
    let (restricted_max, top) = if k == 0 {
        (f64::NEG_INFINITY, None)
    } else {
        let (l, v) = top_generalized(&pz, &qz).ok()?;
        (l, Some(v))
    };
    // A certified lower bound for every K at these multipliers: the exact
    // Rayleigh quotient of a rational vector of ker G^T.
    let witness = top.as_ref().filter(|_| variation.family.directions.is_empty()).and_then(|v| {
        rayleigh_lower_bound((&base, &b_f), (q_base, &q_f), sign, (&variation.kernel, &z_f), &(&r_inv * v))
    });
    let infimum = restricted_max.max(0.0);
    let first_here = || Some((first.clone(), forms.first.clone(), first_growth.clone()));
    if infimum.max(first_growth.sigma2) <= 0.0 {
        // The first choice already has Sigma^2 = 0, the floor.
        return Some(AtMultipliers { restricted_max, witness, best: first_here() });
    }
    let scale = if infimum > 0.0 { infimum } else { first_growth.sigma2 };
    if t_rational == first.family_parameters.as_slice()
        && first_growth.condition_number <= cond_limit
        && first_growth.sigma2 <= infimum + 1.1e-12 * scale
    {
        // The first choice attains the infimum at these multipliers (to the
        // tolerance the construction below accepts for delta = 0) and is
        // conditioned: building another K could not do better.
        return Some(AtMultipliers { restricted_max, witness, best: first_here() });
    }
    let pzw = zo.transpose() * &b_f * &w_f;
    let pw = congruent(&b_f, &w_f);
    let k0 = if k == 0 {
        -&pw
    } else {
        let ch = pz.clone().cholesky()?;
        pzw.transpose() * ch.solve(&pzw) - &pw
    };
    let margin = casimir::conserved_margin(variation, &multipliers, sign)?.to_dmatrix();
    let frame =
        FramePencil { pz, pzw, pw, qz, qzw: zo.transpose() * &q_f * &w_f, qw: congruent(&q_f, &w_f), k0, margin };
    // Everything below is screened in floating point first (sP = sB + Y K' Y^T,
    // and sQ = sQ(B) since Q does not depend on K); only a K that passes the
    // screen is made exact, so the search costs a few small dense
    // eigenproblems per step instead of exact congruences.
    let y_f = variation.independent_gradients().to_dmatrix();
    let screen = |kp: &DMatrix<f64>| -> Option<(f64, f64)> {
        let p = &b_f + &y_f * kp * y_f.transpose();
        let p = (&p + p.transpose()) * 0.5;
        let (l, _) = top_generalized(&p, &q_f).ok()?;
        Some((l.max(0.0), condition_number(&p)))
    };
    // Passes the screen: conditioned and within `allowed` of the infimum, up
    // to the round-off a condition number `c` allows.
    let passes = |(sigma2, c): (f64, f64), allowed: f64| -> bool {
        c <= 1.1 * cond_limit && sigma2 <= infimum + allowed + c * 1e-15 * scale
    };
    // K' for a target, rounded to the fewest digits (3, 6, 9, then 15) that
    // pass the screen (short numbers in the certificate), made exact; the
    // exact P must be definite, conditioned and within `allowed`.
    let build = |delta: f64, allowed: f64| -> Option<(CasimirChoice, GeneratorForm, GrowthConstant)> {
        let kp = frame.k_for(infimum + delta, delta == 0.0)?;
        if !screen(&kp).is_some_and(|v| passes(v, allowed)) {
            return None;
        }
        for digits in [3u32, 6, 9, 15] {
            let Some(entries) =
                kp.iter().map(|&x| exact::decimal_near(x * s, digits)).collect::<Option<Vec<Rational>>>()
            else {
                continue;
            };
            // Column-major, as nalgebra stores kp.
            let k_short = Matrix::from_fn(kp.nrows(), kp.ncols(), |i, j| entries[j * kp.nrows() + i].clone());
            let k_float = k_short.to_dmatrix() * s;
            if digits < 15 && !screen(&k_float).is_some_and(|v| passes(v, allowed)) {
                continue;
            }
            let Some(choice) = exact_choice(variation, sign, t_rational.to_vec(), &k_short, first.relative_margin)
            else {
                continue;
            };
            // Q does not depend on K: the form of B(t) serves.
            let Ok(growth) = growth_constant(&choice.p, q_base, sign) else { continue };
            if growth.condition_number <= cond_limit && growth.sigma2 <= infimum + allowed + 1e-13 * scale {
                let form = forms.of(&base_form, &choice.p);
                return Some((choice, form, growth));
            }
        }
        None
    };
    // delta = 0 first: when the infimum is attained, S = lambda_max itself
    // (exactly singular S P - Q: a sharp certificate).
    let best = if restricted_max > 0.0 { build(0.0, 1e-12 * scale) } else { None };
    let best = best.or_else(|| {
        let condition_at = |delta: f64| frame.k_for(infimum + delta, false).and_then(|kp| screen(&kp)).map(|v| v.1);
        approach_infimum(
            Approach { infimum, ceiling: first_growth.sigma2, scale, tolerance: settings.tolerance, cond_limit },
            |delta| build(delta, 2.0 * delta + 1e-12 * scale),
            condition_at,
        )
    });
    Some(AtMultipliers { restricted_max, witness, best })
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

/// `max(0, x^T sQ x / x^T sP x)` exactly for `x = Z n`, with `n` the
/// floating-point top eigenvector `v` of the restricted pencil (in the
/// coordinates of the kernel basis `Z`) scaled to integers
/// (`round(10^d v / |v|_inf)`): a lower bound on `lambda_max(sQ, sP)` over
/// `ker G^T`, with the vector `x`.
///
/// The number of digits `d` is the fewest of 2, 4, 6, 9, 12, 15 whose
/// quotient, evaluated in floating point, is within 1e-15 of the 15-digit
/// one (an eigenvector with simple entries gives the sharp value as a short
/// rational); only that vector is evaluated exactly. The exact quotient is
/// the claim, whichever vector the floating-point screen picked: a poor
/// pick gives a lower, still valid, bound. Integers keep the exact quadratic
/// forms cheap: the common denominator `10^d` cancels in the quotient.
///
/// Each matrix comes with its floating-point value (`sP`, `sQ` signed).
fn rayleigh_lower_bound(
    (p, pf): (&Matrix, &DMatrix<f64>),
    (q, qf): (&Matrix, &DMatrix<f64>),
    sign: Sign,
    (z, z_f): (&Matrix, &DMatrix<f64>),
    v: &DVector<f64>,
) -> Option<(Rational, Vec<Rational>)> {
    let top = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if top.is_nan() || top <= 0.0 || !top.is_finite() {
        return None;
    }
    // 10^15 < 2^53: the rounded entries are exact integers in f64.
    let integers = |digits: i32| v.map(|x| (x / top * 10f64.powi(digits)).round());
    let quotient = |n: &DVector<f64>| {
        let x = z_f * n;
        x.dot(&(qf * &x)) / x.dot(&(pf * &x))
    };
    let target = quotient(&integers(15));
    let digits =
        [2, 4, 6, 9, 12, 15].into_iter().find(|&d| quotient(&integers(d)) >= target * (1.0 - 1e-15)).unwrap_or(15);
    // Divided by their gcd: the shortest integer vector on that line.
    let ints: Vec<i64> = integers(digits).iter().map(|&x| x as i64).collect();
    let g = ints.iter().fold(0i64, |g, &x| num_integer::Integer::gcd(&g, &x)).max(1);
    let n: Vec<Rational> = ints.iter().map(|&x| Rational::from(x / g)).collect();
    let x = z.mul_vec(&n);
    let quad = |m: &Matrix| x.iter().zip(m.mul_vec(&x)).fold(Rational::zero(), |acc, (a, b)| acc + a * b);
    let (pv, qv) = (quad(p), quad(q));
    let (pv, qv) = if !sign.is_positive() { (-pv, -qv) } else { (pv, qv) };
    if !pv.is_positive() {
        return None;
    }
    let rho = qv / pv;
    Some((if rho.is_positive() { rho } else { Rational::zero() }, x))
}
