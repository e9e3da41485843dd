//! FITS images: a writer of 2-D `float32` maps with a linear world
//! coordinate system, and a reader of what it writes.
//!
//! A FITS file (standard 4.0) is a sequence of 2880-byte blocks. The
//! primary header is ASCII text of 80-character "cards" (36 per block),
//! each `KEYWORD = value / comment`, ending with an `END` card and padded
//! with spaces to a whole block. The data follows, big-endian, padded with
//! zeros to a whole block. The writer writes one such header and data unit:
//!
//! ```text
//! SIMPLE  =                    T / conforms to FITS standard
//! BITPIX  =                  -32 / IEEE single precision floating point
//! NAXIS   =                    2
//! NAXIS1  =                  640 / width: pixels along x
//! NAXIS2  =                  480 / height: pixels along y
//! BUNIT   = 'g/cm^2  '           / unit of the pixel values
//! CTYPE1  = 'X       ' ...        (a linear WCS, when given)
//! ...                               (the caller's cards, then HISTORY text)
//! CHECKSUM= 'aD3Bb93Aa93Aa93A'   / HDU checksum
//! DATASUM = '2503531142'         / data unit checksum
//! END
//! ```
//!
//! Values follow the fixed format: logical `T`/`F` and numbers right-
//! justified to column 30, strings in single quotes starting in column 11
//! (a quote inside doubled, at least 8 characters between the quotes),
//! comments after ` / `. Reals are written with the fewest digits that
//! read back as the same `f64` (`0.1`, `1.0E-7`); the rare value that needs
//! more than the 20 columns (17 digits and an exponent) extends past
//! column 30 in the standard's free format. `HISTORY` text is wrapped over
//! as many cards as it needs. `CHECKSUM` and `DATASUM` follow the FITS
//! checksum convention, so `astropy.io.fits.open(..., checksum=True)` and
//! `fitsverify` can tell a damaged file.
//!
//! FITS counts rows from the bottom: pixel (1, 1) is the lower left corner,
//! and image viewers and astropy draw row 1 at the bottom. Our images keep
//! row 0 at the top (as the `.npy` and PNG outputs do), so the writer
//! stores the rows in reverse order, and the WCS describes the file's
//! order: pixel (i, j) has world coordinates
//! `crval + cdelt · ((i, j) − crpix)`, with j counted upwards from 1
//! ([`LinearWcs::covering`] builds one for a picture of a region).
//!
//! [`read_fits_image`] reads back the header cards and the data of such a
//! file (any primary `BITPIX = -32`, `NAXIS = 2` image), for round-trip
//! tests and `voxless info`; it checks the declared size against the
//! file's length before allocating.

use std::io::{BufReader, ErrorKind, Read, Seek, Write};
use std::path::Path;

use crate::{IoError, checked_product, open_with_len, remaining_len};

/// Bytes per FITS block.
const BLOCK: usize = 2880;

/// Characters per header card.
const CARD: usize = 80;

/// Longest string value: columns 11–80 minus the two quotes.
const MAX_TEXT: usize = CARD - 10 - 2;

/// Characters of text a `HISTORY` card holds (columns 9–80).
const HISTORY_TEXT: usize = CARD - 8;

/// Keywords the writer sets itself or that would change how the data
/// reads; the caller's cards may not use them.
const RESERVED: [&str; 16] = [
    "SIMPLE", "BITPIX", "NAXIS", "END", "EXTEND", "BSCALE", "BZERO", "BLANK", "XTENSION", "PCOUNT",
    "GCOUNT", "GROUPS", "CHECKSUM", "DATASUM", "HISTORY", "COMMENT",
];

/// A linear world coordinate system: pixel (i, j) (1-based, in the file's
/// order, j = 1 the bottom row) is at `crval + cdelt · ((i, j) − crpix)`.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearWcs {
    /// Axis names (`CTYPE1`, `CTYPE2`), e.g. "X", "Y"; names of four
    /// characters or fewer read as linear axes in WCS libraries.
    pub ctype: [String; 2],
    /// Axis units (`CUNIT1`, `CUNIT2`), e.g. "kpc"; empty to leave out.
    pub cunit: [String; 2],
    /// Reference pixel (`CRPIX1`, `CRPIX2`), 1-based.
    pub crpix: [f64; 2],
    /// World coordinates of the reference pixel (`CRVAL1`, `CRVAL2`).
    pub crval: [f64; 2],
    /// World size of a pixel along each axis (`CDELT1`, `CDELT2`).
    pub cdelt: [f64; 2],
}

impl LinearWcs {
    /// The WCS of a `width` × `height` picture of the world rectangle
    /// `[lo, hi]`, x to the right and y upwards: pixel edges on its sides,
    /// pixel (1, 1) centred half a pixel inside the lower left corner `lo`.
    pub fn covering(
        width: usize,
        height: usize,
        lo: [f64; 2],
        hi: [f64; 2],
        ctype: [&str; 2],
        cunit: [&str; 2],
    ) -> LinearWcs {
        let n = [width as f64, height as f64];
        let cdelt = [0, 1].map(|a| (hi[a] - lo[a]) / n[a]);
        LinearWcs {
            ctype: ctype.map(str::to_string),
            cunit: cunit.map(str::to_string),
            crpix: [1.0, 1.0],
            crval: [0, 1].map(|a| lo[a] + 0.5 * cdelt[a]),
            cdelt,
        }
    }
}

/// The value of a header card.
#[derive(Clone, Debug, PartialEq)]
pub enum CardValue {
    /// Printable ASCII, at most 68 characters once quotes are doubled.
    Text(String),
    /// A finite number.
    Real(f64),
    Int(i64),
    Logical(bool),
}

/// A 2-D `float32` image with its header, for [`write_fits_image`].
#[derive(Clone, Debug)]
pub struct FitsImage<'a> {
    pub width: usize,
    pub height: usize,
    /// Row-major, row 0 = TOP of the picture (as our .npy/PNG outputs).
    /// The writer flips rows so that FITS row 1 is the bottom (FITS/astropy
    /// convention: y increases upward), and the WCS refers to that order.
    /// NaN marks pixels without a value.
    pub data: &'a [f32],
    pub wcs: Option<LinearWcs>,
    /// Unit of the pixel values (`BUNIT`).
    pub bunit: Option<String>,
    /// Further keywords: (KEYWORD, value, comment). Keywords are 1–8
    /// characters of `A-Z 0-9 - _`, not one the writer sets itself.
    pub cards: Vec<(String, CardValue, String)>,
    /// `HISTORY` text, one entry per record (wrapped over several cards
    /// when long; characters other than printable ASCII become `?`).
    pub history: Vec<String>,
}

impl<'a> FitsImage<'a> {
    /// An image with no WCS, unit, extra cards or history.
    pub fn new(width: usize, height: usize, data: &'a [f32]) -> FitsImage<'a> {
        FitsImage {
            width,
            height,
            data,
            wcs: None,
            bunit: None,
            cards: Vec::new(),
            history: Vec::new(),
        }
    }
}

/// Writes `image` as a FITS file at `path` (through a temporary file
/// renamed into place). Fails with [`IoError::Format`], before creating
/// the file, if the data does not hold `width × height` values, a side is
/// 0, or a card is invalid (keyword, non-finite or non-ASCII value, a text
/// too long, a zero `CDELT`).
pub fn write_fits_image(path: &Path, image: &FitsImage) -> Result<(), IoError> {
    let header = header_bytes(path, image)?;
    crate::write_atomically(path, |out| write_unit(out, path, image, &header))
}

/// [`write_fits_image`] into any writer; `name` labels errors.
pub fn write_fits_image_to<W: Write>(
    mut out: W,
    name: &Path,
    image: &FitsImage,
) -> Result<(), IoError> {
    let header = header_bytes(name, image)?;
    write_unit(&mut out, name, image, &header)?;
    out.flush().map_err(|e| IoError::io(name, e))
}

/// Writes the header, then the rows bottom first, then the zero padding.
fn write_unit(
    out: &mut impl Write,
    name: &Path,
    image: &FitsImage,
    header: &[u8],
) -> Result<(), IoError> {
    let io = |e| IoError::io(name, e);
    out.write_all(header).map_err(io)?;
    let mut row = Vec::with_capacity(image.width * 4);
    for values in image.data.chunks_exact(image.width).rev() {
        row.clear();
        row.extend(values.iter().flat_map(|v| v.to_be_bytes()));
        out.write_all(&row).map_err(io)?;
    }
    let pad = (BLOCK - image.data.len() * 4 % BLOCK) % BLOCK;
    out.write_all(&vec![0u8; pad]).map_err(io)
}

/// The checked header of `image`, padded to whole blocks, its checksum
/// filled in.
fn header_bytes(name: &Path, image: &FitsImage) -> Result<Vec<u8>, IoError> {
    let err = |m: String| IoError::format(name, m);
    let (w, h) = (image.width, image.height);
    if w == 0 || h == 0 {
        return Err(err(format!(
            "cannot write a {w}x{h} FITS image: both sides must be at least 1 pixel"
        )));
    }
    if checked_product(&[w, h, 4]).is_none() || w * h != image.data.len() {
        return Err(err(format!(
            "a {w}x{h} FITS image needs {w}·{h} values but {} were given",
            image.data.len()
        )));
    }
    let mut cards = Cards {
        name,
        text: String::new(),
        keywords: Vec::new(),
    };
    let int = |n: usize| CardValue::Int(i64::try_from(n).unwrap_or(i64::MAX));
    cards.push(
        "SIMPLE",
        &CardValue::Logical(true),
        "conforms to FITS standard",
    )?;
    cards.push(
        "BITPIX",
        &CardValue::Int(-32),
        "IEEE single precision floating point",
    )?;
    cards.push("NAXIS", &CardValue::Int(2), "number of array dimensions")?;
    cards.push("NAXIS1", &int(w), "width: pixels along x")?;
    cards.push(
        "NAXIS2",
        &int(h),
        "height: pixels along y, row 1 at the bottom",
    )?;
    if let Some(unit) = &image.bunit {
        cards.push(
            "BUNIT",
            &CardValue::Text(unit.clone()),
            "unit of the pixel values",
        )?;
    }
    if let Some(wcs) = &image.wcs {
        for a in 0..2 {
            let n = a + 1;
            if wcs.cdelt[a] == 0.0 {
                return Err(err(format!(
                    "CDELT{n} is 0: a WCS axis needs a non-zero pixel size"
                )));
            }
            cards.push(
                &format!("CTYPE{n}"),
                &CardValue::Text(wcs.ctype[a].clone()),
                "",
            )?;
            if !wcs.cunit[a].is_empty() {
                cards.push(
                    &format!("CUNIT{n}"),
                    &CardValue::Text(wcs.cunit[a].clone()),
                    "",
                )?;
            }
        }
        let reals = [
            ("CRPIX", wcs.crpix, "reference pixel (1-based)"),
            (
                "CRVAL",
                wcs.crval,
                "world coordinate at the reference pixel",
            ),
            ("CDELT", wcs.cdelt, "world size of a pixel"),
        ];
        for (key, values, comment) in reals {
            for (a, v) in values.into_iter().enumerate() {
                cards.push(&format!("{key}{}", a + 1), &CardValue::Real(v), comment)?;
            }
        }
    }
    for (key, value, comment) in &image.cards {
        check_keyword(key).map_err(err)?;
        if RESERVED.contains(&key.as_str()) || is_naxis_n(key) {
            return Err(err(format!(
                "keyword {key} is one the FITS writer sets itself; use another name"
            )));
        }
        cards.push(key, value, comment)?;
    }
    for text in &image.history {
        cards.history(text);
    }
    // The checksum convention: CHECKSUM holds 16 zeros while the header's
    // sum is taken, then the characters that make the unit's sum -0.
    let datasum = ones_complement_sum(0, image.data.iter().map(|v| v.to_bits()));
    let checksum_at = cards.text.len() + 11;
    cards.push("CHECKSUM", &CardValue::Text("0".repeat(16)), "HDU checksum")?;
    cards.push(
        "DATASUM",
        &CardValue::Text(datasum.to_string()),
        "data unit checksum",
    )?;
    cards.text.push_str(&format!("{:<CARD$}", "END"));
    let mut bytes = cards.text.into_bytes();
    bytes.resize(bytes.len().div_ceil(BLOCK) * BLOCK, b' ');
    let words = bytes
        .chunks_exact(4)
        .map(|w| u32::from_be_bytes([w[0], w[1], w[2], w[3]]));
    let sum = ones_complement_sum(datasum, words);
    bytes[checksum_at..checksum_at + 16].copy_from_slice(&encode_checksum(!sum));
    Ok(bytes)
}

/// Header cards being built (80 characters each, back to back), with the
/// keywords used so far; `name` labels errors.
struct Cards<'a> {
    name: &'a Path,
    text: String,
    keywords: Vec<String>,
}

impl Cards<'_> {
    /// Appends `KEYWORD = value / comment`.
    fn push(&mut self, key: &str, value: &CardValue, comment: &str) -> Result<(), IoError> {
        let card = value_card(key, value, comment).map_err(|m| IoError::format(self.name, m))?;
        if self.keywords.iter().any(|k| k == key) {
            return Err(IoError::format(
                self.name,
                format!("keyword {key} appears twice in the FITS header"),
            ));
        }
        self.text.push_str(&card);
        self.keywords.push(key.to_string());
        Ok(())
    }

    /// Appends `text` as `HISTORY` cards: one per line, long lines wrapped
    /// at a space where there is one.
    fn history(&mut self, text: &str) {
        let text: String = printable(text).collect();
        for line in text.split('\n') {
            let mut rest = line.trim_end();
            loop {
                let (card, next) = if rest.len() <= HISTORY_TEXT {
                    (rest, "")
                } else {
                    match rest[..=HISTORY_TEXT].rfind(' ').filter(|&i| i > 0) {
                        Some(i) => (&rest[..i], &rest[i + 1..]),
                        None => rest.split_at(HISTORY_TEXT),
                    }
                };
                self.text
                    .push_str(&format!("{:<CARD$}", format!("HISTORY {card}")));
                if next.is_empty() {
                    break;
                }
                rest = next;
            }
        }
    }
}

/// The 80 characters of the card `KEYWORD = value / comment`.
fn value_card(key: &str, value: &CardValue, comment: &str) -> Result<String, String> {
    let field = match value {
        CardValue::Logical(b) => format!("{:>20}", if *b { "T" } else { "F" }),
        CardValue::Int(i) => format!("{i:>20}"),
        CardValue::Real(v) if !v.is_finite() => {
            return Err(format!(
                "keyword {key}: {v} is not a finite number, which FITS cannot write"
            ));
        }
        CardValue::Real(v) => format!("{:>20}", real_text(*v)),
        CardValue::Text(s) => {
            if let Some(c) = s.chars().find(|c| !(' '..='~').contains(c)) {
                return Err(format!(
                    "keyword {key}: text {s:?} has the character {c:?}; FITS strings are \
                         printable ASCII"
                ));
            }
            let escaped = s.replace('\'', "''");
            if escaped.len() > MAX_TEXT {
                return Err(format!(
                    "keyword {key}: text of {} characters is too long for a FITS card \
                         (at most {MAX_TEXT}, counting a quote twice)",
                    s.len()
                ));
            }
            format!("{:<20}", format!("'{escaped:<8}'"))
        }
    };
    let mut card = format!("{key:<8}= {field}");
    // Comments are informative: one that does not fit is shortened.
    let room = CARD.saturating_sub(card.len() + 3);
    if !comment.is_empty() && room > 0 {
        card.push_str(" / ");
        card.extend(printable(comment).take(room));
    }
    Ok(format!("{card:<CARD$}"))
}

/// `text` with every character other than printable ASCII (and, for
/// [`Cards::history`], newlines) replaced by `?`.
fn printable(text: &str) -> impl Iterator<Item = char> + '_ {
    text.chars().map(|c| {
        if (' '..='~').contains(&c) || c == '\n' {
            c
        } else {
            '?'
        }
    })
}

/// Whether a keyword is valid: 1–8 characters of `A-Z 0-9 - _`.
fn check_keyword(key: &str) -> Result<(), String> {
    let ok = |c: u8| c.is_ascii_uppercase() || c.is_ascii_digit() || c == b'-' || c == b'_';
    if key.is_empty() || key.len() > 8 || !key.bytes().all(ok) {
        return Err(format!(
            "{key:?} is not a FITS keyword: 1 to 8 characters of upper-case letters, digits, \
             '-' and '_'"
        ));
    }
    Ok(())
}

/// `NAXISn`, which sizes the data.
fn is_naxis_n(key: &str) -> bool {
    key.strip_prefix("NAXIS")
        .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
}

/// A finite `f64` in the fewest characters that parse back to it: plain
/// (`0.25`, `-3.0`) or with an exponent (`1.0E-7`), always with a decimal
/// point so that FITS readers take it as a real.
fn real_text(v: f64) -> String {
    let mut plain = format!("{v}");
    if !plain.contains('.') {
        plain.push_str(".0");
    }
    let exp = format!("{v:E}");
    let exp = match exp.split_once('E') {
        Some((m, e)) if !m.contains('.') => format!("{m}.0E{e}"),
        _ => exp,
    };
    if plain.len() <= exp.len() { plain } else { exp }
}

/// The 32-bit ones' complement sum of `words` added to `start` (the FITS
/// checksum's arithmetic: carries wrap around).
fn ones_complement_sum(start: u32, words: impl Iterator<Item = u32>) -> u32 {
    let fold = |s: u64| (s & 0xffff_ffff) + (s >> 32);
    let mut sum = u64::from(start);
    for w in words {
        // Below 2^33 after every step, so the u64 never overflows.
        sum = fold(sum + u64::from(w));
    }
    fold(sum) as u32
}

/// The 16 characters of a `CHECKSUM` value for `value` (the complement
/// of the unit's sum), as the convention's `char_encode` writes them:
/// each byte spread over four characters from `0`, avoiding punctuation,
/// then rotated by one place.
fn encode_checksum(value: u32) -> [u8; 16] {
    const EXCLUDE: [u8; 13] = [
        0x3a, 0x3b, 0x3c, 0x3d, 0x3e, 0x3f, 0x40, 0x5b, 0x5c, 0x5d, 0x5e, 0x5f, 0x60,
    ];
    let mut asc = [0u8; 16];
    for (i, byte) in value.to_be_bytes().into_iter().enumerate() {
        let quotient = byte / 4 + b'0';
        let remainder = byte % 4;
        let mut ch = [quotient; 4];
        ch[0] += remainder;
        let mut changed = true;
        while changed {
            changed = false;
            for j in [0, 2] {
                if EXCLUDE.contains(&ch[j]) || EXCLUDE.contains(&ch[j + 1]) {
                    ch[j] += 1;
                    ch[j + 1] -= 1;
                    changed = true;
                }
            }
        }
        for (j, c) in ch.into_iter().enumerate() {
            asc[4 * j + i] = c;
        }
    }
    std::array::from_fn(|i| asc[(i + 15) % 16])
}

/// What [`read_fits_image`] gives: the header cards, width, height, data.
pub type FitsContents = (Vec<(String, String)>, usize, usize, Vec<f32>);

/// Reads a FITS file's primary image written as [`write_fits_image`]
/// writes them (`BITPIX = -32`, `NAXIS = 2`): the header cards as
/// (keyword, value) pairs in order (string values unquoted, comments
/// dropped, `HISTORY` and `COMMENT` cards with their text), the width and
/// height, and the pixels row by row as stored: row 1, the bottom of the
/// picture, first.
pub fn read_fits_image(path: &Path) -> Result<FitsContents, IoError> {
    let (file, len) = open_with_len(path)?;
    read_sized(BufReader::new(file), len, path)
}

/// [`read_fits_image`] of the bytes from `reader`'s position to its end;
/// `name` only labels errors.
pub fn read_fits_image_from<R: Read + Seek>(
    mut reader: R,
    name: &Path,
) -> Result<FitsContents, IoError> {
    let len = remaining_len(&mut reader, name)?;
    read_sized(BufReader::new(reader), len, name)
}

/// The reader behind [`read_fits_image`]: `reader` holds `len` bytes.
fn read_sized(mut reader: impl Read, len: u64, name: &Path) -> Result<FitsContents, IoError> {
    let err = |m: String| IoError::format(name, m);
    let eof = |what: &str| {
        let what = what.to_string();
        move |e: std::io::Error| match e.kind() {
            ErrorKind::UnexpectedEof => {
                IoError::format(name, format!("file ends inside the {what}"))
            }
            _ => IoError::io(name, e),
        }
    };
    let mut cards = Vec::new();
    let mut block = vec![0u8; BLOCK];
    let mut header_len = 0u64;
    'blocks: loop {
        if header_len + BLOCK as u64 > len {
            return Err(err(if header_len == 0 {
                format!("not a FITS file: {len} bytes long, shorter than a 2880-byte header block")
            } else {
                "file ends inside the header (no END card)".to_string()
            }));
        }
        reader.read_exact(&mut block).map_err(eof("header"))?;
        header_len += BLOCK as u64;
        for card in block.chunks_exact(CARD) {
            let n = cards.len() + 1;
            let Ok(card) = std::str::from_utf8(card) else {
                return Err(err(format!("header card {n} is not ASCII text")));
            };
            if !card.bytes().all(|b| (b' '..=b'~').contains(&b)) {
                return Err(err(format!("header card {n} is not printable ASCII text")));
            }
            let key = card[..8].trim_end();
            if n == 1 && !(key == "SIMPLE" && parse_value(&card[10..]).as_deref() == Ok("T")) {
                return Err(err(
                    "not a FITS file: it does not start with SIMPLE = T".into()
                ));
            }
            if key == "END" {
                break 'blocks;
            }
            let value = if &card[8..10] == "= " && !matches!(key, "HISTORY" | "COMMENT" | "") {
                parse_value(&card[10..]).map_err(|m| err(format!("keyword {key}: {m}")))?
            } else {
                card[8..].trim_end().to_string()
            };
            cards.push((key.to_string(), value));
        }
    }
    let lookup = |key: &str| {
        cards
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    };
    let int = |key: &str| -> Result<i64, IoError> {
        let v = lookup(key).ok_or_else(|| err(format!("the header has no {key}")))?;
        v.parse()
            .map_err(|_| err(format!("{key} = {v} is not an integer")))
    };
    let bitpix = int("BITPIX")?;
    if bitpix != -32 {
        return Err(err(format!(
            "BITPIX = {bitpix}: only 32-bit float images (BITPIX = -32) are read"
        )));
    }
    let naxis = int("NAXIS")?;
    if naxis != 2 {
        return Err(err(format!("NAXIS = {naxis}: only 2-D images are read")));
    }
    for (key, neutral) in [("BSCALE", 1.0), ("BZERO", 0.0)] {
        if let Some(v) = lookup(key)
            && v.parse::<f64>().ok() != Some(neutral)
        {
            return Err(err(format!("{key} = {v}: scaled data is not supported")));
        }
    }
    let size = |key: &str| -> Result<usize, IoError> {
        let n = int(key)?;
        usize::try_from(n)
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| err(format!("{key} = {n} is not a positive image size")))
    };
    let (width, height) = (size("NAXIS1")?, size("NAXIS2")?);
    let available = len - header_len;
    let bytes = checked_product(&[width, height, 4]).filter(|&b| b as u64 <= available);
    let Some(bytes) = bytes else {
        return Err(err(format!(
            "a {width}x{height} float32 image needs {} bytes of data but {available} follow the \
             header",
            width as u128 * height as u128 * 4
        )));
    };
    let mut raw = vec![0u8; bytes];
    reader.read_exact(&mut raw).map_err(eof("data"))?;
    let data = raw
        .chunks_exact(4)
        .map(|w| f32::from_be_bytes([w[0], w[1], w[2], w[3]]))
        .collect();
    Ok((cards, width, height, data))
}

/// The value in a card's columns 11–80: a string unquoted (doubled quotes
/// undone, trailing blanks dropped) or the text before a comment, trimmed.
fn parse_value(field: &str) -> Result<String, String> {
    let t = field.trim_start();
    let Some(quoted) = t.strip_prefix('\'') else {
        return Ok(t.split('/').next().unwrap_or("").trim().to_string());
    };
    let mut out = String::new();
    let mut chars = quoted.chars();
    while let Some(c) = chars.next() {
        if c == '\'' {
            if chars.as_str().starts_with('\'') {
                chars.next();
            } else {
                return Ok(out.trim_end().to_string());
            }
        }
        out.push(c);
    }
    Err("string value has no closing quote".to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reals_round_trip_in_few_characters() {
        for (v, text) in [
            (0.25, "0.25"),
            (-3.0, "-3.0"),
            (1e-7, "1.0E-7"),
            (1.5e300, "1.5E300"),
            (-0.0, "-0.0"),
            (123456.0, "123456.0"),
            (0.1 + 0.2, "0.30000000000000004"),
        ] {
            assert_eq!(real_text(v), text);
        }
        let mut x = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..10_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = f64::from_bits(x);
            if v.is_finite() {
                let t = real_text(v);
                assert_eq!(t.parse::<f64>().unwrap().to_bits(), v.to_bits(), "{t}");
                assert!(t.len() <= 24 && t.contains('.'), "{t}");
            }
        }
    }

    #[test]
    fn checksum_encoding_matches_the_convention() {
        // The worked example of the checksum convention (Seaman et al.),
        // and values astropy's `_char_encode` gives.
        assert_eq!(&encode_checksum(!868_229_149u32), b"hcHjjc9ghcEghc9g");
        assert_eq!(&encode_checksum(!0), b"orrrrooooooooooo");
        assert_eq!(&encode_checksum(!0xdead_beef), b"49FH48D948DG48D9");
        assert_eq!(&encode_checksum(0), b"0000000000000000");
        assert_eq!(ones_complement_sum(0xffff_ffff, [1u32].into_iter()), 1);
        assert_eq!(
            ones_complement_sum(0, [0x8000_0000, 0x8000_0000].into_iter()),
            1
        );
    }

    #[test]
    fn values_parse_back() {
        assert_eq!(parse_value("'it''s   '  / c").unwrap(), "it's");
        assert_eq!(parse_value("               -32 / c").unwrap(), "-32");
        assert!(parse_value("'open").is_err());
        assert!(is_naxis_n("NAXIS12") && !is_naxis_n("NAXIS") && !is_naxis_n("NAXISX"));
        assert!(check_keyword("DATE-OBS").is_ok() && check_keyword("date").is_err());
        assert!(check_keyword("TOOLONGKEY").is_err() && check_keyword("").is_err());
    }
}
