//! PySPH output files (`<name>_<iteration>.hdf5`).
//!
//! PySPH's `HDFOutput` writes one group per particle array:
//!
//! ```text
//! solver_data            attributes t (time), dt, count (iteration)
//! particles/<array>/arrays/<prop>      one 1-D dataset per property
//! particles/<array>/constants/<name>   per-array constants (ignored here)
//! ```
//!
//! Each property dataset carries the attributes `name`, `type`, `default`,
//! `stride` and `stored`. Properties that were not selected for output are
//! still written, as empty float32 datasets with `stored = False`; they are
//! skipped. A property with `stride` s > 1 holds s values per particle
//! (particle-major) and becomes the columns `<prop>_0` … `<prop>_<s-1>`.
//! The time is the `t` attribute of `solver_data`; PySPH writes it as a float,
//! except in the first output where it is the integer 0.

use std::path::Path;

use hdf5_metno as h5;

use super::{Hdf5File, is_numeric, name_list};
use crate::{IoError, ParticleTable};

/// The names of the particle arrays (groups under `particles/`) of a PySPH
/// output file, sorted.
pub fn pysph_groups(path: &Path) -> Result<Vec<String>, IoError> {
    let f = Hdf5File::open(path)?;
    let particles = particles_group(&f)?;
    f.subgroup_names(&particles, "particles", |_| true)
}

/// Reads the particle array `group` of a PySPH output file.
///
/// Positions come from `particles/<group>/arrays/{x,y,z}`; every other
/// stored numeric property becomes a column (converted to `f32`), in name
/// order, followed by `speed` = |(u, v, w)| when the velocities are stored.
/// The time is `solver_data`'s attribute `t`. An unknown `group` is an error
/// that lists the groups present; so is a property whose length is not the
/// number of particles.
pub fn read_pysph(path: &Path, group: &str) -> Result<ParticleTable, IoError> {
    let f = Hdf5File::open(path)?;
    let particles = particles_group(&f)?;
    let groups = f.subgroup_names(&particles, "particles", |_| true)?;
    let Some(array_group) = f.child_group(&particles, group) else {
        return Err(f.err(format!(
            "no particle array {group:?} under particles/ (arrays present: {})",
            name_list(&groups)
        )));
    };
    let prefix = format!("particles/{group}/arrays");
    let arrays = f.child_group(&array_group, "arrays").ok_or_else(|| {
        f.err(format!(
            "group particles/{group} has no arrays group (expected {prefix})"
        ))
    })?;

    // Positions.
    let mut coords = Vec::with_capacity(3);
    for axis in ["x", "y", "z"] {
        let full = format!("{prefix}/{axis}");
        let ds = f.required_dataset(&arrays, axis, &full)?;
        // Positions in float64, as stored: data far from the origin keeps
        // its digits until the library recentres it.
        let (shape, data) = f.read_f64(&ds, &full)?;
        if shape.len() != 1 {
            return Err(f.err(format!(
                "dataset {full}: expected a 1-D array, found shape {}",
                super::shape_text(&shape)
            )));
        }
        coords.push((full, data));
    }
    let n = coords[0].1.len();
    for (full, data) in &coords[1..] {
        if data.len() != n {
            return Err(f.length_mismatch(full, data.len(), &coords[0].0, n));
        }
    }
    let positions = (0..n)
        .map(|i| [coords[0].1[i], coords[1].1[i], coords[2].1[i]])
        .collect();
    drop(coords);

    let mut table = ParticleTable {
        positions,
        ..ParticleTable::default()
    };
    let reference = format!("{prefix}/x");
    for name in f.member_names(&arrays, &prefix)? {
        if matches!(name.as_str(), "x" | "y" | "z") {
            continue;
        }
        let Some(ds) = f.child_dataset(&arrays, &name) else {
            continue;
        };
        let full = format!("{prefix}/{name}");
        if !is_stored(&f, &ds, &full)? || ds.ndim() != 1 || !is_numeric(&ds) {
            continue;
        }
        let len = ds.shape()[0];
        if len == 0 && n > 0 {
            // An unstored property from a writer without the `stored` flag.
            continue;
        }
        let stride = stride(&f, &ds, &full);
        if len != n && (stride <= 1 || Some(len) != n.checked_mul(stride)) {
            return Err(f.length_mismatch(&full, len, &reference, n));
        }
        let values = f.read_f32(&ds, &full)?.data;
        if len == n {
            table.columns.push((name, values));
        } else {
            for c in 0..stride {
                let column = values.iter().skip(c).step_by(stride).copied().collect();
                table.columns.push((format!("{name}_{c}"), column));
            }
        }
    }
    table.derive_speed("u", "v", "w");

    if let Some(solver) = f.child_group(f.root(), "solver_data") {
        table.time = f.attr_scalar(&solver, "group solver_data", "t")?;
    }
    Ok(table)
}

/// The `particles` group, or an error saying this is not PySPH output.
fn particles_group(f: &Hdf5File) -> Result<h5::Group, IoError> {
    f.child_group(f.root(), "particles").ok_or_else(|| {
        let top = f.member_names(f.root(), "/").unwrap_or_default();
        f.err(format!(
            "not a PySPH output file: no group particles (top-level members: {})",
            name_list(&top)
        ))
    })
}

/// False when the dataset's `stored` attribute says PySPH did not write its
/// data.
fn is_stored(f: &Hdf5File, ds: &h5::Dataset, full: &str) -> Result<bool, IoError> {
    // h5py writes NumPy booleans as an enum, which `attr_f64` does not read;
    // read the flag as a byte instead.
    let owner = format!("dataset {full}");
    let names = ds
        .attr_names()
        .map_err(|e| f.h5err(&format!("attributes of {owner}"), e))?;
    if !names.iter().any(|n| n == "stored") {
        return Ok(true);
    }
    let attr = ds
        .attr("stored")
        .map_err(|e| f.h5err(&format!("{owner} attribute stored"), e))?;
    if attr.size() != 1 {
        return Ok(true);
    }
    match attr.read_raw::<u8>() {
        Ok(v) => Ok(v.first().is_none_or(|&b| b != 0)),
        Err(_) => Ok(true),
    }
}

/// The dataset's `stride` attribute (values per particle); 1 when absent or
/// not a positive whole number.
fn stride(f: &Hdf5File, ds: &h5::Dataset, full: &str) -> usize {
    let owner = format!("dataset {full}");
    match f.attr_scalar(ds, &owner, "stride") {
        Ok(Some(s)) if s >= 1.0 && s.fract() == 0.0 && s <= 1e9 => s as usize,
        _ => 1,
    }
}
