//! An N×3 `.npy` of positions read straight into rows, on every core.
//!
//! A 16.7M-particle set is 200 MB of `float32`: read through one buffer and
//! converted value by value into a `Vec<f64>`, then regrouped into rows,
//! it cost a second of a load (two 400 MB copies, one core). Here the
//! header is checked as [`super::read_npy`] checks it, and blocks of rows
//! are read at their offsets and decoded by the same decoder on every core
//! into the rows' final place. Fortran-ordered arrays (their rows are not
//! contiguous) go through [`super::read_npy`] and are regrouped.

use std::io::{BufReader, ErrorKind};
use std::path::Path;

use rayon::prelude::*;

use super::{decode, read_header};
use crate::{IoError, open_with_len};

/// Rows per block: a block's bytes and its decoded values stay in cache
/// (64K rows of `float64` are 1.5 MB), and 16.7M rows make 256 blocks.
const BLOCK_ROWS: usize = 1 << 16;

/// The rows of the N×3 position array in the `.npy` at `path`, as `f64`
/// (any numeric dtype, either byte order), with [`super::read_npy`]'s
/// errors and an error naming the shape when it is not N×3.
pub fn read_npy_positions(path: &Path) -> Result<Vec<[f64; 3]>, IoError> {
    let (file, len) = open_with_len(path)?;
    let (header, dtype, offset) = read_header(&mut BufReader::new(&file), len, path)?;
    check_positions_shape(&header.shape, path)?;
    if header.fortran_order {
        let a = super::read_npy(path)?;
        return Ok(a.data.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect());
    }
    // Zeroed pages come from the kernel on first touch: in the block that
    // writes them, on whichever core decodes it.
    let mut rows = vec![[0.0f64; 3]; header.shape[0]];
    decode_rows(&file, path, &dtype, offset, &mut rows)?;
    Ok(rows)
}

/// Rows `first .. first + out.len()` of the N×3 position array in the
/// `.npy` at `path`, decoded on every core straight into `out` (a share of
/// a larger set: no copy of the rows through another buffer). The errors
/// of [`read_npy_positions`], and one naming the rows when the array has
/// fewer.
pub fn read_npy_positions_into(
    path: &Path,
    first: usize,
    out: &mut [[f64; 3]],
) -> Result<(), IoError> {
    let (file, len) = open_with_len(path)?;
    let (header, dtype, offset) = read_header(&mut BufReader::new(&file), len, path)?;
    check_positions_shape(&header.shape, path)?;
    let end = first.saturating_add(out.len());
    if end > header.shape[0] {
        return Err(IoError::format(
            path,
            format!(
                "rows {first}..{end} asked of an array of {} rows",
                header.shape[0]
            ),
        ));
    }
    if header.fortran_order {
        let a = super::read_npy(path)?;
        for (o, c) in out.iter_mut().zip(a.data.chunks_exact(3).skip(first)) {
            *o = [c[0], c[1], c[2]];
        }
        return Ok(());
    }
    let at = offset + (first * 3 * dtype.size) as u64;
    decode_rows(&file, path, &dtype, at, out)
}

/// The rows from byte `offset` of a C-ordered N×3 array into `out`, blocks
/// of [`BLOCK_ROWS`] read at their offsets and decoded on every core.
fn decode_rows(
    file: &std::fs::File,
    path: &Path,
    dtype: &super::Dtype,
    offset: u64,
    out: &mut [[f64; 3]],
) -> Result<(), IoError> {
    let size = dtype.size;
    let read_err = |e: std::io::Error| match e.kind() {
        ErrorKind::UnexpectedEof => IoError::format(path, "file ends inside the array data"),
        _ => IoError::io(path, e),
    };
    out.par_chunks_mut(BLOCK_ROWS)
        .enumerate()
        .try_for_each_init(
            || (Vec::new(), Vec::new()),
            |(bytes, values): &mut (Vec<u8>, Vec<f64>), (b, out)| {
                bytes.resize(out.len() * 3 * size, 0);
                let at = offset + (b * BLOCK_ROWS * 3 * size) as u64;
                read_at(file, bytes, at).map_err(read_err)?;
                values.clear();
                decode(bytes, dtype, values);
                out.as_flattened_mut().copy_from_slice(values);
                Ok(())
            },
        )
}

/// Refuses an array that is not N×3 (positions), naming its shape.
pub(crate) fn check_positions_shape(shape: &[usize], path: &Path) -> Result<(), IoError> {
    if shape.len() == 2 && shape[1] == 3 {
        return Ok(());
    }
    let dims: Vec<String> = shape.iter().map(|s| s.to_string()).collect();
    Err(IoError::format(
        path,
        format!(
            "expected an N×3 array of positions, found shape ({})",
            dims.join(", ")
        ),
    ))
}

#[cfg(unix)]
fn read_at(file: &std::fs::File, buf: &mut [u8], at: u64) -> std::io::Result<()> {
    std::os::unix::fs::FileExt::read_exact_at(file, buf, at)
}

#[cfg(not(unix))]
fn read_at(mut file: &std::fs::File, buf: &mut [u8], at: u64) -> std::io::Result<()> {
    use std::io::{Read, Seek, SeekFrom};
    // One reader at a time where positioned reads are not shared-safe.
    static LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _held = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    file.seek(SeekFrom::Start(at))?;
    file.read_exact(buf)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{read_npy, write_npy_f32};

    /// Rows equal the general reader's, across block boundaries and for a
    /// partial last block; other shapes are refused by name.
    #[test]
    fn rows_equal_the_general_reader() {
        let dir = std::env::temp_dir().join(format!("voxless-npy-pos-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("p.npy");
        let n = 2 * BLOCK_ROWS + 17;
        let v: Vec<f32> = (0..3 * n).map(|i| (i as f32 * 0.37).sin() * 1e3).collect();
        write_npy_f32(&path, &[n, 3], &v).unwrap();
        let rows = read_npy_positions(&path).unwrap();
        let whole = read_npy(&path).unwrap();
        assert_eq!(rows.len(), n);
        assert_eq!(rows.as_flattened(), &whole.data[..]);
        // A share of the rows, across a block boundary, into its place.
        let (first, count) = (BLOCK_ROWS - 5, BLOCK_ROWS + 9);
        let mut part = vec![[0.0; 3]; count];
        read_npy_positions_into(&path, first, &mut part).unwrap();
        assert_eq!(part, rows[first..first + count]);
        let e = read_npy_positions_into(&path, n - 2, &mut part).unwrap_err();
        assert!(e.to_string().contains(&format!("of {n} rows")), "{e}");
        write_npy_f32(&path, &[n, 3, 1], &v).unwrap();
        let e = read_npy_positions(&path).unwrap_err().to_string();
        assert!(
            e.contains("p.npy") && e.contains(&format!("({n}, 3, 1)")),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
