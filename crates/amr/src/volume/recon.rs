//! Basis and nearest reconstruction from one region's bricks (octant
//! reconstruction is dispatched from here to [`super::octant`]).

use voxless_core::{Attribute, Sample, Vec3};

use crate::bricks::Brick;

use super::{AmrVolume, Reconstruction};

/// `⌊x⌋` for |x| < 2³¹ without a libm call (`f32::floor` is one on
/// baseline x86-64, and the reconstruction takes three per brick).
#[inline]
fn floor_i32(x: f32) -> i32 {
    let i = x as i32;
    i - (x < i as f32) as i32
}

/// Reconstructed values at a point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Recon {
    pub value: f32,
    pub color: f32,
    pub gradient: Vec3,
}

impl AmrVolume {
    /// Basis (or nearest) values of `field` and the colour field at `p`
    /// (world) using only region `region`'s bricks: what rendering samples.
    #[inline]
    pub(super) fn reconstruct(
        &self,
        p: Vec3,
        region: usize,
        field: usize,
        gradient: bool,
    ) -> Option<Recon> {
        let pu = self.to_units(p);
        let color_field = self.settings.color_field.unwrap_or(field);
        match self.settings.reconstruction {
            Reconstruction::Nearest => return self.nearest(pu, region, field, color_field),
            Reconstruction::Octant => {
                let hint = self.ix().regions.bricks_of(region);
                return self.octant(pu, hint, field, color_field, gradient);
            }
            Reconstruction::Basis => {}
        }
        let fields = self.basis_fields(field);
        let bricks = self.ix().regions.bricks_of(region).iter();
        let grids = bricks.map(|&b| &self.bx().grids[b as usize]);
        if !gradient {
            let mut sums = ValueSums::default();
            grids.for_each(|grid| brick_value_sums(grid, pu, fields, &mut sums));
            return self.finish_values(sums, fields.1.is_some());
        }
        let mut sums = BasisSums::default();
        grids.for_each(|grid| brick_sums(grid, pu, fields, &mut sums));
        self.finish(&sums, gradient, fields.1.is_some())
    }

    /// The value array of `field` and, when the colour comes from another
    /// field, that one's.
    #[inline]
    pub(super) fn basis_fields(&self, field: usize) -> (&[f32], Option<&[f32]>) {
        let color_field = self.settings.color_field.unwrap_or(field);
        // Without a separate colour field its sum is the value's: skip it.
        let color = (color_field != field).then(|| self.bx().values[color_field].as_slice());
        (&self.bx().values[field], color)
    }

    /// `B = Σ Ĥ v / Σ Ĥ` (and the colour's, and the gradient by the
    /// quotient rule) from the sums; `None` where no tent reaches.
    #[inline]
    pub(super) fn finish(&self, s: &BasisSums, gradient: bool, two_fields: bool) -> Option<Recon> {
        if s.sw <= 0.0 {
            return None;
        }
        let value = s.sv / s.sw;
        let mut g = Vec3::ZERO;
        if gradient {
            // Quotient rule; divide by h to go from unit to world coordinates.
            let q = |a: usize| {
                ((s.sw * s.sdv[a] - s.sv * s.sdw[a]) / (s.sw * s.sw) / self.h as f64) as f32
            };
            g = Vec3::new(q(0), q(1), q(2));
        }
        Some(Recon {
            value: value as f32,
            color: if two_fields {
                (s.sc / s.sw) as f32
            } else {
                value as f32
            },
            gradient: g,
        })
    }

    /// `B = Σ Ĥ v / Σ Ĥ` (and the colour's) from value-only sums; `None`
    /// where no tent reaches.
    #[inline]
    pub(super) fn finish_values(&self, s: ValueSums, two_fields: bool) -> Option<Recon> {
        if s.sw <= 0.0 {
            return None;
        }
        let value = (s.sv / s.sw) as f32;
        Some(Recon {
            value,
            color: if two_fields {
                (s.sc / s.sw) as f32
            } else {
                value
            },
            gradient: Vec3::ZERO,
        })
    }

    /// [`AmrVolume::reconstruct`] with the cells' terms added one by one in
    /// an order fixed by the terms themselves rather than by the bricks, so
    /// any set of cells holding every cell whose basis reaches `p` gives
    /// the same bits (a part of a decomposed volume, for `fields_at`).
    pub(super) fn reconstruct_exact(
        &self,
        p: Vec3,
        region: usize,
        field: usize,
        gradient: bool,
    ) -> Option<Recon> {
        let pu = self.to_units(p);
        let color_field = self.settings.color_field.unwrap_or(field);
        match self.settings.reconstruction {
            Reconstruction::Nearest => return self.nearest(pu, region, field, color_field),
            // Cells found by position, terms in a fixed order: the same
            // bits whatever the bricks.
            Reconstruction::Octant => {
                let hint = self.ix().regions.bricks_of(region);
                return self.octant(pu, hint, field, color_field, gradient);
            }
            Reconstruction::Basis => {}
        }
        let (v0, v1) = (&self.bx().values[field], &self.bx().values[color_field]);
        let two_fields = color_field != field;
        let mut terms = SortedTerms::default();
        for &b in self.ix().regions.bricks_of(region) {
            let grid = &self.bx().grids[b as usize];
            let Some(st) = Stencil::new(grid, pu, gradient) else {
                continue;
            };
            for kz in 0..2 {
                for ky in 0..2 {
                    for kx in 0..2 {
                        let (wt, dwt) = (&st.w, &st.dw);
                        let h = wt[0][kx] * wt[1][ky] * wt[2][kz];
                        // Cells outside the brick (clamped indices) have
                        // zero weight and derivative: no term.
                        if !st.inside[0][kx] || !st.inside[1][ky] || !st.inside[2][kz] {
                            continue;
                        }
                        if h <= 0.0 && !gradient {
                            continue;
                        }
                        let cell = st.cell(grid, kx, ky, kz);
                        let d = if gradient {
                            [
                                dwt[0][kx] * wt[1][ky] * wt[2][kz],
                                wt[0][kx] * dwt[1][ky] * wt[2][kz],
                                wt[0][kx] * wt[1][ky] * dwt[2][kz],
                            ]
                        } else {
                            [0.0; 3]
                        };
                        let c = if two_fields { v1[cell] } else { 0.0 };
                        terms.0.push([h, v0[cell], c, d[0], d[1], d[2]]);
                    }
                }
            }
        }
        self.finish(&terms.sums(gradient), gradient, two_fields)
    }

    pub(super) fn nearest(
        &self,
        pu: Vec3,
        region: usize,
        field: usize,
        color_field: usize,
    ) -> Option<Recon> {
        for &b in self.ix().regions.bricks_of(region) {
            if let Some(cell) = self.cell_in_brick(pu, b as usize) {
                return Some(Recon {
                    value: self.bx().values[field][cell],
                    color: self.bx().values[color_field][cell],
                    gradient: Vec3::ZERO,
                });
            }
        }
        None
    }

    /// Index (into the brick-ordered values) of the cell of brick `b`
    /// containing unit-space point `pu`.
    pub(super) fn cell_in_brick(&self, pu: Vec3, b: usize) -> Option<usize> {
        let b = &self.bx().bricks[b];
        let w = b.width() as f32;
        let mut i = [0i32; 3];
        for a in 0..3 {
            let x = ((pu[a] - b.lower[a] as f32) / w).floor();
            if !(x >= 0.0 && x < b.size[a] as f32) {
                return None;
            }
            i[a] = x as i32;
        }
        Some(b.offset as usize + ((i[2] * b.size[1] + i[1]) * b.size[0] + i[0]) as usize)
    }

    pub(super) fn to_sample(&self, r: Recon) -> Sample {
        Sample {
            value: r.value,
            attribute: match self.settings.color_field {
                Some(_) => Attribute::Scalar(r.color),
                None => Attribute::None,
            },
        }
    }
}

/// The sums of the basis reconstruction: Σ weight, Σ weight × value (and
/// colour), and their derivatives.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct BasisSums {
    sw: f64,
    sv: f64,
    sc: f64,
    sdw: [f64; 3],
    sdv: [f64; 3],
}

/// The value-only sums of the basis reconstruction (what a render without
/// shading asks for): Σ weight, Σ weight × value, Σ weight × colour, with a
/// brick's terms in `f32` and the sums in `f64` — the same arithmetic,
/// operation by operation, as the eight-lane form in [`super::lanes`], so
/// the packet path gives these bits.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct ValueSums {
    pub sw: f64,
    pub sv: f64,
    pub sc: f64,
}

/// What the stencil needs of a brick, read once for all the samples a
/// batch reconstructs with it.
#[derive(Clone, Copy, Debug)]
pub(super) struct BrickGrid {
    /// Lower corner, finest units.
    pub lower: [f32; 3],
    /// `1 / cell width`: widths are powers of two, so multiplying by it is
    /// exact division.
    pub inv_w: f32,
    /// Last cell index per axis.
    last: [i32; 3],
    /// The same as floats (exact: at most [`crate::bricks`]' 32 cells).
    pub last_f: [f32; 3],
    /// Strides of y and z in the brick-ordered values, the brick's first
    /// value and its number of cells.
    pub sx: usize,
    pub sxy: usize,
    pub base: usize,
    pub cells: usize,
}

impl BrickGrid {
    #[inline(always)]
    pub fn new(b: &Brick) -> Self {
        let last = b.size.map(|n| n - 1);
        BrickGrid {
            lower: b.lower.map(|l| l as f32),
            inv_w: 1.0 / b.width() as f32,
            last,
            last_f: last.map(|l| l as f32),
            sx: b.size[0] as usize,
            sxy: (b.size[0] * b.size[1]) as usize,
            base: b.offset as usize,
            cells: (b.size[0] * b.size[1] * b.size[2]) as usize,
        }
    }
}

/// One brick's tent stencil at a point, per axis: the two cells whose
/// centres lie within one cell width (indices clamped into the brick), their
/// weights and the weights' derivatives (both zero for a cell outside the
/// brick).
pub(super) struct Stencil {
    c: [[usize; 2]; 3],
    w: [[f32; 2]; 3],
    dw: [[f32; 2]; 3],
    inside: [[bool; 2]; 3],
}

impl Stencil {
    /// The stencil of brick `g` at unit-space point `pu`; `None` when no
    /// cell of the brick reaches it (and, with `gradient`, no derivative
    /// either).
    #[inline(always)]
    pub fn new(g: &BrickGrid, pu: Vec3, gradient: bool) -> Option<Stencil> {
        let mut st = Stencil {
            c: [[0; 2]; 3],
            w: [[0.0; 2]; 3],
            dw: [[0.0; 2]; 3],
            inside: [[false; 2]; 3],
        };
        for (a, p) in [pu.x, pu.y, pu.z].into_iter().enumerate() {
            let t = (p - g.lower[a]) * g.inv_w - 0.5;
            let i0 = floor_i32(t);
            let f = t - i0 as f32;
            let last = g.last[a];
            let in0 = i0 >= 0 && i0 <= last;
            let in1 = i0 + 1 >= 0 && i0 < last;
            st.inside[a] = [in0, in1];
            st.c[a] = [i0.clamp(0, last) as usize, (i0 + 1).clamp(0, last) as usize];
            st.w[a] = [if in0 { 1.0 - f } else { 0.0 }, if in1 { f } else { 0.0 }];
            st.dw[a] = [
                if in0 { -g.inv_w } else { 0.0 },
                if in1 { g.inv_w } else { 0.0 },
            ];
            if st.w[a][0] <= 0.0
                && st.w[a][1] <= 0.0
                && (!gradient || (st.dw[a][0] == 0.0 && st.dw[a][1] == 0.0))
            {
                return None;
            }
        }
        Some(st)
    }

    /// Index into the brick-ordered values of corner `(kx, ky, kz)`.
    #[inline(always)]
    pub fn cell(&self, g: &BrickGrid, kx: usize, ky: usize, kz: usize) -> usize {
        g.base + self.c[2][kz] * g.sxy + self.c[1][ky] * g.sx + self.c[0][kx]
    }
}

/// Adds the terms of brick `g` at unit-space point `pu` to `s`: the values
/// of `fields` (the opacity field, and the colour field when it differs)
/// and the value field's derivatives (value-only sums are
/// [`brick_value_sums`]).
///
/// The tents factor per axis, `Ĥ = hx·hy·hz`, so the eight-cell sums are
/// nested linear interpolations — x within each of the four rows, then y,
/// then z — and the weight sum is a product of per-axis sums; the
/// derivative sums reuse the same partial lerps. In `f64`, with short
/// dependency chains rather than eight sequential additions. A cell outside
/// the brick has zero weight (its clamped index reads a value that is
/// multiplied by zero).
#[inline(always)]
pub(super) fn brick_sums(
    g: &BrickGrid,
    pu: Vec3,
    fields: (&[f32], Option<&[f32]>),
    s: &mut BasisSums,
) {
    let Some(st) = Stencil::new(g, pu, true) else {
        return;
    };
    let [[wx0, wx1], [wy0, wy1], [wz0, wz1]] = st.w.map(|w| w.map(|w| w as f64));
    let [[x0, x1], [y0, y1], [z0, z1]] = st.c;
    // The four rows along x, (ky, kz) = (0, 0), (1, 0), (0, 1), (1, 1).
    let rows = [
        g.base + z0 * g.sxy + y0 * g.sx,
        g.base + z0 * g.sxy + y1 * g.sx,
        g.base + z1 * g.sxy + y0 * g.sx,
        g.base + z1 * g.sxy + y1 * g.sx,
    ];
    let lerp = |v: &[f32]| lerp_rows(v, &rows, [x0, x1], [wx0, wx1], [wy0, wy1]);
    let (r, p0, p1) = lerp(fields.0);
    let (ax, ay, az) = (wx0 + wx1, wy0 + wy1, wz0 + wz1);
    s.sw += ax * ay * az;
    s.sv += wz0 * p0 + wz1 * p1;
    if let Some(color) = fields.1 {
        let (_, c0, c1) = lerp(color);
        s.sc += wz0 * c0 + wz1 * c1;
    }
    let [[dx0, dx1], [dy0, dy1], [dz0, dz1]] = st.dw.map(|d| d.map(|d| d as f64));
    let v = fields.0;
    // ∂/∂x: the x weights replaced by their derivatives.
    let drow = |k: usize| dx0 * v[rows[k] + x0] as f64 + dx1 * v[rows[k] + x1] as f64;
    let d = [drow(0), drow(1), drow(2), drow(3)];
    s.sdv[0] += wz0 * (wy0 * d[0] + wy1 * d[1]) + wz1 * (wy0 * d[2] + wy1 * d[3]);
    // ∂/∂y: the y weights replaced.
    s.sdv[1] += wz0 * (dy0 * r[0] + dy1 * r[1]) + wz1 * (dy0 * r[2] + dy1 * r[3]);
    // ∂/∂z: the z weights replaced.
    s.sdv[2] += dz0 * p0 + dz1 * p1;
    s.sdw[0] += (dx0 + dx1) * ay * az;
    s.sdw[1] += ax * (dy0 + dy1) * az;
    s.sdw[2] += ax * ay * (dz0 + dz1);
}

/// The value-only terms of brick `g` at unit-space point `pu`, added to
/// `s`. The tents factor per axis, so the brick's terms are its weight —
/// the product of the per-axis weight sums — times the trilinear lerp
/// `a + f·(b − a)` of its eight cells (a cell outside the brick has weight
/// zero, and its clamped index reads the inside neighbour, so the lerp
/// does not see it). The lerp form keeps a constant field exactly constant;
/// the weight and lerp are `f32`, the sums `f64` (the products are exact
/// there), so the normalised value rounds back to the constant. The
/// eight-lane form ([`super::lanes::brick_value_lanes`]) does the same
/// operations in the same order, lane by lane.
#[inline(always)]
pub(super) fn brick_value_sums(
    g: &BrickGrid,
    pu: Vec3,
    fields: (&[f32], Option<&[f32]>),
    s: &mut ValueSums,
) {
    let Some(([x0, x1], wx, fx)) = tent_axis(g, 0, pu.x) else {
        return;
    };
    let Some(([y0, y1], wy, fy)) = tent_axis(g, 1, pu.y) else {
        return;
    };
    let Some(([z0, z1], wz, fz)) = tent_axis(g, 2, pu.z) else {
        return;
    };
    let rows = [
        z0 * g.sxy + y0 * g.sx,
        z0 * g.sxy + y1 * g.sx,
        z1 * g.sxy + y0 * g.sx,
        z1 * g.sxy + y1 * g.sx,
    ];
    let lerp = |v: &[f32]| {
        let v = &v[g.base..g.base + g.cells];
        let r = rows.map(|row| v[row + x0] + fx * (v[row + x1] - v[row + x0]));
        let (p0, p1) = (r[0] + fy * (r[1] - r[0]), r[2] + fy * (r[3] - r[2]));
        (p0 + fz * (p1 - p0)) as f64
    };
    let weight = (wx * wy * wz) as f64;
    s.sw += weight;
    s.sv += weight * lerp(fields.0);
    if let Some(color) = fields.1 {
        s.sc += weight * lerp(color);
    }
}

/// One axis of a brick's tent stencil at coordinate `p` (unit space): the
/// two cells whose centres lie within a cell width (clamped into the
/// brick), the sum of their weights (a cell outside the brick weighs zero)
/// and the lerp parameter; `None` when neither weighs anything. The cell
/// coordinate is clamped to `[-2, last + 2]` first — beyond that both
/// weights are zero anyway — so the floor stays exact in the lanes'
/// rounding trick.
#[inline(always)]
fn tent_axis(g: &BrickGrid, a: usize, p: f32) -> Option<([usize; 2], f32, f32)> {
    let last = g.last_f[a];
    let t = ((p - g.lower[a]) * g.inv_w - 0.5).max(-2.0).min(last + 2.0);
    let i0 = floor_i32(t) as f32;
    let f = t - i0;
    let w0 = if i0 >= 0.0 && i0 <= last {
        1.0 - f
    } else {
        0.0
    };
    let w1 = if i0 >= -1.0 && i0 < last { f } else { 0.0 };
    if !(w0 > 0.0 || w1 > 0.0) {
        return None;
    }
    let c = [i0.max(0.0).min(last), (i0 + 1.0).max(0.0).min(last)];
    Some((c.map(|c| c as usize), w0 + w1, f))
}

/// The x lerps of four rows of cells (row starts `rows`, columns `x`,
/// weights `wx`), and the y lerps of their two pairs.
#[inline(always)]
fn lerp_rows(
    v: &[f32],
    rows: &[usize; 4],
    x: [usize; 2],
    wx: [f64; 2],
    wy: [f64; 2],
) -> ([f64; 4], f64, f64) {
    let row = |k: usize| wx[0] * v[rows[k] + x[0]] as f64 + wx[1] * v[rows[k] + x[1]] as f64;
    let r = [row(0), row(1), row(2), row(3)];
    (r, wy[0] * r[0] + wy[1] * r[1], wy[0] * r[2] + wy[1] * r[3])
}

/// The cells' terms `[h, v, c, dx, dy, dz]`, added sorted by their bits.
#[derive(Default)]
pub(super) struct SortedTerms(Vec<[f32; 6]>);

impl SortedTerms {
    fn sums(&mut self, gradient: bool) -> BasisSums {
        self.0.sort_unstable_by_key(|t| t.map(f32::to_bits));
        let mut s = BasisSums::default();
        for &[h, v, c, dx, dy, dz] in &self.0 {
            let v = v as f64;
            s.sw += h as f64;
            s.sv += h as f64 * v;
            s.sc += h as f64 * c as f64;
            if gradient {
                for (a, da) in [dx, dy, dz].into_iter().enumerate() {
                    s.sdw[a] += da as f64;
                    s.sdv[a] += da as f64 * v;
                }
            }
        }
        s
    }
}
