//! Format detection from a path against detection from (name, bytes), and
//! the table dispatch from a path against the dispatch from a reader.

use std::io::Cursor;
use std::path::Path;

use voxless_io::format::{
    self, ParticleFormat as F, SNIFF_LEN, TableOptions, frames_in, frames_in_from, read_table,
    read_table_from,
};

use super::{Sample, Tally, TempDir, files_in, seeds, variants};

/// Every sample file of every format, under its own name: the fuzz seeds,
/// the VTK and HDF5 test files, and small files named by the rules the
/// detection knows (`dump.*`, text table extensions, no extension).
fn samples() -> Vec<Sample> {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let mut all = Vec::new();
    for target in [
        "npy",
        "csv",
        "lammps",
        "xyz",
        "particles",
        "vtk_points",
        "amrclaw",
    ] {
        all.extend(seeds(target));
    }
    all.extend(files_in(&data.join("vtk")));
    all.extend(files_in(&data.join("hdf5")));
    let dump = seeds("lammps")[1].1.clone();
    let xyz = seeds("xyz")[1].1.clone();
    let npy = seeds("npy")[0].1.clone();
    for (name, bytes) in [
        ("dump.melt", dump.clone()),
        ("RUN.LAMMPSTRJ", dump.clone()),
        ("table.txt", dump.clone()),
        ("table.tsv", xyz.clone()),
        ("frames", xyz.clone()),
        ("array.bin", npy.clone()),
        ("A.NPY", npy),
        ("noext", b"x y z\n1 2 3\n".to_vec()),
        (
            "bom.dat",
            b"\xef\xbb\xbf  <VTKFile type=\"PolyData\">".to_vec(),
        ),
        ("hdf.dat", b"\x89HDF\r\n\x1a\n".to_vec()),
        ("empty.dat", Vec::new()),
        ("a.particles", b"0\n".to_vec()),
        // The count line is past the sniffed bytes.
        ("late.dat", [vec![b' '; SNIFF_LEN], xyz].concat()),
    ] {
        all.push((name.to_string(), bytes));
    }
    all
}

#[test]
fn detection_from_bytes_matches_path() {
    let dir = TempDir::new("detect");
    let mut seen = Vec::new();
    for (name, bytes) in samples() {
        let path = dir.write(&name, &bytes);
        let from_path = F::detect(&path).unwrap();
        // The first bytes, or all of them: the same answer.
        let head = &bytes[..bytes.len().min(SNIFF_LEN)];
        assert_eq!(from_path, F::detect_bytes(&path, head), "{name}");
        assert_eq!(
            from_path,
            F::detect_bytes(Path::new(&name), &bytes),
            "{name}"
        );
        seen.push(from_path);
        std::fs::remove_file(&path).unwrap();
    }
    for format in [
        F::Npy,
        F::Csv,
        F::Vtk,
        F::Xyz,
        F::Lammps,
        F::Particles,
        F::Hdf5,
    ] {
        assert!(seen.contains(&Some(format)), "no sample of {format:?}");
    }
    assert!(seen.contains(&None));
    // Content detection needs the file; the name alone needs nothing.
    assert!(F::detect(&dir.path("missing.dat")).is_err());
    assert_eq!(F::detect(&dir.path("missing.npy")).unwrap(), Some(F::Npy));
}

#[test]
fn detection_by_name_and_content() {
    let dump = b"ITEM: TIMESTEP\n0\n";
    for (name, bytes, want) in [
        ("a.npy", &b"x"[..], Some(F::Npy)),
        ("a.VTP", b"x", Some(F::Vtk)),
        ("a.extxyz", b"x", Some(F::Xyz)),
        ("dump.melt", b"x", Some(F::Lammps)),
        ("run.lammpstrj", b"x", Some(F::Lammps)),
        ("a.particles", b"x", Some(F::Particles)),
        ("a.h5", b"x", Some(F::Hdf5)),
        ("a.csv", b"x,y,z\n1,2,3\n", Some(F::Csv)),
        ("a.txt", dump, Some(F::Lammps)),
        ("noext", dump, Some(F::Lammps)),
        ("a.dat", b"\x89HDF\r\n\x1a\n", Some(F::Hdf5)),
        ("b.dat", b"\x93NUMPY", Some(F::Npy)),
        ("c.dat", b"<?xml version=\"1.0\"?>\n<VTKFile", Some(F::Vtk)),
        ("d.dat", b"2\ncomment\nO 0 0 0\n", Some(F::Xyz)),
        ("e.dat", b"x y z\n1 2 3\n", None),
    ] {
        assert_eq!(F::detect_bytes(Path::new(name), bytes), want, "{name}");
    }
    assert_eq!(F::from_name(Path::new("dir/DUMP.x")), Some(F::Lammps));
    assert_eq!(F::from_name(Path::new("a.csv")), None);
}

#[test]
fn table_dispatch_from_reader_matches_path() {
    let dir = TempDir::new("tables");
    let opts = TableOptions::default();
    let mut tally = Tally::default();
    let mut samples = samples();
    // Tables without positions, and arrays of the wrong shape.
    samples.push(("nox.csv".into(), b"a,y,z\n1,2,3\n".to_vec()));
    for (name, bytes) in samples {
        for (v, bytes) in variants(&bytes).iter().enumerate() {
            let path = dir.write(&name, bytes);
            let Some(format) = F::detect(&path).unwrap() else {
                continue;
            };
            if matches!(format, F::Particles | F::Hdf5) {
                continue;
            }
            let what = format!("{name} variant {v} as {format:?}");
            tally.same(
                &what,
                frames_in(&path, format),
                frames_in_from(bytes.as_slice(), &path, format),
            );
            for frame in 0..2 {
                tally.same(
                    &format!("{what} frame {frame}"),
                    read_table(&path, format, frame, &opts).map(|t| (t.table, t.note)),
                    read_table_from(Cursor::new(bytes), &path, format, frame, &opts)
                        .map(|t| (t.table, t.note)),
                );
            }
        }
    }
    tally.check_both("tables");
}

#[test]
fn table_options_and_unsupported_sources() {
    let name = Path::new("p.csv");
    let csv = b"x,y,z\n1,2,3\n";
    let group = TableOptions {
        group: Some("fluid".into()),
        part_type: None,
        share: None,
        ..Default::default()
    };
    let err = read_table_from(Cursor::new(csv), name, F::Csv, 0, &group)
        .err()
        .unwrap();
    assert_eq!(
        err.to_string(),
        "p.csv: particles.group (--group) applies to PySPH HDF5 output, but this is a text table"
    );
    let opts = TableOptions::default();
    let err = read_table_from(
        Cursor::new(b"0\n"),
        Path::new("s.particles"),
        F::Particles,
        0,
        &opts,
    )
    .err()
    .unwrap();
    assert!(err.to_string().contains("read_particles_from"), "{err}");
    let err = read_table_from(Cursor::new(b""), Path::new("s.h5"), F::Hdf5, 0, &opts)
        .err()
        .unwrap();
    assert!(err.to_string().starts_with("s.h5: HDF5 "), "{err}");
    assert_eq!(
        frames_in_from(&b"1\n2\n"[..], Path::new("s.particles"), F::Particles).unwrap(),
        2
    );
    assert!(format::SUPPORTED.contains(".lammpstrj"));
}

/// The HDF5 layouts through the dispatch: which part was read, and the
/// layouts it does not read as particles.
#[cfg(feature = "hdf5")]
#[test]
fn hdf5_table_dispatch() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/hdf5");
    let opts = TableOptions::default();
    let read = |name: &str, opts: &TableOptions| read_table(&data.join(name), F::Hdf5, 0, opts);

    let pysph = read("pysph_two_groups.hdf5", &opts).unwrap();
    assert!(!pysph.table.is_empty());
    let note = pysph.note.unwrap();
    assert!(note.contains("pick one with --group"), "{note}");

    let swift = read("swift_snapshot.hdf5", &opts).unwrap();
    assert!(!swift.table.is_empty());
    let note = swift.note.unwrap();
    assert!(note.starts_with("SWIFT PartType0"), "{note}");
    let type1 = TableOptions {
        group: None,
        part_type: Some(1),
        share: None,
        ..Default::default()
    };
    let gadget = read("gadget4_snapshot.hdf5", &type1).unwrap();
    assert!(!gadget.table.is_empty() && gadget.note.is_none());

    let group = TableOptions {
        group: Some("fluid".into()),
        part_type: None,
        share: None,
        ..Default::default()
    };
    let err = read("gadget4_snapshot.hdf5", &group)
        .unwrap_err()
        .to_string();
    assert!(err.ends_with("applies to PySPH output, but this is a SWIFT/Gadget snapshot"));
    let err = read("jaxpm_N4.h5", &opts).unwrap_err().to_string();
    assert!(
        err.contains("a JaxPM run: render it as a phase-space tessellation"),
        "{err}"
    );
    let err = read("other.h5", &opts).unwrap_err().to_string();
    assert!(
        err.contains("neither PySPH output nor a SWIFT/Gadget snapshot"),
        "{err}"
    );
}
