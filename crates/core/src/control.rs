//! Render control: progress reported by the renderer as (done, total) units
//! of work, and cancellation checked between units (tiles), so a viewer can
//! drop a stale frame and Python's Ctrl-C can stop a render.
//!
//! A [`CancelToken`] is a shared flag: clones see the same flag, and any
//! thread may cancel. Work that notices it returns [`Cancelled`] and leaves
//! no partial result behind (a film keeps only whole passes).

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// A shared cancellation flag.
#[derive(Clone, Debug, Default)]
pub struct CancelToken(Arc<AtomicBool>);

impl CancelToken {
    pub fn new() -> Self {
        CancelToken::default()
    }
    /// Asks every holder of a clone to stop at its next check.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

/// Work stopped because it was cancelled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cancelled;

impl std::fmt::Display for Cancelled {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("cancelled")
    }
}

impl std::error::Error for Cancelled {}

/// Progress callback: `(done, total)` units of work.
pub type ProgressFn<'a> = &'a (dyn Fn(u64, u64) + Sync);

/// What a long operation reports to and checks with its caller.
#[derive(Clone)]
pub struct Control<'a> {
    cancel: Option<CancelToken>,
    progress: Option<ProgressFn<'a>>,
    /// Units already done before this operation and the grand total, when
    /// it is one part of a larger job (see [`Control::part`]).
    offset: u64,
    grand_total: Option<u64>,
}

impl Default for Control<'_> {
    fn default() -> Self {
        Control::new()
    }
}

impl<'a> Control<'a> {
    /// No progress reports, never cancelled.
    pub fn new() -> Self {
        Control {
            cancel: None,
            progress: None,
            offset: 0,
            grand_total: None,
        }
    }

    /// Stops when `token` is cancelled.
    pub fn with_cancel(mut self, token: CancelToken) -> Self {
        self.cancel = Some(token);
        self
    }

    /// Reports `(done, total)` to `progress`.
    pub fn with_progress(mut self, progress: ProgressFn<'a>) -> Self {
        self.progress = Some(progress);
        self
    }

    pub fn is_cancelled(&self) -> bool {
        self.cancel.as_ref().is_some_and(CancelToken::is_cancelled)
    }

    /// `Err(Cancelled)` once cancelled.
    pub fn check(&self) -> Result<(), Cancelled> {
        if self.is_cancelled() {
            Err(Cancelled)
        } else {
            Ok(())
        }
    }

    /// Reports `done` of `total` units of this operation.
    pub fn report(&self, done: u64, total: u64) {
        if let Some(p) = self.progress {
            match self.grand_total {
                Some(g) => p(self.offset + done, g),
                None => p(done, total),
            }
        }
    }

    /// The control of one part of a larger job: its reports are shifted by
    /// `offset` and scaled to `grand_total` units (each part must report in
    /// the same units as the whole).
    pub fn part(&self, offset: u64, grand_total: u64) -> Control<'a> {
        Control {
            cancel: self.cancel.clone(),
            progress: self.progress,
            offset: self.offset + offset,
            grand_total: Some(self.grand_total.unwrap_or(grand_total)),
        }
    }
}
