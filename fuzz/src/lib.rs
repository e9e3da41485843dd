//! Helpers shared by the fuzz targets.
//!
//! The readers take a path, so every target writes its input into files of
//! a scratch directory that belongs to the fuzzing process (its pid is in the
//! name) and overwrites them on every iteration. The directory is left in the
//! system temp dir when the process ends; it holds only the last input.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The scratch directory of this process, created on first use.
pub fn scratch_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("voxless-fuzz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("create the fuzz scratch directory");
        dir
    })
}

/// Writes `bytes` to the file `name` of the scratch directory (replacing it)
/// and returns its path.
pub fn write(name: &str, bytes: &[u8]) -> PathBuf {
    let path = scratch_dir().join(name);
    std::fs::write(&path, bytes).expect("write a fuzz input file");
    path
}

/// Removes the file `name` of the scratch directory if it exists.
pub fn remove(name: &str) {
    let path = scratch_dir().join(name);
    match std::fs::remove_file(&path) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => panic!("cannot remove the fuzz input file {}: {e}", path.display()),
    }
}

/// Splits `data` at `len` (clamped to its length).
pub fn split(data: &[u8], len: usize) -> (&[u8], &[u8]) {
    data.split_at(len.min(data.len()))
}
