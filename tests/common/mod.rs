//! Helpers shared by the end-to-end tests: a scratch directory, running the
//! binary, and deterministic particle sets.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;
pub use voxless_core::SmallRng as Lcg;

pub struct Scratch(pub PathBuf);

impl Scratch {
    pub fn new(name: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("voxless-test-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }
    pub fn path(&self, file: &str) -> PathBuf {
        self.0.join(file)
    }
    pub fn str(&self, file: &str) -> String {
        self.path(file).to_string_lossy().into_owned()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The `voxless` binary. It lives in its own package (crates/cli), so it is
/// built here once per test process — with this test's profile, target
/// directory and `hdf5` and `mpi` features — which is a no-op when it is
/// up to date.
pub fn bin() -> &'static Path {
    static BIN: OnceLock<PathBuf> = OnceLock::new();
    BIN.get_or_init(|| {
        let exe = std::env::current_exe().expect("test executable path");
        // target/<profile>/deps/<test>
        let profile_dir = exe
            .parent()
            .and_then(Path::parent)
            .expect("target/<profile>");
        let target_dir = profile_dir.parent().expect("target directory");
        let profile = match profile_dir.file_name().and_then(|n| n.to_str()) {
            Some("debug") | None => "dev",
            Some(other) => other,
        };
        let mut cmd = Command::new(env!("CARGO"));
        cmd.current_dir(env!("CARGO_MANIFEST_DIR"))
            .args([
                "build",
                "-q",
                "-p",
                "voxless-cli",
                "--bin",
                "voxless",
                "--profile",
            ])
            .arg(profile)
            .arg("--target-dir")
            .arg(target_dir);
        let mut features = Vec::new();
        if cfg!(feature = "hdf5") {
            features.push("voxless-cli/hdf5");
        }
        if cfg!(feature = "mpi") {
            features.push("voxless-cli/mpi");
        }
        if cfg!(feature = "gpu") {
            features.push("voxless-cli/gpu");
        }
        if !features.is_empty() {
            cmd.args(["--features", &features.join(",")]);
        }
        let status = cmd.status().expect("cargo runs");
        assert!(status.success(), "building the voxless binary failed");
        profile_dir.join(format!("voxless{}", std::env::consts::EXE_SUFFIX))
    })
}

/// Runs `voxless` with `args`; returns (success, stderr, output).
pub fn voxless(args: &[&str]) -> (bool, String, Output) {
    let out = Command::new(bin()).args(args).output().unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
        out,
    )
}

pub fn ok(args: &[&str]) -> String {
    let (success, stderr, _) = voxless(args);
    assert!(success, "voxless {args:?} failed:\n{stderr}");
    stderr
}

pub fn fails(args: &[&str]) -> String {
    let (success, stderr, _) = voxless(args);
    assert!(!success, "voxless {args:?} should have failed:\n{stderr}");
    assert!(
        !stderr.contains("panicked"),
        "voxless {args:?} panicked:\n{stderr}"
    );
    stderr
}

/// `n` random positions in the unit cube, written as N×3 float32 .npy.
pub fn write_positions(path: &Path, n: usize, seed: u64) -> Vec<[f32; 3]> {
    let mut rng = Lcg(seed);
    let p: Vec<[f32; 3]> = (0..n).map(|_| [rng.f(), rng.f(), rng.f()]).collect();
    let flat: Vec<f32> = p.iter().flatten().copied().collect();
    voxless_io::write_npy_f32(path, &[n, 3], &flat).unwrap();
    p
}

pub fn write_values(path: &Path, v: &[f32]) {
    voxless_io::write_npy_f32(path, &[v.len()], v).unwrap();
}

/// Reads a float .npy into (shape, values).
pub fn read(path: &Path) -> (Vec<usize>, Vec<f64>) {
    let a = voxless_io::read_npy(path).unwrap();
    (a.shape, a.data)
}

/// The project's real data beside the checkout, when present (a failure
/// instead of a skip under `VOXLESS_REQUIRE_DATA=1`).
#[allow(unused_imports)]
pub use voxless_core::testing::shared_data;

/// Writes float64 N×3 positions as `.npy`.
pub fn write_f64(path: &Path, p: &[[f64; 3]]) {
    let header = format!(
        "{{'descr': '<f8', 'fortran_order': False, 'shape': ({}, 3), }}",
        p.len()
    );
    let mut h = header.into_bytes();
    while (10 + h.len() + 1) % 64 != 0 {
        h.push(b' ');
    }
    h.push(b'\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend((h.len() as u16).to_le_bytes());
    bytes.extend(h);
    for q in p {
        for v in q {
            bytes.extend(v.to_le_bytes());
        }
    }
    std::fs::write(path, bytes).unwrap();
}

/// AMRClaw `fort.q` text: for each grid `(AMR level, [mx, my, mz], lower
/// corner, dx)` its header and one row per cell (x fastest) of the values
/// `row(grid, cell index, cell centre)`, as AMRClaw writes them.
pub fn amrclaw_text(
    grids: &[(usize, [usize; 3], [f64; 3], f64)],
    row: impl Fn(usize, usize, [f64; 3]) -> Vec<f64>,
) -> String {
    use std::fmt::Write as _;
    let mut q = String::new();
    for (g, (level, n, lo, dx)) in grids.iter().enumerate() {
        writeln!(q, "{:6}                 grid_number", g + 1).unwrap();
        writeln!(q, "{level:6}                 AMR_level").unwrap();
        for (v, name) in n.iter().zip(["mx", "my", "mz"]) {
            writeln!(q, "{v:6}                 {name}").unwrap();
        }
        for (v, name) in lo.iter().zip(["xlow", "ylow", "zlow"]) {
            writeln!(q, "{v:26.16E}    {name}").unwrap();
        }
        for name in ["dx", "dy", "dz"] {
            writeln!(q, "{dx:26.16E}    {name}").unwrap();
        }
        writeln!(q).unwrap();
        for c in 0..n[0] * n[1] * n[2] {
            let i = [c % n[0], (c / n[0]) % n[1], c / (n[0] * n[1])];
            let centre = [0, 1, 2].map(|a| lo[a] + (i[a] as f64 + 0.5) * dx);
            for v in row(g, c, centre) {
                write!(q, "{v:26.16E}").unwrap();
            }
            writeln!(q).unwrap();
        }
        writeln!(q).unwrap();
    }
    q
}
