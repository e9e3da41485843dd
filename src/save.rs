//! Saving a view as a scene file: what a viewer's "save scene" writes, so
//! `voxless render saved.toml` draws the view again, wherever the file is
//! saved.
//!
//! Paths in a description are relative to the scene file's directory
//! (`base`). A saved file may land anywhere (a browser's downloads
//! folder), so [`with_absolute_paths`] anchors every path at `base` first.
//! A per-particle spec without an extension names a column of the particle
//! file, not a file, and is left alone (as the command line does).

use std::path::Path;

use voxless_scene::SceneDesc;

use crate::SceneError;

/// `desc` with every data and colormap path made absolute against `base`.
pub fn with_absolute_paths(desc: &SceneDesc, base: &Path) -> SceneDesc {
    let abs = |s: &mut String| {
        let p = Path::new(s.as_str());
        if !p.is_absolute() {
            *s = std::path::absolute(base.join(p))
                .unwrap_or_else(|_| base.join(p))
                .to_string_lossy()
                .into_owned();
        }
    };
    // Column names (no extension) stay; files become absolute.
    let file_or_column = |s: &mut String| {
        if Path::new(s.as_str()).extension().is_some() {
            abs(s);
        }
    };
    let mut d = desc.clone();
    if let Some(p) = &mut d.particles {
        p.file.iter_mut().for_each(abs);
        p.attribute.iter_mut().for_each(file_or_column);
        p.radii.iter_mut().for_each(file_or_column);
        p.weights.iter_mut().for_each(file_or_column);
    }
    if let Some(a) = &mut d.amr {
        a.cells.iter_mut().for_each(abs);
        a.amrclaw.iter_mut().for_each(abs);
        a.file.iter_mut().for_each(abs);
        a.scalars.iter_mut().flatten().for_each(abs);
    }
    if let Some(t) = &mut d.tets {
        t.file.iter_mut().for_each(abs);
    }
    for m in &mut d.meshes {
        abs(&mut m.file);
    }
    d.transfer.colormap_file.iter_mut().for_each(abs);
    d
}

/// The TOML text of `desc` (what [`crate::read_scene`] reads back to an
/// equal description: every number is written with enough digits to parse
/// back to the same `f32`).
pub fn scene_toml(desc: &SceneDesc) -> Result<String, SceneError> {
    toml::to_string(desc).map_err(|e| SceneError::setting("scene", e.to_string()))
}
