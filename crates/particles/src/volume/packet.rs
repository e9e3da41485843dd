//! Packet sampling (CPU RBF paper §4.1): the sample buffer of a whole packet
//! of rays filled by one BVH traversal.
//!
//! The traversal visits every cluster whose box overlaps the box of all the
//! packet's samples; for each cluster, each ray whose pass segment crosses
//! the cluster box, and each member particle, the particle's support cuts the
//! ray in a chord `[u − h, u + h]`, and only the samples inside that chord are
//! evaluated (found by binary search along the ray's sorted samples). Each
//! particle is thus visited once per packet and pass instead of once per
//! sample, and the per-sample point-query traversal disappears.
//!
//! Exactness: a sample takes a particle iff `|p − c|² ≤ R²` with `p =
//! ray.at(t)` — the point query's own test on the same `p` (the chord only
//! pre-selects, padded against rounding). Clusters come in the point query's
//! depth-first order and members in index order, so every sample sums the
//! same terms in the same order as [`ParticleVolume::field`]: the buffer
//! equals per-sample evaluation bit for bit.

use voxless_core::{Aabb, Range1, Sample, SampleBatch, Vec3};

use super::{FieldSample, ParticleVolume, to_sample};
use crate::kernel::Family;

/// Per-sample sums while the buffer fills.
#[derive(Clone, Copy, Default)]
struct Acc {
    density: f32,
    attr: f32,
    color: Vec3,
    grad: Vec3,
    covered: bool,
}

impl ParticleVolume {
    pub(super) fn batch<F: Family, const GRAD: bool>(
        &self,
        batch: &SampleBatch,
        out: &mut Vec<(Option<Sample>, Vec3)>,
    ) {
        let n_rays = batch.rays.len();
        let pts: Vec<Vec3> = (0..n_rays)
            .flat_map(|r| {
                let ray = batch.rays[r];
                batch.samples(r).iter().map(move |&t| ray.at(t))
            })
            .collect();
        let mut acc = vec![Acc::default(); pts.len()];
        let mut bounds = Aabb::EMPTY;
        for p in &pts {
            bounds.grow(*p);
        }
        // Each ray's pass segment, for the ray–cluster test.
        let spans: Vec<Range1> = (0..n_rays)
            .map(|r| {
                let s = batch.samples(r);
                match (s.first(), s.last()) {
                    (Some(&a), Some(&b)) => Range1::new(a, b),
                    _ => Range1::EMPTY,
                }
            })
            .collect();
        let n = self.settings.cluster_size;
        let attr = self.attribute.as_deref();
        let pre = !self.colors.is_empty();
        self.bvh.box_query(&bounds, |c, cbox| {
            let start = c as usize * n;
            let end = (start + n).min(self.packed.len());
            for r in 0..n_rays {
                let span = spans[r];
                let ray = &batch.rays[r];
                // Padded so rounding in the slab test cannot drop a sample.
                let pad = 1e-4 * (span.hi.abs() + span.lo.abs()) + 1e-6;
                if cbox
                    .clip_ray(ray, Range1::new(span.lo - pad, span.hi + pad))
                    .is_empty()
                {
                    continue;
                }
                let ts = batch.samples(r);
                let base = batch.offsets[r] as usize;
                let dd = ray.dir.length_squared();
                let inv_dd = 1.0 / dd;
                for i in start..end {
                    let q = &self.packed[i];
                    if q.support2 < 0.0 {
                        continue;
                    }
                    let oc = q.center - ray.origin;
                    // Distance² from the line and the chord, in t units.
                    let b2 = oc.cross(ray.dir).length_squared() * inv_dd;
                    let slack = q.support2 * 1e-4;
                    if b2 > q.support2 + slack {
                        continue;
                    }
                    let u = oc.dot(ray.dir) * inv_dd;
                    let h = ((q.support2 + slack - b2) * inv_dd).sqrt() * 1.001
                        + 1e-5 * u.abs();
                    let (lo, hi) = (u - h, u + h);
                    if hi < span.lo || lo > span.hi {
                        continue;
                    }
                    let j0 = ts.partition_point(|&t| t < lo);
                    let j1 = ts.partition_point(|&t| t <= hi);
                    for j in base + j0..base + j1 {
                        let p = pts[j];
                        let d = p - q.center;
                        let d2 = d.length_squared();
                        if d2 > q.support2 {
                            continue;
                        }
                        let a = &mut acc[j];
                        a.covered = true;
                        let v = if GRAD {
                            let (v, g) = F::value_and_gradient_factor(d, d2, q.shape, q.amp);
                            a.grad += d * g;
                            v
                        } else {
                            F::value(d, d2, q.shape, q.amp)
                        };
                        a.density += v;
                        if let Some(at) = attr {
                            a.attr += v * at[i];
                        }
                        if pre {
                            a.color += self.colors[i] * v;
                        }
                    }
                }
            }
        });
        out.extend(acc.iter().map(|a| {
            let f = FieldSample {
                density: a.density,
                attribute: if attr.is_some() && a.density > 0.0 {
                    a.attr / a.density
                } else {
                    f32::NAN
                },
                color: (pre && a.density > 0.0).then(|| a.color / a.density),
                gradient: a.grad,
                covered: a.covered,
            };
            (f.covered.then(|| to_sample(&f)), f.gradient)
        }));
    }
}
