//! The baseline the regions replace: cell location per sample.

use voxless_bvh::Bvh;
use voxless_core::{Aabb, Vec3};

use super::AmrCells;

/// The reconstruction that the regions replace: cell location through a BVH
/// over every cell's support, then the same basis sum (Wald et al.'s method).
/// The baseline for benchmarks and a cross-check in tests.
pub struct CellLocator {
    cells: Vec<[i32; 4]>,
    values: Vec<f32>,
    bvh: Bvh,
    origin: Vec3,
    h: f32,
}

impl CellLocator {
    pub fn new(cells: &AmrCells, field: usize) -> CellLocator {
        let (o, h) = (cells.origin, cells.cell_size);
        let boxes: Vec<Aabb> = cells
            .cells
            .iter()
            .map(|c| {
                let w = (1i64 << c[3]) as f32;
                let lo = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) - Vec3::splat(0.5 * w);
                Aabb::new(o + lo * h, o + (lo + Vec3::splat(2.0 * w)) * h)
            })
            .collect();
        CellLocator {
            cells: cells.cells.clone(),
            values: cells.fields[field].1.clone(),
            bvh: Bvh::build(&boxes),
            origin: o,
            h,
        }
    }

    /// Basis-reconstructed value at `p` (world), `None` where no tent reaches.
    pub fn sample(&self, p: Vec3) -> Option<f32> {
        let pu = (p - self.origin) * (1.0 / self.h);
        let (mut sw, mut sv) = (0.0f64, 0.0f64);
        self.bvh.point_query(p, |i| {
            let c = self.cells[i as usize];
            let w = (1i64 << c[3]) as f32;
            let mut h = 1.0f32;
            for a in 0..3 {
                let centre = c[a] as f32 + 0.5 * w;
                h *= (1.0 - (centre - pu[a]).abs() / w).max(0.0);
            }
            sw += h as f64;
            sv += h as f64 * self.values[i as usize] as f64;
        });
        (sw > 0.0).then(|| (sv / sw) as f32)
    }
}
