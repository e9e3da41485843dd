//! [`AmrContext`]: an AMR volume prepared for one transfer function — a
//! mask over the region tree marking the subtrees that hold a region it
//! can see (TF space skipping, ExaBricks §4.1), so rays walk past hidden
//! regions without visiting them. The volume itself stays untouched, so
//! several contexts (different transfer functions) can render it at once.
//!
//! A context's intervals are the regions visible under the function it
//! was prepared with, whatever an [`IntervalQuery`] says: the renderer
//! asks with that same function, and asking it again for every region a
//! ray crosses cost 5 % of an AMR frame. (A narrower query would get
//! regions it calls invisible, which composite to nothing; a wider one
//! never gets the hidden regions — prepare another context for it.)

use std::time::{Duration, Instant};

use voxless_core::{
    Interval, IntervalLists, IntervalQuery, Prepare, PrepareQuery, Range1, Ray, Sample,
    SampleBatch, Simd, TILE, TileIntervals, TileRays, Vec3, View, Volume,
};

use crate::AmrVolume;
use crate::walk::NodeMask;

pub struct AmrContext<'a> {
    volume: &'a AmrVolume,
    /// The subtrees holding a visible region; `None` when every region is
    /// visible.
    visible: Option<NodeMask>,
    visible_count: usize,
    selected_in: Duration,
    /// The SIMD backend of the packet path.
    simd: Simd,
}

impl<'a> AmrContext<'a> {
    /// Selects the regions whose range of the opacity field `is_visible`
    /// accepts and marks the subtrees of the region tree holding them (one
    /// sweep over the tree: no tree is built per transfer function).
    pub fn new(volume: &'a AmrVolume, is_visible: &dyn Fn(Range1) -> bool) -> Self {
        let t = Instant::now();
        let (visible, visible_count) = volume.visible_mask(is_visible);
        AmrContext {
            volume,
            visible,
            visible_count,
            selected_in: t.elapsed(),
            simd: Simd::Auto,
        }
    }

    /// How many regions the transfer function can see.
    pub fn visible_region_count(&self) -> usize {
        self.visible_count
    }

    /// How long selecting the regions and marking the tree took.
    pub fn selected_in(&self) -> Duration {
        self.selected_in
    }

    /// The same context with the packet path on the SIMD backend `simd`.
    pub fn with_simd(self, simd: Simd) -> Self {
        AmrContext { simd, ..self }
    }

    pub fn volume(&self) -> &AmrVolume {
        self.volume
    }
}

impl Prepare for AmrVolume {
    type Prepared<'a> = AmrContext<'a>;

    fn prepare<'a>(&'a self, query: &PrepareQuery) -> AmrContext<'a> {
        AmrContext::new(self, query.is_visible).with_simd(query.simd)
    }
}

impl Volume for AmrContext<'_> {
    voxless_core::forward_volume! {
        to self.volume;
        except sample_batch, sample_batch_values, sample_values_lanes, intervals,
            intervals_chunk, tile_view;
    }
    /// The volume's packet path on the context's SIMD backend.
    fn sample_batch(
        &self,
        batch: &SampleBatch,
        gradient: bool,
        out: &mut Vec<(Option<Sample>, Vec3)>,
    ) {
        self.volume.sample_batch_on(self.simd, batch, gradient, out)
    }
    fn sample_batch_values(&self, batch: &SampleBatch, out: &mut Vec<f32>) -> bool {
        self.volume.sample_batch_values_on(self.simd, batch, out)
    }
    #[inline(always)]
    fn sample_values_lanes<L: voxless_core::Lanes>(
        &self,
        hints: &[u32; voxless_core::simd::LANES],
        p: [L; 3],
        live: u32,
    ) -> L {
        self.volume.values_lanes(hints, p, live)
    }
    /// The regions the context's transfer function sees (see
    /// [`AmrContext`]): only the subtrees holding them are walked, and the
    /// query is not asked again per region.
    fn intervals(&self, ray: &Ray, t: Range1, _: &IntervalQuery, out: &mut Vec<Interval>) {
        self.volume
            .region_intervals(self.visible.as_ref(), ray, t, |_| true, out, usize::MAX);
    }
    fn intervals_chunk(
        &self,
        ray: &Ray,
        t: Range1,
        _: &IntervalQuery,
        out: &mut Vec<Interval>,
        max: usize,
    ) -> Option<f32> {
        self.volume
            .region_intervals(self.visible.as_ref(), ray, t, |_| true, out, max)
    }
    /// Every ray's whole list, the tile's rays walking the region tree
    /// eight at a time (the same lists as [`Volume::intervals`], bit for
    /// bit). Lists are no longer asked for lazily, so a ray that turns
    /// opaque has its regions behind found anyway; a packet walk costs a
    /// fraction of eight single walks, which more than pays for that on
    /// the frames measured (docs/benchmarks.md).
    fn tile_view(&self, _: &View) -> Option<Box<dyn TileIntervals + '_>> {
        Some(Box::new(AmrTileView {
            volume: self.volume,
            mask: self.visible.as_ref(),
            simd: self.simd,
        }))
    }
}

/// A context's tile view: the region tree walked by packets of rays.
struct AmrTileView<'a> {
    volume: &'a AmrVolume,
    mask: Option<&'a NodeMask>,
    /// The SIMD backend of the packet walk.
    simd: Simd,
}

impl TileIntervals for AmrTileView<'_> {
    /// The integrators' own tile size (their default without a view).
    fn tile_size(&self) -> u32 {
        TILE
    }
    fn intervals(&self, tile: &TileRays, _: &IntervalQuery, out: &mut IntervalLists) {
        self.volume.tile_intervals(
            (self.mask, self.simd),
            (tile.rays, tile.t, tile.w as usize),
            out,
        );
    }
}
