//! What the block-structured HDF5 readers (FLASH, Enzo, Athena++) share:
//! a [`Block`] of cells on the finest lattice, checked against its level
//! and the lattice, and [`leaf_masks`], which finds the cells no finer
//! block covers — refusing blocks that overlap (naming both) and, where
//! the layout says coarse blocks stay beside finer ones, children that do
//! not nest.

use std::collections::HashMap;

use crate::amr::MAX_LEVEL;

/// Whether two cell widths agree (to a relative 1e-5, which single-precision
/// coordinates meet).
pub(super) fn same_width(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-5 * a.abs().max(b.abs())
}

/// `(x - origin) / step` as an integer, when it is within a thousandth of
/// one (and well inside `i64`).
pub(super) fn on_lattice(x: f64, origin: f64, step: f64) -> Option<i64> {
    let v = (x - origin) / step;
    let r = v.round();
    (v.is_finite() && (v - r).abs() <= 1e-3 && r.abs() < 1e15).then_some(r as i64)
}

/// A box of cells on the finest lattice: a FLASH block, an Enzo grid or an
/// Athena++ meshblock.
#[derive(Clone, Debug)]
pub(super) struct Block {
    /// Lower corner in finest-cell units.
    pub(super) lo: [i64; 3],
    /// Cells along x, y, z.
    pub(super) dims: [usize; 3],
    /// ExaBricks level: its cells are `2^level` finest cells wide.
    pub(super) level: u32,
}

impl Block {
    /// A block whose level is at most [`MAX_LEVEL`], whose corner lies on its
    /// own level's cell lattice, and whose cells all have 32-bit corners; the
    /// error completes a sentence about the block.
    pub(super) fn new(lo: [i64; 3], dims: [usize; 3], level: u32) -> Result<Block, String> {
        if level > MAX_LEVEL as u32 {
            return Err(format!(
                "is {level} levels coarser than the finest, more than the {MAX_LEVEL} supported"
            ));
        }
        let w = 1i64 << level;
        for d in 0..3 {
            let n = i64::try_from(dims[d]).unwrap_or(i64::MAX);
            if n == 0 {
                return Err(format!("has no cells along axis {d}"));
            }
            if lo[d].rem_euclid(w) != 0 {
                return Err(format!(
                    "has its corner at {} finest cells along axis {d}, not on its own level's \
                     cell lattice (multiples of {w})",
                    lo[d]
                ));
            }
            let hi = n.checked_mul(w).and_then(|e| lo[d].checked_add(e));
            let fits =
                lo[d] >= i64::from(i32::MIN) && hi.is_some_and(|h| h <= i64::from(i32::MAX) + 1);
            if !fits {
                return Err(format!(
                    "reaches beyond the 32-bit cell coordinates along axis {d} (corner {}, {} \
                     cells {w} wide)",
                    lo[d], dims[d]
                ));
            }
        }
        Ok(Block { lo, dims, level })
    }

    /// Cell width in finest cells.
    fn width(&self) -> i64 {
        1i64 << self.level
    }

    /// Upper corner (exclusive) in finest-cell units.
    fn hi(&self) -> [i64; 3] {
        let w = self.width();
        std::array::from_fn(|d| self.lo[d] + self.dims[d] as i64 * w)
    }

    /// Volume in finest cells.
    fn volume(&self) -> u128 {
        let w = self.width() as u128;
        self.dims.iter().map(|&n| n as u128 * w).product()
    }

    /// The number of cells.
    pub(super) fn cell_count(&self) -> usize {
        self.dims.iter().product()
    }
}

/// The part of `[a_lo, a_hi)` inside `[b_lo, b_hi)`, if they overlap.
fn intersect(
    a_lo: [i64; 3],
    a_hi: [i64; 3],
    b_lo: [i64; 3],
    b_hi: [i64; 3],
) -> Option<([i64; 3], [i64; 3])> {
    let lo: [i64; 3] = std::array::from_fn(|d| a_lo[d].max(b_lo[d]));
    let hi: [i64; 3] = std::array::from_fn(|d| a_hi[d].min(b_hi[d]));
    (0..3).all(|d| lo[d] < hi[d]).then_some((lo, hi))
}

/// Volume of a box in finest cells.
fn box_volume(lo: [i64; 3], hi: [i64; 3]) -> u128 {
    (0..3).map(|d| (hi[d] - lo[d]) as u128).product()
}

/// `[x0, x1) × [y0, y1) × [z0, z1)` for messages.
fn region_text(lo: [i64; 3], hi: [i64; 3]) -> String {
    format!(
        "[{}, {}) × [{}, {}) × [{}, {})",
        lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]
    )
}

/// The blocks of one level, bucketed by their lower corners on a grid as
/// coarse as the largest block, so that a query looks at few buckets.
struct LevelIndex {
    members: Vec<usize>,
    bucket: [i64; 3],
    map: HashMap<[i64; 3], Vec<usize>>,
}

impl LevelIndex {
    fn new(blocks: &[Block], members: Vec<usize>) -> LevelIndex {
        let mut bucket = [1i64; 3];
        for &i in &members {
            let (lo, hi) = (blocks[i].lo, blocks[i].hi());
            for d in 0..3 {
                bucket[d] = bucket[d].max(hi[d] - lo[d]);
            }
        }
        let mut map: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
        for &i in &members {
            let key = std::array::from_fn(|d| blocks[i].lo[d].div_euclid(bucket[d]));
            map.entry(key).or_default().push(i);
        }
        LevelIndex {
            members,
            bucket,
            map,
        }
    }

    /// The blocks of this level that overlap `[lo, hi)`, in increasing
    /// order, into `out`.
    fn query(&self, blocks: &[Block], lo: [i64; 3], hi: [i64; 3], out: &mut Vec<usize>) {
        out.clear();
        let hits = |i: usize| intersect(blocks[i].lo, blocks[i].hi(), lo, hi).is_some();
        // A block's extent is at most a bucket, so one overlapping [lo, hi)
        // has its corner in (lo - bucket, hi).
        let k0: [i64; 3] =
            std::array::from_fn(|d| (lo[d] - self.bucket[d] + 1).div_euclid(self.bucket[d]));
        let k1: [i64; 3] = std::array::from_fn(|d| (hi[d] - 1).div_euclid(self.bucket[d]));
        let buckets: u128 = (0..3).map(|d| (k1[d] - k0[d] + 1).max(0) as u128).product();
        if buckets > self.map.len() as u128 {
            out.extend(self.members.iter().copied().filter(|&i| hits(i)));
        } else {
            for kz in k0[2]..=k1[2] {
                for ky in k0[1]..=k1[1] {
                    for kx in k0[0]..=k1[0] {
                        if let Some(list) = self.map.get(&[kx, ky, kz]) {
                            out.extend(list.iter().copied().filter(|&i| hits(i)));
                        }
                    }
                }
            }
            out.sort_unstable();
        }
    }
}

/// How the blocks of a file relate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Layout {
    /// Only leaves (FLASH leaf blocks, Athena++ meshblocks): no two blocks
    /// may overlap.
    LeafOnly,
    /// Properly nested grids of every level (Enzo): grids of one level are
    /// disjoint, each grid lies inside the grids one level coarser, and a
    /// cell covered by grids one level finer is dropped.
    Nested,
}

/// For each block, which of its cells (in z, y, x order, x fastest) are
/// leaves: `None` when all are. The error message names the blocks with
/// `name` and says what is wrong; the caller adds the file.
pub(super) fn leaf_masks(
    blocks: &[Block],
    layout: Layout,
    name: &dyn Fn(usize) -> String,
) -> Result<Vec<Option<Vec<bool>>>, String> {
    let mut levels: Vec<u32> = blocks.iter().map(|b| b.level).collect();
    levels.sort_unstable();
    levels.dedup();
    let slot_of = |level: u32| levels.partition_point(|&l| l < level);
    let mut members = vec![Vec::new(); levels.len()];
    for (i, b) in blocks.iter().enumerate() {
        members[slot_of(b.level)].push(i);
    }
    let index: Vec<LevelIndex> = members
        .into_iter()
        .map(|m| LevelIndex::new(blocks, m))
        .collect();
    let mut masks = vec![None; blocks.len()];
    let mut found = Vec::new();
    let overlap = |i: usize, j: usize| {
        let (a, b) = (i.min(j), i.max(j));
        let (lo, hi) = intersect(blocks[a].lo, blocks[a].hi(), blocks[b].lo, blocks[b].hi())
            .unwrap_or((blocks[a].lo, blocks[a].lo));
        format!(
            "{} and {} overlap: both cover the finest-cell region {}",
            name(a),
            name(b),
            region_text(lo, hi)
        )
    };

    for (i, b) in blocks.iter().enumerate() {
        let slot = slot_of(b.level);
        // Same level, and for leaves every finer one too.
        let first = if layout == Layout::LeafOnly { 0 } else { slot };
        for idx in &index[first..=slot] {
            idx.query(blocks, b.lo, b.hi(), &mut found);
            if let Some(&j) = found.iter().find(|&&j| j != i) {
                return Err(overlap(i, j));
            }
        }
    }
    if layout == Layout::LeafOnly {
        return Ok(masks);
    }

    for (i, b) in blocks.iter().enumerate() {
        let slot = slot_of(b.level);
        let (lo, hi) = (b.lo, b.hi());
        // Proper nesting: inside the grids one level coarser.
        if let Some(coarser) = index.get(slot + 1) {
            coarser.query(blocks, lo, hi, &mut found);
            let inside: u128 = found
                .iter()
                .filter_map(|&j| intersect(lo, hi, blocks[j].lo, blocks[j].hi()))
                .map(|(l, h)| box_volume(l, h))
                .sum();
            if inside != b.volume() {
                return Err(format!(
                    "{} is not properly nested: part of it lies outside the grids one level \
                     coarser",
                    name(i)
                ));
            }
        }
        // The cells that grids one level finer cover.
        let Some(finer) = slot.checked_sub(1).map(|s| &index[s]) else {
            continue;
        };
        finer.query(blocks, lo, hi, &mut found);
        if found.is_empty() {
            continue;
        }
        let w = b.width();
        let [nx, ny, _] = b.dims;
        let mut covered = vec![0u128; b.cell_count()];
        for &j in &found {
            let Some((ilo, ihi)) = intersect(lo, hi, blocks[j].lo, blocks[j].hi()) else {
                continue;
            };
            let c0: [usize; 3] = std::array::from_fn(|d| ((ilo[d] - lo[d]) / w) as usize);
            let c1: [usize; 3] = std::array::from_fn(|d| ((ihi[d] - 1 - lo[d]) / w) as usize);
            let span = |d: usize, c: usize| {
                let a = lo[d] + c as i64 * w;
                ((a + w).min(ihi[d]) - a.max(ilo[d])) as u128
            };
            for cz in c0[2]..=c1[2] {
                let vz = span(2, cz);
                for cy in c0[1]..=c1[1] {
                    let vy = vz * span(1, cy);
                    for cx in c0[0]..=c1[0] {
                        covered[(cz * ny + cy) * nx + cx] += vy * span(0, cx);
                    }
                }
            }
        }
        let full = (w as u128).pow(3);
        if let Some(k) = covered.iter().position(|&c| c != 0 && c != full) {
            let (cx, cy, cz) = (k % nx, (k / nx) % ny, k / (nx * ny));
            let at = [cx, cy, cz];
            let corner: [i64; 3] = std::array::from_fn(|d| lo[d] + at[d] as i64 * w);
            return Err(format!(
                "{}: its cell at finest-cell corner ({}, {}, {}) is only partly covered by the \
                 grids one level finer",
                name(i),
                corner[0],
                corner[1],
                corner[2]
            ));
        }
        masks[i] = Some(covered.iter().map(|&c| c == 0).collect());
    }
    Ok(masks)
}

/// Appends the cells of `block` that `mask` keeps (all without one), in z,
/// y, x order, x fastest.
pub(super) fn push_cells(out: &mut Vec<[i32; 4]>, block: &Block, mask: Option<&[bool]>) {
    let w = block.width();
    let [nx, ny, nz] = block.dims;
    let mut k = 0;
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                if mask.is_none_or(|m| m[k]) {
                    // Block::new checked that every corner fits in i32.
                    out.push([
                        (block.lo[0] + x as i64 * w) as i32,
                        (block.lo[1] + y as i64 * w) as i32,
                        (block.lo[2] + z as i64 * w) as i32,
                        block.level as i32,
                    ]);
                }
                k += 1;
            }
        }
    }
}

/// Appends the values (one per cell, z, y, x order) that `mask` keeps.
pub(super) fn push_values(out: &mut Vec<f32>, values: &[f32], mask: Option<&[bool]>) {
    match mask {
        None => out.extend_from_slice(values),
        Some(m) => out.extend(values.iter().zip(m).filter(|(_, k)| **k).map(|(v, _)| *v)),
    }
}
