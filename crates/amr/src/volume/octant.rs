//! The octant reconstruction (Wang, Wald, Wu, Usher and Johnson, "CPU
//! isosurface ray tracing of adaptive mesh refinement data", IEEE TVCG
//! 2019; the AMR method Open VKL calls `octant`): trilinear interpolation
//! on the dual grid, in boxes fitted to the levels.
//!
//! **The box.** A point `p` lies in one leaf cell `C` (centre `c`, width
//! `w`) and in one of its eight octants: the box from `c` to the corner
//! `c + s·w/2` of `C` on `p`'s side (`s` the signs of `p − c`, `+` on a
//! tie). The field there is the trilinear interpolation of the box's eight
//! vertex values; the vertex `k` (bits x, y, z) sits at `c + s·k·w/2`: the
//! centre, three face centres, three edge midpoints and the corner of `C`.
//!
//! **Vertex values.** Around a vertex lie the width-`w` blocks of space it
//! touches: one for the centre (`C`), two for a face centre, four for an
//! edge midpoint, eight for a corner — block `m ⊆ k` is centred at
//! `c + s·m·w`. Each block holds a leaf of width ≥ `w`, or finer cells, or
//! nothing (a hole or outside the data). Then:
//! - some block holds a *coarser* leaf: the vertex takes the value of the
//!   coarsest one's own octant field at the vertex (the finer side defers,
//!   as in Open VKL; the recursion ends at the coarsest level);
//! - otherwise: the mean of the width-`w` leaves among the blocks (`C` is
//!   one). With every block such a leaf this is the dual-grid trilinear
//!   value (½, ¼, ⅛ of the cells around); finer cells and holes drop out,
//!   so a coarse cell next to finer ones, and the data's edge, repeat the
//!   values on their own side.
//!
//! Open VKL fills a coarse cell's vertex next to finer cells from the
//! width-`w` dual cell whose lower corner lies at or below the vertex,
//! unweighted, so at a face centre or edge midpoint it also averages the
//! leaves one row further along the other axes (whose tents are zero
//! there); we weight by the tents, which keeps the blocks touching the
//! vertex only. Both are C⁰.
//!
//! **Continuity.** A vertex's value depends on the vertex and `w` alone,
//! so same-level neighbours agree on their shared faces. A finer cell's
//! vertices on a coarser neighbour's face take the coarse field's values
//! there; the coarse field is bilinear on each quarter of that face and
//! the fine box's face lies inside one quarter (boxes are aligned to half
//! their cell width), so bilinear interpolation of those values is the
//! coarse field itself: no cracks, for any level jump, holes included.
//! It is C⁰, not C¹: next to finer cells a coarse cell repeats its own
//! side's values, so the field bends at level boundaries (a shaded
//! iso-surface shows a crease there). The gradient is the trilinear
//! form's (piecewise, discontinuous across box faces).
//!
//! **Reach.** The field is linear in the cell values, and a cell `X` of
//! width `W` weighs nothing outside the open box `X ± W/2` — its tent's
//! support — so the regions' value ranges (the values whose tents reach
//! in) bound octant samples as they bound basis samples. By induction from
//! the coarsest level: `X` enters the box of a cell of width `w ≤ W` (never
//! a coarser one's) only through vertices that touch it, which lie inside
//! `X ± W/2`, or through a coarser cell's field at a vertex, which weighs
//! `X` only inside it; the box is a cube of side `w/2` on the lattice of
//! `w/2`, which holds the faces of `X ± W/2` too, so a box not inside it
//! has no vertex inside it and weighs `X` nowhere. The same argument
//! holds for a cell whose mere presence changes a vertex (by being
//! coarser): where that vertex weighs anything, the cell's tent reaches.
//! So a part of a decomposition holding every cell whose tent reaches its
//! box reconstructs there as the whole does.
//!
//! Cells are found by position (finest units, exact): the sample's cell
//! among the bricks of its region (then through a BVH over every brick), a
//! box's blocks by index inside its cell's brick, else among the bricks
//! beside that brick (a list per brick, built with the volume).

mod line;

use voxless_bvh::Bvh;
use voxless_core::{Aabb, Vec3};

use crate::bricks::Brick;

use super::AmrVolume;
use super::recon::Recon;

/// Where octant reconstruction finds cells by position: every brick's box
/// in finest units, and their union's box.
pub(super) struct OctantIndex {
    bvh: Bvh,
    /// Per brick, its box (half-open): a quick test before the cell index.
    boxes: Vec<[[f64; 3]; 2]>,
    /// Per brick, the other bricks meeting its box grown by half its cell
    /// width (`neighbours[starts[b]..starts[b + 1]]`): every brick a block
    /// centre of one of its cells' boxes can lie in.
    neighbours: Vec<u32>,
    starts: Vec<u32>,
    lo: [f64; 3],
    hi: [f64; 3],
}

impl OctantIndex {
    pub fn new(bricks: &[Brick]) -> OctantIndex {
        let boxes: Vec<Aabb> = bricks
            .iter()
            .map(|b| {
                let (lo, hi) = (b.lower, b.upper());
                Aabb::new(
                    Vec3::new(lo[0] as f32, lo[1] as f32, lo[2] as f32),
                    Vec3::new(hi[0] as f32, hi[1] as f32, hi[2] as f32),
                )
            })
            .collect();
        let union = boxes.iter().fold(Aabb::EMPTY, |u, &b| u.union(b));
        let bvh = Bvh::build(&boxes);
        let (mut neighbours, mut starts) = (Vec::new(), vec![0u32]);
        for (i, (b, r)) in bricks.iter().zip(&boxes).enumerate() {
            // Block centres lie within half a cell of the brick.
            let grow = Vec3::splat(0.5 * b.width() as f32);
            bvh.box_query(&Aabb::new(r.min - grow, r.max + grow), |n, _| {
                if n as usize != i {
                    neighbours.push(n);
                }
            });
            starts.push(neighbours.len() as u32);
        }
        OctantIndex {
            bvh,
            neighbours,
            starts,
            boxes: bricks
                .iter()
                .map(|b| [b.lower.map(|v| v as f64), b.upper().map(|v| v as f64)])
                .collect(),
            lo: [0, 1, 2].map(|a| union.min[a] as f64),
            hi: [0, 1, 2].map(|a| union.max[a] as f64),
        }
    }
}

/// A leaf cell: lower corner and width (finest units), its brick and its
/// index there, and where its values are.
#[derive(Clone, Copy, Debug)]
struct Leaf {
    lower: [f64; 3],
    width: f64,
    brick: u32,
    cell: [i32; 3],
    index: usize,
}

/// The value arrays reconstructed: the opacity field and, when it is
/// another field, the colour field.
#[derive(Clone, Copy)]
struct Fields<'a> {
    value: &'a [f32],
    color: Option<&'a [f32]>,
}

impl Fields<'_> {
    #[inline]
    fn at(&self, i: usize) -> [f64; 2] {
        let v = self.value[i] as f64;
        [v, self.color.map_or(v, |c| c[i] as f64)]
    }
}

/// One octant box: its cell's centre, the octant's signs, half the cell
/// width, and the vertex values (value and colour; vertex `k` at
/// `centre + sign·k·half`, bit 0 = x).
#[derive(Clone, Copy, Debug)]
struct OctBox {
    centre: [f64; 3],
    sign: [f64; 3],
    half: f64,
    v: [[f64; 2]; 8],
}

impl OctBox {
    /// The trilinear form at `p` (finest units): value and colour, and
    /// the value's derivatives by the unit coordinates when `gradient`.
    /// Lerps `(1 − t)·a + t·b` in `f64`: a vertex of weight zero adds an
    /// exact zero whatever its value (so cells that only such vertices
    /// read cannot change the bits), and equal vertex values round back to
    /// that value in `f32`.
    fn lerp(&self, p: [f64; 3], gradient: bool) -> ([f64; 2], [f64; 3]) {
        let t =
            [0, 1, 2].map(|a| ((p[a] - self.centre[a]) * self.sign[a] / self.half).clamp(0.0, 1.0));
        let l = |a: f64, b: f64, t: f64| (1.0 - t) * a + t * b;
        let mut out = [0.0; 2];
        let mut d = [0.0; 3];
        for (j, out) in out.iter_mut().enumerate() {
            let v = |k: usize| self.v[k][j];
            let x = [
                l(v(0), v(1), t[0]),
                l(v(2), v(3), t[0]),
                l(v(4), v(5), t[0]),
                l(v(6), v(7), t[0]),
            ];
            let (y0, y1) = (l(x[0], x[1], t[1]), l(x[2], x[3], t[1]));
            *out = l(y0, y1, t[2]);
            if gradient && j == 0 {
                let dx = |k: usize| v(k + 1) - v(k);
                let dt = [
                    l(l(dx(0), dx(2), t[1]), l(dx(4), dx(6), t[1]), t[2]),
                    l(x[1] - x[0], x[3] - x[2], t[2]),
                    y1 - y0,
                ];
                d = [0, 1, 2].map(|a| dt[a] * self.sign[a] / self.half);
            }
        }
        (out, d)
    }
}

/// Per vertex `k`, the blocks touching it as a bit set: every `m ⊆ k`.
const TOUCHING: [u8; 8] = {
    let mut t = [0u8; 8];
    let mut k = 0;
    while k < 8 {
        let mut m = 0;
        while m < 8 {
            if m & !k == 0 {
                t[k] |= 1 << m;
            }
            m += 1;
        }
        k += 1;
    }
    t
};

/// Deferred vertices' boxes already built in one box: (leaf index, octant
/// signs) → box.
type BoxCache = Vec<(usize, [f64; 3], OctBox)>;

impl AmrVolume {
    /// Octant values of `field` and `color_field` at unit-space point `pu`
    /// (and the value's gradient, world units, when `gradient`); `hint`:
    /// bricks to look in first (the sample's region's). `None` outside the
    /// cells.
    pub(super) fn octant(
        &self,
        pu: Vec3,
        hint: &[u32],
        field: usize,
        color_field: usize,
        gradient: bool,
    ) -> Option<Recon> {
        // Into the data's box: rounding from world to finest units can put
        // a point of the bounds (an interval's end) just outside.
        let ix = self.bx().octant.as_ref()?;
        let p = [pu.x, pu.y, pu.z].map(|v| v as f64);
        let p = [0, 1, 2].map(|a| p[a].clamp(ix.lo[a], ix.hi[a]));
        let cell = self.leaf_at(p, hint).or_else(|| self.leaf_touching(p))?;
        let fields = Fields {
            value: &self.bx().values[field],
            color: (color_field != field).then(|| self.bx().values[color_field].as_slice()),
        };
        let b = self.octant_box(&cell, p, fields);
        let ([value, color], d) = b.lerp(p, gradient);
        let inv_h = 1.0 / self.h as f64;
        Some(Recon {
            value: value as f32,
            color: color as f32,
            gradient: Vec3::new(
                (d[0] * inv_h) as f32,
                (d[1] * inv_h) as f32,
                (d[2] * inv_h) as f32,
            ),
        })
    }

    /// The box of `cell` on `p`'s side of its centre, its vertex values
    /// filled by the rules of the module docs.
    fn octant_box(&self, cell: &Leaf, p: [f64; 3], fields: Fields) -> OctBox {
        let w = cell.width;
        let half = 0.5 * w;
        let centre = cell.lower.map(|l| l + half);
        let sign = [0, 1, 2].map(|a| if p[a] < centre[a] { -1.0 } else { 1.0 });
        // The blocks of width w around the box's far corner: block m is the
        // cell itself moved by m·s·w. As bit sets: the blocks holding a
        // leaf of width w (their values read) and those holding a coarser
        // one; the rest hold finer cells or none.
        let (mut same, mut coarser) = (1u8, 0u8);
        let mut values = [[0.0; 2]; 8];
        let mut leaves = [None; 8];
        values[0] = fields.at(cell.index);
        let brick = &self.bx().bricks[cell.brick as usize];
        let step = sign.map(|s| s as i32);
        for m in 1..8 {
            // Inside the cell's brick, by index: a leaf of width w.
            let idx = [0, 1, 2].map(|a| cell.cell[a] + ((m >> a) & 1) as i32 * step[a]);
            if (0..3).all(|a| idx[a] >= 0 && idx[a] < brick.size[a]) {
                same |= 1 << m;
                values[m] = fields.at(cell_index(brick, idx));
                continue;
            }
            match self.block(cell, m, sign) {
                Some(b) if b.width > w => {
                    coarser |= 1 << m;
                    leaves[m] = Some(b);
                }
                Some(b) => {
                    same |= 1 << m;
                    values[m] = fields.at(b.index);
                }
                None => {}
            }
        }
        let mut v = [[0.0; 2]; 8];
        let mut cache = BoxCache::new();
        for (k, vk) in v.iter_mut().enumerate() {
            let touching = TOUCHING[k];
            *vk = if touching & coarser == 0 {
                // The mean of the width-w leaves, in block order.
                let (mut sum, mut n) = ([0.0f64; 2], 0.0f64);
                let mut bits = touching & same;
                while bits != 0 {
                    let x = values[bits.trailing_zeros() as usize];
                    sum = [sum[0] + x[0], sum[1] + x[1]];
                    n += 1.0;
                    bits &= bits - 1;
                }
                [sum[0] / n, sum[1] / n]
            } else {
                // The finer side defers to the coarsest field there (the
                // first of the widest, in block order).
                let mut g: Option<Leaf> = None;
                let mut bits = touching & coarser;
                while bits != 0 {
                    let b = leaves[bits.trailing_zeros() as usize];
                    if let Some(b) = b.filter(|b| g.is_none_or(|g| b.width > g.width)) {
                        g = Some(b);
                    }
                    bits &= bits - 1;
                }
                let g = g.expect("a coarser block has its leaf");
                let q = [0, 1, 2].map(|a| centre[a] + sign[a] * half * ((k >> a) & 1) as f64);
                self.field_of(&g, q, fields, &mut cache)
            };
        }
        OctBox {
            centre,
            sign,
            half,
            v,
        }
    }

    /// Leaf `g`'s own octant field at `q` (a point of its closed box),
    /// reusing a box already built for an earlier vertex.
    fn field_of(&self, g: &Leaf, q: [f64; 3], fields: Fields, cache: &mut BoxCache) -> [f64; 2] {
        let half = 0.5 * g.width;
        let sign = [0, 1, 2].map(|a| if q[a] < g.lower[a] + half { -1.0 } else { 1.0 });
        let b = match cache.iter().find(|c| c.0 == g.index && c.1 == sign) {
            Some(c) => c.2,
            None => {
                let b = self.octant_box(g, q, fields);
                cache.push((g.index, sign, b));
                b
            }
        };
        b.lerp(q, false).0
    }

    /// Block `m` (bits x, y, z) of `cell`'s box with signs `sign`, outside
    /// the cell's brick: the leaf of width ≥ the cell's holding the cell's
    /// box moved by `m·sign·width`, if any.
    fn block(&self, cell: &Leaf, m: usize, sign: [f64; 3]) -> Option<Leaf> {
        let step = [0, 1, 2].map(|a| ((m >> a) & 1) as f64 * sign[a]);
        // Among the bricks beside the cell's (or nowhere).
        let y = [0, 1, 2].map(|a| cell.lower[a] + (step[a] + 0.5) * cell.width);
        let ix = self.bx().octant.as_ref()?;
        let (from, to) = (
            ix.starts[cell.brick as usize],
            ix.starts[cell.brick as usize + 1],
        );
        ix.neighbours[from as usize..to as usize]
            .iter()
            .find_map(|&b| self.leaf_in(b, y))
            .filter(|l| l.width >= cell.width)
    }

    /// The leaf whose half-open box holds `y` (finest units): first among
    /// the bricks `hint`, then any.
    fn leaf_at(&self, y: [f64; 3], hint: &[u32]) -> Option<Leaf> {
        let ix = self.bx().octant.as_ref()?;
        if (0..3).any(|a| !(y[a] >= ix.lo[a] && y[a] < ix.hi[a])) {
            return None;
        }
        if let Some(l) = hint.iter().find_map(|&b| self.leaf_in(b, y)) {
            return Some(l);
        }
        let mut found = None;
        let at = Vec3::new(y[0] as f32, y[1] as f32, y[2] as f32);
        ix.bvh.point_query(at, |b| {
            if found.is_none() {
                found = self.leaf_in(b, y);
            }
        });
        found
    }

    /// A leaf whose closed box holds `y` (the data's upper faces, which no
    /// half-open box holds): the one of the lowest brick number.
    fn leaf_touching(&self, y: [f64; 3]) -> Option<Leaf> {
        let ix = self.bx().octant.as_ref()?;
        let mut found: Option<u32> = None;
        let at = Vec3::new(y[0] as f32, y[1] as f32, y[2] as f32);
        ix.bvh.point_query(at, |b| {
            let brick = &self.bx().bricks[b as usize];
            let (lo, hi) = (brick.lower, brick.upper());
            let inside = (0..3).all(|a| y[a] >= lo[a] as f64 && y[a] <= hi[a] as f64);
            if inside && found.is_none_or(|f| b < f) {
                found = Some(b);
            }
        });
        let b = found?;
        let brick = &self.bx().bricks[b as usize];
        let w = brick.width() as f64;
        let cell = [0, 1, 2].map(|a| {
            (((y[a] - brick.lower[a] as f64) / w).floor() as i32).clamp(0, brick.size[a] - 1)
        });
        Some(leaf(brick, b, cell))
    }

    /// The leaf of brick `b` whose half-open box holds `y`, if any.
    #[inline]
    fn leaf_in(&self, b: u32, y: [f64; 3]) -> Option<Leaf> {
        let [lo, hi] = self.bx().octant.as_ref()?.boxes[b as usize];
        if !(0..3).all(|a| y[a] >= lo[a] && y[a] < hi[a]) {
            return None;
        }
        let brick = &self.bx().bricks[b as usize];
        // Widths are powers of two: multiplying by the inverse is exact.
        let inv_w = self.bx().grids[b as usize].inv_w as f64;
        let mut cell = [0i32; 3];
        for a in 0..3 {
            // Inside the box: `x ≥ 0`, truncation is the floor (and the
            // last cell holds the points below the upper face).
            let x = (y[a] - brick.lower[a] as f64) * inv_w;
            cell[a] = (x as i32).min(brick.size[a] - 1);
        }
        Some(leaf(brick, b, cell))
    }
}

/// Cell `cell` of brick `brick` (number `b`).
#[inline]
fn leaf(brick: &Brick, b: u32, cell: [i32; 3]) -> Leaf {
    let w = brick.width();
    Leaf {
        lower: [0, 1, 2].map(|a| (brick.lower[a] + cell[a] * w) as f64),
        width: w as f64,
        brick: b,
        cell,
        index: cell_index(brick, cell),
    }
}

/// Index into the brick-ordered values of cell `cell` of `brick`.
#[inline]
fn cell_index(brick: &Brick, cell: [i32; 3]) -> usize {
    brick.offset as usize + ((cell[2] * brick.size[1] + cell[1]) * brick.size[0] + cell[0]) as usize
}
