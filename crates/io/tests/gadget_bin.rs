//! Gadget binary snapshots: files written byte by byte here (format 1 and
//! 2, both byte orders, float64 values, 8-byte IDs, gas blocks, a 3-file
//! set), the pynbody-written file from tools/gen_gadget_binary_testdata.py
//! against pynbody's own reading of it, and broken input.

use std::io::{Cursor, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use serde_json::Value;
use voxless_io::gadget_bin::{
    gadget_binary_files, open_gadget_binary, read_gadget_binary, read_gadget_binary_from,
    sniff_gadget_binary,
};
use voxless_io::{IoError, ParticleTable, Region, SphCode};

// ---------------------------------------------------------------------------
// Writing test files.

/// A directory in the system temp dir, removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new(name: &str) -> TempDir {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!(
            "voxless-io-gadget-{}-{n}-{name}",
            std::process::id()
        ));
        std::fs::create_dir_all(&dir).expect("create temp dir");
        TempDir(dir)
    }

    fn write(&self, name: &str, bytes: &[u8]) -> PathBuf {
        let path = self.0.join(name);
        std::fs::write(&path, bytes).expect("write test file");
        path
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// What a test file holds. Particle `i` of type `t` (counting over the
/// whole snapshot from `first[t]`) has values from the functions below.
#[derive(Clone)]
struct Spec {
    npart: [u32; 6],
    /// Index of this file's first particle of each type in the snapshot.
    first: [u32; 6],
    mass_table: [f64; 6],
    total: [u64; 6],
    num_files: i32,
    flag_cooling: i32,
    box_size: f64,
    double: bool,
    long_ids: bool,
    /// Gas blocks U, RHO (NE, NH with cooling), HSML.
    gas_blocks: bool,
    /// Format 2 only: extra blocks, and gas blocks in pynbody's order.
    extras: bool,
}

impl Spec {
    fn new(npart: [u32; 6]) -> Spec {
        Spec {
            npart,
            first: [0; 6],
            mass_table: [0.0, 2.5, 0.0, 0.0, 0.0, 0.0],
            total: npart.map(u64::from),
            num_files: 1,
            flag_cooling: 0,
            box_size: 50.0,
            double: false,
            long_ids: false,
            gas_blocks: true,
            extras: false,
        }
    }

    /// (type, snapshot index) of every particle in the file, in file order.
    fn particles(&self) -> Vec<(usize, u64)> {
        (0..6)
            .flat_map(|t| {
                (0..self.npart[t]).map(move |i| (t, u64::from(self.first[t]) + u64::from(i)))
            })
            .collect()
    }

    fn gas(&self) -> Vec<u64> {
        (0..self.npart[0])
            .map(|i| u64::from(self.first[0]) + u64::from(i))
            .collect()
    }
}

fn pos(t: usize, i: u64, double: bool) -> [f64; 3] {
    let base = t as f64 * 10.0 + i as f64;
    if double {
        // Digits float32 would lose.
        [1e9 + base + 0.123_456_789, base + 1e-9, -base - 0.1]
    } else {
        [base + 0.5, base + 0.25, base + 0.125]
    }
}

fn vel(t: usize, i: u64) -> [f64; 3] {
    [t as f64 - 1.5, i as f64 * 0.5, -(i as f64)]
}

fn id(t: usize, i: u64, long: bool) -> u64 {
    let id = 1000 * t as u64 + i + 1;
    if long { id + (5u64 << 40) } else { id }
}

fn mass(t: usize, i: u64) -> f64 {
    0.5 + t as f64 + i as f64 * 0.25
}

fn gas_value(block: usize, i: u64) -> f64 {
    (block as f64 + 1.0) * 100.0 + i as f64 * 0.5
}

/// Names of the gas blocks in Gadget-2's order.
fn gas_labels(spec: &Spec) -> Vec<&'static [u8; 4]> {
    let mut labels: Vec<&[u8; 4]> = vec![b"U   ", b"RHO "];
    if spec.flag_cooling != 0 {
        labels.extend([b"NE  ", b"NH  "]);
    }
    labels.push(b"HSML");
    labels
}

struct Out {
    big: bool,
    bytes: Vec<u8>,
}

impl Out {
    fn u32(&mut self, v: u32) {
        let b = if self.big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        self.bytes.extend(b);
    }
    fn u64(&mut self, v: u64) {
        let b = if self.big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        self.bytes.extend(b);
    }
    fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    fn f32(&mut self, v: f32) {
        self.u32(v.to_bits());
    }
    /// A float in the spec's width.
    fn real(&mut self, v: f64, double: bool) {
        if double {
            self.f64(v)
        } else {
            self.f32(v as f32)
        }
    }
}

/// The 256-byte header.
fn header(spec: &Spec, big: bool) -> Vec<u8> {
    let mut h = Out {
        big,
        bytes: Vec::new(),
    };
    spec.npart.iter().for_each(|&n| h.u32(n));
    spec.mass_table.iter().for_each(|&m| h.f64(m));
    h.f64(0.25); // time
    h.f64(3.0); // redshift
    h.u32(1); // flag_sfr
    h.u32(0); // flag_feedback
    spec.total.iter().for_each(|&n| h.u32(n as u32));
    h.u32(spec.flag_cooling as u32);
    h.u32(spec.num_files as u32);
    h.f64(spec.box_size);
    h.f64(0.3);
    h.f64(0.7);
    h.f64(0.68);
    h.u32(0);
    h.u32(0);
    spec.total.iter().for_each(|&n| h.u32((n >> 32) as u32));
    h.bytes.resize(256, 0);
    h.bytes
}

/// The blocks of a file: label and data.
fn blocks(spec: &Spec, big: bool) -> Vec<([u8; 4], Vec<u8>)> {
    let d = spec.double;
    let all = spec.particles();
    let mut out = vec![(*b"HEAD", header(spec, big))];
    let mut block = |label: &[u8; 4], fill: &dyn Fn(&mut Out)| {
        let mut o = Out {
            big,
            bytes: Vec::new(),
        };
        fill(&mut o);
        out.push((*label, o.bytes));
    };
    block(b"POS ", &|o| {
        all.iter()
            .flat_map(|&(t, i)| pos(t, i, d))
            .for_each(|v| o.real(v, d))
    });
    block(b"VEL ", &|o| {
        all.iter()
            .flat_map(|&(t, i)| vel(t, i))
            .for_each(|v| o.real(v, d))
    });
    block(b"ID  ", &|o| {
        for &(t, i) in &all {
            if spec.long_ids {
                o.u64(id(t, i, true))
            } else {
                o.u32(id(t, i, false) as u32)
            }
        }
    });
    if all.iter().any(|&(t, _)| spec.mass_table[t] == 0.0) {
        block(b"MASS", &|o| {
            for &(t, i) in &all {
                if spec.mass_table[t] == 0.0 {
                    o.real(mass(t, i), d);
                }
            }
        });
    }
    if spec.gas_blocks && spec.npart[0] > 0 {
        let labels = gas_labels(spec);
        let mut order: Vec<usize> = (0..labels.len()).collect();
        if spec.extras {
            // pynbody's order: HSML before RHO.
            order = vec![0, 2, 1];
        }
        for b in order {
            block(labels[b], &|o| {
                spec.gas().iter().for_each(|&i| o.real(gas_value(b, i), d))
            });
        }
    }
    if spec.extras {
        block(b"POT ", &|o| {
            all.iter().for_each(|&(t, i)| o.f32(-(t as f32) - i as f32))
        });
        block(b"JUNK", &|o| o.bytes.extend([1, 2, 3, 4, 5]));
        block(b"SFR ", &|o| {
            spec.gas().iter().for_each(|&i| o.f32(i as f32 * 2.0))
        });
        block(b"ACCE", &|o| {
            all.iter()
                .for_each(|&(t, i)| (0..3).for_each(|c| o.f32((t * 100 + c) as f32 + i as f32)))
        });
    }
    out
}

/// A whole file in `format` (1 or 2), big-endian when `big`.
fn file_bytes(spec: &Spec, format: u8, big: bool) -> Vec<u8> {
    let mut o = Out {
        big,
        bytes: Vec::new(),
    };
    for (label, data) in blocks(spec, big) {
        if format == 2 {
            o.u32(8);
            o.bytes.extend(label);
            o.u32(data.len() as u32 + 8);
            o.u32(8);
        }
        o.u32(data.len() as u32);
        o.bytes.extend(&data);
        o.u32(data.len() as u32);
    }
    o.bytes
}

// ---------------------------------------------------------------------------
// Checking tables.

/// The table `spec`'s file(s) should give for type `t`, particles `rows` of
/// the snapshot.
fn expected(spec: &Spec, t: usize, rows: std::ops::Range<u64>) -> ParticleTable {
    let d = spec.double;
    let mut table = ParticleTable {
        positions: rows.clone().map(|i| pos(t, i, d)).collect(),
        time: Some(0.25),
        redshift: Some(3.0),
        domain: Some(([0.0; 3], [spec.box_size; 3])),
        periodic: true,
        sph: Some(voxless_io::SphConvention {
            code: SphCode::Gadget,
            kernel: None,
        }),
        ..ParticleTable::default()
    };
    let column = |f: &dyn Fn(u64) -> f64| rows.clone().map(|i| f(i) as f32).collect::<Vec<f32>>();
    let masses = if spec.mass_table[t] != 0.0 {
        column(&|_| spec.mass_table[t])
    } else {
        column(&|i| mass(t, i))
    };
    table.columns.push(("Masses".into(), masses));
    let ids = rows
        .clone()
        .map(|i| id(t, i, spec.long_ids) as f32)
        .collect();
    table.columns.push(("ParticleIDs".into(), ids));
    for (c, name) in ["vx", "vy", "vz"].iter().enumerate() {
        table
            .columns
            .push((name.to_string(), column(&|i| vel(t, i)[c])));
    }
    if t == 0 && spec.gas_blocks {
        let names = ["InternalEnergy", "Density", "SmoothingLength"];
        for (b, name) in names.iter().enumerate() {
            let b = if spec.flag_cooling != 0 && b == 2 {
                4
            } else {
                b
            };
            table
                .columns
                .push((name.to_string(), column(&|i| gas_value(b, i))));
        }
        if spec.flag_cooling != 0 {
            for (b, name) in [(2, "ElectronAbundance"), (3, "NeutralHydrogenAbundance")] {
                table
                    .columns
                    .push((name.to_string(), column(&|i| gas_value(b, i))));
            }
        }
    }
    if spec.extras {
        table
            .columns
            .push(("Potential".into(), column(&|i| -(t as f64) - i as f64)));
        if t == 0 {
            table
                .columns
                .push(("SFR".into(), column(&|i| i as f64 * 2.0)));
        }
        for (c, axis) in ["x", "y", "z"].iter().enumerate() {
            let v = column(&|i| (t * 100 + c) as f64 + i as f64);
            table.columns.push((format!("ACCE_{axis}"), v));
        }
    }
    table.derive_speed("vx", "vy", "vz");
    table
}

fn assert_table(got: &ParticleTable, want: &ParticleTable) {
    assert_eq!(got.column_names(), want.column_names());
    assert_eq!(got.positions, want.positions);
    for ((name, a), (_, b)) in got.columns.iter().zip(&want.columns) {
        assert_eq!(a, b, "column {name}");
    }
    assert_eq!(got, want);
}

fn message(e: IoError) -> String {
    e.to_string()
}

// ---------------------------------------------------------------------------
// Reading good files.

#[test]
fn format1_little_endian_every_type() {
    let dir = TempDir::new("f1");
    let spec = Spec::new([3, 4, 0, 0, 2, 0]);
    let path = dir.write("snap_000", &file_bytes(&spec, 1, false));
    let info = open_gadget_binary(&path).unwrap();
    assert_eq!(info.files, vec![path.clone()]);
    assert_eq!(
        (info.format, info.big_endian, info.double_positions),
        (1, false, false)
    );
    assert_eq!(
        info.blocks,
        ["HEAD", "POS", "VEL", "ID", "MASS", "U", "RHO", "HSML"]
    );
    assert_eq!(info.per_file, vec![[3, 4, 0, 0, 2, 0]]);
    let h = &info.header;
    assert_eq!(h.npart_total, [3, 4, 0, 0, 2, 0]);
    assert_eq!(h.mass, spec.mass_table);
    assert_eq!((h.time, h.redshift, h.box_size), (0.25, 3.0, 50.0));
    assert_eq!(
        (h.omega0, h.omega_lambda, h.hubble, h.num_files),
        (0.3, 0.7, 0.68, 1)
    );

    for t in [0, 1, 4] {
        let got = read_gadget_binary(&path, Some(t as u32), None, None).unwrap();
        assert_table(&got, &expected(&spec, t, 0..u64::from(spec.npart[t])));
    }
    // Gas by default; the mass table's constant for dark matter.
    let gas = read_gadget_binary(&path, None, None, None).unwrap();
    assert_eq!(gas.len(), 3);
    let dm = read_gadget_binary(&path, Some(1), None, None).unwrap();
    assert_eq!(dm.column("Masses").unwrap(), [2.5; 4]);

    let e = message(read_gadget_binary(&path, Some(2), None, None).unwrap_err());
    assert!(
        e.contains("no particles of type 2 (disk)") && e.contains("4 (stars) × 2"),
        "{e}"
    );
    let e = message(read_gadget_binary(&path, Some(7), None, None).unwrap_err());
    assert!(
        e.contains("no particle type 7") && e.contains("snap_000"),
        "{e}"
    );
}

#[test]
fn format2_both_byte_orders_with_extra_blocks() {
    let dir = TempDir::new("f2");
    let mut spec = Spec::new([3, 4, 0, 0, 2, 0]);
    spec.extras = true;
    for big in [false, true] {
        let bytes = file_bytes(&spec, 2, big);
        let path = dir.write(if big { "be" } else { "le" }, &bytes);
        let info = open_gadget_binary(&path).unwrap();
        assert_eq!((info.format, info.big_endian), (2, big));
        let blocks = [
            "HEAD", "POS", "VEL", "ID", "MASS", "U", "HSML", "RHO", "POT", "JUNK",
        ];
        assert_eq!(info.blocks[..10], blocks);
        assert_eq!(info.blocks[10..], ["SFR", "ACCE"]);
        for t in [0, 1, 4] {
            let want = expected(&spec, t, 0..u64::from(spec.npart[t]));
            assert_table(
                &read_gadget_binary(&path, Some(t as u32), None, None).unwrap(),
                &want,
            );
            let got = read_gadget_binary_from(Cursor::new(&bytes), &path, Some(t as u32));
            assert_table(&got.unwrap(), &want);
        }
    }
}

#[test]
fn float64_values_and_8_byte_ids() {
    let dir = TempDir::new("f64");
    let mut spec = Spec::new([2, 3, 0, 0, 0, 0]);
    spec.double = true;
    spec.long_ids = true;
    spec.mass_table = [0.0; 6];
    for (format, big) in [(1, false), (2, true)] {
        let path = dir.write("snap", &file_bytes(&spec, format, big));
        assert!(open_gadget_binary(&path).unwrap().double_positions);
        for t in [0, 1] {
            let got = read_gadget_binary(&path, Some(t as u32), None, None).unwrap();
            assert_table(&got, &expected(&spec, t, 0..u64::from(spec.npart[t])));
            // Exactly the float64 digits.
            let x = pos(t, 1, true)[0];
            assert_eq!(got.positions[1][0], x);
            assert_ne!(x as f32 as f64, x);
        }
    }
}

#[test]
fn format1_with_cooling_has_ne_and_nh_before_hsml() {
    let dir = TempDir::new("cool");
    let mut spec = Spec::new([4, 1, 0, 0, 0, 0]);
    spec.flag_cooling = 1;
    let path = dir.write("snap", &file_bytes(&spec, 1, true));
    let info = open_gadget_binary(&path).unwrap();
    assert_eq!(info.blocks[5..], ["U", "RHO", "NE", "NH", "HSML"]);
    let got = read_gadget_binary(&path, Some(0), None, None).unwrap();
    assert_table(&got, &expected(&spec, 0, 0..4));
}

#[test]
fn format1_without_gas_blocks_and_extra_records() {
    // No U/RHO/HSML; a record of another size after MASS stays unnamed.
    let dir = TempDir::new("f1x");
    let mut spec = Spec::new([2, 2, 0, 0, 0, 0]);
    spec.gas_blocks = false;
    let mut bytes = file_bytes(&spec, 1, false);
    bytes.extend(3u32.to_le_bytes());
    bytes.extend([9, 9, 9]);
    bytes.extend(3u32.to_le_bytes());
    let path = dir.write("snap", &bytes);
    let info = open_gadget_binary(&path).unwrap();
    assert_eq!(
        info.blocks,
        ["HEAD", "POS", "VEL", "ID", "MASS", "record 6"]
    );
    let got = read_gadget_binary(&path, Some(0), None, None).unwrap();
    assert_table(&got, &expected(&spec, 0, 0..2));
}

#[test]
fn memory_reader_starts_at_its_position() {
    let spec = Spec::new([3, 4, 0, 0, 2, 0]);
    let mut bytes = b"junk before".to_vec();
    bytes.extend(file_bytes(&spec, 2, false));
    let mut cursor = Cursor::new(bytes);
    cursor.seek(SeekFrom::Start(11)).unwrap();
    let got = read_gadget_binary_from(cursor, Path::new("mem"), Some(4)).unwrap();
    assert_table(&got, &expected(&spec, 4, 0..2));
}

#[test]
fn single_files_without_counts() {
    // num_files 0 and npartTotal unset, as some IC writers leave them.
    let dir = TempDir::new("zero");
    let mut spec = Spec::new([3, 4, 0, 0, 0, 0]);
    spec.num_files = 0;
    spec.total = [0; 6];
    let path = dir.write("ics.0", &file_bytes(&spec, 1, false));
    let info = open_gadget_binary(&path).unwrap();
    assert_eq!(
        (info.header.num_files, info.header.npart_total),
        (0, [3, 4, 0, 0, 0, 0])
    );
    let got = read_gadget_binary(&path, Some(1), None, None).unwrap();
    assert_table(&got, &expected(&spec, 1, 0..4));
}

#[test]
fn sniffing() {
    let spec = Spec::new([3, 4, 0, 0, 2, 0]);
    for (format, big) in [(1, false), (1, true), (2, false), (2, true)] {
        let bytes = file_bytes(&spec, format, big);
        assert!(
            sniff_gadget_binary(&bytes[..512]),
            "format {format} big {big}"
        );
        assert!(!sniff_gadget_binary(&bytes[..100]));
    }
    assert!(!sniff_gadget_binary(b"\x93NUMPY\x01\x00"));
    assert!(!sniff_gadget_binary(&[0u8; 512]));
    assert!(!sniff_gadget_binary(b""));
}

// ---------------------------------------------------------------------------
// Several files.

/// Writes `stem.0` … `stem.2` with the particles split unevenly (file 1
/// has no gas, so its format-1 blocks stop after MASS); returns the spec of
/// the whole snapshot and the stem.
fn three_files(dir: &TempDir, format: u8) -> (Spec, PathBuf) {
    let counts = [[2, 3, 0, 0, 0, 0], [0, 4, 0, 0, 1, 0], [3, 2, 0, 0, 2, 0]];
    let mut whole = Spec::new([5, 9, 0, 0, 3, 0]);
    whole.num_files = 3;
    let mut first = [0u32; 6];
    for (k, npart) in counts.iter().enumerate() {
        let spec = Spec {
            npart: *npart,
            first,
            ..whole.clone()
        };
        dir.write(&format!("snap_033.{k}"), &file_bytes(&spec, format, false));
        for t in 0..6 {
            first[t] += npart[t];
        }
    }
    (whole, dir.0.join("snap_033"))
}

#[test]
fn three_files_read_as_one_snapshot() {
    for format in [1, 2] {
        let dir = TempDir::new("set");
        let (spec, stem) = three_files(&dir, format);
        let names: Vec<PathBuf> = (0..3)
            .map(|k| dir.0.join(format!("snap_033.{k}")))
            .collect();
        for given in [
            stem.clone(),
            names[0].clone(),
            names[1].clone(),
            names[2].clone(),
        ] {
            assert_eq!(gadget_binary_files(&given).unwrap(), names);
        }
        let info = open_gadget_binary(&names[1]).unwrap();
        assert_eq!(info.files, names);
        assert_eq!(info.header.npart_total, [5, 9, 0, 0, 3, 0]);
        assert_eq!(info.per_file[1], [0, 4, 0, 0, 1, 0]);
        for t in [0, 1, 4] {
            let got = read_gadget_binary(&stem, Some(t as u32), None, None).unwrap();
            assert_table(&got, &expected(&spec, t, 0..spec.total[t]));
        }

        // Shares across file boundaries: rows n·r/k .. n·(r+1)/k.
        let mut rows = Vec::new();
        for r in 0..4 {
            let got = read_gadget_binary(&stem, Some(1), Some((r, 4)), None).unwrap();
            let (lo, hi) = (9 * r as u64 / 4, 9 * (r as u64 + 1) / 4);
            let mut want = expected(&spec, 1, lo..hi);
            want.rows = Some((lo as usize, 9));
            assert_table(&got, &want);
            rows.extend(got.positions);
        }
        assert_eq!(rows, expected(&spec, 1, 0..9).positions);

        // A region keeps the particles inside it, from every file.
        let region = Region {
            lo: [12.0, 0.0, 0.0],
            hi: [16.0, 100.0, 100.0],
            pad: 0.25,
            period: None,
        };
        let got = read_gadget_binary(&stem, Some(1), None, Some(&region)).unwrap();
        let all = expected(&spec, 1, 0..9);
        let keep: Vec<bool> = all.positions.iter().map(|p| region.contains(*p)).collect();
        assert_eq!(keep.iter().filter(|k| **k).count(), 4); // x = 12.5 … 15.5
        let mut want = all.clone();
        want.positions = all
            .positions
            .iter()
            .zip(&keep)
            .filter(|x| *x.1)
            .map(|x| *x.0)
            .collect();
        for (_, v) in &mut want.columns {
            *v = v.iter().zip(&keep).filter(|x| *x.1).map(|x| *x.0).collect();
        }
        assert_table(&got, &want);
        // Both: the share (rows 4..9), then the region; rows is then None.
        let got = read_gadget_binary(&stem, Some(1), Some((1, 2)), Some(&region)).unwrap();
        assert_eq!(got.rows, None);
        let second_half = expected(&spec, 1, 4..9).positions;
        let inside: Vec<[f64; 3]> = second_half
            .into_iter()
            .filter(|p| region.contains(*p))
            .collect();
        assert_eq!(inside.len(), 2);
        assert_eq!(got.positions, inside);
    }
}

#[test]
fn broken_sets_are_errors() {
    let dir = TempDir::new("broken-set");
    let (spec, stem) = three_files(&dir, 2);
    let file = |k: usize| dir.0.join(format!("snap_033.{k}"));

    // A missing file is named.
    let saved = std::fs::read(file(2)).unwrap();
    std::fs::remove_file(file(2)).unwrap();
    for given in [stem.clone(), file(0), file(1)] {
        let e = message(read_gadget_binary(&given, None, None, None).unwrap_err());
        assert!(e.starts_with(&file(2).display().to_string()), "{e}");
        assert!(e.contains("file 2 of the 3 files"), "{e}");
    }
    std::fs::write(file(2), &saved).unwrap();

    // Totals that do not add up.
    let mut bad = Spec {
        npart: [2, 3, 0, 0, 0, 0],
        ..spec.clone()
    };
    bad.total[1] = 10;
    std::fs::write(file(0), file_bytes(&bad, 2, false)).unwrap();
    let e = message(open_gadget_binary(&stem).unwrap_err());
    assert!(
        e.contains("npartTotal[1]") && e.contains("1 (dm) has 10") && e.contains("hold 9"),
        "{e}"
    );

    // num_files 0 although three files are there.
    bad.total = spec.total;
    bad.num_files = 0;
    std::fs::write(file(0), file_bytes(&bad, 2, false)).unwrap();
    let e = message(open_gadget_binary(&stem).unwrap_err());
    assert!(
        e.contains("num_files is 0") && e.contains("snap_033.1 exists"),
        "{e}"
    );

    // Files that disagree on num_files.
    bad.num_files = 3;
    std::fs::write(file(0), file_bytes(&bad, 2, false)).unwrap();
    let mut other = Spec {
        npart: [0, 4, 0, 0, 1, 0],
        ..spec.clone()
    };
    other.num_files = 2;
    std::fs::write(file(1), file_bytes(&other, 2, false)).unwrap();
    let e = message(open_gadget_binary(&stem).unwrap_err());
    assert!(
        e.starts_with(&file(1).display().to_string()) && e.contains("num_files is 2"),
        "{e}"
    );

    // num_files above 1 for a file without a number.
    let lone = dir.write("lone", &file_bytes(&bad, 2, false));
    let e = message(open_gadget_binary(&lone).unwrap_err());
    assert!(
        e.contains("num_files is 3") && e.contains("file number"),
        "{e}"
    );

    // Neither a file nor a stem.
    let e = open_gadget_binary(&dir.0.join("nothing")).unwrap_err();
    assert!(matches!(e, IoError::Io { .. }), "{e}");
}

#[test]
fn high_word_of_the_totals_counts() {
    let dir = TempDir::new("hw");
    let mut spec = Spec::new([3, 4, 0, 0, 0, 0]);
    spec.total[1] = (1u64 << 32) + 4;
    let path = dir.write("snap", &file_bytes(&spec, 2, false));
    let e = message(open_gadget_binary(&path).unwrap_err());
    assert!(
        e.contains("has 4294967300 particles") && e.contains("holds 4"),
        "{e}"
    );
}

// ---------------------------------------------------------------------------
// Broken files.

fn read_err(bytes: &[u8], t: Option<u32>) -> String {
    message(read_gadget_binary_from(Cursor::new(bytes), Path::new("bad.gadget"), t).unwrap_err())
}

#[test]
fn broken_files_are_errors() {
    let spec = Spec::new([3, 4, 0, 0, 2, 0]);
    let f1 = file_bytes(&spec, 1, false);
    let f2 = file_bytes(&spec, 2, true);

    // Truncated inside VEL (format 1: HEAD 264 bytes, POS 9 × 12 + 8).
    let e = read_err(&f1[..264 + 116 + 50], None);
    assert!(
        e.starts_with("bad.gadget: block VEL (record 3)") && e.contains("truncated"),
        "{e}"
    );
    // Cut inside a trailing marker of format 2's POS.
    let pos_end = 16 + 264 + 16 + 4 + 108;
    let e = read_err(&f2[..pos_end + 2], None);
    assert!(e.contains("block POS") && e.contains("truncated"), "{e}");

    // Markers that disagree.
    let mut bad = f1.clone();
    bad[264 + 4 + 108] ^= 1;
    let e = read_err(&bad, None);
    assert!(
        e.contains("block POS (record 2): record markers disagree"),
        "{e}"
    );

    // A header record of 200 bytes.
    let mut h = Out {
        big: false,
        bytes: Vec::new(),
    };
    for v in [8, 0, 208, 8, 200] {
        h.u32(v);
    }
    h.bytes[4..8].copy_from_slice(b"HEAD");
    h.bytes.extend([0u8; 200]);
    h.u32(200);
    let e = read_err(&h.bytes, None);
    assert!(
        e.contains("block HEAD: the header record is 200 bytes, not 256"),
        "{e}"
    );

    // A POS block one particle short (consistent markers).
    let mut short = Spec::new([3, 4, 0, 0, 2, 0]);
    short.npart[1] = 5;
    short.total[1] = 5;
    let mut bytes = header(&short, false);
    let mut file = Out {
        big: false,
        bytes: Vec::new(),
    };
    for data in [std::mem::take(&mut bytes), vec![0u8; 12 * 9]] {
        file.u32(data.len() as u32);
        file.bytes.extend(&data);
        file.u32(data.len() as u32);
    }
    let e = read_err(&file.bytes, None);
    let want = "block POS: 108 bytes, but 10 particles (all types) × 3 values need 120 (4-byte \
                values) or 240 (8-byte values)";
    assert!(e.ends_with(want), "{e}");

    // Not Gadget at all.
    let e = read_err(b"# x y z\n1 2 3\n", None);
    assert!(e.contains("not a Gadget binary file"), "{e}");
    let e = read_err(b"ab", None);
    assert!(e.contains("not a Gadget binary file"), "{e}");

    // A wrong label record size in format 2.
    let mut bad = f2.clone();
    bad[283] = 9; // the label record after HEAD: 8 → 9 (big-endian low byte)
    let e = read_err(&bad, None);
    assert!(e.contains("after block HEAD"), "{e}");
}

#[test]
fn cut_and_flipped_files_never_panic() {
    let mut spec = Spec::new([3, 4, 0, 0, 2, 0]);
    spec.extras = true;
    let mut f64_spec = Spec::new([2, 3, 0, 0, 0, 0]);
    f64_spec.double = true;
    f64_spec.long_ids = true;
    let files = [
        file_bytes(&Spec::new([3, 4, 0, 0, 2, 0]), 1, false),
        file_bytes(&spec, 2, true),
        file_bytes(&f64_spec, 1, true),
    ];
    let read = |bytes: &[u8]| {
        for t in [None, Some(0), Some(1), Some(4), Some(9)] {
            let _ = read_gadget_binary_from(Cursor::new(bytes), Path::new("x"), t);
        }
        let _ = sniff_gadget_binary(bytes);
    };
    for bytes in &files {
        for cut in (0..bytes.len()).step_by(7) {
            read(&bytes[..cut]);
            // Cut inside the header: never a table.
            if cut < 264 {
                assert!(
                    read_gadget_binary_from(Cursor::new(&bytes[..cut]), Path::new("x"), None)
                        .is_err()
                );
            }
        }
        // Flip every byte of the header and every byte near a marker.
        let mut positions: Vec<usize> = (0..300).collect();
        positions.extend((300..bytes.len()).filter(|i| i % 4 == 0 || i % 4 == 3));
        for at in positions {
            for mask in [0xff, 0x01, 0x80] {
                let mut bad = bytes.clone();
                bad[at] ^= mask;
                read(&bad);
            }
        }
    }
}

// ---------------------------------------------------------------------------
// A file pynbody wrote.

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/gadget_bin")
        .join(name)
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

#[test]
fn pynbody_file_reads_as_pynbody_reads_it() {
    let path = fixture("pynbody_snap");
    let expected: Value =
        serde_json::from_str(&std::fs::read_to_string(fixture("expected.json")).unwrap()).unwrap();
    let info = open_gadget_binary(&path).unwrap();
    assert_eq!((info.format, info.double_positions), (2, false));
    assert_eq!(
        info.blocks,
        ["HEAD", "POS", "VEL", "ID", "MASS", "U", "HSML", "RHO"]
    );
    let h = &info.header;
    let npart: Vec<u64> = floats(&expected["npart"])
        .iter()
        .map(|&n| n as u64)
        .collect();
    assert_eq!(h.npart_total.to_vec(), npart);
    assert_eq!(h.mass.to_vec(), floats(&expected["mass_table"]));
    assert_eq!(h.time, expected["time"].as_f64().unwrap());
    assert_eq!(h.redshift, expected["redshift"].as_f64().unwrap());
    assert_eq!(h.box_size, expected["box_size"].as_f64().unwrap());
    assert_eq!(h.omega0, expected["omega0"].as_f64().unwrap());
    assert_eq!(h.omega_lambda, expected["omega_lambda"].as_f64().unwrap());
    assert_eq!(h.hubble, expected["hubble"].as_f64().unwrap());

    for t in [0u32, 1] {
        let want = &expected["types"][t.to_string()];
        let got = read_gadget_binary(&path, Some(t), None, None).unwrap();
        // The file stores float32; serde_json (without its float_roundtrip
        // feature) may parse the last bit of a float64 wrongly, which
        // rounding to float32 removes.
        let f32s = |v: &Value| floats(v).iter().map(|&x| x as f32).collect::<Vec<f32>>();
        let pos: Vec<f32> = got.positions.iter().flatten().map(|&x| x as f32).collect();
        assert_eq!(pos, f32s(&want["pos"]), "type {t} positions");
        assert!(
            got.positions
                .iter()
                .flatten()
                .all(|&x| x as f32 as f64 == x)
        );
        let vel = f32s(&want["vel"]);
        for (c, name) in ["vx", "vy", "vz"].iter().enumerate() {
            let v: Vec<f32> = vel.iter().skip(c).step_by(3).copied().collect();
            assert_eq!(got.column(name).unwrap(), v, "type {t} {name}");
        }
        assert_eq!(got.column("Masses").unwrap(), f32s(&want["mass"]));
        assert_eq!(got.column("ParticleIDs").unwrap(), f32s(&want["iord"]));
        let mut names = vec!["Masses", "ParticleIDs", "vx", "vy", "vz"];
        if t == 0 {
            assert_eq!(got.column("InternalEnergy").unwrap(), f32s(&want["u"]));
            assert_eq!(got.column("Density").unwrap(), f32s(&want["rho"]));
            assert_eq!(
                got.column("SmoothingLength").unwrap(),
                f32s(&want["smooth"])
            );
            names.extend(["InternalEnergy", "Density", "SmoothingLength"]);
        }
        names.push("speed");
        assert_eq!(got.column_names(), names);
        assert_eq!(got.domain, Some(([0.0; 3], [10.0; 3])));
        assert!(got.periodic && got.units.is_none());
        // The memory reader agrees.
        let bytes = std::fs::read(&path).unwrap();
        let from = read_gadget_binary_from(Cursor::new(bytes), &path, Some(t)).unwrap();
        assert_eq!(from, got);
    }
}
