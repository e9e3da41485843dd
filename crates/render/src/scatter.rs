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

use voxless_core::{Interval, IntervalQuery, Range1, Ray, Sample, Vec3, Volume};

use crate::bluenoise;
use crate::cursor::Cursor;
use crate::march::{Ctx, region};
use crate::sampling::PixelRng;

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

/// One sample of pixel `(x, y)` along camera ray `ray` with its visible
/// `intervals`: premultiplied linear RGBA. `scratch` holds the shadow ray's
/// intervals.
#[allow(clippy::too_many_arguments)]
pub(crate) fn path<V: Volume>(
    volume: &V,
    ray: &Ray,
    intervals: &[Interval],
    ctx: &Ctx,
    sc: &Scatter,
    (x, y): (u32, u32),
    sample: u32,
    scratch: &mut Vec<Interval>,
) -> [f32; 4] {
    let settings = ctx.settings;
    let pixel = y as u64 * settings.width as u64 + x as u64;
    let rng = PixelRng::new(settings.seed, pixel, sample);
    let index = settings.frame as u64 * settings.spp.max(1) as u64 + sample as u64;
    let xi = |dim: u32| match sc.noise {
        Noise::Blue => bluenoise::value(x, y, index, dim),
        Noise::White => rng.uniform(DELTA_DIMS - 1 - dim),
    };
    let span = intervals.first().map_or(0.0, |iv| iv.t.lo);
    let Some((t, s)) = free_flight(volume, ray, intervals, span, ctx, sc.method, &rng, xi(0))
    else {
        return [0.0; 4];
    };
    let albedo = ctx.colour_of(&s, settings.normalize(s.value));
    let (_, lit) = light_at(volume, ray.at(t), ctx, sc, (x, y), sample, scratch);
    let light = sc.ambient + (1.0 - sc.ambient) * sc.intensity * lit;
    let c = albedo * light;
    [c.x, c.y, c.z, 1.0]
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
    (x, y): (u32, u32),
    sample: u32,
    scratch: &mut Vec<Interval>,
) -> (Vec3, f32) {
    let settings = ctx.settings;
    let pixel = y as u64 * settings.width as u64 + x as u64;
    let index = settings.frame as u64 * settings.spp.max(1) as u64 + sample as u64;
    let srng = PixelRng::new(settings.seed ^ SHADOW_SALT, pixel, sample);
    let xi = match sc.noise {
        Noise::Blue => bluenoise::value(x, y, index, 1),
        Noise::White => PixelRng::new(settings.seed, pixel, sample).uniform(DELTA_DIMS - 2),
    };
    let (dir, t_max) = match sc.light {
        LightSource::Directional(d) => (d.normalized(), f32::INFINITY),
        LightSource::Point(q) => ((q - p).normalized(), (q - p).length()),
    };
    let shadow = Ray::new(p, dir);
    if crate::surface::blocked(settings, &shadow, Range1::new(0.0, t_max)) {
        return (dir, 0.0);
    }
    scratch.clear();
    let shadow_span = region(volume, settings).clip_ray(&shadow, Range1::new(0.0, t_max));
    let blocked = !shadow_span.is_empty() && {
        let visible = |r: Range1| settings.is_visible(ctx.tf, r);
        volume.intervals(
            &shadow,
            shadow_span,
            &IntervalQuery {
                is_visible: &visible,
            },
            scratch,
        );
        free_flight(
            volume,
            &shadow,
            scratch,
            shadow_span.lo,
            ctx,
            sc.method,
            &srng,
            xi,
        )
        .is_some()
    };
    (dir, if blocked { 0.0 } else { 1.0 })
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

/// The first scattering event along `ray` within `intervals` (from `t0`),
/// or `None` if the ray gets through. `xi` is the distance's uniform number.
#[allow(clippy::too_many_arguments)]
fn free_flight<V: Volume>(
    volume: &V,
    ray: &Ray,
    intervals: &[Interval],
    t0: f32,
    ctx: &Ctx,
    method: FreeFlight,
    rng: &PixelRng,
    xi: f32,
) -> Option<(f32, Sample)> {
    // −ln(1 − ξ): the optical depth at which the event happens.
    let target = -(1.0 - xi).max(f32::MIN_POSITIVE).ln();
    match method {
        FreeFlight::Marching => {
            let mut tau = 0.0f32;
            let all = Range1::new(f32::NEG_INFINITY, f32::INFINITY);
            let mut cursor = Cursor::new(Range1::new(t0, f32::INFINITY), all, rng);
            while let Some(seg) = cursor.next(intervals, ctx.settings) {
                let iv = &intervals[seg.interval as usize];
                let Some(s) = sample_at(volume, ray, iv, seg.t) else {
                    continue;
                };
                let sg = sigma(ctx, &s);
                let step = sg * seg.len;
                if tau + step >= target && sg > 0.0 {
                    // Place the event inside the segment where the running
                    // sum crosses the target (σ is constant on the segment).
                    let start = seg.t - 0.5 * seg.len;
                    return Some((start + (target - tau) / sg, s));
                }
                tau += step;
            }
            None
        }
        FreeFlight::DeltaTracking => {
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
    }
}
