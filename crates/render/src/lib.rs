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
//! Constant intervals (tessellations) are composited whole, in closed form:
//! on a piece of constant value the colour and extinction are constant, so
//! it contributes `C·(1 − e^{−σL})` exactly — no step, no jitter. Their
//! iso-surfaces lie at the interval boundaries where the value crosses the
//! iso-value (gaps beside constant intervals count as zero).
//!
//! **Passes and control.** A render is `spp` passes over the image's tiles;
//! [`Job::pass`] renders one pass into a [`Film`], which can be resolved at
//! any moment (a viewer shows pass 1 while pass 2 runs). Each pass reports
//! progress per finished tile and stops between tiles once its
//! [`Control`]'s token is cancelled, leaving the film as it was.
//!
//! **Surfaces.** Triangle meshes ([`Surfaces`]) are opaque: a ray's
//! volume ends at its nearest mesh hit, and the volume is composited over
//! the shaded surface, with optional ambient occlusion (module [`surface`]).
//!
//! **Preparation.** Integrators work on the volume [`prepare`]d for the
//! transfer function and settings (see [`voxless_core::Prepare`]), so the
//! volume itself stays immutable and can serve several renders at once.
//!
//! Determinism: all randomness comes from [`sampling::PixelRng`] keyed by
//! (seed, pixel, sample, dimension), and passes are accumulated in sample
//! order, so the same inputs give the same image bit for bit regardless of
//! thread count or tile scheduling.

pub mod annotate;
pub mod bluenoise;
mod classify;
pub mod colorbar;
mod composite;
mod ctx;
mod cursor;
pub mod device;
pub mod font;
mod march;
mod meshes;
pub mod mirror;
mod packet;
mod ray_lanes;
pub mod sampling;
pub mod scatter;
mod scatter_packet;
mod spans;
pub mod surface;
#[cfg(any(test, feature = "testing"))]
pub mod testing;
mod tile;
mod work;

pub use cursor::{MIN_STEP_ULPS, min_step_at, step_in};
pub use march::{RayStats, march};
pub use mirror::Mirrored;
pub use packet::{PACKET, WINDOW_STEPS};
pub use scatter::{FreeFlight, LightSource, Noise, Scatter};
pub use spans::own_range;
pub use surface::AmbientOcclusion;
pub use voxless_mesh::{Mesh, MeshError, Paint, Surfaces};
pub use work::{WorkEstimate, estimate_work};

use rayon::prelude::*;
use voxless_core::{
    Aabb, Camera, Cancelled, Control, EventBudget, Image, Prepare, PrepareQuery, Range1, Simd,
    TileIntervals, Vec3, View, Volume,
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
    /// Use the volume's packet path when it has one (module `packet`); the
    /// per-sample path otherwise. Both give the same image.
    pub packets: bool,
    /// On the packet path, march eight rays in SIMD lanes where the
    /// render and the volume allow (module `ray_lanes`); off: packet
    /// passes. Both give the same image.
    pub lanes: bool,
    /// Single scattering with volumetric shadows instead of emission–
    /// absorption (module [`scatter`]); `light` and iso-surfaces are then
    /// not used.
    pub scatter: Option<Scatter>,
    /// Frame index in a time series: the blue noise advances with it.
    pub frame: u32,
    /// Tessellations: the k-buffer (first `k` events exact, the rest in
    /// depth layers) instead of sorting every event.
    pub event_budget: Option<EventBudget>,
    /// Tessellations: blocks smaller than this many pixels are drawn from
    /// coarser levels of detail, when the volume has them (`None`: the
    /// volume's own setting). Progressive renders set it for the coarse
    /// image.
    pub lod_pixels: Option<f32>,
    /// The SIMD backend of the volume's packet path (`Auto`: the best the
    /// CPU has); every backend gives the same image.
    pub simd: Simd,
    /// A render of one box of a domain decomposition: only the samples in
    /// the box are composited (see [`Domain`]).
    pub domain: Option<Domain>,
    /// Opaque triangle meshes drawn with the volume: each ray's volume
    /// integral ends at its nearest mesh hit (module [`surface`]).
    pub surfaces: Option<Surfaces>,
    /// Ambient occlusion on mesh and iso-surface hits.
    pub ao: Option<AmbientOcclusion>,
    /// Mirror instances: the volume and the meshes drawn again, reflected
    /// about these planes (one per axis; see [`mirror`]).
    pub mirrors: Vec<voxless_core::Mirror>,
}

/// One box of a domain decomposition, for a render that composites only
/// the samples inside it; the boxes' images composited front to back give
/// the one-process image.
///
/// A ray's samples sit on a lattice fixed by the pixel, the sample index
/// and the step (module `march`), and a box owns the samples whose
/// midpoints lie in it, so each sample of the one-process render is taken
/// by exactly one box and evaluated there with the same data (the box's
/// volume holds everything that reaches into it). Constant pieces are cut
/// at the box's faces, which their closed form allows exactly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Domain {
    /// The box whose samples this render owns, half-open `[min, max)`.
    pub owned: Aabb,
    /// The bounds of the whole data set: lattice cells are cut where they
    /// leave it (and the clip box), as in a one-process render, rather than
    /// at the bounds of the box's own part of the data.
    pub bounds: Aabb,
}

/// A pixel to render again from a known opacity: the opacity the boxes in
/// front of this one composited (see [`Job::render_pixels`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelRequest {
    pub x: u32,
    pub y: u32,
    pub alpha: f32,
}

impl RenderSettings {
    /// Defaults for `volume`: 1 spp, early termination at 0.99, the volume's
    /// value and attribute ranges, and an opacity scale giving optical depth
    /// 8 across the bounds' diagonal at opacity 1.
    pub fn for_volume<V: Volume>(volume: &V, width: u32, height: u32) -> Self {
        Self::for_data(
            volume.bounds(),
            volume.value_range(),
            volume.attribute_range(),
            width,
            height,
        )
    }

    /// [`RenderSettings::for_volume`] for data with these bounds and ranges
    /// (a decomposed volume: the whole data's, not a part's).
    pub fn for_data(
        bounds: Aabb,
        value_range: Range1,
        attribute_range: Option<Range1>,
        width: u32,
        height: u32,
    ) -> Self {
        RenderSettings {
            width,
            height,
            spp: 1,
            step: None,
            sampling_rate: 1.0,
            early_termination: 0.99,
            opacity_scale: 8.0 / bounds.diagonal().max(1e-12),
            value_range,
            attribute_range,
            light: None,
            seed: 0,
            clip: None,
            iso: Vec::new(),
            iso_opacity: 1.0,
            volume: true,
            log_scale: false,
            packets: true,
            lanes: true,
            scatter: None,
            frame: 0,
            event_budget: None,
            lod_pixels: None,
            simd: Simd::Auto,
            domain: None,
            surfaces: None,
            ao: None,
            mirrors: Vec::new(),
        }
    }

    /// Whether values in `r` can show up in the image: the transfer function
    /// gives them opacity, or an iso-value lies in `r`. Space skipping drops
    /// what this rejects.
    pub fn is_visible(&self, tf: &TransferFunction, r: Range1) -> bool {
        (self.volume && tf.any_opacity(self.normalize(r.lo), self.normalize(r.hi)))
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

/// Side of a square render tile in pixels, unless the volume's tile view
/// asks for another.
pub use voxless_core::TILE;

/// `volume` prepared for `tf` and `settings`: what the integrators sample.
pub fn prepare<'a, P: Prepare>(
    volume: &'a P,
    tf: &TransferFunction,
    settings: &RenderSettings,
) -> P::Prepared<'a> {
    let is_visible = |r: Range1| settings.is_visible(tf, r);
    let attr_range = settings.attribute_range.unwrap_or(Range1::new(0.0, 1.0));
    let attribute_color = |a: f32| tf.color(attr_range.normalize(a));
    volume.prepare(&PrepareQuery {
        is_visible: &is_visible,
        attribute_color: &attribute_color,
        event_budget: settings.event_budget,
        lod_pixels: settings.lod_pixels,
        simd: settings.simd,
    })
}

/// Prepares `volume`, renders `spp` passes and returns their average.
/// Progress is reported in tiles (all passes together); a cancelled render
/// returns [`Cancelled`].
pub fn render<P: Prepare>(
    volume: &P,
    camera: &Camera,
    tf: &TransferFunction,
    settings: &RenderSettings,
    control: &Control,
) -> Result<Image, Cancelled> {
    let film = render_film(volume, camera, tf, settings, control, &mut |_| true)?;
    Ok(film.resolve())
}

/// Prepares `volume` (with its mirror instances, when the settings have
/// mirrors) and renders pass by pass into a film: after each pass
/// `on_pass(&film)` sees it and returns whether to go on. Returns the film
/// with the passes done; progress is reported in tiles over all passes.
pub fn render_film<P: Prepare>(
    volume: &P,
    camera: &Camera,
    tf: &TransferFunction,
    settings: &RenderSettings,
    control: &Control,
    on_pass: &mut dyn FnMut(&Film) -> bool,
) -> Result<Film, Cancelled> {
    let prepared = prepare(volume, tf, settings);
    if settings.mirrors.is_empty() {
        run_film(&Job::new(&prepared, camera, tf, settings), control, on_pass)
    } else {
        let mirrored = Mirrored::new(&prepared, &settings.mirrors);
        run_film(&Job::new(&mirrored, camera, tf, settings), control, on_pass)
    }
}

fn run_film<V: Volume>(
    job: &Job<V>,
    control: &Control,
    on_pass: &mut dyn FnMut(&Film) -> bool,
) -> Result<Film, Cancelled> {
    let mut film = job.film();
    let per = job.tiles_per_pass();
    let total = per * job.settings.spp as u64;
    while film.passes() < job.settings.spp {
        let s = film.passes();
        job.pass(&mut film, s, &control.part(s as u64 * per, total))?;
        if !on_pass(&film) {
            break;
        }
    }
    Ok(film)
}

/// One render's fixed inputs, over an already prepared volume: renders
/// passes into a [`Film`] one at a time.
pub struct Job<'a, V: Volume> {
    volume: &'a V,
    view: Option<Box<dyn TileIntervals + 'a>>,
    camera: &'a Camera,
    tf: &'a TransferFunction,
    settings: &'a RenderSettings,
    tiles: Vec<Tile>,
    tile_size: u32,
}

impl<'a, V: Volume> Job<'a, V> {
    /// Sets up the passes: the volume's tile view for this camera and image
    /// size, if it has one, and the tiles.
    pub fn new(
        volume: &'a V,
        camera: &'a Camera,
        tf: &'a TransferFunction,
        settings: &'a RenderSettings,
    ) -> Self {
        let view = volume.tile_view(&View {
            camera: *camera,
            width: settings.width,
            height: settings.height,
        });
        let size = view.as_ref().map_or(TILE, |v| v.tile_size().max(1));
        Job {
            volume,
            view,
            camera,
            tf,
            settings,
            tiles: tiles(settings.width, settings.height, size),
            tile_size: size,
        }
    }

    /// An empty film of this job's size.
    pub fn film(&self) -> Film {
        Film::new(self.settings.width, self.settings.height)
    }

    /// Units of progress per pass (tiles).
    pub fn tiles_per_pass(&self) -> u64 {
        self.tiles.len() as u64
    }

    /// Runs the remaining passes (from `film.passes()` up to `spp`), with
    /// progress over all of them.
    pub fn run(&self, film: &mut Film, control: &Control) -> Result<(), Cancelled> {
        let per = self.tiles_per_pass();
        let total = per * self.settings.spp as u64;
        while film.passes() < self.settings.spp {
            let sample = film.passes();
            self.pass(film, sample, &control.part(sample as u64 * per, total))?;
        }
        Ok(())
    }

    /// Renders sample index `sample` of every pixel and adds it to `film`.
    /// Progress is reported per tile (of [`Job::tiles_per_pass`]); once
    /// `control` is cancelled the remaining tiles are skipped and the film
    /// is left as it was.
    pub fn pass(&self, film: &mut Film, sample: u32, control: &Control) -> Result<(), Cancelled> {
        assert!(
            film.width == self.settings.width && film.height == self.settings.height,
            "film size differs from the render settings"
        );
        let (pixels, stats) = self.pass_pixels(sample, control)?;
        film.stats.merge(&stats);
        for (s, p) in film.sum.iter_mut().zip(pixels) {
            for c in 0..4 {
                s[c] += p[c];
            }
        }
        film.passes += 1;
        Ok(())
    }

    /// Sample index `sample` of every pixel on its own (row-major
    /// premultiplied RGBA), and what the rays saw: one pass, for a caller
    /// that composites passes itself (a box of a domain decomposition).
    pub fn pass_pixels(
        &self,
        sample: u32,
        control: &Control,
    ) -> Result<(Vec<[f32; 4]>, RayStats), Cancelled> {
        control.check()?;
        let total = self.tiles.len() as u64;
        let done = std::sync::atomic::AtomicU64::new(0);
        let results: Vec<Option<(Vec<[f32; 4]>, RayStats)>> = self
            .tiles
            .par_iter()
            .map(|&tile| {
                if control.is_cancelled() {
                    return None;
                }
                let pixels = tile::render_tile(self, tile, sample, None);
                let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                control.report(d, total);
                Some(pixels)
            })
            .collect();
        if control.is_cancelled() || results.iter().any(Option::is_none) {
            return Err(Cancelled);
        }
        let w = self.settings.width;
        let mut image = vec![[0.0f32; 4]; w as usize * self.settings.height as usize];
        let mut stats = RayStats::default();
        for (tile, (pixels, st)) in self.tiles.iter().zip(results.into_iter().flatten()) {
            stats.merge(&st);
            let mut it = pixels.into_iter();
            for y in tile.y..tile.y + tile.h {
                for x in tile.x..tile.x + tile.w {
                    image[(y * w + x) as usize] = it.next().unwrap_or_default();
                }
            }
        }
        Ok((image, stats))
    }

    /// Sample index `sample` of the requested pixels, each rendered from
    /// the requested opacity onwards (the colour starts at zero): what a
    /// box of a decomposition adds behind the opacity its front boxes
    /// composited, with early termination where the whole ray would stop.
    /// One RGBA per request, in order (alpha is the total opacity).
    pub fn render_pixels(&self, sample: u32, requests: &[PixelRequest]) -> Vec<[f32; 4]> {
        let size = self.tile_size.max(1);
        let per_row = self.settings.width.div_ceil(size) as usize;
        // Requests by tile (tiles are laid out row by row).
        let mut by_tile: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
        for (i, r) in requests.iter().enumerate() {
            if r.x < self.settings.width && r.y < self.settings.height {
                let t = (r.y / size) as usize * per_row + (r.x / size) as usize;
                by_tile.entry(t).or_default().push(i);
            }
        }
        let work: Vec<(usize, Vec<usize>)> = by_tile.into_iter().collect();
        let results: Vec<Vec<(usize, [f32; 4])>> = work
            .par_iter()
            .map(|(t, reqs)| {
                let tile = self.tiles[*t];
                let mut alpha = vec![f32::NAN; (tile.w * tile.h) as usize];
                for &i in reqs {
                    let r = &requests[i];
                    alpha[((r.y - tile.y) * tile.w + (r.x - tile.x)) as usize] = r.alpha;
                }
                let (pixels, _) = tile::render_tile(self, tile, sample, Some(&alpha));
                reqs.iter()
                    .map(|&i| {
                        let r = &requests[i];
                        (
                            i,
                            pixels[((r.y - tile.y) * tile.w + (r.x - tile.x)) as usize],
                        )
                    })
                    .collect()
            })
            .collect();
        let mut out = vec![[0.0f32; 4]; requests.len()];
        for (i, p) in results.into_iter().flatten() {
            out[i] = p;
        }
        out
    }
}

/// Progressive accumulation: one pass per sample index, averaged on resolve.
pub struct Film {
    width: u32,
    height: u32,
    sum: Vec<[f32; 4]>,
    passes: u32,
    stats: RayStats,
}

impl Film {
    pub fn new(width: u32, height: u32) -> Self {
        Film {
            width,
            height,
            sum: vec![[0.0; 4]; width as usize * height as usize],
            passes: 0,
            stats: RayStats::default(),
        }
    }

    /// What the rays of the passes so far saw (iso-surface hits; the range
    /// of the values sampled when iso-surfaces were asked for).
    pub fn stats(&self) -> &RayStats {
        &self.stats
    }

    /// How many passes have been added.
    pub fn passes(&self) -> u32 {
        self.passes
    }

    /// Adds one pass rendered elsewhere (a device integrator): row-major
    /// premultiplied RGBA, one per pixel.
    pub fn add_pass(&mut self, pixels: &[[f32; 4]]) {
        assert_eq!(pixels.len(), self.sum.len(), "a pass of another size");
        for (s, p) in self.sum.iter_mut().zip(pixels) {
            for c in 0..4 {
                s[c] += p[c];
            }
        }
        self.passes += 1;
    }

    /// The average of the passes so far (transparent before the first).
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

#[derive(Clone, Copy, Debug)]
pub(crate) struct Tile {
    x: u32,
    y: u32,
    w: u32,
    h: u32,
}

fn tiles(width: u32, height: u32, size: u32) -> Vec<Tile> {
    let mut v = Vec::new();
    for y in (0..height).step_by(size as usize) {
        for x in (0..width).step_by(size as usize) {
            v.push(Tile {
                x,
                y,
                w: size.min(width - x),
                h: size.min(height - y),
            });
        }
    }
    v
}

/// The line integral `∫ value dt` through the centre of every pixel of a
/// `width`×`height` image, row-major, row 0 at the top: the volume's own
/// whole-image projection when it has one, else one line integral per
/// pixel (progress in rows, cancellation checked between rows).
pub fn project<V: Volume>(
    volume: &V,
    camera: &Camera,
    width: u32,
    height: u32,
    control: &Control,
) -> Result<Vec<f32>, Cancelled> {
    control.check()?;
    if let Some(image) = volume.project_image(camera, width, height, control) {
        return image;
    }
    project_per_pixel(volume, camera, width, height, control)
}

/// [`project`] without the volume's whole-image path: one line integral per
/// pixel centre (the slow path fast paths are tested against).
pub fn project_per_pixel<V: Volume>(
    volume: &V,
    camera: &Camera,
    width: u32,
    height: u32,
    control: &Control,
) -> Result<Vec<f32>, Cancelled> {
    let all = Range1::new(f32::NEG_INFINITY, f32::INFINITY);
    project_per_pixel_in(volume, camera, width, height, all, control)
}

/// [`project_per_pixel`] over the part `t` of every pixel's line (a slab of
/// an orthographic view: `t` is the distance along the view direction from
/// the image plane through the eye).
pub fn project_per_pixel_in<V: Volume>(
    volume: &V,
    camera: &Camera,
    width: u32,
    height: u32,
    t_range: Range1,
    control: &Control,
) -> Result<Vec<f32>, Cancelled> {
    project_in(volume, camera, width, height, None, t_range, control)
}

/// [`project_per_pixel_in`] restricted to the half-open box `domain` (see
/// [`own_range`]): the part of each line integral inside it, so the
/// projections of the boxes of a decomposition add up to the whole one.
pub fn project_in<V: Volume>(
    volume: &V,
    camera: &Camera,
    width: u32,
    height: u32,
    domain: Option<&Aabb>,
    t_range: Range1,
    control: &Control,
) -> Result<Vec<f32>, Cancelled> {
    let bounds = volume.bounds();
    project_each(camera, width, height, control, |ray| {
        let own = own_range(domain, ray);
        let t = Range1::new(own.lo.max(t_range.lo), own.hi.min(t_range.hi));
        let t = bounds.clip_ray(ray, t);
        if t.is_empty() {
            0.0
        } else {
            volume.line_integral(ray, t)
        }
    })
}

/// `column(ray)` through the centre of every pixel of a `width`×`height`
/// image of `camera`, row-major, row 0 at the top, rows in parallel
/// (progress in rows, cancellation checked between rows): the per-pixel
/// loop of every projection.
pub fn project_each(
    camera: &Camera,
    width: u32,
    height: u32,
    control: &Control,
    column: impl Fn(&voxless_core::Ray) -> f64 + Sync,
) -> Result<Vec<f32>, Cancelled> {
    let done = std::sync::atomic::AtomicU64::new(0);
    let rows: Vec<Option<Vec<f32>>> = (0..height)
        .into_par_iter()
        .map(|y| {
            if control.is_cancelled() {
                return None;
            }
            let row: Vec<f32> = (0..width)
                .map(|x| column(&camera.ray(x as f32 + 0.5, y as f32 + 0.5, width, height)) as f32)
                .collect();
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            control.report(d, height as u64);
            Some(row)
        })
        .collect();
    if control.is_cancelled() {
        return Err(Cancelled);
    }
    Ok(rows.into_iter().flatten().flatten().collect())
}

#[cfg(test)]
mod cursor_tests;
#[cfg(test)]
mod scatter_tests;
#[cfg(test)]
mod seam_tests;
#[cfg(test)]
mod surface_tests;
#[cfg(test)]
mod test_volumes;
#[cfg(test)]
mod tests;
