//! The parts of an [`AmrVolume`] built on first use: the bricks (from the
//! validated cells) and the region index (from the bricks), and how a
//! lazy build runs.

use std::time::Instant;

use voxless_bvh::Bvh;
use voxless_core::{Aabb, Range1, Vec3};

use super::{BuildStats, octant, recon};
use crate::bricks::{self, Brick};
use crate::regions::{self, Region, Regions};
use crate::walk::RegionTree;

/// Cells in input order with, per field, one value each.
pub(crate) struct InputCells {
    pub cells: Vec<[i32; 4]>,
    pub fields: Vec<Vec<f32>>,
}

/// The bricks of a volume and what reads them.
pub(super) struct Bricked {
    pub(crate) bricks: Vec<Brick>,
    /// What the reconstruction reads of each brick, derived once.
    pub(crate) grids: Vec<recon::BrickGrid>,
    /// Per field, values in brick order.
    pub(crate) values: Vec<Vec<f32>>,
    /// Brick boxes, for nearest-cell lookups and exact projections.
    pub(crate) brick_bvh: Bvh,
    /// Octant reconstruction's cell location (built for it only).
    pub(crate) octant: Option<octant::OctantIndex>,
    /// The brick columns of [`BuildStats`].
    pub(crate) stats: BuildStats,
}

impl Bricked {
    pub(super) fn build(
        input: std::sync::Arc<InputCells>,
        origin: Vec3,
        h: f32,
        octant: bool,
    ) -> Bricked {
        let mut stats = BuildStats::default();
        let t = Instant::now();
        let (bricks, values) = bricks::build(&input.cells, &input.fields);
        // Freed here, or when a projection still reading them is done.
        drop(input);
        stats.brick_build = t.elapsed();
        stats.bricks = bricks.len();
        let t = Instant::now();
        let brick_bounds: Vec<Aabb> = bricks
            .iter()
            .map(|b| to_world(origin, h, b.lower.map(i64::from), b.upper().map(i64::from)))
            .collect();
        let brick_bvh = Bvh::build(&brick_bounds);
        let octant = octant.then(|| octant::OctantIndex::new(&bricks));
        stats.bvh_build = t.elapsed();
        let grids = bricks.iter().map(recon::BrickGrid::new).collect();
        Bricked {
            bricks,
            grids,
            values,
            brick_bvh,
            octant,
            stats,
        }
    }
}

/// Runs a lazy build `f` (which works on every core) from a thread and on
/// a thread pool of its own, and waits for it.
///
/// **Why.** A build started on first use may start inside a parallel loop
/// of the global pool. Waiting there for its own parallel work would let
/// the thread steal another iteration of that loop, which asks for the
/// same build again on the same thread (a deadlock in `OnceLock`); and
/// every worker may be blocked on the build, leaving none to run its work.
/// A thread of its own waits without stealing, and its pool has free
/// workers (as many as the global pool).
pub(super) fn build_apart<T: Send>(f: impl FnOnce() -> T + Send) -> T {
    std::thread::scope(|s| {
        let job = s.spawn(|| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(rayon::current_num_threads())
                .build();
            match pool {
                Ok(pool) => pool.install(f),
                // No thread to be had for a pool: the global pool's
                // workers, the best left.
                Err(_) => f(),
            }
        });
        job.join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
    })
}

/// The world box of finest-unit corners `lo`, `hi` (what bricks, regions
/// and the bounds all map through, so their faces agree to the bit).
pub(super) fn to_world(origin: Vec3, h: f32, lo: [i64; 3], hi: [i64; 3]) -> Aabb {
    let f = |v: [i64; 3]| Vec3::new(v[0] as f64 as f32, v[1] as f64 as f32, v[2] as f64 as f32);
    Aabb::new(origin + f(lo) * h, origin + f(hi) * h)
}

/// The active brick regions of a volume (ExaBricks §3.2) and what walks
/// and samples read of them.
pub(super) struct RegionIndex {
    pub(crate) regions: Regions,
    /// World boxes of the regions.
    pub(crate) region_bounds: Vec<Aabb>,
    /// `region_ranges[r * fields + f]`.
    pub(crate) region_ranges: Vec<Range1>,
    /// Finest cell width per region, finest units.
    pub(crate) region_finest: Vec<i32>,
    /// Per region, a number it shares with exactly the regions of the same
    /// brick list (which reconstruct the same field): a ray's consecutive
    /// regions of one group are one interval.
    pub(crate) region_group: Vec<u32>,
    /// Per region, what a lane step reads of it in one load: its slice of
    /// the brick list (`start..end` in `regions.brick_ids`) and its group.
    pub(crate) region_lists: Vec<[u32; 3]>,
    /// The k-d tree the regions were cut by: ray intervals, front to back
    /// (a prepared [`crate::AmrContext`] masks the subtrees it cannot see).
    pub(crate) tree: RegionTree,
    /// All regions, for point location.
    pub(crate) region_bvh: Bvh,
    /// The region columns of [`BuildStats`].
    pub(crate) stats: BuildStats,
}

impl RegionIndex {
    pub(super) fn build(
        bricks: &[Brick],
        values: &[Vec<f32>],
        origin: Vec3,
        h: f32,
    ) -> RegionIndex {
        let mut stats = BuildStats::default();
        let t = Instant::now();
        let regions = regions::build(bricks);
        // Octant samples too are convex combinations of the values whose
        // tents reach in (see `volume/octant.rs`): one range serves all.
        let (region_ranges, region_finest) = regions::metadata(&regions, bricks, values);
        let region_group = regions::groups(&regions);
        stats.region_build = t.elapsed();
        let to_world = |lo: [f64; 3], hi: [f64; 3]| {
            Aabb::new(
                origin + Vec3::new(lo[0] as f32, lo[1] as f32, lo[2] as f32) * h,
                origin + Vec3::new(hi[0] as f32, hi[1] as f32, hi[2] as f32) * h,
            )
        };
        let region_bounds: Vec<Aabb> = regions
            .regions
            .iter()
            .map(|r| to_world(r.lo.map(|v| v as f64 * 0.5), r.hi.map(|v| v as f64 * 0.5)))
            .collect();
        stats.regions = regions.regions.len();
        let total = regions.brick_ids.len();
        stats.bricks_per_region = total as f64 / stats.regions.max(1) as f64;
        let vol = |r: &Region| (0..3).map(|a| (r.hi[a] - r.lo[a]) as f64).product::<f64>();
        let vsum: f64 = regions.regions.iter().map(vol).sum();
        stats.bricks_per_region_by_volume = regions
            .regions
            .iter()
            .map(|r| vol(r) * r.bricks.len() as f64)
            .sum::<f64>()
            / vsum.max(1.0);
        let t = Instant::now();
        // Regions come out of the k-d subdivision depth first: already coherent.
        let region_bvh = Bvh::build_in_order(&region_bounds);
        // Cut planes through the same mapping as the region boxes, so the
        // walk's intervals are the boxes' to the bit.
        let tree = RegionTree::new(&regions.tree, &region_bounds, |axis, at| {
            let mut v = [0.0f64; 3];
            v[axis] = at as f64 * 0.5;
            to_world(v, v).min[axis]
        });
        stats.bvh_build = t.elapsed();
        let region_lists = (regions.regions.iter().zip(&region_group))
            .map(|(r, &g)| [r.bricks.start, r.bricks.end, g])
            .collect();
        RegionIndex {
            regions,
            region_bounds,
            region_ranges,
            region_finest,
            region_group,
            region_lists,
            tree,
            region_bvh,
            stats,
        }
    }
}
