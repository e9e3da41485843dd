//! The GPU gives the CPU's image: renders within 1/255 per channel (in
//! fact the same bits on lavapipe so far), projections within 1e-5 of the
//! peak per pixel and in Σ — for every kernel, classification mode,
//! shading and the log scale; projections periodic, with pixel areas and
//! off axis. On whatever adapter wgpu finds; skipped with a notice where
//! there is none, unless `VOXLESS_REQUIRE_GPU=1` (CI, on lavapipe).

use voxless_core::testing::prerequisite;
use voxless_core::{
    Aabb, Camera, Control, PixelIntegral, Projection, Range1, SmallRng, Vec3, Volume,
};
use voxless_gpu::Gpu;
use voxless_particles::splat::{SplatParticle, Splatter};
use voxless_particles::{Classification, Kernel, ParticleData, ParticleSettings, ParticleVolume};
use voxless_render::{Light, RenderSettings};
use voxless_transfer::{Colormap, OpacityMap, TransferFunction};

fn gpu() -> Option<Gpu> {
    let g = Gpu::new();
    let what = match &g {
        Ok(_) => String::new(),
        Err(e) => format!("a GPU adapter ({e})"),
    };
    prerequisite(g.is_ok(), "VOXLESS_REQUIRE_GPU", &what).then(|| g.unwrap())
}

/// A clumpy blob of particles with radii, weights and an attribute.
fn data(n: usize) -> ParticleData {
    let mut r = SmallRng(3);
    let mut positions = Vec::new();
    for i in 0..n {
        // Two clumps and a sheet.
        let c = match i % 3 {
            0 => Vec3::new(0.3, 0.4, 0.5),
            1 => Vec3::new(0.7, 0.6, 0.4),
            _ => Vec3::new(0.5, 0.5, 0.5),
        };
        let s = if i % 3 == 2 { 0.35 } else { 0.12 };
        positions.push(c + Vec3::new(r.f() - 0.5, r.f() - 0.5, (r.f() - 0.5) * 0.6) * (2.0 * s));
    }
    ParticleData {
        radii: Some((0..n).map(|_| 0.04 + 0.04 * r.f()).collect()),
        weights: Some((0..n).map(|_| 0.5 + r.f()).collect()),
        attribute: Some(positions.iter().map(|p| p.x * 2.0 + p.z).collect()),
        positions,
    }
}

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

fn volume(kernel: Kernel, classification: Classification, attribute: bool) -> ParticleVolume {
    let mut d = data(3000);
    if !attribute {
        d.attribute = None;
    }
    let settings = ParticleSettings {
        kernel,
        classification,
        ..Default::default()
    };
    ParticleVolume::new(d, settings).unwrap()
}

fn camera(v: &ParticleVolume) -> Camera {
    let b = v.bounds();
    Camera::look_at(
        b.center() + Vec3::new(0.9, -1.6, 0.7),
        b.center(),
        Vec3::new(0.0, 0.0, 1.0),
        Projection::Perspective { fov_y_deg: 40.0 },
    )
    .unwrap()
}

/// The largest difference between the two renders' 8-bit sRGB channels.
fn render_diff(gpu: &Gpu, v: &ParticleVolume, tf: &TransferFunction, s: &RenderSettings) -> u8 {
    let cam = camera(v);
    let c = Control::new();
    let cpu = voxless_render::render(v, &cam, tf, s, &c).unwrap();
    let film = gpu.render_film(v, &cam, tf, s, &c).unwrap().unwrap();
    let g = film.resolve();
    let lit = cpu.pixels.iter().filter(|p| p[3] > 0.05).count();
    assert!(
        lit > cpu.pixels.len() / 10,
        "the scene shows too little ({lit} pixels)"
    );
    let to8 = |x: f32| (x.clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0).round() as i32;
    let mut worst = 0;
    for (a, b) in cpu.pixels.iter().zip(&g.pixels) {
        for k in 0..4 {
            worst = worst.max((to8(a[k]) - to8(b[k])).unsigned_abs());
        }
    }
    worst as u8
}

fn settings(v: &ParticleVolume) -> RenderSettings {
    let mut s = RenderSettings::for_volume(v, 64, 48);
    s.opacity_scale *= 4.0;
    s
}

#[test]
fn renders_equal_the_cpu_for_every_kernel_and_classification() {
    let Some(gpu) = gpu() else { return };
    let tf = TransferFunction::default_for_density();
    for kernel in KERNELS {
        for (attribute, classification) in [
            (false, Classification::Post),
            (true, Classification::Post),
            (true, Classification::Pre),
        ] {
            let v = volume(kernel, classification, attribute);
            let s = settings(&v);
            let d = render_diff(&gpu, &v, &tf, &s);
            assert!(
                d <= 1,
                "{kernel:?} {classification:?} attribute {attribute}: {d}/255"
            );
        }
    }
}

#[test]
fn renders_equal_the_cpu_shaded_log_scaled_clipped_and_jittered() {
    let Some(gpu) = gpu() else { return };
    let tf = TransferFunction::new(
        Colormap::preset("inferno").unwrap(),
        OpacityMap::preset("linear").unwrap(),
    );
    for kernel in [
        Kernel::Gaussian3,
        Kernel::CubicSpline,
        Kernel::QuarticSpline,
        Kernel::WendlandC4,
    ] {
        let v = volume(kernel, Classification::Post, true);
        let mut s = settings(&v);
        s.light = Some(Light {
            direction: Vec3::new(0.3, -0.5, 0.8).normalized(),
            ambient: 0.3,
        });
        let d = render_diff(&gpu, &v, &tf, &s);
        assert!(d <= 1, "{kernel:?} shaded: {d}/255");
        let mut s = settings(&v);
        s.log_scale = true;
        let hi = s.value_range.hi.max(1e-30).log10();
        s.value_range = Range1::new(hi - 3.0, hi);
        s.spp = 3;
        s.early_termination = 0.9;
        let b = v.bounds();
        s.clip = Some(Aabb::new(b.min, b.center() + Vec3::new(0.2, 0.2, 0.2)));
        let d = render_diff(&gpu, &v, &tf, &s);
        assert!(d <= 1, "{kernel:?} log scale, 3 spp, clipped: {d}/255");
    }
}

/// The largest difference of two projections over the peak, and of their
/// sums.
fn compare(cpu: &[f32], gpu: &[f32]) -> (f64, f64) {
    let peak = cpu.iter().fold(0.0f64, |m, &v| m.max(v as f64));
    assert!(peak > 0.0);
    let d = cpu
        .iter()
        .zip(gpu)
        .map(|(&a, &b)| (a as f64 - b as f64).abs())
        .fold(0.0, f64::max);
    let (sa, sb): (f64, f64) = (
        cpu.iter().map(|&v| v as f64).sum(),
        gpu.iter().map(|&v| v as f64).sum(),
    );
    (d / peak, (sa - sb).abs() / sa)
}

fn splat(
    kernel: Kernel,
    cam: &Camera,
    periodic: Option<Aabb>,
    pixels: PixelIntegral,
    device: Option<&Gpu>,
) -> Vec<f32> {
    let d = data(4000);
    let radii = d.radii.as_ref().unwrap();
    let weights = d.weights.as_ref().unwrap();
    let parts: Vec<SplatParticle> = (0..d.positions.len())
        .map(|i| SplatParticle {
            center: d.positions[i],
            radius: radii[i],
            weight: weights[i],
        })
        .collect();
    let mut s = Splatter::new(cam, 96, 80, kernel, periodic)
        .unwrap()
        .with_pixels(pixels);
    if let Some(g) = device {
        s = s.with_device(g).unwrap();
    }
    // In chunks, as a streamed file comes.
    for (k, chunk) in parts.chunks(1500).enumerate() {
        s.add(chunk, k * 1500, &Control::new()).unwrap();
    }
    s.finish().unwrap()
}

#[test]
fn projections_equal_the_cpu_for_every_kernel_periodic_area_and_off_axis() {
    let Some(gpu) = gpu() else { return };
    let unit = Aabb::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 1.0));
    let on_axis = Camera::axis_projection(&unit, 2).unwrap();
    let off_axis = Camera::look_at(
        Vec3::new(2.0, -1.5, 1.8),
        Vec3::new(0.5, 0.5, 0.5),
        Vec3::new(0.0, 0.0, 1.0),
        Projection::Orthographic {
            half_width: 0.9,
            half_height: 0.75,
        },
    )
    .unwrap();
    for kernel in KERNELS {
        for (name, cam, periodic, pixels) in [
            ("on axis", &on_axis, None, PixelIntegral::Centre),
            ("off axis", &off_axis, None, PixelIntegral::Centre),
            ("periodic", &on_axis, Some(unit), PixelIntegral::Centre),
            (
                "periodic off axis",
                &off_axis,
                Some(unit),
                PixelIntegral::Centre,
            ),
            ("pixel areas", &on_axis, None, PixelIntegral::Area),
        ] {
            let cpu = splat(kernel, cam, periodic, pixels, None);
            let g = splat(kernel, cam, periodic, pixels, Some(&gpu));
            let (px, sum) = compare(&cpu, &g);
            assert!(
                px <= 1e-5 && sum <= 1e-5,
                "{kernel:?} {name}: pixel {px:.1e}, Σ {sum:.1e}"
            );
        }
    }
}

#[test]
fn settings_the_gpu_does_not_carry_are_refused_by_name() {
    let Some(gpu) = gpu() else { return };
    let v = volume(Kernel::Gaussian3, Classification::Post, false);
    let tf = TransferFunction::default_for_density();
    let mut s = settings(&v);
    s.iso = vec![0.5];
    let e = gpu
        .render_film(&v, &camera(&v), &tf, &s, &Control::new())
        .err()
        .expect("iso-surfaces refused");
    assert!(e.to_string().contains("iso-surfaces"), "{e}");
}

#[test]
fn a_buffer_beyond_the_adapter_limit_is_refused_naming_the_limit() {
    let Some(gpu) = gpu() else { return };
    let cam = Camera::axis_projection(&Aabb::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 1.0)), 2).unwrap();
    // An image one pixel row beyond the adapter's storage binding (128 MiB
    // on lavapipe): refused before anything is made.
    let side = ((gpu.max_buffer_bytes() / 4) as f64).sqrt() as u32 + 2;
    let e = Splatter::new(&cam, side, side, Kernel::CubicSpline, None)
        .unwrap()
        .with_device(&gpu)
        .err()
        .expect("refused");
    let m = e.to_string();
    assert!(m.contains("max_storage_buffer_binding_size"), "{m}");
}

/// Rays that take more loop iterations than Mesa's llvmpipe lets one shader
/// invocation run (65,535 over all its loops): dense, overlapping particles
/// and a fine step. The march stops at a budget and is dispatched again,
/// so no ray is cut short (on lavapipe they were: whole rays lost a
/// quarter of their optical depth).
#[test]
fn rays_longer_than_a_software_loop_limit_are_not_cut_short() {
    let Some(gpu) = gpu() else { return };
    let mut r = SmallRng(9);
    let n = 6000;
    let positions: Vec<Vec3> = (0..n)
        .map(|_| Vec3::new(r.f(), r.f(), r.f()) * 0.5)
        .collect();
    let d = ParticleData {
        radii: Some(vec![0.12; n]),
        weights: None,
        attribute: Some(positions.iter().map(|p| p.x + p.y).collect()),
        positions,
    };
    let settings = ParticleSettings {
        kernel: Kernel::CubicSpline,
        ..Default::default()
    };
    let v = ParticleVolume::new(d, settings).unwrap();
    let tf = TransferFunction::default_for_density();
    let mut s = RenderSettings::for_volume(&v, 24, 16);
    s.sampling_rate = 4.0;
    // Light enough that no ray stops early: every ray walks its whole span.
    s.opacity_scale *= 0.2;
    let diff = render_diff(&gpu, &v, &tf, &s);
    assert!(diff <= 1, "{diff}/255");
}
