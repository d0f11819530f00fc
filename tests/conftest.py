"""Shared fixtures: the seed reference values of ../shared/reference/seed_values.json; the pixel size of a
PNG file and the Figures behind the images a function saves (to check a chart's content, not its bytes);
which of the seed census's first samples keep their fate under inputs moved by a few ulps; a start on a
slow approach to a stable cycle, for the sweep's transients too."""

from __future__ import annotations

import json
import os
import pathlib
import struct

import numpy as np
import pytest

# The default thread count (threads=None) is pinned for the whole suite, before the core reads it:
# from 8 threads on, a sweep computes several chunks at once (tribosweep._sweep.runner.overlap),
# and tests that stop a sweep after its n-th chunk, or crash it inside one, count chunks finished
# in order. Their verdicts must not depend on the cores of the machine they run on. Tests of the
# overlap itself ask for 8 threads explicitly.
os.environ["TRIBOSWEEP_THREADS"] = "2"

ROOT = pathlib.Path(__file__).resolve().parents[1]
_CANDIDATES = [ROOT / "tests" / "data" / "seed_values.json", ROOT.parent / "shared" / "reference" / "seed_values.json"]


#: Moves of the inputs under which a single-trajectory verdict must hold (tests/test_robustness.py).
ULPS = (1, -1, 2, -2)
RTOL_FACTORS = (1.01, 0.99)


def moved(x, k: int) -> np.ndarray:
    """``x`` moved by ``k`` ulps (every component, towards +inf for k > 0)."""
    x = np.asarray(x, dtype=np.float64)
    for _ in range(abs(k)):
        x = np.nextafter(x, np.inf if k > 0 else -np.inf)
    return x


#: The switch-law Stribeck point at 10 N, 10.1 cm, 0.2 m/s (benches/bench_stribeck.py): a stable
#: period-2 contact-loss cycle whose slowest multiplier is 0.9933 (x's light damping).
SLOW_POINT = dict(normal_load=[10.0], arm_length=[0.10133333333333333], sliding_speed=[0.2])


def slow_law():
    import tribosweep as ts

    return ts.SliderModel(contact="unilateral", friction_law="switch", mu_static=0.3, sliding_speed=0.2)


def slow_approach_start():
    """The slow point's model, a start on its cycle's section with x moved by 0.3 of its amplitude (no
    chaotic phase: only the slow approach, which repeats to periodic_tol at 15.4 s, the same under
    inputs moved by ulps and rtol by 1 %), and a run from the default start to 60 s (periodic)."""
    import tribosweep as ts

    m = ts.apparatus_model(10.0, SLOW_POINT["arm_length"][0], 0.2, base=slow_law())
    done = ts.ensemble(m, 60.0, {"normal_load": [10.0]}, steady=True)
    y0 = np.array([float(done[f"{v}_end"][0]) for v in ("z", "z_dot", "x", "x_dot", "phi", "phi_dot")])
    y0[2] += 0.3 * float(done.x1_amplitude[0])
    return m, y0, done


@pytest.fixture
def slow_transients(monkeypatch):
    """The sweep's transients at unstable points start at :func:`slow_approach_start`'s state instead
    of on the unstable mode, whose chaotic prelude decides, with the last bits, how long the slow point
    takes to settle and even on which of its coexisting cycles (contact loss, or stick-slip at rtol
    +1 %). Returns that function's result."""
    from tribosweep._sweep import stages

    m, y0, done = slow_approach_start()
    monkeypatch.setattr(stages, "mode_start", lambda full, law, sel, z_amp, eig: np.tile(y0, (np.size(sel), 1)))
    return m, y0, done


#: The seed census's first samples whose fates ``seed_census_fates`` checks.
SEED_FATES = 32


@pytest.fixture(scope="session")
def seed_census_fates():
    """The attractor each of the seed census's first ``SEED_FATES`` samples reaches, and whether that fate is robust.

    A sample's fate is robust when it is the same with its start moved by +-1 and +-2 ulps, with
    rtol 1e-8 moved by +-1 %, and at rtol 1e-7 and 1e-9 (the census's own is 1e-6). Some starts
    are not: their bouncing transient is chaotic, two runs apart by rounding separate at about
    75 1/s, and their fate is a coin toss that another CPU's libm decides differently. Tests that compare fates one by one compare the robust ones only.
    """
    import tribosweep as ts
    from tribosweep import _census

    m, k = ts.SliderModel(contact="unilateral"), SEED_FATES
    ref = ts.census(m, samples=k).attractor_reached.values
    robust = np.ones(k, dtype=bool)
    orig = _census.starts
    try:
        for u in ULPS:
            _census.starts = lambda *a, u=u, **kw: moved(orig(*a, **kw), u)
            robust &= ts.census(m, samples=k).attractor_reached.values == ref
    finally:
        _census.starts = orig
    for f in RTOL_FACTORS:
        robust &= ts.census(m, samples=k, rtol=1e-8 * f).attractor_reached.values == ref
    # And at each decade between the census's rtol (1e-6) and 1e-9: a start whose bouncing transient
    # is captured by the cycle at some tolerances and decays at others is a coin toss too (one was
    # "sliding" at 1e-6, 1e-8 and 1e-10 and "cycle" at 1e-7 and 1e-9, with the model's inputs moved
    # by 2 ulps), which ulp moves alone need not reveal.
    for r in (1e-7, 1e-9):
        robust &= ts.census(m, samples=k, rtol=r).attractor_reached.values == ref
    return ref, robust


@pytest.fixture
def eight_pilots(monkeypatch):
    """The census with 8 pilots instead of 2 (``PHASE_STARTS = (0, 8)``), for tests that need an
    irregular pilot. Whether one pilot ends irregular is the fate of one chaotic transient, a coin
    toss with the irregular fraction's odds (about 0.64 at 20.8 N, 11 cm): with 2 pilots none did
    in 3 of 4 runs with the model's inputs moved by 1 or 2 ulps (which also moves every sample,
    their Halton shift being a hash of the inputs). With 8, none does with odds of 0.36^8 = 3e-4."""
    from tribosweep import _census

    monkeypatch.setattr(_census, "PHASE_STARTS", (0, 8))
    monkeypatch.setattr(_census, "PILOTS", 8)
    return 8


@pytest.fixture(scope="session")
def seed_values() -> dict:
    """Reference values of docs/model.md, computed independently (scipy, tight tolerances)."""
    for p in _CANDIDATES:
        if p.exists():
            return json.loads(p.read_text())
    raise FileNotFoundError(f"seed_values.json not found in {_CANDIDATES}")


def _png_size(path) -> tuple[int, int]:
    """(width, height) in pixels from a PNG file's IHDR chunk; fails if the file is not a PNG."""
    head = pathlib.Path(path).read_bytes()[:24]
    assert head[:8] == b"\x89PNG\r\n\x1a\n" and head[12:16] == b"IHDR", f"{path} is not a PNG file"
    return struct.unpack(">II", head[16:24])


@pytest.fixture
def png_size():
    """The function ``png_size(path) -> (width, height)``."""
    return _png_size


@pytest.fixture
def saved_figures(monkeypatch) -> dict:
    """Every matplotlib Figure saved during the test, by the saved file's name (the Figure itself, to read
    its artists' data)."""
    from matplotlib.figure import Figure

    real = Figure.savefig
    figures = {}

    def savefig(self, fname, *args, **kwargs):
        figures[pathlib.Path(fname).name] = self
        return real(self, fname, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", savefig)
    return figures


def _check_status_chart(ax, ds, var, names):
    """A status map's axes: one red label per failing cell, at the cell's centre, with its code's short name;
    the axis labels are the coordinates' long names, with units where they have one."""
    from tribosweep.bench import status_map as _failure
    from tribosweep.plot import _edges

    x, y = ds[var].dims[1], ds[var].dims[0]
    edges = {d: _edges(ds[d].values, _failure._is_log(ds[d].values)) for d in (x, y)}
    centre = {d: np.sqrt(e[1:] * e[:-1]) if _failure._is_log(ds[d].values) else 0.5 * (e[1:] + e[:-1])
              for d, e in edges.items()}  # fmt: skip

    def cell(item):  # sort by the cell a position falls in: mid-cell, so rounding cannot move it
        return np.searchsorted(edges[x], item[0]), np.searchsorted(edges[y], item[1])

    labels = sorted(((*t.get_position(), t.get_text()) for t in ax.texts if t.get_bbox_patch() is not None), key=cell)
    want = sorted(((centre[x][j], centre[y][i], _failure.STATUS_SHORT.get(names[c], names[c][:2].upper()))
                   for (i, j), c in np.ndenumerate(ds[var].values) if names[c] != names[0]), key=cell)  # fmt: skip
    assert [t for *_, t in labels] == [t for *_, t in want]
    np.testing.assert_allclose([xy for *xy, _ in labels], [xy for *xy, _ in want], rtol=1e-12)
    for dim, label in ((x, ax.get_xlabel()), (y, ax.get_ylabel())):
        units = ds[dim].attrs["units"]
        assert label == ds[dim].attrs["long_name"] + (f" [{units}]" if units != "1" else "")


@pytest.fixture
def check_status_chart():
    """The function ``check_status_chart(ax, ds, var, names)`` (see ``_check_status_chart``)."""
    return _check_status_chart
