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

use std::sync::OnceLock;

use rayon::prelude::*;
use voxless_core::{Camera, Projection, Vec3};

use super::{ParticleData, ParticleVolume};
use crate::error::ParticleError;
use crate::kernel::Kernel;

/// Sets of at least this many particles get a preview.
pub const PREVIEW_MIN: usize = 1 << 20;

/// A preview holds about this many merged particles (at most; the level is
/// the smallest whose runs bring the count below it).
pub const PREVIEW_TARGET: usize = 1 << 18;

/// One merged kernel: a run's mass (`Σ wᵢ·∫φ`, f64 so that levels compose
/// without drift), centroid, radius and mass-weighted attribute.
#[derive(Clone, Copy, Debug)]
struct Node {
    mass: f64,
    center: [f64; 3],
    radius: f32,
    attribute: f32,
}

/// The merged levels: `levels[k - 1]` holds level `k`, node `j` the merge
/// of nodes `8j..8j + 8` of level `k − 1` (level 0: the particles, ghosts
/// and hidden ones left out, in volume order) — so node `j` of level `k` is
/// the run of particles `8ᵏj..8ᵏ(j + 1)`. Merging children keeps the same
/// moments as merging their particles directly (masses add, centroids and
/// second moments about the new centroid compose exactly).
pub(crate) struct LodTree {
    /// The particles level 1 merges (volume indices).
    own: Vec<u32>,
    levels: Vec<Vec<Node>>,
}

/// Levels stop when one has at most this many nodes.
const TOP_NODES: usize = 512;

impl ParticleVolume {
    /// The merged levels, built on first use.
    pub(crate) fn lod_tree(&self) -> &LodTree {
        self.lod.get_or_init(|| {
            let kernel = self.settings.kernel;
            let s = variance_factor(kernel);
            let own: Vec<u32> = (0..self.len())
                .filter(|&i| !self.is_ghost(i) && self.radius[i] > 0.0 && self.weight[i] > 0.0)
                .map(|i| i as u32)
                .collect();
            let particle = |i: u32| {
                let i = i as usize;
                let c = self.packed[i].center;
                Node {
                    mass: self.weight[i] as f64 * kernel.integral(self.radius[i] as f64),
                    center: [c.x as f64, c.y as f64, c.z as f64],
                    radius: self.radius[i],
                    attribute: self.attribute.as_ref().map_or(0.0, |a| a[i]),
                }
            };
            let mut levels: Vec<Vec<Node>> = Vec::new();
            let mut below: Vec<Node> = own.par_iter().map(|&i| particle(i)).collect();
            while below.len() > TOP_NODES || levels.is_empty() {
                let next: Vec<Node> = below.par_chunks(8).map(|c| merge(c, s)).collect();
                levels.push(next);
                below = levels.last().expect("a level").clone();
                if below.len() <= 1 {
                    break;
                }
            }
            LodTree { own, levels }
        })
    }

    /// The volume with every run of `8^level` consecutive particles (volume
    /// order, ghosts left out) merged into one (see the module docs); the
    /// same settings, without the radius and weight maps (the merged radii
    /// and weights are the effective ones). Level 0 and levels beyond the
    /// tree's are clamped to its first and last.
    pub fn merged(&self, level: u32) -> Result<ParticleVolume, ParticleError> {
        let tree = self.lod_tree();
        let k = (level.max(1) as usize).min(tree.levels.len());
        let nodes = &tree.levels[k - 1];
        let mut cut = Cut::new(self, nodes.len());
        for n in nodes {
            cut.node(self, n);
        }
        cut.build(self)
    }

    /// The view-dependent level of detail of `camera` at `height` pixels:
    /// from the coarsest level down, a merged kernel whose support spans
    /// fewer than `pixels` pixels where it lies stands for its particles;
    /// the rest are the particles themselves. `None` when every particle
    /// stays (nothing to merge: render the volume itself).
    pub fn lod_cut(
        &self,
        camera: &Camera,
        height: u32,
        pixels: f32,
    ) -> Result<Option<ParticleVolume>, ParticleError> {
        let tree = self.lod_tree();
        let factor = self.settings.kernel.support_factor() as f64;
        let eye = [
            camera.eye.x as f64,
            camera.eye.y as f64,
            camera.eye.z as f64,
        ];
        let fwd = [
            camera.forward.x as f64,
            camera.forward.y as f64,
            camera.forward.z as f64,
        ];
        let budget = pixels.max(0.0) as f64;
        // World size of a pixel at depth d along the view.
        let pixel = |d: f64| match camera.projection {
            Projection::Orthographic { half_height, .. } => {
                2.0 * half_height as f64 / height as f64
            }
            Projection::Perspective { fov_y_deg } => {
                2.0 * d * (0.5 * fov_y_deg as f64).to_radians().tan() / height as f64
            }
        };
        let small = |n: &Node| {
            let support = factor * n.radius as f64;
            let d: f64 = (0..3).map(|a| (n.center[a] - eye[a]) * fwd[a]).sum();
            // A node reaching the eye's plane is never merged.
            d > support && 2.0 * support < budget * pixel(d)
        };
        let top = tree.levels.len();
        let mut stack: Vec<(usize, usize)> = (0..tree.levels[top - 1].len())
            .rev()
            .map(|j| (top, j))
            .collect();
        let mut cut = Cut::new(self, 0);
        let mut merged = 0usize;
        while let Some((k, j)) = stack.pop() {
            if k == 0 {
                cut.particle(self, tree.own[j] as usize);
                continue;
            }
            let n = &tree.levels[k - 1][j];
            if small(n) {
                cut.node(self, n);
                merged += 1;
                continue;
            }
            let len = if k == 1 {
                tree.own.len()
            } else {
                tree.levels[k - 2].len()
            };
            // Children in reverse so that the cut keeps the volume's order.
            for c in (8 * j..(8 * j + 8).min(len)).rev() {
                stack.push((k - 1, c));
            }
        }
        if merged == 0 {
            return Ok(None);
        }
        cut.build(self).map(Some)
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

/// The merge of `nodes` (module docs), `s` the kernel's variance factor.
fn merge(nodes: &[Node], s: f64) -> Node {
    let mass: f64 = nodes.iter().map(|n| n.mass).sum();
    let mut c = [0.0f64; 3];
    let mut attribute = 0.0f64;
    for n in nodes {
        for (a, ca) in c.iter_mut().enumerate() {
            *ca += n.mass * n.center[a];
        }
        attribute += n.mass * n.attribute as f64;
    }
    let c = c.map(|v| v / mass);
    let second: f64 = nodes
        .iter()
        .map(|n| {
            let d2: f64 = (0..3).map(|a| (n.center[a] - c[a]).powi(2)).sum();
            let r = n.radius as f64;
            n.mass * (s * r * r + d2 / 3.0)
        })
        .sum();
    Node {
        mass,
        center: c,
        radius: (second / mass / s).sqrt() as f32,
        attribute: (attribute / mass) as f32,
    }
}

/// A level-of-detail set being gathered: merged nodes and particles.
struct Cut {
    data: ParticleData,
}

impl Cut {
    fn new(v: &ParticleVolume, capacity: usize) -> Cut {
        Cut {
            data: ParticleData {
                positions: Vec::with_capacity(capacity),
                radii: Some(Vec::with_capacity(capacity)),
                attribute: v.attribute.as_ref().map(|_| Vec::with_capacity(capacity)),
                weights: Some(Vec::with_capacity(capacity)),
            },
        }
    }

    fn push(&mut self, center: Vec3, radius: f32, weight: f32, attribute: f32) {
        let d = &mut self.data;
        d.positions.push(center);
        d.radii.as_mut().expect("radii").push(radius);
        d.weights.as_mut().expect("weights").push(weight);
        if let Some(a) = d.attribute.as_mut() {
            a.push(attribute);
        }
    }

    fn node(&mut self, v: &ParticleVolume, n: &Node) {
        // The weight that gives the merged kernel the run's mass.
        let weight = n.mass / v.settings.kernel.integral(n.radius as f64);
        let c = Vec3::new(n.center[0] as f32, n.center[1] as f32, n.center[2] as f32);
        self.push(c, n.radius, weight as f32, n.attribute);
    }

    fn particle(&mut self, v: &ParticleVolume, i: usize) {
        let a = v.attribute.as_ref().map_or(0.0, |a| a[i]);
        self.push(v.packed[i].center, v.radius[i], v.weight[i], a);
    }

    /// The cut as a volume with `v`'s settings (no maps: the radii and
    /// weights are the effective ones).
    fn build(self, v: &ParticleVolume) -> Result<ParticleVolume, ParticleError> {
        let mut settings = v.settings.clone();
        settings.radius_map = None;
        settings.weight_map = None;
        settings.lod_pixels = None;
        if settings.attribute_range.is_none() {
            settings.attribute_range = v.attribute_range;
        }
        ParticleVolume::new(self.data, settings)
    }
}

/// The kernel's variance per axis at radius 1: `⟨x²⟩ = ½ ∫F(b) b³ db /
/// ∫F(b) b db` over its column `F` (the projection along z keeps the x and
/// y moments), by Simpson's rule; computed once per kernel family.
fn variance_factor(kernel: Kernel) -> f64 {
    static CACHE: OnceLock<std::sync::Mutex<Vec<(Kernel, f64)>>> = OnceLock::new();
    let cache = CACHE.get_or_init(Default::default);
    if let Some(&(_, v)) = cache
        .lock()
        .expect("cache")
        .iter()
        .find(|(k, _)| *k == kernel)
    {
        return v;
    }
    let column = kernel.column(1.0);
    let support = kernel.support_factor() as f64;
    let f3 = |b: f64| column.at(b * b) * b * b * b;
    let f1 = |b: f64| column.at(b * b) * b;
    let v = 0.5 * voxless_core::simpson(f3, 0.0, support, 2000)
        / voxless_core::simpson(f1, 0.0, support, 2000);
    cache.lock().expect("cache").push((kernel, v));
    v
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
    fn a_view_dependent_cut_keeps_the_mass_and_the_image() {
        let v = volume(40_000, Kernel::CubicSpline, true);
        let cam =
            Camera::axis_projection(&Aabb::new(Vec3::splat(0.0), Vec3::splat(1.0)), 2).unwrap();
        // Nothing spans under a thousandth of a pixel: no cut.
        assert!(v.lod_cut(&cam, 16, 1e-3).unwrap().is_none());
        // The cut is chosen for a 16² image; the images are compared at
        // 128² (where every kernel spans pixels, so sampling at pixel
        // centres is accurate), averaged over the 16² image's pixels.
        let c = Control::new();
        let blocks = |img: &[f32]| {
            let mut b = vec![0.0f64; 256];
            for (k, &x) in img.iter().enumerate() {
                b[(k / 128 / 8) * 16 + (k % 128) / 8] += x as f64 / 64.0;
            }
            b
        };
        let exact = blocks(&v.project_image(&cam, 128, 128, &c).unwrap().unwrap());
        let peak = exact.iter().fold(0.0f64, |m, &x| m.max(x));
        let sum = |x: &[f64]| x.iter().sum::<f64>();
        // (pixel budget, the worst pixel's error over the peak allowed:
        // measured 4.2e-3, 5.4e-2 and 5.2e-2, with a margin)
        for (budget, bound) in [(1.0f32, 0.01), (2.0, 0.08), (4.0, 0.08)] {
            let cut = v.lod_cut(&cam, 16, budget).unwrap().expect("merged nodes");
            assert!(cut.particle_count() < v.particle_count());
            let (a, b) = (v.total_mass(), cut.total_mass());
            assert!((a / b - 1.0).abs() <= 1e-6, "{budget}: {a} vs {b}");
            let lod = blocks(&cut.project_image(&cam, 128, 128, &c).unwrap().unwrap());
            let worst = exact
                .iter()
                .zip(&lod)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
            eprintln!(
                "lod {budget} px: {} of {} kernels, worst pixel {:.2e} of the peak, Σ {:.1e}",
                cut.particle_count(),
                v.particle_count(),
                worst / peak,
                sum(&lod) / sum(&exact) - 1.0
            );
            // Merged kernels span under `budget` pixels: each pixel's mean
            // moves by a fraction of the peak that grows with the budget.
            assert!(worst <= bound * peak, "{budget}: {worst} of {peak}");
            assert!((sum(&lod) / sum(&exact) - 1.0).abs() <= 1e-5);
        }
    }

    #[test]
    fn small_sets_have_no_preview() {
        assert!(volume(2000, Kernel::CubicSpline, false).preview().is_none());
    }
}
