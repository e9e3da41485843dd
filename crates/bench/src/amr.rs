//! `voxless-bench amr`: the AMR numbers quoted in `docs/benchmarks.md`.
//!
//! Data sets: frames 2 and 3 of the AMRClaw 3D Euler run converted to
//! ExaBricks files in `--amr-dir` (`exabricks/frameN.cells` and every
//! `exabricks/frameN.*.scalars`; the opacity field is `density`), skipped with
//! a notice when the directory is missing; and a synthetic multi-level set of
//! about `--cells` cells ([`data::synthetic`]), generated deterministically.
//!
//! - **Build** (ExaBricks Table 1): cells, bricks, regions, bricks per region
//!   (by count and by volume) and the phases `AmrVolume::new` times itself
//!   (validate, brick build, region build with metadata, BVH build), median of
//!   `--repeats`; the wall time of the whole `new` is the baseline the phases
//!   are a share of. Then a transfer-function change: a new
//!   `AmrContext::new` (the regions the TF can see and a mask of the region
//!   tree's subtrees holding them; what `voxless_render::render` prepares
//!   per frame) with a TF whose opacity is
//!   zero below the median of the regions' (normalised) maxima, so it hides
//!   about half the regions, against `new`.
//! - **Reconstruction** (Table 3): the same points reconstructed through
//!   `CellLocator` (a BVH over every cell's support, then the basis sum over
//!   the cells found: the baseline, Wald et al.'s cell location) and through
//!   the regions: `AmrVolume::sample_in` with the point's region as the hint,
//!   as the renderer does inside a ray interval (the paper's setup: regions
//!   decide where to sample in both variants), and `AmrVolume::sample`, which
//!   first locates the region through the region BVH. All run with rayon over
//!   the points and collect the values; reported: the times, the speedup of
//!   the region-known path (the target) and of `sample`, the max abs
//!   difference where both have a value, and mismatches (a point covered by
//!   one path only, or `sample` ≠ `sample_in`). Point sets: the sample
//!   positions of rays through random pixels ([`recon::ray_samples`]), uniform in
//!   the bounds (dominated by coarse cells, as volume is), and one uniform
//!   point in each of N random cells (dominated by fine cells).
//! - **Frame** ([`frame`]): `--size`² frames of frame 3 and of the synthetic
//!   set through the shared integrator (`Camera::framing`,
//!   `RenderSettings::for_volume`, viridis, opacity 0 below the cut of the
//!   TF-change table, then linear to 1: about half the regions invisible).
//!   Adaptive sampling on: the default step, half the finest cell width of
//!   each region; off: `settings.step` = half the finest cell width of the
//!   whole volume. TF space skipping on: the context `AmrContext::new` builds
//!   for the TF (what `voxless_render::render` prepares) masks the subtrees
//!   of the region tree without a visible region, so the walk skips them;
//!   off: a context with every region in it. The contexts are built before the timer starts.
//!   Either context still drops intervals whose range the TF makes
//!   invisible, so "off" does not sample them; the two extra "none" rows
//!   wrap the volume so that every interval is handed out and sampled (no
//!   skipping at all). Speedups and max abs RGBA differences are against
//!   (adaptive off, skipping off).

mod data;
mod frame;
mod recon;

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use voxless_amr::{AmrCells, AmrContext, AmrSettings, AmrVolume};
use voxless_core::Range1;
use voxless_transfer::{Colormap, OpacityMap, TransferFunction};

use crate::common::{count, median, ms, print_header, verdict};

#[derive(clap::Args)]
pub struct AmrArgs {
    /// Directory holding exabricks/frame{2,3}.cells and their .scalars; the
    /// real-data parts are skipped (with a notice) when it does not exist.
    #[arg(long, value_name = "DIR", default_value = "../shared/data/amr-euler3d")]
    amr_dir: PathBuf,
    /// Cells of the synthetic multi-level set (approximately).
    #[arg(long, default_value_t = 10_000_000)]
    cells: usize,
    /// Frame width and height in pixels.
    #[arg(long, default_value_t = 1024)]
    size: u32,
    /// Sample points per point set for the reconstruction comparison.
    #[arg(long, default_value_t = 1_000_000)]
    points: usize,
    /// Timed runs per build and reconstruction measurement (the median is reported).
    #[arg(long, default_value_t = 3)]
    repeats: usize,
    /// Timed renders per frame configuration (the median is reported).
    #[arg(long, default_value_t = 3)]
    frame_repeats: usize,
    /// Which data sets get frames: frame 3 and the synthetic set, frame 3 only, or none.
    #[arg(long, default_value = "all", value_parser = ["all", "real", "none"])]
    frames: String,
    /// Write the rendered frames as PNGs into this directory.
    #[arg(long, value_name = "DIR")]
    save: Option<PathBuf>,
}

struct Dataset {
    label: String,
    cells: AmrCells,
    /// Opacity field.
    field: usize,
    /// Whether the frame benchmark renders it.
    frame: bool,
}

pub fn run(o: AmrArgs) -> Result<()> {
    if o.cells == 0 || o.size == 0 || o.points == 0 || o.repeats == 0 || o.frame_repeats == 0 {
        bail!("--cells, --size, --points, --repeats and --frame-repeats must be ≥ 1");
    }
    if let Some(dir) = &o.save {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let mut sets = Vec::new();
    let real = o.amr_dir.is_dir();
    if real {
        for frame in [2, 3] {
            eprintln!("amr: reading frame {frame}");
            let (cells, field) = data::read_frame(&o.amr_dir, frame)?;
            sets.push(Dataset {
                label: format!("euler3d frame {frame}"),
                cells,
                field,
                frame: frame == 3 && o.frames != "none",
            });
        }
    }
    eprintln!("amr: generating about {} synthetic cells", o.cells);
    let t = Instant::now();
    let cells = data::synthetic(o.cells);
    eprintln!(
        "amr: {} synthetic cells in {:.1} s",
        cells.cells.len(),
        t.elapsed().as_secs_f64()
    );
    sets.push(Dataset {
        label: format!("synthetic {}", mcells(cells.cells.len())),
        cells,
        field: 0,
        frame: o.frames == "all",
    });

    print_header();
    if !real {
        println!(
            "Real data skipped: {} is not a directory (pass --amr-dir DIR).\n",
            o.amr_dir.display()
        );
        eprintln!(
            "note: {} not found; benchmarking the synthetic set only",
            o.amr_dir.display()
        );
    }
    let mut vols = Vec::new();
    let mut build_rows = Vec::new();
    for s in &sets {
        let (vol, row) = bench_build(s, o.repeats)?;
        vols.push(vol);
        build_rows.push(row);
    }
    println!(
        "### AMR build (ExaBricks Table 1), median of {}\n\n\
         \"sum\" = validate + bricks + regions (with metadata) + BVHs; \"`new`\" is the \
         wall time of `AmrVolume::new` (the baseline; the rest is input checks and \
         field ranges).\n",
        o.repeats
    );
    println!(
        "| data set | cells | bricks | regions | bricks/region by count | by volume \
         | validate ms | bricks ms | regions ms | BVH ms | sum ms | `new` ms | sum / `new` |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in &build_rows {
        println!("{}", r.line);
    }
    let syn = build_rows
        .last()
        .expect("the synthetic set is always there");
    let n = sets.last().map_or(1, |s| s.cells.cells.len());
    let scaled = syn.sum * 1e7 / n as f64;
    println!(
        "\nTarget (validate + bricks + regions + BVH ≤ 2 s for 10M cells on 2 cores): \
         {} cells {:.2} s, scaled linearly to 10M {scaled:.2} s ({}).\n",
        count(n),
        syn.sum,
        verdict(scaled <= 2.0)
    );

    // Transfer-function change.
    println!(
        "### TF change: `AmrContext::new` with a TF hiding about half the regions, median of {}\n",
        o.repeats
    );
    println!(
        "| data set | regions | visible | `AmrContext::new` ms | / BVH build in `new` | / `new` \
         | `AmrContext::new` (all visible) ms |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|");
    for ((s, vol), b) in sets.iter().zip(&vols).zip(&build_rows) {
        eprintln!("amr/{}: AmrContext::new", s.label);
        let regions = vol.regions().len();
        let vr = vol.field_range(s.field);
        let tf = half_tf(vol, s.field)?;
        let visible = |r: Range1| tf.max_opacity(vr.normalize(r.lo), vr.normalize(r.hi)) > 0.0;
        let (mut half, mut all) = (Vec::new(), Vec::new());
        let mut shown = 0;
        for _ in 0..o.repeats {
            // The context times its own selection and BVH build.
            let ctx = AmrContext::new(vol, &visible);
            half.push(ctx.selected_in().as_secs_f64());
            shown = ctx.visible_region_count();
            drop(ctx);
            all.push(AmrContext::new(vol, &|_| true).selected_in().as_secs_f64());
        }
        let (half, all) = (median(half), median(all));
        println!(
            "| {} | {regions} | {shown} ({:.0} %) | {:.1} | {:.2} | {:.3} | {:.1} |",
            s.label,
            100.0 * shown as f64 / regions.max(1) as f64,
            ms(half),
            half / b.bvh,
            half / b.new,
            ms(all)
        );
    }
    println!();

    // Reconstruction.
    println!(
        "### Reconstruction (ExaBricks Table 3): the same points via cell location vs via \
         regions, rayon over the points, median of {}\n",
        o.repeats
    );
    println!(
        "| data set | points | covered | via cell location ms | via regions (region known) ms \
         | speedup | via regions incl. locate ms | speedup incl. locate | max abs diff \
         | mismatches | `CellLocator::new` ms |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut speedups = Vec::new();
    for (s, vol) in sets.iter().zip(&vols) {
        for line in recon::bench_recon(s, vol, o.points, o.repeats, &mut speedups) {
            println!("{line}");
        }
    }
    let per_set: Vec<String> = sets
        .iter()
        .map(|set| {
            let v: Vec<f64> = speedups
                .iter()
                .filter(|x| x.0 == set.label)
                .map(|x| x.1)
                .collect();
            let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = v.iter().copied().fold(0.0, f64::max);
            format!("{} {lo:.2}–{hi:.2}× ({})", set.label, verdict(lo >= 3.0))
        })
        .collect();
    println!(
        "\nTarget (regions, region known, ≥ 3× faster than cell location; paper 1.9–5.1×): {}.\n",
        per_set.join("; ")
    );

    // Frames.
    let mut rows = Vec::new();
    for (s, vol) in sets.iter().zip(&vols) {
        if s.frame {
            rows.extend(frame::bench_frames(s, vol, &o)?);
        }
    }
    if !rows.is_empty() {
        let (size, repeats) = (o.size, o.frame_repeats);
        println!(
            "### AMR frame: {size}×{size}, 1 spp, sampling rate 1, the TF of the TF-change \
             table (opacity 0 below the cut), median of {repeats}\n"
        );
        println!(
            "| data set | TF cut | adaptive sampling | TF space skipping | regions walked | step \
             | samples / pixel | frame s | speedup vs (off, off) | max abs diff vs (off, off) |"
        );
        println!("|---|---:|---|---|---:|---|---:|---:|---:|---:|");
        for r in rows {
            println!("{r}");
        }
        println!();
    }
    Ok(())
}

/// Viridis with opacity 0 up to just above the median of the regions'
/// normalised maxima of `field`, then linear to 1: hides about half the
/// regions (more where many regions share the median, as ambient values do).
/// The margin covers `TransferFunction::max_opacity`'s 1/256 bins.
fn half_tf(vol: &AmrVolume, field: usize) -> Result<TransferFunction> {
    let vr = vol.field_range(field);
    let his: Vec<f64> = (0..vol.regions().len())
        .map(|r| vr.normalize(vol.region_range(r, field).hi) as f64)
        .collect();
    let cut = (median(his) as f32 + 1.5 / 256.0).clamp(0.01, 0.99);
    Ok(TransferFunction::new(
        Colormap::preset("viridis")?,
        OpacityMap::from_points(&[(0.0, 0.0), (cut, 0.0), (1.0, 1.0)])?,
    ))
}

/// 10234567 → "10.2M cells"-style label.
fn mcells(n: usize) -> String {
    if n >= 1_000_000 {
        format!("{:.1}M", n as f64 / 1e6)
    } else {
        n.to_string()
    }
}

// ---------------------------------------------------------------- build

struct BuildRow {
    line: String,
    /// Seconds: validate + bricks + regions + BVH, BVH alone, whole `new`.
    sum: f64,
    bvh: f64,
    new: f64,
}

fn bench_build(s: &Dataset, repeats: usize) -> Result<(AmrVolume, BuildRow)> {
    let settings = AmrSettings {
        field: s.field,
        ..Default::default()
    };
    let mut t = [(); 6].map(|_| Vec::new());
    let mut vol = None;
    for k in 0..repeats {
        eprintln!("amr/{}: AmrVolume::new ({}/{repeats})", s.label, k + 1);
        drop(vol.take());
        let cells = s.cells.clone();
        let start = Instant::now();
        let v = AmrVolume::new(cells, settings.clone())
            .with_context(|| format!("building {}", s.label))?;
        let wall = start.elapsed().as_secs_f64();
        let st = v.stats();
        let phases =
            [st.validate, st.brick_build, st.region_build, st.bvh_build].map(|d| d.as_secs_f64());
        for (i, x) in phases.into_iter().enumerate() {
            t[i].push(x);
        }
        t[4].push(phases.iter().sum());
        t[5].push(wall);
        vol = Some(v);
    }
    let vol = vol.expect("repeats ≥ 1");
    let [validate, bricks, regions, bvh, sum, new] = t.map(median);
    let st = vol.stats();
    let line = format!(
        "| {} | {} | {} | {} | {:.2} | {:.2} | {:.0} | {:.0} | {:.0} | {:.0} | {:.0} | {:.0} | {:.2} |",
        s.label,
        st.cells,
        st.bricks,
        st.regions,
        st.bricks_per_region,
        st.bricks_per_region_by_volume,
        ms(validate),
        ms(bricks),
        ms(regions),
        ms(bvh),
        ms(sum),
        ms(new),
        sum / new
    );
    Ok((
        vol,
        BuildRow {
            line,
            sum,
            bvh,
            new,
        },
    ))
}
