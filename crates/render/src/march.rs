//! Emission–absorption along one ray, split into the three steps every path
//! (per-sample [`march`], the packets of module `packet`, single
//! scattering) shares, so they place and integrate samples identically:
//!
//! 1. the ray's span inside the volume (and clip box; [`RaySpans`]) and the
//!    volume's visible intervals along it, asked for a chunk at a time as
//!    the ray goes ([`RayIntervals`]; a tile view gives whole lists per
//!    tile);
//! 2. [`Cursor`](crate::cursor::Cursor): the sample segments inside those intervals, in order — the
//!    cells of a lattice of step `dt` fixed on the ray (offset by one random
//!    number per pixel sample: jitter), each sampled at its midpoint; a
//!    constant interval is one segment, whole;
//! 3. [`RayState::feed`]: one segment composited front to back, with the
//!    segment-length opacity correction and iso-surface crossings.

use voxless_core::{
    Attribute, Interval, IntervalKind, IntervalQuery, Range1, Ray, Sample, Vec3, Volume,
};
use voxless_transfer::TransferFunction;

use crate::ctx::Ctx;
use crate::cursor::{RayIntervals, Segment, min_step_at};
use crate::sampling::PixelRng;
use crate::spans::{RaySpans, region};
use crate::surface::iso_visibility;
use crate::{Light, RenderSettings};

/// Emission–absorption along one ray; returns premultiplied linear RGBA.
/// (Renders get their intervals per tile; this is the one-ray entry.)
/// `scratch` holds the ray's intervals (as many as were asked for).
pub fn march<V: Volume>(
    volume: &V,
    ray: &Ray,
    tf: &TransferFunction,
    settings: &RenderSettings,
    rng: &PixelRng,
    scratch: &mut Vec<Interval>,
) -> [f32; 4] {
    scratch.clear();
    let spans = RaySpans::new(&region(volume, settings), settings, ray, f32::INFINITY);
    if spans.is_empty() {
        return [0.0; 4];
    }
    let visible = |r: Range1| settings.is_visible(tf, r);
    let query = IntervalQuery {
        is_visible: &visible,
    };
    let mut ivs = RayIntervals::with_buffer(std::mem::take(scratch));
    ivs.start(spans.span);
    let ctx = Ctx::new(tf, settings, volume.classified());
    let rgba = march_intervals(
        volume,
        ray,
        &mut ivs,
        &query,
        &spans,
        0.0,
        rng,
        &ctx,
        &mut RayStats::default(),
    );
    *scratch = ivs.list;
    rgba
}

/// Emission–absorption along `ray` over its intervals `ivs` (within
/// `spans.span`; asked of the volume as the ray goes unless complete),
/// starting from opacity `alpha0` (0 for a whole ray; a render of one box
/// of a decomposition continues what the boxes in front of it composited);
/// what the ray saw is added to `stats`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn march_intervals<V: Volume>(
    volume: &V,
    ray: &Ray,
    ivs: &mut RayIntervals,
    query: &IntervalQuery,
    spans: &RaySpans,
    alpha0: f32,
    rng: &PixelRng,
    ctx: &Ctx,
    stats: &mut RayStats,
) -> [f32; 4] {
    let gradient = ctx.needs_gradient();
    let mut state = RayState::new(spans.cells, alpha0, *rng);
    // The first chunk: every interval for volumes that hand them out at
    // once, which the fast path below needs.
    ivs.fetch(volume, ray, query);
    // Only constant pieces and no iso-surfaces (a tessellation's usual
    // ray): each piece (the part owned) composited whole, without cursor or
    // iso bookkeeping — the same arithmetic as `feed`, in a tight loop.
    if ctx.settings.iso.is_empty()
        && ivs.is_complete()
        && ivs.list.iter().all(|iv| iv.kind == IntervalKind::Constant)
    {
        if ctx.settings.volume {
            let own = spans.own;
            for iv in &ivs.list {
                let len = iv.t.hi.min(own.hi) - iv.t.lo.max(own.lo);
                if len > 0.0
                    && state.composite(&Sample::scalar(iv.value_range.lo), len, Vec3::ZERO, ctx)
                {
                    break;
                }
            }
        }
        return state.rgba();
    }
    let mut cursor = spans.cursor(rng);
    let opaque = cursor.walk_in(ivs, volume, ray, query, ctx.settings, |seg, iv| {
        let p = ray.at(seg.t);
        let (sample, g) = if let Some(v) = iv.constant_value() {
            (Some(Sample::scalar(v)), Vec3::ZERO)
        } else if gradient {
            match volume.sample_with_gradient_in(p, iv) {
                Some((s, g)) => (Some(s), g),
                None => (None, Vec3::ZERO),
            }
        } else {
            (volume.sample_in(p, iv), Vec3::ZERO)
        };
        !state.feed(volume, ray, iv, seg, sample, g, ctx)
    });
    if opaque {
        // The intervals behind were never asked for.
        stats.merge(&state.stats);
        return state.rgba();
    }
    state.finish(volume, ray, ctx);
    stats.merge(&state.stats);
    state.rgba()
}

/// What the rays of a render saw, for the caller to check: how many
/// iso-surface hits, and the range of the values sampled (tracked only when
/// iso-surfaces are asked for).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayStats {
    pub iso_hits: u64,
    pub values: Range1,
}

impl Default for RayStats {
    fn default() -> Self {
        RayStats {
            iso_hits: 0,
            values: Range1::EMPTY,
        }
    }
}

impl RayStats {
    pub fn merge(&mut self, o: &RayStats) {
        self.iso_hits += o.iso_hits;
        self.values = self.values.union(o.values);
    }
}

/// The compositing state of one ray.
pub(crate) struct RayState {
    acc: Accumulator,
    pub stats: RayStats,
    /// The previous sample (t, value), for iso-surface crossings.
    prev: Option<(f32, f32)>,
    /// The pieces of a gap that hold an iso-value (scratch).
    gap_pieces: Vec<Interval>,
    /// Whether a sampled interval has been sampled yet.
    sampled: bool,
    /// The last sampled segment's length (the gap lattice's step at the
    /// ray's end).
    last_step: f32,
    /// The last interval when it was constant: (end, value). A gap after it
    /// is a crossing to zero.
    last_constant: Option<(f32, f32)>,
    /// The ray's span: a constant interval ending before its end is
    /// followed by (zero) space.
    span: Range1,
    /// The end of the last constant interval (or the span's start).
    last_end: f32,
    /// The pixel sample's random stream (ambient-occlusion rays).
    rng: PixelRng,
}

/// Constant pieces and gaps this many ulps of `t` long or shorter are
/// rounding, not structure, for iso-surfaces.
const ROUNDING: f32 = 4.0;

impl RayState {
    /// The state at the start of a ray whose samples are cut to `span`,
    /// with opacity `alpha0` already in front of it (and no colour).
    pub fn new(span: Range1, alpha0: f32, rng: PixelRng) -> Self {
        RayState {
            rng,
            acc: Accumulator {
                color: Vec3::ZERO,
                alpha: alpha0,
            },
            stats: RayStats::default(),
            prev: None,
            gap_pieces: Vec::new(),
            sampled: false,
            last_step: 0.0,
            last_constant: None,
            span,
            last_end: span.lo,
        }
    }

    /// Composites the sample of `seg` (in interval `iv`); returns true once
    /// the ray is opaque enough to stop.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub fn feed<V: Volume>(
        &mut self,
        volume: &V,
        ray: &Ray,
        iv: &Interval,
        seg: Segment,
        sample: Option<Sample>,
        gradient: Vec3,
        ctx: &Ctx,
    ) -> bool {
        let settings = ctx.settings;
        if let Some(v) = iv.constant_value() {
            if !settings.iso.is_empty() {
                self.stats.values.extend(v);
                if self.constant_crossings(volume, ray, iv, v, ctx) {
                    return true;
                }
            }
            if !settings.volume {
                return false;
            }
            let s = Sample::scalar(v);
            return self.composite(&s, seg.len, gradient, ctx);
        }
        if settings.iso.is_empty() {
            // No iso-surfaces: the bookkeeping below only serves them.
            return match sample {
                Some(s) if settings.volume => self.composite(&s, seg.len, gradient, ctx),
                _ => false,
            };
        }
        let tm = seg.t;
        if seg.reset {
            // A gap: leaving a constant interval into it is a step to zero.
            if let Some((t_end, v0)) = self.last_constant.take()
                && self.step_crossings(volume, ray, t_end, v0, 0.0, ctx)
            {
                return true;
            }
            // Between the previous sample and this one the cursor skipped
            // space: invisible pieces hold no crossing, but a visible piece
            // shorter than a step may have got no sample (a pinhole).
            // Before the ray's first sample, the gap starts where the ray
            // enters the volume.
            let prev = match self.prev.take() {
                None if !self.sampled => Some((self.span.lo, f32::NAN)),
                prev => prev,
            };
            if let Some(prev) = prev
                && self.gap_crossings(volume, ray, prev, (tm, seg.len), sample, ctx)
            {
                return true;
            }
        }
        self.last_constant = None;
        self.last_end = iv.t.hi;
        self.sampled = true;
        self.last_step = seg.len;
        let Some(s) = sample else {
            self.prev = None;
            return false;
        };
        if !settings.iso.is_empty() {
            self.stats.values.extend(s.value);
        }
        // Implicit iso-surfaces: a sign change of value − iso between the
        // previous sample and this one is a hit, placed by linear interpolation.
        if let Some(prev) = self.prev {
            let here = Some((iv, (s, gradient)));
            if self.crossings(volume, ray, here, prev, (tm, s.value), ctx) {
                return true;
            }
        }
        self.prev = Some((tm, s.value));
        if !settings.volume {
            return false;
        }
        self.composite(&s, seg.len, gradient, ctx)
    }

    /// Iso-surfaces at the start of constant interval `iv` (value `v`): a
    /// step from the previous piece when it touches `iv`, else (a gap, which
    /// is zero next to constant pieces) a step down from the last piece and
    /// a step up from zero — but not where the ray's span starts, which cuts
    /// the volume open. Pieces and gaps within [`ROUNDING`] ulps of `t` are
    /// rounding (neighbouring pieces' ends computed from different planes),
    /// not structure, and are passed over.
    fn constant_crossings<V: Volume>(
        &mut self,
        volume: &V,
        ray: &Ray,
        iv: &Interval,
        v: f32,
        ctx: &Ctx,
    ) -> bool {
        let tiny = |t: f32| ROUNDING * f32::EPSILON * t.abs();
        if iv.t.span() <= tiny(iv.t.hi) {
            return false;
        }
        let touching = iv.t.lo - self.last_end <= tiny(iv.t.lo);
        self.last_end = iv.t.hi;
        let before = if touching {
            self.prev.map(|p| p.1)
        } else {
            if let Some((t_end, v0)) = self.last_constant
                && self.step_crossings(volume, ray, t_end, v0, 0.0, ctx)
            {
                return true;
            }
            Some(0.0)
        };
        self.prev = Some((iv.t.hi, v));
        self.last_constant = Some((iv.t.hi, v));
        match before {
            Some(v0) => self.step_crossings(volume, ray, iv.t.lo, v0, v, ctx),
            None => false,
        }
    }

    /// A segment of length `len` of sample `s`, opacity-corrected for its
    /// length (exact when the field is constant over it).
    #[inline(always)]
    fn composite(&mut self, s: &Sample, len: f32, gradient: Vec3, ctx: &Ctx) -> bool {
        let settings = ctx.settings;
        let x = settings.normalize(s.value);
        // A plain scalar sample takes colour and opacity from one LUT
        // position.
        let (opacity, colour) = match (ctx.classified, s.attribute) {
            (false, Attribute::None) => {
                let (c, o) = ctx.tf.color_and_opacity(x);
                (o, Some(c))
            }
            _ => (ctx.opacity_of(s, x), None),
        };
        if opacity > 0.0 {
            // The lanes' `exp` (same bits): packet passes classify their
            // samples in lanes (module `classify`).
            let a = 1.0 - voxless_core::simd::exp(-opacity * settings.opacity_scale * len);
            let c = colour.unwrap_or_else(|| ctx.colour_of(s, x));
            return self.add_shaded(c, a, gradient, ctx);
        }
        false
    }

    /// Colour `c` (shaded by the volume's light, if any) with opacity `a`
    /// behind what the ray holds; true once it is opaque enough to stop.
    #[inline(always)]
    fn add_shaded(&mut self, c: Vec3, a: f32, gradient: Vec3, ctx: &Ctx) -> bool {
        let settings = ctx.settings;
        let c = match settings.light {
            Some(light) => c * shade(gradient, light),
            None => c,
        };
        self.acc.add(c, a, settings.early_termination)
    }

    /// A plain sample's segment (a scalar value, no attribute, not
    /// pre-classified; no iso-surfaces) whose colour `c` and opacity `a`
    /// were computed in lanes (module `classify`; `a < 0`: the transfer
    /// function's opacity is not positive): what [`RayState::feed`] does
    /// with it, the same bits.
    #[inline(always)]
    pub fn feed_classified(&mut self, c: Vec3, a: f32, gradient: Vec3, ctx: &Ctx) -> bool {
        a >= 0.0 && self.add_shaded(c, a, gradient, ctx)
    }

    /// Iso-surfaces crossed in a gap the cursor skipped between the sample
    /// `(t0, v0)` (`v0` NaN: none, the ray's entry) and the next one at
    /// `t1` (`next`, its segment `step` long). The field is continuous and
    /// never equals an iso-value outside the volume's pieces whose range
    /// holds one, so every crossing lies in such a piece; a visible piece
    /// in a gap is shorter than a step, or it would hold a sample. Each
    /// such stretch (touching pieces merged) is sampled at its ends and at
    /// the points of the step's lattice anchored at `t1` inside it (where a
    /// stretch spans one): the points depend on the ray, the step
    /// and the stretch alone, not on how a volume cuts its pieces or which
    /// other pieces it reports (a prepared volume answers for its own
    /// transfer function), so every path finds the same crossings.
    fn gap_crossings<V: Volume>(
        &mut self,
        volume: &V,
        ray: &Ray,
        (t0, v0): (f32, f32),
        (t1, step): (f32, f32),
        next: Option<Sample>,
        ctx: &Ctx,
    ) -> bool {
        let isos = &ctx.settings.iso;
        let holds_iso = |r: Range1| isos.iter().any(|&v| r.contains(v));
        let query = IntervalQuery {
            is_visible: &holds_iso,
        };
        let mut pieces = std::mem::take(&mut self.gap_pieces);
        pieces.clear();
        volume.intervals(ray, Range1::new(t0, t1), &query, &mut pieces);
        // Only pieces whose range holds an iso-value, clipped to the gap;
        // touching ones are one stretch (merged in place: `t` only).
        let mut kept = 0;
        for i in 0..pieces.len() {
            let p = pieces[i];
            let (a, b) = (p.t.lo.max(t0), p.t.hi.min(t1));
            if !holds_iso(p.value_range) || b < a {
                continue;
            }
            if kept > 0 && pieces[kept - 1].t.hi >= a {
                pieces[kept - 1].t.hi = pieces[kept - 1].t.hi.max(b);
            } else {
                pieces[kept].t = Range1::new(a, b);
                kept += 1;
            }
        }
        pieces.truncate(kept);
        let d = step;
        if !(d > 0.0) {
            self.gap_pieces = pieces;
            return false;
        }
        // A point on the volume's boundary may lie just outside its
        // half-open cells: then the field a step inside stands for it.
        let value_at = |t: f32, inward: f32| -> Option<f32> {
            if t == t1
                && let Some(s) = next
            {
                return Some(s.value);
            }
            if t == t0 && !v0.is_nan() {
                return Some(v0);
            }
            volume
                .sample(ray.at(t))
                .or_else(|| volume.sample(ray.at(t + inward * min_step_at(t))))
                .map(|s| s.value)
        };
        let mut stop = false;
        'stretches: for &Interval {
            t: Range1 { lo: a, hi: b },
            ..
        } in &pieces
        {
            let mut last = value_at(a, 1.0).map(|v| (a, v));
            // Lattice points t1 − k·d strictly inside (a, b), front to back.
            let k_hi = ((t1 - a) / d).ceil() as i64;
            let k_lo = ((t1 - b) / d).floor().max(0.0) as i64;
            let inside = (k_lo..=k_hi)
                .rev()
                .map(|k| t1 - k as f32 * d)
                .filter(|&t| a < t && t < b);
            for (t, inward) in inside.map(|t| (t, 1.0)).chain([(b, -1.0)]) {
                let v = value_at(t, inward).map(|v| (t, v));
                if let (Some(p), Some(q)) = (last, v)
                    && self.crossings(volume, ray, None, p, q, ctx)
                {
                    stop = true;
                    break 'stretches;
                }
                last = v;
            }
        }
        self.gap_pieces = pieces;
        stop
    }

    /// Iso-surfaces crossed between samples `(t0, v0)` and `(t1, v1)`: a
    /// sign change of value − iso is a hit, placed by linear interpolation
    /// and shaded with the field's sample and gradient there. `here` is the
    /// interval holding `t1` with the sample and gradient taken at `t1`
    /// (the hint and the fallback), when there is one.
    fn crossings<V: Volume>(
        &mut self,
        volume: &V,
        ray: &Ray,
        here: Option<(&Interval, (Sample, Vec3))>,
        (t0, v0): (f32, f32),
        (t1, v1): (f32, f32),
        ctx: &Ctx,
    ) -> bool {
        let settings = ctx.settings;
        for &iso in &settings.iso {
            if (v0 - iso) * (v1 - iso) < 0.0 || (v1 == iso && v0 != iso) {
                let th = t0 + (iso - v0) / (v1 - v0) * (t1 - t0);
                let ph = ray.at(th);
                // The hit may lie in the previous interval: only use this
                // interval's hint when it contains the hit.
                let hit = match here {
                    Some((iv, _)) if iv.t.contains(th) => volume.sample_with_gradient_in(ph, iv),
                    _ => volume.sample_with_gradient(ph),
                };
                let Some((hs, g)) = hit.or(here.map(|h| h.1)) else {
                    continue;
                };
                self.stats.iso_hits += 1;
                let seen = iso_visibility(
                    volume,
                    ph,
                    g,
                    ray,
                    ctx,
                    &self.rng,
                    self.stats.iso_hits as u32,
                );
                let c =
                    ctx.colour_of(&hs, settings.normalize(iso)) * (iso_shade(ray, g, ctx) * seen);
                if self
                    .acc
                    .add(c, settings.iso_opacity, settings.early_termination)
                {
                    return true;
                }
            }
        }
        false
    }

    /// Iso-surfaces where a piecewise-constant field steps from `v0` to `v1`
    /// at `t`: shaded with the volume's gradient there.
    fn step_crossings<V: Volume>(
        &mut self,
        volume: &V,
        ray: &Ray,
        t: f32,
        v0: f32,
        v1: f32,
        ctx: &Ctx,
    ) -> bool {
        let settings = ctx.settings;
        for &iso in &settings.iso {
            if (v0 - iso) * (v1 - iso) < 0.0 || (v1 == iso && v0 != iso) {
                let g = volume.gradient(ray.at(t));
                self.stats.iso_hits += 1;
                let seen = iso_visibility(
                    volume,
                    ray.at(t),
                    g,
                    ray,
                    ctx,
                    &self.rng,
                    self.stats.iso_hits as u32,
                );
                let c = ctx.colour_of(&Sample::scalar(iso), settings.normalize(iso))
                    * (iso_shade(ray, g, ctx) * seen);
                if self
                    .acc
                    .add(c, settings.iso_opacity, settings.early_termination)
                {
                    return true;
                }
            }
        }
        false
    }

    /// The end of the ray's intervals: a constant interval that ends inside
    /// the span steps down to zero there.
    pub fn finish<V: Volume>(&mut self, volume: &V, ray: &Ray, ctx: &Ctx) {
        if let Some((t_end, v0)) = self.last_constant.take()
            && self.span.hi - t_end > ROUNDING * f32::EPSILON * t_end.abs()
        {
            self.step_crossings(volume, ray, t_end, v0, 0.0, ctx);
        }
        // After the last sample the ray's last visible piece may go on for
        // up to a step, and more pieces may follow that got no sample: a
        // gap up to the span's end.
        if let Some(prev) = self.prev.take()
            && self.last_step > 0.0
            && self.span.hi > prev.0
        {
            self.gap_crossings(volume, ray, prev, (self.span.hi, self.last_step), None, ctx);
        }
    }

    pub fn rgba(&self) -> [f32; 4] {
        self.acc.rgba()
    }

    /// The pixel so far, for compositing plain samples in lanes
    /// (module `composite`, the arithmetic of
    /// [`RayState::feed_classified`] without a light).
    pub fn pixel(&mut self) -> &mut Accumulator {
        &mut self.acc
    }
}

/// The shading of an iso-surface hit: the volume's light, else a headlight.
#[inline]
fn iso_shade(ray: &Ray, gradient: Vec3, ctx: &Ctx) -> f32 {
    let light = ctx.settings.light.unwrap_or(Light {
        direction: -ray.dir,
        ambient: 0.2,
    });
    shade(gradient, light)
}

/// Front-to-back compositing of premultiplied colour.
#[derive(Default)]
pub(crate) struct Accumulator {
    pub color: Vec3,
    pub alpha: f32,
}

impl Accumulator {
    /// Adds colour `c` with opacity `a` behind what is there; returns true
    /// once the pixel is opaque enough to stop.
    #[inline]
    fn add(&mut self, c: Vec3, a: f32, early_termination: f32) -> bool {
        self.color += c * ((1.0 - self.alpha) * a);
        self.alpha += (1.0 - self.alpha) * a;
        self.alpha >= early_termination
    }
    fn rgba(&self) -> [f32; 4] {
        [self.color.x, self.color.y, self.color.z, self.alpha]
    }
}

/// Two-sided diffuse term: the gradient's sign depends on which side of a
/// feature we are, so both sides face the light equally.
pub(crate) fn shade(gradient: Vec3, light: Light) -> f32 {
    let n = gradient.normalized();
    if n.length_squared() == 0.0 {
        return 1.0;
    }
    light.ambient + (1.0 - light.ambient) * n.dot(light.direction).abs()
}
