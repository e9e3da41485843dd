//! LAMMPS text dumps (`dump atom` and `dump custom`).
//!
//! A dump is a sequence of frames, each a list of `ITEM:` sections:
//!
//! ```text
//! ITEM: TIMESTEP
//! 100
//! ITEM: NUMBER OF ATOMS
//! 4000
//! ITEM: BOX BOUNDS pp pp pp
//! xlo xhi
//! ylo yhi
//! zlo zhi
//! ITEM: ATOMS id type xs ys zs vx vy vz
//! 1 1 0.0 0.0 0.0 0.1 -0.2 0.3
//! ...                               (NUMBER OF ATOMS lines)
//! ```
//!
//! `ITEM: UNITS` and `ITEM: TIME` sections (written by `dump_modify units` /
//! `time`) are accepted and skipped; any other item (e.g. the `ENTRIES` of a
//! `dump local`) is an error, as that is not a per-atom dump.
//!
//! **Box.** An orthogonal box gives `lo hi` per axis. A triclinic box
//! (`ITEM: BOX BOUNDS xy xz yz ...`) gives `lo_bound hi_bound tilt` per axis:
//! the bounds of the axis-aligned box around the tilted one, and the tilt
//! factors `xy`, `xz`, `yz`. As the LAMMPS `dump` documentation describes,
//! the real box is `xlo = xlo_bound - min(0, xy, xz, xy + xz)`,
//! `xhi = xhi_bound - max(0, xy, xz, xy + xz)`, `ylo = ylo_bound - min(0, yz)`,
//! `yhi = yhi_bound - max(0, yz)`, `z` unchanged, with edge vectors
//! `a = (xhi - xlo, 0, 0)`, `b = (xy, yhi - ylo, 0)`, `c = (xz, yz, zhi - zlo)`.
//! A general triclinic box (`ITEM: BOX BOUNDS abc origin ...`) gives
//! `ax ay az originx`, `bx by bz originy`, `cx cy cz originz`.
//!
//! **Positions** come from the first complete triple among `x y z`,
//! `xu yu zu` (unwrapped), `xs ys zs` (scaled) and `xsu ysu zsu` (scaled,
//! unwrapped). Scaled coordinates are mapped to world units through the box:
//! `origin + xs a + ys b + zs c`. Every other column (including any further
//! position triple) becomes a named column of the [`ParticleTable`], e.g.
//! `id`, `type` (the species), `vx`; `speed` is added when `vx vy vz` exist.
//! All values must be numbers (string columns such as `element` are rejected).
//!
//! `time` is the frame's TIMESTEP and `domain` the axis-aligned box (for a
//! triclinic box, the bounding box of the tilted one).
//!
//! **Row order.** LAMMPS writes atoms in an arbitrary order that changes from
//! frame to frame; when there is an `id` column the rows are sorted by it, so
//! a particle stays on the same row across frames.
//!
//! **Streaming.** [`read_lammps`] reads the headers of the frames before the
//! one asked for and skips their atom lines without parsing them.
//!
//! **From memory.** [`lammps_frames_from`] and [`read_lammps_from`] read a
//! dump from any reader (a `Cursor` over bytes, a file already open); the
//! path functions open the file and share their code.

use std::io::{BufRead, Read, Seek};
use std::path::Path;

use crate::{IoError, LineReader, ParticleTable};

/// Position column triples in order of preference, and whether they are
/// scaled by the box.
const POSITION_SETS: [([&str; 3], bool); 4] = [
    (["x", "y", "z"], false),
    (["xu", "yu", "zu"], false),
    (["xs", "ys", "zs"], true),
    (["xsu", "ysu", "zsu"], true),
];

/// The simulation box of a frame as an origin and three edge vectors, plus
/// its axis-aligned bounding box.
#[derive(Debug, Clone, Copy, PartialEq)]
struct SimBox {
    origin: [f64; 3],
    edges: [[f64; 3]; 3],
    lo: [f64; 3],
    hi: [f64; 3],
    /// Orthogonal and `pp` along every axis.
    periodic: bool,
    /// The tilt factors `xy xz yz` of a triclinic box that is `pp` along
    /// every axis: periodic in LAMMPS, not here (a note says so).
    tilted_periodic: Option<[f64; 3]>,
}

impl SimBox {
    /// World position of scaled coordinates `s`.
    fn unscale(&self, s: [f64; 3]) -> [f64; 3] {
        unscale(self.origin, &self.edges, s)
    }
}

/// `origin + s[0] a + s[1] b + s[2] c` for edge vectors `a`, `b`, `c`.
fn unscale(origin: [f64; 3], edges: &[[f64; 3]; 3], s: [f64; 3]) -> [f64; 3] {
    let mut p = origin;
    for (k, e) in edges.iter().enumerate() {
        for (pi, ei) in p.iter_mut().zip(e) {
            *pi += s[k] * ei;
        }
    }
    p
}

/// The header items of one frame.
#[derive(Debug, Clone)]
struct FrameHeader {
    timestep: Option<i64>,
    atoms: usize,
    sim_box: Option<SimBox>,
    columns: Vec<String>,
}

/// Number of complete frames in a LAMMPS text dump.
///
/// Reads every frame header and skips the atom lines. A last frame the file
/// ends inside (a dump still being written) is not counted; see
/// [`lammps_frame_scan`] to learn about it. Fails with [`IoError::Format`]
/// if a header is malformed, a frame before the last has fewer atom lines
/// than its NUMBER OF ATOMS, or there is no complete frame.
pub fn lammps_frames(path: &Path) -> Result<usize, IoError> {
    Ok(lammps_frame_scan(path)?.0)
}

/// [`lammps_frames`] and, when the file ends inside a last frame (LAMMPS
/// still writing it), why that frame is incomplete.
pub fn lammps_frame_scan(path: &Path) -> Result<(usize, Option<IoError>), IoError> {
    count_frames(LineReader::open(path)?)
}

/// [`lammps_frames`] of the dump `reader` yields; `name` only labels errors,
/// which read as [`lammps_frames`]'s for a file of that name.
pub fn lammps_frames_from<R: Read>(reader: R, name: &Path) -> Result<usize, IoError> {
    Ok(count_frames(LineReader::from_read(reader, name))?.0)
}

fn count_frames<R: BufRead>(mut lines: LineReader<R>) -> Result<(usize, Option<IoError>), IoError> {
    let mut count = 0;
    let mut partial = None;
    loop {
        // A frame the file ends inside is one still being written.
        let header = match read_header(&mut lines, count) {
            Ok(Some(h)) => h,
            Ok(None) => break,
            Err(e) if count > 0 && lines.at_end() => {
                partial = Some(e);
                break;
            }
            Err(e) => return Err(e),
        };
        match skip_atoms(&mut lines, count, &header) {
            Ok(()) => count += 1,
            Err(e) if count > 0 && lines.at_end() => {
                partial = Some(e);
                break;
            }
            Err(e) => return Err(e),
        }
    }
    if count == 0 {
        return Err(IoError::format(
            lines.path(),
            "not a LAMMPS dump: the file holds no 'ITEM: TIMESTEP' frame",
        ));
    }
    Ok((count, partial))
}

/// Reads frame `frame` (0-based) of a LAMMPS text dump; see the module docs
/// for the accepted layout and how positions, columns and the box are read.
///
/// Fails with [`IoError::Format`] if the frame does not exist (the message
/// says how many there are), a header is malformed, the position columns are
/// missing (the message lists the columns found), a frame has fewer atom
/// lines than it declares, or an atom line has the wrong number of values or
/// a value that is not a number.
pub fn read_lammps(path: &Path, frame: usize) -> Result<ParticleTable, IoError> {
    read_frame(LineReader::open(path)?, frame).map(|r| r.0)
}

/// [`read_lammps`] with a note on what the frame's box means here: a
/// triclinic box with periodic boundaries is periodic in LAMMPS, but
/// periodic images are only made for orthogonal boxes, so its particles
/// are used as they are.
pub fn read_lammps_noted(
    path: &Path,
    frame: usize,
) -> Result<(ParticleTable, Option<String>), IoError> {
    read_frame(LineReader::open(path)?, frame)
}

/// [`read_lammps`] of the dump `reader` yields, from its position to its
/// end; `name` only labels errors, which read as [`read_lammps`]'s for a file
/// of that name. The reader's length caps what NUMBER OF ATOMS may make it
/// allocate, as the file's length does.
pub fn read_lammps_from<R: Read + Seek>(
    reader: R,
    name: &Path,
    frame: usize,
) -> Result<ParticleTable, IoError> {
    read_frame(LineReader::from_seek(reader, name)?, frame).map(|r| r.0)
}

fn read_frame<R: BufRead>(
    mut lines: LineReader<R>,
    frame: usize,
) -> Result<(ParticleTable, Option<String>), IoError> {
    // Skip the frames before, reading only their headers.
    for index in 0..frame {
        match read_header(&mut lines, index)? {
            Some(header) => skip_atoms(&mut lines, index, &header)?,
            None => return Err(past_end(lines.path(), frame, index)),
        }
    }
    let header =
        read_header(&mut lines, frame)?.ok_or_else(|| past_end(lines.path(), frame, frame))?;
    let note = header
        .sim_box
        .and_then(|b| b.tilted_periodic)
        .map(|[xy, xz, yz]| {
            format!(
                "LAMMPS frame {frame}: a triclinic box (tilt xy {xy}, xz {xz}, yz {yz}) with \
             periodic boundaries; periodic images are made for orthogonal boxes only, so the \
             atoms are used as they are (their kernels are cut at the box faces)"
            )
        });
    let table = read_atoms(&mut lines, frame, header)?;
    // More atom rows than NUMBER OF ATOMS says: the count lies, as `info`
    // (which reads every frame) says too. The next frame, even one still
    // being written, starts with an ITEM line.
    while let Some(line) = lines.next_line()? {
        if line.is_empty() {
            continue;
        }
        if !line.starts_with("ITEM:") {
            let shown: String = line.chars().take(60).collect();
            return Err(lines.error(format!(
                "frame {}: expected an 'ITEM:' line but found '{shown}' (frame {frame} holds \
                 more atom rows than its NUMBER OF ATOMS, {})",
                frame + 1,
                table.len()
            )));
        }
        break;
    }
    Ok((table, note))
}

fn past_end(path: &Path, frame: usize, frames: usize) -> IoError {
    if frames == 0 {
        return IoError::format(
            path,
            "not a LAMMPS dump: the file holds no 'ITEM: TIMESTEP' frame",
        );
    }
    IoError::format(
        path,
        format!(
            "frame {frame} requested but the dump has {frames} frame{} (numbered from 0)",
            if frames == 1 { "" } else { "s" }
        ),
    )
}

/// Reads the items of one frame up to and including `ITEM: ATOMS`. Returns
/// `None` if the file ends (blank lines aside) before the frame starts.
fn read_header(
    lines: &mut LineReader<impl BufRead>,
    frame: usize,
) -> Result<Option<FrameHeader>, IoError> {
    let mut timestep = None;
    let mut atoms = None;
    let mut sim_box = None;
    let mut started = false;
    loop {
        let Some(line) = lines.next_line()? else {
            if started {
                return Err(lines.error(format!(
                    "frame {frame}: the file ends before its 'ITEM: ATOMS' line"
                )));
            }
            return Ok(None);
        };
        if line.is_empty() && !started {
            continue;
        }
        let Some(item) = line.strip_prefix("ITEM:") else {
            let shown: String = line.chars().take(60).collect();
            let what = if frame == 0 && !started {
                "not a LAMMPS text dump: expected 'ITEM: TIMESTEP'".to_string()
            } else {
                format!("frame {frame}: expected an 'ITEM:' line")
            };
            return Err(lines.error(format!("{what} but found '{shown}'")));
        };
        started = true;
        let item = item.trim().to_string();
        let words: Vec<&str> = item.split_whitespace().collect();
        match words.as_slice() {
            ["TIMESTEP"] => timestep = Some(value_line(lines, frame, "TIMESTEP")?),
            ["NUMBER", "OF", "ATOMS"] => {
                let n: u64 = value_line(lines, frame, "NUMBER OF ATOMS")?;
                let n = usize::try_from(n)
                    .map_err(|_| lines.error(format!("frame {frame}: {n} atoms is too many")))?;
                atoms = Some(n);
            }
            ["UNITS"] | ["TIME"] => {
                if lines.next_line()?.is_none() {
                    return Err(
                        lines.error(format!("frame {frame}: the file ends after ITEM: {item}"))
                    );
                }
            }
            ["BOX", "BOUNDS", flags @ ..] => sim_box = Some(read_box(lines, frame, flags)?),
            ["ATOMS", names @ ..] => {
                let atoms = atoms.ok_or_else(|| {
                    lines.error(format!(
                        "frame {frame}: 'ITEM: ATOMS' before 'ITEM: NUMBER OF ATOMS'"
                    ))
                })?;
                let columns: Vec<String> = names.iter().map(|s| s.to_string()).collect();
                if columns.is_empty() {
                    return Err(
                        lines.error(format!("frame {frame}: 'ITEM: ATOMS' names no columns"))
                    );
                }
                for (i, c) in columns.iter().enumerate() {
                    if columns[..i].contains(c) {
                        return Err(
                            lines.error(format!("frame {frame}: column '{c}' appears twice"))
                        );
                    }
                }
                return Ok(Some(FrameHeader {
                    timestep,
                    atoms,
                    sim_box,
                    columns,
                }));
            }
            _ => {
                return Err(lines.error(format!(
                    "frame {frame}: unsupported item 'ITEM: {item}' (only per-atom dumps with \
                     TIMESTEP, NUMBER OF ATOMS, BOX BOUNDS and ATOMS items are read)"
                )));
            }
        }
    }
}

/// Reads the line after an item and parses it as one value.
fn value_line<T: std::str::FromStr>(
    lines: &mut LineReader<impl BufRead>,
    frame: usize,
    item: &str,
) -> Result<T, IoError> {
    if !lines.read()? {
        return Err(lines.error(format!("frame {frame}: the file ends after ITEM: {item}")));
    }
    let line = lines.line();
    line.parse().map_err(|_| {
        let shown: String = line.chars().take(60).collect();
        lines.error(format!(
            "frame {frame}: cannot parse '{shown}' as the {item} value"
        ))
    })
}

/// Reads the three lines of `ITEM: BOX BOUNDS <flags>`.
fn read_box(
    lines: &mut LineReader<impl BufRead>,
    frame: usize,
    flags: &[&str],
) -> Result<SimBox, IoError> {
    let triclinic = flags.contains(&"xy");
    let general = flags.contains(&"abc");
    let per_line = if general {
        4
    } else if triclinic {
        3
    } else {
        2
    };
    let mut rows = [[0.0f64; 4]; 3];
    for row in &mut rows {
        if !lines.read()? {
            return Err(lines.error(format!("frame {frame}: the file ends inside BOX BOUNDS")));
        }
        let line = lines.line();
        let values: Vec<&str> = line.split_whitespace().collect();
        if values.len() != per_line {
            return Err(lines.error(format!(
                "frame {frame}: a BOX BOUNDS line needs {per_line} numbers, found '{line}'"
            )));
        }
        for (slot, v) in row.iter_mut().zip(&values) {
            *slot = v.parse().map_err(|_| {
                lines.error(format!(
                    "frame {frame}: cannot parse '{v}' in BOX BOUNDS as a number"
                ))
            })?;
        }
    }
    let sim_box = if general {
        let origin = [rows[0][3], rows[1][3], rows[2][3]];
        let edges = [
            [rows[0][0], rows[0][1], rows[0][2]],
            [rows[1][0], rows[1][1], rows[1][2]],
            [rows[2][0], rows[2][1], rows[2][2]],
        ];
        // Bounding box of the eight corners.
        let (mut lo, mut hi) = (origin, origin);
        for corner in 1..8usize {
            let s = [
                (corner & 1) as f64,
                ((corner >> 1) & 1) as f64,
                (corner >> 2) as f64,
            ];
            let p = unscale(origin, &edges, s);
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        SimBox {
            origin,
            edges,
            lo,
            hi,
            periodic: false,
            tilted_periodic: None,
        }
    } else if triclinic {
        let (xy, xz, yz) = (rows[0][2], rows[1][2], rows[2][2]);
        let bound_lo = [rows[0][0], rows[1][0], rows[2][0]];
        let bound_hi = [rows[0][1], rows[1][1], rows[2][1]];
        let xlo = bound_lo[0] - 0f64.min(xy).min(xz).min(xy + xz);
        let xhi = bound_hi[0] - 0f64.max(xy).max(xz).max(xy + xz);
        let ylo = bound_lo[1] - 0f64.min(yz);
        let yhi = bound_hi[1] - 0f64.max(yz);
        let (zlo, zhi) = (bound_lo[2], bound_hi[2]);
        SimBox {
            origin: [xlo, ylo, zlo],
            edges: [
                [xhi - xlo, 0.0, 0.0],
                [xy, yhi - ylo, 0.0],
                [xz, yz, zhi - zlo],
            ],
            lo: bound_lo,
            hi: bound_hi,
            periodic: false,
            tilted_periodic: None,
        }
    } else {
        let lo = [rows[0][0], rows[1][0], rows[2][0]];
        let hi = [rows[0][1], rows[1][1], rows[2][1]];
        SimBox {
            origin: lo,
            edges: [
                [hi[0] - lo[0], 0.0, 0.0],
                [0.0, hi[1] - lo[1], 0.0],
                [0.0, 0.0, hi[2] - lo[2]],
            ],
            lo,
            hi,
            periodic: false,
            tilted_periodic: None,
        }
    };
    let mut sim_box = sim_box;
    let bounds: Vec<&&str> = flags
        .iter()
        .filter(|f| f.len() == 2 && !["xy", "xz", "yz"].contains(f))
        .collect();
    let all_pp = bounds.len() == 3 && bounds.iter().all(|f| f.eq_ignore_ascii_case("pp"));
    sim_box.periodic = !general && !triclinic && all_pp;
    if triclinic && all_pp {
        sim_box.tilted_periodic = Some([rows[0][2], rows[1][2], rows[2][2]]);
    }
    if sim_box.lo.iter().chain(&sim_box.hi).any(|v| !v.is_finite()) {
        return Err(lines.error(format!("frame {frame}: BOX BOUNDS are not finite")));
    }
    if let Some(a) = (0..3).find(|&a| !(sim_box.lo[a] < sim_box.hi[a])) {
        return Err(lines.error(format!(
            "frame {frame}: BOX BOUNDS along {} run from {} to {}; the lower bound must be \
             below the upper",
            ["x", "y", "z"][a],
            sim_box.lo[a],
            sim_box.hi[a]
        )));
    }
    Ok(sim_box)
}

/// Error for a frame whose atom lines run out early.
fn short_frame(
    lines: &LineReader<impl BufRead>,
    frame: usize,
    header: &FrameHeader,
    found: usize,
    why: &str,
) -> IoError {
    let step = header
        .timestep
        .map_or(String::new(), |t| format!(" (TIMESTEP {t})"));
    lines.error(format!(
        "frame {frame}{step} declares NUMBER OF ATOMS {} but {why} after {found} atom line{}",
        header.atoms,
        if found == 1 { "" } else { "s" }
    ))
}

/// Skips the atom lines of a frame without parsing them.
fn skip_atoms(
    lines: &mut LineReader<impl BufRead>,
    frame: usize,
    header: &FrameHeader,
) -> Result<(), IoError> {
    for found in 0..header.atoms {
        match lines.skip_line(b"ITEM:")? {
            None => return Err(short_frame(lines, frame, header, found, "the file ends")),
            Some(true) => {
                return Err(short_frame(
                    lines,
                    frame,
                    header,
                    found,
                    "the next ITEM: line comes",
                ));
            }
            Some(false) => {}
        }
    }
    Ok(())
}

/// Parses the atom lines of a frame into a table.
fn read_atoms(
    lines: &mut LineReader<impl BufRead>,
    frame: usize,
    header: FrameHeader,
) -> Result<ParticleTable, IoError> {
    let names = &header.columns;
    let find = |n: &str| names.iter().position(|c| c == n);
    let Some((pos_cols, scaled)) = POSITION_SETS
        .iter()
        .find_map(|(set, scaled)| Some(([find(set[0])?, find(set[1])?, find(set[2])?], *scaled)))
    else {
        return Err(lines.error(format!(
            "frame {frame}: no position columns (need x y z, xu yu zu, xs ys zs or xsu ysu zsu); \
             the ATOMS columns are: {}",
            names.join(" ")
        )));
    };
    if scaled && header.sim_box.is_none() {
        return Err(lines.error(format!(
            "frame {frame}: scaled coordinates need a BOX BOUNDS item, and there is none"
        )));
    }
    let ncols = names.len();
    // Each value takes at least two bytes ("0 "), so the rest of the file
    // bounds how many rows can follow, whatever NUMBER OF ATOMS claims.
    let max_rows = lines.remaining_bytes() / (2 * ncols as u64);
    let capacity = header
        .atoms
        .min(usize::try_from(max_rows).unwrap_or(usize::MAX));
    let mut raw_positions: Vec<[f64; 3]> = Vec::with_capacity(capacity);
    let mut columns: Vec<(String, Vec<f32>)> = names
        .iter()
        .enumerate()
        .filter(|(i, _)| !pos_cols.contains(i))
        .map(|(_, n)| (n.clone(), Vec::with_capacity(capacity)))
        .collect();
    let id_col = find("id");
    let mut ids: Vec<f64> = Vec::with_capacity(if id_col.is_some() { capacity } else { 0 });
    let mut values = vec![0.0f64; ncols];

    for found in 0..header.atoms {
        let Some(line) = lines.next_line()? else {
            return Err(short_frame(lines, frame, &header, found, "the file ends"));
        };
        if line.starts_with("ITEM:") {
            return Err(short_frame(
                lines,
                frame,
                &header,
                found,
                "the next ITEM: line comes",
            ));
        }
        let mut n = 0;
        let mut bad = None;
        for field in line.split_ascii_whitespace() {
            if n < ncols {
                match field.parse() {
                    Ok(v) => values[n] = v,
                    Err(_) => {
                        bad = Some((n, field.chars().take(40).collect::<String>()));
                        break;
                    }
                }
            }
            n += 1;
        }
        if let Some((col, shown)) = bad {
            return Err(lines.error(format!(
                "frame {frame}: column '{}': cannot parse '{shown}' as a number",
                names[col]
            )));
        }
        if n != ncols {
            return Err(lines.error(format!(
                "frame {frame}: expected {ncols} values ({}) but found {n}",
                names.join(" ")
            )));
        }
        raw_positions.push([
            values[pos_cols[0]],
            values[pos_cols[1]],
            values[pos_cols[2]],
        ]);
        let others = values
            .iter()
            .enumerate()
            .filter(|(i, _)| !pos_cols.contains(i));
        for ((_, v), (_, col)) in others.zip(&mut columns) {
            col.push(*v as f32);
        }
        if let Some(c) = id_col {
            ids.push(values[c]);
        }
    }

    let mut positions: Vec<[f64; 3]> = raw_positions
        .into_iter()
        .map(|p| match (scaled, &header.sim_box) {
            (true, Some(b)) => b.unscale(p),
            _ => p,
        })
        .collect();
    if id_col.is_some() {
        let mut order: Vec<usize> = (0..ids.len()).collect();
        order.sort_by(|&a, &b| ids[a].total_cmp(&ids[b]));
        // Rows are matched across frames by id: two atoms with one id would
        // be taken for one.
        if let Some(w) = order.windows(2).find(|w| ids[w[0]] == ids[w[1]]) {
            let (a, b) = (w[0].min(w[1]), w[0].max(w[1]));
            return Err(lines.error(format!(
                "frame {frame}: atom id {} appears twice (atom lines {} and {} of the frame); \
                 ids must be unique",
                ids[a],
                a + 1,
                b + 1
            )));
        }
        if order.iter().enumerate().any(|(i, &o)| i != o) {
            positions = order.iter().map(|&i| positions[i]).collect();
            for (_, col) in &mut columns {
                *col = order.iter().map(|&i| col[i]).collect();
            }
        }
    }
    let mut table = ParticleTable {
        positions,
        columns,
        time: header.timestep.map(|t| t as f64),
        domain: header.sim_box.map(|b| (b.lo, b.hi)),
        periodic: header.sim_box.is_some_and(|b| b.periodic),
        rows: None,
        sph: None,
        ..Default::default()
    };
    table.derive_speed("vx", "vy", "vz");
    Ok(table)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orthogonal_unscale() {
        let edges = [[2.0, 0.0, 0.0], [0.0, 4.0, 0.0], [0.0, 0.0, 8.0]];
        assert_eq!(
            unscale([1.0, 2.0, 3.0], &edges, [0.5, 0.25, 1.0]),
            [2.0, 3.0, 11.0]
        );
    }

    #[test]
    fn triclinic_unscale_uses_tilts() {
        let edges = [[10.0, 0.0, 0.0], [2.0, 10.0, 0.0], [1.0, 3.0, 10.0]];
        assert_eq!(
            unscale([0.0; 3], &edges, [0.0, 1.0, 1.0]),
            [3.0, 13.0, 10.0]
        );
        assert_eq!(unscale([0.0; 3], &edges, [1.0, 0.0, 0.0]), [10.0, 0.0, 0.0]);
    }
}
