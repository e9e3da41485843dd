//! `voxless bench`: the performance numbers quoted in `docs/benchmarks.md`.
//!
//! Every benchmark reports a ratio against a baseline measured in the same
//! run, so numbers from different machines (or a busy machine) stay
//! comparable; absolute times are printed too but are only indicative.
//! Timings are the median of `--repeats` runs. Results go to stdout as
//! markdown tables headed by the machine (CPU model, thread count) and the
//! date; progress goes to stderr.
//!
//! - `bench bvh`: the cost of the acceleration structure alone. Synthetic
//!   particles (the demo spiral galaxy, which is strongly clustered, and a
//!   uniform cube) get a fixed radius of 2.5× the mean particle spacing and
//!   are Hilbert-sorted once by `ParticleVolume::new` (cluster size 1; its
//!   time is reported). For cluster sizes 1, 2, 4, 8, 16 the cluster boxes
//!   (union of the members' support boxes) are computed and we time
//!   `Bvh::build` (fresh allocation), `Bvh::rebuild` (reusing the buffers),
//!   and `Bvh::refit` after scaling every radius by 1.5 — the operation a
//!   radius slider triggers. Ratios: refit/build, each build against the
//!   cluster-size-1 build, and tree memory against the particle data
//!   (16 bytes per particle: xyz + radius in f32). Finally the user-facing
//!   `ParticleVolume::set_radius` (radii, refit, macrocells, value range) is
//!   timed against `ParticleVolume::new` at the default cluster size 8.
//!   Why: the targets are a build ≤ 100 ms for 1M particles on two
//!   cores and a tree ≤ 0.5× the particle data at 16 particles per leaf.
//! - `bench frame`: what clustering buys in a real render. One frame through
//!   `voxless_render::render` with `Camera::framing` and
//!   `RenderSettings::for_volume` defaults, once with cluster size 8 (the
//!   default path) and once with cluster size 1 (the reference path: one BVH
//!   leaf per particle). Both use the same render settings (taken from the
//!   clustered volume), so the images differ only by the order in which the
//!   kernel contributions are summed; the max abs channel difference is
//!   reported as a correctness check. With `--dam-break DIR` the same is done
//!   for an SPH dam-break snapshot (`positions.npy`, `h.npy`, `mass.npy`,
//!   `speed.npy`; cubic-spline kernel with radius h, weights = mass).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use rayon::prelude::*;
use voxless_bvh::Bvh;
use voxless_core::{Aabb, Camera, Image, Vec3, Volume};
use voxless_particles::{Kernel, ParticleData, ParticleSettings, ParticleVolume};
use voxless_render::RenderSettings;
use voxless_transfer::TransferFunction;

/// Run the benchmarks and print markdown tables (see docs/benchmarks.md).
#[derive(clap::Args)]
pub struct BenchArgs {
    #[command(subcommand)]
    which: Which,
}

#[derive(clap::Subcommand)]
enum Which {
    /// BVH build / rebuild / refit times and memory for cluster sizes 1–16,
    /// plus ParticleVolume::set_radius against ParticleVolume::new.
    Bvh {
        /// Number of synthetic particles.
        #[arg(long, default_value_t = 1_000_000)]
        n: usize,
        /// Particle distribution: galaxy (demo spiral, clustered), uniform (unit cube) or both.
        #[arg(long, default_value = "both")]
        scene: String,
        /// Timed runs per measurement (the median is reported).
        #[arg(long, default_value_t = 5)]
        repeats: usize,
    },
    /// Frame time with clustered (8) vs unclustered (1) BVH leaves, and the
    /// max difference between the two images.
    Frame {
        /// Image width and height in pixels.
        #[arg(long, default_value_t = 1024)]
        size: u32,
        /// Number of particles of the synthetic galaxy.
        #[arg(long, default_value_t = 1_000_000)]
        n: usize,
        /// Samples per pixel.
        #[arg(long, default_value_t = 1)]
        spp: u32,
        /// Samples per nominal step (RenderSettings::sampling_rate; library default 1).
        #[arg(long, default_value_t = 1.0)]
        sampling_rate: f32,
        /// Timed renders per cluster size (the median is reported).
        #[arg(long, default_value_t = 1)]
        repeats: usize,
        /// Also bench the SPH dam-break snapshot in DIR (positions.npy, h.npy,
        /// mass.npy, speed.npy), e.g. ../shared/data/sph-dam-break/npy_01000.
        #[arg(long, value_name = "DIR")]
        dam_break: Option<PathBuf>,
        /// Write the rendered frames as PNGs into this directory.
        #[arg(long, value_name = "DIR")]
        save: Option<PathBuf>,
    },
}

pub fn run(args: BenchArgs) -> Result<()> {
    match args.which {
        Which::Bvh { n, scene, repeats } => {
            let scenes: &[&str] = match scene.as_str() {
                "both" => &["galaxy", "uniform"],
                "galaxy" => &["galaxy"],
                "uniform" => &["uniform"],
                other => bail!("--scene must be galaxy, uniform or both, not '{other}'"),
            };
            if n == 0 || repeats == 0 {
                bail!("--n and --repeats must be ≥ 1");
            }
            print_header();
            for s in scenes {
                bench_bvh(s, n, repeats)?;
            }
            Ok(())
        }
        Which::Frame {
            size,
            n,
            spp,
            sampling_rate,
            repeats,
            dam_break,
            save,
        } => {
            if size == 0 || n == 0 || spp == 0 || repeats == 0 || !(sampling_rate > 0.0) {
                bail!("--size, --n, --spp, --repeats and --sampling-rate must be > 0");
            }
            if let Some(dir) = &save {
                std::fs::create_dir_all(dir)
                    .with_context(|| format!("creating {}", dir.display()))?;
            }
            let opts = FrameOpts {
                size,
                spp,
                sampling_rate,
                repeats,
                save,
            };
            print_header();
            let mut rows = Vec::new();
            let (data, radius) = synthetic("galaxy", n);
            rows.push(bench_frame(
                &format!("galaxy {}", count(n)),
                data,
                Kernel::Gaussian3,
                radius,
                &opts,
            )?);
            if let Some(dir) = &dam_break {
                let data = read_dam_break(dir)?;
                let label = format!("dam break {}", count(data.positions.len()));
                rows.push(bench_frame(&label, data, Kernel::CubicSpline, 1.0, &opts)?);
            }
            println!(
                "### Frame: {size}×{size}, {spp} spp, sampling rate {sampling_rate}, median of {repeats}\n"
            );
            println!(
                "| scene | kernel | build N=8 s | build N=1 s | frame N=8 s | frame N=1 s | speedup (N=1 / N=8) | max abs diff | mean abs diff |"
            );
            println!("|---|---|---:|---:|---:|---:|---:|---:|---:|");
            for r in rows {
                println!("{r}");
            }
            println!();
            Ok(())
        }
    }
}

// ---------------------------------------------------------------- bvh

fn bench_bvh(scene: &str, n: usize, repeats: usize) -> Result<()> {
    let (data, radius) = synthetic(scene, n);
    let kernel = Kernel::Gaussian3;
    eprintln!("bvh/{scene}: {n} particles, radius {radius:.5}");
    let settings = |cluster_size| ParticleSettings {
        kernel,
        radius,
        cluster_size,
        ..Default::default()
    };
    // ParticleVolume::new at N=1 gives the Hilbert order used below.
    let mut vol = None;
    let t_new1 = median_of(repeats, || {
        let t = Instant::now();
        let v = ParticleVolume::new(data.clone(), settings(1));
        let s = t.elapsed().as_secs_f64();
        vol = Some(v);
        s
    });
    let vol = vol.unwrap()?;
    let positions = vol.positions();
    let factor = kernel.support_factor();
    let support: Vec<f32> = vol.radii().iter().map(|r| r * factor).collect();
    let grown: Vec<f32> = support.iter().map(|s| s * 1.5).collect();
    let particle_bytes = 16.0 * n as f64;

    println!(
        "### BVH: {scene}, {} particles, gaussian3, radius {radius:.5} (2.5 × mean spacing)\n",
        count(n)
    );
    println!(
        "`ParticleVolume::new` (cluster size 1, includes Hilbert sort): {:.1} ms\n",
        ms(t_new1)
    );
    println!(
        "| N/leaf | clusters | boxes ms | build ms | rebuild ms | refit ms (r × 1.5) | refit / build | build / build(N=1) | tree MB | tree / particles |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut build1 = None;
    for cs in [1usize, 2, 4, 8, 16] {
        eprintln!("bvh/{scene}: cluster size {cs}");
        let mut boxes = Vec::new();
        let t_boxes = median_of(repeats, || {
            timed(|| boxes = cluster_boxes(positions, &support, cs))
        });
        let big = cluster_boxes(positions, &grown, cs);
        let t_build = median_of(repeats, || {
            let t = Instant::now();
            let b = Bvh::build(&boxes);
            let s = t.elapsed().as_secs_f64();
            drop(b);
            s
        });
        let mut bvh = Bvh::build(&boxes);
        let t_rebuild = median_of(repeats, || timed(|| bvh.rebuild(&boxes)));
        // Alternate the grown and original radii so every refit changes the boxes.
        let mut k = 0;
        let t_refit = median_of(repeats, || {
            k += 1;
            let prims = if k % 2 == 1 { &big } else { &boxes };
            timed(|| bvh.refit(prims))
        });
        bvh.refit(&big);
        bvh.validate(&big)
            .map_err(|e| anyhow::anyhow!("after refit: {e}"))?;
        let b1 = *build1.get_or_insert(t_build);
        let mem = bvh.memory_bytes() as f64;
        println!(
            "| {cs} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.2} | {:.2} | {:.1} | {:.2} |",
            boxes.len(),
            ms(t_boxes),
            ms(t_build),
            ms(t_rebuild),
            ms(t_refit),
            t_refit / t_build,
            t_build / b1,
            mem / 1e6,
            mem / particle_bytes
        );
    }
    println!();
    drop(vol);

    // The user-facing path at the default cluster size.
    eprintln!("bvh/{scene}: set_radius vs new at cluster size 8");
    let mut vol8 = None;
    let t_new8 = median_of(repeats, || {
        let t = Instant::now();
        let v = ParticleVolume::new(data.clone(), settings(8));
        let s = t.elapsed().as_secs_f64();
        vol8 = Some(v);
        s
    });
    let mut vol8 = vol8.unwrap()?;
    // Up to 1.5 r and back: "back" ends in the state `new` built, so its ratio
    // to `new` compares equal work; "up" touches more macrocells.
    let (mut up, mut down) = (Vec::new(), Vec::new());
    for _ in 0..repeats {
        let t = Instant::now();
        vol8.set_radius(radius * 1.5, None)?;
        up.push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        vol8.set_radius(radius, None)?;
        down.push(t.elapsed().as_secs_f64());
    }
    let (up, down) = (median(up), median(down));
    println!("| cluster size 8 | ms | ratio to `new` |");
    println!("|---|---:|---:|");
    println!("| `ParticleVolume::new` (r) | {:.1} | 1.00 |", ms(t_new8));
    println!(
        "| `set_radius` r → 1.5 r | {:.1} | {:.2} |",
        ms(up),
        up / t_new8
    );
    println!(
        "| `set_radius` 1.5 r → r | {:.1} | {:.2} |",
        ms(down),
        down / t_new8
    );
    println!();
    Ok(())
}

/// One box per run of `cs` consecutive particles: the union of their support boxes.
fn cluster_boxes(positions: &[Vec3], support: &[f32], cs: usize) -> Vec<Aabb> {
    positions
        .par_chunks(cs)
        .zip(support.par_chunks(cs))
        .map(|(p, s)| {
            p.iter()
                .zip(s)
                .map(|(&c, &r)| Aabb::around(c, r))
                .fold(Aabb::EMPTY, Aabb::union)
        })
        .collect()
}

// ---------------------------------------------------------------- frame

struct FrameOpts {
    size: u32,
    spp: u32,
    sampling_rate: f32,
    repeats: usize,
    save: Option<PathBuf>,
}

fn bench_frame(
    label: &str,
    data: ParticleData,
    kernel: Kernel,
    radius: f32,
    o: &FrameOpts,
) -> Result<String> {
    let settings = |cluster_size| ParticleSettings {
        kernel,
        radius,
        cluster_size,
        ..Default::default()
    };
    let tf = TransferFunction::default_for_density();
    eprintln!("frame/{label}: building volumes");
    let (t_b8, v8) = timed_val(|| ParticleVolume::new(data.clone(), settings(8)));
    let (t_b1, v1) = timed_val(|| ParticleVolume::new(data, settings(1)));
    let (v8, v1) = (v8?, v1?);
    let camera = Camera::framing(&v8.bounds(), 1.0);
    let mut rs = RenderSettings::for_volume(&v8, o.size, o.size);
    rs.spp = o.spp;
    rs.sampling_rate = o.sampling_rate;
    let render = |v: &ParticleVolume, what: &str| {
        let mut img = None;
        let t = median_of(o.repeats, || {
            eprintln!("frame/{label}: rendering {what}");
            let t = Instant::now();
            let i = voxless_render::render(v, &camera, &tf, &rs, &|_, _| {});
            let s = t.elapsed().as_secs_f64();
            eprintln!("frame/{label}: {what} took {s:.2} s");
            img = Some(i);
            s
        });
        (t, img.unwrap())
    };
    let (t8, img8) = render(&v8, "cluster size 8");
    let (t1, img1) = render(&v1, "cluster size 1");
    let (max_diff, mean_diff) = image_diff(&img8, &img1);
    if let Some(dir) = &o.save {
        let stem = label.replace(' ', "-");
        save_png(&dir.join(format!("{stem}-n8.png")), &img8)?;
        save_png(&dir.join(format!("{stem}-n1.png")), &img1)?;
    }
    Ok(format!(
        "| {label} | {} | {t_b8:.2} | {t_b1:.2} | {t8:.2} | {t1:.2} | {:.2} | {max_diff:.2e} | {mean_diff:.2e} |",
        kernel.name(),
        t1 / t8
    ))
}

/// Max and mean absolute difference over all pixels and RGBA channels.
fn image_diff(a: &Image, b: &Image) -> (f32, f64) {
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

fn save_png(path: &Path, img: &Image) -> Result<()> {
    voxless_io::write_png_rgb8(path, img.width, img.height, &img.to_srgb8([0.0; 3]))?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

fn read_dam_break(dir: &Path) -> Result<ParticleData> {
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
        if a.data.len() != n {
            bail!(
                "{}: expected {n} values, found {}",
                dir.join(name).display(),
                a.data.len()
            );
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

// ---------------------------------------------------------------- data

/// `n` synthetic particles and a gaussian3 radius of 2.5 × their mean spacing.
fn synthetic(scene: &str, n: usize) -> (ParticleData, f32) {
    let data = if scene == "galaxy" {
        voxless_scene::demo::galaxy(n)
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
    let radius = 2.5 * mean_spacing(&data.positions);
    (data, radius)
}

/// `(occupied volume / N)^(1/3)`, the occupied volume counted on a coarse grid
/// of about four particles per cell (the estimate `voxless render` uses when no
/// radius is given; that function is private to voxless-scene).
fn mean_spacing(positions: &[Vec3]) -> f32 {
    let b = positions.iter().fold(Aabb::EMPTY, |mut b, p| {
        b.grow(*p);
        b
    });
    let n = positions.len();
    let res = ((n as f32 / 4.0).cbrt().round() as usize).clamp(1, 128);
    let cell = b.extent().max_elem().max(1e-12) / res as f32;
    let dims = b.extent() * (1.0 / cell);
    let dim = |a: f32| (a.ceil() as usize).clamp(1, res);
    let (nx, ny, nz) = (dim(dims.x), dim(dims.y), dim(dims.z));
    let mut occupied = vec![false; nx * ny * nz];
    for p in positions {
        let q = (*p - b.min) * (1.0 / cell);
        let (i, j, k) = (
            (q.x as usize).min(nx - 1),
            (q.y as usize).min(ny - 1),
            (q.z as usize).min(nz - 1),
        );
        occupied[(k * ny + j) * nx + i] = true;
    }
    let cells = occupied.iter().filter(|&&o| o).count().max(1);
    (cells as f32 * cell * cell * cell / n as f32).cbrt()
}

// ---------------------------------------------------------------- helpers

fn timed(f: impl FnOnce()) -> f64 {
    let t = Instant::now();
    f();
    t.elapsed().as_secs_f64()
}

fn timed_val<T>(f: impl FnOnce() -> T) -> (f64, T) {
    let t = Instant::now();
    let v = f();
    (t.elapsed().as_secs_f64(), v)
}

/// Median of `repeats` calls of `f`, each returning its own time in seconds.
fn median_of(repeats: usize, mut f: impl FnMut() -> f64) -> f64 {
    median((0..repeats).map(|_| f()).collect())
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    }
}

fn ms(s: f64) -> f64 {
    s * 1e3
}

/// 1000000 → "1M", 23760 → "23,760".
fn count(n: usize) -> String {
    if n >= 1_000_000 && n % 1_000_000 == 0 {
        return format!("{}M", n / 1_000_000);
    }
    let s = n.to_string();
    let mut out = String::new();
    for (i, ch) in s.chars().enumerate() {
        if i > 0 && (s.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(ch);
    }
    out
}

fn print_header() {
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
