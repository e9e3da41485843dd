//! Readers and writers for the file formats voxless consumes and produces.
//!
//! - [`npy`]: NumPy `.npy` arrays. [`read_npy`] reads any numeric array
//!   (floats, integers, booleans; either byte order; C or Fortran order) and
//!   converts it to `f64` in C order. [`write_npy_f32`] writes `float32`
//!   arrays byte for byte the way NumPy does.
//! - [`csv`]: numeric tables with a header line ([`read_csv`]), separated by
//!   commas, tabs or spaces, with `#` comments.
//! - [`image`]: 8-bit sRGB PNG and linear `f32` OpenEXR images, plus small
//!   readers used for round-trip tests.
//! - [`amr`]: block-structured AMR output as leaf cells ([`AmrCellData`]):
//!   ExaBricks `.cells`/`.scalars` files ([`read_exabricks`]) and AMRClaw's
//!   ASCII `fort.q`/`fort.t` output ([`read_amrclaw`]), whose coarse cells
//!   under finer grids are dropped.
//!
//! Every function reports failures as an [`IoError`] that names the file and
//! says what is wrong with it. Bad input never panics, and readers check the
//! sizes a header declares against the file's length before allocating, so a
//! corrupt or hostile header cannot make them allocate more memory than the
//! file's contents could fill.

use std::path::{Path, PathBuf};

pub mod amr;
pub mod csv;
pub mod image;
pub mod npy;
pub mod table;

pub use amr::{AmrCellData, read_amrclaw, read_exabricks};
pub use csv::{CsvTable, read_csv};
pub use image::{read_exr_gray, read_png_rgb8, write_exr_gray, write_exr_rgba, write_png_rgb8};
pub use npy::{NpyArray, read_npy, write_npy_f32};
pub use table::ParticleTable;

/// An error while reading or writing a file. Both variants name the file.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// The operating system failed to open, read or write the file.
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The file was read but its content is malformed or unsupported, or the
    /// data handed to a writer is inconsistent.
    #[error("{path}: {message}")]
    Format { path: PathBuf, message: String },
}

impl IoError {
    /// A [`IoError::Format`] error for `path` with the given explanation.
    pub fn format(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        IoError::Format {
            path: path.into(),
            message: message.into(),
        }
    }

    /// A [`IoError::Io`] error for `path`.
    pub(crate) fn io(path: &Path, source: std::io::Error) -> Self {
        IoError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// Number of elements of an array with this shape; `None` on overflow.
pub(crate) fn checked_product(dims: &[usize]) -> Option<usize> {
    dims.iter().try_fold(1usize, |acc, &d| acc.checked_mul(d))
}
