//! The SPH kernels beyond the cubic spline: the quartic (M5) and quintic
//! (M6) B-splines and the Wendland C2, C4 and C6 functions (3D).
//!
//! Every kernel here is `W(d, h) = σ/h³ · w(d/h)` with `h` the particle's
//! radius parameter, the **smoothing length in PHANTOM's convention** (Price
//! 2012, "Smoothed particle hydrodynamics and magnetohydrodynamics", §2.3;
//! Price et al. 2018, the PHANTOM paper, §2.1.4–2.1.5), and `σ` the 3D
//! normalisation, so `∫ W dV = 1` and with masses as weights `Σ m W` is the
//! SPH density:
//!
//! | kernel | `w(q)` | `σ` | support |
//! |---|---|---|---|
//! | `quartic-spline` (M5) | `(5/2−q)₊⁴ − 5(3/2−q)₊⁴ + 10(1/2−q)₊⁴` | `1/(20π)` | `2.5h` |
//! | `quintic-spline` (M6) | `(3−q)₊⁵ − 6(2−q)₊⁵ + 15(1−q)₊⁵` | `1/(120π)` | `3h` |
//! | `wendland-c2` | `(1−q/2)₊⁴ (1 + 2q)` | `21/(16π)` | `2h` |
//! | `wendland-c4` | `(1−q/2)₊⁶ (1 + 3q + 35q²/12)` | `495/(256π)` | `2h` |
//! | `wendland-c6` | `(1−q/2)₊⁸ (1 + 4q + 25q²/4 + 4q³)` | `1365/(512π)` | `2h` |
//!
//! with `(x)₊ = max(x, 0)`. The Wendland rows are Wendland's functions of
//! `x = d/H` (Dehnen & Aly 2012, table 1: C2 `21/(2πH³)(1−x)⁴(1+4x)`, C4
//! `495/(32πH³)(1−x)⁶(1+6x+35x²/3)`, C6 `1365/(64πH³)(1−x)⁸(1+8x+25x²+32x³)`)
//! with the support `H = 2h`, as PHANTOM defines them.
//!
//! Converting other codes' smoothing lengths to voxless's `h` (radii):
//!
//! - PHANTOM: `h` as written (its `radkern` is the support factor above).
//! - Gadget-2/Gadget-4 and GIZMO write the support radius `H` as
//!   `SmoothingLength`: `h = H/2` for the cubic spline and the Wendland
//!   kernels, `H/2.5` for M5, `H/3` for M6.
//! - SWIFT writes `h_S` with the support `H = γ h_S` (`kernel_gamma`, from
//!   Dehnen & Aly 2012's `H/σ` with `h_S` twice the kernel's standard
//!   deviation): γ = 1.825742 (cubic), 2.018932 (quartic), 2.195775
//!   (quintic), 1.936492 (Wendland C2), 2.207940 (C4), 2.449490 (C6); so
//!   `h = γ h_S / (support factor)`, e.g. `0.912871 h_S` for the cubic
//!   spline and `0.731925 h_S` for the quintic.
//!
//! The projected column `∫ W dz` through the particle at impact parameter
//! `b` is `σ/h² · F(b/h)` with `F(q_b) = ∫ w(√(q_b² + v²)) dv`, tabulated
//! once per kernel over `q_b²` by Simpson's rule split at the kinks of `w`
//! (see [`Sph::projected`]).

use std::sync::OnceLock;

use voxless_core::Vec3;
use voxless_core::simd::Lanes;

use super::Family;

/// A shape `w(q)` of the table above, monomorphised in the hot loops.
pub trait Shape: Copy + Send + Sync + 'static {
    /// Support radius over `h`.
    const SUPPORT: f64;
    /// The 3D normalisation `σ`.
    const SIGMA: f64;
    /// `q` where a derivative of `w` jumps (quadrature splits there).
    const KINKS: &'static [f64];
    /// `w(q)` in f64, 0 beyond the support.
    fn w(q: f64) -> f64;
    /// `w'(q)/q` in f64; its limit `w''(0)` at `q = 0`.
    fn dw_over_q(q: f64) -> f64;
    /// `w(q)` on eight lanes in f32.
    fn w_simd<L: Lanes>(q: L) -> L;
    /// `w'(q)/q` on eight lanes in f32.
    fn dw_over_q_simd<L: Lanes>(q: L) -> L;
}

/// `(k − q)₊` in f64.
#[inline(always)]
fn tp(k: f64, q: f64) -> f64 {
    (k - q).max(0.0)
}

/// `(k − q)₊` on eight lanes.
#[inline(always)]
fn tl<L: Lanes>(k: f32, q: L) -> L {
    (L::splat(k) - q).max(L::splat(0.0))
}

/// The spline's `w'(q)/q` from `w'(q)` on lanes: at `q = 0` the quotient is
/// 0/0, so that lane takes the limit `w''(0)` (the gradient there is 0 either
/// way, `∇φ = g·d` with `d = 0`, but `g` stays finite).
#[inline(always)]
fn over_q<L: Lanes>(dw: L, q: L, w2_at_0: f32) -> L {
    q.gt(L::splat(0.0))
        .select(dw / q.max(L::splat(f32::MIN_POSITIVE)), L::splat(w2_at_0))
}

/// The quartic B-spline M5 (support 2.5h).
#[derive(Clone, Copy)]
pub struct M5;
/// The quintic B-spline M6 (support 3h).
#[derive(Clone, Copy)]
pub struct M6;
/// Wendland C2 with support 2h.
#[derive(Clone, Copy)]
pub struct C2;
/// Wendland C4 with support 2h.
#[derive(Clone, Copy)]
pub struct C4;
/// Wendland C6 with support 2h.
#[derive(Clone, Copy)]
pub struct C6;

impl Shape for M5 {
    const SUPPORT: f64 = 2.5;
    const SIGMA: f64 = 1.0 / (20.0 * std::f64::consts::PI);
    const KINKS: &'static [f64] = &[0.5, 1.5];
    #[inline(always)]
    fn w(q: f64) -> f64 {
        tp(2.5, q).powi(4) - 5.0 * tp(1.5, q).powi(4) + 10.0 * tp(0.5, q).powi(4)
    }
    #[inline(always)]
    fn dw_over_q(q: f64) -> f64 {
        if q > 0.0 {
            let c = |k: f64| tp(k, q).powi(3);
            (-4.0 * c(2.5) + 20.0 * c(1.5) - 40.0 * c(0.5)) / q
        } else {
            // w''(0) = 12·2.5² − 60·1.5² + 120·0.5².
            -30.0
        }
    }
    #[inline(always)]
    fn w_simd<L: Lanes>(q: L) -> L {
        let s = L::splat;
        let p4 = |t: L| {
            let t2 = t * t;
            t2 * t2
        };
        p4(tl(2.5, q)) - s(5.0) * p4(tl(1.5, q)) + s(10.0) * p4(tl(0.5, q))
    }
    #[inline(always)]
    fn dw_over_q_simd<L: Lanes>(q: L) -> L {
        let s = L::splat;
        let p3 = |t: L| t * t * t;
        let dw = s(-4.0) * p3(tl(2.5, q)) + s(20.0) * p3(tl(1.5, q)) - s(40.0) * p3(tl(0.5, q));
        over_q(dw, q, -30.0)
    }
}

impl Shape for M6 {
    const SUPPORT: f64 = 3.0;
    const SIGMA: f64 = 1.0 / (120.0 * std::f64::consts::PI);
    const KINKS: &'static [f64] = &[1.0, 2.0];
    #[inline(always)]
    fn w(q: f64) -> f64 {
        tp(3.0, q).powi(5) - 6.0 * tp(2.0, q).powi(5) + 15.0 * tp(1.0, q).powi(5)
    }
    #[inline(always)]
    fn dw_over_q(q: f64) -> f64 {
        if q > 0.0 {
            let c = |k: f64| tp(k, q).powi(4);
            (-5.0 * c(3.0) + 30.0 * c(2.0) - 75.0 * c(1.0)) / q
        } else {
            // w''(0) = 20·3³ − 120·2³ + 300·1³.
            -120.0
        }
    }
    #[inline(always)]
    fn w_simd<L: Lanes>(q: L) -> L {
        let s = L::splat;
        let p5 = |t: L| {
            let t2 = t * t;
            t2 * t2 * t
        };
        p5(tl(3.0, q)) - s(6.0) * p5(tl(2.0, q)) + s(15.0) * p5(tl(1.0, q))
    }
    #[inline(always)]
    fn dw_over_q_simd<L: Lanes>(q: L) -> L {
        let s = L::splat;
        let p4 = |t: L| {
            let t2 = t * t;
            t2 * t2
        };
        let dw = s(-5.0) * p4(tl(3.0, q)) + s(30.0) * p4(tl(2.0, q)) - s(75.0) * p4(tl(1.0, q));
        over_q(dw, q, -120.0)
    }
}

// The Wendland functions' w'(q) is q times a polynomial (they are smooth at
// the centre), so w'(q)/q is written out: exact at q = 0, no division.

impl Shape for C2 {
    const SUPPORT: f64 = 2.0;
    const SIGMA: f64 = 21.0 / (16.0 * std::f64::consts::PI);
    const KINKS: &'static [f64] = &[];
    #[inline(always)]
    fn w(q: f64) -> f64 {
        tp(1.0, 0.5 * q).powi(4) * (1.0 + 2.0 * q)
    }
    #[inline(always)]
    fn dw_over_q(q: f64) -> f64 {
        -5.0 * tp(1.0, 0.5 * q).powi(3)
    }
    #[inline(always)]
    fn w_simd<L: Lanes>(q: L) -> L {
        let s = L::splat;
        let t = tl(1.0, s(0.5) * q);
        let t2 = t * t;
        t2 * t2 * (s(1.0) + s(2.0) * q)
    }
    #[inline(always)]
    fn dw_over_q_simd<L: Lanes>(q: L) -> L {
        let s = L::splat;
        let t = tl(1.0, s(0.5) * q);
        s(-5.0) * t * t * t
    }
}

impl Shape for C4 {
    const SUPPORT: f64 = 2.0;
    const SIGMA: f64 = 495.0 / (256.0 * std::f64::consts::PI);
    const KINKS: &'static [f64] = &[];
    #[inline(always)]
    fn w(q: f64) -> f64 {
        tp(1.0, 0.5 * q).powi(6) * (1.0 + q * (3.0 + q * (35.0 / 12.0)))
    }
    #[inline(always)]
    fn dw_over_q(q: f64) -> f64 {
        -(14.0 / 3.0) * tp(1.0, 0.5 * q).powi(5) * (1.0 + 2.5 * q)
    }
    #[inline(always)]
    fn w_simd<L: Lanes>(q: L) -> L {
        let s = L::splat;
        let t = tl(1.0, s(0.5) * q);
        let t2 = t * t;
        t2 * t2 * t2 * (s(1.0) + q * (s(3.0) + q * s(35.0 / 12.0)))
    }
    #[inline(always)]
    fn dw_over_q_simd<L: Lanes>(q: L) -> L {
        let s = L::splat;
        let t = tl(1.0, s(0.5) * q);
        let t2 = t * t;
        s(-14.0 / 3.0) * t2 * t2 * t * (s(1.0) + s(2.5) * q)
    }
}

impl Shape for C6 {
    const SUPPORT: f64 = 2.0;
    const SIGMA: f64 = 1365.0 / (512.0 * std::f64::consts::PI);
    const KINKS: &'static [f64] = &[];
    #[inline(always)]
    fn w(q: f64) -> f64 {
        tp(1.0, 0.5 * q).powi(8) * (1.0 + q * (4.0 + q * (6.25 + q * 4.0)))
    }
    #[inline(always)]
    fn dw_over_q(q: f64) -> f64 {
        -5.5 * tp(1.0, 0.5 * q).powi(7) * (1.0 + q * (3.5 + q * 4.0))
    }
    #[inline(always)]
    fn w_simd<L: Lanes>(q: L) -> L {
        let s = L::splat;
        let t = tl(1.0, s(0.5) * q);
        let t2 = t * t;
        let t4 = t2 * t2;
        t4 * t4 * (s(1.0) + q * (s(4.0) + q * (s(6.25) + q * s(4.0))))
    }
    #[inline(always)]
    fn dw_over_q_simd<L: Lanes>(q: L) -> L {
        let s = L::splat;
        let t = tl(1.0, s(0.5) * q);
        let t2 = t * t;
        s(-5.5) * t2 * t2 * t2 * t * (s(1.0) + q * (s(3.5) + q * s(4.0)))
    }
}

/// The evaluation family of shape `S`: packed `(1/h, σ·w/h³)`, so
/// `φ = amp·w(|d|/h)` and `∇φ = amp·w'(q)/(q h²)·d`.
#[derive(Clone, Copy)]
pub struct SphFamily<S>(std::marker::PhantomData<S>);

impl<S: Shape> Family for SphFamily<S> {
    #[inline(always)]
    fn value(d: Vec3, _: f32, inv_h: f32, amp: f32) -> f32 {
        // q in f64, as the cubic spline's: the support-edge factors cancel.
        let (_, q) = super::cubic_q(d, inv_h);
        (amp as f64 * S::w(q)) as f32
    }
    #[inline(always)]
    fn value_and_gradient_factor(d: Vec3, _: f32, inv_h: f32, amp: f32) -> (f32, f32) {
        let (_, q) = super::cubic_q(d, inv_h);
        let (amp, ih) = (amp as f64, inv_h as f64);
        let v = amp * S::w(q);
        let g = amp * ih * ih * S::dw_over_q(q);
        (v as f32, g as f32)
    }
    #[inline(always)]
    fn value_simd<L: Lanes>(d2: L, inv_h: f32, amp: f32) -> L {
        let q = d2.sqrt() * L::splat(inv_h);
        L::splat(amp) * S::w_simd(q)
    }
    #[inline(always)]
    fn value_and_gradient_factor_simd<L: Lanes>(d2: L, inv_h: f32, amp: f32) -> (L, L) {
        let s = L::splat;
        let q = d2.sqrt() * s(inv_h);
        let v = s(amp) * S::w_simd(q);
        let g = s(amp * inv_h * inv_h) * S::dw_over_q_simd(q);
        (v, g)
    }
}

/// The kernels of this module by value (see [`super::Kernel::sph`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sph {
    M5,
    M6,
    C2,
    C4,
    C6,
}

/// `$body` with `$S` the shape type of `$sph`.
macro_rules! with_shape {
    ($sph:expr, $S:ident => $body:expr) => {
        match $sph {
            Sph::M5 => {
                type $S = M5;
                $body
            }
            Sph::M6 => {
                type $S = M6;
                $body
            }
            Sph::C2 => {
                type $S = C2;
                $body
            }
            Sph::C4 => {
                type $S = C4;
                $body
            }
            Sph::C6 => {
                type $S = C6;
                $body
            }
        }
    };
}

/// Entries of each projected-column table over `q_b² ∈ [0, SUPPORT²]`.
pub const COLUMN_TABLE: usize = 8193;

/// Simpson intervals per smooth piece of a column's integrand.
const COLUMN_STEPS: usize = 200;

impl Sph {
    /// Support radius over `h`.
    pub fn support(self) -> f64 {
        with_shape!(self, S => S::SUPPORT)
    }

    /// The 3D normalisation `σ`.
    pub fn sigma(self) -> f64 {
        with_shape!(self, S => S::SIGMA)
    }

    /// `w(q)`.
    pub fn w(self, q: f64) -> f64 {
        with_shape!(self, S => S::w(q))
    }

    /// `F(q_b) = ∫ w(√(q_b² + v²)) dv` over all `v`, by Simpson's rule on
    /// each piece between kinks (where `w` is smooth, so the rule converges
    /// at its full order).
    pub fn projected_quadrature(self, qb: f64) -> f64 {
        let (support, kinks) = with_shape!(self, S => (S::SUPPORT, S::KINKS));
        let qb2 = qb * qb;
        let vmax = (support * support - qb2).max(0.0).sqrt();
        // Chord ends of the kink spheres the line crosses, then the support.
        let mut ends: Vec<f64> = kinks
            .iter()
            .filter(|&&k| k > qb)
            .map(|&k| (k * k - qb2).sqrt())
            .collect();
        ends.push(vmax);
        let f = |v: f64| self.w((qb2 + v * v).sqrt());
        let mut start = 0.0;
        let mut sum = 0.0;
        for end in ends {
            if end > start {
                sum += voxless_core::simpson(f, start, end, COLUMN_STEPS);
            }
            start = end;
        }
        // Symmetric in v.
        2.0 * sum
    }

    /// [`Sph::projected_quadrature`] tabulated over `q_b²` (built once per
    /// kernel on first use).
    pub fn column_table(self) -> &'static [f32; COLUMN_TABLE] {
        static TABLES: [OnceLock<Box<[f32; COLUMN_TABLE]>>; 5] = [const { OnceLock::new() }; 5];
        let support = self.support();
        TABLES[self as usize].get_or_init(|| {
            // On every core (8,193 quadratures took ~4 ms on one, at the
            // start of every projection), on threads of its own: a rayon
            // worker waiting for its own tasks could take up another task
            // that asks for this table, and wait on itself.
            let mut table = Box::new([0.0f32; COLUMN_TABLE]);
            let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
            let per = COLUMN_TABLE.div_ceil(threads);
            std::thread::scope(|scope| {
                for (k, part) in table.chunks_mut(per).enumerate() {
                    scope.spawn(move || {
                        for (j, v) in part.iter_mut().enumerate() {
                            let i = k * per + j;
                            let q2 = support * support * i as f64 / (COLUMN_TABLE - 1) as f64;
                            *v = self.projected_quadrature(q2.sqrt()) as f32;
                        }
                    });
                }
            });
            table
        })
    }

    /// `F(q_b)` at `q_b² = q2` from the table (linear in `q_b²`; 0 beyond
    /// the support).
    pub fn projected(self, q2: f64) -> f64 {
        let support = self.support();
        let last = (COLUMN_TABLE - 1) as f64;
        let x = q2 * (last / (support * support));
        if !(x < last) {
            return 0.0;
        }
        let table = self.column_table();
        let i = (x.max(0.0) as usize).min(COLUMN_TABLE - 2);
        let s = (x - i as f64) as f32;
        (table[i] * (1.0 - s) + table[i + 1] * s) as f64
    }
}
