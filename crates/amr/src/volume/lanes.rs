//! The value-only basis reconstruction on eight samples at once.
//!
//! Two users: a packet pass's run holds samples of one region (of one ray
//! or several), every one adding the same bricks' terms; a step of eight
//! rays in lanes ([`AmrVolume::values_lanes`]) holds one sample per ray,
//! each in its own region — their brick lists are merged, and each brick
//! of the union goes through with the lanes whose list holds it (half the
//! steps of the AMRClaw frame have one list for all eight). Eight samples
//! go through a brick
//! together: the per-axis tent stencils (a clamp, a floor, the weights, two
//! clamped cells) in lanes, the eight cells' values gathered (one
//! instruction each on AVX2), the trilinear lerp in lanes, and the brick's
//! weight and weighted lerp added to `f64` sums. Each lane does exactly the
//! operations of [`super::recon::brick_value_sums`] in its order, so a
//! sample gets the same bits whichever path reconstructs it (tested on
//! every SIMD backend). Lanes whose sample the brick does not reach — or
//! that hold no sample — add exact zeros, as the scalar path adds nothing.

use voxless_core::Vec3;
use voxless_core::simd::{LANES, Lanes};

use super::recon::BrickGrid;
use super::{AmrVolume, Reconstruction};

impl AmrVolume {
    /// Whether [`AmrVolume::values_lanes`] serves: basis reconstruction of
    /// plain values (no colour field).
    pub(crate) fn offers_lanes(&self) -> bool {
        self.settings.color_field.is_none() && self.settings.reconstruction == Reconstruction::Basis
    }

    /// [`voxless_core::Volume::sample_values_lanes`]: eight points, each in
    /// the region its hint names (a lane with no region is located point
    /// by point). Each lane adds its own region's bricks' terms in its
    /// list's order with [`brick_value_lanes`], so it gets the bits of
    /// [`AmrVolume::reconstruct`].
    #[inline(always)]
    pub(crate) fn values_lanes<L: Lanes>(&self, hints: &[u32; LANES], p: [L; 3], live: u32) -> L {
        let s = L::splat;
        let inv = 1.0 / self.h;
        let o = self.origin;
        let pu = [
            (p[0] - s(o.x)) * s(inv),
            (p[1] - s(o.y)) * s(inv),
            (p[2] - s(o.z)) * s(inv),
        ];
        let fields = self.basis_fields(self.settings.field);
        let mut acc = ValueLanes::zero();
        // Every live lane's brick list (sorted by brick), merged: each brick
        // of the union goes through the kernel once, for the lanes whose
        // list holds it, so every lane meets its own bricks in its list's
        // order.
        let mut located = 0u32;
        let mut lists: [&[u32]; LANES] = [&[]; LANES];
        let mut same = None;
        // Half the steps of the AMRClaw frame have every lane in one region:
        // one lookup then.
        let first = hints[(live.trailing_zeros() as usize).min(LANES - 1)];
        let one_region = (0..LANES).all(|k| live >> k & 1 == 0 || hints[k] == first);
        for (k, list) in lists.iter_mut().enumerate() {
            if live >> k & 1 == 0 || (one_region && k > live.trailing_zeros() as usize) {
                continue;
            }
            match self.ix().region_lists.get(hints[k] as usize) {
                Some(&[a, b, g]) => {
                    *list = &self.ix().regions.brick_ids[a as usize..b as usize];
                    same = match same {
                        None => Some(Some(g)),
                        Some(s) => Some(s.filter(|&s| s == g)),
                    };
                }
                // No region named: found point by point below.
                _ => located |= 1 << k,
            }
        }
        if one_region && located != 0 {
            located = live;
        }
        if let Some(Some(_)) = same {
            // One brick list for every lane (the common case): its bricks
            // in order, all lanes at once.
            let mut bits = [0u32; LANES];
            for (k, bit) in bits.iter_mut().enumerate() {
                if (live & !located) >> k & 1 != 0 {
                    *bit = u32::MAX;
                }
            }
            let mask = L::from_bits(bits);
            let first = (live & !located).trailing_zeros() as usize;
            for &b in lists[first] {
                brick_value_lanes(&self.bx().grids[b as usize], pu, mask, fields, &mut acc);
            }
        } else {
            loop {
                let b = lists.iter().filter_map(|l| l.first()).min().copied();
                let Some(b) = b else {
                    break;
                };
                let mut bits = [0u32; LANES];
                for (list, bit) in lists.iter_mut().zip(&mut bits) {
                    if list.first() == Some(&b) {
                        *bit = u32::MAX;
                        *list = &list[1..];
                    }
                }
                let mask = L::from_bits(bits);
                brick_value_lanes(&self.bx().grids[b as usize], pu, mask, fields, &mut acc);
            }
        }
        // `B = Σ Ĥ v / Σ Ĥ`, NaN where no tent reaches (the lanes without a
        // sample have zero sums).
        let v = L::quotient_f64(&acc.sv, &acc.sw);
        if located == 0 {
            return v;
        }
        let mut out = v.to_array();
        let [x, y, z] = [p[0].to_array(), p[1].to_array(), p[2].to_array()];
        for (k, v) in out.iter_mut().enumerate() {
            if located >> k & 1 != 0 {
                let at = Vec3::new(x[k], y[k], z[k]);
                *v = self
                    .locate(at)
                    .and_then(|r| self.reconstruct(at, r, self.settings.field, false))
                    .map_or(f32::NAN, |x| x.value);
            }
        }
        L::from_array(out)
    }
}

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
