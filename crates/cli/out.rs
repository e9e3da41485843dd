//! Output files: checked before any work (see `voxless::output`: known
//! extension, existing directory, never an input), numbered for frame
//! sequences, and written in the format their extension names — always
//! through a temporary file renamed into place.

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use voxless::SceneDesc;
use voxless::output::{ImageFormat, OutputKind, check_outputs, input_files};

/// JPEG quality of `.jpg` outputs.
const JPEG_QUALITY: u8 = 92;

/// Checks `outputs` against the scene's inputs (and `extra_inputs`, such as
/// sample points) before anything is loaded.
pub fn check(
    outputs: &[PathBuf],
    kind: OutputKind,
    desc: &SceneDesc,
    base: &Path,
    extra_inputs: &[PathBuf],
) -> Result<()> {
    let mut inputs = input_files(desc, base);
    inputs.extend(extra_inputs.iter().cloned());
    check_outputs(outputs, kind, &inputs)?;
    Ok(())
}

/// The file of frame number `frame` for `output`: a printf pattern
/// (`f_%03d.png`) is filled in, else `out.png` → `out_0007.png`. A `%` that
/// is no `%d` / `%0Nd` pattern is an error (it would write every frame to
/// one file).
pub fn frame_path(output: &Path, frame: usize) -> Result<PathBuf> {
    let name = output
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    if name.contains('%') {
        let filled = voxless::frames::fill_pattern(output, frame);
        return match filled {
            Some(p) if name.matches('%').count() == 1 => Ok(p),
            _ => bail!(
                "-o {}: a numbered output takes one %d or %0Nd for the frame number (e.g. \
                 frame_%04d.png)",
                output.display()
            ),
        };
    }
    let stem = output
        .file_stem()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = match output.extension() {
        Some(e) => format!("{stem}_{frame:04}.{}", e.to_string_lossy()),
        None => format!("{stem}_{frame:04}"),
    };
    Ok(output.with_file_name(name))
}

/// Writes an image in the format of `output`'s extension (checked before
/// rendering; PNG when it names none).
pub fn write_image(output: &Path, image: &voxless::Image, background: [f32; 3]) -> Result<()> {
    let (w, h) = (image.width, image.height);
    match ImageFormat::of(output) {
        Some(ImageFormat::Exr) => {
            voxless::io::write_exr_rgba(output, w as usize, h as usize, &image.to_rgba_f32())?
        }
        Some(ImageFormat::Jpeg) => {
            voxless::io::write_jpeg_rgb8(output, w, h, &image.to_srgb8(background), JPEG_QUALITY)?
        }
        Some(ImageFormat::Png) | None => {
            voxless::io::write_png_rgb8(output, w, h, &image.to_srgb8(background))?
        }
    }
    Ok(())
}

/// Whether a map output is FITS (written with its world coordinates).
pub fn is_fits(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("fits"))
}

/// Writes a float32 map: `.exr` (one channel) or `.npy` (H×W).
pub fn write_gray(path: &Path, w: u32, h: u32, values: &[f32]) -> Result<()> {
    if ImageFormat::of(path) == Some(ImageFormat::Exr) {
        voxless::io::write_exr_gray(path, w as usize, h as usize, values)?;
    } else {
        voxless::io::write_npy_f32(path, &[h as usize, w as usize], values)?;
    }
    Ok(())
}
