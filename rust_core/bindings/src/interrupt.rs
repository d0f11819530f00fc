//! Ctrl-C during a long computation.
//!
//! [`detach`] runs the numerics on a worker thread (a persistent one, [`workers`]) under a fresh stop request
//! (`tribosweep_core::cancel::Token`) while the calling thread, with the GIL released, waits for the
//! result and every [`POLL`] attaches to run Python's signal handlers (`check_signals`). When a
//! handler raises (SIGINT's default raises `KeyboardInterrupt`), the token is cancelled, the core's
//! loops see it within `cancel::CHECK_EVERY` steps (about a millisecond of work on the slider),
//! the worker's partial results are dropped, and the exception propagates to Python. Reaction
//! time: the poll interval plus the core's check interval plus the worker's return, well under a
//! second. Python runs signal handlers on its main thread only; called from another thread,
//! `check_signals` does nothing and the call simply waits for its result. Such calls are stopped by
//! [`stop_calls`]: a sweep whose chunks run on threads of its own process calls it when Ctrl-C
//! reaches its main thread, so that no chunk computes on after the sweep has stopped.

use pyo3::exceptions::{PyKeyboardInterrupt, PyRuntimeError};
use pyo3::prelude::*;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::{sync_channel, Receiver, RecvTimeoutError};
use std::sync::Arc;
use std::thread::Result as Caught;
use std::time::Duration;
use tribosweep_core::cancel::Token;
use tribosweep_core::parallel::PerProcess;

/// How often the waiting thread looks at Python's signals.
pub(crate) const POLL: Duration = Duration::from_millis(50);

/// Stack of the worker thread: that of a typical main thread (8 MiB), which the numerics ran on
/// before they moved to a worker.
const STACK: usize = 8 << 20;

/// The persistent workers that run the calls ([`detach`]): one per logical core, at most
/// [`MAX_WORKERS`], so that as many calls can run at once (from as many Python threads, e.g. dask's
/// threaded scheduler) without starting a thread. A thread started and joined per call cost
/// 75-100 us on a 2-core Zen 3 (the kernel's `clone`, the stack's mapping and page faults, the
/// exit): about half of a call that integrates ten trajectories for 50 ms of simulated time, as
/// each Lyapunov segment of a sweep does. Further calls at once start a thread of their own, as
/// every call did before. Per process: a child made by `fork` makes its own ([`PerProcess`]).
fn workers() -> Workers {
    static WORKERS: PerProcess<Workers> = PerProcess::new();
    let make = || {
        let n = std::thread::available_parallelism().map_or(1, |n| n.get()).min(MAX_WORKERS);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .stack_size(STACK)
            .thread_name(|i| format!("tribosweep-call-{i}"))
            .build()
            .expect("building the call workers");
        Workers { pool: Arc::new(pool), busy: Arc::new(AtomicUsize::new(0)) }
    };
    WORKERS.with(make, |w| w.clone())
}

/// The most persistent call workers of a process. A process seldom runs more calls at once than
/// this, and each worker is a thread for the process's lifetime: one per core on a 64-core node
/// would leave 64 idle threads in each of, say, 64 dask worker processes (4,096 threads, against
/// containers' process limits of a few thousand).
const MAX_WORKERS: usize = 4;

/// The call workers of this process: the pool and how many calls run on it now.
#[derive(Clone)]
struct Workers {
    pool: Arc<rayon::ThreadPool>,
    busy: Arc<AtomicUsize>,
}

/// Whether [`stop_calls`] has stopped this process's calls.
static STOPPED: AtomicBool = AtomicBool::new(false);

/// The error of a call stopped by [`stop_calls`].
fn stopped() -> PyErr {
    PyKeyboardInterrupt::new_err("stopped by tribosweep._core.stop_calls (the sweep was interrupted)")
}

/// `stop_calls(True)`: stop every call of this process that is computing, from whichever thread
/// it was made, within [`POLL`] plus the core's check interval, and refuse new ones (each raises
/// `KeyboardInterrupt`), until `stop_calls(False)`. Python delivers Ctrl-C to its main thread
/// only, so a sweep that runs chunks on other threads of its process calls this when its main
/// thread is interrupted, waits for those threads, and then lifts it.
#[pyfunction]
fn stop_calls(stop: bool) {
    STOPPED.store(stop, Ordering::SeqCst);
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(stop_calls, m)?)
}

/// `f` on a worker thread with the GIL released, cancelled when a Python signal handler raises or
/// [`stop_calls`] stops the process's calls (the error is returned; `f`'s result is dropped). A
/// panic in `f` propagates as before (pyo3 makes it a `PanicException`).
pub(crate) fn detach<R: Send>(py: Python<'_>, f: impl FnOnce() -> R + Send) -> PyResult<R> {
    if STOPPED.load(Ordering::SeqCst) {
        return Err(stopped());
    }
    let token = Token::new();
    let tok = &token;
    let (tx, rx) = sync_channel::<Caught<R>>(1);
    // The result, or the panic's payload, is sent as the worker's last act.
    let work = move || {
        let _ = tx.send(catch_unwind(AssertUnwindSafe(|| tok.scope(f))));
    };
    let Workers { pool, busy } = workers();
    let got = if busy.fetch_add(1, Ordering::AcqRel) < pool.current_num_threads() {
        // The scope ends when `work` has: on a signal, once the cancelled core has stopped.
        let got = py.detach(|| {
            pool.in_place_scope(|s| {
                s.spawn(move |_| work());
                wait(rx, tok)
            })
        });
        busy.fetch_sub(1, Ordering::AcqRel);
        got
    } else {
        busy.fetch_sub(1, Ordering::AcqRel);
        py.detach(|| {
            std::thread::scope(|scope| {
                std::thread::Builder::new()
                    .name("tribosweep-call".into())
                    .stack_size(STACK)
                    .spawn_scoped(scope, work)
                    .map_err(|e| PyRuntimeError::new_err(format!("cannot start a worker thread: {e}")))?;
                wait(rx, tok)
            })
        })
    };
    match got? {
        Ok(r) => Ok(r),
        // Re-raised on the calling thread, as a panic of the call itself.
        Err(payload) => resume_unwind(payload),
    }
}

/// The worker's result, waited for without the GIL; every [`POLL`] Python's signal handlers run
/// (with the GIL), and when one raises, or [`stop_calls`] has stopped the calls, the token is
/// cancelled and the error returned.
fn wait<R>(rx: Receiver<Caught<R>>, token: &Token) -> PyResult<Caught<R>> {
    loop {
        match rx.recv_timeout(POLL) {
            Ok(r) => return Ok(r),
            Err(RecvTimeoutError::Timeout) => {
                let stop = Python::attach(|py| py.check_signals()).and_then(|()| {
                    if STOPPED.load(Ordering::SeqCst) {
                        Err(stopped())
                    } else {
                        Ok(())
                    }
                });
                if let Err(e) = stop {
                    token.cancel();
                    return Err(e);
                }
            }
            Err(RecvTimeoutError::Disconnected) => {
                return Err(PyRuntimeError::new_err("the worker thread ended without a result"))
            }
        }
    }
}
