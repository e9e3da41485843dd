//! Render, project and sample a decomposed scene: each rank works on its
//! box, then the images composite by direct send and rank 0 collects them.

use voxless_core::{Aabb, Camera, Control, Image, Prepare, Range1, Vec3};
use voxless_parallel::composite::{self, OwnedTiles};
use voxless_parallel::{Comm, CommExt, Decomposition, Reader, TileGrid, Writer};
use voxless_render::{Job, PixelRequest, RayStats, WorkEstimate};

use super::share::{exchange, outboxes};
use super::{ParallelError, Timings};
use crate::load::whole_set::agree;
use crate::volume::with_volume;
use crate::{AnyVolume, Fields, Resolved};

/// Side of the compositing tiles in pixels: small enough that every rank
/// owns several tiles of a modest image, large enough to keep messages few.
pub(crate) const COMPOSITE_TILE: u32 = 32;

/// The passes of this rank's box composited with every other rank's, for
/// the tiles this rank owns (the sum of the passes; the caller averages),
/// and what this rank's rays saw.
fn render_part<P: Prepare>(
    volume: &P,
    comm: &dyn Comm,
    view: &Resolved,
    grid: &TileGrid,
    order: &[usize],
    control: &Control,
    timings: &mut Timings,
) -> Result<(OwnedTiles, RayStats), ParallelError> {
    let st = &view.settings;
    let prepared = voxless_render::prepare(volume, &view.tf, st);
    let job = Job::new(&prepared, &view.camera, &view.tf, st);
    let per = job.tiles_per_pass();
    let total = per * st.spp as u64;
    let mut acc = OwnedTiles::zeros(*grid, 4, comm.rank(), comm.size());
    let mut seen = RayStats::default();
    for sample in 0..st.spp {
        let t = std::time::Instant::now();
        let pass = job
            .pass_pixels(sample, &control.part(sample as u64 * per, total))
            .map_err(ParallelError::from);
        timings.render += t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let (pixels, stats) = agree(comm, pass)?;
        seen.merge(&stats);
        let tiles = composite::over(
            comm,
            grid,
            &pixels,
            order,
            st.early_termination,
            &mut |req| {
                let req: Vec<PixelRequest> = req
                    .iter()
                    .map(|&(x, y, alpha)| PixelRequest { x, y, alpha })
                    .collect();
                job.render_pixels(sample, &req)
            },
        )?;
        acc.add(&tiles);
        timings.composite += t.elapsed().as_secs_f64();
    }
    Ok((acc, seen))
}

/// Renders all passes of `part` (this rank's data, `None` when no data
/// reaches its box) with `view` (its settings restricted to this rank's
/// box): on rank 0 the image and what the rays of every rank saw, `None`
/// on the others.
pub(crate) fn render(
    comm: &dyn Comm,
    part: Option<&AnyVolume>,
    view: &Resolved,
    decomposition: &Decomposition,
    control: &Control,
    timings: &mut Timings,
) -> Result<Option<(Image, RayStats)>, ParallelError> {
    let st = &view.settings;
    let grid = TileGrid::new(st.width, st.height, COMPOSITE_TILE);
    let order = decomposition.front_to_back(&view.camera);
    let (mut acc, seen) = match part {
        Some(v) => with_volume!(v, v => {
            render_part(v, comm, view, &grid, &order, control, timings)?
        }),
        None => {
            // No data here: take part in every pass with an empty image.
            let empty = vec![[0.0f32; 4]; (st.width * st.height) as usize];
            let mut acc = OwnedTiles::zeros(grid, 4, comm.rank(), comm.size());
            for _ in 0..st.spp {
                let t = std::time::Instant::now();
                agree(comm, Ok::<(), ParallelError>(()))?;
                let tiles = composite::over(
                    comm,
                    &grid,
                    &empty,
                    &order,
                    st.early_termination,
                    &mut |req| vec![[0.0; 4]; req.len()],
                )?;
                acc.add(&tiles);
                timings.composite += t.elapsed().as_secs_f64();
            }
            (acc, RayStats::default())
        }
    };
    acc.scale(1.0 / st.spp.max(1) as f32);
    let t = std::time::Instant::now();
    let image = composite::gather(comm, &acc)?;
    // What every rank's rays saw (as one film would say it).
    let lo = comm.all_min(&[seen.values.lo as f64])?[0];
    let hi = comm.all_max(&[seen.values.hi as f64])?[0];
    let hits = comm.all_gather_f64(&[seen.iso_hits as f64])?;
    let seen = RayStats {
        iso_hits: hits.iter().map(|h| h[0] as u64).sum(),
        values: Range1::new(lo as f32, hi as f32),
    };
    timings.composite += t.elapsed().as_secs_f64();
    Ok(image.map(|v| {
        let image = Image {
            width: st.width,
            height: st.height,
            pixels: v
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]])
                .collect(),
        };
        (image, seen)
    }))
}

/// The work of a render over every rank: the sum of the ranks' estimates
/// for their boxes (see [`crate::AnyVolume::estimate_work`]).
pub(crate) fn work(
    comm: &dyn Comm,
    part: Option<&AnyVolume>,
    view: &Resolved,
) -> Result<WorkEstimate, ParallelError> {
    let w = part.map_or(
        WorkEstimate {
            per_ray: 0.0,
            max_per_ray: 0.0,
            total: 0.0,
            step_raised: false,
        },
        |v| v.estimate_work(&view.camera, &view.tf, &view.settings),
    );
    let all = comm.all_gather_f64(&[
        w.per_ray,
        w.max_per_ray,
        w.total,
        w.step_raised as u8 as f64,
    ])?;
    Ok(WorkEstimate {
        per_ray: all.iter().map(|v| v[0]).sum(),
        max_per_ray: all.iter().map(|v| v[1]).sum(),
        total: all.iter().map(|v| v[2]).sum(),
        step_raised: all.iter().any(|v| v[3] > 0.0),
    })
}

/// Column densities (local units) over the part `t` of every pixel's line
/// (`None`: the whole line) of `camera`: each rank integrates the part of
/// each line inside its box (a tessellation, which holds each tet in one
/// box only, projects its tets whole), and the images add up on rank 0.
#[allow(clippy::too_many_arguments)]
pub(crate) fn project(
    comm: &dyn Comm,
    part: Option<&AnyVolume>,
    decomposition: &Decomposition,
    camera: &Camera,
    width: u32,
    height: u32,
    t: Option<Range1>,
    control: &Control,
) -> Result<Option<Vec<f32>>, ParallelError> {
    let owned = decomposition.box_of(comm.rank());
    let values = match part {
        Some(v) => {
            project_part(v, camera, width, height, &owned, t, control).map_err(ParallelError::from)
        }
        None => Ok(vec![0.0; (width * height) as usize]),
    };
    let values = agree(comm, values)?;
    let grid = TileGrid::new(width, height, COMPOSITE_TILE);
    let tiles = composite::sum(comm, &grid, &values, 1)?;
    Ok(composite::gather(comm, &tiles)?)
}

/// This rank's share of a decomposed projection (see [`project`]).
fn project_part(
    v: &AnyVolume,
    camera: &Camera,
    width: u32,
    height: u32,
    owned: &Aabb,
    t: Option<Range1>,
    control: &Control,
) -> Result<Vec<f32>, voxless_core::Cancelled> {
    match (v, t) {
        (AnyVolume::Tets(_), None) => v.project(camera, width, height, control),
        (AnyVolume::Tets(_), Some(t)) => v.project_in(camera, width, height, t, control),
        _ => with_volume!(v, v => {
            let all = Range1::new(f32::NEG_INFINITY, f32::INFINITY);
            let t = t.unwrap_or(all);
            voxless_render::project_in(v, camera, width, height, Some(owned), t, control)
        }),
    }
}

/// The fields at `points` (rank 0's; the others may pass none): each point
/// evaluated by the rank whose box holds it, the rows gathered on rank 0
/// (`None` on the others), row-major `points × columns`.
pub(crate) fn sample(
    comm: &dyn Comm,
    part: Option<&AnyVolume>,
    decomposition: &Decomposition,
    fields: &Fields,
    points: &[Vec3],
    gradient: bool,
) -> Result<Option<Vec<f32>>, ParallelError> {
    let mut w = Writer::new();
    w.u64(points.len() as u64);
    for p in points {
        w.vec3(*p);
    }
    let all = comm.broadcast(0, &w.into_bytes())?;
    let mut r = Reader::new(&all);
    let count = r.u64()? as usize;
    let mut mine = Vec::new();
    let mut index = Vec::new();
    let me = comm.rank();
    for i in 0..count {
        let p = r.vec3()?;
        if decomposition.owner(fields.query_point(p)) == me {
            mine.push(p);
            index.push(i as u64);
        }
    }
    let width = fields.columns(gradient).len();
    let values = match part {
        Some(v) => v.sample_points(&mine, gradient),
        None => mine.iter().flat_map(|_| fields.empty_row(width)).collect(),
    };
    let mut out = outboxes(comm);
    for (k, i) in index.iter().enumerate() {
        out[0].u64(*i);
        out[0].f32s(&values[k * width..(k + 1) * width]);
    }
    let got = exchange(comm, out)?;
    if me != 0 {
        return Ok(None);
    }
    let mut result = vec![0.0f32; count * width];
    for msg in &got {
        let mut r = Reader::new(msg);
        while !r.is_done() {
            let i = r.u64()? as usize;
            let row = r.f32s()?;
            if i >= count || row.len() != width {
                return Err(voxless_parallel::CommError::Transport(format!(
                    "a sampled row {i} of {} values does not fit {count} points × {width} columns",
                    row.len()
                ))
                .into());
            }
            result[i * width..(i + 1) * width].copy_from_slice(&row);
        }
    }
    Ok(Some(result))
}

/// Every rank's image (`None` from a rank without one), on rank 0 in rank
/// order; empty on the others.
pub(crate) fn gather_images(
    comm: &dyn Comm,
    mine: Option<Image>,
) -> Result<Vec<Option<Image>>, ParallelError> {
    let mut send = vec![Vec::new(); comm.size()];
    if let Some(img) = &mine {
        let mut w = Writer::new();
        w.u32(img.width);
        w.u32(img.height);
        w.f32s(img.pixels.as_flattened());
        send[0] = w.into_bytes();
    }
    let got = comm.exchange(send)?;
    if !comm.is_root() {
        return Ok(Vec::new());
    }
    let mut images = Vec::with_capacity(got.len());
    for bytes in got {
        if bytes.is_empty() {
            images.push(None);
            continue;
        }
        let mut r = Reader::new(&bytes);
        let (width, height) = (r.u32()?, r.u32()?);
        let v = r.f32s()?;
        images.push(Some(Image {
            width,
            height,
            pixels: v
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]])
                .collect(),
        }));
    }
    Ok(images)
}
