//! PNG and OpenEXR images.
//!
//! Writers:
//! - [`write_png_rgb8`]: 8-bit RGB PNG tagged as sRGB (an `sRGB` chunk), for
//!   display-ready pictures.
//! - [`write_exr_rgba`] and [`write_exr_gray`]: linear `f32` OpenEXR images
//!   (ZIP-compressed scan lines), for lossless radiance or scalar maps.
//!
//! Readers ([`read_png_rgb8`], [`read_exr_gray`]) exist mainly for round-trip
//! tests. All pixel buffers are row-major with row 0 at the top.
//!
//! Readers check the image size the header declares against the file's
//! length before decoding: lossless compression (deflate) shrinks data by at
//! most about 1032:1, so a header claiming more pixels than that is rejected
//! instead of allocating a huge buffer.

use std::fs::File;
use std::io::{BufReader, BufWriter};
use std::path::Path;

use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image, ReadChannels, ReadLayers, SmallVec,
    SpecificChannels, Vec2, WritableImage,
};

use crate::IoError;

/// Upper bound on decompressed bytes per byte of file (deflate's limit is
/// about 1032:1; the rest is slack for headers and row filters).
const MAX_EXPANSION: u64 = 1100;

/// Checks that `width * height * channels == len` and that the image is not
/// empty; returns a message otherwise.
fn check_buffer(
    path: &Path,
    width: usize,
    height: usize,
    channels: usize,
    len: usize,
    what: &str,
) -> Result<(), IoError> {
    if width == 0 || height == 0 {
        return Err(IoError::format(
            path,
            format!("cannot write a {width}x{height} image: both sides must be at least 1 pixel"),
        ));
    }
    let expected = width
        .checked_mul(height)
        .and_then(|n| n.checked_mul(channels));
    if expected != Some(len) {
        let expected = expected.map_or("more than fits in memory".to_string(), |n| n.to_string());
        return Err(IoError::format(
            path,
            format!("a {width}x{height} {what} image needs {expected} values but {len} were given"),
        ));
    }
    Ok(())
}

/// Rejects a decoded size that the file could not possibly hold.
fn check_declared_size(path: &Path, bytes: Option<u64>, desc: &str) -> Result<(), IoError> {
    let file_len = std::fs::metadata(path)
        .map_err(|e| IoError::io(path, e))?
        .len();
    match bytes {
        Some(n) if n <= file_len.saturating_mul(MAX_EXPANSION) => Ok(()),
        _ => Err(IoError::format(
            path,
            format!("header declares {desc}, more than a {file_len}-byte file can hold"),
        )),
    }
}

/// Writes an 8-bit RGB PNG (`rgb` holds `width * height * 3` bytes, row 0 at
/// the top) and marks it as sRGB.
pub fn write_png_rgb8(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), IoError> {
    let (w, h) = (width as usize, height as usize);
    check_buffer(path, w, h, 3, rgb.len(), "RGB")?;
    let file = File::create(path).map_err(|e| IoError::io(path, e))?;
    let png_error = |e: png::EncodingError| match e {
        png::EncodingError::IoError(e) => IoError::io(path, e),
        other => IoError::format(path, format!("cannot encode PNG: {other}")),
    };
    let mut encoder = png::Encoder::new(BufWriter::new(file), width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    let mut writer = encoder.write_header().map_err(png_error)?;
    writer.write_image_data(rgb).map_err(png_error)?;
    writer.finish().map_err(png_error)
}

/// Reads a PNG as 8-bit RGB: `(width, height, rgb)` with row 0 at the top.
/// Grayscale, palette, alpha and 16-bit images are converted (alpha is
/// dropped, 16-bit samples keep their high byte).
pub fn read_png_rgb8(path: &Path) -> Result<(u32, u32, Vec<u8>), IoError> {
    let file = File::open(path).map_err(|e| IoError::io(path, e))?;
    let png_error = |e: png::DecodingError| match e {
        png::DecodingError::IoError(e) if e.kind() != std::io::ErrorKind::UnexpectedEof => {
            IoError::io(path, e)
        }
        other => IoError::format(path, format!("invalid PNG file: {other}")),
    };
    let mut decoder = png::Decoder::new(BufReader::new(file));
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().map_err(png_error)?;
    let (width, height) = reader.info().size();
    let size = reader.output_buffer_size();
    check_declared_size(
        path,
        size.map(|n| n as u64),
        &format!("a {width}x{height} image"),
    )?;
    let mut buf = vec![0u8; size.unwrap_or(0)];
    let info = reader.next_frame(&mut buf).map_err(png_error)?;
    buf.truncate(info.buffer_size());

    let rgb = match info.color_type {
        png::ColorType::Rgb => buf,
        png::ColorType::Rgba => buf
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect(),
        png::ColorType::Grayscale => buf.iter().flat_map(|&g| [g, g, g]).collect(),
        png::ColorType::GrayscaleAlpha => buf.chunks_exact(2).flat_map(|p| [p[0]; 3]).collect(),
        png::ColorType::Indexed => {
            return Err(IoError::format(
                path,
                "palette PNG could not be expanded to RGB",
            ));
        }
    };
    let expected = (width as usize)
        .checked_mul(height as usize)
        .and_then(|n| n.checked_mul(3));
    if expected != Some(rgb.len()) {
        return Err(IoError::format(
            path,
            format!(
                "PNG decoded to {} bytes, expected {width}x{height}x3",
                rgb.len()
            ),
        ));
    }
    Ok((width, height, rgb))
}

/// Maps an `exr` error: OS errors stay [`IoError::Io`], the rest become
/// [`IoError::Format`] prefixed with `context`.
fn exr_error(path: &Path, context: &str, e: exr::error::Error) -> IoError {
    match e {
        exr::error::Error::Io(e) => IoError::io(path, e),
        other => IoError::format(path, format!("{context}: {other}")),
    }
}

/// Writes a linear `f32` RGBA OpenEXR image; `rgba` holds
/// `width * height * 4` values, row 0 at the top.
pub fn write_exr_rgba(
    path: &Path,
    width: usize,
    height: usize,
    rgba: &[f32],
) -> Result<(), IoError> {
    check_buffer(path, width, height, 4, rgba.len(), "RGBA")?;
    let channels = SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| {
        let i = (y * width + x) * 4;
        (rgba[i], rgba[i + 1], rgba[i + 2], rgba[i + 3])
    });
    let mut image = Image::from_channels((width, height), channels);
    image.layer_data.encoding = Encoding::SMALL_LOSSLESS;
    image
        .write()
        .to_file(path)
        .map_err(|e| exr_error(path, "cannot write OpenEXR", e))
}

/// Writes a single-channel (`"Y"`) linear `f32` OpenEXR image; `values` holds
/// `width * height` values, row 0 at the top.
pub fn write_exr_gray(
    path: &Path,
    width: usize,
    height: usize,
    values: &[f32],
) -> Result<(), IoError> {
    check_buffer(path, width, height, 1, values.len(), "grayscale")?;
    let channel = AnyChannel::new("Y", FlatSamples::F32(values.to_vec()));
    let channels = AnyChannels::sort(SmallVec::from_vec(vec![channel]));
    let mut image = Image::from_channels((width, height), channels);
    image.layer_data.encoding = Encoding::SMALL_LOSSLESS;
    image
        .write()
        .to_file(path)
        .map_err(|e| exr_error(path, "cannot write OpenEXR", e))
}

/// Reads one channel of the first layer of an OpenEXR image as `f32`:
/// the channel named `"Y"` if there is one, otherwise the first channel.
/// Returns `(width, height, values)` with row 0 at the top.
pub fn read_exr_gray(path: &Path) -> Result<(usize, usize, Vec<f32>), IoError> {
    const CONTEXT: &str = "invalid OpenEXR file";
    // Check the declared sizes before the decoder allocates pixel buffers.
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .map_err(|e| exr_error(path, CONTEXT, e))?;
    for header in &meta.headers {
        let Vec2(w, h) = header.layer_size;
        let bytes = w
            .checked_mul(h)
            .and_then(|n| n.checked_mul(header.channels.bytes_per_pixel))
            .map(|n| n as u64);
        check_declared_size(path, bytes, &format!("a {w}x{h} layer"))?;
    }

    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| exr_error(path, CONTEXT, e))?;
    let layer = image.layer_data;
    let Vec2(width, height) = layer.size;
    let list = &layer.channel_data.list;
    let channel = list
        .iter()
        .find(|c| c.name.eq("Y"))
        .or_else(|| list.first())
        .ok_or_else(|| IoError::format(path, "OpenEXR layer has no channels"))?;
    let values: Vec<f32> = match &channel.sample_data {
        FlatSamples::F16(v) => v.iter().map(|s| s.to_f32()).collect(),
        FlatSamples::F32(v) => v.clone(),
        FlatSamples::U32(v) => v.iter().map(|&s| s as f32).collect(),
    };
    if Some(values.len()) != width.checked_mul(height) {
        return Err(IoError::format(
            path,
            format!(
                "OpenEXR channel '{}' has {} samples for a {width}x{height} image (subsampled channels are not supported)",
                channel.name,
                values.len()
            ),
        ));
    }
    Ok((width, height, values))
}
