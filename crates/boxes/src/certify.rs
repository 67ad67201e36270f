//! The box certificate: bisection of the box, a choice at each sub-box's
//! anchor, and an exact proof over the whole sub-box (docs/boxes.md).

use crate::bernstein::{matrix_positive_on_box, sign_on_box, ParamBox};
use crate::frac::{common_denominator, times_denominator, Frac};
use crate::symbolic::{matrix_at, specialise, value_at, BoxChoice, BoxSystem, BoxSystemError, Forms, Symbolic};
use exact::{Matrix, Poly, Rational};
use num_traits::Zero;
pub use outcome::BoxVerdict;
use outcome::{Sign, Verdict};

/// Bounds on the work and the margin of the growth bound.
#[derive(Clone, Debug, PartialEq)]
pub struct BoxSettings {
    /// Largest number of bisections from the whole box to a sub-box
    /// (default 12: a side of 1/64 of the box's in two parameters).
    pub max_depth: u32,
    /// Largest number of sub-boxes analysed (default 4096).
    pub max_boxes: usize,
    /// The bound `S` per sub-box is the largest sampled `Sigma^2` times
    /// `1 + margin` (default `1/1000`).
    pub margin: Rational,
    /// After the bisection, the stable sub-box with the largest bound is
    /// split while its bound exceeds the pipeline's `Sigma^2` at its worst
    /// sampled point by more than this factor minus 1 (default `1/100`).
    pub sup_tolerance: Rational,
}

impl Default for BoxSettings {
    fn default() -> Self {
        BoxSettings {
            max_depth: 12,
            max_boxes: 4096,
            margin: Rational::new(1.into(), 1000.into()),
            sup_tolerance: Rational::new(1.into(), 100.into()),
        }
    }
}

/// What is proved on one sub-box.
#[derive(Clone, Debug, PartialEq)]
pub enum LeafOutcome {
    /// `V = sign P` and `S V - sign Q` positive definite for every
    /// parameter in the sub-box: stable in probability with
    /// `Sigma^2 <= sigma2_upper`.
    Stable {
        /// The choice, fixed at the sub-box's anchor ([`ParamBox::anchor`]).
        choice: BoxChoice,
        /// The proved bound `S`.
        sigma2_upper: Rational,
        /// The largest `Sigma^2` sampled (corners and centre), in floating
        /// point, and where.
        sampled: f64,
        /// Where the largest sample was taken.
        sampled_at: Vec<Rational>,
    },
    /// `A` has an eigenvalue with positive real part for every parameter
    /// in the sub-box ([`prove_unstable`]).
    LinearlyUnstable {
        /// Which sign condition proves it.
        criterion: String,
    },
    /// `ad*_{Dh(mu_e)} mu_e` has a component of one strict sign on the
    /// whole sub-box ([`prove_excluded`]): `mu_e` is an equilibrium for no
    /// parameter in it.
    NotAnEquilibrium {
        /// Which component, and its sign.
        criterion: String,
    },
    /// `mu_e` is an equilibrium for every parameter, and some
    /// `ad*_{sigma_i} mu_e` has a component of one strict sign on the whole
    /// sub-box ([`prove_excluded`]): the noise moves `mu_e` at every
    /// parameter in it.
    NoiseIncompatible {
        /// Which field and component, and its sign.
        criterion: String,
    },
    /// Nothing is claimed.
    Undecided {
        /// Why.
        reason: String,
        /// The pointwise verdict at the sub-box's anchor
        /// ([`ParamBox::anchor`]), if analysed.
        anchor: Option<Verdict>,
    },
}

/// One sub-box of the final partition.
#[derive(Clone, Debug, PartialEq)]
pub struct Leaf {
    /// The sub-box.
    pub range: ParamBox,
    /// Bisections from the whole box.
    pub depth: u32,
    /// What is proved there.
    pub outcome: LeafOutcome,
}

/// The result of [`certify_box`].
#[derive(Clone, Debug)]
pub struct BoxReport {
    /// The verdict.
    pub verdict: BoxVerdict,
    /// One sentence.
    pub reason: String,
    /// The partition (empty only when the system is refused).
    pub leaves: Vec<Leaf>,
    /// Which bound stopped the bisection, if one did.
    pub limit: Option<&'static str>,
}

impl BoxReport {
    /// The largest proved bound over the stable sub-boxes.
    pub fn sup_sigma2(&self) -> Option<Rational> {
        self.leaves
            .iter()
            .filter_map(|l| match &l.outcome {
                LeafOutcome::Stable { sigma2_upper, .. } => Some(sigma2_upper.clone()),
                _ => None,
            })
            .max()
    }

    /// The volume of the undecided sub-boxes.
    pub fn undecided_volume(&self) -> Rational {
        self.leaves
            .iter()
            .filter(|l| matches!(l.outcome, LeafOutcome::Undecided { .. }))
            .fold(Rational::zero(), |acc, l| acc + l.range.volume())
    }

    /// The volume of the sub-boxes proved linearly unstable.
    pub fn unstable_volume(&self) -> Rational {
        self.leaves
            .iter()
            .filter(|l| matches!(l.outcome, LeafOutcome::LinearlyUnstable { .. }))
            .fold(Rational::zero(), |acc, l| acc + l.range.volume())
    }

    /// The volume of the sub-boxes proved not to hold an equilibrium or
    /// proved noise-incompatible.
    pub fn excluded_volume(&self) -> Rational {
        self.leaves.iter().filter(|l| l.outcome.is_excluded()).fold(Rational::zero(), |acc, l| acc + l.range.volume())
    }
}

impl LeafOutcome {
    /// Proved not an equilibrium or noise-incompatible.
    pub fn is_excluded(&self) -> bool {
        matches!(self, LeafOutcome::NotAnEquilibrium { .. } | LeafOutcome::NoiseIncompatible { .. })
    }

    /// What is proved on the sub-box, as a box verdict (never a `partly_`
    /// one).
    pub fn verdict(&self) -> BoxVerdict {
        match self {
            LeafOutcome::Stable { .. } => BoxVerdict::Stable,
            LeafOutcome::LinearlyUnstable { .. } => BoxVerdict::LinearlyUnstable,
            LeafOutcome::NotAnEquilibrium { .. } => BoxVerdict::NotAnEquilibrium,
            LeafOutcome::NoiseIncompatible { .. } => BoxVerdict::NoiseIncompatible,
            LeafOutcome::Undecided { .. } => BoxVerdict::Undecided,
        }
    }
}

/// Why a sub-box's proof failed.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ProofFailure {
    /// The choice gives no functional critical on the whole box.
    #[error(transparent)]
    Form(#[from] crate::symbolic::FormError),
    /// A denominator is not proved to keep one sign.
    #[error("a denominator is not proved nonzero on the sub-box")]
    Denominator,
    /// `V` is not proved positive definite.
    #[error("the second variation is not proved definite on the sub-box")]
    NotDefinite,
    /// `S V - Q` is not proved positive definite.
    #[error("Sigma^2 <= S is not proved on the sub-box")]
    Bound,
    /// `S` is negative.
    #[error("the bound S is negative")]
    NegativeBound,
}

/// Prove, exactly, that for every parameter in `range` the choice's
/// `V = sign P` is positive definite and (unless `Q` vanishes
/// identically) `S V - sign Q` is positive definite, so `Sigma^2 < S`.
/// Every denominator involved (of the multipliers, `V` and `Q`) is first
/// proved to keep one strict sign on the box, so the rational functions
/// are the pipeline's quantities at every point; then `V` and `Q` are
/// multiplied by their common denominator (its sign known) and the
/// polynomial matrices are proved definite by their Bernstein coefficient
/// matrices ([`crate::bernstein`]).
pub fn prove_leaf(sym: &Symbolic, range: &ParamBox, choice: &BoxChoice, s: &Rational) -> Result<Forms, ProofFailure> {
    if s.is_negative() {
        return Err(ProofFailure::NegativeBound);
    }
    let forms = sym.forms(choice)?;
    let n = sym.dim();
    // Every denominator in sight (the inputs', the multipliers', V's and
    // Q's) keeps one strict sign on the box: the functions are defined
    // everywhere there and are the pipeline's quantities.
    let entries = forms.multipliers.iter().chain(forms.v.iter().flatten()).chain(forms.q.iter().flatten());
    let mut signs: Vec<(Poly, Sign)> = Vec::new();
    for (f, _) in common_denominator(entries).iter().chain(sym.input_denominators()) {
        if signs.iter().any(|(g, _)| g == f) {
            continue;
        }
        let fs = sign_on_box(f, n, range).ok_or(ProofFailure::Denominator)?;
        signs.push((f.clone(), fs));
    }
    // The sign of the common denominator of V and Q, from its own exponents.
    let lcm = common_denominator(forms.v.iter().flatten().chain(forms.q.iter().flatten()));
    let mut sign = Sign::Positive;
    for (f, e) in &lcm {
        let fs = signs.iter().find(|(g, _)| g == f).map(|(_, s)| *s).ok_or(ProofFailure::Denominator)?;
        if fs == Sign::Negative && e % 2 == 1 {
            sign = if sign == Sign::Positive { Sign::Negative } else { Sign::Positive };
        }
    }
    let flip = |p: Poly| if sign == Sign::Negative { p.neg() } else { p };
    let v: Vec<Vec<Poly>> =
        forms.v.iter().map(|r| r.iter().map(|x| flip(times_denominator(x, &lcm))).collect()).collect();
    if !matrix_positive_on_box(&v, n, range) {
        return Err(ProofFailure::NotDefinite);
    }
    if !forms.q_zero {
        let q: Vec<Vec<Poly>> =
            forms.q.iter().map(|r| r.iter().map(|x| flip(times_denominator(x, &lcm))).collect()).collect();
        let bound: Vec<Vec<Poly>> =
            v.iter().zip(&q).map(|(vr, qr)| vr.iter().zip(qr).map(|(a, b)| a.scale(s).sub(b)).collect()).collect();
        if !matrix_positive_on_box(&bound, n, range) {
            return Err(ProofFailure::Bound);
        }
    }
    Ok(forms)
}

/// The strict sign of a rational function on the box: every denominator
/// factor and the numerator proved of one sign by their Bernstein
/// coefficients.
fn frac_sign(f: &Frac, n: usize, range: &ParamBox) -> Option<Sign> {
    let mut sign = sign_on_box(f.num(), n, range)?;
    for (g, e) in f.den() {
        if sign_on_box(g, n, range)? == Sign::Negative && e % 2 == 1 {
            sign = if sign == Sign::Positive { Sign::Negative } else { Sign::Positive };
        }
    }
    Some(sign)
}

/// Prove that for every parameter in `range` the drift `A` has an
/// eigenvalue with positive real part, from its characteristic polynomial
/// `c` ([`Symbolic::characteristic_polynomial`]); the criterion used, or
/// `None`.
///
/// The linearisation of a Lie–Poisson system at an equilibrium has a
/// spectrum symmetric under `x -> -x`; when the coefficients show it
/// (`c_i` identically zero unless `n - i` is even), `det(x I - A) =
/// x^r y^j g(y)` with `y = x^2` and `g` monic with `g(0)` not identically
/// zero. Every eigenvalue lies on the imaginary axis exactly when every
/// root of `g` is real and at most 0. Then `g = prod (y + r_i)` with
/// `r_i >= 0` has no negative coefficient. So either of these, proved on
/// the whole box, gives a root `y` off `(-inf, 0]`, and `x = sqrt(y)` or
/// `-sqrt(y)` has a positive real part:
/// * a coefficient of `g` negative;
/// * `g` of degree 2 with discriminant `g_1^2 - 4 g_0 < 0` (a complex pair).
pub fn prove_unstable(sym: &Symbolic, c: &[Frac], range: &ParamBox) -> Option<String> {
    let n = sym.dim();
    // The system is defined on the whole sub-box: every input's
    // denominator keeps one sign (the coefficients' own are checked below).
    for (f, _) in sym.input_denominators() {
        sign_on_box(f, n, range)?;
    }
    let deg = c.len().checked_sub(1)?;
    if (0..deg).any(|i| (deg - i) % 2 == 1 && !c[i].is_zero()) {
        return None;
    }
    let h: Vec<&Frac> = (deg % 2..=deg).step_by(2).map(|i| &c[i]).collect();
    let j0 = h.iter().position(|x| !x.is_zero())?;
    let g = &h[j0..];
    let m = g.len() - 1;
    if m == 0 {
        return None;
    }
    for (i, gi) in g.iter().enumerate().take(m) {
        if frac_sign(gi, n, range) == Some(Sign::Negative) {
            return Some(format!(
                "the coefficient of y^{i} in g(y) (det(x I - A) = x^r y^j g(y), y = x^2) is negative on the sub-box: g has a root off (-inf, 0], so A has an eigenvalue with positive real part"
            ));
        }
    }
    if m == 2 {
        let disc = g[1].mul(g[1]).sub(&g[0].scale(&Rational::from(4)));
        if frac_sign(&disc, n, range) == Some(Sign::Negative) {
            return Some("g(y) = y^2 + g_1 y + g_0 (det(x I - A) = x^r y^j g(y), y = x^2) has a negative discriminant on the sub-box: a complex pair of roots y, so A has eigenvalues with positive real part".into());
        }
    }
    None
}

/// `lambda_max(Q, V)` in floating point for exact `V` (positive definite)
/// and `Q`; `None` if `V` is not numerically definite.
pub fn growth_at(v: &Matrix, q: &Matrix) -> Option<f64> {
    let l = v.to_dmatrix().cholesky()?.l();
    let li = l.try_inverse()?;
    let c = &li * q.to_dmatrix() * li.transpose();
    let c = (&c + c.transpose()) * 0.5;
    let e = c.symmetric_eigen().eigenvalues;
    e.iter().all(|x| x.is_finite()).then(|| e.max())
}

/// The pointwise analysis at one parameter point: the system there, through
/// the exact pipeline (`generator::analyse`, default settings).
pub fn analyse_at(system: &BoxSystem, theta: &[Rational]) -> Option<(casimir::System, generator::Analysis)> {
    let n = system.dim();
    let poly = |f: &Frac| specialise(f, n, theta);
    let value = |f: &Frac| value_at(f, n, theta);
    let h = poly(&system.hamiltonian)?;
    let casimirs = system.casimirs.iter().map(poly).collect::<Option<Vec<_>>>()?;
    let first = system.first_integrals.iter().map(poly).collect::<Option<Vec<_>>>()?;
    let mu = system.equilibrium.iter().map(value).collect::<Option<Vec<_>>>()?;
    let noise =
        system.noise.iter().map(|s| s.iter().map(value).collect::<Option<Vec<_>>>()).collect::<Option<Vec<_>>>()?;
    let s = casimir::System::new(system.algebra.clone(), h, casimirs, first, mu, noise).ok()?;
    // The box proves its own bound over each sub-box: only the choice, the
    // verdict and the exact spectral test are taken from here.
    let a = generator::analyse(&s, &generator::Settings { prove_bound: false, ..generator::Settings::default() });
    Some((s, a))
}

/// The choices to try on a sub-box whose anchor is stable: the optimised
/// one, then the first definite one (a wider margin, a larger `Sigma^2`).
fn anchor_choices(analysis: &generator::Analysis) -> Vec<BoxChoice> {
    let (Some(stable), Some(variation)) = (&analysis.stable, &analysis.variation) else {
        return vec![];
    };
    let n = variation.dim();
    let r = variation.num_conserved();
    let free: Vec<usize> = (0..r).filter(|j| !variation.range_columns.contains(j)).collect();
    // Rows of G[:, range] that are independent at the anchor.
    let g = &variation.gradients;
    let cols = &variation.range_columns;
    let sub_t = Matrix::from_fn(cols.len(), n, |j, i| g[(i, cols[j])].clone());
    let pivot_rows = sub_t.pivot_columns();
    let mut out = Vec::new();
    for c in [&stable.choice, &stable.first_choice] {
        let choice = BoxChoice {
            sign: c.sign,
            multipliers: c.multipliers.clone(),
            free: free.clone(),
            pivot_rows: pivot_rows.clone(),
            m: c.m.clone(),
        };
        if !out.contains(&choice) {
            out.push(choice);
        }
    }
    out
}

/// The bound to prove: the largest `Sigma^2` sampled at the corners and the
/// centre, times `1 + margin`, plus `margin * 1e-6` of the samples' scale,
/// rounded up to 6 decimal digits. `None` if a sample fails.
pub fn sampled_bound(
    forms: &Forms,
    n: usize,
    range: &ParamBox,
    margin: &Rational,
) -> Option<(Rational, f64, Vec<Rational>)> {
    let mut points = range.corners();
    points.push(range.centre());
    let mut best = (f64::NEG_INFINITY, range.centre());
    let mut scale = 0.0f64;
    for p in points {
        let v = matrix_at(&forms.v, n, &p)?;
        let q = matrix_at(&forms.q, n, &p)?;
        let g = growth_at(&v, &q)?;
        let neg = growth_at(&v, &q.scale(&Rational::from(-1)))?;
        scale = scale.max(g.abs()).max(neg.abs());
        if g > best.0 {
            best = (g, p);
        }
    }
    let m = exact::rational_to_f64(margin);
    let target = best.0.max(0.0) * (1.0 + m) + m * 1e-6 * scale.max(f64::MIN_POSITIVE);
    let s = exact::decimal_at_least(target, 6)?;
    Some((s, best.0.max(0.0), best.1))
}

/// Whether the system is defined at `x`: no input denominator or divisor
/// vanishes there.
pub fn defined_at(sym: &Symbolic, x: &[Rational]) -> bool {
    let n = sym.dim();
    let mut point = vec![Rational::zero(); n];
    point.extend_from_slice(x);
    sym.input_denominators().iter().all(|(f, _)| !f.eval(&point).is_zero())
}

fn sign_name(s: Sign) -> &'static str {
    if s == Sign::Positive {
        "positive"
    } else {
        "negative"
    }
}

/// Prove, exactly, that for every parameter in `range` the equilibrium
/// fails or (when `mu_e` is an equilibrium for every parameter) the noise
/// moves it: the system is defined on the whole sub-box (every input
/// denominator keeps one strict sign), and one component of
/// `ad*_{Dh(mu_e)} mu_e` (or of some `ad*_{sigma_i} mu_e`) keeps one strict
/// sign there, by the Bernstein coefficients of its numerator and
/// denominator factors. `None`: not proved (or the residuals vanish
/// identically). A residual that is not identically zero vanishes only on
/// a set of measure zero, so bisection proves this on all of the box but
/// a neighbourhood of that set, which stays undecided.
pub fn prove_excluded(sym: &Symbolic, range: &ParamBox) -> Option<LeafOutcome> {
    let n = sym.dim();
    for (f, _) in sym.input_denominators() {
        sign_on_box(f, n, range)?;
    }
    if !sym.equilibrium_holds() {
        return sym.equilibrium_residual.iter().enumerate().find_map(|(k, r)| {
            let s = frac_sign(r, n, range).filter(|_| !r.is_zero())?;
            Some(LeafOutcome::NotAnEquilibrium {
                criterion: format!(
                    "component {k} of ad*_{{Dh(mu_e)}} mu_e is {} on the whole sub-box (Bernstein coefficients): mu_e is an equilibrium for no parameter in it",
                    sign_name(s)
                ),
            })
        });
    }
    sym.incompatible_noise().into_iter().find_map(|i| {
        sym.noise_residuals[i].iter().enumerate().find_map(|(k, r)| {
            let s = frac_sign(r, n, range).filter(|_| !r.is_zero())?;
            Some(LeafOutcome::NoiseIncompatible {
                criterion: format!(
                    "component {k} of ad*_sigma mu_e for noise field {i} is {} on the whole sub-box (Bernstein coefficients): the noise moves mu_e at every parameter in it",
                    sign_name(s)
                ),
            })
        })
    })
}

/// Why a sub-box is undecided: the budget of sub-boxes was spent first.
pub const BUDGET_SPENT: &str = "the box budget was spent before this sub-box";
/// Why a sub-box is undecided: not proved at `max_depth`.
pub const LARGEST_DEPTH: &str = "not proved at the largest depth";
/// Why a sub-box is undecided when `mu_e` is not an equilibrium for every
/// parameter: the residual is not proved nonzero on it at `max_depth`.
pub const EQUILIBRIUM_UNRESOLVED: &str = "ad*_{Dh(mu_e)} mu_e is not proved nonzero on this sub-box at the largest depth: mu_e may be an equilibrium at some of its parameters (or the system is undefined at some), and nothing is claimed here";
/// The same for noise that moves `mu_e` for some parameters.
pub const NOISE_UNRESOLVED: &str = "no ad*_sigma mu_e is proved nonzero on this sub-box at the largest depth: the noise may keep mu_e at some of its parameters (or the system is undefined at some), and nothing is claimed here";

/// The bit size of a rational: of its numerator or denominator, the larger.
fn rational_bits(r: &Rational) -> u64 {
    r.numer().bits().max(r.denom().bits())
}

/// The largest bit size of the numbers the box's proofs compute with: the
/// box's bounds and the coefficients of the system's functions.
pub fn input_bits(system: &BoxSystem, range: &ParamBox) -> u64 {
    let poly_bits = |p: &Poly| p.terms().map(|(_, c)| rational_bits(c)).max().unwrap_or(0);
    let frac_bits = |f: &Frac| f.den().iter().map(|(g, _)| poly_bits(g)).fold(poly_bits(f.num()), u64::max);
    let functions = std::iter::once(&system.hamiltonian)
        .chain(&system.casimirs)
        .chain(&system.first_integrals)
        .chain(&system.equilibrium)
        .chain(system.noise.iter().flatten());
    functions
        .map(frac_bits)
        .chain(system.divisors.iter().map(poly_bits))
        .chain(range.lo.iter().chain(&range.hi).map(rational_bits))
        .max()
        .unwrap_or(0)
}

/// Numbers up to this many bits cost the box proofs nothing extra.
pub const SHORT_BITS: u64 = 128;

/// The number of sub-boxes the bisection may analyse: `max_boxes`, scaled
/// down by `(SHORT_BITS / bits)^2` (at least 16) when the inputs carry
/// numbers longer than [`SHORT_BITS`] bits. Exact arithmetic on them costs
/// about the square of their length per operation (a box from `1e-308`,
/// about 1030 bits, took four minutes for 740 sub-boxes): the work, not
/// the count, is what a user waits for. Deterministic, so `check` derives
/// the same budget.
pub fn sub_box_budget(system: &BoxSystem, range: &ParamBox, max_boxes: usize) -> (usize, u64) {
    let bits = input_bits(system, range);
    if bits <= SHORT_BITS {
        return (max_boxes, bits);
    }
    let scale = (SHORT_BITS as f64 / bits as f64).powi(2);
    (((max_boxes as f64 * scale).floor() as usize).max(16).min(max_boxes), bits)
}

/// Why a sub-box is undecided when the budget was spent: the plain reason,
/// or, when long numbers scaled the budget down, one that says so.
pub fn budget_reason(budget: usize, max_boxes: usize, bits: u64) -> String {
    if budget < max_boxes {
        format!("{BUDGET_SPENT} (the budget is {budget} sub-boxes: max_boxes = {max_boxes} scaled down for numbers of {bits} bits in the inputs)")
    } else {
        BUDGET_SPENT.to_string()
    }
}

/// Certify the box: bisection until every sub-box is proved (stable,
/// linearly unstable, or, when the equilibrium or the noise fails for some
/// parameters, not an equilibrium or noise-incompatible) or left undecided
/// at the depth or box limit.
pub fn certify_box(system: &BoxSystem, range: &ParamBox, settings: &BoxSettings) -> Result<BoxReport, BoxSystemError> {
    let sym = system.symbolic()?;
    // When mu_e is not an equilibrium (or the noise moves it) for some
    // parameters, nothing can be stable on a sub-box of positive volume:
    // the residual vanishes at most on a set of measure zero. The sub-boxes
    // are then proved to exclude the equilibrium (or the noise), and the
    // ones around the residual's zero set stay undecided.
    let excluded = !sym.equilibrium_holds() || !sym.incompatible_noise().is_empty();
    let unresolved = if sym.equilibrium_holds() { NOISE_UNRESOLVED } else { EQUILIBRIUM_UNRESOLVED };
    let charpoly = std::cell::OnceCell::new();
    let mut queue = std::collections::VecDeque::from([(range.clone(), 0u32)]);
    let mut leaves = Vec::new();
    let mut analysed = 0usize;
    let mut limit = None;
    let (budget, bits) = sub_box_budget(system, range, settings.max_boxes);
    let spent = budget_reason(budget, settings.max_boxes, bits);
    let settings = &BoxSettings { max_boxes: budget, ..settings.clone() };
    while let Some((b, depth)) = queue.pop_front() {
        if analysed >= settings.max_boxes {
            limit = Some("max_boxes");
            leaves.push(Leaf { range: b, depth, outcome: undecided(&spent, None) });
            continue;
        }
        analysed += 1;
        let anchor_verdict = if excluded {
            if let Some(outcome) = prove_excluded(&sym, &b) {
                leaves.push(Leaf { range: b, depth, outcome });
                continue;
            }
            None
        } else {
            let analysis = analyse_at(system, &b.anchor());
            let anchor_verdict = analysis.as_ref().map(|(_, a)| a.verdict);
            let proved = analysis.as_ref().and_then(|(_, a)| prove_stable(&sym, a, &b, &settings.margin));
            if let Some(outcome) = proved {
                leaves.push(Leaf { range: b, depth, outcome });
                continue;
            }
            if anchor_verdict == Some(Verdict::LinearlyUnstable) {
                if let Some(criterion) =
                    prove_unstable(&sym, charpoly.get_or_init(|| sym.characteristic_polynomial()), &b)
                {
                    leaves.push(Leaf { range: b, depth, outcome: LeafOutcome::LinearlyUnstable { criterion } });
                    continue;
                }
            }
            // A sub-box unstable at its anchor and every corner (each proved
            // pointwise by the exact Sturm test) is not split further: that
            // saves the bisection of unstable regions down to the largest
            // depth. Nothing is claimed for it (instability throughout is not
            // proved), and a stable island inside it would stay undecided.
            if anchor_verdict == Some(Verdict::LinearlyUnstable) && unstable_at_anchor_and_corners(system, &b) {
                leaves.push(Leaf { range: b, depth, outcome: undecided(UNSTABLE_CORNERS, anchor_verdict) });
                continue;
            }
            anchor_verdict
        };
        if depth >= settings.max_depth {
            limit.get_or_insert("max_depth");
            let reason = if excluded { unresolved } else { LARGEST_DEPTH };
            leaves.push(Leaf { range: b, depth, outcome: undecided(reason, anchor_verdict) });
            continue;
        }
        let (lo, hi) = b.split(bisection_side(&b, range));
        queue.push_back((lo, depth + 1));
        queue.push_back((hi, depth + 1));
    }
    if !excluded {
        tighten(system, &sym, range, &mut leaves, &mut analysed, settings);
    }
    let (verdict, reason) = verdict_of(&LeafCounts::of(&leaves));
    Ok(BoxReport { verdict, reason, leaves, limit })
}

/// The side along which a sub-box `b` of `whole` is bisected: the widest
/// relative to the whole box's, the first such on a tie (every side has
/// positive width: LO < HI). The bisection and the tightening use it, and
/// `check` rebuilds the bisection tree with it.
pub fn bisection_side(b: &ParamBox, whole: &ParamBox) -> usize {
    (0..b.dim())
        .max_by(|&x, &y| {
            let relative = |k: usize| (&b.hi[k] - &b.lo[k]) / (&whole.hi[k] - &whole.lo[k]);
            relative(x).cmp(&relative(y)).then(y.cmp(&x))
        })
        .unwrap_or(0)
}

/// Whether the pipeline proves `A` unstable (exact Sturm test) at the
/// sub-box's anchor and at every corner: such a sub-box is left whole
/// ([`UNSTABLE_CORNERS`]).
pub fn unstable_at_anchor_and_corners(system: &BoxSystem, b: &ParamBox) -> bool {
    std::iter::once(b.anchor())
        .chain(b.corners())
        .all(|p| analyse_at(system, &p).is_some_and(|(_, a)| unstable_exactly(&a)))
}

/// The stable outcome on sub-box `b` from the pipeline's analysis at its
/// anchor: its choices in turn, each with the bound sampled on `b`, until
/// one is proved.
fn prove_stable(sym: &Symbolic, a: &generator::Analysis, b: &ParamBox, margin: &Rational) -> Option<LeafOutcome> {
    let n = sym.dim();
    for choice in anchor_choices(a) {
        let Ok(forms) = sym.forms(&choice) else { continue };
        let Some((s, sampled, at)) = sampled_bound(&forms, n, b, margin) else { continue };
        // Q = 0 identically: Sigma^2 = 0 needs no margin.
        let s = if forms.q_zero { Rational::zero() } else { s };
        if prove_leaf(sym, b, &choice, &s).is_ok() {
            return Some(LeafOutcome::Stable { choice, sigma2_upper: s, sampled, sampled_at: at });
        }
    }
    None
}

/// Bring the box's bound closer to the pointwise `Sigma^2`: while the
/// stable sub-box with the largest bound `S` has `S` above `1 +
/// sup_tolerance` times the pipeline's own `Sigma^2` at the point where its
/// largest sample was taken, split it and prove both halves (each with the
/// choice at its own anchor, nearer the worst point). Stops at the depth
/// or box limit, or when a half is not proved (the sub-box is then kept).
fn tighten(
    system: &BoxSystem,
    sym: &Symbolic,
    range: &ParamBox,
    leaves: &mut Vec<Leaf>,
    analysed: &mut usize,
    settings: &BoxSettings,
) {
    let tolerance = exact::rational_to_f64(&settings.sup_tolerance);
    loop {
        let worst = leaves
            .iter()
            .enumerate()
            .filter_map(|(i, l)| match &l.outcome {
                LeafOutcome::Stable { sigma2_upper, sampled_at, .. } => {
                    Some((i, sigma2_upper.clone(), sampled_at.clone()))
                }
                _ => None,
            })
            .max_by(|x, y| x.1.cmp(&y.1));
        let Some((i, s, at)) = worst else { return };
        if s.is_zero() || leaves[i].depth >= settings.max_depth || *analysed + 2 > settings.max_boxes {
            return;
        }
        let Some(reference) = analyse_at(system, &at).and_then(|(_, a)| a.sigma2()) else { return };
        if exact::rational_to_f64(&s) <= reference * (1.0 + tolerance) {
            return;
        }
        let leaf = &leaves[i];
        let (lo, hi) = leaf.range.split(bisection_side(&leaf.range, range));
        let depth = leaf.depth + 1;
        let mut halves = Vec::new();
        for half in [lo, hi] {
            *analysed += 1;
            let outcome =
                analyse_at(system, &half.anchor()).and_then(|(_, a)| prove_stable(sym, &a, &half, &settings.margin));
            match outcome {
                Some(outcome) => halves.push(Leaf { range: half, depth, outcome }),
                None => return,
            }
        }
        leaves.splice(i..=i, halves);
    }
}

/// How many sub-boxes have each outcome.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LeafCounts {
    /// Proved stable.
    pub stable: usize,
    /// Proved linearly unstable.
    pub unstable: usize,
    /// Proved not an equilibrium.
    pub not_equilibrium: usize,
    /// Proved noise-incompatible.
    pub noise_incompatible: usize,
    /// Undecided.
    pub undecided: usize,
}

impl LeafCounts {
    /// The counts of a partition.
    pub fn of(leaves: &[Leaf]) -> LeafCounts {
        let mut c = LeafCounts::default();
        for l in leaves {
            c.add(&l.outcome);
        }
        c
    }

    /// Count one more sub-box.
    pub fn add(&mut self, outcome: &LeafOutcome) {
        match outcome {
            LeafOutcome::Stable { .. } => self.stable += 1,
            LeafOutcome::LinearlyUnstable { .. } => self.unstable += 1,
            LeafOutcome::NotAnEquilibrium { .. } => self.not_equilibrium += 1,
            LeafOutcome::NoiseIncompatible { .. } => self.noise_incompatible += 1,
            LeafOutcome::Undecided { .. } => self.undecided += 1,
        }
    }

    /// All sub-boxes.
    pub fn total(&self) -> usize {
        self.stable + self.unstable + self.not_equilibrium + self.noise_incompatible + self.undecided
    }
}

/// The whole box's verdict from its sub-boxes' counts, and the sentence
/// (`check` derives both again from the sub-boxes it re-proves).
pub fn verdict_of(c: &LeafCounts) -> (BoxVerdict, String) {
    let total = c.total();
    let of = |k: usize| format!("{k} of {total} sub-boxes");
    if total > 0 && c.stable == total {
        (BoxVerdict::Stable, "the second variation is definite and Sigma^2 <= S on every sub-box: stable in probability for every parameter in the box".into())
    } else if total > 0 && c.unstable == total {
        (
            BoxVerdict::LinearlyUnstable,
            "A has an eigenvalue with positive real part for every parameter in the box (proved on every sub-box)"
                .into(),
        )
    } else if total > 0 && c.not_equilibrium == total {
        (
            BoxVerdict::NotAnEquilibrium,
            "ad*_{Dh(mu_e)} mu_e is proved nonzero on every sub-box: mu_e is an equilibrium for no parameter in the box".into(),
        )
    } else if total > 0 && c.noise_incompatible == total {
        (
            BoxVerdict::NoiseIncompatible,
            "mu_e is an equilibrium for every parameter, and the noise is proved to move it on every sub-box: for every parameter in the box".into(),
        )
    } else if c.not_equilibrium > 0 {
        (
            BoxVerdict::PartlyNotAnEquilibrium,
            format!(
                "mu_e is proved not an equilibrium on {} (for every parameter in them); nothing is claimed on the other {}, which hold the parameters where ad*_{{Dh(mu_e)}} mu_e may vanish or the system is undefined",
                of(c.not_equilibrium),
                c.undecided
            ),
        )
    } else if c.noise_incompatible > 0 {
        (
            BoxVerdict::PartlyNoiseIncompatible,
            format!(
                "the noise is proved to move mu_e on {} (for every parameter in them); nothing is claimed on the other {}, which hold the parameters where it may keep mu_e or the system is undefined",
                of(c.noise_incompatible),
                c.undecided
            ),
        )
    } else {
        let counts =
            format!("{} are proved stable, {} linearly unstable, {} undecided", of(c.stable), c.unstable, c.undecided);
        if c.stable > 0 {
            (BoxVerdict::PartlyStable, counts)
        } else if c.unstable > 0 {
            (BoxVerdict::PartlyUnstable, counts)
        } else {
            (BoxVerdict::Undecided, "no sub-box is proved stable or unstable".into())
        }
    }
}

/// Why a sub-box unstable at its anchor and corners is left whole.
pub const UNSTABLE_CORNERS: &str = "linearly unstable at its anchor and every corner (proved exactly at each point); not split further, and instability throughout the sub-box is not proved";

fn unstable_exactly(a: &generator::Analysis) -> bool {
    a.verdict == Verdict::LinearlyUnstable
        && matches!(a.spectral_proof, Some(generator::SpectralProof::Unstable { .. }))
}

fn undecided(reason: &str, anchor: Option<Verdict>) -> LeafOutcome {
    LeafOutcome::Undecided { reason: reason.to_string(), anchor }
}
