//! Emission–absorption along one ray, split into the three steps both the
//! per-sample path ([`march`]) and the packet path ([`crate::packet`]) share,
//! so the two place and integrate samples identically:
//!
//! 1. [`ray_intervals`]: the ray clipped to the volume (and clip box), and the
//!    volume's visible intervals along it;
//! 2. [`Cursor`]: the sample segments inside those intervals, in order — per
//!    interval a random first boundary (jitter), then steps of `dt`; each
//!    segment is sampled at its midpoint;
//! 3. [`RayState::feed`]: one sample composited front to back, with the
//!    segment-length opacity correction and iso-surface crossings.

use voxless_core::{Aabb, Attribute, Interval, IntervalQuery, Range1, Ray, Sample, Vec3, Volume};
use voxless_transfer::TransferFunction;

use crate::sampling::PixelRng;
use crate::{Light, RenderSettings};

/// Emission–absorption along one ray; returns premultiplied linear RGBA.
pub fn march<V: Volume>(
    volume: &V,
    ray: &Ray,
    tf: &TransferFunction,
    settings: &RenderSettings,
    rng: &PixelRng,
    scratch: &mut Vec<Interval>,
) -> [f32; 4] {
    scratch.clear();
    if !ray_intervals(volume, ray, tf, settings, f32::INFINITY, scratch) {
        return [0.0; 4];
    }
    let ctx = Ctx::new(tf, settings);
    let gradient = ctx.needs_gradient();
    let mut state = RayState::default();
    let mut cursor = Cursor::default();
    while let Some(seg) = cursor.next(scratch, settings, rng) {
        let iv = &scratch[seg.interval as usize];
        let p = ray.at(seg.t);
        let (sample, g) = if gradient {
            match volume.sample_with_gradient_in(p, iv) {
                Some((s, g)) => (Some(s), g),
                None => (None, Vec3::ZERO),
            }
        } else {
            (volume.sample_in(p, iv), Vec3::ZERO)
        };
        if state.feed(volume, ray, iv, seg, sample, g, &ctx) {
            break;
        }
    }
    state.rgba()
}

/// Appends the visible intervals of `ray` within `t ∈ [0, t_max]` to `out`;
/// false when the ray misses the (clipped) volume there.
pub(crate) fn ray_intervals<V: Volume>(
    volume: &V,
    ray: &Ray,
    tf: &TransferFunction,
    settings: &RenderSettings,
    t_max: f32,
    out: &mut Vec<Interval>,
) -> bool {
    let mut region = volume.bounds();
    if let Some(clip) = settings.clip {
        region = Aabb::new(region.min.max(clip.min), region.max.min(clip.max));
    }
    let t = region.clip_ray(ray, Range1::new(0.0, t_max));
    if t.is_empty() {
        return false;
    }
    let visible = |r: Range1| settings.is_visible(tf, r);
    volume.intervals(
        ray,
        t,
        &IntervalQuery {
            is_visible: &visible,
        },
        out,
    );
    true
}

/// One sample: the midpoint `t` of a segment of length `len` in interval
/// `interval` of the ray's list; `reset` when the segment follows a gap (the
/// previous sample no longer brackets iso-surface crossings).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Segment {
    pub t: f32,
    pub len: f32,
    pub interval: u32,
    pub reset: bool,
}

/// Walks the segments of a ray's intervals in order; resumable, so the
/// packet path can take them a window at a time.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Cursor {
    k: usize,
    start: f32,
    end: f32,
    dt: f32,
    prev_end: f32,
    reset: bool,
    open: bool,
}

impl Default for Cursor {
    fn default() -> Self {
        Cursor {
            k: 0,
            start: 0.0,
            end: 0.0,
            dt: 0.0,
            prev_end: f32::NAN,
            reset: false,
            open: false,
        }
    }
}

impl Cursor {
    /// The step of the current interval (valid after the first `next`).
    pub fn dt(&self) -> f32 {
        self.dt
    }

    pub fn next(
        &mut self,
        intervals: &[Interval],
        settings: &RenderSettings,
        rng: &PixelRng,
    ) -> Option<Segment> {
        loop {
            let iv = intervals.get(self.k)?;
            if !self.open {
                // A gap before this interval breaks iso-surface bracketing.
                if iv.t.lo != self.prev_end {
                    self.reset = true;
                }
                self.prev_end = iv.t.hi;
                self.dt = settings
                    .step
                    .unwrap_or(iv.nominal_dt / settings.sampling_rate)
                    .max(iv.t.span() * 1e-6)
                    .max(f32::MIN_POSITIVE);
                // Segment boundaries start at a random offset inside the first step.
                let xi = rng.uniform(2 + self.k as u32);
                self.start = iv.t.lo;
                self.end = iv.t.lo + xi * self.dt;
                self.open = true;
            }
            while self.start < iv.t.hi {
                let end = self.end.min(iv.t.hi);
                let len = end - self.start;
                self.start = end;
                self.end = end + self.dt;
                if len <= 0.0 {
                    continue;
                }
                return Some(Segment {
                    t: end - 0.5 * len,
                    len,
                    interval: self.k as u32,
                    reset: std::mem::take(&mut self.reset),
                });
            }
            self.open = false;
            self.k += 1;
        }
    }
}

/// What every sample of a frame needs besides the sample itself.
pub(crate) struct Ctx<'a> {
    pub tf: &'a TransferFunction,
    pub settings: &'a RenderSettings,
    attr_range: Range1,
}

impl<'a> Ctx<'a> {
    pub fn new(tf: &'a TransferFunction, settings: &'a RenderSettings) -> Self {
        Ctx {
            tf,
            settings,
            attr_range: settings.attribute_range.unwrap_or(Range1::new(0.0, 1.0)),
        }
    }

    /// Whether samples need the gradient (shading the volume).
    pub fn needs_gradient(&self) -> bool {
        self.settings.light.is_some() && self.settings.volume
    }

    /// The colour of a sample whose normalised value is `x`.
    #[inline]
    pub fn colour_of(&self, s: &Sample, x: f32) -> Vec3 {
        match s.attribute {
            Attribute::Scalar(v) => self.tf.color(self.attr_range.normalize(v)),
            Attribute::Rgb(c) => c,
            Attribute::None => self.tf.color(x),
        }
    }
}

/// The compositing state of one ray.
#[derive(Default)]
pub(crate) struct RayState {
    acc: Accumulator,
    /// The previous sample (t, value), for iso-surface crossings.
    prev: Option<(f32, f32)>,
}

impl RayState {
    /// Composites the sample of `seg` (in interval `iv`); returns true once
    /// the ray is opaque enough to stop.
    #[allow(clippy::too_many_arguments)]
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
        if seg.reset {
            self.prev = None;
        }
        let Some(s) = sample else {
            self.prev = None;
            return false;
        };
        let tm = seg.t;
        // Implicit iso-surfaces: a sign change of value − iso between the
        // previous sample and this one is a hit, placed by linear interpolation.
        if let Some((t0, v0)) = self.prev {
            for &iso in &settings.iso {
                if (v0 - iso) * (s.value - iso) < 0.0 || (s.value == iso && v0 != iso) {
                    let th = t0 + (iso - v0) / (s.value - v0) * (tm - t0);
                    let ph = ray.at(th);
                    // The hit may lie in the previous interval: only use
                    // this interval's hint when it contains the hit.
                    let hit = if iv.t.contains(th) {
                        volume.sample_with_gradient_in(ph, iv)
                    } else {
                        volume.sample_with_gradient(ph)
                    };
                    let (hs, g) = hit.unwrap_or((s, gradient));
                    let light = settings.light.unwrap_or(Light {
                        direction: -ray.dir,
                        ambient: 0.2,
                    });
                    let c = ctx.colour_of(&hs, settings.normalize(iso)) * shade(g, light);
                    if self
                        .acc
                        .add(c, settings.iso_opacity, settings.early_termination)
                    {
                        return true;
                    }
                }
            }
        }
        self.prev = Some((tm, s.value));
        if !settings.volume {
            return false;
        }
        let x = settings.normalize(s.value);
        let opacity = if volume.classified() {
            s.value
        } else {
            ctx.tf.opacity(x)
        };
        if opacity > 0.0 {
            let a = 1.0 - (-opacity * settings.opacity_scale * seg.len).exp();
            let mut c = ctx.colour_of(&s, x);
            if let Some(light) = settings.light {
                c = c * shade(gradient, light);
            }
            return self.acc.add(c, a, settings.early_termination);
        }
        false
    }

    pub fn rgba(&self) -> [f32; 4] {
        self.acc.rgba()
    }
}

/// Front-to-back compositing of premultiplied colour.
#[derive(Default)]
struct Accumulator {
    color: Vec3,
    alpha: f32,
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
