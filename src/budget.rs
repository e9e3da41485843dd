//! Memory an image needs, checked before any work: a `--size` too large
//! for the machine is an error saying how much it needs and how much there
//! is, not an abort half way through allocating it.
//!
//! The memory available is `VOXLESS_MEMORY_LIMIT` when set (bytes, or with
//! a `K`, `M`, `G` or `T` suffix: `8G`), else the system's available memory
//! (`MemAvailable` on Linux); where neither is known nothing is checked.

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

fn gib(b: u64) -> String {
    format!("{:.1} GiB", b as f64 / (1u64 << 30) as f64)
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
                gib(needed),
                gib(avail)
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
                gib(needed),
                gib(avail)
            ),
        )),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn sizes_parse_with_units() {
        use super::parse_bytes;
        assert_eq!(parse_bytes("8G"), Some(8 << 30));
        assert_eq!(parse_bytes("512m"), Some(512 << 20));
        assert_eq!(parse_bytes("1000"), Some(1000));
        assert_eq!(parse_bytes("x"), None);
    }
}
