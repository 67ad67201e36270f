//! `verify plot-fluid CERT... --out DIR`: charts from fluid certificates —
//! Sigma^2 per x-mode beside the paper's constants, the convergence table,
//! and Sigma^2 along the Galilean-shift curve.

use crate::messages::excerpt;
use crate::paths::{ensure_output_dir, file_stem_noted};
use crate::plots::{write_xy, XyChart};
use crate::Failure;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Arguments of `plot-fluid`.
#[derive(clap::Args)]
pub struct PlotFluidArgs {
    /// Fluid certificates (JSON).
    #[arg(required = true)]
    pub certificates: Vec<PathBuf>,
    /// Output directory.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
}

fn points(rows: &Value, x: &str, y: &str) -> Vec<(f64, f64)> {
    rows.as_array()
        .map(|a| a.iter().filter_map(|r| Some((r.get(x)?.as_f64()?, r.get(y)?.as_f64()?))).collect())
        .unwrap_or_default()
}

/// The charts of a fluid certificate: `(file suffix, chart)` for Sigma^2
/// per x-mode, the convergence table and the Galilean-shift curve, those
/// the certificate has data for (also drawn by `verify report`).
pub(crate) fn fluid_charts(cert: &Value) -> Vec<(&'static str, XyChart)> {
    // The name is data: titles quote an excerpt.
    let name = excerpt(cert["name"].as_str().unwrap_or("fluid"));
    let mut charts = vec![];
    let mut hlines = vec![];
    if let Some(b) = cert.pointer("/paper/bound").and_then(Value::as_f64) {
        hlines.push(("paper's bound sup sum eta'^2".to_string(), b, 1));
    }
    if let Some(p) = cert.pointer("/paper/choice_sigma2").and_then(Value::as_f64) {
        hlines.push(("paper's functional (c = 0)".to_string(), p, 2));
    }
    let modes = points(&cert["modes"], "k", "sigma2");
    if !modes.is_empty() && (modes.iter().any(|(_, s)| *s > 0.0) || hlines.iter().any(|h| h.1 > 0.0)) {
        let zero = modes.iter().all(|(_, s)| *s == 0.0);
        charts.push((
            "modes",
            XyChart {
                title: format!("{name}: Sigma^2 per x-mode{}", if zero { " (ours: 0 for every mode)" } else { "" }),
                x_desc: "x-wavenumber k".into(),
                y_desc: "Sigma^2".into(),
                x_log: true,
                series: vec![(
                    "ours (verified upper bound)".into(),
                    points(&cert["modes"], "k", "sigma2_upper"),
                    0,
                    false,
                )],
                hlines,
            },
        ));
    }
    let table = &cert["convergence"];
    let ours = points(table, "ny", "sigma2");
    let paper = points(table, "ny", "sigma2_paper_choice");
    if let Some(&(_, finest)) = ours.last() {
        let mut series = vec![];
        if finest > 0.0 && ours.len() > 1 {
            let rel: Vec<(f64, f64)> =
                ours[..ours.len() - 1].iter().map(|(n, s)| (*n, ((s - finest) / finest).abs().max(1e-17))).collect();
            series.push(("ours: |Sigma^2(ny) - Sigma^2(finest)| / Sigma^2(finest)".to_string(), rel, 0, false));
        }
        if let Some(&(_, pf)) = paper.last() {
            if pf > 0.0 && paper.len() > 1 {
                let rel: Vec<(f64, f64)> =
                    paper[..paper.len() - 1].iter().map(|(n, s)| (*n, ((s - pf) / pf).abs().max(1e-17))).collect();
                series.push(("paper's functional (c = 0), same measure".to_string(), rel, 2, true));
            }
        }
        if !series.is_empty() {
            charts.push((
                "convergence",
                XyChart {
                    title: format!("{name}: convergence of Sigma^2 under refinement in y"),
                    x_desc: "ny".into(),
                    y_desc: "relative change".into(),
                    x_log: true,
                    series,
                    hlines: vec![],
                },
            ));
        }
    }
    let curve = points(&cert["optimisation"]["shift_curve"], "c", "sigma2");
    if curve.len() > 1 {
        // distance from the admissible edge: the curve starts a quarter of the range beyond it
        let edge = curve[0].0 - (curve[1].0 - curve[0].0) / 3.0;
        let shifted: Vec<(f64, f64)> = curve.iter().map(|(c, s)| ((c - edge).abs(), *s)).collect();
        charts.push((
            "shift",
            XyChart {
                title: format!("{name}: Sigma^2 of H + C + cM (limit: pseudomomentum, 0)"),
                x_desc: "|c - c_edge| (distance of the Galilean shift beyond the admissible edge)".into(),
                y_desc: "Sigma^2 (max over modes)".into(),
                x_log: true,
                series: vec![("Sigma^2(c)".into(), shifted, 0, false)],
                hlines: cert
                    .pointer("/paper/choice_sigma2")
                    .and_then(Value::as_f64)
                    .map(|p| vec![("paper's functional (c = 0)".to_string(), p, 2)])
                    .unwrap_or_default(),
            },
        ));
    }
    charts
}

fn charts(cert: &Value, out: &Path) -> Result<Vec<PathBuf>, Failure> {
    // Files use a safe stem of the name (which is data).
    let full_name = cert["name"].as_str().unwrap_or("fluid");
    let file_stem = file_stem_noted(full_name);
    let mut written = vec![];
    for (suffix, chart) in fluid_charts(cert) {
        let stem = out.join(format!("{file_stem}-{suffix}"));
        write_xy(&stem, &chart).map_err(|e| Failure::Failed(format!("{}: drawing failed: {e}", excerpt(full_name))))?;
        written.push(crate::paths::with_suffix(&stem, ".png"));
    }
    Ok(written)
}

/// Run `plot-fluid`.
pub fn run(args: &PlotFluidArgs) -> Result<(), Failure> {
    ensure_output_dir(&args.out, "--out")?;
    for path in &args.certificates {
        let text = std::fs::read_to_string(path)
            .map_err(|e| Failure::BadInput(format!("{}: cannot read: {e}", path.display())))?;
        let cert: Value = serde_json::from_str(&text)
            .map_err(|e| Failure::BadInput(format!("{}: malformed JSON: {e}", path.display())))?;
        if cert.get("kind").and_then(Value::as_str) != Some("fluid") {
            return Err(Failure::BadInput(format!("{}: $.kind: not a fluid certificate", path.display())));
        }
        for w in charts(&cert, &args.out)? {
            eprintln!("wrote {}", w.display());
        }
    }
    Ok(())
}
