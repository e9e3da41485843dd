//! Exact line integrals of the basis reconstruction (column densities).
//!
//! **Model.** Inside one region the basis field is `B = Σ Ĥ v / Σ Ĥ` over the
//! cells of the region's bricks. Every tent `Ĥ` is a product of per-axis hat
//! functions whose kinks lie on the planes through the cell centres of its
//! level, `(k + ½)·w` in finest units (bricks are aligned to their level, so
//! all bricks of one level share these planes). Between two consecutive
//! crossings of such planes along a ray, every hat is linear in `t`, so the
//! numerator and the denominator are cubic polynomials in `t`.
//!
//! Where one brick alone reaches (the bulk of every brick) the tents factor
//! per axis, `Σ Ĥ v / Σ Ĥ` is a product of normalised hats and `B` is a cubic
//! on each piece: two-point Gauss–Legendre integrates it exactly. Where
//! bricks meet (level transitions, holes) `B` is a ratio of cubics;
//! four-point Gauss–Legendre on each piece is exact to ~1e-8 for the smooth
//! quotients this produces (checked against fine quadrature in the tests).
//!
//! **Domain.** Only the cells themselves are integrated: the ray is clipped
//! to each brick of a region (bricks never overlap, and every cell point lies
//! in exactly one region), so the half-cell margin where tents reach beyond
//! the data adds nothing and a constant field integrates to value × length
//! inside the cells, the same as nearest reconstruction.

use voxless_core::{Range1, Ray};

use crate::bricks::Brick;
use crate::volume::AmrVolume;

/// Gauss–Legendre nodes on [0, 1] and weights summing to 1.
const GL2: [(f64, f64); 2] = [
    (0.211_324_865_405_187_1, 0.5),
    (0.788_675_134_594_812_9, 0.5),
];
const GL4: [(f64, f64); 4] = [
    (0.069_431_844_202_973_7, 0.173_927_422_568_726_9),
    (0.330_009_478_207_571_9, 0.326_072_577_431_273_1),
    (0.669_990_521_792_428_1, 0.326_072_577_431_273_1),
    (0.930_568_155_797_026_3, 0.173_927_422_568_726_9),
];

/// `⌊x⌋` without a libm call (exact for |x| < 2⁶³).
#[inline]
fn floor(x: f64) -> i64 {
    let i = x as i64;
    i - (x < i as f64) as i64
}

/// `⌈x⌉`, likewise.
#[inline]
fn ceil(x: f64) -> i64 {
    let i = x as i64;
    i + (x > i as f64) as i64
}

/// The hats of one axis at lattice coordinate `tau` (cell `i`'s hat peaks at
/// `tau = i`): the two cells that may reach, with weights, zero for a cell
/// outside `0..n` (the normalisation then clamps to the face, per axis).
#[inline]
fn hats(tau: f64, n: i64) -> [(i64, f64); 2] {
    let i0 = floor(tau);
    let f = tau - i0 as f64;
    let inside = |i: i64| (0..n).contains(&i);
    [
        (i0, if inside(i0) { 1.0 - f } else { 0.0 }),
        (i0 + 1, if inside(i0 + 1) { f } else { 0.0 }),
    ]
}

/// The ray in finest units, `u(s) = o + d·s`, and what the pieces depend on.
pub(crate) struct Line {
    o: [f64; 3],
    d: [f64; 3],
    /// The one axis the ray moves along, when it is parallel to an axis.
    pub(crate) axis: Option<usize>,
}

/// One brick's tents along a ray: the ray's coordinate in the lattice of
/// the brick's cell centres is affine in the ray parameter,
/// `τ_a(s) = α_a + β_a·s`, so nothing per brick is recomputed per point.
#[derive(Clone, Copy, Debug, Default)]
struct Tents {
    alpha: [f64; 3],
    beta: [f64; 3],
    size: [i64; 3],
    offset: i64,
    stride: [i64; 3],
}

impl Tents {
    fn new(b: &Brick, line: &Line) -> Tents {
        // Bricks are one level, so the width is a power of two and scaling
        // by its inverse is exact.
        let inv = 1.0 / b.width() as f64;
        let (sx, sy) = (b.size[0] as i64, b.size[1] as i64);
        Tents {
            alpha: [0, 1, 2].map(|a| (line.o[a] - b.lower[a] as f64) * inv - 0.5),
            beta: [0, 1, 2].map(|a| line.d[a] * inv),
            size: b.size.map(|n| n as i64),
            offset: b.offset as i64,
            stride: [1, sx, sx * sy],
        }
    }

    /// `(Σ Ĥ v, Σ Ĥ)` of this brick's cells at `s`.
    #[inline]
    fn sums(&self, values: &[f32], s: f64) -> (f64, f64) {
        let h = [0, 1, 2].map(|a| hats(self.alpha[a] + self.beta[a] * s, self.size[a]));
        if h.iter().any(|x| x[0].1 <= 0.0 && x[1].1 <= 0.0) {
            return (0.0, 0.0);
        }
        let (mut sv, mut sw) = (0.0, 0.0);
        for (iz, wz) in h[2] {
            for (iy, wy) in h[1] {
                let wzy = wz * wy;
                if wzy <= 0.0 {
                    continue;
                }
                let row = self.offset + iz * self.stride[2] + iy * self.stride[1];
                for (ix, wx) in h[0] {
                    let w = wzy * wx;
                    if w > 0.0 {
                        sv += w * values[(row + ix) as usize] as f64;
                        sw += w;
                    }
                }
            }
        }
        (sv, sw)
    }
}

/// [`Tents`] for a ray parallel to axis `m`: the hats across the ray are
/// the same all along it, so the (at most four) columns of cells they
/// weight are found once and only the hats along `m` vary.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ColumnTents {
    alpha: f64,
    beta: f64,
    size: i64,
    stride: i64,
    /// Index of each column's cell 0 along `m`, and its weight.
    columns: [(i64, f64); 4],
    count: usize,
}

impl ColumnTents {
    fn new(t: &Tents, m: usize) -> ColumnTents {
        let (a1, a2) = ((m + 1) % 3, (m + 2) % 3);
        let h1 = hats(t.alpha[a1], t.size[a1]);
        let h2 = hats(t.alpha[a2], t.size[a2]);
        let mut c = ColumnTents {
            alpha: t.alpha[m],
            beta: t.beta[m],
            size: t.size[m],
            stride: t.stride[m],
            ..Default::default()
        };
        for (i2, w2) in h2 {
            for (i1, w1) in h1 {
                let w = w2 * w1;
                if w > 0.0 {
                    c.columns[c.count] = (t.offset + i1 * t.stride[a1] + i2 * t.stride[a2], w);
                    c.count += 1;
                }
            }
        }
        c
    }

    #[inline]
    fn sums(&self, values: &[f32], s: f64) -> (f64, f64) {
        let (mut sv, mut sw) = (0.0, 0.0);
        for (i, h) in hats(self.alpha + self.beta * s, self.size) {
            if h <= 0.0 {
                continue;
            }
            for &(base, w) in &self.columns[..self.count] {
                sv += h * w * values[(base + i * self.stride) as usize] as f64;
                sw += h * w;
            }
        }
        (sv, sw)
    }
}

/// `(Σ Ĥ v, Σ Ĥ)` over a region's bricks: B's numerator and denominator.
#[inline]
fn sums_of(tents: &[Tents], values: &[f32], s: f64) -> (f64, f64) {
    tents.iter().fold((0.0, 0.0), |(n, d), t| {
        let (a, b) = t.sums(values, s);
        (n + a, d + b)
    })
}

#[inline]
fn column_sums_of(tents: &[ColumnTents], values: &[f32], s: f64) -> (f64, f64) {
    tents.iter().fold((0.0, 0.0), |(n, d), t| {
        let (a, b) = t.sums(values, s);
        (n + a, d + b)
    })
}

/// `∫₀¹ N(s)/D(s) ds` for `N`, `D` linear between `(N0, D0)` and `(N1, D1)`
/// with `D > 0` (a piece where no tent reaches counts zero).
fn ratio_mean((n0, d0): (f64, f64), (n1, d1): (f64, f64)) -> f64 {
    if d0 <= 0.0 || d1 <= 0.0 {
        // A tent's edge: the field is defined on one side only; the ratio
        // is bounded, so the midpoint of the ends that exist is close.
        return match (d0 > 0.0, d1 > 0.0) {
            (true, false) => n0 / d0,
            (false, true) => n1 / d1,
            _ => 0.0,
        };
    }
    let (dn, dd) = (n1 - n0, d1 - d0);
    let r = dd / d0;
    if r.abs() < 1e-4 {
        // Nearly constant denominator: the series of the closed form
        // (whose log would lose digits), to O(r³).
        let m = n0 / d0;
        let b = dn / d0;
        return m + 0.5 * (b - m * r) - (b * r) / 3.0 + m * r * r / 3.0 + b * r * r / 4.0;
    }
    // ∫ (n0 + dn s)/(d0 + dd s) ds = dn/dd + (n0 − dn·d0/dd)·ln(d1/d0)/dd.
    dn / dd + (n0 - dn * d0 / dd) * (d1 / d0).ln() / dd
}

/// Sorts the cuts of a segment: runs that are already monotone (one per
/// axis and level), so insertion sort is close to linear.
fn sort_cuts(v: &mut [f64]) {
    for i in 1..v.len() {
        let x = v[i];
        let mut j = i;
        while j > 0 && v[j - 1] > x {
            v[j] = v[j - 1];
            j -= 1;
        }
        v[j] = x;
    }
}

/// The levels (as widths in finest units) among `bricks`, finest eight at
/// most (extra planes only refine the pieces).
fn widths(volume: &AmrVolume, bricks: &[u32]) -> ([i32; 8], usize) {
    let (mut ws, mut nw) = ([0i32; 8], 0);
    for &b in bricks {
        let w = volume.bricks()[b as usize].width();
        if !ws[..nw].contains(&w) {
            if nw < ws.len() {
                ws[nw] = w;
                nw += 1;
            } else if let Some(c) = ws.iter_mut().max().filter(|c| w < **c) {
                *c = w;
            }
        }
    }
    (ws, nw)
}

/// The kinks of the tents of widths `ws` that the ray `o + d·s` crosses
/// along `ax` strictly inside `(a, z)`, appended to `cuts`.
fn push_kinks(cuts: &mut Vec<f64>, ws: &[i32], o: f64, d: f64, a: f64, z: f64) {
    for &w in ws {
        let w = w as f64;
        let (ua, uz) = (o + d * a, o + d * z);
        let (umin, umax) = (ua.min(uz), ua.max(uz));
        for k in ceil(umin / w - 0.5)..=floor(umax / w - 0.5) {
            let tc = ((k as f64 + 0.5) * w - o) / d;
            if tc > a && tc < z {
                cuts.push(tc);
            }
        }
    }
}

/// A region's pieces along rays parallel to one axis `m` that share their
/// position and direction along `m` and their range `t`: which bricks'
/// cells the region holds there, and where the ray crosses kinks inside
/// each. Everything here is the same for all such rays (the parallel rays
/// of a projection down an axis), so a whole-image projection finds it once
/// per region ([`crate::project`]).
#[derive(Clone, Debug, Default)]
pub(crate) struct AxisPieces {
    /// Per brick (index into the volume's bricks): its segment's cuts,
    /// `cuts[start..end]`, ends included.
    segments: Vec<(u32, u32, u32)>,
    cuts: Vec<f64>,
}

/// Per-thread buffers, reused from ray to ray.
#[derive(Default)]
pub(crate) struct Scratch {
    cuts: Vec<f64>,
    tents: Vec<Tents>,
    columns: Vec<ColumnTents>,
    pieces: AxisPieces,
}

thread_local! {
    static SCRATCH: std::cell::Cell<Scratch> = const {
        std::cell::Cell::new(Scratch {
            cuts: Vec::new(),
            tents: Vec::new(),
            columns: Vec::new(),
            pieces: AxisPieces { segments: Vec::new(), cuts: Vec::new() },
        })
    };
}

impl Line {
    /// `ray` in the finest units of `volume`.
    pub(crate) fn new(volume: &AmrVolume, ray: &Ray) -> Line {
        let (origin, h) = (volume.origin(), volume.cell_size() as f64);
        let d = [0, 1, 2].map(|a| ray.dir[a] as f64 / h);
        Line {
            o: [0, 1, 2].map(|a| (ray.origin[a] as f64 - origin[a] as f64) / h),
            d,
            axis: match d.map(|x| x != 0.0) {
                [true, false, false] => Some(0),
                [false, true, false] => Some(1),
                [false, false, true] => Some(2),
                _ => None,
            },
        }
    }
}

impl AmrVolume {
    /// `∫ B dt` along `ray` over `t`, integrating the basis reconstruction of
    /// the opacity field exactly inside the cells (see the module docs).
    pub(crate) fn basis_line_integral(&self, ray: &Ray, t: Range1) -> f64 {
        let line = Line::new(self, ray);
        // Taken out of the thread-local (not borrowed) for the walk.
        let mut scratch = SCRATCH.take();
        let mut sum = 0.0f64;
        // Regions in any order would do for a sum; the walk of the region
        // k-d tree finds them without the BVH's overlapping siblings (and
        // puts a ray lying in a cut plane on the plane's upper side, as the
        // half-open clips below do).
        self.region_tree().walk(ray, t, None, |r, _| {
            let r = r as usize;
            sum += match line.axis {
                Some(m) => {
                    let s = &mut scratch;
                    self.axis_pieces(&line, m, t, r, &mut s.pieces);
                    self.axis_region_integral(ray, &line, r, &s.pieces, &mut s.columns)
                }
                None => self.oblique_region_integral(ray, &line, t, r, &mut scratch),
            };
            true
        });
        SCRATCH.set(scratch);
        sum
    }

    /// Region `r`'s [`AxisPieces`] for rays like `line` (parallel to axis
    /// `m`) over `t`.
    pub(crate) fn axis_pieces(
        &self,
        line: &Line,
        m: usize,
        t: Range1,
        r: usize,
        out: &mut AxisPieces,
    ) {
        out.segments.clear();
        out.cuts.clear();
        let region = &self.regions()[r];
        let bricks = self.region_bricks(r);
        let (ws, nw) = widths(self, bricks);
        let (o, d) = (line.o[m], line.d[m]);
        for &b in bricks {
            let brick = &self.bricks()[b as usize];
            // The ray inside region ∩ brick cells along m, in f64 from the
            // exact integer boxes; region ∩ brick must not be empty across
            // m either (the side a ray lies on there is decided per ray).
            let (blo, bhi) = (brick.lower, brick.upper());
            let lo = |ax: usize| (blo[ax] as f64).max(region.lo[ax] as f64 * 0.5);
            let hi = |ax: usize| (bhi[ax] as f64).min(region.hi[ax] as f64 * 0.5);
            if (0..3).any(|ax| lo(ax) >= hi(ax)) {
                continue;
            }
            let (ta, tb) = ((lo(m) - o) / d, (hi(m) - o) / d);
            let a = (t.lo as f64).max(ta.min(tb));
            let z = (t.hi as f64).min(ta.max(tb));
            if z <= a {
                continue;
            }
            let start = out.cuts.len();
            out.cuts.push(a);
            push_kinks(&mut out.cuts, &ws[..nw], o, d, a, z);
            out.cuts.push(z);
            sort_cuts(&mut out.cuts[start..]);
            out.segments.push((b, start as u32, out.cuts.len() as u32));
        }
    }

    /// `∫ B dt` in region `r` along `ray`, parallel to an axis, from the
    /// region's `pieces` for it.
    pub(crate) fn axis_region_integral(
        &self,
        ray: &Ray,
        line: &Line,
        r: usize,
        pieces: &AxisPieces,
        columns: &mut Vec<ColumnTents>,
    ) -> f64 {
        if pieces.segments.is_empty() {
            return 0.0;
        }
        let Some(m) = line.axis else {
            return 0.0;
        };
        let (origin, h) = (self.origin(), self.cell_size());
        let values = self.field_values(self.settings().field);
        let region = &self.regions()[r];
        let bricks = self.region_bricks(r);
        columns.clear();
        for &b in bricks {
            let c = ColumnTents::new(&Tents::new(&self.bricks()[b as usize], line), m);
            // A brick whose hats miss the ray adds nothing.
            if c.count > 0 {
                columns.push(c);
            }
        }
        // One brick: the tents factor per axis, so B is linear along the
        // ray on each piece; more bricks make it a ratio of linear pieces.
        let polynomial = bricks.len() == 1;
        let mut sum = 0.0;
        for &(b, start, end) in &pieces.segments {
            let brick = &self.bricks()[b as usize];
            // A ray in the plane of a face across the ray: decide its side
            // in f32 world coordinates, as the tree did (in units the
            // rounding could fall on the other side). Faces are half-open
            // like the cells, so a ray in a face between two bricks is
            // counted once.
            let inside = (0..3).filter(|&ax| ax != m).all(|ax| {
                let lo = (brick.lower[ax] as f64).max(region.lo[ax] as f64 * 0.5);
                let hi = (brick.upper()[ax] as f64).min(region.hi[ax] as f64 * 0.5);
                let world = |u: f64| origin[ax] + u as f32 * h;
                ray.origin[ax] >= world(lo) && ray.origin[ax] < world(hi)
            });
            if !inside {
                continue;
            }
            let cuts = &pieces.cuts[start as usize..end as usize];
            let pieces = cuts.windows(2).map(|p| (p[0], p[1] - p[0]));
            if polynomial {
                // Linear on each piece: the midpoint rule is exact.
                for (s, len) in pieces {
                    let (n, den) = column_sums_of(columns, values, s + 0.5 * len);
                    if den > 0.0 {
                        sum += len * n / den;
                    }
                }
            } else {
                // Numerator Σ Ĥ v and denominator Σ Ĥ are both linear on a
                // piece, so the integral of their ratio is exact in closed
                // form from their values at the piece's ends (shared
                // between neighbouring pieces).
                let mut prev = column_sums_of(columns, values, cuts[0]);
                for (s, len) in pieces {
                    let next = column_sums_of(columns, values, s + len);
                    sum += len * ratio_mean(prev, next);
                    prev = next;
                }
            }
        }
        sum
    }

    /// `∫ B dt` in region `r` along an oblique `ray` over `t`.
    fn oblique_region_integral(
        &self,
        ray: &Ray,
        line: &Line,
        t: Range1,
        r: usize,
        scratch: &mut Scratch,
    ) -> f64 {
        let (origin, h) = (self.origin(), self.cell_size() as f64);
        let (o, d) = (line.o, line.d);
        let values = self.field_values(self.settings().field);
        let region = &self.regions()[r];
        let bricks = self.region_bricks(r);
        let (ws, nw) = widths(self, bricks);
        scratch.tents.clear();
        for &b in bricks {
            scratch
                .tents
                .push(Tents::new(&self.bricks()[b as usize], line));
        }
        let (t0, t1) = (t.lo as f64, t.hi as f64);
        // One brick: the tents factor per axis, so B is at most cubic on a
        // piece, two Gauss points are exact. Several bricks (level
        // transitions, holes): a ratio of cubics; four Gauss points are
        // exact to ~1e-8 on these smooth quotients.
        let nodes: &[(f64, f64)] = if bricks.len() == 1 { &GL2 } else { &GL4 };
        let mut sum = 0.0;
        for &b in bricks {
            let brick = &self.bricks()[b as usize];
            // The ray inside region ∩ brick cells, in f64 from the exact
            // integer boxes (the f32 walk of the tree only finds them),
            // half-open like the cells.
            let (blo, bhi) = (brick.lower, brick.upper());
            let (mut a, mut z) = (t0, t1);
            for ax in 0..3 {
                let lo = (blo[ax] as f64).max(region.lo[ax] as f64 * 0.5);
                let hi = (bhi[ax] as f64).min(region.hi[ax] as f64 * 0.5);
                if lo >= hi {
                    z = f64::NEG_INFINITY;
                    break;
                }
                if d[ax] == 0.0 {
                    // In the plane of a face: the side in f32 world
                    // coordinates, as the tree decided it.
                    let world = |u: f64| origin[ax] + u as f32 * h as f32;
                    if !(ray.origin[ax] >= world(lo) && ray.origin[ax] < world(hi)) {
                        z = f64::NEG_INFINITY;
                        break;
                    }
                    continue;
                }
                let (ta, tb) = ((lo - o[ax]) / d[ax], (hi - o[ax]) / d[ax]);
                a = a.max(ta.min(tb));
                z = z.min(ta.max(tb));
            }
            if z <= a {
                continue;
            }
            // Kinks of every level's tents inside (a, z).
            let cuts = &mut scratch.cuts;
            cuts.clear();
            cuts.push(a);
            for ax in (0..3).filter(|&ax| d[ax] != 0.0) {
                push_kinks(cuts, &ws[..nw], o[ax], d[ax], a, z);
            }
            cuts.push(z);
            sort_cuts(cuts);
            for p in cuts.windows(2) {
                let (s, len) = (p[0], p[1] - p[0]);
                for &(x, wt) in nodes {
                    let (n, den) = sums_of(&scratch.tents, values, s + x * len);
                    if den > 0.0 {
                        sum += wt * len * n / den;
                    }
                }
            }
        }
        sum
    }
}

#[cfg(test)]
mod tests {
    //! Known answers: fine quadrature of the reconstructed field over each
    //! cell chord (brute force over all cells), constant fields, the domain.
    use crate::tests::{cells_with, smooth, synthetic};
    use crate::{AmrCells, AmrSettings, AmrVolume};
    use voxless_core::SmallRng as Lcg;
    use voxless_core::{Aabb, Range1, Ray, Vec3, Volume};

    /// `∫ sample dt` over the chords of every cell the ray crosses, each by
    /// the composite midpoint rule with 4096 points (second order across the
    /// field's kinks, so converged far below 1e-6; unlike Simpson it never
    /// samples a chord's end, which rounding may put just outside the data).
    fn quadrature(vol: &AmrVolume, input: &AmrCells, ray: &Ray) -> f64 {
        let mut sum = 0.0;
        for c in &input.cells {
            let Some((ta, tb)) = chord(input, c, ray) else {
                continue;
            };
            let f = |s: f64| {
                let p = Vec3::new(
                    (ray.origin.x as f64 + ray.dir.x as f64 * s) as f32,
                    (ray.origin.y as f64 + ray.dir.y as f64 * s) as f32,
                    (ray.origin.z as f64 + ray.dir.z as f64 * s) as f32,
                );
                vol.sample(p).map_or(0.0, |x| x.value as f64)
            };
            let (a, n) = (ta, 4096);
            let h = (tb - a) / n as f64;
            sum += (0..n).map(|k| f(a + (k as f64 + 0.5) * h)).sum::<f64>() * h;
        }
        sum
    }

    /// The ray's parameter range inside cell `c`, in f64; cells are
    /// half-open so a ray in a face between two cells meets one of them.
    fn chord(input: &AmrCells, c: &[i32; 4], ray: &Ray) -> Option<(f64, f64)> {
        let w = (1i64 << c[3]) as f64;
        let h = input.cell_size as f64;
        let (mut a, mut z) = (f64::NEG_INFINITY, f64::INFINITY);
        for ax in 0..3 {
            let lo = input.origin[ax] as f64 + c[ax] as f64 * h;
            let hi = lo + w * h;
            let (o, d) = (ray.origin[ax] as f64, ray.dir[ax] as f64);
            if d == 0.0 {
                // The volume's convention: faces in f32 world coordinates.
                let world = |k: i32| input.origin[ax] + k as f32 * input.cell_size;
                let (wlo, whi) = (world(c[ax]), world(c[ax] + (1 << c[3])));
                if !(ray.origin[ax] >= wlo && ray.origin[ax] < whi) {
                    return None;
                }
                continue;
            }
            let (ta, tb) = ((lo - o) / d, (hi - o) / d);
            a = a.max(ta.min(tb));
            z = z.min(ta.max(tb));
        }
        (z > a).then_some((a, z))
    }

    fn random_ray(rng: &mut Lcg, b: &Aabb) -> Ray {
        let o = b.center()
            + Vec3::new(rng.f() - 0.5, rng.f() - 0.5, rng.f() - 0.5) * (3.0 * b.diagonal());
        let target = b.min + b.extent().mul_elem(Vec3::new(rng.f(), rng.f(), rng.f()));
        Ray::new(o, (target - o).normalized())
    }

    #[test]
    fn basis_line_integral_equals_fine_quadrature_of_samples() {
        // Levels 0–3 with holes: single-level bulk, level transitions, holes.
        let input = cells_with(synthetic(21, true), smooth);
        let vol = AmrVolume::new(input.clone(), AmrSettings::default()).unwrap();
        let b = vol.bounds();
        let all = Range1::new(f32::NEG_INFINITY, f32::INFINITY);
        let mut rng = Lcg(22);
        let mut rays: Vec<Ray> = (0..40).map(|_| random_ray(&mut rng, &b)).collect();
        // Axis-aligned rays along cell faces and through cell centres, where
        // the kinks of a whole plane of tents meet the ray.
        let c = b.center();
        for (dx, dy) in [(0.0, 0.0), (0.05, 0.0), (0.05, 0.05), (0.4, 0.8)] {
            rays.push(Ray::new(
                Vec3::new(c.x + dx, c.y + dy, b.min.z - 1.0),
                Vec3::new(0.0, 0.0, 1.0),
            ));
        }
        let mut worst = 0.0f64;
        for ray in &rays {
            let got = vol.line_integral(ray, all);
            let want = quadrature(&vol, &input, ray);
            let rel = (got - want).abs() / want.abs().max(1e-3);
            worst = worst.max(rel);
            assert!(
                rel <= 1e-5,
                "exact {got} vs quadrature {want} ({rel:.1e}) along {ray:?}"
            );
        }
        eprintln!("basis line integral vs quadrature: worst relative {worst:.1e}");
    }

    #[test]
    fn constant_field_integrates_to_value_times_length_in_the_cells() {
        let input = cells_with(synthetic(23, true), |_| 2.5);
        let vol = AmrVolume::new(input.clone(), AmrSettings::default()).unwrap();
        let mut rng = Lcg(24);
        let all = Range1::new(f32::NEG_INFINITY, f32::INFINITY);
        for _ in 0..100 {
            let ray = random_ray(&mut rng, &vol.bounds());
            let mut length = 0.0f64;
            for c in &input.cells {
                let w = (1 << c[3]) as f32;
                let lo = input.origin
                    + Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) * input.cell_size;
                let b = Aabb::new(lo, lo + Vec3::splat(w * input.cell_size));
                let t = b.clip_ray(&ray, all);
                if !t.is_empty() {
                    length += t.span() as f64;
                }
            }
            let got = vol.line_integral(&ray, all);
            assert!(
                (got - 2.5 * length).abs() <= 1e-5 * (2.5 * length).max(1e-3),
                "{got} vs {}",
                2.5 * length
            );
        }
    }

    #[test]
    fn bounds_are_the_cells_domain() {
        let input = cells_with(synthetic(25, false), smooth);
        let vol = AmrVolume::new(input.clone(), AmrSettings::default()).unwrap();
        // synthetic() covers [0, 64)³ finest units.
        let want = Aabb::new(
            input.origin,
            input.origin + Vec3::splat(64.0 * input.cell_size),
        );
        let got = vol.bounds();
        for a in 0..3 {
            assert!(
                (got.min[a] - want.min[a]).abs() < 1e-5 && (got.max[a] - want.max[a]).abs() < 1e-5,
                "{got:?} vs {want:?}"
            );
        }
        // No samples in the tents' margin outside the cells.
        let outside = input.origin - Vec3::splat(0.25 * input.cell_size);
        assert!(vol.sample(outside).is_none());
    }
}
