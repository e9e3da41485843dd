//! Box outlines drawn over an image: the twelve edges of a box (a periodic
//! box, say) projected through the camera that made the image.
//!
//! Each edge is clipped to the space in front of the camera, projected to
//! pixel coordinates and walked in steps of a third of a pixel; every pixel
//! it crosses gets the colour composited over it once (premultiplied, as
//! the image is). No depth test: the outline is drawn over the volume, as a
//! guide, not as part of the scene.

use crate::camera::{Camera, Projection};
use crate::image::Image;
use crate::math::{Aabb, Vec3};

impl Camera {
    /// Pixel coordinates (x to the right, y down, pixel centres at +0.5) of
    /// `p` in a `width`×`height` image, and its depth along the view; `None`
    /// behind the eye of a perspective camera.
    pub fn to_pixel(&self, p: Vec3, width: u32, height: u32) -> Option<(f32, f32, f32)> {
        let d = p - self.eye;
        let z = d.dot(self.forward);
        let (sx, sy) = match self.projection {
            Projection::Perspective { fov_y_deg } => {
                if z <= 0.0 {
                    return None;
                }
                let half = (fov_y_deg.to_radians() * 0.5).tan();
                let aspect = width as f32 / height as f32;
                (
                    d.dot(self.right) / (z * half * aspect),
                    d.dot(self.up) / (z * half),
                )
            }
            Projection::Orthographic {
                half_width,
                half_height,
            } => (d.dot(self.right) / half_width, d.dot(self.up) / half_height),
        };
        Some((
            0.5 * (sx + 1.0) * width as f32,
            0.5 * (1.0 - sy) * height as f32,
            z,
        ))
    }
}

/// Draws the edges of `b` as seen by `camera` over `image`, in the linear
/// RGBA colour `rgba` (not premultiplied).
pub fn draw_box_outline(image: &mut Image, camera: &Camera, b: &Aabb, rgba: [f32; 4]) {
    let (w, h) = (image.width, image.height);
    let corner = |k: usize| {
        Vec3::new(
            if k & 1 == 0 { b.min.x } else { b.max.x },
            if k & 2 == 0 { b.min.y } else { b.max.y },
            if k & 4 == 0 { b.min.z } else { b.max.z },
        )
    };
    // Near plane for perspective views: a little in front of the eye.
    let near = 1e-4 * b.diagonal().max(f32::MIN_POSITIVE);
    let mut marked = vec![false; image.pixels.len()];
    for a in 0..8usize {
        for bit in [1usize, 2, 4] {
            if a & bit != 0 {
                continue;
            }
            let (mut p, mut q) = (corner(a), corner(a | bit));
            if matches!(camera.projection, Projection::Perspective { .. }) {
                let (zp, zq) = (
                    (p - camera.eye).dot(camera.forward),
                    (q - camera.eye).dot(camera.forward),
                );
                if zp < near && zq < near {
                    continue;
                }
                // Cut the part behind the near plane.
                if zp < near {
                    p = p + (q - p) * ((near - zp) / (zq - zp));
                } else if zq < near {
                    q = q + (p - q) * ((near - zq) / (zp - zq));
                }
            }
            let (Some(s), Some(e)) = (camera.to_pixel(p, w, h), camera.to_pixel(q, w, h)) else {
                continue;
            };
            let len = ((e.0 - s.0).powi(2) + (e.1 - s.1).powi(2)).sqrt();
            if !len.is_finite() {
                continue;
            }
            // Edges far outside the image are walked only where they could show.
            let steps = (3.0 * len).ceil().min(3.0 * 4.0 * (w + h) as f32) as usize + 1;
            for i in 0..=steps {
                let t = i as f32 / steps as f32;
                let (x, y) = (s.0 + (e.0 - s.0) * t, s.1 + (e.1 - s.1) * t);
                // Edges on the image's own border (a box framed exactly) count.
                let (wf, hf) = (w as f32, h as f32);
                if !(x >= -0.5 && y >= -0.5 && x <= wf + 0.5 && y <= hf + 0.5) {
                    continue;
                }
                let (xi, yi) = (
                    x.clamp(0.0, wf - 1.0) as usize,
                    y.clamp(0.0, hf - 1.0) as usize,
                );
                let k = yi * w as usize + xi;
                if !marked[k] {
                    marked[k] = true;
                    let px = &mut image.pixels[k];
                    for c in 0..3 {
                        px[c] = rgba[c] * rgba[3] + px[c] * (1.0 - rgba[3]);
                    }
                    px[3] = rgba[3] + px[3] * (1.0 - rgba[3]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_box_framed_by_an_axis_camera_outlines_the_image_border() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let cam = Camera::axis_projection(&b, 2).unwrap();
        let mut img = Image::new(20, 10);
        draw_box_outline(&mut img, &cam, &b, [1.0, 1.0, 1.0, 1.0]);
        // Every pixel of the border rows and columns, nothing inside.
        for y in 0..10usize {
            for x in 0..20usize {
                let border = x == 0 || y == 0 || x == 19 || y == 9;
                let a = img.pixels[y * 20 + x][3];
                assert_eq!(a > 0.0, border, "pixel ({x}, {y}): {a}");
            }
        }
    }

    #[test]
    fn pixels_of_points_invert_the_camera_rays() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let cam = Camera::framing(&b, 1.5);
        for (x, y) in [(3.5f32, 7.25f32), (120.0, 40.0), (0.5, 99.5)] {
            let ray = cam.ray(x, y, 150, 100);
            let (px, py, _) = cam.to_pixel(ray.origin + ray.dir * 2.7, 150, 100).unwrap();
            assert!((px - x).abs() < 1e-3 && (py - y).abs() < 1e-3, "{px}, {py}");
        }
        // Behind a perspective eye: nowhere.
        assert!(cam.to_pixel(cam.eye - cam.forward, 150, 100).is_none());
    }
}
