//! `voxless-bench`: the performance numbers quoted in `docs/benchmarks.md`,
//! measured through the `voxless` library (the same volumes, defaults and
//! integrator `voxless render` uses), not through copies of it.
//!
//! ```sh
//! cargo run --release -p voxless-bench -- bvh|frame|packets|amr|tets|parallel|serve|surfaces [flags]
//! ```
//!
//! Every benchmark reports a ratio against a baseline measured in the same
//! run, so numbers from different machines (or a busy machine) stay
//! comparable; absolute times are printed too but are only indicative.
//! Timings are the median of `--repeats` runs. Results go to stdout as
//! markdown tables headed by the machine (CPU model, thread count) and the
//! date; progress goes to stderr.
//!
//! - `bvh`: the particle BVH alone — build, rebuild, refit and memory for
//!   cluster sizes 1–16, and `ParticleVolume::set_radius` against `new`
//!   ([`bvh`]).
//! - `frame`: what clustering buys in a rendered frame ([`frame`]).
//! - `packets`: the packet path against per-sample point queries, a radius
//!   sweep, blue against white noise with shadows ([`packets`]).
//! - `amr`: AMR build, transfer-function changes, reconstruction through
//!   regions against cell location, adaptive sampling and space skipping
//!   ([`amr`]).
//! - `tets`: phase-space tessellations — build, projection, exact render,
//!   block culling, k-buffer and level of detail ([`tets`]).
//! - `parallel`: sort-last compositing against image size and rank count,
//!   and the inputs of the per-rank memory measurements ([`parallel`]).
//! - `serve`: `voxless serve` as a client sees it — camera move to the
//!   first coarse image and to the converged image ([`serve`]).
//! - `surfaces`: the dam break with a 10⁶-triangle mesh and with ambient
//!   occlusion, against the volume alone ([`surfaces`]).
//!
//! Variants the library does not offer (an AMR volume that hands out every
//! interval, a tessellation with every block in every tile) are small
//! wrappers over the `Volume` seam in these modules, rendered by the shared
//! integrator.

mod amr;
mod bvh;
mod common;
mod frame;
mod packets;
mod parallel;
mod serve;
mod surfaces;
mod tets;

/// Large arrays on huge pages where the kernel offers them (see the
/// library's `huge_pages`).
#[global_allocator]
static ALLOC: voxless::huge_pages::HugePages = voxless::huge_pages::HugePages;

use anyhow::Result;
use clap::{Parser, Subcommand};

/// Run the benchmarks and print markdown tables (see docs/benchmarks.md).
#[derive(Parser)]
#[command(name = "voxless-bench", version)]
struct Cli {
    #[command(subcommand)]
    which: Which,
}

#[derive(Subcommand)]
enum Which {
    /// BVH build / rebuild / refit times and memory for cluster sizes 1–16,
    /// plus ParticleVolume::set_radius against ParticleVolume::new.
    Bvh(bvh::BvhArgs),
    /// Packet traversal vs per-sample point queries (same image), a radius
    /// sweep for clustered and unclustered trees, and blue vs white noise
    /// frame time with volumetric shadows.
    Packets(packets::PacketArgs),
    /// Frame time with clustered (8) vs unclustered (1) BVH leaves, and the
    /// max difference between the two images.
    Frame(frame::FrameArgs),
    /// AMR: build statistics and times (ExaBricks Table 1), reconstruction via
    /// cell location vs via regions (Table 3), and frame time with adaptive
    /// sampling and TF space skipping on and off.
    Amr(amr::AmrArgs),
    /// Phase-space tessellations: build, projection and exact frame times
    /// (64³ JaxPM run, optionally a refined 128³), block culling, k-buffer
    /// size and level of detail against exact mode.
    Tets(tets::TetsArgs),
    /// Data-parallel rendering: direct-send compositing time against image
    /// size and rank count; the inputs of the per-rank memory runs.
    Parallel(parallel::ParallelArgs),
    /// `voxless serve` over a websocket: camera move → first (coarse) image
    /// and → converged 1024² image, on the dam break and the 64³
    /// tessellation.
    Serve(serve::ServeArgs),
    /// Frame time of the dam break with a 10⁶-triangle mesh and with 2
    /// ambient-occlusion rays, against the volume alone.
    Surfaces(surfaces::SurfacesArgs),
}

fn main() {
    if let Err(e) = run(Cli::parse().which) {
        eprintln!("error: {}", describe(&e));
        std::process::exit(1);
    }
}

/// The error and its causes on one line (no backtrace), skipping a cause
/// whose text the message above it already contains (library errors often
/// embed their source).
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

fn run(which: Which) -> Result<()> {
    match which {
        Which::Bvh(o) => bvh::run(o),
        Which::Packets(o) => packets::run(o),
        Which::Frame(o) => frame::run(o),
        Which::Amr(o) => amr::run(o),
        Which::Tets(o) => tets::run(o),
        Which::Parallel(o) => parallel::run(o),
        Which::Serve(o) => serve::run(o),
        Which::Surfaces(o) => surfaces::run(o),
    }
}
