//! AMR cells over the ranks: each rank reads a run of cells through the
//! one-process reader (`crate::load::amr::read_cells`), the ranks agree
//! on the world frame (its scale from the cells' reach), the fields' ranges
//! and the bounds (the cells' domain, computed as the volume computes its
//! bricks' boxes), decompose a sample of cell centres, and send every cell
//! to each box its basis support overlaps. Each rank then builds an
//! ordinary AMR volume from its cells: inside its box every cell whose tent
//! reaches a point is there, so the reconstruction is the whole volume's,
//! and a projection integrates it (the exact basis line integral) over the
//! part of each ray inside the box, half-open like the cells.

use std::path::Path;

use voxless_amr::{AmrCells, AmrError, AmrVolume};
use voxless_core::{Aabb, Range1, Vec3};
use voxless_parallel::{Comm, CommExt, Reader};
use voxless_scene::AmrDesc;

use super::share::{decompose, exchange, outboxes, root_box};
use super::{ParallelError, Part, PartCounts};
use crate::load::amr::read_cells;
use crate::load::whole_set::{agree, union_bounds};
use crate::load::{Share, amr_settings, cells_reach};
use crate::{AnyVolume, Fields, SceneError, VolumeKind, VolumeSummary};

/// Cells sampled for the decomposition, about.
const SAMPLE: usize = 16_384;

/// The box of a cell's basis support (its tent reaches half a cell beyond
/// it), computed as the volume computes its regions' boxes.
fn support_box(c: &[i32; 4], h: f32) -> Aabb {
    let w = 1i64 << c[3];
    let at = |a: usize, d: i64| (((2 * c[a] as i64 + d) as f64 * 0.5) as f32) * h;
    Aabb::new(
        Vec3::new(at(0, -w), at(1, -w), at(2, -w)),
        Vec3::new(at(0, 3 * w), at(1, 3 * w), at(2, 3 * w)),
    )
}

/// A cell's box, computed as the volume computes its bricks' boxes.
fn cell_box(c: &[i32; 4], h: f32) -> Aabb {
    let w = 1i64 << c[3];
    let at = |a: usize, d: i64| (c[a] as i64 + d) as f64 as f32;
    Aabb::new(
        Vec3::ZERO + Vec3::new(at(0, 0), at(1, 0), at(2, 0)) * h,
        Vec3::ZERO + Vec3::new(at(0, w), at(1, w), at(2, w)) * h,
    )
}

pub(crate) fn open(comm: &dyn Comm, a: &AmrDesc, base: &Path) -> Result<Part, ParallelError> {
    let share = Share {
        rank: comm.rank(),
        ranks: comm.size(),
    };
    let run = agree(comm, read_cells(a, base, share, &Default::default()))?;
    let names: Vec<String> = run.data.fields.iter().map(|f| f.0.clone()).collect();
    let name_refs: Vec<&str> = names.iter().map(String::as_str).collect();
    // The frame's scale from how far the whole data reaches (as one
    // process finds it over every cell).
    let reach = comm.all_max(&[cells_reach(&run.data.cells)])?[0];
    let (settings, frame, h) = amr_settings(
        &name_refs,
        run.data.origin,
        run.data.finest_cell_size as f32,
        reach,
        a,
        &run.source,
    )?;
    // The fields' ranges and the bounds over all cells.
    let nf = names.len();
    let mut lo = vec![f64::INFINITY; nf];
    let mut hi = vec![f64::NEG_INFINITY; nf];
    for (f, (_, v)) in run.data.fields.iter().enumerate() {
        for &x in v {
            lo[f] = lo[f].min(x as f64);
            hi[f] = hi[f].max(x as f64);
        }
    }
    let lo = comm.all_min(&lo)?;
    let hi = comm.all_max(&hi)?;
    let range = |f: usize| {
        if lo[f] <= hi[f] {
            Range1::new(lo[f] as f32, hi[f] as f32)
        } else {
            Range1::EMPTY
        }
    };
    // The bounds are the cells' domain (the volume's bounds: its bricks'
    // boxes), not the tents' margin around them.
    let own = run
        .data
        .cells
        .iter()
        .fold(Aabb::EMPTY, |b, c| b.union(cell_box(c, h)));
    let bounds = union_bounds(comm, own)?;
    let stride = (run.total / SAMPLE).max(1);
    let sample: Vec<Vec3> = run
        .data
        .cells
        .iter()
        .enumerate()
        .filter(|(i, _)| (run.offset + i).is_multiple_of(stride))
        .map(|(_, c)| support_box(c, h).center())
        .collect();
    let decomposition = decompose(comm, root_box(bounds), &sample)?;
    // Every cell to each box its support overlaps, with its index.
    let mut out = outboxes(comm);
    let mut dst = Vec::new();
    for (i, c) in run.data.cells.iter().enumerate() {
        decomposition.overlapping(&support_box(c, h), &mut dst);
        for &r in &dst {
            let w = &mut out[r];
            w.u64((run.offset + i) as u64);
            for v in c {
                w.u32(*v as u32);
            }
            for (_, f) in &run.data.fields {
                w.f32(f[i]);
            }
        }
    }
    let read = run.data.cells.len() as u64;
    drop(run.data);
    let mut got: Vec<(u64, [i32; 4], Vec<f32>)> = Vec::new();
    for msg in exchange(comm, out)? {
        let mut r = Reader::new(&msg);
        while !r.is_done() {
            let i = r.u64()?;
            let c = [
                r.u32()? as i32,
                r.u32()? as i32,
                r.u32()? as i32,
                r.u32()? as i32,
            ];
            let v = (0..nf).map(|_| r.f32()).collect::<Result<Vec<_>, _>>()?;
            got.push((i, c, v));
        }
    }
    got.sort_unstable_by_key(|g| g.0);
    let held = got.len() as u64;
    let cells = AmrCells {
        cells: got.iter().map(|g| g.1).collect(),
        fields: names
            .iter()
            .enumerate()
            .map(|(f, n)| (n.clone(), got.iter().map(|g| g.2[f]).collect()))
            .collect(),
        origin: Vec3::ZERO,
        cell_size: h,
    };
    drop(got);
    let volume = match AmrVolume::new(cells, settings.clone()) {
        Ok(v) => Ok(Some(AnyVolume::Amr(Box::new(v)))),
        Err(AmrError::Empty) => Ok(None),
        Err(e) => Err(SceneError::Amr {
            path: run.source.clone(),
            source: e,
        }),
    };
    let volume = agree(comm, volume)?;
    Ok(Part {
        volume,
        frame,
        summary: VolumeSummary {
            kind: VolumeKind::Amr,
            bounds,
            value_range: range(settings.field),
            attribute_range: settings.color_field.map(range),
        },
        decomposition,
        fields: Fields::Amr(names),
        counts: PartCounts { read, held },
        notes: Vec::new(),
        radii: None,
    })
}
