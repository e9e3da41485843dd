//! `read_vtk_points_bytes` on the input as the content of a VTK XML file
//! (`.vtp`, `.vtu` or any dataset with points).

#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = voxless_io::read_vtk_points_bytes(data, Path::new("input.vtp"));
});
