//! Hostile input through the CLI: sizes that cannot fit are refused before
//! any work, special files are refused instead of read forever, a dump
//! whose atom count lies fails as `info` does, a projection that misses the
//! data is an error, and an output named by a symbolic link stays a link.
//! (Times are never asserted; a quadratic reader shows as a test that does
//! not finish.)

mod common;
use common::*;

/// An n³ Lagrangian grid in the unit box, in Lagrangian order.
fn write_grid(path: &std::path::Path, n: usize) {
    let grid: Vec<f32> = (0..n * n * n)
        .flat_map(|c| [c / (n * n), (c / n) % n, c % n].map(|v| v as f32 / n as f32))
        .collect();
    voxless_io::write_npy_f32(path, &[n * n * n, 3], &grid).unwrap();
}

#[test]
fn sizes_that_cannot_fit_are_refused_before_any_work() {
    let s = Scratch::new("hostile-sizes");
    write_grid(&s.path("grid.npy"), 6);
    let out = s.str("x.png");
    let e = fails(&[
        "render",
        "--particles",
        &s.str("grid.npy"),
        "--lagrangian",
        "6",
        "--box",
        "1",
        "--tet-mode",
        "kbuffer",
        "--layers",
        "1000000000",
        "--size",
        "16",
        "12",
        "-o",
        &out,
    ]);
    assert!(
        e.contains("tets.layers (--layers)") && e.contains("available"),
        "{e}"
    );
    let p = s.path("p.npy");
    write_positions(&p, 200, 3);
    let e = fails(&[
        "render",
        "--particles",
        &s.str("p.npy"),
        "--radius",
        "0.05",
        "--iso",
        "0.3",
        "--ao",
        "1000000000",
        "--size",
        "16",
        "12",
        "-o",
        &out,
    ]);
    assert!(
        e.contains("render.ao (--ao)") && e.contains("at most 4096"),
        "{e}"
    );
    // A million tiny frames are a million files: the disk's free space is
    // checked before any work (capped here to 1 MiB).
    let out = std::process::Command::new(bin())
        .env("VOXLESS_DISK_LIMIT", "1M")
        .args(["render", "--particles", &s.str("p.npy"), "--radius", "0.05"])
        .args([
            "--size",
            "1",
            "1",
            "--turntable",
            "1000000",
            "-o",
            &s.str("t.png"),
        ])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        e.contains("--turntable") && e.contains("1000000 files") && !e.contains("rendering"),
        "{e}"
    );
    assert!(!s.path("t_0000.png").exists());
}

#[cfg(unix)]
#[test]
fn special_files_are_refused_and_links_stay_links() {
    let s = Scratch::new("hostile-files");
    let out = s.str("x.png");
    let e = fails(&[
        "render",
        "--particles",
        "/dev/zero",
        "--size",
        "16",
        "12",
        "-o",
        &out,
    ]);
    assert!(e.contains("not a regular file"), "{e}");
    write_positions(&s.path("p.npy"), 200, 4);
    std::fs::write(s.path("target.png"), b"keep").unwrap();
    std::os::unix::fs::symlink("target.png", s.path("link.png")).unwrap();
    ok(&[
        "render",
        "--particles",
        &s.str("p.npy"),
        "--radius",
        "0.05",
        "--size",
        "16",
        "12",
        "-o",
        &s.str("link.png"),
    ]);
    let link = std::fs::symlink_metadata(s.path("link.png")).unwrap();
    assert!(
        link.file_type().is_symlink(),
        "the link was replaced by a file"
    );
    let png = std::fs::read(s.path("target.png")).unwrap();
    assert!(
        png.starts_with(b"\x89PNG"),
        "the link's target holds the image"
    );
}

#[test]
fn lying_counts_and_empty_projections_are_errors() {
    let s = Scratch::new("hostile-counts");
    let mut dump = String::from(
        "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n30\nITEM: BOX BOUNDS pp pp pp\n0 1\n0 1\n0 1\n\
         ITEM: ATOMS id type xs ys zs\n",
    );
    for i in 0..40 {
        let f = i as f32 / 40.0;
        dump.push_str(&format!("{} 1 {f} {} {}\n", i + 1, 1.0 - f, 0.5));
    }
    std::fs::write(s.path("dump.liar"), dump).unwrap();
    let e = fails(&[
        "render",
        "--particles",
        &s.str("dump.liar"),
        "--size",
        "16",
        "12",
        "-o",
        &s.str("x.png"),
    ]);
    assert!(e.contains("more atom rows than its NUMBER OF ATOMS"), "{e}");
    let (success, _, _) = voxless(&["info", &s.str("dump.liar")]);
    assert!(!success, "info and render must agree");
    write_positions(&s.path("p.npy"), 200, 5);
    let e = fails(&[
        "project",
        "--particles",
        &s.str("p.npy"),
        "--radius",
        "0.05",
        "--bounds",
        "10",
        "10",
        "10",
        "11",
        "11",
        "11",
        "--size",
        "16",
        "16",
        "-o",
        &s.str("e.npy"),
    ]);
    assert!(e.contains("misses the data"), "{e}");
    assert!(!s.path("e.npy").exists());
}

#[test]
fn wide_headers_are_read_in_linear_time() {
    let s = Scratch::new("hostile-wide");
    let n = 50_000;
    let mut header = String::from("x,y,z");
    let mut row = String::from("0.5,0.5,0.5");
    for i in 0..n {
        header.push_str(&format!(",c{i}"));
        row.push_str(",1");
    }
    std::fs::write(s.path("wide.csv"), format!("{header}\n{row}\n")).unwrap();
    let (success, stderr, out) = voxless(&["info", &s.str("wide.csv")]);
    assert!(success, "{stderr}");
    assert!(String::from_utf8_lossy(&out.stdout).contains(&format!("columns ({})", n + 3)));
    // A duplicate among them is still found.
    std::fs::write(s.path("dup.csv"), format!("{header},c7\n{row},1\n")).unwrap();
    let e = fails(&["info", &s.str("dup.csv")]);
    assert!(e.contains("duplicate column name 'c7'"), "{e}");
}

#[test]
fn settings_that_would_be_ignored_or_misread_name_their_flag() {
    let s = Scratch::new("hostile-flags");
    write_positions(&s.path("p.npy"), 200, 6);
    let p = s.str("p.npy");
    let out = s.str("x.png");
    let base = [
        "render",
        "--particles",
        &p,
        "--size",
        "16",
        "12",
        "-o",
        &out,
    ];
    let with = |extra: &[&str]| -> Vec<String> {
        base.iter().chain(extra).map(|a| a.to_string()).collect()
    };
    let fails_with = |extra: &[&str], needle: &str| {
        let args = with(extra);
        let e = fails(&args.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(e.contains(needle), "{extra:?}: {e}");
    };
    // AMR settings on particles: the flag, not "more than one data source".
    fails_with(&["--field", "density"], "field");
    fails_with(&["--cell-size", "0.1"], "applies to AMR cells");
    // The Gaussian's σ = 0 is named as such.
    fails_with(
        &["--kernel", "gaussian", "--sigma", "0"],
        "particles.sigma (--sigma)",
    );
    // Settings of an attribute without one.
    fails_with(
        &["--attribute-range", "0", "1"],
        "acts on a per-particle attribute",
    );
    fails_with(
        &["--classification", "pre"],
        "acts on a per-particle attribute",
    );
    // Value ranges that make every sample transparent name the range, not
    // the camera.
    fails_with(&["--value-range", "0.5", "0.5"], "zero width");
    fails_with(
        &["--value-range", "1e30", "2e30"],
        "above the field's largest value",
    );
    // A frame the data does not have.
    write_grid(&s.path("grid.npy"), 6);
    let tets = [
        "--particles",
        &s.str("grid.npy"),
        "--lagrangian",
        "6",
        "--box",
        "1",
    ];
    let mut args = vec!["render", "--frame", "2", "--size", "16", "12", "-o", &out];
    args.extend(tets);
    let e = fails(&args);
    assert!(e.contains("frame 2") && e.contains("one frame"), "{e}");
    let proj = s.str("x.npy");
    let mut args = vec!["project", "--frame", "1", "--size", "8", "8", "-o", &proj];
    args.extend(tets);
    assert!(fails(&args).contains("one frame"));
    // A gradient the tessellation does not have.
    voxless_io::write_npy_f32(&s.path("q.npy"), &[1, 3], &[0.5, 0.5, 0.5]).unwrap();
    let pts = s.str("q.npy");
    let samples = s.str("s.npy");
    let mut args = vec!["sample", "--points", &pts, "--gradient", "-o", &samples];
    args.extend(tets);
    let e = fails(&args);
    assert!(e.contains("gradient (--gradient)"), "{e}");
    // A scene mirror at NaN (the flag form is refused by its parser).
    let scene = s.path("mirror.toml");
    std::fs::write(
        &scene,
        format!("[particles]\nfile = '{p}'\n[[instances]]\nmirror = 'x'\nat = nan\n"),
    )
    .unwrap();
    let e = fails(&[
        "render",
        &s.str("mirror.toml"),
        "--size",
        "16",
        "12",
        "-o",
        &out,
    ]);
    assert!(e.contains("instances.at"), "{e}");
}
