"""The Lyapunov exponent's own settings, judged on replicates (issue 10).

The irregular points of the issue-10 Stribeck sweep (`contact="unilateral"`, `mu_static=0.3`,
200 points, ``benches/bench_stribeck.py``) carry a largest finite-time Lyapunov exponent
``irregular_ftle`` with its standard error from one run's segments. One run cannot tell two
settings of the exponent's runs (``ftle_rtol``, ``ftle_warmup``, ...) apart: the segments'
standard error matches the spread over starts at the median point but underestimates it several
times on intermittent motion, and a changed tolerance moves the base trajectory, so two single
runs differ by more than their errors say without either being wrong.

So each irregular point is measured ``replicates`` times (by :func:`tribosweep._irregular.measure`,
window and exponent), from the transient's end and from states 1, 2, ... s further along its
attractor (runs at rtol 1e-8), under each setting. A point's exponent is then the replicates'
mean with their standard error, and a setting is compared with the reference (``ftle_rtol``
1e-11, ``ftle_warmup`` 4: the defaults until 2026-11-29) in units of the combined standard
errors, ``z``. Under no difference ``z`` is about t-distributed with ``2 (replicates - 1)``
degrees of freedom: its median absolute value about 0.7 and its largest of 31 points about 2-3
(the reference's two halves of replicates against each other show the floor). A bias shows as a
mean ``z`` off 0 by more than ``2 / sqrt(points)``.

    python benches/bench_stribeck.py --ftle [--law switch] [--threads 2]
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .. import _core, _irregular
from .._settings import DEFAULTS

#: The settings compared (``Irregular`` fields over the defaults), the reference among them.
SETTINGS: dict[str, dict] = {
    "default": {},
    "ftle_rtol 1e-9, warmup 4 (2026-11-29 morning)": dict(ftle_rtol=1e-9, ftle_warmup=4),
    "ftle_rtol 1e-8": dict(ftle_rtol=1e-8),
    "ftle_rtol 1e-6": dict(ftle_rtol=1e-6),
    "reference: ftle_rtol 1e-11, warmup 4": dict(ftle_rtol=1e-11, ftle_warmup=4),
}
REFERENCE = "reference: ftle_rtol 1e-11, warmup 4"


def replicate_z(f_ref: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Per point (columns), the difference of the replicates' means (rows) of ``f`` and ``f_ref``
    in units of their combined standard errors."""
    r, q = f_ref.shape[0], f.shape[0]
    se = np.hypot(f_ref.std(axis=0, ddof=1) / math.sqrt(r), f.std(axis=0, ddof=1) / math.sqrt(q))
    return (f.mean(axis=0) - f_ref.mean(axis=0)) / se


def _irregular_points(law: str, threads: int, axes: dict | None = None):
    """The sweep's call of :func:`tribosweep._irregular.measure` (its arguments; the sweep in one
    chunk, so that one call measures every irregular point)."""
    from .._model import SliderModel
    from .._sweep import sweep
    from .sweep_settings import AXES

    axes = AXES if axes is None else axes
    got = {}
    measure = _irregular.measure

    def record(*a, **k):
        got["args"] = a
        return measure(*a, **k)

    _irregular.measure = record
    try:
        model = SliderModel(contact="unilateral", friction_law=law, mu_static=0.3)
        n = int(np.prod([np.size(v) for v in axes.values()]))
        sweep(model=model, census=False, t_max=20.0, threads=threads, progress=False, chunk_size=n, **axes)
    finally:
        _irregular.measure = measure
    return got["args"]


def ftle_settings(*, threads: int = 2, replicates: int = 8, law: str = "switch", axes: dict | None = None,
                  settings: dict | None = None) -> dict:  # fmt: skip
    """Measure every setting of ``settings`` (default :data:`SETTINGS`, which must hold
    :data:`REFERENCE`) on ``replicates`` starts per irregular point of the sweep over ``axes``
    (default the issue-10 Stribeck sweep's).

    Returns ``numbers`` (per setting: ``rhs`` per measurement of all points, ``median_z``,
    ``max_z``, ``mean_z``), ``floor`` (the reference's halves against each other) and ``markdown``.
    """
    settings = SETTINGS if settings is None else settings
    base, contact, friction_law, pp, sel, y0 = _irregular_points(law, threads, axes)
    names = sorted(pp)
    values = np.column_stack([np.asarray(pp[k], dtype=np.float64)[sel] for k in names])
    starts = [np.asarray(y0, dtype=np.float64)]
    for k in range(1, replicates):
        r = _core.ensemble({n: float(v) for n, v in base.items()}, contact, friction_law, names, values,
                           np.ascontiguousarray(y0), float(k), "dop853", 1e-8, threads=threads, kind="final")  # fmt: skip
        starts.append(np.asarray(r["y_end"]))
    runs = {}
    for name, kw in settings.items():
        st = dataclasses.replace(DEFAULTS.irregular, **kw)
        outs = [_irregular.measure(base, contact, friction_law, pp, sel, y, settings=st, threads=threads) for y in starts]
        runs[name] = (np.array([o["irregular_ftle"] for o in outs]), float(np.mean([o["n_rhs"].sum() for o in outs])))
    ref = runs[REFERENCE][0]
    ok = np.all(np.isfinite(ref), axis=0) & np.all([np.all(np.isfinite(f), axis=0) for f, _ in runs.values()], axis=0)
    numbers = {}
    for name, (f, rhs) in runs.items():
        z = replicate_z(ref[:, ok], f[:, ok])
        numbers[name] = {"rhs": rhs, "median_z": float(np.median(np.abs(z))), "max_z": float(np.abs(z).max()),
                         "mean_z": float(z.mean())}  # fmt: skip
    h = replicates // 2
    zf = replicate_z(ref[:h, ok], ref[h:, ok])
    floor = {"median_z": float(np.median(np.abs(zf))), "max_z": float(np.abs(zf).max())}
    lines = [
        f"The {int(ok.sum())} irregular points of the sweep ({law} law), each measured from "
        f"{replicates} starts along its attractor; each setting's exponents against the reference's "
        f"({REFERENCE}) in units of the replicates' combined standard errors. The reference's two halves "
        f"against each other: median |z| {floor['median_z']:.2f}, largest {floor['max_z']:.2f}. A mean z off 0 by "
        f"more than {2 / math.sqrt(max(ok.sum(), 1)):.2f} is a bias.",
        "",
        "| setting | rhs per measurement | median abs z | largest abs z | mean z |",
        "|---|---|---|---|---|",
    ]
    for name, v in numbers.items():
        if name != REFERENCE:
            lines.append(f"| {name} | {v['rhs'] / 1e6:.2f} M | {v['median_z']:.2f} | {v['max_z']:.2f} | {v['mean_z']:+.2f} |")
    lines.append(f"| {REFERENCE} | {numbers[REFERENCE]['rhs'] / 1e6:.2f} M | | | |")
    return {"numbers": numbers, "floor": floor, "markdown": "\n".join(lines)}
