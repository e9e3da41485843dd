//! Levels of detail: particles merged into fewer, wider kernels, for
//! previews (the viewer's coarse images) of sets too large to render at
//! interactive rates.
//!
//! The volume's particles are in Hilbert order, so a run of `8^level`
//! consecutive particles is a compact clump — the particles of one BVH
//! subtree. Each run becomes one kernel of the same family that keeps the
//! run's
//!
//! - **mass** `M = Σ mᵢ`, `mᵢ = wᵢ·∫φ` (the kernel's integral for the
//!   particle's radius and weight): `∫Φ dV` is unchanged, so a projection
//!   of the merged volume conserves mass exactly;
//! - **centroid** `c = Σ mᵢ xᵢ / M`;
//! - **second moment** about the centroid, `Σ mᵢ (s·rᵢ² + |xᵢ − c|²/3) / M
//!   = s·R²` per axis, with `s·r²` the kernel's own variance per axis at
//!   radius `r`: the merged kernel's radius `R` spreads the mass as far as
//!   the run's particles and kernels together do;
//! - **attribute** as the mass-weighted mean (what Θ would average to).
//!
//! Error: far from a run (distances beyond its extent) the merged field
//! matches the run's to second order (mass, centroid and second moment
//! agree); near it, the merged kernel is a smoothed version of the run, so
//! it is used only where its support covers few pixels of the image — a
//! preview at reduced resolution. Tested: the total mass to 1e-6, and the
//! merged projection against the exact one at the preview's resolution.

use rayon::prelude::*;

use voxless_core::Vec3;

use super::{ParticleData, ParticleVolume};
use crate::error::ParticleError;
use crate::kernel::Kernel;

/// Sets of at least this many particles get a preview.
pub const PREVIEW_MIN: usize = 1 << 20;

/// A preview holds about this many merged particles (at most; the level is
/// the smallest whose runs bring the count below it).
pub const PREVIEW_TARGET: usize = 1 << 18;

impl ParticleVolume {
    /// The volume with every run of `8^level` consecutive particles (volume
    /// order, ghosts left out) merged into one (see the module docs); the
    /// same settings, without the radius and weight maps (the merged radii
    /// and weights are the effective ones).
    pub fn merged(&self, level: u32) -> Result<ParticleVolume, ParticleError> {
        let run = 8usize.saturating_pow(level).max(1);
        let kernel = self.settings.kernel;
        let s = variance_factor(kernel);
        let own: Vec<u32> = (0..self.len())
            .filter(|&i| !self.is_ghost(i) && self.radius[i] > 0.0)
            .map(|i| i as u32)
            .collect();
        // Per run, in one pass: M = Σ m, Σ m·x, Σ m·a and the second moment
        // about the origin Σ m (s r² + |x|²/3); the centroid's is that minus
        // M|c|²/3 (in f64: with |x| up to the data's size and a run's extent
        // a thousandth of it, the difference keeps ~10 of 16 digits).
        let merged: Vec<Option<(Vec3, f32, f32, f32)>> = own
            .par_chunks(run)
            .map(|members| {
                let (mut mass, mut c, mut attr, mut second) = (0.0f64, [0.0f64; 3], 0.0f64, 0.0);
                for &i in members {
                    let i = i as usize;
                    let r = self.radius[i] as f64;
                    let m = self.weight[i] as f64 * kernel.integral(r);
                    let p = self.packed[i].center;
                    let p = [p.x as f64, p.y as f64, p.z as f64];
                    mass += m;
                    for (ca, pa) in c.iter_mut().zip(p) {
                        *ca += m * pa;
                    }
                    attr += m * self.attribute.as_ref().map_or(0.0, |a| a[i] as f64);
                    second += m * (s * r * r + p.iter().map(|v| v * v).sum::<f64>() / 3.0);
                }
                if !(mass > 0.0) {
                    return None;
                }
                let c = c.map(|v| v / mass);
                let about = (second - mass * c.iter().map(|v| v * v).sum::<f64>() / 3.0).max(0.0);
                let radius = (about / mass / s).sqrt();
                // The weight that gives the merged kernel the run's mass.
                let weight = mass / kernel.integral(radius);
                let centre = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32);
                Some((centre, radius as f32, weight as f32, (attr / mass) as f32))
            })
            .collect();
        let mut data = ParticleData {
            positions: Vec::with_capacity(merged.len()),
            radii: Some(Vec::with_capacity(merged.len())),
            attribute: self
                .attribute
                .as_ref()
                .map(|_| Vec::with_capacity(merged.len())),
            weights: Some(Vec::with_capacity(merged.len())),
        };
        for (centre, radius, weight, attr) in merged.into_iter().flatten() {
            data.positions.push(centre);
            data.radii.as_mut().expect("radii").push(radius);
            data.weights.as_mut().expect("weights").push(weight);
            if let Some(a) = data.attribute.as_mut() {
                a.push(attr);
            }
        }
        let mut settings = self.settings.clone();
        settings.radius_map = None;
        settings.weight_map = None;
        if settings.attribute_range.is_none() {
            settings.attribute_range = self.attribute_range;
        }
        ParticleVolume::new(data, settings)
    }

    /// The preview of a large set (at least [`PREVIEW_MIN`] particles): its
    /// particles merged down to about [`PREVIEW_TARGET`], built on first
    /// use; `None` for smaller sets (they render fast enough) or when the
    /// merge fails.
    pub fn preview(&self) -> Option<&ParticleVolume> {
        let n = self.particle_count();
        if n < PREVIEW_MIN {
            return None;
        }
        self.preview
            .get_or_init(|| {
                let mut level = 1;
                while n / 8usize.pow(level) > PREVIEW_TARGET {
                    level += 1;
                }
                self.merged(level).ok().map(Box::new)
            })
            .as_deref()
    }
}

/// The kernel's variance per axis at radius 1: `⟨x²⟩ = ½ ∫F(b) b³ db /
/// ∫F(b) b db` over its column `F` (the projection along z keeps the x and
/// y moments), by Simpson's rule (4,000 column reads: once per merge).
fn variance_factor(kernel: Kernel) -> f64 {
    let column = kernel.column(1.0);
    let support = kernel.support_factor() as f64;
    let f3 = |b: f64| column.at(b * b) * b * b * b;
    let f1 = |b: f64| column.at(b * b) * b;
    0.5 * voxless_core::simpson(f3, 0.0, support, 2000)
        / voxless_core::simpson(f1, 0.0, support, 2000)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ParticleSettings;
    use voxless_core::{Aabb, Camera, Control, SmallRng, Volume};

    fn volume(n: usize, kernel: Kernel, periodic: bool) -> ParticleVolume {
        let mut rng = SmallRng(3);
        let positions: Vec<Vec3> = (0..n)
            .map(|i| {
                // Clumps and a background.
                let c = if i % 2 == 0 { 0.3 } else { 0.5 };
                let s = if i % 2 == 0 { 0.1 } else { 1.0 };
                Vec3::new(
                    c + s * (rng.f() - 0.5),
                    c + s * (rng.f() - 0.5),
                    c + s * (rng.f() - 0.5),
                )
            })
            .collect();
        let data = ParticleData {
            // Kernels overlapping their neighbours, as SPH's do (~32 of
            // them): the clump's spacing is ~0.004, the background's ~0.04.
            radii: Some(
                (0..n)
                    .map(|i| if i % 2 == 0 { 0.01 } else { 0.08 } * (1.0 + (i % 5) as f32 / 10.0))
                    .collect(),
            ),
            weights: Some((0..n).map(|i| 1.0 + (i % 3) as f32).collect()),
            attribute: Some((0..n).map(|i| (i % 7) as f32).collect()),
            positions,
        };
        let settings = ParticleSettings {
            kernel,
            periodic: periodic.then(|| Aabb::new(Vec3::splat(0.0), Vec3::splat(1.0))),
            ..Default::default()
        };
        ParticleVolume::new(data, settings).unwrap()
    }

    #[test]
    fn merged_kernels_keep_the_mass_and_the_large_scale_field() {
        for (kernel, periodic) in [
            (Kernel::CubicSpline, true),
            (Kernel::WendlandC2, false),
            (Kernel::Gaussian3, false),
        ] {
            let v = volume(40_000, kernel, periodic);
            let m = v.merged(1).unwrap();
            assert!(m.particle_count() <= 40_000 / 8 + 1);
            let (a, b) = (v.total_mass(), m.total_mass());
            assert!((a / b - 1.0).abs() <= 1e-6, "{kernel:?}: {a} vs {b}");
            // The images at 256², averaged over 16×16-pixel blocks (1/16 of
            // the box, wider than the merged supports): the field at the
            // scale the merged kernels keep.
            let cam =
                Camera::axis_projection(&Aabb::new(Vec3::splat(0.0), Vec3::splat(1.0)), 2).unwrap();
            let c = Control::new();
            let exact = v.project_image(&cam, 256, 256, &c).unwrap().unwrap();
            let lod = m.project_image(&cam, 256, 256, &c).unwrap().unwrap();
            let blocks = |img: &[f32]| {
                let mut b = vec![0.0f64; 256];
                for (k, &x) in img.iter().enumerate() {
                    b[(k / 256 / 16) * 16 + (k % 256) / 16] += x as f64;
                }
                b
            };
            let (be, bl) = (blocks(&exact), blocks(&lod));
            let sum = |x: &[f64]| x.iter().sum::<f64>();
            let l1: f64 = be.iter().zip(&bl).map(|(a, b)| (a - b).abs()).sum();
            eprintln!("{kernel:?}: merged L1 {:.2e}", l1 / sum(&be));
            assert!(l1 <= 0.03 * sum(&be), "{kernel:?}: L1 {}", l1 / sum(&be));
            if periodic {
                // The box's mass, on axis, exactly (both).
                assert!((sum(&bl) / sum(&be) - 1.0).abs() <= 1e-5);
            }
        }
    }

    #[test]
    fn the_variance_factor_is_the_kernels() {
        // M4 with h = 1: ⟨r²⟩ = 4∫q⁴M4(q)dq = 0.9, so 0.3 per axis.
        let m4 = variance_factor(Kernel::CubicSpline);
        assert!((m4 - 0.3).abs() < 1e-4, "{m4}");
        // The Gaussian of deviation r/3 truncated at 3σ: below (1/3)², by
        // the ~8% of ⟨r²⟩ the 3% of its mass beyond 3σ carried.
        let g = variance_factor(Kernel::Gaussian3);
        assert!(g < 1.0 / 9.0 && g > 0.9 / 9.0, "{g}");
    }

    #[test]
    fn small_sets_have_no_preview() {
        assert!(volume(2000, Kernel::CubicSpline, false).preview().is_none());
    }
}
