//! Annotations drawn into an image by the library, so that every front-end
//! (CLI, viewer, Python) puts the same ones on its images and movies:
//!
//! - a **scale bar** in the bottom left corner: a bar whose length is a
//!   round world length (1, 2 or 5 × 10ᵏ, the largest not longer than a
//!   fifth of the image width), labelled with that length and the unit
//!   when known;
//! - a **label** in the top left corner (a time or redshift).
//!
//! Both are white with a dark outline, scaled with the image height as the
//! colour bar's text is ([`crate::colorbar`]), clipped to the image, and
//! left out (`None`) when the image is too small to hold them.

use voxless_core::Image;

use crate::colorbar::{Mark, Overlay, Rect};
use crate::font;

/// The text scale and outline width for an image `h` rows tall.
fn text_scale(h: u32) -> (u32, i64) {
    let s = (h / 180).max(1);
    (s, (s as i64 / 2).max(1))
}

/// The round length a scale bar shows for `world_per_pixel` across `w`
/// pixels: 1, 2 or 5 × 10ᵏ, at most a fifth of the image's world width.
pub fn scale_bar_length(world_per_pixel: f64, w: u32) -> Option<f64> {
    let most = 0.2 * w as f64 * world_per_pixel;
    if !(most.is_finite() && most > 0.0) {
        return None;
    }
    let k = most.log10().floor() as i32;
    // Parsed from decimal so that 5e-6 is the double nearest 5·10⁻⁶.
    [5, 2, 1]
        .into_iter()
        .filter_map(|m| format!("{m}e{k}").parse::<f64>().ok())
        .find(|&l| l <= most * (1.0 + 1e-9))
}

/// A length as a short label: `0.5`, `20`, `1e-05`, `2e+06`.
pub fn format_length(l: f64) -> String {
    if (1e-3..1e5).contains(&l.abs()) {
        let s = format!("{l:.6}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        let s = format!("{l:e}");
        s.replace("e-", "e-0").replace("e-00", "e-0")
    }
}

/// Draws a scale bar for an image whose pixels are `world_per_pixel` wide
/// (at the depth it applies to), labelled with `unit` when given. Returns
/// where it went, or `None` when the image is too small.
pub fn draw_scale_bar(image: &mut Image, world_per_pixel: f64, unit: Option<&str>) -> Option<Rect> {
    let (w, h) = (image.width, image.height);
    if w < 16 || h < 16 || image.pixels.len() != (w * h) as usize {
        return None;
    }
    let length = scale_bar_length(world_per_pixel, w)?;
    let px = (length / world_per_pixel).round() as i64;
    let label = match unit {
        Some(u) if !u.is_empty() => format!("{} {u}", format_length(length)),
        _ => format_length(length),
    };
    let (scale, o) = text_scale(h);
    let glyph_h = font::GLYPH_H as i64 * scale as i64;
    let margin = ((h as f32 * 0.03).round() as i64).max(2);
    let thick = (scale as i64 * 2).max(2);
    let (x0, y1) = (margin, h as i64 - margin);
    let bar_y0 = y1 - thick;
    let text_y = bar_y0 - 2 * o - scale as i64 - glyph_h;
    if px < 2 || text_y < 0 || x0 + px > w as i64 - margin {
        return None;
    }
    let mut ov = Overlay::new(w as i64, h as i64);
    ov.fill(x0 - o, bar_y0 - o, x0 + px + o, y1 + o, Mark::Outline);
    ov.fill(x0, bar_y0, x0 + px, y1, Mark::Ink);
    ov.text(&label, x0, text_y, scale, o);
    ov.apply(image);
    Some(Rect {
        x0: (x0 - o).max(0) as u32,
        y0: (text_y - o).max(0) as u32,
        x1: (x0 + px + o).max(x0 + font::text_width(&label, scale) as i64 + o) as u32,
        y1: (y1 + o).min(h as i64) as u32,
    })
}

/// Draws `text` in the top left corner; `None` when it does not fit.
pub fn draw_label(image: &mut Image, text: &str) -> Option<Rect> {
    let (w, h) = (image.width, image.height);
    if w < 8 || h < 8 || image.pixels.len() != (w * h) as usize {
        return None;
    }
    let (mut scale, o) = text_scale(h);
    let margin = ((h as f32 * 0.03).round() as i64).max(2);
    while scale > 1 && font::text_width(text, scale) as i64 > w as i64 - 2 * margin {
        scale -= 1;
    }
    let tw = font::text_width(text, scale) as i64;
    let th = font::GLYPH_H as i64 * scale as i64;
    if tw > w as i64 - 2 * margin || th + 2 * margin > h as i64 {
        return None;
    }
    let mut ov = Overlay::new(w as i64, h as i64);
    ov.text(text, margin, margin, scale, o);
    ov.apply(image);
    Some(Rect {
        x0: (margin - o) as u32,
        y0: (margin - o) as u32,
        x1: (margin + tw + o) as u32,
        y1: (margin + th + o) as u32,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scale_bars_are_round_and_at_most_a_fifth() {
        assert_eq!(scale_bar_length(0.01, 500), Some(1.0));
        assert_eq!(scale_bar_length(0.013, 500), Some(1.0));
        assert_eq!(scale_bar_length(0.021, 500), Some(2.0));
        assert_eq!(scale_bar_length(0.06, 500), Some(5.0));
        assert_eq!(scale_bar_length(3e-7, 100), Some(5e-6));
        assert_eq!(scale_bar_length(0.0, 100), None);
        assert_eq!(format_length(0.5), "0.5");
        assert_eq!(format_length(20.0), "20");
        assert_eq!(format_length(1e-5), "1e-05");
    }

    #[test]
    fn a_scale_bar_is_as_long_as_its_label_says() {
        let mut image = Image::new(600, 200);
        let r = draw_scale_bar(&mut image, 0.01, Some("kpc")).unwrap();
        // The ink of the bar's bottom row: 1 kpc = 100 pixels.
        let row = r.y1 as usize - 2;
        let ink = (0..600)
            .filter(|&x| image.pixels[row * 600 + x] == [1.0, 1.0, 1.0, 1.0])
            .count();
        assert_eq!(ink, 100);
        assert!(draw_scale_bar(&mut Image::new(10, 10), 0.01, None).is_none());
        let mut image = Image::new(300, 100);
        assert!(draw_label(&mut image, "t = 1.25").is_some());
        assert!(image.pixels.contains(&[1.0, 1.0, 1.0, 1.0]));
    }
}
