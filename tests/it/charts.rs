//! Every chart type through the `verify` binary (simulate: density, with
//! the isotropic noise's mean, and growth; plot-sweep: map and line charts; plot-fluid: per-mode,
//! convergence and shift charts): each is written as SVG and PNG, and every
//! tick label in the SVG is a short number in the axis formats (the growth
//! chart's labels once overflowed as `0000000000.0` and switched to 16
//! digits). PNG text itself: `png::tests` in the binary.

use std::path::{Path, PathBuf};
use std::process::Command;

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

fn verify(args: &[&str]) {
    let o = Command::new(env!("CARGO_BIN_EXE_verify")).current_dir(ROOT).args(args).output().expect("run verify");
    assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
}

/// The text of every `<text>` element.
fn texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| Some(t.split_once('>')?.1.split("</text>").next()?.trim().to_string()))
        .collect()
}

fn files(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().and_then(|e| e.to_str()) == Some(ext))
        .collect();
    v.sort();
    v
}

#[test]
fn every_chart_type_has_short_numeric_ticks_and_a_png() {
    let out = std::env::temp_dir().join(format!("verify-charts-{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    let o = out.to_str().unwrap();
    verify(&[
        "simulate",
        "fixtures/rigid-body-major-axis.json",
        "--paths",
        "300",
        "--t-end",
        "40",
        "--compare-isotropic",
        "--out",
        o,
    ]);
    // The paper's figure: the isotropic noise's mean beside the compatible one.
    let density = std::fs::read_to_string(out.join("rigid-body-major-axis-density.svg")).unwrap();
    assert!(texts(&density).iter().any(|t| t == "mean, isotropic noise (same amplitude)"));
    for s in ["lagrange-top-map", "heavy-top-gravity"] {
        let lines = format!("fixtures/sweeps/{s}.jsonl");
        let spec = format!("fixtures/sweeps/{s}.json");
        verify(&["plot-sweep", &lines, "--spec", &spec, "--out", o]);
    }
    verify(&[
        "plot-fluid",
        "fixtures/fluids/rayleigh-cos-walls.cert.json",
        "fixtures/fluids/channel-sin-walls.cert.json",
        "--out",
        o,
    ]);
    let svgs = files(&out, "svg");
    let kinds = ["-density", "-growth", "-map", "-sigma2", "-T", "-modes", "-convergence", "-shift"];
    for k in kinds {
        assert!(svgs.iter().any(|p| p.to_string_lossy().contains(k)), "no {k} chart among {svgs:?}");
    }
    for svg in &svgs {
        let png = svg.with_extension("png");
        assert!(std::fs::metadata(&png).map(|m| m.len() > 10_000).unwrap_or(false), "{}", png.display());
        let text = std::fs::read_to_string(svg).unwrap();
        let numeric: Vec<String> = texts(&text)
            .into_iter()
            .filter(|t| !t.is_empty() && t.chars().all(|c| c.is_ascii_digit() || "-.e+".contains(c)))
            .collect();
        assert!(numeric.len() >= 4, "{}: {numeric:?}", svg.display());
        for t in &numeric {
            assert!(t.len() <= 7 && t.parse::<f64>().is_ok(), "{}: tick {t:?}", svg.display());
            assert!(!t.ends_with(".0"), "{}: tick {t:?} (a whole number written with .0)", svg.display());
        }
    }
}

/// The isotropic comparison is a plain run's: with a shard it is refused
/// (exit 2, naming both options).
#[test]
fn the_isotropic_comparison_is_not_sharded() {
    let o = Command::new(env!("CARGO_BIN_EXE_verify"))
        .current_dir(ROOT)
        .args(["simulate", "fixtures/rigid-body-major-axis.json", "--compare-isotropic", "--shard", "0/2"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--compare-isotropic") && err.contains("--shard"), "{err}");
}
