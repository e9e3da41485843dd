//! Meshes beside a volume and ambient occlusion, against brute force.

use super::*;
use voxless_core::Ray;
use voxless_transfer::{Colormap, OpacityMap};

use crate::ctx::Ctx;
use crate::meshes;
use crate::surface::occlusion;

use crate::test_volumes::Blob;

fn tf() -> TransferFunction {
    TransferFunction::new(
        Colormap::preset("viridis").unwrap(),
        OpacityMap::preset("linear").unwrap(),
    )
}

/// A square of side `2·half` centred at `c`, spanned by `u` and `v`.
fn square(c: Vec3, u: Vec3, v: Vec3, half: f32) -> Mesh {
    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    Mesh {
        positions: corners
            .iter()
            .map(|&(a, b)| (c + u * (a * half) + v * (b * half)).to_array())
            .collect(),
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        fields: Vec::new(),
    }
}

fn surfaces(meshes: &[Mesh]) -> Surfaces {
    let paint = Paint::Solid([0.9, 0.5, 0.2]);
    let list: Vec<(&Mesh, &Paint)> = meshes.iter().map(|m| (m, &paint)).collect();
    Surfaces::new(&list).unwrap()
}

#[test]
fn a_mesh_leaves_exactly_the_volume_in_front_of_it() {
    let camera = Camera::framing(&Blob.bounds(), 1.0);
    // A plane through the blob, facing the camera: behind it the volume
    // must not show, in front of it all of it.
    let centre = Vec3::new(0.0, 0.0, 0.0) + camera.forward * 0.15;
    let plane = square(centre, camera.right, camera.up, 3.0);
    let tf = tf();
    let size = 48;
    let mut s = RenderSettings::for_volume(&Blob, size, size);
    s.opacity_scale = 3.0;
    s.step = Some(0.002);
    s.early_termination = 1.0;
    s.surfaces = Some(surfaces(&[plane]));
    let image = render(&Blob, &camera, &tf, &s, &Control::new()).unwrap();
    let colour = Vec3::new(0.9, 0.5, 0.2);
    let mut worst = 0.0f32;
    for y in 0..size {
        for x in 0..size {
            let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5, size, size);
            // The plane along this ray, then a fine Riemann sum of the
            // emission–absorption integral up to it.
            let t_hit = (centre - ray.origin).dot(camera.forward) / ray.dir.dot(camera.forward);
            let span = Blob.bounds().clip_ray(&ray, Range1::new(0.0, t_hit));
            let (mut c, mut trans) = (Vec3::ZERO, 1.0f32);
            if !span.is_empty() {
                let n = 20_000;
                let dt = span.span() / n as f32;
                for i in 0..n {
                    let t = span.lo + (i as f32 + 0.5) * dt;
                    let v = Blob.sample(ray.at(t)).map_or(0.0, |s| s.value);
                    let a = 1.0 - (-tf.opacity(v) * s.opacity_scale * dt).exp();
                    c += tf.color(v) * (trans * a);
                    trans *= 1.0 - a;
                }
            }
            // The surface behind: headlight, ambient 0.2.
            let shade = 0.2 + 0.8 * camera.forward.dot(ray.dir).abs();
            let want = c + colour * (shade * trans);
            let got = image.pixels[(y * size + x) as usize];
            for k in 0..3 {
                worst = worst.max((got[k] - want[k]).abs());
            }
            assert!((got[3] - 1.0).abs() < 1e-6);
        }
    }
    assert!(worst < 2e-3, "largest difference {worst}");
}

fn ctx_settings(surfaces: Surfaces) -> RenderSettings {
    let mut s = RenderSettings::for_volume(&Blob, 8, 8);
    s.surfaces = Some(surfaces);
    s.ao = Some(AmbientOcclusion {
        rays: 64,
        distance: 10.0,
    });
    s
}

#[test]
fn occlusion_of_an_open_plane_is_0_and_inside_a_closed_box_is_1() {
    let tf = tf();
    let floor = square(
        Vec3::ZERO,
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        5.0,
    );
    let s = ctx_settings(surfaces(&[floor]));
    let ctx = Ctx::new(&tf, &s, false);
    let rng = |p: u64| sampling::PixelRng::new(1, p, 0);
    for p in 0..50 {
        let at = Vec3::new(p as f32 * 0.05 - 1.0, 0.3, 0.0);
        assert_eq!(
            occlusion(&Blob, at, Vec3::new(0.0, 0.0, 1.0), &ctx, &rng(p), 0),
            0.0
        );
    }
    // The six faces of [−1, 1]³.
    let e = [
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
    ];
    let faces: Vec<Mesh> = (0..3)
        .flat_map(|a| {
            [-1.0f32, 1.0].map(|side| square(e[a] * side, e[(a + 1) % 3], e[(a + 2) % 3], 1.0))
        })
        .collect();
    let s = ctx_settings(surfaces(&faces));
    let ctx = Ctx::new(&tf, &s, false);
    for p in 0..50 {
        let at = Vec3::new(0.3, -0.2, p as f32 * 0.03 - 0.75);
        let n = Vec3::new(0.3, 0.5, p as f32 - 25.0).normalized();
        assert_eq!(occlusion(&Blob, at, n, &ctx, &rng(p), 0), 1.0);
    }
}

#[test]
fn ambient_occlusion_only_darkens_and_is_deterministic() {
    let camera = Camera::framing(&Blob.bounds(), 1.0);
    let tf = tf();
    let floor = square(
        Vec3::ZERO + camera.forward * 0.5,
        camera.right,
        camera.up,
        3.0,
    );
    let mut s = RenderSettings::for_volume(&Blob, 40, 40);
    s.volume = false;
    s.iso = vec![0.5];
    s.surfaces = Some(surfaces(&[floor]));
    let plain = render(&Blob, &camera, &tf, &s, &Control::new()).unwrap();
    s.ao = Some(AmbientOcclusion {
        rays: 4,
        distance: 1.0,
    });
    let a = render(&Blob, &camera, &tf, &s, &Control::new()).unwrap();
    let b = render(&Blob, &camera, &tf, &s, &Control::new()).unwrap();
    assert_eq!(a.pixels, b.pixels);
    let mut darker = 0;
    for (p, q) in plain.pixels.iter().zip(&a.pixels) {
        for k in 0..3 {
            assert!(q[k] <= p[k] + 1e-6);
        }
        if q[0] < p[0] - 1e-3 {
            darker += 1;
        }
    }
    // The floor around the blob's iso-surface is occluded by it.
    assert!(darker > 20, "{darker} pixels darker");
}

#[test]
fn a_mirror_instance_of_a_mesh_is_the_mirrored_mesh() {
    // A box [0.5, 1.5]×[0, 1]×[0, 1] of 12 triangles, and its reflection
    // about x = 0 written out (winding flipped).
    let e = [
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
    ];
    let c = Vec3::new(1.0, 0.5, 0.5);
    let faces: Vec<Mesh> = (0..3)
        .flat_map(|a| {
            [-0.5f32, 0.5].map(|side| square(c + e[a] * side, e[(a + 1) % 3], e[(a + 2) % 3], 0.5))
        })
        .collect();
    let flipped: Vec<Mesh> = faces
        .iter()
        .map(|m| Mesh {
            positions: m.positions.iter().map(|p| [-p[0], p[1], p[2]]).collect(),
            triangles: m.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect(),
            fields: Vec::new(),
        })
        .collect();
    let tf = tf();
    let mut inst = RenderSettings::for_volume(&Blob, 8, 8);
    inst.surfaces = Some(surfaces(&faces));
    inst.mirrors = vec![voxless_core::Mirror {
        axis: 0,
        plane: 0.0,
    }];
    let mut explicit = RenderSettings::for_volume(&Blob, 8, 8);
    explicit.surfaces = Some(surfaces(&[faces, flipped].concat()));
    let (a, b) = (Ctx::new(&tf, &inst, false), Ctx::new(&tf, &explicit, false));
    let mut rng = voxless_core::SmallRng(9);
    let mut hits = 0;
    for _ in 0..2000 {
        let o = (rng.v() - Vec3::splat(0.5)) * 8.0;
        let target = Vec3::new(rng.f() * 3.0 - 1.5, rng.f(), rng.f());
        let ray = Ray::new(o, (target - o).normalized());
        let (p, q) = (meshes::nearest(&a, &ray), meshes::nearest(&b, &ray));
        assert_eq!(p.is_some(), q.is_some());
        if let (Some(p), Some(q)) = (p, q) {
            hits += 1;
            assert!((p.t - q.t).abs() <= 1e-5 * q.t.max(1.0), "{p:?} vs {q:?}");
            assert!((p.normal - q.normal).length() < 1e-4, "{p:?} vs {q:?}");
        }
        let t = Range1::new(0.0, 100.0);
        assert_eq!(
            meshes::blocked(&inst, &ray, t),
            meshes::blocked(&explicit, &ray, t)
        );
    }
    assert!(hits > 500, "{hits} hits");
}
