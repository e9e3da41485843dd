//! `voxless-bench frame`: what clustering buys in a real render.
//!
//! One frame through `voxless_render::render` with `Camera::framing` and
//! `RenderSettings::for_volume` defaults (what `voxless render` resolves
//! for particles when the scene sets nothing; `AnyVolume::default_settings`),
//! once with cluster size 8 (the default path) and once with cluster size 1
//! (the reference path: one BVH leaf per particle). Both use the same render
//! settings (taken from the clustered volume), so the images differ only by
//! the order in which the kernel contributions are summed; the max abs
//! channel difference is reported as a correctness check. With
//! `--dam-break DIR` the same is done for an SPH dam-break snapshot
//! (`positions.npy`, `h.npy`, `mass.npy`, `speed.npy`; cubic-spline kernel
//! with radius h, weights = mass).

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use voxless_core::{Camera, Control, Volume};
use voxless_particles::{Kernel, ParticleData, ParticleSettings, ParticleVolume};
use voxless_render::RenderSettings;
use voxless_transfer::TransferFunction;

use crate::common::{bench, count, image_diff, print_header, read_dam_break, save_png, synthetic};

#[derive(clap::Args)]
pub struct FrameArgs {
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
}

pub fn run(o: FrameArgs) -> Result<()> {
    if o.size == 0 || o.n == 0 || o.spp == 0 || o.repeats == 0 || !(o.sampling_rate > 0.0) {
        bail!("--size, --n, --spp, --repeats and --sampling-rate must be > 0");
    }
    if let Some(dir) = &o.save {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    // Read the snapshot first so a bad path fails before the long galaxy runs.
    let dam_break = o.dam_break.as_deref().map(read_dam_break).transpose()?;
    print_header();
    let (data, radius) = synthetic("galaxy", o.n);
    let label = format!("galaxy {}", count(o.n));
    let mut rows = vec![bench_frame(&label, data, Kernel::Gaussian3, radius, &o)?];
    if let Some(data) = dam_break {
        let label = format!("dam break {}", count(data.positions.len()));
        rows.push(bench_frame(&label, data, Kernel::CubicSpline, 1.0, &o)?);
    }
    let (size, spp, rate, repeats) = (o.size, o.spp, o.sampling_rate, o.repeats);
    println!("### Frame: {size}×{size}, {spp} spp, sampling rate {rate}, median of {repeats}\n");
    println!(
        "| scene | kernel | volume N=8 s | volume N=1 s | frame N=8 s | frame N=1 s \
         | speedup (N=1 / N=8) | max abs diff | mean abs diff |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        println!("{r}");
    }
    println!();
    Ok(())
}

fn bench_frame(
    label: &str,
    data: ParticleData,
    kernel: Kernel,
    radius: f32,
    o: &FrameArgs,
) -> Result<String> {
    let settings = |cluster_size| ParticleSettings {
        kernel,
        radius,
        cluster_size,
        ..Default::default()
    };
    let tf = TransferFunction::default_for_density();
    eprintln!("frame/{label}: building volumes");
    let (t_b8, v8) = bench(1, || data.clone(), |d| ParticleVolume::new(d, settings(8)));
    let (t_b1, v1) = bench(1, || data.clone(), |d| ParticleVolume::new(d, settings(1)));
    let (v8, v1) = (v8?, v1?);
    let camera = Camera::framing(&v8.bounds(), 1.0);
    let mut rs = RenderSettings::for_volume(&v8, o.size, o.size);
    rs.spp = o.spp;
    rs.sampling_rate = o.sampling_rate;
    let render = |v: &ParticleVolume, what: &str| -> Result<(f64, voxless_core::Image)> {
        let setup = || eprintln!("frame/{label}: rendering {what}");
        let (t, img) = bench(o.repeats, setup, |_| {
            voxless_render::render(v, &camera, &tf, &rs, &Control::new())
        });
        eprintln!("frame/{label}: {what}: median {t:.2} s");
        Ok((t, img?))
    };
    let (t8, img8) = render(&v8, "cluster size 8")?;
    let (t1, img1) = render(&v1, "cluster size 1")?;
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
