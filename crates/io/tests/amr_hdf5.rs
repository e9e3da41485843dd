//! The HDF5 AMR readers (FLASH, Enzo, Athena++) on small synthetic files
//! written here with `hdf5-metno`: every leaf cell, level and value against
//! a brute-force expectation on the finest lattice, and the bad inputs each
//! reader must refuse.
#![cfg(feature = "hdf5")]

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use hdf5_metno as h5;
use hdf5_metno::H5Type;
use hdf5_metno::types::FixedAscii;
use voxless_io::{AmrCellData, IoError, read_amrclaw, read_athena, read_enzo, read_flash};

/// A directory in the system temp dir that no other test (or test run)
/// uses, removed with its contents when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new(name: &str) -> TempDir {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let dir =
            std::env::temp_dir().join(format!("voxless-io-amr-{}-{n}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("create temp dir");
        TempDir(dir)
    }

    fn join(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The value of field `field` in the leaf cell with finest-lattice corner
/// `c` and ExaBricks level `level`: distinct per cell, level and field, and
/// exact in `f32`.
fn value(c: [i32; 3], level: i32, field: usize) -> f64 {
    let v = 1 + c[0] + 20 * c[1] + 400 * c[2] + 10_000 * level;
    f64::from(v) * if field.is_multiple_of(2) { 1.0 } else { -0.5 } + field as f64
}

/// Checks `data` cell by cell against the brute-force expectation on the
/// `n`³ finest lattice: `leaf(p)` is the leaf cell (corner, level) that
/// must hold finest cell `p`. Every finest cell must be covered exactly
/// once (so the cells' volume is the domain's), by the expected cell, with
/// the expected value of every field.
fn check_cells(data: &AmrCellData, n: i32, fields: &[&str], leaf: impl Fn([i32; 3]) -> [i32; 4]) {
    let names: Vec<&str> = data.fields.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, fields, "field names");
    for (name, values) in &data.fields {
        assert_eq!(values.len(), data.cells.len(), "values of {name}");
    }
    let n = n as usize;
    let mut owner = vec![usize::MAX; n * n * n];
    let mut volume = 0u64;
    for (k, c) in data.cells.iter().enumerate() {
        let w = 1i32 << c[3];
        volume += (w as u64).pow(3);
        for z in c[2]..c[2] + w {
            for y in c[1]..c[1] + w {
                for x in c[0]..c[0] + w {
                    assert!(
                        [x, y, z].iter().all(|&v| v >= 0 && (v as usize) < n),
                        "cell {c:?} lies outside the {n}³ lattice"
                    );
                    let p = (z as usize * n + y as usize) * n + x as usize;
                    assert_eq!(
                        owner[p],
                        usize::MAX,
                        "finest cell ({x}, {y}, {z}) is covered by cells {:?} and {c:?}",
                        data.cells.get(owner[p])
                    );
                    owner[p] = k;
                }
            }
        }
    }
    assert_eq!(volume, (n as u64).pow(3), "total covered volume");
    let mut leaves = std::collections::HashSet::new();
    for z in 0..n as i32 {
        for y in 0..n as i32 {
            for x in 0..n as i32 {
                let p = (z as usize * n + y as usize) * n + x as usize;
                let expected = leaf([x, y, z]);
                leaves.insert(expected);
                let k = owner[p];
                assert_eq!(data.cells[k], expected, "cell holding ({x}, {y}, {z})");
                for (i, (name, values)) in data.fields.iter().enumerate() {
                    let want = value([expected[0], expected[1], expected[2]], expected[3], i);
                    assert_eq!(values[k], want as f32, "{name} of cell {expected:?}");
                }
            }
        }
    }
    assert_eq!(data.cells.len(), leaves.len(), "leaf count");
}

/// The message of a format error (panics on other errors or success).
fn format_error(result: Result<AmrCellData, IoError>) -> (PathBuf, String) {
    match result {
        Err(IoError::Format { path, message }) => (path, message),
        Err(other) => panic!("expected a format error, got {other}"),
        Ok(_) => panic!("expected an error, got data"),
    }
}

fn ascii<const N: usize>(s: &str) -> FixedAscii<N> {
    FixedAscii::from_ascii(s).expect("ascii")
}

fn write<T: H5Type>(group: &h5::Group, name: &str, shape: &[usize], data: &[T]) {
    group
        .new_dataset::<T>()
        .shape(shape)
        .create(name)
        .and_then(|ds| ds.write_raw(data))
        .unwrap_or_else(|e| panic!("write {name}: {e}"));
}

fn attr<T: H5Type>(group: &h5::Group, name: &str, data: &[T]) {
    group
        .new_attr::<T>()
        .shape([data.len()])
        .create(name)
        .and_then(|a| a.write_raw(data))
        .unwrap_or_else(|e| panic!("attribute {name}: {e}"));
}

// ---------------------------------------------------------------------------
// FLASH
// ---------------------------------------------------------------------------

#[derive(H5Type, Clone)]
#[repr(C)]
struct IntRow {
    name: FixedAscii<80>,
    value: i32,
}

#[derive(H5Type, Clone)]
#[repr(C)]
struct RealRow {
    name: FixedAscii<80>,
    value: f64,
}

#[derive(H5Type, Clone)]
#[repr(C)]
struct StrRow {
    name: FixedAscii<80>,
    value: FixedAscii<80>,
}

#[derive(Default)]
struct FlashOptions {
    /// Mark the refined root block a leaf too (it then overlaps its
    /// children).
    parent_is_leaf: bool,
    /// An extra unknown name with no dataset.
    extra_name: Option<&'static str>,
    /// Stretch the domain along x (non-cubic cells).
    stretch_x: bool,
}

/// FLASH refined root block (1, 0, 1): finest x ∈ [4, 8), y ∈ [0, 4), z ∈ [4, 8).
fn flash_leaf(p: [i32; 3]) -> [i32; 4] {
    if (4..8).contains(&p[0]) && (0..4).contains(&p[1]) && (4..8).contains(&p[2]) {
        [p[0], p[1], p[2], 0]
    } else {
        [p[0] & !1, p[1] & !1, p[2] & !1, 1]
    }
}

/// A FLASH file over [-1, 1]³: 2×2×2 root blocks of 2³ cells (refine level
/// 1, cells 0.5 wide), root block (1, 0, 1) refined into 8 children
/// (refine level 2, cells 0.25 wide, the finest), so the finest lattice is
/// 8³. Variables `dens` and `pres`.
fn write_flash(path: &Path, opt: &FlashOptions) {
    let file = h5::File::create(path).expect("create FLASH file");
    let xmax = if opt.stretch_x { 2.0 } else { 1.0 };
    let sx = (xmax + 1.0) / 2.0; // root block width along x
    // (lower corner, width along y/z, refine level, node type)
    let mut blocks: Vec<([f64; 3], f64, i32, i32)> = Vec::new();
    let refined = [1, 0, 1];
    for k in 0..2 {
        for j in 0..2 {
            for i in 0..2 {
                let lo = [-1.0 + i as f64 * sx, -1.0 + j as f64, -1.0 + k as f64];
                let parent = [i, j, k] == refined;
                let node = if parent && !opt.parent_is_leaf { 2 } else { 1 };
                blocks.push((lo, 1.0, 1, node));
            }
        }
    }
    for c in 0..2 {
        for b in 0..2 {
            for a in 0..2 {
                let lo = [
                    -1.0 + (2 + a) as f64 * sx / 2.0,
                    -1.0 + b as f64 * 0.5,
                    -1.0 + (2 + c) as f64 * 0.5,
                ];
                blocks.push((lo, 0.5, 2, 1));
            }
        }
    }
    let nb = blocks.len();
    let mut bbox = Vec::new();
    let mut dens = Vec::new();
    for (lo, w, level, node) in &blocks {
        let wx = if *level == 1 { sx } else { sx / 2.0 };
        bbox.extend_from_slice(&[lo[0], lo[0] + wx, lo[1], lo[1] + w, lo[2], lo[2] + w]);
        let exa = 2 - level;
        let cw = 1 << exa;
        let corner = |d: usize| ((lo[d] + 1.0) / if d == 0 { sx / 2.0 } else { 0.5 }) as i32 * 2;
        for z in 0..2 {
            for y in 0..2 {
                for x in 0..2 {
                    let c = [corner(0) + x * cw, corner(1) + y * cw, corner(2) + z * cw];
                    let parent_data = *node == 2;
                    dens.push(if parent_data { -7.0 } else { value(c, exa, 0) });
                }
            }
        }
    }
    // pres = value(.., 1): derive from dens's cell by recomputing.
    let pres: Vec<f64> = dens
        .iter()
        .map(|&v| if v == -7.0 { -7.0 } else { v * -0.5 + 1.0 })
        .collect();
    let mut names = vec![ascii::<4>("dens"), ascii::<4>("pres")];
    if let Some(extra) = opt.extra_name {
        names.push(ascii::<4>(extra));
    }
    write(&file, "unknown names", &[names.len(), 1], &names);
    let levels: Vec<i32> = blocks.iter().map(|b| b.2).collect();
    let nodes: Vec<i32> = blocks.iter().map(|b| b.3).collect();
    write(&file, "refine level", &[nb], &levels);
    write(&file, "node type", &[nb], &nodes);
    write(&file, "bounding box", &[nb, 3, 2], &bbox);
    let sizes: Vec<f64> = blocks
        .iter()
        .flat_map(|b| [if b.2 == 1 { sx } else { sx / 2.0 }, b.1, b.1])
        .collect();
    write(&file, "block size", &[nb, 3], &sizes);
    write(&file, "dens", &[nb, 2, 2, 2], &dens);
    write(&file, "pres", &[nb, 2, 2, 2], &pres);
    let ints: Vec<IntRow> = [("nxb", 2), ("nyb", 2), ("nzb", 2), ("dimensionality", 3)]
        .iter()
        .map(|(n, v)| IntRow {
            name: ascii(n),
            value: *v,
        })
        .collect();
    write(&file, "integer scalars", &[ints.len()], &ints);
    let reals = [RealRow {
        name: ascii("time"),
        value: 0.125,
    }];
    write(&file, "real scalars", &[1], &reals);
    let params: Vec<RealRow> = [
        ("xmin", -1.0),
        ("xmax", xmax),
        ("ymin", -1.0),
        ("ymax", 1.0),
    ]
    .iter()
    .chain(&[("zmin", -1.0), ("zmax", 1.0)])
    .map(|(n, v)| RealRow {
        name: ascii(n),
        value: *v,
    })
    .collect();
    write(&file, "real runtime parameters", &[params.len()], &params);
    let strings = [StrRow {
        name: ascii("geometry"),
        value: ascii("cartesian"),
    }];
    write(&file, "string runtime parameters", &[1], &strings);
}

#[test]
fn flash_two_levels_leaf_cells() {
    let dir = TempDir::new("flash");
    let path = dir.join("sod_hdf5_plt_cnt_0001");
    write_flash(&path, &FlashOptions::default());
    let data = read_flash(&path).expect("read FLASH");
    check_cells(&data, 8, &["dens", "pres"], flash_leaf);
    assert_eq!(data.cells.len(), 7 * 8 + 8 * 8);
    assert_eq!(data.origin, [-1.0; 3]);
    assert_eq!(data.finest_cell_size, 0.25);
    assert_eq!(data.time, Some(0.125));
}

#[test]
fn flash_overlapping_leaf_blocks_are_refused() {
    let dir = TempDir::new("flash-overlap");
    let path = dir.join("overlap.h5");
    let opt = FlashOptions {
        parent_is_leaf: true,
        ..Default::default()
    };
    write_flash(&path, &opt);
    let (at, message) = format_error(read_flash(&path));
    assert_eq!(at, path);
    // Root block (1, 0, 1) is block 5; its first child is block 8.
    assert!(
        message.contains("leaf block 5 and leaf block 8 overlap"),
        "{message}"
    );
}

#[test]
fn flash_unknown_name_without_dataset_is_refused() {
    let dir = TempDir::new("flash-unknown");
    let path = dir.join("unknown.h5");
    let opt = FlashOptions {
        extra_name: Some("temp"),
        ..Default::default()
    };
    write_flash(&path, &opt);
    let (at, message) = format_error(read_flash(&path));
    assert_eq!(at, path);
    assert!(message.contains("dataset temp is missing"), "{message}");
}

#[test]
fn flash_non_cubic_cells_are_refused() {
    let dir = TempDir::new("flash-stretch");
    let path = dir.join("stretched.h5");
    let opt = FlashOptions {
        stretch_x: true,
        ..Default::default()
    };
    write_flash(&path, &opt);
    let (_, message) = format_error(read_flash(&path));
    assert!(message.contains("non-cubic"), "{message}");
}

// ---------------------------------------------------------------------------
// Enzo
// ---------------------------------------------------------------------------

#[derive(Default)]
struct EnzoOptions {
    /// Write `Level = L` lines in the hierarchy (else the reader deduces
    /// the levels from the cell widths).
    levels: bool,
    /// Leave out data0003.cpu0001 (grids 2 and 3).
    omit_cpu1: bool,
    /// Leave TotalEnergy out of grid 3.
    omit_energy_of_grid3: bool,
    /// A DataLabel no grid holds.
    extra_label: bool,
    /// Move grid 3 out of grid 2.
    grid3_outside: bool,
}

/// A grid: (id, finest-lattice corner, active cells, ExaBricks level).
type EnzoGrid = (u32, [i32; 3], [i32; 3], i32);

/// Enzo grids on [-1, 1]³, TopGridDimensions 4³ (finest lattice 16³, finest
/// cell 0.125): root grid 1 (level 0), grid 2 (level 1) over finest x ∈
/// [4, 12), y ∈ [8, 16), z ∈ [0, 4), grid 3 (level 2) over x ∈ [6, 10),
/// y ∈ [8, 12), z ∈ [0, 2).
fn enzo_grids(opt: &EnzoOptions) -> [EnzoGrid; 3] {
    let g3 = if opt.grid3_outside {
        [0, 0, 8]
    } else {
        [6, 8, 0]
    };
    [
        (1, [0, 0, 0], [4, 4, 4], 2),
        (2, [4, 8, 0], [4, 4, 2], 1),
        (3, g3, [4, 4, 2], 0),
    ]
}

fn enzo_leaf(p: [i32; 3]) -> [i32; 4] {
    let inside = |lo: [i32; 3], hi: [i32; 3]| (0..3).all(|d| lo[d] <= p[d] && p[d] < hi[d]);
    if inside([6, 8, 0], [10, 12, 2]) {
        [p[0], p[1], p[2], 0]
    } else if inside([4, 8, 0], [12, 16, 4]) {
        [p[0] & !1, p[1] & !1, p[2] & !1, 1]
    } else {
        [p[0] & !3, p[1] & !3, p[2] & !3, 2]
    }
}

/// Writes DD0003/data0003 (+ .hierarchy, .cpu0000 with the root grid and
/// its ghost zones, .cpu0001 with grids 2 and 3, active zones only) and
/// returns the parameter file's path.
fn write_enzo(dir: &TempDir, opt: &EnzoOptions) -> PathBuf {
    let dd = dir.join("DD0003");
    std::fs::create_dir_all(&dd).expect("mkdir DD0003");
    let base = dd.join("data0003");
    let mut labels = vec!["Density", "TotalEnergy"];
    if opt.extra_label {
        labels.push("Temperature");
    }
    let mut params = String::from(
        "InitialCycleNumber  = 3\nInitialTime         = 0.75\nTopGridRank         = 3\n\
         TopGridDimensions   = 4 4 4\nDomainLeftEdge      = -1 -1 -1\n\
         DomainRightEdge     = 1 1 1\nRefineBy            = 2\nMaximumRefinementLevel = 2\n",
    );
    for (i, l) in labels.iter().enumerate() {
        params.push_str(&format!("DataLabel[{i}]              = {l}\n"));
        params.push_str(&format!("DataUnits[{i}]              = none\n"));
    }
    std::fs::write(&base, params).expect("write parameter file");

    let finest = 0.125;
    let mut hierarchy = String::new();
    let files = [
        h5::File::create(dd.join("data0003.cpu0000")).expect("cpu0000"),
        h5::File::create(dd.join("data0003.cpu0001")).expect("cpu0001"),
    ];
    for (id, corner, n, exa) in enzo_grids(opt) {
        let level = 2 - exa;
        let w = 1 << exa;
        let ghost = 3;
        let left: Vec<String> = (0..3)
            .map(|d| format!("{}", -1.0 + f64::from(corner[d]) * finest))
            .collect();
        let right: Vec<String> = (0..3)
            .map(|d| format!("{}", -1.0 + f64::from(corner[d] + n[d] * w) * finest))
            .collect();
        let file_name = match id {
            1 => "./data0003.cpu0000",
            2 => "./data0003.cpu0001",
            // Named from the run's directory, as Enzo often does.
            _ => "./DD0003/data0003.cpu0001",
        };
        hierarchy.push_str(&format!(
            "\nGrid = {id}\nTask              = 0\nGridRank          = 3\n\
             GridDimension     = {} {} {}\nGridStartIndex    = 3 3 3\n\
             GridEndIndex      = {} {} {}\nGridLeftEdge      = {}\nGridRightEdge     = {}\n",
            n[0] + 2 * ghost,
            n[1] + 2 * ghost,
            n[2] + 2 * ghost,
            n[0] + 2,
            n[1] + 2,
            n[2] + 2,
            left.join(" "),
            right.join(" ")
        ));
        if opt.levels {
            hierarchy.push_str(&format!("Level             = {level}\n"));
        }
        hierarchy.push_str(&format!(
            "Time              = 0.75\nSubgridsAreStatic = 0\nNumberOfBaryonFields = 2\n\
             FieldType = 0 1\nBaryonFileName = {file_name}\nCourantSafetyNumber    = 0.3\n\
             NumberOfParticles   = 0\nGravityBoundaryType = 0\n\
             Pointer: Grid[{id}]->NextGridThisLevel = 0\n"
        ));

        let file = &files[if id == 1 { 0 } else { 1 }];
        let group = file.create_group(&format!("Grid{id:08}")).expect("group");
        for (i, label) in ["Density", "TotalEnergy"].iter().enumerate() {
            if id == 3 && i == 1 && opt.omit_energy_of_grid3 {
                continue;
            }
            let g = if id == 1 { ghost } else { 0 };
            let full = [n[0] + 2 * g, n[1] + 2 * g, n[2] + 2 * g];
            let mut data = Vec::new();
            for z in 0..full[2] {
                for y in 0..full[1] {
                    for x in 0..full[0] {
                        let a = [x - g, y - g, z - g];
                        if (0..3).all(|d| (0..n[d]).contains(&a[d])) {
                            let c: [i32; 3] = std::array::from_fn(|d| corner[d] + a[d] * w);
                            data.push(value(c, exa, i));
                        } else {
                            data.push(-99.0);
                        }
                    }
                }
            }
            let shape = [full[2] as usize, full[1] as usize, full[0] as usize];
            write(&group, label, &shape, &data);
        }
        // A particle dataset the reader must not take for a field.
        write(&group, "particle_mass", &[1], &[1.0f64]);
    }
    std::fs::write(dd.join("data0003.hierarchy"), hierarchy).expect("write hierarchy");
    drop(files);
    if opt.omit_cpu1 {
        std::fs::remove_file(dd.join("data0003.cpu0001")).expect("remove cpu0001");
    }
    base
}

#[test]
fn enzo_three_levels_leaf_cells() {
    let dir = TempDir::new("enzo");
    let opt = EnzoOptions {
        levels: true,
        ..Default::default()
    };
    let path = write_enzo(&dir, &opt);
    let data = read_enzo(&path).expect("read Enzo");
    check_cells(&data, 16, &["Density", "TotalEnergy"], enzo_leaf);
    assert_eq!(data.origin, [-1.0; 3]);
    assert_eq!(data.finest_cell_size, 0.125);
    assert_eq!(data.time, Some(0.75));
}

#[test]
fn enzo_levels_deduced_from_cell_width() {
    let dir = TempDir::new("enzo-nolevel");
    let path = write_enzo(&dir, &EnzoOptions::default());
    let data = read_enzo(&path).expect("read Enzo");
    check_cells(&data, 16, &["Density", "TotalEnergy"], enzo_leaf);
}

#[test]
fn enzo_missing_grid_file_is_refused() {
    let dir = TempDir::new("enzo-nofile");
    let opt = EnzoOptions {
        omit_cpu1: true,
        ..Default::default()
    };
    let path = write_enzo(&dir, &opt);
    let (at, message) = format_error(read_enzo(&path));
    assert!(at.ends_with("DD0003/data0003.cpu0001"), "{}", at.display());
    assert!(message.contains("grid file is missing"), "{message}");
}

#[test]
fn enzo_missing_field_dataset_is_refused() {
    let dir = TempDir::new("enzo-nofield");
    let opt = EnzoOptions {
        omit_energy_of_grid3: true,
        ..Default::default()
    };
    let path = write_enzo(&dir, &opt);
    let (at, message) = format_error(read_enzo(&path));
    assert!(at.ends_with("data0003.cpu0001"), "{}", at.display());
    assert!(
        message.contains("dataset /Grid00000003/TotalEnergy is missing"),
        "{message}"
    );
}

#[test]
fn enzo_unknown_field_is_refused() {
    let dir = TempDir::new("enzo-label");
    let opt = EnzoOptions {
        extra_label: true,
        ..Default::default()
    };
    let path = write_enzo(&dir, &opt);
    let (_, message) = format_error(read_enzo(&path));
    assert!(
        message.contains("dataset /Grid00000001/Temperature is missing"),
        "{message}"
    );
}

#[test]
fn enzo_improper_nesting_is_refused() {
    let dir = TempDir::new("enzo-nesting");
    let opt = EnzoOptions {
        grid3_outside: true,
        ..Default::default()
    };
    let path = write_enzo(&dir, &opt);
    let (at, message) = format_error(read_enzo(&path));
    assert!(at.ends_with("data0003.hierarchy"), "{}", at.display());
    assert!(
        message.contains("grid 3 (level 2) is not properly nested"),
        "{message}"
    );
}

#[test]
fn enzo_missing_hierarchy_is_refused() {
    let dir = TempDir::new("enzo-nohier");
    let path = write_enzo(&dir, &EnzoOptions::default());
    std::fs::remove_file(dir.join("DD0003/data0003.hierarchy")).expect("remove");
    match read_enzo(&path) {
        Err(IoError::Io { path, .. }) => assert!(path.ends_with("data0003.hierarchy")),
        other => panic!("expected an I/O error, got {other:?}"),
    }
}

#[test]
fn enzo_malformed_hierarchy_line_is_refused() {
    let dir = TempDir::new("enzo-badline");
    let path = write_enzo(&dir, &EnzoOptions::default());
    let hierarchy = dir.join("DD0003/data0003.hierarchy");
    let text = std::fs::read_to_string(&hierarchy).expect("read hierarchy");
    let line = 1 + text
        .lines()
        .position(|l| l.starts_with("GridEndIndex"))
        .expect("GridEndIndex line");
    let text = text.replacen(
        "GridEndIndex      = 6 6 6",
        "GridEndIndex      = 6 six 6",
        1,
    );
    std::fs::write(&hierarchy, text).expect("write hierarchy");
    let (at, message) = format_error(read_enzo(&path));
    assert_eq!(at, hierarchy);
    assert!(
        message.starts_with(&format!("line {line}: GridEndIndex = 6 six 6")),
        "{message}"
    );
}

// ---------------------------------------------------------------------------
// Athena++
// ---------------------------------------------------------------------------

#[derive(Default)]
struct AthenaOptions {
    /// Also write the refined root meshblock (it overlaps its children).
    parent_too: bool,
    /// List `cons` in DatasetNames without writing it.
    omit_cons: bool,
    /// RootGridX1 ratio 1.1.
    ratio: bool,
}

/// The refined root meshblock (1, 0, 1): finest x ∈ [4, 8), y ∈ [0, 4),
/// z ∈ [4, 8).
fn athena_leaf(p: [i32; 3]) -> [i32; 4] {
    flash_leaf(p)
}

/// An Athena++ file: RootGridSize 4³ over x1 ∈ [0, 2], x2 ∈ [-1, 1],
/// x3 ∈ [1, 3] (cells 0.5 wide), MeshBlockSize 2³, root meshblock (1, 0, 1)
/// refined into 8 level-1 meshblocks (finest cells 0.25, lattice 8³).
/// Datasets `prim` (rho, press) and `cons` (dens).
fn write_athena(path: &Path, opt: &AthenaOptions) {
    let file = h5::File::create(path).expect("create athdf");
    let mut blocks: Vec<(i32, [i64; 3])> = Vec::new();
    for k in 0..2 {
        for j in 0..2 {
            for i in 0..2 {
                if [i, j, k] != [1, 0, 1] || opt.parent_too {
                    blocks.push((0, [i, j, k]));
                }
            }
        }
    }
    for c in 0..2 {
        for b in 0..2 {
            for a in 0..2 {
                blocks.push((1, [2 + a, b, 2 + c]));
            }
        }
    }
    let nb = blocks.len();
    attr(&file, "RootGridSize", &[4i32, 4, 4]);
    attr(&file, "MeshBlockSize", &[2i32, 2, 2]);
    attr(&file, "NumMeshBlocks", &[nb as i32]);
    attr(&file, "MaxLevel", &[1i32]);
    let ratio = if opt.ratio { 1.1f32 } else { 1.0 };
    attr(&file, "RootGridX1", &[0.0f32, 2.0, ratio]);
    attr(&file, "RootGridX2", &[-1.0f32, 1.0, 1.0]);
    attr(&file, "RootGridX3", &[1.0f32, 3.0, 1.0]);
    file.new_attr::<f64>()
        .shape(())
        .create("Time")
        .and_then(|a| a.write_scalar(&2.5))
        .expect("Time");
    attr(&file, "NumCycles", &[40i32]);
    attr(&file, "NumVariables", &[2i32, 1]);
    attr(
        &file,
        "DatasetNames",
        &[ascii::<20>("prim"), ascii::<20>("cons")],
    );
    attr(
        &file,
        "VariableNames",
        &[
            ascii::<20>("rho"),
            ascii::<20>("press"),
            ascii::<20>("dens"),
        ],
    );
    let levels: Vec<i32> = blocks.iter().map(|b| b.0).collect();
    let locs: Vec<i64> = blocks.iter().flat_map(|b| b.1).collect();
    write(&file, "Levels", &[nb], &levels);
    write(&file, "LogicalLocations", &[nb, 3], &locs);
    let var = |field: usize| -> Vec<f32> {
        let mut out = Vec::new();
        for (level, loc) in &blocks {
            let exa = 1 - level;
            let w = 1 << exa;
            for z in 0..2 {
                for y in 0..2 {
                    for x in 0..2 {
                        let a = [x, y, z];
                        let c: [i32; 3] = std::array::from_fn(|d| (loc[d] as i32 * 2 + a[d]) * w);
                        out.push(value(c, exa, field) as f32);
                    }
                }
            }
        }
        out
    };
    let mut prim = var(0);
    prim.extend(var(1));
    write(&file, "prim", &[2, nb, 2, 2, 2], &prim);
    if !opt.omit_cons {
        write(&file, "cons", &[1, nb, 2, 2, 2], &var(2));
    }
}

#[test]
fn athena_two_levels_leaf_cells() {
    let dir = TempDir::new("athena");
    let path = dir.join("blast.out2.00004.athdf");
    write_athena(&path, &AthenaOptions::default());
    let data = read_athena(&path).expect("read Athena++");
    check_cells(&data, 8, &["rho", "press", "dens"], athena_leaf);
    assert_eq!(data.cells.len(), 7 * 8 + 8 * 8);
    assert_eq!(data.origin, [0.0, -1.0, 1.0]);
    assert_eq!(data.finest_cell_size, 0.25);
    assert_eq!(data.time, Some(2.5));
}

#[test]
fn athena_overlapping_meshblocks_are_refused() {
    let dir = TempDir::new("athena-overlap");
    let path = dir.join("overlap.athdf");
    let opt = AthenaOptions {
        parent_too: true,
        ..Default::default()
    };
    write_athena(&path, &opt);
    let (at, message) = format_error(read_athena(&path));
    assert_eq!(at, path);
    assert!(
        message.contains("meshblock 5 (level 0) and meshblock 8 (level 1) overlap"),
        "{message}"
    );
}

#[test]
fn athena_missing_dataset_is_refused() {
    let dir = TempDir::new("athena-nocons");
    let path = dir.join("nocons.athdf");
    let opt = AthenaOptions {
        omit_cons: true,
        ..Default::default()
    };
    write_athena(&path, &opt);
    let (_, message) = format_error(read_athena(&path));
    assert!(message.contains("dataset cons is missing"), "{message}");
}

#[test]
fn athena_nonuniform_spacing_is_refused() {
    let dir = TempDir::new("athena-ratio");
    let path = dir.join("ratio.athdf");
    let opt = AthenaOptions {
        ratio: true,
        ..Default::default()
    };
    write_athena(&path, &opt);
    let (_, message) = format_error(read_athena(&path));
    assert!(message.contains("RootGridX1: ratio"), "{message}");
}

#[test]
fn readers_refuse_files_that_are_not_hdf5() {
    let dir = TempDir::new("nothdf5");
    let path = dir.join("plain.txt");
    std::fs::write(&path, "not an HDF5 file\n").expect("write");
    for result in [read_flash(&path), read_athena(&path)] {
        let (_, message) = format_error(result);
        assert!(message.contains("not an HDF5 file"), "{message}");
    }
}

// ---------------------------------------------------------------------------
// The AMRClaw frame rewritten by tools/amr_formats.py
// ---------------------------------------------------------------------------

/// Finest-lattice cell → index of the cell of `data` that covers it, on the
/// `n`³ lattice; panics unless every finest cell is covered exactly once.
fn owners(data: &AmrCellData, n: usize, what: &str) -> Vec<u32> {
    let mut owner = vec![u32::MAX; n * n * n];
    for (k, c) in data.cells.iter().enumerate() {
        let w = 1i32 << c[3];
        for z in c[2]..c[2] + w {
            for y in c[1]..c[1] + w {
                for x in c[0]..c[0] + w {
                    assert!(
                        [x, y, z].iter().all(|&v| v >= 0 && (v as usize) < n),
                        "{what}: cell {c:?} lies outside the {n}³ lattice"
                    );
                    let p = (z as usize * n + y as usize) * n + x as usize;
                    assert_eq!(owner[p], u32::MAX, "{what}: ({x}, {y}, {z}) covered twice");
                    owner[p] = k as u32;
                }
            }
        }
    }
    assert!(
        owner.iter().all(|&o| o != u32::MAX),
        "{what}: the leaves leave finest cells uncovered"
    );
    owner
}

/// The files `tools/amr_formats.py` writes from the AMRClaw frame
/// ../shared/data/amr-euler3d/fort.q0003 into the directory named by
/// `$VOXLESS_AMR_FORMATS` (skipped when unset): each reader's leaf cells
/// cover the 80³ finest lattice of [0, 2]³ exactly once, and every leaf
/// cell holds the values of the AMRClaw leaf at its centre. Enzo keeps
/// AMRClaw's grids (cut along parent edges), so its leaves are exactly
/// AMRClaw's 216,089.
#[test]
fn amr_formats_tool_output_matches_amrclaw() {
    let Some(dir) = std::env::var_os("VOXLESS_AMR_FORMATS").map(PathBuf::from) else {
        eprintln!(
            "notice: VOXLESS_AMR_FORMATS is not set; skipping (run tools/amr_formats.py \
             FORT_Q OUT_DIR and set it to OUT_DIR)"
        );
        return;
    };
    let Some(fort_q) = voxless_core::testing::shared_data("amr-euler3d/fort.q0003") else {
        return;
    };
    let claw = read_amrclaw(&fort_q).expect("read AMRClaw");
    let n = 80;
    let claw_owner = owners(&claw, n, "AMRClaw");
    type Reader = fn(&Path) -> Result<AmrCellData, IoError>;
    let formats: [(&str, Reader, &str, [&str; 5]); 3] = [
        (
            "FLASH",
            read_flash,
            "flash_hdf5_chk_0003",
            ["dens", "momx", "momy", "momz", "etot"],
        ),
        (
            "Enzo",
            read_enzo,
            "DD0003/data0003",
            [
                "Density",
                "x-momentum",
                "y-momentum",
                "z-momentum",
                "TotalEnergyDensity",
            ],
        ),
        (
            "Athena++",
            read_athena,
            "amrclaw.out1.00003.athdf",
            ["dens", "mom1", "mom2", "mom3", "Etot"],
        ),
    ];
    for (what, read, file, names) in formats {
        let data = read(&dir.join(file)).unwrap_or_else(|e| panic!("{what}: {e}"));
        let got: Vec<&str> = data.fields.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(got, names, "{what}: fields");
        assert_eq!(data.origin, [0.0; 3], "{what}: origin");
        assert!(
            (data.finest_cell_size - 0.025).abs() < 1e-12,
            "{what}: finest cell"
        );
        assert_eq!(data.time, Some(1.5), "{what}: time");
        owners(&data, n, what);
        for (k, c) in data.cells.iter().enumerate() {
            let half = (1i32 << c[3]) / 2;
            let p = [c[0] + half, c[1] + half, c[2] + half].map(|v| v as usize);
            let j = claw_owner[(p[2] * n + p[1]) * n + p[0]] as usize;
            for (i, (name, values)) in data.fields.iter().enumerate() {
                assert_eq!(
                    values[k], claw.fields[i].1[j],
                    "{what}: {name} of cell {c:?} against AMRClaw cell {:?}",
                    claw.cells[j]
                );
            }
        }
        if what == "Enzo" {
            assert_eq!(data.cells.len(), 216_089, "Enzo: leaf count");
            let mut ours = data.cells.clone();
            let mut theirs = claw.cells.clone();
            ours.sort_unstable();
            theirs.sort_unstable();
            assert_eq!(ours, theirs, "Enzo: the leaf cells are AMRClaw's");
        }
    }
}
