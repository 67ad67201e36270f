//! `verify sweep`: certify a spec over a grid or random samples of its
//! parameters, one JSON line per point, resumable and shardable.

use crate::{read, Failure};
use clap::Args;
use spec::{parse_any_spec, ParamRange};
use std::fs::OpenOptions;
use std::io::{Seek, SeekFrom, Write};
use std::path::PathBuf;
use std::time::Instant;
use sweep::{Done, Evaluator, Level, Plan, Sampling, Shard};

/// Options of `verify sweep`.
#[derive(Args, Debug)]
pub struct SweepArgs {
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
    /// Only the points whose index is K modulo N (split a sweep across
    /// machines; concatenate the outputs).
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
    /// Write the lines here (default: stdout).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Keep the complete lines already in --output and compute only the
    /// missing points.
    #[arg(long, requires = "output")]
    pub resume: bool,
    /// Floating-point verdicts only (settings.exact = false): much faster,
    /// level `numerical`.
    #[arg(long)]
    pub numeric: bool,
    /// After the sweep, draw the charts into this directory (needs --output).
    #[arg(long, requires = "output")]
    pub plot: Option<PathBuf>,
}

fn bad(m: impl Into<String>) -> Failure {
    Failure::BadInput(m.into())
}

/// Run `verify sweep`.
pub fn run(args: &SweepArgs) -> Result<(), Failure> {
    let text = read(&args.spec)?;
    let spec = parse_any_spec(&text).map_err(|e| bad(format!("{}: {e}", args.spec.display())))?;
    let ranges: Vec<ParamRange> = if args.params.is_empty() {
        spec.sweep().ranges.clone()
    } else {
        args.params
            .iter()
            .map(|p| ParamRange::parse(p).map_err(|m| bad(format!("--param {m}"))))
            .collect::<Result<_, _>>()?
    };
    let names: Vec<String> = ranges.iter().map(|r| r.name.clone()).collect();
    let sampling = match args.random {
        Some(points) => Sampling::Random { points, seed: args.seed },
        None => Sampling::Grid,
    };
    let plan = Plan::new(ranges, sampling).map_err(|m| bad(format!("{}: {m}", args.spec.display())))?;
    let level = if args.numeric { Level::Numeric } else { Level::Spec };
    let id = sweep::sweep_id(&spec, &plan, level);
    let evaluator = Evaluator::new(spec, names, level).map_err(|m| bad(format!("--param: {m}")))?;
    let shard = match &args.shard {
        Some(s) => Shard::parse(s).map_err(|m| bad(format!("--shard {m}")))?,
        None => Shard::ALL,
    };

    let mut done = Done::none();
    let mut sink: Box<dyn Write + Send> = match &args.output {
        None => Box::new(std::io::stdout()),
        Some(path) => {
            let mut file = OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(!args.resume)
                .open(path)
                .map_err(|e| bad(format!("{}: cannot open: {e}", path.display())))?;
            if args.resume {
                let existing = sweep::scan(&mut file, &id, plan.len()).map_err(|e| {
                    bad(format!(
                        "{}: cannot resume: {e} (use another --output, or drop --resume to overwrite)",
                        path.display()
                    ))
                })?;
                if existing.truncated_line {
                    eprintln!("{}: dropping an incomplete last line (that point is computed again)", path.display());
                }
                file.set_len(existing.valid_len)
                    .and_then(|_| file.seek(SeekFrom::End(0)))
                    .map_err(|e| Failure::Failed(format!("{}: {e}", path.display())))?;
                done = existing.done;
                eprintln!("{}: {} points already done", path.display(), done.len());
            }
            Box::new(file)
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
    if let (Some(dir), Some(out)) = (&args.plot, &args.output) {
        crate::sweep_plots::plot_files(std::slice::from_ref(out), &args.spec, dir, None)?;
    }
    if summary.invalid > 0 {
        return Err(bad(format!(
            "the spec is invalid at {} of the points (their lines carry an \"error\" naming the field)",
            summary.invalid
        )));
    }
    Ok(())
}
