//! The orthographic projection kernels against each other, against exact
//! (f64) clipping and against the full per-ray clip.

use super::*;

/// Every orthographic kernel this CPU can run as itself, the scalar
/// reference first (a notice when AVX2 is missing).
fn kernels() -> Vec<crate::ortho::Kernel> {
    use crate::ortho::Kernel;
    use voxless_core::simd::Simd;
    let mut k = vec![Kernel::Scalar, Kernel::Lanes(Simd::Portable)];
    if Simd::Avx2.available() {
        k.push(Kernel::Lanes(Simd::Avx2));
    } else {
        eprintln!("notice: no AVX2 on this CPU; the portable lanes only");
    }
    k
}

fn project_kernel(
    v: &TetVolume,
    cam: &Camera,
    w: u32,
    h: u32,
    k: crate::ortho::Kernel,
) -> Vec<f32> {
    render::project_with(
        &v.mesh,
        cam,
        (w, h),
        TetOptions::default(),
        k,
        &Control::new(),
    )
    .unwrap()
}

#[test]
fn ortho_lanes_equal_the_scalar_kernel_per_pixel() {
    // Random tessellations (one shell-crossed with slivers and caustics), a
    // uniform grid (faces parallel to the view) and views larger than the
    // box (rays outside it, tets clipped at its faces); several tiles.
    let cases = [
        (grid(8, 1.0, jitter(23, 0.04)), 0.0),
        (grid(8, 1.0, jitter(29, 0.05)), 0.15),
        (folded_sheet(8, 43), 0.0),
        (grid(6, 1.0, |_| [0.0; 3]), 0.2),
    ];
    for (case, (g, pad)) in cases.iter().enumerate() {
        let v = TetVolume::new(g, &TetSettings::default(), 0).unwrap();
        let b = Aabb::new(Vec3::splat(-pad), Vec3::splat(1.0 + pad));
        for axis in 0..3 {
            let cam = Camera::axis_projection(&b, axis).unwrap();
            let (w, h) = (300, 280);
            let scalar = project_kernel(&v, &cam, w, h, crate::ortho::Kernel::Scalar);
            let peak = scalar.iter().copied().fold(0.0f32, f32::max);
            assert!(peak > 0.5, "case {case}: {peak}");
            for k in &kernels()[1..] {
                let lanes = project_kernel(&v, &cam, w, h, *k);
                // The same crossings bit for bit; only the f32 (lanes) vs
                // f64 (scalar) sums differ.
                for (p, (&a, &s)) in lanes.iter().zip(&scalar).enumerate() {
                    assert!(
                        (a - s).abs() <= 1e-5 * s.abs().max(1e-3 * peak),
                        "case {case}, axis {axis}, {k:?}: pixel {p}: {a} vs scalar {s}"
                    );
                }
            }
        }
    }
}

/// Column density of pixel `(x, y)` of an orthographic view by clipping
/// the ray through the pixel centre against the box and every tet, in f64.
fn column_f64(
    v: &TetVolume,
    tets: &[Tet],
    cam: &Camera,
    (w, h): (u32, u32),
    (x, y): (u32, u32),
) -> f64 {
    type D = [f64; 3];
    let d = |p: Vec3| [p.x as f64, p.y as f64, p.z as f64];
    let sub = |a: D, b: D| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: D, b: D| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let cross = |a: D, b: D| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let voxless_core::Projection::Orthographic {
        half_width,
        half_height,
    } = cam.projection
    else {
        panic!("orthographic views only")
    };
    let sx = 2.0 * (x as f64 + 0.5) / w as f64 - 1.0;
    let sy = 1.0 - 2.0 * (y as f64 + 0.5) / h as f64;
    let (eye, right, up) = (d(cam.eye), d(cam.right), d(cam.up));
    let o: D = std::array::from_fn(|i| {
        eye[i] + right[i] * sx * half_width as f64 + up[i] * sy * half_height as f64
    });
    let dir = d(cam.forward);
    // The part of the ray inside the box [0, L)³.
    let (mut lo, mut hi) = (0.0f64, f64::INFINITY);
    for i in 0..3 {
        if dir[i] == 0.0 {
            if !(0.0..=v.mesh.box_size as f64).contains(&o[i]) {
                return 0.0;
            }
        } else {
            let (a, b) = (-o[i] / dir[i], (v.mesh.box_size as f64 - o[i]) / dir[i]);
            (lo, hi) = (lo.max(a.min(b)), hi.min(a.max(b)));
        }
    }
    if !(hi > lo) {
        return 0.0;
    }
    let mut total = 0.0;
    'tet: for t in tets {
        let q = t.v.map(d);
        let (mut t0, mut t1) = (lo, hi);
        for f in 0..4 {
            let (a, b, c) = (q[(f + 1) % 4], q[(f + 2) % 4], q[(f + 3) % 4]);
            let mut n = cross(sub(b, a), sub(c, a));
            if dot(n, sub(q[f], a)) > 0.0 {
                n = n.map(|c| -c);
            }
            let (nd, dist) = (dot(n, dir), dot(n, sub(a, o)));
            if nd > 0.0 {
                t1 = t1.min(dist / nd);
            } else if nd < 0.0 {
                t0 = t0.max(dist / nd);
            } else if dist < 0.0 {
                continue 'tet;
            }
        }
        if t1 > t0 {
            total += t.density as f64 * (t1 - t0);
        }
    }
    total
}

#[test]
fn ortho_kernels_match_f64_clipping_per_pixel() {
    // Small random tessellations, also seen from beyond the box, and a
    // uniform grid. Against exact clipping of the same f32 tets through the
    // pixel centres the kernels stay within 1e-5 per pixel (8e-6 at worst
    // here). The full clip (`clip_only`) is further off (3.4e-5 at worst):
    // its f32 ray origins are rounded by ~1e-7 of the box, which a face
    // nearly parallel to the rays turns into a chord error ~250× that.
    let cases = [
        (grid(8, 1.0, jitter(23, 0.04)), 0.0),
        (grid(8, 1.0, jitter(37, 0.03)), 0.1),
        (grid(6, 1.0, |_| [0.0; 3]), 0.2),
    ];
    let (w, h) = (200, 180);
    for (case, (g, pad)) in cases.iter().enumerate() {
        let v = TetVolume::new(g, &TetSettings::default(), 0).unwrap();
        let tets = v.mesh.tets();
        let b = Aabb::new(Vec3::splat(-pad), Vec3::splat(1.0 + pad));
        for axis in 0..3 {
            let cam = Camera::axis_projection(&b, axis).unwrap();
            let full = render::project(
                &v.mesh,
                &cam,
                w,
                h,
                TetOptions {
                    clip_only: true,
                    ..Default::default()
                },
                &Control::new(),
            )
            .unwrap();
            let images: Vec<_> = kernels()
                .into_iter()
                .map(|k| (k, project_kernel(&v, &cam, w, h, k)))
                .collect();
            let mut covered = 0;
            for p in (0..(w * h) as usize).step_by(3) {
                let exact = column_f64(&v, &tets, &cam, (w, h), (p as u32 % w, p as u32 / w));
                let rel = |x: f32| (x as f64 - exact).abs() / exact.max(1e-3);
                for (k, img) in &images {
                    assert!(
                        rel(img[p]) <= 1e-5,
                        "case {case}, axis {axis}, {k:?}: pixel {p}: {} vs {exact}",
                        img[p]
                    );
                }
                assert!(rel(full[p]) <= 5e-5, "case {case}: full clip {}", full[p]);
                covered += (exact > 0.5) as usize;
            }
            assert!(covered > 1000, "case {case}: {covered} covered pixels");
        }
    }
}

/// An orthographic view of the unit box from an oblique direction.
fn oblique_camera() -> Camera {
    Camera::look_at(
        Vec3::new(2.3, 1.6, -0.9),
        Vec3::splat(0.5),
        Vec3::new(0.1, 1.0, 0.2),
        voxless_core::Projection::Orthographic {
            half_width: 0.95,
            half_height: 0.9,
        },
    )
    .unwrap()
}

#[test]
fn oblique_views_match_f64_clipping_and_the_lanes() {
    let v = TetVolume::new(&grid(6, 1.0, jitter(53, 0.04)), &TetSettings::default(), 0).unwrap();
    let tets = v.mesh.tets();
    let cam = oblique_camera();
    let (w, h) = (160, 150);
    let images: Vec<_> = kernels()
        .into_iter()
        .map(|k| (k, project_kernel(&v, &cam, w, h, k)))
        .collect();
    let exact: Vec<f64> = (0..w * h)
        .map(|p| column_f64(&v, &tets, &cam, (w, h), (p % w, p / w)))
        .collect();
    let peak = exact.iter().copied().fold(0.0, f64::max);
    let mut covered = 0;
    for (p, &exact) in exact.iter().enumerate() {
        for (k, img) in &images {
            // Rays grazing the box: its f32 ray spans, not the tets, round.
            assert!(
                (img[p] as f64 - exact).abs() <= 1e-5 * exact.max(0.1 * peak),
                "{k:?}: pixel {p}: {} vs {exact}",
                img[p]
            );
        }
        covered += (exact > 0.1) as usize;
    }
    assert!(covered > 5000, "{covered} covered pixels");
}

#[test]
fn orthographic_tet_rects_equal_the_per_vertex_rects() {
    let v = TetVolume::new(&grid(6, 1.0, jitter(59, 0.05)), &TetSettings::default(), 0).unwrap();
    let b = Aabb::new(Vec3::splat(-0.1), Vec3::splat(1.1));
    let cams = [0, 1, 2].map(|a| Camera::axis_projection(&b, a).unwrap());
    for cam in cams.iter().chain([&oblique_camera()]) {
        let screen = raster::Screen::new(cam, 97, 83);
        for t in &v.mesh.tets() {
            assert_eq!(screen.tet_rect(&t.v), screen.pixel_rect(&t.v));
        }
    }
}
