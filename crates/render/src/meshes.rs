//! The render's meshes ([`Surfaces`](crate::Surfaces)) and their mirror
//! instances along a ray: the nearest hit of a camera ray, and whether
//! anything blocks a shadow or occlusion ray. Each mirror instance is traced
//! by reflecting the ray. Shading and ambient occlusion (module `surface`)
//! build on them.

use voxless_core::{Range1, Ray};
use voxless_mesh::Hit;

use crate::RenderSettings;
use crate::ctx::Ctx;

/// `ray` reflected about the mirrors whose bit is set in `fold`.
#[inline]
fn reflected(mirrors: &[voxless_core::Mirror], fold: usize, ray: &Ray) -> Ray {
    let mut r = *ray;
    for (i, m) in mirrors.iter().enumerate() {
        if fold & (1 << i) != 0 {
            r = m.ray(&r);
        }
    }
    r
}

/// The nearest mesh hit of a camera ray, when the render has meshes: over
/// the meshes and each of their mirror instances (every combination of
/// the mirrors), traced by reflecting the ray.
#[inline]
pub(crate) fn nearest(ctx: &Ctx, ray: &Ray) -> Option<Hit> {
    let surfaces = ctx.settings.surfaces.as_ref()?;
    let mirrors = &ctx.settings.mirrors;
    let mut best: Option<Hit> = None;
    for fold in 0..1usize << mirrors.len() {
        let t = Range1::new(0.0, best.map_or(f32::INFINITY, |h| h.t));
        if let Some(mut h) = surfaces.nearest(&reflected(mirrors, fold, ray), t) {
            let mut n = h.normal;
            for (i, m) in mirrors.iter().enumerate() {
                if fold & (1 << i) != 0 {
                    n = m.vector(n);
                }
            }
            h.normal = n;
            best = Some(h);
        }
    }
    best
}

/// Whether a mesh or one of its mirror instances lies on `ray` within `t`.
pub(crate) fn blocked(settings: &RenderSettings, ray: &Ray, t: Range1) -> bool {
    let Some(surfaces) = &settings.surfaces else {
        return false;
    };
    let mirrors = &settings.mirrors;
    (0..1usize << mirrors.len()).any(|fold| surfaces.occluded(&reflected(mirrors, fold, ray), t))
}
