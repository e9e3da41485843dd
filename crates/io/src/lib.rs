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
//!   output, SWIFT, Gadget-4, AREPO and GIZMO snapshots in one file or
//!   several, with SWIFT's cell metadata for regions, and JaxPM runs
//!   (`read_pysph`, `read_gadget_snapshot`, `read_jaxpm`), layout sniffing and a tree listing of any
//!   HDF5 file (`describe_hdf5`).
//! - [`lammps`]: LAMMPS text dumps ([`read_lammps`], [`lammps_frames`]) with
//!   any column set, scaled or unscaled coordinates, orthogonal or triclinic
//!   boxes; rows sorted by atom id.
//! - [`xyz`]: plain and extended XYZ files ([`read_xyz`], [`xyz_frames`]),
//!   several frames back to back.
//! - [`gadget_bin`]: Gadget binary snapshots, format 1 and 2, either byte
//!   order, one file or several ([`read_gadget_binary`]); [`tipsy`]: Tipsy
//!   files of ChaNGa and Gasoline ([`read_tipsy`]); [`snapshot`]: what the
//!   snapshot readers share (particle types by name, regions read without
//!   reading everything, the unit system a file states, multi-file sets,
//!   [`snapshot_header`] for `voxless info`).
//! - [`fits`]: FITS images with a linear world coordinate system
//!   ([`write_fits_image`]) for projected maps, and a reader of what it
//!   writes.
//! - [`particles_fmt`]: the `.particles` time series of the attribute-aware
//!   RBF renderer ([`read_particles_file`], [`particles_frames`]).
//! - [`vtk`]: VTK XML `.vtp`/`.vtu` files in every encoding VTK writes:
//!   points and point data as particles ([`read_vtk_points`]) and tetrahedral
//!   meshes ([`read_vtu_mesh`]).
//! - [`format`](mod@format): which particle format a file is ([`ParticleFormat`], by
//!   name, then by its first bytes), how many frames it holds, and one frame
//!   of any of them as a table ([`format::read_table`]), with the
//!   [`TableOptions`] that pick a part of an HDF5 file.
//!
//! The particle readers return a [`ParticleTable`]; multi-frame formats read
//! one frame per call and skip the frames before it without parsing them.
//!
//! # Reading from memory
//!
//! Every reader also reads data that is not a file (an upload, a network
//! stream, bytes already in memory), through a variant next to its path
//! function:
//!
//! - `_from` variants take a reader and read it from its position to its
//!   end: [`read_npy_from`], [`read_csv_from`], [`read_lammps_from`],
//!   [`lammps_frames_from`], [`read_xyz_from`], [`xyz_frames_from`],
//!   [`xyz_species_from`], [`read_amrclaw_from`] (plus the `fort.t` text),
//!   [`read_png_rgb8_from`], [`read_exr_gray_from`]. Those that
//!   pre-allocate from a size the data declares ask for `Read + Seek`, and
//!   the reader's length then bounds that size as a file's length does;
//!   those that only stream (frame counts, species lists, CSV, the
//!   `.particles` index) take any `Read`. Wrap a byte slice in a
//!   `std::io::Cursor`.
//! - `_bytes` variants take a byte slice where the parser needs all of it:
//!   VTK XML ([`read_vtk_points_bytes`], [`read_vtu_mesh_bytes`]), whose
//!   appended data is addressed by offset, and ExaBricks
//!   ([`read_exabricks_bytes`]: the cells, each field's name with its
//!   scalars, and the meta JSON).
//! - A `.particles` series names one file per timestep, so
//!   [`read_particles_from`] takes the index text and a closure that opens
//!   a named timestep; [`read_particles_timestep_from`] reads one
//!   timestep's data alone.
//! - Writers have `_to` variants into any writer: [`write_npy_f32_to`],
//!   [`write_png_rgb8_to`], and (seekable, as OpenEXR writes its offset
//!   table last) [`write_exr_rgba_to`], [`write_exr_gray_to`].
//! - [`ParticleFormat::detect_bytes`] detects a format from a name and the
//!   first bytes; [`format::read_table_from`] and [`format::frames_in_from`]
//!   dispatch on a reader.
//!
//! Each variant takes a `name` that only labels its errors: an error reads
//! exactly as the path function's does for a file of that name (e.g.
//! `frame3.cells: size 24 bytes is not a multiple of 16 ...`). The path
//! functions open the file and run the same code, so both give the same
//! results. The HDF5 readers stay path-based: the `hdf5-metno` crate opens
//! files by name and does not offer HDF5's in-memory file images (see the
//! `hdf5` module).
//!
//! # Errors
//!
//! Every function reports failures as an [`IoError`] that names the file and
//! says what is wrong with it. Bad input never panics, and readers check the
//! sizes a header declares against the file's length before allocating, so a
//! corrupt or hostile header cannot make them allocate more memory than the
//! file's contents could fill. The bounds, per byte of input:
//!
//! - binary arrays (`.npy`, Gadget, Tipsy, FITS, ExaBricks, AMReX FABs,
//!   uncompressed HDF5 and VTK): values are held as float32 or float64, at
//!   most 8× the bytes the file holds (one-byte integers widened to
//!   float64; 2× for float32 data), checked against the file's length
//!   before the first allocation;
//! - text (CSV, XYZ, LAMMPS, AMRClaw, legacy VTK): at most 16 bytes held per
//!   byte read (a one-digit value and its separator become a float64), and
//!   each reader is linear in its input (wide headers, many attributes);
//!   AMRClaw's `fort.q` is mapped rather than read (its text stays in the
//!   page cache, not on the heap) and only the fields asked for are parsed
//!   ([`FieldPick`]);
//! - compressed blocks (VTK zlib, HDF5 filters, PNG colormaps): at most
//!   1100× the compressed size (zlib's own limit is 1032×), checked against
//!   the sizes the block declares before inflating;
//! - special files (devices, FIFOs) are refused before they are opened for
//!   reading.

use std::fs::File;
use std::io::{BufRead, BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

pub mod amr;
mod atomic;
pub mod csv;
mod decimal;
pub mod fits;
pub mod format;
pub mod gadget_bin;
#[cfg(feature = "hdf5")]
pub mod hdf5;
pub mod image;
pub mod lammps;
pub mod npy;
pub mod particles_fmt;
pub mod snapshot;
pub mod surface;
pub mod table;
pub mod tipsy;
pub mod vtk;
pub mod xyz;

pub use amr::{
    AmrCellData, AmrFormat, FieldPick, amr_field, amr_format, amrclaw_time, exabricks_scalars,
    read_amr, read_amr_picked, read_amrclaw, read_amrclaw_from, read_amrclaw_picked,
    read_amrclaw_text, read_amrex, read_amrex_files, read_exabricks, read_exabricks_bytes,
    read_exabricks_rows,
};
pub use atomic::write_atomically;
pub use csv::{CsvTable, read_csv, read_csv_from};
pub use fits::{CardValue, FitsImage, LinearWcs, read_fits_image, write_fits_image};
pub use format::{ParticleFormat, TableOptions};
pub use gadget_bin::{
    GadgetBinary, GadgetHeader, gadget_binary_files, open_gadget_binary, read_gadget_binary,
    read_gadget_binary_from, sniff_gadget_binary,
};
#[cfg(feature = "hdf5")]
pub use hdf5::{
    Hdf5Kind, JaxpmSnapshot, describe_hdf5, hdf5_kind, jaxpm_snapshots, pysph_groups, read_gadget,
    read_gadget_share, read_gadget_snapshot, read_jaxpm, read_pysph, read_pysph_share,
};
#[cfg(feature = "hdf5")]
pub use hdf5::{read_athena, read_enzo, read_flash};
pub use image::{
    read_exr_gray, read_exr_gray_from, read_png_rgb8, read_png_rgb8_from, write_exr_gray,
    write_exr_gray_to, write_exr_rgba, write_exr_rgba_to, write_jpeg_rgb8, write_jpeg_rgb8_to,
    write_png_rgb8, write_png_rgb8_to,
};
pub use lammps::{
    lammps_frame_scan, lammps_frames, lammps_frames_from, read_lammps, read_lammps_from,
};
pub use npy::{NpyArray, read_npy, read_npy_from, read_npy_rows, write_npy_f32, write_npy_f32_to};
pub use particles_fmt::{
    particles_frames, particles_frames_from, read_particles_file, read_particles_from,
    read_particles_timestep_from,
};
pub use snapshot::{
    Region, SnapshotHeader, Units, part_type_label, part_type_named, snapshot_header,
};
pub use surface::{SurfaceFormat, SurfaceMesh, read_surface, read_surface_bytes};
pub use table::{ParticleTable, SphCode, SphConvention};
pub use tipsy::{TipsyHeader, read_tipsy, read_tipsy_from, sniff_tipsy, tipsy_header};
pub use vtk::{
    VtkMesh, read_vtk_points, read_vtk_points_bytes, read_vtu_mesh, read_vtu_mesh_bytes,
};
pub use xyz::{
    read_xyz, read_xyz_from, xyz_frames, xyz_frames_from, xyz_species, xyz_species_from,
};

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

/// Bytes from `reader`'s position to its end, for the size checks of the
/// memory variants (the path functions take a file's length from its
/// metadata instead). The position is left where it was.
pub(crate) fn remaining_len<R: Seek>(reader: &mut R, name: &Path) -> Result<u64, IoError> {
    let io = |e| IoError::io(name, e);
    // The end's offset minus the current one; a `Cursor` may sit past its
    // end, which leaves nothing to read.
    let start = reader.stream_position().map_err(io)?;
    let end = reader.seek(SeekFrom::End(0)).map_err(io)?;
    reader.seek(SeekFrom::Start(start)).map_err(io)?;
    Ok(end.saturating_sub(start))
}

/// Opens `path` for reading and returns the file with its length.
pub(crate) fn open_with_len(path: &Path) -> Result<(File, u64), IoError> {
    let file = File::open(path).map_err(|e| IoError::io(path, e))?;
    let len = file.metadata().map_err(|e| IoError::io(path, e))?.len();
    Ok((file, len))
}

/// Reads text line by line, counting lines, for the text formats (LAMMPS
/// dumps, XYZ, `.particles` lists). Lines may end in `\n` or `\r\n`. The
/// text comes from a file or from memory; `path` only names it in errors.
pub(crate) struct LineReader<R> {
    reader: R,
    path: PathBuf,
    buf: Vec<u8>,
    /// Byte range of the trimmed text of the last line read by `read`.
    range: (usize, usize),
    line_no: usize,
    /// Length of the input in bytes, for capping pre-allocations.
    len: u64,
    consumed: u64,
}

impl LineReader<BufReader<File>> {
    /// Opens the file at `path`.
    pub(crate) fn open(path: &Path) -> Result<Self, IoError> {
        let (file, len) = open_with_len(path)?;
        Ok(LineReader::new(BufReader::new(file), path, len))
    }
}

impl<R: Read> LineReader<BufReader<R>> {
    /// Reads `reader` from its position to its end; `name` labels errors.
    /// Its length is unknown and counts as 0, so [`LineReader::remaining_bytes`]
    /// caps pre-allocations at nothing: use it where nothing is allocated up
    /// front.
    pub(crate) fn from_read(reader: R, name: &Path) -> Self {
        LineReader::new(BufReader::new(reader), name, 0)
    }
}

impl<R: Read + Seek> LineReader<BufReader<R>> {
    /// Reads `reader` from its position to its end, whose length then caps
    /// pre-allocations as a file's does; `name` labels errors.
    pub(crate) fn from_seek(mut reader: R, name: &Path) -> Result<Self, IoError> {
        let len = remaining_len(&mut reader, name)?;
        Ok(LineReader::new(BufReader::new(reader), name, len))
    }
}

impl<R: BufRead> LineReader<R> {
    /// Reads `reader`, which holds `len` bytes; `path` labels errors.
    pub(crate) fn new(reader: R, path: &Path, len: u64) -> Self {
        LineReader {
            reader,
            path: path.to_path_buf(),
            buf: Vec::new(),
            range: (0, 0),
            line_no: 0,
            len,
            consumed: 0,
        }
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

    /// Whether nothing is left to read (an I/O error counts as not).
    pub(crate) fn at_end(&mut self) -> bool {
        self.reader.fill_buf().is_ok_and(|b| b.is_empty())
    }

    /// Number of the line returned last (1-based; 0 before the first).
    pub(crate) fn line_no(&self) -> usize {
        self.line_no
    }

    /// Bytes of the file not read yet (for capping pre-allocations).
    pub(crate) fn remaining_bytes(&self) -> u64 {
        self.len.saturating_sub(self.consumed)
    }

    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// A format error for the file, prefixed with the current line number.
    pub(crate) fn error(&self, message: impl std::fmt::Display) -> IoError {
        IoError::format(&self.path, format!("line {}: {message}", self.line_no))
    }
}
