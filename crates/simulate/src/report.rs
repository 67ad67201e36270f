//! A study as JSON: what `verify simulate` writes to `NAME.json` and what the
//! Python package's `simulate` returns (as numpy arrays).

use crate::{EnsembleStats, Prepared, Study, StudySettings};
use serde_json::{json, Value};

/// The study's report: the spec's name and verdict, `Sigma^2`, the stopping
/// time, the settings used (`parameters`), each ensemble's series
/// (`times`, `mean` per coordinate, `norm_mean_over_delta` and its standard
/// error, `exceedance`, `casimir_drift`), the exact second moments, the
/// worst start, the bound `exp(Sigma^2 t)`, the moment Lyapunov exponent,
/// the observable's histogram and the exceedance levels.
/// `coordinates` names the algebra's coordinates (recorded, the columns of
/// each `mean`, and the observable's name);
/// `threads` is recorded as run.
pub fn study_report(
    name: &str,
    verdict: &str,
    prepared: &Prepared<'_>,
    settings: &StudySettings,
    study: &Study,
    coordinates: &[String],
    threads: u64,
) -> Value {
    let delta = prepared.delta;
    let exceedance: Vec<Value> = study
        .exceedance
        .iter()
        .map(|e| {
            let certified = e.certified_until.map(|t| if t.is_infinite() { Value::from("infinity") } else { Value::from(t) });
            json!({ "level": e.level, "certified_until": certified, "empirical_first_exceeded": e.empirical_first_exceeded })
        })
        .collect();
    let series = |stats: &EnsembleStats| -> Value {
        json!({
            "times": stats.times,
            "mean": stats.mean,
            "norm_mean_over_delta": stats.norm_mean.iter().map(|x| x / delta).collect::<Vec<_>>(),
            "norm_std_error_over_delta": stats.norm_std_error.iter().map(|x| x / delta).collect::<Vec<_>>(),
            "exceedance": stats.exceedance,
            "casimir_drift": stats.casimir_drift,
        })
    };
    let observable = coordinates.get(prepared.observable).cloned().unwrap_or_else(|| prepared.observable.to_string());
    json!({
        "name": name,
        "verdict": verdict,
        "coordinates": coordinates,
        "sigma2": prepared.sigma2,
        "stopping_time": prepared.stopping_time,
        "epsilon": prepared.epsilon,
        "delta": delta,
        "parameters": {
            "paths": settings.paths, "dt": settings.dt, "t_end": prepared.ensemble.t_end,
            "steps": study.nonlinear.steps, "seed": settings.seed, "scheme": settings.scheme.as_str(),
            "observable": observable, "bins": settings.bins, "mu0": prepared.mu0, "threads": threads,
        },
        "nonlinear": series(&study.nonlinear),
        "linearised": study.linear.as_ref().map(series),
        "exact_moments_over_delta": study.exact_over_delta,
        "worst_case_over_delta": study.worst_over_delta,
        "bound_over_delta": study.bound_over_delta,
        "moment_lyapunov_exponent": study.lyapunov,
        "histogram": { "range": [study.histogram_range.0, study.histogram_range.1], "counts": study.nonlinear.histogram },
        "exceedance": exceedance,
    })
}
