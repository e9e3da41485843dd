//! How far apart particles are: the default radius comes from the spacing
//! of neighbouring particles, not from the box they sit in, so atoms of a
//! liquid stay atoms and a thin disc in a big box is not blurred.
//!
//! - [`mean_spacing`]: `(occupied volume / N)^(1/3)`, the occupied volume
//!   counted on a coarse grid of about four particles per cell (if the data
//!   were uniform), so clustered data get the spacing where the particles
//!   actually are. Cheap; the search radius of the next estimate.
//! - [`nearest_neighbour_spacing`]: the median distance from a particle to
//!   its nearest other particle, over up to [`PROBES`] particles, found in a
//!   grid of cells one search radius wide (a neighbour within the radius
//!   lies in the 27 cells around the particle's own). Coincident particles
//!   (distance 0) are passed over, so duplicates do not shrink the radius to
//!   nothing.
//!
//! Both are scale-free: positions ×10ᵏ give spacings ×10ᵏ.

use rayon::prelude::*;
use voxless_core::{Aabb, Vec3};

/// Particles whose nearest neighbour is looked up.
pub const PROBES: usize = 4096;

pub(crate) fn bounds(positions: &[Vec3]) -> Aabb {
    let mut b = Aabb::EMPTY;
    for p in positions {
        b.grow(*p);
    }
    b
}

/// The mean spacing of the occupied part of the data; `None` when the
/// particles have no extent (one particle, or all at one point).
pub fn mean_spacing(positions: &[Vec3]) -> Option<f32> {
    let mut grid = OccupancyGrid::new(bounds(positions), positions.len())?;
    for p in positions {
        grid.mark(*p);
    }
    Some(grid.spacing(grid.occupied()))
}

/// The coarse grid [`mean_spacing`] counts occupied cells on, over the
/// positions' bounds `b` for `n` particles. A decomposed set marks each
/// part's positions on a grid over the whole set's bounds and counts the
/// cells any part marked.
pub(crate) struct OccupancyGrid {
    b: Aabb,
    n: usize,
    cell: f32,
    dims: [usize; 3],
    pub occupied: Vec<bool>,
}

impl OccupancyGrid {
    /// `None` when the particles have no extent.
    pub fn new(b: Aabb, n: usize) -> Option<OccupancyGrid> {
        let longest = b.extent().max_elem();
        if n == 0 || !(longest > 0.0) || !longest.is_finite() {
            return None;
        }
        let res = ((n as f32 / 4.0).cbrt().round() as usize).clamp(1, 128);
        let cell = longest / res as f32;
        let dims = b.extent().mul_elem(Vec3::splat(1.0 / cell));
        let dim = |a: f32| (a.ceil() as usize).clamp(1, res);
        let dims = [dim(dims.x), dim(dims.y), dim(dims.z)];
        Some(OccupancyGrid {
            b,
            n,
            cell,
            dims,
            occupied: vec![false; dims[0] * dims[1] * dims[2]],
        })
    }

    pub fn mark(&mut self, p: Vec3) {
        let [nx, ny, nz] = self.dims;
        let q = (p - self.b.min) * (1.0 / self.cell);
        let (i, j, k) = (
            (q.x as usize).min(nx - 1),
            (q.y as usize).min(ny - 1),
            (q.z as usize).min(nz - 1),
        );
        self.occupied[(k * ny + j) * nx + i] = true;
    }

    /// How many cells are marked.
    pub fn occupied(&self) -> usize {
        self.occupied.iter().filter(|&&o| o).count()
    }

    /// The mean spacing with `count` occupied cells.
    pub fn spacing(&self, count: usize) -> f32 {
        let count = count.max(1);
        // In f64: cell³ of a tiny extent would underflow in f32.
        let cell = self.cell as f64;
        (count as f64 * cell * cell * cell / self.n as f64).cbrt() as f32
    }
}

/// The median nearest-neighbour distance (see the module docs); `None`
/// when no particle has a neighbour at a distance > 0.
pub fn nearest_neighbour_spacing(positions: &[Vec3]) -> Option<f32> {
    let b = bounds(positions);
    let stride = (positions.len() / PROBES).max(1);
    let probes: Vec<Vec3> = positions.iter().copied().step_by(stride).collect();
    spacing_search(&b, mean_spacing(positions), &mut |h| {
        nearest_within(positions, &probes, &b, h)
    })
}

/// The search behind [`nearest_neighbour_spacing`] for particles within
/// `b` of mean spacing `mean`, with `nearest(h)` giving each probe's
/// squared distance to its nearest other particle among those within the
/// 27 cells of side `h` around it (∞ without one) — over the whole set, or
/// over a decomposed set's parts and then their minimum.
pub(crate) fn spacing_search(
    b: &Aabb,
    mean: Option<f32>,
    nearest: &mut dyn FnMut(f64) -> Vec<f64>,
) -> Option<f32> {
    let longest = b.extent().max_elem() as f64;
    let mut h = mean? as f64;
    // At most 2²⁰ cells per axis, so cell keys fit in 63 bits.
    h = h.max(longest / (1 << 20) as f64);
    // A few widenings when most particles are further apart than the mean
    // spacing suggests (sparse outliers around a dense core).
    for _ in 0..4 {
        if let Some(d) = median_within(nearest(h), h) {
            return Some(d);
        }
        h *= 4.0;
        if h > 2.0 * longest {
            break;
        }
    }
    // Everything farther apart than the search radius: the mean spacing.
    mean
}

/// The median nearest-neighbour distance from the probes' squared
/// distances `best` when more than half of them have a neighbour within
/// `h` (else `None`: the median lies beyond the search radius).
fn median_within(best: Vec<f64>, h: f64) -> Option<f32> {
    // Only a neighbour within h is certainly the nearest one.
    let mut found: Vec<f64> = best
        .into_iter()
        .map(|b| if b <= h * h { b.sqrt() } else { f64::INFINITY })
        .collect();
    if found.is_empty() {
        return None;
    }
    let mid = found.len() / 2;
    found.select_nth_unstable_by(mid, f64::total_cmp);
    let m = found[mid];
    m.is_finite().then_some(m as f32)
}

/// For each of `probes`, the squared distance to its nearest particle of
/// `positions` at a distance > 0 within the 27 cells of side `h` (over
/// `b`) around it; ∞ without one.
pub(crate) fn nearest_within(positions: &[Vec3], probes: &[Vec3], b: &Aabb, h: f64) -> Vec<f64> {
    let inv = 1.0 / h;
    let cell_of = |p: Vec3| -> [u64; 3] {
        std::array::from_fn(|a| ((p[a] as f64 - b.min[a] as f64) * inv).max(0.0) as u64)
    };
    let dims: [u64; 3] = std::array::from_fn(|a| cell_of(b.max)[a] + 1);
    let key = |c: [u64; 3]| (c[2] * dims[1] + c[1]) * dims[0] + c[0];
    // Particles sorted by cell: each cell's members are one run.
    let mut keyed: Vec<(u64, u32)> = positions
        .par_iter()
        .enumerate()
        .map(|(i, p)| (key(cell_of(*p)), i as u32))
        .collect();
    voxless_bvh::order::sort_pairs(&mut keyed);
    let run = |k: u64| {
        let start = keyed.partition_point(|e| e.0 < k);
        let end = keyed.partition_point(|e| e.0 <= k);
        &keyed[start..end]
    };
    probes
        .par_iter()
        .map(|&p| {
            let c = cell_of(p);
            let mut best = f64::INFINITY;
            for dz in -1i64..=1 {
                for dy in -1i64..=1 {
                    for dx in -1i64..=1 {
                        let q = [c[0] as i64 + dx, c[1] as i64 + dy, c[2] as i64 + dz];
                        if (0..3).any(|a| q[a] < 0 || q[a] >= dims[a] as i64) {
                            continue;
                        }
                        for &(_, j) in run(key(q.map(|v| v as u64))) {
                            let d = positions[j as usize] - p;
                            let d2 =
                                (d.x as f64).powi(2) + (d.y as f64).powi(2) + (d.z as f64).powi(2);
                            // Coincident particles are no neighbours.
                            if d2 > 0.0 && d2 < best {
                                best = d2;
                            }
                        }
                    }
                }
            }
            best
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lattice(n: usize, spacing: f32, offset: Vec3) -> Vec<Vec3> {
        let mut v = Vec::new();
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    v.push(offset + Vec3::new(i as f32, j as f32, k as f32) * spacing);
                }
            }
        }
        v
    }

    #[test]
    fn a_lattice_has_its_spacing_at_any_scale() {
        for s in [1e-12f32, 1e-3, 1.0, 1e3, 1e12] {
            let p = lattice(12, s, Vec3::ZERO);
            let d = nearest_neighbour_spacing(&p).unwrap();
            assert!((d / s - 1.0).abs() < 1e-4, "scale {s}: {d}");
        }
    }

    #[test]
    fn a_small_cluster_in_a_big_box_gets_its_own_spacing() {
        let mut p = lattice(10, 0.01, Vec3::ZERO);
        p.push(Vec3::splat(100.0));
        let d = nearest_neighbour_spacing(&p).unwrap();
        assert!((d / 0.01 - 1.0).abs() < 1e-3, "{d}");
    }

    #[test]
    fn duplicates_are_passed_over_and_one_point_has_no_spacing() {
        let mut p = lattice(6, 0.5, Vec3::ZERO);
        p.extend(p.clone());
        let d = nearest_neighbour_spacing(&p).unwrap();
        assert!((d - 0.5).abs() < 1e-5, "{d}");
        assert_eq!(nearest_neighbour_spacing(&[Vec3::splat(3.0); 10]), None);
        assert_eq!(nearest_neighbour_spacing(&[Vec3::ONE]), None);
    }
}
