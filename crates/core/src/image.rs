//! Linear RGBA images and their conversion to 8-bit sRGB.

/// A linear-light RGBA image, premultiplied alpha, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
}

impl Image {
    pub fn new(width: u32, height: u32) -> Self {
        Image {
            width,
            height,
            pixels: vec![[0.0; 4]; width as usize * height as usize],
        }
    }

    /// Composite over an opaque linear `background` and encode as 8-bit sRGB.
    pub fn to_srgb8(&self, background: [f32; 3]) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.pixels.len() * 3);
        for p in &self.pixels {
            for c in 0..3 {
                let v = p[c] + (1.0 - p[3]) * background[c];
                out.push((linear_to_srgb(v) * 255.0 + 0.5).clamp(0.0, 255.0) as u8);
            }
        }
        out
    }

    /// Flat RGBA floats, for EXR output.
    pub fn to_rgba_f32(&self) -> Vec<f32> {
        self.pixels.iter().flat_map(|p| p.iter().copied()).collect()
    }
}

/// The sRGB transfer curve (IEC 61966-2-1), input clamped to [0, 1].
pub fn linear_to_srgb(v: f32) -> f32 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// Inverse of [`linear_to_srgb`].
pub fn srgb_to_linear(v: f32) -> f32 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}
