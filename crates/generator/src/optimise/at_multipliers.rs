//! The construction at fixed rational multipliers: the restricted
//! `lambda_max` (the infimum over `K`), a certified lower bound from a
//! rational vector of `ker G^T`, and `K` built as a Schur complement
//! ([`super::FramePencil::k_for`]) for targets just above the infimum.

use super::{
    approach_infimum, congruent, exact_choice, orthonormalising, top_generalized, Approach, Forms, FramePencil,
    OptimiseSettings, Optimum,
};
use crate::bound::InfimumWitness;
use crate::form::GeneratorForm;
use crate::growth::{condition_number, growth_constant, GrowthConstant};
use casimir::{CasimirChoice, SecondVariation, Sign};
use exact::{Matrix, Rational};
use nalgebra::{DMatrix, DVector};
use num_traits::Zero;

/// An exact choice with its generator form and growth constant.
type Built = (CasimirChoice, GeneratorForm, GrowthConstant);

/// What the construction of `K` gives at fixed rational multipliers.
pub(super) struct AtMultipliers {
    /// The restricted `lambda_max` at these multipliers (the infimum over
    /// `K`); `-inf` when `ker G^T` is trivial.
    pub(super) restricted_max: f64,
    /// A certified lower bound on `lambda_max` for every `K` at these
    /// multipliers, with its witness in the algebra's coordinates.
    witness: Option<(Rational, Vec<Rational>)>,
    /// The exact choice built, if any, with its form: it has `cond(P)`
    /// within the limit (only such a choice is kept).
    pub(super) best: Option<Built>,
}

impl AtMultipliers {
    /// `Sigma^2` of the choice built (infinite without one).
    pub(super) fn sigma2(&self) -> f64 {
        self.best.as_ref().map_or(f64::INFINITY, |b| b.2.sigma2)
    }

    /// The optimum over the family, given the infimum estimate over the
    /// multipliers (`on_edge`: the search ran to the edge of its region, so
    /// the infimum may be lower still).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn into_optimum(
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
pub(super) fn at_multipliers(
    variation: &SecondVariation,
    forms: &Forms,
    first: &CasimirChoice,
    first_growth: &GrowthConstant,
    t_rational: &[Rational],
    cond_limit: f64,
    settings: &OptimiseSettings,
) -> Option<AtMultipliers> {
    let sign = first.sign;
    let blocks = Blocks::at(variation, forms, sign, t_rational);
    // The restricted lambda_max: the infimum over K at these multipliers
    // (K -> infinity along the conserved directions leaves only ker G^T).
    let (restricted_max, top) = if variation.kernel.ncols() == 0 {
        (f64::NEG_INFINITY, None)
    } else {
        let (l, v) = top_generalized(&blocks.pz, &blocks.qz).ok()?;
        (l, Some(v))
    };
    // A certified lower bound for every K at these multipliers: the exact
    // Rayleigh quotient of a rational vector of ker G^T.
    let witness = top.as_ref().filter(|_| variation.family.directions.is_empty()).and_then(|v| {
        rayleigh_lower_bound(
            (&blocks.base, &blocks.b_f),
            (&blocks.base_form.q, &blocks.q_f),
            sign,
            (&variation.kernel, &blocks.z_f),
            &(&blocks.r_inv * v),
        )
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
    let frame = blocks.frame_pencil(variation, sign)?;
    let y_f = variation.independent_gradients().to_dmatrix();
    let construction =
        Construction { variation, forms, first, t_rational, blocks: &blocks, frame, y_f, cond_limit, infimum, scale };
    let best = construction.best(restricted_max, first_growth.sigma2, settings.tolerance);
    Some(AtMultipliers { restricted_max, witness, best })
}

/// The floating-point blocks at fixed multipliers: `sB(t)`, `sQ(t)` and
/// their compressions to `ker G^T` in orthonormal coordinates.
struct Blocks {
    /// The multipliers `lambda(t)`.
    multipliers: Vec<Rational>,
    /// `B(t)`, exactly.
    base: Matrix,
    /// The generator form of `B(t)`, exactly.
    base_form: GeneratorForm,
    /// `sB(t)`.
    b_f: DMatrix<f64>,
    /// `sQ(t)`.
    q_f: DMatrix<f64>,
    /// The kernel basis `Z`.
    z_f: DMatrix<f64>,
    /// The complement basis `W`.
    w_f: DMatrix<f64>,
    /// `R^{-1}`, with `Z R^{-1}` orthonormal.
    r_inv: DMatrix<f64>,
    /// `Z R^{-1}`.
    zo: DMatrix<f64>,
    /// The compression of `sB` to `ker G^T`.
    pz: DMatrix<f64>,
    /// The compression of `sQ` to `ker G^T`.
    qz: DMatrix<f64>,
}

impl Blocks {
    /// `sB(t)`, `sQ(t)` and their compressions `Pz`, `Qz`.
    fn at(variation: &SecondVariation, forms: &Forms, sign: Sign, t_rational: &[Rational]) -> Self {
        let multipliers = variation.family.at(t_rational);
        let base = variation.base(&multipliers);
        let base_form = (forms.at)(t_rational);
        let s = sign.as_f64();
        // The frame blocks in floating point (everything here is a floating-point
        // screen; only the K finally chosen is made exact, and the witness below
        // is evaluated exactly in the algebra's coordinates).
        let b_f = base.to_dmatrix() * s;
        let q_f = base_form.q.to_dmatrix() * s;
        let z_f = variation.kernel.to_dmatrix();
        let w_f = variation.complement().to_dmatrix();
        // Orthonormal coordinates of ker G^T (Z R^{-1}): K1 below is invariant
        // under a change of basis of ker G^T, its rounding is not.
        let r_inv = orthonormalising(&variation.kernel);
        let zo = &z_f * &r_inv;
        let pz = congruent(&b_f, &zo);
        let qz = congruent(&q_f, &zo);
        Blocks { multipliers, base, base_form, b_f, q_f, z_f, w_f, r_inv, zo, pz, qz }
    }

    /// The pair `(sP, sQ)` in the frame `[Z R^{-1}, W]`, with the Schur
    /// bound `K0'` and the conserved margin `D`.
    fn frame_pencil(&self, variation: &SecondVariation, sign: Sign) -> Option<FramePencil> {
        let (b_f, q_f, zo, w_f) = (&self.b_f, &self.q_f, &self.zo, &self.w_f);
        let pz = self.pz.clone();
        let pzw = zo.transpose() * b_f * w_f;
        let pw = congruent(b_f, w_f);
        let k0 = if variation.kernel.ncols() == 0 {
            -&pw
        } else {
            let ch = pz.clone().cholesky()?;
            pzw.transpose() * ch.solve(&pzw) - &pw
        };
        let margin = casimir::conserved_margin(variation, &self.multipliers, sign)?.to_dmatrix();
        Some(FramePencil {
            pz,
            pzw,
            pw,
            qz: self.qz.clone(),
            qzw: zo.transpose() * q_f * w_f,
            qw: congruent(q_f, w_f),
            k0,
            margin,
        })
    }
}

/// `K` for targets `S = infimum + delta` at fixed multipliers, screened in
/// floating point and made exact.
struct Construction<'a> {
    variation: &'a SecondVariation,
    forms: &'a Forms<'a>,
    first: &'a CasimirChoice,
    t_rational: &'a [Rational],
    blocks: &'a Blocks,
    frame: FramePencil,
    /// The independent conserved gradients `Y`.
    y_f: DMatrix<f64>,
    /// The largest `cond(P)` accepted.
    cond_limit: f64,
    /// The infimum over `K` (the restricted `lambda_max`, floored at 0).
    infimum: f64,
    /// The scale of `Sigma^2`.
    scale: f64,
}

impl Construction<'_> {
    /// `max(0, lambda_max(sQ, sP))` and `cond(sP)` for `sP = sB + Y K' Y^T`.
    ///
    /// Everything is screened in floating point first (sP = sB + Y K' Y^T,
    /// and sQ = sQ(B) since Q does not depend on K); only a K that passes the
    /// screen is made exact, so the search costs a few small dense
    /// eigenproblems per step instead of exact congruences.
    fn screen(&self, kp: &DMatrix<f64>) -> Option<(f64, f64)> {
        let p = &self.blocks.b_f + &self.y_f * kp * self.y_f.transpose();
        let p = (&p + p.transpose()) * 0.5;
        let (l, _) = top_generalized(&p, &self.blocks.q_f).ok()?;
        Some((l.max(0.0), condition_number(&p)))
    }

    /// Passes the screen: conditioned and within `allowed` of the infimum, up
    /// to the round-off a condition number `c` allows.
    fn passes(&self, (sigma2, c): (f64, f64), allowed: f64) -> bool {
        c <= 1.1 * self.cond_limit && sigma2 <= self.infimum + allowed + c * 1e-15 * self.scale
    }

    /// The exact choice for the target `infimum + delta`, if one passes the
    /// screen and is conditioned and within `allowed` exactly.
    fn build(&self, delta: f64, allowed: f64) -> Option<Built> {
        let kp = self.frame.k_for(self.infimum + delta, delta == 0.0)?;
        if !self.screen(&kp).is_some_and(|v| self.passes(v, allowed)) {
            return None;
        }
        self.exact(&kp, allowed)
    }

    /// K' rounded to the fewest digits (3, 6, 9, then 15) that pass the
    /// screen (short numbers in the certificate), made exact; the exact P
    /// must be definite, conditioned and within `allowed`.
    fn exact(&self, kp: &DMatrix<f64>, allowed: f64) -> Option<Built> {
        let sign = self.first.sign;
        let s = sign.as_f64();
        for digits in [3u32, 6, 9, 15] {
            let Some(entries) =
                kp.iter().map(|&x| exact::decimal_near(x * s, digits)).collect::<Option<Vec<Rational>>>()
            else {
                continue;
            };
            // Column-major, as nalgebra stores kp.
            let k_short = Matrix::from_fn(kp.nrows(), kp.ncols(), |i, j| entries[j * kp.nrows() + i].clone());
            let k_float = k_short.to_dmatrix() * s;
            if digits < 15 && !self.screen(&k_float).is_some_and(|v| self.passes(v, allowed)) {
                continue;
            }
            let Some(choice) =
                exact_choice(self.variation, sign, self.t_rational.to_vec(), &k_short, self.first.relative_margin)
            else {
                continue;
            };
            // Q does not depend on K: the form of B(t) serves.
            let Ok(growth) = growth_constant(&choice.p, &self.blocks.base_form.q, sign) else { continue };
            if growth.condition_number <= self.cond_limit
                && growth.sigma2 <= self.infimum + allowed + 1e-13 * self.scale
            {
                let form = self.forms.of(&self.blocks.base_form, &choice.p);
                return Some((choice, form, growth));
            }
        }
        None
    }

    /// The best choice: at the infimum itself when it is positive, else for
    /// targets approaching it (below the first choice's `ceiling`).
    fn best(&self, restricted_max: f64, ceiling: f64, tolerance: f64) -> Option<Built> {
        let (infimum, scale) = (self.infimum, self.scale);
        // delta = 0 first: when the infimum is attained, S = lambda_max itself
        // (exactly singular S P - Q: a sharp certificate).
        let best = if restricted_max > 0.0 { self.build(0.0, 1e-12 * scale) } else { None };
        best.or_else(|| {
            let condition_at =
                |delta: f64| self.frame.k_for(infimum + delta, false).and_then(|kp| self.screen(&kp)).map(|v| v.1);
            approach_infimum(
                Approach { infimum, ceiling, scale, tolerance, cond_limit: self.cond_limit },
                |delta| self.build(delta, 2.0 * delta + 1e-12 * scale),
                condition_at,
            )
        })
    }
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
