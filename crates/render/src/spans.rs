//! Where one ray's samples lie: the region a render integrates (the
//! volume's bounds cut by the clip box), the ray's span inside it, the
//! lattice span its cells are cut on and the part of it a render owns under
//! a decomposition ([`RaySpans`], [`own_range`]).

use voxless_core::{Aabb, Range1, Ray, Volume};

use crate::RenderSettings;
use crate::cursor::Cursor;
use crate::sampling::PixelRng;

/// The part of the world a render integrates: the volume's bounds, cut by
/// the clip box.
pub(crate) fn region<V: Volume>(volume: &V, settings: &RenderSettings) -> Aabb {
    clipped(volume.bounds(), settings.clip)
}

fn clipped(b: Aabb, clip: Option<Aabb>) -> Aabb {
    match clip {
        Some(c) => Aabb::new(b.min.max(c.min), b.max.min(c.max)),
        None => b,
    }
}

/// Where one ray's samples lie.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RaySpans {
    /// The part `t ∈ [0, t_max]` inside the volume's bounds and the clip
    /// box, where its intervals are asked for.
    pub span: Range1,
    /// Where lattice cells are cut: `span`, or under a decomposition the
    /// ray inside the whole data's bounds and the clip box — the same for
    /// every box, as in a one-process render.
    pub cells: Range1,
    /// The samples this render owns (see [`own_range`]).
    pub own: Range1,
}

impl RaySpans {
    /// The spans of `ray` for a volume whose integrated region (bounds and
    /// clip box) is `region`.
    pub fn new(region: &Aabb, settings: &RenderSettings, ray: &Ray, t_max: f32) -> RaySpans {
        let t = Range1::new(0.0, t_max);
        let span = region.clip_ray(ray, t);
        match &settings.domain {
            None => RaySpans {
                span,
                cells: span,
                own: Range1::new(f32::NEG_INFINITY, f32::INFINITY),
            },
            Some(d) => {
                let own = own_range(Some(&d.owned), ray);
                RaySpans {
                    span: if own.is_empty() { Range1::EMPTY } else { span },
                    cells: clipped(d.bounds, settings.clip).clip_ray(ray, t),
                    own,
                }
            }
        }
    }

    /// Whether the ray has nothing to integrate.
    pub fn is_empty(&self) -> bool {
        self.span.is_empty()
    }

    /// A cursor over this ray's segments.
    pub fn cursor(&self, rng: &PixelRng) -> Cursor {
        Cursor::new(self.cells, self.own, rng)
    }
}

/// The part `[lo, hi)` of `ray` whose samples a render restricted to the
/// half-open box `domain` owns (everything without one). Boxes that tile
/// space split every ray's samples exactly: a shared face gives both boxes
/// the same `t`, and a ray lying in a face belongs to the box on its upper
/// side only.
pub fn own_range(domain: Option<&Aabb>, ray: &Ray) -> Range1 {
    let Some(d) = domain else {
        return Range1::new(f32::NEG_INFINITY, f32::INFINITY);
    };
    let (mut lo, mut hi) = (f32::NEG_INFINITY, f32::INFINITY);
    for a in 0..3 {
        let (o, dir) = (ray.origin[a], ray.dir[a]);
        if dir == 0.0 {
            if !(d.min[a] <= o && o < d.max[a]) {
                return Range1::EMPTY;
            }
            continue;
        }
        let inv = 1.0 / dir;
        let t0 = (d.min[a] - o) * inv;
        let t1 = (d.max[a] - o) * inv;
        lo = lo.max(t0.min(t1));
        hi = hi.min(t0.max(t1));
    }
    if hi > lo {
        Range1::new(lo, hi)
    } else {
        Range1::EMPTY
    }
}
