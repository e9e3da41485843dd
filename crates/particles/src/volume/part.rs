//! Parts of a particle set split over the boxes of a domain decomposition,
//! and the pieces of a volume's construction that the whole set and its
//! parts share, so both compute them identically.
//!
//! A part holds the particles whose supports reach into its box. Its
//! statistics — the median support (which sets the sampling step) and the
//! density range (which normalises the transfer function) — must be the
//! whole set's, not its own, or a decomposed render would sample and colour
//! differently. The whole set's are computed from *probes*: every
//! [`probe_stride`]-th particle in input order, which a rank holding rows
//! `a..b` of a file finds by their row numbers.

use voxless_core::{Aabb, Range1, Vec3};
use voxless_transfer::ControlPoints;

use super::{ParticleData, ParticleSettings, ParticleVolume};
use crate::error::ParticleError;
use crate::kernel::Kernel;

/// About this many probes estimate the median support and max Φ. The
/// estimate only normalises the transfer function and sets the step, and
/// it dominated the cost of a radius change at 65,536 probes
/// (docs/benchmarks.md).
pub const RANGE_PROBES: usize = 16_384;

/// Probes are the particles whose input row is a multiple of this.
pub fn probe_stride(n: usize) -> usize {
    (n / RANGE_PROBES).max(1)
}

/// What a part of a decomposed particle set takes from the whole set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldStatistics {
    /// The probes' median support radius: the step is 1/8 of it.
    pub median_support: f32,
    /// `[0, max Φ over the probes' centres]`.
    pub value_range: Range1,
}

/// The median of `v` (the upper one of an even count); 0 when empty.
pub fn median(v: &mut [f32]) -> f32 {
    if v.is_empty() {
        return 0.0;
    }
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f32::total_cmp).1
}

/// A radius or weight map's factor for a particle with attribute `attr`
/// (normalised to `range`); 1 without a map or attribute. Values ≤ 0 hide
/// the particle.
pub(crate) fn map_factor(map: &Option<ControlPoints>, attr: Option<f32>, range: Range1) -> f32 {
    match (map, attr) {
        (Some(m), Some(a)) => m.eval(range.normalize(a)).max(0.0),
        _ => 1.0,
    }
}

/// The box of a particle's support at `center` with radius parameter
/// `radius`, exactly as the BVH sees it (empty for a hidden particle).
pub fn support_box(center: Vec3, radius: f32, kernel: Kernel) -> Aabb {
    if radius > 0.0 {
        let support = kernel.support_factor() * radius;
        Aabb::around(center, (support * support).sqrt())
    } else {
        Aabb::EMPTY
    }
}

fn check_len(what: &'static str, n: usize, v: &Option<Vec<f32>>) -> Result<(), ParticleError> {
    match v {
        Some(v) if v.len() != n => Err(ParticleError::LengthMismatch {
            what,
            expected: n,
            got: v.len(),
        }),
        _ => Ok(()),
    }
}

/// Checks `data`'s arrays (lengths, finite positions and attributes,
/// positive radii, non-negative weights); errors name the particle by its
/// row `offset + i`, so a rank checking rows `offset..` of a file names the
/// file's row.
pub fn check_data(data: &ParticleData, offset: usize) -> Result<(), ParticleError> {
    let n = data.positions.len();
    check_len("radii", n, &data.radii)?;
    check_len("attribute", n, &data.attribute)?;
    check_len("weights", n, &data.weights)?;
    if let Some(i) = data.positions.iter().position(|p| !p.is_finite()) {
        let p = data.positions[i];
        return Err(ParticleError::NonFinitePosition {
            index: offset + i,
            x: p.x,
            y: p.y,
            z: p.z,
        });
    }
    if let Some(r) = &data.radii
        && let Some(i) = r.iter().position(|r| !(r.is_finite() && *r > 0.0))
    {
        return Err(ParticleError::BadRadius {
            index: offset + i,
            value: r[i],
        });
    }
    if let Some(a) = &data.attribute
        && let Some(i) = a.iter().position(|a| !a.is_finite())
    {
        return Err(ParticleError::NonFiniteValue {
            index: offset + i,
            what: "attribute",
            value: a[i],
        });
    }
    if let Some(w) = &data.weights
        && let Some(i) = w.iter().position(|w| !(w.is_finite() && *w >= 0.0))
    {
        return Err(ParticleError::BadWeight {
            index: offset + i,
            value: w[i],
        });
    }
    Ok(())
}

impl ParticleSettings {
    /// Particle radius parameter after the radius map: `base` (its own or
    /// the global radius) times the map's factor for attribute `attr`
    /// normalised to `range`.
    pub fn effective_radius(&self, base: f32, attr: Option<f32>, range: Range1) -> f32 {
        base * map_factor(&self.radius_map, attr, range)
    }
}

impl ParticleVolume {
    /// A volume over one part of a decomposed particle set (the particles
    /// whose supports reach into one box, in the whole set's input order),
    /// with the whole set's `statistics` and `settings` whose attribute
    /// range is the whole set's. A part may be empty, and it is not refused
    /// for supports larger than its own extent (the whole set was checked).
    pub fn new_part(
        data: ParticleData,
        settings: ParticleSettings,
        statistics: FieldStatistics,
    ) -> Result<ParticleVolume, ParticleError> {
        Self::build(data, settings, Default::default(), Some(statistics))
    }

    /// The statistics this volume renders with.
    pub fn statistics(&self) -> FieldStatistics {
        FieldStatistics {
            median_support: self.nominal_dt * 8.0,
            value_range: voxless_core::Volume::value_range(self),
        }
    }
}

impl ParticleVolume {
    /// Sets the density range (a part of a decomposed set takes the whole
    /// set's, known only once every part is built).
    pub fn set_value_range(&mut self, range: voxless_core::Range1) {
        self.value_range = std::sync::OnceLock::from(range);
    }
}
