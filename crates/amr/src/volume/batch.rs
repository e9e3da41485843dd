//! The packet path (CPU RBF paper §4, for AMR): a whole [`SampleBatch`]
//! reconstructed run by run, brick by brick.
//!
//! A packet pass hands over, per ray, the samples inside a short window of
//! depth, each with the region its interval came from; at two samples per
//! finest cell, consecutive samples of a ray mostly share a region. The
//! batch is cut into such runs, and each run is reconstructed with its
//! region's bricks in the outer loop: a brick's stencil constants
//! ([`BrickGrid`]) and the region's brick list are read once for the whole
//! run, and the
//! run's samples, a fraction of a cell apart, read the same few cells while
//! they are in cache. Every sample still adds its bricks' terms in the
//! region's brick order with the arithmetic of [`AmrVolume::reconstruct`],
//! so the batch gives exactly the bits of sampling point by point.
//!
//! (Grouping the runs of all the packet's rays by region as well, by
//! sorting them, was measured on the AMRClaw frame: no faster — the cells a
//! packet touches fit in cache either way — so runs stay in batch order and
//! their results go straight to the output.)

use voxless_core::{Interval, Sample, SampleBatch, Vec3};

use super::recon::{BasisSums, BrickGrid, brick_sums, brick_value_sums};
use super::{AmrVolume, Reconstruction};

/// Samples per run at most (a run of one region longer than this is cut).
const RUN: usize = 32;

impl AmrVolume {
    /// [`voxless_core::Volume::sample_batch`]: every sample of `batch` in
    /// the region its hint names (found by point location without one, as
    /// [`voxless_core::Volume::sample`] does).
    pub(super) fn sample_batch_in(
        &self,
        batch: &SampleBatch,
        gradient: bool,
        out: &mut Vec<(Option<Sample>, Vec3)>,
    ) {
        let field = self.settings.field;
        let nearest = self.settings.reconstruction == Reconstruction::Nearest;
        let mut run = Run::default();
        let mut i = 0;
        for (r, ray) in batch.rays.iter().enumerate() {
            for &t in batch.samples(r) {
                let p = ray.at(t);
                let hint = batch.hints.map_or(Interval::NO_HINT, |h| h[i]);
                i += 1;
                let region = match hint {
                    Interval::NO_HINT => self.locate(p),
                    h => Some(h as usize),
                };
                let Some(region) = region.filter(|_| !nearest) else {
                    // Nearest reconstruction reads one cell: nothing to
                    // share. No region: no data.
                    self.flush(&mut run, gradient, out);
                    let x = region.and_then(|reg| self.reconstruct(p, reg, field, gradient));
                    out.push(self.output(x));
                    continue;
                };
                if run.len == RUN || (run.len > 0 && run.region != region) {
                    self.flush(&mut run, gradient, out);
                }
                run.region = region;
                run.pu[run.len] = self.to_units(p);
                run.len += 1;
            }
            // Runs do not cross rays: the next ray's samples start anew.
            self.flush(&mut run, gradient, out);
        }
    }

    /// Reconstructs the samples of `run` (one region) and appends them.
    fn flush(&self, run: &mut Run, gradient: bool, out: &mut Vec<(Option<Sample>, Vec3)>) {
        let n = run.len;
        if n == 0 {
            return;
        }
        let fields = self.basis_fields(self.settings.field);
        let sums = &mut run.sums[..n];
        sums.fill(BasisSums::default());
        for &b in self.regions.bricks_of(run.region) {
            let grid = BrickGrid::new(&self.bricks[b as usize]);
            let samples = sums.iter_mut().zip(&run.pu[..n]);
            if gradient {
                samples.for_each(|(s, &pu)| brick_sums(&grid, pu, true, fields, s));
            } else {
                samples.for_each(|(s, &pu)| brick_value_sums(&grid, pu, fields, s));
            }
        }
        for s in sums.iter() {
            out.push(self.output(self.finish(s, gradient, fields.1.is_some())));
        }
        run.len = 0;
    }

    #[inline]
    fn output(&self, x: Option<super::recon::Recon>) -> (Option<Sample>, Vec3) {
        match x {
            Some(x) => (Some(self.to_sample(x)), x.gradient),
            None => (None, Vec3::ZERO),
        }
    }
}

/// Consecutive samples of one ray in one region.
struct Run {
    region: usize,
    len: usize,
    /// Unit-space positions.
    pu: [Vec3; RUN],
    sums: [BasisSums; RUN],
}

impl Default for Run {
    fn default() -> Self {
        Run {
            region: 0,
            len: 0,
            pu: [Vec3::ZERO; RUN],
            sums: [BasisSums::default(); RUN],
        }
    }
}
