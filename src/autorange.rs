//! Transfer-function defaults from the data itself: the value range from
//! robust percentiles of the field, and the opacity scale from a target
//! optical depth — so a default image shows the data, whatever its units
//! and whatever its kind.
//!
//! **The probe** ([`Probe`]): rays parallel to each axis through a
//! [`GRID`]×[`GRID`] grid across the volume's bounds, sampled at
//! [`SAMPLES`] midpoints each. The samples the data covers are what a
//! render sees, weighted by volume (not by particle or cell), and they do
//! not depend on the camera, so orbiting or a turntable keeps the same
//! transfer function. Probes of several frames of a time series merge into
//! one, so a series gets one range and one opacity scale for all frames.
//!
//! **The value range** ([`Probe::value_range`]): linear scale: from 0 for a
//! density field that is zero outside its support (particles), else from
//! the [`LOW_PERCENTILE`]th percentile, to the [`HIGH_PERCENTILE`]th of the
//! covered samples; log scale (tessellations): the same percentiles of the
//! positive samples in log10, at least one decade wide. A few extreme
//! samples (a dense clump, one hot cell) then neither darken nor wash out
//! the rest; values beyond the range saturate.
//!
//! **The opacity scale** ([`Probe::opacity_scale`]): the extinction per
//! unit length at opacity 1 such that the median of the rays that meet any
//! opacity reaches optical depth [`TARGET_OPTICAL_DEPTH`], i.e. lets
//! `e^-τ` ≈ 13 % of the light through: the front of the data shows, and so
//! does what lies behind it.

use rayon::prelude::*;
use voxless_core::{Aabb, Range1, Vec3, Volume};
use voxless_render::RenderSettings;
use voxless_transfer::TransferFunction;

use crate::AnyVolume;

/// Rays per axis direction: `GRID`² of them.
pub const GRID: usize = 24;
/// Samples per probe ray.
pub const SAMPLES: usize = 96;
/// Lower percentile of the default value range (fields with a floor of 0,
/// i.e. particle densities, start at 0).
pub const LOW_PERCENTILE: f64 = 50.0;
/// Upper percentile of the default value range.
pub const HIGH_PERCENTILE: f64 = 99.5;
/// Optical depth of the median ray through the data.
pub const TARGET_OPTICAL_DEPTH: f64 = 2.0;

/// The field along the probe rays (see the module docs).
#[derive(Clone, Debug, Default)]
pub struct Probe {
    rays: Vec<ProbeRay>,
}

/// One probe ray: parallel to axis `axis` from `start`, samples at
/// `start + (k + ½)·dt` along it.
#[derive(Clone, Debug)]
struct ProbeRay {
    start: Vec3,
    axis: usize,
    /// The step between samples (local units).
    dt: f32,
    /// Half the spacing of the probe's grid across the ray.
    half_cell: [f32; 3],
    /// The value at each sample (NaN where the data does not cover it).
    values: Vec<f32>,
}

/// Opacity (of the transfer function's maximum 1) below which a probe
/// sample does not count as visible for framing.
const VISIBLE_OPACITY: f32 = 0.02;

/// The opacity field's finite value at every point of `points` (NaN where
/// the data does not cover it). A tessellation takes them all in one sweep
/// over its cells, the same values its point index would give, without
/// building that index (seconds at 10⁸ tets; see `voxless_tets`).
pub(crate) fn values_at(volume: &AnyVolume, points: &[Vec3]) -> Vec<f32> {
    let finite = |v: Option<f32>| v.filter(|v| v.is_finite()).unwrap_or(f32::NAN);
    match volume {
        AnyVolume::Tets(v) => v
            .samples(points)
            .into_iter()
            .map(|s| finite(s.map(|s| s.value)))
            .collect(),
        _ => points
            .par_iter()
            .map(|&q| finite(value_at(volume, q)))
            .collect(),
    }
}

/// [`values_at`] of the points `i` for which `keep(i)` holds (in
/// `volume`, when there is one); NaN at the others.
pub(crate) fn values_where(
    volume: Option<&AnyVolume>,
    points: &[Vec3],
    keep: impl Fn(usize) -> bool,
) -> Vec<f32> {
    let kept: Vec<usize> = (0..points.len()).filter(|&i| keep(i)).collect();
    let mut out = vec![f32::NAN; points.len()];
    if let Some(v) = volume {
        let at: Vec<Vec3> = kept.iter().map(|&i| points[i]).collect();
        for (&i, value) in kept.iter().zip(values_at(v, &at)) {
            out[i] = value;
        }
    }
    out
}

/// The opacity-field value at `p`, when the data covers it.
pub(crate) fn value_at(volume: &AnyVolume, p: Vec3) -> Option<f32> {
    match volume {
        AnyVolume::Particles(v) => v.sample(p).map(|s| s.value),
        AnyVolume::Amr(v) => v.sample(p).map(|s| s.value),
        AnyVolume::Tets(v) => v.sample(p).map(|s| s.value),
        AnyVolume::Materials(_) => None,
    }
}

impl Probe {
    /// The probe of `volume` within its bounds (and the `clip` box, when
    /// given; both local). Empty for multi-material volumes, whose
    /// materials each classify their own density.
    pub fn of(volume: &AnyVolume, clip: Option<&Aabb>) -> Probe {
        if matches!(volume, AnyVolume::Materials(_)) {
            return Probe::default();
        }
        let mut b = volume.bounds();
        if let Some(c) = clip {
            b = Aabb::new(b.min.max(c.min), b.max.min(c.max));
        }
        Probe::within(volume, &b)
    }

    fn within(volume: &AnyVolume, b: &Aabb) -> Probe {
        Probe::from_values(b, &values_at(volume, &Probe::points(b)))
    }

    /// The probe's sample points within the box `b` (local), ray after ray
    /// (three axes, [`GRID`]² rays each, [`SAMPLES`] points per ray); empty
    /// for an empty or non-finite box. A decomposed volume samples each
    /// point in the box that holds it and assembles the values in this
    /// order ([`Probe::from_values`]).
    pub fn points(b: &Aabb) -> Vec<Vec3> {
        Probe::rays(b)
            .into_iter()
            .flat_map(|(ray, _)| ray)
            .collect()
    }

    /// The probe within `b` whose field at [`Probe::points`]`(b)` is
    /// `values` (NaN where the data does not cover the point).
    pub fn from_values(b: &Aabb, values: &[f32]) -> Probe {
        let rays = Probe::rays(b)
            .into_iter()
            .enumerate()
            .map(|(r, (_, mut ray))| {
                ray.values = (0..SAMPLES)
                    .map(|k| values.get(r * SAMPLES + k).copied().unwrap_or(f32::NAN))
                    .collect();
                ray
            })
            .collect();
        Probe { rays }
    }

    /// Every probe ray within `b`: its sample points, and the ray (values
    /// not yet filled).
    fn rays(b: &Aabb) -> Vec<(Vec<Vec3>, ProbeRay)> {
        if b.is_empty() || !b.min.is_finite() || !b.max.is_finite() {
            return Vec::new();
        }
        let e = b.extent();
        let jobs: Vec<(usize, usize, usize)> = (0..3)
            .flat_map(|a| (0..GRID).flat_map(move |i| (0..GRID).map(move |j| (a, i, j))))
            .collect();
        jobs.iter()
            .map(|&(a, i, j)| {
                let (u, v) = ((a + 1) % 3, (a + 2) % 3);
                let mut p = b.min;
                let at = |k: usize, n: usize, axis: usize| {
                    b.min[axis] + e[axis] * ((k as f32 + 0.5) / n as f32)
                };
                let mut set = |axis: usize, x: f32| match axis {
                    0 => p.x = x,
                    1 => p.y = x,
                    _ => p.z = x,
                };
                set(u, at(i, GRID, u));
                set(v, at(j, GRID, v));
                let dt = e[a] / SAMPLES as f32;
                let points = (0..SAMPLES)
                    .map(|k| {
                        let mut q = p;
                        match a {
                            0 => q.x = at(k, SAMPLES, 0),
                            1 => q.y = at(k, SAMPLES, 1),
                            _ => q.z = at(k, SAMPLES, 2),
                        }
                        q
                    })
                    .collect();
                let mut start = p;
                match a {
                    0 => start.x = b.min.x,
                    1 => start.y = b.min.y,
                    _ => start.z = b.min.z,
                }
                let mut half_cell = [0.5 * dt; 3];
                half_cell[u] = 0.5 * e[u] / GRID as f32;
                half_cell[v] = 0.5 * e[v] / GRID as f32;
                (
                    points,
                    ProbeRay {
                        start,
                        axis: a,
                        dt,
                        half_cell,
                        values: Vec::new(),
                    },
                )
            })
            .collect()
    }

    /// Adds another probe's rays (another frame of a time series).
    pub fn merge(&mut self, other: Probe) {
        self.rays.extend(other.rays);
    }

    /// Whether no ray met any data.
    pub fn is_empty(&self) -> bool {
        !self
            .rays
            .iter()
            .any(|r| r.values.iter().any(|x| !x.is_nan()))
    }

    /// The `q`th percentile (0..=100) of the covered samples that pass
    /// `keep`.
    fn percentile(&self, q: f64, keep: impl Fn(f32) -> bool) -> Option<f32> {
        let mut v: Vec<f32> = self
            .rays
            .iter()
            .flat_map(|r| r.values.iter().copied())
            .filter(|x| !x.is_nan() && keep(*x))
            .collect();
        if v.is_empty() {
            return None;
        }
        let k = ((q / 100.0) * (v.len() - 1) as f64).round() as usize;
        let k = k.min(v.len() - 1);
        Some(*v.select_nth_unstable_by(k, f32::total_cmp).1)
    }

    /// The default value range (module docs): `floor_zero` for fields that
    /// are 0 outside their support; `log` for a log10 transfer function
    /// (the range is then in log10 units). `None` when the probe saw no
    /// usable value.
    pub fn value_range(&self, floor_zero: bool, log: bool) -> Option<Range1> {
        if log {
            let hi = self.percentile(HIGH_PERCENTILE, |x| x > 0.0)?.log10();
            let lo = self.percentile(LOW_PERCENTILE, |x| x > 0.0)?.log10();
            let lo = lo.min(hi - 1.0);
            return (lo.is_finite() && hi.is_finite()).then(|| Range1::new(lo, hi));
        }
        let hi = self.percentile(HIGH_PERCENTILE, |_| true)?;
        let lo = if floor_zero {
            0.0
        } else {
            self.percentile(LOW_PERCENTILE, |_| true)?
        };
        if !(lo.is_finite() && hi.is_finite()) || hi <= lo {
            return None;
        }
        Some(Range1::new(lo, hi))
    }

    /// The opacity scale (local units) that gives the median ray meeting
    /// any opacity optical depth [`TARGET_OPTICAL_DEPTH`] under `tf` and
    /// `settings`' value range and scale; `None` when no ray meets opacity.
    pub fn opacity_scale(&self, tf: &TransferFunction, settings: &RenderSettings) -> Option<f32> {
        let mut depths: Vec<f64> = self
            .rays
            .iter()
            .map(|r| {
                r.values
                    .iter()
                    .filter(|x| !x.is_nan())
                    .map(|&x| tf.opacity(settings.normalize(x)) as f64 * r.dt as f64)
                    .sum::<f64>()
            })
            .filter(|&d| d > 0.0 && d.is_finite())
            .collect();
        if depths.is_empty() {
            return None;
        }
        let mid = depths.len() / 2;
        let median = *depths.select_nth_unstable_by(mid, f64::total_cmp).1;
        let s = (TARGET_OPTICAL_DEPTH / median) as f32;
        (s.is_finite() && s > 0.0).then_some(s)
    }

    /// The box (local units) around the probe samples that `tf` and
    /// `settings` make visible (opacity above `VISIBLE_OPACITY`), padded by
    /// the probe's spacing: what a default camera frames. `None` when no
    /// sample is visible.
    pub fn visible_box(&self, tf: &TransferFunction, settings: &RenderSettings) -> Option<Aabb> {
        let mut b = Aabb::EMPTY;
        for r in &self.rays {
            for (k, &x) in r.values.iter().enumerate() {
                if x.is_nan() || tf.opacity(settings.normalize(x)) <= VISIBLE_OPACITY {
                    continue;
                }
                let mut p = r.start;
                let t = (k as f32 + 0.5) * r.dt;
                match r.axis {
                    0 => p.x += t,
                    1 => p.y += t,
                    _ => p.z += t,
                }
                let h = Vec3::new(r.half_cell[0], r.half_cell[1], r.half_cell[2]);
                b.grow(p - h);
                b.grow(p + h);
            }
        }
        (!b.is_empty()).then_some(b)
    }
}
