use super::*;
use voxless_core::SmallRng as Lcg;

fn random_boxes(n: usize, seed: u64, max_r: f32) -> Vec<Aabb> {
    let mut rng = Lcg(seed);
    (0..n)
        .map(|_| Aabb::around(rng.v(), rng.f() * max_r))
        .collect()
}

#[test]
fn point_query_equals_brute_force() {
    for &n in &[1usize, 2, 3, 17, 1000, 20_000] {
        let prims = random_boxes(n, n as u64, 0.05);
        let bvh = Bvh::build(&prims);
        bvh.validate(&prims).unwrap();
        assert_point_queries_exact(&bvh, &prims, 99);
    }
}

#[test]
fn ray_query_equals_brute_force() {
    let prims = random_boxes(5000, 7, 0.03);
    let bvh = Bvh::build(&prims);
    let mut rng = Lcg(3);
    for _ in 0..200 {
        let o = rng.v() * 3.0 - Vec3::ONE;
        let d = (rng.v() - Vec3::splat(0.5)).normalized();
        let ray = Ray::new(o, d);
        let t = Range1::new(0.0, 10.0);
        let mut got = Vec::new();
        bvh.ray_query(&ray, t, |i, _| got.push(i));
        got.sort_unstable();
        let want: Vec<u32> = (0..prims.len() as u32)
            .filter(|&i| !prims[i as usize].clip_ray(&ray, t).is_empty())
            .collect();
        assert_eq!(got, want);
    }
}

#[test]
fn refit_after_growth_stays_valid_and_exact() {
    let mut prims = random_boxes(3000, 5, 0.01);
    let mut bvh = Bvh::build(&prims);
    // Grow every box (a radius change): the topology stays, boxes update.
    for b in prims.iter_mut() {
        *b = Aabb::around(b.center(), b.extent().x * 4.0 + 0.02);
    }
    bvh.refit(&prims);
    bvh.validate(&prims).unwrap();
    assert_point_queries_exact(&bvh, &prims, 11);
}

#[test]
fn duplicates_and_degenerate_boxes() {
    // All primitives at one point: keys are equal, the split falls back to the middle.
    let prims = vec![Aabb::around(Vec3::splat(0.5), 0.1); 10_000];
    let bvh = Bvh::build(&prims);
    bvh.validate(&prims).unwrap();
    let mut count = 0;
    bvh.point_query(Vec3::splat(0.5), |_| count += 1);
    assert_eq!(count, 10_000);
    // Empty boxes are kept but never hit.
    let mut prims = random_boxes(100, 1, 0.1);
    prims[10] = Aabb::EMPTY;
    let bvh = Bvh::build(&prims);
    bvh.validate(&prims).unwrap();
    bvh.point_query(prims[11].center(), |i| assert_ne!(i, 10));
    // Zero primitives.
    let bvh = Bvh::build(&[]);
    bvh.validate(&[]).unwrap();
    bvh.point_query(Vec3::ZERO, |_| panic!("empty tree visited"));
}

#[test]
fn validate_catches_a_bad_box() {
    let prims = random_boxes(100, 2, 0.1);
    let bvh = Bvh::build(&prims);
    let mut wrong = prims.clone();
    wrong[5] = Aabb::around(Vec3::splat(5.0), 1.0);
    assert!(bvh.validate(&wrong).is_err());
}

#[test]
fn rebuild_reuses_buffers() {
    let prims = random_boxes(10_000, 4, 0.01);
    let mut bvh = Bvh::build(&prims);
    let cap = bvh.nodes.capacity();
    let fewer = random_boxes(8_000, 6, 0.01);
    bvh.rebuild(&fewer);
    bvh.validate(&fewer).unwrap();
    assert_eq!(bvh.nodes.capacity(), cap);
}

#[test]
fn in_order_build_answers_the_same_queries() {
    // Boxes in a coherent order (sorted along x), built without keys.
    let mut prims = random_boxes(5000, 21, 0.02);
    prims.sort_by(|a, b| a.min.x.total_cmp(&b.min.x));
    let bvh = Bvh::build_in_order(&prims);
    bvh.validate(&prims).unwrap();
    assert_point_queries_exact(&bvh, &prims, 22);
}

/// Every point query returns exactly the boxes containing the point.
fn assert_point_queries_exact(bvh: &Bvh, prims: &[Aabb], seed: u64) {
    let mut rng = Lcg(seed);
    for _ in 0..500 {
        let p = rng.v();
        let mut got = Vec::new();
        bvh.point_query(p, |i| got.push(i));
        got.sort_unstable();
        let want: Vec<u32> = (0..prims.len() as u32)
            .filter(|&i| prims[i as usize].contains(p))
            .collect();
        assert_eq!(got, want, "{} boxes, at {p:?}", prims.len());
    }
}

#[test]
fn box_query_equals_brute_force_and_keeps_point_query_order() {
    let prims = random_boxes(5000, 11, 0.04);
    let bvh = Bvh::build(&prims);
    let mut rng = Lcg(5);
    for _ in 0..200 {
        let b = Aabb::around(rng.v(), rng.f() * 0.1);
        let mut got = Vec::new();
        bvh.box_query(&b, |i, _| got.push(i));
        let mut sorted = got.clone();
        sorted.sort_unstable();
        let want: Vec<u32> = (0..prims.len() as u32)
            .filter(|&i| {
                let p = &prims[i as usize];
                p.min.x <= b.max.x
                    && p.max.x >= b.min.x
                    && p.min.y <= b.max.y
                    && p.max.y >= b.min.y
                    && p.min.z <= b.max.z
                    && p.max.z >= b.min.z
            })
            .collect();
        assert_eq!(sorted, want);
        // For a point inside the box, the primitives containing it come in
        // the point query's order.
        let p = b.center();
        let mut by_point = Vec::new();
        bvh.point_query(p, |i| by_point.push(i));
        let filtered: Vec<u32> = got
            .into_iter()
            .filter(|&i| prims[i as usize].contains(p))
            .collect();
        assert_eq!(filtered, by_point);
    }
}

#[test]
fn ray_closest_finds_the_nearest_box_entry() {
    // The "hit" of a primitive is where the ray enters its box: the closest
    // traversal must return the smallest such entry, as a scan over all
    // boxes does, while opening fewer leaves than there are boxes hit.
    let prims = random_boxes(5000, 11, 0.03);
    let bvh = Bvh::build(&prims);
    let mut rng = Lcg(5);
    let (mut opened, mut crossed) = (0usize, 0usize);
    for _ in 0..300 {
        let o = rng.v() * 3.0 - Vec3::ONE;
        let d = (rng.v() - Vec3::splat(0.5)).normalized();
        let ray = Ray::new(o, d);
        let t = Range1::new(0.0, 10.0);
        let want = prims
            .iter()
            .map(|b| b.clip_ray(&ray, t))
            .filter(|r| !r.is_empty())
            .map(|r| r.lo)
            .fold(t.hi, f32::min);
        crossed += prims
            .iter()
            .filter(|b| !b.clip_ray(&ray, t).is_empty())
            .count();
        let got = bvh.ray_closest(&ray, t, |i, t_max| {
            opened += 1;
            let r = prims[i as usize].clip_ray(&ray, Range1::new(t.lo, t_max));
            (!r.is_empty() && r.lo < t_max).then_some(r.lo)
        });
        assert_eq!(got, want);
    }
    assert!(opened < crossed, "opened {opened} of {crossed}");
}
