//! The files of a snapshot written in several pieces: `snap_033.0`,
//! `snap_033.1`, …, found from any one of them or from their stem.

use std::ffi::OsString;
use std::fs::File;
use std::path::{Path, PathBuf};

use super::layout::{Source, scan};
use crate::IoError;

/// See [`super::gadget_binary_files`].
pub(super) fn snapshot_files(path: &Path) -> Result<Vec<PathBuf>, IoError> {
    if !path.is_file() {
        // The stem of a set, which is not a file itself.
        let first = numbered(path, 0, 1);
        if first.is_file() {
            return set_of(&first);
        }
        // Let the system say why the path cannot be read.
        return Err(match File::open(path) {
            Err(e) => IoError::io(path, e),
            Ok(_) => IoError::format(path, "not a file"),
        });
    }
    set_of(path)
}

/// The set `path` (an existing file) belongs to, by its header's
/// `num_files`.
fn set_of(path: &Path) -> Result<Vec<PathBuf>, IoError> {
    let num_files = scan(&mut Source::open(path)?, true)?.num_files;
    let show = |p: &Path| p.display().to_string();
    let Some((stem, index, width)) = split_index(path) else {
        if num_files > 1 {
            return Err(IoError::format(
                path,
                format!(
                    "block HEAD: num_files is {num_files}, but the name does not end in a file \
                     number (.0 … .{}) to find the other files by",
                    num_files - 1
                ),
            ));
        }
        return Ok(vec![path.to_path_buf()]);
    };
    if num_files <= 0 {
        // Without a count, other numbered files next to this one make the
        // set ambiguous.
        let other = numbered(&stem, if index == 0 { 1 } else { 0 }, width);
        if other.is_file() {
            return Err(IoError::format(
                path,
                format!(
                    "block HEAD: num_files is {num_files}, but {} exists too: cannot tell how \
                     many files the snapshot has",
                    show(&other)
                ),
            ));
        }
        return Ok(vec![path.to_path_buf()]);
    }
    if num_files == 1 {
        return Ok(vec![path.to_path_buf()]);
    }
    let count = num_files as u64;
    if index >= count {
        return Err(IoError::format(
            path,
            format!(
                "block HEAD: num_files is {num_files}, so the files are numbered 0 to {}, not \
                 {index}",
                count - 1
            ),
        ));
    }
    // Stops at the first missing file, so a corrupt count costs nothing.
    let mut files = Vec::new();
    for i in 0..count {
        let file = numbered(&stem, i, width);
        if !file.is_file() {
            return Err(IoError::format(
                &file,
                format!(
                    "missing: file {i} of the {num_files} files of snapshot {} (num_files in {})",
                    show(&stem),
                    show(path)
                ),
            ));
        }
        files.push(file);
    }
    Ok(files)
}

/// `stem.K` as (stem, K, digits to pad file numbers to): names written
/// with leading zeros (`snap.000`) keep their width.
pub(super) fn split_index(path: &Path) -> Option<(PathBuf, u64, usize)> {
    let name = path.file_name()?.to_str()?;
    let (stem, digits) = name.rsplit_once('.')?;
    if stem.is_empty() || digits.is_empty() || digits.len() > 9 {
        return None;
    }
    if !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let index = digits.parse().ok()?;
    let width = if digits.len() > 1 && digits.starts_with('0') {
        digits.len()
    } else {
        1
    };
    Some((path.with_file_name(stem), index, width))
}

/// `stem.i`, with `i` padded to `width` digits.
pub(super) fn numbered(stem: &Path, i: u64, width: usize) -> PathBuf {
    let mut name = OsString::from(stem.as_os_str());
    name.push(format!(".{i:0width$}"));
    PathBuf::from(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_numbers_split_off_the_stem() {
        let split = |s: &str| split_index(Path::new(s));
        assert_eq!(split("dir/snap_033.2"), Some(("dir/snap_033".into(), 2, 1)));
        assert_eq!(split("snap.010"), Some(("snap".into(), 10, 3)));
        assert_eq!(split("snap.0"), Some(("snap".into(), 0, 1)));
        assert_eq!(split("snap_033"), None);
        assert_eq!(split("snap.hdf5"), None);
        assert_eq!(split(".3"), None);
        assert_eq!(split("snap.1234567890"), None);
        assert_eq!(
            numbered(Path::new("a/snap"), 7, 3),
            PathBuf::from("a/snap.007")
        );
        assert_eq!(
            numbered(Path::new("a/snap"), 12, 1),
            PathBuf::from("a/snap.12")
        );
    }
}
