//! [`ParticleVolume`]: construction, field evaluation and the `Volume` impl.

use rayon::prelude::*;
use voxless_bvh::{Bvh, order};
use voxless_core::{
    Aabb, Attribute, Interval, IntervalQuery, MacroGrid, PixelIntegral, Range1, Ray, Sample,
    SampleBatch, Vec3, Volume, simd::Simd,
};
use voxless_transfer::{ControlPoints, TransferFunction};

use crate::error::ParticleError;
use crate::kernel::{Family, Kernel, with_family};

mod device;
mod exact;
mod lod;
mod packet;
mod part;
mod periodic;
mod splat;

pub use device::DeviceParticles;
pub use periodic::{INSIDE, MAX_PERIODS, images, only_image, wrap};

pub use part::{FieldStatistics, RANGE_PROBES, check_data, median, probe_stride, support_box};

/// Particle arrays as read from a file, in file order.
#[derive(Clone, Debug, Default)]
pub struct ParticleData {
    pub positions: Vec<Vec3>,
    /// Per-particle radius parameter; when absent every particle gets the
    /// global radius.
    pub radii: Option<Vec<f32>>,
    /// Per-particle scalar attribute (`sᵢ`).
    pub attribute: Option<Vec<f32>>,
    /// Per-particle weight (`k_i` of the CPU paper, the mass for the cubic
    /// spline); 1 when absent.
    pub weights: Option<Vec<f32>>,
}

/// How the attribute becomes colour.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Classification {
    /// Average the attribute (Θ), then colour-map it.
    #[default]
    Post,
    /// Colour-map each particle's attribute, then average the colours.
    Pre,
}

#[derive(Clone, Debug)]
pub struct ParticleSettings {
    pub kernel: Kernel,
    /// Global radius parameter; used for every particle when no per-particle
    /// radii are given, and scaled by the radius map either way.
    pub radius: f32,
    /// Attribute (normalised to `attribute_range`) → fraction of the radius.
    pub radius_map: Option<ControlPoints>,
    /// Attribute (normalised) → weight factor.
    pub weight_map: Option<ControlPoints>,
    /// Particles per BVH leaf, 1..=16.
    pub cluster_size: usize,
    /// Normalisation range of the attribute; its min/max when `None`.
    pub attribute_range: Option<Range1>,
    pub classification: Classification,
    /// A periodic box: the field repeats with it (see the `periodic`
    /// module); positions outside are wrapped into it.
    pub periodic: Option<Aabb>,
    /// How orthographic projections integrate each pixel (see
    /// [`crate::kernel::area`]).
    pub pixels: PixelIntegral,
}

impl Default for ParticleSettings {
    fn default() -> Self {
        ParticleSettings {
            kernel: Kernel::Gaussian3,
            radius: 1.0,
            radius_map: None,
            weight_map: None,
            cluster_size: 8,
            attribute_range: None,
            classification: Classification::Post,
            periodic: None,
            pixels: PixelIntegral::Centre,
        }
    }
}

/// One particle's hot data: centre, squared support radius (negative when
/// hidden) and the kernel's packed `(shape, amplitude)`. 24 bytes.
#[derive(Clone, Copy, Debug)]
struct Packed {
    center: Vec3,
    support2: f32,
    shape: f32,
    amp: f32,
}

/// The fields at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldSample {
    /// Φ.
    pub density: f32,
    /// Θ (post-classification scalar); NaN where Φ = 0 or there is no attribute.
    pub attribute: f32,
    /// Pre-classified colour average (linear RGB), when pre-classification is on.
    pub color: Option<Vec3>,
    /// ∇Φ (zero unless requested).
    pub gradient: Vec3,
    /// Whether any particle's support contains the point.
    pub covered: bool,
}

/// At most this many particles per volume (indices are `u32`).
const MAX_PARTICLES: usize = (u32::MAX / 2) as usize;

pub struct ParticleVolume {
    settings: ParticleSettings,
    // Hilbert-ordered inputs (the centres are `packed`'s). Radii and
    // weights as given; empty when not given (the global radius, 1): a
    // set without them costs 8 bytes a particle less.
    base_radius: Vec<f32>,
    base_weight: Vec<f32>,
    attribute: Option<Vec<f32>>,
    original_index: Vec<u32>,
    // Derived from inputs and settings.
    radius: Vec<f32>,
    weight: Vec<f32>,
    packed: Vec<Packed>,
    bvh: Bvh,
    grid: MacroGrid,
    /// Φ's range (its maximum over a sample of particle centres), probed on
    /// first use: renders need it, projections and samples do not.
    value_range: std::sync::OnceLock<Range1>,
    attribute_range: Option<Range1>,
    nominal_dt: f32,
    /// Periodic boxes: whether the volume made its ghosts itself (a whole
    /// set; a part of a decomposed set receives its images from the other
    /// parts), the number of ghosts, and how many particles were wrapped
    /// into the box.
    own_images: bool,
    ghosts: usize,
    wrapped: usize,
    /// The merged particles of a large set's previews, built on first use
    /// (see the `lod` module).
    preview: std::sync::OnceLock<Option<Box<ParticleVolume>>>,
}

fn check_settings(s: &ParticleSettings) -> Result<(), ParticleError> {
    if !(1..=16).contains(&s.cluster_size) {
        return Err(ParticleError::BadClusterSize {
            value: s.cluster_size,
        });
    }
    if !(s.radius.is_finite() && s.radius > 0.0) {
        return Err(ParticleError::BadGlobalRadius { value: s.radius });
    }
    if let Some(b) = &s.periodic
        && !(b.min.is_finite() && b.max.is_finite() && (0..3).all(|a| b.max[a] > b.min[a]))
    {
        return Err(ParticleError::BadBox {
            lo: b.min.to_array(),
            hi: b.max.to_array(),
        });
    }
    if let Kernel::Gaussian { kappa, sigma } = s.kernel {
        for (name, value) in [("kappa", kappa), ("sigma", sigma)] {
            if !(value.is_finite() && value > 0.0) {
                return Err(ParticleError::BadKernelParameter { name, value });
            }
        }
    }
    Ok(())
}

impl ParticleVolume {
    /// Validates `data`, sorts it along a Hilbert curve, and builds the
    /// clusters, BVH and macrocells.
    pub fn new(data: ParticleData, settings: ParticleSettings) -> Result<Self, ParticleError> {
        Self::build(data, settings, Bvh::default(), None)
    }

    /// Replaces the particles with the next frame of a time series: the
    /// settings stay, and so does the attribute range (no flicker from
    /// per-frame autoranging; a range set in the settings still wins). The
    /// BVH is rebuilt into its existing buffers, which do not reallocate
    /// unless the particle count grows. On error the volume is unchanged.
    pub fn load_frame(&mut self, data: ParticleData) -> Result<(), ParticleError> {
        let mut settings = self.settings.clone();
        if settings.attribute_range.is_none() {
            settings.attribute_range = self.attribute_range;
        }
        let bvh = std::mem::take(&mut self.bvh);
        match Self::build(data, settings, bvh, None) {
            Ok(mut next) => {
                // Keep the caller's own settings (an attribute range that was
                // only inherited for this frame is not written back).
                next.settings.attribute_range = self.settings.attribute_range;
                *self = next;
                Ok(())
            }
            Err(e) => {
                // Restore the tree that was lent to the failed build.
                self.bvh = Bvh::build(&self.cluster_bounds());
                Err(e)
            }
        }
    }

    /// Validates and builds; a part of a decomposed set (`part`: the
    /// statistics of the whole set) may be empty and is not checked for
    /// supports larger than its own extent.
    fn build(
        data: ParticleData,
        settings: ParticleSettings,
        bvh: Bvh,
        part: Option<FieldStatistics>,
    ) -> Result<Self, ParticleError> {
        check_settings(&settings)?;
        let n = data.positions.len();
        if n == 0 && part.is_none() {
            return Err(ParticleError::Empty);
        }
        if n > MAX_PARTICLES {
            return Err(ParticleError::TooMany {
                count: n,
                max: MAX_PARTICLES,
            });
        }
        check_data(&data, 0)?;
        let attribute_range = data.attribute.as_ref().map(|a| {
            settings.attribute_range.unwrap_or_else(|| {
                a.iter().fold(Range1::EMPTY, |mut r, &v| {
                    r.extend(v);
                    r
                })
            })
        });
        if data.attribute.is_none() {
            for (what, present) in [
                ("radius map", settings.radius_map.is_some()),
                ("weight map", settings.weight_map.is_some()),
            ] {
                if present {
                    return Err(ParticleError::NeedsAttribute { what });
                }
            }
        }

        // A periodic box (of a whole set: a part receives its images):
        // wrap, and add the ghosts.
        let (data, source, wrapped) = match (&settings.periodic, &part) {
            (Some(b), None) => {
                let range = attribute_range.unwrap_or(Range1::new(0.0, 1.0));
                let im = periodic::with_images(data, b, &settings, range)?;
                (im.data, Some(im.source), im.wrapped)
            }
            _ => (data, None, 0),
        };
        let own_images = source.is_some();
        let ghosts = data.positions.len() - n;

        // Hilbert order so runs of consecutive particles are compact clusters.
        let bounds = box_of(&data.positions, |p| *p);
        let mut keys: Vec<order::Pair> = data
            .positions
            .par_iter()
            .enumerate()
            .map(|(i, p)| (order::hilbert(order::quantize(*p, &bounds)), i as u32))
            .collect();
        order::sort_pairs(&mut keys);
        let order: Vec<u32> = keys.par_iter().map(|k| k.1).collect();
        drop(keys);
        // Gathers are random reads: on every core (order-preserving).
        let gather = |v: &[f32]| -> Vec<f32> { order.par_iter().map(|&i| v[i as usize]).collect() };
        // The centres go straight into the packed particles; each input
        // array is freed once gathered, so peak memory is the volume plus
        // one array, not two copies of the set.
        let packed: Vec<Packed> = order
            .par_iter()
            .map(|&i| Packed {
                center: data.positions[i as usize],
                support2: -1.0,
                shape: 0.0,
                amp: 0.0,
            })
            .collect();
        let mut data = data;
        drop(std::mem::take(&mut data.positions));
        let base_radius = data.radii.take().map(|r| gather(&r)).unwrap_or_default();
        let base_weight = data.weights.take().map(|w| gather(&w)).unwrap_or_default();
        let attribute = data.attribute.take().as_deref().map(gather);
        let original_index = match source {
            Some(s) => order.par_iter().map(|&i| s[i as usize]).collect(),
            None => order,
        };

        let mut vol = ParticleVolume {
            settings,
            base_radius,
            base_weight,
            attribute,
            original_index,
            radius: Vec::new(),
            weight: Vec::new(),
            packed,
            bvh,
            grid: MacroGrid::with_cell_size(Aabb::EMPTY, 1.0, 1),
            value_range: std::sync::OnceLock::new(),
            attribute_range,
            nominal_dt: 1.0,
            own_images,
            ghosts,
            wrapped,
            preview: std::sync::OnceLock::new(),
        };
        vol.derive_radii_and_weights();
        if part.is_none() {
            vol.check_support()?;
        }
        let boxes = vol.cluster_bounds();
        vol.bvh.rebuild(&boxes);
        vol.derive_acceleration(part);
        Ok(vol)
    }

    /// Changes the global radius and/or the radius map and refits the tree
    /// (the topology stays; paper §3.2.2). Per-particle radii from the input
    /// are kept and scaled by the new map.
    pub fn set_radius(
        &mut self,
        radius: f32,
        radius_map: Option<ControlPoints>,
    ) -> Result<(), ParticleError> {
        let mut s = self.settings.clone();
        s.radius = radius;
        s.radius_map = radius_map;
        check_settings(&s)?;
        if s.radius_map.is_some() && self.attribute.is_none() {
            return Err(ParticleError::NeedsAttribute { what: "radius map" });
        }
        if self.own_images {
            // A periodic box's ghosts follow the supports: rebuild.
            let bvh = std::mem::take(&mut self.bvh);
            return match Self::build(self.originals(), s, bvh, None) {
                Ok(next) => {
                    *self = next;
                    Ok(())
                }
                Err(e) => {
                    self.bvh = Bvh::build(&self.cluster_bounds());
                    Err(e)
                }
            };
        }
        let old = std::mem::replace(&mut self.settings, s);
        self.derive_radii_and_weights();
        if let Err(e) = self.check_support() {
            // Leave the volume exactly as it was.
            self.settings = old;
            self.derive_radii_and_weights();
            return Err(e);
        }
        self.bvh.refit(&self.cluster_bounds());
        self.derive_acceleration(None);
        Ok(())
    }

    /// For pre-classification: every particle's attribute through `color`
    /// (a raw attribute value → linear RGB), in volume order; empty in post
    /// mode or without an attribute. A render's prepared context holds
    /// these, so the volume serves every transfer function at once.
    pub fn preclassify(&self, color: &(dyn Fn(f32) -> Vec3 + Sync)) -> Vec<Vec3> {
        match (&self.attribute, self.settings.classification) {
            (Some(a), Classification::Pre) => a.par_iter().map(|&s| color(s)).collect(),
            _ => Vec::new(),
        }
    }

    /// [`ParticleVolume::preclassify`] through `tf`'s colormap over the
    /// volume's attribute range.
    pub fn preclassify_with(&self, tf: &TransferFunction) -> Vec<Vec3> {
        let range = self.attribute_range.unwrap_or(Range1::new(0.0, 1.0));
        self.preclassify(&|s| tf.color(range.normalize(s)))
    }

    fn derive_radii_and_weights(&mut self) {
        // A preview merged from the old radii and weights is stale.
        self.preview = std::sync::OnceLock::new();
        let s = &self.settings;
        let range = self.attribute_range.unwrap_or(Range1::new(0.0, 1.0));
        let attr = |i: usize| self.attribute.as_ref().map(|a| a[i]);
        let n = self.packed.len();
        let base_r = |i: usize| self.base_radius.get(i).copied().unwrap_or(s.radius);
        let base_w = |i: usize| self.base_weight.get(i).copied().unwrap_or(1.0);
        // Linear in N, per particle: on every core.
        let radius = (0..n)
            .into_par_iter()
            .map(|i| base_r(i) * part::map_factor(&s.radius_map, attr(i), range))
            .collect();
        let weight = (0..n)
            .into_par_iter()
            .map(|i| base_w(i) * part::map_factor(&s.weight_map, attr(i), range))
            .collect();
        (self.radius, self.weight) = (radius, weight);
        let s = &self.settings;
        let factor = s.kernel.support_factor();
        let (radius, weight) = (&self.radius, &self.weight);
        self.packed.par_iter_mut().enumerate().for_each(|(i, q)| {
            let r = radius[i];
            (q.shape, q.amp) = if r > 0.0 {
                s.kernel.pack(r, weight[i])
            } else {
                (0.0, 0.0)
            };
            let support = factor * r;
            // Hidden particles get a negative support so `d² ≤ support²` never holds.
            q.support2 = if r > 0.0 { support * support } else { -1.0 };
        });
    }

    /// Refuses supports that would make every query visit (nearly) every
    /// particle — a render that would effectively hang. Small sets are exempt:
    /// there the cost stays bounded whatever the radius.
    fn check_support(&self) -> Result<(), ParticleError> {
        const EXEMPT: usize = 1000;
        if self.len() <= EXEMPT {
            return Ok(());
        }
        let b = box_of(&self.packed, |p| p.center);
        let factor = self.settings.kernel.support_factor();
        let mut supports: Vec<f32> = self.probes().map(|j| self.radius[j] * factor).collect();
        let support = median(&mut supports);
        let extent = b.diagonal();
        if support > extent {
            return Err(ParticleError::HugeRadius {
                support,
                extent,
                count: self.len(),
            });
        }
        Ok(())
    }

    /// Box of each cluster: the union of its visible members' support boxes.
    fn cluster_bounds(&self) -> Vec<Aabb> {
        self.packed
            .par_chunks(self.settings.cluster_size)
            .map(|c| {
                c.iter()
                    .filter(|p| p.support2 >= 0.0)
                    .map(|p| Aabb::around(p.center, p.support2.sqrt()))
                    .fold(Aabb::EMPTY, Aabb::union)
            })
            .collect()
    }

    /// The probes: every [`probe_stride`]-th particle in input order (so a
    /// decomposed set finds the same ones by their row numbers), by index in
    /// volume order.
    fn probes(&self) -> impl Iterator<Item = usize> + '_ {
        let stride = probe_stride(self.particle_count()) as u32;
        (0..self.len()).filter(move |&j| {
            let o = self.original_index[j];
            o & periodic::GHOST == 0 && o.is_multiple_of(stride)
        })
    }

    /// Macrocells, value range and nominal step, from the current radii —
    /// or, for a part of a decomposed set, from the whole set's statistics.
    fn derive_acceleration(&mut self, whole: Option<FieldStatistics>) {
        let median_support = match whole {
            Some(w) => w.median_support,
            None => {
                let mut visible: Vec<f32> = self
                    .probes()
                    .map(|j| self.packed[j].support2)
                    .filter(|&s2| s2 >= 0.0)
                    .map(f32::sqrt)
                    .collect();
                if visible.is_empty() {
                    self.bounds().diagonal().max(1e-6)
                } else {
                    median(&mut visible)
                }
            }
        };
        self.nominal_dt = median_support / 8.0;

        // Macrocells about two support radii wide, at most 128 per axis.
        let mut grid = MacroGrid::with_cell_size(self.bounds(), 2.0 * median_support, 128);
        let cells = grid.len();
        // Per-part sums of peak values; -1 marks a cell no particle touches.
        // One part per thread, each summing into its own grid: a part per
        // work-stealing split allocated, filled and merged a whole grid each
        // (2M cells: most of a second of a 16.7M-particle load).
        let per = self
            .packed
            .len()
            .div_ceil(rayon::current_num_threads().max(1))
            .max(4096);
        let sums = self
            .packed
            .par_chunks(per)
            .map(|chunk| {
                let mut acc = vec![-1.0f32; cells];
                for p in chunk.iter().filter(|p| p.support2 >= 0.0) {
                    let b = Aabb::around(p.center, p.support2.sqrt());
                    if let Some((lo, hi)) = grid.cells_overlapping(&b) {
                        for k in lo[2]..=hi[2] {
                            for j in lo[1]..=hi[1] {
                                for i in lo[0]..=hi[0] {
                                    let c = &mut acc[grid.index(i, j, k)];
                                    *c = c.max(0.0) + p.amp;
                                }
                            }
                        }
                    }
                }
                acc
            })
            .reduce_with(|mut a, b| {
                for (x, y) in a.iter_mut().zip(b) {
                    if y >= 0.0 {
                        *x = x.max(0.0) + y;
                    }
                }
                a
            })
            .unwrap_or_else(|| vec![-1.0f32; cells]);
        // Rounding in the f32 sum could undercut the true bound; pad it.
        grid.set_ranges(
            sums.into_iter()
                .map(|s| {
                    if s >= 0.0 {
                        Range1::new(0.0, s * 1.0001)
                    } else {
                        Range1::EMPTY
                    }
                })
                .collect(),
        );
        self.grid = grid;

        // Φ's range depends on the radii and weights just derived: a part
        // takes the whole set's, a whole volume probes it on first use.
        self.value_range = match whole {
            Some(w) => std::sync::OnceLock::from(w.value_range),
            None => std::sync::OnceLock::new(),
        };
    }

    /// Φ's range for normalisation: max over the probes' centres (in input
    /// order, with canonical sums, so a decomposed set finds the same).
    fn probe_value_range(&self) -> Range1 {
        let probes: Vec<usize> = self.probes().collect();
        let max = probes
            .par_iter()
            .map(|&j| self.density_exact(self.packed[j].center))
            .reduce(|| 0.0, f32::max);
        Range1::new(0.0, max)
    }

    /// Φ alone.
    pub fn density(&self, p: Vec3) -> f32 {
        self.field(p, false).density
    }

    /// Φ, Θ and (if `gradient`) ∇Φ at `p`.
    pub fn field(&self, p: Vec3, gradient: bool) -> FieldSample {
        self.field_with(&[], p, gradient)
    }

    /// [`ParticleVolume::field`] with pre-classified colours, one per
    /// particle in volume order (see [`ParticleVolume::preclassify`]; empty:
    /// none): the sample's colour is their kernel-weighted average.
    pub fn field_with(&self, colors: &[Vec3], p: Vec3, gradient: bool) -> FieldSample {
        // Colours of the wrong length count as none (a stale classification).
        let colors = if colors.len() == self.len() {
            colors
        } else {
            &[]
        };
        let p = self.wrap_point(p);
        // Dispatch on the kernel family once; the loop below is monomorphised.
        with_family!(self.settings.kernel, F => if gradient {
            self.eval::<F, true>(colors, p)
        } else {
            self.eval::<F, false>(colors, p)
        })
    }

    #[inline]
    fn eval<F: Family, const GRAD: bool>(&self, colors: &[Vec3], p: Vec3) -> FieldSample {
        let n = self.settings.cluster_size;
        let mut density = 0.0f32;
        let mut attr_sum = 0.0f32;
        let mut color = Vec3::ZERO;
        let mut grad = Vec3::ZERO;
        let mut covered = false;
        let attr = self.attribute.as_deref();
        let pre = !colors.is_empty();
        self.bvh.point_query(p, |c| {
            let start = c as usize * n;
            let end = (start + n).min(self.packed.len());
            for i in start..end {
                let q = &self.packed[i];
                let d = p - q.center;
                let d2 = d.length_squared();
                if d2 > q.support2 {
                    continue;
                }
                covered = true;
                let v = if GRAD {
                    let (v, g) = F::value_and_gradient_factor(d, d2, q.shape, q.amp);
                    grad += d * g;
                    v
                } else {
                    F::value(d, d2, q.shape, q.amp)
                };
                density += v;
                if let Some(a) = attr {
                    attr_sum += v * a[i];
                }
                if pre {
                    color += colors[i] * v;
                }
            }
        });
        FieldSample {
            density,
            attribute: if attr.is_some() && density > 0.0 {
                attr_sum / density
            } else {
                f32::NAN
            },
            color: (pre && density > 0.0).then(|| color / density),
            gradient: grad,
            covered,
        }
    }

    pub fn settings(&self) -> &ParticleSettings {
        &self.settings
    }
    pub fn len(&self) -> usize {
        self.packed.len()
    }
    pub fn is_empty(&self) -> bool {
        self.packed.is_empty()
    }
    pub fn has_attribute(&self) -> bool {
        self.attribute.is_some()
    }
    /// Positions in the volume's (Hilbert) order (a copy: the volume keeps
    /// them packed with each particle's kernel constants).
    pub fn positions(&self) -> Vec<Vec3> {
        self.packed.iter().map(|p| p.center).collect()
    }
    /// Effective radius parameter per particle (after the radius map), volume order.
    pub fn radii(&self) -> &[f32] {
        &self.radius
    }
    /// Effective weight per particle (after the weight map), volume order.
    pub fn weights(&self) -> &[f32] {
        &self.weight
    }
    /// Attribute per particle, volume order.
    pub fn attributes(&self) -> Option<&[f32]> {
        self.attribute.as_deref()
    }
    /// Input index of each particle, volume order.
    pub fn original_index(&self) -> &[u32] {
        &self.original_index
    }
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }
    /// Bytes of the particle arrays the renderer keeps hot (centre, support,
    /// kernel constants).
    pub fn particle_bytes(&self) -> usize {
        self.packed.len() * std::mem::size_of::<Packed>()
    }

    /// Checks the BVH against freshly computed cluster boxes.
    pub fn validate(&self) -> Result<(), voxless_bvh::InvalidBvh> {
        self.bvh.validate(&self.cluster_bounds())
    }

    /// Indices (volume order) of the particles whose support contains `p`,
    /// found through the BVH.
    pub fn overlapping(&self, p: Vec3) -> Vec<usize> {
        let n = self.settings.cluster_size;
        let mut out = Vec::new();
        let p = self.wrap_point(p);
        self.bvh.point_query(p, |c| {
            let start = c as usize * n;
            for i in start..(start + n).min(self.packed.len()) {
                let q = &self.packed[i];
                if (p - q.center).length_squared() <= q.support2 {
                    out.push(i);
                }
            }
        });
        out
    }

    /// Σᵢ ∫φᵢ dV: what a projection over the full bounds must conserve.
    pub fn total_mass(&self) -> f64 {
        let k = self.settings.kernel;
        (0..self.len())
            .filter(|&i| self.radius[i] > 0.0 && !self.is_ghost(i))
            .map(|i| self.weight[i] as f64 * k.integral(self.radius[i] as f64))
            .sum()
    }
}

impl Volume for ParticleVolume {
    fn bounds(&self) -> Aabb {
        self.settings.periodic.unwrap_or_else(|| self.bvh.bounds())
    }

    fn value_range(&self) -> Range1 {
        *self.value_range.get_or_init(|| self.probe_value_range())
    }

    fn attribute_range(&self) -> Option<Range1> {
        self.attribute_range
    }

    fn sample(&self, p: Vec3) -> Option<Sample> {
        let f = self.field(p, false);
        f.covered.then(|| to_sample(&f))
    }

    fn gradient(&self, p: Vec3) -> Vec3 {
        self.field(p, true).gradient
    }

    fn sample_with_gradient(&self, p: Vec3) -> Option<(Sample, Vec3)> {
        let f = self.field(p, true);
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
        self.sample_batch_with(&[], Simd::Auto, batch, gradient, out);
    }

    fn intervals(&self, ray: &Ray, t: Range1, query: &IntervalQuery, out: &mut Vec<Interval>) {
        self.grid.intervals(ray, t, self.nominal_dt, query, out);
    }

    /// Orthographic views: every particle's chord added to the pixels its
    /// support covers ([`splat`]); the same image as the per-pixel path up
    /// to summation order.
    fn project_image(
        &self,
        camera: &voxless_core::Camera,
        width: u32,
        height: u32,
        control: &voxless_core::Control,
    ) -> Option<Result<Vec<f32>, voxless_core::Cancelled>> {
        self.splat_projection(camera, width, height, control)
    }

    /// Exact: the closed-form chord integral of every particle the ray
    /// crosses, found by a BVH ray traversal. Assumes a unit ray direction.
    fn line_integral(&self, ray: &Ray, t: Range1) -> f64 {
        let n = self.settings.cluster_size;
        let kernel = self.settings.kernel;
        let mut sum = 0.0f64;
        self.bvh.ray_query(ray, t, |c, _| {
            let start = c as usize * n;
            for i in start..(start + n).min(self.packed.len()) {
                let q = &self.packed[i];
                if q.support2 < 0.0 {
                    continue;
                }
                let oc = q.center - ray.origin;
                // Distance² from the line via the cross product (no cancellation).
                let b2 = oc.cross(ray.dir).length_squared() as f64;
                if b2 >= q.support2 as f64 {
                    continue;
                }
                let u0 = oc.dot(ray.dir) as f64;
                let chord = kernel.chord_integral(
                    b2,
                    self.radius[i] as f64,
                    t.lo as f64 - u0,
                    t.hi as f64 - u0,
                );
                sum += self.weight[i] as f64 * chord;
            }
        });
        sum
    }
}

pub(crate) fn to_sample(f: &FieldSample) -> Sample {
    Sample {
        value: f.density,
        attribute: match f.color {
            Some(c) => Attribute::Rgb(c),
            None if !f.attribute.is_nan() => Attribute::Scalar(f.attribute),
            None => Attribute::None,
        },
    }
}

/// The box of the points `at` gives for `items`, on every core (min and max
/// are exact, so any grouping gives a serial loop's box; a serial pass over
/// a 16.7M-particle set was 0.035–0.05 s of its load).
fn box_of<T: Sync>(items: &[T], at: impl Fn(&T) -> Vec3 + Sync) -> Aabb {
    items
        .par_chunks(1 << 16)
        .map(|chunk| {
            chunk.iter().fold(Aabb::EMPTY, |mut b, p| {
                b.grow(at(p));
                b
            })
        })
        .reduce(|| Aabb::EMPTY, Aabb::union)
}
