//! Render, project and sample a [`DistributedScene`]: each rank works on its
//! box, then the images composite by direct send and rank 0 collects them.

use voxless_core::{Camera, Control, Image, Prepare, Range1, Vec3};
use voxless_parallel::composite::{self, OwnedTiles};
use voxless_parallel::{Comm, CommExt, Reader, TileGrid, Writer};
use voxless_render::{Job, PixelRequest};

use super::share::{agree, exchange, outboxes};
use super::{Columns, DistributedScene, ParallelError, Timings};

/// Side of the compositing tiles in pixels: small enough that every rank
/// owns several tiles of a modest image, large enough to keep messages few.
pub(crate) const COMPOSITE_TILE: u32 = 32;

/// The passes of this rank's box composited with every other rank's, for
/// the tiles this rank owns (the sum of the passes; the caller averages).
pub(crate) fn render_part<P: Prepare>(
    volume: &P,
    comm: &dyn Comm,
    s: &DistributedScene,
    grid: &TileGrid,
    order: &[usize],
    control: &Control,
    timings: &mut Timings,
) -> Result<OwnedTiles, ParallelError> {
    let st = &s.settings;
    let prepared = voxless_render::prepare(volume, &s.tf, st);
    let job = Job::new(&prepared, &s.camera, &s.tf, st);
    let per = job.tiles_per_pass();
    let total = per * st.spp as u64;
    let mut acc = OwnedTiles::zeros(*grid, 4, comm.rank(), comm.size());
    for sample in 0..st.spp {
        let t = std::time::Instant::now();
        let pass = job
            .pass_pixels(sample, &control.part(sample as u64 * per, total))
            .map_err(ParallelError::from);
        timings.render += t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let (pixels, _) = agree(comm, pass)?;
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
    Ok(acc)
}

pub(crate) fn render(
    s: &DistributedScene,
    comm: &dyn Comm,
    control: &Control,
    timings: &mut Timings,
) -> Result<Option<Image>, ParallelError> {
    let st = &s.settings;
    let grid = TileGrid::new(st.width, st.height, COMPOSITE_TILE);
    let order = s.decomposition.front_to_back(&s.camera);
    let mut acc = match &s.part {
        Some(v) => v.render_part(comm, s, &grid, &order, control, timings)?,
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
            acc
        }
    };
    acc.scale(1.0 / st.spp.max(1) as f32);
    let t = std::time::Instant::now();
    let image = composite::gather(comm, &acc)?;
    timings.composite += t.elapsed().as_secs_f64();
    Ok(image.map(|v| Image {
        width: st.width,
        height: st.height,
        pixels: v
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect(),
    }))
}

pub(crate) fn project(
    s: &DistributedScene,
    comm: &dyn Comm,
    camera: &Camera,
    width: u32,
    height: u32,
    t: Option<Range1>,
    control: &Control,
) -> Result<Option<Vec<f32>>, ParallelError> {
    let owned = s.decomposition.box_of(comm.rank());
    let values = match &s.part {
        Some(v) => v
            .project_part(camera, width, height, &owned, t, control)
            .map_err(ParallelError::from),
        None => Ok(vec![0.0; (width * height) as usize]),
    };
    let values = agree(comm, values)?;
    let grid = TileGrid::new(width, height, COMPOSITE_TILE);
    let tiles = composite::sum(comm, &grid, &values, 1)?;
    Ok(composite::gather(comm, &tiles)?)
}

/// Where a query at `p` is evaluated (tessellations wrap and nudge it).
fn query_point(columns: &Columns, p: Vec3) -> Vec3 {
    match columns {
        Columns::Tets { box_size, n } => voxless_tets::canonical_point(*box_size, *n, p),
        _ => p,
    }
}

/// The row of a point no data reaches.
fn empty_row(columns: &Columns, width: usize) -> Vec<f32> {
    match columns {
        Columns::Particles { attribute } => {
            let mut row = vec![0.0; width];
            if *attribute {
                row[1] = f32::NAN;
            }
            row
        }
        Columns::Amr(_) => vec![f32::NAN; width],
        Columns::Materials(_) | Columns::Tets { .. } => vec![0.0; width],
    }
}

pub(crate) fn sample(
    s: &DistributedScene,
    comm: &dyn Comm,
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
        if s.decomposition.owner(query_point(&s.columns, p)) == me {
            mine.push(p);
            index.push(i as u64);
        }
    }
    let width = s.sample_columns(gradient).len();
    let values = match &s.part {
        Some(v) => v.sample_points(&mine, gradient),
        None => mine
            .iter()
            .flat_map(|_| empty_row(&s.columns, width))
            .collect(),
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
