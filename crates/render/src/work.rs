//! What a render will cost, estimated before it starts: a render whose
//! radius or step lies far below the data's scale would otherwise run for
//! hours with no output.

use rayon::prelude::*;
use voxless_core::{
    Camera, Interval, IntervalLists, IntervalQuery, Range1, Ray, TileIntervals, TileRays, View,
    Volume,
};
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
/// the intervals of an [`ESTIMATE_RAYS`]² grid of camera rays (for a volume
/// with a tile view, the pixels of an image of about that many in the
/// view's shape, through the tile view) and the
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
    let count = |out: &[Interval]| {
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
    };
    let clipped = |ray: Ray| (ray, region.clip_ray(&ray, Range1::new(0.0, f32::INFINITY)));
    // A volume with a tile view (tessellations) answers as its renders get
    // their intervals: by tiles, with no per-ray index to build (seconds at
    // 10⁸ tets). Its grid is a small image of the view's shape (about n²
    // pixels: a perspective ray depends on the image's aspect).
    let aspect = settings.width as f64 / settings.height.max(1) as f64;
    let gw = ((n as f64 * aspect.sqrt()).round() as u32).clamp(1, settings.width.max(1));
    let gh = ((n as f64 / aspect.sqrt()).round() as u32).clamp(1, settings.height.max(1));
    let small = View {
        camera: *camera,
        width: gw,
        height: gh,
    };
    let counts: Vec<(f64, bool)> = match volume.tile_view(&small) {
        Some(tiles) => tiled_counts(
            &*tiles,
            (gw, gh),
            &|x, y| clipped(camera.ray(x as f32 + 0.5, y as f32 + 0.5, gw, gh)),
            &query,
            &count,
        ),
        None => (0..n * n)
            .into_par_iter()
            .map(|k| {
                let px = ((k % n) as f32 + 0.5) / n as f32 * settings.width as f32;
                let py = ((k / n) as f32 + 0.5) / n as f32 * settings.height as f32;
                let (ray, t) = clipped(camera.ray(px, py, settings.width, settings.height));
                if t.is_empty() {
                    return (0.0, false);
                }
                let mut out = Vec::new();
                volume.intervals(&ray, t, &query, &mut out);
                count(&out)
            })
            .collect(),
    };
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

/// The per-ray counts of the `gw × gh` grid of rays (`ray_t(x, y)`: the
/// ray and its clipped range), the pixels of the image the tile view
/// `tiles` was made for, row-major.
fn tiled_counts(
    tiles: &dyn TileIntervals,
    (gw, gh): (u32, u32),
    ray_t: &(dyn Fn(u32, u32) -> (Ray, Range1) + Sync),
    query: &IntervalQuery,
    count: &(dyn Fn(&[Interval]) -> (f64, bool) + Sync),
) -> Vec<(f64, bool)> {
    let s = tiles.tile_size().max(1);
    let (across, down) = (gw.div_ceil(s), gh.div_ceil(s));
    let per_tile: Vec<Vec<(u32, (f64, bool))>> = (0..across * down)
        .into_par_iter()
        .map(|i| {
            let (x0, y0) = ((i % across) * s, (i / across) * s);
            let (w, h) = (s.min(gw - x0), s.min(gh - y0));
            let (rays, t): (Vec<Ray>, Vec<Range1>) = (y0..y0 + h)
                .flat_map(|y| (x0..x0 + w).map(move |x| (x, y)))
                .map(|(x, y)| ray_t(x, y))
                .unzip();
            let tile = TileRays {
                x0,
                y0,
                w,
                h,
                rays: &rays,
                t: &t,
                centred: true,
            };
            let mut lists = IntervalLists::default();
            tiles.intervals(&tile, query, &mut lists);
            (0..(w * h) as usize)
                .map(|r| {
                    let (x, y) = (x0 + r as u32 % w, y0 + r as u32 / w);
                    (y * gw + x, count(lists.of(r)))
                })
                .collect()
        })
        .collect();
    let mut out = vec![(0.0, false); (gw * gh) as usize];
    for (k, c) in per_tile.into_iter().flatten() {
        out[k as usize] = c;
    }
    out
}
