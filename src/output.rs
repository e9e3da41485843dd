//! Outputs that never destroy inputs: before any work starts, every output
//! path is checked — a known extension for what is written, an existing
//! directory to write into, no two outputs on one file, and never one of the
//! scene's input files (compared as files, so a symbolic or hard link to an
//! input counts as the input). The writers of `voxless_io` then write
//! through a temporary file and rename it, so a failed or interrupted run
//! leaves no partial file and keeps what was there.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use voxless_scene::SceneDesc;

use crate::SceneError;
use crate::load::frames;

/// The formats an image is written in, by the output's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// `.png`: 8-bit sRGB.
    Png,
    /// `.jpg` / `.jpeg`: 8-bit sRGB, lossy.
    Jpeg,
    /// `.exr`: linear float RGBA.
    Exr,
}

impl ImageFormat {
    /// The format `path`'s extension names (case-insensitive).
    pub fn of(path: &Path) -> Option<ImageFormat> {
        match extension(path).as_deref() {
            Some("png") => Some(ImageFormat::Png),
            Some("jpg" | "jpeg") => Some(ImageFormat::Jpeg),
            Some("exr") => Some(ImageFormat::Exr),
            _ => None,
        }
    }
}

/// What an output holds, and so which extensions it may have.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputKind {
    /// A rendered image: `.png`, `.jpg`/`.jpeg` or `.exr`.
    Image,
    /// A float32 map (a projection): `.npy`, `.exr` or `.fits` (with a
    /// world coordinate system and the data's unit).
    Map,
    /// Float32 columns (sampled fields): `.npy`.
    Columns,
    /// A slice: a map's formats, or `.png` (colormapped).
    Slice,
    /// A movie: `.mp4`, `.webm` or `.gif` (see [`crate::movie`]).
    Movie,
}

impl OutputKind {
    fn extensions(self) -> &'static [&'static str] {
        match self {
            OutputKind::Image => &["png", "jpg", "jpeg", "exr"],
            OutputKind::Map => &["npy", "exr", "fits"],
            OutputKind::Columns => &["npy"],
            OutputKind::Slice => &["npy", "exr", "fits", "png"],
            OutputKind::Movie => &["mp4", "webm", "gif"],
        }
    }
}

/// The most bytes an image file of `width`×`height` in `path`'s format
/// takes: float32 RGBA for EXR; RGB8 with a filter byte a row and stored
/// deflate blocks' headers for PNG (JPEG stays below that too); plus the
/// headers.
pub fn image_bytes_at_most(path: &Path, width: u32, height: u32) -> u64 {
    let pixels = width as u64 * height as u64;
    let headers = 4096;
    match extension(path).as_deref() {
        Some("exr") => pixels * 16 + height as u64 * 8 + headers,
        _ => {
            let raw = pixels * 3 + height as u64;
            raw + raw.div_ceil(65535) * 5 + headers
        }
    }
}

/// Checks before a sequence renders that its `frames` image files, each
/// `width`×`height` and named like `first`, fit on the disk (see
/// [`crate::budget::check_disk`]); `what` is the flag that asked for them.
pub fn check_frames_disk(
    first: &Path,
    frames: usize,
    (width, height): (u32, u32),
    what: &str,
) -> Result<Option<String>, SceneError> {
    let at_most = image_bytes_at_most(first, width, height);
    crate::budget::check_disk(&directory_of(first), frames as u64, at_most, what)
}

fn extension(path: &Path) -> Option<String> {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
}

/// Every input file the scene reads, as far as it can be told before
/// loading: data files (every file of a sequence), per-particle files,
/// AMR cells, scalars and AMRClaw output, colormap files. Paths that name
/// no existing file (column names, files still to be checked by the
/// readers) are left out.
pub fn input_files(desc: &SceneDesc, base: &Path) -> Vec<PathBuf> {
    let mut specs: Vec<&str> = Vec::new();
    if let Some(p) = &desc.particles {
        specs.extend(p.file.as_deref());
        specs.extend(p.attribute.as_deref());
        specs.extend(p.radii.as_deref());
        specs.extend(p.weights.as_deref());
    }
    if let Some(a) = &desc.amr {
        specs.extend(a.cells.as_deref());
        specs.extend(a.amrclaw.as_deref());
        specs.extend(a.file.as_deref());
        specs.extend(a.scalars.iter().flatten().map(String::as_str));
    }
    if let Some(t) = &desc.tets {
        specs.extend(t.file.as_deref());
    }
    specs.extend(desc.transfer.colormap_file.as_deref());
    let mut files = Vec::new();
    for spec in specs {
        if frames::is_sequence(spec, base) {
            files.extend(frames::expand(spec, base).unwrap_or_default());
        } else {
            files.push(base.join(spec));
        }
    }
    files.retain(|f| f.is_file());
    files
}

/// What makes two paths the same file: the same device and inode (so
/// hard and symbolic links count) for a file that exists, else the
/// canonical directory and the name.
#[derive(Clone, PartialEq, Eq, Hash)]
enum Identity {
    Inode(u64, u64),
    Path(PathBuf),
}

/// The identity of `path` (see [`Identity`]) and whether it is a
/// directory; `dirs` caches each parent directory's canonical form (`None`:
/// not a directory), so the frames of one directory cost a `stat` each.
fn identity(path: &Path, dirs: &mut HashMap<PathBuf, Option<PathBuf>>) -> (Identity, bool) {
    let meta = std::fs::metadata(path).ok();
    let is_dir = meta.as_ref().is_some_and(|m| m.is_dir());
    #[cfg(unix)]
    if let Some(m) = &meta {
        use std::os::unix::fs::MetadataExt;
        return (Identity::Inode(m.dev(), m.ino()), is_dir);
    }
    if meta.is_some()
        && let Ok(c) = path.canonicalize()
    {
        return (Identity::Path(c), is_dir);
    }
    let dir = directory_of(path);
    let canonical = dirs.entry(dir.clone()).or_insert_with(|| {
        dir.is_dir()
            .then(|| dir.canonicalize().unwrap_or(dir.clone()))
    });
    let dir = canonical.clone().unwrap_or(dir);
    let id = match path.file_name() {
        Some(name) => dir.join(name),
        None => path.to_path_buf(),
    };
    (Identity::Path(id), is_dir)
}

/// The directory `path` is written into.
fn directory_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Checks outputs before any work (module docs): `outputs` of `kind`, and
/// the files the work reads (`inputs`). Errors name the output and say
/// what is wrong with it.
pub fn check_outputs(
    outputs: &[PathBuf],
    kind: OutputKind,
    inputs: &[PathBuf],
) -> Result<(), SceneError> {
    let allowed = kind.extensions();
    // One identity per file, so a million frames cost a million lookups
    // (comparing each output with every earlier one took minutes).
    let mut dirs = HashMap::new();
    let inputs: HashMap<Identity, &PathBuf> = inputs
        .iter()
        .map(|p| (identity(p, &mut dirs).0, p))
        .collect();
    let mut seen: HashMap<Identity, usize> = HashMap::with_capacity(outputs.len());
    for (i, out) in outputs.iter().enumerate() {
        let (id, is_dir) = identity(out, &mut dirs);
        if let Some(&input) = inputs.get(&id) {
            let how = if out == input {
                String::new()
            } else {
                format!(" ({})", input.display())
            };
            return Err(SceneError::output(
                out,
                format!(
                    "is one of the inputs{how}: writing it would destroy the data; give \
                     another output name"
                ),
            ));
        }
        match extension(out) {
            Some(e) if allowed.contains(&e.as_str()) => {}
            other => {
                let what = other.map_or("no extension".to_string(), |e| format!("extension .{e}"));
                return Err(SceneError::output(
                    out,
                    format!(
                        "{what} is not a format this command writes: give .{}",
                        allowed.join(", .")
                    ),
                ));
            }
        }
        let dir = directory_of(out);
        let dir_exists = match dirs.get(&dir) {
            Some(known) => known.is_some(),
            None => dir.is_dir(),
        };
        if !dir_exists {
            return Err(SceneError::output(
                out,
                format!(
                    "the directory {} does not exist (create it first)",
                    dir.display()
                ),
            ));
        }
        if is_dir {
            return Err(SceneError::output(out, "is a directory; give a file name"));
        }
        if let Some(&j) = seen.get(&id) {
            return Err(SceneError::output(
                out,
                format!(
                    "outputs {} and {} would both be written to this file; give a name with \
                     %d (or %04d) for the frame number",
                    j + 1,
                    i + 1
                ),
            ));
        }
        seen.insert(id, i);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn links_to_inputs_duplicates_and_unknown_extensions_are_refused() {
        let dir = std::env::temp_dir().join(format!("voxless-output-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let input = dir.join("in.npy");
        std::fs::write(&input, b"data").unwrap();
        let hard = dir.join("hard.npy");
        std::fs::hard_link(&input, &hard).unwrap();
        let inputs = vec![input.clone()];
        let check = |o: &[&str], kind| {
            let outs: Vec<PathBuf> = o.iter().map(|n| dir.join(n)).collect();
            check_outputs(&outs, kind, &inputs)
        };
        assert!(check(&["in.npy"], OutputKind::Columns).is_err());
        assert!(check(&["hard.npy"], OutputKind::Columns).is_err());
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(&input, dir.join("soft.png")).unwrap();
            assert!(check(&["soft.png"], OutputKind::Image).is_err());
        }
        assert!(check(&["a.png", "a.png"], OutputKind::Image).is_err());
        assert!(check(&["a.gif"], OutputKind::Image).is_err());
        assert!(check(&["a.png"], OutputKind::Map).is_err());
        assert!(check(&["none/a.png"], OutputKind::Image).is_err());
        assert!(check(&["a.PNG", "b.jpg", "c.exr"], OutputKind::Image).is_ok());
        assert_eq!(
            ImageFormat::of(Path::new("x.JPEG")),
            Some(ImageFormat::Jpeg)
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
