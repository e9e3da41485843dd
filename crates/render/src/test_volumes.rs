//! Procedural volumes the integrator tests share.

use voxless_core::{Aabb, Interval, IntervalQuery, Range1, Ray, Sample, Vec3, Volume};

voxless_core::prepare_as_self!(Blob);

/// A smooth Gaussian blob in [−1, 1]³, value in [0, 1].
pub(crate) struct Blob;

impl Volume for Blob {
    fn bounds(&self) -> Aabb {
        Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0))
    }
    fn value_range(&self) -> Range1 {
        Range1::new(0.0, 1.0)
    }
    fn sample(&self, p: Vec3) -> Option<Sample> {
        let q = p - Vec3::new(0.2, -0.1, 0.0);
        self.bounds()
            .contains(p)
            .then(|| Sample::scalar((-q.length_squared() / 0.35).exp()))
    }
    fn intervals(&self, ray: &Ray, t: Range1, _: &IntervalQuery, out: &mut Vec<Interval>) {
        let c = self.bounds().clip_ray(ray, t);
        if !c.is_empty() {
            out.push(Interval::sampled(c, Range1::new(0.0, 1.0), 0.02));
        }
    }
}

voxless_core::prepare_as_self!(BatchedBlob);

/// [`Blob`] claiming a packet path (the default `sample_batch`, which gives
/// exactly `sample`), so renders of it take the packet integrators.
pub(crate) struct BatchedBlob;

impl Volume for BatchedBlob {
    fn bounds(&self) -> Aabb {
        Blob.bounds()
    }
    fn value_range(&self) -> Range1 {
        Blob.value_range()
    }
    fn sample(&self, p: Vec3) -> Option<Sample> {
        Blob.sample(p)
    }
    fn packet_sampling(&self) -> bool {
        true
    }
    fn intervals(&self, ray: &Ray, t: Range1, q: &IntervalQuery, out: &mut Vec<Interval>) {
        Blob.intervals(ray, t, q, out)
    }
}
