//! The column-density projection for orthographic cameras, eight pixels of a
//! row at a time.
//!
//! With parallel rays the ray parameter at which a ray meets a face plane is
//! an affine function of the pixel position. Per tile and tet, the tet is
//! mapped to screen space — pixel offsets `(i, j)` from the first pixel of its
//! rectangle in the tile, ray parameters relative to its vertex 0 — and each
//! face becomes `t_f(i, j) = a_f + c_f·j + b_f·i`. Faces whose outward normal
//! points against the rays are entering, the others leaving; a
//! non-degenerate tet has one to three of each, and the faces are sorted into
//! slots, entering first, so that with `E` entering faces
//!
//! ```text
//! t_in = max(t_0 … t_{E−1}),   t_out = min(t_E … t_3)
//! ```
//!
//! with no branch per face or pixel (one code path per `E`). A row of the
//! tet's rectangle is evaluated eight pixels at a time: lanes with
//! `t_out > t_in` add `ρ·(t_out − t_in)` to an f32 tile accumulator, which
//! is added to the tile's f64 sums every [`FLUSH`] tets. The range along the
//! ray inside the periodic box is only applied to tets that reach out of
//! the range common to all of the tile's rays.
//!
//! Three kernels evaluate the same operations in the same order (no fused
//! multiply-add), so they find the same crossings bit for bit: a scalar
//! reference (f64 sums per crossing) and one row kernel written once over
//! [`voxless_core::simd::Lanes`], compiled for portable `wide` lanes and for
//! AVX2; a [`Simd`] value picks one (`Auto`: AVX2 where the CPU has it). Tets with a face parallel to the rays (exactly, or too
//! close for finite coefficients) go through a scalar loop with an inside
//! test for that face, the same in every kernel.
//!
//! Rounding: vertex 0's pixel position is computed in f64, everything else
//! in f32 relative to it. A face nearly parallel to the rays makes the chord
//! sensitive to the pixel position (at 1e-7 of the box, a chord error of
//! ~250× that for a face 0.2° off the view direction); the full per-ray clip
//! of [`crate::render::TetOptions::clip_only`] rounds its ray origins there,
//! this path only its vertex differences.

use voxless_core::simd::{LANES, Lanes, PortableLanes, Simd, WithLanes, dispatch};
use voxless_core::{Camera, Projection, Vec3};

use crate::mesh::{Tet, TetMesh};
use crate::raster::{BlockTets, Frame};

/// Tets accumulated in f32 before the tile's f64 sums take them over.
const FLUSH: usize = 256;

/// How the pixels of a tet's rows are evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kernel {
    /// One pixel at a time, f64 sums: the reference the others are tested
    /// against.
    #[cfg_attr(not(test), allow(dead_code))]
    Scalar,
    /// Eight pixels at a time on the lanes the value resolves to
    /// ([`Simd::resolve`]).
    Lanes(Simd),
}

/// Three f64 components.
type D3 = [f64; 3];

#[inline(always)]
fn d3(v: Vec3) -> D3 {
    [v.x as f64, v.y as f64, v.z as f64]
}
#[inline(always)]
fn sub(a: D3, b: D3) -> D3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
#[inline(always)]
fn dot(a: D3, b: D3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
#[inline(always)]
fn cross(a: D3, b: D3) -> D3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// World point → (pixel x, pixel y, ray parameter) of an orthographic view,
/// with pixel `x`'s centre at continuous coordinate `x` (ray `(x, y)` of
/// [`crate::raster::Screen::ray`]): in f64 for points, in f32 for the
/// differences of a tet's vertices.
#[derive(Clone, Copy, Debug)]
pub(crate) struct OrthoMap {
    eye: D3,
    ex: D3,
    ey: D3,
    ez: D3,
    cx: f64,
    cy: f64,
    /// `ex`, `ey`, `ez` in f32, for vertex differences.
    fx: Vec3,
    fy: Vec3,
    fz: Vec3,
}

impl OrthoMap {
    /// `None` for a perspective camera or a degenerate basis.
    pub(crate) fn new(camera: &Camera, width: u32, height: u32) -> Option<OrthoMap> {
        let Projection::Orthographic {
            half_width,
            half_height,
        } = camera.projection
        else {
            return None;
        };
        // Ray (x, y) starts at eye + right·(sx·hw) + up·(sy·hh) and runs along
        // forward; the dual basis of (right, up, forward) inverts that.
        let (r, u, f) = (d3(camera.right), d3(camera.up), d3(camera.forward));
        let det = dot(r, cross(u, f));
        let dual = |a: D3, b: D3, k: f64| cross(a, b).map(|c| c / det * k);
        // sx = 2(x + 0.5)/W − 1, sy = 1 − 2(y + 0.5)/H.
        let kx = width as f64 / (2.0 * half_width as f64);
        let ky = height as f64 / (2.0 * half_height as f64);
        let (ex, ey, ez) = (dual(u, f, kx), dual(f, r, -ky), dual(r, u, 1.0));
        let f32s = |v: D3| Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32);
        let (fx, fy, fz) = (f32s(ex), f32s(ey), f32s(ez));
        let finite = fx.is_finite() && fy.is_finite() && fz.is_finite() && camera.eye.is_finite();
        (finite && det != 0.0).then_some(OrthoMap {
            eye: d3(camera.eye),
            ex,
            ey,
            ez,
            cx: width as f64 * 0.5 - 0.5,
            cy: height as f64 * 0.5 - 0.5,
            fx,
            fy,
            fz,
        })
    }
}

impl OrthoMap {
    /// World point `p` (f64) → `(u, v, t)`: pixel coordinates relative to
    /// pixel `reference` with pixel `(i, j)` the square `[i, i+1] ×
    /// [j, j+1]`, and the ray parameter.
    #[inline]
    pub(crate) fn uvt(&self, p: D3, (ref_x, ref_y): (u32, u32)) -> D3 {
        let d = sub(p, self.eye);
        [
            dot(d, self.ex) + self.cx + 0.5 - ref_x as f64,
            dot(d, self.ey) + self.cy + 0.5 - ref_y as f64,
            dot(d, self.ez),
        ]
    }
}

/// A tet seen from a reference pixel: vertex 0 at pixel offset `(x0, y0)`
/// and ray parameter `t_ref` (computed in f64: an error here would shift
/// the whole tet across the pixel grid, which steep faces turn into large
/// chord errors); `q[k]` is vertex k − vertex 0 in (pixels x, pixels y, ray
/// parameter).
#[derive(Clone, Copy, Debug)]
struct Local {
    x0: f64,
    y0: f64,
    t_ref: f64,
    q: [Vec3; 4],
}

impl Local {
    /// `tet` seen from pixels `(ref_x + i, ref_y + j)`.
    #[inline(always)]
    fn new(map: &OrthoMap, tet: &Tet, ref_x: u32, ref_y: u32) -> Local {
        let v = &tet.v;
        let p0 = sub(d3(v[0]), map.eye);
        let dir = |p: Vec3| {
            let d = p - v[0];
            Vec3::new(d.dot(map.fx), d.dot(map.fy), d.dot(map.fz))
        };
        Local {
            x0: dot(p0, map.ex) + map.cx - ref_x as f64,
            y0: dot(p0, map.ey) + map.cy - ref_y as f64,
            t_ref: dot(p0, map.ez),
            q: [Vec3::ZERO, dir(v[1]), dir(v[2]), dir(v[3])],
        }
    }

    /// The tet's range of ray parameters, relative to `t_ref`.
    #[inline(always)]
    fn t_range(&self) -> (f32, f32) {
        let q = &self.q;
        (
            q[1].z.min(q[2].z).min(q[3].z).min(0.0),
            q[1].z.max(q[2].z).max(q[3].z).max(0.0),
        )
    }
}

/// Slot order per mask of entering faces: entering faces first.
const ORDER: [[u8; 4]; 16] = {
    let mut t = [[0u8; 4]; 16];
    let mut m = 0;
    while m < 16 {
        let mut n = 0;
        let mut pass = 0;
        while pass < 2 {
            let mut k = 0;
            while k < 4 {
                if ((m >> k) & 1 == 1) == (pass == 0) {
                    t[m][n] = k as u8;
                    n += 1;
                }
                k += 1;
            }
            pass += 1;
        }
        m += 1;
    }
    t
};

/// A tet's faces in slots, as affine functions `a + c·j + b·i` of the pixel
/// offset from the reference pixel, ray parameters relative to `t_ref`.
#[derive(Clone, Copy, Debug)]
struct Faces {
    a: [f32; 4],
    b: [f32; 4],
    c: [f32; 4],
    /// Faces in slots `..entering` enter (1 to 3), the others leave.
    entering: usize,
    t_ref: f32,
}

/// The four faces' values in lanes 0–3 (repeated in lanes 4–7, which are
/// computed alongside and ignored): each lane's arithmetic is that of one
/// face alone.
#[inline(always)]
fn faces4<V: Lanes>(a: f32, b: f32, c: f32, d: f32) -> V {
    V::from_array([a, b, c, d, a, b, c, d])
}

/// Mask of the lanes holding a finite value (false on ±∞ and NaN).
#[inline(always)]
fn finite<V: Lanes>(x: V) -> V {
    x.abs().lt(V::splat(f32::INFINITY))
}

/// The faces' lanes 0–3.
const FACES: u32 = 0b1111;

impl Faces {
    /// `None` when a face is parallel to the rays (or too close to it for
    /// finite coefficients), or the tet is flat. The four faces are
    /// computed at once in lanes `V` (the same bits on every lane type).
    #[inline(always)]
    fn new<V: Lanes>(t: &Local) -> Option<Faces> {
        let [_, q1, q2, q3] = t.q;
        let s = V::splat;
        // Face k (opposite vertex k) spans A × B from corner P: P = q1 for
        // face 0, vertex 0 (the origin) for the others. Pointing out of the
        // tet when det = q1·(q2 × q3) > 0, into it when det < 0.
        let ax = faces4::<V>(q2.x - q1.x, q3.x, q1.x, q2.x);
        let ay = faces4::<V>(q2.y - q1.y, q3.y, q1.y, q2.y);
        let az = faces4::<V>(q2.z - q1.z, q3.z, q1.z, q2.z);
        let bx = faces4::<V>(q3.x - q1.x, q2.x, q3.x, q1.x);
        let by = faces4::<V>(q3.y - q1.y, q2.y, q3.y, q1.y);
        let bz = faces4::<V>(q3.z - q1.z, q2.z, q3.z, q1.z);
        let nx = ay * bz - az * by;
        let ny = az * bx - ax * bz;
        let nz = ax * by - ay * bx;
        // n·((i − x0, j − y0, t) − P) = 0 solved for t. `−1·n` is `−n`
        // exactly (the sign flipped, zeros included) for every non-NaN
        // value, and a NaN fails the finiteness test below either way.
        let inv = s(1.0) / nz;
        let b = (s(-1.0) * nx) * inv;
        let c = (s(-1.0) * ny) * inv;
        let px = s(t.x0 as f32) + faces4::<V>(q1.x, 0.0, 0.0, 0.0);
        let py = s(t.y0 as f32) + faces4::<V>(q1.y, 0.0, 0.0, 0.0);
        let a = faces4::<V>(q1.z, 0.0, 0.0, 0.0) - b * px - c * py;
        let finite = finite(a) & finite(b) & finite(c);
        let det = q1.dot(q2.cross(q3));
        // Entering faces: outward normal against the rays.
        let zero = s(0.0);
        let enter = if det > 0.0 {
            nz.lt(zero)
        } else if det < 0.0 {
            nz.gt(zero)
        } else {
            return None;
        };
        let mask = (enter.bitmask() & FACES) as usize;
        if finite.bitmask() & FACES != FACES || mask == 0 || mask == FACES as usize {
            return None;
        }
        let (a, b, c) = (a.to_array(), b.to_array(), c.to_array());
        let mut f = Faces {
            a: [0.0; 4],
            b: [0.0; 4],
            c: [0.0; 4],
            entering: mask.count_ones() as usize,
            t_ref: t.t_ref as f32,
        };
        for (slot, &k) in ORDER[mask].iter().enumerate() {
            let k = k as usize;
            (f.a[slot], f.b[slot], f.c[slot]) = (a[k], b[k], c[k]);
        }
        Some(f)
    }
}

/// A tet's pixels in one tile: offsets of its first pixel in the tile and
/// its size.
#[derive(Clone, Copy, Debug)]
struct Rect {
    x: usize,
    y: usize,
    nx: usize,
    ny: usize,
}

/// One tile of a projection.
pub(crate) struct TileJob<'a> {
    pub mesh: &'a TetMesh,
    pub frame: &'a Frame,
    pub map: &'a OrthoMap,
    pub tile: u32,
    /// Per pixel (row-major), the ray's range inside the box.
    pub spans: &'a [(f32, f32)],
}

/// Padded tile buffers.
struct Buffers {
    /// Row stride: a tile row plus one chunk.
    stride: usize,
    acc: Vec<f32>,
    s0: Vec<f32>,
    s1: Vec<f32>,
    /// Range common to every pixel's span.
    common: (f32, f32),
    /// Pixels touched since the last flush: rows and columns.
    dirty: (usize, usize, usize, usize),
}

impl TileJob<'_> {
    /// Column-density sums `Σ ρ·chord` of the tile's pixels (row-major),
    /// with `kernel`.
    pub(crate) fn run(&self, kernel: Kernel) -> Vec<f64> {
        match kernel {
            Kernel::Scalar => self.run_in::<PortableLanes, true>(),
            Kernel::Lanes(simd) => dispatch(simd, RunTile(self)),
        }
    }

    /// The tile on lanes `V` (`SCALAR`: the scalar reference instead; `V`
    /// unused). Called through [`dispatch`] so that the AVX2 instantiation
    /// is compiled inside its AVX2 entry. No closures here: the AVX2 copy
    /// must contain the whole loop.
    #[inline(always)]
    fn run_in<V: Lanes, const SCALAR: bool>(&self) -> Vec<f64> {
        let (tx0, ty0, w, h) = self.frame.tile(self.tile);
        let (tx1, ty1) = (tx0 + w - 1, ty0 + h - 1);
        let (w, h) = (w as usize, h as usize);
        let mut sum = vec![0.0f64; w * h];
        // A tile row plus one chunk.
        let stride = w + LANES;
        let mut buf = Buffers {
            stride,
            acc: vec![0.0; h * stride],
            s0: vec![0.0; h * stride],
            s1: vec![0.0; h * stride],
            common: (f32::NEG_INFINITY, f32::INFINITY),
            dirty: (usize::MAX, 0, usize::MAX, 0),
        };
        for (p, &(a, b)) in self.spans.iter().enumerate() {
            let at = (p / w) * stride + p % w;
            (buf.s0[at], buf.s1[at]) = (a, b);
            buf.common = (buf.common.0.max(a), buf.common.1.min(b));
        }
        let mut pending = 0;
        let mut block = BlockTets::default();
        for &entry in &self.frame.bins[self.tile as usize] {
            // The block's tets that meet this tile, derived (lean meshes)
            // outside the lanes' hot loop.
            self.frame
                .block_into(self.mesh, entry, self.tile, &mut block);
            for (tet, rect) in block.tets.iter().zip(&block.rects) {
                let (x0, x1) = ((rect[0] as u32).max(tx0), (rect[1] as u32).min(tx1));
                let (y0, y1) = ((rect[2] as u32).max(ty0), (rect[3] as u32).min(ty1));
                if x0 > x1 || y0 > y1 {
                    continue;
                }
                let r = Rect {
                    x: (x0 - tx0) as usize,
                    y: (y0 - ty0) as usize,
                    nx: (x1 - x0 + 1) as usize,
                    ny: (y1 - y0 + 1) as usize,
                };
                let local = Local::new(self.map, tet, x0, y0);
                let Some(f) = Faces::new::<V>(&local) else {
                    general(&local, tet.density, r, &buf, &mut sum, w);
                    continue;
                };
                // Inside the common range the box clip changes nothing.
                let (t_lo, t_hi) = local.t_range();
                let margin = 1e-5 * (local.t_ref.abs() + (t_hi - t_lo) as f64);
                let clamp = !(local.t_ref + (t_lo as f64) - margin >= buf.common.0 as f64
                    && local.t_ref + (t_hi as f64) + margin <= buf.common.1 as f64);
                if SCALAR {
                    scalar(&f, tet.density, r, clamp, &buf, &mut sum, w);
                    continue;
                }
                let d = &mut buf.dirty;
                *d = (
                    d.0.min(r.y),
                    d.1.max(r.y + r.ny),
                    d.2.min(r.x),
                    d.3.max(r.x + r.nx),
                );
                rows_for::<V>(&f, tet.density, r, clamp, &mut buf);
                pending += 1;
                if pending == FLUSH {
                    flush(&mut buf, &mut sum, w);
                    pending = 0;
                }
            }
        }
        flush(&mut buf, &mut sum, w);
        sum
    }
}

/// [`TileJob::run_in`] as a [`dispatch`] job.
struct RunTile<'a, 'b>(&'a TileJob<'b>);

impl WithLanes for RunTile<'_, '_> {
    type Output = Vec<f64>;
    #[inline(always)]
    fn run<L: Lanes>(self) -> Vec<f64> {
        self.0.run_in::<L, false>()
    }
}

/// Adds the f32 accumulator's touched pixels to the f64 sums and clears them.
#[inline(always)]
fn flush(buf: &mut Buffers, sum: &mut [f64], w: usize) {
    let (y0, y1, x0, x1) = buf.dirty;
    for y in y0..y1 {
        let row = &mut buf.acc[y * buf.stride + x0..y * buf.stride + x1];
        for (s, a) in sum[y * w + x0..y * w + x1].iter_mut().zip(row.iter_mut()) {
            *s += *a as f64;
            *a = 0.0;
        }
    }
    buf.dirty = (usize::MAX, 0, usize::MAX, 0);
}

/// A face's value at pixel `i` of a row whose value at `i = 0` is `row`.
#[inline(always)]
fn face_at(row: f32, b: f32, i: usize) -> f32 {
    row + b * i as f32
}

/// The reference: one pixel at a time, f64 sums per crossing.
#[inline(always)]
fn scalar(f: &Faces, rho: f32, r: Rect, clamp: bool, buf: &Buffers, sum: &mut [f64], w: usize) {
    for j in 0..r.ny {
        let jf = j as f32;
        let row = [0, 1, 2, 3].map(|k| f.a[k] + f.c[k] * jf);
        for i in 0..r.nx {
            let v = [0, 1, 2, 3].map(|k| face_at(row[k], f.b[k], i));
            let mut t0 = v[..f.entering]
                .iter()
                .copied()
                .fold(f32::NEG_INFINITY, f32::max);
            let mut t1 = v[f.entering..]
                .iter()
                .copied()
                .fold(f32::INFINITY, f32::min);
            let at = (r.y + j) * buf.stride + r.x + i;
            if clamp {
                t0 = t0.max(buf.s0[at] - f.t_ref);
                t1 = t1.min(buf.s1[at] - f.t_ref);
            }
            let ch = t1 - t0;
            if ch > 0.0 {
                sum[(r.y + j) * w + r.x + i] += rho as f64 * ch as f64;
            }
        }
    }
}

/// Tets that [`Faces::new`] leaves out (a face parallel to the rays): per
/// pixel and face, that face's crossing or, for a parallel face, its inside
/// test. The same in every kernel.
#[inline(never)]
fn general(t: &Local, rho: f32, r: Rect, buf: &Buffers, sum: &mut [f64], w: usize) {
    let q = &t.q;
    let (x0, y0) = (t.x0 as f32, t.y0 as f32);
    let mut coef = [[0.0f32; 3]; 4];
    let mut kind = [0i8; 4];
    for k in 0..4 {
        // The face opposite vertex k, its normal pointing out.
        let (p, r, s) = (q[(k + 1) % 4], q[(k + 2) % 4], q[(k + 3) % 4]);
        let mut n = (r - p).cross(s - p);
        if n.dot(q[k] - p) > 0.0 {
            n = -n;
        }
        let inv = 1.0 / n.z;
        let (b, c) = (-n.x * inv, -n.y * inv);
        let a = p.z - b * (x0 + p.x) - c * (y0 + p.y);
        if n.z != 0.0 && a.is_finite() && b.is_finite() && c.is_finite() {
            coef[k] = [a, b, c];
            kind[k] = if n.z < 0.0 { -1 } else { 1 };
        } else {
            // Inside where n·((i − x0, j − y0) − p) ≤ 0.
            coef[k] = [-(n.x * (x0 + p.x) + n.y * (y0 + p.y)), n.x, n.y];
        }
    }
    if !(kind.contains(&-1) && kind.contains(&1)) {
        // No volume along the rays (flat, or rounding).
        return;
    }
    let t_ref = t.t_ref as f32;
    for j in 0..r.ny {
        let jf = j as f32;
        'pixel: for i in 0..r.nx {
            let x = i as f32;
            let at = (r.y + j) * buf.stride + r.x + i;
            let mut t0 = buf.s0[at] - t_ref;
            let mut t1 = buf.s1[at] - t_ref;
            for k in 0..4 {
                let [a, b, c] = coef[k];
                let v = a + c * jf + b * x;
                match kind[k] {
                    -1 => t0 = t0.max(v),
                    1 => t1 = t1.min(v),
                    _ if v > 0.0 => continue 'pixel,
                    _ => {}
                }
            }
            let ch = t1 - t0;
            if ch > 0.0 {
                sum[(r.y + j) * w + r.x + i] += rho as f64 * ch as f64;
            }
        }
    }
}

/// [`rows`] for the tet's count of entering faces and box clip.
#[inline(always)]
fn rows_for<V: Lanes>(f: &Faces, rho: f32, r: Rect, clamp: bool, buf: &mut Buffers) {
    match (clamp, f.entering) {
        (false, 1) => rows::<V, false, 1>(f, rho, r, buf),
        (false, 2) => rows::<V, false, 2>(f, rho, r, buf),
        (false, _) => rows::<V, false, 3>(f, rho, r, buf),
        (true, 1) => rows::<V, true, 1>(f, rho, r, buf),
        (true, 2) => rows::<V, true, 2>(f, rho, r, buf),
        (true, _) => rows::<V, true, 3>(f, rho, r, buf),
    }
}

/// A tet's rows, eight pixels at a time: lanes whose ray crosses the tet
/// add `ρ·chord` to the accumulator. `E` faces enter; `CLAMP`: clip to the
/// pixels' box spans. No closures: their bodies would not get the AVX2
/// features of the dispatch entry, and the intrinsics would become calls.
#[inline(always)]
fn rows<V: Lanes, const CLAMP: bool, const E: usize>(
    f: &Faces,
    rho: f32,
    r: Rect,
    buf: &mut Buffers,
) {
    let s = V::splat;
    let iota = V::iota();
    let b = [s(f.b[0]), s(f.b[1]), s(f.b[2]), s(f.b[3])];
    let (rho_v, t_ref, zero) = (s(rho), s(f.t_ref), s(0.0));
    // Lanes of the row's last chunk inside the tet's rectangle.
    let last = (r.nx - 1) & !(LANES - 1);
    let tail = V::first(r.nx - last);
    let all = V::first(LANES);
    for j in 0..r.ny {
        let jf = j as f32;
        let row = [
            s(f.a[0] + f.c[0] * jf),
            s(f.a[1] + f.c[1] * jf),
            s(f.a[2] + f.c[2] * jf),
            s(f.a[3] + f.c[3] * jf),
        ];
        let base = (r.y + j) * buf.stride + r.x;
        let mut i = 0;
        while i < r.nx {
            // The faces' ray parameters at pixels i..i + 8, as in `face_at`.
            let x = iota + s(i as f32);
            let v = [
                row[0] + b[0] * x,
                row[1] + b[1] * x,
                row[2] + b[2] * x,
                row[3] + b[3] * x,
            ];
            let t0 = match E {
                1 => v[0],
                2 => v[0].max(v[1]),
                _ => v[0].max(v[1]).max(v[2]),
            };
            let t1 = match E {
                1 => v[1].min(v[2]).min(v[3]),
                2 => v[2].min(v[3]),
                _ => v[3],
            };
            let (t0, t1) = if CLAMP {
                (
                    t0.max(V::load(&buf.s0, base + i) - t_ref),
                    t1.min(V::load(&buf.s1, base + i) - t_ref),
                )
            } else {
                (t0, t1)
            };
            let ch = t1 - t0;
            let valid = if i == last { tail } else { all };
            let hit = zero.lt(ch) & valid;
            let acc = V::load(&buf.acc, base + i) + (hit & (ch * rho_v));
            acc.store(&mut buf.acc, base + i);
            i += LANES;
        }
    }
}
