"""The contract of the compiled core ``tribosweep._core`` at the Python boundary.

- One exception hierarchy: ``TribosweepError`` is the base of every error raised on purpose; bad
  input raises ``InvalidArgumentError``, which is also a ``ValueError`` (so ``except ValueError``
  keeps working), with a message that names the argument, its value and what is valid.
- Optional parameters are keyword-only in every function (required ones stay positional), so an
  argument can never land in the wrong slot when a parameter is added.
- The ensemble's path (lane-batched or scalar) and grouping are the core's choice: the results do
  not depend on the thread count, bit for bit, nor on how many calls run at once.
"""

from __future__ import annotations

import concurrent.futures
import inspect
import multiprocessing
import os
import sys
import threading

import numpy as np
import pytest

from tribosweep import _core


def test_the_exception_hierarchy():
    assert issubclass(_core.TribosweepError, Exception)
    assert not issubclass(_core.TribosweepError, ValueError)
    assert issubclass(_core.InvalidArgumentError, _core.TribosweepError)
    assert issubclass(_core.InvalidArgumentError, ValueError)
    assert _core.InvalidArgumentError.__module__ == "tribosweep._core"


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: _core.validate_params({"mu": -1.0}, "bilateral", "constant"), r"mu = -1\.0 is out of range: must be"),
        (lambda: _core.validate_params({"spam": 1.0}, "bilateral", "constant"), r'unknown parameter "spam"; valid names: mass, '),
        (lambda: _core.validate_params({}, "sticky", "constant"), r"contact = \"sticky\" is not valid: must be 'bilateral' or"),
        (
            lambda: _core.linear_stability({}, "bilateral", "constant", ["mu"], np.array([[0.2], [-0.5]])),
            r"trajectory 1: mu = -0\.5 is out of range",
        ),
        (
            lambda: _core.ensemble({}, "bilateral", "constant", [], np.zeros((1, 0)), np.zeros((1, 6)), 0.1, "dopri5",
                                   1e-6, kind="chaotic"),
            r"kind = \"chaotic\" is not valid: must be 'final', 'sampled' or 'steady'",
        ),
        (
            lambda: _core.ensemble({}, "bilateral", "constant", [], np.zeros((1, 0)), np.zeros((1, 6)), 0.1, "euler",
                                   1e-6),
            r"method = \"euler\" is not valid: must be one of dopri5, dop853, rodas4",
        ),
        (
            lambda: _core.ensemble({}, "unilateral", "constant", [], np.zeros((1, 0)), np.zeros((1, 6)), 0.1, "dop853",
                                   1e-6, kind="steady", irregular_block=256, known_irregular=np.zeros((1, 2, 7))),
            r"known_irregular must be an \(1, 2, 7\) array whose rows are all NaN \(no fingerprint\) or finite values "
            r">= 0 with a residual > 0; got shape \[1, 2, 7\]",
        ),
        (
            lambda: _core.ensemble({}, "unilateral", "constant", [], np.zeros((2, 0)), np.zeros((2, 6)), 0.1, "dop853",
                                   1e-6, kind="steady", known_irregular=np.full((1, 2, 7), np.nan)),
            r"known_irregular must be an \(2, 2, 7\) array .* got shape \[1, 2, 7\]",
        ),
        (
            # Cells whose extent is backwards (lower corner above the upper one).
            lambda: _core.ensemble({}, "unilateral", "constant", [], np.zeros((1, 0)), np.zeros((1, 6)), 0.1, "dop853",
                                   1e-6, kind="steady", irregular_block=256, known_irregular=np.full((1, 2, 7), np.nan),
                                   known_cells=np.ones((1, 2, 216), dtype=np.uint64),
                                   known_cell_extent=np.tile([1.0, 1.0, 1.0, 0.0, 0.0, 0.0], (1, 2, 1))),
            r"known_cells must be an \(1, 2, 216\) uint64 array and known_cell_extent an \(1, 2, 6\) array whose "
            r"rows are all NaN \(with zero cells: none\) or finite lower corners below the upper ones; got shapes "
            r"\[1, 2, 216\] and \[1, 2, 6\]",
        ),
        (
            lambda: _core.ensemble({}, "unilateral", "constant", [], np.zeros((1, 0)), np.zeros((1, 6)), 0.1, "dop853",
                                   1e-6, kind="steady", irregular_block=256, known_irregular=np.full((1, 2, 7), np.nan),
                                   known_cells=np.zeros((1, 2, 216), dtype=np.uint64)),
            r"known_cells and known_cell_extent go together, and with known_irregular",
        ),
        (
            # A restart with no time left (t_max must be > 0), and one of the wrong shape.
            lambda: _core.ensemble({}, "unilateral", "constant", [], np.zeros((1, 0)), np.zeros((1, 6)), 0.1, "dop853",
                                   1e-6, kind="steady", restart=np.array([[0.0, 0.0]])),
            r"restart must be an \(1, 2\) array of rows \(t_max > 0, hold >= 0\), finite, one per trajectory; got "
            r"shape \[1, 2\]",
        ),
        (
            lambda: _core.ensemble({}, "unilateral", "constant", [], np.zeros((2, 0)), np.zeros((2, 6)), 0.1, "dop853",
                                   1e-6, kind="steady", restart=np.array([[1.0, 0.0]])),
            r"restart must be an \(2, 2\) array .* got shape \[1, 2\]",
        ),
    ],
)
def test_bad_input_raises_invalid_argument_naming_it(call, message):
    with pytest.raises(_core.InvalidArgumentError, match=message) as e:
        call()
    assert isinstance(e.value, ValueError) and isinstance(e.value, _core.TribosweepError)


def _functions():
    return [f for name in _core.__all__ if callable(f := getattr(_core, name)) and not isinstance(f, type)]


def test_optional_parameters_are_keyword_only():
    checked = 0
    for f in _functions():
        for p in inspect.signature(f).parameters.values():
            if p.default is not inspect.Parameter.empty:
                assert p.kind is inspect.Parameter.KEYWORD_ONLY, f"{f.__name__}({p.name}=...) is not keyword-only"
                checked += 1
            else:
                assert p.kind is inspect.Parameter.POSITIONAL_OR_KEYWORD, f"{f.__name__}({p.name})"
    # simulate 4, ensemble 10, linear_stability 1, describing_function 5, periodic_orbit 7,
    # periodic_orbits 8, tidf_solve 2: the signatures really were read.
    assert checked >= 37
    values = np.array([[0.2]])
    with pytest.raises(TypeError):
        _core.linear_stability({}, "bilateral", "constant", ["mu"], values, 1)
    assert _core.linear_stability({}, "bilateral", "constant", ["mu"], values, threads=1)["status"][0] == 0


def test_ensemble_results_do_not_depend_on_the_thread_count():
    # 40 seed trajectories (mu across the Hopf point) on each of the core's paths: the bilateral
    # end state (batch), samples (lanes), steady states (lanes) and Rodas4 (scalar driver).
    mus = np.linspace(0.18, 0.26, 40)[:, None]
    y0 = np.array([[1e-6, 0, 0, 0, 0, 0]])
    te = np.linspace(0.0, 0.05, 11)
    cases = [
        dict(method="dopri5", kind="final"),
        dict(method="dop853", kind="sampled", t_eval=te),
        dict(method="dop853", kind="steady"),
        dict(method="rodas4", kind="final"),
    ]
    for case in cases:
        args = dict(case)
        method = args.pop("method")
        runs = [
            _core.ensemble({}, "bilateral", "constant", ["mu"], mus, y0, 0.05, method, 1e-7, threads=th, **args)
            for th in (1, 3)
        ]
        for key, value in runs[0].items():
            if isinstance(value, np.ndarray):
                assert np.array_equal(value, runs[1][key], equal_nan=True), (case, key)


def test_calls_from_more_python_threads_than_cores_give_the_serial_results():
    # Calls run on persistent workers, one per core; a call made while every worker is busy starts
    # a thread of its own. Four calls per core at once (each of 2 threads inside): every result is
    # the same call's made alone, bit for bit, on either kind of worker.
    n = 4 * (os.cpu_count() or 1)
    mus = np.linspace(0.18, 0.26, 12)[:, None]
    y0 = np.array([[1e-6, 0, 0, 0, 0, 0]])

    def call(k: int) -> dict:
        return _core.ensemble({}, "unilateral", "constant", ["mu"], mus + 1e-3 * k, y0, 0.02 + 1e-3 * k, "dop853",
                              1e-7, threads=2)  # fmt: skip

    alone = [call(k) for k in range(n)]
    start = threading.Barrier(n)

    def at_once(k: int) -> dict:
        start.wait()
        return call(k)

    with concurrent.futures.ThreadPoolExecutor(n) as ex:
        together = list(ex.map(at_once, range(n)))
    for a, b in zip(alone, together):
        for key, value in a.items():
            if isinstance(value, np.ndarray):
                assert np.array_equal(value, b[key], equal_nan=True), key
    assert all(int(np.sum(a["n_rhs"])) > 0 for a in alone)


def _fork_call(threads: int) -> tuple[int, bytes]:
    mus = np.linspace(0.18, 0.26, 12)[:, None]
    r = _core.ensemble({}, "unilateral", "constant", ["mu"], mus, np.array([[1e-6, 0, 0, 0, 0, 0]]), 0.02, "dop853",
                       1e-7, threads=threads)  # fmt: skip
    return int(np.sum(r["n_rhs"])), np.asarray(r["y_end"]).tobytes()


@pytest.mark.skipif(sys.platform != "linux", reason="fork is multiprocessing's default start method on Linux")
@pytest.mark.parametrize("threads", [1, 2])
def test_a_forked_child_computes_as_its_parent(threads):
    # A child made by fork inherits the parent's thread pools without their threads: its first call
    # waited forever (on 2 threads; on 1 too, once calls ran on persistent workers). Each process
    # now makes its own pools.
    expect = _fork_call(threads)  # the parent's pools exist before the fork
    with multiprocessing.get_context("fork").Pool(1) as pool:
        got = pool.apply_async(_fork_call, (threads,)).get(timeout=120)
    assert got == expect


def test_steady_runs_return_cells_only_where_a_run_left_any():
    # Cells come from runs that end stationary-irregular. Without stationarity blocks there are
    # none, and the cell array has no columns (not 216 words of zeros per trajectory); its extents
    # are NaN. (That cells reach the census's later samples is test_census.py's recurrence test:
    # stops before a block of 256 sections could match.)
    base = {"normal_load": 20.7692}
    n = 3
    y0 = np.tile([1e-6, 0, 0, 0, 0, 0.0], (n, 1))
    off = _core.ensemble(base, "unilateral", "constant", [], np.zeros((n, 0)), y0, 0.5, "dop853", 1e-6, kind="steady")
    assert off["irregular_cells"].shape == (n, 0) and off["irregular_cells"].dtype == np.uint64
    assert off["irregular_cell_extent"].shape == (n, 6) and np.isnan(off["irregular_cell_extent"]).all()
