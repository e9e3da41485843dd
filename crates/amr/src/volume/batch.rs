//! The packet path (CPU RBF paper §4, for AMR): a whole [`SampleBatch`]
//! reconstructed run by run, brick by brick, eight samples at a time.
//!
//! A packet pass hands over, per ray, the samples inside a short window of
//! depth, each with the region its interval came from. Samples are
//! collected into runs by region — one open run per hash of the region
//! number, so neighbouring rays of the packet, which cross the same
//! regions, fill the same run — and a run is reconstructed when it is full,
//! when another region takes its place, or at the end of the batch. A run
//! goes through its region's bricks with its samples in lanes
//! ([`super::lanes`]): a brick's stencil is found for eight samples in a
//! few vector operations, and the samples, close together, read the same
//! few cells while they are in cache. Every sample still adds its bricks'
//! terms in the region's brick order with the arithmetic of
//! [`AmrVolume::reconstruct`], and each result goes to its sample's slot,
//! so the batch gives exactly the bits of sampling point by point (on every
//! SIMD backend). With the gradient a run goes sample by sample, in `f64`
//! as the point path does.
//!
//! (Runs of one ray only — the first form of this path — filled 2.7 of 8
//! lanes on the AMRClaw frame; collecting across rays fills 5.5. Sorting a
//! batch's samples by region instead was measured no faster in the scalar
//! path: the sort cost what the sharing saved.)

use voxless_core::simd::{LANES, Lanes, Simd, WithLanes, dispatch};
use voxless_core::{Interval, Sample, SampleBatch, Vec3};

use super::lanes::{ValueLanes, brick_value_lanes};
use super::recon::{BasisSums, Recon, ValueSums, brick_sums};
use super::{AmrVolume, Reconstruction};

/// Samples per run at most (a run of one region longer than this is cut);
/// a multiple of [`LANES`].
const RUN: usize = 16;

/// What a packet pass's batch is reconstructed into.
type Out = Vec<(Option<Sample>, Vec3)>;

impl AmrVolume {
    /// [`voxless_core::Volume::sample_batch`] on the SIMD backend `simd`:
    /// every sample of `batch` in the region its hint names (found by point
    /// location without one, as [`voxless_core::Volume::sample`] does).
    pub(crate) fn sample_batch_on(
        &self,
        simd: Simd,
        batch: &SampleBatch,
        gradient: bool,
        out: &mut Out,
    ) {
        dispatch(
            simd,
            BatchJob {
                volume: self,
                batch,
                gradient,
                out,
            },
        )
    }

    /// [`voxless_core::Volume::sample_batch_values`] on the SIMD backend
    /// `simd`: the same reconstruction, each result's value alone (false
    /// when samples carry a colour field).
    pub(crate) fn sample_batch_values_on(
        &self,
        simd: Simd,
        batch: &SampleBatch,
        out: &mut Vec<f32>,
    ) -> bool {
        if self.settings.color_field.is_some() {
            return false;
        }
        dispatch(
            simd,
            BatchJob {
                volume: self,
                batch,
                gradient: false,
                out: Values(out),
            },
        );
        true
    }

    #[inline(always)]
    fn sample_batch_lanes<L: Lanes, O: BatchOut>(
        &self,
        batch: &SampleBatch,
        gradient: bool,
        out: &mut O,
    ) {
        let field = self.settings.field;
        // Only the basis has a packet form; the others go point by point.
        let per_point = self.settings.reconstruction != Reconstruction::Basis;
        // Results go to their sample's slot, so runs may gather samples of
        // several rays and finish in any order. Every slot is written below,
        // so the caller's buffer is only sized, not filled (filling it took
        // 6 % of an AMR frame).
        let total = match (batch.offsets.first(), batch.offsets.last()) {
            (Some(&a), Some(&b)) => (b - a) as usize,
            _ => 0,
        };
        out.size(total);
        // The open runs are 17 kB: reused, not built afresh per batch
        // (taken out of the thread-local, so nothing is borrowed across
        // the reconstruction).
        let mut runs = RUNS_SCRATCH.take().unwrap_or_default();
        for run in &mut runs.0 {
            (run.region, run.len) = (usize::MAX, 0);
        }
        let mut slot = 0;
        for (r, ray) in batch.rays.iter().enumerate() {
            for &t in batch.samples(r) {
                let p = ray.at(t);
                let hint = match batch.hints {
                    Some(h) => h[slot],
                    None => Interval::NO_HINT,
                };
                let region = match hint {
                    Interval::NO_HINT => self.locate(p),
                    h => Some(h as usize),
                };
                match region.filter(|_| !per_point) {
                    Some(region) => {
                        let run = runs.for_region(region);
                        if run.region != region || run.len == RUN {
                            self.flush::<L, O>(run, gradient, out);
                            run.region = region;
                        }
                        let (k, pu) = (run.len, self.to_units(p));
                        (run.x[k], run.y[k], run.z[k]) = (pu.x, pu.y, pu.z);
                        run.slot[k] = slot as u32;
                        run.len += 1;
                    }
                    // Nearest reconstruction reads one cell, octant finds
                    // its cells by position: nothing to share. No region:
                    // no data.
                    None => {
                        let x = region.and_then(|reg| self.reconstruct(p, reg, field, gradient));
                        out.put(self, slot, x);
                    }
                }
                slot += 1;
            }
        }
        for run in &mut runs.0 {
            self.flush::<L, O>(run, gradient, out);
        }
        RUNS_SCRATCH.set(Some(runs));
    }

    /// Reconstructs the samples of `run` (one region) into their slots of
    /// `out`: values only, eight samples at a time through each brick; with
    /// the gradient, sample by sample in `f64`.
    #[inline(always)]
    fn flush<L: Lanes, O: BatchOut>(&self, run: &mut Run, gradient: bool, out: &mut O) {
        let n = run.len;
        if n == 0 {
            return;
        }
        run.len = 0;
        let fields = self.basis_fields(self.settings.field);
        let two_fields = fields.1.is_some();
        let bricks = self.ix().regions.bricks_of(run.region);
        if gradient {
            let mut sums = [BasisSums::default(); RUN];
            let sums = &mut sums[..n];
            for &b in bricks {
                let grid = &self.bx().grids[b as usize];
                for (k, s) in sums.iter_mut().enumerate() {
                    let pu = Vec3::new(run.x[k], run.y[k], run.z[k]);
                    brick_sums(grid, pu, fields, s);
                }
            }
            for (s, &slot) in sums.iter().zip(&run.slot) {
                out.put(self, slot as usize, self.finish(s, true, two_fields));
            }
            return;
        }
        // Bricks outside, lane groups inside: each brick's constants once
        // per run; every sample still adds its bricks in the region's order.
        let mut acc = [ValueLanes::zero(); RUN / LANES];
        for &b in bricks {
            let grid = &self.bx().grids[b as usize];
            for (acc, at) in acc.iter_mut().zip((0..n).step_by(LANES)) {
                let p = [
                    L::load(&run.x, at),
                    L::load(&run.y, at),
                    L::load(&run.z, at),
                ];
                brick_value_lanes(grid, p, L::first(n - at), fields, acc);
            }
        }
        for (acc, at) in acc.iter().zip((0..n).step_by(LANES)) {
            for k in 0..LANES.min(n - at) {
                let s = ValueSums {
                    sw: acc.sw[k],
                    sv: acc.sv[k],
                    sc: acc.sc[k],
                };
                let slot = run.slot[at + k] as usize;
                out.put(self, slot, self.finish_values(s, two_fields));
            }
        }
    }
}

/// Where a batch's results go, by slot: whole samples, or values alone.
trait BatchOut {
    /// Sized for `n` results (every slot is written, so not filled).
    fn size(&mut self, n: usize);
    fn put(&mut self, volume: &AmrVolume, slot: usize, x: Option<Recon>);
}

impl BatchOut for &mut Out {
    fn size(&mut self, n: usize) {
        self.resize(n, (None, Vec3::ZERO));
    }
    #[inline(always)]
    fn put(&mut self, volume: &AmrVolume, slot: usize, x: Option<Recon>) {
        self[slot] = match x {
            Some(x) => (Some(volume.to_sample(x)), x.gradient),
            None => (None, Vec3::ZERO),
        };
    }
}

/// Values alone, NaN where there is no sample.
struct Values<'a>(&'a mut Vec<f32>);

impl BatchOut for Values<'_> {
    fn size(&mut self, n: usize) {
        self.0.resize(n, f32::NAN);
    }
    #[inline(always)]
    fn put(&mut self, _: &AmrVolume, slot: usize, x: Option<Recon>) {
        self.0[slot] = x.map_or(f32::NAN, |x| x.value);
    }
}

/// [`AmrVolume::sample_batch_on`]'s loop, instantiated per lane type.
struct BatchJob<'a, 'b, O> {
    volume: &'a AmrVolume,
    batch: &'a SampleBatch<'b>,
    gradient: bool,
    out: O,
}

impl<O: BatchOut> WithLanes for BatchJob<'_, '_, O> {
    type Output = ();
    #[inline(always)]
    fn run<L: Lanes>(mut self) {
        self.volume
            .sample_batch_lanes::<L, O>(self.batch, self.gradient, &mut self.out)
    }
}

/// Samples of one region waiting to be reconstructed (of one ray or
/// several): unit-space positions by axis (the lanes load them eight at a
/// time), and each one's slot in the output.
struct Run {
    region: usize,
    len: usize,
    x: [f32; RUN],
    y: [f32; RUN],
    z: [f32; RUN],
    slot: [u32; RUN],
}

impl Default for Run {
    fn default() -> Self {
        Run {
            region: usize::MAX,
            len: 0,
            x: [0.0; RUN],
            y: [0.0; RUN],
            z: [0.0; RUN],
            slot: [0; RUN],
        }
    }
}

/// Open runs, one per hash of the region (direct mapped): neighbouring
/// rays of a packet cross the same regions, so a region's run collects
/// samples from several rays and fills more lanes.
struct Runs([Run; RUNS]);

thread_local! {
    static RUNS_SCRATCH: std::cell::Cell<Option<Box<Runs>>> = const { std::cell::Cell::new(None) };
}

/// Open runs at most (a power of two).
const RUNS: usize = 64;

impl Default for Runs {
    fn default() -> Self {
        Runs(std::array::from_fn(|_| Run::default()))
    }
}

impl Runs {
    /// The run slot of `region` (it may hold another region's samples).
    #[inline(always)]
    fn for_region(&mut self, region: usize) -> &mut Run {
        // Fibonacci hashing: consecutive region numbers spread out.
        let h = (region as u32).wrapping_mul(0x9E37_79B9) >> (32 - RUNS.trailing_zeros());
        &mut self.0[h as usize]
    }
}
