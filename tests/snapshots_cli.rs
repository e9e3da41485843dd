//! Cosmological snapshots through the CLI, on the sets of
//! `tests/data/snapshots/` (pynbody's Gadget binary and Tipsy writers,
//! swiftsimio's SWIFT writer, h5py following the AREPO/GIZMO layouts; see
//! `tools/gen_snapshots.py`): `info` states counts, files and units; the
//! same particles in different formats project to the same map, and that
//! map holds their mass; several types render as materials; regions read
//! only what can reach them; FITS maps carry their world coordinates and
//! unit; bad input is an error naming the file.

mod common;

use std::path::PathBuf;

use common::{Scratch, fails, ok, read, voxless};

/// `voxless info FILE`'s report (stdout).
fn info(file: &str) -> String {
    let (success, stderr, out) = voxless(&["info", file]);
    assert!(success, "info {file} failed:\n{stderr}");
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn set(name: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/snapshots")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

/// The number after `key` in a CLI line ("exact ∫ field dV = 1.23e4").
fn number_after(text: &str, key: &str) -> f64 {
    let at = text
        .find(key)
        .unwrap_or_else(|| panic!("no '{key}' in:\n{text}"))
        + key.len();
    let rest = text[at..].trim_start();
    let end = rest
        .find(|c: char| !(c.is_ascii_digit() || "+-.eE".contains(c)))
        .unwrap_or(rest.len());
    rest[..end].parse().unwrap()
}

/// Projects `file` (with `extra` flags) over the box [0, L]³ along z.
fn project(dir: &Scratch, file: &str, extra: &[&str], out: &str) -> (Vec<f64>, String) {
    let l = "100";
    let mut args = vec![
        "project",
        "--particles",
        file,
        "--radius",
        "2",
        "--axis",
        "z",
        "--size",
        "48",
        "48",
        "--bounds",
        "0",
        "0",
        "0",
        l,
        l,
        l,
        "-o",
    ];
    let path = dir.str(out);
    args.push(&path);
    args.extend_from_slice(extra);
    if !extra.contains(&"--kernel") {
        args.extend(["--kernel", "cubic-spline"]);
    }
    let err = ok(&args);
    (read(&dir.path(out)).1, err)
}

#[test]
fn info_states_counts_files_box_and_units() {
    let text = info(&set("gadget_multi/snap_005.1"));
    for needle in [
        "Gadget binary (format 1",
        "files (3): snap_005.0 … snap_005.2",
        "type 0 (gas): 119 particles",
        "type 1 (dm): 512 particles",
        "box: [100, 100, 100] (periodic)",
        "units: none stated",
    ] {
        assert!(text.contains(needle), "no '{needle}' in:\n{text}");
    }
    let tipsy = info(&set("snap.tipsy"));
    assert!(
        tipsy.contains("Tipsy (big-endian)") && tipsy.contains("type 4 (stars)"),
        "{tipsy}"
    );
}

#[test]
fn the_same_particles_in_every_binary_format_project_alike_and_keep_their_mass() {
    let dir = Scratch::new("snapshots-formats");
    // The dark matter of the format-2 file (pynbody), the 3-file format-1
    // set and the big-endian file are the same particles.
    let (a, err) = project(&dir, &set("gadget2_snap"), &[], "a.npy");
    let mass = number_after(&err, "exact ∫ field dV =");
    let area = (100.0f64 / 48.0).powi(2);
    let sum: f64 = a.iter().sum::<f64>() * area;
    assert!((sum - mass).abs() <= 1e-3 * mass, "Σ {sum} vs mass {mass}");
    for (name, extra) in [
        ("gadget_multi/snap_005", &["--part-type", "dm"][..]),
        ("gadget_multi/snap_005.2", &["--part-type", "1"][..]),
        ("gadget_be_snap", &[][..]),
    ] {
        let (b, _) = project(&dir, &set(name), extra, "b.npy");
        let l1: f64 = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).sum::<f64>();
        assert!(l1 <= 1e-6 * a.iter().sum::<f64>(), "{name}: L1 {l1}");
    }
}

#[test]
fn a_given_kernel_is_used_and_the_masses_still_weigh() {
    let dir = Scratch::new("snapshots-kernel");
    let (cubic, a) = project(&dir, &set("gadget2_snap"), &[], "c.npy");
    let (wendland, b) = project(
        &dir,
        &set("gadget2_snap"),
        &["--kernel", "wendland-c2"],
        "w.npy",
    );
    // The user's kernel, not the code's: a different map of the same mass.
    assert!(
        cubic
            .iter()
            .zip(&wendland)
            .any(|(x, y)| (x - y).abs() > 1e-6 * x.abs())
    );
    let (ma, mb) = (
        number_after(&a, "exact ∫ field dV ="),
        number_after(&b, "exact ∫ field dV ="),
    );
    assert!((ma - mb).abs() <= 1e-6 * ma, "{ma} vs {mb}");
    assert!(b.contains("weights = Masses"), "{b}");
}

#[test]
fn several_types_render_as_materials() {
    let dir = Scratch::new("snapshots-materials");
    let out = dir.str("m.png");
    let err = ok(&[
        "render",
        "--particles",
        &set("gadget2_gas_snap"),
        "--part-type",
        "gas,dm",
        "--size",
        "64",
        "48",
        "-o",
        &out,
    ]);
    assert!(
        err.contains("material 'gas'") && err.contains("material 'dm'"),
        "{err}"
    );
    assert!(dir.path("m.png").exists());
}

#[test]
fn bad_snapshot_input_is_an_error_naming_the_file() {
    let dir = Scratch::new("snapshots-errors");
    let out = dir.str("x.npy");
    let err = fails(&[
        "project",
        "--particles",
        &set("gadget2_snap"),
        "--part-type",
        "quarks",
        "-o",
        &out,
    ]);
    assert!(
        err.contains("unknown particle type 'quarks'") && err.contains("gadget2_snap"),
        "{err}"
    );
    let err = fails(&[
        "project",
        "--particles",
        &set("gadget2_snap"),
        "--part-type",
        "stars",
        "-o",
        &out,
    ]);
    assert!(err.contains("no particles of type 4 (stars)"), "{err}");
    let err = fails(&[
        "project",
        "--particles",
        &set("gadget2_snap"),
        "--no-box",
        "--region",
        "200",
        "200",
        "200",
        "300",
        "300",
        "300",
        "-o",
        &out,
    ]);
    assert!(
        err.contains("no particle of the snapshot can reach it"),
        "{err}"
    );
    let err = fails(&["project", "--particles", &dir.str("snap_009"), "-o", &out]);
    assert!(err.contains("snap_009"), "{err}");
    let err = fails(&[
        "project",
        "--particles",
        &set("gadget2_snap"),
        "--region",
        "1",
        "1",
        "1",
        "0",
        "2",
        "2",
        "-o",
        &out,
    ]);
    assert!(err.contains("particles.region"), "{err}");
}

#[test]
fn a_region_keeps_what_reaches_it_and_projects_the_same_inside() {
    let dir = Scratch::new("snapshots-region");
    // The slab through the middle of the box along z is the whole box in z,
    // so the box stays periodic and pixels inside the region see everything.
    let region = ["--region", "30", "30", "0", "70", "70", "100"];
    let (whole, _) = project(
        &dir,
        &set("gadget2_gas_snap"),
        &["--part-type", "dm"],
        "w.npy",
    );
    let mut extra = vec!["--part-type", "dm"];
    extra.extend_from_slice(&region);
    let (cut, err) = project(&dir, &set("gadget2_gas_snap"), &extra, "c.npy");
    assert!(
        err.contains("--region:") && err.contains("particles kept"),
        "{err}"
    );
    // Pixels whose centre is inside the region: 30..70 of 100 over 48.
    let px = |x: f64| (x / 100.0 * 48.0) as usize;
    let (lo, hi) = (px(30.0) + 1, px(70.0) - 1);
    let mut checked = 0;
    for row in lo..hi {
        for col in lo..hi {
            let i = row * 48 + col;
            assert!(
                (whole[i] - cut[i]).abs() <= 1e-5 * whole[i].abs().max(1e-12),
                "pixel {row},{col}"
            );
            checked += 1;
        }
    }
    assert!(checked > 100);
    assert!(cut.iter().sum::<f64>() < whole.iter().sum::<f64>());
}

#[test]
fn fits_maps_carry_their_coordinates_and_unit() {
    let dir = Scratch::new("snapshots-fits");
    let (npy, _) = project(&dir, &set("gadget2_snap"), &[], "m.npy");
    let out = dir.str("m.fits");
    ok(&[
        "project",
        "--particles",
        &set("gadget2_snap"),
        "--kernel",
        "cubic-spline",
        "--radius",
        "2",
        "--axis",
        "z",
        "--size",
        "48",
        "48",
        "--bounds",
        "0",
        "0",
        "0",
        "100",
        "100",
        "100",
        "-o",
        &out,
    ]);
    let (cards, w, h, data) = voxless_io::fits::read_fits_image(&dir.path("m.fits")).unwrap();
    assert_eq!((w, h), (48, 48));
    let card = |k: &str| {
        cards
            .iter()
            .find(|c| c.0 == k)
            .map(|c| c.1.trim_matches(|c| c == '\'' || c == ' ').to_string())
            .unwrap_or_else(|| panic!("no {k} in {cards:?}"))
    };
    assert_eq!(card("CTYPE1"), "X");
    assert_eq!(card("CTYPE2"), "Y");
    assert!((card("CDELT1").parse::<f64>().unwrap() - 100.0 / 48.0).abs() < 1e-9);
    assert!(cards.iter().any(|c| c.0 == "BUNIT"));
    assert!(
        cards
            .iter()
            .any(|c| c.0 == "HISTORY" && c.1.contains("project"))
    );
    // FITS row 1 is the bottom of the picture, the .npy's last row.
    for row in 0..48 {
        for col in 0..48 {
            let fits = data[row * 48 + col] as f64;
            let top_down = npy[(47 - row) * 48 + col];
            assert_eq!(fits, top_down, "row {row} col {col}");
        }
    }
}

#[cfg(feature = "hdf5")]
#[test]
fn swift_cells_let_a_region_read_only_what_overlaps() {
    let dir = Scratch::new("snapshots-cells");
    let file = set("swift_snap.hdf5");
    let err = ok(&[
        "project",
        "--particles",
        &file,
        "--part-type",
        "dm",
        "--region",
        "0",
        "0",
        "0",
        "40",
        "40",
        "40",
        "--kernel",
        "cubic-spline",
        "--radius",
        "1",
        "-o",
        &dir.str("r.npy"),
    ]);
    // "--region: K of N particles kept (R read, only the cells that overlap)"
    let read_rows = number_after(&err, "kept (");
    assert!(err.contains("only the cells that overlap"), "{err}");
    assert!(read_rows < 512.0, "{err}");
    // The AREPO set by its directory: four files, units, cell radii.
    let err = ok(&[
        "project",
        "--particles",
        &set("arepo_multi/snapdir_010"),
        "-o",
        &dir.str("a.npy"),
    ]);
    assert!(
        err.contains("4 files") && err.contains("cell volumes"),
        "{err}"
    );
    assert!(err.contains("h⁻¹"), "{err}");
}

/// `project` of `file` with its defaults, streamed, against the in-memory
/// path (`--save-radii` loads the volume): the same map to f64 summation
/// order, and the log says which path ran.
fn streams_as_in_memory(dir: &Scratch, file: &str, flags: &[&str]) {
    let run = |extra: &[&str], out: &str| {
        let path = dir.str(out);
        let mut args = vec!["project", "--particles", file, "--size", "64", "48"];
        args.extend_from_slice(flags);
        args.extend_from_slice(extra);
        args.extend(["-o", &path]);
        let err = ok(&args);
        (read(&dir.path(out)).1, err)
    };
    let (a, log) = run(&[], "a.npy");
    assert!(log.contains("streamed in"), "{file}:\n{log}");
    let radii = dir.str("radii.npy");
    let (b, log) = run(&["--save-radii", &radii], "b.npy");
    assert!(!log.contains("streamed in"), "{file}:\n{log}");
    let peak = b.iter().fold(0.0f64, |m, &v| m.max(v));
    assert!(peak > 0.0, "{file}");
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() <= 1e-6 * peak, "{file}: {x} vs {y}");
    }
}

#[test]
fn binary_snapshots_with_smoothing_lengths_stream() {
    let dir = Scratch::new("snapshots-stream");
    for name in ["gadget2_gas_snap", "gadget_multi/snap_005", "snap.tipsy"] {
        streams_as_in_memory(&dir, &set(name), &[]);
    }
    // The file's box ignored: the frame and view come from the data.
    streams_as_in_memory(&dir, &set("gadget2_gas_snap"), &["--no-box", "--axis", "x"]);
}

#[cfg(feature = "hdf5")]
#[test]
fn hdf5_snapshots_with_smoothing_lengths_stream() {
    let dir = Scratch::new("snapshots-stream-hdf5");
    for name in [
        "swift_snap.hdf5",
        "gizmo_snap.hdf5",
        "arepo_multi/snapdir_010",
    ] {
        streams_as_in_memory(&dir, &set(name), &[]);
    }
}
