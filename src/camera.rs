//! The camera: what a description's `[camera]` table (and its defaults)
//! becomes, in the volume's frame ([`camera`]).
//!
//! - The **default view** is a three-quarter view: the
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
//!   [`crate::Resolved::reaim`] applies a new camera description to a
//!   resolved view, which is how a turntable renders without reloading the
//!   data.

use voxless_core::{Aabb, Camera, Projection, Vec3};
use voxless_scene::{CameraDesc, ProjectionName};

use crate::checks::positive;
use crate::{SceneError, WorldFrame};

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
