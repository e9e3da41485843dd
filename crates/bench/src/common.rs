//! What every benchmark shares: timing (median of repeats), the table
//! header, image comparison, the synthetic particle sets and the dam-break
//! reader, and rendering an already prepared volume.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use voxless::formats::{ParticleFormat, TableOptions, read_table};
use voxless_core::{Camera, Control, Image, Vec3, Volume};
use voxless_particles::{Kernel, ParticleData};
use voxless_render::{Job, RenderSettings};
use voxless_transfer::TransferFunction;

/// Renders a volume that is already prepared (a context the caller built
/// and timed apart, or a benchmark's wrapper) with the shared integrator:
/// what `voxless_render::render` does after its `prepare` step.
pub fn render_prepared<V: Volume>(
    volume: &V,
    camera: &Camera,
    tf: &TransferFunction,
    settings: &RenderSettings,
) -> Result<Image> {
    let job = Job::new(volume, camera, tf, settings);
    let mut film = job.film();
    job.run(&mut film, &Control::new())?;
    Ok(film.resolve())
}

/// Max and mean absolute difference over all pixels and RGBA channels.
pub fn image_diff(a: &Image, b: &Image) -> (f32, f64) {
    let mut max = 0.0f32;
    let mut sum = 0.0f64;
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        for c in 0..4 {
            let d = (p[c] - q[c]).abs();
            max = max.max(d);
            sum += d as f64;
        }
    }
    (max, sum / (4.0 * a.pixels.len().max(1) as f64))
}

pub fn save_png(path: &Path, img: &Image) -> Result<()> {
    voxless_io::write_png_rgb8(path, img.width, img.height, &img.to_srgb8([0.0; 3]))?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

// ---------------------------------------------------------------- data

/// An SPH snapshot: a directory in the `.npy` layout (`positions.npy`,
/// `h.npy`, `mass.npy`, `speed.npy`) or any particle file the library reads
/// (e.g. a PySPH `.hdf5` frame with the `hdf5` feature; the `fluid` array,
/// columns h, m and speed).
pub fn read_dam_break(path: &Path) -> Result<ParticleData> {
    if path.is_dir() {
        return read_dam_break_npy(path);
    }
    let Some(format) = ParticleFormat::detect(path)? else {
        bail!("{}: not a particle file voxless reads", path.display());
    };
    let opts = TableOptions {
        group: (format == ParticleFormat::Hdf5).then(|| "fluid".to_string()),
        ..Default::default()
    };
    let t = read_table(path, format, 0, &opts)?.table;
    let column = |name: &str| -> Result<Vec<f32>> {
        t.column(name).map(<[f32]>::to_vec).with_context(|| {
            format!(
                "{}: no column '{name}' (columns: {})",
                path.display(),
                t.column_names().join(", ")
            )
        })
    };
    Ok(ParticleData {
        positions: t
            .positions
            .iter()
            .map(|p| Vec3::from_array(p.map(|c| c as f32)))
            .collect(),
        radii: Some(column("h")?),
        weights: Some(column("m")?),
        attribute: Some(column("speed")?),
    })
}

fn read_dam_break_npy(dir: &Path) -> Result<ParticleData> {
    let read =
        |name: &str| -> Result<voxless_io::NpyArray> { Ok(voxless_io::read_npy(&dir.join(name))?) };
    let pos = read("positions.npy")?;
    if pos.shape.len() != 2 || pos.shape[1] != 3 {
        bail!(
            "{}: expected N×3 positions, found shape {:?}",
            dir.join("positions.npy").display(),
            pos.shape
        );
    }
    let n = pos.shape[0];
    let column = |name: &str| -> Result<Vec<f32>> {
        let a = read(name)?;
        let (path, got) = (dir.join(name), a.data.len());
        if got != n {
            bail!("{}: expected {n} values, found {got}", path.display());
        }
        Ok(a.data.iter().map(|&v| v as f32).collect())
    };
    Ok(ParticleData {
        positions: pos
            .data
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32))
            .collect(),
        radii: Some(column("h.npy")?),
        weights: Some(column("mass.npy")?),
        attribute: Some(column("speed.npy")?),
    })
}

/// `n` synthetic particles and a gaussian3 radius of 2.5 × their mean
/// spacing (the radius `voxless render` picks when none is given).
pub fn synthetic(scene: &str, n: usize) -> (ParticleData, f32) {
    let data = if scene == "galaxy" {
        voxless::demo::galaxy(n)
    } else {
        // xorshift64: deterministic, no dependency.
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let mut u = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            ((s >> 40) as f32 + 0.5) / (1u64 << 24) as f32
        };
        ParticleData {
            positions: (0..n).map(|_| Vec3::new(u(), u(), u())).collect(),
            ..Default::default()
        }
    };
    let radius = voxless::load::default_radius(&data.positions, Kernel::Gaussian3);
    (data, radius)
}

// ---------------------------------------------------------------- helpers

/// Median time in seconds of `repeats` calls of `f(setup())` (`setup` is not
/// timed), and the last call's result (earlier results are dropped untimed).
pub fn bench<S, T>(
    repeats: usize,
    mut setup: impl FnMut() -> S,
    mut f: impl FnMut(S) -> T,
) -> (f64, T) {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..repeats.max(1) {
        let input = setup();
        let t = Instant::now();
        let out = f(input);
        times.push(t.elapsed().as_secs_f64());
        last = Some(out);
    }
    (median(times), last.expect("at least one run"))
}

/// The median (the upper one for an even count).
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

pub fn ms(s: f64) -> f64 {
    s * 1e3
}

/// 1000000 → "1M", else the plain number.
pub fn count(n: usize) -> String {
    if n.is_multiple_of(1_000_000) {
        format!("{}M", n / 1_000_000)
    } else {
        n.to_string()
    }
}

pub fn verdict(ok: bool) -> &'static str {
    if ok { "met" } else { "not met" }
}

pub fn print_header() {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!(
        "Machine: {model}, {cores} cores available, {} rayon threads. Date: {} (UTC).\n",
        rayon::current_num_threads(),
        today()
    );
}

/// Today's UTC date as YYYY-MM-DD (civil-from-days, proleptic Gregorian).
fn today() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let z = (secs / 86_400) as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    format!("{:04}-{m:02}-{d:02}", yoe + era * 400 + (m <= 2) as i64)
}
