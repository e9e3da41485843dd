//! The packet path (CPU RBF paper §4): rays of a small screen block march
//! together. Each pass takes, for every ray still running, its next samples
//! inside a common depth window, has the volume fill the whole sample buffer
//! at once ([`Volume::sample_batch`] — for particles, one BVH traversal that
//! visits each particle once per packet and pass), then composites every ray
//! front to back from the buffer. Passes repeat until every ray of the packet
//! is opaque or out of samples (multi-pass early termination, §4.2).
//!
//! Samples are placed by the same [`Cursor`] and composited by the same
//! [`RayState::feed`] as [`crate::march`], so the packet path draws the same
//! image; only the sums inside the volume may run in another order.

use voxless_core::{Camera, Interval, Ray, Sample, SampleBatch, Vec3, Volume};
use voxless_transfer::TransferFunction;

use crate::march::{Ctx, Cursor, RayState, Segment, ray_intervals};
use crate::sampling::PixelRng;
use crate::{RenderSettings, Tile};

/// Side of a packet in pixels.
pub const PACKET: u32 = 8;
/// Depth window of a pass, in steps of the ray that is furthest behind.
pub const WINDOW_STEPS: f32 = 32.0;
/// At most this many samples of one ray per pass (tiny steps in a wide window).
const MAX_PER_RAY: usize = 256;

/// One ray of a packet.
struct PacketRay {
    ray: Ray,
    rng: PixelRng,
    /// This ray's intervals: `intervals[iv_lo..iv_hi]` of the packet's list.
    iv_lo: usize,
    iv_hi: usize,
    cursor: Cursor,
    /// The next segment, already taken from the cursor.
    next: Option<Segment>,
    state: RayState,
    done: bool,
}

/// Scratch reused across the packets of a tile.
#[derive(Default)]
pub(crate) struct PacketScratch {
    intervals: Vec<Interval>,
    rays: Vec<PacketRay>,
    batch_rays: Vec<Ray>,
    batch_owner: Vec<usize>,
    offsets: Vec<u32>,
    t: Vec<f32>,
    segs: Vec<Segment>,
    out: Vec<(Option<Sample>, Vec3)>,
}

/// Renders sample index `sample` of `tile` with packets; pixels row-major.
#[allow(clippy::too_many_arguments)]
pub(crate) fn render_tile<V: Volume>(
    volume: &V,
    camera: &Camera,
    tf: &TransferFunction,
    settings: &RenderSettings,
    sample: u32,
    tile: Tile,
    scratch: &mut PacketScratch,
    out: &mut Vec<[f32; 4]>,
) {
    out.clear();
    out.resize((tile.w * tile.h) as usize, [0.0; 4]);
    let ctx = Ctx::new(tf, settings);
    for py in (0..tile.h).step_by(PACKET as usize) {
        for px in (0..tile.w).step_by(PACKET as usize) {
            let pw = PACKET.min(tile.w - px);
            let ph = PACKET.min(tile.h - py);
            scratch.intervals.clear();
            scratch.rays.clear();
            for y in tile.y + py..tile.y + py + ph {
                for x in tile.x + px..tile.x + px + pw {
                    let (rng, ray) = crate::pixel_ray(camera, settings, x, y, sample);
                    let iv_lo = scratch.intervals.len();
                    let hit = ray_intervals(
                        volume,
                        &ray,
                        tf,
                        settings,
                        f32::INFINITY,
                        &mut scratch.intervals,
                    );
                    let mut r = PacketRay {
                        ray,
                        rng,
                        iv_lo,
                        iv_hi: scratch.intervals.len(),
                        cursor: Cursor::default(),
                        next: None,
                        state: RayState::default(),
                        done: !hit,
                    };
                    r.next = r
                        .cursor
                        .next(&scratch.intervals[r.iv_lo..r.iv_hi], settings, &r.rng);
                    r.done |= r.next.is_none();
                    scratch.rays.push(r);
                }
            }
            run_packet(volume, &ctx, scratch);
            for (i, r) in scratch.rays.iter().enumerate() {
                let (x, y) = (px + i as u32 % pw, py + i as u32 / pw);
                out[(y * tile.w + x) as usize] = r.state.rgba();
            }
        }
    }
}

/// Runs passes until every ray of the packet is done.
fn run_packet<V: Volume>(volume: &V, ctx: &Ctx, s: &mut PacketScratch) {
    let settings = ctx.settings;
    let gradient = ctx.needs_gradient();
    loop {
        // The window starts at the ray that is furthest behind.
        let Some((t0, dt)) = s
            .rays
            .iter()
            .filter(|r| !r.done)
            .filter_map(|r| r.next.map(|n| (n.t, r.cursor.dt())))
            .min_by(|a, b| a.0.total_cmp(&b.0))
        else {
            return;
        };
        let window_end = t0 + WINDOW_STEPS * dt;
        // Gather each running ray's segments inside the window.
        s.batch_rays.clear();
        s.batch_owner.clear();
        s.offsets.clear();
        s.t.clear();
        s.segs.clear();
        s.offsets.push(0);
        for (i, r) in s.rays.iter_mut().enumerate() {
            if r.done {
                continue;
            }
            let ivs = &s.intervals[r.iv_lo..r.iv_hi];
            let first = s.t.len();
            while let Some(seg) = r.next {
                // The furthest-behind ray always takes its first sample, so
                // every pass advances even if `t0 + window` rounds to `t0`.
                let leads = seg.t == t0 && s.t.len() == first;
                if (seg.t >= window_end && !leads) || s.t.len() - first >= MAX_PER_RAY {
                    break;
                }
                s.t.push(seg.t);
                s.segs.push(seg);
                r.next = r.cursor.next(ivs, settings, &r.rng);
            }
            if s.t.len() > first {
                s.batch_rays.push(r.ray);
                s.batch_owner.push(i);
                s.offsets.push(s.t.len() as u32);
            }
        }
        s.out.clear();
        volume.sample_batch(
            &SampleBatch {
                rays: &s.batch_rays,
                offsets: &s.offsets,
                t: &s.t,
            },
            gradient,
            &mut s.out,
        );
        // Composite every ray front to back from the buffer.
        for (b, &owner) in s.batch_owner.iter().enumerate() {
            let r = &mut s.rays[owner];
            let ivs = &s.intervals[r.iv_lo..r.iv_hi];
            for j in s.offsets[b] as usize..s.offsets[b + 1] as usize {
                let seg = s.segs[j];
                let (sample, g) = s.out[j];
                let iv = &ivs[seg.interval as usize];
                if r.state.feed(volume, &r.ray, iv, seg, sample, g, ctx) {
                    r.done = true;
                    break;
                }
            }
            r.done |= r.next.is_none();
        }
    }
}
