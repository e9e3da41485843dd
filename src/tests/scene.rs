use std::path::Path;

use crate::load::table as load;
use crate::{Scene, SceneDesc, formats, read_scene};

/// Loads and resolves frame 0 of `desc`.
fn resolve(desc: &SceneDesc, base: &Path) -> Result<Scene, crate::SceneError> {
    Scene::open(desc, base, 0)
}

#[test]
fn example_scenes_parse() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    assert!(
        read_scene(&dir.join("galaxy.toml"))
            .unwrap()
            .particles
            .is_some()
    );
    let amr = read_scene(&dir.join("amr-euler3d.toml")).unwrap();
    assert_eq!(amr.render.iso, Some(vec![1.1, 2.0]));
    assert!(amr.amr.unwrap().amrclaw.is_some());
    let dm = read_scene(&dir.join("dark-matter.toml")).unwrap();
    assert_eq!(dm.tets.unwrap().lagrangian, Some(64));
}

#[test]
fn unknown_keys_are_errors_naming_the_file() {
    let dir = std::env::temp_dir().join(format!("voxless-scene-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("typo.toml");
    std::fs::write(&path, "[particles]\nfiel = \"x.npy\"\n").unwrap();
    let e = read_scene(&path).unwrap_err().to_string();
    assert!(e.contains("typo.toml") && e.contains("fiel"), "{e}");
}

#[test]
fn missing_data_source_is_explained() {
    let e = resolve(&SceneDesc::default(), Path::new("."))
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("--particles"), "{e}");
}

#[test]
fn particle_formats_by_extension_name_and_content() {
    use formats::ParticleFormat as F;
    let dir = std::env::temp_dir().join(format!("voxless-formats-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let write = |name: &str, text: &[u8]| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
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
        let path = write(name, bytes);
        assert_eq!(F::detect(&path).unwrap(), want, "{name}");
    }
    assert!(F::detect(&dir.join("missing.dat")).is_err());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn columns_species_and_unknown_names() {
    let dir = std::env::temp_dir().join(format!("voxless-columns-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("p.csv");
    std::fs::write(&path, "x,y,z,Temp,type\n0,0,0,1,1\n1,0,0,2,2\n0,1,0,3,1\n").unwrap();
    let select = load::Selection {
        species: Some("1"),
        ..Default::default()
    };
    let (positions, source, _) = load::open(&path, 0, &select).unwrap();
    assert_eq!(positions.len(), 2);
    let (temp, _) = load::read_per_particle("temp", &dir, &source, 2, "attribute").unwrap();
    assert_eq!(temp, [1.0, 3.0]);
    let e = load::read_per_particle("pressure", &dir, &source, 2, "attribute")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("pressure") && e.contains("x, y, z, Temp, type"),
        "{e}"
    );
    let select = load::Selection {
        species: Some("7"),
        ..Default::default()
    };
    let e = load::open(&path, 0, &select).err().unwrap().to_string();
    assert!(e.contains("type 7") && e.contains("1, 2"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
