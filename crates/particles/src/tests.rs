#![allow(clippy::needless_range_loop)] // component loops over x, y, z read clearest
//! Known-answer tests: every field the BVH path computes is compared with a
//! brute-force sum over all particles written from the kernel definitions.

use super::*;
use voxless_core::SmallRng as Lcg;
use voxless_core::simd::Simd;
use voxless_core::{Aabb, Range1, Ray, Vec3, Volume};
use voxless_transfer::{Colormap, ControlPoints, OpacityMap, TransferFunction};

fn random_data(n: usize, seed: u64) -> ParticleData {
    let mut rng = Lcg(seed);
    ParticleData {
        positions: (0..n).map(|_| rng.v()).collect(),
        radii: Some((0..n).map(|_| 0.04 + 0.06 * rng.f()).collect()),
        attribute: Some((0..n).map(|_| 10.0 * rng.f() - 3.0).collect()),
        weights: Some((0..n).map(|_| 0.5 + rng.f()).collect()),
    }
}

pub(crate) const KERNELS: [Kernel; 8] = [
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

/// The SPH kernels beyond M4 as the literature writes them, independent of
/// the crate's forms: `(W, dW/dd)` at distance `d` for smoothing length `h`.
/// M5 and M6 piecewise (Price 2012, eqs. 5–6 with σ₃ = 1/20π, 1/120π);
/// Wendland in `x = d/H` with `H = 2h` (Dehnen & Aly 2012, table 1).
fn reference_sph(k: Kernel, d: f64, h: f64) -> (f64, f64) {
    let pi = std::f64::consts::PI;
    let q = d / h;
    let (w, dw) = match k {
        Kernel::QuarticSpline => {
            let (a, b, c) = (2.5 - q, 1.5 - q, 0.5 - q);
            let (w, dw) = if q < 0.5 {
                (
                    a.powi(4) - 5.0 * b.powi(4) + 10.0 * c.powi(4),
                    -4.0 * a.powi(3) + 20.0 * b.powi(3) - 40.0 * c.powi(3),
                )
            } else if q < 1.5 {
                (
                    a.powi(4) - 5.0 * b.powi(4),
                    -4.0 * a.powi(3) + 20.0 * b.powi(3),
                )
            } else if q < 2.5 {
                (a.powi(4), -4.0 * a.powi(3))
            } else {
                (0.0, 0.0)
            };
            (w / (20.0 * pi), dw / (20.0 * pi))
        }
        Kernel::QuinticSpline => {
            let (a, b, c) = (3.0 - q, 2.0 - q, 1.0 - q);
            let (w, dw) = if q < 1.0 {
                (
                    a.powi(5) - 6.0 * b.powi(5) + 15.0 * c.powi(5),
                    -5.0 * a.powi(4) + 30.0 * b.powi(4) - 75.0 * c.powi(4),
                )
            } else if q < 2.0 {
                (
                    a.powi(5) - 6.0 * b.powi(5),
                    -5.0 * a.powi(4) + 30.0 * b.powi(4),
                )
            } else if q < 3.0 {
                (a.powi(5), -5.0 * a.powi(4))
            } else {
                (0.0, 0.0)
            };
            (w / (120.0 * pi), dw / (120.0 * pi))
        }
        Kernel::WendlandC2 | Kernel::WendlandC4 | Kernel::WendlandC6 => {
            // W = norm/H³ · (1−x)^n P(x); dW/dx by the product rule.
            let x = q / 2.0;
            let (norm, n, p, dp): (f64, i32, f64, f64) = match k {
                Kernel::WendlandC2 => (21.0 / (2.0 * pi), 4, 1.0 + 4.0 * x, 4.0),
                Kernel::WendlandC4 => (
                    495.0 / (32.0 * pi),
                    6,
                    1.0 + 6.0 * x + 35.0 / 3.0 * x * x,
                    6.0 + 70.0 / 3.0 * x,
                ),
                _ => (
                    1365.0 / (64.0 * pi),
                    8,
                    1.0 + 8.0 * x + 25.0 * x * x + 32.0 * x.powi(3),
                    8.0 + 50.0 * x + 96.0 * x * x,
                ),
            };
            let t = (1.0 - x).max(0.0);
            let w = t.powi(n) * p;
            let dw = -(n as f64) * t.powi(n - 1) * p + t.powi(n) * dp;
            // In units of h: H³ = 8h³ and dx/dq = 1/2.
            (norm / 8.0 * w, norm / 16.0 * dw)
        }
        _ => unreachable!(),
    };
    (w / h.powi(3), dw / h.powi(4))
}

/// φ and dφ/dd per the formulas in the kernel docs, in f64.
pub(crate) fn reference_kernel(k: Kernel, d: f64, r: f64, w: f64) -> (f64, f64) {
    match k {
        Kernel::Gaussian3 if d <= r => {
            let v = w * (-0.5 * (3.0 * d / r).powi(2)).exp();
            (v, -9.0 * d / (r * r) * v)
        }
        Kernel::Gaussian { kappa, sigma } if d <= sigma as f64 * r => {
            let v = kappa as f64 * w * (-d * d / (2.0 * r * r)).exp();
            (v, -d / (r * r) * v)
        }
        Kernel::CubicSpline if d <= 2.0 * r => {
            let q = d / r;
            let norm = w / (std::f64::consts::PI * r.powi(3));
            if q < 1.0 {
                (
                    norm * (1.0 - 1.5 * q * q + 0.75 * q.powi(3)),
                    norm * (-3.0 * q + 2.25 * q * q) / r,
                )
            } else {
                (
                    norm * 0.25 * (2.0 - q).powi(3),
                    norm * -0.75 * (2.0 - q).powi(2) / r,
                )
            }
        }
        k if k.sph().is_some() && d <= k.support_factor() as f64 * r => {
            let (v, dv) = reference_sph(k, d, r);
            (w * v, w * dv)
        }
        _ => (0.0, 0.0),
    }
}

/// (Φ, Θ, ∇Φ, Σ|∇φᵢ|) by summing over every particle.
fn brute_force(data: &ParticleData, k: Kernel, p: Vec3) -> (f64, f64, [f64; 3], f64) {
    let (mut phi, mut num, mut g, mut gabs) = (0.0, 0.0, [0.0; 3], 0.0);
    for i in 0..data.positions.len() {
        let c = data.positions[i];
        let dv = [(p.x - c.x) as f64, (p.y - c.y) as f64, (p.z - c.z) as f64];
        let d = (dv[0] * dv[0] + dv[1] * dv[1] + dv[2] * dv[2]).sqrt();
        let r = data.radii.as_ref().unwrap()[i] as f64;
        let w = data.weights.as_ref().unwrap()[i] as f64;
        let (v, dd) = reference_kernel(k, d, r, w);
        phi += v;
        num += v * data.attribute.as_ref().unwrap()[i] as f64;
        if d > 0.0 {
            for a in 0..3 {
                g[a] += dd * dv[a] / d;
            }
            gabs += dd.abs();
        }
    }
    (phi, if phi > 0.0 { num / phi } else { f64::NAN }, g, gabs)
}

#[test]
fn fields_equal_brute_force_for_every_kernel_and_cluster_size() {
    let data = random_data(2000, 42);
    for kernel in KERNELS {
        for cluster_size in [1, 4, 16] {
            let settings = ParticleSettings {
                kernel,
                cluster_size,
                ..Default::default()
            };
            let vol = ParticleVolume::new(data.clone(), settings).unwrap();
            vol.validate().unwrap();
            let max_phi = vol.value_range().hi as f64;
            let mut rng = Lcg(7 + cluster_size as u64);
            let bounds = vol.bounds();
            let mut checked = 0;
            for _ in 0..10_000 {
                let p = bounds.min + rng.v().mul_elem(bounds.extent());
                let (phi, theta, g, gabs) = brute_force(&data, kernel, p);
                let f = vol.field(p, true);
                if phi < 1e-6 * max_phi {
                    continue;
                }
                // The canonical-order sums (`sample`, decomposed sets) are
                // the same field.
                let e = vol.field_exact(p, true);
                assert!(
                    (e.density - f.density).abs() <= 1e-5 * f.density.abs(),
                    "{kernel:?} exact Φ {} vs {}",
                    e.density,
                    f.density
                );
                checked += 1;
                let rel = |a: f64, b: f64, scale: f64| (a - b).abs() / scale;
                assert!(
                    rel(f.density as f64, phi, phi) <= 1e-5,
                    "{kernel:?} N={cluster_size} Φ {} vs {phi}",
                    f.density
                );
                // Θ is an average of values in [-3, 7]: relative to that scale.
                assert!(
                    rel(f.attribute as f64, theta, 10.0) <= 1e-5,
                    "Θ {} vs {theta}",
                    f.attribute
                );
                // Gradient components can cancel, so compare against Σ|∇φᵢ|.
                for a in 0..3 {
                    assert!(
                        rel(f.gradient[a] as f64, g[a], gabs) <= 1e-5,
                        "{kernel:?} ∇Φ[{a}] {} vs {}",
                        f.gradient[a],
                        g[a]
                    );
                }
            }
            assert!(
                checked > 5000,
                "only {checked} points had Φ above the threshold"
            );
        }
    }
}

#[test]
fn point_query_returns_exactly_the_overlapping_particles() {
    let data = random_data(3000, 5);
    for cluster_size in [1, 3, 16] {
        let vol = ParticleVolume::new(
            data.clone(),
            ParticleSettings {
                cluster_size,
                ..Default::default()
            },
        )
        .unwrap();
        let radii = data.radii.as_ref().unwrap();
        assert_overlaps_match(&vol, &data.positions, |i| radii[i], 9, 2000);
    }
}

/// The BVH point query returns exactly the particles (input indices) whose
/// support `radius_of(i)` contains each of `count` random points.
fn assert_overlaps_match(
    vol: &ParticleVolume,
    positions: &[Vec3],
    radius_of: impl Fn(usize) -> f32,
    seed: u64,
    count: usize,
) {
    let mut rng = Lcg(seed);
    for _ in 0..count {
        let p = rng.v();
        let mut got: Vec<u32> = vol
            .overlapping(p)
            .iter()
            .map(|&i| vol.original_index()[i])
            .collect();
        got.sort_unstable();
        let want: Vec<u32> = (0..positions.len())
            .filter(|&i| {
                let r = radius_of(i);
                r > 0.0 && (p - positions[i]).length_squared() <= r * r
            })
            .map(|i| i as u32)
            .collect();
        assert_eq!(got, want, "at {p:?}");
    }
}

#[test]
fn radius_map_refits_and_stays_exact() {
    let mut data = random_data(4000, 8);
    data.radii = None;
    let settings = ParticleSettings {
        radius: 0.05,
        cluster_size: 8,
        ..Default::default()
    };
    let mut vol = ParticleVolume::new(data.clone(), settings).unwrap();
    let nodes_before = vol.bvh().nodes().len();
    // Small attributes shrink to nothing (hidden), large ones double.
    let map = ControlPoints::new("radius map", &[(0.0, 0.0), (0.3, 0.0), (1.0, 2.0)]).unwrap();
    vol.set_radius(0.05, Some(map.clone())).unwrap();
    vol.validate().unwrap();
    assert_eq!(
        vol.bvh().nodes().len(),
        nodes_before,
        "refit keeps the topology"
    );
    let attr = data.attribute.as_ref().unwrap();
    let range = vol.attribute_range().unwrap();
    let radius_of = |i: usize| 0.05 * map.eval(range.normalize(attr[i])).max(0.0);
    assert_overlaps_match(&vol, &data.positions, radius_of, 1, 3000);
    // A global radius change refits too.
    vol.set_radius(0.08, None).unwrap();
    vol.validate().unwrap();
    assert!(vol.radii().iter().all(|&r| r == 0.08));
}

#[test]
fn line_integral_matches_quadrature_of_samples() {
    let data = random_data(500, 3);
    for kernel in KERNELS {
        let vol = ParticleVolume::new(
            data.clone(),
            ParticleSettings {
                kernel,
                ..Default::default()
            },
        )
        .unwrap();
        let mut rng = Lcg(4);
        for _ in 0..12 {
            let o = Vec3::new(rng.f(), rng.f(), -1.0);
            let ray = Ray::new(
                o,
                (Vec3::new(rng.f(), rng.f(), 1.0) - o + Vec3::new(0.0, 0.0, 1.0)).normalized(),
            );
            // Partial chords too: stop inside the cube.
            for t in [Range1::new(0.0, 10.0), Range1::new(0.0, 1.0 + rng.f())] {
                let exact = vol.line_integral(&ray, t);
                let f = |s: f64| vol.density(ray.at(s as f32)) as f64;
                // Every support lies within t < 4; the truncated Gaussians jump
                // at their support edge, so the quadrature needs a fine step.
                let quad = voxless_core::simpson(f, t.lo as f64, t.hi.min(4.0) as f64, 400_000);
                assert!(
                    (exact - quad).abs() <= 1e-4 * quad.max(1e-3),
                    "{kernel:?}: exact {exact} vs quadrature {quad}"
                );
            }
        }
    }
}

#[test]
fn kernel_integrals_match_radial_quadrature() {
    for kernel in KERNELS {
        let r = 0.7;
        let support = kernel.support_factor() as f64 * r;
        let f = |d: f64| 4.0 * std::f64::consts::PI * d * d * reference_kernel(kernel, d, r, 1.0).0;
        let quad = voxless_core::simpson(f, 0.0, support * (1.0 - 1e-12), 200_000);
        let exact = kernel.integral(r);
        assert!(
            (quad - exact).abs() < 1e-6 * exact,
            "{kernel:?}: {quad} vs {exact}"
        );
    }
}

#[test]
fn pre_classification_averages_colours() {
    // Two overlapping particles with attributes at the ends of the range.
    let data = ParticleData {
        positions: vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.5, 0.0, 0.0)],
        radii: None,
        attribute: Some(vec![0.0, 1.0]),
        weights: None,
    };
    let vol = ParticleVolume::new(
        data,
        ParticleSettings {
            radius: 1.0,
            classification: Classification::Pre,
            ..Default::default()
        },
    )
    .unwrap();
    let tf = TransferFunction::new(
        Colormap::preset("cool-warm").unwrap(),
        OpacityMap::preset("linear").unwrap(),
    );
    let colors = vol.preclassify_with(&tf);
    let p = Vec3::new(0.1, 0.0, 0.0);
    let w0 = (-4.5f32 * 0.01).exp();
    let w1 = (-4.5f32 * 0.16).exp();
    let want = (tf.color(0.0) * w0 + tf.color(1.0) * w1) / (w0 + w1);
    let got = vol.field_with(&colors, p, false).color.unwrap();
    assert!((got - want).length() < 1e-5, "{got:?} vs {want:?}");
    // Post-classification would colour-map Θ instead: a different colour.
    let theta = vol.field(p, false).attribute;
    assert!((theta - w1 / (w0 + w1)).abs() < 1e-5);
}

#[test]
fn bad_input_is_a_clear_error() {
    let ok = random_data(10, 1);
    let s = ParticleSettings::default();
    // The error a change to the good data (and/or settings) produces.
    let error = |edit: &dyn Fn(&mut ParticleData), settings: ParticleSettings| {
        let mut d = ok.clone();
        edit(&mut d);
        ParticleVolume::new(d, settings)
            .err()
            .expect("bad input must be refused")
    };
    let e = error(&|d| d.positions[3].y = f32::NAN, s.clone());
    let want = format!(
        "particle 3 has a non-finite coordinate ({}, NaN, {})",
        ok.positions[3].x, ok.positions[3].z
    );
    assert_eq!(e.to_string(), want);
    let e = error(&|d| d.radii.as_mut().unwrap()[4] = 0.0, s.clone());
    assert!(e.to_string().contains("particle 4 has radius 0"), "{e}");
    let e = error(&|d| d.radii.as_mut().unwrap()[2] = -1.0, s.clone());
    assert!(
        matches!(e, ParticleError::BadRadius { index: 2, .. }),
        "{e}"
    );
    let e = error(&|d| d.attribute.as_mut().unwrap().truncate(9), s.clone());
    assert!(
        e.to_string()
            .contains("attribute has 9 values but there are 10 particles"),
        "{e}"
    );
    assert!(matches!(
        error(&|d| *d = ParticleData::default(), s.clone()),
        ParticleError::Empty
    ));
    let e = error(
        &|d| d.weights.as_mut().unwrap()[0] = f32::INFINITY,
        s.clone(),
    );
    assert!(
        matches!(e, ParticleError::BadWeight { index: 0, .. }),
        "{e}"
    );
    for radius in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        let e = error(
            &|d| d.radii = None,
            ParticleSettings {
                radius,
                ..s.clone()
            },
        );
        assert!(matches!(e, ParticleError::BadGlobalRadius { .. }), "{e}");
    }
    for cluster_size in [0, 17] {
        let e = error(
            &|_| {},
            ParticleSettings {
                cluster_size,
                ..s.clone()
            },
        );
        assert!(matches!(e, ParticleError::BadClusterSize { .. }), "{e}");
    }
    let map = ControlPoints::new("weight map", &[(0.0, 1.0)]).unwrap();
    let e = error(
        &|d| d.attribute = None,
        ParticleSettings {
            weight_map: Some(map),
            ..s
        },
    );
    assert!(matches!(e, ParticleError::NeedsAttribute { .. }), "{e}");
}

#[test]
fn huge_radii_are_refused_not_rendered_forever() {
    // A support far larger than the data would make every sample visit every
    // particle: refused up front, and a refit to such a radius is refused too.
    let mut big = random_data(5000, 2);
    big.radii = None;
    let s = ParticleSettings::default();
    let e = ParticleVolume::new(
        big.clone(),
        ParticleSettings {
            radius: 1e6,
            ..s.clone()
        },
    )
    .err()
    .unwrap();
    assert!(matches!(e, ParticleError::HugeRadius { .. }), "{e}");
    assert!(e.to_string().contains("radius too large"), "{e}");
    let mut vol = ParticleVolume::new(big, ParticleSettings { radius: 0.05, ..s }).unwrap();
    assert!(vol.set_radius(1e6, None).is_err());
    assert!(
        vol.radii().iter().all(|&r| r == 0.05),
        "a refused change leaves the volume as it was"
    );
    vol.validate().unwrap();
}

#[test]
fn intervals_cover_every_nonzero_sample_with_its_range() {
    let data = random_data(1500, 12);
    let vol = ParticleVolume::new(data, ParticleSettings::default()).unwrap();
    let mut rng = Lcg(77);
    let mut out = Vec::new();
    for _ in 0..200 {
        let o = Vec3::new(rng.f(), rng.f(), -0.5);
        let ray = Ray::new(o, (rng.v() - o + Vec3::new(0.0, 0.0, 0.5)).normalized());
        let t = Range1::new(0.0, 5.0);
        out.clear();
        vol.intervals(&ray, t, &voxless_core::IntervalQuery::all(), &mut out);
        for w in out.windows(2) {
            assert!(w[0].t.hi <= w[1].t.lo, "intervals overlap or are unsorted");
        }
        for k in 0..2000 {
            let s = 5.0 * k as f32 / 2000.0;
            let phi = vol.density(ray.at(s));
            let inside = out.iter().find(|iv| iv.t.contains(s));
            match inside {
                Some(iv) => assert!(
                    iv.value_range.contains(phi),
                    "Φ {phi} outside {:?}",
                    iv.value_range
                ),
                None => assert!(
                    phi == 0.0
                        || out
                            .iter()
                            .any(|iv| (iv.t.lo - s).abs() < 1e-4 || (iv.t.hi - s).abs() < 1e-4),
                    "Φ {phi} in a gap at t = {s}"
                ),
            }
        }
    }
    let _ = Aabb::EMPTY;
}

#[test]
fn weight_map_scales_each_kernel() {
    let data = random_data(800, 21);
    let map = ControlPoints::new("weight map", &[(0.0, 0.0), (1.0, 2.0)]).unwrap();
    let vol = ParticleVolume::new(
        data.clone(),
        ParticleSettings {
            weight_map: Some(map.clone()),
            ..Default::default()
        },
    )
    .unwrap();
    let range = vol.attribute_range().unwrap();
    // Fold the map into the weights and compare with the brute-force sum.
    let mut mapped = data.clone();
    let attr = data.attribute.as_ref().unwrap();
    for (i, w) in mapped.weights.as_mut().unwrap().iter_mut().enumerate() {
        *w *= map.eval(range.normalize(attr[i]));
    }
    let mut rng = Lcg(5);
    for _ in 0..2000 {
        let p = rng.v();
        let (phi, ..) = brute_force(&mapped, Kernel::Gaussian3, p);
        let got = vol.density(p) as f64;
        assert!((got - phi).abs() <= 1e-5 * phi.max(1e-3), "{got} vs {phi}");
    }
}

#[test]
fn frames_rebuild_in_place_with_a_fixed_attribute_range() {
    let first = random_data(3000, 31);
    let mut vol = ParticleVolume::new(first, ParticleSettings::default()).unwrap();
    let range = vol.attribute_range().unwrap();
    let nodes = vol.bvh().nodes().as_ptr();
    // The next frame has fewer particles and a wider attribute spread.
    let mut next = random_data(2500, 32);
    for a in next.attribute.as_mut().unwrap() {
        *a *= 3.0;
    }
    vol.load_frame(next.clone()).unwrap();
    vol.validate().unwrap();
    assert_eq!(vol.len(), 2500);
    assert_eq!(
        vol.attribute_range(),
        Some(range),
        "no per-frame autoranging"
    );
    assert_eq!(
        vol.bvh().nodes().as_ptr(),
        nodes,
        "the node buffer is reused"
    );
    // Fields follow the new particles exactly.
    let mut rng = Lcg(33);
    for _ in 0..500 {
        let p = rng.v();
        let (phi, ..) = brute_force(&next, Kernel::Gaussian3, p);
        assert!((vol.density(p) as f64 - phi).abs() <= 1e-5 * phi.max(1e-3));
    }
    // A bad frame is refused and leaves the volume as it was.
    let mut bad = random_data(100, 34);
    bad.positions[7].x = f32::NAN;
    assert!(vol.load_frame(bad).is_err());
    assert_eq!(vol.len(), 2500);
    vol.validate().unwrap();
}

// ---------------------------------------------------------------- materials

fn two_materials(opacity_b: &str) -> (ParticleData, ParticleData, MaterialVolume) {
    let a = random_data(1500, 71);
    let mut b = random_data(1200, 72);
    // Material B sits a little to the side and has bigger particles.
    for p in b.positions.iter_mut() {
        *p += Vec3::new(0.3, 0.0, 0.0);
    }
    if let Some(r) = b.radii.as_mut() {
        r.iter_mut().for_each(|r| *r *= 1.5);
    }
    let material = |name: &str, data: &ParticleData, cmap: &str, op: &str, range: f32| Material {
        name: name.into(),
        volume: ParticleVolume::new(
            ParticleData {
                attribute: None,
                ..data.clone()
            },
            ParticleSettings {
                kernel: Kernel::Gaussian3,
                ..Default::default()
            },
        )
        .unwrap(),
        class: MaterialClass {
            tf: TransferFunction::new(
                Colormap::preset(cmap).unwrap(),
                OpacityMap::preset(op).unwrap(),
            ),
            value_range: Range1::new(0.0, range),
            color: None,
        },
    };
    let mats = vec![
        material("a", &a, "viridis", "linear", 40.0),
        material("b", &b, "magma", opacity_b, 30.0),
    ];
    (a, b, MaterialVolume::new(mats).unwrap())
}

#[test]
fn materials_blend_brute_force_classifications() {
    let (a, b, vol) = two_materials("ramp-high");
    let mut rng = Lcg(5);
    let mut checked = 0;
    for _ in 0..3000 {
        let p = rng.v() * 1.4 - Vec3::splat(0.05);
        let pa = brute_force(&a, Kernel::Gaussian3, p).0;
        let pb = brute_force(&b, Kernel::Gaussian3, p).0;
        let classes: Vec<&MaterialClass> = vol.materials().iter().map(|m| &m.class).collect();
        let (oa, ca) = classes[0].classify(pa as f32);
        let (ob, cb) = classes[1].classify(pb as f32);
        let Some(s) = vol.sample(p) else {
            assert!(
                pa == 0.0 && pb == 0.0,
                "uncovered point with density at {p:?}"
            );
            continue;
        };
        let want = oa + ob;
        assert!(
            (s.value - want).abs() <= 1e-5 * want.max(1e-3),
            "opacity {} vs {want}",
            s.value
        );
        if want > 1e-3 {
            let c = (ca * oa + cb * ob) / want;
            let voxless_core::Attribute::Rgb(got) = s.attribute else {
                panic!("classified samples carry a colour");
            };
            assert!((got - c).length() <= 1e-4, "colour {got:?} vs {c:?}");
            checked += 1;
        }
    }
    assert!(checked > 300, "only {checked} points inside the materials");
}

#[test]
fn materials_render_the_same_with_packets_and_a_hidden_material_drops_out() {
    use voxless_render::{RenderSettings, render};
    let (_, _, vol) = two_materials("ramp-high");
    let camera = voxless_core::Camera::framing(&vol.bounds(), 1.2);
    let tf = TransferFunction::default_for_density();
    let mut s = RenderSettings::for_volume(&vol, 48, 40);
    s.spp = 2;
    s.opacity_scale = 12.0;
    s.packets = false;
    let slow = render(&vol, &camera, &tf, &s, &voxless_core::Control::new()).unwrap();
    s.packets = true;
    let fast = render(&vol, &camera, &tf, &s, &voxless_core::Control::new()).unwrap();
    let diff = |x: &voxless_core::Image, y: &voxless_core::Image| {
        x.pixels
            .iter()
            .zip(&y.pixels)
            .flat_map(|(p, q)| (0..4).map(move |c| (p[c] - q[c]).abs()))
            .fold(0.0f32, f32::max)
    };
    assert!(slow.pixels.iter().filter(|p| p[3] > 0.05).count() > 100);
    assert!(diff(&slow, &fast) <= 1.0 / 255.0);
    // With material B's opacity zero, the image is material A's alone.
    let (_, _, mut both) = two_materials("linear");
    let (_, _, mut alone) = two_materials("linear");
    let mut mats = std::mem::take(&mut both.materials);
    mats[1].class.tf = TransferFunction::new(
        Colormap::preset("magma").unwrap(),
        OpacityMap::from_points(&[(0.0, 0.0), (1.0, 0.0)]).unwrap(),
    );
    let both = MaterialVolume::new(mats).unwrap();
    let mut mats = std::mem::take(&mut alone.materials);
    mats.truncate(1);
    let alone = MaterialVolume::new(mats).unwrap();
    let camera = voxless_core::Camera::framing(&both.bounds(), 1.2);
    let x = render(&both, &camera, &tf, &s, &voxless_core::Control::new()).unwrap();
    let y = render(&alone, &camera, &tf, &s, &voxless_core::Control::new()).unwrap();
    assert!(y.pixels.iter().filter(|p| p[3] > 0.05).count() > 100);
    // The sample lattice is cut where rays enter the volume's bounds, which
    // material B widens: the first cells of some rays move by a fraction of
    // a step, at the edge of A's supports where A's field vanishes.
    assert!(
        diff(&x, &y) <= 1e-4,
        "a hidden material changed the image by {}",
        diff(&x, &y)
    );
}

/// The column is the full chord integral, and the splatter adds it at
/// every pixel centre, on every SIMD backend: one particle at a time at
/// random sub-pixel positions against `w · column.at(b²)` per pixel in f64
/// (the lanes compute the table position in f32: ~1e-7 of the peak).
#[test]
fn splatted_columns_equal_the_pixel_loop_on_every_backend() {
    let mut rng = Lcg(17);
    let (n, side) = (64u32, 2.0f64);
    let bounds = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
    let cam = voxless_core::Camera::axis_projection(&bounds, 2).unwrap();
    let pixel = side / n as f64;
    for kernel in KERNELS {
        for _ in 0..20 {
            let r = 0.01 + 0.2 * rng.f() as f64;
            let column = kernel.column(r);
            let (cx, cy, w) = (
                1.6 * rng.f() as f64 - 0.8,
                1.6 * rng.f() as f64 - 0.8,
                0.5 + rng.f() as f64,
            );
            let b2 = 0.3 * rng.f() as f64 * r;
            let exact = kernel.chord_integral(b2, r, f64::NEG_INFINITY, f64::INFINITY);
            let peak = kernel.chord_integral(0.0, r, f64::NEG_INFINITY, f64::INFINITY);
            assert!((column.at(b2) - exact).abs() <= 1e-6 * peak, "{kernel:?}");
            let p = crate::splat::SplatParticle {
                center: Vec3::new(cx as f32, cy as f32, 0.3),
                radius: r as f32,
                weight: w as f32,
            };
            let slow: Vec<f64> = (0..n * n)
                .map(|k| {
                    let x = -1.0 + ((k % n) as f64 + 0.5) * pixel - p.center.x as f64;
                    let y = 1.0 - ((k / n) as f64 + 0.5) * pixel - p.center.y as f64;
                    w * column.at(x * x + y * y)
                })
                .collect();
            for simd in Simd::ALL.into_iter().filter(|s| s.available()) {
                let mut splatter = crate::splat::Splatter::new(&cam, n, n, kernel, None)
                    .unwrap()
                    .on(simd);
                splatter
                    .add(&[p], 0, &voxless_core::Control::new())
                    .unwrap();
                let fast = splatter.finish().unwrap();
                for (k, (x, y)) in fast.iter().zip(&slow).enumerate() {
                    assert!(
                        (*x as f64 - y).abs() <= 1e-6 * w * peak,
                        "{kernel:?} {simd:?} pixel {k}: {x} vs {y} (peak {peak})"
                    );
                }
            }
        }
    }
}

/// The projections' partial chords (tabled for the SPH kernels) against
/// Simpson's rule on the same chord: within 5·10⁻⁶ of the kernel's peak
/// column, for every kernel, radius and cut.
#[test]
fn tabled_partial_chords_equal_simpson() {
    let mut rng = Lcg(9);
    for kernel in KERNELS {
        for r in [0.01, 0.3, 7.0] {
            let support = kernel.support_factor() as f64 * r;
            let peak = kernel.chord_integral(0.0, r, f64::NEG_INFINITY, f64::INFINITY);
            for _ in 0..300 {
                let b2 = (support * rng.f() as f64).powi(2);
                let (a, b) = (
                    support * (2.0 * rng.f() as f64 - 1.0),
                    support * (2.0 * rng.f() as f64 - 1.0),
                );
                let (u0, u1) = (a.min(b), a.max(b));
                let slow = kernel.chord_integral(b2, r, u0, u1);
                let fast = kernel.chord_integral_tabled(b2, r, u0, u1);
                assert!(
                    (fast - slow).abs() <= 5e-6 * peak,
                    "{kernel:?} r {r}: tabled {fast} vs Simpson {slow} (peak {peak})"
                );
            }
        }
    }
}
