//! What every model's simulation asks of its options, in one place: the
//! limits of a run and the checks of the paths, the time step and the
//! output times.

/// At most this many paths.
pub(crate) const MAX_PATHS: usize = 10_000_000;
/// At most this many steps per path.
pub(crate) const MAX_STEPS: f64 = 1e8;

/// The paths (2 to [`MAX_PATHS`]), the time step (positive and finite) and
/// the number of output times (at least one): `Err((field, message))`
/// naming the first that is not.
pub(crate) fn check_paths_dt_outputs(paths: usize, dt: f64, outputs: usize) -> Result<(), (&'static str, String)> {
    if !(2..=MAX_PATHS).contains(&paths) {
        return Err(("paths", format!("need 2 to {MAX_PATHS} paths, got {paths}")));
    }
    if !(dt.is_finite() && dt > 0.0) {
        return Err(("dt", format!("must be positive and finite, got {dt}")));
    }
    if outputs == 0 {
        return Err(("outputs", "need at least one output time".into()));
    }
    Ok(())
}
