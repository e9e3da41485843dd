//! `parallel`: data-parallel rendering.
//!
//! - `parallel composite`: sort-last compositing time against image size
//!   and rank count, K ranks as threads of this process (the library's
//!   `LocalComm`: the same direct-send code `mpirun` runs, without the
//!   network). Each rank's pass image is a decomposed render's: its k-d
//!   box covers a vertical band of the screen (one K-th, plus 10 % overlap
//!   with each neighbour), semi-opaque, so tiles have one or two fragments
//!   and some pixels stop early behind a front box (the re-render requests
//!   run too). Baseline, same run: every rank sends its whole image to rank
//!   0, which composites them — the full-image reduce to one rank that
//!   direct send replaces.
//! - `parallel data DIR`: writes the inputs of the per-rank memory
//!   measurements in docs/benchmarks.md: 10⁷ SPH-like particles
//!   (positions, smoothing lengths, masses as .npy) and the refined 128³
//!   tessellation of the 64³ JaxPM run.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use clap::{Args, Subcommand};
use voxless::parallel::{Comm, run_local};
use voxless_core::SmallRng;
use voxless_parallel::TileGrid;
use voxless_parallel::composite::{gather, over};

use crate::common::{median, ms, print_header};

#[derive(Args)]
pub struct ParallelArgs {
    #[command(subcommand)]
    what: What,
}

#[derive(Subcommand)]
enum What {
    /// Compositing time against image size and rank count.
    Composite {
        /// Rank counts (threads).
        #[arg(long, num_args = 1.., default_values_t = [1usize, 2, 4, 8, 16])]
        ranks: Vec<usize>,
        /// Image sizes W×H.
        #[arg(long, num_args = 1.., default_values = ["512x512", "1024x1024", "2048x2048", "3840x2160"])]
        sizes: Vec<String>,
        #[arg(long, default_value_t = 3)]
        repeats: usize,
    },
    /// Writes the memory-measurement inputs into DIR.
    Data {
        dir: PathBuf,
        /// Particle count of the SPH-like set.
        #[arg(long, default_value_t = 10_000_000)]
        particles: usize,
        /// The 64³ JaxPM positions that the 128³ set refines.
        #[arg(
            long,
            default_value = "../shared/data/nbody-jaxpm/npy_N64_a1/positions.npy"
        )]
        jaxpm: PathBuf,
    },
}

pub fn run(o: ParallelArgs) -> Result<()> {
    match o.what {
        What::Composite {
            ranks,
            sizes,
            repeats,
        } => composite(&ranks, &sizes, repeats),
        What::Data {
            dir,
            particles,
            jaxpm,
        } => data(&dir, particles, &jaxpm),
    }
}

/// Rank `r`'s pass image of `k`: its band of the screen, semi-opaque.
fn fragment(r: usize, k: usize, w: u32, h: u32) -> Vec<[f32; 4]> {
    let band = w as f32 / k as f32;
    let (lo, hi) = ((r as f32 - 0.1) * band, (r as f32 + 1.1) * band);
    let mut rng = SmallRng(r as u64 + 1);
    (0..w * h)
        .map(|i| {
            let x = (i % w) as f32;
            if x >= lo && x < hi {
                let a = 0.5 + 0.49 * rng.f();
                [0.3 * a, 0.5 * a, 0.7 * a, a]
            } else {
                [0.0; 4]
            }
        })
        .collect()
}

/// Median seconds (the slowest rank's) of direct send (over + gather) and
/// of the full-image baseline, for `k` ranks.
fn time_both(k: usize, w: u32, h: u32, repeats: usize) -> (f64, f64) {
    let grid = TileGrid::new(w, h, 32);
    let order: Vec<usize> = (0..k).collect();
    let out = run_local(k, |comm| {
        let image = fragment(comm.rank(), k, w, h);
        let mut direct = Vec::new();
        let mut full = Vec::new();
        for _ in 0..repeats.max(1) {
            let t = Instant::now();
            let tiles = over(comm, &grid, &image, &order, 0.99, &mut |req| {
                req.iter()
                    .map(|&(_, _, a)| [0.1, 0.1, 0.1, a + (1.0 - a) * 0.6])
                    .collect()
            })
            .expect("compositing");
            let img = gather(comm, &tiles).expect("gather");
            direct.push(t.elapsed().as_secs_f64());
            drop(img);
            // Baseline: every full image to rank 0, composited there.
            let t = Instant::now();
            let bytes: Vec<u8> = image
                .iter()
                .flatten()
                .flat_map(|v| v.to_le_bytes())
                .collect();
            let mut send = vec![Vec::new(); comm.size()];
            send[0] = bytes;
            let got = comm.exchange(send).expect("exchange");
            if comm.rank() == 0 {
                let mut acc = vec![[0.0f32; 4]; (w * h) as usize];
                for msg in &got {
                    for (p, c) in acc.iter_mut().zip(msg.chunks_exact(16)) {
                        let f = |i: usize| f32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]);
                        let t = 1.0 - p[3];
                        for (ch, v) in p.iter_mut().enumerate() {
                            *v += t * f(4 * ch);
                        }
                    }
                }
            }
            full.push(t.elapsed().as_secs_f64());
        }
        (median(direct), median(full))
    });
    let direct = out.iter().map(|o| o.0).fold(0.0, f64::max);
    let full = out.iter().map(|o| o.1).fold(0.0, f64::max);
    (direct, full)
}

fn composite(ranks: &[usize], sizes: &[String], repeats: usize) -> Result<()> {
    print_header();
    println!("| image | ranks | direct send (ms) | full images to rank 0 (ms) | ratio |");
    println!("|---|---|---|---|---|");
    for size in sizes {
        let (w, h) = size
            .split_once('x')
            .and_then(|(a, b)| Some((a.parse::<u32>().ok()?, b.parse::<u32>().ok()?)))
            .ok_or_else(|| anyhow::anyhow!("size '{size}' is not W×H (e.g. 1024x1024)"))?;
        for &k in ranks {
            eprintln!("composite {w}×{h}, {k} ranks");
            let (direct, full) = time_both(k, w, h, repeats);
            println!(
                "| {w}×{h} | {k} | {:.1} | {:.1} | {:.2} |",
                ms(direct),
                ms(full),
                full / direct
            );
        }
    }
    Ok(())
}

fn data(dir: &std::path::Path, n: usize, jaxpm: &std::path::Path) -> Result<()> {
    std::fs::create_dir_all(dir.join("particles"))?;
    std::fs::create_dir_all(dir.join("tets128"))?;
    // Clumps of SPH-like particles with smoothing lengths that follow the
    // local density (h ∝ n^(-1/3)) and equal masses.
    let mut rng = SmallRng(2026);
    let clumps: Vec<([f32; 3], f32, f32)> = (0..64)
        .map(|_| ([rng.f(), rng.f(), rng.f()], 0.02 + 0.1 * rng.f(), rng.f()))
        .collect();
    let total: f32 = clumps.iter().map(|c| c.2).sum();
    let mut pos = Vec::with_capacity(3 * n);
    let mut h = Vec::with_capacity(n);
    for c in &clumps {
        let m = ((c.2 / total) * n as f32) as usize;
        for _ in 0..m {
            for a in 0..3 {
                pos.push(c.0[a] + c.1 * rng.normal());
            }
            h.push(1.2 * c.1 * (c.2 / total * n as f32).powf(-1.0 / 3.0) * 3.0);
        }
    }
    while h.len() < n {
        pos.extend([rng.f(), rng.f(), rng.f()]);
        h.push(0.01);
    }
    let m = vec![1.0 / n as f32; n];
    let write = |name: &str, shape: &[usize], v: &[f32]| {
        voxless_io::write_npy_f32(&dir.join(name), shape, v)
    };
    write("particles/positions.npy", &[n, 3], &pos)?;
    write("particles/h.npy", &[n], &h)?;
    write("particles/mass.npy", &[n], &m)?;
    let coarse = voxless_io::read_npy(jaxpm)?;
    let grid = voxless_tets::LagrangianGrid {
        n: 64,
        box_size: 100.0,
        positions: coarse
            .data
            .chunks_exact(3)
            .map(|c| voxless_core::Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32))
            .collect(),
    };
    let fine = crate::tets::refine(&grid);
    let flat: Vec<f32> = fine.positions.iter().flat_map(|p| p.to_array()).collect();
    write("tets128/positions.npy", &[fine.positions.len(), 3], &flat)?;
    eprintln!(
        "wrote {n} particles to {} and {} Lagrangian particles (128³) to {}",
        dir.join("particles").display(),
        fine.positions.len(),
        dir.join("tets128").display()
    );
    Ok(())
}
