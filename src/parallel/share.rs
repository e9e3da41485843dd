//! Which part of a file each rank reads, and the exchange of items to the
//! boxes they reach into.

use std::ops::Range;

use voxless_core::{Aabb, Vec3};
use voxless_parallel::{Comm, CommError, CommExt, Decomposition, Reader, Writer};

use super::ParallelError;

/// Rows `n·r/K .. n·(r+1)/K` of `n`: rank `r`'s share of `K` (every row in
/// exactly one share, shares in rank order).
pub(crate) fn share(n: usize, rank: usize, ranks: usize) -> Range<usize> {
    let ranks = ranks.max(1) as u128;
    let at = |r: usize| (n as u128 * r as u128 / ranks) as usize;
    at(rank)..at(rank + 1)
}

/// Every rank's outcome of a local step: `Ok` everywhere or an error
/// everywhere (this rank's own, or the failing rank's).
pub(crate) fn agree<T, E>(comm: &dyn Comm, local: Result<T, E>) -> Result<T, ParallelError>
where
    E: std::fmt::Display + Into<ParallelError>,
{
    match comm.agree(local)? {
        Ok(v) => Ok(v),
        Err(e) => Err(e.into()),
    }
}

/// The union over all ranks of their boxes.
pub(crate) fn union_bounds(comm: &dyn Comm, b: Aabb) -> Result<Aabb, CommError> {
    let (lo, hi) = if b.is_empty() {
        ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3])
    } else {
        (
            [b.min.x as f64, b.min.y as f64, b.min.z as f64],
            [b.max.x as f64, b.max.y as f64, b.max.z as f64],
        )
    };
    let lo = comm.all_min(&lo)?;
    let hi = comm.all_max(&hi)?;
    Ok(Aabb::new(
        Vec3::new(lo[0] as f32, lo[1] as f32, lo[2] as f32),
        Vec3::new(hi[0] as f32, hi[1] as f32, hi[2] as f32),
    ))
}

/// The root box a decomposition tiles: the data's bounds grown a little,
/// so that the half-open boxes hold every point of the data.
pub(crate) fn root_box(bounds: Aabb) -> Aabb {
    if bounds.is_empty() {
        return Aabb::new(Vec3::ZERO, Vec3::ONE);
    }
    let far = (0..3).fold(0.0f32, |m, a| {
        m.max(bounds.min[a].abs()).max(bounds.max[a].abs())
    });
    let pad = bounds.diagonal() * 1e-3 + far * 1e-6;
    let pad = Vec3::splat(pad.max(f32::MIN_POSITIVE));
    Aabb::new(bounds.min - pad, bounds.max + pad)
}

/// The decomposition every rank builds from the same gathered sample:
/// each rank contributes `mine` (positions, in its share's order).
pub(crate) fn decompose(
    comm: &dyn Comm,
    root: Aabb,
    mine: &[Vec3],
) -> Result<Decomposition, CommError> {
    let mut w = Writer::with_capacity(12 * mine.len() + 8);
    w.u64(mine.len() as u64);
    for p in mine {
        w.vec3(*p);
    }
    let mut points = Vec::new();
    for msg in comm.all_gather(&w.into_bytes())? {
        let mut r = Reader::new(&msg);
        for _ in 0..r.u64()? {
            points.push((r.vec3()?, 1.0));
        }
    }
    Ok(Decomposition::build(root, &points, comm.size()))
}

/// Sends each rank its messages and returns what arrived, by source rank.
pub(crate) fn exchange(comm: &dyn Comm, out: Vec<Writer>) -> Result<Vec<Vec<u8>>, CommError> {
    comm.exchange(out.into_iter().map(Writer::into_bytes).collect())
}

/// One empty message per rank.
pub(crate) fn outboxes(comm: &dyn Comm) -> Vec<Writer> {
    (0..comm.size()).map(|_| Writer::new()).collect()
}
