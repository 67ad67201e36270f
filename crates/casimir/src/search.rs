//! Search over the Casimir freedom for a definite second variation.
//!
//! The free data are the family parameters `t` (multipliers
//! `lambda(t) = lambda0 + N t`) and the symmetric matrix `M`. By Finsler's
//! lemma a definite `P` exists for some `M` iff the restricted Hessian
//! `R(t) = Z^T (D^2h + sum lambda_j(t) D^2K_j) Z` is definite, and `R` is affine
//! in `t`, so `phi_s(t) = lambda_min(s R(t))` (`s = ±1`) is concave. We
//! maximise it with the central-cut ellipsoid method (bisection in one
//! dimension), which converges to the global maximum of a concave function
//! inside the search ball; the ball grows if the maximiser sits on its edge.
//! Then `M` completes the Schur complement exactly (see `choose_m`): once
//! the rounded restricted Hessian is exactly definite, so is `P`.

use crate::ellipsoid::Ellipsoid;
use crate::variation::SecondVariation;
use exact::{best_rational_approximation, decimal_near, Matrix, Rational};
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use num_traits::{One, Zero};
pub use outcome::Sign;

/// Settings of the search, with documented defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct SearchSettings {
    /// A restricted Hessian counts as definite only if its smallest
    /// eigenvalue (of `s R`) exceeds this fraction of its largest absolute
    /// eigenvalue. Default `1e-9`: closer to singular than that is reported as
    /// not definite (the verdict becomes inconclusive, never a false claim).
    pub definiteness_tolerance: f64,
    /// Iterations of the ellipsoid method per ball radius. Default 200.
    pub max_iterations: usize,
    /// How many times the search ball may grow by a factor 100. Default 4.
    pub max_expansions: usize,
    /// Largest denominator used when rounding the chosen family parameters
    /// to rationals. Default 10^6.
    pub max_denominator: u64,
}

impl Default for SearchSettings {
    fn default() -> Self {
        SearchSettings {
            definiteness_tolerance: 1e-9,
            max_iterations: 200,
            max_expansions: 4,
            max_denominator: 1_000_000,
        }
    }
}

/// A choice of Casimir freedom that makes `P` definite.
#[derive(Clone, Debug, PartialEq)]
pub struct CasimirChoice {
    /// Whether `P` is positive or negative definite.
    pub sign: Sign,
    /// The family parameters `t`.
    pub family_parameters: Vec<Rational>,
    /// The multipliers `lambda(t)`.
    pub multipliers: Vec<Rational>,
    /// The symmetric matrix `M` (`r × r`), the Hessian of the Casimir function.
    pub m: Matrix,
    /// `P = D^2h + sum lambda_j D^2K_j + G M G^T`, exactly.
    pub p: Matrix,
    /// `lambda_min(s R) / max|eig(R)|` at the choice (the Finsler margin).
    pub relative_margin: f64,
}

/// Result of [`find_definite_choice`].
#[derive(Clone, Debug, PartialEq)]
pub enum SearchOutcome {
    /// A definite `P` was found and confirmed exactly.
    Definite(CasimirChoice),
    /// No definite choice was found.
    NotFound {
        /// Best relative margin `max_t lambda_min(s R(t)) / |R(t)|` for `s = +1`.
        best_positive_margin: f64,
        /// The same for `s = -1`.
        best_negative_margin: f64,
        /// Dimension of `ker G^T`.
        restricted_dimension: usize,
    },
}

impl SearchOutcome {
    /// The choice, if one was found.
    pub fn definite(&self) -> Option<&CasimirChoice> {
        match self {
            SearchOutcome::Definite(c) => Some(c),
            SearchOutcome::NotFound { .. } => None,
        }
    }
}

/// Symmetric eigen-decomposition with an iteration limit (nalgebra's default
/// has none), `None` if it does not converge or the input is not finite.
pub(crate) fn symmetric_eigen(m: DMatrix<f64>) -> Option<SymmetricEigen<f64, nalgebra::Dyn>> {
    if m.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let limit = 1000 * (m.nrows() + 1);
    SymmetricEigen::try_new(m, f64::EPSILON, limit)
}

/// Smallest eigenvalue, its eigenvector, and the largest absolute eigenvalue;
/// `-inf` (never definite) if the eigen-solve fails.
fn symmetric_extremes(m: &DMatrix<f64>) -> (f64, DVector<f64>, f64) {
    if m.nrows() == 0 {
        // The empty form is vacuously definite.
        return (f64::INFINITY, DVector::zeros(0), 0.0);
    }
    let Some(eig) = symmetric_eigen(m.clone()) else {
        return (f64::NEG_INFINITY, DVector::zeros(m.nrows()), f64::INFINITY);
    };
    let mut imin = 0;
    for i in 1..eig.eigenvalues.len() {
        if eig.eigenvalues[i] < eig.eigenvalues[imin] {
            imin = i;
        }
    }
    let max_abs = eig.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    (eig.eigenvalues[imin], eig.eigenvectors.column(imin).into_owned(), max_abs)
}

/// The affine pencil `R(u) = R0 + sum_i u_i R_i` with the `R_i` normalised.
struct Pencil {
    r0: DMatrix<f64>,
    ri: Vec<DMatrix<f64>>,
    scales: Vec<f64>,
}

impl Pencil {
    fn at(&self, u: &[f64]) -> DMatrix<f64> {
        let mut r = self.r0.clone();
        for (ui, ri) in u.iter().zip(&self.ri) {
            r += ri * *ui;
        }
        r
    }

    /// `phi(u) = lambda_min(s R(u))`, the relative margin and a supergradient.
    fn evaluate(&self, sign: f64, u: &[f64]) -> (f64, f64, Vec<f64>) {
        let r = self.at(u) * sign;
        let (lmin, v, max_abs) = symmetric_extremes(&r);
        let grad = self.ri.iter().map(|ri| sign * (v.transpose() * ri * &v)[(0, 0)]).collect();
        let rel = if max_abs > 0.0 { lmin / max_abs } else { 0.0 };
        (lmin, rel, grad)
    }

    /// Maximise `lambda_min(s R(u))` over the ball `|u| <= radius`, returning
    /// the best point, its value and relative margin.
    fn maximise(&self, sign: f64, radius: f64, iterations: usize) -> (Vec<f64>, f64, f64) {
        let f = self.ri.len();
        let mut best_u = vec![0.0; f];
        let (mut best, mut best_rel, _) = self.evaluate(sign, &best_u);
        if f == 0 {
            return (best_u, best, best_rel);
        }
        let mut ellipsoid = Ellipsoid::ball(&vec![0.0; f], radius);
        for _ in 0..iterations {
            let c = ellipsoid.centre().to_vec();
            let norm_c = c.iter().map(|x| x * x).sum::<f64>().sqrt();
            // Keep {x : g . (x - c) >= 0}: towards the ball, or up the supergradient.
            let g: Vec<f64> = if norm_c > radius {
                c.iter().map(|x| -x / norm_c).collect()
            } else {
                let (value, rel, g) = self.evaluate(sign, &c);
                if value > best {
                    best = value;
                    best_rel = rel;
                    best_u = c.clone();
                }
                g
            };
            if !ellipsoid.cut(&g) || ellipsoid.size() < 1e-13 * radius {
                break;
            }
        }
        (best_u, best, best_rel)
    }
}

/// The restricted `lambda_max` at rational family parameters.
pub type Objective<'a> = dyn Fn(&[Rational]) -> Option<f64> + 'a;

/// Round the family parameters `t` to rationals, the first candidate that
/// keeps the exact restricted Hessian definite with the sign and (when an
/// objective is given) does not raise it above `limit`: first the simplest
/// rationals within `1e-9` of each entry (relative to `1 + |t_i|` in units
/// of the normalised direction: an optimum at a simple rational, as in the
/// closed-form examples, is found exactly), with an objective also those
/// within `1e-6` with denominators up to 1000 (a minimiser is located only
/// to about the square root of the rounding), then decimals of 8, 12, 15
/// and 17 significant digits (relative, so independent of how the conserved
/// quantities are scaled). `units` are the sizes of the family directions
/// (a parameter is compared in units of its direction); simple rationals
/// have denominators at most `max_denominator`.
pub fn round_family_parameters(
    variation: &SecondVariation,
    sign: Sign,
    t: &[f64],
    units: &[f64],
    max_denominator: u64,
    objective: Option<(&Objective, f64)>,
) -> Option<Vec<Rational>> {
    let simple = |denominator: u64, tolerance: f64| -> Option<Vec<Rational>> {
        t.iter()
            .zip(units)
            .map(|(&x, &unit)| {
                let r = if x == 0.0 { Rational::zero() } else { best_rational_approximation(x, denominator)? };
                ((exact::rational_to_f64(&r) - x).abs() * unit <= tolerance * (1.0 + x.abs() * unit)).then_some(r)
            })
            .collect()
    };
    let decimal = |digits: u32| t.iter().map(|&x| exact::decimal_near(x, digits)).collect::<Option<Vec<Rational>>>();
    // A minimiser of a smooth objective is found only to about the square
    // root of the rounding (the objective is flat there): with an
    // objective to guard the value, simple rationals (denominators up to
    // 1000) within 1e-6 are tried too, and kept only if they do not raise it.
    let loose = objective.is_some().then_some([1u64, 10, 100, 1000]).into_iter().flatten();
    let candidates = [1u64, 10, 100, 1000, 10_000, 100_000, 1_000_000]
        .into_iter()
        .filter(|&d| d <= max_denominator.max(1))
        .filter_map(|d| simple(d, 1e-9))
        .chain(loose.filter(|&d| d <= max_denominator.max(1)).filter_map(|d| simple(d, 1e-6)))
        .chain([8u32, 12, 15, 17].into_iter().filter_map(decimal));
    for candidate in candidates {
        let r = variation.restricted(&variation.family.at(&candidate));
        if r.nrows() > 0 && !r.is_definite_with_sign(sign) {
            continue;
        }
        match &objective {
            Some((f, limit)) if f(&candidate).is_none_or(|v| v > *limit) => continue,
            _ => return Some(candidate),
        }
    }
    None
}

/// Find multipliers and `M` that make the second variation definite.
///
/// Tries both signs; when both are possible the positive one is returned.
/// The returned `P` has been confirmed definite exactly (rational LDLᵀ), and
/// the restricted Hessian's relative margin exceeds
/// [`SearchSettings::definiteness_tolerance`].
pub fn find_definite_choice(variation: &SecondVariation, settings: &SearchSettings) -> SearchOutcome {
    let family = &variation.family;
    let f = family.directions.len();
    let zero_t = vec![Rational::zero(); f];
    // Without free multipliers the frame blocks at the particular solution
    // give both the restricted Hessian and, later, the Schur bound.
    let blocks = (f == 0).then(|| variation.frame_blocks(&variation.base(&family.particular)));
    let r0 = match &blocks {
        Some((bzz, _, _)) => bzz.clone(),
        None => variation.restricted(&family.particular),
    };
    let k = r0.nrows();
    // R(t) - R(0) is linear in t; the pencil matrices are R(e_i) - R(0).
    let raw: Vec<Matrix> = (0..f)
        .map(|i| {
            let mut t = zero_t.clone();
            t[i] = Rational::one();
            variation.restricted(&family.at(&t)).sub(&r0)
        })
        .collect();
    // In orthonormal coordinates of ker G^T, so the margins do not depend
    // on the kernel basis nor on how the conserved quantities are scaled.
    // The exact forms are rounded once, in the well-conditioned kernel
    // basis (see `SecondVariation::orthonormal`): a form restricted with a
    // badly scaled basis (`(-1/a, 1, 0)`, `(-1/a, 0, 1)`) and rounded has
    // lost its O(1) eigenvalues before any whitening.
    let raw: Vec<DMatrix<f64>> = raw.iter().map(|m| variation.orthonormal(m)).collect();
    let r0f = variation.orthonormal(&r0);
    let scales: Vec<f64> = raw.iter().map(|m| m.norm().max(f64::MIN_POSITIVE)).collect();
    let pencil = Pencil { r0: r0f.clone(), ri: raw.iter().zip(&scales).map(|(m, s)| m / *s).collect(), scales };
    let base_radius = 4.0 * r0f.norm().max(1.0);

    let mut margins = [f64::NEG_INFINITY; 2];
    let mut found: Option<(Sign, Vec<f64>, f64)> = None;
    for (slot, sign) in [(0usize, Sign::Positive), (1, Sign::Negative)] {
        if found.is_some() {
            break; // the positive sign is preferred when both are possible
        }
        let mut radius = base_radius;
        let mut best = (vec![0.0; f], f64::NEG_INFINITY, f64::NEG_INFINITY);
        for _ in 0..=settings.max_expansions {
            let (u, value, rel) = pencil.maximise(sign.as_f64(), radius, settings.max_iterations);
            if value > best.1 {
                best = (u, value, rel);
            }
            let norm_u = best.0.iter().map(|x| x * x).sum::<f64>().sqrt();
            if f == 0 || best.2 > settings.definiteness_tolerance || norm_u < 0.5 * radius {
                break;
            }
            radius *= 100.0;
        }
        margins[slot] = if k == 0 { 1.0 } else { best.2 };
        if found.is_none() && margins[slot] > settings.definiteness_tolerance {
            let t: Vec<f64> = best.0.iter().zip(&pencil.scales).map(|(u, s)| u / s).collect();
            found = Some((sign, t, margins[slot]));
        }
    }
    let not_found = || SearchOutcome::NotFound {
        best_positive_margin: margins[0],
        best_negative_margin: margins[1],
        restricted_dimension: k,
    };
    let Some((sign, t, relative_margin)) = found else {
        return not_found();
    };
    let t_rational = if f == 0 {
        // Nothing to round: confirm the restricted Hessian's sign exactly.
        if k > 0 && r0.definiteness() != Some(sign) {
            return not_found();
        }
        vec![]
    } else {
        match round_family_parameters(variation, sign, &t, &pencil.scales, settings.max_denominator, None) {
            Some(t) => t,
            None => return not_found(),
        }
    };
    let multipliers = family.at(&t_rational);
    match choose_m(variation, &multipliers, sign, blocks.as_ref()) {
        Some((m, p)) => SearchOutcome::Definite(CasimirChoice {
            sign,
            family_parameters: t_rational,
            multipliers,
            m,
            p,
            relative_margin,
        }),
        None => not_found(),
    }
}

/// The natural size of the level-set block: `sqrt(l_min l_max)` of the
/// pencil `(s B_zz, Z^T Z)`, the Euclidean Rayleigh quotients of `s B` on
/// `ker G^T` (so it does not depend on how `Z` is written, nor on how the
/// conserved quantities are scaled); `|B|_2` (or 1) when `ker G^T = 0`.
/// The Casimir function adds this size along the conserved directions, so
/// `P` is as well conditioned as the level-set block allows. `B_zz` is
/// formed exactly and rounded once in orthonormal coordinates
/// ([`SecondVariation::orthonormal`]).
pub fn level_scale(variation: &SecondVariation, multipliers: &[Rational], sign: Sign) -> f64 {
    let fallback = || {
        let base = variation.base(multipliers).to_dmatrix();
        let norm =
            symmetric_eigen(base).map(|e| e.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b.abs()))).unwrap_or(1.0);
        if norm.is_finite() && norm > 0.0 {
            norm
        } else {
            1.0
        }
    };
    if variation.kernel.ncols() == 0 {
        return fallback();
    }
    let r = variation.orthonormal(&variation.restricted(multipliers)) * sign.as_f64();
    let Some(e) = symmetric_eigen(r) else { return fallback() };
    let lo = e.eigenvalues.iter().fold(f64::INFINITY, |a, &b| a.min(b));
    let hi = e.eigenvalues.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
    let c = (lo.max(0.0) * hi.max(0.0)).sqrt();
    if c.is_finite() && c > 0.0 {
        c
    } else {
        fallback()
    }
}

/// `D = c (Y^T Y)^{-1}` with `c` the [`level_scale`] rounded to three
/// digits: adding `Y (s D) Y^T` to `P` adds `c |v|^2` along the conserved
/// directions (the Euclidean norm of the part of `v` in the range of `G`).
pub fn conserved_margin(variation: &SecondVariation, multipliers: &[Rational], sign: Sign) -> Option<Matrix> {
    let c = decimal_near(level_scale(variation, multipliers, sign), 3)?;
    Some(variation.gram_inverse().scale(&c))
}

/// `K` rounded to `digits` significant digits (short numbers in the
/// certificate).
pub fn short_entries(k: &Matrix, digits: u32) -> Option<Matrix> {
    let mut out = k.clone();
    for i in 0..k.nrows() {
        for j in 0..k.ncols() {
            out[(i, j)] = decimal_near(exact::rational_to_f64(&k[(i, j)]), digits)?;
        }
    }
    Some(out)
}

/// The Casimir Hessian by exact Schur completion: `K = K0 + s D` with `K0`
/// the [`SecondVariation::schur_bound`] and `D` the [`conserved_margin`], so
/// `s (K - K0) = D ≻ 0` and `P` is definite *exactly* whenever the
/// restricted Hessian `s B_zz` is (which the caller has confirmed). No
/// search over a scale `mu`: a definite form found in floating point is
/// never lost here. The same `K` rounded to 3, 6, 9 and 15 digits is tried
/// first and kept when it is still definite (short numbers).
///
/// `blocks` are the [`SecondVariation::frame_blocks`] of `B` at these
/// multipliers when the caller has them.
fn choose_m(
    variation: &SecondVariation,
    multipliers: &[Rational],
    sign: Sign,
    blocks: Option<&(Matrix, Matrix, Matrix)>,
) -> Option<(Matrix, Matrix)> {
    let r = variation.num_conserved();
    if variation.range_columns.is_empty() {
        let base = variation.base(multipliers);
        let m = Matrix::zeros(r, r);
        return base.is_definite_with_sign(sign).then_some((m, base));
    }
    let k0 = match blocks {
        Some(b) => SecondVariation::schur_bound_of_blocks(b)?,
        None => variation.schur_bound(multipliers)?,
    };
    let d = conserved_margin(variation, multipliers, sign)?;
    let k_exact = if sign.is_positive() { k0.add(&d) } else { k0.sub(&d) };
    let mut candidates: Vec<Matrix> =
        [3u32, 6, 9, 15].into_iter().filter_map(|digits| short_entries(&k_exact, digits)).collect();
    candidates.push(k_exact);
    for k in candidates {
        let m = variation.m_from_k(&k);
        let p = variation.second_variation(multipliers, &m);
        if p.is_definite_with_sign(sign) {
            return Some((m, p));
        }
    }
    None
}
