//! Test adapters and the contract every [`Volume`] honours (feature
//! `testing`), so a new data kind gets the same checks for free; and
//! [`check_same_hooks`], whether a prepared context offers the hooks its
//! volume offers.
//!
//! Adapters turn a fast path off, so tests can compare it with the slow path
//! it replaces: [`PerRay`] hides a volume's tile view (integrators then ask
//! for intervals ray by ray) and [`Resampled`] makes every interval a
//! sampled one (integrators then step through constant pieces and look the
//! field up point by point, like any other volume).
//!
//! Every test of the workspace that needs something a machine may lack (the
//! real data beside the checkout, `mpirun`, a browser, the HDF5 feature)
//! asks [`prerequisite`] or [`shared_data`]: absent, the test skips with a
//! notice — or fails, where CI installed the prerequisite and says so.

use crate::camera::Camera;
use crate::control::{Cancelled, Control};
use crate::math::{Aabb, Range1, Ray, Vec3};
use crate::prepare::{Prepare, PrepareQuery};
use crate::simd::{LANES, Lanes, WithLanes};
use crate::tiles::{TileIntervals, View};
use crate::volume::{Interval, IntervalKind, IntervalQuery, Sample, SampleBatch, Volume};

mod hooks;
mod prerequisites;
pub use hooks::{HOOKS, Hook, assert_same_hooks, check_same_hooks};
pub use prerequisites::{prerequisite, shared_data};

/// Forwards every method of `V` but [`Volume::tile_view`]: intervals come
/// ray by ray.
pub struct PerRay<V>(pub V);

/// Forwards every method of `V`, but every interval is sampled (a constant
/// interval becomes a sampled one with `step` as its nominal step).
pub struct Resampled<V> {
    pub volume: V,
    pub step: f32,
}

macro_rules! forward_common {
    ($f:tt) => {
        fn bounds(&self) -> Aabb {
            self.$f.bounds()
        }
        fn value_range(&self) -> Range1 {
            self.$f.value_range()
        }
        fn attribute_range(&self) -> Option<Range1> {
            self.$f.attribute_range()
        }
        fn sample(&self, p: Vec3) -> Option<Sample> {
            self.$f.sample(p)
        }
        fn gradient(&self, p: Vec3) -> Vec3 {
            self.$f.gradient(p)
        }
        fn sample_with_gradient(&self, p: Vec3) -> Option<(Sample, Vec3)> {
            self.$f.sample_with_gradient(p)
        }
        fn classified(&self) -> bool {
            self.$f.classified()
        }
        fn packet_sampling(&self) -> bool {
            self.$f.packet_sampling()
        }
        fn sample_batch(
            &self,
            batch: &SampleBatch,
            gradient: bool,
            out: &mut Vec<(Option<Sample>, Vec3)>,
        ) {
            self.$f.sample_batch(batch, gradient, out)
        }
        fn line_integral(&self, ray: &Ray, t: Range1) -> f64 {
            self.$f.line_integral(ray, t)
        }
    };
}

impl<V: Volume> Volume for PerRay<V> {
    forward_common!(0);
    fn sample_in(&self, p: Vec3, iv: &Interval) -> Option<Sample> {
        self.0.sample_in(p, iv)
    }
    fn sample_with_gradient_in(&self, p: Vec3, iv: &Interval) -> Option<(Sample, Vec3)> {
        self.0.sample_with_gradient_in(p, iv)
    }
    fn intervals(&self, ray: &Ray, t: Range1, query: &IntervalQuery, out: &mut Vec<Interval>) {
        self.0.intervals(ray, t, query, out)
    }
    fn project_image(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        control: &Control,
    ) -> Option<Result<Vec<f32>, Cancelled>> {
        self.0.project_image(camera, width, height, control)
    }
}

impl<V: Volume> Volume for Resampled<V> {
    forward_common!(volume);
    fn intervals(&self, ray: &Ray, t: Range1, query: &IntervalQuery, out: &mut Vec<Interval>) {
        let start = out.len();
        self.volume.intervals(ray, t, query, out);
        for iv in &mut out[start..] {
            if iv.kind == IntervalKind::Constant {
                iv.kind = IntervalKind::Sampled;
                iv.nominal_dt = self.step;
                // Point samples see the field, not the interval's hint.
                iv.hint = Interval::NO_HINT;
            }
        }
    }
    fn tile_view(&self, _: &View) -> Option<Box<dyn TileIntervals + '_>> {
        None
    }
}

/// Adapters around a prepared context are themselves prepared.
impl<V: Volume> Prepare for PerRay<V> {
    type Prepared<'a>
        = &'a PerRay<V>
    where
        Self: 'a;
    fn prepare<'a>(&'a self, _: &PrepareQuery) -> &'a PerRay<V> {
        self
    }
}

impl<V: Volume> Prepare for Resampled<V> {
    type Prepared<'a>
        = &'a Resampled<V>
    where
        Self: 'a;
    fn prepare<'a>(&'a self, _: &PrepareQuery) -> &'a Resampled<V> {
        self
    }
}

/// What [`check_contract`] tries, and how closely.
#[derive(Clone, Debug)]
pub struct Contract {
    /// Random rays through the bounds.
    pub rays: usize,
    pub seed: u64,
    /// Points sampled per interval.
    pub samples_per_interval: usize,
    /// Relative tolerance of sample values against their interval's range
    /// (rounding in the volume's sums).
    pub range_tolerance: f32,
    /// Gradients against central differences of `sample`: the step (a
    /// fraction of the bounds' diagonal) and the relative tolerance that
    /// at least 90 % of the points must meet; `None` skips the check (a
    /// field whose gradient is not the derivative of its samples, e.g. a
    /// piecewise-constant one).
    pub gradient: Option<(f32, f32)>,
    /// Relative tolerance of `line_integral` against Simpson quadrature of
    /// the samples over the intervals (with an absolute floor of 1 % of
    /// this times the largest integral seen); `None` skips the check: a
    /// classified volume (samples are opacities, projections integrate
    /// densities), or a prepared context whose intervals leave out what its
    /// transfer function hides (projections use the volume itself).
    pub integral_tolerance: Option<f64>,
    /// The share of samples in constant intervals allowed to differ from
    /// the interval's value: a point lookup that nudges its point off
    /// shared faces (tessellations) sees the neighbouring piece when a face
    /// passes within the nudge.
    pub constant_mismatch_share: f32,
}

impl Default for Contract {
    fn default() -> Self {
        Contract {
            rays: 64,
            seed: 1,
            samples_per_interval: 5,
            range_tolerance: 1e-4,
            gradient: Some((1e-4, 2e-2)),
            integral_tolerance: Some(1e-3),
            constant_mismatch_share: 0.0,
        }
    }
}

/// Checks `volume` against the seam's contract on random rays through its
/// bounds; returns every violation found (empty: it holds):
///
/// 1. intervals are non-empty, inside the asked range, sorted and disjoint;
/// 2. samples inside an interval lie within its value range (a constant
///    interval's samples equal its value);
/// 3. [`Volume::sample_batch`] equals [`Volume::sample`] (and the gradients
///    of `sample_with_gradient`) at the same points;
/// 4. gradients agree with central differences of the samples;
/// 5. [`Volume::line_integral`] agrees with quadrature of the samples;
/// 6. where offered, [`Volume::sample_values_lanes`] gives the values of
///    [`Volume::sample_in`], bit for bit, on every SIMD backend.
pub fn check_contract<V: Volume>(volume: &V, c: &Contract) -> Vec<String> {
    let mut bad = Vec::new();
    let b = volume.bounds();
    if b.is_empty() {
        return vec!["bounds are empty".into()];
    }
    let mut rng = crate::SmallRng(c.seed);
    let point = |rng: &mut crate::SmallRng| {
        Vec3::new(
            b.min.x + rng.f() * (b.max.x - b.min.x),
            b.min.y + rng.f() * (b.max.y - b.min.y),
            b.min.z + rng.f() * (b.max.z - b.min.z),
        )
    };
    let mut integrals = Vec::new();
    let (mut constant_samples, mut constant_misses) = (0usize, Vec::new());
    let mut lane_points = Vec::new();
    let mut batch_rays = Vec::new();
    let mut batch_t = Vec::new();
    let mut offsets = vec![0u32];
    for r in 0..c.rays {
        // A ray from outside the bounds through a random inner point.
        let target = point(&mut rng);
        let dir = Vec3::new(rng.f() - 0.5, rng.f() - 0.5, rng.f() - 0.5).normalized();
        if !dir.is_finite() || dir.length_squared() < 0.5 {
            continue;
        }
        let ray = Ray::new(target - dir * (2.0 * b.diagonal()), dir);
        let t = b.clip_ray(&ray, Range1::new(0.0, f32::INFINITY));
        if t.is_empty() {
            continue;
        }
        let mut ivs = Vec::new();
        volume.intervals(&ray, t, &IntervalQuery::all(), &mut ivs);
        // 1. Intervals: non-empty, inside t, sorted, disjoint.
        let slack = 1e-5 * (t.hi.abs() + 1.0);
        let mut prev_end = f32::NEG_INFINITY;
        for iv in &ivs {
            if !(iv.t.hi > iv.t.lo) {
                bad.push(format!("ray {r}: empty interval {:?}", iv.t));
            }
            if iv.t.lo < t.lo - slack || iv.t.hi > t.hi + slack {
                bad.push(format!("ray {r}: interval {:?} outside {t:?}", iv.t));
            }
            if iv.t.lo < prev_end - slack {
                bad.push(format!(
                    "ray {r}: interval {:?} overlaps or is unsorted",
                    iv.t
                ));
            }
            prev_end = iv.t.hi;
        }
        // 2. Samples within the value range.
        let mut ts = Vec::new();
        for iv in &ivs {
            // A constant piece a few ulps of t long is rounding between
            // neighbouring pieces' ends, not a place to sample.
            if iv.constant_value().is_some() && iv.t.span() <= 4.0 * f32::EPSILON * iv.t.hi.abs() {
                continue;
            }
            for k in 0..c.samples_per_interval {
                let tt = iv.t.lo + (k as f32 + 0.5) / c.samples_per_interval as f32 * iv.t.span();
                let Some(s) = volume.sample_in(ray.at(tt), iv) else {
                    continue;
                };
                let tol = c.range_tolerance * iv.value_range.hi.abs().max(iv.value_range.lo.abs())
                    + f32::MIN_POSITIVE;
                if let Some(v) = iv.constant_value() {
                    constant_samples += 1;
                    if (s.value - v).abs() > tol.max(c.range_tolerance * v.abs()) {
                        constant_misses.push(format!(
                            "ray {r}: sample {} in constant interval of value {v}",
                            s.value
                        ));
                    }
                } else if s.value < iv.value_range.lo - tol || s.value > iv.value_range.hi + tol {
                    bad.push(format!(
                        "ray {r}: sample {} outside its interval's range {:?}",
                        s.value, iv.value_range
                    ));
                }
                ts.push(tt);
                if iv.constant_value().is_none() && lane_points.len() < 4096 {
                    lane_points.push((ray.at(tt), *iv));
                }
            }
        }
        if !ts.is_empty() && batch_rays.len() < 16 {
            batch_rays.push(ray);
            batch_t.extend_from_slice(&ts);
            offsets.push(batch_t.len() as u32);
        }
        // 5. Line integral against quadrature.
        let exact = volume.line_integral(&ray, t);
        let quad = crate::quadrature_line_integral(volume, &ray, t);
        integrals.push((r, exact, quad));
    }
    if constant_misses.len() as f32 > c.constant_mismatch_share * constant_samples as f32 {
        bad.extend(constant_misses);
    }
    let scale = integrals
        .iter()
        .map(|x| x.1.abs().max(x.2.abs()))
        .fold(0.0f64, f64::max);
    for (r, exact, quad) in integrals {
        let Some(tol) = c.integral_tolerance else {
            break;
        };
        if (exact - quad).abs() > tol * (quad.abs() + scale * 1e-2) {
            bad.push(format!(
                "ray {r}: line integral {exact} vs quadrature {quad}"
            ));
        }
    }
    // 3. The batch path against point samples.
    let batch = SampleBatch {
        rays: &batch_rays,
        offsets: &offsets,
        t: &batch_t,
        hints: None,
    };
    for gradient in [false, true] {
        // What an earlier batch left in the caller's buffer (longer than
        // this batch, and wrong): every element must be replaced.
        let stale = (Some(Sample::scalar(f32::NAN)), Vec3::splat(f32::NAN));
        let mut out = vec![stale; batch_t.len() + 5];
        volume.sample_batch(&batch, gradient, &mut out);
        if out.len() != batch_t.len() {
            bad.push(format!(
                "sample_batch gave {} samples for {}",
                out.len(),
                batch_t.len()
            ));
            continue;
        }
        let mut j = 0;
        for (ri, ray) in batch_rays.iter().enumerate() {
            for &tt in batch.samples(ri) {
                let p = ray.at(tt);
                let (want, want_g) = if gradient {
                    match volume.sample_with_gradient(p) {
                        Some((s, g)) => (Some(s), g),
                        None => (None, Vec3::ZERO),
                    }
                } else {
                    (volume.sample(p), Vec3::ZERO)
                };
                let (got, got_g) = out[j];
                j += 1;
                let close = |a: f32, b: f32| (a - b).abs() <= 1e-4 * a.abs().max(b.abs()) + 1e-6;
                match (got, want) {
                    (None, None) => {}
                    (Some(a), Some(b)) if close(a.value, b.value) => {
                        let gmax = want_g.length().max(got_g.length());
                        if gradient && (got_g - want_g).length() > 1e-3 * gmax + 1e-6 {
                            bad.push(format!(
                                "sample_batch gradient {got_g:?} vs {want_g:?} at {p:?}"
                            ));
                        }
                    }
                    _ => bad.push(format!("sample_batch {got:?} vs sample {want:?} at {p:?}")),
                }
            }
        }
    }
    // 6. Eight samples in lanes against point samples in their intervals,
    // bit for bit, on every SIMD backend.
    if volume.samples_in_lanes() {
        for simd in crate::Simd::ALL.into_iter().filter(|s| s.available()) {
            let got = crate::simd::dispatch(
                simd,
                LaneSamples {
                    volume,
                    points: &lane_points,
                },
            );
            for (k, ((p, iv), v)) in lane_points.iter().zip(got).enumerate() {
                let want = volume.sample_in(*p, iv).map_or(f32::NAN, |s| s.value);
                // Every third group leaves its last lane out (NaN).
                let out = k % (3 * LANES) == 3 * LANES - 1;
                let same = v.to_bits() == want.to_bits() || (v.is_nan() && (out || want.is_nan()));
                if !same {
                    bad.push(format!(
                        "sample_values_lanes ({simd:?}) gave {v}, sample_in {want} at {p:?}"
                    ));
                }
            }
        }
    }
    // 4. Gradients against central differences.
    if let Some((step, tol)) = c.gradient {
        let h = step * b.diagonal();
        let (mut tried, mut ok) = (0, 0);
        for _ in 0..4 * c.rays {
            let p = point(&mut rng);
            let f = |q: Vec3| volume.sample(q).map(|s| s.value);
            let Some(v0) = f(p) else { continue };
            let axis = [
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(0.0, 0.0, 1.0),
            ];
            let fd: Option<Vec<f32>> = axis
                .iter()
                .map(|&e| Some((f(p + e * h)? - f(p - e * h)?) / (2.0 * h)))
                .collect();
            let Some(fd) = fd else { continue };
            let fd = Vec3::new(fd[0], fd[1], fd[2]);
            let g = volume.gradient(p);
            if fd.length() < 1e-3 * (v0.abs() / b.diagonal()) {
                continue; // flat: relative errors mean nothing there
            }
            tried += 1;
            if (g - fd).length() <= tol * fd.length() {
                ok += 1;
            }
        }
        if tried > 0 && (ok as f32) < 0.9 * tried as f32 {
            bad.push(format!(
                "gradients match central differences at only {ok} of {tried} points"
            ));
        }
    }
    bad
}

/// Points sampled eight at a time with [`Volume::sample_values_lanes`]
/// (each with its interval's hint), every third group with its last lane
/// left out.
struct LaneSamples<'a, V> {
    volume: &'a V,
    points: &'a [(Vec3, Interval)],
}

impl<V: Volume> WithLanes for LaneSamples<'_, V> {
    type Output = Vec<f32>;
    #[inline(always)]
    fn run<L: Lanes>(self) -> Vec<f32> {
        let mut out = Vec::with_capacity(self.points.len());
        for (g, group) in self.points.chunks(LANES).enumerate() {
            let (mut hints, mut p) = ([Interval::NO_HINT; LANES], [[0.0; LANES]; 3]);
            for (k, (q, iv)) in group.iter().enumerate() {
                hints[k] = iv.hint;
                (p[0][k], p[1][k], p[2][k]) = (q.x, q.y, q.z);
            }
            let mut live = (1u32 << group.len()) - 1;
            if g % 3 == 2 {
                live &= !(1 << (LANES - 1));
            }
            let p = [
                L::from_array(p[0]),
                L::from_array(p[1]),
                L::from_array(p[2]),
            ];
            let v = self.volume.sample_values_lanes::<L>(&hints, p, live);
            out.extend_from_slice(&v.to_array()[..group.len()]);
        }
        out
    }
}

/// Panics listing the violations of [`check_contract`], if any.
pub fn assert_contract<V: Volume>(name: &str, volume: &V, c: &Contract) {
    let bad = check_contract(volume, c);
    assert!(
        bad.is_empty(),
        "{name} breaks the Volume contract ({} violations):\n{}",
        bad.len(),
        bad.iter().take(12).cloned().collect::<Vec<_>>().join("\n")
    );
}
