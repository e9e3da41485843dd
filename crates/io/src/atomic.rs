//! Writing files safely: every writer of this crate writes a temporary
//! file beside the destination (same directory, so the same file system)
//! and renames it over the destination only once it is complete. A failed
//! or interrupted write never leaves a partial file under the
//! destination's name and never clobbers what was there. A destination
//! that is a symbolic link is replaced by the new file; the link's target
//! is left alone.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::IoError;

/// Temporary files written by this process so far (keeps names unique).
static COUNTER: AtomicU64 = AtomicU64::new(0);

/// The temporary file a write to `path` goes through: hidden, beside it.
fn temporary_for(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    let k = COUNTER.fetch_add(1, Ordering::Relaxed);
    path.with_file_name(format!(".{name}.{}-{k}.part", std::process::id()))
}

/// Runs `write` on a temporary file beside `path`, then renames it to
/// `path`. On any error the temporary file is removed and `path` is left
/// as it was.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<(), IoError>,
) -> Result<(), IoError> {
    let tmp = temporary_for(path);
    let result = (|| {
        let file = File::create(&tmp).map_err(|e| IoError::io(path, e))?;
        let mut out = BufWriter::new(file);
        write(&mut out)?;
        out.flush().map_err(|e| IoError::io(path, e))?;
        drop(out);
        std::fs::rename(&tmp, path).map_err(|e| IoError::io(path, e))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_temporary() {
        let dir = std::env::temp_dir().join(format!("voxless-atomic-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
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
}
