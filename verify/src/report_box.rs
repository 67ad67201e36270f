//! A box certificate in `verify report`: the map of its sub-boxes as inline
//! SVG, coloured by what each proves, and the shares of the box.

use crate::report::escape;
use exact::Rational;
use serde_json::Value;
use std::fmt::Write as _;

fn rational(v: &Value) -> Option<Rational> {
    exact::parse_number(v.as_str()?).ok()
}

/// `lo` and `hi` of a sub-box record, exactly.
fn corners(sub: &Value) -> Option<(Vec<Rational>, Vec<Rational>)> {
    let side = |k: &str| sub.get(k)?.as_array()?.iter().map(rational).collect::<Option<Vec<_>>>();
    Some((side("lo")?, side("hi")?))
}

fn volume(lo: &[Rational], hi: &[Rational]) -> Rational {
    lo.iter().zip(hi).fold(Rational::from(1), |acc, (a, b)| acc * (b - a))
}

/// The share of the box's volume in sub-boxes proved stable, exactly from
/// their corners (0 when the certificate has none).
pub fn stable_share(cert: &Value) -> f64 {
    let Some(subs) = cert.get("sub_boxes").and_then(Value::as_array) else { return 0.0 };
    let (mut stable, mut total) = (Rational::from(0), Rational::from(0));
    for sub in subs {
        let Some((lo, hi)) = corners(sub) else { continue };
        let v = volume(&lo, &hi);
        if sub["verdict"] == "stable" {
            stable += &v;
        }
        total += v;
    }
    if total == Rational::from(0) {
        0.0
    } else {
        exact::rational_to_f64(&(stable / total))
    }
}

/// A share as a percentage with four significant digits.
pub fn percent(x: f64) -> String {
    format!("{}%", spec::theorem::significant(100.0 * x, false))
}

/// The fill of a sub-box by its verdict.
fn colour(verdict: &str) -> &'static str {
    match verdict {
        "stable" => "#8fb0ea",
        "linearly_unstable" => "#ec9c9c",
        "not_an_equilibrium" | "noise_incompatible" => "#e0c77a",
        _ => "#cfcfcf",
    }
}

/// The sub-boxes as an SVG map over the first two box parameters (a strip
/// for one parameter; with more, the projection onto the first two, said
/// in the caption). `None` when there are no sub-boxes.
pub fn sub_box_map(cert: &Value) -> Option<String> {
    let subs = cert.get("sub_boxes")?.as_array()?;
    if subs.is_empty() {
        return None;
    }
    let names: Vec<&str> = cert.get("parameters")?.as_array()?.iter().filter_map(Value::as_str).collect();
    let box_side = |n: &str| -> Option<(f64, f64)> {
        let side = cert.get("spec")?.pointer(&format!("/box/parameters/{n}"))?.as_array()?;
        Some((exact::rational_to_f64(&rational(side.first()?)?), exact::rational_to_f64(&rational(side.get(1)?)?)))
    };
    let x_range = box_side(names.first()?)?;
    let y_range = match names.get(1) {
        Some(n) => Some(box_side(n)?),
        None => None,
    };
    let (w, h, left, top, plot_w) = (720.0, if y_range.is_some() { 520.0 } else { 170.0 }, 80.0, 40.0, 600.0);
    let plot_h = h - top - 70.0;
    let sx = |x: f64| left + plot_w * (x - x_range.0) / (x_range.1 - x_range.0);
    let sy = |y: f64| match y_range {
        Some((lo, hi)) => top + plot_h * (1.0 - (y - lo) / (hi - lo)),
        None => top,
    };
    let mut svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 {w} {h}\" width=\"{w}\" height=\"{h}\" role=\"img\"><title>{}</title>",
        escape(&format!("{}: the sub-boxes", cert["name"].as_str().unwrap_or("?")))
    );
    let opacity = if names.len() > 2 { "0.45" } else { "1" };
    for sub in subs {
        let Some((lo, hi)) = corners(sub) else { continue };
        let f = |r: &Rational| exact::rational_to_f64(r);
        let (x0, x1) = (sx(f(&lo[0])), sx(f(&hi[0])));
        let (y0, y1) = match y_range {
            Some(_) => (sy(f(&hi[1])), sy(f(&lo[1]))),
            None => (top, top + plot_h),
        };
        let _ = write!(
            svg,
            "<rect x=\"{x0:.2}\" y=\"{y0:.2}\" width=\"{:.2}\" height=\"{:.2}\" fill=\"{}\" fill-opacity=\"{opacity}\" stroke=\"#fff\" stroke-width=\"0.4\"/>",
            (x1 - x0).max(0.3),
            (y1 - y0).max(0.3),
            colour(sub["verdict"].as_str().unwrap_or(""))
        );
    }
    let _ = write!(
        svg,
        "<rect x=\"{left}\" y=\"{top}\" width=\"{plot_w}\" height=\"{plot_h}\" fill=\"none\" stroke=\"#333\"/>"
    );
    let label = |v: f64| spec::theorem::significant(v, false);
    let _ = write!(
        svg,
        "<text x=\"{left}\" y=\"{}\" font-size=\"13\">{}</text><text x=\"{}\" y=\"{}\" font-size=\"13\" text-anchor=\"end\">{}</text><text x=\"{}\" y=\"{}\" font-size=\"14\" text-anchor=\"middle\">{}</text>",
        top + plot_h + 18.0,
        label(x_range.0),
        left + plot_w,
        top + plot_h + 18.0,
        label(x_range.1),
        left + plot_w / 2.0,
        top + plot_h + 22.0,
        escape(names[0])
    );
    if let (Some((lo, hi)), Some(n)) = (y_range, names.get(1)) {
        let _ = write!(
            svg,
            "<text x=\"{}\" y=\"{}\" font-size=\"13\" text-anchor=\"end\">{}</text><text x=\"{}\" y=\"{}\" font-size=\"13\" text-anchor=\"end\">{}</text><text x=\"20\" y=\"{}\" font-size=\"14\">{}</text>",
            left - 6.0,
            top + plot_h,
            label(lo),
            left - 6.0,
            top + 12.0,
            label(hi),
            top + plot_h / 2.0,
            escape(n)
        );
    }
    let legend = [
        ("stable", "stable"),
        ("linearly_unstable", "linearly unstable"),
        ("not_an_equilibrium", "not an equilibrium, or noise moves it"),
        ("undecided", "undecided (no claim)"),
    ];
    let mut x = left;
    let y = h - 22.0;
    for (v, text) in legend {
        let _ = write!(
            svg,
            "<rect x=\"{x}\" y=\"{}\" width=\"12\" height=\"12\" fill=\"{}\"/><text x=\"{}\" y=\"{y}\" font-size=\"12\">{text}</text>",
            y - 10.0,
            colour(v),
            x + 16.0
        );
        x += 28.0 + 6.5 * text.len() as f64;
    }
    if names.len() > 2 {
        let _ = write!(
            svg,
            "<text x=\"{left}\" y=\"{}\" font-size=\"12\">projection onto ({}, {}) of a box in {} parameters: sub-boxes overlap here</text>",
            top - 10.0,
            escape(names[0]),
            escape(names[1]),
            names.len()
        );
    }
    svg.push_str("</svg>");
    Some(svg)
}
