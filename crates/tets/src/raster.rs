//! Tile rasterisation of tets: which pixels a tet covers and where each
//! pixel's ray enters and leaves it.
//!
//! Per frame every block is projected to the screen and binned into the
//! tiles its box overlaps (block culling, paper §"Tiled rendering"). Per tile
//! and tet, the four face planes are built once; each covered pixel then
//! clips its ray against them (entering faces raise `t_in`, leaving faces
//! lower `t_out`).

use voxless_core::simd::{LANES, Lanes, PortableLanes};
use voxless_core::{Aabb, Camera, Projection, Ray, Vec3};

use crate::faces::FaceLanes;
pub use crate::frame::{BlockTets, Frame};
use crate::lattice::{max, min};
use crate::mesh::{Tet, TetMesh};

/// Side of a tile in pixels.
pub const TILE: u32 = 32;

/// Maps world points to continuous pixel coordinates.
#[derive(Clone, Copy)]
pub struct Screen {
    pub(crate) camera: Camera,
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// Perspective: tan(fov/2) (vertical) and aspect.
    tan_half: f32,
    aspect: f32,
}

impl Screen {
    pub fn new(camera: &Camera, width: u32, height: u32) -> Screen {
        let tan_half = match camera.projection {
            Projection::Perspective { fov_y_deg } => (fov_y_deg.to_radians() * 0.5).tan(),
            Projection::Orthographic { .. } => 0.0,
        };
        Screen {
            camera: *camera,
            width,
            height,
            tan_half,
            aspect: width as f32 / height as f32,
        }
    }

    /// Pixel coordinates of `p`, or `None` when it is at or behind the eye
    /// plane of a perspective camera (callers then assume full coverage).
    pub fn project(&self, p: Vec3) -> Option<(f32, f32)> {
        let c = &self.camera;
        let v = p - c.eye;
        let (sx, sy) = match c.projection {
            Projection::Perspective { .. } => {
                let z = v.dot(c.forward);
                if z <= 1e-6 {
                    return None;
                }
                (
                    v.dot(c.right) / (z * self.tan_half * self.aspect),
                    v.dot(c.up) / (z * self.tan_half),
                )
            }
            Projection::Orthographic {
                half_width,
                half_height,
            } => (v.dot(c.right) / half_width, v.dot(c.up) / half_height),
        };
        Some((
            (sx + 1.0) * 0.5 * self.width as f32,
            (1.0 - sy) * 0.5 * self.height as f32,
        ))
    }

    /// Inclusive pixel ranges `(x0, x1, y0, y1)` whose centres may lie in the
    /// projection of `points`, clipped to the image; `None` if empty.
    pub fn pixel_rect(&self, points: &[Vec3]) -> Option<(u32, u32, u32, u32)> {
        self.pixel_rect_padded(points, 0.0)
    }

    /// [`Screen::pixel_rect`] of the projection grown by `pad` pixels.
    pub fn pixel_rect_padded(&self, points: &[Vec3], pad: f32) -> Option<(u32, u32, u32, u32)> {
        let (mut x0, mut x1, mut y0, mut y1) = (
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::INFINITY,
            f32::NEG_INFINITY,
        );
        let mut grow = |(x, y): (f32, f32)| {
            x0 = min(x0, x);
            x1 = max(x1, x);
            y0 = min(y0, y);
            y1 = max(y1, y);
        };
        let mut behind = false;
        for &p in points {
            match self.project(p) {
                Some(q) => grow(q),
                None => behind = true,
            }
        }
        if behind {
            // Part of the convex hull is behind the eye: what is seen is the
            // part in front of a plane just ahead of the eye, whose outline is
            // the front points plus where hull edges cross that plane. All
            // points behind: nothing is seen.
            let c = &self.camera;
            let depth = |p: Vec3| (p - c.eye).dot(c.forward);
            const NEAR: f32 = 2e-6;
            for &a in points.iter().filter(|&&a| depth(a) > NEAR) {
                for &b in points.iter().filter(|&&b| depth(b) <= NEAR) {
                    let (za, zb) = (depth(a), depth(b));
                    let t = (za - NEAR * 1.5) / (za - zb);
                    if let Some(q) = self.project(a + (b - a) * t) {
                        grow(q);
                    }
                }
            }
            if x0 > x1 {
                return None;
            }
        }
        self.rect_of(x0 - pad, x1 + pad, y0 - pad, y1 + pad)
    }

    /// [`Screen::pixel_rect`] of a tet's vertices under an orthographic
    /// camera: the four projected at once, with the same operations, so the
    /// same rectangle.
    #[inline]
    fn ortho_rect(
        &self,
        v: &[Vec3; 4],
        half: (f32, f32),
        pad: f32,
    ) -> Option<(u32, u32, u32, u32)> {
        let (x0, x1, y0, y1) = self.ortho_extent(v, half);
        self.rect_of(x0 - pad, x1 + pad, y0 - pad, y1 + pad)
    }

    /// The continuous pixel coordinates of eight points under an
    /// orthographic camera, projected at once ([`Lanes`]; lane by lane the
    /// same operations as one point alone).
    #[inline(always)]
    fn ortho_lanes<L: Lanes>(
        &self,
        v: &[Vec3; LANES],
        half: (f32, f32),
    ) -> ([f32; LANES], [f32; LANES]) {
        let (c, s) = (&self.camera, L::splat);
        let dot = self.eye_dots::<L>(v);
        let (sx, sy) = (dot(c.right) / s(half.0), dot(c.up) / s(half.1));
        self.pixels(sx, sy)
    }

    /// `d ↦ (v − eye)·d` for the eight points in lanes, as
    /// [`Screen::project`] takes the dot products.
    #[inline(always)]
    fn eye_dots<L: Lanes>(&self, v: &[Vec3; LANES]) -> impl Fn(Vec3) -> L {
        let (e, s) = (self.camera.eye, L::splat);
        let x = L::from_array(v.map(|p| p.x)) - s(e.x);
        let y = L::from_array(v.map(|p| p.y)) - s(e.y);
        let z = L::from_array(v.map(|p| p.z)) - s(e.z);
        move |d: Vec3| x * s(d.x) + y * s(d.y) + z * s(d.z)
    }

    /// Continuous pixel coordinates of screen coordinates `(sx, sy)` in
    /// `[-1, 1]²` (x right, y up), as [`Screen::project`] maps them.
    #[inline(always)]
    fn pixels<L: Lanes>(&self, sx: L, sy: L) -> ([f32; LANES], [f32; LANES]) {
        let s = L::splat;
        let px = ((sx + s(1.0)) * s(0.5) * s(self.width as f32)).to_array();
        let py = ((s(1.0) - sy) * s(0.5) * s(self.height as f32)).to_array();
        (px, py)
    }

    /// [`Screen::ortho_lanes`] of a cell's eight corners.
    #[inline]
    pub(crate) fn ortho_points(&self, c: &[Vec3; 8], half: (f32, f32)) -> ([f32; 8], [f32; 8]) {
        self.ortho_lanes::<PortableLanes>(c, half)
    }

    /// [`Screen::project`] of eight points under a perspective camera, at
    /// once (lane by lane the same operations, so the same bits): their
    /// continuous pixel coordinates, and whether all eight are in front of
    /// the eye plane (else the coordinates of those behind are meaningless).
    #[inline(always)]
    fn perspective_lanes<L: Lanes>(&self, v: &[Vec3; LANES]) -> ([f32; LANES], [f32; LANES], bool) {
        let (c, s) = (&self.camera, L::splat);
        let dot = self.eye_dots::<L>(v);
        let depth = dot(c.forward);
        let behind = depth.le(s(1e-6)).any();
        let sx = dot(c.right) / (depth * s(self.tan_half) * s(self.aspect));
        let sy = dot(c.up) / (depth * s(self.tan_half));
        let (px, py) = self.pixels(sx, sy);
        (px, py, !behind)
    }

    /// [`Screen::perspective_lanes`] of a cell's eight corners.
    #[inline]
    pub(crate) fn perspective_points(&self, c: &[Vec3; 8]) -> ([f32; 8], [f32; 8], bool) {
        self.perspective_lanes::<PortableLanes>(c)
    }

    /// The continuous pixel extent `(x0, x1, y0, y1)` of four points under
    /// an orthographic camera, projected at once (the four in lanes 0–3 of
    /// [`Screen::ortho_lanes`], repeated in lanes 4–7).
    #[inline]
    fn ortho_extent(&self, v: &[Vec3; 4], half: (f32, f32)) -> (f32, f32, f32, f32) {
        let eight = [v[0], v[1], v[2], v[3], v[0], v[1], v[2], v[3]];
        let (px, py) = self.ortho_lanes::<PortableLanes>(&eight, half);
        let (mut x0, mut x1, mut y0, mut y1) = (px[0], px[0], py[0], py[0]);
        for k in 1..4 {
            (x0, x1) = (min(x0, px[k]), max(x1, px[k]));
            (y0, y1) = (min(y0, py[k]), max(y1, py[k]));
        }
        (x0, x1, y0, y1)
    }

    /// Whether the cube of half-size `r` about `c` may reach a pixel
    /// (centre, or square with `pad` 0.5) of the pixel rectangle `(x0, x1,
    /// y0, y1)`: a superset, with a pixel of slack for rounding — for
    /// culling, not drawing.
    #[inline]
    pub fn cube_meets(
        &self,
        c: Vec3,
        r: f32,
        pad: f32,
        (x0, x1, y0, y1): (u32, u32, u32, u32),
    ) -> bool {
        let cam = &self.camera;
        let v = c - cam.eye;
        let (w, h) = (self.width as f32, self.height as f32);
        let l1 = |d: Vec3| d.x.abs() + d.y.abs() + d.z.abs();
        // The cube's centre on screen and how far its points may be from it.
        let (px, py, rx, ry) = match cam.projection {
            Projection::Orthographic {
                half_width,
                half_height,
            } => {
                let (sx, sy) = (v.dot(cam.right) / half_width, v.dot(cam.up) / half_height);
                (
                    (sx + 1.0) * 0.5 * w,
                    (1.0 - sy) * 0.5 * h,
                    r * l1(cam.right) * 0.5 * w / half_width,
                    r * l1(cam.up) * 0.5 * h / half_height,
                )
            }
            Projection::Perspective { .. } => {
                // A point δ (|δ| ≤ ρ = r√3) off a centre at depth z with
                // screen offset u moves on screen by at most
                // f·ρ·(1 + |u|/z)/(z − ρ), f the focal length in pixels.
                let rho = r * 3f32.sqrt();
                let z = v.dot(cam.forward);
                if !(z - rho > 1e-6 * z.abs().max(1.0)) {
                    return true;
                }
                let f = 0.5 * h / self.tan_half;
                let (u, t) = (v.dot(cam.right), v.dot(cam.up));
                (
                    0.5 * w + f * u / z,
                    0.5 * h - f * t / z,
                    f * rho * (1.0 + u.abs() / z) / (z - rho),
                    f * rho * (1.0 + t.abs() / z) / (z - rho),
                )
            }
        };
        let (rx, ry) = (rx + pad + 1.0, ry + pad + 1.0);
        // Pixel x's centre is at x + 0.5. NaN (a degenerate view) keeps.
        !(px - rx > x1 as f32 + 0.5
            || px + rx < x0 as f32 + 0.5
            || py - ry > y1 as f32 + 0.5
            || py + ry < y0 as f32 + 0.5)
    }

    /// The pixels whose centres lie in `[x0, x1] × [y0, y1]`, clipped to the
    /// image.
    #[inline]
    pub(crate) fn rect_of(
        &self,
        x0: f32,
        x1: f32,
        y0: f32,
        y1: f32,
    ) -> Option<(u32, u32, u32, u32)> {
        // Pixel c's centre is c + 0.5. Clamped to [-1, n] before rounding
        // (NaN to the side `ceil`/`floor` then `max`/`min` would take it):
        // the same rectangle, with the rounding done through i32.
        let lo = |v: f32, n: u32| ceil_small((v - 0.5).max(-1.0).min(n as f32)).max(0.0);
        let hi =
            |v: f32, n: u32| floor_small((v - 0.5).min(n as f32).max(-1.0)).min(n as f32 - 1.0);
        let (ax, bx) = (lo(x0, self.width), hi(x1, self.width));
        let (ay, by) = (lo(y0, self.height), hi(y1, self.height));
        if !(ax <= bx && ay <= by) {
            return None;
        }
        Some((ax as u32, bx as u32, ay as u32, by as u32))
    }

    /// [`Screen::pixel_rect`] of a tet's four vertices.
    #[inline]
    pub fn tet_rect(&self, v: &[Vec3; 4]) -> Option<(u32, u32, u32, u32)> {
        self.tet_rect_padded(v, 0.0)
    }

    /// [`Screen::tet_rect`] grown by `pad` pixels on every side before
    /// rounding (0.5: every pixel whose square meets the tet's outline,
    /// which rays jittered over the pixel can hit).
    #[inline]
    pub fn tet_rect_padded(&self, v: &[Vec3; 4], pad: f32) -> Option<(u32, u32, u32, u32)> {
        match self.camera.projection {
            Projection::Orthographic {
                half_width,
                half_height,
            } => self.ortho_rect(v, (half_width, half_height), pad),
            Projection::Perspective { .. } => self.pixel_rect_padded(v, pad),
        }
    }

    pub fn width(&self) -> u32 {
        self.width
    }
    pub fn height(&self) -> u32 {
        self.height
    }

    pub fn ray(&self, x: u32, y: u32) -> Ray {
        self.camera
            .ray(x as f32 + 0.5, y as f32 + 0.5, self.width, self.height)
    }
}

/// `v.floor()` for |v| < 2³¹, up to the sign of a zero (inlined; without
/// SSE4.1 `floor` is a call).
#[inline(always)]
fn floor_small(v: f32) -> f32 {
    let t = v as i32 as f32;
    if t > v { t - 1.0 } else { t }
}

/// `v.ceil()` for |v| < 2³¹, up to the sign of a zero.
#[inline(always)]
fn ceil_small(v: f32) -> f32 {
    let t = v as i32 as f32;
    if t < v { t + 1.0 } else { t }
}

/// The eight corners of a box.
pub(crate) fn corners(b: &Aabb) -> [Vec3; 8] {
    let mut out = [b.min; 8];
    for (i, c) in out.iter_mut().enumerate() {
        *c = Vec3::new(
            if i & 1 == 0 { b.min.x } else { b.max.x },
            if i & 2 == 0 { b.min.y } else { b.max.y },
            if i & 4 == 0 { b.min.z } else { b.max.z },
        );
    }
    out
}

/// A tet's projected vertices. The projection of a tet is the convex hull of
/// its four projected vertices, and a horizontal line meets that hull exactly
/// where it meets the six vertex-to-vertex segments, so a row's covered span
/// is the min and max of those crossings.
struct Outline([(f32, f32); 4]);

/// Pixels of slack on each side of a row span, so rounding never drops a
/// pixel the exact 3D test would accept.
const OUTLINE_SLACK: f32 = 1e-3;

impl Outline {
    fn new(screen: &Screen, tet: &Tet) -> Option<Outline> {
        let mut p = [(0.0, 0.0); 4];
        for (slot, v) in p.iter_mut().zip(&tet.v) {
            *slot = screen.project(*v)?;
        }
        Some(Outline(p))
    }

    /// The x-span covered at height `yc`, if any.
    #[inline]
    fn row(&self, yc: f32) -> Option<(f32, f32)> {
        let p = &self.0;
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for (i, j) in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)] {
            let ((ax, ay), (bx, by)) = (p[i], p[j]);
            if (ay - yc) * (by - yc) > 0.0 {
                continue;
            }
            if ay == by {
                lo = min(lo, min(ax, bx));
                hi = max(hi, max(ax, bx));
            } else {
                let x = ax + (yc - ay) / (by - ay) * (bx - ax);
                lo = min(lo, x);
                hi = max(hi, x);
            }
        }
        (lo <= hi).then_some((lo - OUTLINE_SLACK, hi + OUTLINE_SLACK))
    }
}

/// Per ray, the parametric range inside the periodic box and in front of the
/// eye: the images of box-crossing tets fill the box exactly, so only that
/// range may be integrated.
pub fn box_spans(mesh: &TetMesh, rays: &[Ray]) -> Vec<(f32, f32)> {
    let b = Aabb::new(Vec3::ZERO, Vec3::splat(mesh.box_size));
    rays.iter()
        .map(|r| {
            let t = b.clip_ray(r, voxless_core::Range1::new(0.0, f32::INFINITY));
            if t.is_empty() {
                (1.0, 0.0)
            } else {
                (t.lo, t.hi)
            }
        })
        .collect()
}

/// The four face planes of a tet, `n·x ≤ c` inside.
#[derive(Clone, Copy, Debug)]
pub struct Planes {
    n: [Vec3; 4],
    c: [f32; 4],
}

impl Planes {
    pub fn new(t: &Tet) -> Planes {
        let v = &t.v;
        let mut n = [Vec3::ZERO; 4];
        let mut c = [0.0; 4];
        for f in 0..4 {
            // Face opposite vertex f.
            let (a, b, d) = (v[(f + 1) % 4], v[(f + 2) % 4], v[(f + 3) % 4]);
            let mut normal = (b - a).cross(d - a);
            if normal.dot(v[f] - a) > 0.0 {
                normal = -normal;
            }
            n[f] = normal;
            c[f] = normal.dot(a);
        }
        Planes { n, c }
    }

    /// Affine per-pixel crossings for the orthographic `screen`.
    pub fn linear(&self, screen: &Screen) -> LinearPlanes {
        // Ray origins are affine in the pixel index: o(x, y) = o0 + x·dx + y·dy.
        let o0 = screen.ray(0, 0).origin;
        let dx = screen.ray(1, 0).origin - o0;
        let dy = screen.ray(0, 1).origin - o0;
        let dir = screen.camera.forward;
        let mut coef = [[0.0; 3]; 4];
        let mut kind = [0i8; 4];
        for f in 0..4 {
            let nd = self.n[f].dot(dir);
            let d0 = self.c[f] - self.n[f].dot(o0);
            let (ddx, ddy) = (-self.n[f].dot(dx), -self.n[f].dot(dy));
            if nd != 0.0 {
                let inv = 1.0 / nd;
                coef[f] = [d0 * inv, ddx * inv, ddy * inv];
                kind[f] = if nd > 0.0 { 1 } else { -1 };
            } else {
                coef[f] = [d0, ddx, ddy];
            }
        }
        LinearPlanes { coef, kind }
    }

    /// The parametric range of `ray` inside the tet, possibly empty.
    #[inline]
    pub fn clip(&self, ray: &Ray) -> (f32, f32) {
        let (mut t0, mut t1) = (f32::NEG_INFINITY, f32::INFINITY);
        for f in 0..4 {
            let nd = self.n[f].dot(ray.dir);
            let dist = self.c[f] - self.n[f].dot(ray.origin);
            if nd > 0.0 {
                t1 = t1.min(dist / nd);
            } else if nd < 0.0 {
                t0 = t0.max(dist / nd);
            } else if dist < 0.0 {
                return (1.0, 0.0);
            }
        }
        (t0, t1)
    }
}

/// Calls `f(tet, rect)` for every tet of tile `tile`'s blocks (at the
/// level of detail chosen for its block) whose pixel rectangle meets the
/// tile, with `rect = (x0, x1, y0, y1)` clipped to the tile.
pub fn for_each_tet(
    mesh: &TetMesh,
    frame: &Frame,
    tile: u32,
    mut f: impl FnMut(&Tet, (u32, u32, u32, u32)),
) {
    let (tx0, ty0, w, h) = frame.tile(tile);
    let mut block = BlockTets::default();
    for &entry in &frame.bins[tile as usize] {
        frame.block_into(mesh, entry, tile, &mut block);
        for (tet, r) in block.tets.iter().zip(&block.rects) {
            let (x0, x1) = ((r[0] as u32).max(tx0), (r[1] as u32).min(tx0 + w - 1));
            let (y0, y1) = ((r[2] as u32).max(ty0), (r[3] as u32).min(ty0 + h - 1));
            f(tet, (x0, x1, y0, y1));
        }
    }
}

/// Calls `visit(local_pixel_index, t_in, t_out, density)` for every pixel of
/// tile `tile` whose ray crosses a tet of the tile's blocks, with
/// `[t_in, t_out]` clipped to the pixel's `spans` entry (the part of its ray
/// inside the periodic box, in front of the eye).
pub fn for_each_crossing(
    mesh: &TetMesh,
    frame: &Frame,
    tile: u32,
    rays: &[Ray],
    spans: &[(f32, f32)],
    mut visit: impl FnMut(usize, f32, f32, f32),
) {
    for_each_tet(mesh, frame, tile, |tet, rect| {
        clip_tet(frame, tile, tet, rect, rays, spans, &mut visit)
    });
}

/// [`for_each_crossing`] for rays anywhere inside their pixels (jittered
/// passes, with a [`Frame::covering`] frame): every pixel of each tet's
/// rectangle clips its own ray against the tet's planes — no outline or
/// pixel-centre shortcut.
pub fn for_each_crossing_jittered(
    mesh: &TetMesh,
    frame: &Frame,
    tile: u32,
    rays: &[Ray],
    spans: &[(f32, f32)],
    mut visit: impl FnMut(usize, f32, f32, f32),
) {
    let (tx0, ty0, w, _) = frame.tile(tile);
    for_each_tet(mesh, frame, tile, |tet, (x0, x1, y0, y1)| {
        let planes = Planes::new(tet);
        for y in y0..=y1 {
            for x in x0..=x1 {
                let local = ((y - ty0) * w + (x - tx0)) as usize;
                let (t0, t1) = planes.clip(&rays[local]);
                let (t0, t1) = (t0.max(spans[local].0), t1.min(spans[local].1));
                if t1 > t0 {
                    visit(local, t0, t1, tet.density);
                }
            }
        }
    });
}

/// Pixels in a tet's rectangle up to which every pixel is clipped without
/// the outline: for the sub-pixel tets of a distant view (a 256³ render:
/// 55 % of the tets have at most two pixel centres in their rectangle) the
/// outline's four projections and per-row edge crossings cost more than the
/// clips they save (render ×0.82 with 16, ×0.90 with 2); on close-ups,
/// where tets cover tens of pixels, it still pays (no outline at all:
/// ×1.06 there).
const SMALL_RECT: u32 = 16;

/// The pixels of `rect` whose rays cross `tet`, by clipping each ray against
/// the tet's planes (when the rectangle holds more than [`SMALL_RECT`]
/// pixels, only those inside its projected outline are tried).
pub fn clip_tet(
    frame: &Frame,
    tile: u32,
    tet: &Tet,
    rect: (u32, u32, u32, u32),
    rays: &[Ray],
    spans: &[(f32, f32)],
    visit: &mut impl FnMut(usize, f32, f32, f32),
) {
    let (tx0, ty0, w, _) = frame.tile(tile);
    let (x0, x1, y0, y1) = rect;
    let perspective = matches!(
        frame.screen.camera.projection,
        Projection::Perspective { .. }
    );
    // The tet's screen outline: pixels outside it need no 3D test.
    let small = (x1 - x0 + 1) * (y1 - y0 + 1) <= SMALL_RECT;
    let outline = if small {
        None
    } else {
        Outline::new(&frame.screen, tet)
    };
    let row_span = |y: u32| -> Option<(u32, u32)> {
        let (xa, xb) = match &outline {
            Some(o) => {
                let (a, b) = o.row(y as f32 + 0.5)?;
                // Clamped to the rectangle (and a pixel past it) before
                // rounding, through i32 (`ceil` is a call without SSE4.1).
                let (lo, hi) = (x0 as f32, x1 as f32);
                (
                    ceil_small((a - 0.5).max(lo).min(hi + 1.0)) as u32,
                    floor_small((b - 0.5).min(hi).max(-1.0)) as u32,
                )
            }
            None => (x0, x1),
        };
        (xa <= xb).then_some((xa, xb))
    };
    if perspective {
        // Rays share their origin: its plane distances once per tet, the
        // four faces in lanes.
        let faces = FaceLanes::new(tet);
        let dist = faces.with_origin(frame.screen.camera.eye);
        for y in y0..=y1 {
            let Some((xa, xb)) = row_span(y) else {
                continue;
            };
            for x in xa..=xb {
                let local = ((y - ty0) * w + (x - tx0)) as usize;
                let (t0, t1) = faces.clip_from(dist, rays[local].dir);
                let (t0, t1) = (t0.max(spans[local].0), t1.min(spans[local].1));
                if t1 > t0 {
                    visit(local, t0, t1, tet.density);
                }
            }
        }
    } else {
        // Parallel rays: each face's crossing t is an affine function of the
        // pixel position, so a pixel costs a few multiply-adds, no division.
        let lin = Planes::new(tet).linear(&frame.screen);
        for y in y0..=y1 {
            let Some((xa, xb)) = row_span(y) else {
                continue;
            };
            for x in xa..=xb {
                let local = ((y - ty0) * w + (x - tx0)) as usize;
                let (t0, t1) = lin.clip(x as f32, y as f32);
                let (t0, t1) = (t0.max(spans[local].0), t1.min(spans[local].1));
                if t1 > t0 {
                    visit(local, t0, t1, tet.density);
                }
            }
        }
    }
}

/// A tet's face crossings as affine functions of the pixel position, for
/// orthographic views: `t_f(x, y) = a_f + b_f·x + c_f·y`, entering faces
/// (`n·d < 0`) raising `t_in`, leaving faces lowering `t_out`, and faces
/// parallel to the view giving an inside test `d_f(x, y) ≥ 0` instead.
pub struct LinearPlanes {
    coef: [[f32; 3]; 4],
    kind: [i8; 4],
}

impl LinearPlanes {
    #[inline]
    pub fn clip(&self, x: f32, y: f32) -> (f32, f32) {
        let (mut t0, mut t1) = (f32::NEG_INFINITY, f32::INFINITY);
        for f in 0..4 {
            let [a, b, c] = self.coef[f];
            let v = a + b * x + c * y;
            match self.kind[f] {
                1 => t1 = t1.min(v),
                -1 => t0 = t0.max(v),
                _ if v < 0.0 => return (1.0, 0.0),
                _ => {}
            }
        }
        (t0, t1)
    }
}
