//! Eight f32 lanes behind one trait, and the backend chosen by value.
//!
//! **Model.** SIMD kernels are written once, generic over [`Lanes`] (eight
//! f32 lanes with the arithmetic, comparisons, masks and the `exp` they
//! need), and compiled once per lane type: [`PortableLanes`] (`wide`'s
//! `f32x8`, SSE2 on x86-64, NEON elsewhere) and, on x86-64, an AVX2 type.
//! Which one runs is a value, [`Simd`], passed down by the caller — never a
//! process-wide flag — and [`dispatch`] turns it into the instantiation.
//!
//! **Invariants.**
//! - Every operation is one IEEE-rounded step (no approximate
//!   reciprocals; [`Lanes::mul_add`] is fused — one rounding — on every
//!   backend, and no other operation is), and the composite ones ([`Lanes::exp`],
//!   [`Lanes::abs`], [`Lanes::first`]) are written once, in terms of the
//!   others. So on x86-64 the portable and the AVX2 types give the same
//!   bits for the same operations in the same order (tested below,
//!   operation by operation, edge cases included).
//! - Masks are lanes with all bits set (true) or clear (false), as the
//!   comparisons make them; [`Lanes::select`] and [`Lanes::bitmask`] are
//!   only specified for such masks.
//! - `min`/`max` follow x86's `minps`/`maxps`: `a.min(b)` is `a < b ? a :
//!   b`, so a NaN in either lane gives `b` (other targets: `wide`'s fast
//!   min/max, NaN handling unspecified). Comparisons are ordered: false on
//!   NaN.
//!
//! **Safety.** AVX2 code is only entered after the run-time check: the AVX2
//! lane type is private to this module, values of it are only made inside
//! [`dispatch`]'s AVX2 branch — a `#[target_feature(enable = "avx2,fma")]`
//! entry function reached only when [`Simd::resolve`] found both on this
//! CPU — so its safe methods can use the intrinsics. Its methods are
//! `#[inline(always)]`: inlined into the AVX2 entry, they compile to single
//! instructions; kernels should avoid closures in their hot loops for the
//! same reason (a closure body is a function of its own, without the entry's
//! target features).

use std::fmt::Debug;
use std::ops::{Add, BitAnd, BitOr, Div, Mul, Sub};

/// Lanes per [`Lanes`] value.
pub const LANES: usize = 8;

/// Half of [`LANES`]: [`Lanes::add_f64_halves`] adds each half to its own
/// four f64s.
pub const HALF_LANES: usize = LANES / 2;

/// Which SIMD backend a kernel runs on.
///
/// `Auto` picks the best one the CPU has; `Avx2` on a CPU (or target)
/// without AVX2 is clamped to `Portable` by [`Simd::resolve`] — a documented
/// clamp, not an error, so a setting read from a file works everywhere.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Simd {
    /// AVX2 where the CPU has it, else portable.
    #[default]
    Auto,
    /// `wide`'s portable eight-lane type (SSE2 on x86-64).
    Portable,
    /// AVX2 with FMA (x86-64 CPUs that have AVX2: all of them have FMA).
    Avx2,
}

impl Simd {
    /// Every value, for tests and benchmarks that compare backends.
    pub const ALL: [Simd; 3] = [Simd::Auto, Simd::Portable, Simd::Avx2];

    /// Whether this backend runs as itself here (`Auto` and `Portable`
    /// always do; `Avx2` only on x86-64 CPUs with AVX2).
    pub fn available(self) -> bool {
        match self {
            Simd::Auto | Simd::Portable => true,
            Simd::Avx2 => avx2_detected(),
        }
    }

    /// The backend that actually runs: `Auto` → `Avx2` where the CPU has
    /// it, else `Portable`; `Avx2` without AVX2 → `Portable` (clamp).
    /// Never returns `Auto`.
    pub fn resolve(self) -> Simd {
        match self {
            Simd::Portable => Simd::Portable,
            Simd::Auto | Simd::Avx2 if avx2_detected() => Simd::Avx2,
            Simd::Auto | Simd::Avx2 => Simd::Portable,
        }
    }

    /// Lower-case name, for logs and benchmark tables.
    pub fn name(self) -> &'static str {
        match self {
            Simd::Auto => "auto",
            Simd::Portable => "portable",
            Simd::Avx2 => "avx2",
        }
    }
}

fn avx2_detected() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        // Every AVX2 CPU has FMA as well; checked, since the AVX2 entry uses it.
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Eight f32 lanes. Masks are `Self` values whose lanes are all ones or
/// all zeros (see the module docs for the exact semantics every backend
/// shares).
pub trait Lanes:
    Copy
    + Send
    + Sync
    + Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + BitAnd<Output = Self>
    + BitOr<Output = Self>
{
    /// The backend this type implements (`Portable` or `Avx2`).
    const BACKEND: Simd;

    /// `x` in every lane.
    fn splat(x: f32) -> Self;
    fn from_array(a: [f32; LANES]) -> Self;
    /// Lanes with the given bit patterns.
    fn from_bits(b: [u32; LANES]) -> Self;
    /// `v[at..at + 8]` (panics if `v` is shorter: callers pad their buffers).
    fn load(v: &[f32], at: usize) -> Self;
    /// Writes the lanes to `v[at..at + 8]` (panics if `v` is shorter).
    fn store(self, v: &mut [f32], at: usize);
    fn to_array(self) -> [f32; LANES];

    /// `self < o ? self : o` per lane (x86 `minps`).
    fn min(self, o: Self) -> Self;
    /// `self > o ? self : o` per lane (x86 `maxps`).
    fn max(self, o: Self) -> Self;
    /// Correctly rounded square root.
    fn sqrt(self) -> Self;
    /// `self & !o`, bitwise.
    fn and_not(self, o: Self) -> Self;
    /// Mask of `self < o` (false on NaN).
    fn lt(self, o: Self) -> Self;
    /// Mask of `self <= o` (false on NaN).
    fn le(self, o: Self) -> Self;
    /// Mask of `self > o` (false on NaN).
    fn gt(self, o: Self) -> Self;
    /// Mask of `self >= o` (false on NaN).
    fn ge(self, o: Self) -> Self;
    /// Per lane, `t` where the mask `self` is set, else `f`.
    fn select(self, t: Self, f: Self) -> Self;
    /// Bit `k` = the sign bit of lane `k` (for a mask: whether it is set).
    fn bitmask(self) -> u32;
    /// Truncated toward zero; NaN and lanes outside the i32 range give
    /// `i32::MIN` on x86 (`cvttps`). Callers clamp first.
    fn trunc_i32(self) -> [i32; LANES];
    /// Rounded towards zero, in every lane.
    fn trunc(self) -> Self;

    /// Each lane's bit pattern shifted left by 23 bits (into the exponent
    /// field), zeros shifted in.
    fn shl23(self) -> Self;
    /// Each lane's bit pattern shifted right by 23 bits (a positive f32's
    /// biased exponent), zeros shifted in.
    fn shr23(self) -> Self;
    /// `self[i & 7]` in every lane, `i` the lane of `at` as a `u32` bit
    /// pattern: a lookup in an eight-entry table held in lanes (AVX2: one
    /// `vpermps`), no memory read.
    fn permute(self, at: Self) -> Self;
    /// `v[i]` in every lane, `i` its value truncated toward zero and
    /// clamped into `0..v.len()`; a lane whose value is not in `[0, 2³¹)`
    /// (NaN included) reads `v[0]`. Zero in every lane when `v` is empty.
    /// (AVX2: one hardware gather; portable: eight loads.)
    fn gather(v: &[f32], at: Self) -> Self;
    /// `acc[k] += a[k] as f64 * b[k] as f64` in every lane: the product is
    /// exact (an f32 × f32 product fits an f64), the sum rounded once — for
    /// sums that must stay exact where the terms' weights add up to one.
    fn add_product_f64(acc: &mut [f64; LANES], a: Self, b: Self);
    /// `lo[k] += a[k] as f64` and `hi[k] += a[k + 4] as f64` (each sum
    /// rounded once): the halves may go to different places, two rows of
    /// an image say.
    fn add_f64_halves(lo: &mut [f64; HALF_LANES], hi: &mut [f64; HALF_LANES], a: Self);
    /// `self * b + c` rounded once (fused), the same bits on every
    /// backend: AVX2 `vfmadd`, NEON `vfma`, else each lane's
    /// `f32::mul_add` (exact in software where the CPU has no FMA: slow,
    /// but only x86-64 CPUs older than AVX2 run that).
    fn mul_add(self, b: Self, c: Self) -> Self;
    /// `(num[k] / den[k]) as f32` in every lane where `den[k] > 0`, NaN
    /// elsewhere: the quotient of two such sums, rounded once to `f64` and
    /// once to `f32`, as scalar code does it.
    fn quotient_f64(num: &[f64; LANES], den: &[f64; LANES]) -> Self;

    /// Whether any lane of the mask is set.
    #[inline(always)]
    fn any(self) -> bool {
        self.bitmask() != 0
    }

    /// `0, 1, …, 7`.
    #[inline(always)]
    fn iota() -> Self {
        Self::from_array([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0])
    }

    /// The mask of the first `min(n, 8)` lanes, from a table (one load).
    #[inline(always)]
    fn first(n: usize) -> Self {
        Self::from_bits(FIRST_LANES[n.min(LANES)])
    }

    /// `|self|`: the sign bit cleared.
    #[inline(always)]
    fn abs(self) -> Self {
        self.and_not(Self::splat(-0.0))
    }

    /// `e^x`, Cephes-style: `x = n·ln2 + r` with `|r| ≤ ln2/2`, a degree-5
    /// polynomial for `(e^r − 1 − r)/r²`, and `2^n` written into the exponent
    /// bits. Within 2 ulp of `wide`'s `f32x8::exp` and of the correctly
    /// rounded value wherever the result is a normal float, `x` in
    /// `[ln 2^−126, 88.3]` (tested; 1 ulp at most on a dense sweep). Below
    /// `ln 2^−126 ≈ −87.34` it flushes to 0 where `wide` returns subnormals
    /// (< 1.2e-38; the particle kernels only go there for a Gaussian
    /// truncated beyond 13 standard deviations): handling them cost the
    /// Gaussian packet pass 4–8 % (measured, docs/benchmarks.md). +∞ above
    /// 88.38 (where the true value is finite up to 88.72), 0 for −∞, NaN for
    /// NaN. The same bits on every backend: written once, here.
    #[inline(always)]
    fn exp(self) -> Self {
        let s = Self::splat;
        let flush = self.lt(s(EXP_MIN));
        // Clamp so that n stays in −126..=128. `max`/`min` return their
        // second operand on NaN, so NaN passes through.
        let x = s(89.0).min(s(EXP_MIN).max(self));
        let y = x * s(std::f32::consts::LOG2_E);
        // In [2^23, 2^24) floats are the integers: adding 2^23 + 127 rounds
        // y to n (ties to even) and leaves n + 127, the biased exponent, in
        // the low mantissa bits.
        let t = y + s(EXP_MAGIC);
        let n = t - s(EXP_MAGIC);
        // r = x − n·ln2 in two steps (Cody–Waite): n·C1 is exact.
        let r = (x - n * s(0.693_359_4)) - n * s(-2.121_944_4e-4);
        let mut p = s(1.987_569_1e-4);
        p = p * r + s(1.398_199_9e-3);
        p = p * r + s(8.333_452e-3);
        p = p * r + s(4.166_579_6e-2);
        p = p * r + s(0.166_666_66);
        p = p * r + s(0.5);
        let e = (p * r * r + r) + s(1.0);
        // 2^n from the exponent bits; at n = −126, r ≥ 0, so e·2^n stays
        // normal.
        (e * t.shl23()).and_not(flush)
    }
}

/// [`Lanes::exp`] of one value: the same operations in the same order, so
/// the same bits as every lane type gives (tested) — for scalar code whose
/// results must equal a lane kernel's (compositing: the packet path
/// classifies a pass's samples in lanes, the per-sample path one by one).
/// About a dozen instructions inlined, against a call into libm.
#[inline(always)]
pub fn exp(x: f32) -> f32 {
    // `min`/`max` as the lanes do them (`minps`/`maxps`): NaN passes.
    let flush = x < EXP_MIN;
    let x = if EXP_MIN > x { EXP_MIN } else { x };
    let x = if 89.0 < x { 89.0 } else { x };
    let y = x * std::f32::consts::LOG2_E;
    let t = y + EXP_MAGIC;
    let n = t - EXP_MAGIC;
    let r = (x - n * 0.693_359_4) - n * -2.121_944_4e-4;
    let mut p = 1.987_569_1e-4;
    p = p * r + 1.398_199_9e-3;
    p = p * r + 8.333_452e-3;
    p = p * r + 4.166_579_6e-2;
    p = p * r + 0.166_666_66;
    p = p * r + 0.5;
    let e = (p * r * r + r) + 1.0;
    let v = e * f32::from_bits(t.to_bits() << 23);
    if flush { 0.0 } else { v }
}

/// The float just above `ln 2^−126`: below it `e^x` is subnormal, and
/// [`Lanes::exp`] flushes.
const EXP_MIN: f32 = -87.336_54;

/// `2^23 + 127`: see [`Lanes::exp`].
const EXP_MAGIC: f32 = 8_388_735.0;

/// `FIRST_LANES[n]`: the first `n` lanes set (all bits).
const FIRST_LANES: [[u32; LANES]; LANES + 1] = {
    let mut m = [[0u32; LANES]; LANES + 1];
    let mut n = 0;
    while n <= LANES {
        let mut k = 0;
        while k < n {
            m[n][k] = u32::MAX;
            k += 1;
        }
        n += 1;
    }
    m
};

/// A computation generic over the lane type, run by [`dispatch`].
pub trait WithLanes {
    type Output;
    /// The computation on lanes `L`. Mark it `#[inline(always)]` so the
    /// AVX2 instantiation is compiled inside the AVX2 entry function.
    fn run<L: Lanes>(self) -> Self::Output;
}

/// Runs `w` on the lanes `simd` resolves to ([`Simd::resolve`]).
#[inline]
pub fn dispatch<W: WithLanes>(simd: Simd, w: W) -> W::Output {
    match simd.resolve() {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `resolve` returns `Avx2` only where the CPU has AVX2.
        Simd::Avx2 => unsafe { run_avx2(w) },
        _ => w.run::<PortableLanes>(),
    }
}

/// The AVX2 entry: `w` compiled with AVX2 and FMA enabled, on AVX2 lanes
/// (Rust never contracts a separate multiply and add into an FMA, so only
/// [`Lanes::mul_add`] fuses).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn run_avx2<W: WithLanes>(w: W) -> W::Output {
    w.run::<Avx2Lanes>()
}

/// The portable lane type: `wide`'s eight f32 lanes.
pub type PortableLanes = wide::f32x8;

impl Lanes for wide::f32x8 {
    const BACKEND: Simd = Simd::Portable;

    #[inline(always)]
    fn splat(x: f32) -> Self {
        wide::f32x8::splat(x)
    }
    #[inline(always)]
    fn from_array(a: [f32; LANES]) -> Self {
        wide::f32x8::new(a)
    }
    #[inline(always)]
    fn from_bits(b: [u32; LANES]) -> Self {
        wide::bytemuck::cast(b)
    }
    #[inline(always)]
    fn load(v: &[f32], at: usize) -> Self {
        let a: [f32; LANES] = v[at..at + LANES].try_into().expect("eight lanes");
        wide::f32x8::new(a)
    }
    #[inline(always)]
    fn store(self, v: &mut [f32], at: usize) {
        v[at..at + LANES].copy_from_slice(&wide::f32x8::to_array(self));
    }
    #[inline(always)]
    fn to_array(self) -> [f32; LANES] {
        wide::f32x8::to_array(self)
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        self.fast_min(o)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        self.fast_max(o)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        wide::f32x8::sqrt(self)
    }
    #[inline(always)]
    fn and_not(self, o: Self) -> Self {
        self & !o
    }
    #[inline(always)]
    fn lt(self, o: Self) -> Self {
        self.simd_lt(o)
    }
    #[inline(always)]
    fn le(self, o: Self) -> Self {
        self.simd_le(o)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> Self {
        self.simd_gt(o)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> Self {
        self.simd_ge(o)
    }
    #[inline(always)]
    fn select(self, t: Self, f: Self) -> Self {
        wide::f32x8::select(self, t, f)
    }
    #[inline(always)]
    fn bitmask(self) -> u32 {
        self.to_bitmask()
    }
    #[inline(always)]
    fn trunc_i32(self) -> [i32; LANES] {
        self.fast_trunc_int().to_array()
    }
    #[inline(always)]
    fn trunc(self) -> Self {
        wide::f32x8::trunc(self)
    }
    #[inline(always)]
    fn shl23(self) -> Self {
        let bits: wide::u32x8 = wide::bytemuck::cast(self);
        wide::bytemuck::cast(bits << 23u32)
    }
    #[inline(always)]
    fn shr23(self) -> Self {
        let bits: wide::u32x8 = wide::bytemuck::cast(self);
        wide::bytemuck::cast(bits >> 23u32)
    }
    #[inline(always)]
    fn permute(self, at: Self) -> Self {
        let (v, at) = (wide::f32x8::to_array(self), wide::f32x8::to_array(at));
        wide::f32x8::new(at.map(|i| v[(i.to_bits() & 7) as usize]))
    }
    #[inline(always)]
    fn gather(v: &[f32], at: Self) -> Self {
        let Some(last) = v.len().checked_sub(1) else {
            return Self::splat(0.0);
        };
        let last = last.min(i32::MAX as usize) as i32;
        wide::f32x8::new(wide::f32x8::to_array(at).map(|x| {
            let i = if (0.0..2_147_483_648.0).contains(&x) {
                x as i32
            } else {
                0
            };
            v[i.min(last) as usize]
        }))
    }
    #[inline(always)]
    fn add_product_f64(acc: &mut [f64; LANES], a: Self, b: Self) {
        let (a, b) = (wide::f32x8::to_array(a), wide::f32x8::to_array(b));
        for k in 0..LANES {
            acc[k] += a[k] as f64 * b[k] as f64;
        }
    }
    #[inline(always)]
    fn mul_add(self, b: Self, c: Self) -> Self {
        #[cfg(any(target_feature = "fma", target_arch = "aarch64"))]
        {
            // `wide` fuses where the target has FMA (x86-64 `fma`, NEON).
            wide::f32x8::mul_add(self, b, c)
        }
        #[cfg(not(any(target_feature = "fma", target_arch = "aarch64")))]
        {
            let (a, b, c) = (self.to_array(), b.to_array(), c.to_array());
            wide::f32x8::new(std::array::from_fn(|k| a[k].mul_add(b[k], c[k])))
        }
    }
    #[inline(always)]
    fn add_f64_halves(lo: &mut [f64; HALF_LANES], hi: &mut [f64; HALF_LANES], a: Self) {
        let a = wide::f32x8::to_array(a);
        for k in 0..HALF_LANES {
            lo[k] += a[k] as f64;
            hi[k] += a[k + HALF_LANES] as f64;
        }
    }
    #[inline(always)]
    fn quotient_f64(num: &[f64; LANES], den: &[f64; LANES]) -> Self {
        let mut q = [f32::NAN; LANES];
        for k in 0..LANES {
            if den[k] > 0.0 {
                q[k] = (num[k] / den[k]) as f32;
            }
        }
        wide::f32x8::new(q)
    }
}

#[cfg(target_arch = "x86_64")]
use avx2::Avx2Lanes;

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::{HALF_LANES, LANES, Lanes, Simd};
    use std::arch::x86_64::*;
    use std::ops::{Add, BitAnd, BitOr, Div, Mul, Sub};

    /// Eight AVX lanes.
    ///
    /// Soundness: the methods are safe yet use AVX2 instructions, so a value
    /// must never exist on a CPU without AVX2. The type is private to this
    /// module tree (no constant, no `Default`): outside it, the only way to
    /// get one is as the lane type of [`super::dispatch`]'s AVX2 branch,
    /// which runs after the CPU check; inside it, the tests check first.
    #[derive(Clone, Copy, Debug)]
    pub(super) struct Avx2Lanes(__m256);

    // SAFETY (every `unsafe` block below): a value of `Avx2Lanes` exists,
    // or is being made inside code reached through `dispatch`, only where
    // the CPU has AVX2 (see the type's docs); loads and stores go through
    // bounds-checked slices of exactly eight lanes.

    macro_rules! binop {
        ($tr:ident, $f:ident, $op:ident) => {
            impl $tr for Avx2Lanes {
                type Output = Avx2Lanes;
                #[inline(always)]
                fn $f(self, o: Self) -> Self {
                    unsafe { Avx2Lanes($op(self.0, o.0)) }
                }
            }
        };
    }
    binop!(Add, add, _mm256_add_ps);
    binop!(Sub, sub, _mm256_sub_ps);
    binop!(Mul, mul, _mm256_mul_ps);
    binop!(Div, div, _mm256_div_ps);
    binop!(BitAnd, bitand, _mm256_and_ps);
    binop!(BitOr, bitor, _mm256_or_ps);

    impl Lanes for Avx2Lanes {
        const BACKEND: Simd = Simd::Avx2;

        #[inline(always)]
        fn splat(x: f32) -> Self {
            unsafe { Avx2Lanes(_mm256_set1_ps(x)) }
        }
        #[inline(always)]
        fn from_array(a: [f32; LANES]) -> Self {
            unsafe { Avx2Lanes(_mm256_loadu_ps(a.as_ptr())) }
        }
        #[inline(always)]
        fn from_bits(b: [u32; LANES]) -> Self {
            unsafe { Avx2Lanes(_mm256_loadu_ps(b.as_ptr().cast())) }
        }
        #[inline(always)]
        fn load(v: &[f32], at: usize) -> Self {
            let s = &v[at..at + LANES];
            unsafe { Avx2Lanes(_mm256_loadu_ps(s.as_ptr())) }
        }
        #[inline(always)]
        fn store(self, v: &mut [f32], at: usize) {
            let s = &mut v[at..at + LANES];
            unsafe { _mm256_storeu_ps(s.as_mut_ptr(), self.0) }
        }
        #[inline(always)]
        fn to_array(self) -> [f32; LANES] {
            let mut a = [0.0; LANES];
            unsafe { _mm256_storeu_ps(a.as_mut_ptr(), self.0) };
            a
        }
        #[inline(always)]
        fn min(self, o: Self) -> Self {
            unsafe { Avx2Lanes(_mm256_min_ps(self.0, o.0)) }
        }
        #[inline(always)]
        fn max(self, o: Self) -> Self {
            unsafe { Avx2Lanes(_mm256_max_ps(self.0, o.0)) }
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            unsafe { Avx2Lanes(_mm256_sqrt_ps(self.0)) }
        }
        #[inline(always)]
        fn and_not(self, o: Self) -> Self {
            unsafe { Avx2Lanes(_mm256_andnot_ps(o.0, self.0)) }
        }
        #[inline(always)]
        fn lt(self, o: Self) -> Self {
            unsafe { Avx2Lanes(_mm256_cmp_ps::<_CMP_LT_OQ>(self.0, o.0)) }
        }
        #[inline(always)]
        fn le(self, o: Self) -> Self {
            unsafe { Avx2Lanes(_mm256_cmp_ps::<_CMP_LE_OQ>(self.0, o.0)) }
        }
        #[inline(always)]
        fn gt(self, o: Self) -> Self {
            unsafe { Avx2Lanes(_mm256_cmp_ps::<_CMP_GT_OQ>(self.0, o.0)) }
        }
        #[inline(always)]
        fn ge(self, o: Self) -> Self {
            unsafe { Avx2Lanes(_mm256_cmp_ps::<_CMP_GE_OQ>(self.0, o.0)) }
        }
        #[inline(always)]
        fn select(self, t: Self, f: Self) -> Self {
            unsafe { Avx2Lanes(_mm256_blendv_ps(f.0, t.0, self.0)) }
        }
        #[inline(always)]
        fn bitmask(self) -> u32 {
            unsafe { _mm256_movemask_ps(self.0) as u32 }
        }
        #[inline(always)]
        fn trunc_i32(self) -> [i32; LANES] {
            let mut a = [0i32; LANES];
            unsafe { _mm256_storeu_si256(a.as_mut_ptr().cast(), _mm256_cvttps_epi32(self.0)) };
            a
        }
        #[inline(always)]
        fn trunc(self) -> Self {
            unsafe {
                Avx2Lanes(_mm256_round_ps::<{ _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC }>(self.0))
            }
        }
        #[inline(always)]
        fn gather(v: &[f32], at: Self) -> Self {
            let Some(last) = v.len().checked_sub(1) else {
                return Self::splat(0.0);
            };
            let last = last.min(i32::MAX as usize) as i32;
            // `cvttps` gives i32::MIN for NaN and values ≥ 2³¹, so the clamp
            // sends them to 0; every index read is in 0..v.len().
            unsafe {
                let i = _mm256_cvttps_epi32(at.0);
                let i = _mm256_max_epi32(i, _mm256_setzero_si256());
                let i = _mm256_min_epi32(i, _mm256_set1_epi32(last));
                Avx2Lanes(_mm256_i32gather_ps::<4>(v.as_ptr(), i))
            }
        }
        #[inline(always)]
        fn add_product_f64(acc: &mut [f64; LANES], a: Self, b: Self) {
            // Two halves of four f64 lanes; `acc` is eight f64s, so both
            // unaligned loads and stores stay inside it.
            unsafe {
                let lo = _mm256_mul_pd(
                    _mm256_cvtps_pd(_mm256_castps256_ps128(a.0)),
                    _mm256_cvtps_pd(_mm256_castps256_ps128(b.0)),
                );
                let hi = _mm256_mul_pd(
                    _mm256_cvtps_pd(_mm256_extractf128_ps::<1>(a.0)),
                    _mm256_cvtps_pd(_mm256_extractf128_ps::<1>(b.0)),
                );
                let p = acc.as_mut_ptr();
                _mm256_storeu_pd(p, _mm256_add_pd(_mm256_loadu_pd(p), lo));
                _mm256_storeu_pd(p.add(4), _mm256_add_pd(_mm256_loadu_pd(p.add(4)), hi));
            }
        }
        #[inline(always)]
        fn mul_add(self, b: Self, c: Self) -> Self {
            // The AVX2 entry enables FMA too (`avx2_detected` checks both).
            unsafe { Avx2Lanes(_mm256_fmadd_ps(self.0, b.0, c.0)) }
        }
        #[inline(always)]
        fn add_f64_halves(lo: &mut [f64; HALF_LANES], hi: &mut [f64; HALF_LANES], a: Self) {
            // As `add_product_f64`, without the product, each half to its
            // own four f64s.
            unsafe {
                let (l, h) = (lo.as_mut_ptr(), hi.as_mut_ptr());
                let a_lo = _mm256_cvtps_pd(_mm256_castps256_ps128(a.0));
                let a_hi = _mm256_cvtps_pd(_mm256_extractf128_ps::<1>(a.0));
                _mm256_storeu_pd(l, _mm256_add_pd(_mm256_loadu_pd(l), a_lo));
                _mm256_storeu_pd(h, _mm256_add_pd(_mm256_loadu_pd(h), a_hi));
            }
        }
        #[inline(always)]
        fn quotient_f64(num: &[f64; LANES], den: &[f64; LANES]) -> Self {
            // Four f64 lanes at a time: divide, round to f32, NaN where the
            // denominator is not positive (`den > 0` is false on NaN).
            unsafe {
                let half = |at: usize| {
                    let (n, d) = (
                        _mm256_loadu_pd(num.as_ptr().add(at)),
                        _mm256_loadu_pd(den.as_ptr().add(at)),
                    );
                    let q = _mm256_div_pd(n, d);
                    let ok = _mm256_cmp_pd::<_CMP_GT_OQ>(d, _mm256_setzero_pd());
                    _mm256_blendv_pd(_mm256_set1_pd(f64::NAN), q, ok)
                };
                let (lo, hi) = (_mm256_cvtpd_ps(half(0)), _mm256_cvtpd_ps(half(4)));
                Avx2Lanes(_mm256_set_m128(hi, lo))
            }
        }
        #[inline(always)]
        fn shl23(self) -> Self {
            unsafe {
                Avx2Lanes(_mm256_castsi256_ps(_mm256_slli_epi32::<23>(
                    _mm256_castps_si256(self.0),
                )))
            }
        }
        #[inline(always)]
        fn shr23(self) -> Self {
            unsafe {
                Avx2Lanes(_mm256_castsi256_ps(_mm256_srli_epi32::<23>(
                    _mm256_castps_si256(self.0),
                )))
            }
        }
        #[inline(always)]
        fn permute(self, at: Self) -> Self {
            // `vpermps` reads the low three bits of each index.
            unsafe { Avx2Lanes(_mm256_permutevar8x32_ps(self.0, _mm256_castps_si256(at.0))) }
        }
    }
}

/// Asks the CPU to bring the cache line holding `at` into its caches ahead
/// of use (x86-64 `prefetcht0`; nothing elsewhere). A hint only: `at` is
/// never read through, so any address may be given — for strided reads
/// (a lattice's rows) that the hardware prefetchers do not follow.
#[inline(always)]
pub fn prefetch<T>(at: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `prefetcht0` only hints; it does not fault on any address.
    unsafe {
        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(at.cast())
    };
    #[cfg(not(target_arch = "x86_64"))]
    let _ = at;
}

#[cfg(test)]
#[path = "simd_tests.rs"]
mod tests;
