//! Multi-material particle scenes: `[[particles.materials]]` entries, each a
//! species of the particle file with its own radius and transfer function
//! (see `voxless_particles::MaterialVolume` for the blending).

use std::borrow::Cow;
use std::path::Path;

use voxless_core::{Range1, Vec3, Volume, srgb_to_linear};
use voxless_particles::{Material, MaterialClass, MaterialVolume, ParticleVolume};
use voxless_transfer::{Colormap, OpacityMap, TransferFunction};

use voxless_scene::{MaterialDesc, ParticlesDesc, Species};

use super::particles::{FrameData, build_frame, frame_for, read_frame};
use crate::checks::range;
use crate::{SceneError, WorldFrame};

/// Loads every material of `p` at `frame`: the particle file filtered to
/// each material's species, with the material's radius, all in one world
/// frame (`world`, or the one the policy picks for all of them together).
pub(crate) fn load_materials(
    p: &ParticlesDesc,
    mats: &[MaterialDesc],
    base: &Path,
    notes: &mut Vec<String>,
    frame: usize,
    world: Option<&WorldFrame>,
) -> Result<(MaterialVolume, WorldFrame), SceneError> {
    // Every material's particles first, so the frame fits them all.
    let mut read: Vec<(ParticlesDesc, FrameData)> = Vec::new();
    for desc in material_descs(p, mats)? {
        let mut fd = read_frame(&desc, base, frame)?;
        notes.append(&mut fd.notes);
        read.push((desc, fd));
    }
    let world = world.copied().unwrap_or_else(|| {
        let reach = read
            .iter()
            .filter_map(|(d, fd)| fd.world_reach(d))
            .reduce(|a, b| {
                (
                    std::array::from_fn(|i| a.0[i].min(b.0[i])),
                    std::array::from_fn(|i| a.1[i].max(b.1[i])),
                )
            });
        frame_for(reach)
    });
    let mut pending = read.into_iter();
    let v = build_materials(p, mats, notes, &mut |desc, notes| {
        let (_, fd) = pending.next().ok_or_else(|| {
            SceneError::setting("particles.materials", "more materials than were read")
        })?;
        build_frame(fd, desc, &world, notes)
    })?;
    Ok((v, world))
}

/// Colormaps of the materials several snapshot types become, in order.
const TYPE_COLORMAPS: [&str; 4] = ["inferno", "viridis", "magma", "cividis"];

/// `p` with several snapshot types (`part_type = "gas,stars"`) turned into
/// one material per type (species = the type, a colormap each); `p` as it
/// is otherwise. Types and materials together are refused.
pub(crate) fn with_types(p: &ParticlesDesc) -> Result<Cow<'_, ParticlesDesc>, SceneError> {
    let Some(types) = p.part_type.as_ref().filter(|t| t.0.contains(',')) else {
        return Ok(Cow::Borrowed(p));
    };
    if p.materials.is_some() || p.species.is_some() {
        return Err(SceneError::setting(
            "particles.part_type",
            "several types become materials of their own: give them either as part_type = \
             \"gas,stars\" or as [[particles.materials]] species, not both",
        ));
    }
    let mats = types
        .0
        .split(',')
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .enumerate()
        .map(|(k, t)| MaterialDesc {
            species: Species(t.to_string()),
            name: Some(t.to_string()),
            colormap: Some(TYPE_COLORMAPS[k % TYPE_COLORMAPS.len()].to_string()),
            ..Default::default()
        })
        .collect();
    Ok(Cow::Owned(ParticlesDesc {
        part_type: None,
        materials: Some(mats),
        ..p.clone()
    }))
}

/// Every material's particle description (see [`material_desc`]); the
/// species are the materials', not the particles'.
pub(crate) fn material_descs(
    p: &ParticlesDesc,
    mats: &[MaterialDesc],
) -> Result<Vec<ParticlesDesc>, SceneError> {
    check_species(p)?;
    Ok(mats.iter().map(|m| material_desc(p, m)).collect())
}

/// With materials, the species are the materials' (an error when the
/// particles give one too).
pub(crate) fn check_species(p: &ParticlesDesc) -> Result<(), SceneError> {
    if p.species.is_some() {
        return Err(SceneError::setting(
            "particles.species",
            "give the species per material ([[particles.materials]] species = ...), not both",
        ));
    }
    Ok(())
}

/// The particle description of material `m` of `p`: its species, its radius
/// (else the particles' radius).
fn material_desc(p: &ParticlesDesc, m: &MaterialDesc) -> ParticlesDesc {
    ParticlesDesc {
        species: Some(m.species.clone()),
        radius: m.radius.or(p.radius),
        materials: None,
        ..p.clone()
    }
}

/// Builds one material's particles from its particle description (adding
/// notes).
pub(crate) type VolumeOf<'a> =
    dyn FnMut(&ParticlesDesc, &mut Vec<String>) -> Result<ParticleVolume, SceneError> + 'a;

/// The materials of `p`, each material's particles built by `volume_of`
/// from the material's particle description (the species to keep, its
/// radius).
pub(crate) fn build_materials(
    p: &ParticlesDesc,
    mats: &[MaterialDesc],
    notes: &mut Vec<String>,
    volume_of: &mut VolumeOf,
) -> Result<MaterialVolume, SceneError> {
    let mut out = Vec::with_capacity(mats.len());
    for (k, m) in mats.iter().enumerate() {
        let field = |key: &str| format!("particles.materials[{k}].{key}");
        let desc = material_desc(p, m);
        let volume = volume_of(&desc, notes)?;
        let colormap = Colormap::preset(m.colormap.as_deref().unwrap_or("viridis"))?;
        let opacity = match &m.opacity_points {
            Some(pts) => {
                let v: Vec<(f32, f32)> = pts.iter().map(|q| (q[0], q[1])).collect();
                OpacityMap::from_points(&v)?
            }
            None => OpacityMap::preset(m.opacity.as_deref().unwrap_or("linear"))?,
        };
        let value_range = match m.value_range {
            Some([lo, hi]) => range(&field("value_range"), lo, hi)?,
            None => volume.value_range(),
        };
        let color = match m.color {
            Some(c) if c.iter().all(|v| (0.0..=1.0).contains(v)) => Some(Vec3::new(
                srgb_to_linear(c[0]),
                srgb_to_linear(c[1]),
                srgb_to_linear(c[2]),
            )),
            Some(c) => {
                return Err(SceneError::setting(
                    &field("color"),
                    format!("{c:?} is not an sRGB colour in [0, 1]"),
                ));
            }
            None => None,
        };
        let name = m
            .name
            .clone()
            .unwrap_or_else(|| format!("species {}", m.species));
        notes.push(format!(
            "material '{name}': {} particles, density range [{:.4e}, {:.4e}]",
            volume.particle_count(),
            value_range.lo,
            value_range.hi
        ));
        out.push(Material {
            name,
            volume,
            class: MaterialClass {
                tf: TransferFunction::new(colormap, opacity),
                value_range: if value_range.span() > 0.0 {
                    value_range
                } else {
                    Range1::new(value_range.lo, value_range.lo + 1.0)
                },
                color,
            },
        });
    }
    MaterialVolume::new(out)
        .ok_or_else(|| SceneError::setting("particles.materials", "the list of materials is empty"))
}
