//! One x-mode of a fluid spec simulated beside its certified growth: what
//! `verify simulate FLUID-SPEC` and the Python package's `simulate_fluid`
//! run (docs/simulation.md, "Fluid specs").
//!
//! The fluid analysis is run again on the simulation's grid, so that the
//! certified `Sigma_k^2` it is set beside is that of the simulated discrete
//! SDE's grid. The mode starts from the direction whose `E V` grows fastest
//! at `t = 0` ([`fluid::analysis::ModeStudy`]); a Monte Carlo and the exact
//! second moment give `E V(t) / V(0)`.

use crate::run_options::{check_paths_dt_outputs, MAX_STEPS};
use crate::FluidSpec;
use fluid::analysis::{analyse_with, mode_study, FluidError, FluidModel, FluidProblem, ModeResult, Progress, Verdict};
use serde_json::{json, Value};

/// The grid the simulation runs on when none is asked for (at most the
/// spec's): incompressible, compressible. The SDE is dense, and its exact
/// second moment costs `O(n^3)` per step; the compressible model has three
/// unknowns per node and a stiffer moment equation (its acoustic
/// frequencies), hence the coarser default.
pub const FLUID_SIMULATION_DEFAULT_NY: (usize, usize) = (32, 16);
/// The finest grid a simulation may ask for (dense matrices of `3 ny` unknowns).
pub const FLUID_SIMULATION_MAX_NY: usize = 512;
/// Paths when none are asked for.
pub const FLUID_SIMULATION_DEFAULT_PATHS: usize = 1000;
/// Floating-point operations per second and thread assumed for the exact
/// moment when one of its Taylor steps is too long to time
/// ([`EXACT_PILOT_SECONDS`]). Measured on the 2-core machine:
/// the incompressible exact moment ran at about 1.7 times the speed this
/// assumes at ny = 128 and 256, the compressible one faster still (its
/// Taylor steps stop before the 40 terms counted).
const FLOPS_PER_SECOND: f64 = 6e9;
/// Floating-point operations (as [`fluid::analysis::ModeStudy::flops_per_path_step`]
/// counts them) of the pilot that times the ensemble: about 0.1 to 0.5 s,
/// long enough that the scheduler's time slices and the pool's start do
/// not decide it (a pilot of 400 path-steps, 2 ms, said 4 times the
/// time). A tenth of the run's path-steps at most, so a short run is not
/// dominated by it.
const PILOT_FLOPS: f64 = 1e9;
/// One Taylor step of the exact moment is timed when its flop count says
/// it takes at most this many seconds; a longer one is estimated by
/// [`FLOPS_PER_SECOND`].
const EXACT_PILOT_SECONDS: f64 = 0.5;
/// The default end time in growth times `1/Sigma_k^2`: at
/// `t = 1/Sigma_k^2` the certified bound `exp(Sigma_k^2 t)` has grown by
/// `e = 2.72`, a factor the chart shows plainly, and the exact moment,
/// which starts along the fastest-growing direction, has grown by up to as
/// much. A fixed end (10 once) shows a flat chart when `1/Sigma_k^2` is
/// hundreds (784 for a jet with weak noise: `exp(10/784) = 1.013`).
pub const FLUID_SIMULATION_GROWTH_TIMES: f64 = 1.0;
/// The default end time is at least this (a fast-growing mode still runs
/// long enough to see its drift).
pub const FLUID_SIMULATION_MIN_T_END: f64 = 1.0;
/// The default end time when the certified `Sigma_k^2` is 0 (nothing grows,
/// no time scale to take).
pub const FLUID_SIMULATION_NO_GROWTH_T_END: f64 = 10.0;
/// A run with the default end time is kept to about this many seconds of
/// computation (estimated by the pilot): one growth time is shortened to
/// what fits, with a note; a longer run is asked for with `t_end`. Two
/// minutes, the limit beyond which the exact moment is skipped too.
pub const FLUID_SIMULATION_DEFAULT_SECONDS: f64 = 120.0;
/// The exact second moment is skipped (with a note) above this estimate
/// unless forced.
pub const FLUID_EXACT_SECONDS: f64 = 120.0;
/// A Monte Carlo estimated above this is refused unless forced.
pub const FLUID_SIMULATION_SECONDS: f64 = 900.0;

/// What to simulate; `None` takes the default.
#[derive(Clone, Debug)]
pub struct FluidSimulationOptions {
    /// The x-mode (default: the largest certified growth, the gravest of
    /// equals; the gravest for the compressible model).
    pub mode: Option<usize>,
    /// The simulation's grid (default [`FLUID_SIMULATION_DEFAULT_NY`], at
    /// most the spec's).
    pub ny: Option<usize>,
    /// Paths (default [`FLUID_SIMULATION_DEFAULT_PATHS`]).
    pub paths: Option<usize>,
    /// Time step.
    pub dt: f64,
    /// Final time (default: one growth time `1 / Sigma_k^2`
    /// ([`FLUID_SIMULATION_GROWTH_TIMES`]), at least
    /// [`FLUID_SIMULATION_MIN_T_END`], shortened to what
    /// [`FLUID_SIMULATION_DEFAULT_SECONDS`] of computation reach;
    /// [`FLUID_SIMULATION_NO_GROWTH_T_END`] when `Sigma_k^2 = 0`).
    pub t_end: Option<f64>,
    /// Output times (about; every `record_every` steps).
    pub outputs: usize,
    /// Seed of the random streams.
    pub seed: u64,
    /// Run whatever the estimated cost.
    pub force: bool,
    /// The threads that work (named in the estimate's note; the estimate
    /// itself is timed on the thread pool).
    pub threads: f64,
}

/// Why a simulation was not run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FluidSimulationError {
    /// An option is out of range (`field`: `mode`, `ny`, `paths`, `dt`,
    /// `t_end`, `t_end/dt`, `outputs`).
    #[error("{field}: {message}")]
    Invalid {
        /// The option.
        field: &'static str,
        /// What is wrong.
        message: String,
    },
    /// The Monte Carlo is estimated above [`FLUID_SIMULATION_SECONDS`].
    #[error(
        "paths/dt/t_end: {path_steps:.2e} path-steps of {unknowns} unknowns would take about {minutes:.0} minutes here"
    )]
    TooLong {
        /// Paths times steps.
        path_steps: f64,
        /// Unknowns of the SDE.
        unknowns: usize,
        /// The estimate.
        minutes: f64,
    },
    /// The analysis on the simulation's grid certifies no growth.
    #[error("the analysis at ny = {ny} is `{verdict}`: {reason}; there is no certified growth to simulate beside")]
    NoGrowth {
        /// The grid.
        ny: usize,
        /// Its verdict.
        verdict: &'static str,
        /// Its reason.
        reason: String,
    },
    /// The dense SDE cannot be formed in doubles (noise amplitudes near
    /// `1e150` and above make its generator form overflow).
    #[error("{0}")]
    Unrepresentable(String),
    /// The run was stopped through its [`Progress`] before it ended.
    #[error("the simulation was cancelled before it finished")]
    Cancelled,
    /// Something that should not fail did.
    #[error("internal: {0}")]
    Failed(String),
}

impl From<fluid::analysis::Cancelled> for FluidSimulationError {
    fn from(_: fluid::analysis::Cancelled) -> Self {
        FluidSimulationError::Cancelled
    }
}

/// `work` with a fresh [`Progress`] that is cancelled when `outer` is (a
/// scoped thread looks every 10 ms until `work` returns). The analysis on
/// the simulation's grid counts its own steps in it, so that `outer` has one
/// plan, in one unit, and its fraction done only grows. Without a thread,
/// `work` runs all the same, only not cancellable.
fn with_cancel_of<R>(outer: &Progress, work: impl FnOnce(&Progress) -> R) -> R {
    use std::sync::atomic::{AtomicBool, Ordering};
    let inner = Progress::new();
    let finished = AtomicBool::new(false);
    std::thread::scope(|scope| {
        let _watcher = std::thread::Builder::new().spawn_scoped(scope, || {
            while !finished.load(Ordering::Acquire) {
                if outer.is_cancelled() {
                    inner.cancel();
                    return;
                }
                std::thread::sleep(std::time::Duration::from_millis(10));
            }
        });
        let out = work(&inner);
        finished.store(true, Ordering::Release);
        out
    })
}

fn invalid(field: &'static str, message: String) -> FluidSimulationError {
    FluidSimulationError::Invalid { field, message }
}

/// A finished simulation: the report (`kind: "fluid-simulation"`; every
/// series by name) and what a caller draws or prints from it.
#[derive(Clone, Debug)]
pub struct FluidSimulation {
    /// The report.
    pub report: Value,
    /// Whether the model is compressible.
    pub compressible: bool,
    /// The x-mode.
    pub m: usize,
    /// The grid.
    pub ny: usize,
    /// The certified `Sigma_k^2` on that grid (the verified upper bound, else the estimate).
    pub certified: f64,
    /// The initial rate from the start.
    pub rate: f64,
    /// Output times.
    pub times: Vec<f64>,
    /// Monte Carlo mean of `E V(t) / V(0)`.
    pub mean: Vec<f64>,
    /// Its standard error.
    pub std_error: Vec<f64>,
    /// The exact `E V(t) / V(0)`, if run.
    pub exact: Option<Vec<f64>>,
    /// `exp(Sigma_k^2 t)`.
    pub bound: Vec<f64>,
    /// `exp(rate t)`.
    pub rate_curve: Vec<f64>,
    /// The paper's `sup_y sum eta'^2`, if finite.
    pub paper: Option<f64>,
    /// The wavenumber.
    pub k: f64,
    /// Unknowns of the SDE.
    pub unknowns: usize,
    /// Whether `certified` is a verified upper bound.
    pub verified: bool,
    /// Paths, steps, the step and the final time run.
    pub paths: usize,
    /// Steps per path.
    pub steps: usize,
    /// The time step.
    pub dt: f64,
    /// The final time (a whole number of steps).
    pub t_end: f64,
    /// The largest `exact / exp(Sigma_k^2 t)`, if the exact moment ran.
    pub exact_over_bound: Option<f64>,
    /// At how many output times the Monte Carlo is within 4 standard errors
    /// plus `1e-3` of the value (the splitting's bias) of the exact moment.
    pub agreeing: Option<usize>,
    /// The first output time at which the exact moment exceeds the paper's bound.
    pub paper_exceeded_at: Option<f64>,
    /// The run's estimated wall-clock seconds (the Monte Carlo and the
    /// exact moment, not the analysis), from a pilot of its own stepping.
    pub estimated_seconds: f64,
    /// The wall-clock seconds the Monte Carlo and the exact moment took.
    pub run_seconds: f64,
}

/// Notes for the user, in order, as the run is planned (the estimate, a
/// skipped exact moment) and after it (values beyond the doubles).
pub type Notes<'a> = &'a mut dyn FnMut(String);

/// Simulate one x-mode of `spec` (see the module docs).
///
/// ```
/// let text = r#"{"name": "t", "fluid": {"model": "incompressible", "x_period": "2*pi",
///   "y_interval": [0, "pi"], "boundary": "walls", "shear_flow": "sin(y)",
///   "noise": ["0.3*cos(y)"], "ny": 32, "x_modes": 2}}"#;
/// let spec = spec::parse_fluid_spec(text).unwrap();
/// let options = spec::FluidSimulationOptions {
///     mode: None, ny: Some(16), paths: Some(200), dt: 0.01, t_end: Some(1.0),
///     outputs: 4, seed: 1, force: false, threads: 1.0,
/// };
/// let run = spec::simulate_fluid(&spec, &options, &mut |_| {}).unwrap();
/// let exact = run.exact.unwrap();
/// // the exact second moment stays under the certified exp(Sigma_k^2 t)
/// assert!(exact.iter().zip(&run.bound).all(|(e, b)| *e <= b * (1.0 + 1e-9)));
/// assert_eq!(run.report["kind"], "fluid-simulation");
/// ```
pub fn simulate_fluid(
    spec: &FluidSpec,
    options: &FluidSimulationOptions,
    notes: Notes<'_>,
) -> Result<FluidSimulation, FluidSimulationError> {
    simulate_fluid_with(spec, options, &Progress::new(), notes)
}

/// [`simulate_fluid`], its steps counted in `progress` and stopped with
/// [`FluidSimulationError::Cancelled`] soon after [`Progress::cancel`]
/// (between the analysis's modes, every 1e7 flops or so of each path,
/// between two terms of a Taylor step of the exact moment). The count is
/// planned once, when the Monte Carlo and the exact moment start, in units
/// of about a thousand flops
/// ([`fluid::analysis::ModeStudy::ensemble_units`]); until then (the
/// analysis on the simulation's grid and the dense start) it is `(0, 0)`.
///
/// ```
/// # let text = r#"{"name": "t", "fluid": {"model": "incompressible", "x_period": "2*pi",
/// #   "y_interval": [0, "pi"], "boundary": "walls", "shear_flow": "sin(y)",
/// #   "noise": ["0.3*cos(y)"], "ny": 32, "x_modes": 2}}"#;
/// # let spec = spec::parse_fluid_spec(text).unwrap();
/// # let options = spec::FluidSimulationOptions {
/// #     mode: None, ny: Some(16), paths: Some(200), dt: 0.01, t_end: Some(1.0),
/// #     outputs: 4, seed: 1, force: false, threads: 1.0,
/// # };
/// use fluid::analysis::Progress;
/// let progress = Progress::new();
/// let run = spec::simulate_fluid_with(&spec, &options, &progress, &mut |_| {}).unwrap();
/// let (done, total) = progress.snapshot();
/// assert!(total > 0 && done == total);
/// // the same numbers as without a progress
/// assert_eq!(run.mean, spec::simulate_fluid(&spec, &options, &mut |_| {}).unwrap().mean);
/// progress.cancel();
/// let stopped = spec::simulate_fluid_with(&spec, &options, &progress, &mut |_| {});
/// assert_eq!(stopped.unwrap_err(), spec::FluidSimulationError::Cancelled);
/// ```
pub fn simulate_fluid_with(
    spec: &FluidSpec,
    options: &FluidSimulationOptions,
    progress: &Progress,
    notes: Notes<'_>,
) -> Result<FluidSimulation, FluidSimulationError> {
    let shape = RunShape::of(spec, options)?;
    let (problem, analysis) = stable_analysis(spec, shape.ny, progress)?;
    let m = chosen_mode(options, &analysis, shape.compressible, problem.x_modes)?;
    let row = analysis
        .modes
        .iter()
        .find(|r| r.m == m)
        .ok_or_else(|| FluidSimulationError::Failed(format!("mode {m} missing from the analysis")))?;
    let (certified, verified) = (growth(row), row.sigma2_upper.is_some());
    let ny = shape.ny;
    let study = mode_study(&problem, analysis.form.galilean_shift, m).ok_or_else(|| {
        FluidSimulationError::Unrepresentable(format!(
            "the dense SDE of x-mode {m} at ny = {ny} could not be formed in doubles (its generator form overflows, or its form is not definite in floating point: noise amplitudes near 1e150 and above do this; the certificate runs on normalised noise, the simulation cannot): nothing to simulate"
        ))
    })?;
    let plan = plan_run(&study, &shape, options, certified, progress, notes)?;
    progress.check()?;
    let series = run_series(&study, &plan, &shape, options.seed, progress)?;
    Ok(summarise(
        spec,
        &problem,
        &analysis,
        &study,
        &shape,
        &plan,
        options.seed,
        Certified { m, certified, verified },
        series,
        notes,
    ))
}

/// The certified growth of a mode: its proved bound, else its estimate.
fn growth(r: &ModeResult) -> f64 {
    r.sigma2_upper.unwrap_or(r.sigma2)
}

/// The run's grid, paths and time step, checked.
struct RunShape {
    compressible: bool,
    ny: usize,
    paths: usize,
    dt: f64,
}

impl RunShape {
    fn of(spec: &FluidSpec, options: &FluidSimulationOptions) -> Result<Self, FluidSimulationError> {
        let compressible = matches!(spec.problem.model, FluidModel::Compressible { .. });
        let default_ny = if compressible { FLUID_SIMULATION_DEFAULT_NY.1 } else { FLUID_SIMULATION_DEFAULT_NY.0 };
        let ny = options.ny.unwrap_or(spec.problem.ny.min(default_ny));
        let (low, high) = (crate::NY_RANGE.0, FLUID_SIMULATION_MAX_NY);
        if !(low..=high).contains(&ny) {
            return Err(invalid(
                "ny",
                format!("the simulation's grid must have {low} to {high} points (dense SDE), got {ny}"),
            ));
        }
        let paths = options.paths.unwrap_or(FLUID_SIMULATION_DEFAULT_PATHS);
        let dt = options.dt;
        check_paths_dt_outputs(paths, dt, options.outputs).map_err(|(field, message)| invalid(field, message))?;
        // the analysis at this grid has the spec's work limits (they depend
        // on ny: a spec accepted at ny = 16 may not be at 512)
        let fields = spec.problem.profile.eta.len();
        crate::fluid::work_limits(spec.problem.profile.boundary, ny, spec.problem.x_modes, fields)
            .map_err(|(_, message)| invalid("ny", format!("at ny = {ny}: {message}")))?;
        Ok(RunShape { compressible, ny, paths, dt })
    }
}

/// The spec's problem at the simulation's grid and its analysis there,
/// which must be stable with a certified mode (else nothing is simulated).
fn stable_analysis(
    spec: &FluidSpec,
    ny: usize,
    progress: &Progress,
) -> Result<(FluidProblem, fluid::analysis::FluidAnalysis), FluidSimulationError> {
    let problem = FluidProblem { ny, ..spec.problem.clone() };
    let analysis =
        with_cancel_of(progress, |inner| analyse_with(&problem, &spec.settings, inner)).map_err(|e| match e {
            FluidError::Cancelled(_) => FluidSimulationError::Cancelled,
            e => FluidSimulationError::Failed(e.to_string()),
        })?;
    if analysis.verdict != Verdict::Stable || analysis.modes.is_empty() {
        return Err(FluidSimulationError::NoGrowth {
            ny,
            verdict: analysis.verdict.as_str(),
            reason: analysis.reason.clone(),
        });
    }
    Ok((problem, analysis))
}

/// The x-mode to simulate: the one asked for, else (compressible) the
/// gravest, else the largest certified growth.
fn chosen_mode(
    options: &FluidSimulationOptions,
    analysis: &fluid::analysis::FluidAnalysis,
    compressible: bool,
    x_modes: usize,
) -> Result<usize, FluidSimulationError> {
    Ok(match options.mode {
        Some(m) if (1..=x_modes).contains(&m) => m,
        Some(m) => return Err(invalid("mode", format!("the spec has x-modes 1 to {x_modes}, got {m}"))),
        // Compressible: the gravest mode. The pointwise noise of the
        // discrete SDE differs from the certified continuum generator form
        // by the Casimir defect, which grows with k (docs/fluids.md §1b): on
        // a coarse grid the short waves of the discrete SDE outgrow the
        // certified Sigma_k^2 (at ny = 16, mode 32 of the compatible-noise
        // fixture: lambda_B = 650 against 0.087).
        None if compressible => 1,
        // Incompressible: the largest certified growth, the gravest of
        // equals (`max_by` would give the last).
        None => {
            let mut best = &analysis.modes[0];
            for r in &analysis.modes[1..] {
                if growth(r) > growth(best) {
                    best = r;
                }
            }
            best.m
        }
    })
}

/// What the run will do: its output times, whether the exact moment runs,
/// and the costs estimated for it.
struct RunPlan {
    grid: TimeGrid,
    run_exact: bool,
    cost: Estimate,
    estimated_seconds: f64,
}

/// The run's times and costs: `t_end` (asked, or one growth time shortened
/// to what a default run is kept to), the measured costs of the ensemble
/// and the exact moment, and the refusals and notes they imply.
fn plan_run(
    study: &fluid::analysis::ModeStudy,
    shape: &RunShape,
    options: &FluidSimulationOptions,
    certified: f64,
    progress: &Progress,
    notes: Notes<'_>,
) -> Result<RunPlan, FluidSimulationError> {
    let (dt, paths, ny) = (shape.dt, shape.paths, shape.ny);
    // Times: `steps` of `dt`, recorded every `record_every`. Default: one
    // growth time 1/Sigma_k^2 (see FLUID_SIMULATION_GROWTH_TIMES), at
    // least 1, shortened to what FLUID_SIMULATION_DEFAULT_SECONDS of
    // computation reach; 10 when nothing grows.
    // (at most MAX_STEPS steps: a Sigma_k^2 of 1e-12 would ask for 1e14)
    let longest = MAX_STEPS * dt * (1.0 - 1e-9);
    let t_end = options.t_end.unwrap_or_else(|| default_t_end(certified, longest, |_| 0.0).0);
    if options.t_end.is_none() && dt > t_end {
        return Err(invalid("dt", format!("{dt:e} is longer than the default t_end = {t_end:e}")));
    }
    if !(t_end.is_finite() && t_end >= dt) {
        return Err(invalid("t_end", format!("must be finite and at least dt = {dt:e}, got {t_end:e}")));
    }
    // exp(Sigma_k^2 t) must be a double over the run (noise near 1e100
    // makes Sigma_k^2 near 1e200).
    if certified * t_end > 700.0 {
        return Err(invalid(
            "t_end",
            format!(
                "the certified exp(Sigma_k^2 t) with Sigma_k^2 = {certified:e} leaves the range of doubles before t = {t_end:e}; ask for t_end (and dt) below {:e}",
                700.0 / certified
            ),
        ));
    }
    let mut grid = time_grid(t_end, dt, options.outputs)?;
    let costs = measure_costs(study, &grid, dt, paths, options.seed, progress)?;
    let estimate = |grid: &TimeGrid| costs.estimate(study, paths, grid);
    if options.t_end.is_none() {
        // (an exact moment of too many Taylor steps is not run: not counted)
        let seconds = |t: f64| {
            time_grid(t, dt, options.outputs).map_or(f64::INFINITY, |g| {
                let e = estimate(&g);
                e.wall(e.exact.is_finite())
            })
        };
        if let (shortened, Some(growth)) = default_t_end(certified, longest, seconds) {
            grid = time_grid(shortened, dt, options.outputs)?;
            notes(format!(
                "t_end = {}: one growth time 1/Sigma_k^2 = {} would take about {:.0} s, more than the {:.0} s a default run is kept to (ask for t_end {} to run it)",
                short(grid.t_end),
                short(growth),
                seconds(growth),
                FLUID_SIMULATION_DEFAULT_SECONDS,
                short(growth)
            ));
        }
    }
    let cost = estimate(&grid);
    // (said only of an end asked for: a default one is a time scale, not a time)
    if options.t_end.is_some() && (grid.t_end - grid.asked).abs() > 1e-9 * grid.asked {
        notes(format!(
            "the run ends at t = {} ({} output times of {} steps of {}), not at t_end = {}",
            short(grid.t_end),
            grid.records,
            grid.record_every,
            short(dt),
            short(grid.asked)
        ));
    }
    if cost.monte_carlo > FLUID_SIMULATION_SECONDS && !options.force {
        return Err(FluidSimulationError::TooLong {
            path_steps: cost.path_steps,
            unknowns: study.unknowns(),
            minutes: cost.monte_carlo / 60.0,
        });
    }
    let run_exact = cost.exact.is_finite() && (cost.exact <= FLUID_EXACT_SECONDS || options.force);
    if !cost.exact.is_finite() {
        notes(format!(
            "the exact second moment would need more than {} Taylor steps per output time (the noise's amplitude): not run",
            fluid::simulate::MAX_TAYLOR_STEPS
        ));
    } else if !run_exact {
        notes(format!(
            "the exact second moment would take about {:.0} minutes at ny = {ny}: skipped (forcing runs it; a smaller ny is faster)",
            cost.exact / 60.0
        ));
    }
    let estimated_seconds = cost.wall(run_exact);
    if estimated_seconds > 10.0 {
        notes(format!(
            "about {estimated_seconds:.0} s of computation ({:.2e} path-steps on {} threads{})",
            cost.path_steps,
            options.threads,
            if costs.exact_rate.is_some() { "; timed by a pilot run" } else { "; the exact moment by its flop count" }
        ));
    }
    Ok(RunPlan { grid, run_exact, cost, estimated_seconds })
}

/// The costs measured on this machine: the ensemble's by a pilot of its
/// own stepping, the exact moment's by one timed Taylor step (seconds per
/// flop), when that step is short.
struct Costs {
    timing: fluid::analysis::EnsembleTiming,
    exact_rate: Option<f64>,
}

impl Costs {
    /// The estimate for a run of `paths` on `grid`.
    fn estimate(&self, study: &fluid::analysis::ModeStudy, paths: usize, grid: &TimeGrid) -> Estimate {
        let path_steps = paths as f64 * grid.steps as f64;
        let monte_carlo = self.timing.setup_seconds + self.timing.path_step_seconds * path_steps;
        let (flops, units) = study.exact_growth_cost(grid.t_end, grid.records);
        let exact = flops * self.exact_rate.unwrap_or(1.0 / FLOPS_PER_SECOND);
        Estimate { path_steps, monte_carlo, exact, exact_units: units }
    }
}

/// Costs, measured here: a pilot of the ensemble's own stepping (on the
/// thread pool, under the machine's present load) and one Taylor step of
/// the exact moment time them; a constant rate per flop cannot know the
/// machine, its load or the cost of the noise's phases.
fn measure_costs(
    study: &fluid::analysis::ModeStudy,
    grid: &TimeGrid,
    dt: f64,
    paths: usize,
    seed: u64,
    progress: &Progress,
) -> Result<Costs, FluidSimulationError> {
    progress.check()?;
    // The pilot: PILOT_FLOPS worth of path-steps, at most a tenth of the
    // run's, as paths of the run's length or fewer steps (at least twice
    // the pool's threads in paths, so that none idles).
    let pool = rayon::current_num_threads().max(1);
    let run_path_steps = paths as f64 * grid.steps as f64;
    let pilot_path_steps = (PILOT_FLOPS / study.flops_per_path_step()).min(run_path_steps / 10.0).max(1.0);
    let pilot_steps = ((pilot_path_steps / (2 * pool) as f64) as usize).clamp(1, grid.steps);
    let pilot_paths = ((pilot_path_steps / pilot_steps as f64).ceil() as usize).clamp(1, paths);
    let timing = study
        .time_ensemble(dt, pilot_steps, pilot_paths, seed)
        .ok_or_else(|| FluidSimulationError::Failed("the drift's propagator could not be formed".into()))?;
    progress.check()?;
    let step_flops = study.exact_step_flops();
    // One Taylor step is timed when the flop count says it is short (at
    // ny = 256 in the compressible model it takes about a minute); the
    // seconds per flop it gives scale the whole exact moment's count.
    let exact_rate = if step_flops / FLOPS_PER_SECOND <= EXACT_PILOT_SECONDS {
        study.time_exact_step(grid.t_end, grid.records).map(|s| s / step_flops)
    } else {
        None
    };
    Ok(Costs { timing, exact_rate })
}

/// The series a run produced.
struct Series {
    times: Vec<f64>,
    mean: Vec<f64>,
    std_error: Vec<f64>,
    exact: Option<Vec<f64>>,
    run_seconds: f64,
}

/// The ensemble and (beside it, on its own thread) the exact second
/// moment, with progress counted over both.
fn run_series(
    study: &fluid::analysis::ModeStudy,
    plan: &RunPlan,
    shape: &RunShape,
    seed: u64,
    progress: &Progress,
) -> Result<Series, FluidSimulationError> {
    let TimeGrid { steps, record_every, records, t_end, .. } = plan.grid;
    let (dt, paths) = (shape.dt, shape.paths);
    // (capped: a forced run of 1e7 paths of 1e8 steps would pass u64, and
    // the count only needs its proportions)
    let planned =
        study.ensemble_units(steps, paths).saturating_add(if plan.run_exact { plan.cost.exact_units } else { 0 });
    progress.plan(planned.min(u64::MAX / 4));
    let started = std::time::Instant::now();
    let (rows, exact) = rayon::join(
        || study.ensemble_with(dt, steps, record_every, paths, seed, progress),
        || plan.run_exact.then(|| study.exact_growth_with(t_end, records, progress)).transpose(),
    );
    let run_seconds = started.elapsed().as_secs_f64();
    let (rows, exact) = (rows?, exact?);
    progress.settle();
    let rows = rows.ok_or_else(|| FluidSimulationError::Failed("the drift's propagator could not be formed".into()))?;
    Ok(Series {
        times: rows.iter().map(|r| r.t).collect(),
        mean: rows.iter().map(|r| r.mean).collect(),
        std_error: rows.iter().map(|r| r.std_error).collect(),
        exact: exact.filter(|e| e.len() == records).map(|e| e.iter().map(|(_, v)| *v).collect()),
        run_seconds,
    })
}

/// The mode simulated and its certified growth.
struct Certified {
    m: usize,
    certified: f64,
    verified: bool,
}

/// What the run shows, beside the certified bound: the report and the
/// typed result.
#[allow(clippy::too_many_arguments)]
fn summarise(
    spec: &FluidSpec,
    problem: &FluidProblem,
    analysis: &fluid::analysis::FluidAnalysis,
    study: &fluid::analysis::ModeStudy,
    shape: &RunShape,
    plan: &RunPlan,
    seed: u64,
    mode: Certified,
    series: Series,
    notes: Notes<'_>,
) -> FluidSimulation {
    let Certified { m, certified, verified } = mode;
    let Series { times, mean, std_error, exact, run_seconds } = series;
    let TimeGrid { steps, records, t_end, .. } = plan.grid;
    let (compressible, ny, paths, dt) = (shape.compressible, shape.ny, shape.paths, shape.dt);
    let rate = study.initial_rate();
    let bound: Vec<f64> = times.iter().map(|t| (certified * t).exp()).collect();
    let rate_curve: Vec<f64> = times.iter().map(|t| (rate * t).exp()).collect();
    let overflowed = mean
        .iter()
        .chain(&std_error)
        .chain(exact.iter().flatten())
        .chain(&rate_curve)
        .filter(|v| !v.is_finite())
        .count();
    if overflowed > 0 {
        notes(format!(
            "{overflowed} values of the series are not finite (beyond the range of doubles; null in the report): a shorter t_end shows the growth"
        ));
    }
    let exact_over_bound = exact.as_ref().map(|e| e.iter().zip(&bound).map(|(e, b)| e / b).fold(0.0, f64::max));
    // The splitting's bias is O(dt^2); 4 standard errors plus 1e-3 of the
    // value (as in tests/it/fluid.rs) is the agreement asked of each time.
    let agreeing = exact.as_ref().map(|e| {
        e.iter().zip(&mean).zip(&std_error).filter(|((e, m), s)| (*m - *e).abs() <= 4.0 * *s + 1e-3 * e.abs()).count()
    });
    let paper = analysis.paper_bound;
    // Only the exact moment (not the Monte Carlo's noisy mean) decides this,
    // and only where the simulated SDE is the certified one: in the
    // compressible model the discrete SDE's rate lambda_B carries the grid's
    // Casimir defect, which can exceed the paper's constant by itself.
    let paper_exceeded_at = paper
        .zip(exact.as_ref().filter(|_| !compressible))
        .and_then(|(p, e)| times.iter().zip(e).find(|(t, v)| **v > (p * **t).exp() * (1.0 + 1e-9)).map(|(t, _)| *t));
    let report = json!({
        "kind": "fluid-simulation",
        "format": 1,
        "engine": crate::ENGINE_VERSION,
        "name": spec.name,
        "spec_digest": crate::spec_digest(&spec.raw),
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
        "seed": seed,
        "times": times,
        "monte_carlo_mean": mean,
        "monte_carlo_std_error": std_error,
        "exact": exact,
        "certified_bound": bound,
        "initial_rate_bound": rate_curve,
        "summary": {
            "exact_over_certified_bound_max": exact_over_bound,
            "monte_carlo_agrees_with_exact": agreeing,
            "monte_carlo_agreement": "|mean - exact| <= 4 standard errors + 1e-3 exact (the splitting's O(dt^2) bias)",
            "records": records,
            "paper_bound_exceeded_at": paper_exceeded_at,
        },
    });
    FluidSimulation {
        report,
        compressible,
        m,
        ny,
        certified,
        rate,
        times,
        mean,
        std_error,
        exact,
        bound,
        rate_curve,
        paper,
        k: study.k(),
        unknowns: study.unknowns(),
        verified,
        paths,
        steps,
        dt,
        t_end,
        exact_over_bound,
        agreeing,
        paper_exceeded_at,
        estimated_seconds: plan.estimated_seconds,
        run_seconds,
    }
}

/// The output times of a run: `steps` of `dt`, recorded every
/// `record_every` steps (`records` times), ending at `t_end`, which may
/// lie a little after the `asked` one.
#[derive(Clone, Copy, Debug)]
struct TimeGrid {
    steps: usize,
    record_every: usize,
    records: usize,
    t_end: f64,
    asked: f64,
}

/// At most `outputs` output times, each a whole number of steps apart, so
/// the run may end a little after `t_end`.
fn time_grid(t_end: f64, dt: f64, outputs: usize) -> Result<TimeGrid, FluidSimulationError> {
    // (t_end / dt within rounding of a whole number is that number: 0.9 / 0.03
    // is 30.000000000000004)
    let wanted = (t_end / dt * (1.0 - 1e-12)).ceil().max(1.0);
    if wanted > MAX_STEPS {
        return Err(invalid("t_end/dt", format!("{wanted:e} steps per path; at most {MAX_STEPS:e}")));
    }
    let wanted = wanted as usize;
    let record_every = wanted.div_ceil(outputs);
    let records = wanted.div_ceil(record_every);
    let steps = records * record_every;
    Ok(TimeGrid { steps, record_every, records, t_end: steps as f64 * dt, asked: t_end })
}

/// A run's estimated cost in wall-clock seconds.
#[derive(Clone, Copy, Debug)]
struct Estimate {
    path_steps: f64,
    /// The ensemble, on the thread pool (its setup and steps).
    monte_carlo: f64,
    /// The exact moment, on one thread.
    exact: f64,
    /// The exact moment's units of progress.
    exact_units: u64,
}

impl Estimate {
    /// The wall-clock time of the run: the exact moment (one thread) runs
    /// beside the ensemble (every thread of the pool), so the run lasts
    /// between `max(exact, monte_carlo + exact / cores)` on idle cores and
    /// `monte_carlo + exact` when the cores are busy (on the 2-core machine
    /// with another job running, the compressible fixture's default run took
    /// 48.5 s where the first form said 38 s). The sum is taken: at most 1.5
    /// times the first (at `exact = 2 monte_carlo` on two cores), and right
    /// on a loaded machine.
    fn wall(&self, with_exact: bool) -> f64 {
        if with_exact {
            self.monte_carlo + self.exact
        } else {
            self.monte_carlo
        }
    }
}

/// The default end time for the certified `sigma2`, and
/// the growth time when it was shortened: one growth time
/// `FLUID_SIMULATION_GROWTH_TIMES / sigma2`, at least
/// [`FLUID_SIMULATION_MIN_T_END`], at most `longest`;
/// [`FLUID_SIMULATION_NO_GROWTH_T_END`] when `sigma2` is 0. When
/// `seconds(t)`, the run's estimated wall-clock cost to `t`, exceeds
/// [`FLUID_SIMULATION_DEFAULT_SECONDS`], the end is shortened in proportion
/// (the cost is about linear in `t`: the Monte Carlo's steps and the exact
/// moment's Taylor steps both are), rounded down to two digits, and
/// shortened again (by halves) until it fits or reaches the floor.
fn default_t_end(sigma2: f64, longest: f64, seconds: impl Fn(f64) -> f64) -> (f64, Option<f64>) {
    let floor = FLUID_SIMULATION_MIN_T_END;
    if sigma2 <= 0.0 || !sigma2.is_finite() {
        return (FLUID_SIMULATION_NO_GROWTH_T_END, None);
    }
    let growth = FLUID_SIMULATION_GROWTH_TIMES / sigma2;
    let t = growth.min(longest).max(floor);
    let budget = FLUID_SIMULATION_DEFAULT_SECONDS;
    let cost = seconds(t);
    if cost <= budget {
        return (t, None);
    }
    let mut shorter = two_digits_down(t * budget / cost).max(floor);
    while shorter > floor && seconds(shorter) > budget {
        shorter = two_digits_down(shorter / 2.0).max(floor);
    }
    (shorter, Some(growth))
}

/// `x > 0` rounded down to two significant digits (`473.6` is `470`): a
/// shortened default end time that reads as chosen, not computed.
fn two_digits_down(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return x;
    }
    let unit = 10f64.powi(x.log10().floor() as i32 - 1);
    ((x / unit).floor() * unit).max(unit)
}

/// `x` to 9 significant digits at most, without trailing zeros
/// (`3.8200000000000003` is `3.82`).
fn short(x: f64) -> String {
    let s = format!("{x:.9e}");
    let (mantissa, exponent) = s.split_once('e').unwrap_or((&s, "0"));
    let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
    match exponent.parse::<i32>() {
        Ok(e) if (-4..15).contains(&e) => format!("{}", format!("{mantissa}e{e}").parse::<f64>().unwrap_or(x)),
        _ => format!("{mantissa}e{exponent}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default end time: one growth time `1/Sigma^2` when it is cheap
    /// (784 for `Sigma^2 = 1/784`, the case whose chart was flat at the old
    /// cap of 10), the floor 1 for fast growth, 10 without growth, at most
    /// `longest`; shortened to the budget (120 s) when the run would cost
    /// more, in proportion to two digits: at 0.5 s per unit time one
    /// growth time costs 392 s, so `784 * 120 / 392 = 240`, which costs
    /// exactly the budget. A cost that grows faster than `t` is halved
    /// until it fits, and a cost that never fits stops at the floor.
    #[test]
    fn default_end_is_one_growth_time_within_the_budget() {
        let free = |_: f64| 0.0;
        let (t, growth) = default_t_end(1.0 / 784.0, 1e6, free);
        assert!((t - 784.0).abs() < 1e-9 && growth.is_none(), "{t}");
        assert_eq!(default_t_end(5.0, 1e6, free), (FLUID_SIMULATION_MIN_T_END, None));
        assert_eq!(default_t_end(0.0, 1e6, free), (FLUID_SIMULATION_NO_GROWTH_T_END, None));
        assert_eq!(default_t_end(1e-12, 1e6, free), (1e6, None));
        // linear cost: shortened in proportion
        let (t, growth) = default_t_end(1.0 / 784.0, 1e6, |t| 0.5 * t);
        assert!((growth.unwrap() - 784.0).abs() < 1e-9);
        assert!((t - 240.0).abs() < 1e-9, "{t}");
        assert!(0.5 * t <= FLUID_SIMULATION_DEFAULT_SECONDS);
        // super-linear cost t^2 / 1000: 614.7 s at 784; 784 * 120 / 614.7 =
        // 153 -> 150 costs 22.5 s, within the budget
        let (t, _) = default_t_end(1.0 / 784.0, 1e6, |t| t * t / 1000.0);
        assert!(t * t / 1000.0 <= FLUID_SIMULATION_DEFAULT_SECONDS && t >= FLUID_SIMULATION_MIN_T_END, "{t}");
        assert!((t - 150.0).abs() < 1e-9, "{t}");
        // a cost that never fits stops at the floor
        let (t, growth) = default_t_end(1.0 / 784.0, 1e6, |_| 1e9);
        assert!(t == FLUID_SIMULATION_MIN_T_END && growth.is_some(), "{t}");
    }

    #[test]
    fn two_digits_round_down() {
        assert_eq!(two_digits_down(473.6), 470.0);
        assert_eq!(two_digits_down(153.6), 150.0);
        assert_eq!(two_digits_down(0.0357), 0.035);
        assert_eq!(two_digits_down(7.0), 7.0);
    }
}
