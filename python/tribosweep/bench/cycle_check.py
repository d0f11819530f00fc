"""What a run's periodic stop is worth, and what checking it by shooting costs.

A run to steady state stops on a cycle once its section state repeats to ``periodic_tol``. On a
cycle whose slowest non-trivial Floquet multiplier has modulus ``|mu|``, the remaining distance
decays by ``|mu|`` a period while consecutive sections differ by ``(1 - |mu|)`` of it: the stop is
about ``periodic_tol / (1 - |mu|)`` from the cycle. A sweep therefore shoots from every stop and
measures the converged orbit (:mod:`tribosweep._cycles`). This module runs the issue-10 Stribeck
sweep (both friction laws, 200 points each) and, for every cycle shooting verified, compares the
stop's ``z1_amplitude`` with the orbit's against that prediction; it times the sweep with the
check and without it (every stop taken as it was) in the same process.
"""

from __future__ import annotations

import os
import pathlib
import time

import numpy as np

from .. import _cycles
from .._cycles import slowest_multiplier
from .._settings import DEFAULTS
from .._sweep import stages
from .._sweep import sweep as _sweep
from .sweep_settings import AXES

#: The laws compared (the Stribeck sweep's two).
LAWS = ("switch", "coulomb")
#: A cycle whose A1 is below this fraction of its largest harmonic of z is left out of the
#: comparison: its A1, a small part of its motion, carries the Fourier quadrature's own error.
SMALL_A1 = 0.1


def stops(law: str, threads: int = 2, **axes) -> dict:
    """The Stribeck sweep of ``law`` (``axes`` override its grid), recording every check: per verified
    cycle the stop's and the orbit's ``A1``, the stop's largest harmonic of z and the slowest multiplier."""
    from .._model import SliderModel

    rec: list[tuple[np.ndarray, np.ndarray, dict]] = []
    real = _cycles.shoot

    def recording(*args, **kwargs):
        out = real(*args, **kwargs)
        rec.append((np.asarray(args[7]), np.asarray(args[8]), out))
        return out

    _cycles.shoot = recording
    try:
        model = SliderModel(contact="unilateral", friction_law=law, mu_static=0.3)
        # The stops at periodic_tol (a slow approach checked in the run ends on its orbit instead).
        ds = _sweep(model=model, census=False, t_max=20.0, threads=threads, progress=False, approach_periods=0,
                    **(axes or AXES))  # fmt: skip
    finally:
        _cycles.shoot = real
    z1, a1, size, mu = [], [], [], []
    for stop_a1, stop_size, orbs in rec:
        ok = orbs["stable"]
        z1.append(stop_a1[ok])
        size.append(stop_size[ok])
        a1.append(orbs["A1"][ok])
        mu.append(slowest_multiplier(orbs["moduli"][ok]) if ok.any() else np.zeros(0))
    cat = (lambda v: np.concatenate(v) if v else np.zeros(0))  # noqa: E731
    return {"law": law, "stop_a1": cat(z1), "orbit_a1": cat(a1), "stop_z_size": cat(size), "mu": cat(mu),
            "verified": int((ds.cycle_verified.values == 1).sum()), "not_verified": int((ds.cycle_verified.values == 0)
            .sum()), "points": int(ds.regime.size)}  # fmt: skip


def timed(law: str, threads: int, repeat: int, check: bool) -> float:
    """Best wall time of the Stribeck sweep of ``law``, with the cycle check or with every stop taken as it was."""
    from .._model import SliderModel

    model = SliderModel(contact="unilateral", friction_law=law, mu_static=0.3)
    real = stages.check_cycles
    if not check:
        stages.check_cycles = lambda p, sel, s: (_cycles.rows(s), np.ones(len(sel), dtype=bool))
    try:
        walls = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            _sweep(model=model, census=False, t_max=20.0, threads=threads, progress=False, approach_periods=0, **AXES)
            walls.append(time.perf_counter() - t0)
    finally:
        stages.check_cycles = real
    return min(walls)


def cycle_check(out_dir: os.PathLike, *, quick: bool = False, threads: int = 2) -> dict:
    """Measure, draw ``cycle_check.png`` into ``out_dir``; return ``numbers``, ``markdown``, ``files``."""
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    repeat = 1 if quick else 3
    numbers: dict = {"periodic_tol": DEFAULTS.steady.periodic_tol, "threads": threads, "laws": []}
    for law in LAWS:
        d = stops(law, threads)
        d["wall_checked"] = timed(law, threads, repeat, True)
        d["wall_unchecked"] = timed(law, threads, repeat, False)
        numbers["laws"].append(d)
    png = out / "cycle_check.png"
    _chart(numbers).savefig(png, dpi=100)
    return {"numbers": numbers, "markdown": _markdown(numbers, png.name), "files": {"cycle_check": png}}


def summary(d: dict, periodic_tol: float) -> dict:
    """The stops' errors against the prediction ``periodic_tol / (1 - |mu|)``, for cycles whose A1 is not small."""
    err = np.abs(d["stop_a1"] / d["orbit_a1"] - 1)
    pred = periodic_tol / np.maximum(1 - d["mu"], 1e-12)
    big = d["stop_a1"] >= SMALL_A1 * d["stop_z_size"]
    ratio, err = err[big] / pred[big], err[big]
    return {"n": int(big.sum()), "small": int((~big).sum()), "err_max": float(err.max()) if err.size else np.nan,
            "err_median": float(np.median(err)) if err.size else np.nan,
            "within_3x": float(np.mean(ratio <= 3)) if ratio.size else np.nan,
            "ratio_median": float(np.median(ratio)) if ratio.size else np.nan}  # fmt: skip


def _chart(numbers: dict):
    from matplotlib.figure import Figure

    tol = numbers["periodic_tol"]
    fig = Figure(figsize=(10.5, 4.6), layout="constrained")
    ax, ax_t = fig.subplots(1, 2, width_ratios=(2, 1))
    colors = {"switch": "tab:blue", "coulomb": "tab:orange"}
    names = {"switch": "switch law", "coulomb": "tanh law (coulomb)"}
    for d in numbers["laws"][::-1]:  # the switch law's on top
        err = np.abs(d["stop_a1"] / d["orbit_a1"] - 1)
        gap = np.maximum(1 - d["mu"], 1e-12)
        big = d["stop_a1"] >= SMALL_A1 * d["stop_z_size"]
        ax.plot(gap[big], err[big], "o", ms=5, mfc="none" if d["law"] == "switch" else colors[d["law"]],
                color=colors[d["law"]], label=names[d["law"]])  # fmt: skip
        ax.plot(gap[~big], err[~big], "x", ms=5, color=colors[d["law"]],
                label=f"{names[d['law']]}, A1 < {SMALL_A1:g} of the motion (quadrature-limited)")  # fmt: skip
    g = np.logspace(-3.5, 0, 50)
    ax.plot(g, tol / g, "k--", lw=1, label=f"periodic_tol / (1 - |mu|), periodic_tol = {tol:g}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("1 - |mu|: gap of the slowest non-trivial Floquet multiplier to 1")
    ax.set_ylabel("stop's z1 amplitude: relative error against the orbit")
    ax.set_title("where a run stops on a cycle, against the converged orbit", fontsize=9)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, loc="upper left")
    laws = [d["law"] for d in numbers["laws"]]
    x = np.arange(len(laws))
    ax_t.bar(x - 0.2, [d["wall_unchecked"] for d in numbers["laws"]], 0.4, color="0.7", label="stops taken as they were")
    ax_t.bar(x + 0.2, [d["wall_checked"] for d in numbers["laws"]], 0.4, color="tab:green", label="every cycle checked")
    ax_t.set_xticks(x, [names[law] for law in laws])
    ax_t.set_ylabel(f"wall time of the sweep [s] ({numbers['threads']} threads)")
    ax_t.set_title("the cost of the check", fontsize=9)
    ax_t.legend(fontsize=7, loc="lower right")
    ax_t.grid(alpha=0.3, axis="y")
    fig.suptitle("The Stribeck sweep (200 points a law): cycle amplitudes where the transients stopped, and what "
                 "checking them by shooting costs", fontsize=10)  # fmt: skip
    return fig


def _markdown(numbers: dict, png: str) -> str:
    tol = numbers["periodic_tol"]
    lines = ["## Checking the cycles a run stops on", "", f"![cycle check]({png})", "",
             f"A run stops on a cycle once its section state repeats to periodic_tol = {tol:g}; the stop is then "
             "up to about periodic_tol / (1 - |mu|) from the cycle (|mu|: the slowest non-trivial Floquet "
             "multiplier). Errors are over the cycles whose A1 is at least a tenth of their largest harmonic of z. "
             f"The issue-10 Stribeck sweep ({numbers['threads']} threads), every verified cycle's stop against its "
             "converged orbit, and the sweep's wall time with the check and with every stop taken as it was:", "",
             "| law | cycles verified (not) | stop's A1 error, median / max | within 3x the bound | "
             "error / bound, median | wall, checked / unchecked |", "|---|---|---|---|---|---|"]  # fmt: skip
    for d in numbers["laws"]:
        s = summary(d, tol)
        lines.append(f"| {d['law']} | {d['verified']} ({d['not_verified']}) | {s['err_median']:.1e} / {s['err_max']:.1e} "
                     f"| {s['within_3x']:.0%} of {s['n']} ({s['small']} with a small A1 left out) | "
                     f"{s['ratio_median']:.2f} | {d['wall_checked']:.2f} / {d['wall_unchecked']:.2f} s |")  # fmt: skip
    lines.append("")
    return "\n".join(lines)
