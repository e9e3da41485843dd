//! Particle and mesh readers: LAMMPS dumps, XYZ, `.particles`, VTK XML.
//!
//! Small inputs are written into a fresh temp directory by each test; the VTK
//! files in `tests/data/vtk/` were written by VTK itself
//! (`tools/gen_vtk_testdata.py`) and are compared with its `expected.json`.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use voxless_io::{
    IoError, ParticleTable, lammps_frames, particles_frames, read_lammps, read_particles_file,
    read_xyz, xyz_frames, xyz_species,
};

/// The VTK XML tests (kept in their own file for size).
#[path = "readers/vtk.rs"]
mod vtk;

/// A fresh directory in the system temp dir, removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new(name: &str) -> TempDir {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!(
            "voxless-io-readers-{}-{n}-{name}",
            std::process::id()
        ));
        std::fs::create_dir_all(&dir).expect("create test dir");
        TempDir(dir)
    }

    /// Writes `bytes` to `name` inside the directory and returns its path.
    fn write(&self, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
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

/// The message of an expected error, checked to name the file.
fn error_message<T: std::fmt::Debug>(result: Result<T, IoError>, path: &Path) -> String {
    let err = result.expect_err("expected an error");
    let message = err.to_string();
    let name = path.file_name().unwrap().to_string_lossy();
    assert!(
        message.contains(name.as_ref()),
        "error does not name the file {name}: {message}"
    );
    message
}

fn column<'a>(table: &'a ParticleTable, name: &str) -> &'a [f32] {
    table
        .column(name)
        .unwrap_or_else(|| panic!("no column {name}; columns: {:?}", table.column_names()))
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + b.abs())
}

// ---------------------------------------------------------------- LAMMPS

const LAMMPS_TWO_FRAMES: &str = "\
ITEM: TIMESTEP
100
ITEM: NUMBER OF ATOMS
3
ITEM: BOX BOUNDS pp pp pp
-1.0 1.0
0.0 4.0
0.0 2.0
ITEM: ATOMS id type x y z vx vy vz
3 2 0.5 1.0 1.5 0 0 0
1 1 -0.5 2.0 0.25 3 4 0
2 1 0.0 3.0 1.0 0 0 2
ITEM: TIMESTEP
200
ITEM: NUMBER OF ATOMS
2
ITEM: BOX BOUNDS pp pp pp
-1.0 1.0
0.0 4.0
0.0 2.0
ITEM: ATOMS id type xs ys zs
2 1 0.5 0.25 1.0
1 1 0.0 0.0 0.0
";

#[test]
fn lammps_columns_sorting_and_scaling() {
    let dir = TempDir::new("lammps");
    let path = dir.write("dump.two", LAMMPS_TWO_FRAMES);
    assert_eq!(lammps_frames(&path).unwrap(), 2);

    let t = read_lammps(&path, 0).unwrap();
    assert_eq!(t.len(), 3);
    assert_eq!(t.time, Some(100.0));
    assert_eq!(t.domain, Some(([-1.0, 0.0, 0.0], [1.0, 4.0, 2.0])));
    // Sorted by id; positions are not columns; speed derived from v.
    assert_eq!(column(&t, "id"), [1.0, 2.0, 3.0]);
    assert_eq!(column(&t, "type"), [1.0, 1.0, 2.0]);
    assert_eq!(
        t.positions,
        [[-0.5, 2.0, 0.25], [0.0, 3.0, 1.0], [0.5, 1.0, 1.5]]
    );
    assert_eq!(column(&t, "speed"), [5.0, 2.0, 0.0]);
    assert!(t.column("x").is_none());
    assert_eq!(t.column_names(), ["id", "type", "vx", "vy", "vz", "speed"]);

    // Frame 1 has scaled coordinates: lo + s * (hi - lo).
    let t = read_lammps(&path, 1).unwrap();
    assert_eq!(t.time, Some(200.0));
    assert_eq!(t.positions, [[-1.0, 0.0, 0.0], [0.0, 1.0, 2.0]]);
    assert!(t.column("speed").is_none());

    let msg = error_message(read_lammps(&path, 2), &path);
    assert!(msg.contains("2 frames"), "{msg}");
}

#[test]
fn lammps_triclinic_box() {
    // Real box [0,10]^3 with tilts xy = 2, xz = 1, yz = -3; the dump gives the
    // bounding box: x in [0, 13], y in [-3, 10].
    let text = "\
ITEM: TIMESTEP
5
ITEM: NUMBER OF ATOMS
2
ITEM: BOX BOUNDS xy xz yz pp pp pp
0.0 13.0 2.0
-3.0 10.0 1.0
0.0 10.0 -3.0
ITEM: ATOMS id xs ys zs
1 0.5 0.5 0.5
2 1.0 1.0 1.0
";
    let dir = TempDir::new("tri");
    let path = dir.write("dump.tri", text);
    let t = read_lammps(&path, 0).unwrap();
    assert_eq!(t.domain, Some(([0.0, -3.0, 0.0], [13.0, 10.0, 10.0])));
    // x = xlo + xs lx + ys xy + zs xz, y = ylo + ys ly + zs yz, z = zlo + zs lz.
    assert_eq!(t.positions, [[6.5, 3.5, 5.0], [13.0, 7.0, 10.0]]);
    // Periodic in LAMMPS (pp), not here: not a periodic table, and a note
    // that says so, with the tilts.
    assert!(!t.periodic);
    let (_, note) = voxless_io::lammps::read_lammps_noted(&path, 0).unwrap();
    let note = note.expect("a note on the tilted periodic box");
    assert!(
        note.contains("triclinic") && note.contains("xy 2"),
        "{note}"
    );
    // An orthogonal pp box is periodic, without a note.
    let ortho = dir.write(
        "dump.ortho",
        "ITEM: TIMESTEP\n5\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS pp pp pp\n0 10\n0 10\n0 10\n\
         ITEM: ATOMS id x y z\n1 1 2 3\n",
    );
    let (t, note) = voxless_io::lammps::read_lammps_noted(&ortho, 0).unwrap();
    assert!(t.periodic && note.is_none(), "{note:?}");
}

#[test]
fn lammps_general_triclinic_and_unwrapped() {
    let text = "\
ITEM: TIMESTEP
0
ITEM: NUMBER OF ATOMS
1
ITEM: BOX BOUNDS abc origin pp pp pp
2.0 0.0 0.0 1.0
1.0 2.0 0.0 1.0
0.0 0.0 3.0 1.0
ITEM: ATOMS id xsu ysu zsu
7 0.5 0.5 0.5
";
    let dir = TempDir::new("general");
    let path = dir.write("dump.general", text);
    let t = read_lammps(&path, 0).unwrap();
    assert_eq!(t.positions, [[2.5, 2.0, 2.5]]);
    assert_eq!(t.domain, Some(([1.0, 1.0, 1.0], [4.0, 3.0, 4.0])));

    // x y z wins over xu yu zu, which then stay columns.
    let text = "\
ITEM: TIMESTEP
0
ITEM: NUMBER OF ATOMS
1
ITEM: BOX BOUNDS pp pp pp
0 1
0 1
0 1
ITEM: ATOMS xu yu zu x y z
5 6 7 0.5 0.6 0.7
";
    let path = dir.write("dump.both", text);
    let t = read_lammps(&path, 0).unwrap();
    assert_eq!(t.positions, [[0.5, 0.6, 0.7]]);
    assert_eq!(column(&t, "xu"), [5.0]);
}

#[test]
fn lammps_skips_earlier_frames_without_parsing() {
    // Frame 0's atom lines are garbage; reading frame 1 must not look at them.
    let text = "\
ITEM: TIMESTEP
0
ITEM: NUMBER OF ATOMS
2
ITEM: BOX BOUNDS pp pp pp
0 1
0 1
0 1
ITEM: ATOMS id x y z
not numbers at all
neither is this
ITEM: TIMESTEP
10
ITEM: NUMBER OF ATOMS
1
ITEM: BOX BOUNDS pp pp pp
0 1
0 1
0 1
ITEM: ATOMS id x y z
1 0.1 0.2 0.3
";
    let dir = TempDir::new("skip");
    let path = dir.write("dump.skip", text);
    assert_eq!(lammps_frames(&path).unwrap(), 2);
    assert_eq!(read_lammps(&path, 1).unwrap().positions, [[0.1, 0.2, 0.3]]);
    let msg = error_message(read_lammps(&path, 0), &path);
    assert!(
        msg.contains("column 'id'") && msg.contains("'not'"),
        "{msg}"
    );
}

#[test]
fn lammps_malformed_inputs() {
    let dir = TempDir::new("lammps-bad");
    let frame = |atoms: &str, columns: &str, rows: &str| {
        format!(
            "ITEM: TIMESTEP\n7\nITEM: NUMBER OF ATOMS\n{atoms}\nITEM: BOX BOUNDS pp pp pp\n\
             0 1\n0 1\n0 1\nITEM: ATOMS {columns}\n{rows}"
        )
    };
    let cases: Vec<(&str, String, &str)> = vec![
        // Truncated: declares 3 atoms, has 2.
        (
            "truncated",
            frame("3", "id x y z", "1 0 0 0\n2 0 0 0\n"),
            "frame 0 (TIMESTEP 7) declares NUMBER OF ATOMS 3",
        ),
        // A count far beyond the file must not be allocated.
        (
            "huge",
            frame("999999999999999999", "id x y z", "1 0 0 0\n"),
            "999999999999999999",
        ),
        (
            "bad-number",
            frame("1", "id x y z", "1 0 zero 0\n"),
            "column 'y': cannot parse 'zero'",
        ),
        (
            "short-row",
            frame("1", "id x y z", "1 0 0\n"),
            "expected 4 values",
        ),
        ("long-row", frame("1", "id x y z", "1 0 0 0 9\n"), "found 5"),
        // Two atoms with one id would be matched as one across frames.
        (
            "duplicate-id",
            frame("2", "id x y z", "4 0 0 0\n4 0.5 0 0\n"),
            "atom id 4 appears twice",
        ),
        // A box whose lower bound is above its upper.
        (
            "inverted-box",
            "ITEM: TIMESTEP\n7\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS pp pp pp\n\
             0 1\n2 1\n0 1\nITEM: ATOMS id x y z\n1 0 0 0\n"
                .to_string(),
            "BOX BOUNDS along y run from 2 to 1",
        ),
        (
            "no-positions",
            frame("1", "id type vx vy vz", "1 1 0 0 0\n"),
            "columns are: id type vx vy vz",
        ),
        (
            "partial-positions",
            frame("1", "id x y", "1 0 0\n"),
            "columns are: id x y",
        ),
        (
            "bad-count",
            frame("many", "id x y z", ""),
            "NUMBER OF ATOMS",
        ),
        (
            "wrong-header",
            "Some other file\n1 2 3\n".to_string(),
            "not a LAMMPS text dump",
        ),
        ("empty", String::new(), "no 'ITEM: TIMESTEP'"),
        (
            "local-dump",
            "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ENTRIES\n1\n".to_string(),
            "ENTRIES",
        ),
        (
            "bad-box",
            "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n0\nITEM: BOX BOUNDS pp pp pp\n0 1\n0\n"
                .to_string(),
            "BOX BOUNDS",
        ),
        (
            "header-truncated",
            "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n".to_string(),
            "ends after ITEM: NUMBER OF ATOMS",
        ),
    ];
    for (name, text, expected) in cases {
        let path = dir.write(&format!("dump.{name}"), &text);
        let msg = error_message(read_lammps(&path, 0), &path);
        assert!(msg.contains(expected), "{name}: {msg}");
        // Counting frames skips atom lines, so only structural errors show.
        let structural = !matches!(
            name,
            "bad-number"
                | "short-row"
                | "long-row"
                | "no-positions"
                | "partial-positions"
                | "duplicate-id"
        );
        if structural {
            assert!(lammps_frames(&path).is_err(), "{name}");
        }
    }

    // The next frame starting early is caught while skipping, too.
    let text = frame("3", "id x y z", "1 0 0 0\n") + &frame("1", "id x y z", "1 0 0 0\n");
    let path = dir.write("dump.overlap", &text);
    let msg = error_message(lammps_frames(&path), &path);
    assert!(
        msg.contains("frame 0") && msg.contains("after 1 atom line"),
        "{msg}"
    );
    // Binary garbage.
    let path = dir.write("dump.bin", [0x80u8, 0xff, 0x00, 0x10, b'\n', 0xfe]);
    let msg = error_message(read_lammps(&path, 0), &path);
    assert!(msg.contains("UTF-8"), "{msg}");
    // A missing file is an I/O error naming it.
    let path = dir.0.join("missing.dump");
    error_message(read_lammps(&path, 0), &path);
}

#[test]
fn lammps_real_melt_dump() {
    let Some(path) = voxless_core::testing::shared_data("md-lammps-melt/dump.melt") else {
        return;
    };
    assert_eq!(lammps_frames(&path).unwrap(), 6);
    let side = 1.6795961913825074e1;
    for frame in 0..6 {
        let t = read_lammps(&path, frame).unwrap();
        assert_eq!(t.len(), 4000, "frame {frame}");
        assert_eq!(t.time, Some(50.0 * frame as f64), "frame {frame}");
        assert_eq!(t.domain, Some(([0.0; 3], [side; 3])));
        let ids = column(&t, "id");
        assert!(
            ids.iter().enumerate().all(|(i, &id)| id == (i + 1) as f32),
            "frame {frame}: ids are not 1..4000 after sorting"
        );
        assert!(column(&t, "type").iter().all(|&ty| ty == 1.0));
        // Atoms may sit slightly outside the periodic box between
        // re-neighbourings (scaled coordinates down to -0.008 in this dump).
        let margin = 0.02 * side;
        for p in &t.positions {
            for &c in p {
                assert!(
                    (-margin..=side + margin).contains(&c),
                    "frame {frame}: {p:?} outside the box"
                );
            }
        }
        if frame == 0 {
            // "2 1 0.05 0.05 0" in the file.
            let expected = [0.05 * side, 0.05 * side, 0.0];
            for (&got, want) in t.positions[1].iter().zip(expected) {
                assert!(close(got, want, 1e-6), "{got} vs {want}");
            }
        }
    }
    let msg = error_message(read_lammps(&path, 6), &path);
    assert!(msg.contains("6 frames"), "{msg}");
}

// ---------------------------------------------------------------- XYZ

#[test]
fn xyz_plain_frames_and_species_order() {
    let text = "\
3
water
O 0.0 0.0 0.1 7.5
H 0.0 0.7 -0.4 1.0
H 0.0 -0.7 -0.4 1.0

3
second frame, carbon appears
H 1.0 0.0 0.0 2.0
C 2.0 0.0 0.0 3.0
O 3.0 0.0 0.0 4.0
";
    let dir = TempDir::new("xyz");
    let path = dir.write("two.xyz", text);
    assert_eq!(xyz_frames(&path).unwrap(), 2);
    let t = read_xyz(&path, 0).unwrap();
    assert_eq!(t.positions[1], [0.0, 0.7, -0.4]);
    assert_eq!(t.column_names(), ["type", "c4"]);
    assert_eq!(column(&t, "type"), [1.0, 2.0, 2.0]);
    assert_eq!(column(&t, "c4"), [7.5, 1.0, 1.0]);
    assert_eq!(t.time, None);
    assert_eq!(t.domain, None);
    // Species numbers follow first appearance in the file: O=1, H=2, C=3.
    let t = read_xyz(&path, 1).unwrap();
    assert_eq!(column(&t, "type"), [2.0, 3.0, 1.0]);
    assert_eq!(column(&t, "c4"), [2.0, 3.0, 4.0]);
    let msg = error_message(read_xyz(&path, 2), &path);
    assert!(msg.contains("2 frames"), "{msg}");
    // The symbols behind those numbers, through each frame.
    assert_eq!(xyz_species(&path, 0).unwrap(), ["O", "H"]);
    assert_eq!(xyz_species(&path, 1).unwrap(), ["O", "H", "C"]);
    assert!(xyz_species(&path, 2).is_err());
}

#[test]
fn xyz_extended_properties() {
    let text = "\
2
Lattice=\"10.0 0.0 0.0 0.0 20.0 0.0 0.0 0.0 30.0\" Properties=species:S:1:pos:R:3:vel:R:3:mass:R:1:fixed:L:1:tag:S:1 Time=2.5 pbc=\"T T T\"
Si 1.0 2.0 3.0 3.0 0.0 4.0 28.1 T a
O 4.0 5.0 6.0 0.0 1.0 0.0 16.0 F b
";
    let dir = TempDir::new("extxyz");
    let path = dir.write("ext.xyz", text);
    let t = read_xyz(&path, 0).unwrap();
    assert_eq!(t.positions, [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    assert_eq!(
        t.column_names(),
        ["type", "vel_x", "vel_y", "vel_z", "mass", "fixed", "speed"]
    );
    assert_eq!(column(&t, "type"), [1.0, 2.0]);
    assert_eq!(column(&t, "vel_z"), [4.0, 0.0]);
    assert_eq!(column(&t, "speed"), [5.0, 1.0]);
    assert_eq!(column(&t, "fixed"), [1.0, 0.0]);
    assert_eq!(t.time, Some(2.5));
    assert_eq!(t.domain, Some(([0.0; 3], [10.0, 20.0, 30.0])));

    // A tilted cell gives no domain; positions first, 2-vectors as name0/1.
    let text = "\
1
Lattice=\"1 0 0 0.5 1 0 0 0 1\" Properties=pos:R:3:Z:I:1:f:R:2
0.1 0.2 0.3 14 7 8
";
    let path = dir.write("tilted.xyz", text);
    let t = read_xyz(&path, 0).unwrap();
    assert_eq!(t.domain, None);
    assert_eq!(t.column_names(), ["Z", "f0", "f1"]);
    assert_eq!(column(&t, "f1"), [8.0]);
}

#[test]
fn xyz_malformed_inputs() {
    let dir = TempDir::new("xyz-bad");
    let cases = [
        (
            "truncated",
            "3\ncomment\nH 0 0 0\nH 1 1 1\n",
            "declares 3 atoms but the file ends after 2",
        ),
        (
            "huge",
            "99999999999999999\ncomment\nH 0 0 0\n",
            "declares 99999999999999999 atoms",
        ),
        ("bad-number", "1\n\nH 0 zero 0\n", "cannot parse 'zero'"),
        ("missing-columns", "1\n\nH 0 0\n", "at least 4 fields"),
        ("ragged", "2\n\nH 0 0 0 1\nH 0 0 0\n", "expected 5 fields"),
        (
            "wrong-header",
            "<html>\n</html>\n",
            "expected the atom count of frame 0",
        ),
        ("no-comment", "2\n", "before its comment line"),
        ("empty", "", "holds no frame"),
        (
            "no-pos",
            "1\nProperties=species:S:1:mass:R:1\nH 1\n",
            "no 'pos:R:3' property",
        ),
        (
            "bad-props",
            "1\nProperties=species:S\nH 0 0 0\n",
            "name:type:count",
        ),
        ("bad-lattice", "1\nLattice=\"1 2\"\nH 0 0 0\n", "9 numbers"),
        (
            "extra-lines",
            "1\n\nH 0 0 0\nH 1 1 1\n",
            "atom count of frame 1",
        ),
    ];
    for (name, text, expected) in cases {
        let path = dir.write(&format!("{name}.xyz"), text);
        let result = if name == "extra-lines" {
            read_xyz(&path, 1)
        } else {
            read_xyz(&path, 0)
        };
        let msg = error_message(result, &path);
        assert!(msg.contains(expected), "{name}: {msg}");
    }
    // More atom lines than the count: reading frame 0 fails too (as
    // counting the frames does), rather than dropping the extra lines.
    let path = dir.write("extra-lines-0.xyz", "1\n\nH 0 0 0\nH 1 1 1\n");
    let msg = error_message(read_xyz(&path, 0), &path);
    assert!(msg.contains("more atom lines than its count"), "{msg}");
    assert!(xyz_frames(&path).is_err());
    let path = dir.write("binary.xyz", [1u8, 0xff, 0xfe, b'\n']);
    let msg = error_message(xyz_frames(&path), &path);
    assert!(msg.contains("UTF-8"), "{msg}");
}

// ---------------------------------------------------------------- .particles

/// A timestep file: u64 count then x, y, z, attribute per particle.
fn particles_bytes(records: &[[f32; 4]], big_endian: bool) -> Vec<u8> {
    let mut out = Vec::new();
    let n = records.len() as u64;
    out.extend(if big_endian {
        n.to_be_bytes()
    } else {
        n.to_le_bytes()
    });
    for r in records {
        for v in r {
            out.extend(if big_endian {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            });
        }
    }
    out
}

#[test]
fn particles_series() {
    let dir = TempDir::new("particles");
    let index = dir.write("run.particles", "0\n\n10\r\nstep2.bin\n");
    dir.write(
        "run.particles_0",
        particles_bytes(&[[1.0, 2.0, 3.0, 0.5], [4.0, 5.0, 6.0, 0.25]], false),
    );
    dir.write(
        "run.particles_10",
        particles_bytes(&[[0.0, 0.0, 1.0, 9.0]], false),
    );
    // Resolved relative to the index's directory, and big-endian.
    dir.write(
        "step2.bin",
        particles_bytes(&[[7.0, 8.0, 9.0, -1.0], [0.0; 4], [1.0; 4]], true),
    );
    assert_eq!(particles_frames(&index).unwrap(), 3);
    let t = read_particles_file(&index, 0).unwrap();
    assert_eq!(t.positions, [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    assert_eq!(column(&t, "attribute"), [0.5, 0.25]);
    assert_eq!(t.time, Some(0.0));
    let t = read_particles_file(&index, 1).unwrap();
    assert_eq!(t.positions, [[0.0, 0.0, 1.0]]);
    assert_eq!(t.time, Some(10.0));
    let t = read_particles_file(&index, 2).unwrap();
    assert_eq!(t.len(), 3);
    assert_eq!(t.positions[0], [7.0, 8.0, 9.0]);
    assert_eq!(column(&t, "attribute")[0], -1.0);
    assert_eq!(t.time, None);
    let msg = error_message(read_particles_file(&index, 3), &index);
    assert!(msg.contains("3 timesteps"), "{msg}");
}

#[test]
fn particles_malformed_inputs() {
    let dir = TempDir::new("particles-bad");
    let index = dir.write("bad.particles", "trunc\nhuge\nmissing\nshort\n");
    // Truncated: count 5, three records.
    let mut bytes = particles_bytes(&[[0.0; 4]; 3], false);
    bytes[..8].copy_from_slice(&5u64.to_le_bytes());
    let trunc = dir.write("bad.particles_trunc", &bytes);
    // A count far beyond the file.
    let mut bytes = particles_bytes(&[[0.0; 4]], false);
    bytes[..8].copy_from_slice(&(u64::MAX / 3).to_le_bytes());
    let huge = dir.write("bad.particles_huge", &bytes);
    let short = dir.write("bad.particles_short", [1u8, 2, 3]);

    let msg = error_message(read_particles_file(&index, 0), &trunc);
    assert!(msg.contains("declares 5 particles"), "{msg}");
    let msg = error_message(read_particles_file(&index, 1), &huge);
    assert!(msg.contains("particles"), "{msg}");
    let msg = error_message(read_particles_file(&index, 2), &index);
    assert!(msg.contains("bad.particles_missing"), "{msg}");
    let msg = error_message(read_particles_file(&index, 3), &short);
    assert!(msg.contains("too short"), "{msg}");

    let empty = dir.write("empty.particles", "\n  \n");
    let msg = error_message(particles_frames(&empty), &empty);
    assert!(msg.contains("no timestep"), "{msg}");
    let binary = dir.write("binary.particles", [0u8, 0x9f, 0xff, 0x80]);
    let msg = error_message(particles_frames(&binary), &binary);
    assert!(msg.contains("UTF-8"), "{msg}");
}
