//! `voxless info FILE`: what a data file holds — particle files (count,
//! frames and their times, columns with ranges, bounds), `.npy` arrays, AMR
//! cells, `.vtu` meshes and HDF5 files.

use std::fmt::Write;
use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use clap::Args;
use voxless::formats::{self, ParticleFormat, TableOptions};
use voxless::io::ParticleTable;

/// Frames listed one by one (each is read for its time and count); longer
/// series show the first and last.
const LISTED_FRAMES: usize = 32;

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// The file: any particle format, .npy, ExaBricks .cells, AMRClaw
    /// fort.qNNNN, .vtu mesh or HDF5; or a frame pattern / directory.
    #[arg(required_unless_present = "devices")]
    pub file: Option<PathBuf>,
    /// List the GPU adapters `--device gpu` can use (instead of a file).
    #[arg(long, conflicts_with = "file")]
    pub devices: bool,
    /// The frame whose particles and columns are shown.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub frame: usize,
    /// PySPH particle array to show (default: fluid if present, else the first).
    #[arg(long, value_name = "NAME")]
    pub group: Option<String>,
    /// Snapshot particle type to show: 0–6 or gas, dm, disk, bulge, stars,
    /// bh (default: gas if present, else the first type with particles).
    #[arg(long, value_name = "T", value_parser = part_type)]
    pub part_type: Option<u32>,
}

/// A particle type by number or name.
fn part_type(s: &str) -> Result<u32, String> {
    voxless::io::part_type_named(s).ok_or_else(|| {
        format!(
            "unknown particle type '{s}': give 0–6 or one of {}",
            voxless::io::snapshot::PART_TYPE_NAMES.join(", ")
        )
    })
}

pub fn run(args: &InfoArgs) -> Result<()> {
    if args.devices {
        println!("GPU adapters (for --device gpu|auto):");
        for a in voxless::device::adapters() {
            println!("  {a}");
        }
        return Ok(());
    }
    print!("{}", describe(args)?);
    Ok(())
}

/// The whole report as text.
fn describe(args: &InfoArgs) -> Result<String> {
    let Some(path) = args.file.as_deref() else {
        anyhow::bail!("give a file, or --devices");
    };
    let spec = path.to_string_lossy();
    let mut out = String::new();
    if voxless::frames::is_sequence(&spec, Path::new("")) {
        let files = voxless::frames::numbered(&spec, Path::new(""))?;
        writeln!(
            out,
            "{spec}: a sequence of {} frame(s), numbered by the last number in each name",
            files.len()
        )?;
        let options = TableOptions {
            group: args.group.clone(),
            part_type: args.part_type,
            ..Default::default()
        };
        for (i, (n, f)) in files.iter().enumerate() {
            if i < LISTED_FRAMES / 2 || i + LISTED_FRAMES / 2 >= files.len() {
                let name = f.file_name().unwrap_or(f.as_os_str()).to_string_lossy();
                // Formats that record a time: the count and time of each.
                let what = match ParticleFormat::detect(f)? {
                    Some(format) if has_time(format) => {
                        let t = formats::read_table(f, format, 0, &options)?.table;
                        format!("  {}{}", count(t.len()), time_of(format, t.time))
                    }
                    _ => String::new(),
                };
                writeln!(out, "  frame {n:>4}  {name}{what}")?;
            } else if i == LISTED_FRAMES / 2 {
                writeln!(out, "  …")?;
            }
        }
        let first = files.first().map_or(0, |f| f.0);
        let wanted = if args.frame == 0 { first } else { args.frame };
        let Some((_, file)) = files.iter().find(|f| f.0 == wanted) else {
            let numbers: Vec<usize> = files.iter().map(|f| f.0).collect();
            bail!(
                "--frame {}: no file of the sequence is numbered {}; it has frames {}",
                args.frame,
                args.frame,
                voxless::frames::list_numbers(&numbers)
            );
        };
        writeln!(out)?;
        let one = InfoArgs {
            file: Some(file.clone()),
            devices: false,
            frame: 0,
            group: args.group.clone(),
            part_type: args.part_type,
        };
        out.push_str(&describe_file(&one)?);
        return Ok(out);
    }
    out.push_str(&describe_file(args)?);
    Ok(out)
}

fn describe_file(args: &InfoArgs) -> Result<String> {
    let Some(path) = args.file.as_deref() else {
        bail!("give a file, or --devices");
    };
    // A snapshot's stem (snap_033 of snap_033.0, snap_033.1, …) is no file.
    if !path.exists() && voxless::io::snapshot::snapshot_files(path).is_none() {
        bail!("{}: no such file", path.display());
    }
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if ext == "cells" {
        let scalars = voxless::io::exabricks_scalars(path)?;
        return amr(
            path,
            "ExaBricks cells",
            voxless::io::read_exabricks(path, &scalars),
        );
    }
    if name.starts_with("fort.q") {
        return amr(path, "AMRClaw output", voxless::io::read_amrclaw(path));
    }
    // AMR outputs the library tells apart by their paths (HDF5 ones with
    // a FLASH or Athena++ layout also below, by their layout).
    use voxless::io::AmrFormat;
    if let Ok(format @ (AmrFormat::Amrex | AmrFormat::Enzo | AmrFormat::Athena)) =
        voxless::io::amr_format(path)
    {
        return amr(
            path,
            format.name(),
            voxless::io::read_amr(path).map(|r| r.0),
        );
    }
    if ext == "vtu" {
        return mesh(path);
    }
    match ParticleFormat::detect(path)? {
        Some(ParticleFormat::Npy) => npy(path),
        Some(ParticleFormat::Hdf5) => hdf5(path, args),
        Some(format) => particles(path, format, args),
        None => bail!(
            "{}: not a format voxless reads; it reads {}",
            path.display(),
            formats::SUPPORTED
        ),
    }
}

/// A particle file: frames (with times), then the chosen frame's count,
/// bounds, domain and columns.
fn particles(path: &Path, format: ParticleFormat, args: &InfoArgs) -> Result<String> {
    let options = TableOptions {
        group: args.group.clone(),
        part_type: args.part_type,
        ..Default::default()
    };
    let frames = formats::frames_in(path, format)?;
    let mut out = String::new();
    writeln!(
        out,
        "{}: {}, {frames} frame{}",
        path.display(),
        format.name(),
        plural(frames)
    )?;
    if let Some(h) = voxless::io::snapshot_header(path, format)? {
        snapshot(&mut out, &h)?;
    }
    if args.frame >= frames {
        bail!(
            "{}: --frame {}: the file has {frames} frame(s), 0..{}",
            path.display(),
            args.frame,
            frames - 1
        );
    }
    if format == ParticleFormat::Lammps
        && let (_, Some(partial)) = voxless::io::lammps_frame_scan(path)?
    {
        writeln!(
            out,
            "  (the file ends inside a further frame, so LAMMPS is probably still writing it: \
             {partial})"
        )?;
    }
    if frames > 1 {
        for f in 0..frames {
            if f < LISTED_FRAMES / 2 || f + LISTED_FRAMES / 2 >= frames {
                let t = formats::read_table(path, format, f, &options)?.table;
                let when = time_of(format, t.time);
                writeln!(out, "  frame {f:>4}  {}{when}", count(t.len()))?;
            } else if f == LISTED_FRAMES / 2 {
                writeln!(out, "  … ({} more)", frames - LISTED_FRAMES)?;
            }
        }
    }
    let table = formats::read_table(path, format, args.frame, &options)?;
    if let Some(note) = table.note {
        writeln!(out, "{note}")?;
    }
    let which = (frames > 1).then_some(args.frame);
    table_summary(&mut out, &table.table, format, which)?;
    Ok(out)
}

/// What a snapshot's headers say: code, files, particles and fields per
/// type, box, epoch, units, and which fields would be the radii and masses.
fn snapshot(out: &mut String, h: &voxless::io::SnapshotHeader) -> std::fmt::Result {
    use voxless::io::part_type_label;
    writeln!(out, "snapshot: {}", h.code)?;
    if h.files.len() > 1 {
        let name = |p: &Path| {
            p.file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default()
        };
        writeln!(
            out,
            "  files ({}): {} … {}",
            h.files.len(),
            name(&h.files[0]),
            name(&h.files[h.files.len() - 1])
        )?;
    }
    let total: u64 = h.counts.iter().sum();
    writeln!(out, "  {total} particles in all")?;
    for (t, &n) in h.counts.iter().enumerate() {
        if n == 0 {
            continue;
        }
        writeln!(out, "  type {}: {n} particles", part_type_label(t as u32))?;
        if let Some((_, fields)) = h.fields.iter().find(|f| f.0 == t as u32) {
            writeln!(out, "    fields: {}", fields.join(", "))?;
            // The file's own name of the first field named like one of these.
            let has = |names: &[&str]| {
                names
                    .iter()
                    .find_map(|n| fields.iter().find(|f| f.eq_ignore_ascii_case(n)))
                    .cloned()
            };
            let table_mass = h.mass_table.get(t).copied().filter(|m| *m != 0.0);
            let mass = has(&["Masses", "MASS", "mass"])
                .or(table_mass.map(|m| format!("MassTable = {}", num(m))));
            let radius = match has(&["SmoothingLengths", "SmoothingLength", "HSML", "hsmooth"]) {
                Some(hs) => format!("{hs} (the code's convention)"),
                None if h.code == "AREPO" && t == 0 => "cell volume Masses/Density".into(),
                None => format!("the {} nearest neighbours (--neighbours)", n.min(32)),
            };
            writeln!(
                out,
                "    used: mass {}, radius {radius}; colour by a field with --attribute",
                mass.unwrap_or_else(|| "1 (none in the file)".into())
            )?;
        }
    }
    if let Some(b) = h.box_size {
        writeln!(out, "  box: {} (periodic)", triple(b))?;
    }
    let mut epoch = Vec::new();
    if let Some(t) = h.time {
        epoch.push(format!("time {}", num(t)));
    }
    if let Some(z) = h.redshift {
        epoch.push(format!("redshift {}", num(z)));
    }
    if !epoch.is_empty() {
        writeln!(out, "  {}", epoch.join(", "))?;
    }
    match &h.units {
        Some(u) => writeln!(out, "  units: {}", u.describe())?,
        None => writeln!(
            out,
            "  units: none stated (positions, masses and column densities in the code's units)"
        )?,
    }
    Ok(())
}

/// Whether files of `format` may record their time.
fn has_time(format: ParticleFormat) -> bool {
    !matches!(format, ParticleFormat::Npy | ParticleFormat::Csv)
}

/// `, t = …`, or `, timestep …` for a LAMMPS dump (whose frames carry the
/// step number, not the time).
fn time_of(format: ParticleFormat, t: Option<f64>) -> String {
    match (format, t) {
        (ParticleFormat::Lammps, Some(step)) => format!(", timestep {}", num(step)),
        _ => time(t),
    }
}

/// Count, time, bounds, domain and columns of one frame (`frame` is shown
/// when the file has several).
fn table_summary(
    out: &mut String,
    t: &ParticleTable,
    format: ParticleFormat,
    frame: Option<usize>,
) -> std::fmt::Result {
    let which = frame.map(|f| format!("frame {f}: ")).unwrap_or_default();
    writeln!(out, "{which}{}{}", count(t.len()), time_of(format, t.time))?;
    if !t.is_empty() {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &t.positions {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        writeln!(out, "bounds: {}..{}", triple(lo), triple(hi))?;
    }
    if let Some((lo, hi)) = t.domain {
        writeln!(out, "domain: {}..{}", triple(lo), triple(hi))?;
    }
    if t.columns.is_empty() {
        return writeln!(out, "columns: none (positions only)");
    }
    writeln!(out, "columns ({}), min .. max:", t.columns.len())?;
    let width = t.columns.iter().map(|c| c.0.len()).max().unwrap_or(0);
    for (name, values) in &t.columns {
        writeln!(out, "  {name:<width$}  {}", range_text(values))?;
    }
    Ok(())
}

/// `min .. max` of values, NaNs left out and counted.
fn range_text<T: Copy + Into<f64>>(values: &[T]) -> String {
    let (mut lo, mut hi, mut nan) = (f64::INFINITY, f64::NEG_INFINITY, 0usize);
    for &v in values {
        let v: f64 = v.into();
        if v.is_nan() {
            nan += 1;
        } else {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    let nans = if nan > 0 {
        format!(" ({nan} NaN)")
    } else {
        String::new()
    };
    if lo > hi {
        format!("no values{nans}")
    } else {
        format!("{} .. {}{nans}", num(lo), num(hi))
    }
}

/// A number as short as it reads well: whole numbers without a fraction,
/// others with 6 significant digits.
fn num(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{v:.0}")
    } else if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e6) {
        format!("{v:.5e}")
    } else {
        // Six significant digits, trailing zeros dropped.
        let decimals = (5 - v.abs().log10().floor() as i32).max(0) as usize;
        let s = format!("{v:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    }
}

fn triple<T: Copy + Into<f64>>(v: [T; 3]) -> String {
    format!(
        "[{}, {}, {}]",
        num(v[0].into()),
        num(v[1].into()),
        num(v[2].into())
    )
}

fn count(n: usize) -> String {
    format!("{n} particle{}", plural(n))
}

fn time(t: Option<f64>) -> String {
    t.map(|t| format!(", t = {}", num(t))).unwrap_or_default()
}

fn plural(n: usize) -> &'static str {
    if n == 1 { "" } else { "s" }
}

fn npy(path: &Path) -> Result<String> {
    let a = voxless::io::read_npy(path)?;
    let shape: Vec<String> = a.shape.iter().map(|d| d.to_string()).collect();
    let mut out = String::new();
    writeln!(
        out,
        "{}: NumPy array, shape ({}), dtype {}",
        path.display(),
        shape.join(", "),
        a.dtype
    )?;
    writeln!(out, "values: {}", range_text(&a.data))?;
    if let [n, 3] = a.shape.as_slice() {
        writeln!(out, "as positions: {}", count(*n))?;
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in a.data.chunks_exact(3) {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        if *n > 0 {
            writeln!(out, "bounds: {}..{}", triple(lo), triple(hi))?;
        }
        if let Some(side) = cube_root(*n) {
            writeln!(
                out,
                "{n} = {side}³: could be a Lagrangian grid (--lagrangian {side} --box L)"
            )?;
        }
    }
    Ok(out)
}

fn cube_root(n: usize) -> Option<usize> {
    let c = (n as f64).cbrt().round() as usize;
    (c > 1 && c.checked_pow(3) == Some(n)).then_some(c)
}

/// The `.scalars` files beside an ExaBricks `.cells` file:
/// `<stem>.<field>.scalars`.
fn amr(
    path: &Path,
    what: &str,
    data: Result<voxless::io::AmrCellData, voxless::io::IoError>,
) -> Result<String> {
    let d = data?;
    let mut out = String::new();
    writeln!(
        out,
        "{}: {what}, {} leaf cells{}",
        path.display(),
        d.cells.len(),
        time(d.time)
    )?;
    let max_level = d.cells.iter().map(|c| c[3]).max().unwrap_or(0).max(0) as usize;
    let mut per_level = vec![0usize; max_level + 1];
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for c in &d.cells {
        per_level[c[3].max(0) as usize] += 1;
        let width = (1u64 << c[3].clamp(0, 62)) as f64;
        for a in 0..3 {
            let x = d.origin[a] + d.finest_cell_size * c[a] as f64;
            lo[a] = lo[a].min(x);
            hi[a] = hi[a].max(x + d.finest_cell_size * width);
        }
    }
    writeln!(out, "cells per level (0 = finest):")?;
    for (level, n) in per_level.iter().enumerate() {
        let width = d.finest_cell_size * (1u64 << level) as f64;
        writeln!(out, "  level {level}: {n} cells of width {}", num(width))?;
    }
    if !d.cells.is_empty() {
        writeln!(out, "bounds: {}..{}", triple(lo), triple(hi))?;
    }
    if d.fields.is_empty() {
        writeln!(
            out,
            "fields: none (no <stem>.<field>.scalars beside the cells)"
        )?;
    } else {
        writeln!(out, "fields ({}), min .. max:", d.fields.len())?;
        let width = d.fields.iter().map(|f| f.0.len()).max().unwrap_or(0);
        for (name, values) in &d.fields {
            writeln!(out, "  {name:<width$}  {}", range_text(values))?;
        }
    }
    Ok(out)
}

fn mesh(path: &Path) -> Result<String> {
    let m = voxless::io::read_vtu_mesh(path)?;
    let mut out = String::new();
    writeln!(
        out,
        "{}: VTK unstructured grid, {} points, {} tetrahedra, {} other cells skipped",
        path.display(),
        m.points.len(),
        m.tets.len(),
        m.skipped_cells
    )?;
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in &m.points {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    if !m.points.is_empty() {
        writeln!(out, "bounds: {}..{}", triple(lo), triple(hi))?;
    }
    for (what, arrays) in [("point data", &m.point_data), ("cell data", &m.cell_data)] {
        if arrays.is_empty() {
            writeln!(out, "{what}: none")?;
            continue;
        }
        writeln!(out, "{what} ({}), min .. max:", arrays.len())?;
        let width = arrays.iter().map(|a| a.0.len()).max().unwrap_or(0);
        for (name, values) in arrays {
            writeln!(out, "  {name:<width$}  {}", range_text(values))?;
        }
    }
    Ok(out)
}

#[cfg(feature = "hdf5")]
fn hdf5(path: &Path, args: &InfoArgs) -> Result<String> {
    use voxless::io::Hdf5Kind;
    let mut out = String::new();
    let kind = voxless::io::hdf5_kind(path)?;
    match kind {
        Hdf5Kind::PySph => {
            let groups = voxless::io::pysph_groups(path)?;
            writeln!(
                out,
                "{}: HDF5, PySPH output (particle arrays: {})",
                path.display(),
                groups.join(", ")
            )?;
        }
        Hdf5Kind::Gadget => {
            writeln!(out, "{}: HDF5 snapshot", path.display())?;
            if let Some(h) = voxless::io::snapshot_header(path, ParticleFormat::Hdf5)? {
                snapshot(&mut out, &h)?;
            }
        }
        Hdf5Kind::Jaxpm => {
            let snaps: Vec<String> = voxless::io::jaxpm_snapshots(path)?
                .iter()
                .map(|k| format!("snap_{k}"))
                .collect();
            writeln!(
                out,
                "{}: HDF5, JaxPM run (snapshots: {}); render it with --lagrangian or --snapshot",
                path.display(),
                snaps.join(", ")
            )?;
        }
        Hdf5Kind::Flash => {
            return amr(path, "FLASH", voxless::io::read_amr(path).map(|r| r.0));
        }
        Hdf5Kind::Athena => {
            return amr(path, "Athena++", voxless::io::read_amr(path).map(|r| r.0));
        }
        Hdf5Kind::Other => writeln!(out, "{}: HDF5 (no known layout)", path.display())?,
    }
    if matches!(kind, Hdf5Kind::PySph | Hdf5Kind::Gadget) {
        let options = TableOptions {
            group: args.group.clone(),
            part_type: args.part_type,
            ..Default::default()
        };
        let table = formats::read_table(path, ParticleFormat::Hdf5, 0, &options)?;
        if let Some(note) = table.note {
            writeln!(out, "{note}")?;
        }
        table_summary(&mut out, &table.table, ParticleFormat::Hdf5, None)?;
    }
    // A snapshot of several files: the first file's contents.
    let first = voxless::io::snapshot::first_file(path);
    writeln!(out, "\ncontents of {}:", first.display())?;
    out.push_str(&voxless::io::describe_hdf5(&first)?);
    Ok(out)
}

#[cfg(not(feature = "hdf5"))]
fn hdf5(path: &Path, _: &InfoArgs) -> Result<String> {
    Err(formats::hdf5::unsupported(path).into())
}
