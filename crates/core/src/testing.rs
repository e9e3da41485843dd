//! Test adapters and the contract every [`Volume`] honours (feature
//! `testing`), so a new data kind gets the same checks for free.
//!
//! Adapters turn a fast path off, so tests can compare it with the slow path
//! it replaces: [`PerRay`] hides a volume's tile view (integrators then ask
//! for intervals ray by ray) and [`Resampled`] makes every interval a
//! sampled one (integrators then step through constant pieces and look the
//! field up point by point, like any other volume).

use crate::camera::Camera;
use crate::control::{Cancelled, Control};
use crate::math::{Aabb, Range1, Ray, Vec3};
use crate::prepare::{Prepare, PrepareQuery};
use crate::tiles::{TileIntervals, View};
use crate::volume::{Interval, IntervalKind, IntervalQuery, Sample, SampleBatch, Volume};

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
