//! `read_amrex_files` on an AMReX plotfile in memory: two levels (a 2³
//! coarse box and a 2³ fine box covering one coarse cell), one component.
//! Byte 0 picks which of the five files the rest of the input replaces
//! (modulo 6); with 5, the rest is split at `|` bytes into all five.

#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

const HEADER: &str = "HyperCLaw-V1.1\n1\ndensity\n3\n0.5\n1\n0 0 0\n1 1 1\n2\n\
((0,0,0) (1,1,1) (0,0,0)) ((0,0,0) (3,3,3) (0,0,0))\n0 0\n0.5 0.5 0.5\n0.25 0.25 0.25\n0\n0\n\
0 1 0.5\n0\n0 1\n0 1\n0 1\nLevel_0/Cell\n\
1 1 0.5\n0\n0 0.5\n0 0.5\n0 0.5\nLevel_1/Cell\n";

const CELL_H0: &str = "1\n1\n1\n0\n(1 0\n((0,0,0) (1,1,1) (0,0,0))\n)\n1\nFabOnDisk: Cell_D_00000 0\n";
const CELL_H1: &str = "1\n1\n1\n0\n(1 0\n((0,0,0) (1,1,1) (0,0,0))\n)\n1\nFabOnDisk: Cell_D_00000 0\n";

/// A FAB of the 2³ box `(0,0,0)..(1,1,1)`, one component, little-endian f64.
fn fab(base: f64) -> Vec<u8> {
    let mut out =
        b"FAB ((8, (64 11 52 0 1 12 0 1023)),(8, (8 7 6 5 4 3 2 1)))((0,0,0) (1,1,1) (0,0,0)) 1\n"
            .to_vec();
    for i in 0..8 {
        out.extend_from_slice(&(base + i as f64).to_le_bytes());
    }
    out
}

const NAMES: [&str; 5] = [
    "Header",
    "Level_0/Cell_H",
    "Level_0/Cell_D_00000",
    "Level_1/Cell_H",
    "Level_1/Cell_D_00000",
];

fuzz_target!(|data: &[u8]| {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    let (d0, d1) = (fab(1.0), fab(10.0));
    let mut files: [&[u8]; 5] = [
        HEADER.as_bytes(),
        CELL_H0.as_bytes(),
        &d0,
        CELL_H1.as_bytes(),
        &d1,
    ];
    match mode % 6 {
        5 => {
            for (slot, part) in files.iter_mut().zip(rest.split(|&b| b == b'|')) {
                *slot = part;
            }
        }
        m => files[m as usize] = rest,
    }
    let named: Vec<(&str, &[u8])> = NAMES.iter().copied().zip(files).collect();
    let _ = voxless_io::read_amrex_files(Path::new("plt"), &named);
});
