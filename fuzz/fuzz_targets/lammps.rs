//! `lammps_frames`, then `read_lammps` of frame 0 and of the last frame, on
//! the input as a LAMMPS text dump.

#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = voxless_fuzz::write("dump.lammpstrj", data);
    let frames = voxless_io::lammps_frames(&path);
    let _ = voxless_io::read_lammps(&path, 0);
    if let Ok(n) = frames
        && n > 1
    {
        let _ = voxless_io::read_lammps(&path, n - 1);
    }
});
