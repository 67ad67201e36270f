//! `verify simulate`: ensembles of the nonlinear and the linearised system,
//! exact moments, the exceedance probability against the certified bound,
//! and the charts.

use crate::messages::excerpt;
use crate::paths::{ensure_output_dir, file_stem_noted, write_atomic, write_failure};
use crate::plots::{write_density, write_growth, DensityChart, GrowthChart};
use crate::Failure;
use serde_json::json;
use simulate::{EnsembleSettings, EnsembleStats, Scheme, Study, StudyError, StudySettings};
use std::path::PathBuf;

/// Options of `verify simulate`.
#[derive(clap::Args, Debug)]
pub struct SimulateArgs {
    /// The spec (JSON).
    pub spec: PathBuf,
    /// Number of paths (default 10 000; 1 000 for a fluid spec).
    #[arg(long)]
    pub paths: Option<usize>,
    /// Time step.
    #[arg(long, default_value_t = 0.01, allow_negative_numbers = true)]
    pub dt: f64,
    /// Final time (default: 8 T(eps, delta) for a stable spec, within [1, 200],
    /// long enough to see the passage to the ergodic regime; else 20. For a
    /// fluid spec: one growth time 1/Sigma_k^2, where the certified bound
    /// has grown by e, at least 1, shortened with a note to what about 2
    /// minutes of computation reach; 10 when Sigma_k^2 = 0).
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
    /// Fluid specs: the x-mode to simulate (default: the one with the
    /// largest certified growth; the gravest for the compressible model).
    /// Zeitlin specs: the azimuthal wavenumber m, the diagonal of the
    /// perturbation (default: the largest lambda_max(Q_m, P_m)).
    #[arg(long)]
    pub mode: Option<usize>,
    /// Fluid specs: the y-grid of the simulated SDE, 16 to 512 (default: the
    /// spec's ny, at most 32; 16 for the compressible model). The growth it
    /// is set beside is certified on the same grid.
    #[arg(long)]
    pub ny: Option<usize>,
    /// Output directory.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Run even if the estimated cost exceeds 15 minutes.
    #[arg(long)]
    pub force: bool,
    /// Also write NAME.npz: every series of NAME.json as a numpy array
    /// (`numpy.load`), named by its key path (`nonlinear_mean`,
    /// `histogram_counts`, `exact_moments_over_delta`...).
    #[arg(long)]
    pub npz: bool,
    /// Run only shard K of N (K from 0): its share of the paths of each
    /// ensemble, written as exact sums to OUT/NAME.shard-K-of-N.json for
    /// `--merge` (a Slurm job array runs `--shard $SLURM_ARRAY_TASK_ID/N`).
    #[arg(long, value_name = "K/N", conflicts_with = "merge")]
    pub shard: Option<String>,
    /// Merge the shard files of this study (written by `--shard K/N` with
    /// the same spec and options) and write the outputs of the whole run,
    /// identical to an unsharded run's. Give SPEC before `--merge`.
    #[arg(long, value_name = "FILE", num_args = 1..)]
    pub merge: Vec<PathBuf>,
    /// Also run the nonlinear system with isotropic noise (a field along
    /// every coordinate axis, each of the largest amplitude among the spec's
    /// noise entries), from the same start and with the same seed, and draw
    /// its mean beside the compatible noise's on the density chart (the
    /// paper's figure). Not with --shard or --merge.
    #[arg(long, conflicts_with_all = ["shard", "merge"])]
    pub compare_isotropic: bool,
}

/// The spec's system with isotropic noise: one field along each coordinate
/// axis, of the largest absolute entry among the spec's noise fields (the
/// paper's isotropic comparison: `sigma e_1, sigma e_2, sigma e_3` beside
/// the compatible `sigma e_1`). `None` when the spec has no noise.
fn isotropic_system(system: &casimir::System) -> Option<casimir::System> {
    let amplitude = system.noise().iter().flatten().map(|x| x.abs()).max()?;
    if amplitude == exact::Rational::from(0) {
        return None;
    }
    let n = system.dim();
    let noise = (0..n)
        .map(|i| (0..n).map(|j| if i == j { amplitude.clone() } else { exact::Rational::from(0) }).collect())
        .collect();
    casimir::System::new(
        system.algebra().clone(),
        system.hamiltonian().clone(),
        system.casimirs().to_vec(),
        system.first_integrals().to_vec(),
        system.equilibrium().to_vec(),
        noise,
    )
    .ok()
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

/// A study error as a failure naming the flag.
fn study_failure(e: StudyError, coords: &[String]) -> Failure {
    match e {
        StudyError::EpsilonDelta { delta, epsilon } => {
            bad(format!("--delta/--epsilon: need 0 < delta < epsilon, got delta = {delta}, epsilon = {epsilon}"))
        }
        StudyError::Escaped { index, extent } => bad(format!(
            "--dt: the pilot run's paths left every bounded range ({} reached {:?}); lower --dt",
            coords[index], extent
        )),
        StudyError::Ensemble(e) => ensemble_failure(e),
        other => Failure::Failed(format!("internal: {other}")),
    }
}

pub fn run(args: &SimulateArgs) -> Result<(), Failure> {
    check_histogram_limits(args)?;
    ensure_output_dir(&args.out, "--out")?;
    let text =
        std::fs::read_to_string(&args.spec).map_err(|e| bad(format!("{}: cannot read: {e}", args.spec.display())))?;
    if serde_json::from_str::<serde_json::Value>(&text).is_ok_and(|v| spec::is_fluid_spec(&v)) {
        return crate::fluid_simulate::run(args, &text);
    }
    if serde_json::from_str::<serde_json::Value>(&text).is_ok_and(|v| spec::is_zeitlin_spec(&v)) {
        return crate::zeitlin_simulate::run(args, &text);
    }
    if args.mode.is_some() || args.ny.is_some() {
        return Err(bad("--mode/--ny: for fluid and Zeitlin specs only".into()));
    }
    let paths = args.paths.unwrap_or(10_000);
    let spec = spec::parse_spec(&text).map_err(|e| bad(format!("{}: {e}", args.spec.display())))?;
    let scheme = Scheme::from_name(&args.scheme)
        .ok_or_else(|| bad(format!("--scheme: '{}' is not 'lie' or 'heun'", excerpt(&args.scheme))))?;
    let cert = spec::certify_lie(&spec);
    let coords = spec.system.algebra().coordinates();
    let settings = study_settings(args, &spec, paths, scheme, coords)?;
    let prepared = simulate::prepare(&spec.system, &cert.analysis, &settings).map_err(|e| study_failure(e, coords))?;
    let shard = match &args.shard {
        Some(text) => {
            let s = sweep::Shard::parse(text).map_err(|m| bad(format!("--shard '{}': {m}", excerpt(text))))?;
            Some((s.k, s.n))
        }
        None => None,
    };
    // Everything that fixes the numbers of the study: shards of one study
    // carry the same identity, and `--merge` insists on it.
    let identity = simulate::study_identity(&spec::spec_digest(&spec.raw), &spec.name, &settings, &prepared, coords);
    let threads = rayon::current_num_threads() as f64;
    announce_cost(args, &prepared, shard, threads)?;
    let run = Run {
        args,
        name: &spec.name,
        coords,
        prepared: &prepared,
        paths,
        scheme,
        file_stem: file_stem_noted(&spec.name),
    };
    let Some(sums) = run.sums(shard, &identity)? else {
        return Ok(());
    };
    let study = simulate::finish(&prepared, &sums);
    let verdict = cert.json["verdict"].as_str().unwrap_or_default();
    let report = simulate::study_report(&spec.name, verdict, &prepared, &settings, &study, coords, threads as u64);
    run.write_files(&report, &study)?;
    run.write_charts(&study, &spec.system)?;
    run.print_summary(&study);
    Ok(())
}

/// The study's settings from the flags and the spec's stopping question.
fn study_settings(
    args: &SimulateArgs,
    spec: &spec::Spec,
    paths: usize,
    scheme: Scheme,
    coords: &[String],
) -> Result<StudySettings, Failure> {
    let observable = match &args.observable {
        Some(name) => Some(coords.iter().position(|c| c == name).ok_or_else(|| {
            bad(format!("--observable: unknown coordinate '{}' (coordinates: {})", excerpt(name), coords.join(", ")))
        })?),
        None => None,
    };
    Ok(StudySettings {
        paths,
        dt: args.dt,
        t_end: args.t_end,
        outputs: args.outputs,
        seed: args.seed,
        bins: args.bins,
        scheme,
        observable,
        epsilon: args.epsilon.or(spec.stopping.map(|s| s.epsilon)).unwrap_or(0.1),
        delta: args.delta.or(spec.stopping.map(|s| s.delta)).unwrap_or(1e-3),
    })
}

/// Refuse a run estimated above 15 minutes (unless forced), and say when
/// the default end time was moved or the run takes more than 10 s.
fn announce_cost(
    args: &SimulateArgs,
    prepared: &simulate::Prepared<'_>,
    shard: Option<(u64, u64)>,
    threads: f64,
) -> Result<(), Failure> {
    // More threads than cores (RAYON_NUM_THREADS up to 4 per core) do not
    // run faster: the estimate counts the cores that work.
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get) as f64;
    // A shard runs its share of the paths (and the whole pilot); a merge runs none.
    let share = shard.map_or(1.0, |(_, n)| 1.0 / n as f64);
    let estimate = if args.merge.is_empty() { prepared.estimated_seconds(threads.min(cores)) * share } else { 0.0 };
    if estimate > 900.0 && !args.force {
        return Err(bad(format!(
            "--paths/--dt/--t-end: {:.2e} path-steps would take about {:.0} minutes here; lower them, split the run (--shard K/N) or pass --force",
            prepared.ensemble.path_steps() * share,
            estimate / 60.0
        )));
    }
    if args.t_end.is_none() {
        // The default 8 T(eps, delta) is kept within [1, 200]: say so when
        // it was moved.
        if let Some(t) = prepared.stopping_time.filter(|t| t.is_finite()) {
            let wanted = 8.0 * t;
            if wanted != prepared.ensemble.t_end {
                eprintln!(
                    "note: t_end = {} (the default 8 T(eps, delta) = {} lies outside [1, 200]; pass --t-end {} to simulate that long)",
                    crate::table::format_number(&json!(prepared.ensemble.t_end)),
                    crate::table::format_number(&json!(wanted)),
                    crate::table::format_number(&json!(wanted))
                );
            }
        }
    }
    if estimate > 10.0 {
        eprintln!(
            "note: about {:.0} s of computation ({:.2e} path-steps on {} threads)",
            estimate,
            prepared.ensemble.path_steps() * share,
            threads
        );
    }
    Ok(())
}

/// One study's run: what its steps share.
struct Run<'a> {
    args: &'a SimulateArgs,
    name: &'a str,
    coords: &'a [String],
    prepared: &'a simulate::Prepared<'a>,
    paths: usize,
    scheme: Scheme,
    /// A safe stem: the name is data, and every file stays inside --out.
    file_stem: String,
}

impl Run<'_> {
    /// The study's exact sums: run here (all of it, or a shard, written to
    /// its file: then `None`), or merged from the shard files of `--merge`.
    fn sums(
        &self,
        shard: Option<(u64, u64)>,
        identity: &serde_json::Value,
    ) -> Result<Option<simulate::StudyShard>, Failure> {
        let (args, prepared, paths) = (self.args, self.prepared, self.paths);
        if !args.merge.is_empty() {
            return merge_shards(&args.merge, identity, prepared).map(Some);
        }
        let (index, count) = shard.unwrap_or((0, 1));
        let shard_paths = simulate::block_paths(paths, &simulate::shard_blocks(paths, index, count)).len();
        let bar =
            crate::progress_bar(shard_paths as u64 * prepared.ensembles(), "{bar:40} {pos}/{len} paths ({eta} left)");
        let tick = |k: u64| {
            if let Some(b) = &bar {
                b.inc(k)
            }
        };
        let never = std::sync::atomic::AtomicBool::new(false);
        let sums = simulate::run_shard_cancellable(prepared, index, count, &tick, &never)
            .map_err(|e| study_failure(e, self.coords))?;
        if let Some(b) = &bar {
            b.finish_and_clear();
        }
        if shard.is_none() {
            return Ok(Some(sums));
        }
        let path = args.out.join(format!("{}.shard-{index}-of-{count}.json", self.file_stem));
        let document = simulate::shard_document(identity, &sums);
        write_atomic(&path, spec::to_pretty_json(&document).as_bytes()).map_err(|e| write_failure(&path, &e))?;
        eprintln!(
            "{}: shard {index} of {count}: {} paths of each ensemble; merge all {count} with `verify simulate {} [the same options] --merge FILES`; wrote {}",
            excerpt(self.name),
            sums.nonlinear.paths,
            args.spec.display(),
            path.display()
        );
        Ok(None)
    }

    /// The report (JSON, and `.npz` with `--npz`) and the CSV series.
    fn write_files(&self, report: &serde_json::Value, study: &Study) -> Result<(), Failure> {
        let dir = &self.args.out;
        let json_path = dir.join(format!("{}.json", self.file_stem));
        write_atomic(&json_path, spec::to_pretty_json(report).as_bytes()).map_err(|e| write_failure(&json_path, &e))?;
        if self.args.npz {
            let npz_path = dir.join(format!("{}.npz", self.file_stem));
            crate::npz_out::write_json_arrays(&npz_path, report).map_err(|e| write_failure(&npz_path, &e))?;
        }
        write_csv(
            &dir.join(format!("{}.csv", self.file_stem)),
            &study.nonlinear,
            study.linear.as_ref(),
            study.exact_over_delta.as_deref(),
            study.bound_over_delta.as_deref(),
            study.worst_over_delta.as_deref(),
            self.prepared.delta,
        )
    }

    /// With `--compare-isotropic`: the observable's mean under isotropic
    /// noise of the same amplitude, on the same ensemble settings.
    fn isotropic_means(&self, system: &casimir::System) -> Result<Vec<(String, Vec<f64>)>, Failure> {
        if !self.args.compare_isotropic {
            return Ok(vec![]);
        }
        let iso = isotropic_system(system)
            .ok_or_else(|| bad("--compare-isotropic: the spec has no noise to compare with".into()))?;
        let model = simulate::Model::new(&iso);
        let target = simulate::Target::Nonlinear { model: &model, scheme: self.scheme, mu0: self.prepared.mu0.clone() };
        let bar = crate::progress_bar(self.paths as u64, "{bar:40} {pos}/{len} paths, isotropic noise ({eta} left)");
        let tick = |k: u64| {
            if let Some(b) = &bar {
                b.inc(k)
            }
        };
        let stats = simulate::run_ensemble(&target, &self.prepared.ensemble, &tick).map_err(ensemble_failure)?;
        if let Some(b) = &bar {
            b.finish_and_clear();
        }
        let observable = self.prepared.observable;
        Ok(vec![(
            "mean, isotropic noise (same amplitude)".to_string(),
            stats.mean.iter().map(|m| m[observable]).collect(),
        )])
    }

    /// The observable's density, and the growth of `E|dmu_t|_P^2` against
    /// the certified bound.
    fn write_charts(&self, study: &Study, system: &casimir::System) -> Result<(), Failure> {
        let Study {
            nonlinear, linear, exact_over_delta: exact, worst_over_delta: worst, bound_over_delta: bound, ..
        } = study;
        let prepared = self.prepared;
        let (observable, delta, stopping_time) = (prepared.observable, prepared.delta, prepared.stopping_time);
        let times = &nonlinear.times;
        let dir = &self.args.out;
        let name = excerpt(self.name);
        let observable_name = &self.coords[observable];
        let mean_obs: Vec<f64> = nonlinear.mean.iter().map(|m| m[observable]).collect();
        let other_means = self.isotropic_means(system)?;
        write_density(
            &dir.join(format!("{}-density", self.file_stem)),
            &DensityChart {
                title: format!("{name}: density of {observable_name} ({} paths, {})", self.paths, self.scheme.as_str()),
                observable: observable_name,
                times,
                histogram: &nonlinear.histogram,
                range: study.histogram_range,
                mean: mean_obs,
                other_means,
                stopping_time,
            },
        )
        .map_err(io)?;
        let Some(lin) = linear else {
            return Ok(());
        };
        let over = |v: &[f64]| v.iter().map(|x| x / delta).collect::<Vec<_>>();
        let lin_mean = over(&lin.norm_mean);
        let se = over(&lin.norm_std_error);
        let mut curves = vec![("linearised ensemble (mean)".to_string(), lin_mean.clone(), 2, false)];
        if let Some(e) = exact {
            curves.push(("exact second moments".into(), e.clone(), 0, false));
        }
        if let Some(w) = worst {
            curves.push(("worst start (exact)".into(), w.clone(), 4, true));
        }
        curves.push(("nonlinear ensemble (mean)".into(), over(&nonlinear.norm_mean), 3, false));
        write_growth(
            &dir.join(format!("{}-growth", self.file_stem)),
            &GrowthChart {
                title: format!("{name}: growth of E|dmu_t|_P^2"),
                times,
                curves,
                band: Some((
                    "ensemble ± 2 s.e.".into(),
                    lin_mean.iter().zip(&se).map(|(m, s)| m - 2.0 * s).collect(),
                    lin_mean.iter().zip(&se).map(|(m, s)| m + 2.0 * s).collect(),
                )),
                bound: bound.as_ref().map(|b| {
                    (
                        format!(
                            "certified bound exp(Sigma^2 t), Sigma^2 = {}",
                            crate::table::format_number(&serde_json::json!(prepared.sigma2.unwrap_or(0.0)))
                        ),
                        b.clone(),
                    )
                }),
                stopping_time,
                y_label: "E|dmu_t|^2 / |dmu_0|^2",
                ratio_caption: crate::plots::FINITE_RATIO_CAPTION,
            },
        )
        .map_err(io)
    }

    /// The run in a few lines on stderr: paths, Casimir drift, Sigma^2 and
    /// the stopping time, and each exceedance level against the ensemble.
    fn print_summary(&self, study: &Study) {
        let prepared = self.prepared;
        let (epsilon, delta, stopping_time) = (prepared.epsilon, prepared.delta, prepared.stopping_time);
        let nonlinear = &study.nonlinear;
        eprintln!(
            "{}: {} paths x {} steps ({}), Casimir drift {:.1e}; outputs in {}",
            excerpt(self.name),
            self.paths,
            nonlinear.steps,
            self.scheme.as_str(),
            nonlinear.casimir_drift,
            self.args.out.display()
        );
        // Every number to six significant digits at most, in one style.
        let num = |x: f64| crate::table::format_number(&json!(x));
        if let Some(s) = prepared.sigma2 {
            eprintln!(
                "  Sigma^2 = {}, T({}, {}) = {}, moment Lyapunov exponent = {}",
                num(s),
                num(epsilon),
                num(delta),
                stopping_time.map_or("infinity".into(), num),
                study.lyapunov.map_or("-".into(), num)
            );
        }
        for e in &study.exceedance {
            let certified = match e.certified_until {
                Some(t) if t.is_infinite() => "certified for all t".to_string(),
                Some(t) => format!("certified until t = {}", num(t)),
                None => "not certified".to_string(),
            };
            let seen = e.empirical_first_exceeded.map_or_else(
                || format!("not exceeded in the ensemble up to t = {}", num(prepared.ensemble.t_end)),
                |t| format!("first exceeded in the ensemble at t = {}", num(t)),
            );
            eprintln!("  P(|dmu_t|_P^2 > {}) <= {}: {certified}; {seen}", num(epsilon), num(e.level));
        }
    }
}

/// Read the shard files of a study and merge their exact sums
/// ([`simulate::merge_shard_documents`]: exactly the study `identity`
/// describes). Unreadable and malformed files are bad input (exit 2); a
/// shard of another study or an incomplete set is a failure (exit 1).
fn merge_shards(
    files: &[PathBuf],
    identity: &serde_json::Value,
    prepared: &simulate::Prepared<'_>,
) -> Result<simulate::StudyShard, Failure> {
    let mut documents = Vec::with_capacity(files.len());
    for path in files {
        let at = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| bad(format!("{at}: cannot read: {e}")))?;
        let v: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| bad(format!("{at}: not JSON ({e}); was the shard interrupted?")))?;
        documents.push((at, v));
    }
    simulate::merge_shard_documents(&documents, identity, prepared).map_err(|e| match e {
        simulate::MergeError::BadInput(m) if files.is_empty() => bad(format!("--merge: {m}")),
        simulate::MergeError::BadInput(m) => bad(m),
        other => Failure::Failed(other.to_string()),
    })
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
