//! Right on any data, through the binary: outputs never destroy inputs,
//! no panic or hang at extreme scales, results invariant under scaling and
//! translating the coordinates, degenerate inputs rendered or refused with
//! the reason, and bad values refused by name.

mod common;
use common::*;

use std::path::Path;

/// `n` random points in a 1 × 0.6 × 0.4 box (seeded).
fn blob(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = Lcg(seed);
    (0..n)
        .map(|_| [rng.f() as f64, 0.6 * rng.f() as f64, 0.4 * rng.f() as f64])
        .collect()
}

fn pixels(path: &Path) -> Vec<u8> {
    voxless_io::read_png_rgb8(path).unwrap().2
}

fn max_diff(a: &[u8], b: &[u8]) -> u8 {
    a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max().unwrap()
}

#[test]
fn outputs_never_overwrite_inputs() {
    let s = Scratch::new("protect");
    write_f64(&s.path("in.npy"), &blob(300, 1));
    let before = std::fs::read(s.path("in.npy")).unwrap();
    let input = s.str("in.npy");
    let e = fails(&["render", "--particles", &input, "-o", &input]);
    assert!(
        e.contains("one of the inputs") && !e.contains("loaded"),
        "{e}"
    );
    let e = fails(&[
        "sample",
        "--particles",
        &input,
        "--points",
        &input,
        "-o",
        &input,
    ]);
    assert!(e.contains("one of the inputs"), "{e}");
    let e = fails(&["project", "--particles", &input, "-o", &input]);
    assert!(e.contains("one of the inputs"), "{e}");
    // Through a hard link and a symbolic link.
    std::fs::hard_link(s.path("in.npy"), s.path("hard.npy")).unwrap();
    let e = fails(&["project", "--particles", &input, "-o", &s.str("hard.npy")]);
    assert!(e.contains("one of the inputs"), "{e}");
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(s.path("in.npy"), s.path("link.png")).unwrap();
        let e = fails(&["render", "--particles", &input, "-o", &s.str("link.png")]);
        assert!(e.contains("one of the inputs"), "{e}");
    }
    // The points of `sample` are inputs too.
    write_f64(&s.path("q.npy"), &blob(10, 2));
    let e = fails(&[
        "sample",
        "--particles",
        &input,
        "--points",
        &s.str("q.npy"),
        "-o",
        &s.str("q.npy"),
    ]);
    assert!(e.contains("one of the inputs"), "{e}");
    assert_eq!(std::fs::read(s.path("in.npy")).unwrap(), before);
    // A run that fails after loading keeps the old output and leaves no
    // partial or temporary file.
    std::fs::write(s.path("old.png"), b"old picture").unwrap();
    let entries = std::fs::read_dir(&s.0).unwrap().count();
    let e = fails(&[
        "render",
        "--particles",
        &input,
        "--iso",
        "1e9",
        "--size",
        "16",
        "16",
        "-o",
        &s.str("old.png"),
    ]);
    assert!(e.contains("iso"), "{e}");
    assert_eq!(std::fs::read(s.path("old.png")).unwrap(), b"old picture");
    assert_eq!(std::fs::read_dir(&s.0).unwrap().count(), entries);
}

#[test]
fn outputs_are_checked_before_any_work_and_written_as_named() {
    let s = Scratch::new("outputs");
    write_f64(&s.path("p.npy"), &blob(300, 3));
    let p = s.str("p.npy");
    let render = |out: &str| -> (bool, String) {
        let (ok, e, _) = voxless(&["render", "--particles", &p, "--size", "24", "16", "-o", out]);
        (ok, e)
    };
    let (good, e) = render(&s.str("x.jpg"));
    assert!(good, "{e}");
    assert_eq!(
        &std::fs::read(s.path("x.jpg")).unwrap()[..3],
        &[0xFF, 0xD8, 0xFF]
    );
    let (good, e) = render(&s.str("x.PNG"));
    assert!(good, "{e}");
    assert_eq!(&std::fs::read(s.path("x.PNG")).unwrap()[1..4], b"PNG");
    for bad in ["x.gif", "x", "missing/x.png"] {
        let (good, e) = render(&s.str(bad));
        assert!(
            !good && !e.contains("loaded") && !e.contains("panicked"),
            "{bad}: {e}"
        );
    }
    let e = fails(&["project", "--particles", &p, "-o", &s.str("col.png")]);
    assert!(e.contains(".npy") && !e.contains("loaded"), "{e}");
    let e = fails(&["render", "--particles", &p, "-o", &s.str("none/x.png")]);
    assert!(e.contains("does not exist"), "{e}");
    // Memory for the image is checked up front.
    let out = std::process::Command::new(bin())
        .args([
            "render",
            "--particles",
            &p,
            "--size",
            "16384",
            "16384",
            "-o",
            &s.str("huge.png"),
        ])
        .env("VOXLESS_MEMORY_LIMIT", "1G")
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && e.contains("GiB") && e.contains("--size"),
        "{e}"
    );
}

#[test]
fn extreme_scales_neither_panic_nor_hang() {
    let s = Scratch::new("extreme");
    let unit = blob(400, 5);
    let far: Vec<[f64; 3]> = unit.iter().map(|p| p.map(|v| 1e9 + v)).collect();
    write_f64(&s.path("far.npy"), &far);
    let mut outlier = unit.clone();
    outlier[0][1] = 1e38;
    write_f64(&s.path("outlier.npy"), &outlier);
    write_f64(&s.path("unit.npy"), &unit);
    let out = s.str("x.png");
    let small = ["--size", "24", "16", "-o", out.as_str()];
    let run = |args: &[&str]| {
        let (_, e, _) = voxless(args);
        assert!(!e.contains("panicked"), "{args:?}: {e}");
        e
    };
    let with = |file: &str, extra: &[&str]| {
        let f = s.str(file);
        let mut a = vec!["render", "--particles", f.as_str()];
        a.extend(extra);
        a.extend(small);
        run(&a)
    };
    ok(&[
        "render",
        "--particles",
        &s.str("far.npy"),
        "--size",
        "24",
        "16",
        "-o",
        &out,
    ]);
    for r in ["1e19", "1e30"] {
        let e = with("unit.npy", &["--radius", r]);
        assert!(e.contains("radius") || e.contains("rendered"), "{e}");
    }
    // Tiny supports or steps: refused or clamped with a note, never a hang.
    let e = with("unit.npy", &["--radius", "1e-7"]);
    assert!(e.contains("error") || e.contains("rendered"), "{e}");
    let e = with("unit.npy", &["--step", "1e-9"]);
    assert!(e.contains("--step") || e.contains("raised"), "{e}");
    // One particle 10³⁸ away: an error naming it.
    let e = with("outlier.npy", &[]);
    assert!(e.contains("particle 0 lies farthest"), "{e}");
    let q = s.str("unit.npy");
    for file in ["far.npy", "outlier.npy"] {
        run(&[
            "sample",
            "--particles",
            &s.str(file),
            "--points",
            &q,
            "-o",
            &s.str("s.npy"),
        ]);
        run(&[
            "project",
            "--particles",
            &s.str(file),
            "--size",
            "8",
            "8",
            "-o",
            &s.str("c.npy"),
        ]);
    }
    // A tessellation in a box of 10³⁰.
    let n = 6;
    let mut rng = Lcg(9);
    let grid: Vec<[f64; 3]> = (0..n * n * n)
        .map(|i| {
            let c = [i / (n * n), i / n % n, i % n];
            c.map(|k| ((k as f64 + 0.5 + 0.2 * (rng.f() as f64 - 0.5)) / n as f64) * 1e30)
        })
        .collect();
    write_f64(&s.path("grid.npy"), &grid);
    let tets = ["--lagrangian", "6", "--box", "1e30"];
    with("grid.npy", &tets);
    let g = s.str("grid.npy");
    let mut a = vec![
        "sample",
        "--particles",
        g.as_str(),
        "--points",
        g.as_str(),
        "-o",
    ];
    let o = s.str("ts.npy");
    a.push(&o);
    a.extend(tets);
    run(&a);
}

/// Renders, projects and samples `positions` (scaled by 10^k, or shifted)
/// at a small size; returns the image, the column map and the samples.
fn measure(
    s: &Scratch,
    tag: &str,
    positions: &[[f64; 3]],
    query: &[[f64; 3]],
) -> (Vec<u8>, Vec<f64>, Vec<f64>) {
    let (p, q) = (s.str(&format!("p{tag}.npy")), s.str(&format!("q{tag}.npy")));
    write_f64(Path::new(&p), positions);
    write_f64(Path::new(&q), query);
    let img = s.str(&format!("i{tag}.png"));
    ok(&[
        "render",
        "--particles",
        &p,
        "--size",
        "48",
        "32",
        "-o",
        &img,
    ]);
    let col = s.str(&format!("c{tag}.npy"));
    ok(&[
        "project",
        "--particles",
        &p,
        "--size",
        "24",
        "16",
        "-o",
        &col,
    ]);
    let smp = s.str(&format!("s{tag}.npy"));
    ok(&["sample", "--particles", &p, "--points", &q, "-o", &smp]);
    (
        pixels(Path::new(&img)),
        read(Path::new(&col)).1,
        read(Path::new(&smp)).1,
    )
}

fn assert_close(a: &[f64], b: &[f64], tol: f64, what: &str) {
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (x, y) in a.iter().zip(b) {
        assert!(
            (x - y).abs() <= tol * scale,
            "{what}: {x} vs {y} (max {scale})"
        );
    }
}

/// Render, project and sample are invariant under scaling the coordinates
/// by 10^k, k in −12..=12 (visited in a seeded random order with a fresh
/// random particle set per seed), and under a 10⁹ translation of float64
/// positions: images to 1/255, fields to 1e-5 relative after the obvious
/// unit scaling (columns scale with length, Φ of unit weights not at all).
#[test]
fn scale_and_translation_invariance_property() {
    let s = Scratch::new("invariance");
    let mut rng = Lcg(2024);
    let mut ks: Vec<i32> = (-12..=12).filter(|&k| k != 0).collect();
    for i in (1..ks.len()).rev() {
        ks.swap(i, (rng.f() * (i + 1) as f32) as usize % (i + 1));
    }
    for (round, chunk) in ks.chunks(8).enumerate() {
        let seed = 100 + round as u64;
        let base = blob(250, seed);
        let query: Vec<[f64; 3]> = blob(40, seed + 50);
        let (img0, col0, smp0) = measure(&s, &format!("{seed}_0"), &base, &query);
        assert!(
            img0.iter().any(|&v| v > 20),
            "the reference image shows the data"
        );
        for &k in chunk {
            let f = 10f64.powi(k);
            let scaled: Vec<[f64; 3]> = base.iter().map(|p| p.map(|v| v * f)).collect();
            let q: Vec<[f64; 3]> = query.iter().map(|p| p.map(|v| v * f)).collect();
            let (img, col, smp) = measure(&s, &format!("{seed}_{k}"), &scaled, &q);
            let d = max_diff(&img, &img0);
            assert!(d <= 1, "×1e{k}: image differs by {d}/255");
            let col: Vec<f64> = col.iter().map(|c| c / f).collect();
            assert_close(&col, &col0, 1e-5, &format!("×1e{k} columns"));
            assert_close(&smp, &smp0, 1e-5, &format!("×1e{k} samples"));
        }
    }
    let base = blob(250, 7);
    let query = blob(40, 8);
    let (img0, col0, smp0) = measure(&s, "t0", &base, &query);
    let shift =
        |v: &[[f64; 3]]| -> Vec<[f64; 3]> { v.iter().map(|p| p.map(|x| x + 1e9)).collect() };
    let (img, col, smp) = measure(&s, "t9", &shift(&base), &shift(&query));
    assert!(max_diff(&img, &img0) <= 1, "+1e9: image differs");
    assert_close(&col, &col0, 1e-5, "+1e9 columns");
    assert_close(&smp, &smp0, 1e-5, "+1e9 samples");
}

#[test]
fn degenerate_inputs_render_or_say_why() {
    let s = Scratch::new("degenerate");
    let out = s.str("x.png");
    let render = |file: &str, extra: &[&str]| {
        let f = s.str(file);
        let mut a = vec![
            "render",
            "--particles",
            f.as_str(),
            "--size",
            "24",
            "16",
            "-o",
            out.as_str(),
        ];
        a.extend(extra);
        voxless(&a)
    };
    write_f64(&s.path("one.npy"), &[[3.0, -2.0, 7.5]]);
    write_f64(&s.path("same.npy"), &[[1e-20, 5.0, 5.0]; 40]);
    for file in ["one.npy", "same.npy"] {
        let (good, e, _) = render(file, &[]);
        assert!(good, "{file}: {e}");
        assert!(e.contains("no spacing to size"), "{file}: {e}");
        assert!(
            pixels(Path::new(&out)).iter().any(|&v| v > 20),
            "{file}: image is black"
        );
    }
    write_f64(&s.path("p.npy"), &blob(300, 4));
    write_values(&s.path("zero.npy"), &[0.0; 300]);
    write_values(&s.path("flat.npy"), &[2.5; 300]);
    let (good, e, _) = render("p.npy", &["--weights", &s.str("zero.npy")]);
    assert!(
        !good && e.contains("weights") && e.contains("0 everywhere"),
        "{e}"
    );
    let (good, e, _) = render("p.npy", &["--attribute", &s.str("flat.npy")]);
    assert!(good, "{e}");
    assert!(
        pixels(Path::new(&out)).iter().any(|&v| v > 20),
        "constant attribute: black"
    );
    // A constant AMR field shows as a uniform medium; a zero one is refused.
    let cells: Vec<u8> = (0..8i32)
        .flat_map(|i| [i & 1, i >> 1 & 1, i >> 2, 0])
        .flat_map(|v| v.to_le_bytes())
        .collect();
    std::fs::write(s.path("c.cells"), cells).unwrap();
    for (name, v) in [("flat", 3.0f32), ("zero", 0.0)] {
        let bytes: Vec<u8> = (0..8).flat_map(|_| v.to_le_bytes()).collect();
        std::fs::write(s.path(&format!("{name}.scalars")), bytes).unwrap();
    }
    let amr = |field: &str| {
        voxless(&[
            "render",
            "--cells",
            &s.str("c.cells"),
            "--scalars",
            &s.str(field),
            "--size",
            "24",
            "16",
            "-o",
            &out,
        ])
    };
    let (good, e, _) = amr("flat.scalars");
    assert!(good && e.contains("everywhere"), "{e}");
    assert!(
        pixels(Path::new(&out)).iter().any(|&v| v > 20),
        "constant AMR field: black"
    );
    let (good, e, _) = amr("zero.scalars");
    assert!(!good && e.contains("0 everywhere"), "{e}");
}

/// Absurd sample counts are refused before any work, naming the flag and
/// the limit (a million passes would take days).
#[test]
fn absurd_samples_per_pixel_are_refused() {
    let s = Scratch::new("spp");
    write_positions(&s.path("p.npy"), 200, 4);
    let p = s.str("p.npy");
    let out = s.str("x.png");
    let e = fails(&["render", "--particles", &p, "--spp", "1000000", "-o", &out]);
    assert!(e.contains("--spp") && e.contains("65536"), "{e}");
    assert!(!s.path("x.png").exists());
    ok(&[
        "render",
        "--particles",
        &p,
        "--spp",
        "2",
        "--size",
        "16",
        "16",
        "-o",
        &out,
    ]);
}
