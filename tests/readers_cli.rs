//! End-to-end: particle files of every format through `--particles`, their
//! columns as `--attribute`/`--radii`/`--weights`, multi-frame files as time
//! series, `--species`, and `voxless info`. Tiny files are written by each
//! test; the real LAMMPS melt (and, with `--features hdf5`, the PySPH and
//! JaxPM runs) in ../shared/data are used when present.

mod common;
use common::*;

use std::fmt::Write;
use std::path::Path;

/// Runs `voxless` with `args`, which must succeed; returns its stdout.
fn stdout_of(args: &[&str]) -> String {
    let (success, stderr, out) = voxless(args);
    assert!(success, "voxless {args:?} failed:\n{stderr}");
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// A LAMMPS `dump custom` with `frames` frames of `n` atoms in a box [0, 4]³,
/// columns `id type x y z vx vy vz`; types alternate 1, 2 and the atoms drift
/// from frame to frame. Rows are written in reverse id order (LAMMPS's order
/// is arbitrary; the reader sorts by id).
fn lammps_dump(n: usize, frames: usize) -> String {
    let mut rng = Lcg(7);
    let start: Vec<[f32; 3]> = (0..n)
        .map(|_| [4.0 * rng.f(), 4.0 * rng.f(), 4.0 * rng.f()])
        .collect();
    let mut text = String::new();
    for f in 0..frames {
        let step = 100 * f;
        writeln!(text, "ITEM: TIMESTEP\n{step}\nITEM: NUMBER OF ATOMS\n{n}").unwrap();
        writeln!(text, "ITEM: BOX BOUNDS pp pp pp\n0 4\n0 4\n0 4").unwrap();
        writeln!(text, "ITEM: ATOMS id type x y z vx vy vz").unwrap();
        for i in (0..n).rev() {
            let v = [0.1 * (i % 5) as f32, -0.2, 0.3 * f as f32];
            let p: Vec<f32> = (0..3)
                .map(|a| (start[i][a] + f as f32 * v[a]).rem_euclid(4.0))
                .collect();
            writeln!(
                text,
                "{} {} {} {} {} {} {} {}",
                i + 1,
                1 + i % 2,
                p[0],
                p[1],
                p[2],
                v[0],
                v[1],
                v[2]
            )
            .unwrap();
        }
    }
    text
}

fn png_size(path: &Path) -> (u32, u32) {
    let (w, h, _) = voxless_io::read_png_rgb8(path).unwrap();
    (w, h)
}

#[test]
fn lammps_dump_renders_frames_columns_and_species() {
    let s = Scratch::new("lammps");
    std::fs::write(s.path("dump.tiny"), lammps_dump(300, 2)).unwrap();
    let dump = s.str("dump.tiny");
    let small = ["--size", "32", "24", "--radius", "0.6"];
    let render = |extra: &[&str], out: &str| {
        let mut a = vec!["render", "--particles", &dump, "-o", out];
        a.extend(small);
        a.extend(extra);
        ok(&a)
    };

    // --frames writes one PNG per frame of the dump; the frames differ.
    let out = s.str("md.png");
    let log = render(&["--frames", "0..1", "--attribute", "speed"], &out);
    assert!(log.contains("rendered 2 frames"), "{log}");
    let frames: Vec<Vec<u8>> = (0..2)
        .map(|f| std::fs::read(s.path(&format!("md_{f:04}.png"))).unwrap())
        .collect();
    assert_ne!(frames[0], frames[1], "the atoms moved between frames");
    assert_eq!(png_size(&s.path("md_0001.png")), (32, 24));
    let e = fails(&[
        "render",
        "--particles",
        &dump,
        "--frames",
        "2..3",
        "-o",
        &out,
    ]);
    assert!(e.contains("frames 0, 1"), "{e}");

    // Columns by name, case-insensitively, for attribute, radii and weights.
    render(&["--frame", "1", "--attribute", "VX"], &s.str("vx.png"));
    render(
        &["--attribute", "type", "--radii", "type", "--weights", "id"],
        &s.str("cols.png"),
    );
    let e = fails(&[
        "render",
        "--particles",
        &dump,
        "--attribute",
        "temperature",
        "-o",
        &out,
    ]);
    assert!(
        e.contains("temperature") && e.contains("id, type, vx, vy, vz, speed"),
        "an unknown column lists the available ones: {e}"
    );

    // --species keeps one type; an absent type lists the ones present.
    let log = render(&["--species", "2"], &s.str("t2.png"));
    assert!(log.contains("loaded particles"), "{log}");
    let e = fails(&["render", "--particles", &dump, "--species", "3", "-o", &out]);
    assert!(e.contains("type 3") && e.contains("1, 2"), "{e}");

    // The same in a scene file, with the species as a key.
    std::fs::write(
        s.path("md.toml"),
        "[particles]\nfile = \"dump.tiny\"\nspecies = \"1\"\nattribute = \"speed\"\n\
         radius = 0.6\n[image]\nwidth = 20\nheight = 20\n",
    )
    .unwrap();
    ok(&["render", &s.str("md.toml"), "-o", &s.str("scene.png")]);
    assert_eq!(png_size(&s.path("scene.png")), (20, 20));

    // Any text file whose first line is ITEM: TIMESTEP is a dump.
    std::fs::copy(s.path("dump.tiny"), s.path("md.txt")).unwrap();
    let txt = s.str("md.txt");
    let log = ok(&[
        "render",
        "--particles",
        &txt,
        "--frame",
        "1",
        "--size",
        "16",
        "16",
        "-o",
        &s.str("txt.png"),
    ]);
    assert!(log.contains("loaded particles"), "{log}");

    // info: frames with their timesteps, count, columns with ranges, box.
    let info = stdout_of(&["info", &dump]);
    for want in [
        "LAMMPS dump, 2 frames",
        "timestep 100",
        "300 particles",
        "domain: [0, 0, 0]..[4, 4, 4]",
        "type",
        "1 .. 2",
        "speed",
    ] {
        assert!(info.contains(want), "info lacks '{want}':\n{info}");
    }
}

#[test]
fn xyz_vtp_and_particles_files_render_and_describe() {
    let s = Scratch::new("formats");
    // Renders `file` at 24×24 with `extra` flags to `out` in the scratch dir.
    let render = |file: &str, extra: &[&str], out: &str| {
        let out = s.str(out);
        let mut a = vec![
            "render",
            "--particles",
            file,
            "--size",
            "24",
            "24",
            "-o",
            &out,
        ];
        a.extend(extra);
        ok(&a)
    };

    // XYZ: two frames, species by symbol or number.
    let mut xyz = String::new();
    let mut rng = Lcg(3);
    for frame in 0..2 {
        writeln!(xyz, "40\nframe {frame}").unwrap();
        for i in 0..40 {
            let sym = if i % 4 == 0 { "O" } else { "H" };
            let (x, y, z) = (rng.f(), rng.f(), rng.f());
            writeln!(xyz, "{sym} {x} {y} {z} {}", i as f32 * 0.5).unwrap();
        }
    }
    std::fs::write(s.path("water.xyz"), xyz).unwrap();
    let file = s.str("water.xyz");
    let log = render(&file, &["--attribute", "c4", "--frames", "0..1"], "w.png");
    assert!(log.contains("rendered 2 frames"), "{log}");
    assert!(s.path("w_0000.png").exists() && s.path("w_0001.png").exists());
    for species in ["H", "2"] {
        render(&file, &["--species", species], "h.png");
    }
    let e = fails(&[
        "render",
        "--particles",
        &file,
        "--species",
        "C",
        "-o",
        "x.png",
    ]);
    assert!(e.contains("'C'") && e.contains("O, H"), "{e}");
    let info = stdout_of(&["info", &file]);
    assert!(
        info.contains("XYZ, 2 frames") && info.contains("40 particles") && info.contains("c4"),
        "{info}"
    );

    // VTK PolyData written by VTK itself.
    let vtp = s.path("points.vtp");
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/io/tests/data/vtk");
    std::fs::copy(data.join("points_ascii.vtp"), &vtp).unwrap();
    let vtp = vtp.to_string_lossy().into_owned();
    render(&vtp, &["--attribute", "temperature"], "v.png");
    let info = stdout_of(&["info", &vtp]);
    assert!(
        info.contains("64 particles") && info.contains("temperature") && info.contains("t = 1.5"),
        "{info}"
    );

    // A .vtu mesh: points, tets and arrays.
    let vtu = s.path("tets.vtu");
    std::fs::copy(data.join("tets_ascii.vtu"), &vtu).unwrap();
    let info = stdout_of(&["info", &vtu.to_string_lossy()]);
    assert!(
        info.contains("tetrahedra") && info.contains("points"),
        "{info}"
    );

    // A .particles series: an index and one binary file per timestep.
    std::fs::write(s.path("run.particles"), "0\n5\n").unwrap();
    for (step, n) in [(0, 50u64), (5, 60)] {
        let mut bytes = n.to_le_bytes().to_vec();
        for i in 0..n {
            let t = i as f32 / n as f32;
            for v in [t, (7.0 * t).fract(), (13.0 * t).fract(), t + step as f32] {
                bytes.extend(v.to_le_bytes());
            }
        }
        std::fs::write(s.path(&format!("run.particles_{step}")), bytes).unwrap();
    }
    let index = s.str("run.particles");
    render(
        &index,
        &["--attribute", "attribute", "--frames", "0..1"],
        "p.png",
    );
    assert!(s.path("p_0000.png").exists() && s.path("p_0001.png").exists());
    let info = stdout_of(&["info", &index]);
    assert!(
        info.contains("2 frames") && info.contains("60 particles") && info.contains("t = 5"),
        "{info}"
    );
}

#[test]
fn info_describes_npy_and_amr_and_rejects_unknown_formats() {
    let s = Scratch::new("info");
    write_positions(&s.path("p.npy"), 27, 5);
    let info = stdout_of(&["info", &s.str("p.npy")]);
    assert!(
        info.contains("shape (27, 3)") && info.contains("<f4") && info.contains("27 = 3³"),
        "{info}"
    );
    // ExaBricks: two cells of level 0 and one of level 1, one field.
    let cells: Vec<u8> = [[0i32, 0, 0, 0], [1, 0, 0, 0], [2, 0, 0, 1]]
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    std::fs::write(s.path("f.cells"), cells).unwrap();
    let rho: Vec<u8> = [1.0f32, 2.0, 4.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    std::fs::write(s.path("f.rho.scalars"), rho).unwrap();
    let info = stdout_of(&["info", &s.str("f.cells")]);
    assert!(
        info.contains("3 leaf cells")
            && info.contains("level 0: 2 cells")
            && info.contains("level 1: 1 cells")
            && info.contains("rho  1 .. 4")
            && info.contains("[4, 2, 2]"),
        "{info}"
    );
    std::fs::write(s.path("notes.md"), "# hello\n").unwrap();
    let e = fails(&["info", &s.str("notes.md")]);
    assert!(
        e.contains("notes.md") && e.contains(".xyz") && e.contains("fort.q"),
        "{e}"
    );
}

/// Without the feature the HDF5 tests are not built: a skip, or a failure
/// under `VOXLESS_REQUIRE_HDF5=1` (CI's feature step).
#[cfg(not(feature = "hdf5"))]
#[test]
fn hdf5_tests_need_the_feature() {
    voxless_core::testing::prerequisite(
        false,
        "VOXLESS_REQUIRE_HDF5",
        "a build with the hdf5 feature (cargo test --features hdf5)",
    );
}

#[cfg(not(feature = "hdf5"))]
#[test]
fn hdf5_without_the_feature_says_how_to_build_it() {
    let s = Scratch::new("nohdf5");
    std::fs::write(s.path("run.h5"), b"\x89HDF\r\n\x1a\nnot really").unwrap();
    for cmd in [
        vec!["render", "--particles", &s.str("run.h5"), "-o", "x.png"],
        vec!["info", &s.str("run.h5")],
    ] {
        let e = fails(&cmd);
        assert!(
            e.contains("--features hdf5") && e.contains("libhdf5-dev"),
            "{e}"
        );
    }
}

#[test]
fn real_lammps_melt() {
    let Some(dir) = shared_data("md-lammps-melt") else {
        return;
    };
    let dump = dir.join("dump.melt").to_string_lossy().into_owned();
    let info = stdout_of(&["info", &dump]);
    assert!(
        info.contains("6 frames")
            && info.contains("4000 particles")
            && info.contains("timestep 250"),
        "{info}"
    );
    let s = Scratch::new("melt");
    let log = ok(&[
        "render",
        "--particles",
        &dump,
        "--frame",
        "5",
        "--attribute",
        "id",
        "--size",
        "48",
        "48",
        "-o",
        &s.str("melt.png"),
    ]);
    assert!(log.contains("loaded particles"), "{log}");
    assert_eq!(png_size(&s.path("melt.png")), (48, 48));
}

#[cfg(feature = "hdf5")]
mod hdf5 {
    use super::*;
    use std::path::PathBuf;

    fn tiny(name: &str) -> String {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("crates/io/tests/data/hdf5")
            .join(name)
            .to_string_lossy()
            .into_owned()
    }

    #[test]
    fn pysph_frame_with_defaults_groups_and_columns() {
        let s = Scratch::new("pysph");
        let file = tiny("pysph_two_groups.hdf5");
        let out = s.str("sph.png");
        let base = ["--size", "24", "24", "-o", &out];
        let with = |extra: &[&str]| {
            let mut a = vec!["render", "--particles", &file];
            a.extend(base);
            a.extend(extra);
            ok(&a)
        };
        // h and m become radii and weights of the cubic spline, with a note;
        // the fluid array is the default and its speed a column.
        let log = with(&["--attribute", "speed"]);
        assert!(
            log.contains("cubic-spline kernel, radii = h, weights = m") && log.contains("'fluid'"),
            "{log}"
        );
        // An explicit kernel turns the defaults off.
        let log = with(&["--kernel", "gaussian3", "--radius", "0.1"]);
        assert!(!log.contains("radii = h"), "{log}");
        with(&["--group", "wall", "--attribute", "RHO"]);
        let mut a = vec!["render", "--particles", &file, "--group", "pipes"];
        a.extend(base);
        let e = fails(&a);
        assert!(e.contains("pipes") && e.contains("fluid, wall"), "{e}");
        let mut a = vec!["render", "--particles", &file, "--attribute", "nope"];
        a.extend(base);
        let e = fails(&a);
        assert!(e.contains("nope") && e.contains("rho"), "{e}");

        let info = stdout_of(&["info", &file]);
        assert!(
            info.contains("PySPH output")
                && info.contains("fluid, wall")
                && info.contains("12 particles")
                && info.contains("speed"),
            "{info}"
        );
        let info = stdout_of(&["info", &tiny("swift_snapshot.hdf5"), "--part-type", "1"]);
        assert!(info.contains("6 particles"), "{info}");
    }

    #[test]
    fn jaxpm_tessellation_from_hdf5() {
        let s = Scratch::new("jaxpm");
        let file = tiny("jaxpm_N4.h5");
        let out = s.str("web.png");
        let log = ok(&[
            "render",
            "--particles",
            &file,
            "--snapshot",
            "0",
            "--size",
            "24",
            "24",
            "-o",
            &out,
        ]);
        assert!(
            log.contains("snap_0") && log.contains("N = 4") && log.contains("phase-space"),
            "{log}"
        );
        // N and L given: they must match the file's.
        ok(&[
            "render",
            "--particles",
            &file,
            "--lagrangian",
            "4",
            "--box",
            "100",
            "--size",
            "16",
            "16",
            "-o",
            &out,
        ]);
        let e = fails(&[
            "render",
            "--particles",
            &file,
            "--lagrangian",
            "5",
            "-o",
            &out,
        ]);
        assert!(e.contains("5") && e.contains("4³"), "{e}");
        let e = fails(&[
            "render",
            "--particles",
            &file,
            "--snapshot",
            "9",
            "-o",
            &out,
        ]);
        assert!(e.contains("snap_9") && e.contains("snap_0, snap_1"), "{e}");
        // A scene's [tets] file, the last snapshot by default.
        std::fs::write(
            s.path("dm.toml"),
            format!(
                "[tets]\nfile = {file:?}\n[image]\nwidth = 16\nheight = 16\n",
                file = file
            ),
        )
        .unwrap();
        let log = ok(&["render", &s.str("dm.toml"), "-o", &s.str("scene.png")]);
        assert!(log.contains("snap_1"), "{log}");
        // Without tessellation flags a JaxPM file is its last snapshot's
        // tessellation, as the help says; particle flags do not apply.
        let log = ok(&[
            "render",
            "--particles",
            &file,
            "--size",
            "16",
            "16",
            "-o",
            &out,
        ]);
        assert!(
            log.contains("snap_1") && log.contains("phase-space"),
            "{log}"
        );
        let e = fails(&["render", "--particles", &file, "--radius", "2", "-o", &out]);
        assert!(e.contains("--radius") && e.contains("JaxPM"), "{e}");
    }

    #[test]
    fn real_pysph_directory_and_jaxpm_run() {
        let Some(dir) = shared_data("") else {
            return;
        };
        let s = Scratch::new("real-h5");
        let dam: PathBuf = dir.join("sph-dam-break");
        let dam = dam.to_string_lossy().into_owned();
        // A directory of PySPH outputs is a time series numbered by the
        // solver iterations in the names (0, 250, …, 2250).
        let log = ok(&[
            "render",
            "--particles",
            &dam,
            "--attribute",
            "speed",
            "--frames",
            "2000..2250",
            "--size",
            "32",
            "24",
            "-o",
            &s.str("dam.png"),
        ]);
        assert!(log.contains("rendered 2 frames"), "{log}");
        assert!(s.path("dam_2000.png").exists() && s.path("dam_2250.png").exists());
        let info = stdout_of(&["info", &dam]);
        assert!(
            info.contains("10 frame")
                && info.contains("frame 1750")
                && info.contains("23760 particles"),
            "{info}"
        );

        let run = dir.join("nbody-jaxpm/jaxpm_N32_L100.h5");
        let log = ok(&[
            "render",
            "--particles",
            &run.to_string_lossy(),
            "--snapshot",
            "3",
            "--size",
            "32",
            "32",
            "-o",
            &s.str("web.png"),
        ]);
        assert!(
            log.contains("N = 32") && log.contains("box L = 100"),
            "{log}"
        );
    }
}
