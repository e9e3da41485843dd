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

use crate::autorange::{HIGH_PERCENTILE, LOW_PERCENTILE, Probe, TARGET_OPTICAL_DEPTH};
use crate::camera::{DEFAULT_UP, VIEW_FOV_DEG, ViewAdjust, default_eye, default_light_direction};
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
    /// The box (local) the camera frames when the description places no
    /// eye or look-at point: the part of the data the transfer function
    /// shows, within the bounds (see [`Probe::visible_box`]).
    pub framed: Aabb,
}

/// The data kinds, for what depends on the kind alone.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeKind {
    Particles,
    Amr,
    Tets,
    Materials,
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
    resolve_with(volume, frame, desc, base, None, None)
}

/// [`resolve_in`] with defaults taken over more than this volume: a probe
/// of the field (see [`Probe`]; e.g. merged over every frame of a time
/// series) for the value range and opacity scale, and the world box to
/// frame with the camera (e.g. the union over the frames).
pub fn resolve_with(
    volume: &AnyVolume,
    frame: &WorldFrame,
    desc: &SceneDesc,
    base: &Path,
    probe: Option<&Probe>,
    framed: Option<([f64; 3], [f64; 3])>,
) -> Result<Resolved, SceneError> {
    let mut own = |clip: Option<&Aabb>| Probe::of(volume, clip);
    let mut resolved = resolve_summary(
        &volume.summary(),
        frame,
        desc,
        base,
        probe,
        &mut own,
        framed,
    )?;
    if let AnyVolume::Amr(v) = volume {
        let (settings, tf) = (&resolved.settings, &resolved.tf);
        let visible = v.visible_region_count(&|r: Range1| settings.is_visible(tf, r));
        resolved.notes.push(format!(
            "{} cells in {} bricks and {} regions; {} regions visible under the transfer function",
            v.stats().cells,
            v.stats().bricks,
            v.stats().regions,
            visible,
        ));
    }
    Ok(resolved)
}

/// [`resolve_with`] from what resolving needs of a volume: its summary, and
/// the probe of its field (`probe`, or `probe_of(clip)` when the defaults
/// need one) — for a decomposed volume, the whole data's summary and a
/// probe its ranks sample together.
pub fn resolve_summary(
    volume: &VolumeSummary,
    frame: &WorldFrame,
    desc: &SceneDesc,
    base: &Path,
    probe: Option<&Probe>,
    probe_of: &mut dyn FnMut(Option<&Aabb>) -> Probe,
    framed: Option<([f64; 3], [f64; 3])>,
) -> Result<Resolved, SceneError> {
    let kind = volume.kind;
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
    crate::budget::check_image_memory(width, height)?;
    let spp = desc.image.spp.unwrap_or(1);
    if spp == 0 {
        return Err(SceneError::setting(
            "image.spp",
            "samples per pixel must be ≥ 1",
        ));
    }
    let bounds = match framed {
        Some((lo, hi)) => Aabb::new(frame.to_local(lo), frame.to_local(hi)),
        None => volume.bounds,
    };

    let mut settings = RenderSettings::for_data(
        volume.bounds,
        volume.value_range,
        volume.attribute_range,
        width,
        height,
    );
    settings.spp = spp;
    let r = &desc.render;
    if let Some(step) = r.step {
        positive("render.step (--step)", step)?;
        settings.step = Some(frame.length_to_local(step as f64));
    }
    if let Some(rate) = r.sampling_rate {
        positive("render.sampling_rate (--sampling-rate)", rate)?;
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
    if kind == VolumeKind::Tets {
        // Dark-matter sheets are thin: filaments a fraction of a Lagrangian
        // spacing across need a denser medium to show.
        settings.opacity_scale = 100.0 / volume.bounds.diagonal().max(1e-12);
    }
    settings.packets = r.packets.unwrap_or(true);
    settings.log_scale = r.log_scale.unwrap_or(kind == VolumeKind::Tets);
    if settings.log_scale {
        // Log-scale transfer functions take their range in log10 units; the
        // data range's non-positive floor becomes 3 decades below its top.
        let vr = settings.value_range;
        let hi = vr.hi.max(f32::MIN_POSITIVE).log10();
        let lo = if vr.lo > 0.0 { vr.lo.log10() } else { hi - 3.0 };
        settings.value_range = Range1::new(lo, hi);
    }
    if let Some(c) = r.clip {
        let b = frame.box_to_local(c);
        if !c.iter().all(|v| v.is_finite()) || b.is_empty() {
            return Err(SceneError::setting(
                "render.clip (--clip)",
                format!("{c:?} is not a finite box with min ≤ max"),
            ));
        }
        settings.clip = Some(b);
    }
    // What the data looks like along probe rays (a time series passes the
    // probe of all its frames), for the defaults below; inside the clip box,
    // as that is what the image shows.
    let default_view = desc.camera.eye.is_none() && desc.camera.look_at.is_none();
    let needs_probe =
        desc.transfer.value_range.is_none() || r.opacity_scale.is_none() || default_view;
    let own_probe;
    let probe = match (needs_probe, probe) {
        (false, _) => None,
        (true, Some(p)) => Some(p),
        (true, None) => {
            own_probe = probe_of(settings.clip.as_ref());
            Some(&own_probe)
        }
    };
    let units = if settings.log_scale { "log10 " } else { "" };
    match desc.transfer.value_range {
        Some([lo, hi]) => {
            settings.value_range = range("transfer.value_range (--value-range)", lo, hi)?;
        }
        None => {
            let floor_zero = kind == VolumeKind::Particles;
            if let Some(vr) = probe.and_then(|p| p.value_range(floor_zero, settings.log_scale)) {
                settings.value_range = vr;
                notes.push(format!(
                    "value range [{:.4e}, {:.4e}] ({units}{} of the field in the data; set \
                     with --value-range)",
                    vr.lo,
                    vr.hi,
                    if floor_zero {
                        format!("0 to the {HIGH_PERCENTILE}th percentile")
                    } else {
                        format!("{LOW_PERCENTILE}th to {HIGH_PERCENTILE}th percentile")
                    }
                ));
            }
        }
    }
    if desc.transfer.value_range.is_none() && kind != VolumeKind::Materials {
        constant_field(volume.value_range, &mut settings, &mut notes);
    }
    match r.opacity_scale {
        Some(s) => {
            positive("render.opacity_scale (--opacity-scale)", s)?;
            // Extinction per world length → per local length.
            settings.opacity_scale = (s as f64 * frame.scale) as f32;
        }
        None => {
            if let Some(s) = probe.and_then(|p| p.opacity_scale(&tf, &settings)) {
                settings.opacity_scale = s;
                notes.push(format!(
                    "opacity scale {:.4e} per unit length (a typical ray through the data \
                     reaches optical depth {TARGET_OPTICAL_DEPTH}; set with --opacity-scale)",
                    s as f64 / frame.scale
                ));
            }
        }
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
    if kind == VolumeKind::Tets
        && let Some(t) = &desc.tets
    {
        if t.mode == Some(TetModeName::Kbuffer) {
            settings.event_budget = Some(EventBudget {
                k: at_least_one("tets.k (--k)", t.k.unwrap_or(16))?,
                layers: at_least_one("tets.layers (--layers)", t.layers.unwrap_or(64))?,
            });
        } else if t.k.is_some() || t.layers.is_some() {
            return Err(SceneError::setting(
                if t.k.is_some() {
                    "tets.k (--k)"
                } else {
                    "tets.layers (--layers)"
                },
                "applies to the k-buffer only: add --tet-mode kbuffer (scene: tets.mode), \
                 or leave it out for the exact render",
            ));
        }
    }
    crate::surfaces::resolve(desc, base, frame, &volume.bounds, &mut settings, &mut notes)?;
    // The default view frames what the transfer function shows (the whole
    // bounds with iso-surfaces, whose visibility the probe cannot tell).
    let mut framed_box = bounds;
    if default_view
        && settings.volume
        && settings.iso.is_empty()
        && let Some(v) = probe.and_then(|p| p.visible_box(&tf, &settings))
    {
        let v = Aabb::new(v.min.max(bounds.min), v.max.min(bounds.max));
        let shrinks = (0..3).any(|a| v.extent()[a] < 0.9 * bounds.extent()[a]);
        if !v.is_empty() && shrinks {
            framed_box = v;
            let (lo, hi) = (frame.to_world(v.min), frame.to_world(v.max));
            notes.push(format!(
                "the view frames the part of the data the transfer function shows, \
                 [{:.4e}, {:.4e}, {:.4e}]..[{:.4e}, {:.4e}, {:.4e}] (give --eye/--look-at to \
                 frame otherwise)",
                lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
            ));
        }
    }
    // Mirror instances belong in the picture.
    for m in &settings.mirrors {
        let (p, q) = (m.point(framed_box.min), m.point(framed_box.max));
        framed_box = framed_box.union(Aabb::new(p.min(q), p.max(q)));
    }
    let camera = camera(
        &desc.camera,
        &framed_box,
        width as f32 / height as f32,
        frame,
    )?;
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
    refuse_what_the_kind_cannot_honour(kind, &settings)?;
    refuse_settings_without_effect(desc)?;
    let background = r.background.unwrap_or([0.0; 3]);
    if !background.iter().all(|c| c.is_finite() && *c >= 0.0) {
        return Err(SceneError::setting(
            "render.background (--background)",
            format!("{background:?} is not a colour: give three finite linear RGB values ≥ 0"),
        ));
    }
    Ok(Resolved {
        camera,
        tf,
        settings,
        background,
        notes,
        framed: framed_box,
    })
}

/// A value range of one value (a constant field) maps everything to 0,
/// which the transfer function shows as nothing: map the constant to the
/// top of the range instead, so the field shows as a uniform medium (a
/// field that is 0 everywhere stays as it is; [`check_work`] refuses it).
fn constant_field(data: Range1, settings: &mut RenderSettings, notes: &mut Vec<String>) {
    let vr = settings.value_range;
    if vr.hi > vr.lo || !(vr.lo.is_finite() && vr.hi.is_finite()) {
        return;
    }
    if !(data.hi > 0.0 || data.lo < 0.0) {
        return;
    }
    settings.value_range = if settings.log_scale {
        Range1::new(vr.hi - 1.0, vr.hi)
    } else {
        Range1::new(data.hi.min(0.0), data.hi.max(0.0))
    };
    notes.push(format!(
        "the field is {:.4e} everywhere: shown as a uniform medium (value range [{:.4e}, \
         {:.4e}]; set with --value-range)",
        data.hi, settings.value_range.lo, settings.value_range.hi
    ));
}

fn at_least_one(field: &str, v: usize) -> Result<usize, SceneError> {
    if v == 0 {
        return Err(SceneError::setting(field, "must be at least 1"));
    }
    Ok(v)
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
    let mut up = Vec3::from_array(c.up.unwrap_or(DEFAULT_UP));
    if !(up.is_finite() && up.length_squared() > 0.0) {
        return Err(SceneError::setting(
            "camera.up (--up)",
            format!("{:?} is not a finite, non-zero vector", up.to_array()),
        ));
    }
    let fov = c.fov.unwrap_or(VIEW_FOV_DEG);
    if !(fov > 0.0 && fov < 180.0) {
        return Err(SceneError::setting(
            "camera.fov (--fov)",
            format!("{fov} is outside (0, 180) degrees"),
        ));
    }
    for (field, p) in [
        ("camera.eye (--eye)", c.eye),
        ("camera.look_at (--look-at)", c.look_at),
    ] {
        if let Some(p) = p
            && !p.iter().all(|v| v.is_finite())
        {
            return Err(SceneError::setting(field, format!("{p:?} is not finite")));
        }
    }
    let look_at = c
        .look_at
        .map(|p| frame.to_local(p))
        .unwrap_or(bounds.center());
    let eye = match c.eye {
        Some(p) => frame.to_local(p),
        None => default_eye(bounds, aspect, up, fov).ok_or_else(|| {
            SceneError::setting(
                "camera",
                format!(
                    "the data's bounds {:?}..{:?} cannot be framed; give --eye and --look-at",
                    bounds.min.to_array(),
                    bounds.max.to_array()
                ),
            )
        })?,
    };
    if c.up.is_none() && eye != look_at {
        // The default up (+z) along the line of sight of an explicit eye
        // (looking straight down or up): +y instead, as before +z was the
        // default.
        let d = (look_at - eye).normalized();
        if d.is_finite() && d.z.abs() > 0.999 {
            up = Vec3::new(0.0, 1.0, 0.0);
        }
    }
    // Orbit, elevation and zoom act on the eye the lines above chose.
    let view = ViewAdjust::from_desc(c)?;
    let ortho = c.projection == Some(ProjectionName::Orthographic);
    let eye = view.place_eye(eye, look_at, up, !ortho);
    let projection = match c.projection.unwrap_or(ProjectionName::Perspective) {
        ProjectionName::Perspective => Projection::Perspective { fov_y_deg: fov },
        ProjectionName::Orthographic => {
            let h = match c.ortho_height {
                Some(h) => {
                    positive("camera.ortho_height (--orthographic)", h)?;
                    frame.length_to_local(h as f64)
                }
                None => bounds.diagonal(),
            };
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

/// Mean samples per camera ray beyond which a render is refused: real data
/// needs thousands (10⁹ particles: ~8,000 at the default radius); a
/// quarter of a million means a radius or step far below the data's scale,
/// and minutes for even a thumbnail.
pub const MAX_SAMPLES_PER_RAY: f64 = (1u64 << 18) as f64;
/// Samples in all beyond which a render is refused (about a day at 10⁸
/// samples per second).
pub const MAX_SAMPLES: f64 = 1e13;

/// A render whose estimated work (see [`AnyVolume::estimate_work`]) is
/// absurd is an error with the estimate and the flags that change it,
/// before any work starts. Otherwise returns a note when the step was
/// raised to what f32 can resolve along the rays.
pub(crate) fn check_work(
    volume: &AnyVolume,
    frame: &WorldFrame,
    desc: &SceneDesc,
    camera: &Camera,
    tf: &TransferFunction,
    settings: &RenderSettings,
) -> Result<Option<String>, SceneError> {
    let data = volume.value_range();
    let materials = matches!(volume, AnyVolume::Materials(_));
    if !(materials || data.hi > 0.0 || data.lo < 0.0) {
        let (field, why) = match volume {
            AnyVolume::Particles(_) => (
                "particles.weights (--weights)",
                "every particle's weight is 0 (or a weight or radius map hides it)",
            ),
            AnyVolume::Amr(_) => ("amr.field (--field)", "every cell's value is 0"),
            _ => ("data", "it holds no mass"),
        };
        return Err(SceneError::setting(
            field,
            format!("the field is 0 everywhere, so there is nothing to render: {why}"),
        ));
    }
    let work = volume.estimate_work(camera, tf, settings);
    let extent = frame.length_to_world(volume.bounds().diagonal());
    if work.per_ray <= MAX_SAMPLES_PER_RAY && work.total <= MAX_SAMPLES {
        return Ok(work.step_raised.then(|| {
            format!(
                "the ray-marching step is finer than float32 can resolve along the rays \
                 (data extent {extent:.3e}); it was raised to {} units in the last place of \
                 the distance along each ray",
                voxless_render::MIN_STEP_ULPS
            )
        }));
    }
    let given_radius = desc
        .particles
        .as_ref()
        .is_some_and(|p| p.radius.is_some() || p.radii.is_some());
    let (field, fix) = if let Some(step) = desc.render.step {
        (
            "render.step (--step)",
            format!(
                "the step {step} is tiny against the data (extent {extent:.3e}): give a \
                 larger --step"
            ),
        )
    } else if given_radius && work.per_ray > MAX_SAMPLES_PER_RAY {
        (
            "particles.radius (--radius)",
            format!(
                "the particles' supports are tiny against the data (extent {extent:.3e}), and \
                 rays step 1/8 of a support: give a larger --radius (or omit it for one from \
                 the particle spacing), or a --step"
            ),
        )
    } else if work.per_ray > MAX_SAMPLES_PER_RAY {
        (
            "render.step (--step)",
            format!(
                "the data's own step is tiny against its extent ({extent:.3e}) — outliers far \
                 from the rest, or a sampling rate too high: give a --step (e.g. {:.3e}), a \
                 smaller --sampling-rate, or leave out the outliers",
                extent / 2000.0
            ),
        )
    } else {
        (
            "image (--size, --spp)",
            "give a smaller --size or fewer --spp".to_string(),
        )
    };
    Err(SceneError::setting(
        field,
        format!(
            "this render would take about {:.1e} samples per ray, {:.1e} in all (limits \
             {MAX_SAMPLES_PER_RAY:.1e} per ray, {MAX_SAMPLES:.0e} in all): {fix}",
            work.per_ray, work.total
        ),
    ))
}

/// Settings that only act together with another one, given without it,
/// are errors naming both: they would silently do nothing.
fn refuse_settings_without_effect(desc: &SceneDesc) -> Result<(), SceneError> {
    let r = &desc.render;
    let no_iso = r.iso.as_ref().is_none_or(|v| v.is_empty());
    if no_iso && r.iso_opacity.is_some() {
        return Err(SceneError::setting(
            "render.iso_opacity (--iso-opacity)",
            "applies to iso-surfaces: add --iso V",
        ));
    }
    if no_iso && r.volume == Some(false) {
        return Err(SceneError::setting(
            "render.volume (--iso-only)",
            "with the volume off and no iso-surface the image would be empty: add --iso V",
        ));
    }
    if let Some(l) = &desc.light
        && !l.shadows.unwrap_or(false)
    {
        let only_with_shadows = [
            ("light.position (--light-pos)", l.position.is_some()),
            ("light.intensity (--light-intensity)", l.intensity.is_some()),
            ("light.free_flight (--free-flight)", l.free_flight.is_some()),
            ("light.noise (--noise)", l.noise.is_some()),
        ];
        if let Some((field, _)) = only_with_shadows.iter().find(|f| f.1) {
            return Err(SceneError::setting(
                field,
                "applies to single scattering: add --shadows (scene: light.shadows = true)",
            ));
        }
    }
    if let Some(p) = &desc.particles
        && p.kernel != Some(voxless_scene::KernelName::Gaussian)
    {
        for (field, given) in [
            ("particles.kappa (--kappa)", p.kappa.is_some()),
            ("particles.sigma (--sigma)", p.sigma.is_some()),
        ] {
            if given {
                return Err(SceneError::setting(
                    field,
                    "applies to the gaussian kernel only: add --kernel gaussian",
                ));
            }
        }
    }
    Ok(())
}

/// Settings the volume's kind cannot honour are errors naming them.
fn refuse_what_the_kind_cannot_honour(
    kind: VolumeKind,
    settings: &RenderSettings,
) -> Result<(), SceneError> {
    if kind == VolumeKind::Tets
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
