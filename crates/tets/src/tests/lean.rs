//! Lean meshes against the former explicit construction (every tet held):
//! the same tets, blocks and point masses, bit for bit, and so the same
//! projections and tile intervals; nothing held per tet; nothing built that
//! an operation does not use.

use super::*;
use crate::mesh::{KUHN, TetMeshBuilder};
use voxless_core::{IntervalLists, IntervalQuery, Range1, TileIntervals, TileRays};

/// The former construction, kept as the reference: every tet of every
/// block, grouped by image shift in order of first appearance, each tet
/// unwrapped to its anchor's image, degenerate tets as point masses.
struct Explicit {
    /// Per group: Lagrangian block, shift, tets, bounds.
    groups: Vec<(u32, [i8; 3], Vec<Tet>, Aabb)>,
    points: Vec<(Vec3, f64)>,
}

fn explicit(g: &LagrangianGrid, particle_mass: f64, fraction: f64, block: usize) -> Explicit {
    let (n, l) = (g.n, g.box_size);
    let at = |a: usize, b: usize, c: usize| g.positions[((a % n) * n + (b % n)) * n + (c % n)];
    let tet_mass = particle_mass / 6.0;
    let floor = fraction * (l as f64 / n as f64).powi(3) / 6.0;
    let nb = n.div_ceil(block);
    let mut out = Explicit {
        groups: Vec::new(),
        points: Vec::new(),
    };
    for b in 0..nb * nb * nb {
        let (bi, bj, bk) = (b / (nb * nb), (b / nb) % nb, b % nb);
        let first = out.groups.len();
        for i in bi * block..((bi + 1) * block).min(n) {
            for j in bj * block..((bj + 1) * block).min(n) {
                for k in bk * block..((bk + 1) * block).min(n) {
                    let anchor = at(i, j, k);
                    let mut corners = [anchor; 8];
                    for (c, slot) in corners.iter_mut().enumerate() {
                        let d = at(i + (c >> 2), j + ((c >> 1) & 1), k + (c & 1)) - anchor;
                        let wrap = |x: f32| x - l * (x / l).round();
                        *slot = anchor + Vec3::new(wrap(d.x), wrap(d.y), wrap(d.z));
                    }
                    for t in KUHN {
                        let v = t.map(|c| corners[c]);
                        let vol = Tet::signed_volume(&v).abs();
                        let mut lo = [f32::INFINITY; 3];
                        let mut hi = [f32::NEG_INFINITY; 3];
                        for p in &v {
                            for a in 0..3 {
                                lo[a] = lo[a].min(p[a]);
                                hi[a] = hi[a].max(p[a]);
                            }
                        }
                        let shifts = |a: usize| -> Vec<i8> {
                            [-1i8, 0, 1]
                                .into_iter()
                                .filter(|&s| {
                                    hi[a] + s as f32 * l > 0.0 && lo[a] + (s as f32) * l < l
                                })
                                .collect()
                        };
                        for x in shifts(0) {
                            for y in shifts(1) {
                                for z in shifts(2) {
                                    let shift = [x, y, z];
                                    let off = Vec3::new(x as f32, y as f32, z as f32) * l;
                                    let vs = v.map(|p| p + off);
                                    if vol < floor {
                                        let c = (vs[0] + vs[1] + vs[2] + vs[3]) * 0.25;
                                        if (0..3).all(|a| c[a] >= 0.0 && c[a] < l) {
                                            out.points.push((c, tet_mass));
                                        }
                                        continue;
                                    }
                                    let tet = Tet {
                                        v: vs,
                                        density: (tet_mass / vol) as f32,
                                    };
                                    let group =
                                        match out.groups[first..].iter().position(|g| g.1 == shift)
                                        {
                                            Some(p) => first + p,
                                            None => {
                                                out.groups.push((
                                                    b as u32,
                                                    shift,
                                                    Vec::new(),
                                                    Aabb::EMPTY,
                                                ));
                                                out.groups.len() - 1
                                            }
                                        };
                                    out.groups[group].3 = out.groups[group].3.union(tet.bounds());
                                    out.groups[group].2.push(tet);
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    out
}

/// The reference construction as an explicit mesh.
fn explicit_mesh(g: &LagrangianGrid) -> TetMesh {
    let n = g.n;
    let mass = 1.0 / (n * n * n) as f64;
    let e = explicit(g, mass, TetSettings::default().degenerate_fraction, BLOCK);
    let mean = (g.box_size as f64 / n as f64).powi(3) / 6.0;
    let mut b = TetMeshBuilder::new(n, g.box_size, mass / 6.0, mean);
    for (lagrangian, _, tets, _) in e.groups {
        b.push_block(lagrangian, tets);
    }
    for (p, m) in e.points {
        b.push_point_mass(p, m);
    }
    b.build()
}

/// A grid with a flattened layer of cells (particles of plane i = 3 moved
/// onto plane i = 4): degenerate tets, kept as point masses.
fn flattened(n: usize) -> LagrangianGrid {
    let mut g = grid(n, 1.0, jitter(7, 0.03));
    for j in 0..n {
        for k in 0..n {
            let (a, b) = ((3 * n + j) * n + k, (4 * n + j) * n + k);
            g.positions[a] = g.positions[b];
        }
    }
    g
}

fn cases() -> Vec<(&'static str, LagrangianGrid)> {
    vec![
        ("jittered 8", grid(8, 1.0, jitter(3, 0.04))),
        // N not a multiple of the block: partial blocks.
        ("jittered 11", grid(11, 2.0, jitter(5, 0.08))),
        ("folded sheet 12", folded_sheet(12, 41)),
        ("flattened 10", flattened(10)),
        ("uniform 16", grid(16, 1.0, jitter(9, 0.01))),
    ]
}

#[test]
fn lean_tets_equal_the_explicit_construction() {
    for (name, g) in cases() {
        let s = TetSettings::default();
        let mesh = TetMesh::new(&g, &s).unwrap();
        assert!(mesh.is_lean());
        let mass = 1.0 / (g.n * g.n * g.n) as f64;
        let want = explicit(&g, mass, s.degenerate_fraction, BLOCK);
        assert_eq!(mesh.blocks().len(), want.groups.len(), "{name}: blocks");
        let mut next = 0u64;
        let mut buf = Vec::new();
        for (b, (block, group)) in mesh.blocks().iter().zip(&want.groups).enumerate() {
            assert_eq!(block.lagrangian, group.0, "{name}: block {b}");
            assert_eq!(block.shift, group.1, "{name}: block {b}");
            assert_eq!(block.bounds, group.3, "{name}: block {b}");
            assert_eq!(block.tets, next..next + group.2.len() as u64, "{name}");
            next = block.tets.end;
            // Bit for bit, in order.
            assert_eq!(
                mesh.block_tets(b, &mut buf),
                &group.2[..],
                "{name}: block {b}"
            );
        }
        assert_eq!(
            mesh.point_masses(),
            &want.points[..],
            "{name}: point masses"
        );
        if name.starts_with("flattened") {
            assert!(!want.points.is_empty(), "{name}: degenerate tets");
        }
        let all: Vec<Tet> = want.groups.iter().flat_map(|g| g.2.clone()).collect();
        assert_eq!(mesh.tets(), all, "{name}: every tet");
        assert_eq!(mesh.tet_count(), all.len());
    }
}

#[test]
fn lean_levels_of_detail_equal_the_explicit_coarse_grids() {
    let g = grid(16, 1.0, jitter(29, 0.02));
    let mesh = TetMesh::new(&g, &TetSettings::default())
        .unwrap()
        .with_lod(5);
    assert_eq!(
        mesh.lod().len(),
        3,
        "N = 16: 8, 4, 2 (blocks of 4, 2, 1 cells)"
    );
    for (r, level) in (1..).zip(mesh.lod()) {
        let step = 1 << r;
        let nc = 16 / step;
        let coarse = LagrangianGrid {
            n: nc,
            box_size: 1.0,
            positions: (0..nc * nc * nc)
                .map(|c| {
                    let (i, j, k) = (c / (nc * nc), (c / nc) % nc, c % nc);
                    g.positions[((i * step) * 16 + j * step) * 16 + k * step]
                })
                .collect(),
        };
        let mass = (1.0 / 4096.0) * (step * step * step) as f64;
        let want = explicit(&coarse, mass, 1e-6, BLOCK >> r);
        let tets: Vec<Tet> = want.groups.iter().flat_map(|g| g.2.clone()).collect();
        assert_eq!(level.tets(), tets, "level {r}");
        let lag: Vec<u32> = want.groups.iter().map(|g| g.0).collect();
        let got: Vec<u32> = level.blocks().iter().map(|b| b.lagrangian).collect();
        assert_eq!(got, lag, "level {r}: same Lagrangian blocks");
    }
}

#[test]
fn slabs_are_the_whole_mesh_in_order() {
    let g = grid(20, 1.0, jitter(13, 0.05));
    let whole = TetMesh::new(&g, &TetSettings::default()).unwrap();
    let n = g.n;
    let nb = n.div_ceil(BLOCK);
    let mut tets = Vec::new();
    for rows in [0..1, 1..3] {
        let first = rows.start * BLOCK;
        let last = (rows.end * BLOCK).min(n);
        let mut positions = g.positions[first * n * n..last * n * n].to_vec();
        let extra = last % n;
        positions.extend_from_slice(&g.positions[extra * n * n..(extra + 1) * n * n]);
        let slab = LagrangianSlab {
            n,
            box_size: 1.0,
            rows: rows.clone(),
            first_plane: first,
            planes: last - first + 1,
            positions,
        };
        tets.extend(
            TetMesh::from_slab(&slab, &TetSettings::default())
                .unwrap()
                .tets(),
        );
    }
    assert_eq!(nb, 3);
    assert_eq!(tets, whole.tets());
}

#[test]
fn lean_and_explicit_meshes_project_and_render_identically() {
    for (name, g) in cases() {
        let lean = TetVolume::new(&g, &TetSettings::default(), 0).unwrap();
        let held = TetVolume::from_mesh(explicit_mesh(&g));
        assert!(!held.mesh.is_lean());
        assert_eq!(lean.value_range(), held.value_range(), "{name}");
        let b = Aabb::new(Vec3::splat(-0.1), Vec3::splat(1.1) * g.box_size);
        for axis in 0..3 {
            let cam = Camera::axis_projection(&b, axis).unwrap();
            for pixels in [PixelIntegral::Centre, PixelIntegral::Area] {
                let options = TetOptions {
                    pixels,
                    ..Default::default()
                };
                let project = |v: &TetVolume| {
                    render::project(&v.mesh, &cam, 90, 70, options, &Control::new()).unwrap()
                };
                let (a, b) = (project(&lean), project(&held));
                if pixels == PixelIntegral::Centre {
                    assert_eq!(a, b, "{name}, axis {axis}");
                } else {
                    // A lean mesh walks each edge of a cell once for the
                    // tets that share it, an explicit one tet by tet: the
                    // same integrals, summed in another order.
                    let peak = b.iter().copied().fold(0.0f32, f32::max);
                    for (p, (x, y)) in a.iter().zip(&b).enumerate() {
                        assert!((x - y).abs() <= 1e-5 * peak, "{name}, axis {axis}, {p}");
                    }
                }
            }
        }
        // Tile intervals of a perspective view, centred and jittered rays.
        let cam = Camera::look_at(
            Vec3::new(1.6, 1.3, -0.8) * g.box_size,
            Vec3::splat(0.5 * g.box_size),
            Vec3::new(0.0, 1.0, 0.0),
            voxless_core::Projection::Perspective { fov_y_deg: 40.0 },
        )
        .unwrap();
        let (w, h) = (40u32, 36u32);
        let views = [&lean, &held].map(|v| TetTileView::new(&v.mesh, &cam, w, h, None, None));
        for centred in [true, false] {
            let mut lists = [IntervalLists::default(), IntervalLists::default()];
            for (view, out) in views.iter().zip(&mut lists) {
                for ty in (0..h).step_by(raster::TILE as usize) {
                    for tx in (0..w).step_by(raster::TILE as usize) {
                        let (tw, th) = ((w - tx).min(raster::TILE), (h - ty).min(raster::TILE));
                        let jitter = if centred { 0.5 } else { 0.3 };
                        let rays: Vec<Ray> = (0..tw * th)
                            .map(|p| {
                                let (x, y) = (tx + p % tw, ty + p / tw);
                                cam.ray(x as f32 + jitter, y as f32 + jitter, w, h)
                            })
                            .collect();
                        let t = vec![Range1::new(0.0, 1e3); rays.len()];
                        let tile = TileRays {
                            x0: tx,
                            y0: ty,
                            w: tw,
                            h: th,
                            rays: &rays,
                            t: &t,
                            centred,
                        };
                        view.intervals(&tile, &IntervalQuery::all(), out);
                    }
                }
            }
            assert_eq!(
                lists[0].intervals, lists[1].intervals,
                "{name}, centred {centred}"
            );
            assert_eq!(lists[0].ends, lists[1].ends, "{name}, centred {centred}");
        }
    }
}

#[test]
fn a_lean_mesh_holds_no_tets_and_a_projection_builds_nothing_else() {
    let n = 16;
    let g = grid(n, 1.0, jitter(31, 0.03));
    let v = TetVolume::new(&g, &TetSettings::default(), 3).unwrap();
    let held = v.mesh.held_bytes();
    let positions = n * n * n * std::mem::size_of::<Vec3>();
    // Positions plus a few hundred bytes per 8³-cell block — not the
    // 6 × 52 bytes per cell the tets would take.
    let tets = v.mesh.tet_count() * std::mem::size_of::<Tet>();
    assert!(held < positions + 64 * v.mesh.blocks().len(), "{held}");
    assert!(held * 10 < tets, "{held} vs {tets}");
    // A projection (either pixel integral) needs no point index and no
    // coarser levels.
    let cam = axis_camera(1.0);
    for pixels in [PixelIntegral::Centre, PixelIntegral::Area] {
        let v = TetVolume::new(&g, &TetSettings::default(), 3)
            .unwrap()
            .with_pixel_integral(pixels);
        let _ = v.project_image(&cam, 64, 64, &Control::new()).unwrap();
        assert!(!v.has_index(), "{pixels:?}");
        assert_eq!(v.mesh.held_bytes(), held, "{pixels:?}: nothing built");
    }
    // A point sample builds the index; a render with a threshold the levels.
    let _ = v.density_and_streams(Vec3::splat(0.5));
    assert!(v.has_index());
    let _ = raster::Frame::new(&v.mesh, &cam, 64, 64, Some(1e6));
    assert!(v.mesh.held_bytes() > held);
}

#[test]
fn point_samples_through_the_cell_index_equal_every_tet() {
    for (name, g) in cases() {
        let v = TetVolume::new(&g, &TetSettings::default(), 0).unwrap();
        let tets = v.mesh.tets();
        let mut rng = Lcg(77);
        for _ in 0..300 {
            let p = Vec3::new(rng.f(), rng.f(), rng.f()) * g.box_size;
            let q = v.canonical_point(p);
            let mut want: Vec<f32> = tets
                .iter()
                .filter(|t| t.contains(q))
                .map(|t| t.density)
                .collect();
            want.sort_unstable_by(f32::total_cmp);
            let rho: f64 = want.iter().map(|&d| d as f64).sum();
            assert_eq!(
                v.density_and_streams(p),
                (rho, want.len() as u32),
                "{name} at {p:?}"
            );
        }
        // Line integrals through the index against every tet.
        let ray = Ray::new(
            Vec3::new(-0.1, 0.37, 0.61) * g.box_size,
            Vec3::new(1.0, 0.13, -0.07).normalized(),
        );
        let t = Range1::new(0.0, 1.5 * g.box_size);
        let want: f64 = tets
            .iter()
            .map(|tet| {
                let (a, b) = raster::Planes::new(tet).clip(&ray);
                let (a, b) = (a.max(t.lo), b.min(t.hi));
                if b > a {
                    tet.density as f64 * (b - a) as f64
                } else {
                    0.0
                }
            })
            .sum();
        let got = v.line_integral(&ray, t);
        assert!(
            (got - want).abs() <= 1e-9 * want.max(1.0),
            "{name}: {got} vs {want}"
        );
    }
}
