//! A no-panic, bounded-cost and forgery fuzz run of the engine.
//!
//! ```text
//! cargo run --release -p verify --example fuzz_edges -- [--specs N] [--certs M] [--seed S]
//!     [--time-limit SECS] [--memory-limit MB] [--merges K]
//! ```
//!
//! * **Specs** (default 100,000): mutations of every fixture spec (a random
//!   leaf replaced by a hostile value: numbers at `1e308`, `1e-308`, `5e-324`,
//!   thousand-digit literals, `nan`, names holding `../`, expressions nested
//!   250 deep, products of 500 factors, huge powers, duplicated keys), random
//!   finite-dimensional systems on the builtin algebras with coefficients at
//!   scales `10^-200 .. 10^200`, and random shear flows with noise at
//!   scales `10^-300 .. 10^300`. Each goes through `parse_any_spec`; a spec
//!   that parses is certified, and its certificate must pass `check`.
//! * **Certificates** (default 10,000): certificates of fixtures and of
//!   random valid specs, each altered once (a number scaled by `1 + d` with
//!   `|d|` from `1e-3` down to `1e-13`, set to 0 or negated; the verdict,
//!   the level or a flag changed; a field dropped, added or duplicated; the
//!   embedded spec edited with its digest recomputed). `check` must reject
//!   every alteration that states a false number: a change above the
//!   loosest documented tolerance (`1e-9` relative to the number's array) is
//!   counted as an accepted forgery; smaller ones, and fluid bounds that the
//!   checker proves at the altered value, are counted apart.
//!
//! * **Boxes** (part of both): rigid bodies over a box of `I2` whose
//!   equilibrium or noise depends on `I2` and vanishes inside, at the edge
//!   of, or outside the box. A whole-box verdict that `check` confirms must
//!   be the pipeline's verdict at the spec's own point.
//! * **Merged sweeps** (`--merges K`, default 300): the three shards of a
//!   small sweep, each case altering one (a result, a point, the id, a key
//!   added, a byte-order mark, CRLF, a cut or garbage line, a missing line,
//!   two results for one point) and merging them with the `verify` binary
//!   beside this example, half the time with `--recheck`. An edited result
//!   may merge only without `--recheck` and with the summary saying the
//!   results are data; anything else merged is a forgery.
//!
//! Every case runs under `catch_unwind` on a pool of worker threads; a case
//! over the time limit, or a process peak memory (VmHWM) above the memory
//! limit, is counted; a case running ten times over the time limit aborts the
//! run naming it. The run prints a table and exits with status 1 if any count
//! that must be zero is not.

use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use serde_json::{json, Value};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

#[derive(Default)]
struct Counts {
    specs: AtomicU64,
    spec_ok: AtomicU64,
    spec_bad_input: AtomicU64,
    spec_panics: AtomicU64,
    own_check_rejected: AtomicU64,
    over_time: AtomicU64,
    certs: AtomicU64,
    cert_rejected: AtomicU64,
    cert_bad_input: AtomicU64,
    cert_panics: AtomicU64,
    forgeries_accepted: AtomicU64,
    accepted_within_tolerance: AtomicU64,
    accepted_proved: AtomicU64,
    unchanged: AtomicU64,
    /// Box specs whose whole-box verdict (as `check` reports it under the
    /// spec's name) is not the pipeline's verdict at the spec's own point.
    box_point_disagrees: AtomicU64,
    /// Box specs certified (with a parameter-dependent residual, of them).
    box_specs: AtomicU64,
    box_residual_specs: AtomicU64,
    /// Slowest case, in microseconds.
    slowest_us: AtomicU64,
}

fn bump(c: &AtomicU64) {
    c.fetch_add(1, Ordering::Relaxed);
}

struct Options {
    specs: u64,
    certs: u64,
    seed: u64,
    time_limit: f64,
    memory_limit_mb: f64,
    merges: u64,
}

fn options() -> Options {
    let mut o =
        Options { specs: 100_000, certs: 10_000, seed: 1, time_limit: 60.0, memory_limit_mb: 4096.0, merges: 300 };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut i = 0;
    while i + 1 < args.len() {
        let v = &args[i + 1];
        match args[i].as_str() {
            "--specs" => o.specs = v.parse().expect("--specs N"),
            "--certs" => o.certs = v.parse().expect("--certs M"),
            "--seed" => o.seed = v.parse().expect("--seed S"),
            "--time-limit" => o.time_limit = v.parse().expect("--time-limit SECS"),
            "--memory-limit" => o.memory_limit_mb = v.parse().expect("--memory-limit MB"),
            "--merges" => o.merges = v.parse().expect("--merges K"),
            other => panic!("unknown option {other}"),
        }
        i += 2;
    }
    o
}

fn fixtures_dir() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../fixtures"))
}

fn files(dir: &std::path::Path, cert: bool, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut entries: Vec<_> = entries.flatten().map(|e| e.path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            files(&p, cert, out);
        } else if let Some(n) = p.file_name().and_then(|n| n.to_str()) {
            if n.ends_with(".json") && n.ends_with(".cert.json") == cert {
                out.push(p);
            }
        }
    }
}

/// Fluid fixtures at a size the fuzz can afford (the parser accepts up to
/// ny = 4096; the cost guard bounds that separately).
fn shrink(mut v: Value) -> Value {
    if let Some(f) = v.get_mut("fluid") {
        f["ny"] = json!(32);
        f["x_modes"] = json!(2);
        if let Some(s) = v.get_mut("settings").and_then(Value::as_object_mut) {
            s.remove("convergence_from");
            s.remove("instability_ny");
        }
    }
    v
}

// ---- hostile values ----------------------------------------------------------

fn hostile_number(rng: &mut Xoshiro256PlusPlus) -> Value {
    match rng.random_range(0..14) {
        0 => json!(0),
        1 => json!(1e308),
        2 => json!(-1e308),
        3 => json!(1e-308),
        4 => json!(5e-324),
        5 => json!(1e-160),
        6 => json!(1e160),
        7 => Value::String("1/0".into()),
        8 => Value::String("nan".into()),
        9 => Value::String(format!("0.{}", "7".repeat(rng.random_range(10..2000)))),
        10 => Value::String("1e999".into()),
        11 => json!(rng.random_range(-1000i64..1000)),
        12 => json!(10f64.powi(rng.random_range(-300..300)) * rng.random_range(0.1..10.0)),
        _ => json!(-0.0),
    }
}

fn hostile_string(rng: &mut Xoshiro256PlusPlus) -> Value {
    let s = match rng.random_range(0..18) {
        0 => "../escape".to_string(),
        1 => "/tmp/abs".to_string(),
        2 => String::new(),
        3 => "x".repeat(rng.random_range(100..20_000)),
        4 => "(".repeat(250) + "y" + &")".repeat(250),
        5 => {
            let n = rng.random_range(50..300);
            "sin(".repeat(n) + "y" + &")".repeat(n)
        }
        6 => vec!["y"; rng.random_range(20..500)].join("*"),
        7 => vec!["sin(y)"; rng.random_range(20..400)].join("*"),
        8 => "((10^64)^64)^64*Pi1^2".to_string(),
        9 => "Pi1^64*Pi2^64".to_string(),
        10 => "(10*y)^64".to_string(),
        11 => format!("{}*sin(y)", 10f64.powi(rng.random_range(-320..320))),
        12 => "exp(exp(exp(y)))".to_string(),
        13 => "sqrt(y - 1)".to_string(),
        14 => "π·y".to_string(),
        15 => "-".repeat(rng.random_range(10..400)) + "y",
        16 => vec!["2"; rng.random_range(2..60)].join("^"),
        _ => format!("1/({} - {})", rng.random_range(0..3), rng.random_range(0..3)),
    };
    Value::String(s)
}

fn hostile(rng: &mut Xoshiro256PlusPlus) -> Value {
    match rng.random_range(0..10) {
        0..=3 => hostile_number(rng),
        4..=7 => hostile_string(rng),
        8 => Value::Array((0..rng.random_range(0..5)).map(|_| hostile_number(rng)).collect()),
        _ => json!({"unexpected": hostile_number(rng)}),
    }
}

/// Replace a random leaf (or container) of `v` by `replacement`.
fn mutate(v: &mut Value, rng: &mut Xoshiro256PlusPlus, replacement: Value) {
    let mut paths = Vec::new();
    collect_paths(v, String::new(), &mut paths);
    if paths.is_empty() {
        return;
    }
    let p = &paths[rng.random_range(0..paths.len())];
    if let Some(slot) = v.pointer_mut(p) {
        *slot = replacement;
    }
}

fn collect_paths(v: &Value, here: String, out: &mut Vec<String>) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                let p = format!("{here}/{}", k.replace('~', "~0").replace('/', "~1"));
                out.push(p.clone());
                collect_paths(x, p, out);
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                let p = format!("{here}/{i}");
                out.push(p.clone());
                collect_paths(x, p, out);
            }
        }
        _ => {}
    }
}

// ---- random systems ---------------------------------------------------------

fn random_coefficient(rng: &mut Xoshiro256PlusPlus) -> String {
    let e = if rng.random_bool(0.7) { rng.random_range(-3..3) } else { rng.random_range(-200..200) };
    let m = rng.random_range(1..1000);
    format!("{}{m}e{e}", if rng.random_bool(0.2) { "-" } else { "" })
}

fn random_finite(rng: &mut Xoshiro256PlusPlus) -> Value {
    let (algebra, coords): (&str, Vec<&str>) = match rng.random_range(0..5) {
        0 | 1 => ("so3", vec!["Pi1", "Pi2", "Pi3"]),
        2 => ("se3", vec!["Pi1", "Pi2", "Pi3", "Gamma1", "Gamma2", "Gamma3"]),
        3 => ("sl2", vec!["muH", "muE", "muF"]),
        _ => ("se2", vec!["M", "P1", "P2"]),
    };
    let n = coords.len();
    let mut terms = vec![];
    for c in &coords {
        terms.push(format!("{}*{c}^2", random_coefficient(rng)));
    }
    if rng.random_bool(0.3) {
        terms.push(format!("{}*{}", random_coefficient(rng), coords[rng.random_range(0..n)]));
    }
    if rng.random_bool(0.2) {
        terms.push(format!("{}*{}^3", random_coefficient(rng), coords[rng.random_range(0..n)]));
    }
    let axis = rng.random_range(0..n);
    let equilibrium: Vec<Value> = (0..n)
        .map(|i| {
            if i == axis {
                json!(random_coefficient(rng))
            } else if rng.random_bool(0.1) {
                json!(1)
            } else {
                json!(0)
            }
        })
        .collect();
    let noise: Vec<Value> = (0..rng.random_range(0..3))
        .map(|_| {
            Value::Array(
                (0..n)
                    .map(|i| if i == axis || rng.random_bool(0.15) { json!(random_coefficient(rng)) } else { json!(0) })
                    .collect(),
            )
        })
        .collect();
    let eps = 10f64.powi(rng.random_range(-300..300));
    let mut v = json!({
        "name": "random", "algebra": algebra, "hamiltonian": terms.join(" + "),
        "equilibrium": equilibrium, "noise": noise,
        "stopping": {"epsilon": eps, "delta": eps * 10f64.powi(-rng.random_range(1..300))}
    });
    if rng.random_bool(0.3) {
        v["settings"] = json!({"exact": rng.random_bool(0.5), "optimise": rng.random_bool(0.7)});
    }
    v
}

fn random_profile(rng: &mut Xoshiro256PlusPlus) -> String {
    let scale = if rng.random_bool(0.6) { 1.0 } else { 10f64.powi(rng.random_range(-300..300)) };
    let base = match rng.random_range(0..9) {
        0 => "sin(y)",
        1 => "cos(y)",
        2 => "y^2",
        3 => "1 - y^2",
        4 => "y^3 - y",
        5 => "exp(-y^2)",
        6 => "sin(y) + 3*y",
        7 => "(exp(y) - exp(-y))/(exp(y) + exp(-y))",
        _ => "y",
    };
    format!("{scale:e}*({base})")
}

fn random_fluid(rng: &mut Xoshiro256PlusPlus) -> Value {
    let walls = rng.random_bool(0.6);
    let ny = if walls { 8 * rng.random_range(2..=8) } else { 2 * rng.random_range(8..=32) };
    let noise: Vec<Value> = (0..rng.random_range(0..3)).map(|_| Value::String(random_profile(rng))).collect();
    let mut v = json!({
        "name": "random-flow",
        "fluid": {
            "model": "incompressible", "x_period": 10f64.powi(rng.random_range(-3..3)) * 6.0,
            "y_interval": if walls { json!([0, "pi"]) } else { json!([0, "2*pi"]) },
            "boundary": if walls { "walls" } else { "periodic" },
            "shear_flow": random_profile(rng), "noise": noise, "ny": ny, "x_modes": rng.random_range(1..=3)
        },
        "stopping": {"epsilon": 0.1, "delta": 0.001}
    });
    if rng.random_bool(0.25) {
        v["fluid"]["model"] = json!("compressible");
        v["fluid"]["sound_speed"] = json!(10f64.powi(rng.random_range(-2..4)));
        if rng.random_bool(0.5) {
            v["fluid"]["noise"] = json!([format!("{}", random_coefficient(rng))]);
        }
    }
    v
}

/// A rigid body certified over a box of `I2` (and sometimes `sigma`), with
/// an equilibrium or noise that depends on `I2` and vanishes at a random
/// `c` inside, at the edge of, or outside the box: the verdict must be
/// about the part of the box that is proved, never the whole box from one
/// point.
fn random_box(rng: &mut Xoshiro256PlusPlus) -> Value {
    let lo = rng.random_range(1..8) as f64 / 4.0; // 1/4 .. 7/4, below I1 = 3
    let hi = lo + rng.random_range(1..12) as f64 / 4.0;
    let own = (lo + hi) / 2.0;
    let c = match rng.random_range(0..4) {
        0 => own,
        1 => lo,
        2 => lo + (hi - lo) * rng.random_range(1..8) as f64 / 8.0,
        _ => hi + 1.0,
    };
    let mut v = json!({
        "name": "random-box", "algebra": "so3",
        "parameters": {"I1": 3, "I2": format!("{own}"), "I3": "1/2", "sigma": "3/10"},
        "hamiltonian": "Pi1^2/(2*I1) + Pi2^2/(2*I2) + Pi3^2/(2*I3)",
        "casimirs": ["(Pi1^2 + Pi2^2 + Pi3^2)/2"],
        "equilibrium": [1, 0, 0], "noise": [["sigma", 0, 0]],
        "box": {"parameters": {"I2": [format!("{lo}"), format!("{hi}")]},
                "max_depth": rng.random_range(1..9), "max_boxes": rng.random_range(4..400)}
    });
    match rng.random_range(0..4) {
        0 => v["equilibrium"] = json!([1, format!("I2 - {c}"), 0]),
        1 => v["noise"] = json!([["sigma", format!("(I2 - {c})/10"), 0]]),
        2 => v["noise"] = json!([["sigma", format!("(I2 - {c})^2"), 0]]),
        _ => {}
    }
    if rng.random_bool(0.3) {
        v["box"]["parameters"]["sigma"] = json!(["1/10", "1/2"]);
    }
    v
}

// ---- running a case ----------------------------------------------------------

fn peak_memory_mb() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find(|l| l.starts_with("VmHWM:"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|k| k.parse::<f64>().ok())
        .map_or(0.0, |kb| kb / 1024.0)
}

struct Worker {
    started: Mutex<Option<(Instant, String)>>,
}

/// Spec case: parse, certify, check the engine's own certificate.
fn run_spec(text: &str, counts: &Counts) {
    bump(&counts.specs);
    let outcome = catch_unwind(AssertUnwindSafe(|| match spec::parse_any_spec(text) {
        Err(_) => None,
        Ok(s) => {
            let cert = spec::certify(&s, &spec::Options::default()).unwrap().into_json();
            let checked = spec::check_certificate(&spec::to_pretty_json(&cert));
            if let (Ok(report), true) = (&checked, cert.get("kind").is_some_and(|k| k == "box")) {
                box_point_agrees(text, &cert, report, counts);
            }
            Some(checked.err().map(|e| e.to_string()))
        }
    }));
    match outcome {
        Err(_) => {
            bump(&counts.spec_panics);
            eprintln!("PANIC on spec: {}", &text[..text.len().min(400)]);
            // FUZZ_DUMP=DIR keeps the whole spec, to reproduce it.
            if let Ok(dir) = std::env::var("FUZZ_DUMP") {
                let path = std::path::Path::new(&dir).join(format!("panic-{}.json", text.len()));
                let _ = std::fs::write(&path, text);
            }
        }
        Ok(None) => bump(&counts.spec_bad_input),
        Ok(Some(None)) => bump(&counts.spec_ok),
        Ok(Some(Some(e))) => {
            bump(&counts.own_check_rejected);
            eprintln!("OWN CHECK REJECTED: {e}\n  spec: {}", &text[..text.len().min(400)]);
        }
    }
}

/// What `check` reports under a box spec's name holds for the spec itself:
/// a whole-box verdict is the pipeline's verdict at the spec's own values
/// (a point of the box).
fn box_point_agrees(text: &str, cert: &Value, report: &spec::CheckReport, counts: &Counts) {
    bump(&counts.box_specs);
    let Ok(mut raw) = serde_json::from_str::<Value>(text) else { return };
    if raw["equilibrium"].to_string().contains("I2 -") || raw["noise"].to_string().contains("I2 -") {
        bump(&counts.box_residual_specs);
    }
    if report.verdict == spec::Verdict::Inconclusive {
        return;
    }
    raw.as_object_mut().map(|m| m.remove("box"));
    let Ok(point) = spec::parse_spec(&raw.to_string()) else { return };
    let at = spec::certify_lie(&point).analysis.verdict;
    if at != report.verdict {
        bump(&counts.box_point_disagrees);
        eprintln!("BOX VERDICT FALSE AT ITS OWN POINT: box {} ({:?}), point {:?}", cert["verdict"], report.verdict, at);
    }
}

/// A numeric leaf's value and the largest magnitude in its enclosing array.
fn number_at(cert: &Value, pointer: &str) -> Option<(f64, f64)> {
    let x = cert.pointer(pointer)?;
    let value = match x {
        Value::Number(n) => n.as_f64()?,
        Value::String(s) => exact::rational_to_f64(&exact::parse_certificate_rational(s).ok()?),
        _ => return None,
    };
    // The spectrum is compared to 1e-9 of its radius (check.rs SPECTRUM_TOLERANCE).
    if pointer.starts_with("/linearisation/spectrum/") {
        let radius = cert
            .pointer("/linearisation/spectrum")?
            .as_array()?
            .iter()
            .filter_map(|z| Some(z.get("re")?.as_f64()?.hypot(z.get("im")?.as_f64()?)))
            .fold(0.0f64, f64::max);
        return Some((value, radius.max(value.abs())));
    }
    let parent = &pointer[..pointer.rfind('/')?];
    let scale = match cert.pointer(parent) {
        Some(Value::Array(a)) => a
            .iter()
            .filter_map(|e| match e {
                Value::Number(n) => n.as_f64(),
                Value::String(s) => exact::parse_certificate_rational(s).ok().map(|r| exact::rational_to_f64(&r)),
                _ => None,
            })
            .fold(0.0f64, |m, v| m.max(v.abs())),
        _ => 0.0,
    };
    Some((value, scale.max(value.abs())))
}

enum Mutation {
    /// A number changed by a relative `delta` (or set to 0 / negated).
    Number { pointer: String, before: f64, after: f64, scale: f64 },
    /// A string or flag edited (docs/ci.md: every field is read).
    Field { pointer: String },
    /// Anything else: any acceptance is a forgery.
    Other(String),
}

/// A box certificate's proof inputs (docs/ci.md class `witness`), and a
/// sub-box's bound `S` (class `proved`, re-proved at the stated value): any
/// value with which the proof passes is accepted.
fn box_witness(original: &Value, pointer: &str) -> bool {
    let is_box = original.get("kind").is_some_and(|k| k == "box");
    is_box && ["/M/", "/multipliers/", "/free/", "/pivot_rows/"].iter().any(|p| pointer.contains(p))
        || is_box
            && (pointer.ends_with("/sign") || pointer.starts_with("/sub_boxes/") && pointer.ends_with("/sigma2_upper"))
}

fn mutate_certificate(cert: &Value, rng: &mut Xoshiro256PlusPlus) -> Option<(String, Mutation)> {
    let mut c = cert.clone();
    let mut paths = Vec::new();
    collect_paths(cert, String::new(), &mut paths);
    let numeric: Vec<&String> = paths
        .iter()
        .filter(|p| !p.starts_with("/spec") && !p.starts_with("/settings") && number_at(cert, p).is_some())
        .collect();
    match rng.random_range(0..12) {
        0..=5 if !numeric.is_empty() => {
            let p = numeric[rng.random_range(0..numeric.len())].clone();
            let (before, scale) = number_at(cert, &p)?;
            let slot = c.pointer_mut(&p)?;
            let after = match rng.random_range(0..12) {
                _ if before == 0.0 => {
                    if scale > 0.0 {
                        scale * 1e-6
                    } else {
                        1e-3
                    }
                }
                0 => 0.0,
                1 => -before,
                k => {
                    let d = [1e-3, 1e-5, 1e-7, 5e-7, 2e-9, 3e-9, 1e-10, 1e-11, 1e-13, 1e-2][(k - 2) as usize];
                    before * (1.0 + if rng.random_bool(0.5) { d } else { -d })
                }
            };
            if after == before || !after.is_finite() {
                return None;
            }
            *slot = match slot {
                Value::String(_) => {
                    Value::String(exact::rational_from_f64(after).map_or_else(|| after.to_string(), |r| r.to_string()))
                }
                _ => json!(after),
            };
            Some((spec::to_pretty_json(&c), Mutation::Number { pointer: p, before, after, scale }))
        }
        10 | 11 => {
            // a string or flag anywhere outside the inputs (spec, settings)
            let fields: Vec<&String> = paths
                .iter()
                .filter(|p| !p.starts_with("/spec") && !p.starts_with("/settings"))
                .filter(|p| matches!(cert.pointer(p), Some(Value::String(_) | Value::Bool(_))))
                .collect();
            if fields.is_empty() {
                return None;
            }
            let p = fields[rng.random_range(0..fields.len())].clone();
            let slot = c.pointer_mut(&p)?;
            *slot = match slot {
                Value::Bool(b) => json!(!*b),
                Value::String(t) if exact::parse_certificate_rational(t).is_ok() => {
                    let r = exact::parse_certificate_rational(t).ok()?;
                    let step = exact::Rational::new(1.into(), 10_000_000.into());
                    Value::String((&r + &step * (&r * &r + exact::Rational::from(1))).to_string())
                }
                Value::String(t) => Value::String(match rng.random_range(0..3) {
                    0 => format!("{t} (edited)"),
                    1 => String::new(),
                    _ => t.chars().rev().collect(),
                }),
                _ => return None,
            };
            (c.pointer(&p) != cert.pointer(&p)).then(|| (spec::to_pretty_json(&c), Mutation::Field { pointer: p }))
        }
        6 => {
            let verdicts: &[&str] = if cert.get("kind").is_some_and(|k| k == "box") {
                &[
                    "stable",
                    "partly_stable",
                    "linearly_unstable",
                    "partly_unstable",
                    "undecided",
                    "not_an_equilibrium",
                    "partly_not_an_equilibrium",
                    "noise_incompatible",
                    "partly_noise_incompatible",
                ]
            } else {
                &["stable", "linearly_unstable", "inconclusive", "not_an_equilibrium", "noise_incompatible"]
            };
            let now = cert["verdict"].as_str()?;
            let others: Vec<&&str> = verdicts.iter().filter(|v| **v != now).collect();
            let other = others[rng.random_range(0..others.len())];
            c["verdict"] = json!(other);
            Some((spec::to_pretty_json(&c), Mutation::Other(format!("verdict {now} -> {other}"))))
        }
        7 => {
            let levels = ["exact", "numerical", "verified_float", "exact_structure", "float", "none"];
            let now = cert["level"].as_str()?;
            let other = levels.iter().filter(|v| **v != now).nth(rng.random_range(0..5))?;
            c["level"] = json!(other);
            Some((spec::to_pretty_json(&c), Mutation::Other(format!("level {now} -> {other}"))))
        }
        8 => {
            // the embedded spec edited, digest recomputed
            let params = c.pointer_mut("/spec/parameters").and_then(Value::as_object_mut)?;
            let key = params.keys().next()?.clone();
            let old = params[&key].clone();
            let new = match &old {
                Value::Number(n) => json!(n.as_f64()? * 1.001 + 1e-3),
                Value::String(s) => json!(format!("({s})*1001/1000")),
                _ => return None,
            };
            params.insert(key.clone(), new);
            let digest = spec::spec_digest(&c["spec"]);
            c["spec_sha256"] = json!(digest);
            Some((spec::to_pretty_json(&c), Mutation::Other(format!("spec parameter {key} changed"))))
        }
        _ => {
            // a duplicated key, textually, or a dropped field
            let text = spec::to_pretty_json(cert);
            if rng.random_bool(0.5) {
                let v = cert["verdict"].as_str()?;
                let forged = text.replacen(
                    &format!("\"verdict\": \"{v}\","),
                    &format!("\"verdict\": \"{v}\",\n  \"verdict\": \"stable\","),
                    1,
                );
                (forged != text).then_some((forged, Mutation::Other("verdict duplicated".into())))
            } else {
                let keys: Vec<String> = c.as_object()?.keys().filter(|k| *k != "engine").cloned().collect();
                let k = &keys[rng.random_range(0..keys.len())];
                c.as_object_mut()?.remove(k);
                Some((spec::to_pretty_json(&c), Mutation::Other(format!("field {k} dropped"))))
            }
        }
    }
}

/// Whether the certificate's `fastest_direction` is, independently of the
/// checker, a unit-`P`-norm eigenvector of the stated `lambda_max` (to 1e-9):
/// then an altered direction still states a true thing (an eigenspace of a
/// multiple eigenvalue holds many).
fn direction_still_true(text: &str) -> bool {
    let Ok(c) = serde_json::from_str::<Value>(text) else { return false };
    let matrix = |key: &str| -> Option<nalgebra::DMatrix<f64>> {
        let rows = c.get(key)?.as_array()?;
        let n = rows.len();
        let mut m = nalgebra::DMatrix::zeros(n, n);
        for (i, r) in rows.iter().enumerate() {
            for (j, x) in r.as_array()?.iter().enumerate() {
                m[(i, j)] = exact::rational_to_f64(&exact::parse_certificate_rational(x.as_str()?).ok()?);
            }
        }
        Some(m)
    };
    let (Some(p), Some(q)) = (matrix("P"), matrix("Q")) else { return false };
    let sign = c.pointer("/casimir_choice/sign").and_then(Value::as_f64).unwrap_or(1.0);
    let (p, q) = (p * sign, q * sign);
    let Some(lmax) = c.pointer("/growth/largest_generalized_eigenvalue").and_then(Value::as_f64) else { return false };
    let Some(v) = c.pointer("/growth/fastest_direction").and_then(Value::as_array) else { return false };
    let v: Vec<f64> = v.iter().filter_map(Value::as_f64).collect();
    if v.len() != p.nrows() {
        return false;
    }
    let x = nalgebra::DVector::from_vec(v);
    let norm = (x.transpose() * &p * &x)[(0, 0)];
    let residual = (&q * &x - &p * &x * lmax).norm();
    (norm - 1.0).abs() <= 1e-9 * (p.norm() * x.norm_squared()).max(1.0)
        && residual <= 1e-9 * (q.norm() + lmax.abs() * p.norm()) * x.norm()
}

fn run_cert(original: &Value, text: &str, mutation: &Mutation, counts: &Counts) {
    bump(&counts.certs);
    let outcome = catch_unwind(AssertUnwindSafe(|| spec::check_certificate(text)));
    match outcome {
        Err(_) => {
            bump(&counts.cert_panics);
            eprintln!("PANIC on certificate of {}", original["name"]);
        }
        Ok(Err(spec::CheckError::BadInput(_))) => bump(&counts.cert_bad_input),
        Ok(Err(_)) => bump(&counts.cert_rejected),
        Ok(Ok(_)) => match mutation {
            Mutation::Number { pointer, before, after, scale } => {
                let change = (after - before).abs();
                // a lowered bound or stopping time is still a true statement
                // once the checker has proved it at the stated value
                let fluid_bound = original.get("kind").is_some_and(|k| k == "fluid")
                    && (pointer.ends_with("/sigma2_upper") || pointer == "/stopping/T")
                    && after < before;
                // A box certificate's choices (M, the free multipliers, the
                // rows) and bounds are the inputs of proofs that `check`
                // redoes exactly from the embedded spec (the solved
                // multipliers, the depth and the samples it re-derives and
                // compares): an accepted change there is proved again.
                // A sub-box's S is proved again at the stated value, in either
                // direction (a larger S is a weaker true bound).
                let box_input = box_witness(original, pointer)
                    || original.get("kind").is_some_and(|k| k == "box") && pointer.ends_with("/sigma2_upper");
                if change <= 1e-9 * scale {
                    bump(&counts.accepted_within_tolerance);
                } else if box_input {
                    bump(&counts.accepted_proved);
                } else if pointer.starts_with("/growth/fastest_direction/") && direction_still_true(text) {
                    // a vector of a multiple eigenvalue's eigenspace stays one
                    bump(&counts.accepted_proved);
                } else if fluid_bound {
                    // a lowered bound or T the checker proved at the stated value
                    bump(&counts.accepted_proved);
                } else {
                    bump(&counts.forgeries_accepted);
                    eprintln!(
                        "FORGERY ACCEPTED: {} {pointer}: {before:e} -> {after:e} (scale {scale:e})",
                        original["name"]
                    );
                }
            }
            Mutation::Field { pointer } if box_witness(original, pointer) => bump(&counts.accepted_proved),
            Mutation::Field { pointer } => {
                bump(&counts.forgeries_accepted);
                eprintln!("FORGERY ACCEPTED: {} field {pointer} edited", original["name"]);
            }
            // a box certificate re-proves every sub-box from the edited
            // embedded spec: accepted, its claims hold for that spec
            Mutation::Other(what)
                if original.get("kind").is_some_and(|k| k == "box") && what.starts_with("spec parameter") =>
            {
                bump(&counts.accepted_proved)
            }
            Mutation::Other(what) => {
                bump(&counts.forgeries_accepted);
                eprintln!("FORGERY ACCEPTED: {} {what}", original["name"]);
            }
        },
    }
}

/// What the merge fuzz counted.
#[derive(Default)]
struct MergeCounts {
    tried: u64,
    exit0: u64,
    exit1: u64,
    exit2: u64,
    panics: u64,
    /// An edited result merged without `--recheck`, with the summary saying
    /// the results are data (not re-derived): allowed, and counted.
    passed_as_data: u64,
    /// An edited result merged as checked, or an edited point, id or form
    /// merged at all: must be 0.
    forgeries: u64,
    /// A harmless change (a byte-order mark, CRLF) merged, and refused.
    harmless_merged: u64,
    harmless_refused: u64,
}

/// Shards of a small sweep, altered once each and merged by the `verify`
/// binary (next to this example in the target folder), half the time with
/// `--recheck`.
fn fuzz_merges(o: &Options) -> Option<MergeCounts> {
    let exe = std::env::current_exe().ok()?;
    let verify = exe.parent()?.parent()?.join("verify");
    if !verify.is_file() {
        eprintln!("merge fuzz skipped: no {} (build it with `cargo build --release -p verify`)", verify.display());
        return None;
    }
    let dir = std::env::temp_dir().join(format!("fuzz-merge-{}", std::process::id()));
    std::fs::create_dir_all(&dir).ok()?;
    let spec = fixtures_dir().join("rigid-body-major-axis.json");
    let spec = spec.to_str()?;
    // I2 from 2 to 4 with I1 = 3: stable, I2 = I1 inconclusive, then unstable
    let plan = ["--param", "I2=2:4:9"];
    let mut shards = vec![];
    for k in 0..3 {
        let path = dir.join(format!("shard{k}.jsonl"));
        let status = std::process::Command::new(&verify)
            .args(["sweep", spec, "-o", path.to_str()?, "--shard", &format!("{k}/3")])
            .args(plan)
            .stderr(std::process::Stdio::null())
            .status()
            .ok()?;
        if !status.success() {
            eprintln!("merge fuzz: a shard failed to run");
            return None;
        }
        shards.push(std::fs::read_to_string(&path).ok()?);
    }
    let mut counts = MergeCounts::default();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(o.seed ^ 0x3E46E);
    #[derive(PartialEq)]
    enum Kind {
        Result,
        Point,
        Harmless,
        Broken,
    }
    for case in 0..o.merges {
        let mut files = shards.clone();
        let f = rng.random_range(0..files.len());
        let mut lines: Vec<String> = files[f].lines().map(str::to_string).collect();
        let l = rng.random_range(0..lines.len());
        let mut v: Value = serde_json::from_str(&lines[l]).ok()?;
        let kind = match rng.random_range(0..16) {
            0 => {
                let now = v["verdict"].as_str().unwrap_or("").to_string();
                let others: Vec<&str> =
                    ["stable", "linearly_unstable", "inconclusive", "not_an_equilibrium", "noise_incompatible"]
                        .into_iter()
                        .filter(|x| *x != now)
                        .collect();
                v["verdict"] = json!(others[rng.random_range(0..others.len())]);
                Kind::Result
            }
            1 | 2 => {
                let key = if rng.random_bool(0.5) { "sigma2" } else { "T" };
                match v.get(key).and_then(Value::as_f64) {
                    Some(x) => v[key] = json!(x * (1.0 + [1e-3, 1e-7, 1e-12][rng.random_range(0..3)])),
                    None => v[key] = json!(0.5),
                }
                Kind::Result
            }
            3 => {
                v["level"] = json!(["exact", "numerical", "verified_float", "none"][rng.random_range(0..4)]);
                if lines[l].contains(&format!("\"level\":{}", v["level"])) {
                    continue;
                }
                Kind::Result
            }
            4 => {
                let x = v["parameters"]["I2"].as_f64().unwrap_or(2.0);
                v["parameters"]["I2"] = json!(x * (1.0 + 1e-7));
                Kind::Point
            }
            5 => {
                v["exact_parameters"]["I2"] = json!(format!("{}/7", rng.random_range(14..28)));
                Kind::Point
            }
            6 => {
                v["index"] = json!(rng.random_range(0..9));
                if lines[l].contains(&format!("\"index\":{},", v["index"])) {
                    continue;
                }
                Kind::Point
            }
            7 => {
                v["sweep"] = json!("0123456789abcdef");
                Kind::Point
            }
            8 => {
                v["spec"] = json!("fedcba9876543210");
                Kind::Point
            }
            9 => {
                v["checked_by"] = json!("hand");
                Kind::Point
            }
            10 => {
                files[f] = format!("\u{feff}{}", files[f]);
                Kind::Harmless
            }
            11 => {
                files[f] = files[f].replace('\n', "\r\n");
                Kind::Harmless
            }
            12 => {
                let text = files[f].trim_end().to_string();
                files[f] = text[..text.len() - rng.random_range(1..text.len().min(60))].to_string();
                Kind::Broken
            }
            13 => {
                lines.insert(l, "{\"sweep\": [1, 2".to_string());
                files[f] = lines.join("\n") + "\n";
                Kind::Broken
            }
            14 => {
                lines.remove(l);
                files[f] = lines.join("\n") + "\n";
                Kind::Broken
            }
            _ => {
                // the same point twice, with two results
                let mut w = v.clone();
                w["verdict"] = json!(if v["verdict"] == "stable" { "inconclusive" } else { "stable" });
                lines.push(w.to_string());
                files[f] = lines.join("\n") + "\n";
                Kind::Broken
            }
        };
        if matches!(kind, Kind::Result | Kind::Point) {
            lines[l] = v.to_string();
            files[f] = lines.join("\n") + "\n";
        }
        if files == shards {
            continue;
        }
        let paths: Vec<PathBuf> = files
            .iter()
            .enumerate()
            .map(|(k, text)| {
                let p = dir.join(format!("case{case}-{k}.jsonl"));
                let _ = std::fs::write(&p, text);
                p
            })
            .collect();
        let recheck = rng.random_bool(0.5);
        let out = dir.join("merged.jsonl");
        let _ = std::fs::remove_file(&out);
        let mut cmd = std::process::Command::new(&verify);
        cmd.args(["merge", spec, "-o", out.to_str()?]).args(plan);
        if recheck {
            cmd.arg("--recheck");
        }
        cmd.arg("--lines").args(&paths);
        let Ok(result) = cmd.output() else { continue };
        for p in &paths {
            let _ = std::fs::remove_file(p);
        }
        counts.tried += 1;
        let said = String::from_utf8_lossy(&result.stderr);
        match result.status.code() {
            Some(0) => {
                counts.exit0 += 1;
                match kind {
                    Kind::Result if !recheck && said.contains("not re-derived") => counts.passed_as_data += 1,
                    Kind::Result | Kind::Point | Kind::Broken => {
                        counts.forgeries += 1;
                        eprintln!("MERGE FORGERY: case {case} (recheck {recheck}) merged: {said}");
                    }
                    Kind::Harmless => counts.harmless_merged += 1,
                }
            }
            Some(1) => counts.exit1 += 1,
            Some(2) => counts.exit2 += 1,
            _ => {
                counts.panics += 1;
                eprintln!("MERGE PANIC (case {case}): {said}");
            }
        }
        if kind == Kind::Harmless && result.status.code() != Some(0) {
            counts.harmless_refused += 1;
            eprintln!("MERGE REFUSED A HARMLESS CHANGE (case {case}): {said}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    Some(counts)
}

fn main() {
    let o = options();
    let counts = Counts::default();
    let started = Instant::now();
    let mut spec_texts: Vec<Value> = Vec::new();
    let mut paths = Vec::new();
    files(&fixtures_dir(), false, &mut paths);
    for p in &paths {
        if let Ok(v) = serde_json::from_str::<Value>(&std::fs::read_to_string(p).unwrap_or_default()) {
            spec_texts.push(shrink(v));
        }
    }
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    let workers: Vec<Worker> = (0..threads).map(|_| Worker { started: Mutex::new(None) }).collect();
    let next = AtomicU64::new(0);
    let over_memory = AtomicUsize::new(0);
    let done = std::sync::atomic::AtomicBool::new(false);
    let silent = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));

    // Certificates to alter: fixtures (fluid ones shrunk and re-certified)
    // and random valid specs.
    let mut pool: Vec<Value> = Vec::new();
    let mut cert_paths = Vec::new();
    files(&fixtures_dir(), true, &mut cert_paths);
    for p in &cert_paths {
        if let Ok(v) = serde_json::from_str::<Value>(&std::fs::read_to_string(p).unwrap_or_default()) {
            if v.get("kind").is_some_and(|k| k == "fluid") {
                if let Ok(s) = spec::parse_any_spec(&shrink(v["spec"].clone()).to_string()) {
                    pool.push(spec::certify(&s, &spec::Options::default()).unwrap().into_json());
                }
            } else {
                pool.push(v);
            }
        }
    }
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(o.seed ^ 0xC0FFEE);
    while pool.len() < 200 {
        let v = match rng.random_range(0..20) {
            0..=13 => random_finite(&mut rng),
            14..=16 => random_box(&mut rng),
            _ => random_fluid(&mut rng),
        };
        if let Ok(s) = spec::parse_any_spec(&v.to_string()) {
            pool.push(spec::certify(&s, &spec::Options::default()).unwrap().into_json());
        }
    }

    std::thread::scope(|scope| {
        // Watchdog: report memory, abort on a case that hangs.
        scope.spawn(|| {
            while !done.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(200));
                if peak_memory_mb() > o.memory_limit_mb {
                    over_memory.store(1, Ordering::Relaxed);
                }
                for w in &workers {
                    if let Some((t, case)) = w.started.lock().unwrap().as_ref() {
                        if t.elapsed().as_secs_f64() > 10.0 * o.time_limit {
                            eprintln!(
                                "HANG: a case ran {:.0} s: {}",
                                t.elapsed().as_secs_f64(),
                                &case[..case.len().min(400)]
                            );
                            std::process::exit(1);
                        }
                    }
                }
            }
        });
        for (w, worker) in workers.iter().enumerate() {
            let (counts, next, spec_texts, pool) = (&counts, &next, &spec_texts, &pool);
            scope.spawn(move || {
                let total = o.specs + o.certs;
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    if i >= total {
                        break;
                    }
                    let mut rng = Xoshiro256PlusPlus::seed_from_u64(o.seed.wrapping_mul(0x9E3779B97F4A7C15) ^ i);
                    if i < o.specs {
                        let text = match rng.random_range(0..20) {
                            0..=10 => {
                                let mut v = spec_texts[rng.random_range(0..spec_texts.len())].clone();
                                for _ in 0..rng.random_range(1..3) {
                                    let h = hostile(&mut rng);
                                    mutate(&mut v, &mut rng, h);
                                }
                                let t = v.to_string();
                                if rng.random_bool(0.03) {
                                    t.replacen("{\"", "{\"name\":\"dup\",\"", 1)
                                } else {
                                    t
                                }
                            }
                            11..=15 => random_finite(&mut rng).to_string(),
                            16 => random_box(&mut rng).to_string(),
                            _ => random_fluid(&mut rng).to_string(),
                        };
                        *worker.started.lock().unwrap() = Some((Instant::now(), text.clone()));
                        let t = Instant::now();
                        run_spec(&text, counts);
                        counts.slowest_us.fetch_max(t.elapsed().as_micros() as u64, Ordering::Relaxed);
                        if t.elapsed().as_secs_f64() > o.time_limit {
                            bump(&counts.over_time);
                            eprintln!(
                                "OVER TIME ({:.1} s): {}",
                                t.elapsed().as_secs_f64(),
                                &text[..text.len().min(300)]
                            );
                            // FUZZ_DUMP=DIR keeps the whole spec, to reproduce it.
                            if let Ok(dir) = std::env::var("FUZZ_DUMP") {
                                let path = std::path::Path::new(&dir).join(format!("slow-{i}.json"));
                                let _ = std::fs::write(&path, &text);
                            }
                        }
                    } else {
                        // draw until an alteration changes something (a number
                        // already 0 scaled, a spec without parameters...)
                        let mut drawn = None;
                        for _ in 0..50 {
                            let original = &pool[rng.random_range(0..pool.len())];
                            if let Some(m) = mutate_certificate(original, &mut rng) {
                                drawn = Some((original, m));
                                break;
                            }
                            bump(&counts.unchanged);
                        }
                        let Some((original, (text, mutation))) = drawn else { continue };
                        *worker.started.lock().unwrap() =
                            Some((Instant::now(), format!("certificate of {}", original["name"])));
                        let t = Instant::now();
                        run_cert(original, &text, &mutation, counts);
                        counts.slowest_us.fetch_max(t.elapsed().as_micros() as u64, Ordering::Relaxed);
                        if t.elapsed().as_secs_f64() > o.time_limit {
                            bump(&counts.over_time);
                        }
                    }
                    *worker.started.lock().unwrap() = None;
                    if w == 0 && i % 5000 == 0 {
                        eprintln!("{i}/{total} cases, {:.0} s", started.elapsed().as_secs_f64());
                    }
                }
            });
        }
        // the workers end when the cases run out; then stop the watchdog
        while next.load(Ordering::Relaxed) < o.specs + o.certs
            || workers.iter().any(|w| w.started.lock().unwrap().is_some())
        {
            std::thread::sleep(Duration::from_millis(100));
        }
        done.store(true, Ordering::Relaxed);
    });
    std::panic::set_hook(silent);
    let merges = fuzz_merges(&o);

    let g = |c: &AtomicU64| c.load(Ordering::Relaxed);
    let peak = peak_memory_mb();
    let over_memory = over_memory.load(Ordering::Relaxed) as u64;
    println!(
        "fuzz_edges: seed {}, {:.0} s, {} threads, peak memory {:.0} MB",
        o.seed,
        started.elapsed().as_secs_f64(),
        threads,
        peak
    );
    println!("specs tried                          {}", g(&counts.specs));
    println!("  certified (exit 0), own check ok   {}", g(&counts.spec_ok));
    println!("  refused as bad input (exit 2)      {}", g(&counts.spec_bad_input));
    println!("  panics                             {}", g(&counts.spec_panics));
    println!("  own certificate rejected by check  {}", g(&counts.own_check_rejected));
    println!("certificates altered                 {}", g(&counts.certs));
    println!("  rejected by check (exit 1)         {}", g(&counts.cert_rejected));
    println!("  rejected as bad input (exit 2)     {}", g(&counts.cert_bad_input));
    println!("  panics                             {}", g(&counts.cert_panics));
    println!("  accepted: change within 1e-9       {}", g(&counts.accepted_within_tolerance));
    println!("  accepted: still true (proved)      {}", g(&counts.accepted_proved));
    println!("  accepted: forgery of a number      {}", g(&counts.forgeries_accepted));
    println!("  (draws that altered nothing, redrawn {})", g(&counts.unchanged));
    println!("box specs certified                  {}", g(&counts.box_specs));
    println!("  with a parameter-dependent residual {}", g(&counts.box_residual_specs));
    println!("  whole-box verdict false at the spec's own point {}", g(&counts.box_point_disagrees));
    let m = merges.unwrap_or_default();
    println!("merged sweep files tried             {}", m.tried);
    println!("  merged (exit 0)                    {}", m.exit0);
    println!("  refused (exit 1)                   {}", m.exit1);
    println!("  bad input (exit 2)                 {}", m.exit2);
    println!("  panics                             {}", m.panics);
    println!("  edited results passed as data, said so (no --recheck) {}", m.passed_as_data);
    println!("  forgeries merged as checked        {}", m.forgeries);
    println!("  harmless changes (BOM, CRLF) merged {}", m.harmless_merged);
    println!("  harmless changes refused           {}", m.harmless_refused);
    println!("slowest case                         {:.2} s", g(&counts.slowest_us) as f64 / 1e6);
    println!("cases over {} s                      {}", o.time_limit, g(&counts.over_time));
    println!("peak memory over {} MB              {}", o.memory_limit_mb, over_memory);
    let must_be_zero = g(&counts.spec_panics)
        + g(&counts.box_point_disagrees)
        + m.panics
        + m.forgeries
        + m.harmless_refused
        + g(&counts.cert_panics)
        + g(&counts.own_check_rejected)
        + g(&counts.forgeries_accepted)
        + g(&counts.over_time)
        + over_memory;
    if must_be_zero > 0 {
        std::process::exit(1);
    }
}
