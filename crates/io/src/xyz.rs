//! XYZ files, plain and extended (extxyz), with one or more frames.
//!
//! Each frame is:
//!
//! ```text
//! 3                                   number of atoms
//! water molecule                      comment line (may be empty)
//! O  0.000  0.000  0.117              one line per atom
//! H  0.000  0.757 -0.467
//! H  0.000 -0.757 -0.467
//! ```
//!
//! and frames follow each other directly (blank lines between frames are
//! tolerated).
//!
//! **Plain XYZ.** Each atom line is `Element x y z [more numbers]`; every line
//! of a frame must have the same number of fields. Extra numeric fields become
//! columns named after their 0-based field index: `c4`, `c5`, ...
//!
//! **Extended XYZ.** When the comment line is a list of `key=value` pairs
//! (values may be `"quoted"`), these keys are used (case-insensitively):
//!
//! - `Properties=name:type:count:...` names the fields, e.g.
//!   `species:S:1:pos:R:3:vel:R:3:mass:R:1`. Types are `S` (string), `R`
//!   (real), `I` (integer) and `L` (logical, `T`/`F`). Positions come from
//!   `pos` (or `positions`). A property of count 1 becomes a column of its
//!   name; of count 3 it becomes `name_x`, `name_y`, `name_z`; of any other
//!   count `name0`, `name1`, ... Logical values become 1 and 0. String
//!   properties other than the species are skipped. A velocity property
//!   (`vel`, `velo`, `velocity`, `velocities`) also gives `speed`. Without
//!   `Properties`, the plain layout above applies.
//! - `Lattice="ax ay az bx by bz cx cy cz"` (cell vectors) gives the domain
//!   when the cell is orthogonal (off-diagonal entries zero): from `Origin`
//!   (three numbers, default 0) to `Origin` + the diagonal.
//! - `Time=t` gives the frame's time.
//!
//! **Species.** The element symbol (or `species` property) becomes a numeric
//! `type` column: 1, 2, ... in order of first appearance *in the file*
//! (frames before the one read included), so a symbol has the same number in
//! every frame of a file. The symbols are compared exactly (`Fe` and `FE`
//! differ); numeric symbols such as `1` are numbered like any other.
//!
//! **Streaming.** [`read_xyz`] skips the frames before the one asked for,
//! reading only their species fields.
//!
//! **From memory.** [`xyz_frames_from`], [`read_xyz_from`] and
//! [`xyz_species_from`] read from any reader (a `Cursor` over bytes, a file
//! already open); the path functions open the file and share their code.

use std::collections::HashMap;
use std::io::{BufRead, Read, Seek};
use std::path::Path;

use crate::{IoError, LineReader, ParticleTable};

/// Number of frames in an XYZ file.
///
/// Fails with [`IoError::Format`] if a count line is not a number or a frame
/// has fewer lines than its count.
pub fn xyz_frames(path: &Path) -> Result<usize, IoError> {
    count_frames(LineReader::open(path)?)
}

/// [`xyz_frames`] of the XYZ text `reader` yields; `name` only labels
/// errors, which read as [`xyz_frames`]'s for a file of that name.
pub fn xyz_frames_from<R: Read>(reader: R, name: &Path) -> Result<usize, IoError> {
    count_frames(LineReader::from_read(reader, name))
}

fn count_frames<R: BufRead>(mut lines: LineReader<R>) -> Result<usize, IoError> {
    let mut count = 0;
    while let Some(n) = read_count(&mut lines, count)? {
        read_comment(&mut lines, count, n)?;
        for found in 0..n {
            if lines.skip_line(b"")?.is_none() {
                return Err(truncated(&lines, count, n, found));
            }
        }
        count += 1;
    }
    if count == 0 {
        return Err(IoError::format(
            lines.path(),
            "not an XYZ file: it holds no frame",
        ));
    }
    Ok(count)
}

/// Reads frame `frame` (0-based) of a plain or extended XYZ file; see the
/// module docs for the accepted layout and the columns it gives.
///
/// Fails with [`IoError::Format`] if the frame does not exist (the message
/// says how many there are), a count line is not a number, the file ends
/// inside a frame, an atom line has the wrong number of fields or a field
/// that is not a number, or `Properties` is malformed or lacks `pos`.
pub fn read_xyz(path: &Path, frame: usize) -> Result<ParticleTable, IoError> {
    read_frame(LineReader::open(path)?, frame)
}

/// [`read_xyz`] of the XYZ text `reader` yields, from its position to its
/// end; `name` only labels errors, which read as [`read_xyz`]'s for a file
/// of that name. The reader's length caps what an atom count may make it
/// allocate, as the file's length does.
pub fn read_xyz_from<R: Read + Seek>(
    reader: R,
    name: &Path,
    frame: usize,
) -> Result<ParticleTable, IoError> {
    read_frame(LineReader::from_seek(reader, name)?, frame)
}

fn read_frame<R: BufRead>(
    mut lines: LineReader<R>,
    frame: usize,
) -> Result<ParticleTable, IoError> {
    // The frames before only number the species, so that a symbol gets the
    // same type in every frame.
    let mut species = Species::default();
    scan_species(&mut lines, frame, 0..frame, &mut species)?;
    let n = read_count(&mut lines, frame)?.ok_or_else(|| past_end(lines.path(), frame, frame))?;
    let comment = read_comment(&mut lines, frame, n)?;
    let table = read_atoms(&mut lines, frame, n, &comment, &mut species)?;
    // What follows must be the next frame's count (or the end): more atom
    // lines than the count said fail here as they do when frames are
    // counted, instead of being dropped without a word.
    read_count(&mut lines, frame + 1)?;
    Ok(table)
}

/// Reads frames `frames` past, numbering the species they use in order of
/// first appearance and parsing nothing else (`frame` is the frame asked
/// for, named in the error when the file ends first).
fn scan_species(
    lines: &mut LineReader<impl BufRead>,
    frame: usize,
    frames: std::ops::Range<usize>,
    species: &mut Species,
) -> Result<(), IoError> {
    for index in frames {
        let Some(n) = read_count(lines, index)? else {
            return Err(past_end(lines.path(), frame, index));
        };
        let comment = read_comment(lines, index, n)?;
        let layout = Layout::from_comment(&comment).map_err(|m| lines.error(m))?;
        for found in 0..n {
            let Some(line) = lines.next_line()? else {
                return Err(truncated(lines, index, n, found));
            };
            if let Some(s) = layout.species {
                let token = line.split_ascii_whitespace().nth(s).unwrap_or("");
                species.id(token);
            }
        }
    }
    Ok(())
}

/// The species symbols of frames 0 through `frame` of an XYZ file, in the
/// order of the numbers the `type` column gives them: symbol `i` (0-based)
/// is type `i + 1` in frame `frame` and every frame before it. Empty when the
/// file has no species field (extended XYZ without a species property).
///
/// Fails like [`read_xyz`] when the frame does not exist or the file ends
/// inside a frame.
pub fn xyz_species(path: &Path, frame: usize) -> Result<Vec<String>, IoError> {
    species_of(LineReader::open(path)?, frame)
}

/// [`xyz_species`] of the XYZ text `reader` yields; `name` only labels
/// errors, which read as [`xyz_species`]'s for a file of that name.
pub fn xyz_species_from<R: Read>(
    reader: R,
    name: &Path,
    frame: usize,
) -> Result<Vec<String>, IoError> {
    species_of(LineReader::from_read(reader, name), frame)
}

fn species_of<R: BufRead>(mut lines: LineReader<R>, frame: usize) -> Result<Vec<String>, IoError> {
    let mut species = Species::default();
    scan_species(&mut lines, frame, 0..frame + 1, &mut species)?;
    Ok(species.symbols())
}

/// Numbers species symbols 1, 2, ... in order of first appearance.
#[derive(Default)]
struct Species(HashMap<String, u32>);

impl Species {
    fn id(&mut self, symbol: &str) -> u32 {
        let next = self.0.len() as u32 + 1;
        *self.0.entry(symbol.to_string()).or_insert(next)
    }

    /// The symbols in the order of their numbers.
    fn symbols(self) -> Vec<String> {
        let mut v: Vec<(u32, String)> = self.0.into_iter().map(|(s, i)| (i, s)).collect();
        v.sort_unstable();
        v.into_iter().map(|(_, s)| s).collect()
    }
}

fn past_end(path: &Path, frame: usize, frames: usize) -> IoError {
    if frames == 0 {
        return IoError::format(path, "not an XYZ file: it holds no frame");
    }
    IoError::format(
        path,
        format!(
            "frame {frame} requested but the file has {frames} frame{} (numbered from 0)",
            if frames == 1 { "" } else { "s" }
        ),
    )
}

fn truncated(lines: &LineReader<impl BufRead>, frame: usize, n: usize, found: usize) -> IoError {
    lines.error(format!(
        "frame {frame} declares {n} atoms but the file ends after {found} atom line{}",
        if found == 1 { "" } else { "s" }
    ))
}

/// Reads the count line of a frame; `None` at the end of the file.
fn read_count(
    lines: &mut LineReader<impl BufRead>,
    frame: usize,
) -> Result<Option<usize>, IoError> {
    loop {
        let Some(line) = lines.next_line()? else {
            return Ok(None);
        };
        if line.is_empty() {
            continue;
        }
        // Some writers put more on the count line; the first field counts.
        let first = line.split_ascii_whitespace().next().unwrap_or("");
        return match first.parse::<usize>() {
            Ok(n) => Ok(Some(n)),
            Err(_) => {
                let shown: String = line.chars().take(60).collect();
                Err(lines.error(format!(
                    "expected the atom count of frame {frame} but found '{shown}'{}",
                    if frame == 0 {
                        " (not an XYZ file?)"
                    } else {
                        " (does the previous frame have more atom lines than its count?)"
                    }
                )))
            }
        };
    }
}

fn read_comment(
    lines: &mut LineReader<impl BufRead>,
    frame: usize,
    n: usize,
) -> Result<String, IoError> {
    match lines.next_line()? {
        Some(line) => Ok(line.to_string()),
        None => Err(lines.error(format!(
            "frame {frame} declares {n} atoms but the file ends before its comment line"
        ))),
    }
}

/// What a field group of an atom line holds.
#[derive(Debug, Clone, PartialEq)]
enum Kind {
    Species,
    Position,
    /// Numeric columns with these names.
    Numbers(Vec<String>),
    /// Logical (T/F) columns with these names.
    Logical(Vec<String>),
    /// String fields that are not kept.
    Skip,
}

/// The fields of the atom lines of one frame.
#[derive(Debug, Clone, PartialEq)]
struct Layout {
    /// Field groups with their first field index and width. `None` for a
    /// plain file, whose width comes from the first atom line.
    groups: Option<Vec<(Kind, usize, usize)>>,
    /// Field index of the species symbol, if any.
    species: Option<usize>,
    lattice: Option<[f64; 9]>,
    origin: [f64; 3],
    time: Option<f64>,
    /// `pbc="T T T"`: periodic along every lattice vector.
    pbc: bool,
    /// Names of velocity columns (x, y, z) for `speed`.
    velocity: Option<[String; 3]>,
}

impl Layout {
    fn from_comment(comment: &str) -> Result<Layout, String> {
        let pairs = key_values(comment);
        let get = |key: &str| {
            pairs
                .iter()
                .find(|(k, _)| k.eq_ignore_ascii_case(key))
                .map(|(_, v)| v.as_str())
        };
        let numbers = |key: &str, count: usize| -> Result<Option<Vec<f64>>, String> {
            let Some(text) = get(key) else {
                return Ok(None);
            };
            let values: Result<Vec<f64>, _> =
                text.split_ascii_whitespace().map(str::parse).collect();
            match values {
                Ok(v) if v.len() == count => Ok(Some(v)),
                _ => Err(format!(
                    "comment line: {key}=\"{text}\" must hold {count} numbers"
                )),
            }
        };
        let lattice = numbers("Lattice", 9)?.map(|v| {
            let mut l = [0.0; 9];
            l.copy_from_slice(&v);
            l
        });
        let origin = numbers("Origin", 3)?.map_or([0.0; 3], |v| [v[0], v[1], v[2]]);
        let time = match get("Time") {
            Some(t) => Some(
                t.parse::<f64>()
                    .map_err(|_| format!("comment line: cannot parse Time={t} as a number"))?,
            ),
            None => None,
        };
        let mut layout = Layout {
            groups: None,
            species: Some(0),
            lattice,
            origin,
            time,
            pbc: get("pbc").is_some_and(|v| {
                let f: Vec<&str> = v.split_ascii_whitespace().collect();
                f.len() == 3
                    && f.iter()
                        .all(|t| t.eq_ignore_ascii_case("t") || t.eq_ignore_ascii_case("true"))
            }),
            velocity: None,
        };
        if let Some(props) = get("Properties") {
            layout.parse_properties(props)?;
        }
        Ok(layout)
    }

    /// Parses `name:type:count:name:type:count:...`.
    fn parse_properties(&mut self, props: &str) -> Result<(), String> {
        let bad = |why: String| format!("comment line: Properties={props}: {why}");
        let parts: Vec<&str> = props.split(':').collect();
        if !parts.len().is_multiple_of(3) || parts.is_empty() {
            return Err(bad("expected name:type:count triples".into()));
        }
        let mut groups = Vec::new();
        let mut start = 0usize;
        let mut species = None;
        let mut position = false;
        for triple in parts.chunks(3) {
            let (name, ty) = (triple[0], triple[1].to_ascii_uppercase());
            let count: usize = triple[2]
                .parse()
                .ok()
                .filter(|&c| (1..=64).contains(&c))
                .ok_or_else(|| bad(format!("bad count '{}' for '{name}'", triple[2])))?;
            let lower = name.to_ascii_lowercase();
            let names = || -> Vec<String> {
                match count {
                    1 => vec![name.to_string()],
                    3 => ["x", "y", "z"]
                        .iter()
                        .map(|a| format!("{name}_{a}"))
                        .collect(),
                    _ => (0..count).map(|i| format!("{name}{i}")).collect(),
                }
            };
            let kind = match (ty.as_str(), lower.as_str()) {
                ("S", "species" | "element" | "symbol" | "elem")
                    if species.is_none() && count == 1 =>
                {
                    species = Some(start);
                    Kind::Species
                }
                ("R", "pos" | "positions" | "position") if count == 3 && !position => {
                    position = true;
                    Kind::Position
                }
                ("S", _) => Kind::Skip,
                ("R" | "I", _) => {
                    let n = names();
                    if count == 3
                        && matches!(lower.as_str(), "vel" | "velo" | "velocity" | "velocities")
                        && self.velocity.is_none()
                    {
                        self.velocity = Some([n[0].clone(), n[1].clone(), n[2].clone()]);
                    }
                    Kind::Numbers(n)
                }
                ("L", _) => Kind::Logical(names()),
                _ => return Err(bad(format!("unknown type '{}' for '{name}'", triple[1]))),
            };
            groups.push((kind, start, count));
            start += count;
        }
        if !position {
            let names: Vec<&str> = parts.chunks(3).map(|t| t[0]).collect();
            return Err(bad(format!(
                "no 'pos:R:3' property (properties: {})",
                names.join(", ")
            )));
        }
        self.groups = Some(groups);
        self.species = species;
        Ok(())
    }

    /// The domain from an orthogonal lattice.
    fn domain(&self) -> Option<([f64; 3], [f64; 3])> {
        let l = self.lattice?;
        let diag = [l[0], l[4], l[8]];
        let scale = diag.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let off = [l[1], l[2], l[3], l[5], l[6], l[7]];
        if scale == 0.0 || off.iter().any(|v| v.abs() > 1e-9 * scale) {
            return None;
        }
        let mut lo = self.origin;
        let mut hi = self.origin;
        for k in 0..3 {
            let end = self.origin[k] + diag[k];
            lo[k] = lo[k].min(end);
            hi[k] = hi[k].max(end);
        }
        Some((lo, hi))
    }
}

/// Splits an extended-XYZ comment into `key=value` pairs. Values may be
/// quoted with `"` (the quotes are removed); a key without `=` gets `T`.
fn key_values(comment: &str) -> Vec<(String, String)> {
    let mut pairs = Vec::new();
    let mut chars = comment.chars().peekable();
    loop {
        while chars.next_if(|c| c.is_whitespace()).is_some() {}
        if chars.peek().is_none() {
            break;
        }
        let mut key = String::new();
        while let Some(c) = chars.next_if(|c| !c.is_whitespace() && *c != '=') {
            key.push(c);
        }
        while chars.next_if(|c| c.is_whitespace()).is_some() {}
        if chars.next_if_eq(&'=').is_none() {
            if key.is_empty() {
                chars.next();
            } else {
                pairs.push((key, "T".to_string()));
            }
            continue;
        }
        while chars.next_if(|c| c.is_whitespace()).is_some() {}
        let mut value = String::new();
        if let Some(quote) = chars.next_if(|c| *c == '"' || *c == '\'' || *c == '{') {
            let close = if quote == '{' { '}' } else { quote };
            for c in chars.by_ref() {
                if c == close {
                    break;
                }
                value.push(c);
            }
        } else {
            while let Some(c) = chars.next_if(|c| !c.is_whitespace()) {
                value.push(c);
            }
        }
        pairs.push((key, value));
    }
    pairs
}

/// Parses the atom lines of one frame.
fn read_atoms(
    lines: &mut LineReader<impl BufRead>,
    frame: usize,
    n: usize,
    comment: &str,
    species: &mut Species,
) -> Result<ParticleTable, IoError> {
    let layout = Layout::from_comment(comment).map_err(|m| lines.error(m))?;
    // Each atom line takes at least 8 bytes ("H 0 0 0\n").
    let max_rows = usize::try_from(lines.remaining_bytes() / 8).unwrap_or(usize::MAX);
    let capacity = n.min(max_rows);
    let mut positions = Vec::with_capacity(capacity);
    let mut types: Vec<f32> = Vec::new();
    let mut columns: Vec<(String, Vec<f32>)> = Vec::new();
    // Per field: which column it feeds (None = skipped), and how to read it.
    let mut plan: Vec<Field> = Vec::new();
    let path = lines.path().to_path_buf();
    let at = |line_no: usize, message: String| {
        IoError::format(&path, format!("line {line_no}: frame {frame}: {message}"))
    };

    for row in 0..n {
        let line_no = lines.line_no() + 1;
        let Some(line) = lines.next_line()? else {
            return Err(truncated(lines, frame, n, row));
        };
        if row == 0 {
            plan = field_plan(&layout, line.split_ascii_whitespace().count())
                .map_err(|m| at(line_no, m))?;
            if layout.species.is_some() {
                types.reserve(capacity);
            }
            for f in &plan {
                if let Field::Column(_, name, _) = f {
                    columns.push((name.clone(), Vec::with_capacity(capacity)));
                }
            }
        }
        let mut pos = [0.0f64; 3];
        let mut count = 0;
        for (i, field) in line.split_ascii_whitespace().enumerate() {
            count += 1;
            let Some(action) = plan.get(i) else {
                continue;
            };
            let number = || {
                field.parse::<f64>().map_err(|_| {
                    let shown: String = field.chars().take(40).collect();
                    at(
                        line_no,
                        format!(
                            "field {} ({}): cannot parse '{shown}' as a number",
                            i + 1,
                            action.name()
                        ),
                    )
                })
            };
            match action {
                Field::Species => types.push(species.id(field) as f32),
                Field::Position(k) => pos[*k] = number()?,
                Field::Column(c, _, false) => columns[*c].1.push(number()? as f32),
                Field::Column(c, _, true) => {
                    let v = match field {
                        "T" | "t" | "True" | "true" | "1" => 1.0,
                        "F" | "f" | "False" | "false" | "0" => 0.0,
                        _ => {
                            return Err(at(
                                line_no,
                                format!("field {}: '{field}' is not a logical (T/F)", i + 1),
                            ));
                        }
                    };
                    columns[*c].1.push(v);
                }
                Field::Skip => {}
            }
        }
        if count != plan.len() {
            return Err(at(
                line_no,
                format!(
                    "expected {} fields per atom line (as on the frame's first atom line or in \
                     Properties) but found {count}",
                    plan.len()
                ),
            ));
        }
        positions.push([pos[0], pos[1], pos[2]]);
    }

    if layout.species.is_some() && n > 0 {
        columns.insert(0, ("type".to_string(), types));
    }
    let mut table = ParticleTable {
        positions,
        columns,
        time: layout.time,
        domain: layout.domain(),
        periodic: layout.pbc && layout.domain().is_some(),
        rows: None,
        sph: None,
        ..Default::default()
    };
    if let Some([x, y, z]) = &layout.velocity {
        table.derive_speed(x, y, z);
    }
    Ok(table)
}

/// What to do with one field of an atom line.
#[derive(Debug, Clone, PartialEq)]
enum Field {
    Species,
    Position(usize),
    /// Column index, name, logical?
    Column(usize, String, bool),
    Skip,
}

impl Field {
    fn name(&self) -> &str {
        match self {
            Field::Species => "species",
            Field::Position(0) => "x",
            Field::Position(1) => "y",
            Field::Position(_) => "z",
            Field::Column(_, name, _) => name,
            Field::Skip => "skipped",
        }
    }
}

/// The per-field plan for a frame, given the field count of its first line.
fn field_plan(layout: &Layout, first_line_fields: usize) -> Result<Vec<Field>, String> {
    let mut plan = Vec::new();
    let mut next_col = 0;
    match &layout.groups {
        None => {
            if first_line_fields < 4 {
                return Err(format!(
                    "an atom line needs at least 4 fields (element x y z) but the first has \
                     {first_line_fields}"
                ));
            }
            plan.push(Field::Species);
            plan.extend((0..3).map(Field::Position));
            for i in 4..first_line_fields {
                plan.push(Field::Column(next_col, format!("c{i}"), false));
                next_col += 1;
            }
        }
        Some(groups) => {
            for (kind, _, width) in groups {
                match kind {
                    Kind::Species => plan.push(Field::Species),
                    Kind::Position => plan.extend((0..3).map(Field::Position)),
                    Kind::Numbers(names) | Kind::Logical(names) => {
                        let logical = matches!(kind, Kind::Logical(_));
                        for name in names {
                            plan.push(Field::Column(next_col, name.clone(), logical));
                            next_col += 1;
                        }
                    }
                    Kind::Skip => plan.extend((0..*width).map(|_| Field::Skip)),
                }
            }
        }
    }
    Ok(plan)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn comment_pairs() {
        let p = key_values(
            r#"Lattice="1 0 0 0 2 0 0 0 3" Properties=species:S:1:pos:R:3 pbc="T T T" flag Time = 2.5"#,
        );
        let keys: Vec<&str> = p.iter().map(|(k, _)| k.as_str()).collect();
        assert_eq!(keys, ["Lattice", "Properties", "pbc", "flag", "Time"]);
        assert_eq!(p[0].1, "1 0 0 0 2 0 0 0 3");
        assert_eq!(p[3].1, "T");
        assert_eq!(p[4].1, "2.5");
        assert!(key_values("just a title").iter().all(|(_, v)| v == "T"));
    }

    #[test]
    fn properties_layout() {
        let l =
            Layout::from_comment("Properties=pos:R:3:species:S:1:vel:R:3:fix:L:1:tag:S:1:f:R:2")
                .unwrap();
        assert_eq!(l.species, Some(3));
        assert_eq!(
            l.velocity,
            Some(["vel_x".to_string(), "vel_y".into(), "vel_z".into()])
        );
        let plan = field_plan(&l, 0).unwrap();
        assert_eq!(plan.len(), 11);
        assert_eq!(plan[4], Field::Column(0, "vel_x".into(), false));
        assert_eq!(plan[7], Field::Column(3, "fix".into(), true));
        assert_eq!(plan[8], Field::Skip);
        assert_eq!(plan[10], Field::Column(5, "f1".into(), false));
        assert!(Layout::from_comment("Properties=species:S:1:mass:R:1").is_err());
        assert!(Layout::from_comment("Properties=pos:R").is_err());
    }

    #[test]
    fn lattice_domain() {
        let l = Layout::from_comment(r#"Lattice="2 0 0 0 3 0 0 0 4" Origin="1 1 1""#).unwrap();
        assert_eq!(l.domain(), Some(([1.0; 3], [3.0, 4.0, 5.0])));
        let tilted = Layout::from_comment(r#"Lattice="2 0 0 1 3 0 0 0 4""#).unwrap();
        assert_eq!(tilted.domain(), None);
    }
}
