use super::*;
use voxless_core::{Aabb, Interval, IntervalQuery, Projection, Ray, Sample};

voxless_core::prepare_as_self!(Slab, Radial);
use voxless_transfer::{Colormap, OpacityMap};

/// A procedural homogeneous slab `z ∈ [0, thickness]` of value 1 with exact
/// intervals — an analytic oracle for the integrator.
struct Slab {
    thickness: f32,
}

impl Volume for Slab {
    fn bounds(&self) -> Aabb {
        Aabb::new(
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, self.thickness),
        )
    }
    fn value_range(&self) -> Range1 {
        Range1::new(0.0, 1.0)
    }
    fn sample(&self, p: Vec3) -> Option<Sample> {
        self.bounds().contains(p).then(|| Sample::scalar(1.0))
    }
    fn intervals(&self, ray: &Ray, t: Range1, _: &IntervalQuery, out: &mut Vec<Interval>) {
        let c = self.bounds().clip_ray(ray, t);
        if !c.is_empty() {
            out.push(Interval::sampled(c, Range1::new(1.0, 1.0), 0.1));
        }
    }
}

fn white_constant() -> TransferFunction {
    TransferFunction::new(
        Colormap::preset("gray").unwrap(),
        OpacityMap::preset("constant").unwrap(),
    )
}

/// Opacity of one ray through `slab` with a white, constant-opacity transfer function.
fn alpha_along(
    slab: &Slab,
    ray: &Ray,
    step: f32,
    opacity_scale: f32,
    early_termination: f32,
) -> f32 {
    let settings = RenderSettings {
        step: Some(step),
        opacity_scale,
        early_termination,
        ..RenderSettings::for_volume(slab, 1, 1)
    };
    let rng = PixelRng::new(0, 0, 0);
    march(
        slab,
        ray,
        &white_constant(),
        &settings,
        &rng,
        &mut Vec::new(),
    )[3]
}

#[test]
fn homogeneous_slab_transmittance_is_exact_at_any_step() {
    let thickness = 0.37;
    let slab = Slab { thickness };
    let sigma = 3.0;
    let tf = white_constant();
    let camera = Camera::look_at(
        Vec3::new(0.0, 0.0, 5.0),
        Vec3::ZERO,
        Vec3::new(0.0, 1.0, 0.0),
        Projection::Orthographic {
            half_width: 0.5,
            half_height: 0.5,
        },
    )
    .unwrap();
    let want = (-sigma * thickness).exp();
    for step in [0.001, 0.01, 0.033, 0.1, 0.2, 0.3, 0.5, 2.0] {
        let settings = RenderSettings {
            step: Some(step),
            opacity_scale: sigma,
            early_termination: 1.0,
            ..RenderSettings::for_volume(&slab, 8, 8)
        };
        let img = render(&slab, &camera, &tf, &settings, &Control::new()).unwrap();
        for p in &img.pixels {
            let transmittance = 1.0 - p[3];
            assert!(
                (transmittance - want).abs() < 1e-3,
                "step {step}: T = {transmittance}, want {want}"
            );
        }
    }
    // A tilted ray crosses thickness / cos θ.
    let cos = 0.8f32;
    let ray = Ray::new(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(0.6, 0.0, -cos));
    let a = alpha_along(&slab, &ray, 0.07, sigma, 1.0);
    assert!(((1.0 - a) - (-sigma * thickness / cos).exp()).abs() < 1e-3);
}

#[test]
fn early_termination_stops_at_the_threshold() {
    let slab = Slab { thickness: 0.5 };
    let ray = Ray::new(Vec3::new(0.0, 0.0, 2.0), Vec3::new(0.0, 0.0, -1.0));
    let a = alpha_along(&slab, &ray, 0.001, 100.0, 0.9);
    assert!((0.9..0.92).contains(&a), "alpha {a}");
}

#[test]
fn project_of_the_slab_is_its_thickness() {
    let slab = Slab { thickness: 0.25 };
    let camera = Camera::look_at(
        Vec3::new(0.0, 0.0, 5.0),
        Vec3::ZERO,
        Vec3::new(0.0, 1.0, 0.0),
        Projection::Orthographic {
            half_width: 0.9,
            half_height: 0.9,
        },
    )
    .unwrap();
    // The default line integral (Simpson over intervals) of a constant 1.
    for v in project(&slab, &camera, 4, 4, &Control::new()).unwrap() {
        assert!((v - 0.25).abs() < 1e-5, "{v}");
    }
}

/// An analytic field `value = |p|` inside the cube [-1, 1]³, one interval.
struct Radial;

impl Volume for Radial {
    fn bounds(&self) -> Aabb {
        Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0))
    }
    fn value_range(&self) -> Range1 {
        Range1::new(0.0, 3f32.sqrt())
    }
    fn sample(&self, p: Vec3) -> Option<Sample> {
        self.bounds()
            .contains(p)
            .then(|| Sample::scalar(p.length()))
    }
    fn intervals(&self, ray: &Ray, t: Range1, _: &IntervalQuery, out: &mut Vec<Interval>) {
        let c = self.bounds().clip_ray(ray, t);
        if !c.is_empty() {
            out.push(Interval::sampled(c, self.value_range(), 0.05));
        }
    }
}

#[test]
fn iso_surface_is_hit_exactly_where_the_field_crosses() {
    let settings = RenderSettings {
        iso: vec![0.5],
        volume: false,
        ..RenderSettings::for_volume(&Radial, 1, 1)
    };
    let tf = white_constant();
    let alpha_at = |b: f32| {
        let ray = Ray::new(Vec3::new(b, 0.0, 3.0), Vec3::new(0.0, 0.0, -1.0));
        march(
            &Radial,
            &ray,
            &tf,
            &settings,
            &PixelRng::new(0, 0, 0),
            &mut Vec::new(),
        )[3]
    };
    // Inside the sphere |p| = 0.5 the ray crosses the surface; outside it never does.
    for b in [0.0, 0.2, 0.45, 0.49] {
        assert_eq!(alpha_at(b), 1.0, "impact {b}");
    }
    for b in [0.51, 0.6, 0.9] {
        assert_eq!(alpha_at(b), 0.0, "impact {b}");
    }
}

#[test]
fn clip_box_limits_what_is_integrated() {
    let slab = Slab { thickness: 1.0 };
    let sigma = 2.0;
    let ray = Ray::new(Vec3::new(0.1, 0.1, 3.0), Vec3::new(0.0, 0.0, -1.0));
    let settings = RenderSettings {
        step: Some(0.05),
        opacity_scale: sigma,
        early_termination: 1.0,
        clip: Some(Aabb::new(Vec3::splat(-5.0), Vec3::new(5.0, 5.0, 0.3))),
        ..RenderSettings::for_volume(&slab, 1, 1)
    };
    let a = march(
        &slab,
        &ray,
        &white_constant(),
        &settings,
        &PixelRng::new(0, 0, 0),
        &mut Vec::new(),
    )[3];
    assert!(((1.0 - a) - (-sigma * 0.3f32).exp()).abs() < 1e-3, "{a}");
}
