//! `read_vtu_mesh_bytes` on the input as the content of a `.vtu` file.

#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = voxless_io::read_vtu_mesh_bytes(data, Path::new("mesh.vtu"));
});
