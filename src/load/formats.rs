//! Particle file formats: which reader a path needs (by extension, then by
//! content), how many frames it holds, and one frame of any of them as a
//! [`ParticleTable`].
//!
//! | format | recognised by | reader |
//! |---|---|---|
//! | NumPy | `.npy`, or the `\x93NUMPY` magic | N×3 positions, no columns |
//! | CSV / text table | `.csv`, `.tsv`, `.txt`, any other text | columns x, y, z and the rest |
//! | VTK XML | `.vtp`, `.vtu`, or `<VTKFile` | points and point data |
//! | XYZ | `.xyz`, `.extxyz` | frames back to back; `type` numbers the species |
//! | LAMMPS dump | `dump.*`, `.lammpstrj`, `.dump`, or a first line `ITEM: TIMESTEP` | frames; `type`, `id`, … |
//! | `.particles` | `.particles` | an index of timesteps; column `attribute` |
//! | HDF5 | `.h5`, `.hdf5`, or the HDF5 signature | PySPH or SWIFT/Gadget (feature `hdf5`) |

use std::io::Read;
use std::path::Path;

use voxless_io::{ParticleTable, read_csv, read_npy};

use crate::SceneError;

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
}

/// What `voxless info` and error messages list as readable.
pub const SUPPORTED: &str = "particles: .npy (N×3), .csv/.txt (x, y, z columns), .vtp/.vtu, \
    .xyz/.extxyz, LAMMPS dumps (dump.*, .lammpstrj, .dump), .particles, .h5/.hdf5 (PySPH, \
    SWIFT/Gadget; JaxPM as a tessellation; needs --features hdf5); AMR: ExaBricks .cells, \
    AMRClaw fort.qNNNN; meshes: .vtu";

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
        }
    }

    /// Whether one file of this format can hold several frames.
    pub fn is_multi_frame(self) -> bool {
        matches!(
            self,
            ParticleFormat::Xyz | ParticleFormat::Lammps | ParticleFormat::Particles
        )
    }

    /// The format of `path`: by extension (`dump.*` by name), and for text
    /// tables and unknown extensions by the file's first bytes. `None` when
    /// neither says (callers reading particles take it as a text table).
    /// Fails only when the file cannot be read.
    pub fn detect(path: &Path) -> Result<Option<ParticleFormat>, SceneError> {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        let by_ext = match ext.as_str() {
            "npy" => Some(ParticleFormat::Npy),
            "vtp" | "vtu" => Some(ParticleFormat::Vtk),
            "xyz" | "extxyz" => Some(ParticleFormat::Xyz),
            "lammpstrj" | "dump" => Some(ParticleFormat::Lammps),
            "particles" => Some(ParticleFormat::Particles),
            "h5" | "hdf5" => Some(ParticleFormat::Hdf5),
            _ if name.starts_with("dump.") => Some(ParticleFormat::Lammps),
            _ => None,
        };
        if by_ext.is_some() {
            return Ok(by_ext);
        }
        let sniffed = sniff(path)?;
        let table_ext = matches!(ext.as_str(), "csv" | "tsv" | "txt");
        Ok(match sniffed {
            // A text table's extension wins unless the content is a dump.
            Some(ParticleFormat::Lammps) => Some(ParticleFormat::Lammps),
            _ if table_ext => Some(ParticleFormat::Csv),
            other => other,
        })
    }
}

/// The format the first bytes of a file show, if any.
fn sniff(path: &Path) -> Result<Option<ParticleFormat>, SceneError> {
    let mut head = Vec::with_capacity(512);
    let file = std::fs::File::open(path).map_err(|source| voxless_io::IoError::Io {
        path: path.into(),
        source,
    })?;
    file.take(512)
        .read_to_end(&mut head)
        .map_err(|source| voxless_io::IoError::Io {
            path: path.into(),
            source,
        })?;
    if head.starts_with(b"\x89HDF\r\n\x1a\n") {
        return Ok(Some(ParticleFormat::Hdf5));
    }
    if head.starts_with(b"\x93NUMPY") {
        return Ok(Some(ParticleFormat::Npy));
    }
    let text = String::from_utf8_lossy(&head);
    let text = text.trim_start_matches('\u{feff}').trim_start();
    if text.starts_with("<?xml") || text.starts_with("<VTKFile") {
        return Ok(Some(ParticleFormat::Vtk));
    }
    let first = text.lines().next().unwrap_or("").trim();
    if first == "ITEM: TIMESTEP" {
        return Ok(Some(ParticleFormat::Lammps));
    }
    // An XYZ file starts with its atom count alone on a line.
    if first.parse::<usize>().is_ok() && text.lines().nth(1).is_some() {
        return Ok(Some(ParticleFormat::Xyz));
    }
    Ok(None)
}

/// Which part of a file to read: the PySPH particle array and the
/// SWIFT/Gadget particle type.
#[derive(Clone, Debug, Default)]
pub struct TableOptions {
    pub group: Option<String>,
    pub part_type: Option<u32>,
}

/// Frames in one file of `format` (1 for single-frame formats).
pub fn frames_in(path: &Path, format: ParticleFormat) -> Result<usize, SceneError> {
    Ok(match format {
        ParticleFormat::Lammps => voxless_io::lammps_frames(path)?,
        ParticleFormat::Xyz => voxless_io::xyz_frames(path)?,
        ParticleFormat::Particles => voxless_io::particles_frames(path)?,
        _ => 1,
    })
}

/// A frame of a particle file: the table, and for HDF5 a line saying which
/// part was read (worth a note).
pub struct Table {
    pub table: ParticleTable,
    pub note: Option<String>,
}

/// Reads frame `frame` of `path` (in `format`) as a table. Single-frame
/// formats ignore `frame`. `group` and `part_type` are errors for formats
/// they do not apply to, so a typo does not pass silently.
pub fn read_table(
    path: &Path,
    format: ParticleFormat,
    frame: usize,
    opts: &TableOptions,
) -> Result<Table, SceneError> {
    if format != ParticleFormat::Hdf5 {
        if opts.group.is_some() {
            return Err(not_applicable(path, "group", "PySPH HDF5 output", format));
        }
        if opts.part_type.is_some() {
            return Err(not_applicable(
                path,
                "part_type",
                "SWIFT/Gadget HDF5 snapshots",
                format,
            ));
        }
    }
    let table = match format {
        ParticleFormat::Npy => read_npy_table(path)?,
        ParticleFormat::Csv => read_csv_table(path)?,
        ParticleFormat::Vtk => voxless_io::read_vtk_points(path)?,
        ParticleFormat::Xyz => voxless_io::read_xyz(path, frame)?,
        ParticleFormat::Lammps => voxless_io::read_lammps(path, frame)?,
        ParticleFormat::Particles => voxless_io::read_particles_file(path, frame)?,
        ParticleFormat::Hdf5 => return hdf5::read(path, opts),
    };
    Ok(Table { table, note: None })
}

fn not_applicable(path: &Path, key: &str, applies: &str, format: ParticleFormat) -> SceneError {
    SceneError::data(
        path,
        format!(
            "particles.{key} (--{}) applies to {applies}, but this is a {}",
            key.replace('_', "-"),
            format.name()
        ),
    )
}

fn read_npy_table(path: &Path) -> Result<ParticleTable, SceneError> {
    let a = read_npy(path)?;
    if a.shape.len() != 2 || a.shape[1] != 3 {
        return Err(SceneError::data(
            path,
            format!(
                "expected an N×3 array of positions, found shape ({})",
                a.shape
                    .iter()
                    .map(|s| s.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ));
    }
    let positions = a
        .data
        .chunks_exact(3)
        .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
        .collect();
    Ok(ParticleTable {
        positions,
        ..Default::default()
    })
}

/// A CSV with x, y, z columns; every column (x, y, z included) is kept.
fn read_csv_table(path: &Path) -> Result<ParticleTable, SceneError> {
    let t = read_csv(path)?;
    let col = |name: &str| {
        t.column(name).ok_or_else(|| {
            SceneError::data(
                path,
                format!("no column '{name}' (columns: {})", t.columns.join(", ")),
            )
        })
    };
    let (x, y, z) = (col("x")?, col("y")?, col("z")?);
    let positions = (0..t.rows())
        .map(|i| [x[i] as f32, y[i] as f32, z[i] as f32])
        .collect();
    let columns = t
        .columns
        .iter()
        .map(|name| {
            let v = t.column(name).unwrap_or(&[]);
            (name.clone(), v.iter().map(|&v| v as f32).collect())
        })
        .collect();
    Ok(ParticleTable {
        positions,
        columns,
        ..Default::default()
    })
}

/// Keeps the rows whose `type` column equals `species`: a number, or for an
/// XYZ file also an element symbol (`frame` is the frame the table is of).
pub fn keep_species(
    table: &mut ParticleTable,
    species: &str,
    path: &Path,
    format: ParticleFormat,
    frame: usize,
) -> Result<(), SceneError> {
    let Some(types) = table.column("type") else {
        return Err(SceneError::data(
            path,
            format!(
                "particles.species (--species) needs a 'type' column, and this {} has none \
                 (columns: {})",
                format.name(),
                column_list(table)
            ),
        ));
    };
    let present = distinct(types);
    let wanted: f32 = match species.trim().parse::<f32>() {
        Ok(v) => v,
        Err(_) if format == ParticleFormat::Xyz => {
            let symbols = voxless_io::xyz_species(path, frame)?;
            match symbols.iter().position(|s| s == species.trim()) {
                Some(i) => (i + 1) as f32,
                None => {
                    return Err(SceneError::data(
                        path,
                        format!(
                            "no species '{species}' in frame {frame} (species: {})",
                            symbols.join(", ")
                        ),
                    ));
                }
            }
        }
        Err(_) => {
            return Err(SceneError::data(
                path,
                format!(
                    "particles.species: '{species}' is not a type number (types present: {present})"
                ),
            ));
        }
    };
    let keep: Vec<bool> = types.iter().map(|&t| t == wanted).collect();
    if !keep.iter().any(|&k| k) {
        return Err(SceneError::data(
            path,
            format!("no particle of type {species} (types present: {present})"),
        ));
    }
    let mut it = keep.iter();
    table.positions.retain(|_| *it.next().unwrap_or(&false));
    for (_, c) in &mut table.columns {
        let mut it = keep.iter();
        c.retain(|_| *it.next().unwrap_or(&false));
    }
    Ok(())
}

/// The distinct values of a type column, sorted, as text ("1, 2, 3").
fn distinct(values: &[f32]) -> String {
    let mut v: Vec<f32> = values.to_vec();
    v.sort_by(f32::total_cmp);
    v.dedup();
    let shown: Vec<String> = v.iter().take(20).map(|t| t.to_string()).collect();
    let more = if v.len() > 20 { ", …" } else { "" };
    format!("{}{more}", shown.join(", "))
}

/// The table's column names for messages, or "none".
pub fn column_list(table: &ParticleTable) -> String {
    if table.columns.is_empty() {
        "none".into()
    } else {
        table.column_names().join(", ")
    }
}

/// The HDF5 particle layouts (PySPH, SWIFT/Gadget) when the `hdf5` feature
/// is on; an error saying how to turn it on otherwise.
#[cfg(feature = "hdf5")]
pub mod hdf5 {
    use std::path::Path;

    use voxless_io::{Hdf5Kind, hdf5_kind, pysph_groups, read_gadget, read_pysph};

    use super::{Table, TableOptions};
    use crate::SceneError;

    pub(super) fn read(path: &Path, opts: &TableOptions) -> Result<Table, SceneError> {
        let kind = hdf5_kind(path)?;
        let what = match kind {
            Hdf5Kind::PySph => "PySPH output",
            Hdf5Kind::Gadget => "a SWIFT/Gadget snapshot",
            Hdf5Kind::Jaxpm => "a JaxPM run",
            Hdf5Kind::Other => "an HDF5 file of unknown layout",
        };
        if opts.group.is_some() && kind != Hdf5Kind::PySph {
            return Err(SceneError::data(
                path,
                format!("particles.group (--group) applies to PySPH output, but this is {what}"),
            ));
        }
        if opts.part_type.is_some() && kind != Hdf5Kind::Gadget {
            return Err(SceneError::data(
                path,
                format!(
                    "particles.part_type (--part-type) applies to SWIFT/Gadget snapshots, but \
                     this is {what}"
                ),
            ));
        }
        match kind {
            Hdf5Kind::PySph => {
                let groups = pysph_groups(path)?;
                let group = match &opts.group {
                    Some(g) => g.clone(),
                    None if groups.iter().any(|g| g == "fluid") => "fluid".into(),
                    None => groups.first().cloned().ok_or_else(|| {
                        SceneError::data(path, "PySPH output without particle arrays")
                    })?,
                };
                let table = read_pysph(path, &group)?;
                let note = (opts.group.is_none() && groups.len() > 1).then(|| {
                    format!(
                        "PySPH particle array '{group}' (arrays: {}; pick one with --group)",
                        groups.join(", ")
                    )
                });
                Ok(Table { table, note })
            }
            Hdf5Kind::Gadget => {
                let part_type = opts.part_type.unwrap_or(0);
                let table = read_gadget(path, part_type)?;
                let note = opts.part_type.is_none().then(|| {
                    format!("SWIFT/Gadget PartType{part_type} (pick another with --part-type N)")
                });
                Ok(Table { table, note })
            }
            Hdf5Kind::Jaxpm => Err(SceneError::data(
                path,
                "a JaxPM run: render it as a phase-space tessellation by adding --snapshot K \
                 or --lagrangian N (N and the box come from the file), or in a scene with \
                 [tets] file = ...",
            )),
            Hdf5Kind::Other => Err(SceneError::data(
                path,
                "an HDF5 file that is neither PySPH output nor a SWIFT/Gadget snapshot \
                 (`voxless info FILE` lists what it holds)",
            )),
        }
    }
}

/// Without the `hdf5` feature every HDF5 file is an error that says how to
/// build with it.
#[cfg(not(feature = "hdf5"))]
pub mod hdf5 {
    use std::path::Path;

    use super::{Table, TableOptions};
    use crate::SceneError;

    /// The error for an HDF5 file in a build without HDF5 support.
    pub fn unsupported(path: &Path) -> SceneError {
        SceneError::data(
            path,
            "HDF5 files need voxless built with the hdf5 feature: \
             `cargo build --release --features hdf5` (needs libhdf5-dev)",
        )
    }

    pub(super) fn read(path: &Path, _: &TableOptions) -> Result<Table, SceneError> {
        Err(unsupported(path))
    }
}
