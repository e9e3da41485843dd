//! The tile hook of the [`crate::Volume`] seam: the intervals of every ray of
//! a screen tile at once.
//!
//! Integrators render the image in square tiles. For most kinds each ray
//! asks for its own intervals; a kind that can do better for a whole tile
//! (tessellations rasterise each tet once per tile and sort every pixel's
//! crossings) returns a [`TileIntervals`] from [`crate::Volume::tile_view`],
//! prepared once per camera and image size, and integrators then fill a
//! tile's [`IntervalLists`] with one call. Dynamic dispatch happens once per
//! tile, never per sample.

use crate::camera::Camera;
use crate::math::{Range1, Ray};
use crate::volume::{Interval, IntervalQuery};

/// Side of a square render tile in pixels: what integrators use unless a
/// volume's tile view asks for another.
pub const TILE: u32 = 16;

/// What a tile view is prepared for: the camera and the image size.
#[derive(Clone, Copy, Debug)]
pub struct View {
    pub camera: Camera,
    pub width: u32,
    pub height: u32,
}

/// The rays of one tile.
#[derive(Clone, Copy, Debug)]
pub struct TileRays<'a> {
    /// The tile's pixels: `x0..x0 + w`, `y0..y0 + h`, a tile of the grid of
    /// [`TileIntervals::tile_size`] squares.
    pub x0: u32,
    pub y0: u32,
    pub w: u32,
    pub h: u32,
    /// One ray per pixel, row-major.
    pub rays: &'a [Ray],
    /// Per ray, the part to integrate (already clipped to the volume's
    /// bounds, the clip box and `t ≥ 0`); empty when the ray misses.
    pub t: &'a [Range1],
    /// Whether every ray passes through its pixel's centre (the first pass;
    /// later passes jitter the rays over the pixel).
    pub centred: bool,
}

/// Per-ray interval lists of one tile, in one flat buffer.
#[derive(Clone, Debug, Default)]
pub struct IntervalLists {
    pub intervals: Vec<Interval>,
    /// Ray `r`'s intervals are `intervals[ends[r - 1]..ends[r]]` (from 0 for
    /// `r = 0`).
    pub ends: Vec<u32>,
}

impl IntervalLists {
    pub fn clear(&mut self) {
        self.intervals.clear();
        self.ends.clear();
    }

    /// Closes the current ray's list (the intervals pushed since the last
    /// call).
    #[inline]
    pub fn end_ray(&mut self) {
        self.ends.push(self.intervals.len() as u32);
    }

    /// Ray `r`'s intervals.
    #[inline]
    pub fn of(&self, r: usize) -> &[Interval] {
        let start = if r == 0 { 0 } else { self.ends[r - 1] as usize };
        &self.intervals[start..self.ends[r] as usize]
    }

    /// The number of closed lists.
    pub fn rays(&self) -> usize {
        self.ends.len()
    }
}

/// A volume's intervals for whole tiles of one view.
pub trait TileIntervals: Send + Sync {
    /// Side of the square tiles this view works on; integrators tile the
    /// image with it.
    fn tile_size(&self) -> u32;

    /// Fills `out` (cleared by the caller) with one closed list per ray of
    /// `tile`, in ray order, each as [`crate::Volume::intervals`] would give
    /// it for that ray and range.
    fn intervals(&self, tile: &TileRays, query: &IntervalQuery, out: &mut IntervalLists);
}
