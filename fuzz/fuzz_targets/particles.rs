//! `read_particles_file` of a fixed index `series.particles` that lists the
//! timestep `0`; the input is the binary timestep file `series.particles_0`
//! (a `u64` count, then four `f32` per particle).

#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let index = voxless_fuzz::write("series.particles", b"0\n");
    voxless_fuzz::write("series.particles_0", data);
    let _ = voxless_io::read_particles_file(&index, 0);
});
