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
use crate::kernel::column_poly::{ColumnPoly, DEGREE, OFFSET};

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
    if first >= end {
        return;
    }
    let top = _mm512_set1_ps(last as f32);
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
    let (offset, half) = (_mm512_set1_ps(OFFSET), _mm512_set1_ps(1.5));
    let (mantissa, one) = (
        _mm512_set1_epi32(0x007f_ffff),
        _mm512_set1_epi32(0x3f80_0000),
    );
    let dx0 = _mm512_set1_ps((first as f64 + 0.5 - p.cx) as f32);
    let lanes_end = _mm512_set1_ps((end - first) as f32);
    let ax = _mm512_set1_ps(p.ax);
    let rows = p.rows.0.max(y.0)..p.rows.1.min(y.1);
    // A row's table position, infinite (every lane masked) past the
    // support or the band.
    let row_t = |yy: u32| p.row_position(yy, rows.end, last).unwrap_or(f32::INFINITY);
    for yy in rows.clone().step_by(2) {
        let (t0, t1) = (row_t(yy), row_t(yy + 1));
        if t0 == f32::INFINITY && t1 == f32::INFINITY {
            continue;
        }
        let ty = _mm512_mask_blend_ps(0xff00, _mm512_set1_ps(t0), _mm512_set1_ps(t1));
        let up = out[(yy - y.0) as usize * width..].as_mut_ptr();
        // The lower row, where it is in the band (else never written).
        let lower = yy + 1 < rows.end;
        let down = up.wrapping_add(width);
        let mut k = 0;
        while first + k < end {
            let kk = _mm512_add_ps(iota, _mm512_set1_ps(k as f32));
            let dx = _mm512_add_ps(dx0, kk);
            let t = _mm512_add_ps(_mm512_mul_ps(_mm512_mul_ps(dx, dx), ax), ty);
            let inside = _mm512_cmp_ps_mask::<_CMP_LT_OQ>(kk, lanes_end)
                & _mm512_cmp_ps_mask::<_CMP_LT_OQ>(t, top);
            let tp = _mm512_castps_si512(_mm512_add_ps(t, offset));
            // The exponent's low four bits pick the segment.
            let at = _mm512_srli_epi32::<23>(tp);
            let x = _mm512_sub_ps(
                _mm512_castsi512_ps(_mm512_or_si512(_mm512_and_si512(tp, mantissa), one)),
                half,
            );
            let c = |k: usize| _mm512_permutexvar_ps(at, c[k]);
            let ma = |a: __m512, b: __m512, c: __m512| _mm512_fmadd_ps(a, b, c);
            let x2 = _mm512_mul_ps(x, x);
            let lo = ma(ma(c(4), x, c(5)), x2, ma(c(6), x, c(7)));
            let hi = ma(ma(c(0), x, c(1)), x2, ma(c(2), x, c(3)));
            // Never below 0, as `ColumnPoly::eval`.
            let v = _mm512_max_ps(ma(hi, _mm512_mul_ps(x2, x2), lo), _mm512_setzero_ps());
            let col = _mm512_maskz_mov_ps(inside, v);
            // Summed in f64 as the eight lanes do: one rounding per add.
            let col_up = _mm512_cvtps_pd(_mm512_castps512_ps256(col));
            let col_down = _mm512_cvtps_pd(_mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(
                _mm512_castps_pd(col),
            )));
            let at = first + k;
            let room = width - at;
            let m_up: __mmask8 = if room >= 8 {
                0xff
            } else {
                ((1u32 << room) - 1) as __mmask8
            };
            let m_down = if lower { m_up } else { 0 };
            // SAFETY: the masks keep the lanes inside the rows of the band.
            unsafe {
                let (u, d) = (up.add(at), down.wrapping_add(at));
                let sum_up = _mm512_add_pd(_mm512_maskz_loadu_pd(m_up, u), col_up);
                _mm512_mask_storeu_pd(u, m_up, sum_up);
                let sum_down = _mm512_add_pd(_mm512_maskz_loadu_pd(m_down, d), col_down);
                _mm512_mask_storeu_pd(d, m_down, sum_down);
            }
            k += 8;
        }
    }
}
