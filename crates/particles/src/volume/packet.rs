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
//! evaluated in f32 SIMD, within a few ulp of the scalar forms (the SIMD
//! Gaussians use a polynomial `exp`; the scalar cubic spline works in f64,
//! so near its support edge, where an f32 `2 − q` cancels, the SIMD term is
//! a few ulp of the kernel's peak rather than of itself).
//!
//! SIMD: the pass is written once, generic over [`Lanes`] (eight f32 lanes:
//! eight rays in the chord test, eight samples of one ray in the deposit
//! loop), and compiled once per lane type; [`Simd`] — a value passed by the
//! caller of [`ParticleVolume::sample_batch_with`], not a global — picks the
//! instantiation through [`dispatch`]: portable `wide` lanes, or the whole
//! pass compiled for AVX2 behind the run-time check. Every lane operation is
//! one IEEE-rounded step on both, so the two backends give the same bits
//! (tested); measured in docs/benchmarks.md. An attempt to let LLVM
//! vectorise plain per-lane array code instead produced shuffle-heavy code
//! and was slower than both.

use std::marker::PhantomData;

use voxless_core::simd::{LANES, Lanes, Simd, WithLanes, dispatch};
use voxless_core::{Aabb, Attribute, Sample, SampleBatch, Vec3};

use super::ParticleVolume;
use crate::kernel::{Family, with_family};

/// Adds `x` to lanes `j..j + 8` of a padded buffer.
#[inline(always)]
fn add<L: Lanes>(v: &mut [f32], j: usize, x: L) {
    // One bounds check for the load and the store.
    let s = &mut v[j..j + LANES];
    (L::load(s, 0) + x).store(s, 0);
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
    /// Ray groups crossing the current cluster's box.
    groups: Vec<u32>,
}

impl Buffer {
    fn reset(&mut self, n: usize, attr: bool, color: bool, grad: bool) {
        // (`clusters` and `groups` are refilled by each pass.)
        let len = n + LANES;
        // The positions are all written before they are read (the padding
        // lanes are masked), so they only need the length: zeroing them
        // was a tenth of a shadowed frame's memory traffic.
        for v in [&mut self.px, &mut self.py, &mut self.pz] {
            v.resize(len, 0.0);
        }
        // The sums start at zero.
        for v in [&mut self.density, &mut self.covered] {
            v.clear();
            v.resize(len, 0.0);
        }
        self.attr.clear();
        self.attr.resize(if attr { len } else { 0 }, 0.0);
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

thread_local! {
    static BUFFER: std::cell::RefCell<Buffer> = std::cell::RefCell::new(Buffer::default());
}

/// Samples per unit t over sorted `ts` (0 for fewer than two samples).
fn inv_step(ts: &[f32]) -> f32 {
    match (ts.first(), ts.last()) {
        (Some(&a), Some(&b)) if ts.len() > 1 && b - a > 0.0 => (ts.len() - 1) as f32 / (b - a),
        _ => 0.0,
    }
}

/// The first index of sorted `ts` with `ts[j] ≥ x` (`strict`: `> x`),
/// walking from the guess `g`. Samples are nearly evenly spaced (jitter
/// restarts only at interval boundaries), so a guess from the mean spacing
/// is within a step or two — cheaper than a binary search, which dominated
/// the pass.
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

/// Fields of [`RayGroup`], one array of eight lanes each (scalar set-up).
const RAY_FIELDS: usize = 14;

/// Eight rays of a packet, structure of arrays, with their pass spans.
struct RayGroup<L> {
    ox: L,
    oy: L,
    oz: L,
    dx: L,
    dy: L,
    dz: L,
    inv_dd: L,
    /// 1 / direction, with zero components replaced by a tiny value so the
    /// slab test never computes 0·∞.
    ix: L,
    iy: L,
    iz: L,
    lo: L,
    hi: L,
    /// Samples per unit t (mean spacing⁻¹) and sample count, for the index
    /// guesses.
    inv_step: L,
    count: L,
}

/// The lanes of ray group `g` as plain arrays; padding lanes get an empty
/// span. Scalar code, apart from the lane type, so that the closures here
/// need no CPU features.
#[allow(clippy::needless_range_loop)] // lane k is column k of every field
fn group_arrays(batch: &SampleBatch, inv_steps: &[f32], g: usize) -> [[f32; LANES]; RAY_FIELDS] {
    let mut a = [[0.0f32; LANES]; RAY_FIELDS];
    for k in 0..LANES {
        let r = g * LANES + k;
        let ray_samples = batch.rays.get(r).map(|ray| (ray, batch.samples(r)));
        let Some((ray, s)) = ray_samples.filter(|(_, s)| !s.is_empty()) else {
            // Padding (or a ray without samples): unit inverse direction,
            // empty span [∞, −∞], so no chord ever meets it.
            for f in [7, 8, 9] {
                a[f][k] = 1.0;
            }
            (a[10][k], a[11][k]) = (f32::INFINITY, f32::NEG_INFINITY);
            continue;
        };
        let v = [
            ray.origin.x,
            ray.origin.y,
            ray.origin.z,
            ray.dir.x,
            ray.dir.y,
            ray.dir.z,
            1.0 / ray.dir.length_squared(),
            safe_inv(ray.dir.x),
            safe_inv(ray.dir.y),
            safe_inv(ray.dir.z),
            s[0],
            s[s.len() - 1],
            inv_steps[r],
            s.len() as f32,
        ];
        for (f, x) in v.into_iter().enumerate() {
            a[f][k] = x;
        }
    }
    a
}

impl<L: Lanes> RayGroup<L> {
    #[inline(always)]
    fn new(a: &[[f32; LANES]; RAY_FIELDS]) -> Self {
        let l = L::from_array;
        RayGroup {
            ox: l(a[0]),
            oy: l(a[1]),
            oz: l(a[2]),
            dx: l(a[3]),
            dy: l(a[4]),
            dz: l(a[5]),
            inv_dd: l(a[6]),
            ix: l(a[7]),
            iy: l(a[8]),
            iz: l(a[9]),
            lo: l(a[10]),
            hi: l(a[11]),
            inv_step: l(a[12]),
            count: l(a[13]),
        }
    }

    /// Whether any of the eight rays crosses box `b` within its pass span
    /// (padded for rounding).
    #[inline(always)]
    fn crosses(&self, b: &Aabb) -> bool {
        let s = L::splat;
        let tx0 = (s(b.min.x) - self.ox) * self.ix;
        let tx1 = (s(b.max.x) - self.ox) * self.ix;
        let ty0 = (s(b.min.y) - self.oy) * self.iy;
        let ty1 = (s(b.max.y) - self.oy) * self.iy;
        let tz0 = (s(b.min.z) - self.oz) * self.iz;
        let tz1 = (s(b.max.z) - self.oz) * self.iz;
        let pad = s(1e-4) * (self.lo.abs().min(s(1e30)) + s(1.0));
        let enter = tx0.min(tx1).max(ty0.min(ty1)).max(tz0.min(tz1));
        let exit = tx0.max(tx1).min(ty0.max(ty1)).min(tz0.max(tz1));
        let enter = enter.max(self.lo - pad);
        let exit = exit.min(self.hi + pad);
        enter.le(exit).any()
    }

    /// The chord `[lo, hi]` (in t) each ray cuts from the ball of squared
    /// radius `r2` around `c`, padded for rounding; bit `k` of the mask is
    /// set iff ray `k` meets the ball within its pass span; and, for those,
    /// first guesses at the sample indices of `lo` and `hi` from the mean
    /// spacing (one float → int conversion for eight rays).
    #[inline(always)]
    #[allow(clippy::type_complexity)]
    fn chord(&self, c: Vec3, r2: f32) -> ([f32; LANES], [f32; LANES], u32, [[i32; LANES]; 2]) {
        let s = L::splat;
        let ox = s(c.x) - self.ox;
        let oy = s(c.y) - self.oy;
        let oz = s(c.z) - self.oz;
        // Distance² from the line via the cross product (no cancellation).
        let cx = oy * self.dz - oz * self.dy;
        let cy = oz * self.dx - ox * self.dz;
        let cz = ox * self.dy - oy * self.dx;
        let b2 = (cx * cx + cy * cy + cz * cz) * self.inv_dd;
        let u = (ox * self.dx + oy * self.dy + oz * self.dz) * self.inv_dd;
        let r2 = s(r2);
        let h2 = (r2 - b2) * self.inv_dd;
        let h = h2.max(s(0.0)).sqrt() * s(1.001) + s(1e-5) * u.abs();
        let (lo, hi) = (u - h, u + h);
        let hit = b2.le(r2) & lo.le(self.hi) & hi.ge(self.lo);
        let bits = hit.bitmask();
        if bits == 0 {
            return ([0.0; LANES], [0.0; LANES], 0, [[0; LANES]; 2]);
        }
        // Index guesses, clamped to [0, count] (NaN → 0: `max` returns its
        // second operand) and truncated.
        let g_lo = ((lo - self.lo) * self.inv_step).max(s(0.0)).min(self.count);
        let g_hi = ((hi - self.lo) * self.inv_step).max(s(0.0)).min(self.count);
        (
            lo.to_array(),
            hi.to_array(),
            bits,
            [g_lo.trunc_i32(), g_hi.trunc_i32()],
        )
    }
}

/// One packet pass for kernel family `F`, run by [`dispatch`] on the lane
/// type the caller's [`Simd`] resolves to.
struct Pass<'a, F, const GRAD: bool> {
    vol: &'a ParticleVolume,
    colors: &'a [Vec3],
    batch: &'a SampleBatch<'a>,
    buf: &'a mut Buffer,
    out: &'a mut Vec<(Option<Sample>, Vec3)>,
    family: PhantomData<F>,
}

impl<F: Family, const GRAD: bool> WithLanes for Pass<'_, F, GRAD> {
    type Output = ();
    #[inline(always)]
    fn run<L: Lanes>(self) {
        self.vol
            .batch_in::<F, GRAD, L>(self.colors, self.batch, self.buf, self.out);
    }
}

impl ParticleVolume {
    /// The packet path with an explicit backend and pre-classified colours
    /// (empty: none).
    ///
    /// Fills `out` with one `(sample, gradient)` per sample of `batch`, in
    /// order, replacing what it held, as
    /// [`voxless_core::Volume::sample_batch`] does (the gradient is zero
    /// unless `gradient`). `colors` holds one colour per particle in volume
    /// order ([`ParticleVolume::positions`]); a slice of any other length is
    /// treated as empty (a documented clamp). `simd` picks the lane type
    /// ([`Simd::resolve`]: `Auto` is the best this CPU has, `Avx2` without
    /// AVX2 runs portable); every backend gives the same bits.
    pub fn sample_batch_with(
        &self,
        colors: &[Vec3],
        simd: Simd,
        batch: &SampleBatch,
        gradient: bool,
        out: &mut Vec<(Option<Sample>, Vec3)>,
    ) {
        out.clear();
        let colors = if colors.len() == self.packed.len() {
            colors
        } else {
            &[]
        };
        // Dispatch on the kernel family once; the pass is monomorphised.
        with_family!(self.settings.kernel, F => if gradient {
            self.batch::<F, true>(colors, simd, batch, out)
        } else {
            self.batch::<F, false>(colors, simd, batch, out)
        })
    }

    fn batch<F: Family, const GRAD: bool>(
        &self,
        colors: &[Vec3],
        simd: Simd,
        batch: &SampleBatch,
        out: &mut Vec<(Option<Sample>, Vec3)>,
    ) {
        BUFFER.with_borrow_mut(|buf| {
            let pass = Pass::<F, GRAD> {
                vol: self,
                colors,
                batch,
                buf,
                out,
                family: PhantomData,
            };
            dispatch(simd, pass);
        });
    }

    /// Adds particle `i` to buffer samples `j0..j1` (one ray's), eight at a
    /// time, each iff `|p − c|² ≤ R²`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn deposit<F: Family, const GRAD: bool, L: Lanes>(
        &self,
        colors: &[Vec3],
        buf: &mut Buffer,
        i: usize,
        j0: usize,
        j1: usize,
        attr: Option<&[f32]>,
    ) {
        let q = &self.packed[i];
        let s = L::splat;
        let (cx, cy, cz) = (s(q.center.x), s(q.center.y), s(q.center.z));
        let r2 = s(q.support2);
        let one = s(1.0);
        let mut j = j0;
        while j < j1 {
            // The first min(j1 − j, 8) lanes, from a table.
            let valid = L::first(j1 - j);
            let dx = L::load(&buf.px, j) - cx;
            let dy = L::load(&buf.py, j) - cy;
            let dz = L::load(&buf.pz, j) - cz;
            // The point query's own test, as (x² + y²) + z².
            let d2 = dx * dx + dy * dy + dz * dz;
            let inside = d2.le(r2) & valid;
            if inside.any() {
                let v = if GRAD {
                    let (v, g) = F::value_and_gradient_factor_simd(d2, q.shape, q.amp);
                    let g = g & inside;
                    add(&mut buf.grad[0], j, dx * g);
                    add(&mut buf.grad[1], j, dy * g);
                    add(&mut buf.grad[2], j, dz * g);
                    v
                } else {
                    F::value_simd(d2, q.shape, q.amp)
                };
                // Masked lanes add exactly zero.
                let v = v & inside;
                add(&mut buf.density, j, v);
                let cov = L::load(&buf.covered, j).max(one & inside);
                cov.store(&mut buf.covered, j);
                if let Some(a) = attr {
                    add(&mut buf.attr, j, v * s(a[i]));
                }
                if let Some(c) = colors.get(i) {
                    add(&mut buf.color[0], j, v * s(c.x));
                    add(&mut buf.color[1], j, v * s(c.y));
                    add(&mut buf.color[2], j, v * s(c.z));
                }
            }
            j += LANES;
        }
    }

    /// The pass on lanes `L`; called only through [`dispatch`] (so the AVX2
    /// instantiation is compiled inside its AVX2 entry function).
    #[inline(always)]
    fn batch_in<F: Family, const GRAD: bool, L: Lanes>(
        &self,
        colors: &[Vec3],
        batch: &SampleBatch,
        buf: &mut Buffer,
        out: &mut Vec<(Option<Sample>, Vec3)>,
    ) {
        let n_rays = batch.rays.len();
        let attr = self.attribute.as_deref();
        let pre = !colors.is_empty();
        buf.reset(batch.t.len(), attr.is_some(), pre, GRAD);
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
        // tested against eight rays at once. Samples per unit t of each ray,
        // for the index guesses, once per pass.
        let inv_steps: Vec<f32> = (0..n_rays).map(|r| inv_step(batch.samples(r))).collect();
        // (A plain loop: no closure around the lane constructors.)
        let mut rg: Vec<RayGroup<L>> = Vec::with_capacity(n_rays.div_ceil(LANES));
        for g in 0..n_rays.div_ceil(LANES) {
            rg.push(RayGroup::new(&group_arrays(batch, &inv_steps, g)));
        }
        let n = self.settings.cluster_size;
        let mut hit_groups = std::mem::take(&mut buf.groups);
        hit_groups.clear();
        hit_groups.resize(rg.len(), 0);
        // Collect first, so the loop below is compiled in this function
        // (with AVX2 when dispatched so), not inside the traversal.
        let mut clusters = std::mem::take(&mut buf.clusters);
        clusters.clear();
        self.bvh.box_query(&bounds, |c, b| clusters.push((c, *b)));
        for &(c, cbox) in &clusters {
            let start = c as usize * n;
            let end = (start + n).min(self.packed.len());
            // Which ray groups cross the cluster box at all: one slab test
            // per eight rays instead of a chord test per particle and ray.
            let mut ng = 0;
            for (g, rays) in rg.iter().enumerate() {
                if rays.crosses(&cbox) {
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
                    let (lo, hi, mut bits, guesses) = rg[g].chord(q.center, r2);
                    // Each ray whose chord meets its span: the samples in
                    // the chord, found by walking from the guesses.
                    while bits != 0 {
                        let k = bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        let r = g * LANES + k;
                        let ts = batch.samples(r);
                        let base = batch.offsets[r] as usize;
                        let j0 = base + walk(ts, lo[k], guesses[0][k], false);
                        let j1 = base + walk(ts, hi[k], guesses[1][k], true);
                        self.deposit::<F, GRAD, L>(colors, buf, i, j0, j1, attr);
                    }
                }
            }
        }
        buf.clusters = clusters;
        buf.groups = hit_groups;
        // The sums become samples as `to_sample` makes them, one loop per
        // kind of attribute over slices cut to the batch, so the loop
        // carries no bounds checks and no per-sample test of the kind (it
        // was a tenth of a shadowed frame).
        let n = batch.t.len();
        let (density, covered) = (&buf.density[..n], &buf.covered[..n]);
        let grad = |j: usize| {
            if GRAD {
                Vec3::new(buf.grad[0][j], buf.grad[1][j], buf.grad[2][j])
            } else {
                Vec3::ZERO
            }
        };
        if pre {
            let [r, g, b] = &buf.color;
            let (r, g, b) = (&r[..n], &g[..n], &b[..n]);
            emit(density, covered, grad, out, |j, d| {
                Attribute::Rgb(Vec3::new(r[j], g[j], b[j]) / d)
            });
        } else if attr.is_some() {
            let a = &buf.attr[..n];
            emit(density, covered, grad, out, |j, d| {
                let x = a[j] / d;
                if x.is_nan() {
                    Attribute::None
                } else {
                    Attribute::Scalar(x)
                }
            });
        } else {
            emit(density, covered, grad, out, |_, _| Attribute::None);
        }
    }
}

/// Appends the samples of a batch's sums to `out`: the sample where some
/// support covers it (its attribute from `attribute(j, density)` where the
/// density is positive, none elsewhere), and the gradient.
#[inline(always)]
fn emit(
    density: &[f32],
    covered: &[f32],
    grad: impl Fn(usize) -> Vec3,
    out: &mut Vec<(Option<Sample>, Vec3)>,
    attribute: impl Fn(usize, f32) -> Attribute,
) {
    let n = density.len().min(covered.len());
    out.extend((0..n).map(|j| {
        let d = density[j];
        let sample = (covered[j] > 0.0).then(|| Sample {
            value: d,
            attribute: if d > 0.0 {
                attribute(j, d)
            } else {
                Attribute::None
            },
        });
        (sample, grad(j))
    }));
}
