//! The memory variants of the readers against their path functions: on every
//! sample file (the fuzz seeds in `fuzz/corpus/`, which hold small files of
//! every layout the readers accept, and the VTK files in `tests/data/vtk/`)
//! and on corrupt versions of them (cut short, a byte changed), the variant
//! reading bytes must give exactly the result the path function gives for a
//! file with those bytes, or an error with exactly the same text.
//!
//! Each case writes the bytes to a temp file and passes that file's path as
//! the memory variant's `name`, so even the path in an error must agree.

use std::fmt::Debug;
use std::io::{Cursor, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use voxless_io::{
    IoError, lammps_frames, lammps_frames_from, particles_frames, particles_frames_from,
    read_amrclaw, read_amrclaw_from, read_csv, read_csv_from, read_exabricks, read_exabricks_bytes,
    read_lammps, read_lammps_from, read_npy, read_npy_from, read_particles_file,
    read_particles_from, read_vtk_points, read_vtk_points_bytes, read_vtu_mesh,
    read_vtu_mesh_bytes, read_xyz, read_xyz_from, write_npy_f32, write_npy_f32_to, xyz_frames,
    xyz_frames_from, xyz_species, xyz_species_from,
};

/// Format detection and the table dispatch, from paths and from bytes.
#[path = "memory/formats.rs"]
mod formats;
/// Image writers and readers over `Write`/`Read`.
#[path = "memory/images.rs"]
mod images;

/// A fresh directory in the system temp dir, removed when dropped.
pub struct TempDir(PathBuf);

impl TempDir {
    pub fn new(name: &str) -> TempDir {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!(
            "voxless-io-memory-{}-{n}-{name}",
            std::process::id()
        ));
        std::fs::create_dir_all(&dir).expect("create test dir");
        TempDir(dir)
    }

    /// Writes `bytes` to `name` inside the directory and returns its path.
    pub fn write(&self, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
        let path = self.0.join(name);
        std::fs::write(&path, bytes).expect("write test file");
        path
    }

    pub fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A sample: its name and its bytes.
pub type Sample = (String, Vec<u8>);

/// The tracked seed files of one fuzz target's corpus (libFuzzer's own
/// additions, named by their SHA-1, are left out), sorted by name.
pub fn seeds(target: &str) -> Vec<Sample> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus");
    files_in(&dir.join(target))
        .into_iter()
        .filter(|(name, _)| !(name.len() == 40 && name.bytes().all(|b| b.is_ascii_hexdigit())))
        .collect()
}

/// The files of a directory with their contents, sorted by name.
pub fn files_in(dir: &Path) -> Vec<Sample> {
    let mut files: Vec<Sample> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|entry| {
            let path = entry.expect("directory entry").path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            let bytes = std::fs::read(&path).expect("read sample");
            (name, bytes)
        })
        .collect();
    files.sort();
    assert!(!files.is_empty(), "no samples in {}", dir.display());
    files
}

/// The bytes themselves and corrupt versions of them: cut in half, cut
/// before the last byte, cut after 3 bytes, and with the middle byte
/// changed.
pub fn variants(bytes: &[u8]) -> Vec<Vec<u8>> {
    let mut out = vec![bytes.to_vec()];
    for cut in [bytes.len() / 2, bytes.len().saturating_sub(1), 3] {
        if cut < bytes.len() {
            out.push(bytes[..cut].to_vec());
        }
    }
    if !bytes.is_empty() {
        let mut flipped = bytes.to_vec();
        flipped[bytes.len() / 2] ^= 0x55;
        out.push(flipped);
    }
    out
}

/// Counts of agreeing results, to check that a test saw both kinds.
#[derive(Default, Debug)]
pub struct Tally {
    pub ok: usize,
    pub err: usize,
}

impl Tally {
    /// Checks that the path function's and the memory variant's results
    /// agree: equal values (compared through `Debug`, so NaN equals NaN),
    /// or errors with the same text.
    pub fn same<T: Debug>(
        &mut self,
        what: &str,
        path: Result<T, IoError>,
        memory: Result<T, IoError>,
    ) {
        match (&path, &memory) {
            (Ok(a), Ok(b)) => {
                assert_eq!(format!("{a:?}"), format!("{b:?}"), "{what}: values differ");
                self.ok += 1;
            }
            (Err(a), Err(b)) => {
                assert_eq!(a.to_string(), b.to_string(), "{what}: errors differ");
                self.err += 1;
            }
            _ => panic!("{what}: the path gave {path:?} but memory gave {memory:?}"),
        }
    }

    /// Both kinds of result were seen.
    pub fn check_both(&self, what: &str) {
        assert!(self.ok > 0 && self.err > 0, "{what}: {self:?}");
    }
}

#[test]
fn npy_from_reader_matches_path() {
    let dir = TempDir::new("npy");
    let mut tally = Tally::default();
    for (name, bytes) in seeds("npy") {
        for (v, bytes) in variants(&bytes).iter().enumerate() {
            let path = dir.write("case.npy", bytes);
            let what = format!("{name} variant {v}");
            tally.same(
                &what,
                read_npy(&path),
                read_npy_from(Cursor::new(bytes), &path),
            );
            // A reader reads from its position on: skip a prefix.
            let mut shifted = Cursor::new([b"junk".as_slice(), bytes].concat());
            shifted.seek(SeekFrom::Start(4)).unwrap();
            tally.same(&what, read_npy(&path), read_npy_from(shifted, &path));
        }
    }
    tally.check_both("npy");

    // An open file is a reader too.
    let path = dir.write("f.npy", &seeds("npy")[0].1);
    let file = std::fs::File::open(&path).unwrap();
    tally.same("file", read_npy(&path), read_npy_from(file, &path));
}

#[test]
fn npy_header_cannot_claim_more_than_the_bytes() {
    // A header declaring 2^40 float64 values over 16 bytes of data.
    let dict = "{'descr': '<f8', 'fortran_order': False, 'shape': (1099511627776,), }";
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(dict.len() as u16 + 1).to_le_bytes());
    bytes.extend_from_slice(dict.as_bytes());
    bytes.push(b'\n');
    bytes.extend_from_slice(&[0; 16]);
    let err = read_npy_from(Cursor::new(&bytes), Path::new("huge.npy")).unwrap_err();
    assert!(
        err.to_string()
            .starts_with("huge.npy: header declares 1099511627776 float64 values"),
        "{err}"
    );
}

#[test]
fn npy_writer_to_memory_matches_file() {
    let dir = TempDir::new("npy-write");
    let path = dir.path("w.npy");
    let data: Vec<f32> = (0..12).map(|i| i as f32 * 0.5 - 1.0).collect();
    write_npy_f32(&path, &[4, 3], &data).unwrap();
    let mut out = Vec::new();
    write_npy_f32_to(&mut out, &path, &[4, 3], &data).unwrap();
    assert_eq!(out, std::fs::read(&path).unwrap());

    // A shape that does not fit: the same error, and no file is created.
    let bad = dir.path("bad.npy");
    let from_path = write_npy_f32(&bad, &[5, 3], &data).unwrap_err();
    let from_memory = write_npy_f32_to(Vec::new(), &bad, &[5, 3], &data).unwrap_err();
    assert_eq!(from_path.to_string(), from_memory.to_string());
    assert!(!bad.exists());
}

#[test]
fn csv_from_reader_matches_path() {
    let dir = TempDir::new("csv");
    let mut tally = Tally::default();
    let mut samples = seeds("csv");
    // Rows that fail in the middle of the file.
    samples.push(("bad_row".into(), b"x,y,z\n1,2,3\n4,five,6\n".to_vec()));
    samples.push(("not_text".into(), b"x,y\n\xff\xfe,1\n".to_vec()));
    for (name, bytes) in samples {
        for (v, bytes) in variants(&bytes).iter().enumerate() {
            let path = dir.write("case.csv", bytes);
            tally.same(
                &format!("{name} variant {v}"),
                read_csv(&path),
                read_csv_from(bytes.as_slice(), &path),
            );
        }
    }
    tally.check_both("csv");
}

#[test]
fn lammps_from_reader_matches_path() {
    let dir = TempDir::new("lammps");
    let mut tally = Tally::default();
    for (name, bytes) in seeds("lammps") {
        for (v, bytes) in variants(&bytes).iter().enumerate() {
            let path = dir.write("dump.case", bytes);
            let what = format!("{name} variant {v}");
            tally.same(
                &what,
                lammps_frames(&path),
                lammps_frames_from(bytes.as_slice(), &path),
            );
            // Every frame, and the one past the end.
            let frames = lammps_frames(&path).unwrap_or(1);
            for frame in 0..=frames {
                tally.same(
                    &format!("{what} frame {frame}"),
                    read_lammps(&path, frame),
                    read_lammps_from(Cursor::new(bytes), &path, frame),
                );
            }
        }
    }
    tally.check_both("lammps");
}

#[test]
fn xyz_from_reader_matches_path() {
    let dir = TempDir::new("xyz");
    let mut tally = Tally::default();
    for (name, bytes) in seeds("xyz") {
        for (v, bytes) in variants(&bytes).iter().enumerate() {
            let path = dir.write("case.xyz", bytes);
            let what = format!("{name} variant {v}");
            tally.same(
                &what,
                xyz_frames(&path),
                xyz_frames_from(bytes.as_slice(), &path),
            );
            let frames = xyz_frames(&path).unwrap_or(1);
            for frame in 0..=frames {
                let what = format!("{what} frame {frame}");
                tally.same(
                    &what,
                    read_xyz(&path, frame),
                    read_xyz_from(Cursor::new(bytes), &path, frame),
                );
                tally.same(
                    &what,
                    xyz_species(&path, frame),
                    xyz_species_from(bytes.as_slice(), &path, frame),
                );
            }
        }
    }
    tally.check_both("xyz");
}

#[test]
fn particles_from_memory_matches_path() {
    let dir = TempDir::new("particles");
    let mut tally = Tally::default();
    // Timestep data: every seed and its variants, under an index listing
    // the timestep `0`.
    let index = dir.write("series.particles", "0\n");
    for (name, bytes) in seeds("particles") {
        for (v, bytes) in variants(&bytes).iter().enumerate() {
            let data = dir.write("series.particles_0", bytes);
            tally.same(
                &format!("{name} variant {v}"),
                read_particles_file(&index, 0),
                read_particles_from(&b"0\n"[..], &index, 0, |step| {
                    assert_eq!(step, "0");
                    Ok((data.clone(), Cursor::new(bytes)))
                }),
            );
        }
    }

    // Indexes: several timesteps (read each, and one past the end), no
    // timestep, a control character.
    let step = dir.write("many.particles_2.5", &seeds("particles")[1].1);
    dir.write("many.particles_7", &seeds("particles")[2].1);
    for (name, text) in [
        ("three", "\n2.5\n  7 \n2.5\n"),
        ("empty", "\n \n"),
        ("control", "1\n2\u{7}\n"),
        ("binary", "1\n\u{0}\u{1}\n"),
    ] {
        let index = dir.write("many.particles", text);
        tally.same(
            name,
            particles_frames(&index),
            particles_frames_from(text.as_bytes(), &index),
        );
        for frame in 0..4 {
            tally.same(
                &format!("{name} frame {frame}"),
                read_particles_file(&index, frame),
                read_particles_from(text.as_bytes(), &index, frame, |step| {
                    let path = dir.path(&format!("many.particles_{step}"));
                    let bytes = std::fs::read(&path).unwrap();
                    Ok((path, Cursor::new(bytes)))
                }),
            );
        }
    }
    assert!(step.exists());
    tally.check_both("particles");
}

#[test]
fn particles_opener_errors_pass_through() {
    let err = read_particles_from(&b"4\n"[..], Path::new("s.particles"), 0, |step| {
        Err::<(PathBuf, Cursor<Vec<u8>>), _>(IoError::format(
            "store",
            format!("no timestep {step}"),
        ))
    })
    .unwrap_err();
    assert_eq!(err.to_string(), "store: no timestep 4");
}

/// The VTK files VTK wrote, and the fuzz seeds (which add a corrupt one).
fn vtk_samples() -> Vec<Sample> {
    let mut samples = files_in(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk"));
    samples.retain(|(name, _)| name.ends_with(".vtp") || name.ends_with(".vtu"));
    samples.extend(seeds("vtk_points"));
    samples
}

#[test]
fn vtk_from_bytes_matches_path() {
    let dir = TempDir::new("vtk");
    let mut points = Tally::default();
    let mut meshes = Tally::default();
    for (name, bytes) in vtk_samples() {
        for (v, bytes) in variants(&bytes).iter().enumerate() {
            let path = dir.write("case.vtu", bytes);
            let what = format!("{name} variant {v}");
            points.same(
                &what,
                read_vtk_points(&path),
                read_vtk_points_bytes(bytes, &path),
            );
            meshes.same(
                &what,
                read_vtu_mesh(&path),
                read_vtu_mesh_bytes(bytes, &path),
            );
        }
    }
    points.check_both("vtk points");
    meshes.check_both("vtu meshes");
}

/// A fuzz seed of the `exabricks` target cut into its parts: cells, meta
/// JSON (if any) and up to three scalars parts (see
/// `fuzz/fuzz_targets/exabricks.rs`).
fn exabricks_parts(data: &[u8]) -> (Vec<u8>, Option<Vec<u8>>, Vec<Vec<u8>>) {
    let split = |d: &[u8], n: usize| {
        let (a, b) = d.split_at(n.min(d.len()));
        (a.to_vec(), b.to_vec())
    };
    let (&flags, rest) = data.split_first().expect("a seed has a flags byte");
    let (len, rest) = split(rest, 2);
    let cells_len = match *len {
        [a, b] => usize::from(u16::from_le_bytes([a, b])),
        [a] => usize::from(a),
        _ => 0,
    };
    let (cells, mut rest) = split(&rest, cells_len);
    let mut meta = None;
    if flags & 4 != 0 {
        let (len, after) = split(&rest, 1);
        let (json, after) = split(&after, len.first().map_or(0, |&b| usize::from(b)));
        meta = Some(json);
        rest = after;
    }
    let count = usize::from(flags & 3);
    let mut scalars = Vec::new();
    for i in 0..count {
        if i + 1 == count {
            scalars.push(std::mem::take(&mut rest));
        } else {
            let (part, after) = split(&rest, cells.len() / 4);
            scalars.push(part);
            rest = after;
        }
    }
    (cells, meta, scalars)
}

/// An ExaBricks case: what it is, the cells, the meta JSON and the scalars
/// parts.
struct ExaCase(String, Vec<u8>, Option<Vec<u8>>, Vec<Vec<u8>>);

/// Little-endian bytes of `int32` cells.
fn cell_bytes(cells: &[[i32; 4]]) -> Vec<u8> {
    cells
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect()
}

#[test]
fn exabricks_from_bytes_matches_path() {
    const FIELDS: [&str; 3] = ["density", "energy", "momentum_x"];
    let mut cases: Vec<ExaCase> = Vec::new();
    for (name, seed) in seeds("exabricks") {
        let (cells, meta, scalars) = exabricks_parts(&seed);
        for (v, cells) in variants(&cells).into_iter().enumerate() {
            cases.push(ExaCase(
                format!("{name} cells variant {v}"),
                cells,
                meta.clone(),
                scalars.clone(),
            ));
        }
        if let Some(meta) = &meta {
            for (v, meta) in variants(meta).into_iter().enumerate() {
                let what = format!("{name} meta variant {v}");
                cases.push(ExaCase(what, cells.clone(), Some(meta), scalars.clone()));
            }
        }
        if let Some(first) = scalars.first() {
            for (v, part) in variants(first).into_iter().enumerate() {
                let mut scalars = scalars.clone();
                scalars[0] = part;
                let what = format!("{name} scalars variant {v}");
                cases.push(ExaCase(what, cells.clone(), meta.clone(), scalars));
            }
        }
    }
    // A level out of range, and meta files of the wrong shape.
    let two = cell_bytes(&[[0, 0, 0, 0], [2, 0, 0, 31]]);
    cases.push(ExaCase("level".into(), two, None, vec![]));
    let one = cell_bytes(&[[0, 0, 0, 1]]);
    for meta in [
        r#"{"origin": [0, 0], "finest_cell_size": 1}"#,
        r#"{"origin": [0, 0, 0], "finest_cell_size": -1}"#,
        r#"{"origin": [0, 0, 0], "finest_cell_size": 1, "time": "soon"}"#,
        r#"{"origin": [1, 2, 3], "finest_cell_size": 0.5, "time": 4.5}"#,
    ] {
        let what = format!("meta {meta}");
        cases.push(ExaCase(what, one.clone(), Some(meta.into()), vec![]));
    }

    let mut tally = Tally::default();
    for ExaCase(what, cells, meta, scalars) in cases {
        let dir = TempDir::new("exabricks");
        let cells_path = dir.write("frame.cells", &cells);
        if let Some(meta) = &meta {
            dir.write("frame.meta.json", meta);
        }
        let paths: Vec<PathBuf> = FIELDS
            .iter()
            .zip(&scalars)
            .map(|(field, part)| dir.write(&format!("frame.{field}.scalars"), part))
            .collect();
        let parts: Vec<(&str, &[u8])> = FIELDS
            .iter()
            .zip(&scalars)
            .map(|(field, part)| (*field, part.as_slice()))
            .collect();
        tally.same(
            &what,
            read_exabricks(&cells_path, &paths),
            read_exabricks_bytes(&cells, &cells_path, &parts, meta.as_deref()),
        );
    }
    tally.check_both("exabricks");

    // Two parts with one field name: the later one is at fault.
    let dir = TempDir::new("exabricks-twice");
    let cells = dir.write("f.cells", &one);
    let value = 1f32.to_le_bytes();
    let twice = [
        dir.write("f.rho.scalars", value),
        dir.write("rho.scalars", value),
    ];
    let from_path = read_exabricks(&cells, &twice).unwrap_err().to_string();
    let parts: [(&str, &[u8]); 2] = [("rho", &value), ("rho", &value)];
    let from_memory = read_exabricks_bytes(&one, &cells, &parts, None)
        .unwrap_err()
        .to_string();
    assert!(
        from_path.ends_with("rho.scalars: field name `rho` is used by an earlier scalars file too")
    );
    assert!(
        from_memory
            .ends_with("f.rho.scalars: field name `rho` is used by an earlier scalars file too")
    );
}

/// The `fort.q` and `fort.t` texts among the `amrclaw` fuzz seeds (the
/// first byte of a seed says which it is; see
/// `fuzz/fuzz_targets/amrclaw.rs`).
fn amrclaw_texts() -> (Vec<Sample>, Vec<Sample>) {
    let (mut q, mut t) = (Vec::new(), Vec::new());
    for (name, seed) in seeds("amrclaw") {
        let (&mode, rest) = seed.split_first().expect("a seed has a mode byte");
        if mode % 3 == 1 {
            t.push((name, rest.to_vec()));
        } else {
            q.push((name, rest.to_vec()));
        }
    }
    assert!(!q.is_empty() && !t.is_empty());
    (q, t)
}

#[test]
fn amrclaw_from_memory_matches_path() {
    let (q_texts, t_texts) = amrclaw_texts();
    let mut tally = Tally::default();
    // Every fort.q text (and its variants) alone and with every fort.t text;
    // every fort.t variant with the first fort.q.
    let mut cases: Vec<(String, Vec<u8>, Option<Vec<u8>>)> = Vec::new();
    for (q_name, q) in &q_texts {
        for (v, q) in variants(q).into_iter().enumerate() {
            cases.push((format!("{q_name} variant {v}"), q.clone(), None));
            for (t_name, t) in &t_texts {
                let what = format!("{q_name} variant {v} with {t_name}");
                cases.push((what, q.clone(), Some(t.clone())));
            }
        }
    }
    for (t_name, t) in &t_texts {
        for (v, t) in variants(t).into_iter().enumerate() {
            let what = format!("{t_name} variant {v}");
            cases.push((what, q_texts[0].1.clone(), Some(t)));
        }
    }
    cases.push((
        "huge fort.t".into(),
        q_texts[0].1.clone(),
        Some(vec![b' '; 70_000]),
    ));
    for (what, q, t) in cases {
        let dir = TempDir::new("amrclaw");
        let q_path = dir.write("fort.q0001", &q);
        if let Some(t) = &t {
            dir.write("fort.t0001", t);
        }
        tally.same(
            &what,
            read_amrclaw(&q_path),
            read_amrclaw_from(Cursor::new(&q), &q_path, t.as_deref()),
        );
    }
    tally.check_both("amrclaw");

    // A fort.t beside a file not named fort.qNNNN is called fort.t.
    let err = read_amrclaw_from(
        Cursor::new(&q_texts[0].1),
        Path::new("run/grids.txt"),
        Some(b"x"),
    )
    .unwrap_err();
    assert!(err.to_string().starts_with("run/fort.t: "), "{err}");
}
