//! Images to bytes for the page: JPEG while the view is still changing
//! (small and fast to encode), PNG once converged (lossless: the saved
//! image equals `voxless render`'s).

use std::path::Path;

use voxless::Image;

use crate::ServeError;

/// JPEG quality of coarse and intermediate images.
const JPEG_QUALITY: u8 = 85;

/// An encoded image and its MIME type.
pub struct Encoded {
    pub bytes: Vec<u8>,
    pub mime: &'static str,
}

/// `image` over `background` as 8-bit sRGB, JPEG (`lossless` false) or PNG.
pub fn encode(image: &Image, background: [f32; 3], lossless: bool) -> Result<Encoded, ServeError> {
    let rgb = image.to_srgb8(background);
    if lossless {
        png(image.width, image.height, &rgb).map(|bytes| Encoded {
            bytes,
            mime: "image/png",
        })
    } else {
        jpeg(image.width, image.height, &rgb).map(|bytes| Encoded {
            bytes,
            mime: "image/jpeg",
        })
    }
}

/// PNG bytes of an RGB8 image.
pub fn png(width: u32, height: u32, rgb: &[u8]) -> Result<Vec<u8>, ServeError> {
    let mut out = Vec::new();
    voxless::io::write_png_rgb8_to(&mut out, Path::new("frame.png"), width, height, rgb)
        .map_err(|e| ServeError::Encode(e.to_string()))?;
    Ok(out)
}

/// JPEG bytes of an RGB8 image (sides up to 65535).
pub fn jpeg(width: u32, height: u32, rgb: &[u8]) -> Result<Vec<u8>, ServeError> {
    let (Ok(w), Ok(h)) = (u16::try_from(width), u16::try_from(height)) else {
        return Err(ServeError::Encode(format!(
            "{width}×{height} is too large for JPEG"
        )));
    };
    let mut out = Vec::new();
    jpeg_encoder::Encoder::new(&mut out, JPEG_QUALITY)
        .encode(rgb, w, h, jpeg_encoder::ColorType::Rgb)
        .map_err(|e| ServeError::Encode(e.to_string()))?;
    Ok(out)
}
