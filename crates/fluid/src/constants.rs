//! The fixed numerical constants of the fluid pipeline, in one place, and
//! recorded in every fluid certificate (`constants`), so a certificate says
//! every number its claims depended on (the tunable ones are
//! [`crate::analysis::FluidSettings`]).

/// Uniform samples of the closed interval for the checks of the profile,
/// the noise's scale and the shifted functionals.
pub const PROFILE_SAMPLES: usize = 4096;
/// Uniform samples for the choice of functional (zeros of `U''`), the
/// paper's bound `sup sum eta_k'^2` and the compressible residuals.
pub const FINE_SAMPLES: usize = 8192;
/// Uniform samples for `max |U|`, the scale of the instability floor.
pub const SCALE_SAMPLES: usize = 1024;
/// The verified bound of a mode is tried at `Sigma^2 (1 + m) + m
/// VERIFY_RITZ_WEIGHT |T| + residual` with `m` starting here ...
pub const VERIFY_MARGIN_START: f64 = 1e-8;
/// ... growing by this factor ...
pub const VERIFY_MARGIN_GROWTH: f64 = 30.0;
/// ... at most this many times.
pub const VERIFY_ATTEMPTS: usize = 5;
/// The margin of rung `rung` of the ladder:
/// `VERIFY_MARGIN_START * VERIFY_MARGIN_GROWTH^rung` (rungs from
/// `VERIFY_ATTEMPTS` on are the continued ladder of the modes whose own
/// ladder proved nothing).
///
/// ```
/// use fluid::constants::ladder_margin;
/// assert_eq!(ladder_margin(0), 1e-8);
/// assert!((ladder_margin(4) - 8.1e-3).abs() < 1e-15);
/// ```
pub fn ladder_margin(rung: usize) -> f64 {
    VERIFY_MARGIN_START * VERIFY_MARGIN_GROWTH.powi(rung as i32)
}
/// The weight of the Ritz scale `|T|` in the verified bound's slack.
pub const VERIFY_RITZ_WEIGHT: f64 = 1e-3;
/// A growth rate is evidence of instability only above this times
/// `k max |U|` ...
pub const INSTABILITY_FLOOR: f64 = 1e-6;
/// ... and when the rates on two grids agree to this, relative.
pub const INSTABILITY_AGREEMENT: f64 = 1e-3;
/// The finest grid of the instability search: a rate that has not
/// converged at `instability_ny` is refined by doubling up to this (a
/// critical layer can be far thinner than the user's grid).
pub const INSTABILITY_MAX_NY: f64 = 1024.0;
/// A zero of `U''` is multiple (no forced shift) when `|U'''|` there is below
/// this times `max |U''| / length`.
pub const MULTIPLE_ZERO: f64 = 1e-8;

/// The constants as `(name, value)` pairs, for certificates.
///
/// ```
/// let c = fluid::constants::all();
/// assert!(c.iter().any(|(n, v)| *n == "verify_margin_growth" && *v == 30.0));
/// ```
pub fn all() -> Vec<(&'static str, f64)> {
    vec![
        ("profile_samples", PROFILE_SAMPLES as f64),
        ("fine_samples", FINE_SAMPLES as f64),
        ("scale_samples", SCALE_SAMPLES as f64),
        ("verify_margin_start", VERIFY_MARGIN_START),
        ("verify_margin_growth", VERIFY_MARGIN_GROWTH),
        ("verify_attempts", VERIFY_ATTEMPTS as f64),
        ("verify_ritz_weight", VERIFY_RITZ_WEIGHT),
        ("instability_floor", INSTABILITY_FLOOR),
        ("instability_agreement", INSTABILITY_AGREEMENT),
        ("instability_max_ny", INSTABILITY_MAX_NY),
        ("multiple_zero", MULTIPLE_ZERO),
    ]
}
