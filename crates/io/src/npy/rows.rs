//! Part of a `.npy` by rows: what one rank of a parallel run reads. The
//! header is parsed and checked as for a whole file; then only the bytes of
//! rows `a..b` are read, from their offset.

use std::io::{BufReader, ErrorKind, Seek, SeekFrom};
use std::path::Path;

use super::{NpyArray, fortran_to_c, read_header, read_values};
use crate::{IoError, checked_product, open_with_len};

/// Rows `rows` (along the first axis) of the `.npy` at `path`, converted to
/// `f64` in C order, and the array's full shape. The rows are clamped to
/// the array; a Fortran-ordered array of two or more axes is read whole and
/// cut (its rows are not contiguous in the file). Errors are those of
/// [`super::read_npy`], plus a 0-d array, which has no rows.
pub fn read_npy_rows(
    path: &Path,
    rows: std::ops::Range<usize>,
) -> Result<(NpyArray, Vec<usize>), IoError> {
    let (file, len) = open_with_len(path)?;
    let mut reader = BufReader::new(file);
    let (header, dtype, offset) = read_header(&mut reader, len, path)?;
    let Some(&total) = header.shape.first() else {
        return Err(IoError::format(
            path,
            "a 0-d array (a single value) has no rows to read",
        ));
    };
    let per_row = checked_product(&header.shape[1..]).unwrap_or(0);
    let (a, b) = (
        rows.start.min(total),
        rows.end.min(total).max(rows.start.min(total)),
    );
    let mut shape = header.shape.clone();
    shape[0] = b - a;
    let read_err = |e: std::io::Error| match e.kind() {
        ErrorKind::UnexpectedEof => IoError::format(path, "file ends inside the array data"),
        _ => IoError::io(path, e),
    };
    let data = if header.fortran_order && header.shape.len() > 1 {
        let all = read_values(&mut reader, &dtype, total * per_row).map_err(read_err)?;
        fortran_to_c(&all, &header.shape)[a * per_row..b * per_row].to_vec()
    } else {
        let start = offset + (a * per_row * dtype.size) as u64;
        reader
            .seek(SeekFrom::Start(start))
            .map_err(|e| IoError::io(path, e))?;
        read_values(&mut reader, &dtype, (b - a) * per_row).map_err(read_err)?
    };
    Ok((
        NpyArray {
            shape,
            dtype: header.descr,
            data,
        },
        header.shape,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{read_npy, write_npy_f32};

    #[test]
    fn rows_are_the_whole_arrays_rows() {
        let dir = std::env::temp_dir().join(format!("voxless-npy-rows-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.npy");
        let data: Vec<f32> = (0..30).map(|i| i as f32 * 0.5).collect();
        write_npy_f32(&path, &[10, 3], &data).unwrap();
        let whole = read_npy(&path).unwrap();
        for (a, b) in [(0, 10), (3, 7), (9, 10), (4, 4), (8, 20)] {
            let (part, shape) = read_npy_rows(&path, a..b).unwrap();
            assert_eq!(shape, vec![10, 3]);
            let (a, b) = (a.min(10), b.min(10));
            assert_eq!(part.shape, vec![b - a, 3]);
            assert_eq!(part.data, whole.data[3 * a..3 * b]);
        }
        std::fs::remove_dir_all(&dir).ok();
    }
}
