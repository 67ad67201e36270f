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
/// The finest grid of the instability search's dense stage: a rate that
/// has not converged at `instability_ny` is refined by doubling up to this
/// (a critical layer can be far thinner than the user's grid) with all the
/// eigenvalues of the drift, the largest `Im c` the candidate ...
pub const INSTABILITY_MAX_NY: f64 = 1024.0;
/// ... and beyond it, up to this, with the one eigenvalue nearest the
/// last candidate above the floor (shift-invert on the banded pencil,
/// `analysis::instability` docs): the weakly growing modes near a neutral
/// wavenumber have critical layers of width about `Im c / |U'|`. Measured
/// for the Bickley jet `sech^2 y` on `[-8, 8]`
/// (`examples/instability_rates.rs`; shooting values in the regression
/// test `the_bickley_jet_sinuous_mode_is_found`): the rates agree to
/// `1e-3` between 2048 and 4096 at `k = 1.9` (`Im c = 0.0116`), 4096 and
/// 8192 at 1.95 (`0.0057`), 32768 and 65536 at 1.99 (`0.0011`) and 1.995
/// (`0.00056`, `8e-4` apart). A tracked grid costs 9 ms at 2048 and 77 ms
/// at 65536 (26 MB; grid, coefficients, banded LU, 3 to 60 inverse
/// iteration steps), where the dense eigenvalues cost 4 s at 2048 and
/// 0.4 s at 1024: the six tracked grids add about 0.2 s to the 0.5 s of
/// the dense stage.
pub const INSTABILITY_TRACK_MAX_NY: f64 = 65536.0;
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
        ("instability_track_max_ny", INSTABILITY_TRACK_MAX_NY),
        ("multiple_zero", MULTIPLE_ZERO),
    ]
}
