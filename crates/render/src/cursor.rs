//! Where a ray's samples lie: the [`Cursor`] over the sample lattice, and
//! the ray's intervals, which [`RayIntervals`] asks of the volume a chunk at
//! a time as the cursor reaches them — front to back, so a ray that turns
//! opaque never asks for the intervals behind the point where it stopped.

use voxless_core::{Interval, IntervalQuery, Range1, Ray, Volume};

use crate::RenderSettings;
use crate::sampling::PixelRng;

/// One sample: the midpoint `t` of a segment of length `len` in interval
/// `interval` of the ray's list; `reset` when the segment does not start
/// where the previous one ended (a gap: the previous sample no longer
/// brackets iso-surface crossings; next to a constant interval the gap is
/// zero).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Segment {
    pub t: f32,
    pub len: f32,
    pub interval: u32,
    pub reset: bool,
}

/// The step through sampled interval `iv`: the settings' step, else the
/// interval's nominal step over the sampling rate — but at least a
/// millionth of the interval and [`MIN_STEP_ULPS`] units in the last place
/// of its far end, so every step moves `t` (a step below f32's resolution
/// at `t` would never reach the end of the interval).
#[inline]
pub fn step_in(iv: &Interval, settings: &RenderSettings) -> f32 {
    settings
        .step
        .unwrap_or(iv.nominal_dt / settings.sampling_rate)
        .max(iv.t.span() * 1e-6)
        .max(min_step_at(iv.t.hi))
}

/// Smallest step [`step_in`] takes at distance `t` along a ray.
pub const MIN_STEP_ULPS: f32 = 4.0;

/// [`MIN_STEP_ULPS`] units in the last place at `t` (f32), and at least
/// the smallest normal f32.
#[inline]
pub fn min_step_at(t: f32) -> f32 {
    (MIN_STEP_ULPS * f32::EPSILON * t.abs()).max(f32::MIN_POSITIVE)
}

/// How [`Cursor::walk`] ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Walk {
    /// The taker refused a segment (it has it).
    Stopped,
    /// The list ends before the next segment is known and more intervals
    /// may follow: fetch them and walk on (the cursor has not moved past
    /// anything it still needs).
    More,
    /// No more segments.
    Done,
}

/// How [`Cursor::whole_cells`] stopped.
enum Cells {
    /// The taker refused a segment.
    Stopped,
    /// At a cell the one-by-one loop handles.
    Edge,
    /// At a gap before interval `k`, which is to be entered.
    Gap,
}

/// Walks the segments of a ray's intervals in order; resumable, so the
/// packet path can take them a window at a time, and lazy, so the list may
/// grow as the walk goes (it looks at most one lattice cell ahead).
///
/// **The sample lattice.** Sampled intervals are cut into the cells of a
/// lattice fixed on the ray: boundaries at `t = (n + ξ)·dt` for integers
/// `n`, with `ξ` one random number per pixel sample and `dt` the interval's
/// step. A cell is sampled at its midpoint, with its length as the segment
/// length, when that midpoint lies in one of the intervals. Cells are cut
/// only where the lattice must end: at the ray's span (the volume's bounds
/// and the clip box), where the step changes, and next to constant
/// intervals — never at the seams between intervals of one step (macrocell
/// or region boundaries) nor at the edges of skipped space, which depend on
/// how the data is organised rather than on the field. So the samples of a
/// ray depend on the field, the camera, the pixel and the sample index only,
/// and a domain decomposition that renders the samples whose midpoints lie
/// in its box ([`crate::own_range`]) takes exactly the samples of the
/// one-process render.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Cursor {
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
    /// Where the current run of same-step intervals starts (cells are cut
    /// there).
    run_lo: f32,
    /// Whether a run of sampled intervals is open: `dt`, `n` and `run_lo`
    /// belong to it, and interval `k` continues it if its step is `dt`.
    open: bool,
    /// Where the last returned segment ended.
    prev_end: f32,
    /// Intervals `k..=run_last` are known to go on with the open run.
    run_last: usize,
    /// Whether interval `k` has been entered: its run is open with its step
    /// and `n` is at or past its start, so the next call goes straight to
    /// its cells.
    entered: bool,
}

impl Cursor {
    /// A cursor for a ray whose part inside the volume is `span`, returning
    /// the segments whose midpoints lie in `own` (half-open; everything for
    /// a one-process render), with the lattice offset drawn from `rng`.
    pub fn new(span: Range1, own: Range1, rng: &PixelRng) -> Self {
        Cursor {
            k: 0,
            n: 0,
            dt: 0.0,
            xi: rng.uniform(2) as f64,
            span,
            own,
            run_lo: span.lo,
            open: false,
            prev_end: span.lo,
            run_last: 0,
            entered: false,
        }
    }

    /// The step of the current interval (valid after the first segment).
    pub fn dt(&self) -> f32 {
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
        nx.constant_value().is_none() && step_in(nx, settings).to_bits() == self.dt.to_bits()
    }

    /// [`Cursor::walk`] over the ray's intervals, asking the volume for
    /// more of them as the walk reaches the end of what it has; true when
    /// `take` stopped it, false when the ray has no more segments.
    #[inline]
    pub fn walk_in<V: Volume, F: FnMut(Segment, &Interval) -> bool>(
        &mut self,
        ivs: &mut RayIntervals,
        volume: &V,
        ray: &Ray,
        query: &IntervalQuery,
        settings: &RenderSettings,
        mut take: F,
    ) -> bool {
        loop {
            match self.walk(&ivs.list, ivs.is_complete(), settings, &mut take) {
                Walk::Stopped => return true,
                Walk::Done => return false,
                Walk::More => ivs.fetch(volume, ray, query),
            }
        }
    }

    /// Hands the segments of `intervals` (each with its interval) to `take`
    /// in order until it returns false (the segment it refused is consumed:
    /// the caller keeps it), the list runs out ([`Walk::More`] when it is
    /// not `complete`: the list is the ray's first intervals) or the ray
    /// does ([`Walk::Done`]). One call emits a whole window of segments
    /// with the walk's state in registers.
    #[inline]
    pub fn walk<F: FnMut(Segment, &Interval) -> bool>(
        &mut self,
        intervals: &[Interval],
        complete: bool,
        settings: &RenderSettings,
        mut take: F,
    ) -> Walk {
        loop {
            let Some(iv) = intervals.get(self.k) else {
                return if complete { Walk::Done } else { Walk::More };
            };
            if iv.t.lo >= self.own.hi {
                // Every later midpoint lies beyond what this render owns.
                return Walk::Done;
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
                let seg = self.emit(lo, hi, self.k - 1);
                if !take(seg, iv) {
                    return Walk::Stopped;
                }
                continue;
            }
            if !self.entered {
                // A sampled interval either goes on with the open run (same
                // step: no cut at the seam) or starts a run of its own, at the
                // span for the first interval, else where it starts (the step
                // changed, or a constant interval ended).
                if !(self.open && self.continues(iv, settings)) {
                    self.dt = step_in(iv, settings);
                    self.run_lo = if self.k == 0 { self.span.lo } else { iv.t.lo };
                    self.n = self.cell_before(self.run_lo);
                    self.open = true;
                    self.run_last = self.k;
                }
                // Skip the cells before this interval and before what is owned
                // without walking them (a gap of skipped space can be long).
                // Only a jump of more than two cells is worth the division: the
                // loop below passes over cells ending before the interval
                // anyway, so starting a little early changes nothing.
                let from = iv.t.lo.max(self.own.lo).max(self.run_lo);
                if from > self.boundary(self.n + 2) {
                    self.n = self.n.max(self.cell_before(from));
                }
                self.entered = true;
            }
            // The cells of this interval. Each boundary is computed from its
            // index (never accumulated); the far one of a cell is the near
            // one of the next, so it is computed once.
            let mut iv = iv;
            let mut b_near = self.boundary(self.n);
            loop {
                if b_near >= self.own.lo.max(self.run_lo) {
                    match self.whole_cells(intervals, settings, &mut b_near, &mut take) {
                        Cells::Stopped => return Walk::Stopped,
                        // The walk enters interval `k` at the top.
                        Cells::Gap => break,
                        Cells::Edge => iv = &intervals[self.k],
                    }
                }
                let b0 = b_near.max(self.run_lo);
                // A cell starting at or past the interval's end (or the
                // span's) has its midpoint beyond the interval: done here.
                if b0 >= iv.t.hi || b0 >= self.span.hi {
                    break;
                }
                // The cell ends at the next boundary unless the run ends
                // first. Only a cell reaching past this interval can meet
                // the run's end, which the intervals after it decide.
                let bn = self.boundary(self.n + 1);
                let b1 = if bn <= iv.t.hi {
                    bn.min(self.span.hi)
                } else {
                    match self.run_end_within(intervals, complete, bn, settings) {
                        Some(b) => b,
                        None => return Walk::More,
                    }
                };
                b_near = bn;
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
                    return Walk::Done;
                }
                let seg = Segment {
                    t: m,
                    ..self.emit(b0, b1, self.k)
                };
                if !take(seg, iv) {
                    return Walk::Stopped;
                }
            }
            // This interval is done (or, after a gap, interval `k` is yet to
            // be entered); the run stays open for the next one.
            if !self.entered {
                continue;
            }
            self.k += 1;
            self.entered = false;
        }
    }

    /// The whole cells from cell `n` on (`b_near`: its near boundary, at
    /// or past the run's start and what is owned) that lie inside the open
    /// run's known intervals, the span and what is owned: no cell among
    /// them is cut, so each is emitted as the one-by-one loop would emit
    /// it, with the interval its midpoint lies in — entering the run's
    /// next intervals on the way without leaving the loop (short regions
    /// make that the common way from one interval to the next). Stops at
    /// a cell that is not whole ([`Cells::Edge`], for the one-by-one loop
    /// at interval `k`) or whose midpoint falls in a gap before interval
    /// `k` ([`Cells::Gap`]: that cell is passed over, and `k` is left to
    /// be entered, which jumps the rest of the gap).
    #[inline(always)]
    fn whole_cells<F: FnMut(Segment, &Interval) -> bool>(
        &mut self,
        intervals: &[Interval],
        settings: &RenderSettings,
        b_near: &mut f32,
        take: &mut F,
    ) -> Cells {
        // The run's intervals known so far: `k..=run_last` (each checked
        // once).
        let mut j = self.run_last.max(self.k);
        while let Some(nx) = intervals.get(j + 1)
            && self.continues(nx, settings)
        {
            j += 1;
        }
        self.run_last = j;
        let lim = intervals[j].t.hi.min(self.span.hi).min(self.own.hi);
        // The walk's state in registers (the taker may not be seen
        // through), written back after.
        let (xi, dt) = (self.xi, self.dt as f64);
        let (mut n, mut prev_end, mut k) = (self.n, self.prev_end, self.k);
        let mut near = *b_near;
        let mut iv = &intervals[k];
        let out = loop {
            let far = (((n + 1) as f64 + xi) * dt) as f32;
            if !(far <= lim && near < far) {
                break Cells::Edge;
            }
            let m = near + 0.5 * (far - near);
            // `m < far <= intervals[j].t.hi`: this ends by `j`.
            while m >= iv.t.hi {
                k += 1;
                iv = &intervals[k];
            }
            if m < iv.t.lo {
                // Skipped, as the one-by-one loop skips it; entering `k`
                // jumps the rest of a long gap.
                (n, near) = (n + 1, far);
                self.entered = false;
                break Cells::Gap;
            }
            n += 1;
            let seg = Segment {
                t: m,
                len: far - near,
                interval: k as u32,
                reset: near != prev_end,
            };
            (near, prev_end) = (far, far);
            if !take(seg, iv) {
                break Cells::Stopped;
            }
        };
        (self.n, self.prev_end, self.k, *b_near) = (n, prev_end, k, near);
        out
    }

    /// `min(b, run end)` for the run holding interval `k`, where `b` lies
    /// past interval `k`'s end. The run ends with its last same-step
    /// interval — at the span when that is the ray's last interval — so
    /// this looks ahead only through the intervals that start before `b`;
    /// `None` when the list ends first and is not complete.
    #[inline]
    fn run_end_within(
        &self,
        intervals: &[Interval],
        complete: bool,
        b: f32,
        settings: &RenderSettings,
    ) -> Option<f32> {
        let cap = b.min(self.span.hi);
        let mut j = self.k;
        loop {
            // An interval of the run reaching `b` puts the run's end at or
            // past `b`, so only the span cuts the cell.
            if intervals[j].t.hi >= b {
                return Some(cap);
            }
            match intervals.get(j + 1) {
                Some(nx) if self.continues(nx, settings) => j += 1,
                Some(_) => return Some(cap.min(intervals[j].t.hi)),
                // The ray's last interval: its run ends at the span.
                None if complete => return Some(cap),
                None => return None,
            }
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

/// Intervals asked for first; each later request asks for twice as many,
/// up to [`MAX_CHUNK`]. Small, because rays that turn opaque early are
/// where asking lazily pays; growing, so long rays ask only a few times.
pub(crate) const FIRST_CHUNK: usize = 8;
/// The most intervals one request asks for.
pub(crate) const MAX_CHUNK: usize = 256;

/// A ray's intervals, asked of the volume a chunk at a time
/// ([`Volume::intervals_chunk`]), front to back, as its cursor reaches them.
#[derive(Clone, Debug, Default)]
pub(crate) struct RayIntervals {
    /// The intervals so far, in increasing `t`.
    pub list: Vec<Interval>,
    /// Where the intervals not yet asked for begin; `None` once all are in
    /// `list`.
    rest: Option<f32>,
    /// The end of the part of the ray the intervals are asked for.
    end: f32,
    /// How many intervals the next request asks for.
    chunk: usize,
}

impl RayIntervals {
    /// Intervals kept in `buffer` (its allocation reused).
    pub fn with_buffer(buffer: Vec<Interval>) -> Self {
        RayIntervals {
            list: buffer,
            ..Default::default()
        }
    }

    /// Starts over for a ray whose intervals lie in `span` (none asked for
    /// yet).
    pub fn start(&mut self, span: Range1) {
        self.list.clear();
        self.rest = (!span.is_empty()).then_some(span.lo);
        self.end = span.hi;
        self.chunk = FIRST_CHUNK;
    }

    /// Starts over with a ray's complete list (from a tile view).
    pub fn complete(&mut self, list: &[Interval]) {
        self.list.clear();
        self.list.extend_from_slice(list);
        self.rest = None;
    }

    /// Whether every interval is in `list`.
    #[inline]
    pub fn is_complete(&self) -> bool {
        self.rest.is_none()
    }

    /// Asks the volume for the next chunk of intervals (nothing once
    /// complete).
    pub fn fetch<V: Volume>(&mut self, volume: &V, ray: &Ray, query: &IntervalQuery) {
        let Some(lo) = self.rest else {
            return;
        };
        let before = self.list.len();
        let rest = volume.intervals_chunk(
            ray,
            Range1::new(lo, self.end),
            query,
            &mut self.list,
            self.chunk,
        );
        self.chunk = (self.chunk * 2).min(MAX_CHUNK);
        // A volume must move on with every request; one that hands out
        // nothing and would resume where it started is taken as done
        // rather than asked forever.
        self.rest = rest.filter(|&r| r > lo || self.list.len() > before);
    }

    /// Asks for everything still missing (integrators that need the whole
    /// list: scattering).
    pub fn fetch_all<V: Volume>(&mut self, volume: &V, ray: &Ray, query: &IntervalQuery) {
        while !self.is_complete() {
            self.fetch(volume, ray, query);
        }
    }
}
