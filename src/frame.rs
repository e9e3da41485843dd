//! World coordinates and the volume's own frame.
//!
//! Volumes compute in `f32`, which holds about seven digits: positions
//! around 10⁹ (a galaxy in a cosmological box, SI-unit molecular dynamics
//! with an offset) would lose everything below 100 units. So data is kept
//! relative to an origin chosen when it is loaded — float64 input is
//! recentred in float64 before it becomes float32 — and [`WorldFrame`]
//! records where that origin lies. Everything a user gives in world
//! coordinates (camera eye and look-at, clip box, a point light, query
//! points, projection bounds) is `f64` in the description and is moved into
//! the volume's frame here, so results do not depend on where the data sits.

use voxless_core::{Aabb, Vec3};

/// Where a volume's local coordinates sit in the world: world = local +
/// `origin`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WorldFrame {
    pub origin: [f64; 3],
}

impl WorldFrame {
    /// The frame whose origin is the centre of `points` (their bounding
    /// box's), so the local coordinates are as small as the data's extent
    /// allows. An empty or non-finite set keeps the world origin.
    pub fn centred_on(points: &[[f64; 3]]) -> WorldFrame {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in points {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        let origin = std::array::from_fn(|a| 0.5 * (lo[a] + hi[a]));
        if origin.iter().all(|c: &f64| c.is_finite()) {
            WorldFrame { origin }
        } else {
            WorldFrame::default()
        }
    }

    /// A world point in the volume's coordinates.
    #[inline]
    pub fn to_local(&self, p: [f64; 3]) -> Vec3 {
        Vec3::new(
            (p[0] - self.origin[0]) as f32,
            (p[1] - self.origin[1]) as f32,
            (p[2] - self.origin[2]) as f32,
        )
    }

    /// A point of the volume's coordinates in the world.
    #[inline]
    pub fn to_world(&self, p: Vec3) -> [f64; 3] {
        [
            p.x as f64 + self.origin[0],
            p.y as f64 + self.origin[1],
            p.z as f64 + self.origin[2],
        ]
    }

    /// A world box `[x0, y0, z0, x1, y1, z1]` in the volume's coordinates.
    pub fn box_to_local(&self, b: [f64; 6]) -> Aabb {
        Aabb::new(
            self.to_local([b[0], b[1], b[2]]),
            self.to_local([b[3], b[4], b[5]]),
        )
    }

    /// Whether this is the world frame itself.
    pub fn is_world(&self) -> bool {
        self.origin == [0.0; 3]
    }
}
