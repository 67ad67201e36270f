//! `verify sweep`: certify a spec over a grid or random samples of its
//! parameters, one JSON line per point, resumable and shardable.

use crate::messages::{excerpt, quoting};
use crate::paths::{check_output_file, ensure_output_dir, is_stdout, shown};
use crate::{read, Failure};
use clap::Args;
use spec::ParamRange;
use std::fs::{File, OpenOptions, TryLockError};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;
use sweep::{Done, Evaluator, Level, Plan, Sampling, Shard};

/// The plan of a sweep: the spec, the ranges, grid or random points, the
/// level. `verify sweep` runs it; `verify merge` re-derives it to check
/// that shard files make up exactly this sweep.
#[derive(Args, Debug)]
pub struct PlanArgs {
    /// The spec (JSON). Its optional `sweep` section gives default ranges,
    /// boundaries and reference constants for the plots.
    pub spec: PathBuf,
    /// A swept parameter, NAME=START:STOP:COUNT (repeatable; replaces the
    /// spec's ranges). START and STOP may be rationals such as 3/10.
    #[arg(long = "param", value_name = "NAME=START:STOP:COUNT", allow_hyphen_values = true)]
    pub params: Vec<String>,
    /// Every point of the tensor grid (the default).
    #[arg(long, conflicts_with = "random")]
    pub grid: bool,
    /// N points drawn uniformly from the box of the ranges (COUNT unused).
    #[arg(long, value_name = "N")]
    pub random: Option<u64>,
    /// Seed of --random (the same seed gives the same points).
    #[arg(long, default_value_t = 0, requires = "random")]
    pub seed: u64,
    /// Floating-point verdicts only (settings.exact = false): much faster,
    /// level `numerical`.
    #[arg(long)]
    pub numeric: bool,
}

/// Options of `verify sweep`.
#[derive(Args, Debug)]
pub struct SweepArgs {
    #[command(flatten)]
    pub plan: PlanArgs,
    /// Only the points whose index is K modulo N (split a sweep across
    /// machines or Slurm array tasks; `verify merge` joins the outputs).
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
    /// Write the lines to this file (default, and with `-o -`: stdout).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Keep the complete lines already in --output and compute only the
    /// missing points (needs -o FILE).
    #[arg(long, requires = "output")]
    pub resume: bool,
    /// After the sweep, draw the charts into this directory (needs -o FILE:
    /// the charts are drawn from it).
    #[arg(long, requires = "output")]
    pub plot: Option<PathBuf>,
    /// After the sweep, also write its lines (all of --output, in index
    /// order) as numpy arrays: `index`, one per parameter, `sigma2`, `T`,
    /// `verdict_code` (0 stable, 1 linearly_unstable, 2 inconclusive,
    /// 3 not_an_equilibrium, 4 noise_incompatible, -1 invalid). Needs
    /// -o FILE (read back); `--npz -` writes the archive to stdout.
    #[arg(long, value_name = "FILE", requires = "output")]
    pub npz: Option<PathBuf>,
}

/// A sweep's plan made concrete: the evaluator, the points, the id.
pub(crate) struct PlannedSweep {
    pub evaluator: Evaluator,
    pub plan: Plan,
    pub id: String,
}

/// Read the spec and build the plan, the evaluator and the sweep's id.
pub(crate) fn planned(args: &PlanArgs) -> Result<PlannedSweep, Failure> {
    let text = read(&args.spec)?;
    let spec = spec::parse(&text, &spec::Options::relative_to(args.spec.parent()))
        .map_err(|e| bad(format!("{}: {e}", args.spec.display())))?;
    let ranges: Vec<ParamRange> = if args.params.is_empty() {
        spec.sweep().ranges.clone()
    } else {
        args.params
            .iter()
            .map(|p| ParamRange::parse(p).map_err(|m| bad(format!("--param {}", quoting(m.0, p)))))
            .collect::<Result<_, _>>()?
    };
    let names: Vec<String> = ranges.iter().map(|r| r.name.clone()).collect();
    let sampling = match args.random {
        Some(points) => Sampling::Random { points, seed: args.seed },
        None => Sampling::Grid,
    };
    let plan = Plan::new(ranges, sampling).map_err(|m| {
        bad(format!("{}: {}", args.spec.display(), names.iter().fold(m.to_string(), |m, n| quoting(m, n))))
    })?;
    let level = if args.numeric { Level::Numeric } else { Level::Spec };
    let id = sweep::sweep_id(&spec, &plan, level);
    let evaluator = Evaluator::new(spec, names.clone(), level)
        .map_err(|m| bad(format!("--param: {}", names.iter().fold(m.to_string(), |m, n| quoting(m, n)))))?;
    Ok(PlannedSweep { evaluator, plan, id })
}

fn bad(m: impl Into<String>) -> Failure {
    Failure::BadInput(m.into())
}

/// Open the output file for a sweep and take an exclusive lock on it
/// before changing anything: a second sweep on the same file (resumed or
/// not) is refused, instead of both writing and garbling it. Only then is
/// the file emptied (a fresh sweep) or cut back to its complete lines
/// (`--resume`, which also returns the points already done). The file is
/// opened for appending, so every chunk of whole lines goes to its end.
/// The lock is released when the process exits, however it exits.
fn open_locked(path: &Path, resume: bool, id: &str, len: u64) -> Result<(File, Done), Failure> {
    check_output_file(path, "-o")?;
    let mut file = OpenOptions::new()
        .read(true)
        .append(true)
        .create(true)
        .open(path)
        .map_err(|e| bad(format!("-o {}: cannot open: {e}", path.display())))?;
    match file.try_lock() {
        Ok(()) => {}
        Err(TryLockError::WouldBlock) => {
            return Err(bad(format!(
                "-o {}: the file is in use by another sweep (it holds the lock); wait for it to finish, or choose another --output",
                path.display()
            )))
        }
        // A filesystem without locks (some network mounts): go on, warned.
        Err(TryLockError::Error(e)) if e.kind() == std::io::ErrorKind::Unsupported => {
            eprintln!("note: -o {}: cannot lock the file here ({e}); do not run two sweeps on it at once", path.display())
        }
        Err(TryLockError::Error(e)) => {
            return Err(Failure::Failed(format!("-o {}: cannot lock the file: {e}", path.display())))
        }
    }
    let failed = |e: std::io::Error| Failure::Failed(format!("-o {}: {e}", path.display()));
    // A device or FIFO (-o /dev/stdout) has no length to cut or lines to resume.
    let regular = file.metadata().map_err(failed)?.is_file();
    if !resume {
        if regular {
            file.set_len(0).map_err(failed)?;
        }
        return Ok((file, Done::none()));
    }
    if !regular {
        return Err(bad(format!("-o {}: --resume needs a regular file", path.display())));
    }
    let existing = sweep::scan(&mut file, id, len).map_err(|e| {
        bad(format!("{}: cannot resume: {e} (use another --output, or drop --resume to overwrite)", path.display()))
    })?;
    if existing.truncated_line {
        eprintln!("{}: dropping an incomplete last line (that point is computed again)", path.display());
    }
    file.set_len(existing.valid_len).map_err(failed)?;
    eprintln!("{}: {} points already done", path.display(), existing.done.len());
    Ok((file, existing.done))
}

/// Run `verify sweep`.
pub fn run(args: &SweepArgs) -> Result<(), Failure> {
    // `-o -` is stdout; what reads the output back needs a file.
    let output = args.output.as_deref().filter(|p| !is_stdout(p));
    if args.output.is_some() && output.is_none() {
        let needs = [(args.resume, "--resume"), (args.plot.is_some(), "--plot"), (args.npz.is_some(), "--npz")];
        if let Some((_, flag)) = needs.iter().find(|(given, _)| *given) {
            return Err(bad(format!(
                "{flag} reads the sweep's lines back from -o FILE: with -o - they go to standard output; name a file"
            )));
        }
    }
    if let Some(dir) = &args.plot {
        ensure_output_dir(dir, "--plot")?;
    }
    if let (Some(npz), Some(out)) = (&args.npz, output) {
        // Checked before the sweep runs: a bad name must not cost the sweep.
        check_output_file(npz, "--npz")?;
        crate::paths::check_distinct(npz, "--npz", out, "-o")?;
    }
    let PlannedSweep { evaluator, plan, id } = planned(&args.plan)?;
    let shard = match &args.shard {
        Some(s) => Shard::parse(s).map_err(|m| bad(format!("--shard '{}': {m}", excerpt(s))))?,
        None => Shard::ALL,
    };

    let (mut sink, done): (Box<dyn Write + Send>, Done) = match output {
        None => (Box::new(std::io::stdout()), Done::none()),
        Some(path) => {
            let (file, done) = open_locked(path, args.resume, &id, plan.len())?;
            (Box::new(file), done)
        }
    };

    let bar = crate::progress_bar(plan.len(), "{bar:40} {pos}/{len} points ({per_sec}, {eta} left)");
    let started = Instant::now();
    let progress = |n: u64| {
        if let Some(b) = &bar {
            b.inc(n);
        }
    };
    let summary = sweep::run(&evaluator, &plan, &id, shard, &done, &mut sink, &progress)
        .map_err(|e| Failure::Failed(format!("writing the sweep: {e}")))?;
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let secs = started.elapsed().as_secs_f64();
    eprintln!(
        "sweep {id}: {} points certified in {secs:.2} s ({:.0} points/s, {} threads); {}",
        summary.computed,
        summary.computed as f64 / secs.max(1e-9),
        rayon::current_num_threads(),
        summary.verdict_counts()
    );
    if summary.skipped_done > 0 {
        eprintln!("  {} points were already in the output", summary.skipped_done);
    }
    if summary.outside_domain > 0 {
        eprintln!("  {} points lie outside the spec's sweep domain (no line)", summary.outside_domain);
    }
    if let (Some(npz), Some(out)) = (&args.npz, output) {
        let text = read(out)?;
        let mut lines: Vec<(u64, &str)> = text
            .lines()
            .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok()?.get("index")?.as_u64().map(|i| (i, l)))
            .collect();
        lines.sort_by_key(|(i, _)| *i);
        crate::npz_out::write_sweep_columns(npz, evaluator.names(), lines.into_iter().map(|(_, l)| l))
            .map_err(|e| Failure::Failed(format!("--npz {}: cannot write: {e}", shown(npz))))?;
    }
    if let (Some(dir), Some(out)) = (&args.plot, output) {
        crate::sweep_plots::plot_files(&[out.to_path_buf()], &args.plan.spec, dir, None, None)?;
    }
    if summary.invalid > 0 {
        return Err(bad(format!(
            "the spec is invalid at {} of the points (their lines carry an \"error\" naming the field)",
            summary.invalid
        )));
    }
    Ok(())
}
