//! Known answers: brute-force basis sums over all cells, constant fields,
//! continuity across levels, value-range containment, exact chord sums.
#![allow(clippy::needless_range_loop)] // loops over x, y, z read clearest

use super::*;
use voxless_core::SmallRng as Lcg;
use voxless_core::{Aabb, IntervalQuery, Range1, Ray, Vec3, Volume};

/// A multi-level grid over [0, 64)³ finest units: level-3 cells, some refined
/// to 2, 1 and 0 (so level jumps of up to three occur where a refined cell
/// touches an unrefined one), and a few holes.
pub(crate) fn synthetic(seed: u64, holes: bool) -> Vec<[i32; 4]> {
    let mut rng = Lcg(seed);
    let mut out = Vec::new();
    fn refine(c: [i32; 4], rng: &mut Lcg, out: &mut Vec<[i32; 4]>, holes: bool) {
        let p_refine = [0.0, 0.5, 0.35, 0.3][c[3] as usize];
        if c[3] > 0 && rng.f() < p_refine {
            let w = 1 << (c[3] - 1);
            for k in 0..2 {
                for j in 0..2 {
                    for i in 0..2 {
                        refine(
                            [c[0] + i * w, c[1] + j * w, c[2] + k * w, c[3] - 1],
                            rng,
                            out,
                            holes,
                        );
                    }
                }
            }
        } else if !(holes && rng.f() < 0.03) {
            out.push(c);
        }
    }
    for k in 0..8 {
        for j in 0..8 {
            for i in 0..8 {
                refine([i * 8, j * 8, k * 8, 3], &mut rng, &mut out, holes);
            }
        }
    }
    out
}

pub(crate) fn smooth(c: &[i32; 4]) -> f32 {
    let w = (1 << c[3]) as f32;
    let p = [0, 1, 2].map(|a| c[a] as f32 + 0.5 * w);
    (p[0] * 0.11).sin() + (p[1] * 0.07).cos() * 2.0 + p[2] * 0.03
}

pub(crate) fn cells_with(cells: Vec<[i32; 4]>, f: impl Fn(&[i32; 4]) -> f32) -> AmrCells {
    let v: Vec<f32> = cells.iter().map(&f).collect();
    let v2: Vec<f32> = cells.iter().map(|c| c[3] as f32).collect();
    AmrCells {
        cells,
        fields: vec![("f".into(), v), ("level".into(), v2)],
        origin: Vec3::new(-1.0, 2.0, 0.5),
        cell_size: 0.1,
    }
}

/// B(p) by its definition, summing over every cell.
fn brute_force(cells: &AmrCells, field: usize, p: Vec3) -> Option<f64> {
    let pu = (p - cells.origin) * (1.0 / cells.cell_size);
    let (mut sw, mut sv) = (0.0f64, 0.0f64);
    for (i, c) in cells.cells.iter().enumerate() {
        let w = (1i64 << c[3]) as f64;
        let mut h = 1.0f64;
        for a in 0..3 {
            let centre = c[a] as f64 + 0.5 * w;
            h *= (1.0 - (centre - pu[a] as f64).abs() / w).max(0.0);
        }
        sw += h;
        sv += h * cells.fields[field].1[i] as f64;
    }
    (sw > 0.0).then(|| sv / sw)
}

fn random_point(rng: &mut Lcg, b: &Aabb) -> Vec3 {
    b.min + Vec3::new(rng.f(), rng.f(), rng.f()).mul_elem(b.extent())
}

#[test]
fn basis_via_regions_equals_brute_force_and_cell_location() {
    let input = cells_with(synthetic(1, true), smooth);
    let vol = AmrVolume::new(input.clone(), AmrSettings::default()).unwrap();
    let locator = CellLocator::new(&input, 0);
    let s = vol.stats();
    assert!(s.bricks > 10 && s.regions > s.bricks, "{s:?}");
    let mut rng = Lcg(2);
    let mut checked = 0;
    for _ in 0..10_000 {
        let p = random_point(&mut rng, &vol.bounds());
        let want = brute_force(&input, 0, p);
        let got = vol.sample(p).map(|s| s.value as f64);
        match (want, got) {
            (Some(w), Some(g)) => {
                assert!(
                    (w - g).abs() <= 1e-5 * w.abs().max(1.0),
                    "at {p:?}: {g} vs {w}"
                );
                let l = locator.sample(p).unwrap() as f64;
                assert!((w - l).abs() <= 1e-5 * w.abs().max(1.0));
                checked += 1;
            }
            (None, None) => {}
            // At the very edge of a support both are ~0-weight; anything else is a bug.
            (w, g) => panic!("coverage differs at {p:?}: brute force {w:?}, regions {g:?}"),
        }
    }
    assert!(checked > 8000, "{checked}");
}

#[test]
fn analytic_gradient_matches_finite_differences_of_brute_force() {
    let input = cells_with(synthetic(3, false), smooth);
    let vol = AmrVolume::new(input.clone(), AmrSettings::default()).unwrap();
    let mut rng = Lcg(4);
    let h = 1e-3f32;
    let mut checked = 0;
    for _ in 0..2000 {
        let p = random_point(&mut rng, &vol.bounds().intersect_box());
        let Some((_, g)) = vol.sample_with_gradient(p) else {
            continue;
        };
        let mut fd = [0.0f64; 3];
        let mut ok = true;
        for a in 0..3 {
            let mut e = Vec3::ZERO;
            match a {
                0 => e.x = h,
                1 => e.y = h,
                _ => e.z = h,
            }
            match (brute_force(&input, 0, p + e), brute_force(&input, 0, p - e)) {
                (Some(x), Some(y)) => fd[a] = (x - y) / (2.0 * h as f64),
                _ => ok = false,
            }
        }
        // The basis is only piecewise smooth: skip points whose difference
        // stencil crosses a kink (where one-sided slopes disagree).
        if !ok {
            continue;
        }
        let err = (0..3)
            .map(|a| (g[a] as f64 - fd[a]).abs())
            .fold(0.0, f64::max);
        let scale = fd.iter().map(|v| v.abs()).fold(1.0, f64::max);
        if err <= 1e-2 * scale {
            checked += 1;
        }
    }
    assert!(
        checked > 1800,
        "analytic gradient agreed at only {checked} of ~2000 points"
    );
}

trait Shrink {
    fn intersect_box(self) -> Aabb;
}
impl Shrink for Aabb {
    /// The box shrunk by 5% per side (away from the outer support edge).
    fn intersect_box(self) -> Aabb {
        let m = self.extent() * 0.05;
        Aabb::new(self.min + m, self.max - m)
    }
}

#[test]
fn constant_field_is_exactly_constant_across_levels() {
    let input = cells_with(synthetic(5, true), |_| 3.25);
    let vol = AmrVolume::new(input, AmrSettings::default()).unwrap();
    let mut rng = Lcg(6);
    let mut n = 0;
    for _ in 0..20_000 {
        let p = random_point(&mut rng, &vol.bounds());
        if let Some((s, g)) = vol.sample_with_gradient(p) {
            assert!((s.value - 3.25).abs() <= 1e-6, "{} at {p:?}", s.value);
            assert!(g.length() <= 1e-3, "gradient {g:?} of a constant at {p:?}");
            n += 1;
        }
    }
    assert!(n > 15_000);
}

#[test]
fn no_seams_across_level_boundaries() {
    let input = cells_with(synthetic(7, false), smooth);
    let vol = AmrVolume::new(input, AmrSettings::default()).unwrap();
    let h = 0.1f32;
    let eps_units = 1e-3f32;
    let eps = eps_units * h;
    let mut rng = Lcg(8);
    let mut crossings = 0;
    // Points on every brick face, pushed ε to either side along the normal.
    for b in vol.bricks() {
        for axis in 0..3 {
            for side in [b.lower[axis], b.upper()[axis]] {
                let mut pu = [0.0f32; 3];
                for a in 0..3 {
                    pu[a] = if a == axis {
                        side as f32
                    } else {
                        b.lower[a] as f32 + rng.f() * (b.upper()[a] - b.lower[a]) as f32
                    };
                }
                let p = Vec3::new(-1.0, 2.0, 0.5) + Vec3::from_array(pu) * h;
                let mut e = Vec3::ZERO;
                match axis {
                    0 => e.x = eps,
                    1 => e.y = eps,
                    _ => e.z = eps,
                }
                let (Some(a), Some(c)) = (vol.sample(p - e), vol.sample(p + e)) else {
                    continue;
                };
                let r = vol.locate(p).unwrap();
                // Local Lipschitz bound: the region's value spread over its
                // finest cell width, per unit world length, summed over axes.
                let range = vol.region_range(r, 0);
                let finest = vol
                    .region_bricks(r)
                    .iter()
                    .map(|&i| vol.bricks()[i as usize].width())
                    .min()
                    .unwrap() as f32
                    * h;
                let lipschitz = 3.0 * range.span() / finest;
                assert!(
                    (a.value - c.value).abs() <= lipschitz * 2.0 * eps + 1e-5,
                    "seam at {p:?}: {} vs {}",
                    a.value,
                    c.value
                );
                crossings += 1;
            }
        }
    }
    assert!(crossings > 100, "{crossings}");
}

#[test]
fn every_sample_lies_in_its_regions_value_range() {
    let input = cells_with(synthetic(9, true), smooth);
    let vol = AmrVolume::new(input, AmrSettings::default()).unwrap();
    let mut rng = Lcg(10);
    let mut out = Vec::new();
    for _ in 0..300 {
        let b = vol.bounds();
        let o = b.center() + Vec3::new(rng.f() - 0.5, rng.f() - 0.5, 3.0) * b.diagonal();
        let target = random_point(&mut rng, &b);
        let ray = Ray::new(o, (target - o).normalized());
        out.clear();
        vol.intervals(
            &ray,
            Range1::new(0.0, f32::INFINITY),
            &IntervalQuery::all(),
            &mut out,
        );
        for w in out.windows(2) {
            assert!(w[0].t.hi <= w[1].t.lo + 1e-4, "overlapping intervals");
        }
        for iv in &out {
            for k in 0..8 {
                let t = iv.t.lo + (k as f32 + 0.5) / 8.0 * iv.t.span();
                if let Some(s) = vol.sample_in(ray.at(t), iv) {
                    let r = iv.value_range;
                    assert!(
                        s.value >= r.lo - 1e-5 && s.value <= r.hi + 1e-5,
                        "{} outside {r:?}",
                        s.value
                    );
                }
            }
        }
    }
}

/// Σ value × chord length over every cell the ray crosses, by brute force.
fn exact_chord_sum(input: &AmrCells, ray: &Ray) -> f64 {
    let mut sum = 0.0;
    for (i, c) in input.cells.iter().enumerate() {
        let w = (1 << c[3]) as f32;
        let lo = input.origin + Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) * input.cell_size;
        let b = Aabb::new(lo, lo + Vec3::splat(w * input.cell_size));
        let t = b.clip_ray(ray, Range1::new(f32::NEG_INFINITY, f32::INFINITY));
        if !t.is_empty() {
            sum += input.fields[0].1[i] as f64 * t.span() as f64;
        }
    }
    sum
}

#[test]
fn nearest_projection_equals_exact_chord_sums() {
    let input = cells_with(synthetic(11, true), smooth);
    let vol = AmrVolume::new(
        input.clone(),
        AmrSettings {
            reconstruction: Reconstruction::Nearest,
            ..Default::default()
        },
    )
    .unwrap();
    let mut rng = Lcg(12);
    for _ in 0..300 {
        let b = vol.bounds();
        let o = b.center()
            + Vec3::new(rng.f() - 0.5, rng.f() - 0.5, rng.f() - 0.5) * (3.0 * b.diagonal());
        let ray = Ray::new(o, (random_point(&mut rng, &b) - o).normalized());
        let t = b.clip_ray(&ray, Range1::new(f32::NEG_INFINITY, f32::INFINITY));
        let got = if t.is_empty() {
            0.0
        } else {
            vol.line_integral(&ray, t)
        };
        let want = exact_chord_sum(&input, &ray);
        assert!(
            (got - want).abs() <= 1e-4 * want.abs().max(1.0),
            "{got} vs {want}"
        );
    }
}

#[test]
fn opacity_correction_makes_transmittance_independent_of_the_rate() {
    use voxless_render::{RenderSettings, march, sampling::PixelRng};
    use voxless_transfer::{Colormap, OpacityMap, TransferFunction};
    let input = cells_with(synthetic(13, false), |_| 1.0);
    let vol = AmrVolume::new(input, AmrSettings::default()).unwrap();
    let tf = TransferFunction::new(
        Colormap::preset("gray").unwrap(),
        OpacityMap::preset("constant").unwrap(),
    );
    let b = vol.bounds();
    let ray = Ray::new(
        b.center() - Vec3::new(0.0, 0.0, 10.0),
        Vec3::new(0.013, 0.021, 1.0).normalized(),
    );
    let mut alphas = Vec::new();
    for rate in [0.25, 0.5, 1.0, 2.0, 7.0] {
        let settings = RenderSettings {
            sampling_rate: rate,
            opacity_scale: 0.2,
            early_termination: 1.0,
            ..RenderSettings::for_volume(&vol, 1, 1)
        };
        alphas.push(
            march(
                &vol,
                &ray,
                &tf,
                &settings,
                &PixelRng::new(0, 0, 0),
                &mut Vec::new(),
            )[3],
        );
    }
    let t = b.clip_ray(&ray, Range1::new(0.0, f32::INFINITY));
    // Inside the cells the field is 1; in the half-cell support margin outside
    // them the tents still average to 1, so the whole support is homogeneous.
    let want = 1.0 - (-0.2 * t.span()).exp();
    for a in &alphas {
        assert!((a - want).abs() < 1e-3, "{alphas:?} vs {want}");
    }
}

#[test]
fn bad_cells_are_clear_errors() {
    let ok = |cells: Vec<[i32; 4]>| {
        let n = cells.len();
        AmrVolume::new(
            AmrCells {
                cells,
                fields: vec![("f".into(), vec![1.0; n])],
                origin: Vec3::ZERO,
                cell_size: 1.0,
            },
            AmrSettings::default(),
        )
    };
    assert!(matches!(ok(vec![]), Err(AmrError::Empty)));
    assert!(matches!(
        ok(vec![[1, 0, 0, 1]]),
        Err(AmrError::Misaligned { cell: 0, .. })
    ));
    assert!(matches!(
        ok(vec![[0, 0, 0, -1]]),
        Err(AmrError::BadLevel { .. })
    ));
    // A fine cell inside a coarse one, and an exact duplicate.
    assert!(matches!(
        ok(vec![[0, 0, 0, 1], [4, 4, 4, 0], [1, 1, 1, 0]]),
        Err(AmrError::Overlap { a: 0, b: 2 })
    ));
    assert!(matches!(
        ok(vec![[2, 2, 2, 0], [2, 2, 2, 0]]),
        Err(AmrError::Overlap { .. })
    ));
    // The same with a cell 2^20 units away: keys too wide to carry the
    // level beside them (the other sort), the same errors.
    let far = [1 << 20, 0, 0, 0];
    assert!(matches!(
        ok(vec![[0, 0, 0, 1], [4, 4, 4, 0], [1, 1, 1, 0], far]),
        Err(AmrError::Overlap { a: 0, b: 2 })
    ));
    assert!(matches!(
        ok(vec![far, [2, 2, 2, 0], [2, 2, 2, 0]]),
        Err(AmrError::Overlap { a: 1, b: 2 })
    ));
    assert!(matches!(
        ok(vec![[2, 2, 2, 0], [6, 2, 2, 1], [2, 2, 2, 0]]),
        Err(AmrError::Overlap { a: 0, b: 2 })
    ));
    // Negative coordinates are fine.
    ok(vec![[-2, -2, -2, 1], [0, 0, 0, 0]]).unwrap();
    let e = AmrVolume::new(
        AmrCells {
            cells: vec![[0, 0, 0, 0]; 1],
            fields: vec![("density".into(), vec![f32::NAN])],
            origin: Vec3::ZERO,
            cell_size: 1.0,
        },
        AmrSettings::default(),
    )
    .err()
    .unwrap();
    assert!(
        e.to_string().contains("density") && e.to_string().contains("cell 0"),
        "{e}"
    );
    let e = AmrVolume::new(
        AmrCells {
            cells: vec![[0, 0, 0, 0]; 1],
            fields: vec![("f".into(), vec![1.0, 2.0])],
            origin: Vec3::ZERO,
            cell_size: 0.0,
        },
        AmrSettings::default(),
    )
    .err()
    .unwrap();
    assert!(matches!(e, AmrError::FieldLength { .. }), "{e}");
}

#[test]
fn bricks_are_filled_same_level_and_at_most_32_wide() {
    let input = cells_with(synthetic(15, true), smooth);
    let n = input.cells.len();
    let vol = AmrVolume::new(input, AmrSettings::default()).unwrap();
    let total: usize = vol.bricks().iter().map(|b| b.cell_count()).sum();
    assert_eq!(total, n, "every cell in exactly one brick");
    assert!(
        vol.bricks()
            .iter()
            .all(|b| b.size.iter().all(|&s| (1..=32).contains(&s)))
    );
    // A uniform 40³ level-0 block splits into bricks of at most 32.
    let cells: Vec<[i32; 4]> = (0..40 * 40 * 40)
        .map(|i| [i % 40, (i / 40) % 40, i / 1600, 0])
        .collect();
    let vol = AmrVolume::new(cells_with(cells, |_| 1.0), AmrSettings::default()).unwrap();
    assert!(vol.bricks().len() >= 8);
    assert!(vol.bricks().iter().all(|b| b.size.iter().all(|&s| s <= 32)));
}

#[test]
fn abutting_same_level_bricks_are_merged() {
    // Level-1 cells over x ∈ [0, 40) finest units and level-0 cells over
    // [40, 48), 16 wide in y and z: the middle splits cut the level-1 part
    // at x = 24 and 36 on their way to the level boundary; merged, it is one
    // 20 × 8 × 8 brick.
    let mut cells = Vec::new();
    for z in 0..16 {
        for y in 0..16 {
            for x in 0..48 {
                if x >= 40 {
                    cells.push([x, y, z, 0]);
                } else if x % 2 == 0 && y % 2 == 0 && z % 2 == 0 {
                    cells.push([x, y, z, 1]);
                }
            }
        }
    }
    let vol = AmrVolume::new(cells_with(cells, smooth), AmrSettings::default()).unwrap();
    let coarse: Vec<_> = vol.bricks().iter().filter(|b| b.level == 1).collect();
    assert_eq!(coarse.len(), 1, "{coarse:?}");
    assert_eq!((coarse[0].lower, coarse[0].size), ([0, 0, 0], [20, 8, 8]));
    // On mixed data no two bricks are left that could still be joined.
    let vol = AmrVolume::new(
        cells_with(synthetic(16, true), smooth),
        AmrSettings::default(),
    )
    .unwrap();
    let bricks = vol.bricks();
    for b in bricks {
        for axis in 0..3 {
            let mut next = b.lower;
            next[axis] += b.size[axis] * b.width();
            let joinable = bricks.iter().any(|n| {
                n.level == b.level
                    && n.lower == next
                    && (0..3).all(|a| a == axis || n.size[a] == b.size[a])
                    && b.size[axis] + n.size[axis] <= 32
            });
            assert!(
                !joinable,
                "{b:?} could still join its neighbour along {axis}"
            );
        }
    }
}

/// The real AMRClaw frame (ExaBricks conversion): regions equal the
/// brute-force sum over all 216k cells at a few hundred points and cell
/// location at 10⁴; skipped with a notice when the shared data is absent.
#[test]
fn real_frame_matches_brute_force() {
    let Some(dir) = voxless_core::testing::shared_data("amr-euler3d/exabricks") else {
        return;
    };
    let scalars: Vec<_> = ["density", "energy"]
        .iter()
        .map(|f| dir.join(format!("frame3.{f}.scalars")))
        .collect();
    let data = voxless_io::read_exabricks(&dir.join("frame3.cells"), &scalars).unwrap();
    let input = AmrCells {
        cells: data.cells,
        fields: data.fields,
        origin: Vec3::from_array(data.origin.map(|v| v as f32)),
        cell_size: data.finest_cell_size as f32,
    };
    let vol = AmrVolume::new(input.clone(), AmrSettings::default()).unwrap();
    assert_eq!(vol.stats().cells, 216_089);
    let locator = CellLocator::new(&input, 0);
    let mut rng = Lcg(21);
    for k in 0..10_000 {
        let p = random_point(&mut rng, &vol.bounds());
        let got = vol.sample(p).map(|s| s.value as f64);
        let want = if k < 300 {
            brute_force(&input, 0, p)
        } else {
            locator.sample(p).map(|v| v as f64)
        };
        match (got, want) {
            (Some(g), Some(w)) => assert!(
                (g - w).abs() <= 1e-5 * w.abs().max(1e-3),
                "at {p:?}: {g} vs {w}"
            ),
            (None, None) => {}
            (g, w) => panic!("coverage differs at {p:?}: regions {g:?}, reference {w:?}"),
        }
    }
}

#[test]
fn colour_field_is_the_basis_reconstruction_of_that_field() {
    let input = cells_with(synthetic(17, true), smooth);
    let settings = AmrSettings {
        color_field: Some(1),
        ..Default::default()
    };
    let vol = AmrVolume::new(input.clone(), settings).unwrap();
    let mut rng = Lcg(18);
    let mut checked = 0;
    for _ in 0..3000 {
        let p = random_point(&mut rng, &vol.bounds());
        let (Some(s), Some(want)) = (vol.sample(p), brute_force(&input, 1, p)) else {
            continue;
        };
        let voxless_core::Attribute::Scalar(c) = s.attribute else {
            panic!("no colour sample")
        };
        assert!(
            (c as f64 - want).abs() <= 1e-5 * want.abs().max(1.0),
            "{c} vs {want}"
        );
        checked += 1;
    }
    assert!(checked > 2000);
}

/// Bricks and regions built on first use from inside parallel loops (every
/// worker asking at once, for a render's first samples) finish, and give
/// what a volume built before the loop gives.
#[test]
fn lazy_builds_inside_parallel_loops_finish() {
    use rayon::prelude::*;
    // Enough cells that the builds split their work over the pool.
    let mut cells = synthetic(19, true);
    let top = cells.iter().map(|c| c[2] + (1 << c[3])).max().unwrap_or(0);
    cells.extend((0..48 * 48 * 24).map(|i| [i % 48, (i / 48) % 48, top + i / (48 * 48), 0]));
    let input = cells_with(cells, smooth);
    let ready = AmrVolume::new(input.clone(), AmrSettings::default()).unwrap();
    let _ = ready.stats();
    let mut rng = Lcg(20);
    let points: Vec<Vec3> = (0..512)
        .map(|_| random_point(&mut rng, &ready.bounds()))
        .collect();
    let want: Vec<_> = points.iter().map(|&p| ready.fields_at(p, true)).collect();
    for threads in [1, 2, 4] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let lazy = AmrVolume::new(input.clone(), AmrSettings::default()).unwrap();
        let got: Vec<_> = pool.install(|| {
            points
                .par_iter()
                .with_max_len(1)
                .map(|&p| lazy.fields_at(p, true))
                .collect()
        });
        assert_eq!(got, want, "{threads} threads");
    }
}

/// The bitmap overlap check says what the sorted one says: random
/// hierarchies, each with a duplicate, a fine cell under a coarse one or
/// nothing added, and a sparse one the bitmaps leave to the sort.
#[test]
fn overlap_bitmaps_agree_with_the_sorted_check() {
    let run = |cells: &[[i32; 4]]| {
        let n = cells.len();
        AmrVolume::new(
            AmrCells {
                cells: cells.to_vec(),
                fields: vec![("f".into(), vec![1.0; n])],
                origin: Vec3::ZERO,
                cell_size: 1.0,
            },
            AmrSettings::default(),
        )
        .err()
    };
    let mut rng = Lcg(31);
    let mut overlaps = 0;
    for seed in 0..40 {
        let mut cells = synthetic(seed, seed % 2 == 0);
        let want = match seed % 3 {
            0 => false,
            1 => {
                let c = cells[(rng.f() * cells.len() as f32) as usize % cells.len()];
                cells.push(c);
                true
            }
            _ => match cells.iter().find(|c| c[3] > 0).copied() {
                Some(c) => {
                    cells.push([c[0], c[1], c[2], 0]);
                    true
                }
                None => false,
            },
        };
        assert_eq!(
            crate::bricks::no_overlap_in_bitmaps(&cells),
            Some(!want),
            "seed {seed}"
        );
        match run(&cells) {
            None => assert!(!want, "seed {seed}: no error"),
            Some(AmrError::Overlap { a, b }) => {
                assert!(want && a < b, "seed {seed}");
                overlaps += 1;
            }
            Some(e) => panic!("seed {seed}: {e}"),
        }
    }
    assert!(overlaps >= 20, "{overlaps}");
    // Two finest cells 2^18 apart: the bitmaps would hold 2^54 bits.
    let sparse = [[0, 0, 0, 0], [1 << 18, 1 << 18, 1 << 18, 0]];
    assert_eq!(crate::bricks::no_overlap_in_bitmaps(&sparse), None);
    assert!(run(&sparse).is_none());
}
