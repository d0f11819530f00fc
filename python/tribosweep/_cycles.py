"""Cycles that runs to steady state stopped on, checked and converged by shooting.

A run to steady state stops on a cycle once its section state has repeated to ``periodic_tol``.
Near a slowly attracting cycle (a multiplier near 1) it is then still about
``periodic_tol / (1 - |mu|)`` away from it: on the Stribeck sweep of benches/bench_stribeck.py the
transients' amplitudes were up to 0.7 % off the orbits. In a laminar phase of intermittent motion,
or started close to a saddle, it repeats near an unstable cycle, which is no steady state. Shooting
from the stop (Floquet multipliers, saltation at every switch) tells. A sweep's transients
(``_sweep.stages.check_cycles``) and the census's cycles (``_census``) go through here.
"""

from __future__ import annotations

import numpy as np

from . import _core
from ._codes import OUTCOME_NAMES, STATUS

#: Newton iterations of a check. From a section state that repeated to ``periodic_tol`` shooting
#: converges in 2-4 (the Stribeck sweep: 53 of 63 cycles in 2, 9 in 3, 1 in 4); the one that had
#: not by 8 had not by 30 either.
CHECK_MAX_ITER: int = 8

#: Shooting from a stop must end on an orbit of the same period and first-harmonic amplitude of z
#: within these relative differences, or the cycle is not verified. On the Stribeck sweep the
#: converged orbits were within 7.1e-3 of the stops in A1 (a slow approach) and closer in period;
#: a tenfold margin, far below the gap to another orbit of the same multiplicity.
SAME_ORBIT_PERIOD: float = 1e-2
SAME_ORBIT_A1: float = 5e-2

#: Most checks of one run: each one after the first follows a stop near an unstable cycle (a
#: laminar phase of intermittent motion comes back every few seconds).
CHECK_ROUNDS: int = 8

#: Leaving an unstable cycle, a run declares no cycle until a deviation along the cycle's largest
#: multiplier ``|mu|`` has grown by this factor: ``ceil(ln(LEAVE_GROWTH) / ln|mu|)`` periods, from
#: 4 to :data:`LEAVE_PERIODS_MAX` (it may decay, escape or turn out irregular meanwhile). Without
#: it, the run would stop on the same cycle again a few periods later (it repeats as well as it
#: did when the run first stopped).
LEAVE_GROWTH: float = 1e3
LEAVE_PERIODS_MAX: int = 1000

#: Cycle quantities of a steady-state summary that a run measured on the converged orbit replaces.
CYCLE_KEYS: tuple[str, ...] = (
    "omega", "period", "multiplicity", "z0", "z1_amplitude", "z1_phase", "z2_amplitude", "z2_phase", "z3_amplitude",
    "z3_phase", "phi1_amplitude", "phi1_phase", "x1_amplitude", "x1_phase", "min_normal_force", "fraction_off_disk",
    "min_slip_velocity", "max_gap", "max_abs_z",
)  # fmt: skip

PERIODIC: int = OUTCOME_NAMES.index("periodic")
UNSETTLED: int = OUTCOME_NAMES.index("unsettled")


def rows(summary: dict) -> dict:
    """A steady-state summary as numpy arrays (copies), one row per run."""
    return {k: np.array(v, dtype=object if k == "reason" else None) for k, v in summary.items()}


def check_rtol(rtol: float, shooting_rtol: float) -> float:
    """The checks' integration tolerance: ten times tighter than the runs' own (1e-9 by default), so
    the orbit is as accurate as the runs and its multipliers have digits to spare; never tighter
    than ``shooting_rtol`` (1e-10, for the describing function's roots)."""
    return max(0.1 * float(rtol), float(shooting_rtol))


def shoot(base, contact: str, friction_law: str, names, values: np.ndarray, y_end: np.ndarray, period: np.ndarray,
          z1: np.ndarray, *, rtol: float, tol: float, threads: int | None) -> dict:  # fmt: skip
    """Shooting from the stops ``(y_end, period)`` whose first-harmonic amplitude of z was ``z1``.

    Returns the core's orbits with ``stable`` and ``unstable`` (converged, on the same orbit:
    :data:`SAME_ORBIT_PERIOD`, :data:`SAME_ORBIT_A1`) and ``note``: why a check verified nothing
    (empty where it converged on the same orbit).
    """
    orbs = _core.periodic_orbits(
        base, contact, friction_law, names, np.ascontiguousarray(values), y0=np.ascontiguousarray(y_end),
        periods=np.ascontiguousarray(period), rtol=rtol, tol=tol, max_iter=CHECK_MAX_ITER, threads=threads,
    )  # fmt: skip
    out = {k: np.asarray(v) for k, v in orbs.items()}
    ok = out["status"] == STATUS["success"]
    with np.errstate(divide="ignore", invalid="ignore"):
        same = (np.abs(out["period"] / period - 1) <= SAME_ORBIT_PERIOD) & (np.abs(out["A1"] / z1 - 1) <= SAME_ORBIT_A1)
    note = np.full(len(ok), "", dtype=object)
    for j in np.flatnonzero(~ok):
        note[j] = f"shooting from it failed ({out['reason'][j]})"
    for j in np.flatnonzero(ok & ~same):
        note[j] = (f"shooting from it converged to another orbit (period {float(out['period'][j]):.6g} s against "
                   f"{float(period[j]):.6g} s, A1 {float(out['A1'][j]):.4g} m against {float(z1[j]):.4g} m)")  # fmt: skip
    ok &= same
    out["stable"] = ok & out["stable"].astype(bool)
    out["unstable"] = ok & ~out["stable"]
    out["note"] = note
    return out


def leave(t_end: np.ndarray, t_max: float, moduli: np.ndarray, period: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The restarts of runs that stopped at ``t_end`` near unstable cycles: per run ``(time left, hold)``.

    The hold lasts until a deviation along the cycle's largest multiplier has grown
    :data:`LEAVE_GROWTH`-fold (from 4 to :data:`LEAVE_PERIODS_MAX` periods).
    """
    mu = np.max(moduli, axis=1) if len(moduli) else np.zeros(0)
    with np.errstate(divide="ignore", invalid="ignore"):
        grow = np.where(mu > 1, np.ceil(np.log(LEAVE_GROWTH) / np.log(mu)), LEAVE_PERIODS_MAX)
    return t_max - np.asarray(t_end, dtype=np.float64), np.clip(grow, 4, LEAVE_PERIODS_MAX) * period


def merge(s: dict, idx: np.ndarray, r: dict, t0: np.ndarray, skip: tuple[str, ...] = ("reason",)) -> None:
    """Rows ``idx`` of summary ``s`` become the restarted runs ``r`` (in ``idx`` order), which began at ``t0``:
    ``t_end`` from the first run's start, ``n_rhs`` over both. Keys whose rows differ in shape
    (the cells, padded per call) are left."""
    n_rhs = s["n_rhs"][idx] + r["n_rhs"]
    for key, v in r.items():
        if key in s and key not in skip and np.shape(s[key])[1:] == np.shape(v)[1:]:
            s[key][idx] = v
    s["n_rhs"][idx] = n_rhs
    s["t_end"][idx] = t0 + r["t_end"]
