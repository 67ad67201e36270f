//! Running a sweep: points in parallel (rayon), lines streamed to a sink as
//! chunks finish, so memory stays flat and an interruption loses only the
//! chunks in flight.

use crate::plan::{Plan, Shard};
use crate::point::{record_line, Evaluator};
use rayon::prelude::*;
use std::io::{self, Write};
use std::sync::mpsc::sync_channel;
use std::time::Instant;

/// Which points are already done (read back from an output file).
#[derive(Clone, Debug, Default)]
pub struct Done {
    bits: Vec<u64>,
    count: u64,
}

impl Done {
    /// Nothing done yet.
    pub fn none() -> Done {
        Done::default()
    }

    /// Mark point `index`.
    pub fn insert(&mut self, index: u64) {
        let (w, b) = ((index / 64) as usize, index % 64);
        if w >= self.bits.len() {
            self.bits.resize(w + 1, 0);
        }
        if self.bits[w] & (1 << b) == 0 {
            self.bits[w] |= 1 << b;
            self.count += 1;
        }
    }

    /// Whether point `index` is done.
    pub fn contains(&self, index: u64) -> bool {
        self.bits.get((index / 64) as usize).is_some_and(|w| w & (1 << (index % 64)) != 0)
    }

    /// Number of points marked.
    pub fn len(&self) -> u64 {
        self.count
    }

    /// Whether no point is marked.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }
}

/// What a run did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Summary {
    /// Points certified in this run (lines written).
    pub computed: u64,
    /// Points skipped because they were already done.
    pub skipped_done: u64,
    /// Points outside the spec's sweep domain (no line).
    pub outside_domain: u64,
    /// Points where the spec was invalid (lines with `error`).
    pub invalid: u64,
    /// Count per verdict, in the order stable, linearly_unstable,
    /// inconclusive, not_an_equilibrium, noise_incompatible.
    pub verdicts: [u64; 5],
}

const VERDICTS: [&str; 5] = ["stable", "linearly_unstable", "inconclusive", "not_an_equilibrium", "noise_incompatible"];

impl Summary {
    /// `stable 1200, linearly_unstable 300, ...` (non-zero counts only).
    pub fn verdict_counts(&self) -> String {
        let parts: Vec<String> =
            VERDICTS.iter().zip(self.verdicts).filter(|(_, c)| *c > 0).map(|(v, c)| format!("{v} {c}")).collect();
        if parts.is_empty() {
            "no verdicts".into()
        } else {
            parts.join(", ")
        }
    }
}

/// A chunk's lines and counts.
struct Chunk {
    text: String,
    summary: Summary,
    points: u64,
}

/// Run the points of `plan` that belong to `shard` and are not in `done`,
/// writing one line per certified point to `sink` (each finished chunk in
/// one `write_all`, followed by a flush). `progress` is called after each
/// chunk with the number of points it settled.
///
/// Points are certified on rayon's pool; lines come in completion order,
/// each carrying its `index`. The first point is timed to size the chunks so
/// that each takes about 20 ms (at most 256 points): an interrupted run
/// loses at most the chunks in flight.
pub fn run(
    evaluator: &Evaluator,
    plan: &Plan,
    id: &str,
    shard: Shard,
    done: &Done,
    sink: &mut (dyn Write + Send),
    progress: &(dyn Fn(u64) + Sync),
) -> io::Result<Summary> {
    let len = plan.len();
    let todo = |i: u64| shard.contains(i) && !done.contains(i);
    let names = evaluator.names().to_vec();
    let work = |i: u64, chunk: &mut Chunk| {
        chunk.points += 1;
        if !todo(i) {
            if shard.contains(i) {
                chunk.summary.skipped_done += 1;
            }
            return;
        }
        let values = plan.point(i);
        if !evaluator.in_domain(&values) {
            chunk.summary.outside_domain += 1;
            return;
        }
        let outcome = evaluator.evaluate(&values);
        match outcome.verdict {
            Some(v) => {
                if let Some(k) = VERDICTS.iter().position(|x| *x == v) {
                    chunk.summary.verdicts[k] += 1;
                }
            }
            None => chunk.summary.invalid += 1,
        }
        chunk.summary.computed += 1;
        chunk.text.push_str(&record_line(id, i, &names, &values, &outcome));
    };
    let new_chunk = || Chunk { text: String::new(), summary: Summary::default(), points: 0 };

    // Size the chunks from the first point to do.
    let mut total = Summary::default();
    let mut first = new_chunk();
    let first_index = (0..len).find(|&i| todo(i));
    let mut chunk_len = 1u64;
    if let Some(f) = first_index {
        let t = Instant::now();
        work(f, &mut first);
        let secs = t.elapsed().as_secs_f64().max(1e-7);
        chunk_len = ((0.02 / secs) as u64).clamp(1, 256);
        sink.write_all(first.text.as_bytes())?;
        sink.flush()?;
        merge(&mut total, &first.summary);
        progress(1);
    }
    // Points are numbered 0..len; chunk c covers [c*chunk_len, (c+1)*chunk_len)
    // minus the first point done above.
    let (tx, rx) = sync_channel::<Chunk>(64);
    let error = std::sync::Mutex::new(None::<io::Error>);
    let nchunks = len.div_ceil(chunk_len);
    let result = std::thread::scope(|scope| {
        let writer = scope.spawn(|| {
            let mut sum = Summary::default();
            for chunk in rx {
                if !chunk.text.is_empty() {
                    if let Err(e) = sink.write_all(chunk.text.as_bytes()).and_then(|_| sink.flush()) {
                        *error.lock().unwrap_or_else(|p| p.into_inner()) = Some(e);
                        break;
                    }
                }
                merge(&mut sum, &chunk.summary);
                progress(chunk.points);
            }
            sum
        });
        (0..nchunks).into_par_iter().for_each_with(tx, |tx, c| {
            if error.lock().map(|e| e.is_some()).unwrap_or(true) {
                return;
            }
            let mut chunk = new_chunk();
            let lo = c * chunk_len;
            let hi = (lo + chunk_len).min(len);
            for i in lo..hi {
                if Some(i) == first_index {
                    continue;
                }
                work(i, &mut chunk);
            }
            // A send fails only when the writer stopped on an error.
            let _ = tx.send(chunk);
        });
        writer.join()
    });
    let sum = result.map_err(|_| io::Error::other("the sweep's writer thread panicked"))?;
    if let Some(e) = error.into_inner().unwrap_or_else(|p| p.into_inner()) {
        return Err(e);
    }
    merge(&mut total, &sum);
    Ok(total)
}

fn merge(total: &mut Summary, s: &Summary) {
    total.computed += s.computed;
    total.skipped_done += s.skipped_done;
    total.outside_domain += s.outside_domain;
    total.invalid += s.invalid;
    for (t, x) in total.verdicts.iter_mut().zip(s.verdicts) {
        *t += x;
    }
}
