//! `sniff_gadget_binary`, then `read_gadget_binary_from` of the default
//! particle type and of gas, on the input as one Gadget binary file
//! (format 1 or 2, either byte order).

#![no_main]

use std::io::Cursor;
use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let name = Path::new("input");
    let _ = voxless_io::gadget_bin::sniff_gadget_binary(data);
    for part_type in [None, Some(0)] {
        let _ = voxless_io::gadget_bin::read_gadget_binary_from(Cursor::new(data), name, part_type);
    }
});
