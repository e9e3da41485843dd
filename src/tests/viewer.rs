//! The library pieces interactive front-ends use: camera poses written back
//! into descriptions, saved scenes, particle scales, histograms and
//! progressive renders.

use std::path::Path;

use crate::pose::Pose;
use crate::progressive::{CoarseBudget, Stage, coarse_settings, render_progressive};
use crate::{
    AnyVolume, Control, ParticleArrays, ParticlesDesc, Scene, SceneDesc, Vec3, field_histogram,
    resolve, scene_toml, with_absolute_paths,
};

/// A small blob of particles with an attribute.
fn particles(desc: &ParticlesDesc) -> AnyVolume {
    let mut rng = crate::core::SmallRng(11);
    let positions: Vec<Vec3> = (0..600)
        .map(|_| Vec3::new(rng.f(), rng.f() * 0.6, rng.f() * 0.8))
        .collect();
    let attribute = Some(positions.iter().map(|p| p.x).collect());
    let arrays = ParticleArrays {
        positions,
        attribute,
        ..Default::default()
    };
    AnyVolume::from_particles(arrays, desc).unwrap().volume
}

fn small(desc: &mut SceneDesc) {
    desc.image.width = Some(48);
    desc.image.height = Some(32);
}

#[test]
fn a_written_pose_resolves_to_the_same_camera() {
    let v = particles(&ParticlesDesc {
        radius: Some(0.1),
        ..Default::default()
    });
    let mut desc = SceneDesc::default();
    small(&mut desc);
    desc.camera.orbit = Some(20.0);
    desc.camera.zoom = Some(1.5);
    let before = resolve(&v, &desc, Path::new(".")).unwrap().camera;
    // Writing the pose unchanged keeps the camera, bit for bit.
    let pose = Pose::of(&desc.camera, &v.bounds(), 1.5, &Default::default()).unwrap();
    let mut written = desc.clone();
    pose.write(&mut written.camera);
    assert_eq!(written.camera.orbit, None);
    assert_eq!(
        resolve(&v, &written, Path::new(".")).unwrap().camera,
        before
    );
    // An orbit keeps the distance to the look-at point and turns the view.
    let turned = pose.orbit(30.0, 10.0);
    let d = |p: &Pose| (p.eye - p.look_at).length();
    assert!((d(&turned) - d(&pose)).abs() < 1e-4 * d(&pose));
    let mut t = desc.clone();
    turned.write(&mut t.camera);
    let cam = resolve(&v, &t, Path::new(".")).unwrap().camera;
    assert_eq!(cam.eye, turned.eye);
    assert!(cam.forward.dot((turned.look_at - turned.eye).normalized()) > 0.99999);
    // Zoom divides the distance; pan moves eye and look-at point together.
    assert!((d(&pose.zoom(2.0)) - 0.5 * d(&pose)).abs() < 1e-4 * d(&pose));
    let panned = pose.pan(0.25, -0.1, 30.0);
    assert!(((panned.eye - panned.look_at) - (pose.eye - pose.look_at)).length() < 1e-4);
    assert!((panned.look_at - pose.look_at).length() > 0.0);
    // Orbiting over the pole stops short of it.
    let top = pose.orbit(0.0, 500.0);
    let up = (top.eye - top.look_at)
        .normalized()
        .dot(pose.up.normalized());
    assert!(up < 1.0 && up > 0.999);
}

#[test]
fn saved_scenes_read_back_equal_with_absolute_paths() {
    let v = particles(&ParticlesDesc {
        radius: Some(0.1),
        ..Default::default()
    });
    let mut desc = SceneDesc {
        particles: Some(ParticlesDesc {
            file: Some("data/pos.npy".into()),
            attribute: Some("temperature".into()),
            radii: Some("h.npy".into()),
            radius_scale: Some(1.37),
            ..Default::default()
        }),
        ..Default::default()
    };
    desc.transfer.opacity_points = Some(vec![[0.0, 0.1], [0.337, 0.71], [1.0, 1.0]]);
    desc.transfer.value_range = Some([0.1, 3.3]);
    desc.render.clip = Some([0.1, 0.2, 0.3, 0.9, 0.8, 0.7]);
    Pose::of(&desc.camera, &v.bounds(), 4.0 / 3.0, &Default::default())
        .unwrap()
        .orbit(33.3, -12.1)
        .write(&mut desc.camera);
    let saved = with_absolute_paths(&desc, Path::new("/some/where"));
    let p = saved.particles.as_ref().unwrap();
    assert_eq!(p.file.as_deref(), Some("/some/where/data/pos.npy"));
    assert_eq!(p.radii.as_deref(), Some("/some/where/h.npy"));
    // A column name is not a path.
    assert_eq!(p.attribute.as_deref(), Some("temperature"));
    let text = scene_toml(&saved).unwrap();
    assert_eq!(crate::load::parse_scene(&text).unwrap(), saved, "{text}");
}

#[test]
fn radius_scale_equals_the_scaled_radius_and_weight_scale_the_density() {
    let render = |p: ParticlesDesc| {
        let mut desc = SceneDesc::default();
        small(&mut desc);
        desc.transfer.value_range = Some([0.0, 5.0]);
        let v = particles(&p);
        let hi = v.value_range().hi;
        (
            Scene::with_volume(v, &desc, Path::new("."))
                .unwrap()
                .render(&Control::new())
                .unwrap(),
            hi,
        )
    };
    let base = ParticlesDesc {
        radius: Some(0.1),
        ..Default::default()
    };
    let (scaled, _) = render(ParticlesDesc {
        radius_scale: Some(2.0),
        ..base.clone()
    });
    let (direct, hi) = render(ParticlesDesc {
        radius: Some(0.2),
        ..base.clone()
    });
    assert_eq!(scaled, direct);
    let (_, hi2) = render(ParticlesDesc {
        radius: Some(0.2),
        weight_scale: Some(3.0),
        ..base.clone()
    });
    assert!((hi2 / hi - 3.0).abs() < 1e-3, "{hi} → {hi2}");
    let bad = AnyVolume::from_particles(
        ParticleArrays {
            positions: vec![Vec3::ZERO; 3],
            ..Default::default()
        },
        &ParticlesDesc {
            radius_scale: Some(-1.0),
            ..base
        },
    );
    let e = bad.err().unwrap().to_string();
    assert!(e.contains("radius_scale"), "{e}");
}

#[test]
fn histogram_counts_every_nonzero_sample_once() {
    let v = particles(&ParticlesDesc {
        radius: Some(0.15),
        ..Default::default()
    });
    let mut desc = SceneDesc::default();
    small(&mut desc);
    let mut st = resolve(&v, &desc, Path::new(".")).unwrap().settings;
    let h = field_histogram(&v, &st, 32, 24);
    let inside: u32 = h.counts.iter().sum();
    assert!(inside > 0);
    // Zero (empty space) is not counted; the range is the data's estimate,
    // which the field may exceed (counted above it).
    let seen = h.seen.unwrap();
    assert!(seen[0] > 0.0 && seen[0] <= seen[1]);
    // Half the range: the rest is counted above it, nothing is lost.
    st.value_range.hi = 0.5 * (st.value_range.lo + st.value_range.hi);
    let half = field_histogram(&v, &st, 32, 24);
    assert_eq!(
        half.counts.iter().sum::<u32>() + half.above + half.below,
        inside + h.above + h.below
    );
    assert!(half.above > 0);
}

#[test]
fn progressive_ends_on_the_render_and_the_coarse_image_is_small() {
    let v = particles(&ParticlesDesc {
        radius: Some(0.1),
        ..Default::default()
    });
    let mut desc = SceneDesc::default();
    small(&mut desc);
    desc.image.spp = Some(3);
    let r = resolve(&v, &desc, Path::new(".")).unwrap();
    let coarse = coarse_settings(&r.settings, 200);
    assert!(coarse.width * coarse.height <= 200 && coarse.spp == 1);
    assert!((coarse.width as f32 / coarse.height as f32 - 1.5).abs() < 0.2);
    let mut stages = Vec::new();
    let mut budget = CoarseBudget::new(0.05, 16);
    let film = render_progressive(
        &v,
        &r.camera,
        &r.tf,
        &r.settings,
        Some(200),
        Some(&mut budget),
        &Control::new(),
        &mut |stage, film, at| {
            stages.push((stage, film.passes(), at.width));
            true
        },
    )
    .unwrap();
    assert_eq!(stages[0].0, Stage::Coarse);
    assert_eq!(stages.len(), 4);
    assert!(stages[3].0.is_converged());
    let direct = v
        .render(&r.camera, &r.tf, &r.settings, &Control::new())
        .unwrap();
    assert_eq!(film.resolve(), direct);
    // The budget follows the measured speed, within its bounds.
    let p = budget.pixels(48 * 32);
    assert!((16..=48 * 32 / 4).contains(&p));
}

/// A 32³ lattice in a box of 32, displaced by a wave (so that the density
/// varies and coarser levels of detail differ from the full mesh).
fn tessellation(desc: &crate::TetsDesc) -> AnyVolume {
    let n = 32;
    let positions: Vec<Vec3> = (0..n * n * n)
        .map(|c| {
            let (i, j, k) = ((c / (n * n)) as f32, ((c / n) % n) as f32, (c % n) as f32);
            let wave = 0.3 * (i * std::f32::consts::TAU / n as f32).sin();
            Vec3::new(i + 0.5 + wave, j + 0.5, k + 0.5)
        })
        .collect();
    AnyVolume::from_tessellation(positions, n, n as f32, desc)
        .unwrap()
        .volume
}

#[test]
fn coarse_images_of_tessellations_draw_from_their_levels_of_detail() {
    let mut desc = SceneDesc::default();
    small(&mut desc);
    let plain = tessellation(&Default::default());
    let levels = tessellation(&crate::TetsDesc {
        lod_levels: Some(3),
        ..Default::default()
    });
    let r = resolve(&plain, &desc, Path::new(".")).unwrap();
    let coarse = coarse_settings(&r.settings, 24 * 16);
    // 24×16: blocks smaller than 24 pixels use coarser levels.
    assert_eq!((coarse.width, coarse.height), (24, 16));
    assert_eq!(coarse.lod_pixels, Some(24.0));
    let render = |v: &AnyVolume, s| v.render(&r.camera, &r.tf, s, &Control::new()).unwrap();
    // Levels of detail unused leave the image as it was.
    assert_eq!(render(&levels, &r.settings), render(&plain, &r.settings));
    // Without levels the coarse settings draw the full mesh; with them the
    // coarse image draws coarser levels: close, not equal.
    let full = render(&plain, &coarse);
    let lod = render(&levels, &coarse);
    let diff: f64 = (full.pixels.iter().zip(&lod.pixels))
        .map(|(a, b)| ((a[0] - b[0]).abs() + (a[3] - b[3]).abs()) as f64)
        .sum::<f64>()
        / full.pixels.len() as f64;
    assert!(diff > 0.0 && diff < 0.05, "mean |Δ| {diff}");
    // The render's threshold is the volume's own `lod_pixels` (`--lod`)
    // through a different door: the same image.
    let own = tessellation(&crate::TetsDesc {
        lod_pixels: Some(24.0),
        ..Default::default()
    });
    let own_settings = crate::RenderSettings {
        lod_pixels: None,
        ..coarse.clone()
    };
    assert_eq!(render(&own, &own_settings), lod);
}

#[test]
fn tessellation_histograms_sweep_the_cells_and_equal_the_indexed_ones() {
    use voxless_tets::{TetSettings, TetVolume, testing::folded_sheet};
    let tets = || {
        let v = TetVolume::new(&folded_sheet(12, 2), &TetSettings::default(), 0).unwrap();
        AnyVolume::Tets(Box::new(v))
    };
    let (swept, indexed) = (tets(), tets());
    let mut desc = SceneDesc::default();
    small(&mut desc);
    let st = resolve(&indexed, &desc, Path::new(".")).unwrap().settings;
    let AnyVolume::Tets(v) = &indexed else {
        unreachable!()
    };
    v.density_and_streams(Vec3::splat(0.5));
    assert!(v.has_index());
    let a = field_histogram(&swept, &st, 32, 24);
    let AnyVolume::Tets(v) = &swept else {
        unreachable!()
    };
    assert!(!v.has_index(), "a histogram builds no point index");
    assert!(a.counts.iter().sum::<u32>() > 1000, "{a:?}");
    assert_eq!(a, field_histogram(&indexed, &st, 32, 24));
}
