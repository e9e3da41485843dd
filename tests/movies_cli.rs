//! Slices, camera paths and movies end to end: `voxless slice` against
//! `voxless sample`, a path's keyframe frames against stills from their
//! cameras, movies read back with ffprobe (required under
//! `VOXLESS_REQUIRE_FFMPEG=1`), resume, and every bad input refused before
//! any rendering.

mod common;

use std::process::Command;

use common::{Scratch, fails, ok, read, voxless, write_positions};
use voxless_core::testing::prerequisite;

/// A blob of particles and the flags reading it.
fn blob(s: &Scratch) -> Vec<String> {
    write_positions(&s.path("p.npy"), 400, 3);
    vec![
        "--particles".into(),
        s.str("p.npy"),
        "--radius".into(),
        "0.12".into(),
    ]
}

/// `cmd`, the data flags `v`, then `more`.
fn args<'a>(cmd: &'a str, v: &'a [String], more: &[&'a str]) -> Vec<&'a str> {
    std::iter::once(cmd)
        .chain(v.iter().map(String::as_str))
        .chain(more.iter().copied())
        .collect()
}

#[test]
fn slice_equals_sample_at_its_pixel_centres() {
    let s = Scratch::new("slice-sample");
    let data = blob(&s);
    let (w, h) = (23usize, 17usize);
    let (c, wid, hei) = ([0.4, 0.5, 0.55], 0.9, 0.7);
    ok(&args(
        "slice",
        &data,
        &[
            "--axis",
            "z",
            "--center",
            "0.4",
            "0.5",
            "0.55",
            "--width",
            "0.9",
            "0.7",
            "--size",
            "23",
            "17",
            "-o",
            &s.str("s.npy"),
        ],
    ));
    // The pixel centres, float32-exact (sample reads float32 points).
    let mut pts = Vec::new();
    for i in 0..h {
        for j in 0..w {
            pts.push([
                c[0] + ((j as f64 + 0.5) / w as f64 - 0.5) * wid,
                c[1] + (0.5 - (i as f64 + 0.5) / h as f64) * hei,
                c[2],
            ]);
        }
    }
    common::write_f64(&s.path("pts.npy"), &pts);
    ok(&args(
        "sample",
        &data,
        &["--points", &s.str("pts.npy"), "-o", &s.str("v.npy")],
    ));
    let (shape, slice) = read(&s.path("s.npy"));
    assert_eq!(shape, vec![h, w]);
    let (_, sampled) = read(&s.path("v.npy"));
    let mut worst = 0.0f64;
    for (a, b) in slice.iter().zip(&sampled) {
        worst = worst.max((a - b).abs());
    }
    let peak = sampled.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(peak > 0.0 && worst <= 1e-6 * peak, "{worst} of {peak}");
}

#[test]
fn slice_outputs_and_refusals() {
    let s = Scratch::new("slice-out");
    let data = blob(&s);
    let png = s.str("s.png");
    let e = ok(&args(
        "slice",
        &data,
        &[
            "--size",
            "200",
            "150",
            "--colorbar",
            "--scale-bar",
            "--log",
            "-o",
            &png,
        ],
    ));
    assert!(e.contains("sliced 200×150 of density"), "{e}");
    assert!(s.path("s.png").is_file());
    ok(&args(
        "slice",
        &data,
        &["--size", "20", "20", "-o", &s.str("s.fits")],
    ));
    let e = fails(&args(
        "slice",
        &data,
        &["--center", "0.5", "0.5", "9", "-o", &s.str("m.npy")],
    ));
    assert!(e.contains("misses the data") && e.contains("bounds"), "{e}");
    let e = fails(&args(
        "slice",
        &data,
        &["--quantity", "temperature", "-o", &s.str("q.npy")],
    ));
    assert!(e.contains("temperature") && e.contains("density"), "{e}");
    let e = fails(&args(
        "slice",
        &data,
        &["--colorbar", "-o", &s.str("r.npy")],
    ));
    assert!(e.contains(".png"), "{e}");
    let e = fails(&args("slice", &data, &["-o", &s.str("r.jpg")]));
    assert!(e.contains("jpg"), "{e}");
    assert!(!s.path("m.npy").exists() && !s.path("q.npy").exists());
}

/// A scene with a three-keyframe path around the blob.
fn path_scene(s: &Scratch, keys: &str) -> String {
    write_positions(&s.path("p.npy"), 400, 3);
    let scene = format!(
        "[particles]\nfile = \"p.npy\"\nradius = 0.12\n[image]\nwidth = 48\nheight = 36\n{keys}"
    );
    std::fs::write(s.path("path.toml"), scene).unwrap();
    s.str("path.toml")
}

const KEYS: &str = "\
[[camera.keyframes]]\nframe = 0\neye = [0.5, -2.5, 1.0]\nlook_at = [0.5, 0.5, 0.5]\n\
[[camera.keyframes]]\nframe = 4\neye = [3.5, 0.5, 1.0]\nlook_at = [0.5, 0.5, 0.5]\n\
[[camera.keyframes]]\nframe = 7\neye = [0.5, 3.5, 1.5]\nlook_at = [0.5, 0.5, 0.5]\n";

fn pixels(path: &std::path::Path) -> Vec<u8> {
    voxless::io::read_png_rgb8(path).unwrap().2
}

#[test]
fn a_camera_path_passes_through_its_keyframes() {
    let s = Scratch::new("path");
    let scene = path_scene(&s, KEYS);
    let e = ok(&["render", &scene, "--frames", "0..7", "-o", &s.str("f.png")]);
    assert!(e.contains("rendered 8 path frames"), "{e}");
    for k in 0..8 {
        assert!(s.path(&format!("f_{k:04}.png")).is_file(), "frame {k}");
    }
    // Keyframe 4 equals a still from its camera.
    ok(&[
        "render",
        &scene,
        "--eye",
        "3.5",
        "0.5",
        "1.0",
        "--look-at",
        "0.5",
        "0.5",
        "0.5",
        "-o",
        &s.str("still.png"),
    ]);
    let (a, b) = (pixels(&s.path("f_0004.png")), pixels(&s.path("still.png")));
    let worst = a.iter().zip(&b).map(|(x, y)| x.abs_diff(*y)).max().unwrap();
    assert!(
        worst <= 1,
        "keyframe 4 differs from its still by {worst}/255"
    );
    // Between keyframes the view moves: frame 2 is neither neighbour.
    assert_ne!(pixels(&s.path("f_0002.png")), a);
    // A single render of a scene with a path shows its first keyframe, and says so.
    let e = ok(&["render", &scene, "-o", &s.str("one.png")]);
    assert!(e.contains("camera path"), "{e}");
    assert_eq!(pixels(&s.path("one.png")), pixels(&s.path("f_0000.png")));
}

#[test]
fn bad_paths_are_refused_before_rendering() {
    let cases = [
        (
            "[[camera.keyframes]]\nframe = 0\neye = [0.5, -2.5, 1.0]\nlook_at = [0.5, 0.5, 0.5]\n",
            "at least two",
        ),
        (
            "[[camera.keyframes]]\nframe = 5\neye = [0.5, -2.5, 1.0]\nlook_at = [0.5, 0.5, 0.5]\n\
             [[camera.keyframes]]\nframe = 2\neye = [3.5, 0.5, 1.0]\nlook_at = [0.5, 0.5, 0.5]\n",
            "increasing frame order",
        ),
        (
            "[[camera.keyframes]]\nframe = 0\neye = [0.5, -2.5, 1.0]\nlook_at = [0.5, 0.5, 0.5]\n\
             [[camera.keyframes]]\nframe = 2\nlook_at = [0.5, 0.5, 0.5]\n",
            "keyframes[1].eye",
        ),
    ];
    for (keys, want) in cases {
        let s = Scratch::new("badpath");
        let scene = path_scene(&s, keys);
        let e = fails(&["render", &scene, "--frames", "0..5", "-o", &s.str("f.png")]);
        assert!(e.contains(want), "{want}: {e}");
        assert!(!s.path("f_0000.png").exists());
    }
    let s = Scratch::new("badpath-movie");
    let scene = path_scene(&s, KEYS);
    let e = fails(&["render", &scene, "-o", &s.str("m.mp4")]);
    assert!(e.contains("--frames") && e.contains("--turntable"), "{e}");
    let e = fails(&["render", &scene, "--frames", "0..3", "-o", &s.str("m.avi")]);
    assert!(e.contains("avi"), "{e}");
    let e = fails(&[
        "render",
        &scene,
        "--frames",
        "0..3",
        "--fps",
        "0",
        "-o",
        &s.str("m.gif"),
    ]);
    assert!(e.contains("fps"), "{e}");
    // No encoder: the package to install, and the PNG alternative.
    let out = Command::new(common::bin())
        .args(["render", &scene, "--frames", "0..3", "-o", &s.str("m.mp4")])
        .env("VOXLESS_FFMPEG", s.str("no-such-ffmpeg"))
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && e.contains("apt install ffmpeg") && e.contains("m.png"),
        "{e}"
    );
    assert!(
        !s.path("m.mp4.frames").exists(),
        "nothing is rendered without an encoder"
    );
}

fn ffprobe(path: &std::path::Path) -> (String, String, String) {
    let out = Command::new("ffprobe")
        .args([
            "-v",
            "error",
            "-count_frames",
            "-select_streams",
            "v:0",
            "-show_entries",
            "stream=nb_read_frames,width,height",
            "-of",
            "csv=p=0",
        ])
        .arg(path)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).trim().to_string();
    let v: Vec<String> = text.split(',').map(str::to_string).collect();
    (
        v[0].clone(),
        v[1].clone(),
        v.get(2).cloned().unwrap_or_default(),
    )
}

fn have_ffmpeg() -> bool {
    let found = ["ffmpeg", "ffprobe"].iter().all(|p| {
        Command::new(p)
            .arg("-version")
            .output()
            .is_ok_and(|o| o.status.success())
    });
    prerequisite(found, "VOXLESS_REQUIRE_FFMPEG", "ffmpeg and ffprobe")
}

#[test]
fn movies_encode_every_frame_and_resume() {
    if !have_ffmpeg() {
        return;
    }
    let s = Scratch::new("movie");
    let scene = path_scene(&s, KEYS);
    for ext in ["mp4", "webm", "gif"] {
        let out = s.path(&format!("m.{ext}"));
        let e = ok(&[
            "render",
            &scene,
            "--frames",
            "0..7",
            "--fps",
            "12",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(e.contains("(8 frames"), "{e}");
        assert_eq!(
            ffprobe(&out),
            ("48".into(), "36".into(), "8".into()),
            "{ext}"
        );
        assert!(
            !s.path(&format!("m.{ext}.frames")).exists(),
            "frames are cleaned up"
        );
    }
    // Resume: frames already on disk (same scene, same frames) are not rendered again.
    let movie = s.path("r.mp4");
    ok(&[
        "render",
        &scene,
        "--frames",
        "0..7",
        "--keep-frames",
        "-o",
        movie.to_str().unwrap(),
    ]);
    let frames = s.path("r.mp4.frames");
    for k in [5, 6, 7] {
        std::fs::remove_file(frames.join(format!("frame_{k:06}.png"))).unwrap();
    }
    std::fs::remove_file(&movie).unwrap();
    let e = ok(&[
        "render",
        &scene,
        "--frames",
        "0..7",
        "-o",
        movie.to_str().unwrap(),
    ]);
    assert!(
        e.contains("resuming: 5 of 8") && e.contains("rendered 3 of 8"),
        "{e}"
    );
    assert_eq!(ffprobe(&movie).2, "8");
    // A turntable is a movie too.
    let t = s.path("t.gif");
    ok(&[
        "render",
        &scene,
        "--turntable",
        "6",
        "-o",
        t.to_str().unwrap(),
    ]);
    assert_eq!(ffprobe(&t).2, "6");
    let (success, _, _) = voxless(&["render", &scene, "--frames", "0..1", "-o", &s.str("x.png")]);
    assert!(success);
}

/// A tessellation over numbered position files is a time series: each
/// frame its own grid, rendered and sliced; one file has one frame.
#[test]
fn tessellation_time_series_from_numbered_files() {
    let s = Scratch::new("tets-series");
    let n = 8;
    for f in 0..3 {
        let mut pos = Vec::new();
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    // A wave growing with the frame number.
                    let q = [i, j, k].map(|c| (c as f32 + 0.5) / n as f32);
                    let d = 0.08 * f as f32 * (std::f32::consts::TAU * q[0]).sin();
                    pos.extend([(q[0] + d).rem_euclid(1.0), q[1], q[2]]);
                }
            }
        }
        voxless::io::write_npy_f32(&s.path(&format!("g_{f}.npy")), &[n * n * n, 3], &pos).unwrap();
    }
    let (t, sl, x) = (s.str("t.png"), s.str("s.npy"), s.str("x.png"));
    let (g, g0) = (s.str("g_%d.npy"), s.str("g_0.npy"));
    let data = ["--particles", &g, "--lagrangian", "8", "--box", "1"];
    let mut a = vec!["render"];
    a.extend(data);
    a.extend(["--frames", "0..2", "--size", "40", "30", "-o", &t]);
    let e = ok(&a);
    assert!(e.contains("rendered 3 frames"), "{e}");
    assert_ne!(pixels(&s.path("t_0000.png")), pixels(&s.path("t_0002.png")));
    // Frame 2's slice is frame 2's grid: denser where the wave converges.
    let mut a = vec!["slice"];
    a.extend(data);
    a.extend(["--frame", "2", "--size", "16", "4", "-o", &sl]);
    ok(&a);
    let (_, v) = read(&s.path("s.npy"));
    let (lo, hi) = v
        .iter()
        .fold((f64::MAX, 0.0f64), |(l, h), &x| (l.min(x), h.max(x)));
    assert!(hi > 1.5 * lo, "frame 2 is not uniform: {lo} .. {hi}");
    let single = ["--particles", &g0, "--lagrangian", "8", "--box", "1"];
    let mut a = vec!["render"];
    a.extend(single);
    a.extend(["--frame", "1", "-o", &x]);
    let e = fails(&a);
    assert!(
        e.contains("one frame") && e.contains("numbered files"),
        "{e}"
    );
}
