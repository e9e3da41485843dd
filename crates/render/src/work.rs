//! What a render will cost, estimated before it starts: a render whose
//! radius or step lies far below the data's scale would otherwise run for
//! hours with no output.

use rayon::prelude::*;
use voxless_core::{Camera, IntervalQuery, Range1, Volume};
use voxless_transfer::TransferFunction;

use crate::RenderSettings;
use crate::cursor::step_in;
use crate::spans::region;

/// What a render is expected to cost, before it starts (see
/// [`estimate_work`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorkEstimate {
    /// Mean samples (field evaluations, or constant pieces) per camera ray.
    pub per_ray: f64,
    /// The most samples of any probed ray.
    pub max_per_ray: f64,
    /// `per_ray` × pixels × passes (× 2 with shadow rays).
    pub total: f64,
    /// Whether some interval's step was raised to the resolution of f32 at
    /// its distance along the ray (see [`crate::step_in`]): the step asked
    /// for is finer than the ray's coordinates can tell apart.
    pub step_raised: bool,
}

/// Rays per image axis that [`estimate_work`] traces.
const ESTIMATE_RAYS: u32 = 16;

/// The samples a render of `volume` with these settings will take, from
/// the intervals of an [`ESTIMATE_RAYS`]² grid of camera rays and the
/// integrators' own step rule ([`step_in`]; constant pieces count one
/// each). Early termination is ignored, so this is an upper estimate: it
/// tells a render that would run for hours (a radius or step far below the
/// data's scale) before it starts.
pub fn estimate_work<V: Volume>(
    volume: &V,
    camera: &Camera,
    tf: &TransferFunction,
    settings: &RenderSettings,
) -> WorkEstimate {
    let region = region(volume, settings);
    let is_visible = |r: Range1| settings.is_visible(tf, r);
    let query = IntervalQuery {
        is_visible: &is_visible,
    };
    let n = ESTIMATE_RAYS;
    let counts: Vec<(f64, bool)> = (0..n * n)
        .into_par_iter()
        .map(|k| {
            let (x, y) = (k % n, k / n);
            let px = (x as f32 + 0.5) / n as f32 * settings.width as f32;
            let py = (y as f32 + 0.5) / n as f32 * settings.height as f32;
            let ray = camera.ray(px, py, settings.width, settings.height);
            let t = region.clip_ray(&ray, Range1::new(0.0, f32::INFINITY));
            if t.is_empty() {
                return (0.0, false);
            }
            let mut out = Vec::new();
            volume.intervals(&ray, t, &query, &mut out);
            let mut raised = false;
            let samples = out
                .iter()
                .map(|iv| {
                    if iv.constant_value().is_some() {
                        return 1.0;
                    }
                    let asked = settings
                        .step
                        .unwrap_or(iv.nominal_dt / settings.sampling_rate);
                    let dt = step_in(iv, settings);
                    raised |= dt > asked && dt > iv.t.span() * 1e-6;
                    (iv.t.span() as f64 / dt as f64).ceil()
                })
                .sum::<f64>();
            (samples, raised)
        })
        .collect();
    let per_ray = counts.iter().map(|c| c.0).sum::<f64>() / counts.len().max(1) as f64;
    let max_per_ray = counts.iter().fold(0.0f64, |m, c| m.max(c.0));
    let shadows = if settings.scatter.is_some() { 2.0 } else { 1.0 };
    let total = per_ray
        * settings.width as f64
        * settings.height as f64
        * settings.spp.max(1) as f64
        * shadows;
    WorkEstimate {
        per_ray,
        max_per_ray,
        total,
        step_raised: counts.iter().any(|c| c.1),
    }
}
