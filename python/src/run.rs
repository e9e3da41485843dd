//! Running library work without the GIL, cancellable by Ctrl-C.
//!
//! The work runs on a scoped worker thread with a [`CancelToken`] in its
//! [`Control`]; the calling Python thread waits for it with the GIL released
//! and, every few milliseconds, takes the GIL back to run Python's signal
//! handlers ([`Python::check_signals`]). When a handler raises
//! (`KeyboardInterrupt` on Ctrl-C), the token is cancelled, the worker stops
//! at its next check (between tiles), and the exception propagates. Other
//! Python threads run while the work does. A panic in the work (a bug) is
//! caught and becomes a `RuntimeError`: it never aborts the interpreter.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::time::Duration;

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use voxless::{CancelToken, Control};

/// How often the waiting thread looks for pending signals.
const POLL: Duration = Duration::from_millis(20);

type Outcome<T> = std::thread::Result<T>;

/// Waits up to [`POLL`] for the worker, with the GIL released. The receiver
/// goes into the closure and comes back (it is `Send`, not `Sync`).
fn wait<T: Send>(
    py: Python<'_>,
    rx: Receiver<Outcome<T>>,
) -> (Result<Outcome<T>, RecvTimeoutError>, Receiver<Outcome<T>>) {
    py.detach(move || (rx.recv_timeout(POLL), rx))
}

/// Runs `work` with a cancellable [`Control`] off the GIL (see the module
/// docs). Returns what `work` returns, or the exception a signal handler
/// raised.
pub fn cancellable<T, F>(py: Python<'_>, work: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce(&Control) -> T + Send,
{
    let token = CancelToken::new();
    let control = Control::new().with_cancel(token.clone());
    let (tx, rx) = mpsc::channel::<Outcome<T>>();
    std::thread::scope(|scope| {
        let control = &control;
        scope.spawn(move || {
            let outcome = catch_unwind(AssertUnwindSafe(|| work(control)));
            // The receiver is gone only if the caller has already returned.
            let _ = tx.send(outcome);
        });
        let mut rx = rx;
        loop {
            let (got, back) = wait(py, rx);
            rx = back;
            match got {
                Ok(outcome) => return outcome.map_err(panic_error),
                Err(RecvTimeoutError::Timeout) => {
                    if let Err(interrupt) = py.check_signals() {
                        // Stop the worker at its next check, and wait for it:
                        // the scope cannot end while it runs.
                        token.cancel();
                        let _ = py.detach(move || rx.recv());
                        return Err(interrupt);
                    }
                }
                Err(RecvTimeoutError::Disconnected) => {
                    return Err(PyRuntimeError::new_err(
                        "voxless: the worker thread ended without a result",
                    ));
                }
            }
        }
    })
}

/// Runs `work` off the GIL without cancellation (building a volume cannot be
/// stopped half way); a panic becomes a `RuntimeError`.
pub fn detached<T, F>(py: Python<'_>, work: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce() -> T + Send,
{
    cancellable(py, |_| work())
}

/// A caught panic as a Python `RuntimeError` with its message.
fn panic_error(payload: Box<dyn std::any::Any + Send>) -> PyErr {
    let message = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into());
    PyRuntimeError::new_err(format!(
        "voxless internal error (please report it): {message}"
    ))
}
