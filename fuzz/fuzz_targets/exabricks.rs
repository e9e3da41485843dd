//! `read_exabricks_bytes` on the contents of a `.cells` file, up to three
//! `.scalars` files and an optional `.meta.json`, all cut from the input:
//!
//! - byte 0: flags; bits 0-1 give the number of scalars parts (0 to 3),
//!   bit 2 says whether there is a meta JSON part;
//! - bytes 1-2: the length of the `.cells` part (`u16`, little-endian),
//!   which follows;
//! - with a meta part: one length byte, then the JSON;
//! - the rest: the scalars parts, each but the last taking a quarter of the
//!   cells part's length (one `f32` per 16-byte cell), the last taking all
//!   that remains.
//!
//! Parts are clamped to the bytes available, so any input is usable.

#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use voxless_fuzz::split;

const FIELDS: [&str; 3] = ["density", "energy", "momentum_x"];

fuzz_target!(|data: &[u8]| {
    let Some((&flags, rest)) = data.split_first() else {
        return;
    };
    let (len, rest) = split(rest, 2);
    let cells_len = match *len {
        [a, b] => usize::from(u16::from_le_bytes([a, b])),
        [a] => usize::from(a),
        _ => 0,
    };
    let (cells, mut rest) = split(rest, cells_len);

    let mut meta = None;
    if flags & 4 != 0 {
        let (len, after) = split(rest, 1);
        let (json, after) = split(after, len.first().map_or(0, |&b| usize::from(b)));
        meta = Some(json);
        rest = after;
    }

    let count = usize::from(flags & 3);
    let mut scalars = Vec::with_capacity(count);
    for (i, &field) in FIELDS.iter().take(count).enumerate() {
        let part;
        if i + 1 == count {
            part = rest;
        } else {
            (part, rest) = split(rest, cells.len() / 4);
        }
        scalars.push((field, part));
    }
    let _ = voxless_io::read_exabricks_bytes(cells, Path::new("frame.cells"), &scalars, meta);
});
