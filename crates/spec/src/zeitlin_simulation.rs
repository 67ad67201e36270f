//! One block of a Zeitlin spec's linearised SDE simulated beside its
//! certified growth: what `verify simulate ZEITLIN-SPEC` and the Python
//! package's `simulate_zeitlin` run (docs/simulation.md, "Zeitlin specs").
//!
//! The state must be zonal in some frame (as given, or about a tilted axis:
//! the rotated system is the same system) and certified `stable` with a
//! conserved form. About `W_e = i diag(omega)` a perturbation's entries on
//! the diagonal `m` evolve by themselves ([`zeitlin::block_sde`]); the block
//! (default: the one with the largest `lambda_max(Q_m, P_m)`) starts from the
//! direction whose `E|z|_P^2` grows fastest, and a Monte Carlo and the
//! scheme's exact second moment give `E|z_t|_P^2 / |z_0|_P^2` beside the
//! certificate's proved `exp(sigma2_upper t)` and the block's own
//! `exp(lambda_max t)`. Beside them, a smaller ensemble of the nonlinear
//! stochastic Zeitlin model (the isospectral midpoint scheme,
//! [`zeitlin::isospectral`]) from `W_e + sqrt(delta) X` on the same Brownian
//! increments, with its Casimir drift. Times are the model's `t`
//! (quflow's), and the report gives them per `qtime = t / hbar` too.

use crate::run_options::{check_paths_dt_outputs, MAX_STEPS};
use crate::zeitlin::{analyse_zeitlin_with, ZeitlinInput, ZeitlinOutcome, ZeitlinSpec};
use nalgebra::Complex;
use outcome::{Progress, Verdict};
use serde_json::{json, Value};
use zeitlin::analysis::ZeitlinAnalysis;
use zeitlin::block_sde::BlockSde;
use zeitlin::isospectral::IsospectralError;

/// Paths when none are asked for.
pub const ZEITLIN_SIMULATION_DEFAULT_PATHS: usize = 1000;
/// `N` at most (dense blocks of `N - m` complex unknowns; the exact moment
/// costs `O(N^3)` per step).
pub const ZEITLIN_SIMULATION_MAX_N: usize = 512;
/// Floating-point operations per second and thread assumed by the
/// estimates (complex matrix products and matrix-vector products of size
/// `N - m`, cache-resident).
const FLOPS_PER_SECOND: f64 = 1e9;
/// A Monte Carlo estimated above this many seconds is refused unless forced.
pub const ZEITLIN_SIMULATION_SECONDS: f64 = 900.0;
/// The exact moment is skipped (with a note) above this many seconds unless forced.
pub const ZEITLIN_EXACT_SECONDS: f64 = 120.0;
/// The default end time: one growth time `1 / lambda_max` (the bound has
/// grown by `e`), at least 1, shortened to what
/// [`ZEITLIN_SIMULATION_DEFAULT_SECONDS`] of computation reach; 10 when
/// nothing grows.
pub const ZEITLIN_SIMULATION_NO_GROWTH_T_END: f64 = 10.0;
/// A run with the default end time is kept to about this many seconds.
pub const ZEITLIN_SIMULATION_DEFAULT_SECONDS: f64 = 120.0;

/// What to simulate; `None` takes the default.
#[derive(Clone, Debug)]
pub struct ZeitlinSimulationOptions {
    /// The diagonal `m` (default: the largest `lambda_max`, the smallest `m` of equals).
    pub block: Option<usize>,
    /// Paths (default [`ZEITLIN_SIMULATION_DEFAULT_PATHS`]).
    pub paths: Option<usize>,
    /// Time step (the scheme splits exact flows: stable for any step,
    /// `O(dt^2)` accurate).
    pub dt: f64,
    /// Final time (see [`ZEITLIN_SIMULATION_NO_GROWTH_T_END`]).
    pub t_end: Option<f64>,
    /// Output times (about: every `ceil(steps / outputs)` steps).
    pub outputs: usize,
    /// Seed of the random streams.
    pub seed: u64,
    /// Run whatever the estimated cost.
    pub force: bool,
    /// The threads that work (for the estimate).
    pub threads: f64,
    /// The nonlinear ensemble's initial size `|dW_0|_P^2` (default
    /// [`ZEITLIN_NONLINEAR_DEFAULT_DELTA`]).
    pub delta: Option<f64>,
}

/// The nonlinear ensemble's initial size `|dW_0|_P^2` when none is asked for.
pub const ZEITLIN_NONLINEAR_DEFAULT_DELTA: f64 = 1e-6;
/// The nonlinear ensemble runs one path in this many of the linear one's
/// (at least 2): an isospectral midpoint step costs `O(N^3)`.
pub const ZEITLIN_NONLINEAR_PATH_SHARE: usize = 10;
/// The nonlinear ensemble is run up to this `N` (beyond, skipped with a note).
pub const ZEITLIN_NONLINEAR_MAX_N: usize = 64;

/// Why a Zeitlin simulation was not run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ZeitlinSimulationError {
    /// An option is out of range (`field`: `N`, `block`, `paths`, `dt`,
    /// `t_end`, `t_end/dt`, `outputs`, `delta`).
    #[error("{field}: {message}")]
    Invalid {
        /// The option.
        field: &'static str,
        /// What is wrong.
        message: String,
    },
    /// The Monte Carlo is estimated above [`ZEITLIN_SIMULATION_SECONDS`].
    #[error("paths/dt/t_end: {path_steps:.2e} path-steps of {unknowns} complex unknowns would take about {minutes:.0} minutes here")]
    TooLong {
        /// Paths times steps.
        path_steps: f64,
        /// Unknowns of the block.
        unknowns: usize,
        /// The estimate.
        minutes: f64,
    },
    /// The certificate gives nothing to simulate beside (not stable with a
    /// conserved form, or zonal in no frame).
    #[error("{0}")]
    NothingToCompare(String),
    /// Values beyond the doubles (a bound `exp(Sigma^2 t)` that overflows).
    #[error("{0}")]
    Unrepresentable(String),
    /// The run was stopped through its [`Progress`].
    #[error("the simulation was cancelled before it finished")]
    Cancelled,
    /// Something that should not fail did.
    #[error("internal: {0}")]
    Failed(String),
}

fn invalid(field: &'static str, message: String) -> ZeitlinSimulationError {
    ZeitlinSimulationError::Invalid { field, message }
}

fn from_block(e: IsospectralError) -> ZeitlinSimulationError {
    match e {
        IsospectralError::Cancelled => ZeitlinSimulationError::Cancelled,
        IsospectralError::Numerical(m) if m.contains("beyond the doubles") => {
            ZeitlinSimulationError::Unrepresentable(m)
        }
        other => ZeitlinSimulationError::Failed(other.to_string()),
    }
}

/// The zonal problem a certificate is about.
struct Zonal {
    omega: Vec<f64>,
    noise: Vec<Vec<f64>>,
    analysis: ZeitlinAnalysis,
    /// The axis it was rotated from (quflow's frame), if tilted.
    axis: Option<[f64; 3]>,
}

/// The zonal problem the certificate is about: `omega`, the noise
/// diagonals, the analysis, and whether it was rotated from a tilted axis.
fn zonal_problem(spec: &ZeitlinSpec, outcome: &ZeitlinOutcome) -> Result<Zonal, ZeitlinSimulationError> {
    let nothing = |why: String| ZeitlinSimulationError::NothingToCompare(why);
    match (&spec.input, outcome) {
        (ZeitlinInput::Zonal(p), ZeitlinOutcome::Zonal(Ok(a))) => {
            Ok(Zonal { omega: p.omega.clone(), noise: p.noise.clone(), analysis: a.clone(), axis: None })
        }
        (_, ZeitlinOutcome::General(g)) => match g.as_ref() {
            Ok(g) => match &g.zonal {
                Some(r) => {
                    let axis = match g.frame {
                        Some(zeitlin::general::Frame::Rotated { axis }) => Some(axis),
                        _ => None,
                    };
                    Ok(Zonal { omega: r.omega.clone(), noise: r.noise.clone(), analysis: r.analysis.clone(), axis })
                }
                None => Err(nothing(format!(
                    "the certificate is `{}`: {}; only states zonal in some frame are simulated (their blocks decouple)",
                    g.verdict.as_str(),
                    g.reason
                ))),
            },
            Err(e) => Err(nothing(format!("the analysis could not run: {e}"))),
        },
        (_, ZeitlinOutcome::Zonal(Err(e))) => Err(nothing(format!("the analysis could not run: {e}"))),
        _ => Err(ZeitlinSimulationError::Failed("the outcome does not match the spec's input".into())),
    }
}

/// Simulate one block of `spec` (see the module docs). Returns the report
/// (`kind: "zeitlin-simulation"`). `notes` receives what the user should
/// know (a shortened default run, a skipped exact moment).
///
/// ```
/// let text = r#"{"name": "z", "zeitlin": {"N": 8, "equilibrium": "z + 0.3*z^3", "noise": ["3*z^2"]},
///   "settings": {"casimir_momentum": false}}"#;
/// let spec = spec::zeitlin_spec_from_value(serde_json::from_str(text).unwrap()).unwrap();
/// let options = spec::ZeitlinSimulationOptions {
///     block: None, paths: Some(200), dt: 0.01, t_end: Some(2.0), outputs: 4, seed: 1, force: false, threads: 1.0,
///     delta: None,
/// };
/// let r = spec::simulate_zeitlin(&spec, &options, &outcome::Progress::new(), &mut |_| {}).unwrap();
/// assert_eq!(r["kind"], "zeitlin-simulation");
/// // the exact second moment stays under the certificate's proved bound
/// let exact = r["exact"].as_array().unwrap();
/// let bound = r["certified_bound"].as_array().unwrap();
/// assert!(exact.iter().zip(bound).all(|(e, b)| e.as_f64().unwrap() <= b.as_f64().unwrap() * (1.0 + 1e-6)));
/// // the nonlinear model, isospectral: its Casimirs move by rounding only
/// assert!(r["nonlinear"]["casimir_drift"].as_f64().unwrap() < 1e-12);
/// ```
pub fn simulate_zeitlin(
    spec: &ZeitlinSpec,
    options: &ZeitlinSimulationOptions,
    progress: &Progress,
    notes: &mut dyn FnMut(String),
) -> Result<Value, ZeitlinSimulationError> {
    let n = spec.input.n();
    check_options(n, options)?;
    let paths = options.paths.unwrap_or(ZEITLIN_SIMULATION_DEFAULT_PATHS);
    let outcome = analyse_zeitlin_with(spec, &Progress::new());
    let zonal = zonal_problem(spec, &outcome)?;
    let choice = match (zonal.analysis.verdict, zonal.analysis.choice) {
        (Verdict::Stable, Some(c)) => c,
        (v, _) => {
            return Err(ZeitlinSimulationError::NothingToCompare(format!(
                "the certificate is `{}`: {}; a simulation is set beside a stable certificate's conserved form",
                v.as_str(),
                zonal.analysis.reason
            )))
        }
    };
    let analysis = &zonal.analysis;
    // The blocks' lambda_max (empty under exact structure, Q = 0: every block 0).
    let lambda = |m: usize| analysis.blocks.iter().find(|b| b.m == m).map_or(0.0, |b| b.lambda_max);
    let m = match options.block {
        Some(m) if (1..n).contains(&m) => m,
        Some(m) => return Err(invalid("block", format!("need 1 <= block <= N - 1 = {}, got {m}", n - 1))),
        None => (1..n).fold(1, |best, m| if lambda(m) > lambda(best) { m } else { best }),
    };
    let sde = BlockSde::new(&zonal.omega, &zonal.noise, &choice, m).map_err(from_block)?;
    let (rate, start) = sde.top().ok_or_else(|| ZeitlinSimulationError::Failed("the block's top direction".into()))?;
    let z0: Vec<Complex<f64>> = start.iter().map(|x| Complex::new(*x, 0.0)).collect();
    let certified = analysis.sigma2_upper.or(analysis.sigma2).unwrap_or(0.0);
    let plan = plan_run(n, paths, &sde, zonal.noise.len(), certified, lambda(m), options, notes)?;
    let (dt, steps, outputs) = (options.dt, plan.steps, plan.outputs);
    progress.plan(
        paths as u64
            + if plan.run_exact { steps as u64 } else { 0 }
            + if plan.run_nonlinear { plan.nonlinear_paths as u64 } else { 0 },
    );
    let mc = sde.monte_carlo(&z0, dt, steps, outputs, paths, options.seed, progress).map_err(from_block)?;
    let exact = if plan.run_exact {
        Some(sde.exact_moment(&z0, dt, steps, outputs, progress).map_err(from_block)?)
    } else {
        None
    };
    let nonlinear = if plan.run_nonlinear {
        let start = Start { omega: &zonal.omega, noise: &zonal.noise, choice: &choice, m, z0: &z0, delta: plan.delta };
        Some(nonlinear_ensemble(&start, dt, steps, outputs, plan.nonlinear_paths, options.seed, progress)?)
    } else {
        None
    };
    let nonlinear_values =
        nonlinear.iter().flat_map(|e| e.mean.iter().chain(&e.std_error).chain([&e.casimir_drift, &e.momentum_drift]));
    if mc.mean.iter().chain(&mc.std_error).chain(exact.iter().flatten()).chain(nonlinear_values).any(|x| !x.is_finite())
    {
        return Err(ZeitlinSimulationError::Unrepresentable(
            "the run left the doubles (a value became infinite or NaN): lower dt or t_end".into(),
        ));
    }
    let run = Run { n, m, paths, rate, certified, block_lambda: lambda(m), plan };
    Ok(report(spec, options, &zonal, &sde, &run, &mc, exact, nonlinear))
}

/// The options' ranges (the grid, the paths, the time step and end).
fn check_options(n: usize, options: &ZeitlinSimulationOptions) -> Result<(), ZeitlinSimulationError> {
    if n > ZEITLIN_SIMULATION_MAX_N {
        return Err(invalid(
            "N",
            format!(
                "the simulation forms dense blocks of N - m unknowns: N at most {ZEITLIN_SIMULATION_MAX_N}, got {n}"
            ),
        ));
    }
    let paths = options.paths.unwrap_or(ZEITLIN_SIMULATION_DEFAULT_PATHS);
    check_paths_dt_outputs(paths, options.dt, options.outputs).map_err(|(field, message)| invalid(field, message))?;
    if let Some(t) = options.t_end {
        if !(t.is_finite() && t > 0.0) {
            return Err(invalid("t_end", format!("must be positive and finite, got {t}")));
        }
    }
    Ok(())
}

/// What the run will do: its steps and output times, and which of the
/// exact moment and the nonlinear ensemble it runs (from estimated costs).
struct Plan {
    steps: usize,
    outputs: usize,
    run_exact: bool,
    delta: f64,
    nonlinear_paths: usize,
    run_nonlinear: bool,
}

/// The run's length (asked, or one growth time shortened to what a default
/// run is kept to), its costs, and the refusals and notes they imply.
#[allow(clippy::too_many_arguments)]
fn plan_run(
    n: usize,
    paths: usize,
    sde: &BlockSde,
    noise_fields: usize,
    certified: f64,
    block_lambda: f64,
    options: &ZeitlinSimulationOptions,
    notes: &mut dyn FnMut(String),
) -> Result<Plan, ZeitlinSimulationError> {
    let dt = options.dt;
    let len = sde.len() as f64;
    let threads = options.threads.max(1.0);
    // Complex flops: a matrix-vector product per half step (8 len^2), the
    // noise rotations and the norm; the exact moment four products (32 len^3).
    let path_step_seconds = (16.0 * len * len + 20.0 * len * noise_fields as f64) / FLOPS_PER_SECOND;
    let exact_step_seconds = 32.0 * len * len * len / FLOPS_PER_SECOND;
    let block_rate = block_lambda.max(0.0);
    let t_end = match options.t_end {
        Some(t) => t,
        None => {
            let wanted =
                if block_rate > 0.0 { (1.0 / block_rate).max(1.0) } else { ZEITLIN_SIMULATION_NO_GROWTH_T_END };
            let per_time = (paths as f64 * path_step_seconds / threads + exact_step_seconds) / dt;
            let affordable = ZEITLIN_SIMULATION_DEFAULT_SECONDS / per_time;
            if wanted > affordable {
                notes(format!(
                    "t_end = {affordable:.4} (one growth time 1/lambda_max = {wanted:.4} would take about {:.0} s here; ask for t_end {wanted:.4} to run it)",
                    wanted * per_time
                ));
                affordable
            } else {
                wanted
            }
        }
    };
    let steps_f = (t_end / dt).round();
    if !(1.0..=MAX_STEPS).contains(&steps_f) {
        return Err(invalid("t_end/dt", format!("t_end / dt = {steps_f:e} steps: need 1 to {MAX_STEPS:e}")));
    }
    let steps = steps_f as usize;
    // exp(Sigma^2 t) must be a double over the run (at most e^700).
    if certified.max(block_lambda) * steps as f64 * dt > 700.0 {
        return Err(ZeitlinSimulationError::Unrepresentable(format!(
            "exp(Sigma^2 t_end) = exp({:e}) is beyond the doubles: lower t_end (Sigma^2 = {certified:e})",
            certified.max(block_lambda) * steps as f64 * dt
        )));
    }
    let outputs = options.outputs.min(steps);
    let mc_seconds = paths as f64 * steps as f64 * path_step_seconds / threads;
    if mc_seconds > ZEITLIN_SIMULATION_SECONDS && !options.force {
        return Err(ZeitlinSimulationError::TooLong {
            path_steps: paths as f64 * steps as f64,
            unknowns: sde.len(),
            minutes: mc_seconds / 60.0,
        });
    }
    let exact_seconds = steps as f64 * exact_step_seconds;
    let run_exact = exact_seconds <= ZEITLIN_EXACT_SECONDS || options.force;
    if !run_exact {
        notes(format!("the exact second moment is skipped: about {exact_seconds:.0} s (forcing runs it)"));
    }
    let delta = options.delta.unwrap_or(ZEITLIN_NONLINEAR_DEFAULT_DELTA);
    // Below 1e-280 the squared entries of dW leave the normal doubles and
    // E|dW_t|_P^2 / delta loses its digits (measured: 0.9988 at 1e-320
    // where 1e-300 and 1 give 0.999986).
    if !(delta.is_finite() && (1e-280..=1.0).contains(&delta)) {
        return Err(invalid("delta", format!("the nonlinear start's |dW_0|_P^2 must be in [1e-280, 1], got {delta}")));
    }
    let nonlinear_paths = (paths / ZEITLIN_NONLINEAR_PATH_SHARE).max(2);
    // An isospectral midpoint step: about 7 iterations of two complex
    // products and a stream solve (about 32 N^3 flops each), plus the norm
    // over the blocks.
    let nonlinear_seconds =
        nonlinear_paths as f64 * steps as f64 * 250.0 * (n as f64).powi(3) / FLOPS_PER_SECOND / threads;
    let run_nonlinear =
        n <= ZEITLIN_NONLINEAR_MAX_N && (nonlinear_seconds <= ZEITLIN_SIMULATION_SECONDS || options.force);
    if !run_nonlinear {
        notes(if n > ZEITLIN_NONLINEAR_MAX_N {
            format!("the nonlinear ensemble is skipped: N = {n} is above {ZEITLIN_NONLINEAR_MAX_N}")
        } else {
            format!("the nonlinear ensemble is skipped: about {nonlinear_seconds:.0} s (forcing runs it)")
        });
    }
    Ok(Plan { steps, outputs, run_exact, delta, nonlinear_paths, run_nonlinear })
}

/// The numbers of a run the report states.
struct Run {
    n: usize,
    m: usize,
    paths: usize,
    rate: f64,
    certified: f64,
    block_lambda: f64,
    plan: Plan,
}

/// The report (`kind: "zeitlin-simulation"`): the series beside the
/// certified and the block's bounds, and what they show.
#[allow(clippy::too_many_arguments)]
fn report(
    spec: &ZeitlinSpec,
    options: &ZeitlinSimulationOptions,
    zonal: &Zonal,
    sde: &BlockSde,
    run: &Run,
    mc: &zeitlin::block_sde::BlockMonteCarlo,
    exact: Option<Vec<f64>>,
    nonlinear: Option<Nonlinear>,
) -> Value {
    let Run { n, m, paths, rate, certified, block_lambda, ref plan } = *run;
    let (dt, steps, delta) = (options.dt, plan.steps, plan.delta);
    let analysis = &zonal.analysis;
    let h = sde.hbar();
    let certified_bound: Vec<f64> = mc.times.iter().map(|t| (certified * t).exp()).collect();
    let block_bound: Vec<f64> = mc.times.iter().map(|t| (block_lambda * t).exp()).collect();
    let exact_over_bound =
        exact.as_ref().map(|e| e.iter().zip(&certified_bound).map(|(e, b)| e / b).fold(f64::NEG_INFINITY, f64::max));
    let agreeing = exact.as_ref().map(|e| {
        e.iter()
            .zip(mc.mean.iter().zip(&mc.std_error))
            .filter(|(e, (m, s))| (*m - *e).abs() <= 4.0 * *s + 1e-3 * e.abs())
            .count()
    });
    let times_qtime: Vec<f64> = mc.times.iter().map(|t| t / h).collect();
    json!({
        "kind": "zeitlin-simulation",
        "format": 1,
        "engine": crate::ENGINE_VERSION,
        "name": spec.name,
        "spec_digest": crate::spec_digest(&spec.raw),
        "N": n,
        "hbar": h,
        "axis": zonal.axis,
        "block": m,
        "unknowns": sde.len(),
        "verdict": "stable",
        "sigma2": analysis.sigma2,
        "sigma2_upper": analysis.sigma2_upper,
        "block_lambda_max": block_lambda,
        "initial_rate": rate,
        "paths": paths,
        "seed": options.seed,
        "dt": dt,
        "steps": steps,
        "t_end": steps as f64 * dt,
        "time_unit": "t (the model's time, quflow's t); times_qtime = t / hbar, quflow's integrator time",
        "times": mc.times,
        "times_qtime": times_qtime,
        "monte_carlo_mean": mc.mean,
        "monte_carlo_std_error": mc.std_error,
        "exact": exact,
        "certified_bound": certified_bound,
        "block_bound": block_bound,
        "nonlinear": nonlinear.as_ref().map(|e| json!({
            "paths": e.paths,
            "delta": delta,
            "mean": e.mean,
            "std_error": e.std_error,
            "casimir_drift": e.casimir_drift,
            "momentum_drift": e.momentum_drift,
            "iterations_max": e.iterations_max,
            "meaning": "the nonlinear stochastic Zeitlin model (the isospectral midpoint scheme) from W_e + sqrt(delta) X, X the block's fastest start (|X|_P^2 = 1), on the same Brownian increments as the linear paths of the same index: E|W_t - W_e|_P^2 / delta over the off-diagonal blocks (the diagonal block, which the linearisation leaves constant, is not measured); casimir_drift the largest relative change of tr W^2 and tr W^3 over every path and step",
        })),
        "summary": {
            "exact_over_certified_bound_max": exact_over_bound,
            "monte_carlo_agrees_with_exact": agreeing,
            "monte_carlo_agreement": "|mean - exact| <= 4 standard errors + 1e-3 exact",
            "records": mc.times.len(),
        },
        "meaning": "E|z_t|_P^2 / |z_0|_P^2 for the perturbation's entries z_j = dW[j, j + m] on diagonal `block` of the linearised SDE about the zonal state (the blocks decouple), from the direction whose E|z|_P^2 grows fastest (initial_rate = lambda_max(Q_m, P_m)); P the certificate's energy–Casimir form; certified_bound = exp(sigma2_upper t), the certificate's proved bound (exp(sigma2 t) when none was proved), block_bound = exp(block_lambda_max t); the Monte Carlo and `exact` are of the Strang splitting of the exact drift and noise flows, the exact second moment of that scheme (O(dt^2) from the SDE's)",
    })
}

/// The nonlinear ensemble's statistics.
struct Nonlinear {
    paths: usize,
    mean: Vec<f64>,
    std_error: Vec<f64>,
    casimir_drift: f64,
    momentum_drift: f64,
    iterations_max: usize,
}

/// Where the nonlinear ensemble starts: `W_e = i diag(omega)` with its
/// noise and form, pushed by `sqrt(delta) X`, `X` on diagonal `m` with
/// entries `z0` (`|X|_P^2 = 1`).
struct Start<'a> {
    omega: &'a [f64],
    noise: &'a [Vec<f64>],
    choice: &'a zeitlin::analysis::Choice,
    m: usize,
    z0: &'a [Complex<f64>],
    delta: f64,
}

/// The nonlinear stochastic Zeitlin model from `start`, path `p` drawing
/// from the same stream as the linear ensemble's path `p` (the same
/// increments, in the same order: one normal per noise field per step):
/// `E|W_t - W_e|_P^2 / delta` summed over the off-diagonal blocks with each
/// block's form.
fn nonlinear_ensemble(
    start: &Start<'_>,
    dt: f64,
    steps: usize,
    outputs: usize,
    paths: usize,
    seed: u64,
    progress: &Progress,
) -> Result<Nonlinear, ZeitlinSimulationError> {
    use rayon::prelude::*;
    use zeitlin::isospectral::{diagonal_perturbation, path_rng, zonal_state, MidpointSettings, ZeitlinModel};
    let Start { omega, noise, choice, m, z0, delta } = *start;
    let n = omega.len();
    let blocks: Vec<BlockSde> =
        (1..n).map(|b| BlockSde::new(omega, noise, choice, b)).collect::<Result<_, _>>().map_err(from_block)?;
    let model = ZeitlinModel::new(n, noise.to_vec()).map_err(from_block)?;
    let we = zonal_state(omega);
    let scaled: Vec<Complex<f64>> = z0.iter().map(|z| z * delta.sqrt()).collect();
    let w0 = &we + diagonal_perturbation(n, m, &scaled).map_err(from_block)?;
    let every = steps.div_ceil(outputs.max(1)).max(1);
    let norm = |w: &nalgebra::DMatrix<Complex<f64>>| -> f64 {
        blocks
            .iter()
            .map(|b| {
                let z: Vec<Complex<f64>> = (0..n - b.m()).map(|j| w[(j, j + b.m())] - we[(j, j + b.m())]).collect();
                b.norm2(&z)
            })
            .sum::<f64>()
            / delta
    };
    let settings = MidpointSettings::default();
    type Run = (Vec<f64>, f64, f64, usize);
    let runs: Vec<Result<Run, IsospectralError>> = (0..paths)
        .into_par_iter()
        .map(|p| {
            if progress.is_cancelled() {
                return Err(IsospectralError::Cancelled);
            }
            let mut rng = path_rng(seed, p as u64);
            let mut series = Vec::with_capacity(outputs + 2);
            let summary = model.run(&w0, dt, steps, &mut rng, &settings, |s, _, w| {
                if s % every == 0 || s == steps {
                    series.push(norm(w));
                }
            })?;
            progress.step(1);
            Ok((series, summary.casimir_drift, summary.momentum_drift, summary.iterations_max))
        })
        .collect();
    let mut sum: Vec<f64> = vec![];
    let mut square: Vec<f64> = vec![];
    let (mut casimir, mut momentum, mut iterations) = (0.0f64, 0.0f64, 0usize);
    for run in runs {
        let (series, c, mo, it) = run.map_err(from_block)?;
        if sum.is_empty() {
            sum = vec![0.0; series.len()];
            square = vec![0.0; series.len()];
        }
        for (k, x) in series.iter().enumerate() {
            sum[k] += x;
            square[k] += x * x;
        }
        // (a NaN drift stays NaN: f64::max would drop it)
        casimir = if c.is_nan() || casimir.is_nan() { f64::NAN } else { casimir.max(c) };
        momentum = if mo.is_nan() || momentum.is_nan() { f64::NAN } else { momentum.max(mo) };
        iterations = iterations.max(it);
    }
    let count = paths as f64;
    let mean: Vec<f64> = sum.iter().map(|s| s / count).collect();
    let std_error = mean
        .iter()
        .zip(&square)
        .map(|(m, q)| ((q / count - m * m).max(0.0) * count / (count - 1.0).max(1.0) / count).sqrt())
        .collect();
    Ok(Nonlinear {
        paths,
        mean,
        std_error,
        casimir_drift: casimir,
        momentum_drift: momentum,
        iterations_max: iterations,
    })
}
