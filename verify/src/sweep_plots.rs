//! `verify plot-sweep LINES... --spec SPEC --out DIR`: stability maps from
//! sweep lines.
//!
//! * Two swept parameters: a map coloured by verdict (blue stable, red
//!   linearly unstable, grey inconclusive, ...), stable points shaded by
//!   `Sigma^2` (or `log T`), unstable ones by the growth rate; the spec's
//!   analytic boundaries drawn as curves (zero sets, by marching squares on
//!   a fine grid), and where the spec gives a reference `Sigma^2` (the
//!   paper's claim), the points where the sharp constant exceeds it marked.
//! * One swept parameter: `Sigma^2` and `T(eps, delta)` against it, with
//!   the reference constants dashed beside the engine's.

use crate::messages::excerpt;
use crate::paths::{ensure_output_dir, file_stem_noted, with_suffix};
use crate::plots::{draw_file, linear_ticks, palette, register_font, DrawResult, Legend, Mark};
use crate::{read, Failure};
use plotters::coord::Shift;
use plotters::prelude::*;
use serde_json::Value;
use spec::{Annotation, AnySpec};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Arguments of `plot-sweep`.
#[derive(clap::Args)]
pub struct PlotSweepArgs {
    /// Sweep output files (JSON lines; shards may be given together).
    #[arg(required = true)]
    pub lines: Vec<PathBuf>,
    /// The spec that was swept (for boundaries, reference constants and the
    /// fixed parameter values).
    #[arg(long)]
    pub spec: PathBuf,
    /// Output directory.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Shade stable points by `sigma2` (default) or `logT`.
    #[arg(long, default_value = "sigma2")]
    pub shade: String,
    /// A box certificate of the same spec over the two swept parameters
    /// (docs/boxes.md): its sub-boxes are drawn under the points, after
    /// the certificate is checked and every point inside a stable sub-box
    /// is checked to be stable with `Sigma^2` at most the sub-box's bound.
    #[arg(long = "box")]
    pub box_certificate: Option<PathBuf>,
}

/// A sub-box of a box certificate, in the map's two parameters.
#[derive(Clone, Debug)]
struct SubBox {
    lo: [exact::Rational; 2],
    hi: [exact::Rational; 2],
    /// The proved bound, if stable.
    bound: Option<exact::Rational>,
    /// Whether linear instability is proved on it.
    unstable: bool,
}

/// Read and check a box certificate for a map over `names` of `spec`.
fn read_box(path: &Path, spec: &AnySpec, names: &[String]) -> Result<Vec<SubBox>, Failure> {
    let bad = |m: String| Failure::BadInput(format!("{}: {m}", path.display()));
    let text = read(path)?;
    let cert: Value = serde_json::from_str(&text).map_err(|e| bad(format!("not JSON: {e}")))?;
    if !spec::box_cert::is_box_certificate(&cert) {
        return Err(bad("not a box certificate (kind \"box\")".into()));
    }
    spec::check_certificate_value(&cert)
        .map_err(|e| Failure::Failed(format!("{}: the box certificate fails its check: {e}", path.display())))?;
    // The box's system must be the swept one: the fields that define it
    // agree (the name, the description, the stopping question and the
    // sections for sweeps and boxes may differ).
    for key in ["algebra", "parameters", "hamiltonian", "casimirs", "first_integrals", "equilibrium", "noise"] {
        if cert["spec"].get(key) != spec.raw().get(key) {
            return Err(bad(format!("its spec's {key} is not the swept spec's")));
        }
    }
    let params: Vec<String> =
        cert["parameters"].as_array().into_iter().flatten().filter_map(|v| v.as_str().map(String::from)).collect();
    let index: Vec<usize> = names
        .iter()
        .map(|n| params.iter().position(|p| p == n))
        .collect::<Option<Vec<_>>>()
        .filter(|_| params.len() == names.len())
        .ok_or_else(|| bad(format!("its parameters {params:?} are not the swept {names:?}")))?;
    let rational = |v: &Value| exact::parse_certificate_rational(v.as_str().unwrap_or("")).ok();
    let mut out = Vec::new();
    for sub in cert["sub_boxes"].as_array().into_iter().flatten() {
        let side = |which: &str, k: usize| rational(&sub[which][index[k]]);
        let (Some(a), Some(b), Some(c), Some(d)) = (side("lo", 0), side("lo", 1), side("hi", 0), side("hi", 1)) else {
            return Err(bad("a sub-box without its corners".into()));
        };
        let bound = if sub["verdict"] == "stable" {
            sub["sigma2_upper"].as_str().and_then(|t| exact::parse_certificate_rational(t).ok())
        } else {
            None
        };
        out.push(SubBox { lo: [a, b], hi: [c, d], bound, unstable: sub["verdict"] == "linearly_unstable" });
    }
    Ok(out)
}

/// Every point inside a stable sub-box (exactly, by its exact parameters)
/// is stable with `Sigma^2` at most the sub-box's bound, and every point
/// inside a sub-box proved linearly unstable is linearly unstable.
fn check_points_in_boxes(points: &[Point], boxes: &[SubBox]) -> Result<usize, Failure> {
    let mut inside = 0;
    for p in points {
        let Some(x) = &p.exact else { continue };
        for b in boxes.iter().filter(|b| b.unstable) {
            if (0..2).all(|k| b.lo[k] <= x[k] && x[k] <= b.hi[k]) {
                inside += 1;
                if p.verdict != "linearly_unstable" {
                    return Err(Failure::Failed(format!(
                        "the sweep point ({}, {}) lies in a sub-box proved linearly unstable, but the sweep says {}",
                        x[0], x[1], p.verdict
                    )));
                }
            }
        }
        for b in boxes.iter().filter(|b| b.bound.is_some()) {
            if (0..2).all(|k| b.lo[k] <= x[k] && x[k] <= b.hi[k]) {
                inside += 1;
                let bound = b.bound.as_ref().map(exact::rational_to_f64_up).unwrap_or(f64::NAN);
                let ok = p.verdict == "stable" && p.sigma2.is_some_and(|s| s <= bound);
                if !ok {
                    return Err(Failure::Failed(format!(
                        "the sweep point ({}, {}) lies in a stable sub-box with Sigma^2 <= {bound:e}, but the sweep says {} (Sigma^2 {:?})",
                        x[0], x[1], p.verdict, p.sigma2
                    )));
                }
            }
        }
    }
    Ok(inside)
}

/// One point read back.
#[derive(Clone, Debug)]
struct Point {
    x: Vec<f64>,
    verdict: String,
    sigma2: Option<f64>,
    t: Option<f64>,
    growth: Option<f64>,
    /// The exact parameters (the first two), when the line has them.
    exact: Option<[exact::Rational; 2]>,
}

/// Run `plot-sweep`.
pub fn run(args: &PlotSweepArgs) -> Result<(), Failure> {
    let shade = match args.shade.as_str() {
        "sigma2" => Shade::Sigma2,
        "logT" | "logt" => Shade::LogT,
        other => {
            return Err(Failure::BadInput(format!("--shade: unknown '{}' (expected sigma2 or logT)", excerpt(other))))
        }
    };
    let written = plot_files(&args.lines, &args.spec, &args.out, Some(shade), args.box_certificate.as_deref())?;
    for w in written {
        println!("{}", w.display());
    }
    Ok(())
}

/// How stable points are shaded.
#[derive(Clone, Copy, PartialEq)]
pub enum Shade {
    /// Darker = larger `Sigma^2`.
    Sigma2,
    /// Darker = shorter `T` (log scale).
    LogT,
}

/// Read the lines and the spec and draw the charts; returns the PNG paths.
pub fn plot_files(
    lines: &[PathBuf],
    spec_path: &Path,
    out: &Path,
    shade: Option<Shade>,
    box_certificate: Option<&Path>,
) -> Result<Vec<PathBuf>, Failure> {
    let spec = spec::parse(&read(spec_path)?, &spec::Options::relative_to(spec_path.parent()))
        .map_err(|e| Failure::BadInput(format!("{}: {e}", spec_path.display())))?;
    let known = spec.parameter_names();
    let tag = sweep::spec_tag(&spec);
    let mut untagged = 0usize;
    let mut names: Option<Vec<String>> = None;
    let mut id: Option<String> = None;
    let mut points = Vec::new();
    for path in lines {
        let text = read(path)?;
        for (k, line) in text.lines().enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            let at = |m: &str| Failure::BadInput(format!("{}:{}: {m}", path.display(), k + 1));
            let v: Value = serde_json::from_str(line).map_err(|e| at(&format!("not JSON: {e}")))?;
            let this_id = v["sweep"].as_str().ok_or_else(|| at("not a sweep record (no \"sweep\" id)"))?;
            match &id {
                None => id = Some(this_id.to_string()),
                Some(i) if i != this_id => {
                    return Err(at(&format!(
                        "a record of another sweep ({}, the first line's is {})",
                        excerpt(this_id),
                        excerpt(i)
                    )))
                }
                _ => {}
            }
            // The lines' spec must be this spec: a map drawn from one
            // system's lines under another's name and boundaries is wrong.
            match v["spec"].as_str() {
                Some(t) if t == tag => {}
                Some(t) => {
                    return Err(at(&format!(
                        "these lines are a sweep of another spec (spec tag {}; {} has {tag}): pass the spec that was swept as --spec",
                        excerpt(t),
                        spec_path.display()
                    )))
                }
                None => untagged += 1,
            }
            let params = v["parameters"].as_object().ok_or_else(|| at("no \"parameters\" object"))?;
            let these: Vec<String> = order(params.keys().cloned().collect(), &spec);
            if names.get_or_insert_with(|| these.clone()) != &these {
                return Err(at("the swept parameters differ from the first line's"));
            }
            if let Some(unknown) = these.iter().find(|n| !known.contains(n)) {
                return Err(at(&format!("'{}' is not a parameter of the spec", excerpt(unknown))));
            }
            let Some(verdict) = v["verdict"].as_str() else { continue };
            let x = these.iter().map(|n| params[n.as_str()].as_f64().unwrap_or(f64::NAN)).collect();
            let exact_of = |n: &String| {
                v["exact_parameters"][n.as_str()].as_str().and_then(|t| exact::parse_certificate_rational(t).ok())
            };
            let exact = match these.as_slice() {
                [a, b] => exact_of(a).zip(exact_of(b)).map(|(a, b)| [a, b]),
                _ => None,
            };
            points.push(Point {
                x,
                verdict: verdict.to_string(),
                sigma2: v["sigma2"].as_f64(),
                t: if v["T"] == "infinity" { Some(f64::INFINITY) } else { v["T"].as_f64() },
                growth: v["growth_rate"].as_f64(),
                exact,
            });
        }
    }
    let names = names.ok_or_else(|| Failure::BadInput("no sweep lines to plot".into()))?;
    if untagged > 0 {
        eprintln!(
            "note: {untagged} line(s) carry no spec tag (written by an older engine): not checked against --spec"
        );
    }
    ensure_output_dir(out, "--out")?;
    // The name is data: a safe stem keeps every file inside the directory.
    let stem = out.join(file_stem_noted(spec.name()));
    let fail = |e: Box<dyn std::error::Error>| Failure::Failed(format!("drawing failed: {e}"));
    let fixed = fixed_values(&spec);
    match names.len() {
        1 => {
            let chart = LineCharts { spec: &spec, name: &names[0], points: &points, fixed: &fixed };
            chart.write(&stem).map_err(fail)?;
            Ok(vec![png(&stem, "sigma2"), png(&stem, "T")])
        }
        2 => {
            let boxes = match box_certificate {
                Some(path) => {
                    let boxes = read_box(path, &spec, &names)?;
                    let inside = check_points_in_boxes(&points, &boxes)?;
                    eprintln!(
                        "{}: checked; {inside} sweep point(s) lie in its proved sub-boxes, all with the proved verdict (stable within the bound)",
                        path.display()
                    );
                    boxes
                }
                None => vec![],
            };
            let map = Map {
                spec: &spec,
                names: [&names[0], &names[1]],
                points: &points,
                fixed: &fixed,
                shade: shade.unwrap_or(Shade::Sigma2),
                boxes: &boxes,
            };
            map.write(&stem).map_err(fail)?;
            Ok(vec![png(&stem, "map")])
        }
        _ if box_certificate.is_some() => {
            Err(Failure::BadInput("--box: a box is drawn on maps of two swept parameters".into()))
        }
        n => Err(Failure::BadInput(format!(
            "{n} swept parameters: maps are drawn for one or two (sweep fewer, or fix the others)"
        ))),
    }
}

fn png(stem: &Path, what: &str) -> PathBuf {
    with_suffix(stem, &format!("-{what}.png"))
}

/// The swept names in the spec's range order when it has one, else as read.
fn order(mut names: Vec<String>, spec: &AnySpec) -> Vec<String> {
    let pos = |n: &String| spec.sweep().ranges.iter().position(|r| &r.name == n).unwrap_or(usize::MAX);
    names.sort_by_key(pos);
    names
}

fn fixed_values(spec: &AnySpec) -> BTreeMap<String, f64> {
    spec.parameters().iter().map(|(k, v)| (k.clone(), spec::to_f64(v))).collect()
}

fn eval(a: &Annotation, fixed: &BTreeMap<String, f64>, swept: &[(&str, f64)]) -> f64 {
    a.eval(|n| swept.iter().find(|(m, _)| *m == n).map(|(_, v)| *v).or_else(|| fixed.get(n).copied()))
}

/// A box certificate's sub-box: pale blue (stable), pale red (linearly
/// unstable) or grey (undecided).
fn box_fill(stable: bool, unstable: bool) -> RGBColor {
    if stable {
        tint(verdict_colour("stable"), 0.12)
    } else if unstable {
        tint(verdict_colour("linearly_unstable"), 0.12)
    } else {
        RGBColor(225, 225, 225)
    }
}

fn verdict_colour(v: &str) -> RGBColor {
    match v {
        "stable" => RGBColor(40, 90, 200),
        "linearly_unstable" => RGBColor(200, 40, 40),
        "inconclusive" => RGBColor(150, 150, 150),
        "not_an_equilibrium" => RGBColor(220, 180, 40),
        _ => RGBColor(140, 60, 170),
    }
}

/// The colour of stable cells with `Sigma^2 = 0` (teal: apart from the
/// blue shades of positive `Sigma^2` and from every verdict's colour).
const ZERO_GROWTH: RGBColor = RGBColor(40, 170, 150);

/// Mix `c` towards white: `t = 0` white, `t = 1` the full colour.
fn tint(c: RGBColor, t: f64) -> RGBColor {
    let t = t.clamp(0.0, 1.0);
    let f = |x: u8| (255.0 - (255.0 - x as f64) * t) as u8;
    RGBColor(f(c.0), f(c.1), f(c.2))
}

struct Map<'a> {
    spec: &'a AnySpec,
    names: [&'a str; 2],
    points: &'a [Point],
    fixed: &'a BTreeMap<String, f64>,
    shade: Shade,
    /// A box certificate's sub-boxes, drawn under the points.
    boxes: &'a [SubBox],
}

fn range_of(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) =
        v.filter(|x| x.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| (l.min(x), h.max(x)));
    if lo.is_finite() {
        (lo, hi)
    } else {
        (0.0, 1.0)
    }
}

/// The spacing of sorted distinct values (the grid step), if regular.
fn step(values: impl Iterator<Item = f64>) -> Option<f64> {
    let mut v: Vec<f64> = values.collect();
    v.sort_by(f64::total_cmp);
    v.dedup();
    if v.len() < 2 {
        return None;
    }
    Some((v[v.len() - 1] - v[0]) / (v.len() - 1) as f64)
}

impl Map<'_> {
    fn write(&self, stem: &Path) -> DrawResult {
        register_font();
        draw_file(&with_suffix(stem, "-map.svg"), |p| self.draw(SVGBackend::new(p, (1100, 800)).into_drawing_area()))?;
        draw_file(&png(stem, "map"), |p| self.draw(crate::png::PngBackend::new(p, (1100, 800)).into_drawing_area()))
    }

    /// The stable points' shade value and its range.
    fn shade_value(&self, p: &Point) -> Option<f64> {
        match self.shade {
            Shade::Sigma2 => p.sigma2,
            Shade::LogT => p.t.map(|t| if t.is_finite() { t.log10() } else { f64::INFINITY }),
        }
    }

    fn draw<DB: DrawingBackend>(&self, area: DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        area.fill(&WHITE)?;
        let corner = |b: &SubBox, k: usize| [exact::rational_to_f64(&b.lo[k]), exact::rational_to_f64(&b.hi[k])];
        let (x0, x1) = range_of(self.points.iter().map(|p| p.x[0]).chain(self.boxes.iter().flat_map(|b| corner(b, 0))));
        let (y0, y1) = range_of(self.points.iter().map(|p| p.x[1]).chain(self.boxes.iter().flat_map(|b| corner(b, 1))));
        let dx = step(self.points.iter().map(|p| p.x[0])).unwrap_or((x1 - x0).max(1e-12) / 50.0);
        let dy = step(self.points.iter().map(|p| p.x[1])).unwrap_or((y1 - y0).max(1e-12) / 50.0);
        let on_grid = |v: f64, v0: f64, d: f64| d > 0.0 && (((v - v0) / d) - ((v - v0) / d).round()).abs() < 1e-6;
        let regular = self.points.iter().all(|p| on_grid(p.x[0], x0, dx) && on_grid(p.x[1], y0, dy))
            && ((x1 - x0) / dx + 1.0) * ((y1 - y0) / dy + 1.0) < 4e6;
        let (px, py) = (dx.max(1e-12) / 2.0, dy.max(1e-12) / 2.0);
        let title = format!("{}: verdicts over ({}, {})", excerpt(self.spec.name()), self.names[0], self.names[1]);
        // A stable point with Sigma^2 = 0 (T infinite) has its own colour:
        // no growth at all, not a small one.
        let zero = |p: &Point| p.verdict == "stable" && p.sigma2 == Some(0.0);
        // The paper's (reference) constants: stable points where the sharp
        // Sigma^2 exceeds them (the reference bound fails there).
        let references: Vec<(String, Vec<(f64, f64)>)> = self
            .spec
            .sweep()
            .reference_sigma2
            .iter()
            .map(|r| {
                let above = self
                    .points
                    .iter()
                    .filter(|p| p.verdict == "stable")
                    .filter(|p| {
                        let reference = eval(r, self.fixed, &[(self.names[0], p.x[0]), (self.names[1], p.x[1])]);
                        p.sigma2.is_some_and(|s| s > reference * (1.0 + 1e-9) + 1e-300)
                    })
                    .map(|p| (p.x[0], p.x[1]))
                    .collect();
                (r.label.clone(), above)
            })
            .collect();
        let mut legend = Legend::default();
        for v in ["stable", "linearly_unstable", "inconclusive", "not_an_equilibrium", "noise_incompatible"] {
            let n = self.points.iter().filter(|p| p.verdict == v && !zero(p)).count();
            if n > 0 {
                legend.add(format!("{v} ({n})"), Mark::Swatch(verdict_colour(v).to_rgba()));
            }
        }
        let stable_boxes = self.boxes.iter().filter(|b| b.bound.is_some()).count();
        let unstable_boxes = self.boxes.iter().filter(|b| b.unstable).count();
        if !self.boxes.is_empty() {
            legend
                .add(format!("proved stable sub-box ({stable_boxes})"), Mark::Swatch(box_fill(true, false).to_rgba()));
            legend.add(
                format!("proved linearly unstable sub-box ({unstable_boxes})"),
                Mark::Swatch(box_fill(false, true).to_rgba()),
            );
            legend.add(
                format!("undecided sub-box ({})", self.boxes.len() - stable_boxes - unstable_boxes),
                Mark::Swatch(box_fill(false, false).to_rgba()),
            );
        }
        let zeros = self.points.iter().filter(|p| zero(p)).count();
        if zeros > 0 {
            legend.add(format!("stable, Sigma^2 = 0: T infinite ({zeros})"), Mark::Swatch(ZERO_GROWTH.to_rgba()));
        }
        for (k, (label, above)) in references.iter().enumerate() {
            legend.add(format!("Sigma^2 above {label} ({} points)", above.len()), Mark::Cross(palette(3 + k)));
        }
        for (k, b) in self.spec.sweep().boundaries.iter().enumerate() {
            legend
                .add(format!("boundary: {}", b.label), Mark::Line(if k == 0 { BLACK } else { palette(1 + k) }, false));
        }
        let area = legend.split(&area)?;
        let (main, side) = area.split_horizontally(900);
        let mut chart = ChartBuilder::on(&main)
            .caption(title, ("sans-serif", 22))
            .margin(14)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d((x0 - px)..(x1 + px), (y0 - py)..(y1 + py))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(self.names[0])
            .y_desc(self.names[1])
            .x_label_formatter(&linear_ticks(x1 - x0))
            .y_label_formatter(&linear_ticks(y1 - y0))
            .label_style(("sans-serif", 15))
            .draw()?;

        let finite = |v: Option<f64>| v.filter(|x| x.is_finite());
        let (s_lo, s_hi) =
            range_of(self.points.iter().filter(|p| p.verdict == "stable").filter_map(|p| finite(self.shade_value(p))));
        // Sigma^2 spanning decades (it diverges at a stability boundary) is
        // shaded on a log scale, with 0 at the light end.
        let positive = range_of(
            self.points
                .iter()
                .filter(|p| p.verdict == "stable")
                .filter_map(|p| finite(self.shade_value(p)))
                .filter(|v| *v > 0.0),
        );
        let log_shade = self.shade == Shade::Sigma2 && positive.0 > 0.0 && positive.1 > 10.0 * positive.0;
        let (s_lo, s_hi) = if log_shade { (positive.0.log10(), positive.1.log10()) } else { (s_lo, s_hi) };
        let shade_of = |v: f64| {
            if log_shade {
                if v > 0.0 {
                    v.log10()
                } else {
                    s_lo
                }
            } else {
                v
            }
        };
        let (g_lo, g_hi) = range_of(self.points.iter().filter_map(|p| finite(p.growth)));
        let scaled = |v: f64, lo: f64, hi: f64| if hi > lo { (v - lo) / (hi - lo) } else { 0.5 };
        let colour = |p: &Point| -> RGBColor {
            let base = verdict_colour(&p.verdict);
            if zero(p) {
                return ZERO_GROWTH;
            }
            match p.verdict.as_str() {
                // Darker = larger Sigma^2 (shorter T); with log T, darker = shorter T.
                "stable" => match self.shade_value(p) {
                    Some(v) if v.is_finite() => {
                        let t = scaled(shade_of(v), s_lo, s_hi);
                        tint(base, 0.25 + 0.75 * if self.shade == Shade::LogT { 1.0 - t } else { t })
                    }
                    _ => tint(base, 0.25),
                },
                "linearly_unstable" => tint(base, 0.3 + 0.7 * p.growth.map_or(1.0, |g| scaled(g, g_lo, g_hi))),
                _ => base,
            }
        };
        // The box certificate's sub-boxes under the points, with their edges.
        chart.draw_series(self.boxes.iter().map(|b| {
            let fill = box_fill(b.bound.is_some(), b.unstable);
            let (x, y) = (corner(b, 0), corner(b, 1));
            Rectangle::new([(x[0], y[0]), (x[1], y[1])], fill.filled())
        }))?;
        chart.draw_series(self.boxes.iter().map(|b| {
            let (x, y) = (corner(b, 0), corner(b, 1));
            Rectangle::new([(x[0], y[0]), (x[1], y[1])], RGBColor(90, 90, 90).stroke_width(1))
        }))?;
        if regular && self.boxes.is_empty() {
            chart.draw_series(self.points.iter().map(|p| {
                Rectangle::new([(p.x[0] - px, p.x[1] - py), (p.x[0] + px, p.x[1] + py)], colour(p).filled())
            }))?;
        } else {
            chart.draw_series(self.points.iter().map(|p| Circle::new((p.x[0], p.x[1]), 3, colour(p).filled())))?;
        }
        for (k, (_, above)) in references.iter().enumerate() {
            let colour = palette(3 + k);
            let size = if regular { 2 } else { 1 };
            chart.draw_series(above.iter().map(|q| Cross::new(*q, size + 1, colour.stroke_width(1))))?;
        }

        // Analytic boundaries: zero sets on a fine grid.
        for (k, b) in self.spec.sweep().boundaries.iter().enumerate() {
            let segments = zero_set(
                |x, y| eval(b, self.fixed, &[(self.names[0], x), (self.names[1], y)]),
                (x0 - px, x1 + px),
                (y0 - py, y1 + py),
                400,
            );
            let style = if k == 0 { BLACK.stroke_width(3) } else { palette(1 + k).stroke_width(3) };
            chart.draw_series(segments.into_iter().map(|(a, c)| PathElement::new(vec![a, c], style)))?;
        }

        // Colour bar of the stable shading.
        let (label, lo, hi) = match self.shade {
            Shade::Sigma2 if log_shade => ("log10 Sigma^2 (stable)", s_lo, s_hi),
            Shade::Sigma2 => ("Sigma^2 (stable)", s_lo, s_hi),
            Shade::LogT => ("log10 T (stable)", s_lo, s_hi),
        };
        let hi = if hi > lo { hi } else { lo + 1.0 };
        let mut bar = ChartBuilder::on(&side)
            .margin_top(60)
            .margin_bottom(60)
            .margin_right(10)
            .y_label_area_size(70)
            .caption(label, ("sans-serif", 15))
            .build_cartesian_2d(0.0..1.0, lo..hi)?;
        bar.configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_label_formatter(&linear_ticks(hi - lo))
            .label_style(("sans-serif", 13))
            .draw()?;
        let n = 100;
        let base = verdict_colour("stable");
        bar.draw_series((0..n).map(|i| {
            let a = lo + (hi - lo) * i as f64 / n as f64;
            let b = lo + (hi - lo) * (i + 1) as f64 / n as f64;
            let t = (i as f64 + 0.5) / n as f64;
            let t = if self.shade == Shade::LogT { 1.0 - t } else { t };
            Rectangle::new([(0.0, a), (1.0, b)], tint(base, 0.25 + 0.75 * t).filled())
        }))?;
        area.present()?;
        Ok(())
    }
}

/// Segments approximating `{f = 0}` in the box, by marching squares on an
/// `n x n` grid (linear interpolation along cell edges).
fn zero_set(
    f: impl Fn(f64, f64) -> f64,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
    n: usize,
) -> Vec<((f64, f64), (f64, f64))> {
    let xs: Vec<f64> = (0..=n).map(|i| x0 + (x1 - x0) * i as f64 / n as f64).collect();
    let ys: Vec<f64> = (0..=n).map(|j| y0 + (y1 - y0) * j as f64 / n as f64).collect();
    let v: Vec<Vec<f64>> = xs.iter().map(|&x| ys.iter().map(|&y| f(x, y)).collect()).collect();
    let mut out = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            let mut crossings = Vec::new();
            for e in 0..4 {
                let (a, b) = (corners[e], corners[(e + 1) % 4]);
                let (fa, fb) = (v[a.0][a.1], v[b.0][b.1]);
                if !(fa.is_finite() && fb.is_finite()) || (fa > 0.0) == (fb > 0.0) {
                    continue;
                }
                let t = fa / (fa - fb);
                let p = (xs[a.0] + t * (xs[b.0] - xs[a.0]), ys[a.1] + t * (ys[b.1] - ys[a.1]));
                crossings.push(p);
            }
            for pair in crossings.chunks(2) {
                if let [a, b] = pair {
                    out.push((*a, *b));
                }
            }
        }
    }
    out
}

struct LineCharts<'a> {
    spec: &'a AnySpec,
    name: &'a str,
    points: &'a [Point],
    fixed: &'a BTreeMap<String, f64>,
}

impl LineCharts<'_> {
    fn write(&self, stem: &Path) -> DrawResult {
        register_font();
        for what in ["sigma2", "T"] {
            draw_file(&with_suffix(stem, &format!("-{what}.svg")), |p| {
                self.draw(SVGBackend::new(p, (1000, 600)).into_drawing_area(), what)
            })?;
            draw_file(&png(stem, what), |p| {
                self.draw(crate::png::PngBackend::new(p, (1000, 600)).into_drawing_area(), what)
            })?;
        }
        Ok(())
    }

    fn draw<DB: DrawingBackend>(&self, area: DrawingArea<DB, Shift>, what: &str) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        area.fill(&WHITE)?;
        let mut pts: Vec<&Point> = self.points.iter().collect();
        pts.sort_by(|a, b| a.x[0].total_cmp(&b.x[0]));
        let (x0, x1) = range_of(pts.iter().map(|p| p.x[0]));
        let stopping = self.spec.raw().get("stopping");
        let ln_ratio = stopping.and_then(|s| {
            let e = s.get("epsilon")?.as_f64()?;
            let d = s.get("delta")?.as_f64()?;
            Some((e / d).ln())
        });
        // Reference curves on a fine grid.
        let fine: Vec<f64> = (0..=400).map(|i| x0 + (x1 - x0) * i as f64 / 400.0).collect();
        let value = |s: f64| if what == "sigma2" { Some(s) } else { ln_ratio.filter(|_| s > 0.0).map(|l| l / s) };
        let references: Vec<(String, Vec<(f64, f64)>)> = self
            .spec
            .sweep()
            .reference_sigma2
            .iter()
            .map(|r| {
                let curve =
                    fine.iter().filter_map(|&x| Some((x, value(eval(r, self.fixed, &[(self.name, x)]))?))).collect();
                (r.label.clone(), curve)
            })
            .collect();
        let ours: Vec<(f64, f64)> = pts
            .iter()
            .filter(|p| p.verdict == "stable")
            .filter_map(|p| {
                let y = if what == "sigma2" { p.sigma2? } else { p.t.filter(|t| t.is_finite())? };
                Some((p.x[0], y))
            })
            .collect();
        // Values spanning decades are drawn as log10 (Sigma^2 diverges at a
        // stability boundary, T at Sigma^2 = 0).
        let all: Vec<f64> =
            ours.iter().map(|q| q.1).chain(references.iter().flat_map(|(_, c)| c.iter().map(|q| q.1))).collect();
        let (lo_pos, hi_pos) = range_of(all.iter().copied().filter(|v| *v > 0.0));
        let log = lo_pos > 0.0 && hi_pos > 20.0 * lo_pos;
        let tr = |pts: &[(f64, f64)]| -> Vec<(f64, f64)> {
            if log {
                pts.iter().filter(|q| q.1 > 0.0).map(|q| (q.0, q.1.log10())).collect()
            } else {
                pts.to_vec()
            }
        };
        let ours = tr(&ours);
        let references: Vec<(String, Vec<(f64, f64)>)> = references.iter().map(|(l, c)| (l.clone(), tr(c))).collect();
        let (y_lo, y_hi) = if log {
            let (a, b) = (lo_pos.log10(), hi_pos.log10());
            (a - 0.05 * (b - a), b + 0.1 * (b - a))
        } else {
            let (_, h) = range_of(all.iter().copied());
            (0.0, if h > 0.0 { h * 1.15 } else { 1.0 })
        };
        let pad = (x1 - x0).max(1e-12) * 0.03;
        let (title, y_desc) = if what == "sigma2" {
            (format!("{}: Sigma^2 against {}", excerpt(self.spec.name()), self.name), "Sigma^2".to_string())
        } else {
            (
                format!("{}: stopping time T(eps, delta) against {}", excerpt(self.spec.name()), self.name),
                "T = ln(eps/delta) / Sigma^2".to_string(),
            )
        };
        let y_desc = if log { format!("log10 {y_desc}") } else { y_desc };
        let strips = ["linearly_unstable", "inconclusive", "not_an_equilibrium", "noise_incompatible"];
        let mut legend = Legend::default();
        for v in strips {
            let n = pts.iter().filter(|p| p.verdict == v).count();
            if n > 0 {
                legend.add(format!("{v} ({n})"), Mark::Swatch(verdict_colour(v).mix(0.35)));
            }
        }
        for (k, (label, _)) in references.iter().enumerate() {
            legend.add(format!("{label} (reference)"), Mark::Line(palette(1 + k), true));
        }
        legend.add(
            if what == "sigma2" { "engine: sharp Sigma^2 (stable points)" } else { "engine: T from the sharp Sigma^2" },
            Mark::Dot(verdict_colour("stable")),
        );
        let area = legend.split(&area)?;
        let mut chart = ChartBuilder::on(&area)
            .caption(title, ("sans-serif", 21))
            .margin(14)
            .margin_right(30)
            .x_label_area_size(45)
            .y_label_area_size(80)
            .build_cartesian_2d((x0 - pad)..(x1 + pad), y_lo..y_hi)?;
        chart
            .configure_mesh()
            .x_desc(self.name)
            .y_desc(y_desc)
            .x_label_formatter(&linear_ticks(x1 - x0))
            .y_label_formatter(&linear_ticks(y_hi - y_lo))
            .label_style(("sans-serif", 14))
            .draw()?;
        // Verdict strips along the bottom: where the points are not stable.
        let half = step(pts.iter().map(|p| p.x[0])).unwrap_or(pad) / 2.0;
        for v in strips {
            let c = verdict_colour(v);
            let strip: Vec<&&Point> = pts.iter().filter(|p| p.verdict == v).collect();
            chart.draw_series(
                strip
                    .iter()
                    .map(|p| Rectangle::new([(p.x[0] - half, y_lo), (p.x[0] + half, y_hi)], c.mix(0.18).filled())),
            )?;
        }
        for (k, (_, curve)) in references.iter().enumerate() {
            chart.draw_series(DashedLineSeries::new(curve.clone(), 8, 5, palette(1 + k).stroke_width(2)))?;
        }
        let blue = verdict_colour("stable");
        chart.draw_series(LineSeries::new(ours.clone(), blue.stroke_width(2)))?;
        chart.draw_series(ours.iter().map(|q| Circle::new(*q, 3, blue.filled())))?;
        area.present()?;
        Ok(())
    }
}
