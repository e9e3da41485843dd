//! The seam's newer parts on procedural volumes with known answers:
//! constant intervals integrated in closed form, iso-surfaces at their
//! steps, the pass-by-pass film, progress and cancellation.

use super::*;
use voxless_core::{
    Aabb, CancelToken, Interval, IntervalQuery, Projection, Ray, Sample, testing::Resampled,
};
use voxless_transfer::{Colormap, OpacityMap};

/// Two slabs along z with constant values: `lo_value` in z ∈ [0, 0.5),
/// `hi_value` in z ∈ [0.5, 1], handed out as constant intervals.
struct Steps {
    lo_value: f32,
    hi_value: f32,
}

impl Volume for Steps {
    fn bounds(&self) -> Aabb {
        Aabb::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, 1.0, 1.0))
    }
    fn value_range(&self) -> Range1 {
        Range1::new(0.0, self.lo_value.max(self.hi_value))
    }
    fn sample(&self, p: Vec3) -> Option<Sample> {
        self.bounds().contains(p).then(|| {
            Sample::scalar(if p.z < 0.5 {
                self.lo_value
            } else {
                self.hi_value
            })
        })
    }
    fn intervals(&self, ray: &Ray, t: Range1, _: &IntervalQuery, out: &mut Vec<Interval>) {
        let c = self.bounds().clip_ray(ray, t);
        if c.is_empty() {
            return;
        }
        // Where the ray crosses z = 0.5.
        let tm = (0.5 - ray.origin.z) / ray.dir.z;
        let (first, second) = if ray.dir.z > 0.0 {
            (self.lo_value, self.hi_value)
        } else {
            (self.hi_value, self.lo_value)
        };
        let mid = tm.clamp(c.lo, c.hi);
        for (r, v) in [
            (Range1::new(c.lo, mid), first),
            (Range1::new(mid, c.hi), second),
        ] {
            if r.hi > r.lo && v > 0.0 {
                out.push(Interval::constant(r, v));
            }
        }
    }
}

voxless_core::prepare_as_self!(Steps);

fn gray_constant() -> TransferFunction {
    TransferFunction::new(
        Colormap::preset("gray").unwrap(),
        OpacityMap::preset("constant").unwrap(),
    )
}

fn down_z(half: f32) -> Camera {
    Camera::look_at(
        Vec3::new(0.0, 0.0, 5.0),
        Vec3::new(0.0, 0.0, 0.5),
        Vec3::new(0.0, 1.0, 0.0),
        Projection::Orthographic {
            half_width: half,
            half_height: half,
        },
    )
    .unwrap()
}

#[test]
fn constant_intervals_are_integrated_exactly_without_steps_or_jitter() {
    let v = Steps {
        lo_value: 1.0,
        hi_value: 1.0,
    };
    let sigma = 2.5;
    let settings = RenderSettings {
        opacity_scale: sigma,
        early_termination: 1.0,
        spp: 3,
        ..RenderSettings::for_volume(&v, 6, 6)
    };
    let img = render(
        &v,
        &down_z(0.5),
        &gray_constant(),
        &settings,
        &Control::new(),
    )
    .unwrap();
    let want = 1.0 - (-sigma * 1.0f32).exp();
    for p in &img.pixels {
        assert!((p[3] - want).abs() < 1e-6, "alpha {} want {want}", p[3]);
    }
    // The same field sampled point by point converges to it.
    let sampled = Resampled {
        volume: &v,
        step: 0.01,
    };
    let img = render(
        &sampled,
        &down_z(0.5),
        &gray_constant(),
        &settings,
        &Control::new(),
    )
    .unwrap();
    for p in &img.pixels {
        assert!((p[3] - want).abs() < 1e-3, "sampled alpha {}", p[3]);
    }
}

#[test]
fn iso_surfaces_of_constant_pieces_lie_on_their_steps() {
    let tf = gray_constant();
    let camera = down_z(0.5);
    let mut settings = RenderSettings::for_volume(
        &Steps {
            lo_value: 0.5,
            hi_value: 2.0,
        },
        4,
        4,
    );
    settings.volume = false;
    settings.value_range = Range1::new(0.0, 4.0);
    // A step from 2 to 0.5 crosses 1 (looking down −z: the high slab first).
    settings.iso = vec![1.0];
    let steps = Steps {
        lo_value: 0.5,
        hi_value: 2.0,
    };
    let img = render(&steps, &camera, &tf, &settings, &Control::new()).unwrap();
    assert!(
        img.pixels.iter().all(|p| p[3] == 1.0),
        "every ray hits the step"
    );
    // 3 lies above both values: only the entry from the gap (zero) can
    // cross it — and the top face is where the volume is cut, so nothing.
    settings.iso = vec![3.0];
    let img = render(&steps, &camera, &tf, &settings, &Control::new()).unwrap();
    assert!(img.pixels.iter().all(|p| p[3] == 0.0));
    // A value below both: the ray leaves the lower slab at z = 0, the end
    // of its span, where the volume is cut: no surface.
    settings.iso = vec![0.25];
    let img = render(&steps, &camera, &tf, &settings, &Control::new()).unwrap();
    assert!(img.pixels.iter().all(|p| p[3] == 0.0), "cut at the bounds");
    // With the upper slab empty the ray meets a gap (zero) first, and the
    // step up into the lower slab inside its span is a surface.
    let hole = Steps {
        lo_value: 0.5,
        hi_value: 0.0,
    };
    let img = render(&hole, &camera, &tf, &settings, &Control::new()).unwrap();
    assert!(img.pixels.iter().all(|p| p[3] == 1.0), "entry from zero");
}

#[test]
fn passes_accumulate_into_the_same_image_as_a_full_render() {
    let v = Steps {
        lo_value: 0.3,
        hi_value: 1.0,
    };
    let tf = TransferFunction::new(
        Colormap::preset("viridis").unwrap(),
        OpacityMap::preset("linear").unwrap(),
    );
    let camera = Camera::look_at(
        Vec3::new(0.3, -2.0, 2.5),
        Vec3::new(0.0, 0.0, 0.5),
        Vec3::new(0.0, 0.0, 1.0),
        Projection::Perspective { fov_y_deg: 40.0 },
    )
    .unwrap();
    let settings = RenderSettings {
        spp: 3,
        ..RenderSettings::for_volume(&v, 20, 12)
    };
    let full = render(&v, &camera, &tf, &settings, &Control::new()).unwrap();
    let prepared = prepare(&v, &tf, &settings);
    let job = Job::new(&prepared, &camera, &tf, &settings);
    let mut film = job.film();
    assert_eq!(film.resolve().pixels.iter().map(|p| p[3]).sum::<f32>(), 0.0);
    job.pass(&mut film, 0, &Control::new()).unwrap();
    let one = film.resolve();
    let single_settings = RenderSettings {
        spp: 1,
        ..settings.clone()
    };
    let single = render(&v, &camera, &tf, &single_settings, &Control::new()).unwrap();
    assert_eq!(one.pixels, single.pixels, "pass 0 is the 1-spp image");
    job.pass(&mut film, 1, &Control::new()).unwrap();
    job.pass(&mut film, 2, &Control::new()).unwrap();
    assert_eq!(film.passes(), 3);
    assert_eq!(film.resolve().pixels, full.pixels, "bit for bit");
}

#[test]
fn progress_counts_every_tile_once_and_cancellation_stops_between_tiles() {
    let v = Steps {
        lo_value: 0.3,
        hi_value: 1.0,
    };
    let tf = gray_constant();
    let camera = down_z(1.0);
    let mut settings = RenderSettings::for_volume(&v, 64, 48);
    settings.spp = 2;
    let calls = std::sync::atomic::AtomicU64::new(0);
    let last = std::sync::Mutex::new((0u64, 0u64));
    let report = |d: u64, t: u64| {
        calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let mut l = last.lock().unwrap();
        *l = (l.0.max(d), t);
    };
    render(
        &v,
        &camera,
        &tf,
        &settings,
        &Control::new().with_progress(&report),
    )
    .unwrap();
    let tiles = (64u64 / TILE as u64) * (48u64 / TILE as u64);
    assert_eq!(calls.into_inner(), tiles * 2);
    assert_eq!(*last.lock().unwrap(), (tiles * 2, tiles * 2));
    // Cancelled before: nothing runs.
    let token = CancelToken::new();
    token.cancel();
    let ctl = Control::new().with_cancel(token);
    assert_eq!(
        render(&v, &camera, &tf, &settings, &ctl).unwrap_err(),
        Cancelled
    );
    // Cancelled by the first finished tile: the pass stops, the film keeps
    // only the passes done before.
    let token = CancelToken::new();
    let cancel_now = |_: u64, _: u64| token.cancel();
    let ctl = Control::new()
        .with_cancel(token.clone())
        .with_progress(&cancel_now);
    let prepared = prepare(&v, &tf, &settings);
    let job = Job::new(&prepared, &camera, &tf, &settings);
    let mut film = job.film();
    job.pass(&mut film, 0, &Control::new()).unwrap();
    let before = film.resolve();
    assert_eq!(job.pass(&mut film, 1, &ctl).unwrap_err(), Cancelled);
    assert_eq!(film.passes(), 1);
    assert_eq!(film.resolve().pixels, before.pixels);
}

#[test]
fn projections_report_progress_and_stop_when_cancelled() {
    let v = Steps {
        lo_value: 1.0,
        hi_value: 3.0,
    };
    let camera = down_z(0.9);
    let col = project(&v, &camera, 8, 8, &Control::new()).unwrap();
    for c in &col {
        // ∫ over z ∈ [0, 1]: 0.5·1 + 0.5·3, exact for constant pieces.
        assert!((c - 2.0).abs() < 1e-5, "{c}");
    }
    let token = CancelToken::new();
    token.cancel();
    assert!(project(&v, &camera, 8, 8, &Control::new().with_cancel(token)).is_err());
}
