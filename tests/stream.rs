//! Projections streamed from `.npy` files and snapshots (`voxless::stream`) against the
//! in-memory path they replace: the same image to f64 summation order (the
//! streamed particles come in file order, the volume's in Hilbert order),
//! for periodic and open sets, on and off axis, several chunks; the scenes
//! that cannot stream say so; and `voxless project` takes the stream.

mod common;

use std::path::PathBuf;

use common::{Lcg, Scratch, bin};
use voxless::stream::Streamed;
use voxless::{
    BoxDesc, Control, KernelName, ParticlesDesc, ProjectionDesc, ProjectionView, SceneDesc,
};

/// `n` particles in a box of side `l` at `offset`, some outside it (to be
/// wrapped), with radii and weights; returns the scene reading them.
fn files(s: &Scratch, n: usize, l: f32, offset: f32, periodic: bool) -> SceneDesc {
    let mut rng = Lcg(11);
    let mut pos = Vec::with_capacity(3 * n);
    for i in 0..n {
        for _ in 0..3 {
            // A clump and a background; a few just outside the box.
            let u = if i % 3 == 0 {
                0.5 + 0.1 * (rng.f() - 0.5)
            } else {
                rng.f() * 1.02 - 0.01
            };
            pos.push(offset + l * u);
        }
    }
    let radii: Vec<f32> = (0..n)
        .map(|i| l * (0.004 + 0.02 * ((i * 7) % 13) as f32 / 13.0))
        .collect();
    let weights: Vec<f32> = (0..n).map(|i| 1.0 + (i % 5) as f32 * 0.25).collect();
    voxless_io::write_npy_f32(&s.path("p.npy"), &[n, 3], &pos).unwrap();
    voxless_io::write_npy_f32(&s.path("h.npy"), &[n], &radii).unwrap();
    voxless_io::write_npy_f32(&s.path("m.npy"), &[n], &weights).unwrap();
    SceneDesc {
        particles: Some(ParticlesDesc {
            file: Some(s.str("p.npy")),
            radii: Some(s.str("h.npy")),
            weights: Some(s.str("m.npy")),
            kernel: Some(KernelName::WendlandC2),
            periodic_box: periodic.then_some(BoxDesc::Corners([
                offset as f64,
                offset as f64,
                offset as f64,
                (offset + l) as f64,
                (offset + l) as f64,
                (offset + l) as f64,
            ])),
            wrap: periodic.then_some(true),
            ..Default::default()
        }),
        ..Default::default()
    }
}

/// The in-memory projection of `desc`.
fn in_memory(desc: &SceneDesc, projection: &ProjectionDesc, (w, h): (u32, u32)) -> Vec<f32> {
    let l = voxless::load(desc, std::path::Path::new("."), 0).unwrap();
    let view = ProjectionView::new(projection, &l.volume.bounds(), &l.frame).unwrap();
    view.project(&l.volume, w, h, &Control::new()).unwrap()
}

/// The views every comparison takes: on axis and off axis.
fn views() -> [ProjectionDesc; 2] {
    [
        ProjectionDesc {
            axis: Some(2),
            ..Default::default()
        },
        ProjectionDesc {
            normal: Some([1.0, 0.4, 0.3]),
            ..Default::default()
        },
    ]
}

/// `desc` (`n` particles) streamed through `projection` at 96×80, in at
/// least three chunks, against the in-memory path: f64 sums in another
/// order, rounded once to f32, within 1e-6 of the peak.
fn streams_as_in_memory(desc: &SceneDesc, projection: &ProjectionDesc, n: usize) -> Streamed {
    let size = (96, 80);
    let c = Control::new();
    let streamed = voxless::stream::project(desc, ".".as_ref(), 0, projection, size, &c)
        .unwrap()
        .expect("streams");
    assert_eq!(streamed.particles, n);
    assert!(streamed.chunks >= 3);
    let memory = in_memory(desc, projection, size);
    let peak = memory.iter().fold(0.0f32, |m, &v| m.max(v));
    assert!(peak > 0.0);
    let worst = streamed
        .column
        .iter()
        .zip(&memory)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    assert!(worst <= 1e-6 * peak, "{projection:?}: {worst} of {peak}");
    streamed
}

#[test]
fn streamed_projections_equal_the_in_memory_path() {
    let s = Scratch::new("stream-equal");
    // 150k particles: three chunks.
    let n = 150_000;
    for (periodic, offset) in [(true, -3.0f32), (false, 1000.0)] {
        let desc = files(&s, n, 8.0, offset, periodic);
        for projection in views() {
            streams_as_in_memory(&desc, &projection, n);
        }
    }
}

#[test]
fn scenes_that_need_every_particle_do_not_stream() {
    let s = Scratch::new("stream-none");
    let mut desc = files(&s, 2000, 1.0, 0.0, false);
    let p = desc.particles.as_mut().unwrap();
    p.radii = None;
    // No radius: the default comes from the spacing of all particles.
    let c = Control::new();
    let axis = ProjectionDesc::default();
    let none = voxless::stream::project(&desc, ".".as_ref(), 0, &axis, (8, 8), &c).unwrap();
    assert!(none.is_none());
    // Neighbour radii, and slabs.
    desc.particles.as_mut().unwrap().neighbours = Some(8);
    assert!(
        voxless::stream::project(&desc, ".".as_ref(), 0, &axis, (8, 8), &c)
            .unwrap()
            .is_none()
    );
    let mut desc = files(&s, 2000, 1.0, 0.0, false);
    let slab = ProjectionDesc {
        depth: Some(0.2),
        ..Default::default()
    };
    assert!(
        voxless::stream::project(&desc, ".".as_ref(), 0, &slab, (8, 8), &c)
            .unwrap()
            .is_none()
    );
    // Bad rows are named as the loader names them.
    let mut pos = vec![0.5f32; 30];
    pos[13] = f32::NAN;
    voxless_io::write_npy_f32(&s.path("nan.npy"), &[10, 3], &pos).unwrap();
    let p = desc.particles.as_mut().unwrap();
    p.file = Some(s.str("nan.npy"));
    p.radii = None;
    p.weights = None;
    p.radius = Some(0.1);
    let err = voxless::stream::project(&desc, ".".as_ref(), 0, &axis, (8, 8), &c)
        .err()
        .expect("a NaN position is an error")
        .to_string();
    assert!(
        err.contains("nan.npy") && err.contains("particle 4"),
        "{err}"
    );
}

#[test]
fn a_file_projection_streams_when_it_can_and_loads_when_it_cannot() {
    // What a front-end without a volume calls (Python's `voxless.project`).
    let s = Scratch::new("stream-file");
    let (n, size, c) = (70_000, (64, 48), Control::new());
    let axis = ProjectionDesc {
        axis: Some(0),
        ..Default::default()
    };
    let cpu = voxless::device::Device::cpu();
    let mut desc = files(&s, n, 2.0, 0.0, true);
    let file = |desc: &SceneDesc| {
        voxless::stream::project_file(desc, ".".as_ref(), 0, &axis, size, &cpu, &c)
            .unwrap()
            .unwrap()
    };
    let streamed = file(&desc);
    let direct = voxless::stream::project(&desc, ".".as_ref(), 0, &axis, size, &c)
        .unwrap()
        .unwrap();
    assert_eq!(streamed.chunks, Some(2));
    assert_eq!(streamed.column, direct.column);
    assert_eq!(streamed.mass, Some(direct.mass));
    assert_eq!(streamed.notes, direct.notes);
    // Radii from the spacing need every particle: loaded, as in memory.
    desc.particles.as_mut().unwrap().radii = None;
    let loaded = file(&desc);
    assert_eq!(loaded.chunks, None);
    assert_eq!(loaded.column, in_memory(&desc, &axis, size));
    let l = voxless::load(&desc, ".".as_ref(), 0).unwrap();
    let mass = l.volume.total_mass().unwrap() * l.frame.scale.powi(3);
    assert_eq!(loaded.mass, Some(mass));
    assert!(loaded.notes.iter().any(|n| n.contains("periodic box")));
    // A cancelled projection, streamed or loaded, is not an error of the
    // data.
    let token = voxless_core::CancelToken::new();
    token.cancel();
    let cancelled = Control::new().with_cancel(token);
    let streamable = files(&s, 1000, 2.0, 0.0, true);
    for desc in [&streamable, &desc] {
        assert!(
            voxless::stream::project_file(desc, ".".as_ref(), 0, &axis, size, &cpu, &cancelled)
                .unwrap()
                .is_err()
        );
    }
}

#[test]
fn the_cli_streams_npy_projections() {
    let s = Scratch::new("stream-cli");
    files(&s, 20_000, 4.0, 0.0, true);
    let run = |extra: &[&str], out: &str| {
        let o = std::process::Command::new(bin())
            .args([
                "project",
                "--particles",
                &s.str("p.npy"),
                "--radii",
                &s.str("h.npy"),
            ])
            .args([
                "--weights",
                &s.str("m.npy"),
                "--kernel",
                "wendland-c2",
                "--box",
                "4",
                "--wrap",
            ])
            .args(["--size", "64", "64", "-o", &s.str(out)])
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let log = run(&[], "a.npy");
    assert!(log.contains("streamed"), "{log}");
    // Saving the radii loads the volume: the in-memory path.
    let log = run(&["--save-radii", &s.str("r.npy")], "b.npy");
    assert!(!log.contains("streamed"), "{log}");
    let a = voxless_io::read_npy(&s.path("a.npy")).unwrap().data;
    let b = voxless_io::read_npy(&s.path("b.npy")).unwrap().data;
    let peak = b.iter().fold(0.0f64, |m, &v| m.max(v));
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() <= 1e-6 * peak, "{x} vs {y}");
    }
}

#[test]
fn a_set_wider_than_its_box_does_not_stream() {
    // With a box the span is taken while splatting; a set wider than the
    // box goes to the in-memory path, which refuses it naming the whole
    // set's span — also when every chunk alone fits the box.
    let s = Scratch::new("stream-wide");
    let n = 150_000;
    let pos: Vec<f32> = (0..n)
        .flat_map(|i| {
            // Chunk by chunk the particles move along x: 0.0–0.4, then
            // 0.3–0.7, then 0.6–0.95 (a box of 0.5 holds each chunk).
            let x = 0.3 * (i / 65_536) as f32 + 0.4 * (i % 1000) as f32 / 1000.0;
            [x.min(0.95), 0.2, 0.2]
        })
        .collect();
    voxless_io::write_npy_f32(&s.path("p.npy"), &[n, 3], &pos).unwrap();
    let mut desc = SceneDesc {
        particles: Some(ParticlesDesc {
            file: Some(s.str("p.npy")),
            radius: Some(0.01),
            kernel: Some(KernelName::WendlandC2),
            periodic_box: Some(BoxDesc::Corners([0.0, 0.0, 0.0, 0.5, 0.5, 0.5])),
            ..Default::default()
        }),
        ..Default::default()
    };
    let (axis, c) = (ProjectionDesc::default(), Control::new());
    let none = voxless::stream::project(&desc, ".".as_ref(), 0, &axis, (8, 8), &c).unwrap();
    assert!(none.is_none());
    let err = voxless::load(&desc, ".".as_ref(), 0)
        .err()
        .expect("too wide");
    assert!(err.to_string().contains("--wrap"), "{err}");
    // Asked to wrap, it streams.
    desc.particles.as_mut().unwrap().wrap = Some(true);
    let wrapped = voxless::stream::project(&desc, ".".as_ref(), 0, &axis, (8, 8), &c)
        .unwrap()
        .expect("wrapped into the box, it streams");
    assert!(wrapped.notes.iter().any(|n| n.contains("were wrapped in")));
}

/// Writes `n` gas particles in a periodic box of side `l` as a one-file
/// Gadget binary snapshot in format 1 (header, `POS`, `VEL`, `ID`, `MASS`,
/// `U`, `RHO`, `HSML`; little-endian), a few just outside the box (the
/// file's box is trusted: they are wrapped).
fn gadget_gas(path: &std::path::Path, n: usize, l: f32) {
    let mut rng = Lcg(5);
    let record = |out: &mut Vec<u8>, body: &[u8]| {
        out.extend((body.len() as u32).to_le_bytes());
        out.extend(body);
        out.extend((body.len() as u32).to_le_bytes());
    };
    let f32s = |v: &mut dyn Iterator<Item = f32>| v.flat_map(f32::to_le_bytes).collect::<Vec<_>>();
    let mut header = Vec::with_capacity(256);
    let mut npart = [0u32; 6];
    npart[0] = n as u32;
    header.extend(npart.iter().flat_map(|c| c.to_le_bytes()));
    header.extend([0.0f64; 6].iter().flat_map(|m| m.to_le_bytes())); // masses in MASS
    header.extend([1.0f64, 0.0].iter().flat_map(|t| t.to_le_bytes())); // time, redshift
    header.extend([0i32; 2].iter().flat_map(|f| f.to_le_bytes())); // sfr, feedback
    header.extend(npart.iter().flat_map(|c| c.to_le_bytes())); // npartTotal
    header.extend([0i32, 1].iter().flat_map(|f| f.to_le_bytes())); // cooling, files
    header.extend(
        [l as f64, 0.3, 0.7, 0.7]
            .iter()
            .flat_map(|v| v.to_le_bytes()),
    );
    header.resize(256, 0);
    let mut file = Vec::new();
    record(&mut file, &header);
    let pos: Vec<f32> = (0..3 * n)
        .map(|i| {
            let u = if (i / 3) % 3 == 0 {
                0.5 + 0.1 * (rng.f() - 0.5)
            } else {
                rng.f() * 1.02 - 0.01
            };
            l * u
        })
        .collect();
    record(&mut file, &f32s(&mut pos.iter().copied()));
    record(&mut file, &f32s(&mut (0..3 * n).map(|i| i as f32 * 1e-3)));
    record(
        &mut file,
        &(0..n as u32)
            .flat_map(|i| (i + 1).to_le_bytes())
            .collect::<Vec<_>>(),
    );
    record(
        &mut file,
        &f32s(&mut (0..n).map(|i| 1.0 + (i % 5) as f32 * 0.25)),
    );
    record(&mut file, &f32s(&mut (0..n).map(|_| 1.0)));
    record(&mut file, &f32s(&mut (0..n).map(|_| 1.0)));
    let hsml = (0..n).map(|i| l * (0.008 + 0.04 * ((i * 7) % 13) as f32 / 13.0));
    record(&mut file, &f32s(&mut hsml.into_iter()));
    std::fs::write(path, file).unwrap();
}

#[test]
fn snapshots_stream_by_rows_and_equal_the_in_memory_path() {
    let s = Scratch::new("stream-gadget");
    // 150k gas particles: three chunks, each read by its rows; the
    // snapshot's kernel (cubic spline, radii = HSML / 2), masses and box.
    let n = 150_000;
    gadget_gas(&s.path("snap_000"), n, 8.0);
    let desc = SceneDesc {
        particles: Some(ParticlesDesc {
            file: Some(s.str("snap_000")),
            ..Default::default()
        }),
        ..Default::default()
    };
    for projection in views() {
        let streamed = streams_as_in_memory(&desc, &projection, n);
        for said in ["cubic-spline", "periodic box (the file's)", "were wrapped"] {
            assert!(
                streamed.notes.iter().any(|m| m.contains(said)),
                "no '{said}' in {:?}",
                streamed.notes
            );
        }
        // Σ masses (1, 1.25, …, 2 in turn): the mass of every kernel.
        let mass: f64 = (0..n).map(|i| 1.0 + (i % 5) as f64 * 0.25).sum();
        assert!(
            (streamed.mass - mass).abs() <= 1e-6 * mass,
            "{}",
            streamed.mass
        );
    }
    // Dark matter without smoothing lengths takes radii from neighbours:
    // it does not stream.
    let dm = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/snapshots/gadget2_snap");
    let mut desc = desc;
    desc.particles.as_mut().unwrap().file = Some(dm.to_string_lossy().into_owned());
    let c = Control::new();
    let axis = ProjectionDesc::default();
    assert!(
        voxless::stream::project(&desc, ".".as_ref(), 0, &axis, (8, 8), &c)
            .unwrap()
            .is_none()
    );
}

#[test]
fn ranks_stream_shares_of_the_file_to_one_process_image() {
    // Each rank streams a share of the chunks; the images add up on rank
    // 0: one process's image to f32 rounding of the sums' order, the same
    // mass, notes and counts; the other ranks get no image.
    let s = Scratch::new("stream-ranks");
    let (n, size, c) = (70_000, (96, 80), Control::new());
    for (periodic, offset) in [(true, -3.0f32), (false, 1000.0)] {
        let desc = files(&s, n, 8.0, offset, periodic);
        for projection in views() {
            let one = voxless::stream::project(&desc, ".".as_ref(), 0, &projection, size, &c)
                .unwrap()
                .unwrap();
            let peak = one.column.iter().fold(0.0f32, |m, &v| m.max(v));
            for ranks in [2, 3] {
                let got = voxless::parallel::run_local(ranks, |comm| {
                    voxless::stream::project_ranks(
                        comm,
                        &desc,
                        ".".as_ref(),
                        0,
                        &projection,
                        size,
                        &c,
                    )
                    .unwrap()
                    .unwrap()
                });
                let reads: usize = got.iter().map(|g| g.read).sum();
                assert_eq!(reads, n);
                for g in &got[1..] {
                    assert!(g.column.is_empty());
                    assert_eq!((g.mass, &g.notes), (got[0].mass, &got[0].notes));
                }
                let root = &got[0];
                assert_eq!(root.chunks % ranks, 0);
                assert_eq!((root.particles, &root.notes), (n, &one.notes));
                assert!((root.mass / one.mass - 1.0).abs() < 1e-12);
                assert_eq!(root.view.camera, one.view.camera);
                let worst = root
                    .column
                    .iter()
                    .zip(&one.column)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0f32, f32::max);
                assert!(worst <= 1e-6 * peak, "{ranks} ranks: {worst} of {peak}");
            }
        }
    }
    // A bad row in the last rank's share is an error on every rank, named
    // on the rank that read it.
    let mut desc = files(&s, 70_000, 8.0, 0.0, false);
    let mut pos = vec![0.5f32; 3 * 70_000];
    pos[3 * 69_990 + 1] = f32::NAN;
    voxless_io::write_npy_f32(&s.path("nan.npy"), &[70_000, 3], &pos).unwrap();
    desc.particles.as_mut().unwrap().file = Some(s.str("nan.npy"));
    let axis = ProjectionDesc::default();
    let errs = voxless::parallel::run_local(3, |comm| {
        voxless::stream::project_ranks(comm, &desc, ".".as_ref(), 0, &axis, (8, 8), &c)
            .err()
            .expect("every rank fails")
            .to_string()
    });
    assert!(
        errs[2].contains("nan.npy") && errs[2].contains("particle 69990"),
        "{}",
        errs[2]
    );
    assert!(
        errs[0].contains("rank 2") && errs[0].contains("particle 69990"),
        "{}",
        errs[0]
    );
}
