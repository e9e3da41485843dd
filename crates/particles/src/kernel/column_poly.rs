//! The SPH kernels' projected columns as piecewise polynomials, for the
//! splatter's lanes: a table read would need a gather per eight pixels,
//! which costs more than everything else a pixel needs (measured: more than
//! half of a projection's time on an AMD Zen 3, whose gathers are
//! microcoded); eight polynomials of degree seven are read with one
//! in-register permute per coefficient instead.
//!
//! **The function.** `T(t)`, the column table's value at table position
//! `t ∈ [0, L]` (`L` = [`COLUMN_TABLE`] − 1, `t = L·q_b²/Q²`, `Q` the
//! support factor; see [`super::Column`]), fitted to the kernel's column by
//! quadrature in f64 (not to the table).
//!
//! **Segments.** With `t' = t + 64`, segment `s` (0–7) is the octave
//! `t' ∈ [64·2ˢ, 128·2ˢ)`, read straight from the f32 exponent of `t'`
//! (`s = exponent − 133`), and the polynomial's variable is `x = m − 1.5`,
//! `m ∈ [1, 2)` the mantissa of `t'`: two bit operations, no division. The
//! octaves are narrow where the column is least smooth: at `t = 0` (terms
//! `u·ln u` in `u = q_b²` for kernels with odd powers of `q`), the first
//! segment is 64 table positions wide; they widen towards the support,
//! where every column is smooth except at the splines' kinks. The last
//! segment holds only `t ∈ [8128, 8192]`, where the columns are below 1e-7
//! of their peak: a straight line to 0 at `t = L − 1`, exactly 0 from `L`
//! to [`ZERO_UNTIL`] (tested).
//!
//! **Bound.** `|P(t) − F(t)| ≤ 1e-6 · F(0)` and `P(t) ≥ 0` (the fit dips
//! a hair below 0 near the support: clamped) for every kernel and every
//! `t` (measured 1.5e-7–7e-7, the largest for M5 at its kink; the linear
//! table it replaces on the lanes: 1.4e-7–3.9e-7), evaluated in f32
//! exactly as the lanes do (tested).
//!
//! **Evaluation.** Estrin's scheme, `((c₀x + c₁)x² + (c₂x + c₃))x⁴ +
//! ((c₄x + c₅)x² + (c₆x + c₇))`: three dependent multiply-add levels
//! instead of Horner's seven (measured on the splat: within the noise of
//! Horner on a Zen 3; kept for the shorter chain). Each `a·x + b` is one
//! fused multiply-add ([`Lanes::mul_add`], one rounding, the same bits on
//! every lane type and width): 6 % of a projection's time against a
//! separate multiply and add (Zen 3). The splatter scales the coefficients
//! by a particle's weight before the evaluation (eight products a particle
//! instead of one a pixel); the bound above then holds relative to the
//! scaled peak, plus one f32 rounding.
//!
//! **Sixteen lanes.** AVX-512's two-table permute reads a 32-entry table
//! from two registers in one instruction, so the sixteen-lane splats
//! ([`ColumnPoly::wide`]) take the octaves of `t' = t + 128`
//! ([`WIDE_OFFSET`]), quarter each at its mantissa's top two bits (the
//! segment is `(t' bits >> 21) & 31`, the variable `x = m'`, `m' ∈ [1,
//! 1.25)` the mantissa without those bits: one bit operation, no
//! subtraction) and hold a quartic on each quarter, evaluated by Horner's
//! scheme (four fused multiply-adds, [`ColumnPoly::at_wide`]): 2.3e-7–
//! 4.4e-7 of the peak over the six kernels (1.2e-7–2.5e-7 with `x`
//! centred, `m' − 1.125`, one subtraction more a lane group), against
//! 1.8e-7–6.9e-7 for the septics on octaves. The support ends in the
//! seventh octave, so the eighth's slots are zeros and a sum of two table
//! positions past the support (up to `2·ZERO_UNTIL`) needs no clamp: its
//! octave's slots are the seventh's sliver or zeros (tested up to `t' =
//! 2¹⁵`). The lanes never scale the coefficients: they multiply each value
//! by the particle's scale as they add it (rounded coefficients of an
//! uncentred variable cancel, and scaled ones moved the mass of particles
//! sharing a scale by ~2e-7, all one way). (Quintics on half-octaves,
//! one-table permutes: 2.0e-7–5.3e-7, one permute and one multiply-add
//! more a lane group, ×1.03 on the 2.1M projection; degree 6 on octaves
//! reached 1.9e-6, degree 4 on half-octaves 5e-6, cubics on quarter-octaves
//! 3.5e-6–5e-6 and on eighth-octaves of `t + 1024` 2.3e-5; Estrin's scheme
//! for the quartic, one product more: no faster.) On AVX2 a wide read
//! takes two permutes and a blend, so the eight lanes keep the octaves.
//!
//! **Fit.** Interpolation at the Chebyshev nodes of each segment (within a
//! small factor of the best polynomial), in Newton's form in f64, expanded
//! to coefficients in `x` and rounded to f32; the quartics' constant term
//! then moved by the mean of what is left over the segment (a
//! projection's mass within ~4e-8 over random positions).
//!
//! **Mass.** Over random sub-pixel positions the sixteen lanes' columns
//! sum to the kernel's mass within 1e-8–4e-8 (six kernels, supports ten
//! pixels wide; the exact columns sampled at the same pixels: 2e-10–
//! 1.5e-8).

use std::sync::OnceLock;

use voxless_core::simd::{LANES, Lanes, PortableLanes};

use super::Kernel;
use super::sph::COLUMN_TABLE;

/// Polynomial degree per segment.
pub const DEGREE: usize = 7;

/// Polynomial degree per quarter-octave on sixteen lanes.
pub const WIDE_DEGREE: usize = 4;

/// Added to the table position before its octave is taken.
pub const OFFSET: f32 = 64.0;

/// The table position up to which `P(t)` is exactly 0 past the last one
/// (`L`): the last segment's line is negative there and the evaluation
/// clamps it (tested for every kernel and scale), so the splatter clamps
/// `t` to this instead of masking lanes outside the support.
pub const ZERO_UNTIL: f32 = (COLUMN_TABLE - 1 + 32) as f32;

/// The biased f32 exponent of `OFFSET` (segment 0).
const FIRST_EXPONENT: u32 = 133;

/// The sixteen lanes' [`OFFSET`]: their octaves of `t + 128` reach the
/// support in seven (`t' < 8192 + 128`), so that the eighth octave's slots
/// are zeros and take every `t' ∈ [2¹⁴, 2¹⁵)` (see [`ColumnPoly::wide`]).
pub const WIDE_OFFSET: f32 = 128.0;

/// The biased f32 exponent of [`WIDE_OFFSET`].
const WIDE_FIRST_EXPONENT: u32 = 134;

/// One SPH kernel's column as eight polynomials (see the module docs).
#[derive(Clone, Debug)]
pub struct ColumnPoly {
    /// Coefficient `k` (highest degree first) of segment `s` at position
    /// `(133 + s) & 7`: the lanes' permute index is the exponent's low
    /// three bits.
    pub lanes8: [[f32; 8]; DEGREE + 1],
    /// The sixteen lanes' polynomials (see "Sixteen lanes" above):
    /// coefficient `k` (highest degree first) of quarter `h` of octave `s`
    /// at position `((134 + s) & 7)·4 + h`, the permute index being the
    /// low five bits of `(t + 128)`'s bits shifted right by 21 (octave 7,
    /// `t' ∈ [2¹⁴, 2¹⁵)`, all zeros).
    pub wide: [[f32; 32]; WIDE_DEGREE + 1],
}

impl ColumnPoly {
    /// The coefficients in lanes, one register a coefficient (for
    /// [`ColumnPoly::eval`]).
    #[inline(always)]
    pub fn lanes<L: Lanes>(&self) -> [L; DEGREE + 1] {
        std::array::from_fn(|k| L::from_array(self.lanes8[k]))
    }

    /// `P(t)` at the table positions `t` on eight lanes, `c` from
    /// [`ColumnPoly::lanes`]: the segment from the exponent of `t + 64`,
    /// the variable from its mantissa, Estrin's scheme on the permuted
    /// coefficients, never below 0 (a meaningless value for `t` outside
    /// `[0, L]`; callers mask).
    #[inline(always)]
    pub fn eval<L: Lanes>(c: &[L; DEGREE + 1], t: L) -> L {
        let tp = t + L::splat(OFFSET);
        let at = tp.shr23();
        let mantissa = L::from_bits([0x007f_ffff; LANES]);
        let one = L::from_bits([0x3f80_0000; LANES]);
        let x = ((tp & mantissa) | one) - L::splat(1.5);
        let x2 = x * x;
        // (No closure for the permutes: it would be compiled without the
        // AVX2 entry's target features.)
        let p = [
            c[0].permute(at),
            c[1].permute(at),
            c[2].permute(at),
            c[3].permute(at),
            c[4].permute(at),
            c[5].permute(at),
            c[6].permute(at),
            c[7].permute(at),
        ];
        let lo = p[4].mul_add(x, p[5]).mul_add(x2, p[6].mul_add(x, p[7]));
        let hi = p[0].mul_add(x, p[1]).mul_add(x2, p[2].mul_add(x, p[3]));
        // Near the support the fit dips a hair below 0, where a column
        // never goes (a negative density would read as a hole on a log
        // scale): clamped.
        hi.mul_add(x2 * x2, lo).max(L::splat(0.0))
    }

    /// `P(t)` in f32: [`ColumnPoly::eval`] on the portable lanes (the same
    /// bits as every lane type).
    pub fn at(&self, t: f32) -> f32 {
        Self::eval(&self.lanes::<PortableLanes>(), PortableLanes::splat(t)).to_array()[0]
    }

    /// `P(t)` in f32 as the sixteen lanes evaluate it (the quarter-octaves'
    /// quartics, see [`ColumnPoly::wide`]), `c` their coefficients.
    pub fn at_wide(c: &[[f32; 32]; WIDE_DEGREE + 1], t: f32) -> f32 {
        let tp = (t + WIDE_OFFSET).to_bits();
        let at = ((tp >> 21) & 31) as usize;
        let x = f32::from_bits((tp & 0x001f_ffff) | 0x3f80_0000);
        let p = c[1..].iter().fold(c[0][at], |p, c| p.mul_add(x, c[at]));
        p.max(0.0)
    }

    /// Fits `f(t)` over `t ∈ [0, L]`.
    fn fit(f: impl Fn(f64) -> f64) -> ColumnPoly {
        let last = (COLUMN_TABLE - 1) as f64;
        let mut lanes8 = [[0.0f32; 8]; DEGREE + 1];
        let mut wide = [[0.0f32; 32]; WIDE_DEGREE + 1];
        for s in 0..8u32 {
            let e = FIRST_EXPONENT + s;
            // The octave of t', `lo·m` for m in [1, 2); eight lanes: x = m − 1.5.
            let lo = OFFSET as f64 * (1u32 << s) as f64;
            let coef = segment(&f, (lo, OFFSET), 1.5, (1.0, 2.0), (DEGREE, interpolate));
            for (k, c) in coef.iter().enumerate() {
                lanes8[k][(e & 7) as usize] = *c as f32;
            }
        }
        // Sixteen lanes: the octaves of `t + WIDE_OFFSET` (seven reach the
        // support; the eighth's slots stay 0), each in quarters m in [1 +
        // h/4, 1.25 + h/4), x = m − h/4 in [1, 1.25).
        let offset = WIDE_OFFSET as f64;
        for s in 0..8u32 {
            let e = WIDE_FIRST_EXPONENT + s;
            let lo = offset * (1u32 << s) as f64;
            for h in 0..4u32 {
                let shift = 0.25 * h as f64;
                if lo * (1.0 + shift) >= last + offset {
                    // Never reached below the support: zeros.
                    continue;
                }
                let coef = segment(
                    &f,
                    (lo, WIDE_OFFSET),
                    shift,
                    (1.0 + shift, 1.25 + shift),
                    (WIDE_DEGREE, rounded_fit),
                );
                for (k, c) in coef.iter().enumerate() {
                    wide[k][((e & 7) * 4 + h) as usize] = *c as f32;
                }
            }
        }
        ColumnPoly { lanes8, wide }
    }
}

/// A fit of degree `degree` to `g` over `[a, b]`, as coefficients of
/// `x^degree … x^0` ([`interpolate`] or [`rounded_fit`]).
type Fit = fn(&dyn Fn(f64) -> f64, f64, f64, usize) -> Vec<f64>;

/// The polynomial of degree `degree` in `x = m − shift` for `f(t)` at
/// `t' = lo·m` (`t = t' − offset`), over the segment `m ∈ [m0, m1)` (the
/// part of it inside the table) by `fit`, highest degree first.
fn segment(
    f: impl Fn(f64) -> f64,
    (lo, offset): (f64, f32),
    shift: f64,
    (m0, m1): (f64, f64),
    (degree, fit): (usize, Fit),
) -> Vec<f64> {
    let last = (COLUMN_TABLE - 1) as f64;
    let offset = offset as f64;
    let t_of = |x: f64| (x + shift) * lo - offset;
    let (xa, xb) = (m0 - shift, (m1 * lo).min(last + offset) / lo - shift);
    if m1 * lo > last + offset {
        // The last sliver: a line from the column to 0 one table position
        // before L, so that rounded to f32 it is ≤ 0 from L on (the clamp
        // then gives exactly 0 there; the column is below 1e-7 of its peak
        // on the whole sliver).
        let (y0, x1) = (f(t_of(xa)), xb - 1.0 / lo);
        let slope = -y0 / (x1 - xa);
        let mut c = vec![0.0; degree + 1];
        c[degree - 1] = slope;
        c[degree] = y0 - slope * xa;
        c
    } else {
        fit(&|x| f(t_of(x)), xa, xb, degree)
    }
}

/// [`interpolate`] with coefficients that f32 holds exactly, the constant
/// term then moved by the mean of what is left of `g` over the segment
/// (for the quartics, whose variable is not centred, `x ∈ [1, 1.25)`:
/// their terms cancel, and rounding them moved whole segments one way, a
/// projection's mass by up to 1.6e-7 (quintic spline; 4e-8 with the
/// mean taken out, over random sub-pixel positions). The mean is uniform
/// in `x`, as a projection's area is in the table position (eight-point
/// Gauss–Legendre).
fn rounded_fit(g: &dyn Fn(f64) -> f64, a: f64, b: f64, degree: usize) -> Vec<f64> {
    const NODES: [(f64, f64); 4] = [
        (0.183_434_642_495_649_8, 0.362_683_783_378_362),
        (0.525_532_409_916_329, 0.313_706_645_877_887_3),
        (0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
        (0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
    ];
    let mut c: Vec<f64> = interpolate(g, a, b, degree)
        .into_iter()
        .map(|c| c as f32 as f64)
        .collect();
    let left = |x: f64| g(x) - c.iter().fold(0.0, |acc, c| acc * x + c);
    let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
    let mean = NODES
        .iter()
        .map(|&(x, w)| w * (left(mid - half * x) + left(mid + half * x)))
        .sum::<f64>()
        / 2.0;
    c[degree] = (c[degree] + mean) as f32 as f64;
    c
}

/// The polynomial of degree `degree` through `g` at the Chebyshev nodes
/// of `[a, b]`, as coefficients of `x^degree … x^0`.
fn interpolate(g: &dyn Fn(f64) -> f64, a: f64, b: f64, degree: usize) -> Vec<f64> {
    let n = degree + 1;
    let nodes: Vec<f64> = (0..n)
        .map(|k| {
            let c = ((2 * k + 1) as f64 * std::f64::consts::PI / (2 * n) as f64).cos();
            0.5 * (a + b) + 0.5 * (b - a) * c
        })
        .collect();
    // Newton's divided differences, in place.
    let mut d: Vec<f64> = nodes.iter().map(|&x| g(x)).collect();
    for j in 1..n {
        for i in (j..n).rev() {
            d[i] = (d[i] - d[i - 1]) / (nodes[i] - nodes[i - j]);
        }
    }
    // Expand d[0] + d[1](x − x0) + d[2](x − x0)(x − x1) + … by Horner's
    // scheme on coefficient vectors (lowest degree first while building).
    let mut poly = vec![0.0f64; n];
    poly[0] = d[n - 1];
    for k in (0..n - 1).rev() {
        // poly ← poly·(x − x_k) + d[k]
        for i in (1..n).rev() {
            poly[i] = poly[i - 1] - nodes[k] * poly[i];
        }
        poly[0] = -nodes[k] * poly[0] + d[k];
    }
    poly.reverse();
    poly
}

impl Kernel {
    /// The kernel's column as piecewise polynomials in the table position
    /// (see [`column_poly`](self)); `None` for the Gaussians. Built once per
    /// kernel on first use.
    pub fn column_poly(&self) -> Option<&'static ColumnPoly> {
        static POLYS: [OnceLock<ColumnPoly>; 6] = [const { OnceLock::new() }; 6];
        if !self.is_sph() {
            return None;
        }
        let slot = self.sph().map_or(0, |s| 1 + s as usize);
        let q = self.support_factor() as f64;
        let last = (COLUMN_TABLE - 1) as f64;
        Some(POLYS[slot].get_or_init(|| {
            ColumnPoly::fit(|t| column_by_quadrature(*self, (q * q * t.max(0.0) / last).sqrt()))
        }))
    }
}

/// An SPH kernel's `F(q_b)` by quadrature in f64 (the function the table
/// and the polynomials hold; 0 for the Gaussians).
pub(crate) fn column_by_quadrature(kernel: Kernel, qb: f64) -> f64 {
    match kernel.sph() {
        _ if kernel == Kernel::CubicSpline => super::projected_m4_quadrature(qb),
        Some(s) => s.projected_quadrature(qb),
        None => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The polynomials against the columns by quadrature, in f32 as the
    /// lanes evaluate them: within 1e-6 of the peak everywhere, on a grid
    /// through every segment and geometrically towards `t = 0`.
    #[test]
    fn polynomials_hold_the_columns_to_1e_6_of_the_peak() {
        let last = (COLUMN_TABLE - 1) as f64;
        let sph = crate::tests::KERNELS.into_iter().filter(|k| k.is_sph());
        assert_eq!(sph.clone().count(), 6);
        for kernel in sph {
            let poly = kernel.column_poly().unwrap();
            let q = kernel.support_factor() as f64;
            let exact = |t: f64| column_by_quadrature(kernel, (q * q * t / last).sqrt());
            let peak = exact(0.0);
            let ts = (0..=6000)
                .map(|i| last * i as f64 / 6000.0)
                .chain((0..200).map(|i| 64.0 * 0.9f64.powi(i)));
            // The eight lanes' octaves and the sixteen lanes' quarter-octaves.
            let (mut worst, mut worst_wide): (f64, f64) = (0.0, 0.0);
            for t in ts {
                let t = t as f32;
                let e = exact(t as f64);
                for (got, worst) in [
                    (poly.at(t), &mut worst),
                    (ColumnPoly::at_wide(&poly.wide, t), &mut worst_wide),
                ] {
                    assert!(got >= 0.0, "{kernel:?}: {got} at {t}");
                    *worst = worst.max((got as f64 - e).abs() / peak);
                }
            }
            assert!(worst < 1e-6, "{kernel:?}: {worst:e} of the peak");
            assert!(
                worst_wide < 1e-6,
                "{kernel:?}, sixteen lanes: {worst_wide:e}"
            );
            assert!(poly.at(last as f32).abs() < 1e-7 * peak as f32);
            assert!(ColumnPoly::at_wide(&poly.wide, last as f32).abs() < 1e-7 * peak as f32);
        }
        assert!(Kernel::Gaussian3.column_poly().is_none());
    }

    /// Past the support, up to `ZERO_UNTIL`, the eight lanes' evaluation
    /// gives exactly 0 (what the splatter's clamp of `t` relies on),
    /// whatever the scale the coefficients are multiplied by; the sixteen
    /// lanes' past the support wherever their sums can reach.
    #[test]
    fn the_column_is_exactly_zero_past_the_support() {
        let last = (COLUMN_TABLE - 1) as f32;
        for kernel in crate::tests::KERNELS.into_iter().filter(|k| k.is_sph()) {
            let poly = kernel.column_poly().unwrap();
            for scale in [1.0f32, 3.7e-9, 0.31, 2.9e7, f32::MIN_POSITIVE] {
                let c = poly
                    .lanes::<PortableLanes>()
                    .map(|c| c * PortableLanes::splat(scale));
                let mut t = last;
                while t <= ZERO_UNTIL {
                    let at = |t: f32| ColumnPoly::eval(&c, PortableLanes::splat(t)).to_array()[0];
                    assert_eq!(at(t).to_bits(), 0, "{kernel:?} × {scale}: {} at {t}", at(t));
                    t = if t < last + 1.0 {
                        t.next_up()
                    } else {
                        t + 0.25
                    };
                }
            }
            // The sixteen lanes' coefficients are never scaled (the lanes
            // multiply their values), and their sums of two table positions
            // reach `2·ZERO_UNTIL` unclamped: every t' from the support up
            // to 2¹⁵ (the eighth octave's zeros take [2¹⁴, 2¹⁵)).
            let mut t = last;
            while t + WIDE_OFFSET < 32768.0 {
                let on_16 = ColumnPoly::at_wide(&poly.wide, t);
                assert_eq!(on_16.to_bits(), 0, "{kernel:?}, 16: {on_16} at {t}");
                t = if t < last + 1.0 {
                    t.next_up()
                } else {
                    t + 0.25
                };
            }
        }
    }

    /// Interpolation reproduces a polynomial of its degree.
    #[test]
    fn interpolation_is_exact_for_polynomials() {
        let want = [0.5, -1.0, 2.0, 0.25, -3.0, 1.5, 0.75, -2.0];
        for degree in [DEGREE, WIDE_DEGREE] {
            let want = &want[DEGREE - degree..];
            let p = |x: f64| want.iter().fold(0.0, |acc, c| acc * x + c);
            let got = interpolate(&p, -0.5, 0.5, degree);
            assert_eq!(got.len(), degree + 1);
            for (g, w) in got.iter().zip(want) {
                assert!((g - w).abs() < 1e-9, "{got:?}");
            }
        }
    }
}
