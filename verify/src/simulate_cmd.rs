//! `verify simulate`: ensembles of the nonlinear and the linearised system,
//! exact moments, the exceedance probability against the certified bound,
//! and the charts.

use crate::messages::excerpt;
use crate::paths::{ensure_output_dir, file_stem_noted, write_atomic, write_failure};
use crate::plots::{write_density, write_growth, DensityChart, GrowthChart};
use crate::Failure;
use nalgebra::DMatrix;
use serde_json::{json, Value};
use simulate::{run_ensemble, EnsembleSettings, EnsembleStats, LinearModel, Model, Observable, Scheme, Target};
use std::path::PathBuf;

/// Options of `verify simulate`.
#[derive(clap::Args, Debug)]
pub struct SimulateArgs {
    /// The spec (JSON).
    pub spec: PathBuf,
    /// Number of paths.
    #[arg(long, default_value_t = 10_000)]
    pub paths: usize,
    /// Time step.
    #[arg(long, default_value_t = 0.01, allow_negative_numbers = true)]
    pub dt: f64,
    /// Final time (default: 8 T(eps, delta) for a stable spec, within [1, 200],
    /// long enough to see the passage to the ergodic regime; else 20).
    #[arg(long, allow_negative_numbers = true)]
    pub t_end: Option<f64>,
    /// Coordinate whose distribution is plotted (default: the first coordinate
    /// with a nonzero equilibrium value).
    #[arg(long)]
    pub observable: Option<String>,
    /// Seed of the random streams.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// `lie` (coadjoint-orbit preserving) or `heun` (Stratonovich Heun).
    #[arg(long, default_value = "lie")]
    pub scheme: String,
    /// Number of output times (at most 100 000).
    #[arg(long, default_value_t = 200)]
    pub outputs: usize,
    /// Histogram bins of the observable (at most 10 000, and outputs x bins
    /// at most 10^7).
    #[arg(long, default_value_t = 80)]
    pub bins: usize,
    /// Initial size |dmu_0|_P^2 (default: the spec's stopping delta, else 1e-3).
    #[arg(long, allow_negative_numbers = true)]
    pub delta: Option<f64>,
    /// Threshold eps on |dmu_t|_P^2 (default: the spec's stopping epsilon, else 0.1).
    #[arg(long, allow_negative_numbers = true)]
    pub epsilon: Option<f64>,
    /// Output directory.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Run even if the estimated cost exceeds 15 minutes.
    #[arg(long)]
    pub force: bool,
}

fn bad(message: String) -> Failure {
    Failure::BadInput(message)
}

fn io(e: impl std::fmt::Display) -> Failure {
    Failure::Failed(e.to_string())
}

/// The command-line flag of a field of [`EnsembleSettings`], for messages
/// (`t_end` is `--t-end`); `None` for fields the command computes itself.
fn flag(field: &str) -> Option<&'static str> {
    Some(match field {
        "paths" => "--paths",
        "dt" => "--dt",
        "t_end" => "--t-end",
        "steps" => "--t-end/--dt",
        "outputs" => "--outputs",
        "bins" => "--bins",
        "histogram_cells" => "--outputs/--bins",
        "statistics" => "--paths/--outputs/--bins",
        "observable" => "--observable",
        "epsilon" => "--epsilon",
        _ => return None,
    })
}

/// An ensemble error as a failure naming the flag: bad input (exit 2) for a
/// field the user sets, an internal failure (exit 1) otherwise.
fn ensemble_failure(e: simulate::EnsembleError) -> Failure {
    match e {
        simulate::EnsembleError::Invalid { field, message } => match flag(field) {
            Some(flag) => bad(format!("{flag}: {message}")),
            None => Failure::Failed(format!("internal: the ensemble's {field}: {message}")),
        },
        other => Failure::Failed(format!("internal: {other}")),
    }
}

/// The limits on the histogram, checked before anything is read or run.
fn check_histogram_limits(args: &SimulateArgs) -> Result<(), Failure> {
    let (max_bins, max_outputs, max_cells) =
        (EnsembleSettings::MAX_BINS, EnsembleSettings::MAX_OUTPUTS, EnsembleSettings::MAX_HISTOGRAM_CELLS);
    if args.bins > max_bins {
        return Err(bad(format!("--bins: at most {max_bins} bins, got {}", args.bins)));
    }
    if args.outputs > max_outputs {
        return Err(bad(format!("--outputs: at most {max_outputs} output times, got {}", args.outputs)));
    }
    if args.outputs as u64 * args.bins as u64 > max_cells as u64 {
        return Err(bad(format!(
            "--outputs/--bins: outputs x bins = {} histogram cells exceeds the limit of {max_cells}",
            args.outputs as u64 * args.bins as u64
        )));
    }
    Ok(())
}

/// Rough cost per path-step in seconds, from the benchmarks: closed-form
/// exponentials (so3, se3) versus a matrix exponential per step.
fn cost_per_step(model: &Model) -> f64 {
    if model.closed_form_exponential() {
        4e-8
    } else {
        3e-6
    }
}

pub fn run(args: &SimulateArgs) -> Result<(), Failure> {
    check_histogram_limits(args)?;
    ensure_output_dir(&args.out, "--out")?;
    let text =
        std::fs::read_to_string(&args.spec).map_err(|e| bad(format!("{}: cannot read: {e}", args.spec.display())))?;
    if serde_json::from_str::<serde_json::Value>(&text).is_ok_and(|v| spec::is_fluid_spec(&v)) {
        return Err(bad(format!(
            "{}: $.fluid: `simulate` runs finite-dimensional specs; a fluid certificate's growth is checked against a Monte Carlo of the discretised SDE in tests/fluid.rs (fluid::simulate::ModeSde)",
            args.spec.display()
        )));
    }
    let spec = spec::parse_spec(&text).map_err(|e| bad(format!("{}: {e}", args.spec.display())))?;
    let scheme = Scheme::from_name(&args.scheme)
        .ok_or_else(|| bad(format!("--scheme: '{}' is not 'lie' or 'heun'", excerpt(&args.scheme))))?;
    let cert = spec::certify(&spec);
    let analysis = &cert.analysis;
    let system = &spec.system;
    let coords = system.algebra().coordinates();
    let n = coords.len();
    let mu_e: Vec<f64> = system.equilibrium().iter().map(exact::rational_to_f64).collect();
    let observable = match &args.observable {
        Some(name) => coords.iter().position(|c| c == name).ok_or_else(|| {
            bad(format!("--observable: unknown coordinate '{}' (coordinates: {})", excerpt(name), coords.join(", ")))
        })?,
        None => mu_e.iter().position(|x| *x != 0.0).unwrap_or(0),
    };
    let delta = args.delta.or(spec.stopping.map(|s| s.delta)).unwrap_or(1e-3);
    let epsilon = args.epsilon.or(spec.stopping.map(|s| s.epsilon)).unwrap_or(0.1);
    if !(delta.is_finite() && delta > 0.0 && epsilon.is_finite() && epsilon > delta) {
        return Err(bad(format!(
            "--delta/--epsilon: need 0 < delta < epsilon, got delta = {delta}, epsilon = {epsilon}"
        )));
    }
    let stable = analysis.stable.as_ref();
    let sigma2 = stable.map(|s| s.sigma2());
    let stopping_time = sigma2.filter(|s| *s > 0.0).map(|s| (epsilon / delta).ln() / s);
    let t_end = args.t_end.unwrap_or_else(|| stopping_time.map_or(20.0, |t| (8.0 * t).clamp(1.0, 200.0)));
    // The norm P (sign-adjusted) and the perturbation: sqrt(delta) along the
    // fastest-growing direction for a stable spec, else along the observable.
    let (p, direction) = match stable {
        Some(s) => (s.choice.p.to_dmatrix() * s.choice.sign.as_f64(), s.growth.direction.clone()),
        None => {
            let mut v = vec![0.0; n];
            v[observable] = 1.0;
            (DMatrix::identity(n, n), v)
        }
    };
    let x0: Vec<f64> = direction.iter().map(|v| v * delta.sqrt()).collect();
    let mu0: Vec<f64> = mu_e.iter().zip(&x0).map(|(m, x)| m + x).collect();
    let model = Model::new(system);
    let radius = mu0.iter().map(|x| x * x).sum::<f64>().sqrt().max(1.0); // before the pilot run
    let settings = EnsembleSettings {
        paths: args.paths,
        dt: args.dt,
        t_end,
        outputs: args.outputs,
        seed: args.seed,
        observable: Observable { index: observable, lo: -1.05 * radius, hi: 1.05 * radius, bins: args.bins },
        norm: Some((p.clone(), mu_e.clone())),
        epsilon: Some(epsilon),
    };
    settings.validate(n).map_err(ensemble_failure)?;
    let threads = rayon::current_num_threads() as f64;
    // More threads than cores (RAYON_NUM_THREADS up to 4 per core) do not
    // run faster: the estimate counts the cores that work.
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get) as f64;
    let runs = if stable.is_some() { 2.0 } else { 1.0 };
    let estimate = settings.path_steps() * cost_per_step(&model) * runs / threads.min(cores);
    if estimate > 900.0 && !args.force {
        return Err(bad(format!(
            "--paths/--dt/--t-end: {:.2e} path-steps would take about {:.0} minutes here; lower them or pass --force",
            settings.path_steps(),
            estimate / 60.0
        )));
    }
    if estimate > 10.0 {
        eprintln!(
            "note: about {:.0} s of computation ({:.2e} path-steps on {} threads)",
            estimate,
            settings.path_steps(),
            threads
        );
    }
    // A pilot run (1% of the paths, at most 200) finds the range the
    // observable actually explores, for the histogram.
    let pilot = EnsembleSettings { paths: (args.paths / 100).clamp(1, 200), ..settings.clone() };
    let extent = run_ensemble(&Target::Nonlinear { model: &model, scheme, mu0: mu0.clone() }, &pilot, &|_| {})
        .map_err(ensemble_failure)?
        .observable_extent;
    if !(extent.0.is_finite() && extent.1.is_finite()) {
        return Err(bad(format!(
            "--dt: the pilot run's paths left every bounded range ({} reached {:?}); lower --dt",
            coords[observable], extent
        )));
    }
    let half = 0.5 * (extent.1 - extent.0).max(1e-9);
    let centre = 0.5 * (extent.0 + extent.1);
    let settings = EnsembleSettings {
        observable: Observable { lo: centre - 1.2 * half, hi: centre + 1.2 * half, ..settings.observable },
        ..settings
    };
    let bar = crate::progress_bar(args.paths as u64 * runs as u64, "{bar:40} {pos}/{len} paths ({eta} left)");
    let tick = |k: u64| {
        if let Some(b) = &bar {
            b.inc(k)
        }
    };
    let nonlinear = run_ensemble(&Target::Nonlinear { model: &model, scheme, mu0: mu0.clone() }, &settings, &tick)
        .map_err(ensemble_failure)?;
    let linear = match (stable, &analysis.linearisation) {
        (Some(_), Some(lin)) => {
            let lm = LinearModel::new(lin);
            let s = EnsembleSettings { norm: Some((p.clone(), vec![0.0; n])), ..settings.clone() };
            Some(run_ensemble(&Target::Linear { model: &lm, x0: x0.clone() }, &s, &tick).map_err(ensemble_failure)?)
        }
        _ => None,
    };
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    // Exact moments of the linearised SDE from x0, the worst case, the exponent.
    let moments = analysis.linearisation.as_ref().map(generator::SecondMoments::new);
    let times = &nonlinear.times;
    let exact: Option<Vec<f64>> = moments
        .as_ref()
        .filter(|_| stable.is_some())
        .map(|m| times.iter().map(|t| m.expected_norm(&p, &x0, *t) / delta).collect());
    let worst: Option<Vec<f64>> = moments
        .as_ref()
        .filter(|_| stable.is_some())
        .map(|m| times.iter().map(|t| m.worst_case_growth(&p, *t).unwrap_or(f64::NAN)).collect());
    let lyapunov = moments.as_ref().and_then(|m| m.lyapunov_exponent());
    let bound: Option<Vec<f64>> = sigma2.map(|s| times.iter().map(|t| (s * t).exp()).collect());
    // Exceedance: certified guarantee P <= (delta/eps) e^{Sigma^2 t} <= alpha for
    // t <= ln(alpha eps / delta)/Sigma^2; empirical first time P > alpha.
    let exceedance: Vec<Value> = [0.01, 0.1, 0.5]
        .iter()
        .map(|&alpha| {
            let certified = sigma2.map(|s| {
                let t = (alpha * epsilon / delta).ln();
                if t < 0.0 {
                    Value::from(0.0)
                } else if s > 0.0 {
                    Value::from(t / s)
                } else {
                    Value::from("infinity")
                }
            });
            let empirical = times.iter().zip(&nonlinear.exceedance).find(|(_, p)| **p > alpha).map(|(t, _)| *t);
            json!({ "level": alpha, "certified_until": certified, "empirical_first_exceeded": empirical })
        })
        .collect();
    // Outputs.
    let dir = &args.out;
    // The name is data: a safe stem keeps every file inside --out.
    let file_stem = file_stem_noted(&spec.name);
    let name = excerpt(&spec.name);
    let observable_name = &coords[observable];
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
    let report = json!({
        "name": spec.name,
        "verdict": cert.json["verdict"],
        "sigma2": sigma2,
        "stopping_time": stopping_time,
        "epsilon": epsilon,
        "delta": delta,
        "parameters": {
            "paths": args.paths, "dt": args.dt, "t_end": t_end, "steps": nonlinear.steps, "seed": args.seed,
            "scheme": scheme.as_str(), "observable": observable_name, "bins": args.bins,
            "mu0": mu0, "threads": threads as u64,
        },
        "nonlinear": series(&nonlinear),
        "linearised": linear.as_ref().map(series),
        "exact_moments_over_delta": exact,
        "worst_case_over_delta": worst,
        "bound_over_delta": bound,
        "moment_lyapunov_exponent": lyapunov,
        "histogram": { "range": [settings.observable.lo, settings.observable.hi], "counts": nonlinear.histogram },
        "exceedance": exceedance,
    });
    let json_path = dir.join(format!("{file_stem}.json"));
    write_atomic(&json_path, spec::to_pretty_json(&report).as_bytes()).map_err(|e| write_failure(&json_path, &e))?;
    write_csv(
        &dir.join(format!("{file_stem}.csv")),
        &nonlinear,
        linear.as_ref(),
        exact.as_deref(),
        bound.as_deref(),
        worst.as_deref(),
        delta,
    )?;
    let mean_obs: Vec<f64> = nonlinear.mean.iter().map(|m| m[observable]).collect();
    write_density(
        &dir.join(format!("{file_stem}-density")),
        &DensityChart {
            title: format!("{name}: density of {observable_name} ({} paths, {})", args.paths, scheme.as_str()),
            observable: observable_name,
            times,
            histogram: &nonlinear.histogram,
            range: (settings.observable.lo, settings.observable.hi),
            mean: mean_obs,
            stopping_time,
        },
    )
    .map_err(io)?;
    if let Some(lin) = &linear {
        let over = |v: &[f64]| v.iter().map(|x| x / delta).collect::<Vec<_>>();
        let lin_mean = over(&lin.norm_mean);
        let se = over(&lin.norm_std_error);
        let mut curves = vec![("linearised ensemble (mean)".to_string(), lin_mean.clone(), 2, false)];
        if let Some(e) = &exact {
            curves.push(("exact second moments".into(), e.clone(), 0, false));
        }
        if let Some(w) = &worst {
            curves.push(("worst start (exact)".into(), w.clone(), 4, true));
        }
        if let Some(b) = &bound {
            curves.push((
                format!("certified bound exp(Sigma^2 t), Sigma^2 = {:.4}", sigma2.unwrap_or(0.0)),
                b.clone(),
                1,
                true,
            ));
        }
        curves.push(("nonlinear ensemble (mean)".into(), over(&nonlinear.norm_mean), 3, false));
        write_growth(
            &dir.join(format!("{file_stem}-growth")),
            &GrowthChart {
                title: format!("{name}: growth of E|dmu_t|_P^2"),
                times,
                curves,
                band: Some((
                    "ensemble ± 2 s.e.".into(),
                    lin_mean.iter().zip(&se).map(|(m, s)| m - 2.0 * s).collect(),
                    lin_mean.iter().zip(&se).map(|(m, s)| m + 2.0 * s).collect(),
                )),
                stopping_time,
            },
        )
        .map_err(io)?;
    }
    // Summary.
    eprintln!(
        "{}: {} paths x {} steps ({}), Casimir drift {:.1e}; outputs in {}",
        name,
        args.paths,
        nonlinear.steps,
        scheme.as_str(),
        nonlinear.casimir_drift,
        dir.display()
    );
    if let Some(s) = sigma2 {
        eprintln!(
            "  Sigma^2 = {s}, T({epsilon}, {delta}) = {}, moment Lyapunov exponent = {}",
            stopping_time.map_or("infinity".into(), |t| format!("{t:.3}")),
            lyapunov.map_or("-".into(), |l| format!("{l:.4}"))
        );
    }
    for e in &exceedance {
        eprintln!(
            "  P(|dmu_t|_P^2 > {epsilon}) <= {}: certified until t = {}, first exceeded in the ensemble at t = {}",
            e["level"], e["certified_until"], e["empirical_first_exceeded"]
        );
    }
    Ok(())
}

fn write_csv(
    path: &std::path::Path,
    nonlinear: &EnsembleStats,
    linear: Option<&EnsembleStats>,
    exact: Option<&[f64]>,
    bound: Option<&[f64]>,
    worst: Option<&[f64]>,
    delta: f64,
) -> Result<(), Failure> {
    let mut out = String::from(
        "t,nonlinear_norm_over_delta,nonlinear_exceedance,linearised_norm_over_delta,linearised_std_error_over_delta,exact_over_delta,worst_over_delta,bound_over_delta\n",
    );
    let opt = |v: Option<&[f64]>, k: usize| v.map_or(String::new(), |v| format!("{}", v[k]));
    for (k, t) in nonlinear.times.iter().enumerate() {
        out.push_str(&format!(
            "{t},{},{},{},{},{},{},{}\n",
            nonlinear.norm_mean[k] / delta,
            nonlinear.exceedance[k],
            linear.map_or(String::new(), |l| format!("{}", l.norm_mean[k] / delta)),
            linear.map_or(String::new(), |l| format!("{}", l.norm_std_error[k] / delta)),
            opt(exact, k),
            opt(worst, k),
            opt(bound, k),
        ));
    }
    write_atomic(path, out.as_bytes()).map_err(|e| write_failure(path, &e))
}
