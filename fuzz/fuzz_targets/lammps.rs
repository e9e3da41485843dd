//! `lammps_frames_from`, then `read_lammps_from` of frame 0 and of the last
//! frame, on the input as a LAMMPS text dump.

#![no_main]

use std::io::Cursor;
use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let name = Path::new("dump.lammpstrj");
    let frames = voxless_io::lammps_frames_from(data, name);
    let _ = voxless_io::read_lammps_from(Cursor::new(data), name, 0);
    if let Ok(n) = frames
        && n > 1
    {
        let _ = voxless_io::read_lammps_from(Cursor::new(data), name, n - 1);
    }
});
