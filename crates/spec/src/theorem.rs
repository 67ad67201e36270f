//! The theorem a certificate states, in words generated from its data:
//! which SDE (the linearisation, about which state, on which space or
//! grid), which norm, the bound, its Markov corollary, and what is not
//! checked. The CLI summary, `verify report` and the README use these
//! words; `check` re-derives them with the rest of the certificate and
//! compares them.
//!
//! What the engine proves for a stable verdict is the paper's linear
//! statement: for the linearised Stratonovich SDE `dx = A x dt + sum_i B_i
//! x o dW^i` about `mu_e` and the definite energy–Casimir form `P`, the
//! generator satisfies `L(x^T P x) <= Sigma^2 x^T P x`, so (Dynkin and
//! Gronwall) `E|x_t|_P^2 <= |x_0|_P^2 e^(Sigma^2 t)` for every `t >= 0`;
//! by Markov's inequality `P(|x_t|_P^2 > eps) <= (delta/eps)
//! e^(Sigma^2 t)` at each fixed `t` when `|x_0|_P^2 = delta`. That is
//! neither a bound on the probability of ever leaving the ball (a maximal
//! inequality) nor a statement about the nonlinear stochastic system.
//!
//! ```
//! let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/rigid-body-major-axis.json")).unwrap();
//! let cert = spec::certify_lie(&spec::parse_spec(&text).unwrap()).json;
//! let statement = cert["theorem"]["statement"].as_str().unwrap();
//! assert!(statement.starts_with("Proved (exact): for the linearised Stratonovich SDE"));
//! assert!(statement.contains("E|dmu_t|_P^2 <= |dmu_0|_P^2 exp(Sigma^2 t)"));
//! assert_eq!(cert["theorem"]["status"], "proved");
//! ```

use outcome::{Verdict, VerificationLevel};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// How firmly a certificate's statement is established.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum TheoremStatus {
    /// Proved: exact arithmetic, or floating point with every rounding
    /// bounded.
    Proved,
    /// Computed in floating point without a proof: an estimate.
    Estimated,
    /// Nothing is claimed.
    None,
}

/// The statement of a certificate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TheoremRecord {
    /// `proved`, `estimated` or `none`.
    pub status: TheoremStatus,
    /// What is claimed, in one paragraph.
    pub statement: String,
    /// What the certificate does not check.
    pub not_checked: String,
}

/// What a statement is about: the system's linearisation and its norm.
pub(crate) struct Subject {
    /// The linear SDE, about which state, on which space or grid.
    pub sde: String,
    /// The perturbation's name (`dmu`, `dW`, `dw`).
    pub state: &'static str,
    /// The norm's subscript (`P`, `V`).
    pub norm: &'static str,
    /// What the norm is.
    pub norm_is: String,
    /// The drift's linearisation, for an instability (`A`).
    pub drift: String,
    /// What is not checked.
    pub not_checked: String,
}

/// `x` with 7 significant digits, rounded up (`up`) or down as a decimal:
/// a printed bound is never below the bound, a printed stopping time never
/// above the time.
///
/// ```
/// assert_eq!(spec::theorem::significant(1.0 / 3.0, true), "0.3333334");
/// assert_eq!(spec::theorem::significant(17.056185874029936, false), "17.05618");
/// assert_eq!(spec::theorem::significant(4.0346621e-7, true), "4.034663e-7");
/// ```
pub fn significant(x: f64, up: bool) -> String {
    if !x.is_finite() || x == 0.0 {
        return format!("{x}");
    }
    let text = format!("{:.6e}", x.abs());
    let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
    let mut digits: u64 = mantissa.replace('.', "").parse().unwrap_or(0);
    let mut e: i32 = exponent.parse().unwrap_or(0);
    // The decimal against the double's exact value, in rationals: a
    // decimal that parses back to the double can still lie on the wrong
    // side of it (subnormals have few digits).
    let exact_x = exact::rational_from_f64(x.abs());
    let printed = exact::parse_number(&text).ok();
    let order = match (&printed, &exact_x) {
        (Some(p), Some(v)) => p.cmp(v),
        _ => std::cmp::Ordering::Equal,
    };
    // away from zero for an upper bound of a positive number, and so on
    let outward = (up && x > 0.0) || (!up && x < 0.0);
    if outward && order == std::cmp::Ordering::Less {
        digits += 1;
    } else if !outward && order == std::cmp::Ordering::Greater {
        digits -= 1;
    }
    if digits >= 10_000_000 {
        digits /= 10;
        e += 1;
    } else if digits < 1_000_000 {
        digits = digits * 10 + 9; // 0.9999999: the next digit down
        e -= 1;
    }
    let sign = if x < 0.0 { "-" } else { "" };
    let d = digits.to_string();
    let body = if (-4..7).contains(&e) {
        if e >= 0 {
            let (int, frac) = d.split_at((e as usize + 1).min(d.len()));
            let int = format!("{int}{}", "0".repeat((e as usize + 1).saturating_sub(d.len())));
            let frac = frac.trim_end_matches('0');
            if frac.is_empty() {
                int
            } else {
                format!("{int}.{frac}")
            }
        } else {
            format!("0.{}{}", "0".repeat((-e - 1) as usize), d.trim_end_matches('0'))
        }
    } else {
        let (first, rest) = d.split_at(1);
        let rest = rest.trim_end_matches('0');
        if rest.is_empty() {
            format!("{first}e{e}")
        } else {
            format!("{first}.{rest}e{e}")
        }
    };
    format!("{sign}{body}")
}

/// A double as the shortest decimal that reads back to it (`0.1`,
/// `5e-324`), without a trailing `.0`.
pub fn shortest(x: f64) -> String {
    let t = format!("{x:?}");
    t.strip_suffix(".0").map(str::to_string).unwrap_or(t)
}

/// The status a level gives a claim.
fn status_of(level: Option<VerificationLevel>) -> TheoremStatus {
    match level {
        Some(VerificationLevel::Exact | VerificationLevel::ExactStructure | VerificationLevel::VerifiedFloat) => {
            TheoremStatus::Proved
        }
        Some(VerificationLevel::Numerical | VerificationLevel::Float) => TheoremStatus::Estimated,
        None => TheoremStatus::None,
    }
}

fn opening(level: Option<VerificationLevel>) -> &'static str {
    match level {
        Some(VerificationLevel::Exact) => "Proved (exact)",
        Some(VerificationLevel::ExactStructure) => "Proved (exact structure)",
        Some(VerificationLevel::VerifiedFloat) => "Proved (verified floating point)",
        _ => "Estimated in floating point, not proved",
    }
}

/// The numbers a stable statement needs.
pub(crate) struct Bound {
    /// `Sigma^2` as printed (an exact rational, or a double rounded up).
    pub sigma2: String,
    /// Whether `Sigma^2 = 0`.
    pub zero: bool,
    /// `(epsilon, delta, T)` when the spec asks (`T` `None`: infinite).
    pub stopping: Option<(f64, f64, Option<f64>)>,
}

/// The theorem of a certificate with this verdict and level.
pub(crate) fn theorem(
    subject: &Subject,
    verdict: Verdict,
    level: Option<VerificationLevel>,
    bound: Option<&Bound>,
    growth_rate: Option<f64>,
) -> TheoremRecord {
    let x = subject.state;
    let (n_t, n_0) = (format!("|{x}_t|_{}^2", subject.norm), format!("|{x}_0|_{}^2", subject.norm));
    let head = opening(level);
    let (status, statement) = match (verdict, bound) {
        (Verdict::Stable, Some(b)) => {
            let moment = if b.zero {
                format!("E{n_t} <= {n_0} for every t >= 0 (Sigma^2 = 0)")
            } else {
                format!("E{n_t} <= {n_0} exp(Sigma^2 t) for every t >= 0, with Sigma^2 = {}", b.sigma2)
            };
            let markov = if b.zero {
                format!("P({n_t} > epsilon) <= delta/epsilon at every time t when {n_0} = delta")
            } else {
                format!("P({n_t} > epsilon) <= (delta/epsilon) exp(Sigma^2 t) at each fixed time t when {n_0} = delta")
            };
            // epsilon and delta exactly as the spec's doubles (the
            // shortest text that reads back to them): rounded, two close
            // values could print equal and the sentence would be false
            let time = match b.stopping {
                Some((e, d, Some(t))) => format!(
                    "; for epsilon = {}, delta = {} it stays below 1 for t < T = {}",
                    shortest(e),
                    shortest(d),
                    significant(t, false)
                ),
                Some((e, d, None)) => {
                    format!("; for epsilon = {}, delta = {} it is below 1 for all t", shortest(e), shortest(d))
                }
                None => String::new(),
            };
            (
                status_of(level),
                format!(
                    "{head}: for {}, {moment}, for every initial {x}_0, where {}. Hence (Markov's inequality) {markov}{time}.",
                    subject.sde, subject.norm_is
                ),
            )
        }
        (Verdict::LinearlyUnstable, _) => (
            status_of(level),
            format!(
                "{head}: {} has an eigenvalue with positive real part{}, so the equilibrium is linearly (spectrally) unstable; {x} grows exponentially along its eigenvector without noise.",
                subject.drift,
                growth_rate.map_or(String::new(), |g| format!(" (real part {})", significant(g, false)))
            ),
        ),
        (Verdict::NotAnEquilibrium, _) => (
            status_of(level),
            format!("{head}: the state is not an equilibrium (the drift does not vanish there, see the residual), so no stability statement applies to it."),
        ),
        (Verdict::NoiseIncompatible, _) => (
            status_of(level),
            format!("{head}: the noise moves the equilibrium (some ad*_sigma_i mu_e is not zero, see the residuals), so it is not an equilibrium of the stochastic system and its stability in probability is not defined."),
        ),
        _ => (
            TheoremStatus::None,
            "Nothing is claimed either way: no definite conserved form was proved and no instability was found (the reason says what is missing).".to_string(),
        ),
    };
    TheoremRecord { status, statement, not_checked: subject.not_checked.clone() }
}

/// A vector for a statement: its entries when there are at most 8, else
/// `what` (the certificate holds it).
pub(crate) fn listed<T: std::fmt::Display>(v: &[T], what: &str) -> String {
    if v.len() <= 8 {
        format!("({})", v.iter().map(|x| exact::cut(&x.to_string(), 40)).collect::<Vec<_>>().join(", "))
    } else {
        what.to_string()
    }
}

/// What finite-dimensional certificates (and large ones) do not check.
pub(crate) const FINITE_NOT_CHECKED: &str = "The nonlinear stochastic system: the paper's convexity conditions for nonlinear stability in probability are not checked, so every statement is about the linearisation at mu_e (a definite second variation also gives formal stability of the deterministic system). The bound is at each fixed time, not on the probability of ever leaving the ball.";

/// The subject of a finite-dimensional (or large) certificate.
pub(crate) fn finite_subject(name: &str, algebra: &str, dim: usize, equilibrium: &str, noise_fields: usize) -> Subject {
    Subject {
        sde: format!(
            "the linearised Stratonovich SDE d(dmu) = A dmu dt + sum_i B_i dmu o dW^i of '{}' ({algebra}, on R^{dim}) about mu_e = {equilibrium}, with A the Jacobian of the drift ad*_(Dh(mu)) mu at mu_e and B_i = ad*_(sigma_i) for its {noise_fields} noise field(s)",
            exact::cut(name, 80)
        ),
        state: "dmu",
        norm: "P",
        norm_is: "|x|_P^2 = x^T (s P) x with the certificate's energy–Casimir second variation P and sign s (s P positive definite)".into(),
        drift: "the linearised drift A at mu_e".into(),
        not_checked: FINITE_NOT_CHECKED.into(),
    }
}

#[cfg(feature = "fluid")]
/// The theorem of a certificate whose `Sigma^2` is a double: the proved
/// `sigma2_upper` when there is one, else the estimate `sigma2` (the
/// statement then says it is not proved).
pub(crate) fn from_doubles(
    subject: &Subject,
    verdict: Verdict,
    level: Option<VerificationLevel>,
    sigma2_upper: Option<f64>,
    sigma2: Option<f64>,
    stopping: Option<&crate::record::StoppingRecord>,
    growth_rate: Option<f64>,
) -> TheoremRecord {
    // The bound a proof stands behind: the proved sigma2_upper, or, at the
    // exact-structure level, Sigma^2 = 0 itself (Q = 0 by the form's
    // structure). A stable verdict without one is an estimate.
    let proved_bound = match level {
        Some(VerificationLevel::ExactStructure) => sigma2_upper.or(sigma2),
        Some(VerificationLevel::Exact | VerificationLevel::VerifiedFloat) => sigma2_upper,
        _ => None,
    };
    let s = proved_bound.or(sigma2);
    let level = if status_of(level) == TheoremStatus::Proved && proved_bound.is_none() && verdict == Verdict::Stable {
        Some(VerificationLevel::Numerical)
    } else {
        level
    };
    let bound = s.map(|s| Bound {
        sigma2: significant(s, true),
        zero: s == 0.0,
        stopping: stopping.map(|st| (st.epsilon.0, st.delta.0, Some(st.t.0).filter(|t| t.is_finite()))),
    });
    theorem(subject, verdict, level, bound.as_ref(), growth_rate)
}

#[cfg(feature = "fluid")]
/// The statement of a certificate that claims nothing (a spec the analysis
/// could not run on).
pub(crate) fn nothing(not_checked: &str) -> TheoremRecord {
    TheoremRecord {
        status: TheoremStatus::None,
        statement: "Nothing is claimed either way (the reason says why).".into(),
        not_checked: not_checked.into(),
    }
}

#[cfg(feature = "fluid")]
/// What fluid certificates do not check.
pub(crate) fn fluid_not_checked(x_modes: usize) -> String {
    format!("The PDE and the nonlinear system: every statement is about the linearised SDE discretised in y, on the grid the statement names, for the x-modes m = 1..{x_modes} only; the convergence table shows how Sigma^2 moves under refinement, and no bound is claimed for the continuum or for higher modes. The bound is at each fixed time, not on the probability of ever leaving the ball.")
}

#[cfg(feature = "fluid")]
/// The subject of a fluid certificate.
pub(crate) fn fluid_subject(
    name: &str,
    compressible: bool,
    shear_flow: &str,
    boundary: &str,
    ny: usize,
    x_modes: usize,
    unstable: Option<(usize, f64, usize)>,
) -> Subject {
    let model = if compressible {
        "the linearised compressible (barotropic) Stratonovich SDE in (dm, drho), noise ((eta_j, 0), r_j) acting by the coadjoint action,"
    } else {
        "the linearised vorticity Stratonovich SDE dw = -ik (U + U'' L^-1) w dt - sum_j ik eta_j w o dW^j"
    };
    Subject {
        sde: format!(
            "{model} of '{}' about the shear flow U(y) = {} ({boundary}), for each x-mode exp(ikx), m = 1..{x_modes}, discretised in y by spectral elements on {ny} nodes",
            exact::cut(name, 80),
            exact::cut(shear_flow, 80)
        ),
        state: "dw",
        norm: "V",
        norm_is: "|x|_V^2 = x^* V x with V the discretised energy–Casimir(–momentum) form of the certificate's `form`, positive definite per mode".into(),
        drift: match unstable {
            Some((m, k, grid)) => format!(
                "the linearised drift of '{}' about U(y) = {} for x-mode m = {m} (k = {}), discretised in y on {grid} nodes (the certificate's `instability`)",
                exact::cut(name, 80),
                exact::cut(shear_flow, 80),
                significant(k, false)
            ),
            None => "the discretised linearised drift of one x-mode (the certificate's `instability`)".into(),
        },
        not_checked: fluid_not_checked(x_modes),
    }
}

#[cfg(feature = "fluid")]
/// What Zeitlin certificates do not check.
pub(crate) const ZEITLIN_NOT_CHECKED: &str = "The nonlinear Zeitlin SDE and the continuum limit N -> infinity: every statement is about the linearisation of the su(N) model at W_e. The bound is at each fixed time, not on the probability of ever leaving the ball.";

#[cfg(feature = "fluid")]
/// The subject of a Zeitlin certificate.
pub(crate) fn zeitlin_subject(name: &str, n: usize, equilibrium: &str, noise_fields: usize) -> Subject {
    Subject {
        sde: format!(
            "the linearised Stratonovich SDE d(dW) = ([P_e, dW] + [dP, W_e]) dt + sum_i [X_i, dW] o dB^i (Delta_N dP = dW, Hoppe–Yau Laplacian) of the su({n}) Zeitlin model '{}' about the steady vorticity W_e = {}, with {noise_fields} noise field(s) X_i, on su({n}) (dimension {})",
            exact::cut(name, 80),
            exact::cut(equilibrium, 80),
            n * n - 1
        ),
        state: "dW",
        norm: "P",
        norm_is: "|x|_P^2 = <x, P x> with P the second variation of the certificate's energy–Casimir–momentum form (`form`), positive definite".into(),
        drift: "the linearised drift at W_e".into(),
        not_checked: ZEITLIN_NOT_CHECKED.into(),
    }
}

/// The parts of a box certificate's statement.
pub(crate) struct BoxParts<'a> {
    /// The spec's name.
    pub name: &'a str,
    /// The box, as `I2 in [3/2, 5/2], I3 in [4/5, 6/5]`.
    pub range: String,
    /// The equilibrium as given (expressions of the parameters).
    pub equilibrium: String,
    /// The whole box's verdict (`boxes::BoxVerdict::as_str`).
    pub verdict: &'a str,
    /// The volume shares proved stable, linearly unstable, excluded (not
    /// an equilibrium or noise-incompatible) and undecided.
    pub shares: [f64; 4],
    /// `sup_sigma2`, exactly, when some sub-box is stable.
    pub sup: Option<String>,
}

/// What box certificates do not check.
pub(crate) const BOX_NOT_CHECKED: &str = "The nonlinear stochastic system (the paper's convexity conditions) and every parameter outside the box or in an undecided sub-box: every statement is about the linearisation at mu_e(theta), sub-box by sub-box. The bound is at each fixed time, not on the probability of ever leaving the ball.";

/// The statement of a box certificate.
pub(crate) fn box_theorem(b: &BoxParts<'_>) -> TheoremRecord {
    // a proved share rounded down, an unclaimed one up: neither overstated
    let pct = |x: f64| format!("{}% of the box by volume", significant(100.0 * x, false));
    let pct_up = |x: f64| format!("{}% of the box by volume", significant(100.0 * x, true));
    let [stable, unstable, excluded, undecided] = b.shares;
    let sde = format!(
        "the linearised Stratonovich SDE d(dmu) = A(theta) dmu dt + sum_i B_i(theta) dmu o dW^i of '{}' about mu_e(theta) = {}, at the parameter value theta (the other parameters at the spec's values)",
        exact::cut(b.name, 80),
        exact::cut(&b.equilibrium, 200)
    );
    let bound = |s: &str| {
        format!("and {sde}: E|dmu_t|_P^2 <= |dmu_0|_P^2 exp(S t) for every t >= 0 and every initial dmu_0, with |x|_P^2 = x^T V(theta) x, V = s P(theta) the energy–Casimir form of the sub-box's recorded choice (positive definite on the closed sub-box), and S the sub-box's sigma2_upper, at most sup_sigma2 = {s}; hence (Markov's inequality) P(|dmu_t|_P^2 > epsilon) <= (delta/epsilon) exp(S t) at each fixed time t when |dmu_0|_P^2 = delta")
    };
    let sup = b.sup.clone().unwrap_or_default();
    let unstable_part = "A(theta) has an eigenvalue with positive real part (linear instability)";
    let (status, statement) = match b.verdict {
        "stable" => (TheoremStatus::Proved, format!("Proved (exact), for every parameter value theta in the box {} {}.", b.range, bound(&sup))),
        "linearly_unstable" => (TheoremStatus::Proved, format!("Proved (exact), for every parameter value theta in the box {}: {unstable_part}.", b.range)),
        "not_an_equilibrium" => (TheoremStatus::Proved, format!("Proved (exact), for every parameter value theta in the box {}: mu_e(theta) is not an equilibrium (ad*_(Dh(mu_e)) mu_e is not zero).", b.range)),
        "noise_incompatible" => (TheoremStatus::Proved, format!("Proved (exact), for every parameter value theta in the box {}: mu_e(theta) is an equilibrium and the noise moves it (some ad*_(sigma_i) mu_e is not zero), so its stability in probability is not defined.", b.range)),
        "partly_stable" | "partly_unstable" => {
            let mut parts = vec![];
            if stable > 0.0 {
                parts.push(format!("on the sub-boxes proved stable ({}), for every theta there {}", pct(stable), bound(&sup)));
            }
            if unstable > 0.0 {
                parts.push(format!(
                    "on the sub-boxes proved linearly unstable ({}), for every theta there {unstable_part}",
                    pct(unstable)
                ));
            }
            (
                TheoremStatus::Proved,
                format!(
                    "Proved (exact), in the box {}: {}; nothing is claimed on the undecided sub-boxes ({}).",
                    b.range,
                    parts.join("; "),
                    pct_up(undecided)
                ),
            )
        }
        "partly_not_an_equilibrium" => (TheoremStatus::Proved, format!("Proved (exact), on part of the box {} ({}): for every theta there, mu_e(theta) is not an equilibrium. Nothing is claimed on the rest ({}), which holds the parameters where it may be one (or where the system is undefined).", b.range, pct(excluded), pct_up(undecided))),
        "partly_noise_incompatible" => (TheoremStatus::Proved, format!("Proved (exact), on part of the box {} ({}): for every theta there, the noise moves the equilibrium mu_e(theta). Nothing is claimed on the rest ({}), which holds the parameters where the noise may keep it (or where the system is undefined).", b.range, pct(excluded), pct_up(undecided))),
        _ => (TheoremStatus::None, "Nothing is claimed on any part of the box (the reason says why).".to_string()),
    };
    TheoremRecord { status, statement, not_checked: BOX_NOT_CHECKED.into() }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Printed bounds round outward: never below a bound, never above a
    /// time.
    #[test]
    fn printed_numbers_round_outward() {
        for &x in &[0.27, 1.0 / 3.0, 17.056185874029936, 4.034662e-7, 1.141402e7, 123456789.0, 2.0 / 3.0, 1e-300, 5e300]
        {
            let up: f64 = significant(x, true).parse().unwrap();
            let down: f64 = significant(x, false).parse().unwrap();
            assert!(up >= x && down <= x, "{x}: {up} {down}");
            assert!((up - x) <= 1.1e-6 * x && (x - down) <= 1.1e-6 * x, "{x}: {up} {down}");
        }
        // the double 0.27 is 0.27000000000000001776...: a bound on it
        // rounds up past 0.27; 0.25 is exact
        assert_eq!(significant(0.27, true), "0.2700001");
        assert_eq!(significant(0.27, false), "0.27");
        assert_eq!(significant(0.25, true), "0.25");
        assert_eq!(significant(1.0 / 3.0, false), "0.3333333");
        assert_eq!(significant(1.141402e7, false), "1.141402e7");
        assert_eq!(significant(1141402.7, false), "1141402");
        // the double 1e-300 is 1.0000000000000000250...e-300
        assert_eq!(significant(1e-300, true), "1.000001e-300");
        assert_eq!(significant(1e-300, false), "1e-300");
        assert_eq!(significant(-2.5, true), "-2.5");
        // the smallest subnormal, 4.9406564584e-324: rounded as a decimal,
        // not through the double it parses back to
        assert_eq!(significant(5e-324, true), "4.940657e-324");
        assert_eq!(significant(5e-324, false), "4.940656e-324");
        assert_eq!(shortest(0.10000005), "0.10000005");
        assert_eq!(shortest(5e-324), "5e-324");
        assert_eq!(shortest(1.0), "1");
        // 9.9999999 rounded up carries into the next decade
        assert_eq!(significant(9.99999999, true), "10");
    }
}
