//! The band loop of the splatter: one band's rows summed over its splats
//! in order, the SPH columns eight (or sixteen) pixels at a time as the
//! kernel's column polynomials, the Gaussians' closed form per pixel.

use voxless_core::simd::{HALF_LANES, Lanes, WithLanes};

use super::{BandSplats, Lean, splat_wide};
use crate::kernel::column_poly::{ColumnPoly, DEGREE, ZERO_UNTIL};

/// One band's f64 sums over its splats in order (on the SIMD lanes the
/// splatter was given). Clipped splats are left to `clipped`.
pub(super) struct SplatBand<'a> {
    pub(super) splats: BandSplats<'a>,
    /// SPH splats on sixteen lanes (the `Splatter`'s `wide`).
    pub(super) wide: bool,
    pub(super) y: (u32, u32),
    /// The distance between the band's rows (the image's width and its
    /// padding: `row_stride`).
    pub(super) stride: usize,
    /// The kernel's column as polynomials (zeros for the Gaussians).
    pub(super) poly: &'a ColumnPoly,
    /// The band's rows of the image.
    pub(super) out: &'a mut [f64],
}

impl WithLanes for SplatBand<'_> {
    type Output = ();
    #[inline(always)]
    fn run<L: Lanes>(mut self) {
        // Table positions run over 0..=LAST for every kernel (the Gaussians'
        // columns scale their offsets alike).
        let last = (crate::kernel::sph::COLUMN_TABLE - 1) as f64;
        // The column's polynomials, one coefficient per register.
        let c = self.poly.lanes::<L>();
        let splats = self.splats;
        for p in splats.iter() {
            if p.clip || p.area {
                continue;
            }
            if p.column.is_sph() {
                // (On the CPU these are lean splats unless clipped or averaged;
                // the loop sums any it is given.)
                self.lean_rows::<L>(&p.lean, &c, last);
                continue;
            }
            // The columns of the support's square.
            let (first, end) = (p.lean.cols.0 as usize, p.lean.cols.1 as usize);
            let rows = p.lean.rows.0.max(self.y.0)..p.lean.rows.1.min(self.y.1);
            if first >= end || rows.is_empty() {
                continue;
            }
            // The Gaussians: the closed form per pixel, in f64.
            let (pw, ph) = p.pixel;
            for y in rows {
                let dy = y as f64 + 0.5 - p.lean.cy;
                if !(p.lean.ay * dy * dy < last) {
                    continue;
                }
                let row = &mut self.out[(y - self.y.0) as usize * self.stride..][..self.stride];
                for (x, o) in row.iter_mut().enumerate().take(end).skip(first) {
                    let dx = x as f64 + 0.5 - p.lean.cx;
                    let b2 = dx * dx * pw * pw + dy * dy * ph * ph;
                    *o += p.weight * p.column.at(b2);
                }
            }
        }
        #[cfg(target_arch = "x86_64")]
        if self.wide {
            // SAFETY: `wide` is set only where the CPU has AVX-512F.
            unsafe { splat_wide::band(splats, self.y, self.stride, self.poly, last, self.out) };
            return;
        }
        for p in splats.lean() {
            self.lean_rows::<L>(p, &c, last);
        }
    }
}

impl SplatBand<'_> {
    /// Adds the SPH splat `p`'s columns to the band's rows, on lane groups
    /// of two rows by half as many columns (four by two on eight lanes,
    /// eight by two on sixteen): `c` the column's polynomials on the lanes,
    /// `last` the last table position.
    #[inline(always)]
    fn lean_rows<L: Lanes>(&mut self, p: &Lean, c: &[L; DEGREE + 1], last: f64) {
        #[cfg(target_arch = "x86_64")]
        if self.wide {
            // SAFETY: `wide` is set only where the CPU has AVX-512F.
            unsafe { splat_wide::sph_rows(p, self.y, self.stride, self.poly, last, self.out) };
            return;
        }
        let s = L::splat;
        // The columns of the support's square: the lanes outside the
        // support add 0, which costs less than finding each row's chord (a
        // varying trip count mispredicts: measured 1.3× slower). Two rows a
        // group, not one row of eight columns: a support 2–3 pixels wide
        // fills half the lanes instead of a quarter, one 20 wide wastes
        // 4 % of its columns instead of 17 %.
        let (first, end) = (p.cols.0 as usize, p.cols.1 as usize);
        let rows = p.rows.0.max(self.y.0)..p.rows.1.min(self.y.1);
        if first >= end || rows.is_empty() {
            return;
        }
        // Offsets of evenly spaced pixel centres: dx = dx0 + k.
        let dx0 = s((first as f64 + 0.5 - p.cx) as f32);
        // The column's coefficients times the particle's scale: eight
        // products a particle instead of one a pixel (6–9 % of a
        // projection's time on a Zen 3).
        let scale = s(p.scale);
        let c = [
            c[0] * scale,
            c[1] * scale,
            c[2] * scale,
            c[3] * scale,
            c[4] * scale,
            c[5] * scale,
            c[6] * scale,
            c[7] * scale,
        ];
        let lanes_end = s((end - first) as f32);
        let ax = s(p.ax);
        // Lanes 0–3 hold the upper row of a pair, 4–7 the lower one, over
        // the same four columns.
        let upper = L::first(HALF_LANES);
        let iota = L::from_array(std::array::from_fn(|k| (k % HALF_LANES) as f32));
        // Spans of up to SPAN lane groups: each group's `dx²·ax` is the
        // same on every row, so it is computed once a span (measured:
        // 5–10 % of the loop). Lanes past the row's end, and rows past the
        // band's or the support's, start at `ZERO_UNTIL`, and `t` is
        // clamped to it: the polynomial is exactly 0 from the support on
        // (tested), so no lane needs a mask (measured: 5 % of the loop),
        // and adding that +0 leaves every sum's bits as they were.
        let zero = s(ZERO_UNTIL);
        let row_t = |y: u32| p.row_position(y, rows.end, last).unwrap_or(ZERO_UNTIL);
        let width = self.stride;
        let mut span = first;
        while span < end {
            let groups = (end - span).div_ceil(HALF_LANES).min(SPAN);
            let mut tx = [zero; SPAN];
            for (g, tx) in tx.iter_mut().enumerate().take(groups) {
                let kk = iota + s((span - first + g * HALF_LANES) as f32);
                let dx = dx0 + kk;
                *tx = kk.lt(lanes_end).select(dx * dx * ax, zero);
            }
            for y in rows.clone().step_by(2) {
                let (t0, t1) = (row_t(y), row_t(y + 1));
                if t0 == ZERO_UNTIL && t1 == ZERO_UNTIL {
                    continue;
                }
                let ty = upper.select(s(t0), s(t1));
                // The pair's rows (the lower one may be past the band).
                let at_row = (y - self.y.0) as usize * width;
                let (up, down) = self.out[at_row..].split_at_mut(width);
                let lower = y + 1 < rows.end;
                let n = groups * HALF_LANES;
                if lower && span + n <= width {
                    // The common case: every group inside both rows.
                    let up = up[span..span + n].chunks_exact_mut(HALF_LANES);
                    let down = down[span..span + n].chunks_exact_mut(HALF_LANES);
                    for ((u, d), &tx) in up.zip(down).zip(&tx) {
                        let col = ColumnPoly::eval(&c, (tx + ty).min(zero));
                        // Summed in f64: the order of the particles moves
                        // only f64 bits.
                        L::add_f64_halves(
                            u.try_into().expect("half"),
                            d.try_into().expect("half"),
                            col,
                        );
                    }
                    continue;
                }
                // The row's end, or no lower row: through a copy, the
                // lanes past either dropped (they hold +0).
                let down = if lower { &mut down[..width] } else { &mut [] };
                for (g, &tx) in tx.iter().enumerate().take(groups) {
                    let col = ColumnPoly::eval(&c, (tx + ty).min(zero));
                    let at = span + g * HALF_LANES;
                    let mut tail = [[0.0f64; HALF_LANES]; 2];
                    let [tu, td] = &mut tail;
                    L::add_f64_halves(tu, td, col);
                    for (o, t) in up[at..].iter_mut().zip(tu) {
                        *o += *t;
                    }
                    for (o, t) in down.get_mut(at..).unwrap_or_default().iter_mut().zip(td) {
                        *o += *t;
                    }
                }
            }
            span += groups * HALF_LANES;
        }
    }
}

/// Lane groups per span of a splat's columns (see `SplatBand::lean_rows`).
pub(super) const SPAN: usize = 16;
