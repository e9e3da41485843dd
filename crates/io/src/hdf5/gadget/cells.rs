//! SWIFT's cell metadata: which rows of which file hold the particles of
//! the top-level cells that overlap a region.
//!
//! SWIFT writes its particles sorted by top-level cell and describes the
//! cells in `Cells/`: `Centres` (one row per cell), the `Meta-data`
//! attribute `size` (a cell's width along each axis), and per type
//! `Counts/PartType<N>` with either `OffsetsInFile/PartType<N>` plus
//! `Files/PartType<N>` (the file and the row within it) or, in older
//! snapshots, `Offsets/PartType<N>` (the row over all files).

use std::ops::Range;

use super::super::Hdf5File;
use super::GadgetHdf5;
use crate::IoError;
use crate::snapshot::Region;

/// Rows of one file: (file index, rows).
pub(super) type Piece = (usize, Range<usize>);

/// The (file, rows) pieces holding the cells that overlap `region`, merged
/// and in file order; `None` when the metadata is incomplete (the caller
/// then streams every row).
pub(super) fn pieces(
    snap: &GadgetHdf5,
    t: u32,
    region: &Region,
) -> Result<Option<Vec<Piece>>, IoError> {
    let f = Hdf5File::open(&snap.files[0])?;
    let Some(cells) = f.child_group(f.root(), "Cells") else {
        return Ok(None);
    };
    let Some(meta) = f.child_group(&cells, "Meta-data") else {
        return Ok(None);
    };
    let Some(size) = f.attr_f64(&meta, "group Cells/Meta-data", "size")? else {
        return Ok(None);
    };
    let size: [f64; 3] = match *size.as_slice() {
        [s] => [s; 3],
        [x, y, z] => [x, y, z],
        _ => return Ok(None),
    };
    let Some(centres) = f.child_dataset(&cells, "Centres") else {
        return Ok(None);
    };
    let (shape, centres) = f.read_f64(&centres, "Cells/Centres")?;
    if shape.len() != 2 || shape[1] != 3 {
        return Ok(None);
    }
    let nc = shape[0];
    let gname = format!("PartType{t}");
    let ints = |group: &str| -> Result<Option<Vec<i64>>, IoError> {
        let Some(g) = f.child_group(&cells, group) else {
            return Ok(None);
        };
        let Some(ds) = f.child_dataset(&g, &gname) else {
            return Ok(None);
        };
        let full = format!("Cells/{group}/{gname}");
        let (s, v) = f.read_i64(&ds, &full)?;
        if s.first() != Some(&nc) {
            return Err(f.err(format!(
                "dataset {full} has {} entries for {nc} cells in Cells/Centres",
                s.first().copied().unwrap_or(0)
            )));
        }
        Ok(Some(v))
    };
    let Some(counts) = ints("Counts")? else {
        return Ok(None);
    };
    // (file, row in file) of each cell's first particle.
    let starts: Vec<(usize, i64)> = match (ints("OffsetsInFile")?, ints("Files")?) {
        (Some(off), Some(files)) => files
            .iter()
            .zip(&off)
            .map(|(&k, &o)| (usize::try_from(k).unwrap_or(usize::MAX), o))
            .collect(),
        (Some(off), None) if snap.files.len() == 1 => off.iter().map(|&o| (0, o)).collect(),
        _ => match ints("Offsets")? {
            Some(global) => {
                let per: Vec<i64> = snap
                    .per_file
                    .iter()
                    .map(|c| c.get(t as usize).copied().unwrap_or(0) as i64)
                    .collect();
                global.iter().map(|&g| locate(&per, g)).collect()
            }
            None => return Ok(None),
        },
    };
    let mut pieces: Vec<Piece> = Vec::new();
    for c in 0..nc {
        let centre = [centres[3 * c], centres[3 * c + 1], centres[3 * c + 2]];
        let lo = std::array::from_fn(|a| centre[a] - 0.5 * size[a]);
        let hi = std::array::from_fn(|a| centre[a] + 0.5 * size[a]);
        let (count, (file, start)) = (counts[c], starts[c]);
        if count <= 0 || !region.overlaps(lo, hi) {
            continue;
        }
        let in_file = snap
            .per_file
            .get(file)
            .and_then(|p| p.get(t as usize))
            .copied()
            .unwrap_or(0) as i64;
        if start < 0 || start.checked_add(count).is_none_or(|end| end > in_file) {
            return Err(f.err(format!(
                "Cells metadata of {gname}: cell {c} says rows {start}..{} of file {file}, \
                 which holds {in_file} particles of the type",
                start.saturating_add(count)
            )));
        }
        pieces.push((file, start as usize..(start + count) as usize));
    }
    // Neighbouring cells are neighbouring rows: merge them.
    pieces.sort_by_key(|(k, r)| (*k, r.start));
    let mut merged: Vec<Piece> = Vec::with_capacity(pieces.len());
    for (k, r) in pieces {
        match merged.last_mut() {
            Some((mk, mr)) if *mk == k && mr.end >= r.start => mr.end = mr.end.max(r.end),
            _ => merged.push((k, r)),
        }
    }
    Ok(Some(merged))
}

/// The file and row within it of global row `g`, given each file's count.
fn locate(per_file: &[i64], g: i64) -> (usize, i64) {
    let mut start = 0i64;
    for (k, &n) in per_file.iter().enumerate() {
        if g < start + n {
            return (k, g - start);
        }
        start += n;
    }
    (per_file.len(), g - start)
}
