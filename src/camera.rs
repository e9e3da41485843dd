//! Views and what an image says about itself.
//!
//! - The **default view** ([`default_view`]) is a three-quarter view: the
//!   up vector is `camera.up` (default +z, the convention of SPH,
//!   cosmology and most CFD output), the eye looks across the data's
//!   longest horizontal side (so it runs across the image, left to right
//!   along +axis), from [`VIEW_AZIMUTH_DEG`] to its side and
//!   [`VIEW_ELEVATION_DEG`] above the horizontal, at the distance where
//!   every corner of the bounds lies inside the image with a margin.
//!
//! - Orbit, elevation and zoom ([`crate::CameraDesc`]) act on the camera the
//!   rest of the description gives (explicit or the default framing): orbit
//!   turns the eye about the up vector through the look-at point (positive
//!   angles towards the camera's right), elevation raises it towards the up
//!   vector (the result stays within ±89.9° of the horizontal, so the view
//!   never flips over the pole), and zoom divides its distance to the
//!   look-at point (orthographic cameras: the view height instead).
//!   [`Scene::reaim`] applies a new camera description to a resolved
//!   scene, which is how a turntable renders without reloading the data.
//! - [`Scene::colorbar`]: the range, scale and field name a colour bar
//!   shows.

use std::path::Path;

use voxless_core::{Aabb, Camera, Vec3};
use voxless_render::colorbar::ColorbarSpec;

use voxless_scene::{CameraDesc, SceneDesc};

use crate::load::positive;
use crate::{AnyVolume, Scene, SceneError};

/// Largest elevation reached, in degrees.
const MAX_ELEVATION_DEG: f64 = 89.9;
/// The default view's turn away from square-on to the long side, degrees.
pub const VIEW_AZIMUTH_DEG: f64 = 35.0;
/// The default view's height above the horizontal, degrees.
pub const VIEW_ELEVATION_DEG: f64 = 25.0;
/// The default view's vertical field of view, degrees.
pub const VIEW_FOV_DEG: f32 = 30.0;
/// Fraction of the image the default view's bounds may fill (each side
/// keeps half the rest as margin).
const VIEW_FILL: f64 = 0.92;

/// The default up vector: +z.
pub const DEFAULT_UP: [f32; 3] = [0.0, 0.0, 1.0];

/// The eye of the default view of `bounds` (local coordinates) for an
/// image of `aspect` = width / height, with `up` the up vector (unit) and
/// a perspective camera of `fov_y_deg` looking at the bounds' centre. Computed
/// in f64; `None` for empty or non-finite bounds.
pub(crate) fn default_eye(bounds: &Aabb, aspect: f32, up: Vec3, fov_y_deg: f32) -> Option<Vec3> {
    if bounds.is_empty() || !bounds.min.is_finite() || !bounds.max.is_finite() {
        return None;
    }
    let u = wide(up);
    let ul = dot(u, u).sqrt();
    if !(ul > 0.0 && ul.is_finite()) {
        return None;
    }
    let u = scale(u, 1.0 / ul);
    let lo = wide(bounds.min);
    let hi = wide(bounds.max);
    let centre: V3 = std::array::from_fn(|a| 0.5 * lo[a] + 0.5 * hi[a]);
    let ext: V3 = std::array::from_fn(|a| hi[a] - lo[a]);
    // The long horizontal direction: the world axis whose extent, seen in
    // the plane across the up vector, is longest (the first on ties).
    let flat = |a: usize| {
        let mut e = [0.0; 3];
        e[a] = 1.0;
        add(e, scale(u, -dot(e, u)))
    };
    let (mut best, mut h1) = (-1.0, [1.0, 0.0, 0.0]);
    for (a, &extent) in ext.iter().enumerate() {
        let f = flat(a);
        let len = dot(f, f).sqrt();
        if len > 1e-3 && extent * len > best * (1.0 + 1e-6) {
            best = extent * len;
            h1 = scale(f, 1.0 / len);
        }
    }
    if best < 0.0 {
        return None;
    }
    // Square-on to the long side from −h2 (so +h1 runs to the right), turned
    // by the azimuth and raised by the elevation.
    let h2 = cross(u, h1);
    let (sa, ca) = VIEW_AZIMUTH_DEG.to_radians().sin_cos();
    let (se, ce) = VIEW_ELEVATION_DEG.to_radians().sin_cos();
    let d = add(scale(add(scale(h2, -ca), scale(h1, -sa)), ce), scale(u, se));
    let forward = scale(d, -1.0);
    let right = {
        let r = cross(forward, u);
        scale(r, 1.0 / dot(r, r).sqrt())
    };
    let cam_up = cross(right, forward);
    let tan_y = (0.5 * (fov_y_deg as f64).to_radians()).tan() * VIEW_FILL;
    let tan_x = tan_y * aspect as f64;
    // Every corner c (relative to the centre) at depth D + c·forward must
    // satisfy |c·right| ≤ tan_x·depth and |c·up| ≤ tan_y·depth.
    let mut dist: f64 = 0.0;
    let diag = dot(ext, ext).sqrt();
    for k in 0..8 {
        let c: V3 =
            std::array::from_fn(|a| (if k >> a & 1 == 1 { hi[a] } else { lo[a] }) - centre[a]);
        let depth = dot(c, forward);
        dist = dist
            .max(dot(c, right).abs() / tan_x - depth)
            .max(dot(c, cam_up).abs() / tan_y - depth)
            // The eye stays outside the box.
            .max(0.05 * diag - depth);
    }
    if !(dist > 0.0) {
        // A point: any distance frames it; one that f32 can subtract.
        dist = centre
            .iter()
            .fold(1e-30f64, |m, c| m.max(c.abs() * 1e-3))
            .max(1e-6);
    }
    let eye = add(centre, scale(d, dist));
    let v = Vec3::new(eye[0] as f32, eye[1] as f32, eye[2] as f32);
    v.is_finite().then_some(v)
}

/// Orbit, elevation (degrees) and zoom, validated.
pub(crate) struct ViewAdjust {
    pub orbit: f32,
    pub elevation: f32,
    pub zoom: f32,
}

type V3 = [f64; 3];

fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn scale(a: V3, s: f64) -> V3 {
    a.map(|v| v * s)
}
fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn wide(v: Vec3) -> V3 {
    [v.x as f64, v.y as f64, v.z as f64]
}

impl ViewAdjust {
    pub fn from_desc(c: &CameraDesc) -> Result<Self, SceneError> {
        let angle = |field: &str, v: Option<f32>| match v {
            Some(x) if !x.is_finite() => Err(SceneError::setting(
                field,
                format!("{x} is not a finite angle in degrees"),
            )),
            _ => Ok(v.unwrap_or(0.0)),
        };
        let zoom = c.zoom.unwrap_or(1.0);
        positive("camera.zoom", zoom)?;
        Ok(ViewAdjust {
            orbit: angle("camera.orbit", c.orbit)?,
            elevation: angle("camera.elevation", c.elevation)?,
            zoom,
        })
    }

    /// `eye` orbited and raised about `look_at`, then (when `dolly`) moved
    /// towards it by the zoom. Computed in f64, so a quarter turn lands on
    /// the exact rotated position.
    pub fn place_eye(&self, eye: Vec3, look_at: Vec3, up: Vec3, dolly: bool) -> Vec3 {
        let zoom = if dolly { self.zoom } else { 1.0 };
        let u = wide(up);
        let ul = dot(u, u).sqrt();
        if (self.orbit == 0.0 && self.elevation == 0.0 && zoom == 1.0)
            || !(ul > 0.0 && ul.is_finite())
        {
            return eye;
        }
        let u = scale(u, 1.0 / ul);
        let centre = wide(look_at);
        let mut d = add(wide(eye), scale(centre, -1.0));
        if self.orbit != 0.0 {
            // Rodrigues: rotation by θ about the unit axis u.
            let (sin, cos) = sin_cos_deg(self.orbit as f64);
            d = add(
                add(scale(d, cos), scale(cross(u, d), sin)),
                scale(u, dot(u, d) * (1.0 - cos)),
            );
        }
        let dist = dot(d, d).sqrt();
        if self.elevation != 0.0 && dist > 0.0 {
            let along = dot(d, u);
            let flat = add(d, scale(u, -along));
            let fl = dot(flat, flat).sqrt();
            let horizontal = if fl > 1e-12 * dist {
                scale(flat, 1.0 / fl)
            } else {
                // Straight above or below: any horizontal direction will do.
                let other = if u[0].abs() < 0.9 {
                    [1.0, 0.0, 0.0]
                } else {
                    [0.0, 1.0, 0.0]
                };
                let h = cross(cross(u, other), u);
                scale(h, 1.0 / dot(h, h).sqrt())
            };
            let limit = MAX_ELEVATION_DEG.to_radians();
            let e = (along.atan2(fl) + (self.elevation as f64).to_radians()).clamp(-limit, limit);
            d = add(scale(horizontal, dist * e.cos()), scale(u, dist * e.sin()));
        }
        let d = scale(d, 1.0 / zoom as f64);
        let p = add(centre, d);
        Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)
    }
}

/// Sine and cosine of an angle in degrees, exact at multiples of 90° (so
/// quarter turns of a turntable land exactly).
fn sin_cos_deg(deg: f64) -> (f64, f64) {
    let r = deg.rem_euclid(360.0);
    match r {
        0.0 => (0.0, 1.0),
        90.0 => (1.0, 0.0),
        180.0 => (0.0, -1.0),
        270.0 => (-1.0, 0.0),
        _ => r.to_radians().sin_cos(),
    }
}

/// The light's default direction: over the camera's left shoulder.
pub(crate) fn default_light_direction(camera: &Camera) -> Vec3 {
    (camera.up * 0.6 - camera.right * 0.4 - camera.forward * 0.7).normalized()
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

impl Scene {
    /// Points the camera as `desc.camera` says (e.g. a turntable frame's
    /// orbit), keeping the data, image size and settings; a default light
    /// follows the camera.
    pub fn reaim(&mut self, desc: &SceneDesc) -> Result<(), SceneError> {
        let aspect = self.settings.width as f32 / self.settings.height as f32;
        self.camera = crate::resolve::camera(&desc.camera, &self.framed, aspect, &self.frame)?;
        let follows = desc.light.as_ref().is_some_and(|l| l.direction.is_none());
        if let Some(light) = &mut self.settings.light
            && follows
        {
            light.direction = default_light_direction(&self.camera);
            if let Some(sc) = &mut self.settings.scatter
                && let voxless_render::LightSource::Directional(d) = &mut sc.light
            {
                *d = light.direction;
            }
        }
        Ok(())
    }

    /// The name of the field the colours stand for, when known: the
    /// particle attribute (its file or column name; "temperature" for the
    /// demo) or "density", the AMR colour (else opacity) field, or "density"
    /// for a tessellation.
    pub fn colour_field_name(&self, desc: &SceneDesc) -> Option<String> {
        match &self.volume {
            AnyVolume::Particles(v) => {
                match desc.particles.as_ref().and_then(|p| p.attribute.as_deref()) {
                    Some(spec) => name_of(spec),
                    None if v.has_attribute() => Some("temperature".into()),
                    None => Some("density".into()),
                }
            }
            AnyVolume::Amr(v) => desc
                .amr
                .as_ref()
                .and_then(|a| a.color_field.clone().or_else(|| a.field.clone()))
                .or_else(|| v.field_names().first().cloned()),
            AnyVolume::Tets(..) => Some("density".into()),
            AnyVolume::Materials(_) => None,
        }
    }

    /// What a colour bar for this scene shows: the attribute range when
    /// colour comes from an attribute (or an AMR colour field), else the
    /// value range, in log10 units when the transfer function is in log scale.
    pub fn colorbar(&self, desc: &SceneDesc) -> ColorbarSpec {
        let st = &self.settings;
        let (range, log10) = match st.attribute_range {
            Some(r) => (r, false),
            None => (st.value_range, st.log_scale),
        };
        ColorbarSpec {
            lo: range.lo,
            hi: range.hi,
            log10,
            label: self.colour_field_name(desc),
        }
    }
}
