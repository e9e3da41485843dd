//! Radius and weight scales of particles (`radius_scale`, `weight_scale`):
//! one factor on every particle's radius or weight, whether they came from
//! the global radius, per-particle arrays or the SPH defaults — what an
//! interactive radius slider sets, and what a saved scene repeats.
//!
//! Invariant: the factors are applied once per frame's arrays, before the
//! volume is built (or a new frame is loaded into it), so a time series, a
//! multi-material scene and in-memory arrays all see the same scaled data.

use voxless_particles::ParticleData;
use voxless_scene::ParticlesDesc;

use crate::SceneError;
use crate::checks::positive;

/// The validated `(radius_scale, weight_scale)` of `p` (1 when absent).
pub(crate) fn scales(p: &ParticlesDesc) -> Result<(f32, f32), SceneError> {
    let r = p.radius_scale.unwrap_or(1.0);
    let w = p.weight_scale.unwrap_or(1.0);
    positive("particles.radius_scale", r)?;
    positive("particles.weight_scale", w)?;
    Ok((r, w))
}

/// Multiplies per-particle radii and weights of `data` by `p`'s scales
/// (weights of 1 become explicit when scaled). The global radius is scaled
/// where it is chosen (`build_particles`).
pub(crate) fn scale_arrays(data: &mut ParticleData, p: &ParticlesDesc) -> Result<(), SceneError> {
    let (r, w) = scales(p)?;
    if r != 1.0
        && let Some(radii) = &mut data.radii
    {
        radii.iter_mut().for_each(|x| *x *= r);
    }
    if w != 1.0 {
        match &mut data.weights {
            Some(weights) => weights.iter_mut().for_each(|x| *x *= w),
            None => data.weights = Some(vec![w; data.positions.len()]),
        }
    }
    Ok(())
}
