//! Time series, LAMMPS dumps still being written, help texts, progress
//! when stderr is not a terminal, and bad values refused by name — through
//! the binary.

mod common;
use common::*;

use std::fmt::Write as _;

/// A LAMMPS dump of `n` atoms (types 1 and 7) over `frames` frames; atoms
/// drift along +x frame by frame.
fn dump(n: usize, frames: usize) -> String {
    let mut rng = Lcg(3);
    let start: Vec<[f32; 3]> = (0..n).map(|_| [rng.f(), rng.f(), rng.f()]).collect();
    let mut text = String::new();
    for f in 0..frames {
        writeln!(
            text,
            "ITEM: TIMESTEP\n{}\nITEM: NUMBER OF ATOMS\n{n}",
            10 * f
        )
        .unwrap();
        writeln!(text, "ITEM: BOX BOUNDS pp pp pp\n0 4\n0 4\n0 4").unwrap();
        writeln!(text, "ITEM: ATOMS id type x y z").unwrap();
        for (i, p) in start.iter().enumerate() {
            let t = if i % 3 == 0 { 7 } else { 1 };
            let x = p[0] + 0.5 * f as f32;
            writeln!(text, "{} {t} {x} {} {}", i + 1, p[1], p[2]).unwrap();
        }
    }
    text
}

#[test]
fn frames_are_numbered_by_their_file_names() {
    let s = Scratch::new("numbered");
    for f in [0usize, 1, 2, 4] {
        write_positions(&s.path(&format!("step_{f:04}.npy")), 200, 20 + f as u64);
    }
    for f in 0..5usize {
        let t: Vec<f32> = (0..200).map(|i| (i + f) as f32).collect();
        write_values(&s.path(&format!("temp_{f:04}.npy")), &t);
    }
    let (pos, temp) = (s.str("step_%04d.npy"), s.str("temp_%04d.npy"));
    let render = |frames: &str, out: &str| {
        voxless(&[
            "render",
            "--particles",
            &pos,
            "--attribute",
            &temp,
            "--radius",
            "0.1",
            "--size",
            "16",
            "16",
            "--frames",
            frames,
            "-o",
            &s.str(out),
        ])
    };
    // Frame 3 is missing from the positions but not from the attribute.
    let (good, e, _) = render("3..4", "a.png");
    assert!(
        !good && e.contains("step_0003.npy") && e.contains("frame 3"),
        "{e}"
    );
    assert!(
        !s.path("a_0004.png").exists(),
        "nothing rendered before the error"
    );
    let (good, e, _) = render("4..4", "b.png");
    assert!(good, "{e}");
    assert!(s.path("b_0004.png").exists() && !s.path("b_0003.png").exists());
    // A directory of frames keeps their numbers too.
    let (good, e, _) = voxless(&[
        "render",
        "--particles",
        &s.str("step_*.npy"),
        "--radius",
        "0.1",
        "--size",
        "16",
        "16",
        "--frames",
        "2..4",
        "-o",
        &s.str("g.png"),
    ]);
    assert!(good, "{e}");
    assert!(s.path("g_0002.png").exists() && s.path("g_0004.png").exists());
    // A pattern that would put two frames in one file is refused up front.
    let (good, e, _) = render("0..1", "frame_%s%n.png");
    assert!(!good && e.contains("%d") && !e.contains("loaded"), "{e}");
    // --frame picks a frame by number for render, project and sample.
    let e = fails(&[
        "project",
        "--particles",
        &pos,
        "--radius",
        "0.1",
        "--frame",
        "3",
        "-o",
        &s.str("c.npy"),
    ]);
    assert!(e.contains("step_0003.npy"), "{e}");
    ok(&[
        "project",
        "--particles",
        &pos,
        "--radius",
        "0.1",
        "--size",
        "8",
        "8",
        "--frame",
        "4",
        "-o",
        &s.str("c4.npy"),
    ]);
    ok(&[
        "project",
        "--particles",
        &pos,
        "--radius",
        "0.1",
        "--size",
        "8",
        "8",
        "--frame",
        "0",
        "-o",
        &s.str("c0.npy"),
    ]);
    assert_ne!(read(&s.path("c4.npy")).1, read(&s.path("c0.npy")).1);
    let q = s.str("step_0000.npy");
    ok(&[
        "sample",
        "--particles",
        &pos,
        "--radius",
        "0.1",
        "--frame",
        "4",
        "--points",
        &q,
        "-o",
        &s.str("s4.npy"),
    ]);
    ok(&[
        "sample",
        "--particles",
        &pos,
        "--radius",
        "0.1",
        "--frame",
        "0",
        "--points",
        &q,
        "-o",
        &s.str("s0.npy"),
    ]);
    assert_ne!(read(&s.path("s4.npy")).1, read(&s.path("s0.npy")).1);
}

#[test]
fn series_defaults_hold_over_every_frame() {
    let s = Scratch::new("over-series");
    std::fs::write(s.path("dump.melt"), dump(300, 4)).unwrap();
    let d = s.str("dump.melt");
    let e = ok(&[
        "render",
        "--particles",
        &d,
        "--attribute",
        "id",
        "--size",
        "24",
        "16",
        "--frames",
        "0..3",
        "-o",
        &s.str("m.png"),
    ]);
    assert!(
        e.contains("time series of 4 frames")
            && e.contains("attribute range")
            && e.contains("framing"),
        "{e}"
    );
    // The atoms drift 1.5 along x: the last frame is framed as well as the first.
    let last = voxless_io::read_png_rgb8(&s.path("m_0003.png")).unwrap().2;
    assert!(
        last.iter().any(|&v| v > 20),
        "the last frame shows its atoms"
    );
    // A dump still being written: info and render use its complete frames.
    let text = dump(300, 3);
    std::fs::write(s.path("dump.partial"), &text[..text.len() - 2000]).unwrap();
    let p = s.str("dump.partial");
    let (good, _, out) = voxless(&["info", &p]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        good && stdout.contains("2 frames") && stdout.contains("still writing"),
        "{stdout}"
    );
    ok(&[
        "render",
        "--particles",
        &p,
        "--size",
        "16",
        "16",
        "-o",
        &s.str("p.png"),
    ]);
    ok(&[
        "project",
        "--particles",
        &p,
        "--frame",
        "1",
        "--size",
        "8",
        "8",
        "-o",
        &s.str("p.npy"),
    ]);
    // A scene file's species = 7 is the LAMMPS type number.
    std::fs::write(
        s.path("scene.toml"),
        format!("[particles]\nfile = {d:?}\nspecies = 7\n"),
    )
    .unwrap();
    let e = ok(&[
        "render",
        &s.str("scene.toml"),
        "--size",
        "16",
        "16",
        "-o",
        &s.str("t.png"),
    ]);
    assert!(!e.contains("error"), "{e}");
}

#[test]
fn progress_lines_when_stderr_is_not_a_terminal() {
    let s = Scratch::new("progress");
    write_positions(&s.path("p.npy"), 500, 1);
    let out = std::process::Command::new(bin())
        .args([
            "render",
            "--particles",
            &s.str("p.npy"),
            "--size",
            "64",
            "48",
            "--spp",
            "3",
            "-o",
            &s.str("x.png"),
        ])
        .env("VOXLESS_PROGRESS_EVERY", "0")
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&out.stderr);
    let lines = e
        .lines()
        .filter(|l| l.starts_with("rendering:") && l.contains('%'))
        .count();
    assert!(out.status.success() && lines >= 2, "{e}");
    assert!(e.contains("rendering: 100%"), "{e}");
}

#[test]
fn help_shows_defaults_and_only_the_flags_a_command_uses() {
    let help = |cmd: &str| {
        let (good, _, out) = voxless(&[cmd, "--help"]);
        assert!(good);
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let render = help("render");
    for flag in [
        "--eye",
        "--look-at",
        "--up",
        "--frames",
        "--colormap",
        "--particles",
    ] {
        assert!(render.contains(flag), "render --help lacks {flag}");
    }
    assert!(
        render.contains("default 0 0 1") && render.contains("default 800 600"),
        "{render}"
    );
    let sample = help("sample");
    let project = help("project");
    let demo = help("demo");
    for flag in [
        "--eye",
        "--colormap",
        "--shadows",
        "--iso",
        "--spp",
        "--frames",
    ] {
        assert!(!sample.contains(flag), "sample --help lists {flag}");
        assert!(!project.contains(flag), "project --help lists {flag}");
    }
    assert!(
        sample.contains("--frame") && project.contains("--frame") && project.contains("--size")
    );
    assert!(!sample.contains("--size"), "sample takes no size");
    for flag in ["--particles", "--cells", "--lagrangian", "--frames"] {
        assert!(!demo.contains(flag), "demo --help lists {flag}");
    }
}

#[test]
fn bad_values_are_refused_by_name() {
    let s = Scratch::new("bad-values");
    write_positions(&s.path("p.npy"), 200, 2);
    let p = s.str("p.npy");
    let out = s.str("x.png");
    let e = fails(&[
        "render",
        "--particles",
        &p,
        "--background",
        "nan",
        "0",
        "0",
        "-o",
        &out,
    ]);
    assert!(e.contains("--background"), "{e}");
    // Flags that would do nothing without another are refused, naming both.
    for (flags, needs) in [
        (&["--light-pos", "0", "0", "1"][..], "--shadows"),
        (&["--noise", "white"][..], "--shadows"),
        (&["--iso-opacity", "0.5"][..], "--iso"),
        (&["--kappa", "2"][..], "--kernel gaussian"),
    ] {
        let mut a = vec!["render", "--particles", p.as_str(), "-o", out.as_str()];
        a.extend(flags);
        let e = fails(&a);
        assert!(e.contains(flags[0]) && e.contains(needs), "{flags:?}: {e}");
    }
    // An 8³ Lagrangian grid.
    let n = 8;
    let grid: Vec<f32> = (0..n * n * n)
        .flat_map(|i| [i / (n * n), i / n % n, i % n].map(|k| (k as f32 + 0.5) / n as f32 * 10.0))
        .collect();
    voxless_io::write_npy_f32(&s.path("g.npy"), &[n * n * n, 3], &grid).unwrap();
    let g = s.str("g.npy");
    let tets = |extra: &[&str]| {
        let mut a = vec![
            "render",
            "--particles",
            g.as_str(),
            "--box",
            "10",
            "--size",
            "16",
            "16",
            "-o",
            out.as_str(),
        ];
        a.extend(extra);
        voxless(&a)
    };
    let (good, e, _) = tets(&["--lagrangian", "7"]);
    assert!(
        !good && e.contains("8³") && e.contains("--lagrangian 8"),
        "{e}"
    );
    let (good, e, _) = tets(&["--lagrangian", "8", "--tet-mode", "kbuffer", "--k", "0"]);
    assert!(!good && e.contains("--k"), "{e}");
    let (good, e, _) = tets(&["--lagrangian", "8", "--k", "4"]);
    assert!(!good && e.contains("kbuffer"), "{e}");
    let (good, e, _) = tets(&["--lagrangian", "8"]);
    assert!(good, "{e}");
    // Positions outside [0, box).
    let mut outside = grid.clone();
    outside[3 * 5] = 12.0;
    voxless_io::write_npy_f32(&s.path("o.npy"), &[n * n * n, 3], &outside).unwrap();
    let e = fails(&[
        "render",
        "--particles",
        &s.str("o.npy"),
        "--lagrangian",
        "8",
        "--box",
        "10",
        "-o",
        &out,
    ]);
    assert!(
        e.contains("particle 5") && e.contains("outside the periodic box"),
        "{e}"
    );
}
