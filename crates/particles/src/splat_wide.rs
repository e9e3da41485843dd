//! Sixteen lanes for the SPH splats, where the CPU has AVX-512.
//!
//! The eight-lane loop of `SplatBand` on sixteen lanes (the table position
//! `dx·dx·ax + ty` in f32 without fused multiply-adds, the f32 columns
//! summed in f64; eight columns of two rows where the eight lanes take
//! four), with the column's own polynomials: quintics on half-octaves
//! ([`ColumnPoly::wide`]), whose sixteen segments fill one register, read
//! with six permutes and evaluated with five fused multiply-adds where the
//! eight lanes' septics on octaves take eight and seven plus two products.
//! Both hold the column within 1e-6 of its peak (tested); a pixel's value
//! on sixteen lanes differs from the eight lanes' by less than that bound
//! (tested against the sum of the peaks over the pixel), not bit for bit.
//! Measured on the 2.1M-particle projection at 1024² (AVX-512 Xeon): the
//! loop ×0.8, the whole process ×0.85.

use super::Lean;
use super::band::SPAN;
use crate::kernel::column_poly::{ColumnPoly, OFFSET, WIDE_DEGREE, ZERO_UNTIL};

/// Whether the sixteen-lane path can run on this CPU.
pub(super) fn available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx512f")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Adds SPH splat `p` (not clipped, no pixel areas) to the rows `y.0..y.1`
/// of a band, `out` being those rows of the image, `width` apart (the
/// image's width and its padding, `row_stride`; lanes past the image's
/// edge add their zeros to the padding), with the
/// kernel's column polynomials `poly` (`last`: the table's last position).
///
/// # Safety
/// The CPU must have AVX-512F ([`available`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
pub(super) unsafe fn sph_rows(
    p: &Lean,
    y: (u32, u32),
    width: usize,
    poly: &ColumnPoly,
    last: f64,
    out: &mut [f64],
) {
    use std::arch::x86_64::*;
    let (first, end) = (p.cols.0 as usize, p.cols.1 as usize);
    let rows = p.rows.0.max(y.0)..p.rows.1.min(y.1);
    if first >= end || rows.is_empty() {
        return;
    }
    // Lanes 0–7: columns `k..k + 8` of a pair's upper row; 8–15: the same
    // columns of its lower row (as the eight lanes pair rows, four columns
    // a row).
    let iota = _mm512_setr_ps(
        0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0,
    );
    // The coefficients times the scale.
    let scale = _mm512_set1_ps(p.scale);
    // SAFETY: each table is sixteen f32s.
    let c: [__m512; WIDE_DEGREE + 1] = std::array::from_fn(|k| unsafe {
        _mm512_mul_ps(_mm512_loadu_ps(poly.wide[k].as_ptr()), scale)
    });
    let dx0 = _mm512_set1_ps((first as f64 + 0.5 - p.cx) as f32);
    let lanes_end = _mm512_set1_ps((end - first) as f32);
    let ax = _mm512_set1_ps(p.ax);
    // As on the eight lanes: each group's `dx²·ax` once a span; lanes past
    // the row's end, and rows past the band's or the support's, at
    // `ZERO_UNTIL`, and `t` clamped to it, where the polynomial is exactly
    // 0 (tested), so that no lane needs a mask: ~31 vector instructions a
    // group instead of ~41 (recomputed offsets, two compares, masked loads
    // and stores), ×0.92–0.94 on the 2.1M and 16.7M projections.
    let zero = _mm512_set1_ps(ZERO_UNTIL);
    // Each row's table position once, before the loop over its groups (a
    // row's ~5 scalar f64 operations run on the port the lanes' arithmetic
    // needs); rows past the band's or the support's end, and the row after
    // an odd count, at `ZERO_UNTIL`.
    let mut ty = [ZERO_UNTIL; super::BAND as usize + 1];
    for (t, yy) in ty.iter_mut().zip(rows.clone()) {
        *t = p.row_position(yy, rows.end, last).unwrap_or(ZERO_UNTIL);
    }
    let pairs = Pairs {
        ty: &ty[..rows.len() + 1],
        first_row: (rows.start - y.0) as usize,
        width,
        c: &c,
    };
    let mut span = first;
    while span < end {
        let groups = (end - span).div_ceil(8).min(SPAN);
        let mut tx = [zero; SPAN];
        for (g, tx) in tx.iter_mut().enumerate().take(groups) {
            let kk = _mm512_add_ps(iota, _mm512_set1_ps((span - first + g * 8) as f32));
            let dx = _mm512_add_ps(dx0, kk);
            let inside = _mm512_cmp_ps_mask::<_CMP_LT_OQ>(kk, lanes_end);
            *tx = _mm512_mask_blend_ps(inside, zero, _mm512_mul_ps(_mm512_mul_ps(dx, dx), ax));
        }
        // A fixed number of groups a pair where supports are narrow: the
        // loop unrolled, the groups' `tx` in registers, no exit to
        // mispredict per pair.
        // SAFETY: AVX-512F as this function; `span` a column of the rows.
        unsafe {
            match groups {
                1 => pairs.add::<1>(&tx, groups, span, out),
                2 => pairs.add::<2>(&tx, groups, span, out),
                3 => pairs.add::<3>(&tx, groups, span, out),
                4 => pairs.add::<4>(&tx, groups, span, out),
                _ => pairs.add::<0>(&tx, groups, span, out),
            }
        }
        span += groups * 8;
    }
}

/// What the row pairs of a splat in a band share (see [`sph_rows`]).
#[cfg(target_arch = "x86_64")]
struct Pairs<'a> {
    /// The table positions of the splat's rows in the band, then one at
    /// `ZERO_UNTIL` (the lower row of an odd count's last pair).
    ty: &'a [f32],
    /// The splat's first row in the band, from the band's first.
    first_row: usize,
    /// The distance between rows (the image's width and its padding).
    width: usize,
    /// The coefficients times the splat's scale.
    c: &'a [std::arch::x86_64::__m512; WIDE_DEGREE + 1],
}

#[cfg(target_arch = "x86_64")]
impl Pairs<'_> {
    /// Adds the columns of `groups` lane groups (`N` where `N > 0`) from
    /// column `span` on, their `dx²·ax` in `tx`, to every row pair.
    ///
    /// # Safety
    /// AVX-512F; `span` a column of the rows of `out`.
    #[target_feature(enable = "avx512f")]
    #[inline]
    unsafe fn add<const N: usize>(
        &self,
        tx: &[std::arch::x86_64::__m512; SPAN],
        groups: usize,
        span: usize,
        out: &mut [f64],
    ) {
        use std::arch::x86_64::*;
        let groups = if N > 0 { N } else { groups };
        let (c, width, rows) = (self.c, self.width, self.ty.len() - 1);
        let zero = _mm512_set1_ps(ZERO_UNTIL);
        let n = groups * 8;
        for k in (0..rows).step_by(2) {
            let (t0, t1) = (self.ty[k], self.ty[k + 1]);
            if t0 == ZERO_UNTIL && t1 == ZERO_UNTIL {
                continue;
            }
            let ty = _mm512_mask_blend_ps(0xff00, _mm512_set1_ps(t0), _mm512_set1_ps(t1));
            let up = out[(self.first_row + k) * width..]
                .as_mut_ptr()
                .wrapping_add(span);
            // The lower row, where it is in the band (else never written).
            let lower = k + 1 < rows;
            let down = up.wrapping_add(width);
            if lower && span + n <= width {
                // The common case: every group inside both rows.
                for (g, &tx) in tx.iter().enumerate().take(groups) {
                    let (lo, hi) = column(c, _mm512_min_ps(_mm512_add_ps(tx, ty), zero));
                    // SAFETY: `span + n <= width` and the lower row is in
                    // the band.
                    unsafe {
                        let (u, d) = (up.add(g * 8), down.add(g * 8));
                        _mm512_storeu_pd(u, _mm512_add_pd(_mm512_loadu_pd(u), lo));
                        _mm512_storeu_pd(d, _mm512_add_pd(_mm512_loadu_pd(d), hi));
                    }
                }
                continue;
            }
            for (g, &tx) in tx.iter().enumerate().take(groups) {
                let (lo, hi) = column(c, _mm512_min_ps(_mm512_add_ps(tx, ty), zero));
                let room = width - (span + g * 8);
                let m_up: __mmask8 = if room >= 8 {
                    0xff
                } else {
                    ((1u32 << room) - 1) as __mmask8
                };
                let m_down = if lower { m_up } else { 0 };
                // SAFETY: the masks keep the lanes inside the rows of the band.
                unsafe {
                    let (u, d) = (up.wrapping_add(g * 8), down.wrapping_add(g * 8));
                    let sum = _mm512_add_pd(_mm512_maskz_loadu_pd(m_up, u), lo);
                    _mm512_mask_storeu_pd(u, m_up, sum);
                    let sum = _mm512_add_pd(_mm512_maskz_loadu_pd(m_down, d), hi);
                    _mm512_mask_storeu_pd(d, m_down, sum);
                }
            }
        }
    }
}

/// The column at table positions `t` (clamped to `ZERO_UNTIL`) on sixteen
/// lanes, as [`ColumnPoly::at_wide`] computes it, widened to f64: the
/// upper row's eight lanes and the lower row's.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[inline]
fn column(
    c: &[std::arch::x86_64::__m512; WIDE_DEGREE + 1],
    t: std::arch::x86_64::__m512,
) -> (std::arch::x86_64::__m512d, std::arch::x86_64::__m512d) {
    use std::arch::x86_64::*;
    let tp = _mm512_castps_si512(_mm512_add_ps(t, _mm512_set1_ps(OFFSET)));
    // The exponent's low three bits and the mantissa's top bit pick the
    // half-octave; the rest of the mantissa is the variable.
    let at = _mm512_srli_epi32::<22>(tp);
    let mantissa = _mm512_and_si512(tp, _mm512_set1_epi32(0x003f_ffff));
    let x = _mm512_sub_ps(
        _mm512_castsi512_ps(_mm512_or_si512(mantissa, _mm512_set1_epi32(0x3f80_0000))),
        _mm512_set1_ps(1.25),
    );
    // Horner's scheme: five fused multiply-adds on the permuted
    // coefficients (the chain's latency is hidden by the other groups).
    let mut v = _mm512_permutexvar_ps(at, c[0]);
    for c in &c[1..] {
        v = _mm512_fmadd_ps(v, x, _mm512_permutexvar_ps(at, *c));
    }
    // Never below 0, as `ColumnPoly::at_wide`.
    let v = _mm512_max_ps(v, _mm512_setzero_ps());
    // Summed in f64: one rounding per add.
    let upper = _mm512_cvtps_pd(_mm512_castps512_ps256(v));
    let lower = _mm512_cvtps_pd(_mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(
        _mm512_castps_pd(v),
    )));
    (upper, lower)
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;
    use crate::kernel::Kernel;
    use crate::kernel::column_poly::ColumnPoly;

    /// The lanes' evaluation is `ColumnPoly::at_wide`'s, bit for bit (the
    /// bound is tested on the latter), at table positions through every
    /// half-octave, past the support and at the clamp.
    #[test]
    fn the_lanes_evaluate_at_wide() {
        if !available() {
            println!("note: this CPU has no AVX-512F; the sixteen-lane splats are not run here");
            return;
        }
        use std::arch::x86_64::*;
        for kernel in crate::tests::KERNELS.into_iter().filter(|k| k.is_sph()) {
            let poly: &ColumnPoly = Kernel::column_poly(&kernel).unwrap();
            let scale = 0.37f32;
            let wide = poly.wide.map(|c| c.map(|c| c * scale));
            let mut t = 0.0f32;
            while t <= ZERO_UNTIL {
                let ts: [f32; 16] = std::array::from_fn(|k| (t + k as f32 * 0.37).min(ZERO_UNTIL));
                // SAFETY: AVX-512F is available; sixteen f32s each.
                let (lo, hi) = unsafe {
                    let c = wide.map(|c| _mm512_loadu_ps(c.as_ptr()));
                    column(&c, _mm512_loadu_ps(ts.as_ptr()))
                };
                let mut got = [0.0f64; 16];
                // SAFETY: sixteen f64s.
                unsafe {
                    _mm512_storeu_pd(got.as_mut_ptr(), lo);
                    _mm512_storeu_pd(got.as_mut_ptr().add(8), hi);
                }
                for (g, &t) in got.iter().zip(&ts) {
                    let want = ColumnPoly::at_wide(&wide, t);
                    assert_eq!(*g, want as f64, "{kernel:?} at {t}");
                }
                t = t * 1.01 + 0.1;
            }
        }
    }
}
