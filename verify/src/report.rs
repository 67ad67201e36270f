//! `verify report CERT... -o report.html`: one self-contained HTML page for
//! a set of certificates, for a person or a CI artifact.
//!
//! Per certificate: the verdict in words, what was proved and at which
//! level (the certificate's `checks`), the key numbers, the Casimir choice,
//! the result of re-checking it (the engine re-derives everything, as
//! `verify check` does), and charts as inline SVG: for a stable
//! certificate, the guarantee `(delta/epsilon) e^(Sigma^2 t)` over time;
//! for fluids, `Sigma^2` per x-mode, the convergence table and the Galilean
//! shift. No script, no style sheet, font or image is fetched: the page is
//! one file, and its Content-Security-Policy (`default-src 'none'`) makes a
//! browser refuse any fetch (and log it). Every string from a certificate
//! is escaped (names are data).

use crate::messages::cut_message;
use crate::paths::write_output;
use crate::plots::{xy_svg, XyChart};
use crate::table::format_number;
use crate::Failure;
use serde_json::Value;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Arguments of `report`.
#[derive(clap::Args)]
pub struct ReportArgs {
    /// Certificates (JSON).
    #[arg(required = true)]
    pub certificates: Vec<PathBuf>,
    /// The HTML file to write (`-o -`: stdout).
    #[arg(short, long)]
    pub output: PathBuf,
}

/// `text` with `&`, `<`, `>`, `"` and `'` escaped for HTML.
pub(crate) fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

fn kind(cert: &Value) -> &str {
    cert.get("kind").and_then(Value::as_str).unwrap_or("finite")
}

/// What the certificate claims: its own statement (`theorem`, re-derived
/// by `check`), or, for a certificate without one, the verdict in words.
fn in_words(cert: &Value) -> String {
    if let Some(t) = cert.pointer("/theorem/statement").and_then(Value::as_str) {
        return t.to_string();
    }
    fallback_words(cert)
}

/// The verdict in a sentence, for a certificate with no `theorem`.
fn fallback_words(cert: &Value) -> String {
    let verdict = cert["verdict"].as_str().unwrap_or("?");
    let stopping = cert.get("stopping");
    let number = |p: &str| stopping.and_then(|s| s.get(p)).map(format_number).unwrap_or_else(|| "?".into());
    match verdict {
        "stable" => {
            let guarantee = match stopping {
                Some(_) => format!(
                    " For |dmu_0|_P^2 = delta = {}, P(|dmu_t|_P^2 > epsilon = {}) <= (delta/epsilon) exp(Sigma^2 t) at each fixed time t, below 1 until T(epsilon, delta) = {}.",
                    number("delta"),
                    number("epsilon"),
                    number("T")
                ),
                None => String::new(),
            };
            format!(
                "Stable for the linearised SDE: a conserved form P is definite at the equilibrium, and E|dmu_t|_P^2 <= |dmu_0|_P^2 exp(Sigma^2 t) with Sigma^2 = {}.{guarantee}",
                cert.get("sigma2_upper").or(cert.get("sigma2")).map(format_number).unwrap_or_else(|| "?".into())
            )
        }
        "linearly_unstable" => {
            "Unstable: the linearised drift has an eigenvalue with positive real part, so small perturbations grow.".into()
        }
        "not_an_equilibrium" => "Not an equilibrium: the drift does not vanish at the state given.".into(),
        "noise_incompatible" => {
            "The noise moves the equilibrium (it does not preserve it), so stability in probability is not defined there; the certificate names the compatible part.".into()
        }
        _ => "Inconclusive: nothing is claimed either way (the reason says what is missing).".into(),
    }
}

/// What a verification level means.
fn level_in_words(level: &str) -> &'static str {
    match level {
        "exact" => "every claim is proved in exact rational arithmetic",
        "exact_structure" => "Sigma^2 = 0 holds by the structure of the conserved form, proved exactly",
        "verified_float" => "the bounds are proved in floating point with every rounding error accounted for",
        "numerical" | "float" => "floating point, not proved: a careful computation, not a proof",
        _ => "no claim needs a proof",
    }
}

/// The level a certificate states; a box certificate's proofs are exact
/// (its `theorem.status` says whether anything is claimed).
fn level_of(cert: &Value) -> &str {
    match cert["level"].as_str() {
        Some(l) => l,
        None if kind(cert) == "box" && cert.pointer("/theorem/status").and_then(Value::as_str) == Some("proved") => {
            "exact"
        }
        None => "none",
    }
}

/// The certificate's `Sigma^2` for the summary: the pointwise value, or a
/// box's proved sup.
fn sigma2_of(cert: &Value) -> Option<&Value> {
    cert.get("sigma2_upper").or(cert.get("sigma2")).or(cert.get("sup_sigma2"))
}

fn row(out: &mut String, key: &str, value: &str) {
    let _ = write!(out, "<tr><th>{}</th><td>{}</td></tr>", escape(key), escape(value));
}

fn rationals(v: &Value) -> String {
    match v {
        Value::Array(a) => format!("[{}]", a.iter().map(rationals).collect::<Vec<_>>().join(", ")),
        Value::String(s) => s.clone(),
        other => format_number(other),
    }
}

/// The guarantee over time: `(delta/epsilon) e^(Sigma^2 t)` up to where it
/// reaches 1 (twice T), on a log scale.
fn guarantee_chart(cert: &Value) -> Option<XyChart> {
    let s = cert.get("sigma2_upper").or(cert.get("sigma2"))?.as_f64()?;
    let stopping = cert.get("stopping")?;
    let (e, d) = (stopping.get("epsilon")?.as_f64()?, stopping.get("delta")?.as_f64()?);
    let t = stopping.get("T")?.as_f64()?;
    if !(s > 0.0 && (2.0 * t).is_finite() && t > 0.0 && e > d && d > 0.0) {
        return None;
    }
    let points: Vec<(f64, f64)> =
        (0..=24).map(|i| 2.0 * t * i as f64 / 24.0).map(|x| (x, d / e * (s * x).exp())).collect();
    Some(XyChart {
        title: format!("{}: the guarantee over time", crate::messages::excerpt(cert["name"].as_str().unwrap_or("?"))),
        x_desc: "t".into(),
        y_desc: "bound on P(|dmu_t|^2 > epsilon)".into(),
        x_log: false,
        series: vec![("(delta/epsilon) exp(Sigma^2 t)".into(), points, 2, false)],
        hlines: vec![("probability 1: the bound says nothing from T on".into(), 1.0, 1)],
    })
}

fn section(out: &mut String, path: &Path, cert: &Value, check: &Result<spec::CheckReport, spec::CheckError>) {
    let name = cert["name"].as_str().unwrap_or("?");
    let verdict = cert["verdict"].as_str().unwrap_or("?");
    let level = level_of(cert);
    let _ = write!(
        out,
        "<section><h2>{}</h2><p class=\"file\">{}</p><p><span class=\"verdict {}\">{}</span> <span class=\"level\">level: {} ({})</span></p>",
        escape(name),
        escape(&path.display().to_string()),
        escape(verdict),
        escape(verdict),
        escape(level),
        level_in_words(level)
    );
    let _ = write!(out, "<p class=\"words\">{}</p>", escape(&in_words(cert)));
    if let Some(t) = cert.pointer("/theorem/not_checked").and_then(Value::as_str) {
        let _ = write!(out, "<p class=\"limits\">Not checked: {}</p>", escape(t));
    }
    if let Some(reason) = cert["reason"].as_str() {
        let _ = write!(out, "<p class=\"reason\">{}</p>", escape(reason));
    }
    match check {
        Ok(_) => out.push_str(
            "<p class=\"check ok\">Re-checked now: every claim re-derived from the embedded spec and confirmed.</p>",
        ),
        Err(e) => {
            let _ =
                write!(out, "<p class=\"check failed\">Re-check FAILED: {}</p>", escape(&cut_message(&e.to_string())));
        }
    }
    out.push_str("<h3>Key numbers</h3><table>");
    row(out, "kind", kind(cert));
    for (key, label) in
        [("sigma2", "Sigma^2"), ("sigma2_exact", "Sigma^2, exact"), ("sigma2_upper", "Sigma^2, proved upper bound")]
    {
        if let Some(v) = cert.get(key) {
            row(out, label, &format_number(v));
        }
    }
    if let Some(s) = cert.get("stopping") {
        for (key, label) in
            [("epsilon", "epsilon"), ("delta", "delta"), ("T", "T(epsilon, delta)"), ("bound", "the bound")]
        {
            if let Some(v) = s.get(key) {
                row(out, label, &format_number(v));
            }
        }
    }
    match kind(cert) {
        "fluid" => {
            for (p, label) in [
                ("/model", "model"),
                ("/discretisation/ny", "ny"),
                ("/discretisation/x_modes", "x-modes"),
                ("/form/kind", "conserved form"),
                ("/form/casimir_weight", "Casimir weight"),
                ("/form/galilean_shift", "Galilean shift"),
            ] {
                if let Some(v) = cert.pointer(p) {
                    row(out, label, &format_number(v));
                }
            }
        }
        "zeitlin" => {
            for (p, label) in [
                ("/spec/zeitlin/N", "N"),
                ("/form/energy_coefficient", "energy coefficient"),
                ("/form/momentum_coefficient", "momentum coefficient"),
            ] {
                if let Some(v) = cert.pointer(p) {
                    row(out, label, &format_number(v));
                }
            }
        }
        "large" => {
            if let Some(v) = cert.get("dimension") {
                row(out, "dimension", &format_number(v));
            }
        }
        "box" => box_rows(out, cert),
        _ => {
            if let Some(c) = cert.get("casimir_choice") {
                for (key, label) in
                    [("multipliers", "multipliers lambda"), ("M", "Casimir Hessian M"), ("sign", "sign of P")]
                {
                    if let Some(v) = c.get(key) {
                        row(out, label, &rationals(v));
                    }
                }
            }
        }
    }
    out.push_str("</table>");
    if let Some(checks) = cert.get("checks").and_then(Value::as_object) {
        out.push_str("<h3>What was proved, and how</h3><table>");
        for (k, v) in checks {
            row(out, k, v.as_str().unwrap_or(&v.to_string()));
        }
        out.push_str("</table>");
    }
    let mut charts: Vec<XyChart> = vec![];
    if verdict == "stable" {
        charts.extend(guarantee_chart(cert));
    }
    if kind(cert) == "fluid" {
        charts.extend(crate::fluid_plots::fluid_charts(cert).into_iter().map(|(_, c)| c));
    }
    if kind(cert) == "box" {
        match crate::report_box::sub_box_map(cert) {
            Some(svg) => {
                let _ = write!(out, "<figure>{svg}</figure>");
            }
            None => out.push_str("<p>(no map: the certificate has no sub-boxes)</p>"),
        }
    }
    for chart in &charts {
        match xy_svg(chart, (900, 520)) {
            Ok(svg) => {
                let _ = write!(out, "<figure>{svg}</figure>");
            }
            Err(e) => {
                let _ = write!(out, "<p>(a chart could not be drawn: {})</p>", escape(&e.to_string()));
            }
        }
    }
    out.push_str("</section>");
}

const STYLE: &str = "body{font-family:sans-serif;max-width:960px;margin:2em auto;padding:0 1em;color:#222}\
h1{font-size:1.6em}section{border-top:2px solid #ccc;margin-top:2em;padding-top:1em}\
.file{color:#666;font-size:.9em;margin-top:-.5em}.verdict{font-weight:bold;padding:.2em .6em;border-radius:4px;color:#fff;background:#777}\
.verdict.stable{background:#2a62c9}.verdict.partly_stable{background:#6f8fcf}.verdict.partly_unstable{background:#c86a6a}.verdict.linearly_unstable{background:#c82828}.verdict.noise_incompatible{background:#8c3caa}\
.verdict.not_an_equilibrium{background:#b48c14}.level{color:#444}.words{font-size:1.05em}.limits{color:#555;font-size:.95em}.reason{color:#444;font-style:italic}\
.check.ok{color:#17703a}.check.failed{color:#c82828;font-weight:bold}table{border-collapse:collapse;margin:.5em 0}\
th,td{border:1px solid #ddd;padding:.3em .6em;text-align:left;vertical-align:top;font-size:.92em}th{background:#f4f4f4}\
figure{margin:1em 0}svg{max-width:100%;height:auto}";

/// Run `report`.
pub fn run(args: &ReportArgs) -> Result<(), Failure> {
    crate::paths::check_output_file(&args.output, "-o")?;
    crate::plots::register_font();
    let mut body = String::new();
    let mut summary = String::from(
        "<table><tr><th>certificate</th><th>verdict</th><th>level</th><th>Sigma^2 (proved bound where there is one)</th><th>re-check</th></tr>",
    );
    let mut failed = 0usize;
    for path in &args.certificates {
        let text = std::fs::read_to_string(path)
            .map_err(|e| Failure::BadInput(format!("{}: cannot read: {e}", path.display())))?;
        let cert: Value = serde_json::from_str(&text)
            .map_err(|e| Failure::BadInput(format!("{}: malformed JSON: {e}", path.display())))?;
        if !cert.is_object() || cert.get("verdict").is_none() || cert.get("spec").is_none() {
            return Err(Failure::BadInput(format!(
                "{}: $: not a certificate (no verdict or spec): run `verify certify` on a spec first",
                path.display()
            )));
        }
        let check = spec::check_json(&text, &spec::Options::relative_to(path.parent()));
        if check.is_err() {
            failed += 1;
        }
        let _ = write!(
            summary,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            escape(cert["name"].as_str().unwrap_or("?")),
            escape(cert["verdict"].as_str().unwrap_or("?")),
            escape(level_of(&cert)),
            escape(&sigma2_of(&cert).map(format_number).unwrap_or_else(|| "-".into())),
            if check.is_ok() { "passed" } else { "FAILED" }
        );
        section(&mut body, path, &cert, &check);
    }
    summary.push_str("</table>");
    let html = format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; style-src 'unsafe-inline'\"><title>Stability certificates</title><style>{STYLE}</style></head><body><h1>Stochastic energy–Casimir stability certificates</h1><p>Engine {}. Each certificate below was re-checked when this page was written.</p>{summary}{body}</body></html>\n",
        escape(spec::ENGINE_VERSION)
    );
    write_output(&args.output, html.as_bytes()).map_err(|e| crate::paths::write_failure(&args.output, &e))?;
    eprintln!("wrote {} ({} certificate(s))", crate::paths::shown(&args.output), args.certificates.len());
    if failed > 0 {
        return Err(Failure::Failed(format!(
            "{failed} certificate(s) failed their re-check (marked FAILED in the report)"
        )));
    }
    Ok(())
}

/// A box certificate's key numbers: the box, the sup and where it is
/// approached, the shares of the box by verdict, the sub-boxes.
fn box_rows(out: &mut String, cert: &Value) {
    if let (Some(names), Some(spec)) = (cert.get("parameters").and_then(Value::as_array), cert.get("spec")) {
        for n in names.iter().filter_map(Value::as_str) {
            if let Some(side) = spec.pointer(&format!("/box/parameters/{n}")) {
                row(out, &format!("box: {n}"), &rationals(side));
            }
        }
    }
    if let Some(v) = cert.get("sup_sigma2_exact") {
        row(out, "sup Sigma^2 over the stable sub-boxes (proved, exact)", &rationals(v));
    }
    if let Some(m) = cert.get("sampled_max") {
        row(
            out,
            "largest Sigma^2 sampled, and where (the sup is approached there)",
            &format!("{} at {}", format_number(&m["sigma2"]), rationals(&m["at"])),
        );
    }
    let share = |key: &str| cert.get(key).and_then(Value::as_f64);
    let (undecided, unstable, excluded) = (
        share("undecided_fraction").unwrap_or(0.0),
        share("unstable_fraction").unwrap_or(0.0),
        share("excluded_fraction"),
    );
    let stable = crate::report_box::stable_share(cert);
    row(out, "share of the box proved stable", &crate::report_box::percent(stable));
    row(out, "share proved linearly unstable", &crate::report_box::percent(unstable));
    if let Some(x) = excluded {
        row(out, "share proved not an equilibrium or noise-incompatible", &crate::report_box::percent(x));
    }
    row(out, "share undecided", &crate::report_box::percent(undecided));
    let subs = cert.get("sub_boxes").and_then(Value::as_array).map_or(0, Vec::len);
    row(out, "sub-boxes", &subs.to_string());
    if let Some(l) = cert.get("limit").and_then(Value::as_str) {
        row(out, "bisection stopped by", l);
    }
}
