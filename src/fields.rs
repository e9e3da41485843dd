//! [`Fields`]: what a volume's field is made of, as far as a front-end
//! needs to know it — the columns `sample` writes, the row of a point no
//! data reaches, and the name the colours stand for. A volume held whole
//! and one decomposed over ranks describe their fields with the same value,
//! so both sample into the same columns and label a colour bar alike.

use std::path::Path;

use voxless_core::Vec3;
use voxless_scene::SceneDesc;

/// The fields of a volume (see the module docs; a volume's own:
/// [`crate::AnyVolume::fields`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Fields {
    /// Particle density Φ, and the attribute field Θ when particles carry
    /// an attribute.
    /// Particles, with or without an attribute, in a periodic box (local
    /// units) or not.
    Particles {
        attribute: bool,
        periodic: Option<voxless_core::Aabb>,
    },
    /// One density per material, by name.
    Materials(Vec<String>),
    /// A phase-space tessellation: density and stream count, in a periodic
    /// box of `box_size` (local units) over an `n`³ Lagrangian grid.
    Tets { box_size: f32, n: usize },
    /// AMR cells: every named field.
    Amr(Vec<String>),
}

impl Fields {
    /// Names of the columns sampling writes: particles Φ, then Θ (with an
    /// attribute), then ∂Φ/∂x, ∂Φ/∂y, ∂Φ/∂z (with `gradient`); materials one
    /// density each; tessellations density and streams; AMR every field,
    /// then every field's gradient.
    /// Refuses a gradient of fields that have none to give (it would be
    /// dropped without a word): a tessellation's density is constant inside
    /// each tet, and several materials are sampled as densities only.
    pub fn check_gradient(&self, gradient: bool) -> Result<(), crate::SceneError> {
        let why = match self {
            Fields::Tets { .. } if gradient => {
                "a phase-space tessellation's density is constant inside every tet (its gradient \
                 is zero there and undefined on the faces)"
            }
            Fields::Materials(_) if gradient => {
                "materials are sampled as one density per species, without gradients"
            }
            _ => return Ok(()),
        };
        Err(crate::SceneError::setting("gradient (--gradient)", why))
    }

    pub fn columns(&self, gradient: bool) -> Vec<String> {
        let grad = |name: &str| ["x", "y", "z"].map(|a| format!("d{name}/d{a}"));
        match self {
            Fields::Particles { attribute, .. } => {
                let mut c = vec!["density".to_string()];
                if *attribute {
                    c.push("attribute".into());
                }
                if gradient {
                    c.extend(grad("density"));
                }
                c
            }
            Fields::Tets { .. } => vec!["density".into(), "streams".into()],
            Fields::Materials(names) => names.iter().map(|n| format!("density ({n})")).collect(),
            Fields::Amr(names) => {
                let mut c = names.clone();
                if gradient {
                    for n in names {
                        c.extend(grad(n));
                    }
                }
                c
            }
        }
    }

    /// The sampled row of a point no data reaches, `width` columns wide:
    /// zero density (an undefined attribute), or NaN outside AMR cells.
    pub(crate) fn empty_row(&self, width: usize) -> Vec<f32> {
        match self {
            Fields::Particles { attribute, .. } => {
                let mut row = vec![0.0; width];
                if *attribute {
                    row[1] = f32::NAN;
                }
                row
            }
            Fields::Amr(_) => vec![f32::NAN; width],
            Fields::Materials(_) | Fields::Tets { .. } => vec![0.0; width],
        }
    }

    /// Where a query at `p` is evaluated: a tessellation wraps it into its
    /// box and nudges it off the tets' faces; other fields take it as it is.
    pub(crate) fn query_point(&self, p: Vec3) -> Vec3 {
        match self {
            Fields::Tets { box_size, n } => voxless_tets::canonical_point(*box_size, *n, p),
            // The box's own copy of the point (its owner holds every image).
            Fields::Particles {
                periodic: Some(b), ..
            } => voxless_particles::wrap(b, p),
            _ => p,
        }
    }

    /// The name of the field the colours stand for, when known: the
    /// particle attribute (its file or column name; "temperature" for the
    /// demo's) or "density", the AMR colour (else opacity) field, "density"
    /// for a tessellation; none for materials (each has its own).
    pub fn colour_name(&self, desc: &SceneDesc) -> Option<String> {
        match self {
            Fields::Particles { attribute, .. } => {
                match desc.particles.as_ref().and_then(|p| p.attribute.as_deref()) {
                    Some(spec) => name_of(spec),
                    None if *attribute => Some("temperature".into()),
                    None => Some("density".into()),
                }
            }
            Fields::Amr(names) => desc
                .amr
                .as_ref()
                .and_then(|a| a.color_field.clone().or_else(|| a.field.clone()))
                .or_else(|| names.first().cloned()),
            Fields::Tets { .. } => Some("density".into()),
            Fields::Materials(_) => None,
        }
    }
}

/// A name for a field given as a file (`temp_%04d.npy` → `temp`) or a
/// CSV column.
pub(crate) fn name_of(spec: &str) -> Option<String> {
    let p = Path::new(spec);
    let file = p.file_name()?.to_string_lossy().into_owned();
    let stem = match p.extension() {
        Some(_) => p.file_stem()?.to_string_lossy().into_owned(),
        None => file,
    };
    let cut = stem.find(['%', '*', '?']).unwrap_or(stem.len());
    let name = stem[..cut].trim_end_matches(['_', '-', '.', ' ']);
    (!name.is_empty()).then(|| name.to_string())
}
