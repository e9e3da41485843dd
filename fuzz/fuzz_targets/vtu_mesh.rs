//! `read_vtu_mesh` on the input as a `.vtu` file.

#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = voxless_fuzz::write("mesh.vtu", data);
    let _ = voxless_io::read_vtu_mesh(&path);
});
