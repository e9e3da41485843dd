//! `voxless-bench bvh`: the cost of the particle acceleration structure alone.
//!
//! Synthetic particles (the demo spiral galaxy, which is strongly clustered,
//! and a uniform cube) get a fixed radius of 2.5× the mean particle spacing
//! and are Hilbert-sorted once by `ParticleVolume::new` (cluster size 1; its
//! time is reported). For cluster sizes 1, 2, 4, 8, 16 the cluster boxes
//! (union of the members' support boxes) are computed and we time
//! `Bvh::build` (fresh allocation), `Bvh::rebuild` (reusing the buffers),
//! and `Bvh::refit` after scaling every radius by 1.5 — the operation a
//! radius slider triggers. Ratios: refit/build, each build against the
//! cluster-size-1 build, and tree memory against the particle data
//! (16 bytes per particle: xyz + radius in f32). Finally the user-facing
//! `ParticleVolume::set_radius` (radii, refit, macrocells, value range) is
//! timed against `ParticleVolume::new` at the default cluster size 8.
//! With `--dam-break DIR|FILE` (repeatable) the same tables are made for SPH
//! dam-break frames (cubic spline, radius h per particle).
//!
//! Why: the targets are a build ≤ 100 ms for 1M particles on two cores and
//! a tree ≤ 0.5× the particle data at 16 particles per leaf.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Result, bail};
use rayon::prelude::*;
use voxless_bvh::Bvh;
use voxless_core::{Aabb, Vec3};
use voxless_particles::{Kernel, ParticleData, ParticleSettings, ParticleVolume};

use crate::common::{bench, count, median, ms, print_header, read_dam_break, synthetic, verdict};

#[derive(clap::Args)]
pub struct BvhArgs {
    /// Number of synthetic particles.
    #[arg(long, default_value_t = 1_000_000)]
    n: usize,
    /// Particle distribution: the demo spiral galaxy (clustered), a uniform unit cube, or both.
    #[arg(long, default_value = "both", value_parser = ["galaxy", "uniform", "both"])]
    scene: String,
    /// Timed runs per measurement (the median is reported).
    #[arg(long, default_value_t = 5)]
    repeats: usize,
    /// Also the SPH dam-break snapshot in DIR (positions.npy, h.npy,
    /// mass.npy, speed.npy) or a PySPH .hdf5 frame (built with
    /// --features hdf5), repeatable; cubic spline with radius h: the
    /// paper's Tables 1 and 2 on real frames.
    #[arg(long, value_name = "DIR|FILE")]
    dam_break: Vec<PathBuf>,
}

pub fn run(o: BvhArgs) -> Result<()> {
    if o.n == 0 || o.repeats == 0 {
        bail!("--n and --repeats must be ≥ 1");
    }
    let frames = o
        .dam_break
        .iter()
        .map(|d| Ok((d.clone(), read_dam_break(d)?)))
        .collect::<Result<Vec<_>>>()?;
    print_header();
    for s in ["galaxy", "uniform"]
        .into_iter()
        .filter(|s| o.scene == "both" || o.scene == *s)
    {
        let (data, radius) = synthetic(s, o.n);
        let what = format!(
            "{s}, {} particles, gaussian3, radius {radius:.5} (2.5 × mean spacing)",
            count(o.n)
        );
        bench_bvh(&what, data, Kernel::Gaussian3, radius, o.repeats)?;
    }
    for (dir, data) in frames {
        let name = dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let what = format!(
            "dam break {name}, {} particles, cubic spline, radius h per particle",
            count(data.positions.len())
        );
        bench_bvh(&what, data, Kernel::CubicSpline, 1.0, o.repeats)?;
    }
    Ok(())
}

fn bench_bvh(
    what: &str,
    data: ParticleData,
    kernel: Kernel,
    radius: f32,
    repeats: usize,
) -> Result<()> {
    let n = data.positions.len();
    eprintln!("bvh/{what}");
    let settings = |cluster_size| ParticleSettings {
        kernel,
        radius,
        cluster_size,
        ..Default::default()
    };
    // ParticleVolume::new at N=1 gives the Hilbert order used below.
    let (t_new1, vol) = bench(
        repeats,
        || data.clone(),
        |d| ParticleVolume::new(d, settings(1)),
    );
    let vol = vol?;
    let positions = &vol.positions()[..];
    let factor = kernel.support_factor();
    let support: Vec<f32> = vol.radii().iter().map(|r| r * factor).collect();
    let grown: Vec<f32> = support.iter().map(|s| s * 1.5).collect();
    let particle_bytes = 16.0 * n as f64;

    println!("### BVH: {what}\n");
    println!(
        "`ParticleVolume::new` (cluster size 1, includes Hilbert sort): {:.1} ms\n",
        ms(t_new1)
    );
    println!(
        "| N/leaf | clusters | boxes ms | build ms | rebuild ms | refit ms (r × 1.5) | refit / build | build / build(N=1) | tree MB | tree / particles |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut builds = Vec::new();
    let mut mem16 = 0.0;
    for cs in [1usize, 2, 4, 8, 16] {
        eprintln!("bvh: cluster size {cs}");
        let (t_boxes, boxes) = bench(repeats, || (), |_| cluster_boxes(positions, &support, cs));
        let big = cluster_boxes(positions, &grown, cs);
        let (t_build, mut bvh) = bench(repeats, || (), |_| Bvh::build(&boxes));
        let (t_rebuild, _) = bench(repeats, || (), |_| bvh.rebuild(&boxes));
        // Alternate the grown and original radii so every refit changes the boxes.
        let mut k = 0;
        let mut pick = || {
            k += 1;
            if k % 2 == 1 { &big } else { &boxes }
        };
        let (t_refit, _) = bench(repeats, &mut pick, |prims| bvh.refit(prims));
        bvh.refit(&big);
        bvh.validate(&big)
            .map_err(|e| anyhow::anyhow!("after refit: {e}"))?;
        builds.push(t_build);
        let b1 = builds[0];
        let mem = bvh.memory_bytes() as f64;
        mem16 = mem / particle_bytes;
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
    let per_1m = |t: f64| ms(t) * 1e6 / n as f64;
    println!(
        "\nTargets (1M particles, 2 cores; times scaled linearly to 1M): build ≤ 100 ms: \
         1/leaf {:.1} ms ({}), 8/leaf {:.1} ms ({}); tree ≤ 0.5× particle data at 16/leaf: \
         {mem16:.2}× ({}).\n",
        per_1m(builds[0]),
        verdict(per_1m(builds[0]) <= 100.0),
        per_1m(builds[3]),
        verdict(per_1m(builds[3]) <= 100.0),
        verdict(mem16 <= 0.5)
    );
    drop(vol);

    // The user-facing path at the default cluster size.
    eprintln!("bvh: set_radius vs new at cluster size 8");
    let (t_new8, vol8) = bench(
        repeats,
        || data.clone(),
        |d| ParticleVolume::new(d, settings(8)),
    );
    let mut vol8 = vol8?;
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
    println!("| 8/leaf | ms | ratio to `new` |");
    println!("|---|---:|---:|");
    for (what, t) in [
        ("`ParticleVolume::new` (r)", t_new8),
        ("`set_radius` r → 1.5 r", up),
        ("`set_radius` 1.5 r → r", down),
    ] {
        println!("| {what} | {:.1} | {:.2} |", ms(t), t / t_new8);
    }
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
