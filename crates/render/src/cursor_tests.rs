//! The lazy [`Cursor`] against the cursor it replaced (kept here as
//! [`Reference`]), which looked ahead through the whole list of intervals
//! to find where each run of same-step intervals ends: on random interval
//! lists — gaps, step changes, constant pieces, owned ranges — the lazy
//! cursor gives the same segments, bit for bit, whether it has the whole
//! list or gets it a few intervals at a time.

use voxless_core::{Interval, Range1, SmallRng};

use crate::RenderSettings;
use crate::cursor::{Cursor, Segment, Walk, step_in};
use crate::sampling::PixelRng;

/// The cursor as it was before intervals came in chunks.
#[derive(Clone, Copy, Debug)]
struct Reference {
    /// The interval the next segment is looked for in.
    k: usize,
    /// Lattice index of the next cell.
    n: i64,
    dt: f32,
    /// The lattice offset in steps, in `[0, 1)`.
    xi: f64,
    /// Cells are cut to this span (the ray inside the bounds and clip box).
    span: Range1,
    /// Only segments whose midpoints lie in `[own.lo, own.hi)` are returned.
    own: Range1,
    /// Cuts of the current run of same-step intervals.
    run_lo: f32,
    run_hi: f32,
    /// Whether `dt`, `n` and `run_lo` belong to interval `k`'s run.
    open: bool,
    /// Where the last returned segment ended.
    prev_end: f32,
}

impl Reference {
    /// A cursor for a ray whose part inside the volume is `span`, returning
    /// the segments whose midpoints lie in `own` (half-open; everything for
    /// a one-process render), with the lattice offset drawn from `rng`.
    fn new(span: Range1, own: Range1, rng: &PixelRng) -> Self {
        Reference {
            k: 0,
            n: 0,
            dt: 0.0,
            xi: rng.uniform(2) as f64,
            span,
            own,
            run_lo: span.lo,
            run_hi: span.hi,
            open: false,
            prev_end: span.lo,
        }
    }

    /// The step of the current interval (valid after the first `next`).
    #[allow(dead_code)]
    fn dt(&self) -> f32 {
        self.dt
    }

    /// Boundary `n` of the lattice (computed from `n`, never accumulated, so
    /// it does not depend on where the walk started).
    #[inline]
    fn boundary(&self, n: i64) -> f32 {
        ((n as f64 + self.xi) * self.dt as f64) as f32
    }

    /// The first lattice cell that can hold a midpoint at or after `t`.
    #[inline]
    fn cell_before(&self, t: f32) -> i64 {
        ((t as f64 / self.dt as f64 - self.xi).floor() as i64).saturating_sub(1)
    }

    /// Whether interval `nx` goes on with the current run's lattice.
    #[inline]
    fn continues(&self, nx: &Interval, settings: &RenderSettings) -> bool {
        nx.constant_value().is_none() && Self::step_of(nx, settings).to_bits() == self.dt.to_bits()
    }

    /// The step of sampled interval `iv` ([`step_in`]: its floors keep the
    /// lattice representable in `f32` at this `t` and bound the cells per
    /// interval, so a tiny step can never hang a render; they depend on the
    /// interval's extent only where the step is below a millionth of it).
    #[inline]
    fn step_of(iv: &Interval, settings: &RenderSettings) -> f32 {
        step_in(iv, settings)
    }

    #[inline]
    fn next(&mut self, intervals: &[Interval], settings: &RenderSettings) -> Option<Segment> {
        loop {
            let iv = intervals.get(self.k)?;
            if iv.t.lo >= self.own.hi {
                // Every later midpoint lies beyond what this render owns.
                return None;
            }
            if iv.constant_value().is_some() {
                // Constant: one segment, the whole interval (the part owned),
                // no jitter.
                self.k += 1;
                self.open = false;
                let lo = iv.t.lo.max(self.own.lo);
                let hi = iv.t.hi.min(self.own.hi);
                if hi <= lo {
                    continue;
                }
                return Some(self.emit(lo, hi, self.k - 1));
            }
            if !self.open {
                self.dt = Self::step_of(iv, settings);
                // A new run starts at the span for the first interval, else
                // where this interval starts (the step changed, or a
                // constant interval ended).
                self.run_lo = if self.k == 0 { self.span.lo } else { iv.t.lo };
                self.n = self.cell_before(self.run_lo);
                // The run goes on while the next intervals are sampled with
                // the same step; its cells end with the last of them (at the
                // span when that is the ray's last interval).
                let mut last = self.k;
                while intervals
                    .get(last + 1)
                    .is_some_and(|nx| self.continues(nx, settings))
                {
                    last += 1;
                }
                self.run_hi = if last + 1 == intervals.len() {
                    self.span.hi
                } else {
                    intervals[last].t.hi.min(self.span.hi)
                };
                self.open = true;
            }
            let continues = intervals
                .get(self.k + 1)
                .is_some_and(|nx| self.continues(nx, settings));
            let run_hi = self.run_hi;
            // Skip the cells before this interval and before what is owned
            // without walking them (a gap of skipped space can be long).
            self.n = self
                .n
                .max(self.cell_before(iv.t.lo.max(self.own.lo).max(self.run_lo)));
            loop {
                let b0 = self.boundary(self.n).max(self.run_lo);
                let b1 = self.boundary(self.n + 1).min(run_hi);
                if b0 >= run_hi {
                    break;
                }
                if b1 <= b0 {
                    self.n += 1;
                    continue;
                }
                let m = b0 + 0.5 * (b1 - b0);
                if m >= iv.t.hi {
                    break;
                }
                self.n += 1;
                if m < iv.t.lo || m < self.own.lo {
                    continue;
                }
                if m >= self.own.hi {
                    return None;
                }
                return Some(Segment {
                    t: m,
                    ..self.emit(b0, b1, self.k)
                });
            }
            // This interval is done; a run that goes on keeps its lattice.
            self.open = continues;
            self.k += 1;
        }
    }

    /// The segment `[lo, hi)` of interval `k`, sampled at its midpoint.
    #[inline]
    fn emit(&mut self, lo: f32, hi: f32, k: usize) -> Segment {
        let reset = lo != self.prev_end;
        self.prev_end = hi;
        Segment {
            t: lo + 0.5 * (hi - lo),
            len: hi - lo,
            interval: k as u32,
            reset,
        }
    }
}

/// A random ray's intervals in `span`: sampled pieces with one of a few
/// steps (runs of one step, changes of step), gaps, and constant pieces.
fn random_intervals(rng: &mut SmallRng, span: Range1) -> Vec<Interval> {
    let steps = [0.01, 0.02, 0.037, 0.1];
    let mut out = Vec::new();
    let mut t = span.lo + if rng.f() < 0.5 { 0.0 } else { rng.f() * 0.2 };
    while t < span.hi {
        let len = (0.005 + rng.f() * 0.3).min(span.hi - t);
        let piece = Range1::new(t, t + len);
        let kind = rng.f();
        if kind < 0.15 {
            out.push(Interval::constant(piece, rng.f()));
        } else {
            let dt = steps[(rng.f() * 2.2) as usize];
            out.push(Interval::sampled(piece, Range1::new(0.0, 1.0), dt));
        }
        t += len;
        if rng.f() < 0.3 {
            t += rng.f() * 0.15; // skipped space
        }
    }
    out
}

fn reference_segments(
    ivs: &[Interval],
    span: Range1,
    own: Range1,
    rng: &PixelRng,
    settings: &RenderSettings,
) -> Vec<Segment> {
    let mut c = Reference::new(span, own, rng);
    std::iter::from_fn(|| c.next(ivs, settings)).collect()
}

/// The lazy cursor's walks, `window` segments a call (one: segment by
/// segment; more: the packet path's use, where a refused segment is held
/// and comes first in the next window), handed the list `chunk` intervals
/// at a time; checks that each segment comes with its own interval.
fn walked_segments(
    ivs: &[Interval],
    (chunk, window): (usize, usize),
    span: Range1,
    own: Range1,
    rng: &PixelRng,
    settings: &RenderSettings,
) -> Vec<Segment> {
    let mut c = Cursor::new(span, own, rng);
    let mut have = chunk.min(ivs.len());
    let mut out = Vec::new();
    let mut held: Option<Segment> = None;
    loop {
        let mut taken = 0;
        if let Some(s) = held.take() {
            out.push(s);
            taken = 1;
        }
        let walk = c.walk(&ivs[..have], have == ivs.len(), settings, |seg, iv| {
            assert_eq!(*iv, ivs[seg.interval as usize]);
            if taken < window {
                out.push(seg);
                taken += 1;
                true
            } else {
                held = Some(seg);
                false
            }
        });
        match walk {
            Walk::Stopped => {}
            Walk::More => have = (have + chunk).min(ivs.len()),
            Walk::Done => return out,
        }
    }
}

#[test]
fn lazy_cursor_places_the_samples_of_the_look_ahead_cursor() {
    let mut rng = SmallRng(17);
    let mut settings = RenderSettings::for_data(
        voxless_core::Aabb::new(voxless_core::Vec3::ZERO, voxless_core::Vec3::splat(1.0)),
        Range1::new(0.0, 1.0),
        None,
        8,
        8,
    );
    let mut segments = 0;
    for case in 0..3000 {
        let span = Range1::new(rng.f() * 2.0, 2.5 + rng.f() * 2.0);
        let ivs = random_intervals(&mut rng, span);
        // Everything owned, or a box's share of a decomposition.
        let own = if case % 3 == 0 {
            let a = span.lo + rng.f() * span.span();
            Range1::new(a, a + rng.f() * span.span())
        } else {
            Range1::new(f32::NEG_INFINITY, f32::INFINITY)
        };
        settings.sampling_rate = [1.0, 0.7, 3.0][case % 3];
        let pixel = PixelRng::new(3, case as u64, 0);
        let want = reference_segments(&ivs, span, own, &pixel, &settings);
        segments += want.len();
        // Chunks of `usize::MAX`: the whole list at once.
        for chunk in [1, 2, 3, 8, usize::MAX] {
            for window in [1, 5, usize::MAX] {
                let got = walked_segments(&ivs, (chunk, window), span, own, &pixel, &settings);
                assert_eq!(
                    got, want,
                    "case {case}, chunks of {chunk}, windows of {window}"
                );
            }
        }
    }
    assert!(segments > 100_000, "only {segments} segments compared");
}
