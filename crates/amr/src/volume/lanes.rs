//! The value-only basis reconstruction on eight samples at once.
//!
//! A run holds samples of one region (of one ray or several); every sample
//! adds the same bricks' terms. Here eight of them go through a brick
//! together: the per-axis tent stencils (a clamp, a floor, the weights, two
//! clamped cells) in lanes, the eight cells' values gathered (one
//! instruction each on AVX2), the trilinear lerp in lanes, and the brick's
//! weight and weighted lerp added to `f64` sums. Each lane does exactly the
//! operations of [`super::recon::brick_value_sums`] in its order, so a
//! sample gets the same bits whichever path reconstructs it (tested on
//! every SIMD backend). Lanes whose sample the brick does not reach — or
//! that hold no sample — add exact zeros, as the scalar path adds nothing.

use voxless_core::simd::{LANES, Lanes};

use super::recon::BrickGrid;

/// `1.5 · 2²³`: for |t| < 2²², `(t + ROUND) − ROUND` is `t` rounded to an
/// integer (the float spacing there is 1).
const ROUND: f32 = 12_582_912.0;

/// Eight samples' value-only sums (see [`super::recon::ValueSums`]), in
/// `f64`.
#[derive(Clone, Copy)]
pub(super) struct ValueLanes {
    pub sw: [f64; LANES],
    pub sv: [f64; LANES],
    pub sc: [f64; LANES],
}

impl ValueLanes {
    #[inline(always)]
    pub fn zero() -> Self {
        ValueLanes {
            sw: [0.0; LANES],
            sv: [0.0; LANES],
            sc: [0.0; LANES],
        }
    }
}

/// Adds brick `g`'s terms at the unit-space points `p` (x, y, z lanes) to
/// `acc`, for the lanes set in `live`.
#[inline(always)]
pub(super) fn brick_value_lanes<L: Lanes>(
    g: &BrickGrid,
    p: [L; 3],
    live: L,
    fields: (&[f32], Option<&[f32]>),
    acc: &mut ValueLanes,
) {
    let s = L::splat;
    let (zero, one) = (s(0.0), s(1.0));
    let mut active = live;
    let mut w = [zero; 3];
    let mut f = [zero; 3];
    let mut c = [[zero; 2]; 3];
    for a in 0..3 {
        let last = s(g.last_f[a]);
        // The cell coordinate, clamped to [-2, last + 2] (beyond it both
        // weights are zero; inside it the rounding trick is exact).
        let t = ((p[a] - s(g.lower[a])) * s(g.inv_w) - s(0.5))
            .max(s(-2.0))
            .min(last + s(2.0));
        let r = (t + s(ROUND)) - s(ROUND);
        let i0 = r - r.gt(t).select(one, zero);
        f[a] = t - i0;
        let in0 = i0.ge(zero) & i0.le(last);
        let in1 = i0.ge(s(-1.0)) & i0.lt(last);
        let (w0, w1) = (in0.select(one - f[a], zero), in1.select(f[a], zero));
        active = active & (w0.gt(zero) | w1.gt(zero));
        w[a] = w0 + w1;
        c[a] = [i0.max(zero).min(last), (i0 + one).max(zero).min(last)];
    }
    if !active.any() {
        return;
    }
    // Brick-local offsets of the eight cells, rows (ky, kz) = (0, 0),
    // (1, 0), (0, 1), (1, 1), each at x0 then x1; exact in f32 (a brick
    // has at most 32³ cells).
    let (sx, sxy) = (s(g.sx as f32), s(g.sxy as f32));
    let [[x0, x1], [y0, y1], [z0, z1]] = c;
    let rows = [
        z0 * sxy + y0 * sx,
        z0 * sxy + y1 * sx,
        z1 * sxy + y0 * sx,
        z1 * sxy + y1 * sx,
    ];
    let mut at = [zero; 8];
    for (k, row) in rows.into_iter().enumerate() {
        (at[2 * k], at[2 * k + 1]) = (row + x0, row + x1);
    }
    // The brick's weight and its lerp; masked lanes add exact zeros.
    let weight = active.select(w[0] * w[1] * w[2], zero);
    L::add_product_f64(&mut acc.sw, weight, one);
    let v = lerp::<L>(&fields.0[g.base..g.base + g.cells], &at, f);
    L::add_product_f64(&mut acc.sv, weight, active.select(v, zero));
    if let Some(color) = fields.1 {
        let v = lerp::<L>(&color[g.base..g.base + g.cells], &at, f);
        L::add_product_f64(&mut acc.sc, weight, active.select(v, zero));
    }
}

/// The trilinear lerp `a + f·(b − a)`, x then y then z, of the eight cells
/// at brick-local offsets `at` of the brick's values `v` (in range: the
/// cells are clamped into the brick).
#[inline(always)]
fn lerp<L: Lanes>(v: &[f32], at: &[L; 8], f: [L; 3]) -> L {
    let mut r = [L::splat(0.0); 4];
    for (k, r) in r.iter_mut().enumerate() {
        let (a, b) = (L::gather(v, at[2 * k]), L::gather(v, at[2 * k + 1]));
        *r = a + f[0] * (b - a);
    }
    let (p0, p1) = (r[0] + f[1] * (r[1] - r[0]), r[2] + f[1] * (r[3] - r[2]));
    p0 + f[2] * (p1 - p0)
}
