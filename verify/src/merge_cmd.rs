//! `verify merge`: join the line files of a sharded sweep (`verify sweep
//! --shard K/N -o FILE`, one per machine or Slurm array task) into one file,
//! after checking that together they are exactly the sweep the plan
//! describes:
//!
//! * **identity**: every line carries the plan's sweep id (spec, ranges,
//!   sampling and level hashed; a line of another spec or plan is refused,
//!   naming its file and line);
//! * **duplicates**: a point that appears twice must carry the same result
//!   (the same shard given twice is harmless: the copy is dropped); two
//!   different results for one point are refused;
//! * **completeness**: every point of the plan inside the spec's sweep
//!   domain has its line (the missing ones are counted, with the shard that
//!   holds the first few);
//! * **form**: every line is exactly what `verify sweep` writes for its
//!   index's plan point and its own results ([`sweep::record_line`]): the
//!   float parameters are the exact ones rounded, the spec tag is the
//!   spec's, the verdict and level are names the engine uses, no key is
//!   added.
//!
//! The results themselves (verdict, `Sigma^2`, `T`) are the shards' data:
//! without `--recheck` they are passed on as the shards state them, and the
//! summary says so; `--recheck` certifies every point again and refuses a
//! line whose results differ.
//!
//! The output has the lines in index order, written atomically.

use crate::messages::excerpt;
use crate::paths::{check_one_stdout, check_output_file, ensure_output_dir, is_stdout, shown, write_output};
use crate::sweep_cmd::{planned, PlanArgs, PlannedSweep};
use crate::Failure;
use clap::Args;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// Options of `verify merge`.
#[derive(Args, Debug)]
pub struct MergeArgs {
    /// The plan the shards ran: the same spec and options as `verify sweep`.
    #[command(flatten)]
    pub plan: PlanArgs,
    /// The shard files (JSON lines), any order. They take every value up to
    /// the next option, so give SPEC before `--lines`.
    #[arg(long = "lines", value_name = "FILE", required = true, num_args = 1..)]
    pub lines: Vec<PathBuf>,
    /// The merged file (`-o -`: stdout).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also draw the charts of the merged sweep into this directory (needs
    /// -o FILE: the charts are drawn from it).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Also write the merged sweep as numpy arrays (`numpy.load`): `index`,
    /// one array per parameter, `sigma2` and `T` (NaN where absent, inf for
    /// an infinite T), and `verdict_code` (0 stable, 1 linearly_unstable,
    /// 2 inconclusive, 3 not_an_equilibrium, 4 noise_incompatible, -1 an
    /// invalid point). `--npz -` writes the archive to stdout.
    #[arg(long, value_name = "FILE")]
    pub npz: Option<PathBuf>,
    /// Certify every point again and refuse a line whose results (verdict,
    /// level, Sigma^2, T, growth rate) differ from the re-derived ones.
    /// Costs as much as the sweep itself.
    #[arg(long)]
    pub recheck: bool,
}

fn bad(m: impl Into<String>) -> Failure {
    Failure::BadInput(m.into())
}

/// Run `verify merge`.
pub fn run(args: &MergeArgs) -> Result<(), Failure> {
    check_output_file(&args.output, "-o")?;
    if let Some(dir) = &args.plot {
        if is_stdout(&args.output) {
            return Err(bad(
                "--plot draws the charts from -o FILE: with -o - the merged lines go to standard output; name a file",
            ));
        }
        ensure_output_dir(dir, "--plot")?;
    }
    if let Some(npz) = &args.npz {
        check_output_file(npz, "--npz")?;
        check_one_stdout(npz, "--npz", &args.output, "-o")?;
        crate::paths::check_distinct(npz, "--npz", &args.output, "-o")?;
        for input in &args.lines {
            crate::paths::check_distinct(npz, "--npz", input, "--lines")?;
        }
    }
    let PlannedSweep { evaluator, plan, id } = planned(&args.plan)?;
    // index -> (line, where it came from). Memory is about the size of the
    // files (a line is about 200 bytes).
    let mut points: BTreeMap<u64, (String, String)> = BTreeMap::new();
    let mut dropped = 0u64;
    let spec_tag = evaluator.spec_tag();
    let stopping = evaluator.spec().stopping();
    for path in &args.lines {
        let bytes = std::fs::read(path).map_err(|e| bad(format!("{}: cannot read: {e}", path.display())))?;
        let complete = bytes.last().is_none_or(|&b| b == b'\n');
        if !bytes.contains(&b'\n') && bytes.iter().filter(|&&b| b == b'\r').count() > 1 {
            return Err(bad(format!(
                "{}: its lines end in CR alone (an old Mac text format), not LF or CRLF: convert the line ends",
                path.display()
            )));
        }
        let chunks: Vec<&[u8]> = bytes.split(|&b| b == b'\n').collect();
        let last = chunks.len().saturating_sub(1);
        let interrupted = |at: &str, what: String| {
            bad(format!(
                "{at}: the file ends in a partial line ({what}): an interrupted shard; finish it with `verify sweep --resume`"
            ))
        };
        for (n, line) in chunks.into_iter().enumerate() {
            let at = format!("{}:{}", path.display(), n + 1);
            let cut = n == last && !complete;
            let mut line = match String::from_utf8(line.to_vec()) {
                Ok(l) => l,
                // a shard cut inside a multi-byte character
                Err(_) if cut => return Err(interrupted(&at, "not UTF-8 text".into())),
                Err(_) => return Err(bad(format!("{at}: not UTF-8 text"))),
            };
            // A byte-order mark an editor added (at the start of any line:
            // `cat` of two such shards puts one mid-file): not part of it.
            if line.starts_with('\u{feff}') {
                line.remove(0);
            }
            if line.ends_with('\r') {
                line.pop(); // a CRLF file (copied through Windows): the same line
            }
            if line.trim().is_empty() {
                continue;
            }
            // Duplicated keys are refused, as in certificates: the last
            // one would silently win.
            let value: Value = spec::parse_json(&line).map_err(|e| {
                if cut {
                    interrupted(&at, e.message.clone())
                } else {
                    bad(format!("{at}: not a sweep line: {} ({})", e.message, e.path))
                }
            })?;
            let Some(line_id) = value.get("sweep").and_then(Value::as_str) else {
                return Err(bad(format!("{at}: not a sweep record (no \"sweep\" id)")));
            };
            if line_id != id {
                return Err(Failure::Failed(format!(
                    "{at}: the line belongs to sweep '{}', not to this plan's '{id}' (another spec, other ranges, sampling or level)",
                    excerpt(line_id)
                )));
            }
            let index = value
                .get("index")
                .and_then(Value::as_u64)
                .filter(|&i| i < plan.len())
                .ok_or_else(|| bad(format!("{at}: no index of this plan's {} points", plan.len())))?;
            // The point must be the plan's point at that index, inside the
            // domain: a line edited to another index is not this sweep.
            let values = plan.point(index);
            let stated = value.get("exact_parameters").and_then(Value::as_object);
            let same_point = stated.is_some_and(|m| {
                m.len() == evaluator.names().len()
                    && evaluator.names().iter().zip(&values).all(|(name, v)| {
                        m.get(name).and_then(Value::as_str).and_then(|t| exact::parse_number(t).ok()).as_ref()
                            == Some(v)
                    })
            });
            if !same_point || !evaluator.in_domain(&values) {
                return Err(Failure::Failed(format!(
                    "{at}: point {index} of this plan is not the point the line states, or lies outside the sweep domain"
                )));
            }
            // The line is exactly what `verify sweep` writes for this point
            // and these results.
            let outcome = sweep::outcome_from_line(&value).ok_or_else(|| {
                Failure::Failed(format!(
                    "{at}: not a result `verify sweep` writes (an unknown verdict or level, or a number that is not one)"
                ))
            })?;
            let canonical = sweep::record_line(&id, &spec_tag, index, evaluator.names(), &values, &outcome);
            let written: Value = serde_json::from_str(&canonical).unwrap_or_default();
            if written != value {
                let key = differing_key(&written, &value);
                return Err(Failure::Failed(format!(
                    "{at}: the line differs from what `verify sweep` writes for point {index} with these results (at \"{key}\"{})",
                    if key == "parameters" { ": the float parameters are not the exact ones rounded" } else { "" }
                )));
            }
            if let Some(why) = inconsistent(&outcome, stopping) {
                return Err(Failure::Failed(format!("{at}: the line contradicts itself: {why}")));
            }
            // The merged file holds the canonical text (keys in the order
            // `verify sweep` writes them).
            let line = canonical.trim_end().to_string();
            match points.get(&index) {
                Some((seen, _)) if *seen == line => dropped += 1,
                Some((_, first)) => {
                    return Err(Failure::Failed(format!(
                        "point {index} has two different results: {first} and {at} (shards of different runs?)"
                    )))
                }
                None => {
                    points.insert(index, (line, at));
                }
            }
        }
    }
    // Completeness: every point in the sweep domain has its line.
    let mut missing = 0u64;
    let mut examples = vec![];
    for index in 0..plan.len() {
        if !points.contains_key(&index) && evaluator.in_domain(&plan.point(index)) {
            missing += 1;
            if examples.len() < 5 {
                examples.push(index);
            }
        }
    }
    if missing > 0 {
        let list: Vec<String> = examples.iter().map(u64::to_string).collect();
        return Err(Failure::Failed(format!(
            "incomplete: {missing} of the plan's {} points have no line (indices {}{}); the shard --shard K/N holds the indices equal to K modulo N: run or resume the shards that hold them",
            plan.len(),
            list.join(", "),
            if missing > 5 { ", ..." } else { "" }
        )));
    }
    if args.recheck {
        recheck(&evaluator, &plan, &id, &spec_tag, &points)?;
    }
    let mut text = String::new();
    let mut verdicts: BTreeMap<String, u64> = BTreeMap::new();
    for (line, _) in points.values() {
        text.push_str(line);
        text.push('\n');
        let v: Value = serde_json::from_str(line).unwrap_or_default();
        let verdict = v.get("verdict").and_then(Value::as_str).unwrap_or("error");
        *verdicts.entry(verdict.to_string()).or_default() += 1;
    }
    write_output(&args.output, text.as_bytes())
        .map_err(|e| Failure::Failed(format!("-o {}: cannot write: {e}", shown(&args.output))))?;
    let counts: Vec<String> = verdicts.iter().map(|(v, c)| format!("{v} {c}")).collect();
    eprintln!(
        "merged sweep {id}: {} files, {} points ({}) into {}{}",
        args.lines.len(),
        points.len(),
        counts.join(", "),
        shown(&args.output),
        if dropped > 0 { format!("; {dropped} repeated lines dropped") } else { String::new() }
    );
    eprintln!(
        "  {}",
        if args.recheck {
            "every point was certified again here and its results agree with the line"
        } else {
            "the results are the shards' data: each line's form and parameters were checked against the plan, its verdict and numbers were not re-derived (--recheck certifies every point again)"
        }
    );
    if let Some(path) = &args.npz {
        crate::npz_out::write_sweep_columns(path, evaluator.names(), points.values().map(|(line, _)| line.as_str()))
            .map_err(|e| Failure::Failed(format!("--npz {}: cannot write: {e}", shown(path))))?;
    }
    if let Some(dir) = &args.plot {
        crate::sweep_plots::plot_files(std::slice::from_ref(&args.output), &args.plan.spec, dir, None, None)?;
    }
    Ok(())
}

/// The first top-level key whose value differs between two lines, the
/// results first (the verdict before the numbers that follow from it).
fn differing_key(written: &Value, found: &Value) -> String {
    let (Some(w), Some(f)) = (written.as_object(), found.as_object()) else { return "$".into() };
    const ORDER: [&str; 10] =
        ["verdict", "error", "level", "sigma2", "T", "growth_rate", "parameters", "exact_parameters", "spec", "sweep"];
    let keys = ORDER.iter().map(|k| k.to_string()).chain(w.keys().cloned()).chain(f.keys().cloned());
    keys.into_iter().find(|k| w.get(k) != f.get(k)).unwrap_or_else(|| "the layout".into())
}

/// Certify every merged point again (in parallel) and compare its line.
fn recheck(
    evaluator: &sweep::Evaluator,
    plan: &sweep::Plan,
    id: &str,
    spec_tag: &str,
    points: &BTreeMap<u64, (String, String)>,
) -> Result<(), Failure> {
    use rayon::prelude::*;
    let entries: Vec<(&u64, &(String, String))> = points.iter().collect();
    let mut differing: Vec<(u64, String, String)> = entries
        .par_iter()
        .filter_map(|(&index, (line, at))| {
            let values = plan.point(index);
            let outcome = evaluator.evaluate(&values);
            let derived = sweep::record_line(id, spec_tag, index, evaluator.names(), &values, &outcome);
            if derived.trim_end() == line {
                return None;
            }
            let (w, f) =
                (serde_json::from_str(&derived).unwrap_or_default(), serde_json::from_str(line).unwrap_or_default());
            Some((index, at.clone(), differing_key(&w, &f)))
        })
        .collect();
    if differing.is_empty() {
        return Ok(());
    }
    differing.sort();
    let examples: Vec<String> =
        differing.iter().take(5).map(|(i, at, key)| format!("point {i} ({at}) at \"{key}\"")).collect();
    Err(Failure::Failed(format!(
        "--recheck: {} of {} lines differ from the results certified again: {}{}",
        differing.len(),
        points.len(),
        examples.join("; "),
        if differing.len() > 5 { "; ..." } else { "" }
    )))
}

/// What a line states that cannot all be true (a result is data, but not
/// nonsense): a stable point without a finite `Sigma^2 >= 0`; a stopping
/// time that is not positive, present without the spec's question,
/// infinite with `Sigma^2 > 0`, or beyond
/// `ln(epsilon/delta)/Sigma^2` of its own `Sigma^2` (the engine's `T`
/// comes from a proved bound at or above it: the exact value rounded up, a
/// fluid's `sigma2_upper`); a growth rate that is not positive, or on a
/// stable point; `Sigma^2` or `T` on a linearly unstable point.
fn inconsistent(o: &sweep::Outcome, stopping: Option<spec::Stopping>) -> Option<String> {
    use sweep::Verdict;
    match o.verdict {
        Some(Verdict::Stable) => {
            let s = o.sigma2.filter(|s| s.is_finite() && *s >= 0.0);
            let Some(s) = s else { return Some("a stable point without a finite Sigma^2 >= 0".into()) };
            match (stopping, o.stopping_time) {
                (None, Some(_)) => return Some("a stopping time, but the spec asks for none".into()),
                // no T: nothing proved bounds Sigma^2 (a fluid's unverified
                // estimate), which a line may say
                (Some(_), None) => {}
                (Some(st), Some(t)) => {
                    let own = generator::StoppingTime::new(st.epsilon, st.delta, s).time();
                    let fine = match (t, own) {
                        (None, None) => true,
                        (None, Some(_)) => false,
                        (Some(t), None) => t.is_finite() && t > 0.0,
                        (Some(t), Some(d)) => t.is_finite() && t > 0.0 && t <= d * (1.0 + 1e-9),
                    };
                    if !fine {
                        return Some("T is not at most ln(epsilon/delta)/Sigma^2 of its own Sigma^2".into());
                    }
                }
                (None, None) => {}
            }
            o.growth_rate.is_some().then(|| "a growth rate on a stable point".into())
        }
        Some(Verdict::LinearlyUnstable) => {
            if o.sigma2.is_some() || o.stopping_time.is_some() {
                return Some("Sigma^2 or T on a linearly unstable point".into());
            }
            o.growth_rate.filter(|g| !(g.is_finite() && *g > 0.0)).map(|_| "a growth rate that is not positive".into())
        }
        _ => None,
    }
}
