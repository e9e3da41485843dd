//! The record structure of one Gadget binary file: its byte order and
//! format, its header, the list of its blocks, and what each block holds.
//!
//! Scanning a file reads only the record markers (and format 2's labels),
//! seeking over the data, so it costs a few small reads per block whatever
//! the file's size.

use std::fs::File;
use std::io::{ErrorKind, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use super::GadgetHeader;
use crate::snapshot::part_type_label;
use crate::{IoError, open_with_len, remaining_len};

/// Most blocks a file may have. Real snapshots have a few dozen at most;
/// more means the records are not Gadget blocks, and the cap keeps the
/// block list small whatever the input.
const MAX_BLOCKS: usize = 1024;

/// Bytes of the header block.
const HEADER_LEN: u64 = 256;

/// Byte order of a file's numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Endian {
    Little,
    Big,
}

impl Endian {
    pub(super) fn u32(self, b: [u8; 4]) -> u32 {
        match self {
            Endian::Little => u32::from_le_bytes(b),
            Endian::Big => u32::from_be_bytes(b),
        }
    }

    pub(super) fn u64(self, b: [u8; 8]) -> u64 {
        match self {
            Endian::Little => u64::from_le_bytes(b),
            Endian::Big => u64::from_be_bytes(b),
        }
    }

    pub(super) fn f64(self, b: [u8; 8]) -> f64 {
        f64::from_bits(self.u64(b))
    }
}

/// The format (1 or 2) and byte order the first record marker shows: the
/// header's size, 256, in format 1, or a label record's, 8, in format 2,
/// read either way round.
pub(super) fn detect(first: [u8; 4]) -> Option<(u8, Endian)> {
    [Endian::Little, Endian::Big]
        .into_iter()
        .find_map(|e| match e.u32(first) {
            256 => Some((1, e)),
            8 => Some((2, e)),
            _ => None,
        })
}

/// See [`super::sniff_gadget_binary`]: the whole header record must be
/// there with matching markers.
pub(super) fn sniff(head: &[u8]) -> bool {
    let word = |at: usize| -> Option<[u8; 4]> { head.get(at..at + 4)?.try_into().ok() };
    let Some((format, endian)) = word(0).and_then(detect) else {
        return false;
    };
    let marker = |at: usize| word(at).map(|w| endian.u32(w));
    match format {
        1 => marker(260) == Some(256),
        _ => marker(12) == Some(8) && marker(16) == Some(256) && marker(276) == Some(256),
    }
}

/// Bytes to read from: a file, or a reader from its position to its end.
/// Offsets are counted from that start; `name` labels errors.
pub(super) struct Source<R> {
    reader: R,
    base: u64,
    len: u64,
    pub(super) name: PathBuf,
}

impl Source<File> {
    pub(super) fn open(path: &Path) -> Result<Self, IoError> {
        let (reader, len) = open_with_len(path)?;
        Ok(Source {
            reader,
            base: 0,
            len,
            name: path.to_path_buf(),
        })
    }
}

impl<R: Read + Seek> Source<R> {
    pub(super) fn from_reader(mut reader: R, name: &Path) -> Result<Self, IoError> {
        let base = reader.stream_position().map_err(|e| IoError::io(name, e))?;
        let len = remaining_len(&mut reader, name)?;
        Ok(Source {
            reader,
            base,
            len,
            name: name.to_path_buf(),
        })
    }

    pub(super) fn err(&self, message: impl Into<String>) -> IoError {
        IoError::format(&self.name, message)
    }

    /// Fills `buf` from `offset`; running out of data is a format error
    /// naming `what`.
    pub(super) fn read_at(
        &mut self,
        offset: u64,
        buf: &mut [u8],
        what: &str,
    ) -> Result<(), IoError> {
        let fits = offset
            .checked_add(buf.len() as u64)
            .is_some_and(|end| end <= self.len);
        if !fits {
            return Err(self.err(format!("file ends inside {what}")));
        }
        let io = |e| IoError::io(&self.name, e);
        self.reader
            .seek(SeekFrom::Start(self.base.saturating_add(offset)))
            .map_err(io)?;
        self.reader.read_exact(buf).map_err(|e| match e.kind() {
            // The length was checked; the data shrank under us.
            ErrorKind::UnexpectedEof => {
                IoError::format(&self.name, format!("file ends inside {what}"))
            }
            _ => IoError::io(&self.name, e),
        })
    }

    fn word(&mut self, offset: u64, endian: Endian, what: &str) -> Result<u32, IoError> {
        let mut b = [0u8; 4];
        self.read_at(offset, &mut b, what)?;
        Ok(endian.u32(b))
    }

    /// The Fortran record at `at` (`n | n bytes | n`): its data's offset
    /// and size, and where the next record starts. `what` names it in
    /// errors.
    fn record(&mut self, at: u64, endian: Endian, what: &str) -> Result<(u64, u64, u64), IoError> {
        let size = u64::from(self.word(at, endian, &format!("the record marker before {what}"))?);
        let data = at + 4;
        let left = self.len.saturating_sub(data);
        // The block and its trailing marker must both be there.
        if size.saturating_add(4) > left {
            return Err(self.err(format!(
                "{what}: the record marker says {size} bytes, but only {} follow (truncated file?)",
                left.saturating_sub(4)
            )));
        }
        let trailing = u64::from(self.word(
            data + size,
            endian,
            &format!("the record marker after {what}"),
        )?);
        if trailing != size {
            return Err(self.err(format!(
                "{what}: record markers disagree: {size} bytes before the block, {trailing} after \
                 (corrupt file?)"
            )));
        }
        Ok((data, size, data + size + 4))
    }
}

/// One block of a file: where its data starts and how long it is.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Block {
    /// The label without trailing blanks ("POS", "U"); in format 1 the
    /// inferred one, or "record N" for a record past the known ones.
    pub label: String,
    pub offset: u64,
    pub size: u64,
    /// Whether the label is the file's (format 2) or a known inferred one,
    /// i.e. whether it says what the block holds.
    pub named: bool,
}

/// The structure of one file.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Layout {
    pub format: u8,
    pub endian: Endian,
    pub header: GadgetHeader,
    /// `num_files` as stored (≤ 0 in some single-file snapshots).
    pub num_files: i32,
    /// The header block first.
    pub blocks: Vec<Block>,
}

/// Reads the record structure of `src`: only the header block when
/// `header_only`, else every block to the end of the file.
pub(super) fn scan<R: Read + Seek>(
    src: &mut Source<R>,
    header_only: bool,
) -> Result<Layout, IoError> {
    if src.len < 4 {
        return Err(src.err(format!(
            "not a Gadget binary file: only {} bytes long",
            src.len
        )));
    }
    let mut first = [0u8; 4];
    src.read_at(0, &mut first, "the first record marker")?;
    let Some((format, endian)) = detect(first) else {
        return Err(src.err(format!(
            "not a Gadget binary file: it starts with {:02x?}, not a record marker of 256 (a \
             format-1 header) or 8 (a format-2 block label) in either byte order",
            first
        )));
    };
    // Format 2: a label record before every block.
    let labelled = |src: &mut Source<R>, at: u64, prev: Option<&Block>| {
        let what = match prev {
            None => "the first label record".to_string(),
            Some(b) => format!("the label record after block {}", b.label),
        };
        let (data, size, next) = src.record(at, endian, &what)?;
        if size != 8 {
            return Err(src.err(format!(
                "{what} (at byte {at}) is {size} bytes long, not 8 (a format-2 label record \
                 holds a 4-character block name and the next block's size)"
            )));
        }
        let mut raw = [0u8; 4];
        src.read_at(data, &mut raw, &what)?;
        // The size that follows the name repeats the block's own
        // markers, which are checked instead.
        Ok((label_text(raw), next))
    };

    // The header.
    let (label, start) = match format {
        2 => labelled(src, 0, None)?,
        _ => ("HEAD".to_string(), 0),
    };
    let (offset, size, mut at) = src.record(start, endian, &format!("block {label}"))?;
    if size != HEADER_LEN {
        return Err(src.err(format!(
            "block {label}: the header record is {size} bytes, not {HEADER_LEN}"
        )));
    }
    let mut bytes = [0u8; HEADER_LEN as usize];
    src.read_at(offset, &mut bytes, "the header")?;
    let (header, num_files, flag_cooling) = parse_header(&bytes, endian);
    let mut blocks = vec![Block {
        label,
        offset,
        size,
        named: true,
    }];

    // The other blocks, to the end of the file.
    let order = format1_order(&header, flag_cooling);
    while !header_only && at < src.len {
        if blocks.len() >= MAX_BLOCKS {
            return Err(src.err(format!(
                "more than {MAX_BLOCKS} blocks: not a Gadget snapshot (corrupt record markers?)"
            )));
        }
        let block = if format == 2 {
            let (label, start) = labelled(src, at, blocks.last())?;
            let (offset, size, next) = src.record(start, endian, &format!("block {label}"))?;
            at = next;
            Block {
                label,
                offset,
                size,
                named: true,
            }
        } else {
            // Named by its place in Gadget-2's order, if it has one.
            let record = blocks.len() + 1;
            let what = match order.get(blocks.len() - 1) {
                Some((label, _)) => format!("block {label} (record {record})"),
                None => format!("record {record}"),
            };
            let (offset, size, next) = src.record(at, endian, &what)?;
            at = next;
            Block {
                label: format!("record {record}"),
                offset,
                size,
                named: false,
            }
        };
        blocks.push(block);
    }
    if format == 1 {
        name_format1(&mut blocks, &order, header.npart[0]);
    }
    Ok(Layout {
        format,
        endian,
        header,
        num_files,
        blocks,
    })
}

/// A label as text without trailing blanks; bytes that are not printable
/// ASCII show as `?`.
fn label_text(raw: [u8; 4]) -> String {
    let text: String = raw
        .iter()
        .map(|&b| {
            if b.is_ascii_graphic() || b == b' ' {
                b as char
            } else {
                '?'
            }
        })
        .collect();
    text.trim_end().to_string()
}

/// The header's fields (Gadget-2 user guide, table 4), plus the stored
/// `num_files` and `flag_cooling`.
fn parse_header(b: &[u8; 256], e: Endian) -> (GadgetHeader, i32, i32) {
    let w4 = |at: usize| [b[at], b[at + 1], b[at + 2], b[at + 3]];
    let w8 = |at: usize| {
        let mut w = [0u8; 8];
        w.copy_from_slice(&b[at..at + 8]);
        w
    };
    let u32s = |at: usize| std::array::from_fn::<u32, 6, _>(|t| e.u32(w4(at + 4 * t)));
    let f64_at = |at: usize| e.f64(w8(at));
    let npart = u32s(0);
    let total_low = u32s(96);
    let total_high = u32s(168);
    let num_files = e.u32(w4(124)) as i32;
    let flag_cooling = e.u32(w4(120)) as i32;
    let header = GadgetHeader {
        npart,
        mass: std::array::from_fn(|t| f64_at(24 + 8 * t)),
        time: f64_at(72),
        redshift: f64_at(80),
        npart_total: std::array::from_fn(|t| {
            u64::from(total_low[t]) | (u64::from(total_high[t]) << 32)
        }),
        num_files: num_files.max(0) as u32,
        box_size: f64_at(128),
        omega0: f64_at(136),
        omega_lambda: f64_at(144),
        hubble: f64_at(152),
    };
    (header, num_files, flag_cooling)
}

/// The blocks of a format-1 file after the header, in Gadget-2's fixed
/// order: POS, VEL, ID, MASS (when a type with particles has no mass in the
/// mass table), then for gas U, RHO, NE and NH (with cooling), HSML. The
/// flag marks gas blocks, which are only there while the records have
/// their size.
fn format1_order(header: &GadgetHeader, flag_cooling: i32) -> Vec<(&'static str, bool)> {
    let mut order = vec![("POS", false), ("VEL", false), ("ID", false)];
    if (0..6).any(|t| header.npart[t] > 0 && header.mass[t] == 0.0) {
        order.push(("MASS", false));
    }
    if header.npart[0] > 0 {
        order.extend([("U", true), ("RHO", true)]);
        if flag_cooling != 0 {
            order.extend([("NE", true), ("NH", true)]);
        }
        order.push(("HSML", true));
    }
    order
}

/// Names the records of a format-1 file by `order`; the records after the
/// first that does not fit stay unnamed.
fn name_format1(blocks: &mut [Block], order: &[(&str, bool)], gas: u32) {
    let gas = u64::from(gas);
    for (block, (label, gas_only)) in blocks.iter_mut().skip(1).zip(order) {
        if *gas_only && block.size != gas * 4 && block.size != gas * 8 {
            break;
        }
        block.label = (*label).to_string();
        block.named = true;
    }
}

/// What a block means to the reader.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    Positions,
    Velocities,
    Ids,
    Masses,
    /// Any other per-particle quantity, a column named after the block.
    Column,
}

/// A per-particle block: which types it holds and how its values are laid
/// out.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Field {
    pub kind: Kind,
    /// The block's label ("RHO").
    pub label: String,
    /// The column name ("Density"; `vx` etc. for velocities).
    pub name: String,
    /// The types the block holds, one after the other in type order.
    pub types: [bool; 6],
    /// Values per particle: 1, or 3 for vectors.
    pub comps: u64,
    /// Bytes per value: 4 or 8.
    pub width: u64,
    /// The block's data: offset in the file and size.
    pub offset: u64,
    pub size: u64,
}

impl Field {
    /// Byte offset in the block of type `t`'s first particle. At most
    /// 6 × (2³² − 1) × 3 × 8 bytes: no overflow in u64.
    pub(super) fn start(&self, npart: &[u32; 6], t: usize) -> u64 {
        let before: u64 = (0..t)
            .filter(|&u| self.types[u])
            .map(|u| u64::from(npart[u]))
            .sum();
        before * self.comps * self.width
    }
}

/// Which types a known block holds.
#[derive(Clone, Copy)]
enum Set {
    All,
    Gas,
    /// The types with particles and no mass in the mass table.
    MassTypes,
}

/// The blocks the reader knows: label, meaning, column name, types, values
/// per particle. Gas blocks may also hold every type (some writers do).
const KNOWN: [(&str, Kind, &str, Set, u64); 10] = [
    ("POS", Kind::Positions, "Coordinates", Set::All, 3),
    ("VEL", Kind::Velocities, "Velocities", Set::All, 3),
    ("ID", Kind::Ids, "ParticleIDs", Set::All, 1),
    ("MASS", Kind::Masses, "Masses", Set::MassTypes, 1),
    ("U", Kind::Column, "InternalEnergy", Set::Gas, 1),
    ("RHO", Kind::Column, "Density", Set::Gas, 1),
    ("HSML", Kind::Column, "SmoothingLength", Set::Gas, 1),
    ("NE", Kind::Column, "ElectronAbundance", Set::Gas, 1),
    ("NH", Kind::Column, "NeutralHydrogenAbundance", Set::Gas, 1),
    ("POT", Kind::Column, "Potential", Set::All, 1),
];

/// Rank of a known column in a table, for the documented column order
/// (other blocks follow in file order).
pub(super) fn column_rank(field: &Field) -> usize {
    match field.kind {
        Kind::Masses => 0,
        Kind::Ids => 1,
        Kind::Velocities => 2,
        _ => match field.label.as_str() {
            "U" => 3,
            "RHO" => 4,
            "HSML" => 5,
            _ => 6,
        },
    }
}

/// What `block` holds in a file whose header has these counts and masses:
/// `None` for the header and for blocks that are not per-particle data the
/// reader understands; an error message when a known block's size does not
/// fit its particles.
pub(super) fn classify(
    block: &Block,
    npart: &[u32; 6],
    mass: &[f64; 6],
) -> Result<Option<Field>, String> {
    if !block.named || block.label == "HEAD" {
        return Ok(None);
    }
    let set = |s: Set| -> [bool; 6] {
        match s {
            Set::All => [true; 6],
            Set::Gas => std::array::from_fn(|t| t == 0),
            Set::MassTypes => std::array::from_fn(|t| npart[t] > 0 && mass[t] == 0.0),
        }
    };
    let count = |types: &[bool; 6]| -> u64 {
        (0..6)
            .filter(|&t| types[t])
            .map(|t| u64::from(npart[t]))
            .sum()
    };
    // The value width that makes `types` × `comps` values fill the block.
    let width = |types: &[bool; 6], comps: u64| -> Option<u64> {
        let values = count(types) * comps;
        [4, 8].into_iter().find(|w| values * w == block.size)
    };
    let field = |kind, name: String, types, comps, width| Field {
        kind,
        label: block.label.clone(),
        name,
        types,
        comps,
        width,
        offset: block.offset,
        size: block.size,
    };
    if let Some(&(_, kind, name, s, comps)) = KNOWN.iter().find(|k| k.0 == block.label) {
        let mut tries = vec![set(s)];
        if matches!(s, Set::Gas) {
            tries.push(set(Set::All));
        }
        for types in tries {
            if let Some(w) = width(&types, comps) {
                return Ok(Some(field(kind, name.to_string(), types, comps, w)));
            }
        }
        let types = set(s);
        let values = count(&types) * comps;
        let per = if comps == 3 { " × 3 values" } else { "" };
        return Err(format!(
            "block {}: {} bytes, but {} particles ({}){per} need {} (4-byte values) or {} \
             (8-byte values)",
            block.label,
            block.size,
            count(&types),
            type_list(&types),
            values * 4,
            values * 8
        ));
    }
    // Another label: a column named after it when its size fits one or
    // three values per particle of every type, or of gas (in that order).
    let usable = !block.label.is_empty()
        && block
            .label
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if !usable {
        return Ok(None);
    }
    for (s, comps) in [(Set::All, 1), (Set::Gas, 1), (Set::All, 3), (Set::Gas, 3)] {
        let types = set(s);
        if count(&types) > 0
            && let Some(w) = width(&types, comps)
        {
            return Ok(Some(field(
                Kind::Column,
                block.label.clone(),
                types,
                comps,
                w,
            )));
        }
    }
    Ok(None)
}

/// "all types", "type 0 (gas)", "types 0 (gas), 1 (dm)".
fn type_list(types: &[bool; 6]) -> String {
    if types.iter().all(|&t| t) {
        return "all types".into();
    }
    let names: Vec<String> = (0..6u32)
        .filter(|&t| types[t as usize])
        .map(part_type_label)
        .collect();
    match names.len() {
        0 => "no types".into(),
        1 => format!("type {}", names[0]),
        _ => format!("types {}", names.join(", ")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block(label: &str, size: u64) -> Block {
        Block {
            label: label.into(),
            offset: 0,
            size,
            named: true,
        }
    }

    #[test]
    fn detects_format_and_byte_order() {
        assert_eq!(detect(256u32.to_le_bytes()), Some((1, Endian::Little)));
        assert_eq!(detect(256u32.to_be_bytes()), Some((1, Endian::Big)));
        assert_eq!(detect(8u32.to_le_bytes()), Some((2, Endian::Little)));
        assert_eq!(detect(8u32.to_be_bytes()), Some((2, Endian::Big)));
        assert_eq!(detect(12u32.to_le_bytes()), None);
    }

    #[test]
    fn blocks_are_classified_by_label_and_size() {
        let npart = [2, 3, 0, 0, 0, 0];
        let mass = [0.0, 1.5, 0.0, 0.0, 0.0, 0.0];
        let f = classify(&block("POS", 60), &npart, &mass).unwrap().unwrap();
        assert_eq!((f.kind, f.width, f.comps), (Kind::Positions, 4, 3));
        assert_eq!(f.start(&npart, 1), 24);
        let f = classify(&block("POS", 120), &npart, &mass)
            .unwrap()
            .unwrap();
        assert_eq!(f.width, 8);
        let e = classify(&block("POS", 61), &npart, &mass).unwrap_err();
        assert!(e.contains("block POS: 61 bytes") && e.contains("60"), "{e}");
        // Only the gas has no mass-table entry.
        let f = classify(&block("MASS", 8), &npart, &mass).unwrap().unwrap();
        assert_eq!(f.types, [true, false, false, false, false, false]);
        // HSML for every type rather than gas only.
        let f = classify(&block("HSML", 20), &npart, &mass)
            .unwrap()
            .unwrap();
        assert_eq!(f.types, [true; 6]);
        // Unknown labels: by size, else skipped.
        let f = classify(&block("ACCE", 60), &npart, &mass)
            .unwrap()
            .unwrap();
        assert_eq!(
            (f.kind, f.comps, f.name.as_str()),
            (Kind::Column, 3, "ACCE")
        );
        assert_eq!(classify(&block("JUNK", 7), &npart, &mass), Ok(None));
        assert_eq!(classify(&block("a b", 20), &npart, &mass), Ok(None));
    }

    #[test]
    fn sniffing_needs_the_whole_header_record() {
        let mut f1 = vec![0u8; 300];
        f1[..4].copy_from_slice(&256u32.to_le_bytes());
        f1[260..264].copy_from_slice(&256u32.to_le_bytes());
        assert!(sniff(&f1));
        assert!(!sniff(&f1[..263]));
        let mut f2 = vec![0u8; 300];
        f2[..4].copy_from_slice(&8u32.to_be_bytes());
        f2[4..8].copy_from_slice(b"HEAD");
        f2[12..16].copy_from_slice(&8u32.to_be_bytes());
        f2[16..20].copy_from_slice(&256u32.to_be_bytes());
        f2[276..280].copy_from_slice(&256u32.to_be_bytes());
        assert!(sniff(&f2));
        f2[276] = 1;
        assert!(!sniff(&f2));
        assert!(!sniff(b"\x93NUMPY"));
    }
}
