//! Sixteen lanes for the SPH splats, where the CPU has AVX-512.
//!
//! The same arithmetic as the eight-lane loop of `SplatBand` (the table
//! position `dx·dx·ax + ty` in f32 without fused multiply-adds, the
//! truncated index clamped to the table, the linear interpolation, the f64
//! sums of the exact f32 × f32 products), lane for lane, so every pixel
//! gets the same bits; only the number of pixels per step differs. A row
//! of a support 10–16 pixels wide takes one step where eight lanes take two,
//! and one 64-bit gather reads eight (value, next value) pairs.

use super::Splat;

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
/// of a band, `out` being those rows of an image `width` wide, reading the
/// column table as (value, next value) `pairs` (`last`: the table's last
/// position).
///
/// # Safety
/// The CPU must have AVX-512F ([`available`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
pub(super) unsafe fn sph_rows(
    p: &Splat,
    y: (u32, u32),
    width: usize,
    pairs: &[[f32; 2]],
    last: f64,
    out: &mut [f64],
) {
    use std::arch::x86_64::*;
    let (first, end) = (p.cols.0 as usize, p.cols.1 as usize);
    let Some(max_index) = pairs.len().checked_sub(1) else {
        return;
    };
    if first >= end {
        return;
    }
    let max_index = _mm512_set1_epi32(max_index.min(i32::MAX as usize) as i32);
    let zero = _mm512_setzero_si512();
    let (top, edge) = (
        _mm512_set1_ps(last as f32),
        _mm512_set1_ps((last - 1.0) as f32),
    );
    let iota = _mm512_setr_ps(
        0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0, 12.0, 13.0, 14.0, 15.0,
    );
    // The values (even f32s) and the next values (odd) of the two gathers'
    // sixteen pairs, in lane order.
    let even = _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30);
    let odd = _mm512_setr_epi32(1, 3, 5, 7, 9, 11, 13, 15, 17, 19, 21, 23, 25, 27, 29, 31);
    let base = pairs.as_ptr().cast::<f64>();
    let dx0 = _mm512_set1_ps((first as f64 + 0.5 - p.cx) as f32);
    let scale = _mm512_set1_pd(p.scale as f32 as f64);
    let lanes_end = _mm512_set1_ps((end - first) as f32);
    let ax = _mm512_set1_ps(p.ax as f32);
    for yy in p.rows.0.max(y.0)..p.rows.1.min(y.1) {
        let dy = yy as f64 + 0.5 - p.cy;
        let ty = p.ay * dy * dy;
        if !(ty < last) {
            continue;
        }
        let ty = _mm512_set1_ps(ty as f32);
        let row = &mut out[(yy - y.0) as usize * width..][..width];
        let mut k = 0;
        while first + k < end {
            let kk = _mm512_add_ps(iota, _mm512_set1_ps(k as f32));
            let dx = _mm512_add_ps(dx0, kk);
            let t = _mm512_add_ps(_mm512_mul_ps(_mm512_mul_ps(dx, dx), ax), ty);
            let inside = _mm512_cmp_ps_mask::<_CMP_LT_OQ>(kk, lanes_end)
                & _mm512_cmp_ps_mask::<_CMP_LT_OQ>(t, top);
            let x = _mm512_min_ps(t, edge);
            let i = _mm512_roundscale_ps::<{ _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC }>(x);
            let f = _mm512_sub_ps(x, i);
            let at_table =
                _mm512_min_epi32(_mm512_max_epi32(_mm512_cvttps_epi32(i), zero), max_index);
            // SAFETY: every index is clamped to 0..pairs.len(); each pair's
            // eight bytes are read as one f64.
            let (a, b) = unsafe {
                (
                    _mm512_i32gather_pd::<8>(_mm512_castsi512_si256(at_table), base),
                    _mm512_i32gather_pd::<8>(_mm512_extracti64x4_epi64::<1>(at_table), base),
                )
            };
            let (a, b) = (_mm512_castpd_ps(a), _mm512_castpd_ps(b));
            let lo = _mm512_permutex2var_ps(a, even, b);
            let hi = _mm512_permutex2var_ps(a, odd, b);
            let col = _mm512_maskz_mov_ps(
                inside,
                _mm512_add_ps(lo, _mm512_mul_ps(_mm512_sub_ps(hi, lo), f)),
            );
            // Summed in f64 as the eight lanes do: (column × scale) exact,
            // one rounding per add.
            let col_lo = _mm512_cvtps_pd(_mm512_castps512_ps256(col));
            let col_hi = _mm512_cvtps_pd(_mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(
                _mm512_castps_pd(col),
            )));
            let at = first + k;
            let room = row.len() - at;
            let (m_lo, m_hi): (__mmask8, __mmask8) = if room >= 16 {
                (0xff, 0xff)
            } else {
                let keep = |n: usize| ((1u32 << n.min(8)) - 1) as __mmask8;
                (keep(room), keep(room.saturating_sub(8)))
            };
            // SAFETY: the masks keep the lanes inside the row.
            unsafe {
                let o = row.as_mut_ptr().add(at);
                let sum_lo =
                    _mm512_add_pd(_mm512_maskz_loadu_pd(m_lo, o), _mm512_mul_pd(col_lo, scale));
                _mm512_mask_storeu_pd(o, m_lo, sum_lo);
                let sum_hi = _mm512_add_pd(
                    _mm512_maskz_loadu_pd(m_hi, o.wrapping_add(8)),
                    _mm512_mul_pd(col_hi, scale),
                );
                _mm512_mask_storeu_pd(o.wrapping_add(8), m_hi, sum_hi);
            }
            k += 16;
        }
    }
}
