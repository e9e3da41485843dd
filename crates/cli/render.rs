//! The render commands' work over a scene however it is held (one
//! process, or the ranks of `mpirun`): one image, a turntable, and what
//! every command prints — notes, what was loaded, timings, memory.

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use voxless::annotate::{Annotations, Marks};
use voxless::core::Image;
use voxless::output::OutputKind;
use voxless::parallel::Timings;
use voxless::{Control, Placed, Placement, SceneDesc};

use crate::out;
use crate::progress::Progress;

/// A turntable's frame count: at least 1.
pub fn frame_count(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(0) => Err("a turntable needs at least 1 frame".into()),
        Ok(n) => Ok(n),
        Err(_) => Err(format!("'{s}' is not a whole number of frames")),
    }
}

/// Every rank's outcome of a step only some ranks take (rank 0 writing a
/// file): an error anywhere is an error everywhere, with its message.
pub fn agree<T>(placement: Placement, local: Result<T>) -> Result<T> {
    let local = local.map_err(|e| crate::describe(&e));
    placement.agree(local)?.map_err(anyhow::Error::msg)
}

/// " on K ranks" under `mpirun`, else nothing.
pub fn on_ranks(placement: Placement) -> String {
    match placement {
        Placement::Process => String::new(),
        Placement::Ranks(_) => format!(" on {} ranks", placement.ranks()),
    }
}

/// Prints (rank 0) `notes` and what was loaded: its kind and world bounds.
pub fn report_loaded(
    placement: Placement,
    notes: &[String],
    kind: &str,
    (lo, hi): ([f64; 3], [f64; 3]),
    t: Instant,
) {
    if !placement.is_root() {
        return;
    }
    for n in notes {
        eprintln!("note: {n}");
    }
    eprintln!(
        "loaded {kind}{} in {:.2}s: bounds [{:.4e}, {:.4e}, {:.4e}]..[{:.4e}, {:.4e}, {:.4e}]",
        on_ranks(placement),
        t.elapsed().as_secs_f64(),
        lo[0],
        lo[1],
        lo[2],
        hi[0],
        hi[1],
        hi[2],
    );
}

/// Opens frame `frame` of the scene and prints its notes and a summary.
pub fn open<'c>(
    placement: Placement<'c>,
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
) -> Result<Placed<'c>> {
    let t = Instant::now();
    let s = placement.open(desc, base, frame)?;
    report_placed(placement, &s, t);
    Ok(s)
}

/// [`report_loaded`] for a resolved scene, said once — by rank 0 of
/// `placement` — however the scene itself is held (time series under
/// `mpirun` may hold whole frames per rank).
pub fn report_placed(placement: Placement, s: &Placed, t: Instant) {
    if placement.is_root() {
        let notes = &s.view().notes;
        report_loaded(s.placement(), notes, s.kind().name(), s.world_bounds(), t);
    }
}

/// Prints (rank 0) a report a placement gives (timings, memory).
pub fn say(report: Option<String>) {
    if let Some(r) = report {
        eprintln!("{r}");
    }
}

/// Checks the render's work, rank 0 of `placement` printing a note if the
/// step was raised (however the scene itself is held).
pub fn check_work(placement: Placement, s: &Placed, desc: &SceneDesc) -> Result<()> {
    if let (true, Some(note)) = (placement.is_root(), s.check_work(desc)?) {
        eprintln!("note: {note}");
    }
    Ok(())
}

/// The annotations `marks` asks for on frame `frame` of the scene.
pub fn annotations(
    s: &Placed,
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
    marks: Marks,
) -> Result<Annotations> {
    Ok(Annotations::new(
        marks,
        s.colorbar(desc),
        desc,
        base,
        frame,
    )?)
}

/// Draws the annotations into a rendered image of data frame `frame` seen
/// as `desc` describes it, with a note for what does not fit.
pub fn decorate(
    image: &mut Image,
    s: &Placed,
    a: &Annotations,
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
) -> Result<()> {
    for note in a.draw(image, s.view(), s.frame(), desc, base, frame)? {
        eprintln!("note: {note}");
    }
    Ok(())
}

/// Renders frame `frame` of the scene to `output` (checked before loading),
/// writing the particles' radii to `radii` if given.
#[allow(clippy::too_many_arguments)]
pub fn render_one(
    placement: Placement,
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
    output: &Path,
    radii: Option<&Path>,
    marks: Marks,
    device: &voxless::device::Device,
) -> Result<()> {
    out::check(&[output.to_path_buf()], OutputKind::Image, desc, base, &[])?;
    check_radii_output(radii, desc, base)?;
    let s = open(placement, desc, base, frame)?;
    save_radii(placement, radii, || s.smoothing_lengths())?;
    let a = annotations(&s, desc, base, frame, marks)?;
    render_to(&s, desc, output, &a, base, frame, device)
}

/// Refuses a radii output that would overwrite an input.
pub fn check_radii_output(radii: Option<&Path>, desc: &SceneDesc, base: &Path) -> Result<()> {
    match radii {
        Some(p) => out::check(&[p.to_path_buf()], OutputKind::Columns, desc, base, &[]),
        None => Ok(()),
    }
}

/// Writes the particles' radii (rank 0 of `placement`) to `path`, if given.
pub fn save_radii(
    placement: Placement,
    path: Option<&Path>,
    radii: impl FnOnce() -> Result<Option<Vec<f32>>, voxless::ParallelError>,
) -> Result<()> {
    let Some(path) = path else {
        return Ok(());
    };
    let written = radii()?.map_or(Ok(()), |r| {
        voxless::io::write_npy_f32(path, &[r.len()], &r)?;
        eprintln!(
            "wrote the radii of {} particles → {}",
            r.len(),
            path.display()
        );
        Ok(())
    });
    agree(placement, written)
}

/// Checks the scene's render work, renders it with a progress bar, checks
/// the image shows something, and writes `output` (rank 0).
pub fn render_to(
    s: &Placed,
    desc: &SceneDesc,
    output: &Path,
    a: &Annotations,
    base: &Path,
    frame: usize,
    device: &voxless::device::Device,
) -> Result<()> {
    let placement = s.placement();
    check_work(placement, s, desc)?;
    let progress = Progress::new("rendering", 1, placement.is_root());
    let report = |d: u64, total: u64| progress.set_fraction(0, d, total);
    let t = Instant::now();
    let mut timings = Timings::default();
    let mut notes = Vec::new();
    let control = Control::new().with_progress(&report);
    let rendered = s.render_on(device, &control, &mut timings, &mut notes)?;
    progress.finish();
    if placement.is_root() {
        for n in &notes {
            eprintln!("note: {n}");
        }
    }
    let secs = t.elapsed().as_secs_f64();
    say(placement.timings_report(timings)?);
    let written = rendered.map_or(Ok(()), |mut r| {
        s.check_rendered(&r)?;
        decorate(&mut r.image, s, a, desc, base, frame)?;
        out::write_image(output, &r.image, s.view().background)
    });
    agree(placement, written)?;
    say(placement.memory_report(s.counts())?);
    if placement.is_root() {
        let st = &s.view().settings;
        eprintln!(
            "rendered {}×{} at {} spp{}{} in {secs:.3}s → {}",
            st.width,
            st.height,
            st.spp,
            on_ranks(placement),
            match device.gpu_bytes().filter(|_| device.last_on_gpu()) {
                Some(b) => format!(
                    " on the {} ({:.1} MiB of buffers)",
                    device.name(),
                    b as f64 / (1u64 << 20) as f64
                ),
                None => String::new(),
            },
            output.display()
        );
    }
    Ok(())
}
