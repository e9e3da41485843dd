//! End-to-end: the `voxless` binary as a user runs it.

mod common;
use common::*;

#[test]
fn demo_writes_a_png() {
    let s = Scratch::new("demo");
    ok(&["demo", "-o", &s.str("demo.png"), "--size", "64", "36"]);
    let (w, h, rgb) = voxless_io::read_png_rgb8(&s.path("demo.png")).unwrap();
    assert_eq!((w, h), (64, 36));
    // Something is drawn: not every pixel is background.
    assert!(rgb.iter().any(|&c| c > 30));
}

#[test]
fn render_from_flags_is_deterministic_and_writes_exr_on_request() {
    let s = Scratch::new("render");
    write_positions(&s.path("p.npy"), 3000, 1);
    let attr: Vec<f32> = (0..3000).map(|i| (i % 7) as f32).collect();
    write_values(&s.path("a.npy"), &attr);
    let common = [
        "--particles",
        &s.str("p.npy"),
        "--attribute",
        &s.str("a.npy"),
        "--radius",
        "0.08",
        "--size",
        "48",
        "32",
        "--spp",
        "3",
        "--colormap",
        "cool-warm",
        "--shade",
        "--cluster",
        "4",
    ];
    let run = |out: &str| {
        let mut args = vec!["render", "-o", out];
        args.extend(common.iter().copied());
        ok(&args);
    };
    run(&s.str("a.png"));
    run(&s.str("b.png"));
    assert_eq!(
        std::fs::read(s.path("a.png")).unwrap(),
        std::fs::read(s.path("b.png")).unwrap()
    );
    run(&s.str("c.exr"));
    let bytes = std::fs::read(s.path("c.exr")).unwrap();
    assert_eq!(&bytes[..4], &[0x76, 0x2f, 0x31, 0x01], "EXR magic");
}

#[test]
fn render_from_the_example_scene_with_overrides() {
    let s = Scratch::new("scene");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/galaxy.toml");
    ok(&[
        "render",
        scene,
        "-o",
        &s.str("g.png"),
        "--size",
        "40",
        "24",
        "--spp",
        "1",
    ]);
    let (w, h, _) = voxless_io::read_png_rgb8(&s.path("g.png")).unwrap();
    assert_eq!((w, h), (40, 24));
}

/// gaussian3 by its definition, for the brute-force check of `sample`.
fn gaussian3(d2: f64, r: f64) -> f64 {
    if d2 <= r * r {
        (-4.5 * d2 / (r * r)).exp()
    } else {
        0.0
    }
}

#[test]
fn sample_writes_the_documented_columns_and_matches_brute_force() {
    let s = Scratch::new("sample");
    let p = write_positions(&s.path("p.npy"), 2000, 2);
    let attr: Vec<f32> = (0..2000).map(|i| (i as f32 * 0.37).sin()).collect();
    write_values(&s.path("a.npy"), &attr);
    let q = write_positions(&s.path("q.npy"), 500, 3);
    let r = 0.1;
    ok(&[
        "sample",
        "--particles",
        &s.str("p.npy"),
        "--attribute",
        &s.str("a.npy"),
        "--radius",
        "0.1",
        "--points",
        &s.str("q.npy"),
        "-o",
        &s.str("out.npy"),
        "--gradient",
    ]);
    let (shape, v) = read(&s.path("out.npy"));
    assert_eq!(shape, vec![500, 5]);
    for (k, x) in q.iter().enumerate() {
        let (mut phi, mut num, mut g) = (0.0f64, 0.0f64, [0.0f64; 3]);
        for (i, c) in p.iter().enumerate() {
            let d = [0, 1, 2].map(|a| x[a] as f64 - c[a] as f64);
            let d2 = d.iter().map(|v| v * v).sum::<f64>();
            let w = gaussian3(d2, r);
            phi += w;
            num += w * attr[i] as f64;
            for a in 0..3 {
                g[a] += -9.0 / (r * r) * w * d[a];
            }
        }
        let row = &v[k * 5..k * 5 + 5];
        assert!(
            (row[0] - phi).abs() <= 1e-5 * phi.max(1e-3),
            "Φ {} vs {phi}",
            row[0]
        );
        if phi > 1e-3 {
            assert!(
                (row[1] - num / phi).abs() <= 1e-4,
                "Θ {} vs {}",
                row[1],
                num / phi
            );
        }
        for a in 0..3 {
            assert!((row[2 + a] - g[a]).abs() <= 1e-4 * (1.0 + g[a].abs()), "∇Φ");
        }
    }
    // Without an attribute or gradient: one column.
    ok(&[
        "sample",
        "--particles",
        &s.str("p.npy"),
        "--radius",
        "0.1",
        "--points",
        &s.str("q.npy"),
        "-o",
        &s.str("phi.npy"),
    ]);
    assert_eq!(read(&s.path("phi.npy")).0, vec![500, 1]);
}

#[test]
fn project_conserves_the_kernel_mass_for_every_kernel() {
    let s = Scratch::new("project");
    let n = 300;
    write_positions(&s.path("p.npy"), n, 4);
    let weights: Vec<f32> = (0..n).map(|i| 0.5 + (i % 3) as f32).collect();
    write_values(&s.path("w.npy"), &weights);
    let wsum: f64 = weights.iter().map(|&w| w as f64).sum();
    // Per unit weight: gaussian3 with r = 0.1 is a Gaussian of s = r/3 cut at
    // 3s; gaussian (κ = 1, σ = 2) with r = 0.05 cut at 2s; the cubic spline
    // integrates to exactly 1.
    let chi3 = |a: f64| {
        libm::erf(a / 2f64.sqrt()) - (2.0 / std::f64::consts::PI).sqrt() * a * (-a * a / 2.0).exp()
    };
    let gauss = |s: f64, a: f64| (2.0 * std::f64::consts::PI).powf(1.5) * s.powi(3) * chi3(a);
    for (kernel, radius, unit_mass) in [
        ("gaussian3", "0.1", gauss(0.1 / 3.0, 3.0)),
        ("gaussian", "0.05", gauss(0.05, 2.0)),
        ("cubic-spline", "0.05", 1.0),
    ] {
        let want = wsum * unit_mass;
        let (p, w) = (s.str("p.npy"), s.str("w.npy"));
        let project = |extra: &[&str]| {
            let mut args = vec![
                "project",
                "--particles",
                &p,
                "--weights",
                &w,
                "--kernel",
                kernel,
                "--radius",
                radius,
            ];
            args.extend_from_slice(extra);
            ok(&args)
        };
        let col = s.str("col.npy");
        for axis in ["x", "y", "z"] {
            // Default bounds: the image covers the particles' supports; the CLI
            // reports Σ column × pixel area and the exact kernel mass.
            let stderr = project(&["--axis", axis, "--size", "300", "240", "-o", &col]);
            assert_eq!(read(&s.path("col.npy")).0, vec![240, 300]);
            let (integral, mass) = integral_and_mass(&stderr);
            assert!(
                (mass - want).abs() <= 1e-6 * want,
                "{kernel}: kernel mass {mass} vs {want}"
            );
            assert!(
                (integral - want).abs() <= 1e-3 * want,
                "{kernel} down {axis}: {integral} vs {want}"
            );
        }
        // Explicit bounds, with the pixel area computed here.
        let bounds = ["--bounds", "-0.2", "-0.2", "-0.2", "1.2", "1.2", "1.2"];
        let mut extra = vec!["--axis", "z", "--size", "280", "280", "-o", &col];
        extra.extend(bounds);
        project(&extra);
        let area = (1.4f64 / 280.0).powi(2);
        let total: f64 = read(&s.path("col.npy")).1.iter().sum::<f64>() * area;
        assert!(
            (total - want).abs() <= 1e-3 * want,
            "{kernel} with --bounds: {total} vs {want}"
        );
    }
}

/// (Σ column × pixel area, total kernel mass) from `project`'s summary line.
fn integral_and_mass(stderr: &str) -> (f64, f64) {
    let line = stderr.lines().find(|l| l.contains("Σ column")).unwrap();
    let nums: Vec<f64> = line
        .split(['=', ',', ')', ' '])
        .filter_map(|t| t.parse::<f64>().ok())
        .collect();
    (nums[nums.len() - 2], nums[nums.len() - 1])
}

#[test]
fn project_pixel_mapping_follows_the_documented_convention() {
    let s = Scratch::new("mapping");
    // One particle at (0.3, 0.6, 0.8) inside explicit bounds [0, 1]³.
    voxless_io::write_npy_f32(&s.path("p.npy"), &[1, 3], &[0.3, 0.6, 0.8]).unwrap();
    for (axis, u, v) in [("x", 0.6, 0.8), ("y", 0.3, 0.8), ("z", 0.3, 0.6)] {
        ok(&[
            "project",
            "--particles",
            &s.str("p.npy"),
            "--radius",
            "0.05",
            "--axis",
            axis,
            "--size",
            "100",
            "50",
            "--bounds",
            "0",
            "0",
            "0",
            "1",
            "1",
            "1",
            "-o",
            &s.str("c.npy"),
        ]);
        let (_, col) = read(&s.path("c.npy"));
        let (imax, _) = col
            .iter()
            .enumerate()
            .fold((0, f64::MIN), |m, (i, &c)| if c > m.1 { (i, c) } else { m });
        let (row, colx) = (imax / 100, imax % 100);
        // centre = (min_u + (col + 0.5)·du, max_v − (row + 0.5)·dv)
        let cu = (colx as f64 + 0.5) / 100.0;
        let cv = 1.0 - (row as f64 + 0.5) / 50.0;
        assert!(
            (cu - u).abs() <= 0.01 && (cv - v).abs() <= 0.02,
            "axis {axis}: peak at ({cu}, {cv}), want ({u}, {v})"
        );
    }
}

#[test]
fn csv_input_with_named_columns() {
    let s = Scratch::new("csv");
    let mut text = String::from("x,y,z,temperature,h\n");
    let mut rng = Lcg(5);
    for _ in 0..500 {
        text += &format!(
            "{},{},{},{},{}\n",
            rng.f(),
            rng.f(),
            rng.f(),
            rng.f() * 100.0,
            0.05 + 0.05 * rng.f()
        );
    }
    std::fs::write(s.path("p.csv"), text).unwrap();
    ok(&[
        "render",
        "--particles",
        &s.str("p.csv"),
        "--attribute",
        "temperature",
        "--radii",
        "h",
        "--size",
        "32",
        "32",
        "-o",
        &s.str("c.png"),
    ]);
    let e = fails(&[
        "render",
        "--particles",
        &s.str("p.csv"),
        "--attribute",
        "pressure",
        "-o",
        &s.str("c.png"),
    ]);
    assert!(
        e.contains("temperature"),
        "unknown column should list the columns: {e}"
    );
}

#[test]
fn bad_input_gives_clear_errors() {
    let s = Scratch::new("bad");
    let good = s.str("p.npy");
    write_positions(&s.path("p.npy"), 100, 6);
    let out = s.str("o.png");

    // NaN coordinate.
    let mut flat = vec![0.5f32; 300];
    flat[3 * 17 + 1] = f32::NAN;
    voxless_io::write_npy_f32(&s.path("nan.npy"), &[100, 3], &flat).unwrap();
    let e = fails(&[
        "render",
        "--particles",
        &s.str("nan.npy"),
        "--radius",
        "0.1",
        "-o",
        &out,
    ]);
    assert!(
        e.contains("nan.npy") && e.contains("particle 17") && e.contains("non-finite"),
        "{e}"
    );

    // Infinite coordinate.
    flat[3 * 17 + 1] = f32::INFINITY;
    voxless_io::write_npy_f32(&s.path("inf.npy"), &[100, 3], &flat).unwrap();
    let e = fails(&[
        "render",
        "--particles",
        &s.str("inf.npy"),
        "--radius",
        "0.1",
        "-o",
        &out,
    ]);
    assert!(e.contains("inf.npy") && e.contains("non-finite"), "{e}");

    // Zero and negative radii, globally and per particle.
    for r in ["0", "-1"] {
        let e = fails(&["render", "--particles", &good, "--radius", r, "-o", &out]);
        assert!(e.contains("radius") && e.contains("> 0"), "{e}");
    }
    let mut radii = vec![0.1f32; 100];
    radii[42] = 0.0;
    write_values(&s.path("r.npy"), &radii);
    let e = fails(&[
        "render",
        "--particles",
        &good,
        "--radii",
        &s.str("r.npy"),
        "-o",
        &out,
    ]);
    assert!(
        e.contains("r.npy") && e.contains("particle 42 has radius 0"),
        "{e}"
    );

    // Empty file and an empty array.
    std::fs::write(s.path("empty.npy"), b"").unwrap();
    let e = fails(&["render", "--particles", &s.str("empty.npy"), "-o", &out]);
    assert!(e.contains("empty.npy"), "{e}");
    voxless_io::write_npy_f32(&s.path("zero.npy"), &[0, 3], &[]).unwrap();
    let e = fails(&["render", "--particles", &s.str("zero.npy"), "-o", &out]);
    assert!(e.contains("zero.npy") && e.contains("no particles"), "{e}");

    // Mismatched lengths.
    write_values(&s.path("short.npy"), &[1.0; 99]);
    let e = fails(&[
        "render",
        "--particles",
        &good,
        "--attribute",
        &s.str("short.npy"),
        "-o",
        &out,
    ]);
    assert!(
        e.contains("short.npy") && e.contains("99") && e.contains("100"),
        "{e}"
    );

    // Wrong shape.
    voxless_io::write_npy_f32(&s.path("flat.npy"), &[300], &[0.5; 300]).unwrap();
    let e = fails(&["render", "--particles", &s.str("flat.npy"), "-o", &out]);
    assert!(e.contains("flat.npy") && e.contains("N×3"), "{e}");

    // Missing file; truncated file.
    let e = fails(&["render", "--particles", &s.str("missing.npy"), "-o", &out]);
    assert!(e.contains("missing.npy"), "{e}");
    let bytes = std::fs::read(s.path("p.npy")).unwrap();
    std::fs::write(s.path("trunc.npy"), &bytes[..bytes.len() - 7]).unwrap();
    let e = fails(&["render", "--particles", &s.str("trunc.npy"), "-o", &out]);
    assert!(e.contains("trunc.npy"), "{e}");

    // Bad settings: (flag, value, what the message must mention).
    for (flag, value, mentions) in [
        ("--kernel", "wendland", ["wendland", "cubic-spline"]),
        ("--colormap", "jet", ["jet", "viridis"]),
        ("--cluster", "32", ["cluster", "1..=16"]),
        ("--opacity", "cloudy", ["cloudy", "linear"]),
    ] {
        let e = fails(&["render", "--particles", &good, flag, value, "-o", &out]);
        assert!(
            mentions.iter().all(|m| e.contains(m)),
            "{flag} {value}: {e}"
        );
    }
    let e = fails(&["render", "-o", &out]);
    assert!(e.contains("--particles"), "{e}");
}

/// The SPH dam-break frame: with the cubic spline, radii = h and weights =
/// mass, Φ is the SPH density and its projection must conserve Σ m.
#[test]
fn dam_break_projection_conserves_mass() {
    let Some(dir) = shared_data("sph-dam-break/npy_01000") else {
        return;
    };
    let s = Scratch::new("dam");
    let f = |n: &str| dir.join(n).to_string_lossy().into_owned();
    let stderr = ok(&[
        "project",
        "--particles",
        &f("positions.npy"),
        "--radii",
        &f("h.npy"),
        "--weights",
        &f("mass.npy"),
        "--kernel",
        "cubic-spline",
        "--axis",
        "y",
        "--size",
        "400",
        "300",
        "-o",
        &s.str("col.npy"),
    ]);
    let (integral, mass) = integral_and_mass(&stderr);
    let total_mass: f64 = voxless_io::read_npy(&dir.join("mass.npy"))
        .unwrap()
        .data
        .iter()
        .sum();
    assert!(
        (mass - total_mass).abs() <= 1e-4 * total_mass,
        "kernel mass {mass} vs Σm {total_mass}"
    );
    assert!(
        (integral - total_mass).abs() <= 1e-3 * total_mass,
        "Σ column × area {integral} vs Σm {total_mass}"
    );
}

#[test]
fn time_series_renders_numbered_frames_with_fixed_ranges() {
    let s = Scratch::new("series");
    // Three frames with different particle counts and a per-frame attribute.
    for (f, n) in [(0usize, 400usize), (1, 450), (2, 380)] {
        write_positions(&s.path(&format!("step_{f}.npy")), n, 10 + f as u64);
        let attr: Vec<f32> = (0..n).map(|i| (i as f32 * 0.1 + f as f32).sin()).collect();
        write_values(&s.path(&format!("temp_{f}.npy")), &attr);
    }
    let pattern = s.str("step_%d.npy");
    let attr = s.str("temp_*.npy");
    let stderr = ok(&[
        "render",
        "--particles",
        &pattern,
        "--attribute",
        &attr,
        "--radius",
        "0.1",
        "--size",
        "32",
        "24",
        "--frames",
        "0..2",
        "-o",
        &s.str("out.png"),
    ]);
    assert!(stderr.contains("rendered 3 frames"), "{stderr}");
    let images: Vec<Vec<u8>> = (0..3)
        .map(|f| std::fs::read(s.path(&format!("out_{f:04}.png"))).unwrap())
        .collect();
    assert_ne!(images[0], images[1], "frames differ");
    // --frame N renders one frame; a printf output pattern is filled in.
    ok(&[
        "render",
        "--particles",
        &pattern,
        "--radius",
        "0.1",
        "--size",
        "32",
        "24",
        "--frame",
        "1",
        "-o",
        &s.str("one.png"),
    ]);
    assert!(s.path("one.png").exists());
    ok(&[
        "render",
        "--particles",
        &pattern,
        "--radius",
        "0.1",
        "--size",
        "16",
        "16",
        "--frames",
        "1..2",
        "-o",
        &s.str("f_%03d.png"),
    ]);
    assert!(s.path("f_001.png").exists() && s.path("f_002.png").exists());
    // A range past the data renders the frames in it, and says so.
    let e = ok(&[
        "render",
        "--particles",
        &pattern,
        "--radius",
        "0.1",
        "--size",
        "16",
        "16",
        "--frames",
        "0..5",
        "-o",
        &s.str("x.png"),
    ]);
    assert!(e.contains("frames 0, 1, 2"), "{e}");
    assert!(s.path("x_0002.png").exists() && !s.path("x_0003.png").exists());
    let e = fails(&[
        "render",
        "--particles",
        &pattern,
        "--radius",
        "0.1",
        "--frames",
        "7..9",
        "-o",
        &s.str("x.png"),
    ]);
    assert!(
        e.contains("no frame is numbered") && e.contains("0, 1, 2"),
        "{e}"
    );
}
