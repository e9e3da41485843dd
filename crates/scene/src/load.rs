//! Reading particle arrays named by a scene, with errors that name the file
//! and what is wrong with it.

use std::path::{Path, PathBuf};

use voxless_core::Vec3;
use voxless_io::{CsvTable, read_csv, read_npy};

use crate::SceneError;

/// Where the particle columns come from.
pub enum Source {
    Npy(PathBuf),
    Csv(PathBuf, CsvTable),
}

impl Source {
    pub fn path(&self) -> &Path {
        match self {
            Source::Npy(p) | Source::Csv(p, _) => p,
        }
    }
}

fn is_npy(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npy"))
}

/// Reads positions from an N×3 `.npy` or a CSV with x, y, z columns.
pub fn read_positions(path: &Path) -> Result<(Vec<Vec3>, Source), SceneError> {
    if is_npy(path) {
        let a = read_npy(path)?;
        if a.shape.len() != 2 || a.shape[1] != 3 {
            return Err(SceneError::data(
                path,
                format!(
                    "expected an N×3 array of positions, found shape ({})",
                    a.shape
                        .iter()
                        .map(|s| s.to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
        if a.shape[0] == 0 {
            return Err(SceneError::data(
                path,
                "no particles (the array has 0 rows)",
            ));
        }
        let p = a
            .data
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32))
            .collect();
        Ok((p, Source::Npy(path.to_path_buf())))
    } else {
        let t = read_csv(path)?;
        let col = |name: &str| {
            t.column(name).ok_or_else(|| {
                SceneError::data(
                    path,
                    format!("no column '{name}' (columns: {})", t.columns.join(", ")),
                )
            })
        };
        let (x, y, z) = (col("x")?, col("y")?, col("z")?);
        if t.rows() == 0 {
            return Err(SceneError::data(
                path,
                "no particles (the table has no rows)",
            ));
        }
        let p = (0..t.rows())
            .map(|i| Vec3::new(x[i] as f32, y[i] as f32, z[i] as f32))
            .collect();
        Ok((p, Source::Csv(path.to_path_buf(), t)))
    }
}

/// Reads a per-particle array: a CSV column of the particle table when
/// `spec` names one, else a `.npy` file (N or N×1 values).
pub fn read_per_particle(
    spec: &str,
    base: &Path,
    source: &Source,
    n: usize,
    what: &str,
) -> Result<(Vec<f32>, PathBuf), SceneError> {
    if let Source::Csv(path, table) = source
        && let Some(c) = table.column(spec)
    {
        return Ok((c.iter().map(|&v| v as f32).collect(), path.clone()));
    }
    let path = base.join(spec);
    if !is_npy(&path) {
        let hint = match source {
            Source::Csv(_, t) => format!(
                " or a column of the particle table ({})",
                t.columns.join(", ")
            ),
            Source::Npy(_) => String::new(),
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
