//! Periodic particle boxes and radii from neighbours through the CLI: the
//! projection of a box conserves its mass, `--save-radii` writes the
//! brute-force periodic neighbour radii, the file's box is used (and can be
//! turned off), and bad boxes and counts are refused with the flag named.

mod common;

use common::{Scratch, fails, ok, read, write_positions};

/// The n-th nearest distances by comparing every pair (minimum image in a
/// unit box).
fn brute_neighbours(p: &[[f32; 3]], n: usize) -> Vec<f64> {
    p.iter()
        .map(|q| {
            let mut d: Vec<f64> = p
                .iter()
                .map(|r| {
                    (0..3)
                        .map(|a| {
                            let x = (q[a] as f64 - r[a] as f64).abs();
                            x.min(1.0 - x).powi(2)
                        })
                        .sum::<f64>()
                        .sqrt()
                })
                .collect();
            d.sort_by(f64::total_cmp);
            d[n - 1]
        })
        .collect()
}

#[test]
fn a_periodic_projection_conserves_mass_and_saves_neighbour_radii() {
    let dir = Scratch::new("periodic-cli");
    let n = 1500;
    let p = write_positions(&dir.path("p.npy"), n, 3);
    let (pos, out, h) = (dir.str("p.npy"), dir.str("c.npy"), dir.str("h.npy"));
    let err = ok(&[
        "project",
        "--particles",
        &pos,
        "--box",
        "1",
        "--kernel",
        "cubic-spline",
        "--neighbours",
        "12",
        "--save-radii",
        &h,
        "--axis",
        "x",
        "--size",
        "128",
        "128",
        "-o",
        &out,
    ]);
    assert!(err.contains("periodic box (given)"), "{err}");
    assert!(err.contains("12 nearest neighbours"), "{err}");
    // The default image covers the box: Σ × pixel area = the mass (1 each).
    let (shape, c) = read(&dir.path("c.npy"));
    assert_eq!(shape, [128, 128]);
    let mass = c.iter().sum::<f64>() / (128.0 * 128.0);
    assert!((mass / n as f64 - 1.0).abs() <= 1e-5, "Σ = {mass}");
    // Radii: h = the 12th-neighbour distance / 2 (the cubic spline reaches 2h).
    let (shape, got) = read(&dir.path("h.npy"));
    assert_eq!(shape, [n]);
    for (i, want) in brute_neighbours(&p, 12).iter().enumerate() {
        let want = want / 2.0;
        assert!(
            (got[i] - want).abs() <= 1e-6 * want,
            "{i}: {} vs {want}",
            got[i]
        );
    }
}

#[test]
fn pixel_areas_conserve_the_mass_of_kernels_far_smaller_than_a_pixel() {
    let dir = Scratch::new("periodic-area");
    let n = 3000;
    write_positions(&dir.path("p.npy"), n, 4);
    let pos = dir.str("p.npy");
    // Supports of 1/20 of a pixel: pixel centres miss most of them.
    let project = |pixels: &str, view: &[&str], out: &str| {
        let mut a = vec![
            "project",
            "--particles",
            &pos,
            "--box",
            "1",
            "--kernel",
            "cubic-spline",
            "--radius",
            "0.0002",
            "--size",
            "100",
            "100",
            "--pixels",
            pixels,
            "-o",
            out,
        ];
        a.extend_from_slice(view);
        ok(&a)
    };
    let (on, off, centre) = (dir.str("on.npy"), dir.str("off.npy"), dir.str("centre.npy"));
    project("area", &["--axis", "y"], &on);
    let err = project(
        "area",
        &[
            "--normal", "1", "0.7", "0.4", "--center", "0.5", "0.5", "0.5", "--width", "1.8",
        ],
        &off,
    );
    assert!(!err.contains("projected mass differs"), "{err}");
    let mass = |path: &str, width: f64| {
        let (_, c) = read(std::path::Path::new(path));
        c.iter().sum::<f64>() * (width / 100.0) * (width / 100.0)
    };
    assert!(
        (mass(&on, 1.0) / n as f64 - 1.0).abs() <= 1e-6,
        "on axis {}",
        mass(&on, 1.0)
    );
    assert!(
        (mass(&off, 1.8) / n as f64 - 1.0).abs() <= 1e-5,
        "off axis {}",
        mass(&off, 1.8)
    );
    // Pixel centres: the mass is sampled, and a note says how to keep it.
    let err = project("centre", &["--axis", "y"], &centre);
    assert!((mass(&centre, 1.0) / n as f64 - 1.0).abs() > 0.01);
    assert!(err.contains("--pixels area conserves"), "{err}");
    // A slab integrates through pixel centres: refused, naming the flag.
    let err = fails(&[
        "project",
        "--particles",
        &pos,
        "--box",
        "1",
        "--radius",
        "0.01",
        "--axis",
        "z",
        "--depth",
        "0.3",
        "--pixels",
        "area",
        "--size",
        "16",
        "16",
        "-o",
        &centre,
    ]);
    assert!(err.contains("pixels") && err.contains("--depth"), "{err}");
}

#[test]
fn a_whole_pixel_shift_modulo_the_box_rolls_the_projection_bit_for_bit() {
    // Positions, radii and the shift on a 1/1024 grid: the shifted file
    // holds exactly p + s mod 1, so a whole-pixel shift must give the same
    // bits rolled (sub-pixel positions, kernels crossing faces, corners).
    let dir = Scratch::new("periodic-roll");
    let n = 2000;
    let mut seed = 7u64;
    let mut grid = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 33) % 1024) as f64 / 1024.0
    };
    let p: Vec<[f64; 3]> = (0..n).map(|_| [grid(), grid(), grid()]).collect();
    let radii: Vec<f32> = (0..n)
        .map(|_| (8.0 + 40.0 * grid()).round() as f32 / 1024.0)
        .collect();
    let shift = [0.25, 0.125, 0.375];
    let shifted: Vec<[f64; 3]> = p
        .iter()
        .map(|q| std::array::from_fn(|a| (q[a] + shift[a]).rem_euclid(1.0)))
        .collect();
    common::write_f64(&dir.path("p.npy"), &p);
    common::write_f64(&dir.path("s.npy"), &shifted);
    common::write_values(&dir.path("h.npy"), &radii);
    let h = dir.str("h.npy");
    let project = |file: &str, pixels: &str, out: &str| {
        ok(&[
            "project",
            "--particles",
            &dir.str(file),
            "--radii",
            &h,
            "--box",
            "1",
            "--kernel",
            "wendland-c2",
            "--axis",
            "z",
            "--size",
            "128",
            "128",
            "--pixels",
            pixels,
            "-o",
            out,
        ]);
        read(std::path::Path::new(out)).1
    };
    for pixels in ["centre", "area"] {
        let a = project("p.npy", pixels, &dir.str("a.npy"));
        let b = project("s.npy", pixels, &dir.str("b.npy"));
        // x right by 32 pixels, y up by 16 (row 0 at the top: rows up by 16).
        let rolled: Vec<f64> = (0..128 * 128)
            .map(|k| {
                let (row, col) = (k / 128, k % 128);
                a[((row + 16) % 128) * 128 + (col + 128 - 32) % 128]
            })
            .collect();
        let same = rolled
            .iter()
            .zip(&b)
            .filter(|(x, y)| x.to_bits() == y.to_bits())
            .count();
        assert_eq!(
            same,
            128 * 128,
            "{pixels}: {same} of {} pixels equal",
            128 * 128
        );
    }
}

#[test]
fn bad_boxes_and_counts_are_refused_naming_the_flag() {
    let dir = Scratch::new("periodic-bad");
    write_positions(&dir.path("p.npy"), 300, 4);
    let pos = dir.str("p.npy");
    let out = dir.str("o.npy");
    let run = |extra: &[&str]| {
        let mut a = vec![
            "project",
            "--particles",
            &pos,
            "--size",
            "8",
            "8",
            "-o",
            &out,
        ];
        a.extend(extra);
        fails(&a)
    };
    for (flags, says) in [
        (&["--box", "0"][..], "box"),
        (&["--box", "-5"], "box"),
        (&["--box", "1", "2"], "box"),
        (&["--box", "0", "0", "0", "1", "-1", "1"], "box"),
        (&["--box", "0.5"], "--wrap"),
        (&["--neighbours", "1"], "neighbours"),
        (&["--neighbours", "301"], "neighbours"),
        (&["--neighbours", "8", "--radius", "0.1"], "neighbours"),
    ] {
        let err = run(flags);
        assert!(err.contains(says), "{flags:?}: {err}");
    }
    // Asked for, the wrap folds the data into the smaller box.
    let mut a = vec![
        "project",
        "--particles",
        &pos,
        "--size",
        "8",
        "8",
        "-o",
        &out,
    ];
    a.extend(["--box", "0.5", "--wrap", "--radius", "0.05"]);
    let err = ok(&a);
    assert!(err.contains("were wrapped in"), "{err}");
    // A box far larger than the data is run, with a question.
    let mut a = vec![
        "project",
        "--particles",
        &pos,
        "--size",
        "8",
        "8",
        "-o",
        &out,
    ];
    a.extend(["--box", "1000"]);
    let err = ok(&a);
    assert!(err.contains("is the box right"), "{err}");
}

#[test]
fn a_lammps_box_with_pp_bounds_is_periodic_unless_turned_off() {
    let dir = Scratch::new("periodic-lammps");
    let mut dump = String::from(
        "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n64\nITEM: BOX BOUNDS pp pp pp\n0 4\n0 4\n0 4\n\
         ITEM: ATOMS id type x y z\n",
    );
    for i in 0..64 {
        let (x, y, z) = (i % 4, (i / 4) % 4, i / 16);
        dump.push_str(&format!("{} 1 {} {} {}\n", i + 1, x as f32 + 0.5, y, z));
    }
    std::fs::write(dir.path("dump.lattice"), dump).unwrap();
    let (file, out) = (dir.str("dump.lattice"), dir.str("o.npy"));
    let base = [
        "project",
        "--particles",
        &file,
        "--size",
        "8",
        "8",
        "-o",
        &out,
    ];
    let err = ok(&base);
    assert!(err.contains("periodic box (the file's)"), "{err}");
    // A lattice of a periodic box projects to a uniform image.
    let (_, c) = read(&dir.path("o.npy"));
    let (lo, hi) = c
        .iter()
        .fold((f64::MAX, 0.0f64), |m, &v| (m.0.min(v), m.1.max(v)));
    assert!(lo > 0.0 && hi > 0.0);
    let mut a = base.to_vec();
    a.push("--no-box");
    let err = ok(&a);
    assert!(!err.contains("periodic box"), "{err}");
}
