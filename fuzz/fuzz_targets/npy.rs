//! `read_npy` on the input as a `.npy` file.

#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = voxless_fuzz::write("input.npy", data);
    let _ = voxless_io::read_npy(&path);
});
