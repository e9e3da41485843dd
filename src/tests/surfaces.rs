//! Mirror instances against explicitly mirrored data, and meshes resolved
//! from a scene description.

use std::path::Path;

use voxless_scene::{AxisName, InstanceDesc, MeshDesc};

use crate::{AnyVolume, Control, ParticleArrays, ParticlesDesc, Scene, SceneDesc, Vec3};

/// A particle cloud in x ∈ [0.3, 1], and with `mirrored` its reflection
/// about x = 0 as well (explicit copies).
fn cloud(mirrored: bool, desc: &ParticlesDesc) -> AnyVolume {
    let mut rng = crate::core::SmallRng(5);
    let mut positions: Vec<Vec3> = (0..700)
        .map(|_| Vec3::new(0.3 + 0.7 * rng.f(), rng.f() * 0.6, rng.f() * 0.5))
        .collect();
    if mirrored {
        let copies: Vec<Vec3> = positions
            .iter()
            .map(|p| Vec3::new(-p.x, p.y, p.z))
            .collect();
        positions.extend(copies);
    }
    let attribute = Some(positions.iter().map(|p| p.y).collect());
    let arrays = ParticleArrays {
        positions,
        attribute,
        ..Default::default()
    };
    AnyVolume::from_particles(arrays, desc).unwrap().volume
}

fn desc(packets: bool) -> SceneDesc {
    let mut d = SceneDesc::default();
    d.image.width = Some(72);
    d.image.height = Some(48);
    d.camera.eye = Some([0.4, -1.6, 1.3]);
    d.camera.look_at = Some([0.0, 0.3, 0.25]);
    d.camera.up = Some([0.0, 0.0, 1.0]);
    d.transfer.value_range = Some([0.0, 40.0]);
    d.render.opacity_scale = Some(2.0);
    d.render.packets = Some(packets);
    d
}

#[test]
fn a_mirrored_render_equals_the_render_of_mirrored_data() {
    let p = ParticlesDesc {
        radius: Some(0.08),
        attribute_range: Some([0.0, 0.6]),
        ..Default::default()
    };
    for packets in [true, false] {
        let mut with_mirror = desc(packets);
        with_mirror.instances = vec![InstanceDesc {
            mirror: AxisName::X,
            at: Some(0.0),
        }];
        let a = Scene::with_volume(cloud(false, &p), &with_mirror, Path::new("."))
            .unwrap()
            .render(&Control::new())
            .unwrap();
        let b = Scene::with_volume(cloud(true, &p), &desc(packets), Path::new("."))
            .unwrap()
            .render(&Control::new())
            .unwrap();
        let worst = a
            .pixels
            .iter()
            .zip(&b.pixels)
            .flat_map(|(x, y)| (0..4).map(move |k| (x[k] - y[k]).abs()))
            .fold(0.0f32, f32::max);
        assert!(
            worst <= 1.0 / 255.0,
            "packets {packets}: largest difference {worst}"
        );
        // The mirror image is there: the left half is not empty.
        let left: f32 = a
            .pixels
            .chunks(72)
            .flat_map(|row| row[..20].iter().map(|p| p[3]))
            .sum();
        assert!(left > 1.0, "nothing drawn on the mirror side");
    }
}

#[test]
fn scene_meshes_are_loaded_and_bad_ones_named() {
    let dir = std::env::temp_dir().join(format!("voxless-surfaces-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
               property float z\nproperty float p\nelement face 1\n\
               property list uchar int vertex_indices\nend_header\n\
               0 0 0 1\n1 0 0 2\n0 1 0 3\n3 0 1 2\n";
    std::fs::write(dir.join("tri.ply"), ply).unwrap();
    let v = cloud(false, &ParticlesDesc::default());
    let mut d = desc(true);
    d.meshes = vec![MeshDesc {
        file: "tri.ply".into(),
        field: Some("p".into()),
        ..Default::default()
    }];
    let scene = Scene::with_volume(v, &d, &dir).unwrap();
    assert_eq!(
        scene
            .view
            .settings
            .surfaces
            .as_ref()
            .unwrap()
            .triangle_count(),
        1
    );
    // A field the mesh does not have names the file and the fields it has.
    d.meshes[0].field = Some("q".into());
    let v = cloud(false, &ParticlesDesc::default());
    let e = Scene::with_volume(v, &d, &dir).err().unwrap().to_string();
    assert!(
        e.contains("tri.ply") && e.contains("'q'") && e.contains("p"),
        "{e}"
    );
    // Ambient occlusion with nothing to shade is refused by name.
    let mut d = desc(true);
    d.render.ao = Some(2);
    let v = cloud(false, &ParticlesDesc::default());
    let e = Scene::with_volume(v, &d, &dir).err().unwrap().to_string();
    assert!(e.contains("--ao") && e.contains("--mesh"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}
