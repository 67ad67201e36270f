//! `energy_casimir._core`: the engine's library API for Python.
//!
//! The Python package (`pysrc/energy_casimir`) wraps these functions; they
//! take and return JSON text so that the certificate a Python user gets is
//! byte for byte the one `verify certify` writes, and `check` runs the same
//! code as `verify check`. Every call releases the GIL while the engine
//! works (`Python::detach`), so threads certify in parallel.
//!
//! Errors are Python exceptions: `SpecError` (a `ValueError`) with `.path`
//! (the JSON path, e.g. `$.noise[0][1]`) and `.message`; `CheckError` (also a
//! `ValueError`) with `.path`, `.message` and `.kind` (`"failed"`: a claim
//! does not hold; `"bad_input"`: the certificate or its spec is not valid).

use outcome::Progress;
use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

// The same allocator as the `verify` binary, so that the engine runs at the
// same speed from Python (Python's own objects keep Python's allocator).
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

create_exception!(
    energy_casimir._core,
    SpecError,
    PyValueError,
    "A spec is not valid input: `.path` is the JSON path of the field, `.message` what is wrong."
);
create_exception!(
    energy_casimir._core,
    CheckError,
    PyValueError,
    "A certificate failed its check: `.path` names the field, `.message` what differs, `.kind` is \"failed\" or \"bad_input\"."
);

/// A Python exception of type `E` with attributes set on the instance.
fn error_with<E: pyo3::PyTypeInfo>(py: Python<'_>, text: String, attributes: &[(&str, &str)]) -> PyErr {
    let err = PyErr::new::<E, _>(text);
    let value = err.value(py);
    for (name, v) in attributes {
        // Setting an attribute on a fresh exception instance cannot fail;
        // if it ever did, the message still carries the path.
        let _ = value.setattr(*name, *v);
    }
    err
}

/// A `SpecError`; `has_base` says whether the caller gave a folder. A spec
/// given as a dict or JSON text has none, so a file it names (a Zeitlin
/// field's `.npy`) is read from the current folder; the message then says
/// how to name the folder from Python.
fn spec_error(py: Python<'_>, e: &spec::SpecError, has_base: bool) -> PyErr {
    let mut message = e.message.clone();
    if !has_base && names_a_file(&e.path) {
        message.push_str(BASE_DIR_HINT);
    }
    let text = format!("{}: {message}", e.path);
    error_with::<SpecError>(py, text, &[("path", &e.path), ("message", &message)])
}

/// What a file-reading error says when the spec came without a folder.
const BASE_DIR_HINT: &str = "; a spec given as a dict or JSON text has no folder of its own, so its files are read from the current folder: pass base_dir= the folder that holds them (e.g. certify(spec, base_dir=\"specs/\"); every function that takes a spec accepts base_dir=), or give the spec file's path";

/// Whether a JSON path is that of a field naming a file (a `.npy`).
fn names_a_file(path: &str) -> bool {
    path.ends_with(".npy")
}

fn check_error(py: Python<'_>, e: &spec::CheckError, has_base: bool) -> PyErr {
    match e {
        spec::CheckError::BadInput(s) if !has_base && names_a_file(&s.path) => {
            let message = format!("{}{BASE_DIR_HINT}", s.message);
            error_with::<CheckError>(
                py,
                format!("{}: {message}", s.path),
                &[("path", &s.path), ("message", &message), ("kind", "bad_input")],
            )
        }
        spec::CheckError::BadInput(s) => error_with::<CheckError>(
            py,
            e.to_string(),
            &[("path", &s.path), ("message", &s.message), ("kind", "bad_input")],
        ),
        spec::CheckError::Failed { path, message } => {
            error_with::<CheckError>(py, e.to_string(), &[("path", path), ("message", message), ("kind", "failed")])
        }
        // Only after an interrupt, which is raised instead.
        spec::CheckError::Cancelled => pyo3::exceptions::PyKeyboardInterrupt::new_err(e.to_string()),
        // `CheckError` is non-exhaustive: a future kind keeps its message.
        other => error_with::<CheckError>(
            py,
            other.to_string(),
            &[("path", "$"), ("message", &other.to_string()), ("kind", "failed")],
        ),
    }
}

/// Certify a spec given as JSON text; files it names (a Zeitlin field's
/// `.npy`) are relative to `base` (the current folder when `None`). Returns
/// the certificate as pretty JSON text, as `verify certify` writes it.
/// Fluid, Zeitlin and large specs run on a worker thread: Ctrl-C stops them
/// (the engine stops at its next step and the `KeyboardInterrupt` is
/// raised), and `progress(done, total)` is called from the calling thread
/// as the steps go by.
#[pyfunction]
#[pyo3(signature = (text, base=None, progress=None))]
fn certify_text(
    py: Python<'_>,
    text: String,
    base: Option<PathBuf>,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<String> {
    let has_base = base.is_some();
    let spec = py
        .detach(move || spec::parse(&text, &spec::Options::relative_to(base.as_deref())))
        .map_err(|e| spec_error(py, &e, has_base))?;
    let state = Progress::new();
    if matches!(spec, spec::AnySpec::Lie(_)) && progress.is_none() {
        // Finite-dimensional systems certify in micro- to milliseconds:
        // on this thread, without the cost of another.
        let cert = py.detach(|| spec::certify(&spec, &spec::Options::default()));
        return cert.map(|c| c.to_pretty_json()).map_err(certify_error);
    }
    let out = interruptible(py, progress.as_ref(), &state, || {
        spec::certify(&spec, &spec::Options::default().with_progress(&state)).map(|c| c.to_pretty_json())
    })?;
    // `Err(Cancelled)` only follows an interrupt, which `interruptible`
    // has raised already.
    out.map_err(certify_error)
}

/// A certificate that was not made: cancelled (an interrupt), or the
/// engine's own bug (an internal error, never a certificate).
fn certify_error(e: spec::CertifyError) -> PyErr {
    match e {
        spec::CertifyError::Cancelled => pyo3::exceptions::PyKeyboardInterrupt::new_err(e.to_string()),
        _ => pyo3::exceptions::PyRuntimeError::new_err(e.to_string()),
    }
}

/// Check a certificate given as JSON text (files its spec names are relative
/// to `base`). Returns `(name, verdict, level, sigma2)`; `level` and
/// `sigma2` may be `None`. The re-derivation runs on a worker thread, so
/// Ctrl-C stops a long one and `progress(done, total)` follows it.
#[pyfunction]
#[pyo3(signature = (text, base=None, progress=None))]
fn check_text(
    py: Python<'_>,
    text: String,
    base: Option<PathBuf>,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<(String, String, Option<String>, Option<f64>)> {
    let state = Progress::new();
    let out = interruptible(py, progress.as_ref(), &state, || {
        spec::check_json(&text, &spec::Options::relative_to(base.as_deref()).with_progress(&state))
    })?;
    match out {
        Ok(r) => Ok((r.name, r.verdict.as_str().to_string(), r.level.map(|l| l.as_str().to_string()), r.sigma2)),
        Err(e) => Err(check_error(py, &e, base.is_some())),
    }
}

/// Parse a spec (JSON text) without certifying it: `None` if it is valid,
/// else a `SpecError`.
#[pyfunction]
#[pyo3(signature = (text, base=None))]
fn validate_text(py: Python<'_>, text: String, base: Option<PathBuf>) -> PyResult<()> {
    let has_base = base.is_some();
    let out = py.detach(move || spec::parse(&text, &spec::Options::relative_to(base.as_deref())).map(|_| ()));
    out.map_err(|e| spec_error(py, &e, has_base))
}

/// `T(eps, delta) = ln(eps/delta) / Sigma^2`, rounded down (a guarantee), or
/// `None` when `Sigma^2 = 0` (no finite stopping time). The engine's own
/// `generator::StoppingTime`.
#[pyfunction]
fn stopping_time(epsilon: f64, delta: f64, sigma2: f64) -> Option<f64> {
    generator::StoppingTime::new(epsilon, delta, sigma2).time()
}

/// Run `verify simulate`'s study of a finite-dimensional spec (JSON text):
/// the nonlinear and the linearised ensembles, the exact second moments, the
/// worst start and the bound. Returns the study's report as JSON text (the
/// file `verify simulate` writes). Refuses, like the CLI, a study estimated
/// at more than 15 minutes unless `force`. Ctrl-C stops it;
/// `progress(done, total)` counts paths, from the calling thread.
///
/// `shard=(k, n)` runs only shard `k` of `n` and returns its shard file
/// (`verify simulate --shard k/n`'s JSON); `merge=[(label, json_text), ...]`
/// runs nothing and merges shard files into the report an unsharded run
/// gives (`--merge`).
// One argument per Python keyword argument.
#[allow(clippy::too_many_arguments)]
#[pyfunction]
#[pyo3(signature = (text, base=None, paths=10_000, dt=0.01, t_end=None, outputs=200, seed=1, bins=80, scheme="lie", observable=None, epsilon=None, delta=None, force=false, progress=None, shard=None, merge=None))]
fn simulate_text(
    py: Python<'_>,
    text: String,
    base: Option<PathBuf>,
    paths: usize,
    dt: f64,
    t_end: Option<f64>,
    outputs: usize,
    seed: u64,
    bins: usize,
    scheme: &str,
    observable: Option<String>,
    epsilon: Option<f64>,
    delta: Option<f64>,
    force: bool,
    progress: Option<Bound<'_, PyAny>>,
    shard: Option<(u64, u64)>,
    merge: Option<Vec<(String, String)>>,
) -> PyResult<String> {
    if let Some((k, n)) = shard {
        if n == 0 || k >= n {
            return Err(PyValueError::new_err(format!("shard: ({k}, {n}) is not a shard: need 0 <= k < n")));
        }
        if merge.is_some() {
            return Err(PyValueError::new_err("shard/merge: a run is either a shard or a merge"));
        }
    }
    let scheme = simulate::Scheme::from_name(scheme)
        .ok_or_else(|| PyValueError::new_err(format!("scheme: {scheme:?} is not 'lie' or 'heun'")))?;
    let spec =
        match spec::parse(&text, &spec::Options::relative_to(base.as_deref()))
            .map_err(|e| spec_error(py, &e, base.is_some()))?
        {
            spec::AnySpec::Lie(s) => s,
            spec::AnySpec::Fluid(_) => {
                return Err(PyValueError::new_err(
                    "simulate runs finite-dimensional specs; a fluid spec's x-mode is simulated by simulate_fluid",
                ))
            }
            _ => return Err(PyValueError::new_err(
                "simulate runs finite-dimensional specs (Zeitlin and large specs are certified, not simulated here)",
            )),
        };
    let cert = py.detach(|| spec::certify_lie(&spec));
    let coords = spec.system.algebra().coordinates();
    let observable = match &observable {
        Some(name) => Some(coords.iter().position(|c| c == name).ok_or_else(|| {
            PyValueError::new_err(format!(
                "observable: unknown coordinate {name:?} (coordinates: {})",
                coords.join(", ")
            ))
        })?),
        None => None,
    };
    let settings = simulate::StudySettings {
        paths,
        dt,
        t_end,
        outputs,
        seed,
        bins,
        scheme,
        observable,
        epsilon: epsilon.or(spec.stopping.map(|s| s.epsilon)).unwrap_or(0.1),
        delta: delta.or(spec.stopping.map(|s| s.delta)).unwrap_or(1e-3),
    };
    let prepared =
        simulate::prepare(&spec.system, &cert.analysis, &settings).map_err(|e| PyValueError::new_err(e.to_string()))?;
    // The engine's threads (rayon: RAYON_NUM_THREADS or every core), counted
    // only up to the cores that work, as `verify simulate` does.
    let threads = rayon::current_num_threads();
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get);
    // A shard runs its share of the paths (and the whole pilot); a merge runs none.
    let share = shard.map_or(1.0, |(_, n)| 1.0 / n as f64);
    let estimate = if merge.is_some() { 0.0 } else { prepared.estimated_seconds(threads.min(cores) as f64) * share };
    if estimate > 900.0 && !force {
        return Err(PyValueError::new_err(format!(
            "paths/dt/t_end: {:.2e} path-steps would take about {:.0} minutes here; lower them, split the run (shard=(k, n)) or pass force=True",
            prepared.ensemble.path_steps() * share,
            estimate / 60.0
        )));
    }
    let identity = simulate::study_identity(&spec::spec_digest(&spec.raw), &spec.name, &settings, &prepared, coords);
    let sums = match &merge {
        Some(files) => {
            let mut documents = Vec::with_capacity(files.len());
            for (label, text) in files {
                let v: serde_json::Value = serde_json::from_str(text).map_err(|e| {
                    PyValueError::new_err(format!("{label}: not JSON ({e}); was the shard interrupted?"))
                })?;
                documents.push((label.clone(), v));
            }
            simulate::merge_shard_documents(&documents, &identity, &prepared)
                .map_err(|e| PyValueError::new_err(format!("merge: {e}")))?
        }
        None => {
            let (k, n) = shard.unwrap_or((0, 1));
            let shard_paths = simulate::block_paths(paths, &simulate::shard_blocks(paths, k, n)).len();
            let state = Progress::new();
            state.plan(shard_paths as u64 * prepared.ensembles());
            let sums = interruptible(py, progress.as_ref(), &state, || {
                simulate::run_shard_cancellable(&prepared, k, n, &|c: u64| state.step(c), state.cancel_flag())
            })?
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
            if shard.is_some() {
                return Ok(spec::to_pretty_json(&simulate::shard_document(&identity, &sums)));
            }
            sums
        }
    };
    let study = simulate::finish(&prepared, &sums);
    let verdict = cert.json["verdict"].as_str().unwrap_or_default();
    let report = simulate::study_report(&spec.name, verdict, &prepared, &settings, &study, coords, threads as u64);
    Ok(report.to_string())
}

/// One x-mode of a fluid spec simulated beside its certified growth
/// (`spec::simulate_fluid`, as `verify simulate` runs it): the report as
/// JSON text. Notes (a skipped exact moment, values beyond the doubles) are
/// in the report's `notes`. The run is on a worker thread: Ctrl-C stops it
/// and `progress(done, total)` follows it (planned once, when the Monte
/// Carlo and the exact moment start; `(0, 0)` during the analysis on the
/// grid).
#[allow(clippy::too_many_arguments)]
#[pyfunction]
#[pyo3(signature = (text, base=None, mode=None, ny=None, paths=None, dt=0.01, t_end=None, outputs=200, seed=1, force=false, progress=None))]
fn simulate_fluid_text(
    py: Python<'_>,
    text: String,
    base: Option<PathBuf>,
    mode: Option<usize>,
    ny: Option<usize>,
    paths: Option<usize>,
    dt: f64,
    t_end: Option<f64>,
    outputs: usize,
    seed: u64,
    force: bool,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<String> {
    let spec = match spec::parse(&text, &spec::Options::relative_to(base.as_deref()))
        .map_err(|e| spec_error(py, &e, base.is_some()))?
    {
        spec::AnySpec::Fluid(s) => s,
        _ => return Err(PyValueError::new_err("simulate_fluid runs fluid specs; use simulate for the others")),
    };
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get);
    let options = spec::FluidSimulationOptions {
        mode,
        ny,
        paths,
        dt,
        t_end,
        outputs,
        seed,
        force,
        threads: rayon::current_num_threads().min(cores) as f64,
    };
    let mut notes = vec![];
    let state = Progress::new();
    let run = interruptible(py, progress.as_ref(), &state, || {
        spec::simulate_fluid_with(&spec, &options, &state, &mut |n: String| notes.push(n))
    })?;
    // (`Cancelled` only follows an interrupt, which `interruptible` has raised)
    let run = run.map_err(|e| match e {
        spec::FluidSimulationError::TooLong { .. } => {
            PyValueError::new_err(format!("{e}; lower them or ny, or pass force=True"))
        }
        e => PyValueError::new_err(e.to_string()),
    })?;
    let mut report = run.report;
    report["notes"] = notes.into();
    Ok(report.to_string())
}

/// One block (azimuthal wavenumber `m`) of a Zeitlin spec's linearised SDE
/// simulated beside the certificate's bound (`spec::simulate_zeitlin`, as
/// `verify simulate` runs it): the report as JSON text, with `notes`.
#[allow(clippy::too_many_arguments)]
#[pyfunction]
#[pyo3(signature = (text, base=None, block=None, paths=None, dt=0.01, t_end=None, outputs=200, seed=1, force=false, progress=None, delta=None))]
fn simulate_zeitlin_text(
    py: Python<'_>,
    text: String,
    base: Option<PathBuf>,
    block: Option<usize>,
    paths: Option<usize>,
    dt: f64,
    t_end: Option<f64>,
    outputs: usize,
    seed: u64,
    force: bool,
    progress: Option<Bound<'_, PyAny>>,
    delta: Option<f64>,
) -> PyResult<String> {
    let spec = match spec::parse(&text, &spec::Options::relative_to(base.as_deref()))
        .map_err(|e| spec_error(py, &e, base.is_some()))?
    {
        spec::AnySpec::Zeitlin(s) => s,
        _ => {
            return Err(PyValueError::new_err(
                "simulate_zeitlin runs Zeitlin specs; use simulate or simulate_fluid for the others",
            ))
        }
    };
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get);
    let options = spec::ZeitlinSimulationOptions {
        block,
        paths,
        dt,
        t_end,
        outputs,
        seed,
        force,
        threads: rayon::current_num_threads().min(cores) as f64,
        delta,
    };
    let mut notes = vec![];
    let state = Progress::new();
    let run = interruptible(py, progress.as_ref(), &state, || {
        spec::simulate_zeitlin(&spec, &options, &state, &mut |n: String| notes.push(n))
    })?;
    let mut report = run.map_err(|e| match e {
        spec::ZeitlinSimulationError::TooLong { .. } => {
            PyValueError::new_err(format!("{e}; lower them, or pass force=True"))
        }
        e => PyValueError::new_err(e.to_string()),
    })?;
    report["notes"] = notes.into();
    Ok(report.to_string())
}

/// A Zeitlin spec's fields as quflow's `omega` vectors
/// (`spec::zeitlin_fields`): JSON text `{"N", "state", "noise", "mode"}`.
#[pyfunction]
#[pyo3(signature = (text, base=None))]
fn zeitlin_fields_text(py: Python<'_>, text: String, base: Option<PathBuf>) -> PyResult<String> {
    let spec = match spec::parse(&text, &spec::Options::relative_to(base.as_deref()))
        .map_err(|e| spec_error(py, &e, base.is_some()))?
    {
        spec::AnySpec::Zeitlin(s) => s,
        _ => return Err(PyValueError::new_err("zeitlin_fields takes Zeitlin specs")),
    };
    let fields = py.detach(|| spec::zeitlin_fields(&spec)).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let mode = fields.mode.map(|m| {
        serde_json::json!({
            "kind": m.kind, "block": m.block, "rate": m.rate, "frequency": m.frequency,
            "real": m.real, "imaginary": m.imaginary,
        })
    });
    Ok(serde_json::json!({"N": fields.n, "state": fields.state, "noise": fields.noise, "mode": mode}).to_string())
}

/// Run `work` on a worker thread while this (the calling, usually the main)
/// thread, without the GIL, wakes every 100 ms to honour Ctrl-C
/// (`check_signals`, which only the main thread can) and to call
/// `progress(done, total)` with `state`'s counts when they moved. On an
/// interrupt (or an exception from `progress`) `state` is cancelled; `work`
/// then stops at its next step, and the exception is raised once it has
/// (the worker is joined: no work is left running).
fn interruptible<R: Send>(
    py: Python<'_>,
    progress: Option<&Bound<'_, PyAny>>,
    state: &Progress,
    work: impl FnOnce() -> R + Send,
) -> PyResult<R> {
    let mut interrupt: Option<PyErr> = None;
    let mut reported = (u64::MAX, u64::MAX);
    // Set (and the watcher woken) when `work` returns or unwinds.
    let finished = (std::sync::Mutex::new(false), std::sync::Condvar::new());
    struct Finished<'a>(&'a (std::sync::Mutex<bool>, std::sync::Condvar));
    impl Drop for Finished<'_> {
        fn drop(&mut self) {
            *self.0 .0.lock().unwrap_or_else(|p| p.into_inner()) = true;
            self.0 .1.notify_all();
        }
    }
    let joined = std::thread::scope(|scope| {
        let worker = std::thread::Builder::new()
            .name("energy-casimir".into())
            // The main thread's usual 8 MiB, not a spawned thread's 2 MiB:
            // parsing a deeply nested expression recurses.
            .stack_size(8 << 20)
            .spawn_scoped(scope, || {
                let _finished = Finished(&finished);
                work()
            });
        let worker = match worker {
            Ok(w) => w,
            Err(e) => return Err(e),
        };
        loop {
            let over = py.detach(|| {
                let (lock, wake) = &finished;
                let guard = lock.lock().unwrap_or_else(|p| p.into_inner());
                let (guard, _) = wake
                    .wait_timeout_while(guard, Duration::from_millis(100), |over| !*over)
                    .unwrap_or_else(|p| p.into_inner());
                *guard
            });
            if over {
                break;
            }
            if interrupt.is_none() {
                if let Err(e) = py.check_signals() {
                    state.cancel();
                    interrupt = Some(e);
                }
            }
            let now = state.snapshot();
            if let (Some(cb), None) = (progress, &interrupt) {
                if now != reported {
                    reported = now;
                    if let Err(e) = cb.call1(now) {
                        state.cancel();
                        interrupt = Some(e);
                    }
                }
            }
        }
        Ok(py.detach(|| worker.join()))
    });
    let joined =
        joined.map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(format!("cannot start a thread: {e}")))?;
    let result = joined.map_err(|payload| {
        let text = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown".into());
        pyo3::panic::PanicException::new_err(format!("the engine panicked (a bug: please report it): {text}"))
    })?;
    if let Some(e) = interrupt {
        return Err(e);
    }
    let now = state.snapshot();
    if let (Some(cb), true) = (progress, now != reported) {
        cb.call1(now)?;
    }
    Ok(result)
}

/// A sink for sweep lines that refuses to take more once `cancel` is set,
/// which stops the sweep after the chunks in flight.
struct CancellableSink<'a> {
    lines: Vec<u8>,
    cancel: &'a AtomicBool,
}

impl std::io::Write for CancellableSink<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.cancel.load(Ordering::Acquire) {
            // Not `ErrorKind::Interrupted`: `write_all` retries those forever.
            return Err(std::io::Error::other("stopped: interrupted or the progress callback raised"));
        }
        self.lines.extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// The columns of a sweep, in index order: `index`, each parameter's
/// values (in the order of the names), `verdict`, `level`, `sigma2` (NaN
/// where absent), `T` (NaN where absent, inf for `"infinity"`), `error`,
/// and the JSON lines themselves.
type SweepColumns = (
    Vec<u64>,
    Vec<Vec<f64>>,
    Vec<Option<String>>,
    Vec<Option<String>>,
    Vec<f64>,
    Vec<f64>,
    Vec<Option<String>>,
    Vec<String>,
);

/// The fields of a sweep line that the columns take (serde skips the rest).
#[derive(serde::Deserialize)]
struct SweepLine {
    index: u64,
    #[serde(default)]
    parameters: std::collections::HashMap<String, serde_json::Value>,
    verdict: Option<String>,
    level: Option<String>,
    sigma2: Option<serde_json::Value>,
    #[serde(rename = "T")]
    t: Option<serde_json::Value>,
    error: Option<String>,
}

/// Read the sweep's JSON lines into columns, in parallel and in Rust
/// (parsing 10^4 lines in Python cost more than the numeric sweep itself).
fn sweep_columns(text: &str, names: &[String]) -> PyResult<SweepColumns> {
    use rayon::prelude::*;
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    let mut rows: Vec<(SweepLine, &str)> = lines
        .par_iter()
        .map(|l| serde_json::from_str::<SweepLine>(l).map(|r| (r, *l)))
        .collect::<Result<_, _>>()
        .map_err(|e| PyValueError::new_err(format!("the sweep wrote a line that is not a sweep record: {e}")))?;
    rows.sort_by_key(|r| r.0.index);
    let number = |v: Option<&serde_json::Value>| -> f64 {
        match v {
            Some(serde_json::Value::String(s)) if s == "infinity" => f64::INFINITY,
            Some(x) => x.as_f64().unwrap_or(f64::NAN),
            None => f64::NAN,
        }
    };
    let params = names.iter().map(|n| rows.iter().map(|(r, _)| number(r.parameters.get(n))).collect()).collect();
    Ok((
        rows.iter().map(|(r, _)| r.index).collect(),
        params,
        rows.iter().map(|(r, _)| r.verdict.clone()).collect(),
        rows.iter().map(|(r, _)| r.level.clone()).collect(),
        rows.iter().map(|(r, _)| number(r.sigma2.as_ref())).collect(),
        rows.iter().map(|(r, _)| number(r.t.as_ref())).collect(),
        rows.iter().map(|(r, _)| r.error.clone()).collect(),
        rows.iter().map(|(_, l)| l.to_string()).collect(),
    ))
}

/// Certify a spec (JSON text) over a grid or random points of its
/// parameters (`params`: `NAME=START:STOP:COUNT` each; empty: the spec's
/// own `sweep` ranges), in parallel. Returns the swept parameters' names and
/// the sweep's columns in index order ([`SweepColumns`]: the last are the
/// JSON lines of `verify sweep`). Ctrl-C stops it; `progress(done, total)`
/// is called from the calling thread.
#[allow(clippy::too_many_arguments)]
#[pyfunction]
#[pyo3(signature = (text, base=None, params=vec![], random=None, seed=0, numeric=false, shard=None, progress=None))]
fn sweep_text(
    py: Python<'_>,
    text: String,
    base: Option<PathBuf>,
    params: Vec<String>,
    random: Option<u64>,
    seed: u64,
    numeric: bool,
    shard: Option<String>,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<(Vec<String>, SweepColumns)> {
    let spec = spec::parse(&text, &spec::Options::relative_to(base.as_deref()))
        .map_err(|e| spec_error(py, &e, base.is_some()))?;
    let ranges: Vec<spec::ParamRange> = if params.is_empty() {
        spec.sweep().ranges.clone()
    } else {
        params
            .iter()
            .map(|p| spec::ParamRange::parse(p).map_err(|e| PyValueError::new_err(format!("params: {}", e.0))))
            .collect::<PyResult<_>>()?
    };
    let names: Vec<String> = ranges.iter().map(|r| r.name.clone()).collect();
    let sampling = match random {
        Some(points) => sweep::Sampling::Random { points, seed },
        None => sweep::Sampling::Grid,
    };
    let plan = sweep::Plan::new(ranges, sampling).map_err(|e| PyValueError::new_err(format!("params: {e}")))?;
    let level = if numeric { sweep::Level::Numeric } else { sweep::Level::Spec };
    let id = sweep::sweep_id(&spec, &plan, level);
    let evaluator =
        sweep::Evaluator::new(spec, names.clone(), level).map_err(|e| PyValueError::new_err(format!("params: {e}")))?;
    let shard = match &shard {
        Some(s) => sweep::Shard::parse(s).map_err(|e| PyValueError::new_err(format!("shard {s:?}: {e}")))?,
        None => sweep::Shard::ALL,
    };
    let state = Progress::new();
    state.plan(plan.len());
    let out = interruptible(py, progress.as_ref(), &state, || {
        let mut sink = CancellableSink { lines: vec![], cancel: state.cancel_flag() };
        sweep::run(&evaluator, &plan, &id, shard, &sweep::Done::none(), &mut sink, &|n: u64| state.step(n))
            .map(|_| sink.lines)
    })?;
    let lines = out.map_err(|e| PyValueError::new_err(format!("the sweep stopped: {e}")))?;
    let text = String::from_utf8(lines).map_err(|_| PyValueError::new_err("the sweep wrote text that is not UTF-8"))?;
    let columns = py.detach(|| sweep_columns(&text, &names))?;
    Ok((names, columns))
}

/// The engine's version, as certificates record it.
#[pyfunction]
fn engine_version() -> &'static str {
    spec::ENGINE_VERSION
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("SpecError", m.py().get_type::<SpecError>())?;
    m.add("CheckError", m.py().get_type::<CheckError>())?;
    m.add_function(wrap_pyfunction!(certify_text, m)?)?;
    m.add_function(wrap_pyfunction!(check_text, m)?)?;
    m.add_function(wrap_pyfunction!(validate_text, m)?)?;
    m.add_function(wrap_pyfunction!(stopping_time, m)?)?;
    m.add_function(wrap_pyfunction!(simulate_text, m)?)?;
    m.add_function(wrap_pyfunction!(simulate_fluid_text, m)?)?;
    m.add_function(wrap_pyfunction!(simulate_zeitlin_text, m)?)?;
    m.add_function(wrap_pyfunction!(zeitlin_fields_text, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_text, m)?)?;
    m.add_function(wrap_pyfunction!(engine_version, m)?)?;
    Ok(())
}
