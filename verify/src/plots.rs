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
        let bytes: &'static [u8] = include_bytes!("../assets/DejaVuSansMono.ttf");
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
    /// The certified stopping time, if finite.
    pub stopping_time: Option<f64>,
}

/// Curves on a log scale.
pub struct GrowthChart<'a> {
    /// Chart title.
    pub title: String,
    /// Output times.
    pub times: &'a [f64],
    /// Named curves (label, values, colour index, dashed).
    pub curves: Vec<(String, Vec<f64>, usize, bool)>,
    /// A band (label, lower, upper) drawn under the curves.
    pub band: Option<(String, Vec<f64>, Vec<f64>)>,
    /// The certified stopping time, if finite.
    pub stopping_time: Option<f64>,
}

/// The legend box every chart uses, at `position`.
pub(crate) fn draw_legend<'a, DB, CT>(chart: &mut ChartContext<'a, DB, CT>, position: SeriesLabelPosition) -> DrawResult
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    CT: plotters::coord::CoordTranslate,
{
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()?;
    Ok(())
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
    let mut chart = ChartBuilder::on(&area)
        .caption(&c.title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..t_max, c.range.0..c.range.1)?;
    chart.configure_mesh().disable_mesh().x_desc("t").y_desc(c.observable).label_style(("sans-serif", 14)).draw()?;
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
    chart
        .draw_series(LineSeries::new(c.times.iter().copied().zip(c.mean.iter().copied()), BLACK.stroke_width(2)))?
        .label("mean")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2)));
    if let Some(t) = c.stopping_time.filter(|t| *t <= t_max) {
        chart
            .draw_series(DashedLineSeries::new(vec![(t, c.range.0), (t, c.range.1)], 6, 4, RED.stroke_width(2)))?
            .label("stopping time T(eps, delta)")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()?;
    area.present()?;
    Ok(())
}

fn draw_growth<DB: DrawingBackend>(area: DrawingArea<DB, Shift>, c: &GrowthChart) -> DrawResult
where
    DB::ErrorType: 'static,
{
    area.fill(&WHITE)?;
    let t_max = c.times.last().copied().unwrap_or(1.0).max(1e-12);
    let positive = |v: &f64| v.is_finite() && *v > 0.0;
    let all: Vec<f64> = c
        .curves
        .iter()
        .flat_map(|(_, v, _, _)| v.iter().copied())
        .chain(c.band.iter().flat_map(|(_, lo, hi)| lo.iter().chain(hi).copied()))
        .filter(positive)
        .collect();
    let lo = all.iter().copied().fold(f64::INFINITY, f64::min).max(1e-300);
    let hi = all.iter().copied().fold(0.0, f64::max).max(lo * 10.0);
    let mut chart = ChartBuilder::on(&area)
        .caption(&c.title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..t_max, (lo * 0.8..hi * 1.25).log_scale())?;
    chart.configure_mesh().x_desc("t").y_desc("E |dmu_t|_P^2 / |dmu_0|_P^2").label_style(("sans-serif", 14)).draw()?;
    if let Some((label, lo_b, hi_b)) = &c.band {
        let mut poly: Vec<(f64, f64)> =
            c.times.iter().copied().zip(hi_b.iter().copied()).filter(|(_, v)| positive(v)).collect();
        poly.extend(c.times.iter().copied().zip(lo_b.iter().copied()).filter(|(_, v)| positive(v)).rev());
        chart
            .draw_series(std::iter::once(Polygon::new(poly, RGBColor(30, 90, 200).mix(0.25).filled())))?
            .label(label.as_str())
            .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 20, y + 5)], RGBColor(30, 90, 200).mix(0.25).filled()));
    }
    for (label, values, colour, dashed) in &c.curves {
        let colour = palette(*colour);
        let points: Vec<(f64, f64)> =
            c.times.iter().copied().zip(values.iter().copied()).filter(|(_, v)| positive(v)).collect();
        let style = colour.stroke_width(2);
        if *dashed {
            chart.draw_series(DashedLineSeries::new(points, 8, 5, style))?
        } else {
            chart.draw_series(LineSeries::new(points, style))?
        }
        .label(label.as_str())
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
    }
    if let Some(t) = c.stopping_time.filter(|t| *t <= t_max) {
        chart.draw_series(DashedLineSeries::new(vec![(t, lo * 0.8), (t, hi * 1.25)], 6, 4, RED.stroke_width(1)))?;
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
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
        draw_density(BitMapBackend::new(p, (1000, 600)).into_drawing_area(), chart)
    })
}

/// Write `stem.svg` and `stem.png`.
pub fn write_growth(stem: &Path, chart: &GrowthChart) -> DrawResult {
    register_font();
    draw_file(&with_suffix(stem, ".svg"), |p| draw_growth(SVGBackend::new(p, (1000, 600)).into_drawing_area(), chart))?;
    draw_file(&with_suffix(stem, ".png"), |p| {
        draw_growth(BitMapBackend::new(p, (1000, 600)).into_drawing_area(), chart)
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
    let xs: Vec<f64> =
        c.series.iter().flat_map(|(_, p, _, _)| p.iter().map(|q| q.0)).filter(|x| !c.x_log || ok(*x)).collect();
    let ys: Vec<f64> = c
        .series
        .iter()
        .flat_map(|(_, p, _, _)| p.iter().map(|q| q.1))
        .chain(c.hlines.iter().map(|h| h.1))
        .filter(|y| ok(*y))
        .collect();
    if xs.is_empty() || ys.is_empty() {
        return Err("nothing to plot".into());
    }
    let (x0, x1) = xs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| (l.min(*x), h.max(*x)));
    let (y0, y1) = ys.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), y| (l.min(*y), h.max(*y)));
    let (y0, y1) = (y0 / 2.0, (y1 * 2.0).max(y0 * 10.0));
    let mut builder = ChartBuilder::on(&area);
    builder.caption(&c.title, ("sans-serif", 20)).margin(12).x_label_area_size(40).y_label_area_size(90);
    macro_rules! finish {
        ($chart:expr) => {{
            let mut chart = $chart;
            chart
                .configure_mesh()
                .x_desc(c.x_desc.as_str())
                .y_desc(c.y_desc.as_str())
                .label_style(("sans-serif", 14))
                .draw()?;
            for (label, y, colour) in &c.hlines {
                let colour = palette(*colour);
                chart
                    .draw_series(DashedLineSeries::new(vec![(x0, *y), (x1, *y)], 8, 5, colour.stroke_width(2)))?
                    .label(label.as_str())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
            }
            for (label, points, colour, dashed) in &c.series {
                let colour = palette(*colour);
                let pts: Vec<(f64, f64)> =
                    points.iter().copied().filter(|(x, y)| ok(*y) && (!c.x_log || ok(*x))).collect();
                let style = colour.stroke_width(2);
                if *dashed {
                    chart.draw_series(DashedLineSeries::new(pts.clone(), 6, 4, style))?;
                } else {
                    chart.draw_series(LineSeries::new(pts.clone(), style))?;
                }
                chart
                    .draw_series(pts.iter().map(|p| Circle::new(*p, 4, colour.filled())))?
                    .label(label.as_str())
                    .legend(move |(x, y)| Circle::new((x + 10, y), 4, colour.filled()));
            }
            draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
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

/// Write `stem.svg` and `stem.png`.
pub fn write_xy(stem: &Path, chart: &XyChart) -> DrawResult {
    register_font();
    draw_file(&with_suffix(stem, ".svg"), |p| draw_xy(SVGBackend::new(p, (1000, 600)).into_drawing_area(), chart))?;
    draw_file(&with_suffix(stem, ".png"), |p| draw_xy(BitMapBackend::new(p, (1000, 600)).into_drawing_area(), chart))
}
