//! Parallel ensembles that keep only statistics.

use crate::exact_sum::ExactSum;
use crate::kernel::Kernel;
use crate::model::Model;
use crate::scheme::{LinearModel, Scheme, Stepper};
use nalgebra::DMatrix;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;
use rayon::prelude::*;
use serde_json::{json, Value};
use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

/// What is integrated.
#[derive(Clone, Debug)]
pub enum Target<'a> {
    /// The nonlinear system from `mu0`, with a scheme.
    Nonlinear {
        /// The compiled system.
        model: &'a Model,
        /// The scheme.
        scheme: Scheme,
        /// The initial point.
        mu0: Vec<f64>,
    },
    /// The linearised SDE from `x0` (a perturbation of `mu_e`).
    Linear {
        /// The linear SDE.
        model: &'a LinearModel,
        /// The initial perturbation.
        x0: Vec<f64>,
    },
}

/// The coordinate whose distribution is recorded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Observable {
    /// Coordinate index.
    pub index: usize,
    /// Histogram range.
    pub lo: f64,
    /// Histogram range.
    pub hi: f64,
    /// Histogram bins.
    pub bins: usize,
}

/// Ensemble settings.
#[derive(Clone, Debug)]
pub struct EnsembleSettings {
    /// Number of paths.
    pub paths: usize,
    /// Time step.
    pub dt: f64,
    /// Final time.
    pub t_end: f64,
    /// Number of output times after 0.
    pub outputs: usize,
    /// Seed of the random streams (path `k` uses stream `k`).
    pub seed: u64,
    /// The recorded coordinate.
    pub observable: Observable,
    /// The norm matrix `sP` (for `|mu - mu_e|_P^2`) and `mu_e`, if any.
    pub norm: Option<(DMatrix<f64>, Vec<f64>)>,
    /// Threshold `eps` for the exceedance probability `P(|dmu|_P^2 > eps)`.
    pub epsilon: Option<f64>,
}

/// Why an ensemble cannot run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum EnsembleError {
    /// A parameter is out of range.
    #[error("{field}: {message}")]
    Invalid {
        /// Which parameter.
        field: &'static str,
        /// What is wrong.
        message: String,
    },
    /// The caller asked the run to stop (Ctrl-C in the Python package).
    #[error("stopped before the end (interrupted)")]
    Cancelled,
}

impl EnsembleSettings {
    /// Most histogram bins of the observable.
    pub const MAX_BINS: usize = 10_000;
    /// Most output times.
    pub const MAX_OUTPUTS: usize = 100_000;
    /// Most histogram cells, `outputs x bins` (80 MB of counts).
    pub const MAX_HISTOGRAM_CELLS: usize = 10_000_000;
    /// Most bytes of statistics held while running: every block of
    /// 256 paths keeps its own statistics (histogram, means, norms at
    /// each output time) until its wave of 64 blocks is reduced in
    /// order, which makes the numbers independent of the thread count.
    pub const MAX_STATISTICS_BYTES: u64 = 2 << 30;

    /// Number of steps.
    pub fn steps(&self) -> u64 {
        (self.t_end / self.dt).round().max(1.0) as u64
    }

    /// Check the parameters (not the cost; see [`Self::path_steps`]),
    /// including the limits on the memory the statistics take
    /// ([`Self::MAX_BINS`], [`Self::MAX_OUTPUTS`],
    /// [`Self::MAX_HISTOGRAM_CELLS`], [`Self::MAX_STATISTICS_BYTES`]).
    /// An error names the field: `paths`, `dt`, `t_end`, `steps` (`t_end /
    /// dt`), `outputs`, `bins`, `histogram_cells` (`outputs x bins`),
    /// `statistics` (paths, outputs and bins together), `observable`,
    /// `range` (the histogram range) or `epsilon`.
    pub fn validate(&self, dim: usize) -> Result<(), EnsembleError> {
        let bad = |field, message: String| Err(EnsembleError::Invalid { field, message });
        if self.paths == 0 {
            return bad("paths", "must be at least 1".into());
        }
        if !(self.dt.is_finite() && self.dt > 0.0) {
            return bad("dt", format!("must be a positive number, got {}", self.dt));
        }
        if !(self.t_end.is_finite() && self.t_end > 0.0) {
            return bad("t_end", format!("must be a positive number, got {}", self.t_end));
        }
        if self.t_end / self.dt > 1e12 {
            return bad("steps", format!("t_end/dt = {:e} steps per path is beyond reason", self.t_end / self.dt));
        }
        if self.outputs > Self::MAX_OUTPUTS {
            return bad("outputs", format!("at most {} output times, got {}", Self::MAX_OUTPUTS, self.outputs));
        }
        if self.outputs == 0 || self.outputs as u64 > self.steps() {
            return bad("outputs", format!("must be between 1 and the number of steps ({})", self.steps()));
        }
        let o = &self.observable;
        if o.index >= dim {
            return bad("observable", format!("coordinate {} does not exist (dimension {dim})", o.index));
        }
        if o.bins == 0 || o.bins > Self::MAX_BINS {
            return bad("bins", format!("must be between 1 and {}, got {}", Self::MAX_BINS, o.bins));
        }
        let cells = self.outputs as u64 * o.bins as u64;
        if cells > Self::MAX_HISTOGRAM_CELLS as u64 {
            return bad(
                "histogram_cells",
                format!("outputs x bins = {cells} histogram cells exceeds the limit of {}", Self::MAX_HISTOGRAM_CELLS),
            );
        }
        if o.lo >= o.hi || !o.lo.is_finite() || !o.hi.is_finite() {
            return bad("range", format!("the histogram needs a finite range lo < hi, got [{}, {}]", o.lo, o.hi));
        }
        // What run_ensemble holds: per block, at each output time, the
        // histogram, the mean of every coordinate and three norm statistics.
        let steps = self.steps();
        let stride = (steps / self.outputs as u64).max(1);
        let times = steps / stride + 1;
        let blocks = self.paths.div_ceil(BLOCK).min(WAVE) as u64;
        let per_time = 8 * (o.bins as u64 + dim as u64 + 3);
        // Plus the exact sums the blocks are added into (dim + 2 per output
        // time, about 100 bytes each: a few 32-bit chunks).
        let exact = (times as f64) * (dim as f64 + 2.0) * EXACT_SUM_BYTES;
        let bytes = (blocks as f64) * (times as f64) * (per_time as f64) + exact;
        if bytes > Self::MAX_STATISTICS_BYTES as f64 {
            return bad(
                "statistics",
                format!(
                    "{blocks} blocks of {BLOCK} paths x {times} output times x {} bins, with their exact sums, would hold {:.1} GB of statistics (limit {:.1} GB); lower the paths, the outputs or the bins",
                    o.bins,
                    bytes / 1e9,
                    Self::MAX_STATISTICS_BYTES as f64 / 1e9
                ),
            );
        }
        if let Some(e) = self.epsilon {
            if !(e.is_finite() && e > 0.0) {
                return bad("epsilon", "must be positive".into());
            }
        }
        Ok(())
    }

    /// Total path-steps: the cost of the run.
    pub fn path_steps(&self) -> f64 {
        self.paths as f64 * self.steps() as f64
    }
}

/// Statistics at the output times.
#[derive(Clone, Debug, PartialEq)]
pub struct EnsembleStats {
    /// Output times (starting at 0).
    pub times: Vec<f64>,
    /// Mean of every coordinate at each output time.
    pub mean: Vec<Vec<f64>>,
    /// Histogram of the observable at each output time.
    pub histogram: Vec<Vec<u64>>,
    /// Mean of `|mu - mu_e|_P^2` (or of `|x|_P^2`) at each output time.
    pub norm_mean: Vec<f64>,
    /// Standard error of that mean.
    pub norm_std_error: Vec<f64>,
    /// Fraction of paths with `|.|_P^2 > eps`.
    pub exceedance: Vec<f64>,
    /// Largest `|C(mu_t) - C(mu_0)|` over paths, times and Casimirs.
    pub casimir_drift: f64,
    /// Smallest and largest recorded value of the observable (inside or
    /// outside the histogram range).
    pub observable_extent: (f64, f64),
    /// Paths run.
    pub paths: usize,
    /// Steps per path.
    pub steps: u64,
}

/// The random stream of one path: xoshiro256++ seeded (through SplitMix64,
/// as `seed_from_u64` does) from the seed and the path index, so every path
/// has its own stream whatever thread runs it.
pub fn path_rng(seed: u64, path: u64) -> Xoshiro256PlusPlus {
    // Mix the path index in with the golden-ratio increment of SplitMix64.
    Xoshiro256PlusPlus::seed_from_u64(seed ^ path.wrapping_mul(0x9E37_79B9_7F4A_7C15).rotate_left(17))
}

/// Paths per block. A block's statistics are summed in floating point in
/// path order; blocks are then added into exact sums ([`ExactSum`]), so the
/// results depend neither on how rayon schedules the blocks nor on how the
/// blocks are split between shards (`verify simulate --shard K/N`).
pub const BLOCK: usize = 256;

/// Bytes an [`ExactSum`] takes, for the memory estimate.
const EXACT_SUM_BYTES: f64 = 100.0;

/// The blocks of [`BLOCK`] paths that shard `index` of `count` runs: a
/// contiguous range, the ranges of the `count` shards tiling `0..blocks`.
///
/// ```
/// let paths = 10_000; // 40 blocks
/// let ranges: Vec<_> = (0..3).map(|k| simulate::shard_blocks(paths, k, 3)).collect();
/// assert_eq!(ranges, vec![0..13, 13..26, 26..40]);
/// ```
pub fn shard_blocks(paths: usize, index: u64, count: u64) -> Range<usize> {
    let blocks = paths.div_ceil(BLOCK) as u128;
    let (k, n) = (index as u128, count.max(1) as u128);
    ((blocks * k / n) as usize)..((blocks * (k + 1) / n).min(blocks) as usize)
}

/// The paths of a range of blocks.
pub fn block_paths(paths: usize, blocks: &Range<usize>) -> Range<usize> {
    (blocks.start * BLOCK).min(paths)..(blocks.end * BLOCK).min(paths)
}

/// Blocks run (and held) at once before they are merged in order.
const WAVE: usize = 64;

struct Accumulator {
    mean: Vec<Vec<f64>>,
    histogram: Vec<Vec<u64>>,
    norm_sum: Vec<f64>,
    norm_sumsq: Vec<f64>,
    exceed: Vec<u64>,
    drift: f64,
    lo: f64,
    hi: f64,
}

impl Accumulator {
    fn new(times: usize, dim: usize, bins: usize) -> Self {
        Accumulator {
            mean: vec![vec![0.0; dim]; times],
            histogram: vec![vec![0; bins]; times],
            norm_sum: vec![0.0; times],
            norm_sumsq: vec![0.0; times],
            exceed: vec![0; times],
            drift: 0.0,
            lo: f64::INFINITY,
            hi: f64::NEG_INFINITY,
        }
    }
}

/// The exact sufficient statistics of the paths of some blocks: sums of the
/// state, of `|.|_P^2` and of its square at every output time (exact),
/// histogram and exceedance counts, the largest Casimir drift and the
/// observable's extent. Sums of disjoint sets of blocks merge exactly, in
/// any order ([`Self::merge`]); [`Self::finish`] turns the whole ensemble's
/// sums into [`EnsembleStats`].
#[derive(Clone, Debug, PartialEq)]
pub struct EnsembleSums {
    /// Paths summed.
    pub paths: u64,
    /// Sum of every coordinate at each output time.
    pub mean: Vec<Vec<ExactSum>>,
    /// Sum of `|.|_P^2` at each output time.
    pub norm_sum: Vec<ExactSum>,
    /// Sum of `|.|_P^4` at each output time.
    pub norm_sumsq: Vec<ExactSum>,
    /// Histogram counts of the observable at each output time.
    pub histogram: Vec<Vec<u64>>,
    /// Paths with `|.|_P^2 > eps` at each output time.
    pub exceed: Vec<u64>,
    /// Largest `|C(mu_t) - C(mu_0)|` at the final time.
    pub casimir_drift: f64,
    /// Smallest and largest value of the observable.
    pub extent: (f64, f64),
}

/// A double in JSON: a number when finite, else `"inf"`, `"-inf"` or `"nan"`.
fn float_json(x: f64) -> Value {
    if x.is_finite() {
        json!(x)
    } else if x.is_nan() {
        json!("nan")
    } else if x > 0.0 {
        json!("inf")
    } else {
        json!("-inf")
    }
}

fn float_from_json(v: &Value) -> Option<f64> {
    match v {
        Value::String(s) if s == "inf" => Some(f64::INFINITY),
        Value::String(s) if s == "-inf" => Some(f64::NEG_INFINITY),
        Value::String(s) if s == "nan" => Some(f64::NAN),
        _ => v.as_f64(),
    }
}

impl EnsembleSums {
    /// No paths yet: `times` output times, `dim` coordinates, `bins` bins.
    pub fn empty(times: usize, dim: usize, bins: usize) -> Self {
        EnsembleSums {
            paths: 0,
            mean: vec![vec![ExactSum::new(); dim]; times],
            norm_sum: vec![ExactSum::new(); times],
            norm_sumsq: vec![ExactSum::new(); times],
            histogram: vec![vec![0; bins]; times],
            exceed: vec![0; times],
            casimir_drift: 0.0,
            extent: (f64::INFINITY, f64::NEG_INFINITY),
        }
    }

    fn add_block(&mut self, b: &Accumulator, paths: u64) {
        self.paths += paths;
        for (a, m) in self.mean.iter_mut().zip(&b.mean) {
            for (x, y) in a.iter_mut().zip(m) {
                x.add(*y);
            }
        }
        for (a, h) in self.histogram.iter_mut().zip(&b.histogram) {
            for (x, y) in a.iter_mut().zip(h) {
                *x += y;
            }
        }
        for k in 0..self.norm_sum.len() {
            self.norm_sum[k].add(b.norm_sum[k]);
            self.norm_sumsq[k].add(b.norm_sumsq[k]);
            self.exceed[k] += b.exceed[k];
        }
        self.casimir_drift = self.casimir_drift.max(b.drift);
        self.extent = (self.extent.0.min(b.lo), self.extent.1.max(b.hi));
    }

    /// Add the sums of other paths (exactly; the shapes must agree).
    pub fn merge(&mut self, o: &EnsembleSums) {
        self.paths += o.paths;
        for (a, m) in self.mean.iter_mut().zip(&o.mean) {
            for (x, y) in a.iter_mut().zip(m) {
                x.merge(y);
            }
        }
        for (a, h) in self.histogram.iter_mut().zip(&o.histogram) {
            for (x, y) in a.iter_mut().zip(h) {
                *x += y;
            }
        }
        for k in 0..self.norm_sum.len() {
            self.norm_sum[k].merge(&o.norm_sum[k]);
            self.norm_sumsq[k].merge(&o.norm_sumsq[k]);
            self.exceed[k] += o.exceed[k];
        }
        self.casimir_drift = self.casimir_drift.max(o.casimir_drift);
        self.extent = (self.extent.0.min(o.extent.0), self.extent.1.max(o.extent.1));
    }

    /// The statistics of the ensemble these sums cover (means over
    /// [`Self::paths`]), at the output times of `settings`.
    pub fn finish(&self, settings: &EnsembleSettings) -> EnsembleStats {
        let steps = settings.steps();
        let stride = (steps / settings.outputs as u64).max(1);
        let np = self.paths.max(1) as f64;
        let norm_mean: Vec<f64> = self.norm_sum.iter().map(|s| s.to_f64() / np).collect();
        let norm_std_error = self
            .norm_sumsq
            .iter()
            .zip(&norm_mean)
            .map(|(sq, m)| {
                let var = (sq.to_f64() / np - m * m).max(0.0) * np / (np - 1.0).max(1.0);
                (var / np).sqrt()
            })
            .collect();
        EnsembleStats {
            times: (0..self.norm_sum.len()).map(|k| k as f64 * stride as f64 * settings.dt).collect(),
            mean: self.mean.iter().map(|m| m.iter().map(|x| x.to_f64() / np).collect()).collect(),
            histogram: self.histogram.clone(),
            norm_mean,
            norm_std_error,
            exceedance: self.exceed.iter().map(|&c| c as f64 / np).collect(),
            casimir_drift: self.casimir_drift,
            observable_extent: self.extent,
            paths: self.paths as usize,
            steps,
        }
    }

    /// The sums as JSON, every sum as its exact rational (`"p/q"`), so that
    /// another process can [`Self::merge`] them without rounding.
    pub fn to_json(&self) -> Value {
        let texts = |v: &[ExactSum]| v.iter().map(ExactSum::to_text).collect::<Vec<_>>();
        json!({
            "paths": self.paths,
            "mean": self.mean.iter().map(|m| texts(m)).collect::<Vec<_>>(),
            "norm_sum": texts(&self.norm_sum),
            "norm_sumsq": texts(&self.norm_sumsq),
            "histogram": self.histogram,
            "exceed": self.exceed,
            "casimir_drift": float_json(self.casimir_drift),
            "extent": [float_json(self.extent.0), float_json(self.extent.1)],
        })
    }

    /// Read [`Self::to_json`], expecting `times` output times, `dim`
    /// coordinates and `bins` bins. An error names the JSON path (under
    /// `at`) and what is wrong.
    pub fn from_json(v: &Value, at: &str, times: usize, dim: usize, bins: usize) -> Result<EnsembleSums, String> {
        let field = |name: &str| v.get(name).ok_or_else(|| format!("{at}.{name}: missing"));
        let array = |x: &Value, path: String, len: usize| -> Result<Vec<Value>, String> {
            let a = x.as_array().ok_or_else(|| format!("{path}: expected an array"))?;
            if a.len() != len {
                return Err(format!("{path}: expected {len} entries, got {}", a.len()));
            }
            Ok(a.clone())
        };
        let sums = |x: &Value, path: String, len: usize| -> Result<Vec<ExactSum>, String> {
            array(x, path.clone(), len)?
                .iter()
                .enumerate()
                .map(|(i, e)| {
                    e.as_str().and_then(ExactSum::from_text).ok_or_else(|| {
                        format!("{path}[{i}]: expected an exact sum of doubles (\"p/q\" with q a power of two, or nan, inf, -inf)")
                    })
                })
                .collect()
        };
        let counts = |x: &Value, path: String, len: usize| -> Result<Vec<u64>, String> {
            array(x, path.clone(), len)?
                .iter()
                .enumerate()
                .map(|(i, e)| e.as_u64().ok_or_else(|| format!("{path}[{i}]: expected a count")))
                .collect()
        };
        let paths = field("paths")?.as_u64().ok_or_else(|| format!("{at}.paths: expected a count"))?;
        let mean = array(field("mean")?, format!("{at}.mean"), times)?
            .iter()
            .enumerate()
            .map(|(k, row)| sums(row, format!("{at}.mean[{k}]"), dim))
            .collect::<Result<Vec<_>, _>>()?;
        let histogram = array(field("histogram")?, format!("{at}.histogram"), times)?
            .iter()
            .enumerate()
            .map(|(k, row)| counts(row, format!("{at}.histogram[{k}]"), bins))
            .collect::<Result<Vec<_>, _>>()?;
        let float = |name: &str| -> Result<f64, String> {
            float_from_json(field(name)?).ok_or_else(|| format!("{at}.{name}: expected a number"))
        };
        // No count exceeds the paths summed (so merged counts cannot overflow
        // and no exceedance exceeds 1).
        for (k, row) in histogram.iter().enumerate() {
            if row.iter().try_fold(0u64, |a, &c| a.checked_add(c)).is_none_or(|total| total > paths) {
                return Err(format!("{at}.histogram[{k}]: counts more than the {paths} paths"));
            }
        }
        let exceed = counts(field("exceed")?, format!("{at}.exceed"), times)?;
        if let Some(k) = exceed.iter().position(|&c| c > paths) {
            return Err(format!("{at}.exceed[{k}]: more than the {paths} paths"));
        }
        let extent = array(field("extent")?, format!("{at}.extent"), 2)?;
        let bound =
            |i: usize| float_from_json(&extent[i]).ok_or_else(|| format!("{at}.extent[{i}]: expected a number"));
        Ok(EnsembleSums {
            paths,
            mean,
            norm_sum: sums(field("norm_sum")?, format!("{at}.norm_sum"), times)?,
            norm_sumsq: sums(field("norm_sumsq")?, format!("{at}.norm_sumsq"), times)?,
            histogram,
            exceed,
            casimir_drift: float("casimir_drift")?,
            extent: (bound(0)?, bound(1)?),
        })
    }
}

struct Recorder<'s> {
    settings: &'s EnsembleSettings,
    pmat: Option<&'s DMatrix<f64>>,
    centre: Option<&'s [f64]>,
    diff: Vec<f64>,
}

impl Recorder<'_> {
    fn record(&mut self, acc: &mut Accumulator, k: usize, state: &[f64]) {
        for (m, x) in acc.mean[k].iter_mut().zip(state) {
            *m += x;
        }
        let o = &self.settings.observable;
        let v = state[o.index];
        acc.lo = acc.lo.min(v);
        acc.hi = acc.hi.max(v);
        if v >= o.lo && v <= o.hi {
            let bin = (((v - o.lo) / (o.hi - o.lo)) * o.bins as f64) as usize;
            acc.histogram[k][bin.min(o.bins - 1)] += 1;
        }
        if let Some(p) = self.pmat {
            let n = state.len();
            for i in 0..n {
                self.diff[i] = state[i] - self.centre.map_or(0.0, |c| c[i]);
            }
            let mut q = 0.0;
            for i in 0..n {
                let mut row = 0.0;
                for j in 0..n {
                    row += p[(i, j)] * self.diff[j];
                }
                q += self.diff[i] * row;
            }
            acc.norm_sum[k] += q;
            acc.norm_sumsq[k] += q * q;
            if self.settings.epsilon.is_some_and(|e| q > e) {
                acc.exceed[k] += 1;
            }
        }
    }
}

/// The loop bounds of one block.
struct BlockRun {
    first: usize,
    last: usize,
    steps: u64,
    stride: u64,
    n_times: usize,
    dt: f64,
    sqdt: f64,
    seed: u64,
}

/// Paths advanced together by the fixed-size kernels. One step of one path
/// is a chain of dependent floating-point operations (latency-bound); the
/// steps of independent paths interleave in the processor, which roughly
/// doubles the throughput. Each path keeps its own random stream, so the
/// numbers are the same as one path at a time.
const LANES: usize = 4;

/// The path loop with a fixed-size kernel, monomorphised so the step is
/// inlined and the states stay in registers.
fn kernel_paths<const N: usize>(
    k: &Kernel<N>,
    b: &BlockRun,
    mu0: &[f64],
    c0: &[f64],
    model: &Model,
    rec: &mut Recorder<'_>,
    acc: &mut Accumulator,
) {
    let noise = k.noise.len();
    let mut start = [0.0; N];
    start.copy_from_slice(mu0);
    let mut first = b.first;
    while first < b.last {
        let lanes = LANES.min(b.last - first);
        let mut rngs: Vec<_> = (0..lanes).map(|l| path_rng(b.seed, (first + l) as u64)).collect();
        let mut mu = [start; LANES];
        let mut dw = [[0.0f64; 8]; LANES];
        for m in mu.iter().take(lanes) {
            rec.record(acc, 0, m);
        }
        for s in 1..=b.steps {
            for (l, rng) in rngs.iter_mut().enumerate() {
                for w in dw[l].iter_mut().take(noise) {
                    let z: f64 = StandardNormal.sample(rng);
                    *w = z * b.sqdt;
                }
            }
            for l in 0..lanes {
                k.step(&mut mu[l], b.dt, &dw[l][..noise]);
            }
            if s % b.stride == 0 {
                let t = (s / b.stride) as usize;
                if t < b.n_times {
                    for m in mu.iter().take(lanes) {
                        rec.record(acc, t, m);
                    }
                }
            }
        }
        for m in mu.iter().take(lanes) {
            for (c, c0) in model.casimir_values(m).iter().zip(c0) {
                acc.drift = acc.drift.max((c - c0).abs());
            }
        }
        first += lanes;
    }
}

/// Run the ensemble. `progress` is called with the number of paths finished
/// after each block (for a progress bar).
pub fn run_ensemble(
    target: &Target<'_>,
    settings: &EnsembleSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<EnsembleStats, EnsembleError> {
    run_ensemble_cancellable(target, settings, progress, &AtomicBool::new(false))
}

/// [`run_ensemble`] that stops when `cancel` is set: blocks of paths not
/// yet started are skipped, and the result is [`EnsembleError::Cancelled`]
/// once the blocks in flight end.
pub fn run_ensemble_cancellable(
    target: &Target<'_>,
    settings: &EnsembleSettings,
    progress: &(dyn Fn(u64) + Sync),
    cancel: &AtomicBool,
) -> Result<EnsembleStats, EnsembleError> {
    let all = 0..settings.paths.div_ceil(BLOCK);
    Ok(run_blocks_cancellable(target, settings, all, progress, cancel)?.finish(settings))
}

/// The exact sums of the paths of blocks `blocks` (of [`BLOCK`] paths; see
/// [`shard_blocks`]) of the ensemble `settings` describes: one shard of it.
/// The shards' sums [`EnsembleSums::merge`] into exactly the sums of the
/// whole ensemble.
pub fn run_blocks_cancellable(
    target: &Target<'_>,
    settings: &EnsembleSettings,
    blocks: Range<usize>,
    progress: &(dyn Fn(u64) + Sync),
    cancel: &AtomicBool,
) -> Result<EnsembleSums, EnsembleError> {
    let (dim, noise_count) = match target {
        Target::Nonlinear { model, mu0, .. } => {
            if mu0.len() != model.dim() {
                return Err(EnsembleError::Invalid { field: "mu0", message: "wrong length".into() });
            }
            (model.dim(), model.noise_count())
        }
        Target::Linear { model, x0 } => {
            if x0.len() != model.dim() {
                return Err(EnsembleError::Invalid { field: "x0", message: "wrong length".into() });
            }
            (model.dim(), model.noise_count())
        }
    };
    settings.validate(dim)?;
    let steps = settings.steps();
    let stride = (steps / settings.outputs as u64).max(1);
    let n_times = (steps / stride) as usize + 1;
    if blocks.start > blocks.end || blocks.end > settings.paths.div_ceil(BLOCK) {
        return Err(EnsembleError::Invalid {
            field: "blocks",
            message: format!("{blocks:?} is not a range of the {} blocks", settings.paths.div_ceil(BLOCK)),
        });
    }
    let run_block = |block: usize| -> Accumulator {
        let mut acc = Accumulator::new(n_times, dim, settings.observable.bins);
        if cancel.load(Ordering::Relaxed) {
            return acc;
        }
        let mut rec = Recorder {
            settings,
            pmat: settings.norm.as_ref().map(|(p, _)| p),
            centre: match target {
                Target::Nonlinear { .. } => settings.norm.as_ref().map(|(_, c)| c.as_slice()),
                Target::Linear { .. } => None,
            },
            diff: vec![0.0; dim],
        };
        let first = block * BLOCK;
        let last = (first + BLOCK).min(settings.paths);
        let dt = settings.dt;
        let run = BlockRun { first, last, steps, stride, n_times, dt, sqdt: dt.sqrt(), seed: settings.seed };
        match target {
            Target::Nonlinear { model, scheme, mu0 } => {
                nonlinear_block(model, *scheme, mu0, &run, noise_count, &mut rec, &mut acc)
            }
            Target::Linear { model, x0 } => linear_block(model, x0, &run, noise_count, &mut rec, &mut acc),
        }
        progress((last - first) as u64);
        acc
    };
    // Blocks run in waves of WAVE and are added into the exact sums after
    // each wave, with memory for one wave instead of one set of statistics
    // per block (10^6 paths held 0.69 GB).
    let mut total = EnsembleSums::empty(n_times, dim, settings.observable.bins);
    let mut start = blocks.start;
    while start < blocks.end {
        if cancel.load(Ordering::Relaxed) {
            return Err(EnsembleError::Cancelled);
        }
        let end = (start + WAVE).min(blocks.end);
        let partial: Vec<Accumulator> = (start..end).into_par_iter().map(&run_block).collect();
        for (block, p) in (start..end).zip(&partial) {
            let first = block * BLOCK;
            total.add_block(p, ((first + BLOCK).min(settings.paths) - first) as u64);
        }
        start = end;
    }
    if cancel.load(Ordering::Relaxed) {
        return Err(EnsembleError::Cancelled);
    }
    Ok(total)
}

/// The paths `run.first..run.last` of the nonlinear system from `mu0`:
/// the fixed-size Lie–Heun kernels where the dimension has one, else the
/// general stepper; each path's Casimir drift into `acc`.
fn nonlinear_block(
    model: &Model,
    scheme: Scheme,
    mu0: &[f64],
    run: &BlockRun,
    noise_count: usize,
    rec: &mut Recorder<'_>,
    acc: &mut Accumulator,
) {
    let c0 = model.casimir_values(mu0);
    match (scheme, model.kernel3(), model.kernel6()) {
        (Scheme::LieHeun, Some(k), _) => kernel_paths(&k, run, mu0, &c0, model, rec, acc),
        (Scheme::LieHeun, _, Some(k)) => kernel_paths(&k, run, mu0, &c0, model, rec, acc),
        _ => {
            let mut stepper = Stepper::new(model, scheme);
            let end = |mu: &[f64], acc: &mut Accumulator| {
                for (c, c0) in model.casimir_values(mu).iter().zip(&c0) {
                    acc.drift = acc.drift.max((c - c0).abs());
                }
            };
            run_paths(run, mu0, noise_count, rec, acc, |mu, dw| stepper.step(mu, run.dt, dw), end);
        }
    }
}

/// The paths `run.first..run.last` from `start`, each with its own stream
/// ([`path_rng`]): Brownian increments `sqrt(dt) N(0, 1)`, `step`, the state
/// recorded every `stride` steps, and `end` at the end of each path.
fn run_paths(
    run: &BlockRun,
    start: &[f64],
    noise_count: usize,
    rec: &mut Recorder<'_>,
    acc: &mut Accumulator,
    mut step: impl FnMut(&mut [f64], &[f64]),
    mut end: impl FnMut(&[f64], &mut Accumulator),
) {
    let mut dw = vec![0.0; noise_count];
    let mut x = start.to_vec();
    for path in run.first..run.last {
        let mut rng = path_rng(run.seed, path as u64);
        x.copy_from_slice(start);
        rec.record(acc, 0, &x);
        for s in 1..=run.steps {
            for w in dw.iter_mut() {
                let z: f64 = StandardNormal.sample(&mut rng);
                *w = z * run.sqdt;
            }
            step(&mut x, &dw);
            if s % run.stride == 0 {
                let k = (s / run.stride) as usize;
                if k < run.n_times {
                    rec.record(acc, k, &x);
                }
            }
        }
        end(&x, acc);
    }
}

/// The paths `run.first..run.last` of the linearised SDE from `x0`.
fn linear_block(
    model: &LinearModel,
    x0: &[f64],
    run: &BlockRun,
    noise_count: usize,
    rec: &mut Recorder<'_>,
    acc: &mut Accumulator,
) {
    let dim = x0.len();
    let mut kbuf = vec![0.0; dim * dim];
    let mut ybuf = vec![0.0; 2 * dim];
    let step = |x: &mut [f64], dw: &[f64]| model.step(x, run.dt, dw, &mut kbuf, &mut ybuf);
    run_paths(run, x0, noise_count, rec, acc, step, |_, _| {});
}
