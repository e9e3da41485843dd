use super::*;
use voxless_core::SmallRng;

/// The surface of the cube [0, n]³ as 2·6·n² triangles over shared integer
/// vertices, outward winding: rays on the integer and half-integer lattice
/// pass exactly through its vertices and edges (diagonals included).
fn lattice_cube(n: u32) -> Mesh {
    let mut m = Mesh::default();
    let mut index = std::collections::HashMap::new();
    let mut vertex = |m: &mut Mesh, p: [u32; 3]| -> u32 {
        *index.entry(p).or_insert_with(|| {
            m.positions.push(p.map(|c| c as f32));
            m.positions.len() as u32 - 1
        })
    };
    for axis in 0..3 {
        for side in [0, n] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            for i in 0..n {
                for j in 0..n {
                    let at = |di: u32, dj: u32| {
                        let mut p = [0u32; 3];
                        p[axis] = side;
                        p[u] = i + di;
                        p[v] = j + dj;
                        p
                    };
                    let q = [at(0, 0), at(1, 0), at(1, 1), at(0, 1)].map(|p| vertex(&mut m, p));
                    // Outward: counter-clockwise seen from outside.
                    let (a, b, c, d) = if side == n {
                        (q[0], q[1], q[2], q[3])
                    } else {
                        (q[0], q[3], q[2], q[1])
                    };
                    m.triangles.push([a, b, c]);
                    m.triangles.push([a, c, d]);
                }
            }
        }
    }
    m
}

fn surfaces(m: &Mesh) -> Surfaces {
    Surfaces::new(&[(m, &Paint::Solid([1.0; 3]))]).unwrap()
}

/// Möller–Trumbore in f64: the reference distance.
fn reference_t(ray: &Ray, a: Vec3, b: Vec3, c: Vec3) -> Option<f64> {
    let f = |v: Vec3| [v.x as f64, v.y as f64, v.z as f64];
    let (o, d, a, b, c) = (f(ray.origin), f(ray.dir), f(a), f(b), f(c));
    let sub = |p: [f64; 3], q: [f64; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
    let cross = |p: [f64; 3], q: [f64; 3]| {
        [
            p[1] * q[2] - p[2] * q[1],
            p[2] * q[0] - p[0] * q[2],
            p[0] * q[1] - p[1] * q[0],
        ]
    };
    let dot = |p: [f64; 3], q: [f64; 3]| p[0] * q[0] + p[1] * q[1] + p[2] * q[2];
    let (e1, e2) = (sub(b, a), sub(c, a));
    let p = cross(d, e2);
    let det = dot(e1, p);
    if det.abs() < 1e-300 {
        return None;
    }
    let s = sub(o, a);
    let u = dot(s, p) / det;
    let q = cross(s, e1);
    let v = dot(d, q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0).then(|| dot(e2, q) / det)
}

#[test]
fn nearest_hit_equals_brute_force_over_all_triangles() {
    let mut rng = SmallRng(17);
    let mut m = Mesh::default();
    for i in 0..3000u32 {
        let c = rng.v();
        for _ in 0..3 {
            m.positions
                .push((c + (rng.v() - Vec3::splat(0.5)) * 0.08).to_array());
        }
        m.triangles.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    let s = surfaces(&m);
    let mut hits = 0;
    for _ in 0..2000 {
        let o = rng.v() * 3.0 - Vec3::ONE;
        let d = (rng.v() - o).normalized();
        let ray = Ray::new(o, d);
        let t = Range1::new(0.0, 10.0);
        let frame = RayFrame::new(&ray);
        // Brute force: the same test over every triangle, and an f64
        // reference for the distance.
        let mut want: Option<(f32, f64)> = None;
        for tri in &m.triangles {
            let [a, b, c] = tri.map(|v| Vec3::from_array(m.positions[v as usize]));
            if let Some(h) = intersect(&frame, a, b, c, t)
                && want.is_none_or(|w| h.t < w.0)
            {
                want = Some((
                    h.t,
                    reference_t(&ray, a, b, c).expect("reference misses a hit"),
                ));
            }
        }
        let got = s.nearest(&ray, t);
        match (got, want) {
            (None, None) => {}
            (Some(g), Some((w, r))) => {
                hits += 1;
                assert_eq!(g.t, w);
                assert!(((g.t as f64 - r) / r).abs() < 1e-6, "t {} vs {r}", g.t);
                assert!((g.normal.length() - 1.0).abs() < 1e-5 && g.normal.dot(d) <= 0.0);
            }
            (g, w) => panic!("bvh {g:?} vs brute force {w:?}"),
        }
    }
    assert!(hits > 1000, "only {hits} rays hit");
}

#[test]
fn rays_through_edges_and_vertices_cross_a_closed_mesh_exactly_twice() {
    let n = 4;
    let m = lattice_cube(n);
    let s = surfaces(&m);
    let all = Range1::new(f32::NEG_INFINITY, f32::INFINITY);
    let mut rays = 0;
    // Along each axis through every vertex, edge and diagonal of the faces
    // (integer and half-integer lattice), including the cube's own edges.
    for axis in 0..3 {
        for i in 0..=2 * n {
            for j in 0..=2 * n {
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                let mut o = Vec3::ZERO;
                o[axis] = -1.0;
                o[u] = i as f32 * 0.5;
                o[v] = j as f32 * 0.5;
                let mut d = Vec3::ZERO;
                d[axis] = 1.0;
                let on_boundary = i == 0 || j == 0 || i == 2 * n || j == 2 * n;
                let hits = s.all_hits(&Ray::new(o, d), all);
                if !on_boundary {
                    assert_eq!(hits.len(), 2, "axis {axis} ray at ({i}/2, {j}/2): {hits:?}");
                    assert_eq!(hits, vec![1.0, 1.0 + n as f32]);
                } else {
                    // Grazing the cube's surface: in or out, but even.
                    assert_eq!(hits.len() % 2, 0, "grazing ray {hits:?}");
                }
                rays += 1;
            }
        }
    }
    // Oblique rays with exact (dyadic) directions through lattice points.
    let dirs = [
        Vec3::new(1.0, 0.5, 0.25),
        Vec3::new(-0.5, 1.0, 0.5),
        Vec3::new(0.25, -0.25, 1.0),
    ];
    for d in dirs {
        for i in 1..2 * n {
            for j in 1..2 * n {
                // Through the point (i/2, j/2, n/2) of the cube's inside.
                let p = Vec3::new(i as f32 * 0.5, j as f32 * 0.5, n as f32 * 0.5);
                let o = p - d * 16.0;
                let hits = s.all_hits(&Ray::new(o, d), all);
                assert_eq!(hits.len(), 2, "oblique ray {d:?} through {p:?}: {hits:?}");
                rays += 1;
            }
        }
    }
    assert!(rays > 200);
}

#[test]
fn occlusion_inside_a_closed_box_and_over_an_open_plane() {
    let m = lattice_cube(2);
    let s = surfaces(&m);
    let mut rng = SmallRng(3);
    let far = Range1::new(1e-4, 100.0);
    for _ in 0..500 {
        let d = (rng.v() - Vec3::splat(0.5)).normalized();
        // From the centre every direction is blocked.
        assert!(s.occluded(&Ray::new(Vec3::splat(1.0), d), far));
        // From above the top face, directions away from it see nothing.
        let up = Vec3::new(d.x, d.y, d.z.abs());
        assert!(!s.occluded(&Ray::new(Vec3::new(1.0, 1.0, 2.0 + 1e-3), up), far));
    }
}

#[test]
fn bad_meshes_are_named() {
    let mut m = lattice_cube(1);
    m.triangles.push([0, 1, 99]);
    assert!(matches!(
        m.validate(),
        Err(MeshError::Index { vertex: 99, .. })
    ));
    let mut m = lattice_cube(1);
    m.positions[3][1] = f32::NAN;
    assert_eq!(m.validate(), Err(MeshError::NonFinite(3)));
    assert_eq!(Mesh::default().validate(), Err(MeshError::Empty));
}

#[test]
fn cosine_directions_lie_in_the_hemisphere() {
    let mut rng = SmallRng(1);
    for _ in 0..1000 {
        let n = (rng.v() - Vec3::splat(0.5)).normalized();
        let d = cosine_direction(n, rng.f(), rng.f());
        assert!((d.length() - 1.0).abs() < 1e-5);
        assert!(d.dot(n) >= -1e-6);
    }
}
