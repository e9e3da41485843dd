//! HDF5 readers: the tiny files written by tools/gen_hdf5_testdata.py
//! against the NumPy-computed expected.json, the real PySPH and JaxPM runs in
//! ../shared/data (skipped when absent), and bad input.
#![cfg(feature = "hdf5")]

mod common;

use std::path::{Path, PathBuf};

use common::TempFile;
use serde_json::Value;
use voxless_io::{
    Hdf5Kind, IoError, NpyArray, ParticleTable, describe_hdf5, hdf5_kind, jaxpm_snapshots,
    pysph_groups, read_gadget, read_jaxpm, read_npy, read_pysph,
};

fn tiny(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/hdf5")
        .join(name)
}

fn expected() -> Value {
    let text = std::fs::read_to_string(tiny("expected.json")).expect("read expected.json");
    serde_json::from_str(&text).expect("parse expected.json")
}

/// ../shared/data, or `None` (with the notice) when it is not there.
fn shared_data() -> Option<PathBuf> {
    voxless_core::testing::shared_data("")
}

fn num(v: &Value) -> f64 {
    v.as_f64()
        .unwrap_or_else(|| panic!("expected a number, found {v}"))
}

/// An expected position; expected.json holds them rounded to `f32`.
fn triple(v: &Value) -> [f32; 3] {
    let a = v.as_array().expect("array");
    [num(&a[0]) as f32, num(&a[1]) as f32, num(&a[2]) as f32]
}

/// A read position rounded to `f32`, to compare with expected values that
/// were written in single precision (the readers keep the file's `f64`).
fn single(p: &[f64; 3]) -> [f32; 3] {
    p.map(|x| x as f32)
}

/// `speed` is a float32 sqrt of float32 squares on both sides; allow an ulp.
fn close(a: f32, b: f32) -> bool {
    (a - b).abs() <= 2.0 * f32::EPSILON * b.abs().max(f32::MIN_POSITIVE)
}

/// Checks a table against an expected.json group entry: count, column names
/// and order, first/last positions, per-axis and per-column min/max and first
/// values (exact, except `speed` within an ulp).
fn check_table(table: &ParticleTable, exp: &Value, what: &str) {
    assert_eq!(
        table.len() as u64,
        exp["count"].as_u64().unwrap(),
        "{what}: count"
    );
    let names: Vec<&str> = exp["columns"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(table.column_names(), names, "{what}: columns");
    assert_eq!(
        single(&table.positions[0]),
        triple(&exp["first_position"]),
        "{what}: first position"
    );
    assert_eq!(
        single(table.positions.last().unwrap()),
        triple(&exp["last_position"]),
        "{what}: last position"
    );
    for axis in 0..3 {
        let lo = table
            .positions
            .iter()
            .map(|p| p[axis] as f32)
            .fold(f32::INFINITY, f32::min);
        let hi = table
            .positions
            .iter()
            .map(|p| p[axis] as f32)
            .fold(f32::NEG_INFINITY, f32::max);
        assert_eq!(
            lo,
            triple(&exp["position_min"])[axis],
            "{what}: min of axis {axis}"
        );
        assert_eq!(
            hi,
            triple(&exp["position_max"])[axis],
            "{what}: max of axis {axis}"
        );
    }
    for name in names {
        let column = table.column(name).unwrap();
        assert_eq!(column.len(), table.len(), "{what}: length of {name}");
        let lo = column.iter().copied().fold(f32::INFINITY, f32::min);
        let hi = column.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        let range = exp["minmax"][name].as_array().unwrap();
        let (want_lo, want_hi) = (num(&range[0]) as f32, num(&range[1]) as f32);
        let first = num(&exp["first"][name]) as f32;
        if name == "speed" {
            assert!(
                close(lo, want_lo) && close(hi, want_hi),
                "{what}: speed range {lo}..{hi}"
            );
            assert!(close(column[0], first), "{what}: first speed {}", column[0]);
        } else {
            assert_eq!((lo, hi), (want_lo, want_hi), "{what}: range of {name}");
            assert_eq!(column[0], first, "{what}: first {name}");
        }
    }
}

/// `f64` positions equal, after rounding to `f32`, an N×3 `.npy` array
/// rounded to `f32` (the reference arrays are single precision).
fn assert_positions_eq(got: &[[f64; 3]], want: &NpyArray, what: &str) {
    assert_eq!(got.len() * 3, want.data.len(), "{what}: count");
    for (i, (p, w)) in got.iter().zip(want.data.chunks_exact(3)).enumerate() {
        assert_eq!(
            single(p),
            [w[0] as f32, w[1] as f32, w[2] as f32],
            "{what}: particle {i}"
        );
    }
}

/// `f32` positions (JaxPM keeps the file's single precision) equal, exactly,
/// to an N×3 `.npy` array rounded to `f32`.
fn assert_positions_eq_f32(got: &[[f32; 3]], want: &NpyArray, what: &str) {
    assert_eq!(got.len() * 3, want.data.len(), "{what}: count");
    for (i, (p, w)) in got.iter().zip(want.data.chunks_exact(3)).enumerate() {
        assert_eq!(
            *p,
            [w[0] as f32, w[1] as f32, w[2] as f32],
            "{what}: particle {i}"
        );
    }
}

/// The error's text, after checking that it names `path`.
fn message_naming(err: IoError, path: &Path) -> String {
    let text = err.to_string();
    assert!(
        text.contains(&path.display().to_string()),
        "error does not name the file: {text}"
    );
    text
}

#[test]
fn pysph_tiny_file() {
    let exp = &expected()["pysph"];
    let path = tiny(exp["file"].as_str().unwrap());
    assert_eq!(hdf5_kind(&path).unwrap(), Hdf5Kind::PySph);
    assert_eq!(pysph_groups(&path).unwrap(), ["fluid", "wall"]);

    let fluid = read_pysph(&path, "fluid").unwrap();
    check_table(&fluid, &exp["fluid"], "fluid");
    assert_eq!(fluid.time, Some(num(&exp["time"])));
    assert_eq!(fluid.domain, None);
    // Unstored properties (empty, stored=False) are not columns.
    assert!(fluid.column("au").is_none());

    let wall = read_pysph(&path, "wall").unwrap();
    check_table(&wall, &exp["wall"], "wall");
    assert!(wall.column("speed").is_none(), "no velocities, no speed");

    let text = message_naming(read_pysph(&path, "gas").unwrap_err(), &path);
    assert!(
        text.contains("\"gas\"") && text.contains("fluid, wall"),
        "{text}"
    );
}

#[test]
fn swift_tiny_snapshot() {
    let exp = &expected()["swift"];
    let path = tiny(exp["file"].as_str().unwrap());
    assert_eq!(hdf5_kind(&path).unwrap(), Hdf5Kind::Gadget);
    let domain = (
        triple(&exp["domain"][0]).map(f64::from),
        triple(&exp["domain"][1]).map(f64::from),
    );
    for part in ["PartType0", "PartType1"] {
        let n: u32 = part["PartType".len()..].parse().unwrap();
        let table = read_gadget(&path, n).unwrap();
        check_table(&table, &exp[part], part);
        assert_eq!(table.time, Some(num(&exp["time"])), "{part}: time");
        assert_eq!(table.domain, Some(domain), "{part}: domain");
    }
    // N×2 datasets are skipped; PartType1's masses come from MassTable.
    let gas = read_gadget(&path, 0).unwrap();
    assert!(
        gas.column_names()
            .iter()
            .all(|n| !n.starts_with("ElementMassFractions"))
    );
    let dm = read_gadget(&path, 1).unwrap();
    assert!(dm.column("Masses").unwrap().iter().all(|&m| m == 0.25));
    // The kernel SWIFT records, for the smoothing-length convention.
    assert_eq!(
        gas.sph,
        Some(voxless_io::SphConvention {
            code: voxless_io::SphCode::Swift,
            kernel: Some(exp["kernel"].as_str().unwrap().to_string()),
        })
    );

    let text = message_naming(read_gadget(&path, 4).unwrap_err(), &path);
    assert!(
        text.contains("type 4 (stars)") && text.contains("0 (gas) × 8, 1 (dm) × 6"),
        "{text}"
    );
}

#[test]
fn gadget4_tiny_snapshot_with_scalar_header() {
    let exp = &expected()["gadget4"];
    let path = tiny(exp["file"].as_str().unwrap());
    let table = read_gadget(&path, 1).unwrap();
    check_table(&table, &exp["PartType1"], "PartType1");
    assert_eq!(table.time, Some(0.5));
    assert_eq!(table.domain, Some(([0.0; 3], [10.0; 3])));
    // No HydroScheme and no SWIFT code: Gadget's support-radius convention.
    assert_eq!(table.sph.map(|s| s.code), Some(voxless_io::SphCode::Gadget));
    let text = message_naming(read_gadget(&path, 0).unwrap_err(), &path);
    assert!(text.contains("present: 1 (dm) × 5"), "{text}");
}

#[test]
fn jaxpm_tiny_run_in_lagrangian_order() {
    let exp = &expected()["jaxpm"];
    let path = tiny(exp["file"].as_str().unwrap());
    assert_eq!(hdf5_kind(&path).unwrap(), Hdf5Kind::Jaxpm);
    let scale = exp["scale_factors"].as_array().unwrap();
    for (k, want) in exp["positions"].as_array().unwrap().iter().enumerate() {
        let snap = read_jaxpm(&path, k).unwrap();
        assert_eq!(snap.n, 4);
        assert_eq!(snap.box_size, num(&exp["box_size"]));
        assert_eq!(snap.scale_factor, Some(num(&scale[k])));
        let want: Vec<[f32; 3]> = want.as_array().unwrap().iter().map(triple).collect();
        assert_eq!(snap.positions, want, "snapshot {k}");
    }
    assert_eq!(jaxpm_snapshots(&path).unwrap(), [0, 1]);
    let text = message_naming(read_jaxpm(&path, 7).unwrap_err(), &path);
    assert!(
        text.contains("snap_7") && text.contains("snap_0, snap_1"),
        "{text}"
    );

    let bad = tiny("jaxpm_bad_q.h5");
    let text = message_naming(read_jaxpm(&bad, 0).unwrap_err(), &bad);
    assert!(
        text.contains("q_index") && text.contains("permutation"),
        "{text}"
    );
}

#[test]
fn broken_pysph_groups_are_errors() {
    let path = tiny("pysph_bad.hdf5");
    let text = message_naming(read_pysph(&path, "short").unwrap_err(), &path);
    assert!(
        text.contains("particles/short/arrays/h") && text.contains("particles/short/arrays/x"),
        "length mismatch must name both datasets: {text}"
    );
    let text = message_naming(read_pysph(&path, "text").unwrap_err(), &path);
    assert!(
        text.contains("particles/text/arrays/x") && text.contains("expected numbers"),
        "{text}"
    );
    // 2^40 float64 values declared in a 6 KB file: refused, not allocated.
    let text = message_naming(read_pysph(&path, "huge").unwrap_err(), &path);
    assert!(
        text.contains("particles/huge/arrays/x") && text.contains("file can hold"),
        "{text}"
    );
}

#[test]
fn other_files_are_sniffed_and_described() {
    let path = tiny("other.h5");
    assert_eq!(hdf5_kind(&path).unwrap(), Hdf5Kind::Other);
    let text = message_naming(read_pysph(&path, "fluid").unwrap_err(), &path);
    assert!(text.contains("not a PySPH output"), "{text}");
    assert!(read_gadget(&path, 0).is_err());
    assert!(read_jaxpm(&path, 0).is_err());

    let tree = describe_hdf5(&path).unwrap();
    for needle in [
        "@title = \"not a particle file\"",
        "@flags = [true, false]",
        "meta/",
        "@version = 3",
        "@name = \"fixed-length text\"",
        "temperature  (2, 2) float64  min -2  max 4.25  (1 NaN)",
        "counts  (5,) uint64  min 1099511627776  max 1099511627780",
        "labels  (2,) string (len 2)",
        "alias -> soft link (not followed)",
    ] {
        assert!(tree.contains(needle), "missing {needle:?} in:\n{tree}");
    }
}

#[test]
fn describe_lists_layouts() {
    let tree = describe_hdf5(&tiny("swift_snapshot.hdf5")).unwrap();
    for needle in [
        "Header/",
        "@BoxSize = [1, 2, 0.5]",
        "@Time = [0.75]",
        "@Code = \"SWIFT\"",
        "PartType0/",
        "Coordinates  (8, 3) float64  min ",
        "ParticleIDs  (8,) uint64  min 1000  max 8000",
    ] {
        assert!(tree.contains(needle), "missing {needle:?} in:\n{tree}");
    }
    let tree = describe_hdf5(&tiny("pysph_two_groups.hdf5")).unwrap();
    for needle in [
        "solver_data/",
        "@t = 0.338311847553724",
        "@count = 1000",
        "@stored = false",
        "au  (0,) float32  empty",
        "[deflate(9)]",
    ] {
        assert!(tree.contains(needle), "missing {needle:?} in:\n{tree}");
    }
    let tree = describe_hdf5(&tiny("pysph_bad.hdf5")).unwrap();
    assert!(
        tree.contains("(1099511627776,) float64  (min/max not computed"),
        "{tree}"
    );
}

/// Every public function on `path` returns an error naming it (no panic).
fn all_fail(path: &Path) -> Vec<String> {
    let mut texts = vec![
        message_naming(pysph_groups(path).unwrap_err(), path),
        message_naming(read_pysph(path, "fluid").unwrap_err(), path),
        message_naming(read_gadget(path, 0).unwrap_err(), path),
        message_naming(read_jaxpm(path, 0).unwrap_err(), path),
        message_naming(hdf5_kind(path).unwrap_err(), path),
    ];
    texts.push(message_naming(describe_hdf5(path).unwrap_err(), path));
    texts
}

#[test]
fn missing_and_non_hdf5_files_are_errors() {
    let missing = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/hdf5/no-such-file.h5");
    for err in [
        read_pysph(&missing, "fluid").unwrap_err(),
        hdf5_kind(&missing).unwrap_err(),
    ] {
        assert!(matches!(err, IoError::Io { .. }), "{err:?}");
    }
    all_fail(&missing);

    let text = TempFile::with_bytes("text.h5", b"x,y,z\n1,2,3\n");
    for msg in all_fail(text.path()) {
        assert!(msg.contains("not an HDF5 file"), "{msg}");
    }
    let empty = TempFile::with_bytes("empty.h5", b"");
    all_fail(empty.path());
}

#[test]
fn truncated_files_are_errors() {
    // The first 1000 bytes of a real file when there is one, and cuts of
    // every tiny file at several lengths.
    let mut sources = vec![];
    if let Some(dir) = shared_data() {
        sources.push((
            dir.join("sph-dam-break/dam_break_3d_01000.hdf5"),
            vec![1000],
        ));
        sources.push((
            dir.join("nbody-jaxpm/jaxpm_N32_L100.h5"),
            vec![1000, 100_000],
        ));
    }
    for name in [
        "pysph_two_groups.hdf5",
        "swift_snapshot.hdf5",
        "jaxpm_N4.h5",
    ] {
        let len = std::fs::metadata(tiny(name)).unwrap().len() as usize;
        sources.push((tiny(name), vec![8, 100, 1000, len / 2, len - 1]));
    }
    for (source, cuts) in sources {
        let bytes = std::fs::read(&source).unwrap();
        for cut in cuts {
            let file = TempFile::with_bytes("truncated.h5", &bytes[..cut]);
            all_fail(file.path());
        }
    }
}

#[test]
fn real_dam_break_frame_matches_npy() {
    let Some(dir) = shared_data() else { return };
    let dam = dir.join("sph-dam-break");
    let path = dam.join("dam_break_3d_01000.hdf5");
    let fluid = read_pysph(&path, "fluid").unwrap();
    assert_eq!(fluid.len(), 23_760);
    assert!(fluid.column("h").unwrap().iter().all(|&h| h == 0.039f32));
    let t = fluid.time.unwrap();
    assert!((t - 0.338311847553724).abs() < 1e-12, "time {t}");

    let npy = |name: &str| read_npy(&dam.join("npy_01000").join(name)).unwrap();
    let positions = npy("positions.npy");
    assert_eq!(positions.shape, [23_760, 3]);
    assert_positions_eq(&fluid.positions, &positions, "dam break");
    for (file, column) in [
        ("h.npy", "h"),
        ("mass.npy", "m"),
        ("rho.npy", "rho"),
        ("speed.npy", "speed"),
    ] {
        let want = npy(file);
        let got = fluid.column(column).unwrap();
        assert_eq!(want.data.len(), got.len(), "{file}");
        for (i, (&g, &w)) in got.iter().zip(&want.data).enumerate() {
            let w = w as f32;
            let ok = if column == "speed" {
                close(g, w)
            } else {
                g == w
            };
            assert!(ok, "{column}[{i}]: read {g}, npy {w}");
        }
    }
}

#[test]
fn real_dam_break_all_frames() {
    let Some(dir) = shared_data() else { return };
    let dam = dir.join("sph-dam-break");
    let mut frames: Vec<PathBuf> = std::fs::read_dir(&dam)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "hdf5"))
        .collect();
    frames.sort();
    assert_eq!(frames.len(), 10);
    for path in &frames {
        assert_eq!(hdf5_kind(path).unwrap(), Hdf5Kind::PySph);
        assert_eq!(
            pysph_groups(path).unwrap(),
            ["boundary", "fluid", "obstacle"]
        );
        for (group, count) in [("fluid", 23_760), ("boundary", 22_506), ("obstacle", 390)] {
            let table = read_pysph(path, group).unwrap();
            assert_eq!(table.len(), count, "{} {group}", path.display());
            assert!(table.time.is_some());
            assert_eq!(table.column("speed").is_some(), group == "fluid");
        }
    }
    // The first frame stores t as the integer 0.
    let first = read_pysph(&frames[0], "fluid").unwrap();
    assert_eq!(first.time, Some(0.0));
    let tree = describe_hdf5(&frames[0]).unwrap();
    assert!(
        tree.contains("@t = 0") && tree.contains("gid  (23760,) uint32"),
        "{tree}"
    );
}

#[test]
fn real_jaxpm_matches_npy() {
    let Some(dir) = shared_data() else { return };
    let jax = dir.join("nbody-jaxpm");
    let path = jax.join("jaxpm_N64_L100.h5");
    assert_eq!(hdf5_kind(&path).unwrap(), Hdf5Kind::Jaxpm);
    let snap = read_jaxpm(&path, 3).unwrap();
    assert_eq!(
        (snap.n, snap.box_size, snap.scale_factor),
        (64, 100.0, Some(1.0))
    );
    let want = read_npy(&jax.join("npy_N64_a1/positions.npy")).unwrap();
    assert_eq!(want.shape, [64 * 64 * 64, 3]);
    assert_positions_eq_f32(&snap.positions, &want, "JaxPM N64 snap_3");
    let small = jax.join("jaxpm_N32_L100.h5");
    for k in 0..4 {
        let snap = read_jaxpm(&small, k).unwrap();
        assert_eq!((snap.n, snap.positions.len()), (32, 32 * 32 * 32));
    }
    let text = message_naming(read_jaxpm(&small, 4).unwrap_err(), &small);
    assert!(text.contains("snap_0, snap_1, snap_2, snap_3"), "{text}");
}

/// One rank's share of a parallel run: the shares' rows, in rank order, are
/// the whole table's (positions and every column, strided PySPH properties
/// and N×3 Gadget datasets included), and each says which rows it holds.
#[test]
fn shares_read_by_hyperslab_make_up_the_whole_table() {
    use voxless_io::{read_gadget_share, read_pysph_share};
    let check = |whole: &ParticleTable, parts: Vec<ParticleTable>, what: &str| {
        let mut at = 0;
        for p in &parts {
            let (first, total) = p.rows.unwrap_or_else(|| panic!("{what}: rows"));
            assert_eq!((first, total), (at, whole.len()), "{what}");
            assert_eq!(p.positions[..], whole.positions[at..at + p.len()], "{what}");
            for (name, values) in &p.columns {
                let w = whole
                    .column(name)
                    .unwrap_or_else(|| panic!("{what}: {name}"));
                assert_eq!(values[..], w[at..at + p.len()], "{what}: {name}");
            }
            assert_eq!(p.columns.len(), whole.columns.len(), "{what}");
            at += p.len();
        }
        assert_eq!(at, whole.len(), "{what}");
    };
    let pysph = tiny("pysph_two_groups.hdf5");
    let gadget = tiny("gadget4_snapshot.hdf5");
    let swift = tiny("swift_snapshot.hdf5");
    for k in [1, 2, 3, 5] {
        let whole = read_pysph(&pysph, "fluid").unwrap();
        let parts = (0..k)
            .map(|r| read_pysph_share(&pysph, "fluid", Some((r, k))).unwrap())
            .collect();
        check(&whole, parts, &format!("pysph, {k} shares"));
        for (file, part_type) in [(&gadget, 1), (&swift, 0)] {
            let whole = read_gadget(file, part_type).unwrap();
            let parts = (0..k)
                .map(|r| read_gadget_share(file, part_type, Some((r, k))).unwrap())
                .collect();
            check(&whole, parts, &format!("{}, {k} shares", file.display()));
        }
    }
}
