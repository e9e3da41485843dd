//! AMReX plotfiles written here by the layout AMReX's plotfile writer uses
//! (`Header`, `Level_N/Cell_H`, FABs in `Cell_D_NNNNN`): every leaf cell,
//! level and value against a brute-force expectation on the finest
//! lattice; the bad inputs the reader must refuse, naming the file; the
//! format detection of `read_amr` and the field lookup by the codes' names.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use voxless_io::{
    AmrCellData, AmrFormat, IoError, amr_field, amr_format, read_amr, read_amrex, read_amrex_files,
};

/// A fresh directory in the system temp dir, removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new(name: &str) -> TempDir {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!(
            "voxless-io-amrex-{}-{n}-{name}",
            std::process::id()
        ));
        std::fs::create_dir_all(&dir).expect("create test dir");
        TempDir(dir)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A distinct value per finest-lattice corner, ExaBricks level and field,
/// exact in f32.
fn value(c: [i64; 3], level: i64, field: usize) -> f64 {
    let v = 1 + c[0] + 40 * c[1] + 1600 * c[2] + 100_000 * level;
    v as f64 * if field == 0 { 1.0 } else { -0.25 }
}

/// A box `lo..=hi` on one level.
type IBox = ([i64; 3], [i64; 3]);

/// How the test writes its FAB values.
#[derive(Clone, Copy)]
enum Real {
    F64Le,
    F32Be,
}

/// Writes a plotfile of two components (`density`, `xmom`) into `dir`:
/// `levels[l]` the boxes of level l (ratio `ratio` between levels; the
/// domain of level 0 is `n0`³), each cell's values from [`value`] at its
/// corner in finest cells with its ExaBricks level.
fn write_plotfile(dir: &Path, n0: i64, ratio: i64, levels: &[Vec<IBox>], real: Real) {
    let finest = levels.len() - 1;
    let dx0 = 1.0 / n0 as f64;
    let width = |l: usize| ratio.pow((finest - l) as u32);
    let mut h = String::new();
    writeln!(h, "HyperCLaw-V1.1\n2\ndensity\nxmom\n3\n0.75\n{finest}").unwrap();
    writeln!(h, "0 0 0\n1 1 1").unwrap();
    writeln!(h, "{}", vec![ratio.to_string(); finest].join(" ")).unwrap();
    for l in 0..=finest {
        let n = n0 * ratio.pow(l as u32) - 1;
        write!(h, "((0,0,0) ({n},{n},{n}) (0,0,0)) ").unwrap();
    }
    writeln!(h).unwrap();
    writeln!(h, "{}", vec!["0"; finest + 1].join(" ")).unwrap();
    for l in 0..=finest {
        let d = dx0 / ratio.pow(l as u32) as f64;
        writeln!(h, "{d} {d} {d}").unwrap();
    }
    writeln!(h, "0\n0").unwrap();
    for (l, boxes) in levels.iter().enumerate() {
        writeln!(h, "{l} {} 0.75\n0", boxes.len()).unwrap();
        let d = dx0 / ratio.pow(l as u32) as f64;
        for (lo, hi) in boxes {
            for a in 0..3 {
                writeln!(h, "{} {}", lo[a] as f64 * d, (hi[a] + 1) as f64 * d).unwrap();
            }
        }
        writeln!(h, "Level_{l}/Cell").unwrap();
        std::fs::create_dir_all(dir.join(format!("Level_{l}"))).unwrap();
        let mut data = Vec::new();
        let mut cell_h = format!("1\n1\n2\n0\n({} 0\n", boxes.len());
        for (lo, hi) in boxes {
            writeln!(
                cell_h,
                "(({},{},{}) ({},{},{}) (0,0,0))",
                lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
            )
            .unwrap();
        }
        writeln!(cell_h, ")\n{}", boxes.len()).unwrap();
        for (lo, hi) in boxes {
            writeln!(cell_h, "FabOnDisk: Cell_D_00000 {}", data.len()).unwrap();
            let desc = match real {
                Real::F64Le => "((8, (64 11 52 0 1 12 0 1023)),(8, (8 7 6 5 4 3 2 1)))",
                Real::F32Be => "((4, (32 8 23 0 1 9 0 127)),(4, (1 2 3 4)))",
            };
            let header = format!(
                "FAB {desc}(({},{},{}) ({},{},{}) (0,0,0)) 2\n",
                lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
            );
            data.extend_from_slice(header.as_bytes());
            let exa = width(l).trailing_zeros() as i64;
            for f in 0..2 {
                for z in lo[2]..=hi[2] {
                    for y in lo[1]..=hi[1] {
                        for x in lo[0]..=hi[0] {
                            let v = value([x, y, z].map(|i| i * width(l)), exa, f);
                            match real {
                                Real::F64Le => data.extend_from_slice(&v.to_le_bytes()),
                                Real::F32Be => data.extend_from_slice(&(v as f32).to_be_bytes()),
                            }
                        }
                    }
                }
            }
        }
        std::fs::write(dir.join(format!("Level_{l}/Cell_H")), cell_h).unwrap();
        std::fs::write(dir.join(format!("Level_{l}/Cell_D_00000")), data).unwrap();
    }
    std::fs::write(dir.join("Header"), h).unwrap();
}

/// Checks every finest cell of the `n`³ lattice: covered exactly once, by
/// the leaf `leaf(p)` (corner, ExaBricks level), with both fields' values.
fn check_cells(data: &AmrCellData, n: i64, leaf: impl Fn([i64; 3]) -> ([i64; 3], i64)) {
    let names: Vec<&str> = data.fields.iter().map(|f| f.0.as_str()).collect();
    assert_eq!(names, ["density", "xmom"]);
    let nu = n as usize;
    let mut owner = vec![usize::MAX; nu * nu * nu];
    for (i, c) in data.cells.iter().enumerate() {
        let w = 1i64 << c[3];
        for z in 0..w {
            for y in 0..w {
                for x in 0..w {
                    let p = [c[0] as i64 + x, c[1] as i64 + y, c[2] as i64 + z];
                    assert!(
                        p.iter().all(|&v| (0..n).contains(&v)),
                        "cell {c:?} leaves the domain"
                    );
                    let k = (p[0] + n * (p[1] + n * p[2])) as usize;
                    assert_eq!(owner[k], usize::MAX, "finest cell {p:?} covered twice");
                    owner[k] = i;
                }
            }
        }
    }
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let i = owner[(x + n * (y + n * z)) as usize];
                assert_ne!(i, usize::MAX, "finest cell {:?} not covered", [x, y, z]);
                let c = data.cells[i];
                let (corner, level) = leaf([x, y, z]);
                assert_eq!(
                    [c[0] as i64, c[1] as i64, c[2] as i64, c[3] as i64],
                    [corner[0], corner[1], corner[2], level],
                    "leaf of {:?}",
                    [x, y, z]
                );
                for f in 0..2 {
                    assert_eq!(data.fields[f].1[i], value(corner, level, f) as f32);
                }
            }
        }
    }
}

fn inside(p: [i64; 3], (lo, hi): &IBox) -> bool {
    (0..3).all(|a| lo[a] <= p[a] && p[a] <= hi[a])
}

#[test]
fn two_levels_leave_the_uncovered_coarse_cells_and_every_fine_cell() {
    let dir = TempDir::new("two");
    // Level 0: 8³ in two boxes (two FABs in one data file); level 1: one
    // box straddling both.
    let coarse = vec![([0, 0, 0], [3, 7, 7]), ([4, 0, 0], [7, 7, 7])];
    let fine = vec![([4, 2, 6], [9, 7, 11])];
    write_plotfile(&dir.0, 8, 2, &[coarse, fine.clone()], Real::F64Le);
    let data = read_amrex(&dir.0).unwrap();
    assert_eq!(data.origin, [0.0; 3]);
    assert_eq!(data.finest_cell_size, 1.0 / 16.0);
    assert_eq!(data.time, Some(0.75));
    check_cells(&data, 16, |p| {
        if inside(p, &fine[0]) {
            (p, 0)
        } else {
            (p.map(|v| v / 2 * 2), 1)
        }
    });
    // Through the one entry point, format detected.
    let (again, format) = read_amr(&dir.0).unwrap();
    assert_eq!(format, AmrFormat::Amrex);
    assert_eq!(again, data);
}

#[test]
fn from_memory_reads_as_from_the_directory() {
    let dir = TempDir::new("memory");
    let coarse = vec![([0, 0, 0], [7, 7, 7])];
    let fine = vec![([2, 4, 6], [9, 11, 13])];
    write_plotfile(&dir.0, 8, 2, &[coarse, fine], Real::F64Le);
    let names = [
        "Header",
        "Level_0/Cell_H",
        "Level_0/Cell_D_00000",
        "Level_1/Cell_H",
        "Level_1/Cell_D_00000",
    ];
    let bytes: Vec<Vec<u8>> = names
        .iter()
        .map(|n| std::fs::read(dir.0.join(n)).unwrap())
        .collect();
    let files: Vec<(&str, &[u8])> = names
        .iter()
        .copied()
        .zip(bytes.iter().map(|b| b.as_slice()))
        .collect();
    assert_eq!(
        read_amrex_files(&dir.0, &files).unwrap(),
        read_amrex(&dir.0).unwrap()
    );
    // A missing file is named as the directory would name it.
    let msg = message(
        "Level_1/Cell_D_00000",
        read_amrex_files(&dir.0, &files[..4]),
    );
    assert!(msg.contains("No such file"), "{msg}");
    // A box larger than its data file can hold is refused before any
    // allocation of its size.
    let h = String::from_utf8(bytes[3].clone()).unwrap();
    let huge = h.replace(
        "((2,4,6) (9,11,13)",
        "((2,4,6) (2000000000,2000000000,2000000000)",
    );
    let mut patched = files.clone();
    patched[3].1 = huge.as_bytes();
    let msg = message("Level_1/Cell_D_00000", read_amrex_files(&dir.0, &patched));
    assert!(msg.contains("needs") && msg.contains("bytes"), "{msg}");
}

#[test]
fn ratio_four_and_big_endian_single_precision() {
    let dir = TempDir::new("four");
    let coarse = vec![([0, 0, 0], [3, 3, 3])];
    let fine = vec![([4, 0, 8], [11, 7, 15]), ([0, 8, 0], [3, 15, 3])];
    write_plotfile(&dir.0, 4, 4, &[coarse, fine.clone()], Real::F32Be);
    let data = read_amrex(&dir.0).unwrap();
    check_cells(&data, 16, |p| {
        if fine.iter().any(|b| inside(p, b)) {
            (p, 0)
        } else {
            (p.map(|v| v / 4 * 4), 2)
        }
    });
}

#[test]
fn three_levels_nest() {
    let dir = TempDir::new("three");
    let l0 = vec![([0, 0, 0], [3, 3, 3])];
    let l1 = vec![([2, 2, 2], [5, 7, 5])];
    let l2 = vec![([6, 6, 6], [9, 13, 9])];
    write_plotfile(&dir.0, 4, 2, &[l0, l1.clone(), l2.clone()], Real::F64Le);
    let data = read_amrex(&dir.0).unwrap();
    check_cells(&data, 16, |p| {
        if inside(p, &l2[0]) {
            (p, 0)
        } else if inside(p.map(|v| v / 2), &l1[0]) {
            (p.map(|v| v / 2 * 2), 1)
        } else {
            (p.map(|v| v / 4 * 4), 2)
        }
    });
}

/// The error's message, checking it names `file` (somewhere in its text).
fn message(file: &str, result: Result<AmrCellData, IoError>) -> String {
    let msg = result.expect_err("expected an error").to_string();
    assert!(msg.contains(file), "error does not name {file}: {msg}");
    msg
}

#[test]
fn bad_plotfiles_are_clear_errors_naming_the_file() {
    let make = |name: &str| {
        let dir = TempDir::new(name);
        let coarse = vec![([0, 0, 0], [3, 3, 3])];
        let fine = vec![([2, 2, 2], [5, 5, 5])];
        write_plotfile(&dir.0, 4, 2, &[coarse, fine], Real::F64Le);
        dir
    };
    // A missing level directory.
    let dir = make("missing");
    std::fs::remove_dir_all(dir.0.join("Level_1")).unwrap();
    let msg = message("Level_1/Cell_H", read_amrex(&dir.0));
    assert!(
        msg.contains("No such file") || msg.contains("not found"),
        "{msg}"
    );
    // Data cut short.
    let dir = make("short");
    let d = dir.0.join("Level_1/Cell_D_00000");
    let bytes = std::fs::read(&d).unwrap();
    std::fs::write(&d, &bytes[..bytes.len() - 9]).unwrap();
    let msg = message("Cell_D_00000", read_amrex(&dir.0));
    assert!(msg.contains("needs"), "{msg}");
    // A refinement ratio that is not a power of two.
    let dir = make("ratio");
    let h = std::fs::read_to_string(dir.0.join("Header")).unwrap();
    std::fs::write(
        dir.0.join("Header"),
        h.replacen("1 1 1\n2\n", "1 1 1\n3\n", 1),
    )
    .unwrap();
    let msg = message("Header", read_amrex(&dir.0));
    assert!(msg.contains("power of two"), "{msg}");
    // A FAB whose box disagrees with Cell_H.
    let dir = make("box");
    let c = dir.0.join("Level_1/Cell_H");
    let h = std::fs::read_to_string(&c).unwrap();
    std::fs::write(&c, h.replace("((2,2,2) (5,5,5)", "((2,2,2) (5,5,4)")).unwrap();
    message("Cell_D_00000", read_amrex(&dir.0));
    // An unknown byte order.
    let dir = make("order");
    let d = dir.0.join("Level_0/Cell_D_00000");
    let bytes = std::fs::read(&d).unwrap();
    let text = String::from_utf8_lossy(&bytes[..80]).replace("8 7 6 5 4 3 2 1", "8 7 6 5 1 2 3 4");
    let mut patched = text.into_bytes();
    patched.extend_from_slice(&bytes[80..]);
    std::fs::write(&d, patched).unwrap();
    let msg = message("Cell_D_00000", read_amrex(&dir.0));
    assert!(msg.contains("byte order"), "{msg}");
    // A multi-FAB path leaving the plotfile.
    let dir = make("escape");
    let h = std::fs::read_to_string(dir.0.join("Header")).unwrap();
    std::fs::write(dir.0.join("Header"), h.replace("Level_1/Cell", "../x/Cell")).unwrap();
    message("Header", read_amrex(&dir.0));
    // A directory that is no plotfile.
    let dir = TempDir::new("empty");
    message(&dir.0.display().to_string(), read_amr(&dir.0).map(|r| r.0));
}

#[test]
fn formats_are_told_apart_by_their_paths() {
    let dir = TempDir::new("detect");
    let q = dir.0.join("fort.q0007");
    std::fs::write(&q, "").unwrap();
    assert_eq!(amr_format(&q).unwrap(), AmrFormat::AmrClaw);
    let cells = dir.0.join("frame.cells");
    std::fs::write(&cells, [0u8; 16]).unwrap();
    assert_eq!(amr_format(&cells).unwrap(), AmrFormat::ExaBricks);
    // ExaBricks through `read_amr`: its scalars are found beside it.
    std::fs::write(dir.0.join("frame.rho.scalars"), 2.5f32.to_le_bytes()).unwrap();
    let (data, _) = read_amr(&cells).unwrap();
    assert_eq!(data.fields, vec![("rho".to_string(), vec![2.5])]);
    let enzo = dir.0.join("data0003");
    std::fs::write(&enzo, "InitialTime = 0\n").unwrap();
    std::fs::write(dir.0.join("data0003.hierarchy"), "").unwrap();
    assert_eq!(amr_format(&enzo).unwrap(), AmrFormat::Enzo);
    let athena = dir.0.join("run.out1.00003.athdf");
    std::fs::write(&athena, b"\x89HDF\r\n\x1a\n").unwrap();
    assert_eq!(amr_format(&athena).unwrap(), AmrFormat::Athena);
    let other = dir.0.join("notes.txt");
    std::fs::write(&other, "hello").unwrap();
    message("notes.txt", read_amr(&other).map(|r| r.0));
}

#[test]
fn fields_are_found_under_the_names_the_codes_give_them() {
    assert_eq!(amr_field(&["dens", "velx"], "density"), Some(0));
    assert_eq!(amr_field(&["Density", "TotalEnergy"], "density"), Some(0));
    assert_eq!(amr_field(&["mom1", "rho"], "density"), Some(1));
    assert_eq!(amr_field(&["density", "dens"], "dens"), Some(1));
    assert_eq!(amr_field(&["dens", "rho"], "density"), None, "ambiguous");
    assert_eq!(amr_field(&["q0", "q1"], "density"), None);
    assert_eq!(amr_field(&["TEMP"], "temp"), Some(0));
}
