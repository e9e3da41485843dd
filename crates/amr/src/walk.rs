//! Front-to-back walks of the region tree: the k-d tree the regions were
//! cut by ([`crate::regions::KdNode`]), in world coordinates.
//!
//! **Why this tree.** The two children of a node lie on either side of its
//! plane and do not overlap, so visiting the child on the ray's side of the
//! plane first (the near child) meets the regions in the order the ray
//! does: intervals come out sorted, one region at a time, and a walk can
//! stop at any region and resume behind it (ExaBricks §4 steps a ray from
//! region to region the same way, with one hardware traversal per step).
//! A BVH over the regions (what [`crate::AmrVolume`] keeps for point
//! location) has overlapping siblings, so it must collect every region a
//! ray hits and sort them, even behind the point where the ray is opaque.
//!
//! **Exactness.** A region's `t` range comes out as
//! `max(t.lo, entry planes)..min(t.hi, exit planes)`, each plane's `t`
//! computed as `(x − o)·(1/d)` like [`voxless_core::Aabb::clip_ray`] does
//! from the same `f32` plane positions as the region's box; the planes
//! passed on the way down are the region's own faces or lie outside them
//! along the ray, so the range is bit for bit the region box clipped to the
//! ray. A ray in the plane of a cut belongs to the upper side (half-open
//! boxes, as `clip_ray` treats them).
//!
//! **Visibility.** A [`NodeMask`] marks the subtrees holding at least one
//! region a transfer function can see; the walk skips the others whole
//! (TF space skipping, ExaBricks §4.1, without a tree per transfer
//! function).
//!
//! **Packets.** [`RegionTree::walk_packet`] (in `packet`) takes up to
//! eight rays of one octant through the tree together, each with the
//! steps and ranges of its own walk; a renderer's tile view uses it.

use voxless_core::{Aabb, Range1, Ray};

use crate::regions::KdNode;

mod packet;
pub(crate) use packet::{PACKET_RAYS, same_octant};

/// A node in world coordinates, 12 bytes.
#[derive(Clone, Copy, Debug)]
struct Node {
    /// The cut's plane (inner nodes).
    at: f32,
    /// `0..=2`: an inner node cut across that axis; [`LEAF`]; [`HOLE`].
    kind: u32,
    /// Inner: offset of the right child from this node; leaf: the region.
    index: u32,
}

const LEAF: u32 = 3;
const HOLE: u32 = 4;

/// An inner node's axis and children as a walk meets them: below and
/// above the plane, and the same two in the walk's order.
struct Cut {
    axis: usize,
    left: usize,
    right: usize,
    near: usize,
    far: usize,
}

impl Node {
    /// This node (number `i`, an inner node) for a walk whose near child
    /// lies below the plane on the axes where `below_near` says so.
    #[inline(always)]
    fn cut(&self, i: usize, below_near: [bool; 3]) -> Cut {
        let axis = self.kind as usize;
        let (left, right) = (i + 1, i + self.index as usize);
        let (near, far) = if below_near[axis] {
            (left, right)
        } else {
            (right, left)
        };
        Cut {
            axis,
            left,
            right,
            near,
            far,
        }
    }
}

/// The region k-d tree, ready to walk.
#[derive(Clone, Debug, Default)]
pub(crate) struct RegionTree {
    nodes: Vec<Node>,
    /// The box the tree cuts (the union of the regions).
    root: Aabb,
    /// Inner nodes on the longest path from the root: a walk never holds
    /// more far children than that.
    depth: usize,
}

/// Per node of a [`RegionTree`], whether its subtree holds a region that
/// can be seen.
#[derive(Clone, Debug)]
pub(crate) struct NodeMask(Vec<u64>);

impl NodeMask {
    #[inline]
    fn get(&self, i: usize) -> bool {
        self.0[i / 64] >> (i % 64) & 1 != 0
    }
    fn set(&mut self, i: usize) {
        self.0[i / 64] |= 1 << (i % 64);
    }
}

thread_local! {
    /// A walk's pending far children (node, and the part of the ray in
    /// it), kept between walks so that none allocates or clears a stack.
    static STACK: std::cell::Cell<Vec<(u32, f32, f32)>> = const { std::cell::Cell::new(Vec::new()) };
}

impl RegionTree {
    /// The tree of `tree` (as [`crate::regions::build`] made it) with cut
    /// positions mapped to world coordinates by `world(axis, doubled
    /// units)` — the mapping the region boxes `region_bounds` were made
    /// with, so planes and boxes agree to the bit.
    pub fn new(tree: &[KdNode], region_bounds: &[Aabb], world: impl Fn(usize, i64) -> f32) -> Self {
        let nodes: Vec<Node> = tree
            .iter()
            .map(|n| match *n {
                KdNode::Inner { axis, at, right } => Node {
                    at: world(axis as usize, at),
                    kind: axis as u32,
                    index: right,
                },
                KdNode::Leaf(r) => Node {
                    at: 0.0,
                    kind: LEAF,
                    index: r,
                },
                KdNode::Hole => Node {
                    at: 0.0,
                    kind: HOLE,
                    index: 0,
                },
            })
            .collect();
        let root = region_bounds.iter().fold(Aabb::EMPTY, |b, &r| b.union(r));
        let depth = inner_depth(&nodes);
        RegionTree { nodes, root, depth }
    }

    /// The mask of the subtrees holding a region `visible` accepts.
    pub fn mask(&self, visible: impl Fn(u32) -> bool) -> NodeMask {
        let mut mask = NodeMask(vec![0; self.nodes.len().div_ceil(64)]);
        // Children follow their parent: a reverse sweep sees them first.
        for i in (0..self.nodes.len()).rev() {
            let n = self.nodes[i];
            let seen = match n.kind {
                LEAF => visible(n.index),
                HOLE => false,
                _ => mask.get(i + 1) || mask.get(i + n.index as usize),
            };
            if seen {
                mask.set(i);
            }
        }
        mask
    }

    /// Calls `leaf(region, t)` for every region (of those `mask` keeps)
    /// that `ray` crosses within `t`, front to back, with a non-empty part
    /// of the ray; `leaf` returns whether to go on. Returns where a stopped
    /// walk can resume (the end of the last region given), `None` when
    /// every region was given.
    #[inline]
    pub fn walk(
        &self,
        ray: &Ray,
        t: Range1,
        mask: Option<&NodeMask>,
        mut leaf: impl FnMut(u32, Range1) -> bool,
    ) -> Option<f32> {
        if self.nodes.is_empty() {
            return None;
        }
        let t = self.root.clip_ray(ray, t);
        if !(t.lo < t.hi) {
            return None;
        }
        // Taken out of the thread-local (not borrowed) for the walk.
        let mut stack = STACK.take();
        let rest = self.walk_with(ray, t, mask, &mut leaf, &mut stack);
        STACK.set(stack);
        rest
    }

    /// Calls `leaf(region)` for every region whose subtree box `keep`
    /// accepts, in the order the walk of any ray along axis `m` (towards
    /// `+m` when `positive`) meets them: the near child of every cut
    /// across `m` first. A ray parallel to `m` lies on one side of every
    /// other cut, so the regions it crosses come in its walk's order.
    pub fn visit_along(
        &self,
        m: usize,
        positive: bool,
        keep: impl Fn(&Aabb) -> bool,
        mut leaf: impl FnMut(u32),
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = vec![(0usize, self.root)];
        while let Some((i, b)) = stack.pop() {
            if !keep(&b) {
                continue;
            }
            let n = self.nodes[i];
            match n.kind {
                LEAF => leaf(n.index),
                HOLE => {}
                a => {
                    let a = a as usize;
                    let (mut lb, mut rb) = (b, b);
                    lb.max[a] = n.at;
                    rb.min[a] = n.at;
                    let (left, right) = ((i + 1, lb), (i + n.index as usize, rb));
                    // Pushed far first, so the near child pops first.
                    let (near, far) = if a != m || positive {
                        (left, right)
                    } else {
                        (right, left)
                    };
                    stack.push(far);
                    stack.push(near);
                }
            }
        }
    }

    /// The walk: the near child first, the far one onto the stack when the
    /// ray reaches both. The stack is a slice of `depth + 1` entries (more
    /// than the far children a walk can hold), written at every inner node
    /// and kept only where the ray reaches both sides: no growth check and
    /// no branch for the push. (Choosing the child without branches as
    /// well was slower: the predictor guesses the walk's turns well, and
    /// selects put every node load behind the previous node's test.)
    #[inline]
    fn walk_with(
        &self,
        ray: &Ray,
        t: Range1,
        mask: Option<&NodeMask>,
        leaf: &mut impl FnMut(u32, Range1) -> bool,
        stack: &mut Vec<(u32, f32, f32)>,
    ) -> Option<f32> {
        let inv = ray.inv_dir();
        let (org, inv) = (
            [ray.origin.x, ray.origin.y, ray.origin.z],
            [inv.x, inv.y, inv.z],
        );
        // The child below a plane is the near one when the ray goes up the
        // axis. Judged by the sign of `1/d`: a ray with `d = ±0` then meets
        // the plane at `±∞` and goes to the side its origin is on (in the
        // plane, at NaN: handled below).
        let below_near = inv.map(|v| v.is_sign_positive());
        // Entries are written before they are read: only the length counts.
        if stack.len() <= self.depth {
            stack.resize(self.depth + 1, (0, 0.0, 0.0));
        }
        let mut sp = 0;
        let (mut i, mut lo, mut hi) = (0usize, t.lo, t.hi);
        loop {
            let n = self.nodes[i];
            let keep = mask.is_none_or(|m| m.get(i));
            if keep && n.kind < LEAF {
                let Cut {
                    axis: a,
                    left,
                    right,
                    near,
                    far,
                } = n.cut(i, below_near);
                let ts = (n.at - org[a]) * inv[a];
                if ts.is_nan() {
                    // In the plane: the upper side.
                    i = if org[a] < n.at { left } else { right };
                    continue;
                }
                // Only the far side when the plane lies before `lo`, only
                // the near one when past `hi`; both: the far part waits.
                let to_far = ts <= lo;
                let both = !(ts >= hi) & !to_far;
                stack[sp] = (far as u32, ts, hi);
                sp += both as usize;
                hi = if both { ts } else { hi };
                i = if to_far { far } else { near };
                continue;
            }
            if keep && n.kind == LEAF && lo < hi && !leaf(n.index, Range1::new(lo, hi)) {
                return (sp > 0).then_some(hi);
            }
            if sp == 0 {
                return None;
            }
            sp -= 1;
            let (next, a, b) = stack[sp];
            (i, lo, hi) = (next as usize, a, b);
        }
    }
}

/// Inner nodes on the longest path from the root of `nodes` (a pre-order
/// k-d tree: the left child follows its parent).
fn inner_depth(nodes: &[Node]) -> usize {
    let mut deepest = 0;
    let mut todo = vec![(0usize, 0usize)];
    while let Some((i, d)) = todo.pop() {
        let Some(n) = nodes.get(i) else { continue };
        if n.kind < LEAF {
            todo.push((i + 1, d + 1));
            todo.push((i + n.index as usize, d + 1));
        } else {
            deepest = deepest.max(d);
        }
    }
    deepest
}
