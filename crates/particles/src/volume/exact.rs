//! Point samples whose bits do not depend on how the particles are
//! organised: every particle reaching the point contributes, and the
//! contributions are added in an order fixed by the particles themselves
//! (not by the BVH), so a part of a decomposed set that holds every
//! particle reaching the point gives the same bits as the whole set. The
//! `sample` command uses these; renders use the faster BVH-order sums,
//! which agree to a few ulp.

use voxless_core::Vec3;

use super::{FieldSample, ParticleVolume};
use crate::kernel::{Family, with_family};

/// One particle's contribution: value, attribute × value, colour × value,
/// gradient, and the key that orders it (centre, then the terms).
#[derive(Clone, Copy)]
struct Term {
    key: [u32; 4],
    v: f32,
    attr: f32,
    color: Vec3,
    grad: Vec3,
}

impl ParticleVolume {
    /// Φ, Θ and (if `gradient`) ∇Φ at `p`, summed in a canonical order: the
    /// same bits for any set of particles that contains every particle
    /// whose support holds `p`.
    pub fn field_exact(&self, p: Vec3, gradient: bool) -> FieldSample {
        self.field_exact_with(&[], p, gradient)
    }

    /// Φ alone, in the canonical order of [`ParticleVolume::field_exact`].
    pub fn density_exact(&self, p: Vec3) -> f32 {
        self.field_exact(p, false).density
    }

    /// [`ParticleVolume::field_exact`] with pre-classified colours (see
    /// [`ParticleVolume::field_with`]).
    pub fn field_exact_with(&self, colors: &[Vec3], p: Vec3, gradient: bool) -> FieldSample {
        let colors = if colors.len() == self.len() {
            colors
        } else {
            &[]
        };
        let p = self.wrap_point(p);
        // Every kernel through its own family, as `field_with` dispatches.
        let mut terms = with_family!(self.settings.kernel, F => if gradient {
            self.terms::<F, true>(colors, p)
        } else {
            self.terms::<F, false>(colors, p)
        });
        terms.sort_unstable_by(|a, b| {
            a.key.cmp(&b.key).then_with(|| {
                let bits = |t: &Term| {
                    [
                        t.v.to_bits(),
                        t.attr.to_bits(),
                        t.grad.x.to_bits(),
                        t.grad.y.to_bits(),
                        t.grad.z.to_bits(),
                    ]
                };
                bits(a).cmp(&bits(b))
            })
        });
        let (mut density, mut attr_sum) = (0.0f32, 0.0f32);
        let (mut color, mut grad) = (Vec3::ZERO, Vec3::ZERO);
        for t in &terms {
            density += t.v;
            attr_sum += t.attr;
            color += t.color;
            grad += t.grad;
        }
        let has_attr = self.attribute.is_some();
        let pre = !colors.is_empty();
        FieldSample {
            density,
            attribute: if has_attr && density > 0.0 {
                attr_sum / density
            } else {
                f32::NAN
            },
            color: (pre && density > 0.0).then(|| color / density),
            gradient: grad,
            covered: !terms.is_empty(),
        }
    }

    /// Every contribution at `p`, in BVH order.
    fn terms<F: Family, const GRAD: bool>(&self, colors: &[Vec3], p: Vec3) -> Vec<Term> {
        let n = self.settings.cluster_size;
        let attr = self.attribute.as_deref();
        let mut out = Vec::new();
        self.bvh.point_query(p, |c| {
            let start = c as usize * n;
            for i in start..(start + n).min(self.packed.len()) {
                let q = &self.packed[i];
                let d = p - q.center;
                let d2 = d.length_squared();
                if d2 > q.support2 {
                    continue;
                }
                let (v, grad) = if GRAD {
                    let (v, g) = F::value_and_gradient_factor(d, d2, q.shape, q.amp);
                    (v, d * g)
                } else {
                    (F::value(d, d2, q.shape, q.amp), Vec3::ZERO)
                };
                out.push(Term {
                    key: [
                        q.center.x.to_bits(),
                        q.center.y.to_bits(),
                        q.center.z.to_bits(),
                        q.support2.to_bits(),
                    ],
                    v,
                    attr: attr.map_or(0.0, |a| v * a[i]),
                    color: colors.get(i).map_or(Vec3::ZERO, |c| *c * v),
                    grad,
                });
            }
        });
        out
    }
}
