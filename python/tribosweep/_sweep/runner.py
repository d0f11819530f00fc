"""Running a sweep's chunks: in-process, on a process or thread pool, or on a dask cluster, surviving crashes.

Every backend runs the same pure function (:func:`tribosweep._sweep.chunk.compute_chunk`) through
:func:`run_task`, and hands each finished chunk to ``sink(k, arrays)`` as soon as it is complete
(with an output file the sink saves the part at once, so nothing finished is lost to a later fault).

A point that kills its process (an abort, a segmentation fault, a stack overflow in native code)
costs only itself:

- **process pool** (``concurrent.futures.ProcessPoolExecutor``): a dead worker breaks the pool. The
  chunks that had started (each marks itself in a ``running/`` folder while it computes) are the
  suspects; those not yet started go back to the queue untouched, on a new pool of the same size.
  Each suspect is run again alone in a fresh process. One that crashes again is split in halves,
  and so on down to single points; a single point that has crashed ``MAX_CRASHES`` times is
  **quarantined**: regime and status ``crashed``, with a reason, and the sweep goes on.
- **dask**: the scheduler retries a task whose worker died (``distributed.scheduler.allowed-failures``
  times, 3 by default) and then reports ``KilledWorker``; such a chunk is split and its halves
  sent to the cluster again, down to single points. The scheduler blames every task that was on
  the dying worker, bystanders included, so a single point is then run alone in a fresh process on
  the client's machine: it is quarantined only if it kills that process too.
- **in-process** (no executor): a crash ends the process; the chunks it was computing (one, or up to
  :data:`MAX_OVERLAP` on 8 or more threads: :func:`overlap`) stay marked in
  ``<output>.parts/running/``, and the resumed sweep runs each alone in a fresh process first,
  with the splitting above. A crash is survived across resumes, never repeated forever.

Chunks on threads of the sweep's own process (a ``ThreadPoolExecutor``, or the in-process default
on many threads) are stopped by Ctrl-C as promptly as a chunk on the main thread: Python delivers
the signal to the main thread only, which then stops their core calls (:func:`stop_running`).

Test hook: :func:`run_task` honours the environment variable ``TRIBOSWEEP_TEST_CRASH`` (a JSON
object, see :func:`_test_crash_hook`) so that the tests can crash a real worker process on a chosen
point. It is never set in production; nothing else in the product reads it.
"""

from __future__ import annotations

import collections
import concurrent.futures
import json
import logging
import multiprocessing
import os
import shutil
import signal
import tempfile
from collections.abc import Callable, Iterable
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import _checks, _core
from .._codes import DECIDED_BY, REGIME, STATUS_CRASHED
from . import chunk as _chunk
from . import schema
from .plan import Plan

_log = logging.getLogger("tribosweep")

#: Crashes of its process after which a single point is quarantined (a chunk is split after one
#: crash on its own; the point has then crashed at least once inside a bigger piece already).
MAX_CRASHES: int = 2
#: Chunks handed to an executor at a time (executors queue whatever they are given, each task with
#: its points' parameters, so the tasks are fed in windows to keep memory bounded).
EXECUTOR_WINDOW: int = 256
#: The environment variable of the test hook (see the module docstring).
TEST_CRASH_ENV: str = "TRIBOSWEEP_TEST_CRASH"
#: Most chunks a sweep without an executor computes at once (:func:`overlap`).
MAX_OVERLAP: int = 4
#: Seconds the sweep waits, after Ctrl-C, for the chunks computing on its own threads to stop.
STOP_WAIT: float = 10.0


def overlap(threads: int | None) -> int:
    """Chunks a sweep without an executor computes at once on ``threads`` core threads (None: the default).

    A chunk is a sequence of core calls, each of which ends with its longest runs finishing on a
    few threads (a census's slowest disturbances, a transient that goes on to ``t_max``), with
    Python between them (clustering the cycles, assembling the arrays) on one thread. On 2 cores
    that idle time is small; on 16 cores it is a fifth of the sweep. From 8 threads on, chunks
    therefore run on threads of the process, one chunk per 4 core threads (at most
    :data:`MAX_OVERLAP`), whose core calls share the process's thread pool, so that one chunk's tail
    is filled by another's work. The results are the same bits (a chunk's result does not depend on
    what runs beside it). Measured on a 16-core Intel Xeon, 16 threads, runs alternating: the
    98,394-point grid of ``benches/bench_sweep.py`` with its census 15.0-15.7 s one chunk at a time,
    12.1-12.4 s four at once; the 2,000-point grid of ``benches/bench_census.py`` 1.95 -> 1.58 s.

    >>> overlap(2), overlap(8), overlap(12), overlap(64)
    (1, 2, 3, 4)
    """
    n = _checks.default_threads() if threads is None else int(threads)
    return 1 if n < 8 else min(MAX_OVERLAP, n // 4)


def stop_running(futures) -> None:
    """Ctrl-C (or an error) reached the main thread while chunks compute on other threads of this
    process, where Python delivers no signal: stop their core calls (each raises
    ``KeyboardInterrupt`` there, and new ones are refused) and wait for those threads to end."""
    _core.stop_calls(True)
    try:
        concurrent.futures.wait(futures, timeout=STOP_WAIT)
    finally:
        _core.stop_calls(False)


def run_task(task: tuple) -> dict[str, np.ndarray]:
    """One call of the chunk function (module level, so executors can pickle it)."""
    if TEST_CRASH_ENV in os.environ:
        _test_crash_hook(task)
    # Looked up at call time (not bound at import) so that tests can patch it.
    return _chunk.compute_chunk(*task)


def run_dask_task(task: tuple) -> dict[str, np.ndarray]:
    """:func:`run_task` on a dask worker, with the worker's threads unless the sweep gave ``threads``."""
    from .cluster import worker_threads

    if task[5].get("threads") is None:
        task = (*task[:5], dict(task[5], threads=worker_threads()))
    return run_task(task)


def run_marked(task: tuple, marker: str) -> dict[str, np.ndarray]:
    """:func:`run_task` with a marker file that exists while the task computes (the suspects of a
    crash: a process that dies leaves it; an exception, Ctrl-C included, does not)."""
    Path(marker).touch()
    try:
        return run_task(task)
    finally:
        Path(marker).unlink(missing_ok=True)


def _test_crash_hook(task: tuple) -> None:
    """TEST HOOK ONLY: crash this process when the task holds a chosen point.

    ``TRIBOSWEEP_TEST_CRASH`` is a JSON object, or a list of them: ``normal_load`` (the point's
    load, compared exactly), ``action`` (``"abort"``: ``os.abort()``, SIGABRT; ``"exit"``:
    ``os._exit(70)``), optional ``once`` (a file: crash only if it can be created, i.e. on the
    first attempt) and optional ``log`` (a file that gets one line per call: the task's first load
    and its size).
    """
    specs = json.loads(os.environ[TEST_CRASH_ENV])
    loads = np.asarray(task[3]["normal_load"])
    for spec in specs if isinstance(specs, list) else [specs]:
        if spec.get("log"):
            with open(spec["log"], "a") as f:
                f.write(f"{float(loads[0])!r} {loads.size}\n")
        if float(spec["normal_load"]) not in loads:
            continue
        if spec.get("once"):
            try:
                os.close(os.open(spec["once"], os.O_CREAT | os.O_EXCL | os.O_WRONLY))
            except FileExistsError:
                continue
        if spec.get("action") == "exit":
            os._exit(70)
        os.abort()


# --- running one piece alone in a fresh process ---------------------------------------------------


class ProcessCrash(Exception):
    """The process computing a piece died (``how`` says of what)."""

    def __init__(self, how: str):
        super().__init__(how)
        self.how = how


def _isolated_main(task: tuple, conn, test_hook: str | None) -> None:
    if test_hook is not None:  # a forkserver's children inherit its environment, not the sweep's
        os.environ[TEST_CRASH_ENV] = test_hook
    try:
        conn.send((True, run_task(task)))
    except BaseException as e:  # noqa: BLE001 - a Python error is sent back and raised there
        try:
            conn.send((False, e))
        except Exception:  # noqa: BLE001 - an exception that does not pickle goes back as text
            conn.send((False, RuntimeError(f"{type(e).__name__}: {e}")))
    finally:
        conn.close()


def _fresh_context():
    """Where isolated processes come from: a fork server with the package loaded (a new process in
    milliseconds, and none of the parent's threads or locks), else spawn."""
    if "forkserver" in multiprocessing.get_all_start_methods():
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(["tribosweep._sweep.runner"])  # effective if the server is not running yet
        return ctx
    return multiprocessing.get_context("spawn")


def isolate(task: tuple) -> dict[str, np.ndarray]:
    """Run one task in a fresh process (nothing inherited but the arguments).

    Raises
    ------
    ProcessCrash
        The process died before returning (its exit signal or status in the message).
    """
    ctx = _fresh_context()
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_isolated_main, args=(task, send, os.environ.get(TEST_CRASH_ENV)), daemon=True)
    proc.start()
    send.close()
    try:
        ok, payload = recv.recv()
    except EOFError:
        ok, payload = None, None
    finally:
        recv.close()
        proc.join()
    if ok is None:
        code = proc.exitcode
        how = f"killed by {signal.Signals(-code).name}" if code is not None and code < 0 else f"exit status {code}"
        raise ProcessCrash(how)
    if not ok:
        raise payload
    return payload


# --- pieces: chunks and their halves ---------------------------------------------------------------


@dataclass
class Piece:
    """Points ``[start, stop)`` of chunk ``k``; ``crashes`` counts process deaths attributed to it."""

    k: int
    start: int
    stop: int
    crashes: int = 0
    how: str = ""

    @property
    def size(self) -> int:
        return self.stop - self.start

    def halves(self) -> list[Piece]:
        mid = (self.start + self.stop) // 2
        return [Piece(self.k, self.start, mid, self.crashes, self.how), Piece(self.k, mid, self.stop, self.crashes, self.how)]


def crashed_result(n: int, reason: str, *, wear_rate: bool) -> dict[str, np.ndarray]:
    """The output of ``n`` quarantined points: regime and status ``crashed``, the reason, fill values elsewhere."""
    out = schema.empty_result(n, wear_rate=wear_rate)
    out["regime"][:] = REGIME["crashed"]
    out["status"][:] = STATUS_CRASHED
    out["decided_by"][:] = DECIDED_BY["quarantine"]
    out["wear_applicability"][:] = 2  # undetermined
    out["reason"] = np.full(n, reason)
    return out


class _Assembly:
    """Collects the pieces of split chunks and hands each chunk to the sink once it is whole."""

    def __init__(self, plan: Plan, sink: Callable[[int, dict], None], bar):
        self.plan, self.sink, self.bar = plan, sink, bar
        self.pieces: dict[int, dict[int, dict]] = collections.defaultdict(dict)

    def add(self, piece: Piece, arrays: dict) -> None:
        got = self.pieces[piece.k]
        got[piece.start] = arrays
        start, stop = self.plan.chunk_range(piece.k)
        if sum(len(next(iter(a.values()))) for a in got.values()) < stop - start:
            return
        del self.pieces[piece.k]
        parts = [got[s] for s in sorted(got)]
        whole = parts[0] if len(parts) == 1 else {name: np.concatenate([p[name] for p in parts]) for name in parts[0]}
        self.sink(piece.k, whole)
        self.bar.update(stop - start)

    def quarantine(self, piece: Piece) -> None:
        p = self.plan
        at = ", ".join(f"{d} = {float(v):.6g}" for d, v in zip(p.dims, p.point_values(piece.start)))
        reason = (f"crashed: computing this point kills its process ({piece.how}; in its chunk, in smaller pieces "
                  "and alone); it was quarantined so that the rest of the sweep could finish; rerun it alone to "
                  "investigate")  # fmt: skip
        _log.warning("quarantined the point %s (%s): %s", piece.start, at, piece.how)
        self.add(piece, crashed_result(piece.size, reason, wear_rate=p.wear_calibration is not None))


# --- the backends ----------------------------------------------------------------------------------


def is_dask(executor) -> bool:
    """True for a dask ``distributed.Client``."""
    return type(executor).__module__.split(".")[0] == "distributed" and hasattr(executor, "submit")


def run(plan: Plan, chunks: Iterable[int], threads, executor, sink, bar, *, markers: Path | None = None,
        suspects: Iterable[int] = ()) -> None:  # fmt: skip
    """Compute ``chunks`` and hand each finished one to ``sink(k, arrays)`` (in completion order).

    ``markers`` is the folder of running-chunk markers (``<output>.parts/running``; a temporary one
    is made for a process pool without output). ``suspects`` are chunks a previous run was
    computing when its process died: they run alone in a fresh process first.
    """
    chunks = list(chunks)
    asm = _Assembly(plan, sink, bar)
    suspects = [k for k in suspects if k in set(chunks)]
    isolated = [Piece(k, *plan.chunk_range(k), crashes=1, how="its process died in an earlier run") for k in suspects]
    rest = [k for k in chunks if k not in set(suspects)]
    if executor is None:
        _run_isolated(plan, isolated, threads, asm)
        inflight = min(overlap(threads), len(rest))
        if inflight > 1:
            with concurrent.futures.ThreadPoolExecutor(inflight, thread_name_prefix="tribosweep-chunk") as pool:
                _run_pool(plan, rest, threads, pool, asm, markers, [])
        else:
            _run_serial(plan, rest, threads, asm, markers)
    elif is_dask(executor):
        _run_isolated(plan, isolated, threads, asm)
        _run_dask(plan, rest, threads, executor, asm)
    elif hasattr(executor, "submit"):
        _run_pool(plan, rest, threads, executor, asm, markers, isolated)
    else:
        _run_isolated(plan, isolated, threads, asm)
        _run_map(plan, rest, threads, executor, asm)


def _run_isolated(plan: Plan, pieces: list[Piece], threads, asm: _Assembly) -> None:
    queue = collections.deque(pieces)
    while queue:
        piece = queue.popleft()
        try:
            asm.add(piece, isolate(plan.task_range(piece.start, piece.stop, threads)))
        except ProcessCrash as e:
            queue.extendleft(reversed(_after_crash(piece, e.how, asm)))


def _after_crash(piece: Piece, how: str, asm: _Assembly) -> list[Piece]:
    """A piece killed its process (for certain): its halves to run alone, or quarantine for a point."""
    piece.crashes += 1
    piece.how = how
    if piece.size > 1:
        _log.warning("chunk %d, points %d-%d: %s; splitting it", piece.k, piece.start, piece.stop - 1, how)
        return piece.halves()
    if piece.crashes >= MAX_CRASHES:
        asm.quarantine(piece)
        return []
    return [piece]


def _run_serial(plan: Plan, chunks: list[int], threads, asm: _Assembly, markers: Path | None) -> None:
    for k in chunks:
        start, stop = plan.chunk_range(k)
        marker = None if markers is None else markers / f"{k}_{start}_{stop}"
        if marker is not None:
            marker.touch()
        try:
            asm.add(Piece(k, start, stop), run_task(plan.task_range(start, stop, threads)))
        finally:
            if marker is not None:  # reached unless the process itself died
                marker.unlink(missing_ok=True)


def _run_map(plan: Plan, chunks: list[int], threads, executor, asm: _Assembly) -> None:
    """Executors with only ``map``: in windows, no crash supervision."""
    for i in range(0, len(chunks), EXECUTOR_WINDOW):
        window = chunks[i : i + EXECUTOR_WINDOW]
        results = executor.map(run_task, [plan.task(k, threads) for k in window])
        for k, res in zip(window, results):
            if hasattr(res, "result"):  # futures
                res = res.result()
            asm.add(Piece(k, *plan.chunk_range(k)), res)


def slots(executor) -> int:
    """Workers of a ``concurrent.futures`` executor (else the cores of this machine)."""
    n = getattr(executor, "_max_workers", None)
    return int(n) if isinstance(n, int) and n > 0 else os.cpu_count() or 1


def _run_pool(plan, chunks, threads, executor, asm: _Assembly, markers: Path | None, isolated: list[Piece]) -> None:
    """``concurrent.futures`` executors: pieces by ``submit``, isolation of suspects after a broken pool."""
    own_markers = markers is None
    markers = Path(tempfile.mkdtemp(prefix="tribosweep-running-")) if own_markers else markers
    queue = collections.deque(Piece(k, *plan.chunk_range(k)) for k in chunks)
    alone = collections.deque(isolated)  # pieces to run alone in a fresh process
    window = min(EXECUTOR_WINDOW, 2 * slots(executor) + 2)
    inflight: dict[concurrent.futures.Future, tuple[Piece, Path | None]] = {}
    owned: list = []  # pools made here to replace broken ones
    lone = concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix="tribosweep-isolate")
    lone_busy = False
    try:
        while queue or alone or inflight:
            broken = False
            while queue and sum(m is not None for _p, m in inflight.values()) < window:
                piece = queue.popleft()
                marker = markers / f"{piece.k}_{piece.start}_{piece.stop}"
                task = plan.task_range(piece.start, piece.stop, threads)
                try:
                    inflight[executor.submit(run_marked, task, str(marker))] = (piece, marker)
                except BrokenProcessPool:  # it broke since the last look
                    queue.appendleft(piece)
                    broken = True
                    break
            if alone and not lone_busy:
                piece = alone.popleft()
                inflight[lone.submit(isolate, plan.task_range(piece.start, piece.stop, threads))] = (piece, None)
                lone_busy = True
            done = set()
            if not broken:
                done, _ = concurrent.futures.wait(list(inflight), return_when=concurrent.futures.FIRST_COMPLETED)
            for f in done:
                piece, marker = inflight.pop(f)
                if marker is None:
                    lone_busy = False
                try:
                    res = f.result()
                except ProcessCrash as e:
                    alone.extendleft(reversed(_after_crash(piece, e.how, asm)))
                    continue
                except BrokenProcessPool:
                    broken = True
                    _requeue(piece, marker, queue, alone)
                    continue
                asm.add(piece, res)
            if broken:
                # Every future of the broken pool fails: the pieces that had started are suspects.
                for f in [f for f, (_p, m) in inflight.items() if m is not None]:
                    piece, marker = inflight.pop(f)
                    if f.done() and not f.cancelled() and f.exception() is None:
                        asm.add(piece, f.result())  # finished just before the break
                    else:
                        f.cancel()
                        _requeue(piece, marker, queue, alone)
                executor = _replacement(executor)
                owned.append(executor)
                _log.warning("a worker process died: its chunk runs again alone, the others go on in a new pool")
    except BaseException:
        for f in inflight:
            f.cancel()
        if isinstance(executor, concurrent.futures.ThreadPoolExecutor):
            stop_running([f for f, (_p, m) in inflight.items() if m is not None])
        raise
    finally:
        lone.shutdown(wait=False, cancel_futures=True)
        for ex in owned:
            ex.shutdown(wait=False, cancel_futures=True)
        if own_markers:
            shutil.rmtree(markers, ignore_errors=True)


def _requeue(piece: Piece, marker: Path, queue: collections.deque, alone: collections.deque) -> None:
    """A piece of a broken pool: a suspect (it had started) runs alone, any other goes back to the queue."""
    if marker.exists():
        marker.unlink(missing_ok=True)
        piece.crashes += 1
        piece.how = "its worker process died"
        alone.append(piece)
    else:
        queue.appendleft(piece)


def _replacement(executor):
    """A new process pool like the broken one (the caller's own pool cannot be used again)."""
    return concurrent.futures.ProcessPoolExecutor(
        max_workers=getattr(executor, "_max_workers", None), mp_context=getattr(executor, "_mp_context", None)
    )


def _run_dask(plan: Plan, chunks: list[int], threads, client, asm: _Assembly) -> None:
    """A dask cluster: pieces by ``submit``; a piece that killed its workers (``KilledWorker``) is split."""
    from distributed import wait
    from distributed.scheduler import KilledWorker

    from .cluster import total_threads

    queue = collections.deque(Piece(k, *plan.chunk_range(k)) for k in chunks)
    window = min(EXECUTOR_WINDOW, 2 * total_threads(client) + 2)
    inflight: dict = {}
    suspects: list[Piece] = []  # single points whose workers died: culprits or bystanders
    try:
        while queue or inflight:
            while queue and len(inflight) < window:
                piece = queue.popleft()
                task = plan.task_range(piece.start, piece.stop, threads)
                inflight[client.submit(run_dask_task, task, pure=False)] = piece
            done, _ = wait(list(inflight), return_when="FIRST_COMPLETED")
            for f in done:
                piece = inflight.pop(f)
                try:
                    res = f.result()
                except KilledWorker as e:
                    piece.how = f"its dask workers died ({e})"
                    if piece.size > 1:
                        piece.crashes += 1
                        _log.warning("chunk %d, points %d-%d: %s; splitting it", piece.k, piece.start,
                                     piece.stop - 1, piece.how)  # fmt: skip
                        queue.extendleft(reversed(piece.halves()))
                    else:
                        suspects.append(piece)
                    continue
                asm.add(piece, res)
    except BaseException:
        for f in inflight:
            f.cancel()
        raise
    # The scheduler blames every task that was on a worker when it died, including those that only
    # shared the worker with the culprit. A single point is therefore quarantined only if it kills
    # a fresh process of its own here too; a bystander is computed there instead.
    for piece in suspects:
        try:
            asm.add(piece, isolate(plan.task_range(piece.start, piece.stop, threads)))
        except ProcessCrash as e:
            piece.how = f"{piece.how}; alone in a fresh process: {e.how}"
            asm.quarantine(piece)
