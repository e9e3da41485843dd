//! The per-particle columns a scene's particle file offers: what a front-end
//! lists as choices for `particles.attribute` (the colour field), so a user
//! picks `temperature` or `speed` by name instead of typing a path.

use std::path::Path;

use voxless_scene::SceneDesc;

use crate::SceneError;
use crate::load::{formats, frames};

/// The column names of the scene's particle file (its first frame; the
/// first file of a sequence), in the file's order. Empty for formats
/// without columns (`.npy`), for the built-in demo, and for scenes that are
/// not particles.
pub fn particle_columns(desc: &SceneDesc, base: &Path) -> Result<Vec<String>, SceneError> {
    let Some(p) = &desc.particles else {
        return Ok(Vec::new());
    };
    let Some(spec) = &p.file else {
        return Ok(Vec::new());
    };
    let Some(path) = frames::expand(spec, base)?.into_iter().next() else {
        return Ok(Vec::new());
    };
    // A bare array has no columns: not worth reading.
    if let None | Some(formats::ParticleFormat::Npy) =
        formats::ParticleFormat::detect(&path).map_err(SceneError::from)?
    {
        return Ok(Vec::new());
    }
    let select = crate::load::particles::selection(p, None);
    let (_, source, _) = crate::load::table::open(&path, 0, &select)?;
    Ok(source
        .table
        .column_names()
        .into_iter()
        .map(String::from)
        .collect())
}
