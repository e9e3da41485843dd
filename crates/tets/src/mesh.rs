//! The phase-space tessellation: Lagrangian grid → tetrahedra with masses,
//! densities, periodic images and culling blocks.
//!
//! A mesh over a grid is *lean*: it holds the particle positions and, per
//! 8³-cell culling block, the bounds of each group of image tets — nothing
//! per tet. The tets of a block are derived from grid indices when an
//! operation visits it ([`TetMesh::block_tets`], `crate::lattice`).
//! Acceleration structures are built by the operations that need them: the
//! coarser levels of detail on first use ([`TetMesh::lod`]), the point/ray
//! index by `crate::TetVolume` on its first point sample. A mesh assembled
//! tet by tet (a part of a decomposed run, [`TetMeshBuilder`]) holds its
//! tets explicitly and answers the same questions.

use std::ops::Range;
use std::sync::OnceLock;

use rayon::prelude::*;
use voxless_core::{Aabb, Vec3};

use crate::TetError;
use crate::lattice::{Cell, Lattice};

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
        Tet::bounds_of(&self.v)
    }
    /// The bounds of four vertices.
    #[inline]
    pub fn bounds_of(v: &[Vec3; 4]) -> Aabb {
        let mut b = Aabb::EMPTY;
        for &p in v {
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
    /// The signed volumes of a cell's six [`KUHN`] tets, in order: each
    /// is [`Tet::signed_volume`] of its vertices bit for bit (the same
    /// differences and products in the same order), but the tets share the
    /// cell's first corner and its opposite one, so the edges from the
    /// first corner and the three cross products with the diagonal are
    /// computed once for all six.
    #[inline(always)]
    pub fn kuhn_volumes(corners: &[Vec3; 8]) -> [f64; 6] {
        let d = |a: Vec3, b: Vec3| [(a.x - b.x) as f64, (a.y - b.y) as f64, (a.z - b.z) as f64];
        let e: [[f64; 3]; 8] = std::array::from_fn(|k| d(corners[k], corners[0]));
        let c = e[7];
        // `signed_volume`'s (b × c) terms for the tets' third vertices.
        let cross = |b: [f64; 3]| {
            [
                b[1] * c[2] - b[2] * c[1],
                b[0] * c[2] - b[2] * c[0],
                b[0] * c[1] - b[1] * c[0],
            ]
        };
        let (x3, x5, x6) = (cross(e[3]), cross(e[5]), cross(e[6]));
        let volume = |a: [f64; 3], x: [f64; 3]| (a[0] * x[0] - a[1] * x[1] + a[2] * x[2]) / 6.0;
        [
            volume(e[1], x3),
            volume(e[1], x5),
            volume(e[2], x3),
            volume(e[2], x6),
            volume(e[4], x5),
            volume(e[4], x6),
        ]
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
    /// The group's tets' indices in mesh order (the order of
    /// [`TetMesh::tets`]).
    pub tets: Range<u64>,
    pub bounds: Aabb,
    /// Index of the 8³-cell Lagrangian block this group belongs to (the same
    /// at every level of detail).
    pub lagrangian: u32,
    /// The image shift of the group's tets, in box lengths per axis
    /// (explicit meshes: `[0; 3]`, their tets are already placed).
    pub shift: [i8; 3],
    /// Lean meshes: the group holds every tet of its Lagrangian block once.
    complete: bool,
    /// Lean meshes: the tets of a cell of the block lie within this of the
    /// cell's first corner, per axis.
    pub(crate) reach: f32,
}

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

/// Where a mesh's tets come from.
#[derive(Clone, Debug)]
enum Source {
    /// Derived from the particles when visited.
    Lattice(Lattice),
    /// Held, in mesh order.
    Explicit(Vec<Tet>),
}

/// The tessellated mesh.
#[derive(Debug)]
pub struct TetMesh {
    pub n: usize,
    pub box_size: f32,
    pub tet_mass: f64,
    /// Mean tet volume (L/N)³/6.
    pub mean_volume: f64,
    blocks: Vec<Block>,
    /// Point masses of degenerate tets (centroid, mass), images included.
    point_masses: Vec<(Vec3, f64)>,
    source: Source,
    /// Levels of detail asked for ([`TetMesh::with_lod`]) and, once an
    /// operation needed them, built.
    lod_levels: usize,
    lod: OnceLock<Vec<TetMesh>>,
}

impl Clone for TetMesh {
    /// The mesh without its built levels of detail (a clone builds them
    /// again when needed).
    fn clone(&self) -> TetMesh {
        TetMesh {
            n: self.n,
            box_size: self.box_size,
            tet_mass: self.tet_mass,
            mean_volume: self.mean_volume,
            blocks: self.blocks.clone(),
            point_masses: self.point_masses.clone(),
            source: self.source.clone(),
            lod_levels: self.lod_levels,
            lod: OnceLock::new(),
        }
    }
}

fn check_box(l: f32) -> Result<(), TetError> {
    if !(l.is_finite() && l > 0.0) {
        return Err(TetError::BadBox { box_size: l });
    }
    Ok(())
}

fn check_mass(settings: &TetSettings, n: usize) -> Result<f64, TetError> {
    let particle_mass = settings.particle_mass.unwrap_or(1.0 / (n * n * n) as f64);
    if !(particle_mass.is_finite() && particle_mass > 0.0) {
        return Err(TetError::BadMass {
            mass: particle_mass,
        });
    }
    Ok(particle_mass)
}

impl TetMesh {
    /// Tessellates `grid` (see [`TetMesh::from_grid`]; this copies the
    /// positions).
    pub fn new(grid: &LagrangianGrid, settings: &TetSettings) -> Result<TetMesh, TetError> {
        TetMesh::check_grid(grid)?;
        TetMesh::from_grid(grid.clone(), settings)
    }

    fn check_grid(grid: &LagrangianGrid) -> Result<(), TetError> {
        let n = grid.n;
        check_box(grid.box_size)?;
        if n < 2 || n.checked_pow(3) != Some(grid.positions.len()) {
            return Err(TetError::NotCubic {
                count: grid.positions.len(),
            });
        }
        if let Some(i) = grid.positions.iter().position(|p| !p.is_finite()) {
            return Err(TetError::NonFinite { index: i });
        }
        Ok(())
    }

    /// Tessellates `grid`, keeping its positions: 6 tets per cell, every
    /// tet unwrapped to the periodic image nearest its anchor (corner 0),
    /// and every tet that crosses a face of the box repeated at the images
    /// that bring its parts back inside, so that exactly the box shows each
    /// tet whole. One pass over the tets finds each block's image groups
    /// and bounds and the degenerate tets' point masses; the tets themselves
    /// are not kept.
    pub fn from_grid(grid: LagrangianGrid, settings: &TetSettings) -> Result<TetMesh, TetError> {
        TetMesh::check_grid(&grid)?;
        let particle_mass = check_mass(settings, grid.n)?;
        let lattice = Lattice::new(
            (grid.n, grid.box_size),
            grid.positions,
            0,
            BLOCK,
            particle_mass,
            settings.degenerate_fraction,
        );
        let rows = 0..lattice.blocks_per_axis();
        Ok(TetMesh::scan(lattice, rows))
    }

    /// The tets of the Lagrangian blocks whose first index lies in
    /// `slab.rows` (block rows of [`BLOCK`] cells along i), exactly as
    /// [`TetMesh::new`] makes them for the whole grid and in the same order:
    /// the whole mesh's tets are the slabs' tets, slab after slab. So ranks
    /// that each read a slab of a run tessellate it together (see
    /// [`LagrangianSlab`]).
    pub fn from_slab(slab: &LagrangianSlab, settings: &TetSettings) -> Result<TetMesh, TetError> {
        let n = slab.n;
        check_box(slab.box_size)?;
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
        let particle_mass = check_mass(settings, n)?;
        let nb = n.div_ceil(BLOCK);
        let rows = slab.rows.start.min(nb)..slab.rows.end.min(nb);
        let needed = (rows.end * BLOCK).min(n) + 1 - (rows.start * BLOCK).min(n);
        if !rows.is_empty() && (slab.first_plane != rows.start * BLOCK || slab.planes < needed) {
            return Err(TetError::NotCubic {
                count: slab.positions.len(),
            });
        }
        let lattice = Lattice::new(
            (n, slab.box_size),
            slab.positions.clone(),
            slab.first_plane,
            BLOCK,
            particle_mass,
            settings.degenerate_fraction,
        );
        Ok(TetMesh::scan(lattice, rows))
    }

    /// Asks for up to `levels` coarser levels of detail (each halving N;
    /// they stop when N is odd or the blocks would hold less than one cell).
    /// They are built when an operation first needs them ([`TetMesh::lod`]).
    pub fn with_lod(mut self, levels: usize) -> TetMesh {
        self.lod_levels = levels;
        self.lod = OnceLock::new();
        self
    }

    /// The coarser levels of detail asked for by [`TetMesh::with_lod`],
    /// built on first use: level r (index r − 1) tessellates every 2^r-th
    /// particle per axis with tet mass × 2^{3r}, its blocks covering the
    /// same Lagrangian blocks as level 0. Empty for explicit meshes and
    /// slabs.
    pub fn lod(&self) -> &[TetMesh] {
        self.lod.get_or_init(|| {
            let Source::Lattice(lattice) = &self.source else {
                return Vec::new();
            };
            (1..=self.lod_levels as u32)
                .map_while(|r| lattice.coarse(r))
                .map(|coarse| {
                    let rows = 0..coarse.blocks_per_axis();
                    TetMesh::scan(coarse, rows)
                })
                .collect()
        })
    }

    /// The levels of detail asked for (built or not).
    pub fn lod_levels(&self) -> usize {
        self.lod_levels
    }

    /// Scans the blocks of block rows `rows` of `lattice`: per block, in
    /// parallel, its image groups (tet counts and bounds) and point masses.
    fn scan(lattice: Lattice, rows: Range<usize>) -> TetMesh {
        let nb = lattice.blocks_per_axis();
        let first = rows.start * nb * nb;
        let scans: Vec<_> = (first..rows.end * nb * nb)
            .into_par_iter()
            .map(|b| lattice.scan(b as u32))
            .collect();
        let mut blocks = Vec::new();
        let mut point_masses = Vec::new();
        let mut next = 0u64;
        for (b, scan) in (first..).zip(scans) {
            for (shift, count, bounds) in scan.groups {
                blocks.push(Block {
                    tets: next..next + count,
                    bounds,
                    lagrangian: b as u32,
                    shift,
                    complete: scan.complete,
                    reach: scan.reach,
                });
                next += count;
            }
            point_masses.extend(scan.points);
        }
        let (n, l) = (lattice.n, lattice.l);
        TetMesh {
            n,
            box_size: l,
            tet_mass: lattice.tet_mass,
            mean_volume: (l as f64 / n as f64).powi(3) / 6.0,
            blocks,
            point_masses,
            source: Source::Lattice(lattice),
            lod_levels: 0,
            lod: OnceLock::new(),
        }
    }

    /// The culling blocks (image groups), in mesh order.
    pub fn blocks(&self) -> &[Block] {
        &self.blocks
    }

    /// Point masses of degenerate tets (centroid, mass), images included.
    pub fn point_masses(&self) -> &[(Vec3, f64)] {
        &self.point_masses
    }

    /// How many tets the mesh has (images included, degenerate tets not).
    pub fn tet_count(&self) -> usize {
        self.blocks.last().map_or(0, |b| b.tets.end as usize)
    }

    /// Whether the tets are derived from grid indices (not held).
    pub fn is_lean(&self) -> bool {
        matches!(self.source, Source::Lattice(_))
    }

    /// Bytes the mesh holds: positions (or explicit tets), blocks and point
    /// masses; levels of detail once built.
    pub fn held_bytes(&self) -> usize {
        let own = match &self.source {
            Source::Lattice(l) => l.held_bytes(),
            Source::Explicit(t) => t.len() * std::mem::size_of::<Tet>(),
        };
        own + self.blocks.len() * std::mem::size_of::<Block>()
            + self.point_masses.len() * std::mem::size_of::<(Vec3, f64)>()
            + self
                .lod
                .get()
                .map_or(0, |l| l.iter().map(TetMesh::held_bytes).sum())
    }

    /// The tets of block `b` (an index into [`TetMesh::blocks`]), in mesh
    /// order: the held ones, or derived into `buf`.
    pub fn block_tets<'a>(&'a self, b: usize, buf: &'a mut Vec<Tet>) -> &'a [Tet] {
        self.block_tets_where(b, |_| true, buf)
    }

    /// [`TetMesh::block_tets`] of the cells `keep` accepts — it sees a
    /// cell's first corner (moved to the block's image), and the cell's
    /// tets lie within [`Block`]'s `reach` of it per axis — so an operation
    /// that needs part of a block (a tile's pixels) skips deriving the rest.
    /// Explicit meshes give every tet of the block.
    pub(crate) fn block_tets_where<'a>(
        &'a self,
        b: usize,
        keep: impl FnMut(Vec3) -> bool,
        buf: &'a mut Vec<Tet>,
    ) -> &'a [Tet] {
        let block = &self.blocks[b];
        match &self.source {
            Source::Explicit(tets) => &tets[block.tets.start as usize..block.tets.end as usize],
            Source::Lattice(lattice) => {
                buf.clear();
                let group = (block.lagrangian, block.shift, block.complete);
                lattice.tets(group, keep, buf);
                buf
            }
        }
    }

    /// The Lagrangian blocks the mesh covers, in order (a slab covers some;
    /// a block's image groups are consecutive).
    pub(crate) fn lagrangian_blocks(&self) -> Vec<u32> {
        let mut lagrangian: Vec<u32> = self.blocks.iter().map(|b| b.lagrangian).collect();
        lagrangian.dedup();
        lagrangian
    }

    /// Tet `idx` (in mesh order) of block `b`, derived alone, when `b` is a
    /// lean mesh's block whose one group holds six tets a cell (see
    /// `Lattice::nth_tet`); `None` otherwise (derive the block).
    pub(crate) fn complete_block_tet(&self, b: usize, idx: u64) -> Option<Tet> {
        let block = &self.blocks[b];
        match &self.source {
            Source::Lattice(lattice) if block.complete => {
                let count = block.tets.end - block.tets.start;
                lattice.nth_tet(block.lagrangian, block.shift, count, idx)
            }
            _ => None,
        }
    }

    /// A lean mesh's [`TetMesh::block_tets_where`] cell by cell: `f` gets
    /// each accepted cell (its corners at the block's image, its tets on
    /// request). `false` for explicit meshes (nothing visited).
    pub(crate) fn block_cells_where(
        &self,
        b: usize,
        keep: impl FnMut(Vec3) -> bool,
        f: impl FnMut(&Cell),
    ) -> bool {
        let block = &self.blocks[b];
        match &self.source {
            Source::Explicit(_) => false,
            Source::Lattice(lattice) => {
                let group = (block.lagrangian, block.shift, block.complete);
                lattice.cells_where(group, keep, f);
                true
            }
        }
    }

    /// Every tet, in mesh order (for tests and tools: this materialises
    /// what the mesh does not hold).
    pub fn tets(&self) -> Vec<Tet> {
        let mut out = Vec::with_capacity(self.tet_count());
        let mut buf = Vec::new();
        for b in 0..self.blocks.len() {
            out.extend_from_slice(self.block_tets(b, &mut buf));
        }
        out
    }

    /// The lattice behind a lean mesh.
    pub(crate) fn lattice(&self) -> Option<&Lattice> {
        match &self.source {
            Source::Lattice(l) => Some(l),
            Source::Explicit(_) => None,
        }
    }

    /// The held tets of an explicit mesh.
    pub(crate) fn explicit_tets(&self) -> Option<&[Tet]> {
        match &self.source {
            Source::Explicit(t) => Some(t),
            Source::Lattice(_) => None,
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

/// A mesh assembled tet by tet — the part of a decomposed run that reaches
/// into one box, or tets from elsewhere — held explicitly.
#[derive(Debug)]
pub struct TetMeshBuilder {
    mesh: TetMesh,
    tets: Vec<Tet>,
}

impl TetMeshBuilder {
    /// An empty mesh of a run of N³ particles in a box of size `box_size`
    /// whose tets carry `tet_mass` and have mean volume `mean_volume`.
    pub fn new(n: usize, box_size: f32, tet_mass: f64, mean_volume: f64) -> TetMeshBuilder {
        TetMeshBuilder {
            mesh: TetMesh {
                n,
                box_size,
                tet_mass,
                mean_volume,
                blocks: Vec::new(),
                point_masses: Vec::new(),
                source: Source::Explicit(Vec::new()),
                lod_levels: 0,
                lod: OnceLock::new(),
            },
            tets: Vec::new(),
        }
    }

    /// Adds a culling block of Lagrangian block `lagrangian` holding `tets`.
    pub fn push_block(&mut self, lagrangian: u32, tets: impl IntoIterator<Item = Tet>) {
        let start = self.tets.len();
        let mut bounds = Aabb::EMPTY;
        for t in tets {
            bounds = bounds.union(t.bounds());
            self.tets.push(t);
        }
        self.mesh.blocks.push(Block {
            tets: start as u64..self.tets.len() as u64,
            bounds,
            lagrangian,
            shift: [0; 3],
            complete: false,
            reach: f32::INFINITY,
        });
    }

    /// Adds a degenerate tet's point mass.
    pub fn push_point_mass(&mut self, p: Vec3, mass: f64) {
        self.mesh.point_masses.push((p, mass));
    }

    /// Tets held so far.
    pub fn tet_count(&self) -> usize {
        self.tets.len()
    }

    pub fn build(mut self) -> TetMesh {
        self.tets.shrink_to_fit();
        self.mesh.source = Source::Explicit(self.tets);
        self.mesh
    }
}
