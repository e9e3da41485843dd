//! Multi-material particle volumes (CPU RBF paper §5.5).
//!
//! Particles of different species (atoms of different elements, gas and
//! stars, halos) become separate density fields `Φ_m = Σ_{i ∈ m} φᵢ`, each
//! with its own kernel radius and its own transfer function. At every sample
//! each field is classified by its material's transfer function and the
//! results are blended: extinctions add (`a = Σ a_m`, two media in the same
//! place absorb like their sum) and the colour is the extinction-weighted
//! mean `Σ a_m c_m / a` — the order-independent form of compositing the
//! materials' samples one after another at the same position. A material's
//! colour comes from its colormap applied to its own density (normalised to
//! its value range), or is one fixed colour — categorical colours are thus
//! pre-classified per material, never averaged through one colormap.
//!
//! The volume reports classified samples ([`Volume::classified`]): `value` is
//! the blended opacity and the attribute the blended colour. Intervals are
//! the union of the materials' visible intervals (each material skips the
//! space its own transfer function hides), with a conservative opacity range
//! and the finest step of all visible materials everywhere — a step that depends on
//! the field alone, not on which materials' intervals happen to join up
//! along a ray (which would differ between a whole set and its parts in a
//! decomposition).

use voxless_core::{
    Aabb, Attribute, Interval, IntervalQuery, Range1, Ray, Sample, SampleBatch, Simd, Vec3, Volume,
};
use voxless_transfer::TransferFunction;

use crate::ParticleVolume;

/// How a material's density becomes colour and opacity.
#[derive(Clone, Debug)]
pub struct MaterialClass {
    pub tf: TransferFunction,
    /// Density range mapped to the transfer function's [0, 1].
    pub value_range: Range1,
    /// One fixed colour (linear RGB) instead of the colormap.
    pub color: Option<Vec3>,
}

impl MaterialClass {
    /// (opacity, colour) of density `phi`.
    #[inline]
    pub fn classify(&self, phi: f32) -> (f32, Vec3) {
        let x = self.value_range.normalize(phi);
        let c = self.color.unwrap_or_else(|| self.tf.color(x));
        (self.tf.opacity(x), c)
    }
}

/// One material: its particles (with their own kernel settings) and class.
pub struct Material {
    pub name: String,
    pub volume: ParticleVolume,
    pub class: MaterialClass,
}

pub struct MaterialVolume {
    pub(crate) materials: Vec<Material>,
    bounds: Aabb,
    /// Σ of every material's maximum opacity: the blended opacity's bound.
    max_opacity: f32,
    /// The finest nominal step of the materials that can be seen.
    nominal_dt: f32,
}

impl MaterialVolume {
    /// `None` when `materials` is empty.
    pub fn new(materials: Vec<Material>) -> Option<Self> {
        if materials.is_empty() {
            return None;
        }
        let mut bounds = Aabb::EMPTY;
        let mut max_opacity = 0.0;
        let mut nominal_dt = f32::INFINITY;
        for m in &materials {
            // A material its transfer function hides never takes a sample.
            if m.class.tf.max_opacity(0.0, 1.0) > 0.0 {
                nominal_dt = nominal_dt.min(m.volume.statistics().median_support / 8.0);
            }
            let b = m.volume.bounds();
            bounds = Aabb::new(bounds.min.min(b.min), bounds.max.max(b.max));
            max_opacity += m.class.tf.max_opacity(0.0, 1.0);
        }
        Some(MaterialVolume {
            materials,
            bounds,
            max_opacity,
            nominal_dt,
        })
    }

    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// [`Volume::sample_batch`] with each material's packet path on `simd`.
    pub(crate) fn sample_batch_on(
        &self,
        simd: Simd,
        batch: &SampleBatch,
        gradient: bool,
        out: &mut Vec<(Option<Sample>, Vec3)>,
    ) {
        let parts: Vec<Vec<(Option<Sample>, Vec3)>> = self
            .materials
            .iter()
            .map(|m| {
                let mut v = Vec::with_capacity(batch.t.len());
                m.volume
                    .sample_batch_with(&[], simd, batch, gradient, &mut v);
                v
            })
            .collect();
        out.clear();
        out.extend(
            (0..batch.t.len())
                .map(|j| self.blend(parts.iter().enumerate().map(|(m, p)| (m, p[j].0, p[j].1)))),
        );
    }

    /// Blends per-material densities (and gradients) into one classified
    /// sample; `None` where no material's particles cover the point.
    fn blend(
        &self,
        parts: impl Iterator<Item = (usize, Option<Sample>, Vec3)>,
    ) -> (Option<Sample>, Vec3) {
        let mut opacity = 0.0f32;
        let mut color = Vec3::ZERO;
        let mut grad = Vec3::ZERO;
        let mut covered = false;
        for (m, s, g) in parts {
            let Some(s) = s else { continue };
            covered = true;
            let (a, c) = self.materials[m].class.classify(s.value);
            opacity += a;
            color += c * a;
            grad += g;
        }
        if !covered {
            return (None, Vec3::ZERO);
        }
        let color = if opacity > 0.0 {
            color / opacity
        } else {
            Vec3::ZERO
        };
        (
            Some(Sample {
                value: opacity,
                attribute: Attribute::Rgb(color),
            }),
            grad,
        )
    }
}

impl Volume for MaterialVolume {
    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn value_range(&self) -> Range1 {
        Range1::new(0.0, self.max_opacity)
    }

    fn classified(&self) -> bool {
        true
    }

    fn sample(&self, p: Vec3) -> Option<Sample> {
        self.blend(
            self.materials
                .iter()
                .enumerate()
                .map(|(m, mat)| (m, mat.volume.sample(p), Vec3::ZERO)),
        )
        .0
    }

    fn gradient(&self, p: Vec3) -> Vec3 {
        self.materials
            .iter()
            .fold(Vec3::ZERO, |g, m| g + m.volume.gradient(p))
    }

    fn sample_with_gradient(&self, p: Vec3) -> Option<(Sample, Vec3)> {
        let (s, g) = self.blend(self.materials.iter().enumerate().map(|(m, mat)| {
            match mat.volume.sample_with_gradient(p) {
                Some((s, g)) => (m, Some(s), g),
                None => (m, None, Vec3::ZERO),
            }
        }));
        s.map(|s| (s, g))
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
        self.sample_batch_on(Simd::Auto, batch, gradient, out)
    }

    fn intervals(&self, ray: &Ray, t: Range1, _: &IntervalQuery, out: &mut Vec<Interval>) {
        // Each material skips what its own transfer function hides.
        let start = out.len();
        for m in &self.materials {
            let class = &m.class;
            let visible = |r: Range1| {
                class.tf.max_opacity(
                    class.value_range.normalize(r.lo),
                    class.value_range.normalize(r.hi),
                ) > 0.0
            };
            m.volume.intervals(
                ray,
                t,
                &IntervalQuery {
                    is_visible: &visible,
                },
                out,
            );
        }
        // The union, in increasing t, with the finest step of all materials.
        let mut parts: Vec<Interval> = out.drain(start..).collect();
        parts.sort_by(|a, b| a.t.lo.total_cmp(&b.t.lo));
        for iv in parts {
            let mine = out.len() > start;
            match out.last_mut() {
                Some(last) if mine && iv.t.lo <= last.t.hi => {
                    last.t.hi = last.t.hi.max(iv.t.hi);
                }
                _ => out.push(Interval::sampled(
                    iv.t,
                    Range1::new(0.0, self.max_opacity),
                    self.nominal_dt,
                )),
            }
        }
    }

    /// ∫ Σ_m Φ_m dt: the column of all materials' densities together.
    fn line_integral(&self, ray: &Ray, t: Range1) -> f64 {
        self.materials
            .iter()
            .map(|m| m.volume.line_integral(ray, t))
            .sum()
    }
}
