//! HDF5 particle snapshots (behind the cargo feature `hdf5`, which links the
//! system HDF5 library through the `hdf5-metno` crate).
//!
//! Three layouts are read into a [`ParticleTable`](crate::ParticleTable) or a
//! [`JaxpmSnapshot`]:
//!
//! - PySPH output ([`pysph_groups`], [`read_pysph`]): one group per particle
//!   array under `particles/`, each property a 1-D dataset in
//!   `particles/<group>/arrays/`; the time is the `t` attribute of the
//!   `solver_data` group.
//! - SWIFT and Gadget-4 snapshots ([`read_gadget`]): `PartType<N>/Coordinates`
//!   (N×3) and friends, with the box size, time and mass table as attributes
//!   of `Header`.
//! - JaxPM particle-mesh runs ([`read_jaxpm`]): `snap_<K>/x` positions
//!   reordered into Lagrangian grid order with `q_index`.
//!
//! And three block-structured AMR layouts into an
//! [`AmrCellData`](crate::AmrCellData) of leaf cells ([`read_flash`],
//! [`read_enzo`], [`read_athena`]), sharing the block checks of
//! `amr_blocks`.
//!
//! [`hdf5_kind`] tells the layouts apart from the groups present, and
//! [`describe_hdf5`] prints any HDF5 file as a tree (for `voxless info`).
//!
//! Every error names the file and, where one is involved, the dataset or
//! attribute. Bad input never panics: the file must carry the HDF5 signature
//! before the library opens it, and a dataset is only read when the bytes its
//! shape declares fit in the file (or in 1100 times the file for a compressed
//! dataset, deflate's ratio limit being about 1032), so a corrupt header
//! cannot make a reader allocate memory the file's contents could not fill.
//! Datasets whose data live outside the file (external or virtual storage)
//! are therefore limited by the file's own length too.
//!
//! **Paths only.** Unlike the other readers of this crate, these have no
//! variant reading from memory. The HDF5 library parses the file and
//! `hdf5-metno` (0.15) opens files by name only: its file access properties
//! leave out HDF5's file image API (`H5Pset_file_image`, which would let the
//! library read a buffer), and exposing it would mean unsafe calls into the
//! raw `hdf5-metno-sys` bindings behind the safe wrapper's back. Data held
//! in memory has to be written to a file first.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use hdf5_metno as h5;
use hdf5_metno::types::{FloatSize, TypeDescriptor};

use crate::{IoError, checked_product};

mod amr_blocks;
mod athena;
mod describe;
mod enzo;
mod flash;
mod gadget;
mod jaxpm;
mod pysph;

pub use athena::read_athena;
pub use describe::describe_hdf5;
pub use enzo::read_enzo;
pub use flash::read_flash;
pub use gadget::{
    GadgetHdf5, open_gadget_hdf5, read_gadget, read_gadget_share, read_gadget_snapshot,
};
pub use jaxpm::{JaxpmSnapshot, jaxpm_snapshots, read_jaxpm};
pub use pysph::{pysph_groups, read_pysph, read_pysph_share};

/// The 8-byte signature at the start of an HDF5 superblock.
const SIGNATURE: &[u8; 8] = b"\x89HDF\r\n\x1a\n";

/// How much larger than the file a compressed dataset may be.
const MAX_COMPRESSION_RATIO: u128 = 1100;

/// Which simulation code's layout an HDF5 file follows, judged by its
/// top-level groups.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hdf5Kind {
    /// PySPH output: a `particles` group whose subgroups hold `arrays`.
    PySph,
    /// SWIFT or Gadget-4 snapshot: top-level `PartType<N>` groups.
    Gadget,
    /// JaxPM run: a `q_index` dataset and `snap_<K>` groups.
    Jaxpm,
    /// FLASH AMR output: an `unknown names` dataset beside `refine level`.
    Flash,
    /// Athena++ AMR output (`.athdf`): `RootGridSize` and `MeshBlockSize`
    /// attributes on the root.
    Athena,
    /// Any other HDF5 file.
    Other,
}

/// Decides which layout the HDF5 file at `path` follows: a `particles`
/// group with an `arrays` subgroup in some child means PySPH, a top-level
/// `PartType<N>` group means SWIFT/Gadget, a `q_index` dataset next to
/// `snap_<K>` groups means JaxPM; `unknown names` with `refine level`
/// means FLASH, `RootGridSize` with `MeshBlockSize` attributes Athena++.
pub fn hdf5_kind(path: &Path) -> Result<Hdf5Kind, IoError> {
    // A snapshot of several files: its first file says.
    let first = crate::snapshot::first_file(path);
    let f = Hdf5File::open(&first)?;
    let root = f.root();
    let names = f.member_names(root, "/")?;
    if let Some(particles) = f.child_group(root, "particles") {
        for name in f.member_names(&particles, "particles")? {
            if let Some(g) = f.child_group(&particles, &name)
                && f.child_group(&g, "arrays").is_some()
            {
                return Ok(Hdf5Kind::PySph);
            }
        }
    }
    let counted = f.child_group(root, "Header").is_some_and(|h| {
        h.attr_names()
            .is_ok_and(|n| n.iter().any(|a| a == "NumPart_Total"))
    });
    if counted
        || names
            .iter()
            .any(|n| numbered(n, "PartType").is_some() && f.child_group(root, n).is_some())
    {
        return Ok(Hdf5Kind::Gadget);
    }
    let has_snap = names
        .iter()
        .any(|n| numbered(n, "snap_").is_some() && f.child_group(root, n).is_some());
    if has_snap && f.child_dataset(root, "q_index").is_some() {
        return Ok(Hdf5Kind::Jaxpm);
    }
    if f.child_dataset(root, "unknown names").is_some()
        && f.child_dataset(root, "refine level").is_some()
    {
        return Ok(Hdf5Kind::Flash);
    }
    let attrs = root.attr_names().unwrap_or_default();
    if ["RootGridSize", "MeshBlockSize"]
        .iter()
        .all(|a| attrs.iter().any(|n| n == a))
    {
        return Ok(Hdf5Kind::Athena);
    }
    Ok(Hdf5Kind::Other)
}

/// `Some(k)` when `name` is `prefix` followed by a decimal number `k`.
pub(crate) fn numbered(name: &str, prefix: &str) -> Option<u64> {
    let digits = name.strip_prefix(prefix)?;
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok()
}

/// A list of names for error messages, or "none".
pub(crate) fn name_list(names: &[String]) -> String {
    if names.is_empty() {
        "none".to_string()
    } else {
        names.join(", ")
    }
}

/// Rows `n·r/k .. n·(r+1)/k` of `n`: share `r` of `k`.
pub(crate) fn share_rows(n: usize, r: usize, k: usize) -> std::ops::Range<usize> {
    let k = k.max(1) as u128;
    let at = |r: usize| ((n as u128 * r as u128) / k) as usize;
    at(r.min(k as usize))..at((r + 1).min(k as usize))
}

/// A shape as `(a, b, c)`; `()` for a scalar.
pub(crate) fn shape_text(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => {
            let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
            format!("({})", dims.join(", "))
        }
    }
}

/// The dtype of a dataset or attribute in NumPy's words ("float64",
/// "string (len 8)").
pub(crate) fn type_name(container: &h5::Container) -> String {
    match container.dtype().and_then(|t| t.to_descriptor()) {
        Ok(desc) => desc.to_string(),
        Err(_) => "an unsupported type".to_string(),
    }
}

/// Whether a dtype is an integer or floating-point number.
pub(crate) fn is_numeric(container: &h5::Container) -> bool {
    matches!(
        container.dtype().and_then(|t| t.to_descriptor()),
        Ok(TypeDescriptor::Integer(_) | TypeDescriptor::Unsigned(_) | TypeDescriptor::Float(_))
    )
}

/// A numeric dataset read into memory, converted to `f32`.
pub(crate) struct Values {
    pub(crate) shape: Vec<usize>,
    pub(crate) data: Vec<f32>,
}

/// An open HDF5 file, with the path and length that error messages and
/// size checks need.
pub(crate) struct Hdf5File<'p> {
    pub(crate) path: &'p Path,
    pub(crate) file: h5::File,
    /// File length in bytes.
    pub(crate) len: u64,
}

impl<'p> Hdf5File<'p> {
    /// Opens `path` read-only after checking it exists, is a regular file
    /// and carries the HDF5 signature (at offset 0 or at a user-block offset
    /// 512, 1024, 2048, …).
    pub(crate) fn open(path: &'p Path) -> Result<Self, IoError> {
        let mut raw = File::open(path).map_err(|e| IoError::io(path, e))?;
        let meta = raw.metadata().map_err(|e| IoError::io(path, e))?;
        if !meta.is_file() {
            return Err(IoError::format(path, "not a regular file"));
        }
        let len = meta.len();
        if !has_signature(&mut raw, len).map_err(|e| IoError::io(path, e))? {
            return Err(IoError::format(
                path,
                format!(
                    "not an HDF5 file: the HDF5 signature \\x89HDF\\r\\n\\x1a\\n is not at offset 0 \
                     or at any user-block offset ({len} bytes)"
                ),
            ));
        }
        drop(raw);
        let file = h5::File::open(path).map_err(|e| {
            IoError::format(
                path,
                format!("cannot open the HDF5 file (damaged or truncated?): {e}"),
            )
        })?;
        Ok(Hdf5File { path, file, len })
    }

    /// A [`IoError::Format`] for this file.
    pub(crate) fn err(&self, message: impl Into<String>) -> IoError {
        IoError::format(self.path, message)
    }

    /// Wraps an HDF5 library error: "`what`: `error`".
    pub(crate) fn h5err(&self, what: &str, e: h5::Error) -> IoError {
        self.err(format!("{what}: {e}"))
    }

    /// The root group `/`.
    pub(crate) fn root(&self) -> &h5::Group {
        &self.file
    }

    /// The names of the links in `group` (called `gname` in messages), sorted.
    pub(crate) fn member_names(
        &self,
        group: &h5::Group,
        gname: &str,
    ) -> Result<Vec<String>, IoError> {
        group
            .member_names_by(h5::IndexType::Name, h5::IterationOrder::Increasing)
            .map_err(|e| self.h5err(&format!("group {gname}"), e))
    }

    /// The child group `name` of `parent` (one path component), if there is
    /// one and it is a group.
    pub(crate) fn child_group(&self, parent: &h5::Group, name: &str) -> Option<h5::Group> {
        if name.contains('/') || !parent.link_exists(name) {
            return None;
        }
        match parent.loc_type_by_name(name) {
            Ok(h5::LocationType::Group) => parent.group(name).ok(),
            _ => None,
        }
    }

    /// The child dataset `name` of `parent` (one path component), if there is
    /// one and it is a dataset.
    pub(crate) fn child_dataset(&self, parent: &h5::Group, name: &str) -> Option<h5::Dataset> {
        if name.contains('/') || !parent.link_exists(name) {
            return None;
        }
        match parent.loc_type_by_name(name) {
            Ok(h5::LocationType::Dataset) => parent.dataset(name).ok(),
            _ => None,
        }
    }

    /// The names of the subgroups of `group` whose names satisfy `keep`.
    pub(crate) fn subgroup_names(
        &self,
        group: &h5::Group,
        gname: &str,
        keep: impl Fn(&str) -> bool,
    ) -> Result<Vec<String>, IoError> {
        Ok(self
            .member_names(group, gname)?
            .into_iter()
            .filter(|n| keep(n) && self.child_group(group, n).is_some())
            .collect())
    }

    /// The dataset `name` of `parent`, which must exist; `full` is its path
    /// for messages.
    pub(crate) fn required_dataset(
        &self,
        parent: &h5::Group,
        name: &str,
        full: &str,
    ) -> Result<h5::Dataset, IoError> {
        self.child_dataset(parent, name)
            .ok_or_else(|| self.err(format!("dataset {full} is missing")))
    }

    /// Checks that the data `shape` declares for `container` (called `what`)
    /// fits in the file, and returns its element count.
    fn checked_count(
        &self,
        container: &h5::Container,
        shape: &[usize],
        compressed: bool,
        what: &str,
    ) -> Result<usize, IoError> {
        let too_large = || self.err(format!("{what}: shape {} is too large", shape_text(shape)));
        let count = checked_product(shape).ok_or_else(too_large)?;
        let elem = container.dtype().map(|t| t.size()).unwrap_or(1).max(1);
        let bytes = count as u128 * elem as u128;
        let limit = if compressed {
            u128::from(self.len) * MAX_COMPRESSION_RATIO
        } else {
            u128::from(self.len)
        };
        if bytes > limit {
            return Err(self.err(format!(
                "{what}: shape {} declares {bytes} bytes of data, more than the {}-byte file can hold",
                shape_text(shape),
                self.len
            )));
        }
        Ok(count)
    }

    /// Reads the numeric dataset `ds` (path `full`) as `f32`: float32 data
    /// as is, other numbers through `f64` (rounded to nearest).
    pub(crate) fn read_f32(&self, ds: &h5::Dataset, full: &str) -> Result<Values, IoError> {
        let what = format!("dataset {full}");
        self.expect_numeric(ds, &what)?;
        let shape = ds.shape();
        self.checked_count(ds, &shape, !ds.filters().is_empty(), &what)?;
        let single = matches!(
            ds.dtype().and_then(|t| t.to_descriptor()),
            Ok(TypeDescriptor::Float(FloatSize::U4))
        );
        let data = if single {
            ds.read_raw::<f32>().map_err(|e| self.h5err(&what, e))?
        } else {
            let wide = ds.read_raw::<f64>().map_err(|e| self.h5err(&what, e))?;
            wide.into_iter().map(|v| v as f32).collect()
        };
        Ok(Values { shape, data })
    }

    /// Rows `rows` of the numeric 1-D or N×k dataset `ds` (path `full`) as
    /// `f32`, read by hyperslab: entries `rows.start·per .. rows.end·per`
    /// of the first axis (`per` > 1 for PySPH's strided arrays), every
    /// entry of the second. The shape returned is the whole dataset's.
    pub(crate) fn read_f32_rows(
        &self,
        ds: &h5::Dataset,
        full: &str,
        rows: std::ops::Range<usize>,
        per: usize,
    ) -> Result<Values, IoError> {
        let what = format!("dataset {full}");
        self.expect_numeric(ds, &what)?;
        let shape = ds.shape();
        self.checked_count(ds, &shape, !ds.filters().is_empty(), &what)?;
        let first = shape.first().copied().unwrap_or(0);
        let (a, b) = ((rows.start * per).min(first), (rows.end * per).min(first));
        let single = matches!(
            ds.dtype().and_then(|t| t.to_descriptor()),
            Ok(TypeDescriptor::Float(FloatSize::U4))
        );
        let err = |e| self.h5err(&what, e);
        let slab = || -> h5::Selection {
            h5::Hyperslab::from(vec![
                h5::SliceOrIndex::from(a..b),
                h5::SliceOrIndex::from(..),
            ])
            .into()
        };
        let data: Vec<f32> = match (shape.len(), single) {
            (1, true) => ds.read_slice_1d::<f32, _>(a..b).map_err(err)?.to_vec(),
            (1, false) => ds
                .read_slice_1d::<f64, _>(a..b)
                .map_err(err)?
                .iter()
                .map(|&v| v as f32)
                .collect(),
            (2, true) => ds
                .read_slice_2d::<f32, _>(slab())
                .map_err(err)?
                .iter()
                .copied()
                .collect(),
            (2, false) => ds
                .read_slice_2d::<f64, _>(slab())
                .map_err(err)?
                .iter()
                .map(|&v| v as f32)
                .collect(),
            _ => {
                return Err(self.err(format!(
                    "{what}: expected a 1-D or N×k array, found shape {}",
                    shape_text(&shape)
                )));
            }
        };
        Ok(Values { shape, data })
    }

    /// [`Hdf5File::read_f32_rows`] as `f64`: rows `rows` (times `per`
    /// along the first axis) of a 1-D or N×k dataset, by hyperslab, with
    /// the whole dataset's shape.
    pub(crate) fn read_f64_rows(
        &self,
        ds: &h5::Dataset,
        full: &str,
        rows: std::ops::Range<usize>,
        per: usize,
    ) -> Result<(Vec<usize>, Vec<f64>), IoError> {
        let what = format!("dataset {full}");
        self.expect_numeric(ds, &what)?;
        let shape = ds.shape();
        self.checked_count(ds, &shape, !ds.filters().is_empty(), &what)?;
        let first = shape.first().copied().unwrap_or(0);
        let (a, b) = ((rows.start * per).min(first), (rows.end * per).min(first));
        let err = |e| self.h5err(&what, e);
        let data: Vec<f64> = match shape.len() {
            1 => ds.read_slice_1d::<f64, _>(a..b).map_err(err)?.to_vec(),
            2 => {
                let slab: h5::Selection = h5::Hyperslab::from(vec![
                    h5::SliceOrIndex::from(a..b),
                    h5::SliceOrIndex::from(..),
                ])
                .into();
                ds.read_slice_2d::<f64, _>(slab)
                    .map_err(err)?
                    .iter()
                    .copied()
                    .collect()
            }
            _ => {
                return Err(self.err(format!(
                    "{what}: expected a 1-D or N×k array, found shape {}",
                    shape_text(&shape)
                )));
            }
        };
        Ok((shape, data))
    }

    /// Reads the numeric dataset `ds` (path `full`) as `f64`.
    pub(crate) fn read_f64(
        &self,
        ds: &h5::Dataset,
        full: &str,
    ) -> Result<(Vec<usize>, Vec<f64>), IoError> {
        let what = format!("dataset {full}");
        self.expect_numeric(ds, &what)?;
        let shape = ds.shape();
        self.checked_count(ds, &shape, !ds.filters().is_empty(), &what)?;
        let data = ds.read_raw::<f64>().map_err(|e| self.h5err(&what, e))?;
        Ok((shape, data))
    }

    /// Reads the integer dataset `ds` (path `full`) as `i64`.
    pub(crate) fn read_i64(
        &self,
        ds: &h5::Dataset,
        full: &str,
    ) -> Result<(Vec<usize>, Vec<i64>), IoError> {
        let what = format!("dataset {full}");
        match ds.dtype().and_then(|t| t.to_descriptor()) {
            // uint64 values above i64::MAX saturate, which callers' range
            // checks reject.
            Ok(TypeDescriptor::Integer(_) | TypeDescriptor::Unsigned(_)) => {}
            _ => {
                return Err(self.err(format!(
                    "{what}: expected integers, found {}",
                    type_name(ds)
                )));
            }
        }
        let shape = ds.shape();
        self.checked_count(ds, &shape, !ds.filters().is_empty(), &what)?;
        let data = ds.read_raw::<i64>().map_err(|e| self.h5err(&what, e))?;
        Ok((shape, data))
    }

    /// Fails unless `container` holds integers or floats.
    fn expect_numeric(&self, container: &h5::Container, what: &str) -> Result<(), IoError> {
        if is_numeric(container) {
            Ok(())
        } else {
            Err(self.err(format!(
                "{what}: expected numbers, found {}",
                type_name(container)
            )))
        }
    }

    /// The values of the numeric attribute `name` of `loc` (called `owner` in
    /// messages) as `f64`; a scalar gives one value. `None` when absent.
    pub(crate) fn attr_f64(
        &self,
        loc: &h5::Location,
        owner: &str,
        name: &str,
    ) -> Result<Option<Vec<f64>>, IoError> {
        let names = loc
            .attr_names()
            .map_err(|e| self.h5err(&format!("attributes of {owner}"), e))?;
        if !names.iter().any(|n| n == name) {
            return Ok(None);
        }
        let what = format!("{owner} attribute {name}");
        let attr = loc.attr(name).map_err(|e| self.h5err(&what, e))?;
        self.expect_numeric(&attr, &what)?;
        let shape = attr.shape();
        self.checked_count(&attr, &shape, false, &what)?;
        let values = attr.read_raw::<f64>().map_err(|e| self.h5err(&what, e))?;
        Ok(Some(values))
    }

    /// The text of the string attribute `name` of `loc` (fixed or variable
    /// length, ASCII or UTF-8), when present; `None` for other types.
    pub(crate) fn attr_text(
        &self,
        loc: &h5::Location,
        owner: &str,
        name: &str,
    ) -> Result<Option<String>, IoError> {
        use h5::types::{FixedAscii, FixedUnicode, VarLenAscii, VarLenUnicode};
        if !loc.attr_names().is_ok_and(|n| n.iter().any(|a| a == name)) {
            return Ok(None);
        }
        let attr = loc
            .attr(name)
            .map_err(|e| self.h5err(&format!("{owner} attribute {name}"), e))?;
        let Ok(desc) = attr.dtype().and_then(|t| t.to_descriptor()) else {
            return Ok(None);
        };
        let text = match desc {
            TypeDescriptor::VarLenUnicode => attr
                .read_raw::<VarLenUnicode>()
                .map(|v| v.first().map(|s| s.as_str().to_string())),
            TypeDescriptor::VarLenAscii => attr
                .read_raw::<VarLenAscii>()
                .map(|v| v.first().map(|s| s.as_str().to_string())),
            TypeDescriptor::FixedAscii(_) => attr
                .read_raw::<FixedAscii<256>>()
                .map(|v| v.first().map(|s| s.as_str().to_string())),
            TypeDescriptor::FixedUnicode(_) => attr
                .read_raw::<FixedUnicode<256>>()
                .map(|v| v.first().map(|s| s.as_str().to_string())),
            _ => return Ok(None),
        };
        text.map(|t| t.map(|s| s.trim_end_matches('\0').trim().to_string()))
            .map_err(|e| self.h5err(&format!("{owner} attribute {name}"), e))
    }

    /// The first value of the numeric attribute `name` of `loc`, when present
    /// and non-empty.
    pub(crate) fn attr_scalar(
        &self,
        loc: &h5::Location,
        owner: &str,
        name: &str,
    ) -> Result<Option<f64>, IoError> {
        Ok(self
            .attr_f64(loc, owner, name)?
            .and_then(|v| v.first().copied()))
    }

    /// The error for a dataset whose length does not match the particles'.
    pub(crate) fn length_mismatch(
        &self,
        full: &str,
        found: usize,
        reference: &str,
        n: usize,
    ) -> IoError {
        self.err(format!(
            "dataset {full} has length {found} but {reference} has length {n}; \
             every per-particle dataset needs one entry per particle"
        ))
    }
}

/// Whether the HDF5 signature sits at offset 0 or at a power-of-two offset
/// from 512 on (where a file with a user block has its superblock).
fn has_signature(file: &mut File, len: u64) -> std::io::Result<bool> {
    let mut offset = 0u64;
    while offset.saturating_add(8) <= len {
        file.seek(SeekFrom::Start(offset))?;
        let mut buf = [0u8; 8];
        file.read_exact(&mut buf)?;
        if &buf == SIGNATURE {
            return Ok(true);
        }
        offset = if offset == 0 { 512 } else { offset * 2 };
    }
    Ok(false)
}
