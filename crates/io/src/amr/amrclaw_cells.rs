//! An AMRClaw frame's grids as leaf cells: levels from the cell sizes,
//! coarse cells that finer grids cover dropped, every grid's cells on
//! every core.

use std::path::Path;

use rayon::prelude::*;

use super::{AmrCellData, FieldPick, Grid, MAX_LEVEL, columns};
use crate::IoError;

/// Drops covered cells and converts grids to ExaBricks cells.
pub(super) fn grids_to_cells(
    path: &Path,
    grids: Vec<Grid>,
    meqn: usize,
    pick: &FieldPick,
) -> Result<AmrCellData, IoError> {
    let grid_error = |g: &Grid, message: String| {
        IoError::format(
            path,
            format!("grid {} (header at line {}): {message}", g.number, g.line),
        )
    };
    for g in &grids {
        let [dx, dy, dz] = g.d;
        let tol = 1e-9 * dx;
        if (dy - dx).abs() > tol || (dz - dx).abs() > tol {
            return Err(grid_error(
                g,
                format!("dx = {dx}, dy = {dy}, dz = {dz} differ; only cubic cells are supported"),
            ));
        }
    }
    let finest = grids.iter().map(|g| g.d[0]).fold(f64::INFINITY, f64::min);

    // Level (log2 of the cell width in finest units) per grid.
    let mut levels = Vec::with_capacity(grids.len());
    for g in &grids {
        let ratio = g.d[0] / finest;
        let level = ratio.log2().round();
        if !(level <= f64::from(MAX_LEVEL)) || (ratio - level.exp2()).abs() > 1e-6 * level.exp2() {
            return Err(grid_error(
                g,
                format!(
                    "dx = {} is {ratio} times the finest dx {finest}; the refinement ratio \
                     must be a power of two",
                    g.d[0]
                ),
            ));
        }
        levels.push(level as u32);
    }
    // Each AMR level must have one cell size, and finer AMR levels smaller
    // cells: the first grid of each AMR level stands for it (one pass and a
    // sort, not every pair of grids).
    let mut first_of: std::collections::BTreeMap<i64, usize> = Default::default();
    let inconsistent = |a: usize, b: usize| {
        let (ga, gb) = (&grids[a], &grids[b]);
        grid_error(
            gb,
            format!(
                "AMR level {} with dx = {} is inconsistent with grid {} (AMR level {}, dx = {})",
                gb.amr_level, gb.d[0], ga.number, ga.amr_level, ga.d[0]
            ),
        )
    };
    for (b, gb) in grids.iter().enumerate() {
        let a = *first_of.entry(gb.amr_level).or_insert(b);
        if levels[a] != levels[b] {
            return Err(inconsistent(a, b));
        }
    }
    let firsts: Vec<usize> = first_of.values().copied().collect();
    for pair in firsts.windows(2) {
        // AMR levels ascending: cell sizes (log2) strictly descending.
        if levels[pair[1]] >= levels[pair[0]] {
            let (a, b) = (pair[0].min(pair[1]), pair[0].max(pair[1]));
            return Err(inconsistent(a, b));
        }
    }

    let coarsest = grids.iter().map(|g| g.amr_level).min().unwrap_or(1);
    let mut origin = [f64::INFINITY; 3];
    for g in grids.iter().filter(|g| g.amr_level == coarsest) {
        for (o, &low) in origin.iter_mut().zip(&g.low) {
            *o = o.min(low);
        }
    }

    // Grid boxes in finest units: lower corner and exclusive upper corner.
    let mut boxes = Vec::with_capacity(grids.len());
    for (g, &level) in grids.iter().zip(&levels) {
        let width = 1i64 << level;
        let mut lo = [0i64; 3];
        let mut hi = [0i64; 3];
        for a in 0..3 {
            let exact = (g.low[a] - origin[a]) / finest;
            let rounded = exact.round();
            if (exact - rounded).abs() > 1e-3 || rounded.abs() > f64::from(i32::MAX) {
                return Err(grid_error(
                    g,
                    format!(
                        "{}low = {} is not on the finest-cell lattice from origin {} with \
                         spacing {finest}",
                        ["x", "y", "z"][a],
                        g.low[a],
                        origin[a]
                    ),
                ));
            }
            lo[a] = rounded as i64;
            hi[a] = lo[a] + g.size[a] as i64 * width;
            if hi[a] > i64::from(i32::MAX) {
                return Err(grid_error(
                    g,
                    "extends past the int32 coordinate range".into(),
                ));
            }
        }
        boxes.push((lo, hi));
    }

    // Mark cells that a grid of a finer AMR level contains. Grids sorted by
    // their lower x: the grids that may overlap one lie in a window of that
    // order (lower x within the widest grid's width of it), found by binary
    // search, so many grids cost far less than every pair. Each grid's
    // mask on every core.
    let mut by_x: Vec<usize> = (0..grids.len()).collect();
    by_x.sort_unstable_by_key(|&b| boxes[b].0[0]);
    let widest = boxes
        .iter()
        .map(|(lo, hi)| hi[0] - lo[0])
        .max()
        .unwrap_or(0);
    let covered: Vec<Vec<bool>> = (0..grids.len())
        .into_par_iter()
        .map(|a| {
            let ga = &grids[a];
            let mut mask: Vec<bool> = Vec::new();
            let (lo, hi) = boxes[a];
            let width = 1i64 << levels[a];
            let start = by_x.partition_point(|&b| boxes[b].0[0] <= lo[0] - widest);
            let end = by_x.partition_point(|&b| boxes[b].0[0] < hi[0]);
            for &b in &by_x[start..end] {
                let gb = &grids[b];
                let (flo, fhi) = boxes[b];
                if gb.amr_level <= ga.amr_level
                    || (0..3).any(|k| fhi[k] <= lo[k] || flo[k] >= hi[k])
                {
                    continue;
                }
                // Cells i with [lo + i·w, lo + (i+1)·w) inside [flo, fhi).
                let mut range = [(0usize, 0usize); 3];
                for k in 0..3 {
                    let first = (flo[k] - lo[k] + width - 1).div_euclid(width).max(0);
                    let end = (fhi[k] - lo[k]).div_euclid(width).min(ga.size[k] as i64);
                    range[k] = (first as usize, end.max(first) as usize);
                }
                if mask.is_empty() {
                    mask.resize(ga.size[0] * ga.size[1] * ga.size[2], false);
                }
                let [nx, ny, _] = ga.size;
                for z in range[2].0..range[2].1 {
                    for y in range[1].0..range[1].1 {
                        let row = (z * ny + y) * nx;
                        mask[row + range[0].0..row + range[0].1].fill(true);
                    }
                }
            }
            mask
        })
        .collect();

    // Each grid's leaf cells written on every core into its own run of the
    // output (the runs in grid order, cells x fastest as in the file).
    let counts: Vec<usize> = grids
        .iter()
        .zip(&covered)
        .map(|(g, mask)| {
            let total = g.size[0] * g.size[1] * g.size[2];
            total - mask.iter().filter(|&&c| c).count()
        })
        .collect();
    let kept: usize = counts.iter().sum();
    let (names, cols) = columns(meqn, pick);
    let stride = cols.as_ref().map_or(meqn, Vec::len);
    let names: Vec<String> = match &cols {
        Some(cols) => cols.iter().map(|&c| names[c].clone()).collect(),
        None => names,
    };
    let mut cells = vec![[0i32; 4]; kept];
    let mut values = vec![vec![0.0f32; kept]; stride];
    let mut runs = Vec::with_capacity(grids.len());
    let mut cell_rest = cells.as_mut_slice();
    let mut value_rest: Vec<&mut [f32]> = values.iter_mut().map(Vec::as_mut_slice).collect();
    for &n in &counts {
        let (run, tail) = std::mem::take(&mut cell_rest).split_at_mut(n);
        cell_rest = tail;
        let mut field_runs = Vec::with_capacity(stride);
        for rest in &mut value_rest {
            let (run, tail) = std::mem::take(rest).split_at_mut(n);
            *rest = tail;
            field_runs.push(run);
        }
        runs.push((run, field_runs));
    }
    {
        runs.into_par_iter()
            .zip(&grids)
            .zip(&covered)
            .zip(&boxes)
            .zip(&levels)
            .for_each(|(((((out, mut field_out), g), mask), (lo, _)), &level)| {
                let width = 1i64 << level;
                let [nx, ny, nz] = g.size;
                let (mut index, mut k) = (0, 0);
                for z in 0..nz {
                    for y in 0..ny {
                        for x in 0..nx {
                            if mask.is_empty() || !mask[index] {
                                // In range: hi was checked against i32::MAX above.
                                let corner = |a: usize, i: usize| (lo[a] + i as i64 * width) as i32;
                                out[k] = [corner(0, x), corner(1, y), corner(2, z), level as i32];
                                let row = &g.values[index * stride..(index + 1) * stride];
                                for (field, &v) in field_out.iter_mut().zip(row) {
                                    field[k] = v;
                                }
                                k += 1;
                            }
                            index += 1;
                        }
                    }
                }
            });
    }
    let fields: Vec<(String, Vec<f32>)> = names.into_iter().zip(values).collect();
    Ok(AmrCellData {
        cells,
        fields,
        origin,
        finest_cell_size: finest,
        time: None,
    })
}
