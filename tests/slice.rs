//! Slices (`voxless::slice`): a slice equals `sample` at its pixel centres
//! bit for bit for every data kind, wraps through periodic boxes, averages
//! pixels exactly for low-degree fields, and refuses planes that miss the
//! data and unknown quantities by name.

mod common;

use common::{Lcg, Scratch};
use voxless::slice::{SliceDesc, SlicePixels, slice_points, slice_view};
use voxless::{
    AmrArrays, AmrDesc, AnyVolume, BoxDesc, KernelName, ParticleArrays, ParticlesDesc, PlacedData,
    ProjectionDesc, SceneDesc, TetsDesc,
};

fn slice(
    data: &PlacedData,
    desc: &SceneDesc,
    s: &SliceDesc,
    size: (u32, u32),
) -> Result<(voxless::ProjectionView, String, Vec<f32>), voxless::ParallelError> {
    let (view, name, v) = data.slice(desc, s, size, &|_, _| {})?;
    Ok((view, name, v.unwrap()))
}

/// The slice of `data` against `sample` at the same points (column
/// `column` of `columns`), compared bit for bit.
fn equals_sample(data: &PlacedData, desc: &SceneDesc, s: &SliceDesc, column: usize) {
    let size = (37, 29);
    let (view, _, values) = slice(data, desc, s, size).unwrap();
    let pts = slice_points(&view, size, 0..size.1, SlicePixels::Centre);
    let columns = data.fields().columns(false).len();
    let sampled = data.sample(&pts, false).unwrap().unwrap();
    assert_eq!(values.len(), pts.len());
    let mut nonzero = 0;
    for (k, v) in values.iter().enumerate() {
        let want = sampled[k * columns + column];
        assert_eq!(v.to_bits(), want.to_bits(), "pixel {k}: {v} vs {want}");
        nonzero += (*v != 0.0 && v.is_finite()) as usize;
    }
    assert!(
        nonzero > values.len() / 10,
        "the slice shows little: {nonzero}"
    );
}

fn particles(periodic: bool) -> AnyVolume {
    let mut rng = Lcg(5);
    let pos: Vec<[f64; 3]> = (0..500)
        .map(|_| [rng.f() as f64, rng.f() as f64, rng.f() as f64])
        .collect();
    let mut arrays = ParticleArrays::from_f64(&pos);
    arrays.radii = Some(vec![0.12; 500]);
    arrays.attribute = Some((0..500).map(|i| i as f32).collect());
    let desc = ParticlesDesc {
        kernel: Some(KernelName::CubicSpline),
        periodic_box: periodic.then_some(BoxDesc::Side(1.0)),
        ..Default::default()
    };
    AnyVolume::from_particles(arrays, &desc).unwrap().volume
}

fn loaded(volume: AnyVolume) -> PlacedData<'static> {
    PlacedData::Process(voxless::Loaded {
        volume,
        frame: Default::default(),
        notes: vec![],
    })
}

fn axis_z(center: [f64; 3], width: [f64; 2]) -> SliceDesc {
    SliceDesc {
        plane: ProjectionDesc {
            axis: Some(2),
            center: Some(center),
            width: Some(width),
            ..Default::default()
        },
        ..Default::default()
    }
}

#[test]
fn particle_slices_equal_sample_for_density_and_attribute() {
    let data = loaded(particles(false));
    let desc = SceneDesc::default();
    let mut s = axis_z([0.5, 0.5, 0.5], [1.0, 0.8]);
    equals_sample(&data, &desc, &s, 0);
    s.quantity = Some("attribute".into());
    equals_sample(&data, &desc, &s, 1);
    // Off axis, through the default centre.
    s.plane = ProjectionDesc {
        normal: Some([1.0, 2.0, 0.5]),
        ..Default::default()
    };
    equals_sample(&data, &desc, &s, 1);
}

#[test]
fn slice_geometry_is_projections() {
    let data = loaded(particles(false));
    let (view, name, _) = slice(
        &data,
        &SceneDesc::default(),
        &axis_z([0.2, 0.3, 0.4], [2.0, 1.0]),
        (4, 2),
    )
    .unwrap();
    assert_eq!(name, "density");
    // Pixel (0, 0): the top left, x = 0.2 − 1 + 0.25, y = 0.3 + 0.5 − 0.25.
    let p = view.pixel_center(0, 0, 4, 2);
    for (a, b) in p.iter().zip([-0.55, 0.55, 0.4]) {
        assert!((a - b).abs() < 1e-12, "{p:?}");
    }
}

#[test]
fn periodic_slices_wrap() {
    let data = loaded(particles(true));
    let desc = SceneDesc::default();
    // A plane one box up and across: the same field as the box's own.
    let (_, _, here) = slice(&data, &desc, &axis_z([0.5, 0.5, 0.3], [1.0, 1.0]), (16, 16)).unwrap();
    let (_, _, there) = slice(
        &data,
        &desc,
        &axis_z([1.5, -0.5, 1.3], [1.0, 1.0]),
        (16, 16),
    )
    .unwrap();
    for (a, b) in here.iter().zip(&there) {
        assert!((a - b).abs() <= 1e-5 * a.abs().max(1e-3), "{a} vs {b}");
    }
    // A plane far outside the box still meets the tiled medium.
    assert!(slice(&data, &desc, &axis_z([0.5, 0.5, 7.3], [1.0, 1.0]), (4, 4)).is_ok());
}

#[test]
fn planes_that_miss_the_data_are_refused() {
    let data = loaded(particles(false));
    let e = slice(
        &data,
        &SceneDesc::default(),
        &axis_z([0.5, 0.5, 9.0], [1.0, 1.0]),
        (4, 4),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("misses the data") && e.contains("bounds"), "{e}");
    let mut s = axis_z([0.5, 0.5, 0.5], [1.0, 1.0]);
    s.quantity = Some("pressure".into());
    let e = slice(&data, &SceneDesc::default(), &s, (4, 4))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("pressure") && e.contains("density, attribute"),
        "{e}"
    );
    s.quantity = None;
    s.plane.depth = Some(0.1);
    let e = slice(&data, &SceneDesc::default(), &s, (4, 4))
        .unwrap_err()
        .to_string();
    assert!(e.contains("depth"), "{e}");
}

fn amr() -> AnyVolume {
    // A 4³ coarse grid with a refined 4³ patch (level 1) in one corner.
    let mut cells = Vec::new();
    let mut rho = Vec::new();
    let mut temp = Vec::new();
    for z in 0..4 {
        for y in 0..4 {
            for x in 0..4 {
                if x < 2 && y < 2 && z < 2 {
                    continue;
                }
                cells.push([2 * x, 2 * y, 2 * z, 1]);
                rho.push((x + 2 * y + 3 * z) as f32);
                temp.push(10.0 + x as f32);
            }
        }
    }
    for z in 0..4 {
        for y in 0..4 {
            for x in 0..4 {
                cells.push([x, y, z, 0]);
                rho.push(0.5 * (x + y + z) as f32);
                temp.push(5.0);
            }
        }
    }
    AnyVolume::from_amr(
        AmrArrays {
            cells,
            fields: vec![("rho".into(), rho), ("temp".into(), temp)],
            origin: [0.0; 3],
            cell_size: 0.25,
        },
        &AmrDesc::default(),
    )
    .unwrap()
    .volume
}

#[test]
fn amr_slices_equal_sample_for_every_field() {
    let data = loaded(amr());
    let desc = SceneDesc::default();
    let mut s = axis_z([1.0, 1.0, 0.6], [2.0, 2.0]);
    equals_sample(&data, &desc, &s, 0);
    // "density" finds rho; any field by name.
    s.quantity = Some("density".into());
    equals_sample(&data, &desc, &s, 0);
    s.quantity = Some("TEMP".into());
    equals_sample(&data, &desc, &s, 1);
    // The scene's AMR field is the default.
    let by_scene = SceneDesc {
        amr: Some(AmrDesc {
            field: Some("temp".into()),
            ..Default::default()
        }),
        ..Default::default()
    };
    s.quantity = None;
    let (_, name, _) = slice(&data, &by_scene, &s, (4, 4)).unwrap();
    assert_eq!(name, "temp");
}

#[test]
fn tessellation_slices_equal_sample_for_density_and_streams() {
    let s = Scratch::new("slice-tets");
    let n = 6;
    let mut rng = Lcg(9);
    let mut pos = Vec::new();
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                for c in [i, j, k] {
                    pos.push((c as f32 + 0.5) * 2.0 / n as f32 + 0.2 * (rng.f() - 0.5));
                }
            }
        }
    }
    voxless_io::write_npy_f32(&s.path("p.npy"), &[n * n * n, 3], &pos).unwrap();
    let desc = SceneDesc {
        tets: Some(TetsDesc {
            file: Some(s.str("p.npy")),
            lagrangian: Some(n),
            box_size: Some(2.0),
            ..Default::default()
        }),
        ..Default::default()
    };
    let data = PlacedData::Process(voxless::load(&desc, std::path::Path::new("."), 0).unwrap());
    let mut sd = axis_z([1.0, 1.0, 0.7], [2.0, 2.0]);
    equals_sample(&data, &desc, &sd, 0);
    sd.quantity = Some("streams".into());
    equals_sample(&data, &desc, &sd, 1);
}

/// The area rule is exact for a field linear across each pixel: an AMR
/// field that is constant per cell, with pixels inside cells.
#[test]
fn area_pixels_average_each_square() {
    let data = loaded(amr());
    let desc = SceneDesc::default();
    let mut s = axis_z([0.5, 0.5, 0.9], [1.0, 1.0]);
    s.quantity = Some("temp".into());
    let (view, _, centre) = slice(&data, &desc, &s, (8, 8)).unwrap();
    s.pixels = SlicePixels::Area;
    let (_, _, area) = slice(&data, &desc, &s, (8, 8)).unwrap();
    // The mean of 16 samples per pixel, by the rule's weights.
    let pts = slice_points(&view, (8, 8), 0..8, SlicePixels::Area);
    assert_eq!(pts.len(), 64 * 16);
    let sampled = data.sample(&pts, false).unwrap().unwrap();
    for (px, a) in area.iter().enumerate() {
        let vals: Vec<f32> = (0..16).map(|q| sampled[(px * 16 + q) * 2 + 1]).collect();
        let (lo, hi) = vals
            .iter()
            .fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
        assert!(
            *a >= lo - 1e-4 && *a <= hi + 1e-4,
            "pixel {px}: {a} outside {lo}..{hi}"
        );
        if hi - lo < 1e-6 {
            assert!(
                (a - centre[px]).abs() < 1e-4,
                "pixel {px}: {a} vs {}",
                centre[px]
            );
        }
    }
    let view2 = slice_view(&s.plane, &amr().bounds(), &Default::default(), false).unwrap();
    assert_eq!(view2.center, view.center);
}
