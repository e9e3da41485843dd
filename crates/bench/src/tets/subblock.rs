//! The VTK side-by-side: export a sub-block of the tessellation for
//! `tools/vtk_tets.py` and time our exact render of the same tets.
//!
//! The sub-block is built tet by tet as a `TetMesh` (not as a periodic
//! Lagrangian grid, see below) and rendered as `TetVolume::from_mesh` by
//! the shared integrator, with the settings `voxless render` resolves for
//! the whole run (log10 value range) and an opacity scale of 100 over the
//! sub-block's diagonal.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use rayon::prelude::*;
use voxless_core::{Aabb, Camera, Control, Projection, Vec3};
use voxless_tets::mesh::KUHN;
use voxless_tets::raster::{Frame, box_spans, for_each_crossing};
use voxless_tets::{BLOCK, LagrangianGrid, Tet, TetMesh, TetMeshBuilder, TetSettings, TetVolume};

use super::{resolved, wrap};
use crate::common::{bench, print_header, save_png};

/// Cells per axis of the exported sub-block, and its first Lagrangian cell.
const SUB: usize = 32;
const SUB_START: usize = 16;

/// Writes the 32³-cell sub-block starting at Lagrangian cell (16, 16, 16)
/// of `grid` for tools/vtk_tets.py: `vertices.npy` (N×12, f32), `density.npy`
/// (N), `tf.npy` (256×4: linear RGB and opacity of the transfer function at
/// x = i/255), `view.json` (camera, value range in log10, opacity scale),
/// our exact render (`tets-voxless.png`, linear RGBA `voxless-rgba.npy`),
/// timed, and per pixel the most tets overlapping on its ray (`streams.npy`).
pub(super) fn export_subblock(
    grid: &LagrangianGrid,
    dir: &Path,
    size: u32,
    repeats: usize,
) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let (n, l) = (grid.n, grid.box_size);
    if n < SUB_START + SUB {
        bail!("the sub-block needs N ≥ {}", SUB_START + SUB);
    }
    let p = SUB + 1;
    // Positions unwrapped along the Lagrangian grid: x = q + nearest image of x − q.
    let spacing = l / n as f32;
    let point = |a: usize, b: usize, c: usize| {
        let (i, j, k) = (SUB_START + a, SUB_START + b, SUB_START + c);
        let q = Vec3::new(i as f32, j as f32, k as f32) * spacing;
        q + wrap(grid.positions[((i % n) * n + j % n) * n + k % n] - q, l)
    };
    let pts: Vec<Vec3> = (0..p * p * p)
        .map(|c| point(c / (p * p), (c / p) % p, c % p))
        .collect();
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for &q in &pts {
        lo = lo.min(q);
        hi = hi.max(q);
    }
    // Shift into a box [0, big)³ with a margin, so nothing is near a face.
    let margin = 2.0 * spacing;
    let shift = Vec3::splat(margin) - lo;
    let big = (hi - lo).max_elem() + 2.0 * margin;
    let pts: Vec<Vec3> = pts.into_iter().map(|q| q + shift).collect();
    let tet_mass = 1.0 / (6.0 * (n * n * n) as f64);
    let mean_volume = (spacing as f64).powi(3) / 6.0;
    let floor = TetSettings::default().degenerate_fraction * mean_volume;
    let mut built = TetMeshBuilder::new(SUB, big, tet_mass, mean_volume);
    let mut bounds = Aabb::EMPTY;
    let mut degenerate = 0usize;
    let nb = SUB / BLOCK;
    for bi in 0..nb {
        for bj in 0..nb {
            for bk in 0..nb {
                let mut tets = Vec::new();
                for i in bi * BLOCK..(bi + 1) * BLOCK {
                    for j in bj * BLOCK..(bj + 1) * BLOCK {
                        for k in bk * BLOCK..(bk + 1) * BLOCK {
                            let corner = |c: usize| {
                                pts[((i + (c >> 2)) * p + j + ((c >> 1) & 1)) * p + k + (c & 1)]
                            };
                            for t in KUHN {
                                let v = t.map(corner);
                                let vol = Tet::signed_volume(&v).abs();
                                if vol < floor {
                                    degenerate += 1;
                                    continue;
                                }
                                let tet = Tet {
                                    v,
                                    density: (tet_mass / vol) as f32,
                                };
                                bounds = bounds.union(tet.bounds());
                                tets.push(tet);
                            }
                        }
                    }
                }
                built.push_block(((bi * nb + bj) * nb + bk) as u32, tets);
            }
        }
    }
    let mesh = built.build();
    eprintln!(
        "sub-block: {} tets ({degenerate} degenerate dropped), extent {:?}, box {big}",
        mesh.tet_count(),
        (hi - lo).to_array()
    );

    // The check asked of the CLI route: a 33³ point grid tessellated as a
    // periodic Lagrangian grid gives 33³ cells, not 32³ (the last layer
    // wraps around to the first), so the mesh is built here directly.
    let periodic = TetMesh::new(
        &LagrangianGrid {
            n: p,
            box_size: big,
            positions: pts.clone(),
        },
        &TetSettings::default(),
    )?;
    let wide = periodic
        .tets()
        .iter()
        .filter(|t| t.bounds().extent().max_elem() > 0.5 * big)
        .count();

    // Render settings as the CLI's, over the sub-block: value range of the
    // whole 64³ volume (log10), opacity scale 100 / the sub-block's diagonal.
    let (full, view) = resolved(TetVolume::new(grid, &TetSettings::default(), 0)?, size)?;
    drop(full);
    let tf = view.tf;
    let mut settings = view.settings;
    settings.opacity_scale = 100.0 / bounds.diagonal();
    let camera = Camera::framing(&bounds, 1.0);
    let mesh = TetVolume::from_mesh(mesh);
    let render = || voxless_render::render(&mesh, &camera, &tf, &settings, &Control::new());
    let t0 = Instant::now();
    let first = render()?;
    let t_first = t0.elapsed().as_secs_f64();
    let (t, img) = bench(repeats, || (), |_| render());
    let img = img?;
    debug_assert_eq!(first.pixels.len(), img.pixels.len());
    let mesh = &mesh.mesh;
    save_png(&dir.join("tets-voxless.png"), &img)?;
    voxless_io::write_npy_f32(
        &dir.join("voxless-rgba.npy"),
        &[size as usize, size as usize, 4],
        &img.to_rgba_f32(),
    )?;
    // Streams along each ray: the most tets covering one point of it.
    let streams = max_streams(mesh, &camera, size);
    let streams_f: Vec<f32> = streams.iter().map(|&s| s as f32).collect();
    voxless_io::write_npy_f32(
        &dir.join("streams.npy"),
        &[size as usize, size as usize],
        &streams_f,
    )?;
    let covered: Vec<u32> = streams.iter().copied().filter(|&s| s > 0).collect();
    let multi = covered.iter().filter(|&&s| s >= 3).count();
    let two = covered.iter().filter(|&&s| s == 2).count();

    let all = mesh.tets();
    let nt = all.len();
    let verts: Vec<f32> = all
        .iter()
        .flat_map(|t| t.v.iter().flat_map(|v| v.to_array()))
        .collect();
    let dens: Vec<f32> = all.iter().map(|t| t.density).collect();
    voxless_io::write_npy_f32(&dir.join("vertices.npy"), &[nt, 12], &verts)?;
    voxless_io::write_npy_f32(&dir.join("density.npy"), &[nt], &dens)?;
    let table: Vec<f32> = (0..256)
        .flat_map(|i| {
            let x = i as f32 / 255.0;
            let c = tf.color(x);
            [c.x, c.y, c.z, tf.opacity(x)]
        })
        .collect();
    voxless_io::write_npy_f32(&dir.join("tf.npy"), &[256, 4], &table)?;
    let fov = match camera.projection {
        Projection::Perspective { fov_y_deg } => fov_y_deg,
        Projection::Orthographic { .. } => unreachable!("framing is perspective"),
    };
    let v3 = |v: Vec3| format!("[{}, {}, {}]", v.x, v.y, v.z);
    let json = format!(
        "{{\n  \"size\": {size},\n  \"eye\": {},\n  \"look_at\": {},\n  \"up\": {},\n  \"fov_y_deg\": {fov},\n  \"log10_range\": [{}, {}],\n  \"opacity_scale\": {},\n  \"tets\": {nt},\n  \"voxless_exact_s\": {t},\n  \"voxless_first_s\": {t_first}\n}}\n",
        v3(camera.eye),
        v3(bounds.center()),
        v3(camera.up),
        settings.value_range.lo,
        settings.value_range.hi,
        settings.opacity_scale,
    );
    std::fs::write(dir.join("view.json"), json)?;

    print_header();
    println!("### Sub-block for the VTK comparison\n");
    println!(
        "Lagrangian cells [{SUB_START}, {}) per axis of the {n}³ run: {} tets ({degenerate} degenerate dropped), \
         extent {:.1} × {:.1} × {:.1}, shifted into a box of {big:.1}.\n",
        SUB_START + SUB,
        nt,
        (hi - lo).x,
        (hi - lo).y,
        (hi - lo).z
    );
    println!(
        "The same 33³ points as a periodic Lagrangian grid (`--lagrangian 33`): {} tets \
         (33³ cells × 6 = {}, plus periodic images), {wide} of them spanning more than half the \
         box (the wrap-around layer joining the last plane to the first), so the CLI route does \
         not give the 32³-cell block.\n",
        periodic.tet_count(),
        33 * 33 * 33 * 6
    );
    println!(
        "Exact render {size}×{size}: {t:.3} s (median of {repeats}; first run {t_first:.3} s). \
         Covered pixels {}, with 2 streams at some depth {:.1} %, with ≥ 3 streams {:.1} % \
         (max {}).\n",
        covered.len(),
        100.0 * two as f64 / covered.len().max(1) as f64,
        100.0 * multi as f64 / covered.len().max(1) as f64,
        covered.iter().max().copied().unwrap_or(0)
    );
    Ok(())
}

/// Per pixel, the largest number of tets covering one point of its ray.
fn max_streams(mesh: &TetMesh, camera: &Camera, size: u32) -> Vec<u32> {
    let frame = Frame::new(mesh, camera, size, size, None);
    let tiles: Vec<(u32, Vec<u32>)> = (0..frame.tiles_x * frame.tiles_y)
        .into_par_iter()
        .map(|i| {
            let rays = frame.rays(i);
            let spans = box_spans(mesh, &rays);
            let mut events: Vec<Vec<(f32, i32)>> = vec![Vec::new(); rays.len()];
            for_each_crossing(mesh, &frame, i, &rays, &spans, |p, t0, t1, _| {
                events[p].push((t0, 1));
                events[p].push((t1, -1));
            });
            let out = events
                .iter_mut()
                .map(|ev| {
                    // Exits before entries at equal t: shared faces are not overlaps.
                    ev.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                    let (mut c, mut m) = (0i32, 0i32);
                    for &(_, d) in ev.iter() {
                        c += d;
                        m = m.max(c);
                    }
                    m as u32
                })
                .collect();
            (i, out)
        })
        .collect();
    let mut out = vec![0u32; (size * size) as usize];
    for (i, px) in tiles {
        let (x0, y0, w, _) = frame.tile(i);
        for (k, s) in px.into_iter().enumerate() {
            out[((y0 + k as u32 / w) * size + x0 + k as u32 % w) as usize] = s;
        }
    }
    out
}
