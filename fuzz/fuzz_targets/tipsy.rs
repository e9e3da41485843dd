//! `sniff_tipsy`, then `read_tipsy_from` of every Tipsy particle type and
//! the default one, on the input as a Tipsy snapshot.

#![no_main]

use std::io::Cursor;
use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let name = Path::new("input.std");
    let _ = voxless_io::tipsy::sniff_tipsy(data, data.len() as u64);
    let _ = voxless_io::tipsy::tipsy_header_from(Cursor::new(data), name);
    for part_type in [None, Some(0), Some(1), Some(4), Some(5)] {
        let _ = voxless_io::tipsy::read_tipsy_from(Cursor::new(data), name, part_type);
    }
});
