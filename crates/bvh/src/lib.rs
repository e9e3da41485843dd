//! A bounding volume hierarchy that knows only boxes.
//!
//! The builder takes one [`Aabb`] per primitive and returns a binary tree whose
//! leaves are single primitives; callers keep their payload (particle clusters,
//! bricks, tets) and receive primitive indices from the traversals.
//!
//! **Build** is a linear BVH (Karras 2012 style): primitives are sorted by the
//! Morton key of their box centre, and each node splits its key range where the
//! highest differing key bit flips (the middle when all keys are equal). The
//! sort and the two halves of every large node run in parallel with rayon.
//!
//! **Layout** is depth first: a subtree over `k` primitives is exactly `2k − 1`
//! consecutive nodes, the left child directly follows its parent and the right
//! child follows the left subtree. This lets the parallel build split the node
//! array with `split_at_mut` (no locks, no unsafe), and lets [`Bvh::refit`]
//! update bounds in one reverse sweep, since children always sit after parents.
//!
//! **Invariants**, checked by [`Bvh::validate`]: every primitive is in exactly
//! one leaf, every leaf box equals its primitive's box, and every inner box
//! encloses both children.

pub mod order;

use rayon::prelude::*;
use voxless_core::{Aabb, Range1, Ray, Vec3};

/// One node: its box, and either a primitive index (leaf) or the index of its
/// offset from this node to its right child (inner; the left child is the
/// next node). Offsets, not absolute indices, so subtrees build independently. 32 bytes.
#[derive(Clone, Copy, Debug)]
pub struct Node {
    pub min: [f32; 3],
    pub max: [f32; 3],
    index: u32,
    is_leaf: u32,
}

impl Node {
    const EMPTY: Node = Node {
        min: [f32::INFINITY; 3],
        max: [f32::NEG_INFINITY; 3],
        index: 0,
        is_leaf: 0,
    };
    pub fn bounds(&self) -> Aabb {
        Aabb::new(Vec3::from_array(self.min), Vec3::from_array(self.max))
    }
    fn set_bounds(&mut self, b: Aabb) {
        self.min = b.min.to_array();
        self.max = b.max.to_array();
    }
    pub fn is_leaf(&self) -> bool {
        self.is_leaf != 0
    }
    /// Primitive index of a leaf.
    pub fn primitive(&self) -> u32 {
        self.index
    }
    #[inline]
    fn contains(&self, p: Vec3) -> bool {
        p.x >= self.min[0]
            && p.x <= self.max[0]
            && p.y >= self.min[1]
            && p.y <= self.max[1]
            && p.z >= self.min[2]
            && p.z <= self.max[2]
    }
}

/// What [`Bvh::validate`] found wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct InvalidBvh(pub String);

impl std::fmt::Display for InvalidBvh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "invalid BVH: {}", self.0)
    }
}
impl std::error::Error for InvalidBvh {}

/// Subtrees with fewer primitives than this are built on one thread.
const PARALLEL_GRAIN: usize = 4096;
/// Traversal stack depth: Morton splits give at most 63 levels plus log2(n)
/// for runs of equal keys, well below this.
const STACK: usize = 128;

#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
    /// Scratch for the build, kept so a rebuild of the same size reuses it.
    keys: Vec<(u64, u32)>,
}

impl Bvh {
    /// Builds over `prims`. An empty input gives an empty tree (queries find
    /// nothing). Empty or non-finite boxes are allowed; they are never hit.
    pub fn build(prims: &[Aabb]) -> Bvh {
        let mut bvh = Bvh::default();
        bvh.rebuild(prims);
        bvh
    }

    /// Rebuilds in place, reusing the node and key buffers (no reallocation
    /// when the primitive count does not grow).
    pub fn rebuild(&mut self, prims: &[Aabb]) {
        self.rebuild_with(prims, |keys| {
            // Key space: the bounds of the box centres, so keys use all their bits.
            let centroid_bounds = prims
                .par_iter()
                .map(|b| {
                    let mut a = Aabb::EMPTY;
                    if !b.is_empty() && b.min.is_finite() && b.max.is_finite() {
                        a.grow(b.center());
                    }
                    a
                })
                .reduce(|| Aabb::EMPTY, Aabb::union);
            prims
                .par_iter()
                .enumerate()
                .map(|(i, b)| {
                    (
                        order::morton(order::quantize(b.center(), &centroid_bounds)),
                        i as u32,
                    )
                })
                .collect_into_vec(keys);
            order::sort_pairs(keys);
        });
    }

    /// Builds over primitives that already come in a spatially coherent
    /// order — the depth-first leaves of a k-d tree, say: the hierarchy
    /// follows that order (splitting index ranges where their highest bit
    /// changes) and skips the Morton keys and their sort.
    pub fn build_in_order(prims: &[Aabb]) -> Bvh {
        let mut bvh = Bvh::default();
        bvh.rebuild_in_order(prims);
        bvh
    }

    /// [`Bvh::build_in_order`] into the existing buffers.
    pub fn rebuild_in_order(&mut self, prims: &[Aabb]) {
        self.rebuild_with(prims, |keys| {
            keys.extend((0..prims.len() as u32).map(|i| (i as u64, i)))
        });
    }

    /// The shared build: `make_keys` fills the (cleared) key buffer with one
    /// sorted `(key, primitive)` pair per primitive, then the hierarchy follows
    /// the keys' bits.
    fn rebuild_with(&mut self, prims: &[Aabb], make_keys: impl FnOnce(&mut Vec<(u64, u32)>)) {
        let n = prims.len();
        self.nodes.clear();
        self.keys.clear();
        if n == 0 {
            return;
        }
        assert!(n < u32::MAX as usize / 2, "BVH limited to 2^31 primitives");
        make_keys(&mut self.keys);
        self.nodes.resize(2 * n - 1, Node::EMPTY);
        build_subtree(&mut self.nodes, &self.keys, prims);
    }

    /// Recomputes every box from new primitive boxes without changing the tree
    /// (after a radius change, for instance). `prims` must have the length the
    /// tree was built with.
    pub fn refit(&mut self, prims: &[Aabb]) {
        assert_eq!(
            prims.len(),
            self.primitive_count(),
            "refit needs the primitive count the tree was built with"
        );
        // Children follow their parent, so a reverse sweep sees children first.
        for i in (0..self.nodes.len()).rev() {
            let b = if self.nodes[i].is_leaf() {
                prims[self.nodes[i].index as usize]
            } else {
                let r = i + self.nodes[i].index as usize;
                self.nodes[i + 1].bounds().union(self.nodes[r].bounds())
            };
            self.nodes[i].set_bounds(b);
        }
    }

    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    pub fn primitive_count(&self) -> usize {
        if self.nodes.is_empty() {
            0
        } else {
            self.nodes.len().div_ceil(2)
        }
    }

    /// Bytes held by the tree (nodes only; the build scratch is excluded).
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>()
    }

    pub fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, Node::bounds)
    }

    /// Calls `visit(prim)` for every primitive whose box contains `p` (boundary
    /// included), in no particular order, visiting only nodes whose box
    /// contains `p`.
    #[inline]
    pub fn point_query(&self, p: Vec3, mut visit: impl FnMut(u32)) {
        self.descend(|n| n.contains(p), |n| visit(n.index));
    }

    /// Depth-first, left child first, over the nodes `hit` accepts; calls
    /// `leaf` for each accepted leaf. The left child is descended without
    /// touching the stack.
    #[inline(always)]
    fn descend(&self, hit: impl Fn(&Node) -> bool, mut leaf: impl FnMut(&Node)) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = [0u32; STACK];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let mut i = stack[sp] as usize;
            loop {
                let node = &self.nodes[i];
                if !hit(node) {
                    break;
                }
                if node.is_leaf() {
                    leaf(node);
                    break;
                }
                stack[sp] = (i + node.index as usize) as u32;
                sp += 1;
                i += 1;
            }
        }
    }

    /// Nearest first: visits the leaves whose box lies within the current
    /// bound of `p` (squared distance ≤ `bound2`), nearer children first;
    /// `leaf(prim)` returns the new squared bound (it may only shrink the
    /// search: a k-nearest search returns its k-th best distance so far).
    /// Box distances are computed in f32; callers needing exact answers pad
    /// the bound.
    pub fn nearest(&self, p: Vec3, mut bound2: f32, mut leaf: impl FnMut(u32) -> f32) {
        if self.nodes.is_empty() {
            return;
        }
        let d2 = |n: &Node| {
            let mut s = 0.0f32;
            for a in 0..3 {
                let v = p[a];
                let d = (n.min[a] - v).max(v - n.max[a]).max(0.0);
                s += d * d;
            }
            s
        };
        let mut stack = [(0u32, 0.0f32); STACK];
        let mut sp = 1;
        stack[0] = (0, d2(&self.nodes[0]));
        while sp > 0 {
            sp -= 1;
            let (mut i, mut di) = stack[sp];
            loop {
                if di > bound2 {
                    break;
                }
                let node = &self.nodes[i as usize];
                if node.is_leaf() {
                    bound2 = leaf(node.index);
                    break;
                }
                let (l, r) = (i + 1, i + node.index);
                let (dl, dr) = (d2(&self.nodes[l as usize]), d2(&self.nodes[r as usize]));
                // Descend into the nearer child; the farther waits on the stack.
                let (near, far) = if dl <= dr {
                    ((l, dl), (r, dr))
                } else {
                    ((r, dr), (l, dl))
                };
                if far.1 <= bound2 {
                    stack[sp] = far;
                    sp += 1;
                }
                (i, di) = near;
            }
        }
    }

    /// Calls `visit(prim, leaf box)` for every primitive whose box overlaps `b`, depth
    /// first, left child first — the order [`Bvh::point_query`] uses, so for
    /// any point in `b` the primitives containing it come in the same relative
    /// order (packet sampling relies on that to sum bit-identically).
    pub fn box_query(&self, b: &Aabb, mut visit: impl FnMut(u32, &Aabb)) {
        let overlaps = |n: &Node| {
            n.min[0] <= b.max.x
                && n.max[0] >= b.min.x
                && n.min[1] <= b.max.y
                && n.max[1] >= b.min.y
                && n.min[2] <= b.max.z
                && n.max[2] >= b.min.z
        };
        self.descend(overlaps, |n| visit(n.index, &n.bounds()));
    }

    /// Calls `visit(prim, t)` for every primitive whose box `ray` crosses
    /// within `t`, with the clipped parametric range, in no particular order.
    pub fn ray_query(&self, ray: &Ray, t: Range1, mut visit: impl FnMut(u32, Range1)) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = [0u32; STACK];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let i = stack[sp] as usize;
            let node = &self.nodes[i];
            let hit = node.bounds().clip_ray(ray, t);
            if hit.is_empty() {
                continue;
            }
            if node.is_leaf() {
                visit(node.index, hit);
            } else {
                stack[sp] = (i + node.index as usize) as u32;
                stack[sp + 1] = i as u32 + 1;
                sp += 2;
            }
        }
    }

    /// Closest-hit traversal: nodes front to back along `ray` (the nearer
    /// child first), calling `test(prim, t_max)` for each leaf the ray
    /// crosses before the current `t_max`; a `Some(t)` answer (a hit at `t`,
    /// which must be `< t_max`) shrinks `t_max`, so subtrees behind the
    /// nearest hit so far are never opened. Returns the final `t_max`
    /// (`t.hi` when nothing was hit).
    pub fn ray_closest(
        &self,
        ray: &Ray,
        t: Range1,
        mut test: impl FnMut(u32, f32) -> Option<f32>,
    ) -> f32 {
        let mut t_max = t.hi;
        if self.nodes.is_empty() {
            return t_max;
        }
        let inv = ray.inv_dir();
        // Stack entries carry the entry distance of their box, so a subtree
        // queued before a closer hit was found is dropped when popped.
        let mut stack = [(0u32, 0f32); STACK];
        let mut sp = 0;
        let mut i = 0usize;
        let Some(first) = slab(&self.nodes[0], ray, inv, t.lo, t_max) else {
            return t_max;
        };
        let mut entry = first;
        loop {
            if entry < t_max {
                let node = &self.nodes[i];
                if node.is_leaf() {
                    if let Some(h) = test(node.index, t_max) {
                        t_max = t_max.min(h);
                    }
                } else {
                    let (l, r) = (i + 1, i + node.index as usize);
                    let tl = slab(&self.nodes[l], ray, inv, t.lo, t_max);
                    let tr = slab(&self.nodes[r], ray, inv, t.lo, t_max);
                    match (tl, tr) {
                        (Some(a), Some(b)) => {
                            // Descend into the nearer child, keep the other.
                            let (near, far) = if a <= b {
                                ((l, a), (r, b))
                            } else {
                                ((r, b), (l, a))
                            };
                            stack[sp] = (far.0 as u32, far.1);
                            sp += 1;
                            (i, entry) = near;
                            continue;
                        }
                        (Some(a), None) => {
                            (i, entry) = (l, a);
                            continue;
                        }
                        (None, Some(b)) => {
                            (i, entry) = (r, b);
                            continue;
                        }
                        (None, None) => {}
                    }
                }
            }
            if sp == 0 {
                return t_max;
            }
            sp -= 1;
            (i, entry) = (stack[sp].0 as usize, stack[sp].1);
        }
    }

    /// Checks the invariants listed in the crate docs against `prims` (the
    /// boxes the tree was built or last refitted with).
    pub fn validate(&self, prims: &[Aabb]) -> Result<(), InvalidBvh> {
        let n = prims.len();
        if n == 0 {
            return if self.nodes.is_empty() {
                Ok(())
            } else {
                Err(InvalidBvh("nodes present for zero primitives".into()))
            };
        }
        if self.nodes.len() != 2 * n - 1 {
            return Err(InvalidBvh(format!(
                "{} nodes for {n} primitives",
                self.nodes.len()
            )));
        }
        let mut seen = vec![false; n];
        // (node, end of its subtree) — depth-first ranges must tile exactly.
        let mut stack = vec![(0usize, self.nodes.len())];
        while let Some((i, end)) = stack.pop() {
            let node = &self.nodes[i];
            if node.is_leaf() {
                if end != i + 1 {
                    return Err(InvalidBvh(format!("leaf {i} spans {} nodes", end - i)));
                }
                let p = node.index as usize;
                if p >= n || std::mem::replace(&mut seen[p], true) {
                    return Err(InvalidBvh(format!("primitive {p} missing or repeated")));
                }
                if node.bounds() != prims[p] && !(node.bounds().is_empty() && prims[p].is_empty()) {
                    return Err(InvalidBvh(format!(
                        "leaf {i} box differs from primitive {p}"
                    )));
                }
            } else {
                let r = i + node.index as usize;
                if r <= i + 1 || r >= end {
                    return Err(InvalidBvh(format!(
                        "node {i} has right child {r} outside ({i}, {end})"
                    )));
                }
                for c in [i + 1, r] {
                    if !node.bounds().encloses(&self.nodes[c].bounds()) {
                        return Err(InvalidBvh(format!("node {i} does not enclose child {c}")));
                    }
                }
                stack.push((i + 1, r));
                stack.push((r, end));
            }
        }
        Ok(())
    }
}

/// Builds the subtree over `keys` into `nodes` (exactly `2·keys.len() − 1`
/// slots) and returns its box.
fn build_subtree(nodes: &mut [Node], keys: &[(u64, u32)], prims: &[Aabb]) -> Aabb {
    if keys.len() == 1 {
        let p = keys[0].1;
        let b = prims[p as usize];
        nodes[0] = Node {
            index: p,
            is_leaf: 1,
            ..Node::EMPTY
        };
        nodes[0].set_bounds(b);
        return b;
    }
    let split = split_position(keys);
    let (head, rest) = nodes.split_at_mut(1);
    let (left_nodes, right_nodes) = rest.split_at_mut(2 * split - 1);
    let (left_keys, right_keys) = keys.split_at(split);
    let (lb, rb) = if keys.len() > PARALLEL_GRAIN {
        rayon::join(
            || build_subtree(left_nodes, left_keys, prims),
            || build_subtree(right_nodes, right_keys, prims),
        )
    } else {
        (
            build_subtree(left_nodes, left_keys, prims),
            build_subtree(right_nodes, right_keys, prims),
        )
    };
    let b = lb.union(rb);
    head[0] = Node {
        index: (2 * split) as u32,
        is_leaf: 0,
        ..Node::EMPTY
    };
    head[0].set_bounds(b);
    b
}

/// Number of keys in the left child: the first position where the highest bit
/// that differs between the first and last key is set, or the middle when all
/// keys are equal (duplicates still give a balanced subtree).
fn split_position(keys: &[(u64, u32)]) -> usize {
    let first = keys[0].0;
    let last = keys[keys.len() - 1].0;
    if first == last {
        return keys.len() / 2;
    }
    // All keys share the bits above `bit`; those with `bit` clear sort first.
    let bit = 63 - (first ^ last).leading_zeros();
    let lo_prefix = first >> bit;
    keys.partition_point(|&(k, _)| k >> bit == lo_prefix)
}

#[cfg(test)]
mod tests;

/// Where `ray` enters `node`'s box within `[t_lo, t_hi]` (slab test with a
/// precomputed inverse direction); `None` when it misses.
#[inline(always)]
fn slab(node: &Node, ray: &Ray, inv: Vec3, t_lo: f32, t_hi: f32) -> Option<f32> {
    let mut lo = t_lo;
    let mut hi = t_hi;
    for a in 0..3 {
        if ray.dir[a] == 0.0 {
            // Parallel to the slab: inside it (faces included) or a miss;
            // no 0·∞ products.
            if ray.origin[a] < node.min[a] || ray.origin[a] > node.max[a] {
                return None;
            }
            continue;
        }
        let t0 = (node.min[a] - ray.origin[a]) * inv[a];
        let t1 = (node.max[a] - ray.origin[a]) * inv[a];
        lo = lo.max(t0.min(t1));
        hi = hi.min(t0.max(t1));
    }
    (lo <= hi).then_some(lo)
}
