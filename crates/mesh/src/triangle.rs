//! The watertight ray–triangle test (Woop, Benthin and Wald, JCGT 2013).
//!
//! The ray is turned into a frame where it runs along +z from the origin
//! (a permutation of the axes and a shear, no rotation, so nothing is
//! rounded differently for two triangles that share a vertex). In that
//! frame the hit test is three 2D edge functions at the origin, evaluated
//! in f64 (hit distances to ~1e-15 of the coordinates). A vertex shared by
//! two triangles is sheared to the same coordinates in both, and an edge
//! they share gives exactly negated edge functions (rounding is symmetric
//! under negation), so both triangles see the same side of it.
//!
//! Points exactly on an edge or a vertex (an edge function of 0) are given
//! to one triangle only, by a fill rule on the edge's direction in the
//! ray's frame (the rasteriser's top-left rule): of two triangles sharing
//! an edge, seen from the same side, exactly one owns it. A ray through an
//! edge or a vertex of a closed mesh thus hits it once per crossing — no
//! gap, no double hit.

use voxless_core::{Range1, Ray, Vec3};

/// A ray prepared for many triangle tests.
#[derive(Clone, Copy, Debug)]
pub struct RayFrame {
    origin: [f64; 3],
    kx: usize,
    ky: usize,
    kz: usize,
    sx: f64,
    sy: f64,
    sz: f64,
}

impl RayFrame {
    pub fn new(ray: &Ray) -> RayFrame {
        let d = ray.dir;
        let (ax, ay, az) = (d.x.abs(), d.y.abs(), d.z.abs());
        // z along the dominant direction, so the shear never divides by a
        // small number; swapping x and y for a negative z keeps the winding.
        let kz = if ax >= ay && ax >= az {
            0
        } else if ay >= az {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let (dx, dy, dz) = (d[kx] as f64, d[ky] as f64, d[kz] as f64);
        RayFrame {
            origin: [
                ray.origin.x as f64,
                ray.origin.y as f64,
                ray.origin.z as f64,
            ],
            kx,
            ky,
            kz,
            sx: dx / dz,
            sy: dy / dz,
            sz: 1.0 / dz,
        }
    }

    /// `p` relative to the origin, sheared: (x, y) in the image plane of
    /// the ray, z along it (unscaled).
    #[inline(always)]
    fn shear(&self, p: Vec3) -> (f64, f64, f64) {
        let q = |k: usize| p[k] as f64 - self.origin[k];
        let z = q(self.kz);
        (q(self.kx) - self.sx * z, q(self.ky) - self.sy * z, z)
    }
}

/// A hit: the ray parameter and the barycentric weights of the vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    pub t: f32,
    pub weights: [f32; 3],
}

/// Edge function of the edge `p → q` at the origin.
#[inline(always)]
fn edge(p: (f64, f64), q: (f64, f64)) -> f64 {
    q.0 * p.1 - q.1 * p.0
}

/// The fill rule: of `d` and `−d` exactly one is owned (d ≠ 0).
#[inline(always)]
fn owns(dx: f64, dy: f64) -> bool {
    dy > 0.0 || (dy == 0.0 && dx > 0.0)
}

/// Whether the origin is inside edge `p → q` of a triangle of orientation
/// `s` (±1), with the fill rule on the line.
#[inline(always)]
fn inside(e: f64, s: f64, p: (f64, f64), q: (f64, f64)) -> bool {
    let se = s * e;
    se > 0.0 || (se == 0.0 && owns(s * (q.0 - p.0), s * (q.1 - p.1)))
}

/// Where the ray of `f` crosses triangle `(a, b, c)` strictly inside `t`.
#[inline]
pub fn intersect(f: &RayFrame, a: Vec3, b: Vec3, c: Vec3, t: Range1) -> Option<TriangleHit> {
    let (ax, ay, az) = f.shear(a);
    let (bx, by, bz) = f.shear(b);
    let (cx, cy, cz) = f.shear(c);
    let (pa, pb, pc) = ((ax, ay), (bx, by), (cx, cy));
    // u, v, w: twice the signed areas opposite a, b, c.
    let u = edge(pb, pc);
    let v = edge(pc, pa);
    let w = edge(pa, pb);
    let det = u + v + w;
    if det == 0.0 {
        // Seen edge-on (or degenerate): no area to hit.
        return None;
    }
    let s = det.signum();
    if !(inside(u, s, pb, pc) && inside(v, s, pc, pa) && inside(w, s, pa, pb)) {
        return None;
    }
    let tt = ((u * az + v * bz + w * cz) * f.sz / det) as f32;
    if !(tt > t.lo && tt < t.hi) {
        return None;
    }
    Some(TriangleHit {
        t: tt,
        weights: [(u / det) as f32, (v / det) as f32, (w / det) as f32],
    })
}
