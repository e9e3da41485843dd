//! The packet path by value: [`ParticleVolume::sample_batch_with`] on every
//! SIMD backend against the per-sample path ([`Volume::sample`],
//! [`Volume::sample_with_gradient`]), for every kernel, with and without
//! gradient, attribute and pre-classified colours; and the backends against
//! each other, bit for bit. Each test passes its backend as a value, so the
//! tests are independent of one another and of test threads.
//!
//! Tolerances (see the packet module docs for why they hold): coverage
//! exactly equal; density relative 1e-5 (of the larger of the sample's
//! density and 1e-4 of the volume's peak: near a support edge the cubic
//! spline's f32 `2 − q` cancels, which the per-sample path avoids in f64);
//! attribute (in [0, 1]) and colour absolute 1e-5; gradient components
//! relative 1e-4 of the larger of the gradient's length and 1e-3 of the
//! largest gradient in the packet.

use super::*;
use voxless_core::simd::Simd;
use voxless_core::{Attribute, Control, Image, Ray, Sample, SampleBatch, SmallRng, Vec3, Volume};
use voxless_render::{Light, RenderSettings, render};
use voxless_transfer::{Colormap, OpacityMap, TransferFunction};

const KERNELS: [Kernel; 8] = [
    Kernel::Gaussian3,
    Kernel::Gaussian {
        kappa: 1.5,
        sigma: 2.0,
    },
    Kernel::CubicSpline,
    Kernel::QuarticSpline,
    Kernel::QuinticSpline,
    Kernel::WendlandC2,
    Kernel::WendlandC4,
    Kernel::WendlandC6,
];

/// Particles in the unit cube, radii 0.05–0.12, weights 0.5–1.5 and (if
/// `attribute`) an attribute in [0, 1].
fn data(n: usize, seed: u64, attribute: bool) -> ParticleData {
    let mut rng = SmallRng(seed);
    ParticleData {
        positions: (0..n).map(|_| rng.v()).collect(),
        radii: Some((0..n).map(|_| 0.05 + 0.07 * rng.f()).collect()),
        attribute: attribute.then(|| (0..n).map(|_| rng.f()).collect()),
        weights: Some((0..n).map(|_| 0.5 + rng.f()).collect()),
    }
}

/// A packet as the renderer makes them: `n` rays through the cube (one
/// along an axis, so a direction component is zero), each with jittered,
/// nearly even samples in two intervals, one ray with a single sample and
/// one with none.
struct Packet {
    rays: Vec<Ray>,
    offsets: Vec<u32>,
    t: Vec<f32>,
}

impl Packet {
    fn new(n: usize, seed: u64) -> Packet {
        let mut rng = SmallRng(seed);
        let mut p = Packet {
            rays: Vec::new(),
            offsets: vec![0],
            t: Vec::new(),
        };
        for r in 0..n {
            let (x, y) = (0.1 + 0.8 * rng.f(), 0.1 + 0.8 * rng.f());
            let dir = if r == 0 {
                Vec3::new(0.0, 0.0, 1.0)
            } else {
                Vec3::new(0.3 * rng.f() - 0.15, 0.3 * rng.f() - 0.15, 1.0).normalized()
            };
            p.rays.push(Ray::new(Vec3::new(x, y, -0.5), dir));
            let dt = 0.004 + 0.01 * rng.f();
            match r {
                1 => p.t.push(1.0),
                2 => {}
                _ => {
                    for (a, b) in [(0.3f32, 0.9f32), (0.95, 1.7)] {
                        let jitter = rng.f();
                        let mut k = 0.0;
                        while a + (k + jitter) * dt < b {
                            p.t.push(a + (k + jitter) * dt);
                            k += 1.0;
                        }
                    }
                }
            }
            p.offsets.push(p.t.len() as u32);
        }
        p
    }

    fn batch(&self) -> SampleBatch<'_> {
        SampleBatch {
            rays: &self.rays,
            offsets: &self.offsets,
            t: &self.t,
            hints: None,
        }
    }

    /// The sample points, in batch order.
    fn points(&self) -> Vec<Vec3> {
        (0..self.rays.len())
            .flat_map(|r| {
                let ray = self.rays[r];
                self.batch()
                    .samples(r)
                    .to_vec()
                    .into_iter()
                    .map(move |t| ray.at(t))
            })
            .collect()
    }
}

/// Every backend the test can run as itself; notice when AVX2 is missing.
fn backends() -> Vec<Simd> {
    if Simd::Avx2.available() {
        vec![Simd::Portable, Simd::Avx2]
    } else {
        eprintln!("notice: no AVX2 on this CPU; the packet path is tested on portable lanes only");
        vec![Simd::Portable]
    }
}

/// `(Φ, attribute as numbers)` of a sample.
fn parts(s: &Sample) -> (f32, Vec<f32>) {
    let a = match s.attribute {
        Attribute::None => vec![],
        Attribute::Scalar(x) => vec![x],
        Attribute::Rgb(c) => vec![c.x, c.y, c.z],
    };
    (s.value, a)
}

/// Checks `got` (packet path) against `want` (per-sample path) within the
/// module's tolerances; `peak` is the volume's peak density.
fn assert_close(
    got: &[(Option<Sample>, Vec3)],
    want: &[(Option<Sample>, Vec3)],
    peak: f32,
    what: &str,
) {
    assert_eq!(got.len(), want.len(), "{what}: sample count");
    let g_max = want.iter().map(|w| w.1.length()).fold(0.0f32, f32::max);
    let mut covered = 0;
    for (j, ((gs, gg), (ws, wg))) in got.iter().zip(want).enumerate() {
        match (gs, ws) {
            (None, None) => {}
            (Some(g), Some(w)) => {
                covered += 1;
                let ((gv, ga), (wv, wa)) = (parts(g), parts(w));
                let scale = wv.max(1e-4 * peak);
                assert!(
                    (gv - wv).abs() <= 1e-5 * scale,
                    "{what}: sample {j}: density {gv} vs {wv}"
                );
                assert_eq!(ga.len(), wa.len(), "{what}: sample {j}: attribute kind");
                for (a, b) in ga.iter().zip(&wa) {
                    assert!(
                        (a - b).abs() <= 1e-5,
                        "{what}: sample {j}: attribute {ga:?} vs {wa:?}"
                    );
                }
            }
            _ => panic!("{what}: sample {j}: coverage {gs:?} vs {ws:?}"),
        }
        let scale = wg.length().max(1e-3 * g_max);
        for a in 0..3 {
            assert!(
                (gg[a] - wg[a]).abs() <= 1e-4 * scale,
                "{what}: sample {j}: gradient {gg:?} vs {wg:?}"
            );
        }
    }
    assert!(
        covered > got.len() / 4,
        "{what}: only {covered} of {} samples covered",
        got.len()
    );
}

/// What the per-sample path gives at each point.
fn per_sample(vol: &impl Volume, points: &[Vec3], gradient: bool) -> Vec<(Option<Sample>, Vec3)> {
    points
        .iter()
        .map(|&p| {
            if gradient {
                match vol.sample_with_gradient(p) {
                    Some((s, g)) => (Some(s), g),
                    None => (None, Vec3::ZERO),
                }
            } else {
                (vol.sample(p), Vec3::ZERO)
            }
        })
        .collect()
}

fn bits(v: &[(Option<Sample>, Vec3)]) -> Vec<u32> {
    v.iter()
        .flat_map(|(s, g)| {
            let mut b = vec![
                s.is_some() as u32,
                g.x.to_bits(),
                g.y.to_bits(),
                g.z.to_bits(),
            ];
            if let Some(s) = s {
                let (v, a) = parts(s);
                b.push(v.to_bits());
                b.extend(a.iter().map(|x| x.to_bits()));
            }
            b
        })
        .collect()
}

#[test]
fn every_backend_matches_the_per_sample_path() {
    let tf = TransferFunction::new(
        Colormap::preset("viridis").unwrap(),
        OpacityMap::preset("linear").unwrap(),
    );
    let packet = Packet::new(61, 5);
    let points = packet.points();
    for kernel in KERNELS {
        for attribute in [false, true] {
            let classes: &[Classification] = if attribute {
                &[Classification::Post, Classification::Pre]
            } else {
                &[Classification::Post]
            };
            for &classification in classes {
                let vol = ParticleVolume::new(
                    data(3000, 11, attribute),
                    ParticleSettings {
                        kernel,
                        classification,
                        ..Default::default()
                    },
                )
                .unwrap();
                let colors = vol.preclassify_with(&tf);
                let ctx = ParticleContext::new(&vol, colors.clone(), Simd::Auto);
                let peak = vol.value_range().hi;
                for gradient in [false, true] {
                    let what = format!(
                        "{} attribute {attribute} {classification:?} gradient {gradient}",
                        kernel.name()
                    );
                    let want = per_sample(&ctx, &points, gradient);
                    let mut first: Option<Vec<u32>> = None;
                    for simd in backends() {
                        let mut got = Vec::new();
                        vol.sample_batch_with(&colors, simd, &packet.batch(), gradient, &mut got);
                        assert_close(&got, &want, peak, &format!("{what} {simd:?}"));
                        // The backends agree bit for bit.
                        let b = bits(&got);
                        match &first {
                            None => first = Some(b),
                            Some(f) => assert!(*f == b, "{what}: {simd:?} differs from portable"),
                        }
                    }
                    // A prepared context's `Volume::sample_batch` is its
                    // backend (`Auto` here) with its colours.
                    let mut auto = Vec::new();
                    ctx.sample_batch(&packet.batch(), gradient, &mut auto);
                    assert!(first.as_ref() == Some(&bits(&auto)), "{what}: auto");
                }
            }
        }
    }
}

#[test]
fn colours_passed_in_match_a_pre_classified_volume() {
    // The colours come with the call, not the volume: a post-classified
    // volume given a pre-classified twin's colours samples like the twin;
    // colours of the wrong length count as none.
    let tf = TransferFunction::new(
        Colormap::preset("magma").unwrap(),
        OpacityMap::preset("linear").unwrap(),
    );
    let settings = |classification| ParticleSettings {
        kernel: Kernel::CubicSpline,
        classification,
        ..Default::default()
    };
    let pre = ParticleVolume::new(data(2000, 3, true), settings(Classification::Pre)).unwrap();
    let pre_colors = pre.preclassify_with(&tf);
    let post = ParticleVolume::new(data(2000, 3, true), settings(Classification::Post)).unwrap();
    assert!(post.preclassify_with(&tf).is_empty() && !pre_colors.is_empty());
    let packet = Packet::new(40, 9);
    for simd in backends() {
        let (mut a, mut b, mut c, mut d) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        post.sample_batch_with(&pre_colors, simd, &packet.batch(), true, &mut a);
        pre.sample_batch_with(&pre_colors, simd, &packet.batch(), true, &mut b);
        assert!(bits(&a) == bits(&b), "{simd:?}: colours passed in");
        post.sample_batch_with(&pre_colors[1..], simd, &packet.batch(), true, &mut c);
        post.sample_batch_with(&[], simd, &packet.batch(), true, &mut d);
        assert!(bits(&c) == bits(&d), "{simd:?}: wrong length is none");
        assert!(matches!(
            d.iter().find_map(|x| x.0),
            Some(Sample {
                attribute: Attribute::Scalar(_),
                ..
            })
        ));
    }
}

/// Largest per-channel difference between two images.
fn max_diff(a: &Image, b: &Image) -> f32 {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(p, q)| (0..4).map(move |c| (p[c] - q[c]).abs()))
        .fold(0.0, f32::max)
}

#[test]
fn images_of_every_backend_match_the_per_sample_image() {
    // Renders, shaded (gradients) and pre-classified: the backends give the
    // same image bit for bit, within 1/255 of the per-sample path's.
    let tf = TransferFunction::new(
        Colormap::preset("viridis").unwrap(),
        OpacityMap::preset("linear").unwrap(),
    );
    for kernel in KERNELS {
        let vol = ParticleVolume::new(
            data(4000, 21, true),
            ParticleSettings {
                kernel,
                classification: Classification::Pre,
                ..Default::default()
            },
        )
        .unwrap();
        let camera = voxless_core::Camera::framing(&vol.bounds(), 1.2);
        let mut s = RenderSettings::for_volume(&vol, 48, 40);
        s.opacity_scale *= 3.0;
        s.light = Some(Light {
            direction: Vec3::new(0.3, 0.8, 0.5).normalized(),
            ambient: 0.2,
        });
        s.packets = false;
        let slow = render(&vol, &camera, &tf, &s, &Control::new()).unwrap();
        assert!(slow.pixels.iter().filter(|p| p[3] > 0.05).count() > 200);
        s.packets = true;
        let mut first: Option<Image> = None;
        for simd in backends() {
            s.simd = simd;
            let img = render(&vol, &camera, &tf, &s, &Control::new()).unwrap();
            let d = max_diff(&slow, &img);
            assert!(
                d <= 1.0 / 255.0,
                "{} {simd:?}: {d} from per-sample",
                kernel.name()
            );
            if let Some(f) = &first {
                assert!(
                    f.pixels == img.pixels,
                    "{} {simd:?} differs from portable",
                    kernel.name()
                );
            }
            first = Some(img);
        }
    }
}
