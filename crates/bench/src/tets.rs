//! `voxless-bench tets`: the phase-space tessellation numbers quoted in
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
//! Camera, transfer function and render settings are the ones
//! `voxless render` uses for a tessellation: `voxless::resolve` of a scene
//! that sets only the image size (`Camera::framing`, viridis with linear
//! opacity, log10 scale over `TetVolume::value_range`, opacity scale
//! 100/diagonal). Renders go through the shared integrator
//! (`voxless_render::render` of the `TetVolume`: exact constant intervals
//! per tile from its tile view), projections through
//! `voxless_render::project` (the volume's whole-image projection).
//!
//! - **Main** (per data set): tessellation time (`TetMesh::new`, and
//!   `TetVolume::new` with 0 and with 3 levels of detail, as the library's
//!   loader builds it), tet, block and image counts; a `--size`²
//!   column-density projection (orthographic `Camera::axis_projection` down
//!   z over the box; mass conservation is checked) and an exact render. The
//!   128³ targets on two cores: projection ≤ 3 s, exact render ≤ 30 s. Work
//!   counters ([`work`]) explain the times.
//! - **Effects** ([`effects`]): block culling against every block in every
//!   tile, the k-buffer (`RenderSettings::event_budget`) against exact mode,
//!   and level of detail (`TetVolume::with_lod_pixels`) against none.
//!
//! `--export-subblock DIR` (hidden) writes a 32³-cell sub-block (196,608
//! tets) and its view for `tools/vtk_tets.py`, and times our exact render of
//! it ([`subblock`]); see docs/benchmarks.md.

mod effects;
mod subblock;
mod unculled;
mod work;

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use rayon::prelude::*;
use voxless::{AnyVolume, ImageDesc, Resolved, SceneDesc};
use voxless_core::{Camera, Control, Image, Vec3, Volume};
use voxless_tets::{LagrangianGrid, TetMesh, TetSettings, TetVolume};

use crate::common::{bench, print_header, save_png, verdict};
use subblock::export_subblock;
use work::work;

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
            effects::bench_effects(label, vol, &exact, &o)?;
        }
    }
    println!(
        "### Phase-space tessellation: build and frame, {0}×{0}\n",
        o.size
    );
    println!(
        "| data | particles | tets | images | blocks | point masses | `TetMesh::new` s \
         | `TetVolume::new` s | … with 3 LOD levels s | LOD tets (levels 1–3) | project s \
         | exact s | exact / project | project mass error |"
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

pub(crate) fn read_grid(dir: &Path, box_size: f32) -> Result<LagrangianGrid> {
    let path = dir.join("positions.npy");
    let a = voxless_io::read_npy(&path)?;
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
pub(crate) fn refine(grid: &LagrangianGrid) -> LagrangianGrid {
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

/// The camera, transfer function and render settings `voxless render`
/// resolves for `vol` in a `size`² image (a scene that sets nothing else).
fn resolved(vol: TetVolume, size: u32) -> Result<(TetVolume, Resolved)> {
    let any = AnyVolume::Tets(Box::new(vol));
    let desc = SceneDesc {
        image: ImageDesc {
            width: Some(size),
            height: Some(size),
            spp: None,
        },
        ..Default::default()
    };
    let view = voxless::resolve(&any, &desc, Path::new("."))?;
    let AnyVolume::Tets(vol) = any else {
        unreachable!("built as a tessellation")
    };
    Ok((*vol, view))
}

// ---------------------------------------------------------------- main

struct MainRow {
    n: usize,
    row: String,
    work: Vec<String>,
    t_project: f64,
    t_exact: f64,
}

/// The exact render of the framing view: its view, time, image and
/// per-pixel crossing counts (the baseline of the effects tables).
struct Exact {
    view: Resolved,
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
    let (tets, blocks, points) = (
        mesh.tet_count(),
        mesh.blocks().len(),
        mesh.point_masses().len(),
    );
    drop(mesh);
    eprintln!("tets/{label}: TetVolume::new, 0 levels");
    let (t_vol0, v) = bench(r, || (), |_| TetVolume::new(grid, &s, 0));
    drop(v?);
    eprintln!("tets/{label}: TetVolume::new, 3 levels");
    let (t_vol3, vol) = bench(r, || (), |_| TetVolume::new(grid, &s, 3));
    let (vol, view) = resolved(vol?, o.size)?;
    let mesh = &vol.mesh;
    let lod_tets: Vec<String> = mesh
        .lod()
        .iter()
        .map(|m| m.tet_count().to_string())
        .collect();
    // Degenerate tets are point masses; images are the extra copies of tets
    // that cross a face of the box.
    let images = tets as i64 - (cells6 - points.min(cells6)) as i64;

    let size = o.size;
    let ortho = Camera::axis_projection(&vol.bounds(), 2)?;
    eprintln!("tets/{label}: project");
    let (t_project, col) = bench(
        r,
        || (),
        |_| voxless_render::project(&vol, &ortho, size, size, &Control::new()),
    );
    let col = col?;
    let px = (mesh.box_size as f64 / size as f64).powi(2);
    let mass: f64 = col.iter().map(|&v| v as f64).sum::<f64>() * px;
    let mass_err = (mass - mesh.total_mass()).abs() / mesh.total_mass();

    eprintln!("tets/{label}: exact render");
    let (t_exact, image) = bench(
        r,
        || (),
        |_| {
            voxless_render::render(
                &vol,
                &view.camera,
                &view.tf,
                &view.settings,
                &Control::new(),
            )
        },
    );
    let image = image?;
    eprintln!("tets/{label}: project {t_project:.2} s, exact {t_exact:.2} s; counting work");
    let stem = label.replace(['³', ' '], "");
    if let Some(dir) = &o.save {
        save_png(&dir.join(format!("{stem}-exact.png")), &image)?;
        voxless_io::write_npy_f32(
            &dir.join(format!("{stem}-project.npy")),
            &[size as usize, size as usize],
            &col,
        )?;
    }
    let (w_ortho, _) = work(mesh, &ortho, size, None);
    let (w_persp, crossings) = work(mesh, &view.camera, size, None);
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
            view,
            time: t_exact,
            image,
            crossings,
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::refine;
    use voxless_core::Vec3;
    use voxless_tets::LagrangianGrid;

    /// Refining a uniform grid gives the uniform grid of twice the resolution.
    #[test]
    fn refine_uniform() {
        let (n, l) = (4usize, 8.0f32);
        let s = l / n as f32;
        let positions = (0..n * n * n)
            .map(|c| {
                let (i, j, k) = (c / (n * n), (c / n) % n, c % n);
                Vec3::new(i as f32, j as f32, k as f32) * s
            })
            .collect();
        let fine = refine(&LagrangianGrid {
            n,
            box_size: l,
            positions,
        });
        assert_eq!(fine.n, 8);
        for (c, p) in fine.positions.iter().enumerate() {
            let (i, j, k) = (c / 64, (c / 8) % 8, c % 8);
            let want = Vec3::new(i as f32, j as f32, k as f32) * (s / 2.0);
            assert!((*p - want).length() < 1e-5, "{c}: {p:?} vs {want:?}");
        }
    }
}
