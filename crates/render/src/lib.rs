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
//! - [`colorbar::draw_colorbar`]: a labelled colour bar drawn into an image.
//!
//! Determinism: all randomness comes from [`sampling::PixelRng`] keyed by
//! (seed, pixel, sample, dimension), and passes are accumulated in sample
//! order, so the same inputs give the same image bit for bit regardless of
//! thread count or tile scheduling.

pub mod bluenoise;
pub mod colorbar;
pub mod font;
mod march;
mod packet;
pub mod sampling;
pub mod scatter;

pub use march::march;
pub use packet::{PACKET, WINDOW_STEPS};
pub use scatter::{FreeFlight, LightSource, Noise, Scatter};

use rayon::prelude::*;
use voxless_core::{Aabb, Camera, Image, Range1, Vec3, Volume};
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
    /// Use the volume's packet path when it has one (module `packet`); the
    /// per-sample path otherwise. Both give the same image.
    pub packets: bool,
    /// Single scattering with volumetric shadows instead of emission–
    /// absorption (module [`scatter`]); `light` and iso-surfaces are then
    /// not used.
    pub scatter: Option<Scatter>,
    /// Frame index in a time series: the blue noise advances with it.
    pub frame: u32,
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
            packets: true,
            scatter: None,
            frame: 0,
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
                let mut out = Vec::with_capacity((tile.w * tile.h) as usize);
                if let Some(sc) = &settings.scatter {
                    // Scattering paths are incoherent: one ray at a time.
                    let mut scratch = Vec::new();
                    for_each_pixel(tile, |x, y| {
                        let (_, ray) = pixel_ray(camera, settings, x, y, sample);
                        out.push(scatter::path(
                            volume,
                            &ray,
                            tf,
                            settings,
                            sc,
                            (x, y),
                            sample,
                            &mut scratch,
                        ));
                    });
                } else if settings.packets && volume.packet_sampling() {
                    let mut scratch = packet::PacketScratch::default();
                    packet::render_tile(
                        volume,
                        camera,
                        tf,
                        settings,
                        sample,
                        tile,
                        &mut scratch,
                        &mut out,
                    );
                } else {
                    let mut scratch = Vec::new();
                    for_each_pixel(tile, |x, y| {
                        let (rng, ray) = pixel_ray(camera, settings, x, y, sample);
                        out.push(march(volume, &ray, tf, settings, &rng, &mut scratch));
                    });
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

/// The random stream and camera ray of sample `sample` of pixel `(x, y)`:
/// the first sample goes through the pixel centre, later ones are jittered
/// over the pixel (antialiasing).
#[inline]
pub(crate) fn pixel_ray(
    camera: &Camera,
    settings: &RenderSettings,
    x: u32,
    y: u32,
    sample: u32,
) -> (PixelRng, voxless_core::Ray) {
    let (w, h) = (settings.width, settings.height);
    let rng = PixelRng::new(settings.seed, y as u64 * w as u64 + x as u64, sample);
    let (jx, jy) = if sample == 0 {
        (0.5, 0.5)
    } else {
        (rng.uniform(0), rng.uniform(1))
    };
    (rng, camera.ray(x as f32 + jx, y as f32 + jy, w, h))
}

/// Calls `f(x, y)` for the pixels of `tile`, row-major.
fn for_each_pixel(tile: Tile, mut f: impl FnMut(u32, u32)) {
    for y in tile.y..tile.y + tile.h {
        for x in tile.x..tile.x + tile.w {
            f(x, y);
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct Tile {
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
mod scatter_tests;
#[cfg(test)]
mod tests;
