//! The packet path (rays marched in packets sharing one BVH traversal per
//! pass) must draw the image of the per-sample point-query path: at most
//! 1/255 apart on every channel of every pixel, with the same jitter, for
//! every kernel and every way a sample is used (density, post- and
//! pre-classified attribute, gradient shading, iso-surfaces, several spp).

mod common;

use voxless_core::{Camera, Image, Range1, Vec3, Volume};
use voxless_particles::{Classification, Kernel, ParticleData, ParticleSettings, ParticleVolume};
use voxless_render::{Light, RenderSettings, render};
use voxless_transfer::{Colormap, OpacityMap, TransferFunction};

const TOLERANCE: f32 = 1.0 / 255.0;

fn max_diff(a: &Image, b: &Image) -> f32 {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(p, q)| (0..4).map(move |c| (p[c] - q[c]).abs()))
        .fold(0.0, f32::max)
}

/// Renders with and without packets and checks the difference.
fn assert_same(vol: &ParticleVolume, tf: &TransferFunction, settings: &RenderSettings, what: &str) {
    let camera = Camera::framing(&vol.bounds(), 1.2);
    let mut slow = settings.clone();
    slow.packets = false;
    let mut fast = settings.clone();
    fast.packets = true;
    let a = render(vol, &camera, tf, &slow, &voxless::Control::new()).unwrap();
    // The best SIMD backend this CPU has; the backends are compared with
    // each other, by value, in the particle crate's tests.
    let b = render(vol, &camera, tf, &fast, &voxless::Control::new()).unwrap();
    let lit = a.pixels.iter().filter(|p| p[3] > 0.05).count();
    assert!(
        lit > a.pixels.len() / 20,
        "{what}: too little is visible ({lit} pixels) for the test to mean anything"
    );
    let d = max_diff(&a, &b);
    assert!(
        d <= TOLERANCE,
        "{what}: packet and per-sample images differ by {d}"
    );
}

fn galaxy(n: usize) -> ParticleData {
    let mut data = voxless::demo::galaxy(n);
    // A second attribute-like column for radius-independent checks.
    if data.attribute.is_none() {
        data.attribute = Some(data.positions.iter().map(|p| p.x).collect());
    }
    data
}

#[test]
fn every_kernel_and_mode_matches_the_per_sample_path() {
    let kernels = [
        (Kernel::Gaussian3, 0.12),
        (
            Kernel::Gaussian {
                kappa: 1.0,
                sigma: 2.0,
            },
            0.06,
        ),
        (Kernel::CubicSpline, 0.06),
    ];
    let tf = TransferFunction::new(
        Colormap::preset("viridis").unwrap(),
        OpacityMap::preset("linear").unwrap(),
    );
    for (kernel, radius) in kernels {
        for classification in [Classification::Post, Classification::Pre] {
            let vol = ParticleVolume::new(
                galaxy(6000),
                ParticleSettings {
                    kernel,
                    radius,
                    classification,
                    ..Default::default()
                },
            )
            .unwrap();
            let mut s = RenderSettings::for_volume(&vol, 64, 48);
            s.spp = 2;
            s.opacity_scale *= 3.0;
            let what = format!("{} {classification:?}", kernel.name());
            assert_same(&vol, &tf, &s, &what);
            // Gradient shading reads ∇Φ from the buffer.
            s.light = Some(Light {
                direction: Vec3::new(0.3, 0.8, 0.5).normalized(),
                ambient: 0.2,
            });
            assert_same(&vol, &tf, &s, &format!("{what} shaded"));
            // Iso-surfaces bracket crossings between buffered samples.
            let vr = vol.value_range();
            s.iso = vec![0.2 * vr.hi, 0.5 * vr.hi];
            s.volume = false;
            assert_same(&vol, &tf, &s, &format!("{what} iso"));
        }
    }
}

#[test]
fn clip_box_fixed_step_and_early_termination_match() {
    let vol = ParticleVolume::new(
        galaxy(4000),
        ParticleSettings {
            radius: 0.15,
            ..Default::default()
        },
    )
    .unwrap();
    let tf = TransferFunction::default_for_density();
    let b = vol.bounds();
    let mut s = RenderSettings::for_volume(&vol, 40, 40);
    s.clip = Some(voxless_core::Aabb::new(
        b.min,
        Vec3::new(b.center().x, b.max.y, b.max.z),
    ));
    s.step = Some(b.diagonal() / 300.0);
    s.early_termination = 0.5;
    s.opacity_scale *= 4.0;
    s.attribute_range = Some(Range1::new(-1.0, 1.0));
    assert_same(&vol, &tf, &s, "clip + step + early termination");
}

#[test]
fn dam_break_frame_matches() {
    let Some(dir) = common::shared_data("sph-dam-break/npy_01000") else {
        return;
    };
    let read = |name: &str| voxless_io::read_npy(&dir.join(name)).unwrap().data;
    let pos = read("positions.npy");
    let col = |name: &str| Some(read(name).iter().map(|&v| v as f32).collect());
    let data = ParticleData {
        positions: pos
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32))
            .collect(),
        radii: col("h.npy"),
        weights: col("mass.npy"),
        attribute: col("speed.npy"),
    };
    let vol = ParticleVolume::new(
        data,
        ParticleSettings {
            kernel: Kernel::CubicSpline,
            ..Default::default()
        },
    )
    .unwrap();
    let tf = TransferFunction::default_for_density();
    let s = RenderSettings::for_volume(&vol, 96, 96);
    assert_same(&vol, &tf, &s, "dam break");
}
