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
//! - `hdf5` (cargo feature `hdf5`, needs the system HDF5 library): PySPH
//!   output, SWIFT/Gadget-4 snapshots and JaxPM runs (`read_pysph`,
//!   `read_gadget`, `read_jaxpm`), layout sniffing and a tree listing of any
//!   HDF5 file (`describe_hdf5`).
//! - [`lammps`]: LAMMPS text dumps ([`read_lammps`], [`lammps_frames`]) with
//!   any column set, scaled or unscaled coordinates, orthogonal or triclinic
//!   boxes; rows sorted by atom id.
//! - [`xyz`]: plain and extended XYZ files ([`read_xyz`], [`xyz_frames`]),
//!   several frames back to back.
//! - [`particles_fmt`]: the `.particles` time series of the attribute-aware
//!   RBF renderer ([`read_particles_file`], [`particles_frames`]).
//! - [`vtk`]: VTK XML `.vtp`/`.vtu` files in every encoding VTK writes:
//!   points and point data as particles ([`read_vtk_points`]) and tetrahedral
//!   meshes ([`read_vtu_mesh`]).
//!
//! The particle readers return a [`ParticleTable`]; multi-frame formats read
//! one frame per call and skip the frames before it without parsing them.
//!
//! Every function reports failures as an [`IoError`] that names the file and
//! says what is wrong with it. Bad input never panics, and readers check the
//! sizes a header declares against the file's length before allocating, so a
//! corrupt or hostile header cannot make them allocate more memory than the
//! file's contents could fill.

use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};

pub mod amr;
pub mod csv;
#[cfg(feature = "hdf5")]
pub mod hdf5;
pub mod image;
pub mod lammps;
pub mod npy;
pub mod particles_fmt;
pub mod table;
pub mod vtk;
pub mod xyz;

pub use amr::{AmrCellData, read_amrclaw, read_exabricks};
pub use csv::{CsvTable, read_csv};
#[cfg(feature = "hdf5")]
pub use hdf5::{
    Hdf5Kind, JaxpmSnapshot, describe_hdf5, hdf5_kind, jaxpm_snapshots, pysph_groups, read_gadget,
    read_jaxpm, read_pysph,
};
pub use image::{read_exr_gray, read_png_rgb8, write_exr_gray, write_exr_rgba, write_png_rgb8};
pub use lammps::{lammps_frames, read_lammps};
pub use npy::{NpyArray, read_npy, write_npy_f32};
pub use particles_fmt::{particles_frames, read_particles_file};
pub use table::ParticleTable;
pub use vtk::{VtkMesh, read_vtk_points, read_vtu_mesh};
pub use xyz::{read_xyz, xyz_frames, xyz_species};

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

/// Reads a text file line by line, counting lines, for the text formats
/// (LAMMPS dumps, XYZ, `.particles` lists). Lines may end in `\n` or `\r\n`.
pub(crate) struct LineReader {
    reader: BufReader<File>,
    path: PathBuf,
    buf: Vec<u8>,
    /// Byte range of the trimmed text of the last line read by `read`.
    range: (usize, usize),
    line_no: usize,
    file_len: u64,
    consumed: u64,
}

impl LineReader {
    pub(crate) fn open(path: &Path) -> Result<LineReader, IoError> {
        let file = File::open(path).map_err(|e| IoError::io(path, e))?;
        let file_len = file.metadata().map_err(|e| IoError::io(path, e))?.len();
        Ok(LineReader {
            reader: BufReader::new(file),
            path: path.to_path_buf(),
            buf: Vec::new(),
            range: (0, 0),
            line_no: 0,
            file_len,
            consumed: 0,
        })
    }

    /// Reads the next line into the buffer; `false` at the end of the file.
    fn fill(&mut self) -> Result<bool, IoError> {
        self.buf.clear();
        self.range = (0, 0);
        let n = self
            .reader
            .read_until(b'\n', &mut self.buf)
            .map_err(|e| IoError::io(&self.path, e))?;
        if n == 0 {
            return Ok(false);
        }
        self.line_no += 1;
        self.consumed += n as u64;
        Ok(true)
    }

    /// Reads the next line; `false` at the end of the file. The line is then
    /// available from [`LineReader::line`]. Text that is not UTF-8 is an
    /// error.
    pub(crate) fn read(&mut self) -> Result<bool, IoError> {
        if !self.fill()? {
            self.range = (0, 0);
            return Ok(false);
        }
        let text = std::str::from_utf8(&self.buf).map_err(|e| {
            IoError::format(
                &self.path,
                format!(
                    "line {}: not valid UTF-8 text (bad byte at column {}); is this a binary \
                     file?",
                    self.line_no,
                    e.valid_up_to() + 1
                ),
            )
        })?;
        let mut start = 0;
        if self.line_no == 1 && text.starts_with('\u{feff}') {
            start = '\u{feff}'.len_utf8();
        }
        let trimmed = text[start..].trim();
        start = text.len() - text[start..].trim_start().len();
        self.range = (start, start + trimmed.len());
        Ok(true)
    }

    /// The line read last, without its line ending, trimmed of surrounding
    /// whitespace (and of a UTF-8 byte order mark on line 1).
    pub(crate) fn line(&self) -> &str {
        std::str::from_utf8(&self.buf[self.range.0..self.range.1]).unwrap_or("")
    }

    /// [`LineReader::read`] then [`LineReader::line`]; `None` at the end.
    pub(crate) fn next_line(&mut self) -> Result<Option<&str>, IoError> {
        Ok(if self.read()? {
            Some(self.line())
        } else {
            None
        })
    }

    /// Skips the next line without decoding it. Returns `None` at the end of
    /// the file, otherwise whether the line starts with `prefix`.
    pub(crate) fn skip_line(&mut self, prefix: &[u8]) -> Result<Option<bool>, IoError> {
        if !self.fill()? {
            return Ok(None);
        }
        let start = self.buf.iter().position(|b| !b.is_ascii_whitespace());
        let rest = start.map_or(&[][..], |s| &self.buf[s..]);
        Ok(Some(rest.starts_with(prefix)))
    }

    /// Number of the line returned last (1-based; 0 before the first).
    pub(crate) fn line_no(&self) -> usize {
        self.line_no
    }

    /// Bytes of the file not read yet (for capping pre-allocations).
    pub(crate) fn remaining_bytes(&self) -> u64 {
        self.file_len.saturating_sub(self.consumed)
    }

    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// A format error for the file, prefixed with the current line number.
    pub(crate) fn error(&self, message: impl std::fmt::Display) -> IoError {
        IoError::format(&self.path, format!("line {}: {message}", self.line_no))
    }
}
