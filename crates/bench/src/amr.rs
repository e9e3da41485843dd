//! `voxless bench amr`: the AMR numbers quoted in `docs/benchmarks.md`.
//!
//! Data sets: frames 2 and 3 of the AMRClaw 3D Euler run converted to
//! ExaBricks files in `--amr-dir` (`exabricks/frameN.cells` and every
//! `exabricks/frameN.*.scalars`; the opacity field is `density`), skipped with
//! a notice when the directory is missing; and a synthetic multi-level set of
//! about `--cells` cells ([`synthetic`]), generated deterministically.
//!
//! - **Build** (ExaBricks Table 1): cells, bricks, regions, bricks per region
//!   (by count and by volume) and the phases `AmrVolume::new` times itself
//!   (validate, brick build, region build with metadata, BVH build), median of
//!   `--repeats`; the wall time of the whole `new` is the baseline the phases
//!   are a share of. Then a transfer-function change: `set_visibility` with a
//!   TF whose opacity is zero below the median of the regions' (normalised)
//!   maxima, so it hides about half the regions, against `new`.
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
//!   positions of rays through random pixels ([`ray_samples`]), uniform in
//!   the bounds (dominated by coarse cells, as volume is), and one uniform
//!   point in each of N random cells (dominated by fine cells).
//! - **Frame**: `--size`² frames of frame 3 and of the synthetic set through
//!   `voxless::render::render` (`Camera::framing`, `RenderSettings::for_volume`,
//!   viridis, opacity 0 below the cut of the TF-change table, then linear to
//!   1: about half the regions invisible). Adaptive sampling on:
//!   the default step, half the finest cell width of each region; off:
//!   `settings.step` = half the finest cell width of the whole volume. TF space
//!   skipping on: `set_visibility` leaves the regions the TF makes invisible
//!   out of the interval BVH; off: every region in it. The renderer also drops
//!   intervals whose range the TF makes invisible, so "off" still does not
//!   sample them; the two extra "none" rows wrap the volume so that every
//!   interval is handed out and sampled (no skipping at all). Speedups and
//!   max abs RGBA differences are against (adaptive off, skipping off).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use rayon::prelude::*;
use voxless_amr::{AmrCells, AmrSettings, AmrVolume, CellLocator};
use voxless::core::{
    Aabb, Camera, Image, Interval, IntervalQuery, Range1, Ray, Sample, Vec3, Volume,
};
use voxless::render::RenderSettings;
use voxless::transfer::{Colormap, OpacityMap, TransferFunction};

use crate::bench::{count, image_diff, median, ms, print_header, save_png};

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
            let (cells, field) = read_frame(&o.amr_dir, frame)?;
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
    let cells = synthetic(o.cells);
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
         wall time of `AmrVolume::new` (the baseline; the rest is input checks, field \
         ranges and the first visibility pass).\n",
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
        "### TF change: `set_visibility` with a TF hiding about half the regions, median of {}\n",
        o.repeats
    );
    println!(
        "| data set | regions | visible | `set_visibility` ms | / BVH build in `new` | / `new` \
         | `set_visibility(all)` ms |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|");
    for ((s, vol), b) in sets.iter().zip(&mut vols).zip(&build_rows) {
        eprintln!("amr/{}: set_visibility", s.label);
        let regions = vol.regions().len();
        let vr = vol.field_range(s.field);
        let tf = half_tf(vol, s.field)?;
        let visible = |r: Range1| tf.max_opacity(vr.normalize(r.lo), vr.normalize(r.hi)) > 0.0;
        let (mut half, mut all) = (Vec::new(), Vec::new());
        let mut shown = 0;
        for _ in 0..o.repeats {
            half.push(vol.set_visibility(&visible).as_secs_f64());
            shown = vol.visible_region_count();
            all.push(vol.set_visibility(&|_| true).as_secs_f64());
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
        for line in bench_recon(s, vol, o.points, o.repeats, &mut speedups) {
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
    for (s, vol) in sets.iter().zip(&mut vols) {
        if s.frame {
            rows.extend(bench_frames(s, vol, &o)?);
        }
    }
    if !rows.is_empty() {
        let (size, repeats) = (o.size, o.frame_repeats);
        println!(
            "### AMR frame: {size}×{size}, 1 spp, sampling rate 1, the TF of the TF-change \
             table (opacity 0 below the cut), median of {repeats}\n"
        );
        println!(
            "| data set | TF cut | adaptive sampling | TF space skipping | regions in BVH | step \
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

fn verdict(ok: bool) -> &'static str {
    if ok { "met" } else { "not met" }
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

// ---------------------------------------------------------------- reconstruction

fn bench_recon(
    s: &Dataset,
    vol: &AmrVolume,
    n: usize,
    repeats: usize,
    speedups: &mut Vec<(String, f64)>,
) -> Vec<String> {
    eprintln!("amr/{}: CellLocator::new", s.label);
    let t = Instant::now();
    let loc = CellLocator::new(&s.cells, s.field);
    let t_loc = t.elapsed().as_secs_f64();
    let mut rng = Rng::new(0x5eed_0000 ^ s.cells.cells.len() as u64);
    let b = vol.bounds();
    let uniform: Vec<Vec3> = (0..n)
        .map(|_| {
            let u = Vec3::new(rng.unit(), rng.unit(), rng.unit());
            b.min + b.extent().mul_elem(u)
        })
        .collect();
    let (o, h) = (s.cells.origin, s.cells.cell_size);
    let in_cells: Vec<Vec3> = (0..n)
        .map(|_| {
            let c = s.cells.cells[rng.below(s.cells.cells.len())];
            let w = (1i64 << c[3]) as f32;
            let u = Vec3::new(rng.unit(), rng.unit(), rng.unit());
            o + (Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) + u * w) * h
        })
        .collect();
    let on_rays = ray_samples(vol, n, &mut rng);
    let mut rows = Vec::new();
    for (what, pts) in [
        ("ray samples", &on_rays),
        ("uniform in bounds", &uniform),
        ("one in each of N random cells", &in_cells),
    ] {
        eprintln!("amr/{}: reconstruction, {what}", s.label);
        // The region of each point, as a ray's interval would hand it over.
        let hints: Vec<u32> = pts
            .par_iter()
            .map(|&p| vol.locate(p).map_or(Interval::NO_HINT, |r| r as u32))
            .collect();
        let interval = |hint| Interval {
            t: Range1::EMPTY,
            value_range: Range1::EMPTY,
            nominal_dt: 0.0,
            hint,
        };
        // Repeats go round the three variants (see `bench_frames`).
        let (mut times, mut a, mut r, mut r2) =
            ([(); 3].map(|_| Vec::new()), vec![], vec![], vec![]);
        for _ in 0..repeats {
            let t = Instant::now();
            a = pts.par_iter().map(|&p| loc.sample(p)).collect::<Vec<_>>();
            times[0].push(t.elapsed().as_secs_f64());
            let t = Instant::now();
            r = pts
                .par_iter()
                .zip(&hints)
                .map(|(&p, &hint)| match hint {
                    Interval::NO_HINT => None,
                    _ => vol.sample_in(p, &interval(hint)).map(|x| x.value),
                })
                .collect::<Vec<_>>();
            times[1].push(t.elapsed().as_secs_f64());
            let t = Instant::now();
            r2 = pts
                .par_iter()
                .map(|&p| vol.sample(p).map(|x| x.value))
                .collect::<Vec<_>>();
            times[2].push(t.elapsed().as_secs_f64());
        }
        let [t_cell, t_in, t_sample] = times.map(median);
        let (mut max_diff, mut covered, mut one_only) = (0.0f32, 0usize, 0usize);
        for ((x, y), y2) in a.iter().zip(&r).zip(&r2) {
            match (x, y) {
                (Some(x), Some(y)) => {
                    max_diff = max_diff.max((x - y).abs());
                    covered += 1;
                }
                (None, None) => {}
                _ => one_only += 1,
            }
            if y != y2 {
                one_only += 1;
            }
        }
        speedups.push((s.label.clone(), t_cell / t_in));
        rows.push(format!(
            "| {} | {what}, {} | {:.1} % | {:.1} | {:.1} | {:.2} | {:.1} | {:.2} | {max_diff:.2e} | {one_only} | {:.0} |",
            s.label,
            count(n),
            100.0 * covered as f64 / n as f64,
            ms(t_cell),
            ms(t_in),
            t_cell / t_in,
            ms(t_sample),
            t_cell / t_sample,
            ms(t_loc)
        ));
    }
    rows
}

/// `n` sample positions of rays through random pixels of a 1024² framing
/// view: every interval of every region (no TF), stepped at half the region's
/// finest cell width from a random offset, segment midpoints — where the
/// renderer samples with adaptive sampling and no space skipping.
fn ray_samples(vol: &AmrVolume, n: usize, rng: &mut Rng) -> Vec<Vec3> {
    let camera = Camera::framing(&vol.bounds(), 1.0);
    let mut out = Vec::with_capacity(n);
    let mut ivs = Vec::new();
    let mut misses = 0;
    while out.len() < n && misses < 1_000_000 {
        let ray = camera.ray(rng.unit() * 1024.0, rng.unit() * 1024.0, 1024, 1024);
        let t = vol.bounds().clip_ray(&ray, Range1::new(0.0, f32::INFINITY));
        ivs.clear();
        if !t.is_empty() {
            vol.intervals(&ray, t, &IntervalQuery::all(), &mut ivs);
        }
        if ivs.is_empty() {
            misses += 1;
        }
        for iv in &ivs {
            let dt = iv.nominal_dt.max(iv.t.span() * 1e-6);
            let mut t0 = iv.t.lo;
            let mut t1 = iv.t.lo + rng.unit() * dt;
            while t0 < iv.t.hi && out.len() < n {
                let end = t1.min(iv.t.hi);
                out.push(ray.at(0.5 * (t0 + end)));
                t0 = end;
                t1 = end + dt;
            }
        }
    }
    out
}

// ---------------------------------------------------------------- frame

/// The volume with every interval handed out, visible or not: what the
/// renderer does without any transfer-function space skipping.
struct NoSkip<'a>(&'a AmrVolume);

impl Volume for NoSkip<'_> {
    fn bounds(&self) -> Aabb {
        self.0.bounds()
    }
    fn value_range(&self) -> Range1 {
        self.0.value_range()
    }
    fn attribute_range(&self) -> Option<Range1> {
        self.0.attribute_range()
    }
    fn sample(&self, p: Vec3) -> Option<Sample> {
        self.0.sample(p)
    }
    fn gradient(&self, p: Vec3) -> Vec3 {
        self.0.gradient(p)
    }
    fn sample_with_gradient(&self, p: Vec3) -> Option<(Sample, Vec3)> {
        self.0.sample_with_gradient(p)
    }
    fn sample_in(&self, p: Vec3, iv: &Interval) -> Option<Sample> {
        self.0.sample_in(p, iv)
    }
    fn sample_with_gradient_in(&self, p: Vec3, iv: &Interval) -> Option<(Sample, Vec3)> {
        self.0.sample_with_gradient_in(p, iv)
    }
    fn intervals(&self, ray: &Ray, t: Range1, _: &IntervalQuery, out: &mut Vec<Interval>) {
        self.0.intervals(ray, t, &IntervalQuery::all(), out)
    }
    fn line_integral(&self, ray: &Ray, t: Range1) -> f64 {
        self.0.line_integral(ray, t)
    }
}

/// Counts the samples the renderer takes (an untimed pass).
struct Counting<'a, V> {
    inner: &'a V,
    samples: AtomicU64,
}

impl<V: Volume> Counting<'_, V> {
    fn tick(&self) {
        self.samples.fetch_add(1, Ordering::Relaxed);
    }
}

impl<V: Volume> Volume for Counting<'_, V> {
    fn bounds(&self) -> Aabb {
        self.inner.bounds()
    }
    fn value_range(&self) -> Range1 {
        self.inner.value_range()
    }
    fn attribute_range(&self) -> Option<Range1> {
        self.inner.attribute_range()
    }
    fn sample(&self, p: Vec3) -> Option<Sample> {
        self.tick();
        self.inner.sample(p)
    }
    fn sample_with_gradient(&self, p: Vec3) -> Option<(Sample, Vec3)> {
        self.tick();
        self.inner.sample_with_gradient(p)
    }
    fn sample_in(&self, p: Vec3, iv: &Interval) -> Option<Sample> {
        self.tick();
        self.inner.sample_in(p, iv)
    }
    fn sample_with_gradient_in(&self, p: Vec3, iv: &Interval) -> Option<(Sample, Vec3)> {
        self.tick();
        self.inner.sample_with_gradient_in(p, iv)
    }
    fn intervals(&self, ray: &Ray, t: Range1, q: &IntervalQuery, out: &mut Vec<Interval>) {
        self.inner.intervals(ray, t, q, out)
    }
    fn line_integral(&self, ray: &Ray, t: Range1) -> f64 {
        self.inner.line_integral(ray, t)
    }
}

/// Samples per pixel `render` takes on `v` at a quarter of the resolution
/// (per pixel the count hardly depends on the resolution).
fn samples_per_pixel<V: Volume>(
    v: &V,
    camera: &Camera,
    tf: &TransferFunction,
    rs: &RenderSettings,
) -> f64 {
    let mut rs = rs.clone();
    rs.width = (rs.width / 4).max(16);
    rs.height = (rs.height / 4).max(16);
    let c = Counting {
        inner: v,
        samples: AtomicU64::new(0),
    };
    voxless::render::render(&c, camera, tf, &rs, &|_, _| {});
    c.samples.load(Ordering::Relaxed) as f64 / (rs.width as f64 * rs.height as f64)
}

fn bench_frames(s: &Dataset, vol: &mut AmrVolume, o: &AmrArgs) -> Result<Vec<String>> {
    let tf = half_tf(vol, s.field)?;
    let cut = tf.opacity_map().0.points()[1].0;
    let camera = Camera::framing(&vol.bounds(), 1.0);
    let adaptive = RenderSettings::for_volume(&*vol, o.size, o.size);
    let finest = vol.bricks().iter().map(|b| b.width()).min().unwrap_or(1);
    let mut fixed = adaptive.clone();
    fixed.step = Some(0.5 * finest as f32 * s.cells.cell_size);
    // The renderer's own test (`march`), without iso-surfaces.
    let tf_visible =
        |r: Range1| tf.max_opacity(adaptive.normalize(r.lo), adaptive.normalize(r.hi)) > 0.0;
    let onoff = |b: bool| if b { "on" } else { "off" };
    // (adaptive, skipping): Some(true/false) = BVH of visible/all regions,
    // None = no skipping at all (every interval sampled).
    let configs = [
        (false, Some(false)),
        (true, Some(false)),
        (false, Some(true)),
        (true, Some(true)),
        (false, None),
        (true, None),
    ];
    // Repeats go round all configurations, so that load from elsewhere on
    // the machine hits every configuration alike.
    let mut times = vec![Vec::new(); configs.len()];
    let mut images = vec![None; configs.len()];
    let mut in_bvh = vec![0; configs.len()];
    let mut spp = vec![0.0; configs.len()];
    for (k, &(adapt, skip)) in configs.iter().enumerate() {
        eprintln!("amr/{}: counting samples, config {}", s.label, k + 1);
        if skip == Some(true) {
            vol.set_visibility(&tf_visible);
        } else {
            vol.set_visibility(&|_| true);
        }
        let rs = if adapt { &adaptive } else { &fixed };
        spp[k] = match skip {
            Some(_) => samples_per_pixel(&*vol, &camera, &tf, rs),
            None => samples_per_pixel(&NoSkip(vol), &camera, &tf, rs),
        };
    }
    for rep in 0..o.frame_repeats {
        for (k, &(adapt, skip)) in configs.iter().enumerate() {
            if skip == Some(true) {
                vol.set_visibility(&tf_visible);
            } else {
                vol.set_visibility(&|_| true);
            }
            in_bvh[k] = vol.visible_region_count();
            let rs = if adapt { &adaptive } else { &fixed };
            eprintln!(
                "amr/{}: rendering ({}/{}), adaptive {}, skipping {}",
                s.label,
                rep + 1,
                o.frame_repeats,
                onoff(adapt),
                skip.map_or("none", onoff)
            );
            let t = Instant::now();
            let img = match skip {
                Some(_) => voxless::render::render(&*vol, &camera, &tf, rs, &|_, _| {}),
                None => voxless::render::render(&NoSkip(vol), &camera, &tf, rs, &|_, _| {}),
            };
            times[k].push(t.elapsed().as_secs_f64());
            images[k] = Some(img);
        }
    }
    let times: Vec<f64> = times.into_iter().map(median).collect();
    let images: Vec<Image> = images.into_iter().flatten().collect();
    let mut rows = Vec::new();
    for (k, &(adapt, skip)) in configs.iter().enumerate() {
        if let Some(dir) = &o.save {
            let stem = format!(
                "{}-adaptive-{}-skip-{}",
                s.label.replace(' ', "-"),
                onoff(adapt),
                skip.map_or("none", onoff)
            );
            save_png(&dir.join(format!("{stem}.png")), &images[k])?;
        }
        let diff = image_diff(&images[0], &images[k]).0;
        let skipping = match skip {
            Some(true) => "on (BVH of visible regions)",
            Some(false) => "off (BVH of all regions)",
            None => "none (every interval sampled)",
        };
        let step = match (if adapt { &adaptive } else { &fixed }).step {
            Some(dt) => format!("{dt:.3e} fixed"),
            None => "½ region finest".into(),
        };
        rows.push(format!(
            "| {} | {cut:.3} | {} | {skipping} | {} | {step} | {:.0} | {:.2} | {:.2} | {diff:.2e} |",
            s.label,
            onoff(adapt),
            in_bvh[k],
            spp[k],
            times[k],
            times[0] / times[k]
        ));
    }
    vol.set_visibility(&|_| true);
    Ok(rows)
}

// ---------------------------------------------------------------- data

/// ExaBricks frame `frame` in `dir/exabricks`: the cells and every
/// `frameN.*.scalars`, sorted by name; the opacity field is `density` if there
/// is one, else the first.
fn read_frame(dir: &Path, frame: u32) -> Result<(AmrCells, usize)> {
    let ex = dir.join("exabricks");
    let cells = ex.join(format!("frame{frame}.cells"));
    let prefix = format!("frame{frame}.");
    let mut scalars: Vec<PathBuf> = std::fs::read_dir(&ex)
        .with_context(|| format!("listing {}", ex.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with(&prefix) && n.ends_with(".scalars"))
        })
        .collect();
    scalars.sort();
    if scalars.is_empty() {
        bail!("no {prefix}*.scalars in {}", ex.display());
    }
    let d = voxless::io::read_exabricks(&cells, &scalars)?;
    let field = d.fields.iter().position(|f| f.0 == "density").unwrap_or(0);
    let o = d.origin.map(|v| v as f32);
    Ok((
        AmrCells {
            cells: d.cells,
            fields: d.fields,
            origin: Vec3::new(o[0], o[1], o[2]),
            cell_size: d.finest_cell_size as f32,
        },
        field,
    ))
}

/// About `target` leaf cells on four levels (level 3, 8 units wide, the
/// coarsest) in the unit cube: a G³ grid of level-3 cells, refined by aligned
/// patches of 4³ cells of one level (each cell into 8) when the patch comes
/// within 1.5 cell widths of a wavy spherical shell, or with probability 1/32
/// anywhere (hash of patch and level).
/// Level-3 cells outside the shell are left out in about 15 % of the 32-unit
/// blocks (holes). One field, "density": a smooth background in about
/// [0.08, 0.32] plus a peak of 0.65 on the shell. G is found by a few
/// counting passes.
fn synthetic(target: usize) -> AmrCells {
    let mut g = 64;
    let mut best = (usize::MAX, g);
    for _ in 0..8 {
        let n = Synth { g }.count();
        let err = n.abs_diff(target);
        if err < best.0 {
            best = (err, g);
        }
        if err * 100 < target {
            break;
        }
        let next = ((g as f64) * (target as f64 / n.max(1) as f64).powf(0.4)).round() as i32;
        let next = next.clamp(1, 1 << 17);
        if next == g {
            break;
        }
        g = next;
    }
    let s = Synth { g: best.1 };
    let cells: Vec<[i32; 4]> = (0..s.g)
        .into_par_iter()
        .flat_map_iter(|z| {
            let mut v = Vec::new();
            s.slice(z, &mut |c| v.push(c));
            v
        })
        .collect();
    let l = 8.0 * s.g as f64;
    let values = cells
        .par_iter()
        .map(|c| {
            let w = (1i64 << c[3]) as f64;
            s.value([0, 1, 2].map(|a| c[a] as f64 + 0.5 * w))
        })
        .collect();
    AmrCells {
        cells,
        fields: vec![("density".into(), values)],
        origin: Vec3::ZERO,
        cell_size: (1.0 / l) as f32,
    }
}

struct Synth {
    /// Level-3 cells per axis; the domain is 8g finest units wide.
    g: i32,
}

impl Synth {
    fn count(&self) -> usize {
        (0..self.g)
            .into_par_iter()
            .map(|z| {
                let mut n = 0usize;
                self.slice(z, &mut |_| n += 1);
                n
            })
            .sum()
    }

    /// Every leaf cell of the level-3 slice `z`, in order.
    fn slice(&self, z: i32, out: &mut dyn FnMut([i32; 4])) {
        for y in 0..self.g {
            for x in 0..self.g {
                let p = [8 * x, 8 * y, 8 * z];
                let c = p.map(|v| v as f64 + 4.0);
                let hole = hash([p[0] >> 5, p[1] >> 5, p[2] >> 5, 99]) % 100 < 15;
                if hole && self.shell(c) > 0.0 {
                    continue;
                }
                self.visit(p, 3, out);
            }
        }
    }

    fn visit(&self, p: [i32; 3], level: i32, out: &mut dyn FnMut([i32; 4])) {
        let w = 1 << level;
        // Refinement is decided per aligned block of 4³ cells of this level
        // (block-structured AMR refines patches, not single cells).
        let block = p.map(|v| v >> (level + 2));
        let bw = 4.0 * w as f64;
        let c = block.map(|b| (b as f64 + 0.5) * bw);
        let refine = level > 0
            && (self.shell(c).abs() < 0.87 * bw + 1.5 * w as f64
                || hash([block[0], block[1], block[2], level]).is_multiple_of(32));
        if !refine {
            out([p[0], p[1], p[2], level]);
            return;
        }
        let h = w / 2;
        for k in 0..8 {
            let q = [
                p[0] + (k & 1) * h,
                p[1] + (k >> 1 & 1) * h,
                p[2] + (k >> 2) * h,
            ];
            self.visit(q, level - 1, out);
        }
    }

    /// Signed distance-like function to the wavy shell, finest units
    /// (negative inside).
    fn shell(&self, c: [f64; 3]) -> f64 {
        let l = 8.0 * self.g as f64;
        let u = c.map(|v| v / l);
        let d = u.iter().map(|v| (v - 0.5) * (v - 0.5)).sum::<f64>().sqrt();
        let tau = std::f64::consts::TAU;
        let r = 0.3 + 0.03 * (3.0 * tau * u[0]).sin() * (3.0 * tau * u[1]).sin();
        (d - r) * l
    }

    fn value(&self, c: [f64; 3]) -> f32 {
        let l = 8.0 * self.g as f64;
        let u = c.map(|v| v / l);
        let tau = std::f64::consts::TAU;
        let background = 0.2 + 0.12 * (tau * (u[0] + u[1])).sin() * (tau * u[2]).cos();
        let s = self.shell(c) / (0.01 * l);
        (background + 0.65 * (-s * s).exp()) as f32
    }
}

/// splitmix64 of four coordinates.
fn hash(v: [i32; 4]) -> u64 {
    let mut x = v.iter().fold(0x243f_6a88_85a3_08d3u64, |h, &c| {
        (h ^ c as u32 as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)
    });
    x ^= x >> 30;
    x = x.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x ^= x >> 27;
    x = x.wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// xorshift64: deterministic, no dependency.
struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Rng {
        Rng(seed | 1)
    }
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    /// Uniform in (0, 1).
    fn unit(&mut self) -> f32 {
        ((self.next() >> 40) as f32 + 0.5) / (1u64 << 24) as f32
    }
    /// Uniform in 0..n.
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}
