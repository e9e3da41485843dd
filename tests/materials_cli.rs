//! Multi-material scenes end to end: a LAMMPS dump with two atom types, one
//! `[[particles.materials]]` entry per type, rendered (also as a time series)
//! and sampled through the binary.

mod common;

use common::{Lcg, Scratch, fails, ok};
use std::fmt::Write as _;

/// Two frames of 400 atoms: type 1 on the left half of the box, type 2 on
/// the right.
fn write_dump(path: &std::path::Path) {
    let mut rng = Lcg(17);
    let mut text = String::new();
    for step in [0, 100] {
        writeln!(text, "ITEM: TIMESTEP\n{step}\nITEM: NUMBER OF ATOMS\n400").unwrap();
        writeln!(text, "ITEM: BOX BOUNDS pp pp pp\n0 10\n0 10\n0 10").unwrap();
        writeln!(text, "ITEM: ATOMS id type x y z").unwrap();
        for id in 1..=400 {
            let t = if id <= 200 { 1 } else { 2 };
            let x = rng.f() * 5.0 + if t == 1 { 0.0 } else { 5.0 };
            let (y, z) = (rng.f() * 10.0, rng.f() * 10.0);
            writeln!(text, "{id} {t} {x} {y} {z}").unwrap();
        }
    }
    std::fs::write(path, text).unwrap();
}

fn scene(dir: &Scratch, extra: &str) -> String {
    let toml = format!(
        r#"[particles]
file = "melt.dump"
radius = 1.5
{extra}
[[particles.materials]]
species = "1"
name = "argon"
color = [0.2, 0.4, 1.0]
value_range = [0.0, 2.0]

[[particles.materials]]
species = "2"
radius = 2.5
colormap = "inferno"
opacity = "ramp-high"

[image]
width = 64
height = 48
"#
    );
    let path = dir.path("scene.toml");
    std::fs::write(&path, toml).unwrap();
    path.to_string_lossy().into_owned()
}

#[test]
fn two_materials_render_sample_and_step_through_frames() {
    let dir = Scratch::new("materials");
    write_dump(&dir.path("melt.dump"));
    let scene = scene(&dir, "");
    let out = dir.str("m.png");
    let log = ok(&["render", &scene, "-o", &out]);
    assert!(log.contains("material 'argon': 200 particles"), "{log}");
    assert!(log.contains("material 'species 2': 200 particles"), "{log}");
    let (w, h, rgb) = voxless_io::read_png_rgb8(&dir.path("m.png")).unwrap();
    assert_eq!((w, h), (64, 48));
    // Argon is blue (a fixed colour) and sits on the left: the left half is
    // bluer than the right, which has inferno colours.
    let mean_blue_minus_red = |x0: u32, x1: u32| {
        let mut s = 0.0;
        for y in 0..h {
            for x in x0..x1 {
                let i = ((y * w + x) * 3) as usize;
                s += rgb[i + 2] as f64 - rgb[i] as f64;
            }
        }
        s / ((x1 - x0) * h) as f64
    };
    assert!(rgb.iter().any(|&c| c > 20), "the image is empty");
    // The default camera looks down −z with x to the right.
    assert!(
        mean_blue_minus_red(0, w / 2) > mean_blue_minus_red(w / 2, w),
        "argon (blue) should dominate the left half"
    );
    // Packets and the per-sample path agree through the CLI too.
    let slow = dir.str("slow.png");
    ok(&["render", &scene, "--no-packets", "-o", &slow]);
    let (_, _, rgb_slow) = voxless_io::read_png_rgb8(&dir.path("slow.png")).unwrap();
    let worst = rgb
        .iter()
        .zip(&rgb_slow)
        .map(|(a, b)| (*a as i32 - *b as i32).abs())
        .max()
        .unwrap();
    assert!(
        worst <= 1,
        "packet and per-sample PNGs differ by {worst} levels"
    );
    // A time series re-reads every material per frame.
    let seq = dir.str("seq.png");
    ok(&["render", &scene, "--frames", "0..1", "-o", &seq]);
    assert!(dir.path("seq_0000.png").exists() && dir.path("seq_0001.png").exists());
    // `sample` gives one density column per material.
    let pts = dir.path("q.npy");
    voxless_io::write_npy_f32(&pts, &[2, 3], &[2.5, 5.0, 5.0, 7.5, 5.0, 5.0]).unwrap();
    let samples = dir.str("s.npy");
    ok(&[
        "sample",
        &scene,
        "--points",
        &pts.to_string_lossy(),
        "-o",
        &samples,
    ]);
    let a = voxless_io::read_npy(&dir.path("s.npy")).unwrap();
    assert_eq!(a.shape, vec![2, 2]);
    // Left point: argon only; right point: type 2 only.
    assert!(a.data[0] > 0.0 && a.data[1] == 0.0, "{:?}", a.data);
    assert!(a.data[2] == 0.0 && a.data[3] > 0.0, "{:?}", a.data);
}

#[test]
fn bad_material_settings_are_clear_errors() {
    let dir = Scratch::new("materials-bad");
    write_dump(&dir.path("melt.dump"));
    // A species that is not in the file.
    let bad = scene(&dir, "").replace("scene.toml", "bad.toml");
    let text = std::fs::read_to_string(dir.path("scene.toml"))
        .unwrap()
        .replace("species = \"2\"", "species = \"7\"");
    std::fs::write(&bad, text).unwrap();
    let err = fails(&["render", &bad, "-o", &dir.str("x.png")]);
    assert!(err.contains("type 7") || err.contains("7"), "{err}");
    // Both a global species filter and materials.
    let both = scene(&dir, "species = \"1\"");
    let err = fails(&["render", &both, "-o", &dir.str("x.png")]);
    assert!(err.contains("particles.species"), "{err}");
}
