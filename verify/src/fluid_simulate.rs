//! `verify simulate` on a fluid spec: one x-mode's discretised linear SDE,
//! a Monte Carlo of it and its exact second moment, beside the growth the
//! analysis certifies for that mode on the same grid
//! (docs/simulation.md, "Fluid specs").

use crate::messages::excerpt;
use crate::paths::{file_stem_noted, write_atomic, write_failure};
use crate::plots::{write_growth, GrowthChart};
use crate::simulate_cmd::SimulateArgs;
use crate::Failure;
use fluid::analysis::{analyse, mode_study, FluidModel, FluidProblem, Verdict};
use serde_json::json;

/// The grid the simulation runs on when `--ny` is not given (at most the
/// spec's): the SDE is dense, and its exact second moment costs `O(n^3)`
/// per step. The compressible model has three unknowns per node and a
/// stiffer moment equation (its acoustic frequencies), hence the coarser
/// default.
const DEFAULT_NY: (usize, usize) = (32, 16);
/// The finest grid `--ny` may ask for (dense matrices of `3 ny` unknowns).
const MAX_NY: usize = 512;
/// Paths when `--paths` is not given.
const DEFAULT_PATHS: usize = 1000;
/// At most this many paths.
const MAX_PATHS: usize = 10_000_000;
/// Floating-point operations per second and thread assumed by the cost
/// estimates. Measured on the 2-core machine (2026-11-27): the incompressible
/// exact moment at ny = 128 ran at 7e9 of the estimate's flops per second,
/// the compressible one at ny = 16 at 1.5e10 (its Taylor steps stop before
/// the 40 terms counted), the Monte Carlo at ny = 32 at about 1e10 on two
/// threads.
const FLOPS_PER_SECOND: f64 = 6e9;
/// The exact second moment is skipped (with a note) above this estimate
/// unless `--force`.
const EXACT_SECONDS: f64 = 120.0;

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

/// `verify simulate FLUID-SPEC`.
pub fn run(args: &SimulateArgs, text: &str) -> Result<(), Failure> {
    refuse_finite_dimensional_flags(args)?;
    let shown = args.spec.display();
    let spec = spec::parse_fluid_spec(text).map_err(|e| bad(format!("{shown}: {e}")))?;
    let compressible = matches!(spec.problem.model, FluidModel::Compressible { .. });
    let default_ny = if compressible { DEFAULT_NY.1 } else { DEFAULT_NY.0 };
    let ny = args.ny.unwrap_or(spec.problem.ny.min(default_ny));
    let low = spec::NY_RANGE.0;
    if !(low..=MAX_NY).contains(&ny) {
        return Err(bad(format!(
            "--ny: the simulation's grid must have {low} to {MAX_NY} points (dense SDE), got {ny}"
        )));
    }
    let problem = FluidProblem { ny, ..spec.problem.clone() };
    let analysis = analyse(&problem, &spec.settings).map_err(|e| bad(format!("{shown}: {e}")))?;
    if analysis.verdict != Verdict::Stable || analysis.modes.is_empty() {
        return Err(bad(format!(
            "{shown}: the analysis at ny = {ny} is `{}`: {}; there is no certified growth to simulate beside",
            analysis.verdict.as_str(),
            analysis.reason
        )));
    }
    let m = match args.mode {
        Some(m) if (1..=problem.x_modes).contains(&m) => m,
        Some(m) => return Err(bad(format!("--mode: the spec has x-modes 1 to {}, got {m}", problem.x_modes))),
        // Compressible: the gravest mode. The pointwise noise of the
        // discrete SDE differs from the certified continuum generator form
        // by the Casimir defect, which grows with k (docs/fluids.md §1b): on
        // a coarse grid the short waves of the discrete SDE outgrow the
        // certified Sigma_k^2 (at ny = 16, mode 32 of the compatible-noise
        // fixture: lambda_B = 650 against 0.087).
        None if compressible => 1,
        // Incompressible: the mode whose certified growth is largest (the
        // gravest of equals: `max_by` would give the last).
        None => {
            let growth = |r: &fluid::analysis::ModeResult| r.sigma2_upper.unwrap_or(r.sigma2);
            let mut best = &analysis.modes[0];
            for r in &analysis.modes[1..] {
                if growth(r) > growth(best) {
                    best = r;
                }
            }
            best.m
        }
    };
    let Some(row) = analysis.modes.iter().find(|r| r.m == m) else {
        return Err(Failure::Failed(format!("internal: mode {m} missing from the analysis")));
    };
    let (certified, verified) = (row.sigma2_upper.unwrap_or(row.sigma2), row.sigma2_upper.is_some());
    let study = mode_study(&problem, analysis.form.galilean_shift, m).ok_or_else(|| {
        Failure::Failed(format!(
            "internal: the SDE of mode {m} at ny = {ny} could not be formed (form not definite in floating point)"
        ))
    })?;
    let rate = study.initial_rate();

    // Times: `steps` of `dt`, recorded every `record_every`.
    let paths = args.paths.unwrap_or(DEFAULT_PATHS);
    if !(2..=MAX_PATHS).contains(&paths) {
        return Err(bad(format!("--paths: need 2 to {MAX_PATHS} paths, got {paths}")));
    }
    let dt = args.dt;
    if !(dt.is_finite() && dt > 0.0) {
        return Err(bad(format!("--dt: must be positive and finite, got {dt}")));
    }
    // Default: long enough for the bound exp(Sigma^2 t) to reach e, within [1, 10].
    let t_end = args.t_end.unwrap_or(if certified > 0.0 { (1.0 / certified).clamp(1.0, 10.0) } else { 10.0 });
    if !(t_end.is_finite() && t_end >= dt) {
        return Err(bad(format!("--t-end: must be finite and at least --dt = {dt}, got {t_end}")));
    }
    if args.outputs == 0 {
        return Err(bad("--outputs: need at least one output time".into()));
    }
    // exp(Sigma_k^2 t) must be a double over the run (noise near 1e100
    // makes Sigma_k^2 near 1e200).
    if certified * t_end > 700.0 {
        return Err(bad(format!(
            "--t-end: the certified exp(Sigma_k^2 t) with Sigma_k^2 = {certified:e} leaves the range of doubles before t = {t_end:e}; pass --t-end (and --dt) below {:e}",
            700.0 / certified
        )));
    }
    let wanted = (t_end / dt).ceil();
    if wanted > 1e8 {
        return Err(bad(format!("--t-end/--dt: {wanted:e} steps per path; at most 1e8")));
    }
    let wanted = wanted as usize;
    let record_every = (wanted / args.outputs).max(1);
    let steps = wanted.div_ceil(record_every) * record_every;
    let records = steps / record_every;
    let t_end = steps as f64 * dt;

    // Costs.
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get) as f64;
    let threads = (rayon::current_num_threads() as f64).min(cores);
    let mc_seconds = paths as f64 * steps as f64 * study.flops_per_path_step() / (FLOPS_PER_SECOND * threads);
    if mc_seconds > 900.0 && !args.force {
        return Err(bad(format!(
            "--paths/--dt/--t-end: {:.2e} path-steps of {} unknowns would take about {:.0} minutes here; lower them or --ny, or pass --force",
            paths as f64 * steps as f64,
            study.unknowns(),
            mc_seconds / 60.0
        )));
    }
    let exact_seconds = study.exact_growth_flops(t_end, records) / FLOPS_PER_SECOND;
    let run_exact = exact_seconds.is_finite() && (exact_seconds <= EXACT_SECONDS || args.force);
    if !exact_seconds.is_finite() {
        eprintln!(
            "note: the exact second moment would need more than {} Taylor steps per output time (the noise's amplitude): not run",
            fluid::simulate::MAX_TAYLOR_STEPS
        );
    } else if !run_exact {
        eprintln!(
            "note: the exact second moment would take about {:.0} minutes at ny = {ny}: skipped (--force runs it, a smaller --ny is faster)",
            exact_seconds / 60.0
        );
    }
    if mc_seconds + if run_exact { exact_seconds } else { 0.0 } > 10.0 {
        eprintln!(
            "note: about {:.0} s of computation ({:.2e} path-steps on {threads} threads)",
            mc_seconds + if run_exact { exact_seconds } else { 0.0 },
            paths as f64 * steps as f64
        );
    }
    let (rows, exact) = rayon::join(
        || study.ensemble(dt, steps, record_every, paths, args.seed),
        || run_exact.then(|| study.exact_growth(t_end, records)),
    );
    let rows = rows.ok_or_else(|| Failure::Failed("internal: the drift's propagator could not be formed".into()))?;
    let times: Vec<f64> = rows.iter().map(|r| r.t).collect();
    let mean: Vec<f64> = rows.iter().map(|r| r.mean).collect();
    let se: Vec<f64> = rows.iter().map(|r| r.std_error).collect();
    let exact: Option<Vec<f64>> = exact.filter(|e| e.len() == records).map(|e| e.iter().map(|(_, v)| *v).collect());
    let overflowed = mean.iter().chain(exact.iter().flatten()).filter(|v| !v.is_finite()).count();
    if overflowed > 0 {
        eprintln!(
            "note: {overflowed} values of the Monte Carlo mean or the exact moment are not finite (beyond the range of doubles; null in the JSON): a shorter --t-end shows the growth"
        );
    }
    let bound: Vec<f64> = times.iter().map(|t| (certified * t).exp()).collect();
    let rate_curve: Vec<f64> = times.iter().map(|t| (rate * t).exp()).collect();

    // What the run shows.
    let exact_over_bound = exact.as_ref().map(|e| e.iter().zip(&bound).map(|(e, b)| e / b).fold(0.0, f64::max));
    // The splitting's bias is O(dt^2); 4 standard errors plus 1e-3 of the
    // value (as in tests/fluid.rs) is the agreement asked of each time.
    let agreeing = exact.as_ref().map(|e| {
        e.iter().zip(&mean).zip(&se).filter(|((e, m), s)| (*m - *e).abs() <= 4.0 * *s + 1e-3 * e.abs()).count()
    });
    let paper = analysis.paper_bound;
    // Only the exact moment (not the Monte Carlo's noisy mean) decides this.
    let paper_exceeded_at = paper
        .zip(exact.as_ref())
        .and_then(|(p, e)| times.iter().zip(e).find(|(t, v)| **v > (p * **t).exp() * (1.0 + 1e-9)).map(|(t, _)| *t));

    // Outputs.
    let name = excerpt(&spec.name);
    let stem = format!("{}-m{m}", file_stem_noted(&spec.name));
    let dir = &args.out;
    let report = json!({
        "kind": "fluid-simulation",
        "format": 1,
        "engine": env!("CARGO_PKG_VERSION"),
        "name": spec.name,
        "spec_digest": spec::spec_digest(&spec.raw),
        "model": problem.model.as_str(),
        "ny": ny,
        "unknowns": study.unknowns(),
        "m": m,
        "k": study.k(),
        "verdict_at_ny": analysis.verdict.as_str(),
        "sigma2_mode": certified,
        "sigma2_mode_verified": verified,
        "sigma2": analysis.sigma2_upper.or(analysis.sigma2),
        "initial_rate": rate,
        "paper_bound": paper,
        "paths": paths,
        "dt": dt,
        "steps": steps,
        "t_end": t_end,
        "seed": args.seed,
        "times": times,
        "monte_carlo_mean": mean,
        "monte_carlo_std_error": se,
        "exact": exact,
        "certified_bound": bound,
        "initial_rate_bound": rate_curve,
        "summary": {
            "exact_over_certified_bound_max": exact_over_bound,
            "monte_carlo_within_4_se_of_exact": agreeing,
            "records": records,
            "paper_bound_exceeded_at": paper_exceeded_at,
        },
    });
    let json_path = dir.join(format!("{stem}.json"));
    write_atomic(&json_path, spec::to_pretty_json(&report).as_bytes()).map_err(|e| write_failure(&json_path, &e))?;
    if args.npz {
        let npz_path = dir.join(format!("{stem}.npz"));
        crate::npz_out::write_json_arrays(&npz_path, &report).map_err(|e| write_failure(&npz_path, &e))?;
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
            title: format!("{name}: E V(t) / V(0) of x-mode {m}, ny = {ny}, from the fastest start"),
            times: &times,
            curves,
            band: Some((
                "Monte Carlo ± 2 s.e.".into(),
                mean.iter().zip(&se).map(|(m, s)| m - 2.0 * s).collect(),
                mean.iter().zip(&se).map(|(m, s)| m + 2.0 * s).collect(),
            )),
            bound: Some((format!("certified exp(Sigma_k^2 t), Sigma_k^2 = {}", num(certified)), bound.clone())),
            stopping_time: None,
            y_label: "E V(t) / V(0)",
        },
    )
    .map_err(|e| Failure::Failed(e.to_string()))?;

    // Summary.
    eprintln!(
        "{name}: x-mode {m} (k = {}) at ny = {ny} ({} unknowns): {paths} paths x {steps} steps of {}; outputs in {}",
        num(study.k()),
        study.unknowns(),
        num(dt),
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
    if compressible && rate > certified {
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
            "  exact / certified bound: at most {} over the run; Monte Carlo within 4 s.e. of exact at {a} of {records} times",
            num(r)
        );
    }
    if let (Some(p), Some(t)) = (paper, paper_exceeded_at) {
        eprintln!("  the paper's bound exp({} t) is exceeded from t = {}", num(p), num(t));
    }
    Ok(())
}
