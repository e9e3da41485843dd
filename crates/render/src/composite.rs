//! Plain samples of a packet pass composited eight rays at a time.
//!
//! Front-to-back compositing is a chain per ray: each sample's weight is
//! the transparency the ones in front of it left (`1 − α`), so one ray's
//! samples go strictly in order, a few dependent multiply–adds each. Ray
//! by ray, the core waits on that chain. Here the chains of eight rays run
//! side by side, one ray per SIMD lane: step `k` takes the `k`-th sample
//! of every ray (gathered from the classified arrays), adds it where the
//! ray still runs and the sample has opacity, and retires a lane once its
//! ray is opaque enough to stop.
//!
//! Each lane does [`crate::march::RayState::feed_classified`]'s arithmetic
//! in its order — `c·((1 − α)·a)` added to the colour, `(1 − α)·a` to `α`,
//! nothing for an opacity below zero — so a ray gets the bits it would
//! have composited alone (tested against the ray-by-ray loop).

use voxless_core::simd::{LANES, Lanes, Simd, WithLanes, dispatch};

use crate::classify::Classified;

/// One ray's plain samples in a pass and its pixel so far.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Run {
    /// The slot of its first sample in the classified arrays; its samples
    /// are the `n` slots from there, front to back.
    pub first: u32,
    pub n: u32,
    pub color: [f32; 3],
    pub alpha: f32,
    /// Set once the ray is opaque enough to stop (the samples behind the
    /// one that made it so are not composited).
    pub done: bool,
}

/// Composites every run's samples from `cl` (colour and segment opacity
/// per slot; below zero: no opacity) onto its pixel, stopping a ray once
/// its opacity reaches `early_termination`.
pub(crate) fn composite(simd: Simd, runs: &mut [Run], cl: &Classified, early_termination: f32) {
    dispatch(
        simd,
        Job {
            runs,
            cl,
            early_termination,
        },
    )
}

struct Job<'a> {
    runs: &'a mut [Run],
    cl: &'a Classified,
    early_termination: f32,
}

impl WithLanes for Job<'_> {
    type Output = ();
    #[inline(always)]
    fn run<L: Lanes>(self) {
        let s = L::splat;
        let (zero, one, stop) = (s(0.0), s(1.0), s(self.early_termination));
        let [red, green, blue] = &self.cl.rgb;
        for group in self.runs.chunks_mut(LANES) {
            // Lanes past the group's rays have no samples.
            let (mut first, mut n) = ([0.0; LANES], [0.0; LANES]);
            let mut rgba = [[0.0; LANES]; 4];
            for (k, r) in group.iter().enumerate() {
                // Slots and counts are exact in f32 (a pass has far fewer
                // than 2²⁴ samples).
                (first[k], n[k]) = (r.first as f32, r.n as f32);
                let [cr, cg, cb] = r.color;
                (rgba[0][k], rgba[1][k], rgba[2][k], rgba[3][k]) = (cr, cg, cb, r.alpha);
            }
            let steps = group.iter().map(|r| r.n).max().unwrap_or(0);
            let (first, n) = (L::from_array(first), L::from_array(n));
            let [mut cr, mut cg, mut cb, mut alpha] = rgba.map(L::from_array);
            let mut done = zero.lt(zero);
            for k in 0..steps {
                let k = s(k as f32);
                let live = k.lt(n).and_not(done);
                if !live.any() {
                    break;
                }
                // Lanes without a sample here read slot 0 (any slot is in
                // range) and add nothing.
                let at = live.select(first + k, zero);
                let a = L::gather(&self.cl.alpha, at);
                let add = live & a.ge(zero);
                let w = (one - alpha) * a;
                cr = add.select(cr + L::gather(red, at) * w, cr);
                cg = add.select(cg + L::gather(green, at) * w, cg);
                cb = add.select(cb + L::gather(blue, at) * w, cb);
                alpha = add.select(alpha + (one - alpha) * a, alpha);
                done = done | (add & alpha.ge(stop));
            }
            let (cr, cg, cb, alpha) = (
                cr.to_array(),
                cg.to_array(),
                cb.to_array(),
                alpha.to_array(),
            );
            let done = done.bitmask();
            for (k, r) in group.iter_mut().enumerate() {
                r.color = [cr[k], cg[k], cb[k]];
                r.alpha = alpha[k];
                r.done = done >> k & 1 != 0;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use voxless_core::SmallRng;

    /// The ray-by-ray compositing of `feed_classified` (no light).
    fn one_by_one(r: &mut Run, cl: &Classified, stop: f32) {
        for slot in r.first..r.first + r.n {
            let k = slot as usize;
            let a = cl.alpha[k];
            if a < 0.0 {
                continue;
            }
            let w = (1.0 - r.alpha) * a;
            for c in 0..3 {
                r.color[c] += cl.rgb[c][k] * w;
            }
            r.alpha += (1.0 - r.alpha) * a;
            if r.alpha >= stop {
                r.done = true;
                return;
            }
        }
    }

    #[test]
    fn lanes_composite_the_bits_of_one_ray_at_a_time() {
        let mut rng = SmallRng(7);
        let slots = 3000;
        let mut cl = Classified::default();
        for c in 0..3 {
            cl.rgb[c] = (0..slots).map(|_| rng.f()).collect();
        }
        // A quarter of the samples without opacity (below zero), some
        // nearly opaque ones so rays stop at every point.
        cl.alpha = (0..slots)
            .map(|_| match (rng.f() * 8.0) as u32 {
                0 | 1 => -1.0,
                2 => 0.0,
                3 => 0.9 + 0.1 * rng.f(),
                _ => 0.2 * rng.f(),
            })
            .collect();
        for stop in [0.99, 1.0, 0.5] {
            for simd in Simd::ALL.into_iter().filter(|s| s.available()) {
                // Groups of 1 to 19 rays with 0 to 40 samples each, some
                // starting partly opaque (a pixel behind another box).
                let mut at = 0;
                let mut runs = Vec::new();
                let mut stopped = 0;
                for _ in 0..60 {
                    runs.clear();
                    for _ in 0..1 + (rng.f() * 19.0) as usize {
                        let n = (rng.f() * 41.0) as u32;
                        if at + n as usize > slots {
                            at = 0;
                        }
                        runs.push(Run {
                            first: at as u32,
                            n,
                            color: [rng.f() * 0.1, 0.0, rng.f() * 0.1],
                            alpha: if rng.f() < 0.2 { 0.5 * rng.f() } else { 0.0 },
                            done: false,
                        });
                        at += n as usize;
                    }
                    let mut want = runs.clone();
                    want.iter_mut().for_each(|r| one_by_one(r, &cl, stop));
                    composite(simd, &mut runs, &cl, stop);
                    for (got, want) in runs.iter().zip(&want) {
                        assert_eq!(got.done, want.done, "{simd:?} {want:?}");
                        assert_eq!(got.alpha.to_bits(), want.alpha.to_bits(), "{simd:?}");
                        for c in 0..3 {
                            assert_eq!(got.color[c].to_bits(), want.color[c].to_bits());
                        }
                    }
                    stopped += want.iter().filter(|r| r.done).count();
                }
                assert!(stopped > 50, "only {stopped} rays stopped");
            }
        }
    }
}
