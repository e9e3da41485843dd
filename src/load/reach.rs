//! Two statistics of a particle set that one process computes over every
//! row and the ranks of a decomposed set over their shares: how far the
//! supports reach (what the world frame is fitted to, [`Reach`]), and
//! whether float32 resolves the supports across the data's extent
//! ([`Unresolvable`]). Both come in pieces the ranks merge, so a rank and
//! one process reach the same answer with the same words.

use voxless_core::Vec3;
use voxless_particles::{Kernel, median};
use voxless_scene::ParticlesDesc;

use crate::SceneError;

/// What fixes the world box a particle set's supports reach, in pieces
/// that merge over the shares of a decomposed set: the positions' bounds
/// (NaN passed over) and the largest radius (when the rows have radii).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Reach {
    pub lo: [f64; 3],
    pub hi: [f64; 3],
    pub max_radius: Option<f32>,
}

impl Reach {
    /// The pieces of rows read: world `positions` and their `radii`.
    pub fn of(positions: &[[f64; 3]], radii: Option<&[f32]>) -> Reach {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for q in positions {
            for a in 0..3 {
                lo[a] = lo[a].min(q[a]);
                hi[a] = hi[a].max(q[a]);
            }
        }
        let max_radius = radii.map(|r| r.iter().fold(0.0f32, |m, &v| m.max(v)));
        Reach { lo, hi, max_radius }
    }

    /// The pieces of two shares together.
    pub fn merge(self, o: Reach) -> Reach {
        Reach {
            lo: std::array::from_fn(|a| self.lo[a].min(o.lo[a])),
            hi: std::array::from_fn(|a| self.hi[a].max(o.hi[a])),
            max_radius: match (self.max_radius, o.max_radius) {
                (Some(a), Some(b)) => Some(a.max(b)),
                (a, b) => a.or(b),
            },
        }
    }

    /// The world box the set's supports reach (`total` particles of
    /// `kernel`): the positions' bounds grown by the largest support the
    /// description or the radii give; `None` for non-finite positions.
    pub fn world_box(&self, p: &ParticlesDesc, kernel: Kernel, total: usize) -> Option<WorldBox> {
        let (lo, hi) = (self.lo, self.hi);
        if !lo.iter().chain(&hi).all(|v| v.is_finite()) {
            return None;
        }
        let factor = kernel.support_factor() as f64;
        let radius = match (p.radius, self.max_radius) {
            (Some(r), _) => r as f64,
            (None, Some(r)) => r as f64,
            (None, None) => 0.0,
        };
        let extent = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
        // A support beyond the data's extent is refused when there are many
        // particles (see `ParticleError::HugeRadius`): placing the frame
        // around it would only blur the positions the error reports.
        let refused = total > 1000 && factor * radius > extent;
        let grow = if radius.is_finite() && !refused {
            factor * radius
        } else {
            0.0
        };
        Some((lo.map(|v| v - grow), hi.map(|v| v + grow)))
    }
}

/// A world box: lower and upper corner (float64).
pub(crate) type WorldBox = ([f64; 3], [f64; 3]);

/// Supports too small for float32 across the data's extent (see
/// `check_resolvable`), found from the medians of `radii` and of
/// `centres` — every particle's, or a decomposed set's probes (every k-th
/// row, so exact up to that many particles).
pub(crate) struct Unresolvable {
    support: f64,
    extent: f64,
    centre: [f32; 3],
}

impl Unresolvable {
    /// `Some` when the supports (`support` times the median radius, when
    /// there are radii) are below what float32 resolves across `bounds`
    /// (the positions' bounds) for a set of `total` particles.
    pub fn find(
        support: f32,
        radii: Option<&mut [f32]>,
        centres: &[Vec3],
        bounds: voxless_core::Aabb,
        total: usize,
    ) -> Option<Unresolvable> {
        let support = match radii {
            Some(r) if !r.is_empty() => support * median(r),
            _ => support,
        } as f64;
        let extent = (0..3)
            .map(|a| (bounds.max[a] - bounds.min[a]) as f64)
            .fold(0.0, f64::max);
        // Non-finite positions are reported as such when the volume is built.
        if total < 2 || !extent.is_finite() || !(support < extent * 1e-6) {
            return None;
        }
        let centre: [f32; 3] = std::array::from_fn(|a| {
            let mut v: Vec<f32> = centres.iter().map(|p| p[a]).collect();
            median(&mut v)
        });
        Some(Unresolvable {
            support,
            extent,
            centre,
        })
    }

    /// The first of `positions` farthest from the centre, and its distance.
    pub fn farthest(&self, positions: &[Vec3]) -> (usize, f64) {
        let dist = |p: &Vec3| {
            (0..3)
                .map(|a| (p[a] - self.centre[a]).abs() as f64)
                .fold(0.0, f64::max)
        };
        positions.iter().enumerate().fold(
            (0, -1.0),
            |m, (i, p)| {
                if dist(p) > m.1 { (i, dist(p)) } else { m }
            },
        )
    }

    /// The error naming particle `far` (lengths in world units: the frame's
    /// scale is `scale`).
    pub fn error(&self, far: usize, scale: f64) -> SceneError {
        SceneError::setting(
            "particles (positions)",
            format!(
                "the particles' supports ({:.3e}) are too small for float32 to resolve across \
                 the data's extent ({:.3e}): particle {far} lies farthest from the rest; leave \
                 out outliers like it (or give a larger --radius)",
                self.support * scale,
                self.extent * scale
            ),
        )
    }
}
