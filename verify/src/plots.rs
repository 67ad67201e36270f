//! SVG and PNG charts with plotters, using an embedded font (DejaVu Sans
//! Mono, see `assets/DejaVu-LICENSE.txt`) so no system font library is
//! needed.

use crate::paths::with_suffix;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

static FONT: Once = Once::new();

pub(crate) fn register_font() {
    FONT.call_once(|| {
        let bytes: &'static [u8] = crate::png::FONT_BYTES;
        // A failure here leaves plotters without a font; the charts would
        // then fail to draw text, which the caller reports.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, bytes);
    });
}

pub(crate) type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// A time-by-value density (grey shades, normalised per time column), the
/// mean path (black), and a dashed vertical line at the stopping time.
pub struct DensityChart<'a> {
    /// Chart title.
    pub title: String,
    /// Name of the observable (y axis).
    pub observable: &'a str,
    /// Output times.
    pub times: &'a [f64],
    /// Histogram per time.
    pub histogram: &'a [Vec<u64>],
    /// Histogram range.
    pub range: (f64, f64),
    /// Mean of the observable per time.
    pub mean: Vec<f64>,
    /// Other means to compare with (label, mean per time), dashed: the
    /// isotropic noise's in the paper's figure.
    pub other_means: Vec<(String, Vec<f64>)>,
    /// The certified stopping time, if finite.
    pub stopping_time: Option<f64>,
}

/// Curves on a log scale, and below them the same curves divided by the
/// certified bound.
pub struct GrowthChart<'a> {
    /// Chart title.
    pub title: String,
    /// Output times.
    pub times: &'a [f64],
    /// Named curves (label, values, colour index, dashed).
    pub curves: Vec<(String, Vec<f64>, usize, bool)>,
    /// A band (label, lower, upper) drawn under the curves.
    pub band: Option<(String, Vec<f64>, Vec<f64>)>,
    /// The certified bound (label, values): drawn where it fits in the
    /// growth panel, and the divisor of the ratio panel below it.
    pub bound: Option<(String, Vec<f64>)>,
    /// The certified stopping time, if finite.
    pub stopping_time: Option<f64>,
    /// The growth axis's label.
    pub y_label: &'a str,
    /// The caption of the panel divided by the bound.
    pub ratio_caption: &'a str,
}

/// The ratio panel's caption for a finite-dimensional study.
pub const FINITE_RATIO_CAPTION: &str =
    "divided by the certified bound exp(Sigma^2 t): the claim is that the exact moments stay at or below 1";

/// How a legend entry is drawn.
#[derive(Clone, Copy)]
pub(crate) enum Mark {
    /// A line (dashed or not) of the colour, 2 px.
    Line(RGBColor, bool),
    /// A filled swatch (a band, a verdict's cells).
    Swatch(RGBAColor),
    /// A filled dot (points).
    Dot(RGBColor),
    /// A cross (marked points).
    Cross(RGBColor),
}

/// Legend entries, drawn in a strip of their own below the chart so that
/// they never cover data.
#[derive(Default)]
pub(crate) struct Legend(pub Vec<(String, Mark)>);

impl Legend {
    /// Add an entry.
    pub fn add(&mut self, label: impl Into<String>, mark: Mark) {
        self.0.push((label.into(), mark));
    }

    /// The strip's height in pixels for a chart `width` wide: entries in
    /// two columns (one when a label is too long for half the width), 22 px
    /// a row.
    pub fn height(&self, width: u32) -> u32 {
        if self.0.is_empty() {
            return 0;
        }
        12 + 22 * self.rows(width) as u32
    }

    fn columns(&self, width: u32) -> usize {
        // 8.5 px a character at 14 px (DejaVu Sans Mono), plus the mark.
        let widest = self.0.iter().map(|(l, _)| l.chars().count()).max().unwrap_or(0) as f64 * 8.5 + 60.0;
        if widest * 2.0 <= width as f64 - 40.0 {
            2
        } else {
            1
        }
    }

    fn rows(&self, width: u32) -> usize {
        self.0.len().div_ceil(self.columns(width))
    }

    /// Split `area` into the chart and the strip, draw the strip, and return
    /// the chart's part.
    pub fn split<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> Result<DrawingArea<DB, Shift>, Box<dyn std::error::Error>>
    where
        DB::ErrorType: 'static,
    {
        let (w, h) = area.dim_in_pixel();
        let strip_h = self.height(w);
        if strip_h == 0 {
            return Ok(area.clone());
        }
        let (chart, strip) = area.split_vertically(h.saturating_sub(strip_h));
        let columns = self.columns(w);
        let rows = self.rows(w);
        let col_w = (w as i32 - 40) / columns as i32;
        let style = ("sans-serif", 14).into_font().color(&BLACK);
        for (k, (label, mark)) in self.0.iter().enumerate() {
            let (col, row) = (k / rows, k % rows);
            let x = 30 + col as i32 * col_w;
            let y = 6 + 22 * row as i32 + 11;
            match *mark {
                Mark::Line(c, false) => strip.draw(&PathElement::new(vec![(x, y), (x + 30, y)], c.stroke_width(2)))?,
                Mark::Line(c, true) => {
                    for s in [(x, x + 8), (x + 12, x + 20), (x + 24, x + 30)] {
                        strip.draw(&PathElement::new(vec![(s.0, y), (s.1, y)], c.stroke_width(2)))?;
                    }
                }
                Mark::Swatch(c) => strip.draw(&Rectangle::new([(x + 4, y - 7), (x + 26, y + 7)], c.filled()))?,
                Mark::Dot(c) => strip.draw(&Circle::new((x + 15, y), 5, c.filled()))?,
                Mark::Cross(c) => strip.draw(&Cross::new((x + 15, y), 5, c.stroke_width(2)))?,
            }
            strip.draw(&Text::new(label.clone(), (x + 40, y - 8), style.clone()))?;
        }
        Ok(chart)
    }
}

/// Tick labels for a linear axis over `range`: as many decimals as the
/// tick spacing (about a tenth of the range) needs, no more (`20`, not
/// `20.0`; `0.25`, not `0.250000`; never a rounded value), and exponent
/// notation far from 1.
pub(crate) fn linear_ticks(range: f64) -> impl Fn(&f64) -> String {
    let step = range.abs() / 10.0;
    let decimals = if step > 0.0 && step.is_finite() { (-step.log10().floor()).clamp(0.0, 12.0) as usize } else { 0 };
    move |v: &f64| {
        let a = v.abs();
        if *v == 0.0 {
            "0".into()
        } else if !(1e-4..1e6).contains(&a) {
            // As few mantissa digits as give the value back (2.25e-5 keeps
            // its 5).
            (0..=12)
                .map(|d| format!("{v:.d$e}"))
                .find(|t| t.parse::<f64>().is_ok_and(|x| (x - v).abs() <= 1e-9 * a))
                .unwrap_or_else(|| format!("{v:e}"))
        } else {
            // More decimals when the tick needs them (0.25 on a 0.1 grid).
            let mut d = decimals;
            let mut text = format!("{v:.d$}");
            while d < 12 && text.parse::<f64>().map_or(true, |x| (x - v).abs() > 1e-9 * a) {
                d += 1;
                text = format!("{v:.d$}");
            }
            if text.contains('.') {
                text.trim_end_matches('0').trim_end_matches('.').to_string()
            } else {
                text
            }
        }
    }
}

/// Tick labels for a log axis: `0.01`, `0.1`, `1`, `10`, `100`, `1000`,
/// then `1e4`, `1e5`... (and `1e-3`, `1e-4`... below), mantissas kept
/// (`2e5`, `0.05`).
pub(crate) fn log_ticks(v: &f64) -> String {
    let a = v.abs();
    if (0.01..1e4).contains(&a) {
        let text = format!("{v:.2}");
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        // A decade computed as 10^k lands a rounding off it (1e-5 is
        // 9.999999999999999e-6): the mantissa is brought back into [1, 10).
        let mut e = a.log10().floor();
        let mut m = v / 10f64.powf(e);
        if m.abs() >= 10.0 - 1e-9 {
            e += 1.0;
            m /= 10.0;
        }
        let text = format!("{m:.2}");
        let text = text.trim_end_matches('0').trim_end_matches('.');
        format!("{text}e{e}")
    }
}

pub(crate) fn palette(i: usize) -> RGBColor {
    [RGBColor(0, 0, 0), RGBColor(200, 30, 30), RGBColor(30, 90, 200), RGBColor(20, 140, 60), RGBColor(150, 60, 170)]
        [i % 5]
}

fn draw_density<DB: DrawingBackend>(area: DrawingArea<DB, Shift>, c: &DensityChart) -> DrawResult
where
    DB::ErrorType: 'static,
{
    area.fill(&WHITE)?;
    let t_max = c.times.last().copied().unwrap_or(1.0).max(1e-12);
    let shown_t = c.stopping_time.filter(|t| *t <= t_max);
    let mut legend = Legend::default();
    legend.add("mean", Mark::Line(BLACK, false));
    for (k, (label, _)) in c.other_means.iter().enumerate() {
        legend.add(label.as_str(), Mark::Line(palette(2 + k), true));
    }
    legend.add("density (log shade per time, darker = more paths)", Mark::Swatch(RGBColor(90, 90, 90).to_rgba()));
    if shown_t.is_some() {
        legend.add("stopping time T(eps, delta)", Mark::Line(RED, true));
    }
    let area = legend.split(&area)?;
    let mut chart = ChartBuilder::on(&area)
        .caption(&c.title, ("sans-serif", 22))
        .margin(12)
        .margin_right(30)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..t_max, c.range.0..c.range.1)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("t")
        .y_desc(c.observable)
        .x_label_formatter(&linear_ticks(t_max))
        .y_label_formatter(&linear_ticks(c.range.1 - c.range.0))
        .label_style(("sans-serif", 14))
        .draw()?;
    let bins = c.histogram.first().map_or(1, Vec::len).max(1);
    let bin_h = (c.range.1 - c.range.0) / bins as f64;
    for (k, hist) in c.histogram.iter().enumerate() {
        let t0 = c.times[k];
        let t1 = c.times.get(k + 1).copied().unwrap_or(t_max);
        let peak = hist.iter().copied().max().unwrap_or(0).max(1) as f64;
        for (b, &count) in hist.iter().enumerate() {
            if count == 0 {
                continue;
            }
            // Grey level by log-density relative to the column's peak, so the
            // thin tails that carry the transition stay visible.
            let level = (1.0 + count as f64).ln() / (1.0 + peak).ln();
            let g = (255.0 * (1.0 - 0.85 * level)) as u8;
            let y0 = c.range.0 + b as f64 * bin_h;
            chart.draw_series(std::iter::once(Rectangle::new(
                [(t0, y0), (t1, y0 + bin_h)],
                RGBColor(g, g, g).filled(),
            )))?;
        }
    }
    chart.draw_series(LineSeries::new(c.times.iter().copied().zip(c.mean.iter().copied()), BLACK.stroke_width(2)))?;
    for (k, (_, mean)) in c.other_means.iter().enumerate() {
        let points: Vec<(f64, f64)> = c.times.iter().copied().zip(mean.iter().copied()).collect();
        chart.draw_series(DashedLineSeries::new(points, 8, 5, palette(2 + k).stroke_width(2)))?;
    }
    if let Some(t) = shown_t {
        chart.draw_series(DashedLineSeries::new(vec![(t, c.range.0), (t, c.range.1)], 6, 4, RED.stroke_width(2)))?;
    }
    area.present()?;
    Ok(())
}

/// Whether plotters can draw a log axis over `[lo, hi]`: its tick search
/// counts the decades from `hi / lo`, and an infinite ratio (more than
/// about 308 decades) never ends.
fn log_axis_ok(lo: f64, hi: f64) -> bool {
    lo > 0.0 && hi.is_finite() && (hi / lo).is_finite()
}

/// The `(lo, hi)` of the positive finite values, widened for a log axis
/// (at least a decade), and at most 300 decades deep: the axis stays inside
/// the doubles and [`log_axis_ok`]; values below `lo` are not drawn.
fn log_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) =
        values.filter(|v| v.is_finite() && *v > 0.0).fold((f64::INFINITY, 0.0f64), |(l, h), v| (l.min(v), h.max(v)));
    lo.is_finite().then(|| {
        let high = (hi * 1.25).max(lo * 10.0).min(f64::MAX);
        ((lo * 0.8).max(high * 1e-300), high)
    })
}

fn draw_growth<DB: DrawingBackend>(area: DrawingArea<DB, Shift>, c: &GrowthChart) -> DrawResult
where
    DB::ErrorType: 'static,
{
    area.fill(&WHITE)?;
    let t_max = c.times.last().copied().unwrap_or(1.0).max(1e-12);
    let positive = |v: &f64| v.is_finite() && *v > 0.0;
    let band_colour = RGBColor(30, 90, 200).mix(0.3);
    let shown_t = c.stopping_time.filter(|t| *t <= t_max);
    let mut legend = Legend::default();
    if let Some((label, _, _)) = &c.band {
        legend.add(label.as_str(), Mark::Swatch(band_colour));
    }
    for (label, _, colour, dashed) in &c.curves {
        legend.add(label.as_str(), Mark::Line(palette(*colour), *dashed));
    }
    if let Some((label, _)) = &c.bound {
        legend.add(label.as_str(), Mark::Line(palette(1), true));
    }
    if shown_t.is_some() {
        legend.add("stopping time T(eps, delta)", Mark::Line(RGBColor(230, 110, 110), true));
    }
    let area = legend.split(&area)?;
    let (w, h) = area.dim_in_pixel();
    let (top, bottom) = area.split_vertically(h * 3 / 5);
    let _ = w;
    // Top: the data on a log scale fitted to the data (the bound, which
    // grows far faster, is drawn where it fits and read in the ratio panel).
    let band_values = c.band.iter().flat_map(|(_, lo, hi)| lo.iter().chain(hi).copied());
    let Some((lo, hi)) = log_range(c.curves.iter().flat_map(|(_, v, _, _)| v.iter().copied()).chain(band_values))
    else {
        return Err("nothing positive to plot".into());
    };
    if !log_axis_ok(lo, hi) {
        return Err(format!("the curves span {lo:e} to {hi:e}, more decades than a log axis can draw").into());
    }
    let mut chart = ChartBuilder::on(&top)
        .caption(&c.title, ("sans-serif", 22))
        .margin(12)
        .margin_right(30)
        .x_label_area_size(35)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..t_max, (lo..hi).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("t")
        .y_desc(c.y_label)
        .x_label_formatter(&linear_ticks(t_max))
        .y_label_formatter(&log_ticks)
        .label_style(("sans-serif", 14))
        .draw()?;
    let series = |values: &[f64]| -> Vec<(f64, f64)> {
        c.times.iter().copied().zip(values.iter().copied()).filter(|(_, v)| positive(v) && *v >= lo).collect()
    };
    if let Some((_, lo_b, hi_b)) = &c.band {
        let mut poly = series(hi_b);
        poly.extend(series(lo_b).into_iter().rev());
        chart.draw_series(std::iter::once(Polygon::new(poly, band_colour.filled())))?;
    }
    let draw_line =
        |chart: &mut ChartContext<'_, DB, _>, points: Vec<(f64, f64)>, colour: RGBColor, dashed: bool| -> DrawResult {
            let style = colour.stroke_width(2);
            if dashed {
                chart.draw_series(DashedLineSeries::new(points, 8, 5, style))?;
            } else {
                chart.draw_series(LineSeries::new(points, style))?;
            }
            Ok(())
        };
    for (_, values, colour, dashed) in &c.curves {
        draw_line(&mut chart, series(values), palette(*colour), *dashed)?;
    }
    if let Some((_, bound)) = &c.bound {
        let inside: Vec<(f64, f64)> = series(bound).into_iter().take_while(|(_, v)| *v <= hi).collect();
        draw_line(&mut chart, inside, palette(1), true)?;
    }
    if let Some(t) = shown_t {
        chart.draw_series(DashedLineSeries::new(vec![(t, lo), (t, hi)], 6, 4, RED.mix(0.6).stroke_width(1)))?;
    }
    // Bottom: each curve divided by the bound, so the claim reads off a
    // line at 1 whatever the size of exp(Sigma^2 t).
    if let Some((_, bound)) = &c.bound {
        let ratio = |values: &[f64]| -> Vec<(f64, f64)> {
            c.times
                .iter()
                .zip(values.iter().zip(bound))
                .map(|(t, (v, b))| (*t, v / b))
                .filter(|(_, r)| positive(r))
                .collect()
        };
        let ratio_lo = |ratios: Vec<(f64, f64)>, lo: f64| -> Vec<(f64, f64)> {
            ratios.into_iter().filter(|q| q.1 >= lo).collect()
        };
        let ratios: Vec<f64> = c.curves.iter().flat_map(|(_, v, _, _)| ratio(v)).map(|(_, r)| r).chain([1.0]).collect();
        let Some((r_lo, r_hi)) = log_range(ratios.into_iter()).filter(|(a, b)| log_axis_ok(*a, *b)) else {
            return Err("the ratios to the bound span more decades than a log axis can draw".into());
        };
        let mut panel = ChartBuilder::on(&bottom)
            .caption(c.ratio_caption, ("sans-serif", 15))
            .margin(12)
            .margin_right(30)
            .x_label_area_size(35)
            .y_label_area_size(80)
            .build_cartesian_2d(0.0..t_max, (r_lo..r_hi).log_scale())?;
        panel
            .configure_mesh()
            .x_desc("t")
            .y_desc("ratio to the bound")
            .x_label_formatter(&linear_ticks(t_max))
            .y_label_formatter(&log_ticks)
            .label_style(("sans-serif", 14))
            .draw()?;
        if let Some((_, lo_b, hi_b)) = &c.band {
            let mut poly = ratio_lo(ratio(hi_b), r_lo);
            poly.extend(ratio_lo(ratio(lo_b), r_lo).into_iter().rev());
            panel.draw_series(std::iter::once(Polygon::new(poly, band_colour.filled())))?;
        }
        for (_, values, colour, dashed) in &c.curves {
            draw_line(&mut panel, ratio_lo(ratio(values), r_lo), palette(*colour), *dashed)?;
        }
        draw_line(&mut panel, vec![(0.0, 1.0), (t_max, 1.0)], palette(1), true)?;
        if let Some(t) = shown_t {
            panel.draw_series(DashedLineSeries::new(vec![(t, r_lo), (t, r_hi)], 6, 4, RED.mix(0.6).stroke_width(1)))?;
        }
    }
    area.present()?;
    Ok(())
}

/// Draw one chart file atomically: `draw` renders into a temporary file
/// beside `path`, which then replaces `path` (see
/// [`crate::paths::write_atomic_with`]); a failed drawing leaves no partial
/// chart and keeps an existing one.
pub(crate) fn draw_file(path: &Path, draw: impl FnOnce(&Path) -> DrawResult) -> DrawResult {
    crate::paths::write_atomic_with(path, |tmp| draw(tmp).map_err(|e| std::io::Error::other(e.to_string())))?;
    Ok(())
}

/// Write `stem.svg` and `stem.png`.
pub fn write_density(stem: &Path, chart: &DensityChart) -> DrawResult {
    register_font();
    draw_file(&with_suffix(stem, ".svg"), |p| {
        draw_density(SVGBackend::new(p, (1000, 600)).into_drawing_area(), chart)
    })?;
    draw_file(&with_suffix(stem, ".png"), |p| {
        draw_density(crate::png::PngBackend::new(p, (1000, 600)).into_drawing_area(), chart)
    })
}

/// Write `stem.svg` and `stem.png`.
pub fn write_growth(stem: &Path, chart: &GrowthChart) -> DrawResult {
    register_font();
    draw_file(&with_suffix(stem, ".svg"), |p| draw_growth(SVGBackend::new(p, (1000, 860)).into_drawing_area(), chart))?;
    draw_file(&with_suffix(stem, ".png"), |p| {
        draw_growth(crate::png::PngBackend::new(p, (1000, 860)).into_drawing_area(), chart)
    })
}

/// A named series of points: (label, points, colour index, dashed).
pub type Series = (String, Vec<(f64, f64)>, usize, bool);

/// Points on log-log or lin-log axes: named series with markers, and
/// labelled horizontal reference lines.
pub struct XyChart {
    /// Chart title.
    pub title: String,
    /// x-axis label.
    pub x_desc: String,
    /// y-axis label.
    pub y_desc: String,
    /// Logarithmic x axis.
    pub x_log: bool,
    /// Series (label, points, colour index, dashed).
    pub series: Vec<Series>,
    /// Horizontal lines (label, y, colour index).
    pub hlines: Vec<(String, f64, usize)>,
}

fn draw_xy<DB: DrawingBackend>(area: DrawingArea<DB, Shift>, c: &XyChart) -> DrawResult
where
    DB::ErrorType: 'static,
{
    area.fill(&WHITE)?;
    let ok = |v: f64| v.is_finite() && v > 0.0;
    // The points drawn: a finite x (positive on a log axis) and a positive y.
    let kept = |&(x, y): &(f64, f64)| ok(y) && x.is_finite() && (!c.x_log || ok(x));
    let points = || c.series.iter().flat_map(|(_, p, _, _)| p.iter().copied().filter(kept));
    // (The x axis spans every point with a usable x, drawn or not: a series
    // of zeros still places the reference lines over its range.)
    let xs: Vec<f64> = c
        .series
        .iter()
        .flat_map(|(_, p, _, _)| p.iter().map(|q| q.0))
        .filter(|x| x.is_finite() && (!c.x_log || ok(*x)))
        .collect();
    let ys: Vec<f64> = points().map(|q| q.1).chain(c.hlines.iter().map(|h| h.1).filter(|y| ok(*y))).collect();
    if xs.is_empty() || ys.is_empty() {
        return Err("nothing to plot".into());
    }
    let (x0, x1) = xs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| (l.min(*x), h.max(*x)));
    let (y0, y1) = ys.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), y| (l.min(*y), h.max(*y)));
    // At most 300 decades deep, inside the doubles (as `log_range`); points
    // below are not drawn.
    let y1 = (y1 * 2.0).max(y0 * 10.0).min(f64::MAX);
    let y0 = (y0 / 2.0).max(y1 * 1e-300);
    // Axes whose span or logarithm leaves the doubles (values near 1e308
    // or 1e-308) are refused: plotters' tick search does not end on them.
    let x_ok = if c.x_log { log_axis_ok(x0, x1) } else { (x1 - x0).is_finite() };
    if !(x_ok && log_axis_ok(y0, y1)) {
        return Err("the values span more than double precision can draw".into());
    }
    let mut legend = Legend::default();
    for (label, _, colour) in &c.hlines {
        legend.add(label.as_str(), Mark::Line(palette(*colour), true));
    }
    for (label, _, colour, _) in &c.series {
        legend.add(label.as_str(), Mark::Dot(palette(*colour)));
    }
    let area = legend.split(&area)?;
    let mut builder = ChartBuilder::on(&area);
    builder
        .caption(&c.title, ("sans-serif", 20))
        .margin(12)
        .margin_right(30)
        .x_label_area_size(40)
        .y_label_area_size(90);
    macro_rules! finish {
        ($chart:expr) => {{
            let mut chart = $chart;
            chart
                .configure_mesh()
                .x_desc(c.x_desc.as_str())
                .y_desc(c.y_desc.as_str())
                .x_label_formatter(&|v: &f64| if c.x_log { log_ticks(v) } else { linear_ticks(x1 - x0)(v) })
                .y_label_formatter(&log_ticks)
                .label_style(("sans-serif", 14))
                .draw()?;
            for (_, y, colour) in &c.hlines {
                let colour = palette(*colour);
                chart.draw_series(DashedLineSeries::new(vec![(x0, *y), (x1, *y)], 8, 5, colour.stroke_width(2)))?;
            }
            for (_, points, colour, dashed) in &c.series {
                let colour = palette(*colour);
                let pts: Vec<(f64, f64)> = points.iter().copied().filter(|q| kept(q) && q.1 >= y0).collect();
                let style = colour.stroke_width(2);
                if *dashed {
                    chart.draw_series(DashedLineSeries::new(pts.clone(), 6, 4, style))?;
                } else {
                    chart.draw_series(LineSeries::new(pts.clone(), style))?;
                }
                chart.draw_series(pts.iter().map(|p| Circle::new(*p, 4, colour.filled())))?;
            }
        }};
    }
    if c.x_log {
        finish!(builder.build_cartesian_2d((x0 * 0.8..x1 * 1.25).log_scale(), (y0..y1).log_scale())?);
    } else {
        let pad = (x1 - x0).max(1e-12) * 0.05;
        finish!(builder.build_cartesian_2d((x0 - pad)..(x1 + pad), (y0..y1).log_scale())?);
    }
    area.present()?;
    Ok(())
}

/// The chart as SVG text of `size` pixels (for inline use in HTML).
pub(crate) fn xy_svg(chart: &XyChart, size: (u32, u32)) -> Result<String, Box<dyn std::error::Error>> {
    register_font();
    let mut svg = String::new();
    draw_xy(SVGBackend::with_string(&mut svg, size).into_drawing_area(), chart)?;
    Ok(svg)
}

/// Write `stem.svg` and `stem.png`.
pub fn write_xy(stem: &Path, chart: &XyChart) -> DrawResult {
    register_font();
    draw_file(&with_suffix(stem, ".svg"), |p| draw_xy(SVGBackend::new(p, (1000, 600)).into_drawing_area(), chart))?;
    draw_file(&with_suffix(stem, ".png"), |p| {
        draw_xy(crate::png::PngBackend::new(p, (1000, 600)).into_drawing_area(), chart)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `(x, y, text)` of every `<text>` element of an SVG that plotters wrote.
    fn svg_texts(svg: &str) -> Vec<(f64, f64, String)> {
        let attr = |tag: &str, name: &str| -> Option<f64> {
            let start = tag.find(&format!(" {name}=\""))? + name.len() + 3;
            tag[start..].split('"').next()?.parse().ok()
        };
        svg.split("<text")
            .skip(1)
            .filter_map(|t| {
                let (tag, rest) = t.split_once('>')?;
                let body = rest.split("</text>").next()?;
                Some((attr(tag, "x")?, attr(tag, "y")?, body.trim().to_string()))
            })
            .collect()
    }

    /// A growth chart whose bound spans 16 decades above the data (as the
    /// rigid body's over 8 T does): every tick label is a short number in
    /// the axis formats (no `0000000000.0`), the data's decades are
    /// labelled, and every legend label lies below both panels.
    #[test]
    fn the_growth_chart_labels_its_decades_and_keeps_the_legend_off_the_data() {
        register_font();
        let times: Vec<f64> = (0..=140).map(|i| i as f64).collect();
        let data: Vec<f64> = times.iter().map(|t| (0.09 * t).exp()).collect();
        let bound: Vec<f64> = times.iter().map(|t| (0.27 * t).exp()).collect();
        let chart = GrowthChart {
            title: "test".into(),
            times: &times,
            curves: vec![("exact second moments".into(), data.clone(), 0, false)],
            band: Some(("band".into(), data.iter().map(|x| x * 0.9).collect(), data.iter().map(|x| x * 1.1).collect())),
            bound: Some(("bound".into(), bound)),
            stopping_time: Some(17.0),
            y_label: "E|dmu_t|^2 / |dmu_0|^2",
            ratio_caption: FINITE_RATIO_CAPTION,
        };
        let mut svg = String::new();
        draw_growth(SVGBackend::with_string(&mut svg, (1000, 860)).into_drawing_area(), &chart).unwrap();
        let texts = svg_texts(&svg);
        let legend: Vec<&(f64, f64, String)> = texts
            .iter()
            .filter(|t| {
                ["exact second moments", "band", "bound", "stopping time T(eps, delta)"].contains(&t.2.as_str())
            })
            .collect();
        assert_eq!(legend.len(), 4, "{texts:?}");
        let number = |s: &str| {
            s.len() <= 6 && s.chars().all(|c| c.is_ascii_digit() || "-.e".contains(c)) && s.parse::<f64>().is_ok()
        };
        let ticks: Vec<&(f64, f64, String)> = texts.iter().filter(|t| number(&t.2)).collect();
        // Only captions, axis names and legend labels are not numbers.
        let words = texts.len() - ticks.len();
        assert!(words <= 4 + 1 + 1 + 4, "{texts:?}");
        for decade in ["1", "10", "100", "1000", "1e4", "1e5"] {
            assert!(ticks.iter().any(|t| t.2 == decade), "no tick {decade}: {ticks:?}");
        }
        let lowest_tick = ticks.iter().map(|t| t.1).fold(0.0, f64::max);
        assert!(legend.iter().all(|t| t.1 > lowest_tick), "a legend label above a tick: {legend:?}");
    }

    /// Values at the ends of the double range: an x span that overflows
    /// (-1.7e308 to 1.7e308) is refused; x at infinity is dropped; a y of
    /// 5e-324 beside 1 leaves the axis at most 300 decades deep: never a hang
    /// (plotters' tick search did not end on an infinite axis).
    #[test]
    fn charts_at_the_ends_of_the_double_range_end() {
        register_font();
        let chart = |series: Vec<(f64, f64)>| XyChart {
            title: "edge".into(),
            x_desc: "x".into(),
            y_desc: "y".into(),
            x_log: false,
            series: vec![("s".into(), series, 0, false)],
            hlines: vec![],
        };
        assert!(xy_svg(&chart(vec![(-1.7e308, 1.0), (1.7e308, 2.0)]), (400, 300)).is_err());
        assert!(xy_svg(&chart(vec![(0.0, 1.0), (1.0, 5e-324)]), (400, 300)).is_ok());
        // A point at infinity is dropped; the finite ones are drawn.
        assert!(xy_svg(&chart(vec![(0.0, 1.0), (1.0, 2.0), (f64::INFINITY, 3.0)]), (400, 300)).is_ok());
        assert!(xy_svg(&chart(vec![(0.0, 1.0), (1e-300, 1e300)]), (400, 300)).is_ok());
    }

    /// Growth charts whose curves span 600 decades (down to 5e-324, up to
    /// 1.7e308) or 200, with the bound at f64::MAX and infinity (its ratio
    /// at 1e-308), are drawn and end: each log axis is at most 300 decades
    /// deep (plotters' tick search never ended on a deeper one).
    #[test]
    fn a_growth_chart_at_the_ends_of_the_double_range_ends() {
        register_font();
        let times = [0.0, 1.0, 2.0];
        let chart = |curve: Vec<f64>| GrowthChart {
            title: "edge".into(),
            times: &times,
            curves: vec![("c".into(), curve, 0, false)],
            band: None,
            bound: Some(("b".into(), vec![1.0, f64::MAX, f64::INFINITY])),
            stopping_time: None,
            y_label: "E|dmu_t|^2 / |dmu_0|^2",
            ratio_caption: FINITE_RATIO_CAPTION,
        };
        let draw = |c: &GrowthChart| {
            let mut svg = String::new();
            draw_growth(SVGBackend::with_string(&mut svg, (1000, 860)).into_drawing_area(), c).map(|_| svg)
        };
        for curve in [vec![1e-300, 1.0, 1e300], vec![5e-324, 1.0, 1.7e308], vec![1e-100, 1.0, 1e100]] {
            assert!(draw(&chart(curve.clone())).unwrap().contains("<svg"), "{curve:?}");
        }
    }

    #[test]
    fn tick_formats() {
        let f = linear_ticks(140.0);
        assert_eq!([f(&0.0), f(&20.0), f(&120.0)], ["0", "20", "120"]);
        let f = linear_ticks(1e-4);
        assert_eq!([f(&2.25e-5), f(&5e-5)], ["2.25e-5", "5e-5"]);
        let f = linear_ticks(1.0);
        assert_eq!([f(&0.5), f(&-0.25), f(&1.0)], ["0.5", "-0.25", "1"]);
        assert_eq!(
            [log_ticks(&1.0), log_ticks(&1000.0), log_ticks(&1e4), log_ticks(&1e-3), log_ticks(&0.1)],
            ["1", "1000", "1e4", "1e-3", "0.1"]
        );
        assert_eq!(log_ticks(&2e5), "2e5");
        assert_eq!(log_ticks(&2.5e5), "2.5e5", "a mantissa keeps its digits");
        // Decades as 10^k computes them, a rounding away from the power.
        assert_eq!(log_ticks(&9.999999999999999e-6), "1e-5");
        assert_eq!(log_ticks(&1.0000000000000002e12), "1e12");
        assert_eq!(log_ticks(&10f64.powi(-7)), "1e-7");
    }
}
