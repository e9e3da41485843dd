//! JaxPM particle-mesh runs saved with h5py.
//!
//! ```text
//! /                 attributes N (particles per side), boxsize_Mpc_h, …
//! q_index           N³×3 integers: the Lagrangian grid cell (i, j, k) of each row
//! snap_<K>/x        N³×3 Eulerian positions (Mpc/h, periodic box), attribute a
//! snap_<K>/v        N³×3 velocities
//! ic_delta          N×N×N initial density contrast
//! ```
//!
//! Row r of every `snap_<K>/x` belongs to the particle that started at grid
//! cell `q_index[r]`. [`read_jaxpm`] puts the particles in Lagrangian order,
//! (i·N + j)·N + k with k fastest, which is the order the phase-space
//! tessellation needs.

use std::path::Path;

use super::{Hdf5File, name_list, numbered, shape_text};
use crate::IoError;

/// One snapshot of a JaxPM run, in Lagrangian order.
#[derive(Clone, Debug, PartialEq)]
pub struct JaxpmSnapshot {
    /// Particles per side of the Lagrangian grid (N³ particles in all).
    pub n: usize,
    /// Side of the periodic box (Mpc/h).
    pub box_size: f64,
    /// Positions; particle (i, j, k) of the Lagrangian grid is at index
    /// (i·N + j)·N + k, k fastest.
    pub positions: Vec<[f32; 3]>,
    /// The snapshot's scale factor (attribute `a` of `snap_<K>`), when given.
    pub scale_factor: Option<f64>,
}

/// Root attributes that may hold the box size, in order of preference.
const BOX_ATTRS: [&str; 4] = ["boxsize_Mpc_h", "box_size", "boxsize", "BoxSize"];

/// The snapshot numbers K of the `snap_<K>` groups of a JaxPM file, in
/// increasing order (empty when there are none).
pub fn jaxpm_snapshots(path: &Path) -> Result<Vec<usize>, IoError> {
    let f = Hdf5File::open(path)?;
    snapshot_numbers(&f)
}

/// The numbers of the `snap_<K>` groups of an open file, sorted.
fn snapshot_numbers(f: &Hdf5File) -> Result<Vec<usize>, IoError> {
    let mut numbers: Vec<usize> = f
        .subgroup_names(f.root(), "/", |n| numbered(n, "snap_").is_some())?
        .iter()
        .filter_map(|n| numbered(n, "snap_").and_then(|k| usize::try_from(k).ok()))
        .collect();
    numbers.sort_unstable();
    Ok(numbers)
}

/// Reads snapshot `snapshot` (the group `snap_<snapshot>`) of a JaxPM file
/// and reorders its positions with `q_index` into Lagrangian order.
///
/// `N` is the root attribute `N`, or the cube root of the particle count
/// when that attribute is absent. Fails, naming the file and dataset, when
/// the snapshot does not exist (listing those that do), when the positions or
/// `q_index` are not N³×3, when `q_index` is not a permutation of the N³ grid
/// cells, or when no root attribute gives the box size.
pub fn read_jaxpm(path: &Path, snapshot: usize) -> Result<JaxpmSnapshot, IoError> {
    let f = Hdf5File::open(path)?;
    let root = f.root();
    let gname = format!("snap_{snapshot}");
    let Some(group) = f.child_group(root, &gname) else {
        let names: Vec<String> = snapshot_numbers(&f)?
            .into_iter()
            .map(|k| format!("snap_{k}"))
            .collect();
        return Err(f.err(format!(
            "no snapshot group {gname} (snapshots present: {})",
            name_list(&names)
        )));
    };

    let mut box_size = None;
    for name in BOX_ATTRS {
        if let Some(size) = f.attr_scalar(root, "root group", name)? {
            box_size = Some(size);
            break;
        }
    }
    let box_size = box_size.ok_or_else(|| {
        f.err(format!(
            "no box size: the root group has none of the attributes {}",
            BOX_ATTRS.join(", ")
        ))
    })?;
    let scale_factor = f.attr_scalar(&group, &format!("group {gname}"), "a")?;

    // Positions in file order.
    let x_name = format!("{gname}/x");
    let ds = f.required_dataset(&group, "x", &x_name)?;
    let x = f.read_f32(&ds, &x_name)?;
    if x.shape.len() != 2 || x.shape[1] != 3 {
        return Err(f.err(format!(
            "dataset {x_name}: expected an N³×3 array, found shape {}",
            shape_text(&x.shape)
        )));
    }
    let count = x.shape[0];
    let n = grid_side(&f, count, &x_name)?;

    // The Lagrangian cell of every row.
    let q_ds = f.required_dataset(root, "q_index", "q_index")?;
    let q_shape = q_ds.shape();
    if q_shape.as_slice() != [count, 3] {
        return Err(f.err(format!(
            "dataset q_index: expected shape {} to match {x_name}, found {}",
            shape_text(&[count, 3]),
            shape_text(&q_shape)
        )));
    }
    let (_, q) = f.read_i64(&q_ds, "q_index")?;

    let mut positions = vec![[0.0f32; 3]; count];
    let mut seen = vec![false; count];
    let side = n as i64;
    for (row, (cell, p)) in q.chunks_exact(3).zip(x.data.chunks_exact(3)).enumerate() {
        if cell.iter().any(|&c| c < 0 || c >= side) {
            return Err(f.err(format!(
                "dataset q_index: row {row} is ({}, {}, {}), outside the {n}³ grid; \
                 q_index must be a permutation of the grid cells",
                cell[0], cell[1], cell[2]
            )));
        }
        let index = ((cell[0] * side + cell[1]) * side + cell[2]) as usize;
        if seen[index] {
            return Err(f.err(format!(
                "dataset q_index: cell ({}, {}, {}) appears more than once (again in row {row}); \
                 q_index must be a permutation of the {n}³ grid cells",
                cell[0], cell[1], cell[2]
            )));
        }
        seen[index] = true;
        positions[index] = [p[0], p[1], p[2]];
    }
    Ok(JaxpmSnapshot {
        n,
        box_size,
        positions,
        scale_factor,
    })
}

/// N for `count` = N³ particles: the root attribute `N` when present (it must
/// agree), otherwise the exact cube root.
fn grid_side(f: &Hdf5File, count: usize, x_name: &str) -> Result<usize, IoError> {
    let cube_root = (count as f64).cbrt().round() as usize;
    let exact = (cube_root.checked_pow(3) == Some(count)).then_some(cube_root);
    match f.attr_scalar(f.root(), "root group", "N")? {
        Some(n) => {
            let fits = n >= 0.0 && n.fract() == 0.0 && exact.is_some_and(|e| e as f64 == n);
            if !fits {
                return Err(f.err(format!(
                    "root attribute N = {n} does not match the {count} rows of {x_name} \
                     (expected N³ rows)"
                )));
            }
            Ok(n as usize)
        }
        None => exact.ok_or_else(|| {
            f.err(format!(
                "dataset {x_name}: {count} rows is not a cube N³, so it is not a JaxPM grid"
            ))
        }),
    }
}
