//! Projection views (`voxless::projection`): orientation (yt's default north,
//! off-axis along an axis = the axis projection), mass conservation off
//! axis, slabs against the closed-form chord, pixel geometry and errors.

mod common;

use voxless::projection::default_north;
use voxless::{
    AmrArrays, AmrDesc, AnyVolume, Control, KernelName, Loaded, ParticleArrays, ParticlesDesc,
    ProjectionDesc, ProjectionView,
};

fn close(a: [f64; 3], b: [f64; 3]) -> bool {
    (0..3).all(|i| (a[i] - b[i]).abs() < 1e-12)
}

/// A blob of cubic-spline particles with masses, around `offset`.
fn blob(offset: [f64; 3]) -> Loaded {
    blob_with(offset, KernelName::CubicSpline)
}

/// [`blob`] with another kernel.
fn blob_with(offset: [f64; 3], kernel: KernelName) -> Loaded {
    let mut rng = voxless::core::SmallRng(3);
    let pos: Vec<[f64; 3]> = (0..400)
        .map(|_| {
            let p = [rng.f(), rng.f() * 0.6, rng.f() * 0.3];
            [
                p[0] as f64 + offset[0],
                p[1] as f64 + offset[1],
                p[2] as f64 + offset[2],
            ]
        })
        .collect();
    let mut arrays = ParticleArrays::from_f64(&pos);
    arrays.weights = Some((0..400).map(|i| 1.0 + (i % 7) as f32 * 0.1).collect());
    arrays.radii = Some(vec![0.05; 400]);
    let desc = ParticlesDesc {
        kernel: Some(kernel),
        ..Default::default()
    };
    AnyVolume::from_particles(arrays, &desc).unwrap()
}

/// Every SPH kernel's projection, along an axis and off axis, conserves the
/// particles' mass: Σ pixels × pixel area = Σ masses to 1e-4 (the default
/// view's bounds hold every support), compared with the masses themselves,
/// not with the volume's own `total_mass`.
#[test]
fn every_sph_kernel_projection_conserves_mass() {
    let masses: f64 = (0..400).map(|i| (1.0 + (i % 7) as f32 * 0.1) as f64).sum();
    for kernel in [
        KernelName::CubicSpline,
        KernelName::QuarticSpline,
        KernelName::QuinticSpline,
        KernelName::WendlandC2,
        KernelName::WendlandC4,
        KernelName::WendlandC6,
    ] {
        let l = blob_with([0.0; 3], kernel);
        let (w, h) = (160, 120);
        for desc in [
            ProjectionDesc {
                axis: Some(2),
                ..Default::default()
            },
            ProjectionDesc {
                normal: Some([1.0, 0.5, 0.7]),
                ..Default::default()
            },
        ] {
            let (column, view) = project(&l, &desc, w, h);
            let m = mass(&column, &view, w, h);
            assert!(
                (m - masses).abs() <= 1e-4 * masses,
                "{kernel}: {m} vs Σm = {masses} ({desc:?})"
            );
        }
    }
}

fn project(l: &Loaded, desc: &ProjectionDesc, w: u32, h: u32) -> (Vec<f32>, ProjectionView) {
    let view = ProjectionView::new(desc, &l.volume.bounds(), &l.frame).unwrap();
    let column = view.project(&l.volume, w, h, &Control::new()).unwrap();
    (column, view)
}

fn mass(column: &[f32], view: &ProjectionView, w: u32, h: u32) -> f64 {
    column.iter().map(|&c| c as f64).sum::<f64>() * view.pixel_area(w, h)
}

#[test]
fn default_north_is_yts_rule() {
    // Along x the image axes are (y, z), along z (x, y): the axis
    // projections' orientation; along y, (z, x).
    assert!(close(default_north([1.0, 0.0, 0.0]), [0.0, 0.0, 1.0]));
    assert!(close(default_north([0.0, 0.0, 1.0]), [0.0, 1.0, 0.0]));
    assert!(close(default_north([0.0, 1.0, 0.0]), [1.0, 0.0, 0.0]));
    // Off axis: perpendicular to the normal.
    let n = [1.0, 0.5, 0.7];
    let north = default_north(n);
    assert!((north[0] * n[0] + north[1] * n[1] + north[2] * n[2]).abs() < 1e-12);
}

#[test]
fn off_axis_along_an_axis_equals_the_axis_projection() {
    let l = blob([0.0; 3]);
    let (w, h) = (48, 32);
    for (axis, normal) in [(0, [1.0, 0.0, 0.0]), (2, [0.0, 0.0, 1.0])] {
        let (a, va) = project(
            &l,
            &ProjectionDesc {
                axis: Some(axis),
                ..Default::default()
            },
            w,
            h,
        );
        let (b, vb) = project(
            &l,
            &ProjectionDesc {
                normal: Some(normal),
                center: Some(va.center),
                width: Some(va.width),
                ..Default::default()
            },
            w,
            h,
        );
        assert!(
            close(va.right, vb.right) && close(va.up, vb.up),
            "axis {axis}"
        );
        let peak = a.iter().cloned().fold(0.0f32, f32::max);
        let worst = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f32::max);
        assert!(worst <= 1e-5 * peak, "axis {axis}: {worst} vs peak {peak}");
    }
}

#[test]
fn off_axis_projections_conserve_mass_far_from_the_origin() {
    for offset in [[0.0; 3], [1e9, -3e8, 2e9]] {
        let l = blob(offset);
        let exact = l.volume.total_mass().unwrap();
        let (w, h) = (160, 120);
        let (column, view) = project(
            &l,
            &ProjectionDesc {
                normal: Some([1.0, 0.5, 0.7]),
                ..Default::default()
            },
            w,
            h,
        );
        let m = mass(&column, &view, w, h);
        assert!(
            (m - exact).abs() <= 1e-4 * exact,
            "{m} vs {exact} at {offset:?}"
        );
    }
}

#[test]
fn a_slab_holds_the_chord_inside_it() {
    // One particle at the origin: a slab through half of it holds half its
    // column; a slab covering it holds all.
    let mut arrays = ParticleArrays::from_f64(&[[0.0; 3]]);
    arrays.radii = Some(vec![1.0]);
    arrays.weights = Some(vec![2.0]);
    let desc = ParticlesDesc {
        kernel: Some(KernelName::CubicSpline),
        ..Default::default()
    };
    let l = AnyVolume::from_particles(arrays, &desc).unwrap();
    let at = |center: [f64; 3], depth: Option<f64>| {
        let d = ProjectionDesc {
            normal: Some([0.0, 0.0, 1.0]),
            center: Some(center),
            width: Some([0.01, 0.01]),
            depth,
            ..Default::default()
        };
        project(&l, &d, 1, 1).0[0] as f64
    };
    let whole = at([0.0; 3], None);
    assert!(whole > 0.0);
    assert!((at([0.0; 3], Some(10.0)) - whole).abs() <= 1e-6 * whole);
    // The slab [0, 4] along z: half the symmetric kernel.
    let half = at([0.0, 0.0, 2.0], Some(4.0));
    assert!(
        (half - 0.5 * whole).abs() <= 1e-5 * whole,
        "{half} vs {whole}"
    );
}

#[test]
fn pixel_centres_and_areas() {
    let l = blob([0.0; 3]);
    let view = ProjectionView::new(
        &ProjectionDesc {
            bounds: Some([0.0, 0.0, 0.0, 4.0, 2.0, 1.0]),
            ..Default::default()
        },
        &l.volume.bounds(),
        &l.frame,
    )
    .unwrap();
    assert_eq!(view.pixel_area(4, 2), 1.0);
    // Row 0 at the top: the pixel (0, 0) of a 4×2 image is at (0.5, 1.5).
    assert!(close(view.pixel_center(0, 0, 4, 2), [0.5, 1.5, 0.5]));
    assert!(close(view.pixel_center(1, 3, 4, 2), [3.5, 0.5, 0.5]));
    // The integral on eight running sums against one sum in order, for
    // counts past and between multiples of eight.
    let mut rng = voxless_core::SmallRng(5);
    for n in [0, 1, 7, 8, 13, 1003] {
        let column: Vec<f32> = (0..n).map(|_| 1e3 * rng.f() + 1e-3).collect();
        let want = column.iter().map(|&c| c as f64).sum::<f64>() * view.pixel_area(4, 2);
        let got = view.integral(&column, 4, 2);
        assert!(
            (got - want).abs() <= 1e-12 * want.max(1.0),
            "{n}: {got} vs {want}"
        );
    }
}

#[test]
fn bad_projections_are_errors_naming_the_setting() {
    let l = blob([0.0; 3]);
    let field = |d: ProjectionDesc| match ProjectionView::new(&d, &l.volume.bounds(), &l.frame) {
        Err(voxless::SceneError::Setting { field, .. }) => field,
        other => panic!("expected a setting error, got {:?}", other.map(|v| v.width)),
    };
    let n = Some([0.0, 0.0, 1.0]);
    let cases = [
        (
            ProjectionDesc {
                axis: Some(2),
                normal: n,
                ..Default::default()
            },
            "normal",
        ),
        (
            ProjectionDesc {
                axis: Some(3),
                ..Default::default()
            },
            "axis",
        ),
        (
            ProjectionDesc {
                normal: Some([0.0; 3]),
                ..Default::default()
            },
            "normal",
        ),
        (
            ProjectionDesc {
                normal: Some([f64::NAN, 0.0, 1.0]),
                ..Default::default()
            },
            "normal",
        ),
        (
            ProjectionDesc {
                normal: n,
                north: n,
                ..Default::default()
            },
            "north",
        ),
        (
            ProjectionDesc {
                north: n,
                ..Default::default()
            },
            "north",
        ),
        (
            ProjectionDesc {
                width: Some([1.0, -1.0]),
                ..Default::default()
            },
            "width",
        ),
        (
            ProjectionDesc {
                center: Some([0.0, f64::INFINITY, 0.0]),
                ..Default::default()
            },
            "center",
        ),
        (
            ProjectionDesc {
                depth: Some(0.0),
                ..Default::default()
            },
            "depth",
        ),
        (
            ProjectionDesc {
                bounds: Some([1.0, 0.0, 0.0, 0.0, 1.0, 1.0]),
                ..Default::default()
            },
            "bounds",
        ),
        (
            ProjectionDesc {
                bounds: Some([0.0, 0.0, 0.0, 0.0, 1.0, 1.0]),
                ..Default::default()
            },
            "bounds",
        ),
    ];
    for (desc, want) in cases {
        assert_eq!(field(desc.clone()), want, "{desc:?}");
    }
}

#[test]
fn amr_slab_projection_matches_the_whole_line_when_it_covers_the_data() {
    // Two cells side by side along z; nearest reconstruction (exact chords).
    let amr = AnyVolume::from_amr(
        AmrArrays {
            cells: vec![[0, 0, 0, 0], [0, 0, 1, 0]],
            fields: vec![("rho".into(), vec![1.0, 3.0])],
            origin: [0.0; 3],
            cell_size: 1.0,
        },
        &AmrDesc {
            reconstruction: Some(voxless::ReconstructionName::Nearest),
            ..Default::default()
        },
    )
    .unwrap();
    // Pixel centres inside the cells (a line along a cell face may miss both).
    let d = |depth| ProjectionDesc {
        axis: Some(2),
        center: Some([0.5, 0.5, 1.0]),
        width: Some([1.0, 1.0]),
        depth,
        ..Default::default()
    };
    let whole = project(&amr, &d(None), 2, 2).0;
    let slab = project(&amr, &d(Some(5.0)), 2, 2).0;
    for (a, b) in whole.iter().zip(&slab) {
        assert!((a - 4.0).abs() < 1e-4 && (b - 4.0).abs() < 1e-4, "{a} {b}");
    }
    // Only the lower cell: a slab [0, 1] around z = 0.5.
    let lower = project(
        &amr,
        &ProjectionDesc {
            axis: Some(2),
            center: Some([0.5, 0.5, 0.5]),
            width: Some([1.0, 1.0]),
            depth: Some(1.0),
            ..Default::default()
        },
        2,
        2,
    )
    .0;
    assert!(lower.iter().all(|v| (v - 1.0).abs() < 1e-4), "{lower:?}");
}

/// The particles' splatting path against one line integral per pixel, for
/// every kernel, along an axis and off axis, with pixels smaller and larger
/// than the particles; and the same bits for any thread count.
#[test]
fn particle_splatting_equals_the_per_pixel_path() {
    let mut rng = voxless::core::SmallRng(11);
    let pos: Vec<[f64; 3]> = (0..3000)
        .map(|_| [rng.f() as f64, rng.f() as f64 * 0.5, rng.f() as f64 * 0.25])
        .collect();
    let radii: Vec<f32> = (0..3000).map(|_| 0.004 + 0.05 * rng.f()).collect();
    for kernel in KernelName::ALL.iter().copied() {
        let mut arrays = ParticleArrays::from_f64(&pos);
        arrays.radii = Some(radii.clone());
        arrays.weights = Some((0..3000).map(|i| (i % 5) as f32 * 0.5).collect());
        let desc = ParticlesDesc {
            kernel: Some(kernel),
            ..Default::default()
        };
        let l = AnyVolume::from_particles(arrays, &desc).unwrap();
        let AnyVolume::Particles(v) = &l.volume else {
            panic!("particles expected")
        };
        for (desc, w, h) in [
            (ProjectionDesc::default(), 97, 61),
            (
                ProjectionDesc {
                    normal: Some([1.0, 0.5, 0.7]),
                    ..Default::default()
                },
                40,
                300,
            ),
        ] {
            let view = ProjectionView::new(&desc, &l.volume.bounds(), &l.frame).unwrap();
            let c = Control::new();
            let fast = voxless::render::project(&**v, &view.camera, w, h, &c).unwrap();
            let slow = voxless::render::project_per_pixel(&**v, &view.camera, w, h, &c).unwrap();
            let peak = slow.iter().cloned().fold(0.0f32, f32::max);
            assert!(peak > 0.0);
            let worst = fast
                .iter()
                .zip(&slow)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f32::max);
            // The per-pixel path's rays are f32: origins and direction
            // rounded to ~1e-7 of the eye's distance (the fast path measures
            // distances in f64 in the image plane). On the steep flanks of
            // the smallest particles (support 0.008) that is ~1e-5 of the
            // peak; the sums agree far closer.
            assert!(
                worst <= 1e-4 * peak,
                "{kernel:?} {w}×{h}: {worst} vs {peak}"
            );
            let total = |v: &[f32]| v.iter().map(|&x| x as f64).sum::<f64>();
            let (tf, ts) = (total(&fast), total(&slow));
            assert!((tf - ts).abs() <= 1e-6 * ts, "{kernel:?}: Σ {tf} vs {ts}");
            let in_pool = |n| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .unwrap()
                    .install(|| voxless::render::project(&**v, &view.camera, w, h, &c).unwrap())
            };
            assert_eq!(
                in_pool(1),
                in_pool(3),
                "{kernel:?}: thread count changed the bits"
            );
        }
    }
}

#[test]
fn projection_image_sizes_are_the_resolved_ones() {
    let l = blob([0.0; 3]);
    for (w, h) in [(None, None), (Some(64), None), (Some(3), Some(5))] {
        let mut desc = voxless::SceneDesc::default();
        desc.image.width = w;
        desc.image.height = h;
        let r = voxless::resolve_in(&l.volume, &l.frame, &desc, ".".as_ref()).unwrap();
        let size = voxless::projection::image_size(&desc.image).unwrap();
        assert_eq!(size, (r.settings.width, r.settings.height));
    }
    let bad = voxless::ImageDesc {
        width: Some(0),
        ..Default::default()
    };
    assert!(voxless::projection::image_size(&bad).is_err());
}

/// Data of any scale (a rescaled frame): the same image in world units —
/// a column density scales as mass / length² — and Σ pixels × pixel area
/// the world mass, along an axis, off axis and through a slab.
#[test]
fn projections_do_not_depend_on_the_units() {
    let make = |s: f64| {
        let mut rng = voxless::core::SmallRng(5);
        let pos: Vec<[f64; 3]> = (0..300)
            .map(|_| {
                [
                    rng.f() as f64 * s,
                    rng.f() as f64 * 0.5 * s,
                    rng.f() as f64 * 0.3 * s,
                ]
            })
            .collect();
        let mut arrays = ParticleArrays::from_f64(&pos);
        arrays.radii = Some(vec![(0.06 * s) as f32; 300]);
        arrays.weights = Some(vec![1.0; 300]);
        let desc = ParticlesDesc {
            kernel: Some(KernelName::CubicSpline),
            ..Default::default()
        };
        AnyVolume::from_particles(arrays, &desc).unwrap()
    };
    let one = make(1.0);
    for s in [1e-9, 1e12] {
        let scaled = make(s);
        assert!(scaled.frame.scale != 1.0, "{s}: the frame should rescale");
        for desc in [
            ProjectionDesc::default(),
            ProjectionDesc {
                normal: Some([1.0, 0.5, 0.7]),
                ..Default::default()
            },
            ProjectionDesc {
                axis: Some(0),
                center: Some([0.5, 0.25, 0.15]),
                depth: Some(0.1),
                ..Default::default()
            },
        ] {
            let at = |d: &ProjectionDesc, k: f64| ProjectionDesc {
                center: d.center.map(|c| c.map(|v| v * k)),
                depth: d.depth.map(|v| v * k),
                ..d.clone()
            };
            let (a, va) = project(&one, &desc, 40, 30);
            let (b, vb) = project(&scaled, &at(&desc, s), 40, 30);
            let peak = a.iter().cloned().fold(0.0f32, f32::max) as f64;
            for (x, y) in a.iter().zip(&b) {
                let y = *y as f64 * s * s;
                assert!(
                    (*x as f64 - y).abs() <= 1e-4 * peak,
                    "{s} {desc:?}: {x} vs {y}"
                );
            }
            if desc.depth.is_none() {
                let (ma, mb) = (mass(&a, &va, 40, 30), mass(&b, &vb, 40, 30));
                assert!((ma - 300.0).abs() <= 1e-3 * 300.0, "{ma}");
                assert!((mb - 300.0).abs() <= 1e-3 * 300.0, "{s}: {mb}");
            }
        }
    }
}

/// A projection's load parses only the projected field of AMRClaw text:
/// its image has the bits of the image of a load that reads every field,
/// for the default field and a named one, with either reconstruction; a
/// colour field the description names is read too.
#[test]
fn amr_projection_loads_read_only_the_projected_field() {
    let dir = common::Scratch::new("amr-picked-projection");
    let grids = [
        (1, [4, 4, 4], [0.0; 3], 0.25),
        (2, [4, 2, 4], [0.25, 0.5, 0.25], 0.125),
    ];
    let q = common::amrclaw_text(&grids, |g, c, _| {
        let v = 1.0 + (c * 7 + g * 3) as f64 * 0.013;
        vec![v, -v, v * v]
    });
    let path = dir.path("fort.q0001");
    std::fs::write(&path, q).unwrap();
    let view = ProjectionDesc {
        axis: Some(2),
        ..Default::default()
    };
    for recon in [
        voxless::ReconstructionName::Nearest,
        voxless::ReconstructionName::Basis,
    ] {
        for (field, color) in [(None, None), (Some("q2"), None), (Some("q1"), Some("q2"))] {
            let desc = voxless::SceneDesc {
                amr: Some(AmrDesc {
                    amrclaw: Some(path.to_string_lossy().into()),
                    field: field.map(Into::into),
                    color_field: color.map(Into::into),
                    reconstruction: Some(recon),
                    ..Default::default()
                }),
                ..Default::default()
            };
            let whole = voxless::load(&desc, &dir.0, 0).unwrap();
            let picked =
                voxless::load::load_for(&desc, &dir.0, 0, voxless::Purpose::Project).unwrap();
            let names = |l: &Loaded| match &l.volume {
                AnyVolume::Amr(v) => v.field_names().to_vec(),
                _ => panic!("not AMR"),
            };
            assert_eq!(names(&whole), ["q0", "q1", "q2"]);
            let expected: Vec<&str> = match (field, color) {
                (None, _) => vec!["q0"],
                (Some(f), None) => vec![f],
                (Some(f), Some(c)) => vec![f, c],
            };
            assert_eq!(names(&picked), expected, "{field:?} {color:?}");
            let (a, _) = project(&whole, &view, 48, 40);
            let (b, _) = project(&picked, &view, 48, 40);
            assert!(a.iter().any(|&v| v != 0.0));
            assert_eq!(a, b, "{recon:?} {field:?}");
        }
    }
}
