//! `read_vtk_points` on the input as a VTK XML file, named `.vtp` when the
//! input's length is even and `.vtu` when it is odd (the reader goes by the
//! content, not the name, but both names are exercised).

#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let name = if data.len().is_multiple_of(2) {
        "input.vtp"
    } else {
        "input.vtu"
    };
    let path = voxless_fuzz::write(name, data);
    let _ = voxless_io::read_vtk_points(&path);
});
