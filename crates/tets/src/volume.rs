//! [`TetVolume`]: a tet mesh behind the `Volume` seam — exact constant
//! intervals per ray (through a point/ray index over the cells) and per
//! screen tile ([`crate::events::TetTileView`]), point samples (density and
//! stream count), exact line integrals and whole-image projections.
//!
//! What an operation needs is built by the first operation that needs it,
//! and kept: the point/ray index by point samples, single rays (shadows)
//! and per-ray integrals; the default density range by renders (it is a
//! transfer-function default); the levels of detail by renders that use
//! them. A projection builds none of these.

use std::sync::OnceLock;

use voxless_core::{
    Aabb, Camera, Cancelled, Control, EventBudget, Interval, IntervalQuery, Prepare, PrepareQuery,
    Range1, Ray, Sample, TileIntervals, Vec3, View, Volume,
};

use crate::TetError;
use crate::events::{TetTileView, event, sort_and_sweep};
use crate::index::TetIndex;
use crate::mesh::{LagrangianGrid, TetMesh, TetSettings};
use crate::raster::Planes;
use crate::render::{PixelIntegral, TetOptions, project};

pub struct TetVolume {
    pub mesh: TetMesh,
    index: OnceLock<TetIndex>,
    bounds: Aabb,
    /// The default density range: given, or found on first use.
    value_range: OnceLock<Range1>,
    /// Level of detail for tile renders and projections (blocks smaller
    /// than this many pixels use the coarser levels); `None`: off.
    lod_pixels: Option<f32>,
    /// How whole-image projections integrate each pixel.
    pixels: PixelIntegral,
}

impl TetVolume {
    /// Tessellates `grid`, with `lod_levels` coarser levels of detail (0 for
    /// none; built when a render first uses them). Copies the positions
    /// ([`TetVolume::from_grid`] keeps them).
    pub fn new(
        grid: &LagrangianGrid,
        settings: &TetSettings,
        lod_levels: usize,
    ) -> Result<TetVolume, TetError> {
        let mesh = TetMesh::new(grid, settings)?;
        Ok(TetVolume::from_mesh(mesh.with_lod(lod_levels)))
    }

    /// [`TetVolume::new`], keeping the grid's positions as the mesh's.
    pub fn from_grid(
        grid: LagrangianGrid,
        settings: &TetSettings,
        lod_levels: usize,
    ) -> Result<TetVolume, TetError> {
        let mesh = TetMesh::from_grid(grid, settings)?;
        Ok(TetVolume::from_mesh(mesh.with_lod(lod_levels)))
    }

    /// A volume over a mesh built elsewhere (a sub-block cut out of a run,
    /// a mesh assembled tet by tet): its bounds are the mesh's box
    /// `[0, box_size)³`, which must hold every tet. Its default density
    /// range is found when first asked for.
    pub fn from_mesh(mesh: TetMesh) -> TetVolume {
        TetVolume::with_range(mesh, OnceLock::new())
    }

    /// A volume over part of a decomposed run (the tets reaching into one
    /// box) with the whole run's density range; its bounds are the whole
    /// box `[0, box_size)³` like the whole run's.
    pub fn from_parts(mesh: TetMesh, value_range: Range1) -> TetVolume {
        TetVolume::with_range(mesh, OnceLock::from(value_range))
    }

    fn with_range(mesh: TetMesh, value_range: OnceLock<Range1>) -> TetVolume {
        // The periodic box: image tets fill it exactly, and outside it they
        // would double what the originals show.
        let bounds = Aabb::new(Vec3::ZERO, Vec3::splat(mesh.box_size));
        TetVolume {
            mesh,
            index: OnceLock::new(),
            bounds,
            value_range,
            lod_pixels: None,
            pixels: PixelIntegral::default(),
        }
    }

    /// How whole-image projections integrate each pixel (see
    /// [`PixelIntegral`]).
    pub fn with_pixel_integral(mut self, pixels: PixelIntegral) -> Self {
        self.pixels = pixels;
        self
    }

    /// The projections' pixel integral.
    pub fn pixel_integral(&self) -> PixelIntegral {
        self.pixels
    }

    /// Draws blocks smaller than `pixels` on screen from the coarser levels
    /// of detail (when the mesh has them).
    pub fn with_lod_pixels(mut self, pixels: Option<f32>) -> Self {
        self.lod_pixels = pixels;
        self
    }

    /// The level-of-detail threshold in pixels, if on.
    pub fn lod_pixels(&self) -> Option<f32> {
        self.lod_pixels
    }

    /// The point/ray index, built on first use.
    fn index(&self) -> &TetIndex {
        self.index.get_or_init(|| TetIndex::build(&self.mesh))
    }

    /// Whether the point/ray index has been built (by a point sample, a
    /// single ray or a per-ray integral).
    pub fn has_index(&self) -> bool {
        self.index.get().is_some()
    }

    /// The Lagrangian spacing L/N: the scale of the smoothed gradient.
    fn spacing(&self) -> f32 {
        self.mesh.box_size / self.mesh.n as f32
    }

    /// Density ρ (sum over the covering tets) and stream count at `p`,
    /// wrapped periodically into the box.
    ///
    /// Tets share faces, edges and vertices (all six of a cell share its main
    /// diagonal, which passes through the cell centre), and a point exactly on
    /// one would count in every tet touching it. So the point is nudged by
    /// 1e-4 of the Lagrangian spacing (at least a few ulps) along a fixed
    /// direction that no tessellation face contains; the density is
    /// discontinuous only across faces, so this changes nothing elsewhere.
    ///
    /// The densities are added in increasing order, so the sum's bits do not
    /// depend on how the tets are stored: a part of a decomposed run that
    /// holds every tet covering the point gives the same value.
    pub fn density_and_streams(&self, p: Vec3) -> (f64, u32) {
        let p = self.canonical_point(p);
        let mut covering: Vec<f32> = Vec::new();
        self.index().at_point(&self.mesh, p, |t| {
            if t.contains(p) {
                covering.push(t.density);
            }
        });
        covering.sort_unstable_by(f32::total_cmp);
        let rho = covering.iter().map(|&d| d as f64).sum();
        (rho, covering.len() as u32)
    }

    /// Where [`TetVolume::density_and_streams`] evaluates a query at `p`:
    /// nudged off the tessellation's faces and wrapped into the box (a
    /// decomposition routes the query to the box holding this point).
    pub fn canonical_point(&self, p: Vec3) -> Vec3 {
        canonical_point(self.mesh.box_size, self.mesh.n, p)
    }
}

impl Volume for TetVolume {
    fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Density range used by default with a log10 transfer function
    /// (found on first use: see [`density_range`]).
    fn value_range(&self) -> Range1 {
        *self
            .value_range
            .get_or_init(|| density_range(&self.mesh, &mut sampled_densities(&self.mesh)))
    }

    fn sample(&self, p: Vec3) -> Option<Sample> {
        let (rho, streams) = self.density_and_streams(p);
        (streams > 0).then(|| Sample::scalar(rho as f32))
    }

    /// The density is constant inside each tet, so its gradient is zero
    /// there and a jump across faces. For shading iso-surfaces (which lie on
    /// faces) this is the gradient of the density smoothed over a quarter
    /// of the Lagrangian spacing: central differences at that step.
    fn gradient(&self, p: Vec3) -> Vec3 {
        let h = 0.25 * self.spacing();
        let f = |q: Vec3| self.density_and_streams(q).0 as f32;
        let d = |e: Vec3| (f(p + e * h) - f(p - e * h)) / (2.0 * h);
        Vec3::new(
            d(Vec3::new(1.0, 0.0, 0.0)),
            d(Vec3::new(0.0, 1.0, 0.0)),
            d(Vec3::new(0.0, 0.0, 1.0)),
        )
    }

    /// Exact constant pieces: every tet the ray crosses within `t` (BVH ray
    /// traversal, plane clip), events sorted and swept. Every piece of
    /// positive density is handed out, visible or not.
    fn intervals(&self, ray: &Ray, t: Range1, _: &IntervalQuery, out: &mut Vec<Interval>) {
        let mut events = Vec::new();
        self.index().along_ray(&self.mesh, ray, t, |tet| {
            let (a, b) = Planes::new(tet).clip(ray);
            let (a, b) = (a.max(t.lo), b.min(t.hi));
            if b > a {
                events.extend([event(a, tet.density), event(b, -tet.density)]);
            }
        });
        sort_and_sweep(&mut events, out);
    }

    fn tile_view(&self, view: &View) -> Option<Box<dyn TileIntervals + '_>> {
        Some(Box::new(TetTileView::new(
            &self.mesh,
            &view.camera,
            view.width,
            view.height,
            self.lod_pixels,
            None,
        )))
    }

    /// Exact: Σ ρ × chord over every tet the ray crosses within `t`.
    fn line_integral(&self, ray: &Ray, t: Range1) -> f64 {
        let mut sum = 0.0f64;
        self.index().along_ray(&self.mesh, ray, t, |tet| {
            let (a, b) = Planes::new(tet).clip(ray);
            let (a, b) = (a.max(t.lo), b.min(t.hi));
            if b > a {
                sum += tet.density as f64 * (b - a) as f64;
            }
        });
        sum
    }

    /// Per screen tile, every tet's column added to the pixels it covers
    /// (eight pixels at a time for orthographic views), plus the point
    /// masses of degenerate tets.
    fn project_image(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        control: &Control,
    ) -> Option<Result<Vec<f32>, Cancelled>> {
        let options = TetOptions {
            lod_pixels: self.lod_pixels,
            pixels: self.pixels,
            ..Default::default()
        };
        Some(project(&self.mesh, camera, width, height, options, control))
    }
}

/// A tessellation prepared for one render: the k-buffer budget, if any,
/// and the level-of-detail threshold (the render's, else the volume's).
pub struct TetContext<'a> {
    volume: &'a TetVolume,
    budget: Option<EventBudget>,
    lod_pixels: Option<f32>,
}

impl Prepare for TetVolume {
    type Prepared<'a> = TetContext<'a>;

    fn prepare<'a>(&'a self, query: &PrepareQuery) -> TetContext<'a> {
        TetContext {
            volume: self,
            budget: query.event_budget,
            lod_pixels: query.lod_pixels.or(self.lod_pixels),
        }
    }
}

impl Volume for TetContext<'_> {
    voxless_core::forward_volume! {
        to self.volume;
        except tile_view;
    }
    /// The mesh rasterised per tile with the render's level of detail and
    /// k-buffer budget.
    fn tile_view(&self, view: &View) -> Option<Box<dyn TileIntervals + '_>> {
        Some(Box::new(TetTileView::new(
            &self.volume.mesh,
            &view.camera,
            view.width,
            view.height,
            self.lod_pixels,
            self.budget,
        )))
    }
}

/// [`TetVolume::canonical_point`] for a run of N³ particles in a box of
/// size `l`.
pub fn canonical_point(l: f32, n: usize, p: Vec3) -> Vec3 {
    let nudge = (1e-4 * l / n as f32).max(8.0 * l * f32::EPSILON);
    let p = p + Vec3::new(0.812_403_8, 0.445_259_4, 0.376_556_9) * nudge;
    Vec3::new(p.x.rem_euclid(l), p.y.rem_euclid(l), p.z.rem_euclid(l))
}

/// The default density range takes every this-many-th tet of a mesh of
/// `tets` tets (in mesh order).
pub fn density_stride(tets: usize) -> usize {
    (tets / 100_000).max(1)
}

/// The densities of every [`density_stride`]-th tet of `mesh` in mesh
/// order (what [`density_range`] takes), block by block in parallel.
pub fn sampled_densities(mesh: &TetMesh) -> Vec<f32> {
    use rayon::prelude::*;
    let stride = density_stride(mesh.tet_count()) as u64;
    let per_block: Vec<Vec<f32>> = (0..mesh.blocks().len())
        .into_par_iter()
        .map(|b| {
            let range = mesh.blocks()[b].tets.clone();
            // The first multiple of the stride in the block's range.
            let first = range.start.div_ceil(stride) * stride;
            if first >= range.end {
                return Vec::new();
            }
            let picked = (first..range.end).step_by(stride as usize);
            // Most blocks hold six tets a cell: each picked tet alone.
            let alone: Option<Vec<f32>> = picked
                .clone()
                .map(|i| {
                    mesh.complete_block_tet(b, i - range.start)
                        .map(|t| t.density)
                })
                .collect();
            alone.unwrap_or_else(|| {
                let mut buf = Vec::new();
                let tets = mesh.block_tets(b, &mut buf);
                picked
                    .map(|i| tets[(i - range.start) as usize].density)
                    .collect()
            })
        })
        .collect();
    per_block.concat()
}

/// The default density range of a run (log10 by default): from the mean
/// density (voids stay transparent) to the 99.9th percentile of `sample`,
/// the densities of every [`density_stride`]-th tet in mesh order.
pub fn density_range(mesh: &TetMesh, sample: &mut [f32]) -> Range1 {
    let mean = mesh.total_mass() / (mesh.box_size as f64).powi(3);
    let at = ((sample.len() as f64 * 0.999) as usize).min(sample.len().saturating_sub(1));
    let high = if sample.is_empty() {
        mean as f32
    } else {
        *sample.select_nth_unstable_by(at, f32::total_cmp).1
    };
    Range1::new(mean as f32, high.max(mean as f32 * 10.0))
}
