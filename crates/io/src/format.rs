//! Particle file formats: which reader a file needs (by its name, then by
//! its first bytes), how many frames it holds, and one frame of any of them
//! as a [`ParticleTable`].
//!
//! | format | recognised by | reader |
//! |---|---|---|
//! | NumPy | `.npy`, or the `\x93NUMPY` magic | N×3 positions, no columns |
//! | CSV / text table | `.csv`, `.tsv`, `.txt`, any other text | columns x, y, z and the rest |
//! | VTK XML | `.vtp`, `.vtu`, or `<VTKFile` | points and point data |
//! | XYZ | `.xyz`, `.extxyz`, or a first line holding only a count | frames back to back; `type` numbers the species |
//! | LAMMPS dump | `dump.*`, `.lammpstrj`, `.dump`, or a first line `ITEM: TIMESTEP` | frames; `type`, `id`, … |
//! | `.particles` | `.particles` | an index of timesteps; column `attribute` |
//! | HDF5 | `.h5`, `.hdf5`, or the HDF5 signature | PySPH, SWIFT, Gadget-4, AREPO, GIZMO, one file or several (feature `hdf5`) |
//! | Gadget binary | its first record (format 1 or 2, either byte order) | `snap_033`, or `snap_033.0` … of a multi-file set |
//! | Tipsy | `.tipsy`, `.std`, or a header whose counts match the file's size | ChaNGa/Gasoline, big- or little-endian |
//!
//! Detection works on a path ([`ParticleFormat::detect`]) or on a name and
//! the first bytes of the content ([`ParticleFormat::detect_bytes`]), so
//! data that never was a file (an upload, a network stream) is recognised
//! the same way: `detect(path)` is `detect_bytes(path, first 512 bytes)`
//! (and the file's length, which a Tipsy header must match). A snapshot
//! split over several files is detected by its first file, whichever of
//! them, its stem or its directory names it.
//!
//! [`read_table`] and [`frames_in`] dispatch to the readers of this crate by
//! format; [`read_table_from`] and [`frames_in_from`] do the same on a
//! reader, for every format held in one stream (not a `.particles` series,
//! which names other files, nor HDF5, which the HDF5 library reads by file
//! name).

use std::fs::File;
use std::io::{Read, Seek};
use std::path::Path;

use crate::{CsvTable, IoError, NpyArray, ParticleTable};

/// How many leading bytes content detection looks at.
pub const SNIFF_LEN: usize = 512;

/// What `voxless info` and error messages list as readable.
pub const SUPPORTED: &str = "particles: .npy (N×3), .csv/.txt (x, y, z columns), .vtp/.vtu, \
    .xyz/.extxyz, LAMMPS dumps (dump.*, .lammpstrj, .dump), .particles, Gadget binary \
    snapshots (format 1/2, multi-file), Tipsy, .h5/.hdf5 (PySPH, SWIFT, Gadget-4, AREPO, GIZMO, \
    multi-file; JaxPM as a tessellation; needs --features hdf5); AMR: ExaBricks .cells, \
    AMRClaw fort.qNNNN; meshes: .vtu";

/// A particle file format voxless reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParticleFormat {
    Npy,
    Csv,
    Vtk,
    Xyz,
    Lammps,
    Particles,
    Hdf5,
    GadgetBinary,
    Tipsy,
}

impl ParticleFormat {
    /// A short name for messages.
    pub fn name(self) -> &'static str {
        match self {
            ParticleFormat::Npy => "NumPy array",
            ParticleFormat::Csv => "text table",
            ParticleFormat::Vtk => "VTK XML",
            ParticleFormat::Xyz => "XYZ",
            ParticleFormat::Lammps => "LAMMPS dump",
            ParticleFormat::Particles => ".particles series",
            ParticleFormat::Hdf5 => "HDF5",
            ParticleFormat::GadgetBinary => "Gadget binary snapshot",
            ParticleFormat::Tipsy => "Tipsy file",
        }
    }

    /// Whether this is a cosmological snapshot format (particle types,
    /// regions, units).
    pub fn is_snapshot(self) -> bool {
        matches!(
            self,
            ParticleFormat::Hdf5 | ParticleFormat::GadgetBinary | ParticleFormat::Tipsy
        )
    }

    /// Whether one file of this format can hold several frames.
    pub fn is_multi_frame(self) -> bool {
        matches!(
            self,
            ParticleFormat::Xyz | ParticleFormat::Lammps | ParticleFormat::Particles
        )
    }

    /// The format a file name alone gives: its extension (case-insensitive),
    /// or for LAMMPS also a name starting with `dump.`. `None` for text
    /// table extensions (`.csv`, `.tsv`, `.txt`), which the content may
    /// overrule, and for any other name.
    pub fn from_name(name: &Path) -> Option<ParticleFormat> {
        let file_name = lowercase(name.file_name());
        match lowercase(name.extension()).as_str() {
            "npy" => Some(ParticleFormat::Npy),
            "vtp" | "vtu" => Some(ParticleFormat::Vtk),
            "xyz" | "extxyz" => Some(ParticleFormat::Xyz),
            "lammpstrj" | "dump" => Some(ParticleFormat::Lammps),
            "particles" => Some(ParticleFormat::Particles),
            "h5" | "hdf5" => Some(ParticleFormat::Hdf5),
            "tipsy" | "std" => Some(ParticleFormat::Tipsy),
            _ if file_name.starts_with("dump.") => Some(ParticleFormat::Lammps),
            _ => None,
        }
    }

    /// The format of the file at `path`: by its name ([`from_name`]), and
    /// when that does not decide, by its first [`SNIFF_LEN`] bytes (see
    /// [`detect_bytes`]). `None` when neither says (callers reading
    /// particles take it as a text table). Fails only when the file has to
    /// be read and cannot be.
    ///
    /// [`from_name`]: ParticleFormat::from_name
    /// [`detect_bytes`]: ParticleFormat::detect_bytes
    pub fn detect(path: &Path) -> Result<Option<ParticleFormat>, IoError> {
        // A snapshot of several files: its first file says.
        let first = crate::snapshot::first_file(path);
        if first != path {
            return ParticleFormat::detect(&first);
        }
        // A device, FIFO or socket (/dev/zero, a pipe named x.npy) would
        // block or never end: particle data comes from regular files.
        if let Ok(meta) = std::fs::metadata(path)
            && !meta.is_file()
            && !meta.is_dir()
        {
            return Err(IoError::format(
                path,
                "not a regular file (a device, FIFO or socket): particle data is read from files",
            ));
        }
        // The name decides without opening the file (which may not exist
        // yet, or be a directory of frames the caller expands).
        if let Some(format) = ParticleFormat::from_name(path) {
            return Ok(Some(format));
        }
        let mut head = Vec::with_capacity(SNIFF_LEN);
        let file = File::open(path).map_err(|e| IoError::io(path, e))?;
        let len = file.metadata().map_err(|e| IoError::io(path, e))?.len();
        file.take(SNIFF_LEN as u64)
            .read_to_end(&mut head)
            .map_err(|e| IoError::io(path, e))?;
        Ok(ParticleFormat::detect_content(path, &head, len))
    }

    /// The format of content named `name` (a file name, or whatever the
    /// data is called) that starts with `head`: by the name, then by the
    /// content. Only the first [`SNIFF_LEN`] bytes of `head` are looked at,
    /// so passing all of the data gives the same answer as
    /// [`detect`](ParticleFormat::detect) on a file holding it.
    ///
    /// The content shows HDF5 and NumPy by their magic bytes, VTK XML by
    /// `<?xml` or `<VTKFile`, a LAMMPS dump by a first line
    /// `ITEM: TIMESTEP`, and XYZ by a first line that is just a count
    /// followed by more lines. A `.csv`, `.tsv` or `.txt` name makes it a
    /// text table unless the content is a LAMMPS dump.
    pub fn detect_bytes(name: &Path, head: &[u8]) -> Option<ParticleFormat> {
        ParticleFormat::detect_content(name, head, head.len() as u64)
    }

    /// [`detect_bytes`](ParticleFormat::detect_bytes) of content `len`
    /// bytes long (which a Tipsy header's counts must match).
    pub fn detect_content(name: &Path, head: &[u8], len: u64) -> Option<ParticleFormat> {
        if let Some(format) = ParticleFormat::from_name(name) {
            return Some(format);
        }
        let head = &head[..head.len().min(SNIFF_LEN)];
        if crate::gadget_bin::sniff_gadget_binary(head) {
            return Some(ParticleFormat::GadgetBinary);
        }
        if crate::tipsy::sniff_tipsy(head, len) {
            return Some(ParticleFormat::Tipsy);
        }
        let table_ext = matches!(lowercase(name.extension()).as_str(), "csv" | "tsv" | "txt");
        match sniff(head) {
            // A text table's extension wins unless the content is a dump.
            Some(ParticleFormat::Lammps) => Some(ParticleFormat::Lammps),
            _ if table_ext => Some(ParticleFormat::Csv),
            other => other,
        }
    }
}

/// A path component in lower case ("" when absent), for matching names.
fn lowercase(part: Option<&std::ffi::OsStr>) -> String {
    part.map(|p| p.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// The format the first bytes of a file show, if any.
fn sniff(head: &[u8]) -> Option<ParticleFormat> {
    // Binary formats announce themselves with magic bytes.
    if head.starts_with(b"\x89HDF\r\n\x1a\n") {
        return Some(ParticleFormat::Hdf5);
    }
    if head.starts_with(b"\x93NUMPY") {
        return Some(ParticleFormat::Npy);
    }
    // Text formats by their first line, after a byte order mark and blank
    // space.
    let text = String::from_utf8_lossy(head);
    let text = text.trim_start_matches('\u{feff}').trim_start();
    if text.starts_with("<?xml") || text.starts_with("<VTKFile") {
        return Some(ParticleFormat::Vtk);
    }
    let first = text.lines().next().unwrap_or("").trim();
    if first == "ITEM: TIMESTEP" {
        return Some(ParticleFormat::Lammps);
    }
    // An XYZ file starts with its atom count alone on a line.
    if first.parse::<usize>().is_ok() && text.lines().nth(1).is_some() {
        return Some(ParticleFormat::Xyz);
    }
    None
}

/// Which part of a file to read: the PySPH particle array and the
/// SWIFT/Gadget particle type.
#[derive(Clone, Debug, Default)]
pub struct TableOptions {
    pub group: Option<String>,
    pub part_type: Option<u32>,
    /// Share `r` of `k` of the particles (`Some((r, k))`: rows
    /// `n·r/k .. n·(r+1)/k`), for one rank of a parallel run. HDF5 files read
    /// only those rows (hyperslabs) and say so in [`ParticleTable::rows`];
    /// other formats read every row.
    pub share: Option<(usize, usize)>,
    /// Keep only the particles that can touch this region (cosmological
    /// snapshots: SWIFT through its cell metadata, Gadget binary and Tipsy
    /// by streaming); other formats ignore it and the caller cuts.
    pub region: Option<crate::Region>,
    /// The file's periodic box is to be ignored (`--no-box`): a region
    /// without a `period` then measures plainly.
    pub no_file_box: bool,
}

/// A frame of a particle file: the table, and for HDF5 a line saying which
/// part was read (worth a note).
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    pub table: ParticleTable,
    pub note: Option<String>,
}

/// Frames in one file of `format` (1 for single-frame formats, whose file
/// is then not opened).
pub fn frames_in(path: &Path, format: ParticleFormat) -> Result<usize, IoError> {
    Ok(match format {
        ParticleFormat::Lammps => crate::lammps_frames(path)?,
        ParticleFormat::Xyz => crate::xyz_frames(path)?,
        ParticleFormat::Particles => crate::particles_frames(path)?,
        _ => 1,
    })
}

/// [`frames_in`] of the content `reader` yields (for a `.particles` series,
/// the index text); `name` labels errors.
pub fn frames_in_from<R: Read>(
    reader: R,
    name: &Path,
    format: ParticleFormat,
) -> Result<usize, IoError> {
    Ok(match format {
        ParticleFormat::Lammps => crate::lammps_frames_from(reader, name)?,
        ParticleFormat::Xyz => crate::xyz_frames_from(reader, name)?,
        ParticleFormat::Particles => crate::particles_frames_from(reader, name)?,
        _ => 1,
    })
}

/// Reads frame `frame` of `path` (in `format`) as a table. Single-frame
/// formats ignore `frame`. `group` and `part_type` are errors for formats
/// they do not apply to, so a typo does not pass silently.
///
/// A `.npy` file must hold an N×3 array (the positions); a text table must
/// have columns `x`, `y` and `z` (any case), and every column, positions
/// included, becomes a column of the table.
pub fn read_table(
    path: &Path,
    format: ParticleFormat,
    frame: usize,
    opts: &TableOptions,
) -> Result<Table, IoError> {
    check_options(path, format, opts)?;
    let table = match format {
        ParticleFormat::Npy => ParticleTable {
            positions: crate::npy::read_npy_positions(path)?,
            ..Default::default()
        },
        ParticleFormat::Csv => csv_table(crate::read_csv(path)?, path)?,
        ParticleFormat::Vtk => crate::read_vtk_points(path)?,
        ParticleFormat::Xyz => crate::read_xyz(path, frame)?,
        ParticleFormat::Lammps => {
            let (table, note) = crate::lammps::read_lammps_noted(path, frame)?;
            return Ok(Table { table, note });
        }
        ParticleFormat::Particles => crate::read_particles_file(path, frame)?,
        ParticleFormat::Hdf5 => return read_hdf5(path, opts),
        ParticleFormat::GadgetBinary => {
            let mut region = opts.region;
            if let Some(r) = region.as_mut()
                && r.period.is_none()
                && !opts.no_file_box
            {
                let b = crate::gadget_bin::open_gadget_binary(path)?.header.box_size;
                r.period = (b > 0.0).then_some(([0.0; 3], [b; 3]));
            }
            let t = crate::gadget_bin::read_gadget_binary(
                path,
                opts.part_type,
                opts.share,
                region.as_ref(),
            )?;
            return Ok(snapshot_table(t, opts, "Gadget binary", path));
        }
        ParticleFormat::Tipsy => {
            let t =
                crate::tipsy::read_tipsy(path, opts.part_type, opts.share, opts.region.as_ref())?;
            return Ok(snapshot_table(t, opts, "Tipsy", path));
        }
    };
    Ok(Table { table, note: None })
}

/// A snapshot's table with a note saying which type was read when none was
/// asked for, and how many particles a region kept.
fn snapshot_table(table: ParticleTable, opts: &TableOptions, what: &str, path: &Path) -> Table {
    let mut said = Vec::new();
    if opts.part_type.is_none() {
        said.push(format!(
            "{what}: the particles of the default type (pick one with --part-type; `voxless \
             info {}` lists them)",
            path.display()
        ));
    }
    if opts.region.is_some() {
        said.push(format!("--region: {} particles kept", table.len()));
    }
    Table {
        table,
        note: (!said.is_empty()).then(|| said.join("; ")),
    }
}

/// [`read_table`] of the content from `reader`'s position to its end;
/// `name` labels errors, which read as [`read_table`]'s for a file of that
/// name. The readers' size checks use the reader's length.
///
/// A `.particles` series is an index naming other files: read it with
/// [`read_particles_from`](crate::read_particles_from), which takes a way to
/// open them. HDF5 content needs a file (the HDF5 library opens files by
/// name). Both are errors here.
pub fn read_table_from<R: Read + Seek>(
    mut reader: R,
    name: &Path,
    format: ParticleFormat,
    frame: usize,
    opts: &TableOptions,
) -> Result<Table, IoError> {
    check_options(name, format, opts)?;
    let table = match format {
        ParticleFormat::Npy => npy_table(crate::read_npy_from(reader, name)?, name)?,
        ParticleFormat::Csv => csv_table(crate::read_csv_from(reader, name)?, name)?,
        ParticleFormat::Vtk => {
            // The VTK parser addresses appended data by offset, so it needs
            // the whole content; that allocates its length, no more.
            let mut bytes = Vec::new();
            reader
                .read_to_end(&mut bytes)
                .map_err(|e| IoError::io(name, e))?;
            crate::read_vtk_points_bytes(&bytes, name)?
        }
        ParticleFormat::Xyz => crate::read_xyz_from(reader, name, frame)?,
        ParticleFormat::Lammps => crate::read_lammps_from(reader, name, frame)?,
        ParticleFormat::Particles => {
            return Err(IoError::format(
                name,
                "a .particles series is an index naming one file per timestep; read it from a \
                 path, or with read_particles_from and a way to open its timesteps",
            ));
        }
        ParticleFormat::Hdf5 => return Err(hdf5_from_memory(name)),
        ParticleFormat::GadgetBinary => {
            crate::gadget_bin::read_gadget_binary_from(reader, name, opts.part_type)?
        }
        ParticleFormat::Tipsy => crate::tipsy::read_tipsy_from(reader, name, opts.part_type)?,
    };
    Ok(Table { table, note: None })
}

/// `group` only applies to PySPH HDF5 output, `part_type` and `region` to
/// snapshots.
fn check_options(path: &Path, format: ParticleFormat, opts: &TableOptions) -> Result<(), IoError> {
    if format == ParticleFormat::Hdf5 {
        return Ok(());
    }
    if opts.group.is_some() {
        return Err(not_applicable(path, "group", "PySPH HDF5 output", format));
    }
    if format.is_snapshot() {
        return Ok(());
    }
    if opts.part_type.is_some() {
        return Err(not_applicable(
            path,
            "part_type",
            "snapshots (SWIFT/Gadget/AREPO/GIZMO HDF5, Gadget binary, Tipsy)",
            format,
        ));
    }
    if opts.region.is_some() {
        return Err(not_applicable(
            path,
            "region",
            "snapshots (SWIFT/Gadget/AREPO/GIZMO HDF5, Gadget binary, Tipsy)",
            format,
        ));
    }
    Ok(())
}

fn not_applicable(path: &Path, key: &str, applies: &str, format: ParticleFormat) -> IoError {
    IoError::format(
        path,
        format!(
            "particles.{key} (--{}) applies to {applies}, but this is a {}",
            key.replace('_', "-"),
            format.name()
        ),
    )
}

/// The positions of an N×3 array.
fn npy_table(a: NpyArray, path: &Path) -> Result<ParticleTable, IoError> {
    crate::npy::check_positions_shape(&a.shape, path)?;
    let positions = a.data.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    Ok(ParticleTable {
        positions,
        ..Default::default()
    })
}

/// A table with x, y, z columns; every column (x, y, z included) is kept.
fn csv_table(t: CsvTable, path: &Path) -> Result<ParticleTable, IoError> {
    let col = |name: &str| {
        t.column(name).ok_or_else(|| {
            IoError::format(
                path,
                format!("no column '{name}' (columns: {})", t.columns.join(", ")),
            )
        })
    };
    let (x, y, z) = (col("x")?, col("y")?, col("z")?);
    let positions = (0..t.rows()).map(|i| [x[i], y[i], z[i]]).collect();
    // Every column in order, by index (not looked up by name per column,
    // which is quadratic in the columns).
    let columns = t
        .columns
        .iter()
        .zip(&t.data)
        .map(|(name, v)| (name.clone(), v.iter().map(|&v| v as f32).collect()))
        .collect();
    Ok(ParticleTable {
        positions,
        columns,
        ..Default::default()
    })
}

/// The error for an HDF5 file in a build without the `hdf5` feature; it
/// says how to build with it.
pub fn hdf5_unsupported(path: &Path) -> IoError {
    IoError::format(
        path,
        "HDF5 files need voxless built with the hdf5 feature: \
         `cargo build --release --features hdf5` (needs libhdf5-dev)",
    )
}

/// The error for HDF5 content handed over in memory.
fn hdf5_from_memory(name: &Path) -> IoError {
    if cfg!(feature = "hdf5") {
        IoError::format(
            name,
            "HDF5 content can only be read from a file: the HDF5 library opens files by name",
        )
    } else {
        hdf5_unsupported(name)
    }
}

/// The HDF5 particle layouts (PySPH, SWIFT/Gadget) when the `hdf5` feature
/// is on.
#[cfg(feature = "hdf5")]
fn read_hdf5(path: &Path, opts: &TableOptions) -> Result<Table, IoError> {
    use crate::hdf5::read_pysph_share;
    use crate::{Hdf5Kind, hdf5_kind, pysph_groups};

    let kind = hdf5_kind(path)?;
    let what = match kind {
        Hdf5Kind::PySph => "PySPH output",
        Hdf5Kind::Gadget => "a SWIFT/Gadget snapshot",
        Hdf5Kind::Jaxpm => "a JaxPM run",
        Hdf5Kind::Flash => "FLASH AMR output (read it with --amr)",
        Hdf5Kind::Athena => "Athena++ AMR output (read it with --amr)",
        Hdf5Kind::Other => "an HDF5 file of unknown layout",
    };
    // The options must fit the layout found, as for the other formats.
    if opts.group.is_some() && kind != Hdf5Kind::PySph {
        return Err(IoError::format(
            path,
            format!("particles.group (--group) applies to PySPH output, but this is {what}"),
        ));
    }
    for (given, key) in [
        (opts.part_type.is_some(), "part_type (--part-type)"),
        (opts.region.is_some(), "region (--region)"),
    ] {
        if given && kind != Hdf5Kind::Gadget {
            return Err(IoError::format(
                path,
                format!("particles.{key} applies to snapshots, but this is {what}"),
            ));
        }
    }
    match kind {
        Hdf5Kind::PySph => {
            // Default to the `fluid` array, else the first one, and say so
            // when there was a choice.
            let groups = pysph_groups(path)?;
            let group = match &opts.group {
                Some(g) => g.clone(),
                None if groups.iter().any(|g| g == "fluid") => "fluid".into(),
                None => groups
                    .first()
                    .cloned()
                    .ok_or_else(|| IoError::format(path, "PySPH output without particle arrays"))?,
            };
            let table = read_pysph_share(path, &group, opts.share)?;
            let note = (opts.group.is_none() && groups.len() > 1).then(|| {
                format!(
                    "PySPH particle array '{group}' (arrays: {}; pick one with --group)",
                    groups.join(", ")
                )
            });
            Ok(Table { table, note })
        }
        Hdf5Kind::Gadget => {
            let (table, note) = crate::hdf5::read_gadget_snapshot(
                path,
                opts.part_type,
                opts.share,
                opts.region.as_ref(),
                !opts.no_file_box,
            )?;
            Ok(Table { table, note })
        }
        Hdf5Kind::Jaxpm => Err(IoError::format(
            path,
            "a JaxPM run: render it as a phase-space tessellation by adding --snapshot K \
             or --lagrangian N (N and the box come from the file), or in a scene with \
             [tets] file = ...",
        )),
        Hdf5Kind::Flash | Hdf5Kind::Athena => {
            Err(IoError::format(path, format!("is {what}, not particles")))
        }
        Hdf5Kind::Other => Err(IoError::format(
            path,
            "an HDF5 file that is neither PySPH output nor a SWIFT/Gadget snapshot \
             (`voxless info FILE` lists what it holds)",
        )),
    }
}

/// Without the `hdf5` feature every HDF5 file is an error that says how to
/// build with it.
#[cfg(not(feature = "hdf5"))]
fn read_hdf5(path: &Path, _: &TableOptions) -> Result<Table, IoError> {
    Err(hdf5_unsupported(path))
}
