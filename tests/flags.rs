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
    use voxless::flags::{DataFlags, KindFlags, ViewFlags};
    fn longs<T: clap::Args>() -> Vec<String> {
        T::augment_args(clap::Command::new("flags"))
            .get_arguments()
            .filter_map(|a| a.get_long())
            .map(|l| l.replace('-', "_"))
            .collect()
    }
    assert_eq!(longs::<DataFlags>(), DataFlags::NAMES);
    assert_eq!(longs::<KindFlags>(), KindFlags::NAMES);
    assert_eq!(longs::<ViewFlags>(), ViewFlags::NAMES);
}

#[test]
fn serde_knows_the_names() {
    use voxless::flags::{DataFlags, KindFlags, ViewFlags};
    // serde lists the names it knows when it refuses one.
    fn listed<T: serde::de::DeserializeOwned + std::fmt::Debug>() -> BTreeSet<String> {
        let err = toml::from_str::<T>("no_such_flag = 1")
            .unwrap_err()
            .to_string();
        err.split('`')
            .skip(3)
            .step_by(2)
            .map(str::to_string)
            .collect()
    }
    let set = |names: &[&str]| names.iter().map(|n| n.to_string()).collect::<BTreeSet<_>>();
    assert_eq!(listed::<DataFlags>(), set(DataFlags::NAMES));
    assert_eq!(listed::<KindFlags>(), set(KindFlags::NAMES));
    assert_eq!(listed::<ViewFlags>(), set(ViewFlags::NAMES));
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
    // One table: each name to its group; errors name the flag.
    let f = flags("kernel = 'm4'\ntet_mode = 'kbuffer'\nfov = 40");
    assert_eq!(f.data.kernel, Some(KernelName::CubicSpline));
    assert_eq!(f.view.fov, Some(40.0));
    let err = toml::from_str::<SceneFlags>("fov = 'wide'\nkernel = 'm4'")
        .unwrap_err()
        .to_string();
    assert!(err.contains("fov:"), "{err}");
    let err = toml::from_str::<SceneFlags>("colourmap = 'x'")
        .unwrap_err()
        .to_string();
    assert!(err.contains("unknown flag `colourmap`"), "{err}");
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
    flags("size = [64, 32]\nbox = 2.0\nlagrangian = 4\nparticles = 'x.npy'")
        .apply(&mut d, cwd)
        .unwrap();
    assert_eq!((d.image.width, d.image.height), (Some(64), Some(32)));
    assert_eq!(d.tets.as_ref().unwrap().box_size, Some(2.0));
    // Without a Lagrangian grid, a box makes particles periodic.
    let mut p = SceneDesc::default();
    flags("box = [0.0, 0.0, 0.0, 1.0, 2.0, 3.0]\nparticles = 'x.npy'")
        .apply(&mut p, cwd)
        .unwrap();
    assert!(p.tets.is_none());
    assert_eq!(
        p.particles.unwrap().periodic_box,
        Some(voxless::BoxDesc::Corners([0.0, 0.0, 0.0, 1.0, 2.0, 3.0]))
    );
    assert_eq!(
        SceneFlags::group_of("box"),
        Some(voxless::flags::FlagGroup::Data)
    );
    assert!(d.particles.is_none());
}

#[test]
fn bad_flags_are_errors_naming_the_flag() {
    let cwd = Path::new(".");
    let apply = |toml: &str| flags(toml).apply(&mut SceneDesc::default(), cwd);
    assert_eq!(field(apply("eye = [1.0, 2.0]").unwrap_err()), "eye");
    assert_eq!(field(apply("size = [1, 2, 3]").unwrap_err()), "size");
    assert_eq!(
        field(apply("box = 1.0\nlagrangian = 8\nkernel = 'm4'").unwrap_err()),
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
