//! AMR frames: adaptive sampling and transfer-function space skipping on
//! and off (see the parent module for the setup).
//!
//! Skipping "on" renders the context `AmrContext::new` builds for the TF —
//! exactly what `voxless_render::render` prepares for an `AmrVolume` (a test
//! below holds the two images equal) — and "off" a context with every
//! region visible. Both still drop intervals whose range the TF makes
//! invisible, so the "none" rows wrap the all-regions context in [`NoSkip`],
//! which asks it for every interval. Contexts are built before the timer
//! starts and rendered by the shared integrator
//! ([`crate::common::render_prepared`]); samples per pixel come from an
//! untimed pass through the [`Counting`] wrapper.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use anyhow::Result;
use voxless_amr::{AmrContext, AmrVolume};
use voxless_core::{
    Aabb, Camera, Image, Interval, IntervalQuery, Range1, Ray, Sample, Vec3, Volume,
};
use voxless_render::RenderSettings;
use voxless_transfer::TransferFunction;

use super::{AmrArgs, Dataset, half_tf};
use crate::common::{image_diff, median, render_prepared, save_png};

/// A volume that hands out every interval, visible or not: what the
/// renderer does without any transfer-function space skipping.
pub struct NoSkip<V>(pub V);

impl<V: Volume> Volume for NoSkip<V> {
    fn bounds(&self) -> Aabb {
        self.0.bounds()
    }
    fn value_range(&self) -> Range1 {
        self.0.value_range()
    }
    fn attribute_range(&self) -> Option<Range1> {
        self.0.attribute_range()
    }
    fn sample(&self, p: Vec3) -> Option<Sample> {
        self.0.sample(p)
    }
    fn gradient(&self, p: Vec3) -> Vec3 {
        self.0.gradient(p)
    }
    fn sample_with_gradient(&self, p: Vec3) -> Option<(Sample, Vec3)> {
        self.0.sample_with_gradient(p)
    }
    fn sample_in(&self, p: Vec3, iv: &Interval) -> Option<Sample> {
        self.0.sample_in(p, iv)
    }
    fn sample_with_gradient_in(&self, p: Vec3, iv: &Interval) -> Option<(Sample, Vec3)> {
        self.0.sample_with_gradient_in(p, iv)
    }
    fn intervals(&self, ray: &Ray, t: Range1, _: &IntervalQuery, out: &mut Vec<Interval>) {
        self.0.intervals(ray, t, &IntervalQuery::all(), out)
    }
    fn line_integral(&self, ray: &Ray, t: Range1) -> f64 {
        self.0.line_integral(ray, t)
    }
}

/// Counts the samples the renderer takes (an untimed pass).
struct Counting<'a, V> {
    inner: &'a V,
    samples: AtomicU64,
}

impl<V: Volume> Counting<'_, V> {
    fn tick(&self) {
        self.samples.fetch_add(1, Ordering::Relaxed);
    }
}

impl<V: Volume> Volume for Counting<'_, V> {
    fn bounds(&self) -> Aabb {
        self.inner.bounds()
    }
    fn value_range(&self) -> Range1 {
        self.inner.value_range()
    }
    fn attribute_range(&self) -> Option<Range1> {
        self.inner.attribute_range()
    }
    fn sample(&self, p: Vec3) -> Option<Sample> {
        self.tick();
        self.inner.sample(p)
    }
    fn sample_with_gradient(&self, p: Vec3) -> Option<(Sample, Vec3)> {
        self.tick();
        self.inner.sample_with_gradient(p)
    }
    fn sample_in(&self, p: Vec3, iv: &Interval) -> Option<Sample> {
        self.tick();
        self.inner.sample_in(p, iv)
    }
    fn sample_with_gradient_in(&self, p: Vec3, iv: &Interval) -> Option<(Sample, Vec3)> {
        self.tick();
        self.inner.sample_with_gradient_in(p, iv)
    }
    fn intervals(&self, ray: &Ray, t: Range1, q: &IntervalQuery, out: &mut Vec<Interval>) {
        self.inner.intervals(ray, t, q, out)
    }
    fn line_integral(&self, ray: &Ray, t: Range1) -> f64 {
        self.inner.line_integral(ray, t)
    }
}

/// Samples per pixel a render of `v` takes at a quarter of the resolution
/// (per pixel the count hardly depends on the resolution).
fn samples_per_pixel<V: Volume>(
    v: &V,
    camera: &Camera,
    tf: &TransferFunction,
    rs: &RenderSettings,
) -> Result<f64> {
    let mut rs = rs.clone();
    rs.width = (rs.width / 4).max(16);
    rs.height = (rs.height / 4).max(16);
    let c = Counting {
        inner: v,
        samples: AtomicU64::new(0),
    };
    render_prepared(&c, camera, tf, &rs)?;
    Ok(c.samples.load(Ordering::Relaxed) as f64 / (rs.width as f64 * rs.height as f64))
}

/// Space skipping of one configuration.
#[derive(Clone, Copy, PartialEq)]
enum Skip {
    /// The context for the TF: the region tree's walk skips subtrees
    /// without a visible region.
    On,
    /// A context with every region: invisible intervals still dropped.
    Off,
    /// Every interval handed out and sampled.
    None,
}

pub(super) fn bench_frames(s: &Dataset, vol: &AmrVolume, o: &AmrArgs) -> Result<Vec<String>> {
    let tf = half_tf(vol, s.field)?;
    let cut = tf.opacity_map().0.points()[1].0;
    let camera = Camera::framing(&vol.bounds(), 1.0);
    let adaptive = RenderSettings::for_volume(vol, o.size, o.size);
    let finest = vol.bricks().iter().map(|b| b.width()).min().unwrap_or(1);
    let mut fixed = adaptive.clone();
    fixed.step = Some(0.5 * finest as f32 * s.cells.cell_size);
    // The renderer's own visibility test (no iso-surfaces here).
    let tf_visible = |r: Range1| adaptive.is_visible(&tf, r);
    eprintln!("amr/{}: preparing contexts", s.label);
    let visible = AmrContext::new(vol, &tf_visible);
    let every = AmrContext::new(vol, &|_| true);
    let onoff = |b: bool| if b { "on" } else { "off" };
    let skip_name = |k: Skip| match k {
        Skip::On => "on",
        Skip::Off => "off",
        Skip::None => "none",
    };
    let configs = [
        (false, Skip::Off),
        (true, Skip::Off),
        (false, Skip::On),
        (true, Skip::On),
        (false, Skip::None),
        (true, Skip::None),
    ];
    let in_bvh = |skip: Skip| match skip {
        Skip::On => visible.visible_region_count(),
        Skip::Off | Skip::None => every.visible_region_count(),
    };
    let settings = |adapt: bool| if adapt { &adaptive } else { &fixed };
    let mut spp = vec![0.0; configs.len()];
    for (k, &(adapt, skip)) in configs.iter().enumerate() {
        eprintln!("amr/{}: counting samples, config {}", s.label, k + 1);
        let rs = settings(adapt);
        spp[k] = match skip {
            Skip::On => samples_per_pixel(&visible, &camera, &tf, rs)?,
            Skip::Off => samples_per_pixel(&every, &camera, &tf, rs)?,
            Skip::None => samples_per_pixel(&NoSkip(&every), &camera, &tf, rs)?,
        };
    }
    // Repeats go round all configurations, so that load from elsewhere on
    // the machine hits every configuration alike.
    let mut times = vec![Vec::new(); configs.len()];
    let mut images: Vec<Option<Image>> = vec![None; configs.len()];
    for rep in 0..o.frame_repeats {
        for (k, &(adapt, skip)) in configs.iter().enumerate() {
            let rs = settings(adapt);
            eprintln!(
                "amr/{}: rendering ({}/{}), adaptive {}, skipping {}",
                s.label,
                rep + 1,
                o.frame_repeats,
                onoff(adapt),
                skip_name(skip)
            );
            let t = Instant::now();
            let img = match skip {
                Skip::On => render_prepared(&visible, &camera, &tf, rs)?,
                Skip::Off => render_prepared(&every, &camera, &tf, rs)?,
                Skip::None => render_prepared(&NoSkip(&every), &camera, &tf, rs)?,
            };
            times[k].push(t.elapsed().as_secs_f64());
            images[k] = Some(img);
        }
    }
    let times: Vec<f64> = times.into_iter().map(median).collect();
    let images: Vec<Image> = images.into_iter().flatten().collect();
    let mut rows = Vec::new();
    for (k, &(adapt, skip)) in configs.iter().enumerate() {
        if let Some(dir) = &o.save {
            let stem = format!(
                "{}-adaptive-{}-skip-{}",
                s.label.replace(' ', "-"),
                onoff(adapt),
                skip_name(skip)
            );
            save_png(&dir.join(format!("{stem}.png")), &images[k])?;
        }
        let diff = image_diff(&images[0], &images[k]).0;
        let skipping = match skip {
            Skip::On => "on (tree masked to visible regions)",
            Skip::Off => "off (every region walked)",
            Skip::None => "none (every interval sampled)",
        };
        let step = match settings(adapt).step {
            Some(dt) => format!("{dt:.3e} fixed"),
            None => "½ region finest".into(),
        };
        rows.push(format!(
            "| {} | {cut:.3} | {} | {skipping} | {} | {step} | {:.0} | {:.2} | {:.2} | {diff:.2e} |",
            s.label,
            onoff(adapt),
            in_bvh(skip),
            spp[k],
            times[k],
            times[0] / times[k]
        ));
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use voxless_amr::AmrSettings;
    use voxless_core::Control;

    /// Skipping "on" is what the library's render prepares; "none" samples
    /// more but shows the same image up to the sampling of invisible space.
    #[test]
    fn skipping_on_is_the_library_render() {
        let cells = super::super::data::synthetic(150_000);
        let vol = AmrVolume::new(cells, AmrSettings::default()).unwrap();
        let tf = half_tf(&vol, 0).unwrap();
        let camera = Camera::framing(&vol.bounds(), 1.0);
        let rs = RenderSettings::for_volume(&vol, 48, 48);
        let visible = AmrContext::new(&vol, &|r| rs.is_visible(&tf, r));
        assert!(visible.visible_region_count() < vol.regions().len());
        let ours = render_prepared(&visible, &camera, &tf, &rs).unwrap();
        let library = voxless_render::render(&vol, &camera, &tf, &rs, &Control::new()).unwrap();
        assert_eq!(ours.pixels, library.pixels);
        let every = AmrContext::new(&vol, &|_| true);
        let none = render_prepared(&NoSkip(&every), &camera, &tf, &rs).unwrap();
        let (max, _) = image_diff(&none, &library);
        assert!(max < 0.05, "{max}");
        let n_on = samples_per_pixel(&visible, &camera, &tf, &rs).unwrap();
        let n_none = samples_per_pixel(&NoSkip(&every), &camera, &tf, &rs).unwrap();
        assert!(n_none > n_on, "{n_none} vs {n_on}");
    }
}
