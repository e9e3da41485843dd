//! Tets derived from grid indices: the six tets of a Lagrangian cell, its
//! periodic images and its degenerate point masses, computed from the
//! particle positions whenever an operation asks for them.
//!
//! Nothing is stored per tet. A tet is a function of its cell `(i, j, k)`,
//! its place in the Kuhn decomposition and its image shift, so a mesh keeps
//! only the positions (12 bytes per particle, against 6 × 52 bytes per cell
//! for explicit tets) and, per culling block, the bounds of each image
//! group. Every operation regenerates the tets of the blocks it visits, with
//! exactly the arithmetic of the former explicit construction (the same f32
//! unwrapping, f64 volumes and f32 densities, the same order), so the tets
//! — and every image made from them — are bit for bit the same.

use std::ops::Range;

use voxless_core::{Aabb, Vec3};

use crate::mesh::{KUHN, Tet};

/// The particles of a Lagrangian grid (or of a slab of its planes) and
/// what turns them into tets.
#[derive(Clone, Debug)]
pub(crate) struct Lattice {
    /// Particles per axis of the whole run.
    pub n: usize,
    /// Periodic box size.
    pub l: f32,
    /// Positions of planes `first_plane ..` (periodically), plane-major in
    /// Lagrangian order within each plane.
    positions: Vec<Vec3>,
    first_plane: usize,
    /// Cells per culling-block axis.
    pub block: usize,
    /// Mass of each tet: the particle mass / 6.
    pub tet_mass: f64,
    /// Tets with `|V|` below this are degenerate: point masses, not tets.
    pub floor: f64,
    /// The fraction of the mean volume `floor` was made from (coarser
    /// levels of detail use it with their own mean volume).
    pub degenerate_fraction: f64,
}

/// What a scan of one Lagrangian block finds: its tets grouped by image
/// shift in order of first appearance (shift, tet count, bounds), and its
/// degenerate tets' point masses.
pub(crate) struct BlockScan {
    pub groups: Vec<([i8; 3], u64, Aabb)>,
    pub points: Vec<(Vec3, f64)>,
    /// Whether the block's one group holds every (non-degenerate) tet of
    /// the block once: then no tet has another image, and deriving the
    /// group needs no image test.
    pub complete: bool,
    /// How far any corner of a cell of the block lies from the cell's first
    /// corner, per axis (unwrapped): the cell's tets lie in the cube of
    /// this half-size about it.
    pub reach: f32,
}

impl Lattice {
    /// `positions` hold the planes `first_plane ..` of an N³ run (checked
    /// by the caller: every plane an operation reaches is there).
    pub fn new(
        (n, l): (usize, f32),
        positions: Vec<Vec3>,
        first_plane: usize,
        block: usize,
        particle_mass: f64,
        degenerate_fraction: f64,
    ) -> Lattice {
        let mean_volume = (l as f64 / n as f64).powi(3) / 6.0;
        Lattice {
            n,
            l,
            positions,
            first_plane,
            block,
            tet_mass: particle_mass / 6.0,
            floor: degenerate_fraction * mean_volume,
            degenerate_fraction,
        }
    }

    /// Bytes of positions held.
    pub fn held_bytes(&self) -> usize {
        self.positions.len() * std::mem::size_of::<Vec3>()
    }

    /// Position of particle `(i, j, k)` of a whole grid (indices below N).
    fn at(&self, i: usize, j: usize, k: usize) -> Vec3 {
        self.positions[(i * self.n + j) * self.n + k]
    }

    /// Culling blocks per axis.
    pub fn blocks_per_axis(&self) -> usize {
        self.n.div_ceil(self.block)
    }

    /// The cells of Lagrangian block `b`, per axis.
    #[inline]
    pub fn cells(&self, b: u32) -> [Range<usize>; 3] {
        let nb = self.blocks_per_axis();
        let b = b as usize;
        let (bi, bj, bk) = (b / (nb * nb), (b / nb) % nb, b % nb);
        let axis = |c: usize| c * self.block..((c + 1) * self.block).min(self.n);
        [axis(bi), axis(bj), axis(bk)]
    }

    /// The index in `positions` of plane `i` (up to N: plane N of the whole
    /// grid is plane 0; a slab holds the plane after its last row as its
    /// own last plane).
    #[inline(always)]
    fn plane(&self, i: usize) -> usize {
        let n = self.n;
        let p = i - self.first_plane;
        if p * n * n >= self.positions.len() {
            p - n
        } else {
            p
        }
    }

    /// The 8 corners of cell (i, j, k), unwrapped to the periodic image
    /// nearest corner 0 (corner index = 4·di + 2·dj + dk).
    #[inline(always)]
    pub fn cell_corners(&self, i: usize, j: usize, k: usize) -> [Vec3; 8] {
        let (n, l) = (self.n, self.l);
        // Offsets of the corners' planes, rows and columns in `positions`
        // (no division per corner: only the last index of an axis wraps).
        let next = |a: usize| if a + 1 == n { 0 } else { a + 1 };
        let pi = [self.plane(i) * n * n, self.plane(i + 1) * n * n];
        let rj = [j * n, next(j) * n];
        let ck = [k, next(k)];
        let anchor = self.positions[pi[0] + rj[0] + ck[0]];
        let mut d = [Vec3::ZERO; 8];
        // One running maximum per axis: three short chains, not one long.
        let mut far = [0.0f32; 3];
        for (c, slot) in d.iter_mut().enumerate().skip(1) {
            *slot = self.positions[pi[c >> 2] + rj[(c >> 1) & 1] + ck[c & 1]] - anchor;
            for a in 0..3 {
                far[a] = max(far[a], slot[a].abs());
            }
        }
        let far = max(max(far[0], far[1]), far[2]);
        let mut out = [anchor; 8];
        if far < 0.49 * l {
            // Every neighbour is nearest to the anchor as it is: the wrap
            // below rounds d/L to a zero of d's sign, and d − l·(±0) is
            // d + 0 (−0 becoming +0), without a division or rounding.
            for c in 1..8 {
                out[c] = anchor + (d[c] + Vec3::ZERO);
            }
        } else {
            let wrap = |x: f32| x - l * round(x / l);
            for c in 1..8 {
                out[c] = anchor + Vec3::new(wrap(d[c].x), wrap(d[c].y), wrap(d[c].z));
            }
        }
        out
    }

    /// One pass over block `b`'s tets: the image groups and point masses
    /// the explicit construction made, in its order.
    pub fn scan(&self, b: u32) -> BlockScan {
        let mut groups: Vec<([i8; 3], u64, Aabb)> = Vec::new();
        let mut points = Vec::new();
        let mut tets = 0u64;
        let mut reach = 0.0f32;
        let [ri, rj, rk] = self.cells(b);
        for i in ri {
            for j in rj.clone() {
                for k in rk.clone() {
                    let corners = self.cell_corners(i, j, k);
                    let mut far = [0.0f32; 3];
                    for c in &corners[1..] {
                        let d = *c - corners[0];
                        for a in 0..3 {
                            far[a] = max(far[a], d[a].abs());
                        }
                    }
                    reach = max(reach, max(max(far[0], far[1]), far[2]));
                    // A cell strictly inside the box: its tets are their own
                    // only image (no shift brings them back in or out).
                    let (clo, chi) = extent(&corners);
                    let inside = (0..3).all(|a| clo[a] > 0.0 && chi[a] < self.l);
                    if inside && self.scan_inside(&corners, (clo, chi), &mut groups) {
                        tets += 6;
                        continue;
                    }
                    let volumes = Tet::kuhn_volumes(&corners);
                    for (t, volume) in KUHN.into_iter().zip(volumes) {
                        let v = t.map(|c| corners[c]);
                        let vol = volume.abs();
                        let (lo, hi) = extent(&v);
                        let (shifts, count) = if inside {
                            ([[0i8; 3]; 27], 1)
                        } else {
                            images_of(lo, hi, self.l)
                        };
                        if vol < self.floor {
                            for &shift in &shifts[..count] {
                                let vs = v.map(|p| p + offset(shift, self.l));
                                let c = (vs[0] + vs[1] + vs[2] + vs[3]) * 0.25;
                                // The point mass belongs to the image whose
                                // centroid is in the box.
                                if in_box(c, self.l) {
                                    points.push((c, self.tet_mass));
                                }
                            }
                            continue;
                        }
                        tets += 1;
                        for &shift in &shifts[..count] {
                            // Rounding is monotonic, so the bounds of the
                            // moved vertices are the moved extent.
                            let off = offset(shift, self.l);
                            let bounds = Aabb::new(
                                Vec3::new(lo[0] + off.x, lo[1] + off.y, lo[2] + off.z),
                                Vec3::new(hi[0] + off.x, hi[1] + off.y, hi[2] + off.z),
                            );
                            match groups.iter_mut().find(|g| g.0 == shift) {
                                Some(g) => {
                                    g.1 += 1;
                                    g.2 = g.2.union(bounds);
                                }
                                None => groups.push((shift, 1, bounds)),
                            }
                        }
                    }
                }
            }
        }
        let complete = groups.len() == 1 && groups[0].1 == tets;
        BlockScan {
            groups,
            points,
            complete,
            reach,
        }
    }

    /// [`Lattice::scan`] of a cell strictly inside the box whose six tets
    /// are all non-degenerate: they join the group of shift 0 with the
    /// cell's extent (the union of theirs: every corner is some tet's
    /// vertex). `false`, with nothing added, when a tet is degenerate.
    #[inline(always)]
    fn scan_inside(
        &self,
        corners: &[Vec3; 8],
        (lo, hi): ([f32; 3], [f32; 3]),
        groups: &mut Vec<([i8; 3], u64, Aabb)>,
    ) -> bool {
        if Tet::kuhn_volumes(corners)
            .iter()
            .any(|v| v.abs() < self.floor)
        {
            return false;
        }
        let bounds = Aabb::new(
            Vec3::new(lo[0], lo[1], lo[2]),
            Vec3::new(hi[0], hi[1], hi[2]),
        );
        match groups.iter_mut().find(|g| g.0 == [0; 3]) {
            Some(g) => {
                g.1 += 6;
                g.2 = g.2.union(bounds);
            }
            None => groups.push(([0; 3], 6, bounds)),
        }
        true
    }

    /// Appends the tets of block `b` at image `shift`, in mesh order, of the
    /// cells `keep` accepts: it sees the cell's first corner moved to the
    /// image, and every tet of the cell lies within the block's `reach` of
    /// it per axis (see [`BlockScan::reach`]); cells it rejects cost no
    /// more. `complete`: the group holds every tet of the block (see
    /// [`BlockScan::complete`]).
    #[inline]
    pub fn tets(
        &self,
        group: (u32, [i8; 3], bool),
        keep: impl FnMut(Vec3) -> bool,
        out: &mut Vec<Tet>,
    ) {
        self.cells_where(group, keep, |cell| {
            let (tets, count) = cell.tets();
            out.extend(tets[..count].iter().map(|t| t.1));
        });
    }

    /// [`Lattice::tets`] cell by cell: `f` gets each accepted [`Cell`],
    /// whose corners are at hand and whose tets it derives if it wants them.
    #[inline]
    pub fn cells_where(
        &self,
        (b, shift, complete): (u32, [i8; 3], bool),
        mut keep: impl FnMut(Vec3) -> bool,
        mut f: impl FnMut(&Cell),
    ) {
        let off = offset(shift, self.l);
        let [ri, rj, rk] = self.cells(b);
        let n = self.n;
        if let Some(i) = ri.clone().next() {
            self.prefetch_rows(i, &rj, &rk);
        }
        for i in ri {
            // The next plane's rows while this one's cells are worked on:
            // a block's rows are ~100 bytes each, N·12 bytes apart, which
            // the hardware prefetchers do not follow (the first read of a
            // cell's anchor was ~8 % of an exact 256³ render's samples).
            self.prefetch_rows(i + 1, &rj, &rk);
            let plane = self.plane(i) * n * n;
            for j in rj.clone() {
                for k in rk.clone() {
                    if !keep(self.positions[plane + j * n + k] + off) {
                        continue;
                    }
                    let corners = self.cell_corners(i, j, k);
                    f(&Cell {
                        lattice: self,
                        at_image: corners.map(|p| p + off),
                        corners,
                        shift,
                        off,
                        complete,
                    });
                }
            }
        }
    }

    /// Prefetches the positions of plane `i`'s rows `rj` and the row after
    /// (the cells' corners), columns `rk` and the one after.
    #[inline]
    fn prefetch_rows(&self, i: usize, rj: &Range<usize>, rk: &Range<usize>) {
        let n = self.n;
        let plane = self.plane(i) * n * n;
        let last = rk.end.min(n - 1);
        for j in rj.start..=rj.end.min(n - 1) {
            let row = &self.positions[plane + j * n..plane + (j + 1) * n];
            let (a, b) = (
                row[rk.start..].as_ptr() as usize,
                &row[last] as *const Vec3 as usize,
            );
            for line in (a & !63..=b).step_by(64) {
                voxless_core::simd::prefetch(line as *const u8);
            }
        }
    }

    /// The tets of the cell with `corners` at image `shift` (`off` its
    /// offset), in Kuhn order with their index in [`KUHN`]: those that are
    /// not degenerate and whose own images include `shift` (`TEST`; without
    /// it every tet is taken).
    #[inline(always)]
    pub fn cell_tets<const TEST: bool>(
        &self,
        corners: &[Vec3; 8],
        shift: [i8; 3],
        off: Vec3,
        f: &mut impl FnMut((usize, Tet)),
    ) {
        for (index, t) in KUHN.into_iter().enumerate() {
            let v = t.map(|c| corners[c]);
            let vol = Tet::signed_volume(&v).abs();
            if vol < self.floor || (TEST && !has_image(&v, shift, self.l)) {
                continue;
            }
            f((
                index,
                Tet {
                    v: v.map(|p| p + off),
                    density: (self.tet_mass / vol) as f32,
                },
            ));
        }
    }

    /// Every cell of block `b` at each image its corners reach the box at
    /// (the point index's primitives; a cell's hull holds its six tets and
    /// their images are among the cell's): `f(cell, shift, offset, corners,
    /// bounds)`, the cell's index `(i·N + j)·N + k`, its corners unmoved and
    /// their bounds at the image.
    #[inline]
    pub fn cell_images(&self, b: u32, mut f: impl FnMut(usize, [i8; 3], Vec3, &[Vec3; 8], Aabb)) {
        let n = self.n;
        let [ri, rj, rk] = self.cells(b);
        for i in ri {
            for j in rj.clone() {
                for k in rk.clone() {
                    let corners = self.cell_corners(i, j, k);
                    let (shifts, count) = images(&corners, self.l);
                    for &shift in &shifts[..count] {
                        let off = offset(shift, self.l);
                        let mut bounds = Aabb::EMPTY;
                        for p in corners {
                            bounds.grow(p + off);
                        }
                        f((i * n + j) * n + k, shift, off, &corners, bounds);
                    }
                }
            }
        }
    }

    /// Tet `idx`, in mesh order, of block `b` at image `shift` when that
    /// group holds all of the block's tets and they number `count` = six a
    /// cell (none degenerate): then tet `idx` is tet `idx % 6` of the
    /// `idx / 6`-th cell, derived alone. `None` for any other block.
    pub fn nth_tet(&self, b: u32, shift: [i8; 3], count: u64, idx: u64) -> Option<Tet> {
        let [ri, rj, rk] = self.cells(b);
        let (nj, nk) = (rj.len(), rk.len());
        if count != 6 * (ri.len() * nj * nk) as u64 || idx >= count {
            return None;
        }
        let c = (idx / 6) as usize;
        let (i, j, k) = (
            ri.start + c / (nj * nk),
            rj.start + (c / nk) % nj,
            rk.start + c % nk,
        );
        let corners = self.cell_corners(i, j, k);
        let target = (idx % 6) as usize;
        let mut found = None;
        self.cell_tets::<false>(&corners, shift, offset(shift, self.l), &mut |(index, t)| {
            if index == target {
                found = Some(t);
            }
        });
        found
    }

    /// Level of detail `r`: every 2^r-th particle per axis, each carrying
    /// the mass of the 2^{3r} it stands for, in blocks of `block >> r`
    /// cells (so a coarse block covers the same Lagrangian block). `None`
    /// where N is not divisible by 2^r, the coarse grid would be below 2³,
    /// or the blocks below one cell.
    pub fn coarse(&self, r: u32) -> Option<Lattice> {
        let step = 1usize << r;
        if self.block >> r == 0 || !self.n.is_multiple_of(step) || self.n >> r < 2 {
            return None;
        }
        let nc = self.n / step;
        // Only a whole grid (all planes held) has coarse levels.
        if self.positions.len() != self.n * self.n * self.n || self.first_plane != 0 {
            return None;
        }
        let positions = (0..nc * nc * nc)
            .map(|c| {
                let (i, j, k) = (c / (nc * nc), (c / nc) % nc, c % nc);
                self.at(i * step, j * step, k * step)
            })
            .collect();
        let mass = self.tet_mass * 6.0 * (step * step * step) as f64;
        Some(Lattice::new(
            (nc, self.l),
            positions,
            0,
            self.block >> r,
            mass,
            self.degenerate_fraction,
        ))
    }
}

/// `y.round()` (half away from zero, signed zeros kept), inline: without
/// SSE4.1 `roundf` is a library call, and unwrapping a cell's corners makes
/// 21 of them.
#[inline(always)]
fn round(y: f32) -> f32 {
    if !(y.abs() < 8_388_608.0) {
        // |y| ≥ 2²³ is integral already (or not finite).
        return y.round();
    }
    let t = (y as i32 as f32).copysign(y);
    // y − t is exact (t is y truncated), so the comparisons are exact.
    let r = y - t;
    if r >= 0.5 {
        t + 1.0
    } else if r <= -0.5 {
        t - 1.0
    } else {
        t
    }
}

/// A cell of a block group being visited: its corners moved to the group's
/// image, and its tets on request.
pub(crate) struct Cell<'a> {
    lattice: &'a Lattice,
    /// The corners (corner index = 4·di + 2·dj + dk) at the image.
    pub at_image: [Vec3; 8],
    corners: [Vec3; 8],
    shift: [i8; 3],
    off: Vec3,
    complete: bool,
}

impl Cell<'_> {
    /// The cell's tets at the image, in Kuhn order with their index in
    /// [`KUHN`] (`tet.v[m] == at_image[KUHN[index][m]]`): the first `count`
    /// of the array.
    #[inline]
    pub fn tets(&self) -> ([(usize, Tet); 6], usize) {
        let none = Tet {
            v: [Vec3::ZERO; 4],
            density: 0.0,
        };
        let mut tets = [(0, none); 6];
        let mut count = 0;
        let mut push = |t| {
            tets[count] = t;
            count += 1;
        };
        let l = self.lattice;
        if self.complete {
            l.cell_tets::<false>(&self.corners, self.shift, self.off, &mut push);
        } else {
            l.cell_tets::<true>(&self.corners, self.shift, self.off, &mut push);
        }
        (tets, count)
    }
}

/// The offset of image `shift` (in box lengths per axis).
#[inline(always)]
pub(crate) fn offset(shift: [i8; 3], l: f32) -> Vec3 {
    Vec3::new(shift[0] as f32, shift[1] as f32, shift[2] as f32) * l
}

pub(crate) fn in_box(p: Vec3, l: f32) -> bool {
    (0..3).all(|a| p[a] >= 0.0 && p[a] < l)
}

/// Per axis, whether shift `s` (−1, 0 or +1) brings the extent `[lo, hi]`
/// to overlap `[0, L)`.
#[inline(always)]
fn overlaps(lo: f32, hi: f32, s: i8, l: f32) -> bool {
    hi + s as f32 * l > 0.0 && lo + (s as f32) * l < l
}

#[inline(always)]
pub(crate) fn extent(v: &[Vec3]) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in v {
        for a in 0..3 {
            lo[a] = min(lo[a], p[a]);
            hi[a] = max(hi[a], p[a]);
        }
    }
    (lo, hi)
}

/// The larger of two coordinates. A lattice's positions are finite (the
/// loader refuses others), and so are their projections (points behind a
/// perspective eye are never projected), so `f32::max`'s NaN handling —
/// three instructions on x86 where this is one — buys nothing here; in the
/// per-cell chains of the scan and the corners it was a third of the
/// scan's time. (Equal values of either sign of zero may give either.)
#[inline(always)]
pub(crate) fn max(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// The smaller of two coordinates (see [`max`]).
#[inline(always)]
pub(crate) fn min(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// Whether `shift` is one of [`images`] of `v`.
#[inline(always)]
fn has_image(v: &[Vec3; 4], shift: [i8; 3], l: f32) -> bool {
    let (lo, hi) = extent(v);
    (0..3).all(|a| overlaps(lo[a], hi[a], shift[a], l))
}

/// The image shifts (in box lengths, per axis −1, 0 or +1) at which the
/// points `v` (a tet, a cell) overlap the box `[0, L)³`: the points
/// themselves if they do, plus the images that bring their out-of-box
/// parts back in; x slowest, each axis in the order −1, 0, +1.
#[inline]
pub(crate) fn images(v: &[Vec3], l: f32) -> ([[i8; 3]; 27], usize) {
    let (lo, hi) = extent(v);
    images_of(lo, hi, l)
}

/// [`images`] of the extent `[lo, hi]`.
#[inline]
fn images_of(lo: [f32; 3], hi: [f32; 3], l: f32) -> ([[i8; 3]; 27], usize) {
    let mut out = [[0i8; 3]; 27];
    let mut count = 0;
    for x in [-1i8, 0, 1] {
        if !overlaps(lo[0], hi[0], x, l) {
            continue;
        }
        for y in [-1i8, 0, 1] {
            if !overlaps(lo[1], hi[1], y, l) {
                continue;
            }
            for z in [-1i8, 0, 1] {
                if overlaps(lo[2], hi[2], z, l) {
                    out[count] = [x, y, z];
                    count += 1;
                }
            }
        }
    }
    (out, count)
}
