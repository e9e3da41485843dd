//! `xyz_frames`, then `read_xyz` of frame 0 and of the last frame, on the
//! input as a (plain or extended) XYZ file.

#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = voxless_fuzz::write("input.xyz", data);
    let frames = voxless_io::xyz_frames(&path);
    let _ = voxless_io::read_xyz(&path, 0);
    if let Ok(n) = frames
        && n > 1
    {
        let _ = voxless_io::read_xyz(&path, n - 1);
    }
});
