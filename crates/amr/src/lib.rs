//! Block-structured AMR volumes, rendered from the cells themselves
//! (ExaBricks: Wald, Zellmann, Usher et al.).
//!
//! **Model.** Input is a list of leaf cells `(x, y, z, level)`: lower corner
//! in finest-cell units, width `2^level` (level 0 finest), one value per field
//! per cell, plus the world position of unit 0 (`origin`) and the world width
//! of a finest cell (`cell_size`). Cells must be aligned to their level and
//! must not overlap; holes and level jumps larger than one are allowed.
//!
//! **Structure.** Cells are regrouped into [`bricks::Brick`]s (same-level,
//! fully filled, ≤ 32 cells per axis, from a k-d tree), then the space covered
//! by the bricks' supports is cut into [`regions::Region`]s, each knowing the
//! bricks active inside it, the value range of every field there, and its
//! finest cell width. The k-d tree the regions were cut by hands out ray
//! intervals, walked front to back so a ray that turns opaque stops the
//! walk; a render's prepared [`AmrContext`] masks the subtrees holding no
//! region its transfer function can see (the volume itself is never
//! changed, so several transfer functions can render it at once). A BVH
//! over the regions serves point location.
//!
//! **Reconstruction.** *Basis* (default): every cell carries a tent
//! `Ĥ(p) = Π_axes max(0, 1 − |c − p|/w)` around its centre `c`, and
//! `B(p) = Σ Ĥ v / Σ Ĥ` over the cells of the region's bricks only — no cell
//! location. It is continuous across level boundaries and exact for constant
//! fields. Its gradient is analytic (quotient rule on the tents). *Nearest*:
//! the value of the cell containing `p`.
//!
//! *Octant* (Wang et al., TVCG 2019; Open VKL's AMR method `octant`): the
//! cell `C` containing `p` is cut at its centre into eight octants, and the
//! field is trilinear in the octant holding `p`, between its eight
//! vertices (`C`'s centre, three face centres, three edge midpoints, a
//! corner). A vertex takes the mean of the same-level cells around it (the
//! dual-grid value), or, when a coarser cell touches it, that cell's own
//! octant field there; finer cells and holes drop out of the mean.
//! *Continuity*: the finer side always takes the coarser side's values, so
//! the field is C⁰ everywhere — across any level jump and around holes, no
//! T-junction cracks — and it interpolates the cell values at the centres;
//! on one level it is the dual-grid trilinear field (the basis's too), exact
//! for linear fields. It is not C¹: a coarse cell's vertices next to finer
//! cells repeat its own side's values, so the field bends at level
//! boundaries, and shaded iso-surfaces crossing one show a crease there
//! (on the AMRClaw frame sharper than the basis's softer bend; removing it
//! is what the later GTI interpolation of Wang et al. 2020 is for). The
//! gradient is the analytic derivative of the trilinear form (discontinuous
//! across box faces). *Cost*: a sample finds its cell, then the seven
//! blocks around its box's far corner — by index inside the cell's brick,
//! else among the bricks beside it — and recurses into coarser cells at
//! level boundaries; there is no packet or lane form, so a volume render
//! of that frame takes about four times the basis's (twice, both point by
//! point). Line integrals are exact (a cubic per box piece, two Gauss
//! nodes). A cell's octant weight vanishes outside its tent's support, so
//! the regions, their value ranges and a decomposition's ghost cells serve
//! it unchanged.
//!
//! **Invariants.** Every basis or octant sample inside a region lies within
//! the region's value range (a convex combination of the values of the
//! cells reaching into it);
//! regions do not overlap; every point where some tent is non-zero lies
//! in exactly one region (up to shared faces).

pub mod bricks;
mod context;
mod integral;
mod project;
pub mod regions;
mod volume;
mod walk;

pub use bricks::Brick;
pub use context::AmrContext;
pub use regions::{Region, Regions};
pub use volume::{AmrCells, AmrSettings, AmrVolume, BuildStats, CellLocator, Reconstruction};

/// Why cells cannot be used. Cell indices are positions in the input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AmrError {
    #[error("no cells")]
    Empty,
    #[error("cell {cell} has level {level}; levels must be in 0..=20 (0 = finest)")]
    BadLevel { cell: usize, level: i32 },
    #[error(
        "cell {cell} at {pos:?} is not aligned to its level {level}: coordinates must be multiples of 2^{level}"
    )]
    Misaligned {
        cell: usize,
        pos: [i32; 3],
        level: i32,
    },
    #[error("cells {a} and {b} overlap")]
    Overlap { a: usize, b: usize },
    #[error("the cells span {extent} finest cells along an axis; at most 2^21 are supported")]
    TooLarge { extent: i64 },
    #[error("field '{name}' has {got} values but there are {expected} cells")]
    FieldLength {
        name: String,
        expected: usize,
        got: usize,
    },
    #[error("field '{name}' has a non-finite value {value} at cell {cell}")]
    NonFinite {
        name: String,
        cell: usize,
        value: f32,
    },
    #[error("no field '{name}' (fields: {available})")]
    UnknownField { name: String, available: String },
    #[error("no fields: at least one scalar field is needed")]
    NoFields,
    #[error("{what} {value} must be finite{extra}")]
    BadGeometry {
        what: &'static str,
        value: f32,
        extra: &'static str,
    },
}

#[cfg(test)]
mod iso_tests;
#[cfg(test)]
mod octant_tests;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod walk_tests;
