//! Resolving defaults: a volume (from a file or from memory) and a scene
//! description become the camera, transfer function and render settings —
//! the same defaults for every front-end. Defaults come from the data: the
//! camera frames the bounds, the value range is the data's, tessellations
//! get a log scale and a denser medium. A setting the data kind cannot
//! honour is refused by name, never ignored.

use std::path::Path;

use voxless_core::{Aabb, Camera, EventBudget, Projection, Range1, Vec3};
use voxless_render::{FreeFlight, Light, LightSource, Noise, RenderSettings, Scatter};
use voxless_scene::{
    CameraDesc, FreeFlightName, LightDesc, NoiseName, ProjectionName, SceneDesc, TetModeName,
    TransferDesc,
};
use voxless_transfer::{Colormap, OpacityMap, TransferFunction};

use crate::camera::{ViewAdjust, default_light_direction};
use crate::load::{positive, range};
use crate::{AnyVolume, SceneError, WorldFrame};

/// How to look at a volume: everything a render, projection or sample needs
/// besides the volume itself.
#[derive(Clone, Debug)]
pub struct Resolved {
    pub camera: Camera,
    pub tf: TransferFunction,
    pub settings: RenderSettings,
    /// Linear RGB behind the volume.
    pub background: [f32; 3],
    /// Defaults chosen from the data, worth telling the user.
    pub notes: Vec<String>,
}

/// Fills every default of `desc` for `volume`, whose coordinates are the
/// world's. Colormap files are read relative to `base` (the scene file's
/// directory).
pub fn resolve(volume: &AnyVolume, desc: &SceneDesc, base: &Path) -> Result<Resolved, SceneError> {
    resolve_in(volume, &WorldFrame::default(), desc, base)
}

/// [`resolve`] for a volume whose coordinates are relative to `frame`:
/// the description's world positions (eye, look-at, clip box, point light)
/// are moved into the volume's frame, and the resolved camera and settings
/// are in it.
pub fn resolve_in(
    volume: &AnyVolume,
    frame: &WorldFrame,
    desc: &SceneDesc,
    base: &Path,
) -> Result<Resolved, SceneError> {
    let mut notes = Vec::new();
    let tf = transfer_function_at(&desc.transfer, base, &mut notes)?;
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
    let camera = camera(
        &desc.camera,
        &volume.bounds(),
        width as f32 / height as f32,
        frame,
    )?;

    let mut settings = volume.default_settings(width, height);
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
        // In the transfer function's units: log10 of the value in log scale.
        settings.iso = if settings.log_scale {
            iso.iter().map(|v| 10f32.powf(*v)).collect()
        } else {
            iso.clone()
        };
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
        let b = frame.box_to_local(c);
        if !c.iter().all(|v| v.is_finite()) || b.is_empty() {
            return Err(SceneError::setting(
                "render.clip",
                format!("{c:?} is not a finite box with min ≤ max"),
            ));
        }
        settings.clip = Some(b);
    }
    if let AnyVolume::Amr(v) = volume {
        let visible = v.visible_region_count(&|r: Range1| settings.is_visible(&tf, r));
        notes.push(format!(
            "{} cells in {} bricks and {} regions; {} regions visible under the transfer function",
            v.stats().cells,
            v.stats().bricks,
            v.stats().regions,
            visible,
        ));
    }
    if let AnyVolume::Tets(_) = volume
        && let Some(t) = &desc.tets
        && t.mode == Some(TetModeName::Kbuffer)
    {
        settings.event_budget = Some(EventBudget {
            k: t.k.unwrap_or(16).max(1),
            layers: t.layers.unwrap_or(64).max(1),
        });
    }
    if let Some(l) = &desc.light {
        let dir = match l.direction {
            Some(d) => Vec3::from_array(d).normalized(),
            None => default_light_direction(&camera),
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
            settings.scatter = Some(scatter_settings(l, dir, ambient, frame)?);
            if !settings.iso.is_empty() {
                return Err(SceneError::setting(
                    "light.shadows",
                    "iso-surfaces are not rendered with shadows; drop one of them",
                ));
            }
        }
    }
    refuse_what_the_kind_cannot_honour(volume, &settings)?;
    let background = r.background.unwrap_or([0.0; 3]);
    Ok(Resolved {
        camera,
        tf,
        settings,
        background,
        notes,
    })
}

/// The single-scattering settings of a light with `shadows = true`.
fn scatter_settings(
    l: &LightDesc,
    dir: Vec3,
    ambient: f32,
    frame: &WorldFrame,
) -> Result<Scatter, SceneError> {
    let light = match l.position {
        Some(p) => {
            if !p.iter().all(|v| v.is_finite()) {
                return Err(SceneError::setting("light.position", "must be finite"));
            }
            LightSource::Point(frame.to_local(p))
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
    let method = match l.free_flight.unwrap_or(FreeFlightName::Marching) {
        FreeFlightName::Marching => FreeFlight::Marching,
        FreeFlightName::Delta => FreeFlight::DeltaTracking,
    };
    let noise = match l.noise.unwrap_or(NoiseName::Blue) {
        NoiseName::Blue => Noise::Blue,
        NoiseName::White => Noise::White,
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

/// The camera `c` describes (world positions moved into `frame`) for data
/// within `bounds` (in the frame).
pub(crate) fn camera(
    c: &CameraDesc,
    bounds: &Aabb,
    aspect: f32,
    frame: &WorldFrame,
) -> Result<Camera, SceneError> {
    let framing = Camera::framing(bounds, aspect);
    let eye = c.eye.map(|p| frame.to_local(p)).unwrap_or(framing.eye);
    let look_at = c
        .look_at
        .map(|p| frame.to_local(p))
        .unwrap_or(bounds.center());
    let up =
        c.up.map(Vec3::from_array)
            .unwrap_or(Vec3::new(0.0, 1.0, 0.0));
    // Orbit, elevation and zoom act on the eye the lines above chose.
    let view = ViewAdjust::from_desc(c)?;
    let ortho = c.projection == Some(ProjectionName::Orthographic);
    let eye = view.place_eye(eye, look_at, up, !ortho);
    let projection = match c.projection.unwrap_or(ProjectionName::Perspective) {
        ProjectionName::Perspective => Projection::Perspective {
            fov_y_deg: c.fov.unwrap_or(30.0),
        },
        ProjectionName::Orthographic => {
            let h = c.ortho_height.unwrap_or(bounds.diagonal());
            positive("camera.ortho_height", h)?;
            let h = h / view.zoom;
            Projection::Orthographic {
                half_width: 0.5 * h * aspect,
                half_height: 0.5 * h,
            }
        }
    };
    Camera::look_at(eye, look_at, up, projection)
        .map_err(|e| SceneError::setting("camera", e.to_string()))
}

/// Settings the volume's kind cannot honour are errors naming them.
fn refuse_what_the_kind_cannot_honour(
    volume: &AnyVolume,
    settings: &RenderSettings,
) -> Result<(), SceneError> {
    if let AnyVolume::Tets(_) = volume
        && settings.light.is_some()
        && settings.scatter.is_none()
        && settings.volume
        && settings.iso.is_empty()
    {
        return Err(SceneError::setting(
            "light (--shade)",
            "a phase-space tessellation's density is constant inside every tet, so the volume \
             has no gradient to shade with; use --shadows for lighting, or --iso V for shaded \
             iso-surfaces",
        ));
    }
    Ok(())
}
