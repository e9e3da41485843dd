//! The decomposition the ranks build from a sample of the data, and the
//! exchange of items to the boxes they reach into.

use voxless_core::{Aabb, Vec3};
use voxless_parallel::{Comm, CommError, Decomposition, Reader, Writer};

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
