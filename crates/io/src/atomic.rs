//! Writing files safely: every writer of this crate writes a temporary
//! file beside the destination (same directory, so the same file system)
//! and renames it over the destination only once it is complete. A failed
//! or interrupted write never leaves a partial file under the
//! destination's name and never clobbers what was there. A destination
//! that is a symbolic link stays one: the file it points to is replaced
//! (written beside it). A destination that exists but is no regular file
//! (a device such as `/dev/full`, a FIFO, a directory) is refused, so
//! nothing is renamed over it.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::IoError;

/// Temporary files written by this process so far (keeps names unique).
static COUNTER: AtomicU64 = AtomicU64::new(0);

/// The temporary file a write to `path` goes through: hidden, beside it,
/// its name no longer than the destination's allows (a legal 251-character
/// name must not fail for its temporary's length).
fn temporary_for(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    let stem: String = name.chars().take(80).collect();
    let k = COUNTER.fetch_add(1, Ordering::Relaxed);
    path.with_file_name(format!(".{stem}.{}-{k}.part", std::process::id()))
}

/// The file a write to `path` lands in: `path`, or the file a chain of
/// symbolic links at `path` ends in. Fails when that exists and is no
/// regular file, or the chain is too long.
fn destination(path: &Path) -> Result<PathBuf, IoError> {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                let target = std::fs::read_link(&p).map_err(|e| IoError::io(path, e))?;
                p = match p.parent() {
                    Some(dir) if target.is_relative() => dir.join(target),
                    _ => target,
                };
            }
            Ok(m) if !m.is_file() => {
                return Err(IoError::format(
                    path,
                    format!(
                        "{} is not a regular file (a device, FIFO or directory): outputs are \
                         written to files",
                        p.display()
                    ),
                ));
            }
            _ => return Ok(p),
        }
    }
    Err(IoError::format(path, "too many levels of symbolic links"))
}

/// Runs `write` on a temporary file beside `path`, then renames it to
/// `path`. On any error the temporary file is removed and `path` is left
/// as it was.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<(), IoError>,
) -> Result<(), IoError> {
    let target = destination(path)?;
    let tmp = temporary_for(&target);
    let result = (|| {
        let file = File::create(&tmp).map_err(|e| IoError::io(path, e))?;
        let mut out = BufWriter::new(file);
        write(&mut out)?;
        out.flush().map_err(|e| IoError::io(path, e))?;
        drop(out);
        std::fs::rename(&tmp, &target).map_err(|e| IoError::io(path, e))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An empty directory of its own for test `name`.
    fn empty_dir(name: &str) -> std::path::PathBuf {
        let dir =
            std::env::temp_dir().join(format!("voxless-atomic-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_temporary() {
        let dir = empty_dir("plain");
        let path = dir.join("out.bin");
        std::fs::write(&path, b"old").unwrap();
        let e = write_atomically(&path, |out| {
            out.write_all(b"partial").unwrap();
            Err(IoError::format(&path, "stopped half way"))
        });
        assert!(e.is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        write_atomically(&path, |out| {
            out.write_all(b"new").map_err(|e| IoError::io(&path, e))
        })
        .unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_legal_name_of_251_characters_is_written() {
        let dir = empty_dir("long");
        // 251 characters: the longest most filesystems take (255) less
        // room for nothing; a temporary named after it whole would fail.
        let path = dir.join(format!("{}.png", "n".repeat(247)));
        write_atomically(&path, |out| {
            out.write_all(b"png").map_err(|e| IoError::io(&path, e))
        })
        .unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"png");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[cfg(unix)]
    #[test]
    fn a_link_stays_a_link_and_devices_are_refused() {
        let dir = empty_dir("link");
        let (target, link) = (dir.join("target.bin"), dir.join("link.bin"));
        std::fs::write(&target, b"old").unwrap();
        std::os::unix::fs::symlink("target.bin", &link).unwrap();
        let write = |p: &Path| {
            write_atomically(p, |out| {
                out.write_all(b"new").map_err(|e| IoError::io(p, e))
            })
        };
        write(&link).unwrap();
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        // A link to a device: refused, the link and the device untouched.
        let dev = dir.join("dev.bin");
        std::os::unix::fs::symlink("/dev/null", &dev).unwrap();
        let e = write(&dev).unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
        assert!(
            std::fs::symlink_metadata(&dev)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        // A long but legal name.
        let long = dir.join("x".repeat(250));
        write(&long).unwrap();
        assert_eq!(std::fs::read(&long).unwrap(), b"new");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
