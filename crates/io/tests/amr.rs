//! AMR cell readers: ExaBricks `.cells`/`.scalars` and AMRClaw `fort.q`.

use std::collections::HashSet;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use voxless_io::{AmrCellData, IoError, read_amrclaw, read_exabricks};

/// A fresh directory in the system temp dir, removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new(name: &str) -> TempDir {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let dir =
            std::env::temp_dir().join(format!("voxless-io-amr-{}-{n}-{name}", std::process::id()));
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

/// The Format message of an error, checking that the error names `file`.
fn format_message(file: &Path, result: Result<AmrCellData, IoError>) -> String {
    let err = result.expect_err("expected an error");
    assert!(
        err.to_string().contains(&file.display().to_string()),
        "{err}"
    );
    match err {
        IoError::Format { message, .. } => message,
        other => panic!("expected a Format error, got {other:?}"),
    }
}

fn cell_bytes(cells: &[[i32; 4]]) -> Vec<u8> {
    cells
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect()
}

fn scalar_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

const CELLS: [[i32; 4]; 3] = [[0, 0, 0, 1], [2, 0, 0, 0], [-4, 6, 8, 2]];

#[test]
fn exabricks_with_meta() {
    let dir = TempDir::new("exa");
    let cells = dir.write("frame3.cells", cell_bytes(&CELLS));
    let density = dir.write("frame3.density.scalars", scalar_bytes(&[1.0, 2.5, -3.0]));
    let other = dir.write("rho.scalars", scalar_bytes(&[4.0, 5.0, 6.0]));
    dir.write(
        "frame3.meta.json",
        r#"{"origin": [1.5, -2, 0.25], "finest_cell_size": 0.025, "time": 0.5, "levels": 3}"#,
    );
    let data = read_exabricks(&cells, &[density, other]).unwrap();
    assert_eq!(data.cells, CELLS);
    assert_eq!(data.fields.len(), 2);
    assert_eq!(data.field("density").unwrap(), [1.0, 2.5, -3.0]);
    assert_eq!(data.field("rho").unwrap(), [4.0, 5.0, 6.0]);
    assert_eq!(data.origin, [1.5, -2.0, 0.25]);
    assert_eq!(data.finest_cell_size, 0.025);
    assert_eq!(data.time, Some(0.5));
}

#[test]
fn exabricks_without_meta_or_fields() {
    let dir = TempDir::new("exa-plain");
    let cells = dir.write("a.cells", cell_bytes(&CELLS));
    let data = read_exabricks(&cells, &[]).unwrap();
    assert_eq!(data.cells.len(), 3);
    assert!(data.fields.is_empty());
    assert_eq!(data.origin, [0.0; 3]);
    assert_eq!(data.finest_cell_size, 1.0);
    assert_eq!(data.time, None);
    // An empty file is zero cells, not an error.
    let empty = dir.write("empty.cells", []);
    assert!(read_exabricks(&empty, &[]).unwrap().cells.is_empty());
}

#[test]
fn exabricks_bad_inputs() {
    let dir = TempDir::new("exa-bad");
    let mut bytes = cell_bytes(&CELLS);
    bytes.truncate(40);
    let truncated = dir.write("t.cells", &bytes);
    let message = format_message(&truncated, read_exabricks(&truncated, &[]));
    assert!(message.contains("multiple of 16"), "{message}");

    let cells = dir.write("f.cells", cell_bytes(&CELLS));
    let short = dir.write("f.rho.scalars", scalar_bytes(&[1.0, 2.0]));
    let err = read_exabricks(&cells, std::slice::from_ref(&short)).unwrap_err();
    let text = err.to_string();
    assert!(text.contains(&short.display().to_string()), "{text}");
    assert!(text.contains(&cells.display().to_string()), "{text}");
    assert!(
        text.contains("2 values") && text.contains("3 cells"),
        "{text}"
    );

    let odd = dir.write("f.odd.scalars", [0u8; 13]);
    let message = format_message(&odd, read_exabricks(&cells, std::slice::from_ref(&odd)));
    assert!(message.contains("multiple of 4"), "{message}");

    for level in [-1, 31] {
        let bad = dir.write("l.cells", cell_bytes(&[[0, 0, 0, 0], [0, 0, 0, level]]));
        let message = format_message(&bad, read_exabricks(&bad, &[]));
        assert!(
            message.contains("cell 1") && message.contains("level"),
            "{message}"
        );
    }

    let good = dir.write("f.rho.scalars", scalar_bytes(&[1.0, 2.0, 3.0]));
    let message = format_message(&good, read_exabricks(&cells, &[good.clone(), good.clone()]));
    assert!(message.contains("`rho`"), "{message}");

    let meta = dir.write(
        "f.meta.json",
        r#"{"origin": [0, 0], "finest_cell_size": 1}"#,
    );
    let message = format_message(&meta, read_exabricks(&cells, &[]));
    assert!(message.contains("origin"), "{message}");
    dir.write(
        "f.meta.json",
        r#"{"origin": [0, 0, 0], "finest_cell_size": -1}"#,
    );
    let message = format_message(&meta, read_exabricks(&cells, &[]));
    assert!(message.contains("finest_cell_size"), "{message}");
    dir.write("f.meta.json", "{not json");
    let message = format_message(&meta, read_exabricks(&cells, &[]));
    assert!(message.contains("JSON"), "{message}");

    let missing = dir.0.join("missing.cells");
    assert!(matches!(
        read_exabricks(&missing, &[]),
        Err(IoError::Io { .. })
    ));
}

/// `v` the way Fortran's `E` edit descriptor writes it: `0.1234000000000000E+04`.
fn fortran_e(v: f64) -> String {
    if v == 0.0 {
        return "0.0000000000000000E+00".into();
    }
    let sci = format!("{:.15e}", v.abs());
    let (mantissa, exponent) = sci.split_once('e').unwrap();
    let digits: String = mantissa.chars().filter(char::is_ascii_digit).collect();
    let exponent: i32 = exponent.parse::<i32>().unwrap() + 1;
    let sign = if v < 0.0 { "-" } else { " " };
    format!(
        "{sign}0.{digits}E{}{:02}",
        if exponent < 0 { '-' } else { '+' },
        exponent.abs()
    )
}

/// One AMRClaw grid as text, with the blank lines AMRClaw puts after every
/// x row and every z slice. Values: `value(x, y, z)` per cell.
struct GridSpec {
    number: i32,
    level: i32,
    n: [usize; 3],
    low: [f64; 3],
    dx: [f64; 3],
}

fn write_grid(out: &mut String, g: &GridSpec, value: impl Fn(usize, usize, usize) -> Vec<f64>) {
    let ints = [
        (g.number, "grid_number"),
        (g.level, "AMR_level"),
        (g.n[0] as i32, "mx"),
        (g.n[1] as i32, "my"),
        (g.n[2] as i32, "mz"),
    ];
    for (v, name) in ints {
        writeln!(out, "{v:6}                 {name}").unwrap();
    }
    let floats = [
        (g.low[0], "xlow"),
        (g.low[1], "ylow"),
        (g.low[2], "zlow"),
        (g.dx[0], "dx"),
        (g.dx[1], "dy"),
        (g.dx[2], "dz"),
    ];
    for (v, name) in floats {
        writeln!(out, "   {}    {name}", fortran_e(v)).unwrap();
    }
    out.push('\n');
    for z in 0..g.n[2] {
        for y in 0..g.n[1] {
            for x in 0..g.n[0] {
                for v in value(x, y, z) {
                    write!(out, "   {}", fortran_e(v)).unwrap();
                }
                out.push('\n');
            }
            out.push_str("  \n");
        }
        out.push_str("  \n");
    }
}

fn fort_t(time: f64, meqn: usize, ngrids: usize, ndim: usize) -> String {
    format!(
        "    {}    time\n{meqn:6}                 meqn\n{ngrids:6}                 ngrids\n     0                 naux\n{ndim:6}                 ndim\n     2                 nghost\n  ascii                format\n\n",
        fortran_e(time)
    )
}

/// A two-level frame: a 4³ coarse grid (dx 0.5, lower corner -1) and a 2³
/// fine grid (dx 0.25) covering exactly coarse cell (1, 1, 1). Two fields:
/// q0 = 1000·grid + cell index, q1 = -0.5·x + 2.25·z.
fn two_level_text() -> String {
    let mut text = String::new();
    let coarse = GridSpec {
        number: 1,
        level: 1,
        n: [4, 4, 4],
        low: [-1.0; 3],
        dx: [0.5; 3],
    };
    write_grid(&mut text, &coarse, |x, y, z| {
        let i = x + 4 * (y + 4 * z);
        vec![1000.0 + i as f64, -0.5 * x as f64 + 2.25 * z as f64]
    });
    let fine = GridSpec {
        number: 7,
        level: 2,
        n: [2, 2, 2],
        low: [-0.5; 3],
        dx: [0.25; 3],
    };
    write_grid(&mut text, &fine, |x, y, z| {
        let i = x + 2 * (y + 2 * z);
        vec![7000.0 + i as f64, -0.5 * x as f64 + 2.25 * z as f64]
    });
    text
}

fn check_two_level(data: &AmrCellData) {
    assert_eq!(data.cells.len(), 63 + 8);
    assert_eq!(data.origin, [-1.0; 3]);
    assert_eq!(data.finest_cell_size, 0.25);
    assert_eq!(data.fields.len(), 2);
    assert_eq!(data.fields[0].0, "q0");
    assert_eq!(data.fields[1].0, "q1");
    let q0 = data.field("q0").unwrap();
    let q1 = data.field("q1").unwrap();
    // Coarse cells first, in x-fastest order, without the covered (1,1,1).
    assert_eq!(data.cells[0], [0, 0, 0, 1]);
    assert_eq!(data.cells[1], [2, 0, 0, 1]);
    assert!(!data.cells.contains(&[2, 2, 2, 1]));
    assert!(!q0.contains(&(1000.0 + 21.0)));
    let volume: i64 = data.cells.iter().map(|c| 1i64 << (3 * c[3])).sum();
    assert_eq!(volume, 8 * 8 * 8, "cells tile the domain exactly once");
    for (c, (&a, &b)) in data.cells.iter().zip(q0.iter().zip(q1)) {
        let (grid, w, n) = if c[3] == 1 {
            (1000, 2, 4)
        } else {
            (7000, 1, 2)
        };
        let offset = if c[3] == 1 { 0 } else { 2 };
        let [x, y, z] = [0, 1, 2].map(|k| ((c[k] - offset) / w) as usize);
        assert_eq!(a, (grid + x + n * (y + n * z)) as f32, "{c:?}");
        assert_eq!(b, (-0.5 * x as f64 + 2.25 * z as f64) as f32, "{c:?}");
    }
    let fine: Vec<_> = data.cells.iter().filter(|c| c[3] == 0).collect();
    assert_eq!(fine.len(), 8);
    assert_eq!(*fine[0], [2, 2, 2, 0]);
    assert_eq!(*fine[7], [3, 3, 3, 0]);
}

#[test]
fn amrclaw_two_levels() {
    let dir = TempDir::new("claw");
    let q = dir.write("fort.q0004", two_level_text());
    dir.write("fort.t0004", fort_t(0.75, 2, 2, 3));
    let data = read_amrclaw(&q).unwrap();
    check_two_level(&data);
    assert_eq!(data.time, Some(0.75));
}

#[test]
fn amrclaw_without_fort_t() {
    let dir = TempDir::new("claw-no-t");
    let q = dir.write("fort.q0001", two_level_text());
    let data = read_amrclaw(&q).unwrap();
    check_two_level(&data);
    assert_eq!(data.time, None);
    // Any name works without fort.t.
    let renamed = dir.write("frame.txt", two_level_text().replace('\n', "\r\n"));
    check_two_level(&read_amrclaw(&renamed).unwrap());
}

#[test]
fn amrclaw_fortran_numbers() {
    // D exponents, lower case, and a three-digit exponent without a letter.
    let text = "1 grid_number\n1 AMR_level\n2 mx\n1 my\n1 mz\n0.0D+00 xlow\n0.0 ylow\n0.0 zlow\n\
                0.5D0 dx\n0.5d0 dy\n5.0E-1 dz\n\n 0.1D+01 -0.25d-1 0.1-100\n 1.5 +2E+00 -0.3+101\n";
    let dir = TempDir::new("claw-fortran");
    let q = dir.write("fort.q0000", text);
    let data = read_amrclaw(&q).unwrap();
    assert_eq!(data.cells, [[0, 0, 0, 0], [1, 0, 0, 0]]);
    assert_eq!(data.finest_cell_size, 0.5);
    assert_eq!(data.field("q0").unwrap(), [1.0, 1.5]);
    assert_eq!(data.field("q1").unwrap(), [-0.025, 2.0]);
    let q2 = data.field("q2").unwrap();
    assert_eq!(q2[0], 0.0, "1e-101 underflows f32");
    assert_eq!(q2[1], f32::NEG_INFINITY, "-3e100 overflows f32");
}

#[test]
fn amrclaw_refinement_ratio_four() {
    // Levels 1 and 2 with ratio 4: AMR level 2 becomes cell level 0.
    let mut text = String::new();
    let coarse = GridSpec {
        number: 1,
        level: 1,
        n: [2, 1, 1],
        low: [0.0; 3],
        dx: [1.0; 3],
    };
    write_grid(&mut text, &coarse, |x, _, _| vec![x as f64]);
    let fine = GridSpec {
        number: 2,
        level: 2,
        n: [4, 4, 4],
        low: [1.0, 0.0, 0.0],
        dx: [0.25; 3],
    };
    write_grid(&mut text, &fine, |x, y, z| vec![(x + y + z) as f64 + 10.0]);
    let dir = TempDir::new("claw-r4");
    let q = dir.write("fort.q0000", text);
    let data = read_amrclaw(&q).unwrap();
    assert_eq!(data.cells.len(), 1 + 64);
    assert_eq!(data.cells[0], [0, 0, 0, 2]);
    assert_eq!(data.cells[1], [4, 0, 0, 0]);
    assert_eq!(data.field("q0").unwrap()[0], 0.0);
}

#[test]
fn amrclaw_bad_inputs() {
    let dir = TempDir::new("claw-bad");
    let good = two_level_text();

    // Truncated inside the fine grid: names the grid and the last line.
    let cut = &good[..good.len() - 300];
    let q = dir.write("fort.q0001", cut);
    let message = format_message(&q, read_amrclaw(&q));
    assert!(
        message.contains("grid 7") && message.contains("line") && message.contains("truncated"),
        "{message}"
    );
    // Truncated in the middle of the coarse grid, so the fine grid's header
    // is read as data.
    let header = good.find("     7                 grid_number").unwrap();
    let cut = good[..header - 2000].rfind('\n').unwrap() + 1;
    let spliced = format!("{}{}", &good[..cut], &good[header..]);
    let q = dir.write("fort.q0002", &spliced);
    let message = format_message(&q, read_amrclaw(&q));
    assert!(
        message.contains("grid 1") && message.contains("grid_number"),
        "{message}"
    );

    // Refinement ratio 3.
    // (The fine grid now has the smallest dx, so the coarse grid is the bad one.)
    let ratio3 = good.replace("0.2500000000000000E+00", "0.1666666666666667E+00");
    let q = dir.write("fort.q0003", ratio3);
    let message = format_message(&q, read_amrclaw(&q));
    assert!(
        message.contains("power of two") && message.contains("grid 1"),
        "{message}"
    );

    // dy differs from dx.
    let mut lines: Vec<&str> = good.lines().collect();
    lines[9] = "    0.2500000000000000E+00    dy";
    let q = dir.write("fort.q0004", lines.join("\n"));
    let message = format_message(&q, read_amrclaw(&q));
    assert!(
        message.contains("dy") && message.contains("grid 1"),
        "{message}"
    );

    // fort.t says 2D, or more grids than there are.
    let q = dir.write("fort.q0005", &good);
    let t = dir.write("fort.t0005", fort_t(0.0, 2, 2, 2));
    let message = format_message(&t, read_amrclaw(&q));
    assert!(message.contains("ndim"), "{message}");
    dir.write("fort.t0005", fort_t(0.0, 2, 3, 3));
    let message = format_message(&q, read_amrclaw(&q));
    assert!(
        message.contains("2 grids") && message.contains("3"),
        "{message}"
    );
    // fort.t with the wrong meqn: rows do not line up with the header.
    dir.write("fort.t0005", fort_t(0.0, 3, 2, 3));
    let message = format_message(&q, read_amrclaw(&q));
    assert!(message.contains("grid"), "{message}");

    // A header that declares far more cells than the file holds.
    let huge = good.replacen("     4                 mx", "2000000000 mx", 1);
    let q = dir.write("fort.q0006", huge);
    let message = format_message(&q, read_amrclaw(&q));
    assert!(message.contains("more than the file"), "{message}");

    // Garbage, an empty file, a bad number, a wrong header name.
    for (name, text) in [
        ("fort.q0007", "\u{0}\u{1} binary"),
        ("fort.q0008", ""),
        ("fort.q0009", "x grid_number\n"),
        (
            "fort.q0010",
            "1 grid_number\n1 AMR_level\n4 mx\n4 my\n0.0 xlow\n",
        ),
    ] {
        let q = dir.write(name, text);
        format_message(&q, read_amrclaw(&q));
    }
    let bad_number = good.replacen("0.1000000000000000E+04", "0.10000x0000000000E+04", 1);
    let q = dir.write("fort.q0011", bad_number);
    let message = format_message(&q, read_amrclaw(&q));
    assert!(message.contains("0.10000x"), "{message}");
}

/// The shared real-data directory, or `None` (with a notice) if absent.
fn real_data() -> Option<PathBuf> {
    voxless_core::testing::shared_data("amr-euler3d")
}

/// The two files hold the same cells with the same values (within 1 ulp).
fn compare_frame(frame: u32, expected_cells: Option<usize>) {
    let Some(dir) = real_data() else { return };
    let start = std::time::Instant::now();
    let claw = read_amrclaw(&dir.join(format!("fort.q{frame:04}"))).unwrap();
    println!(
        "fort.q{frame:04}: {} cells in {:?}",
        claw.cells.len(),
        start.elapsed()
    );
    let names = [
        "density",
        "momentum_x",
        "momentum_y",
        "momentum_z",
        "energy",
    ];
    let exa_dir = dir.join("exabricks");
    let scalars: Vec<PathBuf> = names
        .iter()
        .map(|n| exa_dir.join(format!("frame{frame}.{n}.scalars")))
        .collect();
    let exa = read_exabricks(&exa_dir.join(format!("frame{frame}.cells")), &scalars).unwrap();

    if let Some(n) = expected_cells {
        assert_eq!(claw.cells.len(), n);
    }
    assert_eq!(claw.cells.len(), exa.cells.len());
    assert_eq!(claw.finest_cell_size, 0.025);
    assert_eq!(exa.finest_cell_size, 0.025);
    assert_eq!(claw.origin, [0.0; 3]);
    assert_eq!(exa.origin, [0.0; 3]);
    assert!(claw.time.is_some());
    assert_eq!(claw.fields.len(), 5);

    // The leaf cells cover the 80³ finest lattice exactly once.
    let volume: i64 = claw.cells.iter().map(|c| 1i64 << (3 * c[3])).sum();
    assert_eq!(volume, 80 * 80 * 80);
    let unique: HashSet<[i32; 4]> = claw.cells.iter().copied().collect();
    assert_eq!(unique.len(), claw.cells.len());

    let rows = |d: &AmrCellData, fields: [&str; 5]| {
        let columns = fields.map(|f| d.field(f).unwrap());
        let mut rows: Vec<([i32; 4], [f32; 5])> = d
            .cells
            .iter()
            .enumerate()
            .map(|(i, &c)| (c, columns.map(|col| col[i])))
            .collect();
        rows.sort_by_key(|r| r.0);
        rows
    };
    let a = rows(&claw, ["q0", "q1", "q2", "q3", "q4"]);
    let b = rows(&exa, names);
    let mut inexact = 0;
    for (ra, rb) in a.iter().zip(&b) {
        assert_eq!(ra.0, rb.0);
        for (f, (&va, &vb)) in ra.1.iter().zip(&rb.1).enumerate() {
            let ulps = (va.to_bits() as i64 - vb.to_bits() as i64).abs();
            assert!(
                va == vb || ulps <= 1,
                "cell {:?} field {f}: {va} vs {vb}",
                ra.0
            );
            inexact += usize::from(va.to_bits() != vb.to_bits());
        }
    }
    println!("frame {frame}: {inexact} values differ by 1 ulp");
}

#[test]
fn real_frame_3_matches_exabricks() {
    compare_frame(3, Some(216_089));
}

#[test]
fn real_frame_2_matches_exabricks() {
    compare_frame(2, None);
}

/// Cells whose coordinates reach past ±2³⁰ finest cells (a corrupt file, or
/// one near i32::MAX that would wrap around downstream) are an error naming
/// the file and the cell, not a render that blames the camera.
#[test]
fn exabricks_cells_near_the_i32_limit_are_refused_by_name() {
    let cell = |x: i32, level: i32| -> Vec<u8> {
        [x, 0, 0, level]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect()
    };
    let mut bytes = cell(0, 0);
    bytes.extend(cell(i32::MAX - 1, 2));
    let values: Vec<u8> = [1.0f32, 2.0].iter().flat_map(|v| v.to_le_bytes()).collect();
    let e = voxless_io::read_exabricks_bytes(
        &bytes,
        std::path::Path::new("big.cells"),
        &[("rho", &values)],
        None,
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("big.cells") && e.contains("cell 1") && e.contains("2^30"),
        "{e}"
    );
    // The largest coordinates allowed read.
    let mut ok = cell(0, 0);
    ok.extend(cell((1 << 30) - 4, 2));
    assert!(
        voxless_io::read_exabricks_bytes(
            &ok,
            std::path::Path::new("ok.cells"),
            &[("rho", &values)],
            None
        )
        .is_ok()
    );
}
