//! `read_particles_from` of a fixed index that lists the timestep `0`; the
//! input is that timestep's binary data (a `u64` count, then four `f32` per
//! particle), handed over by the timestep opener.

#![no_main]

use std::io::Cursor;
use std::path::{Path, PathBuf};

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = voxless_io::read_particles_from(&b"0\n"[..], Path::new("series.particles"), 0, |_| {
        Ok((PathBuf::from("series.particles_0"), Cursor::new(data)))
    });
});
