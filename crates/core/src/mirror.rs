//! Reflection about an axis-aligned plane: the one instance transform
//! voxless renders (a half-model and its mirror image, as the AMR paper
//! renders half an aircraft), applied to rays rather than to the data.
//!
//! A reflection is an isometry and its own inverse, so a ray reflected into
//! the data's side keeps its parameter: the point at `t` of the reflected
//! ray is the reflection of the point at `t` of the original. Integrals and
//! hit distances along either are the same numbers.

use crate::{Ray, Vec3};

/// The plane `x[axis] = plane`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mirror {
    /// 0, 1, 2 for x, y, z.
    pub axis: usize,
    pub plane: f32,
}

impl Mirror {
    /// The reflection of point `p`.
    #[inline]
    pub fn point(&self, mut p: Vec3) -> Vec3 {
        let a = &mut p[self.axis];
        *a = 2.0 * self.plane - *a;
        p
    }

    /// The reflection of direction or normal `v`.
    #[inline]
    pub fn vector(&self, mut v: Vec3) -> Vec3 {
        v[self.axis] = -v[self.axis];
        v
    }

    /// The reflection of `ray` (same parameter `t`).
    #[inline]
    pub fn ray(&self, ray: &Ray) -> Ray {
        Ray::new(self.point(ray.origin), self.vector(ray.dir))
    }

    /// Signed distance of `p` from the plane (positive on the +axis side).
    #[inline]
    pub fn side(&self, p: Vec3) -> f32 {
        p[self.axis] - self.plane
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reflection_is_an_involution_that_keeps_t() {
        let m = Mirror {
            axis: 1,
            plane: 0.25,
        };
        let p = Vec3::new(0.1, 0.9, -0.3);
        assert!((m.point(p) - Vec3::new(0.1, -0.4, -0.3)).length() < 1e-6);
        assert_eq!(m.point(m.point(p)), p);
        let r = Ray::new(p, Vec3::new(0.0, 0.6, 0.8));
        let q = m.ray(&r);
        for t in [0.0f32, 0.5, 2.0] {
            let a = m.point(r.at(t));
            let b = q.at(t);
            assert!((a - b).length() < 1e-6);
        }
        assert!(m.side(p) > 0.0 && m.side(m.point(p)) < 0.0);
    }
}
