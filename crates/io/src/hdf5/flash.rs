//! FLASH HDF5 plot and checkpoint files as AMR leaf cells, and the block
//! machinery the three AMR readers of this module share (FLASH here, Enzo in
//! `enzo.rs`, Athena++ in `athena.rs`).
//!
//! A FLASH file (PARAMESH, HDF5 format version 8 and later) holds, for
//! `nblocks` blocks of the octree, parents and leaves alike:
//!
//! ```text
//! unknown names            (nvar, 1) fixed-length strings: the variables ("dens", …)
//! refine level             (nblocks,) integers, 1 = coarsest
//! node type                (nblocks,) integers, 1 = leaf
//! bounding box             (nblocks, 3, 2) float64: [axis][min, max]
//! <name>                   (nblocks, nzb, nyb, nxb) per variable, x fastest
//! integer scalars          compound (name, value) table: nxb, nyb, nzb, dimensionality
//! real scalars             compound (name, value) table: time
//! real runtime parameters  compound (name, value) table: xmin, ymin, zmin, …
//! ```
//!
//! Only leaf blocks give cells. The domain's lower corner (`xmin`, `ymin`,
//! `zmin`; without them, the lowest leaf corner) is the origin, and the
//! leaves' finest cell width the unit.

use std::path::Path;

use hdf5_metno as h5;
use hdf5_metno::H5Type;
use hdf5_metno::types::{FixedAscii, FixedUnicode, TypeDescriptor, VarLenAscii, VarLenUnicode};

use super::amr_blocks::{Block, Layout, leaf_masks, on_lattice, push_cells, same_width};
use super::{Hdf5File, shape_text, type_name};
use crate::IoError;
use crate::amr::{AmrCellData, MAX_LEVEL};

/// Reads the leaf blocks of a FLASH HDF5 plot or checkpoint file as leaf
/// cells, one field per `unknown names` entry, named as the file names it.
///
/// Fails, naming the file, when a dataset the layout needs is missing or
/// has the wrong shape, when a listed variable has no dataset (naming it),
/// when the file is not 3-D Cartesian, when cells are not cubic, when a
/// block's width does not match its refine level, and when two leaf blocks
/// overlap (naming both).
pub fn read_flash(path: &Path) -> Result<AmrCellData, IoError> {
    let f = Hdf5File::open(path)?;
    let root = f.root();

    let ints = read_table(&f, "integer scalars")?;
    let reals = read_table(&f, "real scalars")?;
    let real_params = read_table(&f, "real runtime parameters")?;
    let int_params = read_table(&f, "integer runtime parameters")?;
    let lookup = |tables: &[&[(String, f64)]], key: &str| {
        tables
            .iter()
            .find_map(|t| t.iter().find(|(n, _)| n == key).map(|(_, v)| *v))
    };
    if let Some(dim) = lookup(&[&ints, &int_params], "dimensionality")
        && dim != 3.0
    {
        return Err(f.err(format!(
            "integer scalars: dimensionality is {dim}; only 3-D FLASH files are supported"
        )));
    }
    if let Some(geometry) = read_text_table(&f, "string runtime parameters")?
        .into_iter()
        .find(|(n, _)| n == "geometry")
        .map(|(_, v)| v)
        && !geometry.eq_ignore_ascii_case("cartesian")
    {
        return Err(f.err(format!(
            "string runtime parameters: geometry is {geometry}; only Cartesian meshes are \
             supported"
        )));
    }

    // The variables.
    let names_ds = f.required_dataset(root, "unknown names", "unknown names")?;
    let names = read_strings(&f, &names_ds, "dataset unknown names")?;
    if names.is_empty() {
        return Err(f.err("dataset unknown names lists no variables"));
    }
    if let Some(k) = names.iter().position(|n| n.is_empty()) {
        return Err(f.err(format!("dataset unknown names: entry {k} is an empty name")));
    }

    // The blocks.
    let levels = read_per_block(&f, "refine level")?;
    let nblocks = levels.len();
    let node_type = read_per_block(&f, "node type")?;
    if node_type.len() != nblocks {
        return Err(f.err(format!(
            "dataset node type has {} entries but refine level has {nblocks}; both need one \
             per block",
            node_type.len()
        )));
    }
    let bbox_ds = f.required_dataset(root, "bounding box", "bounding box")?;
    let (bbox_shape, bbox) = f.read_f64(&bbox_ds, "bounding box")?;
    if bbox_shape != [nblocks, 3, 2] {
        return Err(f.err(format!(
            "dataset bounding box: expected shape {} (blocks, axes, min/max), found {}",
            shape_text(&[nblocks, 3, 2]),
            shape_text(&bbox_shape)
        )));
    }

    // Cells per block: the integer scalars nxb, nyb, nzb, else the shape of
    // the first variable's dataset.
    let first_name = &names[0];
    let first_ds = f.child_dataset(root, first_name).ok_or_else(|| {
        f.err(format!(
            "dataset {first_name} is missing (variable {first_name} is listed in unknown names)"
        ))
    })?;
    let first_shape = first_ds.shape();
    let mut block_dims = [0usize; 3];
    for (d, key) in ["nxb", "nyb", "nzb"].iter().enumerate() {
        block_dims[d] = match lookup(&[&ints], key) {
            Some(v) if v >= 1.0 && v.fract() == 0.0 && v <= 1e9 => v as usize,
            Some(v) => {
                return Err(f.err(format!("integer scalars: {key} = {v} is not a block size")));
            }
            None if first_shape.len() == 4 => first_shape[3 - d],
            None => {
                return Err(f.err(format!(
                    "integer scalars: {key} is missing, and dataset {first_name} has shape {}, \
                     not (blocks, nzb, nyb, nxb)",
                    shape_text(&first_shape)
                )));
            }
        };
    }
    let [nxb, nyb, nzb] = block_dims;
    let var_shape = [nblocks, nzb, nyb, nxb];

    // The leaves, their levels and cell widths.
    let leaves: Vec<usize> = (0..nblocks).filter(|&b| node_type[b] == 1).collect();
    if leaves.is_empty() {
        return Err(f.err(format!(
            "none of the {nblocks} blocks is a leaf (node type 1)"
        )));
    }
    let mut max_refine = 1i64;
    for &b in &leaves {
        let r = levels[b];
        if !(1..=i64::from(MAX_LEVEL) + 1).contains(&r) {
            return Err(f.err(format!(
                "dataset refine level: block {b} has refine level {r}, outside 1..={}",
                MAX_LEVEL + 1
            )));
        }
        max_refine = max_refine.max(r);
    }
    let min_refine = leaves.iter().map(|&b| levels[b]).min().unwrap_or(1);
    if max_refine - min_refine > i64::from(MAX_LEVEL) {
        return Err(f.err(format!(
            "the leaf blocks span refine levels {min_refine}..={max_refine}, more than {} levels",
            MAX_LEVEL + 1
        )));
    }
    let corner = |b: usize, d: usize| bbox[(b * 3 + d) * 2];
    let width_of = |b: usize| -> Result<f64, IoError> {
        let mut dx = [0.0f64; 3];
        for d in 0..3 {
            let (lo, hi) = (bbox[(b * 3 + d) * 2], bbox[(b * 3 + d) * 2 + 1]);
            dx[d] = (hi - lo) / block_dims[d] as f64;
            if !(dx[d].is_finite() && dx[d] > 0.0 && lo.is_finite()) {
                return Err(f.err(format!(
                    "dataset bounding box: block {b} spans [{lo}, {hi}] along axis {d}, not a \
                     positive finite width"
                )));
            }
        }
        if !(same_width(dx[0], dx[1]) && same_width(dx[0], dx[2])) {
            return Err(f.err(format!(
                "block {b} has cells of {} × {} × {}: non-cubic cells are not supported",
                dx[0], dx[1], dx[2]
            )));
        }
        Ok(dx[0])
    };
    let finest_block = leaves
        .iter()
        .copied()
        .find(|&b| levels[b] == max_refine)
        .unwrap_or(leaves[0]);
    let finest = width_of(finest_block)?;

    let mut origin = [0.0f64; 3];
    for (d, key) in ["xmin", "ymin", "zmin"].iter().enumerate() {
        origin[d] = match lookup(&[&real_params], key) {
            Some(v) if v.is_finite() => v,
            _ => leaves
                .iter()
                .map(|&b| corner(b, d))
                .fold(f64::INFINITY, f64::min),
        };
    }

    let mut blocks = Vec::with_capacity(leaves.len());
    for &b in &leaves {
        let level = (max_refine - levels[b]) as u32;
        let dx = width_of(b)?;
        let expected = finest * f64::from(1u32 << level);
        if !same_width(dx, expected) {
            return Err(f.err(format!(
                "block {b} (refine level {}) has cells {dx} wide, but refine level {max_refine} \
                 has cells {finest} wide, so it should have {expected}",
                levels[b]
            )));
        }
        let mut lo = [0i64; 3];
        for d in 0..3 {
            lo[d] = on_lattice(corner(b, d), origin[d], finest).ok_or_else(|| {
                f.err(format!(
                    "block {b}: its corner {} along axis {d} is not on the finest cell lattice \
                     (origin {}, width {finest})",
                    corner(b, d),
                    origin[d]
                ))
            })?;
        }
        blocks.push(
            Block::new(lo, block_dims, level)
                .map_err(|m| f.err(format!("block {b} (refine level {}) {m}", levels[b])))?,
        );
    }
    leaf_masks(&blocks, Layout::LeafOnly, &|k| {
        format!("leaf block {}", leaves[k])
    })
    .map_err(|m| f.err(m))?;

    // Every variable's dataset, checked before anything is allocated.
    let mut datasets = Vec::with_capacity(names.len());
    for n in &names {
        let ds = f.child_dataset(root, n).ok_or_else(|| {
            f.err(format!(
                "dataset {n} is missing (variable {n} is listed in unknown names)"
            ))
        })?;
        let shape = ds.shape();
        if shape != var_shape {
            return Err(f.err(format!(
                "dataset {n}: expected shape {} (blocks, nzb, nyb, nxb), found {}",
                shape_text(&var_shape),
                shape_text(&shape)
            )));
        }
        f.checked_count(
            &ds,
            &shape,
            !ds.filters().is_empty(),
            &format!("dataset {n}"),
        )?;
        datasets.push(ds);
    }

    let per_block = nxb * nyb * nzb;
    let mut cells = Vec::with_capacity(leaves.len() * per_block);
    for b in &blocks {
        push_cells(&mut cells, b, None);
    }
    let mut fields = Vec::with_capacity(names.len());
    for (n, ds) in names.iter().zip(&datasets) {
        let values = f.read_f32(ds, n)?;
        let mut out = Vec::with_capacity(cells.len());
        for &b in &leaves {
            out.extend_from_slice(&values.data[b * per_block..(b + 1) * per_block]);
        }
        fields.push((n.clone(), out));
    }
    Ok(AmrCellData {
        cells,
        fields,
        origin,
        finest_cell_size: finest,
        time: lookup(&[&reals], "time"),
    })
}

/// The 1-D integer dataset `name` with one entry per block.
fn read_per_block(f: &Hdf5File, name: &str) -> Result<Vec<i64>, IoError> {
    let ds = f.required_dataset(f.root(), name, name)?;
    let (shape, values) = f.read_i64(&ds, name)?;
    if shape.len() != 1 {
        return Err(f.err(format!(
            "dataset {name}: expected one entry per block, found shape {}",
            shape_text(&shape)
        )));
    }
    Ok(values)
}

/// A row of a FLASH `(name, value)` table with a numeric value.
#[derive(H5Type, Clone)]
#[repr(C)]
struct NamedNumber {
    name: FixedAscii<80>,
    value: f64,
}

/// A row of a FLASH `(name, value)` table with a string value.
#[derive(H5Type, Clone)]
#[repr(C)]
struct NamedText {
    name: FixedAscii<80>,
    value: FixedAscii<80>,
}

/// The most rows a FLASH parameter table or a list of names may have.
const MAX_ROWS: usize = 1 << 20;

/// The compound dataset `name` (a FLASH table of `name` and `value`
/// members), checked; `None` when the file has no such dataset.
fn table_dataset(f: &Hdf5File, name: &str, numeric: bool) -> Result<Option<h5::Dataset>, IoError> {
    let Some(ds) = f.child_dataset(f.root(), name) else {
        return Ok(None);
    };
    let what = format!("dataset {name}");
    let desc = ds
        .dtype()
        .and_then(|t| t.to_descriptor())
        .map_err(|e| f.h5err(&what, e))?;
    let member = |key: &str| match &desc {
        TypeDescriptor::Compound(c) => c.fields.iter().find(|m| m.name == key).map(|m| &m.ty),
        _ => None,
    };
    let name_ok = matches!(member("name"), Some(TypeDescriptor::FixedAscii(_)));
    let value_ok = match member("value") {
        Some(
            TypeDescriptor::Integer(_) | TypeDescriptor::Unsigned(_) | TypeDescriptor::Float(_),
        ) => numeric,
        Some(TypeDescriptor::FixedAscii(_)) => !numeric,
        _ => false,
    };
    if !(name_ok && value_ok) {
        return Err(f.err(format!(
            "{what}: expected a table of (name: fixed-length string, value: {}), found {}",
            if numeric {
                "number"
            } else {
                "fixed-length string"
            },
            type_name(&ds)
        )));
    }
    let shape = ds.shape();
    let count = f.checked_count(&ds, &shape, !ds.filters().is_empty(), &what)?;
    if count > MAX_ROWS {
        return Err(f.err(format!(
            "{what}: {count} rows is too many for a parameter table"
        )));
    }
    Ok(Some(ds))
}

/// The rows of the numeric FLASH table `name` (names trimmed); empty when
/// the file has no such table.
fn read_table(f: &Hdf5File, name: &str) -> Result<Vec<(String, f64)>, IoError> {
    let Some(ds) = table_dataset(f, name, true)? else {
        return Ok(Vec::new());
    };
    let rows = ds
        .read_raw::<NamedNumber>()
        .map_err(|e| f.h5err(&format!("dataset {name}"), e))?;
    Ok(rows
        .iter()
        .map(|r| (trim(r.name.as_str()), r.value))
        .collect())
}

/// The rows of the string FLASH table `name`; empty when absent.
fn read_text_table(f: &Hdf5File, name: &str) -> Result<Vec<(String, String)>, IoError> {
    let Some(ds) = table_dataset(f, name, false)? else {
        return Ok(Vec::new());
    };
    let rows = ds
        .read_raw::<NamedText>()
        .map_err(|e| f.h5err(&format!("dataset {name}"), e))?;
    Ok(rows
        .iter()
        .map(|r| (trim(r.name.as_str()), trim(r.value.as_str())))
        .collect())
}

/// Text without padding: trailing NULs, spaces, and surrounding blanks.
fn trim(s: &str) -> String {
    s.trim_matches(|c: char| c == '\0' || c.is_whitespace())
        .to_string()
}

// ---------------------------------------------------------------------------
// Shared by the FLASH, Enzo and Athena++ readers.
// ---------------------------------------------------------------------------

/// The strings of a dataset or attribute (fixed or variable length, ASCII or
/// UTF-8), trimmed of padding, in storage order. `what` names it in errors.
pub(super) fn read_strings(
    f: &Hdf5File,
    container: &h5::Container,
    what: &str,
) -> Result<Vec<String>, IoError> {
    let shape = container.shape();
    let count = f.checked_count(container, &shape, false, what)?;
    if count > MAX_ROWS {
        return Err(f.err(format!("{what}: {count} names is too many")));
    }
    let desc = container
        .dtype()
        .and_then(|t| t.to_descriptor())
        .map_err(|e| f.h5err(what, e))?;
    let err = |e| f.h5err(what, e);
    let texts: Vec<String> = match desc {
        TypeDescriptor::FixedAscii(_) => container
            .read_raw::<FixedAscii<256>>()
            .map_err(err)?
            .iter()
            .map(|s| trim(s.as_str()))
            .collect(),
        TypeDescriptor::FixedUnicode(_) => container
            .read_raw::<FixedUnicode<256>>()
            .map_err(err)?
            .iter()
            .map(|s| trim(s.as_str()))
            .collect(),
        TypeDescriptor::VarLenAscii => container
            .read_raw::<VarLenAscii>()
            .map_err(err)?
            .iter()
            .map(|s| trim(s.as_str()))
            .collect(),
        TypeDescriptor::VarLenUnicode => container
            .read_raw::<VarLenUnicode>()
            .map_err(err)?
            .iter()
            .map(|s| trim(s.as_str()))
            .collect(),
        _ => {
            return Err(f.err(format!(
                "{what}: expected strings, found {}",
                type_name(container)
            )));
        }
    };
    Ok(texts)
}
