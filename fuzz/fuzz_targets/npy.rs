//! `read_npy_from` on the input as the content of a `.npy` file.

#![no_main]

use std::io::Cursor;
use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = voxless_io::read_npy_from(Cursor::new(data), Path::new("input.npy"));
});
