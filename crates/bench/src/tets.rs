//! `voxless bench tets`: the phase-space tessellation numbers quoted in
//! `docs/benchmarks.md`.
//!
//! Data sets: the 64³ JaxPM run in `--data` (`positions.npy`, N³ × 3 in
//! Lagrangian order, periodic box `--box`), and with `--n128` a 128³ set made
//! from it by [`refine`]: the 2× finer Lagrangian grid's particles are the
//! trilinear interpolation of the 64³ particles' unwrapped positions at the
//! half-integer Lagrangian coordinates (equivalently, of their displacements
//! q → x), wrapped back into the box. This adds no new physics (the finer
//! particles follow the trilinear map of the coarse ones), but it gives 8×
//! the tets with the same folds and overlaps, which is what the renderer's
//! cost depends on.
//!
//! - **Main** (per data set): tessellation time (`TetMesh::new`, and the
//!   CLI's `TetVolume::new` with 0 and with 3 levels of detail, which adds
//!   the tet BVH and macrocells), tet, block and image counts; a `--size`²
//!   column-density projection (`render::project`, orthographic
//!   `Camera::axis_projection` down z over the box; mass conservation is
//!   checked) and an exact render (`render::render`, `TetMode::Exact`,
//!   `Camera::framing` and the render settings `voxless render` uses for
//!   tets: log10 scale over `TetVolume::value_range`, opacity scale
//!   100/diagonal, viridis with linear opacity). The 128³ targets on two
//!   cores: projection ≤ 3 s, exact render ≤ 30 s. Work counters explain the
//!   times: tet visits (a tet of a block binned to a tile, once per such
//!   tile), pixel tests (a ray clipped against a tet's planes) and crossings
//!   (tests that hit; two events each in exact mode).
//! - **Culling**: per view, the blocks binned to tiles against every block in
//!   every tile, and the exact render with the library's culled bins against
//!   the same render with every block put in every tile (the frame's bins
//!   are public; the render loop is repeated here, see [`exact_with`], and
//!   checked against `render::render`). Views: the framing view, a 4× zoom
//!   (same eye, field of view 7.5°), and a camera inside the box.
//! - **k-buffer**: `TetMode::KBuffer { k, layers: 64 }` for k = 4 … 64 against
//!   the exact render (time ratio, max and mean abs RGBA difference, share of
//!   covered pixels with at least k events, where the k-buffer is inexact).
//! - **LOD**: `TetOptions::lod_pixels` thresholds on the mesh with 3 coarser
//!   levels, against the same mesh without LOD (exact mode).
//!
//! `--export-subblock DIR` (hidden) writes a 32³-cell sub-block (196,608
//! tets) and its view for `tools/vtk_tets.py`, and times our exact render of
//! it; see docs/benchmarks.md.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use rayon::prelude::*;
use voxless::core::{Aabb, Camera, Image, Projection, Range1, Vec3, Volume};
use voxless::render::RenderSettings;
use voxless_tets::mesh::KUHN;
use voxless_tets::raster::{Frame, TILE, box_spans, for_each_crossing};
use voxless_tets::render::{project, render};
use voxless_tets::{
    BLOCK, Block, LagrangianGrid, Tet, TetMesh, TetMode, TetOptions, TetSettings, TetVolume,
};
use voxless::transfer::TransferFunction;

use crate::bench::{bench, image_diff, print_header, save_png};

mod subblock;
use subblock::export_subblock;

#[derive(clap::Args)]
pub struct TetsArgs {
    /// Directory holding positions.npy (N³×3, Lagrangian order (i·N + j)·N + k).
    #[arg(
        long,
        value_name = "DIR",
        default_value = "../shared/data/nbody-jaxpm/npy_N64_a1"
    )]
    data: PathBuf,
    /// Periodic box size of the data.
    #[arg(long = "box", default_value_t = 100.0)]
    box_size: f32,
    /// Image width and height in pixels.
    #[arg(long, default_value_t = 1024)]
    size: u32,
    /// Also bench a 128³ set refined from the data (trilinear interpolation
    /// of the unwrapped positions onto a 2× finer Lagrangian grid).
    #[arg(long)]
    n128: bool,
    /// Timed runs per measurement (the median is reported).
    #[arg(long, default_value_t = 2)]
    repeats: usize,
    /// Effects tables (culling, k-buffer, LOD) for: every data set, the
    /// largest only, or none.
    #[arg(long, default_value = "all", value_parser = ["all", "largest", "none"])]
    effects: String,
    /// Also time the culling baseline that puts every block in every tile
    /// (slow: every tet is visited once per tile).
    #[arg(long)]
    unculled: bool,
    /// Write the rendered frames as PNGs into this directory.
    #[arg(long, value_name = "DIR")]
    save: Option<PathBuf>,
    /// Export a 32³-cell sub-block (vertices N×12, densities N, transfer
    /// function, view) into DIR for tools/vtk_tets.py, render it exactly and stop.
    #[arg(long, value_name = "DIR", hide = true)]
    export_subblock: Option<PathBuf>,
    /// Image size for --export-subblock.
    #[arg(long, default_value_t = 512, hide = true)]
    subblock_size: u32,
}

pub fn run(o: TetsArgs) -> Result<()> {
    if o.size == 0 || o.size > 8192 || o.repeats == 0 || o.subblock_size == 0 {
        bail!("--size must be in 1..=8192, --repeats and --subblock-size ≥ 1");
    }
    if let Some(dir) = &o.save {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let grid = read_grid(&o.data, o.box_size)?;
    if let Some(dir) = &o.export_subblock {
        return export_subblock(&grid, dir, o.subblock_size, o.repeats);
    }
    print_header();
    let mut sets = vec![(format!("JaxPM {}³", grid.n), grid)];
    if o.n128 {
        let t = Instant::now();
        let fine = refine(&sets[0].1);
        eprintln!(
            "tets: refined to {}³ in {:.1} s",
            fine.n,
            t.elapsed().as_secs_f64()
        );
        sets.push((format!("refined {}³", fine.n), fine));
    }
    let last = sets.len() - 1;
    let mut mains = Vec::new();
    for (i, (label, grid)) in sets.iter().enumerate() {
        let (row, vol, exact) = bench_main(label, grid, &o)?;
        mains.push(row);
        let effects = match o.effects.as_str() {
            "all" => true,
            "largest" => i == last,
            _ => false,
        };
        if effects {
            bench_effects(label, &vol, &exact, &o)?;
        }
    }
    println!(
        "### Phase-space tessellation: build and frame, {0}×{0}\n",
        o.size
    );
    println!(
        "| data | particles | tets | images | blocks | point masses | `TetMesh::new` s | `TetVolume::new` s | … with 3 LOD levels s | LOD tets (levels 1–3) | project s | exact s | exact / project | project mass error |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|");
    for r in &mains {
        println!("{}", r.row);
    }
    println!(
        "\nWork per frame (tet visits: tets of binned blocks per tile; pixel tests: ray–tet clips; crossings: clips that hit):\n"
    );
    println!(
        "| data | view | tet visits | pixel tests | crossings | crossings / covered pixel (mean, max) | hits / tests |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|");
    for r in &mains {
        for w in &r.work {
            println!("{w}");
        }
    }
    if let Some(r) = mains.iter().find(|r| r.n == 128) {
        let verdict = |ok: bool| if ok { "met" } else { "not met" };
        println!(
            "\nTargets (128³, {0}×{0}, 2 cores): project ≤ 3 s: {1:.2} s ({2}); exact render ≤ 30 s: {3:.2} s ({4}).\n",
            o.size,
            r.t_project,
            verdict(r.t_project <= 3.0),
            r.t_exact,
            verdict(r.t_exact <= 30.0)
        );
    } else {
        println!();
    }
    Ok(())
}

// ---------------------------------------------------------------- data

fn read_grid(dir: &Path, box_size: f32) -> Result<LagrangianGrid> {
    let path = dir.join("positions.npy");
    let a = voxless::io::read_npy(&path)?;
    if a.shape.len() != 2 || a.shape[1] != 3 {
        bail!("{}: expected N³×3, found {:?}", path.display(), a.shape);
    }
    let count = a.shape[0];
    let n = (count as f64).cbrt().round() as usize;
    if n * n * n != count {
        bail!("{}: {count} particles is not N³", path.display());
    }
    Ok(LagrangianGrid {
        n,
        box_size,
        positions: a
            .data
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32))
            .collect(),
    })
}

/// The nearest periodic image of `d` (a difference of positions).
fn wrap(d: Vec3, l: f32) -> Vec3 {
    let w = |x: f32| x - l * (x / l).round();
    Vec3::new(w(d.x), w(d.y), w(d.z))
}

fn into_box(p: Vec3, l: f32) -> Vec3 {
    let w = |x: f32| {
        let r = x.rem_euclid(l);
        if r >= l { 0.0 } else { r }
    };
    Vec3::new(w(p.x), w(p.y), w(p.z))
}

/// A 2N³ Lagrangian grid from an N³ one: fine particle (i, j, k) sits at
/// coarse Lagrangian coordinate (i/2, j/2, k/2); its position is the
/// trilinear interpolation of the coarse positions there (the average of the
/// 1, 2, 4 or 8 coarse neighbours, unwrapped to the periodic image nearest
/// the first), wrapped into the box. With q = i·L/N this is the same as
/// interpolating the displacements x − q.
pub fn refine(grid: &LagrangianGrid) -> LagrangianGrid {
    let (n, l) = (grid.n, grid.box_size);
    let m = 2 * n;
    let at = |i: usize, j: usize, k: usize| grid.positions[((i % n) * n + (j % n)) * n + (k % n)];
    let positions = (0..m * m * m)
        .into_par_iter()
        .map(|c| {
            let (i, j, k) = (c / (m * m), (c / m) % m, c % m);
            let (bi, bj, bk) = (i / 2, j / 2, k / 2);
            let anchor = at(bi, bj, bk);
            let mut sum = Vec3::ZERO;
            let mut count = 0.0f32;
            for di in 0..=(i % 2) {
                for dj in 0..=(j % 2) {
                    for dk in 0..=(k % 2) {
                        sum += wrap(at(bi + di, bj + dj, bk + dk) - anchor, l);
                        count += 1.0;
                    }
                }
            }
            into_box(anchor + sum * (1.0 / count), l)
        })
        .collect();
    LagrangianGrid {
        n: m,
        box_size: l,
        positions,
    }
}

/// The render settings `voxless render` uses for a tessellation (see
/// `voxless_scene::resolve`): log10 scale over the volume's value range,
/// opacity scale 100 / diagonal.
fn cli_settings(vol: &TetVolume, size: u32) -> RenderSettings {
    let mut s = RenderSettings::for_volume(vol, size, size);
    s.opacity_scale = 100.0 / vol.bounds().diagonal().max(1e-12);
    s.log_scale = true;
    let vr = s.value_range;
    let hi = vr.hi.max(f32::MIN_POSITIVE).log10();
    let lo = if vr.lo > 0.0 { vr.lo.log10() } else { hi - 3.0 };
    s.value_range = Range1::new(lo, hi);
    s
}

// ---------------------------------------------------------------- main

struct MainRow {
    n: usize,
    row: String,
    work: Vec<String>,
    t_project: f64,
    t_exact: f64,
}

/// The exact render of the framing view: its time, image and per-pixel
/// crossing counts (the baseline of the effects tables).
struct Exact {
    camera: Camera,
    settings: RenderSettings,
    time: f64,
    image: Image,
    crossings: Vec<u32>,
}

fn bench_main(
    label: &str,
    grid: &LagrangianGrid,
    o: &TetsArgs,
) -> Result<(MainRow, TetVolume, Exact)> {
    let s = TetSettings::default();
    let r = o.repeats;
    eprintln!("tets/{label}: TetMesh::new");
    let (t_mesh, mesh) = bench(r, || (), |_| TetMesh::new(grid, &s));
    let mesh = mesh?;
    let n = mesh.n;
    let cells6 = 6 * n * n * n;
    let (tets, blocks, points) = (mesh.tets.len(), mesh.blocks.len(), mesh.point_masses.len());
    drop(mesh);
    eprintln!("tets/{label}: TetVolume::new, 0 levels");
    let (t_vol0, v) = bench(r, || (), |_| TetVolume::new(grid, &s, 0));
    drop(v?);
    eprintln!("tets/{label}: TetVolume::new, 3 levels");
    let (t_vol3, vol) = bench(r, || (), |_| TetVolume::new(grid, &s, 3));
    let vol = vol?;
    let mesh = &vol.mesh;
    let lod_tets: Vec<String> = mesh.lod.iter().map(|m| m.tets.len().to_string()).collect();
    // Degenerate tets are point masses; images are the extra copies of tets
    // that cross a face of the box.
    let images = tets as i64 - (cells6 - points.min(cells6)) as i64;

    let size = o.size;
    let ortho = Camera::axis_projection(&vol.bounds(), 2)?;
    eprintln!("tets/{label}: project");
    let (t_project, col) = bench(
        r,
        || (),
        |_| project(mesh, &ortho, size, size, TetOptions::default(), &|_, _| {}),
    );
    let px = (mesh.box_size as f64 / size as f64).powi(2);
    let mass: f64 = col.iter().map(|&v| v as f64).sum::<f64>() * px;
    let mass_err = (mass - mesh.total_mass()).abs() / mesh.total_mass();

    let camera = Camera::framing(&vol.bounds(), 1.0);
    let settings = cli_settings(&vol, size);
    let tf = TransferFunction::default_for_density();
    eprintln!("tets/{label}: exact render");
    let (t_exact, image) = bench(
        r,
        || (),
        |_| {
            render(
                mesh,
                &camera,
                &tf,
                &settings,
                TetMode::Exact,
                TetOptions::default(),
                &|_, _| {},
            )
        },
    );
    eprintln!("tets/{label}: project {t_project:.2} s, exact {t_exact:.2} s; counting work");
    let stem = label.replace(['³', ' '], "");
    if let Some(dir) = &o.save {
        save_png(&dir.join(format!("{stem}-exact.png")), &image)?;
        voxless::io::write_npy_f32(
            &dir.join(format!("{stem}-project.npy")),
            &[size as usize, size as usize],
            &col,
        )?;
    }
    let (w_ortho, _) = work(mesh, &ortho, size, None);
    let (w_persp, crossings) = work(mesh, &camera, size, None);
    let work_rows = vec![
        w_ortho.row(label, "project (ortho, z)"),
        w_persp.row(label, "exact (framing)"),
    ];
    let row = format!(
        "| {label} | {} | {tets} | {images} | {blocks} | {points} | {t_mesh:.2} | {t_vol0:.2} | {t_vol3:.2} | {} | {t_project:.2} | {t_exact:.2} | {:.1} | {mass_err:.1e} |",
        grid.positions.len(),
        lod_tets.join(" / "),
        t_exact / t_project,
    );
    Ok((
        MainRow {
            n,
            row,
            work: work_rows,
            t_project,
            t_exact,
        },
        vol,
        Exact {
            camera,
            settings,
            time: t_exact,
            image,
            crossings,
        },
    ))
}

struct Work {
    visits: u64,
    tests: u64,
    /// `None` when the pixel tests exceed the limit given to [`work`].
    crossings: Option<u64>,
    covered: u64,
    max: u32,
}

impl Work {
    fn row(&self, label: &str, view: &str) -> String {
        let (crossings, per_pixel, ratio) = match self.crossings {
            Some(c) => (
                sci(c as f64),
                format!("{:.1}, {}", c as f64 / self.covered.max(1) as f64, self.max),
                format!("{:.3}", c as f64 / self.tests.max(1) as f64),
            ),
            None => ("—".into(), "—".into(), "—".into()),
        };
        format!(
            "| {label} | {view} | {} | {} | {crossings} | {per_pixel} | {ratio} |",
            sci(self.visits as f64),
            sci(self.tests as f64),
        )
    }
}

fn sci(v: f64) -> String {
    format!("{v:.2e}")
}

/// Inclusive pixel rectangle `(x0, x1, y0, y1)`, as `Screen::pixel_rect`.
type PixelRect = (u32, u32, u32, u32);

/// Pixel tests beyond which [`work`] does not count crossings (and a view is
/// not timed): a frame that size would take hours.
const TEST_LIMIT: u64 = 20_000_000_000;

/// Counts the renderer's work for one frame (same tiles, bins and pixel
/// rects as `render`) and, unless the pixel tests exceed [`TEST_LIMIT`], the
/// crossings per pixel (row-major).
fn work(mesh: &TetMesh, camera: &Camera, size: u32, lod: Option<f32>) -> (Work, Vec<u32>) {
    let frame = Frame::new(mesh, camera, size, size, lod);
    let levels: Vec<&TetMesh> = std::iter::once(mesh).chain(mesh.lod.iter()).collect();
    let rects: Vec<Vec<Option<PixelRect>>> = levels
        .iter()
        .map(|m| {
            m.tets
                .par_iter()
                .map(|t| frame.screen.pixel_rect(&t.v))
                .collect()
        })
        .collect();
    let (visits, tests) = (0..frame.tiles_x * frame.tiles_y)
        .into_par_iter()
        .map(|i| {
            let (x0, y0, w, h) = frame.tile(i);
            let (mut visits, mut tests) = (0u64, 0u64);
            for &e in &frame.bins[i as usize] {
                let level = (e >> 28) as usize;
                let b = &levels[level].blocks[(e & ((1 << 28) - 1)) as usize];
                let range = b.tets.start as usize..b.tets.end as usize;
                visits += range.len() as u64;
                for r in rects[level][range].iter().flatten() {
                    let (ax, bx) = (r.0.max(x0), r.1.min(x0 + w - 1));
                    let (ay, by) = (r.2.max(y0), r.3.min(y0 + h - 1));
                    if ax <= bx && ay <= by {
                        tests += ((bx - ax + 1) * (by - ay + 1)) as u64;
                    }
                }
            }
            (visits, tests)
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    drop(rects);
    let mut counts = vec![0u32; (size * size) as usize];
    let mut crossings = None;
    if tests <= TEST_LIMIT {
        let per_tile: Vec<(u32, Vec<u32>)> = (0..frame.tiles_x * frame.tiles_y)
            .into_par_iter()
            .map(|i| {
                let rays = frame.rays(i);
                let spans = box_spans(mesh, &rays);
                let mut hits = vec![0u32; rays.len()];
                for_each_crossing(mesh, &frame, i, &rays, &spans, |p, _, _, _| hits[p] += 1);
                (i, hits)
            })
            .collect();
        for (i, hits) in per_tile {
            let (x0, y0, w, _) = frame.tile(i);
            for (k, c) in hits.into_iter().enumerate() {
                counts[((y0 + k as u32 / w) * size + x0 + k as u32 % w) as usize] = c;
            }
        }
        crossings = Some(counts.iter().map(|&c| c as u64).sum());
    }
    let covered = counts.iter().filter(|&&c| c > 0).count() as u64;
    let max = counts.iter().copied().max().unwrap_or(0);
    (
        Work {
            visits,
            tests,
            crossings,
            covered,
            max,
        },
        counts,
    )
}

// ---------------------------------------------------------------- effects

fn bench_effects(label: &str, vol: &TetVolume, exact: &Exact, o: &TetsArgs) -> Result<()> {
    let mesh = &vol.mesh;
    let size = o.size;
    let tf = TransferFunction::default_for_density();
    let settings = &exact.settings;
    let stem = label.replace(['³', ' '], "");

    // ---- culling
    let b = vol.bounds();
    let c = b.center();
    let framing = exact.camera;
    let zoom = Camera::look_at(
        framing.eye,
        c,
        Vec3::new(0.0, 1.0, 0.0),
        Projection::Perspective { fov_y_deg: 7.5 },
    )?;
    let inside = Camera::look_at(
        c,
        c + Vec3::new(1.0, 0.3, 0.2),
        Vec3::new(0.0, 1.0, 0.0),
        Projection::Perspective { fov_y_deg: 60.0 },
    )?;
    println!("### Phase-space tessellation effects: {label}, {size}×{size}\n");
    println!(
        "Block culling. \"binned\" counts (block, tile) pairs; \"all\" is every block in every tile. \
         Times: exact mode, the library's bins vs every block in every tile (same render loop).\n"
    );
    println!(
        "| view | blocks | blocks on screen | binned / all | pixel tests | crossings | culled s | unculled s | speedup | max abs diff vs `render` |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let tiles = (size.div_ceil(TILE) * size.div_ceil(TILE)) as u64;
    for (name, cam) in [
        ("framing (whole box)", framing),
        ("zoom 4× (fov 7.5°)", zoom),
        ("inside (eye at centre, fov 60°)", inside),
    ] {
        let frame = Frame::new(mesh, &cam, size, size, None);
        let binned: u64 = frame.bins.iter().map(|b| b.len() as u64).sum();
        let all = mesh.blocks.len() as u64 * tiles;
        let (w, _) = work(mesh, &cam, size, None);
        // A camera inside the box puts blocks behind the eye in every tile
        // with full-screen pixel rects: far too slow to time.
        let feasible = w.crossings.is_some();
        let (culled, unculled, diff) = if feasible {
            eprintln!("tets/{label}: culling, {name}");
            let (tc, img) = bench(
                o.repeats,
                || (),
                |_| {
                    let f = Frame::new(mesh, &cam, size, size, None);
                    exact_with(mesh, &f, &tf, settings)
                },
            );
            let reference = render(
                mesh,
                &cam,
                &tf,
                settings,
                TetMode::Exact,
                TetOptions::default(),
                &|_, _| {},
            );
            let diff = image_diff(&img, &reference).0;
            if let Some(dir) = &o.save {
                let v = name.split(' ').next().unwrap_or("view");
                save_png(&dir.join(format!("{stem}-view-{v}.png")), &reference)?;
            }
            let tu = if o.unculled {
                let everything: Vec<u32> = (0..mesh.blocks.len() as u32).collect();
                let (tu, img_u) = bench(
                    o.repeats,
                    || (),
                    |_| {
                        let mut f = Frame::new(mesh, &cam, size, size, None);
                        f.bins = vec![everything.clone(); f.bins.len()];
                        exact_with(mesh, &f, &tf, settings)
                    },
                );
                let d = image_diff(&img_u, &img).0;
                if d > 0.0 {
                    eprintln!("warning: unculled image differs by {d:e}");
                }
                Some(tu)
            } else {
                None
            };
            (format!("{tc:.2}"), tu, format!("{diff:.1e}"))
        } else {
            ("not timed".into(), None, "—".into())
        };
        let (un, speed) = match (unculled, culled.parse::<f64>().ok()) {
            (Some(tu), Some(tc)) => (format!("{tu:.2}"), format!("{:.1}", tu / tc)),
            _ => ("—".into(), "—".into()),
        };
        println!(
            "| {name} | {} | {} | {:.3} | {} | {} | {culled} | {un} | {speed} | {diff} |",
            mesh.blocks.len(),
            frame.blocks_per_level[0],
            binned as f64 / all as f64,
            sci(w.tests as f64),
            w.crossings.map_or("—".into(), |c| sci(c as f64)),
        );
    }
    println!();

    // ---- k-buffer
    println!(
        "k-buffer (`TetMode::KBuffer {{ k, layers: 64 }}`) against exact mode, framing view. \
         Inexact pixels: covered pixels with ≥ k events (2 per crossing).\n"
    );
    println!("| mode | s | time / exact | max abs diff | mean abs diff | inexact pixels |");
    println!("|---|---:|---:|---:|---:|---:|");
    println!("| exact | {:.2} | 1.00 | 0 | 0 | 0 % |", exact.time);
    let covered = exact.crossings.iter().filter(|&&c| c > 0).count().max(1);
    for k in [4usize, 8, 16, 32, 64] {
        eprintln!("tets/{label}: k-buffer k = {k}");
        let (t, img) = bench(
            o.repeats,
            || (),
            |_| {
                render(
                    mesh,
                    &exact.camera,
                    &tf,
                    settings,
                    TetMode::KBuffer { k, layers: 64 },
                    TetOptions::default(),
                    &|_, _| {},
                )
            },
        );
        let (max, mean) = image_diff(&img, &exact.image);
        let inexact = exact
            .crossings
            .iter()
            .filter(|&&c| 2 * c as usize >= k)
            .count();
        println!(
            "| k = {k} | {t:.2} | {:.2} | {max:.3} | {mean:.2e} | {:.1} % |",
            t / exact.time,
            100.0 * inexact as f64 / covered as f64
        );
        if let Some(dir) = &o.save {
            save_png(&dir.join(format!("{stem}-kbuffer{k}.png")), &img)?;
        }
    }
    println!();

    // ---- LOD
    println!(
        "Level of detail: blocks whose screen box is below the threshold use coarser levels \
         (one per halving; {} levels built). Exact mode, framing view, against the same mesh without LOD.\n",
        mesh.lod.len()
    );
    println!(
        "| lod_pixels | blocks per level (0/1/2/3) | pixel tests | s | time / no LOD | max abs diff | mean abs diff |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|");
    let (w0, _) = work(mesh, &exact.camera, size, None);
    println!(
        "| none | {} | {} | {:.2} | 1.00 | 0 | 0 |",
        mesh.blocks.len(),
        sci(w0.tests as f64),
        exact.time
    );
    for p in [8.0f32, 16.0, 32.0, 64.0, 128.0] {
        eprintln!("tets/{label}: LOD {p} px");
        let opts = TetOptions {
            lod_pixels: Some(p),

            ..Default::default()
        };
        let frame = Frame::new(mesh, &exact.camera, size, size, Some(p));
        let per_level: Vec<String> = frame
            .blocks_per_level
            .iter()
            .map(|b| b.to_string())
            .collect();
        let (w, _) = work(mesh, &exact.camera, size, Some(p));
        let (t, img) = bench(
            o.repeats,
            || (),
            |_| {
                render(
                    mesh,
                    &exact.camera,
                    &tf,
                    settings,
                    TetMode::Exact,
                    opts,
                    &|_, _| {},
                )
            },
        );
        let (max, mean) = image_diff(&img, &exact.image);
        println!(
            "| {p} | {} | {} | {t:.2} | {:.2} | {max:.3} | {mean:.2e} |",
            per_level.join(" / "),
            sci(w.tests as f64),
            t / exact.time
        );
        if let Some(dir) = &o.save {
            save_png(&dir.join(format!("{stem}-lod{p}.png")), &img)?;
        }
    }
    println!();
    Ok(())
}

/// Exact mode through a given frame: the loop of `render::render` (tiles in
/// parallel, every event of a pixel sorted, constant-density segments
/// composited in closed form), so that the frame's bins can be changed.
fn exact_with(
    mesh: &TetMesh,
    frame: &Frame,
    tf: &TransferFunction,
    settings: &RenderSettings,
) -> Image {
    let scale = mesh
        .tets
        .iter()
        .map(|t| t.density as f64)
        .fold(0.0, f64::max);
    let tiles: Vec<(u32, Vec<[f32; 4]>)> = (0..frame.tiles_x * frame.tiles_y)
        .into_par_iter()
        .map(|i| {
            let rays = frame.rays(i);
            let spans = box_spans(mesh, &rays);
            let mut events: Vec<Vec<(f32, f32)>> = vec![Vec::new(); rays.len()];
            for_each_crossing(mesh, frame, i, &rays, &spans, |p, t0, t1, rho| {
                events[p].push((t0, rho));
                events[p].push((t1, -rho));
            });
            let px = events
                .iter_mut()
                .map(|ev| {
                    ev.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
                    composite(ev, tf, settings, scale)
                })
                .collect();
            (i, px)
        })
        .collect();
    let (w, h) = (frame.screen.width(), frame.screen.height());
    let mut pixels = vec![[0.0f32; 4]; (w * h) as usize];
    for (i, px) in tiles {
        let (x0, y0, tw, _) = frame.tile(i);
        for (k, p) in px.into_iter().enumerate() {
            pixels[((y0 + k as u32 / tw) * w + x0 + k as u32 % tw) as usize] = p;
        }
    }
    Image {
        width: w,
        height: h,
        pixels,
    }
}

/// Front-to-back emission–absorption over sorted `(t, Δρ)` events, as the
/// library's exact sweep (running densities below 1e-9 of the largest tet
/// density are cancellation residue).
fn composite(
    events: &[(f32, f32)],
    tf: &TransferFunction,
    s: &RenderSettings,
    scale: f64,
) -> [f32; 4] {
    let (mut color, mut alpha) = (Vec3::ZERO, 0.0f32);
    let mut rho = 0.0f64;
    let mut t_prev = f32::NAN;
    for &(t, d) in events {
        if t_prev.is_finite() {
            let r = if rho.abs() < 1e-9 * scale { 0.0 } else { rho };
            let len = t - t_prev;
            if r > 0.0 && len > 0.0 {
                let x = s.normalize(r as f32);
                let op = tf.opacity(x);
                if op > 0.0 {
                    let a = 1.0 - (-op * s.opacity_scale * len).exp();
                    color += tf.color(x) * ((1.0 - alpha) * a);
                    alpha += (1.0 - alpha) * a;
                    if alpha >= s.early_termination {
                        break;
                    }
                }
            }
        }
        rho += d as f64;
        t_prev = t;
    }
    [color.x, color.y, color.z, alpha]
}
