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
use exact::{best_rational_approximation, decimal_at_least, Matrix, Rational};
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
    /// Doublings of the Casimir-function scale `M` when approaching the
    /// infimum (stopped early once they no longer help). Default 40.
    pub max_doublings: usize,
}

impl Default for OptimiseSettings {
    fn default() -> Self {
        OptimiseSettings { tolerance: 1e-6, max_iterations: 3000, max_doublings: 40 }
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

/// `lambda_max / lambda_min` of a (hopefully) positive definite matrix;
/// infinite when it is not.
fn condition_number(m: &DMatrix<f64>) -> f64 {
    match sym_eigen(m.clone()) {
        Some(e) => {
            let lo = e.eigenvalues.iter().fold(f64::INFINITY, |a, &b| a.min(b));
            let hi = e.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
            if lo > 0.0 {
                hi / lo
            } else {
                f64::INFINITY
            }
        }
        None => f64::INFINITY,
    }
}

fn signed(m: &Matrix, sign: i8) -> DMatrix<f64> {
    m.to_dmatrix() * (sign as f64)
}

/// Build the exact choice at parameters `t` (rounded to rationals so that
/// the restricted Hessian keeps its sign) and `K` (rational).
fn exact_choice(
    variation: &SecondVariation,
    sign: i8,
    t: &[f64],
    k: &Matrix,
    relative_margin: f64,
) -> Option<CasimirChoice> {
    let mut t_rational: Option<Vec<Rational>> = None;
    // Fine denominators: near the optimum Sigma^2 is quadratic in t, and a
    // coarse rounding would cost more than the tolerance.
    for denominator in [1u64 << 24, 1 << 32, 1 << 40, 1 << 48] {
        let cand: Option<Vec<Rational>> = t
            .iter()
            .map(|&x| if x == 0.0 { Some(Rational::zero()) } else { best_rational_approximation(x, denominator) })
            .collect();
        let Some(cand) = cand else { continue };
        let r = variation.restricted(&variation.family.at(&cand));
        if r.nrows() == 0 || r.is_definite_with_sign(sign) {
            t_rational = Some(cand);
            break;
        }
    }
    let t_rational = t_rational?;
    let multipliers = variation.family.at(&t_rational);
    let r = variation.num_conserved();
    let cols = &variation.range_columns;
    let mut m = Matrix::zeros(r, r);
    for (a, &ca) in cols.iter().enumerate() {
        for (b, &cb) in cols.iter().enumerate() {
            m[(ca, cb)] = k[(a, b)].clone();
        }
    }
    let p = variation.second_variation(&multipliers, &m);
    p.is_definite_with_sign(sign).then_some(CasimirChoice {
        sign,
        family_parameters: t_rational,
        multipliers,
        m,
        p,
        relative_margin,
    })
}

/// Minimise `Sigma^2` over the Casimir freedom, starting from a definite
/// choice. Returns `None` only if no better-or-equal exact choice could be
/// built (then the first choice stands).
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
    let n = variation.dim();
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
    let y = Matrix::from_fn(n, rk, |i, j| variation.gradients[(i, cols[j])].clone());
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
        // Restricted problem on ker G^T over t.
        let z = &variation.kernel;
        let zt = z.transpose();
        let restrict = |m: &Matrix| zt.mul(m).mul(z);
        let pencil = AffinePencil {
            p0: signed(&restrict(&base0), sign),
            q0: signed(&restrict(&lq(&base0)), sign),
            p_dirs: t_dirs.iter().map(|d| signed(&restrict(d), sign)).collect(),
            q_dirs: t_dirs.iter().map(|d| signed(&restrict(&lq(d)), sign)).collect(),
        };
        let (t_best, infimum) = if z.ncols() == 0 {
            // Every direction is a conserved-gradient direction: K -> infinity
            // drives Sigma^2 to the floor.
            (t0.clone(), 0.0)
        } else {
            let radius = 10.0 * (t0.iter().map(|x| x * x).sum::<f64>().sqrt() + 1.0);
            let (t, v) = pencil.minimise(&t0, radius, settings.max_iterations);
            (t, v.max(0.0))
        };
        if f == 0 && first_growth.sigma2 <= infimum * (1.0 + 1e-12) + 1e-15 {
            // The first choice already attains the infimum: nothing to rebuild.
            return Some(Optimum {
                choice: first.clone(),
                growth: first_growth.clone(),
                infimum,
                attained: true,
                within_tolerance: true,
                q_depends_on_m,
                method: "restricted to ker G^T (no free multipliers); the first choice attains it",
            });
        }
        // Grow K until lambda_max is within the tolerance of the infimum.
        // Within `tolerance` of the infimum, relative to the larger of the
        // infimum and the first choice's constant (so an infimum of 0, which
        // is only approached, is certified to tolerance * first_sigma2).
        let target = infimum + settings.tolerance * infimum.max(first_growth.sigma2);
        let mut scale = Rational::from(1);
        let mut best: Option<(CasimirChoice, GrowthConstant)> = None;
        // With no independent conserved gradient there is no K to grow.
        let doublings = if rk == 0 { 1 } else { settings.max_doublings };
        let mut stalled = 0;
        for _ in 0..doublings {
            let k = k_first.scale(&scale);
            if let Some(choice) = exact_choice(variation, sign, &t_best, &k, first.relative_margin) {
                // Beyond a condition number of 1e8 floating point can no
                // longer resolve P (the fastest direction, lambda_max): stop
                // and keep the best so far; the certificate says the
                // tolerance was not reached.
                if condition_number(&signed(&choice.p, sign)) > 1e8 && best.is_some() {
                    break;
                }
                let q = lq(&choice.p);
                if let Ok(g) = growth_constant(&choice.p, &q, sign) {
                    let done = g.sigma2 <= target;
                    // Improvements below 1e-9 relative are round-off: growing K
                    // further only ruins the conditioning of P.
                    let improves = best.as_ref().is_none_or(|(_, b)| g.sigma2 < b.sigma2 * (1.0 - 1e-9));
                    if improves {
                        best = Some((choice, g));
                        stalled = 0;
                    } else {
                        stalled += 1;
                    }
                    if done || stalled >= 3 {
                        break;
                    }
                }
            }
            scale *= Rational::from(2);
        }
        let (choice, growth) = best?;
        if growth.sigma2 > first_growth.sigma2 {
            return None;
        }
        let attained = growth.sigma2 <= infimum * (1.0 + 1e-12) + 1e-15;
        let within_tolerance = growth.sigma2 <= target;
        let method = if f == 0 {
            "restricted to ker G^T (no free multipliers)"
        } else {
            "restricted to ker G^T, ellipsoid over t"
        };
        return Some(Optimum { choice, growth, infimum, attained, within_tolerance, q_depends_on_m, method });
    }

    // General case: Q depends on K. Minimise over theta = (t, K entries).
    let p0 = base0;
    let mut p_dirs: Vec<DMatrix<f64>> = t_dirs.iter().map(|d| signed(d, sign)).collect();
    let mut q_dirs: Vec<DMatrix<f64>> = t_dirs.iter().map(|d| signed(&lq(d), sign)).collect();
    for (_, _, d) in &k_dirs {
        p_dirs.push(signed(d, sign));
        q_dirs.push(signed(&lq(d), sign));
    }
    let pencil = AffinePencil { p0: signed(&p0, sign), q0: signed(&lq(&p0), sign), p_dirs, q_dirs };
    let mut theta0 = t0.clone();
    for (a, b, _) in &k_dirs {
        theta0.push(exact::rational_to_f64(&k_first[(*a, *b)]));
    }
    let mut radius = 10.0 * (theta0.iter().map(|x| x * x).sum::<f64>().sqrt() + 1.0);
    let mut start = theta0.clone();
    let mut best = (theta0.clone(), pencil.value(&theta0).unwrap_or(f64::INFINITY));
    let mut on_boundary = false;
    for _ in 0..4 {
        let (theta, v) = pencil.minimise(&start, radius, settings.max_iterations);
        if v < best.1 {
            best = (theta.clone(), v);
        }
        let dist = theta.iter().zip(&start).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt();
        on_boundary = dist > 0.9 * radius;
        if !on_boundary || v <= 0.0 {
            break;
        }
        start = theta;
        radius *= 100.0;
    }
    let (theta, infimum) = (best.0, best.1.max(0.0));
    let t = &theta[..f];
    let mut k = Matrix::zeros(rk, rk);
    for (i, (a, b, _)) in k_dirs.iter().enumerate() {
        let x = theta[f + i];
        let r = if x == 0.0 {
            Rational::zero()
        } else {
            best_rational_approximation(x, 1 << 40).or_else(|| decimal_at_least(x, 12))?
        };
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
        q_depends_on_m,
        method: "ellipsoid over (t, M)",
    })
}
