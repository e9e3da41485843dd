//! Plain data shared by every voxless crate: vectors, boxes, rays, value
//! ranges, cameras, images, and the [`Volume`] trait — the one seam between
//! data kinds (particles, AMR, tetrahedra) and integrators — with its
//! per-render [`Prepare`] step, its per-tile hook ([`TileIntervals`]) and
//! render [`Control`] (progress and cancellation); and [`simd`], the
//! eight-lane abstraction that data kinds write their SIMD kernels against
//! once, with the backend ([`Simd`]) chosen by value.
//!
//! Conventions: `f32` world coordinates; rays have unit directions so the ray
//! parameter `t` is a distance; images are row-major with row 0 at the top and
//! hold linear, premultiplied RGBA.

pub mod camera;
pub mod control;
mod forward;
pub mod image;
pub mod macrogrid;
pub mod math;
pub mod mirror;
pub mod outline;
pub mod prepare;
pub mod rng;
pub mod simd;
#[cfg(any(test, feature = "testing"))]
pub mod testing;
pub mod tiles;
pub mod volume;

pub use camera::{Camera, CameraError, Projection};
pub use control::{CancelToken, Cancelled, Control};
pub use image::{Image, linear_to_srgb, srgb_to_linear};
pub use macrogrid::MacroGrid;
pub use math::{Aabb, Range1, Ray, Vec3};
pub use mirror::Mirror;
pub use outline::draw_box_outline;
pub use prepare::{EventBudget, Prepare, PrepareQuery};
pub use rng::SmallRng;
pub use simd::{Lanes, Simd};
pub use tiles::{IntervalLists, TILE, TileIntervals, TileRays, View};
pub use volume::{
    Attribute, Interval, IntervalKind, IntervalQuery, PixelIntegral, Sample, SampleBatch, Volume,
    quadrature_line_integral, simpson,
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ray_in_a_shared_face_belongs_to_exactly_one_box() {
        let lower = Aabb::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 1.0));
        let upper = Aabb::new(Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 1.0, 2.0));
        let all = Range1::new(f32::NEG_INFINITY, f32::INFINITY);
        // Along x, in the plane z = 1 both boxes share.
        let ray = Ray::new(Vec3::new(-1.0, 0.5, 1.0), Vec3::new(1.0, 0.0, 0.0));
        assert!(lower.clip_ray(&ray, all).is_empty());
        assert_eq!(upper.clip_ray(&ray, all), Range1::new(1.0, 2.0));
        // On the outer lower face it is inside, off the box it is not.
        let ray = Ray::new(Vec3::new(-1.0, 0.5, 0.0), Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(lower.clip_ray(&ray, all), Range1::new(1.0, 2.0));
        let ray = Ray::new(Vec3::new(-1.0, 0.5, -0.1), Vec3::new(1.0, 0.0, 0.0));
        assert!(lower.clip_ray(&ray, all).is_empty());
    }

    #[test]
    fn macrogrid_intervals_cover_nonempty_cells_only() {
        let b = Aabb::new(Vec3::ZERO, Vec3::splat(4.0));
        let mut g = MacroGrid::with_cell_size(b, 1.0, 64);
        assert_eq!(g.dims, [4, 4, 4]);
        // Mark cells x = 1 and x = 3 on the row y = 0, z = 0 as occupied.
        let mut ranges = g.ranges().to_vec();
        ranges[g.index(1, 0, 0)] = Range1::new(0.0, 1.0);
        ranges[g.index(3, 0, 0)] = Range1::new(0.0, 2.0);
        g.set_ranges(ranges.clone());
        let ray = Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::new(1.0, 0.0, 0.0));
        let mut out = Vec::new();
        g.intervals(
            &ray,
            Range1::new(0.0, 100.0),
            0.1,
            &IntervalQuery::all(),
            &mut out,
        );
        assert_eq!(out.len(), 2);
        assert!((out[0].t.lo - 2.0).abs() < 1e-5 && (out[0].t.hi - 3.0).abs() < 1e-5);
        assert!((out[1].t.lo - 4.0).abs() < 1e-5 && (out[1].t.hi - 5.0).abs() < 1e-5);
        // Adjacent occupied cells merge, with the union of their ranges.
        ranges[g.index(2, 0, 0)] = Range1::new(0.5, 0.7);
        g.set_ranges(ranges);
        out.clear();
        g.intervals(
            &ray,
            Range1::new(0.0, 100.0),
            0.1,
            &IntervalQuery::all(),
            &mut out,
        );
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].value_range, Range1::new(0.0, 2.0));
        // An invisible range is a gap.
        let hide = |r: Range1| r.hi > 1.5;
        out.clear();
        g.intervals(
            &ray,
            Range1::new(0.0, 100.0),
            0.1,
            &IntervalQuery { is_visible: &hide },
            &mut out,
        );
        assert_eq!(out.len(), 1);
        assert!((out[0].t.lo - 4.0).abs() < 1e-5);
    }

    #[test]
    fn macrogrid_diagonal_ray_visits_every_cell_once() {
        let b = Aabb::new(Vec3::ZERO, Vec3::splat(8.0));
        let mut g = MacroGrid::with_cell_size(b, 1.0, 64);
        g.set_ranges(vec![Range1::new(0.0, 1.0); g.len()]);
        let ray = Ray::new(
            Vec3::new(-1.0, -0.7, -0.3),
            Vec3::new(1.0, 0.9, 0.8).normalized(),
        );
        let mut out = Vec::new();
        g.intervals(
            &ray,
            Range1::new(0.0, 1e9),
            0.1,
            &IntervalQuery::all(),
            &mut out,
        );
        let clip = b.clip_ray(&ray, Range1::new(0.0, 1e9));
        assert_eq!(out.len(), 1);
        assert!((out[0].t.lo - clip.lo).abs() < 1e-4 && (out[0].t.hi - clip.hi).abs() < 1e-4);
    }

    #[test]
    fn camera_rejects_degenerate_vectors() {
        let p = Projection::Perspective { fov_y_deg: 40.0 };
        assert!(Camera::look_at(Vec3::ZERO, Vec3::ZERO, Vec3::new(0.0, 1.0, 0.0), p).is_err());
        assert!(
            Camera::look_at(
                Vec3::ZERO,
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
                p
            )
            .is_err()
        );
        assert!(
            Camera::look_at(
                Vec3::splat(f32::NAN),
                Vec3::ZERO,
                Vec3::new(0.0, 1.0, 0.0),
                p
            )
            .is_err()
        );
    }

    #[test]
    fn srgb_round_trip() {
        for i in 0..=100 {
            let v = i as f32 / 100.0;
            assert!((srgb_to_linear(linear_to_srgb(v)) - v).abs() < 1e-5);
        }
    }
}
