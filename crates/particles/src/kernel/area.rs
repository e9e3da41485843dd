//! Pixel areas of a kernel's column: the fraction of a particle's mass
//! whose column falls in a rectangle of the image plane, for projections
//! that average each pixel over its square (`PixelIntegral::Area`).
//!
//! The column of every kernel is radial and, measured in units of the
//! support, has one shape per kernel (the radius only scales it). A table
//! holds its cumulative distribution over the support's square,
//! `F(u, v)` = the fraction of the mass at `x < u·s, y < v·s` (`s` the
//! support, the particle at the origin), on a [`NODES`]² grid over
//! `[−1, 1]²`; between nodes it is bilinear, beyond the square clamped. A
//! pixel `[u0, u1] × [v0, v1]` then holds `F(u1, v1) − F(u0, v1) −
//! F(u1, v0) + F(u0, v0)` of the mass.
//!
//! **Mass is exact.** Neighbouring pixels share their corners' values, so
//! over every pixel the support touches the sum telescopes to
//! `F(1, 1) − F(−1, 1) − F(1, −1) + F(−1, −1) = 1 − 0 − 0 + 0`: the table is
//! normalised so that its last node is exactly 1 and its first row and
//! column exactly 0, whatever the interpolation error inside. A kernel far
//! smaller than a pixel lands whole in the pixels it overlaps.
//!
//! **Values.** The cells are integrated with 3×3 Gauss–Legendre points of
//! the column (the same column the pixel-centre path reads); a pixel's
//! value is then within the table's bilinear error: 2e-7 to 4e-5 of the
//! peak pixel for supports of 0.4 to 15 pixels against a fine quadrature
//! (the test holds 1e-4). Supports of [`table_pixels`] or more are
//! sampled at pixel centres instead: there the table's cells would start
//! to show, the centres hold the kernel's mass to ~1e-7, and a pixel's
//! centre value is within ~1e-3 of its mean.

use std::sync::{Arc, Mutex};

use super::Kernel;

/// Nodes per side of the table (513² f64: 2.1 MB per kernel).
pub const NODES: usize = 513;

/// Supports narrower than this many pixels (radius, along the image's
/// narrower pixel side) use the table; wider ones are sampled at pixel
/// centres. The truncated Gaussians' columns fall to 0 with infinite slope
/// at the support, which pixel centres integrate more slowly (1.4e-6 of
/// the mass at 16 pixels): they keep the table to 64.
pub fn table_pixels(kernel: Kernel) -> f64 {
    if kernel.is_sph() { 16.0 } else { 64.0 }
}

/// 3-point Gauss–Legendre on [−½, ½]: offsets and weights (summing to 1),
/// for the table's cells.
pub const GAUSS3: [(f64, f64); 3] = [
    (-0.387_298_334_620_741_7, 5.0 / 18.0),
    (0.0, 8.0 / 18.0),
    (0.387_298_334_620_741_7, 5.0 / 18.0),
];

/// A kernel's cumulative column table (see the module docs).
pub struct AreaTable {
    /// `F` at node `(i, j)` (u = −1 + i·step, v = −1 + j·step) at `i·NODES + j`.
    f: Vec<f64>,
}

impl AreaTable {
    /// The table of `kernel`, built once per kernel and process.
    pub fn of(kernel: Kernel) -> Arc<AreaTable> {
        static TABLES: Mutex<Vec<(Kernel, Arc<AreaTable>)>> = Mutex::new(Vec::new());
        let mut tables = TABLES.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, t)) = tables.iter().find(|(k, _)| *k == kernel) {
            return t.clone();
        }
        let t = Arc::new(AreaTable::build(kernel));
        tables.push((kernel, t.clone()));
        t
    }

    fn build(kernel: Kernel) -> AreaTable {
        let cells = NODES - 1;
        let step = 2.0 / cells as f64;
        // A radius whose support is 1.
        let column = kernel.column(1.0 / kernel.support_factor() as f64);
        // One quadrant's cells (the column is symmetric in u and v), by
        // 3×3 Gauss–Legendre points; cell (a, b) spans u ∈ [a, a+1]·step.
        let half = cells / 2;
        let quadrant: Vec<f64> = (0..half * half)
            .map(|k| {
                let (a, b) = (k / half, k % half);
                let mut sum = 0.0;
                for (du, wu) in GAUSS3 {
                    let u = (a as f64 + 0.5 + du) * step;
                    for (dv, wv) in GAUSS3 {
                        let v = (b as f64 + 0.5 + dv) * step;
                        sum += wu * wv * column.at(u * u + v * v);
                    }
                }
                sum
            })
            .collect();
        // Cell (i, j) of the whole square mirrors quadrant cell (|i − half|…).
        let cell = |i: usize, j: usize| {
            let a = if i >= half { i - half } else { half - 1 - i };
            let b = if j >= half { j - half } else { half - 1 - j };
            quadrant[a * half + b]
        };
        let mut f = vec![0.0f64; NODES * NODES];
        for i in 1..NODES {
            let mut row = 0.0;
            for j in 1..NODES {
                row += cell(i - 1, j - 1);
                f[i * NODES + j] = f[(i - 1) * NODES + j] + row;
            }
        }
        let total = f[NODES * NODES - 1];
        f.iter_mut().for_each(|v| *v /= total);
        AreaTable { f }
    }

    /// `F(u, v)`: the fraction of the mass at `x < u·s, y < v·s`.
    #[inline]
    pub fn at(&self, u: f64, v: f64) -> f64 {
        let last = (NODES - 1) as f64;
        let x = ((u + 1.0) * 0.5 * last).clamp(0.0, last);
        let y = ((v + 1.0) * 0.5 * last).clamp(0.0, last);
        let (i, j) = ((x as usize).min(NODES - 2), (y as usize).min(NODES - 2));
        let (fx, fy) = (x - i as f64, y - j as f64);
        let f = &self.f;
        let at = i * NODES + j;
        let lo = f[at] + (f[at + 1] - f[at]) * fy;
        let hi = f[at + NODES] + (f[at + NODES + 1] - f[at + NODES]) * fy;
        lo + (hi - lo) * fx
    }
}
