//! Pixel-area projections: each tet's column density integrated exactly
//! over the part of every pixel's square it covers.
//!
//! **Why.** A tet's column `ρ·chord(u, v)` is piecewise linear over its
//! projected outline (a triangle or a quadrilateral, with creases along the
//! projected edges). Sampling it at pixel centres misses or doubles part of
//! each boundary pixel, so the projected mass drifts with the resolution;
//! integrating it over pixel squares makes `Σ pixels × pixel area` the mass
//! in view at every resolution.
//!
//! **How.** In screen coordinates `(u, v)` (pixels; pixel `(i, j)` is the
//! square `[i, i+1] × [j, j+1]` of its tile) and depth `t` along the rays,
//! the chord is `t_back − t_front`: the projected back faces tile the
//! outline, and so do the front faces, each carrying its plane `t_F(u, v)`.
//! With every face walked along its boundary in outward orientation,
//! `∫ chord dA = −Σ_faces ∮-sum of the face's plane`, where an edge `P → Q`
//! carrying a linear `g` adds, for every row it crosses, `∫∫ g` over the
//! part of the row to the right of the edge (signed by the edge's
//! direction in v) — the signed-area accumulation of exact polygon
//! rasterisers, with a linear integrand:
//!
//! - the pixel the edge passes through gets `∫∫` from the edge to the
//!   pixel's right side (a quadratic in v along the edge: Simpson's rule is
//!   exact);
//! - every pixel further right gets `Δv·(a + c·v̄) + b·Δv·(k + ½)`, added as
//!   two running sums per row (`d0`, `d1`) resolved once per tile.
//!
//! Each tet edge borders two faces whose boundaries run along it in
//! opposite directions, so the six edges are walked once each with the
//! difference of the two faces' planes. Rows and columns outside the tile
//! clip the walk (the part left of the tile adds to the whole row).
//!
//! **Box.** The periodic images fill the box exactly, so only `tet ∩ box`
//! may be projected: a tet that crosses a face of the box (or the plane of
//! the eye) is cut into at most three tets per plane (the classic
//! one/two/three-vertex cases) and the pieces inside are projected.

use voxless_core::{Camera, Projection, Vec3};

use crate::mesh::{KUHN, Tet};
use crate::ortho::OrthoMap;

/// A half-space `n·x ≤ c` (world, f64).
#[derive(Clone, Copy, Debug)]
struct Plane {
    n: [f64; 3],
    c: f64,
}

impl Plane {
    #[inline(always)]
    fn dist(&self, p: [f64; 3]) -> f64 {
        self.n[0] * p[0] + self.n[1] * p[1] + self.n[2] * p[2] - self.c
    }
}

/// The planes a view's tets must be cut at: the faces of the box `[0, L)³`
/// whose outside the image sees, and the plane of the eye when the box
/// reaches behind it.
#[derive(Clone, Debug)]
pub(crate) struct BoxClip {
    planes: Vec<Plane>,
}

impl BoxClip {
    pub fn new(camera: &Camera, l: f32) -> BoxClip {
        let l = l as f64;
        let [eye, right, up, fwd] = camera.basis_f64();
        let (hw, hh) = match camera.projection {
            Projection::Orthographic {
                half_width,
                half_height,
            } => (half_width as f64, half_height as f64),
            Projection::Perspective { .. } => (f64::INFINITY, f64::INFINITY),
        };
        // The image's corners on the plane of the eye: a face parallel to
        // the rays whose outside holds none of them cuts nothing the image
        // shows.
        let corners: Vec<[f64; 3]> = [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)]
            .iter()
            .map(|&(sx, sy)| std::array::from_fn(|a| eye[a] + right[a] * sx * hw + up[a] * sy * hh))
            .collect();
        let mut planes = Vec::new();
        for a in 0..3 {
            for (sign, c) in [(-1.0, 0.0), (1.0, l)] {
                let mut n = [0.0; 3];
                n[a] = sign;
                let plane = Plane { n, c: sign * c };
                let parallel = fwd[a] == 0.0;
                if parallel && corners.iter().all(|&p| plane.dist(p) <= 0.0) {
                    continue;
                }
                planes.push(plane);
            }
        }
        // The eye's plane: t ≥ 0, i.e. −fwd·x ≤ −fwd·eye.
        let eye_plane = Plane {
            n: fwd.map(|v| -v),
            c: -(fwd[0] * eye[0] + fwd[1] * eye[1] + fwd[2] * eye[2]),
        };
        let box_corners = (0..8).map(|i| {
            [
                (i & 1) as f64 * l,
                ((i >> 1) & 1) as f64 * l,
                (i >> 2) as f64 * l,
            ]
        });
        if box_corners.into_iter().any(|p| eye_plane.dist(p) > 0.0) {
            planes.push(eye_plane);
        }
        BoxClip { planes }
    }
}

/// One tile's pixel-area sums.
pub(crate) struct AreaTile {
    w: usize,
    h: usize,
    /// Per pixel (row-major), the integrals of the pixels edges pass through.
    acc: Vec<f64>,
    /// Per row, running sums (w + 1 per row) of the constant and the
    /// per-column part of what edges add to every pixel to their right.
    d0: Vec<f64>,
    d1: Vec<f64>,
}

/// Vertices in screen space: tile-local pixels `(u, v)`, depth `t`
/// relative to the tet.
type Uvt = [f64; 3];

impl AreaTile {
    pub fn new(w: usize, h: usize) -> AreaTile {
        AreaTile {
            w,
            h,
            acc: vec![0.0; w * h],
            d0: vec![0.0; (w + 1) * h],
            d1: vec![0.0; (w + 1) * h],
        }
    }

    /// The pixel integrals, row-major: the running sums resolved.
    pub fn finish(mut self) -> Vec<f64> {
        let w = self.w;
        for j in 0..self.h {
            let (mut s0, mut s1) = (0.0, 0.0);
            for k in 0..w {
                s0 += self.d0[j * (w + 1) + k];
                s1 += self.d1[j * (w + 1) + k];
                self.acc[j * w + k] += s0 + s1 * (k as f64 + 0.5);
            }
        }
        self.acc
    }

    /// Adds `rho × ∫ chord` of `tet` over each pixel of the tile, cut at
    /// the planes of `clip` it crosses. `ref_x`, `ref_y`: the tile's first
    /// pixel.
    pub fn tet(&mut self, map: &OrthoMap, clip: &BoxClip, tet: &Tet, (ref_x, ref_y): (u32, u32)) {
        let w = tet.v.map(|p| [p.x as f64, p.y as f64, p.z as f64]);
        // The planes the tet crosses; none: the whole tet.
        let mut cut = [0usize; 8];
        let mut cuts = 0;
        for (k, plane) in clip.planes.iter().enumerate() {
            let d = w.map(|p| plane.dist(p));
            if d.iter().all(|&x| x > 0.0) {
                return;
            }
            if d.iter().any(|&x| x > 0.0) {
                cut[cuts] = k;
                cuts += 1;
            }
        }
        let rho = tet.density as f64;
        if cuts == 0 {
            self.solid(map, w, rho, (ref_x, ref_y));
            return;
        }
        let mut pieces = vec![w];
        for &k in &cut[..cuts] {
            let plane = clip.planes[k];
            let mut next = Vec::with_capacity(pieces.len() * 3);
            for p in &pieces {
                split(p, plane, &mut next);
            }
            pieces = next;
        }
        for p in pieces {
            self.solid(map, p, rho, (ref_x, ref_y));
        }
    }

    /// [`AreaTile::tet`] of a tet inside every plane, world vertices `w`.
    fn solid(&mut self, map: &OrthoMap, w: [[f64; 3]; 4], rho: f64, reference: (u32, u32)) {
        let s = w.map(|p| map.uvt(p, reference));
        // Depth relative to vertex 0: the planes' offsets cancel between
        // front and back faces, so keep them small.
        let s = s.map(|p| [p[0], p[1], p[2] - s[0][2]]);
        let Some(det) = solid_det(&s) else {
            return;
        };
        if let Some(at) = self.one_pixel(&s) {
            self.acc[at] += rho * det.abs() / 6.0;
            return;
        }
        let terms = edge_terms(&s, det, rho);
        for (e, &(from, to)) in TET_EDGES.iter().enumerate() {
            self.edge([s[from][0], s[from][1]], [s[to][0], s[to][1]], terms[e]);
        }
    }

    /// The pixel of the tile (its index) that holds every point of `s`,
    /// if one does: a column inside one pixel integrates to its mass there,
    /// with no edge to walk.
    #[inline]
    fn one_pixel(&self, s: &[Uvt]) -> Option<usize> {
        let (mut lo, mut hi) = ([s[0][0], s[0][1]], [s[0][0], s[0][1]]);
        for p in &s[1..] {
            for a in 0..2 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        if !(lo[0] >= 0.0 && lo[1] >= 0.0 && hi[0] < self.w as f64 && hi[1] < self.h as f64) {
            return None;
        }
        let (i, j) = (lo[0] as usize, lo[1] as usize);
        (hi[0] < (i + 1) as f64 && hi[1] < (j + 1) as f64).then_some(j * self.w + i)
    }

    /// The tets of one Lagrangian cell (`corners` at their image, `tets`
    /// with their index in [`KUHN`]), as [`AreaTile::tet`] each, but each
    /// of the cell's 19 edges walked once for all the tets that share it
    /// (the main diagonal is in all six): their terms add up. Tets that a
    /// plane of `clip` cuts go alone.
    pub fn cell(
        &mut self,
        map: &OrthoMap,
        clip: &BoxClip,
        (corners, tets): (&[Vec3; 8], &[(usize, Tet)]),
        reference: (u32, u32),
    ) {
        let w = corners.map(|p| [p.x as f64, p.y as f64, p.z as f64]);
        // Per plane, whether it cuts or misses the cell (else the cell is
        // inside it).
        let mut whole = true;
        for plane in &clip.planes {
            let d = w.map(|p| plane.dist(p));
            if d.iter().any(|&x| x > 0.0) {
                whole = false;
            }
        }
        if !whole {
            for (_, tet) in tets {
                self.tet(map, clip, tet, reference);
            }
            return;
        }
        let s = w.map(|p| map.uvt(p, reference));
        let s = s.map(|p| [p[0], p[1], p[2] - s[0][2]]);
        if let Some(at) = self.one_pixel(&s) {
            for &(index, ref tet) in tets {
                if let Some(det) = solid_det(&KUHN[index].map(|c| s[c])) {
                    self.acc[at] += tet.density as f64 * det.abs() / 6.0;
                }
            }
            return;
        }
        let mut table = [[0.0f64; 3]; 19];
        for &(index, ref tet) in tets {
            let k = KUHN[index];
            let v = k.map(|c| s[c]);
            let Some(det) = solid_det(&v) else {
                continue;
            };
            let terms = edge_terms(&v, det, tet.density as f64);
            for (e, &(from, to)) in TET_EDGES.iter().enumerate() {
                let slot = &mut table[PAIR[k[from]][k[to]] as usize];
                for x in 0..3 {
                    slot[x] += terms[e][x];
                }
            }
        }
        for (g, &(a, b)) in table.iter().zip(&PAIRS) {
            if *g != [0.0; 3] {
                self.edge([s[a][0], s[a][1]], [s[b][0], s[b][1]], *g);
            }
        }
    }

    /// Adds, for the directed segment `p → q` carrying the linear
    /// `g(u, v) = g₀ + g₁·u + g₂·v`, `∫∫ g` over the part of each row to the
    /// right of it, signed by its direction in v (see the module docs).
    fn edge(&mut self, p: [f64; 2], q: [f64; 2], g: [f64; 3]) {
        // Walk downwards (increasing v); upwards is the negative.
        let (p, q, g) = if p[1] <= q[1] {
            (p, q, g)
        } else {
            (q, p, g.map(|x| -x))
        };
        if !(q[1] > p[1]) || q[1] <= 0.0 || p[1] >= self.h as f64 {
            return;
        }
        let slope = (q[0] - p[0]) / (q[1] - p[1]);
        let u_at = |v: f64| {
            if v == p[1] {
                p[0]
            } else if v == q[1] {
                q[0]
            } else {
                p[0] + (v - p[1]) * slope
            }
        };
        let (v_lo, v_hi) = (p[1].max(0.0), q[1].min(self.h as f64));
        // v_lo ≥ 0: truncation is the floor (no library call).
        let mut j = v_lo as usize;
        let mut v0 = v_lo;
        while v0 < v_hi && j < self.h {
            let v1 = ((j + 1) as f64).min(v_hi);
            self.row(j, [u_at(v0), v0], [u_at(v1), v1], g);
            v0 = v1;
            j += 1;
        }
    }

    /// [`AreaTile::edge`] within row `j`: `p → q` with `p.v < q.v`, both
    /// in `[j, j + 1]`.
    fn row(&mut self, j: usize, p: [f64; 2], q: [f64; 2], g: [f64; 3]) {
        let wf = self.w as f64;
        let dvdu = (q[1] - p[1]) / (q[0] - p[0]);
        let at = |u: f64| -> [f64; 2] {
            // The segment's point at u (between p and q).
            if u == p[0] {
                p
            } else if u == q[0] {
                q
            } else {
                [u, p[1] + (u - p[0]) * dvdu]
            }
        };
        let (u_min, u_max) = (p[0].min(q[0]), p[0].max(q[0]));
        // The part left of the tile (or on its left side) adds to the whole
        // row; the part right of it adds nothing to the tile.
        if u_max <= 0.0 {
            self.carry(j, 0, p, q, g);
            return;
        }
        if u_min >= wf {
            return;
        }
        if u_min < 0.0 {
            let m = at(0.0);
            let (a, b) = if p[0] < 0.0 { (p, m) } else { (m, q) };
            self.carry(j, 0, a, b, g);
        }
        // The part inside the tile, column by column (right of the tile
        // adds nothing to it).
        if u_min == u_max {
            // Vertical: one column (on a column's left side, that column).
            // 0 < u < W: truncation is the floor.
            let i = u_min as usize;
            self.piece(i, j, p, q, g);
            return;
        }
        let (lo, hi) = (u_min.max(0.0), u_max.min(wf));
        // 0 ≤ lo < hi ≤ W: truncation is the floor; a piece of no width at
        // the end (hi on a column's side) is skipped below.
        let (first, last) = (lo as usize, (hi as usize).min(self.w - 1));
        let forward = q[0] > p[0];
        for i in first..=last {
            let (c0, c1) = ((i as f64).max(lo), ((i + 1) as f64).min(hi));
            if !(c1 > c0) {
                continue;
            }
            let (a, b) = if forward {
                (at(c0), at(c1))
            } else {
                (at(c1), at(c0))
            };
            self.piece(i, j, a, b, g);
        }
    }

    /// The piece `a → b` (`a.v ≤ b.v`) of an edge in column `i` of row `j`:
    /// `∫∫ g` from the piece to the column's right side into pixel `(i,
    /// j)`, and what it adds to the pixels further right (see
    /// [`AreaTile::carry`]).
    #[inline(always)]
    fn piece(&mut self, i: usize, j: usize, a: [f64; 2], b: [f64; 2], g: [f64; 3]) {
        let dv = b[1] - a[1];
        if dv == 0.0 {
            return;
        }
        let vm = 0.5 * (a[1] + b[1]);
        // Relative to the column's left side, so that g is evaluated near
        // where it is integrated: g = g0' + g1·u' + g2·v, u' = u − i.
        let fi = i as f64;
        let g0 = g[0] + g[1] * fi;
        let (ua, ub) = (a[0] - fi, b[0] - fi);
        // ∫ from u' to 1 of g du' = G(1, v) − G(u', v), G = g0'u' + g1u'²/2
        // + g2·v·u'; along the piece G(u'(v), v) is quadratic in v.
        let big = |u: f64, v: f64| u * (g0 + 0.5 * g[1] * u + g[2] * v);
        let whole = dv * (g0 + 0.5 * g[1] + g[2] * vm);
        let under = dv / 6.0 * (big(ua, a[1]) + 4.0 * big(0.5 * (ua + ub), vm) + big(ub, b[1]));
        let w = self.w;
        self.acc[j * w + i] += whole - under;
        if i + 1 < w {
            let at = j * (w + 1) + i + 1;
            self.d0[at] += dv * (g[0] + g[2] * vm);
            self.d1[at] += dv * g[1];
        }
    }

    /// What the piece `a → b` adds to every pixel of row `j` from column
    /// `from` on: `Δv·(g0 + g2·v̄) + g1·Δv·(k + ½)` at column k.
    #[inline]
    fn carry(&mut self, j: usize, from: usize, a: [f64; 2], b: [f64; 2], g: [f64; 3]) {
        if from >= self.w {
            return;
        }
        let dv = b[1] - a[1];
        let vm = 0.5 * (a[1] + b[1]);
        let at = j * (self.w + 1) + from;
        self.d0[at] += dv * (g[0] + g[2] * vm);
        self.d1[at] += dv * g[1];
    }
}

/// A tet's edges `(from, to)`, in the order of [`edge_terms`].
const TET_EDGES: [(usize, usize); 6] = [(1, 2), (2, 3), (1, 3), (0, 3), (0, 2), (0, 1)];

/// The 19 edges of the Kuhn decomposition of a cell, as corner pairs `(a,
/// b)` with `a < b`: 12 cube edges, 6 face diagonals, the main diagonal.
const PAIRS: [(usize, usize); 19] = {
    let mut out = [(0, 0); 19];
    let mut n = 0;
    let mut a = 0;
    while a < 8 {
        let mut b = a + 1;
        while b < 8 {
            // A Kuhn edge joins corners whose index bits are nested (b's
            // set bits include a's): that is every edge of the six paths
            // 0 → … → 7.
            if a & b == a {
                out[n] = (a, b);
                n += 1;
            }
            b += 1;
        }
        a += 1;
    }
    out
};

/// The index in [`PAIRS`] of corner pair `(a, b)`, `a < b` (255: not an
/// edge).
const PAIR: [[u8; 8]; 8] = {
    let mut out = [[255u8; 8]; 8];
    let mut n = 0;
    while n < 19 {
        out[PAIRS[n].0][PAIRS[n].1] = n as u8;
        n += 1;
    }
    out
};

/// The determinant (6 × the signed volume) of a tet with vertices `s` in
/// screen space; `None` for a flat one, which has no volume and no outward
/// side to orient its faces by.
#[inline]
fn solid_det(s: &[Uvt; 4]) -> Option<f64> {
    let sub = |a: Uvt, b: Uvt| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let (e1, e2, e3) = (sub(s[1], s[0]), sub(s[2], s[0]), sub(s[3], s[0]));
    let det = e1[0] * (e2[1] * e3[2] - e2[2] * e3[1]) - e1[1] * (e2[0] * e3[2] - e2[2] * e3[0])
        + e1[2] * (e2[0] * e3[1] - e2[1] * e3[0]);
    let scale = [e1, e2, e3]
        .iter()
        .map(|e| e[0].abs() + e[1].abs() + e[2].abs())
        .fold(0.0, f64::max);
    (det.abs() > 1e-12 * scale * scale * scale).then_some(det)
}

/// A tet's six edge terms (in [`TET_EDGES`] order: what to walk each edge
/// with, see the module docs) times its density `rho`, for vertices `s` in
/// screen space with determinant `det` ([`solid_det`]).
#[inline]
fn edge_terms(s: &[Uvt; 4], det: f64, rho: f64) -> [[f64; 3]; 6] {
    // Outward faces of a positively oriented tet (the boundary of
    // [0, 1, 2, 3]): F0 = (1, 2, 3), F1 = (0, 3, 2), F2 = (0, 1, 3),
    // F3 = (0, 2, 1); a negative one has them reversed, which negates every
    // face's contribution.
    let faces =
        [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]].map(|f| plane_fn(s[f[0]], s[f[1]], s[f[2]]));
    let sign = if det > 0.0 { -rho } else { rho };
    // Each edge runs one way in one face and the other way in the other:
    // walked once (from → to), with the difference of their planes.
    let faces_of = [(0, 3), (0, 1), (2, 0), (1, 2), (3, 1), (2, 3)];
    faces_of.map(|(f, g)| {
        let (a, b) = (faces[f], faces[g]);
        [
            sign * (a[0] - b[0]),
            sign * (a[1] - b[1]),
            sign * (a[2] - b[2]),
        ]
    })
}

/// The plane of the face `(a, b, c)` as `t = g0 + g1·u + g2·v`; zero for a
/// face parallel to the rays (its projection has no area, so it adds
/// nothing whatever its plane).
#[inline]
fn plane_fn(a: Uvt, b: Uvt, c: Uvt) -> [f64; 3] {
    let (e, f) = (
        [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
        [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
    );
    let n = [
        e[1] * f[2] - e[2] * f[1],
        e[2] * f[0] - e[0] * f[2],
        e[0] * f[1] - e[1] * f[0],
    ];
    let size = n[0].abs() + n[1].abs() + n[2].abs();
    if !(n[2].abs() > 1e-9 * size) {
        return [0.0; 3];
    }
    let (g1, g2) = (-n[0] / n[2], -n[1] / n[2]);
    [a[2] - g1 * a[0] - g2 * a[1], g1, g2]
}

/// The parts of tet `v` inside `plane`, as at most three tets, into `out`.
fn split(v: &[[f64; 3]; 4], plane: Plane, out: &mut Vec<[[f64; 3]; 4]>) {
    let d = v.map(|p| plane.dist(p));
    let inside: Vec<usize> = (0..4).filter(|&k| d[k] <= 0.0).collect();
    let outside: Vec<usize> = (0..4).filter(|&k| d[k] > 0.0).collect();
    // Where edge (a inside, b outside) meets the plane.
    let cross = |a: usize, b: usize| -> [f64; 3] {
        let s = d[a] / (d[a] - d[b]);
        std::array::from_fn(|x| v[a][x] + (v[b][x] - v[a][x]) * s)
    };
    // A prism of triangles (a0, a1, a2) and (b0, b1, b2) with a_k joined
    // to b_k, as three tets.
    let mut prism = |a: [[f64; 3]; 3], b: [[f64; 3]; 3]| {
        out.push([a[0], a[1], a[2], b[0]]);
        out.push([a[1], a[2], b[0], b[1]]);
        out.push([a[2], b[0], b[1], b[2]]);
    };
    match (inside.len(), outside.len()) {
        (4, _) => out.push(*v),
        (0, _) => {}
        (1, _) => {
            let a = inside[0];
            out.push([
                v[a],
                cross(a, outside[0]),
                cross(a, outside[1]),
                cross(a, outside[2]),
            ]);
        }
        (3, _) => {
            let o = outside[0];
            let t = [inside[0], inside[1], inside[2]];
            prism(t.map(|k| v[k]), t.map(|k| cross(k, o)));
        }
        _ => {
            let (a, b) = (inside[0], inside[1]);
            let (c, e) = (outside[0], outside[1]);
            prism(
                [v[a], cross(a, c), cross(a, e)],
                [v[b], cross(b, c), cross(b, e)],
            );
        }
    }
}
