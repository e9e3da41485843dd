//! Time series: frames A..B by their numbers, rendered to numbered images
//! with one progress bar and defaults held over the whole series.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Result, bail};
use voxless::output::OutputKind;
use voxless::parallel::{FramePlan, Timings};
use voxless::{Control, Placement, SceneDesc};

use crate::progress::Progress;
use crate::{out, render};

/// Renders the frames numbered in `range` (A..B, inclusive) to numbered
/// images. Value range, opacity scale, attribute range and camera come
/// from a first pass over the series (see [`voxless::Scene::open_series`])
/// and stay fixed, so the sequence does not flicker. Under `mpirun` the
/// ranks either render whole frames each, one process per frame, or each
/// frame together, decomposed (see [`Placement::frame_plan`]).
pub fn render(
    placement: Placement,
    desc: &SceneDesc,
    base: &Path,
    range: &str,
    output: &Path,
    colorbar: bool,
) -> Result<()> {
    let (frames, outputs) = frames_and_outputs(desc, base, range, output, placement.is_root())?;
    let plan = placement.frame_plan(desc, base, &frames)?;
    // Whole frames per rank: each rank holds its frames in one process,
    // and a round renders as many frames as there are ranks.
    let (held, per_round) = match plan {
        FramePlan::ByFrame => (Placement::Process, placement.ranks()),
        FramePlan::BySpace => (placement, 1),
    };
    let t = Instant::now();
    let opened = held
        .open_series(desc, base, &frames)
        .map_err(anyhow::Error::from);
    let (mut scene, series) = render::agree(placement, opened)?;
    render::report_placed(placement, &scene, t);
    render::check_work(placement, &scene, desc)?;
    let bar = render::colorbar(&scene, desc, colorbar);
    let progress = Progress::new("rendering frames", frames.len() as u64, placement.is_root());
    let t = Instant::now();
    let mut timings = Timings::default();
    for (round, chunk) in frames.chunks(per_round).enumerate() {
        let first = round * per_round;
        let mine = match plan {
            FramePlan::ByFrame => chunk
                .get(placement.rank())
                .map(|&f| (first + placement.rank(), f)),
            FramePlan::BySpace => Some((first, chunk[0])),
        };
        let rendered = match mine {
            Some((k, f)) => (|| {
                if k > 0 {
                    scene.load_frame(&series, base, f)?;
                }
                // Blue noise advances with the frame (spatiotemporal).
                scene.view_mut().settings.frame = f as u32;
                let report = |d: u64, total: u64| progress.set_fraction(k as u64, d, total);
                let r = scene.render(&Control::new().with_progress(&report), &mut timings)?;
                Ok(r.map(|mut r| {
                    if let Err(e) = scene.check_rendered(&r) {
                        progress.println(&format!("note: frame {f}: {e}"));
                    }
                    render::decorate(&mut r.image, scene.view(), bar.as_ref());
                    r.image
                }))
            })(),
            None => Ok(None),
        };
        let rendered = match plan {
            FramePlan::ByFrame => render::agree(placement, rendered)?,
            FramePlan::BySpace => rendered?,
        };
        let images = match plan {
            FramePlan::ByFrame => placement.gather_images(rendered)?,
            FramePlan::BySpace => vec![rendered],
        };
        let written: Result<()> = images
            .into_iter()
            .enumerate()
            .filter_map(|(r, image)| Some((outputs.get(first + r)?, image?)))
            .try_for_each(|(path, image)| out::write_image(path, &image, scene.view().background));
        render::agree(placement, written)?;
        progress.set((first + chunk.len()) as u64);
    }
    progress.finish();
    render::say(placement.memory_report(scene.counts())?);
    if placement.is_root() {
        let how = match (placement, plan) {
            (Placement::Process, _) => "",
            (_, FramePlan::ByFrame) => " (whole frames per rank)",
            (_, FramePlan::BySpace) => " (each frame decomposed over all ranks)",
        };
        let how = format!("{}{how}", render::on_ranks(placement));
        eprintln!(
            "rendered {} frames{how} in {:.2}s → {} … {}",
            frames.len(),
            t.elapsed().as_secs_f64(),
            outputs[0].display(),
            outputs[outputs.len() - 1].display()
        );
    }
    Ok(())
}

/// The frames numbered in `range` (A..B, inclusive) and their numbered
/// output paths, checked before any work; an error when no frame is in the
/// range, and (with `note`) a note when the range reaches past the data.
/// One process and `mpirun` (its root notes) select frames alike.
fn frames_and_outputs(
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
