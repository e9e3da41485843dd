//! Small fixed-size vector math. `f32` throughout: the data is single precision and
//! every hot loop runs on it; reductions that need more (sums over many particles)
//! widen locally.

use std::ops::{Add, AddAssign, Div, Index, IndexMut, Mul, Neg, Sub};

/// A 3-vector (point, direction or colour).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vec3 {
    pub x: f32,
    pub y: f32,
    pub z: f32,
}

impl Vec3 {
    pub const ZERO: Vec3 = Vec3::new(0.0, 0.0, 0.0);
    pub const ONE: Vec3 = Vec3::new(1.0, 1.0, 1.0);

    pub const fn new(x: f32, y: f32, z: f32) -> Self {
        Vec3 { x, y, z }
    }
    pub const fn splat(v: f32) -> Self {
        Vec3 { x: v, y: v, z: v }
    }
    pub fn from_array(a: [f32; 3]) -> Self {
        Vec3::new(a[0], a[1], a[2])
    }
    pub fn to_array(self) -> [f32; 3] {
        [self.x, self.y, self.z]
    }
    pub fn dot(self, o: Vec3) -> f32 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    pub fn cross(self, o: Vec3) -> Vec3 {
        Vec3::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }
    pub fn length_squared(self) -> f32 {
        self.dot(self)
    }
    pub fn length(self) -> f32 {
        self.length_squared().sqrt()
    }
    /// Unit vector in the same direction; the zero vector stays zero.
    pub fn normalized(self) -> Vec3 {
        let l = self.length();
        if l > 0.0 { self / l } else { self }
    }
    pub fn min(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x.min(o.x), self.y.min(o.y), self.z.min(o.z))
    }
    pub fn max(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x.max(o.x), self.y.max(o.y), self.z.max(o.z))
    }
    pub fn mul_elem(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x * o.x, self.y * o.y, self.z * o.z)
    }
    pub fn max_elem(self) -> f32 {
        self.x.max(self.y).max(self.z)
    }
    pub fn min_elem(self) -> f32 {
        self.x.min(self.y).min(self.z)
    }
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }
}

impl Index<usize> for Vec3 {
    type Output = f32;
    fn index(&self, i: usize) -> &f32 {
        match i {
            0 => &self.x,
            1 => &self.y,
            _ => &self.z,
        }
    }
}

impl IndexMut<usize> for Vec3 {
    fn index_mut(&mut self, i: usize) -> &mut f32 {
        match i {
            0 => &mut self.x,
            1 => &mut self.y,
            _ => &mut self.z,
        }
    }
}

impl Add for Vec3 {
    type Output = Vec3;
    fn add(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}
impl AddAssign for Vec3 {
    fn add_assign(&mut self, o: Vec3) {
        *self = *self + o;
    }
}
impl Sub for Vec3 {
    type Output = Vec3;
    fn sub(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}
impl Mul<f32> for Vec3 {
    type Output = Vec3;
    fn mul(self, s: f32) -> Vec3 {
        Vec3::new(self.x * s, self.y * s, self.z * s)
    }
}
impl Div<f32> for Vec3 {
    type Output = Vec3;
    fn div(self, s: f32) -> Vec3 {
        Vec3::new(self.x / s, self.y / s, self.z / s)
    }
}
impl Neg for Vec3 {
    type Output = Vec3;
    fn neg(self) -> Vec3 {
        Vec3::new(-self.x, -self.y, -self.z)
    }
}

/// A closed scalar range `[lo, hi]`. The empty range has `lo > hi`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range1 {
    pub lo: f32,
    pub hi: f32,
}

impl Range1 {
    pub const EMPTY: Range1 = Range1 {
        lo: f32::INFINITY,
        hi: f32::NEG_INFINITY,
    };
    pub const fn new(lo: f32, hi: f32) -> Self {
        Range1 { lo, hi }
    }
    #[inline]
    pub fn is_empty(&self) -> bool {
        !(self.lo <= self.hi)
    }
    #[inline]
    pub fn extend(&mut self, v: f32) {
        self.lo = self.lo.min(v);
        self.hi = self.hi.max(v);
    }
    #[inline]
    pub fn union(self, o: Range1) -> Range1 {
        Range1::new(self.lo.min(o.lo), self.hi.max(o.hi))
    }
    #[inline]
    pub fn contains(&self, v: f32) -> bool {
        v >= self.lo && v <= self.hi
    }
    #[inline]
    pub fn span(&self) -> f32 {
        self.hi - self.lo
    }
    /// Maps `v` to `[0, 1]` over this range (clamped). A degenerate range maps
    /// everything to 0 so a constant field still gets a defined colour.
    #[inline]
    pub fn normalize(&self, v: f32) -> f32 {
        let s = self.span();
        if s > 0.0 {
            ((v - self.lo) / s).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }
}

/// An axis-aligned box. The empty box has `min > max` on every axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Aabb::EMPTY
    }
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };
    pub fn new(min: Vec3, max: Vec3) -> Self {
        Aabb { min, max }
    }
    /// The box around a sphere.
    pub fn around(center: Vec3, radius: f32) -> Self {
        Aabb::new(center - Vec3::splat(radius), center + Vec3::splat(radius))
    }
    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }
    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    pub fn union(self, o: Aabb) -> Aabb {
        Aabb::new(self.min.min(o.min), self.max.max(o.max))
    }
    pub fn contains(&self, p: Vec3) -> bool {
        p.x >= self.min.x
            && p.x <= self.max.x
            && p.y >= self.min.y
            && p.y <= self.max.y
            && p.z >= self.min.z
            && p.z <= self.max.z
    }
    /// True when `o` lies inside `self` (touching faces count as inside).
    pub fn encloses(&self, o: &Aabb) -> bool {
        o.is_empty()
            || (self.min.x <= o.min.x
                && self.min.y <= o.min.y
                && self.min.z <= o.min.z
                && self.max.x >= o.max.x
                && self.max.y >= o.max.y
                && self.max.z >= o.max.z)
    }
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }
    pub fn diagonal(&self) -> f32 {
        if self.is_empty() {
            0.0
        } else {
            self.extent().length()
        }
    }
    /// The parametric range where `ray` is inside this box, clipped to `t`;
    /// empty when the ray misses. Uses the slab method; a zero direction
    /// component yields ±inf, which the min/max chain handles.
    ///
    /// A ray parallel to an axis that lies exactly in a face plane meets the
    /// box as if the box were half-open, `[min, max)` along that axis: in
    /// the plane of `min` it is inside, in the plane of `max` outside. Boxes
    /// that tile space (cells, bricks, regions) thus share such a ray
    /// between them exactly once, with no gap and no double count.
    #[inline]
    pub fn clip_ray(&self, ray: &Ray, t: Range1) -> Range1 {
        let inv = ray.inv_dir();
        let t0 = (self.min - ray.origin).mul_elem(inv);
        let t1 = (self.max - ray.origin).mul_elem(inv);
        let near = t0.min(t1);
        let far = t0.max(t1);
        // In the plane of `max`, t1 is 0·∞ = NaN and max/min drop it, so
        // the axis reads as a miss (the half-open upper face). In the plane
        // of `min` they would drop t0 and miss as well: that case is
        // redone below, off the fast path.
        let lo = t.lo.max(near.x).max(near.y).max(near.z);
        let hi = t.hi.min(far.x).min(far.y).min(far.z);
        if !(lo < hi) && (t0.x.is_nan() | t0.y.is_nan() | t0.z.is_nan()) {
            return self.clip_ray_in_min_face(ray, t);
        }
        Range1::new(lo, hi)
    }

    /// [`Aabb::clip_ray`] for a ray in the plane of a `min` face.
    #[cold]
    fn clip_ray_in_min_face(&self, ray: &Ray, t: Range1) -> Range1 {
        let (mut lo, mut hi) = (t.lo, t.hi);
        for a in 0..3 {
            let (o, d) = (ray.origin[a], ray.dir[a]);
            if d == 0.0 {
                if !(o >= self.min[a] && o < self.max[a]) {
                    return Range1::EMPTY;
                }
                continue;
            }
            let (ta, tb) = ((self.min[a] - o) / d, (self.max[a] - o) / d);
            lo = lo.max(ta.min(tb));
            hi = hi.min(ta.max(tb));
        }
        Range1::new(lo, hi)
    }
}

/// A ray `origin + t·dir`. `dir` need not be unit length, but every integrator
/// in voxless uses unit directions so that `t` is a distance.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
}

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Ray { origin, dir }
    }
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }
    #[inline]
    pub fn inv_dir(&self) -> Vec3 {
        Vec3::new(1.0 / self.dir.x, 1.0 / self.dir.y, 1.0 / self.dir.z)
    }
}

#[cfg(test)]
mod clip_tests {
    use super::*;

    /// Unit boxes tiling a 3×3 slab of space along x and y.
    fn tiles() -> Vec<Aabb> {
        let mut out = Vec::new();
        for j in 0..3 {
            for i in 0..3 {
                let lo = Vec3::new(i as f32, j as f32, 0.0);
                out.push(Aabb::new(lo, lo + Vec3::new(1.0, 1.0, 4.0)));
            }
        }
        out
    }

    #[test]
    fn axis_rays_in_face_planes_meet_tiling_boxes_exactly_once() {
        let all = Range1::new(f32::NEG_INFINITY, f32::INFINITY);
        // Rays along z in the planes of shared faces, at shared edges, and
        // in the interior: every point of [0, 3)² is covered once, so the
        // total length inside the tiles is the slab's depth (4).
        for (x, y) in [
            (1.0, 0.5),
            (0.5, 2.0),
            (1.0, 1.0),
            (2.0, 2.0),
            (0.0, 0.0),
            (1.5, 1.5),
        ] {
            let ray = Ray::new(Vec3::new(x, y, -1.0), Vec3::new(0.0, 0.0, 1.0));
            let len: f32 = tiles()
                .iter()
                .map(|b| b.clip_ray(&ray, all))
                .filter(|r| !r.is_empty())
                .map(|r| r.span())
                .sum();
            assert_eq!(len, 4.0, "ray at ({x}, {y})");
        }
        // The far faces of the tiling are half-open: outside.
        let ray = Ray::new(Vec3::new(3.0, 0.5, -1.0), Vec3::new(0.0, 0.0, 1.0));
        assert!(tiles().iter().all(|b| b.clip_ray(&ray, all).is_empty()));
        // Oblique rays are unaffected.
        let b = Aabb::new(Vec3::ZERO, Vec3::splat(1.0));
        let r = b.clip_ray(
            &Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::new(1.0, 0.0, 0.0)),
            all,
        );
        assert_eq!((r.lo, r.hi), (1.0, 2.0));
    }
}
