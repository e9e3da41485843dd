//! Sixteen lanes for the SPH splats, where the CPU has AVX-512.
//!
//! The eight-lane loop of `SplatBand` on sixteen lanes (the table position
//! `dx·dx·ax + ty` in f32 without fused multiply-adds, the f32 columns
//! summed in f64; eight columns of two rows where the eight lanes take
//! four), with the column's own polynomials: quartics on quarter-octaves
//! ([`ColumnPoly::wide`]), whose 32 segments fill two registers, read with
//! five two-table permutes and evaluated with four fused multiply-adds
//! where the eight lanes' septics on octaves take eight and seven plus two
//! products. Both hold the column within 1e-6 of its peak (tested); a
//! pixel's value on sixteen lanes differs from the eight lanes' by less
//! than that bound (tested against the sum of the peaks over the pixel),
//! not bit for bit. Measured on the 2.1M-particle projection at 1024²
//! (AVX-512 Xeon, quintics on half-octaves then): the loop ×0.8, the whole
//! process ×0.85.
//!
//! Where the time goes (AMD Zen 5, 2.1M particles, 20-pixel supports, 33
//! lane groups a particle's ~330 pixels): a group took 20 vector
//! instructions in ~9 cycles, bound by the pipe the permutes share with
//! the widenings to f64 (two conversions and an extract; measured by
//! taking each out: ~8–10 ms of the 2.1M projection per instruction on
//! that pipe). Three changes (2026-12-02) took the group to 19, only 5 of
//! them on that pipe (was 8), and the process to ×0.86:
//! the f32s widened by shifts and ANDs into f64s `2⁻⁸⁹⁶` times their
//! value, the scale and `2⁸⁹⁶` applied by the image's fused multiply-add
//! ([`widen`]); the polynomials' variable left uncentred (no subtraction);
//! and no clamp of `t` (octaves of `t + 128`, see `column_poly`). The
//! lanes' order (`2j`, `2j + 1`: column `j` of the upper and the lower
//! row) is what lets a 64-bit lane hold both rows' values. (Summing
//! batches of splats in f32 first and flushing them into f64 was tried:
//! consecutive particles of a cosmological box drift ~4 pixels apart in
//! projection, so batches held ~5 splats and the flushes cost what the
//! widenings did.) The batches of particles are also placed here, on
//! eight f64 lanes ([`place_lanes`]).

use super::{BATCH, BandSplats, BatchLanes, CENTRE_SLACK, Lean, Placer, SplatParticle};
use crate::kernel::column_poly::{ColumnPoly, WIDE_DEGREE, WIDE_OFFSET as OFFSET, ZERO_UNTIL};
use crate::volume::INSIDE;

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

/// `ZERO_UNTIL + OFFSET` (the sixteen lanes' offset, `WIDE_OFFSET`): the
/// rows' positions are kept offset, so that a group's `t + OFFSET` (the
/// polynomials' variable) is one add, `tx + (ty + OFFSET)`, where it took
/// two (one f32 rounding more or less in `t`, far below the polynomials'
/// bound; −1 of the group's ~24 instructions).
const TOP: f32 = ZERO_UNTIL + OFFSET;

/// [`sph_rows`] of every lean splat of a band, in order (one loop with
/// `sph_rows` inlined: a call and an iterator's step a splat were ~10 %
/// of a projection of 2.1M particles).
///
/// # Safety
/// The CPU must have AVX-512F ([`available`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
pub(super) unsafe fn band(
    splats: BandSplats,
    y: (u32, u32),
    width: usize,
    poly: &ColumnPoly,
    last: f64,
    out: &mut [f64],
) {
    for piece in splats.pieces {
        let leans = &piece.lean;
        for &i in piece.lean_bands.members(splats.band) {
            // SAFETY: AVX-512F as this function.
            unsafe { sph_rows(&leans[i as usize], y, width, poly, last, out) };
        }
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
#[inline]
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
    // The coefficients as they are: the splat's scale multiplies each
    // value as it is added (see [`widen`]). (Scaled coefficients are each
    // rounded once more, and the quartics' terms cancel: for particles
    // sharing a scale that moved their mass by ~2e-7, all one way.)
    // SAFETY: each table is thirty-two f32s.
    let c: [[__m512; 2]; WIDE_DEGREE + 1] = std::array::from_fn(|k| unsafe {
        let at = poly.wide[k].as_ptr();
        [_mm512_loadu_ps(at), _mm512_loadu_ps(at.add(16))]
    });
    // Each row's table position once, before the loop over its groups (a
    // row's ~5 scalar f64 operations run on the port the lanes' arithmetic
    // needs); rows past the band's or the support's end, and the row after
    // an odd count, at `TOP`.
    let mut ty = [TOP; super::BAND as usize + 8];
    // SAFETY: AVX-512F as this function; `row_positions` writes
    // `(rows + 1).div_ceil(8)` blocks of eight, within `ty`.
    unsafe { row_positions(p, rows.clone(), last, &mut ty) };
    let pairs = Pairs {
        ty: &ty[..rows.len() + 1],
        first_row: (rows.start - y.0) as usize,
        width,
        c: &c,
        first,
        dx0: _mm512_set1_ps((first as f64 + 0.5 - p.cx) as f32),
        lanes_end: _mm512_set1_ps((end - first) as f32),
        ax: _mm512_set1_ps(p.ax),
        unbias: _mm512_set1_pd(p.scale as f64 * UNBIAS),
    };
    // Spans of at most four groups, each the pairs' loop unrolled over its
    // groups, their `dx²·ax` in registers (no exit to mispredict per
    // pair; a support up to 32 columns wide is one span).
    let mut span = first;
    while span < end {
        let groups = (end - span).div_ceil(8);
        // SAFETY: AVX-512F as this function; `span` a column of the rows.
        unsafe {
            match groups {
                1 => pairs.add::<1>(span, out),
                2 => pairs.add::<2>(span, out),
                3 => pairs.add::<3>(span, out),
                _ => pairs.add::<4>(span, out),
            }
        }
        span += groups.min(4) * 8;
    }
}

/// [`Lean::row_position`] of rows `rows` and the row after them, eight
/// rows at a time in f64 lanes (the same operations in the same order: the
/// same bits), `ZERO_UNTIL` where it gives `None`, plus `OFFSET` (see
/// [`TOP`]), into `ty` from its start. (A splat's ~20 rows took ~8 scalar
/// operations each, on the ports the groups' arithmetic needs: ×0.95 on
/// the 2.1M projection.)
///
/// # Safety
/// AVX-512F; `ty` holds `(rows.len() + 1).div_ceil(8) · 8` positions.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn row_positions(p: &Lean, rows: std::ops::Range<u32>, last: f64, ty: &mut [f32]) {
    use std::arch::x86_64::*;
    let n = rows.len() + 1;
    debug_assert!(ty.len() >= n.div_ceil(8) * 8);
    // Pixel centres `y + ½` (exact in f64, as `row_position` forms them).
    let half = _mm512_setr_pd(0.5, 1.5, 2.5, 3.5, 4.5, 5.5, 6.5, 7.5);
    let (cy, ay, last) = (
        _mm512_set1_pd(p.cy),
        _mm512_set1_pd(p.ay),
        _mm512_set1_pd(last),
    );
    let zero = _mm512_set1_pd(ZERO_UNTIL as f64);
    for b in 0..n.div_ceil(8) {
        let y = _mm512_add_pd(_mm512_set1_pd((rows.start as usize + 8 * b) as f64), half);
        let dy = _mm512_sub_pd(y, cy);
        let t = _mm512_mul_pd(_mm512_mul_pd(ay, dy), dy);
        // Rows inside `rows` (the last block's tail and the row after them
        // are not) whose position is below `last` (false for NaN).
        let k = rows.len().saturating_sub(8 * b).min(8);
        let inside = ((1u32 << k) - 1) as __mmask8;
        let keep = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(t, last) & inside;
        let t = _mm512_cvtpd_ps(_mm512_mask_blend_pd(keep, zero, t));
        let t = _mm256_add_ps(t, _mm256_set1_ps(OFFSET));
        // SAFETY: block `b` is within `ty` (the caller's bound).
        unsafe { _mm256_storeu_ps(ty.as_mut_ptr().add(8 * b), t) };
    }
}

/// What the row pairs of a splat in a band share (see [`sph_rows`]).
#[cfg(target_arch = "x86_64")]
struct Pairs<'a> {
    /// The offset table positions of the splat's rows in the band, then
    /// one at [`TOP`] (the lower row of an odd count's last pair).
    ty: &'a [f32],
    /// The splat's first row in the band, from the band's first.
    first_row: usize,
    /// The distance between rows (the image's width and its padding).
    width: usize,
    /// The coefficients (not scaled).
    c: &'a [[std::arch::x86_64::__m512; 2]; WIDE_DEGREE + 1],
    /// The splat's first column, the offset of its centre from that
    /// column's centre, its columns' count and `ax` in every lane.
    first: usize,
    dx0: std::arch::x86_64::__m512,
    lanes_end: std::arch::x86_64::__m512,
    ax: std::arch::x86_64::__m512,
    /// The splat's scale times [`UNBIAS`] (exact, and finite for every
    /// finite f32 scale: below `2¹²⁸·2⁸⁹⁶`).
    unbias: std::arch::x86_64::__m512d,
}

#[cfg(target_arch = "x86_64")]
impl Pairs<'_> {
    /// Adds the columns of `N` lane groups from column `span` on to every
    /// row pair.
    ///
    /// # Safety
    /// AVX-512F; `span` a column of the rows of `out`.
    #[target_feature(enable = "avx512f")]
    #[inline]
    unsafe fn add<const N: usize>(&self, span: usize, out: &mut [f64]) {
        use std::arch::x86_64::*;
        // Lanes `2j` and `2j + 1`: column `k + j` of a pair's upper row and
        // of its lower row (one 64-bit lane a column, see [`widen`]).
        let iota = _mm512_setr_ps(
            0.0, 0.0, 1.0, 1.0, 2.0, 2.0, 3.0, 3.0, 4.0, 4.0, 5.0, 5.0, 6.0, 6.0, 7.0, 7.0,
        );
        // As on the eight lanes: each group's `dx²·ax` once a span; lanes
        // past the row's end at `ZERO_UNTIL` and the others at most there,
        // so that a lane's `t` is below `2·ZERO_UNTIL`, where the
        // polynomial is exactly 0 past the support (tested): no lane needs
        // a mask (×0.92–0.94 on the 2.1M and 16.7M projections) or a clamp
        // a group (×0.97). Rows past the support (at `TOP`) are summed too:
        // their +0 costs less than a test a pair.
        let zero = _mm512_set1_ps(ZERO_UNTIL);
        let tx: [__m512; N] = std::array::from_fn(|g| {
            let kk = _mm512_add_ps(iota, _mm512_set1_ps((span - self.first + g * 8) as f32));
            let dx = _mm512_add_ps(self.dx0, kk);
            let inside = _mm512_cmp_ps_mask::<_CMP_LT_OQ>(kk, self.lanes_end);
            let tx = _mm512_min_ps(_mm512_mul_ps(_mm512_mul_ps(dx, dx), self.ax), zero);
            _mm512_mask_blend_ps(inside, zero, tx)
        });
        let (c, width, rows) = (self.c, self.width, self.ty.len() - 1);
        let unbias = self.unbias;
        let n = N * 8;
        for k in (0..rows).step_by(2) {
            let (t0, t1) = (self.ty[k], self.ty[k + 1]);
            let ty = _mm512_mask_blend_ps(0xaaaa, _mm512_set1_ps(t0), _mm512_set1_ps(t1));
            let up = out[(self.first_row + k) * width..]
                .as_mut_ptr()
                .wrapping_add(span);
            // The lower row, where it is in the band (else never written).
            let lower = k + 1 < rows;
            let down = up.wrapping_add(width);
            if lower && span + n <= width {
                // The common case: every group inside both rows.
                for (g, &tx) in tx.iter().enumerate() {
                    let (lo, hi) = widen(column(c, _mm512_add_ps(tx, ty)));
                    // SAFETY: `span + n <= width` and the lower row is in
                    // the band.
                    unsafe {
                        let (u, d) = (up.add(g * 8), down.add(g * 8));
                        _mm512_storeu_pd(u, _mm512_fmadd_pd(lo, unbias, _mm512_loadu_pd(u)));
                        _mm512_storeu_pd(d, _mm512_fmadd_pd(hi, unbias, _mm512_loadu_pd(d)));
                    }
                }
                continue;
            }
            for (g, &tx) in tx.iter().enumerate() {
                let (lo, hi) = widen(column(c, _mm512_add_ps(tx, ty)));
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
                    let sum = _mm512_fmadd_pd(lo, unbias, _mm512_maskz_loadu_pd(m_up, u));
                    _mm512_mask_storeu_pd(u, m_up, sum);
                    let sum = _mm512_fmadd_pd(hi, unbias, _mm512_maskz_loadu_pd(m_down, d));
                    _mm512_mask_storeu_pd(d, m_down, sum);
                }
            }
        }
    }
}

/// The column at offset table positions `t + OFFSET` (`t` below
/// `2·ZERO_UNTIL`) on sixteen lanes, as [`ColumnPoly::at_wide`] computes
/// it from `t + OFFSET`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[inline]
fn column(
    c: &[[std::arch::x86_64::__m512; 2]; WIDE_DEGREE + 1],
    t: std::arch::x86_64::__m512,
) -> std::arch::x86_64::__m512 {
    use std::arch::x86_64::*;
    let tp = _mm512_castps_si512(t);
    // The exponent's low three bits and the mantissa's top two bits pick
    // the quarter-octave; the rest of the mantissa is the variable.
    let at = _mm512_srli_epi32::<21>(tp);
    let mantissa = _mm512_and_si512(tp, _mm512_set1_epi32(0x001f_ffff));
    let x = _mm512_castsi512_ps(_mm512_or_si512(mantissa, _mm512_set1_epi32(0x3f80_0000)));
    // Horner's scheme: four fused multiply-adds on the permuted
    // coefficients (the chain's latency is hidden by the other groups).
    let mut v = _mm512_permutex2var_ps(c[0][0], at, c[0][1]);
    for c in &c[1..] {
        v = _mm512_fmadd_ps(v, x, _mm512_permutex2var_ps(c[0], at, c[1]));
    }
    // Never below 0, as `ColumnPoly::at_wide`.
    _mm512_max_ps(v, _mm512_setzero_ps())
}

/// `2⁸⁹⁶`: what [`widen`]'s lanes are scaled by (exactly).
const UNBIAS: f64 = f64::from_bits((1023 + 896) << 52);

/// The even and the odd f32 lanes of `v` (non-negative, not NaN) as f64
/// lanes, each `2⁻⁸⁹⁶` times its value, exactly: an f32's bits moved to
/// an f64's exponent and mantissa fields keep its exponent's bias (127,
/// not 1023), which is the same number times `2⁻⁸⁹⁶` (subnormal f32s
/// included, and 0 stays 0). The adds into the image are fused
/// multiply-adds by the splat's scale times [`UNBIAS`]: the exact product
/// of the column and the scale, added with one rounding. (Two shifts and
/// two ANDs run where the conversions and the upper half's extract took
/// the permutes' pipe: ×0.92 on the 2.1M-particle projection.)
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[inline]
fn widen(v: std::arch::x86_64::__m512) -> (std::arch::x86_64::__m512d, std::arch::x86_64::__m512d) {
    use std::arch::x86_64::*;
    let v = _mm512_castps_si512(v);
    // Bits 0–31 (even lane) and 32–63 (odd lane) to bits 29–60.
    let even = _mm512_srli_epi64::<3>(_mm512_slli_epi64::<32>(v));
    let odd = _mm512_and_si512(
        _mm512_srli_epi64::<3>(v),
        _mm512_set1_epi64(0x1fff_ffff_e000_0000),
    );
    (_mm512_castsi512_pd(even), _mm512_castsi512_pd(odd))
}

/// [`Placer::lanes`] on eight f64 lanes: the same operations in the same
/// order (the same bits; tested), the particles' coordinates read into
/// lanes once. The compiler's own vectorisation of the portable loop kept
/// two lanes and stored each result apart (~20 ns a particle on a
/// 16.7M-particle projection).
///
/// # Safety
/// The CPU must have AVX-512F ([`available`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
pub(super) unsafe fn place_lanes(
    pl: &Placer,
    batch: &[SplatParticle; BATCH],
    support: f32,
    (rx, ry): (f64, f64),
    l: &mut BatchLanes,
) {
    use std::arch::x86_64::*;
    let axis = |a: usize| -> [f32; BATCH] { std::array::from_fn(|k| batch[k].center[a]) };
    let (x, y, z) = (axis(0), axis(1), axis(2));
    // SAFETY: eight f32s each.
    let mut q = unsafe { [x, y, z].map(|c| _mm256_loadu_ps(c.as_ptr())) };
    l.only = 0xff;
    if let Some(b) = &pl.periodic {
        // `only_image`, lane by lane.
        let (size, s) = (b.extent(), _mm256_set1_ps(support));
        for (a, c) in q.iter().enumerate() {
            let lo = _mm256_sub_ps(_mm256_sub_ps(_mm256_set1_ps(b.min[a]), *c), s);
            let hi = _mm256_add_ps(_mm256_sub_ps(_mm256_set1_ps(b.max[a]), *c), s);
            let m = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GT_OQ>(lo, _mm256_set1_ps(-INSIDE * size[a])),
                _mm256_cmp_ps::<_CMP_LT_OQ>(hi, _mm256_set1_ps(INSIDE * size[a])),
            );
            l.only &= _mm256_movemask_ps(m) as u8;
        }
        // (+ 0, as `images` gives the particle itself.)
        q = q.map(|c| _mm256_add_ps(c, _mm256_setzero_ps()));
    }
    let [eye, right, up, _] = &pl.basis;
    let d: [__m512d; 3] =
        std::array::from_fn(|a| _mm512_sub_pd(_mm512_cvtps_pd(q[a]), _mm512_set1_pd(eye[a])));
    let dot = |e: &[f64; 3]| {
        let t = _mm512_add_pd(
            _mm512_mul_pd(d[0], _mm512_set1_pd(e[0])),
            _mm512_mul_pd(d[1], _mm512_set1_pd(e[1])),
        );
        _mm512_add_pd(t, _mm512_mul_pd(d[2], _mm512_set1_pd(e[2])))
    };
    let (a, b) = (dot(right), dot(up));
    let (w, h) = (pl.size.0 as f64, pl.size.1 as f64);
    let (kx, ky) = pl.to_pixels;
    let set = _mm512_set1_pd;
    let cx = _mm512_add_pd(_mm512_mul_pd(a, set(kx)), set(0.5 * w));
    let cy = _mm512_sub_pd(set(0.5 * h), _mm512_mul_pd(b, set(ky)));
    let (rx, ry, one, zero) = (set(rx), set(ry), set(1.0), _mm512_setzero_pd());
    let lt = |p: __m512d, q: __m512d| _mm512_cmp_pd_mask::<_CMP_LT_OQ>(p, q);
    let unseen = lt(_mm512_add_pd(_mm512_add_pd(cx, rx), one), zero)
        | lt(set(w), _mm512_sub_pd(_mm512_sub_pd(cx, rx), one))
        | lt(_mm512_add_pd(_mm512_add_pd(cy, ry), one), zero)
        | lt(set(h), _mm512_sub_pd(_mm512_sub_pd(cy, ry), one));
    // `floor_in` and `ceil_in`: clamped (NaN to 0, as `max` takes it),
    // truncated, and one more where the truncation is below the value.
    let clamp = |v: __m512d, hi: f64| _mm512_min_pd(_mm512_max_pd(v, zero), set(hi));
    let floor = |v: __m512d, hi: f64| {
        let m = clamp(v, hi);
        _mm512_cvtepu32_pd(_mm512_cvttpd_epu32(m))
    };
    let ceil = |v: __m512d, hi: f64| {
        let m = clamp(v, hi);
        let t = _mm512_cvtepu32_pd(_mm512_cvttpd_epu32(m));
        _mm512_mask_add_pd(t, lt(t, m), t, one)
    };
    let (half, slack) = (set(0.5), set(CENTRE_SLACK));
    let low =
        |c: __m512d, r: __m512d| _mm512_sub_pd(_mm512_sub_pd(_mm512_sub_pd(c, r), half), slack);
    let high =
        |c: __m512d, r: __m512d| _mm512_add_pd(_mm512_add_pd(_mm512_add_pd(c, r), half), slack);
    let (row0, row1) = (ceil(low(cy, ry), h), floor(high(cy, ry), h));
    let (col0, col1) = (ceil(low(cx, rx), w), floor(high(cx, rx), w));
    l.keep = !unseen & lt(row0, row1) & lt(col0, col1);
    // SAFETY: eight lanes into eight-entry arrays.
    unsafe {
        _mm512_storeu_pd(l.cx.as_mut_ptr(), cx);
        _mm512_storeu_pd(l.cy.as_mut_ptr(), cy);
        for (v, out) in [
            (row0, &mut l.row0),
            (row1, &mut l.row1),
            (col0, &mut l.col0),
            (col1, &mut l.col1),
        ] {
            _mm256_storeu_si256(out.as_mut_ptr().cast(), _mm512_cvttpd_epu32(v));
        }
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;
    use crate::kernel::Kernel;
    use crate::kernel::column_poly::ColumnPoly;

    /// The rows' positions in lanes are `Lean::row_position`'s plus
    /// `OFFSET` bit for bit, `TOP` where it gives none (past the rows, past
    /// the support), for rows from every offset and counts of a band.
    #[test]
    fn row_positions_are_row_position_plus_the_offset() {
        if !available() {
            return;
        }
        let last = (crate::kernel::sph::COLUMN_TABLE - 1) as f64;
        let mut rng = voxless_core::SmallRng(3);
        for _ in 0..2000 {
            let p = Lean {
                cx: 0.0,
                cy: 40.0 * rng.f() as f64,
                ay: last / (1.0 + 400.0 * rng.f() as f64),
                ax: 1.0,
                scale: 1.0,
                rows: (0, 0),
                cols: (0, 0),
            };
            let start = (30.0 * rng.f()) as u32;
            let rows = start..start + (super::super::BAND as f32 * rng.f()) as u32;
            let mut ty = [0.0f32; super::super::BAND as usize + 8];
            // SAFETY: AVX-512F is available; `ty` holds BAND + 8 positions.
            unsafe { row_positions(&p, rows.clone(), last, &mut ty) };
            for (k, &got) in ty[..rows.len() + 1].iter().enumerate() {
                let y = rows.start + k as u32;
                let want = p
                    .row_position(y, rows.end, last)
                    .map_or(TOP, |t| t + OFFSET);
                assert_eq!(got.to_bits(), want.to_bits(), "row {y} of {rows:?}");
            }
        }
    }

    /// The lanes' evaluation is `ColumnPoly::at_wide`'s, bit for bit (the
    /// bound is tested on the latter), at table positions through every
    /// quarter-octave, past the support and at the clamp.
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
                let got = unsafe {
                    let c = wide.map(|c| {
                        [
                            _mm512_loadu_ps(c.as_ptr()),
                            _mm512_loadu_ps(c.as_ptr().add(16)),
                        ]
                    });
                    let v = column(
                        &c,
                        _mm512_add_ps(_mm512_loadu_ps(ts.as_ptr()), _mm512_set1_ps(OFFSET)),
                    );
                    let mut got = [0.0f32; 16];
                    _mm512_storeu_ps(got.as_mut_ptr(), v);
                    got
                };
                for (g, &t) in got.iter().zip(&ts) {
                    let want = ColumnPoly::at_wide(&wide, t);
                    assert_eq!(g.to_bits(), want.to_bits(), "{kernel:?} at {t}");
                }
                t = t * 1.01 + 0.1;
            }
        }
    }

    /// The widened lanes times a scale times `UNBIAS`, added by a fused
    /// multiply-add, are the f32s converted, multiplied by the scale and
    /// added with one rounding: the same bits, for zeros, subnormals, the
    /// largest f32s and values across every exponent, scales from the
    /// smallest f32 to the largest, to sums of every size.
    #[test]
    fn widened_lanes_add_as_converted_ones() {
        if !available() {
            return;
        }
        use std::arch::x86_64::*;
        let mut state = 11u64;
        let mut bits = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 32) as u32
        };
        let special = [
            0.0f32,
            f32::from_bits(1),
            f32::from_bits(0x007f_ffff),
            f32::MIN_POSITIVE,
            f32::MAX,
            1.0,
        ];
        for round in 0..20_000 {
            let v: [f32; 16] = std::array::from_fn(|k| {
                if round < 6 && k % 3 == 0 {
                    special[round]
                } else {
                    f32::from_bits(bits() & 0x7f7f_ffff)
                }
            });
            let base: [f64; 16] = std::array::from_fn(|k| {
                if k % 4 == 0 {
                    0.0
                } else {
                    (bits() as f64 / 4e9 - 0.3) * 10f64.powi((bits() % 80) as i32 - 40)
                }
            });
            let scale = match round % 4 {
                0 => 1.0f32,
                1 => [f32::from_bits(1), f32::MIN_POSITIVE, f32::MAX][round % 3],
                _ => f32::from_bits(bits() & 0x7f7f_ffff),
            };
            let (mut even, mut odd) = ([0.0f64; 8], [0.0f64; 8]);
            // SAFETY: AVX-512F is available; sixteen f32s, eight f64s each.
            unsafe {
                let (e, o) = widen(_mm512_loadu_ps(v.as_ptr()));
                let unbias = _mm512_set1_pd(scale as f64 * UNBIAS);
                let e = _mm512_fmadd_pd(e, unbias, _mm512_loadu_pd(base.as_ptr()));
                let o = _mm512_fmadd_pd(o, unbias, _mm512_loadu_pd(base.as_ptr().add(8)));
                _mm512_storeu_pd(even.as_mut_ptr(), e);
                _mm512_storeu_pd(odd.as_mut_ptr(), o);
            }
            for j in 0..8 {
                let add = |base: f64, v: f32| (v as f64).mul_add(scale as f64, base);
                let want = (add(base[j], v[2 * j]), add(base[8 + j], v[2 * j + 1]));
                assert_eq!(
                    even[j].to_bits(),
                    want.0.to_bits(),
                    "{:e} + {:e}",
                    base[j],
                    v[2 * j]
                );
                assert_eq!(
                    odd[j].to_bits(),
                    want.1.to_bits(),
                    "{:e} + {:e}",
                    base[8 + j],
                    v[2 * j + 1]
                );
            }
        }
    }
}
