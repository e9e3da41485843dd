//! [`TetVolume`]: a tet mesh behind the generic `Volume` seam — point
//! samples (density and stream count) through a BVH over the tets, macrocell
//! intervals, and exact line integrals.

use rayon::prelude::*;
use voxless_bvh::Bvh;
use voxless_core::{Aabb, Interval, IntervalQuery, MacroGrid, Range1, Ray, Sample, Vec3, Volume};

use crate::TetError;
use crate::mesh::{LagrangianGrid, TetMesh, TetSettings};
use crate::raster::Planes;

pub struct TetVolume {
    pub mesh: TetMesh,
    bvh: Bvh,
    grid: MacroGrid,
    bounds: Aabb,
    value_range: Range1,
    nominal_dt: f32,
}

impl TetVolume {
    /// Tessellates `grid`, with `lod_levels` coarser levels of detail (0 for none).
    pub fn new(
        grid: &LagrangianGrid,
        settings: &TetSettings,
        lod_levels: usize,
    ) -> Result<TetVolume, TetError> {
        let mut mesh = TetMesh::new(grid, settings)?;
        if lod_levels > 0 {
            mesh = mesh.with_lod(grid, lod_levels, settings);
        }
        let boxes: Vec<Aabb> = mesh.tets.par_iter().map(|t| t.bounds()).collect();
        let bvh = Bvh::build(&boxes);
        // The periodic box: image tets fill it exactly, and outside it they
        // would double what the originals show.
        let bounds = Aabb::new(Vec3::ZERO, Vec3::splat(mesh.box_size));
        let spacing = mesh.box_size / mesh.n as f32;
        // Macrocells of about two Lagrangian spacings: [0, Σ ρ of tets touching].
        let mut mg = MacroGrid::with_cell_size(bounds, 2.0 * spacing, 128);
        let mut sums = vec![-1.0f32; mg.ranges.len()];
        for (t, b) in mesh.tets.iter().zip(&boxes) {
            if let Some((lo, hi)) = mg.cells_overlapping(b) {
                for k in lo[2]..=hi[2] {
                    for j in lo[1]..=hi[1] {
                        for i in lo[0]..=hi[0] {
                            let c = &mut sums[mg.index(i, j, k)];
                            *c = c.max(0.0) + t.density;
                        }
                    }
                }
            }
        }
        for (r, s) in mg.ranges.iter_mut().zip(sums) {
            *r = if s >= 0.0 {
                Range1::new(0.0, s * 1.0001)
            } else {
                Range1::EMPTY
            };
        }
        // Density range for the transfer function (log10 by default): from the
        // mean density (voids stay transparent) to the 99.9th-percentile tet density.
        let mean = mesh.total_mass() / (mesh.box_size as f64).powi(3);
        let mut d: Vec<f32> = mesh
            .tets
            .iter()
            .step_by((mesh.tets.len() / 100_000).max(1))
            .map(|t| t.density)
            .collect();
        let at = ((d.len() as f64 * 0.999) as usize).min(d.len().saturating_sub(1));
        let high = if d.is_empty() {
            mean as f32
        } else {
            *d.select_nth_unstable_by(at, f32::total_cmp).1
        };
        let value_range = Range1::new(mean as f32, high.max(mean as f32 * 10.0));
        Ok(TetVolume {
            mesh,
            bvh,
            grid: mg,
            bounds,
            value_range,
            nominal_dt: spacing / 8.0,
        })
    }

    /// Density ρ (sum over the covering tets) and stream count at `p`,
    /// wrapped periodically into the box.
    ///
    /// Tets share faces, edges and vertices (all six of a cell share its main
    /// diagonal, which passes through the cell centre), and a point exactly on
    /// one would count in every tet touching it. So the point is nudged by
    /// 1e-4 of the Lagrangian spacing (at least a few ulps) along a fixed
    /// direction that no tessellation face contains; the density is
    /// discontinuous only across faces, so this changes nothing elsewhere.
    pub fn density_and_streams(&self, p: Vec3) -> (f64, u32) {
        let l = self.mesh.box_size;
        let nudge = (1e-4 * l / self.mesh.n as f32).max(8.0 * l * f32::EPSILON);
        let p = p + Vec3::new(0.812_403_8, 0.445_259_4, 0.376_556_9) * nudge;
        let p = Vec3::new(p.x.rem_euclid(l), p.y.rem_euclid(l), p.z.rem_euclid(l));
        let (mut rho, mut streams) = (0.0f64, 0u32);
        self.bvh.point_query(p, |i| {
            let t = &self.mesh.tets[i as usize];
            if t.contains(p) {
                rho += t.density as f64;
                streams += 1;
            }
        });
        (rho, streams)
    }
}

impl Volume for TetVolume {
    fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Density range used by default with a log10 transfer function.
    fn value_range(&self) -> Range1 {
        self.value_range
    }

    fn sample(&self, p: Vec3) -> Option<Sample> {
        let (rho, streams) = self.density_and_streams(p);
        (streams > 0).then(|| Sample::scalar(rho as f32))
    }

    /// Piecewise constant: zero almost everywhere.
    fn gradient(&self, _: Vec3) -> Vec3 {
        Vec3::ZERO
    }

    fn intervals(&self, ray: &Ray, t: Range1, query: &IntervalQuery, out: &mut Vec<Interval>) {
        self.grid.intervals(ray, t, self.nominal_dt, query, out);
    }

    /// Exact: Σ ρ × chord over every tet the ray crosses within `t`.
    fn line_integral(&self, ray: &Ray, t: Range1) -> f64 {
        let mut sum = 0.0f64;
        self.bvh.ray_query(ray, t, |i, _| {
            let tet = &self.mesh.tets[i as usize];
            let (a, b) = Planes::new(tet).clip(ray);
            let (a, b) = (a.max(t.lo), b.min(t.hi));
            if b > a {
                sum += tet.density as f64 * (b - a) as f64;
            }
        });
        sum
    }
}
