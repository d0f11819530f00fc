"""dask.distributed: a sweep's chunks on a cluster (``scheduler=``, ``--scheduler``, ``[dask] scheduler``).

``scheduler`` is the address of a running dask scheduler (``tcp://host:8786``), or ``local:N``,
which starts a ``LocalCluster`` of ``N`` worker processes on this machine for the sweep and closes
it afterwards. The chunks are the same pure function as everywhere (``compute_chunk``), sent with
``Client.submit``; the client saves each finished chunk to ``<output>.parts/`` at once, so the
parts directory stays the single source of truth: a client that dies loses at most the chunks in
flight, and ``resume=True`` against any cluster (or none) finishes the sweep.

Threads: a dask worker runs ``nthreads`` tasks at once, so each task gets the worker's thread
budget divided among those slots: one Rust thread per dask thread by default, so a worker never
runs more threads than it was given. A worker's budget is ``TRIBOSWEEP_THREADS`` in its
environment when set (``local:N`` starts workers of one slot each with ``TRIBOSWEEP_THREADS`` =
cores / N: each runs one chunk at a time on its share of the cores), else its ``nthreads``.
An explicit ``threads=`` is used as given.

Chunks: without ``chunk_size`` a sweep on a cluster cuts its points into at least
``CHUNKS_PER_THREAD`` chunks per worker thread (never more points per chunk than the default),
so that every thread has work until the end; a resumed sweep keeps the chunking it started with.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator

#: Most worker processes ``local:N`` starts.
MAX_LOCAL_WORKERS: int = 256
#: Chunks per worker thread a sweep on a cluster aims at (for load balance at the end of a sweep).
CHUNKS_PER_THREAD: int = 4
#: Seconds to wait for a scheduler to answer.
CONNECT_TIMEOUT: str = "10s"


def check_scheduler(value) -> str:
    """A scheduler address or ``local:N``, checked before any work (``ValueError`` naming the value)."""
    if not isinstance(value, str) or not value.strip():
        raise ValueError(f"scheduler = {value!r} is not valid: give a dask scheduler address such as "
                         "'tcp://host:8786', or 'local:N' to start N worker processes on this machine")  # fmt: skip
    value = value.strip()
    if value.startswith("local:"):
        n = value[len("local:") :]
        if not n.isdigit() or not 1 <= int(n) <= MAX_LOCAL_WORKERS:
            raise ValueError(f"scheduler = {value!r} is out of range: N must be an integer in "
                             f"[1, {MAX_LOCAL_WORKERS}] (worker processes on this machine)")  # fmt: skip
    return value


def _distributed():
    try:
        import distributed
    except ImportError:
        raise ImportError("a dask scheduler needs dask.distributed: pip install 'tribosweep[dask]'") from None
    return distributed


@contextlib.contextmanager
def connect(scheduler: str) -> Iterator:
    """A dask ``Client`` of ``scheduler`` (see :func:`check_scheduler`), closed afterwards."""
    distributed = _distributed()
    if scheduler.startswith("local:"):
        n = int(scheduler[len("local:") :])
        per = max(1, (os.cpu_count() or 1) // n)
        with distributed.LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                                      env={"TRIBOSWEEP_THREADS": str(per)}) as cluster:  # fmt: skip
            with distributed.Client(cluster) as client:
                yield client
        return
    try:
        client = distributed.Client(scheduler, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError) as e:
        raise OSError(f"scheduler = {scheduler!r}: cannot connect to a dask scheduler there ({e})") from None
    with client:
        yield client


def total_threads(client) -> int:
    """Task slots of the whole cluster (the sum of its workers' ``nthreads``)."""
    return max(1, sum(client.nthreads().values()))


def chunk_size(n_points: int, default: int, threads: int) -> int:
    """Points per chunk on a cluster of ``threads`` task slots: at most ``default``, and small enough for
    ``CHUNKS_PER_THREAD`` chunks per slot.

    Examples
    --------
    >>> chunk_size(2000, 64, 32), chunk_size(10**6, 4096, 32), chunk_size(10, 64, 8)
    (16, 4096, 1)
    """
    return max(1, min(default, -(-n_points // (CHUNKS_PER_THREAD * threads))))


def worker_threads(dask_worker=None) -> int:
    """Rust threads for one task on this dask worker (``Client.run`` passes ``dask_worker``; inside a
    task it is found): its thread budget over its task slots."""
    if dask_worker is None:
        from distributed import get_worker

        dask_worker = get_worker()
    slots = max(1, int(dask_worker.state.nthreads))
    env = os.environ.get("TRIBOSWEEP_THREADS", "")
    budget = int(env) if env.isdigit() and int(env) > 0 else slots
    return max(1, budget // slots)


def code_identity() -> dict:
    """The code identity of this process (what a sweep's manifest records)."""
    from .. import __version__
    from .plan import core_build

    return {"tribosweep_version": __version__, "core_build": core_build()}


def check_workers(client) -> None:
    """Refuse a cluster whose workers run other code than this process: their numbers could differ."""
    mine = code_identity()
    for worker, theirs in client.run(code_identity).items():
        if theirs != mine:
            raise ValueError(f"the dask worker {worker} runs tribosweep {theirs}, this process {mine}: install the "
                             "same build on every worker (results must not depend on where a chunk ran)")  # fmt: skip


def provenance(client) -> dict:
    """Global attributes of a sweep run on a cluster."""
    import dask
    import distributed

    workers = client.nthreads()
    return {
        "dask_version": dask.__version__,
        "dask_distributed_version": distributed.__version__,
        "dask_scheduler": str(client.scheduler.address),
        "dask_workers": len(workers),
        "dask_worker_threads": int(sum(workers.values())),
    }
