//! The fast paths against the slow paths they replaced: the front-to-back
//! walk of the region tree against every region the BVH hits, sorted; the
//! walk a chunk at a time against the whole list; the packet batch and
//! eight samples in lanes against point samples; and whole renders — rays
//! in lanes and packet passes against point by point, lazy intervals
//! against the sorted lists — pixel for pixel.

use voxless_core::{
    Aabb, Camera, Control, Interval, IntervalLists, IntervalQuery, Prepare, PrepareQuery, Range1,
    Ray, Sample, SampleBatch, Simd, TileRays, Vec3, View, Volume,
};
use voxless_render::{Light, RenderSettings, render};
use voxless_transfer::{Colormap, OpacityMap, TransferFunction};

use super::tests::{cells_with, smooth, synthetic};
use super::*;
use crate::regions::KdNode;
use voxless_core::SmallRng as Lcg;

/// Rays from outside and inside the bounds in random directions, and
/// axis-parallel rays lying in cut planes (half-open faces) and along
/// cell centres.
fn rays(vol: &AmrVolume, rng: &mut Lcg, n: usize) -> Vec<Ray> {
    let b = vol.bounds();
    let c = b.center();
    let r = b.diagonal();
    let (o, h) = (vol.origin(), vol.cell_size());
    (0..n)
        .map(|k| match k % 4 {
            0 => {
                let d = direction(rng);
                Ray::new(c - d * r + (rng.v() - Vec3::splat(0.5)) * (0.6 * r), d)
            }
            1 => {
                let p = b.min + Vec3::new(rng.f(), rng.f(), rng.f()).mul_elem(b.extent());
                Ray::new(p, direction(rng))
            }
            _ => {
                // Along an axis, in planes at multiples of half a finest
                // cell: region faces, cell faces and cell centres.
                let axis = (rng.f() * 3.0) as usize % 3;
                let q = b.min + Vec3::new(rng.f(), rng.f(), rng.f()).mul_elem(b.extent());
                let mut p = [0, 1, 2].map(|a| {
                    let u = ((q[a] - o[a]) / h * 2.0).round() * 0.5;
                    o[a] + u * h
                });
                let mut d = [0.0; 3];
                d[axis] = if rng.f() < 0.5 { 1.0 } else { -1.0 };
                p[axis] = c[axis] - d[axis] * r;
                Ray::new(Vec3::from_array(p), Vec3::from_array(d))
            }
        })
        .collect()
}

/// A random unit vector.
fn direction(rng: &mut Lcg) -> Vec3 {
    Vec3::new(rng.normal(), rng.normal(), rng.normal()).normalized()
}

fn volumes() -> Vec<AmrVolume> {
    [(31, true), (32, false), (33, true)]
        .into_iter()
        .map(|(seed, holes)| {
            AmrVolume::new(
                cells_with(synthetic(seed, holes), smooth),
                AmrSettings::default(),
            )
            .unwrap()
        })
        .collect()
}

#[test]
fn the_tree_cuts_the_bounds_into_exactly_the_regions_in_order() {
    for vol in volumes() {
        let tree = &vol.region_set().tree;
        let mut leaves = Vec::new();
        // Depth first: (node, box in doubled units).
        let lo = (0..3).map(|a| vol.regions().iter().map(|r| r.lo[a]).min().unwrap());
        let hi = (0..3).map(|a| vol.regions().iter().map(|r| r.hi[a]).max().unwrap());
        let root: ([i64; 3], [i64; 3]) = (
            lo.collect::<Vec<_>>().try_into().unwrap(),
            hi.collect::<Vec<_>>().try_into().unwrap(),
        );
        let mut stack = vec![(0usize, root)];
        while let Some((i, (lo, hi))) = stack.pop() {
            match tree[i] {
                KdNode::Inner { axis, at, right } => {
                    let a = axis as usize;
                    assert!(lo[a] < at && at < hi[a], "cut {at} outside {lo:?}..{hi:?}");
                    let (mut left_hi, mut right_lo) = (hi, lo);
                    left_hi[a] = at;
                    right_lo[a] = at;
                    // Right pushed first: the left subtree is visited first.
                    stack.push((i + right as usize, (right_lo, hi)));
                    stack.push((i + 1, (lo, left_hi)));
                }
                KdNode::Leaf(r) => {
                    let region = &vol.regions()[r as usize];
                    assert_eq!((region.lo, region.hi), (lo, hi), "region {r}");
                    leaves.push(r);
                }
                KdNode::Hole => {}
            }
        }
        let want: Vec<u32> = (0..vol.regions().len() as u32).collect();
        assert_eq!(leaves, want, "leaves are the regions, in order");
    }
}

#[test]
fn walk_gives_the_sorted_intervals_of_every_region_the_ray_hits() {
    let mut rng = Lcg(40);
    let hide = |r: Range1| r.hi > 1.2; // about half the regions
    let queries = [IntervalQuery::all(), IntervalQuery { is_visible: &hide }];
    let mut compared = 0;
    for vol in volumes() {
        for ray in rays(&vol, &mut rng, 2000) {
            let t = Range1::new(0.0, f32::INFINITY);
            for query in &queries {
                let (mut want, mut got) = (Vec::new(), Vec::new());
                vol.region_intervals_sorted(&ray, t, query, &mut want);
                vol.intervals(&ray, t, query, &mut got);
                assert_eq!(got, want, "{ray:?}");
                compared += got.len();
                for w in got.windows(2) {
                    assert!(w[0].t.hi <= w[1].t.lo, "overlap {w:?}");
                }
            }
        }
    }
    assert!(compared > 50_000, "only {compared} intervals compared");
}

#[test]
fn an_interval_over_several_regions_samples_like_point_location() {
    // Touching regions of one brick list are one interval whose hint is
    // the first region: every point of it must reconstruct as the region
    // that point location finds.
    let mut rng = Lcg(43);
    let (mut merged, mut points) = (0, 0);
    for vol in volumes() {
        let groups = vol.region_groups();
        for ray in rays(&vol, &mut rng, 1500) {
            let mut ivs = Vec::new();
            let t = Range1::new(0.0, f32::INFINITY);
            vol.intervals(&ray, t, &IntervalQuery::all(), &mut ivs);
            for iv in &ivs {
                let mut spans_regions = false;
                for k in 1..16 {
                    let tp = iv.t.lo + iv.t.span() * (k as f32 / 16.0);
                    let p = ray.at(tp);
                    let Some(at) = vol.locate(p) else { continue };
                    // A point on a region's face (rays in cut planes), or
                    // rounded off the ray into a neighbour (slivers where a
                    // ray grazes an edge), may be located in either region:
                    // only points strictly inside the region found, at a
                    // `t` strictly inside its part of the ray, are compared.
                    let b = vol.region_bounds(at);
                    let hit = b.clip_ray(&ray, t);
                    if (0..3).any(|a| !(b.min[a] < p[a] && p[a] < b.max[a]))
                        || !(hit.lo < tp && tp < hit.hi)
                    {
                        continue;
                    }
                    assert_eq!(groups[at], groups[iv.hint as usize], "{p:?} in {iv:?}");
                    spans_regions |= at != iv.hint as usize;
                    let (a, b) = (vol.sample_in(p, iv), vol.sample(p));
                    let (a, b) = (a.expect("hinted").value, b.expect("located").value);
                    assert_eq!(a.to_bits(), b.to_bits(), "{p:?}: {a} vs {b}");
                    points += 1;
                }
                merged += spans_regions as usize;
            }
        }
    }
    assert!(merged > 100, "only {merged} intervals span several regions");
    assert!(points > 10_000, "only {points} points compared");
}

#[test]
fn the_walk_a_chunk_at_a_time_is_the_whole_list() {
    let mut rng = Lcg(41);
    for vol in volumes() {
        let ctx = AmrContext::new(&vol, &|r| r.hi > 1.0);
        for ray in rays(&vol, &mut rng, 600) {
            let t = vol.bounds().clip_ray(&ray, Range1::new(0.0, f32::INFINITY));
            let query = IntervalQuery::all();
            for v in [&vol as &dyn ChunkedVolume, &ctx] {
                let mut whole = Vec::new();
                v.all(&ray, t, &query, &mut whole);
                for max in [1, 2, 5] {
                    let mut got = Vec::new();
                    let mut lo = t.lo;
                    while let Some(rest) =
                        v.chunk(&ray, Range1::new(lo, t.hi), &query, &mut got, max)
                    {
                        assert!(rest > lo, "no progress at {lo}");
                        lo = rest;
                    }
                    assert_eq!(got, whole, "chunks of {max}");
                }
            }
        }
    }
}

/// The two interval entries of a volume, object-safe for the test above.
trait ChunkedVolume {
    fn all(&self, ray: &Ray, t: Range1, q: &IntervalQuery, out: &mut Vec<Interval>);
    fn chunk(
        &self,
        ray: &Ray,
        t: Range1,
        q: &IntervalQuery,
        out: &mut Vec<Interval>,
        max: usize,
    ) -> Option<f32>;
}

impl<V: Volume> ChunkedVolume for V {
    fn all(&self, ray: &Ray, t: Range1, q: &IntervalQuery, out: &mut Vec<Interval>) {
        self.intervals(ray, t, q, out)
    }
    fn chunk(
        &self,
        ray: &Ray,
        t: Range1,
        q: &IntervalQuery,
        out: &mut Vec<Interval>,
        max: usize,
    ) -> Option<f32> {
        self.intervals_chunk(ray, t, q, out, max)
    }
}

#[test]
fn a_context_walks_exactly_the_regions_its_transfer_function_sees() {
    let mut rng = Lcg(42);
    let seen = |r: Range1| r.hi > 1.5 || r.lo < -1.0;
    for vol in volumes() {
        let ctx = AmrContext::new(&vol, &seen);
        assert!(ctx.visible_region_count() < vol.regions().len());
        assert_eq!(ctx.visible_region_count(), vol.visible_region_count(&seen));
        for ray in rays(&vol, &mut rng, 1000) {
            let t = Range1::new(0.0, f32::INFINITY);
            let (mut want, mut got) = (Vec::new(), Vec::new());
            vol.region_intervals_sorted(&ray, t, &IntervalQuery { is_visible: &seen }, &mut want);
            ctx.intervals(&ray, t, &IntervalQuery::all(), &mut got);
            assert_eq!(got, want);
        }
    }
}

#[test]
fn a_tile_walked_in_packets_gets_every_rays_own_list() {
    // Rays in every octant, axis rays in cut planes (±0 components), rays
    // that miss, empty and partial ranges; packets cut short by a tile's
    // edges, and packets that straddle octants.
    let mut rng = Lcg(43);
    let seen = |r: Range1| r.hi > 1.2;
    let mut compared = 0;
    for vol in volumes() {
        // The walk's lanes on every SIMD backend this CPU has.
        let backends = Simd::ALL.into_iter().filter(|s| s.available());
        let contexts = backends.flat_map(|simd| {
            [
                AmrContext::new(&vol, &|_| true).with_simd(simd),
                AmrContext::new(&vol, &seen).with_simd(simd),
            ]
        });
        for ctx in contexts {
            let view = View {
                camera: Camera::framing(&vol.bounds(), 1.0),
                width: 8,
                height: 8,
            };
            let tiles = ctx
                .tile_view(&view)
                .expect("an AMR context has a tile view");
            let all = rays(&vol, &mut rng, 1300);
            // Tiles of 5 × 3 rays (the last 5 × 2): packets of 4 × 2 cut
            // at the tile's edges.
            for chunk in all.chunks(15) {
                let t: Vec<Range1> = chunk
                    .iter()
                    .map(|_| match (rng.f() * 4.0) as u32 {
                        0 => Range1::EMPTY,
                        1 => Range1::new(rng.f() * 2.0, 2.0 + rng.f() * 3.0),
                        _ => Range1::new(0.0, f32::INFINITY),
                    })
                    .collect();
                let mut got = IntervalLists::default();
                let tile = TileRays {
                    x0: 0,
                    y0: 0,
                    w: 5,
                    h: chunk.len() as u32 / 5,
                    rays: chunk,
                    t: &t,
                    centred: true,
                };
                tiles.intervals(&tile, &IntervalQuery::all(), &mut got);
                assert_eq!(got.rays(), chunk.len());
                for (k, (ray, &t)) in chunk.iter().zip(&t).enumerate() {
                    let mut want = Vec::new();
                    ctx.intervals(ray, t, &IntervalQuery::all(), &mut want);
                    assert_eq!(got.of(k), &want[..], "{ray:?} {t:?}");
                    compared += want.len();
                }
            }
        }
    }
    assert!(compared > 20_000, "only {compared} intervals compared");
}

#[test]
fn a_batch_gives_the_bits_of_point_samples() {
    let input = cells_with(synthetic(34, true), smooth);
    for settings in [
        AmrSettings::default(),
        AmrSettings {
            color_field: Some(1),
            ..Default::default()
        },
        AmrSettings {
            reconstruction: Reconstruction::Nearest,
            ..Default::default()
        },
    ] {
        let vol = AmrVolume::new(input.clone(), settings).unwrap();
        let mut rng = Lcg(43);
        let rays = rays(&vol, &mut rng, 64);
        let (mut offsets, mut ts, mut hints, mut ivs) =
            (vec![0u32], Vec::new(), Vec::new(), Vec::new());
        for ray in &rays {
            let mut list = Vec::new();
            vol.intervals(
                ray,
                Range1::new(0.0, f32::INFINITY),
                &IntervalQuery::all(),
                &mut list,
            );
            for (j, iv) in list.iter().enumerate() {
                // 1 to 19 samples per interval, as packet windows take
                // them: runs that fill no lanes, some, and more than 2 × 8.
                let m = 1 + (j * 7 + ray_index(ray)) % 19;
                for k in 0..m {
                    ts.push(iv.t.lo + iv.t.span() * (0.05 + 0.9 * k as f32 / m as f32));
                    hints.push(iv.hint);
                    ivs.push(*iv);
                }
            }
            offsets.push(ts.len() as u32);
        }
        let batch = |hints| SampleBatch {
            rays: &rays,
            offsets: &offsets,
            t: &ts,
            hints,
        };
        // Every SIMD backend (the value-only batch runs in lanes) against
        // the scalar point path.
        let backends = voxless_core::Simd::ALL
            .into_iter()
            .filter(|s| s.available());
        for (simd, gradient) in backends.flat_map(|s| [(s, false), (s, true)]) {
            for with_hints in [true, false] {
                let mut out = Vec::new();
                let b = batch(with_hints.then_some(&hints[..]));
                vol.sample_batch_on(simd, &b, gradient, &mut out);
                assert_eq!(out.len(), ts.len());
                let mut i = 0;
                for (r, ray) in rays.iter().enumerate() {
                    for &t in batch(None).samples(r) {
                        let p = ray.at(t);
                        let want: (Option<Sample>, Vec3) = match (with_hints, gradient) {
                            (true, false) => (vol.sample_in(p, &ivs[i]), Vec3::ZERO),
                            (true, true) => vol
                                .sample_with_gradient_in(p, &ivs[i])
                                .map_or((None, Vec3::ZERO), |(s, g)| (Some(s), g)),
                            (false, false) => (vol.sample(p), Vec3::ZERO),
                            (false, true) => vol
                                .sample_with_gradient(p)
                                .map_or((None, Vec3::ZERO), |(s, g)| (Some(s), g)),
                        };
                        assert_eq!(out[i], want, "{simd:?}: sample {i} at {p:?}");
                        i += 1;
                    }
                }
                if gradient {
                    continue;
                }
                // Values alone: the same bits, NaN where there is no
                // sample; refused (and `values` untouched) with a colour
                // field, whose samples carry more than a value.
                let mut values = vec![7.0; 3];
                let plain = vol.sample_batch_values_on(simd, &b, &mut values);
                assert_eq!(plain, vol.settings().color_field.is_none());
                if !plain {
                    assert_eq!(values, [7.0; 3]);
                    continue;
                }
                assert_eq!(values.len(), out.len());
                for (k, (v, (want, _))) in values.iter().zip(&out).enumerate() {
                    match want {
                        Some(s) => assert_eq!(v.to_bits(), s.value.to_bits(), "{simd:?}: {k}"),
                        None => assert!(v.is_nan(), "{simd:?}: {k} has no sample"),
                    }
                }
            }
        }
    }
}

/// A small number that differs between rays (to vary the test's runs).
fn ray_index(ray: &Ray) -> usize {
    (ray.dir.x.to_bits() % 5) as usize
}

/// An AMR volume as it was handed out before the walk: every region's
/// interval found through the BVH and sorted, all at once, and sampled
/// point by point.
struct SortAll<'a>(&'a AmrVolume);

impl Volume for SortAll<'_> {
    fn bounds(&self) -> Aabb {
        self.0.bounds()
    }
    fn value_range(&self) -> Range1 {
        self.0.value_range()
    }
    fn attribute_range(&self) -> Option<Range1> {
        self.0.attribute_range()
    }
    fn sample(&self, p: Vec3) -> Option<Sample> {
        self.0.sample(p)
    }
    fn gradient(&self, p: Vec3) -> Vec3 {
        self.0.gradient(p)
    }
    fn sample_with_gradient(&self, p: Vec3) -> Option<(Sample, Vec3)> {
        self.0.sample_with_gradient(p)
    }
    fn sample_in(&self, p: Vec3, iv: &Interval) -> Option<Sample> {
        self.0.sample_in(p, iv)
    }
    fn sample_with_gradient_in(&self, p: Vec3, iv: &Interval) -> Option<(Sample, Vec3)> {
        self.0.sample_with_gradient_in(p, iv)
    }
    fn intervals(&self, ray: &Ray, t: Range1, query: &IntervalQuery, out: &mut Vec<Interval>) {
        self.0.region_intervals_sorted(ray, t, query, out)
    }
}

impl Prepare for SortAll<'_> {
    type Prepared<'b>
        = &'b Self
    where
        Self: 'b;
    fn prepare<'b>(&'b self, _: &PrepareQuery) -> &'b Self {
        self
    }
}

fn max_diff(a: &voxless_core::Image, b: &voxless_core::Image) -> f32 {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(p, q)| (0..4).map(move |c| (p[c] - q[c]).abs()))
        .fold(0.0, f32::max)
}

#[test]
fn packets_and_lazy_intervals_draw_the_image_of_sorted_lists_sampled_point_by_point() {
    let input = cells_with(synthetic(35, true), smooth);
    let tf = TransferFunction::new(
        Colormap::preset("viridis").unwrap(),
        OpacityMap::preset("ramp-high").unwrap(),
    );
    for (what, amr, tweak) in [
        ("density", AmrSettings::default(), 0),
        (
            "colour field",
            AmrSettings {
                color_field: Some(1),
                ..Default::default()
            },
            0,
        ),
        ("shaded", AmrSettings::default(), 1),
        ("iso-surfaces, 2 spp", AmrSettings::default(), 2),
        ("clip box, opaque", AmrSettings::default(), 3),
        ("a box of a decomposition", AmrSettings::default(), 4),
        (
            "nearest",
            AmrSettings {
                reconstruction: Reconstruction::Nearest,
                ..Default::default()
            },
            0,
        ),
    ] {
        let vol = AmrVolume::new(input.clone(), amr).unwrap();
        let camera = Camera::framing(&vol.bounds(), 1.1);
        let mut settings = RenderSettings::for_volume(&vol, 40, 32);
        settings.opacity_scale *= 3.0;
        settings.simd = Simd::Auto;
        match tweak {
            1 => {
                settings.light = Some(Light {
                    direction: Vec3::new(0.3, 0.5, 0.8).normalized(),
                    ambient: 0.3,
                })
            }
            2 => {
                settings.iso = vec![0.5, 1.5];
                settings.iso_opacity = 0.6;
                settings.spp = 2;
            }
            3 => {
                let b = vol.bounds();
                settings.clip = Some(Aabb::new(b.min, b.center() + b.extent() * 0.2));
                settings.opacity_scale *= 20.0;
            }
            4 => {
                // One box of a decomposition: only the samples it owns.
                let b = vol.bounds();
                settings.domain = Some(voxless_render::Domain {
                    owned: Aabb::new(b.min - b.extent(), b.center() + b.extent() * 0.2),
                    bounds: b,
                });
            }
            _ => {}
        }
        let run = |v: &dyn Fn(&RenderSettings) -> voxless_core::Image, packets: bool| {
            let mut s = settings.clone();
            s.packets = packets;
            v(&s)
        };
        let fast = |s: &RenderSettings| render(&vol, &camera, &tf, s, &Control::new()).unwrap();
        let slow =
            |s: &RenderSettings| render(&SortAll(&vol), &camera, &tf, s, &Control::new()).unwrap();
        let reference = run(&slow, false);
        let lit = reference.pixels.iter().filter(|p| p[3] > 0.05).count();
        assert!(lit > 100, "{what}: too little is visible ({lit} pixels)");
        // The same samples, evaluated with the same arithmetic: identical.
        let passes = |s: &RenderSettings| {
            let s = RenderSettings {
                lanes: false,
                ..s.clone()
            };
            fast(&s)
        };
        for (name, image) in [
            ("packets (rays in lanes where they apply)", run(&fast, true)),
            ("packet passes", run(&passes, true)),
            ("point by point", run(&fast, false)),
        ] {
            let d = max_diff(&reference, &image);
            assert!(d == 0.0, "{what}, {name}: differs by {d}");
        }
    }
}

#[test]
fn a_constant_field_reconstructs_to_the_constant_exactly() {
    // Across bricks of three levels and their boundaries, the normalised
    // basis sum of a constant is the constant to the bit — point by point
    // and in the batch, on every backend (the CLI's constant-field check
    // and users' probes rely on it).
    for value in [3.0f32, 0.1, 1.0e-20, 7.3e12] {
        let vol = AmrVolume::new(
            cells_with(synthetic(34, true), |_| value),
            AmrSettings::default(),
        )
        .unwrap();
        let mut rng = Lcg(7);
        let rays = rays(&vol, &mut rng, 48);
        let (mut offsets, mut ts) = (vec![0u32], Vec::new());
        for ray in &rays {
            let mut list = Vec::new();
            let all = Range1::new(0.0, f32::INFINITY);
            vol.intervals(ray, all, &IntervalQuery::all(), &mut list);
            for iv in &list {
                ts.extend((0..5).map(|k| iv.t.lo + iv.t.span() * (0.1 + 0.2 * k as f32)));
            }
            offsets.push(ts.len() as u32);
        }
        let batch = SampleBatch {
            rays: &rays,
            offsets: &offsets,
            t: &ts,
            hints: None,
        };
        let mut seen = 0;
        for simd in voxless_core::Simd::ALL
            .into_iter()
            .filter(|s| s.available())
        {
            let mut out = Vec::new();
            vol.sample_batch_on(simd, &batch, false, &mut out);
            for s in out.iter().filter_map(|x| x.0) {
                assert_eq!(s.value, value, "{simd:?}");
                seen += 1;
            }
        }
        for (r, ray) in rays.iter().enumerate() {
            for &t in batch.samples(r) {
                if let Some(s) = vol.sample(ray.at(t)) {
                    assert_eq!(s.value, value);
                }
            }
        }
        assert!(seen > 1000, "too few samples ({seen})");
    }
}

/// Groups of eight points, one per lane, sampled in lanes on `simd`.
struct LaneSamples<'a> {
    vol: &'a AmrVolume,
    groups: &'a [([u32; 8], [Vec3; 8], u32)],
}

impl voxless_core::simd::WithLanes for LaneSamples<'_> {
    type Output = Vec<[f32; 8]>;
    #[inline(always)]
    fn run<L: voxless_core::Lanes>(self) -> Vec<[f32; 8]> {
        self.groups
            .iter()
            .map(|(hints, p, live)| {
                let axis = |a: usize| L::from_array(p.map(|q| q[a]));
                let p = [axis(0), axis(1), axis(2)];
                self.vol
                    .sample_values_lanes::<L>(hints, p, *live)
                    .to_array()
            })
            .collect()
    }
}

#[test]
fn eight_lanes_give_the_bits_of_point_samples() {
    let input = cells_with(synthetic(34, true), smooth);
    for (settings, offered) in [
        (AmrSettings::default(), true),
        (
            AmrSettings {
                color_field: Some(1),
                ..Default::default()
            },
            false,
        ),
        (
            AmrSettings {
                reconstruction: Reconstruction::Nearest,
                ..Default::default()
            },
            false,
        ),
    ] {
        let vol = AmrVolume::new(input.clone(), settings).unwrap();
        assert_eq!(vol.samples_in_lanes(), offered);
        if !offered {
            continue;
        }
        // Points along rays, each with its interval's hint, in order.
        let mut rng = Lcg(71);
        let mut points = Vec::new();
        for ray in rays(&vol, &mut rng, 64) {
            let mut list = Vec::new();
            let all = Range1::new(0.0, f32::INFINITY);
            vol.intervals(&ray, all, &IntervalQuery::all(), &mut list);
            for iv in &list {
                for k in 0..3 {
                    let p = ray.at(iv.t.lo + iv.t.span() * (0.1 + 0.4 * k as f32));
                    points.push((iv.hint, p));
                }
            }
        }
        // Eight consecutive points (a few regions, often one list for all
        // lanes), eight picked at random (regions all different: lists
        // merged), lanes left out, and lanes with no region named (found
        // point by point).
        let mut groups = Vec::new();
        for (g, chunk) in points.chunks(8).enumerate() {
            let mut hints = [Interval::NO_HINT; 8];
            let mut p = [Vec3::ZERO; 8];
            for (k, &(h, q)) in chunk.iter().enumerate() {
                (hints[k], p[k]) = (h, q);
            }
            let live = (1u32 << chunk.len()) - 1;
            groups.push((hints, p, live));
            let mut mixed = (hints, p, 0u32);
            for k in 0..8 {
                let (h, q) = points[(rng.f() * points.len() as f32) as usize % points.len()];
                (mixed.0[k], mixed.1[k]) = (h, q);
                if rng.f() < 0.85 {
                    mixed.2 |= 1 << k;
                }
                if g % 5 == 0 && k == 3 {
                    mixed.0[k] = Interval::NO_HINT;
                }
            }
            groups.push(mixed);
        }
        let backends = Simd::ALL.into_iter().filter(|s| s.available());
        let mut compared = 0;
        for simd in backends {
            let got = voxless_core::simd::dispatch(
                simd,
                LaneSamples {
                    vol: &vol,
                    groups: &groups,
                },
            );
            for ((hints, p, live), got) in groups.iter().zip(&got) {
                for k in 0..8 {
                    if live >> k & 1 == 0 {
                        assert!(got[k].is_nan(), "{simd:?}: lane {k} has no sample");
                        continue;
                    }
                    let want = match hints[k] {
                        Interval::NO_HINT => vol.sample(p[k]),
                        h => {
                            let iv = Interval {
                                hint: h,
                                ..Interval::sampled(Range1::EMPTY, Range1::EMPTY, 1.0)
                            };
                            vol.sample_in(p[k], &iv)
                        }
                    };
                    match want {
                        Some(s) => assert_eq!(got[k].to_bits(), s.value.to_bits(), "{simd:?}"),
                        None => assert!(got[k].is_nan(), "{simd:?}: no data at {:?}", p[k]),
                    }
                    compared += 1;
                }
            }
        }
        assert!(compared > 10_000, "only {compared} lanes compared");
    }
}
