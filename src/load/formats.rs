//! Particle file formats: a thin layer over [`voxless_io::format`], which
//! detects formats (by name, then by content), counts frames and reads one
//! frame of any of them as a [`ParticleTable`]. This module keeps the names
//! the rest of the scene crate and the CLI use, turns the reader errors into
//! [`SceneError`]s, and adds the species selection.

use std::path::Path;

use voxless_io::ParticleTable;
pub use voxless_io::format::{ParticleFormat, SUPPORTED, Table, TableOptions};

use crate::SceneError;

/// Frames in one file of `format` (1 for single-frame formats).
pub fn frames_in(path: &Path, format: ParticleFormat) -> Result<usize, SceneError> {
    Ok(voxless_io::format::frames_in(path, format)?)
}

/// Reads frame `frame` of `path` (in `format`) as a table. Single-frame
/// formats ignore `frame`. `group` and `part_type` are errors for formats
/// they do not apply to, so a typo does not pass silently.
pub fn read_table(
    path: &Path,
    format: ParticleFormat,
    frame: usize,
    opts: &TableOptions,
) -> Result<Table, SceneError> {
    Ok(voxless_io::format::read_table(path, format, frame, opts)?)
}

/// Keeps the rows whose `type` column equals `species`: a number, or for an
/// XYZ file also an element symbol (`frame` is the frame the table is of).
pub fn keep_species(
    table: &mut ParticleTable,
    species: &str,
    path: &Path,
    format: ParticleFormat,
    frame: usize,
) -> Result<(), SceneError> {
    let Some(types) = table.column("type") else {
        return Err(SceneError::data(
            path,
            format!(
                "particles.species (--species) needs a 'type' column, and this {} has none \
                 (columns: {})",
                format.name(),
                column_list(table)
            ),
        ));
    };
    let present = distinct(types);
    let wanted: f32 = match species.trim().parse::<f32>() {
        Ok(v) => v,
        Err(_) if format == ParticleFormat::Xyz => {
            let symbols = voxless_io::xyz_species(path, frame)?;
            match symbols.iter().position(|s| s == species.trim()) {
                Some(i) => (i + 1) as f32,
                None => {
                    return Err(SceneError::data(
                        path,
                        format!(
                            "no species '{species}' in frame {frame} (species: {})",
                            symbols.join(", ")
                        ),
                    ));
                }
            }
        }
        Err(_) => {
            return Err(SceneError::data(
                path,
                format!(
                    "particles.species: '{species}' is not a type number (types present: {present})"
                ),
            ));
        }
    };
    let keep: Vec<bool> = types.iter().map(|&t| t == wanted).collect();
    if !keep.iter().any(|&k| k) {
        return Err(SceneError::data(
            path,
            format!("no particle of type {species} (types present: {present})"),
        ));
    }
    let mut it = keep.iter();
    table.positions.retain(|_| *it.next().unwrap_or(&false));
    for (_, c) in &mut table.columns {
        let mut it = keep.iter();
        c.retain(|_| *it.next().unwrap_or(&false));
    }
    Ok(())
}

/// The distinct values of a type column, sorted, as text ("1, 2, 3").
fn distinct(values: &[f32]) -> String {
    let mut v: Vec<f32> = values.to_vec();
    v.sort_by(f32::total_cmp);
    v.dedup();
    let shown: Vec<String> = v.iter().take(20).map(|t| t.to_string()).collect();
    let more = if v.len() > 20 { ", …" } else { "" };
    format!("{}{more}", shown.join(", "))
}

/// The table's column names for messages, or "none".
pub fn column_list(table: &ParticleTable) -> String {
    if table.columns.is_empty() {
        "none".into()
    } else {
        table.column_names().join(", ")
    }
}

/// Without the `hdf5` feature every HDF5 file is an error that says how to
/// build with it.
#[cfg(not(feature = "hdf5"))]
pub mod hdf5 {
    use std::path::Path;

    use crate::SceneError;

    /// The error for an HDF5 file in a build without HDF5 support.
    pub fn unsupported(path: &Path) -> SceneError {
        voxless_io::format::hdf5_unsupported(path).into()
    }
}
