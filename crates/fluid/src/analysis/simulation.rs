//! One x-mode's discretised linear SDE with the functional the analysis
//! used, for `verify simulate` on a fluid spec: the Monte Carlo and the
//! exact second moment beside the certified growth.

use super::*;
use crate::barotropic::{BarotropicMode, WallGrid};
use crate::barotropic_sde::BarotropicSde;
use crate::simulate::{EnsembleRow, ModeSde, StrangRun, Ticks};
use nalgebra::{Complex, DMatrix, DVector};

type C = Complex<f64>;

enum Sde {
    Incompressible { sde: ModeSde, start: Vec<f64> },
    Compressible { sde: Box<BarotropicSde>, start: DVector<C> },
}

/// The linear SDE of x-mode `m` on the problem's grid (`problem.ny`), built
/// as [`analyse`] and [`prove_mode_bounds`] build its matrices (the same
/// choice of functional and form; for the compressible model the
/// generator's at the Galilean shift the analysis chose), started from the
/// direction whose `E V` grows fastest at `t = 0`.
///
/// That start is the top eigenvector of the discrete SDE's own generator
/// form: of `(Q, V)` in the incompressible model, where the pointwise noise
/// on the grid is the coadjoint action and `Q` is its generator form, so
/// the rate is the mode's `Sigma^2_k`; of `(Q_B, K)` in the compressible
/// model (`lambda_B`, [`crate::barotropic_sde`]), which exceeds the
/// certified `Sigma^2_k` by at most the discrete Casimir defect. Dense:
/// for moderate `ny`.
///
/// ```
/// use fluid::analysis::{analyse, mode_study, FluidModel, FluidProblem, FluidSettings};
/// use fluid::{expr::parse, grid::Boundary, profile::Profile};
/// let p = |s: &str| parse(s, &Default::default()).unwrap();
/// let profile = Profile::new(p("sin(y)"), vec![p("0.3*cos(y)")], (0.0, std::f64::consts::PI), Boundary::Walls);
/// let problem = FluidProblem { model: FluidModel::Incompressible, profile, x_period: 6.283185307179586, ny: 16, x_modes: 1 };
/// let analysis = analyse(&problem, &FluidSettings::default()).unwrap();
/// let study = mode_study(&problem, analysis.form.galilean_shift, 1).unwrap();
/// // the initial rate from the worst start is the certified per-mode Sigma^2 ...
/// let certified = analysis.modes[0].sigma2_upper.unwrap();
/// assert!(study.initial_rate() <= certified && study.initial_rate() > certified * (1.0 - 1e-6));
/// // ... and the exact second moment stays under exp(Sigma^2 t)
/// for (t, ratio) in study.exact_growth(1.0, 4) {
///     assert!(ratio <= (certified * t).exp());
/// }
/// ```
pub struct ModeStudy {
    k: f64,
    rate: f64,
    sde: Sde,
}

/// What a short run of [`ModeStudy::ensemble`]'s actual stepping took
/// ([`ModeStudy::time_ensemble`]): wall-clock seconds on this machine, its
/// threads and its present load, for a caller's estimate of a long run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnsembleTiming {
    /// Forming the drift propagator, once per run.
    pub setup_seconds: f64,
    /// Per path and step, the thread pool's threads all stepping.
    pub path_step_seconds: f64,
}

/// The wavenumber of mode `m` of `problem`, if it is one.
fn wavenumber(problem: &FluidProblem, m: usize) -> Option<f64> {
    wavenumbers(problem).into_iter().find(|(mm, _)| *mm == m).map(|(_, k)| k)
}

/// The study of x-mode `m` (see [`ModeStudy`]); `None` when the mode does
/// not exist, the profile admits no form, the compressible model has no
/// shift (`shift` is the analysis's `form.galilean_shift`) or no walls, or
/// the form is not numerically definite.
pub fn mode_study(problem: &FluidProblem, shift: Option<f64>, m: usize) -> Option<ModeStudy> {
    let k = wavenumber(problem, m)?;
    let profile = &problem.profile;
    let (a, b) = profile.interval;
    match problem.model {
        FluidModel::Incompressible => {
            let grid = YGrid::new(profile.boundary, a, b, problem.ny);
            let coef = profile.coefficients(&grid);
            let form = form_for(&choose(profile), profile, &coef, &grid)?;
            let mode = Mode::new(&grid, k);
            let (rate, start) = dense_top(&mode.generator_matrix(&form, &coef), &mode.form_matrix(&form))?;
            let sde = ModeSde::new(&grid, &coef, &form, k);
            Some(ModeStudy { k, rate, sde: Sde::Incompressible { sde, start } })
        }
        FluidModel::Compressible { sound_speed } => {
            if profile.boundary != Boundary::Walls {
                return None;
            }
            let c = shift?;
            let choice = choose(profile);
            let uniform = profile.u[1].sign_on(a, b, crate::choice::SIGN_PROOF_BUDGET) == SignProof::Zero;
            let grid = WallGrid::new(a, b, problem.ny);
            let coef = coefficients(profile, &choice, uniform, &grid, c);
            if !coef.usable() {
                return None;
            }
            let sde = BarotropicSde::new(&BarotropicMode::new(&grid, &coef, k, sound_speed, c))?;
            let (rate, start) = sde.pointwise_generator_rate();
            Some(ModeStudy { k, rate, sde: Sde::Compressible { sde: Box::new(sde), start } })
        }
    }
}

/// The top eigenpair of the pencil `(Q, V)`, `V ≻ 0` (dense Cholesky).
fn dense_top(q: &DMatrix<f64>, v: &DMatrix<f64>) -> Option<(f64, Vec<f64>)> {
    let linv = nalgebra::Cholesky::new(v.clone())?.l().try_inverse()?;
    let t = &linv * q * linv.transpose();
    let eig = nalgebra::SymmetricEigen::new((&t + t.transpose()) * 0.5);
    let top = eig.eigenvalues.imax();
    let x = linv.transpose() * eig.eigenvectors.column(top);
    x.iter().all(|v| v.is_finite()).then(|| (eig.eigenvalues[top], x.iter().copied().collect()))
}

impl ModeStudy {
    /// Its wavenumber.
    pub fn k(&self) -> f64 {
        self.k
    }

    /// Unknowns of the discrete SDE.
    pub fn unknowns(&self) -> usize {
        match &self.sde {
            Sde::Incompressible { start, .. } => start.len(),
            Sde::Compressible { sde, .. } => sde.n(),
        }
    }

    /// Noise fields.
    fn fields(&self) -> usize {
        match &self.sde {
            Sde::Incompressible { sde, .. } => sde.fields(),
            Sde::Compressible { sde, .. } => sde.fields(),
        }
    }

    /// `d E V / dt / V` at `t = 0` from the start: the largest eigenvalue of
    /// the discrete SDE's generator form (dense).
    pub fn initial_rate(&self) -> f64 {
        self.rate
    }

    /// `E V(t) / V(0)` from the start by the exact second moment, at
    /// `t = j t_end / samples`, `j = 1..=samples`.
    pub fn exact_growth(&self, t_end: f64, samples: usize) -> Vec<(f64, f64)> {
        // A fresh `Progress` is never cancelled.
        self.exact_growth_with(t_end, samples, &Progress::new()).unwrap_or_default()
    }

    /// [`Self::exact_growth`], counting [`Self::exact_growth_cost`] in
    /// `progress` as it goes (its [`Self::exact_growth_cost`]) and stopping
    /// with [`Cancelled`] soon after [`Progress::cancel`] (between two terms
    /// of a Taylor step).
    ///
    /// ```
    /// # use fluid::analysis::{analyse, mode_study, FluidModel, FluidProblem, FluidSettings, Progress};
    /// # use fluid::{expr::parse, grid::Boundary, profile::Profile};
    /// # let p = |s: &str| parse(s, &Default::default()).unwrap();
    /// # let profile = Profile::new(p("sin(y)"), vec![p("0.3*cos(y)")], (0.0, std::f64::consts::PI), Boundary::Walls);
    /// # let problem = FluidProblem { model: FluidModel::Incompressible, profile, x_period: 6.283185307179586, ny: 16, x_modes: 1 };
    /// # let analysis = analyse(&problem, &FluidSettings::default()).unwrap();
    /// let study = mode_study(&problem, analysis.form.galilean_shift, 1).unwrap();
    /// let progress = Progress::new();
    /// progress.plan(study.exact_growth_cost(1.0, 4).1);
    /// let growth = study.exact_growth_with(1.0, 4, &progress).unwrap();
    /// assert_eq!(growth, study.exact_growth(1.0, 4));
    /// let (done, total) = progress.snapshot();
    /// assert!(total > 0 && done == total);
    /// progress.cancel();
    /// assert!(study.exact_growth_with(1.0, 4, &progress).is_err());
    /// ```
    pub fn exact_growth_with(
        &self,
        t_end: f64,
        samples: usize,
        progress: &Progress,
    ) -> Result<Vec<(f64, f64)>, Cancelled> {
        Ok(match &self.sde {
            Sde::Incompressible { sde, start } => {
                let v0 = sde.energy(&complex(start));
                let ticks = Ticks { progress, weight: units(sde.taylor_step_flops()) };
                sde.exact_mean_energy_ticked(start, t_end, samples, ticks)?
                    .into_iter()
                    .map(|(t, e)| (t, e / v0))
                    .collect()
            }
            Sde::Compressible { sde, start } => {
                let v0 = sde.energy(start);
                let ticks = Ticks { progress, weight: units(sde.taylor_step_flops()) };
                sde.exact_moments_ticked(t_end, samples, ticks)?
                    .into_iter()
                    .map(|m| (m.t, start.dotc(&(&m.g * start)).re / v0))
                    .collect()
            }
        })
    }

    /// What [`Self::exact_growth`] costs: about how many floating-point
    /// operations ([`Self::exact_growth_flops`]), and the units of a
    /// [`Progress`] that [`Self::exact_growth_with`] counts (about a
    /// thousand flops each, as [`Self::ensemble_units`], so the two runs can
    /// share one total). Infinite flops and 0 units when the Taylor steps
    /// would be too many (it then computes nothing).
    pub fn exact_growth_cost(&self, t_end: f64, samples: usize) -> (f64, u64) {
        // (the step count once: for the compressible model it takes SVDs)
        let (steps, step_flops, per_sample) = match &self.sde {
            Sde::Incompressible { sde, .. } => (sde.exact_taylor_steps(t_end, samples), sde.taylor_step_flops(), 0.0),
            Sde::Compressible { sde, .. } => {
                (sde.exact_taylor_steps(t_end, samples), sde.taylor_step_flops(), sde.per_sample_flops())
            }
        };
        match steps {
            Some(0) => (0.0, 0),
            Some(steps) => (
                steps as f64 * step_flops + samples as f64 * per_sample,
                units(step_flops).saturating_mul(steps as u64),
            ),
            None => (f64::INFINITY, 0),
        }
    }

    /// Time a short run of [`Self::ensemble`] (`paths` paths of `steps`
    /// steps of `dt`, on the thread pool as a run takes them): see
    /// [`EnsembleTiming`]. Give at least twice the pool's threads in paths,
    /// or the pilot leaves threads idle that the run keeps busy. `None` if
    /// the drift's propagator could not be formed.
    ///
    /// ```
    /// # use fluid::analysis::{analyse, mode_study, FluidModel, FluidProblem, FluidSettings};
    /// # use fluid::{expr::parse, grid::Boundary, profile::Profile};
    /// # let p = |s: &str| parse(s, &Default::default()).unwrap();
    /// # let profile = Profile::new(p("sin(y)"), vec![p("0.3*cos(y)")], (0.0, std::f64::consts::PI), Boundary::Walls);
    /// # let problem = FluidProblem { model: FluidModel::Incompressible, profile, x_period: 6.283185307179586, ny: 16, x_modes: 1 };
    /// # let analysis = analyse(&problem, &FluidSettings::default()).unwrap();
    /// let study = mode_study(&problem, analysis.form.galilean_shift, 1).unwrap();
    /// let timing = study.time_ensemble(0.01, 50, 8, 1).unwrap();
    /// assert!(timing.path_step_seconds > 0.0 && timing.setup_seconds >= 0.0);
    /// ```
    pub fn time_ensemble(&self, dt: f64, steps: usize, paths: usize, seed: u64) -> Option<EnsembleTiming> {
        let run = StrangRun { dt, steps: steps.max(1), record_every: steps.max(1), paths: paths.max(1), seed };
        let (setup, stepping) = match &self.sde {
            Sde::Incompressible { sde, start } => sde.time_ensemble(start, &run)?,
            Sde::Compressible { sde, start } => sde.time_ensemble(start, &run),
        };
        let path_steps = (run.steps * run.paths) as f64;
        Some(EnsembleTiming { setup_seconds: setup, path_step_seconds: stepping / path_steps })
    }

    /// Wall-clock seconds of one Taylor step of [`Self::exact_growth`] for
    /// `(t_end, samples)` (every step of a run has the same length), on
    /// one thread as the run takes it; `None` when the run has no step or
    /// too many. A step costs about [`Self::exact_step_flops`]: at ny = 256
    /// in the compressible model, about a minute.
    pub fn time_exact_step(&self, t_end: f64, samples: usize) -> Option<f64> {
        match &self.sde {
            Sde::Incompressible { sde, start } => sde.time_taylor_step(start, t_end, samples),
            Sde::Compressible { sde, .. } => sde.time_taylor_step(t_end, samples),
        }
    }

    /// The floating-point operations [`Self::exact_growth_cost`] counts per
    /// Taylor step.
    pub fn exact_step_flops(&self) -> f64 {
        match &self.sde {
            Sde::Incompressible { sde, .. } => sde.taylor_step_flops(),
            Sde::Compressible { sde, .. } => sde.taylor_step_flops(),
        }
    }

    /// The units of a [`Progress`] that [`Self::ensemble_with`] counts.
    pub fn ensemble_units(&self, steps: usize, paths: usize) -> u64 {
        units(self.flops_per_path_step()).saturating_mul(steps as u64).saturating_mul(paths as u64)
    }

    /// About how many floating-point operations [`Self::exact_growth`] takes.
    pub fn exact_growth_flops(&self, t_end: f64, samples: usize) -> f64 {
        self.exact_growth_cost(t_end, samples).0
    }

    /// About how many floating-point operations [`Self::ensemble`] takes
    /// per path and step: two products with the dense half-step drift
    /// propagator (`8 n^2` flops each, complex), the compressible noise's
    /// node couplings (one more per field) and the energy at the records.
    pub fn flops_per_path_step(&self) -> f64 {
        let n2 = (self.unknowns() as f64).powi(2);
        let coupling = match self.sde {
            Sde::Incompressible { .. } => 0.0,
            Sde::Compressible { .. } => self.fields() as f64,
        };
        (2.0 + coupling) * 8.0 * n2
    }

    /// `E V(t) / V(0)` from the start by Monte Carlo (Strang splitting of
    /// the exact drift and noise flows), with its standard error, at every
    /// multiple of `record_every` of `steps` steps of `dt`. Deterministic
    /// in `seed` whatever the thread count. `None` if the drift's
    /// propagator could not be formed.
    pub fn ensemble(
        &self,
        dt: f64,
        steps: usize,
        record_every: usize,
        paths: usize,
        seed: u64,
    ) -> Option<Vec<EnsembleRow>> {
        // A fresh `Progress` is never cancelled.
        self.ensemble_with(dt, steps, record_every, paths, seed, &Progress::new()).ok().flatten()
    }

    /// [`Self::ensemble`], counting [`Self::ensemble_units`] in `progress`
    /// as the paths go and stopping with [`Cancelled`] soon after
    /// [`Progress::cancel`] (each path looks every 1e7 flops or so).
    pub fn ensemble_with(
        &self,
        dt: f64,
        steps: usize,
        record_every: usize,
        paths: usize,
        seed: u64,
        progress: &Progress,
    ) -> Result<Option<Vec<EnsembleRow>>, Cancelled> {
        let run = StrangRun { dt, steps, record_every, paths, seed };
        let ticks = Ticks { progress, weight: units(self.flops_per_path_step()) };
        let (rows, v0) = match &self.sde {
            Sde::Incompressible { sde, start } => {
                let Some(rows) = sde.ensemble_ticked(start, &run, ticks)? else { return Ok(None) };
                (rows, sde.energy(&complex(start)))
            }
            Sde::Compressible { sde, start } => (sde.ensemble_ticked(start, &run, ticks)?, sde.energy(start)),
        };
        Ok(Some(
            rows.into_iter().map(|r| EnsembleRow { mean: r.mean / v0, std_error: r.std_error / v0, ..r }).collect(),
        ))
    }
}

/// Flops in units of a thousand (at least one), the unit a [`ModeStudy`]
/// counts its progress in. (Products of these with counts saturate; a
/// caller planning their sum caps it, see `spec::simulate_fluid_with`.)
fn units(flops: f64) -> u64 {
    (flops / 1000.0).ceil().clamp(1.0, 1e15) as u64
}

fn complex(x: &[f64]) -> DVector<C> {
    DVector::from_iterator(x.len(), x.iter().map(|x| C::new(*x, 0.0)))
}
