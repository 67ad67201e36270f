//! `verify simulate` on a fluid spec: one x-mode's discretised linear SDE,
//! a Monte Carlo of it and its exact second moment, beside the growth the
//! analysis certifies for that mode on the same grid
//! ([`spec::simulate_fluid`]; docs/simulation.md, "Fluid specs").

use crate::messages::excerpt;
use crate::paths::{file_stem_noted, write_atomic, write_failure};
use crate::plots::{write_growth, GrowthChart};
use crate::simulate_cmd::SimulateArgs;
use crate::Failure;
use serde_json::json;
use spec::{FluidSimulationError, FluidSimulationOptions};

fn bad(message: String) -> Failure {
    Failure::BadInput(message)
}

/// Flags of `simulate` that mean nothing for a fluid spec: refused by name
/// rather than ignored.
fn refuse_finite_dimensional_flags(args: &SimulateArgs) -> Result<(), Failure> {
    let refuse =
        |flag: &str, why: &str| Err(bad(format!("{flag}: {why} (a fluid spec simulates one x-mode's linear SDE)")));
    if args.shard.is_some() || !args.merge.is_empty() {
        return refuse("--shard/--merge", "sharding is for finite-dimensional specs");
    }
    if args.compare_isotropic {
        return refuse("--compare-isotropic", "isotropic noise does not preserve the shear flow's coadjoint orbit");
    }
    if args.observable.is_some() {
        return refuse("--observable", "the observable is the mode's energy V");
    }
    if args.scheme != "lie" {
        return refuse("--scheme", "the mode is simulated by Strang splitting of its exact drift and noise flows");
    }
    if args.delta.is_some() || args.epsilon.is_some() {
        return refuse("--delta/--epsilon", "the SDE is linear, so only the ratio E V(t) / V(0) is reported");
    }
    Ok(())
}

/// The library's error with the command line's flags.
fn failure(shown: &str, e: FluidSimulationError) -> Failure {
    match e {
        FluidSimulationError::Invalid { field, message } => {
            let flag = match field {
                "t_end/dt" => "--t-end/--dt".to_string(),
                other => format!("--{}", other.replace('_', "-")),
            };
            bad(format!("{flag}: {}", message.replace("t_end", "--t-end").replace("(and dt)", "(and --dt)")))
        }
        FluidSimulationError::TooLong { path_steps, unknowns, minutes } => bad(format!(
            "--paths/--dt/--t-end: {path_steps:.2e} path-steps of {unknowns} unknowns would take about {minutes:.0} minutes here; lower them or --ny, or pass --force"
        )),
        e @ FluidSimulationError::NoGrowth { .. } => bad(format!("{shown}: {e}")),
        e @ FluidSimulationError::Unrepresentable(_) => bad(format!("{shown}: {e}")),
        FluidSimulationError::Failed(m) => Failure::Failed(format!("internal: {m}")),
        // (nothing cancels a command-line run: Ctrl-C ends the process)
        e @ FluidSimulationError::Cancelled => Failure::Failed(format!("{shown}: {e}")),
    }
}

/// `verify simulate FLUID-SPEC`.
pub fn run(args: &SimulateArgs, text: &str) -> Result<(), Failure> {
    refuse_finite_dimensional_flags(args)?;
    let shown = args.spec.display().to_string();
    let spec = spec::parse_fluid_spec(text).map_err(|e| bad(format!("{shown}: {e}")))?;
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get) as f64;
    let options = FluidSimulationOptions {
        mode: args.mode,
        ny: args.ny,
        paths: args.paths,
        dt: args.dt,
        t_end: args.t_end,
        outputs: args.outputs,
        seed: args.seed,
        force: args.force,
        threads: (rayon::current_num_threads() as f64).min(cores),
    };
    // A bar on stderr when it is a terminal, for the Monte Carlo and the
    // exact moment (empty during the analysis on the grid; notes print
    // above it).
    let bar = crate::progress_bar(1, "{msg} [{bar:30}] {percent:>3}% ({elapsed})");
    let note = |n: String| {
        let line = format!(
            "note: {}",
            n.replace("forcing runs it", "--force runs it")
                .replace("smaller ny", "smaller --ny")
                .replace("shorter t_end", "shorter --t-end")
                .replace("ask for t_end ", "pass --t-end ")
        );
        match &bar {
            Some(bar) => bar.suspend(|| eprintln!("{line}")),
            None => eprintln!("{line}"),
        }
    };
    let state = outcome::Progress::new();
    let simulate = || spec::simulate_fluid_with(&spec, &options, &state, &mut |n| note(n));
    let run = match &bar {
        Some(bar) => {
            bar.set_message(excerpt(&shown));
            let run = crate::run_showing_progress(bar, &state, simulate);
            bar.finish_and_clear();
            run
        }
        None => simulate(),
    };
    let run = run.map_err(|e| failure(&shown, e))?;
    let spec::FluidSimulation {
        report,
        compressible,
        m,
        ny,
        certified,
        rate,
        times,
        mean,
        std_error: se,
        exact,
        bound,
        rate_curve,
        paper,
        k,
        unknowns,
        verified,
        paths,
        steps,
        dt,
        t_end,
        exact_over_bound,
        agreeing,
        paper_exceeded_at,
        estimated_seconds,
        run_seconds,
    } = run;
    let records = times.len();
    let report = &report;

    // Outputs.
    let name = excerpt(&spec.name);
    let stem = format!("{}-m{m}", file_stem_noted(&spec.name));
    let dir = &args.out;
    let json_path = dir.join(format!("{stem}.json"));
    write_atomic(&json_path, spec::to_pretty_json(report).as_bytes()).map_err(|e| write_failure(&json_path, &e))?;
    if args.npz {
        let npz_path = dir.join(format!("{stem}.npz"));
        crate::npz_out::write_json_arrays(&npz_path, report).map_err(|e| write_failure(&npz_path, &e))?;
    }
    let mut csv = String::from("t,monte_carlo_mean,monte_carlo_std_error,exact,certified_bound,initial_rate_bound\n");
    for (i, t) in times.iter().enumerate() {
        let e = exact.as_ref().map_or(String::new(), |e| e[i].to_string());
        csv.push_str(&format!("{t},{},{},{e},{},{}\n", mean[i], se[i], bound[i], rate_curve[i]));
    }
    let csv_path = dir.join(format!("{stem}.csv"));
    write_atomic(&csv_path, csv.as_bytes()).map_err(|e| write_failure(&csv_path, &e))?;
    let num = |x: f64| crate::table::format_number(&json!(x));
    let mut curves = vec![];
    if let Some(e) = &exact {
        curves.push(("exact second moment".to_string(), e.clone(), 0, false));
    }
    curves.push(("Monte Carlo mean".into(), mean.clone(), 2, false));
    if compressible {
        curves.push((
            format!("exp(lambda_B t), the discrete SDE's rate lambda_B = {}", num(rate)),
            rate_curve.clone(),
            4,
            true,
        ));
    }
    if let Some(p) = paper {
        curves.push((
            format!("paper's bound exp({} t)", num(p)),
            times.iter().map(|t| (p * t).exp()).collect(),
            3,
            true,
        ));
    }
    write_growth(
        &dir.join(format!("{stem}-growth")),
        &GrowthChart {
            title: format!("{name}: E V(t)/V(0), x-mode {m}, ny = {ny}"),
            times: &times,
            curves,
            band: Some((
                "Monte Carlo ± 2 s.e.".into(),
                mean.iter().zip(se.iter()).map(|(m, s)| m - 2.0 * s).collect(),
                mean.iter().zip(se.iter()).map(|(m, s)| m + 2.0 * s).collect(),
            )),
            bound: Some((format!("certified exp(Sigma_k^2 t), Sigma_k^2 = {}", num(certified)), bound.clone())),
            stopping_time: None,
            y_label: "E V(t) / V(0), from the fastest start",
            ratio_caption: if compressible {
                "divided by the certified exp(Sigma_k^2 t) of the continuum generator form; the discrete SDE's own bound is exp(lambda_B t)"
            } else {
                "divided by the certified exp(Sigma_k^2 t): the claim is that the exact moment stays at or below 1"
            },
        },
    )
    .map_err(|e| Failure::Failed(e.to_string()))?;

    // Summary.
    eprintln!(
        "{name}: x-mode {m} (k = {}) at ny = {ny} ({} unknowns): {paths} paths x {steps} steps of {} in {:.1} s (estimated {:.1} s); outputs in {}",
        num(k),
        unknowns,
        num(dt),
        run_seconds,
        estimated_seconds,
        dir.display()
    );
    eprintln!(
        "  certified Sigma_k^2 = {} ({}); initial rate from the fastest start {}{}",
        num(certified),
        if verified { "verified upper bound" } else { "not verified" },
        num(rate),
        if compressible {
            " (lambda_B: the pointwise noise on the discrete K, within Sigma_k^2 + the Casimir defect)"
        } else {
            ""
        }
    );
    // (an excess that moves exp(rate t) by less than 1e-9 over the run is rounding)
    if compressible && (rate - certified) * t_end > 1e-9 {
        eprintln!(
            "  the discrete SDE's rate exceeds the certified Sigma_k^2 by {} (the Casimir defect of the pointwise noise on this grid; it vanishes under refinement at fixed k): the certified number is the continuum generator's",
            num(rate - certified)
        );
    }
    let last = times.len() - 1;
    eprintln!(
        "  at t = {}: Monte Carlo {} ± {}, exact {}, certified exp(Sigma_k^2 t) = {}",
        num(t_end),
        num(mean[last]),
        num(se[last]),
        exact.as_ref().map_or("skipped".into(), |e| num(e[last])),
        num(bound[last])
    );
    if let (Some(r), Some(a)) = (exact_over_bound, agreeing) {
        eprintln!(
            "  exact / certified bound: at most {} over the run; Monte Carlo within 4 s.e. (plus 1e-3 of the value) of exact at {a} of {records} times",
            num(r)
        );
    }
    if let (Some(p), Some(t)) = (paper, paper_exceeded_at) {
        eprintln!("  the paper's bound exp({} t) is exceeded from t = {}", num(p), num(t));
    }
    Ok(())
}
