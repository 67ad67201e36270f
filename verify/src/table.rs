//! The no-argument run: certify every fixture and print a table.

use crate::messages::{cut_message, excerpt};
use crate::paths::write_atomic;
use crate::Failure;
use serde_json::Value;
use spec::CheckError;
use std::path::{Path, PathBuf};

/// A number (or the string "infinity") in a compact form.
pub fn format_number(v: &Value) -> String {
    match v {
        Value::Number(n) => match n.as_f64() {
            Some(0.0) => "0".into(),
            Some(x) if (1e-3..1e5).contains(&x.abs()) => {
                let s = format!("{x:.6}");
                s.trim_end_matches('0').trim_end_matches('.').to_string()
            }
            Some(x) => format!("{x:.6e}"),
            None => n.to_string(),
        },
        Value::String(s) => s.clone(),
        Value::Null => "-".into(),
        other => other.to_string(),
    }
}

fn spec_files(dir: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    let mut entries: Vec<_> = std::fs::read_dir(dir)?.collect::<Result<_, _>>()?;
    entries.sort_by_key(|e| e.path());
    for e in entries {
        let p = e.path();
        if p.is_dir() {
            spec_files(&p, out)?;
        } else if let Some(name) = p.file_name().and_then(|n| n.to_str()) {
            if name.ends_with(".json") && !name.ends_with(".cert.json") {
                out.push(p);
            }
        }
    }
    Ok(())
}

fn cert_path(spec: &Path) -> PathBuf {
    let name = spec.file_name().and_then(|n| n.to_str()).unwrap_or("spec.json");
    spec.with_file_name(format!("{}.cert.json", name.trim_end_matches(".json")))
}

/// Certify every spec under `dir`; returns the exit status as a nested result.
pub fn fixtures_table(dir: &Path, write: bool) -> anyhow::Result<Result<(), Failure>> {
    let mut specs = Vec::new();
    spec_files(dir, &mut specs).map_err(|e| anyhow::anyhow!("{}: {e}", dir.display()))?;
    if specs.is_empty() {
        return Ok(Err(Failure::BadInput(format!("no specs found under {}", dir.display()))));
    }
    let header = ["name", "verdict", "Sigma^2", "first choice", "T(eps, delta)", "level", "certificate"];
    let mut rows: Vec<[String; 7]> = Vec::new();
    let (mut bad, mut failed) = (0, 0);
    // On a terminal: one line of progress over the specs, and below it a
    // bar for each spec that takes seconds (fluids, Zeitlin, large).
    let multi = indicatif::MultiProgress::new();
    let overall = crate::progress_bar(specs.len() as u64, "{pos}/{len} specs [{bar:30}] {msg}").map(|b| multi.add(b));
    // Messages print above the bars, not through them.
    let say = |m: String| multi.suspend(|| eprintln!("{m}"));
    for path in &specs {
        if let Some(b) = &overall {
            b.set_message(crate::messages::excerpt(&path.display().to_string()));
        }
        let text = std::fs::read_to_string(path)?;
        let spec = match spec::parse(&text, &spec::Options::relative_to(path.parent())) {
            Ok(s) => s,
            Err(e) => {
                bad += 1;
                say(format!("error: {}", cut_message(&format!("{}: {e}", path.display()))));
                let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("?").to_string();
                rows.push([name, "bad input".into(), "-".into(), "-".into(), "-".into(), "-".into(), "-".into()]);
                continue;
            }
        };
        let cert =
            crate::certify_showing_progress(&spec, &path.display().to_string(), overall.as_ref().map(|_| &multi));
        let cpath = cert_path(path);
        if write {
            // Atomic: an interrupted or failed write keeps the committed certificate.
            write_atomic(&cpath, spec::to_pretty_json(&cert).as_bytes())
                .map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", cpath.display()))?;
        }
        let status = match std::fs::read_to_string(&cpath) {
            Err(_) => "missing".to_string(),
            Ok(t) => match spec::check_json(&t, &spec::Options::relative_to(cpath.parent())) {
                Ok(_) => "checked".to_string(),
                Err(CheckError::Failed { path, message }) => {
                    failed += 1;
                    say(format!("FAIL {}", cut_message(&format!("{}: {path}: {message}", cpath.display()))));
                    "FAILED".to_string()
                }
                Err(e) => {
                    failed += 1;
                    say(format!("FAIL {}", cut_message(&format!("{}: {e}", cpath.display()))));
                    "FAILED".to_string()
                }
            },
        };
        let j = &cert;
        let first_choice = j
            .pointer("/optimisation/first_definite_sigma2")
            .or_else(|| j.pointer("/paper/choice_sigma2"))
            .map_or("-".into(), format_number);
        rows.push([
            excerpt(spec.name()),
            j["verdict"].as_str().unwrap_or("?").to_string(),
            j.get("sigma2").or_else(|| j.get("sup_sigma2")).map_or("-".into(), format_number),
            first_choice,
            j.get("stopping").map_or("-".into(), |s| format_number(&s["T"])),
            j["level"].as_str().unwrap_or(if j["kind"] == "box" { "exact (box)" } else { "?" }).to_string(),
            status,
        ]);
        if let Some(b) = &overall {
            b.inc(1);
        }
    }
    if let Some(b) = overall {
        b.finish_and_clear();
    }
    let widths: Vec<usize> = (0..header.len())
        .map(|c| rows.iter().map(|r| r[c].len()).chain([header[c].len()]).max().unwrap_or(0))
        .collect();
    let line = |cells: &[String]| {
        cells.iter().zip(&widths).map(|(c, w)| format!("{c:<w$}")).collect::<Vec<_>>().join("  ").trim_end().to_string()
    };
    println!("{}", line(&header.map(String::from)));
    println!("{}", widths.iter().map(|w| "-".repeat(*w)).collect::<Vec<_>>().join("  "));
    for r in &rows {
        println!("{}", line(r));
    }
    if failed > 0 {
        return Ok(Err(Failure::Failed(format!("{failed} committed certificate(s) failed their check"))));
    }
    if bad > 0 {
        return Ok(Err(Failure::BadInput(format!("{bad} spec(s) are bad input"))));
    }
    Ok(Ok(()))
}
