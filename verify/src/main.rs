//! `verify`: certify stochastic Lie–Poisson equilibria from JSON specs.
//!
//! * `verify` — certify every spec under `fixtures/`, re-check the committed
//!   certificates, print a table;
//! * `verify certify SPEC [-o CERT]` — certificate JSON on stdout (or CERT),
//!   a short summary on stderr;
//! * `verify check CERT...` — re-derive each certificate from its embedded
//!   spec and compare;
//! * `verify plot-fluid CERT... [--out DIR]` — charts from fluid certificates;
//! * `verify sweep SPEC --param NAME=START:STOP:COUNT... [--random N --seed S]
//!   [--shard K/N] [-o FILE [--resume]] [--numeric] [--plot DIR]` — certify
//!   over parameter space, one JSON line per point;
//! * `verify plot-sweep LINES... --spec SPEC [--out DIR]` — stability maps;
//! * `verify simulate SPEC [--paths N --dt H --t-end T --observable NAME ...]
//!   [--shard K/N | --merge FILES]` — ensembles, exact moments and charts
//!   (SVG, PNG, JSON, CSV); sharded runs merge into exactly the whole run.
//!
//! Exit status: 0 success (whatever the verdict), 1 a certificate failed its
//! check or an internal failure, 2 bad input (the message names the JSON path).

use anyhow::Context;
use clap::{Parser, Subcommand};
use serde_json::Value;
use spec::CheckError;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

// The exact pipeline allocates many small rationals and polynomials per
// point; mimalloc's thread-local free lists make sweeps on several threads
// markedly faster than the system allocator.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

mod fluid_plots;
mod fluid_simulate;
mod merge_cmd;
mod messages;
mod npz_out;
mod paths;
mod plots;
mod png;
mod report;
mod report_box;
mod simulate_cmd;
mod sweep_cmd;
mod sweep_plots;
mod table;
mod threads;
mod zeitlin_simulate;

#[derive(Parser)]
#[command(
    name = "verify",
    version,
    about = "Stochastic energy–Casimir stability certificates (with no subcommand: certify and re-check the bundled fixtures)",
    long_about = "Stochastic energy–Casimir stability certificates.\n\nWith no subcommand, `verify` certifies every spec under fixtures/ (or --fixtures DIR), re-checks each committed certificate against it, and prints one table row per spec; --write rewrites the certificates instead. Exit status: 0 success whatever the verdict, 1 a certificate failed its check, 2 bad input."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Directory of fixture specs for the no-argument run.
    #[arg(long)]
    fixtures: Option<PathBuf>,
    /// In the no-argument run, (re)write each fixture's certificate.
    #[arg(long)]
    write: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Certify one spec.
    Certify {
        /// The spec (JSON).
        spec: PathBuf,
        /// Write the certificate to this file instead of stdout (`-o -` is stdout).
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Certify a spec for every parameter value in a box (docs/boxes.md): writes a box certificate that `check` re-verifies exactly.
    CertifyBox {
        /// The spec (JSON, finite-dimensional).
        spec: PathBuf,
        /// A box side, `NAME=LO:HI` (exact rationals, LO < HI); repeat for each parameter. Replaces the spec's `box` section.
        #[arg(long = "param", required = true)]
        params: Vec<String>,
        /// Largest number of bisections from the box to a sub-box (default 12).
        #[arg(long)]
        max_depth: Option<u64>,
        /// Largest number of sub-boxes analysed (default 4096).
        #[arg(long)]
        max_boxes: Option<u64>,
        /// Write the certificate to this file instead of stdout (`-o -` is stdout).
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Simulate the nonlinear and the linearised system and draw the charts.
    Simulate(simulate_cmd::SimulateArgs),
    /// Certify a spec over a grid or random samples of its parameters (one JSON line per point).
    Sweep(sweep_cmd::SweepArgs),
    /// Join the line files of a sharded sweep into one, checking identity, duplicates and completeness.
    Merge(merge_cmd::MergeArgs),
    /// Stability maps and Sigma^2 / T charts from sweep lines.
    PlotSweep(sweep_plots::PlotSweepArgs),
    /// Charts from fluid certificates (Sigma^2 per x-mode, convergence, Galilean shift).
    PlotFluid(fluid_plots::PlotFluidArgs),
    /// One self-contained HTML page for certificates (verdicts in words, what was proved, key numbers, charts), each re-checked.
    Report(report::ReportArgs),
    /// Print the JSON Schema of specs (for editors: validation and completion).
    Schema {
        /// Which schema: `spec` (finite-dimensional systems), `fluid-spec`, `zeitlin-spec`, `certificate` (of a finite-dimensional spec), `fluid-certificate`, `zeitlin-certificate`, `large-certificate` (of a spec above 64 coordinates) or `box-certificate` (of a spec with a box).
        #[arg(value_parser = ["spec", "fluid-spec", "zeitlin-spec", "certificate", "fluid-certificate", "zeitlin-certificate", "large-certificate", "box-certificate"], default_value = "spec")]
        which: String,
    },
    /// Re-check certificates.
    Check {
        /// Certificates (JSON).
        #[arg(required = true)]
        certificates: Vec<PathBuf>,
    },
}

/// An outcome that maps to an exit status.
pub(crate) enum Failure {
    BadInput(String),
    Failed(String),
}

/// A progress bar on stderr when it is a terminal: `{pos}/{len} <unit>`.
pub(crate) fn progress_bar(total: u64, template: &str) -> Option<indicatif::ProgressBar> {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = indicatif::ProgressBar::new(total);
    if let Ok(style) = indicatif::ProgressStyle::with_template(template) {
        bar.set_style(style);
    }
    Some(bar)
}

/// Certify, with a progress bar on stderr (when it is a terminal) for the
/// pipelines that can take seconds to minutes: fluids, the Zeitlin model
/// and large systems. The work runs on a scoped thread (with the main
/// thread's 8 MiB of stack) while this one draws the bar.
/// With `multi`, the bar joins it (below the bare run's line of progress).
pub(crate) fn certify_showing_progress(
    spec: &spec::AnySpec,
    label: &str,
    multi: Option<&indicatif::MultiProgress>,
) -> Value {
    let plain = || match spec::certify(spec, &spec::Options::default()) {
        Ok(c) => c.into_json(),
        // (nothing cancels here; an internal error is the engine's bug, and says so)
        Err(e) => panic!("{e}"),
    };
    if matches!(spec, spec::AnySpec::Lie(_)) {
        return plain();
    }
    let Some(bar) = progress_bar(1, "{msg} [{bar:30}] {percent:>3}% ({elapsed})") else {
        return plain();
    };
    let bar = match multi {
        Some(m) => m.add(bar),
        None => bar,
    };
    bar.set_message(messages::excerpt(label));
    let state = outcome::Progress::new();
    // (nothing cancels here: `certify` returns a certificate)
    let out =
        run_showing_progress(&bar, &state, || spec::certify(spec, &spec::Options::default().with_progress(&state)));
    bar.finish_and_clear();
    out.map(spec::AnyCertificate::into_json).unwrap_or_else(|_| plain())
}

/// Run `work` on a scoped thread (with the main thread's 8 MiB of stack)
/// while this one moves `bar` to `state`'s counts every 100 ms; on this
/// thread when no thread can be started.
pub(crate) fn run_showing_progress<R: Send>(
    bar: &indicatif::ProgressBar,
    state: &outcome::Progress,
    work: impl Fn() -> R + Sync,
) -> R {
    let out = std::thread::scope(|scope| {
        let worker = std::thread::Builder::new().stack_size(8 << 20).spawn_scoped(scope, &work).ok()?;
        while !worker.is_finished() {
            let (done, total) = state.snapshot();
            // (indicatif draws a length of 0 as full: nothing planned yet)
            if total > 0 {
                bar.set_length(total);
                bar.set_position(done);
            }
            std::thread::sleep(std::time::Duration::from_millis(100));
        }
        match worker.join() {
            Ok(out) => Some(out),
            Err(panic) => std::panic::resume_unwind(panic),
        }
    });
    out.unwrap_or_else(work)
}

fn read(path: &Path) -> Result<String, Failure> {
    std::fs::read_to_string(path).map_err(|e| Failure::BadInput(format!("{}: cannot read: {e}", path.display())))
}

fn certify_command(spec_path: &Path, output: Option<&Path>) -> Result<(), Failure> {
    if let Some(path) = output {
        paths::check_output_file(path, "-o")?;
    }
    let text = read(spec_path)?;
    let spec = spec::parse(&text, &spec::Options::relative_to(spec_path.parent()))
        .map_err(|e| Failure::BadInput(format!("{}: {e}", spec_path.display())))?;
    let cert = certify_showing_progress(&spec, &spec_path.display().to_string(), None);
    emit(&cert, output)
}

/// The certificate to `output` (or stdout), its summary to stderr.
fn emit(cert: &Value, output: Option<&Path>) -> Result<(), Failure> {
    let pretty = spec::to_pretty_json(cert);
    match output {
        // Atomic: a failed write (a full disk) leaves no partial certificate
        // and keeps an existing one.
        Some(path) => paths::write_output(path, pretty.as_bytes()).map_err(|e| paths::write_failure(path, &e))?,
        None => print!("{pretty}"),
    }
    eprintln!("{}", summary(cert));
    Ok(())
}

/// `verify certify-box`: the spec with its `box` section set from
/// `--param NAME=LO:HI` (and the bounds), certified as any spec with a box.
fn certify_box_command(
    spec_path: &Path,
    params: &[String],
    max_depth: Option<u64>,
    max_boxes: Option<u64>,
    output: Option<&Path>,
) -> Result<(), Failure> {
    if let Some(path) = output {
        paths::check_output_file(path, "-o")?;
    }
    let text = read(spec_path)?;
    let bad = |m: String| Failure::BadInput(format!("{}: {m}", spec_path.display()));
    let mut value: Value = spec::parse_json(&text).map_err(|e| bad(e.to_string()))?;
    if !value.is_object() || value.get("fluid").is_some() || value.get("zeitlin").is_some() {
        return Err(bad("certify-box takes a finite-dimensional spec (a Lie algebra, a Hamiltonian, ...)".into()));
    }
    let mut sides = serde_json::Map::new();
    let mut moved: Vec<String> = vec![];
    for p in params {
        let (name, range) = p
            .split_once('=')
            .ok_or_else(|| Failure::BadInput(format!("--param {}: expected NAME=LO:HI", messages::excerpt(p))))?;
        let (lo, hi) = range
            .split_once(':')
            .ok_or_else(|| Failure::BadInput(format!("--param {}: expected NAME=LO:HI", messages::excerpt(p))))?;
        if sides.insert(name.to_string(), serde_json::json!([lo, hi])).is_some() {
            return Err(Failure::BadInput(format!("--param {}: given twice", messages::excerpt(name))));
        }
        // The box is about the spec: a value of the spec outside the box is
        // moved to the box's centre (the certificate embeds the spec so).
        let (Ok(a), Ok(b)) = (exact::parse_number(lo), exact::parse_number(hi)) else { continue };
        let own = value.pointer(&format!("/parameters/{name}")).and_then(|v| match v {
            Value::String(t) => exact::parse_number(t).ok(),
            Value::Number(n) => exact::parse_number(&n.to_string()).ok(),
            _ => None,
        });
        if let Some(own) = own {
            if a < b && (own < a || own > b) {
                let centre = (&a + &b) / exact::Rational::from(2);
                eprintln!("note: {name} = {own} lies outside [{a}, {b}]: the certificate's spec has {name} = {centre}");
                value["parameters"][name] = Value::String(centre.to_string());
                moved.push(format!("{name} = {centre}"));
            }
        }
    }
    // The certificate's name says the spec was moved: what `check` reports
    // under it holds for the moved spec, not for the original one.
    if !moved.is_empty() {
        let old = value["name"].as_str().unwrap_or("").to_string();
        value["name"] = Value::String(format!("{old} ({})", moved.join(", ")));
        eprintln!("note: the certificate is named '{}'", messages::excerpt(value["name"].as_str().unwrap_or("")));
    }
    let mut section = serde_json::json!({"parameters": sides});
    if let Some(d) = max_depth {
        section["max_depth"] = d.into();
    }
    if let Some(m) = max_boxes {
        section["max_boxes"] = m.into();
    }
    value["box"] = section;
    let spec = spec::spec_from_value(value).map_err(|e| bad(e.to_string()))?;
    emit(&spec::box_cert::certify_box_spec(&spec), output)
}

/// One or two lines for a human.
fn summary(cert: &Value) -> String {
    let mut s = format!(
        "{}: {} ({})",
        messages::excerpt(cert["name"].as_str().unwrap_or("?")),
        cert["verdict"].as_str().unwrap_or("?"),
        cert["level"].as_str().unwrap_or(match cert.pointer("/theorem/status").and_then(Value::as_str) {
            Some("proved") => "exact",
            Some(_) => "nothing is claimed",
            None => "?",
        })
    );
    if let Some(s2) = cert.get("sigma2") {
        s.push_str(&format!(", Sigma^2 = {}", table::format_number(s2)));
    }
    if cert.get("kind").and_then(Value::as_str) == Some("box") {
        let subs = cert["sub_boxes"].as_array().map_or(0, Vec::len);
        s.push_str(&format!(", {subs} sub-boxes"));
        if let Some(sup) = cert.get("sup_sigma2") {
            s.push_str(&format!(", sup Sigma^2 <= {}", table::format_number(sup)));
        }
        if let Some(f) = cert.get("undecided_fraction").and_then(Value::as_f64).filter(|f| *f > 0.0) {
            s.push_str(&format!(", undecided {:.3}% of the box", 100.0 * f));
        }
        if let Some(l) = cert.get("limit").and_then(Value::as_str) {
            s.push_str(&format!(" ({l} reached)"));
        }
    }
    if let Some(st) = cert.get("stopping") {
        s.push_str(&format!(
            ", T({}, {}) = {}",
            st["epsilon"].as_f64().map_or_else(|| table::format_number(&st["epsilon"]), spec::theorem::shortest),
            st["delta"].as_f64().map_or_else(|| table::format_number(&st["delta"]), spec::theorem::shortest),
            table::format_number(&st["T"])
        ));
    }
    if let Some(r) = cert["reason"].as_str() {
        s.push_str(&format!("\n  {r}"));
    }
    // The statement in the certificate's own words (re-derived by check).
    if let Some(t) = cert.pointer("/theorem/statement").and_then(Value::as_str) {
        s.push_str(&format!("\n  claim: {t}"));
    }
    if let Some(t) = cert.pointer("/theorem/not_checked").and_then(Value::as_str) {
        s.push_str(&format!("\n  not checked: {t}"));
    }
    if let Some(line) = compatible_noise_line(cert) {
        s.push_str(&line);
    }
    if let Some(list) = cert.pointer("/compressible/compatible_completion") {
        s.push_str(&format!("\n  compatible noise (paste as fluid.noise): {list}"));
    }
    if let Some(fields) = cert.get("compatible_noise").and_then(Value::as_array) {
        for (i, rows) in fields.iter().enumerate() {
            let rows = messages::cut_message(&rows.to_string());
            s.push_str(&format!("\n  compatible part of noise[{i}] (paste as {{\"harmonics\": ...}}): {rows}"));
        }
    }
    s
}

/// For incompatible noise in a finite-dimensional certificate, the noise
/// that would be compatible: a basis of the isotropy algebra of `mu_e`
/// (`noise.isotropy_basis`; every `sigma` with `ad*_sigma mu_e = 0` is a
/// combination of these), as rows of components on `e_a` that paste into
/// the spec's `noise`. Integers are written as numbers, other rationals as
/// strings (`"3/10"`), as a spec writes them.
fn compatible_noise_line(cert: &Value) -> Option<String> {
    if cert.get("verdict").and_then(Value::as_str) != Some("noise_incompatible") {
        return None;
    }
    let basis = cert.pointer("/noise/isotropy_basis")?.as_array()?;
    if basis.is_empty() {
        return Some(
            "\n  compatible noise: none (the isotropy algebra of mu_e is {0}: only sigma = 0 keeps mu_e)".into(),
        );
    }
    let entry = |x: &Value| match x.as_str() {
        Some(t) if t.parse::<i64>().is_ok() => t.to_string(),
        Some(t) => format!("\"{t}\""),
        None => x.to_string(),
    };
    let rows: Vec<String> = basis
        .iter()
        .map(|row| format!("[{}]", row.as_array().map_or(vec![], |r| r.iter().map(entry).collect()).join(", ")))
        .collect();
    let coordinates: Vec<&str> = cert
        .get("coordinates")
        .and_then(Value::as_array)
        .map_or(vec![], |c| c.iter().filter_map(Value::as_str).collect());
    let on = if coordinates.is_empty() {
        "components on the basis e_a".to_string()
    } else {
        format!("components on e_a, a = {}", coordinates.join(", "))
    };
    Some(messages::cut_message(&format!(
        "\n  compatible noise (ad*_sigma mu_e = 0): the combinations of these {} element(s), a basis of the isotropy algebra of mu_e ({on}; paste rows as noise): [{}]",
        rows.len(),
        rows.join(", ")
    )))
}

/// Whether `text` is a spec rather than a certificate: a JSON object with
/// no `spec` field that the spec parser accepts.
fn is_a_spec(text: &str, base: Option<&Path>) -> bool {
    serde_json::from_str::<Value>(text).is_ok_and(|v| v.get("spec").is_none() && v.is_object())
        && spec::parse(text, &spec::Options::relative_to(base)).is_ok()
}

fn check_command(paths: &[PathBuf]) -> Result<(), Failure> {
    let mut failures = Vec::new();
    let mut bad_input = 0usize;
    // Each problem is printed once, on its own line, as it is found; the
    // closing error only counts them.
    let mut bad = |m: String| {
        eprintln!("BAD  {}", messages::cut_message(&m));
        bad_input += 1;
    };
    for path in paths {
        let text = match read(path) {
            Ok(t) => t,
            Err(Failure::BadInput(m)) | Err(Failure::Failed(m)) => {
                bad(m);
                continue;
            }
        };
        if is_a_spec(&text, path.parent()) {
            bad(format!(
                "{}: this is a spec, not a certificate: run `verify certify {} -o CERT` first, then check CERT",
                path.display(),
                path.display()
            ));
            continue;
        }
        match spec::check_json(&text, &spec::Options::relative_to(path.parent())) {
            Ok(report) => {
                // Display prints every digit of 3e300 or 3e-300: exponent form there
                let s2 = report
                    .sigma2
                    .map(|x| {
                        if x == 0.0 || (1e-4..1e15).contains(&x.abs()) {
                            format!(", Sigma^2 = {x}")
                        } else {
                            format!(", Sigma^2 = {x:e}")
                        }
                    })
                    .unwrap_or_default();
                let boxed = serde_json::from_str::<Value>(&text).ok().filter(spec::box_cert::is_box_certificate);
                match boxed {
                    // A box's verdict and its bound over the whole box.
                    Some(cert) => println!(
                        "ok   {}: {} box {}{}",
                        path.display(),
                        messages::excerpt(&report.name),
                        cert["verdict"].as_str().unwrap_or("?"),
                        cert.get("sup_sigma2")
                            .map(|x| format!(", sup Sigma^2 <= {}", table::format_number(x)))
                            .unwrap_or_default()
                    ),
                    None => {
                        println!(
                            "ok   {}: {} {}{}",
                            path.display(),
                            messages::excerpt(&report.name),
                            report.verdict,
                            s2
                        )
                    }
                }
            }
            Err(CheckError::BadInput(e)) => bad(format!("{}: {e}", path.display())),
            Err(e) => {
                let m = messages::cut_message(&format!("{}: {e}", path.display()));
                eprintln!("FAIL {m}");
                failures.push(m);
            }
        }
    }
    if !failures.is_empty() {
        return Err(Failure::Failed(format!("{} certificate(s) failed their check", failures.len())));
    }
    if bad_input > 0 {
        return Err(Failure::BadInput(format!(
            "{bad_input} of {} file(s) could not be checked (BAD above)",
            paths.len()
        )));
    }
    Ok(())
}

fn fixtures_dir(given: Option<PathBuf>) -> PathBuf {
    if let Some(d) = given {
        return d;
    }
    let local = PathBuf::from("fixtures");
    if local.is_dir() {
        return local;
    }
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../fixtures"))
}

fn run(cli: Cli) -> Result<(), Failure> {
    match cli.command {
        Some(Command::Certify { spec, output }) => certify_command(&spec, output.as_deref()),
        Some(Command::Check { certificates }) => check_command(&certificates),
        Some(Command::CertifyBox { spec, params, max_depth, max_boxes, output }) => {
            certify_box_command(&spec, &params, max_depth, max_boxes, output.as_deref())
        }
        Some(Command::Schema { which }) => {
            let schema = match which.as_str() {
                "spec" => spec::document::spec_schema(),
                "fluid-spec" => spec::document::fluid_spec_schema(),
                "zeitlin-spec" => spec::document::zeitlin_spec_schema(),
                "certificate" => spec::record::certificate_schema(),
                "zeitlin-certificate" => spec::record::zeitlin_certificate_schema(),
                "large-certificate" => spec::record::large_certificate_schema(),
                "box-certificate" => spec::box_cert::box_certificate_schema(),
                _ => spec::record::fluid_certificate_schema(),
            };
            println!("{}", serde_json::to_string_pretty(&schema).unwrap_or_default());
            Ok(())
        }
        Some(Command::Simulate(args)) => simulate_cmd::run(&args),
        Some(Command::PlotFluid(args)) => fluid_plots::run(&args),
        Some(Command::Report(args)) => report::run(&args),
        Some(Command::Sweep(args)) => sweep_cmd::run(&args),
        Some(Command::Merge(args)) => merge_cmd::run(&args),
        Some(Command::PlotSweep(args)) => sweep_plots::run(&args),
        None => table::fixtures_table(&fixtures_dir(cli.fixtures), cli.write)
            .context("running the fixtures")
            .map_err(|e| Failure::Failed(format!("{e:#}")))
            .and_then(|status| status),
    }
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        // clap quotes a bad option value whole: quote an excerpt instead.
        // Help and version (exit 0) are printed as they are.
        Err(e) if e.use_stderr() => {
            use clap::error::{ContextKind, ContextValue};
            let mut text = e.render().to_string();
            for kind in [ContextKind::InvalidValue, ContextKind::InvalidArg] {
                if let Some(ContextValue::String(value)) = e.get(kind) {
                    text = messages::quoting(text, value);
                }
            }
            eprint!("{}", messages::cut_message(&text));
            return ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(2));
        }
        Err(e) => {
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
    };
    threads::configure_global_pool();
    // Every message is cut to an excerpt when long: the last safety net
    // against echoing a huge input (a 50 MB name or value) back.
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Failed(m)) => {
            eprintln!("error: {}", messages::cut_message(&m));
            ExitCode::from(1)
        }
        Err(Failure::BadInput(m)) => {
            eprintln!("error: {}", messages::cut_message(&m));
            ExitCode::from(2)
        }
    }
}
