//! Phase-space tessellations of N-body dark matter (Kähler, Hahn & Abel).
//!
//! **Model.** N³ tracer particles start on a Lagrangian grid; their current
//! positions (periodic box `[0, L)³`) keep the grid's connectivity. Each
//! Lagrangian cell is split into 6 tetrahedra sharing its main diagonal (the
//! Kuhn decomposition, consistent between neighbours), every tet carries mass
//! `m_particle / 6`, and its density is `ρ = m/|V|`. Where sheets fold
//! (shell crossing), tets overlap: the density at a point is the sum over the
//! tets covering it (eq. 1 of the paper), and the number of those tets is the
//! stream count.
//!
//! **Lean meshes.** A mesh over a grid holds the positions (12 bytes a
//! particle) and, per 8³-cell culling block, the bounds of each group of
//! image tets — nothing per tet. The six tets of a cell are derived from
//! its grid indices whenever an operation visits it, with the arithmetic of
//! an explicit construction, so every image is the same bit for bit
//! (`crate::lattice`). Acceleration structures are built by the operations
//! that need them, on first use: the point/ray index (a BVH over cells) by
//! single point samples, shadow rays and per-ray integrals (many points at
//! once — a transfer-function probe — take one sweep over the cells
//! instead, with the same values: `TetVolume::densities_and_streams`); the coarser levels of
//! detail by renders with a threshold; the default density range by renders.
//! Projections build none of them. Meshes assembled tet by tet (a part of a
//! decomposed run, [`TetMeshBuilder`]) hold their tets and work the same way.
//!
//! **Periodicity.** Every tet is unwrapped to the periodic image nearest its
//! anchor vertex (no tet spans the box), and a tet that crosses a face of the
//! box is repeated at the images that bring its parts back in, so a view of
//! exactly the box shows every tet whole and conserves mass.
//!
//! **Degenerate tets.** At caustics `|V| → 0`. Tets with `|V|` below
//! `degenerate_fraction` (default 1e-6) of the mean tet volume are kept as
//! point masses at their centroid: projections add them to the pixel that
//! contains them, so total mass stays exact; renders and point samples, which
//! see volumes, ignore them (they cover no volume).
//!
//! **Rendering** goes through the shared integrator: [`TetVolume`] hands out
//! *constant* intervals — the pieces between sorted tet entry/exit events,
//! on which the density is constant — which integrators composite in closed
//! form, so the image has no sampling error. For a whole screen tile at once
//! ([`events::TetTileView`]) every tet of the tile's culling blocks is
//! rasterised once; the k-buffer (first `k` events exact, the rest in
//! log-spaced depth layers, the paper's bounded-memory mode) is an option of
//! the render ([`voxless_core::EventBudget`]). Single rays (shadows) get
//! their events from the point/ray index. Column-density projections
//! ([`render::project`]) of orthographic views evaluate eight pixel centres
//! of a tet's row at a time (AVX2 where the CPU has it), or, with
//! [`PixelIntegral::Area`], integrate each tet's piecewise-linear column
//! exactly over pixel squares (`crate::area`), so the projected mass does
//! not depend on the resolution.

mod area;
pub mod events;
mod faces;
mod frame;
mod index;
mod lattice;
pub mod mesh;
mod ortho;
mod points;
pub mod raster;
pub mod render;
#[cfg(any(test, feature = "testing"))]
pub mod testing;
mod volume;

pub use events::TetTileView;
pub use mesh::{
    BLOCK, Block, LagrangianGrid, LagrangianSlab, Tet, TetMesh, TetMeshBuilder, TetSettings,
};
pub use render::{PixelIntegral, TetOptions};
pub use volume::{
    TetContext, TetVolume, canonical_point, density_range, density_stride, sampled_densities,
};

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TetError {
    #[error("{count} particles is not N³ for an integer N ≥ 2")]
    NotCubic { count: usize },
    #[error("box size {box_size} must be finite and > 0")]
    BadBox { box_size: f32 },
    #[error("particle {index} has a non-finite coordinate")]
    NonFinite { index: usize },
    #[error("particle mass {mass} must be finite and > 0")]
    BadMass { mass: f64 },
}

#[cfg(test)]
mod tests;
