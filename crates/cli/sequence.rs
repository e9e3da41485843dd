//! Time series: frames A..B by their numbers, rendered to numbered images
//! with one progress bar and defaults held over the whole series.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Result, bail};
use voxless::output::OutputKind;
use voxless::{Control, Scene, SceneDesc};

use crate::progress::Progress;
use crate::{out, view};

/// Renders the frames numbered in `range` (A..B, inclusive) to numbered
/// images. Value range, opacity scale, attribute range and camera come
/// from a first pass over the series (see [`Scene::open_series`]) and stay
/// fixed, so the sequence does not flicker.
pub fn render(
    desc: &SceneDesc,
    base: &Path,
    range: &str,
    output: &Path,
    colorbar: bool,
) -> Result<()> {
    let (frames, outputs) = frames_and_outputs(desc, base, range, output, true)?;
    let t = Instant::now();
    let (mut scene, series) = Scene::open_series(desc, base, &frames)?;
    crate::report_loaded(&scene, t);
    if let Some(note) = scene.check_work(desc)? {
        eprintln!("note: {note}");
    }
    let bar = view::colorbar(&scene, desc, colorbar);
    let progress = Progress::new("rendering frames", frames.len() as u64);
    let t = Instant::now();
    for (k, (&f, path)) in frames.iter().zip(&outputs).enumerate() {
        if k > 0 {
            scene.load_frame(&series, base, f)?;
        }
        // Blue noise advances with the frame (spatiotemporal).
        scene.settings.frame = f as u32;
        let report = |d: u64, total: u64| progress.set_fraction(k as u64, d, total);
        let film = scene.render_film(&Control::new().with_progress(&report))?;
        let mut image = film.resolve();
        if let Err(e) = scene.check_visible(&film, &image) {
            progress.println(&format!("note: frame {f}: {e}"));
        }
        view::decorate(&mut image, &scene, bar.as_ref());
        out::write_image(path, &image, scene.background)?;
        progress.set(k as u64 + 1);
    }
    progress.finish();
    eprintln!(
        "rendered {} frames in {:.2}s → {} … {}",
        frames.len(),
        t.elapsed().as_secs_f64(),
        outputs[0].display(),
        outputs[outputs.len() - 1].display()
    );
    Ok(())
}

/// The frames numbered in `range` (A..B, inclusive) and their numbered
/// output paths, checked before any work; an error when no frame is in the
/// range, and (with `note`) a note when the range reaches past the data.
/// One process and `mpirun` (its root notes) select frames alike.
pub(crate) fn frames_and_outputs(
    desc: &SceneDesc,
    base: &Path,
    range: &str,
    output: &Path,
    note: bool,
) -> Result<(Vec<usize>, Vec<PathBuf>)> {
    let range = voxless::frames::parse_range(range)?;
    let numbers = voxless::frame_numbers(desc, base)?;
    let frames: Vec<usize> = numbers
        .iter()
        .copied()
        .filter(|n| range.contains(n))
        .collect();
    if frames.is_empty() {
        bail!(
            "--frames {}..{}: no frame is numbered in that range; the data has frames {}",
            range.start(),
            range.end(),
            voxless::frames::list_numbers(&numbers)
        );
    }
    if note && (range.start() < &numbers[0] || range.end() > &numbers[numbers.len() - 1]) {
        eprintln!(
            "note: --frames {}..{} reaches past the data, whose frames in that range are {}",
            range.start(),
            range.end(),
            voxless::frames::list_numbers(&frames)
        );
    }
    let outputs = frames
        .iter()
        .map(|&f| out::frame_path(output, f))
        .collect::<Result<Vec<_>>>()?;
    out::check(&outputs, OutputKind::Image, desc, base, &[])?;
    Ok((frames, outputs))
}
