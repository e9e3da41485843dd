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
    // One slab of the lattice per task: each returns its own counts, added
    // after (no shared counters in the loop).
    let slabs: Vec<(Vec<u32>, u32, u32, Range1)> = (0..n)
        .into_par_iter()
        .map(|k| {
            let mut counts = vec![0u32; bins];
            let (mut below, mut above, mut seen) = (0, 0, Range1::EMPTY);
            for j in 0..n {
                for i in 0..n {
                    let p = region.min
                        + Vec3::new(
                            (i as f32 + 0.5) * cell.x,
                            (j as f32 + 0.5) * cell.y,
                            (k as f32 + 0.5) * cell.z,
                        );
                    let Some(v) = value_at(volume, p) else {
                        continue;
                    };
                    // Zero is empty space (and has no logarithm).
                    if !(v.is_finite() && v != 0.0) || (settings.log_scale && v < 0.0) {
                        continue;
                    }
                    let x = if settings.log_scale { v.log10() } else { v };
                    seen.extend(x);
                    if x < range.lo {
                        below += 1;
                    } else if x > range.hi {
                        above += 1;
                    } else {
                        let f = if range.span() > 0.0 {
                            (x - range.lo) / range.span()
                        } else {
                            0.0
                        };
                        counts[((f * bins as f32) as usize).min(bins - 1)] += 1;
                    }
                }
            }
            (counts, below, above, seen)
        })
        .collect();
    let mut seen = Range1::EMPTY;
    for (counts, below, above, s) in slabs {
        for (o, c) in out.counts.iter_mut().zip(counts) {
            *o += c;
        }
        out.below += below;
        out.above += above;
        seen = seen.union(s);
    }
    out.seen = (!seen.is_empty()).then_some([seen.lo, seen.hi]);
    out
}

/// The classified field at `p`, through the kind's own `Volume::sample`.
fn value_at(volume: &AnyVolume, p: Vec3) -> Option<f32> {
    let s = match volume {
        AnyVolume::Particles(v) => v.sample(p),
        AnyVolume::Amr(v) => v.sample(p),
        AnyVolume::Tets(v) => v.sample(p),
        AnyVolume::Materials(v) => v.sample(p),
    };
    s.map(|s| s.value)
}
