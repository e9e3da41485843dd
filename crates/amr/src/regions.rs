//! Active brick regions (ExaBricks §3.2.2–3.2.3).
//!
//! A brick's *support* is its box grown by half its cell width: where its
//! cells' hat basis functions are non-zero. The supports overlap; their
//! superposition partitions space into pieces that each know exactly which
//! bricks are active there. We cut that partition into boxes top-down: a node
//! holds a box and the support fragments overlapping it; it splits at the
//! fragment face closest to its centre, preferring its widest axis; when no
//! face lies strictly inside, every fragment covers the whole box and the box
//! becomes a region with those bricks.
//!
//! Coordinates are doubled finest units, so half-cell offsets of level-0
//! bricks stay integral.

use rayon::prelude::*;
use voxless_core::Range1;

use crate::bricks::Brick;

/// A box of space and the bricks whose support covers it.
#[derive(Clone, Debug, PartialEq)]
pub struct Region {
    /// Doubled finest units, `[lo, hi)` per axis.
    pub lo: [i64; 3],
    pub hi: [i64; 3],
    pub bricks: Vec<u32>,
}

/// A brick's support box in doubled units.
pub fn support(b: &Brick) -> ([i64; 3], [i64; 3]) {
    let w = b.width() as i64;
    let up = b.upper();
    (
        [0, 1, 2].map(|a| 2 * b.lower[a] as i64 - w),
        [0, 1, 2].map(|a| 2 * up[a] as i64 + w),
    )
}

type Fragment = ([i64; 3], [i64; 3], u32);

/// Lists with fewer fragments than this are split on one thread.
const GRAIN: usize = 2048;

/// Partitions the union of brick supports into active brick regions.
pub fn build(bricks: &[Brick]) -> Vec<Region> {
    if bricks.is_empty() {
        return Vec::new();
    }
    let frags: Vec<Fragment> = bricks
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let (lo, hi) = support(b);
            (lo, hi, i as u32)
        })
        .collect();
    let mut lo = [i64::MAX; 3];
    let mut hi = [i64::MIN; 3];
    for f in &frags {
        for a in 0..3 {
            lo[a] = lo[a].min(f.0[a]);
            hi[a] = hi[a].max(f.1[a]);
        }
    }
    let mut out = Vec::new();
    subdivide(lo, hi, frags, &mut out);
    out
}

fn subdivide(lo: [i64; 3], hi: [i64; 3], frags: Vec<Fragment>, out: &mut Vec<Region>) {
    if frags.is_empty() {
        return; // a hole: no brick reaches here
    }
    let centre = [0, 1, 2].map(|a| lo[a] + hi[a]); // doubled again, stays integral
    let mut axes = [0usize, 1, 2];
    axes.sort_by_key(|&a| std::cmp::Reverse(hi[a] - lo[a]));
    let mut plane = None;
    for &a in &axes {
        // The fragment face strictly inside (lo, hi) closest to the centre.
        let best = frags
            .iter()
            .flat_map(|f| [f.0[a], f.1[a]])
            .filter(|&x| x > lo[a] && x < hi[a])
            .min_by_key(|&x| ((2 * x - centre[a]).abs(), x));
        if let Some(x) = best {
            plane = Some((a, x));
            break;
        }
    }
    let Some((axis, x)) = plane else {
        let mut bricks: Vec<u32> = frags.iter().map(|f| f.2).collect();
        bricks.sort_unstable();
        out.push(Region { lo, hi, bricks });
        return;
    };
    let (mut left_hi, mut right_lo) = (hi, lo);
    left_hi[axis] = x;
    right_lo[axis] = x;
    let (left, right): (Vec<Fragment>, Vec<Fragment>) = (
        frags.iter().filter(|f| f.0[axis] < x).copied().collect(),
        frags.iter().filter(|f| f.1[axis] > x).copied().collect(),
    );
    if left.len() + right.len() > GRAIN {
        let (mut a, mut b) = (Vec::new(), Vec::new());
        rayon::join(
            || subdivide(lo, left_hi, left, &mut a),
            || subdivide(right_lo, hi, right, &mut b),
        );
        out.extend(a);
        out.extend(b);
    } else {
        subdivide(lo, left_hi, left, out);
        subdivide(right_lo, hi, right, out);
    }
}

/// Per region and field, the range of every cell value whose basis function
/// reaches into the region (a bound on every basis-reconstructed sample, which
/// is a convex combination of those values), and the finest cell width there.
pub fn metadata(
    regions: &[Region],
    bricks: &[Brick],
    fields: &[Vec<f32>],
) -> (Vec<Range1>, Vec<i32>) {
    let nf = fields.len();
    let per: Vec<(Vec<Range1>, i32)> = regions
        .par_iter()
        .map(|r| {
            let mut ranges = vec![Range1::EMPTY; nf];
            let mut finest = i32::MAX;
            for &b in &r.bricks {
                let b = &bricks[b as usize];
                let w = b.width() as i64;
                finest = finest.min(b.width());
                // Doubled units: cell i has centre c = base + (2i + 1)w and its
                // hat reaches (c − 2w, c + 2w); keep cells overlapping (lo, hi):
                // c + 2w > lo ⇔ i > (lo − base − 3w)/2w, c − 2w < hi ⇔ i < (hi − base + w)/2w.
                let span = |a: usize| {
                    let base = 2 * b.lower[a] as i64;
                    let i0 = (r.lo[a] - base - 3 * w).div_euclid(2 * w) + 1;
                    let i1 = -(-(r.hi[a] - base + w)).div_euclid(2 * w) - 1;
                    (i0.max(0), i1.min(b.size[a] as i64 - 1))
                };
                let (x, y, z) = (span(0), span(1), span(2));
                for k in z.0..=z.1 {
                    for j in y.0..=y.1 {
                        for i in x.0..=x.1 {
                            let idx = b.offset as usize
                                + ((k * b.size[1] as i64 + j) * b.size[0] as i64 + i) as usize;
                            for (f, range) in ranges.iter_mut().enumerate() {
                                range.extend(fields[f][idx]);
                            }
                        }
                    }
                }
            }
            (ranges, finest)
        })
        .collect();
    let mut ranges = Vec::with_capacity(regions.len() * nf);
    let mut finest = Vec::with_capacity(regions.len());
    for (r, f) in per {
        ranges.extend(r);
        finest.push(f);
    }
    (ranges, finest)
}
