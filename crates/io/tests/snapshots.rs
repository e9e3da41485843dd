//! Every snapshot set of `tests/data/snapshots/` (written by pynbody,
//! swiftsimio and h5py with `tools/gen_snapshots.py`, which recorded what
//! NumPy saw in `expected.json`), read the way the CLI reads them: format
//! detection from any member, the stem or the directory, then
//! `format::read_table` per particle type. Counts, position sums and ranges,
//! sample particles and total masses must match; multi-file sets must read
//! as one snapshot; the headers (`snapshot_header`) must state the counts,
//! box, epoch and files. HDF5 sets need the `hdf5` feature.

use std::path::{Path, PathBuf};

use serde_json::Value;
use voxless_io::format::{TableOptions, read_table};
use voxless_io::{ParticleFormat, snapshot_header};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/snapshots")
}

fn expected() -> Value {
    let text = std::fs::read_to_string(root().join("expected.json")).expect("expected.json");
    serde_json::from_str(&text).expect("parse expected.json")
}

fn f(v: &Value) -> f64 {
    v.as_f64()
        .or_else(|| v.as_str().and_then(|s| s.parse().ok()))
        .unwrap_or_else(|| panic!("not a number: {v}"))
}

fn close(a: f64, b: f64, rel: f64, what: &str) {
    let tol = rel * b.abs().max(1e-30);
    assert!((a - b).abs() <= tol, "{what}: {a} vs expected {b}");
}

/// The ways a user may name the set: each member, plus the stem and the
/// directory for multi-file sets.
fn names(paths: &[PathBuf]) -> Vec<PathBuf> {
    let mut out = paths.to_vec();
    if paths.len() > 1 {
        let first = paths[0].file_name().unwrap().to_string_lossy().into_owned();
        let stem = first.split(".0").next().unwrap().to_string();
        out.push(paths[0].with_file_name(stem));
        let dir = paths[0].parent().unwrap();
        if dir
            .file_name()
            .unwrap()
            .to_string_lossy()
            .starts_with("snapdir_")
        {
            out.push(dir.to_path_buf());
        }
    }
    out
}

#[test]
fn every_set_reads_as_numpy_saw_it() {
    let exp = expected();
    let mut checked = 0;
    for (set, e) in exp["sets"].as_object().expect("sets") {
        let paths: Vec<PathBuf> = e["paths"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| root().join(p.as_str().unwrap()))
            .collect();
        let hdf5 = paths[0].extension().is_some_and(|x| x == "hdf5");
        if hdf5 && !cfg!(feature = "hdf5") {
            println!("{set}: skipped (needs the hdf5 feature)");
            continue;
        }
        let counts: Vec<u64> = e["counts"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| f(c) as u64)
            .collect();
        for name in names(&paths) {
            let format = ParticleFormat::detect(&name)
                .unwrap()
                .unwrap_or_else(|| panic!("{}: format not detected", name.display()));
            assert!(format.is_snapshot(), "{set}: {format:?}");
            let h = snapshot_header(&name, format).unwrap().expect("a header");
            assert_eq!(
                &h.counts[..counts.len().min(h.counts.len())],
                &counts[..counts.len().min(h.counts.len())],
                "{set}"
            );
            assert_eq!(h.files, paths, "{set}: the files of {}", name.display());
            if let Some(b) = e.get("box").filter(|b| !b.is_null()) {
                close(h.box_size.expect("a box")[0], f(b), 1e-12, set);
            }
            for (t, te) in e["types"].as_object().unwrap() {
                let t: u32 = t.parse().unwrap();
                let opts = TableOptions {
                    part_type: Some(t),
                    ..Default::default()
                };
                let table = read_table(&name, format, 0, &opts).unwrap().table;
                let n = f(&te["count"]) as usize;
                assert_eq!(table.len(), n, "{set} type {t}");
                for a in 0..3 {
                    let sum: f64 = table.positions.iter().map(|p| p[a]).sum();
                    close(
                        sum,
                        f(&te["pos_sum"][a]),
                        1e-9,
                        &format!("{set} type {t} Σx[{a}]"),
                    );
                    let lo = table
                        .positions
                        .iter()
                        .map(|p| p[a])
                        .fold(f64::INFINITY, f64::min);
                    close(
                        lo,
                        f(&te["pos_min"][a]),
                        1e-12,
                        &format!("{set} type {t} min[{a}]"),
                    );
                }
                let mass = table
                    .column("Masses")
                    .or(table.column("mass"))
                    .expect("masses");
                let total: f64 = mass.iter().map(|&m| m as f64).sum();
                close(
                    total,
                    f(&te["mass_total"]),
                    1e-6,
                    &format!("{set} type {t} mass"),
                );
                for s in te["samples"].as_array().into_iter().flatten() {
                    let i = f(&s["index"]) as usize;
                    for a in 0..3 {
                        close(
                            table.positions[i][a],
                            f(&s["pos"][a]),
                            1e-12,
                            &format!("{set} type {t} row {i}"),
                        );
                    }
                }
            }
            checked += 1;
        }
    }
    assert!(checked >= 5, "only {checked} sets checked");
}

#[test]
fn shares_of_a_multi_file_set_add_up_to_it() {
    let set = root().join("gadget_multi/snap_005");
    let whole = read_table(
        &set,
        ParticleFormat::GadgetBinary,
        0,
        &TableOptions {
            part_type: Some(1),
            ..Default::default()
        },
    )
    .unwrap()
    .table;
    let mut joined = Vec::new();
    for r in 0..3 {
        let part = read_table(
            &set,
            ParticleFormat::GadgetBinary,
            0,
            &TableOptions {
                part_type: Some(1),
                share: Some((r, 3)),
                ..Default::default()
            },
        )
        .unwrap()
        .table;
        joined.extend(part.positions);
    }
    assert_eq!(joined, whole.positions);
}

#[test]
fn a_missing_member_or_a_short_block_is_an_error_naming_it() {
    let dir = std::env::temp_dir().join(format!("voxless-snap-missing-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for k in [0, 2] {
        let name = format!("snap_005.{k}");
        std::fs::copy(root().join("gadget_multi").join(&name), dir.join(&name)).unwrap();
    }
    let stem = dir.join("snap_005");
    let err = read_table(
        &stem,
        ParticleFormat::GadgetBinary,
        0,
        &TableOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("snap_005.1"), "{err}");
    // A file cut short: the block and the file are named.
    let bytes = std::fs::read(root().join("gadget2_snap")).unwrap();
    let cut = dir.join("cut_snap");
    std::fs::write(&cut, &bytes[..bytes.len() * 6 / 10]).unwrap();
    let err = read_table(
        &cut,
        ParticleFormat::GadgetBinary,
        0,
        &TableOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("cut_snap"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}
