//! A labelled colour bar drawn into a rendered image.
//!
//! Layout: a vertical bar inset from the right edge by 3 % of the image
//! height, about 70 % of the height tall, its top row the transfer
//! function's colour at 1 and its bottom row the colour at 0. Tick marks and
//! labels on its left give the minimum, middle and maximum of the range the
//! colours stand for; the title (the field name, prefixed with `log10` when
//! the transfer function maps log10 of the value) sits above it. Text is the
//! built-in 5×7 font ([`crate::font`]) scaled with the image height (×1 up
//! to 359 rows, ×2 up to 539, …), white with a dark outline, so it reads on
//! dark and light backgrounds alike; the bar has a dark frame.
//!
//! The bar shows colour only: opacity is not drawn (a linear opacity ramp
//! would hide the low end of the colours, which is what the bar is for).
//!
//! Everything is drawn opaque (alpha 1) into the linear premultiplied image,
//! so it survives compositing over the background and EXR output alike, and
//! every write is clipped to the image: a bar that does not fit loses its
//! title, then its labels, and tiny images get what fits.

use voxless_core::Image;
use voxless_transfer::TransferFunction;

use crate::font;

/// What a colour bar says.
#[derive(Clone, Debug, PartialEq)]
pub struct ColorbarSpec {
    /// The value at the bottom of the bar (in log10 units when `log10`).
    pub lo: f32,
    /// The value at the top of the bar.
    pub hi: f32,
    /// The transfer function maps log10 of the value; the title says so.
    pub log10: bool,
    /// The field's name, when known.
    pub label: Option<String>,
}

impl ColorbarSpec {
    /// The text above the bar: the field name, `log10 name` in log scale.
    pub fn title(&self) -> Option<String> {
        match (self.log10, &self.label) {
            (true, Some(l)) => Some(format!("log10 {l}")),
            (true, None) => Some("log10".into()),
            (false, Some(l)) => Some(l.clone()),
            (false, None) => None,
        }
    }
}

/// A half-open pixel rectangle `[x0, x1) × [y0, y1)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rect {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

/// Where a colour bar went.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ColorbarLayout {
    /// The colour ramp (inside its frame).
    pub bar: Rect,
    /// Every pixel drawn lies inside this rectangle.
    pub strip: Rect,
    /// Font scale (pixels per font pixel); 0 when no text was drawn.
    pub scale: u32,
}

/// A tick label: up to four significant digits, plain for magnitudes in
/// [0.001, 100000), else scientific (`1.5e-7`).
pub fn format_tick(v: f32) -> String {
    if !v.is_finite() {
        return v.to_string().to_lowercase();
    }
    if v == 0.0 {
        return "0".into();
    }
    let trim = |s: String| -> String {
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    };
    let v = v as f64;
    let a = v.abs();
    if (1e-3..1e5).contains(&a) {
        let decimals = (3 - a.log10().floor() as i32).clamp(0, 6) as usize;
        trim(format!("{v:.decimals$}"))
    } else {
        let s = format!("{v:.3e}");
        match s.split_once('e') {
            Some((mantissa, exp)) => format!("{}e{exp}", trim(mantissa.to_string())),
            None => s,
        }
    }
}

/// What a pixel of the overlay holds.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Mark {
    None,
    Outline,
    Ink,
}

/// Marks drawn over an image: dark outlines and white ink (shared by the
/// colour bar and the annotations, [`crate::annotate`]).
pub(crate) struct Overlay {
    w: i64,
    h: i64,
    marks: Vec<Mark>,
    /// Bounding box of what is drawn: (x0, y0, x1, y1), half-open.
    bbox: Option<(i64, i64, i64, i64)>,
}

impl Overlay {
    pub(crate) fn new(w: i64, h: i64) -> Self {
        Overlay {
            w,
            h,
            marks: vec![Mark::None; (w * h) as usize],
            bbox: None,
        }
    }

    fn touch(&mut self, x: i64, y: i64) {
        let b = self.bbox.get_or_insert((x, y, x + 1, y + 1));
        *b = (b.0.min(x), b.1.min(y), b.2.max(x + 1), b.3.max(y + 1));
    }

    /// Sets a mark inside the image; ink wins over outline.
    fn mark(&mut self, x: i64, y: i64, m: Mark) {
        if x < 0 || y < 0 || x >= self.w || y >= self.h {
            return;
        }
        let slot = &mut self.marks[(y * self.w + x) as usize];
        if *slot != Mark::Ink {
            *slot = m;
        }
        self.touch(x, y);
    }

    pub(crate) fn fill(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, m: Mark) {
        for y in y0.max(0)..y1.min(self.h) {
            for x in x0.max(0)..x1.min(self.w) {
                self.mark(x, y, m);
            }
        }
    }

    /// Draws the marks into `image` (of the overlay's size), opaque.
    pub(crate) fn apply(&self, image: &mut Image) {
        for (p, m) in image.pixels.iter_mut().zip(&self.marks) {
            match m {
                Mark::None => {}
                Mark::Outline => *p = [0.0, 0.0, 0.0, 1.0],
                Mark::Ink => *p = [1.0, 1.0, 1.0, 1.0],
            }
        }
    }

    /// Text with its top left corner at (x, y), and an outline `o` pixels wide.
    pub(crate) fn text(&mut self, s: &str, x: i64, y: i64, scale: u32, o: i64) {
        let mut ink = Vec::new();
        font::rasterize(s, x, y, scale, |px, py| ink.push((px, py)));
        for &(px, py) in &ink {
            self.fill(px - o, py - o, px + o + 1, py + o + 1, Mark::Outline);
        }
        for &(px, py) in &ink {
            self.mark(px, py, Mark::Ink);
        }
    }
}

/// Draws the colour bar for `tf` into `image` and says where it went, or
/// `None` when the image is too small for any bar.
pub fn draw_colorbar(
    image: &mut Image,
    tf: &TransferFunction,
    spec: &ColorbarSpec,
) -> Option<ColorbarLayout> {
    let (w, h) = (image.width as i64, image.height as i64);
    if w < 3 || h < 3 || image.pixels.len() as i64 != w * h {
        return None;
    }
    let margin = ((h as f32 * 0.03).round() as i64).max(1);
    let bar_w = ((h as f32 * 0.035).round() as i64)
        .max(2)
        .min((w / 8).max(1));
    // Width of the dark frame around the bar.
    let outline = 1;
    let bx1 = w - margin - outline;
    let bx0 = bx1 - bar_w;

    let ticks = [spec.lo, 0.5 * (spec.lo + spec.hi), spec.hi].map(format_tick);
    let mut scale = (image.height / 180).max(1);
    let mut title = spec.title();
    // Shrink the text until the labels take at most half the width.
    let label_w = |s: u32| {
        ticks
            .iter()
            .map(|t| font::text_width(t, s))
            .max()
            .unwrap_or(0) as i64
    };
    while scale > 1 && label_w(scale) > w / 2 {
        scale -= 1;
    }
    let s = scale as i64;
    let o = (s / 2).max(1);
    let tick_len = 2 * s;
    let glyph_h = font::GLYPH_H as i64 * s;
    let half_text = (glyph_h + 1) / 2 + o;
    // The labels' right edge, and whether they fit on the left of the bar.
    let label_x1 = bx0 - outline - tick_len - s;
    let mut labels = label_x1 - label_w(scale) - o >= 0;
    if let Some(t) = &title {
        // Truncate a long name to the width the labels and bar take (at
        // least half the image).
        let room = (w / 2).max(bx1 - label_x1 + label_w(scale));
        let max_chars = ((room / s + 1) / font::ADVANCE as i64).max(0) as usize;
        let n = t.chars().count();
        if n > max_chars {
            let keep = max_chars.saturating_sub(2);
            title = Some(t.chars().take(keep).chain("..".chars()).collect());
        }
    }
    let title_h = if title.is_some() {
        glyph_h + s + 2 * o
    } else {
        0
    };
    let mut top = margin + outline + half_text + title_h;
    let mut bottom = h - margin - outline - half_text;
    let min_bar = 2 * (glyph_h + 2 * o) + 1;
    if bottom - top < min_bar {
        title = None;
        top = margin + outline + half_text;
    }
    if bottom - top < min_bar || !labels {
        labels = false;
        title = None;
        top = margin + outline;
        bottom = h - margin - outline;
    }
    let avail = bottom - top;
    if avail < 1 || bx0 < 1 {
        return None;
    }
    let bar_h = avail.min((h as f32 * 0.7).round() as i64).max(1);
    let by0 = top + (avail - bar_h) / 2;
    let by1 = by0 + bar_h;

    let mut ov = Overlay::new(w, h);
    // Dark frame around the bar.
    ov.fill(
        bx0 - outline,
        by0 - outline,
        bx1 + outline,
        by1 + outline,
        Mark::Outline,
    );
    if labels {
        let th = (s / 2).max(1);
        let rows = [by1 - 1, (by0 + by1 - 1) / 2, by0];
        for (text, &ty) in ticks.iter().zip(&rows) {
            let y0 = ty - (th - 1) / 2;
            let tx0 = bx0 - outline - tick_len;
            ov.fill(tx0 - o, y0 - o, bx0 - outline, y0 + th + o, Mark::Outline);
            ov.fill(tx0, y0, bx0 - outline, y0 + th, Mark::Ink);
            let tw = font::text_width(text, scale) as i64;
            ov.text(text, label_x1 - tw, ty - glyph_h / 2, scale, o);
        }
        if let Some(t) = &title {
            let tw = font::text_width(t, scale) as i64;
            let ty = by0 - outline - half_text - s - o - glyph_h;
            ov.text(t, (bx1 - tw).max(o), ty, scale, o);
        }
    }
    ov.apply(image);
    for y in by0..by1 {
        let t = if bar_h > 1 {
            (by1 - 1 - y) as f32 / (bar_h - 1) as f32
        } else {
            1.0
        };
        let c = tf.color(t);
        for x in bx0..bx1 {
            image.pixels[(y * w + x) as usize] = [c.x, c.y, c.z, 1.0];
        }
    }
    let (x0, y0, x1, y1) = ov.bbox.unwrap_or((bx0, by0, bx1, by1));
    let r = |a: i64| a.clamp(0, i64::from(u32::MAX)) as u32;
    Some(ColorbarLayout {
        bar: Rect {
            x0: r(bx0),
            y0: r(by0),
            x1: r(bx1),
            y1: r(by1),
        },
        strip: Rect {
            x0: r(x0.min(bx0)),
            y0: r(y0.min(by0)),
            x1: r(x1.max(bx1)),
            y1: r(y1.max(by1)),
        },
        scale: if labels { scale } else { 0 },
    })
}

#[cfg(test)]
#[path = "colorbar_tests.rs"]
mod tests;
