//! `read_csv_from` on the input as the text of a `.csv` file.

#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = voxless_io::read_csv_from(data, Path::new("input.csv"));
});
