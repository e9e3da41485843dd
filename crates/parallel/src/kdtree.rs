//! [`Decomposition`]: a k-d tree that cuts a root box into K boxes of about
//! equal work, one per rank, and orders them front to back for a camera.
//!
//! **Build.** From a sample of weighted points (every rank contributes the
//! same deterministic sample, so every rank builds the same tree): a node
//! holding `k` parts splits its longest axis where the points' weight
//! divides as `⌊k/2⌋ : ⌈k/2⌉`, recursively, until each node holds one part.
//! Any K works, not only powers of two.
//!
//! **Half-open boxes.** A point belongs to the box it lies in, with a point
//! on a split plane belonging to the upper side ([`Decomposition::owner`]),
//! so the boxes partition the root box. Whatever reaches into a box (a
//! kernel's support, a cell's basis, a tet's bounds) is found with closed
//! tests ([`Decomposition::overlapping`]), so an item touching a face is
//! kept by both sides.
//!
//! **Visibility.** The boxes of a k-d tree stack up front to back for any
//! viewpoint by visiting, at every split, first the side the eye is on
//! (perspective) or the side the view direction comes from (orthographic).
//! A ray never crosses a split plane twice, so every ray meets the boxes in
//! this order — also a ray that runs inside a split plane, which belongs to
//! one side only.

use voxless_core::{Aabb, Camera, Projection, Vec3};

#[derive(Clone, Debug, PartialEq)]
enum Node {
    Leaf(usize),
    Split {
        axis: usize,
        at: f32,
        left: usize,
        right: usize,
    },
}

/// K boxes tiling a root box, one per rank.
#[derive(Clone, Debug, PartialEq)]
pub struct Decomposition {
    root: Aabb,
    nodes: Vec<Node>,
    boxes: Vec<Aabb>,
}

impl Decomposition {
    /// One part: the whole root box.
    pub fn single(root: Aabb) -> Decomposition {
        Decomposition {
            root,
            nodes: vec![Node::Leaf(0)],
            boxes: vec![root],
        }
    }

    /// `parts` boxes (≥ 1) tiling `root`, split so that the weights of
    /// `points` divide about equally; points outside `root` count where
    /// they would be clamped to it. Deterministic in its inputs.
    pub fn build(root: Aabb, points: &[(Vec3, f32)], parts: usize) -> Decomposition {
        let parts = parts.max(1);
        let mut d = Decomposition {
            root,
            nodes: Vec::new(),
            boxes: vec![Aabb::EMPTY; parts],
        };
        let mut pts: Vec<(Vec3, f32)> = points
            .iter()
            .filter(|(p, w)| p.is_finite() && w.is_finite() && *w > 0.0)
            .map(|&(p, w)| (p.max(root.min).min(root.max), w))
            .collect();
        d.split(root, &mut pts, 0, parts);
        d
    }

    /// Builds the node for `parts` parts starting at part `first` over
    /// `bounds`; returns its index.
    fn split(
        &mut self,
        bounds: Aabb,
        pts: &mut [(Vec3, f32)],
        first: usize,
        parts: usize,
    ) -> usize {
        let index = self.nodes.len();
        if parts == 1 {
            self.nodes.push(Node::Leaf(first));
            self.boxes[first] = bounds;
            return index;
        }
        self.nodes.push(Node::Leaf(first));
        let e = bounds.extent();
        let axis = if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        };
        let left_parts = parts / 2;
        let share = left_parts as f64 / parts as f64;
        pts.sort_unstable_by(|a, b| a.0[axis].total_cmp(&b.0[axis]));
        let total: f64 = pts.iter().map(|p| p.1 as f64).sum();
        let mid = 0.5 * (bounds.min[axis] + bounds.max[axis]);
        let at = if total > 0.0 {
            // The first point where the running weight reaches the share;
            // the plane goes halfway to the next point, so points equal to
            // it do not straddle.
            let target = share * total;
            let mut acc = 0.0f64;
            let mut k = pts.len() - 1;
            for (i, p) in pts.iter().enumerate() {
                acc += p.1 as f64;
                if acc >= target {
                    k = i;
                    break;
                }
            }
            let a = pts[k].0[axis];
            let b = pts.get(k + 1).map_or(a, |q| q.0[axis]);
            0.5 * (a + b)
        } else {
            mid
        };
        let at = if at > bounds.min[axis] && at < bounds.max[axis] {
            at
        } else {
            mid
        };
        let cut = pts.partition_point(|p| p.0[axis] < at);
        let (lo_pts, hi_pts) = pts.split_at_mut(cut);
        let mut lo = bounds;
        let mut hi = bounds;
        set(&mut lo.max, axis, at);
        set(&mut hi.min, axis, at);
        let left = self.split(lo, lo_pts, first, left_parts);
        let right = self.split(hi, hi_pts, first + left_parts, parts - left_parts);
        self.nodes[index] = Node::Split {
            axis,
            at,
            left,
            right,
        };
        index
    }

    /// How many parts (ranks).
    pub fn parts(&self) -> usize {
        self.boxes.len()
    }

    /// The root box the parts tile.
    pub fn root(&self) -> Aabb {
        self.root
    }

    /// Part `i`'s box, half-open `[min, max)`.
    pub fn box_of(&self, i: usize) -> Aabb {
        self.boxes[i]
    }

    pub fn boxes(&self) -> &[Aabb] {
        &self.boxes
    }

    /// The part whose half-open box holds `p` (points outside the root box
    /// go to the nearest part along each split).
    pub fn owner(&self, p: Vec3) -> usize {
        let mut n = 0;
        loop {
            match self.nodes[n] {
                Node::Leaf(i) => return i,
                Node::Split {
                    axis,
                    at,
                    left,
                    right,
                } => n = if p[axis] < at { left } else { right },
            }
        }
    }

    /// The parts whose (closed) boxes `b` overlaps, in part order, into `out`.
    pub fn overlapping(&self, b: &Aabb, out: &mut Vec<usize>) {
        out.clear();
        if b.is_empty() {
            return;
        }
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            match self.nodes[n] {
                Node::Leaf(i) => out.push(i),
                Node::Split {
                    axis,
                    at,
                    left,
                    right,
                } => {
                    if b.min[axis] <= at {
                        stack.push(left);
                    }
                    if b.max[axis] >= at {
                        stack.push(right);
                    }
                }
            }
        }
        out.sort_unstable();
    }

    /// The parts in the order a ray from `camera` meets them, nearest first.
    pub fn front_to_back(&self, camera: &Camera) -> Vec<usize> {
        let mut out = Vec::with_capacity(self.parts());
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            match self.nodes[n] {
                Node::Leaf(i) => out.push(i),
                Node::Split {
                    axis,
                    at,
                    left,
                    right,
                } => {
                    let left_first = match camera.projection {
                        Projection::Perspective { .. } => camera.eye[axis] < at,
                        Projection::Orthographic { .. } => camera.forward[axis] >= 0.0,
                    };
                    // The stack pops the last push first.
                    if left_first {
                        stack.push(right);
                        stack.push(left);
                    } else {
                        stack.push(left);
                        stack.push(right);
                    }
                }
            }
        }
        out
    }
}

fn set(v: &mut Vec3, axis: usize, x: f32) {
    match axis {
        0 => v.x = x,
        1 => v.y = x,
        _ => v.z = x,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use voxless_core::Projection;

    fn grid_points(n: usize) -> Vec<(Vec3, f32)> {
        let mut v = Vec::new();
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    let p = Vec3::new(i as f32, j as f32, k as f32) * (1.0 / n as f32);
                    v.push((p * p.x, 1.0)); // denser towards x = 0
                }
            }
        }
        v
    }

    #[test]
    fn boxes_tile_the_root_and_split_the_weight_evenly() {
        let root = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let pts = grid_points(16);
        for parts in 1..=7 {
            let d = Decomposition::build(root, &pts, parts);
            assert_eq!(d.parts(), parts);
            let volume: f32 = d
                .boxes()
                .iter()
                .map(|b| b.extent().x * b.extent().y * b.extent().z)
                .sum();
            assert!((volume - 1.0).abs() < 1e-5, "{parts}: {volume}");
            let mut count = vec![0usize; parts];
            for (p, _) in &pts {
                let o = d.owner(*p);
                assert!(d.box_of(o).contains(*p));
                count[o] += 1;
            }
            let ideal = pts.len() as f64 / parts as f64;
            for c in count {
                assert!(
                    (c as f64 - ideal).abs() <= 0.2 * ideal + 256.0,
                    "{parts}: {c}"
                );
            }
        }
    }

    #[test]
    fn overlapping_is_closed_and_owner_is_half_open() {
        let root = Aabb::new(Vec3::ZERO, Vec3::splat(2.0));
        let d = Decomposition::build(root, &[(Vec3::splat(0.5), 1.0), (Vec3::splat(1.5), 1.0)], 2);
        let Node::Split { axis, at, .. } = d.nodes[0] else {
            panic!("two parts split once");
        };
        let mut p = Vec3::splat(0.3);
        set(&mut p, axis, at);
        // On the plane: owned by the upper side only, touched by both.
        assert_eq!(d.owner(p), 1);
        let mut out = Vec::new();
        d.overlapping(&Aabb::new(p, p), &mut out);
        assert_eq!(out, vec![0, 1]);
    }

    #[test]
    fn front_to_back_puts_the_eye_side_first() {
        let root = Aabb::new(Vec3::ZERO, Vec3::new(4.0, 1.0, 1.0));
        let pts: Vec<(Vec3, f32)> = (0..400)
            .map(|i| (Vec3::new(i as f32 / 100.0, 0.5, 0.5), 1.0))
            .collect();
        let d = Decomposition::build(root, &pts, 4);
        let persp = |eye: Vec3| {
            Camera::look_at(
                eye,
                Vec3::new(2.0, 0.5, 0.5),
                Vec3::new(0.0, 1.0, 0.0),
                Projection::Perspective { fov_y_deg: 30.0 },
            )
            .unwrap()
        };
        // From −x the boxes come in increasing x, from +x decreasing.
        let order = d.front_to_back(&persp(Vec3::new(-5.0, 0.5, 0.5)));
        let xs: Vec<f32> = order.iter().map(|&i| d.box_of(i).min.x).collect();
        assert!(xs.windows(2).all(|w| w[0] < w[1]), "{xs:?}");
        let order = d.front_to_back(&persp(Vec3::new(9.0, 0.5, 0.5)));
        let xs: Vec<f32> = order.iter().map(|&i| d.box_of(i).min.x).collect();
        assert!(xs.windows(2).all(|w| w[0] > w[1]), "{xs:?}");
        // From inside the second box: it comes first.
        let inside = Vec3::new(
            d.box_of(d.owner(Vec3::new(1.5, 0.5, 0.5))).center().x,
            0.5,
            3.0,
        );
        let order = d.front_to_back(&persp(inside));
        assert_eq!(order[0], d.owner(Vec3::new(inside.x, 0.5, 0.5)));
    }
}
