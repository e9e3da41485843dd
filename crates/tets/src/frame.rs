//! Per-frame culling of a tet mesh: which culling blocks (at which level
//! of detail) each screen tile draws, and, per tile, the tets of those
//! blocks that meet it with their pixel rectangles — derived from grid
//! indices for lean meshes, only for the cells that can reach the tile.

use voxless_core::{Camera, Projection, Ray, Vec3};

use crate::lattice::{Cell, max, min};
use crate::mesh::{KUHN, Tet, TetMesh};
use crate::raster::{Screen, TILE, corners};

/// Everything per frame that does not depend on the tile: the level of
/// detail of each Lagrangian block, and per tile the blocks whose screen box
/// overlaps it (block culling). No per-tet data: each tile derives the tets
/// of its blocks, and their pixel rectangles, when it draws them
/// ([`Frame::block_into`]).
pub struct Frame {
    pub screen: Screen,
    /// Side of a tile in pixels ([`TILE`] unless chosen).
    pub tile_size: u32,
    pub tiles_x: u32,
    pub tiles_y: u32,
    /// Per tile (row-major), the overlapping blocks as `level << 28 | block`.
    pub bins: Vec<Vec<u32>>,
    /// Pixels added on every side of a rectangle before rounding (0: pixel
    /// centres; 0.5: every pixel whose square meets the outline).
    pad: f32,
    /// Blocks drawn at each level (for statistics).
    pub blocks_per_level: Vec<usize>,
}

const LEVEL_SHIFT: u32 = 28;

/// The tets of one bin entry that meet one tile, and their pixel
/// rectangles `[x0, x1, y0, y1]` (inclusive, whole image): scratch reused
/// from block to block.
#[derive(Default)]
pub struct BlockTets {
    pub tets: Vec<Tet>,
    pub rects: Vec<[u16; 4]>,
}

impl Frame {
    /// `lod`: blocks whose screen box is smaller than this many pixels use a
    /// coarser level (one level per halving), when the mesh has them.
    pub fn new(
        mesh: &TetMesh,
        camera: &Camera,
        width: u32,
        height: u32,
        lod: Option<f32>,
    ) -> Frame {
        Frame::with_tile(mesh, camera, width, height, lod, TILE)
    }

    /// [`Frame::new`] with tiles of `tile_size`² pixels.
    pub fn with_tile(
        mesh: &TetMesh,
        camera: &Camera,
        width: u32,
        height: u32,
        lod: Option<f32>,
        tile_size: u32,
    ) -> Frame {
        Frame::build(mesh, camera, (width, height), lod, tile_size, 0.0)
    }

    /// [`Frame::with_tile`] for rays anywhere inside their pixels (jittered
    /// passes, pixel-area projections): rectangles hold every pixel whose
    /// square meets a tet's or a block's outline, not only the pixels whose
    /// centres lie inside.
    pub fn covering(
        mesh: &TetMesh,
        camera: &Camera,
        width: u32,
        height: u32,
        lod: Option<f32>,
        tile_size: u32,
    ) -> Frame {
        Frame::build(mesh, camera, (width, height), lod, tile_size, 0.5)
    }

    /// The mesh's levels a frame with threshold `lod` draws from: the mesh
    /// alone without one (its coarser levels are then never built).
    fn levels(mesh: &TetMesh, lod: Option<f32>) -> Vec<&TetMesh> {
        let coarse = if lod.is_some() { mesh.lod() } else { &[] };
        std::iter::once(mesh).chain(coarse.iter()).collect()
    }

    fn build(
        mesh: &TetMesh,
        camera: &Camera,
        (width, height): (u32, u32),
        lod: Option<f32>,
        tile_size: u32,
        pad: f32,
    ) -> Frame {
        let tile_size = tile_size.max(1);
        let screen = Screen::new(camera, width, height);
        let levels = Frame::levels(mesh, lod);
        // Level per Lagrangian block from its level-0 screen size: the
        // largest of its pieces (a block that wraps around the periodic box
        // is drawn as pieces shifted by whole boxes; their union would span
        // the box).
        let nlag = mesh
            .blocks()
            .iter()
            .map(|b| b.lagrangian + 1)
            .max()
            .unwrap_or(0) as usize;
        let mut level_of = vec![0usize; nlag];
        if let (Some(threshold), true) = (lod, levels.len() > 1) {
            let mut sizes = vec![0.0f32; nlag];
            for b in mesh.blocks() {
                let size = match screen.pixel_rect(&corners(&b.bounds)) {
                    Some((x0, x1, y0, y1)) => (x1 - x0).max(y1 - y0) as f32 + 1.0,
                    None if b.bounds.is_empty() => 0.0,
                    None => f32::INFINITY, // off screen: culled anyway
                };
                let s = &mut sizes[b.lagrangian as usize];
                *s = s.max(size);
            }
            for (l, &size) in level_of.iter_mut().zip(&sizes) {
                if size < threshold {
                    let r = 1 + (threshold / size.max(1e-3)).log2().floor() as usize;
                    *l = r.min(levels.len() - 1);
                }
            }
        }
        let tiles_x = width.div_ceil(tile_size);
        let tiles_y = height.div_ceil(tile_size);
        let mut bins = vec![Vec::new(); (tiles_x * tiles_y) as usize];
        let mut blocks_per_level = vec![0; levels.len()];
        for (r, m) in levels.iter().enumerate() {
            for (i, b) in m.blocks().iter().enumerate() {
                if level_of.get(b.lagrangian as usize).copied().unwrap_or(0) != r {
                    continue;
                }
                if let Some((x0, x1, y0, y1)) = screen.pixel_rect_padded(&corners(&b.bounds), pad) {
                    blocks_per_level[r] += 1;
                    for y in y0 / tile_size..=y1 / tile_size {
                        for x in x0 / tile_size..=x1 / tile_size {
                            bins[(y * tiles_x + x) as usize]
                                .push(((r as u32) << LEVEL_SHIFT) | i as u32);
                        }
                    }
                }
            }
        }
        Frame {
            screen,
            tile_size,
            tiles_x,
            tiles_y,
            bins,
            pad,
            blocks_per_level,
        }
    }

    /// How many tets (of the blocks drawn, at their levels) have a
    /// rectangle on screen. Derives every drawn tet: for statistics and
    /// tests.
    pub fn tet_count(&self, mesh: &TetMesh, lod: Option<f32>) -> usize {
        let levels = Frame::levels(mesh, lod);
        let mut seen = std::collections::HashSet::new();
        let mut count = 0;
        let mut buf = Vec::new();
        for &entry in self.bins.iter().flatten() {
            if !seen.insert(entry) {
                continue;
            }
            let level = (entry >> LEVEL_SHIFT) as usize;
            let b = (entry & ((1 << LEVEL_SHIFT) - 1)) as usize;
            count += levels[level]
                .block_tets(b, &mut buf)
                .iter()
                .filter(|t| self.screen.tet_rect_padded(&t.v, self.pad).is_some())
                .count();
        }
        count
    }

    /// The tets of bin entry `entry` (a block at its level of detail) whose
    /// pixel rectangles meet tile `tile`, in mesh order, into `out` with
    /// their rectangles (whole-image pixels, not clipped to the tile).
    /// A lean mesh derives only the cells whose screen box meets the tile.
    pub fn block_into(&self, mesh: &TetMesh, entry: u32, tile: u32, out: &mut BlockTets) {
        let (m, b) = self.entry(mesh, entry);
        let (tx0, ty0, w, h) = self.tile(tile);
        let (tx1, ty1) = (tx0 + w - 1, ty0 + h - 1);
        let meets = |r: (u32, u32, u32, u32)| r.0 <= tx1 && r.1 >= tx0 && r.2 <= ty1 && r.3 >= ty0;
        let keep = self.cell_cull(m, b, tile);
        out.rects.clear();
        let rect = |t: &Tet| {
            self.screen
                .tet_rect_padded(&t.v, self.pad)
                .filter(|&r| meets(r))
                .map(|r| [r.0 as u16, r.1 as u16, r.2 as u16, r.3 as u16])
        };
        out.tets.clear();
        let ortho = match self.screen.camera.projection {
            Projection::Orthographic {
                half_width,
                half_height,
            } => Some((half_width, half_height)),
            Projection::Perspective { .. } => None,
        };
        let lean = m.block_cells_where(b, keep, |cell| {
            let corners = &cell.at_image;
            // The cell's corners projected once (the per-point operations of
            // `Screen::tet_rect`, so each tet's rectangle is the one its own
            // vertices give); a perspective cell reaching behind the eye
            // takes the tets' own outlines (clipped at the eye's plane).
            let (px, py) = match ortho {
                Some(half) => self.screen.ortho_points(corners, half),
                None => {
                    let (px, py, front) = self.screen.perspective_points(corners);
                    if !front {
                        let (tets, count) = cell.tets();
                        for (_, t) in &tets[..count] {
                            if let Some(r) = rect(t) {
                                out.tets.push(*t);
                                out.rects.push(r);
                            }
                        }
                        return;
                    }
                    (px, py)
                }
            };
            let pad = self.pad;
            let rect_over = |k: &[usize]| {
                let (mut x0, mut x1, mut y0, mut y1) = (px[k[0]], px[k[0]], py[k[0]], py[k[0]]);
                for &c in &k[1..] {
                    (x0, x1) = (min(x0, px[c]), max(x1, px[c]));
                    (y0, y1) = (min(y0, py[c]), max(y1, py[c]));
                }
                self.screen
                    .rect_of(x0 - pad, x1 + pad, y0 - pad, y1 + pad)
                    .filter(|&r| meets(r))
            };
            // A cell whose corners' rectangle misses the tile has no tet
            // that meets it (each tet's rectangle lies in it): no tets to
            // derive.
            if rect_over(&[0, 1, 2, 3, 4, 5, 6, 7]).is_none() {
                return;
            }
            let (tets, count) = cell.tets();
            for &(index, t) in &tets[..count] {
                if let Some(r) = rect_over(&KUHN[index]) {
                    out.tets.push(t);
                    out.rects
                        .push([r.0 as u16, r.1 as u16, r.2 as u16, r.3 as u16]);
                }
            }
        });
        if !lean {
            for t in m.block_tets_where(b, |_| true, &mut Vec::new()) {
                if let Some(r) = rect(t) {
                    out.tets.push(*t);
                    out.rects.push(r);
                }
            }
        }
    }

    /// Whether the hull of a cell's corners `c` (at its image) may meet a
    /// pixel of tile `tile` under an orthographic camera (its corners'
    /// rectangle does; it holds every tet's); `true` for perspective ones.
    pub(crate) fn cell_meets_tile(&self, c: &[Vec3; 8], tile: u32) -> bool {
        let Projection::Orthographic {
            half_width,
            half_height,
        } = self.screen.camera.projection
        else {
            return true;
        };
        let (px, py) = self.screen.ortho_points(c, (half_width, half_height));
        let (mut x0, mut x1, mut y0, mut y1) = (px[0], px[0], py[0], py[0]);
        for k in 1..8 {
            (x0, x1) = (min(x0, px[k]), max(x1, px[k]));
            (y0, y1) = (min(y0, py[k]), max(y1, py[k]));
        }
        let (tx0, ty0, w, h) = self.tile(tile);
        let pad = self.pad;
        self.screen
            .rect_of(x0 - pad, x1 + pad, y0 - pad, y1 + pad)
            .is_some_and(|r| r.0 < tx0 + w && r.1 >= tx0 && r.2 < ty0 + h && r.3 >= ty0)
    }

    /// The mesh (level of detail) and block of bin entry `entry`.
    fn entry<'m>(&self, mesh: &'m TetMesh, entry: u32) -> (&'m TetMesh, usize) {
        let level = (entry >> LEVEL_SHIFT) as usize;
        let m = if level == 0 {
            mesh
        } else {
            &mesh.lod()[level - 1]
        };
        (m, (entry & ((1 << LEVEL_SHIFT) - 1)) as usize)
    }

    /// Whether a cell of block `b` of `m` (given its first corner) may
    /// reach tile `tile`: cells wholly off the tile need not be derived. A
    /// cell's tets lie in a cube about its first corner (tested with a
    /// pixel of slack for rounding); no test per cell when the block lies in
    /// the tile.
    fn cell_cull(&self, m: &TetMesh, b: usize, tile: u32) -> impl Fn(Vec3) -> bool {
        let (tx0, ty0, w, h) = self.tile(tile);
        let (tx1, ty1) = (tx0 + w - 1, ty0 + h - 1);
        let block = &m.blocks()[b];
        let inside = self
            .screen
            .pixel_rect_padded(&corners(&block.bounds), self.pad + 1.0)
            .is_some_and(|r| r.0 > tx0 && r.1 < tx1 && r.2 > ty0 && r.3 < ty1);
        let (reach, pad, screen) = (block.reach, self.pad, self.screen);
        move |anchor: Vec3| inside || screen.cube_meets(anchor, reach, pad, (tx0, tx1, ty0, ty1))
    }

    /// The tets of bin entry `entry` that may reach tile `tile`, for
    /// whole-cell work: a lean mesh's cells (culled as in
    /// [`Frame::block_into`]) go to `on_cell` (see
    /// `TetMesh::block_cells_where`); an explicit mesh's tets whose
    /// rectangles meet the tile go to `on_tet`.
    pub(crate) fn cells_of(
        &self,
        mesh: &TetMesh,
        entry: u32,
        tile: u32,
        on_cell: impl FnMut(&Cell),
        mut on_tet: impl FnMut(&Tet),
    ) {
        let (m, b) = self.entry(mesh, entry);
        if m.block_cells_where(b, self.cell_cull(m, b, tile), on_cell) {
            return;
        }
        let (tx0, ty0, w, h) = self.tile(tile);
        let (tx1, ty1) = (tx0 + w - 1, ty0 + h - 1);
        for t in m.block_tets_where(b, |_| true, &mut Vec::new()) {
            if self
                .screen
                .tet_rect_padded(&t.v, self.pad)
                .is_some_and(|r| r.0 <= tx1 && r.1 >= tx0 && r.2 <= ty1 && r.3 >= ty0)
            {
                on_tet(t);
            }
        }
    }

    /// Tile `i`'s pixel rectangle `(x0, y0, w, h)`.
    pub fn tile(&self, i: u32) -> (u32, u32, u32, u32) {
        let t = self.tile_size;
        let (x0, y0) = ((i % self.tiles_x) * t, (i / self.tiles_x) * t);
        (
            x0,
            y0,
            t.min(self.screen.width - x0),
            t.min(self.screen.height - y0),
        )
    }

    /// The rays through the centres of tile `i`'s pixels, row-major.
    pub fn rays(&self, i: u32) -> Vec<Ray> {
        let (x0, y0, w, h) = self.tile(i);
        let mut rays = Vec::with_capacity((w * h) as usize);
        for y in y0..y0 + h {
            for x in x0..x0 + w {
                rays.push(self.screen.ray(x, y));
            }
        }
        rays
    }
}
