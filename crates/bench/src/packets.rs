//! `voxless-bench packets`: what the packet path (CPU RBF paper §4) buys.
//!
//! Every frame goes through `voxless_render::render` with `Camera::framing`,
//! `RenderSettings::for_volume` and the default transfer function.
//!
//! - **Packets vs per-sample**: one 1 spp frame (default 1024²) rendered by
//!   the packet path and by the per-sample point-query path with identical
//!   settings (`RenderSettings::packets` on/off), on the SPH dam-break frame
//!   (`--dam-break DIR`; cubic spline, radius h, weight m, speed as the
//!   attribute) and on the synthetic galaxy (gaussian3, 2.5 × mean spacing).
//!   Reported: the per-sample time, the packet time with the portable SIMD
//!   backend and with `Simd::Auto` (AVX2 where the CPU has it) — chosen by
//!   value through `RenderSettings::simd` — the speedup of the latter, and
//!   the max channel difference of either packet image from the per-sample
//!   one (the correctness check: ≤ 1/255).
//! - **Radius sweep** (the paper's Fig. 9): frame time against the radius
//!   (× 0.5 … × 2 of the default) for cluster sizes 8 and 1, packets on; a
//!   radius change is a refit (`set_radius`), timed too.
//! - **Blue vs white noise**: a frame with volumetric shadows (single
//!   scattering, stochastic ray marching) driven by blue and by white noise,
//!   times and their ratio (the mask is generated once per process, before
//!   timing).

use std::path::PathBuf;

use anyhow::{Result, bail};
use voxless_core::{Camera, Control, Image, Simd, Vec3, Volume};
use voxless_particles::{Kernel, ParticleData, ParticleSettings, ParticleVolume};
use voxless_render::{FreeFlight, LightSource, Noise, RenderSettings, Scatter};
use voxless_transfer::{ControlPoints, TransferFunction};

use crate::common::{bench, count, image_diff, print_header, read_dam_break, synthetic};

/// One frame through the shared integrator.
fn render(
    vol: &ParticleVolume,
    camera: &Camera,
    tf: &TransferFunction,
    rs: &RenderSettings,
) -> Result<Image> {
    Ok(voxless_render::render(
        vol,
        camera,
        tf,
        rs,
        &Control::new(),
    )?)
}

#[derive(clap::Args)]
pub struct PacketArgs {
    /// Image width and height in pixels.
    #[arg(long, default_value_t = 1024)]
    size: u32,
    /// Number of particles of the synthetic galaxy (0: skip it).
    #[arg(long, default_value_t = 1_000_000)]
    n: usize,
    /// Timed renders per measurement (the median is reported).
    #[arg(long, default_value_t = 1)]
    repeats: usize,
    /// The SPH dam-break snapshot in DIR, e.g.
    /// ../shared/data/sph-dam-break/npy_01000.
    #[arg(long, value_name = "DIR")]
    dam_break: Option<PathBuf>,
    /// Image size of the radius sweep and the noise comparison.
    #[arg(long, default_value_t = 512)]
    small: u32,
}

pub fn run(o: PacketArgs) -> Result<()> {
    if o.size == 0 || o.small == 0 || o.repeats == 0 {
        bail!("--size, --small and --repeats must be ≥ 1");
    }
    let dam = o.dam_break.as_deref().map(read_dam_break).transpose()?;
    print_header();
    let mut sets: Vec<(String, ParticleData, Kernel, f32)> = Vec::new();
    if let Some(d) = dam {
        let label = format!("dam break {}", count(d.positions.len()));
        sets.push((label, d, Kernel::CubicSpline, 1.0));
    }
    if o.n > 0 {
        let (d, r) = synthetic("galaxy", o.n);
        sets.push((format!("galaxy {}", count(o.n)), d, Kernel::Gaussian3, r));
    }
    if sets.is_empty() {
        bail!("nothing to measure: give --dam-break DIR or --n > 0");
    }
    let tf = TransferFunction::default_for_density();

    println!(
        "### Packets vs per-sample point queries: {0}×{0}, 1 spp, median of {1}\n",
        o.size, o.repeats
    );
    println!(
        "| data | kernel | per-sample s | packets s, portable SIMD | packets s, auto | speedup (auto) | max abs diff (portable / auto) |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|");
    for (label, data, kernel, radius) in &sets {
        let vol = volume(data, *kernel, *radius, 8)?;
        let camera = Camera::framing(&vol.bounds(), 1.0);
        let mut rs = RenderSettings::for_volume(&vol, o.size, o.size);
        // The SIMD backend is a render setting, chosen by value.
        let mut time = |packets: bool, simd: Simd| {
            rs.packets = packets;
            rs.simd = simd;
            eprintln!("packets/{label}: packets {packets}, {} SIMD", simd.name());
            bench(o.repeats, || (), |_| render(&vol, &camera, &tf, &rs))
        };
        let (t_slow, slow) = time(false, Simd::Auto);
        let (t_portable, portable) = time(true, Simd::Portable);
        let (t_fast, fast) = time(true, Simd::Auto);
        let slow = slow?;
        let (max, _) = image_diff(&slow, &fast?);
        let (max_p, _) = image_diff(&slow, &portable?);
        println!(
            "| {label} | {} | {t_slow:.2} | {t_portable:.2} | {t_fast:.2} | {:.2} | {max_p:.2e} / {max:.2e} |",
            kernel.name(),
            t_slow / t_fast,
        );
    }
    println!();

    println!(
        "### Radius sweep (Fig. 9 style): {0}×{0}, 1 spp, packets, median of {1}\n",
        o.small, o.repeats
    );
    println!("| data | radius × | set_radius ms (N=8) | frame s N=8 | frame s N=1 | N=1 / N=8 |");
    println!("|---|---:|---:|---:|---:|---:|");
    for (label, data, kernel, radius) in &sets {
        let mut v8 = volume(data, *kernel, *radius, 8)?;
        let mut v1 = volume(data, *kernel, *radius, 1)?;
        // The camera and transfer range stay those of the default radius.
        let camera = Camera::framing(&v8.bounds(), 1.0);
        let rs = RenderSettings::for_volume(&v8, o.small, o.small);
        for scale in [0.5f32, 1.0, 1.5, 2.0] {
            // Per-particle radii (SPH h) scale through the radius map's
            // global factor; a global radius scales directly.
            let (r, map) = scaled(data, *radius, scale);
            let (t_refit, res) = bench(1, || map.clone(), |m| v8.set_radius(r, m));
            res?;
            v1.set_radius(r, map)?;
            let frame = |v: &ParticleVolume| -> Result<f64> {
                let (t, img) = bench(o.repeats, || (), |_| render(v, &camera, &tf, &rs));
                img?;
                Ok(t)
            };
            eprintln!("packets/{label}: radius × {scale}");
            let (t8, t1) = (frame(&v8)?, frame(&v1)?);
            println!(
                "| {label} | {scale} | {:.1} | {t8:.2} | {t1:.2} | {:.2} |",
                t_refit * 1e3,
                t1 / t8
            );
        }
    }
    println!();

    println!(
        "### Volumetric shadows, blue vs white noise: {0}×{0}, 1 spp, marching, median of {1}\n",
        o.small, o.repeats
    );
    println!("| data | blue s | white s | white / blue |");
    println!("|---|---:|---:|---:|");
    // Build the mask before timing.
    let _ = voxless_render::bluenoise::mask();
    for (label, data, kernel, radius) in &sets {
        let vol = volume(data, *kernel, *radius, 8)?;
        let camera = Camera::framing(&vol.bounds(), 1.0);
        let mut rs = RenderSettings::for_volume(&vol, o.small, o.small);
        let mut time = |noise: Noise| {
            rs.scatter = Some(Scatter {
                light: LightSource::Directional(Vec3::new(0.3, 1.0, 0.4).normalized()),
                intensity: 1.0,
                ambient: 0.3,
                method: FreeFlight::Marching,
                noise,
            });
            eprintln!("packets/{label}: shadows, {noise:?} noise");
            let (t, img) = bench(o.repeats, || (), |_| render(&vol, &camera, &tf, &rs));
            img.map(|_| t)
        };
        let (blue, white) = (time(Noise::Blue)?, time(Noise::White)?);
        println!("| {label} | {blue:.2} | {white:.2} | {:.2} |", white / blue);
    }
    println!();
    Ok(())
}

fn volume(
    data: &ParticleData,
    kernel: Kernel,
    radius: f32,
    cluster: usize,
) -> Result<ParticleVolume> {
    Ok(ParticleVolume::new(
        data.clone(),
        ParticleSettings {
            kernel,
            radius,
            cluster_size: cluster,
            ..Default::default()
        },
    )?)
}

/// The global radius and radius map that scale every particle's radius by
/// `scale`: per-particle radii need a (constant) map, since the global radius
/// does not touch them.
fn scaled(data: &ParticleData, radius: f32, scale: f32) -> (f32, Option<ControlPoints>) {
    if data.radii.is_some() && data.attribute.is_some() {
        let map = ControlPoints::new("radius map", &[(0.0, scale), (1.0, scale)]).ok();
        (radius, map)
    } else {
        (radius * scale, None)
    }
}
