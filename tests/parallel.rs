//! Data-parallel rendering without MPI: K ranks simulated as K threads of
//! one process (`run_local`) run the same decomposition, exchange and
//! compositing code as `mpirun -n K`, and must give the one-process result:
//! renders within 1/255 per channel, projections within 1e-5 of the image's
//! maximum, samples bit for bit — for particles, materials, AMR cells and
//! tessellations, with cameras looking along a rank boundary and particles
//! whose support spans three ranks.

mod common;

use std::path::Path;

use common::{Lcg, Scratch, write_values};
use voxless::parallel::{Comm, run_local};
use voxless::{AmrDesc, Camera, Control, Image, ParticlesDesc, Scene, SceneDesc, TetsDesc, Vec3};
use voxless::{DistributedScene, Purpose};

/// Renders `desc` with one process and with `ranks` simulated ranks; the
/// largest per-channel difference of the linear RGBA images.
fn render_difference(desc: &SceneDesc, base: &Path, ranks: usize) -> f32 {
    let one = Scene::open(desc, base, 0).unwrap();
    let want = one.render(&Control::new()).unwrap();
    let got = render_ranks(desc, base, ranks);
    assert_eq!((got.width, got.height), (want.width, want.height));
    max_difference(&want, &got)
}

fn render_ranks(desc: &SceneDesc, base: &Path, ranks: usize) -> Image {
    let mut out = run_local(ranks, |comm| {
        let s = DistributedScene::open(comm, desc, base, 0, Purpose::Render).unwrap();
        s.render(comm, &Control::new()).unwrap()
    });
    out.remove(0).expect("rank 0 has the image")
}

fn max_difference(a: &Image, b: &Image) -> f32 {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(p, q)| (0..4).map(move |c| (p[c] - q[c]).abs()))
        .fold(0.0, f32::max)
}

/// The one-process and the `ranks` projection down `axis` over the data's
/// bounds; the largest difference relative to the largest value.
fn project_difference(desc: &SceneDesc, base: &Path, ranks: usize, axis: usize) -> f64 {
    let one = Scene::open(desc, base, 0).unwrap();
    let camera = Camera::axis_projection(&one.volume.bounds(), axis).unwrap();
    let (w, h) = (one.view.settings.width, one.view.settings.height);
    let want = one.volume.project(&camera, w, h, &Control::new()).unwrap();
    let mut out = run_local(ranks, |comm| {
        let s = DistributedScene::open(comm, desc, base, 0, Purpose::Project).unwrap();
        assert_eq!(s.summary.bounds, one.volume.bounds(), "whole-data bounds");
        s.project(comm, &camera, w, h, &Control::new()).unwrap()
    });
    let got = out.remove(0).unwrap();
    let top = want.iter().fold(0.0f64, |m, &v| m.max(v.abs() as f64));
    assert!(top > 0.0, "an empty projection tests nothing");
    want.iter()
        .zip(&got)
        .map(|(&a, &b)| (a as f64 - b as f64).abs() / top)
        .fold(0.0, f64::max)
}

/// Samples at `points` with one process and with `ranks`: bit for bit.
fn assert_samples_equal(desc: &SceneDesc, base: &Path, ranks: usize, points: &[Vec3]) {
    let one = Scene::open(desc, base, 0).unwrap();
    let want = one.volume.sample_points(points, true);
    let mut out = run_local(ranks, |comm| {
        let s = DistributedScene::open(comm, desc, base, 0, Purpose::Render).unwrap();
        assert_eq!(s.sample_columns(true), one.volume.sample_columns(true));
        let mine = if comm.rank() == 0 { points } else { &[][..] };
        s.sample(comm, mine, true).unwrap()
    });
    let got = out.remove(0).unwrap();
    assert_eq!(want.len(), got.len());
    for (i, (a, b)) in want.iter().zip(&got).enumerate() {
        assert!(
            a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
            "{ranks} ranks, value {i}: {a} vs {b}"
        );
    }
}

fn image(desc: &mut SceneDesc, w: u32, h: u32, spp: u32) {
    desc.image.width = Some(w);
    desc.image.height = Some(h);
    desc.image.spp = Some(spp);
}

/// A clumpy particle set as .npy files: positions, radii, masses, speed.
fn particle_files(dir: &Scratch, n: usize) -> SceneDesc {
    let mut rng = Lcg(7);
    let mut pos = Vec::with_capacity(3 * n);
    let mut h = Vec::with_capacity(n);
    for i in 0..n {
        let c = [0.3, 0.7, 0.5][i % 3];
        let p = [
            c + 0.12 * rng.normal(),
            0.5 + 0.15 * rng.normal(),
            0.4 + 0.2 * rng.f(),
        ];
        pos.extend(p);
        h.push(0.02 + 0.03 * rng.f());
    }
    let mass: Vec<f32> = (0..n).map(|_| 0.5 + rng.f()).collect();
    let speed: Vec<f32> = (0..n).map(|i| (i % 17) as f32 + rng.f()).collect();
    voxless_io::write_npy_f32(&dir.path("pos.npy"), &[n, 3], &pos).unwrap();
    write_values(&dir.path("h.npy"), &h);
    write_values(&dir.path("m.npy"), &mass);
    write_values(&dir.path("speed.npy"), &speed);
    let mut desc = SceneDesc {
        particles: Some(ParticlesDesc {
            file: Some("pos.npy".into()),
            radii: Some("h.npy".into()),
            weights: Some("m.npy".into()),
            attribute: Some("speed.npy".into()),
            kernel: Some(voxless::KernelName::CubicSpline),
            ..Default::default()
        }),
        ..Default::default()
    };
    image(&mut desc, 67, 48, 2);
    desc
}

#[test]
fn particles_render_project_and_sample_as_one_process() {
    let dir = Scratch::new("parallel-particles");
    let mut desc = particle_files(&dir, 4000);
    desc.render.opacity_scale = Some(30.0);
    for ranks in 1..=4 {
        let d = render_difference(&desc, &dir.0, ranks);
        assert!(d <= 1.0 / 255.0, "{ranks} ranks: render differs by {d}");
        let p = project_difference(&desc, &dir.0, ranks, 2);
        assert!(p <= 1e-5, "{ranks} ranks: projection differs by {p:e}");
    }
    let mut rng = Lcg(3);
    let points: Vec<Vec3> = (0..300)
        .map(|_| Vec3::new(rng.f(), rng.f(), rng.f()) * 1.2 - Vec3::splat(0.1))
        .collect();
    for ranks in [2, 3] {
        assert_samples_equal(&desc, &dir.0, ranks, &points);
    }
}

#[test]
fn early_termination_in_a_back_box_is_exact() {
    // A dense medium: most rays stop inside some box behind another.
    let dir = Scratch::new("parallel-opaque");
    let mut desc = particle_files(&dir, 3000);
    desc.render.opacity_scale = Some(4000.0);
    desc.camera.eye = Some([-1.5, 0.5, 0.6]);
    desc.camera.look_at = Some([0.5, 0.5, 0.5]);
    let one = Scene::open(&desc, &dir.0, 0).unwrap();
    let img = one.render(&Control::new()).unwrap();
    let opaque = img.pixels.iter().filter(|p| p[3] >= 0.99).count();
    assert!(
        opaque > img.pixels.len() / 10,
        "only {opaque} opaque pixels"
    );
    for ranks in [2, 3, 4] {
        let d = render_difference(&desc, &dir.0, ranks);
        assert!(d <= 1.0 / 255.0, "{ranks} ranks: render differs by {d}");
    }
}

#[test]
fn a_camera_looking_along_a_rank_boundary_sees_no_seam() {
    let dir = Scratch::new("parallel-boundary");
    let mut desc = particle_files(&dir, 3000);
    desc.render.opacity_scale = Some(30.0);
    // The split plane of two ranks.
    let planes = run_local(2, |comm| {
        let s = DistributedScene::open(comm, &desc, &dir.0, 0, Purpose::Render).unwrap();
        (s.decomposition.box_of(0), s.decomposition.box_of(1))
    });
    let (a, b) = planes[0];
    let axis = (0..3)
        .find(|&k| a.max[k] == b.min[k] || b.max[k] == a.min[k])
        .unwrap();
    let at = if a.max[axis] == b.min[axis] {
        a.max[axis]
    } else {
        b.max[axis]
    };
    // Eye and look-at on the plane: the centre column of rays lies in it.
    let mut eye = [0.5f64, 0.5, 0.5];
    let mut look = [0.5f64, 0.5, 0.5];
    eye[axis] = at as f64;
    look[axis] = at as f64;
    let other = (axis + 1) % 3;
    eye[other] = -2.0;
    desc.camera.eye = Some(eye);
    desc.camera.look_at = Some(look);
    let mut up = [0.0f32; 3];
    up[axis] = 1.0;
    desc.camera.up = Some(up);
    for ranks in [2, 3] {
        let d = render_difference(&desc, &dir.0, ranks);
        assert!(d <= 1.0 / 255.0, "{ranks} ranks: render differs by {d}");
    }
    // Orthographic, straight along the plane.
    desc.camera.projection = Some(voxless::ProjectionName::Orthographic);
    let d = render_difference(&desc, &dir.0, 2);
    assert!(d <= 1.0 / 255.0, "orthographic: render differs by {d}");
}

#[test]
fn a_particle_whose_support_spans_three_ranks_is_held_by_each() {
    let dir = Scratch::new("parallel-big");
    let n = 2000;
    let mut rng = Lcg(11);
    // A row of small particles along x, and one big particle in the middle.
    let mut pos = Vec::new();
    for _ in 0..n {
        pos.extend([
            rng.f(),
            0.5 + 0.05 * rng.normal(),
            0.5 + 0.05 * rng.normal(),
        ]);
    }
    let mut h = vec![0.01; n];
    pos.extend([0.5, 0.5, 0.5]);
    h.push(0.3);
    voxless_io::write_npy_f32(&dir.path("pos.npy"), &[n + 1, 3], &pos).unwrap();
    write_values(&dir.path("h.npy"), &h);
    let mut desc = SceneDesc {
        particles: Some(ParticlesDesc {
            file: Some("pos.npy".into()),
            radii: Some("h.npy".into()),
            kernel: Some(voxless::KernelName::CubicSpline),
            ..Default::default()
        }),
        ..Default::default()
    };
    image(&mut desc, 64, 40, 2);
    desc.render.opacity_scale = Some(5.0);
    let held = run_local(3, |comm| {
        let s = DistributedScene::open(comm, &desc, &dir.0, 0, Purpose::Render).unwrap();
        let big = Vec3::new(0.5, 0.5, 0.5);
        match &s.part {
            Some(voxless::AnyVolume::Particles(v)) => v
                .positions()
                .iter()
                .zip(v.radii())
                .any(|(p, r)| *p == big && *r == 0.3),
            _ => false,
        }
    });
    assert_eq!(held, vec![true; 3], "the big particle reaches every box");
    let d = render_difference(&desc, &dir.0, 3);
    assert!(d <= 1.0 / 255.0, "render differs by {d}");
    let p = project_difference(&desc, &dir.0, 3, 1);
    assert!(p <= 1e-5, "projection differs by {p:e}");
    let points: Vec<Vec3> = (0..50)
        .map(|i| Vec3::new(0.2 + 0.012 * i as f32, 0.52, 0.47))
        .collect();
    assert_samples_equal(&desc, &dir.0, 3, &points);
}

#[test]
fn materials_render_as_one_process() {
    let dir = Scratch::new("parallel-materials");
    let mut rng = Lcg(5);
    let mut csv = String::from("x,y,z,type\n");
    for i in 0..3000 {
        let t = 1 + i % 2;
        let c = if t == 1 { 0.35 } else { 0.65 };
        csv.push_str(&format!(
            "{},{},{},{t}\n",
            c + 0.1 * rng.normal(),
            0.5 + 0.1 * rng.normal(),
            0.5 + 0.1 * rng.normal()
        ));
    }
    std::fs::write(dir.path("atoms.csv"), csv).unwrap();
    let toml = r#"
[particles]
file = "atoms.csv"
[[particles.materials]]
species = "1"
radius = 0.05
colormap = "inferno"
[[particles.materials]]
species = "2"
radius = 0.08
color = [0.2, 0.6, 1.0]
"#;
    let mut desc: SceneDesc = voxless::load::parse_scene(toml).unwrap();
    image(&mut desc, 60, 44, 2);
    desc.render.opacity_scale = Some(20.0);
    for ranks in [2, 3] {
        let d = render_difference(&desc, &dir.0, ranks);
        assert!(d <= 1.0 / 255.0, "{ranks} ranks: render differs by {d}");
    }
    let p = project_difference(&desc, &dir.0, 3, 0);
    assert!(p <= 1e-5, "projection differs by {p:e}");
    let points: Vec<Vec3> = (0..100)
        .map(|_| Vec3::new(rng.f(), rng.f(), rng.f()))
        .collect();
    assert_samples_equal(&desc, &dir.0, 3, &points);
}

/// An AMR blast: a 16³ coarse grid (level 1) refined to level 0 in a ball.
fn amr_files(dir: &Scratch) -> SceneDesc {
    let mut cells: Vec<[i32; 4]> = Vec::new();
    let inside = |x: i32, y: i32, z: i32| {
        let d = |v: i32| v as f32 + 1.0 - 16.0;
        d(x).powi(2) + d(y).powi(2) + d(z).powi(2) < 64.0
    };
    for z in (0..32).step_by(2) {
        for y in (0..32).step_by(2) {
            for x in (0..32).step_by(2) {
                if inside(x, y, z) {
                    for k in 0..8 {
                        cells.push([x + (k & 1), y + ((k >> 1) & 1), z + (k >> 2), 0]);
                    }
                } else {
                    cells.push([x, y, z, 1]);
                }
            }
        }
    }
    let density: Vec<f32> = cells
        .iter()
        .map(|c| {
            let r = ((c[0] - 16).pow(2) + (c[1] - 16).pow(2) + (c[2] - 16).pow(2)) as f32;
            1.0 + 2.0 * (-r / 60.0).exp() + 0.1 * ((c[0] * 7 + c[1] * 3) % 5) as f32
        })
        .collect();
    let energy: Vec<f32> = density.iter().map(|d| d * d).collect();
    let bytes: Vec<u8> = cells
        .iter()
        .flat_map(|c| c.iter().flat_map(|v| v.to_le_bytes()))
        .collect();
    std::fs::write(dir.path("blast.cells"), bytes).unwrap();
    let f32s = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    std::fs::write(dir.path("blast.density.scalars"), f32s(&density)).unwrap();
    std::fs::write(dir.path("blast.energy.scalars"), f32s(&energy)).unwrap();
    std::fs::write(
        dir.path("blast.meta.json"),
        r#"{"origin": [-1.0, 0.5, 2.0], "finest_cell_size": 0.0625}"#,
    )
    .unwrap();
    let mut desc = SceneDesc {
        amr: Some(AmrDesc {
            cells: Some("blast.cells".into()),
            scalars: Some(vec![
                "blast.density.scalars".into(),
                "blast.energy.scalars".into(),
            ]),
            color_field: Some("energy".into()),
            ..Default::default()
        }),
        ..Default::default()
    };
    image(&mut desc, 63, 50, 2);
    desc.render.opacity_scale = Some(3.0);
    desc
}

#[test]
fn amr_renders_projects_and_samples_as_one_process() {
    let dir = Scratch::new("parallel-amr");
    let desc = amr_files(&dir);
    for ranks in 1..=4 {
        let d = render_difference(&desc, &dir.0, ranks);
        assert!(d <= 1.0 / 255.0, "{ranks} ranks: render differs by {d}");
    }
    for ranks in [2, 3] {
        let p = project_difference(&desc, &dir.0, ranks, 1);
        assert!(p <= 1e-5, "{ranks} ranks: projection differs by {p:e}");
    }
    let mut rng = Lcg(9);
    let points: Vec<Vec3> = (0..300)
        .map(|_| Vec3::new(rng.f(), rng.f(), rng.f()) * 2.2 - Vec3::splat(0.1))
        .collect();
    assert_samples_equal(&desc, &dir.0, 3, &points);
}

#[test]
fn amr_octant_renders_projects_and_samples_as_one_process() {
    // Each box holds every cell whose tent reaches it; octant weights and
    // the cells that decide a vertex's rule reach no further, so samples
    // keep their bits, and each box integrates its part of a line exactly.
    let dir = Scratch::new("parallel-amr-octant");
    let mut desc = amr_files(&dir);
    if let Some(a) = desc.amr.as_mut() {
        a.reconstruction = Some(voxless::ReconstructionName::Octant);
    }
    for ranks in [2, 3] {
        let d = render_difference(&desc, &dir.0, ranks);
        assert!(d <= 1.0 / 255.0, "{ranks} ranks: render differs by {d}");
        let p = project_difference(&desc, &dir.0, ranks, 2);
        assert!(p <= 1e-5, "{ranks} ranks: projection differs by {p:e}");
    }
    let mut rng = Lcg(10);
    let points: Vec<Vec3> = (0..300)
        .map(|_| Vec3::new(rng.f(), rng.f(), rng.f()) * 2.2 - Vec3::splat(0.1))
        .collect();
    assert_samples_equal(&desc, &dir.0, 3, &points);
}

/// A 16³ Lagrangian grid folded by a sine wave (shell crossing: overlapping
/// streams), as .npy positions.
fn tets_files(dir: &Scratch) -> SceneDesc {
    let n = 16;
    let l = 10.0f32;
    let mut pos = Vec::with_capacity(3 * n * n * n);
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                let q = [i, j, k].map(|v| (v as f32 + 0.5) * l / n as f32);
                let s = |a: f32| 1.6 * (2.0 * std::f32::consts::PI * a / l).sin();
                let p = [
                    q[0] + s(q[0]),
                    q[1] + 0.5 * s(q[1] + q[0]),
                    q[2] + 0.3 * s(q[2]),
                ];
                pos.extend(p.map(|v| v.rem_euclid(l)));
            }
        }
    }
    voxless_io::write_npy_f32(&dir.path("lagrangian.npy"), &[n * n * n, 3], &pos).unwrap();
    let mut desc = SceneDesc {
        tets: Some(TetsDesc {
            file: Some("lagrangian.npy".into()),
            lagrangian: Some(n),
            box_size: Some(l),
            ..Default::default()
        }),
        ..Default::default()
    };
    image(&mut desc, 57, 44, 2);
    desc
}

#[test]
fn tessellations_render_project_and_sample_as_one_process() {
    let dir = Scratch::new("parallel-tets");
    let desc = tets_files(&dir);
    for ranks in 1..=4 {
        let d = render_difference(&desc, &dir.0, ranks);
        assert!(d <= 1.0 / 255.0, "{ranks} ranks: render differs by {d}");
        let p = project_difference(&desc, &dir.0, ranks, 2);
        assert!(p <= 1e-5, "{ranks} ranks: projection differs by {p:e}");
    }
    let mut rng = Lcg(13);
    let points: Vec<Vec3> = (0..200)
        .map(|_| Vec3::new(rng.f(), rng.f(), rng.f()) * 12.0 - Vec3::splat(1.0))
        .collect();
    assert_samples_equal(&desc, &dir.0, 3, &points);
}

#[test]
fn settings_one_box_cannot_honour_are_refused_by_name() {
    let dir = Scratch::new("parallel-refused");
    let mut desc = particle_files(&dir, 500);
    desc.render.iso = Some(vec![0.5]);
    let out = run_local(2, |comm| {
        DistributedScene::open(comm, &desc, &dir.0, 0, Purpose::Render)
            .err()
            .map(|e| e.to_string())
    });
    for e in out {
        let e = e.expect("iso-surfaces under two ranks are refused");
        assert!(e.contains("--iso"), "{e}");
    }
    // One rank renders them as one process does.
    assert!(
        run_local(1, |comm| {
            DistributedScene::open(comm, &desc, &dir.0, 0, Purpose::Render).is_ok()
        })[0]
    );
}

#[test]
fn a_file_error_on_one_rank_is_an_error_on_every_rank() {
    let dir = Scratch::new("parallel-errors");
    let mut desc = particle_files(&dir, 500);
    // Radii with one bad value, in the last rank's rows.
    let mut h = vec![0.02f32; 500];
    h[480] = -1.0;
    write_values(&dir.path("h.npy"), &h);
    desc.image.spp = Some(1);
    let out = run_local(3, |comm| {
        DistributedScene::open(comm, &desc, &dir.0, 0, Purpose::Render)
            .err()
            .map(|e| e.to_string())
    });
    for e in &out {
        let e = e.as_ref().expect("every rank fails");
        assert!(e.contains("h.npy") && e.contains("480"), "{e}");
    }
}

/// PySPH output read by hyperslab: each rank reads only its rows, and the
/// render equals one process's (the real dam break, when present).
#[cfg(feature = "hdf5")]
#[test]
fn hdf5_shares_render_as_one_process() {
    let Some(dir) = common::shared_data("sph-dam-break") else {
        return;
    };
    let mut desc = SceneDesc {
        particles: Some(ParticlesDesc {
            file: Some("dam_break_3d_01000.hdf5".into()),
            attribute: Some("speed".into()),
            ..Default::default()
        }),
        ..Default::default()
    };
    image(&mut desc, 64, 40, 1);
    let read = run_local(3, |comm| {
        DistributedScene::open(comm, &desc, &dir, 0, Purpose::Render)
            .unwrap()
            .counts
            .read
    });
    let one = Scene::open(&desc, &dir, 0).unwrap();
    let n = match &one.volume {
        voxless::AnyVolume::Particles(v) => v.len() as u64,
        _ => 0,
    };
    assert_eq!(
        read.iter().sum::<u64>(),
        n,
        "the shares cover the file once"
    );
    assert!(
        read.iter().all(|&r| r < n),
        "no rank reads every row: {read:?}"
    );
    let d = render_difference(&desc, &dir, 3);
    assert!(d <= 1.0 / 255.0, "render differs by {d}");
}

/// Particles far from the origin and tiny (a frame with an origin and a
/// scale ≠ 1), with every default left to the data: the ranks find the
/// one-process frame, default radius (the median nearest-neighbour spacing
/// over all rows), value range and opacity scale (the probe they sample
/// together), and render its image.
#[test]
fn whole_data_defaults_far_away_and_tiny_are_the_one_process_ones() {
    let dir = Scratch::new("parallel-defaults");
    let n = 5000;
    let mut rng = Lcg(17);
    let mut pos: Vec<f64> = Vec::with_capacity(3 * n);
    for i in 0..n {
        let c = [0.3, 0.7][i % 2];
        pos.extend([
            1e8 + 1e-6 * (c + 0.1 * rng.normal() as f64),
            -3e7 + 1e-6 * (0.5 + 0.1 * rng.normal() as f64),
            1e-6 * rng.f() as f64,
        ]);
    }
    // float64 positions, as the readers keep them.
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    let mut header = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({n}, 3), }}");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    bytes.extend((header.len() as u16).to_le_bytes());
    bytes.extend(header.as_bytes());
    bytes.extend(pos.iter().flat_map(|v| v.to_le_bytes()));
    std::fs::write(dir.path("pos.npy"), bytes).unwrap();
    let mut desc = SceneDesc {
        particles: Some(ParticlesDesc {
            file: Some("pos.npy".into()),
            ..Default::default()
        }),
        ..Default::default()
    };
    image(&mut desc, 60, 40, 2);
    let one = Scene::open(&desc, &dir.0, 0).unwrap();
    assert!(one.frame.scale != 1.0 && one.frame.origin != [0.0; 3]);
    let radius = |v: &voxless::AnyVolume| match v {
        voxless::AnyVolume::Particles(p) => p.settings().radius,
        _ => f32::NAN,
    };
    let want = radius(&one.volume);
    let got = run_local(3, |comm| {
        let s = DistributedScene::open(comm, &desc, &dir.0, 0, Purpose::Render).unwrap();
        (
            s.frame,
            s.part.as_ref().map(radius),
            s.view.settings.value_range,
            s.view.settings.opacity_scale,
            s.view.camera.eye,
        )
    });
    for (frame, r, vr, os, eye) in got {
        assert_eq!(frame, one.frame, "world frame");
        assert_eq!(r.map(f32::to_bits), Some(want.to_bits()), "default radius");
        let close = |a: f32, b: f32| (a - b).abs() <= 1e-5 * a.abs().max(b.abs());
        assert!(
            close(vr.lo, one.view.settings.value_range.lo)
                && close(vr.hi, one.view.settings.value_range.hi),
            "value range {vr:?} vs {:?}",
            one.view.settings.value_range
        );
        assert!(
            close(os, one.view.settings.opacity_scale),
            "opacity scale {os}"
        );
        assert_eq!(eye, one.view.camera.eye, "camera");
    }
    let d = render_difference(&desc, &dir.0, 3);
    assert!(d <= 1.0 / 255.0, "render differs by {d}");
}

/// A time series decomposed frame by frame: the defaults over the series
/// (value range, opacity, framing, attribute range) and each later frame in
/// the first frame's world frame and settings, as one process renders it.
#[test]
fn a_time_series_by_space_renders_as_one_process() {
    let dir = Scratch::new("parallel-series");
    for f in 0..3usize {
        let mut rng = Lcg(40 + f as u64);
        let n = 1500;
        let pos: Vec<f32> = (0..3 * n)
            .map(|i| 0.5 * rng.f() + 0.15 * f as f32 * (i % 3 == 0) as u8 as f32)
            .collect();
        let speed: Vec<f32> = (0..n).map(|i| (f * 10 + i % 7) as f32).collect();
        voxless_io::write_npy_f32(&dir.path(&format!("p_{f:02}.npy")), &[n, 3], &pos).unwrap();
        write_values(&dir.path(&format!("s_{f:02}.npy")), &speed);
    }
    let mut desc = SceneDesc {
        particles: Some(ParticlesDesc {
            file: Some("p_%02d.npy".into()),
            attribute: Some("s_%02d.npy".into()),
            ..Default::default()
        }),
        ..Default::default()
    };
    image(&mut desc, 48, 40, 1);
    let frames = [0, 1, 2];
    let (mut one, series) = Scene::open_series(&desc, &dir.0, &frames).unwrap();
    let mut want = Vec::new();
    for &f in &frames {
        if f > 0 {
            one.load_frame(&series, &dir.0, f).unwrap();
        }
        one.view.settings.frame = f as u32;
        want.push(one.render(&Control::new()).unwrap());
    }
    let mut got = run_local(3, |comm| {
        let (mut s, series) = DistributedScene::open_series(comm, &desc, &dir.0, &frames).unwrap();
        let mut images = Vec::new();
        for &f in &frames {
            if f > 0 {
                s.load_frame(comm, &series, &dir.0, f).unwrap();
            }
            s.view.settings.frame = f as u32;
            images.push(s.render(comm, &Control::new()).unwrap());
        }
        images
    });
    for (f, (a, b)) in want.iter().zip(got.remove(0)).enumerate() {
        let d = max_difference(a, &b.expect("rank 0 has the image"));
        assert!(d <= 1.0 / 255.0, "frame {f}: render differs by {d}");
    }
}

/// Off-axis projections (a normal, a north, a slab of given depth) of
/// particles, AMR cells and a tessellation over 3 ranks equal one process's
/// `ProjectionView::project`.
#[test]
fn off_axis_slab_projections_equal_one_process() {
    let dir = Scratch::new("parallel-off-axis");
    let particles = particle_files(&dir, 3000);
    let amr = amr_files(&dir);
    let tets = tets_files(&dir);
    for (what, desc, depth) in [
        ("particles", particles, 0.3),
        ("amr", amr, 0.8),
        ("tets", tets, 4.0),
    ] {
        let one = Scene::open(&desc, &dir.0, 0).unwrap();
        let projection = voxless::ProjectionDesc {
            normal: Some([0.3, -0.5, 0.8]),
            north: Some([0.0, 0.0, 1.0]),
            depth: Some(depth),
            ..Default::default()
        };
        let view =
            voxless::ProjectionView::new(&projection, &one.volume.bounds(), &one.frame).unwrap();
        let (w, h) = (one.view.settings.width, one.view.settings.height);
        let want = view.project(&one.volume, w, h, &Control::new()).unwrap();
        let mut got = run_local(3, |comm| {
            let s = DistributedScene::open(comm, &desc, &dir.0, 0, Purpose::Project).unwrap();
            let view =
                voxless::ProjectionView::new(&projection, &s.summary.bounds, &s.frame).unwrap();
            s.project_view(comm, &view, w, h, &Control::new()).unwrap()
        });
        let got = got.remove(0).unwrap();
        let top = want.iter().fold(0.0f64, |m, &v| m.max(v.abs() as f64));
        assert!(top > 0.0, "{what}: an empty projection tests nothing");
        let worst = want
            .iter()
            .zip(&got)
            .map(|(&a, &b)| (a as f64 - b as f64).abs() / top)
            .fold(0.0, f64::max);
        assert!(worst <= 1e-5, "{what}: projection differs by {worst:e}");
    }
}

/// Every SPH kernel (M5, M6, Wendland C2/C4/C6 beside the cubic spline)
/// renders within 1/255, projects within 1e-5 and samples bit for bit on
/// several ranks.
#[test]
fn every_sph_kernel_decomposes_as_one_process() {
    use voxless::KernelName::*;
    let dir = Scratch::new("parallel-kernels");
    let mut desc = particle_files(&dir, 2000);
    desc.render.opacity_scale = Some(30.0);
    let mut rng = Lcg(29);
    let points: Vec<Vec3> = (0..150)
        .map(|_| Vec3::new(rng.f(), rng.f(), rng.f()) * 1.2 - Vec3::splat(0.1))
        .collect();
    for kernel in [
        QuarticSpline,
        QuinticSpline,
        WendlandC2,
        WendlandC4,
        WendlandC6,
    ] {
        if let Some(p) = desc.particles.as_mut() {
            p.kernel = Some(kernel);
        }
        let d = render_difference(&desc, &dir.0, 3);
        assert!(d <= 1.0 / 255.0, "{kernel:?}: render differs by {d}");
        let p = project_difference(&desc, &dir.0, 3, 1);
        assert!(p <= 1e-5, "{kernel:?}: projection differs by {p:e}");
        assert_samples_equal(&desc, &dir.0, 2, &points);
    }
}

/// Without the `mpi` feature `tests/mpi_cli.rs` builds no test: a skip, or
/// a failure under `VOXLESS_REQUIRE_MPI=1` (CI's feature step).
#[cfg(not(feature = "mpi"))]
#[test]
fn mpi_tests_need_the_feature() {
    voxless_core::testing::prerequisite(
        false,
        "VOXLESS_REQUIRE_MPI",
        "a build with the mpi feature (cargo test --features mpi)",
    );
}
