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
//! **Invariants.** Every basis sample inside a region lies within the region's
//! value range (a convex combination of the values of the cells reaching into
//! it); regions do not overlap; every point where some tent is non-zero lies
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
mod tests;
#[cfg(test)]
mod walk_tests;
