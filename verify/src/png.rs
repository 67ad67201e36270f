//! The PNG backend: plotters' bitmap backend with its text drawn right.
//!
//! plotters 0.3.7 rasterises text through `ab_glyph` but places each
//! glyph's pixels at the pen position without the glyph's left side bearing
//! (`px_bounds().min.x`), and each glyph vertically by its own bounding box.
//! In a monospaced font that pulls the period of `6.0` against the `6`, where
//! its one or two pixels disappear into the digit: PNG tick labels read
//! `6 0` while the SVG (drawn by the viewer's text engine) says `6.0`. This
//! backend wraps [`BitMapBackend`] and draws text itself: glyphs positioned
//! by `ab_glyph` on one baseline (bearing and kerning included), each pixel
//! blended with its coverage, then anchored and rotated as plotters does.
//! Everything else is delegated. It is written here because the fix is a
//! few lines in a method plotters lets a backend override, and the crate
//! has no release with it.

use ab_glyph::{Font, FontRef, PxScale, ScaleFont};
use plotters::prelude::*;
use plotters_backend::text_anchor::{HPos, VPos};
use plotters_backend::{BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingErrorKind};
use std::sync::OnceLock;

/// The embedded font every chart uses (also registered with plotters for the
/// SVG's layout, see `plots::register_font`).
pub(crate) const FONT_BYTES: &[u8] = include_bytes!("../assets/DejaVuSansMono.ttf");

fn font() -> Option<&'static FontRef<'static>> {
    static FONT: OnceLock<Option<FontRef<'static>>> = OnceLock::new();
    FONT.get_or_init(|| FontRef::try_from_slice(FONT_BYTES).ok()).as_ref()
}

/// Pixels `(x, y, coverage)` and the layout box `(width, height)`.
pub(crate) type Rasterised = (Vec<(i32, i32, f32)>, (i32, i32));

/// Pixels of `text` at `size`: `(x, y, coverage)` with the baseline at
/// `y = ascent` and the pen starting at `x = 0`, and the layout box
/// `(advance width, ascent - descent)`.
pub(crate) fn rasterise(text: &str, size: f32) -> Option<Rasterised> {
    let font = font()?;
    let scaled = font.as_scaled(PxScale::from(size));
    let ascent = scaled.ascent();
    let mut pen = 0.0f32;
    let mut previous = None;
    let mut pixels = vec![];
    for c in text.chars() {
        let id = scaled.glyph_id(c);
        if let Some(p) = previous {
            pen += scaled.kern(p, id);
        }
        previous = Some(id);
        let glyph = id.with_scale_and_position(scaled.scale(), ab_glyph::point(pen, ascent));
        if let Some(outline) = font.outline_glyph(glyph) {
            let bounds = outline.px_bounds();
            outline.draw(|x, y, coverage| {
                pixels.push((bounds.min.x as i32 + x as i32, bounds.min.y as i32 + y as i32, coverage));
            });
        }
        pen += scaled.h_advance(id);
    }
    Some((pixels, (pen.ceil() as i32, (ascent - scaled.descent()).ceil() as i32)))
}

/// [`BitMapBackend`] with [`rasterise`]d text (see the module docs).
pub(crate) struct PngBackend<'a>(pub BitMapBackend<'a>);

impl<'a> PngBackend<'a> {
    /// A PNG file of `size` pixels.
    pub fn new(path: &'a std::path::Path, size: (u32, u32)) -> Self {
        PngBackend(BitMapBackend::new(path, size))
    }
}

type Error<'a> = DrawingErrorKind<<BitMapBackend<'a> as DrawingBackend>::ErrorType>;

impl<'a> DrawingBackend for PngBackend<'a> {
    type ErrorType = <BitMapBackend<'a> as DrawingBackend>::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.0.get_size()
    }
    fn ensure_prepared(&mut self) -> Result<(), Error<'a>> {
        self.0.ensure_prepared()
    }
    fn present(&mut self) -> Result<(), Error<'a>> {
        self.0.present()
    }
    fn draw_pixel(&mut self, point: BackendCoord, color: BackendColor) -> Result<(), Error<'a>> {
        self.0.draw_pixel(point, color)
    }
    fn draw_line<S: BackendStyle>(&mut self, from: BackendCoord, to: BackendCoord, style: &S) -> Result<(), Error<'a>> {
        self.0.draw_line(from, to, style)
    }
    fn draw_rect<S: BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), Error<'a>> {
        self.0.draw_rect(upper_left, bottom_right, style, fill)
    }
    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), Error<'a>> {
        self.0.draw_path(path, style)
    }
    fn draw_circle<S: BackendStyle>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), Error<'a>> {
        self.0.draw_circle(center, radius, style, fill)
    }
    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> Result<(), Error<'a>> {
        self.0.fill_polygon(vert, style)
    }
    fn blit_bitmap(&mut self, pos: BackendCoord, size: (u32, u32), src: &[u8]) -> Result<(), Error<'a>> {
        self.0.blit_bitmap(pos, size, src)
    }

    fn estimate_text_size<S: BackendTextStyle>(&self, text: &str, style: &S) -> Result<(u32, u32), Error<'a>> {
        match rasterise(text, style.size() as f32) {
            Some((_, (w, h))) => Ok((w.max(0) as u32, h.max(0) as u32)),
            None => self.0.estimate_text_size(text, style),
        }
    }

    fn draw_text<S: BackendTextStyle>(&mut self, text: &str, style: &S, pos: BackendCoord) -> Result<(), Error<'a>> {
        let color = style.color();
        if color.alpha == 0.0 {
            return Ok(());
        }
        let Some((pixels, (width, height))) = rasterise(text, style.size() as f32) else {
            return self.0.draw_text(text, style, pos);
        };
        // Anchored and rotated as plotters' default `draw_text` does.
        let dx = match style.anchor().h_pos {
            HPos::Left => 0,
            HPos::Right => -width,
            HPos::Center => -width / 2,
        };
        let dy = match style.anchor().v_pos {
            VPos::Top => 0,
            VPos::Center => -height / 2,
            VPos::Bottom => -height,
        };
        let transform = style.transform();
        let (w, h) = self.get_size();
        for (x, y, coverage) in pixels {
            let (x, y) = transform.transform(x + dx, y + dy);
            let (x, y) = (pos.0 + x, pos.1 + y);
            if x >= 0 && x < w as i32 && y >= 0 && y < h as i32 && coverage > 0.0 {
                let c = BackendColor { alpha: color.alpha * coverage.min(1.0) as f64, rgb: color.rgb };
                self.0.draw_pixel((x, y), c)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Columns that hold ink, grouped into runs separated by blank columns.
    fn ink_runs(pixels: &[(i32, i32, f32)]) -> Vec<(i32, i32)> {
        let mut columns: Vec<i32> = pixels.iter().filter(|p| p.2 > 0.25).map(|p| p.0).collect();
        columns.sort();
        columns.dedup();
        let mut runs: Vec<(i32, i32)> = vec![];
        for x in columns {
            match runs.last_mut() {
                Some(r) if r.1 + 1 == x => r.1 = x,
                _ => runs.push((x, x)),
            }
        }
        runs
    }

    /// `text` drawn at 14 px by plotters onto a white RGB buffer, through
    /// `backend`'s own `draw_text`: the ink runs of the dark pixels.
    fn drawn_runs(text: &str, fixed: bool) -> Vec<(i32, i32)> {
        crate::plots::register_font();
        let (w, h) = (80u32, 30u32);
        let mut buffer = vec![255u8; (w * h * 3) as usize];
        {
            let style = TextStyle::from(("sans-serif", 14).into_font()).color(&BLACK);
            if fixed {
                let root = PngBackend(BitMapBackend::with_buffer(&mut buffer, (w, h))).into_drawing_area();
                root.draw(&Text::new(text, (10, 5), style)).unwrap();
                root.present().unwrap();
            } else {
                let root = BitMapBackend::with_buffer(&mut buffer, (w, h)).into_drawing_area();
                root.draw(&Text::new(text, (10, 5), style)).unwrap();
                root.present().unwrap();
            }
        }
        let pixels: Vec<(i32, i32, f32)> = (0..w * h)
            .filter(|&i| buffer[3 * i as usize] < 128)
            .map(|i| ((i % w) as i32, (i / w) as i32, 1.0))
            .collect();
        ink_runs(&pixels)
    }

    /// The bug at its root, through plotters' drawing API: in a monospaced
    /// font the period of `3.0` is centred in the second character cell
    /// (at 1.5 advances from the pen). With this backend it is; with the
    /// plain bitmap backend it sits against the 3, 3 px early, and leaves a
    /// gap before the 0 (`3. 0`).
    #[test]
    fn every_character_of_a_tick_label_is_where_the_font_puts_it() {
        let font = font().unwrap();
        let advance = font.as_scaled(PxScale::from(14.0)).h_advance(font.glyph_id('0')) as f64;
        let centre = |runs: &[(i32, i32)]| (runs[1].0 + runs[1].1) as f64 / 2.0 + 0.5;
        let expected = 10.0 + 1.5 * advance;
        let fixed = drawn_runs("3.0", true);
        assert_eq!(fixed.len(), 3, "{fixed:?}");
        assert!(
            (centre(&fixed) - expected).abs() <= 1.0,
            "{fixed:?}: period at {}, expected {expected}",
            centre(&fixed)
        );
        let plain = drawn_runs("3.0", false);
        assert!((centre(&plain) - expected).abs() > 2.0, "plotters now places the period right: {plain:?}");
        // A minus and an exponent's minus each keep their own columns.
        assert_eq!(drawn_runs("-0.5", true).len(), 4);
        assert_eq!(drawn_runs("1e-3", true).len(), 4);
    }

    /// At the tick-label size (14 px) the period of `6.0` is a mark of its
    /// own: three runs of ink separated by blank columns, the middle one
    /// narrow, sitting on the baseline (its ink below the digits' middle),
    /// and inside the middle character cell of the monospaced font.
    #[test]
    fn the_period_stands_apart_on_the_baseline() {
        let (pixels, (width, height)) = rasterise("6.0", 14.0).unwrap();
        let runs = ink_runs(&pixels);
        assert_eq!(runs.len(), 3, "{runs:?}");
        let cell = width as f64 / 3.0;
        let dot = runs[1];
        assert!(dot.1 - dot.0 <= 2, "{dot:?}");
        let centre = (dot.0 + dot.1) as f64 / 2.0;
        assert!(centre > cell && centre < 2.0 * cell, "{centre} not in the middle cell of width {cell}");
        let dot_rows: Vec<i32> =
            pixels.iter().filter(|p| p.0 >= dot.0 && p.0 <= dot.1 && p.2 > 0.25).map(|p| p.1).collect();
        let digit_rows: Vec<i32> = pixels.iter().filter(|p| p.0 < runs[0].1 && p.2 > 0.25).map(|p| p.1).collect();
        let mid = (digit_rows.iter().min().unwrap() + digit_rows.iter().max().unwrap()) / 2;
        assert!(dot_rows.iter().all(|&y| y > mid), "the period sits low: {dot_rows:?} vs middle {mid}");
        assert!(height >= 14 && *digit_rows.iter().max().unwrap() < height, "{height}");
    }
}
