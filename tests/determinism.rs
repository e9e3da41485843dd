//! Same scene + same spp → the same image bit for bit, whatever the thread
//! count (the random stream is keyed by pixel and sample, not by scheduling).

use voxless_core::{Camera, Vec3};
use voxless_particles::{ParticleData, ParticleSettings, ParticleVolume};
use voxless_render::{Light, RenderSettings, render};
use voxless_transfer::TransferFunction;

#[test]
fn image_is_identical_across_thread_counts() {
    let data = voxless::demo::galaxy(5000);
    let vol = ParticleVolume::new(
        ParticleData { ..data },
        ParticleSettings {
            radius: 0.1,
            ..Default::default()
        },
    )
    .unwrap();
    let camera = Camera::framing(&voxless_core::Volume::bounds(&vol), 1.5);
    let tf = TransferFunction::default_for_density();
    let mut settings = RenderSettings::for_volume(&vol, 48, 32);
    settings.spp = 3;
    settings.light = Some(Light {
        direction: Vec3::new(0.0, 1.0, 0.0),
        ambient: 0.2,
    });
    let with_threads = |n: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
            .install(|| render(&vol, &camera, &tf, &settings, &voxless::Control::new()).unwrap())
    };
    let one = with_threads(1);
    let three = with_threads(3);
    assert!(
        one.pixels.iter().any(|p| p[3] > 0.1),
        "the galaxy is visible"
    );
    assert_eq!(one, three);
}
