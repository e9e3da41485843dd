//! Pinhole and orthographic cameras.
//!
//! Image convention everywhere: pixel (row, col), row 0 at the top, pixel
//! centres at (col + 0.5, row + 0.5). The camera frame is `right`, `up`,
//! `forward` (unit, orthogonal); rays leave through the image plane.

use crate::math::{Aabb, Ray, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Vertical field of view in degrees.
    Perspective { fov_y_deg: f32 },
    /// Half extents of the image plane in world units.
    Orthographic { half_width: f32, half_height: f32 },
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    pub forward: Vec3,
    pub projection: Projection,
}

/// A camera that cannot be built from the given vectors.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraError(pub String);

impl std::fmt::Display for CameraError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}
impl std::error::Error for CameraError {}

impl Camera {
    /// The eye and the right, up and forward directions in f64, for work
    /// that measures offsets in the image plane in double precision.
    pub fn basis_f64(&self) -> [[f64; 3]; 4] {
        [self.eye, self.right, self.up, self.forward].map(|v| [v.x as f64, v.y as f64, v.z as f64])
    }
    /// A camera at `eye` looking at `look_at`, with `up` as the approximate up
    /// direction. Errors when the vectors are not finite, `eye == look_at`, or
    /// `up` is parallel to the view direction.
    pub fn look_at(
        eye: Vec3,
        look_at: Vec3,
        up: Vec3,
        projection: Projection,
    ) -> Result<Camera, CameraError> {
        if !(eye.is_finite() && look_at.is_finite() && up.is_finite()) {
            return Err(CameraError("camera vectors must be finite".into()));
        }
        let mut forward = (look_at - eye).normalized();
        if !(forward.is_finite() && forward.length_squared() > 0.5) && look_at != eye {
            // The f32 length overflowed or underflowed (positions beyond
            // ~1e19 or below ~1e-19 apart): normalise in f64 instead.
            forward = unit_f64(look_at, eye);
        }
        if forward.length_squared() == 0.0 {
            return Err(CameraError("camera eye and look-at point coincide".into()));
        }
        let mut right = forward.cross(up).normalized();
        if !(right.is_finite() && right.length_squared() > 0.5) {
            // An up vector too long or too short for f32 squares.
            right = forward.cross(unit_f64(up, Vec3::ZERO)).normalized();
        }
        if !(right.length_squared() >= 0.5) {
            return Err(CameraError(
                "camera up vector is parallel to the view direction".into(),
            ));
        }
        if let Projection::Perspective { fov_y_deg } = projection
            && !(fov_y_deg > 0.0 && fov_y_deg < 180.0)
        {
            return Err(CameraError(format!(
                "field of view must be in (0, 180) degrees, got {fov_y_deg}"
            )));
        }
        let up = right.cross(forward);
        Ok(Camera {
            eye,
            right,
            up,
            forward,
            projection,
        })
    }

    /// A simple view of `bounds`: from the +z side, tilted, far enough that
    /// the bounding sphere fills the frame of a 30° perspective camera.
    /// Never fails: bounds too large or too small for f32 arithmetic give
    /// the same view directions with the eye computed in f64 (an empty or
    /// degenerate box is viewed as a box of radius 1e-6 around its centre).
    /// The `voxless` library's default view is a three-quarter view that
    /// honours an up vector; this one serves tests and benchmarks.
    pub fn framing(bounds: &Aabb, aspect: f32) -> Camera {
        let center = bounds.center();
        let radius = (bounds.diagonal() * 0.5).max(1e-6);
        let fov_y_deg: f32 = 30.0;
        let half = (fov_y_deg.to_radians() * 0.5).tan();
        // Fit the sphere in the narrower of the two image directions.
        let fit = half * aspect.min(1.0);
        let distance = radius / fit.atan().sin();
        let dir = Vec3::new(0.35, 0.45, 1.0).normalized();
        let projection = Projection::Perspective { fov_y_deg };
        let up = Vec3::new(0.0, 1.0, 0.0);
        Camera::look_at(center + dir * distance, center, up, projection).unwrap_or_else(|_| {
            // Overflow in f32: the same view, its eye placed in f64.
            let c = |a: usize| {
                let (lo, hi) = (bounds.min[a] as f64, bounds.max[a] as f64);
                if lo <= hi { 0.5 * lo + 0.5 * hi } else { 0.0 }
            };
            let diag = (0..3)
                .map(|a| {
                    (bounds.max[a] as f64 - bounds.min[a] as f64)
                        .max(0.0)
                        .powi(2)
                })
                .sum::<f64>()
                .sqrt();
            let dist = (0.5 * diag).max(1e-6) / (fit as f64).atan().sin();
            let eye = Vec3::new(
                (c(0) + dir.x as f64 * dist) as f32,
                (c(1) + dir.y as f64 * dist) as f32,
                (c(2) + dir.z as f64 * dist) as f32,
            );
            let forward = -dir;
            let right = forward.cross(up).normalized();
            Camera {
                eye,
                right,
                up: right.cross(forward),
                forward,
                projection,
            }
        })
    }

    /// The ray through image position (`x`, `y`) in pixels (continuous, so the
    /// centre of pixel (row, col) is (col + 0.5, row + 0.5)) of a `width`×`height` image.
    pub fn ray(&self, x: f32, y: f32, width: u32, height: u32) -> Ray {
        let sx = 2.0 * x / width as f32 - 1.0;
        let sy = 1.0 - 2.0 * y / height as f32;
        match self.projection {
            Projection::Perspective { fov_y_deg } => {
                let half = (fov_y_deg.to_radians() * 0.5).tan();
                let aspect = width as f32 / height as f32;
                let dir = self.forward + self.right * (sx * half * aspect) + self.up * (sy * half);
                Ray::new(self.eye, dir.normalized())
            }
            Projection::Orthographic {
                half_width,
                half_height,
            } => {
                let (across, down) = self.ortho_terms(sx * half_width, sy * half_height);
                Ray::new(across + down, self.forward)
            }
        }
    }

    /// An orthographic ray's origin in its two parts, the first from the
    /// image column, the second from the row (their sum is the origin).
    #[inline]
    fn ortho_terms(&self, u: f32, v: f32) -> (Vec3, Vec3) {
        (self.eye + self.right * u, self.up * v)
    }

    /// For an orthographic camera, the rays through the pixel centres of a
    /// `width`×`height` image in parts: the ray of pixel (row `y`, column
    /// `x`) has the origin `across[x] + down[y]` (the same operations as
    /// [`Camera::ray`], so the same bits) and the direction `forward`.
    /// `None` for a perspective camera.
    pub fn ortho_parts(&self, width: u32, height: u32) -> Option<(Vec<Vec3>, Vec<Vec3>)> {
        let Projection::Orthographic {
            half_width,
            half_height,
        } = self.projection
        else {
            return None;
        };
        let across = (0..width)
            .map(|x| {
                let sx = 2.0 * (x as f32 + 0.5) / width as f32 - 1.0;
                self.ortho_terms(sx * half_width, 0.0).0
            })
            .collect();
        let down = (0..height)
            .map(|y| {
                let sy = 1.0 - 2.0 * (y as f32 + 0.5) / height as f32;
                self.ortho_terms(0.0, sy * half_height).1
            })
            .collect();
        Some((across, down))
    }
}

/// The unit vector from `b` to `a`, computed in f64 (no overflow or
/// underflow for any finite f32 inputs); zero when they coincide.
fn unit_f64(a: Vec3, b: Vec3) -> Vec3 {
    let d = [
        a.x as f64 - b.x as f64,
        a.y as f64 - b.y as f64,
        a.z as f64 - b.z as f64,
    ];
    let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if l > 0.0 && l.is_finite() {
        Vec3::new((d[0] / l) as f32, (d[1] / l) as f32, (d[2] / l) as f32)
    } else {
        Vec3::ZERO
    }
}

impl Camera {
    /// An orthographic camera looking down `-axis` (0 = x, 1 = y, 2 = z)
    /// whose image exactly covers `bounds` in the other two axes `(u, v)`:
    /// `(y, z)` for x, `(x, z)` for y, `(x, y)` for z. Pixel (row, col) of a
    /// W×H image is centred at `(min_u + (col + 0.5)·du, max_v − (row + 0.5)·dv)`.
    pub fn axis_projection(bounds: &Aabb, axis: usize) -> Result<Camera, CameraError> {
        let (u, v) = match axis {
            0 => (1, 2),
            1 => (0, 2),
            2 => (0, 1),
            _ => return Err(CameraError(format!("axis {axis} is not 0, 1 or 2"))),
        };
        let e = bounds.extent();
        if bounds.is_empty() || !(e[u] > 0.0 && e[v] > 0.0) || !e.is_finite() {
            return Err(CameraError(format!(
                "projection bounds {:?}..{:?} have no area across the view axis",
                bounds.min.to_array(),
                bounds.max.to_array()
            )));
        }
        let unit = |a: usize| {
            let mut d = [0.0; 3];
            d[a] = 1.0;
            Vec3::from_array(d)
        };
        let c = bounds.center();
        let mut eye = c;
        // Outside the bounds on the +axis side; projections integrate the
        // whole line anyway, so the distance only matters for clarity.
        let eye_axis = bounds.max[axis] + e[axis].max(1.0);
        match axis {
            0 => eye.x = eye_axis,
            1 => eye.y = eye_axis,
            _ => eye.z = eye_axis,
        }
        Ok(Camera {
            eye,
            right: unit(u),
            up: unit(v),
            forward: -unit(axis),
            projection: Projection::Orthographic {
                half_width: 0.5 * e[u],
                half_height: 0.5 * e[v],
            },
        })
    }
}

#[cfg(test)]
mod ortho_tests {
    use super::*;

    /// The parts of orthographic rays add up to `Camera::ray`'s origins to
    /// the bit, for cameras down an axis and oblique ones.
    #[test]
    fn ortho_parts_are_the_rays_bits() {
        let bounds = crate::Aabb::new(Vec3::new(-1.3, 0.2, 5.0), Vec3::new(2.7, 3.1, 9.5));
        let mut cams: Vec<Camera> = (0..3)
            .filter_map(|a| Camera::axis_projection(&bounds, a).ok())
            .collect();
        let mut rng = crate::SmallRng(7);
        for _ in 0..6 {
            let mut c = cams[0];
            let v = |r: &mut crate::SmallRng| Vec3::new(r.f() - 0.5, r.f() - 0.5, r.f() - 0.5);
            c.eye = v(&mut rng) * 100.0;
            c.right = v(&mut rng).normalized();
            c.up = v(&mut rng).normalized();
            cams.push(c);
        }
        assert_eq!(cams.len(), 9);
        for cam in &cams {
            for (w, h) in [(1, 1), (7, 5), (64, 33)] {
                let (across, down) = cam.ortho_parts(w, h).unwrap();
                for y in 0..h {
                    for x in 0..w {
                        let r = cam.ray(x as f32 + 0.5, y as f32 + 0.5, w, h);
                        let o = across[x as usize] + down[y as usize];
                        let bits = |v: Vec3| [v.x, v.y, v.z].map(f32::to_bits);
                        assert_eq!(bits(r.origin), bits(o), "{x} {y}");
                        assert_eq!(bits(r.dir), bits(cam.forward));
                    }
                }
            }
        }
        let mut p = cams[0];
        p.projection = Projection::Perspective { fov_y_deg: 40.0 };
        assert!(p.ortho_parts(4, 4).is_none());
    }
}
