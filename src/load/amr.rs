//! AMR data: ExaBricks `.cells` + `.scalars` or AMRClaw `fort.q` output,
//! or cell arrays in memory, through one constructor.

use std::path::{Path, PathBuf};

use voxless_amr::{AmrCells, AmrSettings, AmrVolume, Reconstruction};
use voxless_core::Vec3;
use voxless_io::FieldPick;
use voxless_scene::{AmrDesc, ReconstructionName};

use super::{Purpose, Share};
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

pub(crate) fn load_amr(
    a: &AmrDesc,
    base: &Path,
    pick: FieldPick,
) -> Result<(AmrVolume, WorldFrame), SceneError> {
    let run = read_cells(a, base, Share::WHOLE, &pick)?;
    let arrays = AmrArrays {
        cells: run.data.cells,
        fields: run.data.fields,
        origin: run.data.origin,
        cell_size: run.data.finest_cell_size as f32,
    };
    build_amr(arrays, a, &run.source)
}

/// The fields a load for `purpose` decodes (see [`super::load_for`]).
pub(crate) fn field_pick(a: &AmrDesc, purpose: Purpose) -> FieldPick {
    match purpose {
        Purpose::Render => FieldPick::All,
        Purpose::Project => FieldPick::Named {
            names: a.field.iter().chain(&a.color_field).cloned().collect(),
            first: a.field.is_none(),
        },
    }
}

/// A run of cells a process read: the cells and their fields, the run's
/// first index and the file's cell count, and the file (errors name it).
pub(crate) struct CellRun {
    pub data: voxless_io::AmrCellData,
    pub offset: usize,
    pub total: usize,
    pub source: PathBuf,
}

/// Share `share` of the cells `a` names: ExaBricks cells by offset (whole,
/// with every check of the whole-file reader, for one process); AMRClaw
/// output is read whole and cut.
pub(crate) fn read_cells(
    a: &AmrDesc,
    base: &Path,
    share: Share,
    pick: &FieldPick,
) -> Result<CellRun, SceneError> {
    if let Some(file) = &a.file {
        if a.cells.is_some() || a.amrclaw.is_some() {
            return Err(SceneError::setting(
                "amr.file",
                "give one AMR source: file, cells (ExaBricks) or amrclaw",
            ));
        }
        let path = base.join(file);
        let (data, _) = voxless_io::read_amr_picked(&path, pick)?;
        return Ok(cut_run(data, share, path));
    }
    match (&a.cells, &a.amrclaw) {
        (Some(cells), None) => {
            let scalars: Vec<PathBuf> = a.scalars.iter().flatten().map(|s| base.join(s)).collect();
            if scalars.is_empty() {
                return Err(SceneError::setting(
                    "amr.scalars",
                    "ExaBricks cells need at least one .scalars file (--scalars FILE)",
                ));
            }
            let path = base.join(cells);
            if share.is_whole() {
                let data = voxless_io::read_exabricks(&path, &scalars)?;
                let total = data.cells.len();
                return Ok(CellRun {
                    data,
                    offset: 0,
                    total,
                    source: path,
                });
            }
            let len = std::fs::metadata(&path)
                .map_err(|source| voxless_io::IoError::Io {
                    path: path.clone(),
                    source,
                })?
                .len();
            let rows = share.rows((len / 16) as usize);
            let (data, total) = voxless_io::read_exabricks_rows(&path, &scalars, rows.clone())?;
            Ok(CellRun {
                data,
                offset: rows.start,
                total,
                source: path,
            })
        }
        (None, Some(q)) => {
            let path = base.join(q);
            let data = voxless_io::read_amrclaw_picked(&path, pick)?;
            Ok(cut_run(data, share, path))
        }
        (Some(_), Some(_)) => Err(SceneError::setting(
            "amr",
            "give either cells (ExaBricks) or amrclaw, not both",
        )),
        (None, None) => Err(SceneError::setting(
            "amr",
            "no cells: give file (any AMR output), cells + scalars (ExaBricks) or amrclaw \
             (fort.qNNNN)",
        )),
    }
}

/// Share `share` of cells read whole (formats without row access).
fn cut_run(mut data: voxless_io::AmrCellData, share: Share, source: PathBuf) -> CellRun {
    let total = data.cells.len();
    let rows = share.rows(total);
    if !share.is_whole() {
        data.cells = data.cells[rows.clone()].to_vec();
        for f in &mut data.fields {
            f.1 = f.1[rows.clone()].to_vec();
        }
    }
    CellRun {
        data,
        offset: rows.start,
        total,
        source,
    }
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
    let reach = cells_reach(&data.cells);
    let (settings, frame, cell_size) =
        amr_settings(&names, data.origin, data.cell_size, reach, a, source)?;
    let cells = AmrCells {
        cells: data.cells,
        fields: data.fields,
        origin: Vec3::ZERO,
        cell_size,
    };
    AmrVolume::new(cells, settings)
        .map(|v| (v, frame))
        .map_err(|source_err| SceneError::Amr {
            path: source.to_path_buf(),
            source: source_err,
        })
}

/// How far the cells reach from cell coordinate 0, in finest cells (what
/// the frame's scale follows; a decomposed volume takes the maximum over
/// its parts).
pub(crate) fn cells_reach(cells: &[[i32; 4]]) -> f64 {
    use rayon::prelude::*;
    cells
        .par_iter()
        .map(|c| {
            let w = 1i64 << c[3].clamp(0, 62);
            [c[0], c[1], c[2]]
                .map(|v| {
                    (v as i64)
                        .saturating_add(w)
                        .unsigned_abs()
                        .max((v as i64).unsigned_abs())
                })
                .into_iter()
                .max()
                .unwrap_or(0)
        })
        .max()
        .unwrap_or(0) as f64
}

/// The AMR settings `a` describes for cells with fields `names` (the
/// opacity and colour fields, the reconstruction), the world frame (cell
/// coordinate 0 at the arrays' or the description's origin; its scale from
/// the cells' `reach`, see [`cells_reach`]) and the finest cell width in
/// the frame's units; errors name `source`.
pub(crate) fn amr_settings(
    names: &[&str],
    origin: [f64; 3],
    data_cell_size: f32,
    reach: f64,
    a: &AmrDesc,
    source: &Path,
) -> Result<(AmrSettings, WorldFrame, f32), SceneError> {
    let index = |what: &str, name: &str| {
        voxless_io::amr_field(names, name).ok_or_else(|| {
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
        ReconstructionName::Octant => Reconstruction::Octant,
    };
    let cell_size = a.cell_size.unwrap_or(data_cell_size);
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
    let extent = reach * cell_size as f64;
    let scale = WorldFrame::fit([0.0; 3], [extent; 3]).scale;
    let frame = WorldFrame {
        origin: a.origin.unwrap_or(origin),
        scale,
    };
    let settings = AmrSettings {
        field,
        color_field,
        reconstruction,
    };
    Ok((settings, frame, (cell_size as f64 / scale) as f32))
}
