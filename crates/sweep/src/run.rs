//! Running a sweep: points in parallel (rayon), lines streamed to a sink as
//! chunks finish, so memory stays flat and an interruption loses only the
//! chunks in flight.

use crate::plan::{Plan, Shard};
use crate::point::{record_line, Evaluator, Verdict};
use rayon::prelude::*;
use std::io::{self, Write};
use std::sync::mpsc::sync_channel;
use std::time::Instant;

/// Which points are already done (read back from an output file).
///
/// A sorted, deduplicated list of indices, searched by bisection: memory
/// is proportional to the number of lines written (8 bytes a point), not
/// to the largest index, so resuming a 10^12-point plan whose file holds a
/// few lines near the end takes a few bytes (a bitset over the indices took
/// 125 GB there). A compressed bitmap (the `roaring` crate) would be
/// smaller for dense runs, but the list is already far smaller than the
/// file it was read from (a line is about 200 bytes), with no dependency.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Done {
    sorted: Vec<u64>,
}

impl Done {
    /// Nothing done yet.
    pub fn none() -> Done {
        Done::default()
    }

    /// The points `indices`, in any order, repeats allowed (`O(n log n)`).
    pub fn from_indices(mut indices: Vec<u64>) -> Done {
        indices.sort_unstable();
        indices.dedup();
        indices.shrink_to_fit();
        Done { sorted: indices }
    }

    /// Mark point `index` (`O(1)` when indices come in increasing order,
    /// else a shift of the larger ones; use [`Done::from_indices`] for many).
    pub fn insert(&mut self, index: u64) {
        if let Err(at) = self.sorted.binary_search(&index) {
            self.sorted.insert(at, index);
        }
    }

    /// Whether point `index` is done.
    pub fn contains(&self, index: u64) -> bool {
        self.sorted.binary_search(&index).is_ok()
    }

    /// Number of points marked.
    pub fn len(&self) -> u64 {
        self.sorted.len() as u64
    }

    /// Whether no point is marked.
    pub fn is_empty(&self) -> bool {
        self.sorted.is_empty()
    }

    /// Number of indices held in memory (equal to [`Done::len`]: one per
    /// point, whatever the indices are).
    pub fn stored(&self) -> usize {
        self.sorted.len()
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

impl Summary {
    /// `stable 1200, linearly_unstable 300, ...` (non-zero counts only).
    pub fn verdict_counts(&self) -> String {
        let parts: Vec<String> =
            Verdict::ALL.iter().zip(self.verdicts).filter(|(_, c)| *c > 0).map(|(v, c)| format!("{v} {c}")).collect();
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
    let tag = evaluator.spec_tag();
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
                if let Some(k) = Verdict::ALL.iter().position(|x| *x == v) {
                    chunk.summary.verdicts[k] += 1;
                }
            }
            None => chunk.summary.invalid += 1,
        }
        chunk.summary.computed += 1;
        chunk.text.push_str(&record_line(id, &tag, i, &names, &values, &outcome));
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Marking index 10^12 takes one entry, not a bitset up to 10^12.
    #[test]
    fn done_memory_follows_the_points_not_the_indices() {
        let mut done = Done::none();
        done.insert(1_000_000_000_000);
        assert_eq!(done.stored(), 1);
        assert!(done.contains(1_000_000_000_000));
        assert!(!done.contains(999_999_999_999) && !done.contains(0));
        // Repeats are kept once, in any order.
        for i in [7, 3, 1_000_000_000_000, 7, u64::MAX] {
            done.insert(i);
        }
        assert_eq!(done.len(), 4);
        assert_eq!(done, Done::from_indices(vec![u64::MAX, 3, 7, 1_000_000_000_000, 3]));
        assert!(done.contains(u64::MAX) && done.contains(3) && !done.contains(4));
    }
}
