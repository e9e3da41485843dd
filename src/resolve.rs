//! Resolving defaults: a volume (from a file or from memory) and a scene
//! description become the camera, transfer function and render settings —
//! the same defaults for every front-end. Defaults come from the data: the
//! camera frames the bounds, the value range is the data's, tessellations
//! get a log scale and a denser medium. A setting the data kind cannot
//! honour is refused by name, never ignored.

use std::path::Path;

use voxless_core::{Aabb, Camera, EventBudget, Range1, Vec3};
use voxless_render::{FreeFlight, Light, LightSource, Noise, RenderSettings, Scatter};
use voxless_scene::{FreeFlightName, LightDesc, NoiseName, SceneDesc, TetModeName, TransferDesc};
use voxless_transfer::{Colormap, OpacityMap, TransferFunction};

use crate::autorange::{HIGH_PERCENTILE, LOW_PERCENTILE, Probe, TARGET_OPTICAL_DEPTH};
use crate::camera::{camera, default_light_direction};
use crate::checks::{
    positive, range, refuse_settings_without_effect, refuse_what_the_kind_cannot_honour,
};
use crate::{AnyVolume, SceneError, VolumeKind, VolumeSummary, WorldFrame};

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

/// The most samples per pixel a render takes: the noise falls as
/// 1/√spp, so 65,536 passes leave 1/256 of one pass's noise, well below
/// 8-bit output, and more only costs time.
pub const MAX_SPP: u32 = 65_536;

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
/// probe its ranks sample together. The steps, in order: the transfer
/// function; the image and marching settings; the probe (when a default
/// needs one); the defaults taken from the data (value range, opacity
/// scale); iso-surfaces and the k-buffer; surfaces and instances; the box
/// the camera frames; the camera; the light; the refusals.
pub fn resolve_summary(
    volume: &VolumeSummary,
    frame: &WorldFrame,
    desc: &SceneDesc,
    base: &Path,
    probe: Option<&Probe>,
    probe_of: &mut dyn FnMut(Option<&Aabb>) -> Probe,
    framed: Option<([f64; 3], [f64; 3])>,
) -> Result<Resolved, SceneError> {
    let mut notes = Vec::new();
    let tf = transfer_function_at(&desc.transfer, base, &mut notes)?;
    let mut settings = march_settings(volume, frame, desc)?;
    // What the data looks like along probe rays (a time series passes the
    // probe of all its frames), for the defaults below; inside the clip box,
    // as that is what the image shows.
    let default_view = desc.camera.eye.is_none() && desc.camera.look_at.is_none();
    let needs_probe =
        desc.transfer.value_range.is_none() || desc.render.opacity_scale.is_none() || default_view;
    let own_probe;
    let probe = match (needs_probe, probe) {
        (false, _) => None,
        (true, Some(p)) => Some(p),
        (true, None) => {
            own_probe = probe_of(settings.clip.as_ref());
            Some(&own_probe)
        }
    };
    data_defaults(volume, frame, desc, probe, &tf, &mut settings, &mut notes)?;
    iso_settings(volume.kind, desc, &mut settings)?;
    crate::surfaces::resolve(desc, base, frame, &volume.bounds, &mut settings, &mut notes)?;
    let bounds = match framed {
        Some((lo, hi)) => Aabb::new(frame.to_local(lo), frame.to_local(hi)),
        None => volume.bounds,
    };
    let framed_box = match probe {
        Some(p) if default_view => framed_box(bounds, p, &tf, &settings, frame, &mut notes),
        _ => bounds,
    };
    let framed_box = with_instances(framed_box, &settings);
    let aspect = settings.width as f32 / settings.height as f32;
    let camera = camera(&desc.camera, &framed_box, aspect, frame)?;
    light_settings(desc, &camera, frame, &mut settings)?;
    refuse_what_the_kind_cannot_honour(volume.kind, &settings)?;
    let background = desc.render.background.unwrap_or([0.0; 3]);
    Ok(Resolved {
        camera,
        tf,
        settings,
        background,
        notes,
        framed: framed_box,
    })
}

/// The settings of `desc` that are wrong whatever the data: the image size
/// and its memory, samples per pixel, the step, sampling rate and early
/// termination, the background, a value range that is not a range, and
/// settings that act only with another one. The renderer checks them as it
/// resolves a view; a front-end that edits a view (the viewer's patches)
/// checks them first, so a bad setting never becomes the view it renders.
pub fn check_settings(desc: &SceneDesc) -> Result<(), SceneError> {
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
    if spp == 0 || spp > MAX_SPP {
        return Err(SceneError::setting(
            "image.spp (--spp)",
            format!(
                "{spp} samples per pixel: give 1..={MAX_SPP} (the noise of {MAX_SPP} passes is \
                 already 1/256 of one pass's; a million would take days)"
            ),
        ));
    }
    let r = &desc.render;
    if let Some(step) = r.step {
        positive("render.step (--step)", step)?;
    }
    if let Some(rate) = r.sampling_rate {
        positive("render.sampling_rate (--sampling-rate)", rate)?;
    }
    if let Some(et) = r.early_termination
        && !(et > 0.0 && et <= 1.0)
    {
        return Err(SceneError::setting(
            "render.early_termination",
            format!("{et} is outside (0, 1]"),
        ));
    }
    let background = r.background.unwrap_or([0.0; 3]);
    if !background.iter().all(|c| c.is_finite() && *c >= 0.0) {
        return Err(SceneError::setting(
            "render.background (--background)",
            format!("{background:?} is not a colour: give three finite linear RGB values ≥ 0"),
        ));
    }
    if let Some([lo, hi]) = desc.transfer.value_range {
        const NAME: &str = "transfer.value_range (--value-range)";
        range(NAME, lo, hi)?;
        if lo == hi {
            return Err(SceneError::setting(
                NAME,
                format!("[{lo}, {hi}] has zero width: the transfer function needs lo < hi"),
            ));
        }
    }
    refuse_settings_without_effect(desc)
}

/// The image size, samples per pixel and how rays march (step, rate, early
/// termination, packets, log scale, clip box) the description gives, over
/// the library's generic defaults for the data (the settings checked by
/// [`check_settings`]).
fn march_settings(
    volume: &VolumeSummary,
    frame: &WorldFrame,
    desc: &SceneDesc,
) -> Result<RenderSettings, SceneError> {
    check_settings(desc)?;
    let kind = volume.kind;
    let width = desc.image.width.unwrap_or(800);
    let height = desc.image.height.unwrap_or(600);
    let spp = desc.image.spp.unwrap_or(1);
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
        settings.step = Some(frame.length_to_local(step as f64));
    }
    if let Some(rate) = r.sampling_rate {
        settings.sampling_rate = rate;
    }
    if let Some(et) = r.early_termination {
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
    settings.seed = r.seed.unwrap_or(0);
    Ok(settings)
}

/// The defaults the data decides, from its `probe` when one was taken: the
/// value range (a percentile range of the field; a constant field shown as
/// a uniform medium) and the opacity scale (a typical ray reaches a target
/// optical depth); each said in `notes`.
fn data_defaults(
    volume: &VolumeSummary,
    frame: &WorldFrame,
    desc: &SceneDesc,
    probe: Option<&Probe>,
    tf: &TransferFunction,
    settings: &mut RenderSettings,
    notes: &mut Vec<String>,
) -> Result<(), SceneError> {
    let kind = volume.kind;
    let units = if settings.log_scale { "log10 " } else { "" };
    match desc.transfer.value_range {
        Some([lo, hi]) => {
            const NAME: &str = "transfer.value_range (--value-range)";
            // A range with lo < hi (check_settings).
            settings.value_range = range(NAME, lo, hi)?;
            above_the_data(volume.value_range, lo, settings.log_scale)?;
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
        constant_field(volume.value_range, settings, notes);
    }
    match desc.render.opacity_scale {
        Some(s) => {
            positive("render.opacity_scale (--opacity-scale)", s)?;
            // Extinction per world length → per local length.
            settings.opacity_scale = (s as f64 * frame.scale) as f32;
        }
        None => {
            if let Some(s) = probe.and_then(|p| p.opacity_scale(tf, settings)) {
                settings.opacity_scale = s;
                notes.push(format!(
                    "opacity scale {:.4e} per unit length (a typical ray through the data \
                     reaches optical depth {TARGET_OPTICAL_DEPTH}; set with --opacity-scale)",
                    s as f64 / frame.scale
                ));
            }
        }
    }
    Ok(())
}

/// Iso-surfaces (values in the transfer function's units), whether the
/// volume shows, and a tessellation's k-buffer budget.
fn iso_settings(
    kind: VolumeKind,
    desc: &SceneDesc,
    settings: &mut RenderSettings,
) -> Result<(), SceneError> {
    let r = &desc.render;
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
            let budget = EventBudget {
                k: at_least_one("tets.k (--k)", t.k.unwrap_or(16))?,
                layers: at_least_one("tets.layers (--layers)", t.layers.unwrap_or(64))?,
            };
            crate::budget::check_kbuffer_memory(budget.k, budget.layers)?;
            settings.event_budget = Some(budget);
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
    Ok(())
}

/// The box a default view frames: the part of `bounds` the transfer
/// function shows (the whole bounds with iso-surfaces, whose visibility
/// the probe cannot tell, or when it would barely shrink), said in `notes`
/// when it is smaller.
fn framed_box(
    bounds: Aabb,
    probe: &Probe,
    tf: &TransferFunction,
    settings: &RenderSettings,
    frame: &WorldFrame,
    notes: &mut Vec<String>,
) -> Aabb {
    if !settings.volume || !settings.iso.is_empty() {
        return bounds;
    }
    let Some(v) = probe.visible_box(tf, settings) else {
        return bounds;
    };
    let v = Aabb::new(v.min.max(bounds.min), v.max.min(bounds.max));
    let shrinks = (0..3).any(|a| v.extent()[a] < 0.9 * bounds.extent()[a]);
    if v.is_empty() || !shrinks {
        return bounds;
    }
    let (lo, hi) = (frame.to_world(v.min), frame.to_world(v.max));
    notes.push(format!(
        "the view frames the part of the data the transfer function shows, \
         [{:.4e}, {:.4e}, {:.4e}]..[{:.4e}, {:.4e}, {:.4e}] (give --eye/--look-at to \
         frame otherwise)",
        lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
    ));
    v
}

/// `framed` grown to hold the mirror instances: they belong in the picture.
fn with_instances(mut framed: Aabb, settings: &RenderSettings) -> Aabb {
    for m in &settings.mirrors {
        let (p, q) = (m.point(framed.min), m.point(framed.max));
        framed = framed.union(Aabb::new(p.min(q), p.max(q)));
    }
    framed
}

/// The light the description gives (its direction by default over the
/// camera's shoulder), with single scattering when it casts shadows.
fn light_settings(
    desc: &SceneDesc,
    camera: &Camera,
    frame: &WorldFrame,
    settings: &mut RenderSettings,
) -> Result<(), SceneError> {
    let Some(l) = &desc.light else {
        return Ok(());
    };
    let dir = match l.direction {
        Some(d) => Vec3::from_array(d).normalized(),
        None => default_light_direction(camera),
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
    Ok(())
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

/// Refuses a value range that starts far above the field's largest value
/// `data.hi` (in the transfer function's units: log10 when `log`): every
/// sample would be transparent and the image empty, which the render would
/// blame on the camera. "Far": beyond the data's own span above its maximum
/// (twice the maximum for a field ≥ 0), since the maximum is probed.
fn above_the_data(data: Range1, lo: f32, log: bool) -> Result<(), SceneError> {
    let top = if log {
        if !(data.hi > 0.0) {
            return Ok(());
        }
        data.hi.log10() + std::f32::consts::LOG10_2
    } else {
        data.hi + (data.hi - data.lo).max(data.hi.abs())
    };
    if top.is_finite() && lo > top {
        return Err(SceneError::setting(
            "transfer.value_range (--value-range)",
            format!(
                "starts at {lo:.4e}, above the field's largest value {}{:.4e}: every sample would \
                 be transparent; give a range that overlaps the data's [{:.4e}, {:.4e}]",
                if log { "(log10) " } else { "" },
                if log { data.hi.log10() } else { data.hi },
                data.lo,
                data.hi
            ),
        ));
    }
    Ok(())
}
