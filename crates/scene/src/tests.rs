use super::*;

#[test]
fn example_scenes_parse() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
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
