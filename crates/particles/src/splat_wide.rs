//! Sixteen lanes for the SPH splats, where the CPU has AVX-512.
//!
//! The same arithmetic as the eight-lane loop of `SplatBand` (the table
//! position `dx·dx·ax + ty` in f32 without fused multiply-adds, the
//! segment from its exponent, Estrin's scheme with fused multiply-adds on
//! the segment's coefficients times the particle's scale, the f32 columns
//! summed in f64), lane for
//! lane, so every pixel gets the same bits; only the number of pixels per
//! step differs: eight columns of two rows where the eight lanes take four.

use super::Lean;
use super::band::SPAN;
use crate::kernel::column_poly::{ColumnPoly, DEGREE, OFFSET, ZERO_UNTIL};

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
/// of a band, `out` being those rows of an image `width` wide, with the
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
    // The coefficients times the scale, as the eight lanes take them.
    let scale = _mm512_set1_ps(p.scale);
    // SAFETY: each table is sixteen f32s.
    let c: [__m512; DEGREE + 1] = std::array::from_fn(|k| unsafe {
        _mm512_mul_ps(_mm512_loadu_ps(poly.lanes16[k].as_ptr()), scale)
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
    let row_t = |yy: u32| p.row_position(yy, rows.end, last).unwrap_or(ZERO_UNTIL);
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
        let n = groups * 8;
        for yy in rows.clone().step_by(2) {
            let (t0, t1) = (row_t(yy), row_t(yy + 1));
            if t0 == ZERO_UNTIL && t1 == ZERO_UNTIL {
                continue;
            }
            let ty = _mm512_mask_blend_ps(0xff00, _mm512_set1_ps(t0), _mm512_set1_ps(t1));
            let up = out[(yy - y.0) as usize * width..]
                .as_mut_ptr()
                .wrapping_add(span);
            // The lower row, where it is in the band (else never written).
            let lower = yy + 1 < rows.end;
            let down = up.wrapping_add(width);
            if lower && span + n <= width {
                // The common case: every group inside both rows.
                for (g, &tx) in tx.iter().enumerate().take(groups) {
                    let (lo, hi) = column(&c, _mm512_min_ps(_mm512_add_ps(tx, ty), zero));
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
                let (lo, hi) = column(&c, _mm512_min_ps(_mm512_add_ps(tx, ty), zero));
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
        span += n;
    }
}

/// The column at table positions `t` (clamped to `ZERO_UNTIL`) on sixteen
/// lanes, as `ColumnPoly::eval` computes it, widened to f64: the upper
/// row's eight lanes and the lower row's.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[inline]
fn column(
    c: &[std::arch::x86_64::__m512; DEGREE + 1],
    t: std::arch::x86_64::__m512,
) -> (std::arch::x86_64::__m512d, std::arch::x86_64::__m512d) {
    use std::arch::x86_64::*;
    let tp = _mm512_castps_si512(_mm512_add_ps(t, _mm512_set1_ps(OFFSET)));
    // The exponent's low four bits pick the segment.
    let at = _mm512_srli_epi32::<23>(tp);
    let mantissa = _mm512_and_si512(tp, _mm512_set1_epi32(0x007f_ffff));
    let x = _mm512_sub_ps(
        _mm512_castsi512_ps(_mm512_or_si512(mantissa, _mm512_set1_epi32(0x3f80_0000))),
        _mm512_set1_ps(1.5),
    );
    let c = |k: usize| _mm512_permutexvar_ps(at, c[k]);
    let ma = |a: __m512, b: __m512, c: __m512| _mm512_fmadd_ps(a, b, c);
    let x2 = _mm512_mul_ps(x, x);
    let lo = ma(ma(c(4), x, c(5)), x2, ma(c(6), x, c(7)));
    let hi = ma(ma(c(0), x, c(1)), x2, ma(c(2), x, c(3)));
    // Never below 0, as `ColumnPoly::eval`.
    let v = _mm512_max_ps(ma(hi, _mm512_mul_ps(x2, x2), lo), _mm512_setzero_ps());
    // Summed in f64 as the eight lanes do: one rounding per add.
    let upper = _mm512_cvtps_pd(_mm512_castps512_ps256(v));
    let lower = _mm512_cvtps_pd(_mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(
        _mm512_castps_pd(v),
    )));
    (upper, lower)
}
