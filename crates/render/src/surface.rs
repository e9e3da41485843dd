//! Opaque triangle meshes beside the volume, and ambient occlusion.
//!
//! **Meshes** ([`Surfaces`](crate::Surfaces), from `voxless-mesh`): each camera ray first
//! finds its nearest mesh hit; the volume is then integrated only up to it
//! (the ray's span ends there, for every integrator: per-sample marching,
//! packets and single scattering) and composited over the shaded surface,
//! `C = C_vol + (1 − α_vol)·C_surface`. The surface is opaque. It is lit by
//! the render's light (a headlight when there is none) with two-sided
//! diffuse shading; under single scattering by the scattering light, with
//! shadows cast by the meshes and the volume.
//!
//! **Ambient occlusion** ([`AmbientOcclusion`]): at a mesh hit and at an
//! iso-surface hit, `rays` cosine-distributed rays over the hemisphere of
//! the normal, each up to `distance`, ask whether a mesh or an iso-surface
//! is in the way; the shade is multiplied by the fraction that get through
//! (cosine weighting makes that fraction the irradiance-weighted
//! visibility). An iso-surface blocks a ray when the field crosses one of
//! the iso-values between evenly spaced samples along it. Directions come
//! from the pixel's random stream, so the image is deterministic. A point
//! over an open plane is never occluded (1 − 0); a point inside a closed box
//! always is (1 − 1).

use voxless_core::{Range1, Ray, Vec3, Volume};
use voxless_mesh::{Hit, cosine_direction};

use crate::ctx::Ctx;
use crate::meshes::blocked;
use crate::sampling::PixelRng;
use crate::{Light, scatter};

/// Ambient-occlusion settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AmbientOcclusion {
    /// Rays per hit (≥ 1).
    pub rays: u32,
    /// How far an occluder counts, in the volume's units.
    pub distance: f32,
}

/// Random-number dimensions of the occlusion rays: far above those of the
/// pixel jitter, the sample lattice and delta tracking.
const AO_DIMS: u32 = 1 << 24;
/// Samples per occlusion ray when looking for an iso-surface crossing.
const ISO_STEPS: u32 = 16;

/// Offset along the normal that moves an occlusion ray's origin off the
/// surface it starts on, relative to the point's magnitude and the
/// occlusion distance (f32 hit points are only that exact).
#[inline]
fn lift(p: Vec3, distance: f32) -> f32 {
    let m = p.x.abs().max(p.y.abs()).max(p.z.abs());
    (64.0 * f32::EPSILON * m).max(1e-4 * distance)
}

/// The fraction of the hemisphere around `n` (facing the viewer) at `p`
/// that meshes or iso-surfaces occlude within the occlusion distance; 0
/// without ambient occlusion.
pub(crate) fn occlusion<V: Volume>(
    volume: &V,
    p: Vec3,
    n: Vec3,
    ctx: &Ctx,
    rng: &PixelRng,
    salt: u32,
) -> f32 {
    let Some(ao) = ctx.settings.ao else {
        return 0.0;
    };
    let rays = ao.rays.max(1);
    let origin = p + n * lift(p, ao.distance);
    let mut hidden = 0;
    for k in 0..rays {
        // Each hit on the ray (mesh, then iso-surfaces in order) draws from
        // its own dimensions.
        let dim = AO_DIMS + salt.wrapping_mul(2 * rays) + 2 * k;
        // Stratified in the polar coordinate: one ray per band of cos²θ,
        // less noise than independent directions at the same count.
        let u1 = (k as f32 + rng.uniform(dim)) / rays as f32;
        let d = cosine_direction(n, u1.min(1.0 - f32::EPSILON), rng.uniform(dim + 1));
        let ray = Ray::new(origin, d);
        let by_mesh = blocked(ctx.settings, &ray, Range1::new(0.0, ao.distance));
        if by_mesh || crosses_iso(volume, &ray, ao.distance, ctx) {
            hidden += 1;
        }
    }
    hidden as f32 / rays as f32
}

/// Whether the field crosses an iso-value along `ray` within `distance`
/// (relative to its value at the ray's start, sampled evenly).
fn crosses_iso<V: Volume>(volume: &V, ray: &Ray, distance: f32, ctx: &Ctx) -> bool {
    let iso = &ctx.settings.iso;
    if iso.is_empty() {
        return false;
    }
    let value = |t: f32| volume.sample(ray.at(t)).map_or(0.0, |s| s.value);
    // Start half a step out: a ray leaving an iso-surface starts on it.
    let dt = distance / ISO_STEPS as f32;
    let v0 = value(0.5 * dt);
    (1..=ISO_STEPS).any(|i| {
        let v = value((i as f32 + 0.5).min(ISO_STEPS as f32) * dt);
        iso.iter().any(|&c| (v0 - c) * (v - c) < 0.0)
    })
}

/// The light of an emission–absorption render's surfaces: the render's,
/// else a headlight.
#[inline]
pub(crate) fn light_of(ctx: &Ctx, ray: &Ray) -> Light {
    ctx.settings.light.unwrap_or(Light {
        direction: -ray.dir,
        ambient: 0.2,
    })
}

/// The premultiplied RGBA (alpha 1) of mesh hit `hit` on camera ray `ray`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn shade_hit<V: Volume>(
    volume: &V,
    hit: &Hit,
    ray: &Ray,
    ctx: &Ctx,
    rng: &PixelRng,
    pixel: (u32, u32),
    sample: u32,
    scratch: &mut Vec<voxless_core::Interval>,
) -> [f32; 4] {
    let p = ray.at(hit.t);
    let visible = 1.0 - occlusion(volume, p, hit.normal, ctx, rng, 0);
    let light = match &ctx.settings.scatter {
        // Single scattering: the scattering light, blocked by meshes and
        // the volume (a shadow ray from just off the surface).
        Some(sc) => {
            let origin = p + hit.normal * lift(p, volume.bounds().diagonal());
            let (dir, lit) = scatter::light_at(volume, origin, ctx, sc, pixel, sample, scratch);
            let diffuse = hit.normal.dot(dir).max(0.0);
            sc.ambient + (1.0 - sc.ambient) * sc.intensity * diffuse * lit
        }
        None => {
            // One-sided: the normal faces the viewer, a surface turned
            // away from the light gets only the ambient part.
            let l = light_of(ctx, ray);
            l.ambient + (1.0 - l.ambient) * hit.normal.dot(l.direction).max(0.0)
        }
    };
    let c = hit.color * (light * visible);
    [c.x, c.y, c.z, 1.0]
}

/// `front` (premultiplied) over the opaque `back`.
#[inline]
pub(crate) fn over(front: [f32; 4], back: [f32; 4]) -> [f32; 4] {
    let k = 1.0 - front[3];
    [
        front[0] + k * back[0],
        front[1] + k * back[1],
        front[2] + k * back[2],
        front[3] + k * back[3],
    ]
}

/// The visible fraction at an iso-surface hit at `p` with field gradient
/// `gradient`, seen along `ray` (1 without ambient occlusion). `salt`
/// numbers the hits along one camera ray.
#[inline]
pub(crate) fn iso_visibility<V: Volume>(
    volume: &V,
    p: Vec3,
    gradient: Vec3,
    ray: &Ray,
    ctx: &Ctx,
    rng: &PixelRng,
    salt: u32,
) -> f32 {
    if ctx.settings.ao.is_none() {
        return 1.0;
    }
    let g = gradient.normalized();
    if !(g.length_squared() > 0.0) {
        return 1.0;
    }
    // The side of the surface the viewer is on.
    let n = if g.dot(ray.dir) > 0.0 { g * -1.0 } else { g };
    1.0 - occlusion(volume, p, n, ctx, rng, salt)
}
