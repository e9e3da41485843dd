//! A coarse grid of value ranges ("macrocells") that turns any volume with
//! bounded-support elements into ray intervals.
//!
//! Each cell stores a conservative range of the field inside it (empty when no
//! element reaches the cell). A 3D DDA walks the cells a ray crosses; runs of
//! adjacent visible cells merge into one [`Interval`] whose value range is the
//! union of theirs, and empty or invisible cells become gaps that integrators
//! skip.

use crate::math::{Aabb, Range1, Ray};
use crate::volume::{Interval, IntervalQuery};

#[derive(Clone, Debug)]
pub struct MacroGrid {
    pub bounds: Aabb,
    pub dims: [usize; 3],
    /// Value range per cell, x fastest.
    pub ranges: Vec<Range1>,
}

impl MacroGrid {
    /// A grid over `bounds` with cells of roughly `target_cell` width, capped at
    /// `max_dim` cells per axis; all cells start empty.
    pub fn with_cell_size(bounds: Aabb, target_cell: f32, max_dim: usize) -> Self {
        let e = bounds.extent();
        let dim = |len: f32| {
            if target_cell > 0.0 && len.is_finite() && len > 0.0 {
                ((len / target_cell).ceil() as usize).clamp(1, max_dim.max(1))
            } else {
                1
            }
        };
        let dims = [dim(e.x), dim(e.y), dim(e.z)];
        MacroGrid {
            bounds,
            dims,
            ranges: vec![Range1::EMPTY; dims[0] * dims[1] * dims[2]],
        }
    }

    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        (k * self.dims[1] + j) * self.dims[0] + i
    }

    /// Inclusive cell index ranges `(lo, hi)` per axis of the cells `b` touches;
    /// `None` when `b` misses the grid.
    pub fn cells_overlapping(&self, b: &Aabb) -> Option<([usize; 3], [usize; 3])> {
        if b.is_empty() {
            return None;
        }
        let mut lo = [0; 3];
        let mut hi = [0; 3];
        for a in 0..3 {
            let (min, max) = (self.bounds.min[a], self.bounds.max[a]);
            if b.max[a] < min || b.min[a] > max {
                return None;
            }
            let n = self.dims[a];
            let scale = n as f32 / (max - min).max(f32::MIN_POSITIVE);
            let cell = |v: f32| (((v - min) * scale).floor().max(0.0) as usize).min(n - 1);
            lo[a] = cell(b.min[a]);
            hi[a] = cell(b.max[a]);
        }
        Some((lo, hi))
    }

    /// Append the merged visible intervals of `ray` within `t` to `out`.
    pub fn intervals(
        &self,
        ray: &Ray,
        t: Range1,
        nominal_dt: f32,
        query: &IntervalQuery,
        out: &mut Vec<Interval>,
    ) {
        let tr = self.bounds.clip_ray(ray, t);
        if tr.is_empty() {
            return;
        }
        let mut idx = [0i64; 3];
        let mut step = [0i64; 3];
        let mut t_next = [f32::INFINITY; 3];
        let mut t_delta = [f32::INFINITY; 3];
        let entry = ray.at(tr.lo);
        for a in 0..3 {
            let n = self.dims[a] as i64;
            let min = self.bounds.min[a];
            let cs = (self.bounds.max[a] - min) / self.dims[a] as f32;
            let c = if cs > 0.0 {
                ((entry[a] - min) / cs).floor() as i64
            } else {
                0
            };
            idx[a] = c.clamp(0, n - 1);
            let d = ray.dir[a];
            if d > 0.0 {
                step[a] = 1;
                t_next[a] = (min + (idx[a] + 1) as f32 * cs - ray.origin[a]) / d;
                t_delta[a] = cs / d;
            } else if d < 0.0 {
                step[a] = -1;
                t_next[a] = (min + idx[a] as f32 * cs - ray.origin[a]) / d;
                t_delta[a] = -cs / d;
            }
        }
        let mut t_cur = tr.lo;
        // Whether the last pushed interval ends where the current cell starts,
        // so a visible cell extends it rather than opening a new one.
        let mut open = false;
        loop {
            let axis = if t_next[0] <= t_next[1] && t_next[0] <= t_next[2] {
                0
            } else if t_next[1] <= t_next[2] {
                1
            } else {
                2
            };
            let t_exit = t_next[axis].min(tr.hi);
            if t_exit > t_cur {
                let r = self.ranges[self.index(idx[0] as usize, idx[1] as usize, idx[2] as usize)];
                if !r.is_empty() && (query.is_visible)(r) {
                    match out.last_mut() {
                        Some(last) if open => {
                            last.t.hi = t_exit;
                            last.value_range = last.value_range.union(r);
                        }
                        _ => out.push(Interval::sampled(Range1::new(t_cur, t_exit), r, nominal_dt)),
                    }
                    open = true;
                } else {
                    open = false;
                }
                t_cur = t_exit;
            }
            if t_exit >= tr.hi {
                break;
            }
            idx[axis] += step[axis];
            if idx[axis] < 0 || idx[axis] >= self.dims[axis] as i64 {
                break;
            }
            t_next[axis] += t_delta[axis];
        }
    }
}
