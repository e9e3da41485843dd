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
//!
//! The passes ([`run_passes`]) are generic over what a ray does with its
//! samples ([`Integrator`]): emission–absorption here, free flights of
//! single scattering in module `scatter_packet`.

use voxless_core::{Attribute, Interval, IntervalQuery, Ray, Sample, SampleBatch, Vec3, Volume};

use crate::Tile;
use crate::classify::Classified;
use crate::composite::{self, Run};
use crate::ctx::Ctx;
use crate::cursor::{Cursor, RayIntervals, Segment};
use crate::march::{Accumulator, RayState, RayStats};
use crate::sampling::PixelRng;
use crate::spans::RaySpans;

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

/// Where one ray of a packet is in its samples.
pub(crate) struct Lane {
    /// Index of the ray (and of its intervals) in the arrays a pass gets.
    pub r: usize,
    cursor: Cursor,
    /// The next segment, already taken from the cursor.
    next: Option<Segment>,
    pub done: bool,
}

impl Lane {
    /// Lane of ray `r`, its first segment taken from `cursor` (done at once
    /// when it has none, or when `empty`).
    pub fn start<V: Volume>(
        r: usize,
        mut cursor: Cursor,
        empty: bool,
        (volume, ray, ivs): (&V, &Ray, &mut RayIntervals),
        query: &IntervalQuery,
        ctx: &Ctx,
    ) -> Lane {
        // The first segment: a walk that stops at once.
        let mut next = None;
        if !empty {
            cursor.walk_in(ivs, volume, ray, query, ctx.settings, |seg, _| {
                next = Some(seg);
                false
            });
        }
        Lane {
            r,
            cursor,
            next,
            done: next.is_none(),
        }
    }
}

/// What a ray of a packet does with its samples, front to back.
pub(crate) trait Integrator {
    fn lane(&mut self) -> &mut Lane;
    /// Whether [`Integrator::feed`] reads the gradient (the batch computes
    /// it only then).
    fn needs_gradient(ctx: &Ctx) -> bool {
        ctx.needs_gradient()
    }
    /// Whether plain samples (a scalar value, no attribute) go to
    /// [`Integrator::feed_classified`], classified in lanes.
    fn classifies_in_lanes(_: &Ctx) -> bool {
        false
    }
    /// A plain sample's segment with its colour `c` and opacity `a` from
    /// [`Classified`] (only called when [`Integrator::classifies_in_lanes`]).
    fn feed_classified(&mut self, _c: Vec3, _a: f32, _gradient: Vec3, _ctx: &Ctx) -> bool {
        unreachable!("an integrator that classifies in lanes takes its samples")
    }
    /// The ray's pixel, when its plain samples may be composited in lanes
    /// ([`crate::composite`]: [`Integrator::feed_classified`] is then
    /// emission–absorption without a light).
    fn pixel(&mut self) -> Option<&mut Accumulator> {
        None
    }
    /// One segment and its sample; true when the ray needs no more
    /// (opaque, or its scattering event found).
    #[allow(clippy::too_many_arguments)]
    fn feed<V: Volume>(
        &mut self,
        volume: &V,
        ray: &Ray,
        iv: &Interval,
        seg: Segment,
        sample: Option<Sample>,
        gradient: Vec3,
        ctx: &Ctx,
    ) -> bool;
    /// The ray ran out of segments.
    fn finish<V: Volume>(&mut self, volume: &V, ray: &Ray, ctx: &Ctx);
}

/// One ray of an emission–absorption packet.
struct PacketRay {
    lane: Lane,
    state: RayState,
}

impl Integrator for PacketRay {
    fn lane(&mut self) -> &mut Lane {
        &mut self.lane
    }
    fn classifies_in_lanes(ctx: &Ctx) -> bool {
        ctx.classifies_in_lanes()
    }
    #[inline(always)]
    fn feed_classified(&mut self, c: Vec3, a: f32, gradient: Vec3, ctx: &Ctx) -> bool {
        self.state.feed_classified(c, a, gradient, ctx)
    }
    fn pixel(&mut self) -> Option<&mut Accumulator> {
        Some(self.state.pixel())
    }
    #[inline]
    fn feed<V: Volume>(
        &mut self,
        volume: &V,
        ray: &Ray,
        iv: &Interval,
        seg: Segment,
        sample: Option<Sample>,
        gradient: Vec3,
        ctx: &Ctx,
    ) -> bool {
        self.state.feed(volume, ray, iv, seg, sample, gradient, ctx)
    }
    fn finish<V: Volume>(&mut self, volume: &V, ray: &Ray, ctx: &Ctx) {
        self.state.finish(volume, ray, ctx);
    }
}

/// Buffers of one pass, reused across passes and packets.
#[derive(Default)]
pub(crate) struct PassScratch {
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
    /// Per sample in `t`, its value alone (NaN: no sample), when `plain`:
    /// the volume gave values instead of filling `out`.
    values: Vec<f32>,
    plain: bool,
    /// Per sample in `t`, its segment's length and normalised value, and
    /// what the lanes made of them (when the integrator classifies in
    /// lanes).
    len: Vec<f32>,
    x: Vec<f32>,
    classified: Classified,
    /// Per ray composited in lanes: its index in `gathered`, and its run.
    lane_rays: Vec<usize>,
    runs: Vec<Run>,
}

/// Scratch reused across the packets of a tile.
#[derive(Default)]
pub(crate) struct PacketScratch {
    rays: Vec<PacketRay>,
    pub pass: PassScratch,
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
    for (px, py, pw, ph) in packets(tile) {
        scratch.rays.clear();
        for y in py..py + ph {
            for x in px..px + pw {
                let r = (y * tile.w + x) as usize;
                let spans = &input.spans[r];
                scratch.rays.push(PacketRay {
                    lane: Lane::start(
                        r,
                        spans.cursor(&input.rngs[r]),
                        spans.is_empty(),
                        (volume, &input.rays[r], &mut ivs[r]),
                        input.query,
                        ctx,
                    ),
                    state: RayState::new(spans.cells, input.alpha0[r], input.rngs[r]),
                });
            }
        }
        run_passes(
            volume,
            ctx,
            (input.rays, ivs),
            input.query,
            &mut scratch.rays,
            &mut scratch.pass,
        );
        for p in &scratch.rays {
            out[p.lane.r] = p.state.rgba();
            stats.merge(&p.state.stats);
        }
    }
}

/// The packets of a tile: (x, y, width, height) in tile pixels.
pub(crate) fn packets(tile: Tile) -> impl Iterator<Item = (u32, u32, u32, u32)> {
    (0..tile.h).step_by(PACKET as usize).flat_map(move |py| {
        (0..tile.w)
            .step_by(PACKET as usize)
            .map(move |px| (px, py, PACKET.min(tile.w - px), PACKET.min(tile.h - py)))
    })
}

/// Runs passes until every ray of `items` is done. A lane's `r` indexes
/// `rays` and `ivs`.
pub(crate) fn run_passes<V: Volume, I: Integrator>(
    volume: &V,
    ctx: &Ctx,
    (rays, ivs): (&[Ray], &mut [RayIntervals]),
    query: &IntervalQuery,
    items: &mut [I],
    s: &mut PassScratch,
) {
    let settings = ctx.settings;
    let gradient = I::needs_gradient(ctx);
    let lanes = I::classifies_in_lanes(ctx);
    loop {
        // The window starts at the ray that is furthest behind.
        let Some((t0, dt)) = items
            .iter_mut()
            .map(|i| i.lane())
            .filter(|l| !l.done)
            .filter_map(|l| l.next.map(|n| (n.t, l.cursor.dt())))
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
        s.len.clear();
        s.segs.clear();
        s.gathered.clear();
        s.offsets.push(0);
        for (i, item) in items.iter_mut().enumerate() {
            let p = item.lane();
            if p.done {
                continue;
            }
            let ivs = &mut ivs[p.r];
            let ray = &rays[p.r];
            let (first_seg, first_t) = (s.segs.len(), s.t.len());
            // Takes a segment into the pass, or refuses it when it lies past
            // the window (or the ray has its fill). The furthest-behind ray
            // always takes its first segment, so every pass advances even
            // if `t0 + window` rounds to `t0`.
            let mut take = |seg: Segment, iv: &Interval| {
                let n = s.segs.len() - first_seg;
                let leads = seg.t == t0 && n == 0;
                if (seg.t >= window_end && !leads) || n >= MAX_PER_RAY {
                    return false;
                }
                if iv.constant_value().is_some() {
                    s.segs.push((seg, CONSTANT));
                } else {
                    s.segs.push((seg, s.t.len() as u32));
                    s.t.push(seg.t);
                    if lanes {
                        s.len.push(seg.len);
                    }
                    s.hints.push(iv.hint);
                }
                true
            };
            // The segment the lane holds first, then the cursor's, one walk
            // for the whole window; a refused segment is held for the next
            // pass.
            if let Some(seg) = p.next {
                let mut refused = None;
                let stopped = !take(seg, &ivs.list[seg.interval as usize])
                    || p.cursor
                        .walk_in(ivs, volume, ray, query, settings, |seg, iv| {
                            take(seg, iv) || {
                                refused = Some(seg);
                                false
                            }
                        });
                p.next = if stopped { refused.or(Some(seg)) } else { None };
            }
            if s.t.len() > first_t {
                s.batch_rays.push(*ray);
                s.offsets.push(s.t.len() as u32);
            }
            s.gathered.push((i, first_seg, s.segs.len()));
        }
        // `out` is not cleared: the volume sizes it (see `sample_batch`).
        // An integrator that classifies in lanes reads plain values only,
        // so a volume that can give them alone does.
        s.plain = false;
        if !s.t.is_empty() {
            let batch = SampleBatch {
                rays: &s.batch_rays,
                offsets: &s.offsets,
                t: &s.t,
                hints: Some(&s.hints),
            };
            s.plain = lanes && !gradient && volume.sample_batch_values(&batch, &mut s.values);
            if !s.plain {
                volume.sample_batch(&batch, gradient, &mut s.out);
            }
            if lanes {
                // Colour and opacity of every sample at once; the rays below
                // only accumulate them in order.
                s.x.clear();
                if s.plain {
                    s.x.extend(s.values.iter().map(|&v| {
                        if v.is_nan() {
                            0.0
                        } else {
                            settings.normalize(v)
                        }
                    }));
                } else {
                    s.x.extend(s.out.iter().map(|(sample, _)| match sample {
                        Some(v) => settings.normalize(v.value),
                        None => 0.0,
                    }));
                }
                s.classified.compute(
                    settings.simd,
                    ctx.tf,
                    settings.opacity_scale,
                    &mut s.x,
                    &mut s.len,
                );
                if s.plain {
                    // No sample adds nothing, as an opacity below zero does.
                    for (a, v) in s.classified.alpha.iter_mut().zip(&s.values) {
                        if v.is_nan() {
                            *a = -1.0;
                        }
                    }
                }
            }
        }
        // Rays whose samples here were all classified composite eight at
        // a time; the rest go one by one below.
        composite_in_lanes(volume, ctx, rays, items, s, lanes);
        // Every other ray takes its samples front to back from the buffer.
        let mut in_lanes = s.lane_rays.iter().peekable();
        for (g, &(i, lo, hi)) in s.gathered.iter().enumerate() {
            if in_lanes.next_if(|&&l| l == g).is_some() {
                continue;
            }
            let item = &mut items[i];
            let r = item.lane().r;
            let ray = &rays[r];
            let ivs = &ivs[r].list;
            let mut done = false;
            for &(seg, slot) in &s.segs[lo..hi] {
                // A plain sample (from `values`, or one without attribute in
                // `out`) was classified in lanes above: its colour and
                // opacity are ready, with no interval to look at.
                if s.is_classified(lanes, slot) {
                    let (k, cl) = (slot as usize, &s.classified);
                    let c = Vec3::new(cl.rgb[0][k], cl.rgb[1][k], cl.rgb[2][k]);
                    let g = if s.plain { Vec3::ZERO } else { s.out[k].1 };
                    if item.feed_classified(c, cl.alpha[k], g, ctx) {
                        done = true;
                        break;
                    }
                    continue;
                }
                let iv = &ivs[seg.interval as usize];
                let (sample, g) = match iv.constant_value() {
                    Some(v) => (Some(Sample::scalar(v)), Vec3::ZERO),
                    None => s.out[slot as usize],
                };
                if item.feed(volume, ray, iv, seg, sample, g, ctx) {
                    done = true;
                    break;
                }
            }
            if !done && item.lane().next.is_none() {
                item.finish(volume, ray, ctx);
                done = true;
            }
            item.lane().done = done;
        }
    }
}

impl PassScratch {
    /// Whether the sample in `slot` was classified in lanes: a plain value,
    /// or an `out` sample without an attribute (`lanes`: the integrator
    /// classifies in lanes).
    #[inline(always)]
    fn is_classified(&self, lanes: bool, slot: u32) -> bool {
        lanes
            && slot != CONSTANT
            && (self.plain
                || matches!(
                    self.out[slot as usize].0,
                    Some(Sample {
                        attribute: Attribute::None,
                        ..
                    })
                ))
    }
}

/// Composites the rays of a pass whose samples were all classified in
/// lanes eight at a time ([`crate::composite`]), when there is no light
/// (so [`Integrator::feed_classified`] is plain compositing), and lists
/// them in `s.lane_rays` (indices into `s.gathered`, ascending). A ray
/// with a constant segment, or a sample that is missing or carries an
/// attribute, stays with the one-by-one loop.
fn composite_in_lanes<V: Volume, I: Integrator>(
    volume: &V,
    ctx: &Ctx,
    rays: &[Ray],
    items: &mut [I],
    s: &mut PassScratch,
    lanes: bool,
) {
    s.lane_rays.clear();
    s.runs.clear();
    if !lanes || ctx.settings.light.is_some() {
        return;
    }
    for (g, &(i, lo, hi)) in s.gathered.iter().enumerate() {
        let segs = &s.segs[lo..hi];
        // A ray's slots are consecutive when none of its segments is
        // constant (a constant segment takes no slot).
        if !segs.iter().all(|&(_, slot)| s.is_classified(lanes, slot)) {
            continue;
        }
        let Some(px) = items[i].pixel() else {
            continue;
        };
        s.runs.push(Run {
            first: segs.first().map_or(0, |&(_, slot)| slot),
            n: segs.len() as u32,
            color: [px.color.x, px.color.y, px.color.z],
            alpha: px.alpha,
            done: false,
        });
        s.lane_rays.push(g);
    }
    let settings = ctx.settings;
    composite::composite(
        settings.simd,
        &mut s.runs,
        &s.classified,
        settings.early_termination,
    );
    for (&g, run) in s.lane_rays.iter().zip(&s.runs) {
        let item = &mut items[s.gathered[g].0];
        if let Some(px) = item.pixel() {
            px.color = Vec3::new(run.color[0], run.color[1], run.color[2]);
            px.alpha = run.alpha;
        }
        let mut done = run.done;
        if !done && item.lane().next.is_none() {
            let r = item.lane().r;
            item.finish(volume, &rays[r], ctx);
            done = true;
        }
        item.lane().done = done;
    }
}
