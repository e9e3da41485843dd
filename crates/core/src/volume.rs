//! The one seam between data kinds and integrators.
//!
//! A [`Volume`] answers point queries (value, attribute, gradient) and hands out
//! ray [`Interval`]s: non-overlapping, increasing in `t`, each with a conservative
//! `value_range`. Gaps between intervals are space the field is zero (or invisible)
//! in, so integrators skip them. Integrators are generic over `V: Volume` so the hot
//! loop is monomorphised; dispatch on the data kind happens once per frame.
//!
//! An interval is either *sampled* (the integrator steps through it) or
//! *constant* (the field is the same everywhere in it, so it is integrated in
//! closed form — tessellations, whose density is constant inside each tet).
//! A volume that hands out constant intervals hands out every non-zero piece,
//! visible or not, so a gap next to a constant interval means the field is
//! zero there (iso-surfaces are found at such gaps).
//!
//! Optional hooks with correct defaults let a kind go faster without a second
//! renderer: [`Volume::sample_batch`] (a packet of samples at once),
//! [`Volume::intervals_chunk`] (a ray's intervals front to back, a chunk at
//! a time, so nothing is found behind where a ray turns opaque),
//! [`Volume::tile_view`] (the intervals of a whole screen tile at once) and
//! [`Volume::project_image`] (a whole column-density image at once).

use crate::camera::Camera;
use crate::control::{Cancelled, Control};
use crate::math::{Range1, Ray, Vec3};
use crate::simd::{LANES, Lanes};
use crate::tiles::{TileIntervals, View};

/// A piece of a ray over which a volume is (possibly) non-zero.
///
/// Invariant: every value of the field at `ray.at(t)` for `t` in `self.t` lies
/// in `value_range`. Reporting a wider range is never wrong, only slower.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    pub t: Range1,
    pub value_range: Range1,
    /// The data's own length scale here (particles: a fraction of the support
    /// radius; AMR: the finest cell width). Integrators step a multiple of it.
    pub nominal_dt: f32,
    /// Opaque to integrators: the volume's own note on where this interval
    /// came from (AMR: the active brick region), handed back through
    /// [`Volume::sample_in`]. [`Interval::NO_HINT`] when unused.
    pub hint: u32,
    /// How the field varies over the interval.
    pub kind: IntervalKind,
}

/// How the field varies over an [`Interval`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum IntervalKind {
    /// Anything within `value_range`: integrators sample it.
    #[default]
    Sampled,
    /// Exactly `value_range.lo` (= `value_range.hi`) everywhere: integrators
    /// take it whole, in closed form, without sampling or jitter.
    Constant,
}

impl Interval {
    pub const NO_HINT: u32 = u32::MAX;

    /// A sampled interval without a hint.
    pub fn sampled(t: Range1, value_range: Range1, nominal_dt: f32) -> Self {
        Interval {
            t,
            value_range,
            nominal_dt,
            hint: Interval::NO_HINT,
            kind: IntervalKind::Sampled,
        }
    }

    /// An interval over which the field is `value` everywhere.
    pub fn constant(t: Range1, value: f32) -> Self {
        Interval {
            t,
            value_range: Range1::new(value, value),
            nominal_dt: t.span(),
            hint: Interval::NO_HINT,
            kind: IntervalKind::Constant,
        }
    }

    /// The field's value over a constant interval.
    #[inline]
    pub fn constant_value(&self) -> Option<f32> {
        match self.kind {
            IntervalKind::Constant => Some(self.value_range.lo),
            IntervalKind::Sampled => None,
        }
    }
}

/// What an integrator tells the volume about the intervals it wants.
pub struct IntervalQuery<'a> {
    /// Whether a value range can contribute to the image (the transfer function's
    /// maximum opacity over it is non-zero). Volumes drop invisible pieces and may
    /// merge adjacent visible ones. Must be monotone: a range that holds a
    /// visible range is visible (volumes skip a block whose union of ranges
    /// is invisible, and reuse answers for ranges that hold or lie in ones
    /// already asked about).
    pub is_visible: &'a (dyn Fn(Range1) -> bool + Sync),
}

impl IntervalQuery<'static> {
    /// Every non-empty piece is wanted (projections, references).
    pub fn all() -> Self {
        IntervalQuery {
            is_visible: &|_| true,
        }
    }
}

/// The attribute part of a sample, if the volume carries one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Attribute {
    None,
    /// A scalar attribute field (post-classification: average, then colour-map).
    Scalar(f32),
    /// An already classified colour (pre-classification: colour-map each
    /// element, then average), linear RGB.
    Rgb(Vec3),
}

/// The field at a point: the scalar that drives opacity, plus an optional attribute.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    pub value: f32,
    pub attribute: Attribute,
}

impl Sample {
    pub fn scalar(value: f32) -> Self {
        Sample {
            value,
            attribute: Attribute::None,
        }
    }
}

/// How a projection integrates each pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PixelIntegral {
    /// The column density along the line through the pixel's centre.
    #[default]
    Centre,
    /// The column density averaged over the pixel's square, so that
    /// Σ pixels × pixel area is the mass in view at every resolution:
    /// tessellations integrate each tet's column exactly over the square,
    /// particles each kernel's (see the particle crate's `kernel::area`).
    /// Orthographic projections of whole lines of sight.
    Area,
}

/// A renderable field. See the module docs for the contract.
///
/// A new hook must be added to [`forward_volume!`](crate::forward_volume)
/// too, which writes the forwarding of every hook for `&V` and the
/// prepared contexts (a context that did not forward it would fall back
/// to the default and lose the volume's fast path), and to the hooks the
/// contract suite knows (`testing::HOOKS`; a capability — whether a fast
/// path is there — with a `testing::Hook` that `check_same_hooks`
/// compares between a context and its volume). A test of `testing` fails
/// until both are done.
pub trait Volume: Send + Sync {
    /// Where the field can be non-zero.
    fn bounds(&self) -> crate::Aabb;

    /// The range of the opacity-driving field over the whole volume (used to
    /// normalise it for the transfer function unless the user overrides it).
    fn value_range(&self) -> Range1;

    /// The range of the scalar attribute, if there is one.
    fn attribute_range(&self) -> Option<Range1> {
        None
    }

    /// Field value(s) at `p`, or `None` where no data covers `p`.
    fn sample(&self, p: Vec3) -> Option<Sample>;

    /// Gradient of the value field. The default is central differences with a
    /// step of 1e-4 of the bounds diagonal; data kinds override it analytically.
    fn gradient(&self, p: Vec3) -> Vec3 {
        let h = (self.bounds().diagonal() * 1e-4).max(f32::MIN_POSITIVE);
        let f = |q: Vec3| self.sample(q).map_or(0.0, |s| s.value);
        let d = |e: Vec3| (f(p + e * h) - f(p - e * h)) / (2.0 * h);
        Vec3::new(
            d(Vec3::new(1.0, 0.0, 0.0)),
            d(Vec3::new(0.0, 1.0, 0.0)),
            d(Vec3::new(0.0, 0.0, 1.0)),
        )
    }

    /// Sample and gradient together; override when one pass yields both.
    fn sample_with_gradient(&self, p: Vec3) -> Option<(Sample, Vec3)> {
        self.sample(p).map(|s| (s, self.gradient(p)))
    }

    /// [`Volume::sample`] at a point `p` inside `interval` (one this volume
    /// handed out). Volumes that can use the interval's hint to skip a lookup
    /// override it; the default ignores the interval.
    fn sample_in(&self, p: Vec3, interval: &Interval) -> Option<Sample> {
        let _ = interval;
        self.sample(p)
    }

    /// [`Volume::sample_with_gradient`] at a point inside `interval`.
    fn sample_with_gradient_in(&self, p: Vec3, interval: &Interval) -> Option<(Sample, Vec3)> {
        let _ = interval;
        self.sample_with_gradient(p)
    }

    /// Whether samples come classified: `value` is then the opacity itself
    /// (the transfer function's output, before `opacity_scale`) and the
    /// attribute an [`Attribute::Rgb`] colour, so integrators skip the
    /// transfer function (multi-material volumes classify each material with
    /// its own). Interval value ranges are then opacity ranges.
    fn classified(&self) -> bool {
        false
    }

    /// Whether [`Volume::sample_batch`] is a real packet path (faster than
    /// sampling point by point). Integrators use it only then.
    fn packet_sampling(&self) -> bool {
        false
    }

    /// [`Volume::sample_batch`] for integrators that read a plain value and
    /// nothing else: `out` (sized, not cleared, as there) ends up holding
    /// each sample's value, NaN where no data covers the point. Returns
    /// false, leaving `out` alone, where samples carry more than a value
    /// (an attribute) or the volume has no such path; the caller then uses
    /// [`Volume::sample_batch`]. Where it returns true the values are
    /// exactly those of [`Volume::sample_batch`].
    fn sample_batch_values(&self, _batch: &SampleBatch, _out: &mut Vec<f32>) -> bool {
        false
    }

    /// Whether [`Volume::sample_values_lanes`] is a real lane path: the
    /// renderer then marches eight rays in SIMD lanes, one sample per ray
    /// per step, where it composites plain values.
    fn samples_in_lanes(&self) -> bool {
        false
    }

    /// The plain values at eight points at once, one per lane: lane `k`'s
    /// point `(p[0][k], p[1][k], p[2][k])` (world) lies in the interval
    /// whose [`Interval::hint`] is `hints[k]`. Lanes whose bit is set in
    /// `live` get exactly the value [`Volume::sample_in`] gives there, NaN
    /// where no data covers the point; the others are NaN. The default
    /// samples point by point.
    #[inline(always)]
    fn sample_values_lanes<L: Lanes>(&self, hints: &[u32; LANES], p: [L; 3], live: u32) -> L {
        let [x, y, z] = p.map(L::to_array);
        let mut out = [f32::NAN; LANES];
        for (k, v) in out.iter_mut().enumerate() {
            if live >> k & 1 != 0 {
                let iv = Interval {
                    hint: hints[k],
                    ..Interval::sampled(Range1::EMPTY, Range1::EMPTY, 1.0)
                };
                let at = Vec3::new(x[k], y[k], z[k]);
                *v = self.sample_in(at, &iv).map_or(f32::NAN, |s| s.value);
            }
        }
        L::from_array(out)
    }

    /// Samples every point of a packet at once: `out` — the caller's buffer,
    /// holding whatever an earlier batch left there — ends up holding, for
    /// each `t` of `batch` in order, the sample at `rays[r].at(t)` (`None`
    /// where no data covers it) and, when `gradient`, the gradient there
    /// (zero otherwise): exactly that many elements. (The caller does not
    /// clear it, so a volume that writes its results out of order can size
    /// it without filling it first.) A packet path must give exactly what
    /// [`Volume::sample`]/[`Volume::sample_with_gradient`] give; the default
    /// is that slow path.
    fn sample_batch(
        &self,
        batch: &SampleBatch,
        gradient: bool,
        out: &mut Vec<(Option<Sample>, Vec3)>,
    ) {
        out.clear();
        for (r, ray) in batch.rays.iter().enumerate() {
            for &t in batch.samples(r) {
                let p = ray.at(t);
                out.push(if gradient {
                    match self.sample_with_gradient(p) {
                        Some((s, g)) => (Some(s), g),
                        None => (None, Vec3::ZERO),
                    }
                } else {
                    (self.sample(p), Vec3::ZERO)
                });
            }
        }
    }

    /// Append the intervals of `ray` within `t` to `out` (which the caller
    /// clears), in increasing `t`, non-overlapping.
    fn intervals(&self, ray: &Ray, t: Range1, query: &IntervalQuery, out: &mut Vec<Interval>);

    /// [`Volume::intervals`] a chunk at a time, front to back: appends the
    /// first intervals of `ray` within `t` to `out` — stopping after `max`
    /// of them where the volume can — and returns where the rest begins,
    /// `None` once everything is given. Asking again from there
    /// (`Range1::new(rest, t.hi)`) appends the next ones, and the chunks
    /// together are exactly the list [`Volume::intervals`] gives for `t`
    /// (a returned `rest` lies past the start of what was asked for).
    ///
    /// Integrators ask for the next chunk only while a ray is not opaque,
    /// so a volume that finds its intervals in order (AMR: a front-to-back
    /// walk of its region tree) does no work behind the point where a ray
    /// terminates. The default gives the whole list at once.
    fn intervals_chunk(
        &self,
        ray: &Ray,
        t: Range1,
        query: &IntervalQuery,
        out: &mut Vec<Interval>,
        max: usize,
    ) -> Option<f32> {
        let _ = max;
        self.intervals(ray, t, query, out);
        None
    }

    /// A faster way to get the intervals of every ray of a screen tile at
    /// once, prepared for one camera and image size (tessellations: each
    /// tet rasterised once per tile, every pixel's crossings sorted). `None`
    /// (the default): integrators call [`Volume::intervals`] per ray. The
    /// lists must equal what [`Volume::intervals`] gives, up to a stated
    /// tolerance.
    fn tile_view(&self, view: &View) -> Option<Box<dyn TileIntervals + '_>> {
        let _ = view;
        None
    }

    /// A faster way to compute a whole column-density image (`∫ value dt`
    /// through every pixel centre, row-major, row 0 at the top). `None` (the
    /// default): integrators call [`Volume::line_integral`] per pixel. Must
    /// report progress and stop when `control` is cancelled.
    fn project_image(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        control: &Control,
    ) -> Option<Result<Vec<f32>, Cancelled>> {
        let _ = (camera, width, height, control);
        None
    }

    /// ∫ value dt along `ray` over `t`. The default is composite Simpson
    /// quadrature over the intervals with 16 panels per `nominal_dt` — the slow
    /// path; data kinds with a closed form override it.
    fn line_integral(&self, ray: &Ray, t: Range1) -> f64 {
        quadrature_line_integral(self, ray, t)
    }
}

/// A packet of rays and the sample positions along each: a sample buffer to
/// fill in one go (CPU RBF paper §4).
#[derive(Clone, Copy, Debug)]
pub struct SampleBatch<'a> {
    pub rays: &'a [Ray],
    /// The samples of ray `r` are `t[offsets[r]..offsets[r + 1]]`, increasing.
    pub offsets: &'a [u32],
    pub t: &'a [f32],
    /// Per sample (in the order of `t`), the [`Interval::hint`] of the
    /// interval it lies in, when the caller knows it: a volume may use it
    /// as [`Volume::sample_in`] does. `None`: unknown.
    pub hints: Option<&'a [u32]>,
}

impl SampleBatch<'_> {
    /// The sample parameters of ray `r`.
    #[inline]
    pub fn samples(&self, r: usize) -> &[f32] {
        &self.t[self.offsets[r] as usize..self.offsets[r + 1] as usize]
    }
}

/// The default [`Volume::line_integral`]: composite Simpson quadrature over
/// the volume's intervals with 16 panels per `nominal_dt`. Public so that
/// volumes whose exact integral covers only some modes can fall back to it.
pub fn quadrature_line_integral<V: Volume + ?Sized>(volume: &V, ray: &Ray, t: Range1) -> f64 {
    let mut intervals = Vec::new();
    volume.intervals(ray, t, &IntervalQuery::all(), &mut intervals);
    intervals
        .iter()
        .map(|iv| {
            if let Some(v) = iv.constant_value() {
                // Constant: the integral is exact.
                return v as f64 * iv.t.span() as f64;
            }
            let f = |t: f64| {
                volume
                    .sample_in(ray.at(t as f32), iv)
                    .map_or(0.0, |s| s.value as f64)
            };
            let (a, b) = (iv.t.lo as f64, iv.t.hi as f64);
            let panels = (((b - a) / iv.nominal_dt as f64) * 16.0).ceil().max(2.0) as usize;
            simpson(f, a, b, panels + panels % 2)
        })
        .sum()
}

/// Composite Simpson rule with `n` (even) panels.
pub fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let h = (b - a) / n as f64;
    let mut sum = f(a) + f(b);
    for i in 1..n {
        let w = if i % 2 == 1 { 4.0 } else { 2.0 };
        sum += w * f(a + i as f64 * h);
    }
    sum * h / 3.0
}

/// A borrowed volume is a volume: prepared contexts that need nothing of
/// their own are plain references ([`crate::Prepare`]). Every method
/// forwards, so a volume's overrides are kept.
impl<V: Volume + ?Sized> Volume for &V {
    crate::forward_volume!(to * self);
}
