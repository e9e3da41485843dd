//! Volumes are immutable after they are built: one volume renders with two
//! transfer functions from two threads at once and gives, bit for bit, the
//! images it gives one after the other — for every kind whose preparation
//! depends on the transfer function.

use voxless::{
    AmrDesc, AnyVolume, ClassificationName, Control, ParticlesDesc, RenderSettings,
    TransferFunction,
};
use voxless_core::Camera;
use voxless_transfer::{Colormap, OpacityMap};

mod fixtures;

/// Two transfer functions that see different parts of the value range.
fn two_tfs() -> [TransferFunction; 2] {
    let low = OpacityMap::from_points(&[(0.0, 0.8), (0.4, 0.8), (0.45, 0.0), (1.0, 0.0)]).unwrap();
    [
        TransferFunction::new(Colormap::preset("viridis").unwrap(), low),
        TransferFunction::new(
            Colormap::preset("inferno").unwrap(),
            OpacityMap::preset("ramp-high").unwrap(),
        ),
    ]
}

fn concurrent_equals_sequential(name: &str, volume: &AnyVolume) {
    let camera = Camera::framing(&volume.bounds(), 1.0);
    let settings = RenderSettings {
        spp: 2,
        ..volume.default_settings(48, 48)
    };
    let tfs = two_tfs();
    let render = |tf: &TransferFunction| {
        volume
            .render(&camera, tf, &settings, &Control::new())
            .unwrap()
            .pixels
    };
    let sequential = [render(&tfs[0]), render(&tfs[1])];
    assert_ne!(sequential[0], sequential[1], "{name}: the two looks differ");
    for _ in 0..3 {
        let concurrent = std::thread::scope(|s| {
            let a = s.spawn(|| render(&tfs[0]));
            let b = s.spawn(|| render(&tfs[1]));
            [a.join().unwrap(), b.join().unwrap()]
        });
        assert!(
            concurrent == sequential,
            "{name}: concurrent renders differ from sequential ones"
        );
    }
}

#[test]
fn amr_visible_regions_live_in_each_render_not_in_the_volume() {
    let v = AnyVolume::from_amr(fixtures::amr_cells(), &AmrDesc::default())
        .unwrap()
        .volume;
    concurrent_equals_sequential("AMR", &v);
}

#[test]
fn pre_classified_particles_colour_each_render_with_its_own_colormap() {
    let desc = ParticlesDesc {
        classification: Some(ClassificationName::Pre),
        attribute_range: Some([0.0, 3.0]),
        ..Default::default()
    };
    let v = AnyVolume::from_particles(fixtures::particles(2000, 9), &desc)
        .unwrap()
        .volume;
    concurrent_equals_sequential("pre-classified particles", &v);
    // And the colours are pre-classified: averaging colours is not
    // colour-mapping the average.
    let post = ParticlesDesc {
        classification: Some(ClassificationName::Post),
        ..desc.clone()
    };
    let w = AnyVolume::from_particles(fixtures::particles(2000, 9), &post)
        .unwrap()
        .volume;
    let camera = Camera::framing(&v.bounds(), 1.0);
    let settings = v.default_settings(48, 48);
    let tf = &two_tfs()[1];
    let a = v.render(&camera, tf, &settings, &Control::new()).unwrap();
    let b = w.render(&camera, tf, &settings, &Control::new()).unwrap();
    assert_ne!(a.pixels, b.pixels, "pre- and post-classification differ");
}
