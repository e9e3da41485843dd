#![allow(clippy::needless_range_loop)] // component loops over x, y, z read clearest
//! Periodic boxes and neighbour radii against known answers: the periodic
//! field against a brute-force sum over every particle's images, shifted
//! boxes against rolled images, the projections' mass on and off axis
//! against the exact total, the splatted image against the per-pixel path,
//! and neighbour distances against a brute-force search.

use super::*;
use crate::neighbours::{PeriodicBox, neighbour_distances, smoothing_lengths};
use crate::tests::{KERNELS, reference_kernel};
use voxless_core::SmallRng as Lcg;
use voxless_core::{Aabb, Camera, Control, Projection, Range1, Vec3, Volume};

const L: f32 = 1.0;

fn unit_box() -> Aabb {
    Aabb::new(Vec3::ZERO, Vec3::splat(L))
}

/// `n` particles in the unit box, radii `r0..2·r0`, weights `0.5..1.5`.
fn data(n: usize, r0: f32, seed: u64) -> ParticleData {
    let mut rng = Lcg(seed);
    ParticleData {
        positions: (0..n).map(|_| rng.v()).collect(),
        radii: Some((0..n).map(|_| r0 * (1.0 + rng.f())).collect()),
        attribute: Some((0..n).map(|_| rng.f()).collect()),
        weights: Some((0..n).map(|_| 0.5 + rng.f()).collect()),
    }
}

fn periodic(d: ParticleData, kernel: Kernel) -> ParticleVolume {
    let settings = ParticleSettings {
        kernel,
        periodic: Some(unit_box()),
        ..Default::default()
    };
    ParticleVolume::new(d, settings).unwrap()
}

/// Φ at `p` summed over every particle and every image within two boxes.
fn brute_periodic(d: &ParticleData, k: Kernel, p: Vec3) -> f64 {
    let mut phi = 0.0;
    for i in 0..d.positions.len() {
        for sx in -2..=2 {
            for sy in -2..=2 {
                for sz in -2..=2 {
                    let c = d.positions[i] + Vec3::new(sx as f32, sy as f32, sz as f32) * L;
                    let dist = ((p - c).length_squared() as f64).sqrt();
                    let r = d.radii.as_ref().unwrap()[i] as f64;
                    let w = d.weights.as_ref().unwrap()[i] as f64;
                    phi += reference_kernel(k, dist, r, w).0;
                }
            }
        }
    }
    phi
}

#[test]
fn the_periodic_field_sums_every_image() {
    let d = data(300, 0.06, 7);
    let mut rng = Lcg(3);
    for kernel in KERNELS {
        let v = periodic(d.clone(), kernel);
        let scale = brute_periodic(&d, kernel, Vec3::splat(0.5)).max(1.0);
        for _ in 0..200 {
            // Points inside, on faces and outside the box (wrapped).
            let p = rng.v() * 3.0 - Vec3::splat(1.0);
            let got = v.density(p) as f64;
            let want = brute_periodic(&d, kernel, p);
            assert!(
                (got - want).abs() <= 1e-5 * scale.max(want),
                "{}: Φ({p:?}) = {got}, brute force {want}",
                kernel.name()
            );
        }
    }
}

#[test]
fn a_corner_particle_reaches_all_eight_corners() {
    let d = ParticleData {
        positions: vec![Vec3::splat(0.01)],
        radii: Some(vec![0.1]),
        attribute: None,
        weights: Some(vec![1.0]),
    };
    let v = periodic(d, Kernel::CubicSpline);
    let at = v.density(Vec3::splat(0.01));
    let corner = v.density(Vec3::ZERO);
    assert!(corner > 0.0);
    for k in 0..8 {
        let c = Vec3::new((k & 1) as f32, ((k >> 1) & 1) as f32, (k >> 2) as f32) * L;
        let phi = v.density(c);
        assert!(
            (phi - corner).abs() <= 1e-6 * at,
            "corner {c:?}: {phi} vs {corner}"
        );
    }
}

#[test]
fn positions_outside_are_wrapped_and_counted() {
    let mut d = data(200, 0.05, 11);
    let inside = d.clone();
    d.positions[3] += Vec3::new(L, 0.0, 0.0);
    d.positions[7] = d.positions[7] - Vec3::new(0.0, 2.0 * L, L);
    let (a, b) = (
        periodic(d, Kernel::WendlandC2),
        periodic(inside, Kernel::WendlandC2),
    );
    assert_eq!(a.wrapped(), 2);
    assert_eq!(a.particle_count(), 200);
    assert!((a.total_mass() - b.total_mass()).abs() <= 1e-9 * b.total_mass());
    for p in [Vec3::splat(0.3), Vec3::new(0.0, 0.99, 0.5)] {
        assert!((a.density(p) - b.density(p)).abs() <= 1e-5 * b.density(p).max(1.0));
    }
}

fn axis_camera(axis: usize) -> Camera {
    Camera::axis_projection(&unit_box(), axis).unwrap()
}

/// An orthographic camera looking along `-n` at the box centre, covering
/// `w` × `w`.
fn off_axis_camera(n: Vec3, w: f32) -> Camera {
    let n = n.normalized();
    let right = Vec3::new(0.0, 0.0, 1.0).cross(n).normalized();
    let up = n.cross(right);
    Camera {
        eye: Vec3::splat(0.5) + n * 3.0,
        right,
        up,
        forward: -n,
        projection: Projection::Orthographic {
            half_width: 0.5 * w,
            half_height: 0.5 * w,
        },
    }
}

fn sum(image: &[f32]) -> f64 {
    image.iter().map(|&v| v as f64).sum()
}

/// Checks `Σ × pixel area` of `v`'s n×n projections of the unit box, along
/// `axis` and off axis (1.8 wide), against its mass (`tolerances`: on,
/// off); returns the off-axis image and its camera.
fn box_mass(
    v: &ParticleVolume,
    n: u32,
    axis: usize,
    (on_tol, off_tol): (f64, f64),
) -> (Vec<f32>, Camera) {
    let ctl = Control::new();
    let mass = v.total_mass();
    let name = v.settings().kernel.name();
    let on = v
        .project_image(&axis_camera(axis), n, n, &ctl)
        .unwrap()
        .unwrap();
    let on_mass = sum(&on) * (L as f64 / n as f64).powi(2);
    assert!(
        (on_mass / mass - 1.0).abs() <= on_tol,
        "{name}: on-axis Σ = {on_mass}, mass {mass}"
    );
    let w = 1.8;
    let cam = off_axis_camera(Vec3::new(1.0, 0.7, 0.4), w);
    let off = v.project_image(&cam, n, n, &ctl).unwrap().unwrap();
    let off_mass = sum(&off) * (w as f64 / n as f64).powi(2);
    assert!(
        (off_mass / mass - 1.0).abs() <= off_tol,
        "{name}: off-axis Σ = {off_mass}, mass {mass}"
    );
    (off, cam)
}

#[test]
fn pixel_areas_conserve_the_mass_of_sub_pixel_kernels_on_and_off_axis() {
    let n = 128u32;
    for kernel in KERNELS {
        // Supports of 0.1–0.3 pixels (pixel centres miss most of them);
        // many cross the faces.
        let support = 0.1 / n as f32;
        let v = ParticleVolume::new(
            data(6000, support / kernel.support_factor(), 8),
            ParticleSettings {
                kernel,
                periodic: Some(unit_box()),
                pixels: voxless_core::PixelIntegral::Area,
                ..Default::default()
            },
        )
        .unwrap();
        box_mass(&v, n, 0, (1e-6, 1e-5));
    }
}

#[test]
fn projections_of_the_box_conserve_mass_for_every_kernel() {
    let ctl = Control::new();
    for kernel in KERNELS {
        // Kernels several pixels wide, many of them crossing the faces.
        let v = periodic(data(4000, 0.03, 5), kernel);
        let n = 256u32;
        let (off, cam) = box_mass(&v, n, 2, (1e-6, 1e-4));
        // The fast path against the per-pixel line integrals through the box.
        let slow = voxless_render::project_per_pixel(&v, &cam, n, n, &ctl).unwrap();
        let peak = off.iter().fold(0.0f32, |m, &x| m.max(x));
        for (a, b) in off.iter().zip(&slow) {
            assert!(
                (a - b).abs() <= 1e-4 * peak,
                "{}: {a} vs {b}",
                kernel.name()
            );
        }
    }
}

#[test]
fn shifting_the_box_rolls_the_on_axis_image() {
    let ctl = Control::new();
    let d = data(3000, 0.02, 9);
    let n = 128u32;
    let base = periodic(d.clone(), Kernel::CubicSpline);
    let a = base
        .project_image(&axis_camera(2), n, n, &ctl)
        .unwrap()
        .unwrap();
    // A shift by 32 pixels in x and 16 in y (exact binary fractions).
    let (sx, sy) = (32usize, 16usize);
    let shift = Vec3::new(sx as f32 / n as f32, sy as f32 / n as f32, 0.37);
    let mut moved = d.clone();
    for p in &mut moved.positions {
        *p = crate::wrap(&unit_box(), *p + shift);
    }
    let b = periodic(moved, Kernel::CubicSpline)
        .project_image(&axis_camera(2), n, n, &ctl)
        .unwrap()
        .unwrap();
    let n = n as usize;
    let mut diff = 0.0;
    for y in 0..n {
        for x in 0..n {
            // Row 0 is the top: +y moves the image up.
            let (xs, ys) = ((x + sx) % n, (y + n - sy) % n);
            diff += (a[y * n + x] as f64 - b[ys * n + xs] as f64).abs();
        }
    }
    assert!(diff / sum(&a) <= 1e-5, "L1 / Σ = {}", diff / sum(&a));
}

#[test]
fn a_deep_slab_through_the_tiled_box_counts_each_period() {
    let ctl = Control::new();
    let v = periodic(data(800, 0.04, 13), Kernel::WendlandC4);
    let cam = axis_camera(2);
    let n = 48u32;
    let one = v.project_image(&cam, n, n, &ctl).unwrap().unwrap();
    // The eye sits above the box; a slab 3 boxes deep starting at its top.
    let t0 = (cam.eye.z - L).abs();
    let t = Range1::new(t0, t0 + 3.0 * L);
    let three =
        voxless_render::project_each(&cam, n, n, &ctl, |ray| v.periodic_line_integral(ray, t))
            .unwrap();
    let peak = one.iter().fold(0.0f32, |m, &x| m.max(x));
    for (a, b) in one.iter().zip(&three) {
        assert!((3.0 * a - b).abs() <= 1e-4 * peak, "{a} × 3 vs {b}");
    }
}

#[test]
fn a_radius_change_rebuilds_the_ghosts() {
    let d = data(500, 0.03, 17);
    let mut v = periodic(d.clone(), Kernel::CubicSpline);
    let p = Vec3::new(0.001, 0.5, 0.999);
    v.set_radius(1.0, None).unwrap();
    let mut wider = d.clone();
    wider.radii = None;
    let settings = ParticleSettings {
        kernel: Kernel::CubicSpline,
        radius: 0.08,
        periodic: Some(unit_box()),
        ..Default::default()
    };
    let mut w = ParticleVolume::new(wider.clone(), settings).unwrap();
    w.set_radius(0.12, None).unwrap();
    let mut direct = wider;
    direct.radii = Some(vec![0.12; 500]);
    let want = brute_periodic(&direct, Kernel::CubicSpline, p);
    assert!((w.density(p) as f64 - want).abs() <= 1e-5 * want.max(1.0));
}

/// The n-th nearest distances by comparing every pair (minimum image).
fn brute_neighbours(p: &[[f64; 3]], n: usize, b: Option<&PeriodicBox>) -> Vec<f64> {
    p.iter()
        .map(|q| {
            let mut d: Vec<f64> = p
                .iter()
                .map(|r| {
                    (0..3)
                        .map(|a| {
                            let mut x = (q[a] - r[a]).abs();
                            if let Some(b) = b {
                                x = x.min(b.size[a] - x);
                            }
                            x * x
                        })
                        .sum::<f64>()
                        .sqrt()
                })
                .collect();
            d.sort_by(f64::total_cmp);
            d[n - 1]
        })
        .collect()
}

#[test]
fn neighbour_distances_equal_a_brute_force_search() {
    let mut rng = Lcg(21);
    // Clustered: half the points in a small clump, so radii vary widely.
    let p: Vec<[f64; 3]> = (0..3000)
        .map(|i| {
            let v = rng.v();
            let s = if i % 2 == 0 { 1.0 } else { 0.05 };
            [
                (0.3 + s * v.x as f64).rem_euclid(1.0) * 2.0 + 1.0,
                (0.6 + s * v.y as f64).rem_euclid(1.0) * 3.0 - 1.0,
                (0.9 + s * v.z as f64).rem_euclid(1.0) * 0.5,
            ]
        })
        .collect();
    let b = PeriodicBox {
        lo: [1.0, -1.0, 0.0],
        size: [2.0, 3.0, 0.5],
    };
    for (n, pb) in [(2, None), (32, None), (32, Some(&b)), (7, Some(&b))] {
        let got = neighbour_distances(&p, n, pb).unwrap();
        let want = brute_neighbours(&p, n, pb);
        for i in 0..p.len() {
            assert!(
                (got[i] - want[i]).abs() <= 1e-12 * want[i].max(1e-300),
                "n = {n}, periodic {}: point {i}: {} vs {}",
                pb.is_some(),
                got[i],
                want[i]
            );
        }
    }
    // The clump's edge makes the reach too short for some queries: the
    // wider gathers and the heap answered too (all checked above).
    use std::sync::atomic::Ordering;
    let paths = crate::neighbours::tally::PATHS
        .each_ref()
        .map(|c| c.load(Ordering::Relaxed));
    assert!(paths.iter().all(|&c| c > 0), "paths taken: {paths:?}");
    // Few points: the n-th neighbour lies more than half a box away.
    let few: Vec<[f64; 3]> = p[..20].to_vec();
    let got = neighbour_distances(&few, 20, Some(&b)).unwrap();
    for (g, w) in got.iter().zip(brute_neighbours(&few, 20, Some(&b))) {
        assert!((g - w).abs() <= 1e-12 * w, "{g} vs {w}");
    }
}

#[test]
fn neighbour_radii_refuse_bad_counts_and_coincident_points() {
    let p = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0; 3]];
    assert!(matches!(
        neighbour_distances(&p, 1, None),
        Err(ParticleError::BadNeighbours { n: 1, count: 3 })
    ));
    assert!(matches!(
        neighbour_distances(&p, 4, None),
        Err(ParticleError::BadNeighbours { n: 4, count: 3 })
    ));
    assert!(matches!(
        smoothing_lengths(&p, 2, None, Kernel::CubicSpline),
        Err(ParticleError::CoincidentNeighbours { index: 0, .. })
    ));
    let h = smoothing_lengths(&p, 3, None, Kernel::CubicSpline).unwrap();
    assert_eq!(h, vec![0.5, 0.5, 0.5]);
    let nan = vec![[0.0; 3], [f64::NAN, 0.0, 0.0]];
    assert!(matches!(
        neighbour_distances(&nan, 2, None),
        Err(ParticleError::NonFinitePosition { index: 1, .. })
    ));
}

#[test]
fn bad_boxes_are_refused() {
    for b in [
        Aabb::new(Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0)),
        Aabb::new(Vec3::ZERO, Vec3::new(1.0, f32::INFINITY, 1.0)),
        Aabb::new(Vec3::ONE, Vec3::ZERO),
    ] {
        let settings = ParticleSettings {
            periodic: Some(b),
            ..Default::default()
        };
        assert!(matches!(
            ParticleVolume::new(data(10, 0.1, 1), settings),
            Err(ParticleError::BadBox { .. })
        ));
    }
}

/// The images of every particle against every shift in −2..=2 whose
/// support box meets the box: the shortcut for particles that reach no
/// face gives the same list as the enumeration.
#[test]
fn images_are_every_shift_whose_support_meets_the_box() {
    let b = Aabb::new(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 3.0, 2.5));
    let size = b.extent();
    let mut rng = Lcg(3);
    let mut out = Vec::new();
    // Random particles, then supports that end on a face, a few ulps
    // either side of it or a hair inside the shortcut's margin (where
    // the shortcut without divisions must agree with the divisions).
    let grazing = (0..3).flat_map(|a| {
        [-3.0f32, -1.0, 0.0, 1.0, 3.0, 1e-6, -1e-6, 5e-6]
            .into_iter()
            .flat_map(move |e| [false, true].map(move |top| (a, e, top)))
    });
    let grazing: Vec<_> = grazing.collect();
    for i in 0..20_000 + grazing.len() {
        let mut c = Vec3::new(
            b.min.x + size.x * rng.f(),
            b.min.y + size.y * rng.f(),
            b.min.z + size.z * rng.f(),
        );
        let mut s = if i % 2 == 0 { 0.01 } else { 0.3 } * rng.f() + 1e-4;
        if let Some(&(a, e, top)) = i.checked_sub(20_000).map(|k| &grazing[k]) {
            // Whole ulps of the face's coordinate, or a fraction of the box.
            let step = if e.abs() >= 1.0 {
                e * f32::EPSILON * size[a].max(1.0)
            } else {
                e * size[a]
            };
            s = 0.05;
            c[a] = if top {
                b.max[a] - s + step
            } else {
                b.min[a] + s - step
            };
        }
        crate::volume::images(Some(&b), c, s, i, &mut out).unwrap();
        let mut want = Vec::new();
        for kx in -2i8..=2 {
            for ky in -2i8..=2 {
                for kz in -2i8..=2 {
                    let q = Vec3::new(
                        c.x + kx as f32 * size.x,
                        c.y + ky as f32 * size.y,
                        c.z + kz as f32 * size.z,
                    );
                    if (kx, ky, kz) == (0, 0, 0)
                        || (0..3).all(|a| q[a] - s <= b.max[a] && q[a] + s >= b.min[a])
                    {
                        want.push(([kx, ky, kz], q));
                    }
                }
            }
        }
        assert_eq!(out, want, "particle {i} at {c:?}, support {s}");
    }
}
