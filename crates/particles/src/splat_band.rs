//! The band loop of the splatter: one band's rows summed over its splats
//! in order, the SPH columns eight (or sixteen) pixels at a time as the
//! kernel's column polynomials, the Gaussians' closed form per pixel.

use voxless_core::simd::{LANES, Lanes, WithLanes};

use super::{BandSplats, Lean, splat_wide};
use crate::kernel::column_poly::{ColumnPoly, DEGREE, ZERO_UNTIL};

/// One band's f64 sums over its splats in order (on the SIMD lanes the
/// splatter was given). Clipped splats are left to `clipped`.
pub(super) struct SplatBand<'a> {
    pub(super) splats: BandSplats<'a>,
    /// SPH splats on sixteen lanes (the `Splatter`'s `wide`).
    pub(super) wide: bool,
    pub(super) y: (u32, u32),
    pub(super) width: usize,
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
                let row = &mut self.out[(y - self.y.0) as usize * self.width..][..self.width];
                for (x, o) in row.iter_mut().enumerate().take(end).skip(first) {
                    let dx = x as f64 + 0.5 - p.lean.cx;
                    let b2 = dx * dx * pw * pw + dy * dy * ph * ph;
                    *o += p.weight * p.column.at(b2);
                }
            }
        }
        for p in splats.lean() {
            self.lean_rows::<L>(p, &c, last);
        }
    }
}

impl SplatBand<'_> {
    /// Adds the SPH splat `p`'s columns to the band's rows, eight (or
    /// sixteen) pixels at a time: `c` the column's polynomials on the
    /// lanes, `last` the last table position.
    #[inline(always)]
    fn lean_rows<L: Lanes>(&mut self, p: &Lean, c: &[L; DEGREE + 1], last: f64) {
        #[cfg(target_arch = "x86_64")]
        if self.wide {
            // SAFETY: `wide` is set only where the CPU has AVX-512F.
            unsafe { splat_wide::sph_rows(p, self.y, self.width, self.poly, last, self.out) };
            return;
        }
        let s = L::splat;
        // The columns of the support's square: the lanes outside the
        // support add 0, which costs less than finding each row's chord (a
        // varying trip count mispredicts: measured 1.3× slower).
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
        // Spans of up to SPAN lane groups: each group's `dx²·ax` is the
        // same on every row, so it is computed once a span (measured:
        // 5–10 % of the loop). Lanes past the row's end start at
        // `ZERO_UNTIL`, and `t` is clamped to it: the polynomial is
        // exactly 0 from the support on (tested), so no lane needs a mask
        // (measured: 5 % of the loop).
        let zero = s(ZERO_UNTIL);
        let mut span = first;
        while span < end {
            let groups = (end - span).div_ceil(LANES).min(SPAN);
            let mut tx = [s(0.0); SPAN];
            for (g, tx) in tx.iter_mut().enumerate().take(groups) {
                let kk = L::iota() + s((span - first + g * LANES) as f32);
                let dx = dx0 + kk;
                *tx = kk.lt(lanes_end).select(dx * dx * ax, zero);
            }
            for y in rows.clone() {
                let dy = y as f64 + 0.5 - p.cy;
                let ty = p.ay * dy * dy;
                if !(ty < last) {
                    continue;
                }
                let ty = s(ty as f32);
                let row = &mut self.out[(y - self.y.0) as usize * self.width..][..self.width];
                for (g, &tx) in tx.iter().enumerate().take(groups) {
                    let col = ColumnPoly::eval(&c, (tx + ty).min(zero));
                    // Summed in f64: the order of the particles moves
                    // only f64 bits.
                    let at = span + g * LANES;
                    match row.get_mut(at..at + LANES) {
                        Some(o) => L::add_f64(o.try_into().expect("LANES"), col),
                        None => {
                            let mut tail = [0.0f64; LANES];
                            L::add_f64(&mut tail, col);
                            for (o, t) in row[at..].iter_mut().zip(tail) {
                                *o += t;
                            }
                        }
                    }
                }
            }
            span += groups * LANES;
        }
    }
}

/// Lane groups per span of a splat's columns (see `SplatBand::run`).
const SPAN: usize = 8;
