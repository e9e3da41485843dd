//! `voxless`: render particles, AMR cells and tessellations from the
//! terminal. A thin front-end over the `voxless` library: parse flags into a
//! scene description, open the scene, call render / project / sample, write
//! files, show progress.

mod args;
mod info;
#[cfg(feature = "mpi")]
mod mpi;
mod out;
mod progress;
mod render;
mod sequence;
mod slice;

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Result;
use clap::{Parser, Subcommand, ValueEnum};
use voxless::annotate::Marks;
use voxless::output::OutputKind;
use voxless::{Control, ParticlesDesc, Placement, ProjectionDesc, Purpose};

/// Large arrays on huge pages where the kernel offers them (see the
/// library's `huge_pages`).
#[global_allocator]
static ALLOC: voxless::huge_pages::HugePages = voxless::huge_pages::HugePages;

use args::{DataArgs, DeviceArgs, KindArgs, PlaneArgs, SceneArgs, ViewArgs};
use progress::Progress;

#[derive(Parser)]
#[command(
    name = "voxless",
    version,
    about = "Render particles, AMR cells and phase-space tessellations without resampling them onto a grid"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

// Parsed once per run: the size of the largest variant does not matter.
#[allow(clippy::large_enum_variant)]
#[derive(Subcommand)]
enum Command {
    /// Render the built-in demo particles (a spiral galaxy) to an image.
    Demo {
        /// Output image: .png, .jpg/.jpeg, or .exr (linear float RGBA).
        #[arg(short, long, default_value = "demo.png")]
        output: PathBuf,
        /// Draw a labelled colour bar at the right edge of the image.
        #[arg(long)]
        colorbar: bool,
        #[command(flatten)]
        view: ViewArgs,
        #[command(flatten)]
        device: DeviceArgs,
    },
    /// Render a scene (TOML file and/or flags) to an image.
    Render {
        /// Output image: .png, .jpg/.jpeg, or .exr (linear float RGBA). With
        /// --frames or --turntable, `out.png` becomes out_0000.png, … named
        /// by the frame numbers (or give a printf pattern such as
        /// frame_%03d.png), or a movie: .mp4, .webm or .gif (encoded by
        /// ffmpeg as the frames are rendered; an interrupted movie resumes
        /// from its frames on disk).
        #[arg(short, long, default_value = "out.png")]
        output: PathBuf,
        /// Render the frames numbered A through B of a time series (a
        /// multi-frame file such as a LAMMPS dump or XYZ, frames 0, 1, …; or
        /// files numbered by the last number in their names: a pattern like
        /// step_%04d.npy, a glob, or a directory, e.g. of PySPH .hdf5
        /// outputs). Value range, opacity and framing hold over the series.
        #[arg(long, value_name = "A..B", conflicts_with = "frame")]
        frames: Option<String>,
        /// Render only frame N of a time series (default 0).
        #[arg(long, value_name = "N")]
        frame: Option<usize>,
        /// Render N frames of a full 360° orbit about the look-at point
        /// (out.png → out_0000.png … ), starting from the scene's camera.
        #[arg(long, value_name = "N", conflicts_with = "frames", value_parser = render::frame_count)]
        turntable: Option<u32>,
        /// Draw a labelled colour bar at the right edge of the image.
        #[arg(long)]
        colorbar: bool,
        /// Draw a scale bar in world units (the file's length unit when it
        /// states one) at the depth of the look-at point, bottom left.
        #[arg(long)]
        scale_bar: bool,
        /// Label the image with the frame's time (t = …), redshift (z = …)
        /// or LAMMPS step, top left.
        #[arg(long)]
        time_label: bool,
        /// Movies: frames per second.
        #[arg(
            long,
            default_value_t = 24.0,
            help_heading = "Movies (-o .mp4, .webm, .gif)"
        )]
        fps: f64,
        /// Movies: 1–100 (H.264 CRF 18 at 80; GIFs ignore it).
        #[arg(
            long,
            default_value_t = 80,
            help_heading = "Movies (-o .mp4, .webm, .gif)"
        )]
        quality: u32,
        /// Movies: keep the frame PNGs (NAME.frames/) after encoding.
        #[arg(long, help_heading = "Movies (-o .mp4, .webm, .gif)")]
        keep_frames: bool,
        #[command(flatten)]
        data: DataArgs,
        #[command(flatten)]
        kind: KindArgs,
        #[command(flatten)]
        view: ViewArgs,
        #[command(flatten)]
        device: DeviceArgs,
    },
    /// Evaluate the reconstructed fields at points: writes float32 N×k .npy,
    /// columns Φ, then Θ (with an attribute), then ∂Φ/∂x, ∂Φ/∂y, ∂Φ/∂z (with --gradient).
    Sample {
        /// Points: .npy N×3 (float32 or float64) or CSV with x, y, z columns.
        #[arg(long)]
        points: PathBuf,
        /// Output .npy.
        #[arg(short, long)]
        output: PathBuf,
        /// Also write the analytic gradient of Φ.
        #[arg(long)]
        gradient: bool,
        /// Frame N of a time series (default 0).
        #[arg(long, value_name = "N")]
        frame: Option<usize>,
        #[command(flatten)]
        data: DataArgs,
    },
    /// Column density ∫Φ dt per pixel, orthographic down an axis (or along
    /// --normal), covering the data bounds: float32 H×W .npy (or .exr), row 0
    /// at the top.
    Project {
        #[command(flatten)]
        plane: PlaneArgs,
        /// Integrate only over a slab this thick centred on the image plane
        /// (default: the whole line).
        #[arg(long)]
        depth: Option<f64>,
        /// Output .npy (float32 H×W) or .exr (one channel "Y").
        #[arg(short, long)]
        output: PathBuf,
        /// Particles and phase-space tessellations: how each pixel is
        /// integrated — centre (default): the column along the line through
        /// the pixel's centre; area: the column averaged over the pixel's
        /// square, so Σ column × pixel area is the mass in view at every
        /// resolution, however small a kernel is against a pixel (one
        /// process; not with --depth; tessellations take 4–6× the time).
        /// Scene: particles.pixels, tets.pixels.
        #[arg(long, value_enum)]
        pixels: Option<voxless::PixelsName>,
        /// Frame N of a time series (default 0).
        #[arg(long, value_name = "N")]
        frame: Option<usize>,
        #[command(flatten)]
        data: DataArgs,
        #[command(flatten)]
        device: DeviceArgs,
    },
    /// The reconstructed field on a plane: one value per pixel, exactly what
    /// `sample` gives at the pixel centres (row 0 at the top; for --axis z
    /// the image's right is +x and its up +y). Geometry as `project`'s.
    /// Writes raw values (.npy H×W float32, .exr, .fits with world
    /// coordinates) or a colormapped picture (.png).
    Slice {
        #[command(flatten)]
        plane: PlaneArgs,
        /// What to show: a column `sample` writes — density (default),
        /// attribute (or the attribute's name), streams (tessellations), an
        /// AMR field by name (default: --field, else the first).
        #[arg(long, value_name = "NAME")]
        quantity: Option<String>,
        /// How each pixel takes its value.
        #[arg(long, value_enum)]
        pixels: Option<SlicePixelsArg>,
        /// Output: .npy (float32 H×W), .exr, .fits (raw values) or .png
        /// (colormapped).
        #[arg(short, long)]
        output: PathBuf,
        /// Frame N of a time series (default 0).
        #[arg(long, value_name = "N")]
        frame: Option<usize>,
        /// .png: the colormap (see `voxless colormaps`; default viridis).
        #[arg(long, help_heading = "Picture (.png)")]
        colormap: Option<String>,
        /// .png: log scale (default: when no value is negative and the
        /// largest is over 100× the median, as in clumpy fields).
        #[arg(long, conflicts_with = "linear", help_heading = "Picture (.png)")]
        log: bool,
        /// .png: linear scale.
        #[arg(long, help_heading = "Picture (.png)")]
        linear: bool,
        /// .png: the values mapped to the colormap's ends (default: the
        /// slice's range).
        #[arg(long, num_args = 2, value_names = ["LO", "HI"], allow_negative_numbers = true, help_heading = "Picture (.png)")]
        value_range: Option<Vec<f32>>,
        /// .png: draw a labelled colour bar.
        #[arg(long, help_heading = "Picture (.png)")]
        colorbar: bool,
        /// .png: draw a scale bar in world units.
        #[arg(long, help_heading = "Picture (.png)")]
        scale_bar: bool,
        #[command(flatten)]
        data: DataArgs,
    },
    /// Explore a scene in a browser: prints a URL and serves a page that
    /// renders the data progressively on this machine (orbit, pan, zoom,
    /// transfer function, time series, save image / scene). Takes the same
    /// scene file and flags as `render`.
    Serve {
        /// TCP port to listen on.
        #[arg(long, default_value_t = 8080, help_heading = "Server")]
        port: u16,
        /// Address to listen on. The default serves this machine only; any
        /// other address (e.g. 0.0.0.0) requires the random access token
        /// printed in the URL on every request.
        #[arg(long, default_value = "127.0.0.1", help_heading = "Server")]
        host: String,
        #[command(flatten)]
        data: DataArgs,
        #[command(flatten)]
        kind: KindArgs,
        #[command(flatten)]
        view: ViewArgs,
        #[command(flatten)]
        device: DeviceArgs,
    },
    /// Print what a data file holds: particle count, frames and their times,
    /// columns with ranges and bounds; .npy shape and range; AMR cells per
    /// level and fields; .vtu meshes; HDF5 layouts and contents.
    Info(info::InfoArgs),
    /// List the built-in colormaps.
    Colormaps,
}

/// How a slice's pixel takes its value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum SlicePixelsArg {
    /// The value at the pixel's centre: exactly `sample`'s (default).
    #[value(alias = "center")]
    Centre,
    /// The mean over the pixel's square by a 4×4 Gauss–Legendre rule (16
    /// samples a pixel).
    Area,
}

fn main() {
    let cli = Cli::parse();
    quiet_wayland();
    // Under an MPI launcher, every rank runs the command together.
    #[cfg(feature = "mpi")]
    if voxless::parallel::MpiComm::launched() {
        mpi::main(cli);
    }
    if let Err(e) = run(cli, Placement::Process) {
        eprintln!("error: {}", describe(&e));
        std::process::exit(1);
    }
}

/// Mesa's Vulkan drivers (lavapipe among them) try to reach a Wayland
/// display when a Vulkan instance is made, and libwayland prints "error:
/// XDG_RUNTIME_DIR is invalid or not set" on headless machines — where a
/// GPU render is most likely to run. Pointing the variable at the temporary
/// directory (only when it is unset) lets the attempt fail quietly.
fn quiet_wayland() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // SAFETY: called first thing in `main`, before any thread starts.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
}

/// The error and its causes, skipping a cause whose text the message above
/// it already contains (library errors often embed their source).
fn describe(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let c = cause.to_string();
        if !text.contains(&c) {
            if !text.is_empty() {
                text.push_str(": ");
            }
            text.push_str(&c);
        }
    }
    text
}

/// Runs a command with its data held as `placement` says (one process,
/// or the ranks of `mpirun`: every rank runs the data commands together;
/// the others run on rank 0 alone).
fn run(cli: Cli, placement: Placement) -> Result<()> {
    let root = placement.is_root();
    match cli.command {
        Command::Render {
            output,
            frames,
            frame,
            turntable,
            colorbar,
            scale_bar,
            time_label,
            fps,
            quality,
            keep_frames,
            data,
            kind,
            view,
            device,
        } => {
            let device = device.open(root)?;
            let radii = data.save_radii.clone();
            let radii = radii.as_deref();
            let placed_camera = view.eye.is_some() || view.look_at.is_some();
            let (mut desc, base) = SceneArgs { data, kind, view }.scene()?;
            // Keyframe times count in the movie's frame rate unless the
            // scene gives its path's.
            desc.camera.fps.get_or_insert(fps);
            let movie = sequence::MovieArgs {
                settings: voxless::movie::MovieSettings { fps, quality },
                keep_frames,
            };
            let is_movie = voxless::movie::MovieFormat::of(&output).is_some();
            let marks = Marks {
                colorbar,
                scale_bar,
                label: time_label,
            };
            let frames = match (turntable, &frames) {
                (Some(n), _) => Some(sequence::Frames::Turntable {
                    n: n as usize,
                    frame: frame.unwrap_or(0),
                }),
                (None, Some(range)) => Some(sequence::Frames::Range(range)),
                (None, None) => None,
            };
            if let Some(frames) = frames {
                return sequence::render(
                    placement, &desc, &base, frames, &output, marks, movie, radii, &device,
                );
            }
            if is_movie {
                anyhow::bail!(
                    "-o {}: a movie needs frames: give --frames A..B (a time series or the \
                     scene's camera path) or --turntable N",
                    output.display()
                );
            }
            if let Some(path) = voxless::camera_path::CameraPath::new(&desc.camera)? {
                let (first, _) = path.span();
                let note = if placed_camera {
                    "--eye/--look-at place this image's camera, not the scene's camera path"
                        .to_string()
                } else {
                    desc = path.apply(&desc, first);
                    format!(
                        "the scene has a camera path: this image is its first keyframe (frame \
                         {first}); give --frames A..B to render the path"
                    )
                };
                if placement.is_root() {
                    eprintln!("note: {note}");
                }
            }
            let f = frame.unwrap_or(0);
            render::render_one(placement, &desc, &base, f, &output, radii, marks, &device)
        }
        Command::Sample {
            points,
            output,
            gradient,
            frame,
            data,
        } => {
            let radii = data.save_radii.clone();
            let args = SceneArgs {
                data,
                ..Default::default()
            };
            let (desc, base) = args.scene()?;
            out::check(
                std::slice::from_ref(&output),
                OutputKind::Columns,
                &desc,
                &base,
                std::slice::from_ref(&points),
            )?;
            render::check_radii_output(radii.as_deref(), &desc, &base)?;
            let s = render::open(placement, &desc, &base, frame.unwrap_or(0))?;
            render::save_radii(placement, radii.as_deref(), || s.smoothing_lengths())?;
            // Rank 0 reads the points; the library hands them out.
            let read = if root {
                voxless::read_points(&points).map_err(anyhow::Error::from)
            } else {
                Ok(Vec::new())
            };
            let pts = render::agree(placement, read)?;
            s.fields().check_gradient(gradient)?;
            let cols = s.fields().columns(gradient);
            let t = Instant::now();
            let values = s.sample(&pts, gradient)?;
            let written = values.map_or(Ok(()), |v| {
                voxless::io::write_npy_f32(&output, &[pts.len(), cols.len()], &v)?;
                eprintln!(
                    "sampled {} points{} in {:.2}s → {} (columns: {})",
                    pts.len(),
                    render::on_ranks(placement),
                    t.elapsed().as_secs_f64(),
                    output.display(),
                    cols.join(", ")
                );
                Ok(())
            });
            render::agree(placement, written)?;
            render::say(placement.memory_report(s.counts())?);
            Ok(())
        }
        Command::Project {
            plane,
            depth,
            output,
            pixels,
            frame,
            data,
            device,
        } => {
            let device = device.open(root)?;
            let radii = data.save_radii.clone();
            let args = SceneArgs {
                data,
                view: ViewArgs {
                    size: plane.size.clone(),
                    ..Default::default()
                },
                ..Default::default()
            };
            let (mut desc, base) = args.scene()?;
            let projection = plane.desc(depth);
            voxless::set_projection_pixels(&mut desc, pixels, &projection)?;
            out::check(
                std::slice::from_ref(&output),
                OutputKind::Map,
                &desc,
                &base,
                &[],
            )?;
            render::check_radii_output(radii.as_deref(), &desc, &base)?;
            // A projection needs the data and the image size, not a render's
            // defaults (camera, transfer function, and the probe of the
            // field they are chosen from).
            let size = voxless::projection::image_size(&desc.image)?;
            project(
                placement,
                &desc,
                &base,
                frame.unwrap_or(0),
                size,
                &projection,
                &output,
                radii.as_deref(),
                &device,
            )
        }
        Command::Slice {
            plane,
            quantity,
            pixels,
            output,
            frame,
            colormap,
            log,
            linear,
            value_range,
            colorbar,
            scale_bar,
            data,
        } => {
            if data.save_radii.is_some() {
                anyhow::bail!("--save-radii is written by render, project and sample, not slice");
            }
            let picked_colormap = colormap.is_some();
            let args = SceneArgs {
                data,
                view: ViewArgs {
                    size: plane.size.clone(),
                    colormap,
                    ..Default::default()
                },
                ..Default::default()
            };
            let (desc, base) = args.scene()?;
            let slice = voxless::slice::SliceDesc {
                plane: plane.desc(None),
                quantity,
                pixels: match pixels {
                    Some(SlicePixelsArg::Area) => voxless::slice::SlicePixels::Area,
                    _ => voxless::slice::SlicePixels::Centre,
                },
            };
            let look = voxless::slice::SliceLook {
                log: (log || linear).then_some(log),
                range: value_range.map(|r| [r[0], r[1]]),
                colorbar,
            };
            let picture = slice::Picture {
                look,
                scale_bar,
                colormap: picked_colormap,
            };
            slice::run(
                placement,
                &desc,
                &base,
                frame.unwrap_or(0),
                &slice,
                &picture,
                &output,
            )
        }
        // Commands without data to share run on rank 0.
        _ if !root => Ok(()),
        Command::Demo {
            output,
            colorbar,
            view,
            device,
        } => {
            let device = device.open(true)?;
            let args = SceneArgs {
                view,
                ..Default::default()
            };
            let (mut desc, base) = args.scene()?;
            desc.particles = Some(ParticlesDesc {
                demo: Some(true),
                attribute_range: Some([0.0, 1.0]),
                ..Default::default()
            });
            // The demo's look: a galaxy seen from above at an angle, shaded.
            desc.image.width.get_or_insert(800);
            desc.image.height.get_or_insert(450);
            desc.render.sampling_rate.get_or_insert(0.5);
            if desc.transfer.colormap_file.is_none() {
                desc.transfer
                    .colormap
                    .get_or_insert_with(|| "inferno".into());
            }
            desc.camera.eye.get_or_insert([0.0, 1.3, 1.85]);
            desc.render.opacity_scale.get_or_insert(10.0);
            desc.camera.look_at.get_or_insert([0.0, -0.1, 0.0]);
            desc.light.get_or_insert_with(Default::default);
            let marks = Marks {
                colorbar,
                ..Default::default()
            };
            render::render_one(
                Placement::Process,
                &desc,
                &base,
                0,
                &output,
                None,
                marks,
                &device,
            )
        }
        Command::Serve {
            port,
            host,
            data,
            kind,
            view,
            device,
        } => serve(&SceneArgs { data, kind, view }, port, host, &device),
        Command::Colormaps => {
            for name in voxless::transfer::COLORMAP_NAMES {
                println!("{name}");
            }
            Ok(())
        }
        Command::Info(args) => info::run(&args),
    }
}

#[allow(clippy::too_many_arguments)]
/// Projects frame `frame` of the data `desc` names and writes the column
/// densities (rank 0).
fn project(
    placement: Placement,
    desc: &voxless::SceneDesc,
    base: &Path,
    frame: usize,
    (w, h): (u32, u32),
    projection: &ProjectionDesc,
    output: &Path,
    radii: Option<&Path>,
    device: &voxless::device::Device,
) -> Result<()> {
    let t = Instant::now();
    let on = |gpu: bool| {
        if gpu {
            format!(" on the {}", device.name())
        } else {
            String::new()
        }
    };
    // Nothing else asked of the particles: stream them (under mpirun each
    // rank streams a share of the file, and the images add up on rank 0).
    if radii.is_none() {
        let progress = Progress::new("projecting (streamed)", 1, placement.is_root());
        let report = |d: u64, total: u64| progress.set_fraction(0, d, total);
        let control = Control::new().with_progress(&report);
        let streamed = match placement {
            Placement::Process => voxless::stream::project_on(
                desc,
                base,
                frame,
                projection,
                (w, h),
                device,
                &control,
            )?,
            Placement::Ranks(c) => {
                placement.check_device(device)?;
                voxless::stream::project_ranks(c, desc, base, frame, projection, (w, h), &control)?
            }
        };
        if let Some(s) = streamed {
            progress.finish();
            let written = if placement.is_root() {
                for n in &s.notes {
                    eprintln!("note: {n}");
                }
                write_streamed(placement, desc, base, frame, (w, h), output, device, &s, t)
            } else {
                Ok(())
            };
            render::agree(placement, written)?;
            let counts = voxless::parallel::PartCounts {
                read: s.read as u64,
                held: 0,
            };
            render::say(placement.memory_report(Some(counts))?);
            return Ok(());
        }
    }
    let data = placement.load(desc, base, frame, Purpose::Project)?;
    let kind = data.kind().name();
    render::report_loaded(placement, data.notes(), kind, data.world_bounds(), t);
    render::save_radii(placement, radii, || data.smoothing_lengths())?;
    let progress = Progress::new("projecting", 1, placement.is_root());
    let report = |d: u64, total: u64| progress.set_fraction(0, d, total);
    let t = Instant::now();
    let control = Control::new().with_progress(&report);
    let mut notes = Vec::new();
    let (view, column) = data.project_on(device, projection, w, h, &control, &mut notes)?;
    progress.finish();
    if placement.is_root() {
        for n in &notes {
            eprintln!("note: {n}");
        }
    }
    let written = column.map_or(Ok(()), |column| {
        write_map(output, desc, base, frame, &view, (w, h), &column)?;
        let integral = view.integral(&column, w, h);
        let exact = data.total_mass();
        let mass = exact
            .map(|m| format!(", exact ∫ field dV = {m:.6e}"))
            .unwrap_or_default();
        eprintln!(
            "projected {w}×{h}{}{} in {:.3}s → {} (Σ column × pixel area = {integral:.6e}{mass})",
            render::on_ranks(placement),
            on(device.last_on_gpu()),
            t.elapsed().as_secs_f64(),
            output.display()
        );
        if let Some(n) = exact.and_then(|m| voxless::projection::mass_note(integral, m, desc)) {
            eprintln!("note: {n}");
        }
        Ok(())
    });
    render::agree(placement, written)?;
    render::say(placement.memory_report(data.counts())?);
    Ok(())
}

/// Writes a streamed projection (rank 0) and says what it summed.
#[allow(clippy::too_many_arguments)]
fn write_streamed(
    placement: Placement,
    desc: &voxless::SceneDesc,
    base: &Path,
    frame: usize,
    (w, h): (u32, u32),
    output: &Path,
    device: &voxless::device::Device,
    s: &voxless::stream::Streamed,
    t: Instant,
) -> Result<()> {
    write_map(output, desc, base, frame, &s.view, (w, h), &s.column)?;
    let integral = s.view.integral(&s.column, w, h);
    // A streamed projection splats: on the GPU whenever it is open (one
    // process only).
    let on = if device.is_gpu() && matches!(placement, Placement::Process) {
        format!(" on the {}", device.name())
    } else {
        render::on_ranks(placement)
    };
    eprintln!(
        "projected {w}×{h} from {} particles streamed in {} chunk{}{on} in {:.3}s → {} \
         (Σ column × pixel area = {integral:.6e}, exact ∫ field dV = {:.6e})",
        s.particles,
        s.chunks,
        if s.chunks == 1 { "" } else { "s" },
        t.elapsed().as_secs_f64(),
        output.display(),
        s.mass
    );
    if let Some(n) = voxless::projection::mass_note(integral, s.mass, desc) {
        eprintln!("note: {n}");
    }
    Ok(())
}

/// Writes a projection's column densities: a FITS map with its world
/// coordinates, unit and epoch, or a raw array or image.
fn write_map(
    output: &Path,
    desc: &voxless::SceneDesc,
    base: &Path,
    frame: usize,
    view: &voxless::ProjectionView,
    (w, h): (u32, u32),
    column: &[f32],
) -> Result<()> {
    if out::is_fits(output) {
        let meta = voxless::map_fits::map_meta(desc, base, frame)?;
        let line: Vec<String> = std::env::args().collect();
        voxless::map_fits::write_projection_fits(
            output,
            view,
            (w, h),
            column,
            &meta,
            &[format!("voxless: {}", line.join(" "))],
        )?;
    } else {
        out::write_gray(output, w, h, column)?;
    }
    Ok(())
}

/// `voxless serve`: load the scene (errors before listening), print the URL,
/// serve until Ctrl-C.
fn serve(scene: &SceneArgs, port: u16, host: String, device: &DeviceArgs) -> Result<()> {
    if scene.data.save_radii.is_some() {
        anyhow::bail!(
            "--save-radii is written by render, project and sample; serve shows the data only"
        );
    }
    let (desc, base) = scene.scene()?;
    let t = Instant::now();
    let prepared = voxless_serve::prepare(desc, base)?;
    for n in &prepared.notes {
        eprintln!("note: {n}");
    }
    eprintln!(
        "loaded {} ({} frame{}) in {:.2}s",
        prepared.kind,
        prepared.frames,
        if prepared.frames == 1 { "" } else { "s" },
        t.elapsed().as_secs_f64()
    );
    let device = device.open(true)?;
    if device.is_gpu() {
        eprintln!("rendering full-resolution passes on the {}", device.name());
    }
    let options = voxless_serve::Options {
        host,
        port,
        token: None,
        device,
    };
    voxless_serve::run(prepared, &options, |bound| {
        if bound.token.is_some() {
            eprintln!(
                "note: listening on {} beyond loopback: every request must carry the access \
                 token in this URL",
                bound.addr
            );
        }
        println!("voxless serve: open {}", bound.url());
        eprintln!("press Ctrl-C to stop");
    })?;
    Ok(())
}
