use std::path::Path;

use crate::WorldFrame;
use crate::camera::ViewAdjust;
use crate::fields::name_of;

/// The camera `c` describes in the world frame.
fn camera(
    c: &CameraDesc,
    b: &Aabb,
    aspect: f32,
) -> Result<voxless_core::Camera, crate::SceneError> {
    crate::camera::camera(c, b, aspect, &WorldFrame::default())
}
use crate::{
    CameraDesc, ParticlesDesc, Scene, SceneDesc, TransferDesc, Vec3, transfer_function_at,
};
use voxless_core::{Aabb, Camera, Projection};

/// Loads and resolves frame 0 of `desc`.
fn resolve(desc: &SceneDesc, base: &Path) -> Result<Scene, crate::SceneError> {
    Scene::open(desc, base, 0)
}

fn adjust(orbit: f32, elevation: f32, zoom: f32) -> ViewAdjust {
    ViewAdjust {
        orbit,
        elevation,
        zoom,
    }
}

const Y: Vec3 = Vec3::new(0.0, 1.0, 0.0);

#[test]
fn orbit_turns_the_eye_about_the_up_axis_through_the_look_at_point() {
    let (eye, at) = (Vec3::new(0.0, 0.5, 3.0), Vec3::new(0.5, 0.5, 0.5));
    // A quarter turn lands exactly on the rotated position: towards +x,
    // the camera's right when it looks down −z.
    assert_eq!(
        adjust(90.0, 0.0, 1.0).place_eye(eye, at, Y, true),
        Vec3::new(3.0, 0.5, 1.0)
    );
    assert_eq!(
        adjust(360.0, 0.0, 1.0).place_eye(eye, at, Y, true),
        eye,
        "a full turn comes back"
    );
    // Nothing to do: the eye is returned untouched.
    assert_eq!(adjust(0.0, 0.0, 1.0).place_eye(eye, at, Y, true), eye);
    // Zoom 2 halves the distance; orthographic cameras keep the eye.
    let z = adjust(0.0, 0.0, 2.0);
    assert_eq!(z.place_eye(eye, at, Y, true), Vec3::new(0.25, 0.5, 1.75));
    assert_eq!(z.place_eye(eye, at, Y, false), eye);
}

#[test]
fn elevation_raises_the_eye_and_stops_short_of_the_pole() {
    let at = Vec3::new(1.0, 2.0, 3.0);
    let eye = at + Vec3::new(0.0, 0.0, 4.0);
    let angle = |e: Vec3| {
        let d = e - at;
        d.y.atan2((d.x * d.x + d.z * d.z).sqrt()).to_degrees()
    };
    let e30 = adjust(0.0, 30.0, 1.0).place_eye(eye, at, Y, true);
    assert!((angle(e30) - 30.0).abs() < 1e-4, "{}", angle(e30));
    assert!(((e30 - at).length() - 4.0).abs() < 1e-5);
    assert!(
        (e30 - at).x.abs() < 1e-6,
        "stays in the same vertical plane"
    );
    let up = adjust(0.0, 500.0, 1.0).place_eye(eye, at, Y, true);
    assert!((angle(up) - 89.9).abs() < 0.01, "{}", angle(up));
    let down = adjust(0.0, -95.0, 1.0).place_eye(eye, at, Y, true);
    assert!((angle(down) + 89.9).abs() < 0.01, "{}", angle(down));
    // Elevation adds to the existing angle.
    let again = adjust(0.0, 30.0, 1.0).place_eye(e30, at, Y, true);
    assert!((angle(again) - 60.0).abs() < 1e-3);
}

/// Whether every corner of `b` projects inside the image of `c` (aspect
/// `aspect`).
fn frames_every_corner(c: &Camera, b: &Aabb, aspect: f32) -> bool {
    let Projection::Perspective { fov_y_deg } = c.projection else {
        return false;
    };
    let ty = (fov_y_deg.to_radians() * 0.5).tan();
    (0..8).all(|k| {
        let p = Vec3::new(
            if k & 1 == 1 { b.max.x } else { b.min.x },
            if k & 2 == 2 { b.max.y } else { b.min.y },
            if k & 4 == 4 { b.max.z } else { b.min.z },
        ) - c.eye;
        let depth = p.dot(c.forward);
        depth > 0.0
            && p.dot(c.right).abs() <= ty * aspect * depth * 1.0001
            && p.dot(c.up).abs() <= ty * depth * 1.0001
    })
}

#[test]
fn default_view_is_a_three_quarter_view_that_honours_up_and_frames_the_data() {
    // A dam-break-like box, long in x, z up.
    let b = Aabb::new(Vec3::new(0.0, -0.5, 0.0), Vec3::new(2.0, 0.5, 0.6));
    for aspect in [0.5f32, 1.0, 16.0 / 9.0] {
        let c = camera(&CameraDesc::default(), &b, aspect).unwrap();
        assert!(frames_every_corner(&c, &b, aspect), "aspect {aspect}");
        // Up is +z, the long side runs left to right, the eye above.
        assert!(c.up.z > 0.8, "{:?}", c.up);
        assert!(c.right.x > 0.75, "{:?}", c.right);
        let elevation = (c.eye - b.center()).normalized().z.asin().to_degrees();
        assert!((elevation - 25.0).abs() < 0.1, "{elevation}");
    }
    // --up 0 1 0: the same view about y; the long side still across.
    let y_up = CameraDesc {
        up: Some([0.0, 1.0, 0.0]),
        ..Default::default()
    };
    let c = camera(&y_up, &b, 1.5).unwrap();
    assert!(c.up.y > 0.8 && c.right.x > 0.75, "{c:?}");
    assert!(frames_every_corner(&c, &b, 1.5));
    // A long vertical column seen with z up stays upright.
    let column = Aabb::new(Vec3::ZERO, Vec3::new(0.1, 0.2, 5.0));
    let c = camera(&CameraDesc::default(), &column, 1.0).unwrap();
    assert!(frames_every_corner(&c, &column, 1.0) && c.up.z > 0.8);
    // Bad up vectors name the flag.
    for up in [[0.0; 3], [f32::NAN, 0.0, 1.0]] {
        let e = camera(
            &CameraDesc {
                up: Some(up),
                ..Default::default()
            },
            &b,
            1.0,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("--up"), "{e}");
    }
}

#[test]
fn camera_applies_view_keys_and_rejects_bad_values() {
    let b = Aabb::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 1.0));
    let plain = camera(&CameraDesc::default(), &b, 1.5).unwrap();
    let zoomed = camera(
        &CameraDesc {
            zoom: Some(2.0),
            ..Default::default()
        },
        &b,
        1.5,
    )
    .unwrap();
    let d = |c: &Camera| (c.eye - b.center()).length();
    assert!((d(&zoomed) * 2.0 - d(&plain)).abs() < 1e-5);
    let ortho = |zoom| {
        let c = camera(
            &CameraDesc {
                projection: Some(crate::ProjectionName::Orthographic),
                ortho_height: Some(3.0),
                zoom,
                ..Default::default()
            },
            &b,
            2.0,
        )
        .unwrap();
        (c.eye, c.projection)
    };
    let (e1, _) = ortho(None);
    let (e2, p2) = ortho(Some(4.0));
    assert_eq!(e1, e2, "orthographic zoom leaves the eye");
    assert_eq!(
        p2,
        Projection::Orthographic {
            half_width: 0.75,
            half_height: 0.375
        }
    );
    for (desc, field) in [
        (
            CameraDesc {
                zoom: Some(0.0),
                ..Default::default()
            },
            "camera.zoom",
        ),
        (
            CameraDesc {
                zoom: Some(f32::NAN),
                ..Default::default()
            },
            "camera.zoom",
        ),
        (
            CameraDesc {
                orbit: Some(f32::INFINITY),
                ..Default::default()
            },
            "camera.orbit",
        ),
        (
            CameraDesc {
                elevation: Some(f32::NAN),
                ..Default::default()
            },
            "camera.elevation",
        ),
    ] {
        let e = camera(&desc, &b, 1.0).unwrap_err().to_string();
        assert!(e.contains(field), "{e}");
    }
}

fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("voxless-view-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn colormap_files_resolve_relative_to_the_scene_and_bring_their_opacity() {
    let dir = scratch("cmap");
    std::fs::create_dir_all(dir.join("maps")).unwrap();
    std::fs::write(
        dir.join("maps/p.json"),
        r#"[{"Name": "A", "RGBPoints": [0, 0, 0, 0, 1, 1, 0, 0]},
            {"Name": "B", "RGBPoints": [0, 0, 0, 0, 1, 0, 0, 1],
             "Points": [0, 1, 0.5, 0, 1, 0, 0.5, 0]}]"#,
    )
    .unwrap();
    let mut t = TransferDesc {
        colormap_file: Some("maps/p.json".into()),
        colormap: Some("B".into()),
        ..Default::default()
    };
    let mut notes = Vec::new();
    let tf = transfer_function_at(&t, &dir, &mut notes).unwrap();
    assert_eq!(tf.colormap().srgb(1.0), [0.0, 0.0, 1.0]);
    assert!((tf.opacity(0.0) - 1.0).abs() < 1e-6 && tf.opacity(1.0) < 1e-6);
    assert!(
        notes[0].contains("'B'") && notes[0].contains("opacity"),
        "{notes:?}"
    );
    // The scene's own opacity wins over the file's.
    t.opacity = Some("constant".into());
    let tf = transfer_function_at(&t, &dir, &mut Vec::new()).unwrap();
    assert!((tf.opacity(1.0) - 1.0).abs() < 1e-6);
    // An unknown preset lists the file's names; points and a file clash.
    t.colormap = Some("viridis".into());
    let e = transfer_function_at(&t, &dir, &mut Vec::new())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("p.json") && e.contains("A, B"), "{e}");
    t.colormap = None;
    t.colormap_points = Some(vec![[0.0, 0.0, 0.0, 0.0]]);
    let e = transfer_function_at(&t, &dir, &mut Vec::new())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("colormap_file"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn colorbar_reports_the_range_and_name_colour_comes_from() {
    let dir = scratch("bar");
    let mut csv = String::from("x,y,z,temp\n");
    for i in 0..200 {
        let f = i as f32 / 200.0;
        csv += &format!(
            "{f},{},{},{}\n",
            (f * 7.0).fract(),
            (f * 13.0).fract(),
            10.0 * f
        );
    }
    std::fs::write(dir.join("p.csv"), csv).unwrap();
    let mut desc = SceneDesc {
        particles: Some(ParticlesDesc {
            file: Some("p.csv".into()),
            attribute: Some("temp".into()),
            radius: Some(0.1),
            ..Default::default()
        }),
        ..Default::default()
    };
    let s = resolve(&desc, &dir).unwrap();
    let bar = s.colorbar(&desc);
    assert_eq!(bar.label.as_deref(), Some("temp"));
    assert!(!bar.log10 && bar.lo < 0.1 && bar.hi > 9.9, "{bar:?}");
    // Without an attribute: the density range, in log10 with --log.
    desc.particles.as_mut().unwrap().attribute = None;
    desc.render.log_scale = Some(true);
    let s = resolve(&desc, &dir).unwrap();
    let bar = s.colorbar(&desc);
    assert_eq!(bar.label.as_deref(), Some("density"));
    assert!(bar.log10 && bar.lo == s.view.settings.value_range.lo);
    assert_eq!(name_of("frames/temp_%04d.npy").as_deref(), Some("temp"));
    assert_eq!(name_of("dir/mass-*.npy").as_deref(), Some("mass"));
    assert_eq!(name_of("speed").as_deref(), Some("speed"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn reaim_moves_the_camera_and_a_default_light_with_it() {
    let dir = scratch("reaim");
    let mut csv = String::from("x,y,z\n");
    for i in 0..100 {
        let f = i as f32 / 100.0;
        csv += &format!("{f},{},{}\n", (f * 7.0).fract(), (f * 3.0).fract());
    }
    std::fs::write(dir.join("p.csv"), csv).unwrap();
    let mut desc = SceneDesc {
        particles: Some(ParticlesDesc {
            file: Some("p.csv".into()),
            radius: Some(0.2),
            ..Default::default()
        }),
        light: Some(Default::default()),
        ..Default::default()
    };
    let mut s = resolve(&desc, &dir).unwrap();
    let before = (s.view.camera, s.view.settings.light.unwrap().direction);
    desc.camera.orbit = Some(120.0);
    s.reaim(&desc).unwrap();
    let again = resolve(&desc, &dir).unwrap();
    assert_ne!(s.view.camera, before.0);
    assert_eq!(s.view.camera, again.view.camera);
    assert_eq!(s.view.settings.light, again.view.settings.light);
    assert_ne!(s.view.settings.light.unwrap().direction, before.1);
    let _ = std::fs::remove_dir_all(&dir);
}
