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
use voxless_core::{Attribute, Camera, Image, Interval, IntervalQuery, Range1, Ray, Vec3, Volume};
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

    pub fn passes(&self) -> u32 {
        self.passes
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
    let t = volume
        .bounds()
        .clip_ray(ray, Range1::new(0.0, f32::INFINITY));
    if t.is_empty() {
        return [0.0; 4];
    }
    let vr = settings.value_range;
    let visible = |r: Range1| tf.max_opacity(vr.normalize(r.lo), vr.normalize(r.hi)) > 0.0;
    scratch.clear();
    volume.intervals(
        ray,
        t,
        &IntervalQuery {
            is_visible: &visible,
        },
        scratch,
    );
    let mut color = Vec3::ZERO;
    let mut alpha = 0.0f32;
    let attr_range = settings.attribute_range.unwrap_or(Range1::new(0.0, 1.0));
    for (k, iv) in scratch.iter().enumerate() {
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
            if len > 0.0 {
                let p = ray.at(0.5 * (seg_start + end));
                let (sample, gradient) = match settings.light {
                    Some(_) => match volume.sample_with_gradient(p) {
                        Some((s, g)) => (Some(s), g),
                        None => (None, Vec3::ZERO),
                    },
                    None => (volume.sample(p), Vec3::ZERO),
                };
                if let Some(s) = sample {
                    let x = vr.normalize(s.value);
                    let opacity = tf.opacity(x);
                    if opacity > 0.0 {
                        let a = 1.0 - (-opacity * settings.opacity_scale * len).exp();
                        let mut c = match s.attribute {
                            Attribute::Scalar(v) => tf.color(attr_range.normalize(v)),
                            Attribute::Rgb(c) => c,
                            Attribute::None => tf.color(x),
                        };
                        if let Some(light) = settings.light {
                            c = c * shade(gradient, light);
                        }
                        color += c * ((1.0 - alpha) * a);
                        alpha += (1.0 - alpha) * a;
                        if alpha >= settings.early_termination {
                            return [color.x, color.y, color.z, alpha];
                        }
                    }
                }
            }
            seg_start = end;
            seg_end = end + dt;
        }
    }
    [color.x, color.y, color.z, alpha]
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
