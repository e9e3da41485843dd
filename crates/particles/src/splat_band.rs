//! The band loop of the splatter: one band's rows summed over its splats
//! in order, the SPH columns eight (or sixteen) pixels at a time as the
//! kernel's column polynomials, the Gaussians' closed form per pixel.

use voxless_core::simd::{LANES, Lanes, WithLanes};

use super::{BandSplats, Lean, splat_wide};
use crate::kernel::column_poly::{ColumnPoly, DEGREE};

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
        let s = L::splat;
        let top = s(last as f32);
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
                self.lean_rows::<L>(&p.lean, &c, last, top);
                continue;
            }
            // The columns of the support's square (a pixel of margin).
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
            self.lean_rows::<L>(p, &c, last, top);
        }
    }
}

impl SplatBand<'_> {
    /// Adds the SPH splat `p`'s columns to the band's rows, eight (or
    /// sixteen) pixels at a time: `c` the column's polynomials on the
    /// lanes, `last` the last table position, `top` it on every lane.
    #[inline(always)]
    fn lean_rows<L: Lanes>(&mut self, p: &Lean, c: &[L; DEGREE + 1], last: f64, top: L) {
        #[cfg(target_arch = "x86_64")]
        if self.wide {
            // SAFETY: `wide` is set only where the CPU has AVX-512F.
            unsafe { splat_wide::sph_rows(p, self.y, self.width, self.poly, last, self.out) };
            return;
        }
        let s = L::splat;
        // The columns of the support's square (a pixel of margin): the
        // lanes outside the support add 0, which costs less than finding
        // each row's chord (a varying trip count mispredicts: measured
        // 1.3× slower).
        let (first, end) = (p.cols.0 as usize, p.cols.1 as usize);
        let rows = p.rows.0.max(self.y.0)..p.rows.1.min(self.y.1);
        if first >= end || rows.is_empty() {
            return;
        }
        // Offsets of evenly spaced pixel centres: dx = dx0 + k.
        let dx0 = s((first as f64 + 0.5 - p.cx) as f32);
        let scale = s(p.scale);
        let lanes_end = s((end - first) as f32);
        let ax = s(p.ax);
        // Spans of up to SPAN lane groups: each group's `dx²·ax` and
        // its mask of lanes inside the row are the same on every row,
        // so they are computed once a span (measured: 5–10 % of the
        // loop).
        let mut span = first;
        while span < end {
            let groups = (end - span).div_ceil(LANES).min(SPAN);
            let mut tx = [s(0.0); SPAN];
            let mut live = [s(0.0); SPAN];
            for g in 0..groups {
                let kk = L::iota() + s((span - first + g * LANES) as f32);
                let dx = dx0 + kk;
                tx[g] = dx * dx * ax;
                live[g] = kk.lt(lanes_end);
            }
            for y in rows.clone() {
                let dy = y as f64 + 0.5 - p.cy;
                let ty = p.ay * dy * dy;
                if !(ty < last) {
                    continue;
                }
                let ty = s(ty as f32);
                let row = &mut self.out[(y - self.y.0) as usize * self.width..][..self.width];
                for g in 0..groups {
                    let t = tx[g] + ty;
                    // Inside the support and the row (lanes past the
                    // end add 0).
                    let inside = live[g].select(t.lt(top), s(0.0));
                    let col = inside.select(ColumnPoly::eval(c, t), s(0.0));
                    // Summed in f64: the product with the scale is
                    // exact, so the order of the particles moves only
                    // f64 bits.
                    let at = span + g * LANES;
                    match row.get_mut(at..at + LANES) {
                        Some(o) => L::add_product_f64(o.try_into().expect("LANES"), col, scale),
                        None => {
                            let mut tail = [0.0f64; LANES];
                            L::add_product_f64(&mut tail, col, scale);
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
