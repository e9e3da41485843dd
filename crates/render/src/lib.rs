//! Integrators over the [`Volume`] seam, run tile-parallel with rayon.
//!
//! - [`render`]: emission–absorption ray marching. Per interval the ray is cut
//!   into segments of the step size, starting at a per-pixel random offset
//!   (jitter, against wood-grain artifacts); each segment is sampled at its
//!   midpoint and its opacity corrected for its actual length,
//!   `α = 1 − exp(−σ·len)` with `σ = opacity(value)·opacity_scale`, so a
//!   homogeneous medium gives `exp(−σL)` at any step size. Colour comes from
//!   the attribute (colour-mapped Θ, or a pre-classified colour) when the
//!   volume has one, otherwise from the value; optional diffuse shading uses
//!   the volume's gradient and one directional light. Marching stops once the
//!   pixel's opacity reaches `early_termination`. Intervals whose value range
//!   the transfer function maps to zero opacity are skipped.
//! - [`project`]: the line integral `∫ value dt` per pixel (column density).
//!
//! Determinism: all randomness comes from [`sampling::PixelRng`] keyed by
//! (seed, pixel, sample, dimension), and passes are accumulated in sample
//! order, so the same inputs give the same image bit for bit regardless of
//! thread count or tile scheduling.

pub mod sampling;

use rayon::prelude::*;
use voxless_core::{
    Aabb, Attribute, Camera, Image, Interval, IntervalQuery, Range1, Ray, Vec3, Volume,
};
use voxless_transfer::TransferFunction;

use sampling::PixelRng;

/// One directional light for gradient shading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Unit vector pointing towards the light.
    pub direction: Vec3,
    /// Fraction of the colour kept in full shadow, in [0, 1].
    pub ambient: f32,
}

#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    /// World-space step; when `None`, each interval's `nominal_dt / sampling_rate`.
    pub step: Option<f32>,
    pub sampling_rate: f32,
    /// Stop marching a pixel once its opacity reaches this (≤ 1).
    pub early_termination: f32,
    /// Extinction per unit length at opacity 1.
    pub opacity_scale: f32,
    /// Value range mapped to [0, 1] for the transfer function.
    pub value_range: Range1,
    /// Attribute range mapped to [0, 1] for colour.
    pub attribute_range: Option<Range1>,
    pub light: Option<Light>,
    pub seed: u64,
    /// Only the part of the volume inside this box is rendered.
    pub clip: Option<Aabb>,
    /// Values of implicit iso-surfaces (shaded with the gradient; coloured by
    /// the attribute when there is one, else by the colormap at the iso-value).
    pub iso: Vec<f32>,
    /// Opacity of the iso-surfaces (1 = opaque).
    pub iso_opacity: f32,
    /// Whether the volume itself is rendered (false: iso-surfaces only).
    pub volume: bool,
    /// Map `log10(value)` rather than `value` through the transfer function
    /// (`value_range` is then in log10 units; values ≤ 0 map to 0).
    pub log_scale: bool,
}

impl RenderSettings {
    /// Defaults for `volume`: 1 spp, early termination at 0.99, the volume's
    /// value and attribute ranges, and an opacity scale giving optical depth
    /// 8 across the bounds' diagonal at opacity 1.
    pub fn for_volume<V: Volume>(volume: &V, width: u32, height: u32) -> Self {
        RenderSettings {
            width,
            height,
            spp: 1,
            step: None,
            sampling_rate: 1.0,
            early_termination: 0.99,
            opacity_scale: 8.0 / volume.bounds().diagonal().max(1e-12),
            value_range: volume.value_range(),
            attribute_range: volume.attribute_range(),
            light: None,
            seed: 0,
            clip: None,
            iso: Vec::new(),
            iso_opacity: 1.0,
            volume: true,
            log_scale: false,
        }
    }

    /// Whether values in `r` can show up in the image: the transfer function
    /// gives them opacity, or an iso-value lies in `r`. Space skipping drops
    /// what this rejects.
    pub fn is_visible(&self, tf: &TransferFunction, r: Range1) -> bool {
        (self.volume && tf.max_opacity(self.normalize(r.lo), self.normalize(r.hi)) > 0.0)
            || self.iso.iter().any(|&v| r.contains(v))
    }

    /// A field value → the transfer function's `[0, 1]` coordinate.
    #[inline]
    pub fn normalize(&self, value: f32) -> f32 {
        if self.log_scale {
            if value > 0.0 {
                self.value_range.normalize(value.log10())
            } else {
                0.0
            }
        } else {
            self.value_range.normalize(value)
        }
    }
}

/// Side of a square render tile in pixels.
pub const TILE: u32 = 16;

/// Renders `spp` passes and returns their average. `progress(done, total)` is
/// called after every finished tile.
pub fn render<V: Volume>(
    volume: &V,
    camera: &Camera,
    tf: &TransferFunction,
    settings: &RenderSettings,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Image {
    let mut film = Film::new(settings.width, settings.height);
    let tiles = tiles(settings.width, settings.height);
    let total = tiles.len() as u64 * settings.spp as u64;
    let done = std::sync::atomic::AtomicU64::new(0);
    for sample in 0..settings.spp {
        film.add_pass(volume, camera, tf, settings, sample, &|| {
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress(d, total);
        });
    }
    film.resolve()
}

/// Progressive accumulation: one pass per sample index, averaged on resolve.
pub struct Film {
    width: u32,
    height: u32,
    sum: Vec<[f32; 4]>,
    passes: u32,
}

impl Film {
    pub fn new(width: u32, height: u32) -> Self {
        Film {
            width,
            height,
            sum: vec![[0.0; 4]; width as usize * height as usize],
            passes: 0,
        }
    }

    /// Renders sample index `sample` for every pixel and adds it in.
    pub fn add_pass<V: Volume>(
        &mut self,
        volume: &V,
        camera: &Camera,
        tf: &TransferFunction,
        settings: &RenderSettings,
        sample: u32,
        tile_done: &(dyn Fn() + Sync),
    ) {
        let (w, h) = (self.width, self.height);
        let results: Vec<(Tile, Vec<[f32; 4]>)> = tiles(w, h)
            .into_par_iter()
            .map(|tile| {
                let mut scratch = Vec::new();
                let mut out = Vec::with_capacity((tile.w * tile.h) as usize);
                for y in tile.y..tile.y + tile.h {
                    for x in tile.x..tile.x + tile.w {
                        let pixel = y as u64 * w as u64 + x as u64;
                        let rng = PixelRng::new(settings.seed, pixel, sample);
                        // The first sample goes through the pixel centre; later
                        // ones are jittered over the pixel (antialiasing).
                        let (jx, jy) = if sample == 0 {
                            (0.5, 0.5)
                        } else {
                            (rng.uniform(0), rng.uniform(1))
                        };
                        let ray = camera.ray(x as f32 + jx, y as f32 + jy, w, h);
                        out.push(march(volume, &ray, tf, settings, &rng, &mut scratch));
                    }
                }
                tile_done();
                (tile, out)
            })
            .collect();
        for (tile, pixels) in results {
            let mut it = pixels.into_iter();
            for y in tile.y..tile.y + tile.h {
                for x in tile.x..tile.x + tile.w {
                    let p = it.next().unwrap_or_default();
                    let s = &mut self.sum[(y * w + x) as usize];
                    for c in 0..4 {
                        s[c] += p[c];
                    }
                }
            }
        }
        self.passes += 1;
    }

    /// The average of the passes so far.
    pub fn resolve(&self) -> Image {
        let inv = 1.0 / self.passes.max(1) as f32;
        Image {
            width: self.width,
            height: self.height,
            pixels: self.sum.iter().map(|p| p.map(|c| c * inv)).collect(),
        }
    }
}

#[derive(Clone, Copy, Debug)]
struct Tile {
    x: u32,
    y: u32,
    w: u32,
    h: u32,
}

fn tiles(width: u32, height: u32) -> Vec<Tile> {
    let mut v = Vec::new();
    for y in (0..height).step_by(TILE as usize) {
        for x in (0..width).step_by(TILE as usize) {
            v.push(Tile {
                x,
                y,
                w: TILE.min(width - x),
                h: TILE.min(height - y),
            });
        }
    }
    v
}

/// Emission–absorption along one ray; returns premultiplied linear RGBA.
pub fn march<V: Volume>(
    volume: &V,
    ray: &Ray,
    tf: &TransferFunction,
    settings: &RenderSettings,
    rng: &PixelRng,
    scratch: &mut Vec<Interval>,
) -> [f32; 4] {
    let mut region = volume.bounds();
    if let Some(clip) = settings.clip {
        region = Aabb::new(region.min.max(clip.min), region.max.min(clip.max));
    }
    let t = region.clip_ray(ray, Range1::new(0.0, f32::INFINITY));
    if t.is_empty() {
        return [0.0; 4];
    }
    let visible = |r: Range1| settings.is_visible(tf, r);
    scratch.clear();
    volume.intervals(
        ray,
        t,
        &IntervalQuery {
            is_visible: &visible,
        },
        scratch,
    );
    let mut acc = Accumulator::default();
    let attr_range = settings.attribute_range.unwrap_or(Range1::new(0.0, 1.0));
    let colour_of = |s: &voxless_core::Sample, x: f32| match s.attribute {
        Attribute::Scalar(v) => tf.color(attr_range.normalize(v)),
        Attribute::Rgb(c) => c,
        Attribute::None => tf.color(x),
    };
    let needs_gradient = settings.light.is_some();
    // The previous sample (t, value), for iso-surface crossings; reset at gaps.
    let mut prev: Option<(f32, f32)> = None;
    let mut prev_end = f32::NAN;
    for (k, iv) in scratch.iter().enumerate() {
        if iv.t.lo != prev_end {
            prev = None;
        }
        prev_end = iv.t.hi;
        let dt = settings
            .step
            .unwrap_or(iv.nominal_dt / settings.sampling_rate)
            .max(iv.t.span() * 1e-6)
            .max(f32::MIN_POSITIVE);
        // Segment boundaries start at a random offset inside the first step.
        let xi = rng.uniform(2 + k as u32);
        let mut seg_start = iv.t.lo;
        let mut seg_end = iv.t.lo + xi * dt;
        while seg_start < iv.t.hi {
            let end = seg_end.min(iv.t.hi);
            let len = end - seg_start;
            seg_start = end;
            seg_end = end + dt;
            if len <= 0.0 {
                continue;
            }
            let tm = end - 0.5 * len;
            let p = ray.at(tm);
            let (sample, gradient) = match needs_gradient && settings.volume {
                true => match volume.sample_with_gradient_in(p, iv) {
                    Some((s, g)) => (Some(s), g),
                    None => (None, Vec3::ZERO),
                },
                false => (volume.sample_in(p, iv), Vec3::ZERO),
            };
            let Some(s) = sample else {
                prev = None;
                continue;
            };
            // Implicit iso-surfaces: a sign change of value − iso between the
            // previous sample and this one is a hit, placed by linear interpolation.
            if let Some((t0, v0)) = prev {
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
                        let c = colour_of(&hs, settings.normalize(iso)) * shade(g, light);
                        if acc.add(c, settings.iso_opacity, settings.early_termination) {
                            return acc.rgba();
                        }
                    }
                }
            }
            prev = Some((tm, s.value));
            if !settings.volume {
                continue;
            }
            let x = settings.normalize(s.value);
            let opacity = tf.opacity(x);
            if opacity > 0.0 {
                let a = 1.0 - (-opacity * settings.opacity_scale * len).exp();
                let mut c = colour_of(&s, x);
                if let Some(light) = settings.light {
                    c = c * shade(gradient, light);
                }
                if acc.add(c, a, settings.early_termination) {
                    return acc.rgba();
                }
            }
        }
    }
    acc.rgba()
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
fn shade(gradient: Vec3, light: Light) -> f32 {
    let n = gradient.normalized();
    if n.length_squared() == 0.0 {
        return 1.0;
    }
    light.ambient + (1.0 - light.ambient) * n.dot(light.direction).abs()
}

/// The line integral `∫ value dt` through the centre of every pixel of a
/// `width`×`height` image, row-major, row 0 at the top. `progress(done,
/// total)` counts finished rows.
pub fn project<V: Volume>(
    volume: &V,
    camera: &Camera,
    width: u32,
    height: u32,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Vec<f32> {
    let done = std::sync::atomic::AtomicU64::new(0);
    let bounds = volume.bounds();
    (0..height)
        .into_par_iter()
        .flat_map_iter(|y| {
            let row: Vec<f32> = (0..width)
                .map(|x| {
                    let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5, width, height);
                    let t = bounds.clip_ray(&ray, Range1::new(f32::NEG_INFINITY, f32::INFINITY));
                    if t.is_empty() {
                        0.0
                    } else {
                        volume.line_integral(&ray, t) as f32
                    }
                })
                .collect();
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress(d, height as u64);
            row
        })
        .collect()
}

#[cfg(test)]
mod tests;
