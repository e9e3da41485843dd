//! The region tree walked by eight rays at once (the coherent packet
//! traversal of the CPU RBF paper §4, on the k-d tree of ExaBricks'
//! regions).
//!
//! Rays whose directions have the same signs meet the two children of
//! every cut in the same order, so one walk serves them all: each node is
//! read once for the packet, each ray keeps its own part `[lo, hi)` of the
//! node, and a child is entered when any ray reaches it. Per ray, every
//! step is the one [`RegionTree::walk`] takes — the same plane time, the
//! same comparisons, the same side for a ray in the plane — so each ray
//! gets its regions in its own front-to-back order with bit-identical
//! ranges. What is shared is the node's load and the walk's bookkeeping,
//! which were most of a per-ray walk's cost (~40 instructions per node per
//! ray).
//!
//! The rays' steps at a cut run in SIMD lanes, one ray per lane: the plane
//! times, both comparisons and both new ends are a few vector operations,
//! and the rays that go to each side are the comparisons' bit masks. IEEE
//! arithmetic is the same in a lane as in a scalar, so the lanes give the
//! scalar walk's bits. (Written as a loop over eight rays, the compiler
//! left this step scalar; in lanes the walk costs 3 % less of an AMR
//! frame, docs/benchmarks.md.)

use voxless_core::simd::{LANES, Lanes, Simd, WithLanes, dispatch};
use voxless_core::{Range1, Ray};

use super::{Cut, LEAF, NodeMask, RegionTree};

/// Rays walked together at most.
pub(crate) const PACKET_RAYS: usize = 8;

/// A subtree waiting for the packet: its node, the rays that reach it and
/// their parts of it.
#[derive(Clone, Copy)]
struct Pending {
    node: u32,
    active: u8,
    lo: [f32; PACKET_RAYS],
    hi: [f32; PACKET_RAYS],
}

const EMPTY: Pending = Pending {
    node: 0,
    active: 0,
    lo: [0.0; PACKET_RAYS],
    hi: [0.0; PACKET_RAYS],
};

thread_local! {
    /// The pending subtrees of a packet walk, kept between walks.
    static STACK: std::cell::Cell<Vec<Pending>> = const { std::cell::Cell::new(Vec::new()) };
}

/// Whether the signs of `a`'s and `b`'s inverse directions agree on every
/// axis (so a packet walk can take them together).
pub(crate) fn same_octant(a: &Ray, b: &Ray) -> bool {
    octant(a) == octant(b)
}

/// The signs of a ray's direction (those of `1/d` too, ±0 included).
fn octant(r: &Ray) -> u8 {
    let d = r.dir;
    (d.x.is_sign_negative() as u8)
        | (d.y.is_sign_negative() as u8) << 1
        | (d.z.is_sign_negative() as u8) << 2
}

impl RegionTree {
    /// [`RegionTree::walk`] for up to [`PACKET_RAYS`] rays at once, all in
    /// one octant ([`same_octant`]), never stopping: calls `leaf(k, region,
    /// t)` for every region (of those `mask` keeps) that ray `rays[k]`
    /// crosses within `t[k]`, each ray's regions front to back, with the
    /// range [`RegionTree::walk`] gives it. The rays' steps at a cut run in
    /// lanes on the SIMD backend `simd` (every backend gives the same bits).
    pub fn walk_packet(
        &self,
        simd: Simd,
        rays: &[Ray],
        t: &[Range1],
        mask: Option<&NodeMask>,
        leaf: impl FnMut(usize, u32, Range1),
    ) {
        assert!(
            rays.len() == t.len() && rays.len() <= PACKET_RAYS,
            "a packet walk takes one range per ray and at most {PACKET_RAYS} rays"
        );
        if self.nodes.is_empty() || rays.is_empty() {
            return;
        }
        debug_assert!(rays.iter().all(|r| same_octant(r, &rays[0])));
        dispatch(
            simd,
            PacketWalk {
                tree: self,
                rays,
                t,
                mask,
                leaf,
            },
        );
    }

    /// The walk on lanes `L` (one lane per ray).
    #[inline(always)]
    fn walk_packet_lanes<L: Lanes>(
        &self,
        rays: &[Ray],
        t: &[Range1],
        mask: Option<&NodeMask>,
        mut leaf: impl FnMut(usize, u32, Range1),
    ) {
        let n = rays.len();
        // Lanes without a ray (or whose ray misses the tree) stay inactive.
        let (mut org, mut inv) = ([[0.0; PACKET_RAYS]; 3], [[1.0; PACKET_RAYS]; 3]);
        let (mut lo, mut hi) = ([0.0; PACKET_RAYS], [0.0; PACKET_RAYS]);
        let mut active = 0u8;
        for (k, ray) in rays.iter().enumerate() {
            let tk = self.root.clip_ray(ray, t[k]);
            let d = ray.inv_dir();
            for (a, (o, i)) in [
                (ray.origin.x, d.x),
                (ray.origin.y, d.y),
                (ray.origin.z, d.z),
            ]
            .into_iter()
            .enumerate()
            {
                (org[a][k], inv[a][k]) = (o, i);
            }
            if tk.lo < tk.hi {
                (lo[k], hi[k]) = (tk.lo, tk.hi);
                active |= 1 << k;
            }
        }
        if active == 0 {
            return;
        }
        let below_near = [0, 1, 2].map(|a| inv[a][0].is_sign_positive());
        let (org_l, inv_l) = (org.map(L::from_array), inv.map(L::from_array));
        let (mut lo, mut hi) = (L::from_array(lo), L::from_array(hi));
        let mut stack = STACK.take();
        if stack.len() <= self.depth {
            stack.resize(self.depth + 1, EMPTY);
        }
        let mut sp = 0;
        let mut i = 0usize;
        loop {
            let node = self.nodes[i];
            let keep = mask.is_none_or(|m| m.get(i));
            if keep && node.kind < LEAF {
                let Cut {
                    axis: a,
                    left,
                    near,
                    far,
                    ..
                } = node.cut(i, below_near);
                // Per ray, as the single-ray walk: the near part ends at
                // the plane when the plane lies inside `(lo, hi)`, the far
                // part starts there (the same product and comparisons, in
                // lanes).
                let ts = (L::splat(node.at) - org_l[a]) * inv_l[a];
                let (before_hi, after_lo) = (ts.lt(hi), ts.gt(lo));
                let mut to_near = after_lo.bitmask() as u8;
                let mut to_far = before_hi.bitmask() as u8;
                // A ray in the plane (NaN: no comparison holds, so it keeps
                // its part) goes to the side its origin is on.
                let in_plane = !(ts.le(ts).bitmask() as u8) & active;
                if in_plane != 0 {
                    for k in (0..PACKET_RAYS).filter(|k| in_plane >> k & 1 != 0) {
                        let below = org[a][k] < node.at;
                        to_near |= ((below == (near == left)) as u8) << k;
                        to_far |= ((below != (near == left)) as u8) << k;
                    }
                }
                let near_hi = before_hi.select(ts, hi);
                let far_lo = after_lo.select(ts, lo);
                (to_near, to_far) = (to_near & active, to_far & active);
                if to_far != 0 {
                    if to_near == 0 {
                        (i, active, lo) = (far, to_far, far_lo);
                        continue;
                    }
                    stack[sp] = Pending {
                        node: far as u32,
                        active: to_far,
                        lo: far_lo.to_array(),
                        hi: hi.to_array(),
                    };
                    sp += 1;
                }
                if to_near != 0 {
                    (i, active, hi) = (near, to_near, near_hi);
                    continue;
                }
            } else if keep && node.kind == LEAF {
                let open = lo.lt(hi).bitmask() as u8 & active;
                if open != 0 {
                    let (lo, hi) = (lo.to_array(), hi.to_array());
                    for k in (0..n).filter(|k| open >> k & 1 != 0) {
                        leaf(k, node.index, Range1::new(lo[k], hi[k]));
                    }
                }
            }
            if sp == 0 {
                break;
            }
            sp -= 1;
            let p = stack[sp];
            (i, active) = (p.node as usize, p.active);
            (lo, hi) = (L::from_array(p.lo), L::from_array(p.hi));
        }
        STACK.set(stack);
    }
}

/// [`RegionTree::walk_packet`]'s walk, instantiated per lane type.
struct PacketWalk<'a, F> {
    tree: &'a RegionTree,
    rays: &'a [Ray],
    t: &'a [Range1],
    mask: Option<&'a NodeMask>,
    leaf: F,
}

impl<F: FnMut(usize, u32, Range1)> WithLanes for PacketWalk<'_, F> {
    type Output = ();
    #[inline(always)]
    fn run<L: Lanes>(self) {
        self.tree
            .walk_packet_lanes::<L>(self.rays, self.t, self.mask, self.leaf)
    }
}

// One lane per ray of a packet.
const _: () = assert!(PACKET_RAYS == LANES);
