//! Particle volumes prepared for one render: the pre-classified colours
//! (each particle's attribute through the render's colormap, for
//! pre-classification) and the SIMD backend of the packet path. The volume
//! itself holds neither, so renders with different transfer functions or
//! backends can share it.

use voxless_core::{
    Aabb, Camera, Cancelled, Control, Interval, IntervalQuery, Prepare, PrepareQuery, Range1, Ray,
    Sample, SampleBatch, Simd, Vec3, Volume,
};

use crate::volume::to_sample;
use crate::{MaterialVolume, ParticleVolume};

/// A [`ParticleVolume`] prepared for one render.
pub struct ParticleContext<'a> {
    volume: &'a ParticleVolume,
    /// One per particle in volume order, or empty (post-classification).
    colors: Vec<Vec3>,
    simd: Simd,
}

impl<'a> ParticleContext<'a> {
    pub fn new(volume: &'a ParticleVolume, colors: Vec<Vec3>, simd: Simd) -> Self {
        ParticleContext {
            volume,
            colors,
            simd,
        }
    }

    /// The pre-classified colours (empty: none).
    pub fn colors(&self) -> &[Vec3] {
        &self.colors
    }
}

impl Prepare for ParticleVolume {
    type Prepared<'a> = ParticleContext<'a>;

    fn prepare<'a>(&'a self, query: &PrepareQuery) -> ParticleContext<'a> {
        ParticleContext::new(self, self.preclassify(query.attribute_color), query.simd)
    }
}

impl Volume for ParticleContext<'_> {
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
        let f = self.volume.field_with(&self.colors, p, false);
        f.covered.then(|| to_sample(&f))
    }
    fn gradient(&self, p: Vec3) -> Vec3 {
        self.volume.gradient(p)
    }
    fn sample_with_gradient(&self, p: Vec3) -> Option<(Sample, Vec3)> {
        let f = self.volume.field_with(&self.colors, p, true);
        f.covered.then(|| (to_sample(&f), f.gradient))
    }
    fn packet_sampling(&self) -> bool {
        true
    }
    fn sample_batch(
        &self,
        batch: &SampleBatch,
        gradient: bool,
        out: &mut Vec<(Option<Sample>, Vec3)>,
    ) {
        self.volume
            .sample_batch_with(&self.colors, self.simd, batch, gradient, out);
    }
    fn intervals(&self, ray: &Ray, t: Range1, query: &IntervalQuery, out: &mut Vec<Interval>) {
        self.volume.intervals(ray, t, query, out)
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

/// A [`MaterialVolume`] prepared for one render: the SIMD backend its
/// materials' packet paths use (each material classifies with its own
/// transfer function, part of the volume's description).
pub struct MaterialContext<'a> {
    volume: &'a MaterialVolume,
    simd: Simd,
}

impl Prepare for MaterialVolume {
    type Prepared<'a> = MaterialContext<'a>;

    fn prepare<'a>(&'a self, query: &PrepareQuery) -> MaterialContext<'a> {
        MaterialContext {
            volume: self,
            simd: query.simd,
        }
    }
}

impl Volume for MaterialContext<'_> {
    fn bounds(&self) -> Aabb {
        self.volume.bounds()
    }
    fn value_range(&self) -> Range1 {
        self.volume.value_range()
    }
    fn classified(&self) -> bool {
        true
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
    fn packet_sampling(&self) -> bool {
        true
    }
    fn sample_batch(
        &self,
        batch: &SampleBatch,
        gradient: bool,
        out: &mut Vec<(Option<Sample>, Vec3)>,
    ) {
        self.volume.sample_batch_on(self.simd, batch, gradient, out)
    }
    fn intervals(&self, ray: &Ray, t: Range1, query: &IntervalQuery, out: &mut Vec<Interval>) {
        self.volume.intervals(ray, t, query, out)
    }
    fn line_integral(&self, ray: &Ray, t: Range1) -> f64 {
        self.volume.line_integral(ray, t)
    }
}
