//! `read_amrclaw_from` and `read_amrclaw_text` (one field picked) on
//! AMRClaw ASCII output. Byte 0 picks the mode
//! (modulo 3), the rest of the input is one of the two texts:
//!
//! - 0: the rest is the `fort.q` text, with a small valid `fort.t`
//!   (time 0.5, meqn 2, 2 grids, ndim 3);
//! - 1: the rest is the `fort.t` text, with a small valid `fort.q` (two
//!   grids of 2×2×2 cells with 2 values each, the second one level finer);
//! - 2: the rest is the `fort.q` text and there is no `fort.t`, so `meqn`
//!   comes from the first data row and grids run to the end of the text.

#![no_main]

use std::io::Cursor;
use std::path::Path;

use libfuzzer_sys::fuzz_target;

/// A `fort.t` that fits [`FORT_Q`].
const FORT_T: &str = "\
    0.50000000E+00    time
     2                 meqn
     2                 ngrids
     0                 naux
     3                 ndim
     2                 nghost
  ascii                format
";

/// A `fort.q` of two grids: AMR level 1 with dx = 0.5 and AMR level 2 with
/// dx = 0.25 covering the first coarse cell.
const FORT_Q: &str = "\
     1                 grid_number
     1                 AMR_level
     2                 mx
     2                 my
     2                 mz
    0.0000000000000000E+00    xlow
    0.0000000000000000E+00    ylow
    0.0000000000000000E+00    zlow
    0.5000000000000000E+00    dx
    0.5000000000000000E+00    dy
    0.5000000000000000E+00    dz

    0.1000000000000000E+01    0.2000000000000000E+00
    0.1100000000000000E+01    0.2100000000000000E+00
    0.1200000000000000E+01    0.2200000000000000E+00
    0.1300000000000000E+01    0.2300000000000000E+00
    0.1400000000000000E+01    0.2400000000000000E+00
    0.1500000000000000E+01    0.2500000000000000E+00
    0.1600000000000000E+01    0.2600000000000000E+00
    0.1700000000000000E+01    0.2700000000000000E+00

     2                 grid_number
     2                 AMR_level
     2                 mx
     2                 my
     2                 mz
    0.0000000000000000E+00    xlow
    0.0000000000000000E+00    ylow
    0.0000000000000000E+00    zlow
    0.2500000000000000E+00    dx
    0.2500000000000000E+00    dy
    0.2500000000000000E+00    dz

    0.2000000000000000E+01    0.3000000000000000E+00
    0.2100000000000000E+01    0.3100000000000000E+00
    0.2200000000000000E+01    0.3200000000000000E+00
    0.2300000000000000E+01    0.3300000000000000E+00
    0.2400000000000000E+01    0.3400000000000000E+00
    0.2500000000000000E+01    0.3500000000000000E+00
    0.2600000000000000E+01    0.3600000000000000E+00
    0.2700000000000000E+01    0.3700000000000000E+00
";

fuzz_target!(|data: &[u8]| {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    let (fort_q, fort_t) = match mode % 3 {
        0 => (rest, Some(FORT_T.as_bytes())),
        1 => (FORT_Q.as_bytes(), Some(rest)),
        _ => (rest, None),
    };
    let name = Path::new("fort.q0001");
    let whole = voxless_io::read_amrclaw_from(Cursor::new(fort_q), name, fort_t);
    // The mapped file's path, with the second field alone: where both
    // read, it holds the whole read's second field.
    let pick = voxless_io::FieldPick::Named {
        names: vec!["q1".into()],
        first: false,
    };
    let picked = voxless_io::read_amrclaw_text(fort_q, name, fort_t, &pick);
    if let (Ok(w), Ok(p)) = (&whole, &picked)
        && w.fields.len() == 2
    {
        assert_eq!(p.cells, w.cells);
        assert_eq!(p.fields, w.fields[1..]);
    }
});
