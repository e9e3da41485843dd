//! What a device integrator (the GPU backend) uploads of a particle volume
//! to evaluate Φ and Θ as [`ParticleVolume::field`] does: the packed
//! particles in the volume's (Hilbert) order, the attribute, the BVH over
//! clusters of `cluster_size` particles, and the step its intervals
//! carry.

use voxless_bvh::Bvh;

use super::ParticleVolume;

/// A particle volume's arrays for a device (see the module docs).
pub struct DeviceParticles<'a> {
    /// Per particle: centre x, y, z, squared support radius (negative for
    /// a hidden particle: it never covers a point), and the kernel's packed
    /// `(shape, amplitude)` ([`crate::Kernel::pack`]).
    pub packed: Vec<[f32; 6]>,
    /// Per particle, the scalar attribute (Θ's `sᵢ`).
    pub attribute: Option<&'a [f32]>,
    /// Leaf `c` holds particles `c·cluster_size ..` (at most
    /// `cluster_size` of them).
    pub bvh: &'a Bvh,
    pub cluster_size: usize,
    /// The sampled intervals' nominal step (a fraction of the median
    /// support).
    pub nominal_dt: f32,
}

impl ParticleVolume {
    /// The arrays a device integrator uploads (see [`DeviceParticles`]).
    pub fn device_particles(&self) -> DeviceParticles<'_> {
        DeviceParticles {
            packed: self
                .packed
                .iter()
                .map(|q| {
                    [
                        q.center.x, q.center.y, q.center.z, q.support2, q.shape, q.amp,
                    ]
                })
                .collect(),
            attribute: self.attribute.as_deref(),
            bvh: &self.bvh,
            cluster_size: self.settings.cluster_size,
            nominal_dt: self.nominal_dt,
        }
    }
}
