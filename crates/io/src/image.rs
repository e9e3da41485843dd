//! PNG and OpenEXR images.
//!
//! Writers:
//! - [`write_png_rgb8`]: 8-bit RGB PNG tagged as sRGB (an `sRGB` chunk), for
//!   display-ready pictures; [`write_jpeg_rgb8`]: the same as a JPEG.
//! - [`write_exr_rgba`] and [`write_exr_gray`]: linear `f32` OpenEXR images
//!   (ZIP-compressed scan lines), for lossless radiance or scalar maps.
//!
//! Readers ([`read_png_rgb8`], [`read_exr_gray`]) exist mainly for round-trip
//! tests. All pixel buffers are row-major with row 0 at the top. Files are
//! written through a temporary file and renamed ([`crate::write_atomically`]).
//!
//! Readers check the image size the header declares against the file's
//! length before decoding: lossless compression (deflate) shrinks data by at
//! most about 1032:1, so a header claiming more pixels than that is rejected
//! instead of allocating a huge buffer.
//!
//! Every function also has a variant over a writer or reader instead of a
//! path ([`write_png_rgb8_to`], [`write_exr_rgba_to`], [`write_exr_gray_to`],
//! [`read_png_rgb8_from`], [`read_exr_gray_from`]), e.g. to send an image
//! over the network without a file. The path functions open the file and
//! call them; `name` labels the variants' errors as the path does.

use std::io::{BufRead, BufReader, Read, Seek, SeekFrom, Write};
use std::path::Path;

use crate::atomic::write_atomically;

use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image, ReadChannels, ReadLayers, SmallVec,
    SpecificChannels, Vec2, WritableImage,
};

use crate::{IoError, open_with_len, remaining_len};

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

/// Rejects a decoded size that a file of `file_len` bytes could not
/// possibly hold.
fn check_declared_size(
    path: &Path,
    file_len: u64,
    bytes: Option<u64>,
    desc: &str,
) -> Result<(), IoError> {
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
    // Check before creating the file, so a bad call leaves no empty file.
    check_buffer(path, width as usize, height as usize, 3, rgb.len(), "RGB")?;
    write_atomically(path, |out| write_png_rgb8_to(out, path, width, height, rgb))
}

/// Writes an 8-bit RGB baseline JPEG (quality 0–100; 90 is a good
/// default), row 0 at the top: for pictures where size matters more than
/// exactness. Sides are at most 65,535 pixels.
pub fn write_jpeg_rgb8(
    path: &Path,
    width: u32,
    height: u32,
    rgb: &[u8],
    quality: u8,
) -> Result<(), IoError> {
    check_buffer(path, width as usize, height as usize, 3, rgb.len(), "RGB")?;
    write_atomically(path, |out| {
        write_jpeg_rgb8_to(out, path, width, height, rgb, quality)
    })
}

/// [`write_jpeg_rgb8`] into any writer; `name` labels errors.
pub fn write_jpeg_rgb8_to<W: Write>(
    out: W,
    name: &Path,
    width: u32,
    height: u32,
    rgb: &[u8],
    quality: u8,
) -> Result<(), IoError> {
    check_buffer(name, width as usize, height as usize, 3, rgb.len(), "RGB")?;
    let (w, h) = match (u16::try_from(width), u16::try_from(height)) {
        (Ok(w), Ok(h)) => (w, h),
        _ => {
            return Err(IoError::format(
                name,
                format!("a JPEG is at most 65535 pixels a side, not {width}×{height}"),
            ));
        }
    };
    jpeg_encoder::Encoder::new(out, quality.min(100))
        .encode(rgb, w, h, jpeg_encoder::ColorType::Rgb)
        .map_err(|e| IoError::format(name, format!("cannot encode JPEG: {e}")))
}

/// [`write_png_rgb8`] into any writer (a `Vec<u8>`, a socket), flushed at
/// the end; `name` labels errors.
pub fn write_png_rgb8_to<W: Write>(
    mut out: W,
    name: &Path,
    width: u32,
    height: u32,
    rgb: &[u8],
) -> Result<(), IoError> {
    let (w, h) = (width as usize, height as usize);
    check_buffer(name, w, h, 3, rgb.len(), "RGB")?;
    let png_error = |e: png::EncodingError| match e {
        png::EncodingError::IoError(e) => IoError::io(name, e),
        other => IoError::format(name, format!("cannot encode PNG: {other}")),
    };
    let mut encoder = png::Encoder::new(&mut out, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    let mut writer = encoder.write_header().map_err(png_error)?;
    writer.write_image_data(rgb).map_err(png_error)?;
    writer.finish().map_err(png_error)?;
    // A buffered writer would otherwise flush on drop and lose its error.
    out.flush().map_err(|e| IoError::io(name, e))
}

/// Reads a PNG as 8-bit RGB: `(width, height, rgb)` with row 0 at the top.
/// Grayscale, palette, alpha and 16-bit images are converted (alpha is
/// dropped, 16-bit samples keep their high byte).
pub fn read_png_rgb8(path: &Path) -> Result<(u32, u32, Vec<u8>), IoError> {
    let (file, len) = open_with_len(path)?;
    decode_png(BufReader::new(file), len, path)
}

/// [`read_png_rgb8`] of the PNG from `reader`'s position to its end;
/// `name` labels errors. The reader's length bounds the image size as the
/// file's does.
pub fn read_png_rgb8_from<R: Read + Seek>(
    mut reader: R,
    name: &Path,
) -> Result<(u32, u32, Vec<u8>), IoError> {
    let len = remaining_len(&mut reader, name)?;
    decode_png(BufReader::new(reader), len, name)
}

/// The PNG decoder behind both readers: `reader` holds `len` bytes and
/// `path` labels errors.
fn decode_png(
    reader: impl BufRead + Seek,
    len: u64,
    path: &Path,
) -> Result<(u32, u32, Vec<u8>), IoError> {
    let png_error = |e: png::DecodingError| match e {
        png::DecodingError::IoError(e) if e.kind() != std::io::ErrorKind::UnexpectedEof => {
            IoError::io(path, e)
        }
        other => IoError::format(path, format!("invalid PNG file: {other}")),
    };
    let mut decoder = png::Decoder::new(reader);
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().map_err(png_error)?;
    let (width, height) = reader.info().size();
    let size = reader.output_buffer_size();
    check_declared_size(
        path,
        len,
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

/// A reader or writer seen from the position it had when wrapped. The `exr`
/// crate seeks to offsets counted from the start of its stream; this makes
/// that start the image's first byte wherever the image lies in the stream.
struct FromHere<T> {
    inner: T,
    base: u64,
}

impl<T: Seek> FromHere<T> {
    fn new(mut inner: T) -> std::io::Result<FromHere<T>> {
        let base = inner.stream_position()?;
        Ok(FromHere { inner, base })
    }
}

impl<T: Read> Read for FromHere<T> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        self.inner.read(buf)
    }
}

impl<T: Write> Write for FromHere<T> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.inner.write(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

impl<T: Seek> Seek for FromHere<T> {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        let outside = || {
            std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "seek outside the image's part of the stream",
            )
        };
        // Only absolute positions need shifting; relative ones are relative
        // to the inner position either way.
        let pos = match pos {
            SeekFrom::Start(n) => SeekFrom::Start(self.base.checked_add(n).ok_or_else(outside)?),
            other => other,
        };
        let at = self.inner.seek(pos)?;
        at.checked_sub(self.base).ok_or_else(outside)
    }
}

/// Creates the file `path`, lets `write` fill it, and removes it again when
/// that fails, so a failed write leaves no truncated image behind (as the
/// `exr` crate's own file writer does).
/// Writes a linear `f32` RGBA OpenEXR image; `rgba` holds
/// `width * height * 4` values, row 0 at the top.
pub fn write_exr_rgba(
    path: &Path,
    width: usize,
    height: usize,
    rgba: &[f32],
) -> Result<(), IoError> {
    // Check before creating the file, so a bad call leaves no empty file.
    check_buffer(path, width, height, 4, rgba.len(), "RGBA")?;
    write_atomically(path, |out| {
        write_exr_rgba_to(out, path, width, height, rgba)
    })
}

/// [`write_exr_rgba`] into any seekable writer (a `Cursor<Vec<u8>>`, a
/// file), starting at its current position (OpenEXR's offset tables are
/// written last, after seeking back); `name` labels errors.
pub fn write_exr_rgba_to<W: Write + Seek>(
    out: W,
    name: &Path,
    width: usize,
    height: usize,
    rgba: &[f32],
) -> Result<(), IoError> {
    check_buffer(name, width, height, 4, rgba.len(), "RGBA")?;
    let channels = SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| {
        let i = (y * width + x) * 4;
        (rgba[i], rgba[i + 1], rgba[i + 2], rgba[i + 3])
    });
    let mut image = Image::from_channels((width, height), channels);
    image.layer_data.encoding = Encoding::SMALL_LOSSLESS;
    let out = FromHere::new(out).map_err(|e| IoError::io(name, e))?;
    image
        .write()
        .to_unbuffered(out)
        .map_err(|e| exr_error(name, "cannot write OpenEXR", e))
}

/// Writes a single-channel (`"Y"`) linear `f32` OpenEXR image; `values` holds
/// `width * height` values, row 0 at the top.
pub fn write_exr_gray(
    path: &Path,
    width: usize,
    height: usize,
    values: &[f32],
) -> Result<(), IoError> {
    // Check before creating the file, so a bad call leaves no empty file.
    check_buffer(path, width, height, 1, values.len(), "grayscale")?;
    write_atomically(path, |out| {
        write_exr_gray_to(out, path, width, height, values)
    })
}

/// [`write_exr_gray`] into any seekable writer, starting at its current
/// position; `name` labels errors.
pub fn write_exr_gray_to<W: Write + Seek>(
    out: W,
    name: &Path,
    width: usize,
    height: usize,
    values: &[f32],
) -> Result<(), IoError> {
    check_buffer(name, width, height, 1, values.len(), "grayscale")?;
    let channel = AnyChannel::new("Y", FlatSamples::F32(values.to_vec()));
    let channels = AnyChannels::sort(SmallVec::from_vec(vec![channel]));
    let mut image = Image::from_channels((width, height), channels);
    image.layer_data.encoding = Encoding::SMALL_LOSSLESS;
    let out = FromHere::new(out).map_err(|e| IoError::io(name, e))?;
    image
        .write()
        .to_unbuffered(out)
        .map_err(|e| exr_error(name, "cannot write OpenEXR", e))
}

/// Reads one channel of the first layer of an OpenEXR image as `f32`:
/// the channel named `"Y"` if there is one, otherwise the first channel.
/// Returns `(width, height, values)` with row 0 at the top.
pub fn read_exr_gray(path: &Path) -> Result<(usize, usize, Vec<f32>), IoError> {
    let (file, len) = open_with_len(path)?;
    decode_exr_gray(file, len, path)
}

/// [`read_exr_gray`] of the OpenEXR image from `reader`'s position to its
/// end; `name` labels errors. The reader's length bounds the layer sizes
/// as the file's does.
pub fn read_exr_gray_from<R: Read + Seek>(
    mut reader: R,
    name: &Path,
) -> Result<(usize, usize, Vec<f32>), IoError> {
    let len = remaining_len(&mut reader, name)?;
    decode_exr_gray(reader, len, name)
}

/// The OpenEXR decoder behind both readers: `reader` holds `len` bytes and
/// `path` labels errors.
fn decode_exr_gray(
    reader: impl Read + Seek,
    len: u64,
    path: &Path,
) -> Result<(usize, usize, Vec<f32>), IoError> {
    const CONTEXT: &str = "invalid OpenEXR file";
    let mut src = FromHere::new(reader).map_err(|e| IoError::io(path, e))?;
    // Check the declared sizes before the decoder allocates pixel buffers.
    let meta = exr::meta::MetaData::read_from_unbuffered(&mut src, false)
        .map_err(|e| exr_error(path, CONTEXT, e))?;
    for header in &meta.headers {
        let Vec2(w, h) = header.layer_size;
        let bytes = w
            .checked_mul(h)
            .and_then(|n| n.checked_mul(header.channels.bytes_per_pixel))
            .map(|n| n as u64);
        check_declared_size(path, len, bytes, &format!("a {w}x{h} layer"))?;
    }

    // Then decode from the start again.
    src.seek(SeekFrom::Start(0))
        .map_err(|e| IoError::io(path, e))?;
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_unbuffered(src)
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
