//! Iso-surfaces never missed: a dense fan of rays at a sphere, the iso-
//! surface of a radial field on multi-level cells, where every ray that
//! passes well inside the sphere crosses the surface and must draw it —
//! whatever thin regions, gaps in the sampled intervals or level jumps lie
//! on its way.

use voxless_core::{Camera, Control, Projection, Simd, Vec3};
use voxless_render::{RenderSettings, render};
use voxless_transfer::{Colormap, OpacityMap, TransferFunction};

use super::tests::{cells_with, synthetic};
use super::*;

/// The sphere's centre and radius, in finest cell units.
const CENTRE: [f32; 3] = [29.3, 33.1, 31.7];
const RADIUS: f32 = 17.0;

fn radial(c: &[i32; 4]) -> f32 {
    let w = (1 << c[3]) as f32;
    let d = [0, 1, 2].map(|a| c[a] as f32 + 0.5 * w - CENTRE[a]);
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

#[test]
fn a_dense_fan_of_rays_never_misses_a_crossing() {
    let tf = TransferFunction::new(
        Colormap::preset("viridis").unwrap(),
        OpacityMap::preset("ramp-high").unwrap(),
    );
    for seed in [41, 42, 43] {
        let input = cells_with(synthetic(seed, false), radial);
        let (origin, h) = (input.origin, input.cell_size);
        let vol = AmrVolume::new(input, AmrSettings::default()).unwrap();
        let centre = origin + Vec3::from_array(CENTRE) * h;
        for (k, dir) in [
            Vec3::new(1.0, 0.3, 0.2),
            Vec3::new(-0.4, 1.0, 0.7),
            Vec3::new(0.1, -0.2, -1.0),
        ]
        .into_iter()
        .enumerate()
        {
            let dir = dir.normalized();
            let up = if dir.z.abs() > 0.9 {
                Vec3::new(0.0, 1.0, 0.0)
            } else {
                Vec3::new(0.0, 0.0, 1.0)
            };
            let projection = Projection::Perspective { fov_y_deg: 30.0 };
            let camera =
                Camera::look_at(centre - dir * (80.0 * h), centre, up, projection).unwrap();
            let (w, hgt) = (160, 160);
            for rate in [1.0, 0.7] {
                let mut settings = RenderSettings::for_volume(&vol, w, hgt);
                settings.volume = false;
                settings.iso = vec![RADIUS];
                settings.iso_opacity = 1.0;
                settings.sampling_rate = rate;
                settings.simd = Simd::Auto;
                settings.spp = 1;
                let image = render(&vol, &camera, &tf, &settings, &Control::new()).unwrap();
                // Rays passing within 0.8 R of the centre cross the sphere
                // at a steep angle: each must have drawn it.
                let mut missed = 0;
                for y in 0..hgt {
                    for x in 0..w {
                        let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5, w, hgt);
                        let to_c = centre - ray.origin;
                        let along = to_c.dot(ray.dir);
                        let miss = (to_c - ray.dir * along).length() / h;
                        if miss < 0.8 * RADIUS && image.pixels[(y * w + x) as usize][3] < 0.5 {
                            missed += 1;
                        }
                    }
                }
                assert!(
                    missed == 0,
                    "seed {seed}, view {k}, sampling rate {rate}: {missed} rays missed the surface"
                );
            }
        }
    }
}
