//! Known answers: uniform grids (mean density, one stream), the analytic
//! Zel'dovich plane wave, mass conservation, periodic shifts, and a
//! brute-force renderer that tests every tet against every ray.

use super::*;
use crate::testing::{folded_sheet, grid, jitter};
use voxless_core::SmallRng as Lcg;
use voxless_core::{Aabb, Camera, Control, Ray, Vec3, Volume};

#[test]
fn bad_input_is_a_clear_error() {
    let mut g = grid(4, 1.0, |_| [0.0; 3]);
    let s = TetSettings::default();
    let mut short = g.clone();
    short.positions.pop();
    assert!(matches!(
        TetMesh::new(&short, &s),
        Err(TetError::NotCubic { count: 63 })
    ));
    for l in [0.0, -1.0, f32::NAN] {
        let bad = LagrangianGrid {
            box_size: l,
            ..g.clone()
        };
        assert!(matches!(
            TetMesh::new(&bad, &s),
            Err(TetError::BadBox { .. })
        ));
    }
    g.positions[5].y = f32::NAN;
    assert!(matches!(
        TetMesh::new(&g, &s),
        Err(TetError::NonFinite { index: 5 })
    ));
}

#[test]
fn uniform_grid_has_mean_density_and_one_stream() {
    let g = grid(6, 2.0, |_| [0.0; 3]);
    let v = TetVolume::new(&g, &TetSettings::default(), 0).unwrap();
    let mean = 1.0 / 8.0;
    let mut rng = Lcg(1);
    let mut points: Vec<Vec3> = (0..2000)
        .map(|_| Vec3::new(rng.f(), rng.f(), rng.f()) * 2.0)
        .collect();
    // Grid-aligned points lie on shared faces, edges and vertices: cell
    // centres sit on the diagonal all six tets of a cell share.
    let dq = 2.0 / 6.0;
    for i in 0..6 {
        points.push(Vec3::splat((i as f32 + 0.5) * dq));
        points.push(Vec3::new(i as f32 * dq, 0.5 * dq, (i as f32 + 0.5) * dq));
        points.push(Vec3::splat(i as f32 * dq));
    }
    for p in points {
        let (rho, streams) = v.density_and_streams(p);
        assert_eq!(streams, 1, "at {p:?}");
        assert!((rho - mean).abs() < 1e-5 * mean, "{rho}");
    }
}

#[test]
fn a_volume_from_a_mesh_is_the_volume_of_its_grid() {
    let g = folded_sheet(6, 11);
    let s = TetSettings::default();
    let a = TetVolume::new(&g, &s, 0).unwrap();
    let b = TetVolume::from_mesh(TetMesh::new(&g, &s).unwrap());
    assert_eq!(a.bounds(), b.bounds());
    assert_eq!(a.value_range(), b.value_range());
    assert_eq!(a.mesh.tet_count(), b.mesh.tet_count());
    let p = Vec3::new(0.3, 0.6, 0.2);
    assert_eq!(a.density_and_streams(p), b.density_and_streams(p));
}

fn axis_camera(l: f32) -> Camera {
    Camera::axis_projection(&Aabb::new(Vec3::ZERO, Vec3::splat(l)), 2).unwrap()
}

#[test]
fn projection_of_the_box_conserves_mass() {
    let g = grid(8, 1.0, jitter(3, 0.04));
    let v = TetVolume::new(&g, &TetSettings::default(), 0).unwrap();
    for (axis, res) in [(0, 256u32), (1, 200), (2, 320)] {
        let cam = Camera::axis_projection(&Aabb::new(Vec3::ZERO, Vec3::ONE), axis).unwrap();
        let col = render::project(
            &v.mesh,
            &cam,
            res,
            res,
            TetOptions::default(),
            &Control::new(),
        )
        .unwrap();
        let mass: f64 = col.iter().map(|&c| c as f64).sum::<f64>() / (res as f64 * res as f64);
        assert!((mass - 1.0).abs() <= 1e-3, "axis {axis}: {mass}");
    }
}

#[test]
fn sampled_densities_equal_the_derived_blocks() {
    // Every tet's density in mesh order, block by block: the reference the
    // sample picks every stride-th of.
    let reference = |mesh: &TetMesh| {
        let mut buf = Vec::new();
        let all: Vec<f32> = (0..mesh.blocks().len())
            .flat_map(|b| {
                mesh.block_tets(b, &mut buf)
                    .iter()
                    .map(|t| t.density)
                    .collect::<Vec<_>>()
            })
            .collect();
        let stride = density_stride(mesh.tet_count());
        all.into_iter().step_by(stride).collect::<Vec<f32>>()
    };
    // 40³: stride 3, blocks cut by the box's faces (several images), a
    // folded sheet, and cells squashed flat (degenerate tets).
    let mut g = folded_sheet(40, 4);
    for i in (0..g.positions.len() - 1).step_by(997) {
        g.positions[i + 1] = g.positions[i];
    }
    for g in [g, grid(32, 1.0, jitter(3, 0.2))] {
        let mesh = TetMesh::new(&g, &TetSettings::default()).unwrap();
        let mut lagrangian: Vec<u32> = mesh.blocks().iter().map(|b| b.lagrangian).collect();
        lagrangian.dedup();
        assert!(
            lagrangian.len() < mesh.blocks().len(),
            "blocks at several images"
        );
        let fast = sampled_densities(&mesh);
        assert_eq!(fast.len(), reference(&mesh).len());
        assert!(
            fast.iter()
                .zip(reference(&mesh))
                .all(|(a, b)| a.to_bits() == b.to_bits())
        );
    }
}

#[test]
fn sampled_density_integrates_to_the_total_mass() {
    let g = grid(6, 1.0, jitter(5, 0.05));
    let v = TetVolume::new(&g, &TetSettings::default(), 0).unwrap();
    let mut errors = Vec::new();
    for m in [16usize, 48] {
        let h = 1.0 / m as f32;
        let mut sum = 0.0f64;
        for i in 0..m {
            for j in 0..m {
                for k in 0..m {
                    let p = Vec3::new(i as f32 + 0.5, j as f32 + 0.5, k as f32 + 0.5) * h;
                    sum += v.density_and_streams(p).0;
                }
            }
        }
        errors.push((sum * (h as f64).powi(3) - 1.0).abs());
    }
    assert!(errors[1] < errors[0] && errors[1] < 5e-3, "{errors:?}");
}

/// The Zel'dovich sheet x = q + A sin(kq) after shell crossing (A·k = 1.5).
fn zeldovich(n: usize) -> (LagrangianGrid, impl Fn(f32) -> f32) {
    let l = 1.0f32;
    let k = std::f32::consts::TAU / l;
    let a = 1.5 / k;
    let x_of = move |q: f32| q + a * (k * q).sin();
    (grid(n, l, move |q| [x_of(q[0]) - q[0], 0.0, 0.0]), x_of)
}

#[test]
fn zeldovich_density_matches_the_cell_sum_and_streams() {
    let n = 32;
    let (g, x_of) = zeldovich(n);
    let v = TetVolume::new(&g, &TetSettings::default(), 0).unwrap();
    let dq = 1.0 / n as f32;
    let rho_bar = 1.0f64;
    let mut rng = Lcg(9);
    let mut checked = 0;
    for _ in 0..3000 {
        let x = rng.f();
        // Expected: Σ over Lagrangian cells whose x-extent covers x (periodic).
        let mut want = 0.0f64;
        let mut covering = 0;
        let mut near_edge = false;
        for i in 0..n {
            let (a, b) = (x_of(i as f32 * dq), x_of((i + 1) as f32 * dq));
            let (lo, hi) = (a.min(b), a.max(b));
            for shift in [-1.0f32, 0.0, 1.0] {
                let xs = x + shift;
                if (xs - lo).abs() < 1e-4 || (xs - hi).abs() < 1e-4 {
                    near_edge = true;
                }
                if xs > lo && xs < hi {
                    want += rho_bar * dq as f64 / (hi - lo) as f64;
                    covering += 1;
                }
            }
        }
        if near_edge {
            continue;
        }
        // y, z away from cell faces.
        let p = Vec3::new(
            x,
            (rng.f() * 0.8 + 0.1) * dq + 0.3,
            (rng.f() * 0.8 + 0.1) * dq + 0.6,
        );
        let (rho, streams) = v.density_and_streams(p);
        assert_eq!(streams as usize, covering, "streams at x = {x}");
        assert!(covering == 1 || covering == 3, "{covering}");
        assert!(
            (rho - want).abs() <= 1e-4 * want,
            "x = {x}: {rho} vs {want}"
        );
        checked += 1;
    }
    assert!(checked > 2500);
}

#[test]
fn zeldovich_error_against_the_analytic_density_halves_with_resolution() {
    let k = std::f64::consts::TAU;
    let a = 1.5 / k;
    // Analytic: Σ over streams q_s with x(q_s) = x of ρ̄ / |1 + A k cos(k q_s)|,
    // streams found by bisection on a fine q grid.
    let analytic = |x: f64| -> Option<f64> {
        let f = |q: f64| q + a * (k * q).sin() - x;
        let m = 20_000;
        let mut sum = 0.0;
        for i in 0..m {
            let (q0, q1) = (i as f64 / m as f64 - 0.5, (i + 1) as f64 / m as f64 - 0.5);
            // Search q over [-0.5, 1.5) so periodic images of x are found.
            for off in [0.0, 1.0] {
                let (a0, a1) = (q0 + off, q1 + off);
                if f(a0) * f(a1) <= 0.0 && f(a0) != f(a1) {
                    let (mut lo, mut hi) = (a0, a1);
                    for _ in 0..60 {
                        let mid = 0.5 * (lo + hi);
                        if f(lo) * f(mid) <= 0.0 {
                            hi = mid
                        } else {
                            lo = mid
                        }
                    }
                    let dxdq = (1.0 + a * k * (k * lo).cos()).abs();
                    if dxdq < 0.2 {
                        return None; // too close to a caustic
                    }
                    sum += 1.0 / dxdq;
                }
            }
        }
        Some(sum)
    };
    let mut errs = Vec::new();
    for n in [32usize, 128] {
        let (g, _) = zeldovich(n);
        // Only the x-extent matters: a thin slab of cells suffices, but the
        // tessellation needs the full N³ grid; keep N³ and sample few points.
        let v = TetVolume::new(&g, &TetSettings::default(), 0).unwrap();
        let mut total = 0.0;
        let mut count = 0;
        for i in 0..400 {
            let x = (i as f64 + 0.37) / 400.0;
            let Some(want) = analytic(x) else { continue };
            let (rho, _) = v.density_and_streams(Vec3::new(x as f32, 0.013, 0.021));
            total += (rho - want).abs() / want;
            count += 1;
        }
        errs.push(total / count as f64);
    }
    assert!(
        errs[1] <= 0.5 * errs[0],
        "mean relative error {errs:?} should at least halve"
    );
}

#[test]
fn half_box_shift_renders_identically() {
    let n = 8;
    let base = grid(n, 1.0, jitter(17, 0.04));
    let shifted = LagrangianGrid {
        positions: base
            .positions
            .iter()
            .map(|p| {
                Vec3::new(
                    (p.x + 0.5).rem_euclid(1.0),
                    p.y,
                    (p.z + 0.5).rem_euclid(1.0),
                )
            })
            .collect(),
        ..base.clone()
    };
    // The same particles, relabelled so the Lagrangian grid is shifted too.
    let relabel = |g: &LagrangianGrid| {
        let mut out = g.positions.clone();
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    out[(((i + n / 2) % n) * n + j) * n + (k + n / 2) % n] =
                        g.positions[(i * n + j) * n + k];
                }
            }
        }
        LagrangianGrid {
            positions: out,
            ..g.clone()
        }
    };
    let shifted = relabel(&shifted);
    let a = TetVolume::new(&base, &TetSettings::default(), 0).unwrap();
    let b = TetVolume::new(&shifted, &TetSettings::default(), 0).unwrap();
    // Looking down y with the image covering exactly the box: a shift by half
    // a box in x and z is a periodic relabelling, so the column density is the
    // same map rolled by half the image.
    let cam = Camera::axis_projection(&Aabb::new(Vec3::ZERO, Vec3::ONE), 1).unwrap();
    let res = 64u32;
    let ca = render::project(
        &a.mesh,
        &cam,
        res,
        res,
        TetOptions::default(),
        &Control::new(),
    )
    .unwrap();
    let cb = render::project(
        &b.mesh,
        &cam,
        res,
        res,
        TetOptions::default(),
        &Control::new(),
    )
    .unwrap();
    let mut max = 0.0f32;
    for row in 0..res {
        for col in 0..res {
            let rolled = (((row + res / 2) % res) * res + (col + res / 2) % res) as usize;
            max = max.max((ca[(row * res + col) as usize] - cb[rolled]).abs());
        }
    }
    let scale = ca.iter().copied().fold(0.0f32, f32::max);
    assert!(max <= 1e-4 * scale, "max difference {max} of {scale}");
    // And the unshifted grid's total mass is intact in both.
    let sum = |c: &[f32]| c.iter().map(|&v| v as f64).sum::<f64>() / (res * res) as f64;
    assert!((sum(&ca) - 1.0).abs() < 1e-3 && (sum(&cb) - 1.0).abs() < 1e-3);
}

#[test]
fn ray_tet_clip_matches_point_sampling() {
    let g = grid(4, 1.0, jitter(19, 0.08));
    let mesh = TetMesh::new(&g, &TetSettings::default()).unwrap();
    let mut rng = Lcg(23);
    for t in mesh.tets().iter().take(200) {
        let c = (t.v[0] + t.v[1] + t.v[2] + t.v[3]) * 0.25;
        let o = c + Vec3::new(rng.f() - 0.5, rng.f() - 0.5, 2.0);
        let ray = Ray::new(
            o,
            (c + Vec3::new(rng.f() - 0.5, rng.f() - 0.5, 0.0) * 0.05 - o).normalized(),
        );
        let (a, b) = raster::Planes::new(t).clip(&ray);
        let chord = (b - a).max(0.0);
        let steps = 20_000;
        let inside = (0..steps)
            .filter(|&i| t.contains(ray.at(4.0 * (i as f32 + 0.5) / steps as f32)))
            .count();
        let est = inside as f32 * 4.0 / steps as f32;
        assert!(
            (chord - est).abs() <= 2.0 * 4.0 / steps as f32 + 1e-5,
            "{chord} vs {est}"
        );
    }
    let _ = axis_camera(1.0);
}

#[test]
fn lod_conserves_mass_and_approaches_the_full_render() {
    let g = grid(16, 1.0, jitter(29, 0.02));
    let v = TetVolume::new(&g, &TetSettings::default(), 3).unwrap();
    assert_eq!(v.mesh.lod().len(), 3, "levels for N = 16: 8, 4, 2");
    let cam = axis_camera(1.0);
    // Every block is below 10⁶ pixels: the coarsest levels are used, and a
    // projection still carries the whole mass.
    let opts = TetOptions {
        lod_pixels: Some(1e6),

        ..Default::default()
    };
    let col = render::project(&v.mesh, &cam, 128, 128, opts, &Control::new()).unwrap();
    let mass: f64 = col.iter().map(|&c| c as f64).sum::<f64>() / (128.0 * 128.0);
    assert!((mass - 1.0).abs() <= 1e-3, "{mass}");
    // A threshold below every block's size changes nothing.
    let full = render::project(
        &v.mesh,
        &cam,
        128,
        128,
        TetOptions::default(),
        &Control::new(),
    )
    .unwrap();
    let same = render::project(
        &v.mesh,
        &cam,
        128,
        128,
        TetOptions {
            lod_pixels: Some(1.0),

            ..Default::default()
        },
        &Control::new(),
    )
    .unwrap();
    assert_eq!(full, same);
    // Coarser levels differ from the full mesh, by less as the threshold drops.
    let diff = |t: f32| {
        let c = render::project(
            &v.mesh,
            &cam,
            128,
            128,
            TetOptions {
                lod_pixels: Some(t),

                ..Default::default()
            },
            &Control::new(),
        )
        .unwrap();
        c.iter()
            .zip(&full)
            .map(|(a, b)| (a - b).abs() as f64)
            .sum::<f64>()
    };
    let (coarse, medium) = (diff(1e6), diff(70.0));
    assert!(
        coarse > 0.0 && medium < coarse,
        "coarse {coarse}, medium {medium}"
    );
}

#[test]
fn fast_projection_equals_full_ray_clipping() {
    // Overlapping tets of both projection classes, and tets crossing box
    // faces (clipped to the box).
    let g = folded_sheet(8, 37);
    let v = TetVolume::new(&g, &TetSettings::default(), 0).unwrap();
    for axis in 0..3 {
        let cam = Camera::axis_projection(&Aabb::new(Vec3::ZERO, Vec3::ONE), axis).unwrap();
        let fast = render::project(
            &v.mesh,
            &cam,
            96,
            80,
            TetOptions::default(),
            &Control::new(),
        )
        .unwrap();
        let slow = render::project(
            &v.mesh,
            &cam,
            96,
            80,
            TetOptions {
                clip_only: true,
                ..Default::default()
            },
            &Control::new(),
        )
        .unwrap();
        let scale = slow.iter().copied().fold(0.0f32, f32::max);
        let worst = fast
            .iter()
            .zip(&slow)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        // Same planes, evaluated as affine forms vs per ray: f32 rounding on
        // thin, dense tets at caustics stays well below 1e-3 of the peak.
        assert!(
            worst <= 1e-3 * scale,
            "axis {axis}: fast vs full clip differ by {worst} (max {scale})"
        );
        let mass: f64 = fast.iter().map(|&c| c as f64).sum::<f64>() / (96.0 * 80.0);
        assert!((mass - 1.0).abs() <= 2e-3, "{mass}");
    }
}

/// Perspective views take the per-pixel clips of `for_each_crossing` (the
/// faces in lanes; an outline only for tets over a few pixels): the same
/// planes and rays as the full clip of every pixel of each tet's
/// rectangle, so the same images — from far (sub-pixel tets, no outline)
/// and from near (tets over many pixels, outlines).
#[test]
fn perspective_crossings_equal_full_ray_clipping() {
    let g = folded_sheet(8, 37);
    let v = TetVolume::new(&g, &TetSettings::default(), 0).unwrap();
    let perspective = voxless_core::Projection::Perspective { fov_y_deg: 40.0 };
    for (eye, size) in [
        (Vec3::new(1.6, 1.3, -0.8), 24),
        (Vec3::new(0.9, 0.7, -0.1), 96),
    ] {
        let cam =
            Camera::look_at(eye, Vec3::splat(0.5), Vec3::new(0.0, 1.0, 0.0), perspective).unwrap();
        let image = |clip_only| {
            let options = TetOptions {
                clip_only,
                ..Default::default()
            };
            render::project(&v.mesh, &cam, size, size, options, &Control::new()).unwrap()
        };
        let (fast, slow) = (image(false), image(true));
        let scale = slow.iter().copied().fold(0.0f32, f32::max);
        assert!(scale > 0.0);
        // An outline can only drop a pixel whose ray grazes a tet's edge
        // within rounding; every pixel here agrees to 1e-6 of the peak.
        for (p, (a, b)) in fast.iter().zip(&slow).enumerate() {
            assert!(
                (a - b).abs() <= 1e-6 * scale,
                "eye {eye:?}, pixel {p}: {a} vs {b}"
            );
        }
    }
}

/// Eight points projected in lanes are [`raster::Screen::project`]'s
/// coordinates bit for bit, and the lanes say when one is behind the eye.
#[test]
fn perspective_points_project_as_one_point_does() {
    let mut rng = Lcg(5);
    let cam = Camera::look_at(
        Vec3::new(0.3, -2.0, 0.4),
        Vec3::new(0.5, 0.5, 0.5),
        Vec3::new(0.0, 0.0, 1.0),
        voxless_core::Projection::Perspective { fov_y_deg: 35.0 },
    )
    .unwrap();
    let screen = raster::Screen::new(&cam, 750, 500);
    let mut behind = 0;
    for case in 0..5_000 {
        let spread = if case % 3 == 0 { 8.0 } else { 1.0 };
        let p = [(); 8].map(|_| (Vec3::new(rng.f(), rng.f(), rng.f()) - Vec3::splat(0.5)) * spread);
        let (px, py, front) = screen.perspective_points(&p);
        let one: Vec<_> = p.iter().map(|&q| screen.project(q)).collect();
        assert_eq!(front, one.iter().all(Option::is_some), "{p:?}");
        behind += usize::from(!front);
        for (k, q) in one.iter().enumerate() {
            if let Some((x, y)) = q {
                assert_eq!(
                    (x.to_bits(), y.to_bits()),
                    (px[k].to_bits(), py[k].to_bits())
                );
            }
        }
    }
    assert!(behind > 100, "{behind} sets reach behind the eye");
}

mod area;
mod lean;
mod ortho;

#[test]
fn kuhn_volumes_are_each_tets_signed_volume_bit_for_bit() {
    // Cells of every shape: unit-ish, sheared, far from the origin, folded
    // (corners crossing over), flat and with repeated corners.
    let mut rng = Lcg(17);
    for case in 0..4000 {
        let origin = Vec3::splat([0.0, 1e3, -7e4, 3.3][case % 4]);
        let scale = [1.0, 1e-3, 40.0, 0.25][(case / 4) % 4];
        let mut corners: [Vec3; 8] = std::array::from_fn(|c| {
            let unit = Vec3::new((c & 1) as f32, ((c >> 1) & 1) as f32, ((c >> 2) & 1) as f32);
            let jitter = Vec3::new(rng.f() - 0.5, rng.f() - 0.5, rng.f() - 0.5);
            origin + (unit + jitter * [0.1, 0.9, 2.5][case % 3]) * scale
        });
        if case % 7 == 0 {
            corners[3] = corners[1];
        }
        if case % 11 == 0 {
            for c in &mut corners {
                c.z = origin.z;
            }
        }
        let volumes = Tet::kuhn_volumes(&corners);
        for (k, t) in crate::mesh::KUHN.into_iter().enumerate() {
            let one = Tet::signed_volume(&t.map(|c| corners[c]));
            assert_eq!(volumes[k].to_bits(), one.to_bits(), "case {case}, tet {k}");
        }
    }
}
