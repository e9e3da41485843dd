//! Tessellations through the shared integrator: the tile view's exact
//! constant pieces against a brute-force renderer (every tet against every
//! ray), against the per-ray path and against generic point sampling; the
//! k-buffer converging to exact; the clip box, iso-surfaces, jittered
//! passes and shadows.

use voxless_core::testing::{PerRay, Resampled};
use voxless_core::{Aabb, Camera, Control, EventBudget, Projection, Range1, Vec3, Volume};
use voxless_render::{LightSource, RenderSettings, Scatter, render};
use voxless_tets::raster::{self, Frame};
use voxless_tets::testing::{folded_sheet, grid, jitter};
use voxless_tets::{TetSettings, TetVolume};
use voxless_transfer::{Colormap, OpacityMap, TransferFunction};

/// Largest per-channel difference between two RGBA images.
fn max_abs_diff(a: &[[f32; 4]], b: &[[f32; 4]]) -> f32 {
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..4).map(move |c| (p[c] - q[c]).abs()))
        .fold(0.0, f32::max)
}

fn log_tf() -> TransferFunction {
    TransferFunction::new(
        Colormap::preset("inferno").unwrap(),
        OpacityMap::preset("linear").unwrap(),
    )
}

fn settings_for(v: &TetVolume, w: u32, h: u32) -> RenderSettings {
    let mut s = RenderSettings::for_volume(v, w, h);
    s.log_scale = true;
    s.value_range = Range1::new(v.value_range().lo.log10(), v.value_range().hi.log10());
    s.early_termination = 1.0;
    s
}

fn perspective(eye: Vec3, at: Vec3, fov: f32) -> Camera {
    Camera::look_at(
        eye,
        at,
        Vec3::new(0.0, 1.0, 0.0),
        Projection::Perspective { fov_y_deg: fov },
    )
    .unwrap()
}

fn run<P: voxless_core::Prepare>(
    v: &P,
    cam: &Camera,
    tf: &TransferFunction,
    s: &RenderSettings,
) -> Vec<[f32; 4]> {
    render(v, cam, tf, s, &Control::new()).unwrap().pixels
}

/// Every tet against every pixel-centre ray within `region`, events sorted,
/// integrated exactly.
fn brute_force(
    v: &TetVolume,
    cam: &Camera,
    tf: &TransferFunction,
    s: &RenderSettings,
    region: Aabb,
) -> Vec<[f32; 4]> {
    let mut out = Vec::new();
    let tets = v.mesh.tets();
    for y in 0..s.height {
        for x in 0..s.width {
            let ray = cam.ray(x as f32 + 0.5, y as f32 + 0.5, s.width, s.height);
            let mut ev: Vec<(f32, f64)> = Vec::new();
            let span = region.clip_ray(&ray, Range1::new(0.0, f32::INFINITY));
            for t in &tets {
                let (a, b) = raster::Planes::new(t).clip(&ray);
                let (a, b) = (a.max(span.lo), b.min(span.hi));
                if b > a {
                    ev.push((a, t.density as f64));
                    ev.push((b, -(t.density as f64)));
                }
            }
            ev.sort_by(|a, b| a.0.total_cmp(&b.0));
            let (mut rho, mut c, mut alpha) = (0.0f64, Vec3::ZERO, 0.0f32);
            for w in ev.windows(2) {
                rho += w[0].1;
                let len = w[1].0 - w[0].0;
                if rho > 1e-9 && len > 0.0 {
                    let xx = s.normalize(rho as f32);
                    let a = 1.0 - (-tf.opacity(xx) * s.opacity_scale * len).exp();
                    c += tf.color(xx) * ((1.0 - alpha) * a);
                    alpha += (1.0 - alpha) * a;
                }
            }
            out.push([c.x, c.y, c.z, alpha]);
        }
    }
    out
}

fn unit_box() -> Aabb {
    Aabb::new(Vec3::ZERO, Vec3::ONE)
}

#[test]
fn exact_pieces_equal_brute_force_and_the_kbuffer_converges() {
    let g = folded_sheet(6, 11);
    let v = TetVolume::new(&g, &TetSettings::default(), 0).unwrap();
    let tf = log_tf();
    let cam = perspective(Vec3::new(1.9, 1.4, 2.3), Vec3::splat(0.5), 40.0);
    let s = settings_for(&v, 24, 20);
    let want = brute_force(&v, &cam, &tf, &s, unit_box());
    let exact = run(&v, &cam, &tf, &s);
    let err = max_abs_diff(&exact, &want);
    assert!(err <= 1e-5, "exact vs brute force: {err}");
    assert!(want.iter().any(|p| p[3] > 0.05), "the mesh is visible");
    // The tile view gives what the per-ray path (BVH events) gives.
    let per_ray = run(&PerRay(&v), &cam, &tf, &s);
    let err = max_abs_diff(&exact, &per_ray);
    assert!(err <= 1e-5, "tile view vs per ray: {err}");
    // The k-buffer's error falls as k grows, and vanishes once k holds everything.
    let mut last = f32::INFINITY;
    for k in [2usize, 4, 8, 16, 32, 64, 4096] {
        let mut sk = s.clone();
        sk.event_budget = Some(EventBudget { k, layers: 32 });
        let img = run(&v, &cam, &tf, &sk);
        let e = img
            .iter()
            .zip(&want)
            .map(|(a, b)| (0..4).map(|c| (a[c] - b[c]).abs()).sum::<f32>())
            .sum::<f32>();
        assert!(
            e <= last * 1.0001 + 1e-6,
            "k = {k}: error {e} rose from {last}"
        );
        last = e;
    }
    assert!(last <= 1e-3, "k = 4096 should be exact: {last}");
}

#[test]
fn exact_pieces_agree_with_generic_point_sampling() {
    let g = grid(5, 1.0, jitter(13, 0.05));
    let v = TetVolume::new(&g, &TetSettings::default(), 0).unwrap();
    let tf = log_tf();
    let cam = perspective(Vec3::new(2.0, 1.5, 2.5), Vec3::splat(0.5), 35.0);
    let s = settings_for(&v, 16, 16);
    let exact = run(&v, &cam, &tf, &s);
    // The same intervals stepped through at 5e-4 with a BVH point query
    // per sample: the generic path every other kind takes.
    let sampled = run(
        &Resampled {
            volume: &v,
            step: 0.0005,
        },
        &cam,
        &tf,
        &s,
    );
    let max = max_abs_diff(&exact, &sampled);
    assert!(max <= 5e-3, "exact vs sampled (step 5e-4): {max}");
}

#[test]
fn uniform_grid_shifted_by_half_a_box_renders_identically() {
    let base = grid(8, 1.0, |_| [0.0; 3]);
    let shifted = grid(8, 1.0, |_| [0.5, 0.5, 0.5]);
    let tf = log_tf();
    let cam = perspective(Vec3::new(1.8, 1.3, 2.2), Vec3::splat(0.5), 40.0);
    let images: Vec<_> = [base, shifted]
        .iter()
        .map(|g| {
            let v = TetVolume::new(g, &TetSettings::default(), 0).unwrap();
            let mut s = settings_for(&v, 40, 32);
            // The mean density of a uniform grid sits at the range's low end; widen it.
            s.value_range = Range1::new(-1.0, 1.0);
            run(&v, &cam, &tf, &s)
        })
        .collect();
    let max = max_abs_diff(&images[0], &images[1]);
    assert!(images[0].iter().any(|p| p[3] > 0.1), "visible");
    assert!(max <= 1e-5, "max difference {max}");
}

#[test]
fn camera_inside_the_box_renders_exactly_and_culls_what_is_behind() {
    let g = grid(6, 1.0, jitter(41, 0.04));
    let v = TetVolume::new(&g, &TetSettings::default(), 0).unwrap();
    let tf = log_tf();
    let cam = perspective(Vec3::new(0.5, 0.45, 0.55), Vec3::new(0.9, 0.6, 0.2), 70.0);
    let mut s = settings_for(&v, 24, 20);
    s.value_range = Range1::new(-1.0, 1.0);
    let want = brute_force(&v, &cam, &tf, &s, unit_box());
    let got = run(&v, &cam, &tf, &s);
    assert!(want.iter().any(|p| p[3] > 0.05), "visible");
    assert!(max_abs_diff(&got, &want) <= 1e-5);
    // Tets wholly behind the eye are binned nowhere.
    let frame = Frame::new(&v.mesh, &cam, 24, 20, None);
    let binned: usize = frame.tet_count(&v.mesh, None);
    assert!(
        binned < v.mesh.tet_count(),
        "{binned} of {} tets binned",
        v.mesh.tet_count()
    );
}

#[test]
fn clip_box_cuts_the_exact_render_like_brute_force() {
    let g = folded_sheet(6, 7);
    let v = TetVolume::new(&g, &TetSettings::default(), 0).unwrap();
    let tf = log_tf();
    let cam = perspective(Vec3::new(1.9, 1.4, 2.3), Vec3::splat(0.5), 40.0);
    let mut s = settings_for(&v, 24, 20);
    let full = run(&v, &cam, &tf, &s);
    let clip = Aabb::new(Vec3::new(0.1, 0.0, 0.2), Vec3::new(0.6, 0.7, 0.5));
    s.clip = Some(clip);
    let got = run(&v, &cam, &tf, &s);
    let want = brute_force(&v, &cam, &tf, &s, clip);
    assert!(max_abs_diff(&got, &want) <= 1e-5);
    assert!(
        max_abs_diff(&got, &full) > 0.05,
        "the clip changes the image"
    );
}

#[test]
fn iso_surface_lies_where_the_density_first_crosses_the_value() {
    let g = folded_sheet(6, 3);
    let v = TetVolume::new(&g, &TetSettings::default(), 0).unwrap();
    let tf = log_tf();
    let cam = perspective(Vec3::new(1.9, 1.4, 2.3), Vec3::splat(0.5), 40.0);
    let mut s = settings_for(&v, 24, 20);
    let iso = 2.0 * v.mesh.total_mass() as f32; // twice the mean density
    s.iso = vec![iso];
    s.volume = false;
    let img = run(&v, &cam, &tf, &s);
    // Brute force: a pixel is covered iff some piece of its ray (inside the
    // box, after the ray's first event) crosses the iso-value.
    let mut covered = 0;
    let tets = v.mesh.tets();
    for y in 0..s.height {
        for x in 0..s.width {
            let ray = cam.ray(x as f32 + 0.5, y as f32 + 0.5, s.width, s.height);
            let span = unit_box().clip_ray(&ray, Range1::new(0.0, f32::INFINITY));
            let mut ev: Vec<(f32, f64)> = Vec::new();
            for t in &tets {
                let (a, b) = raster::Planes::new(t).clip(&ray);
                let (a, b) = (a.max(span.lo), b.min(span.hi));
                if b > a {
                    ev.push((a, t.density as f64));
                    ev.push((b, -(t.density as f64)));
                }
            }
            ev.sort_by(|a, b| a.0.total_cmp(&b.0));
            // The positive pieces along the ray, longer than rounding
            // slivers (4 ulps of t); neighbours closer than that touch.
            let ulps = |t: f32| 4.0 * f32::EPSILON * t.abs();
            let mut pieces: Vec<(f32, f32, f64)> = Vec::new();
            let mut rho = 0.0f64;
            for (k, e) in ev.iter().enumerate() {
                rho += e.1;
                if let Some(n) = ev.get(k + 1)
                    && n.0 - e.0 > ulps(n.0)
                    && rho > 1e-9
                {
                    pieces.push((e.0, n.0, rho));
                }
            }
            // A step across the iso-value between touching pieces, or from
            // zero across a gap, is a hit; where the span starts or ends
            // the volume is cut, not bounded.
            let crosses = |a: f64, b: f64| (a - iso as f64) * (b - iso as f64) < 0.0;
            let mut hit = false;
            for (k, p) in pieces.iter().enumerate() {
                match k.checked_sub(1).map(|j| pieces[j]) {
                    Some(q) if p.0 - q.1 <= ulps(p.0) => hit |= crosses(q.2, p.2),
                    Some(q) => hit |= crosses(q.2, 0.0) || crosses(0.0, p.2),
                    None if p.0 - span.lo > ulps(p.0) => hit |= crosses(0.0, p.2),
                    None => {}
                }
            }
            if let Some(last) = pieces.last()
                && span.hi - last.1 > ulps(last.1)
            {
                hit |= crosses(last.2, 0.0);
            }
            let a = img[(y * s.width + x) as usize][3];
            assert_eq!(
                a > 0.5,
                hit,
                "pixel ({x}, {y}): alpha {a}, brute force hit {hit}"
            );
            covered += hit as usize;
        }
    }
    assert!(covered > 10, "{covered} pixels show the surface");
}

#[test]
fn jittered_passes_equal_the_per_ray_path() {
    let g = folded_sheet(6, 5);
    let v = TetVolume::new(&g, &TetSettings::default(), 0).unwrap();
    let tf = log_tf();
    let cam = perspective(Vec3::new(1.9, 1.4, 2.3), Vec3::splat(0.5), 40.0);
    let mut s = settings_for(&v, 24, 20);
    s.spp = 3;
    let tiles = run(&v, &cam, &tf, &s);
    let per_ray = run(&PerRay(&v), &cam, &tf, &s);
    assert!(max_abs_diff(&tiles, &per_ray) <= 1e-5);
    s.spp = 1;
    assert!(
        max_abs_diff(&tiles, &run(&v, &cam, &tf, &s)) > 1e-3,
        "spp antialiases"
    );
    // Orthographic views too.
    let ortho = Camera::axis_projection(&unit_box(), 1).unwrap();
    s.spp = 2;
    let a = run(&v, &ortho, &tf, &s);
    let b = run(&PerRay(&v), &ortho, &tf, &s);
    assert!(max_abs_diff(&a, &b) <= 1e-5);
}

#[test]
fn shadows_darken_a_tessellation_and_are_deterministic() {
    let g = folded_sheet(6, 9);
    let v = TetVolume::new(&g, &TetSettings::default(), 0).unwrap();
    let tf = log_tf();
    let cam = perspective(Vec3::new(1.9, 1.4, 2.3), Vec3::splat(0.5), 40.0);
    let mut s = settings_for(&v, 24, 20);
    s.spp = 4;
    s.scatter = Some(Scatter {
        light: LightSource::Directional(Vec3::new(-1.0, 0.3, 0.2).normalized()),
        intensity: 1.0,
        ambient: 0.1,
        method: Default::default(),
        noise: Default::default(),
    });
    let lit = run(&v, &cam, &tf, &s);
    assert_eq!(lit, run(&v, &cam, &tf, &s), "deterministic");
    let mut dark = s.clone();
    if let Some(sc) = &mut dark.scatter {
        sc.intensity = 0.0;
    }
    let shadowed = run(&v, &cam, &tf, &dark);
    let sum = |img: &[[f32; 4]]| img.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>();
    assert!(sum(&lit) > sum(&shadowed) * 1.5 && sum(&lit) > 0.0);
}

/// The work estimate through the tile view (no point index built) against
/// the per-ray estimate: on a square image both trace the same 16² pixel
/// centres, so the mean pieces per ray agree (to a ray whose f32 direction
/// differs in the last bit); on a wide image the tile view's grid has the
/// image's shape (21 × 12 rays, not 16 × 16): other rays, so the means of
/// this small folded mesh differ by ~10 %.
#[test]
fn work_estimates_through_the_tile_view_match_per_ray_ones() {
    let grid = folded_sheet(16, 5);
    let v = TetVolume::new(&grid, &TetSettings::default(), 0).unwrap();
    let tf = log_tf();
    let cam = perspective(Vec3::new(0.5, 0.4, 2.4), Vec3::splat(0.5), 35.0);
    for (w, h, tol) in [(96, 96, 0.01), (160, 90, 0.25)] {
        let s = settings_for(&v, w, h);
        let fresh = TetVolume::new(&grid, &TetSettings::default(), 0).unwrap();
        let tiled = voxless_render::estimate_work(&fresh, &cam, &tf, &s);
        assert!(!fresh.has_index(), "the tile view builds no point index");
        let per_ray = voxless_render::estimate_work(&PerRay(&v), &cam, &tf, &s);
        assert!(per_ray.per_ray > 10.0, "{per_ray:?}");
        let rel = (tiled.per_ray - per_ray.per_ray).abs() / per_ray.per_ray;
        assert!(rel <= tol, "{w}×{h}: {tiled:?} vs {per_ray:?}");
    }
}
