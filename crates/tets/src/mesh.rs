//! The phase-space tessellation: Lagrangian grid → tetrahedra with masses,
//! densities, periodic images and culling blocks.

use rayon::prelude::*;
use voxless_core::{Aabb, Vec3};

use crate::TetError;

/// N-body particles on an N³ Lagrangian grid in a periodic box `[0, L)³`.
#[derive(Clone, Debug)]
pub struct LagrangianGrid {
    pub n: usize,
    pub box_size: f32,
    /// Positions in Lagrangian order `(i·N + j)·N + k`, k fastest.
    pub positions: Vec<Vec3>,
}

/// Lagrangian planes `first_plane..first_plane + planes` (periodically, so
/// the last slab's extra plane is plane 0) of an N³ run: what one rank reads
/// to tessellate the block rows `rows`. Block row `r` needs planes
/// `r·BLOCK ..= min((r + 1)·BLOCK, N)`, so a slab of rows `a..b` starts at
/// plane `a·BLOCK` and holds `min(b·BLOCK, N) − a·BLOCK + 1` planes.
#[derive(Clone, Debug)]
pub struct LagrangianSlab {
    pub n: usize,
    pub box_size: f32,
    pub rows: std::ops::Range<usize>,
    pub first_plane: usize,
    pub planes: usize,
    /// Positions of the planes in Lagrangian order within each plane.
    pub positions: Vec<Vec3>,
}

#[derive(Clone, Debug)]
pub struct TetSettings {
    /// Mass per particle (per Lagrangian cell); default: total mass 1.
    pub particle_mass: Option<f64>,
    /// Tets with `|V|` below this fraction of the mean tet volume are
    /// degenerate (at caustics): their mass is kept as a point mass at the
    /// centroid instead of a (near-)infinite density over no volume.
    pub degenerate_fraction: f64,
}

impl Default for TetSettings {
    fn default() -> Self {
        TetSettings {
            particle_mass: None,
            degenerate_fraction: 1e-6,
        }
    }
}

/// One tetrahedron: vertices and density ρ = m/|V|.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tet {
    pub v: [Vec3; 4],
    pub density: f32,
}

impl Tet {
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for p in self.v {
            b.grow(p);
        }
        b
    }
    /// Signed volume (positive for the reference orientation).
    pub fn signed_volume(v: &[Vec3; 4]) -> f64 {
        let d = |a: Vec3, b: Vec3| [(a.x - b.x) as f64, (a.y - b.y) as f64, (a.z - b.z) as f64];
        let (a, b, c) = (d(v[1], v[0]), d(v[2], v[0]), d(v[3], v[0]));
        (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0]))
            / 6.0
    }
    /// Whether `p` lies inside (boundary included), by the signs of the four
    /// sub-volumes.
    pub fn contains(&self, p: Vec3) -> bool {
        let v = &self.v;
        let s = Tet::signed_volume(v);
        let parts = [
            Tet::signed_volume(&[p, v[1], v[2], v[3]]),
            Tet::signed_volume(&[v[0], p, v[2], v[3]]),
            Tet::signed_volume(&[v[0], v[1], p, v[3]]),
            Tet::signed_volume(&[v[0], v[1], v[2], p]),
        ];
        if s > 0.0 {
            parts.iter().all(|&x| x >= 0.0)
        } else {
            parts.iter().all(|&x| x <= 0.0)
        }
    }
}

/// A group of tets for culling: the tets of an 8³ block of Lagrangian cells
/// that share one periodic image shift, and their bounds.
#[derive(Clone, Debug, PartialEq)]
pub struct Block {
    pub tets: std::ops::Range<u32>,
    pub bounds: Aabb,
    /// Index of the 8³-cell Lagrangian block this group belongs to (the same
    /// at every level of detail).
    pub lagrangian: u32,
}

/// One block's tets grouped by image shift (with their bounds), and its
/// degenerate tets' point masses.
type BlockTets = (Vec<(Vec<Tet>, Aabb)>, Vec<(Vec3, f64)>);

/// Cells per block axis.
pub const BLOCK: usize = 8;

/// The six tets of a Lagrangian cell (Kuhn decomposition): all share the main
/// diagonal from corner 0 to corner 7 and step through the cube along one
/// axis permutation each, so neighbouring cells' faces match.
pub const KUHN: [[usize; 4]; 6] = [
    [0, 1, 3, 7], // x, y, z
    [0, 1, 5, 7], // x, z, y
    [0, 2, 3, 7], // y, x, z
    [0, 2, 6, 7], // y, z, x
    [0, 4, 5, 7], // z, x, y
    [0, 4, 6, 7], // z, y, x
];

/// The tessellated mesh.
#[derive(Clone, Debug)]
pub struct TetMesh {
    pub n: usize,
    pub box_size: f32,
    pub tet_mass: f64,
    pub tets: Vec<Tet>,
    pub blocks: Vec<Block>,
    /// Point masses of degenerate tets (centroid, mass), images included.
    pub point_masses: Vec<(Vec3, f64)>,
    /// Mean tet volume (L/N)³/6.
    pub mean_volume: f64,
    /// Coarser levels of detail: level r (index r − 1) tessellates every
    /// 2^r-th particle per axis with tet mass × 2^{3r}, its blocks covering the
    /// same Lagrangian blocks as level 0. Empty unless built by [`TetMesh::with_lod`].
    pub lod: Vec<TetMesh>,
}

impl TetMesh {
    /// Tessellates `grid`: 6 tets per cell, every tet unwrapped to the
    /// periodic image nearest its anchor (corner 0), and every tet that
    /// crosses a face of the box repeated at the images that bring its parts
    /// back inside, so that exactly the box shows each tet whole.
    pub fn new(grid: &LagrangianGrid, settings: &TetSettings) -> Result<TetMesh, TetError> {
        let n = grid.n;
        let l = grid.box_size;
        if !(l.is_finite() && l > 0.0) {
            return Err(TetError::BadBox { box_size: l });
        }
        if n < 2 || n.checked_pow(3) != Some(grid.positions.len()) {
            return Err(TetError::NotCubic {
                count: grid.positions.len(),
            });
        }
        if let Some(i) = grid.positions.iter().position(|p| !p.is_finite()) {
            return Err(TetError::NonFinite { index: i });
        }
        let particle_mass = settings.particle_mass.unwrap_or(1.0 / (n * n * n) as f64);
        if !(particle_mass.is_finite() && particle_mass > 0.0) {
            return Err(TetError::BadMass {
                mass: particle_mass,
            });
        }
        Ok(TetMesh::build(
            grid,
            particle_mass,
            settings.degenerate_fraction,
            BLOCK,
        ))
    }

    /// The tets of the Lagrangian blocks whose first index lies in
    /// `slab.rows` (block rows of [`BLOCK`] cells along i), exactly as
    /// [`TetMesh::new`] makes them for the whole grid and in the same order:
    /// the whole mesh's tets are the slabs' tets, slab after slab. So ranks
    /// that each read a slab of a run tessellate it together (see
    /// [`LagrangianSlab`]).
    pub fn from_slab(slab: &LagrangianSlab, settings: &TetSettings) -> Result<TetMesh, TetError> {
        let (n, l) = (slab.n, slab.box_size);
        if !(l.is_finite() && l > 0.0) {
            return Err(TetError::BadBox { box_size: l });
        }
        if n < 2
            || n.checked_mul(n).and_then(|nn| nn.checked_mul(slab.planes))
                != Some(slab.positions.len())
        {
            return Err(TetError::NotCubic {
                count: slab.positions.len(),
            });
        }
        if let Some(i) = slab.positions.iter().position(|p| !p.is_finite()) {
            return Err(TetError::NonFinite {
                index: slab.first_plane * n * n + i,
            });
        }
        let particle_mass = settings.particle_mass.unwrap_or(1.0 / (n * n * n) as f64);
        if !(particle_mass.is_finite() && particle_mass > 0.0) {
            return Err(TetError::BadMass {
                mass: particle_mass,
            });
        }
        let rows = slab.rows.start.min(n.div_ceil(BLOCK))..slab.rows.end.min(n.div_ceil(BLOCK));
        let needed = (rows.end * BLOCK).min(n) + 1 - (rows.start * BLOCK).min(n);
        if !rows.is_empty() && (slab.first_plane != rows.start * BLOCK || slab.planes < needed) {
            return Err(TetError::NotCubic {
                count: slab.positions.len(),
            });
        }
        let at = |a: usize, b: usize, c: usize| {
            let plane = (a % n + n - slab.first_plane % n) % n;
            slab.positions[(plane * n + b % n) * n + c % n]
        };
        Ok(TetMesh::build_rows(
            (n, l),
            &at,
            particle_mass,
            settings.degenerate_fraction,
            BLOCK,
            rows,
        ))
    }

    /// Adds up to `levels` coarser levels of detail (each halving N; stops
    /// when N is odd or the blocks would hold less than one cell).
    pub fn with_lod(
        mut self,
        grid: &LagrangianGrid,
        levels: usize,
        settings: &TetSettings,
    ) -> TetMesh {
        let particle_mass = self.tet_mass * 6.0;
        let mut r = 1;
        while r <= levels && BLOCK >> r >= 1 && grid.n.is_multiple_of(1 << r) && grid.n >> r >= 2 {
            let step = 1 << r;
            let nc = grid.n / step;
            let positions = (0..nc * nc * nc)
                .map(|c| {
                    let (i, j, k) = (c / (nc * nc), (c / nc) % nc, c % nc);
                    grid.positions[((i * step) * grid.n + j * step) * grid.n + k * step]
                })
                .collect();
            let coarse = LagrangianGrid {
                n: nc,
                box_size: grid.box_size,
                positions,
            };
            let mass = particle_mass * (step * step * step) as f64;
            self.lod.push(TetMesh::build(
                &coarse,
                mass,
                settings.degenerate_fraction,
                BLOCK >> r,
            ));
            r += 1;
        }
        self
    }

    /// Tessellates a validated grid with blocks of `block` cells per axis.
    fn build(
        grid: &LagrangianGrid,
        particle_mass: f64,
        degenerate_fraction: f64,
        block: usize,
    ) -> TetMesh {
        let n = grid.n;
        let at =
            |a: usize, b: usize, c: usize| grid.positions[((a % n) * n + (b % n)) * n + (c % n)];
        TetMesh::build_rows(
            (n, grid.box_size),
            &at,
            particle_mass,
            degenerate_fraction,
            block,
            0..n.div_ceil(block),
        )
    }

    /// Tessellates the blocks of block rows `rows` of a grid of N³ particles
    /// in a box of size L (`(n, l)`) whose position `(i, j, k)` is `at(i, j,
    /// k)` (indices may exceed N by one: the periodic neighbour).
    fn build_rows(
        (n, l): (usize, f32),
        at: &(dyn Fn(usize, usize, usize) -> Vec3 + Sync),
        particle_mass: f64,
        degenerate_fraction: f64,
        block: usize,
        rows: std::ops::Range<usize>,
    ) -> TetMesh {
        let tet_mass = particle_mass / 6.0;
        let mean_volume = (l as f64 / n as f64).powi(3) / 6.0;
        let floor = degenerate_fraction * mean_volume;
        let nb = n.div_ceil(block);
        // Per block, in parallel: its tets grouped by image shift.
        let per_block: Vec<BlockTets> = (rows.start * nb * nb..rows.end * nb * nb)
            .into_par_iter()
            .map(|b| {
                let (bi, bj, bk) = (b / (nb * nb), (b / nb) % nb, b % nb);
                let mut groups: Vec<([i8; 3], Vec<Tet>, Aabb)> = Vec::new();
                let mut points = Vec::new();
                for i in bi * block..((bi + 1) * block).min(n) {
                    for j in bj * block..((bj + 1) * block).min(n) {
                        for k in bk * block..((bk + 1) * block).min(n) {
                            let corners = cell_corners(at, l, i, j, k);
                            for t in KUHN {
                                let v = t.map(|c| corners[c]);
                                let vol = Tet::signed_volume(&v).abs();
                                for shift in images(&v, l) {
                                    let off = Vec3::new(
                                        shift[0] as f32,
                                        shift[1] as f32,
                                        shift[2] as f32,
                                    ) * l;
                                    let vs = v.map(|p| p + off);
                                    if vol < floor {
                                        let c = (vs[0] + vs[1] + vs[2] + vs[3]) * 0.25;
                                        // The point mass belongs to the image whose centroid is in the box.
                                        if in_box(c, l) {
                                            points.push((c, tet_mass));
                                        }
                                        continue;
                                    }
                                    let tet = Tet {
                                        v: vs,
                                        density: (tet_mass / vol) as f32,
                                    };
                                    let g = match groups.iter().position(|g| g.0 == shift) {
                                        Some(g) => g,
                                        None => {
                                            groups.push((shift, Vec::new(), Aabb::EMPTY));
                                            groups.len() - 1
                                        }
                                    };
                                    groups[g].2 = groups[g].2.union(tet.bounds());
                                    groups[g].1.push(tet);
                                }
                            }
                        }
                    }
                }
                (groups.into_iter().map(|g| (g.1, g.2)).collect(), points)
            })
            .collect();
        let mut tets = Vec::new();
        let mut blocks = Vec::new();
        let mut point_masses = Vec::new();
        let first = rows.start * nb * nb;
        for (b, (groups, points)) in (first..).zip(per_block) {
            for (ts, bounds) in groups {
                let start = tets.len() as u32;
                tets.extend(ts);
                blocks.push(Block {
                    tets: start..tets.len() as u32,
                    bounds,
                    lagrangian: b as u32,
                });
            }
            point_masses.extend(points);
        }
        TetMesh {
            n,
            box_size: l,
            tet_mass,
            tets,
            blocks,
            point_masses,
            mean_volume,
            lod: Vec::new(),
        }
    }

    /// The mass inside the box: N³ particles × particle mass. Each tet's
    /// images together put exactly its mass inside the box, and degenerate
    /// tets keep theirs as point masses, so this is what a projection of the
    /// box must conserve.
    pub fn total_mass(&self) -> f64 {
        self.tet_mass * 6.0 * (self.n * self.n * self.n) as f64
    }
}

/// The 8 corners of cell (i, j, k), unwrapped to the periodic image nearest
/// corner 0 (corner index = 4·di + 2·dj + dk).
fn cell_corners(
    at: &(dyn Fn(usize, usize, usize) -> Vec3 + Sync),
    l: f32,
    i: usize,
    j: usize,
    k: usize,
) -> [Vec3; 8] {
    let anchor = at(i, j, k);
    let mut out = [anchor; 8];
    for (c, slot) in out.iter_mut().enumerate() {
        let p = at(i + (c >> 2), j + ((c >> 1) & 1), k + (c & 1));
        let d = p - anchor;
        let wrap = |x: f32| x - l * (x / l).round();
        *slot = anchor + Vec3::new(wrap(d.x), wrap(d.y), wrap(d.z));
    }
    out
}

fn in_box(p: Vec3, l: f32) -> bool {
    (0..3).all(|a| p[a] >= 0.0 && p[a] < l)
}

/// The image shifts (in box lengths, per axis −1, 0 or +1) at which a tet
/// overlaps the box `[0, L)³`: the tet itself if it does, plus the images
/// that bring its out-of-box parts back in.
fn images(v: &[Vec3; 4], l: f32) -> Vec<[i8; 3]> {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in v {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    // Per axis, the shifts s with [lo + sL, hi + sL] overlapping [0, L).
    let shifts = |a: usize| -> Vec<i8> {
        [-1i8, 0, 1]
            .into_iter()
            .filter(|&s| hi[a] + s as f32 * l > 0.0 && lo[a] + (s as f32) * l < l)
            .collect()
    };
    let (sx, sy, sz) = (shifts(0), shifts(1), shifts(2));
    let mut out = Vec::new();
    for &x in &sx {
        for &y in &sy {
            for &z in &sz {
                out.push([x, y, z]);
            }
        }
    }
    out
}
