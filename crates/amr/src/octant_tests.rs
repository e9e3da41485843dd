//! Octant reconstruction against known answers: a reference written from
//! the definition (every lookup a search of all cells) at random points,
//! continuity across every level boundary, constant and linear fields,
//! analytic gradients against differences of the field, and samples
//! inside their regions' value ranges.
#![allow(clippy::needless_range_loop)] // loops over x, y, z read clearest

use std::collections::HashMap;

use super::*;
use crate::tests::{cells_with, smooth, synthetic};
use voxless_core::SmallRng as Lcg;
use voxless_core::{Aabb, Attribute, IntervalQuery, Range1, Ray, Vec3, Volume};

fn octant() -> AmrSettings {
    AmrSettings {
        reconstruction: Reconstruction::Octant,
        ..Default::default()
    }
}

/// The octant field by its definition (finest units, `f64`), simple and
/// slow: every cell lookup searches all cells.
struct Reference<'a> {
    cells: &'a [[i32; 4]],
    values: &'a [f32],
}

impl Reference<'_> {
    fn width(&self, i: usize) -> f64 {
        (1i64 << self.cells[i][3]) as f64
    }

    /// The cell whose half-open box holds `y`.
    fn find(&self, y: [f64; 3]) -> Option<usize> {
        self.cells.iter().position(|c| {
            let w = (1i64 << c[3]) as f64;
            (0..3).all(|a| y[a] >= c[a] as f64 && y[a] < c[a] as f64 + w)
        })
    }

    /// The field at `p`; `None` outside the cells.
    fn value(&self, p: [f64; 3]) -> Option<f64> {
        self.find(p).map(|i| self.in_cell(i, p))
    }

    /// The cell `i` and octant signs whose box holds `p`.
    fn box_of(&self, p: [f64; 3]) -> Option<(usize, [bool; 3])> {
        let i = self.find(p)?;
        let w = self.width(i);
        Some((
            i,
            [0, 1, 2].map(|a| p[a] < self.cells[i][a] as f64 + 0.5 * w),
        ))
    }

    /// Cell `i`'s field at `p` (in its closed box): trilinear between the
    /// vertices of the octant holding `p`, weights `Π t or 1 − t`.
    fn in_cell(&self, i: usize, p: [f64; 3]) -> f64 {
        let w = self.width(i);
        let c = [0, 1, 2].map(|a| self.cells[i][a] as f64 + 0.5 * w);
        let s = [0, 1, 2].map(|a| if p[a] < c[a] { -1.0 } else { 1.0 });
        let t = [0, 1, 2].map(|a| (p[a] - c[a]).abs() / (0.5 * w));
        let mut f = 0.0;
        for k in 0..8 {
            let on = |a: usize| (k >> a) & 1 == 1;
            let q = [0, 1, 2].map(|a| c[a] + if on(a) { s[a] * 0.5 * w } else { 0.0 });
            let weight: f64 = (0..3)
                .map(|a| if on(a) { t[a] } else { 1.0 - t[a] })
                .product();
            if weight > 0.0 {
                f += weight * self.vertex(w, q);
            }
        }
        f
    }

    /// The value at vertex `q` of a box of a width-`w` cell: the blocks of
    /// width `w` whose closure holds `q` (per axis: the one `q` is centred
    /// in, or the two it separates); the coarsest leaf's field if one is
    /// coarser than `w`, else the mean of the width-`w` leaves.
    fn vertex(&self, w: f64, q: [f64; 3]) -> f64 {
        let axis = |a: usize| {
            if (q[a] / w).fract() == 0.0 {
                vec![q[a] - 0.5 * w, q[a] + 0.5 * w]
            } else {
                vec![q[a]]
            }
        };
        let (mut coarsest, mut same) = (None::<usize>, Vec::new());
        for &x in &axis(0) {
            for &y in &axis(1) {
                for &z in &axis(2) {
                    let Some(j) = self.find([x, y, z]) else {
                        continue;
                    };
                    let wj = self.width(j);
                    if wj > w && coarsest.is_none_or(|g| wj > self.width(g)) {
                        coarsest = Some(j);
                    } else if wj == w {
                        same.push(self.values[j] as f64);
                    }
                }
            }
        }
        match coarsest {
            Some(g) => self.in_cell(g, q),
            None => same.iter().sum::<f64>() / same.len() as f64,
        }
    }
}

/// The world point of unit-space point `u` and the unit-space point the
/// volume computes back from it (so the reference sees what it sees).
fn world_and_units(input: &AmrCells, u: [f64; 3]) -> (Vec3, [f64; 3]) {
    let p = input.origin + Vec3::new(u[0] as f32, u[1] as f32, u[2] as f32) * input.cell_size;
    let back = (p - input.origin) * (1.0 / input.cell_size);
    (p, [back.x as f64, back.y as f64, back.z as f64])
}

fn random_units(rng: &mut Lcg, lo: f64, hi: f64) -> [f64; 3] {
    [0, 1, 2].map(|_| lo + rng.f() as f64 * (hi - lo))
}

/// Values and colours (the `level` field) against the reference at random
/// points of multi-level sets with and without holes, to 1e-5 relative;
/// `fields_at` gives the bits of `sample_with_gradient`.
#[test]
fn octant_equals_brute_force_reference() {
    for (seed, holes) in [(31, false), (32, true)] {
        let input = cells_with(synthetic(seed, holes), smooth);
        let settings = AmrSettings {
            color_field: Some(1),
            ..octant()
        };
        let vol = AmrVolume::new(input.clone(), settings).unwrap();
        let value = Reference {
            cells: &input.cells,
            values: &input.fields[0].1,
        };
        let color = Reference {
            values: &input.fields[1].1,
            ..value
        };
        let mut rng = Lcg(seed);
        let (mut checked, mut outside) = (0, 0);
        for _ in 0..2000 {
            let (p, u) = world_and_units(&input, random_units(&mut rng, 0.0, 64.0));
            match (vol.sample(p), value.value(u)) {
                (Some(s), Some(want)) => {
                    let close = |got: f32, want: f64| {
                        (got as f64 - want).abs() <= 1e-5 * want.abs().max(1.0)
                    };
                    assert!(close(s.value, want), "at {u:?}: {} vs {want}", s.value);
                    let Attribute::Scalar(c) = s.attribute else {
                        panic!("no colour")
                    };
                    let want_c = color.value(u).unwrap();
                    assert!(close(c, want_c), "colour at {u:?}: {c} vs {want_c}");
                    let (sg, g) = vol.sample_with_gradient(p).unwrap();
                    let f = vol.fields_at(p, true).unwrap();
                    assert_eq!((f[0].0.to_bits(), f[0].1), (sg.value.to_bits(), g));
                    checked += 1;
                }
                (None, None) => outside += 1,
                (g, w) => panic!("coverage differs at {u:?}: volume {g:?}, reference {w:?}"),
            }
        }
        assert!(checked > 1800, "{checked}");
        assert_eq!(outside > 0, holes, "{outside} points in holes");
    }
}

/// The leaf holding `y` (finest units), by hashing each level's aligned
/// cell there.
fn leaf_at(map: &HashMap<[i32; 4], usize>, y: [f64; 3]) -> Option<[i32; 4]> {
    (0..=bricks::MAX_LEVEL).find_map(|l| {
        let w = (1i64 << l) as f64;
        let key = [0, 1, 2].map(|a| ((y[a] / w).floor() * w) as i32);
        let c = [key[0], key[1], key[2], l];
        map.contains_key(&c).then_some(c)
    })
}

/// Across every face between cells of different levels (two random points
/// per face, ±1e-4 finest cells along the normal), the two sides differ by
/// no more than the normal derivatives allow over that step (the field is
/// linear along the normal inside a box) plus rounding: no jumps. Nearest
/// reconstruction, which jumps there, fails the same check.
#[test]
fn no_jumps_across_level_boundaries() {
    for (seed, holes) in [(33, false), (34, true)] {
        let mut input = cells_with(synthetic(seed, holes), smooth);
        // Unit cells at the origin: the ±ε points are exact.
        (input.origin, input.cell_size) = (Vec3::ZERO, 1.0);
        let vol = AmrVolume::new(input.clone(), octant()).unwrap();
        let nearest = AmrVolume::new(
            input.clone(),
            AmrSettings {
                reconstruction: Reconstruction::Nearest,
                ..Default::default()
            },
        )
        .unwrap();
        let map: HashMap<[i32; 4], usize> = input
            .cells
            .iter()
            .enumerate()
            .map(|(i, &c)| (c, i))
            .collect();
        let eps = 1e-4f64;
        let mut rng = Lcg(seed);
        let (mut crossings, mut nearest_jumps, mut worst) = (0, 0, 0.0f64);
        for c in &input.cells {
            let w = (1i64 << c[3]) as f64;
            for axis in 0..3 {
                for side in [0.0, 1.0] {
                    for _ in 0..2 {
                        let mut u = [0.0; 3];
                        for a in 0..3 {
                            u[a] = c[a] as f64
                                + w * if a == axis {
                                    side
                                } else {
                                    0.05 + 0.9 * rng.f() as f64
                                };
                        }
                        let out = if side == 0.0 { -1.0 } else { 1.0 };
                        let mut across = u;
                        across[axis] += out * eps;
                        let Some(n) = leaf_at(&map, across) else {
                            continue;
                        };
                        if n[3] == c[3] {
                            continue;
                        }
                        let mut inside = u;
                        inside[axis] -= out * eps;
                        let at = |x: [f64; 3]| Vec3::new(x[0] as f32, x[1] as f32, x[2] as f32);
                        let (Some((a, ga)), Some((b, gb))) = (
                            vol.sample_with_gradient(at(inside)),
                            vol.sample_with_gradient(at(across)),
                        ) else {
                            panic!("no sample beside the face at {u:?}");
                        };
                        let slope = (ga[axis].abs() + gb[axis].abs()) as f64;
                        let allowed = 1.1 * eps * slope + 1e-5;
                        let jump = (a.value as f64 - b.value as f64).abs();
                        assert!(
                            jump <= allowed,
                            "jump {jump} > {allowed} across {u:?} (levels {} | {})",
                            c[3],
                            n[3]
                        );
                        worst = worst.max(jump / allowed);
                        let na = nearest.sample(at(inside)).unwrap().value;
                        let nb = nearest.sample(at(across)).unwrap().value;
                        nearest_jumps += ((na as f64 - nb as f64).abs() > allowed) as usize;
                        crossings += 1;
                    }
                }
            }
        }
        assert!(crossings > 2000, "{crossings} crossings");
        assert!(
            nearest_jumps > crossings / 2,
            "the check sees nearest's jumps at only {nearest_jumps} of {crossings}"
        );
        assert!(worst <= 1.0, "{worst}");
    }
}

/// The real AMRClaw frame (ExaBricks conversion): no jumps across its level
/// boundaries either (a face point per level-boundary face of 20,000 cells,
/// the check of [`no_jumps_across_level_boundaries`]); skipped with a
/// notice when the shared data is absent.
#[test]
fn real_frame_has_no_jumps_across_levels() {
    let Some(dir) = voxless_core::testing::shared_data("amr-euler3d/exabricks") else {
        return;
    };
    let scalars = [dir.join("frame3.density.scalars")];
    let data = voxless_io::read_exabricks(&dir.join("frame3.cells"), &scalars).unwrap();
    let input = AmrCells {
        cells: data.cells,
        fields: data.fields,
        origin: Vec3::ZERO,
        cell_size: 1.0,
    };
    let vol = AmrVolume::new(input.clone(), octant()).unwrap();
    let map: HashMap<[i32; 4], usize> = input
        .cells
        .iter()
        .enumerate()
        .map(|(i, &c)| (c, i))
        .collect();
    let eps = 1e-4f64;
    let mut rng = Lcg(43);
    let mut crossings = 0;
    for c in input.cells.iter().step_by(input.cells.len() / 20_000) {
        let w = (1i64 << c[3]) as f64;
        for axis in 0..3 {
            for (side, out) in [(0.0, -1.0), (1.0, 1.0)] {
                let u: [f64; 3] = [0, 1, 2].map(|a| {
                    let f = if a == axis {
                        side
                    } else {
                        0.05 + 0.9 * rng.f() as f64
                    };
                    c[a] as f64 + w * f
                });
                let (mut inside, mut across) = (u, u);
                inside[axis] -= out * eps;
                across[axis] += out * eps;
                match leaf_at(&map, across) {
                    Some(n) if n[3] != c[3] => {}
                    _ => continue,
                }
                let at = |x: [f64; 3]| Vec3::new(x[0] as f32, x[1] as f32, x[2] as f32);
                let (a, ga) = vol.sample_with_gradient(at(inside)).unwrap();
                let (b, gb) = vol.sample_with_gradient(at(across)).unwrap();
                let allowed = 1.1 * eps * (ga[axis].abs() + gb[axis].abs()) as f64 + 1e-5;
                let jump = (a.value as f64 - b.value as f64).abs();
                assert!(jump <= allowed, "jump {jump} > {allowed} across {u:?}");
                crossings += 1;
            }
        }
    }
    assert!(crossings > 500, "{crossings} crossings");
}

/// A constant field is reconstructed exactly, with a zero gradient, across
/// levels and holes.
#[test]
fn octant_constant_field_is_exact() {
    let input = cells_with(synthetic(35, true), |_| 3.25);
    let vol = AmrVolume::new(input.clone(), octant()).unwrap();
    let mut rng = Lcg(36);
    let mut n = 0;
    for _ in 0..20_000 {
        let (p, _) = world_and_units(&input, random_units(&mut rng, 0.0, 64.0));
        if let Some((s, g)) = vol.sample_with_gradient(p) {
            assert_eq!(s.value, 3.25, "at {p:?}");
            assert_eq!(g, Vec3::ZERO, "gradient of a constant at {p:?}");
            n += 1;
        }
    }
    assert!(n > 15_000, "{n}");
}

/// A linear field `a·x + b` sampled at the centres of a uniform grid (one
/// level, 40³ cells, several bricks) is reproduced exactly inside (points
/// at least a cell from the edge, where every box vertex has all its
/// cells), to 1e-5 relative; its gradient is `a` (world units) to 1e-4.
#[test]
fn octant_reproduces_linear_fields_on_one_level() {
    let a = [0.3f64, -0.2, 0.15];
    let b = 1.5f64;
    let cells: Vec<[i32; 4]> = (0..40 * 40 * 40)
        .map(|i| [i % 40, (i / 40) % 40, i / 1600, 0])
        .collect();
    let input = cells_with(cells, |c| {
        ((0..3).map(|k| a[k] * (c[k] as f64 + 0.5)).sum::<f64>() + b) as f32
    });
    let vol = AmrVolume::new(input.clone(), octant()).unwrap();
    assert!(vol.bricks().len() >= 8);
    let h = input.cell_size as f64;
    let mut rng = Lcg(37);
    for _ in 0..5000 {
        let (p, u) = world_and_units(&input, random_units(&mut rng, 1.0, 39.0));
        let want = (0..3).map(|k| a[k] * u[k]).sum::<f64>() + b;
        let (s, g) = vol.sample_with_gradient(p).unwrap();
        assert!(
            (s.value as f64 - want).abs() <= 1e-5 * want.abs().max(1.0),
            "at {u:?}: {} vs {want}",
            s.value
        );
        for k in 0..3 {
            let want = a[k] / h;
            assert!(
                (g[k] as f64 - want).abs() <= 1e-4 * want.abs(),
                "gradient at {u:?}: {g:?}"
            );
        }
    }
}

/// The analytic gradient equals central differences of the field with a
/// step of 0.02 finest cells wherever the stencil stays in one octant box
/// (the field is linear along each axis there, so the difference is exact
/// but for rounding): within 1e-3 of the largest component (at least 1).
#[test]
fn octant_gradient_matches_finite_differences() {
    for (seed, holes) in [(38, false), (39, true)] {
        let input = cells_with(synthetic(seed, holes), smooth);
        let vol = AmrVolume::new(input.clone(), octant()).unwrap();
        let r = Reference {
            cells: &input.cells,
            values: &input.fields[0].1,
        };
        let step = 0.02f64;
        let mut rng = Lcg(seed + 100);
        let mut checked = 0;
        for _ in 0..2000 {
            let u = random_units(&mut rng, 0.0, 64.0);
            let Some((_, g)) = vol.sample_with_gradient(world_and_units(&input, u).0) else {
                continue;
            };
            let mut fd = [0.0f64; 3];
            let mut one_box = true;
            for a in 0..3 {
                let (mut lo, mut hi) = (u, u);
                lo[a] -= step;
                hi[a] += step;
                one_box &= r.box_of(lo).is_some() && r.box_of(lo) == r.box_of(hi);
                let (Some(x), Some(y)) = (
                    vol.sample(world_and_units(&input, hi).0),
                    vol.sample(world_and_units(&input, lo).0),
                ) else {
                    one_box = false;
                    continue;
                };
                fd[a] = (x.value as f64 - y.value as f64) / (2.0 * step * input.cell_size as f64);
            }
            if !one_box {
                continue;
            }
            let scale = fd.iter().map(|v| v.abs()).fold(1.0, f64::max);
            for a in 0..3 {
                assert!(
                    (g[a] as f64 - fd[a]).abs() <= 1e-3 * scale,
                    "at {u:?}: analytic {g:?}, differences {fd:?}"
                );
            }
            checked += 1;
        }
        assert!(checked > 1500, "{checked}");
    }
}

/// A field of zeros with a spike of one in about one cell in twenty.
fn spikes(c: &[i32; 4]) -> f32 {
    let h = (c[0] as u32).wrapping_mul(73_856_093)
        ^ (c[1] as u32).wrapping_mul(19_349_663)
        ^ (c[2] as u32).wrapping_mul(83_492_791)
        ^ (c[3] as u32).wrapping_mul(2_654_435_761);
    h.is_multiple_of(20) as u8 as f32
}

/// Every octant sample along random rays lies in its interval's value
/// range — the regions' ranges of the tents, not widened — on a smooth
/// field and on a spiky one (where a range is often a single value and a
/// stray weight shows at once).
#[test]
fn every_octant_sample_lies_in_its_regions_value_range() {
    for field in [smooth, spikes] {
        octant_samples_in_ranges(cells_with(synthetic(9, true), field));
    }
}

/// Cell `X`'s weight — the field of values that are 1 in `X`, 0 elsewhere
/// — is zero outside `X` grown by half its width (its tent's support),
/// exactly, at random points of the box grown by a width and a half,
/// for cells of every level; and it is positive somewhere inside.
#[test]
fn octant_weights_vanish_outside_the_tent_support() {
    let cells = synthetic(41, true);
    let mut rng = Lcg(42);
    for level in 0..=3 {
        let xs: Vec<[i32; 4]> = cells.iter().copied().filter(|c| c[3] == level).collect();
        for _ in 0..6 {
            let x = xs[(rng.f() * xs.len() as f32) as usize % xs.len()];
            let mut input = cells_with(cells.clone(), |c| (*c == x) as u8 as f32);
            (input.origin, input.cell_size) = (Vec3::ZERO, 1.0);
            let vol = AmrVolume::new(input, octant()).unwrap();
            let w = (1i64 << level) as f32;
            let (mut inside, mut positive) = (0, 0);
            for _ in 0..3000 {
                let u = [0, 1, 2].map(|a| x[a] as f32 - 1.5 * w + rng.f() * 4.0 * w);
                let Some(s) = vol.sample(Vec3::new(u[0], u[1], u[2])) else {
                    continue;
                };
                let reach =
                    (0..3).all(|a| u[a] > x[a] as f32 - 0.5 * w && u[a] < x[a] as f32 + 1.5 * w);
                assert!(s.value >= 0.0, "{} at {u:?}", s.value);
                if reach {
                    inside += 1;
                    positive += (s.value > 0.0) as usize;
                } else {
                    assert_eq!(s.value, 0.0, "cell {x:?} weighs {} at {u:?}", s.value);
                }
            }
            assert!(positive > inside / 4, "{positive} of {inside}");
        }
    }
}

/// Checks the samples along random rays against their intervals' ranges.
fn octant_samples_in_ranges(input: AmrCells) {
    let vol = AmrVolume::new(input, octant()).unwrap();
    let mut rng = Lcg(40);
    let mut out = Vec::new();
    let mut samples = 0;
    for _ in 0..400 {
        let b = vol.bounds();
        let o = b.center() + Vec3::new(rng.f() - 0.5, rng.f() - 0.5, 3.0) * b.diagonal();
        let target = b.min + Vec3::new(rng.f(), rng.f(), rng.f()).mul_elem(b.extent());
        let ray = Ray::new(o, (target - o).normalized());
        out.clear();
        vol.intervals(
            &ray,
            Range1::new(0.0, f32::INFINITY),
            &IntervalQuery::all(),
            &mut out,
        );
        for iv in &out {
            for k in 0..32 {
                let t = iv.t.lo + (k as f32 + 0.5) / 32.0 * iv.t.span();
                let Some(s) = vol.sample_in(ray.at(t), iv) else {
                    continue;
                };
                let r = iv.value_range;
                assert!(
                    s.value >= r.lo - 1e-6 && s.value <= r.hi + 1e-6,
                    "{} outside {r:?}",
                    s.value
                );
                samples += 1;
            }
        }
    }
    assert!(samples > 50_000, "{samples}");
}

/// The ray's parameter range inside cell `c` (f64; half-open cells, faces
/// of an axis-parallel ray compared in `f32` world coordinates).
fn chord(input: &AmrCells, c: &[i32; 4], ray: &Ray) -> Option<(f64, f64)> {
    let w = (1i64 << c[3]) as f64;
    let h = input.cell_size as f64;
    let (mut a, mut z) = (f64::NEG_INFINITY, f64::INFINITY);
    for ax in 0..3 {
        let lo = input.origin[ax] as f64 + c[ax] as f64 * h;
        let (o, d) = (ray.origin[ax] as f64, ray.dir[ax] as f64);
        if d == 0.0 {
            let world = |k: i32| input.origin[ax] + k as f32 * input.cell_size;
            if !(ray.origin[ax] >= world(c[ax]) && ray.origin[ax] < world(c[ax] + (1 << c[3]))) {
                return None;
            }
            continue;
        }
        let (ta, tb) = ((lo - o) / d, (lo + w * h - o) / d);
        a = a.max(ta.min(tb));
        z = z.min(ta.max(tb));
    }
    (z > a).then_some((a, z))
}

/// Random rays through the bounds and rays along z in a cell face, a
/// cell's centre plane and at a general place.
fn test_rays(rng: &mut Lcg, b: &Aabb, h: f32, n: usize) -> Vec<Ray> {
    let mut rays: Vec<Ray> = (0..n)
        .map(|_| {
            let o = b.center()
                + Vec3::new(rng.f() - 0.5, rng.f() - 0.5, rng.f() - 0.5) * (3.0 * b.diagonal());
            let target = b.min + b.extent().mul_elem(Vec3::new(rng.f(), rng.f(), rng.f()));
            Ray::new(o, (target - o).normalized())
        })
        .collect();
    let c = b.center();
    for (dx, dy) in [
        (0.0, 0.0),
        (0.5 * h, 0.0),
        (0.5 * h, 0.5 * h),
        (4.3 * h, 8.1 * h),
    ] {
        rays.push(Ray::new(
            Vec3::new(c.x + dx, c.y + dy, b.min.z - 1.0),
            Vec3::new(0.0, 0.0, 1.0),
        ));
    }
    rays
}

/// The exact line integral (two Gauss nodes per piece between box planes)
/// equals the midpoint rule with 1024 points over each cell's chord (brute
/// force over all cells) to 1e-5 relative, on levels 0–3 with holes.
#[test]
fn octant_line_integral_equals_fine_quadrature_of_samples() {
    let input = cells_with(synthetic(44, true), smooth);
    let vol = AmrVolume::new(input.clone(), octant()).unwrap();
    let all = Range1::new(f32::NEG_INFINITY, f32::INFINITY);
    let mut rng = Lcg(45);
    for ray in test_rays(&mut rng, &vol.bounds(), input.cell_size, 16) {
        let mut want = 0.0;
        for c in &input.cells {
            let Some((a, z)) = chord(&input, c, &ray) else {
                continue;
            };
            let n = 1024;
            let step = (z - a) / n as f64;
            let f = |s: f64| {
                let p = [0, 1, 2].map(|k| (ray.origin[k] as f64 + ray.dir[k] as f64 * s) as f32);
                vol.sample(Vec3::new(p[0], p[1], p[2]))
                    .map_or(0.0, |x| x.value as f64)
            };
            want += (0..n).map(|k| f(a + (k as f64 + 0.5) * step)).sum::<f64>() * step;
        }
        let got = vol.line_integral(&ray, all);
        let rel = (got - want).abs() / want.abs().max(1e-3);
        assert!(
            rel <= 1e-5,
            "exact {got} vs quadrature {want} ({rel:.1e}) along {ray:?}"
        );
    }
}

/// A constant field integrates to the value times the length inside the
/// cells (holes left out), along random and axis-parallel rays.
#[test]
fn octant_line_integral_of_a_constant_is_value_times_length() {
    let input = cells_with(synthetic(46, true), |_| 2.5);
    let vol = AmrVolume::new(input.clone(), octant()).unwrap();
    let all = Range1::new(f32::NEG_INFINITY, f32::INFINITY);
    let mut rng = Lcg(47);
    for ray in test_rays(&mut rng, &vol.bounds(), input.cell_size, 100) {
        let length: f64 = input
            .cells
            .iter()
            .filter_map(|c| chord(&input, c, &ray))
            .map(|(a, z)| z - a)
            .sum();
        let got = vol.line_integral(&ray, all);
        assert!(
            (got - 2.5 * length).abs() <= 1e-9 * (2.5 * length).max(1.0),
            "{got} vs {}",
            2.5 * length
        );
    }
}
