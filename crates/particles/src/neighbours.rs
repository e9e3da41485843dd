//! Smoothing lengths from neighbours: each particle's distance to its N-th
//! nearest neighbour (the particle itself counted, as the SPH codes and
//! the peers' `cKDTree.query(k=N)` count it), exactly, optionally in a
//! periodic box (minimum-image distances).
//!
//! The points are put in k-d order (median splits along the longest side,
//! at the cluster boundaries the tree splits at) and grouped into leaves of
//! [`CLUSTER`] consecutive points; a [`Bvh`] — the tree the particle volume
//! builds — is built over the leaf boxes. The queries are the points
//! themselves, a leaf at a time:
//!
//! 1. **Gather**: every point within a reach `r` of the leaf's box is
//!    collected once for the leaf's 16 queries (a box query, at the image
//!    lying near the box when periodic), in coordinate lanes.
//! 2. **Select**: each query scans those lanes branch-free, keeps the
//!    distances within `r` of itself and selects the N-th. If at least N
//!    lie within `r`, the answer is exact: every point not gathered lies
//!    beyond `r` of the box, hence of the query.
//! 3. Queries with fewer than N within reach retry with a 1.5× wider gather
//!    (twice), then fall back to a best-first heap search of the tree.
//!
//! The reach is 1.1× the previous leaf's largest answer: neighbouring leaves
//! have similar densities, so about 1 % of queries fall back. Distances are
//! f64; the f32 boxes are padded so pruning never drops a point of the
//! answer. This is about 2× faster than a heap search per query (the heap's
//! sift-downs and the data-dependent branches were most of its time).
//!
//! Periodic boxes: a gather is exact while no point can be within reach at
//! two images (box extent + 2r below the period); otherwise the heap search
//! repeats for the images `q + s·L` of the query point within its bound,
//! shell by shell, so the answer is exact even when the N-th neighbour lies
//! more than half a box away (each particle then counts once, at its
//! nearest image).

use rayon::prelude::*;
use voxless_bvh::Bvh;
use voxless_core::{Aabb, Vec3};

use crate::error::ParticleError;

/// Points per BVH leaf of the search.
const CLUSTER: usize = 16;

/// Queries per parallel task (consecutive in k-d order, so each leaf's
/// reach can come from the one before).
const CHUNK: usize = 2048;

/// How often each path answered, for the tests to see that all ran:
/// the first gather, a wider one, the heap.
#[cfg(test)]
pub(crate) mod tally {
    use std::sync::atomic::{AtomicUsize, Ordering};
    pub static PATHS: [AtomicUsize; 3] = [const { AtomicUsize::new(0) }; 3];
    pub fn count(path: usize) {
        PATHS[path].fetch_add(1, Ordering::Relaxed);
    }
}

/// The 27 image shifts of a periodic box.
const SHIFTS: [[i32; 3]; 27] = {
    let mut s = [[0i32; 3]; 27];
    let mut k = 0;
    while k < 27 {
        s[k] = [
            (k / 9) as i32 - 1,
            (k / 3 % 3) as i32 - 1,
            (k % 3) as i32 - 1,
        ];
        k += 1;
    }
    s
};

/// A periodic box: the lower corner and the edge lengths.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PeriodicBox {
    pub lo: [f64; 3],
    pub size: [f64; 3],
}

impl PeriodicBox {
    /// `p` moved into `[lo, lo + size)` along every axis.
    pub fn wrap(&self, p: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|a| {
            let l = self.size[a];
            let mut v = (p[a] - self.lo[a]).rem_euclid(l);
            // rem_euclid may round up to l itself.
            if v >= l {
                v = 0.0;
            }
            self.lo[a] + v
        })
    }

    /// Whether `p` lies in `[lo, lo + size)`.
    pub fn contains(&self, p: [f64; 3]) -> bool {
        (0..3).all(|a| p[a] >= self.lo[a] && p[a] < self.lo[a] + self.size[a])
    }
}

/// The distance from each of `positions` to its `n`-th nearest neighbour
/// among `positions` (itself counted, so `n ≥ 2`), in input order;
/// minimum-image distances in `periodic` (whose positions must lie in the
/// box: see [`PeriodicBox::wrap`]).
pub fn neighbour_distances(
    positions: &[[f64; 3]],
    n: usize,
    periodic: Option<&PeriodicBox>,
) -> Result<Vec<f64>, ParticleError> {
    neighbour_distances_of(positions, positions.len(), n, periodic)
}

/// [`neighbour_distances`] of the first `queries` of `positions` only,
/// among all of them (a part of a set with its halo: the rest are there to
/// be found, not asked about).
pub fn neighbour_distances_of(
    positions: &[[f64; 3]],
    queries: usize,
    n: usize,
    periodic: Option<&PeriodicBox>,
) -> Result<Vec<f64>, ParticleError> {
    let count = positions.len();
    let queries = queries.min(count);
    if n < 2 || n > count {
        return Err(ParticleError::BadNeighbours { n, count });
    }
    if let Some(i) = positions
        .iter()
        .position(|p| !p.iter().all(|v| v.is_finite()))
    {
        let p = positions[i];
        return Err(ParticleError::NonFinitePosition {
            index: i,
            x: p[0] as f32,
            y: p[1] as f32,
            z: p[2] as f32,
        });
    }
    let search = Search::new(positions, periodic);
    let mut out = vec![0.0f64; queries];
    let found: Vec<Vec<(u32, f64)>> = search
        .sorted
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(t, chunk)| {
            let mut best = Best::new(n);
            let mut batch = Batch::default();
            let mut found = Vec::with_capacity(chunk.len());
            // The gather radius: a little beyond the previous cluster's
            // largest answer (neighbouring clusters have similar density).
            let mut reach = 0.0f64;
            for (k, members) in chunk.chunks(CLUSTER).enumerate() {
                let c = t * (CHUNK / CLUSTER) + k;
                // Gather around the cluster; members with fewer than n
                // points within reach try a wider gather, then the heap.
                // A chunk's first cluster seeds the reach with one heap
                // search.
                let mut answer = [f64::NAN; CLUSTER];
                let mut pending: Vec<usize> = (0..members.len())
                    .filter(|&j| (members[j].1 as usize) < queries)
                    .collect();
                if pending.is_empty() {
                    continue;
                }
                if !(reach > 0.0) {
                    let j = pending.remove(0);
                    best.items.clear();
                    answer[j] = search.kth(members[j].0, &mut best);
                    reach = answer[j] * 1.5;
                }
                let mut r = reach;
                for _ in 0..3 {
                    if pending.is_empty() || !(r > 0.0) || !search.gather(c, r, &mut batch) {
                        break;
                    }
                    #[cfg(test)]
                    let first_try = r == reach;
                    pending.retain(|&j| match batch.kth(members[j].0, n, r) {
                        Some(d) => {
                            #[cfg(test)]
                            tally::count(if first_try { 0 } else { 1 });
                            answer[j] = d;
                            false
                        }
                        None => true,
                    });
                    r *= 1.5;
                }
                for &j in &pending {
                    #[cfg(test)]
                    tally::count(2);
                    best.items.clear();
                    answer[j] = search.kth(members[j].0, &mut best);
                }
                let mut largest = 0.0f64;
                for (j, &(_, i)) in members.iter().enumerate() {
                    if (i as usize) < queries {
                        largest = largest.max(answer[j]);
                        found.push((i, answer[j]));
                    }
                }
                reach = largest * 1.1;
            }
            found
        })
        .collect();
    for (i, d) in found.into_iter().flatten() {
        out[i as usize] = d;
    }
    Ok(out)
}

/// Each particle's radius parameter for `kernel` such that its support
/// reaches exactly its `n`-th nearest neighbour (see
/// [`neighbour_distances`]), in input order. A particle with `n − 1` others
/// at its own position would get radius 0: an error naming it.
pub fn smoothing_lengths(
    positions: &[[f64; 3]],
    n: usize,
    periodic: Option<&PeriodicBox>,
    kernel: crate::Kernel,
) -> Result<Vec<f64>, ParticleError> {
    radii_from_distances(neighbour_distances(positions, n, periodic)?, n, kernel)
}

/// Radius parameters for `kernel` from the distances `d` to each
/// particle's `n`-th nearest neighbour (its support reaches that far). A
/// distance of 0 — `n − 1` others at the particle's own position — is an
/// error naming the particle (its index in `d`).
pub fn radii_from_distances(
    mut d: Vec<f64>,
    n: usize,
    kernel: crate::Kernel,
) -> Result<Vec<f64>, ParticleError> {
    if let Some(index) = d.iter().position(|&v| !(v > 0.0)) {
        return Err(ParticleError::CoincidentNeighbours {
            index,
            others: n - 1,
        });
    }
    let factor = kernel.support_factor() as f64;
    d.iter_mut().for_each(|v| *v /= factor);
    Ok(d)
}

/// Orders `points` as the depth-first leaves of a k-d tree whose leaves
/// hold [`CLUSTER`] points (the last one fewer).
fn kd_order(points: &mut [([f64; 3], u32)]) {
    if points.len() <= CLUSTER {
        return;
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for (p, _) in points.iter() {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let axis = (0..3)
        .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
        .unwrap_or(0);
    // The split the tree over the clusters makes (the highest bit of the
    // cluster index), so each node of the tree is a cell of the k-d tree.
    let clusters = points.len().div_ceil(CLUSTER);
    let mid = (1usize << (usize::BITS - 1 - (clusters - 1).leading_zeros())) * CLUSTER;
    points.select_nth_unstable_by(mid, |a, b| a.0[axis].total_cmp(&b.0[axis]));
    let (left, right) = points.split_at_mut(mid);
    if left.len() > 4096 {
        rayon::join(|| kd_order(left), || kd_order(right));
    } else {
        kd_order(left);
        kd_order(right);
    }
}

/// The points in k-d order, their clusters and the tree over them.
struct Search<'a> {
    /// Points in k-d order with their input index.
    sorted: Vec<([f64; 3], u32)>,
    /// The same points per cluster as `[x; CLUSTER], [y; …], [z; …]`
    /// (NaN-padded), so a leaf's distances are computed in SIMD lanes.
    lanes: Vec<[[f64; CLUSTER]; 3]>,
    bvh: Bvh,
    /// Bounds of all points (padded like the cluster boxes).
    bounds: Aabb,
    periodic: Option<&'a PeriodicBox>,
    /// Absolute padding of the f32 boxes: f32 rounding of a coordinate
    /// moves it by at most this much.
    pad: f64,
}

impl<'a> Search<'a> {
    fn new(positions: &[[f64; 3]], periodic: Option<&'a PeriodicBox>) -> Self {
        let f = |p: &[f64; 3]| Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32);
        let mut bounds = Aabb::EMPTY;
        let mut far = 0.0f64;
        for p in positions {
            bounds.grow(f(p));
            far = p.iter().fold(far, |m, v| m.max(v.abs()));
        }
        let pad = (far * 4.0 * f32::EPSILON as f64).max(f32::MIN_POSITIVE as f64);
        // A k-d order: median splits along the longest side, at multiples
        // of the cluster size, so every cluster is a tight leaf.
        let mut sorted: Vec<([f64; 3], u32)> = positions
            .iter()
            .enumerate()
            .map(|(i, &p)| (p, i as u32))
            .collect();
        kd_order(&mut sorted);
        let padv = Vec3::splat(pad as f32);
        let boxes: Vec<Aabb> = sorted
            .par_chunks(CLUSTER)
            .map(|c| {
                let b = c.iter().fold(Aabb::EMPTY, |mut b, (p, _)| {
                    b.grow(f(p));
                    b
                });
                Aabb::new(b.min - padv, b.max + padv)
            })
            .collect();
        let bvh = Bvh::build_in_order(&boxes);
        let lanes = sorted
            .chunks(CLUSTER)
            .map(|c| {
                let mut l = [[f64::NAN; CLUSTER]; 3];
                for (j, (p, _)) in c.iter().enumerate() {
                    for a in 0..3 {
                        l[a][j] = p[a];
                    }
                }
                l
            })
            .collect();
        Search {
            sorted,
            lanes,
            bvh,
            bounds: Aabb::new(bounds.min - padv, bounds.max + padv),
            periodic,
            pad,
        }
    }

    /// The k-th nearest distance from `q` by a best-first search, adding to
    /// what `best` holds.
    fn kth(&self, q: [f64; 3], best: &mut Best) -> f64 {
        let Some(pb) = self.periodic else {
            self.search(q, best, false);
            return best.kth();
        };
        // Shell m holds the shifts with max |s| = m; its images are at
        // least (m − 1)·L from the box (q lies in it), so the shells stop
        // once that exceeds the bound.
        let min_size = pb.size.iter().fold(f64::INFINITY, |m, &v| m.min(v));
        let mut m = 0i64;
        loop {
            if m >= 2 && ((m - 1) as f64 * min_size) > best.bound() {
                break;
            }
            for sx in -m..=m {
                for sy in -m..=m {
                    for sz in -m..=m {
                        if sx.abs().max(sy.abs()).max(sz.abs()) != m {
                            continue;
                        }
                        let s = [sx, sy, sz];
                        let image: [f64; 3] =
                            std::array::from_fn(|a| q[a] + s[a] as f64 * pb.size[a]);
                        if self.box_distance(image) <= best.bound() {
                            self.search(image, best, m > 0);
                        }
                    }
                }
            }
            m += 1;
        }
        best.kth()
    }

    /// Gathers into `batch` every point within `reach` of cluster `c`'s
    /// box, at its image there; false where `reach` is too wide for that
    /// image to be unique (a point near the box at two images).
    fn gather(&self, c: usize, reach: f64, batch: &mut Batch) -> bool {
        batch.clear();
        let first = c * CLUSTER;
        let members = &self.sorted[first..(first + CLUSTER).min(self.sorted.len())];
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for (p, _) in members {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        // Rounding between the box test and the distances below: gather a
        // little wider; the per-query test uses `reach` itself.
        let r = reach * (1.0 + 1e-9);
        let shifts: &[[i32; 3]] = match self.periodic {
            None => &[[0; 3]],
            Some(pb) => {
                if (0..3).any(|a| hi[a] - lo[a] + 2.0 * r >= pb.size[a]) {
                    return false;
                }
                &SHIFTS
            }
        };
        for s in shifts {
            // Points x with x + s·L near the box are points near the box − s·L.
            let off: [f64; 3] = match self.periodic {
                None => [0.0; 3],
                Some(pb) => std::array::from_fn(|a| s[a] as f64 * pb.size[a]),
            };
            let (blo, bhi): ([f64; 3], [f64; 3]) = (
                std::array::from_fn(|a| lo[a] - off[a]),
                std::array::from_fn(|a| hi[a] - off[a]),
            );
            let grow = r + 2.0 * self.pad;
            let query = Aabb::new(
                Vec3::new(
                    (blo[0] - grow) as f32,
                    (blo[1] - grow) as f32,
                    (blo[2] - grow) as f32,
                ),
                Vec3::new(
                    (bhi[0] + grow) as f32,
                    (bhi[1] + grow) as f32,
                    (bhi[2] + grow) as f32,
                ),
            );
            let b = &self.bounds;
            if (0..3).any(|a| query.min[a] > b.max[a] || query.max[a] < b.min[a]) {
                continue;
            }
            let r2 = r * r;
            self.bvh.box_query(&query, |leaf, _| {
                // Branch-free, in the leaf's lanes: every slot is written,
                // the length only grows for points within reach.
                let l = &self.lanes[leaf as usize];
                let points = (self.sorted.len() - leaf as usize * CLUSTER).min(CLUSTER);
                let mut m = batch.x.len();
                let grown = m + points;
                batch.x.resize(grown, 0.0);
                batch.y.resize(grown, 0.0);
                batch.z.resize(grown, 0.0);
                let (xs, ys, zs) = (&l[0][..points], &l[1][..points], &l[2][..points]);
                for ((&x, &y), &z) in xs.iter().zip(ys).zip(zs) {
                    let p = [x, y, z];
                    let mut d2 = 0.0;
                    for a in 0..3 {
                        let d = (blo[a] - p[a]).max(p[a] - bhi[a]).max(0.0);
                        d2 += d * d;
                    }
                    batch.x[m] = x + off[0];
                    batch.y[m] = y + off[1];
                    batch.z[m] = z + off[2];
                    m += (d2 <= r2) as usize;
                }
                batch.x.truncate(m);
                batch.y.truncate(m);
                batch.z.truncate(m);
            });
        }
        true
    }

    /// Distance from `p` to the points' bounds (0 inside).
    fn box_distance(&self, p: [f64; 3]) -> f64 {
        let b = &self.bounds;
        let mut s = 0.0;
        for (a, &v) in p.iter().enumerate() {
            let d = (b.min[a] as f64 - v).max(v - b.max[a] as f64).max(0.0);
            s += d * d;
        }
        s.sqrt()
    }

    /// Adds the points near `q` to `best`; `dedup`: a point may already be
    /// there at another image (keep its nearest).
    fn search(&self, q: [f64; 3], best: &mut Best, dedup: bool) {
        let qf = Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32);
        // The f32 query is off by up to `pad` too: pad the bound twice.
        let f32_bound = |b: f64| {
            if b.is_finite() {
                let r = b + 2.0 * self.pad;
                (r * r * (1.0 + 1e-6)) as f32
            } else {
                f32::INFINITY
            }
        };
        let start = f32_bound(best.bound());
        self.bvh.nearest(qf, start, |c| {
            let l = &self.lanes[c as usize];
            let mut d2 = [0.0f64; CLUSTER];
            for j in 0..CLUSTER {
                let (x, y, z) = (l[0][j] - q[0], l[1][j] - q[1], l[2][j] - q[2]);
                d2[j] = x * x + y * y + z * z;
            }
            // The last cluster's padding is NaN (its distances are too).
            let first = c as usize * CLUSTER;
            let members = &self.sorted[first..(first + CLUSTER).min(self.sorted.len())];
            for (&d, &(_, i)) in d2.iter().zip(members) {
                if d <= best.worst() {
                    best.offer(d, i, dedup);
                }
            }
            f32_bound(best.bound())
        });
    }
}

/// The points within a radius of one cluster's box (at their image
/// there), as coordinate lanes, and a scratch list for one query's selection.
#[derive(Default)]
struct Batch {
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
    near: Vec<f64>,
}

impl Batch {
    fn clear(&mut self) {
        self.x.clear();
        self.y.clear();
        self.z.clear();
    }

    /// The n-th nearest distance of `q`, a point of the cluster, when at
    /// least n gathered points lie within `reach` of it (then every point
    /// nearer than the n-th was gathered: the rest lie beyond `reach` of
    /// the whole box).
    fn kth(&mut self, q: [f64; 3], n: usize, reach: f64) -> Option<f64> {
        let r2 = reach * reach;
        // Branch-free: every distance is written, the count only grows for
        // those within reach (about half of them: a branch would mispredict).
        let len = self.x.len();
        self.near.resize(len, 0.0);
        let (x, y, z) = (&self.x[..len], &self.y[..len], &self.z[..len]);
        let mut m = 0;
        for c in 0..len {
            let (dx, dy, dz) = (x[c] - q[0], y[c] - q[1], z[c] - q[2]);
            let d2 = dx * dx + dy * dy + dz * dz;
            self.near[m] = d2;
            m += (d2 <= r2) as usize;
        }
        self.near.truncate(m);
        if self.near.len() < n {
            return None;
        }
        let (_, d, _) = self
            .near
            .select_nth_unstable_by(n - 1, |a, b| a.total_cmp(b));
        Some(d.sqrt())
    }
}

/// The k best squared distances so far, as a max-heap (the worst on
/// top), with their points.
struct Best {
    k: usize,
    items: Vec<(f64, u32)>,
}

impl Best {
    fn new(k: usize) -> Self {
        Best {
            k,
            items: Vec::with_capacity(k),
        }
    }

    /// The squared distance a point must not exceed to enter: the k-th
    /// best when k are known, else unbounded.
    #[inline]
    fn worst(&self) -> f64 {
        if self.items.len() == self.k {
            self.items[0].0
        } else {
            f64::INFINITY
        }
    }

    /// The current search radius.
    fn bound(&self) -> f64 {
        self.worst().sqrt()
    }

    #[inline]
    fn offer(&mut self, d2: f64, i: u32, dedup: bool) {
        let full = self.items.len() == self.k;
        if full && d2 >= self.items[0].0 {
            return;
        }
        if dedup && let Some(j) = self.items.iter().position(|it| it.1 == i) {
            // The same point at a nearer image: keep the nearer, re-heap.
            if d2 < self.items[j].0 {
                self.items[j].0 = d2;
                self.heapify();
            }
            return;
        }
        if full {
            self.items[0] = (d2, i);
            self.sift_down(0);
        } else {
            self.items.push((d2, i));
            let mut c = self.items.len() - 1;
            while c > 0 {
                let parent = (c - 1) / 2;
                if self.items[parent].0 >= self.items[c].0 {
                    break;
                }
                self.items.swap(parent, c);
                c = parent;
            }
        }
    }

    fn sift_down(&mut self, mut at: usize) {
        let n = self.items.len();
        loop {
            let (l, r) = (2 * at + 1, 2 * at + 2);
            let mut big = at;
            if l < n && self.items[l].0 > self.items[big].0 {
                big = l;
            }
            if r < n && self.items[r].0 > self.items[big].0 {
                big = r;
            }
            if big == at {
                return;
            }
            self.items.swap(at, big);
            at = big;
        }
    }

    fn heapify(&mut self) {
        for at in (0..self.items.len() / 2).rev() {
            self.sift_down(at);
        }
    }

    fn kth(&self) -> f64 {
        // The start bound is an upper bound of the answer, so k were found.
        debug_assert_eq!(self.items.len(), self.k);
        self.items.first().map_or(0.0, |it| it.0.sqrt())
    }
}
