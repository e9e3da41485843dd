//! Tipsy snapshots, the binary format of ChaNGa, Gasoline and PKDGRAV.
//!
//! A file is a header and three arrays of fixed-size records, gas first,
//! then dark matter, then stars (the layout pynbody's `tipsy.py` and yt's
//! Tipsy frontend read):
//!
//! ```text
//! header  double time; int nbodies, ndim, nsph, ndark, nstar; [int pad]
//! gas     nsph  × float mass, x, y, z, vx, vy, vz, rho, temp, hsmooth, metals, phi
//! dark    ndark × float mass, x, y, z, vx, vy, vz, eps, phi
//! star    nstar × float mass, x, y, z, vx, vy, vz, metals, tform, eps, phi
//! ```
//!
//! Nothing in the file names its variant, so the reader works it out:
//!
//! - Byte order: "standard" Tipsy is big-endian (XDR), "native" Tipsy the
//!   writing machine's order (little-endian in practice). `ndim` is 3, so
//!   it reads as 3 in exactly one of the two orders.
//! - Header size: C compilers pad the 28-byte header struct to 32 bytes
//!   (pynbody, ChaNGa and yt write and expect the 4 pad bytes), but some
//!   writers omit them.
//! - Precision: ChaNGa built with double positions (`bDoublePos`) stores x,
//!   y, z as float64, which adds 12 bytes to every record; with double
//!   velocities too (`bDoubleVel`), 24.
//!
//! The header's counts must add up (`nbodies = nsph + ndark + nstar`), and
//! the file's length must equal the header plus the records of exactly one
//! of these layouts, as yt requires: no extra bytes are tolerated, since a
//! length that fits no layout means the counts or the variant are not what
//! the reader assumes. (Double velocities without double positions give
//! the same length as double positions alone and are read as the latter.)
//! pynbody's extension that keeps bits 32–39 of the counts in the pad
//! bytes is recognised and refused.
//!
//! The arrays map onto the particle types of [`crate::snapshot`]: gas is 0,
//! dark 1 and stars 4. [`read_tipsy`] reads one of them, or one rank's share
//! of it, or the particles within a region, streaming the records in chunks
//! so that memory grows with what is kept, not with the file. Tipsy says
//! nothing about units or the box: `time` is the header's (the scale factor
//! in cosmological runs, though the file does not say which it is), and
//! gas `hsmooth` is the smoothing length h of a kernel with support 2h
//! ([`SphCode::Tipsy`]).

use std::io::{ErrorKind, Read, Seek, SeekFrom};
use std::path::Path;

use crate::snapshot::{Region, default_part_type, missing_part_type};
use crate::table::{ParticleTable, SphCode, SphConvention};
use crate::{IoError, open_with_len, remaining_len};

/// Bytes of the header struct without its trailing pad.
const HEADER_LEN: u64 = 28;

/// Bytes of the header as C compilers pad it (8-byte alignment).
const PADDED_HEADER_LEN: u64 = 32;

/// Records decoded per read, bounding the buffer (at most 72 bytes each).
const CHUNK: usize = 4096;

/// What a Tipsy header says, and the layout the file's length revealed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TipsyHeader {
    /// Simulation time, or the scale factor in cosmological runs.
    pub time: f64,
    pub nbodies: u32,
    /// Always 3 in a file the reader accepts.
    pub ndim: u32,
    /// Gas particles (type 0).
    pub nsph: u32,
    /// Dark matter particles (type 1).
    pub ndark: u32,
    /// Star particles (type 4).
    pub nstar: u32,
    /// Standard (XDR) Tipsy; `false` for little-endian native files.
    pub big_endian: bool,
    /// Whether the header takes 32 bytes (with its pad) rather than 28.
    pub padded: bool,
    /// Positions stored as float64 (ChaNGa's `bDoublePos`).
    pub double_pos: bool,
    /// Velocities stored as float64 too (ChaNGa's `bDoubleVel`).
    pub double_vel: bool,
}

/// One of the three arrays of a Tipsy file.
struct TipsyArray {
    /// Its name in messages.
    name: &'static str,
    part_type: u32,
    /// The float32 fields after mass, position and velocity.
    tail: &'static [&'static str],
}

/// The arrays in file order.
const ARRAYS: [TipsyArray; 3] = [
    TipsyArray {
        name: "gas",
        part_type: 0,
        tail: &["rho", "temp", "hsmooth", "metals", "phi"],
    },
    TipsyArray {
        name: "dark",
        part_type: 1,
        tail: &["eps", "phi"],
    },
    TipsyArray {
        name: "star",
        part_type: 4,
        tail: &["metals", "tform", "eps", "phi"],
    },
];

impl TipsyHeader {
    /// Bytes of the header in this file.
    fn header_len(&self) -> u64 {
        if self.padded {
            PADDED_HEADER_LEN
        } else {
            HEADER_LEN
        }
    }

    /// The particle counts of the three arrays, in file order.
    fn counts(&self) -> [u32; 3] {
        [self.nsph, self.ndark, self.nstar]
    }

    /// Counts per particle type 0–5, as [`crate::snapshot`] lists them.
    pub fn part_type_counts(&self) -> [u64; 6] {
        [
            self.nsph.into(),
            self.ndark.into(),
            0,
            0,
            self.nstar.into(),
            0,
        ]
    }

    /// Bytes of one record of `array` (index into [`ARRAYS`]).
    fn record_len(&self, array: usize) -> u64 {
        record_len(array, self.double_pos, self.double_vel)
    }

    /// Offset of the first record of `array` from the start of the file.
    fn array_offset(&self, array: usize) -> u64 {
        let counts = self.counts();
        self.header_len()
            + (0..array)
                .map(|a| u64::from(counts[a]) * self.record_len(a))
                .sum::<u64>()
    }
}

/// Bytes of one record of `array` with the given precisions.
fn record_len(array: usize, double_pos: bool, double_vel: bool) -> u64 {
    let word = |double: bool| if double { 8 } else { 4 };
    4 + 3 * word(double_pos) + 3 * word(double_vel) + 4 * ARRAYS[array].tail.len() as u64
}

/// Bytes of the records of all three arrays (counts below 2³² and records
/// below 100 bytes keep this far from overflowing a `u64`).
fn records_len(counts: [u32; 3], double_pos: bool, double_vel: bool) -> u64 {
    (0..3)
        .map(|a| u64::from(counts[a]) * record_len(a, double_pos, double_vel))
        .sum()
}

/// Whether `head` (the first bytes of a file of `file_len` bytes) is a
/// Tipsy header whose counts add up and whose records fill the file
/// exactly, in either byte order, header size and precision.
pub fn sniff_tipsy(head: &[u8], file_len: u64) -> bool {
    parse_header(head, file_len).is_ok()
}

/// Reads and checks the header of the Tipsy file at `path` (see the
/// module documentation for what must hold).
pub fn tipsy_header(path: &Path) -> Result<TipsyHeader, IoError> {
    let (file, len) = open_with_len(path)?;
    header_sized(file, len, path)
}

/// [`tipsy_header`] of the bytes from `reader`'s position to its end;
/// `name` only labels errors.
pub fn tipsy_header_from<R: Read + Seek>(
    mut reader: R,
    name: &Path,
) -> Result<TipsyHeader, IoError> {
    let len = remaining_len(&mut reader, name)?;
    header_sized(reader, len, name)
}

/// Reads the header from `reader`, which holds `len` bytes.
fn header_sized(reader: impl Read, len: u64, name: &Path) -> Result<TipsyHeader, IoError> {
    let mut head = Vec::with_capacity(PADDED_HEADER_LEN as usize);
    reader
        .take(PADDED_HEADER_LEN)
        .read_to_end(&mut head)
        .map_err(|e| IoError::io(name, e))?;
    parse_header(&head, len).map_err(|m| IoError::format(name, m))
}

/// Decodes and checks a header against the file's length; the message
/// says what does not fit.
fn parse_header(head: &[u8], file_len: u64) -> Result<TipsyHeader, String> {
    if head.len() < HEADER_LEN as usize || file_len < HEADER_LEN {
        return Err(format!(
            "not a Tipsy file: {} bytes long, shorter than the {HEADER_LEN}-byte header",
            file_len.min(head.len() as u64)
        ));
    }
    let word = |at: usize, big: bool| {
        let b = [head[at], head[at + 1], head[at + 2], head[at + 3]];
        if big {
            u32::from_be_bytes(b)
        } else {
            u32::from_le_bytes(b)
        }
    };
    // ndim = 3 reads as 3 in one byte order and as 0x03000000 in the other.
    let big_endian = match (word(12, true), word(12, false)) {
        (3, _) => true,
        (_, 3) => false,
        (be, le) => {
            return Err(format!(
                "not a Tipsy file: ndim reads {be} big-endian and {le} little-endian; a Tipsy \
                 header has ndim = 3"
            ));
        }
    };
    let time_bytes: [u8; 8] = std::array::from_fn(|i| head[i]);
    let time = if big_endian {
        f64::from_be_bytes(time_bytes)
    } else {
        f64::from_le_bytes(time_bytes)
    };
    let [nbodies, nsph, ndark, nstar] = [8, 16, 20, 24].map(|at| word(at, big_endian));
    let counts = [nsph, ndark, nstar];
    let sum: u64 = counts.iter().map(|&n| u64::from(n)).sum();
    let order = if big_endian {
        "big-endian"
    } else {
        "little-endian"
    };
    if u64::from(nbodies) != sum {
        // pynbody (and ChaNGa) keep bits 32–39 of each count in a byte of
        // the pad: nbodies in the lowest, then nsph, ndark, nstar.
        if head.len() >= PADDED_HEADER_LEN as usize {
            let pad = word(28, big_endian).to_le_bytes();
            let wide = |n: u32, byte: usize| u64::from(n) | u64::from(pad[byte]) << 32;
            if pad != [0; 4] && wide(nbodies, 0) == wide(nsph, 1) + wide(ndark, 2) + wide(nstar, 3)
            {
                return Err(format!(
                    "Tipsy header ({order}) counts {} particles, with bits above 2^32 kept in \
                     the pad bytes (pynbody's extension), which is not supported",
                    wide(nbodies, 0)
                ));
            }
        }
        return Err(format!(
            "Tipsy header ({order}) counts do not add up: nbodies = {nbodies} but nsph + ndark + \
             nstar = {nsph} + {ndark} + {nstar} = {sum}"
        ));
    }
    // The one layout whose size is the file's. Layouts differ by multiples
    // of 12 bytes per particle and headers by 4, so at most one matches
    // (all of them when there are no particles: then plain float32).
    for double_pos in [false, true] {
        for double_vel in [false, true] {
            if double_vel && !double_pos {
                continue;
            }
            let records = records_len(counts, double_pos, double_vel);
            for padded in [true, false] {
                let header_len = if padded {
                    PADDED_HEADER_LEN
                } else {
                    HEADER_LEN
                };
                if header_len + records == file_len {
                    return Ok(TipsyHeader {
                        time,
                        nbodies,
                        ndim: 3,
                        nsph,
                        ndark,
                        nstar,
                        big_endian,
                        padded,
                        double_pos,
                        double_vel,
                    });
                }
            }
        }
    }
    let plain = PADDED_HEADER_LEN + records_len(counts, false, false);
    let more = if file_len > plain {
        format!(
            " ({} bytes more than float32 records need)",
            file_len - plain
        )
    } else {
        String::new()
    };
    Err(format!(
        "file size {file_len} bytes does not match its Tipsy header ({order}: {nsph} gas, \
         {ndark} dark, {nstar} star particles), which needs {plain} bytes with float32 records, \
         {} with float64 positions or {} with float64 positions and velocities (4 bytes fewer \
         with a 28-byte header){more}; is the file truncated or not Tipsy?",
        PADDED_HEADER_LEN + records_len(counts, true, false),
        PADDED_HEADER_LEN + records_len(counts, true, true),
    ))
}

/// Reads one particle type of the Tipsy file at `path`: 0 (gas), 1 (dark)
/// or 4 (stars); `None` picks gas when there is any, else the first array
/// with particles. Positions become `positions` (float64); the other
/// fields become columns in record order (gas: `mass, vx, vy, vz, rho,
/// temp, hsmooth, metals, phi`; dark: `mass, vx, vy, vz, eps, phi`; star:
/// `mass, vx, vy, vz, metals, tform, eps, phi`), then `speed` = |v|.
///
/// `share = (r, k)` reads rows `n·r/k .. n·(r+1)/k` of the type's `n`
/// particles, and `rows` says which. `region` keeps only the particles
/// [`Region::contains`] accepts (of the share, if both are given); `rows`
/// is then `None`, as the rows kept are not a range. Records are read in
/// chunks, so memory grows with the particles kept.
///
/// Fails if the header or the file's size is not a Tipsy file's (see the
/// module documentation), or if the type is one Tipsy does not have or
/// the file holds none of (the message lists the counts per type).
pub fn read_tipsy(
    path: &Path,
    part_type: Option<u32>,
    share: Option<(usize, usize)>,
    region: Option<&Region>,
) -> Result<ParticleTable, IoError> {
    let (file, len) = open_with_len(path)?;
    read_sized(file, 0, len, path, part_type, share, region)
}

/// [`read_tipsy`] of the bytes from `reader`'s position to its end (e.g. a
/// `Cursor` over a file held in memory), every particle of the type.
/// `name` only labels errors, which read as [`read_tipsy`]'s for a file of
/// that name.
pub fn read_tipsy_from<R: Read + Seek>(
    mut reader: R,
    name: &Path,
    part_type: Option<u32>,
) -> Result<ParticleTable, IoError> {
    let start = reader.stream_position().map_err(|e| IoError::io(name, e))?;
    let len = remaining_len(&mut reader, name)?;
    read_sized(reader, start, len, name, part_type, None, None)
}

/// Rows `n·r/k .. n·(r+1)/k` of `n`: share `r` of `k`.
fn share_rows(n: usize, r: usize, k: usize) -> std::ops::Range<usize> {
    let k = k.max(1) as u128;
    let at = |r: usize| ((n as u128 * r as u128) / k) as usize;
    at(r.min(k as usize))..at((r + 1).min(k as usize))
}

/// The reader behind [`read_tipsy`] and [`read_tipsy_from`]: the file
/// starts at offset `start` of `reader` and holds `len` bytes.
fn read_sized<R: Read + Seek>(
    mut reader: R,
    start: u64,
    len: u64,
    name: &Path,
    part_type: Option<u32>,
    share: Option<(usize, usize)>,
    region: Option<&Region>,
) -> Result<ParticleTable, IoError> {
    let io = |e| IoError::io(name, e);
    let header = header_sized(&mut reader, len, name)?;
    let type_counts = header.part_type_counts();
    let wanted = part_type.unwrap_or_else(|| default_part_type(&type_counts));
    let Some(index) = ARRAYS.iter().position(|a| a.part_type == wanted) else {
        return Err(missing_part_type(name, wanted, &type_counts));
    };
    let array = &ARRAYS[index];
    // An empty array is an error only when asked for by name; an empty
    // file read with the default type gives an empty table.
    let total = header.counts()[index] as usize;
    if total == 0 && part_type.is_some() {
        return Err(missing_part_type(name, wanted, &type_counts));
    }
    let rows = share.map_or(0..total, |(r, k)| share_rows(total, r, k));

    // The file's length was checked against the header, so the rows asked
    // for are in the file and their columns cannot outgrow it.
    let rec_len = header.record_len(index) as usize;
    let first = header.array_offset(index) + rows.start as u64 * rec_len as u64;
    reader.seek(SeekFrom::Start(start + first)).map_err(io)?;
    let names: Vec<&str> = ["mass", "vx", "vy", "vz"]
        .into_iter()
        .chain(array.tail.iter().copied())
        .collect();
    let capacity = if region.is_some() { 0 } else { rows.len() };
    let mut positions = Vec::with_capacity(capacity);
    let mut columns: Vec<Vec<f32>> = names.iter().map(|_| Vec::with_capacity(capacity)).collect();

    let decoder = Decoder {
        big_endian: header.big_endian,
        pos: if header.double_pos { 8 } else { 4 },
        vel: if header.double_vel { 8 } else { 4 },
    };
    let mut buf = vec![0u8; rec_len * CHUNK.min(rows.len())];
    let mut done = 0;
    while done < rows.len() {
        let n = CHUNK.min(rows.len() - done);
        let bytes = &mut buf[..n * rec_len];
        reader.read_exact(bytes).map_err(|e| match e.kind() {
            ErrorKind::UnexpectedEof => IoError::format(
                name,
                format!(
                    "file ends inside the {} records (particle {} of {total}); did it change \
                     while being read?",
                    array.name,
                    rows.start + done
                ),
            ),
            _ => io(e),
        })?;
        for record in bytes.chunks_exact(rec_len) {
            let p = decoder.position(record);
            if region.is_some_and(|r| !r.contains(p)) {
                continue;
            }
            positions.push(p);
            decoder.fields(record, &mut columns);
        }
        done += n;
    }

    let mut table = ParticleTable {
        positions,
        columns: names.iter().map(|n| n.to_string()).zip(columns).collect(),
        time: Some(header.time).filter(|t| t.is_finite()),
        rows: (share.is_some() && region.is_none()).then_some((rows.start, total)),
        sph: Some(SphConvention {
            code: SphCode::Tipsy,
            kernel: None,
        }),
        ..ParticleTable::default()
    };
    table.derive_speed("vx", "vy", "vz");
    Ok(table)
}

/// Decodes the fields of one record.
struct Decoder {
    big_endian: bool,
    /// Bytes per position component (4 or 8).
    pos: usize,
    /// Bytes per velocity component.
    vel: usize,
}

impl Decoder {
    fn f32_at(&self, b: &[u8], at: usize) -> f32 {
        let w = [b[at], b[at + 1], b[at + 2], b[at + 3]];
        if self.big_endian {
            f32::from_be_bytes(w)
        } else {
            f32::from_le_bytes(w)
        }
    }

    /// A float of `size` bytes (4 or 8) at `at`, as float64.
    fn real_at(&self, b: &[u8], at: usize, size: usize) -> f64 {
        if size == 4 {
            return self.f32_at(b, at).into();
        }
        let w: [u8; 8] = std::array::from_fn(|i| b[at + i]);
        if self.big_endian {
            f64::from_be_bytes(w)
        } else {
            f64::from_le_bytes(w)
        }
    }

    /// x, y, z (after the 4-byte mass).
    fn position(&self, record: &[u8]) -> [f64; 3] {
        std::array::from_fn(|a| self.real_at(record, 4 + a * self.pos, self.pos))
    }

    /// Appends mass, velocity and the tail fields to `columns`.
    fn fields(&self, record: &[u8], columns: &mut [Vec<f32>]) {
        let vel_at = 4 + 3 * self.pos;
        let tail_at = vel_at + 3 * self.vel;
        for (c, column) in columns.iter_mut().enumerate() {
            let value = match c {
                0 => self.f32_at(record, 0),
                1..=3 => self.real_at(record, vel_at + (c - 1) * self.vel, self.vel) as f32,
                _ => self.f32_at(record, tail_at + 4 * (c - 4)),
            };
            column.push(value);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A standard header (big-endian, padded) for the given counts.
    fn header(nbodies: u32, ndim: u32, counts: [u32; 3]) -> Vec<u8> {
        let mut h = 0.25f64.to_be_bytes().to_vec();
        for v in [nbodies, ndim, counts[0], counts[1], counts[2], 0] {
            h.extend_from_slice(&v.to_be_bytes());
        }
        h
    }

    #[test]
    fn the_layout_comes_from_the_size() {
        let h = header(3, 3, [1, 1, 1]);
        let plain = 32 + 48 + 36 + 44;
        let p = parse_header(&h, plain).unwrap();
        assert!(p.big_endian && p.padded && !p.double_pos);
        assert_eq!(p.time, 0.25);
        let p = parse_header(&h, plain - 4).unwrap();
        assert!(!p.padded && !p.double_pos);
        let p = parse_header(&h, plain + 36).unwrap();
        assert!(p.padded && p.double_pos && !p.double_vel);
        let p = parse_header(&h, plain + 72 - 4).unwrap();
        assert!(!p.padded && p.double_pos && p.double_vel);
        let e = parse_header(&h, plain + 5).unwrap_err();
        assert!(e.contains("5 bytes more"), "{e}");
        assert_eq!(p.array_offset(2), 28 + 72 + 60);
    }

    #[test]
    fn headers_that_do_not_add_up_are_refused() {
        let e = parse_header(&header(3, 2, [1, 1, 1]), 160).unwrap_err();
        assert!(e.contains("ndim reads 2"), "{e}");
        let e = parse_header(&header(4, 3, [1, 1, 1]), 160).unwrap_err();
        assert!(e.contains("nbodies = 4"), "{e}");
        // 2^32 + 5 gas and 2^32 - 1 dark particles: the low 32 bits do not
        // add up, with bits 32–39 of nbodies (2, the pad's lowest byte)
        // and of nsph (1, the next) they do.
        let mut big = header(4, 3, [5, u32::MAX, 0]);
        big[28..32].copy_from_slice(&0x0102u32.to_be_bytes());
        let e = parse_header(&big, 1 << 20).unwrap_err();
        assert!(e.contains("8589934596 particles"), "{e}");
        big[28..32].copy_from_slice(&0x0103u32.to_be_bytes());
        let e = parse_header(&big, 1 << 20).unwrap_err();
        assert!(e.contains("do not add up: nbodies = 4"), "{e}");
        assert!(
            parse_header(&big[..20], 76)
                .unwrap_err()
                .contains("shorter")
        );
        // u32::MAX particles in each array stay within u64 arithmetic.
        let huge = header(u32::MAX, 3, [u32::MAX, 0, 0]);
        assert!(parse_header(&huge, 1 << 20).is_err());
    }

    #[test]
    fn shares_split_the_rows() {
        assert_eq!(share_rows(10, 0, 3), 0..3);
        assert_eq!(share_rows(10, 2, 3), 6..10);
        assert_eq!(share_rows(10, 5, 3), 10..10);
        assert_eq!(share_rows(10, 0, 0), 0..10);
    }
}
