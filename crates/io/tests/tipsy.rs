//! Tipsy snapshots. The files in `tests/data/tipsy/` were written by
//! pynbody (`tools/gen_tipsy_testdata.py`), which also read them back into
//! `expected.json`; the other variants (native byte order, 28-byte header)
//! are made here from them byte by byte.

mod common;

use std::io::Cursor;
use std::path::{Path, PathBuf};

use common::TempFile;
use serde_json::Value;
use voxless_io::tipsy::{read_tipsy, read_tipsy_from, sniff_tipsy, tipsy_header};
use voxless_io::{IoError, ParticleTable, Region, SphCode};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/tipsy")
        .join(name)
}

fn expected() -> Value {
    let text = std::fs::read_to_string(data("expected.json")).expect("read expected.json");
    serde_json::from_str(&text).expect("parse expected.json")
}

/// Our column names paired with pynbody's field names after mass and
/// velocity.
type Fields = &'static [(&'static str, &'static str)];

/// The file's arrays: (part type, pynbody family, fields).
const ARRAYS: [(u32, &str, Fields); 3] = [
    (
        0,
        "gas",
        &[
            ("rho", "rho"),
            ("temp", "temp"),
            ("hsmooth", "eps"),
            ("metals", "metals"),
            ("phi", "phi"),
        ],
    ),
    (1, "dm", &[("eps", "eps"), ("phi", "phi")]),
    (
        4,
        "star",
        &[
            ("metals", "metals"),
            ("tform", "tform"),
            ("eps", "eps"),
            ("phi", "phi"),
        ],
    ),
];

/// Values stored as their shortest exact text (serde_json's default
/// number parsing may round the last bit; Rust's `parse` does not).
fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_str().expect("string").parse().expect("number"))
        .collect()
}

/// Checks `t` against pynbody's reading of `family` exactly (float32
/// columns equal, positions equal as float64).
fn check_against(t: &ParticleTable, expect: &Value, family: &str, tail: &[(&str, &str)]) {
    let e = &expect[family];
    let pos: Vec<[f64; 3]> = e["pos"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            let p = floats(p);
            [p[0], p[1], p[2]]
        })
        .collect();
    assert_eq!(t.positions, pos, "{family} positions");
    let mut names = vec!["mass", "vx", "vy", "vz"];
    names.extend(tail.iter().map(|(ours, _)| *ours));
    names.push("speed");
    assert_eq!(t.column_names(), names, "{family}");
    let pairs = [("mass", "mass"), ("vx", "vx"), ("vy", "vy"), ("vz", "vz")];
    for (ours, theirs) in pairs.iter().chain(tail) {
        let want: Vec<f32> = floats(&e[*theirs]).iter().map(|&v| v as f32).collect();
        assert_eq!(t.column(ours).unwrap(), want, "{family} {ours}");
    }
    let speed = t.column("speed").unwrap();
    let (vx, vy, vz) = (
        t.column("vx").unwrap(),
        t.column("vy").unwrap(),
        t.column("vz").unwrap(),
    );
    for i in 0..t.len() {
        assert_eq!(
            speed[i],
            (vx[i] * vx[i] + vy[i] * vy[i] + vz[i] * vz[i]).sqrt()
        );
    }
}

#[test]
fn pynbody_files_read_exactly() {
    let all = expected();
    for (file, double_pos) in [("mixed.std", false), ("mixed_dpos.std", true)] {
        let path = data(file);
        let expect = &all[file];
        let h = tipsy_header(&path).unwrap();
        assert_eq!(
            (h.nsph, h.ndark, h.nstar, h.nbodies, h.ndim),
            (10, 20, 5, 35, 3)
        );
        assert!(h.big_endian && h.padded && !h.double_vel, "{file}");
        assert_eq!(h.double_pos, double_pos, "{file}");
        assert_eq!(h.time, expect["time"].as_f64().unwrap());
        for (part_type, family, tail) in ARRAYS {
            let t = read_tipsy(&path, Some(part_type), None, None).unwrap();
            check_against(&t, expect, family, tail);
            assert_eq!(t.time, Some(0.5));
            assert_eq!(
                (t.redshift, t.domain, t.periodic, t.rows),
                (None, None, false, None)
            );
            let sph = t.sph.as_ref().unwrap();
            assert_eq!((sph.code, sph.kernel.as_deref()), (SphCode::Tipsy, None));
        }
        // Without a type: gas.
        let t = read_tipsy(&path, None, None, None).unwrap();
        assert_eq!(t.len(), 10);
        assert!(t.column("hsmooth").is_some());
    }
    // Double positions keep the digits float32 would lose.
    let t = read_tipsy(&data("mixed_dpos.std"), Some(1), None, None).unwrap();
    assert!(t.positions.iter().any(|p| p[0] as f32 as f64 != p[0]));
}

/// The same file in little-endian byte order: every word of the header and
/// of the records swapped. `double_pos` says where the 8-byte words are.
fn to_native(bytes: &[u8], double_pos: bool) -> Vec<u8> {
    let mut out = bytes.to_vec();
    out[..8].reverse();
    for w in out[8..32].chunks_exact_mut(4) {
        w.reverse();
    }
    let counts = [10, 20, 5];
    let fields = [12, 9, 11];
    let mut at = 32;
    for (n, f) in counts.into_iter().zip(fields) {
        for _ in 0..n {
            let mut sizes = vec![4; f];
            if double_pos {
                sizes[1..4].fill(8);
            }
            for size in sizes {
                out[at..at + size].reverse();
                at += size;
            }
        }
    }
    assert_eq!(at, out.len());
    out
}

/// The same file with a 28-byte header (the pad bytes cut out).
fn unpadded(bytes: &[u8]) -> Vec<u8> {
    let mut out = bytes[..28].to_vec();
    out.extend_from_slice(&bytes[32..]);
    out
}

#[test]
fn native_and_unpadded_variants_read_the_same() {
    for (file, double_pos) in [("mixed.std", false), ("mixed_dpos.std", true)] {
        let bytes = std::fs::read(data(file)).unwrap();
        let native = to_native(&bytes, double_pos);
        let variants = [
            (native.clone(), false, true),
            (unpadded(&bytes), true, false),
            (unpadded(&native), false, false),
        ];
        for (variant, big, padded) in variants {
            let f = TempFile::with_bytes("variant.bin", &variant);
            let h = tipsy_header(f.path()).unwrap();
            assert_eq!(
                (h.big_endian, h.padded, h.double_pos),
                (big, padded, double_pos)
            );
            assert!(sniff_tipsy(&variant[..64], variant.len() as u64));
            for (part_type, ..) in ARRAYS {
                let want = read_tipsy(&data(file), Some(part_type), None, None).unwrap();
                let got = read_tipsy(f.path(), Some(part_type), None, None).unwrap();
                assert_eq!(
                    got, want,
                    "{file} big {big} padded {padded} type {part_type}"
                );
                let mem = read_tipsy_from(Cursor::new(&variant), f.path(), Some(part_type));
                assert_eq!(mem.unwrap(), want);
            }
        }
    }
}

#[test]
fn memory_reads_start_at_the_readers_position() {
    let bytes = std::fs::read(data("mixed.std")).unwrap();
    let mut shifted = b"some prefix".to_vec();
    shifted.extend_from_slice(&bytes);
    let mut cursor = Cursor::new(shifted);
    cursor.set_position(11);
    let got = read_tipsy_from(cursor, Path::new("mem.std"), Some(4)).unwrap();
    assert_eq!(
        got,
        read_tipsy(&data("mixed.std"), Some(4), None, None).unwrap()
    );
}

#[test]
fn shares_make_up_the_whole_array() {
    let path = data("mixed.std");
    for (part_type, ..) in ARRAYS {
        let whole = read_tipsy(&path, Some(part_type), None, None).unwrap();
        for k in [1, 2, 3, 7, 40] {
            let mut at = 0;
            for r in 0..k {
                let p = read_tipsy(&path, Some(part_type), Some((r, k)), None).unwrap();
                assert_eq!(p.rows, Some((at, whole.len())), "type {part_type} {r}/{k}");
                assert_eq!(p.positions[..], whole.positions[at..at + p.len()]);
                for ((name, values), (wname, w)) in p.columns.iter().zip(&whole.columns) {
                    assert_eq!(name, wname);
                    assert_eq!(values[..], w[at..at + p.len()], "{name}");
                }
                at += p.len();
            }
            assert_eq!(at, whole.len());
        }
    }
}

#[test]
fn regions_keep_the_particles_inside() {
    let path = data("mixed.std");
    let region = Region {
        lo: [-0.5, -1.0, -1.0],
        hi: [0.5, 1.0, 1.0],
        pad: 0.05,
        period: None,
    };
    for (part_type, ..) in ARRAYS {
        let whole = read_tipsy(&path, Some(part_type), None, None).unwrap();
        let keep: Vec<usize> = (0..whole.len())
            .filter(|&i| region.contains(whole.positions[i]))
            .collect();
        assert!(
            !keep.is_empty() && keep.len() < whole.len(),
            "type {part_type}"
        );
        let got = read_tipsy(&path, Some(part_type), None, Some(&region)).unwrap();
        assert_eq!(got.rows, None);
        let want: Vec<[f64; 3]> = keep.iter().map(|&i| whole.positions[i]).collect();
        assert_eq!(got.positions, want);
        for ((name, values), (_, w)) in got.columns.iter().zip(&whole.columns) {
            let want: Vec<f32> = keep.iter().map(|&i| w[i]).collect();
            assert_eq!(values, &want, "{name}");
        }
        // A share and a region: the region's particles of that share.
        let half = read_tipsy(&path, Some(part_type), Some((1, 2)), Some(&region)).unwrap();
        let second = whole.len() / 2;
        let want: Vec<[f64; 3]> = keep
            .iter()
            .filter(|&&i| i >= second)
            .map(|&i| whole.positions[i])
            .collect();
        assert_eq!((half.positions, half.rows), (want, None));
    }
}

/// A standard Tipsy file with these counts, records filled with their
/// index, in either byte order.
fn synthetic(big_endian: bool, counts: [u32; 3]) -> Vec<u8> {
    let word = |v: u32| {
        if big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let mut out = if big_endian {
        1.5f64.to_be_bytes().to_vec()
    } else {
        1.5f64.to_le_bytes().to_vec()
    };
    for v in [counts.iter().sum(), 3, counts[0], counts[1], counts[2], 0] {
        out.extend_from_slice(&word(v));
    }
    for (n, fields) in counts.into_iter().zip([12, 9, 11]) {
        for i in 0..n * fields {
            out.extend_from_slice(&word((i as f32).to_bits()));
        }
    }
    out
}

fn message(e: IoError, path: &Path) -> String {
    let text = e.to_string();
    assert!(text.contains(&path.display().to_string()), "{text}");
    text
}

#[test]
fn types_pick_the_array_and_missing_ones_are_named() {
    let bytes = synthetic(false, [0, 3, 2]);
    let f = TempFile::with_bytes("nogas.bin", &bytes);
    // No gas: the default is the first array with particles.
    let t = read_tipsy(f.path(), None, None, None).unwrap();
    assert_eq!(t.len(), 3);
    assert_eq!(t.positions[1], [10.0, 11.0, 12.0]);
    assert_eq!(t.column("phi").unwrap(), [8.0, 17.0, 26.0]);
    assert_eq!(t.time, Some(1.5));
    for wanted in [0, 2, 3, 5, 9] {
        let e = message(
            read_tipsy(f.path(), Some(wanted), None, None).unwrap_err(),
            f.path(),
        );
        assert!(
            e.contains("no particles of type") && e.contains("1 (dm) × 3"),
            "{e}"
        );
        assert!(e.contains("4 (stars) × 2"), "{e}");
    }
    // An empty file has nothing to read but is no error.
    let empty = TempFile::with_bytes("empty.bin", &synthetic(true, [0, 0, 0]));
    assert!(
        read_tipsy(empty.path(), None, None, None)
            .unwrap()
            .is_empty()
    );
}

#[test]
fn inconsistent_headers_and_sizes_are_clear_errors() {
    let good = synthetic(true, [2, 3, 1]);
    let edited = |edit: &dyn Fn(&mut Vec<u8>)| {
        let mut b = good.clone();
        edit(&mut b);
        b
    };
    let cases: [(&str, Vec<u8>, &[&str]); 6] = [
        (
            "ndim",
            edited(&|b| b[15] = 2),
            &["ndim reads 2", "ndim = 3"],
        ),
        (
            "nbodies",
            edited(&|b| b[11] = 7),
            &["nbodies = 7", "2 + 3 + 1 = 6"],
        ),
        (
            "extra",
            edited(&|b| b.push(0)),
            &["does not match", "1 bytes more"],
        ),
        (
            "short",
            edited(&|b| b.truncate(b.len() - 1)),
            &["does not match", "2 gas, 3 dark, 1 star"],
        ),
        (
            "counts",
            edited(&|b| b[19] = 200),
            &["counts do not add up"],
        ),
        (
            "tiny",
            edited(&|b| b.truncate(20)),
            &["shorter than the 28-byte header"],
        ),
    ];
    for (what, bytes, wanted) in cases {
        let f = TempFile::with_bytes("bad.bin", &bytes);
        let e = message(
            read_tipsy(f.path(), None, None, None).unwrap_err(),
            f.path(),
        );
        for w in wanted {
            assert!(e.contains(w), "{what}: {e}");
        }
        assert!(tipsy_header(f.path()).is_err());
        assert!(!sniff_tipsy(&bytes, bytes.len() as u64), "{what}");
    }
    assert!(sniff_tipsy(&good, good.len() as u64));
    assert!(!sniff_tipsy(
        b"\x93NUMPY\x01\x00 and more bytes than a header",
        1000
    ));
    // A header declaring 2^32 - 1 particles of a few bytes' file.
    let mut huge = synthetic(true, [0, 0, 0]);
    huge[8..12].copy_from_slice(&u32::MAX.to_be_bytes());
    huge[16..20].copy_from_slice(&u32::MAX.to_be_bytes());
    let f = TempFile::with_bytes("huge.bin", &huge);
    let e = message(
        read_tipsy(f.path(), None, None, None).unwrap_err(),
        f.path(),
    );
    assert!(e.contains("4294967295 gas"), "{e}");
}

/// Cut at every length, and with header bytes and record bytes flipped:
/// an error or a table, never a panic.
#[test]
fn truncated_and_corrupt_files_never_panic() {
    let bytes = std::fs::read(data("mixed.std")).unwrap();
    let name = Path::new("cut.std");
    for cut in 0..bytes.len() {
        let r = read_tipsy_from(Cursor::new(&bytes[..cut]), name, None);
        // 4 bytes short reads as a 28-byte header (with shifted records).
        assert_eq!(r.is_ok(), cut == bytes.len() - 4, "cut at {cut}");
        assert!(!sniff_tipsy(&bytes[..cut], cut as u64) || cut == bytes.len() - 4);
    }
    for at in 0..40 {
        for bit in 0..8 {
            let mut b = bytes.clone();
            b[at] ^= 1 << bit;
            for part_type in [None, Some(0), Some(1), Some(4)] {
                let _ = read_tipsy_from(Cursor::new(&b), name, part_type);
            }
            let _ = sniff_tipsy(&b, b.len() as u64);
        }
    }
    // NaN positions (all bits set in the first record's float64 x) are
    // data, read as they are.
    let mut b = std::fs::read(data("mixed_dpos.std")).unwrap();
    for first in [32, 32 + 10 * 60, 32 + 10 * 60 + 20 * 48] {
        b[first + 4..first + 12].fill(0xff);
    }
    for part_type in [0, 1, 4] {
        let t = read_tipsy_from(Cursor::new(&b), name, Some(part_type)).unwrap();
        assert!(t.positions[0][0].is_nan() && t.positions[1][0].is_finite());
    }
}
