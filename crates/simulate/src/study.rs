//! A whole simulation study of an analysed system, the numbers behind
//! `verify simulate` (and behind any other front end): ensembles of the
//! nonlinear and the linearised SDE started at `sqrt(delta)` along the
//! fastest-growing direction, the exact second moments of the linearised
//! SDE, the worst start, the certified bound, the moment Lyapunov exponent
//! and the exceedance probability against what the certificate guarantees.
//!
//! [`prepare`] validates and fixes every setting (the final time defaults to
//! `8 T(eps, delta)` within `[1, 200]` for a stable system) and estimates the
//! cost; [`run`] runs a pilot ensemble (1% of the paths, at most 200) to size
//! the observable's histogram, then the ensembles.

use crate::ensemble::{
    run_blocks_cancellable, run_ensemble_cancellable, shard_blocks, EnsembleError, EnsembleSettings, EnsembleStats,
    EnsembleSums, Observable, Target,
};
use crate::model::Model;
use crate::scheme::{LinearModel, Scheme};
use casimir::System;
use generator::{Analysis, SecondMoments};
use nalgebra::DMatrix;
use serde_json::{json, Value};
use std::sync::atomic::AtomicBool;

/// What a study is asked for.
#[derive(Clone, Debug, PartialEq)]
pub struct StudySettings {
    /// Number of paths per ensemble.
    pub paths: usize,
    /// Time step.
    pub dt: f64,
    /// Final time (`None`: `8 T(eps, delta)` within `[1, 200]` for a stable
    /// system with `Sigma^2 > 0`, else 20).
    pub t_end: Option<f64>,
    /// Number of output times.
    pub outputs: usize,
    /// Seed of the random streams.
    pub seed: u64,
    /// Histogram bins of the observable.
    pub bins: usize,
    /// The integrator.
    pub scheme: Scheme,
    /// Coordinate index of the observable (`None`: the first coordinate with
    /// a non-zero equilibrium value).
    pub observable: Option<usize>,
    /// Threshold `eps` on `|dmu_t|_P^2`.
    pub epsilon: f64,
    /// Initial size `delta = |dmu_0|_P^2`.
    pub delta: f64,
}

/// Why a study cannot run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum StudyError {
    /// `0 < delta < eps` does not hold.
    #[error("need 0 < delta < epsilon, got delta = {delta}, epsilon = {epsilon}")]
    EpsilonDelta {
        /// `delta`.
        delta: f64,
        /// `eps`.
        epsilon: f64,
    },
    /// The observable index is not a coordinate.
    #[error("observable index {0} is not a coordinate")]
    Observable(usize),
    /// The pilot run's paths left every bounded range.
    #[error("the pilot run's paths left every bounded range (coordinate {index} reached {extent:?}); lower dt")]
    Escaped {
        /// The observable.
        index: usize,
        /// Its extent in the pilot run.
        extent: (f64, f64),
    },
    /// The ensemble refused its settings or failed.
    #[error(transparent)]
    Ensemble(#[from] EnsembleError),
}

/// A study ready to run: every setting fixed, the cost known.
pub struct Prepared<'a> {
    analysis: &'a Analysis,
    model: Model,
    scheme: Scheme,
    /// The ensemble settings (the histogram range is provisional until the
    /// pilot run).
    pub ensemble: EnsembleSettings,
    /// `P` (times its sign) when stable, else the identity.
    pub p: DMatrix<f64>,
    /// The start `x0 = sqrt(delta) v` of the linearised SDE.
    pub x0: Vec<f64>,
    /// The start `mu_e + x0` of the nonlinear SDE.
    pub mu0: Vec<f64>,
    /// The observable's coordinate index.
    pub observable: usize,
    /// `Sigma^2`, when stable.
    pub sigma2: Option<f64>,
    /// `T(eps, delta) = ln(eps/delta) / Sigma^2` when `Sigma^2 > 0`.
    pub stopping_time: Option<f64>,
    /// `eps`.
    pub epsilon: f64,
    /// `delta`.
    pub delta: f64,
}

/// Everything a study computed.
#[derive(Clone, Debug, PartialEq)]
pub struct Study {
    /// The nonlinear ensemble.
    pub nonlinear: EnsembleStats,
    /// The linearised ensemble (stable systems).
    pub linear: Option<EnsembleStats>,
    /// `E|x_t|_P^2 / delta` from the exact second moments (stable systems).
    pub exact_over_delta: Option<Vec<f64>>,
    /// The worst start's `E|x_t|_P^2 / |x_0|_P^2` (stable systems).
    pub worst_over_delta: Option<Vec<f64>>,
    /// `exp(Sigma^2 t)` (stable systems).
    pub bound_over_delta: Option<Vec<f64>>,
    /// The moment Lyapunov exponent of the linearised SDE.
    pub lyapunov: Option<f64>,
    /// Per level `alpha` (0.01, 0.1, 0.5): the certified time up to which
    /// `P(|dmu_t|_P^2 > eps) <= alpha` (`Some(inf)` for `Sigma^2 = 0`), and
    /// the first output time the nonlinear ensemble exceeded it.
    pub exceedance: Vec<Exceedance>,
    /// The histogram range used.
    pub histogram_range: (f64, f64),
}

/// The exceedance probability at one level.
#[derive(Clone, Debug, PartialEq)]
pub struct Exceedance {
    /// The level `alpha`.
    pub level: f64,
    /// `ln(alpha eps / delta) / Sigma^2` (0 if negative; infinite for
    /// `Sigma^2 = 0`), when stable.
    pub certified_until: Option<f64>,
    /// The first output time with an empirical exceedance above `alpha`.
    pub empirical_first_exceeded: Option<f64>,
}

/// Fix every setting of a study of `system` (analysed as `analysis`).
///
/// The rigid body `I = (3, 2, 1)` about its major axis, noise `(3/10) e1`
/// (`Sigma^2 = 0.27`, `generator::closed_forms::rigid_body_sigma2`):
///
/// ```
/// use exact::{parse_expression, parse_number as q, Symbols};
/// let so3 = algebra::builtin("so3").unwrap().algebra;
/// let s = Symbols::new(so3.coordinates());
/// let h = parse_expression("Pi1^2/6 + Pi2^2/4 + Pi3^2/2", &s).unwrap();
/// let c = parse_expression("(Pi1^2 + Pi2^2 + Pi3^2)/2", &s).unwrap();
/// let mu_e = ["1", "0", "0"].map(|x| q(x).unwrap()).to_vec();
/// let noise = vec![["3/10", "0", "0"].map(|x| q(x).unwrap()).to_vec()];
/// let system = casimir::System::new(so3, h, vec![c], vec![], mu_e, noise).unwrap();
/// let analysis = generator::analyse(&system, &generator::Settings::default());
/// let settings = simulate::StudySettings { paths: 64, dt: 0.01, t_end: Some(1.0), outputs: 10, seed: 1, bins: 20,
///     scheme: simulate::Scheme::LieHeun, observable: None, epsilon: 0.1, delta: 1e-3 };
/// let prepared = simulate::prepare(&system, &analysis, &settings).unwrap();
/// // T(eps, delta) = ln(eps / delta) / Sigma^2 = ln(100) / 0.27
/// assert!((prepared.stopping_time.unwrap() - 100f64.ln() / 0.27).abs() < 1e-12);
/// let study = simulate::run(&prepared, &|_| {}).unwrap();
/// // At t = 0 the exact moment and the bound are |x0|_P^2 / delta = 1.
/// assert!((study.exact_over_delta.as_ref().unwrap()[0] - 1.0).abs() < 1e-12);
/// assert_eq!(study.bound_over_delta.as_ref().unwrap()[0], 1.0);
/// // The exact moments never exceed the certified bound.
/// let (exact, bound) = (study.exact_over_delta.unwrap(), study.bound_over_delta.unwrap());
/// assert!(exact.iter().zip(&bound).all(|(e, b)| *e <= b * (1.0 + 1e-9)));
/// ```
pub fn prepare<'a>(system: &'a System, analysis: &'a Analysis, s: &StudySettings) -> Result<Prepared<'a>, StudyError> {
    let (epsilon, delta) = (s.epsilon, s.delta);
    if !(delta.is_finite() && delta > 0.0 && epsilon.is_finite() && epsilon > delta) {
        return Err(StudyError::EpsilonDelta { delta, epsilon });
    }
    let n = system.dim();
    let mu_e: Vec<f64> = system.equilibrium().iter().map(exact::rational_to_f64).collect();
    let observable = match s.observable {
        Some(i) if i < n => i,
        Some(i) => return Err(StudyError::Observable(i)),
        None => mu_e.iter().position(|x| *x != 0.0).unwrap_or(0),
    };
    let stable = analysis.stable.as_ref();
    let sigma2 = stable.map(|st| st.sigma2());
    let stopping_time = sigma2.filter(|x| *x > 0.0).map(|x| (epsilon / delta).ln() / x);
    let t_end = s.t_end.unwrap_or_else(|| stopping_time.map_or(20.0, |t| (8.0 * t).clamp(1.0, 200.0)));
    // The norm P (sign-adjusted) and the perturbation: sqrt(delta) along the
    // fastest-growing direction for a stable system, else along the observable.
    let (p, direction) = match stable {
        Some(st) => (st.choice.p.to_dmatrix() * st.choice.sign.as_f64(), st.growth.direction.clone()),
        None => {
            let mut v = vec![0.0; n];
            v[observable] = 1.0;
            (DMatrix::identity(n, n), v)
        }
    };
    let x0: Vec<f64> = direction.iter().map(|v| v * delta.sqrt()).collect();
    let mu0: Vec<f64> = mu_e.iter().zip(&x0).map(|(m, x)| m + x).collect();
    let radius = mu0.iter().map(|x| x * x).sum::<f64>().sqrt().max(1.0); // before the pilot run
    let ensemble = EnsembleSettings {
        paths: s.paths,
        dt: s.dt,
        t_end,
        outputs: s.outputs,
        seed: s.seed,
        observable: Observable { index: observable, lo: -1.05 * radius, hi: 1.05 * radius, bins: s.bins },
        norm: Some((p.clone(), mu_e)),
        epsilon: Some(epsilon),
    };
    ensemble.validate(n)?;
    Ok(Prepared {
        analysis,
        model: Model::new(system),
        scheme: s.scheme,
        ensemble,
        p,
        x0,
        mu0,
        observable,
        sigma2,
        stopping_time,
        epsilon,
        delta,
    })
}

impl Prepared<'_> {
    /// Path-steps of the whole study (both ensembles when stable).
    pub fn path_steps(&self) -> f64 {
        self.ensemble.path_steps() * self.ensembles() as f64
    }

    /// How many ensembles run (the linearised one only when stable).
    pub fn ensembles(&self) -> u64 {
        if self.analysis.stable.is_some() {
            2
        } else {
            1
        }
    }

    /// Rough seconds on `cores` cores, from the benchmarks: closed-form
    /// exponentials (so3, se3) versus a matrix exponential per step.
    pub fn estimated_seconds(&self, cores: f64) -> f64 {
        let per_step = if self.model.closed_form_exponential() { 4e-8 } else { 3e-6 };
        self.path_steps() * per_step / cores.max(1.0)
    }
}

/// Run a prepared study; `tick(k)` reports `k` more finished paths.
pub fn run(prep: &Prepared<'_>, tick: &(dyn Fn(u64) + Sync)) -> Result<Study, StudyError> {
    run_cancellable(prep, tick, &AtomicBool::new(false))
}

/// [`run`] that stops soon after `cancel` is set, with
/// [`EnsembleError::Cancelled`] (the blocks of paths in flight finish).
pub fn run_cancellable(
    prep: &Prepared<'_>,
    tick: &(dyn Fn(u64) + Sync),
    cancel: &AtomicBool,
) -> Result<Study, StudyError> {
    let whole = run_shard_cancellable(prep, 0, 1, tick, cancel)?;
    Ok(finish(prep, &whole))
}

/// One shard of a study: the exact sums of its share of the paths of each
/// ensemble (see [`run_shard_cancellable`]).
#[derive(Clone, Debug, PartialEq)]
pub struct StudyShard {
    /// Which shard (`0..count`).
    pub index: u64,
    /// How many shards the study was split into.
    pub count: u64,
    /// The histogram range, from the pilot run (the same in every shard).
    pub histogram_range: (f64, f64),
    /// The nonlinear ensemble's sums over this shard's paths.
    pub nonlinear: EnsembleSums,
    /// The linearised ensemble's sums (stable systems).
    pub linear: Option<EnsembleSums>,
}

impl StudyShard {
    /// Add another shard's sums (exactly).
    pub fn merge(&mut self, other: &StudyShard) {
        self.nonlinear.merge(&other.nonlinear);
        if let (Some(a), Some(b)) = (self.linear.as_mut(), other.linear.as_ref()) {
            a.merge(b);
        }
    }
}

impl StudyShard {
    /// The shard as JSON (`index`, `count`, `histogram_range` and each
    /// ensemble's [`EnsembleSums::to_json`]): what `verify simulate --shard`
    /// writes, beside the identity of the study it belongs to.
    pub fn to_json(&self) -> Value {
        json!({
            "index": self.index,
            "count": self.count,
            "histogram_range": [self.histogram_range.0, self.histogram_range.1],
            "nonlinear": self.nonlinear.to_json(),
            "linearised": self.linear.as_ref().map(EnsembleSums::to_json),
        })
    }

    /// Read [`Self::to_json`] (found at JSON path `at`) as a shard of the
    /// study `prep`: the shapes, the path counts of the shard's blocks and
    /// the presence of the linearised ensemble are checked. An error names
    /// the JSON path and what is wrong.
    pub fn from_json(v: &Value, at: &str, prep: &Prepared<'_>) -> Result<StudyShard, String> {
        let count_of = |name: &str| -> Result<u64, String> {
            v.get(name).and_then(Value::as_u64).ok_or_else(|| format!("{at}.{name}: expected a count"))
        };
        let (index, count) = (count_of("index")?, count_of("count")?);
        if count == 0 || index >= count {
            return Err(format!("{at}.index: shard {index} of {count} does not exist"));
        }
        let range = v
            .get("histogram_range")
            .and_then(Value::as_array)
            .filter(|a| a.len() == 2)
            .and_then(|a| Some((a[0].as_f64()?, a[1].as_f64()?)))
            .filter(|(lo, hi)| lo.is_finite() && hi.is_finite() && lo < hi)
            .ok_or_else(|| format!("{at}.histogram_range: expected [lo, hi] with lo < hi"))?;
        let settings = main_settings(prep, range);
        let steps = settings.steps();
        let times = (steps / (steps / settings.outputs as u64).max(1)) as usize + 1;
        let (dim, bins) = (prep.x0.len(), settings.observable.bins);
        let paths = crate::ensemble::block_paths(settings.paths, &shard_blocks(settings.paths, index, count)).len();
        let read = |name: &str| -> Result<EnsembleSums, String> {
            let sums = EnsembleSums::from_json(
                v.get(name).ok_or_else(|| format!("{at}.{name}: missing"))?,
                &format!("{at}.{name}"),
                times,
                dim,
                bins,
            )?;
            if sums.paths != paths as u64 {
                return Err(format!(
                    "{at}.{name}.paths: shard {index} of {count} runs {paths} paths, the file says {}",
                    sums.paths
                ));
            }
            Ok(sums)
        };
        let nonlinear = read("nonlinear")?;
        let stable = prep.analysis.stable.is_some() && prep.analysis.linearisation.is_some();
        let linear = match (stable, v.get("linearised")) {
            (true, _) => Some(read("linearised")?),
            (false, None | Some(Value::Null)) => None,
            (false, Some(_)) => return Err(format!("{at}.linearised: present, but the system is not stable")),
        };
        Ok(StudyShard { index, count, histogram_range: range, nonlinear, linear })
    }
}

/// The ensembles' settings once the pilot run has fixed the histogram range.
fn main_settings(prep: &Prepared<'_>, range: (f64, f64)) -> EnsembleSettings {
    EnsembleSettings {
        observable: Observable { lo: range.0, hi: range.1, ..prep.ensemble.observable },
        ..prep.ensemble.clone()
    }
}

/// Run shard `index` of `count` of a prepared study: the pilot run (every
/// shard runs it whole, so all agree on the histogram range), then this
/// shard's blocks of paths ([`crate::shard_blocks`]) of the nonlinear and,
/// when stable, the linearised ensemble. The shards of a study,
/// [`StudyShard::merge`]d, give exactly the sums one run finds, so
/// [`finish`] gives the same study to the last bit whatever the split.
pub fn run_shard_cancellable(
    prep: &Prepared<'_>,
    index: u64,
    count: u64,
    tick: &(dyn Fn(u64) + Sync),
    cancel: &AtomicBool,
) -> Result<StudyShard, StudyError> {
    if count == 0 || index >= count {
        return Err(StudyError::Ensemble(EnsembleError::Invalid {
            field: "shard",
            message: format!("shard {index} of {count} does not exist"),
        }));
    }
    let target = Target::Nonlinear { model: &prep.model, scheme: prep.scheme, mu0: prep.mu0.clone() };
    // A pilot run (1% of the paths, at most 200) finds the range the
    // observable actually explores, for the histogram.
    let pilot = EnsembleSettings { paths: (prep.ensemble.paths / 100).clamp(1, 200), ..prep.ensemble.clone() };
    let extent = run_ensemble_cancellable(&target, &pilot, &|_| {}, cancel)?.observable_extent;
    if !(extent.0.is_finite() && extent.1.is_finite()) {
        return Err(StudyError::Escaped { index: prep.observable, extent });
    }
    let half = 0.5 * (extent.1 - extent.0).max(1e-9);
    let centre = 0.5 * (extent.0 + extent.1);
    let histogram_range = (centre - 1.2 * half, centre + 1.2 * half);
    let settings = main_settings(prep, histogram_range);
    let blocks = shard_blocks(settings.paths, index, count);
    let nonlinear = run_blocks_cancellable(&target, &settings, blocks.clone(), tick, cancel)?;
    let linear = match (prep.analysis.stable.as_ref(), &prep.analysis.linearisation) {
        (Some(_), Some(lin)) => {
            let lm = LinearModel::new(lin);
            let n = prep.x0.len();
            let s = EnsembleSettings { norm: Some((prep.p.clone(), vec![0.0; n])), ..settings.clone() };
            let target = Target::Linear { model: &lm, x0: prep.x0.clone() };
            Some(run_blocks_cancellable(&target, &s, blocks, tick, cancel)?)
        }
        _ => None,
    };
    Ok(StudyShard { index, count, histogram_range, nonlinear, linear })
}

/// The study from the sums of all its paths (one shard, or every shard of
/// a split merged): the ensembles' statistics, the exact second moments of
/// the linearised SDE, the worst start, the bound and the exceedance
/// levels.
pub fn finish(prep: &Prepared<'_>, sums: &StudyShard) -> Study {
    let settings = main_settings(prep, sums.histogram_range);
    let nonlinear = sums.nonlinear.finish(&settings);
    let stable = prep.analysis.stable.as_ref();
    let linear = sums.linear.as_ref().map(|l| l.finish(&settings));
    // Exact moments of the linearised SDE from x0, the worst case, the exponent.
    let moments = prep.analysis.linearisation.as_ref().map(SecondMoments::new);
    let times = &nonlinear.times;
    let when_stable = moments.as_ref().filter(|_| stable.is_some());
    let exact_over_delta =
        when_stable.map(|m| times.iter().map(|t| m.expected_norm(&prep.p, &prep.x0, *t) / prep.delta).collect());
    let worst_over_delta =
        when_stable.map(|m| times.iter().map(|t| m.worst_case_growth(&prep.p, *t).unwrap_or(f64::NAN)).collect());
    let lyapunov = moments.as_ref().and_then(|m| m.lyapunov_exponent());
    let bound_over_delta = prep.sigma2.map(|s| times.iter().map(|t| (s * t).exp()).collect());
    // Exceedance: certified guarantee P <= (delta/eps) e^{Sigma^2 t} <= alpha
    // for t <= ln(alpha eps / delta)/Sigma^2; empirical first time P > alpha.
    let exceedance = [0.01, 0.1, 0.5]
        .iter()
        .map(|&level| {
            let certified_until = prep.sigma2.map(|s| {
                let t = (level * prep.epsilon / prep.delta).ln();
                if t < 0.0 {
                    0.0
                } else if s > 0.0 {
                    t / s
                } else {
                    f64::INFINITY
                }
            });
            let empirical_first_exceeded =
                times.iter().zip(&nonlinear.exceedance).find(|(_, p)| **p > level).map(|(t, _)| *t);
            Exceedance { level, certified_until, empirical_first_exceeded }
        })
        .collect();
    Study {
        histogram_range: sums.histogram_range,
        nonlinear,
        linear,
        exact_over_delta,
        worst_over_delta,
        bound_over_delta,
        lyapunov,
        exceedance,
    }
}
