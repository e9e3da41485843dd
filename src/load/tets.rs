//! Phase-space tessellations: N³ positions in Lagrangian order from a
//! `.npy` (or any particle file), a JaxPM `.h5` run, or memory.

use std::path::Path;

use voxless_core::Vec3;
use voxless_scene::TetsDesc;
use voxless_tets::{LagrangianGrid, TetSettings, TetVolume};

use super::formats::ParticleFormat;
use super::particles::positive;
use crate::SceneError;

pub(crate) fn load_tets(
    t: &TetsDesc,
    base: &Path,
    notes: &mut Vec<String>,
) -> Result<TetVolume, SceneError> {
    let file = t.file.as_ref().ok_or_else(|| {
        SceneError::setting(
            "tets.file",
            "no positions file given (--particles FILE.npy with --lagrangian N --box L, or a \
             JaxPM FILE.h5)",
        )
    })?;
    let path = base.join(file);
    let grid = if ParticleFormat::detect(&path)? == Some(ParticleFormat::Hdf5) {
        super::jaxpm::grid(t, &path, notes)?
    } else {
        if t.snapshot.is_some() {
            return Err(SceneError::setting(
                "tets.snapshot",
                format!(
                    "--snapshot picks a snapshot of a JaxPM .h5 run, but {} is not one",
                    path.display()
                ),
            ));
        }
        let (positions, _) = super::table::read_positions(&path)?;
        grid_of(positions, t)?
    };
    build_tets(&grid, t, &path)
}

/// The Lagrangian grid of `positions` with the description's N and L.
pub(crate) fn grid_of(positions: Vec<Vec3>, t: &TetsDesc) -> Result<LagrangianGrid, SceneError> {
    let n = t.lagrangian.ok_or_else(|| {
        SceneError::setting(
            "tets.lagrangian",
            "the Lagrangian grid size N is needed (--lagrangian N)",
        )
    })?;
    let box_size = t.box_size.ok_or_else(|| {
        SceneError::setting("tets.box_size", "the periodic box size is needed (--box L)")
    })?;
    Ok(LagrangianGrid {
        n,
        box_size,
        positions,
    })
}

/// A tessellation of `grid` with the description's mass and level of
/// detail; errors name `source`.
pub(crate) fn build_tets(
    grid: &LagrangianGrid,
    t: &TetsDesc,
    source: &Path,
) -> Result<TetVolume, SceneError> {
    let settings = TetSettings {
        particle_mass: t.particle_mass,
        ..Default::default()
    };
    if let Some(p) = t.lod_pixels {
        positive("tets.lod_pixels", p)?;
    }
    let levels = if t.lod_pixels.is_some() { 3 } else { 0 };
    let v = TetVolume::new(grid, &settings, levels).map_err(|e| SceneError::Tets {
        path: source.to_path_buf(),
        source: e,
    })?;
    Ok(v.with_lod_pixels(t.lod_pixels))
}
