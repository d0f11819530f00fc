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
#: converges in 2-4 near a stable cycle (the Stribeck sweep: 53 of 63 cycles in 2, 9 in 3, 1 in 4).
#: Near an unstable one whose multiplier is close to 1 it takes longer: on the 2,000-point
#: constant-friction grid's census 395 of 1,813 checks had not converged by 8 (the limit until
#: 2026-11-27); at 20, 340 of 1,819, and 249 checks find unstable orbits instead of 195 (largest
#: multipliers 1.0003-1.02, in 11-15 iterations), whose samples then go on instead of counting as
#: unverified cycles. The census's fractions move by at most 1.04 standard errors, and its time
#: does not move (35.0 s against 34.6).
CHECK_MAX_ITER: int = 20

#: Shooting from a stop must end on an orbit of the same period, relatively, and the same
#: first-harmonic amplitude of z in units of the stop's largest harmonic of z (a subharmonic
#: cycle's A1 can be a thousandth of its motion, and its relative change then means nothing), or
#: the cycle is not verified. On the Stribeck sweep the converged orbits were within 7.1e-3 of
#: the stops in A1 (a slow approach) and closer in period; a tenfold margin, far below the gap to
#: another orbit of the same multiplicity.
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
    "omega", "period", "multiplicity", "z0", "z_half_range", "z1_amplitude", "z1_phase", "z2_amplitude", "z2_phase",
    "z3_amplitude", "z3_phase", "phi1_amplitude", "phi1_phase", "x1_amplitude", "x1_phase", "min_normal_force",
    "fraction_off_disk", "min_slip_velocity", "max_gap", "max_abs_z",
)  # fmt: skip

#: A run that reached ``t_max`` without repeating to ``periodic_tol`` is shot from its newest
#: section state where that state repeated, after some ``p`` sections, to this relative residual
#: (the repetition test's measure): a slowly attracting cycle, its slow multiplier not yet worked
#: off (the Stribeck sweep's 10 N, 10.1 cm, 0.2 m/s point repeats to periodic_tol at 21.5 s,
#: and by t_max = 20 s to 2.5e-5). Shooting decides: a stable orbit of that period is the run's
#: steady state; an unstable one (a laminar phase) or none leaves the run as it was.
NEAREST_TOL: float = 1e-2

PERIODIC: int = OUTCOME_NAMES.index("periodic")
UNSETTLED: int = OUTCOME_NAMES.index("unsettled")


def rows(summary: dict) -> dict:
    """A steady-state summary as numpy arrays (copies), one row per run."""
    return {k: np.array(v, dtype=object if k == "reason" else None) for k, v in summary.items()}


def check_rtol(rtol: float, shooting_rtol: float) -> float:
    """The checks' integration tolerance: ten times tighter than the measurement tolerance ``rtol``
    (1e-9 by default), so the orbit is as accurate as a run at ``rtol`` and its multipliers have
    digits to spare; never tighter than ``shooting_rtol`` (1e-10, for the describing function's
    roots). It does not follow the tolerance of the transients that found the cycle (a sweep's
    ``transient_rtol``): they find, the check measures."""
    return max(0.1 * float(rtol), float(shooting_rtol))


def shoot(base, contact: str, friction_law: str, names, values: np.ndarray, y_end: np.ndarray, period: np.ndarray,
          z1: np.ndarray, z_size: np.ndarray, *, rtol: float, tol: float, threads: int | None) -> dict:  # fmt: skip
    """Shooting from the stops ``(y_end, period)`` whose first-harmonic amplitude of z was ``z1`` and
    largest harmonic of z ``z_size``.

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
        # A start without a stop's amplitude (NaN ``z1``: a slow approach's newest section) is
        # held to the period alone.
        same = (np.abs(out["period"] / period - 1) <= SAME_ORBIT_PERIOD) & (
            np.isnan(z1) | (np.abs(out["A1"] - z1) <= SAME_ORBIT_A1 * z_size))
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


def slowest_multiplier(moduli: np.ndarray) -> np.ndarray:
    """Per orbit, the largest modulus after dropping the one closest to 1 (the trivial multiplier)."""
    m = np.atleast_2d(np.asarray(moduli, dtype=np.float64))
    trivial = np.argmin(np.abs(m - 1.0), axis=1)
    keep = np.ones_like(m, dtype=bool)
    keep[np.arange(m.shape[0]), trivial] = False
    return np.where(keep, m, -np.inf).max(axis=1)


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


def check(summary: dict, shoot, steady, t_max: float, measure=None) -> tuple[dict, np.ndarray]:
    """The cycles that the runs of ``summary`` stopped on, checked and converged by shooting.

    ``shoot(idx, y_end, period, z1, z_size)``: :func:`shoot` for the runs ``idx``;
    ``steady(idx, y0, restart=None)``: runs to steady state of the runs ``idx`` from ``y0`` (the
    core's summary), each with its own ``(t_max, hold)`` under ``restart``; ``measure(idx, y0)``:
    the runs started on stable orbits that measure them (default ``steady``; a sweep measures at
    its checks' tolerance what its transients, at their own, only found).

    - **stable orbit**: a run started on it measures it (every cycle quantity of the summary,
      from the same Fourier integrals as the first run's, on the orbit itself);
    - **unstable orbit**: the run goes on from where it stopped, to a steady state within what is
      left of ``t_max``, declaring no cycle until a deviation along the largest multiplier has
      grown :data:`LEAVE_GROWTH`-fold; a cycle it stops on is checked again (at most
      :data:`CHECK_ROUNDS` checks; still stopping on one after that: ``unsettled``);
    - **no convergence, or another orbit**: the stop's cycle stays, not verified, and the reason
      says so.

    Returns the summary with those rows replaced (``t_end`` and ``n_rhs`` over all the runs of a
    row, shooting included), and per row whether its cycle was verified (a stable orbit that
    shooting converged and a run on it measured).
    """
    measure = steady if measure is None else measure
    s = rows(summary)
    n = len(s["outcome"])
    verified = np.zeros(n, dtype=bool)
    notes: list[list[str]] = [[] for _ in range(n)]
    periodic = s["outcome"] == PERIODIC
    # A run that stopped on a slow approach was checked inside the run (the core's `approach`):
    # it ended on a stable orbit, measured there.
    approach = periodic & np.asarray(s.get("approach", np.zeros(n, dtype=bool)), dtype=bool)
    verified[approach] = True
    todo = np.flatnonzero(periodic & ~approach)
    for _ in range(CHECK_ROUNDS):
        if not todo.size:
            break
        orbs = shoot(todo, s["y_end"][todo], s["period"][todo], s["z1_amplitude"][todo], z_size(s, todo))
        s["n_rhs"][todo] += orbs["n_rhs"].astype(s["n_rhs"].dtype)
        for j in np.flatnonzero(orbs["note"] != ""):
            notes[todo[j]].append(f"the cycle is the run's stop, not verified: {orbs['note'][j]}")
        good = todo[orbs["stable"]]
        if good.size:
            verified[good] = _measure(measure, s, good, orbs["state0"][orbs["stable"]])
        u = orbs["unstable"]
        todo = _leave(steady, s, todo[u], orbs["moduli"][u], orbs["period"][u], t_max, notes)
    for i in todo:  # still stopping near unstable cycles after CHECK_ROUNDS checks
        s["outcome"][i] = UNSETTLED
        s["status"][i] = STATUS["not_converged"]
        notes[i].append(f"it stopped near an unstable cycle {CHECK_ROUNDS} times")
    stuck = np.zeros(n, dtype=bool)
    stuck[todo] = True
    if "nearest_residual" in s:
        verified |= _slow_approach(shoot, measure, s, ~stuck, notes)
    for i, parts in enumerate(notes):
        if parts:
            s["reason"][i] = "; ".join(([s["reason"][i]] if s["reason"][i] else []) + parts)
    return s, verified


def slow_candidates(outcome: np.ndarray, status: np.ndarray, residual: np.ndarray) -> np.ndarray:
    """Runs that reached ``t_max`` unsettled with their newest section nearly repeating
    (:data:`NEAREST_TOL`): those shot from there as slow approaches."""
    return (outcome == UNSETTLED) & (status == STATUS["not_converged"]) & (residual <= NEAREST_TOL)


#: How the reason of a run that became its cycle as a slow approach begins (:func:`slow_note`).
SLOW_MARK: str = "a slow approach"


def slow_note(t: float, residual: float, mult: int, mu: float) -> str:
    """The reason of a run that became its cycle as a slow approach."""
    return (f"{SLOW_MARK}: no repetition to periodic_tol by t_max = {t:.3g} s (its newest section repeated to "
            f"{residual:.2g} after {int(mult)}); shooting from there converged on this stable cycle (largest "
            f"multiplier {mu:.4g})")  # fmt: skip


def _slow_approach(shoot, measure, s: dict, eligible: np.ndarray, notes: list[list[str]]) -> np.ndarray:
    """Runs of ``s`` that reached ``t_max`` unsettled, shot from their newest section state where it
    nearly repeated (:func:`slow_candidates`); a stable orbit of that period is measured and becomes
    the run's outcome. Returns per row whether it did (verified)."""
    idx = np.flatnonzero(eligible & slow_candidates(s["outcome"], s["status"], s["nearest_residual"]))
    done = np.zeros(len(s["outcome"]), dtype=bool)
    if not idx.size:
        return done
    nan = np.full(idx.size, np.nan)
    orbs = shoot(idx, s["nearest_y"][idx], s["nearest_period"][idx], nan, nan)
    s["n_rhs"][idx] += orbs["n_rhs"].astype(s["n_rhs"].dtype)
    good = idx[orbs["stable"]]
    if not good.size:
        return done
    mu = slowest_multiplier(orbs["moduli"][orbs["stable"]])
    measured = _measure(measure, s, good, orbs["state0"][orbs["stable"]], stop_quantities=False)
    for i, m in zip(good[measured], mu[measured]):
        notes[i].append(slow_note(float(s["t_end"][i]), s["nearest_residual"][i], s["nearest_multiplicity"][i], m))
        s["outcome"][i], s["status"][i], s["reason"][i] = PERIODIC, STATUS["success"], ""
        done[i] = True
    return done


def _measure(measure, s: dict, idx: np.ndarray, state0: np.ndarray, stop_quantities: bool = True) -> np.ndarray:
    """The cycle quantities of ``s`` at rows ``idx``, measured by runs started on their converged orbits.

    Such a run stops once its section state repeats, two periods in. Its limit is the runs'
    ``t_max``, the same for every run: a limit taken from the periods of the call's other runs
    would make a row's result depend on what shares its call (a sweep point's, on its chunk).

    Returns which runs repeated (the others keep the first run's quantities, with a reason; with
    ``stop_quantities=False`` there are none: they are left as they were, without one).
    """
    m = rows(measure(idx, state0))
    s["n_rhs"][idx] += m["n_rhs"]
    done = m["outcome"] == PERIODIC
    for key in CYCLE_KEYS:
        s[key][idx[done]] = m[key][done]
    if not stop_quantities:
        return done
    for i in idx[~done]:
        s["reason"][i] = "; ".join(filter(None, [s["reason"][i], "a run on the converged orbit did not repeat: the "
                                                 "cycle's quantities are the stop's"]))  # fmt: skip
    return done


def _leave(steady, s: dict, idx: np.ndarray, moduli: np.ndarray, period: np.ndarray, t_max: float,
           notes: list[list[str]]) -> np.ndarray:  # fmt: skip
    """Runs ``idx`` on from near the unstable cycles they stopped on, in one call (:func:`leave`);
    returns those that stop on a cycle again."""
    t0 = s["t_end"][idx].astype(np.float64)
    for i, t, m in zip(idx, t0, np.max(moduli, axis=1) if len(idx) else []):
        notes[i].append(f"at t = {t:.3g} s it stopped near an unstable cycle (largest multiplier {m:.3g}) and went on")
    left, hold = leave(t0, t_max, moduli, period)
    done = left <= 0
    s["outcome"][idx[done]] = UNSETTLED  # stopped at t_max: nothing left to go on with
    s["status"][idx[done]] = STATUS["not_converged"]
    go = idx[~done]
    if not go.size:
        return go
    r = rows(steady(go, s["y_end"][go], restart=np.column_stack([left[~done], hold[~done]])))
    merge(s, go, r, t0[~done])
    for j, i in enumerate(go):
        if r["reason"][j] and r["outcome"][j] != UNSETTLED:  # an unsettled run's names its own t_max
            notes[i].append(str(r["reason"][j]))
    return go[r["outcome"] == PERIODIC]


def cluster(omega, mult, amps, size, tol: float) -> tuple[np.ndarray, list[int]]:
    """Cluster periodic samples (in sample order, deterministic); label per sample, first member per cluster.

    Two samples are on the same cycle when they have the same multiplicity, their frequencies
    agree to ``tol`` and each of their first three harmonic amplitudes of z (``amps``, ``(n, 3)``)
    agrees to ``tol`` of the cluster head's motion (``size``: half z's range over the period;
    where NaN, the largest of those harmonics). In units of the motion, not of each harmonic: a
    subharmonic cycle's A1 can be a small part of its motion, and the stops near it (each
    ``periodic_tol / (1 - |mu|)`` off) then spread by more than ``tol`` of A1 itself (on the
    default grid's census a period-6 cycle at 138.6 N, 9.3 cm came out as three "cycles"). All
    three: two period-2 cycles at 52.9 N, 5.8 cm share A1 (1.41e-5 m) and their frequency to 0.2 %,
    and differ in A2 (4.1e-6 against 1.5e-5 m); by A1 alone they were one.
    """
    n = np.size(omega)
    amps = np.asarray(amps, dtype=np.float64).reshape(n, 3)
    size = np.asarray(size, dtype=np.float64).reshape(n)
    if not np.isfinite(size).all():
        size = np.where(np.isfinite(size), size, np.max(amps, axis=1, initial=0.0))
    # :func:`same_cycle`'s test on Python floats (the same float64 arithmetic and comparisons, so
    # the same labels): a census sweep clusters thousands of points of a few samples each, where
    # numpy's cost per call on 3-element arrays was most of the time (the 2,000-point census
    # grid's 3,168 clusterings: 241-279 ms -> 82-95 ms).
    om, am, sz = np.asarray(omega, dtype=np.float64).tolist(), amps.tolist(), size.tolist()
    mu = np.asarray(mult).tolist()
    label: list[int] = []
    heads: list[int] = []
    for s in range(n):
        for c, h in enumerate(heads):
            lim = tol * max(sz[h], 1e-12)
            if (mu[s] == mu[h] and abs(om[s] - om[h]) <= tol * om[h]
                    and all(abs(x - y) <= lim for x, y in zip(am[s], am[h]))):  # fmt: skip
                label.append(c)
                break
        else:
            label.append(len(heads))
            heads.append(s)
    return np.array(label, dtype=np.int64), heads


def same_cycle(omega, amps, ref_omega: float, ref_amps, size: float, tol: float):
    """Whether cycles (``omega``, harmonic amplitudes of z ``amps`` on a last axis) are the cycle
    ``(ref_omega, ref_amps)``: the frequency to ``tol`` and each harmonic to ``tol`` of ``size``,
    the reference cycle's motion (half z's range). :func:`cluster`'s test, less the multiplicity."""
    near = np.abs(np.asarray(amps) - np.asarray(ref_amps)) <= tol * max(size, 1e-12)
    return (np.abs(omega - ref_omega) <= tol * ref_omega) & np.all(near, axis=-1)


def harmonics(res: dict, idx) -> np.ndarray:
    """The amplitudes of harmonics 1-3 of z of the runs ``res[...][idx]``, stacked on a last axis (what :func:`cluster` compares)."""
    return np.stack([res[k][idx] for k in ("z1_amplitude", "z2_amplitude", "z3_amplitude")], axis=-1)


class CensusCheck:
    """The census's cycles (``tribosweep._census.run``), checked by shooting.

    Each distinct cycle of a point (the head of its cluster, :func:`cluster`) is shot from. A
    cycle that is an unstable orbit is no attractor: its samples stopped near it (close to a
    saddle, or in a laminar phase of intermittent motion) and go on, in one call, each with the
    time it has left and a hold on cycles; the cycles they then stop on are checked in turn. A
    stable orbit is kept (:meth:`measure` measures the largest cluster's on its orbit); one whose
    shooting failed or landed on another orbit stays, not verified. Samples that still stop on
    cycles after :data:`CHECK_ROUNDS` checks of cycles they left are not decided (``unsettled``).
    Samples unsettled at ``t_max`` on a slow approach join the stable cycle that shooting from
    their newest section finds (:meth:`_slow_approach`), instead of counting as irregular motion.
    """

    def __init__(self, res: dict, cycle_tol: float, steady, known, t_max: float, rtol: float, tol: float):
        self.res, self.cycle_tol, self.steady, self.known = res, cycle_tol, steady, known
        self.t_max, self.rtol, self.tol = t_max, rtol, tol
        self.orbit: dict[tuple[int, int], tuple[bool, np.ndarray | None]] = {}  # (point, sample) -> (stable, state0)

    def flat(self, key: str) -> np.ndarray:
        """``res[key]`` as one row per sample (a view: writes go to ``res``)."""
        v = self.res[key]
        # The row count spelled out: a cell array without columns (no stationarity blocks) has size 0.
        flat = v.reshape((v.shape[0] * v.shape[1],) + v.shape[2:])
        assert v.size == 0 or np.shares_memory(flat, v), key  # a copy would drop the writes
        return flat

    def resolve(self, shoot, flat: np.ndarray) -> None:
        """The first stops of the samples ``flat`` (flat indices), which repeated to the census's loose
        ``stop_tol``, each shot from, in one call, and held to the period alone (a stop that loose
        is up to ``stop_tol / (1 - |mu|)`` off its cycle: 10 % near a slow multiplier, more than
        :data:`SAME_ORBIT_A1`). A stable orbit is measured by a run started on it, in one call, and
        the sample is on it, verified. The others go on from their stops, in one call, stopping on
        cycles that repeat to ``periodic_tol`` from then on: those near an unstable orbit with the
        hold of :meth:`_leave`, those whose shooting failed or found an orbit of another period
        without one."""
        if not flat.size:
            return
        k = self.res["outcome"].shape[1]
        orbs, done = self._on_orbits(shoot, flat, self.flat("y_end")[flat], self.flat("period")[flat])
        rest = np.flatnonzero(~done)
        if not rest.size:
            return
        unstable = orbs["unstable"][rest]
        moduli = np.where(unstable[:, None], orbs["moduli"][rest], np.nan)
        period = np.where(unstable, orbs["period"][rest], self.flat("period")[flat[rest]])
        self._leave([(int(f // k), int(f % k), mu, p) for f, mu, p in zip(flat[rest], moduli, period)])

    def settle(self, shoot) -> None:
        """Checks the cycles (:meth:`_rounds`), then the samples left unsettled at ``t_max`` on a slow
        approach (:meth:`_slow_approach`)."""
        stuck = self._rounds(shoot)
        self._slow_approach(shoot, stuck)

    def _rounds(self, shoot) -> np.ndarray:
        """The rounds of checks; returns the flat indices of the samples still stopping near unstable
        cycles after the last (made ``unsettled``)."""
        res, m = self.res, self.res["outcome"].shape[0]
        went_on = np.zeros(0, dtype=np.int64)
        for _ in range(CHECK_ROUNDS):
            heads, members = [], []
            for i in range(m):
                per = np.flatnonzero(res["outcome"][i] == PERIODIC)
                label, hs = cluster_of(res, i, per, self.cycle_tol)
                for c, h in enumerate(hs):
                    if (i, per[h]) not in self.orbit:
                        heads.append((i, per[h]))
                        members.append(per[label == c])
            if not heads:
                return went_on[:0]
            pts = np.array([i for i, _ in heads])
            cols = np.array([s for _, s in heads])
            orbs = shoot(pts, res["y_end"][pts, cols], res["period"][pts, cols], res["z1_amplitude"][pts, cols],
                         z_size(res, (pts, cols)))
            res["n_rhs"][pts, cols] += orbs["n_rhs"].astype(res["n_rhs"].dtype)
            for j, key in enumerate(heads):
                self.orbit[key] = (bool(orbs["stable"][j]), orbs["state0"][j] if orbs["stable"][j] else None)
            go = [(heads[j][0], s, orbs["moduli"][j], orbs["period"][j]) for j in np.flatnonzero(orbs["unstable"])
                  for s in members[j]]  # fmt: skip
            if not go:
                return went_on[:0]
            went_on = self._leave(go)
        # The samples that went on in the last round and stopped on a cycle again: not decided.
        again = went_on[self.flat("outcome")[went_on] == PERIODIC]
        self.flat("outcome")[again] = UNSETTLED
        self.flat("status")[again] = STATUS["not_converged"]
        return again

    def _slow_approach(self, shoot, stuck: np.ndarray) -> None:
        """Samples unsettled at ``t_max`` whose newest section nearly repeated (:func:`slow_candidates`;
        not those in ``stuck``), shot from there in one call: each stable orbit is measured by a
        run started on it (period, multiplicity, harmonics: what the census clusters by) and the
        sample becomes ``periodic`` on it, as :func:`check` does for a sweep's transient."""
        if "nearest_residual" not in self.res:
            return
        ok = slow_candidates(self.flat("outcome"), self.flat("status"), self.flat("nearest_residual"))
        ok[stuck] = False
        flat = np.flatnonzero(ok)
        if not flat.size:
            return
        orbs, done = self._on_orbits(shoot, flat, self.flat("nearest_y")[flat], self.flat("nearest_period")[flat])
        mu = slowest_multiplier(orbs["moduli"][done])
        for f, m in zip(flat[done], mu):
            why = slow_note(float(self.flat("t_end")[f]), self.flat("nearest_residual")[f],
                            self.flat("nearest_multiplicity")[f], m)  # fmt: skip
            self.flat("outcome")[f], self.flat("status")[f], self.flat("reason")[f] = PERIODIC, STATUS["success"], why

    def _on_orbits(self, shoot, flat: np.ndarray, y: np.ndarray, period: np.ndarray) -> tuple[dict, np.ndarray]:
        """Shooting from the states ``y`` of the samples ``flat`` (flat indices) with periods ``period``,
        in one call, held to the period alone; each stable orbit measured by a run started on it,
        in one call, whose cycle quantities and state become the sample's (verified). Returns the
        shooting's result and, per sample, whether its stable orbit was measured."""
        k = self.res["outcome"].shape[1]
        nan = np.full(flat.size, np.nan)
        orbs = shoot(flat // k, y, period, nan, nan)
        self.flat("n_rhs")[flat] += orbs["n_rhs"].astype(self.res["n_rhs"].dtype)
        done = np.zeros(flat.size, dtype=bool)
        good = np.flatnonzero(orbs["stable"])
        if not good.size:
            return orbs, done
        g, state0 = flat[good], orbs["state0"][good]
        r = rows(self.steady(g // k, state0, None))
        self.flat("n_rhs")[g] += r["n_rhs"].astype(self.res["n_rhs"].dtype)
        ok = r["outcome"] == PERIODIC
        for key in CYCLE_KEYS:
            if key in self.res:
                self.flat(key)[g[ok]] = r[key][ok]
        self.flat("y_end")[g[ok]] = state0[ok]
        for f, y0 in zip(g[ok], state0[ok]):
            self.orbit[(int(f // k), int(f % k))] = (True, y0)
        done[good[ok]] = True
        return orbs, done

    def _leave(self, go: list) -> np.ndarray:
        """Samples ``go`` (point, sample, moduli, period) go on from near their unstable cycles; returns
        their flat indices. Moduli of NaN: no orbit to leave (a first stop whose shooting found no
        stable one of its period, :meth:`resolve`), no hold and no note."""
        k = self.res["outcome"].shape[1]
        pts = np.array([i for i, *_ in go])
        flat = pts * k + np.array([s for _, s, *_ in go])
        t0 = self.flat("t_end")[flat].astype(np.float64)
        moduli = np.array([g[2] for g in go])
        left, hold = leave(t0, self.t_max, moduli, np.array([g[3] for g in go]))
        none = np.isnan(moduli).any(axis=1)
        hold[none] = 0.0
        for f, t, g, skip in zip(flat, t0, go, none):
            self.orbit.pop((g[0], g[1]), None)  # its next stop is another, to be checked afresh
            if skip:
                continue
            why = f"at t = {t:.3g} s it stopped near an unstable cycle (largest multiplier {np.max(g[2]):.3g})"
            self.flat("reason")[f] = "; ".join(filter(None, [self.flat("reason")[f], why]))
        done = left <= 0
        self.flat("outcome")[flat[done]] = UNSETTLED
        self.flat("status")[flat[done]] = STATUS["not_converged"]
        if done.all():
            return flat[:0]
        flat, pts, t0 = flat[~done], pts[~done], t0[~done]
        r = rows(self.steady(pts, self.flat("y_end")[flat], self.known(),
                                     np.column_stack([left[~done], hold[~done]])))  # fmt: skip
        s = {key: self.flat(key) for key in r if key in self.res and key != "reason"}
        s["n_rhs"], s["t_end"] = self.flat("n_rhs"), self.flat("t_end")
        merge(s, flat, r, t0)
        return flat

    def measure(self, largest: list[tuple[int, int]], out: dict) -> None:
        """``largest_cycle_*`` of the points ``i`` whose largest cycle (head sample ``s``) is a verified
        stable orbit: measured by runs started on it, in one call (``largest_cycle_verified`` 1)."""
        pick = [(i, s) for i, s in largest if self.orbit.get((i, s), (False, None))[0]]
        if not pick:
            return
        pts = np.array([i for i, _ in pick])
        r = rows(self.steady(pts, np.array([self.orbit[key][1] for key in pick]), None))
        self.res["n_rhs"][pts, [s for _, s in pick]] += r["n_rhs"].astype(self.res["n_rhs"].dtype)
        ok = r["outcome"] == PERIODIC
        out["largest_cycle_omega"][pts[ok]] = r["omega"][ok]
        out["largest_cycle_a1"][pts[ok]] = r["z1_amplitude"][ok]
        out["largest_cycle_fraction_off_disk"][pts[ok]] = r["fraction_off_disk"][ok]
        out["largest_cycle_verified"][pts[ok]] = 1


def cluster_of(res: dict, i: int, per: np.ndarray, tol: float) -> tuple[np.ndarray, list[int]]:
    """:func:`cluster` of point ``i``'s periodic samples ``per``."""
    return cluster(res["omega"][i, per], res["multiplicity"][i, per], harmonics(res, (i, per)),
                   res["z_half_range"][i, per], tol)


def z_size(summary: dict, idx) -> np.ndarray:
    """The largest harmonic amplitude of z of the runs ``summary[...][idx]``: the size :func:`shoot` compares A1 in."""
    return np.max(harmonics(summary, idx), axis=-1)
