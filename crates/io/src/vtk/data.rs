//! Decoding the values of a `DataArray`: ascii text, inline base64, appended
//! raw or base64 bytes, optionally zlib-compressed.
//!
//! Binary data (inline or appended) is a header followed by the values:
//!
//! - uncompressed: one header integer, the number of data bytes;
//! - compressed: `[nblocks, block size, last block size, compressed size 1,
//!   ..., compressed size nblocks]`, then the zlib streams of the blocks back
//!   to back. Every block but the last holds `block size` bytes when
//!   decompressed; the last holds `last block size`, or `block size` when
//!   that is 0.
//!
//! Header integers are `UInt32` or `UInt64` (`header_type`) in the file's
//! byte order. In base64 form VTK encodes the header of compressed data on
//! its own (padded) and the blocks as a second stream, while uncompressed
//! header and data share one stream; [`decode_base64`] handles both by
//! decoding each padded stream separately.
//!
//! Every size read from a header is checked against the bytes actually
//! present before anything is allocated for it.

use std::borrow::Cow;
use std::io::Read;

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD;
use flate2::read::ZlibDecoder;

use super::xml::{ArraySpec, ByteOrder, Document, Encoding, Format, HeaderType, Scalar};

/// zlib cannot expand data by more than about 1032 to 1; a header claiming
/// more is corrupt (checked before decompressing).
const MAX_ZLIB_RATIO: u64 = 1100;

/// The file's bytes and structure, for decoding its arrays.
pub(super) struct Source<'a> {
    pub bytes: &'a [u8],
    pub doc: &'a Document,
}

impl<'a> Source<'a> {
    pub(super) fn new(bytes: &'a [u8], doc: &'a Document) -> Source<'a> {
        Source { bytes, doc }
    }

    /// The values of `spec` as `f64`. With `tuples`, the array must hold
    /// exactly `tuples * components` values; without, any whole number of
    /// tuples is accepted.
    pub(super) fn values(
        &self,
        spec: &ArraySpec,
        tuples: Option<usize>,
    ) -> Result<Vec<f64>, String> {
        let scalar = spec.scalar.ok_or_else(|| {
            format!(
                "type \"{}\" is not supported (expected Float32, Float64, Int8..Int64 or \
                 UInt8..UInt64)",
                spec.type_name
            )
        })?;
        let expected = match tuples {
            Some(t) => Some(t.checked_mul(spec.components).ok_or_else(|| {
                format!("{t} tuples of {} components is too many", spec.components)
            })?),
            None => None,
        };
        // The bytes the array's values take, when their count is known.
        let bytes_of =
            |n: Option<usize>| n.map(|n| (n as u64).saturating_mul(scalar.size() as u64));
        let values = match spec.format {
            Format::Ascii => ascii_values(&spec.text, expected)?,
            Format::Binary => {
                let text: Vec<u8> = spec
                    .text
                    .iter()
                    .copied()
                    .filter(|b| !b.is_ascii_whitespace())
                    .collect();
                let blob = decode_base64(&text)?;
                let data = self.payload(&blob, bytes_of(expected))?;
                convert(&data, scalar, self.doc.byte_order, expected)?
            }
            Format::Appended(offset) => {
                let appended = self
                    .doc
                    .appended
                    .ok_or("the array is appended but the file has no <AppendedData>")?;
                let region = &self.bytes[appended.start..appended.end];
                if offset > region.len() {
                    return Err(format!(
                        "offset {offset} is past the end of the appended data ({} bytes)",
                        region.len()
                    ));
                }
                match appended.encoding {
                    Encoding::Raw => {
                        let data = self.payload(&region[offset..], bytes_of(expected))?;
                        convert(&data, scalar, self.doc.byte_order, expected)?
                    }
                    Encoding::Base64 => {
                        let end = self
                            .doc
                            .appended_offsets
                            .iter()
                            .find(|&&o| o > offset)
                            .map_or(region.len(), |&o| o.min(region.len()));
                        let text: Vec<u8> = region[offset..end]
                            .iter()
                            .copied()
                            .filter(|b| !b.is_ascii_whitespace())
                            .collect();
                        let blob = decode_base64(&text)?;
                        let data = self.payload(&blob, bytes_of(expected))?;
                        convert(&data, scalar, self.doc.byte_order, expected)?
                    }
                }
            }
        };
        if expected.is_none() && !values.len().is_multiple_of(spec.components) {
            return Err(format!(
                "holds {} values, not a whole number of {}-component tuples",
                values.len(),
                spec.components
            ));
        }
        Ok(values)
    }

    /// The data bytes of a binary block `blob` (header, then data); `limit`
    /// is what the array needs, when its size is known (compressed data
    /// declaring more is refused before it is inflated).
    fn payload<'b>(&self, blob: &'b [u8], limit: Option<u64>) -> Result<Cow<'b, [u8]>, String> {
        let header = self.doc.header;
        let order = self.doc.byte_order;
        let hsize = header.size();
        let word = |i: usize| -> Result<u64, String> {
            let start = i * hsize;
            blob.get(start..start + hsize)
                .map(|b| read_uint(b, header, order))
                .ok_or_else(|| format!("binary data ends inside its header ({} bytes)", blob.len()))
        };
        match self.doc.compressor.as_deref() {
            None => {
                let n = word(0)?;
                let available = (blob.len() - hsize) as u64;
                if n > available {
                    return Err(format!(
                        "header declares {n} data bytes but only {available} follow"
                    ));
                }
                Ok(Cow::Borrowed(&blob[hsize..hsize + n as usize]))
            }
            Some("vtkZLibDataCompressor") => decompress(blob, hsize, &word, limit).map(Cow::Owned),
            Some(other) => Err(format!(
                "compressor \"{other}\" is not supported (only vtkZLibDataCompressor)"
            )),
        }
    }
}

/// Decompresses zlib-compressed blocks (see the module docs).
fn decompress(
    blob: &[u8],
    hsize: usize,
    word: &dyn Fn(usize) -> Result<u64, String>,
    limit: Option<u64>,
) -> Result<Vec<u8>, String> {
    let blocks = word(0)?;
    let block_size = word(1)?;
    let last_size = word(2)?;
    let room = (blob.len() / hsize).saturating_sub(3) as u64;
    if blocks > room {
        return Err(format!(
            "compression header declares {blocks} blocks but the data holds at most {room} \
             block sizes"
        ));
    }
    let blocks = blocks as usize;
    let header_len = (3 + blocks) * hsize;
    let mut compressed = Vec::with_capacity(blocks);
    let mut total_compressed = 0u64;
    for i in 0..blocks {
        let c = word(3 + i)?;
        total_compressed = total_compressed.saturating_add(c);
        compressed.push(c);
    }
    let available = (blob.len() - header_len) as u64;
    if total_compressed > available {
        return Err(format!(
            "compression header declares {total_compressed} compressed bytes but only \
             {available} follow"
        ));
    }
    if last_size > block_size {
        return Err(format!(
            "last block size {last_size} is larger than the block size {block_size}"
        ));
    }
    // What each block inflates to, checked against what zlib can make of its
    // compressed bytes, and the sum against what the array needs, before
    // anything is reserved: a bomb (a few bytes declaring gigabytes) is
    // refused, not allocated, and memory that cannot be had is an error
    // rather than an abort.
    let expected_size = |i: usize| {
        if i + 1 == blocks && last_size != 0 {
            last_size
        } else {
            block_size
        }
    };
    let mut total = 0u64;
    for (i, &c) in compressed.iter().enumerate() {
        let expected = expected_size(i);
        if expected > c.saturating_mul(MAX_ZLIB_RATIO) + 64 {
            return Err(format!(
                "block {i} claims {expected} bytes from {c} compressed bytes, more than zlib \
                 can expand"
            ));
        }
        total = total.saturating_add(expected);
    }
    if let Some(limit) = limit
        && total > limit
    {
        return Err(format!(
            "compression header declares {total} bytes once inflated, but the array holds \
             {limit}"
        ));
    }
    let mut out = Vec::new();
    usize::try_from(total)
        .ok()
        .and_then(|t| out.try_reserve_exact(t).ok())
        .ok_or_else(|| format!("the inflated data, {total} bytes, does not fit in memory"))?;
    let mut pos = header_len;
    for (i, &c) in compressed.iter().enumerate() {
        let expected = expected_size(i);
        let input = &blob[pos..pos + c as usize];
        pos += c as usize;
        let before = out.len();
        ZlibDecoder::new(input)
            .take(expected + 1)
            .read_to_end(&mut out)
            .map_err(|e| format!("block {i} is not valid zlib data: {e}"))?;
        let got = (out.len() - before) as u64;
        if got != expected {
            return Err(format!(
                "block {i} decompresses to {got} bytes, expected {expected}"
            ));
        }
    }
    Ok(out)
}

/// Reads an unsigned header integer.
fn read_uint(b: &[u8], header: HeaderType, order: ByteOrder) -> u64 {
    match (header, order) {
        (HeaderType::U32, ByteOrder::Little) => {
            u64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        }
        (HeaderType::U32, ByteOrder::Big) => {
            u64::from(u32::from_be_bytes([b[0], b[1], b[2], b[3]]))
        }
        (HeaderType::U64, ByteOrder::Little) => {
            u64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]])
        }
        (HeaderType::U64, ByteOrder::Big) => {
            u64::from_be_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]])
        }
    }
}

/// Decodes base64 text that may be several padded streams back to back
/// (whitespace already removed): the text is split after each run of `=`.
pub(super) fn decode_base64(text: &[u8]) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(text.len() / 4 * 3);
    let mut start = 0;
    let mut i = 0;
    while i < text.len() {
        if text[i] == b'=' {
            while i < text.len() && text[i] == b'=' {
                i += 1;
            }
            decode_chunk(&text[start..i], &mut out)?;
            start = i;
        } else {
            i += 1;
        }
    }
    decode_chunk(&text[start..], &mut out)?;
    Ok(out)
}

fn decode_chunk(chunk: &[u8], out: &mut Vec<u8>) -> Result<(), String> {
    if chunk.is_empty() {
        return Ok(());
    }
    STANDARD
        .decode_vec(chunk, out)
        .map_err(|e| format!("invalid base64 data: {e}"))
}

/// Parses whitespace-separated numbers.
fn ascii_values(text: &[u8], expected: Option<usize>) -> Result<Vec<f64>, String> {
    let text = std::str::from_utf8(text).map_err(|_| "ascii data is not UTF-8 text".to_string())?;
    let mut values = Vec::new();
    for token in text.split_ascii_whitespace() {
        if let Some(n) = expected
            && values.len() == n
        {
            let found = text.split_ascii_whitespace().count();
            return Err(format!("expected {n} values but found {found}"));
        }
        let v: f64 = token.parse().map_err(|_| {
            let shown: String = token.chars().take(40).collect();
            format!("cannot parse '{shown}' as a number")
        })?;
        values.push(v);
    }
    if let Some(n) = expected
        && values.len() != n
    {
        return Err(format!(
            "expected {n} values but found only {}",
            values.len()
        ));
    }
    Ok(values)
}

/// Converts raw bytes of `scalar` values to `f64`, checking the count.
fn convert(
    data: &[u8],
    scalar: Scalar,
    order: ByteOrder,
    expected: Option<usize>,
) -> Result<Vec<f64>, String> {
    let size = scalar.size();
    if let Some(n) = expected
        && n.checked_mul(size) != Some(data.len())
    {
        return Err(format!(
            "expected {n} values ({} bytes) but the data holds {} bytes",
            n.saturating_mul(size),
            data.len()
        ));
    }
    if !data.len().is_multiple_of(size) {
        return Err(format!(
            "{} data bytes are not a whole number of {size}-byte values",
            data.len()
        ));
    }
    macro_rules! conv {
        ($t:ty) => {
            data.chunks_exact(size)
                .map(|c| {
                    let b = c.try_into().unwrap_or([0; std::mem::size_of::<$t>()]);
                    (match order {
                        ByteOrder::Little => <$t>::from_le_bytes(b),
                        ByteOrder::Big => <$t>::from_be_bytes(b),
                    }) as f64
                })
                .collect()
        };
    }
    Ok(match scalar {
        Scalar::F32 => conv!(f32),
        Scalar::F64 => conv!(f64),
        Scalar::I8 => conv!(i8),
        Scalar::I16 => conv!(i16),
        Scalar::I32 => conv!(i32),
        Scalar::I64 => conv!(i64),
        Scalar::U8 => conv!(u8),
        Scalar::U16 => conv!(u16),
        Scalar::U32 => conv!(u32),
        Scalar::U64 => conv!(u64),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_streams_back_to_back() {
        // "AQ==" is [1]; "AgME" is [2, 3, 4]; "BQ==" is [5].
        assert_eq!(decode_base64(b"AQ==AgMEBQ==").unwrap(), [1, 2, 3, 4, 5]);
        assert_eq!(decode_base64(b"").unwrap(), Vec::<u8>::new());
        assert!(decode_base64(b"AQ=").is_err());
        assert!(decode_base64(b"A$==").is_err());
    }

    #[test]
    fn ascii_counts() {
        assert_eq!(ascii_values(b" 1 2\n3 ", Some(3)).unwrap(), [1.0, 2.0, 3.0]);
        assert!(
            ascii_values(b"1 2", Some(3))
                .unwrap_err()
                .contains("only 2")
        );
        assert!(
            ascii_values(b"1 2 3 4", Some(3))
                .unwrap_err()
                .contains("found 4")
        );
        assert!(ascii_values(b"1 x", None).is_err());
    }

    #[test]
    fn converts_each_type() {
        let be = [0x3f, 0x80, 0, 0];
        assert_eq!(
            convert(&be, Scalar::F32, ByteOrder::Big, Some(1)).unwrap(),
            [1.0]
        );
        let le = (-5i16).to_le_bytes();
        assert_eq!(
            convert(&le, Scalar::I16, ByteOrder::Little, None).unwrap(),
            [-5.0]
        );
        assert!(convert(&[0; 5], Scalar::U32, ByteOrder::Little, None).is_err());
        assert!(convert(&[0; 8], Scalar::U32, ByteOrder::Little, Some(3)).is_err());
    }

    #[test]
    fn a_block_claiming_more_than_zlib_can_expand_is_refused_before_reserving() {
        // Header [1 block, 2^62 bytes, last 0, 17 compressed bytes], no
        // limit: the claim is refused by the zlib ratio, before the reserve
        // (which would say "does not fit in memory").
        let mut blob = Vec::new();
        for w in [1u64, 1 << 62, 0, 17] {
            blob.extend_from_slice(&w.to_le_bytes());
        }
        blob.extend_from_slice(&[0; 17]);
        let word = |i: usize| {
            Ok(u64::from_le_bytes(
                blob[i * 8..i * 8 + 8].try_into().unwrap(),
            ))
        };
        let msg = decompress(&blob, 8, &word, None).unwrap_err();
        assert!(msg.contains("more than zlib can expand"), "{msg}");
    }
}
