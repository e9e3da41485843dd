//! Many point samples at once, without the point index.
//!
//! A transfer-function probe or a histogram asks for the density at ~10⁵
//! points once, where building the point/ray index (a BVH over every cell
//! image) costs seconds at 10⁸ tets. Here the points are binned on a
//! uniform grid over the box and the cells are swept once, block by block
//! on every core: a cell image whose box holds a binned point derives its
//! tets and tests them. The tets found for a point are exactly those the
//! index finds (the same cell images, the same corners and offsets, the
//! same containment test at the same nudged point), and their densities
//! are added in increasing order as [`TetVolume::density_and_streams`]
//! adds them, so each value is the index path's bit for bit (tested).

use rayon::prelude::*;
use voxless_core::{Aabb, Sample, Vec3};

use crate::mesh::{Tet, TetMesh};
use crate::volume::TetVolume;

impl TetVolume {
    /// [`TetVolume::density_and_streams`] at every point of `points`: from
    /// the index when a point query already built it, else from one sweep
    /// over the cells (see the module docs). Either way the same values.
    pub fn densities_and_streams(&self, points: &[Vec3]) -> Vec<(f64, u32)> {
        if self.has_index() || points.is_empty() {
            return points
                .par_iter()
                .map(|&p| self.density_and_streams(p))
                .collect();
        }
        let q: Vec<Vec3> = points.iter().map(|&p| self.canonical_point(p)).collect();
        let bins = Bins::new(&q, self.mesh.box_size);
        let mut hits = hits(&self.mesh, &bins, &q);
        // By point, then by density: each point's run is the sorted list
        // the index path sums.
        hits.par_sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
        let mut out = vec![(0.0f64, 0u32); points.len()];
        let mut densities: Vec<f32> = Vec::new();
        for run in hits.chunk_by(|a, b| a.0 == b.0) {
            densities.clear();
            densities.extend(run.iter().map(|h| h.1));
            let rho = densities.iter().map(|&d| d as f64).sum();
            out[run[0].0 as usize] = (rho, run.len() as u32);
        }
        out
    }

    /// [`voxless_core::Volume::sample`] at every point of `points` (see
    /// [`TetVolume::densities_and_streams`]).
    pub fn samples(&self, points: &[Vec3]) -> Vec<Option<Sample>> {
        self.densities_and_streams(points)
            .into_iter()
            .map(|(rho, streams)| (streams > 0).then(|| Sample::scalar(rho as f32)))
            .collect()
    }
}

/// Points binned on a `g`³ grid over the box `[0, l)³` (counting sort).
struct Bins {
    g: usize,
    scale: f32,
    /// Bin `b`'s points are `points[start[b]..start[b + 1]]`.
    start: Vec<u32>,
    points: Vec<u32>,
}

impl Bins {
    fn new(q: &[Vec3], l: f32) -> Bins {
        // About one point in eight bins: most cells meet only empty ones.
        let g = ((2.0 * (q.len() as f64).cbrt()).ceil() as usize).clamp(1, 256);
        let scale = g as f32 / l;
        let mut bins = Bins {
            g,
            scale,
            start: vec![0; g * g * g + 1],
            points: vec![0; q.len()],
        };
        let of: Vec<usize> = q.iter().map(|&p| bins.bin(p)).collect();
        for &b in &of {
            bins.start[b + 1] += 1;
        }
        for b in 0..g * g * g {
            bins.start[b + 1] += bins.start[b];
        }
        let mut fill = bins.start.clone();
        for (i, &b) in of.iter().enumerate() {
            bins.points[fill[b] as usize] = i as u32;
            fill[b] += 1;
        }
        bins
    }

    fn axis(&self, x: f32) -> usize {
        ((x * self.scale).max(0.0) as usize).min(self.g - 1)
    }

    fn bin(&self, p: Vec3) -> usize {
        (self.axis(p.x) * self.g + self.axis(p.y)) * self.g + self.axis(p.z)
    }

    /// Calls `f` with every point whose bin meets `b` and which lies in
    /// `b` (bounds included).
    #[inline]
    fn in_box(&self, q: &[Vec3], b: &Aabb, mut f: impl FnMut(u32, Vec3)) {
        let l = self.g as f32 / self.scale;
        if b.max.x < 0.0 || b.max.y < 0.0 || b.max.z < 0.0 {
            return;
        }
        if b.min.x >= l || b.min.y >= l || b.min.z >= l {
            return;
        }
        let (x0, x1) = (self.axis(b.min.x), self.axis(b.max.x));
        let (y0, y1) = (self.axis(b.min.y), self.axis(b.max.y));
        let (z0, z1) = (self.axis(b.min.z), self.axis(b.max.z));
        for x in x0..=x1 {
            for y in y0..=y1 {
                let row = (x * self.g + y) * self.g;
                let (s, e) = (self.start[row + z0], self.start[row + z1 + 1]);
                for &i in &self.points[s as usize..e as usize] {
                    let p = q[i as usize];
                    if p.x >= b.min.x
                        && p.x <= b.max.x
                        && p.y >= b.min.y
                        && p.y <= b.max.y
                        && p.z >= b.min.z
                        && p.z <= b.max.z
                    {
                        f(i, p);
                    }
                }
            }
        }
    }
}

/// (point, tet density) for every tet of `mesh` containing a point.
fn hits(mesh: &TetMesh, bins: &Bins, q: &[Vec3]) -> Vec<(u32, f32)> {
    let test = |t: &Tet, i: u32, p: Vec3, out: &mut Vec<(u32, f32)>| {
        if t.contains(p) {
            out.push((i, t.density));
        }
    };
    if let Some(tets) = mesh.explicit_tets() {
        return tets
            .par_chunks(4096)
            .flat_map_iter(|chunk| {
                let mut out = Vec::new();
                for t in chunk {
                    bins.in_box(q, &t.bounds(), |i, p| test(t, i, p, &mut out));
                }
                out
            })
            .collect();
    }
    let Some(lattice) = mesh.lattice() else {
        unreachable!("a mesh is lean or explicit")
    };
    // The cell images the point index holds (`crate::index`), block by block.
    mesh.lagrangian_blocks()
        .par_iter()
        .flat_map_iter(|&b| {
            let mut out = Vec::new();
            let mut found: Vec<(u32, Vec3)> = Vec::new();
            lattice.cell_images(b, |_, shift, off, corners, bounds| {
                found.clear();
                bins.in_box(q, &bounds, |i, p| found.push((i, p)));
                if found.is_empty() {
                    return;
                }
                lattice.cell_tets::<true>(corners, shift, off, &mut |(_, t)| {
                    for &(i, p) in &found {
                        test(&t, i, p, &mut out);
                    }
                });
            });
            out
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{LagrangianGrid, TetMeshBuilder, TetSettings};

    /// A 12³ run in a box of 10 whose sheet folds (shell crossing) and
    /// wraps across the box's faces.
    fn folded(n: usize) -> LagrangianGrid {
        let l = 10.0f32;
        let mut positions = Vec::with_capacity(n * n * n);
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    let q = Vec3::new(i as f32, j as f32, k as f32) * (l / n as f32);
                    let phase = 2.0 * std::f32::consts::PI * q.x / l;
                    let d = Vec3::new(
                        2.2 * phase.sin() + 0.7,
                        0.4 * (phase * 2.0).cos() - 0.3,
                        0.9 * (2.0 * std::f32::consts::PI * q.y / l).sin(),
                    );
                    let p = q + d;
                    positions.push(Vec3::new(
                        p.x.rem_euclid(l),
                        p.y.rem_euclid(l),
                        p.z.rem_euclid(l),
                    ));
                }
            }
        }
        LagrangianGrid {
            n,
            box_size: l,
            positions,
        }
    }

    fn points(count: usize, l: f32, seed: u64) -> Vec<Vec3> {
        let mut s = seed;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            // Some points outside the box: they wrap.
            ((s >> 40) as f32 / (1u64 << 24) as f32) * 1.2 * l - 0.1 * l
        };
        (0..count)
            .map(|_| Vec3::new(next(), next(), next()))
            .collect()
    }

    #[test]
    fn the_sweep_gives_the_index_values_bit_for_bit() {
        let grid = folded(12);
        let swept = TetVolume::new(&grid, &TetSettings::default(), 0).expect("volume");
        let indexed = TetVolume::new(&grid, &TetSettings::default(), 0).expect("volume");
        let mut pts = points(20_000, 10.0, 7);
        // Lattice points (on the probe's kind of grid) and the cell corners.
        pts.extend((0..1000).map(|i| Vec3::splat(i as f32 * 0.01)));
        pts.extend(grid.positions.iter().take(500).copied());
        let fast = swept.densities_and_streams(&pts);
        assert!(!swept.has_index(), "the sweep builds no index");
        let slow: Vec<(f64, u32)> = pts
            .iter()
            .map(|&p| indexed.density_and_streams(p))
            .collect();
        let multi = fast.iter().filter(|v| v.1 > 1).count();
        assert!(multi > 100, "the test needs shell crossing: {multi} points");
        for (k, (a, b)) in fast.iter().zip(&slow).enumerate() {
            assert_eq!(a.1, b.1, "streams at {:?}", pts[k]);
            assert_eq!(a.0.to_bits(), b.0.to_bits(), "density at {:?}", pts[k]);
        }
        // With the index built, the same values through it.
        assert_eq!(indexed.densities_and_streams(&pts), slow);
        let samples = swept.samples(&pts);
        for (s, v) in samples.iter().zip(&slow) {
            assert_eq!(s.map(|s| s.value), (v.1 > 0).then_some(v.0 as f32));
        }
    }

    #[test]
    fn the_sweep_of_an_explicit_mesh_equals_its_index() {
        let grid = folded(8);
        let whole = TetMesh::new(&grid, &TetSettings::default()).expect("mesh");
        let explicit = || {
            let mut builder = TetMeshBuilder::new(8, 10.0, 1.0, 1.0);
            builder.push_block(0, whole.tets());
            builder.build()
        };
        let swept = TetVolume::from_mesh(explicit());
        let indexed = TetVolume::from_mesh(explicit());
        let pts = points(5_000, 10.0, 3);
        let fast = swept.densities_and_streams(&pts);
        let slow: Vec<(f64, u32)> = pts
            .iter()
            .map(|&p| indexed.density_and_streams(p))
            .collect();
        assert!(fast.iter().any(|v| v.1 > 0));
        for (a, b) in fast.iter().zip(&slow) {
            assert_eq!((a.0.to_bits(), a.1), (b.0.to_bits(), b.1));
        }
    }
}
