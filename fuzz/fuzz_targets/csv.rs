//! `read_csv` on the input as a `.csv` file.

#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = voxless_fuzz::write("input.csv", data);
    let _ = voxless_io::read_csv(&path);
});
