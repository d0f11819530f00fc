"""Ctrl-C (SIGINT) stops a long computation promptly, keeps a sweep's finished chunks, and changes nothing else.

Every computation below would run for many seconds uncancelled; each is interrupted while its
Rust code runs. The bound on the reaction is ``REACTION`` = 2 s from the signal to the exception (or, for a
subprocess, to its exit). How the time splits: the bindings look at Python's signals every 50 ms,
the core's loops look at the stop request every 256 integrator steps or grid points (under 10 ms
of work on these problems), so a healthy run reacts in about 0.1 s; the rest of the 2 s is room for
a loaded CI machine (2 shared cores) and, for a subprocess, the interpreter's exit. A broken
cancel misses the bound by seconds at least, so the verdict does not hang on the margin.

In-process tests install a SIGINT handler that raises :class:`Interrupted` (the mechanism is the
same as for ``KeyboardInterrupt``, which pytest itself would catch); the subprocess tests send a
real SIGINT and see ``KeyboardInterrupt``.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import tribosweep as ts

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a process is POSIX")

#: Seconds from the signal to the end of the interrupted call (see the module docstring).
REACTION = 2.0

SEED = ts.SliderModel(contact="bilateral")
#: Unilateral contact at mu = 0.3: sliding is unstable and the motion grows into the bouncing cycle.
BOUNCING = SEED.replace(contact="unilateral", mu=0.30)


@pytest.fixture(scope="module", autouse=True)
def _imports_done():
    """xarray imports its backends and chunk managers (dask, scipy, numpy.f2py: 353 modules, 0.35 s)
    at its first Dataset. A signal in the middle of that import (boundary_curves builds Datasets
    within the signal's first 0.3 s) left a .pyc file unclosed, and its ResourceWarning failed the
    test (1 run in 8 when this module ran alone). They are done before any signal is sent."""
    xr.Dataset({"x": ("i", np.zeros(1))})


class Interrupted(Exception):
    """Raised by the test's SIGINT handler."""


@contextmanager
def sigint_after(delay: float):
    """Send SIGINT to this process after ``delay`` s; the handler raises :class:`Interrupted`.
    Yields a dict that gets the monotonic time of the signal under ``"t"``."""
    fired: dict[str, float] = {}

    def handler(signum, frame):
        raise Interrupted

    def send():
        fired["t"] = time.monotonic()
        os.kill(os.getpid(), signal.SIGINT)

    old = signal.signal(signal.SIGINT, handler)
    timer = threading.Timer(delay, send)
    timer.start()
    try:
        yield fired
    finally:
        timer.cancel()
        timer.join()
        signal.signal(signal.SIGINT, old)


def stops_promptly(call) -> float:
    """Run ``call`` with a SIGINT 0.3 s in; it must raise Interrupted. Returns the reaction [s]."""
    with sigint_after(0.3) as fired:
        with pytest.raises(Interrupted):
            call()
        stopped = time.monotonic()
    return stopped - fired["t"]


def _many(n: int) -> dict[str, np.ndarray]:
    return {"mu": np.full(n, 0.215)}


SLOW_CALLS = {
    # One trajectory of 10^5 s of bouncing (an hour of work); t_eval keeps it from storing steps.
    "simulate": lambda: ts.simulate(BOUNCING, 1e5, t_eval=[1e5], y0=[0.1e-6, 0, 0, 0, 0, 0]),
    # 30,000 trajectories of 20 s on the batch route (bilateral end state), two threads: the
    # loops' own reaction (many short runs: "ensemble batch, many" below).
    "ensemble batch": lambda: ts.ensemble(SEED, 20.0, _many(30_000), threads=2),
    # ... on the lanes (unilateral), one thread.
    "ensemble lanes": lambda: ts.ensemble(SEED.replace(contact="unilateral"), 20.0, _many(30_000), threads=1),
    # Many short runs: what a cancelled call does with every unfinished result. Each once got a
    # boxed summary, allocated and faulted in: 0.5-1.0 s to stop 300,000 (2.3 s for 10^6); now
    # 0.05-0.09 s (0.19-0.29 s), 2026-11-26.
    "ensemble batch, many": lambda: ts.ensemble(SEED, 1.0, _many(300_000), threads=2),
    # ... on the scalar driver (Rodas4 is not lane-batched).
    "ensemble scalar": lambda: ts.ensemble(SEED, 1.0, _many(100_000), method="rodas4", threads=2),
    # Runs to steady state that never repeat to 1e-15: each would go on to t_max = 10^4 s.
    "ensemble steady": lambda: ts.ensemble(BOUNCING, 1e4, {"mu": [0.3, 0.3]}, y0=[0.1e-6, 0, 0, 0, 0, 0],
                                           steady=True, periodic_tol=1e-15, threads=2),  # fmt: skip
    # A billion grid points of the describing function's scan.
    "describing_function": lambda: ts.describing_function(SEED, n_grid=10**9),
    # The fold and grazing curves of a box at 60 slices (about 10 s), on pool threads, where no
    # signal arrives: the main thread's stop event ends them at their next branch. On two threads
    # the kinds run at once (each curve's slices on one), on one the slices run on one pool thread.
    "boundary_curves, 2 threads": lambda: ts.boundary_curves(SEED, slices=60, threads=2),
    "boundary_curves, 1 thread": lambda: ts.boundary_curves(SEED, slices=60, threads=1),
}


@pytest.mark.parametrize("name", list(SLOW_CALLS))
def test_a_signal_stops_a_long_call_promptly(name):
    reaction = stops_promptly(SLOW_CALLS[name])
    assert reaction < REACTION, f"{name}: {reaction:.2f} s from the signal to the exception"


def test_a_signal_delivered_to_a_pool_thread_still_stops_boundary_curves_promptly():
    # The kernel gives a process-directed SIGINT (Ctrl-C, os.kill) to any thread. One that lands on
    # a pool thread wakes no blocked wait of the main thread; Python runs the handler once the
    # main thread is back in the interpreter. boundary_curves waited for its kinds' futures without
    # a timeout: a signal on a pool thread waited for the whole box (10.4-10.6 s, once in CI).
    fired: dict[str, float] = {}

    def handler(signum, frame):
        raise Interrupted

    def send():
        others = [t for t in threading.enumerate() if t not in (threading.main_thread(), threading.current_thread())]
        assert others, "no pool thread to signal"
        fired["t"] = time.monotonic()
        signal.pthread_kill(others[0].ident, signal.SIGINT)

    old = signal.signal(signal.SIGINT, handler)
    timer = threading.Timer(0.5, send)
    timer.start()
    try:
        with pytest.raises(Interrupted):
            ts.boundary_curves(SEED, slices=60, threads=2)
        reaction = time.monotonic() - fired["t"]
    finally:
        timer.cancel()
        timer.join()
        signal.signal(signal.SIGINT, old)
    assert reaction < REACTION, f"{reaction:.2f} s from the signal to the exception"


def test_after_an_interrupted_call_the_next_one_is_unchanged():
    # The thread pools and the per-call stop request survive an interruption: the same small
    # ensemble gives bitwise the same numbers before and after (and on 1 and 2 threads).
    def small(threads):
        ds = ts.ensemble(SEED.replace(contact="unilateral"), 0.05, {"mu": np.linspace(0.2, 0.3, 16)}, threads=threads)
        return np.concatenate([ds[v].values for v in ("z_end", "x_end", "phi_dot_end", "t_reached")])

    before = small(2)
    stops_promptly(SLOW_CALLS["ensemble lanes"])
    stops_promptly(SLOW_CALLS["ensemble batch"])
    after = small(2)
    assert np.array_equal(before, after)
    assert np.array_equal(before, small(1))


def test_a_signal_stops_chunks_computing_on_the_sweeps_own_threads():
    # On 8 threads a sweep computes 2 chunks at once on threads of its own process
    # (runner.overlap), where Python delivers no signal. Each chunk here is one point on the
    # bouncing cycle, which never repeats to 1e-15, so its transient would run to t_max = 10^4 s.
    # The signal stops the main thread's wait; the main thread then stops the chunks' core calls:
    # the sweep ends within REACTION, no chunk thread computes on, and later calls are unaffected.
    def sweep():
        ts.sweep(BOUNCING, extra_axes={"mu": [0.28, 0.29, 0.3]}, strategy="transient", census=False, t_max=1e4,
                 periodic_tol=1e-15, chunk_size=1, threads=8, progress=False, boundaries=False)  # fmt: skip

    before = ts.ensemble(BOUNCING, 0.05, {"mu": [0.25, 0.3]}, threads=2)
    reaction = stops_promptly(sweep)
    assert reaction < REACTION, f"{reaction:.2f} s from the signal to the exception"
    assert not [t.name for t in threading.enumerate() if t.name.startswith("tribosweep-chunk")]
    after = ts.ensemble(BOUNCING, 0.05, {"mu": [0.25, 0.3]}, threads=2)
    for name in ("z_end", "x_end", "phi_dot_end"):
        np.testing.assert_array_equal(before[name].values, after[name].values)


def test_stopped_calls_refuse_to_start_until_released():
    from tribosweep import _core

    _core.stop_calls(True)
    try:
        with pytest.raises(KeyboardInterrupt, match="stop_calls"):
            ts.ensemble(SEED, 0.01, {"mu": [0.2]}, threads=1)
    finally:
        _core.stop_calls(False)
    assert np.isfinite(ts.ensemble(SEED, 0.01, {"mu": [0.2]}, threads=1).z_end.values).all()


def _run_until(script: str, ready, args=(), timeout: float = 120.0):
    """Start ``script`` in a fresh interpreter; once ``ready()`` is true (polled), send SIGINT and
    return (seconds from the signal to the exit, return code, stderr)."""
    proc = subprocess.Popen([sys.executable, "-c", textwrap.dedent(script), *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)  # fmt: skip
    try:
        start = time.monotonic()
        while not ready(proc):
            assert proc.poll() is None, f"ended early: {proc.communicate()}"
            assert time.monotonic() - start < timeout, "never got ready"
            time.sleep(0.05)
        time.sleep(0.3)  # inside the Rust code by now
        assert proc.poll() is None, f"ended before the signal: {proc.communicate()}"
        t0 = time.monotonic()
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
        return time.monotonic() - t0, proc.returncode, err
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def _printed_started(proc) -> bool:
    return proc.stdout.readline().strip() == "started"


def test_ctrl_c_interrupts_the_describing_function_with_keyboard_interrupt():
    script = """
        import tribosweep as ts
        print("started", flush=True)
        ts.describing_function(ts.SliderModel(), n_grid=10**9)
        print("finished", flush=True)
    """
    elapsed, code, err = _run_until(script, _printed_started)
    assert elapsed < REACTION, f"{elapsed:.2f} s from SIGINT to exit"
    assert code != 0 and "KeyboardInterrupt" in err, err


def test_ctrl_c_stops_overlapped_chunks_and_leaves_no_suspects(tmp_path: Path):
    # The chunks of an 8-thread sweep compute two at a time on threads of the process; one of
    # mu = 0.1 (quick) and three on the never-repeating cycle. Ctrl-C once the quick one is saved:
    # the process exits within REACTION, and the interrupted chunks leave no "running" markers,
    # which would make a resume run them alone in fresh processes as crash suspects.
    out = tmp_path / "sweep.nc"
    script = """
        import sys
        import tribosweep as ts
        ts.sweep(ts.SliderModel(contact="unilateral"), extra_axes={"mu": [0.1, 0.28, 0.29, 0.3]},
                 strategy="transient", census=False, t_max=1e4, periodic_tol=1e-15, chunk_size=1, threads=8,
                 output=sys.argv[1], progress=False, boundaries=False)
    """
    parts = Path(f"{out}.parts")
    elapsed, code, err = _run_until(script, lambda proc: (parts / "chunk_000000.npz").exists(), args=(str(out),))
    assert elapsed < REACTION, f"{elapsed:.2f} s from SIGINT to exit"
    assert code != 0 and "KeyboardInterrupt" in err, err
    assert "interrupted: 1 of 4 chunks are saved" in err, err
    running = parts / "running"
    assert not running.exists() or not list(running.iterdir()), list(running.iterdir())


def test_ctrl_c_inside_a_slow_chunk_keeps_the_finished_chunks(tmp_path: Path):
    # Two chunks of one point each: mu = 0.1 (sliding stable: the transient decays in well under a
    # second) and mu = 0.3 (the bouncing cycle, which never repeats to periodic_tol = 1e-15, so
    # its transient would run to t_max = 10^4 s). SIGINT while the second runs: the sweep exits
    # within REACTION, says what it kept, and the first chunk's part stays on disk for a resume.
    out = tmp_path / "sweep.nc"
    script = """
        import sys
        import tribosweep as ts
        ts.sweep(ts.SliderModel(contact="unilateral"), extra_axes={"mu": [0.1, 0.3]}, strategy="transient",
                 census=False, t_max=1e4, periodic_tol=1e-15, chunk_size=1, threads=1, output=sys.argv[1],
                 progress=False, boundaries=False)
    """
    first = Path(f"{out}.parts") / "chunk_000000.npz"
    elapsed, code, err = _run_until(script, lambda proc: first.exists(), args=(str(out),))
    assert elapsed < REACTION, f"{elapsed:.2f} s from SIGINT to exit"
    assert code != 0 and "KeyboardInterrupt" in err, err
    assert "interrupted: 1 of 2 chunks are saved" in err, err
    assert first.exists() and not (Path(f"{out}.parts") / "chunk_000001.npz").exists()
    assert not out.exists()
    with np.load(first) as part:  # a complete, readable part
        assert len(part.files) > 0
