//! The flags every front-end shares: the same names from clap and serde,
//! and the rules they are applied by.

use std::collections::BTreeSet;
use std::path::Path;

use voxless::{KernelName, SceneDesc, SceneError, SceneFlags};

fn flags(toml: &str) -> SceneFlags {
    toml::from_str(toml).unwrap()
}

fn field(e: SceneError) -> String {
    match e {
        SceneError::Setting { field, .. } => field,
        other => panic!("expected a setting error, got {other}"),
    }
}

/// With the `clap` feature (the CLI's), clap's long flags are the names.
#[cfg(feature = "clap")]
#[test]
fn clap_knows_the_names() {
    let cmd = <SceneFlags as clap::Args>::augment_args(clap::Command::new("flags"));
    let longs: Vec<String> = cmd
        .get_arguments()
        .filter_map(|a| a.get_long())
        .map(|l| l.replace('-', "_"))
        .collect();
    assert_eq!(longs, SceneFlags::names());
}

#[test]
fn serde_knows_the_names() {
    let names: BTreeSet<String> = SceneFlags::names().into_iter().collect();
    for n in [
        "box",
        "light_dir",
        "kernel",
        "colormap_file",
        "no_packets",
        "size",
    ] {
        assert!(names.contains(n), "{n} missing from {names:?}");
    }
    // serde lists the names it knows when it refuses one.
    let err = toml::from_str::<SceneFlags>("no_such_flag = 1")
        .unwrap_err()
        .to_string();
    let listed: BTreeSet<String> = err
        .split('`')
        .skip(3)
        .step_by(2)
        .map(str::to_string)
        .collect();
    assert_eq!(listed, names, "{err}");
}

#[test]
fn flags_apply_by_the_clis_rules() {
    let cwd = Path::new("/data/run");
    let mut d = SceneDesc::default();
    flags(
        "particles = 'p.npy'\nkernel = 'm4'\nattribute = 'speed'\nradii = 'h.npy'\nambient = 0.5",
    )
    .apply(&mut d, cwd)
    .unwrap();
    let p = d.particles.as_ref().unwrap();
    assert_eq!(p.file.as_deref(), Some("/data/run/p.npy"));
    assert_eq!(p.kernel, Some(KernelName::CubicSpline));
    // A column name stays a name; a file becomes absolute.
    assert_eq!(p.attribute.as_deref(), Some("speed"));
    assert_eq!(p.radii.as_deref(), Some("/data/run/h.npy"));
    // Any light setting turns the light on.
    assert_eq!(d.light.as_ref().unwrap().ambient, Some(0.5));

    // A colormap file replaces the colours; a colormap name then picks in it.
    d.transfer.colormap = Some("viridis".into());
    d.transfer.colormap_points = Some(vec![[0.0, 0.0, 0.0, 0.0]]);
    flags("colormap_file = 'cm.json'")
        .apply(&mut d, cwd)
        .unwrap();
    assert_eq!(d.transfer.colormap, None);
    assert_eq!(d.transfer.colormap_points, None);
    assert_eq!(
        d.transfer.colormap_file.as_deref(),
        Some("/data/run/cm.json")
    );

    let mut d = SceneDesc::default();
    flags("size = [64, 32]\nbox = 2.0\nparticles = 'x.npy'")
        .apply(&mut d, cwd)
        .unwrap();
    assert_eq!((d.image.width, d.image.height), (Some(64), Some(32)));
    assert_eq!(d.tets.as_ref().unwrap().box_size, Some(2.0));
    assert!(d.particles.is_none());
}

#[test]
fn bad_flags_are_errors_naming_the_flag() {
    let cwd = Path::new(".");
    let apply = |toml: &str| flags(toml).apply(&mut SceneDesc::default(), cwd);
    assert_eq!(field(apply("eye = [1.0, 2.0]").unwrap_err()), "eye");
    assert_eq!(field(apply("size = [1, 2, 3]").unwrap_err()), "size");
    assert_eq!(
        field(apply("box = 1.0\nkernel = 'm4'").unwrap_err()),
        "kernel"
    );
    assert_eq!(
        field(apply("log = true\nlinear = true").unwrap_err()),
        "log"
    );
    // The data flags, as opposed to the view's.
    assert_eq!(
        flags("kernel = 'm4'\ncolormap = 'magma'\nlod = 2.0\nfield = 'rho'").data_flags(),
        ["kernel", "lod", "field"]
    );
}

#[test]
fn data_names_are_flag_names() {
    let names = SceneFlags::names();
    for n in SceneFlags::data_names() {
        assert!(names.iter().any(|m| m == n), "{n}");
    }
    assert!(SceneFlags::data_names().contains(&"box"));
    assert!(!SceneFlags::data_names().contains(&"colormap"));
}
