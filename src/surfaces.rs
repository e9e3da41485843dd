//! Surfaces beside the volume: the scene's triangle meshes (`[[meshes]]`,
//! `--mesh`), ambient occlusion (`--ao`) and mirror instances
//! (`[[instances]]`, `--mirror`), resolved into the render settings every
//! front-end uses.
//!
//! Meshes are in the data's world coordinates and are moved into the
//! volume's local frame (see [`WorldFrame`]) like every other position, so
//! they line up with the data at any units or offset. A mesh's colour is
//! sRGB (default light grey); a per-vertex field is colour-mapped over its
//! own range unless one is given.

use std::path::Path;

use voxless_core::{Aabb, Mirror, srgb_to_linear};
use voxless_render::{AmbientOcclusion, Mesh, Paint, RenderSettings, Surfaces};
use voxless_scene::{AxisName, InstanceDesc, MeshDesc, SceneDesc};
use voxless_transfer::Colormap;

use crate::{SceneError, WorldFrame};

/// The default colour of a mesh without one (sRGB).
const GREY: [f32; 3] = [0.8, 0.8, 0.8];

/// `--mesh FILE` (relative to `cwd`) and `--mirror AXIS[=AT]` over `d`.
pub(crate) fn apply_flags(
    meshes: &[std::path::PathBuf],
    mirrors: &[String],
    d: &mut SceneDesc,
    cwd: &Path,
) -> Result<(), SceneError> {
    for m in meshes {
        d.meshes.push(MeshDesc {
            file: cwd.join(m).to_string_lossy().into_owned(),
            ..MeshDesc::default()
        });
    }
    for m in mirrors {
        d.instances.push(parse_mirror(m)?);
    }
    Ok(())
}

/// `x`, `y`, `z` or `AXIS=VALUE`.
fn parse_mirror(s: &str) -> Result<InstanceDesc, SceneError> {
    let bad = || {
        SceneError::setting(
            "mirror",
            format!("'{s}' is not x, y, z or AXIS=VALUE (e.g. x=0.5)"),
        )
    };
    let (axis, at) = match s.split_once('=') {
        Some((a, v)) => (a, Some(v.trim().parse::<f64>().map_err(|_| bad())?)),
        None => (s, None),
    };
    let mirror = match axis.trim().to_ascii_lowercase().as_str() {
        "x" => AxisName::X,
        "y" => AxisName::Y,
        "z" => AxisName::Z,
        _ => return Err(bad()),
    };
    if at.is_some_and(|v| !v.is_finite()) {
        return Err(bad());
    }
    Ok(InstanceDesc { mirror, at })
}

/// Loads the scene's meshes into `settings.surfaces`, sets ambient
/// occlusion and the mirror instances. `bounds` are the data's (local).
pub(crate) fn resolve(
    desc: &SceneDesc,
    base: &Path,
    frame: &WorldFrame,
    bounds: &Aabb,
    settings: &mut RenderSettings,
    notes: &mut Vec<String>,
) -> Result<(), SceneError> {
    settings.mirrors = mirrors(&desc.instances, frame, bounds)?;
    if !desc.meshes.is_empty() {
        let surfaces = cached_surfaces(&desc.meshes, base, frame)?;
        notes.push(format!(
            "{} mesh{} with {} triangles drawn with the volume",
            desc.meshes.len(),
            if desc.meshes.len() == 1 { "" } else { "es" },
            surfaces.triangle_count()
        ));
        settings.surfaces = Some(surfaces);
    }
    let r = &desc.render;
    if r.ao_distance.is_some() && r.ao.is_none() {
        return Err(SceneError::setting(
            "render.ao_distance (--ao-distance)",
            "applies to ambient occlusion: add --ao N (scene: render.ao)",
        ));
    }
    if let Some(rays) = r.ao {
        if rays == 0 {
            return Err(SceneError::setting(
                "render.ao (--ao)",
                "give at least 1 ray per hit (or leave ambient occlusion out)",
            ));
        }
        // Each ray is a march through the volume from every hit of every
        // sample: beyond this a pixel takes seconds and the picture does not
        // change (the noise of n rays falls as 1/√n; more samples per pixel
        // average it too).
        if rays > MAX_AO_RAYS {
            return Err(SceneError::setting(
                "render.ao (--ao)",
                format!(
                    "{rays} rays per hit: at most {MAX_AO_RAYS} (for less noise, add samples \
                     per pixel with --spp)"
                ),
            ));
        }
        if settings.surfaces.is_none() && settings.iso.is_empty() {
            return Err(SceneError::setting(
                "render.ao (--ao)",
                "ambient occlusion shades mesh and iso-surface hits: add a mesh (--mesh) or \
                 an iso-surface (--iso)",
            ));
        }
        let distance = match r.ao_distance {
            Some(d) if d.is_finite() && d > 0.0 => frame.length_to_local(d),
            Some(d) => {
                return Err(SceneError::setting(
                    "render.ao_distance (--ao-distance)",
                    format!("{d} is not a positive length"),
                ));
            }
            None => 0.1 * bounds.diagonal(),
        };
        settings.ao = Some(AmbientOcclusion { rays, distance });
    }
    Ok(())
}

/// Ambient-occlusion rays per hit at most (`render.ao`).
pub const MAX_AO_RAYS: u32 = 4096;

/// What the last built surfaces were made from: the mesh entries, where
/// their paths start, the frame, and each file's modification time.
type SurfaceKey = (
    Vec<MeshDesc>,
    std::path::PathBuf,
    [f64; 4],
    Vec<Option<std::time::SystemTime>>,
);

/// The scene's meshes merged into [`Surfaces`], reused while nothing they
/// were built from changed: a viewer resolves the scene on every camera
/// move, and a million-triangle mesh takes a second to read and index.
fn cached_surfaces(
    meshes: &[MeshDesc],
    base: &Path,
    frame: &WorldFrame,
) -> Result<Surfaces, SceneError> {
    static LAST: std::sync::Mutex<Option<(SurfaceKey, Surfaces)>> = std::sync::Mutex::new(None);
    let o = frame.origin;
    let key: SurfaceKey = (
        meshes.to_vec(),
        base.to_path_buf(),
        [o[0], o[1], o[2], frame.scale],
        meshes
            .iter()
            .map(|m| {
                std::fs::metadata(base.join(&m.file))
                    .and_then(|md| md.modified())
                    .ok()
            })
            .collect(),
    );
    if let Ok(last) = LAST.lock()
        && let Some((k, s)) = last.as_ref()
        && *k == key
    {
        return Ok(s.clone());
    }
    let mut loaded = Vec::with_capacity(meshes.len());
    for m in meshes {
        loaded.push(load_mesh(m, base, frame)?);
    }
    let list: Vec<(&Mesh, &Paint)> = loaded.iter().map(|(m, p)| (m, p)).collect();
    let surfaces = Surfaces::new(&list)
        .map_err(|e| SceneError::setting("meshes", format!("cannot be drawn together: {e}")))?;
    if let Ok(mut last) = LAST.lock() {
        *last = Some((key, surfaces.clone()));
    }
    Ok(surfaces)
}

/// The mirror planes in local coordinates: one per axis at most.
fn mirrors(
    instances: &[InstanceDesc],
    frame: &WorldFrame,
    bounds: &Aabb,
) -> Result<Vec<Mirror>, SceneError> {
    let mut out: Vec<Mirror> = Vec::new();
    for i in instances {
        let axis = match i.mirror {
            AxisName::X => 0,
            AxisName::Y => 1,
            AxisName::Z => 2,
        };
        if out.iter().any(|m| m.axis == axis) {
            return Err(SceneError::setting(
                "instances (--mirror)",
                format!(
                    "two mirrors about the {} axis; give each axis once",
                    i.mirror.name()
                ),
            ));
        }
        let plane = match i.at {
            Some(at) if !at.is_finite() => {
                return Err(SceneError::setting(
                    "instances.at (--mirror AXIS=VALUE)",
                    format!(
                        "the {} mirror's plane is at {at}; it must be a finite coordinate",
                        i.mirror.name()
                    ),
                ));
            }
            Some(at) => {
                let mut p = frame.to_world(bounds.center());
                p[axis] = at;
                frame.to_local(p)[axis]
            }
            None => bounds.min[axis],
        };
        out.push(Mirror { axis, plane });
    }
    Ok(out)
}

/// One mesh, in local coordinates, with its paint.
fn load_mesh(m: &MeshDesc, base: &Path, frame: &WorldFrame) -> Result<(Mesh, Paint), SceneError> {
    let path = base.join(&m.file);
    let table = voxless_io::read_surface(&path)?;
    let positions = table
        .positions
        .iter()
        .map(|p| frame.to_local(*p).to_array())
        .collect();
    let mesh = Mesh {
        positions,
        triangles: table.triangles,
        fields: table.fields,
    };
    mesh.validate()
        .map_err(|e| SceneError::data(&path, e.to_string()))?;
    let paint = match &m.field {
        None => {
            let c = m.color.unwrap_or(GREY);
            if !c.iter().all(|v| (0.0..=1.0).contains(v)) {
                return Err(SceneError::setting(
                    "meshes.color",
                    format!("{c:?} is not an sRGB colour in [0, 1]"),
                ));
            }
            Paint::Solid(c.map(srgb_to_linear))
        }
        Some(name) => {
            let values = mesh.field(name).ok_or_else(|| {
                let have: Vec<&str> = mesh.fields.iter().map(|(n, _)| n.as_str()).collect();
                SceneError::data(
                    &path,
                    format!(
                        "no per-vertex field '{name}' (the mesh has {})",
                        if have.is_empty() {
                            "none".to_string()
                        } else {
                            have.join(", ")
                        }
                    ),
                )
            })?;
            let [lo, hi] = match m.range {
                Some(r) => r,
                None => {
                    let finite = values.iter().filter(|v| v.is_finite());
                    let lo = finite.clone().fold(f32::INFINITY, |a, &b| a.min(b));
                    let hi = finite.fold(f32::NEG_INFINITY, |a, &b| a.max(b));
                    [lo, hi]
                }
            };
            let cmap = Colormap::preset(m.colormap.as_deref().unwrap_or("viridis"))?;
            let span = (hi - lo).max(f32::MIN_POSITIVE);
            Paint::PerVertex(
                values
                    .iter()
                    .map(|&v| {
                        let x = if v.is_finite() {
                            ((v - lo) / span).clamp(0.0, 1.0)
                        } else {
                            0.0
                        };
                        cmap.linear(x).to_array()
                    })
                    .collect(),
            )
        }
    };
    Ok((mesh, paint))
}
