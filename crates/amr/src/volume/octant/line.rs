//! Exact line integrals of the octant reconstruction (column densities).
//!
//! Inside one octant box the field is trilinear, and along a line a
//! trilinear form is a cubic in `t`: two-point Gauss–Legendre integrates
//! it exactly. A ray is cut at every plane where a box ends — the cells'
//! faces and their centre planes — brick by brick, and each piece adds its
//! two nodes (one box built per piece, its cell known from the brick).
//! Bricks clip the ray half-open as the cells do (a ray lying in a face
//! between two bricks counts once); for a ray parallel to an axis the
//! faces are compared in `f32` world coordinates, as everywhere else.

use voxless_core::{Range1, Ray};

use super::{Fields, leaf};
use crate::volume::AmrVolume;

impl AmrVolume {
    /// `∫ value dt` of the opacity field's octant reconstruction along
    /// `ray` over `t`, exact up to rounding.
    pub(in crate::volume) fn octant_line_integral(&self, ray: &Ray, t: Range1) -> f64 {
        let fields = Fields {
            value: &self.bx().values[self.settings.field],
            color: None,
        };
        let h = self.h as f64;
        let o = [0, 1, 2].map(|a| ray.origin[a] as f64);
        let d = [0, 1, 2].map(|a| ray.dir[a] as f64);
        let org = [0, 1, 2].map(|a| self.origin[a] as f64);
        // Finest units of the point at `s`.
        let units = |s: f64| [0, 1, 2].map(|a| (o[a] + d[a] * s - org[a]) / h);
        // The parameter where the ray meets plane `k` (finest units) across `a`.
        let at_plane = |a: usize, k: f64| (org[a] + k * h - o[a]) / d[a];
        let (lo, hi) = (t.lo as f64, t.hi as f64);
        let mut cuts: Vec<f64> = Vec::new();
        let mut sum = 0.0f64;
        self.bx().brick_bvh.ray_query(ray, t, |bi, _| {
            let b = &self.bx().bricks[bi as usize];
            let (lower, upper) = (b.lower, b.upper());
            // The brick's half-open chord.
            let (mut t0, mut t1) = (lo, hi);
            for a in 0..3 {
                if d[a] == 0.0 {
                    let world = |k: i32| self.origin[a] + k as f32 * self.h;
                    if !(ray.origin[a] >= world(lower[a]) && ray.origin[a] < world(upper[a])) {
                        return;
                    }
                    continue;
                }
                let (ta, tb) = (at_plane(a, lower[a] as f64), at_plane(a, upper[a] as f64));
                t0 = t0.max(ta.min(tb));
                t1 = t1.min(ta.max(tb));
            }
            if !(t1 > t0) {
                return;
            }
            // Every face and centre plane of the brick's cells crossed
            // strictly inside the chord: the pieces' ends.
            let w = b.width() as f64;
            cuts.clear();
            cuts.extend([t0, t1]);
            for a in (0..3).filter(|&a| d[a] != 0.0) {
                for k in 0..=2 * b.size[a] {
                    let s = at_plane(a, lower[a] as f64 + 0.5 * w * k as f64);
                    if s > t0 && s < t1 {
                        cuts.push(s);
                    }
                }
            }
            cuts.sort_unstable_by(f64::total_cmp);
            for piece in cuts.windows(2) {
                let (s0, s1) = (piece[0], piece[1]);
                if !(s1 > s0) {
                    continue;
                }
                let (mid, half) = (0.5 * (s0 + s1), 0.5 * (s1 - s0));
                let p = units(mid);
                // The piece's cell and box, from its midpoint.
                let cell = [0, 1, 2].map(|a| {
                    let i = ((p[a] - lower[a] as f64) / w).floor() as i32;
                    i.clamp(0, b.size[a] - 1)
                });
                let c = leaf(b, bi, cell);
                let bx = self.octant_box(&c, p, fields);
                let off = half / 3f64.sqrt();
                let f = |s: f64| bx.lerp(units(s), false).0[0];
                sum += half * (f(mid - off) + f(mid + off));
            }
        });
        sum
    }
}
