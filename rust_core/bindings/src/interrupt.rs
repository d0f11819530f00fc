//! Ctrl-C during a long computation.
//!
//! [`detach`] runs the numerics on a worker thread under a fresh stop request
//! (`tribosweep_core::cancel::Token`) while the calling thread, with the GIL released, waits for the
//! result and every [`POLL`] attaches to run Python's signal handlers (`check_signals`). When a
//! handler raises (SIGINT's default raises `KeyboardInterrupt`), the token is cancelled, the core's
//! loops see it within `cancel::CHECK_EVERY` steps (about a millisecond of work on the slider),
//! the worker's partial results are dropped, and the exception propagates to Python. Reaction
//! time: the poll interval plus the core's check interval plus the thread's exit, well under a
//! second. Python runs signal handlers on its main thread only; called from another thread,
//! `check_signals` does nothing and the call simply waits for its result.

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use std::sync::mpsc::{sync_channel, RecvTimeoutError};
use std::time::Duration;
use tribosweep_core::cancel::Token;

/// How often the waiting thread looks at Python's signals.
pub(crate) const POLL: Duration = Duration::from_millis(50);

/// Stack of the worker thread: that of a typical main thread (8 MiB), which the numerics ran on
/// before they moved to a worker.
const STACK: usize = 8 << 20;

/// `f` on a worker thread with the GIL released, cancelled when a Python signal handler raises
/// (the error is returned; `f`'s result is dropped). A panic in `f` propagates as before (pyo3
/// makes it a `PanicException`).
pub(crate) fn detach<R: Send>(py: Python<'_>, f: impl FnOnce() -> R + Send) -> PyResult<R> {
    let token = Token::new();
    std::thread::scope(|scope| {
        let (tx, mut rx) = sync_channel::<R>(1);
        let tok = &token;
        let work = move || {
            let r = tok.scope(f);
            // The receiver is gone only if the caller stopped waiting: nothing to deliver to.
            let _ = tx.send(r);
        };
        let worker = std::thread::Builder::new()
            .name("tribosweep-call".into())
            .stack_size(STACK)
            .spawn_scoped(scope, work)
            .map_err(|e| PyRuntimeError::new_err(format!("cannot start a worker thread: {e}")))?;
        loop {
            // The receiver is not Sync: it moves into the detached closure and back.
            let (back, got) = py.detach(move || {
                let got = rx.recv_timeout(POLL);
                (rx, got)
            });
            rx = back;
            match got {
                Ok(r) => {
                    // Sent as the worker's last act: the join is immediate.
                    let _ = py.detach(move || worker.join());
                    return Ok(r);
                }
                Err(RecvTimeoutError::Timeout) => {
                    if let Err(e) = py.check_signals() {
                        token.cancel();
                        // A panic while stopping is of no interest now: the signal's error wins.
                        let _ = py.detach(move || worker.join());
                        return Err(e);
                    }
                }
                Err(RecvTimeoutError::Disconnected) => {
                    // The worker ended without a result: it panicked. Re-raise the panic here.
                    match py.detach(move || worker.join()) {
                        Err(payload) => std::panic::resume_unwind(payload),
                        Ok(()) => return Err(PyRuntimeError::new_err("the worker thread ended without a result")),
                    }
                }
            }
        }
    })
}
