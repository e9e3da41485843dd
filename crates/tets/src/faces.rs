//! A tet's four face planes in four SIMD lanes, for the per-pixel clip of
//! perspective tiles.
//!
//! Face `f` (the one opposite vertex `f`) lives in lane `f`. Each lane does
//! the scalar [`Planes`](crate::raster::Planes) arithmetic in the same order
//! (products and sums without fused multiply-adds, correctly rounded
//! divisions), and the lanes' results are folded in face order with the
//! same `min`/`max`, so a clip here equals [`Planes::clip`]
//! (crate::raster::Planes::clip) of the ray from the same origin bit for
//! bit (tested). What the lanes
//! remove is the scalar code's four data-dependent branches per pixel (is
//! the face entering, leaving or parallel to the ray?) and three of its four
//! divisions: a sub-pixel tet covers one or two pixels, so these and the
//! planes' set-up are most of what a tet costs.

use voxless_core::Vec3;
use wide::f32x4;

use crate::mesh::Tet;

/// The vertices spanning face `f` (`a`, `b`, `d`, as `Planes::new` takes
/// them) and the vertex opposite it, per lane.
const A: [usize; 4] = [1, 2, 3, 0];
const B: [usize; 4] = [2, 3, 0, 1];
const D: [usize; 4] = [3, 0, 1, 2];
const P: [usize; 4] = [0, 1, 2, 3];

/// The four face planes `n·x ≤ c` (inside), face `f` in lane `f`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FaceLanes {
    nx: f32x4,
    ny: f32x4,
    nz: f32x4,
    c: f32x4,
}

/// One coordinate of the vertices `at` in four lanes.
#[inline(always)]
fn gather(v: &[Vec3; 4], at: [usize; 4], axis: usize) -> f32x4 {
    f32x4::new(at.map(|i| v[i][axis]))
}

impl FaceLanes {
    /// The planes of `t`, normals pointing out (as `Planes::new`).
    #[inline]
    pub(crate) fn new(t: &Tet) -> FaceLanes {
        let v = &t.v;
        let (x, y, z) = (0, 1, 2);
        let (ax, ay, az) = (gather(v, A, x), gather(v, A, y), gather(v, A, z));
        // The two edges from `a` and their cross product, per face.
        let (ux, uy, uz) = (
            gather(v, B, x) - ax,
            gather(v, B, y) - ay,
            gather(v, B, z) - az,
        );
        let (wx, wy, wz) = (
            gather(v, D, x) - ax,
            gather(v, D, y) - ay,
            gather(v, D, z) - az,
        );
        let nx = uy * wz - uz * wy;
        let ny = uz * wx - ux * wz;
        let nz = ux * wy - uy * wx;
        // Outward: away from the opposite vertex (flipped by the sign bit,
        // as the scalar negation does).
        let (px, py, pz) = (
            gather(v, P, x) - ax,
            gather(v, P, y) - ay,
            gather(v, P, z) - az,
        );
        let inward = (nx * px + ny * py + nz * pz).simd_gt(f32x4::ZERO);
        let sign = inward & f32x4::splat(-0.0);
        let (nx, ny, nz) = (nx ^ sign, ny ^ sign, nz ^ sign);
        let c = nx * ax + ny * ay + nz * az;
        FaceLanes { nx, ny, nz, c }
    }

    /// Each face's `c − n·origin`: what [`FaceLanes::clip_from`] needs of
    /// rays sharing `origin` (a perspective camera's eye).
    #[inline]
    pub(crate) fn with_origin(&self, o: Vec3) -> f32x4 {
        let s = f32x4::splat;
        self.c - (self.nx * s(o.x) + self.ny * s(o.y) + self.nz * s(o.z))
    }

    /// The parametric range inside the tet of the ray from the origin given
    /// to [`FaceLanes::with_origin`] (`dist`) along `dir`, possibly empty:
    /// entering faces (`n·dir < 0`) raise its start, leaving faces lower its
    /// end, a face parallel to the ray empties it when the origin is
    /// outside it.
    #[inline]
    pub(crate) fn clip_from(&self, dist: f32x4, dir: Vec3) -> (f32, f32) {
        let s = f32x4::splat;
        let nd = self.nx * s(dir.x) + self.ny * s(dir.y) + self.nz * s(dir.z);
        let leave = nd.simd_gt(f32x4::ZERO);
        let enter = nd.simd_lt(f32x4::ZERO);
        // Neither (zero or NaN: the scalar code's `else`) and outside.
        let outside = dist.simd_lt(f32x4::ZERO) & !(leave | enter);
        if outside.any() {
            return (1.0, 0.0);
        }
        let q = dist / nd;
        let t1 = leave.select(q, s(f32::INFINITY)).to_array();
        let t0 = enter.select(q, s(f32::NEG_INFINITY)).to_array();
        // Folded in face order with `f32::min`/`max`, as the scalar loop.
        let t1 = t1.into_iter().fold(f32::INFINITY, f32::min);
        let t0 = t0.into_iter().fold(f32::NEG_INFINITY, f32::max);
        (t0, t1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::Planes;
    use voxless_core::{Ray, SmallRng};

    fn bits(t: (f32, f32)) -> (u32, u32) {
        (t.0.to_bits(), t.1.to_bits())
    }

    /// The lanes' clip is the scalar clip bit for bit: random tets (some
    /// flat, some with faces parallel to the rays, some inverted) seen from
    /// random eyes along random directions, axis-aligned ones included.
    #[test]
    fn lanes_clip_as_the_planes_do() {
        let mut rng = SmallRng(7);
        let mut r = |s: f32| (rng.f() - 0.5) * s;
        let mut hits = 0;
        for case in 0..20_000 {
            let mut v = [(); 4].map(|_| Vec3::new(r(2.0), r(2.0), r(2.0)));
            match case % 5 {
                // Two vertices sharing z: a face may be parallel to z rays.
                1 => {
                    v[1].z = v[0].z;
                    v[2].z = v[0].z;
                }
                // Flat: all four in one plane.
                2 => v[3] = v[0] + (v[1] - v[0]) * 0.3 + (v[2] - v[0]) * 0.5,
                // Coincident vertices.
                3 => v[2] = v[1],
                _ => {}
            }
            let tet = Tet { v, density: 1.0 };
            let eye = Vec3::new(r(8.0), r(8.0), r(8.0));
            let dirs = [
                Vec3::new(r(1.0), r(1.0), r(1.0)),
                Vec3::new(0.0, 0.0, 1.0),
                Vec3::new(0.0, -1.0, 0.0),
                (v[0] * 0.25 + v[1] * 0.25 + v[2] * 0.25 + v[3] * 0.25) - eye,
            ];
            let (planes, lanes) = (Planes::new(&tet), FaceLanes::new(&tet));
            let dist = lanes.with_origin(eye);
            for dir in dirs {
                let want = planes.clip(&Ray::new(eye, dir));
                let got = lanes.clip_from(dist, dir);
                assert_eq!(bits(want), bits(got), "{v:?} from {eye:?} along {dir:?}");
                hits += usize::from(want.1 > want.0);
            }
        }
        // The rays aimed at the centroids hit (the test is not all misses).
        assert!(hits > 10_000, "{hits} hits");
    }
}
