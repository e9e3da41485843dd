//! Helpers shared by the fuzz targets.
//!
//! Every target hands the fuzzer's bytes to the memory variants of the
//! readers (`read_npy_from`, `read_exabricks_bytes`, …), so nothing touches
//! the file system; the names the targets pass only label errors.

/// Splits `data` at `len` (clamped to its length).
pub fn split(data: &[u8], len: usize) -> (&[u8], &[u8]) {
    data.split_at(len.min(data.len()))
}
