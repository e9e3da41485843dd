//! Eight rays in SIMD lanes, one sample of each per step — for plain
//! emission–absorption renders (no light, no iso-surfaces, no attribute,
//! a linear value scale) of volumes that sample eight points in one call
//! ([`Volume::sample_values_lanes`]: AMR).
//!
//! Each lane holds one ray of a 4×2 block of neighbouring pixels. The
//! ray's [`Cursor`] places its samples on the same lattice as every other
//! path, a few segments at a time into the lane's queue. A step takes the
//! front segment of every lane, samples the eight points at once,
//! classifies them and composites them onto the eight pixels, all in
//! lanes. There is no sample buffer and no per-sample bookkeeping between
//! those stages — which is what a packet pass spends most of an AMR frame
//! on (docs/benchmarks.md). A lane whose ray turns opaque or runs out of
//! samples idles until the block is done; the next block then comes in.
//! (Handing such a lane the tile's next ray at once keeps the lanes fuller,
//! but its ray then crosses other regions than its neighbours', and the
//! step's eight samples need more bricks: measured slower.)
//!
//! Every ray gets the samples of [`crate::march`], each reconstructed,
//! classified and composited front to back with the arithmetic of the
//! packet path, which gives the per-sample path's bits: the image is the
//! same, bit for bit (tested against the packet path).

use voxless_core::simd::{LANES, Lanes, WithLanes, dispatch};
use voxless_core::{Interval, IntervalQuery, Range1, Ray, Volume};

use crate::Tile;
use crate::ctx::Ctx;
use crate::cursor::{Cursor, RayIntervals, Segment};
use crate::packet::TileInput;

/// Segments a lane holds ahead of its ray's next sample.
const QUEUE: usize = 32;
/// A lane without a ray.
const NONE: usize = usize::MAX;

/// Whether a render of `volume` with `ctx` marches rays in lanes.
pub(crate) fn applies<V: Volume>(volume: &V, ctx: &Ctx) -> bool {
    let s = ctx.settings;
    s.lanes
        && ctx.classifies_in_lanes()
        && s.light.is_none()
        && !s.log_scale
        && volume.samples_in_lanes()
}

/// Renders `tile` with eight rays in lanes; pixels row-major into `out`.
pub(crate) fn render_tile<V: Volume>(
    volume: &V,
    ctx: &Ctx,
    tile: Tile,
    input: TileInput,
    ivs: &mut [RayIntervals],
    out: &mut Vec<[f32; 4]>,
) {
    out.clear();
    out.resize((tile.w * tile.h) as usize, [0.0; 4]);
    dispatch(
        ctx.settings.simd,
        Job {
            volume,
            tile,
            ctx,
            input,
            ivs,
            out,
        },
    );
}

/// The segments the lanes hold, by field, lane `k`'s in the `QUEUE` slots
/// from `k · QUEUE` on, so a step gathers every lane's front segment with
/// one gather per field: the sample's `t`, the segment's length, the
/// interval's hint (its bits) and, for a constant interval, its value
/// (NaN for a sampled one).
struct Queues {
    t: [f32; LANES * QUEUE],
    len: [f32; LANES * QUEUE],
    hint: [f32; LANES * QUEUE],
    constant: [f32; LANES * QUEUE],
}

/// One lane: its ray and where that ray is in its samples.
struct Lane {
    /// The ray's index in the tile ([`NONE`]: no ray).
    r: usize,
    cursor: Cursor,
    /// A segment the cursor gave when the queue was full.
    held: Option<Segment>,
    /// Whether the cursor may have more segments.
    more: bool,
}

impl Lane {
    /// Refills lane `k`'s queue from the held segment and the cursor;
    /// returns how many segments it holds (none only when the ray has no
    /// more).
    fn refill<V: Volume>(
        &mut self,
        (k, q): (usize, &mut Queues),
        (volume, ray, ivs): (&V, &Ray, &mut RayIntervals),
        query: &IntervalQuery,
        ctx: &Ctx,
    ) -> usize {
        let Lane {
            cursor, held, more, ..
        } = self;
        let (base, mut end) = (k * QUEUE, 0);
        let mut push = |seg: Segment, iv: &Interval| {
            if end == QUEUE {
                return false;
            }
            let at = base + end;
            q.t[at] = seg.t;
            q.len[at] = seg.len;
            q.hint[at] = f32::from_bits(iv.hint);
            q.constant[at] = iv.constant_value().unwrap_or(f32::NAN);
            end += 1;
            true
        };
        if let Some(seg) = held.take() {
            push(seg, &ivs.list[seg.interval as usize]);
        }
        if *more {
            let mut refused = None;
            *more = cursor.walk_in(ivs, volume, ray, query, ctx.settings, |seg, iv| {
                push(seg, iv) || {
                    refused = Some(seg);
                    false
                }
            });
            *held = refused;
        }
        end
    }
}

struct Job<'a, 'b, V> {
    volume: &'a V,
    tile: Tile,
    ctx: &'a Ctx<'a>,
    input: TileInput<'b>,
    ivs: &'a mut [RayIntervals],
    out: &'a mut Vec<[f32; 4]>,
}

/// The lanes' rays: origins, directions and pixels so far, by axis.
struct Rays {
    o: [[f32; LANES]; 3],
    d: [[f32; LANES]; 3],
    rgba: [[f32; LANES]; 4],
}

impl<V: Volume> WithLanes for Job<'_, '_, V> {
    type Output = ();

    #[inline(always)]
    fn run<L: Lanes>(self) {
        let Job {
            volume,
            tile,
            ctx,
            input,
            ivs,
            out,
        } = self;
        let settings = ctx.settings;
        let s = L::splat;
        let (zero, one) = (s(0.0), s(1.0));
        let stop = s(settings.early_termination);
        let minus_scale = s(-settings.opacity_scale);
        let (lo, span) = (settings.value_range.lo, settings.value_range.span());
        let mut lanes: [Lane; LANES] = std::array::from_fn(|_| Lane {
            r: NONE,
            cursor: Cursor::new(Range1::EMPTY, Range1::EMPTY, &input.rngs[0]),
            held: None,
            more: false,
        });
        let mut q = Queues {
            t: [0.0; LANES * QUEUE],
            len: [0.0; LANES * QUEUE],
            hint: [0.0; LANES * QUEUE],
            constant: [0.0; LANES * QUEUE],
        };
        let mut rays = Rays {
            o: [[0.0; LANES]; 3],
            d: [[0.0; LANES]; 3],
            rgba: [[0.0; LANES]; 4],
        };
        // Each lane's next segment and the end of its segments, as slots in
        // `q` (equal: the lane has none).
        let base: [f32; LANES] = std::array::from_fn(|k| (k * QUEUE) as f32);
        let (mut head, mut end) = (L::from_array(base), L::from_array(base));
        let [mut o, mut d] = [[zero; 3]; 2];
        let [mut cr, mut cg, mut cb, mut alpha] = [zero; 4];
        let mut groups = groups(tile);
        // The lanes holding a ray.
        let mut occupied = 0u32;
        loop {
            // 1. Lanes without a segment take one from their cursor, or a
            // ray from the group (a ray out of segments leaves its pixel);
            // when no lane has one, the next group of rays comes in.
            let mut live = head.lt(end).bitmask();
            if live != occupied || live == 0 {
                rays.rgba = [
                    cr.to_array(),
                    cg.to_array(),
                    cb.to_array(),
                    alpha.to_array(),
                ];
                let (mut h, mut e) = (head.to_array(), end.to_array());
                let mut refilled = false;
                for (k, lane) in lanes.iter_mut().enumerate() {
                    if live >> k & 1 != 0 || lane.r == NONE {
                        continue;
                    }
                    let r = lane.r;
                    let n = if lane.more || lane.held.is_some() {
                        let ray = (volume, &input.rays[r], &mut ivs[r]);
                        lane.refill((k, &mut q), ray, input.query, ctx)
                    } else {
                        0
                    };
                    if n == 0 {
                        out[r] = pixel(&rays, k);
                        lane.r = NONE;
                        occupied &= !(1 << k);
                    }
                    (h[k], e[k]) = (base[k], base[k] + n as f32);
                    live |= ((n > 0) as u32) << k;
                    refilled = true;
                }
                if live == 0 {
                    // The next group.
                    let Some(group) = groups.next() else {
                        return;
                    };
                    for (k, lane) in lanes.iter_mut().enumerate() {
                        let r = group[k];
                        if r == NONE {
                            continue;
                        }
                        if input.spans[r].is_empty() {
                            out[r] = [0.0, 0.0, 0.0, input.alpha0[r]];
                            continue;
                        }
                        *lane = Lane {
                            r,
                            cursor: input.spans[r].cursor(&input.rngs[r]),
                            held: None,
                            more: true,
                        };
                        occupied |= 1 << k;
                        let ray = &input.rays[r];
                        for a in 0..3 {
                            rays.o[a][k] = ray.origin[a];
                            rays.d[a][k] = ray.dir[a];
                        }
                        rays.rgba[0][k] = 0.0;
                        rays.rgba[1][k] = 0.0;
                        rays.rgba[2][k] = 0.0;
                        rays.rgba[3][k] = input.alpha0[r];
                        // An empty queue: filled at the top of the loop.
                        (h[k], e[k]) = (base[k], base[k]);
                    }
                    (head, end) = (L::from_array(h), L::from_array(e));
                    for a in 0..3 {
                        (o[a], d[a]) = (L::from_array(rays.o[a]), L::from_array(rays.d[a]));
                    }
                    [cr, cg, cb, alpha] = load4::<L>(&rays.rgba);
                    continue;
                }
                if refilled {
                    (head, end) = (L::from_array(h), L::from_array(e));
                }
                [cr, cg, cb, alpha] = load4::<L>(&rays.rgba);
            }
            // 2. Every live lane's front segment.
            let live_mask = head.lt(end);
            let t = L::gather(&q.t, head);
            let len = L::gather(&q.len, head);
            let hint_bits = L::gather(&q.hint, head);
            let constant = L::gather(&q.constant, head);
            head = head + live_mask.select(one, zero);
            let hints = hint_bits.to_array().map(f32::to_bits);
            // 3. The samples: `ray.at(t)` and the volume's values, constant
            // intervals' values as they are.
            let p = [o[0] + d[0] * t, o[1] + d[1] * t, o[2] + d[2] * t];
            let is_constant = constant.le(constant);
            let sampled = live_mask.and_not(is_constant).bitmask();
            let v = volume.sample_values_lanes::<L>(&hints, p, sampled);
            let v = is_constant.select(constant, v);
            // 4. Classification: `RenderSettings::normalize` on a linear
            // scale (NaN, no sample, passes through to an opacity that is
            // not positive), then what `Classified` does.
            let x = if span > 0.0 {
                one.min(zero.max((v - s(lo)) / s(span)))
            } else {
                v.le(v).select(zero, v)
            };
            let ([red, green, blue], op) = ctx.tf.color_and_opacity_lanes(x);
            let a = one - ((op * minus_scale) * len).exp();
            let a = op.gt(zero).select(a, s(-1.0));
            // 5. Compositing, as `crate::composite` does it.
            let add = live_mask & a.ge(zero);
            let w = (one - alpha) * a;
            cr = add.select(cr + red * w, cr);
            cg = add.select(cg + green * w, cg);
            cb = add.select(cb + blue * w, cb);
            alpha = add.select(alpha + (one - alpha) * a, alpha);
            // 6. Opaque rays are done: their lanes drop their segments and
            // leave their pixels at the top of the loop.
            let done = add & alpha.ge(stop);
            if done.any() {
                let bits = done.bitmask();
                for (k, lane) in lanes.iter_mut().enumerate() {
                    if bits >> k & 1 != 0 {
                        (lane.more, lane.held) = (false, None);
                    }
                }
                end = done.select(head, end);
            }
        }
    }
}

/// The tile's rays (row-major indices) in groups of 4×2 pixels, which
/// march together: neighbours in a compact block cross the same regions at
/// about the same steps, so a step's eight samples need few regions'
/// bricks. ([`NONE`] pads groups at the tile's edges.)
fn groups(tile: Tile) -> impl Iterator<Item = [usize; LANES]> {
    const W: u32 = 4;
    const H: u32 = LANES as u32 / W;
    (0..tile.h).step_by(H as usize).flat_map(move |gy| {
        (0..tile.w).step_by(W as usize).map(move |gx| {
            let mut g = [NONE; LANES];
            for (k, slot) in g.iter_mut().enumerate() {
                let (x, y) = (gx + k as u32 % W, gy + k as u32 / W);
                if x < tile.w && y < tile.h {
                    *slot = (y * tile.w + x) as usize;
                }
            }
            g
        })
    })
}

/// Four rows of lanes (no closure: `map` would not be inlined into the
/// SIMD backend's code).
#[inline(always)]
fn load4<L: Lanes>(v: &[[f32; LANES]; 4]) -> [L; 4] {
    [
        L::from_array(v[0]),
        L::from_array(v[1]),
        L::from_array(v[2]),
        L::from_array(v[3]),
    ]
}

/// Lane `k`'s pixel.
fn pixel(rays: &Rays, k: usize) -> [f32; 4] {
    rays.rgba.map(|c| c[k])
}
