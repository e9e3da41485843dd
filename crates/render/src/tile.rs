//! One tile of one pass: the tile's camera rays, their intervals (from the
//! volume's tile view when it has one, else ray by ray, a chunk at a time
//! as each ray goes), then one of the three integrators over those
//! intervals — packets, per-sample marching, or single scattering (on
//! packets too where the volume samples in batches).

use voxless_core::{IntervalLists, IntervalQuery, Range1, Ray, TileRays, Volume};

use crate::ctx::Ctx;
use crate::cursor::RayIntervals;
use crate::march::{RayStats, march_intervals};
use crate::packet::{self, PacketScratch};
use crate::ray_lanes;
use crate::sampling::PixelRng;
use crate::scatter::FreeFlight;
use crate::scatter_packet::{self, ScatterScratch};
use crate::spans::{RaySpans, region};
use crate::{Job, Tile, meshes, pixel_ray, scatter, surface};
use voxless_mesh::Hit;

/// Buffers reused across the tiles a thread renders.
#[derive(Default)]
struct Scratch {
    rays: Vec<Ray>,
    rngs: Vec<PixelRng>,
    spans: Vec<Range1>,
    ray_spans: Vec<RaySpans>,
    alpha0: Vec<f32>,
    /// A tile view's lists.
    lists: IntervalLists,
    /// Per ray, its intervals so far.
    ivs: Vec<RayIntervals>,
    shadow: Vec<voxless_core::Interval>,
    packet: PacketScratch,
    scatter: ScatterScratch,
    hits: Vec<Option<Hit>>,
}

thread_local! {
    static SCRATCH: std::cell::Cell<Option<Box<Scratch>>> = const { std::cell::Cell::new(None) };
}

/// Renders sample index `sample` of `tile`; pixels row-major, and what the
/// tile's rays saw. With `alpha0` (one value per pixel of the tile), only
/// the pixels with a finite value are rendered, each starting from that
/// opacity (the others are left transparent).
pub(crate) fn render_tile<V: Volume>(
    job: &Job<V>,
    tile: Tile,
    sample: u32,
    alpha0: Option<&[f32]>,
) -> (Vec<[f32; 4]>, RayStats) {
    // Taken out of the thread-local (not borrowed), so a volume that runs
    // rayon inside a call cannot re-enter a borrowed buffer.
    let mut s = SCRATCH.take().unwrap_or_default();
    let mut stats = RayStats::default();
    let out = render_with(job, tile, sample, alpha0, &mut s, &mut stats);
    SCRATCH.set(Some(s));
    (out, stats)
}

fn render_with<V: Volume>(
    job: &Job<V>,
    tile: Tile,
    sample: u32,
    alpha0: Option<&[f32]>,
    s: &mut Scratch,
    stats: &mut RayStats,
) -> Vec<[f32; 4]> {
    let (volume, settings, tf) = (job.volume, job.settings, job.tf);
    let region = region(volume, settings);
    let ctx = Ctx::new(tf, settings, volume.classified());
    // 1. The tile's rays, their nearest mesh hits, the part of each inside
    // the (clipped) volume and in front of its hit, and where its samples
    // lie.
    s.hits.clear();
    s.rays.clear();
    s.rngs.clear();
    s.spans.clear();
    s.ray_spans.clear();
    s.alpha0.clear();
    for y in tile.y..tile.y + tile.h {
        for x in tile.x..tile.x + tile.w {
            let (rng, ray) = pixel_ray(job.camera, settings, x, y, sample);
            let mut hit = meshes::nearest(&ctx, &ray);
            let t_max = hit.map_or(f32::INFINITY, |h| h.t);
            let mut spans = RaySpans::new(&region, settings, &ray, t_max);
            let a0 = match alpha0 {
                Some(a) => a[s.rays.len()],
                None => 0.0,
            };
            if !a0.is_finite() {
                spans.span = Range1::EMPTY;
                hit = None;
            }
            s.spans.push(spans.span);
            s.ray_spans.push(spans);
            s.alpha0.push(a0.max(0.0));
            s.rays.push(ray);
            s.rngs.push(rng);
            s.hits.push(hit);
        }
    }
    // 2. Their visible intervals: the whole tile at once where the volume
    // can, else each ray's asked for as its samples reach them (so nothing
    // is asked for behind the point where a ray turns opaque).
    let visible = |r: Range1| settings.is_visible(tf, r);
    let query = IntervalQuery {
        is_visible: &visible,
    };
    let n = s.rays.len();
    if s.ivs.len() < n {
        s.ivs.resize_with(n, RayIntervals::default);
    }
    match &job.view {
        Some(view) => {
            s.lists.clear();
            view.intervals(
                &TileRays {
                    x0: tile.x,
                    y0: tile.y,
                    w: tile.w,
                    h: tile.h,
                    rays: &s.rays,
                    t: &s.spans,
                    centred: sample == 0,
                },
                &query,
                &mut s.lists,
            );
            debug_assert_eq!(s.lists.rays(), n);
            for (r, ivs) in s.ivs[..n].iter_mut().enumerate() {
                ivs.complete(s.lists.of(r));
            }
        }
        None => {
            for (ivs, span) in s.ivs[..n].iter_mut().zip(&s.spans) {
                ivs.start(*span);
            }
        }
    }
    // 3. Integrate.
    let ivs = &mut s.ivs[..n];
    let mut out = Vec::with_capacity(n);
    let packets = settings.packets && volume.packet_sampling();
    let input = packet::TileInput {
        rays: &s.rays,
        rngs: &s.rngs,
        spans: &s.ray_spans,
        alpha0: &s.alpha0,
        query: &query,
    };
    if let Some(sc) = &settings.scatter {
        if packets && sc.method == FreeFlight::Marching {
            // Marching flights, camera and shadow rays, a packet at a time.
            scatter_packet::render_tile(
                volume,
                &ctx,
                sc,
                tile,
                sample,
                input,
                ivs,
                &mut s.scatter,
                &mut out,
            );
        } else {
            for (r, ray_ivs) in ivs.iter_mut().enumerate() {
                let (x, y) = (tile.x + r as u32 % tile.w, tile.y + r as u32 / tile.w);
                out.push(scatter::path(
                    volume,
                    &s.rays[r],
                    ray_ivs,
                    &query,
                    &s.ray_spans[r],
                    &ctx,
                    sc,
                    (x, y),
                    sample,
                    &mut s.shadow,
                ));
            }
        }
    } else if packets && ray_lanes::applies(volume, &ctx) {
        ray_lanes::render_tile(volume, &ctx, tile, input, ivs, &mut out);
    } else if packets {
        packet::render_tile(
            volume,
            &ctx,
            tile,
            input,
            ivs,
            &mut s.packet,
            &mut out,
            stats,
        );
    } else {
        for (r, ray_ivs) in ivs.iter_mut().enumerate() {
            out.push(march_intervals(
                volume,
                &s.rays[r],
                ray_ivs,
                &query,
                &s.ray_spans[r],
                s.alpha0[r],
                &s.rngs[r],
                &ctx,
                stats,
            ));
        }
    }
    // 4. The volume in front of each mesh hit over the shaded surface (not
    // in a box of a decomposition, which composites only its own samples).
    if settings.surfaces.is_some() && settings.domain.is_none() {
        for (r, px) in out.iter_mut().enumerate() {
            if let Some(hit) = &s.hits[r] {
                let pixel = (tile.x + r as u32 % tile.w, tile.y + r as u32 / tile.w);
                let back = surface::shade_hit(
                    volume,
                    hit,
                    &s.rays[r],
                    &ctx,
                    &s.rngs[r],
                    pixel,
                    sample,
                    &mut s.shadow,
                );
                *px = surface::over(*px, back);
            }
        }
    }
    out
}
