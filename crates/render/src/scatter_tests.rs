//! Single scattering: convergence, the blue-noise spectrum, and the two
//! free-flight samplers against each other, on a cheap procedural volume.

use super::*;
use voxless_transfer::{Colormap, OpacityMap};

use crate::test_volumes::{BatchedBlob, Blob};

fn setup(
    size: u32,
    noise: Noise,
    method: FreeFlight,
) -> (Camera, TransferFunction, RenderSettings) {
    let camera = Camera::framing(&Blob.bounds(), 1.0);
    let tf = TransferFunction::new(
        Colormap::preset("viridis").unwrap(),
        OpacityMap::preset("linear").unwrap(),
    );
    let mut s = RenderSettings::for_volume(&Blob, size, size);
    s.opacity_scale = 3.0;
    s.scatter = Some(Scatter {
        light: LightSource::Directional(Vec3::new(0.3, 1.0, 0.2).normalized()),
        intensity: 1.0,
        ambient: 0.2,
        method,
        noise,
    });
    (camera, tf, s)
}

fn render_spp(size: u32, spp: u32, noise: Noise, method: FreeFlight, seed: u64) -> Image {
    let (camera, tf, mut s) = setup(size, noise, method);
    s.spp = spp;
    s.seed = seed;
    render(&Blob, &camera, &tf, &s, &Control::new()).unwrap()
}

fn rmse(a: &Image, b: &Image) -> f64 {
    let sum: f64 = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(p, q)| (0..4).map(move |c| ((p[c] - q[c]) as f64).powi(2)))
        .sum();
    (sum / (4 * a.pixels.len()) as f64).sqrt()
}

#[test]
fn accumulated_samples_converge_like_one_over_sqrt_spp() {
    let size = 24;
    let reference = render_spp(size, 1024, Noise::White, FreeFlight::Marching, 99);
    let e: Vec<f64> = [4, 16, 64]
        .iter()
        .map(|&n| {
            rmse(
                &render_spp(size, n, Noise::White, FreeFlight::Marching, 1),
                &reference,
            )
        })
        .collect();
    eprintln!("RMSE at 4, 16, 64 spp: {e:?}");
    // 4× the samples → half the error (the reference's own noise adds ~1 %).
    for w in e.windows(2) {
        let ratio = w[0] / w[1];
        assert!((1.6..2.5).contains(&ratio), "RMSE {e:?}: ratio {ratio}");
    }
    // Blue noise converges too, and no slower.
    let blue = rmse(
        &render_spp(size, 64, Noise::Blue, FreeFlight::Marching, 1),
        &reference,
    );
    assert!(blue <= e[2] * 1.1, "blue {blue} vs white {}", e[2]);
}

#[test]
fn blue_noise_error_has_less_low_frequency_energy_than_white_noise() {
    const N: usize = bluenoise::SIZE;
    let (camera, tf, mut s) = setup(N as u32, Noise::Blue, FreeFlight::Marching);
    // The exact expected opacity of a 1-spp sample: marching's event
    // probability over the same jittered segments is 1 − exp(−Σ σ·len),
    // which is what `march` composites without early termination.
    let mut ea = s.clone();
    ea.scatter = None;
    ea.early_termination = 1.0;
    let expected = render(&Blob, &camera, &tf, &ea, &Control::new()).unwrap();
    let mut low_energy = |noise: Noise| {
        s.scatter.as_mut().unwrap().noise = noise;
        let img = render(&Blob, &camera, &tf, &s, &Control::new()).unwrap();
        let err: Vec<f64> = img
            .pixels
            .iter()
            .zip(&expected.pixels)
            .map(|(p, q)| (p[3] - q[3]) as f64)
            .collect();
        let spectrum = radial_power(&err, N);
        // Radii 0..N/8: the lowest eighth of the frequencies.
        spectrum[..N / 8].iter().sum::<f64>()
    };
    let blue = low_energy(Noise::Blue);
    let white = low_energy(Noise::White);
    eprintln!("low-frequency error energy: blue {blue:.3e}, white {white:.3e}");
    assert!(
        blue < 0.5 * white,
        "low-frequency error energy: blue {blue:.3e} vs white {white:.3e}"
    );
}

/// Radially averaged power spectrum of an `n`×`n` image (naive DFT, fine at
/// 64²): entry `r` averages |F(u, v)|² over integer radius `r`.
fn radial_power(img: &[f64], n: usize) -> Vec<f64> {
    let tw: Vec<(f64, f64)> = (0..n)
        .map(|k| {
            let a = -2.0 * std::f64::consts::PI * k as f64 / n as f64;
            (a.cos(), a.sin())
        })
        .collect();
    // Rows, then columns.
    let mut rows = vec![(0.0, 0.0); n * n];
    for y in 0..n {
        for u in 0..n {
            let (mut re, mut im) = (0.0, 0.0);
            for x in 0..n {
                let (c, s) = tw[(u * x) % n];
                re += img[y * n + x] * c;
                im += img[y * n + x] * s;
            }
            rows[y * n + u] = (re, im);
        }
    }
    let mut sums = vec![0.0; n];
    let mut counts = vec![0u32; n];
    for v in 0..n {
        for u in 0..n {
            let (mut re, mut im) = (0.0, 0.0);
            for y in 0..n {
                let (c, s) = tw[(v * y) % n];
                let (a, b) = rows[y * n + u];
                re += a * c - b * s;
                im += a * s + b * c;
            }
            let fu = u.min(n - u) as f64;
            let fv = v.min(n - v) as f64;
            let r = (fu * fu + fv * fv).sqrt().round() as usize;
            if r < n {
                sums[r] += re * re + im * im;
                counts[r] += 1;
            }
        }
    }
    sums.iter()
        .zip(&counts)
        .map(|(s, &c)| if c > 0 { s / c as f64 } else { 0.0 })
        .collect()
}

#[test]
fn marching_and_delta_tracking_converge_to_the_same_image() {
    let size = 24;
    let spp = 1024;
    let a = render_spp(size, spp, Noise::White, FreeFlight::Marching, 3);
    let b = render_spp(size, spp, Noise::White, FreeFlight::DeltaTracking, 4);
    // Compare 4×4 block means (each averages 16 × 1024 paths, so noise is
    // ~0.004 per block); the marcher's step bias is far below that.
    let block = |img: &Image, bx: usize, by: usize, c: usize| {
        let mut s = 0.0;
        for y in by * 4..by * 4 + 4 {
            for x in bx * 4..bx * 4 + 4 {
                s += img.pixels[y * size as usize + x][c] as f64;
            }
        }
        s / 16.0
    };
    let mut worst = 0.0f64;
    for by in 0..size as usize / 4 {
        for bx in 0..size as usize / 4 {
            for c in 0..4 {
                worst = worst.max((block(&a, bx, by, c) - block(&b, bx, by, c)).abs());
            }
        }
    }
    eprintln!("marching vs delta tracking: worst block difference {worst:.4}");
    assert!(worst < 0.02, "block means differ by {worst}");
    // And the image is not trivially empty.
    assert!(a.pixels.iter().any(|p| p[3] > 0.5));
}

#[test]
fn shadows_darken_the_side_away_from_the_light() {
    let (camera, tf, mut s) = setup(32, Noise::Blue, FreeFlight::Marching);
    s.spp = 64;
    let lit = render(&Blob, &camera, &tf, &s, &Control::new()).unwrap();
    s.scatter.as_mut().unwrap().ambient = 1.0; // no shadows at all
    let flat = render(&Blob, &camera, &tf, &s, &Control::new()).unwrap();
    let sum = |img: &Image| img.pixels.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>();
    assert!(sum(&lit) < 0.9 * sum(&flat), "shadows must remove light");
}

/// Every pixel of a render on the packet path equals the per-ray path's:
/// the same lattice, random numbers and sums, only batched.
#[test]
fn packet_paths_draw_the_per_ray_image() {
    for (noise, light) in [
        (
            Noise::Blue,
            LightSource::Directional(Vec3::new(0.3, 1.0, 0.2).normalized()),
        ),
        (Noise::White, LightSource::Point(Vec3::new(1.5, 0.5, -2.0))),
    ] {
        let (camera, tf, mut s) = setup(40, noise, FreeFlight::Marching);
        s.spp = 4;
        s.scatter.as_mut().unwrap().light = light;
        let per_ray = render(&Blob, &camera, &tf, &s, &Control::new()).unwrap();
        let packets = render(&BatchedBlob, &camera, &tf, &s, &Control::new()).unwrap();
        assert!(per_ray.pixels.iter().any(|p| p[3] > 0.5));
        let differ = per_ray
            .pixels
            .iter()
            .zip(&packets.pixels)
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(differ, 0, "{noise:?}, {light:?}: {differ} pixels differ");
    }
}

/// The packet path converges like the per-ray path (1/√spp) to the same
/// reference, and with blue noise no slower than white.
#[test]
fn packet_shadows_converge_like_per_ray_shadows() {
    let size = 24;
    let reference = render_spp(size, 1024, Noise::White, FreeFlight::Marching, 99);
    let packets = |spp: u32, noise: Noise| {
        let (camera, tf, mut s) = setup(size, noise, FreeFlight::Marching);
        s.spp = spp;
        s.seed = 1;
        render(&BatchedBlob, &camera, &tf, &s, &Control::new()).unwrap()
    };
    let e: Vec<f64> = [4, 16, 64]
        .iter()
        .map(|&n| rmse(&packets(n, Noise::White), &reference))
        .collect();
    eprintln!("packet path RMSE at 4, 16, 64 spp: {e:?}");
    for w in e.windows(2) {
        let ratio = w[0] / w[1];
        assert!((1.6..2.5).contains(&ratio), "RMSE {e:?}: ratio {ratio}");
    }
    let blue = rmse(&packets(64, Noise::Blue), &reference);
    assert!(blue <= e[2] * 1.1, "blue {blue} vs white {}", e[2]);
}
