//! Tests of the streaming splatter: bits independent of chunks and threads,
//! the periodic support limit, and pixel areas (mass at any kernel size,
//! values against a fine quadrature).

use super::*;
use crate::kernel::area::table_pixels;
use voxless_core::SmallRng;

fn particles(n: usize) -> Vec<SplatParticle> {
    let mut rng = SmallRng(5);
    (0..n)
        .map(|i| SplatParticle {
            center: Vec3::new(rng.f(), rng.f(), rng.f()),
            radius: 0.005 + 0.05 * rng.f(),
            weight: if i % 17 == 0 { 0.0 } else { 0.5 + rng.f() },
        })
        .collect()
}

fn image(p: &[SplatParticle], chunk: usize, kernel: Kernel, periodic: Option<Aabb>) -> Vec<f32> {
    let cam = Camera::axis_projection(&Aabb::new(Vec3::splat(0.0), Vec3::splat(1.0)), 2).unwrap();
    let mut s = Splatter::new(&cam, 70, 45, kernel, periodic).unwrap();
    for (k, c) in p.chunks(chunk).enumerate() {
        s.add(c, k * chunk, &Control::new()).unwrap();
    }
    s.finish().unwrap()
}

#[test]
fn chunks_and_threads_do_not_change_the_bits() {
    // More than two pieces of PIECE particles in the whole chunk.
    let p = particles(2 * PIECE + 1000);
    let unit = Some(Aabb::new(Vec3::splat(0.0), Vec3::splat(1.0)));
    for kernel in [Kernel::WendlandC2, Kernel::QuinticSpline, Kernel::Gaussian3] {
        for periodic in [None, unit] {
            let whole = image(&p, p.len(), kernel, periodic);
            assert!(whole.iter().any(|&v| v > 0.0));
            assert_eq!(whole, image(&p, 257, kernel, periodic));
            let one = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .unwrap();
            assert_eq!(whole, one.install(|| image(&p, 1000, kernel, periodic)));
        }
    }
}

#[test]
fn too_wide_a_support_for_the_box_is_an_error() {
    let cam = Camera::axis_projection(&Aabb::new(Vec3::splat(0.0), Vec3::splat(1.0)), 2).unwrap();
    let unit = Some(Aabb::new(Vec3::splat(0.0), Vec3::splat(1.0)));
    let mut s = Splatter::new(&cam, 8, 8, Kernel::CubicSpline, unit).unwrap();
    let wide = SplatParticle {
        center: Vec3::splat(0.5),
        radius: 3.0,
        weight: 1.0,
    };
    let e = s.add(&[wide], 41, &Control::new()).unwrap_err();
    assert!(
        matches!(e, ParticleError::SupportBeyondBox { index: 41, .. }),
        "{e}"
    );
    // In a chunk placed in pieces on every core, the first such particle
    // in order is named, whichever piece finishes first.
    let mut many = vec![
        SplatParticle {
            center: Vec3::splat(0.5),
            radius: 0.01,
            weight: 1.0,
        };
        3 * PIECE
    ];
    many[PIECE + 7] = wide;
    many[2 * PIECE + 3] = wide;
    let e = s.add(&many, 100, &Control::new()).unwrap_err();
    assert!(
        matches!(e, ParticleError::SupportBeyondBox { index, .. } if index == 100 + PIECE + 7),
        "{e}"
    );
}

/// `Σ pixels × pixel area` of an image of the unit square.
fn mass(image: &[f32], w: u32, h: u32) -> f64 {
    image.iter().map(|&v| v as f64).sum::<f64>() / (w as f64 * h as f64)
}

#[test]
fn pixel_areas_conserve_the_mass_of_kernels_of_any_size() {
    let unit = Aabb::new(Vec3::splat(0.0), Vec3::splat(1.0));
    let cam = Camera::axis_projection(&unit, 2).unwrap();
    let (w, h) = (96, 64);
    let mut rng = SmallRng(9);
    for kernel in [Kernel::CubicSpline, Kernel::WendlandC2, Kernel::Gaussian3] {
        // Supports from 1/20 of a pixel to 40 pixels, inside the image;
        // then the same particles in a periodic box (kernels cross faces).
        let f = kernel.support_factor();
        let p: Vec<SplatParticle> = (0..400)
            .map(|i| {
                let support = (0.05 * 800f32.powf(i as f32 / 399.0)) / w as f32;
                let m = support + 1e-3;
                SplatParticle {
                    center: Vec3::new(
                        m + (1.0 - 2.0 * m) * rng.f(),
                        m + (1.0 - 2.0 * m) * rng.f(),
                        rng.f(),
                    ),
                    radius: support / f,
                    weight: 0.5 + rng.f(),
                }
            })
            .collect();
        let want: f64 = p
            .iter()
            .map(|q| q.weight as f64 * kernel.integral(q.radius as f64))
            .sum();
        for periodic in [None, Some(unit)] {
            let mut s = Splatter::new(&cam, w, h, kernel, periodic)
                .unwrap()
                .with_pixels(PixelIntegral::Area);
            s.add(&p, 0, &Control::new()).unwrap();
            let got = mass(&s.finish().unwrap(), w, h);
            assert!(
                (got / want - 1.0).abs() < 1e-6,
                "{kernel:?}, periodic {}: {got} vs {want}",
                periodic.is_some()
            );
        }
        // Pixel centres lose the mass of sub-pixel kernels.
        let mut s = Splatter::new(&cam, w, h, kernel, None).unwrap();
        s.add(&p[..40], 0, &Control::new()).unwrap();
        let sub: f64 = p[..40]
            .iter()
            .map(|q| q.weight as f64 * kernel.integral(q.radius as f64))
            .sum();
        assert!((mass(&s.finish().unwrap(), w, h) / sub - 1.0).abs() > 1e-3);
    }
}

#[test]
fn pixel_areas_equal_a_fine_quadrature_of_the_column() {
    use crate::kernel::area::GAUSS3;
    let unit = Aabb::new(Vec3::splat(0.0), Vec3::splat(1.0));
    let cam = Camera::axis_projection(&unit, 2).unwrap();
    let n = 48u32;
    let kernel = Kernel::WendlandC2;
    // Supports of 0.4 to 15 pixels take the table; from 16 on, pixel
    // centres (the same bits as the centre image).
    for support_px in [0.4f32, 1.7, 6.0, 15.0, 17.0, 30.0] {
        let support = support_px / n as f32;
        let q = SplatParticle {
            center: Vec3::new(0.5 + 0.3 / n as f32, 0.5 - 0.2 / n as f32, 0.5),
            radius: support / kernel.support_factor(),
            weight: 1.0,
        };
        let mut s = Splatter::new(&cam, n, n, kernel, None)
            .unwrap()
            .with_pixels(PixelIntegral::Area);
        s.add(&[q], 0, &Control::new()).unwrap();
        let got = s.finish().unwrap();
        if support_px as f64 >= table_pixels(kernel) {
            let mut c = Splatter::new(&cam, n, n, kernel, None).unwrap();
            c.add(&[q], 0, &Control::new()).unwrap();
            assert_eq!(got, c.finish().unwrap(), "support {support_px} px");
            continue;
        }
        let column = kernel.column(q.radius as f64);
        let pixel = 1.0 / n as f64;
        // 16×16 sub-cells of 3×3 Gauss–Legendre points per pixel.
        // Measured: 2e-7–4e-5 of the peak.
        let mut peak = 0.0f64;
        let mut worst = 0.0f64;
        for y in 0..n {
            for x in 0..n {
                let mut sum = 0.0;
                for sy in 0..16 {
                    for sx in 0..16 {
                        for (dy, wy) in GAUSS3 {
                            for (dx, wx) in GAUSS3 {
                                let px = (x as f64 + (sx as f64 + 0.5 + dx) / 16.0) * pixel;
                                // Row 0 at the top: y up is 1 − row.
                                let py = 1.0 - (y as f64 + (sy as f64 + 0.5 + dy) / 16.0) * pixel;
                                let (bx, by) = (px - q.center.x as f64, py - q.center.y as f64);
                                sum += wx * wy * column.at(bx * bx + by * by);
                            }
                        }
                    }
                }
                let want = sum / 256.0;
                peak = peak.max(want);
                worst = worst.max((got[(y * n + x) as usize] as f64 - want).abs());
            }
        }
        assert!(
            worst <= 1e-4 * peak,
            "support {support_px} px: worst {worst:e} of peak {peak:e}"
        );
    }
}

/// The sixteen lanes (their own polynomials, [`ColumnPoly::wide`]) against
/// the eight over many overlapping supports, the images' edges, periodic
/// images and odd widths: every pixel within 2e-6 of the sum of the peaks
/// of the supports that reach it (each lane's column is within 1e-6 of its
/// peak) plus the image's f32 rounding.
#[test]
fn sixteen_lanes_hold_the_columns_of_eight() {
    if !splat_wide::available() {
        println!("note: this CPU has no AVX-512F; the sixteen-lane splats are not run here");
        return;
    }
    if !Simd::Avx2.available() {
        return;
    }
    // Supports from under a pixel to ~60 pixels across, many crossing the
    // image's edges (the tails of the rows), widths not a multiple of 16.
    let mut rng = SmallRng(11);
    let p: Vec<SplatParticle> = (0..4000)
        .map(|_| SplatParticle {
            center: Vec3::new(1.2 * rng.f() - 0.1, 1.2 * rng.f() - 0.1, rng.f()),
            radius: 0.002 + 0.2 * rng.f() * rng.f(),
            weight: 0.5 + rng.f(),
        })
        .collect();
    let cam = Camera::axis_projection(&Aabb::new(Vec3::splat(0.0), Vec3::splat(1.0)), 2).unwrap();
    let unit = Some(Aabb::new(Vec3::splat(-0.2), Vec3::splat(1.2)));
    // Every SPH kernel (the Gaussians take the closed form, not the lanes).
    let sph: Vec<Kernel> = crate::tests::KERNELS
        .into_iter()
        .filter(|k| k.column(1.0).is_sph())
        .collect();
    assert_eq!(sph.len(), 6, "the cubic spline, M5, M6 and three Wendlands");
    for kernel in sph {
        let f0 = crate::kernel::column_poly::column_by_quadrature(kernel, 0.0);
        for periodic in [None, unit] {
            for (w, h) in [(150u32, 97u32), (33, 40)] {
                let run = |simd: Simd| {
                    let mut s = Splatter::new(&cam, w, h, kernel, periodic)
                        .unwrap()
                        .on(simd);
                    assert_eq!(s.wide, simd == Simd::Auto);
                    s.add(&p, 0, &Control::new()).unwrap();
                    s.finish().unwrap()
                };
                let wide = run(Simd::Auto);
                assert!(wide.iter().any(|&v| v > 0.0));
                let eight = run(Simd::Avx2);
                // The sum of the peaks of the supports' squares over each
                // pixel centre (every periodic image across the view).
                let mut peaks = vec![0.0f64; (w * h) as usize];
                let shifts: &[f32] = if periodic.is_some() {
                    &[-1.4, 0.0, 1.4]
                } else {
                    &[0.0]
                };
                for q in &p {
                    let column = kernel.column(q.radius as f64);
                    let peak = q.weight as f64 * column.scale() * f0;
                    let s = column.support2().sqrt();
                    for (&sx, &sy) in shifts
                        .iter()
                        .flat_map(|a| shifts.iter().map(move |b| (a, b)))
                    {
                        let (cx, cy) = ((q.center.x + sx) as f64, (q.center.y + sy) as f64);
                        for y in 0..h {
                            let v = 1.0 - (y as f64 + 0.5) / h as f64;
                            if (v - cy).abs() > s {
                                continue;
                            }
                            for x in 0..w {
                                if ((x as f64 + 0.5) / w as f64 - cx).abs() <= s {
                                    peaks[(y * w + x) as usize] += peak;
                                }
                            }
                        }
                    }
                }
                for (k, (a, b)) in wide.iter().zip(&eight).enumerate() {
                    let allowed = 2e-6 * peaks[k] + 1.2e-7 * a.abs().max(b.abs()) as f64;
                    assert!(
                        ((a - b) as f64).abs() <= allowed,
                        "{kernel:?} {w}×{h} pixel {k}: {a} vs {b}"
                    );
                }
            }
        }
    }
}

/// The lanes' columns (polynomials of the table position) against every
/// SPH kernel's column by quadrature at each pixel centre, on both lane
/// backends: within 2e-6 of the peak (the polynomials' bound, 1e-6, plus
/// the f32 table position).
#[test]
fn pixel_centres_hold_the_exact_columns() {
    let unit = Aabb::new(Vec3::splat(0.0), Vec3::splat(1.0));
    let cam = Camera::axis_projection(&unit, 2).unwrap();
    let n = 64u32;
    let sph: Vec<Kernel> = crate::tests::KERNELS
        .into_iter()
        .filter(|k| k.is_sph())
        .collect();
    // Supports a whole number of pixels wide and centres on pixel centres
    // and edges too: the splats' rows and columns are the pixel centres
    // inside the support, with no margin, so a centre on the edge of that
    // square must neither lose nor gain a pixel.
    let cases = [
        (3.3f32, (0.31f32, -0.27f32)),
        (20.7, (0.31, -0.27)),
        (4.0, (0.0, 0.0)),
        (4.0, (0.5, 0.5)),
        (8.0, (0.5, 0.0)),
        (8.0, (0.25, -0.5)),
        (1.0, (0.0, 0.5)),
    ];
    for kernel in sph {
        for (support_px, (ox, oy)) in cases {
            let q = SplatParticle {
                center: Vec3::new(0.5 + ox / n as f32, 0.5 + oy / n as f32, 0.5),
                radius: support_px / n as f32 / kernel.support_factor(),
                weight: 1.5,
            };
            let r = q.radius as f64;
            let column = kernel.column(r);
            let exact = |b2: f64| {
                let f = crate::kernel::column_poly::column_by_quadrature(kernel, b2.sqrt() / r);
                if b2 < column.support2() {
                    q.weight as f64 * column.scale() * f
                } else {
                    0.0
                }
            };
            let peak = exact(0.0);
            // (`Auto`: the sixteen lanes where the CPU has AVX-512.)
            for simd in [Simd::Portable, Simd::Avx2, Simd::Auto] {
                if !simd.available() {
                    continue;
                }
                let mut s = Splatter::new(&cam, n, n, kernel, None).unwrap().on(simd);
                s.add(&[q], 0, &Control::new()).unwrap();
                let got = s.finish().unwrap();
                let mut worst = 0.0f64;
                assert!(
                    got.iter().all(|&v| v >= 0.0),
                    "{kernel:?}: a negative column"
                );
                for (k, &v) in got.iter().enumerate() {
                    let (x, y) = ((k as u32 % n) as f64, (k as u32 / n) as f64);
                    let bx = (x + 0.5) / n as f64 - q.center.x as f64;
                    let by = 1.0 - (y + 0.5) / n as f64 - q.center.y as f64;
                    worst = worst.max((v as f64 - exact(bx * bx + by * by)).abs());
                }
                assert!(
                    worst <= 2e-6 * peak,
                    "{kernel:?}, {support_px} px, {simd:?}: {:e} of the peak",
                    worst / peak
                );
            }
        }
    }
}

/// Images wide enough for padded rows (`row_stride`), their supports
/// crossing both edges, against the columns by quadrature summed pixel by
/// pixel, on every lane backend: within 2e-6 of the sum of the peaks over
/// each pixel plus the image's f32 rounding.
#[test]
fn padded_rows_hold_the_exact_columns() {
    let unit = Aabb::new(Vec3::splat(0.0), Vec3::splat(1.0));
    let cam = Camera::axis_projection(&unit, 2).unwrap();
    let (w, h) = (300u32, 23u32);
    assert!(row_stride(w) > w as usize);
    let mut rng = SmallRng(17);
    let p: Vec<SplatParticle> = (0..60)
        .map(|_| SplatParticle {
            center: Vec3::new(1.1 * rng.f() - 0.05, 1.1 * rng.f() - 0.05, rng.f()),
            radius: 0.005 + 0.03 * rng.f(),
            weight: 0.5 + rng.f(),
        })
        .collect();
    for kernel in [Kernel::WendlandC2, Kernel::CubicSpline] {
        let f = |qb: f64| crate::kernel::column_poly::column_by_quadrature(kernel, qb);
        let (mut exact, mut peaks) = (
            vec![0.0f64; (w * h) as usize],
            vec![0.0f64; (w * h) as usize],
        );
        for q in &p {
            let (r, column) = (q.radius as f64, kernel.column(q.radius as f64));
            for (k, (e, pk)) in exact.iter_mut().zip(&mut peaks).enumerate() {
                let (x, y) = ((k as u32 % w) as f64, (k as u32 / w) as f64);
                let bx = (x + 0.5) / w as f64 - q.center.x as f64;
                let by = 1.0 - (y + 0.5) / h as f64 - q.center.y as f64;
                let b2 = bx * bx + by * by;
                if b2 < column.support2() {
                    *e += q.weight as f64 * column.scale() * f(b2.sqrt() / r);
                    *pk += q.weight as f64 * column.scale() * f(0.0);
                }
            }
        }
        for simd in [Simd::Portable, Simd::Avx2, Simd::Auto] {
            if !simd.available() {
                continue;
            }
            let mut s = Splatter::new(&cam, w, h, kernel, None).unwrap().on(simd);
            s.add(&p, 0, &Control::new()).unwrap();
            let got = s.finish().unwrap();
            assert_eq!(got.len(), (w * h) as usize);
            for (k, &v) in got.iter().enumerate() {
                let allowed = 2e-6 * peaks[k] + 1.2e-7 * exact[k];
                assert!(
                    (v as f64 - exact[k]).abs() <= allowed,
                    "{kernel:?} {simd:?} pixel {k}: {v} vs {}",
                    exact[k]
                );
            }
        }
    }
}

/// Particles sharing a radius are placed eight at a time in lanes
/// (`Placer::place_batch`), others one at a time (`Placer::place`): the
/// same splats, bit for bit. Chunks of 13 put every particle in a batch in
/// one run and on its own in the other (a piece's tail), over supports
/// off the image, crossing it and the periodic box's faces, and weights
/// of 0, on every lane backend.
#[test]
fn batches_place_as_one_particle_at_a_time() {
    let mut rng = SmallRng(23);
    let p: Vec<SplatParticle> = (0..3000)
        .map(|i| SplatParticle {
            center: Vec3::new(1.3 * rng.f() - 0.15, 1.3 * rng.f() - 0.15, rng.f()),
            // A shared radius, broken now and then (a batch with another
            // radius takes the particles one at a time).
            radius: if i % 97 == 0 { 0.031 } else { 0.02 },
            weight: if i % 29 == 0 { 0.0 } else { 0.5 + rng.f() },
        })
        .collect();
    let cam = Camera::axis_projection(&Aabb::new(Vec3::splat(0.0), Vec3::splat(1.0)), 2).unwrap();
    let boxed = Some(Aabb::new(Vec3::splat(-0.1), Vec3::splat(1.1)));
    for simd in [Simd::Portable, Simd::Avx2, Simd::Auto] {
        if !simd.available() {
            continue;
        }
        for periodic in [None, boxed] {
            let run = |chunk: usize| {
                let mut s = Splatter::new(&cam, 90, 61, Kernel::WendlandC2, periodic)
                    .unwrap()
                    .on(simd);
                for (k, c) in p.chunks(chunk).enumerate() {
                    s.add(c, k * chunk, &Control::new()).unwrap();
                }
                s.finish().unwrap()
            };
            let whole = run(p.len());
            assert!(whole.iter().any(|&v| v > 0.0));
            assert_eq!(whole, run(13), "{simd:?}, {periodic:?}");
        }
    }
}

/// The sixteen lanes' placement (`splat_wide::place_lanes`) gives the
/// portable lanes' centres, rows, columns and masks bit for bit.
#[cfg(target_arch = "x86_64")]
#[test]
fn placement_lanes_equal_the_portable_lanes() {
    if !splat_wide::available() {
        println!("note: this CPU has no AVX-512F; the sixteen-lane placement is not run here");
        return;
    }
    let mut rng = SmallRng(29);
    let unit = Aabb::new(Vec3::splat(0.0), Vec3::splat(1.0));
    let views = [
        Camera::axis_projection(&unit, 2).unwrap(),
        Camera::axis_projection(&unit, 0).unwrap(),
    ];
    for cam in views {
        for periodic in [None, Some(unit)] {
            let s = Splatter::new(&cam, 77, 130, Kernel::CubicSpline, periodic).unwrap();
            let placer = s.placer();
            for _ in 0..500 {
                let batch: [SplatParticle; BATCH] = std::array::from_fn(|_| SplatParticle {
                    center: Vec3::new(1.4 * rng.f() - 0.2, 1.4 * rng.f() - 0.2, rng.f()),
                    radius: 0.03,
                    weight: 1.0,
                });
                let support = placer.factor * 0.03 * (0.5 + rng.f());
                let r = (
                    support as f64 * placer.to_pixels.0,
                    support as f64 * placer.to_pixels.1,
                );
                let (mut a, mut b) = (BatchLanes::default(), BatchLanes::default());
                placer.lanes(&batch, support, r, &mut a);
                // SAFETY: AVX-512F is available.
                unsafe { splat_wide::place_lanes(&placer, &batch, support, r, &mut b) };
                assert_eq!((a.only, a.keep), (b.only, b.keep));
                assert_eq!(
                    (a.row0, a.row1, a.col0, a.col1),
                    (b.row0, b.row1, b.col0, b.col1)
                );
                assert_eq!(a.cx.map(f64::to_bits), b.cx.map(f64::to_bits));
                assert_eq!(a.cy.map(f64::to_bits), b.cy.map(f64::to_bits));
            }
        }
    }
}
