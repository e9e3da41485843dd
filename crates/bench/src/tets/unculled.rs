//! The block-culling baseline: a tessellation whose tile view rasterises
//! every block in every tile.
//!
//! The library's tile view (`voxless_tets::TetTileView`) only visits the
//! blocks `raster::Frame` bins to a tile. [`Binned`] wraps a `TetVolume`
//! with its own tile view built from the public raster pieces — a `Frame`
//! whose bins it may replace, `for_each_crossing` for the crossings and
//! `events::sort_and_sweep` for the constant pieces — so the same integrator renders
//! both variants and only the bins differ. With the frame's own bins
//! ([`Bins::Culled`]) it must give the library's image (tested below, and
//! reported by the culling table as its correctness check). Exact mode
//! only: no k-buffer, no level of detail.

use std::sync::OnceLock;

use voxless_core::{
    Aabb, Camera, Interval, IntervalLists, IntervalQuery, Prepare, PrepareQuery, Range1, Ray,
    Sample, TileIntervals, TileRays, Vec3, View, Volume,
};
use voxless_tets::events::{event, sort_and_sweep};
use voxless_tets::raster::{Frame, TILE, for_each_crossing, for_each_crossing_jittered};
use voxless_tets::{TetMesh, TetVolume};

/// Which blocks a tile visits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bins {
    /// The blocks whose screen box overlaps the tile (the library's culling).
    Culled,
    /// Every block in every tile.
    All,
}

/// A tessellation rendered through a tile view with the chosen bins.
pub struct Binned<'a> {
    pub volume: &'a TetVolume,
    pub bins: Bins,
}

impl Volume for Binned<'_> {
    fn bounds(&self) -> Aabb {
        self.volume.bounds()
    }
    fn value_range(&self) -> Range1 {
        self.volume.value_range()
    }
    fn sample(&self, p: Vec3) -> Option<Sample> {
        self.volume.sample(p)
    }
    fn gradient(&self, p: Vec3) -> Vec3 {
        self.volume.gradient(p)
    }
    fn intervals(&self, ray: &Ray, t: Range1, query: &IntervalQuery, out: &mut Vec<Interval>) {
        self.volume.intervals(ray, t, query, out)
    }
    fn line_integral(&self, ray: &Ray, t: Range1) -> f64 {
        self.volume.line_integral(ray, t)
    }
    fn tile_view(&self, view: &View) -> Option<Box<dyn TileIntervals + '_>> {
        let mesh = &self.volume.mesh;
        Some(Box::new(BinnedView {
            mesh,
            camera: view.camera,
            size: (view.width, view.height),
            bins: self.bins,
            centred: with_bins(
                Frame::new(mesh, &view.camera, view.width, view.height, None),
                self.bins,
                mesh,
            ),
            covering: OnceLock::new(),
        }))
    }
}

/// Needs nothing per render: exact mode, so the query's event budget and
/// level of detail do not apply.
impl<'v> Prepare for Binned<'v> {
    type Prepared<'a>
        = &'a Binned<'v>
    where
        Self: 'a;

    fn prepare<'a>(&'a self, _: &PrepareQuery) -> &'a Binned<'v> {
        self
    }
}

/// `frame` with its bins replaced as `bins` asks (level-0 block indices).
fn with_bins(mut frame: Frame, bins: Bins, mesh: &TetMesh) -> Frame {
    if bins == Bins::All {
        let every: Vec<u32> = (0..mesh.blocks().len() as u32).collect();
        frame.bins = vec![every; frame.bins.len()];
    }
    frame
}

struct BinnedView<'a> {
    mesh: &'a TetMesh,
    camera: Camera,
    size: (u32, u32),
    bins: Bins,
    /// Rectangles of pixel centres, for the first pass.
    centred: Frame,
    /// Rectangles of whole pixels, for jittered passes (built on first use).
    covering: OnceLock<Frame>,
}

impl TileIntervals for BinnedView<'_> {
    fn tile_size(&self) -> u32 {
        TILE
    }

    fn intervals(&self, tile: &TileRays, _: &IntervalQuery, out: &mut IntervalLists) {
        let spans: Vec<(f32, f32)> = tile
            .t
            .iter()
            .map(|t| {
                if t.is_empty() {
                    (1.0, 0.0)
                } else {
                    (t.lo, t.hi)
                }
            })
            .collect();
        let mut events: Vec<Vec<u64>> = vec![Vec::new(); tile.rays.len()];
        let visit = |p: usize, t0: f32, t1: f32, rho: f32| {
            events[p].extend([event(t0, rho), event(t1, -rho)]);
        };
        let index = |f: &Frame| (tile.y0 / TILE) * f.tiles_x + tile.x0 / TILE;
        if tile.centred {
            let f = &self.centred;
            for_each_crossing(self.mesh, f, index(f), tile.rays, &spans, visit);
        } else {
            let f = self.covering.get_or_init(|| {
                let (w, h) = self.size;
                let covering = Frame::covering(self.mesh, &self.camera, w, h, None, TILE);
                with_bins(covering, self.bins, self.mesh)
            });
            for_each_crossing_jittered(self.mesh, f, index(f), tile.rays, &spans, visit);
        }
        for ev in &mut events {
            sort_and_sweep(ev, &mut out.intervals);
            out.end_ray();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::common::image_diff;
    use voxless_core::Control;
    use voxless_render::RenderSettings;
    use voxless_tets::TetSettings;
    use voxless_tets::testing::folded_sheet;
    use voxless_transfer::TransferFunction;

    /// With the frame's own bins the wrapper renders the library's image;
    /// with every block in every tile it renders the same image (more work,
    /// same crossings), over a centred and a jittered pass.
    #[test]
    fn every_bin_choice_renders_the_library_image() {
        let vol = TetVolume::new(&folded_sheet(10, 7), &TetSettings::default(), 0).unwrap();
        let camera = Camera::framing(&vol.bounds(), 1.0);
        let tf = TransferFunction::default_for_density();
        let mut rs = RenderSettings::for_volume(&vol, 70, 70);
        rs.spp = 2;
        rs.opacity_scale *= 10.0;
        let library = voxless_render::render(&vol, &camera, &tf, &rs, &Control::new()).unwrap();
        assert!(
            library.pixels.iter().any(|p| p[3] > 0.05),
            "an empty image tests nothing"
        );
        for bins in [Bins::Culled, Bins::All] {
            let ours = voxless_render::render(
                &Binned { volume: &vol, bins },
                &camera,
                &tf,
                &rs,
                &Control::new(),
            )
            .unwrap();
            let (max, _) = image_diff(&ours, &library);
            assert!(max <= 1e-6, "{bins:?}: {max}");
        }
    }
}
