//! Smoothing lengths from neighbours: each particle's distance to its N-th
//! nearest neighbour (the particle itself counted, as the SPH codes and
//! the peers' `cKDTree.query(k=N)` count it), exactly, optionally in a
//! periodic box (minimum-image distances).
//!
//! The search runs over a [`Bvh`] — the tree the particle volume builds —
//! turned to points: the points are put in k-d order (median splits along
//! the longest side, at the cluster boundaries the tree splits at), grouped
//! into leaves of [`CLUSTER`] consecutive points, and the tree over the
//! leaf boxes is searched nearest child first, pruning every box farther
//! than the k-th best distance so far. Queries run in that order, in
//! parallel chunks; each query starts from its predecessor's N nearest at
//! their distances from it — N points, so a full, tight bound — and then
//! only visits boxes that could hold nearer ones (points already held are
//! marked, not offered twice). A leaf's distances are computed in f64
//! lanes; the f32 boxes are padded so pruning never drops a point that
//! belongs in the answer.
//!
//! Periodic boxes: the query is repeated for the images `q + s·L` of the
//! query point whose distance to the data is within the bound, shell by
//! shell, so the answer is exact even when the N-th neighbour lies more
//! than half a box away (each particle then counts once, at its nearest
//! image).

use rayon::prelude::*;
use voxless_bvh::Bvh;
use voxless_core::{Aabb, Vec3};

use crate::error::ParticleError;

/// Points per BVH leaf of the search.
const CLUSTER: usize = 16;

/// Queries per parallel task (consecutive along the Hilbert curve, so the
/// warm-start bound stays tight).
const CHUNK: usize = 2048;

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
    let count = positions.len();
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
    let mut out = vec![0.0f64; count];
    let found: Vec<Vec<(u32, f64)>> = search
        .sorted
        .par_chunks(CHUNK)
        .map_init(
            || vec![u32::MAX; count],
            |seen, chunk| {
                let mut best = Best::new(n);
                let mut prev: Vec<u32> = Vec::with_capacity(n);
                chunk
                    .iter()
                    .map(|&(p, i)| {
                        // The previous query's n nearest, at their distances
                        // from p: n points, so a full, tight start.
                        best.items.clear();
                        for &j in &prev {
                            let d = search.distance(p, positions[j as usize]);
                            best.items.push((d * d, j));
                            seen[j as usize] = i;
                        }
                        best.heapify();
                        let d = search.kth(p, &mut best, seen, i);
                        prev.clear();
                        prev.extend(best.items.iter().map(|it| it.1));
                        (i, d)
                    })
                    .collect()
            },
        )
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
    let mut d = neighbour_distances(positions, n, periodic)?;
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

    /// The distance between two points (minimum image when periodic).
    fn distance(&self, a: [f64; 3], b: [f64; 3]) -> f64 {
        let mut s = 0.0;
        for k in 0..3 {
            let mut d = (a[k] - b[k]).abs();
            if let Some(pb) = self.periodic {
                d = d.min(pb.size[k] - d).abs();
            }
            s += d * d;
        }
        s.sqrt()
    }

    /// The k-th nearest distance from `q`, searching from what `best`
    /// already holds (points marked in `seen` with `query`).
    fn kth(&self, q: [f64; 3], best: &mut Best, seen: &[u32], query: u32) -> f64 {
        let seen = Seen { marks: seen, query };
        let Some(pb) = self.periodic else {
            self.search(q, best, false, &seen);
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
                            self.search(image, best, m > 0, &seen);
                        }
                    }
                }
            }
            m += 1;
        }
        best.kth()
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
    fn search(&self, q: [f64; 3], best: &mut Best, dedup: bool, seen: &Seen) {
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
                // A point the start holds is there at this distance.
                if d <= best.worst() && (dedup || seen.marks[i as usize] != seen.query) {
                    best.offer(d, i, dedup);
                }
            }
            f32_bound(best.bound())
        });
    }
}

/// The points a query's start holds: those marked with its number.
struct Seen<'a> {
    marks: &'a [u32],
    query: u32,
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
