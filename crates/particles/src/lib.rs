//! Particle volumes: attribute-aware radial basis functions.
//!
//! Every particle `i` has a centre `cᵢ`, a radius parameter `rᵢ`, a weight
//! `wᵢ` and optionally a scalar attribute `sᵢ`. Its kernel `φᵢ` (see
//! [`kernel`] for the Gaussians and the SPH kernels — the cubic, quartic and
//! quintic splines and Wendland C2/C4/C6, whose radius is the smoothing
//! length `h` and whose weights are masses — and their formulas) has compact
//! support `Rᵢ = support_factor·rᵢ`. The reconstructed fields are
//!
//! - the density `Φ(x) = Σᵢ φᵢ(x)` (attribute-aware RBF paper, eq. 3), which
//!   drives opacity, and its exact gradient `∇Φ = Σᵢ ∇φᵢ`;
//! - the attribute field `Θ(x) = Σᵢ sᵢ φᵢ(x) / Φ(x)` (eq. 5), a kernel-weighted
//!   average: **post-classification** colour-maps `Θ`; **pre-classification**
//!   colour-maps each `sᵢ` first and averages the colours with the same
//!   weights, so categorical attributes keep distinct colours.
//!
//! Radii and weights can be driven by the attribute (paper §3.2.2): a *radius
//! map* gives a fraction of the global radius and a *weight map* gives `wᵢ`,
//! both as sparse control points over the attribute normalised to its range.
//! A map value ≤ 0 hides the particle (it no longer touches the field or the
//! acceleration structure): a documented clamp, not an error.
//!
//! **Acceleration** (paper §3.1.3, §3.2.3): particles are sorted along a
//! Hilbert curve and grouped into clusters of `N` consecutive particles
//! (`N ∈ 1..=16`); a [`voxless_bvh::Bvh`] over the cluster boxes (the union of
//! the members' support boxes) answers point queries, visiting only clusters
//! whose box contains the point and then testing each member's support. A
//! radius change refits the tree instead of rebuilding it.
//!
//! **Packets** (paper §4.1): [`ParticleVolume::sample_batch_with`] fills a
//! whole packet's sample buffer in one BVH pass, with the SIMD backend given
//! as a value ([`voxless_core::Simd`]; every backend gives the same bits) and
//! the pre-classified colours passed in; it sums the same terms in the same
//! order as the per-sample path, within a few ulp.
//!
//! **Intervals** come from a macrocell grid whose cells store `[0, Σ peak φᵢ]`
//! over the particles touching the cell, a conservative range of `Φ`.
//!
//! **Multi-material** volumes ([`MaterialVolume`]) give each species its own
//! density field, radius and transfer function, blended per sample.
//!
//! **Per-render contexts.** A volume holds nothing that depends on a
//! render: preparing it ([`voxless_core::Prepare`]) gives a
//! [`ParticleContext`] with the render's pre-classified colours (each
//! particle's attribute through the render's colormap, computed once per
//! render) and its SIMD backend, so one volume serves renders with
//! different transfer functions at once.
//!
//! **Projections** splat ([`splat`]): each particle adds its exact column
//! to the pixels its support covers, summed in f64 band by band; the same
//! [`splat::Splatter`] takes a volume's particles or a file's, streamed in
//! chunks that are never all held.
//!
//! **Levels of detail**: [`ParticleVolume::merged`] merges runs of `8^k`
//! Hilbert-ordered particles into one kernel each (mass, centroid and
//! second moment kept); [`ParticleVolume::preview`] is the merged volume a
//! large set's coarse images come from.
//!
//! Invariants: positions, radii, weights and attributes are finite (checked
//! on construction, with the offending particle named); hidden particles have
//! radius 0 and are skipped by every query.

mod context;
mod error;
pub mod kernel;
mod materials;
pub mod neighbours;
pub mod splat;
mod volume;

pub use context::{MaterialContext, ParticleContext};
pub use error::ParticleError;
pub use kernel::{KERNEL_NAMES, Kernel};
pub use materials::{Material, MaterialClass, MaterialVolume};
pub use volume::{
    Classification, DeviceParticles, FieldSample, FieldStatistics, MAX_PERIODS, ParticleData,
    ParticleSettings, ParticleVolume, RANGE_PROBES, check_data, images, median, probe_stride,
    support_box, wrap,
};

#[cfg(test)]
mod packet_tests;
#[cfg(test)]
mod periodic_tests;
#[cfg(test)]
mod sph_tests;
#[cfg(test)]
mod tests;
