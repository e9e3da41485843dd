//! End-to-end AMR: the binary on ExaBricks files it writes, and on the real
//! AMRClaw frame when the shared data is present.

mod common;
use common::*;

/// Writes a two-level ExaBricks set over [0, 8)³ finest units: level-1 cells
/// everywhere except one level-0 corner block; field a = x + 2y + 3z at the
/// cell centre, field b = level.
fn write_exabricks(s: &Scratch) -> Vec<([i32; 4], f32)> {
    let mut cells: Vec<[i32; 4]> = Vec::new();
    for z in (0..8).step_by(2) {
        for y in (0..8).step_by(2) {
            for x in (0..8).step_by(2) {
                if x < 4 && y < 4 && z < 4 {
                    for dz in 0..2 {
                        for dy in 0..2 {
                            for dx in 0..2 {
                                cells.push([x + dx, y + dy, z + dz, 0]);
                            }
                        }
                    }
                } else {
                    cells.push([x, y, z, 1]);
                }
            }
        }
    }
    let value = |c: &[i32; 4]| {
        let w = (1 << c[3]) as f32;
        let p = [0, 1, 2].map(|a| c[a] as f32 + 0.5 * w);
        p[0] + 2.0 * p[1] + 3.0 * p[2]
    };
    let mut bytes = Vec::new();
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for c in &cells {
        for v in c {
            bytes.extend(v.to_le_bytes());
        }
        a.extend(value(c).to_le_bytes());
        b.extend((c[3] as f32).to_le_bytes());
    }
    std::fs::write(s.path("t.cells"), bytes).unwrap();
    std::fs::write(s.path("t.a.scalars"), a).unwrap();
    std::fs::write(s.path("t.b.scalars"), b).unwrap();
    cells.iter().map(|c| (*c, value(c))).collect()
}

fn amr_args(s: &Scratch) -> Vec<String> {
    vec![
        "--cells".into(),
        s.str("t.cells"),
        "--scalars".into(),
        s.str("t.a.scalars"),
        "--scalars".into(),
        s.str("t.b.scalars"),
        "--cell-size".into(),
        "0.5".into(),
    ]
}

fn run(s: &Scratch, cmd: &str, extra: &[&str]) -> String {
    let mut args: Vec<String> = vec![cmd.into()];
    args.extend(amr_args(s));
    args.extend(extra.iter().map(|x| x.to_string()));
    let refs: Vec<&str> = args.iter().map(|x| x.as_str()).collect();
    ok(&refs)
}

#[test]
fn render_iso_clip_and_multifield() {
    let s = Scratch::new("amr-render");
    write_exabricks(&s);
    run(&s, "render", &["--size", "40", "30", "-o", &s.str("v.png")]);
    run(
        &s,
        "render",
        &[
            "--size",
            "40",
            "30",
            "--iso",
            "12",
            "--iso-only",
            "--shade",
            "--color-field",
            "b",
            "-o",
            &s.str("i.png"),
        ],
    );
    run(
        &s,
        "render",
        &[
            "--size",
            "40",
            "30",
            "--clip",
            "0",
            "0",
            "0",
            "2",
            "2",
            "2",
            "--reconstruction",
            "nearest",
            "-o",
            &s.str("c.png"),
        ],
    );
    for f in ["v.png", "i.png", "c.png"] {
        let (_, _, rgb) = voxless_io::read_png_rgb8(&s.path(f)).unwrap();
        assert!(rgb.iter().any(|&c| c > 20), "{f} is blank");
    }
}

#[test]
fn sample_gives_every_field_and_gradients() {
    let s = Scratch::new("amr-sample");
    write_exabricks(&s);
    // Inside the domain, away from its outer half-cell margin, the basis
    // reconstruction of the linear field a = x + 2y + 3z (unit coordinates) is
    // exact within each level and its world gradient is (1, 2, 3) / 0.5.
    let pts: Vec<f32> = vec![1.1, 1.2, 1.3, 2.6, 2.7, 2.9, 0.9, 3.0, 1.7];
    voxless_io::write_npy_f32(&s.path("q.npy"), &[3, 3], &pts).unwrap();
    let stderr = run(
        &s,
        "sample",
        &[
            "--points",
            &s.str("q.npy"),
            "-o",
            &s.str("o.npy"),
            "--gradient",
        ],
    );
    assert!(stderr.contains("a, b, da/dx"), "{stderr}");
    let (shape, v) = read(&s.path("o.npy"));
    assert_eq!(shape, vec![3, 8]);
    let row = &v[0..8];
    let pu = [1.1 / 0.5, 1.2 / 0.5, 1.3 / 0.5];
    let want = pu[0] + 2.0 * pu[1] + 3.0 * pu[2];
    assert!((row[0] - want).abs() < 1e-4, "{} vs {want}", row[0]);
    assert!(
        (row[2] - 2.0).abs() < 1e-3 && (row[3] - 4.0).abs() < 1e-3 && (row[4] - 6.0).abs() < 1e-3,
        "{row:?}"
    );
}

#[test]
fn octant_sample_is_exact_on_one_level_and_continuous_across_levels() {
    let s = Scratch::new("amr-sample-octant");
    write_exabricks(&s);
    // Two points whose octant boxes lie among cells of one level (the
    // level-1 part, the level-0 corner): the linear field a = x + 2y + 3z
    // is reproduced with its world gradient (1, 2, 3) / 0.5; then two
    // points 1e-4 either side of the level boundary x = 2.
    let pts: Vec<f32> = vec![
        2.6, 2.7, 2.9, 0.9, 0.6, 0.7, 1.9999, 1.3, 1.1, 2.0001, 1.3, 1.1,
    ];
    voxless_io::write_npy_f32(&s.path("q.npy"), &[4, 3], &pts).unwrap();
    let args = ["--points", &s.str("q.npy"), "-o", &s.str("o.npy")];
    let rest = ["--gradient", "--reconstruction", "octant"];
    let stderr = run(&s, "sample", &[&args[..], &rest[..]].concat());
    assert!(stderr.contains("a, b, da/dx"), "{stderr}");
    let (shape, v) = read(&s.path("o.npy"));
    assert_eq!(shape, vec![4, 8]);
    for (r, p) in [[2.6f64, 2.7, 2.9], [0.9, 0.6, 0.7]].iter().enumerate() {
        let row = &v[r * 8..r * 8 + 8];
        let want = (p[0] + 2.0 * p[1] + 3.0 * p[2]) / 0.5;
        assert!((row[0] - want).abs() < 1e-4, "{} vs {want}", row[0]);
        let g = &row[2..5];
        assert!(
            (g[0] - 2.0).abs() < 1e-3 && (g[1] - 4.0).abs() < 1e-3 && (g[2] - 6.0).abs() < 1e-3,
            "{row:?}"
        );
    }
    // |Δa| ≤ 2e-4 · |da/dx| (about 2) on a continuous field.
    let (a, b) = (v[16], v[24]);
    assert!((a - b).abs() < 1e-3, "{a} | {b} across the level boundary");
}

#[test]
fn nearest_projection_conserves_the_integral() {
    let s = Scratch::new("amr-project");
    let cells = write_exabricks(&s);
    let exact: f64 = cells
        .iter()
        .map(|(c, v)| *v as f64 * ((1 << c[3]) as f64 * 0.5).powi(3))
        .sum();
    for axis in ["x", "y", "z"] {
        // Pixels aligned with the finest cells: the sum is exact.
        let stderr = run(
            &s,
            "project",
            &[
                "--reconstruction",
                "nearest",
                "--axis",
                axis,
                "--size",
                "64",
                "64",
                "--bounds",
                "0",
                "0",
                "0",
                "4",
                "4",
                "4",
                "-o",
                &s.str("p.npy"),
            ],
        );
        let (_, col) = read(&s.path("p.npy"));
        let total: f64 = col.iter().sum::<f64>() * (4.0f64 / 64.0).powi(2);
        assert!(
            (total - exact).abs() <= 1e-4 * exact,
            "down {axis}: {total} vs {exact}"
        );
        assert!(stderr.contains("exact ∫ field dV"), "{stderr}");
    }
}

/// (cells, scalars, extra flags, what the error message must mention)
type BadCase<'a> = (&'a str, Option<&'a str>, &'a [&'a str], &'a [&'a str]);

#[test]
fn bad_amr_input_gives_clear_errors() {
    let s = Scratch::new("amr-bad");
    write_exabricks(&s);
    // Overlap: a level-0 cell inside a level-1 cell.
    let mut bytes = std::fs::read(s.path("t.cells")).unwrap();
    bytes.extend([6i32, 6, 6, 0].iter().flat_map(|v| v.to_le_bytes()));
    std::fs::write(s.path("o.cells"), &bytes).unwrap();
    let mut a = std::fs::read(s.path("t.a.scalars")).unwrap();
    a.extend(1.0f32.to_le_bytes());
    std::fs::write(s.path("o.a.scalars"), &a).unwrap();
    // (cells, scalars, extra flags, what the message must mention)
    let (o_cells, t_cells, o_a, t_a) = (
        s.str("o.cells"),
        s.str("t.cells"),
        s.str("o.a.scalars"),
        s.str("t.a.scalars"),
    );
    let cases: [BadCase; 4] = [
        (&o_cells, Some(&o_a), &[], &["o.cells", "overlap"]),
        (&t_cells, Some(&o_a), &[], &["o.a.scalars"]),
        (&t_cells, None, &[], &["scalars"]),
        (
            &t_cells,
            Some(&t_a),
            &["--field", "pressure"],
            &["pressure", "a"],
        ),
    ];
    let out = s.str("x.png");
    for (cells, scalars, extra, mentions) in cases {
        let mut args = vec!["render", "--cells", cells, "-o", &out];
        if let Some(sc) = scalars {
            args.extend(["--scalars", sc]);
        }
        args.extend_from_slice(extra);
        let e = fails(&args);
        assert!(mentions.iter().all(|m| e.contains(m)), "{args:?}: {e}");
    }
    std::fs::write(
        s.path("u.cells"),
        [1i32, 0, 0, 1]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect::<Vec<u8>>(),
    )
    .unwrap();
    std::fs::write(s.path("u.a.scalars"), 1.0f32.to_le_bytes()).unwrap();
    let e = fails(&[
        "render",
        "--cells",
        &s.str("u.cells"),
        "--scalars",
        &s.str("u.a.scalars"),
        "-o",
        &s.str("x.png"),
    ]);
    assert!(e.contains("u.cells") && e.contains("aligned"), "{e}");
}

/// AMRClaw's own output and its ExaBricks conversion sample identically.
#[test]
fn amrclaw_and_exabricks_frames_agree() {
    let Some(dir) = shared_data("amr-euler3d") else {
        return;
    };
    let s = Scratch::new("amr-real");
    let mut pts = Vec::new();
    let mut rng = Lcg(3);
    for _ in 0..2000 {
        pts.extend([rng.f() * 2.0, rng.f() * 2.0, rng.f() * 2.0]);
    }
    voxless_io::write_npy_f32(&s.path("q.npy"), &[2000, 3], &pts).unwrap();
    let f = |p: &str| dir.join(p).to_string_lossy().into_owned();
    ok(&[
        "sample",
        "--amrclaw",
        &f("fort.q0003"),
        "--points",
        &s.str("q.npy"),
        "-o",
        &s.str("claw.npy"),
    ]);
    ok(&[
        "sample",
        "--cells",
        &f("exabricks/frame3.cells"),
        "--scalars",
        &f("exabricks/frame3.density.scalars"),
        "--points",
        &s.str("q.npy"),
        "-o",
        &s.str("exa.npy"),
    ]);
    let (shape, claw) = read(&s.path("claw.npy"));
    assert_eq!(shape, vec![2000, 5], "five AMRClaw fields q0..q4");
    let (_, exa) = read(&s.path("exa.npy"));
    for i in 0..2000 {
        assert_eq!(claw[i * 5], exa[i], "density at point {i}");
    }
}

/// Numbered AMRClaw outputs are a time series: `fort.q%04d` has frames 2
/// and 3, each slice equals that file's own, and a movie-style sequence
/// renders both with their `fort.t` times as labels.
#[test]
fn amrclaw_outputs_by_pattern_are_a_time_series() {
    let Some(dir) = shared_data("amr-euler3d") else {
        return;
    };
    let s = Scratch::new("amr-series");
    let f = |p: &str| dir.join(p).to_string_lossy().into_owned();
    let pattern = f("fort.q%04d");
    let (out, one, two) = (s.str("a.png"), s.str("one.npy"), s.str("two.npy"));
    let e = ok(&[
        "render",
        "--amrclaw",
        &pattern,
        "--frames",
        "0..9",
        "--size",
        "48",
        "36",
        "--time-label",
        "-o",
        &out,
    ]);
    assert!(
        e.contains("rendered 2 frames") && e.contains("frames in that range are 2, 3"),
        "{e}"
    );
    assert!(s.path("a_0002.png").is_file() && s.path("a_0003.png").is_file());
    ok(&[
        "slice",
        "--amrclaw",
        &pattern,
        "--frame",
        "2",
        "--size",
        "32",
        "32",
        "-o",
        &one,
    ]);
    ok(&[
        "slice",
        "--amrclaw",
        &f("fort.q0002"),
        "--size",
        "32",
        "32",
        "-o",
        &two,
    ]);
    assert_eq!(read(&s.path("one.npy")).1, read(&s.path("two.npy")).1);
    let e = fails(&["slice", "--amrclaw", &pattern, "--frame", "5", "-o", &one]);
    assert!(e.contains("2") && e.contains("3"), "{e}");
}
