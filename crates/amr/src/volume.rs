//! [`AmrVolume`]: construction, intervals and the `Volume` impl; the
//! reconstruction ([`recon`]), its packet form ([`batch`], eight samples
//! at a time in [`lanes`]), the octant reconstruction ([`octant`]), the
//! exact nearest-reconstruction answers ([`nearest`]), the parts built on
//! first use ([`parts`]) and the cell-location baseline ([`locator`]) live
//! beside it.

mod batch;
mod columns;
mod lanes;
mod locator;
mod nearest;
mod octant;
mod parts;
mod recon;

use rayon::prelude::*;
use std::sync::{Arc, Mutex, OnceLock};

pub(crate) use parts::InputCells;
use parts::{Bricked, RegionIndex, build_apart, to_world};
use std::time::{Duration, Instant};

use voxless_core::{
    Aabb, Camera, Cancelled, Control, Interval, IntervalLists, IntervalQuery, Range1, Ray, Sample,
    SampleBatch, Simd, Vec3, Volume,
};

use crate::AmrError;
use crate::bricks::{self, Brick};
use crate::regions::{Region, Regions};
use crate::walk::{NodeMask, PACKET_RAYS, RegionTree, same_octant};

pub use locator::CellLocator;

thread_local! {
    /// Per ray of a packet, its intervals while a tile's packets walk
    /// ([`AmrVolume::tile_intervals`]), kept between tiles.
    static TILE_LISTS: std::cell::Cell<Vec<Vec<Interval>>> = const { std::cell::Cell::new(Vec::new()) };
}

/// Cells and fields as read from a file.
#[derive(Clone, Debug, Default)]
pub struct AmrCells {
    /// `(x, y, z, level)`, finest units, level 0 finest.
    pub cells: Vec<[i32; 4]>,
    /// Name and one value per cell.
    pub fields: Vec<(String, Vec<f32>)>,
    /// World position of unit coordinate 0.
    pub origin: Vec3,
    /// World width of a finest cell.
    pub cell_size: f32,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Reconstruction {
    /// Tent basis functions, continuous across levels (default).
    #[default]
    Basis,
    /// The value of the containing cell.
    Nearest,
    /// Trilinear on the dual grid in level-aware octant boxes (Wang et
    /// al. 2019, Open VKL's `octant`): C⁰ everywhere, exact for linear
    /// fields on one level; see `volume/octant.rs`.
    Octant,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct AmrSettings {
    /// Field driving opacity (index into the fields).
    pub field: usize,
    /// Field driving colour, when different (multi-field rendering).
    pub color_field: Option<usize>,
    pub reconstruction: Reconstruction,
}

/// Counts and timings of the build (the paper's Table 1 columns).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BuildStats {
    pub cells: usize,
    pub bricks: usize,
    pub regions: usize,
    /// Mean bricks per region, by count and weighted by region volume.
    pub bricks_per_region: f64,
    pub bricks_per_region_by_volume: f64,
    pub validate: Duration,
    pub brick_build: Duration,
    pub region_build: Duration,
    pub bvh_build: Duration,
}

pub struct AmrVolume {
    names: Vec<String>,
    origin: Vec3,
    h: f32,
    settings: AmrSettings,
    field_ranges: Vec<Range1>,
    /// The validated cells and their fields in input order, until the
    /// bricks are built from them (`None` after).
    cells: Mutex<Option<Arc<InputCells>>>,
    /// The bricks, built on first use: an on-axis projection of the
    /// nearest cells sums the cells themselves.
    bricked: OnceLock<Bricked>,
    /// The active brick regions and what walks and samples read of them,
    /// built on first use after the bricks.
    index: OnceLock<RegionIndex>,
    /// ∫ opacity field dV of the cells (nearest reconstruction), finest
    /// units.
    integral: f64,
    bounds: Aabb,
    stats: BuildStats,
}

impl AmrVolume {
    /// Validates the cells and keeps them, with each field's range, the
    /// bounds and the exact integral; the bricks, their BVH and the regions
    /// are built on first use (`volume/parts.rs`), so a nearest projection down an
    /// axis never builds them.
    pub fn new(input: AmrCells, settings: AmrSettings) -> Result<AmrVolume, AmrError> {
        let n = input.cells.len();
        if input.fields.is_empty() {
            return Err(AmrError::NoFields);
        }
        // Each field's range, and its first value that is not finite, in
        // chunks on every core.
        let mut field_ranges = Vec::with_capacity(input.fields.len());
        for (name, v) in &input.fields {
            if v.len() != n {
                return Err(AmrError::FieldLength {
                    name: name.clone(),
                    expected: n,
                    got: v.len(),
                });
            }
            let parts: Vec<(Range1, Option<usize>)> = v
                .par_chunks(1 << 14)
                .enumerate()
                .map(|(k, chunk)| {
                    let bad = chunk.iter().position(|x| !x.is_finite());
                    let range = chunk.iter().fold(Range1::EMPTY, |mut r, &x| {
                        r.extend(x);
                        r
                    });
                    (range, bad.map(|i| (k << 14) + i))
                })
                .collect();
            if let Some(i) = parts.iter().find_map(|p| p.1) {
                return Err(AmrError::NonFinite {
                    name: name.clone(),
                    cell: i,
                    value: v[i],
                });
            }
            field_ranges.push(parts.iter().fold(Range1::EMPTY, |r, p| r.union(p.0)));
        }
        if !input.origin.is_finite() {
            return Err(AmrError::BadGeometry {
                what: "origin component",
                value: [input.origin.x, input.origin.y, input.origin.z]
                    .into_iter()
                    .find(|v| !v.is_finite())
                    .unwrap_or(f32::NAN),
                extra: "",
            });
        }
        if !(input.cell_size.is_finite() && input.cell_size > 0.0) {
            return Err(AmrError::BadGeometry {
                what: "cell size",
                value: input.cell_size,
                extra: " and > 0",
            });
        }
        let nf = input.fields.len();
        for f in std::iter::once(settings.field).chain(settings.color_field) {
            if f >= nf {
                return Err(AmrError::UnknownField {
                    name: format!("#{f}"),
                    available: input
                        .fields
                        .iter()
                        .map(|f| f.0.as_str())
                        .collect::<Vec<_>>()
                        .join(", "),
                });
            }
        }
        let mut stats = BuildStats {
            cells: n,
            ..Default::default()
        };
        let t = Instant::now();
        let (lo, hi) = bricks::validate(&input.cells)?;
        stats.validate = t.elapsed();
        let (names, fields): (Vec<String>, Vec<Vec<f32>>) = input.fields.into_iter().unzip();
        // ∫ field dV of the cells, in a fixed order (cell order, then the
        // parts' sums): the same bits however the volume is used first.
        let integral = input
            .cells
            .par_chunks(1 << 14)
            .zip(fields[settings.field].par_chunks(1 << 14))
            .map(|(c, v)| {
                c.iter()
                    .zip(v)
                    .map(|(c, &v)| v as f64 * (1u64 << (3 * c[3])) as f64)
                    .sum::<f64>()
            })
            .collect::<Vec<f64>>()
            .into_iter()
            .sum();
        // The data's domain is the cells, not the tents' half-cell margin
        // around them: bounds, intervals and samples stop at the cells.
        let bounds = to_world(input.origin, input.cell_size, lo, hi);
        Ok(AmrVolume {
            names,
            origin: input.origin,
            h: input.cell_size,
            settings,
            field_ranges,
            cells: Mutex::new(Some(Arc::new(InputCells {
                cells: input.cells,
                fields,
            }))),
            bricked: OnceLock::new(),
            index: OnceLock::new(),
            integral,
            bounds,
            stats,
        })
    }

    /// The bricks, built on first use (see [`build_apart`]).
    #[inline]
    fn bx(&self) -> &Bricked {
        self.bricked.get_or_init(|| {
            let input = self
                .take_cells()
                .expect("the cells stay until the bricks take them");
            let octant = self.settings.reconstruction == Reconstruction::Octant;
            build_apart(|| Bricked::build(input, self.origin, self.h, octant))
        })
    }

    fn take_cells(&self) -> Option<Arc<InputCells>> {
        self.cells.lock().unwrap_or_else(|e| e.into_inner()).take()
    }

    /// Runs `f` on the cells in input order while no bricks hold them;
    /// `None` once they do. The lock is held only to share them.
    pub(crate) fn with_cells<T>(&self, f: impl FnOnce(&InputCells) -> T) -> Option<T> {
        let cells = self.cells.lock().unwrap_or_else(|e| e.into_inner()).clone();
        cells.as_deref().map(f)
    }

    /// The build's counts and timings, the regions' included (which
    /// builds them if nothing has yet).
    pub fn stats(&self) -> BuildStats {
        let (r, b) = (&self.ix().stats, &self.bx().stats);
        BuildStats {
            bricks: b.bricks,
            brick_build: b.brick_build,
            regions: r.regions,
            bricks_per_region: r.bricks_per_region,
            bricks_per_region_by_volume: r.bricks_per_region_by_volume,
            region_build: r.region_build,
            bvh_build: b.bvh_build + r.bvh_build,
            ..self.stats.clone()
        }
    }

    /// The region index, built on first use.
    #[inline]
    fn ix(&self) -> &RegionIndex {
        self.index.get_or_init(|| {
            let b = self.bx();
            build_apart(|| RegionIndex::build(&b.bricks, &b.values, self.origin, self.h))
        })
    }
    pub fn field_names(&self) -> &[String] {
        &self.names
    }
    pub fn bricks(&self) -> &[Brick] {
        &self.bx().bricks
    }
    pub fn regions(&self) -> &[Region] {
        &self.ix().regions.regions
    }
    /// The regions with their brick lists and the k-d tree that cut them.
    pub fn region_set(&self) -> &Regions {
        &self.ix().regions
    }
    /// The bricks active in region `r`.
    pub fn region_bricks(&self, r: usize) -> &[u32] {
        self.ix().regions.bricks_of(r)
    }
    pub fn settings(&self) -> &AmrSettings {
        &self.settings
    }
    /// World box of region `r`.
    pub fn region_bounds(&self, r: usize) -> Aabb {
        self.ix().region_bounds[r]
    }
    /// Value range of `field` in region `r`.
    #[inline]
    pub fn region_range(&self, r: usize, field: usize) -> Range1 {
        self.ix().region_ranges[r * self.names.len() + field]
    }
    /// Range of `field` over all cells.
    pub fn field_range(&self, field: usize) -> Range1 {
        self.field_ranges[field]
    }

    /// The intervals of the regions `ray` crosses within `t` that `mask`
    /// (all when `None`) and `keep` (given the region's value range)
    /// accept, front to back, stopping after `max`; returns where the rest
    /// begins (see [`Volume::intervals_chunk`]).
    #[inline]
    pub(crate) fn region_intervals(
        &self,
        mask: Option<&NodeMask>,
        ray: &Ray,
        t: Range1,
        keep: impl Fn(Range1) -> bool,
        out: &mut Vec<Interval>,
        max: usize,
    ) -> Option<f32> {
        let t = self.bounds.clip_ray(ray, t);
        if t.is_empty() || max == 0 {
            return None;
        }
        let (start, mut left) = (out.len(), max);
        // Where the walk stopped short of a region that would have opened
        // interval `max + 1`: the next call starts there.
        let mut refused = None;
        let rest = self.ix().tree.walk(ray, t, mask, |r, hit| {
            let r = r as usize;
            let range = self.region_range(r, self.settings.field);
            if !keep(range) || self.extend_last(&mut out[start..], r, hit, range) {
                return true;
            }
            if left == 0 {
                refused = Some(hit.lo);
                return false;
            }
            out.push(self.region_interval(r, hit, range));
            left -= 1;
            true
        });
        refused.or(rest)
    }

    /// The intervals of every ray of a tile at once (see
    /// [`crate::AmrContext`]'s tile view): each ray's list as
    /// [`AmrVolume::region_intervals`] gives it whole, the rays walked
    /// through the region tree eight at a time (by octant of direction
    /// within each eight).
    pub(crate) fn tile_intervals(
        &self,
        (mask, simd): (Option<&NodeMask>, Simd),
        (rays, t, w): (&[Ray], &[Range1], usize),
        out: &mut IntervalLists,
    ) {
        let n = rays.len().min(t.len());
        let w = w.clamp(1, n.max(1));
        let mut lists = TILE_LISTS.take();
        lists.resize_with(n.max(lists.len()), Vec::new);
        lists[..n].iter_mut().for_each(Vec::clear);
        // Packets of 4 × 2 pixels (closer together than a row of eight).
        let blocks = (0..n.div_ceil(w))
            .step_by(2)
            .flat_map(|y| (0..w).step_by(4).map(move |x| (x, y)));
        for (bx, by) in blocks {
            let mut members = [0usize; PACKET_RAYS];
            let mut count = 0;
            for dy in 0..2 {
                for dx in 0..4 {
                    let (x, y) = (bx + dx, by + dy);
                    if x < w && y * w + x < n {
                        members[count] = y * w + x;
                        count += 1;
                    }
                }
            }
            // Rays of one octant walk together; a packet that straddles an
            // axis direction walks once per octant.
            let mut todo = (1u32 << count) - 1;
            while todo != 0 {
                let lead = rays[members[todo.trailing_zeros() as usize]];
                let (mut lanes, mut sub, mut sub_t) = (
                    [0; PACKET_RAYS],
                    [lead; PACKET_RAYS],
                    [Range1::EMPTY; PACKET_RAYS],
                );
                let mut m = 0;
                for (k, &r) in members[..count].iter().enumerate() {
                    if todo >> k & 1 != 0 && same_octant(&rays[r], &lead) {
                        (lanes[m], sub[m], sub_t[m]) =
                            (r, rays[r], self.bounds.clip_ray(&rays[r], t[r]));
                        todo &= !(1 << k);
                        m += 1;
                    }
                }
                self.ix()
                    .tree
                    .walk_packet(simd, &sub[..m], &sub_t[..m], mask, |j, r, hit| {
                        let (list, r) = (&mut lists[lanes[j]], r as usize);
                        let range = self.region_range(r, self.settings.field);
                        if !self.extend_last(list, r, hit, range) {
                            list.push(self.region_interval(r, hit, range));
                        }
                    });
            }
        }
        for list in &lists[..n] {
            out.intervals.extend_from_slice(list);
            out.end_ray();
        }
        TILE_LISTS.set(lists);
    }

    /// Region `r`'s part `hit` of a ray as the next entry of `list` (the
    /// ray's intervals so far): when the region goes on with the last one,
    /// extends it and returns true; else returns false (the caller adds
    /// [`AmrVolume::region_interval`]). Extending happens only within one
    /// list, so chunks cut a ray's intervals where a whole walk puts a new
    /// one.
    #[inline]
    fn extend_last(&self, list: &mut [Interval], r: usize, hit: Range1, range: Range1) -> bool {
        match list.last_mut() {
            Some(last) if self.goes_on(last, hit.lo, r) => {
                last.t.hi = hit.hi;
                last.value_range = last.value_range.union(range);
                true
            }
            _ => false,
        }
    }

    /// Region `r`'s part `hit` of a ray as an interval: sampled at two
    /// samples per finest cell at sampling rate 1 (adaptive sampling,
    /// ExaBricks §4.2), the region as its hint.
    #[inline]
    fn region_interval(&self, r: usize, hit: Range1, range: Range1) -> Interval {
        let dt = 0.5 * self.ix().region_finest[r] as f32 * self.h;
        Interval {
            hint: r as u32,
            ..Interval::sampled(hit, range, dt)
        }
    }

    /// Whether region `r`, whose part of the ray starts at `lo`, goes on
    /// with interval `last`: it touches it and has the same brick list
    /// (the same field and step; the sample lattice is not cut at the seam
    /// anyway).
    #[inline]
    fn goes_on(&self, last: &Interval, lo: f32, r: usize) -> bool {
        last.t.hi == lo && self.ix().region_group[last.hint as usize] == self.ix().region_group[r]
    }

    /// The same intervals as [`AmrVolume::region_intervals`] found the
    /// way the walk replaced: every region the region BVH hits, then
    /// sorted. The reference the walk is tested against.
    #[cfg(test)]
    pub(crate) fn region_intervals_sorted(
        &self,
        ray: &Ray,
        t: Range1,
        query: &IntervalQuery,
        out: &mut Vec<Interval>,
    ) {
        let start = out.len();
        let nf = self.names.len();
        let t = self.bounds.clip_ray(ray, t);
        if t.is_empty() {
            return;
        }
        self.ix().region_bvh.ray_query(ray, t, |r, hit| {
            let r = r as usize;
            let range = self.ix().region_ranges[r * nf + self.settings.field];
            if hit.hi > hit.lo && (query.is_visible)(range) {
                out.push(Interval {
                    hint: r as u32,
                    ..Interval::sampled(
                        hit,
                        range,
                        0.5 * self.ix().region_finest[r] as f32 * self.h,
                    )
                });
            }
        });
        out[start..].sort_unstable_by(|a, b| a.t.lo.total_cmp(&b.t.lo));
        // Touching regions of one brick list are one interval, as in the
        // walk.
        let mut merged = start;
        for i in start..out.len() {
            let iv = out[i];
            if merged > start {
                let last = &mut out[merged - 1];
                if self.goes_on(last, iv.t.lo, iv.hint as usize) {
                    last.t.hi = iv.t.hi;
                    last.value_range = last.value_range.union(iv.value_range);
                    continue;
                }
            }
            out[merged] = iv;
            merged += 1;
        }
        out.truncate(merged);
    }

    /// The mask of the tree's subtrees holding a region whose range of the
    /// opacity field `is_visible` accepts (`None`: all of them).
    /// Also returns how many regions it accepts.
    pub(crate) fn visible_mask(
        &self,
        is_visible: &dyn Fn(Range1) -> bool,
    ) -> (Option<NodeMask>, usize) {
        let nf = self.names.len();
        let f = self.settings.field;
        let seen: Vec<bool> = (0..self.ix().regions.regions.len())
            .map(|r| is_visible(self.ix().region_ranges[r * nf + f]))
            .collect();
        let count = seen.iter().filter(|&&v| v).count();
        let mask = (count < seen.len()).then(|| self.ix().tree.mask(|r| seen[r as usize]));
        (mask, count)
    }

    /// How many regions a transfer function accepting `is_visible` sees.
    pub fn visible_region_count(&self, is_visible: &dyn Fn(Range1) -> bool) -> usize {
        let nf = self.names.len();
        let f = self.settings.field;
        (0..self.ix().regions.regions.len())
            .filter(|&r| is_visible(self.ix().region_ranges[r * nf + f]))
            .count()
    }

    /// Per region, its brick-list group (see `region_group`).
    #[cfg(test)]
    pub(crate) fn region_groups(&self) -> &[u32] {
        &self.ix().region_group
    }

    pub(crate) fn region_tree(&self) -> &RegionTree {
        &self.ix().tree
    }

    /// World position of unit coordinate 0.
    pub fn origin(&self) -> Vec3 {
        self.origin
    }
    /// World width of a finest cell.
    pub fn cell_size(&self) -> f32 {
        self.h
    }

    /// Values of `field`, in brick order.
    pub(crate) fn field_values(&self, field: usize) -> &[f32] {
        &self.bx().values[field]
    }

    fn to_units(&self, p: Vec3) -> Vec3 {
        (p - self.origin) * (1.0 / self.h)
    }

    /// The region containing `p` (world), if any.
    pub fn locate(&self, p: Vec3) -> Option<usize> {
        if !self.bounds.contains(p) {
            return None;
        }
        let mut found = None;
        self.ix().region_bvh.point_query(p, |i| {
            if found.is_none() {
                found = Some(i as usize);
            }
        });
        found
    }

    /// All fields at `p` (world): values, and gradients when asked, using the
    /// volume's reconstruction. `None` outside the data. The cells' terms are
    /// added in an order fixed by the terms, so the bits do not depend on
    /// how the cells were grouped into bricks and regions (the same for a
    /// whole volume and a part of it holding every cell that reaches `p`).
    pub fn fields_at(&self, p: Vec3, gradient: bool) -> Option<Vec<(f32, Vec3)>> {
        let r = self.locate(p)?;
        (0..self.names.len())
            .map(|f| {
                self.reconstruct_exact(p, r, f, gradient)
                    .map(|x| (x.value, x.gradient))
            })
            .collect()
    }
}

impl Volume for AmrVolume {
    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn value_range(&self) -> Range1 {
        self.field_ranges[self.settings.field]
    }

    fn attribute_range(&self) -> Option<Range1> {
        self.settings.color_field.map(|f| self.field_ranges[f])
    }

    fn sample(&self, p: Vec3) -> Option<Sample> {
        let r = self.locate(p)?;
        self.reconstruct(p, r, self.settings.field, false)
            .map(|x| self.to_sample(x))
    }

    fn gradient(&self, p: Vec3) -> Vec3 {
        self.sample_with_gradient(p).map_or(Vec3::ZERO, |s| s.1)
    }

    fn sample_with_gradient(&self, p: Vec3) -> Option<(Sample, Vec3)> {
        let r = self.locate(p)?;
        self.reconstruct(p, r, self.settings.field, true)
            .map(|x| (self.to_sample(x), x.gradient))
    }

    fn sample_in(&self, p: Vec3, iv: &Interval) -> Option<Sample> {
        self.reconstruct(p, iv.hint as usize, self.settings.field, false)
            .map(|x| self.to_sample(x))
    }

    fn sample_with_gradient_in(&self, p: Vec3, iv: &Interval) -> Option<(Sample, Vec3)> {
        self.reconstruct(p, iv.hint as usize, self.settings.field, true)
            .map(|x| (self.to_sample(x), x.gradient))
    }

    /// The packet path reconstructs a whole batch region by region
    /// ([`batch`]).
    fn packet_sampling(&self) -> bool {
        true
    }

    fn sample_batch(
        &self,
        batch: &SampleBatch,
        gradient: bool,
        out: &mut Vec<(Option<Sample>, Vec3)>,
    ) {
        self.sample_batch_on(voxless_core::Simd::Auto, batch, gradient, out);
    }

    fn sample_batch_values(&self, batch: &SampleBatch, out: &mut Vec<f32>) -> bool {
        self.sample_batch_values_on(voxless_core::Simd::Auto, batch, out)
    }

    /// Eight points at once, one per lane (`volume/lanes.rs`): the lanes'
    /// brick lists merged, each brick of the union evaluated once.
    fn samples_in_lanes(&self) -> bool {
        self.offers_lanes()
    }

    #[inline(always)]
    fn sample_values_lanes<L: voxless_core::Lanes>(
        &self,
        hints: &[u32; voxless_core::simd::LANES],
        p: [L; 3],
        live: u32,
    ) -> L {
        self.values_lanes(hints, p, live)
    }

    /// One interval per visible region the ray crosses, in order; the step is
    /// half the region's finest cell width (two samples per finest cell at
    /// sampling rate 1: adaptive sampling, ExaBricks §4.2). The regions are
    /// found by a front-to-back walk of the region tree; a prepared
    /// [`crate::AmrContext`] skips the subtrees its transfer function
    /// cannot see.
    fn intervals(&self, ray: &Ray, t: Range1, query: &IntervalQuery, out: &mut Vec<Interval>) {
        self.region_intervals(None, ray, t, query.is_visible, out, usize::MAX);
    }

    fn intervals_chunk(
        &self,
        ray: &Ray,
        t: Range1,
        query: &IntervalQuery,
        out: &mut Vec<Interval>,
        max: usize,
    ) -> Option<f32> {
        self.region_intervals(None, ray, t, query.is_visible, out, max)
    }

    /// Basis reconstruction down an axis: every region's pieces found
    /// once for all the pixels whose rays cross it ([`crate::project`]);
    /// octant: none (per pixel, its exact [`Volume::line_integral`]).
    fn project_image(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        control: &Control,
    ) -> Option<Result<Vec<f32>, Cancelled>> {
        match self.settings.reconstruction {
            Reconstruction::Basis => self.project_axis_view(camera, width, height, control),
            Reconstruction::Nearest => self.project_axis_nearest(camera, width, height, control),
            Reconstruction::Octant => None,
        }
    }

    fn line_integral(&self, ray: &Ray, t: Range1) -> f64 {
        match self.settings.reconstruction {
            Reconstruction::Nearest => self.nearest_line_integral(ray, t),
            Reconstruction::Basis => self.basis_line_integral(ray, t),
            Reconstruction::Octant => self.octant_line_integral(ray, t),
        }
    }
}
