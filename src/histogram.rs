//! [`Histogram`] of the field a transfer function classifies: what a
//! transfer-function editor draws under its opacity curve, so a user sees
//! where the data's values lie before placing control points.
//!
//! Model: the field is sampled at the centres of an `n × n × n` lattice of
//! cells over the volume's bounds (cut to the clip box, when there is one),
//! through the same [`Volume::sample`] the renderer uses — so it is the
//! field as rendered (AMR reconstruction, tessellation densities summed
//! over streams), whatever the data kind. Points outside the data's support
//! and values of zero (empty space, which would swamp every other bin) are
//! not counted. Values are taken in the transfer function's units (log10 in
//! log scale) and binned uniformly over its value range; values outside
//! the range are counted apart, so the editor can say how much lies beyond.

use rayon::prelude::*;
use voxless_core::{Aabb, Range1, Vec3, Volume};
use voxless_render::RenderSettings;

use crate::AnyVolume;

/// Counts of field values per bin of the transfer function's value range.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Histogram {
    /// Bin `i` counts values in `[lo + i·w, lo + (i+1)·w)` of the value
    /// range (the last bin includes `hi`).
    pub counts: Vec<u32>,
    /// The value range binned, in the transfer function's units.
    pub range: [f32; 2],
    /// Whether values are log10 of the field.
    pub log_scale: bool,
    /// Non-zero samples below and above the range.
    pub below: u32,
    pub above: u32,
    /// The smallest and largest non-zero value seen (transfer-function
    /// units); `None` when no sample met the data.
    pub seen: Option<[f32; 2]>,
}

/// The histogram of `volume`'s field over `bins` bins of `settings`'
/// value range, from `n³` lattice samples (see the module docs).
pub fn field_histogram(
    volume: &AnyVolume,
    settings: &RenderSettings,
    bins: usize,
    n: usize,
) -> Histogram {
    let bins = bins.max(1);
    let n = n.clamp(1, 512);
    let mut region = volume.bounds();
    if let Some(c) = settings.clip {
        region = Aabb::new(region.min.max(c.min), region.max.min(c.max));
    }
    let range = settings.value_range;
    let mut out = Histogram {
        counts: vec![0; bins],
        range: [range.lo, range.hi],
        log_scale: settings.log_scale,
        ..Default::default()
    };
    if region.is_empty() {
        return out;
    }
    let cell = region.extent() * (1.0 / n as f32);
    let mut seen = Range1::EMPTY;
    // Slabs of the lattice a few million points at a time, each chunk's
    // values in one call (a tessellation sweeps its cells once a chunk
    // instead of building its point index).
    let per_chunk = (CHUNK_POINTS / (n * n)).max(1);
    for slabs in (0..n).collect::<Vec<_>>().chunks(per_chunk) {
        let points: Vec<Vec3> = slabs
            .iter()
            .flat_map(|&k| (0..n * n).map(move |ij| (ij % n, ij / n, k)))
            .map(|(i, j, k)| {
                region.min
                    + Vec3::new(
                        (i as f32 + 0.5) * cell.x,
                        (j as f32 + 0.5) * cell.y,
                        (k as f32 + 0.5) * cell.z,
                    )
            })
            .collect();
        for v in values_at(volume, &points).into_iter().flatten() {
            // Zero is empty space (and has no logarithm).
            if !(v.is_finite() && v != 0.0) || (settings.log_scale && v < 0.0) {
                continue;
            }
            let x = if settings.log_scale { v.log10() } else { v };
            seen.extend(x);
            if x < range.lo {
                out.below += 1;
            } else if x > range.hi {
                out.above += 1;
            } else {
                let f = if range.span() > 0.0 {
                    (x - range.lo) / range.span()
                } else {
                    0.0
                };
                out.counts[((f * bins as f32) as usize).min(bins - 1)] += 1;
            }
        }
    }
    out.seen = (!seen.is_empty()).then_some([seen.lo, seen.hi]);
    out
}

/// Lattice points sampled per call.
const CHUNK_POINTS: usize = 1 << 22;

/// The classified field at each of `points`, through the kind's own
/// `Volume::sample` (a tessellation's [`voxless_tets::TetVolume::samples`]:
/// the same values in one sweep over its cells).
fn values_at(volume: &AnyVolume, points: &[Vec3]) -> Vec<Option<f32>> {
    let value = |s: Option<voxless_core::Sample>| s.map(|s| s.value);
    match volume {
        AnyVolume::Tets(v) => v.samples(points).into_iter().map(value).collect(),
        _ => points
            .par_iter()
            .map(|&p| {
                value(match volume {
                    AnyVolume::Particles(v) => v.sample(p),
                    AnyVolume::Amr(v) => v.sample(p),
                    AnyVolume::Tets(v) => v.sample(p),
                    AnyVolume::Materials(v) => v.sample(p),
                })
            })
            .collect(),
    }
}
