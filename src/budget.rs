//! Memory an image needs, checked before any work: a `--size` too large
//! for the machine is an error saying how much it needs and how much there
//! is, not an abort half way through allocating it.
//!
//! The memory available is `VOXLESS_MEMORY_LIMIT` when set (bytes, or with
//! a `K`, `M`, `G` or `T` suffix: `8G`), else the system's available memory
//! (`MemAvailable` on Linux); where neither is known nothing is checked.
//!
//! Disk space for a sequence of frames is checked the same way: what the
//! files cannot take less than (a filesystem block and an inode each) is
//! refused against the free space, what they may take at most gets a note.
//! `VOXLESS_DISK_LIMIT` (bytes, with the same suffixes) caps the free space
//! believed.

use crate::SceneError;

/// Bytes a rendered pixel takes at the peak: the film's running sum, one
/// pass's tiles, the resolved image (RGBA float32 each) and the encoded
/// output.
pub const BYTES_PER_PIXEL: u64 = 64;

/// Parses `8G`, `512M`, `1000000` (bytes).
fn parse_bytes(s: &str) -> Option<u64> {
    let s = s.trim();
    let (digits, unit) = match s.char_indices().last()? {
        (i, c) if c.is_ascii_alphabetic() => (&s[..i], c.to_ascii_uppercase()),
        _ => (s, 'B'),
    };
    let shift = match unit {
        'B' => 0,
        'K' => 10,
        'M' => 20,
        'G' => 30,
        'T' => 40,
        _ => return None,
    };
    let v: f64 = digits.trim().parse().ok()?;
    (v.is_finite() && v >= 0.0).then(|| (v * (1u64 << shift) as f64) as u64)
}

/// The memory a render may use (module docs), if known.
pub fn available_memory() -> Option<u64> {
    if let Ok(v) = std::env::var("VOXLESS_MEMORY_LIMIT")
        && let Some(b) = parse_bytes(&v)
    {
        return Some(b);
    }
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// An error when a `width`×`height` image would not fit in the memory
/// available.
pub fn check_image_memory(width: u32, height: u32) -> Result<(), SceneError> {
    let needed = width as u64 * height as u64 * BYTES_PER_PIXEL;
    match available_memory() {
        Some(avail) if needed > avail => Err(SceneError::setting(
            "image size (--size)",
            format!(
                "a {width}×{height} image needs about {} of memory, but {} is available; \
                 give a smaller --size",
                human(needed),
                human(avail)
            ),
        )),
        _ => Ok(()),
    }
}

/// An error when the k-buffer's per-tile buffers (`k` events and
/// `layers` depth bins per pixel, one tile per thread) would not fit in the
/// memory available: `--layers 1000000000` is refused before any work.
pub fn check_kbuffer_memory(k: usize, layers: usize) -> Result<(), SceneError> {
    let tile = (voxless_tets::raster::TILE as u64).pow(2);
    let threads = rayon::current_num_threads().max(1) as u64;
    // Per pixel: k (depth, value) pairs, a depth bin (f64) and an edge
    // (f32) per layer.
    let per_pixel = (k as u64)
        .saturating_mul(8)
        .saturating_add((layers as u64).saturating_mul(12));
    let needed = per_pixel.saturating_mul(tile).saturating_mul(threads);
    match available_memory() {
        Some(avail) if needed > avail => Err(SceneError::setting(
            if layers as u64 * 12 >= k as u64 * 8 {
                "tets.layers (--layers)"
            } else {
                "tets.k (--k)"
            },
            format!(
                "k = {k} events and {layers} depth layers per pixel need about {} for the \
                 k-buffer's tiles ({threads} at a time), but {} is available",
                human(needed),
                human(avail)
            ),
        )),
        _ => Ok(()),
    }
}

/// Free space of the filesystem holding `dir`: (bytes, inodes, block size)
/// available to this user; `None` where the system does not say.
pub fn available_disk(dir: &std::path::Path) -> Option<(u64, u64, u64)> {
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        let c = std::ffi::CString::new(dir.as_os_str().as_bytes()).ok()?;
        let mut st = std::mem::MaybeUninit::<libc::statvfs>::zeroed();
        // SAFETY: `c` is a valid NUL-terminated path and `st` a buffer of
        // the type statvfs fills; it is read only when the call succeeds.
        let rc = unsafe { libc::statvfs(c.as_ptr(), st.as_mut_ptr()) };
        if rc != 0 {
            return None;
        }
        // SAFETY: statvfs returned 0, so it wrote the whole struct.
        let st = unsafe { st.assume_init() };
        #[allow(clippy::unnecessary_cast)]
        let (block, blocks, inodes) = (
            (st.f_frsize as u64).max(1),
            st.f_bavail as u64,
            // Filesystems without an inode table (btrfs, some network
            // ones) report none at all: no limit, not zero.
            match st.f_files {
                0 => u64::MAX,
                _ => st.f_favail as u64,
            },
        );
        let mut free = blocks.saturating_mul(block);
        if let Some(limit) = std::env::var("VOXLESS_DISK_LIMIT")
            .ok()
            .and_then(|v| parse_bytes(&v))
        {
            free = free.min(limit);
        }
        Some((free, inodes, block))
    }
    #[cfg(not(unix))]
    {
        let _ = dir;
        None
    }
}

/// Checks that `files` files of at most `max_bytes` each fit in `dir`'s
/// filesystem (module docs). An error names `what` (the flag that asked
/// for them) and what they would need; a note when they fit only if they
/// compress.
pub fn check_disk(
    dir: &std::path::Path,
    files: u64,
    max_bytes: u64,
    what: &str,
) -> Result<Option<String>, SceneError> {
    let Some((free, inodes, block)) = available_disk(dir) else {
        return Ok(None);
    };
    let at_least = files.saturating_mul(block);
    let at_most = files.saturating_mul(max_bytes.div_ceil(block) * block);
    let shown = dir.display();
    if files > inodes {
        return Err(SceneError::setting(
            what,
            format!(
                "{files} files, but the filesystem of {shown} has room for {inodes} more: \
                 render fewer frames, or write a movie"
            ),
        ));
    }
    if at_least > free {
        return Err(SceneError::setting(
            what,
            format!(
                "{files} files need at least {} on the filesystem of {shown} (a {block}-byte \
                 block each), but {} is free: render fewer frames or free space",
                human(at_least),
                human(free)
            ),
        ));
    }
    Ok((at_most > free).then(|| {
        format!(
            "{files} files may take up to {} and {} is free on the filesystem of {shown}: \
             the run stops with an error if they do not compress",
            human(at_most),
            human(free)
        )
    }))
}

/// Bytes for people: KiB to TiB.
fn human(b: u64) -> String {
    const UNITS: [&str; 5] = ["bytes", "KiB", "MiB", "GiB", "TiB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{b} bytes")
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_that_cannot_fit_are_refused_and_those_that_may_not_get_a_note() {
        let dir = std::env::temp_dir();
        let Some((free, inodes, block)) = available_disk(&dir) else {
            eprintln!("note: skipped: this system does not report free disk space");
            return;
        };
        assert_eq!(check_disk(&dir, 1, 100, "--frames").unwrap(), None);
        // More blocks (or inodes) than are free: an error naming the flag.
        let files = (free / block + 1).max(inodes.saturating_add(1));
        let e = check_disk(&dir, files, 1, "--turntable")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("--turntable") && e.contains(&files.to_string()),
            "{e}"
        );
        // Files that fit only if they compress: a note.
        let note = check_disk(&dir, 1, free + block, "--frames").unwrap();
        assert!(note.is_some_and(|n| n.contains("may take up to")));
    }

    #[test]
    fn sizes_parse_with_units() {
        assert_eq!(parse_bytes("8G"), Some(8 << 30));
        assert_eq!(parse_bytes("512m"), Some(512 << 20));
        assert_eq!(parse_bytes("1000"), Some(1000));
        assert_eq!(parse_bytes("x"), None);
    }
}
