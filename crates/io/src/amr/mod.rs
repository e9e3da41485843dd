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
//! - [`read_amrex`] reads an AMReX/BoxLib plotfile directory (Castro, Nyx,
//!   WarpX, MAESTROeX, PeleC); behind the `hdf5` feature, `read_flash`,
//!   `read_enzo` and `read_athena` read FLASH, Enzo and Athena++ output.
//!   Each drops the coarse cells finer levels cover.
//! - [`read_amr`] takes any of these paths and tells the format from the
//!   path itself ([`amr_format`]): one flag for every AMR code.
//!
//! Both ExaBricks and AMRClaw also read from memory: [`read_exabricks_bytes`] takes the cells,
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
mod amrex;
mod exabricks;

pub use amrclaw::{
    amrclaw_time, read_amrclaw, read_amrclaw_from, read_amrclaw_picked, read_amrclaw_text,
};
pub use amrex::{read_amrex, read_amrex_files};
pub use exabricks::{read_exabricks, read_exabricks_bytes, read_exabricks_rows};

use crate::IoError;
use std::path::Path;

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

/// Which fields a reader decodes. Text formats pay for every number they
/// parse (an AMRClaw frame spends most of its read on them), so a caller
/// that integrates one field asks for it alone; binary formats read every
/// field either way.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum FieldPick {
    /// Every field (what listings, samples and the viewer need).
    #[default]
    All,
    /// The fields [`amr_field`] finds for these names, and the first field
    /// when `first` (the default opacity field). When a name is not found,
    /// every field is read, so the error that follows lists them all.
    Named { names: Vec<String>, first: bool },
}

impl FieldPick {
    /// The columns of `names` to read, ascending; `None` for all of them.
    pub fn columns(&self, names: &[&str]) -> Option<Vec<usize>> {
        let FieldPick::Named {
            names: wanted,
            first,
        } = self
        else {
            return None;
        };
        let mut cols = wanted
            .iter()
            .map(|w| amr_field(names, w))
            .collect::<Option<Vec<usize>>>()?;
        if *first {
            cols.push(0);
        }
        cols.sort_unstable();
        cols.dedup();
        (!cols.is_empty() && cols.len() < names.len()).then_some(cols)
    }
}

/// Names the codes give the same quantity: a field asked for by one of
/// them is found under any other when the file has no exact match.
const FIELD_ALIASES: &[&[&str]] = &[
    &["density", "dens", "rho"],
    &["pressure", "pres", "press"],
    &["temperature", "temp"],
    &["energy", "eden", "etot", "totalenergy", "total_energy"],
];

/// The index of field `name` among `names`: the exact name, else the one
/// name equal ignoring case, else the one name the codes use for the same
/// quantity (`density` finds FLASH's `dens`, Athena++'s `rho`, Enzo's
/// `Density`). `None` when there is none or the match is ambiguous.
pub fn amr_field(names: &[&str], name: &str) -> Option<usize> {
    if let Some(i) = names.iter().position(|n| *n == name) {
        return Some(i);
    }
    let unique = |hits: Vec<usize>| (hits.len() == 1).then(|| hits[0]);
    let folded: Vec<usize> = (0..names.len())
        .filter(|&i| names[i].eq_ignore_ascii_case(name))
        .collect();
    if !folded.is_empty() {
        return unique(folded);
    }
    let group = FIELD_ALIASES
        .iter()
        .find(|g| g.iter().any(|a| a.eq_ignore_ascii_case(name)))?;
    unique(
        (0..names.len())
            .filter(|&i| group.iter().any(|a| a.eq_ignore_ascii_case(names[i])))
            .collect(),
    )
}

/// The AMR formats [`read_amr`] tells apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AmrFormat {
    /// AMRClaw ASCII `fort.qNNNN` (with `fort.tNNNN`).
    AmrClaw,
    /// ExaBricks `.cells` with `<stem>.<field>.scalars` beside it.
    ExaBricks,
    /// An AMReX/BoxLib plotfile directory (holding `Header`).
    Amrex,
    /// FLASH HDF5 plot or checkpoint file.
    Flash,
    /// Enzo parameter file with `<file>.hierarchy` beside it.
    Enzo,
    /// Athena++ `.athdf`.
    Athena,
}

impl AmrFormat {
    /// The format's name, as users know it.
    pub fn name(self) -> &'static str {
        match self {
            AmrFormat::AmrClaw => "AMRClaw",
            AmrFormat::ExaBricks => "ExaBricks",
            AmrFormat::Amrex => "AMReX plotfile",
            AmrFormat::Flash => "FLASH",
            AmrFormat::Enzo => "Enzo",
            AmrFormat::Athena => "Athena++",
        }
    }

    /// Whether reading it needs the `hdf5` feature.
    pub fn needs_hdf5(self) -> bool {
        matches!(self, AmrFormat::Flash | AmrFormat::Enzo | AmrFormat::Athena)
    }
}

/// The 8-byte signature at the start of an HDF5 file.
const HDF5_SIGNATURE: &[u8; 8] = b"\x89HDF\r\n\x1a\n";

/// Which AMR format `path` holds, from its name, its neighbours and its
/// first bytes: a directory with a `Header` is an AMReX plotfile, a
/// `fort.q*` file AMRClaw output, a `.cells` file ExaBricks cells, a file
/// with `<file>.hierarchy` beside it (or the `.hierarchy` itself) an Enzo
/// output, a `.athdf` file Athena++, any other HDF5 file FLASH.
pub fn amr_format(path: &Path) -> Result<AmrFormat, IoError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    if path.is_dir() {
        if path.join("Header").is_file() {
            return Ok(AmrFormat::Amrex);
        }
        return Err(IoError::format(
            path,
            "is a directory but not an AMReX plotfile (it has no `Header`); give the plotfile \
             directory, or the AMR file itself",
        ));
    }
    if name.starts_with("fort.q") {
        return Ok(AmrFormat::AmrClaw);
    }
    if name.ends_with(".cells") {
        return Ok(AmrFormat::ExaBricks);
    }
    if name.ends_with(".hierarchy") || enzo_hierarchy(path).is_file() {
        return Ok(AmrFormat::Enzo);
    }
    if name.ends_with(".athdf") {
        return Ok(AmrFormat::Athena);
    }
    let mut head = [0u8; 8];
    let file = std::fs::File::open(path).map_err(|e| IoError::io(path, e))?;
    let n = std::io::Read::read(&mut std::io::Read::take(file, 8), &mut head)
        .map_err(|e| IoError::io(path, e))?;
    if n == 8 && &head == HDF5_SIGNATURE {
        #[cfg(feature = "hdf5")]
        {
            use crate::hdf5::{Hdf5Kind, hdf5_kind};
            return match hdf5_kind(path)? {
                Hdf5Kind::Athena => Ok(AmrFormat::Athena),
                Hdf5Kind::Flash => Ok(AmrFormat::Flash),
                _ => Err(IoError::format(
                    path,
                    "is an HDF5 file but not AMR output voxless reads (FLASH has `unknown \
                     names` and `refine level` datasets, Athena++ `RootGridSize` and \
                     `MeshBlockSize` attributes)",
                )),
            };
        }
        #[cfg(not(feature = "hdf5"))]
        return Ok(AmrFormat::Flash);
    }
    Err(IoError::format(
        path,
        "is not an AMR format voxless reads: expected an AMReX plotfile directory, a FLASH HDF5 \
         file, an Enzo parameter file (with .hierarchy beside it), an Athena++ .athdf, AMRClaw \
         fort.qNNNN or ExaBricks .cells",
    ))
}

/// The hierarchy file of the Enzo output whose parameter file is `path`.
fn enzo_hierarchy(path: &Path) -> std::path::PathBuf {
    let mut h = path.as_os_str().to_owned();
    h.push(".hierarchy");
    h.into()
}

/// Reads the AMR output at `path` in whichever format it is
/// ([`amr_format`]): leaf cells with every field the file holds.
pub fn read_amr(path: &Path) -> Result<(AmrCellData, AmrFormat), IoError> {
    read_amr_picked(path, &FieldPick::All)
}

/// [`read_amr`] decoding only the fields `pick` names where the format
/// allows (AMRClaw's text; see [`FieldPick`]).
pub fn read_amr_picked(path: &Path, pick: &FieldPick) -> Result<(AmrCellData, AmrFormat), IoError> {
    let format = amr_format(path)?;
    let data = match format {
        AmrFormat::AmrClaw => read_amrclaw_picked(path, pick)?,
        AmrFormat::Amrex => read_amrex(path)?,
        AmrFormat::ExaBricks => {
            let scalars = exabricks_scalars(path)?;
            if scalars.is_empty() {
                let stem = path.file_stem().unwrap_or_default().to_string_lossy();
                return Err(IoError::format(
                    path,
                    format!(
                        "has no {stem}.<field>.scalars beside it: give --cells with --scalars FILE"
                    ),
                ));
            }
            read_exabricks(path, &scalars)?
        }
        AmrFormat::Flash | AmrFormat::Enzo | AmrFormat::Athena => read_hdf5_amr(path, format)?,
    };
    Ok((data, format))
}

#[cfg(feature = "hdf5")]
fn read_hdf5_amr(path: &Path, format: AmrFormat) -> Result<AmrCellData, IoError> {
    match format {
        AmrFormat::Flash => crate::hdf5::read_flash(path),
        AmrFormat::Athena => crate::hdf5::read_athena(path),
        _ => {
            let param = match path.to_string_lossy().strip_suffix(".hierarchy") {
                Some(p) => std::path::PathBuf::from(p),
                None => path.to_path_buf(),
            };
            crate::hdf5::read_enzo(&param)
        }
    }
}

#[cfg(not(feature = "hdf5"))]
fn read_hdf5_amr(path: &Path, format: AmrFormat) -> Result<AmrCellData, IoError> {
    Err(IoError::format(
        path,
        format!(
            "is {} output, stored in HDF5: this voxless was built without HDF5 support (build \
             with `--features hdf5`, which needs the system HDF5 library, Debian: libhdf5-dev)",
            format.name()
        ),
    ))
}

/// The `.scalars` files beside ExaBricks cells `<stem>.cells`: every
/// `<stem>.<field>.scalars`, sorted by name (none is not an error here).
pub fn exabricks_scalars(cells: &Path) -> Result<Vec<std::path::PathBuf>, IoError> {
    let dir = cells
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let stem = cells
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let prefix = format!("{stem}.");
    let mut found: Vec<_> = std::fs::read_dir(dir)
        .map_err(|e| IoError::io(dir, e))?
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| {
            p.file_name().is_some_and(|n| {
                let n = n.to_string_lossy();
                n.starts_with(&prefix) && n.ends_with(".scalars")
            })
        })
        .collect();
    found.sort();
    Ok(found)
}
