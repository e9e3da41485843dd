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
//! The cuts themselves are kept as a k-d tree ([`Regions::tree`]): its
//! leaves are the regions, and its children are separated by their parent's
//! plane, so a ray walks it front to back by visiting the near child first
//! (see `crate::walk`).
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
    /// This region's slice of [`Regions::brick_ids`] (sorted brick indices).
    pub bricks: std::ops::Range<u32>,
}

/// One node of the k-d tree the regions were cut by.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KdNode {
    /// Cut at `at` (doubled finest units) across `axis`: the left child
    /// (`< at`) is the next node, the right child (`>= at`) lies `right`
    /// nodes after this one.
    Inner { axis: u8, at: i64, right: u32 },
    /// A region (its index).
    Leaf(u32),
    /// A part of the box no brick's support reaches.
    Hole,
}

/// All regions and, flat, their brick lists (one allocation for millions
/// of regions instead of one each), and the k-d tree that cut them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Regions {
    pub regions: Vec<Region>,
    pub brick_ids: Vec<u32>,
    /// Depth first, left child first: the regions in the order its leaves
    /// come (the order of `regions`). Empty when there are no regions.
    pub tree: Vec<KdNode>,
}

impl Regions {
    /// The bricks active in region `r`.
    #[inline]
    pub fn bricks_of(&self, r: usize) -> &[u32] {
        let range = &self.regions[r].bricks;
        &self.brick_ids[range.start as usize..range.end as usize]
    }
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

type Fragment = ([i64; 3], [i64; 3]);

/// Lists with fewer fragments than this are split on one thread.
const GRAIN: usize = 2048;

/// Partitions the union of brick supports into active brick regions.
pub fn build(bricks: &[Brick]) -> Regions {
    if bricks.is_empty() {
        return Regions::default();
    }
    // Fragment i is brick i's support; nodes pass index lists around, so a
    // split copies 4-byte ids rather than whole boxes.
    let frags: Vec<Fragment> = bricks.iter().map(support).collect();
    let mut lo = [i64::MAX; 3];
    let mut hi = [i64::MIN; 3];
    for f in &frags {
        for a in 0..3 {
            lo[a] = lo[a].min(f.0[a]);
            hi[a] = hi[a].max(f.1[a]);
        }
    }
    let ids: Vec<u32> = (0..frags.len() as u32).collect();
    // Parallel branches return their pieces (and the cuts above them, in
    // tree order); they are joined once here, so millions of regions are
    // not copied up through every parallel level.
    let parts = subdivide(lo, hi, ids, &frags);
    let pieces = || {
        parts.iter().filter_map(|p| match p {
            Part::Piece(r) => Some(r),
            Part::Cut { .. } => None,
        })
    };
    let mut out = Regions {
        regions: Vec::with_capacity(pieces().map(|p| p.regions.len()).sum()),
        brick_ids: Vec::with_capacity(pieces().map(|p| p.brick_ids.len()).sum()),
        tree: Vec::with_capacity(parts.iter().map(Part::nodes).sum()),
    };
    for part in parts {
        match part {
            Part::Cut { axis, at, left } => out.tree.push(KdNode::Inner {
                axis,
                at,
                right: 1 + left as u32,
            }),
            Part::Piece(piece) => {
                let offset = out.brick_ids.len() as u32;
                let first = out.regions.len() as u32;
                out.brick_ids.extend(piece.brick_ids);
                out.regions.extend(piece.regions.into_iter().map(|mut r| {
                    r.bricks = r.bricks.start + offset..r.bricks.end + offset;
                    r
                }));
                // A piece's tree is relative (child offsets), only its
                // leaves' region numbers move.
                out.tree.extend(piece.tree.into_iter().map(|n| match n {
                    KdNode::Leaf(r) => KdNode::Leaf(r + first),
                    n => n,
                }));
            }
        }
    }
    out
}

/// What the parallel top of the subdivision returns, in tree order: the
/// cuts it made itself and the pieces below [`GRAIN`] built sequentially.
enum Part {
    /// A cut whose left subtree is the next `left` tree nodes.
    Cut {
        axis: u8,
        at: i64,
        left: usize,
    },
    Piece(Regions),
}

impl Part {
    /// Tree nodes this part holds.
    fn nodes(&self) -> usize {
        match self {
            Part::Cut { .. } => 1,
            Part::Piece(r) => r.tree.len(),
        }
    }
}

/// The fragment face strictly inside `(lo, hi)` closest to the centre,
/// trying the widest axis first; `None` when no face cuts the box.
fn split_plane(
    lo: &[i64; 3],
    hi: &[i64; 3],
    ids: &[u32],
    frags: &[Fragment],
) -> Option<(usize, i64)> {
    let mut axes = [0usize, 1, 2];
    axes.sort_by_key(|&a| std::cmp::Reverse(hi[a] - lo[a]));
    // Widest axis first; most nodes find a face there and never scan the others.
    for a in axes {
        let centre = lo[a] + hi[a]; // doubled again, stays integral
        let mut best = (i64::MAX, 0i64);
        for &i in ids {
            let f = &frags[i as usize];
            for x in [f.0[a], f.1[a]] {
                if x > lo[a] && x < hi[a] {
                    let key = ((2 * x - centre).abs(), x);
                    if key < best {
                        best = key;
                    }
                }
            }
        }
        if best.0 != i64::MAX {
            return Some((a, best.1));
        }
    }
    None
}

fn push_leaf(lo: [i64; 3], hi: [i64; 3], ids: &[u32], out: &mut Regions) {
    out.tree.push(KdNode::Leaf(out.regions.len() as u32));
    let first = out.brick_ids.len();
    out.brick_ids.extend_from_slice(ids);
    out.brick_ids[first..].sort_unstable();
    out.regions.push(Region {
        lo,
        hi,
        bricks: first as u32..out.brick_ids.len() as u32,
    });
}

/// The top of the recursion: big nodes own their id lists and split in
/// parallel; below [`GRAIN`] the rest runs in [`subdivide_in`] on one stack.
fn subdivide(lo: [i64; 3], hi: [i64; 3], ids: Vec<u32>, frags: &[Fragment]) -> Vec<Part> {
    let mut out = Regions::default();
    if ids.len() <= GRAIN {
        let mut stack = ids;
        let len = stack.len();
        subdivide_in(lo, hi, 0, len, &mut stack, frags, &mut out);
        return vec![Part::Piece(out)];
    }
    let Some((axis, x)) = split_plane(&lo, &hi, &ids, frags) else {
        push_leaf(lo, hi, &ids, &mut out);
        return vec![Part::Piece(out)];
    };
    let (mut left_hi, mut right_lo) = (hi, lo);
    left_hi[axis] = x;
    right_lo[axis] = x;
    let left: Vec<u32> = ids
        .iter()
        .copied()
        .filter(|&i| frags[i as usize].0[axis] < x)
        .collect();
    let right: Vec<u32> = ids
        .iter()
        .copied()
        .filter(|&i| frags[i as usize].1[axis] > x)
        .collect();
    drop(ids);
    let (a, b) = rayon::join(
        || subdivide(lo, left_hi, left, frags),
        || subdivide(right_lo, hi, right, frags),
    );
    let left = a.iter().map(Part::nodes).sum();
    let mut parts = Vec::with_capacity(1 + a.len() + b.len());
    parts.push(Part::Cut {
        axis: axis as u8,
        at: x,
        left,
    });
    parts.extend(a);
    parts.extend(b);
    parts
}

/// Sequential recursion over `stack[start..start + len]`. Children's id lists
/// are pushed on the same stack and popped on return, so the millions of
/// small nodes near the leaves allocate nothing.
fn subdivide_in(
    lo: [i64; 3],
    hi: [i64; 3],
    start: usize,
    len: usize,
    stack: &mut Vec<u32>,
    frags: &[Fragment],
    out: &mut Regions,
) {
    if len == 0 {
        out.tree.push(KdNode::Hole); // no brick reaches here
        return;
    }
    let Some((axis, x)) = split_plane(&lo, &hi, &stack[start..start + len], frags) else {
        push_leaf(lo, hi, &stack[start..start + len], out);
        return;
    };
    let (mut left_hi, mut right_lo) = (hi, lo);
    left_hi[axis] = x;
    right_lo[axis] = x;
    // The cut's node; its right child's offset is known once the left
    // subtree is written.
    let node = out.tree.len();
    out.tree.push(KdNode::Inner {
        axis: axis as u8,
        at: x,
        right: 0,
    });
    let top = stack.len();
    for i in start..start + len {
        let id = stack[i];
        if frags[id as usize].0[axis] < x {
            stack.push(id);
        }
    }
    subdivide_in(lo, left_hi, top, stack.len() - top, stack, frags, out);
    stack.truncate(top);
    let offset = (out.tree.len() - node) as u32;
    if let KdNode::Inner { right, .. } = &mut out.tree[node] {
        *right = offset;
    }
    for i in start..start + len {
        let id = stack[i];
        if frags[id as usize].1[axis] > x {
            stack.push(id);
        }
    }
    subdivide_in(right_lo, hi, top, stack.len() - top, stack, frags, out);
    stack.truncate(top);
}

/// Per region, a group number shared with exactly the regions whose brick
/// lists are the same (numbered in order of first appearance).
pub fn groups(regions: &Regions) -> Vec<u32> {
    let mut seen: std::collections::HashMap<&[u32], u32> = std::collections::HashMap::new();
    (0..regions.regions.len())
        .map(|r| {
            let next = seen.len() as u32;
            *seen.entry(regions.bricks_of(r)).or_insert(next)
        })
        .collect()
}

/// Per region and field, the range of every cell value whose basis function
/// reaches into the region (a bound on every basis-reconstructed sample, which
/// is a convex combination of those values), and the finest cell width there.
pub fn metadata(
    regions: &Regions,
    bricks: &[Brick],
    fields: &[Vec<f32>],
) -> (Vec<Range1>, Vec<i32>) {
    let nf = fields.len();
    // Written in place: one flat allocation rather than a small Vec per
    // region (millions of them on a 10M-cell set).
    let width = nf.max(1); // a zero-field set still needs its finest widths
    let mut ranges = vec![Range1::EMPTY; regions.regions.len() * width];
    let mut finest = vec![i32::MAX; regions.regions.len()];
    ranges
        .par_chunks_mut(width)
        .zip(finest.par_iter_mut())
        .enumerate()
        .for_each(|(ri, (ranges, finest))| {
            let r = &regions.regions[ri];
            for &b in regions.bricks_of(ri) {
                let b = &bricks[b as usize];
                let w = b.width() as i64;
                *finest = (*finest).min(b.width());
                // Doubled units: cell i has centre c = base + (2i + 1)w and its
                // hat reaches (c − 2w, c + 2w); keep cells overlapping (lo, hi):
                // c + 2w > lo ⇔ i > (lo − base − 3w)/2w, c − 2w < hi ⇔ i < (hi − base + w)/2w.
                // 2w is a power of two: floor division is an arithmetic shift.
                let shift = b.level as u32 + 1;
                let span = |a: usize| {
                    let base = 2 * b.lower[a] as i64;
                    let i0 = ((r.lo[a] - base - 3 * w) >> shift) + 1;
                    let i1 = -((-(r.hi[a] - base + w)) >> shift) - 1;
                    (i0.max(0), i1.min(b.size[a] as i64 - 1))
                };
                let (x, y, z) = (span(0), span(1), span(2));
                for k in z.0..=z.1 {
                    for j in y.0..=y.1 {
                        for i in x.0..=x.1 {
                            let idx = b.offset as usize
                                + ((k * b.size[1] as i64 + j) * b.size[0] as i64 + i) as usize;
                            for (f, range) in ranges.iter_mut().enumerate().take(nf) {
                                range.extend(fields[f][idx]);
                            }
                        }
                    }
                }
            }
        });
    if nf == 0 {
        ranges.clear();
    }
    (ranges, finest)
}
