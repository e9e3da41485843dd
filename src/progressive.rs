//! Progressive rendering for interactive front-ends: a coarse image first,
//! then full-resolution passes up to the requested samples per pixel.
//!
//! Model: after every interaction a viewer wants *something* on screen fast
//! and the exact image eventually. [`render_progressive`] renders
//!
//! 1. optionally a **coarse** image: the same camera and settings at a
//!    reduced resolution (at most a pixel budget, aspect kept) and 1 spp —
//!    the browser scales it up — with tessellations drawn from their
//!    coarser levels of detail where blocks are small on screen (a
//!    tessellation's cost is its tets, not its pixels); then
//! 2. the **full** image pass by pass (the film of [`AnyVolume::render_passes`]),
//!    handing each stage to the caller, who shows it and says whether to go
//!    on.
//!
//! The last full pass is exactly what `voxless render` of the same scene
//! draws: the full stage uses the caller's settings unchanged, and the coarse
//! stage is a separate render that contributes nothing to it.
//! [`CoarseBudget`] picks the coarse pixel count from the time the previous
//! coarse renders took, so the first image keeps to a target latency on any
//! data and machine. Cancellation ([`Control`]) stops between tiles; the
//! caller never sees a partial pass.

use std::time::Instant;

use voxless_core::{Camera, Cancelled, Control};
use voxless_render::{Film, RenderSettings};
use voxless_transfer::TransferFunction;

use crate::device::Device;
use crate::{AnyVolume, SceneError};

/// Which image a progressive render hands out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// The reduced-resolution 1-spp image.
    Coarse,
    /// `done` of `of` full-resolution passes; `done == of` is converged.
    Pass { done: u32, of: u32 },
}

impl Stage {
    pub fn is_converged(self) -> bool {
        matches!(self, Stage::Pass { done, of } if done >= of)
    }
}

/// `settings` at a resolution of at most `max_pixels` pixels (aspect ratio
/// kept, at least 1×1) and 1 spp: the coarse stage of a progressive render.
/// Settings already within the budget keep their size.
///
/// Tessellations in the coarse image use their levels of detail: blocks
/// (8³ Lagrangian cells) smaller on screen than the image's larger side
/// are drawn from a grid subsampled once per halving below it. A
/// tessellation's render costs its tets whatever the image size, so
/// without this the coarse image would cost nearly what the full one does;
/// tying the threshold to the image keeps the detail drawn, and the cost
/// per pixel, about the same as the budget grows. (On the 64³ run at 96²:
/// 0.44 s for every tet, 0.07 s this way; see docs/benchmarks.md.)
pub fn coarse_settings(settings: &RenderSettings, max_pixels: u64) -> RenderSettings {
    let (w, h) = (settings.width as f64, settings.height as f64);
    let scale = ((max_pixels.max(1) as f64) / (w * h)).sqrt().min(1.0);
    let (width, height) = (
        ((w * scale).floor() as u32).max(1),
        ((h * scale).floor() as u32).max(1),
    );
    let side = width.max(height) as f32;
    RenderSettings {
        width,
        height,
        spp: 1,
        lod_pixels: Some(settings.lod_pixels.map_or(side, |p| p.max(side))),
        ..settings.clone()
    }
}

/// Picks the pixel count of coarse images from the rate the previous ones
/// were rendered at, aiming at `target_secs` per coarse image.
#[derive(Clone, Debug)]
pub struct CoarseBudget {
    target_secs: f64,
    min_pixels: u64,
    /// Pixels per second of the recent coarse renders (smoothed); `None`
    /// before the first.
    rate: Option<f64>,
}

impl CoarseBudget {
    /// A budget aiming at `target_secs` per coarse image, never below
    /// `min_pixels` (a 64×64 image is still worth seeing).
    pub fn new(target_secs: f64, min_pixels: u64) -> Self {
        CoarseBudget {
            target_secs: target_secs.max(1e-3),
            min_pixels: min_pixels.max(1),
            rate: None,
        }
    }

    /// The pixel budget of the next coarse image of a `full`-pixel view: a
    /// sixteenth of the view before anything was measured, then what the
    /// measured rate renders in the target time, at most a quarter of the
    /// view (a coarse image the size of the full one would be no faster).
    pub fn pixels(&self, full: u64) -> u64 {
        let want = match self.rate {
            None => full / 16,
            Some(r) => (r * self.target_secs) as u64,
        };
        want.clamp(self.min_pixels.min(full), (full / 4).max(self.min_pixels))
    }

    /// Records that `pixels` pixels took `secs` seconds.
    pub fn record(&mut self, pixels: u64, secs: f64) {
        if !(secs > 0.0) || pixels == 0 {
            return;
        }
        let r = pixels as f64 / secs;
        // Smooth over renders (the data, view and machine load vary), but
        // follow a drop at once so a slow view does not stall the next.
        self.rate = Some(match self.rate {
            Some(old) if r > old => 0.5 * (old + r),
            _ => r,
        });
    }
}

/// Renders `settings` progressively (see the module docs): the coarse stage
/// when `coarse_pixels` is given and smaller than the view, then every
/// full-resolution pass. `on_image(stage, film, settings)` sees each stage
/// with the settings it was rendered at, and returns whether to go on.
/// Returns the full film with the passes done (empty when stopped after the
/// coarse stage), or [`Cancelled`].
#[allow(clippy::too_many_arguments)]
pub fn render_progressive(
    volume: &AnyVolume,
    camera: &Camera,
    tf: &TransferFunction,
    settings: &RenderSettings,
    coarse_pixels: Option<u64>,
    budget: Option<&mut CoarseBudget>,
    control: &Control,
    on_image: &mut dyn FnMut(Stage, &Film, &RenderSettings) -> bool,
) -> Result<Film, Cancelled> {
    let cpu = Device::cpu();
    let view = (camera, tf, settings);
    let stages = (coarse_pixels, budget);
    // The CPU has no device errors.
    render_progressive_on(
        &cpu,
        volume,
        view,
        stages,
        control,
        &mut Vec::new(),
        on_image,
    )
    .unwrap_or(Err(Cancelled))
}

/// [`render_progressive`] with the full-resolution passes on `device` (the
/// coarse stage stays on the CPU: it draws the particles' merged preview,
/// which is fast there); `notes` gets what a front-end should say about
/// the device. The outer error is the device's, the inner a cancelled
/// render.
pub fn render_progressive_on(
    device: &Device,
    volume: &AnyVolume,
    (camera, tf, settings): (&Camera, &TransferFunction, &RenderSettings),
    (coarse_pixels, budget): (Option<u64>, Option<&mut CoarseBudget>),
    control: &Control,
    notes: &mut Vec<String>,
    on_image: &mut dyn FnMut(Stage, &Film, &RenderSettings) -> bool,
) -> Result<Result<Film, Cancelled>, SceneError> {
    let full = settings.width as u64 * settings.height as u64;
    if let Some(max) = coarse_pixels.filter(|&m| m < full) {
        let coarse = coarse_settings(settings, max);
        let t = Instant::now();
        // A large particle set's coarse image comes from its merged
        // preview (levels of detail): the full set would take seconds.
        let preview = match volume {
            AnyVolume::Particles(v) => v.preview(),
            _ => None,
        };
        let film = match preview {
            Some(p) => voxless_render::render_film(p, camera, tf, &coarse, control, &mut |_| true),
            None => volume.render_passes(camera, tf, &coarse, control, &mut |_| true),
        };
        let Ok(film) = film else {
            return Ok(Err(Cancelled));
        };
        if let Some(b) = budget {
            b.record(
                coarse.width as u64 * coarse.height as u64,
                t.elapsed().as_secs_f64(),
            );
        }
        if !on_image(Stage::Coarse, &film, &coarse) {
            return Ok(Ok(Film::new(settings.width, settings.height)));
        }
    }
    if control.check().is_err() {
        return Ok(Err(Cancelled));
    }
    device.render_passes(volume, camera, tf, settings, control, notes, &mut |film| {
        let stage = Stage::Pass {
            done: film.passes(),
            of: settings.spp,
        };
        on_image(stage, film, settings)
    })
}
