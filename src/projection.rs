//! Projection views: where a column-density image lies in the world.
//!
//! A projection integrates the volume's field along parallel lines — an
//! orthographic camera — through every pixel centre, over the whole line
//! (as far as the data reaches). This module turns what a user asks for
//! into that camera, in the volume's own frame, and keeps the image's
//! footprint in world coordinates (float64), so the pixel area that
//! `Σ pixels × pixel area = ∫ field dV` needs is exact. Every front-end (the
//! CLI's `project`, the Python package, its yt bridge) resolves projections
//! here, so they share defaults and image orientation.
//!
//! The model (image row 0 at the top, as everywhere):
//!
//! - **Axis** 0, 1 or 2: image axes (u, v) = (y, z), (x, z) or (x, y)
//!   ([`Camera::axis_projection`]); the image covers a box's extent in u and
//!   v. The box is `bounds` (default: the volume's bounds, the union of the
//!   particles' supports); `center` and `width` replace its u and v ranges.
//! - **Normal** n (off-axis): the image plane is perpendicular to n, its up
//!   direction is `north` made perpendicular to n, its right direction is
//!   `north × n` (a right-handed view from the +n side, as yt's
//!   `off_axis_projection`). The default north is yt's rule, so that n = x
//!   or n = z gives the axis projection's orientation. The image is centred
//!   on `center` (default: the box's centre) and covers `width` × `height`
//!   (default: the box's extent across the view, so nothing is cut off).
//!
//! Each pixel's line is integrated through all the data, or, with a
//! `depth`, over the slab of that thickness centred on the image plane
//! (kernels and cells are cut at its faces; this takes the per-pixel path).

use voxless_core::{Aabb, Camera, Cancelled, Control, Projection, Range1, Vec3};

use crate::AnyVolume;

use crate::{ImageDesc, PixelsName, SceneDesc, SceneError, WorldFrame};

/// What a projection is asked to show; every field is optional. World
/// coordinates are float64 (see [`WorldFrame`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ProjectionDesc {
    /// Look along this coordinate axis (0 = x, 1 = y, 2 = z); the default
    /// when no `normal` is given is z.
    pub axis: Option<usize>,
    /// Look along this direction instead (off-axis; need not be unit).
    pub normal: Option<[f64; 3]>,
    /// The image's up direction for a normal (need not be perpendicular to
    /// it, nor unit).
    pub north: Option<[f64; 3]>,
    /// World position of the image centre.
    pub center: Option<[f64; 3]>,
    /// World width and height the image covers.
    pub width: Option<[f64; 2]>,
    /// The world box `[x0, y0, z0, x1, y1, z1]` the image covers (default:
    /// the volume's bounds).
    pub bounds: Option<[f64; 6]>,
    /// Integrate only over a slab this thick centred on the image plane
    /// (default: the whole line).
    pub depth: Option<f64>,
}

/// A resolved projection: the camera and where its image lies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProjectionView {
    /// The orthographic camera, in the volume's frame.
    pub camera: Camera,
    /// World position of the image centre.
    pub center: [f64; 3],
    /// Unit vectors of increasing column (`right`) and decreasing row
    /// (`up`), and `normal` = `right × up`, towards the viewer (for the y
    /// axis projection, whose image axes are (x, z), that is −y).
    pub right: [f64; 3],
    pub up: [f64; 3],
    pub normal: [f64; 3],
    /// World width and height of the image.
    pub width: [f64; 2],
    /// The slab integrated, as a range of the camera rays' parameter (None:
    /// the whole line).
    pub t_range: Option<Range1>,
    /// World length of one unit of the volume's frame: the camera works in
    /// the frame, columns come out in world units.
    pub scale: f64,
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
fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}
fn unit(a: V3) -> V3 {
    let l = norm(a);
    a.map(|v| v / l)
}
fn to_vec3(a: V3) -> Vec3 {
    Vec3::new(a[0] as f32, a[1] as f32, a[2] as f32)
}

/// The size of a projection's image: `image.width × image.height`, 800×600
/// by default, each side in 1..=32768 — the sizes [`crate::resolve`] gives,
/// without resolving the rest of the view (so a particle volume's value
/// range, which only renders need, is never probed for a projection).
pub fn image_size(image: &ImageDesc) -> Result<(u32, u32), SceneError> {
    let width = image.width.unwrap_or(800);
    let height = image.height.unwrap_or(600);
    if width == 0 || height == 0 || width > 32768 || height > 32768 {
        return Err(SceneError::setting(
            "image size",
            format!("{width}×{height} is outside 1..=32768 per side"),
        ));
    }
    Ok((width, height))
}

/// The pixel integral a description asks for of its projections (pixel
/// centres by default: pixel areas keep every kernel's or tet's mass but
/// take 1.5–6× as long).
pub fn pixel_integral(p: Option<PixelsName>) -> voxless_core::PixelIntegral {
    match p.unwrap_or(PixelsName::Centre) {
        PixelsName::Area => voxless_core::PixelIntegral::Area,
        PixelsName::Centre => voxless_core::PixelIntegral::Centre,
    }
}

/// A note when a projection of `desc`'s data whose `Σ column × pixel
/// area` is `integral` misses the data's exact mass `mass` by more than
/// 0.1 %: part of the data lies outside the view, or (particles projected
/// through pixel centres) kernels narrower than a pixel are sampled, not
/// integrated.
pub fn mass_note(integral: f64, mass: f64, desc: &SceneDesc) -> Option<String> {
    let short = 1.0 - integral / mass;
    if !(mass > 0.0) || !(short.abs() > 1e-3) {
        return None;
    }
    let centres = desc
        .particles
        .as_ref()
        .is_some_and(|p| p.pixels != Some(PixelsName::Area));
    let why = if centres {
        "kernels narrower than a pixel are sampled at pixel centres (--pixels area \
         conserves their mass), or part of the data lies outside the view"
    } else {
        "part of the data lies outside the view"
    };
    Some(format!(
        "the projected mass differs from the data's by {:+.2} %: {why}",
        -100.0 * short
    ))
}

/// yt's default north for a view along `normal`: the coordinate axis `e`
/// whose `e × n` has the largest component sum gives east = `e × n`, and
/// north = `n × east`. Along x the image axes are (y, z) and along z (x, y),
/// as in the axis projections; along y they are (z, x).
pub fn default_north(normal: [f64; 3]) -> [f64; 3] {
    let n = unit(normal);
    let axes = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let score = |e: V3| cross(e, n).iter().sum::<f64>();
    // The first axis with the largest score (numpy's argmax keeps the first).
    let mut best = 0;
    for a in 1..3 {
        if score(axes[a]) > score(axes[best]) {
            best = a;
        }
    }
    let east = cross(axes[best], n);
    cross(n, east)
}

/// The ray parameters of a slab `depth` (world) thick centred on the plane
/// through `center` (local) across `camera`'s view (local).
fn slab(camera: &Camera, center: Vec3, depth: Option<f64>, frame: &WorldFrame) -> Option<Range1> {
    depth.map(|d| {
        let t = (center - camera.eye).dot(camera.forward) as f64;
        let half = 0.5 * frame.length_to_local(d) as f64;
        Range1::new((t - half) as f32, (t + half) as f32)
    })
}

fn finite(name: &str, v: &[f64]) -> Result<(), SceneError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(SceneError::setting(
            name,
            format!("{v:?} has a non-finite value"),
        ))
    }
}

/// The eight corners of a world box.
pub(crate) fn corners(lo: V3, hi: V3) -> impl Iterator<Item = V3> {
    (0..8).map(move |k| {
        [
            if k & 1 == 0 { lo[0] } else { hi[0] },
            if k & 2 == 0 { lo[1] } else { hi[1] },
            if k & 4 == 0 { lo[2] } else { hi[2] },
        ]
    })
}

impl crate::Loaded {
    /// `∫ field dV` in world units, when the volume knows it exactly.
    pub fn total_mass(&self) -> Option<f64> {
        self.volume
            .total_mass()
            .map(|m| m * self.frame.scale.powi(3))
    }

    /// Projects the volume through `projection` at `w` × `h` (see
    /// [`ProjectionView::project_on`]: `pixels` overrides the description's
    /// pixel rule, splats summed on `device`, notes for a front-end): the
    /// view and the column densities. The inner error is a cancelled
    /// projection.
    #[allow(clippy::too_many_arguments)]
    pub fn project_on(
        &self,
        projection: &ProjectionDesc,
        (w, h): (u32, u32),
        pixels: Option<voxless_core::PixelIntegral>,
        device: &crate::device::Device,
        control: &Control,
        notes: &mut Vec<String>,
    ) -> Result<Result<(ProjectionView, Vec<f32>), Cancelled>, SceneError> {
        let view = ProjectionView::new(projection, &self.volume.bounds(), &self.frame)?;
        view.check(&self.volume)?;
        Ok(view
            .project_on(&self.volume, w, h, pixels, device, control, notes)?
            .map(|column| (view, column)))
    }
}

impl ProjectionView {
    /// Resolves `desc` for a volume with `volume_bounds` (in its frame)
    /// whose frame is `frame`. Errors name the setting (`axis`, `normal`,
    /// `north`, `center`, `width`, `bounds`).
    pub fn new(
        desc: &ProjectionDesc,
        volume_bounds: &Aabb,
        frame: &WorldFrame,
    ) -> Result<ProjectionView, SceneError> {
        if let Some(b) = desc.bounds {
            finite("bounds", &b)?;
            if (0..3).any(|a| !(b[a] <= b[a + 3])) {
                return Err(SceneError::setting(
                    "bounds",
                    format!("{b:?} is not a box: each minimum must be ≤ its maximum"),
                ));
            }
        }
        if let Some(c) = desc.center {
            finite("center", &c)?;
        }
        if let Some(w) = desc.width
            && !w.iter().all(|v| v.is_finite() && *v > 0.0)
        {
            return Err(SceneError::setting(
                "width",
                format!("{w:?}: the width and height must be finite and > 0"),
            ));
        }
        if let Some(d) = desc.depth
            && !(d.is_finite() && d > 0.0)
        {
            return Err(SceneError::setting(
                "depth",
                format!("{d}: the depth must be finite and > 0"),
            ));
        }
        // The box the image covers by default, in world coordinates.
        let (lo, hi) = match desc.bounds {
            Some(b) => ([b[0], b[1], b[2]], [b[3], b[4], b[5]]),
            None => (
                frame.to_world(volume_bounds.min),
                frame.to_world(volume_bounds.max),
            ),
        };
        match (desc.axis, desc.normal) {
            (Some(_), Some(_)) => Err(SceneError::setting(
                "normal",
                "give either an axis or a normal, not both",
            )),
            (axis, None) => {
                if desc.north.is_some() {
                    return Err(SceneError::setting(
                        "north",
                        "applies to projections along a normal; an axis projection's \
                         orientation is fixed",
                    ));
                }
                Self::along_axis(desc, axis.unwrap_or(2), (lo, hi), volume_bounds, frame)
            }
            (None, Some(n)) => Self::along_normal(desc, n, (lo, hi), volume_bounds, frame),
        }
        .and_then(|view| view.meets(volume_bounds, frame))
    }

    /// The view, or an error when its image misses the data altogether (an
    /// all-zero map would look like empty space, not a wrong view).
    fn meets(self, volume_bounds: &Aabb, frame: &WorldFrame) -> Result<Self, SceneError> {
        let (lo, hi) = (
            frame.to_world(volume_bounds.min),
            frame.to_world(volume_bounds.max),
        );
        let corners = (0..8).map(|i| {
            [
                if i & 1 == 0 { lo[0] } else { hi[0] },
                if i & 2 == 0 { lo[1] } else { hi[1] },
                if i & 4 == 0 { lo[2] } else { hi[2] },
            ]
        });
        // The data's extent and the image's along each image axis.
        let span = |axis: V3| {
            corners
                .clone()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), c| {
                    let d = dot(c, axis);
                    (a.min(d), b.max(d))
                })
        };
        for (k, axis) in [self.right, self.up].into_iter().enumerate() {
            let (a, b) = span(axis);
            let c = dot(self.center, axis);
            let half = 0.5 * self.width[k];
            if c + half < a || c - half > b {
                return Err(SceneError::setting(
                    "bounds",
                    format!(
                        "the image ({}) misses the data, whose bounds are {lo:?} to {hi:?}: \
                         the map would be all zero",
                        if k == 0 { "across" } else { "up" }
                    ),
                ));
            }
        }
        Ok(self)
    }

    /// An axis projection covering the box, with `center` and `width`
    /// replacing its ranges across the view.
    fn along_axis(
        desc: &ProjectionDesc,
        axis: usize,
        (mut lo, mut hi): (V3, V3),
        volume_bounds: &Aabb,
        frame: &WorldFrame,
    ) -> Result<ProjectionView, SceneError> {
        let (u, v) = match axis {
            0 => (1, 2),
            1 => (0, 2),
            2 => (0, 1),
            _ => {
                return Err(SceneError::setting(
                    "axis",
                    format!("{axis} is not 0, 1 or 2 (x, y or z)"),
                ));
            }
        };
        let center = desc
            .center
            .unwrap_or(std::array::from_fn(|a| 0.5 * (lo[a] + hi[a])));
        if desc.center.is_some() || desc.width.is_some() {
            let w = desc.width.unwrap_or([hi[u] - lo[u], hi[v] - lo[v]]);
            for (k, a) in [u, v].into_iter().enumerate() {
                lo[a] = center[a] - 0.5 * w[k];
                hi[a] = center[a] + 0.5 * w[k];
            }
        }
        // The volume's own bounds when nothing moves them (no float64 round trip).
        let local = match (desc.bounds, desc.center, desc.width) {
            (None, None, None) => *volume_bounds,
            _ => frame.box_to_local([lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]]),
        };
        let camera = Camera::axis_projection(&local, axis)
            .map_err(|e| SceneError::setting("bounds", e.to_string()))?;
        let e = |a: usize| {
            let mut d = [0.0; 3];
            d[a] = 1.0;
            d
        };
        Ok(ProjectionView {
            camera,
            center,
            right: e(u),
            up: e(v),
            normal: cross(e(u), e(v)),
            width: [hi[u] - lo[u], hi[v] - lo[v]],
            t_range: slab(&camera, frame.to_local(center), desc.depth, frame),
            scale: frame.scale,
        })
    }

    /// An off-axis projection along `normal`.
    fn along_normal(
        desc: &ProjectionDesc,
        normal: V3,
        (lo, hi): (V3, V3),
        volume_bounds: &Aabb,
        frame: &WorldFrame,
    ) -> Result<ProjectionView, SceneError> {
        finite("normal", &normal)?;
        if !(norm(normal) > 0.0) {
            return Err(SceneError::setting("normal", "must not be zero"));
        }
        let n = unit(normal);
        let north = desc.north.unwrap_or_else(|| default_north(n));
        finite("north", &north)?;
        // The image's up: north without its component along the normal.
        let along = dot(north, n);
        let up_raw = sub(north, n.map(|c| c * along));
        if !(norm(up_raw) > 1e-9 * norm(north)) {
            return Err(SceneError::setting(
                "north",
                format!("{north:?} is parallel to the normal {normal:?} (or zero)"),
            ));
        }
        let up = unit(up_raw);
        let right = cross(up, n);
        let center = desc
            .center
            .unwrap_or(std::array::from_fn(|a| 0.5 * (lo[a] + hi[a])));
        // Default footprint: twice the farthest reach of the box's corners
        // from the centre, across the view, so the whole box is covered.
        let width = desc.width.unwrap_or_else(|| {
            let reach = |dir: V3| {
                corners(lo, hi)
                    .map(|c| dot(sub(c, center), dir).abs())
                    .fold(0.0, f64::max)
            };
            [2.0 * reach(right), 2.0 * reach(up)]
        });
        if !(width[0] > 0.0 && width[1] > 0.0) {
            return Err(SceneError::setting(
                "width",
                "the data has no extent across the view; give a width",
            ));
        }
        // The eye sits outside the volume on the +normal side; projections
        // integrate the whole line, so its distance only keeps every path
        // (the tessellations' screen mapping included) in front of it.
        let c = frame.to_local(center);
        let nl = to_vec3(n);
        let lo_local = volume_bounds.min.to_array().map(f64::from);
        let hi_local = volume_bounds.max.to_array().map(f64::from);
        let c64 = [c.x as f64, c.y as f64, c.z as f64];
        let reach = corners(lo_local, hi_local)
            .map(|p| dot(sub(p, c64), n))
            .fold(0.0, f64::max) as f32;
        let eye = c + nl * (reach + volume_bounds.diagonal().max(1.0));
        let camera = Camera {
            eye,
            right: to_vec3(right),
            up: to_vec3(up),
            forward: -nl,
            projection: Projection::Orthographic {
                half_width: frame.length_to_local(0.5 * width[0]),
                half_height: frame.length_to_local(0.5 * width[1]),
            },
        };
        Ok(ProjectionView {
            camera,
            center,
            right,
            up,
            normal: n,
            width,
            t_range: slab(&camera, c, desc.depth, frame),
            scale: frame.scale,
        })
    }

    /// The column density of `volume` through this view, row-major `h × w`,
    /// in world units: the volume's whole-line path, or one line integral
    /// per pixel over the slab.
    pub fn project(
        &self,
        volume: &AnyVolume,
        w: u32,
        h: u32,
        control: &Control,
    ) -> Result<Vec<f32>, Cancelled> {
        self.project_pixels(volume, w, h, None, control)
    }

    /// [`ProjectionView::project`] with each pixel integrated by `pixels`
    /// (particles; `None`: the volume's own rule). A slab (`depth`) always
    /// goes through pixel centres: [`crate::set_projection_pixels`] refuses
    /// the area with it.
    pub fn project_pixels(
        &self,
        volume: &AnyVolume,
        w: u32,
        h: u32,
        pixels: Option<voxless_core::PixelIntegral>,
        control: &Control,
    ) -> Result<Vec<f32>, Cancelled> {
        let local = match (self.t_range, pixels) {
            (None, None) => volume.project(&self.camera, w, h, control)?,
            (None, Some(p)) => volume.project_pixels(&self.camera, w, h, p, control)?,
            (Some(t), _) => volume.project_in(&self.camera, w, h, t, control)?,
        };
        // ∫ field dt with dt in the frame's units: in world units.
        Ok(self.in_world_units(local))
    }

    /// [`ProjectionView::project_pixels`] with particle splats summed on
    /// `device` where it can (see [`crate::device::Device::check_projection`]);
    /// what a front-end should say goes to `notes`. The outer error is the
    /// device's; the inner, a cancelled projection.
    #[allow(clippy::too_many_arguments)]
    pub fn project_on(
        &self,
        volume: &AnyVolume,
        w: u32,
        h: u32,
        pixels: Option<voxless_core::PixelIntegral>,
        device: &crate::device::Device,
        control: &Control,
        notes: &mut Vec<String>,
    ) -> Result<Result<Vec<f32>, Cancelled>, SceneError> {
        let orthographic = matches!(
            self.camera.projection,
            voxless_core::Projection::Orthographic { .. }
        );
        // A slab is one line integral per pixel, on the CPU.
        let slab = match (self.t_range, orthographic) {
            (Some(_), _) => Some("projections of a slab (--depth)"),
            (None, false) => Some("perspective projections"),
            (None, true) => None,
        };
        let whole = slab.is_none();
        device.check_projection(volume, slab, notes)?;
        if whole
            && let Some(r) = crate::device::project_particles(
                volume,
                &self.camera,
                (w, h),
                pixels,
                device,
                control,
            )
        {
            return Ok(r?.map(|local| self.in_world_units(local)));
        }
        Ok(self.project_pixels(volume, w, h, pixels, control))
    }

    /// Local column densities in world units (× the frame's scale).
    fn in_world_units(&self, local: Vec<f32>) -> Vec<f32> {
        if self.scale == 1.0 {
            local
        } else {
            local
                .iter()
                .map(|&c| (c as f64 * self.scale) as f32)
                .collect()
        }
    }

    /// Refuses what this view cannot do for `volume`: a slab through a
    /// periodic box more than [`voxless_particles::MAX_PERIODS`] boxes deep.
    pub fn check(&self, volume: &AnyVolume) -> Result<(), SceneError> {
        let periodic = match volume {
            AnyVolume::Particles(v) => v.periodic(),
            _ => None,
        };
        if let (Some(b), Some(t)) = (periodic, self.t_range) {
            let side = b.extent().min_elem() as f64;
            let periods = (t.hi as f64 - t.lo as f64) / side;
            if periods > voxless_particles::MAX_PERIODS {
                return Err(SceneError::setting(
                    "depth",
                    format!(
                        "the slab is {periods:.3e} periodic boxes deep; at most {} are integrated",
                        voxless_particles::MAX_PERIODS
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The world area of one pixel of a `w`×`h` image.
    pub fn pixel_area(&self, w: u32, h: u32) -> f64 {
        (self.width[0] / w as f64) * (self.width[1] / h as f64)
    }

    /// `Σ column × pixel area` of a `w`×`h` image: the mass (or the field's
    /// integral) the projection holds. Summed in f64 on eight running sums
    /// (one sum in order was a chain of a million dependent adds, ~1–4 ms
    /// at the end of every 1024² projection; eight are as accurate).
    pub fn integral(&self, column: &[f32], w: u32, h: u32) -> f64 {
        let mut sums = [0.0f64; 8];
        let lanes = column.chunks_exact(8);
        let rest: f64 = lanes.remainder().iter().map(|&c| c as f64).sum();
        for c in lanes {
            for (s, &c) in sums.iter_mut().zip(c) {
                *s += c as f64;
            }
        }
        (sums.iter().sum::<f64>() + rest) * self.pixel_area(w, h)
    }

    /// The world position of pixel (`row`, `col`)'s centre in a `w`×`h`
    /// image, on the plane through the image centre.
    pub fn pixel_center(&self, row: u32, col: u32, w: u32, h: u32) -> [f64; 3] {
        let x = ((col as f64 + 0.5) / w as f64 - 0.5) * self.width[0];
        let y = (0.5 - (row as f64 + 0.5) / h as f64) * self.width[1];
        std::array::from_fn(|a| self.center[a] + x * self.right[a] + y * self.up[a])
    }
}
