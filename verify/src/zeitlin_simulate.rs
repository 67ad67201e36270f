//! `verify simulate` on a Zeitlin spec: one block (azimuthal wavenumber
//! `m`) of the linearised SDE about a zonal state, a Monte Carlo of it and
//! its exact second moment, beside the certificate's proved bound
//! ([`spec::simulate_zeitlin`]; docs/simulation.md, "Zeitlin specs").

use crate::messages::excerpt;
use crate::paths::{file_stem_noted, write_atomic, write_failure};
use crate::plots::{write_growth, GrowthChart};
use crate::simulate_cmd::SimulateArgs;
use crate::Failure;
use serde_json::{json, Value};
use spec::{ZeitlinSimulationError, ZeitlinSimulationOptions};

fn bad(message: String) -> Failure {
    Failure::BadInput(message)
}

/// Flags of `simulate` that mean nothing for a Zeitlin spec: refused by
/// name rather than ignored.
fn refuse_other_flags(args: &SimulateArgs) -> Result<(), Failure> {
    let refuse =
        |flag: &str, why: &str| Err(bad(format!("{flag}: {why} (a Zeitlin spec simulates one block's linear SDE)")));
    if args.shard.is_some() || !args.merge.is_empty() {
        return refuse("--shard/--merge", "sharding is for finite-dimensional specs");
    }
    if args.compare_isotropic {
        return refuse("--compare-isotropic", "isotropic noise does not preserve the zonal state's coadjoint orbit");
    }
    if args.observable.is_some() {
        return refuse("--observable", "the observable is the block's |z|_P^2");
    }
    if args.scheme != "lie" {
        return refuse("--scheme", "the block is simulated by Strang splitting of its exact drift and noise flows");
    }
    if args.epsilon.is_some() {
        return refuse("--epsilon", "no threshold is drawn: the report is E|dW_t|_P^2 / |dW_0|_P^2");
    }
    if args.ny.is_some() {
        return refuse("--ny", "the grid is the spec's N");
    }
    Ok(())
}

fn failure(shown: &str, e: ZeitlinSimulationError) -> Failure {
    // The library names its options; the flags differ for the block
    // (`--mode`), the two-field `t_end/dt` and the spec's own `N`.
    match e {
        ZeitlinSimulationError::Invalid { field, message } => {
            let flag = match field {
                "block" => "--mode".to_string(),
                "t_end/dt" => "--t-end/--dt".to_string(),
                "N" => format!("{shown}: $.zeitlin.N"),
                other => format!("--{}", other.replace('_', "-")),
            };
            bad(format!("{flag}: {message}"))
        }
        ZeitlinSimulationError::TooLong { path_steps, unknowns, minutes } => bad(format!(
            "--paths/--dt/--t-end: {path_steps:.2e} path-steps of {unknowns} complex unknowns would take about {minutes:.0} minutes here; lower them, or pass --force"
        )),
        e @ (ZeitlinSimulationError::NothingToCompare(_) | ZeitlinSimulationError::Unrepresentable(_)) => {
            bad(format!("{shown}: {e}"))
        }
        e => Failure::Failed(format!("{shown}: {e}")),
    }
}

/// A series of the report (a value that is not a number reads as NaN, so
/// the series keep their lengths).
fn floats(v: &Value) -> Vec<f64> {
    v.as_array().map(|a| a.iter().map(|x| x.as_f64().unwrap_or(f64::NAN)).collect()).unwrap_or_default()
}

/// `verify simulate ZEITLIN-SPEC`.
pub fn run(args: &SimulateArgs, text: &str) -> Result<(), Failure> {
    refuse_other_flags(args)?;
    let shown = args.spec.display().to_string();
    let base = args.spec.parent().map(std::path::Path::to_path_buf);
    let value: Value = serde_json::from_str(text).map_err(|e| bad(format!("{shown}: {e}")))?;
    let spec = spec::zeitlin_spec_from_value_in(value, base.as_deref()).map_err(|e| bad(format!("{shown}: {e}")))?;
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get) as f64;
    let options = ZeitlinSimulationOptions {
        block: args.mode,
        paths: args.paths,
        dt: args.dt,
        t_end: args.t_end,
        outputs: args.outputs,
        seed: args.seed,
        force: args.force,
        threads: (rayon::current_num_threads() as f64).min(cores),
        delta: args.delta,
    };
    let bar = crate::progress_bar(1, "{msg} [{bar:30}] {percent:>3}% ({elapsed})");
    let state = outcome::Progress::new();
    let started = std::time::Instant::now();
    // Notes are collected and printed after the run (they are decided
    // before it starts, while the bar would overwrite them).
    let simulate = || {
        let mut notes = vec![];
        spec::simulate_zeitlin(&spec, &options, &state, &mut |n| notes.push(n)).map(|r| (r, notes))
    };
    let report = match &bar {
        Some(bar) => {
            bar.set_message(excerpt(&shown));
            let run = crate::run_showing_progress(bar, &state, simulate);
            bar.finish_and_clear();
            run
        }
        None => simulate(),
    };
    let (report, notes) = report.map_err(|e| failure(&shown, e))?;
    for n in notes {
        let line = format!(
            "note: {}",
            n.replace("forcing runs it", "--force runs it").replace("ask for t_end ", "pass --t-end ")
        );
        eprintln!("{line}");
    }
    let seconds = started.elapsed().as_secs_f64();
    let m = report["block"].as_u64().unwrap_or(0);
    let stem = format!("{}-m{m}", file_stem_noted(&spec.name));
    let dir = &args.out;
    let json_path = dir.join(format!("{stem}.json"));
    write_atomic(&json_path, spec::to_pretty_json(&report).as_bytes()).map_err(|e| write_failure(&json_path, &e))?;
    if args.npz {
        let npz_path = dir.join(format!("{stem}.npz"));
        crate::npz_out::write_json_arrays(&npz_path, &report).map_err(|e| write_failure(&npz_path, &e))?;
    }
    let times = floats(&report["times"]);
    let qtimes = floats(&report["times_qtime"]);
    let mean = floats(&report["monte_carlo_mean"]);
    let se = floats(&report["monte_carlo_std_error"]);
    let exact = report["exact"].as_array().map(|_| floats(&report["exact"]));
    let bound = floats(&report["certified_bound"]);
    let block_bound = floats(&report["block_bound"]);
    let nonlinear = report["nonlinear"].as_object().map(|_| floats(&report["nonlinear"]["mean"]));
    let nonlinear_se = report["nonlinear"].as_object().map(|_| floats(&report["nonlinear"]["std_error"]));
    let mut csv = String::from(
        "t,qtime,monte_carlo_mean,monte_carlo_std_error,exact,certified_bound,block_bound,nonlinear_mean,nonlinear_std_error\n",
    );
    for (i, t) in times.iter().enumerate() {
        let e = exact.as_ref().map_or(String::new(), |e| e[i].to_string());
        let nl = nonlinear.as_ref().map_or(String::new(), |v| v[i].to_string());
        let nls = nonlinear_se.as_ref().map_or(String::new(), |v| v[i].to_string());
        csv.push_str(&format!(
            "{t},{},{},{},{e},{},{},{nl},{nls}\n",
            qtimes[i], mean[i], se[i], bound[i], block_bound[i]
        ));
    }
    let csv_path = dir.join(format!("{stem}.csv"));
    write_atomic(&csv_path, csv.as_bytes()).map_err(|e| write_failure(&csv_path, &e))?;
    let num = |x: f64| crate::table::format_number(&json!(x));
    let certified = report["sigma2_upper"].as_f64().or(report["sigma2"].as_f64()).unwrap_or(0.0);
    let lambda = report["block_lambda_max"].as_f64().unwrap_or(0.0);
    let mut curves = vec![];
    if let Some(e) = &exact {
        curves.push(("exact second moment".to_string(), e.clone(), 0, false));
    }
    curves.push(("Monte Carlo mean".into(), mean.clone(), 2, false));
    if let Some(v) = &nonlinear {
        let delta = report["nonlinear"]["delta"].as_f64().unwrap_or(0.0);
        curves.push((format!("nonlinear model, delta = {}", num(delta)), v.clone(), 4, false));
    }
    curves.push((format!("block's exp(lambda_max t), lambda_max = {}", num(lambda)), block_bound.clone(), 3, true));
    let name = excerpt(&spec.name);
    write_growth(
        &dir.join(format!("{stem}-growth")),
        &GrowthChart {
            title: format!("{name}: E|z_t|_P^2 / |z_0|_P^2, block m = {m}, N = {}", report["N"]),
            times: &times,
            curves,
            band: Some((
                "Monte Carlo ± 2 s.e.".into(),
                mean.iter().zip(&se).map(|(m, s)| m - 2.0 * s).collect(),
                mean.iter().zip(&se).map(|(m, s)| m + 2.0 * s).collect(),
            )),
            bound: Some((format!("certified exp(Sigma^2 t), Sigma^2 = {}", num(certified)), bound.clone())),
            stopping_time: None,
            y_label: "E|z_t|_P^2 / |z_0|_P^2, from the fastest start",
            ratio_caption:
                "divided by the certified exp(Sigma^2 t): the claim is that the exact moment stays at or below 1",
        },
    )
    .map_err(|e| Failure::Failed(e.to_string()))?;
    let last = times.len() - 1;
    eprintln!(
        "{name}: block m = {m} of N = {} ({} complex unknowns): {} paths x {} steps of {} in {seconds:.1} s; outputs in {}",
        report["N"],
        report["unknowns"],
        report["paths"],
        report["steps"],
        num(args.dt),
        dir.display()
    );
    eprintln!(
        "  certified Sigma^2 = {} (per unit t; {} per unit qtime); the block's lambda_max = {}, initial rate from the fastest start {}",
        num(certified),
        num(certified * report["hbar"].as_f64().unwrap_or(0.0)),
        num(lambda),
        num(report["initial_rate"].as_f64().unwrap_or(0.0))
    );
    eprintln!(
        "  at t = {} (qtime {}): Monte Carlo {} ± {}, exact {}, certified exp(Sigma^2 t) = {}",
        num(times[last]),
        num(qtimes[last]),
        num(mean[last]),
        num(se[last]),
        exact.as_ref().map_or("skipped".into(), |e| num(e[last])),
        num(bound[last])
    );
    if let Some(v) = &nonlinear {
        eprintln!(
            "  nonlinear model ({} paths, delta = {}): {} ± {} at t = {}; Casimir drift {}, momentum drift {}",
            report["nonlinear"]["paths"],
            num(report["nonlinear"]["delta"].as_f64().unwrap_or(0.0)),
            num(v[last]),
            num(nonlinear_se.as_ref().map_or(f64::NAN, |s| s[last])),
            num(times[last]),
            num(report["nonlinear"]["casimir_drift"].as_f64().unwrap_or(f64::NAN)),
            num(report["nonlinear"]["momentum_drift"].as_f64().unwrap_or(f64::NAN))
        );
    }
    if let (Some(r), Some(a)) = (
        report["summary"]["exact_over_certified_bound_max"].as_f64(),
        report["summary"]["monte_carlo_agrees_with_exact"].as_u64(),
    ) {
        eprintln!(
            "  exact / certified bound: at most {} over the run; Monte Carlo within 4 s.e. (plus 1e-3 of the value) of exact at {a} of {} times",
            num(r),
            times.len()
        );
    }
    Ok(())
}
