//! SWIFT and Gadget-4 snapshots.
//!
//! Both codes write one group per particle type, `PartType0` (gas),
//! `PartType1` (dark matter), …, holding `Coordinates` (N×3) and per-particle
//! datasets such as `Masses`, `SmoothingLengths`, `Density`,
//! `InternalEnergy`, `ParticleIDs` and `Velocities` (N×3). The `Header`
//! group's attributes hold `BoxSize` (a scalar in Gadget-4, a 3-vector in
//! SWIFT), `Time` (a scalar in Gadget-4, a one-element array in SWIFT; the
//! scale factor in cosmological runs) and `MassTable`, the mass of every
//! particle of a type whose group has no `Masses` dataset.

use std::path::Path;

use super::{Hdf5File, is_numeric, name_list, numbered, shape_text};
use crate::{IoError, ParticleTable, SphCode, SphConvention};

/// Reads particle type `part_type` (the group `PartType<part_type>`) of a
/// SWIFT or Gadget-4 snapshot.
///
/// Positions come from `Coordinates`. Every other numeric dataset of the
/// group with one entry per particle becomes a column named after it, in
/// name order: 1-D datasets as they are, N×3 datasets as `<name>_x`,
/// `<name>_y`, `<name>_z`, except `Velocities`, which gives `vx`, `vy`, `vz`.
/// Datasets of other shapes (N×k with k ≠ 3) are skipped. Without a `Masses`
/// dataset, a non-zero `Header` `MassTable[part_type]` gives a constant
/// `Masses` column. `speed` = |v| comes last. `Header` `BoxSize` sets the
/// domain to [0, BoxSize] and `Time` the time.
///
/// A missing group is an error listing the `PartType` groups present; so is
/// a dataset whose length differs from `Coordinates`'.
pub fn read_gadget(path: &Path, part_type: u32) -> Result<ParticleTable, IoError> {
    read_gadget_share(path, part_type, None)
}

/// [`read_gadget`] of share `r` of `k` of the particles (`share = (r, k)`:
/// rows `n·r/k .. n·(r+1)/k`), read by hyperslab; the table's `rows` says
/// which. `None` reads them all.
pub fn read_gadget_share(
    path: &Path,
    part_type: u32,
    share: Option<(usize, usize)>,
) -> Result<ParticleTable, IoError> {
    let f = Hdf5File::open(path)?;
    let root = f.root();
    let gname = format!("PartType{part_type}");
    let Some(group) = f.child_group(root, &gname) else {
        let mut present: Vec<(u64, String)> = f
            .subgroup_names(root, "/", |n| numbered(n, "PartType").is_some())?
            .into_iter()
            .map(|n| (numbered(&n, "PartType").unwrap_or(u64::MAX), n))
            .collect();
        present.sort();
        let names: Vec<String> = present.into_iter().map(|(_, n)| n).collect();
        return Err(f.err(format!(
            "no group {gname} (particle type groups present: {})",
            name_list(&names)
        )));
    };

    // Positions.
    let coords_name = format!("{gname}/Coordinates");
    let ds = f.required_dataset(&group, "Coordinates", &coords_name)?;
    let rows =
        share.map(|(r, k)| super::share_rows(ds.shape().first().copied().unwrap_or(0), r, k));
    let read = |ds: &hdf5_metno::Dataset, full: &str| match &rows {
        Some(r) => f.read_f32_rows(ds, full, r.clone(), 1),
        None => f.read_f32(ds, full),
    };
    // Float64 (cosmological boxes store coordinates in double precision).
    let (shape, data) = match &rows {
        Some(r) => f.read_f64_rows(&ds, &coords_name, r.clone(), 1)?,
        None => f.read_f64(&ds, &coords_name)?,
    };
    if shape.len() != 2 || shape[1] != 3 {
        return Err(f.err(format!(
            "dataset {coords_name}: expected an N×3 array, found shape {}",
            shape_text(&shape)
        )));
    }
    let n = shape[0];
    let positions = data.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
    drop(data);
    let mut table = ParticleTable {
        positions,
        rows: rows.as_ref().map(|r| (r.start, n)),
        ..ParticleTable::default()
    };

    for name in f.member_names(&group, &gname)? {
        if name == "Coordinates" {
            continue;
        }
        let Some(ds) = f.child_dataset(&group, &name) else {
            continue;
        };
        let full = format!("{gname}/{name}");
        let shape = ds.shape();
        let per_particle = matches!(shape.as_slice(), [_] | [_, 3]);
        if !per_particle || !is_numeric(&ds) {
            continue;
        }
        if shape[0] != n {
            return Err(f.length_mismatch(&full, shape[0], &coords_name, n));
        }
        let values = read(&ds, &full)?.data;
        if shape.len() == 1 {
            table.columns.push((name, values));
            continue;
        }
        let names = if name == "Velocities" {
            ["vx".to_string(), "vy".to_string(), "vz".to_string()]
        } else {
            ["x", "y", "z"].map(|axis| format!("{name}_{axis}"))
        };
        for (c, column) in names.into_iter().enumerate() {
            let data = values.iter().skip(c).step_by(3).copied().collect();
            table.columns.push((column, data));
        }
    }

    let header = f.child_group(root, "Header");
    if let Some(header) = &header {
        let owner = "group Header";
        if table.column("Masses").is_none()
            && let Some(masses) = f.attr_f64(header, owner, "MassTable")?
            && let Some(&mass) = masses.get(part_type as usize)
            && mass != 0.0
        {
            let count = table.positions.len();
            table
                .columns
                .push(("Masses".into(), vec![mass as f32; count]));
        }
        table.time = f.attr_scalar(header, owner, "Time")?;
        if let Some(size) = f.attr_f64(header, owner, "BoxSize")? {
            let upper = match size.as_slice() {
                &[s] => [s; 3],
                &[x, y, z] => [x, y, z],
                other => {
                    return Err(f.err(format!(
                        "Header attribute BoxSize: expected 1 or 3 values, found {}",
                        other.len()
                    )));
                }
            };
            table.domain = Some(([0.0; 3], upper));
            table.periodic = true;
        }
    }
    table.sph = Some(convention(&f, root, header.as_ref())?);
    table.derive_speed("vx", "vy", "vz");
    Ok(table)
}

/// SWIFT (a `HydroScheme` group, or `Header` `Code` naming it; the kernel
/// from `HydroScheme` `Kernel function`) or else Gadget.
fn convention(
    f: &Hdf5File,
    root: &hdf5_metno::Group,
    header: Option<&hdf5_metno::Group>,
) -> Result<SphConvention, IoError> {
    let scheme = f.child_group(root, "HydroScheme");
    let code_says_swift = match header {
        Some(h) => f
            .attr_text(h, "group Header", "Code")?
            .is_some_and(|c| c.to_ascii_uppercase().contains("SWIFT")),
        None => false,
    };
    if scheme.is_none() && !code_says_swift {
        return Ok(SphConvention {
            code: SphCode::Gadget,
            kernel: None,
        });
    }
    let kernel = match &scheme {
        Some(s) => f.attr_text(s, "group HydroScheme", "Kernel function")?,
        None => None,
    };
    Ok(SphConvention {
        code: SphCode::Swift,
        kernel,
    })
}
