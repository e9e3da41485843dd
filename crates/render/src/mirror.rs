//! Mirror instances of a volume (ExaBricks' half-aircraft): the data drawn
//! again, reflected about axis-aligned planes, without copying it.
//!
//! Each plane splits space into the data's side (where the centre of its
//! bounds lies) and the mirror side. A point on the mirror side of some
//! planes shows the data at its reflection about exactly those planes: the
//! field is *folded* back onto the data's side. Along a ray this is a
//! handful of pieces, cut where the ray crosses a plane; in each piece the
//! fold is one fixed reflection, and the reflected ray has the same
//! parameter `t` (a reflection is an isometry), so the volume's own
//! interval, sample, packet and line-integral paths serve each piece
//! unchanged. Gradients are reflected back.
//!
//! Data reaching across a plane onto its mirror side is cut there: the
//! mirror side shows only the reflection (what a symmetric half-model
//! means). The meshes' instances are traced in [`crate::surface`].

use voxless_core::{
    Aabb, Interval, IntervalQuery, Mirror, Range1, Ray, Sample, SampleBatch, Vec3, Volume,
};

/// `inner` with its mirror images (see the module docs).
pub struct Mirrored<'a, V: Volume> {
    inner: &'a V,
    mirrors: &'a [Mirror],
    /// Per mirror, the sign of the data's side of the plane.
    sides: Vec<f32>,
    bounds: Aabb,
}

/// Which mirrors a point is folded across: bit `i` for mirror `i`.
type Fold = u8;

impl<'a, V: Volume> Mirrored<'a, V> {
    /// At most 8 mirrors (one per axis in practice).
    pub fn new(inner: &'a V, mirrors: &'a [Mirror]) -> Self {
        assert!(mirrors.len() <= 8, "at most 8 mirrors");
        let b = inner.bounds();
        let sides = mirrors
            .iter()
            .map(|m| if m.side(b.center()) >= 0.0 { 1.0 } else { -1.0 })
            .collect();
        let mut bounds = b;
        for m in mirrors {
            let (p, q) = (m.point(bounds.min), m.point(bounds.max));
            bounds = bounds.union(Aabb::new(p.min(q), p.max(q)));
        }
        Mirrored {
            inner,
            mirrors,
            sides,
            bounds,
        }
    }

    #[inline]
    fn fold_of(&self, p: Vec3) -> Fold {
        let mut f = 0;
        for (i, (m, s)) in self.mirrors.iter().zip(&self.sides).enumerate() {
            if m.side(p) * s < 0.0 {
                f |= 1 << i;
            }
        }
        f
    }

    #[inline]
    fn point(&self, f: Fold, mut p: Vec3) -> Vec3 {
        for (i, m) in self.mirrors.iter().enumerate() {
            if f & (1 << i) != 0 {
                p = m.point(p);
            }
        }
        p
    }

    #[inline]
    fn vector(&self, f: Fold, mut v: Vec3) -> Vec3 {
        for (i, m) in self.mirrors.iter().enumerate() {
            if f & (1 << i) != 0 {
                v = m.vector(v);
            }
        }
        v
    }

    #[inline]
    fn ray(&self, f: Fold, r: &Ray) -> Ray {
        Ray::new(self.point(f, r.origin), self.vector(f, r.dir))
    }

    /// The pieces of `ray` over `t` with one fold each, in order.
    fn pieces(&self, ray: &Ray, t: Range1, mut visit: impl FnMut(Fold, Range1)) {
        if t.is_empty() {
            return;
        }
        let mut cuts = [0f32; 8];
        let mut n = 0;
        for m in self.mirrors {
            let d = ray.dir[m.axis];
            if d != 0.0 {
                let tc = (m.plane - ray.origin[m.axis]) / d;
                if tc > t.lo && tc < t.hi {
                    cuts[n] = tc;
                    n += 1;
                }
            }
        }
        cuts[..n].sort_by(f32::total_cmp);
        let mut lo = t.lo;
        for &c in cuts[..n].iter().chain(std::iter::once(&t.hi)) {
            if c > lo {
                visit(self.fold_of(ray.at(0.5 * (lo + c))), Range1::new(lo, c));
            }
            lo = c;
        }
    }
}

impl<V: Volume> Volume for Mirrored<'_, V> {
    voxless_core::forward_volume! {
        to self.inner;
        // Folded: each point or ray piece reflected onto the data's side.
        except bounds, sample, gradient, sample_with_gradient, sample_in,
            sample_with_gradient_in, sample_batch, intervals, line_integral;
        // The inner volume's would see only the unreflected data: the
        // trait's defaults build these on the folded methods above (a hook
        // added to the trait that takes points or rays belongs here, or
        // above, too).
        default sample_batch_values, samples_in_lanes, sample_values_lanes, intervals_chunk,
            tile_view, project_image;
    }
    fn bounds(&self) -> Aabb {
        self.bounds
    }
    fn sample(&self, p: Vec3) -> Option<Sample> {
        self.inner.sample(self.point(self.fold_of(p), p))
    }
    fn gradient(&self, p: Vec3) -> Vec3 {
        let f = self.fold_of(p);
        self.vector(f, self.inner.gradient(self.point(f, p)))
    }
    fn sample_with_gradient(&self, p: Vec3) -> Option<(Sample, Vec3)> {
        let f = self.fold_of(p);
        self.inner
            .sample_with_gradient(self.point(f, p))
            .map(|(s, g)| (s, self.vector(f, g)))
    }
    fn sample_in(&self, p: Vec3, interval: &Interval) -> Option<Sample> {
        self.inner
            .sample_in(self.point(self.fold_of(p), p), interval)
    }
    fn sample_with_gradient_in(&self, p: Vec3, interval: &Interval) -> Option<(Sample, Vec3)> {
        let f = self.fold_of(p);
        self.inner
            .sample_with_gradient_in(self.point(f, p), interval)
            .map(|(s, g)| (s, self.vector(f, g)))
    }
    fn sample_batch(
        &self,
        batch: &SampleBatch,
        gradient: bool,
        out: &mut Vec<(Option<Sample>, Vec3)>,
    ) {
        // Each ray's samples split into runs of one fold, each run a
        // reflected ray of its own; the order of the samples is kept.
        let (mut rays, mut offsets, mut folds) = (Vec::new(), vec![0u32], Vec::new());
        let mut ts = Vec::with_capacity(batch.t.len());
        for (r, ray) in batch.rays.iter().enumerate() {
            let mut current: Option<Fold> = None;
            for &t in batch.samples(r) {
                let f = self.fold_of(ray.at(t));
                if current != Some(f) {
                    if current.is_some() {
                        offsets.push(ts.len() as u32);
                    }
                    rays.push(self.ray(f, ray));
                    folds.push(f);
                    current = Some(f);
                }
                ts.push(t);
            }
            if current.is_some() {
                offsets.push(ts.len() as u32);
            }
        }
        self.inner.sample_batch(
            &SampleBatch {
                rays: &rays,
                offsets: &offsets,
                t: &ts,
                // The samples keep their order, so the caller's hints (the
                // inner volume's intervals') still line up.
                hints: batch.hints,
            },
            gradient,
            out,
        );
        if gradient {
            for (k, &f) in folds.iter().enumerate() {
                let (a, b) = (offsets[k] as usize, offsets[k + 1] as usize);
                for o in &mut out[a..b] {
                    o.1 = self.vector(f, o.1);
                }
            }
        }
    }
    fn intervals(&self, ray: &Ray, t: Range1, query: &IntervalQuery, out: &mut Vec<Interval>) {
        self.pieces(ray, t, |f, piece| {
            self.inner.intervals(&self.ray(f, ray), piece, query, out)
        });
    }
    fn line_integral(&self, ray: &Ray, t: Range1) -> f64 {
        let mut sum = 0.0;
        self.pieces(ray, t, |f, piece| {
            sum += self.inner.line_integral(&self.ray(f, ray), piece)
        });
        sum
    }
}
