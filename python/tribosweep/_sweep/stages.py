"""The analysis stages of a sweep chunk, one function each (docs/model.md §4-§6).

Every stage reads and writes one :class:`Points` (the chunk's points, their parameters, the
settings and the output arrays) and decides nothing about which stages run: that policy is the
strategy's, in :mod:`tribosweep._sweep.chunk`. A stage that fails at a point leaves a status and a
reason there and goes on.

``linear``
    Eigenvalues of steady sliding (the Rust core, every point): growth rate, frequency of the
    least stable mode, normal-mode frequency (for wear, docs/model.md §8).
``describing_function``
    The triple-input describing function of the bilateral model (all roots in 150-3000 rad/s). At
    a linearly stable point a physical root is the subcritical saddle cycle around stable sliding.
``shooting``
    The periodic orbit of the full ODE near a describing-function root, with Floquet multipliers:
    the root's own error (its ``A1`` against the orbit's) and the saddle's true size.
``transient``
    A run to steady state from a disturbance, classified from its summary; a bounded run that
    neither repeated nor decayed is ``irregular`` and measured (:mod:`tribosweep._irregular`).
``census``
    K disturbances per point, each run to its attractor; fractions with standard errors
    (:mod:`tribosweep._census`); ``bistable`` is derived from it.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from .. import _census, _core, _cycles, _irregular
from .._codes import BISTABLE, DECIDED_BY, OUTCOME_NAMES, REGIME, STATUS, STATUS_NAMES
from .._settings import SweepSettings
from .schema import empty_result

#: A bounded run that did not settle, at a linearly stable point, whose z stays below this fraction
#: of the static penetration |z_st| is taken for sliding's own mode still decaying (not irregular).
SLOW_DECAY_FRACTION: float = 0.5

#: Regimes of a periodic steady state.
CYCLE_REGIMES: tuple[int, ...] = (REGIME["self_excited"], REGIME["contact_loss"], REGIME["stick_slip"])


@dataclass
class Points:
    """The points of one chunk (or its speed-independent subset), their settings and their results."""

    model_values: Mapping[str, float]
    contact: str
    friction_law: str
    point_params: Mapping[str, np.ndarray]
    settings: SweepSettings
    n: int
    out: dict = field(init=False)
    reason: np.ndarray = field(init=False)
    wall: np.ndarray = field(init=False)
    to_transient: np.ndarray = field(init=False)
    stable: np.ndarray = field(init=False)
    lin_failed: np.ndarray = field(init=False)
    eigenvalues: np.ndarray = field(init=False)

    def __post_init__(self):
        self.full = {k: np.asarray(v, dtype=np.float64) for k, v in self.model_values.items()}
        for k, a in self.point_params.items():
            self.full[k] = np.asarray(a, dtype=np.float64)
        self.base = {k: float(v) for k, v in self.model_values.items()}
        self.names = sorted(self.point_params)
        self.values = np.column_stack([np.asarray(self.point_params[k], dtype=np.float64) for k in self.names])
        self.out = empty_result(self.n)
        self.reason = np.full(self.n, "", dtype=object)
        self.wall = np.zeros(self.n)
        self.to_transient = np.zeros(self.n, dtype=bool)
        self.disturbance = float(np.abs(self.settings.y0[0]))
        # The physical describing-function root's first-harmonic amplitudes per component
        # (`_census.saddle_row`): the census's early return to sliding is measured in them.
        self.saddle = np.full((self.n, 6), np.nan)

    @property
    def threads(self) -> int | None:
        return self.settings.threads

    def charge(self, sel: np.ndarray, t0: float) -> None:
        """Share the wall time since ``t0`` evenly among the points ``sel``."""
        if np.size(sel):
            self.wall[sel] += (time.perf_counter() - t0) / np.size(sel)

    def finish(self) -> dict:
        out = self.out
        with np.errstate(invalid="ignore", divide="ignore"):
            out["cycle_period_ratio"] = out["linear_frequency"] / out["cycle_omega"]
        out["wall_time"] = self.wall
        out["reason"] = self.reason.astype(str)
        return out


def static_penetration(full: Mapping[str, np.ndarray], sel: np.ndarray) -> np.ndarray:
    """Static penetration z_st [m] of the selected points (docs/model.md §3, cancellation-free form)."""
    n = max(np.size(v) for v in full.values())
    sub = {k: np.broadcast_to(full[k], (n,))[sel] for k in ("contact_stiffness", "contact_quadratic", "normal_load")}
    return _census._static(sub)[0]


#: A start on the least stable mode (:func:`mode_start`) has ``|z| = z_amp`` unless that puts another
#: component beyond this many times the same multiple of its characteristic size
#: (:func:`tribosweep._irregular.characteristic_sizes`); such a start is scaled down until its largest
#: component is there. On the torsion mode the other components are 3-7.5 times (every start of the
#: issue-10 Stribeck sweep, the default sweep and a 400-point constant-friction grid), so the cap
#: acts only on a mode with almost no ``z``: the frictional mode destabilised by a falling Stribeck
#: curve at a small load, whose start scaled by ``z`` alone put ``x`` at 230 m and ``x'`` at 2e7 m/s.
MODE_START_CAP: float = 10.0


def mode_start(full: Mapping[str, np.ndarray], friction_law: str, sel: np.ndarray, z_amp: np.ndarray,
               eigenvalues: np.ndarray) -> np.ndarray:  # fmt: skip
    """Initial states on the least stable linear mode of each selected point, with ``|z| = z_amp``
    (held smaller where another component would be out of all proportion: :data:`MODE_START_CAP`).

    A disturbance along the mode that self-excites (the torsion mode) reaches the attractor far
    sooner than one in ``z`` alone, which mostly excites the heavily damped normal mode. The mode
    shape is the census's closed form, or under speed-dependent friction a null vector by
    elimination (:mod:`tribosweep._modes`: no LAPACK, the same bits on every machine);
    ``eigenvalues`` are the core's, ``(sel.size, 6)``.
    """
    n = max(np.size(v) for v in full.values())
    sub = {k: np.broadcast_to(np.asarray(full[k], dtype=np.float64), (n,))[sel] for k in full}
    lam = np.asarray(eigenvalues)
    k = np.argmax(lam.real + 1e-9 * lam.imag, axis=1)  # least stable; the +Im member of the pair
    lam = lam[np.arange(sel.size), k]
    if friction_law == "constant":
        v = _census.mode_shape(sub, lam)
    else:
        v = _census._mode_shape_numeric(_census.jacobians(sub, friction_law), lam)
    # Rotate so that z is real and positive at t = 0 (zd then follows from the mode), scale |z|:
    # multiplying by conj(z) does both without angle() and exp() (numpy's arctan2 on arrays runs a
    # SIMD kernel that the CPU picks: other last bits, other chaotic transients, on other machines).
    v = v * np.conj(v[:, :1])
    z_amp = np.broadcast_to(np.asarray(z_amp, dtype=np.float64), (sel.size,))
    y0 = v.real / np.maximum(np.abs(v[:, :1].real), 1e-300) * z_amp[:, None]
    # A mode with almost no z (the frictional mode that a falling Stribeck curve destabilises, at
    # small loads) scaled to that |z| would start thousands of metres off: held at the cap.
    size = _irregular.characteristic_sizes(sub)
    largest = (np.abs(v.real) / size).max(axis=1)
    cap = MODE_START_CAP * z_amp / size[:, 0]
    over = largest * z_amp > cap * np.abs(v[:, 0].real)
    y0[over] = v.real[over] * (cap[over] / largest[over])[:, None]
    return np.ascontiguousarray(y0)


def linear(p: Points) -> None:
    """Stage 1: linear stability of steady sliding at every point."""
    t0 = time.perf_counter()
    lin = _core.linear_stability(p.base, p.contact, p.friction_law, p.names, p.values, threads=p.threads)
    out = p.out
    out["growth_rate"] = lin["growth_rate"]
    out["linear_frequency"] = lin["linear_frequency"]
    out["normal_mode_frequency"] = lin["normal_mode_frequency"]
    p.stable = np.asarray(lin["stable"], dtype=bool)
    p.eigenvalues = np.asarray(lin["eigenvalues"])
    out["status"][:] = lin["status"]
    out["decided_by"][:] = DECIDED_BY["linear"]
    out["regime"][:] = np.where(p.stable, REGIME["steady_sliding"], REGIME["unstable_undetermined"])
    p.lin_failed = lin["status"] != STATUS["success"]
    out["regime"][p.lin_failed] = REGIME["failed"]
    p.reason[p.lin_failed] = "linear stability: eigenvalues failed"
    p.wall[:] = (time.perf_counter() - t0) / max(p.n, 1)


@dataclass
class Roots:
    """The describing function's result over the points ``sel`` and the physical root of each point."""

    sel: np.ndarray
    df: dict | None
    root: np.ndarray  # per point: index of the physical root, -1 none
    shoot: np.ndarray  # per point: shoot this root


def describing_function(p: Points, *, unstable_too: bool, predict_cycles: bool, escalate: bool) -> Roots:
    """Stage 2: the describing function (bilateral: the report's model).

    ``unstable_too``: also at linearly unstable points (at such points ``auto`` needs none: the
    Hopf bifurcation is subcritical, no cycle to find). ``predict_cycles``: at an unstable point a
    root within the law's validity is the predicted cycle (``tidf``/``shooting`` strategies).
    ``escalate``: a failure sends the point to a transient, and a disturbance within
    ``SHOOT_MARGIN`` of the saddle amplitude marks the root for shooting (``auto``).
    """
    n, out, reason, stable = p.n, p.out, p.reason, p.stable
    sel = np.flatnonzero(~p.lin_failed & (stable | unstable_too))
    root = np.full(n, -1)
    shoot = np.zeros(n, dtype=bool)
    df = None
    if not sel.size:
        return Roots(sel, df, root, shoot)
    t1 = time.perf_counter()
    sh = p.settings.shooting
    df = _core.describing_function(p.base, "bilateral", p.friction_law, p.names, p.values[sel], variant="consistent",
                                   w_min=150.0, w_max=3000.0, n_base=int(sh.tidf_grid), threads=p.threads)  # fmt: skip
    p.charge(sel, t1)
    out["tidf_roots"][sel] = df["n_roots"]
    iters = np.where(df["newton_iterations"] > 0, df["newton_iterations"], 0).sum(axis=1)
    out["newton_iterations"][sel] += iters
    for j, i in enumerate(sel):
        k = np.flatnonzero(df["physical"][j] == 1)
        if df["status"][j] != STATUS["success"]:
            p.to_transient[i] = escalate
            reason[i] = f"describing function failed: {STATUS_NAMES[df['status'][j]]}"
            continue
        if k.size:
            root[i] = k[0]
            out["tidf_omega"][i] = df["omega"][j, k[0]]
            out["tidf_a1"][i] = df["A1"][j, k[0]]
            out["tidf_contact_opens"][i] = df["contact_opens"][j, k[0]]
            p.saddle[i] = _census.saddle_row(df, j, k[0])
        if stable[i]:
            out["decided_by"][i] = DECIDED_BY["tidf"]
            if k.size and p.disturbance * SHOOT_MARGIN >= out["tidf_a1"][i] and escalate:
                shoot[i] = True  # the disturbance is near the saddle: its true size matters
            elif df["search_outcome"][j] == "below_resolution":
                reason[i] = "near a Hopf point: the describing function is below resolution"
        elif k.size and predict_cycles and not out["tidf_contact_opens"][i]:
            out["regime"][i] = REGIME["self_excited"]
            out["decided_by"][i] = DECIDED_BY["tidf"]
            out["cycle_omega"][i] = out["tidf_omega"][i]
            out["z1_amplitude"][i] = out["tidf_a1"][i]
            out["z2_amplitude"][i] = df["A2"][j, k[0]]
            out["z_half_range"][i] = 0.5 * (df["z_max"][j, k[0]] - df["z_min"][j, k[0]])
            out["phi1_amplitude"][i] = df["phi1_amplitude"][j, k[0]]
            reason[i] = "cycle predicted by the describing function"
        elif predict_cycles:
            reason[i] = "sliding unstable; no describing-function cycle within the law's validity"
    return Roots(sel, df, root, shoot)


#: ``auto`` shoots the saddle orbit when the disturbance's z exceeds the describing function's A1
#: divided by this margin (the DF's A1 error grows with amplitude: 10-20 % at tens of um).
SHOOT_MARGIN: float = 2.0


def shooting(p: Points, roots: Roots, *, every_root: bool, escalate: bool) -> None:
    """Stage 3: the periodic orbit near the marked roots (``every_root``: near every physical root).

    ``escalate``: a failed shooting, or a disturbance at or beyond the saddle, sends the point to a
    transient.
    """
    out, reason = p.out, p.reason
    pick = roots.shoot | (every_root & (roots.root >= 0))
    shoot = np.flatnonzero(pick)
    if not shoot.size:
        return
    js = np.searchsorted(roots.sel, shoot)
    ks = roots.root[shoot]
    roots_arr = np.column_stack([roots.df[v][js, ks] for v in ("omega", "A0", "A1", "A2", "theta")])
    sh = p.settings.shooting
    t2 = time.perf_counter()
    orbs = _core.periodic_orbits(p.base, "bilateral", p.friction_law, p.names, p.values[shoot], roots=roots_arr,
                                 rtol=sh.rtol, tol=sh.tol, threads=p.threads)  # fmt: skip
    p.charge(shoot, t2)
    for r, i in enumerate(shoot):
        orb = {k: v[r] for k, v in orbs.items()}
        out["newton_iterations"][i] += orb["newton_iterations"]
        out["n_rhs"][i] += orb["n_rhs"]
        if orb["status"] != STATUS["success"]:
            if escalate:
                p.to_transient[i] = True
                reason[i] = f"shooting from the describing-function root failed: {STATUS_NAMES[orb['status']]}"
            continue
        out["orbit_a1"][i] = orb["A1"]
        out["orbit_stable"][i] = int(orb["stable"])
        out["tidf_a1_error"][i] = out["tidf_a1"][i] / orb["A1"] - 1
        if p.stable[i]:
            if p.disturbance < orb["A1"]:
                out["decided_by"][i] = DECIDED_BY["shooting"]
                reason[i] = ""
            elif escalate:
                p.to_transient[i] = True
                reason[i] = "the disturbance reaches the saddle cycle: integrated"


def classify(summary: dict, stable: np.ndarray, t_max: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Regime, status, reason and deciding stage of transient runs from their steady-state summaries.

    A run that stayed bounded (no escape, a finite end state) but neither repeated nor decayed,
    either stationary over three blocks of sections or back near one unstable cycle between bursts
    often enough to call it intermittent (outcome ``irregular``), or still so at ``t_max`` (outcome
    ``unsettled``), is an answer: sustained ``irregular`` motion, decided by the
    transient, status ``success`` (its measurement follows in :func:`transient`). Only a failed
    integration makes a point ``failed``.
    """
    status = np.asarray(summary["status"], dtype=np.uint8).copy()
    outcome = np.asarray(summary["outcome"], dtype=np.uint8)
    off = np.asarray(summary["fraction_off_disk"])
    vmin = np.asarray(summary["min_slip_velocity"])
    y_end = summary.get("y_end")
    names = [OUTCOME_NAMES[o] for o in outcome]
    n = len(names)
    regime = np.full(n, REGIME["failed"], dtype=np.uint8)
    decided = np.full(n, DECIDED_BY["transient"], dtype=np.uint8)
    reason = np.asarray(summary["reason"], dtype=str).astype(object)
    for i, name in enumerate(names):
        st = STATUS_NAMES[status[i]] if status[i] < len(STATUS_NAMES) else str(status[i])
        finite = y_end is None or bool(np.all(np.isfinite(np.asarray(y_end)[i])))
        if name == "diverged" or st == "diverged":
            regime[i] = REGIME["diverged"]
            if not reason[i]:
                reason[i] = _escape_reason(summary, i)
        elif (name == "unsettled" and st == "not_converged" and finite) or (name == "irregular" and finite):
            regime[i] = REGIME["irregular"]
            status[i] = STATUS["success"]
            reason[i] = _irregular.stop_reason(summary, i, t_max) + (
                "" if not stable[i] else " (sliding is linearly stable: this motion coexists with it, or is a slow "
                "transient)")  # fmt: skip
        elif st != "success" or name in ("failed", "unsettled", "irregular"):
            regime[i] = REGIME["failed"]
            if st == "success":
                status[i] = STATUS["non_finite"]
                st = "non_finite"
            detail = f": {reason[i]}" if reason[i] else ""
            reason[i] = f"transient {name}, status {st}{detail}"
        elif name == "decayed" and not stable[i]:
            # Small motion grows where sliding is linearly unstable: no run can come to rest there.
            # The run's decay test was deceived (a motion too small for it in the compared
            # components): a failed detection, not an answer.
            regime[i] = REGIME["unstable_undetermined"]
            status[i] = STATUS["not_converged"]
            reason[i] = (f"the transient stopped as decayed at t = {float(summary['t_end'][i]):.4g} s, but sliding is "
                         "linearly unstable here: no motion comes to rest at an unstable equilibrium")  # fmt: skip
        elif name == "decayed":
            regime[i] = REGIME["steady_sliding"]
        elif name == "periodic":
            if not (vmin[i] > 0):
                regime[i] = REGIME["stick_slip"]
            elif off[i] > 0:
                regime[i] = REGIME["contact_loss"]
            else:
                regime[i] = REGIME["self_excited"]
            if stable[i]:
                note = "sliding is linearly stable: this cycle, reached from the run's start, coexists with it"
                reason[i] = f"{reason[i]}; {note}" if reason[i] else note
    return regime, status, reason.astype(str), decided


def _escape_reason(summary: dict, i: int) -> str:
    """Why run ``i`` of a steady-state summary is ``diverged``: where and when it left the model's validity."""
    if "max_abs_z" not in summary or "t_end" not in summary:
        return "|z| reached the escape limit: the motion left the model's validity"
    z, t = float(summary["max_abs_z"][i]), float(summary["t_end"][i])
    # Off the disk the gap is what grew; pressed into it, z went negative past the limit (gap < 0).
    gap = float(summary["max_gap"][i]) if "max_gap" in summary else float("nan")
    where = f"; the pin flew {gap:.3g} m off the disk" if gap >= 0.5 * z else "; the pin was pressed into the disk past it"
    return f"|z| reached the escape limit ({z:.3g} m) at t = {t:.3g} s: the motion left the model's validity{where}"


def run_steady(p: Points, sel: np.ndarray, y0: np.ndarray, decay: np.ndarray | None = None,
               restart: np.ndarray | None = None, approach: bool = False, rtol: float | None = None) -> dict:  # fmt: skip
    """Runs to steady state of the points ``sel`` from ``y0`` (one row, or one per point), in the core.

    ``restart``: per run ``(t_max, hold)``, runs that go on from where earlier ones stopped (the
    core's ``restart``); default: the settings' ``t_max`` and no hold. ``approach``: a slow
    approach to a cycle is checked by shooting inside the run after ``approach_periods`` periods
    of steady contraction, at the checks' tolerances (the transients' first runs; a run that
    stops so is on a stable orbit, measured there at those tolerances: its check is done).
    ``rtol``: default the transients' ``transient_rtol`` (runs that find an attractor); runs that
    measure an orbit pass the checks' tolerance.
    """
    it, st = p.settings.integration, p.settings.steady
    return _core.ensemble(
        p.base, p.contact, p.friction_law, p.names, np.ascontiguousarray(p.values[sel]),
        np.ascontiguousarray(y0, dtype=np.float64), float(st.t_max), it.integrator,
        float(st.rtol if rtol is None else rtol),
        atol=None if it.atol is None else np.asarray(it.atol, dtype=np.float64), threads=p.threads, kind="steady",
        periodic_tol=float(st.periodic_tol), decay_amplitude=st.decay_amplitude, n_fourier=512,
        restart=None if restart is None else np.ascontiguousarray(restart, dtype=np.float64),
        decay_amplitudes=None if decay is None else np.ascontiguousarray(decay, dtype=np.float64),
        irregular_block=int(p.settings.irregular.transient_block),
        approach_periods=int(st.approach_periods) if approach else 0,
        approach_rtol=_cycles.check_rtol(it.rtol, p.settings.shooting.rtol), approach_tol=float(p.settings.shooting.tol),
    )  # fmt: skip


def check_cycles(p: Points, sel: np.ndarray, summary: dict) -> tuple[dict, np.ndarray]:
    """Stage 4a: the cycles that the transients of ``sel`` stopped on, checked and converged by shooting.

    :func:`tribosweep._cycles.check` with the sweep's settings (shooting at ten times tighter than
    ``rtol``, whatever the transients' ``transient_rtol``), the work charged to the points. A transient's stop near a slowly
    attracting cycle is ``periodic_tol / (1 - |mu|)`` from it (the Stribeck sweep's amplitudes were
    up to 0.7 % off); one in a laminar phase of intermittent motion repeats near an unstable cycle.
    Returns the summary with the checked rows replaced and per run whether its cycle was verified.
    """
    sh = p.settings.shooting
    rtol = _cycles.check_rtol(p.settings.integration.rtol, sh.rtol)

    def shoot(idx, y, period, z1, size):
        t1 = time.perf_counter()
        out = _cycles.shoot(p.base, p.contact, p.friction_law, p.names, p.values[sel[idx]], y, period, z1, size,
                            rtol=rtol, tol=sh.tol, threads=p.threads)  # fmt: skip
        p.charge(sel[idx], t1)
        return out

    def steady(idx, y0, restart=None, measure=False):
        t1 = time.perf_counter()
        out = run_steady(p, sel[idx], y0, restart=restart, rtol=rtol if measure else None)
        p.charge(sel[idx], t1)
        return out

    return _cycles.check(summary, shoot, steady, float(p.settings.steady.t_max),
                         measure=lambda idx, y0: steady(idx, y0, measure=True))  # fmt: skip


def transient(p: Points, *, start_on_mode: bool) -> None:
    """Stage 4: run the points marked ``to_transient`` to steady state and classify them.

    ``start_on_mode``: linearly unstable points start on the unstable (torsion) mode with ``|z| =
    unstable_disturbance |z_st|`` instead of the disturbance ``y0``: a small disturbance grows at
    the linear rate (0.07 /s near the Hopf load), which would cost about 100 s of simulated time
    for nothing. The attractor reached is the same where it is the only one; where it is not, the
    census is what tells.
    """
    sel = np.flatnonzero(p.to_transient)
    if not sel.size:
        return
    out, reason = p.out, p.reason
    y0s = np.tile(np.asarray(p.settings.y0, dtype=np.float64), (sel.size, 1))
    if start_on_mode:
        unstable = ~p.stable[sel]
        z_st = static_penetration(p.full, sel)
        if unstable.any():
            y0s[unstable] = mode_start(p.full, p.friction_law, sel[unstable],
                                       p.settings.unstable_disturbance * np.abs(z_st[unstable]),
                                       p.eigenvalues[sel[unstable]])  # fmt: skip
    t1 = time.perf_counter()
    # The slowest sliding first. A call's lanes take trajectories in order and it ends with its
    # longest, so a long run started last leaves lanes idle; where friction depends on speed, the
    # longest (stick-slip, irregular motion) are at low speeds. On the Stribeck sweep of
    # benches/bench_stribeck.py the transients took 0.31-0.32 s in this order against 0.36-0.37 s
    # in the grid's (0.29-0.30 s in the order of their measured lengths). A run's result does
    # not depend on its place in the call.
    order = np.argsort(np.broadcast_to(p.full["sliding_speed"], (p.n,))[sel], kind="stable")
    back = np.argsort(order)
    summary = {k: v[back] for k, v in _cycles.rows(run_steady(p, sel[order], y0s[order], approach=True)).items()}
    p.charge(sel, t1)
    summary, verified = check_cycles(p, sel, summary)
    t_max = float(p.settings.steady.t_max)
    regime, status, why, decided = classify(summary, p.stable[sel], t_max)
    out["regime"][sel] = regime
    out["status"][sel] = status
    reason[sel] = np.where(why != "", why, reason[sel].astype(str))
    out["decided_by"][sel] = decided
    periodic = np.isin(regime, CYCLE_REGIMES)
    # At a linearly stable point, a "cycle" that shooting could not verify and whose motion stays
    # well inside the contact is sliding's own least-damped mode still decaying: near a Hopf load
    # so slowly that its sections repeat to periodic_tol (0.1-0.2 um at 2 x 23 points of
    # benches/bench_sweep.py's 98,394, where shooting ends on no orbit of that size). Sliding, as
    # for a slow irregular run (:func:`irregular`).
    slow = periodic & ~verified & p.stable[sel]
    if slow.any():
        slow = _still_decaying(p, sel, _cycles.z_size(summary, slice(None)), slow, [
            f"at t_end = {float(t):.3g} s, though its sections repeated to periodic_tol (shooting from there found no "
            "orbit of that size)" for t in summary["t_end"]])  # fmt: skip
        periodic &= ~slow
    for key in ("z1_amplitude", "z2_amplitude", "z_half_range", "phi1_amplitude", "fraction_off_disk"):
        out[key][sel] = np.where(periodic, summary[key], np.nan)
    out["cycle_omega"][sel] = np.where(periodic, summary["omega"], np.nan)
    out["cycle_verified"][sel] = np.where(periodic, verified, -1)
    out["min_normal_force"][sel] = summary["min_normal_force"]
    out["min_slip_velocity"][sel] = summary["min_slip_velocity"]
    out["n_rhs"][sel] += np.asarray(summary["n_rhs"], dtype=np.int64)
    irr = regime == REGIME["irregular"]
    if irr.any():
        irregular(p, sel[irr], np.asarray(summary["y_end"])[irr], t_max)
    # Intermittent motion's unstable cycle, where the point stayed irregular after its measurement.
    still = out["regime"][sel] == REGIME["irregular"]
    for key in ("period", "multiplier"):
        got = np.asarray(summary.get(f"intermittent_{key}", np.full(sel.size, np.nan)), dtype=np.float64)
        out[f"irregular_intermittent_{key}"][sel] = np.where(still, got, np.nan)
    kind = np.asarray(summary.get("intermittent_instability", np.zeros(sel.size)), dtype=np.uint8)
    out["irregular_intermittent_instability"][sel] = np.where(still, kind, 0)


def _still_decaying(p: Points, pts: np.ndarray, amp: np.ndarray, candidate: np.ndarray, when: list[str]) -> np.ndarray:
    """Which of the points ``pts`` (where ``candidate``) are sliding still decaying; marks them so.

    At a linearly stable point, a motion that stays well inside the contact (``amp`` below
    ``SLOW_DECAY_FRACTION |z_st|``: the law nearly linear, no opening) is sliding's own least-damped
    mode still decaying, at the linear rate (0.03 1/s near a Hopf load): a run that did not settle
    by ``t_max``, or whose sections repeated so slowly did it shrink. Sliding, as linear stability
    says, status ``not_converged``; ``when`` (per point) completes the reason.
    """
    slow = candidate & (amp < SLOW_DECAY_FRACTION * np.abs(static_penetration(p.full, pts)))
    q = pts[slow]
    p.out["regime"][q] = REGIME["steady_sliding"]
    p.out["decided_by"][q] = DECIDED_BY["linear"]
    p.out["status"][q] = STATUS["not_converged"]
    p.reason[q] = [f"sliding is linearly stable and the motion small (|z| <= {a:.3g} m, below "
                   f"{SLOW_DECAY_FRACTION:g} |z_st|): still decaying {w}"
                   for a, w in zip(amp[slow], np.asarray(when, dtype=object)[slow])]  # fmt: skip
    return slow


def irregular(p: Points, pts: np.ndarray, y_end: np.ndarray, t_max: float) -> None:
    """Stage 4b: what an irregular run measured, from where it ended (:mod:`tribosweep._irregular`).

    The range and dominant frequency of z over a window, and the largest finite-time Lyapunov
    exponent (about 0: quasi-periodic; > 0: chaotic). A failed measurement leaves the motion
    undetermined: a failure status and its reason.
    """
    out, reason, stable = p.out, p.reason, p.stable
    t1 = time.perf_counter()
    meas = _irregular.measure(p.model_values, p.contact, p.friction_law, p.point_params, pts, y_end,
                              integration=p.settings.integration, settings=p.settings.irregular,
                              threads=p.threads)  # fmt: skip
    p.charge(pts, t1)
    out["n_rhs"][pts] += meas["n_rhs"]
    # At a linearly stable point, a motion that stays well inside the contact (|z| below
    # SLOW_DECAY_FRACTION |z_st|: the law nearly linear, no opening) is sliding's own
    # least-damped mode still decaying, at the linear rate (0.03 1/s near a Hopf load): too
    # slow for t_max, not sustained motion. Sliding, as linear stability says.
    amp = np.maximum(np.abs(meas["irregular_z_min"]), np.abs(meas["irregular_z_max"]))
    slow = _still_decaying(p, pts, amp, stable[pts], [f"(the transient did not settle by t_max = {t_max:g} s)"] * len(pts))
    pts, meas = pts[~slow], {k: v[~slow] for k, v in meas.items()}
    # Transient chaos: bounded until t_max, the motion left through the escape limit during the
    # measurement window. That is an answer (the run diverged), not a failure.
    esc = meas["status"] == STATUS["diverged"]
    if esc.any():
        q = pts[esc]
        out["regime"][q] = REGIME["diverged"]
        out["status"][q] = STATUS["success"]
        reason[q] = [f"bounded until t_max = {t_max:g} s without settling (irregular), then |z| reached the "
                     "escape limit during the measurement window after it: transient chaos"] * q.size
    pts, meas = pts[~esc], {k: v[~esc] for k, v in meas.items()}
    for key in _irregular.IRREGULAR_VARIABLES:
        out[key][pts] = meas[key]
    bad = meas["status"] != STATUS["success"]
    if bad.any():
        out["status"][pts[bad]] = meas["status"][bad]
        out["regime"][pts[bad]] = np.where(stable[pts[bad]], REGIME["failed"], REGIME["unstable_undetermined"])
        reason[pts[bad]] = [f"{a}; {b}" for a, b in zip(reason[pts[bad]], meas["reason"][bad])]
    for j in np.flatnonzero(~bad):
        f, se = meas["irregular_ftle"][j], meas["irregular_ftle_se"][j]
        reason[pts[j]] += f"; largest FTLE {f:.3g} +- {se:.2g} 1/s"


def _regime_share(out: dict, i: int, per: Mapping[str, np.ndarray], j: int) -> tuple[float, float]:
    """The fraction of point ``i``'s counted census samples (row ``j`` of ``per``) that reach its
    regime, and its binomial standard error: sliding, irregular motion, an escape, or the
    transient's own cycle (:func:`tribosweep._cycles.same_cycle` on the first two harmonics of z:
    the sweep keeps no third)."""
    a = per["attractor"][j]
    nv = int(np.sum(a >= 0))
    if nv == 0:
        return np.nan, np.nan
    regime = int(out["regime"][i])
    kind = {REGIME["steady_sliding"]: 0, REGIME["irregular"]: 2, REGIME["diverged"]: 3}.get(regime, 1)
    hit = a == kind
    if regime in CYCLE_REGIMES and np.isfinite(out["cycle_omega"][i]):
        omega, a1, a2, size = (float(out[k][i]) for k in ("cycle_omega", "z1_amplitude", "z2_amplitude", "z_half_range"))
        amps = np.stack([per["z1_amplitude"][j], per["z2_amplitude"][j]], axis=-1)
        size = size if np.isfinite(size) else max(a1, a2)
        hit &= _cycles.same_cycle(per["omega"][j], amps, omega, (a1, a2), size, _census.CYCLE_TOL)
    p = float(np.sum(hit)) / nv
    return p, float(np.sqrt(p * (1.0 - p) / nv))


#: Regimes of a transient at unstable sliding that the census looks past: the motion one small
#: disturbance reached (a cycle, irregular motion, an escape), where others may coexist.
MOTION_REGIMES: tuple[int, ...] = (*CYCLE_REGIMES, REGIME["irregular"], REGIME["diverged"])


def census(p: Points) -> None:
    """Stage 5: the attractor census where a saddle cycle surrounds stable sliding, and where
    sliding is unstable and its transient reached a motion.

    K disturbances, each run to its attractor with the point's contact law; fractions with
    standard errors. Stable points without a saddle have nothing to find (``no_saddle``). At an
    unstable point the regime stays the motion that the transient from the unstable mode reached;
    the census says what else the disturbances reach (another cycle, irregular motion, an
    escape), and its words follow the transient's reason.
    """
    out, reason = p.out, p.reason
    ok = p.stable & ~p.lin_failed
    no_saddle = ok & ~np.isfinite(out["tidf_a1"])
    out["bistable"][no_saddle] = BISTABLE["no_saddle"]
    around = ok & (out["regime"] == REGIME["steady_sliding"]) & np.isfinite(out["tidf_a1"])
    past = ~p.stable & ~p.lin_failed & np.isin(out["regime"], MOTION_REGIMES)
    cand = np.flatnonzero(around | past)
    if not cand.size:
        return
    it, cs = p.settings.integration, p.settings.census
    t1 = time.perf_counter()
    res, per = _census.run(
        p.model_values, p.contact, p.friction_law, p.point_params, cand,
        samples=cs.samples, scale=cs.disturbance_scale, t_max=cs.t_max,
        integrator=it.integrator, rtol=cs.rtol, atol=None if it.atol is None else list(it.atol),
        periodic_tol=p.settings.steady.periodic_tol, threads=p.threads,
        eigenvalues=p.eigenvalues[cand], linear_frequency=out["linear_frequency"][cand],
        saddle=p.saddle[cand], irregular_block=p.settings.irregular.block, recurrence=cs.recurrence,
        shooting_rtol=p.settings.shooting.rtol, shooting_tol=p.settings.shooting.tol, stop_tol=cs.stop_tol,
    )  # fmt: skip
    p.charge(cand, t1)
    out["n_rhs"][cand] += per["n_rhs"].sum(axis=1)
    for key, arr in res.items():
        out[key][cand] = arr
    for j, i in enumerate(cand):
        nv = int(res["census_samples"][j])
        if nv == 0:
            failed = _census.failed_reason(per, j)
            reason[i] = f"{reason[i]}; {failed}" if past[i] and reason[i] else failed
            continue
        out["bistable"][i] = BISTABLE["coexisting"] if res["n_attractors"][j] > 1 else BISTABLE["one_attractor"]
        out["regime_fraction"][i], out["regime_fraction_se"][i] = _regime_share(out, i, per, j)
        counts = np.rint(res["basin_fraction"][j] * nv).astype(int)
        seen = ", ".join(f"{a} {c}/{nv}" for a, c in zip(_census.ATTRACTOR_NAMES, counts) if c)
        if counts[2]:
            # How the irregular samples were decided: stationary (the early stop) or still so at t_max.
            late = int(np.sum((per["outcome"][j] == OUTCOME_NAMES.index("unsettled")) & (per["attractor"][j] == 2)))
            known = int(np.sum(per["matched"][j]))
            seen += (f" ({counts[2] - late - known} stationary, {known} by recurrence on a pilot's attractor, "
                     f"{late} at the census t_max)")
        said = ""
        if res["n_attractors"][j] > 1:
            said = f"coexisting attractors (census): {seen}"
        elif counts[0] < nv:
            said = f"census: {seen}"
        if said:
            reason[i] = f"{reason[i]}; {said}" if past[i] and reason[i] else said
