//! [`AmrContext`]: an AMR volume prepared for one transfer function — the
//! regions it can see and a BVH over only those (TF space skipping,
//! ExaBricks §4.1), so rays skip hidden regions without visiting them.
//! The volume itself stays untouched, so several contexts (different
//! transfer functions) can render it at once.

use std::time::{Duration, Instant};

use voxless_bvh::Bvh;
use voxless_core::{
    Aabb, Camera, Cancelled, Control, Interval, IntervalQuery, Prepare, PrepareQuery, Range1, Ray,
    Sample, Vec3, Volume,
};

use crate::AmrVolume;

pub struct AmrContext<'a> {
    volume: &'a AmrVolume,
    /// The visible regions; `None` when every region is visible (then the
    /// volume's own tree serves).
    visible: Option<(Vec<u32>, Bvh)>,
    selected_in: Duration,
}

impl<'a> AmrContext<'a> {
    /// Selects the regions whose range of the opacity field `is_visible`
    /// accepts and builds a BVH over them.
    pub fn new(volume: &'a AmrVolume, is_visible: &dyn Fn(Range1) -> bool) -> Self {
        let t = Instant::now();
        let ids = volume.visible_regions(is_visible);
        let visible = (ids.len() < volume.regions().len()).then(|| {
            let boxes: Vec<Aabb> = ids
                .iter()
                .map(|&r| volume.region_bounds(r as usize))
                .collect();
            // Regions keep the k-d order of the full tree: already coherent.
            let bvh = Bvh::build_in_order(&boxes);
            (ids, bvh)
        });
        AmrContext {
            volume,
            visible,
            selected_in: t.elapsed(),
        }
    }

    /// How many regions the transfer function can see.
    pub fn visible_region_count(&self) -> usize {
        self.visible
            .as_ref()
            .map_or(self.volume.regions().len(), |v| v.0.len())
    }

    /// How long selecting the regions and building their BVH took.
    pub fn selected_in(&self) -> Duration {
        self.selected_in
    }

    pub fn volume(&self) -> &AmrVolume {
        self.volume
    }
}

impl Prepare for AmrVolume {
    type Prepared<'a> = AmrContext<'a>;

    fn prepare<'a>(&'a self, query: &PrepareQuery) -> AmrContext<'a> {
        AmrContext::new(self, query.is_visible)
    }
}

impl Volume for AmrContext<'_> {
    fn bounds(&self) -> Aabb {
        self.volume.bounds()
    }
    fn value_range(&self) -> Range1 {
        self.volume.value_range()
    }
    fn attribute_range(&self) -> Option<Range1> {
        self.volume.attribute_range()
    }
    fn sample(&self, p: Vec3) -> Option<Sample> {
        self.volume.sample(p)
    }
    fn gradient(&self, p: Vec3) -> Vec3 {
        self.volume.gradient(p)
    }
    fn sample_with_gradient(&self, p: Vec3) -> Option<(Sample, Vec3)> {
        self.volume.sample_with_gradient(p)
    }
    fn sample_in(&self, p: Vec3, iv: &Interval) -> Option<Sample> {
        self.volume.sample_in(p, iv)
    }
    fn sample_with_gradient_in(&self, p: Vec3, iv: &Interval) -> Option<(Sample, Vec3)> {
        self.volume.sample_with_gradient_in(p, iv)
    }
    /// Only the visible regions' tree is traversed.
    fn intervals(&self, ray: &Ray, t: Range1, query: &IntervalQuery, out: &mut Vec<Interval>) {
        match &self.visible {
            Some((ids, bvh)) => self
                .volume
                .region_intervals(bvh, Some(ids), ray, t, query, out),
            None => {
                self.volume
                    .region_intervals(self.volume.region_bvh(), None, ray, t, query, out)
            }
        }
    }
    fn line_integral(&self, ray: &Ray, t: Range1) -> f64 {
        self.volume.line_integral(ray, t)
    }
    fn project_image(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        control: &Control,
    ) -> Option<Result<Vec<f32>, Cancelled>> {
        self.volume.project_image(camera, width, height, control)
    }
}
