//! AMR as the codes write it, end to end: a two-level AMRClaw frame is
//! converted by `tools/amr_formats.py` into an AMReX plotfile, a FLASH
//! file, an Enzo hierarchy and an Athena++ `.athdf`; yt (the community's
//! reader) loads each, and `voxless sample --amr` at yt's leaf-cell centres
//! returns yt's density bit for bit (f32). `voxless info` names each
//! format, and an on-axis projection conserves the field's integral.
//!
//! Needs the `hdf5` feature and a Python with numpy, h5py and yt
//! (`$VOXLESS_PYTHON`, else `python3`): absent, the test skips with a
//! notice, unless `VOXLESS_REQUIRE_YT=1` (CI) makes that a failure.
#![cfg(feature = "hdf5")]

mod common;
use common::*;

use std::path::Path;
use std::process::Command;

use voxless_core::testing::prerequisite;

fn python() -> String {
    std::env::var("VOXLESS_PYTHON").unwrap_or_else(|_| "python3".into())
}

/// A frame of the Euler blast wave's layout: base 8³ over [0, 1]³ (level
/// 1), two level-2 grids, one reaching the domain's edge; 5 fields.
fn write_amrclaw(dir: &Path) -> std::path::PathBuf {
    let grids: [(usize, [usize; 3], [f64; 3], f64); 3] = [
        (1, [8, 8, 8], [0.0; 3], 0.125),
        (2, [6, 4, 8], [0.25, 0.5, 0.25], 0.0625),
        (2, [4, 4, 4], [0.75, 0.0, 0.75], 0.0625),
    ];
    let q = amrclaw_text(&grids, |_, _, p| {
        let rho = 1.0 + p[0] + 2.0 * p[1] * p[1] + 0.5 * (7.0 * p[2]).sin();
        vec![rho, p[0] - 0.5, p[1] * p[2], -p[2], 2.0 + rho * 0.25]
    });
    let path = dir.join("fort.q0004");
    std::fs::write(&path, q).unwrap();
    std::fs::write(
        dir.join("fort.t0004"),
        "    0.25000000E+00    time\n     5                 meqn\n     3                 ngrids\n     0                 naux\n     3                 ndim\n     2                 nghost\n  ascii                format\n",
    )
    .unwrap();
    path
}

/// For each format: yt's leaf-cell centres and density (f32), as the
/// acceptance check takes them.
const YT_SCRIPT: &str = r#"
import sys, json, os, numpy as np, yt
yt.set_log_level(50)
out = sys.argv[1]; man = json.load(open(f"{out}/manifest.json"))
for fmt in ("amrex", "flash", "enzo", "athena"):
    path = os.path.join(out, man[fmt]); ds = yt.load(path); ad = ds.all_data()
    field = [f for f in ds.field_list if f[1].lower() in ("density", "dens", "rho")][0]
    pts = np.stack([ad["index", c].to_value("code_length") for c in "xyz"], -1)
    np.save(f"{out}/{fmt}.pts.npy", pts); np.save(f"{out}/{fmt}.rho.npy", ad[field].v.astype(np.float32))
    open(f"{out}/{fmt}.path", "w").write(path)
"#;

#[test]
fn every_format_reads_as_yt_reads_it() {
    let py = python();
    let has = Command::new(&py)
        .args(["-c", "import numpy, h5py, yt"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !prerequisite(
        has,
        "VOXLESS_REQUIRE_YT",
        &format!("{py} with numpy, h5py and yt"),
    ) {
        return;
    }
    let s = Scratch::new("amr-formats");
    let q = write_amrclaw(&s.path(""));
    let out = s.path("fmt");
    let tool = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/amr_formats.py");
    let gen_run = Command::new(&py)
        .arg(&tool)
        .arg(&q)
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        gen_run.status.success(),
        "amr_formats.py: {}",
        String::from_utf8_lossy(&gen_run.stderr)
    );
    let yt = Command::new(&py)
        .args(["-c", YT_SCRIPT])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        yt.status.success(),
        "yt: {}",
        String::from_utf8_lossy(&yt.stderr)
    );
    for (fmt, name) in [
        ("amrex", "AMReX plotfile"),
        ("flash", "FLASH"),
        ("enzo", "Enzo"),
        ("athena", "Athena++"),
    ] {
        let path = std::fs::read_to_string(out.join(format!("{fmt}.path"))).unwrap();
        let (done, err, o) = voxless(&["info", &path]);
        let info = String::from_utf8_lossy(&o.stdout);
        assert!(done && info.contains(name), "{fmt}: {info}{err}");
        let got = out.join(format!("{fmt}.vx.npy"));
        ok(&[
            "sample",
            "--amr",
            &path,
            "--reconstruction",
            "nearest",
            "--field",
            "density",
            "--points",
            &out.join(format!("{fmt}.pts.npy")).to_string_lossy(),
            "-o",
            &got.to_string_lossy(),
        ]);
        let (shape, values) = read(&got);
        let (_, want) = read(&out.join(format!("{fmt}.rho.npy")));
        assert_eq!(shape[0], want.len(), "{fmt}: rows");
        for (i, w) in want.iter().enumerate() {
            let g = values[i * shape[1]];
            assert!(
                (g as f32).to_bits() == (*w as f32).to_bits(),
                "{fmt}: cell {i}: voxless {g} vs yt {w}"
            );
        }
        // The on-axis projection's Σ column × pixel area is the field's
        // integral (printed by the CLI beside the exact one).
        let log = ok(&[
            "project",
            "--amr",
            &path,
            "--reconstruction",
            "nearest",
            "--axis",
            "z",
            "--size",
            "96",
            "96",
            "-o",
            &s.str(&format!("{fmt}.proj.npy")),
        ]);
        let num = |key: &str| -> f64 {
            let at = log
                .find(key)
                .unwrap_or_else(|| panic!("{fmt}: no '{key}' in {log}"));
            log[at + key.len()..]
                .split(|c: char| c == ',' || c == ')' || c.is_whitespace())
                .find(|t| !t.is_empty())
                .unwrap()
                .parse()
                .unwrap()
        };
        let (sum, exact) = (num("pixel area = "), num("field dV = "));
        assert!(
            ((sum - exact) / exact).abs() < 1e-5,
            "{fmt}: Σ {sum} vs ∫ {exact}"
        );
        // A field the file does not have: named, with the ones it has.
        let e = fails(&[
            "render",
            "--amr",
            &path,
            "--field",
            "vorticity",
            "-o",
            &s.str("x.png"),
        ]);
        assert!(
            e.contains(path.as_str()) && e.contains("vorticity"),
            "{fmt}: {e}"
        );
    }
    // A plotfile missing a level directory: the missing file is named.
    let plt = std::fs::read_to_string(out.join("amrex.path")).unwrap();
    let broken = s.path("broken-plt");
    std::fs::create_dir_all(&broken).unwrap();
    for entry in std::fs::read_dir(&plt).unwrap() {
        let entry = entry.unwrap();
        if entry.file_name() == "Level_1" {
            continue;
        }
        let to = broken.join(entry.file_name());
        if entry.path().is_dir() {
            std::fs::create_dir_all(&to).unwrap();
            for f in std::fs::read_dir(entry.path()).unwrap() {
                let f = f.unwrap();
                std::fs::copy(f.path(), to.join(f.file_name())).unwrap();
            }
        } else {
            std::fs::copy(entry.path(), to).unwrap();
        }
    }
    let e = fails(&["info", &broken.to_string_lossy()]);
    assert!(e.contains("Level_1/Cell_H"), "{e}");
}
