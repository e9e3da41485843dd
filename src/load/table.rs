//! Reading particle arrays named by a scene, with errors that name the file
//! and what is wrong with it.

use std::path::{Path, PathBuf};

use voxless_io::{ParticleTable, read_npy};

use super::formats::{self, ParticleFormat, TableOptions};
use crate::SceneError;

/// Where the particle columns come from: one frame of a particle file.
pub struct Source {
    pub path: PathBuf,
    pub format: ParticleFormat,
    /// The frame's table; its positions have been moved out.
    pub table: ParticleTable,
}

impl Source {
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// What to read from a particle file besides its positions.
#[derive(Default)]
pub struct Selection<'a> {
    pub options: TableOptions,
    /// Keep only this `type` (`particles.species`); in a snapshot, the
    /// particle type (a material's species).
    pub species: Option<&'a str>,
    /// The snapshot particle type asked for (`particles.part_type`), as
    /// given: a number or a name.
    pub part_type: Option<&'a str>,
}

/// Whether `path` names a `.npy` file (by its extension, any case).
pub(crate) fn is_npy(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npy"))
}

/// Reads world positions (float64) from an N×3 `.npy`, a CSV with x, y, z
/// columns, or any other particle format (its first frame).
pub fn read_positions(path: &Path) -> Result<(Vec<[f64; 3]>, Source), SceneError> {
    let (p, s, _) = open(path, 0, &Selection::default())?;
    Ok((p, s))
}

/// World positions (float64), the rest of the table, and a note.
pub type Opened = (Vec<[f64; 3]>, Source, Option<String>);

/// Reads frame `frame` of the particle file at `path` in whichever format it
/// is (see [`formats`]); returns the world positions (float64), the rest of
/// the table, and a note on what part of the file was read, if worth one.
pub fn open(path: &Path, frame: usize, select: &Selection) -> Result<Opened, SceneError> {
    let format = ParticleFormat::detect(path)?.unwrap_or(ParticleFormat::Csv);
    let mut options = select.options.clone();
    let mut species = select.species;
    // A snapshot's types are its species.
    if format.is_snapshot() && select.part_type.is_none() {
        options.part_type = species.take().map(|s| part_type_of(s, path)).transpose()?;
    } else if let Some(t) = select.part_type {
        options.part_type = Some(if format.is_snapshot() {
            part_type_of(t, path)?
        } else {
            0 // the reader says part_type does not apply
        });
    }
    let formats::Table { mut table, note } = formats::read_table(path, format, frame, &options)?;
    if let Some(species) = species {
        formats::keep_species(&mut table, species, path, format, frame)?;
    }
    // An empty share of a file holding particles is not an error (a rank
    // past the last row, a stream's look at the header).
    let holds_some = table.rows.is_some_and(|(_, total)| total > 0);
    if table.is_empty() && !holds_some {
        if let Some(r) = &options.region {
            let box_text = match table.domain {
                Some((lo, hi)) => format!(" (the snapshot's box is {lo:?} to {hi:?})"),
                None => String::new(),
            };
            return Err(SceneError::data(
                path,
                format!(
                    "particles.region (--region) {:?} to {:?}: no particle of the snapshot \
                     can reach it{box_text}",
                    r.lo, r.hi
                ),
            ));
        }
        let what = match format {
            ParticleFormat::Npy => "the array has 0 rows",
            ParticleFormat::Csv => "the table has no rows",
            _ => "the file holds none",
        };
        return Err(SceneError::data(path, format!("no particles ({what})")));
    }
    let positions = std::mem::take(&mut table.positions);
    let source = Source {
        path: path.to_path_buf(),
        format,
        table,
    };
    Ok((positions, source, note))
}

/// The particle type `s` names (`0`–`6`, `gas`, `dm`, …), or an error
/// naming the file.
fn part_type_of(s: &str, path: &Path) -> Result<u32, SceneError> {
    if s.contains(',') {
        return Err(SceneError::data(
            path,
            format!(
                "particles.part_type '{s}': several types are read as materials \
                 ([[particles.materials]] species = \"gas\", …), one type at a time here"
            ),
        ));
    }
    voxless_io::part_type_named(s).ok_or_else(|| {
        SceneError::data(
            path,
            format!(
                "unknown particle type '{s}' (particles.part_type, --part-type): give 0–6 or \
                 one of {}",
                voxless_io::snapshot::PART_TYPE_NAMES.join(", ")
            ),
        )
    })
}

/// Reads a per-particle array: a column of the particle table when `spec`
/// names one (case-insensitively), else a `.npy` file (N or N×1 values).
pub fn read_per_particle(
    spec: &str,
    base: &Path,
    source: &Source,
    n: usize,
    what: &str,
) -> Result<(Vec<f32>, PathBuf), SceneError> {
    if let Some(c) = source.table.column(spec) {
        return Ok((c.to_vec(), source.path.clone()));
    }
    let path = base.join(spec);
    if !is_npy(&path) {
        if !source.table.columns.is_empty() && !path.exists() {
            return Err(SceneError::data(
                &source.path,
                format!(
                    "no column '{spec}' for the {what} (columns: {}); give a column name or \
                     a .npy file with one value per particle",
                    formats::column_list(&source.table)
                ),
            ));
        }
        let hint = if source.table.columns.is_empty() {
            String::new()
        } else {
            format!(
                " or a column of the particle table ({})",
                formats::column_list(&source.table)
            )
        };
        return Err(SceneError::data(
            &path,
            format!("{what} must be a .npy file with one value per particle{hint}"),
        ));
    }
    let a = read_npy(&path)?;
    let ok_shape = matches!(a.shape.as_slice(), [_] | [_, 1]);
    if !ok_shape {
        return Err(SceneError::data(
            &path,
            format!(
                "{what}: expected {n} values (shape (N,)), found shape {:?}",
                a.shape
            ),
        ));
    }
    if a.data.len() != n {
        return Err(SceneError::data(
            &path,
            format!(
                "{what} has {} values but {} has {n} particles",
                a.data.len(),
                source.path().display()
            ),
        ));
    }
    Ok((a.data.iter().map(|&v| v as f32).collect(), path))
}
