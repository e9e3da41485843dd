//! `mpirun -n K voxless …` end to end (the `mpi` feature): for K = 1…4,
//! render, project and sample give the one-process results — renders
//! within 1/255 per channel, projections within 1e-5 of the image's
//! maximum, samples bit for bit — for particles, materials, AMR cells and
//! tessellations, time series by whole frames and by space, and an error
//! on one rank ends every rank with the error said once. Skipped with a
//! notice where `mpirun` is not installed (a failure under
//! `VOXLESS_REQUIRE_MPI=1`); without the feature this file is empty, and
//! `tests/parallel.rs` says so (`mpi_tests_need_the_feature`).
#![cfg(feature = "mpi")]

mod common;

use std::path::Path;
use std::process::Command;

use common::{Lcg, Scratch, write_values};

/// Whether `mpirun` runs here (a failure instead of a skip under
/// `VOXLESS_REQUIRE_MPI=1`, which CI sets where it installed Open MPI).
fn have_mpirun() -> bool {
    let ok = Command::new("mpirun")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    voxless_core::testing::prerequisite(ok, "VOXLESS_REQUIRE_MPI", "mpirun")
}

/// `voxless args` on one process (no MPI launcher in its environment).
fn one(args: &[&str]) {
    let out = Command::new(common::bin()).args(args).output().unwrap();
    assert!(
        out.status.success(),
        "voxless {args:?}:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `mpirun -n ranks voxless args`; its stderr. Each launch gets a session
/// directory of its own: the tests run in parallel, and Open MPI launchers
/// starting at once under one user race to create the shared one ("A call
/// to mkdir was unable to create the desired directory … File exists").
fn mpi(ranks: usize, args: &[&str]) -> (bool, String) {
    static LAUNCH: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = LAUNCH.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let session = std::env::temp_dir().join(format!("voxless-ompi-{}-{n}", std::process::id()));
    std::fs::create_dir_all(&session).unwrap();
    let out = Command::new("mpirun")
        .args(["--allow-run-as-root", "--oversubscribe", "-n"])
        .arg(ranks.to_string())
        .arg(common::bin())
        .args(args)
        // Open MPI 4 (ORTE) and 5 (PRRTE) name the setting differently.
        .env("OMPI_MCA_orte_tmpdir_base", &session)
        .env("PRTE_MCA_prte_tmpdir_base", &session)
        .output()
        .unwrap();
    let _ = std::fs::remove_dir_all(&session);
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn mpi_ok(ranks: usize, args: &[&str]) -> String {
    let (ok, err) = mpi(ranks, args);
    assert!(ok, "mpirun -n {ranks} voxless {args:?}:\n{err}");
    err
}

fn png(path: &Path) -> Vec<u8> {
    voxless::io::read_png_rgb8(path).unwrap().2
}

fn npy(path: &Path) -> Vec<f64> {
    voxless::io::read_npy(path).unwrap().data
}

fn png_difference(a: &Path, b: &Path) -> u8 {
    let (a, b) = (png(a), png(b));
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(&b)
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .unwrap_or(0)
}

fn relative_difference(a: &Path, b: &Path) -> f64 {
    let (a, b) = (npy(a), npy(b));
    assert_eq!(a.len(), b.len());
    let top = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(top > 0.0, "an empty projection tests nothing");
    a.iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs() / top)
        .fold(0.0, f64::max)
}

fn same_bits(a: &Path, b: &Path) {
    let (a, b) = (npy(a), npy(b));
    assert_eq!(a.len(), b.len());
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        assert!(
            x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()),
            "value {i}: {x} vs {y}"
        );
    }
}

/// Renders, projects and samples `data` (flags) with one process and with
/// 1…4 ranks, comparing.
fn check_kind(dir: &Scratch, name: &str, data: &[&str], view: &[&str], points: &str) {
    let d = |f: &str| dir.str(&format!("{name}_{f}"));
    let with = |extra: &[&str]| -> Vec<String> {
        data.iter()
            .chain(extra)
            .map(|s| s.to_string())
            .collect::<Vec<_>>()
    };
    let args = |v: &Vec<String>| v.clone();
    let render = |out: &str| {
        let mut a = with(&["--size", "64", "48", "--spp", "2", "-o", out]);
        a.extend(view.iter().map(|s| s.to_string()));
        a
    };
    let project = |out: &str| with(&["--axis", "y", "--size", "64", "48", "-o", out]);
    // Gradients where the fields have them (a tessellation's density is
    // constant inside each tet: `--gradient` is refused there).
    let gradient = !data.contains(&"--lagrangian");
    let sample = |out: &str| {
        let mut a = with(&["--points", points, "-o", out]);
        if gradient {
            a.push("--gradient".into());
        }
        a
    };
    let run1 = |cmd: &str, a: Vec<String>| {
        let mut v = vec![cmd.to_string()];
        v.extend(a);
        one(&v.iter().map(String::as_str).collect::<Vec<_>>());
    };
    let runk = |k: usize, cmd: &str, a: Vec<String>| {
        let mut v = vec![cmd.to_string()];
        v.extend(a);
        mpi_ok(k, &v.iter().map(String::as_str).collect::<Vec<_>>())
    };
    run1("render", args(&render(&d("r1.png"))));
    run1("project", args(&project(&d("p1.npy"))));
    run1("sample", args(&sample(&d("s1.npy"))));
    for k in 1..=4 {
        let err = runk(k, "render", render(&d(&format!("r{k}k.png"))));
        assert!(err.contains(&format!("on {k} ranks")), "{err}");
        assert!(err.contains("peak memory per rank"), "{err}");
        let diff = png_difference(
            Path::new(&d("r1.png")),
            Path::new(&d(&format!("r{k}k.png"))),
        );
        assert!(diff <= 1, "{name}, {k} ranks: render differs by {diff}/255");
        runk(k, "project", project(&d(&format!("p{k}k.npy"))));
        let rel = relative_difference(
            Path::new(&d("p1.npy")),
            Path::new(&d(&format!("p{k}k.npy"))),
        );
        assert!(
            rel <= 1e-5,
            "{name}, {k} ranks: projection differs by {rel:e}"
        );
        runk(k, "sample", sample(&d(&format!("s{k}k.npy"))));
        same_bits(
            Path::new(&d("s1.npy")),
            Path::new(&d(&format!("s{k}k.npy"))),
        );
    }
}

fn write_points(dir: &Scratch, lo: f32, hi: f32) -> String {
    let mut rng = Lcg(21);
    let p: Vec<f32> = (0..3 * 200).map(|_| lo + (hi - lo) * rng.f()).collect();
    voxless_io::write_npy_f32(&dir.path("points.npy"), &[200, 3], &p).unwrap();
    dir.str("points.npy")
}

#[test]
fn particles_under_mpirun_equal_one_process() {
    if !have_mpirun() {
        return;
    }
    let dir = Scratch::new("mpi-particles");
    let n = 3000;
    let mut rng = Lcg(2);
    let pos: Vec<f32> = (0..n)
        .flat_map(|i| {
            let c = [0.3f32, 0.7][i % 2];
            [c + 0.1 * rng.normal(), 0.5 + 0.1 * rng.normal(), rng.f()]
        })
        .collect();
    voxless_io::write_npy_f32(&dir.path("pos.npy"), &[n, 3], &pos).unwrap();
    write_values(&dir.path("h.npy"), &vec![0.03; n]);
    let speed: Vec<f32> = (0..n).map(|i| (i % 11) as f32).collect();
    write_values(&dir.path("speed.npy"), &speed);
    let points = write_points(&dir, -0.1, 1.1);
    let (pos, h, speed) = (dir.str("pos.npy"), dir.str("h.npy"), dir.str("speed.npy"));
    let data = [
        "--particles",
        &pos,
        "--radii",
        &h,
        "--attribute",
        &speed,
        "--kernel",
        "cubic-spline",
    ];
    check_kind(&dir, "sph", &data, &["--opacity-scale", "40"], &points);
}

#[test]
fn amr_cells_under_mpirun_equal_one_process() {
    if !have_mpirun() {
        return;
    }
    let dir = Scratch::new("mpi-amr");
    let mut cells: Vec<[i32; 4]> = Vec::new();
    for z in (0..16).step_by(2) {
        for y in (0..16).step_by(2) {
            for x in (0..16).step_by(2) {
                if (4..10).contains(&x) && (4..10).contains(&y) {
                    for k in 0..8 {
                        cells.push([x + (k & 1), y + ((k >> 1) & 1), z + (k >> 2), 0]);
                    }
                } else {
                    cells.push([x, y, z, 1]);
                }
            }
        }
    }
    let v: Vec<f32> = cells
        .iter()
        .map(|c| 1.0 + ((c[0] * 3 + c[1] * 5 + c[2]) % 7) as f32 * 0.3)
        .collect();
    let bytes: Vec<u8> = cells
        .iter()
        .flat_map(|c| c.iter().flat_map(|x| x.to_le_bytes()))
        .collect();
    std::fs::write(dir.path("g.cells"), bytes).unwrap();
    let sc: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
    std::fs::write(dir.path("g.rho.scalars"), sc).unwrap();
    let points = write_points(&dir, -1.0, 17.0);
    let (cells, scalars) = (dir.str("g.cells"), dir.str("g.rho.scalars"));
    let data = ["--cells", &cells, "--scalars", &scalars];
    check_kind(&dir, "amr", &data, &["--opacity-scale", "0.3"], &points);
}

#[test]
fn tessellations_under_mpirun_equal_one_process() {
    if !have_mpirun() {
        return;
    }
    let dir = Scratch::new("mpi-tets");
    let n = 16;
    let l = 8.0f32;
    let mut pos = Vec::new();
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                let q = [i, j, k].map(|v| (v as f32 + 0.5) * l / n as f32);
                let s = |a: f32| 1.2 * (2.0 * std::f32::consts::PI * a / l).sin();
                pos.extend(
                    [q[0] + s(q[0]), q[1] + 0.4 * s(q[0] + q[1]), q[2]].map(|v| v.rem_euclid(l)),
                );
            }
        }
    }
    voxless_io::write_npy_f32(&dir.path("lag.npy"), &[n * n * n, 3], &pos).unwrap();
    let points = write_points(&dir, -1.0, 9.0);
    let lag = dir.str("lag.npy");
    let data = ["--particles", &lag, "--lagrangian", "16", "--box", "8"];
    check_kind(&dir, "tets", &data, &[], &points);
    // The pixel-area projection is one process's: refused by name, not
    // silently replaced by pixel centres.
    let out = dir.str("area.npy");
    let mut args = vec!["project"];
    args.extend(data);
    args.extend(["--pixels", "area", "--size", "32", "32", "-o", &out]);
    let (ok, err) = mpi(2, &args);
    assert!(!ok, "--pixels area under mpirun must fail:\n{err}");
    assert_eq!(err.matches("error:").count(), 1, "said once:\n{err}");
    assert!(err.contains("pixels") && err.contains("mpirun"), "{err}");
    assert!(!Path::new(&out).exists());
}

#[test]
fn time_series_by_frame_and_by_space_equal_one_process() {
    if !have_mpirun() {
        return;
    }
    let dir = Scratch::new("mpi-frames");
    for f in 0..4 {
        let mut rng = Lcg(30 + f);
        let pos: Vec<f32> = (0..3 * 800)
            .map(|i| rng.f() * 0.5 + 0.1 * (f as f32) * (i % 3 == 0) as u8 as f32)
            .collect();
        voxless_io::write_npy_f32(&dir.path(&format!("step_{f:02}.npy")), &[800, 3], &pos).unwrap();
    }
    let pattern = dir.str("step_%02d.npy");
    let base = [
        "--particles",
        &pattern,
        "--radius",
        "0.05",
        "--size",
        "48",
        "40",
    ];
    // The defaults hold over the frames rendered, so each mpirun series is
    // compared with one process rendering the same frames.
    // 2 ranks, 4 frames: whole frames per rank; 3 ranks, 2 frames: by space.
    for (k, range, how) in [
        (2, "0..3", "whole frames per rank"),
        (3, "0..1", "each frame decomposed"),
    ] {
        let one_out = dir.str(&format!("one{k}.png"));
        let mut a: Vec<&str> = vec!["render"];
        a.extend(base);
        a.extend(["--frames", range, "-o", &one_out]);
        one(&a);
        let out = dir.str(&format!("k{k}.png"));
        let mut a: Vec<&str> = vec!["render"];
        a.extend(base);
        a.extend(["--frames", range, "-o", &out]);
        let err = mpi_ok(k, &a);
        assert!(err.contains(how), "{err}");
        let (lo, hi) = range.split_once("..").unwrap();
        for f in lo.parse::<usize>().unwrap()..=hi.parse().unwrap() {
            let one_f = dir.path(&format!("one{k}_{f:04}.png"));
            let k_f = dir.path(&format!("k{k}_{f:04}.png"));
            let d = png_difference(&one_f, &k_f);
            assert!(d <= 1, "{k} ranks, frame {f}: {d}/255");
        }
    }
}

#[test]
fn an_error_on_one_rank_ends_every_rank_with_one_message() {
    if !have_mpirun() {
        return;
    }
    let dir = Scratch::new("mpi-error");
    let n = 600;
    let mut rng = Lcg(4);
    let pos: Vec<f32> = (0..3 * n).map(|_| rng.f()).collect();
    voxless_io::write_npy_f32(&dir.path("pos.npy"), &[n, 3], &pos).unwrap();
    let mut h = vec![0.05f32; n];
    h[590] = f32::NAN;
    write_values(&dir.path("h.npy"), &h);
    let (pos, hh, out) = (dir.str("pos.npy"), dir.str("h.npy"), dir.str("x.png"));
    let (ok, err) = mpi(
        3,
        &["render", "--particles", &pos, "--radii", &hh, "-o", &out],
    );
    assert!(!ok, "a bad radius must fail:\n{err}");
    assert_eq!(err.matches("error:").count(), 1, "said once:\n{err}");
    assert!(err.contains("h.npy") && err.contains("590"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(!Path::new(&out).exists());
}

#[test]
fn periodic_particles_with_neighbour_radii_under_mpirun_equal_one_process() {
    if !have_mpirun() {
        return;
    }
    let dir = Scratch::new("mpi-periodic");
    let n = 2000;
    let mut rng = Lcg(5);
    // A clump across the corner, so kernels and neighbours cross every face.
    let pos: Vec<f32> = (0..n)
        .flat_map(|i| {
            let s = if i % 2 == 0 { 1.0 } else { 0.1 };
            [0; 3].map(|_| (s * (rng.f() - 0.5)).rem_euclid(1.0))
        })
        .collect();
    voxless_io::write_npy_f32(&dir.path("pos.npy"), &[n, 3], &pos).unwrap();
    let speed: Vec<f32> = (0..n).map(|i| (i % 7) as f32).collect();
    write_values(&dir.path("speed.npy"), &speed);
    let points = write_points(&dir, -0.2, 1.2);
    let (pos, speed) = (dir.str("pos.npy"), dir.str("speed.npy"));
    let data = [
        "--particles",
        &pos,
        "--box",
        "1",
        "--neighbours",
        "16",
        "--attribute",
        &speed,
        "--kernel",
        "cubic-spline",
    ];
    check_kind(&dir, "periodic", &data, &["--opacity-scale", "20"], &points);
    // The radii the ranks found are one process's, in row order.
    let (out, one_h, k_h) = (dir.str("r.npy"), dir.str("h1.npy"), dir.str("h3.npy"));
    let mut a: Vec<&str> = vec!["project"];
    a.extend(data);
    a.extend([
        "--axis",
        "z",
        "--size",
        "16",
        "16",
        "-o",
        &out,
        "--save-radii",
    ]);
    let (mut a1, mut a3) = (a.clone(), a);
    a1.push(&one_h);
    one(&a1);
    a3.push(&k_h);
    mpi_ok(3, &a3);
    same_bits(Path::new(&one_h), Path::new(&k_h));
}

#[test]
fn snapshots_and_their_regions_under_mpirun_equal_one_process() {
    if !have_mpirun() {
        return;
    }
    let dir = Scratch::new("mpi-snapshots");
    let snap = |name: &str| {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/snapshots")
            .join(name)
            .to_string_lossy()
            .into_owned()
    };
    let points = write_points(&dir, 0.0, 100.0);
    // A 3-file Gadget binary set: dark matter with neighbour radii and the
    // header's masses, every periodic image.
    let multi = snap("gadget_multi/snap_005");
    let data = ["--particles", &multi, "--part-type", "dm"];
    check_kind(&dir, "gadget", &data, &["--opacity-scale", "0.2"], &points);
    // A region: every rank reads the region, then keeps its share.
    let gas = snap("gadget2_gas_snap");
    let region = [
        "--particles",
        &gas,
        "--part-type",
        "dm",
        "--region",
        "10",
        "10",
        "10",
        "60",
        "60",
        "60",
    ];
    check_kind(
        &dir,
        "region",
        &region,
        &["--opacity-scale", "0.2"],
        &points,
    );
}

/// Slices and movies under `mpirun`: a slice equals one process's bit for
/// bit; a movie's frames (a series by whole frames per rank, and a
/// turntable) equal one process's within 1/255, rank 0 encoding.
#[test]
fn slices_and_movies_under_mpirun_equal_one_process() {
    if !have_mpirun() {
        return;
    }
    let dir = Scratch::new("mpi-movies");
    for f in 0..4 {
        let mut rng = Lcg(50 + f);
        let pos: Vec<f32> = (0..3 * 600)
            .map(|i| rng.f() * 0.5 + 0.08 * (f as f32) * (i % 3 == 0) as u8 as f32)
            .collect();
        voxless_io::write_npy_f32(&dir.path(&format!("s_{f}.npy")), &[600, 3], &pos).unwrap();
    }
    let pattern = dir.str("s_%d.npy");
    let data = ["--particles", &pattern, "--radius", "0.05"];
    let (one_s, k_s) = (dir.str("one.npy"), dir.str("k.npy"));
    let slice = |out: &str| -> Vec<String> {
        ["slice"]
            .iter()
            .chain(&data)
            .chain(&[
                "--frame", "2", "--axis", "x", "--size", "40", "30", "-o", out,
            ])
            .map(|s| s.to_string())
            .collect()
    };
    one(&slice(&one_s).iter().map(String::as_str).collect::<Vec<_>>());
    mpi_ok(
        3,
        &slice(&k_s).iter().map(String::as_str).collect::<Vec<_>>(),
    );
    same_bits(Path::new(&one_s), Path::new(&k_s));
    let ffmpeg = Command::new("ffmpeg")
        .arg("-version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !voxless_core::testing::prerequisite(ffmpeg, "VOXLESS_REQUIRE_FFMPEG", "ffmpeg") {
        return;
    }
    for (k, frames, how) in [
        (2, ["--frames", "0..3"], "whole frames per rank"),
        (3, ["--turntable", "3"], "on 3 ranks"),
    ] {
        let movie = |out: &str| -> Vec<String> {
            ["render"]
                .iter()
                .chain(&data)
                .chain(&frames)
                .chain(&["--size", "40", "30", "--keep-frames", "-o", out])
                .map(|s| s.to_string())
                .collect()
        };
        let (one_m, k_m) = (
            dir.str(&format!("one{k}.gif")),
            dir.str(&format!("k{k}.gif")),
        );
        one(&movie(&one_m).iter().map(String::as_str).collect::<Vec<_>>());
        let err = mpi_ok(
            k,
            &movie(&k_m).iter().map(String::as_str).collect::<Vec<_>>(),
        );
        assert!(err.contains(how), "{err}");
        assert!(Path::new(&k_m).is_file(), "rank 0 wrote the movie");
        let n = if k == 2 { 4 } else { 3 };
        for f in 0..n {
            let name = format!("frame_{f:06}.png");
            let a = dir.path(&format!("one{k}.gif.frames")).join(&name);
            let b = dir.path(&format!("k{k}.gif.frames")).join(&name);
            let d = png_difference(&a, &b);
            assert!(d <= 1, "{k} ranks, movie frame {f}: {d}/255");
        }
    }
}
