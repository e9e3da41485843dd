//! Single scattering with volumetric shadows (attribute-aware RBF paper
//! §3.3), one stochastic path per pixel sample.
//!
//! The transfer function's colour becomes the *albedo* and its opacity the
//! extinction `σ = opacity · opacity_scale`. Per sample, a free-flight
//! distance along the camera ray picks one scattering point `x` with
//! probability density `σ(t)·T(t)`; if the ray leaves the volume first the
//! pixel is transparent. At `x` one shadow ray towards the light asks whether
//! the light is reached (a second free flight: lit iff no event before the
//! light). The sample's colour is `albedo(x) · (ambient + (1 − ambient) ·
//! intensity · lit)` with alpha 1. Averaged over samples this converges to
//! the emission–absorption integral whose emission is the albedo times the
//! light's transmittance — the reference the tests converge to.
//!
//! Free-flight distances, two ways:
//! - **stochastic ray marching** (paper §3.3.3): walk the ray's jittered
//!   segments accumulating the Riemann sum of `σ·len` until it exceeds
//!   `−ln(1 − ξ)`; one random number per distance (so blue noise can drive
//!   it), biased only by the step like the ray marcher itself;
//! - **delta tracking**: with a majorant `σ̄` per interval from its value
//!   range (`max opacity over the range · opacity_scale`), tentative
//!   collisions at exponential steps are accepted with probability `σ/σ̄`;
//!   unbiased, several random numbers per distance.
//!
//! `ξ` for both the primary and the shadow distance comes from
//! spatiotemporal blue noise ([`crate::bluenoise`]) or white noise.
//!
//! The camera ray's samples lie on the same jittered lattice as the
//! emission–absorption marcher's, and its intervals are asked for as the
//! flight goes, so nothing behind the event is looked at. With packets
//! (module `scatter_packet`) marching flights — camera and shadow rays —
//! take their samples a packet at a time; this module's per-ray path is
//! the reference it is tested against (and delta tracking's path).

use voxless_core::{Interval, IntervalQuery, Range1, Ray, Sample, Vec3, Volume};

use crate::ctx::Ctx;
use crate::cursor::{Cursor, RayIntervals, Segment};
use crate::meshes::blocked;
use crate::sampling::PixelRng;
use crate::spans::{RaySpans, region};
use crate::{RenderSettings, bluenoise};

/// Where the light comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightSource {
    /// A light at infinity in this direction (unit vector towards the light).
    Directional(Vec3),
    /// A point light at this position.
    Point(Vec3),
}

/// How free-flight distances are sampled.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FreeFlight {
    #[default]
    Marching,
    DeltaTracking,
}

/// Where the uniform numbers of the free flights come from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Noise {
    #[default]
    Blue,
    White,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scatter {
    pub light: LightSource,
    /// Light intensity (1 = the albedo's full colour where lit).
    pub intensity: f32,
    /// Fraction of the albedo kept in full shadow.
    pub ambient: f32,
    pub method: FreeFlight,
    pub noise: Noise,
}

/// Random-number dimensions: the pixel jitter uses 0 and 1 and the sample
/// lattice 2, so delta tracking draws from far above them, and the shadow
/// ray from its own stream.
const DELTA_DIMS: u32 = 1 << 20;
const SHADOW_SALT: u64 = 0x5ad0_5ad0_5ad0_5ad0;

/// The uniform numbers of one pixel sample's path.
pub(crate) struct Noises {
    /// The camera ray's free-flight distance.
    pub primary: f32,
    /// The shadow ray's.
    pub shadow: f32,
    /// The camera ray's stream (its lattice offset, delta tracking).
    pub rng: PixelRng,
    /// The shadow ray's stream.
    pub srng: PixelRng,
}

impl Noises {
    pub fn new(settings: &RenderSettings, sc: &Scatter, (x, y): (u32, u32), sample: u32) -> Self {
        let pixel = y as u64 * settings.width as u64 + x as u64;
        let rng = PixelRng::new(settings.seed, pixel, sample);
        let index = settings.frame as u64 * settings.spp.max(1) as u64 + sample as u64;
        let xi = |dim: u32| match sc.noise {
            Noise::Blue => bluenoise::value(x, y, index, dim),
            Noise::White => rng.uniform(DELTA_DIMS - 1 - dim),
        };
        Noises {
            primary: xi(0),
            shadow: xi(1),
            rng,
            srng: PixelRng::new(settings.seed ^ SHADOW_SALT, pixel, sample),
        }
    }
}

/// The whole line: the shadow ray's samples are all its own.
const ALL: Range1 = Range1 {
    lo: f32::NEG_INFINITY,
    hi: f32::INFINITY,
};

/// One sample of pixel `(x, y)` along camera ray `ray` (its spans
/// `spans`, its intervals `ivs` started on them and asked for as the free
/// flight goes): premultiplied linear RGBA. `scratch` holds the shadow
/// ray's intervals.
#[allow(clippy::too_many_arguments)]
pub(crate) fn path<V: Volume>(
    volume: &V,
    ray: &Ray,
    ivs: &mut RayIntervals,
    query: &IntervalQuery,
    spans: &RaySpans,
    ctx: &Ctx,
    sc: &Scatter,
    pixel: (u32, u32),
    sample: u32,
    scratch: &mut Vec<Interval>,
) -> [f32; 4] {
    if spans.is_empty() {
        return [0.0; 4];
    }
    let n = Noises::new(ctx.settings, sc, pixel, sample);
    let event = match sc.method {
        FreeFlight::Marching => marching(
            volume,
            ray,
            ivs,
            query,
            spans.cursor(&n.rng),
            ctx,
            n.primary,
        ),
        FreeFlight::DeltaTracking => {
            ivs.fetch_all(volume, ray, query);
            delta_tracking(volume, ray, &ivs.list, ctx, &n.rng, n.primary)
        }
    };
    let Some((t, s)) = event else {
        return [0.0; 4];
    };
    let (_, lit) = light_with(volume, ray.at(t), ctx, sc, &n, scratch);
    scattered(ctx, sc, &s, lit)
}

/// The colour of a scattering event with sample `s` that the light reaches
/// by the fraction `lit`.
#[inline]
pub(crate) fn scattered(ctx: &Ctx, sc: &Scatter, s: &Sample, lit: f32) -> [f32; 4] {
    let albedo = ctx.colour_of(s, ctx.settings.normalize(s.value));
    let light = sc.ambient + (1.0 - sc.ambient) * sc.intensity * lit;
    let c = albedo * light;
    [c.x, c.y, c.z, 1.0]
}

/// What the light does at a point before the volume is asked.
pub(crate) enum Shadow {
    /// Settled without the volume: 0 behind a mesh, 1 when the shadow ray
    /// misses the volume.
    Known(f32),
    /// The shadow ray and its part inside the volume: its free flight
    /// decides.
    Trace(Ray, Range1),
}

/// The direction towards the light from `p`, and what is known of the
/// shadow ray there.
pub(crate) fn shadow_ray<V: Volume>(
    volume: &V,
    p: Vec3,
    ctx: &Ctx,
    sc: &Scatter,
) -> (Vec3, Shadow) {
    let settings = ctx.settings;
    let (dir, t_max) = match sc.light {
        LightSource::Directional(d) => (d.normalized(), f32::INFINITY),
        LightSource::Point(q) => ((q - p).normalized(), (q - p).length()),
    };
    let shadow = Ray::new(p, dir);
    if blocked(settings, &shadow, Range1::new(0.0, t_max)) {
        return (dir, Shadow::Known(0.0));
    }
    let span = region(volume, settings).clip_ray(&shadow, Range1::new(0.0, t_max));
    if span.is_empty() {
        return (dir, Shadow::Known(1.0));
    }
    (dir, Shadow::Trace(shadow, span))
}

/// The cursor of a shadow ray whose part inside the volume is `span`.
pub(crate) fn shadow_cursor(span: Range1, n: &Noises) -> Cursor {
    Cursor::new(span, ALL, &n.srng)
}

/// The direction towards the light from `p`, and whether the light reaches
/// `p` (1) or a mesh or a scattering event in the volume blocks it (0): one
/// shadow ray, its free flight drawn with the second noise dimension of
/// sample `sample` of `pixel`.
pub(crate) fn light_at<V: Volume>(
    volume: &V,
    p: Vec3,
    ctx: &Ctx,
    sc: &Scatter,
    pixel: (u32, u32),
    sample: u32,
    scratch: &mut Vec<Interval>,
) -> (Vec3, f32) {
    let n = Noises::new(ctx.settings, sc, pixel, sample);
    light_with(volume, p, ctx, sc, &n, scratch)
}

/// [`light_at`] with the path's noises already drawn.
fn light_with<V: Volume>(
    volume: &V,
    p: Vec3,
    ctx: &Ctx,
    sc: &Scatter,
    n: &Noises,
    scratch: &mut Vec<Interval>,
) -> (Vec3, f32) {
    let (dir, shadow) = shadow_ray(volume, p, ctx, sc);
    let (ray, span) = match shadow {
        Shadow::Known(lit) => return (dir, lit),
        Shadow::Trace(ray, span) => (ray, span),
    };
    let visible = |r: Range1| ctx.settings.is_visible(ctx.tf, r);
    let query = IntervalQuery {
        is_visible: &visible,
    };
    let mut ivs = RayIntervals::with_buffer(std::mem::take(scratch));
    ivs.start(span);
    let blocked = match sc.method {
        FreeFlight::Marching => {
            let cursor = shadow_cursor(span, n);
            marching(volume, &ray, &mut ivs, &query, cursor, ctx, n.shadow).is_some()
        }
        FreeFlight::DeltaTracking => {
            ivs.fetch_all(volume, &ray, &query);
            delta_tracking(volume, &ray, &ivs.list, ctx, &n.srng, n.shadow).is_some()
        }
    };
    *scratch = ivs.list;
    (dir, if blocked { 0.0 } else { 1.0 })
}

/// A free flight by stochastic ray marching: the Riemann sum of `σ·len`
/// over the ray's segments until it reaches the event's optical depth.
pub(crate) struct Flight {
    /// −ln(1 − ξ): the optical depth at which the event happens.
    target: f32,
    tau: f32,
}

impl Flight {
    pub fn new(xi: f32) -> Self {
        Flight {
            target: -(1.0 - xi).max(f32::MIN_POSITIVE).ln(),
            tau: 0.0,
        }
    }

    /// Adds segment `seg` with sample `s`; where the event happens, if in
    /// this segment.
    #[inline]
    pub fn feed(&mut self, ctx: &Ctx, seg: &Segment, s: &Sample) -> Option<f32> {
        let sg = sigma(ctx, s);
        let step = sg * seg.len;
        if self.tau + step >= self.target && sg > 0.0 {
            // Place the event inside the segment where the running sum
            // crosses the target (σ is constant on the segment).
            let start = seg.t - 0.5 * seg.len;
            return Some(start + (self.target - self.tau) / sg);
        }
        self.tau += step;
        None
    }
}

/// Extinction at a sample.
#[inline]
fn sigma(ctx: &Ctx, s: &Sample) -> f32 {
    ctx.opacity_of(s, ctx.settings.normalize(s.value)) * ctx.settings.opacity_scale
}

/// The sample of segment `t` in interval `iv`: the constant, or a lookup.
#[inline]
fn sample_at<V: Volume>(volume: &V, ray: &Ray, iv: &Interval, t: f32) -> Option<Sample> {
    match iv.constant_value() {
        Some(v) => Some(Sample::scalar(v)),
        None => volume.sample_in(ray.at(t), iv),
    }
}

/// The first scattering event of a marching free flight along `ray`
/// (segments from `cursor`, intervals asked for as it goes), or `None` if
/// the ray gets through. `xi` is the distance's uniform number.
fn marching<V: Volume>(
    volume: &V,
    ray: &Ray,
    ivs: &mut RayIntervals,
    query: &IntervalQuery,
    mut cursor: Cursor,
    ctx: &Ctx,
    xi: f32,
) -> Option<(f32, Sample)> {
    let mut flight = Flight::new(xi);
    let mut event = None;
    cursor.walk_in(ivs, volume, ray, query, ctx.settings, |seg, iv| {
        let Some(s) = sample_at(volume, ray, iv, seg.t) else {
            return true;
        };
        event = flight.feed(ctx, &seg, &s).map(|t| (t, s));
        event.is_none()
    });
    event
}

/// The first scattering event by delta tracking along `ray` within
/// `intervals`: with a majorant `σ̄` per interval, tentative collisions at
/// exponential steps accepted with probability `σ/σ̄` (unbiased; several
/// random numbers per distance, the first `xi`).
fn delta_tracking<V: Volume>(
    volume: &V,
    ray: &Ray,
    intervals: &[Interval],
    ctx: &Ctx,
    rng: &PixelRng,
    xi: f32,
) -> Option<(f32, Sample)> {
    let mut dim = DELTA_DIMS;
    let mut first = true;
    let mut next = || {
        if std::mem::take(&mut first) {
            xi
        } else {
            dim += 1;
            rng.uniform(dim)
        }
    };
    for iv in intervals {
        let s = ctx.settings;
        let majorant = ctx.tf.max_opacity(
            s.normalize(iv.value_range.lo),
            s.normalize(iv.value_range.hi),
        ) * s.opacity_scale;
        if majorant <= 0.0 {
            continue;
        }
        // Memoryless: each interval restarts the exponential walk.
        let mut t = iv.t.lo;
        loop {
            t += -(1.0 - next()).max(f32::MIN_POSITIVE).ln() / majorant;
            if t >= iv.t.hi {
                break;
            }
            let Some(sample) = sample_at(volume, ray, iv, t) else {
                continue;
            };
            if next() * majorant < sigma(ctx, &sample) {
                return Some((t, sample));
            }
        }
    }
    None
}
