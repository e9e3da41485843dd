//! Readers for block-structured AMR output, converted to leaf cells.
//!
//! Every reader returns an [`AmrCellData`]: a flat list of cells in the
//! ExaBricks convention plus one `f32` value per cell and field. A cell is
//! `(x, y, z, level)`: its lower corner in integer units of the finest cell
//! width, and its level, where level 0 is the finest and a level-`l` cell is
//! `2^l` units wide. World coordinates are `origin + finest_cell_size · (x, y,
//! z)`. The readers do not check that cells are aligned or disjoint; the AMR
//! crate validates that when it builds its bricks.
//!
//! - [`read_exabricks`] reads an ExaBricks `.cells` file (little-endian
//!   `int32` x, y, z, level per cell, 16 bytes, no header) and any number of
//!   `.scalars` files (little-endian `float32`, one per cell in the same
//!   order). Origin and finest cell size come from an optional sibling
//!   `<stem>.meta.json`.
//! - [`read_amrclaw`] reads AMRClaw's native ASCII output (`fort.qNNNN` plus
//!   `fort.tNNNN`). AMRClaw writes every grid in full, including coarse cells
//!   that finer grids cover; the reader drops those, so the result holds only
//!   leaf cells. Its fields are named `q0`, `q1`, … in the order of AMRClaw's
//!   `meqn` solution components.
//!
//! Both also read from memory: [`read_exabricks_bytes`] takes the cells,
//! the scalars and the meta JSON as byte slices, and [`read_amrclaw_from`]
//! the `fort.q` text from a reader and the `fort.t` text as bytes. The path
//! functions find the sibling files, open them and share the same code, so
//! both kinds give the same data and the same errors.
//!
//! All readers check sizes against the input's length before allocating,
//! and report truncated or malformed input as
//! [`IoError::Format`](crate::IoError::Format) naming the file (and, for
//! text, the line).

mod amrclaw;
mod exabricks;

pub use amrclaw::{read_amrclaw, read_amrclaw_from};
pub use exabricks::{read_exabricks, read_exabricks_bytes, read_exabricks_rows};

/// AMR leaf cells in ExaBricks convention.
#[derive(Clone, Debug, PartialEq)]
pub struct AmrCellData {
    /// (x, y, z, level) per cell: lower corner in finest-cell integer units,
    /// level 0 = finest, cell width 2^level units.
    pub cells: Vec<[i32; 4]>,
    /// Field name and one value per cell, in cell order.
    pub fields: Vec<(String, Vec<f32>)>,
    /// World position of integer coordinate (0,0,0).
    pub origin: [f64; 3],
    /// World width of one finest cell (one integer unit).
    pub finest_cell_size: f64,
    /// Simulation time, when the format records it.
    pub time: Option<f64>,
}

impl AmrCellData {
    /// The values of the field called `name`, if there is one.
    pub fn field(&self, name: &str) -> Option<&[f32]> {
        self.fields
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }
}

/// The largest cell level accepted (cells `2^30` finest units wide).
pub const MAX_LEVEL: i32 = 30;
