//! Time series and camera paths: frames A..B rendered to numbered images or
//! a movie, with one progress bar and defaults held over the whole series.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Result;
use voxless::annotate::Marks;
use voxless::movie::{MovieFormat, MovieSettings, MovieWriter};
use voxless::output::OutputKind;
use voxless::parallel::{FramePlan, Timings};
use voxless::{Control, Image, Placement, SceneDesc};

use crate::progress::Progress;
use crate::{out, render};

/// How a movie is written (`-o` with a movie's extension).
#[derive(Clone, Copy, Debug, Default)]
pub struct MovieArgs {
    pub settings: MovieSettings,
    /// Keep the frame PNGs beside the movie.
    pub keep_frames: bool,
}

/// Which frames to render.
pub enum Frames<'a> {
    /// `--frames A..B`: data frames, or the frames of a camera path.
    Range(&'a str),
    /// `--turntable N` of one data frame.
    Turntable { n: usize, frame: usize },
}

/// Where the frames go: numbered images, or a movie (encoded on rank 0).
enum Sink {
    Images(Vec<PathBuf>),
    Movie(Option<MovieWriter>),
}

/// Renders the frames `range` (A..B, inclusive) selects (see
/// [`voxless::camera_path::sequence`]: data frames, or the frames of the
/// scene's camera path) to numbered images or, for a movie output, a movie.
/// Value range, opacity scale, attribute range and framing come from a
/// first pass over the data frames shown (see
/// [`voxless::Scene::open_series`]) and stay fixed, so the sequence does
/// not flicker. Under `mpirun` the ranks either render whole frames each,
/// one process per frame, or each frame together, decomposed (see
/// [`Placement::frame_plan`]); rank 0 writes (and encodes).
#[allow(clippy::too_many_arguments)]
pub fn render(
    placement: Placement,
    desc: &SceneDesc,
    base: &Path,
    frames: Frames,
    output: &Path,
    marks: Marks,
    movie: MovieArgs,
    radii: Option<&Path>,
    device: &voxless::device::Device,
) -> Result<()> {
    let root = placement.is_root();
    let mut said = false;
    let seq = match frames {
        Frames::Range(range) => {
            let range = voxless::frames::parse_range(range)?;
            voxless::camera_path::sequence(desc, base, range)?
        }
        Frames::Turntable { n, frame } => voxless::camera_path::turntable(desc, n, frame)?,
    };
    render::check_radii_output(radii, desc, base)?;
    if root {
        for n in &seq.notes {
            eprintln!("note: {n}");
        }
    }
    let is_movie = MovieFormat::of(output).is_some();
    // A million frames is a million files: refused before any work when
    // the disk cannot hold them (a movie's frames wait as PNGs in a
    // directory beside it).
    let first = match is_movie {
        true => output.with_file_name("frame.png"),
        false => out::frame_path(output, seq.frames[0].0)?,
    };
    let size = voxless::projection::image_size(&desc.image)?;
    let flag = match seq.turntable {
        Some(_) => "--turntable",
        None => "--frames",
    };
    let disk = voxless::output::check_frames_disk(&first, seq.frames.len(), size, flag)?;
    if let (true, Some(note)) = (root, disk) {
        eprintln!("note: {note}");
    }
    let outputs: Vec<PathBuf> = if is_movie {
        out::check(&[output.to_path_buf()], OutputKind::Movie, desc, base, &[])?;
        voxless::movie::check_encoder(output)?;
        movie.settings.check()?;
        Vec::new()
    } else {
        let o = seq
            .frames
            .iter()
            .map(|&(t, _)| out::frame_path(output, t))
            .collect::<Result<Vec<_>>>()?;
        out::check(&o, OutputKind::Image, desc, base, &[])?;
        o
    };
    let data_frames = seq.data_frames();
    if radii.is_some() && data_frames.len() > 1 {
        anyhow::bail!("--save-radii writes one frame's radii: give --frame N instead of --frames");
    }
    let plan = placement.frame_plan(desc, base, &data_frames)?;
    // Whole frames per rank: each rank holds its frames in one process,
    // and a round renders as many frames as there are ranks.
    let (held, per_round) = match plan {
        FramePlan::ByFrame => (Placement::Process, placement.ranks()),
        FramePlan::BySpace => (placement, 1),
    };
    let t = Instant::now();
    let opened = held
        .open_series(desc, base, &data_frames)
        .map_err(anyhow::Error::from);
    let (mut scene, series) = render::agree(placement, opened)?;
    let mut showing = data_frames[0];
    render::report_placed(placement, &scene, t);
    render::save_radii(placement, radii, || scene.smoothing_lengths())?;
    render::check_work(placement, &scene, desc)?;
    let marks = render::annotations(&scene, desc, base, data_frames[0], marks)?;
    let n = seq.frames.len();
    let mut sink = if is_movie {
        let st = &scene.view().settings;
        let size = (st.width, st.height);
        let started = root
            .then(|| {
                let mut notes = Vec::new();
                let stamp = voxless::movie::stamp(desc, &seq.frames, size);
                let w = MovieWriter::start(
                    output,
                    n,
                    &stamp,
                    size,
                    &movie.settings,
                    movie.keep_frames,
                    &mut notes,
                );
                for note in notes {
                    eprintln!("note: {note}");
                }
                w
            })
            .transpose()
            .map_err(anyhow::Error::from);
        Sink::Movie(render::agree(placement, started)?)
    } else {
        Sink::Images(outputs)
    };
    // Frames already on disk (an interrupted movie): rank 0 knows, every
    // rank skips them.
    let on_disk: Vec<bool> = match &sink {
        Sink::Movie(Some(m)) => (0..n).map(|k| m.has(k)).collect(),
        _ => vec![false; n],
    };
    let on_disk = placement.broadcast_flags(on_disk)?;
    let todo: Vec<usize> = (0..n).filter(|&k| !on_disk[k]).collect();
    let progress = Progress::new(
        if is_movie {
            "rendering movie"
        } else {
            "rendering frames"
        },
        todo.len() as u64,
        root,
    );
    let t = Instant::now();
    let mut timings = Timings::default();
    let mut written = 0;
    for (round, chunk) in todo.chunks(per_round).enumerate() {
        let first = round * per_round;
        let mine = match plan {
            FramePlan::ByFrame => chunk
                .get(placement.rank())
                .map(|&k| (first + placement.rank(), k)),
            FramePlan::BySpace => Some((first, chunk[0])),
        };
        let rendered = match mine {
            Some((done, k)) => (|| {
                let (path_frame, f) = seq.frames[k];
                if f != showing {
                    scene.load_frame(&series, base, f)?;
                    showing = f;
                }
                let shown = seq.desc_at(desc, path_frame);
                if seq.moves() {
                    scene.reaim(&shown)?;
                }
                // Blue noise advances with the data frame (spatiotemporal),
                // so a path's frame equals a still of its camera; a
                // turntable's with the frame.
                scene.view_mut().settings.frame = match seq.turntable {
                    Some(_) => path_frame as u32,
                    None => f as u32,
                };
                let report = |d: u64, total: u64| progress.set_fraction(done as u64, d, total);
                let mut notes = Vec::new();
                let control = Control::new().with_progress(&report);
                let r = scene.render_on(device, &control, &mut timings, &mut notes)?;
                if !said && root {
                    for n in &notes {
                        progress.println(&format!("note: {n}"));
                    }
                    said = true;
                }
                r.map(|mut r| {
                    if let Err(e) = scene.check_rendered(&r) {
                        progress.println(&format!("note: frame {path_frame}: {e}"));
                    }
                    render::decorate(&mut r.image, &scene, &marks, &shown, base, f)?;
                    Ok(r.image)
                })
                .transpose()
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
        let background = scene.view().background;
        let done: Result<()> = images.into_iter().zip(chunk).try_for_each(|(image, &k)| {
            let Some(image) = image else { return Ok(()) };
            written = k + 1;
            put(&mut sink, k, &image, background, &on_disk)
        });
        render::agree(placement, done)?;
        progress.set((first + chunk.len()) as u64);
    }
    progress.finish();
    let finished = match sink {
        Sink::Movie(Some(mut m)) => (|| {
            // Frames on disk after the last rendered one.
            for k in written..n {
                m.put(k, None)?;
            }
            Ok(Some(m.finish()?))
        })(),
        _ => Ok(None),
    };
    let finished = render::agree(placement, finished)?;
    render::say(placement.memory_report(scene.counts())?);
    if root {
        let how = match (placement, plan) {
            (Placement::Process, _) => "",
            (_, FramePlan::ByFrame) => " (whole frames per rank)",
            (_, FramePlan::BySpace) => " (each frame decomposed over all ranks)",
        };
        let how = format!("{}{how}", render::on_ranks(placement));
        let what = match (seq.turntable, &seq.path) {
            (Some(_), _) => "turntable frames",
            (None, Some(_)) => "path frames",
            (None, None) => "frames",
        };
        let secs = t.elapsed().as_secs_f64();
        match finished {
            Some((frames, kept)) => {
                let fps = movie.settings.fps;
                eprintln!(
                    "rendered {} of {n} {what}{how} in {secs:.2}s → {} ({frames} frames, \
                     {:.2}s at {fps} fps){}",
                    todo.len(),
                    output.display(),
                    frames as f64 / fps,
                    kept.map(|d| format!("; frames kept in {}", d.display()))
                        .unwrap_or_default()
                );
            }
            None => {
                let first = out::frame_path(output, seq.frames[0].0)?;
                let last = out::frame_path(output, seq.frames[n - 1].0)?;
                let what = match seq.turntable {
                    Some(_) => {
                        let st = &scene.view().settings;
                        format!("a {n}-frame turntable ({}×{})", st.width, st.height)
                    }
                    None => format!("{n} {what}"),
                };
                eprintln!(
                    "rendered {what}{how} in {secs:.2}s → {} … {}",
                    first.display(),
                    last.display()
                );
            }
        }
    }
    Ok(())
}

/// Hands frame `k` to the sink, in order: a movie first takes the frames
/// on disk before it.
fn put(
    sink: &mut Sink,
    k: usize,
    image: &Image,
    background: [f32; 3],
    on_disk: &[bool],
) -> Result<()> {
    match sink {
        Sink::Images(outputs) => out::write_image(&outputs[k], image, background),
        Sink::Movie(None) => Ok(()),
        Sink::Movie(Some(m)) => {
            let from = (0..k).rev().take_while(|&j| on_disk[j]).last().unwrap_or(k);
            for j in from..k {
                m.put(j, None)?;
            }
            m.put(k, Some(&image.to_srgb8(background)))?;
            Ok(())
        }
    }
}
