//! What an integrator on another device (the GPU backend) needs from this
//! crate to place its samples where the CPU places them: each pixel
//! sample's ray, the part of it inside the volume and clip box, and the
//! first boundary of its sample lattice ([`LatticeRay`]). A device that
//! samples each lattice cell of `[lo, hi]` at its midpoint, with the
//! cell's length as the segment length, takes the samples the CPU takes
//! (module `march`): the CPU skips only cells whose midpoint lies in no
//! visible interval, where the transfer function's opacity is zero.

use rayon::prelude::*;
use voxless_core::{Camera, Interval, Range1, Volume};

use crate::cursor::step_in;
use crate::spans::{RaySpans, region};
use crate::{RenderSettings, pixel_ray};

/// One pixel sample's ray for a device integrator (48 bytes, `f32`s as a
/// GPU buffer lays them out). An empty span (`lo >= hi`) is a ray that
/// misses the volume.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct LatticeRay {
    pub origin: [f32; 3],
    /// The lattice boundary at or before `lo` the walk starts from:
    /// boundary `k` is `t0 + k·dt`.
    pub t0: f32,
    pub dir: [f32; 3],
    /// The lattice step.
    pub dt: f32,
    /// The span sampled: cells are cut to it.
    pub lo: f32,
    pub hi: f32,
    pub _pad: [f32; 2],
}

/// Why a render cannot go to a device integrator: the first setting it
/// does not carry (a front-end names it in its error, or falls back to the
/// CPU).
pub fn device_unsupported(settings: &RenderSettings) -> Option<&'static str> {
    if settings.scatter.is_some() {
        Some("single scattering (--shadows)")
    } else if !settings.iso.is_empty() || !settings.volume {
        Some("iso-surfaces (--iso)")
    } else if settings.surfaces.is_some() {
        Some("surface meshes (--mesh)")
    } else if settings.ao.is_some() {
        Some("ambient occlusion (--ao)")
    } else if !settings.mirrors.is_empty() {
        Some("mirror instances (--mirror)")
    } else if settings.domain.is_some() {
        Some("a domain decomposition (mpirun)")
    } else {
        None
    }
}

/// The rays of pass `sample` of every pixel (row-major), for a volume
/// whose sampled intervals step `nominal_dt` (over the sampling rate,
/// unless the settings fix the step).
pub fn lattice_rays<V: Volume>(
    volume: &V,
    camera: &Camera,
    settings: &RenderSettings,
    nominal_dt: f32,
    sample: u32,
) -> Vec<LatticeRay> {
    let region = region(volume, settings);
    let (w, h) = (settings.width, settings.height);
    let ray_at = |x: u32, y: u32| {
        let (rng, ray) = pixel_ray(camera, settings, x, y, sample);
        let spans = RaySpans::new(&region, settings, &ray, f32::INFINITY);
        let span = spans.cells;
        let mut r = LatticeRay {
            origin: ray.origin.to_array(),
            dir: ray.dir.to_array(),
            lo: 1.0,
            hi: 0.0,
            ..LatticeRay::default()
        };
        if !span.is_empty() {
            // The step of one interval over the whole span (the CPU's
            // guards against steps below f32's resolution use the
            // interval's own ends; they act only where the settings'
            // step is below what f32 resolves along the ray).
            let whole = Interval::sampled(span, Range1::new(0.0, 0.0), nominal_dt);
            let dt = step_in(&whole, settings);
            // The cursor's lattice (module `cursor`): boundaries at
            // (n + ξ)·dt, the walk starting one cell before the span.
            let xi = rng.uniform(2) as f64;
            let n = ((span.lo as f64 / dt as f64 - xi).floor() as i64).saturating_sub(1);
            r.t0 = ((n as f64 + xi) * dt as f64) as f32;
            r.dt = dt;
            r.lo = span.lo;
            r.hi = span.hi;
        }
        r
    };
    // Rows in parallel, each in order: row-major.
    (0..h)
        .into_par_iter()
        .flat_map_iter(|y| (0..w).map(move |x| ray_at(x, y)))
        .collect()
}
