//! AMR data: ExaBricks `.cells` + `.scalars` or AMRClaw `fort.q` output,
//! or cell arrays in memory, through one constructor.

use std::path::{Path, PathBuf};

use voxless_amr::{AmrCells, AmrSettings, AmrVolume, Reconstruction};
use voxless_core::Vec3;
use voxless_scene::{AmrDesc, ReconstructionName};

use crate::{SceneError, WorldFrame};

/// Leaf cells in memory: `(x, y, z, level)` per cell (lower corner in
/// finest-cell units, width `2^level`, level 0 finest), one value per cell
/// per named field, the world position of cell coordinate 0 and the world
/// width of a finest cell.
#[derive(Clone, Debug, Default)]
pub struct AmrArrays {
    pub cells: Vec<[i32; 4]>,
    pub fields: Vec<(String, Vec<f32>)>,
    /// World position of cell coordinate 0 (float64: the volume works
    /// relative to it, so an origin far from zero loses no digits).
    pub origin: [f64; 3],
    pub cell_size: f32,
}

pub(crate) fn load_amr(a: &AmrDesc, base: &Path) -> Result<(AmrVolume, WorldFrame), SceneError> {
    let (data, path) = match (&a.cells, &a.amrclaw) {
        (Some(cells), None) => {
            let scalars: Vec<PathBuf> = a.scalars.iter().flatten().map(|s| base.join(s)).collect();
            if scalars.is_empty() {
                return Err(SceneError::setting(
                    "amr.scalars",
                    "ExaBricks cells need at least one .scalars file (--scalars FILE)",
                ));
            }
            let path = base.join(cells);
            (voxless_io::read_exabricks(&path, &scalars)?, path)
        }
        (None, Some(q)) => {
            let path = base.join(q);
            (voxless_io::read_amrclaw(&path)?, path)
        }
        (Some(_), Some(_)) => {
            return Err(SceneError::setting(
                "amr",
                "give either cells (ExaBricks) or amrclaw, not both",
            ));
        }
        (None, None) => {
            return Err(SceneError::setting(
                "amr",
                "no cells: give cells + scalars (ExaBricks) or amrclaw (fort.qNNNN)",
            ));
        }
    };
    let arrays = AmrArrays {
        cells: data.cells,
        fields: data.fields,
        origin: data.origin,
        cell_size: data.finest_cell_size as f32,
    };
    build_amr(arrays, a, &path)
}

/// An AMR volume from cell arrays, with the description's field choices,
/// reconstruction and geometry overrides, and the world frame it sits in
/// (cell coordinate 0 at the world origin the arrays or the description
/// give); errors name `source`.
pub(crate) fn build_amr(
    data: AmrArrays,
    a: &AmrDesc,
    source: &Path,
) -> Result<(AmrVolume, WorldFrame), SceneError> {
    let names: Vec<&str> = data.fields.iter().map(|f| f.0.as_str()).collect();
    let index = |what: &str, name: &str| {
        names.iter().position(|n| *n == name).ok_or_else(|| {
            SceneError::data(
                source,
                format!(
                    "no field '{name}' for {what} (fields: {})",
                    names.join(", ")
                ),
            )
        })
    };
    let field = a
        .field
        .as_deref()
        .map(|n| index("the opacity field", n))
        .transpose()?
        .unwrap_or(0);
    let color_field = a
        .color_field
        .as_deref()
        .map(|n| index("the colour field", n))
        .transpose()?;
    let reconstruction = match a.reconstruction.unwrap_or(ReconstructionName::Basis) {
        ReconstructionName::Basis => Reconstruction::Basis,
        ReconstructionName::Nearest => Reconstruction::Nearest,
    };
    let cell_size = a.cell_size.unwrap_or(data.cell_size);
    if !(cell_size.is_finite() && cell_size > 0.0) {
        return Err(SceneError::setting(
            "amr.cell_size (--cell-size)",
            format!("{cell_size} must be finite and > 0"),
        ));
    }
    if let Some(o) = a.origin
        && !o.iter().all(|v| v.is_finite())
    {
        return Err(SceneError::setting(
            "amr.origin (--origin)",
            format!("{o:?} must be finite"),
        ));
    }
    // The frame's scale from the data's extent (cell coordinate 0 at the
    // origin): cells of 10⁻²⁰ or 10²⁰ world units compute in a local unit
    // about the data's size. Field values have no length unit and stay.
    let reach = data
        .cells
        .iter()
        .map(|c| {
            let w = 2f64.powi(c[3].clamp(0, 62));
            [c[0], c[1], c[2]].map(|v| (v as f64 + w).abs().max((v as f64).abs()))
        })
        .fold(0.0f64, |m, c| m.max(c[0]).max(c[1]).max(c[2]));
    let extent = reach * cell_size as f64;
    let scale = WorldFrame::fit([0.0; 3], [extent; 3]).scale;
    let frame = WorldFrame {
        origin: a.origin.unwrap_or(data.origin),
        scale,
    };
    let cells = AmrCells {
        cells: data.cells,
        fields: data.fields,
        origin: Vec3::ZERO,
        cell_size: (cell_size as f64 / scale) as f32,
    };
    AmrVolume::new(
        cells,
        AmrSettings {
            field,
            color_field,
            reconstruction,
        },
    )
    .map(|v| (v, frame))
    .map_err(|source_err| SceneError::Amr {
        path: source.to_path_buf(),
        source: source_err,
    })
}
