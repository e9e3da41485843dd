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
//! image; only the sums inside the volume may run in another order. Each
//! ray asks the volume for its intervals as its cursor reaches them, so a
//! ray that turns opaque asks for nothing behind.

use voxless_core::{IntervalQuery, Ray, Sample, SampleBatch, Vec3, Volume};

use crate::Tile;
use crate::cursor::{Cursor, RayIntervals, Segment};
use crate::march::{Ctx, RaySpans, RayState, RayStats};
use crate::sampling::PixelRng;

/// Side of a packet in pixels.
pub const PACKET: u32 = 8;
/// Depth window of a pass, in steps of the ray that is furthest behind.
pub const WINDOW_STEPS: f32 = 32.0;
/// At most this many samples of one ray per pass (tiny steps in a wide window).
const MAX_PER_RAY: usize = 256;
/// Marks a segment of a constant interval: it takes no slot in the batch.
const CONSTANT: u32 = u32::MAX;

/// A tile's rays, their random streams, spans and starting opacities
/// (row-major), and the query their intervals are asked with.
pub(crate) struct TileInput<'a> {
    pub rays: &'a [Ray],
    pub rngs: &'a [PixelRng],
    pub spans: &'a [RaySpans],
    pub alpha0: &'a [f32],
    pub query: &'a IntervalQuery<'a>,
}

/// One ray of a packet.
struct PacketRay {
    /// Index of the ray in the tile.
    r: usize,
    cursor: Cursor,
    /// The next segment, already taken from the cursor.
    next: Option<Segment>,
    state: RayState,
    done: bool,
}

/// Scratch reused across the packets of a tile.
#[derive(Default)]
pub(crate) struct PacketScratch {
    rays: Vec<PacketRay>,
    batch_rays: Vec<Ray>,
    offsets: Vec<u32>,
    t: Vec<f32>,
    /// Per sample in `t`, the hint of its interval.
    hints: Vec<u32>,
    /// Per gathered segment, its slot in `t`/`out` (or [`CONSTANT`]).
    segs: Vec<(Segment, u32)>,
    /// Per ray gathered in a pass: (packet ray, its first and end segment).
    gathered: Vec<(usize, usize, usize)>,
    out: Vec<(Option<Sample>, Vec3)>,
}

/// Renders `tile` with packets; pixels row-major into `out`. `ivs` holds
/// each ray's intervals (started, or complete from a tile view).
#[allow(clippy::too_many_arguments)]
pub(crate) fn render_tile<V: Volume>(
    volume: &V,
    ctx: &Ctx,
    tile: Tile,
    input: TileInput,
    ivs: &mut [RayIntervals],
    scratch: &mut PacketScratch,
    out: &mut Vec<[f32; 4]>,
    stats: &mut RayStats,
) {
    out.clear();
    out.resize((tile.w * tile.h) as usize, [0.0; 4]);
    for py in (0..tile.h).step_by(PACKET as usize) {
        for px in (0..tile.w).step_by(PACKET as usize) {
            let pw = PACKET.min(tile.w - px);
            let ph = PACKET.min(tile.h - py);
            scratch.rays.clear();
            for y in py..py + ph {
                for x in px..px + pw {
                    let r = (y * tile.w + x) as usize;
                    let spans = &input.spans[r];
                    let mut p = PacketRay {
                        r,
                        cursor: spans.cursor(&input.rngs[r]),
                        next: None,
                        state: RayState::new(spans.cells, input.alpha0[r], input.rngs[r]),
                        done: spans.is_empty(),
                    };
                    if !p.done {
                        p.next = p.cursor.next_in(
                            &mut ivs[r],
                            volume,
                            &input.rays[r],
                            input.query,
                            ctx.settings,
                        );
                        p.done = p.next.is_none();
                    }
                    scratch.rays.push(p);
                }
            }
            run_packet(volume, ctx, &input, ivs, scratch);
            for p in &scratch.rays {
                out[p.r] = p.state.rgba();
                stats.merge(&p.state.stats);
            }
        }
    }
}

/// Runs passes until every ray of the packet is done.
fn run_packet<V: Volume>(
    volume: &V,
    ctx: &Ctx,
    input: &TileInput,
    ivs: &mut [RayIntervals],
    s: &mut PacketScratch,
) {
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
        // Gather each running ray's segments inside the window; samples of
        // constant intervals need no slot in the batch.
        s.batch_rays.clear();
        s.offsets.clear();
        s.t.clear();
        s.hints.clear();
        s.segs.clear();
        s.gathered.clear();
        s.offsets.push(0);
        for (i, p) in s.rays.iter_mut().enumerate() {
            if p.done {
                continue;
            }
            let ivs = &mut ivs[p.r];
            let ray = &input.rays[p.r];
            let (first_seg, first_t) = (s.segs.len(), s.t.len());
            while let Some(seg) = p.next {
                // The furthest-behind ray always takes its first sample, so
                // every pass advances even if `t0 + window` rounds to `t0`.
                let leads = seg.t == t0 && s.segs.len() == first_seg;
                if (seg.t >= window_end && !leads) || s.segs.len() - first_seg >= MAX_PER_RAY {
                    break;
                }
                let iv = &ivs.list[seg.interval as usize];
                if iv.constant_value().is_some() {
                    s.segs.push((seg, CONSTANT));
                } else {
                    s.segs.push((seg, s.t.len() as u32));
                    s.t.push(seg.t);
                    s.hints.push(iv.hint);
                }
                p.next = p.cursor.next_in(ivs, volume, ray, input.query, settings);
            }
            if s.t.len() > first_t {
                s.batch_rays.push(input.rays[p.r]);
                s.offsets.push(s.t.len() as u32);
            }
            s.gathered.push((i, first_seg, s.segs.len()));
        }
        s.out.clear();
        if !s.t.is_empty() {
            volume.sample_batch(
                &SampleBatch {
                    rays: &s.batch_rays,
                    offsets: &s.offsets,
                    t: &s.t,
                    hints: Some(&s.hints),
                },
                gradient,
                &mut s.out,
            );
        }
        // Composite every ray front to back from the buffer.
        for &(i, lo, hi) in &s.gathered {
            let p = &mut s.rays[i];
            let ray = &input.rays[p.r];
            let ivs = &ivs[p.r].list;
            for &(seg, slot) in &s.segs[lo..hi] {
                let iv = &ivs[seg.interval as usize];
                let (sample, g) = match iv.constant_value() {
                    Some(v) => (Some(Sample::scalar(v)), Vec3::ZERO),
                    None => s.out[slot as usize],
                };
                if p.state.feed(volume, ray, iv, seg, sample, g, ctx) {
                    p.done = true;
                    break;
                }
            }
            if !p.done && p.next.is_none() {
                p.state.finish(volume, ray, ctx);
                p.done = true;
            }
        }
    }
}
