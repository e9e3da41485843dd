//! Column-density projections of a tet mesh over screen tiles in parallel:
//! per tile, every tet of the tile's culling blocks adds `ρ·chord` to each
//! pixel centre it covers (eight pixels at a time for orthographic views,
//! `crate::ortho`) or, with [`PixelIntegral::Area`], its column integrated
//! over each pixel's square (`crate::area`); degenerate tets add their point
//! mass to the pixel containing them. Renders go through the shared
//! integrator instead (the tile view of [`crate::events`]).

use rayon::prelude::*;
use voxless_core::{Camera, Cancelled, Control, Ray, Simd};

use crate::area::{AreaTile, BoxClip};
use crate::mesh::TetMesh;
use crate::ortho::{Kernel, OrthoMap, TileJob};
use crate::raster::{Frame, Screen, TILE, box_spans, for_each_crossing, for_each_tet};

pub use voxless_core::PixelIntegral;

/// Options of the projection beyond the camera.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TetOptions {
    /// Level of detail: blocks whose screen box is below this many pixels
    /// use the mesh's coarser levels ([`TetMesh::with_lod`]). Off when `None`.
    pub lod_pixels: Option<f32>,
    /// Test every pixel of each tet's rectangle with a full plane clip (the
    /// slow path the fast one is tested against; pixel centres).
    pub clip_only: bool,
    /// Pixel centres or pixel areas.
    pub pixels: PixelIntegral,
}

/// Runs `per_tile(tile, rays)` over every tile in parallel (each returns its
/// pixels row-major) and assembles the full image, row-major. Progress in
/// tiles; stops between tiles once cancelled.
fn over_tiles<T: Copy + Default + Send>(
    frame: &Frame,
    control: &Control,
    per_tile: impl Fn(u32, &[Ray]) -> Vec<T> + Sync,
) -> Result<Vec<T>, Cancelled> {
    let total = (frame.tiles_x * frame.tiles_y) as u64;
    let done = std::sync::atomic::AtomicU64::new(0);
    let tiles: Vec<Option<(u32, Vec<T>)>> = (0..frame.tiles_x * frame.tiles_y)
        .into_par_iter()
        .map(|i| {
            if control.is_cancelled() {
                return None;
            }
            let out = per_tile(i, &frame.rays(i));
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            control.report(d, total);
            Some((i, out))
        })
        .collect();
    control.check()?;
    let width = frame.screen.width();
    let mut image = vec![T::default(); (width * frame.screen.height()) as usize];
    for (i, pixels) in tiles.into_iter().flatten() {
        let (x0, y0, w, _) = frame.tile(i);
        for (k, p) in pixels.into_iter().enumerate() {
            image[((y0 + k as u32 / w) * width + x0 + k as u32 % w) as usize] = p;
        }
    }
    Ok(image)
}

/// Column density `Σ ρ·chord` per pixel centre (row-major), plus each
/// degenerate tet's point mass spread over the pixel containing it. Order
/// independent, so no events are kept. Orthographic views go through the
/// row kernels of `ortho` (AVX2 where the CPU has it), others through the
/// per-pixel clip of [`for_each_crossing`].
pub fn project(
    mesh: &TetMesh,
    camera: &Camera,
    width: u32,
    height: u32,
    options: TetOptions,
    control: &Control,
) -> Result<Vec<f32>, Cancelled> {
    project_with(
        mesh,
        camera,
        (width, height),
        options,
        Kernel::Lanes(Simd::Auto),
        control,
    )
}

/// Tile side of the orthographic projection: up to 128 pixels, so that a
/// tet is set up in fewer tiles (the 128³ set at 1024²: 1.70 tiles per tet
/// on screen at 32 px, 1.31 at 64, 1.14 at 128), while keeping four tiles
/// per thread. (256 px would derive a lean mesh's blocks in half as many
/// tiles, but change the f32 accumulation order, and so the low bits, of
/// every image.)
fn project_tile(width: u32, height: u32) -> u32 {
    let want = 4 * rayon::current_num_threads() as u32;
    [128, 64]
        .into_iter()
        .find(|&t| width.div_ceil(t) * height.div_ceil(t) >= want)
        .unwrap_or(TILE)
}

/// [`project`] with the given kernel for orthographic views.
pub(crate) fn project_with(
    mesh: &TetMesh,
    camera: &Camera,
    (width, height): (u32, u32),
    options: TetOptions,
    kernel: Kernel,
    control: &Control,
) -> Result<Vec<f32>, Cancelled> {
    let ortho = OrthoMap::new(camera, width, height).filter(|_| !options.clip_only);
    if let (PixelIntegral::Area, Some(map)) = (options.pixels, &ortho) {
        return project_areas(mesh, camera, (width, height), options, map, control);
    }
    let tile = if ortho.is_some() {
        project_tile(width, height)
    } else {
        TILE
    };
    let frame = Frame::with_tile(mesh, camera, width, height, options.lod_pixels, tile);
    let mut out: Vec<f64> = over_tiles(&frame, control, |i, rays| {
        let spans = box_spans(mesh, rays);
        if let Some(map) = &ortho {
            let job = TileJob {
                mesh,
                frame: &frame,
                map,
                tile: i,
                spans: &spans,
            };
            return job.run(kernel);
        }
        let mut sum = vec![0.0f64; rays.len()];
        let mut add =
            |p: usize, t0: f32, t1: f32, rho: f32| sum[p] += rho as f64 * (t1 - t0) as f64;
        if options.clip_only {
            // The slow path: every pixel of the tet's rectangle, full plane clips.
            let (tx0, ty0, w, _) = frame.tile(i);
            for_each_tet(mesh, &frame, i, |tet: &crate::Tet, (x0, x1, y0, y1)| {
                let planes = crate::raster::Planes::new(tet);
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        let local = ((y - ty0) * w + (x - tx0)) as usize;
                        let (t0, t1) = planes.clip(&rays[local]);
                        let (t0, t1) = (t0.max(spans[local].0), t1.min(spans[local].1));
                        if t1 > t0 {
                            add(local, t0, t1, tet.density);
                        }
                    }
                }
            });
        } else {
            for_each_crossing(mesh, &frame, i, rays, &spans, add);
        }
        sum
    })?;
    add_point_masses(mesh, camera, &frame.screen, &mut out);
    Ok(out.into_iter().map(|v| v as f32).collect())
}

/// Adds each point mass (of a degenerate tet) to the pixel whose square
/// contains it, as mass over the pixel's area (orthographic views).
fn add_point_masses(mesh: &TetMesh, camera: &Camera, screen: &Screen, out: &mut [f64]) {
    let (width, height) = (screen.width(), screen.height());
    if let voxless_core::Projection::Orthographic {
        half_width,
        half_height,
    } = camera.projection
    {
        let area =
            (2.0 * half_width as f64 / width as f64) * (2.0 * half_height as f64 / height as f64);
        for &(p, m) in mesh.point_masses() {
            if let Some((x, y)) = screen.project(p)
                && x >= 0.0
                && y >= 0.0
                && (x as u32) < width
                && (y as u32) < height
            {
                out[(y as u32 * width + x as u32) as usize] += m / area;
            }
        }
    }
}

/// Tile side of pixel-area projections: up to 128 pixels (a tile's sums
/// and running sums, 24 bytes per pixel, stay near the core), keeping four
/// tiles per thread.
fn area_tile(width: u32, height: u32) -> u32 {
    let want = 4 * rayon::current_num_threads() as u32;
    [128, 64]
        .into_iter()
        .find(|&t| width.div_ceil(t) * height.div_ceil(t) >= want)
        .unwrap_or(TILE)
}

/// [`PixelIntegral::Area`] for an orthographic view: per tile, every tet
/// whose outline meets a pixel square of the tile integrated exactly over
/// the tile's pixels ([`crate::area`]), cut at the box's faces.
fn project_areas(
    mesh: &TetMesh,
    camera: &Camera,
    (width, height): (u32, u32),
    options: TetOptions,
    map: &OrthoMap,
    control: &Control,
) -> Result<Vec<f32>, Cancelled> {
    let tile = area_tile(width, height);
    let frame = Frame::covering(mesh, camera, width, height, options.lod_pixels, tile);
    let clip = BoxClip::new(camera, mesh.box_size);
    let mut out: Vec<f64> = over_tiles(&frame, control, |i, _| {
        let (x0, y0, w, h) = frame.tile(i);
        let mut sums = AreaTile::new(w as usize, h as usize);
        for &entry in &frame.bins[i as usize] {
            // Whole cells where the mesh is lean (their tets share edges),
            // else tet by tet; the two write the same sums.
            let mut tets = Vec::new();
            frame.cells_of(
                mesh,
                entry,
                i,
                |cell| {
                    // Cells whose outline misses the tile add nothing to it.
                    if !frame.cell_meets_tile(&cell.at_image, i) {
                        return;
                    }
                    let (tets, count) = cell.tets();
                    sums.cell(map, &clip, (&cell.at_image, &tets[..count]), (x0, y0));
                },
                |tet| tets.push(*tet),
            );
            for tet in &tets {
                sums.tet(map, &clip, tet, (x0, y0));
            }
        }
        sums.finish()
    })?;
    add_point_masses(mesh, camera, &frame.screen, &mut out);
    Ok(out.into_iter().map(|v| v as f32).collect())
}
