//! View options of the render commands: the colour bar, turntables, and
//! the parser of the turntable's frame count.

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use voxless::core::Image;
use voxless::render::colorbar::{ColorbarSpec, draw_colorbar};
use voxless::{Control, Scene, SceneDesc};

use crate::progress::Progress;

/// A turntable's frame count: at least 1.
pub fn frame_count(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(0) => Err("a turntable needs at least 1 frame".into()),
        Ok(n) => Ok(n),
        Err(_) => Err(format!("'{s}' is not a whole number of frames")),
    }
}

/// The colour bar to draw, when asked for.
pub fn colorbar(scene: &Scene, desc: &SceneDesc, on: bool) -> Option<ColorbarSpec> {
    on.then(|| scene.colorbar(desc))
}

/// Draws the colour bar (if any) into a rendered image.
pub fn decorate(image: &mut Image, scene: &Scene, bar: Option<&ColorbarSpec>) {
    if let Some(spec) = bar
        && draw_colorbar(image, &scene.tf, spec).is_none()
    {
        eprintln!(
            "note: a {}×{} image is too small for a colour bar",
            image.width, image.height
        );
    }
}

/// Renders `frames` images of a full orbit about the look-at point,
/// starting from the scene's camera (its `orbit` included), to numbered
/// files beside `output`, with one progress bar. The data is loaded once.
pub fn render_turntable(
    desc: &SceneDesc,
    base: &Path,
    data_frame: usize,
    frames: u32,
    output: &Path,
    with_colorbar: bool,
) -> Result<()> {
    let mut scene = crate::resolve(desc, base, data_frame)?;
    if let Some(note) = scene.check_work(desc)? {
        eprintln!("note: {note}");
    }
    let bar = colorbar(&scene, desc, with_colorbar);
    let progress = Progress::new("rendering turntable", frames as u64);
    let start = desc.camera.orbit.unwrap_or(0.0);
    let mut view = desc.clone();
    let t = Instant::now();
    for k in 0..frames {
        view.camera.orbit = Some(start + 360.0 * k as f32 / frames as f32);
        scene.reaim(&view)?;
        // Blue noise advances with the frame (spatiotemporal).
        scene.settings.frame = k;
        // Each frame's tiles are one unit of the bar, in fractions.
        let report = |d: u64, total: u64| progress.set_fraction(k as u64, d, total);
        let mut image = scene.render(&Control::new().with_progress(&report))?;
        decorate(&mut image, &scene, bar.as_ref());
        crate::out::write_image(
            &crate::out::frame_path(output, k as usize)?,
            &image,
            scene.background,
        )?;
    }
    progress.finish();
    eprintln!(
        "rendered a {frames}-frame turntable ({}×{}) in {:.2}s → {} … {}",
        scene.settings.width,
        scene.settings.height,
        t.elapsed().as_secs_f64(),
        crate::out::frame_path(output, 0)?.display(),
        crate::out::frame_path(output, frames as usize - 1)?.display()
    );
    Ok(())
}
