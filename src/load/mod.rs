//! Loading: files named by a scene description become a volume. Every
//! reader's failure is a [`SceneError`] naming the file; the data's own
//! defaults (a particle radius from the spacing, SPH kernels for SPH files)
//! are filled here and said in the notes. Defaults of the view (camera,
//! transfer function, settings) are not: [`crate::resolve`] fills those, for
//! loaded and in-memory volumes alike.

mod amr;
pub mod formats;
pub mod frames;
pub(crate) mod jaxpm;
pub(crate) mod materials;
pub(crate) mod particles;
pub(crate) mod scale;
pub(crate) mod spacing;
mod sph;
pub(crate) mod table;
pub(crate) mod tets;

use std::path::Path;

use voxless_io::IoError;
use voxless_scene::SceneDesc;

pub use amr::AmrArrays;
pub(crate) use amr::{amr_settings, build_amr, cells_reach};
pub use particles::{SUPPORT_PER_SPACING, default_radius, frame_count, frame_numbers};
pub(crate) use particles::{positive, range};

use crate::{AnyVolume, SceneError, WorldFrame};

/// A loaded volume, the world frame its coordinates are relative to, and
/// what was worth saying about loading it.
pub struct Loaded {
    pub volume: AnyVolume,
    pub frame: WorldFrame,
    pub notes: Vec<String>,
}

/// Loads the data `desc` names (paths relative to `base`) at frame `frame`
/// of a time series (0 for single frames), in the frame the placement
/// policy picks for it (see [`WorldFrame::fit`]).
pub fn load(desc: &SceneDesc, base: &Path, frame: usize) -> Result<Loaded, SceneError> {
    load_in(desc, base, frame, None)
}

/// [`load`] in a given world frame (`None`: the one the policy picks) —
/// how every frame of a time series lands in the frame of the first.
pub fn load_in(
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
    world: Option<&WorldFrame>,
) -> Result<Loaded, SceneError> {
    let mut notes = Vec::new();
    let sources = [
        desc.particles.is_some(),
        desc.amr.is_some(),
        desc.tets.is_some(),
    ];
    if sources.iter().filter(|&&s| s).count() > 1 {
        return Err(SceneError::setting(
            "scene",
            "more than one data source ([particles], [amr], [tets]) is given; pick one",
        ));
    }
    // `--particles run.h5` of a JaxPM run: its tessellation.
    let jaxpm = match &desc.particles {
        Some(p) => jaxpm::as_tessellation(p, base)?,
        None => None,
    };
    let particles = if jaxpm.is_some() {
        None
    } else {
        desc.particles.as_ref()
    };
    let tets = desc.tets.as_ref().or(jaxpm.as_ref());
    let (volume, world) = match (particles, &desc.amr, tets) {
        (Some(p), _, _) if p.materials.is_some() => {
            let mats = p.materials.as_deref().unwrap_or_default();
            let (v, f) = materials::load_materials(p, mats, base, &mut notes, frame, world)?;
            (AnyVolume::Materials(Box::new(v)), f)
        }
        (Some(p), _, _) => {
            let (v, f) = particles::load_particles(p, base, &mut notes, frame, world)?;
            (AnyVolume::Particles(Box::new(v)), f)
        }
        (_, Some(a), _) => {
            let (v, f) = amr::load_amr(a, base)?;
            (AnyVolume::Amr(Box::new(v)), f)
        }
        (_, _, Some(t)) => {
            let (v, f) = tets::load_tets(t, base, &mut notes)?;
            (AnyVolume::Tets(Box::new(v)), f)
        }
        (None, None, None) => {
            return Err(SceneError::setting(
                "scene",
                "no data source: add a [particles], [amr] or [tets] table to the scene, or pass --particles FILE (with --lagrangian N --box L for a phase-space tessellation), --cells FILE --scalars FILE, or --amrclaw FILE (or use `voxless demo`)",
            ));
        }
    };
    Ok(Loaded {
        volume,
        frame: world,
        notes,
    })
}

/// Query points for `sample`, in world coordinates (float64): an N×3
/// `.npy` (float32/float64) or a CSV with x, y, z columns; non-finite
/// coordinates are an error naming the point.
pub fn read_points(path: &Path) -> Result<Vec<[f64; 3]>, SceneError> {
    let (points, _) = table::read_positions(path)?;
    if let Some(i) = points.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        return Err(SceneError::data(
            path,
            format!("point {i} has a non-finite coordinate"),
        ));
    }
    Ok(points)
}

/// Reads a TOML scene file (unknown keys are errors, so typos surface).
pub fn read_scene(path: &Path) -> Result<SceneDesc, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|source| IoError::Io {
        path: path.into(),
        source,
    })?;
    parse_scene(&text).map_err(|message| SceneError::Toml {
        path: path.into(),
        message,
    })
}

/// Parses a scene from TOML text (unknown keys are errors).
pub fn parse_scene(text: &str) -> Result<SceneDesc, String> {
    toml::from_str(text).map_err(|e| e.to_string())
}
