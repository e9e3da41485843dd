//! `xyz_frames_from`, then `read_xyz_from` of frame 0 and of the last frame,
//! on the input as a (plain or extended) XYZ file.

#![no_main]

use std::io::Cursor;
use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let name = Path::new("input.xyz");
    let frames = voxless_io::xyz_frames_from(data, name);
    let _ = voxless_io::read_xyz_from(Cursor::new(data), name, 0);
    if let Ok(n) = frames
        && n > 1
    {
        let _ = voxless_io::read_xyz_from(Cursor::new(data), name, n - 1);
    }
});
