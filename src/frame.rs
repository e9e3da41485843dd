//! World coordinates and the volume's own frame.
//!
//! Volumes compute in `f32`, which holds about seven digits and squares of
//! lengths up to about 10³⁸: positions around 10⁹ (a galaxy in a
//! cosmological box, SI-unit molecular dynamics with an offset) would lose
//! everything below 100 units, and lengths of 10²¹ cm (astrophysics in cgs)
//! or 10⁻¹⁰ m (molecular dynamics in SI) would overflow or underflow once
//! squared or cubed. So data is kept in a local frame chosen when it is
//! loaded — float64 input is recentred and rescaled in float64 before it
//! becomes float32 — and [`WorldFrame`] records it:
//! `world = origin + scale · local`.
//!
//! **Policy** ([`WorldFrame::fit`]): the frame moves and rescales only what
//! needs it, so everyday data stays bit-identical to reading it as float32:
//!
//! - the **scale** is 1 while the data's extent (its longest side) lies in
//!   `[2⁻¹⁰, 2¹⁰]`; outside it is the power of two nearest the extent, so
//!   the local extent is about 1 and the rescaling is exact in binary
//!   floating point;
//! - the **origin** stays at 0 while the data's centre lies within 16 of its
//!   extents of the origin (f32 then keeps at least 19 bits across the
//!   data); otherwise it is the data's centre.
//!
//! One frame serves a whole scene: every material of a multi-material scene
//! and every frame of a time series is placed in the same frame.
//!
//! **Units.** Lengths (radii, steps, cell and box sizes, clip boxes, camera
//! positions) are divided by `scale` on the way in. Field values are kept in
//! world units: weights of kernels normalised per unit volume (the SPH cubic
//! spline) and tessellation particle masses are divided by `scale³`, so a
//! density read from a volume is the world density. What is integrated over
//! a length (projections) or a volume (total mass) is multiplied by `scale`
//! or `scale³` on the way out ([`WorldFrame::length_to_world`]).

use voxless_core::{Aabb, Vec3};

/// Data whose extent lies in `[2^-LOG2_BAND, 2^LOG2_BAND]` keeps scale 1.
const LOG2_BAND: i32 = 10;
/// Data whose centre lies within this many extents of the origin keeps
/// origin 0.
const CENTRE_EXTENTS: f64 = 16.0;

/// Where a volume's local coordinates sit in the world:
/// `world = origin + scale · local`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldFrame {
    pub origin: [f64; 3],
    /// World length of one local unit: a power of two (1 for data of
    /// everyday extent; see the module docs).
    pub scale: f64,
}

impl Default for WorldFrame {
    fn default() -> Self {
        WorldFrame {
            origin: [0.0; 3],
            scale: 1.0,
        }
    }
}

/// The bounding box `(lo, hi)` of `points`; `None` when empty or not finite.
pub fn bounds_of(points: &[[f64; 3]]) -> Option<([f64; 3], [f64; 3])> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    (lo.iter().chain(&hi).all(|v| v.is_finite())).then_some((lo, hi))
}

impl WorldFrame {
    /// The frame whose origin is the centre of `points` (their bounding
    /// box's), keeping scale 1. An empty or non-finite set keeps the world
    /// origin.
    pub fn centred_on(points: &[[f64; 3]]) -> WorldFrame {
        match bounds_of(points) {
            Some((lo, hi)) => WorldFrame {
                origin: std::array::from_fn(|a| 0.5 * (lo[a] + hi[a])),
                scale: 1.0,
            },
            None => WorldFrame::default(),
        }
    }

    /// The frame the policy (module docs) picks for data whose world
    /// bounding box is `lo..hi`. Non-finite bounds keep the world frame.
    pub fn fit(lo: [f64; 3], hi: [f64; 3]) -> WorldFrame {
        if !lo.iter().chain(&hi).all(|v| v.is_finite()) {
            return WorldFrame::default();
        }
        let extent = (0..3).map(|a| (hi[a] - lo[a]).max(0.0)).fold(0.0, f64::max);
        let centre: [f64; 3] = std::array::from_fn(|a| 0.5 * lo[a] + 0.5 * hi[a]);
        let band = 2f64.powi(LOG2_BAND);
        // Zero extent (one particle, coincident particles) has no length of
        // its own: keep scale 1 and let the origin carry the position.
        let scale = if extent == 0.0 || (1.0 / band..=band).contains(&extent) {
            1.0
        } else {
            // Clamp the exponent so the scale itself stays a normal f64.
            2f64.powi((extent.log2().round() as i32).clamp(-1000, 1000))
        };
        let reach = centre.iter().fold(0.0f64, |m, c| m.max(c.abs()));
        let origin = if reach <= CENTRE_EXTENTS * extent {
            [0.0; 3]
        } else {
            centre
        };
        WorldFrame { origin, scale }
    }

    /// [`WorldFrame::fit`] for the bounding box of `points`.
    pub fn fit_points(points: &[[f64; 3]]) -> WorldFrame {
        match bounds_of(points) {
            Some((lo, hi)) => WorldFrame::fit(lo, hi),
            None => WorldFrame::default(),
        }
    }

    /// A world point in the volume's coordinates.
    #[inline]
    pub fn to_local(&self, p: [f64; 3]) -> Vec3 {
        Vec3::new(
            ((p[0] - self.origin[0]) / self.scale) as f32,
            ((p[1] - self.origin[1]) / self.scale) as f32,
            ((p[2] - self.origin[2]) / self.scale) as f32,
        )
    }

    /// A point of the volume's coordinates in the world.
    #[inline]
    pub fn to_world(&self, p: Vec3) -> [f64; 3] {
        [
            p.x as f64 * self.scale + self.origin[0],
            p.y as f64 * self.scale + self.origin[1],
            p.z as f64 * self.scale + self.origin[2],
        ]
    }

    /// A world box `[x0, y0, z0, x1, y1, z1]` in the volume's coordinates.
    pub fn box_to_local(&self, b: [f64; 6]) -> Aabb {
        Aabb::new(
            self.to_local([b[0], b[1], b[2]]),
            self.to_local([b[3], b[4], b[5]]),
        )
    }

    /// A box of the volume's coordinates in the world (lower, upper corner).
    pub fn box_to_world(&self, b: Aabb) -> ([f64; 3], [f64; 3]) {
        (self.to_world(b.min), self.to_world(b.max))
    }

    /// Column densities integrated over local lengths in world units: each
    /// times the scale (the field's values have no length unit).
    pub fn columns_to_world(&self, mut columns: Vec<f32>) -> Vec<f32> {
        if self.scale != 1.0 {
            let s = self.scale;
            columns.iter_mut().for_each(|c| *c = (*c as f64 * s) as f32);
        }
        columns
    }

    /// A world length (a radius, a step, a view height) in local units.
    #[inline]
    pub fn length_to_local(&self, l: f64) -> f32 {
        (l / self.scale) as f32
    }

    /// A local length in world units.
    #[inline]
    pub fn length_to_world(&self, l: f32) -> f64 {
        l as f64 * self.scale
    }

    /// Whether this is the world frame itself.
    pub fn is_world(&self) -> bool {
        self.origin == [0.0; 3] && self.scale == 1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn everyday_data_keeps_the_world_frame() {
        for (lo, hi) in [
            ([0.0, -0.5, 0.0], [2.0, 0.5, 0.6]),
            ([0.0; 3], [100.0; 3]),
            ([1e-3; 3], [2e-3; 3]),
            ([5.0; 3], [5.0; 3]),
        ] {
            let f = WorldFrame::fit(lo, hi);
            assert_eq!(f.scale, 1.0, "{lo:?}..{hi:?}");
        }
        assert!(WorldFrame::fit([0.0; 3], [1.0; 3]).is_world());
        assert!(WorldFrame::fit([10.0; 3], [11.0; 3]).is_world());
    }

    #[test]
    fn far_or_out_of_band_data_is_recentred_and_rescaled_by_powers_of_two() {
        let f = WorldFrame::fit([1e9; 3], [1e9 + 1.0; 3]);
        assert_eq!(f.origin, [1e9 + 0.5; 3]);
        assert_eq!(f.scale, 1.0);
        assert_eq!(
            f.to_local([1e9 + 0.75, 1e9, 1e9 + 0.5]),
            Vec3::new(0.25, -0.5, 0.0)
        );
        let f = WorldFrame::fit([0.0; 3], [3e21; 3]);
        assert_eq!(f.scale, 2f64.powi(71));
        assert_eq!(f.origin, [0.0; 3]);
        let f = WorldFrame::fit([0.0; 3], [1e-12; 3]);
        assert_eq!(f.scale, 2f64.powi(-40));
        let p = f.to_world(f.to_local([5e-13, 0.0, 1e-12]));
        assert!((p[0] - 5e-13).abs() < 1e-19 && (p[2] - 1e-12).abs() < 1e-19);
        // A single point far away: the origin carries it.
        let f = WorldFrame::fit([0.0, 1e38, 0.0], [0.0, 1e38, 0.0]);
        assert_eq!(f.to_local([0.0, 1e38, 0.0]), Vec3::ZERO);
        assert!(WorldFrame::fit([f64::NAN; 3], [1.0; 3]).is_world());
    }
}
