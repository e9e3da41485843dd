//! Where `--pixels area` can act: particles and tessellations, whole lines
//! of sight, one process; refused elsewhere naming the setting.

use voxless_scene::{ParticlesDesc, PixelsName, SceneDesc, TetsDesc};

use crate::checks::{check_ranks, set_projection_pixels};
use crate::projection::ProjectionDesc;

fn particles() -> SceneDesc {
    SceneDesc {
        particles: Some(ParticlesDesc {
            file: Some("p.npy".into()),
            ..Default::default()
        }),
        ..Default::default()
    }
}

#[test]
fn area_pixels_go_to_particles_or_tessellations_and_are_refused_where_they_cannot_act() {
    let whole = ProjectionDesc::default();
    let mut desc = particles();
    set_projection_pixels(&mut desc, Some(PixelsName::Area), &whole).unwrap();
    assert_eq!(
        desc.particles.as_ref().unwrap().pixels,
        Some(PixelsName::Area)
    );
    // One process projects them; under mpirun each rank's box goes
    // through pixel centres.
    check_ranks(&desc, None, 1, true).unwrap();
    let e = check_ranks(&desc, None, 4, true).unwrap_err().to_string();
    assert!(
        e.contains("particles.pixels") && e.contains("one process"),
        "{e}"
    );
    check_ranks(&desc, None, 4, false).unwrap();
    // A slab integrates through pixel centres.
    let slab = ProjectionDesc {
        depth: Some(1.0),
        ..Default::default()
    };
    let e = set_projection_pixels(&mut particles(), Some(PixelsName::Area), &slab)
        .unwrap_err()
        .to_string();
    assert!(e.contains("--depth"), "{e}");
    // A tessellation takes them as before.
    let mut tets = SceneDesc {
        tets: Some(TetsDesc::default()),
        ..Default::default()
    };
    set_projection_pixels(&mut tets, Some(PixelsName::Area), &whole).unwrap();
    assert_eq!(tets.tets.as_ref().unwrap().pixels, Some(PixelsName::Area));
    // Other data: refused.
    let e = set_projection_pixels(&mut SceneDesc::default(), Some(PixelsName::Area), &whole)
        .unwrap_err()
        .to_string();
    assert!(e.contains("--pixels applies to particles"), "{e}");
}
