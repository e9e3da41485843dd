//! The probe of a decomposed volume's field ([`crate::autorange`]) that a
//! view's defaults come from: the ranks sample its points together, each
//! point by the rank whose box holds it.

use rayon::prelude::*;
use voxless_core::Aabb;
use voxless_parallel::Comm;

use super::{ParallelError, Part};
use crate::VolumeKind;
use crate::autorange::{Probe, values_where};

/// The probe of `part`'s volume within the whole data's bounds (and `clip`,
/// local): every point evaluated by the rank whose box holds it, the
/// values gathered on every rank — the probe one process takes.
pub(crate) fn probe(
    comm: &dyn Comm,
    part: &Part,
    clip: Option<&Aabb>,
) -> Result<Probe, ParallelError> {
    if part.summary.kind == VolumeKind::Materials {
        return Ok(Probe::default());
    }
    let (decomposition, part_volume) = (&part.decomposition, part.volume.as_ref());
    let mut b = part.summary.bounds;
    if let Some(c) = clip {
        b = Aabb::new(b.min.max(c.min), b.max.min(c.max));
    }
    let points = Probe::points(&b);
    let owners: Vec<usize> = points.par_iter().map(|&q| decomposition.owner(q)).collect();
    let me = comm.rank();
    let mine: Vec<u8> = values_where(part_volume, &points, |i| owners[i] == me)
        .into_iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let all = comm.all_gather(&mine)?;
    let values: Vec<f32> = owners
        .iter()
        .enumerate()
        .map(|(i, &o)| {
            all.get(o)
                .and_then(|m| m.get(4 * i..4 * i + 4))
                .map_or(f32::NAN, |b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        })
        .collect();
    Ok(Probe::from_values(&b, &values))
}
