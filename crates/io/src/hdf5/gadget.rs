//! SWIFT, Gadget-4, AREPO and GIZMO snapshots, in one file or several.
//!
//! Every one of these codes writes one group per particle type, `PartType0`
//! (gas), `PartType1` (dark matter), …, holding `Coordinates` (N×3) and
//! per-particle datasets such as `Masses`, `SmoothingLength(s)`, `Density`,
//! `InternalEnergy`, `ParticleIDs` and `Velocities` (N×3). The `Header`
//! group's attributes hold `BoxSize` (a scalar in Gadget-4/AREPO/GIZMO, a
//! 3-vector in SWIFT), `Time` (the scale factor in cosmological runs),
//! `Redshift`, `MassTable` (the mass of every particle of a type whose group
//! has no `Masses` dataset), and the counts `NumPart_ThisFile`,
//! `NumPart_Total` (+ `NumPart_Total_HighWord` × 2³²) and
//! `NumFilesPerSnapshot`.
//!
//! **Several files.** Big runs split a snapshot over `snap_033.0.hdf5` …
//! `snap_033.(K-1).hdf5`, often in a `snapdir_033/` directory; any one of
//! them, the stem or the directory names the whole snapshot
//! ([`snapshot_files`]). Particles of a type are read in file order. Every
//! file must be there (the header's `NumFilesPerSnapshot` says how many),
//! and the files' `NumPart_ThisFile` must add up to `NumPart_Total`.
//!
//! **Codes.** SWIFT (a `HydroScheme` or SWIFT `Units` group, or `Header`
//! `Code`) writes `SmoothingLengths` = h with support γh and its kernel's
//! name; Gadget-4 and GIZMO (`Header` `GIZMO_version`) write
//! `SmoothingLength` = the support radius; AREPO's gas cells (a `Config`
//! group with `VORONOI`, or gas with `Masses` and `Density` but no smoothing
//! length) carry none: their size comes from the cell volume `m/ρ`.
//!
//! **Units.** SWIFT's `Units` group (`Unit length in cgs (U_L)`, …) and the
//! Gadget family's `UnitLength_in_cm`, `UnitMass_in_g`,
//! `UnitVelocity_in_cm_per_s` (in `Header` or `Parameters`) become
//! [`Units`]; positions stay as stored (comoving in cosmological runs).
//!
//! **Regions.** With a [`Region`], only the particles that can touch it are
//! kept: SWIFT's `Cells/` metadata (cell centres, counts and offsets per
//! type) says which rows to read at all; other files are streamed in chunks
//! of [`CHUNK`] rows and filtered, so memory follows what is kept.

use std::ops::Range;
use std::path::{Path, PathBuf};

use super::{Hdf5File, is_numeric, numbered, shape_text};
use crate::snapshot::{
    Region, Units, default_part_type, member_path, missing_part_type, snapshot_files,
};
use crate::{IoError, ParticleTable, SphCode, SphConvention};

mod cells;

/// Rows read at a time when a region filters them.
const CHUNK: usize = 1 << 20;

/// What a snapshot holds, from its headers alone (for `voxless info` and
/// for choosing what to read).
#[derive(Clone, Debug, PartialEq)]
pub struct GadgetHdf5 {
    /// The files, in order.
    pub files: Vec<PathBuf>,
    /// Particles of each type in each file.
    pub per_file: Vec<Vec<u64>>,
    /// Particles of each type in the snapshot.
    pub total: Vec<u64>,
    /// Which code's conventions apply (see the module docs).
    pub code: SphCode,
    /// "SWIFT", "Gadget-4", "AREPO", "GIZMO" or "Gadget".
    pub code_name: &'static str,
    /// The kernel SWIFT names, if any.
    pub kernel: Option<String>,
    pub box_size: Option<[f64; 3]>,
    pub time: Option<f64>,
    pub redshift: Option<f64>,
    pub units: Option<Units>,
    pub mass_table: Vec<f64>,
    /// Per type with particles: the datasets of its group in the first file
    /// that has some.
    pub fields: Vec<(u32, Vec<String>)>,
    /// Whether the file carries SWIFT's `Cells/` metadata.
    pub cells: bool,
}

/// Reads particle type `part_type` (the group `PartType<part_type>`) of a
/// SWIFT or Gadget-family snapshot; see [`read_gadget_snapshot`].
pub fn read_gadget(path: &Path, part_type: u32) -> Result<ParticleTable, IoError> {
    read_gadget_share(path, part_type, None)
}

/// [`read_gadget`] of share `r` of `k` of the particles (`share = (r, k)`:
/// rows `n·r/k .. n·(r+1)/k`); the table's `rows` says which.
pub fn read_gadget_share(
    path: &Path,
    part_type: u32,
    share: Option<(usize, usize)>,
) -> Result<ParticleTable, IoError> {
    read_gadget_snapshot(path, Some(part_type), share, None, true).map(|(t, _)| t)
}

/// The files of the snapshot `path` names, and what their headers say.
pub fn open_gadget_hdf5(path: &Path) -> Result<GadgetHdf5, IoError> {
    let files = match snapshot_files(path) {
        Some(files) => files,
        None => vec![path.to_path_buf()],
    };
    let first = Hdf5File::open(&files[0])?;
    let root = first.root();
    let header = first.child_group(root, "Header");
    let owner = "group Header";
    let attr = |name: &str| match &header {
        Some(h) => first.attr_f64(h, owner, name),
        None => Ok(None),
    };
    // How many files the header says, and that they are all here.
    let declared = attr("NumFilesPerSnapshot")?
        .or(attr("NumFiles")?)
        .and_then(|v| v.first().copied())
        .unwrap_or(1.0);
    if !((1.0..=1e6).contains(&declared) && declared.fract() == 0.0) {
        return Err(first.err(format!(
            "Header attribute NumFilesPerSnapshot: {declared} is not a file count"
        )));
    }
    let declared = declared as usize;
    if declared > 1 || files.len() > 1 {
        let numbered_as = |k: usize| member_path(&files[0], k);
        if files.len() != declared || files.iter().enumerate().any(|(k, f)| *f != numbered_as(k)) {
            let missing: Vec<String> = (0..declared)
                .map(numbered_as)
                .filter(|f| !files.contains(f))
                .map(|f| f.display().to_string())
                .collect();
            return Err(first.err(if missing.is_empty() {
                format!(
                    "the header says the snapshot is {declared} file(s), but {} were found: {}",
                    files.len(),
                    list_names(&files)
                )
            } else {
                format!(
                    "the snapshot is {declared} files (Header NumFilesPerSnapshot), but {} \
                     {} missing",
                    missing.join(", "),
                    if missing.len() == 1 { "is" } else { "are" }
                )
            }));
        }
    }

    // Counts per file, checked against the header's totals.
    let mut per_file = Vec::with_capacity(files.len());
    let mut total_said: Option<Vec<u64>> = None;
    let mut fields: Vec<(u32, Vec<String>)> = Vec::new();
    for (k, file) in files.iter().enumerate() {
        let f = if k == 0 {
            None
        } else {
            Some(Hdf5File::open(file)?)
        };
        let f = f.as_ref().unwrap_or(&first);
        let counts = file_counts(f)?;
        if k == 0 {
            total_said = total_counts(f)?;
        }
        for (t, &n) in counts.iter().enumerate() {
            if n > 0 && !fields.iter().any(|(ft, _)| *ft == t as u32) {
                let gname = format!("PartType{t}");
                if let Some(g) = f.child_group(f.root(), &gname) {
                    fields.push((t as u32, f.member_names(&g, &gname)?));
                }
            }
        }
        per_file.push(counts);
    }
    fields.sort_by_key(|f| f.0);
    let types = per_file.iter().map(Vec::len).max().unwrap_or(0);
    let total: Vec<u64> = (0..types)
        .map(|t| {
            per_file
                .iter()
                .map(|c| c.get(t).copied().unwrap_or(0))
                .sum()
        })
        .collect();
    if let Some(said) = &total_said {
        for t in 0..said.len().max(total.len()) {
            let (s, n) = (
                said.get(t).copied().unwrap_or(0),
                total.get(t).copied().unwrap_or(0),
            );
            if s != n {
                return Err(first.err(format!(
                    "Header NumPart_Total says {s} particles of type {t}, but the {} file(s)' \
                     NumPart_ThisFile add up to {n}",
                    files.len()
                )));
            }
        }
    }

    let (code, code_name, kernel) = code_of(&first, header.as_ref(), &fields)?;
    let mut box_size = None;
    if let Some(size) = attr("BoxSize")? {
        box_size = Some(match size.as_slice() {
            &[s] => [s; 3],
            &[x, y, z] => [x, y, z],
            other => {
                return Err(first.err(format!(
                    "Header attribute BoxSize: expected 1 or 3 values, found {}",
                    other.len()
                )));
            }
        });
    }
    let scalar = |name: &str| attr(name).map(|v| v.and_then(|v| v.first().copied()));
    let units = units_of(&first, header.as_ref(), code)?;
    // A snapshot's time is the scale factor in cosmological runs: Gadget's
    // `Time` is, SWIFT's `Time` is the cosmic time (its `Scale-factor` is).
    let cosmological_swift = code == SphCode::Swift && units.as_ref().is_some_and(|u| u.comoving);
    let time = match (cosmological_swift, scalar("Scale-factor")?, scalar("Time")?) {
        (true, Some(a), _) => Some(a),
        (_, a, t) => t.or(a),
    };
    let mut redshift = scalar("Redshift")?;
    if redshift.is_none()
        && units.as_ref().is_some_and(|u| u.comoving)
        && let Some(a) = time.filter(|a| *a > 0.0)
    {
        redshift = Some(1.0 / a - 1.0);
    }
    let mass_table = attr("MassTable")?.unwrap_or_default();
    let cells = first.child_group(root, "Cells").is_some();
    Ok(GadgetHdf5 {
        files,
        per_file,
        total,
        code,
        code_name,
        kernel,
        box_size: box_size.filter(|b| b.iter().all(|v| *v > 0.0)),
        time,
        redshift,
        units,
        mass_table,
        fields,
        cells,
    })
}

/// Reads particle type `part_type` (default: gas when there is any, else
/// the first type with particles) of the snapshot `path` names: a file,
/// one file of a multi-file set, its stem or its directory.
///
/// Positions come from `Coordinates`. Every other numeric dataset of the
/// group with one entry per particle becomes a column named after it, in
/// name order: 1-D datasets as they are, N×3 datasets as `<name>_x`,
/// `<name>_y`, `<name>_z`, except `Velocities`, which gives `vx`, `vy`, `vz`.
/// Datasets of other shapes are skipped. Without a `Masses` dataset, a
/// non-zero `MassTable[part_type]` gives a constant `Masses` column. `speed`
/// = |v| comes last. `BoxSize` makes the table periodic over [0, BoxSize].
///
/// `share = Some((r, k))` reads rows `n·r/k .. n·(r+1)/k` of the type's `n`
/// (over all files); `region` keeps only the particles that can touch it,
/// measured periodically over the file's box when it gives no period of
/// its own and `file_box` is true.
/// The second value is a note saying what was read when it is worth one (a
/// default type, a region's count).
pub fn read_gadget_snapshot(
    path: &Path,
    part_type: Option<u32>,
    share: Option<(usize, usize)>,
    region: Option<&Region>,
    file_box: bool,
) -> Result<(ParticleTable, Option<String>), IoError> {
    let snap = open_gadget_hdf5(path)?;
    // The region over the file's periodic box (read once, with the rest of
    // the headers).
    let region = region.map(|r| match (r.period, snap.box_size) {
        (None, Some(b)) if file_box => Region {
            period: Some(([0.0; 3], b)),
            ..*r
        },
        _ => *r,
    });
    let region = region.as_ref();
    let t = match part_type {
        Some(t) => t,
        None => default_part_type(&snap.total),
    };
    let n_total = snap.total.get(t as usize).copied().unwrap_or(0);
    if n_total == 0 {
        return Err(missing_part_type(&snap.files[0], t, &snap.total));
    }
    let gname = format!("PartType{t}");

    // The rows of each file to read.
    let counts: Vec<u64> = snap
        .per_file
        .iter()
        .map(|c| c.get(t as usize).copied().unwrap_or(0))
        .collect();
    let mut pieces: Vec<(usize, Range<usize>)> = Vec::new();
    let mut via_cells = false;
    if let Some(region) = region.filter(|_| share.is_none())
        && snap.cells
        && let Some(p) = cells::pieces(&snap, t, region)?
    {
        pieces = p;
        via_cells = true;
    }
    let wanted = share.map(|(r, k)| super::share_rows(n_total as usize, r, k));
    if !via_cells {
        let mut start = 0usize;
        for (k, &n) in counts.iter().enumerate() {
            let n = n as usize;
            let file_rows = start..start + n;
            let keep = match &wanted {
                Some(w) => w.start.max(file_rows.start)..w.end.min(file_rows.end),
                None => file_rows.clone(),
            };
            if keep.start < keep.end {
                pieces.push((k, keep.start - start..keep.end - start));
            }
            start += n;
        }
        // An empty share still has the type's columns (empty): the first
        // file holding the type gives them.
        if pieces.is_empty()
            && let Some(k) = counts.iter().position(|&n| n > 0)
        {
            pieces.push((k, 0..0));
        }
    }

    let mut table = ParticleTable::default();
    let mut reader = Rows::default();
    let mut read_rows = 0usize;
    for (k, rows) in pieces {
        let f = Hdf5File::open(&snap.files[k])?;
        let Some(group) = f.child_group(f.root(), &gname) else {
            return Err(f.err(format!(
                "no group {gname}, though the header counts {} particles of type {t} in this file",
                counts[k]
            )));
        };
        read_rows += reader.read(&f, &group, &gname, rows, region, &mut table)?;
    }
    if !reader.seen_masses
        && let Some(&mass) = snap.mass_table.get(t as usize)
        && mass != 0.0
    {
        let count = table.positions.len();
        table
            .columns
            .push(("Masses".into(), vec![mass as f32; count]));
    }
    table.time = snap.time;
    table.redshift = snap.redshift;
    table.units = snap.units.clone();
    if let Some(b) = snap.box_size {
        table.domain = Some(([0.0; 3], b));
        table.periodic = true;
    }
    let code = if snap.code == SphCode::Arepo && t != 0 {
        // Only AREPO's gas are cells; its other types are plain particles.
        SphCode::Gadget
    } else {
        snap.code
    };
    table.sph = Some(SphConvention {
        code,
        kernel: snap.kernel.clone(),
    });
    table.derive_speed("vx", "vy", "vz");
    if let Some(w) = wanted {
        table.rows = Some((w.start, n_total as usize));
    }
    let mut said = Vec::new();
    if part_type.is_none() {
        said.push(format!(
            "{} {gname} (pick another with --part-type)",
            snap.code_name
        ));
    }
    if snap.files.len() > 1 {
        said.push(format!("{} files", snap.files.len()));
    }
    if region.is_some() {
        said.push(format!(
            "--region: {} of {n_total} particles kept ({read_rows} read{})",
            table.len(),
            if via_cells {
                ", only the cells that overlap"
            } else {
                ""
            }
        ));
    }
    Ok((table, (!said.is_empty()).then(|| said.join("; "))))
}

/// Reads rows of a type's group, file after file, into one table: the
/// dataset names come from the first file, and every later file must hold
/// them too.
#[derive(Default)]
struct Rows {
    /// (dataset name, components) of the columns, fixed by the first file.
    layout: Option<Vec<(String, usize)>>,
    seen_masses: bool,
}

impl Rows {
    /// Appends rows `rows` of `group` (`gname`) to `table`, keeping those
    /// in `region`; returns how many rows were read.
    fn read(
        &mut self,
        f: &Hdf5File,
        group: &hdf5_metno::Group,
        gname: &str,
        rows: Range<usize>,
        region: Option<&Region>,
        table: &mut ParticleTable,
    ) -> Result<usize, IoError> {
        let coords_name = format!("{gname}/Coordinates");
        let coords = f.required_dataset(group, "Coordinates", &coords_name)?;
        let shape = coords.shape();
        if shape.len() != 2 || shape[1] != 3 {
            return Err(f.err(format!(
                "dataset {coords_name}: expected an N×3 array, found shape {}",
                shape_text(&shape)
            )));
        }
        let n = shape[0];
        let rows = rows.start.min(n)..rows.end.min(n);
        if self.layout.is_none() {
            let mut layout = Vec::new();
            for name in f.member_names(group, gname)? {
                if name == "Coordinates" {
                    continue;
                }
                let Some(ds) = f.child_dataset(group, &name) else {
                    continue;
                };
                let s = ds.shape();
                let per_particle = matches!(s.as_slice(), [_] | [_, 3]);
                if per_particle && is_numeric(&ds) {
                    layout.push((name, s.get(1).copied().unwrap_or(1)));
                }
            }
            self.seen_masses = layout.iter().any(|(n, _)| n == "Masses");
            for (name, comps) in &layout {
                for c in column_names(name, *comps) {
                    table.columns.push((c, Vec::new()));
                }
            }
            self.layout = Some(layout);
        }
        let layout = self.layout.clone().unwrap_or_default();
        let mut datasets = Vec::with_capacity(layout.len());
        for (name, comps) in &layout {
            let full = format!("{gname}/{name}");
            let ds = f.child_dataset(group, name).ok_or_else(|| {
                f.err(format!(
                    "dataset {full} is missing (the snapshot's first file has it)"
                ))
            })?;
            let s = ds.shape();
            if s.first() != Some(&n) || s.get(1).copied().unwrap_or(1) != *comps {
                return Err(f.length_mismatch(
                    &full,
                    s.first().copied().unwrap_or(0),
                    &coords_name,
                    n,
                ));
            }
            datasets.push((ds, full, *comps));
        }

        // Chunks when a region filters (memory follows what is kept), else
        // the rows at once.
        let step = if region.is_some() {
            CHUNK
        } else {
            rows.len().max(1)
        };
        let mut at = rows.start;
        while at < rows.end {
            let chunk = at..(at + step).min(rows.end);
            at = chunk.end;
            let (_, pos) = f.read_f64_rows(&coords, &coords_name, chunk.clone(), 1)?;
            let keep: Option<Vec<bool>> = region.map(|r| {
                pos.chunks_exact(3)
                    .map(|p| r.contains([p[0], p[1], p[2]]))
                    .collect()
            });
            let kept = |i: usize| keep.as_ref().is_none_or(|k| k[i]);
            table.positions.extend(
                pos.chunks_exact(3)
                    .enumerate()
                    .filter(|(i, _)| kept(*i))
                    .map(|(_, p)| [p[0], p[1], p[2]]),
            );
            let mut col = 0;
            for (ds, full, comps) in &datasets {
                let values = f.read_f32_rows(ds, full, chunk.clone(), 1)?.data;
                for c in 0..*comps {
                    let out = &mut table.columns[col + c].1;
                    out.extend(
                        values
                            .iter()
                            .skip(c)
                            .step_by(*comps)
                            .enumerate()
                            .filter(|(i, _)| kept(*i))
                            .map(|(_, v)| *v),
                    );
                }
                col += comps;
            }
        }
        Ok(rows.len())
    }
}

/// The columns a dataset gives: itself, or its three components.
fn column_names(name: &str, comps: usize) -> Vec<String> {
    match (name, comps) {
        (_, 1) => vec![name.to_string()],
        ("Velocities", _) => vec!["vx".into(), "vy".into(), "vz".into()],
        _ => ["x", "y", "z"]
            .iter()
            .take(comps)
            .map(|a| format!("{name}_{a}"))
            .collect(),
    }
}

/// A file's `NumPart_ThisFile`, else the `Coordinates` lengths of its
/// `PartType<N>` groups.
fn file_counts(f: &Hdf5File) -> Result<Vec<u64>, IoError> {
    let root = f.root();
    if let Some(h) = f.child_group(root, "Header")
        && let Some(v) = f.attr_f64(&h, "group Header", "NumPart_ThisFile")?
    {
        return counts_from(f, "NumPart_ThisFile", &v);
    }
    let mut counts = Vec::new();
    for name in f.member_names(root, "/")? {
        if let Some(t) = numbered(&name, "PartType").filter(|t| *t < 64)
            && let Some(g) = f.child_group(root, &name)
            && let Some(ds) = f.child_dataset(&g, "Coordinates")
        {
            let t = t as usize;
            if counts.len() <= t {
                counts.resize(t + 1, 0);
            }
            counts[t] = ds.shape().first().copied().unwrap_or(0) as u64;
        }
    }
    Ok(counts)
}

/// `NumPart_Total` + 2³² × `NumPart_Total_HighWord`, when the header says.
fn total_counts(f: &Hdf5File) -> Result<Option<Vec<u64>>, IoError> {
    let Some(h) = f.child_group(f.root(), "Header") else {
        return Ok(None);
    };
    let owner = "group Header";
    let Some(low) = f.attr_f64(&h, owner, "NumPart_Total")? else {
        return Ok(None);
    };
    let mut total = counts_from(f, "NumPart_Total", &low)?;
    if let Some(high) = f.attr_f64(&h, owner, "NumPart_Total_HighWord")? {
        let high = counts_from(f, "NumPart_Total_HighWord", &high)?;
        for (t, hw) in high.iter().enumerate() {
            if *hw > 0 {
                let v = total.get(t).copied().unwrap_or(0);
                let sum = hw
                    .checked_mul(1 << 32)
                    .and_then(|h| h.checked_add(v))
                    .ok_or_else(|| {
                        f.err("Header NumPart_Total_HighWord: the count overflows".to_string())
                    })?;
                if t >= total.len() {
                    total.resize(t + 1, 0);
                }
                total[t] = sum;
            }
        }
    }
    Ok(Some(total))
}

/// Counts from an attribute's values: whole, non-negative, and each at most
/// what the file could hold (a byte per particle, a generous bound).
fn counts_from(f: &Hdf5File, name: &str, v: &[f64]) -> Result<Vec<u64>, IoError> {
    if v.len() > 64 {
        return Err(f.err(format!(
            "Header attribute {name}: {} entries, more than there are particle types",
            v.len()
        )));
    }
    v.iter()
        .enumerate()
        .map(|(t, &c)| {
            if c >= 0.0 && c.fract() == 0.0 && c < 2f64.powi(63) {
                Ok(c as u64)
            } else {
                Err(f.err(format!(
                    "Header attribute {name}[{t}]: {c} is not a particle count"
                )))
            }
        })
        .collect()
}

/// Which code wrote the snapshot (see the module docs), its name, and the
/// kernel SWIFT records.
fn code_of(
    f: &Hdf5File,
    header: Option<&hdf5_metno::Group>,
    fields: &[(u32, Vec<String>)],
) -> Result<(SphCode, &'static str, Option<String>), IoError> {
    let root = f.root();
    let scheme = f.child_group(root, "HydroScheme");
    let code_attr = match header {
        Some(h) => f.attr_text(h, "group Header", "Code")?,
        None => None,
    };
    let swift_units = f.child_group(root, "Units").is_some_and(|u| {
        u.attr_names()
            .is_ok_and(|n| n.iter().any(|a| a.contains("(U_L)")))
    });
    let says = |s: &str| {
        code_attr
            .as_deref()
            .is_some_and(|c| c.to_ascii_uppercase().contains(s))
    };
    if scheme.is_some() || says("SWIFT") || swift_units {
        let kernel = match &scheme {
            Some(s) => f.attr_text(s, "group HydroScheme", "Kernel function")?,
            None => None,
        };
        return Ok((SphCode::Swift, "SWIFT", kernel));
    }
    let header_has = |name: &str| {
        header.is_some_and(|h| h.attr_names().is_ok_and(|n| n.iter().any(|a| a == name)))
    };
    if header_has("GIZMO_version") || says("GIZMO") {
        return Ok((SphCode::Gadget, "GIZMO", None));
    }
    let voronoi = f.child_group(root, "Config").is_some_and(|c| {
        c.attr_names()
            .is_ok_and(|n| n.iter().any(|a| a == "VORONOI"))
    });
    let gas_cells = fields.iter().any(|(t, names)| {
        *t == 0
            && names.iter().any(|n| n == "Density")
            && names.iter().any(|n| n == "Masses")
            && !names.iter().any(|n| n.starts_with("SmoothingLength"))
    });
    if voronoi || says("AREPO") || gas_cells {
        return Ok((SphCode::Arepo, "AREPO", None));
    }
    let gadget4 = f.child_group(root, "Parameters").is_some() || says("GADGET-4");
    Ok((
        SphCode::Gadget,
        if gadget4 { "Gadget-4" } else { "Gadget" },
        None,
    ))
}

/// The unit system the file states (see the module docs).
fn units_of(
    f: &Hdf5File,
    header: Option<&hdf5_metno::Group>,
    code: SphCode,
) -> Result<Option<Units>, IoError> {
    let root = f.root();
    let scalar = |g: &hdf5_metno::Group, owner: &str, name: &str| f.attr_scalar(g, owner, name);
    if code == SphCode::Swift {
        let Some(u) = f
            .child_group(root, "Units")
            .or(f.child_group(root, "InternalCodeUnits"))
        else {
            return Ok(None);
        };
        let owner = "group Units";
        let (Some(l), Some(m), Some(t)) = (
            scalar(&u, owner, "Unit length in cgs (U_L)")?,
            scalar(&u, owner, "Unit mass in cgs (U_M)")?,
            scalar(&u, owner, "Unit time in cgs (U_t)")?,
        ) else {
            return Ok(None);
        };
        let comoving = match f.child_group(root, "Cosmology") {
            Some(c) => scalar(&c, "group Cosmology", "Cosmological run")?.is_some_and(|v| v != 0.0),
            None => false,
        };
        return checked_units(f, l, m, l / t, "SWIFT Units group", comoving, None);
    }
    // Gadget-4 keeps them in Parameters, AREPO and others in Header.
    for (name, group) in [
        ("Header", header.cloned()),
        ("Parameters", f.child_group(root, "Parameters")),
    ] {
        let Some(g) = group else { continue };
        let owner = format!("group {name}");
        let (Some(l), Some(m), Some(v)) = (
            scalar(&g, &owner, "UnitLength_in_cm")?,
            scalar(&g, &owner, "UnitMass_in_g")?,
            scalar(&g, &owner, "UnitVelocity_in_cm_per_s")?,
        ) else {
            continue;
        };
        let hubble = match header {
            Some(h) => scalar(h, "group Header", "HubbleParam")?,
            None => None,
        };
        let omega = match header {
            Some(h) => scalar(h, "group Header", "Omega0")?,
            None => None,
        };
        let comoving = match f.child_group(root, "Parameters") {
            Some(p) => match scalar(&p, "group Parameters", "ComovingIntegrationOn")? {
                Some(c) => c != 0.0,
                None => omega.is_some_and(|o| o > 0.0),
            },
            None => omega.is_some_and(|o| o > 0.0),
        };
        let source = format!("{name} UnitLength_in_cm, UnitMass_in_g, UnitVelocity_in_cm_per_s");
        let hubble = hubble.filter(|h| *h > 0.0 && comoving);
        return checked_units(f, l, m, v, &source, comoving, hubble);
    }
    Ok(None)
}

/// Units from positive finite factors; anything else is an error naming
/// where they came from.
fn checked_units(
    f: &Hdf5File,
    length_cm: f64,
    mass_g: f64,
    velocity_cm_s: f64,
    source: &str,
    comoving: bool,
    hubble: Option<f64>,
) -> Result<Option<Units>, IoError> {
    for (what, v) in [
        ("length", length_cm),
        ("mass", mass_g),
        ("velocity", velocity_cm_s),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(f.err(format!(
                "{source}: the {what} unit is {v}, not a positive number"
            )));
        }
    }
    Ok(Some(Units {
        length_cm,
        mass_g,
        velocity_cm_s,
        source: source.to_string(),
        comoving,
        hubble,
    }))
}

/// File names for messages.
fn list_names(files: &[PathBuf]) -> String {
    let names: Vec<String> = files
        .iter()
        .map(|f| {
            f.file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default()
        })
        .collect();
    names.join(", ")
}
