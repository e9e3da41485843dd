//! Scenes: a serde description ([`SceneDesc`], read from TOML or built from
//! command-line flags) resolved into loaded data, camera, transfer function
//! and render settings ([`LoadedScene`]).
//!
//! Resolution is where user input meets the libraries, so every failure here
//! is a [`SceneError`] naming the file (and field) at fault. Paths in a scene
//! are relative to the scene file. Defaults come from the data: the camera
//! frames the bounds, the value range is the data's, and a missing particle
//! radius is estimated from the mean particle spacing (and reported in
//! [`LoadedScene::notes`]).
//!
//! [`AnyVolume`] is the enum at the top: dispatch on the data kind happens
//! once per call, and the integrators below it are generic.

pub mod demo;
pub mod desc;
pub mod formats;
pub mod frames;
mod jaxpm;
mod load;
mod materials;
mod sources;
mod view;

pub use sources::{default_radius, frame_count};
use sources::{load_amr, load_particles, load_tets, positive, range};

use std::path::{Path, PathBuf};

use rayon::prelude::*;
use voxless_amr::{AmrError, AmrVolume};
use voxless_core::{Aabb, Camera, Image, Projection, Range1, Vec3, Volume};
use voxless_io::IoError;
use voxless_particles::{MaterialVolume, ParticleError, ParticleVolume};
use voxless_render::{FreeFlight, Light, LightSource, Noise, RenderSettings, Scatter};
use voxless_tets::{TetError, TetMode, TetOptions, TetVolume};
use voxless_transfer::{Colormap, OpacityMap, TransferError, TransferFunction};

pub use desc::*;

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error(transparent)]
    Io(#[from] IoError),
    #[error("{path}: {message}")]
    Toml { path: PathBuf, message: String },
    #[error("{path}: {message}")]
    Data { path: PathBuf, message: String },
    #[error("{path}: {source}")]
    Particles {
        path: PathBuf,
        #[source]
        source: ParticleError,
    },
    #[error("{path}: {source}")]
    Amr {
        path: PathBuf,
        #[source]
        source: AmrError,
    },
    #[error("{path}: {source}")]
    Tets {
        path: PathBuf,
        #[source]
        source: TetError,
    },
    #[error("{field}: {message}")]
    Setting { field: String, message: String },
    #[error("transfer function: {0}")]
    Transfer(#[from] TransferError),
    #[error(transparent)]
    ColormapFile(#[from] voxless_transfer::ImportError),
}

impl SceneError {
    pub fn data(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        SceneError::Data {
            path: path.into(),
            message: message.into(),
        }
    }
    pub fn setting(field: &str, message: impl Into<String>) -> Self {
        SceneError::Setting {
            field: field.into(),
            message: message.into(),
        }
    }
}

/// Query points for `sample`: an N×3 `.npy` (float32/float64) or a CSV with
/// x, y, z columns; non-finite coordinates are an error naming the point.
pub fn read_points(path: &Path) -> Result<Vec<Vec3>, SceneError> {
    let (points, _) = load::read_positions(path)?;
    if let Some(i) = points.iter().position(|p| !p.is_finite()) {
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
    toml::from_str(&text).map_err(|e| SceneError::Toml {
        path: path.into(),
        message: e.to_string(),
    })
}

/// Every data kind voxless renders; one variant per kind.
pub enum AnyVolume {
    Particles(Box<ParticleVolume>),
    Amr(Box<AmrVolume>),
    /// A phase-space tessellation and how to render it.
    Tets(Box<TetVolume>, TetMode, TetOptions),
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
            AnyVolume::Tets($v, ..) => {
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

impl AnyVolume {
    pub fn bounds(&self) -> Aabb {
        with_volume!(self, v => v.bounds())
    }
    pub fn value_range(&self) -> Range1 {
        with_volume!(self, v => v.value_range())
    }
    pub fn kind(&self) -> &'static str {
        match self {
            AnyVolume::Particles(_) => "particles",
            AnyVolume::Amr(_) => "AMR cells",
            AnyVolume::Tets(..) => "phase-space tessellation",
            AnyVolume::Materials(_) => "multi-material particles",
        }
    }

    /// Renders with the emission–absorption integrator.
    pub fn render(
        &self,
        camera: &Camera,
        tf: &TransferFunction,
        settings: &RenderSettings,
        progress: &(dyn Fn(u64, u64) + Sync),
    ) -> Image {
        match self {
            // The exact (or k-buffer) tile renderer replaces sampling.
            AnyVolume::Tets(v, mode, opts) => {
                voxless_tets::render::render(&v.mesh, camera, tf, settings, *mode, *opts, progress)
            }
            _ => with_volume!(self, v => voxless_render::render(v, camera, tf, settings, progress)),
        }
    }

    /// Column density `∫ value dt` per pixel, row-major.
    pub fn project(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        progress: &(dyn Fn(u64, u64) + Sync),
    ) -> Vec<f32> {
        match self {
            AnyVolume::Tets(v, _, opts) => {
                voxless_tets::render::project(&v.mesh, camera, width, height, *opts, progress)
            }
            _ => {
                with_volume!(self, v => voxless_render::project(v, camera, width, height, progress))
            }
        }
    }

    /// The integral of the field over all space, when the data kind knows it
    /// exactly (what a projection over the full bounds must conserve).
    pub fn total_mass(&self) -> Option<f64> {
        match self {
            AnyVolume::Particles(v) => Some(v.total_mass()),
            AnyVolume::Amr(v) => v.exact_integral(),
            AnyVolume::Tets(v, ..) => Some(v.mesh.total_mass()),
            AnyVolume::Materials(v) => {
                Some(v.materials().iter().map(|m| m.volume.total_mass()).sum())
            }
        }
    }

    /// Names of the columns [`AnyVolume::sample_points`] writes.
    pub fn sample_columns(&self, gradient: bool) -> Vec<String> {
        let grad = |name: &str| ["x", "y", "z"].map(|a| format!("d{name}/d{a}"));
        match self {
            AnyVolume::Particles(v) => {
                let mut c = vec!["density".to_string()];
                if v.has_attribute() {
                    c.push("attribute".into());
                }
                if gradient {
                    c.extend(grad("density"));
                }
                c
            }
            AnyVolume::Tets(..) => vec!["density".into(), "streams".into()],
            AnyVolume::Materials(v) => v
                .materials()
                .iter()
                .map(|m| format!("density ({})", m.name))
                .collect(),
            AnyVolume::Amr(v) => {
                let mut c: Vec<String> = v.field_names().to_vec();
                if gradient {
                    for n in v.field_names() {
                        c.extend(grad(n));
                    }
                }
                c
            }
        }
    }

    /// The fields at every point, row-major `points.len() × columns`.
    pub fn sample_points(&self, points: &[Vec3], gradient: bool) -> Vec<f32> {
        match self {
            AnyVolume::Particles(v) => points
                .par_iter()
                .flat_map_iter(|&p| {
                    let f = v.field(p, gradient);
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
                        .map(|m| m.volume.density(p))
                        .collect::<Vec<_>>()
                })
                .collect(),
            AnyVolume::Tets(v, ..) => points
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

/// Everything a render, sample or projection needs.
pub struct LoadedScene {
    pub volume: AnyVolume,
    pub camera: Camera,
    pub tf: TransferFunction,
    pub settings: RenderSettings,
    /// Linear RGB behind the volume.
    pub background: [f32; 3],
    /// Defaults chosen from the data, worth telling the user.
    pub notes: Vec<String>,
}

/// Loads the data named by `desc` (paths relative to `base`) and fills every
/// default. For a time series, this is its first frame.
pub fn resolve(desc: &SceneDesc, base: &Path) -> Result<LoadedScene, SceneError> {
    resolve_frame(desc, base, 0)
}

/// [`resolve`] at frame `frame` of a time series.
pub fn resolve_frame(
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
) -> Result<LoadedScene, SceneError> {
    let mut notes = Vec::new();
    let tf = transfer_function_at(&desc.transfer, base, &mut notes)?;
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
    let volume = match (&desc.particles, &desc.amr, &desc.tets) {
        (Some(p), _, _) if p.materials.is_some() => {
            let mats = p.materials.as_deref().unwrap_or_default();
            AnyVolume::Materials(Box::new(materials::load_materials(
                p, mats, base, &mut notes, frame,
            )?))
        }
        (Some(p), _, _) => {
            let mut volume = load_particles(p, base, &mut notes, frame)?;
            volume.classify(&tf);
            AnyVolume::Particles(Box::new(volume))
        }
        (_, Some(a), _) => AnyVolume::Amr(Box::new(load_amr(a, base)?)),
        (_, _, Some(t)) => load_tets(t, base, &mut notes)?,
        (None, None, None) => {
            return Err(SceneError::setting(
                "scene",
                "no data source: add a [particles], [amr] or [tets] table to the scene, or pass --particles FILE (with --lagrangian N --box L for a phase-space tessellation), --cells FILE --scalars FILE, or --amrclaw FILE (or use `voxless demo`)",
            ));
        }
    };

    let width = desc.image.width.unwrap_or(800);
    let height = desc.image.height.unwrap_or(600);
    if width == 0 || height == 0 || width > 32768 || height > 32768 {
        return Err(SceneError::setting(
            "image size",
            format!("{width}×{height} is outside 1..=32768 per side"),
        ));
    }
    let spp = desc.image.spp.unwrap_or(1);
    if spp == 0 {
        return Err(SceneError::setting(
            "image.spp",
            "samples per pixel must be ≥ 1",
        ));
    }
    let camera = camera(&desc.camera, &volume.bounds(), width as f32 / height as f32)?;

    let mut settings = with_volume!(&volume, v => RenderSettings::for_volume(v, width, height));
    settings.spp = spp;
    let r = &desc.render;
    if let Some(step) = r.step {
        positive("render.step", step)?;
        settings.step = Some(step);
    }
    if let Some(rate) = r.sampling_rate {
        positive("render.sampling_rate", rate)?;
        settings.sampling_rate = rate;
    }
    if let Some(et) = r.early_termination {
        if !(et > 0.0 && et <= 1.0) {
            return Err(SceneError::setting(
                "render.early_termination",
                format!("{et} is outside (0, 1]"),
            ));
        }
        settings.early_termination = et;
    }
    if let AnyVolume::Tets(..) = volume {
        // Dark-matter sheets are thin: filaments a fraction of a Lagrangian
        // spacing across need a denser medium to show.
        settings.opacity_scale = 100.0 / volume.bounds().diagonal().max(1e-12);
    }
    if let Some(s) = r.opacity_scale {
        positive("render.opacity_scale", s)?;
        settings.opacity_scale = s;
    }
    settings.packets = r.packets.unwrap_or(true);
    settings.log_scale = r.log_scale.unwrap_or(matches!(volume, AnyVolume::Tets(..)));
    if settings.log_scale {
        // Log-scale transfer functions take their range in log10 units; the
        // data range's non-positive floor becomes 3 decades below its top.
        let vr = settings.value_range;
        let hi = vr.hi.max(f32::MIN_POSITIVE).log10();
        let lo = if vr.lo > 0.0 { vr.lo.log10() } else { hi - 3.0 };
        settings.value_range = Range1::new(lo, hi);
    }
    if let Some([lo, hi]) = desc.transfer.value_range {
        settings.value_range = range("transfer.value_range", lo, hi)?;
    }
    settings.seed = r.seed.unwrap_or(0);
    if let Some(iso) = &r.iso {
        if let Some(v) = iso.iter().find(|v| !v.is_finite()) {
            return Err(SceneError::setting(
                "render.iso",
                format!("iso-value {v} is not finite"),
            ));
        }
        settings.iso = iso.clone();
    }
    if let Some(o) = r.iso_opacity {
        if !(0.0..=1.0).contains(&o) {
            return Err(SceneError::setting(
                "render.iso_opacity",
                format!("{o} is outside [0, 1]"),
            ));
        }
        settings.iso_opacity = o;
    }
    settings.volume = r.volume.unwrap_or(true);
    if let Some(c) = r.clip {
        let b = Aabb::new(Vec3::new(c[0], c[1], c[2]), Vec3::new(c[3], c[4], c[5]));
        if !(b.min.is_finite() && b.max.is_finite()) || b.is_empty() {
            return Err(SceneError::setting(
                "render.clip",
                format!("{c:?} is not a finite box with min ≤ max"),
            ));
        }
        settings.clip = Some(b);
    }
    // TF space skipping for AMR: leave invisible regions out of the BVH.
    let mut volume = volume;
    if let AnyVolume::Amr(v) = &mut volume {
        let took = v.set_visibility(&|r: Range1| settings.is_visible(&tf, r));
        notes.push(format!(
            "{} cells in {} bricks and {} regions; {} regions visible under the transfer function (selected in {:.1} ms)",
            v.stats().cells,
            v.stats().bricks,
            v.stats().regions,
            v.visible_region_count(),
            took.as_secs_f64() * 1e3
        ));
    }
    if let Some(l) = &desc.light {
        let dir = match l.direction {
            Some(d) => Vec3::from_array(d).normalized(),
            None => view::default_light_direction(&camera),
        };
        if !(dir.is_finite() && dir.length_squared() > 0.5) {
            return Err(SceneError::setting(
                "light.direction",
                "must be a finite, non-zero vector",
            ));
        }
        let ambient = l.ambient.unwrap_or(0.3);
        if !(0.0..=1.0).contains(&ambient) {
            return Err(SceneError::setting(
                "light.ambient",
                format!("{ambient} is outside [0, 1]"),
            ));
        }
        settings.light = Some(Light {
            direction: dir,
            ambient,
        });
        if l.shadows.unwrap_or(false) {
            settings.scatter = Some(scatter_settings(l, dir, ambient)?);
            if !settings.iso.is_empty() {
                return Err(SceneError::setting(
                    "light.shadows",
                    "iso-surfaces are not rendered with shadows; drop one of them",
                ));
            }
        }
    }
    let background = r.background.unwrap_or([0.0; 3]);
    Ok(LoadedScene {
        volume,
        camera,
        tf,
        settings,
        background,
        notes,
    })
}

/// The single-scattering settings of a light with `shadows = true`.
fn scatter_settings(l: &LightDesc, dir: Vec3, ambient: f32) -> Result<Scatter, SceneError> {
    let light = match l.position {
        Some(p) => {
            let p = Vec3::from_array(p);
            if !p.is_finite() {
                return Err(SceneError::setting("light.position", "must be finite"));
            }
            LightSource::Point(p)
        }
        None => LightSource::Directional(dir),
    };
    let intensity = l.intensity.unwrap_or(1.0);
    if !(intensity.is_finite() && intensity >= 0.0) {
        return Err(SceneError::setting(
            "light.intensity",
            format!("{intensity} must be finite and ≥ 0"),
        ));
    }
    let method = match l.free_flight.as_deref().unwrap_or("marching") {
        "marching" => FreeFlight::Marching,
        "delta" | "delta-tracking" => FreeFlight::DeltaTracking,
        other => {
            return Err(SceneError::setting(
                "light.free_flight",
                format!("'{other}' is not 'marching' or 'delta'"),
            ));
        }
    };
    let noise = match l.noise.as_deref().unwrap_or("blue") {
        "blue" => Noise::Blue,
        "white" => Noise::White,
        other => {
            return Err(SceneError::setting(
                "light.noise",
                format!("'{other}' is not 'blue' or 'white'"),
            ));
        }
    };
    Ok(Scatter {
        light,
        intensity,
        ambient,
        method,
        noise,
    })
}

/// [`transfer_function_at`] with a colormap file relative to the working
/// directory.
pub fn transfer_function(t: &TransferDesc) -> Result<TransferFunction, SceneError> {
    transfer_function_at(t, Path::new("."), &mut Vec::new())
}

/// The transfer function `t` describes. A `colormap_file` is read relative to
/// `base`, with `colormap` naming the preset in it; its opacity points apply
/// unless `opacity` or `opacity_points` is given. What came from the file is
/// added to `notes`.
pub fn transfer_function_at(
    t: &TransferDesc,
    base: &Path,
    notes: &mut Vec<String>,
) -> Result<TransferFunction, SceneError> {
    let own_opacity = t.opacity.is_some() || t.opacity_points.is_some();
    let imported = match &t.colormap_file {
        Some(_) if t.colormap_points.is_some() => {
            return Err(SceneError::setting(
                "transfer.colormap_file",
                "give either colormap_file or colormap_points, not both",
            ));
        }
        Some(f) => {
            let path = base.join(f);
            let m = voxless_transfer::read_colormap_file(&path, t.colormap.as_deref())?;
            let with = if m.opacity.is_some() && !own_opacity {
                " with its opacity points"
            } else {
                ""
            };
            notes.push(format!(
                "colormap '{}' from {}{with}",
                m.name,
                path.display()
            ));
            Some(m)
        }
        None => None,
    };
    let colormap = match (&imported, &t.colormap_points) {
        (Some(m), _) => m.colormap.clone(),
        (None, Some(pts)) => {
            let v: Vec<(f32, [f32; 3])> = pts.iter().map(|p| (p[0], [p[1], p[2], p[3]])).collect();
            Colormap::from_points(&v)?
        }
        (None, None) => Colormap::preset(t.colormap.as_deref().unwrap_or("viridis"))?,
    };
    let from_file = imported.and_then(|m| m.opacity);
    let opacity = match (&t.opacity_points, &t.opacity, from_file) {
        (Some(pts), _, _) => {
            OpacityMap::from_points(&pts.iter().map(|p| (p[0], p[1])).collect::<Vec<_>>())?
        }
        (None, Some(name), _) => OpacityMap::preset(name)?,
        (None, None, Some(op)) => op,
        (None, None, None) => OpacityMap::preset("linear")?,
    };
    Ok(TransferFunction::new(colormap, opacity))
}

fn camera(c: &CameraDesc, bounds: &Aabb, aspect: f32) -> Result<Camera, SceneError> {
    let framing = Camera::framing(bounds, aspect);
    let eye = c.eye.map(Vec3::from_array).unwrap_or(framing.eye);
    let look_at = c.look_at.map(Vec3::from_array).unwrap_or(bounds.center());
    let up =
        c.up.map(Vec3::from_array)
            .unwrap_or(Vec3::new(0.0, 1.0, 0.0));
    // Orbit, elevation and zoom act on the eye the lines above chose.
    let view = view::ViewAdjust::from_desc(c)?;
    let ortho = matches!(
        c.projection.as_deref(),
        Some("orthographic") | Some("ortho")
    );
    let eye = view.place_eye(eye, look_at, up, !ortho);
    let projection = match c.projection.as_deref().unwrap_or("perspective") {
        "perspective" => Projection::Perspective {
            fov_y_deg: c.fov.unwrap_or(30.0),
        },
        "orthographic" | "ortho" => {
            let h = c.ortho_height.unwrap_or(bounds.diagonal());
            positive("camera.ortho_height", h)?;
            let h = h / view.zoom;
            Projection::Orthographic {
                half_width: 0.5 * h * aspect,
                half_height: 0.5 * h,
            }
        }
        other => {
            return Err(SceneError::setting(
                "camera.projection",
                format!("'{other}' is not 'perspective' or 'orthographic'"),
            ));
        }
    };
    Camera::look_at(eye, look_at, up, projection)
        .map_err(|e| SceneError::setting("camera", e.to_string()))
}

#[cfg(test)]
mod tests;
