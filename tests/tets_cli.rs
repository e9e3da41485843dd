//! End-to-end phase-space tessellations: the binary on a grid it writes, and
//! on the JaxPM run when the shared data is present.

mod common;
use common::*;

/// An N³ grid in a box of size 2 with a small deterministic displacement.
fn write_grid(s: &Scratch, n: usize, name: &str) {
    let l = 2.0f32;
    let dq = l / n as f32;
    let mut flat = Vec::with_capacity(n * n * n * 3);
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                let q = [i as f32 * dq, j as f32 * dq, k as f32 * dq];
                let d = 0.2 * dq * (q[0] * 3.1 + q[1] * 1.7).sin();
                flat.extend([(q[0] + d).rem_euclid(l), q[1], (q[2] - d).rem_euclid(l)]);
            }
        }
    }
    voxless_io::write_npy_f32(&s.path(name), &[n * n * n, 3], &flat).unwrap();
}

#[test]
fn project_render_and_sample_a_tessellation() {
    let s = Scratch::new("tets");
    write_grid(&s, 8, "p.npy");
    let base = [
        "--particles",
        &s.str("p.npy"),
        "--lagrangian",
        "8",
        "--box",
        "2",
        "--particle-mass",
        "0.5",
    ];
    let with = |cmd: &str, extra: &[&str]| {
        let mut a = vec![cmd];
        a.extend(base);
        a.extend(extra);
        ok(&a)
    };
    // Mass: 8³ particles × 0.5 = 256, all inside the box.
    let stderr = with(
        "project",
        &["--axis", "x", "--size", "200", "200", "-o", &s.str("c.npy")],
    );
    let (_, col) = read(&s.path("c.npy"));
    let total = col.iter().sum::<f64>() * (2.0f64 / 200.0).powi(2);
    assert!((total - 256.0).abs() <= 1e-3 * 256.0, "{total}\n{stderr}");
    with(
        "render",
        &[
            "--size",
            "48",
            "40",
            "--opacity-scale",
            "2",
            "-o",
            &s.str("e.png"),
        ],
    );
    with(
        "render",
        &[
            "--size",
            "48",
            "40",
            "--opacity-scale",
            "2",
            "--tet-mode",
            "kbuffer",
            "--k",
            "8",
            "-o",
            &s.str("k.png"),
        ],
    );
    let (_, _, rgb) = voxless_io::read_png_rgb8(&s.path("e.png")).unwrap();
    assert!(rgb.iter().any(|&c| c > 20), "exact render is blank");
    voxless_io::write_npy_f32(&s.path("q.npy"), &[2, 3], &[0.5, 0.5, 0.5, 1.3, 0.2, 1.9]).unwrap();
    with(
        "sample",
        &["--points", &s.str("q.npy"), "-o", &s.str("d.npy")],
    );
    let (shape, v) = read(&s.path("d.npy"));
    assert_eq!(shape, vec![2, 2]);
    // Density and stream count: a single stream at the mean-ish density.
    let mean = 256.0 / 8.0;
    for r in 0..2 {
        assert_eq!(v[r * 2 + 1], 1.0, "one stream");
        assert!(
            (v[r * 2] / mean - 1.0).abs() < 0.5,
            "density {} vs mean {mean}",
            v[r * 2]
        );
    }
}

#[test]
fn bad_tessellation_input_is_a_clear_error() {
    let s = Scratch::new("tets-bad");
    write_grid(&s, 4, "p.npy");
    let p = s.str("p.npy");
    let out = s.str("o.png");
    let e = fails(&[
        "render",
        "--particles",
        &p,
        "--lagrangian",
        "5",
        "--box",
        "2",
        "-o",
        &out,
    ]);
    assert!(
        e.contains("p.npy") && e.contains("64") && e.contains("N³"),
        "{e}"
    );
    let e = fails(&[
        "render",
        "--particles",
        &p,
        "--lagrangian",
        "4",
        "--box",
        "0",
        "-o",
        &out,
    ]);
    assert!(e.contains("box size"), "{e}");
    let e = fails(&["render", "--particles", &p, "--lagrangian", "4", "-o", &out]);
    assert!(e.contains("--box"), "{e}");
    let mut flat = vec![0.5f32; 64 * 3];
    flat[7] = f32::NAN;
    voxless_io::write_npy_f32(&s.path("nan.npy"), &[64, 3], &flat).unwrap();
    let e = fails(&[
        "render",
        "--particles",
        &s.str("nan.npy"),
        "--lagrangian",
        "4",
        "--box",
        "2",
        "-o",
        &out,
    ]);
    assert!(e.contains("nan.npy") && e.contains("particle 2"), "{e}");
}

#[test]
fn jaxpm_projection_conserves_mass() {
    let Some(dir) = shared_data("nbody-jaxpm/npy_N64_a1") else {
        return;
    };
    let s = Scratch::new("jaxpm");
    let stderr = ok(&[
        "project",
        "--particles",
        &dir.join("positions.npy").to_string_lossy(),
        "--lagrangian",
        "64",
        "--box",
        "100",
        "--axis",
        "z",
        "--size",
        "256",
        "256",
        "-o",
        &s.str("c.npy"),
    ]);
    let (_, col) = read(&s.path("c.npy"));
    let total = col.iter().sum::<f64>() * (100.0f64 / 256.0).powi(2);
    // Mean density 1 by default: the box's mass is its volume.
    assert!((total / 1e6 - 1.0).abs() <= 1e-3, "{total}\n{stderr}");
}

#[test]
fn pixel_area_projections_conserve_mass_at_every_resolution() {
    let s = Scratch::new("tets-area");
    write_grid(&s, 8, "p.npy");
    let p = s.str("p.npy");
    let base = ["--particles", &p, "--lagrangian", "8", "--box", "2"];
    for res in ["64", "256", "1024"] {
        let out = s.str(&format!("a{res}.npy"));
        let mut a = vec!["project"];
        a.extend(base);
        a.extend([
            "--axis", "z", "--size", res, res, "--pixels", "area", "-o", &out,
        ]);
        let stderr = ok(&a);
        let (_, col) = read(&s.path(&format!("a{res}.npy")));
        let r: f64 = res.parse().unwrap();
        // Mean density 1: the mass is the box's volume, 8.
        let total = col.iter().sum::<f64>() * (2.0 / r).powi(2);
        assert!(
            (total / 8.0 - 1.0).abs() <= 1e-5,
            "{res}²: {total}\n{stderr}"
        );
    }
    // A slab is integrated through pixel centres: refused by name.
    let slab = s.str("d.npy");
    let mut a = vec!["project"];
    a.extend(base);
    a.extend(["--pixels", "area", "--depth", "0.5", "-o", &slab]);
    let e = fails(&a);
    assert!(e.contains("pixels") && e.contains("--depth"), "{e}");
    // The same positions as particles take pixel areas too (their own
    // kernels'; other data is refused, tested in the library).
    let e = ok(&[
        "project",
        "--particles",
        &p,
        "--radius",
        "0.1",
        "--pixels",
        "area",
        "-o",
        &s.str("q.npy"),
    ]);
    assert!(!e.contains("projected mass differs"), "{e}");
}

#[test]
fn jaxpm_pixel_area_projection_is_exact_at_every_resolution() {
    let Some(dir) = shared_data("nbody-jaxpm/npy_N64_a1") else {
        return;
    };
    let s = Scratch::new("jaxpm-area");
    let positions = dir.join("positions.npy").to_string_lossy().into_owned();
    for res in ["64", "256", "1024"] {
        let out = s.str(&format!("c{res}.npy"));
        let stderr = ok(&[
            "project",
            "--particles",
            &positions,
            "--lagrangian",
            "64",
            "--box",
            "100",
            "--size",
            res,
            res,
            "--pixels",
            "area",
            "-o",
            &out,
        ]);
        let (_, col) = read(&s.path(&format!("c{res}.npy")));
        let r: f64 = res.parse().unwrap();
        let total = col.iter().sum::<f64>() * (100.0 / r).powi(2);
        assert!(
            (total / 1e6 - 1.0).abs() <= 1e-5,
            "{res}²: {total}\n{stderr}"
        );
    }
}
