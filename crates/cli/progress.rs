//! Progress for long work: a bar on a terminal that appears only once work
//! has taken over a second (quick runs stay quiet), and plain lines when
//! stderr is not a terminal (a render piped to a log still says where it
//! is): the first once work has taken a second, then one every few
//! seconds, and a last one at 100 % when any was printed. The environment
//! variable `VOXLESS_PROGRESS_EVERY` (seconds) sets both the wait and the
//! interval.
//!
//! Positions are kept in thousandths of a unit, so a unit (a frame) can be
//! split by the renderer's own (done, total) reports.

use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Sub-steps per unit.
const SUB: u64 = 1000;
/// How often a line is printed when stderr is not a terminal.
const LINE_EVERY: Duration = Duration::from_secs(5);
/// When the first line (or the bar) appears.
const QUIET_FOR: Duration = Duration::from_secs(1);

/// The quiet time and line interval: `VOXLESS_PROGRESS_EVERY` seconds for
/// both when set, else [`QUIET_FOR`] and [`LINE_EVERY`].
fn intervals() -> (Duration, Duration) {
    std::env::var("VOXLESS_PROGRESS_EVERY")
        .ok()
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s >= 0.0)
        .map_or((QUIET_FOR, LINE_EVERY), |s| {
            let d = Duration::from_secs_f64(s);
            (d, d)
        })
}

pub struct Progress {
    bar: ProgressBar,
    what: String,
    start: Instant,
    terminal: bool,
    /// Quiet for this long, then a line (or the bar); then a line this often.
    every: (Duration, Duration),
    /// Whether the bar is drawn (terminal) or a line was printed (not a
    /// terminal) yet, when the last line was printed, and whether it said
    /// 100 %.
    state: Mutex<(bool, Instant, bool)>,
    /// Says nothing at all (a rank other than 0 of an MPI run).
    silent: bool,
}

impl Progress {
    /// Progress over `units` units of work (frames, or 1 for one render),
    /// shown when `shown` (rank 0 of a run; silent on the other ranks).
    pub fn new(what: &str, units: u64, shown: bool) -> Self {
        let bar = ProgressBar::with_draw_target(Some(units * SUB), ProgressDrawTarget::hidden());
        bar.set_style(
            ProgressStyle::with_template(
                "{msg} [{bar:40}] {percent}% ({elapsed} elapsed, ~{eta} left)",
            )
            .expect("static template")
            .progress_chars("=> "),
        );
        bar.set_message(what.to_string());
        Progress {
            bar,
            what: what.to_string(),
            start: Instant::now(),
            terminal: std::io::stderr().is_terminal(),
            every: intervals(),
            state: Mutex::new((false, Instant::now(), false)),
            silent: !shown,
        }
    }

    /// `done` whole units.
    pub fn set(&self, done: u64) {
        self.set_position(done * SUB);
    }

    /// Unit `unit` is `done / total` done (a renderer's report).
    pub fn set_fraction(&self, unit: u64, done: u64, total: u64) {
        let part = (done * SUB).checked_div(total).unwrap_or(0);
        self.set_position(unit * SUB + part.min(SUB));
    }

    fn set_position(&self, pos: u64) {
        if self.silent {
            return;
        }
        self.bar.set_position(pos);
        let elapsed = self.start.elapsed();
        let Ok(mut state) = self.state.lock() else {
            return;
        };
        if self.terminal {
            if elapsed > self.every.0 && !state.0 {
                state.0 = true;
                self.bar.set_draw_target(ProgressDrawTarget::stderr());
            }
        } else if (!state.0 && elapsed >= self.every.0)
            || (state.0 && state.1.elapsed() >= self.every.1)
        {
            state.0 = true;
            state.1 = Instant::now();
            let len = self.bar.length().unwrap_or(1).max(1);
            state.2 = pos >= len;
            self.line(pos as f64 / len as f64, elapsed);
        }
    }

    /// One plain progress line.
    fn line(&self, frac: f64, elapsed: Duration) {
        let left = if frac > 0.0 && frac < 1.0 {
            format!(
                ", ~{:.0} s left",
                elapsed.as_secs_f64() * (1.0 - frac) / frac
            )
        } else {
            String::new()
        };
        eprintln!(
            "{}: {:.0}% ({:.1} s elapsed{left})",
            self.what,
            100.0 * frac,
            elapsed.as_secs_f64()
        );
    }

    /// Prints a line without tearing the bar.
    pub fn println(&self, text: &str) {
        if self.silent {
            return;
        }
        if self.terminal {
            self.bar.suspend(|| eprintln!("{text}"));
        } else {
            eprintln!("{text}");
        }
    }

    pub fn finish(&self) {
        if self.silent {
            return;
        }
        self.bar.finish_and_clear();
        if !self.terminal && self.state.lock().is_ok_and(|s| s.0 && !s.2) {
            self.line(1.0, self.start.elapsed());
        }
    }
}
