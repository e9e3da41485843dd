//! Float64 input far from the origin: particles at 10⁹ + a unit spread,
//! recentred in float64 before they become float32, render, project and
//! sample like the same particles at the origin — with the camera, clip box
//! and query points given in world coordinates.

use voxless::{CameraDesc, Control, ParticleArrays, ParticlesDesc, RenderDesc, Scene, SceneDesc};
use voxless_core::SmallRng;

fn positions(offset: f64) -> Vec<[f64; 3]> {
    let mut rng = SmallRng(17);
    (0..3000)
        .map(|_| {
            [
                offset + rng.f() as f64,
                offset + 0.5 * rng.f() as f64,
                offset + rng.f() as f64,
            ]
        })
        .collect()
}

fn scene(offset: f64) -> Scene {
    let arrays = ParticleArrays::from_f64(&positions(offset));
    let loaded = voxless::AnyVolume::from_particles(
        arrays,
        &ParticlesDesc {
            radius: Some(0.08),
            ..Default::default()
        },
    )
    .unwrap();
    let desc = SceneDesc {
        camera: CameraDesc {
            eye: Some([offset + 0.5, offset + 2.0, offset + 2.5]),
            look_at: Some([offset + 0.5, offset + 0.25, offset + 0.5]),
            ..Default::default()
        },
        render: RenderDesc {
            clip: Some([
                offset + 0.1,
                offset - 1.0,
                offset + 0.1,
                offset + 0.8,
                offset + 1.0,
                offset + 0.9,
            ]),
            ..Default::default()
        },
        image: voxless::ImageDesc {
            width: Some(48),
            height: Some(40),
            spp: Some(2),
        },
        ..Default::default()
    };
    Scene::with_loaded(loaded, &desc, ".".as_ref()).unwrap()
}

#[test]
fn a_billion_units_away_renders_and_samples_the_same() {
    let (near, far) = (scene(0.0), scene(1e9));
    let a = near.render(&Control::new()).unwrap();
    let b = far.render(&Control::new()).unwrap();
    assert!(a.pixels.iter().any(|p| p[3] > 0.1), "visible");
    let worst = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(p, q)| (0..4).map(move |c| (p[c] - q[c]).abs()))
        .fold(0.0f32, f32::max);
    assert!(worst <= 1.0 / 255.0, "images differ by {worst}");
    let pts = |o: f64| vec![[o + 0.5, o + 0.25, o + 0.5], [o + 0.1, o + 0.4, o + 0.9]];
    let (sa, sb) = (near.sample(&pts(0.0), true), far.sample(&pts(1e9), true));
    for (x, y) in sa.iter().zip(&sb) {
        assert!((x - y).abs() <= 1e-5 * x.abs().max(1.0), "{x} vs {y}");
    }
    // The world bounds say where the data is.
    let (lo, _) = far.world_bounds();
    assert!((lo[0] - 1e9).abs() < 1.0, "{lo:?}");
}
