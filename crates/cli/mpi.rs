//! `mpirun -n K voxless render|project|sample …` (the `mpi` feature): the
//! same flags as one process, translated onto the library's decomposed
//! scenes ([`voxless::parallel`]). Rank 0 prints and writes; every rank
//! renders its box. Other commands run on rank 0 alone.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Result, bail};
use voxless::output::OutputKind;
use voxless::parallel::{
    Comm, CommExt, DistributedScene, FramePlan, MpiComm, Purpose, available_bytes, frame_plan,
    peak_rss_bytes, ranks_on_this_node,
};
use voxless::render::colorbar::ColorbarSpec;
use voxless::{Control, Image, ProjectionDesc, ProjectionView, Scene, SceneDesc};

use crate::args::{SceneArgs, ViewArgs};
use crate::progress::Progress;
use crate::{Cli, Command, out};

/// Runs `cli` on every rank of the MPI job this process belongs to, then
/// exits: 0 when every rank succeeded, 1 otherwise (rank 0 says why).
pub fn main(cli: Cli) -> ! {
    let Some(comm) = MpiComm::init() else {
        eprintln!("error: MPI could not be initialised");
        std::process::exit(1);
    };
    let root = comm.is_root();
    let result = match cli.command {
        Command::Render {
            output,
            frames,
            frame,
            turntable,
            colorbar,
            data,
            kind,
            view,
        } => SceneArgs { data, kind, view }
            .scene()
            .and_then(|(desc, base)| {
                let f = frame.unwrap_or(0);
                match (frames, turntable) {
                    (_, Some(n)) => turntable_frames(&comm, &desc, &base, f, n, &output, colorbar),
                    (Some(range), None) => sequence(&comm, &desc, &base, &range, &output, colorbar),
                    (None, None) => render(&comm, &desc, &base, f, &output, colorbar),
                }
            }),
        Command::Project {
            axis,
            bounds,
            normal,
            north,
            center,
            width,
            depth,
            output,
            size,
            pixels,
            frame,
            data,
        } => SceneArgs {
            data,
            view: ViewArgs {
                size,
                ..Default::default()
            },
            ..Default::default()
        }
        .scene()
        .and_then(|(desc, base)| {
            // Ranks project their boxes through pixel centres; the exact
            // pixel-area projection is one process's (refused, not ignored).
            let area = Some(voxless::PixelsName::Area);
            if pixels == area || desc.tets.as_ref().and_then(|t| t.pixels) == area {
                bail!(
                    "pixels: the pixel-area projection (--pixels area, tets.pixels) runs in one \
                     process; under mpirun each rank projects its box through pixel centres \
                     (leave it out, or run voxless project without mpirun)"
                );
            }
            let f = frame.unwrap_or(0);
            let projection =
                crate::projection_desc(axis, bounds, normal, north, center, width, depth);
            project(&comm, &desc, &base, f, &projection, &output)
        }),
        Command::Sample {
            points,
            output,
            gradient,
            frame,
            data,
        } => SceneArgs {
            data,
            ..Default::default()
        }
        .scene()
        .and_then(|(desc, base)| {
            let f = frame.unwrap_or(0);
            sample(&comm, &desc, &base, f, &points, &output, gradient)
        }),
        other => {
            // Commands without data to share run once.
            if root {
                crate::run(Cli { command: other })
            } else {
                Ok(())
            }
        }
    };
    let code = match &result {
        Ok(()) => 0,
        Err(e) => {
            if root {
                eprintln!("error: {}", crate::describe(e));
            }
            1
        }
    };
    drop(comm);
    std::process::exit(code)
}

/// Every rank's outcome of a step that can fail on some ranks only (rank 0
/// writing a file, a rank's frame failing to load): an error anywhere is an
/// error everywhere, with its message.
fn agree<T>(comm: &MpiComm, local: Result<T>) -> Result<T> {
    let local = local.map_err(|e| crate::describe(&e));
    comm.agree(local)?.map_err(anyhow::Error::msg)
}

fn open(
    comm: &MpiComm,
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
    purpose: Purpose,
) -> Result<DistributedScene> {
    let t = Instant::now();
    let s = DistributedScene::open(comm, desc, base, frame, purpose)?;
    report_loaded(comm, &s, t);
    Ok(s)
}

/// Rank 0 prints the scene's notes and what was loaded.
fn report_loaded(comm: &MpiComm, s: &DistributedScene, t: Instant) {
    if !comm.is_root() {
        return;
    }
    for n in &s.notes {
        eprintln!("note: {n}");
    }
    let (lo, hi) = s.world_bounds();
    eprintln!(
        "loaded {} on {} ranks in {:.2}s: bounds [{:.4e}, {:.4e}, {:.4e}]..[{:.4e}, {:.4e}, \
         {:.4e}]",
        kind_name(s),
        comm.size(),
        t.elapsed().as_secs_f64(),
        lo[0],
        lo[1],
        lo[2],
        hi[0],
        hi[1],
        hi[2],
    );
}

fn kind_name(s: &DistributedScene) -> &'static str {
    match s.summary.kind {
        voxless::VolumeKind::Particles => "particles",
        voxless::VolumeKind::Amr => "AMR cells",
        voxless::VolumeKind::Tets => "phase-space tessellation",
        voxless::VolumeKind::Materials => "multi-material particles",
    }
}

/// Each rank's peak memory and what it held, printed by rank 0.
fn report_memory(comm: &MpiComm, s: Option<&DistributedScene>) -> Result<()> {
    let (read, held) = s.map_or((0, 0), |s| (s.counts.read, s.counts.held));
    let peak = peak_rss_bytes().unwrap_or(0);
    let all = comm.all_gather_f64(&[peak as f64, read as f64, held as f64])?;
    if comm.is_root() {
        let mib = |b: f64| b / (1u64 << 20) as f64;
        let list: Vec<String> = all
            .iter()
            .enumerate()
            .map(|(r, v)| {
                format!(
                    "rank {r}: {:.0} MiB (read {}, held {})",
                    mib(v[0]),
                    v[1],
                    v[2]
                )
            })
            .collect();
        eprintln!("peak memory per rank: {}", list.join("; "));
    }
    Ok(())
}

/// A render of the scene, with rank 0's share as progress.
fn render_image(comm: &MpiComm, s: &DistributedScene, what: &str) -> Result<Option<Image>> {
    let progress = comm.is_root().then(|| Progress::new(what, 1));
    let report = |d: u64, total: u64| {
        if let Some(p) = &progress {
            p.set_fraction(0, d, total);
        }
    };
    let (image, times) = s.render_timed(comm, &Control::new().with_progress(&report))?;
    if let Some(p) = &progress {
        p.finish();
    }
    let all = comm.all_gather_f64(&[times.render, times.composite])?;
    if comm.is_root() {
        let most = |k: usize| all.iter().map(|v| v[k]).fold(0.0, f64::max);
        let least = |k: usize| all.iter().map(|v| v[k]).fold(f64::INFINITY, f64::min);
        // A rank's compositing time includes waiting for slower renderers;
        // the least of them is the compositing itself.
        eprintln!(
            "ranks rendering their boxes: {:.3}–{:.3}s; compositing: {:.3}s",
            least(0),
            most(0),
            least(1)
        );
    }
    Ok(image)
}

/// The colour bar to draw, when asked for.
fn colorbar_of(s: &DistributedScene, on: bool) -> Option<ColorbarSpec> {
    on.then(|| s.colorbar())
}

/// Draws the colour bar (if any) into a rendered image (rank 0).
fn decorate(image: &mut Image, s: &DistributedScene, bar: Option<&ColorbarSpec>) {
    if let Some(spec) = bar
        && voxless::render::colorbar::draw_colorbar(image, &s.tf, spec).is_none()
    {
        eprintln!(
            "note: a {}×{} image is too small for a colour bar",
            image.width, image.height
        );
    }
}

/// Rank 0's outcome of a check the others cannot make, told to every rank.
fn check_field(comm: &MpiComm, s: &DistributedScene) -> Result<()> {
    agree(comm, s.check_field().map_err(anyhow::Error::from))
}

/// An error when rank 0's image shows nothing at all (never a silent
/// black image), as one process refuses it.
fn check_visible(image: &Image, s: &DistributedScene) -> Result<()> {
    let alpha = image.pixels.iter().fold(0f32, |m, p| m.max(p[3]));
    if alpha >= 0.5 / 255.0 {
        return Ok(());
    }
    let (lo, hi) = s.world_bounds();
    bail!(
        "image: the image would be empty: no ray meets a visible part of the field (the data's \
         bounds [{:.4e}, {:.4e}, {:.4e}]..[{:.4e}, {:.4e}, {:.4e}]); check --eye/--look-at, \
         --clip, --value-range, --opacity or --opacity-scale",
        lo[0],
        lo[1],
        lo[2],
        hi[0],
        hi[1],
        hi[2]
    )
}

fn render(
    comm: &MpiComm,
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
    output: &Path,
    colorbar: bool,
) -> Result<()> {
    out::check(
        std::slice::from_ref(&output.to_path_buf()),
        OutputKind::Image,
        desc,
        base,
        &[],
    )?;
    let s = open(comm, desc, base, frame, Purpose::Render)?;
    check_field(comm, &s)?;
    let t = Instant::now();
    let image = render_image(comm, &s, "rendering")?;
    let secs = t.elapsed().as_secs_f64();
    let bar = colorbar_of(&s, colorbar);
    agree(
        comm,
        image.map_or(Ok(()), |mut image| {
            check_visible(&image, &s)?;
            decorate(&mut image, &s, bar.as_ref());
            out::write_image(output, &image, s.background)
        }),
    )?;
    report_memory(comm, Some(&s))?;
    if comm.is_root() {
        let st = &s.settings;
        eprintln!(
            "rendered {}×{} at {} spp on {} ranks in {secs:.3}s → {}",
            st.width,
            st.height,
            st.spp,
            comm.size(),
            output.display()
        );
    }
    Ok(())
}

fn turntable_frames(
    comm: &MpiComm,
    desc: &SceneDesc,
    base: &Path,
    data_frame: usize,
    frames: u32,
    output: &Path,
    colorbar: bool,
) -> Result<()> {
    let outputs: Vec<PathBuf> = (0..frames as usize)
        .map(|k| out::frame_path(output, k))
        .collect::<Result<_>>()?;
    out::check(&outputs, OutputKind::Image, desc, base, &[])?;
    let mut s = open(comm, desc, base, data_frame, Purpose::Render)?;
    check_field(comm, &s)?;
    let bar = colorbar_of(&s, colorbar);
    let start = desc.camera.orbit.unwrap_or(0.0);
    let mut view = desc.clone();
    let t = Instant::now();
    for (k, path) in outputs.iter().enumerate() {
        view.camera.orbit = Some(start + 360.0 * k as f32 / frames as f32);
        s.reaim(&view)?;
        // Blue noise advances with the frame (spatiotemporal).
        s.settings.frame = k as u32;
        let image = render_image(comm, &s, &format!("turntable frame {k}"))?;
        agree(
            comm,
            image.map_or(Ok(()), |mut image| {
                decorate(&mut image, &s, bar.as_ref());
                out::write_image(path, &image, s.background)
            }),
        )?;
    }
    report_memory(comm, Some(&s))?;
    if comm.is_root() {
        eprintln!(
            "rendered a {frames}-frame turntable on {} ranks in {:.2}s → {} … {}",
            comm.size(),
            t.elapsed().as_secs_f64(),
            outputs[0].display(),
            outputs[outputs.len() - 1].display()
        );
    }
    Ok(())
}

/// Bytes of one frame's files (positions and per-particle arrays).
fn frame_bytes(desc: &SceneDesc, base: &Path, frame: usize) -> u64 {
    let Some(p) = &desc.particles else {
        return u64::MAX;
    };
    let files = [&p.file, &p.attribute, &p.radii, &p.weights];
    files
        .into_iter()
        .flatten()
        .map(|spec| {
            let path = if voxless::frames::is_sequence(spec, base) {
                voxless::frames::file_numbered(spec, base, frame).ok()
            } else {
                Some(base.join(spec))
            };
            path.and_then(|p| std::fs::metadata(p).ok())
                .map_or(0, |m| m.len())
        })
        .sum()
}

/// A time series under `mpirun`: the frames one process would pick
/// ([`crate::sequence::frames_and_outputs`]), rendered across the ranks.
fn sequence(
    comm: &MpiComm,
    desc: &SceneDesc,
    base: &Path,
    range: &str,
    output: &Path,
    colorbar: bool,
) -> Result<()> {
    let (frames, outputs) =
        crate::sequence::frames_and_outputs(desc, base, range, output, comm.is_root())?;
    let k = comm.size();
    let per_rank =
        available_bytes().map_or(0, |a| a / ranks_on_this_node().unwrap_or(k).max(1) as u64);
    // Every rank reads its own memory: agree on the smallest.
    let per_rank = comm.all_min(&[per_rank as f64])?[0] as u64;
    let plan = frame_plan(
        frames.len(),
        k,
        frame_bytes(desc, base, frames[0]),
        per_rank,
    );
    let t = Instant::now();
    match plan {
        FramePlan::ByFrame => by_frame(comm, desc, base, &frames, &outputs, colorbar)?,
        FramePlan::BySpace => by_space(comm, desc, base, &frames, &outputs, colorbar)?,
    }
    if comm.is_root() {
        let how = match plan {
            FramePlan::ByFrame => "whole frames per rank",
            FramePlan::BySpace => "each frame decomposed over all ranks",
        };
        eprintln!(
            "rendered {} frames on {k} ranks ({how}) in {:.2}s → {} … {}",
            frames.len(),
            t.elapsed().as_secs_f64(),
            outputs[0].display(),
            outputs[outputs.len() - 1].display()
        );
    }
    Ok(())
}

/// Frames `r, r + K, …` of the list on rank `r`, one process each, with
/// the series' defaults (every rank takes them as one process does); the
/// images go to rank 0, which writes them.
fn by_frame(
    comm: &MpiComm,
    desc: &SceneDesc,
    base: &Path,
    frames: &[usize],
    outputs: &[PathBuf],
    colorbar: bool,
) -> Result<()> {
    let k = comm.size();
    let t = Instant::now();
    let first = Scene::open_series(desc, base, frames).map_err(anyhow::Error::from);
    let (mut scene, series) = agree(comm, first)?;
    if comm.is_root() {
        crate::report_loaded(&scene, t);
    }
    let work = scene.check_work(desc).map_err(anyhow::Error::from);
    let note = agree(comm, work)?;
    if let (true, Some(note)) = (comm.is_root(), note) {
        eprintln!("note: {note}");
    }
    let bar = crate::view::colorbar(&scene, desc, colorbar);
    let progress = comm
        .is_root()
        .then(|| Progress::new("rendering frames", frames.len() as u64));
    for (round, chunk) in frames.chunks(k).enumerate() {
        let mine = chunk.get(comm.rank()).copied();
        let rendered: Result<Option<Image>> = match mine {
            Some(f) => (|| {
                if f != frames[0] {
                    scene.load_frame(&series, base, f)?;
                }
                scene.settings.frame = f as u32;
                let mut image = scene.render(&Control::new())?;
                crate::view::decorate(&mut image, &scene, bar.as_ref());
                Ok(Some(image))
            })(),
            None => Ok(None),
        };
        let rendered = agree(comm, rendered)?;
        // Every image to rank 0.
        let mut send = vec![Vec::new(); k];
        if let Some(img) = &rendered {
            send[0] = img
                .pixels
                .iter()
                .flatten()
                .flat_map(|v| v.to_le_bytes())
                .collect();
        }
        let got = comm.exchange(send)?;
        let written: Result<()> = if comm.is_root() {
            (|| {
                for (r, bytes) in got.iter().enumerate() {
                    if r >= chunk.len() {
                        continue;
                    }
                    let v: Vec<f32> = bytes
                        .chunks_exact(4)
                        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                        .collect();
                    let image = Image {
                        width: scene.settings.width,
                        height: scene.settings.height,
                        pixels: v
                            .chunks_exact(4)
                            .map(|c| [c[0], c[1], c[2], c[3]])
                            .collect(),
                    };
                    out::write_image(&outputs[round * k + r], &image, scene.background)?;
                }
                if let Some(p) = &progress {
                    p.set((round * k + chunk.len()) as u64);
                }
                Ok(())
            })()
        } else {
            Ok(())
        };
        agree(comm, written)?;
    }
    if let Some(p) = &progress {
        p.finish();
    }
    report_memory(comm, None)
}

/// Each frame in turn, decomposed over all ranks, with the series'
/// defaults (see [`DistributedScene::open_series`]).
fn by_space(
    comm: &MpiComm,
    desc: &SceneDesc,
    base: &Path,
    frames: &[usize],
    outputs: &[PathBuf],
    colorbar: bool,
) -> Result<()> {
    let t = Instant::now();
    let (mut s, series) = DistributedScene::open_series(comm, desc, base, frames)?;
    report_loaded(comm, &s, t);
    check_field(comm, &s)?;
    let bar = colorbar_of(&s, colorbar);
    for (k, (&f, path)) in frames.iter().zip(outputs).enumerate() {
        if k > 0 {
            s.load_frame(comm, &series, base, f)?;
        }
        // Blue noise advances with the frame, as for one process.
        s.settings.frame = f as u32;
        let image = render_image(comm, &s, &format!("frame {f}"))?;
        agree(
            comm,
            image.map_or(Ok(()), |mut image| {
                if let Err(e) = check_visible(&image, &s) {
                    eprintln!("note: frame {f}: {e}");
                }
                decorate(&mut image, &s, bar.as_ref());
                out::write_image(path, &image, s.background)
            }),
        )?;
    }
    report_memory(comm, Some(&s))
}

fn project(
    comm: &MpiComm,
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
    projection: &ProjectionDesc,
    output: &Path,
) -> Result<()> {
    out::check(
        std::slice::from_ref(&output.to_path_buf()),
        OutputKind::Map,
        desc,
        base,
        &[],
    )?;
    let s = open(comm, desc, base, frame, Purpose::Project)?;
    let view = ProjectionView::new(projection, &s.summary.bounds, &s.frame)?;
    let (w, h) = (s.settings.width, s.settings.height);
    let progress = comm.is_root().then(|| Progress::new("projecting", 1));
    let report = |d: u64, total: u64| {
        if let Some(p) = &progress {
            p.set_fraction(0, d, total);
        }
    };
    let t = Instant::now();
    let column = s.project_view(comm, &view, w, h, &Control::new().with_progress(&report))?;
    if let Some(p) = &progress {
        p.finish();
    }
    let secs = t.elapsed().as_secs_f64();
    agree(
        comm,
        column.map_or(Ok(()), |c| {
            out::write_gray(output, w, h, &c)?;
            let integral: f64 = c.iter().map(|&x| x as f64).sum::<f64>() * view.pixel_area(w, h);
            eprintln!(
                "projected {w}×{h} on {} ranks in {secs:.3}s → {} (Σ column × pixel area = \
                 {integral:.6e})",
                comm.size(),
                output.display()
            );
            Ok(())
        }),
    )?;
    report_memory(comm, Some(&s))
}

fn sample(
    comm: &MpiComm,
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
    points: &Path,
    output: &Path,
    gradient: bool,
) -> Result<()> {
    out::check(
        std::slice::from_ref(&output.to_path_buf()),
        OutputKind::Columns,
        desc,
        base,
        &[points.to_path_buf()],
    )?;
    let s = open(comm, desc, base, frame, Purpose::Render)?;
    // Rank 0 reads the points; the library hands them out.
    let read = if comm.is_root() {
        voxless::read_points(points).map_err(anyhow::Error::from)
    } else {
        Ok(Vec::new())
    };
    let pts = agree(comm, read)?;
    let local: Vec<voxless::Vec3> = pts.iter().map(|&p| s.frame.to_local(p)).collect();
    let cols = s.sample_columns(gradient);
    let t = Instant::now();
    let values = s.sample(comm, &local, gradient)?;
    agree(
        comm,
        values.map_or(Ok(()), |v| {
            voxless::io::write_npy_f32(output, &[pts.len(), cols.len()], &v)?;
            eprintln!(
                "sampled {} points on {} ranks in {:.2}s → {} (columns: {})",
                pts.len(),
                comm.size(),
                t.elapsed().as_secs_f64(),
                output.display(),
                cols.join(", ")
            );
            Ok(())
        }),
    )?;
    report_memory(comm, Some(&s))
}
