//! Athena++ `.athdf` files as AMR leaf cells.
//!
//! Athena++ writes only the leaf meshblocks of its mesh, each
//! `MeshBlockSize` cells, into one file:
//!
//! ```text
//! root attributes   RootGridSize, MeshBlockSize (3 ints), NumMeshBlocks, MaxLevel,
//!                   RootGridX1/X2/X3 ([min, max, ratio]), Time, NumVariables
//!                   (per dataset), DatasetNames, VariableNames
//! Levels            (nblocks,) refinement level, 0 = root
//! LogicalLocations  (nblocks, 3) block index at its own level
//! x1f, x2f, x3f     (nblocks, n + 1) face coordinates (not needed here)
//! prim, cons, …     (nvar, nblocks, nz, ny, nx), x fastest
//! ```
//!
//! `VariableNames` lists the variables of every dataset in `DatasetNames`
//! order, `NumVariables[i]` of them for dataset `i`.

use std::path::Path;

use super::amr_blocks::{Block, Layout, leaf_masks, push_cells, same_width};
use super::flash::read_strings;
use super::{Hdf5File, shape_text};
use crate::IoError;
use crate::amr::{AmrCellData, MAX_LEVEL};

/// Reads an Athena++ `.athdf` file's meshblocks as leaf cells, one field per
/// entry of `VariableNames`, named as the file names it (`rho`, `press`, …).
///
/// Fails, naming the file, when a root attribute or dataset the layout
/// needs is missing or malformed, when the mesh is not 3-D, not uniformly
/// spaced (a `RootGridX` ratio other than 1) or has non-cubic cells, when a
/// meshblock lies outside the mesh, when two meshblocks overlap (naming
/// both), and when a listed dataset is missing or a variable name is empty.
pub fn read_athena(path: &Path) -> Result<AmrCellData, IoError> {
    let f = Hdf5File::open(path)?;
    let root = f.root();
    let owner = "root group";
    let attr = |name: &str, len: usize| -> Result<Vec<f64>, IoError> {
        let values = f
            .attr_f64(root, owner, name)?
            .ok_or_else(|| f.err(format!("root attribute {name} is missing")))?;
        if values.len() != len {
            return Err(f.err(format!(
                "root attribute {name}: expected {len} value(s), found {}",
                values.len()
            )));
        }
        Ok(values)
    };
    let count = |name: &str, v: f64| -> Result<usize, IoError> {
        if v >= 1.0 && v.fract() == 0.0 && v <= 1e9 {
            Ok(v as usize)
        } else {
            Err(f.err(format!(
                "root attribute {name}: {v} is not a positive count"
            )))
        }
    };

    let root_size = attr("RootGridSize", 3)?;
    let block_size = attr("MeshBlockSize", 3)?;
    let mut root_cells = [0usize; 3];
    let mut bs = [0usize; 3];
    for d in 0..3 {
        root_cells[d] = count("RootGridSize", root_size[d])?;
        bs[d] = count("MeshBlockSize", block_size[d])?;
    }
    if root_cells.contains(&1) {
        return Err(f.err(format!(
            "root attribute RootGridSize is ({}, {}, {}): only 3-D meshes are supported",
            root_cells[0], root_cells[1], root_cells[2]
        )));
    }
    if (0..3).any(|d| root_cells[d] % bs[d] != 0) {
        return Err(f.err(format!(
            "root attribute MeshBlockSize ({}, {}, {}) does not divide RootGridSize ({}, {}, {})",
            bs[0], bs[1], bs[2], root_cells[0], root_cells[1], root_cells[2]
        )));
    }
    let root_blocks: [usize; 3] = std::array::from_fn(|d| root_cells[d] / bs[d]);

    let mut origin = [0.0f64; 3];
    let mut dx = [0.0f64; 3];
    for d in 0..3 {
        let name = format!("RootGridX{}", d + 1);
        let x = attr(&name, 3)?;
        let (min, max, ratio) = (x[0], x[1], x[2]);
        if ratio != 1.0 {
            return Err(f.err(format!(
                "root attribute {name}: ratio {ratio}; only uniform spacing (ratio 1) is \
                 supported"
            )));
        }
        dx[d] = (max - min) / root_cells[d] as f64;
        if !(min.is_finite() && dx[d].is_finite() && dx[d] > 0.0) {
            return Err(f.err(format!(
                "root attribute {name}: [{min}, {max}] is not an increasing finite range"
            )));
        }
        origin[d] = min;
    }
    if !(same_width(dx[0], dx[1]) && same_width(dx[0], dx[2])) {
        return Err(f.err(format!(
            "root cells are {} × {} × {}: non-cubic cells are not supported",
            dx[0], dx[1], dx[2]
        )));
    }
    let time = f.attr_scalar(root, owner, "Time")?;

    // The meshblocks.
    let levels_ds = f.required_dataset(root, "Levels", "Levels")?;
    let (levels_shape, levels) = f.read_i64(&levels_ds, "Levels")?;
    if levels_shape.len() != 1 {
        return Err(f.err(format!(
            "dataset Levels: expected one entry per meshblock, found shape {}",
            shape_text(&levels_shape)
        )));
    }
    let nblocks = levels.len();
    if let Some(said) = f.attr_scalar(root, owner, "NumMeshBlocks")?
        && said != nblocks as f64
    {
        return Err(f.err(format!(
            "root attribute NumMeshBlocks is {said} but dataset Levels has {nblocks} entries"
        )));
    }
    if nblocks == 0 {
        return Err(f.err("the file holds no meshblocks"));
    }
    let loc_ds = f.required_dataset(root, "LogicalLocations", "LogicalLocations")?;
    let (loc_shape, locations) = f.read_i64(&loc_ds, "LogicalLocations")?;
    if loc_shape != [nblocks, 3] {
        return Err(f.err(format!(
            "dataset LogicalLocations: expected shape {}, found {}",
            shape_text(&[nblocks, 3]),
            shape_text(&loc_shape)
        )));
    }
    if let Some((b, &l)) = levels
        .iter()
        .enumerate()
        .find(|(_, l)| !(0..=i64::from(MAX_LEVEL)).contains(*l))
    {
        return Err(f.err(format!(
            "dataset Levels: meshblock {b} has level {l}, outside 0..={MAX_LEVEL}"
        )));
    }
    let max_level = levels.iter().copied().max().unwrap_or(0);
    let finest = dx[0] / f64::from(1u32 << max_level);

    let mut blocks = Vec::with_capacity(nblocks);
    for (b, &level) in levels.iter().enumerate() {
        let exa = (max_level - level) as u32;
        let mut lo = [0i64; 3];
        for d in 0..3 {
            let loc = locations[b * 3 + d];
            let across = root_blocks[d] as i64 * (1i64 << level);
            if !(0..across).contains(&loc) {
                return Err(f.err(format!(
                    "dataset LogicalLocations: meshblock {b} (level {level}) is at {loc} along \
                     axis {d}, outside the {across} meshblocks of its level"
                )));
            }
            lo[d] = loc
                .checked_mul(bs[d] as i64)
                .and_then(|v| v.checked_mul(1i64 << exa))
                .ok_or_else(|| {
                    f.err(format!(
                        "meshblock {b} (level {level}) reaches beyond the 32-bit cell coordinates"
                    ))
                })?;
        }
        blocks.push(
            Block::new(lo, bs, exa)
                .map_err(|m| f.err(format!("meshblock {b} (level {level}) {m}")))?,
        );
    }
    leaf_masks(&blocks, Layout::LeafOnly, &|b| {
        format!("meshblock {b} (level {})", levels[b])
    })
    .map_err(|m| f.err(m))?;

    // The datasets and their variables.
    let string_attr = |name: &str| -> Result<Vec<String>, IoError> {
        let what = format!("root attribute {name}");
        if !root.attr_names().is_ok_and(|n| n.iter().any(|a| a == name)) {
            return Err(f.err(format!("{what} is missing")));
        }
        let a = root.attr(name).map_err(|e| f.h5err(&what, e))?;
        read_strings(&f, &a, &what)
    };
    let dataset_names = string_attr("DatasetNames")?;
    let variable_names = string_attr("VariableNames")?;
    let per_dataset = attr("NumVariables", dataset_names.len())?;
    let mut counts = Vec::with_capacity(per_dataset.len());
    for &n in &per_dataset {
        if !(n >= 0.0 && n.fract() == 0.0 && n <= 1e6) {
            return Err(f.err(format!(
                "root attribute NumVariables: {n} is not a variable count"
            )));
        }
        counts.push(n as usize);
    }
    let total: usize = counts.iter().sum();
    if total != variable_names.len() {
        return Err(f.err(format!(
            "root attribute NumVariables adds up to {total}, but VariableNames lists {} names",
            variable_names.len()
        )));
    }
    if total == 0 {
        return Err(f.err("root attribute VariableNames lists no variables"));
    }
    if let Some(k) = variable_names.iter().position(|n| n.is_empty()) {
        return Err(f.err(format!(
            "root attribute VariableNames: entry {k} is an empty name"
        )));
    }

    // Check every dataset before allocating.
    let per_block = bs
        .iter()
        .try_fold(nblocks, |acc, &n| acc.checked_mul(n))
        .map(|all| all / nblocks)
        .ok_or_else(|| f.err("the meshblocks hold too many cells"))?;
    let mut datasets = Vec::with_capacity(dataset_names.len());
    for (name, &nvar) in dataset_names.iter().zip(&counts) {
        if name.is_empty() {
            return Err(f.err("root attribute DatasetNames holds an empty name"));
        }
        let ds = f.child_dataset(root, name).ok_or_else(|| {
            f.err(format!(
                "dataset {name} is missing (it is listed in DatasetNames)"
            ))
        })?;
        let expected = [nvar, nblocks, bs[2], bs[1], bs[0]];
        let shape = ds.shape();
        if shape != expected {
            return Err(f.err(format!(
                "dataset {name}: expected shape {} (variables, meshblocks, nz, ny, nx), found {}",
                shape_text(&expected),
                shape_text(&shape)
            )));
        }
        f.checked_count(
            &ds,
            &shape,
            !ds.filters().is_empty(),
            &format!("dataset {name}"),
        )?;
        datasets.push(ds);
    }

    let mut cells = Vec::with_capacity(nblocks * per_block);
    for b in &blocks {
        push_cells(&mut cells, b, None);
    }
    let mut fields = Vec::with_capacity(total);
    let mut names = variable_names.into_iter();
    for ((ds, name), &nvar) in datasets.iter().zip(&dataset_names).zip(&counts) {
        let values = f.read_f32(ds, name)?;
        for (v, chunk) in values.data.chunks_exact(nblocks * per_block).enumerate() {
            if v >= nvar {
                break;
            }
            let var = names.next().unwrap_or_default();
            fields.push((var, chunk.to_vec()));
        }
    }
    Ok(AmrCellData {
        cells,
        fields,
        origin,
        finest_cell_size: finest,
        time,
    })
}
