//! NumPy `.npy` files.
//!
//! The format (see NumPy's `numpy.lib.format`) is:
//!
//! ```text
//! \x93NUMPY  major minor  header_len  header  data
//! ```
//!
//! `header_len` is a little-endian `u16` in version 1.0 and a `u32` in
//! versions 2.0 and 3.0. The header is a Python dict literal such as
//! `{'descr': '<f4', 'fortran_order': False, 'shape': (10, 3), }`, padded with
//! spaces and a final newline so that the data starts at a multiple of 64
//! bytes. The data follows immediately, with no trailing bytes.
//!
//! [`read_npy`] accepts every numeric dtype (`f2`, `f4`, `f8`, `i1`..`i8`,
//! `u1`..`u8`, `b1`) in either byte order and converts the values to `f64` in
//! C (row-major) order. [`write_npy_f32`] writes `<f4` arrays exactly as
//! `numpy.save` does.
//!
//! [`read_npy_from`] and [`write_npy_f32_to`] do the same over any reader
//! or writer (a `Cursor` over bytes in memory, a socket); the path functions
//! open the file and share their code.

use std::io::{BufReader, ErrorKind, Read, Seek, Write};
use std::path::Path;

use crate::{IoError, checked_product, open_with_len, remaining_len};

mod positions;
mod rows;
pub(crate) use positions::check_positions_shape;
pub use positions::{read_npy_positions, read_npy_positions_into};
pub use rows::read_npy_rows;

/// Magic bytes at the start of every `.npy` file.
const MAGIC: &[u8; 6] = b"\x93NUMPY";

/// NumPy aligns the start of the data to this many bytes.
const ALIGN: usize = 64;

/// Deepest nesting of tuples/lists accepted in a header (guards recursion).
const MAX_DEPTH: usize = 16;

/// A numeric `.npy` array converted to `f64`, row-major (C order).
#[derive(Debug, Clone, PartialEq)]
pub struct NpyArray {
    /// Extent of each axis; empty for a 0-d (scalar) array.
    pub shape: Vec<usize>,
    /// The dtype as written in the header, e.g. `"<f4"`.
    pub dtype: String,
    /// The values in C order; `data.len()` is the product of `shape`.
    pub data: Vec<f64>,
}

/// Reads a `.npy` file (format version 1.0, 2.0 or 3.0) holding a numeric
/// array and converts it to `f64` in C order.
///
/// Fails with [`IoError::Format`] if the magic, version or header is invalid,
/// if the dtype is not a plain number type (structured, object, string and
/// complex arrays are rejected), or if the file does not hold exactly the
/// number of bytes the header's shape requires.
pub fn read_npy(path: &Path) -> Result<NpyArray, IoError> {
    let (file, len) = open_with_len(path)?;
    read_npy_sized(file, len, path)
}

/// [`read_npy`] over the bytes from `reader`'s position to its end (e.g. a
/// `Cursor` over a `.npy` file held in memory). `name` only labels errors,
/// which read exactly as [`read_npy`]'s for a file of that name; the
/// reader's length bounds every allocation as the file's does.
pub fn read_npy_from<R: Read + Seek>(mut reader: R, name: &Path) -> Result<NpyArray, IoError> {
    let len = remaining_len(&mut reader, name)?;
    read_npy_sized(reader, len, name)
}

/// Reads the prefix and header of a `.npy` of `file_len` bytes and checks
/// that the data fills the rest of the file exactly: the header, the
/// dtype, and the data's offset from the start of the file.
pub(crate) fn read_header(
    reader: &mut impl Read,
    file_len: u64,
    path: &Path,
) -> Result<(Header, Dtype, u64), IoError> {
    let fmt = |message: String| IoError::format(path, message);
    // Reads exactly `buf.len()` bytes; running out of file is a format error.
    let read_exact = |reader: &mut dyn Read, buf: &mut [u8], what: &str| {
        reader.read_exact(buf).map_err(|e| match e.kind() {
            ErrorKind::UnexpectedEof => fmt(format!("file ends inside the {what}")),
            _ => IoError::io(path, e),
        })
    };

    // Magic string and version.
    let mut prefix = [0u8; 8];
    if file_len < prefix.len() as u64 {
        return Err(fmt(format!(
            "not a .npy file: only {file_len} bytes long, too short for the \\x93NUMPY header"
        )));
    }
    read_exact(reader, &mut prefix, "file prefix")?;
    if &prefix[..6] != MAGIC {
        return Err(fmt(
            "not a .npy file: it does not start with the magic string \\x93NUMPY".to_string(),
        ));
    }
    let (major, minor) = (prefix[6], prefix[7]);

    // Header length: u16 in version 1.0, u32 in versions 2.0 and 3.0.
    let (header_len, prefix_len) = match (major, minor) {
        (1, 0) => {
            let mut len = [0u8; 2];
            read_exact(reader, &mut len, "header length")?;
            (u64::from(u16::from_le_bytes(len)), 10u64)
        }
        (2, 0) | (3, 0) => {
            let mut len = [0u8; 4];
            read_exact(reader, &mut len, "header length")?;
            (u64::from(u32::from_le_bytes(len)), 12u64)
        }
        _ => {
            return Err(fmt(format!(
                "unsupported .npy format version {major}.{minor} (expected 1.0, 2.0 or 3.0)"
            )));
        }
    };
    // Never allocate a header larger than the file.
    let after_prefix = file_len.saturating_sub(prefix_len);
    if header_len > after_prefix {
        return Err(fmt(format!(
            "header length is {header_len} bytes but only {after_prefix} bytes follow the prefix"
        )));
    }
    let mut header_bytes = vec![0u8; header_len as usize];
    read_exact(reader, &mut header_bytes, "header")?;
    // Versions 1.0 and 2.0 use latin-1, 3.0 uses UTF-8; a valid numeric header
    // is plain ASCII either way, so a lossy conversion only affects messages.
    let header_text = String::from_utf8_lossy(&header_bytes);
    let header = parse_header(&header_text).map_err(fmt)?;
    let dtype = Dtype::parse(&header.descr).map_err(fmt)?;

    // The data must fill the rest of the file exactly.
    let count = checked_product(&header.shape)
        .ok_or_else(|| fmt(format!("shape {} is too large", shape_text(&header.shape))))?;
    let needed = count.checked_mul(dtype.size).ok_or_else(|| {
        fmt(format!(
            "shape {} of {} values is too large",
            shape_text(&header.shape),
            dtype.name()
        ))
    })?;
    let available = after_prefix - header_len;
    if needed as u64 != available {
        let declared = format!(
            "header declares {} {} values ({needed} bytes)",
            dims_text(&header.shape),
            dtype.name()
        );
        let message = if (needed as u64) > available {
            format!("{declared} but only {available} bytes follow")
        } else {
            format!(
                "{declared} but {available} bytes follow ({} unexpected trailing bytes)",
                available - needed as u64
            )
        };
        return Err(fmt(message));
    }

    Ok((header, dtype, prefix_len + header_len))
}

/// The reader behind [`read_npy`] and [`read_npy_from`]: `reader` holds
/// `file_len` bytes, and `path` labels errors.
fn read_npy_sized(reader: impl Read, file_len: u64, path: &Path) -> Result<NpyArray, IoError> {
    let mut reader = BufReader::new(reader);
    let (header, dtype, _) = read_header(&mut reader, file_len, path)?;
    let count = checked_product(&header.shape).unwrap_or(0);
    let fmt = |message: String| IoError::format(path, message);
    let mut data = read_values(&mut reader, &dtype, count).map_err(|e| match e.kind() {
        ErrorKind::UnexpectedEof => fmt("file ends inside the array data".to_string()),
        _ => IoError::io(path, e),
    })?;
    if header.fortran_order && header.shape.len() > 1 {
        data = fortran_to_c(&data, &header.shape);
    }
    Ok(NpyArray {
        shape: header.shape,
        dtype: header.descr,
        data,
    })
}

/// Writes a `float32` array as a version 1.0 `.npy` file (`'<f4'`, C order)
/// with exactly the header layout `numpy.save` produces.
///
/// Fails with [`IoError::Format`] if the product of `shape` is not
/// `data.len()`; the file is then not created.
pub fn write_npy_f32(path: &Path, shape: &[usize], data: &[f32]) -> Result<(), IoError> {
    // Check before creating the file, so a bad call leaves no empty file.
    check_npy_shape(path, shape, data.len())?;
    crate::write_atomically(path, |out| write_npy_f32_to(out, path, shape, data))
}

/// [`write_npy_f32`] into any writer (a `Vec<u8>`, a socket): the same
/// bytes, then a flush. `name` only labels errors.
pub fn write_npy_f32_to<W: Write>(
    mut out: W,
    name: &Path,
    shape: &[usize],
    data: &[f32],
) -> Result<(), IoError> {
    check_npy_shape(name, shape, data.len())?;
    let header = npy_header("<f4", shape);
    let mut write = |bytes: &[u8]| out.write_all(bytes).map_err(|e| IoError::io(name, e));
    write(&header)?;
    // Converted in blocks of 256 KiB, each value's bytes copied in place
    // (a loop the compiler turns into wide copies; pushed a value at a
    // time, and written 16 KiB at a time, a 1024² image took ~2 ms).
    const BLOCK: usize = 1 << 16;
    let mut block = vec![0u8; 4 * BLOCK.min(data.len())];
    for chunk in data.chunks(BLOCK) {
        let bytes = &mut block[..4 * chunk.len()];
        for (b, v) in bytes.chunks_exact_mut(4).zip(chunk) {
            b.copy_from_slice(&v.to_le_bytes());
        }
        write(bytes)?;
    }
    out.flush().map_err(|e| IoError::io(name, e))
}

/// Fails unless `shape` holds exactly `len` values.
fn check_npy_shape(path: &Path, shape: &[usize], len: usize) -> Result<(), IoError> {
    match checked_product(shape) {
        Some(n) if n == len => Ok(()),
        _ => Err(IoError::format(
            path,
            format!(
                "cannot write .npy: shape {} does not match the {len} values given",
                shape_text(shape),
            ),
        )),
    }
}

/// Builds the magic, version, length and padded header dict, as NumPy's
/// `_wrap_header` does: the dict, spaces, then `\n`, such that the data
/// starts at a multiple of 64 bytes. Falls back to version 2.0 only if the
/// header does not fit a `u16` length (NumPy does the same).
fn npy_header(descr: &str, shape: &[usize]) -> Vec<u8> {
    let dict = format!(
        "{{'descr': '{descr}', 'fortran_order': False, 'shape': {}, }}",
        shape_text(shape)
    );
    let build = |major: u8, len_bytes: usize| {
        let hlen = dict.len() + 1; // + the final newline
        let pad = ALIGN - (MAGIC.len() + 2 + len_bytes + hlen) % ALIGN;
        let total = hlen + pad;
        let mut bytes = Vec::with_capacity(MAGIC.len() + 2 + len_bytes + total);
        bytes.extend_from_slice(MAGIC);
        bytes.extend_from_slice(&[major, 0]);
        if len_bytes == 2 {
            bytes.extend_from_slice(&u16::try_from(total).ok()?.to_le_bytes());
        } else {
            bytes.extend_from_slice(&u32::try_from(total).ok()?.to_le_bytes());
        }
        bytes.extend_from_slice(dict.as_bytes());
        bytes.resize(bytes.len() + pad, b' ');
        bytes.push(b'\n');
        Some(bytes)
    };
    match build(1, 2) {
        Some(bytes) => bytes,
        // A shape with thousands of axes: NumPy switches to version 2.0 too.
        None => build(2, 4).unwrap_or_default(),
    }
}

/// Python's repr of a shape tuple: `()`, `(10,)`, `(10, 3)`.
fn shape_text(shape: &[usize]) -> String {
    match shape {
        [] => "()".to_string(),
        [n] => format!("({n},)"),
        _ => {
            let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
            format!("({})", dims.join(", "))
        }
    }
}

/// A shape for messages: `1000000 x 3`, or `1 (scalar)` for a 0-d array.
fn dims_text(shape: &[usize]) -> String {
    if shape.is_empty() {
        return "1 (scalar)".to_string();
    }
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    dims.join(" x ")
}

/// The number kind of a dtype.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Float,
    Int,
    Uint,
    Bool,
}

/// A parsed numeric dtype: kind, item size in bytes and byte order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Dtype {
    kind: Kind,
    size: usize,
    big_endian: bool,
}

impl Dtype {
    /// Parses a simple descr such as `<f4`, `>i8`, `|u1`, `|b1` or `=f8`.
    pub(crate) fn parse(descr: &str) -> Result<Dtype, String> {
        let unsupported = || {
            format!("unsupported dtype '{descr}' (expected float32, float64 or an integer type)")
        };
        let native_big = cfg!(target_endian = "big");
        let (big_endian, rest) = match descr.as_bytes().first() {
            Some(b'<') => (false, &descr[1..]),
            Some(b'>') => (true, &descr[1..]),
            // '|' means "byte order not applicable"; '=' means native.
            Some(b'|') | Some(b'=') => (native_big, &descr[1..]),
            _ => (native_big, descr),
        };
        if rest == "?" {
            return Ok(Dtype {
                kind: Kind::Bool,
                size: 1,
                big_endian,
            });
        }
        let mut chars = rest.chars();
        let kind = match chars.next() {
            Some('f') => Kind::Float,
            Some('i') => Kind::Int,
            Some('u') => Kind::Uint,
            Some('b') => Kind::Bool,
            _ => return Err(unsupported()),
        };
        let size: usize = chars.as_str().parse().map_err(|_| unsupported())?;
        let valid = match kind {
            Kind::Float => matches!(size, 2 | 4 | 8),
            Kind::Int | Kind::Uint => matches!(size, 1 | 2 | 4 | 8),
            Kind::Bool => size == 1,
        };
        if !valid {
            return Err(unsupported());
        }
        Ok(Dtype {
            kind,
            size,
            big_endian,
        })
    }

    /// NumPy's name for the type, for messages: `float32`, `uint8`, `bool`.
    fn name(&self) -> String {
        match self.kind {
            Kind::Float => format!("float{}", self.size * 8),
            Kind::Int => format!("int{}", self.size * 8),
            Kind::Uint => format!("uint{}", self.size * 8),
            Kind::Bool => "bool".to_string(),
        }
    }
}

/// Reads `count` values of type `dtype` and converts them to `f64`.
/// The caller has checked that the file holds exactly these bytes.
pub(crate) fn read_values(
    reader: &mut impl Read,
    dtype: &Dtype,
    count: usize,
) -> std::io::Result<Vec<f64>> {
    const BLOCK_ITEMS: usize = 8192;
    let mut data = Vec::with_capacity(count);
    let mut block = vec![0u8; BLOCK_ITEMS * dtype.size];
    let mut left = count;
    while left > 0 {
        let n = left.min(BLOCK_ITEMS);
        let bytes = &mut block[..n * dtype.size];
        reader.read_exact(bytes)?;
        decode(bytes, dtype, &mut data);
        left -= n;
    }
    Ok(data)
}

/// Converts each `N`-byte item of `bytes` with `convert` and appends it.
fn decode_items<const N: usize>(
    bytes: &[u8],
    out: &mut Vec<f64>,
    convert: impl Fn([u8; N]) -> f64,
) {
    // Extended from an iterator of known length, not pushed one at a time:
    // the compiler converts whole vectors of items (~3× faster on the
    // float32 positions of a 2.1M-particle projection).
    out.extend(bytes.chunks_exact(N).map(|item| {
        let mut raw = [0u8; N];
        raw.copy_from_slice(item);
        convert(raw)
    }));
}

/// Picks the big- or little-endian decoder of a number type.
macro_rules! from_bytes {
    ($big:expr, $t:ty) => {
        |raw| {
            if $big {
                <$t>::from_be_bytes(raw) as f64
            } else {
                <$t>::from_le_bytes(raw) as f64
            }
        }
    };
}

/// Decodes a block of raw items of type `dtype`, appending them to `out`.
fn decode(bytes: &[u8], dtype: &Dtype, out: &mut Vec<f64>) {
    let big = dtype.big_endian;
    match (dtype.kind, dtype.size) {
        (Kind::Float, 2) => decode_items::<2>(bytes, out, |raw| {
            let bits = if big {
                u16::from_be_bytes(raw)
            } else {
                u16::from_le_bytes(raw)
            };
            f16_to_f64(bits)
        }),
        (Kind::Float, 4) => decode_items::<4>(bytes, out, from_bytes!(big, f32)),
        (Kind::Float, _) => decode_items::<8>(bytes, out, from_bytes!(big, f64)),
        (Kind::Int, 1) => decode_items::<1>(bytes, out, from_bytes!(big, i8)),
        (Kind::Int, 2) => decode_items::<2>(bytes, out, from_bytes!(big, i16)),
        (Kind::Int, 4) => decode_items::<4>(bytes, out, from_bytes!(big, i32)),
        (Kind::Int, _) => decode_items::<8>(bytes, out, from_bytes!(big, i64)),
        (Kind::Uint, 1) => decode_items::<1>(bytes, out, from_bytes!(big, u8)),
        (Kind::Uint, 2) => decode_items::<2>(bytes, out, from_bytes!(big, u16)),
        (Kind::Uint, 4) => decode_items::<4>(bytes, out, from_bytes!(big, u32)),
        (Kind::Uint, _) => decode_items::<8>(bytes, out, from_bytes!(big, u64)),
        (Kind::Bool, _) => out.extend(bytes.iter().map(|&b| if b != 0 { 1.0 } else { 0.0 })),
    }
}

/// Converts IEEE 754 half-precision bits to `f64` (exactly).
fn f16_to_f64(bits: u16) -> f64 {
    let sign = if bits & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exponent = i32::from((bits >> 10) & 0x1f);
    let fraction = f64::from(bits & 0x3ff);
    let magnitude = match exponent {
        0 => fraction * 2f64.powi(-24),
        31 if fraction == 0.0 => f64::INFINITY,
        31 => f64::NAN,
        _ => (1.0 + fraction / 1024.0) * 2f64.powi(exponent - 15),
    };
    sign * magnitude
}

/// Reorders Fortran-order (column-major) data of `shape` into C order.
fn fortran_to_c(data: &[f64], shape: &[usize]) -> Vec<f64> {
    // Fortran strides: the first axis varies fastest.
    let mut strides = Vec::with_capacity(shape.len());
    let mut stride = 1usize;
    for &d in shape {
        strides.push(stride);
        stride = stride.saturating_mul(d);
    }
    let mut out = Vec::with_capacity(data.len());
    let mut index = vec![0usize; shape.len()];
    let mut offset = 0usize; // Fortran offset of `index`
    for _ in 0..data.len() {
        out.push(data[offset]);
        // Advance the C-order multi-index (last axis fastest), updating offset.
        for axis in (0..shape.len()).rev() {
            index[axis] += 1;
            offset += strides[axis];
            if index[axis] < shape[axis] {
                break;
            }
            offset -= strides[axis] * shape[axis];
            index[axis] = 0;
        }
    }
    out
}

/// The three entries of a `.npy` header dict.
#[derive(Debug)]
pub(crate) struct Header {
    pub descr: String,
    pub fortran_order: bool,
    pub shape: Vec<usize>,
}

/// A Python literal as it may appear in a `.npy` header.
#[derive(Debug)]
enum Literal {
    Str(String),
    Bool(bool),
    None,
    /// Integer digits as written (sign included, Python 2 `L` suffix removed).
    Int(String),
    /// A tuple or a list.
    Seq(Vec<Literal>),
}

/// Parses the header dict; errors are messages without the path.
fn parse_header(text: &str) -> Result<Header, String> {
    let mut parser = Parser { text, pos: 0 };
    let entries = parser.dict()?;
    parser.skip_ws();
    if parser.pos < text.len() {
        return Err(format!(
            "invalid header: unexpected text after the dict: {:?}",
            excerpt(&text[parser.pos..])
        ));
    }

    let (mut descr, mut fortran_order, mut shape) = (None, None, None);
    for (key, value, raw) in entries {
        let slot_taken = match key.as_str() {
            "descr" => descr.replace((value, raw)).is_some(),
            "fortran_order" => fortran_order.replace((value, raw)).is_some(),
            "shape" => shape.replace((value, raw)).is_some(),
            _ => return Err(format!("invalid header: unexpected key '{key}'")),
        };
        if slot_taken {
            return Err(format!("invalid header: key '{key}' appears twice"));
        }
    }
    let missing = |key: &str| format!("invalid header: missing key '{key}'");

    let descr = match descr.ok_or_else(|| missing("descr"))? {
        (Literal::Str(s), _) => s,
        (_, raw) => {
            return Err(format!(
                "unsupported structured dtype {raw} (expected float32, float64 or an integer type)"
            ));
        }
    };
    let fortran_order = match fortran_order.ok_or_else(|| missing("fortran_order"))? {
        (Literal::Bool(b), _) => b,
        (_, raw) => {
            return Err(format!(
                "invalid header: 'fortran_order' is {raw}, expected True or False"
            ));
        }
    };
    let shape = match shape.ok_or_else(|| missing("shape"))? {
        (Literal::Seq(items), raw) => items
            .iter()
            .map(|item| match item {
                Literal::Int(digits) => digits.parse::<usize>().map_err(|_| {
                    format!(
                        "invalid header: shape {raw} has an invalid or too large dimension {digits}"
                    )
                }),
                _ => Err(format!(
                    "invalid header: shape {raw} must hold only integers"
                )),
            })
            .collect::<Result<Vec<usize>, String>>()?,
        (_, raw) => return Err(format!("invalid header: shape {raw} is not a tuple")),
    };
    Ok(Header {
        descr,
        fortran_order,
        shape,
    })
}

/// The start of `text`, for error messages.
fn excerpt(text: &str) -> String {
    text.chars().take(40).collect()
}

/// A tiny recursive-descent parser for the Python literals of a header.
struct Parser<'a> {
    text: &'a str,
    pos: usize,
}

impl Parser<'_> {
    fn peek(&self) -> Option<u8> {
        self.text.as_bytes().get(self.pos).copied()
    }

    fn skip_ws(&mut self) {
        while matches!(self.peek(), Some(b' ' | b'\t' | b'\n' | b'\r')) {
            self.pos += 1;
        }
    }

    fn expect(&mut self, byte: u8) -> Result<(), String> {
        self.skip_ws();
        if self.peek() == Some(byte) {
            self.pos += 1;
            Ok(())
        } else {
            Err(self.error(&format!("expected '{}'", byte as char)))
        }
    }

    fn error(&self, what: &str) -> String {
        let rest = self.text.get(self.pos..).unwrap_or("");
        if rest.is_empty() {
            format!("invalid header: {what} but the header ends")
        } else {
            format!("invalid header: {what} at {:?}", excerpt(rest))
        }
    }

    /// `{ 'key': value, ... }`, returning (key, value, value source text).
    fn dict(&mut self) -> Result<Vec<(String, Literal, String)>, String> {
        self.expect(b'{')?;
        let mut entries = Vec::new();
        loop {
            self.skip_ws();
            if self.peek() == Some(b'}') {
                self.pos += 1;
                return Ok(entries);
            }
            let key = match self.value(0)? {
                Literal::Str(key) => key,
                _ => return Err("invalid header: dict keys must be strings".to_string()),
            };
            self.expect(b':')?;
            self.skip_ws();
            let start = self.pos;
            let value = self.value(0)?;
            let raw = self.text[start..self.pos].to_string();
            entries.push((key, value, raw));
            self.skip_ws();
            match self.peek() {
                Some(b',') => self.pos += 1,
                Some(b'}') => {}
                _ => return Err(self.error("expected ',' or '}'")),
            }
        }
    }

    /// Any literal: string, True/False/None, integer, tuple or list.
    fn value(&mut self, depth: usize) -> Result<Literal, String> {
        if depth > MAX_DEPTH {
            return Err("invalid header: literals nested too deeply".to_string());
        }
        self.skip_ws();
        match self.peek() {
            Some(q @ (b'\'' | b'"')) => self.string(q),
            Some(b'(') => self.sequence(b')', depth),
            Some(b'[') => self.sequence(b']', depth),
            Some(b'-' | b'+' | b'0'..=b'9') => Ok(self.integer()),
            Some(c) if c.is_ascii_alphabetic() => {
                let start = self.pos;
                while self
                    .peek()
                    .is_some_and(|c| c.is_ascii_alphanumeric() || c == b'_')
                {
                    self.pos += 1;
                }
                match &self.text[start..self.pos] {
                    "True" => Ok(Literal::Bool(true)),
                    "False" => Ok(Literal::Bool(false)),
                    "None" => Ok(Literal::None),
                    word => Err(format!("invalid header: unknown name '{word}'")),
                }
            }
            _ => Err(self.error("expected a value")),
        }
    }

    /// A quoted string; backslash escapes the next character.
    fn string(&mut self, quote: u8) -> Result<Literal, String> {
        self.pos += 1; // opening quote
        let mut out = String::new();
        let mut chars = self.text[self.pos..].char_indices();
        while let Some((i, c)) = chars.next() {
            match c {
                '\\' => match chars.next() {
                    Some((_, escaped)) => out.push(escaped),
                    None => break,
                },
                c if c as u32 == u32::from(quote) => {
                    self.pos += i + 1;
                    return Ok(Literal::Str(out));
                }
                c => out.push(c),
            }
        }
        self.pos = self.text.len();
        Err("invalid header: unterminated string".to_string())
    }

    /// An integer such as `10`, `-1` or Python 2's `10L`.
    fn integer(&mut self) -> Literal {
        let start = self.pos;
        self.pos += 1; // sign or first digit
        while self.peek().is_some_and(|c| c.is_ascii_digit()) {
            self.pos += 1;
        }
        let digits = self.text[start..self.pos].to_string();
        if self.peek() == Some(b'L') {
            self.pos += 1;
        }
        Literal::Int(digits)
    }

    /// A tuple `(a, b)` or list `[a, b]`, with optional trailing comma.
    fn sequence(&mut self, close: u8, depth: usize) -> Result<Literal, String> {
        self.pos += 1; // opening bracket
        let mut items = Vec::new();
        loop {
            self.skip_ws();
            if self.peek() == Some(close) {
                self.pos += 1;
                return Ok(Literal::Seq(items));
            }
            items.push(self.value(depth + 1)?);
            self.skip_ws();
            match self.peek() {
                Some(b',') => self.pos += 1,
                Some(c) if c == close => {}
                _ => return Err(self.error(&format!("expected ',' or '{}'", close as char))),
            }
        }
    }
}

#[cfg(test)]
mod tests;
