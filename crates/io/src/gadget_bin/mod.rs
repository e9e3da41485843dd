//! Gadget binary snapshots (the "unformatted" output of Gadget-1/2/3,
//! GIZMO and the initial-condition generators that write their format),
//! in format 1 or 2, either byte order, one file or several.
//!
//! # Layout
//!
//! A file is a sequence of Fortran unformatted records, `n | n bytes | n`
//! with `n` a 4-byte integer, one per block. The first block is the
//! 256-byte header: `npart[6]` (u32, this file's particles per type),
//! `mass[6]` (f64, the `MassTable`: one mass for every particle of a type,
//! or 0 when the type's masses are in the `MASS` block), `time` (the scale
//! factor in cosmological runs), `redshift`, two flags, `npartTotal[6]`
//! (u32, the whole snapshot's counts), `flag_cooling`, `num_files`,
//! `BoxSize`, `Omega0`, `OmegaLambda`, `HubbleParam`, two flags,
//! `npartTotalHighWord[6]` (the counts' upper 32 bits), then padding.
//!
//! - **Format 2** puts a label record before every block: `8 | "POS " |
//!   nextblock | 8`, a 4-character name and the next record's length plus
//!   8 (ignored here: the block's own markers are checked instead). Blocks
//!   may come in any order.
//! - **Format 1** has no labels; the blocks follow Gadget-2's order:
//!   `POS`, `VEL`, `ID`, `MASS` (only when a type with particles has a
//!   mass-table entry of 0), then for gas `U`, `RHO`, `NE` and `NH` (only
//!   when the header's `flag_cooling` is set) and `HSML`, the gas blocks
//!   only as long as the records have their size. Records after those are
//!   listed as `record N` and not read.
//!
//! The byte order comes from the first marker: 256 (format 1's header) or
//! 8 (format 2's label record) as little-endian, or byte-swapped as
//! big-endian. Markers are read as unsigned, so blocks up to 4 GiB work.
//!
//! Per-particle blocks hold the particles type by type (0 gas, 1 dark
//! matter, …, 5; see [`crate::snapshot`]), float32 values, or float64 when
//! the block's size says so (8 bytes a value; likewise 8-byte IDs):
//! `POS` and `VEL` three values a particle for every type, `ID` one, `MASS`
//! one for the types with particles and a zero mass-table entry, and the
//! gas blocks `U`, `RHO`, `HSML` (also `NE`, `NH`) one per gas particle.
//! `POT` holds every type. A gas block whose size fits every type instead
//! is read that way (some writers store `HSML` for all particles).
//!
//! A snapshot written in `k` pieces is the files `stem.0` … `stem.(k-1)`
//! (`k` = `num_files`), each with its own header and blocks; a type's
//! particles are those of file 0, then file 1, and so on.
//!
//! # What is read
//!
//! [`read_gadget_binary`] reads one particle type into a [`ParticleTable`]:
//! positions from `POS` (as f64), then the columns `Masses` (the `MASS`
//! block, or the mass table's constant when it is not 0), `ParticleIDs`
//! (converted to f32, so IDs above 2²⁴ lose digits), `vx`, `vy`, `vz`
//! (`VEL`), for gas `InternalEnergy` (`U`, entropy in initial conditions
//! whose header flags `flag_entropy_instead_u`), `Density` (`RHO`) and
//! `SmoothingLength` (`HSML`), then other per-particle blocks in file
//! order: `NE` as `ElectronAbundance`, `NH` as `NeutralHydrogenAbundance`,
//! `POT` as `Potential`, and format-2 blocks with other labels as columns
//! named after the label (`ACCE` → `ACCE_x`, `ACCE_y`, `ACCE_z`) when
//! their size fits one or three values per particle of every type, or of
//! the gas (tried in that order). Blocks that fit neither are skipped. A
//! column must be in every file that holds particles of the type; `speed`
//! = |v| comes last. The header's `time` and `redshift` set the table's,
//! a positive `BoxSize` the domain `[0, BoxSize]³` (periodic). The format
//! states no units, so `units` stays `None`; the SPH convention is
//! Gadget's (`HSML` is the kernel's support radius).
//!
//! A rank's share of the rows or a [`Region`] limits what is read: blocks
//! are streamed in chunks of [`CHUNK`] particles with seeks, so the memory
//! a read needs is bounded by the particles kept, not by the files.
//!
//! # Errors
//!
//! Every failure is an [`IoError`] naming the file, and the block and
//! header field where it applies: a file too short for a record its
//! marker announces, record markers that disagree, a header record that is
//! not 256 bytes, a block whose size does not fit its particles, a missing
//! file of a set, counts per type that do not add up to `npartTotal`, a
//! `num_files` that contradicts the files present, a type that is not
//! 0–5 or has no particles. Sizes are checked against the file's length
//! before anything is allocated, so bad input never panics and never
//! allocates more than the file could fill.

use std::io::{Read, Seek};
use std::path::{Path, PathBuf};

use crate::snapshot::{Region, default_part_type, missing_part_type};
use crate::{IoError, ParticleTable, SphCode, SphConvention};

mod files;
mod layout;

use layout::{Field, Kind, Layout, Source, classify, column_rank, scan};

/// Particles per chunk when streaming a block.
pub const CHUNK: usize = 65_536;

/// The header of a Gadget binary file.
#[derive(Clone, Debug, PartialEq)]
pub struct GadgetHeader {
    /// Particles of each type in this file.
    pub npart: [u32; 6],
    /// The mass table: the mass of every particle of a type, or 0 when the
    /// `MASS` block holds them.
    pub mass: [f64; 6],
    /// Simulation time (the scale factor in cosmological runs).
    pub time: f64,
    pub redshift: f64,
    /// Particles of each type in the whole snapshot: `npartTotal` plus
    /// `npartTotalHighWord` × 2³².
    pub npart_total: [u64; 6],
    /// Files of the snapshot as the header states it (0 when it states 0
    /// or a negative number, as some single-file writers do).
    pub num_files: u32,
    pub box_size: f64,
    pub omega0: f64,
    pub omega_lambda: f64,
    pub hubble: f64,
}

/// What [`open_gadget_binary`] finds: the files of a snapshot, their
/// format and counts.
#[derive(Clone, Debug, PartialEq)]
pub struct GadgetBinary {
    /// The files in order `.0`, `.1`, … (one entry for a single file).
    pub files: Vec<PathBuf>,
    /// 1 or 2.
    pub format: u8,
    pub big_endian: bool,
    /// The first file's header; its `npart_total` is checked against the
    /// sum over the files.
    pub header: GadgetHeader,
    /// `npart` of each file.
    pub per_file: Vec<[u32; 6]>,
    /// The first file's block labels in order, without trailing blanks
    /// (format 1: the labels inferred from Gadget-2's order).
    pub blocks: Vec<String>,
    /// Whether positions are stored as float64.
    pub double_positions: bool,
}

/// Whether the first bytes look like a Gadget binary file (either format,
/// either byte order): a record marker of 256 (format 1) or a format-2
/// label record followed by a 256-byte record, with the header record's
/// trailing marker in place (so at least 264 or 280 bytes are needed).
pub fn sniff_gadget_binary(head: &[u8]) -> bool {
    layout::sniff(head)
}

/// The files of the snapshot `path` names: the file itself for a single
/// file, or all of `stem.0` … `stem.(num_files-1)` when `path` is one of
/// them or is the stem (which is not a file itself).
///
/// Reads the header of `path` (or `stem.0`) for `num_files`. Fails when a
/// file of the set is missing (the error names it), when `num_files` is
/// above 1 but the name has no file number, or when it is 0 or negative
/// while other numbered files lie next to it.
pub fn gadget_binary_files(path: &Path) -> Result<Vec<PathBuf>, IoError> {
    files::snapshot_files(path)
}

/// Reads and checks every file's header and block layout (record markers
/// and labels only, no particle data): the sizes of the blocks, that every
/// file states the same `num_files`, and that the files' counts add up to
/// the first header's `npartTotal` per type. A single file whose totals are
/// all 0 (some initial-condition writers leave them unset) counts as
/// holding its own particles.
pub fn open_gadget_binary(path: &Path) -> Result<GadgetBinary, IoError> {
    let files = gadget_binary_files(path)?;
    let layouts = scan_all(&files)?;
    let totals = check_set(&files, &layouts, false)?;
    let first = &layouts[0];
    let pos = field_of(first, &files[0], Kind::Positions)?;
    Ok(GadgetBinary {
        format: first.format,
        big_endian: first.endian == layout::Endian::Big,
        header: GadgetHeader {
            npart_total: totals,
            ..first.header.clone()
        },
        per_file: layouts.iter().map(|l| l.header.npart).collect(),
        blocks: first.blocks.iter().map(|b| b.label.clone()).collect(),
        double_positions: pos.is_some_and(|f| f.width == 8),
        files,
    })
}

/// Reads particle type `part_type` (`None`: [`default_part_type`] of the
/// totals) of the whole snapshot `path` names (see
/// [`gadget_binary_files`]) into a table; see the module documentation for
/// its columns.
///
/// `share = Some((r, k))` reads only rows `n·r/k .. n·(r+1)/k` of the `n`
/// particles of the type over all files and sets `rows` to `(start, n)`.
/// A `region` keeps only the particles it [contains](Region::contains)
/// (`rows` is then `None`).
pub fn read_gadget_binary(
    path: &Path,
    part_type: Option<u32>,
    share: Option<(usize, usize)>,
    region: Option<&Region>,
) -> Result<ParticleTable, IoError> {
    let files = gadget_binary_files(path)?;
    let layouts = scan_all(&files)?;
    let totals = check_set(&files, &layouts, false)?;
    let want = Want {
        part_type,
        share,
        region,
    };
    read_set(&files, &layouts, totals, &want, |i| Source::open(&files[i]))
}

/// [`read_gadget_binary`] of one file's bytes, from `reader`'s position to
/// its end (data that is not a file; the fuzz target); `name` labels
/// errors. A piece of a multi-file snapshot (`num_files` > 1) reads as its
/// own particles, without the check of the totals.
pub fn read_gadget_binary_from<R: Read + Seek>(
    reader: R,
    name: &Path,
    part_type: Option<u32>,
) -> Result<ParticleTable, IoError> {
    let mut src = Source::from_reader(reader, name)?;
    let layout = scan(&mut src, false)?;
    validate(&layout, name)?;
    let layouts = [layout];
    let files = [name.to_path_buf()];
    let mut src = Some(src);
    let totals = check_set(&files, &layouts, true)?;
    let want = Want {
        part_type,
        share: None,
        region: None,
    };
    read_set(&files, &layouts, totals, &want, |_| {
        src.take()
            .ok_or_else(|| IoError::format(name, "read twice"))
    })
}

/// What a read keeps.
struct Want<'a> {
    part_type: Option<u32>,
    share: Option<(usize, usize)>,
    region: Option<&'a Region>,
}

/// The layout of every file, with the sizes of their blocks checked.
fn scan_all(files: &[PathBuf]) -> Result<Vec<Layout>, IoError> {
    files
        .iter()
        .map(|f| {
            let layout = scan(&mut Source::open(f)?, false)?;
            validate(&layout, f)?;
            Ok(layout)
        })
        .collect()
}

/// Checks that every known block's size fits its particles.
fn validate(layout: &Layout, path: &Path) -> Result<(), IoError> {
    for block in &layout.blocks {
        classify(block, &layout.header.npart, &layout.header.mass)
            .map_err(|m| IoError::format(path, m))?;
    }
    Ok(())
}

/// The first block of `kind` in a file.
fn field_of(layout: &Layout, path: &Path, kind: Kind) -> Result<Option<Field>, IoError> {
    Ok(fields(layout, path)?.into_iter().find(|f| f.kind == kind))
}

/// The per-particle blocks of a file in file order.
fn fields(layout: &Layout, path: &Path) -> Result<Vec<Field>, IoError> {
    let mut out = Vec::new();
    for block in &layout.blocks {
        let field = classify(block, &layout.header.npart, &layout.header.mass)
            .map_err(|m| IoError::format(path, m))?;
        out.extend(field);
    }
    Ok(out)
}

/// Checks `num_files` and the totals of a set of files; returns the
/// particles per type of the snapshot. `piece` accepts one file of a
/// larger set (the memory reader), whose own counts are then the totals.
fn check_set(files: &[PathBuf], layouts: &[Layout], piece: bool) -> Result<[u64; 6], IoError> {
    let (Some(first), Some(path)) = (layouts.first(), files.first()) else {
        return Ok([0; 6]);
    };
    let err = |p: &Path, m: String| IoError::format(p, format!("block HEAD: {m}"));
    let nf = first.num_files;
    if files.len() > 1 && nf <= 0 {
        return Err(err(
            path,
            format!(
                "num_files is {nf}, but the snapshot has {} files",
                files.len()
            ),
        ));
    }
    if files.len() == 1 && nf > 1 && !piece {
        return Err(err(
            path,
            format!("num_files is {nf}, but the snapshot has only this file"),
        ));
    }
    for (f, l) in files.iter().zip(layouts).skip(1) {
        if l.num_files != nf {
            return Err(err(
                f,
                format!(
                    "num_files is {}, but {} says {nf}",
                    l.num_files,
                    path.display()
                ),
            ));
        }
    }
    let mut sums = [0u64; 6];
    for l in layouts {
        for (s, &n) in sums.iter_mut().zip(&l.header.npart) {
            *s = s.saturating_add(u64::from(n));
        }
    }
    let totals = first.header.npart_total;
    if files.len() == 1 && (piece && nf > 1 || totals == [0; 6]) {
        return Ok(sums);
    }
    for t in 0..6 {
        if sums[t] != totals[t] {
            let holds = match files.len() {
                1 => "the file holds".to_string(),
                k => format!("the {k} files hold"),
            };
            return Err(err(
                path,
                format!(
                    "npartTotal[{t}] (with npartTotalHighWord) says type {} has {} particles, \
                     but {holds} {}",
                    crate::part_type_label(t as u32),
                    totals[t],
                    sums[t]
                ),
            ));
        }
    }
    Ok(totals)
}

/// Rows `n·r/k .. n·(r+1)/k`, as for the HDF5 readers.
fn share_rows(n: u64, r: usize, k: usize) -> std::ops::Range<u64> {
    let k = k.max(1);
    let at = |r: usize| (u128::from(n) * r.min(k) as u128 / k as u128) as u64;
    at(r)..at(r.saturating_add(1))
}

/// A column of the table and where each file keeps it.
struct Column {
    /// The first file's block, which fixes the column's place and names.
    field: Field,
    /// Per file: the block, or the mass table's constant (`Masses`).
    sources: Vec<Option<ColumnSource>>,
}

#[derive(Clone)]
enum ColumnSource {
    Block(Field),
    Constant(f32),
}

/// The column names a field gives.
fn column_names(field: &Field) -> Vec<String> {
    match (field.kind, field.comps) {
        (Kind::Velocities, _) => vec!["vx".into(), "vy".into(), "vz".into()],
        (_, 3) => ["x", "y", "z"]
            .iter()
            .map(|a| format!("{}_{a}", field.name))
            .collect(),
        _ => vec![field.name.clone()],
    }
}

/// Reads the wanted rows of one type from a set of files; `open(i)` opens
/// file `i`.
fn read_set<S: Read + Seek>(
    files: &[PathBuf],
    layouts: &[Layout],
    totals: [u64; 6],
    want: &Want,
    mut open: impl FnMut(usize) -> Result<Source<S>, IoError>,
) -> Result<ParticleTable, IoError> {
    let name = &files[0];
    let t = want.part_type.unwrap_or_else(|| default_part_type(&totals));
    if t > 5 {
        return Err(IoError::format(
            name,
            format!("there is no particle type {t}: Gadget files hold types 0 to 5"),
        ));
    }
    let ti = t as usize;
    let n = totals[ti];
    if n == 0 {
        return Err(missing_part_type(name, t, &totals));
    }
    let wanted = match want.share {
        Some((r, k)) => share_rows(n, r, k),
        None => 0..n,
    };

    // The blocks of each file that hold the type; files without its
    // particles play no part.
    let holding: Vec<usize> = (0..layouts.len())
        .filter(|&i| layouts[i].header.npart[ti] > 0)
        .collect();
    let mut per_file: Vec<Vec<Field>> = vec![Vec::new(); layouts.len()];
    for &i in &holding {
        per_file[i] = fields(&layouts[i], &files[i])?
            .into_iter()
            .filter(|f| f.types[ti])
            .collect();
        if !per_file[i].iter().any(|f| f.kind == Kind::Positions) {
            return Err(IoError::format(
                &files[i],
                format!(
                    "no POS block for the {} particles of type {} (blocks: {})",
                    layouts[i].header.npart[ti],
                    crate::part_type_label(t),
                    block_list(&layouts[i])
                ),
            ));
        }
    }
    let columns = plan_columns(&holding, layouts, &per_file, ti);

    // Everything below is bounded by what the POS blocks hold, which fit
    // their files; a region keeps an unknown part of it.
    let mut out = Output {
        positions: Vec::new(),
        values: columns
            .iter()
            .flat_map(|c| column_names(&c.field))
            .map(|_| Vec::new())
            .collect(),
        region: want.region,
    };
    if want.region.is_none() {
        let count = usize::try_from(wanted.end - wanted.start).unwrap_or(0);
        out.positions.reserve(count);
        for v in &mut out.values {
            v.reserve(count);
        }
    }
    let mut first_row = 0u64;
    for (i, layout) in layouts.iter().enumerate() {
        let count = u64::from(layout.header.npart[ti]);
        let rows = first_row..first_row + count;
        first_row += count;
        let (lo, hi) = (wanted.start.max(rows.start), wanted.end.min(rows.end));
        if lo >= hi {
            continue;
        }
        let mut src = open(i)?;
        let Some(pos) = per_file[i].iter().find(|f| f.kind == Kind::Positions) else {
            continue;
        };
        let sources: Vec<Option<ColumnSource>> =
            columns.iter().map(|c| c.sources[i].clone()).collect();
        let local = (lo - rows.start)..(hi - rows.start);
        stream(&mut src, layout, ti, local, pos, &sources, &mut out)?;
    }

    let header = &layouts[0].header;
    let mut table = ParticleTable {
        positions: out.positions,
        columns: columns
            .iter()
            .flat_map(|c| column_names(&c.field))
            .zip(out.values)
            .collect(),
        time: Some(header.time),
        redshift: Some(header.redshift),
        units: None,
        rows: match (want.share, want.region) {
            (Some(_), None) => Some((
                usize::try_from(wanted.start).unwrap_or(usize::MAX),
                usize::try_from(n).unwrap_or(usize::MAX),
            )),
            _ => None,
        },
        sph: Some(SphConvention {
            code: SphCode::Gadget,
            kernel: None,
        }),
        ..ParticleTable::default()
    };
    if header.box_size > 0.0 && header.box_size.is_finite() {
        table.domain = Some(([0.0; 3], [header.box_size; 3]));
        table.periodic = true;
    }
    table.derive_speed("vx", "vy", "vz");
    Ok(table)
}

/// The columns of type `ti`: those the first holding file has (`Masses`
/// also from the mass table) that every holding file has, in the
/// documented order, each label and name once.
fn plan_columns(
    holding: &[usize],
    layouts: &[Layout],
    per_file: &[Vec<Field>],
    ti: usize,
) -> Vec<Column> {
    let Some(&first) = holding.first() else {
        return Vec::new();
    };
    let source = |i: usize, field: &Field| -> Option<ColumnSource> {
        if let Some(f) = per_file[i].iter().find(|f| f.label == field.label) {
            return Some(ColumnSource::Block(f.clone()));
        }
        let mass = layouts[i].header.mass[ti];
        (field.kind == Kind::Masses && mass != 0.0).then_some(ColumnSource::Constant(mass as f32))
    };
    let mut candidates: Vec<Field> = per_file[first]
        .iter()
        .filter(|f| f.kind != Kind::Positions)
        .cloned()
        .collect();
    if !candidates.iter().any(|f| f.kind == Kind::Masses) {
        // A stand-in for the mass table's constant.
        candidates.push(Field {
            kind: Kind::Masses,
            label: "MASS".into(),
            name: "Masses".into(),
            types: [true; 6],
            comps: 1,
            width: 4,
            offset: 0,
            size: 0,
        });
    }
    candidates.sort_by_key(column_rank);
    let mut names: Vec<String> = Vec::new();
    let mut labels: Vec<String> = Vec::new();
    let mut columns = Vec::new();
    for field in candidates {
        let sources: Vec<Option<ColumnSource>> = (0..layouts.len())
            .map(|i| {
                if holding.contains(&i) {
                    source(i, &field)
                } else {
                    None
                }
            })
            .collect();
        let everywhere = holding.iter().all(|&i| sources[i].is_some());
        let new_names = column_names(&field);
        if !everywhere
            || labels.contains(&field.label)
            || new_names.iter().any(|n| names.contains(n))
        {
            continue;
        }
        labels.push(field.label.clone());
        names.extend(new_names);
        columns.push(Column { field, sources });
    }
    columns
}

/// The table being filled.
struct Output<'a> {
    positions: Vec<[f64; 3]>,
    /// One vector per column name, in order.
    values: Vec<Vec<f32>>,
    region: Option<&'a Region>,
}

/// Reads rows `local` of type `ti` of one file, chunk by chunk.
fn stream<S: Read + Seek>(
    src: &mut Source<S>,
    layout: &Layout,
    ti: usize,
    local: std::ops::Range<u64>,
    pos: &Field,
    sources: &[Option<ColumnSource>],
    out: &mut Output,
) -> Result<(), IoError> {
    let mut bytes = Vec::new();
    let mut doubles = Vec::new();
    let mut floats = Vec::new();
    let mut keep = Vec::new();
    let mut start = local.start;
    while start < local.end {
        let end = local.end.min(start + CHUNK as u64);
        let rows = (end - start) as usize;
        read_rows(src, layout, pos, ti, start..end, &mut bytes)?;
        decode_f64(&bytes, pos.width, layout.endian, &mut doubles);
        let points = doubles.chunks_exact(3).map(|p| [p[0], p[1], p[2]]);
        keep.clear();
        match out.region {
            Some(region) => keep.extend(points.clone().map(|p| region.contains(p))),
            None => keep.resize(rows, true),
        }
        let kept = keep.iter().filter(|&&k| k).count();
        if kept > 0 {
            if kept == rows {
                out.positions.extend(points);
            } else {
                out.positions
                    .extend(points.zip(&keep).filter(|(_, k)| **k).map(|(p, _)| p));
            }
            let mut slot = 0;
            for source in sources {
                match source {
                    Some(ColumnSource::Block(field)) => {
                        read_rows(src, layout, field, ti, start..end, &mut bytes)?;
                        let ints = field.kind == Kind::Ids;
                        decode_f32(&bytes, field.width, ints, layout.endian, &mut floats);
                        let comps = field.comps as usize;
                        if kept == rows {
                            // Every row kept (no region): whole slices.
                            if let Some(columns) = out.values.get_mut(slot..) {
                                split_columns(&floats, comps, columns);
                            }
                        } else {
                            for c in 0..comps {
                                if let Some(column) = out.values.get_mut(slot + c) {
                                    let values = floats.iter().skip(c).step_by(comps);
                                    column.extend(
                                        values.zip(&keep).filter(|(_, k)| **k).map(|(v, _)| *v),
                                    );
                                }
                            }
                        }
                        slot += comps;
                    }
                    Some(ColumnSource::Constant(mass)) => {
                        if let Some(column) = out.values.get_mut(slot) {
                            column.extend(std::iter::repeat_n(*mass, kept));
                        }
                        slot += 1;
                    }
                    // Files that read rows hold the type, so every column
                    // has a source.
                    None => {}
                }
            }
        }
        start = end;
    }
    Ok(())
}

/// Reads rows `rows` of type `ti` of a block into `bytes`. The block's
/// size was checked against the file's counts, so the range lies in it.
fn read_rows<S: Read + Seek>(
    src: &mut Source<S>,
    layout: &Layout,
    field: &Field,
    ti: usize,
    rows: std::ops::Range<u64>,
    bytes: &mut Vec<u8>,
) -> Result<(), IoError> {
    let per_row = field.comps * field.width;
    let offset = field.start(&layout.header.npart, ti) + rows.start * per_row;
    let len = (rows.end - rows.start) * per_row;
    if offset + len > field.size {
        return Err(src.err(format!(
            "block {}: rows {}..{} of type {ti} lie outside the block",
            field.label, rows.start, rows.end
        )));
    }
    let offset = field.offset + offset;
    bytes.clear();
    bytes.resize(len as usize, 0);
    src.read_at(offset, bytes, &format!("block {}", field.label))
}

/// `comps` interleaved components of `values` appended to the first
/// `comps` of `columns`.
fn split_columns(values: &[f32], comps: usize, columns: &mut [Vec<f32>]) {
    match (comps, columns) {
        (1, [column, ..]) => column.extend_from_slice(values),
        (3, [x, y, z, ..]) => {
            for v in values.chunks_exact(3) {
                x.push(v[0]);
                y.push(v[1]);
                z.push(v[2]);
            }
        }
        (_, columns) => {
            for (c, column) in columns.iter_mut().take(comps).enumerate() {
                column.extend(values.iter().skip(c).step_by(comps));
            }
        }
    }
}

/// 4- or 8-byte words decoded in the file's byte order by `f`, the byte
/// order chosen once per block rather than per value.
fn decode<T, const W: usize>(
    bytes: &[u8],
    endian: layout::Endian,
    out: &mut Vec<T>,
    f: impl Fn([u8; W], bool) -> T,
) {
    let little = endian == layout::Endian::Little;
    out.extend(bytes.chunks_exact(W).map(|b| {
        let mut w = [0u8; W];
        w.copy_from_slice(b);
        f(w, little)
    }));
}

/// 4- or 8-byte floats as f64.
fn decode_f64(bytes: &[u8], width: u64, endian: layout::Endian, out: &mut Vec<f64>) {
    out.clear();
    if width == 8 {
        decode(bytes, endian, out, |w: [u8; 8], le| {
            if le {
                f64::from_le_bytes(w)
            } else {
                f64::from_be_bytes(w)
            }
        });
    } else {
        decode(bytes, endian, out, |w: [u8; 4], le| {
            f64::from(if le {
                f32::from_le_bytes(w)
            } else {
                f32::from_be_bytes(w)
            })
        });
    }
}

/// 4- or 8-byte floats, or unsigned integers when `ints`, as f32 (each
/// rounded once).
fn decode_f32(bytes: &[u8], width: u64, ints: bool, endian: layout::Endian, out: &mut Vec<f32>) {
    out.clear();
    match (width, ints) {
        (8, true) => decode(bytes, endian, out, |w: [u8; 8], le| {
            (if le {
                u64::from_le_bytes(w)
            } else {
                u64::from_be_bytes(w)
            }) as f32
        }),
        (8, false) => decode(bytes, endian, out, |w: [u8; 8], le| {
            (if le {
                f64::from_le_bytes(w)
            } else {
                f64::from_be_bytes(w)
            }) as f32
        }),
        (_, true) => decode(bytes, endian, out, |w: [u8; 4], le| {
            (if le {
                u32::from_le_bytes(w)
            } else {
                u32::from_be_bytes(w)
            }) as f32
        }),
        (_, false) => decode(bytes, endian, out, |w: [u8; 4], le| {
            if le {
                f32::from_le_bytes(w)
            } else {
                f32::from_be_bytes(w)
            }
        }),
    }
}

/// "HEAD, POS, VEL" for messages.
fn block_list(layout: &Layout) -> String {
    let labels: Vec<&str> = layout.blocks.iter().map(|b| b.label.as_str()).collect();
    labels.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shares_split_rows_like_the_hdf5_readers() {
        assert_eq!(share_rows(10, 0, 3), 0..3);
        assert_eq!(share_rows(10, 1, 3), 3..6);
        assert_eq!(share_rows(10, 2, 3), 6..10);
        assert_eq!(share_rows(10, 5, 3), 10..10);
        assert_eq!(share_rows(10, 0, 0), 0..10);
        assert_eq!(share_rows(u64::MAX, 1, 2), u64::MAX / 2..u64::MAX);
    }
}
