//! End-to-end: colormap files, the colour bar, and the camera conveniences
//! (orbit, elevation, zoom, turntables) of the `voxless` binary.

mod common;
use common::*;

/// A small particle cloud in the unit cube, and the flags that render it.
fn particles(s: &Scratch) -> Vec<String> {
    write_positions(&s.path("p.npy"), 2000, 7);
    let attr: Vec<f32> = (0..2000).map(|i| (i % 11) as f32).collect();
    write_values(&s.path("a.npy"), &attr);
    [
        "--particles",
        &s.str("p.npy"),
        "--attribute",
        &s.str("a.npy"),
        "--radius",
        "0.08",
        "--spp",
        "1",
    ]
    .map(String::from)
    .to_vec()
}

fn render(out: &str, base: &[String], extra: &[&str]) -> String {
    let mut args: Vec<&str> = vec!["render", "-o", out];
    args.extend(base.iter().map(String::as_str));
    args.extend_from_slice(extra);
    if !extra.contains(&"--size") {
        args.extend(["--size", "64", "48"]);
    }
    ok(&args)
}

fn png(path: &std::path::Path) -> (u32, u32, Vec<u8>) {
    voxless_io::read_png_rgb8(path).unwrap()
}

const PRESETS: &str = r#"[
  {"Name": "Blue Orange", "ColorSpace": "RGB", "NanColor": [1, 0, 0],
   "RGBPoints": [-10, 0.1, 0.2, 0.8, 0, 0.9, 0.9, 0.9, 10, 0.9, 0.5, 0.1],
   "Points": [-10, 0.2, 0.5, 0, 10, 1, 0.5, 0]},
  {"Name": "Greys", "RGBPoints": [0, 0, 0, 0, 1, 1, 1, 1]}
]"#;

#[test]
fn colormap_file_renders_like_the_same_control_points() {
    let s = Scratch::new("cmapfile");
    write_positions(&s.path("p.npy"), 2000, 3);
    std::fs::create_dir_all(s.path("maps")).unwrap();
    std::fs::write(s.path("maps/presets.json"), PRESETS).unwrap();
    let scene = |transfer: &str| {
        format!(
            "[particles]\nfile = \"p.npy\"\nradius = 0.08\n[image]\nwidth = 48\nheight = 32\n[transfer]\n{transfer}\n"
        )
    };
    // The same colours and opacity as control points in the scene...
    std::fs::write(
        s.path("points.toml"),
        scene(
            "colormap_points = [[0.0, 0.1, 0.2, 0.8], [0.5, 0.9, 0.9, 0.9], [1.0, 0.9, 0.5, 0.1]]\nopacity_points = [[0.0, 0.2], [1.0, 1.0]]",
        ),
    )
    .unwrap();
    // ...and from the file, relative to the scene, picked by name.
    std::fs::write(
        s.path("file.toml"),
        scene("colormap_file = \"maps/presets.json\"\ncolormap = \"Blue Orange\""),
    )
    .unwrap();
    ok(&["render", &s.str("points.toml"), "-o", &s.str("points.png")]);
    let log = ok(&["render", &s.str("file.toml"), "-o", &s.str("file.png")]);
    assert!(log.contains("Blue Orange"), "{log}");
    assert_eq!(
        png(&s.path("points.png")),
        png(&s.path("file.png")),
        "a preset renders exactly as its control points do"
    );
    // From the command line: the first preset by default, --colormap picks.
    let base = particles(&s);
    let file = s.str("maps/presets.json");
    render(&s.str("first.png"), &base, &["--colormap-file", &file]);
    render(
        &s.str("greys.png"),
        &base,
        &["--colormap-file", &file, "--colormap", "Greys"],
    );
    assert_ne!(png(&s.path("first.png")), png(&s.path("greys.png")));
    let (_, _, grey) = png(&s.path("greys.png"));
    assert!(
        grey.chunks(3).all(|p| p[0] == p[1] && p[1] == p[2]),
        "Greys is grey"
    );
    // A matplotlib-style list.
    std::fs::write(s.path("list.json"), "[[0, 0, 0.3], [1, 1, 0]]").unwrap();
    render(
        &s.str("list.png"),
        &base,
        &["--colormap-file", &s.str("list.json")],
    );
    // Unknown preset names list what the file has; bad files say why.
    let mut args: Vec<&str> = vec!["render", "-o", "x.png"];
    args.extend(base.iter().map(String::as_str));
    let with = |extra: &[&str]| {
        let mut a = args.clone();
        a.extend_from_slice(extra);
        fails(&a)
    };
    let e = with(&["--colormap-file", &file, "--colormap", "Jet"]);
    assert!(
        e.contains("Jet") && e.contains("Blue Orange, Greys") && e.contains("presets.json"),
        "{e}"
    );
    std::fs::write(s.path("bad.json"), "[[0, 0, 2]]").unwrap();
    let e = with(&["--colormap-file", &s.str("bad.json")]);
    assert!(
        e.contains("bad.json") && e.contains("outside [0, 1]"),
        "{e}"
    );
}

#[test]
fn orbit_90_equals_the_rotated_eye_and_the_scene_key() {
    let s = Scratch::new("orbit");
    let base = particles(&s);
    // y up (the default up, +z, would roll the explicit eye's view).
    let at = ["--look-at", "0.5", "0.5", "0.5", "--up", "0", "1", "0"];
    let mut orbit = vec!["--eye", "0.5", "0.5", "3", "--orbit", "90"];
    orbit.extend(at);
    render(&s.str("orbit.png"), &base, &orbit);
    // (0.5, 0.5, 3) turned 90° about the vertical through (0.5, 0.5, 0.5).
    let mut eye = vec!["--eye", "3", "0.5", "0.5"];
    eye.extend(at);
    render(&s.str("eye.png"), &base, &eye);
    render(&s.str("plain.png"), &base, &at);
    let (a, b) = (png(&s.path("orbit.png")), png(&s.path("eye.png")));
    assert_eq!((a.0, a.1), (b.0, b.1));
    let worst = a.2.iter().zip(&b.2).map(|(x, y)| x.abs_diff(*y)).max();
    assert!(
        worst <= Some(1),
        "orbit and explicit eye differ by {worst:?}"
    );
    assert_ne!(a, png(&s.path("plain.png")));

    // The same from the scene file's [camera] keys.
    std::fs::write(
        s.path("cam.toml"),
        "[camera]\neye = [0.5, 0.5, 3.0]\nlook_at = [0.5, 0.5, 0.5]\norbit = 90.0\nup = [0.0, 1.0, 0.0]\n",
    )
    .unwrap();
    let scene = s.str("cam.toml");
    let mut args = vec!["render", &scene];
    let out = s.str("toml.png");
    args.extend(["-o", &out, "--size", "64", "48"]);
    args.extend(base.iter().map(String::as_str));
    ok(&args);
    assert_eq!(png(&s.path("toml.png")), a);
    // Elevation changes the view and composes with the default camera.
    render(&s.str("elev.png"), &base, &["--elevation", "40"]);
    render(&s.str("default.png"), &base, &[]);
    assert_ne!(png(&s.path("elev.png")), png(&s.path("default.png")));
}

#[test]
fn zoom_moves_the_eye_halfway_in() {
    let s = Scratch::new("zoom");
    let base = particles(&s);
    let at = ["--look-at", "0.5", "0.5", "0.5"];
    let mut zoom = vec!["--eye", "0.5", "0.5", "3", "--zoom", "2"];
    zoom.extend(at);
    render(&s.str("zoom.png"), &base, &zoom);
    let mut near = vec!["--eye", "0.5", "0.5", "1.75"];
    near.extend(at);
    render(&s.str("near.png"), &base, &near);
    render(&s.str("far.png"), &base, &["--eye", "0.5", "0.5", "3"]);
    let (z, n) = (png(&s.path("zoom.png")), png(&s.path("near.png")));
    let worst = z.2.iter().zip(&n.2).map(|(x, y)| x.abs_diff(*y)).max();
    assert!(worst <= Some(1), "zoom 2 vs half distance: {worst:?}");
    assert_ne!(z, png(&s.path("far.png")), "--zoom 2 changes the image");
    // The default (framing) camera zooms too; orthographic views shrink.
    render(&s.str("dz.png"), &base, &["--zoom", "1.5"]);
    render(&s.str("d.png"), &base, &[]);
    assert_ne!(png(&s.path("dz.png")), png(&s.path("d.png")));
    render(&s.str("o.png"), &base, &["--orthographic", "2"]);
    render(
        &s.str("oz.png"),
        &base,
        &["--orthographic", "2", "--zoom", "2"],
    );
    render(&s.str("o1.png"), &base, &["--orthographic", "1"]);
    assert_eq!(png(&s.path("oz.png")), png(&s.path("o1.png")));
}

#[test]
fn turntable_writes_n_frames_of_a_full_orbit() {
    let s = Scratch::new("turntable");
    let base = particles(&s);
    let at = ["--eye", "0.5", "0.5", "3", "--look-at", "0.5", "0.5", "0.5"];
    let mut args = vec!["--turntable", "4"];
    args.extend(at);
    let log = render(&s.str("turn.png"), &base, &args);
    assert!(log.contains("4-frame turntable"), "{log}");
    for k in 0..4 {
        assert!(s.path(&format!("turn_{k:04}.png")).exists(), "frame {k}");
    }
    assert!(!s.path("turn_0004.png").exists());
    assert!(!s.path("turn.png").exists());
    // Frame 0 is the scene's camera, frame 1 a quarter turn further.
    let mut quarter = vec!["--orbit", "90"];
    quarter.extend(at);
    render(&s.str("plain.png"), &base, &at);
    render(&s.str("quarter.png"), &base, &quarter);
    assert_eq!(png(&s.path("turn_0000.png")), png(&s.path("plain.png")));
    assert_eq!(png(&s.path("turn_0001.png")), png(&s.path("quarter.png")));
    assert_ne!(png(&s.path("turn_0000.png")), png(&s.path("turn_0002.png")));
    // The scene's orbit is the starting point; colour bars go on every frame.
    let mut args = vec!["--turntable", "2", "--orbit", "90", "--colorbar"];
    args.extend(at);
    render(&s.str("t.png"), &base, &args);
    let (_, _, t0) = png(&s.path("t_0000.png"));
    let (_, _, q) = png(&s.path("quarter.png"));
    assert_eq!(
        t0[..3 * 20],
        q[..3 * 20],
        "the left of the first row agrees"
    );
    assert_ne!(t0, q, "the colour bar is drawn");
}

#[test]
fn colorbar_changes_only_the_right_hand_strip() {
    let s = Scratch::new("colorbar");
    let base = particles(&s);
    let size = ["--size", "200", "120"];
    render(&s.str("plain.png"), &base, &size);
    let mut with = vec!["--colorbar"];
    with.extend(size);
    render(&s.str("bar.png"), &base, &with);
    let (w, h, a) = png(&s.path("plain.png"));
    let (_, _, b) = png(&s.path("bar.png"));
    let mut changed = 0;
    for y in 0..h as usize {
        for x in 0..w as usize {
            let i = 3 * (y * w as usize + x);
            if a[i..i + 3] != b[i..i + 3] {
                changed += 1;
                assert!(
                    x >= w as usize / 2,
                    "pixel ({x}, {y}) left of the bar changed"
                );
            }
        }
    }
    assert!(
        changed > 200,
        "the bar and its labels are drawn ({changed} pixels)"
    );
    // EXR output gets the bar too, and so does the demo.
    let mut exr = vec!["--colorbar"];
    exr.extend(size);
    render(&s.str("bar.exr"), &base, &exr);
    assert!(std::fs::metadata(s.path("bar.exr")).unwrap().len() > 0);
    ok(&[
        "demo",
        "-o",
        &s.str("demo.png"),
        "--size",
        "96",
        "54",
        "--orbit",
        "45",
        "--colorbar",
    ]);
    // A tiny image is not a problem.
    render(
        &s.str("tiny.png"),
        &base,
        &["--colorbar", "--size", "16", "16"],
    );
}

#[test]
fn bad_view_values_are_clear_errors() {
    let s = Scratch::new("badview");
    let base = particles(&s);
    let run = |extra: &[&str]| {
        let mut args: Vec<&str> = vec!["render", "-o", "never.png"];
        args.extend(base.iter().map(String::as_str));
        args.extend_from_slice(extra);
        fails(&args)
    };
    for (flags, want) in [
        (&["--zoom", "0"][..], "--zoom"),
        (&["--zoom", "nan"][..], "finite number > 0"),
        (&["--zoom", "-2"][..], "finite number > 0"),
        (&["--zoom", "inf"][..], "--zoom"),
        (&["--turntable", "0"][..], "at least 1 frame"),
        (&["--turntable", "x"][..], "--turntable"),
        (&["--orbit", "nan"][..], "finite angle"),
        (&["--elevation", "inf"][..], "finite angle"),
        (
            &["--turntable", "4", "--frames", "0..1"][..],
            "cannot be used with",
        ),
    ] {
        let e = run(flags);
        assert!(e.contains(want), "{flags:?}: {e}");
    }
    // The scene file's keys are checked as well.
    std::fs::write(s.path("z.toml"), "[camera]\nzoom = 0.0\n").unwrap();
    let scene = s.str("z.toml");
    let mut args = vec!["render", &scene];
    let out = s.str("never.png");
    args.extend(["-o", &out]);
    args.extend(base.iter().map(String::as_str));
    let e = fails(&args);
    assert!(e.contains("camera.zoom"), "{e}");
    assert!(!s.path("never.png").exists());
}
