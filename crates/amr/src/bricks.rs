//! Cells → validated, bricked storage (ExaBricks §3.1).
//!
//! Cells are `(x, y, z, level)` with the lower corner in finest-cell units and
//! width `2^level`. Validation: each cell is aligned to its level (coordinates
//! are multiples of its width) and no two cells overlap. Overlap is found in
//! Morton order: an aligned cube of width `2^l` covers exactly the Morton keys
//! `[m, m + 8^l)` of its finest cells, so cells overlap iff these ranges do.
//!
//! Bricks come from a top-down k-d tree over the cells: a node becomes a brick
//! when its cells share one level and exactly fill their bounding box, at most
//! 32 cells per axis; otherwise it splits its longest axis near the middle at a
//! multiple of the node's coarsest cell width, which never cuts a cell. The
//! middle split also cuts uniform stretches next to a refined patch into
//! small bricks, so a last pass joins same-level bricks that abut with the
//! same cross-section (still at most 32 per axis): 3,018 → 659 bricks on the
//! AMRClaw frame, with half the regions.

use rayon::prelude::*;
use voxless_bvh::order::morton;

use crate::AmrError;

/// A box of same-level cells, `size` cells per axis, values stored x fastest
/// from `offset` in every field's brick-ordered array.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Brick {
    pub lower: [i32; 3],
    pub size: [i32; 3],
    pub level: u8,
    pub offset: u32,
}

impl Brick {
    pub fn width(&self) -> i32 {
        1 << self.level
    }
    pub fn cell_count(&self) -> usize {
        self.size.iter().map(|&s| s as usize).product()
    }
    /// Upper corner (exclusive), finest units.
    pub fn upper(&self) -> [i32; 3] {
        [0, 1, 2].map(|a| self.lower[a] + self.size[a] * self.width())
    }
}

/// Largest level accepted: widths stay far inside `i32`.
pub const MAX_LEVEL: i32 = 20;
/// Cells per brick axis at most.
const BRICK_MAX: i32 = 32;

/// Checks alignment and overlap and returns the cells' extent (lower and
/// exclusive upper corner, finest units). Errors name the cell indices.
pub fn validate(cells: &[[i32; 4]]) -> Result<([i64; 3], [i64; 3]), AmrError> {
    if cells.is_empty() {
        return Err(AmrError::Empty);
    }
    // Levels and alignment (a power-of-two width divides a coordinate iff
    // its low bits are 0, in two's complement too), and the extent with the
    // coarsest width, in one pass on every core; the first bad cell in
    // input order is reported.
    let aligned = |c: &[i32; 4]| {
        (0..=MAX_LEVEL).contains(&c[3]) && {
            let low = (1i32 << c[3]) - 1;
            (c[0] | c[1] | c[2]) & low == 0
        }
    };
    type Extent = ([i64; 3], [i64; 3], i32, usize);
    let none: Extent = ([i64::MAX; 3], [i64::MIN; 3], 0, usize::MAX);
    let (min, max, top, bad) = cells
        .par_iter()
        .enumerate()
        .fold(
            || none,
            |(mut lo, mut hi, top, bad), (i, c)| {
                if !aligned(c) {
                    return (lo, hi, top, bad.min(i));
                }
                for a in 0..3 {
                    lo[a] = lo[a].min(c[a] as i64);
                    hi[a] = hi[a].max(c[a] as i64 + (1i64 << c[3]));
                }
                (lo, hi, top.max(c[3]), bad)
            },
        )
        .reduce(
            || none,
            |a, b| {
                let lo = [0, 1, 2].map(|k| a.0[k].min(b.0[k]));
                let hi = [0, 1, 2].map(|k| a.1[k].max(b.1[k]));
                (lo, hi, a.2.max(b.2), a.3.min(b.3))
            },
        );
    if bad != usize::MAX {
        let c = cells[bad];
        if !(0..=MAX_LEVEL).contains(&c[3]) {
            return Err(AmrError::BadLevel {
                cell: bad,
                level: c[3],
            });
        }
        return Err(AmrError::Misaligned {
            cell: bad,
            pos: [c[0], c[1], c[2]],
            level: c[3],
        });
    }
    // Morton ranges need non-negative coordinates below 2^21.
    // Align the shift to the coarsest width so cells stay aligned after it.
    let coarsest = 1i64 << top;
    let shift = min.map(|m| m.div_euclid(coarsest) * coarsest);
    if (0..3).any(|a| max[a] - shift[a] > 1 << 21) {
        return Err(AmrError::TooLarge {
            extent: (0..3).map(|a| max[a] - shift[a]).max().unwrap_or(0),
        });
    }
    // Levels compact enough for a bitmap each answer at memory speed;
    // an overlap found there is named by the sorted check below.
    if no_overlap_in_bitmaps(cells) == Some(true) {
        return Ok((min, max));
    }
    let key = |c: &[i32; 4]| morton([0, 1, 2].map(|a| (c[a] as i64 - shift[a]) as u32));
    // Overlap of two cells given by key and level (a cell and the cell
    // reaching furthest before it), named by their input indices.
    let overlap = |first: (u64, i32), second: (u64, i32)| {
        let find = |(k, l): (u64, i32), not: Option<usize>| {
            (0..cells.len())
                .find(|&i| Some(i) != not && cells[i][3] == l && key(&cells[i]) == k)
                .unwrap_or(0)
        };
        let a = find(first, None);
        let b = find(second, Some(a));
        AmrError::Overlap {
            a: a.min(b),
            b: a.max(b),
        }
    };
    // Sorted by each cell's first Morton key, a cell overlaps another iff
    // its key falls inside the range of a cell before it. Within 2^19 per
    // axis (57 bits of key) the level rides in the low bits of one u64,
    // which sorts fastest; the indices are found again for an error only.
    if (0..3).all(|a| max[a] - shift[a] <= 1 << 19) {
        let mut keys: Vec<u64> = cells
            .par_iter()
            .map(|c| key(c) << 5 | c[3] as u64)
            .collect();
        keys.par_sort_unstable();
        let mut end = 0u64;
        let mut owner = (0u64, 0i32);
        for (k, &packed) in keys.iter().enumerate() {
            let (start, level) = (packed >> 5, (packed & 31) as i32);
            if k > 0 && start < end {
                return Err(overlap(owner, (start, level)));
            }
            let stop = start + (1u64 << (3 * level));
            if stop > end {
                end = stop;
                owner = (start, level);
            }
        }
        return Ok((min, max));
    }
    let mut ranges: Vec<(u64, u32, u32)> = cells
        .par_iter()
        .enumerate()
        .map(|(i, c)| (key(c), c[3] as u32, i as u32))
        .collect();
    ranges.par_sort_unstable_by_key(|r| r.0);
    let mut end = 0u64;
    let mut owner = 0u32;
    for (k, &(start, level, i)) in ranges.iter().enumerate() {
        if k > 0 && start < end {
            let (a, b) = (owner.min(i) as usize, owner.max(i) as usize);
            return Err(AmrError::Overlap { a, b });
        }
        let stop = start + (1u64 << (3 * level));
        if stop > end {
            end = stop;
            owner = i;
        }
    }
    Ok((min, max))
}

/// Whether no two (aligned) cells overlap, from one bitmap per level over
/// that level's cells' box (in its own cell units): a cell overlaps
/// another of its level iff it is marked twice, and a coarser cell iff its
/// ancestor there is marked (aligned cubes nest or miss). `None` when the
/// boxes hold far more room than cells (sparse levels: the sort decides).
pub(crate) fn no_overlap_in_bitmaps(cells: &[[i32; 4]]) -> Option<bool> {
    use std::sync::atomic::{AtomicU64, Ordering};
    const LEVELS: usize = MAX_LEVEL as usize + 1;
    // Per level: box lower and upper corner (level units) and cell count.
    type Boxes = Vec<([i64; 3], [i64; 3], usize)>;
    let empty = || vec![([i64::MAX; 3], [i64::MIN; 3], 0usize); LEVELS];
    let boxes: Boxes = cells
        .par_iter()
        .fold(empty, |mut b, c| {
            let l = c[3] as usize;
            let p = [0, 1, 2].map(|a| (c[a] >> c[3]) as i64);
            let (lo, hi, n) = &mut b[l];
            *lo = [0, 1, 2].map(|a| lo[a].min(p[a]));
            *hi = [0, 1, 2].map(|a| hi[a].max(p[a] + 1));
            *n += 1;
            b
        })
        .reduce(empty, |mut a, b| {
            for (x, y) in a.iter_mut().zip(b) {
                x.0 = [0, 1, 2].map(|k| x.0[k].min(y.0[k]));
                x.1 = [0, 1, 2].map(|k| x.1[k].max(y.1[k]));
                x.2 += y.2;
            }
            a
        });
    let room = |b: &([i64; 3], [i64; 3], usize)| {
        (0..3)
            .map(|a| (b.1[a] - b.0[a]).max(0) as u64)
            .product::<u64>()
    };
    let bits: u64 = boxes.iter().filter(|b| b.2 > 0).map(room).sum();
    if bits > 64 * cells.len() as u64 + (1 << 22) {
        return None;
    }
    let maps: Vec<Vec<AtomicU64>> = boxes
        .iter()
        .map(|b| match b.2 {
            0 => Vec::new(),
            _ => (0..room(b).div_ceil(64))
                .map(|_| AtomicU64::new(0))
                .collect(),
        })
        .collect();
    // The bit of the level-`l` cell holding finest point `c`, if the level's
    // box holds it.
    let bit = |c: &[i32; 4], l: usize| {
        let (lo, hi, _) = &boxes[l];
        let p = [0, 1, 2].map(|a| (c[a] >> l) as i64);
        if (0..3).any(|a| p[a] < lo[a] || p[a] >= hi[a]) {
            return None;
        }
        let n = [0, 1, 2].map(|a| hi[a] - lo[a]);
        Some((((p[2] - lo[2]) * n[1] + (p[1] - lo[1])) * n[0] + (p[0] - lo[0])) as u64)
    };
    let twice = cells.par_iter().any(|c| {
        let l = c[3] as usize;
        let i = bit(c, l).unwrap_or(0);
        let mask = 1u64 << (i % 64);
        maps[l][(i / 64) as usize].fetch_or(mask, Ordering::Relaxed) & mask != 0
    });
    if twice {
        return Some(false);
    }
    let present: Vec<usize> = (0..LEVELS).filter(|&l| boxes[l].2 > 0).collect();
    let nested = cells.par_iter().any(|c| {
        let l = c[3] as usize;
        present.iter().filter(|&&up| up > l).any(|&up| {
            bit(c, up).is_some_and(|i| {
                maps[up][(i / 64) as usize].load(Ordering::Relaxed) & (1u64 << (i % 64)) != 0
            })
        })
    });
    Some(!nested)
}

/// A cell during brick construction: position, level, input index.
#[derive(Clone, Copy)]
struct CellRef {
    pos: [i32; 3],
    level: u8,
    index: u32,
}

/// A brick as a contiguous run of the partitioned cells.
struct Leaf {
    lower: [i32; 3],
    size: [i32; 3],
    level: u8,
    start: usize,
}

/// A brick after merging: its box and the runs `(start, len)` of the
/// partitioned cells it holds.
struct Merged {
    lower: [i32; 3],
    size: [i32; 3],
    level: u8,
    runs: Vec<(usize, usize)>,
}

/// Builds the bricks and returns them with, per field, the values in brick
/// order. `cells` must have passed [`validate`].
pub fn build(cells: &[[i32; 4]], fields: &[Vec<f32>]) -> (Vec<Brick>, Vec<Vec<f32>>) {
    let mut refs: Vec<CellRef> = cells
        .iter()
        .enumerate()
        .map(|(i, c)| CellRef {
            pos: [c[0], c[1], c[2]],
            level: c[3] as u8,
            index: i as u32,
        })
        .collect();
    let leaves = merge(split(&mut refs, 0));
    let mut bricks = Vec::with_capacity(leaves.len());
    let mut offset = 0u32;
    for l in &leaves {
        let b = Brick {
            lower: l.lower,
            size: l.size,
            level: l.level,
            offset,
        };
        offset += b.cell_count() as u32;
        bricks.push(b);
    }
    // Scatter each field into brick order (x fastest within a brick), each
    // brick's range on its own core.
    let ordered = fields
        .iter()
        .map(|values| {
            let mut out = vec![0.0f32; values.len()];
            let mut parts = Vec::with_capacity(bricks.len());
            let mut rest = out.as_mut_slice();
            for b in &bricks {
                let (part, tail) = rest.split_at_mut(b.cell_count());
                parts.push(part);
                rest = tail;
            }
            parts
                .into_par_iter()
                .zip(&bricks)
                .zip(&leaves)
                .for_each(|((part, b), l)| {
                    let w = b.width();
                    for &(start, len) in &l.runs {
                        for c in &refs[start..start + len] {
                            let i = [0, 1, 2].map(|a| (c.pos[a] - b.lower[a]) / w);
                            let local = (i[2] * b.size[1] + i[1]) * b.size[0] + i[0];
                            part[local as usize] = values[c.index as usize];
                        }
                    }
                });
            out
        })
        .collect();
    (bricks, ordered)
}

/// Joins bricks of one level that abut face to face with the same cross
/// section, while the result stays within [`BRICK_MAX`] cells per axis.
///
/// **Why.** The middle split cuts runs of same-level cells wherever the
/// node's middle falls, not only where the level changes, so a uniform
/// stretch next to a refined patch ends up in many small bricks. Every
/// brick seam is a band where two bricks' supports overlap: the regions
/// multiply and each sample there sums two (at edges four, at corners
/// eight) bricks' stencils. Which bricks hold the cells does not change
/// the reconstruction (a sum over cells), only its cost.
fn merge(leaves: Vec<Leaf>) -> Vec<Merged> {
    let mut out: Vec<Merged> = leaves
        .into_iter()
        .map(|l| Merged {
            lower: l.lower,
            size: l.size,
            level: l.level,
            runs: vec![(l.start, l.size.iter().map(|&n| n as usize).product())],
        })
        .collect();
    loop {
        let before = out.len();
        for axis in 0..3 {
            // Bricks by (level, lower corner); a brick's neighbour along
            // `axis` starts where it ends.
            let mut at: std::collections::HashMap<(u8, [i32; 3]), usize> = out
                .iter()
                .enumerate()
                .map(|(i, b)| ((b.level, b.lower), i))
                .collect();
            let mut alive = vec![true; out.len()];
            for i in 0..out.len() {
                if !alive[i] {
                    continue;
                }
                loop {
                    let b = &out[i];
                    let mut next = b.lower;
                    next[axis] += b.size[axis] << b.level;
                    let Some(&j) = at.get(&(b.level, next)) else {
                        break;
                    };
                    let n = &out[j];
                    let same_section = (0..3).all(|a| a == axis || n.size[a] == b.size[a]);
                    if !alive[j] || !same_section || b.size[axis] + n.size[axis] > BRICK_MAX {
                        break;
                    }
                    let (grow, runs) = (n.size[axis], std::mem::take(&mut out[j].runs));
                    at.remove(&(out[j].level, out[j].lower));
                    alive[j] = false;
                    out[i].size[axis] += grow;
                    out[i].runs.extend(runs);
                }
            }
            let mut k = 0;
            out.retain(|_| {
                k += 1;
                alive[k - 1]
            });
        }
        if out.len() == before {
            return out;
        }
    }
}

/// Subtrees smaller than this run on one thread.
const GRAIN: usize = 8192;

fn split(cells: &mut [CellRef], start: usize) -> Vec<Leaf> {
    let mut lo = [i32::MAX; 3];
    let mut hi = [i32::MIN; 3];
    let (mut min_level, mut max_level) = (u8::MAX, 0u8);
    for c in cells.iter() {
        let w = 1 << c.level;
        for a in 0..3 {
            lo[a] = lo[a].min(c.pos[a]);
            hi[a] = hi[a].max(c.pos[a] + w);
        }
        min_level = min_level.min(c.level);
        max_level = max_level.max(c.level);
    }
    let extent = [0, 1, 2].map(|a| (hi[a] - lo[a]) as i64);
    let w = 1i64 << max_level;
    let filled = min_level == max_level
        && cells.len() as i64 * w * w * w == extent[0] * extent[1] * extent[2];
    let small = extent.iter().all(|&e| e <= BRICK_MAX as i64 * w);
    if filled && small {
        return vec![Leaf {
            lower: lo,
            size: extent.map(|e| (e / w) as i32),
            level: max_level,
            start,
        }];
    }
    // Longest axis; split near its middle at a multiple of the coarsest width
    // (so no cell straddles the plane), strictly inside the node.
    let axis = (0..3).max_by_key(|&a| extent[a]).unwrap_or(0);
    let (a_lo, a_hi) = (lo[axis] as i64, hi[axis] as i64);
    let mid = (a_lo + a_hi).div_euclid(2);
    let mut plane = (mid + w / 2).div_euclid(w) * w;
    if plane <= a_lo {
        plane = (a_lo.div_euclid(w) + 1) * w;
    }
    if plane >= a_hi {
        plane = (a_hi - 1).div_euclid(w) * w;
    }
    let plane = plane as i32;
    // In-place partition: cells below the plane first.
    let mut left = 0;
    for i in 0..cells.len() {
        if cells[i].pos[axis] < plane {
            cells.swap(i, left);
            left += 1;
        }
    }
    if left == 0 || left == cells.len() {
        // Cannot happen for validated cells (see the module docs); rather
        // than recurse forever, give every cell its own brick.
        return cells
            .iter()
            .enumerate()
            .map(|(k, c)| Leaf {
                lower: c.pos,
                size: [1, 1, 1],
                level: c.level,
                start: start + k,
            })
            .collect();
    }
    let (l, r) = cells.split_at_mut(left);
    let (mut a, b) = if l.len() + r.len() > GRAIN {
        rayon::join(|| split(l, start), || split(r, start + left))
    } else {
        (split(l, start), split(r, start + left))
    };
    a.extend(b);
    a
}
