//! [`AnyVolume`]: every data kind behind one enum. Dispatch on the kind
//! happens once per call (render, project, sample); below it the
//! integrators are generic over the concrete volume.

use crate::{SceneError, WorldFrame};
use rayon::prelude::*;
use voxless_amr::AmrVolume;
use voxless_core::{Aabb, Camera, Cancelled, Control, Image, PixelIntegral, Range1, Vec3, Volume};
use voxless_particles::{MaterialVolume, ParticleVolume};
use voxless_render::{Film, RenderSettings};
use voxless_tets::TetVolume;
use voxless_transfer::TransferFunction;

use crate::Fields;

/// Every data kind voxless renders; one variant per kind. Volumes are
/// immutable once built and `Sync`: one volume can serve several renders at
/// once, each with its own camera and transfer function.
pub enum AnyVolume {
    Particles(Box<ParticleVolume>),
    Amr(Box<AmrVolume>),
    /// A phase-space tessellation.
    Tets(Box<TetVolume>),
    /// Several particle species, each with its own radius and transfer
    /// function, blended per sample.
    Materials(Box<MaterialVolume>),
}

/// Runs `$body` with `$v` bound to the concrete volume (monomorphised per kind).
macro_rules! with_volume {
    ($any:expr, $v:ident => $body:expr) => {
        match $any {
            AnyVolume::Particles($v) => {
                let $v = &**$v;
                $body
            }
            AnyVolume::Amr($v) => {
                let $v = &**$v;
                $body
            }
            AnyVolume::Tets($v) => {
                let $v = &**$v;
                $body
            }
            AnyVolume::Materials($v) => {
                let $v = &**$v;
                $body
            }
        }
    };
}

pub(crate) use with_volume;

impl AnyVolume {
    pub fn bounds(&self) -> Aabb {
        with_volume!(self, v => v.bounds())
    }
    pub fn value_range(&self) -> Range1 {
        with_volume!(self, v => v.value_range())
    }
    pub fn attribute_range(&self) -> Option<Range1> {
        with_volume!(self, v => v.attribute_range())
    }
    /// The kind, bounds and ranges resolving a view needs.
    pub fn summary(&self) -> VolumeSummary {
        VolumeSummary {
            kind: self.volume_kind(),
            bounds: self.bounds(),
            value_range: self.value_range(),
            attribute_range: self.attribute_range(),
        }
    }

    /// The data kind.
    pub fn volume_kind(&self) -> VolumeKind {
        match self {
            AnyVolume::Particles(_) => VolumeKind::Particles,
            AnyVolume::Amr(_) => VolumeKind::Amr,
            AnyVolume::Tets(_) => VolumeKind::Tets,
            AnyVolume::Materials(_) => VolumeKind::Materials,
        }
    }

    /// The kind's name in messages (see [`VolumeKind::name`]).
    pub fn kind(&self) -> &'static str {
        self.volume_kind().name()
    }

    /// Render settings with the library's generic defaults for this volume
    /// (see [`RenderSettings::for_volume`]); [`crate::resolve`] refines them
    /// from a description.
    pub fn default_settings(&self, width: u32, height: u32) -> RenderSettings {
        with_volume!(self, v => RenderSettings::for_volume(v, width, height))
    }

    /// Renders `settings.spp` passes with the emission–absorption (or
    /// single-scattering) integrator; progress in tiles over all passes.
    pub fn render(
        &self,
        camera: &Camera,
        tf: &TransferFunction,
        settings: &RenderSettings,
        control: &Control,
    ) -> Result<Image, Cancelled> {
        with_volume!(self, v => voxless_render::render(v, camera, tf, settings, control))
    }

    /// Renders pass by pass into a film: after each pass `on_pass(&film)`
    /// sees it (resolve it to show it) and returns whether to go on.
    /// Returns the film with the passes done.
    pub fn render_passes(
        &self,
        camera: &Camera,
        tf: &TransferFunction,
        settings: &RenderSettings,
        control: &Control,
        on_pass: &mut dyn FnMut(&Film) -> bool,
    ) -> Result<Film, Cancelled> {
        with_volume!(self, v => voxless_render::render_film(v, camera, tf, settings, control, on_pass))
    }

    /// The samples a render with these settings will take (see
    /// [`voxless_render::estimate_work`]).
    pub fn estimate_work(
        &self,
        camera: &Camera,
        tf: &TransferFunction,
        settings: &RenderSettings,
    ) -> voxless_render::WorkEstimate {
        with_volume!(self, v => voxless_render::estimate_work(v, camera, tf, settings))
    }

    /// Column density `∫ value dt` per pixel centre, row-major.
    pub fn project(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        control: &Control,
    ) -> Result<Vec<f32>, Cancelled> {
        with_volume!(self, v => voxless_render::project(v, camera, width, height, control))
    }

    /// [`AnyVolume::project`] with each pixel integrated by `pixels` where
    /// the volume chooses per projection (particles: see
    /// `voxless_particles::kernel::area`); other volumes keep the rule they
    /// were loaded with.
    pub fn project_pixels(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        pixels: PixelIntegral,
        control: &Control,
    ) -> Result<Vec<f32>, Cancelled> {
        if let AnyVolume::Particles(v) = self
            && let Some(image) = v.project_with_pixels(camera, width, height, pixels, control)
        {
            return image;
        }
        self.project(camera, width, height, control)
    }

    /// [`AnyVolume::project`] over the part `t` of every pixel's line (one
    /// line integral per pixel; the volume's whole-image path integrates
    /// whole lines).
    pub fn project_in(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        t: Range1,
        control: &Control,
    ) -> Result<Vec<f32>, Cancelled> {
        // A periodic box's slab goes through the tiled medium.
        if let AnyVolume::Particles(v) = self
            && v.periodic().is_some()
        {
            let column = |ray: &voxless_core::Ray| v.periodic_line_integral(ray, t);
            return voxless_render::project_each(camera, width, height, control, column);
        }
        with_volume!(self, v => voxless_render::project_per_pixel_in(v, camera, width, height, t, control))
    }

    /// The integral of the field over all space, when the data kind knows it
    /// exactly (what a projection over the full bounds must conserve).
    pub fn total_mass(&self) -> Option<f64> {
        match self {
            AnyVolume::Particles(v) => Some(v.total_mass()),
            AnyVolume::Amr(v) => v.exact_integral(),
            AnyVolume::Tets(v) => Some(v.mesh.total_mass()),
            AnyVolume::Materials(v) => {
                Some(v.materials().iter().map(|m| m.volume.total_mass()).sum())
            }
        }
    }

    /// Every particle's radius parameter in world units (`frame`'s scale),
    /// in the input's row order: the smoothing lengths h of the SPH
    /// kernels, the support of gaussian3, σ of gaussian — after the radius
    /// map. Refused for other kinds and for materials (several sets).
    pub fn smoothing_lengths(&self, frame: &WorldFrame) -> Result<Vec<f32>, SceneError> {
        match self {
            AnyVolume::Particles(v) => Ok(v
                .radii_in_input_order()
                .into_iter()
                .map(|r| (r as f64 * frame.scale) as f32)
                .collect()),
            other => Err(SceneError::setting(
                "particles",
                format!(
                    "radii (--save-radii, smoothing_lengths) belong to one set of particles, not to {}",
                    other.volume_kind().name()
                ),
            )),
        }
    }

    /// What the volume's field is made of (see [`Fields`]).
    pub fn fields(&self) -> Fields {
        match self {
            AnyVolume::Particles(v) => Fields::Particles {
                periodic: v.periodic(),
                attribute: v.has_attribute(),
            },
            AnyVolume::Materials(v) => {
                Fields::Materials(v.materials().iter().map(|m| m.name.clone()).collect())
            }
            AnyVolume::Tets(v) => Fields::Tets {
                box_size: v.mesh.box_size,
                n: v.mesh.n,
            },
            AnyVolume::Amr(v) => Fields::Amr(v.field_names().to_vec()),
        }
    }

    /// Names of the columns [`AnyVolume::sample_points`] writes (see
    /// [`Fields::columns`]).
    pub fn sample_columns(&self, gradient: bool) -> Vec<String> {
        self.fields().columns(gradient)
    }

    /// The fields at every point, row-major `points.len() × columns`. Each
    /// value's bits depend only on the data reaching the point (terms are
    /// added in a canonical order), so a decomposed volume samples the same.
    pub fn sample_points(&self, points: &[Vec3], gradient: bool) -> Vec<f32> {
        match self {
            AnyVolume::Particles(v) => points
                .par_iter()
                .flat_map_iter(|&p| {
                    let f = v.field_exact(p, gradient);
                    let mut row = vec![f.density];
                    if v.has_attribute() {
                        row.push(f.attribute);
                    }
                    if gradient {
                        row.extend(f.gradient.to_array());
                    }
                    row
                })
                .collect(),
            AnyVolume::Materials(v) => points
                .par_iter()
                .flat_map_iter(|&p| {
                    v.materials()
                        .iter()
                        .map(|m| m.volume.density_exact(p))
                        .collect::<Vec<_>>()
                })
                .collect(),
            AnyVolume::Tets(v) => points
                .par_iter()
                .flat_map_iter(|&p| {
                    let (rho, streams) = v.density_and_streams(p);
                    [rho as f32, streams as f32]
                })
                .collect(),
            AnyVolume::Amr(v) => {
                let nf = v.field_names().len();
                let width = if gradient { 4 * nf } else { nf };
                points
                    .par_iter()
                    .flat_map_iter(|&p| match v.fields_at(p, gradient) {
                        // Values of every field, then every field's gradient.
                        Some(f) => {
                            let mut row: Vec<f32> = f.iter().map(|x| x.0).collect();
                            if gradient {
                                row.extend(f.iter().flat_map(|x| x.1.to_array()));
                            }
                            row
                        }
                        None => vec![f32::NAN; width],
                    })
                    .collect()
            }
        }
    }
}

/// The data kinds, for what depends on the kind alone.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeKind {
    Particles,
    Amr,
    Tets,
    Materials,
}

impl VolumeKind {
    /// How the kind is called in messages: "particles", "AMR cells",
    /// "phase-space tessellation", "multi-material particles".
    pub fn name(self) -> &'static str {
        match self {
            VolumeKind::Particles => "particles",
            VolumeKind::Amr => "AMR cells",
            VolumeKind::Tets => "phase-space tessellation",
            VolumeKind::Materials => "multi-material particles",
        }
    }
}

/// What resolving needs to know of a volume besides its field along the
/// probe rays: its kind, bounds and ranges. For a volume decomposed over
/// ranks these are the whole data's, so every rank resolves the view a
/// one-process run would.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeSummary {
    pub kind: VolumeKind,
    pub bounds: Aabb,
    pub value_range: Range1,
    pub attribute_range: Option<Range1>,
}
