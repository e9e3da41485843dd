//! Packet sampling (CPU RBF paper §4.1): the sample buffer of a whole packet
//! of rays filled by one BVH traversal.
//!
//! The traversal collects every cluster whose box overlaps the box of all
//! the packet's samples. Rays go in groups of eight (structure of arrays):
//! one slab test says which groups cross a cluster's box at all, then each
//! member particle is tested against eight rays at once — its support cuts
//! each ray in a chord `[u − h, u + h]` — and only the samples inside a ray's
//! chord are evaluated, several at a time. Each particle is thus visited once
//! per packet and pass instead of once per sample, and the per-sample
//! point-query traversal disappears.
//!
//! Exactness: a sample takes a particle iff `|p − c|² ≤ R²` with `p =
//! ray.at(t)` — the point query's own test on the same `p` (the chord only
//! pre-selects, padded against rounding). Clusters come in the point query's
//! depth-first order and members in index order, so every sample sums the
//! same terms in the same order as [`ParticleVolume::field`]; the kernels are
//! evaluated in f32 SIMD, within a few ulp of the scalar forms (the scalar
//! cubic spline works in f64; the SIMD Gaussians use a polynomial `exp`).
//!
//! SIMD: portable `wide` types (four lanes per sample chunk: a ray's run of
//! samples inside one particle is short, ≈ 8 at the default step, so narrow
//! chunks waste few masked lanes), and, chosen at run time when the CPU has
//! AVX2, the whole pass compiled for AVX2 with the chord test and the sample
//! loop on eight AVX lanes (same operations in the same order; measured in
//! docs/benchmarks.md). An attempt to let LLVM vectorise plain per-lane array
//! code instead produced shuffle-heavy code and was slower than both.

use voxless_core::{Aabb, Sample, SampleBatch, Vec3};
use wide::f32x8;

use super::{FieldSample, ParticleVolume, to_sample};
use crate::kernel::{Family, LANES, Lanes};

/// `LANE_MASKS[n]`: the first `n` of eight lanes set (all bits), as f32 bits.
#[cfg(target_arch = "x86_64")]
static LANE_MASKS: [[u32; 8]; 9] = {
    let mut m = [[0u32; 8]; 9];
    let mut n = 0;
    while n <= 8 {
        let mut k = 0;
        while k < n {
            m[n][k] = u32::MAX;
            k += 1;
        }
        n += 1;
    }
    m
};

/// SIMD width of the sample loop.
const L: usize = 8;

#[inline(always)]
fn ld(v: &[f32], j: usize) -> Lanes {
    Lanes::new(v[j..j + LANES].try_into().expect("padded buffer"))
}

#[inline(always)]
fn add(v: &mut [f32], j: usize, x: Lanes) {
    let s = &mut v[j..j + LANES];
    let sum = Lanes::new((&*s).try_into().expect("padded buffer")) + x;
    s.copy_from_slice(&sum.to_array());
}

/// A first guess at the index of `x` in sorted `ts` from the mean sample
/// spacing (`inv_step` samples per unit t from `t0`). Samples are nearly
/// evenly spaced (jitter restarts only at interval boundaries), so it is
/// within a step or two; [`walk`] finishes. Cheaper than a binary search,
/// which dominated the pass. Through i32: one conversion instruction, where
/// f32 → usize is a branchy sequence; NaN-safe (`as` saturates, NaN → 0).
#[inline(always)]
fn guess(ts: &[f32], x: f32, t0: f32, inv_step: f32) -> i32 {
    ((x - t0) * inv_step).clamp(0.0, ts.len() as f32) as i32
}

/// The sample buffer, structure of arrays, padded by one SIMD width so the
/// last chunk of a ray can be loaded whole (its extra lanes are masked).
#[derive(Default)]
struct Buffer {
    px: Vec<f32>,
    py: Vec<f32>,
    pz: Vec<f32>,
    density: Vec<f32>,
    attr: Vec<f32>,
    /// 1 where some support contains the sample.
    covered: Vec<f32>,
    color: [Vec<f32>; 3],
    grad: [Vec<f32>; 3],
    /// Clusters the pass box overlaps, in traversal order.
    clusters: Vec<(u32, Aabb)>,
}

impl Buffer {
    fn reset(&mut self, n: usize, color: bool, grad: bool) {
        // (`clusters` is refilled by each pass.)
        let len = n + L;
        for v in [
            &mut self.px,
            &mut self.py,
            &mut self.pz,
            &mut self.density,
            &mut self.attr,
            &mut self.covered,
        ] {
            v.clear();
            v.resize(len, 0.0);
        }
        for v in self.color.iter_mut() {
            v.clear();
            v.resize(if color { len } else { 0 }, 0.0);
        }
        for v in self.grad.iter_mut() {
            v.clear();
            v.resize(if grad { len } else { 0 }, 0.0);
        }
    }
}

/// Set by [`crate::force_portable_simd`]: skip the AVX2 pass.
static PORTABLE_ONLY: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Makes packet sampling use the portable SIMD path even where AVX2 is
/// available (tests and benchmarks compare the two; both give the same
/// image within a few ulp).
pub fn force_portable_simd(on: bool) {
    PORTABLE_ONLY.store(on, std::sync::atomic::Ordering::Relaxed);
}

thread_local! {
    static BUFFER: std::cell::RefCell<Buffer> = std::cell::RefCell::new(Buffer::default());
}

/// Samples per unit t over sorted `ts` (0 for a single sample).
fn inv_step(ts: &[f32]) -> f32 {
    let width = ts[ts.len() - 1] - ts[0];
    if ts.len() > 1 && width > 0.0 {
        (ts.len() - 1) as f32 / width
    } else {
        0.0
    }
}

/// The first index of sorted `ts` with `ts[j] ≥ x` (`strict`: `> x`),
/// walking from the guess `g`.
#[inline(always)]
fn walk(ts: &[f32], x: f32, g: i32, strict: bool) -> usize {
    let before = |t: f32| if strict { t <= x } else { t < x };
    let mut j = (g.max(0) as usize).min(ts.len());
    while j < ts.len() && before(ts[j]) {
        j += 1;
    }
    while j > 0 && !before(ts[j - 1]) {
        j -= 1;
    }
    j
}

/// `1 / d`, finite: zero becomes ±1e-30 first.
fn safe_inv(d: f32) -> f32 {
    if d.abs() < 1e-30 {
        1.0 / 1e-30f32.copysign(d)
    } else {
        1.0 / d
    }
}

/// Eight rays of a packet, structure of arrays, with their pass spans.
struct RayGroup {
    ox: f32x8,
    oy: f32x8,
    oz: f32x8,
    dx: f32x8,
    dy: f32x8,
    dz: f32x8,
    inv_dd: f32x8,
    /// 1 / direction, with zero components replaced by a tiny value so the
    /// slab test never computes 0·∞.
    ix: f32x8,
    iy: f32x8,
    iz: f32x8,
    lo: f32x8,
    hi: f32x8,
    /// Samples per unit t (mean spacing⁻¹) and sample count, for the
    /// index guesses of the AVX path.
    inv_step: f32x8,
    count: f32x8,
}

impl RayGroup {
    /// Whether any of the eight rays crosses box `b` within its pass span
    /// (padded for rounding).
    #[inline(always)]
    fn crosses(&self, b: &Aabb) -> bool {
        let slab = |lo: f32, hi: f32, o: f32x8, inv: f32x8| {
            let t0 = (f32x8::splat(lo) - o) * inv;
            let t1 = (f32x8::splat(hi) - o) * inv;
            (t0.min(t1), t0.max(t1))
        };
        let (ax, bx) = slab(b.min.x, b.max.x, self.ox, self.ix);
        let (ay, by) = slab(b.min.y, b.max.y, self.oy, self.iy);
        let (az, bz) = slab(b.min.z, b.max.z, self.oz, self.iz);
        let pad = f32x8::splat(1e-4) * (self.lo.abs().min(f32x8::splat(1e30)) + f32x8::ONE);
        let enter = ax.max(ay).max(az).max(self.lo - pad);
        let exit = bx.min(by).min(bz).min(self.hi + pad);
        enter.simd_le(exit).any()
    }

    /// [`Self::chord`] as arrays, with bit `k` set iff ray `k`'s chord
    /// overlaps its pass span.
    #[inline(always)]
    fn chord_hits(&self, c: Vec3, r2: f32) -> ([f32; 8], [f32; 8], u32) {
        let (lo, hi) = self.chord(c, r2);
        let bits = (lo.simd_le(self.hi) & hi.simd_ge(self.lo)).to_bitmask();
        (lo.to_array(), hi.to_array(), bits)
    }

    /// [`Self::chord_hits`] on eight AVX lanes, same operations in the same
    /// order.
    ///
    /// # Safety
    /// The CPU must support AVX2; called only from `batch_avx2`.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn chord_avx(&self, c: Vec3, r2: f32) -> ([f32; 8], [f32; 8], u32, [[i32; 8]; 2]) {
        use std::arch::x86_64::*;
        // `f32x8` is 32 bytes of eight f32 lanes in order, like `__m256`.
        let m = |v: f32x8| -> __m256 { unsafe { std::mem::transmute::<f32x8, __m256>(v) } };
        unsafe {
            let s = _mm256_set1_ps;
            let (dx, dy, dz, inv_dd) = (m(self.dx), m(self.dy), m(self.dz), m(self.inv_dd));
            let ox = _mm256_sub_ps(s(c.x), m(self.ox));
            let oy = _mm256_sub_ps(s(c.y), m(self.oy));
            let oz = _mm256_sub_ps(s(c.z), m(self.oz));
            let (mul, add, sub) = (_mm256_mul_ps, _mm256_add_ps, _mm256_sub_ps);
            let cx = sub(mul(oy, dz), mul(oz, dy));
            let cy = sub(mul(oz, dx), mul(ox, dz));
            let cz = sub(mul(ox, dy), mul(oy, dx));
            let b2 = mul(add(add(mul(cx, cx), mul(cy, cy)), mul(cz, cz)), inv_dd);
            let u = mul(add(add(mul(ox, dx), mul(oy, dy)), mul(oz, dz)), inv_dd);
            let r2 = s(r2);
            let h2 = mul(sub(r2, b2), inv_dd);
            let abs_u = _mm256_andnot_ps(s(-0.0), u);
            let h = add(
                mul(_mm256_sqrt_ps(_mm256_max_ps(h2, s(0.0))), s(1.001)),
                mul(s(1e-5), abs_u),
            );
            let hit = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_LE_OQ>(b2, r2),
                _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_LE_OQ>(sub(u, h), m(self.hi)),
                    _mm256_cmp_ps::<_CMP_GE_OQ>(add(u, h), m(self.lo)),
                ),
            );
            let bits = _mm256_movemask_ps(hit) as u32;
            let mut lo = [0.0f32; 8];
            let mut hi = [0.0f32; 8];
            let mut guess = [[0i32; 8]; 2];
            if bits != 0 {
                let (l, r) = (sub(u, h), add(u, h));
                _mm256_storeu_ps(lo.as_mut_ptr(), l);
                _mm256_storeu_ps(hi.as_mut_ptr(), r);
                // Index guesses from the mean spacing, for all eight rays.
                let g = |x: __m256| {
                    let v = mul(sub(x, m(self.lo)), m(self.inv_step));
                    _mm256_cvttps_epi32(_mm256_min_ps(_mm256_max_ps(v, s(0.0)), m(self.count)))
                };
                _mm256_storeu_si256(guess[0].as_mut_ptr().cast(), g(l));
                _mm256_storeu_si256(guess[1].as_mut_ptr().cast(), g(r));
            }
            (lo, hi, bits, guess)
        }
    }

    /// The chord `[lo, hi]` (in t) each ray cuts from the ball of squared
    /// radius `r2` around `c`, padded for rounding; empty (lo > hi) on a miss.
    #[inline(always)]
    fn chord(&self, c: Vec3, r2: f32) -> (f32x8, f32x8) {
        let ox = f32x8::splat(c.x) - self.ox;
        let oy = f32x8::splat(c.y) - self.oy;
        let oz = f32x8::splat(c.z) - self.oz;
        // Distance² from the line via the cross product (no cancellation).
        let cx = oy * self.dz - oz * self.dy;
        let cy = oz * self.dx - ox * self.dz;
        let cz = ox * self.dy - oy * self.dx;
        let b2 = (cx * cx + cy * cy + cz * cz) * self.inv_dd;
        let u = (ox * self.dx + oy * self.dy + oz * self.dz) * self.inv_dd;
        let r2 = f32x8::splat(r2);
        let h2 = (r2 - b2) * self.inv_dd;
        let h = h2.max(f32x8::ZERO).sqrt() * f32x8::splat(1.001) + f32x8::splat(1e-5) * u.abs();
        let miss = b2.simd_gt(r2);
        let lo = miss.select(f32x8::splat(f32::INFINITY), u - h);
        let hi = miss.select(f32x8::splat(f32::NEG_INFINITY), u + h);
        (lo, hi)
    }
}

impl ParticleVolume {
    /// Adds particle `i` to buffer samples `j0..j1` (one ray's), eight at a
    /// time, each iff `|p − c|² ≤ R²`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn deposit<F: Family, const GRAD: bool>(
        &self,
        buf: &mut Buffer,
        i: usize,
        j0: usize,
        j1: usize,
        lanes: Lanes,
        attr: Option<&[f32]>,
        pre: bool,
    ) {
        let q = &self.packed[i];
        let (cx, cy, cz) = (
            Lanes::splat(q.center.x),
            Lanes::splat(q.center.y),
            Lanes::splat(q.center.z),
        );
        let r2 = Lanes::splat(q.support2);
        let mut j = j0;
        while j < j1 {
            let valid = lanes.simd_lt(Lanes::splat((j1 - j).min(LANES) as i32 as f32));
            let dx = ld(&buf.px, j) - cx;
            let dy = ld(&buf.py, j) - cy;
            let dz = ld(&buf.pz, j) - cz;
            // The point query's own test, as (x² + y²) + z².
            let d2 = dx * dx + dy * dy + dz * dz;
            let inside = d2.simd_le(r2) & valid;
            if inside.any() {
                let v = if GRAD {
                    let (v, g) = F::value_and_gradient_factor_simd(d2, q.shape, q.amp);
                    let g = inside.select(g, Lanes::ZERO);
                    add(&mut buf.grad[0], j, dx * g);
                    add(&mut buf.grad[1], j, dy * g);
                    add(&mut buf.grad[2], j, dz * g);
                    v
                } else {
                    F::value_simd(d2, q.shape, q.amp)
                };
                let v = inside.select(v, Lanes::ZERO);
                add(&mut buf.density, j, v);
                let cov = ld(&buf.covered, j).max(inside.select(Lanes::ONE, Lanes::ZERO));
                buf.covered[j..j + LANES].copy_from_slice(&cov.to_array());
                if let Some(at) = attr {
                    add(&mut buf.attr, j, v * Lanes::splat(at[i]));
                }
                if pre {
                    let col = self.colors[i];
                    add(&mut buf.color[0], j, v * Lanes::splat(col.x));
                    add(&mut buf.color[1], j, v * Lanes::splat(col.y));
                    add(&mut buf.color[2], j, v * Lanes::splat(col.z));
                }
            }
            j += LANES;
        }
    }

    /// [`Self::deposit`] on eight AVX lanes, same operations in the same
    /// order.
    ///
    /// # Safety
    /// The CPU must support AVX2; called only from [`Self::batch_avx2`].
    #[cfg(target_arch = "x86_64")]
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    unsafe fn deposit_avx<F: Family, const GRAD: bool>(
        &self,
        buf: &mut Buffer,
        i: usize,
        j0: usize,
        j1: usize,
        attr: Option<&[f32]>,
        pre: bool,
    ) {
        use std::arch::x86_64::*;
        // Loads and adds lanes `j..j + 8` of a padded buffer.
        #[inline(always)]
        unsafe fn ld(v: &[f32], j: usize) -> __m256 {
            unsafe { _mm256_loadu_ps(v[j..j + 8].as_ptr()) }
        }
        #[inline(always)]
        unsafe fn add(v: &mut [f32], j: usize, x: __m256) {
            unsafe {
                let s = &mut v[j..j + 8];
                _mm256_storeu_ps(
                    s.as_mut_ptr(),
                    _mm256_add_ps(_mm256_loadu_ps(s.as_ptr()), x),
                );
            }
        }
        unsafe {
            let q = &self.packed[i];
            let (cx, cy, cz) = (
                _mm256_set1_ps(q.center.x),
                _mm256_set1_ps(q.center.y),
                _mm256_set1_ps(q.center.z),
            );
            let r2 = _mm256_set1_ps(q.support2);
            let one = _mm256_set1_ps(1.0);
            let mut j = j0;
            while j < j1 {
                // The first min(j1 − j, 8) lanes, from a table.
                let valid = _mm256_loadu_ps(LANE_MASKS[(j1 - j).min(8)].as_ptr().cast());
                let dx = _mm256_sub_ps(ld(&buf.px, j), cx);
                let dy = _mm256_sub_ps(ld(&buf.py, j), cy);
                let dz = _mm256_sub_ps(ld(&buf.pz, j), cz);
                // The point query's own test, as (x² + y²) + z².
                let d2 = _mm256_add_ps(
                    _mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
                    _mm256_mul_ps(dz, dz),
                );
                let inside = _mm256_and_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(d2, r2), valid);
                if _mm256_movemask_ps(inside) != 0 {
                    let v = if GRAD {
                        let (v, g) = F::value_and_gradient_factor_avx(d2, q.shape, q.amp);
                        let g = _mm256_and_ps(g, inside);
                        add(&mut buf.grad[0], j, _mm256_mul_ps(dx, g));
                        add(&mut buf.grad[1], j, _mm256_mul_ps(dy, g));
                        add(&mut buf.grad[2], j, _mm256_mul_ps(dz, g));
                        v
                    } else {
                        F::value_avx(d2, q.shape, q.amp)
                    };
                    let v = _mm256_and_ps(v, inside);
                    add(&mut buf.density, j, v);
                    let cov = _mm256_max_ps(ld(&buf.covered, j), _mm256_and_ps(one, inside));
                    _mm256_storeu_ps(buf.covered[j..j + 8].as_mut_ptr(), cov);
                    if let Some(at) = attr {
                        add(&mut buf.attr, j, _mm256_mul_ps(v, _mm256_set1_ps(at[i])));
                    }
                    if pre {
                        let col = self.colors[i];
                        add(
                            &mut buf.color[0],
                            j,
                            _mm256_mul_ps(v, _mm256_set1_ps(col.x)),
                        );
                        add(
                            &mut buf.color[1],
                            j,
                            _mm256_mul_ps(v, _mm256_set1_ps(col.y)),
                        );
                        add(
                            &mut buf.color[2],
                            j,
                            _mm256_mul_ps(v, _mm256_set1_ps(col.z)),
                        );
                    }
                }
                j += 8;
            }
        }
    }

    pub(super) fn batch<F: Family, const GRAD: bool>(
        &self,
        batch: &SampleBatch,
        out: &mut Vec<(Option<Sample>, Vec3)>,
    ) {
        BUFFER.with_borrow_mut(|buf| {
            #[cfg(target_arch = "x86_64")]
            if !PORTABLE_ONLY.load(std::sync::atomic::Ordering::Relaxed)
                && std::arch::is_x86_feature_detected!("avx2")
            {
                // SAFETY: the CPU has AVX2 (checked just above).
                unsafe { self.batch_avx2::<F, GRAD>(batch, buf, out) };
                return;
            }
            self.batch_in::<F, GRAD, false>(batch, buf, out);
        });
    }

    /// [`ParticleVolume::batch_in`] compiled with AVX2, its sample loop on
    /// eight AVX lanes.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn batch_avx2<F: Family, const GRAD: bool>(
        &self,
        batch: &SampleBatch,
        buf: &mut Buffer,
        out: &mut Vec<(Option<Sample>, Vec3)>,
    ) {
        self.batch_in::<F, GRAD, true>(batch, buf, out);
    }

    /// The pass; `AVX`: deposit with AVX2 (only from [`Self::batch_avx2`]).
    #[inline(always)]
    fn batch_in<F: Family, const GRAD: bool, const AVX: bool>(
        &self,
        batch: &SampleBatch,
        buf: &mut Buffer,
        out: &mut Vec<(Option<Sample>, Vec3)>,
    ) {
        let n_rays = batch.rays.len();
        let attr = self.attribute.as_deref();
        let pre = !self.colors.is_empty();
        buf.reset(batch.t.len(), pre, GRAD);
        let mut bounds = Aabb::EMPTY;
        for r in 0..n_rays {
            let ray = batch.rays[r];
            let base = batch.offsets[r] as usize;
            for (k, &t) in batch.samples(r).iter().enumerate() {
                // Exactly the point the per-sample path evaluates.
                let p = ray.at(t);
                buf.px[base + k] = p.x;
                buf.py[base + k] = p.y;
                buf.pz[base + k] = p.z;
                bounds.grow(p);
            }
        }
        // Rays in groups of eight, structure of arrays, so one particle is
        // tested against eight rays at once. Padding lanes get an empty span.
        let groups = n_rays.div_ceil(L);
        let mut rg = Vec::with_capacity(groups);
        // Samples per unit t of each ray, for the index guesses (once per pass).
        let inv_steps: Vec<f32> = (0..n_rays).map(|r| inv_step(batch.samples(r))).collect();
        for g in 0..groups {
            let lane = |f: &dyn Fn(usize) -> f32, pad: f32| {
                f32x8::new(std::array::from_fn(|k| {
                    let r = g * L + k;
                    if r < n_rays { f(r) } else { pad }
                }))
            };
            let span = |r: usize| {
                let s = batch.samples(r);
                (s[0], s[s.len() - 1])
            };
            let ray = |r: usize| &batch.rays[r];
            rg.push(RayGroup {
                ox: lane(&|r| ray(r).origin.x, 0.0),
                oy: lane(&|r| ray(r).origin.y, 0.0),
                oz: lane(&|r| ray(r).origin.z, 0.0),
                dx: lane(&|r| ray(r).dir.x, 0.0),
                dy: lane(&|r| ray(r).dir.y, 0.0),
                dz: lane(&|r| ray(r).dir.z, 0.0),
                inv_dd: lane(&|r| 1.0 / ray(r).dir.length_squared(), 0.0),
                ix: lane(&|r| safe_inv(ray(r).dir.x), 1.0),
                iy: lane(&|r| safe_inv(ray(r).dir.y), 1.0),
                iz: lane(&|r| safe_inv(ray(r).dir.z), 1.0),
                lo: lane(&|r| span(r).0, f32::INFINITY),
                hi: lane(&|r| span(r).1, f32::NEG_INFINITY),
                inv_step: lane(&|r| inv_steps[r], 0.0),
                count: lane(&|r| batch.samples(r).len() as f32, 0.0),
            });
        }
        let n = self.settings.cluster_size;
        let lanes = Lanes::new(std::array::from_fn(|k| k as f32));
        let mut hit_groups = [0u32; 64];
        // Collect first, so the loop below is compiled in this function
        // (with AVX2 when dispatched so), not inside the traversal.
        let mut clusters = std::mem::take(&mut buf.clusters);
        clusters.clear();
        self.bvh.box_query(&bounds, |c, b| clusters.push((c, *b)));
        for &(c, cbox) in &clusters {
            let cbox = &cbox;
            let start = c as usize * n;
            let end = (start + n).min(self.packed.len());
            // Which ray groups cross the cluster box at all: one slab test
            // per eight rays instead of a chord test per particle and ray.
            let mut ng = 0;
            for (g, rays) in rg.iter().enumerate() {
                if rays.crosses(cbox) {
                    hit_groups[ng] = g as u32;
                    ng += 1;
                }
            }
            if ng == 0 {
                continue;
            }
            for i in start..end {
                let q = &self.packed[i];
                if q.support2 < 0.0 {
                    continue;
                }
                // Padded: the chord only pre-selects samples.
                let r2 = q.support2 * 1.0001;
                for &g in &hit_groups[..ng] {
                    let g = g as usize;
                    let rays = &rg[g];
                    #[cfg(target_arch = "x86_64")]
                    let (lo, hi, mut bits, guesses) = if AVX {
                        // SAFETY: AVX is set only under `batch_avx2`.
                        unsafe { rays.chord_avx(q.center, r2) }
                    } else {
                        let (lo, hi, bits) = rays.chord_hits(q.center, r2);
                        (lo, hi, bits, [[-1; 8]; 2])
                    };
                    #[cfg(not(target_arch = "x86_64"))]
                    let (lo, hi, mut bits, guesses) = {
                        let (lo, hi, bits) = rays.chord_hits(q.center, r2);
                        (lo, hi, bits, [[-1i32; 8]; 2])
                    };
                    if bits == 0 {
                        continue;
                    }
                    while bits != 0 {
                        let k = bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        let r = g * L + k;
                        let ts = batch.samples(r);
                        let base = batch.offsets[r] as usize;
                        let (j0, j1) = if AVX {
                            (
                                walk(ts, lo[k], guesses[0][k], false),
                                walk(ts, hi[k], guesses[1][k], true),
                            )
                        } else {
                            (
                                walk(ts, lo[k], guess(ts, lo[k], ts[0], inv_steps[r]), false),
                                walk(ts, hi[k], guess(ts, hi[k], ts[0], inv_steps[r]), true),
                            )
                        };
                        let (j0, j1) = (base + j0, base + j1);
                        #[cfg(target_arch = "x86_64")]
                        if AVX {
                            // SAFETY: AVX is set only under `batch_avx2`.
                            unsafe { self.deposit_avx::<F, GRAD>(buf, i, j0, j1, attr, pre) };
                            continue;
                        }
                        self.deposit::<F, GRAD>(buf, i, j0, j1, lanes, attr, pre);
                    }
                }
            }
        }
        buf.clusters = clusters;
        out.extend((0..batch.t.len()).map(|j| {
            let density = buf.density[j];
            let f = FieldSample {
                density,
                attribute: if attr.is_some() && density > 0.0 {
                    buf.attr[j] / density
                } else {
                    f32::NAN
                },
                color: (pre && density > 0.0).then(|| {
                    Vec3::new(buf.color[0][j], buf.color[1][j], buf.color[2][j]) / density
                }),
                gradient: if GRAD {
                    Vec3::new(buf.grad[0][j], buf.grad[1][j], buf.grad[2][j])
                } else {
                    Vec3::ZERO
                },
                covered: buf.covered[j] > 0.0,
            };
            (f.covered.then(|| to_sample(&f)), f.gradient)
        }));
    }
}
