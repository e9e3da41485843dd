//! Particle volumes prepared for one render: the pre-classified colours
//! (each particle's attribute through the render's colormap, for
//! pre-classification) and the SIMD backend of the packet path. The volume
//! itself holds neither, so renders with different transfer functions or
//! backends can share it.

use voxless_core::{Prepare, PrepareQuery, Sample, SampleBatch, Simd, Vec3, Volume};

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
    voxless_core::forward_volume! {
        to self.volume;
        // Samples carry the pre-classified colours, if any.
        except sample, sample_with_gradient, sample_batch;
        // Built on the context's own `sample` (the volume's would leave
        // the colours out).
        default sample_in, sample_with_gradient_in;
    }
    fn sample(&self, p: Vec3) -> Option<Sample> {
        let f = self.volume.field_with(&self.colors, p, false);
        f.covered.then(|| to_sample(&f))
    }
    fn sample_with_gradient(&self, p: Vec3) -> Option<(Sample, Vec3)> {
        let f = self.volume.field_with(&self.colors, p, true);
        f.covered.then(|| (to_sample(&f), f.gradient))
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
    voxless_core::forward_volume! {
        to self.volume;
        except sample_batch;
    }
    /// The materials' packet paths on the context's SIMD backend.
    fn sample_batch(
        &self,
        batch: &SampleBatch,
        gradient: bool,
        out: &mut Vec<(Option<Sample>, Vec3)>,
    ) {
        self.volume.sample_batch_on(self.simd, batch, gradient, out)
    }
}
