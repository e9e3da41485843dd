//! Exact answers for nearest reconstruction: line integrals by a DDA
//! through the bricks, and the volume integral.

use voxless_core::{Range1, Ray};

use super::{AmrVolume, Reconstruction};

impl AmrVolume {
    /// Exact `∫ value dt` with nearest reconstruction: every cell's value times
    /// the length of the ray inside it (3D DDA through each brick the ray hits).
    pub(super) fn nearest_line_integral(&self, ray: &Ray, t: Range1) -> f64 {
        let field = &self.bx().values[self.settings.field];
        let mut sum = 0.0f64;
        self.bx().brick_bvh.ray_query(ray, t, |bi, hit| {
            let b = &self.bx().bricks[bi as usize];
            let w = b.width() as f64 * self.h as f64;
            let lower =
                [0, 1, 2].map(|a| self.origin[a] as f64 + b.lower[a] as f64 * self.h as f64);
            let o = [0, 1, 2].map(|a| ray.origin[a] as f64);
            let d = [0, 1, 2].map(|a| ray.dir[a] as f64);
            let (t0, t1) = (hit.lo as f64, hit.hi as f64);
            // Start cell at the midpoint-nudged entry, then step cell faces.
            let entry = t0 + (t1 - t0) * 1e-9;
            let mut i = [0i32; 3];
            let mut t_next = [f64::INFINITY; 3];
            let mut t_delta = [f64::INFINITY; 3];
            let mut step = [0i32; 3];
            for a in 0..3 {
                let x = (o[a] + d[a] * entry - lower[a]) / w;
                i[a] = (x.floor() as i32).clamp(0, b.size[a] - 1);
                if d[a] > 0.0 {
                    step[a] = 1;
                    t_next[a] = (lower[a] + (i[a] + 1) as f64 * w - o[a]) / d[a];
                    t_delta[a] = w / d[a];
                } else if d[a] < 0.0 {
                    step[a] = -1;
                    t_next[a] = (lower[a] + i[a] as f64 * w - o[a]) / d[a];
                    t_delta[a] = -w / d[a];
                }
            }
            let mut t_cur = t0;
            loop {
                let a = if t_next[0] <= t_next[1] && t_next[0] <= t_next[2] {
                    0
                } else if t_next[1] <= t_next[2] {
                    1
                } else {
                    2
                };
                let t_exit = t_next[a].min(t1);
                let cell =
                    b.offset as usize + ((i[2] * b.size[1] + i[1]) * b.size[0] + i[0]) as usize;
                sum += field[cell] as f64 * (t_exit - t_cur).max(0.0);
                t_cur = t_exit;
                if t_exit >= t1 {
                    break;
                }
                i[a] += step[a];
                if i[a] < 0 || i[a] >= b.size[a] {
                    break;
                }
                t_next[a] += t_delta[a];
            }
        });
        sum
    }
}

impl AmrVolume {
    /// `∫ value dV` of the opacity field when it is known exactly: with
    /// nearest reconstruction, Σ value × cell volume (what a projection over
    /// the full bounds must conserve). `None` for basis reconstruction.
    pub fn exact_integral(&self) -> Option<f64> {
        if self.settings.reconstruction != Reconstruction::Nearest {
            return None;
        }
        Some(self.integral * (self.h as f64).powi(3))
    }
}
