//! ExaBricks `.cells` / `.scalars` / `.meta.json` files, from disk or from
//! memory.
//!
//! Both entry points build a list of parts (cells bytes, one part per field,
//! an optional meta part) and hand it to [`assemble`]. A part is either a
//! file, read only when its turn comes (so a scalars file of the wrong size
//! is rejected from its metadata before it is loaded), or a byte slice.

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use super::{AmrCellData, MAX_LEVEL};
use crate::IoError;

/// Bytes per cell: four little-endian `int32`.
const CELL_BYTES: usize = 16;

/// Where the bytes of one part come from.
#[derive(Clone, Copy)]
enum Part<'a> {
    /// A file, read when the part is needed.
    File(&'a Path),
    /// Bytes already in memory.
    Bytes(&'a [u8]),
}

/// One field: its name, the label its errors carry and its bytes.
struct Field<'a> {
    name: String,
    label: PathBuf,
    part: Part<'a>,
}

fn read_all(path: &Path) -> Result<Vec<u8>, IoError> {
    std::fs::read(path).map_err(|e| IoError::io(path, e))
}

/// Reads an ExaBricks `.cells` file and its `.scalars` fields.
///
/// Each scalars file becomes one field. Its name is the part of the file name
/// between the cells file's stem and `.scalars` (`frame3.density.scalars`
/// next to `frame3.cells` gives `density`); a file not named that way is
/// named by its stem (`rho.scalars` gives `rho`).
///
/// If `<stem>.meta.json` exists next to the cells file (`frame3.meta.json`
/// for `frame3.cells`), its `origin` (three numbers) and `finest_cell_size`
/// (a positive number) are used, and its optional `time`; otherwise the
/// origin is (0, 0, 0), the finest cell size 1 and the time unknown.
///
/// Fails if the cells file's size is not a multiple of 16 bytes, a level is
/// outside `0..=30` (the message gives the cell index), a scalars file's size
/// is not a multiple of 4 bytes or its value count differs from the cell
/// count, two fields get the same name, or the meta file is malformed.
pub fn read_exabricks(cells: &Path, scalars: &[PathBuf]) -> Result<AmrCellData, IoError> {
    let stem = cells.file_stem().map(|s| s.to_string_lossy().into_owned());
    let fields = scalars
        .iter()
        .map(|path| Field {
            name: field_name(stem.as_deref(), path),
            label: path.clone(),
            part: Part::File(path),
        })
        .collect();
    // A missing meta file means "defaults", not an error.
    let meta = meta_path(cells).filter(|m| m.is_file());
    let meta = meta.as_deref().map(|m| (m.to_path_buf(), Part::File(m)));
    assemble(Part::File(cells), cells, fields, meta)
}

/// [`read_exabricks`] from memory: `cells` is the content of a `.cells`
/// file, `scalars` lists each field's name with the content of its
/// `.scalars` file, and `meta_json` is the content of the `.meta.json` file,
/// if there is one.
///
/// `cells_name` labels the errors, as the cells path does for
/// [`read_exabricks`]: errors in a field name `<stem>.<field>.scalars` next
/// to it, and errors in the meta JSON `<stem>.meta.json`, i.e. the names
/// the files would have on disk (`frame3.density.scalars` and
/// `frame3.meta.json` for `frame3.cells`). The checks and messages are the
/// same as for the files, and every allocation is bounded by the length of
/// the slices.
pub fn read_exabricks_bytes(
    cells: &[u8],
    cells_name: &Path,
    scalars: &[(&str, &[u8])],
    meta_json: Option<&[u8]>,
) -> Result<AmrCellData, IoError> {
    let stem = cells_name.file_stem().map(|s| s.to_string_lossy());
    // The name a field's file would have next to the cells file.
    let label = |field: &str| {
        let file = match &stem {
            Some(stem) => format!("{stem}.{field}.scalars"),
            None => format!("{field}.scalars"),
        };
        cells_name.with_file_name(file)
    };
    let fields = scalars
        .iter()
        .map(|&(name, bytes)| Field {
            name: name.to_string(),
            label: label(name),
            part: Part::Bytes(bytes),
        })
        .collect();
    let meta_label = meta_path(cells_name).unwrap_or_else(|| PathBuf::from("meta.json"));
    let meta = meta_json.map(|bytes| (meta_label, Part::Bytes(bytes)));
    assemble(Part::Bytes(cells), cells_name, fields, meta)
}

/// The reader behind both entry points: decodes the cells (`cells` labels
/// their errors), then each field in order, then the meta part, so errors
/// come in the same order whichever way the parts arrive.
fn assemble(
    cells_part: Part,
    cells: &Path,
    scalars: Vec<Field>,
    meta: Option<(PathBuf, Part)>,
) -> Result<AmrCellData, IoError> {
    // A cells file's raw bytes are dropped once decoded, before the fields
    // are loaded, so they never share memory with them.
    let cell_list = match cells_part {
        Part::File(path) => decode_cells(&read_all(path)?, cells, 0)?,
        Part::Bytes(bytes) => decode_cells(bytes, cells, 0)?,
    };
    let mut fields: Vec<(String, Vec<f32>)> = Vec::with_capacity(scalars.len());
    for field in scalars {
        let values = read_scalars(&field, cells, cell_list.len())?;
        if fields.iter().any(|(n, _)| *n == field.name) {
            return Err(IoError::format(
                &field.label,
                format!(
                    "field name `{}` is used by an earlier scalars file too",
                    field.name
                ),
            ));
        }
        fields.push((field.name, values));
    }

    let mut data = AmrCellData {
        cells: cell_list,
        fields,
        origin: [0.0; 3],
        finest_cell_size: 1.0,
        time: None,
    };
    if let Some((label, part)) = meta {
        read_meta(&label, part, &mut data)?;
    }
    Ok(data)
}

/// The largest |coordinate| + cell width a cell may reach, in finest
/// cells: well inside i32, so brick corners never overflow.
const MAX_COORD: i64 = 1 << 30;

/// The cells of a `.cells` file: four little-endian `int32` per cell, with
/// levels checked; the first is cell `first` of the file (errors name it).
fn decode_cells(bytes: &[u8], cells: &Path, first: usize) -> Result<Vec<[i32; 4]>, IoError> {
    if !bytes.len().is_multiple_of(CELL_BYTES) {
        return Err(IoError::format(
            cells,
            format!(
                "size {} bytes is not a multiple of 16 (one cell is four int32: x, y, z, \
                 level); the file is truncated or not an ExaBricks .cells file",
                bytes.len()
            ),
        ));
    }
    let mut cell_list = Vec::with_capacity(bytes.len() / CELL_BYTES);
    for (index, chunk) in bytes.chunks_exact(CELL_BYTES).enumerate() {
        let word = |k: usize| {
            i32::from_le_bytes([
                chunk[4 * k],
                chunk[4 * k + 1],
                chunk[4 * k + 2],
                chunk[4 * k + 3],
            ])
        };
        let cell = [word(0), word(1), word(2), word(3)];
        if !(0..=MAX_LEVEL).contains(&cell[3]) {
            return Err(IoError::format(
                cells,
                format!(
                    "cell {} has level {}; levels must be 0 (finest) to {MAX_LEVEL}",
                    first + index,
                    cell[3]
                ),
            ));
        }
        // Bricks and cell corners are computed in i32 (corner + width):
        // coordinates whose cell would reach past ±2³⁰ finest cells would
        // wrap around downstream, so they are an error naming the cell.
        let reach = |c: i32| (c as i64).abs() + (1i64 << cell[3]);
        if cell[..3].iter().any(|&c| reach(c) > MAX_COORD) {
            return Err(IoError::format(
                cells,
                format!(
                    "cell {} at ({}, {}, {}) level {} reaches beyond ±2^30 finest cells (the \
                     coordinates are corrupt, or not in finest-cell units)",
                    first + index,
                    cell[0],
                    cell[1],
                    cell[2],
                    cell[3]
                ),
            ));
        }
        cell_list.push(cell);
    }
    Ok(cell_list)
}

/// One field's `.scalars` data, which must hold exactly `count` float32
/// values.
fn read_scalars(field: &Field, cells: &Path, count: usize) -> Result<Vec<f32>, IoError> {
    let path = &field.label;
    let fits = |len: u64| len.is_multiple_of(4) && len / 4 == count as u64;
    let mismatch = |len: u64| {
        let message = if !len.is_multiple_of(4) {
            format!("size {len} bytes is not a multiple of 4 (one float32 per cell)")
        } else {
            format!(
                "holds {} values, but {} holds {count} cells",
                len / 4,
                cells.display()
            )
        };
        IoError::format(path, message)
    };
    let loaded;
    let bytes = match field.part {
        Part::File(file) => {
            // Check the size before reading so a wrong, huge file is not
            // loaded.
            let len = std::fs::metadata(file)
                .map_err(|e| IoError::io(path, e))?
                .len();
            if !fits(len) {
                return Err(mismatch(len));
            }
            loaded = read_all(file)?;
            &loaded[..]
        }
        Part::Bytes(bytes) => bytes,
    };
    // Slices are checked here; a file again, in case it changed meanwhile.
    if !fits(bytes.len() as u64) {
        return Err(mismatch(bytes.len() as u64));
    }
    Ok(bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect())
}

/// Cells `rows` of an ExaBricks `.cells` file and the same rows of its
/// `.scalars` fields, with the file's total cell count: what one rank of a
/// parallel run reads (by offset, never the whole file). Names, meta file
/// and checks are those of [`read_exabricks`]; every scalars file must hold
/// one value per cell of the whole file. Rows are clamped to the file.
pub fn read_exabricks_rows(
    cells: &Path,
    scalars: &[PathBuf],
    rows: std::ops::Range<usize>,
) -> Result<(AmrCellData, usize), IoError> {
    let len = std::fs::metadata(cells)
        .map_err(|e| IoError::io(cells, e))?
        .len();
    if !len.is_multiple_of(CELL_BYTES as u64) {
        // The whole-file reader's message for a truncated file.
        decode_cells(&vec![0u8; (len % CELL_BYTES as u64) as usize], cells, 0)?;
    }
    let total = (len / CELL_BYTES as u64) as usize;
    let (a, b) = (
        rows.start.min(total),
        rows.end.min(total).max(rows.start.min(total)),
    );
    let cell_list = decode_cells(&read_range(cells, CELL_BYTES, a, b)?, cells, a)?;
    let stem = cells.file_stem().map(|s| s.to_string_lossy().into_owned());
    let mut fields: Vec<(String, Vec<f32>)> = Vec::with_capacity(scalars.len());
    for path in scalars {
        let name = field_name(stem.as_deref(), path);
        let flen = std::fs::metadata(path)
            .map_err(|e| IoError::io(path, e))?
            .len();
        if flen != 4 * total as u64 {
            let message = if !flen.is_multiple_of(4) {
                format!("size {flen} bytes is not a multiple of 4 (one float32 per cell)")
            } else {
                format!(
                    "holds {} values, but {} holds {total} cells",
                    flen / 4,
                    cells.display()
                )
            };
            return Err(IoError::format(path, message));
        }
        if fields.iter().any(|(n, _)| *n == name) {
            return Err(IoError::format(
                path,
                format!("field name `{name}` is used by an earlier scalars file too"),
            ));
        }
        let bytes = read_range(path, 4, a, b)?;
        let values = bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        fields.push((name, values));
    }
    let mut data = AmrCellData {
        cells: cell_list,
        fields,
        origin: [0.0; 3],
        finest_cell_size: 1.0,
        time: None,
    };
    if let Some(meta) = meta_path(cells).filter(|m| m.is_file()) {
        read_meta(&meta, Part::File(&meta), &mut data)?;
    }
    Ok((data, total))
}

/// Records `a..b` of `size` bytes each from `path`.
fn read_range(path: &Path, size: usize, a: usize, b: usize) -> Result<Vec<u8>, IoError> {
    use std::io::{Read, Seek, SeekFrom};
    let mut file = std::fs::File::open(path).map_err(|e| IoError::io(path, e))?;
    file.seek(SeekFrom::Start((a * size) as u64))
        .map_err(|e| IoError::io(path, e))?;
    let mut buf = vec![0u8; (b - a) * size];
    file.read_exact(&mut buf)
        .map_err(|e| IoError::io(path, e))?;
    Ok(buf)
}

/// The field name of a scalars file (see [`read_exabricks`]).
fn field_name(cells_stem: Option<&str>, scalars: &Path) -> String {
    let file_name = scalars
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    if let Some(stem) = cells_stem
        && let Some(rest) = file_name.strip_prefix(stem)
        && let Some(rest) = rest.strip_prefix('.')
        && let Some(middle) = rest.strip_suffix(".scalars")
        && !middle.is_empty()
    {
        return middle.to_string();
    }
    scalars
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or(file_name)
}

/// `<stem>.meta.json` next to the cells file; `None` when the cells path
/// has no file name.
fn meta_path(cells: &Path) -> Option<PathBuf> {
    let mut name = OsString::from(cells.file_stem()?);
    name.push(".meta.json");
    Some(cells.with_file_name(name))
}

/// Applies `origin`, `finest_cell_size` and optional `time` from a meta
/// part; `path` labels its errors.
fn read_meta(path: &Path, part: Part, data: &mut AmrCellData) -> Result<(), IoError> {
    let loaded;
    let bytes = match part {
        Part::File(file) => {
            loaded = read_all(file)?;
            &loaded[..]
        }
        Part::Bytes(bytes) => bytes,
    };
    let value: serde_json::Value = serde_json::from_slice(bytes)
        .map_err(|e| IoError::format(path, format!("not valid JSON: {e}")))?;
    let origin = value
        .get("origin")
        .and_then(|o| o.as_array())
        .filter(|a| a.len() == 3)
        .and_then(|a| {
            let c: Vec<f64> = a.iter().filter_map(|v| v.as_f64()).collect();
            (c.len() == 3 && c.iter().all(|v| v.is_finite())).then(|| [c[0], c[1], c[2]])
        })
        .ok_or_else(|| {
            IoError::format(path, "`origin` must be an array of three finite numbers")
        })?;
    let size = value
        .get("finest_cell_size")
        .and_then(|s| s.as_f64())
        .filter(|s| s.is_finite() && *s > 0.0)
        .ok_or_else(|| IoError::format(path, "`finest_cell_size` must be a positive number"))?;
    let time = match value.get("time") {
        None | Some(serde_json::Value::Null) => None,
        Some(t) => Some(
            t.as_f64()
                .filter(|t| t.is_finite())
                .ok_or_else(|| IoError::format(path, "`time` must be a finite number"))?,
        ),
    };
    data.origin = origin;
    data.finest_cell_size = size;
    data.time = time;
    Ok(())
}
