"""Sustained irregular motion: what a bounded run that neither repeats nor decays measured.

A transient that stays bounded but has neither repeated (to ``periodic_tol``) nor decayed by
``t_max`` is an answer, not a failure: the slider moves irregularly, quasi-periodically or
chaotically. :func:`measure` characterises such motion from the run's end state, for many points
at once (every core call is one batched ``_core.ensemble`` over all points):

``irregular_z_min``, ``irregular_z_max``
    The range of ``z`` over a measurement window of ``window`` seconds (sampled every
    ``sample_dt``) that starts where the transient ended, sampled on the exponent's base run
    (at ``ftle_rtol``; a run of its own until 2026-11-29).
``irregular_omega``
    The dominant angular frequency of ``z`` over the window: the peak of the Hann-windowed
    spectrum, refined by a parabola through the logarithms of the peak bin and its neighbours
    (:func:`dominant_omega`).
``irregular_ftle``, ``irregular_ftle_se``
    The largest finite-time Lyapunov exponent [1/s] by the two-trajectory method of Benettin et
    al. (1980) (:func:`benettin`): the transient's end state and a copy displaced by ``d0`` in
    units of the characteristic sizes are run side by side for ``warmup + segments`` segments of
    ``tau`` seconds; after each the copy is pulled back to distance ``d0`` along the separation.
    The exponent is the mean of ``ln(d_k / d0) / tau`` over the last ``segments`` segments; its
    standard error is the segments' standard deviation over ``sqrt(segments)``. A point runs at
    least until its window is sampled (by default 12 segments, 0.6 s, cover the 0.5 s window).

How to read the exponent. On any bounded motion that is not an equilibrium, the direction along
the flow has exponent 0, so the largest exponent is >= 0: about 0 (within a few standard errors)
for a periodic or quasi-periodic motion, or one still creeping towards a cycle; clearly positive
for chaos; clearly negative only for a motion still decaying towards an equilibrium.

Why these defaults (seed apparatus, docs/model.md §3). The motion the slider self-excites is the
torsion mode at about 98.75 Hz (period 10.1 ms; 640-650 rad/s under load). ``tau = 0.05 s`` is
about 5 of its periods: long enough that the stretching within one cycle (which swings with the
phase, by more than the exponent itself on a bouncing cycle) averages out inside a segment, short
enough that a separation of ``d0 = 1e-8`` grows at most ``e^10`` (to 2e-4 of the characteristic
size, still linear) at exponents up to 200 1/s. ``segments = 40`` (2 s) makes the standard error
a fifth of the segment spread, where it is needed: a point whose exponent is 5 standard errors
from 0 after ``min_segments = 10`` (0.5 s; chaotic points of the Stribeck sweep are 8-9 there)
stops, at a third of the cost of 40 (:data:`FTLE_DECISIVE`). ``warmup = 2`` segments (0.1 s)
let the separation turn from its arbitrary start into the most unstable direction (the normal
mode's transverse contraction, about 50 1/s, is gone after a segment; the torsion mode's, about
0.3-1 1/s, is not after 4 either, which is why the estimate of a periodic motion scatters about 0
by its standard error). Both runs are integrated at ``rtol = 1e-7``, though ``d0`` is smaller:
two runs ``d0`` apart take the same steps (the controller's step sizes are smooth in the state),
so their step errors largely cancel in the separation (the Rust test
``two_runs_a_small_distance_apart_separate_as_at_a_far_tighter_tolerance``; where the pin leaves
the disk and sticks, the floor is the events' located times at every tolerance, 2-5e-2 of the
separation from 1e-6 to 1e-11 over 0.1 s, at most about 1 1/s in one segment's rate).

How the tolerance was chosen (2026-11-29): on replicates, not on one run's segments. The
Stribeck sweep's 31 irregular points (``benches/bench_stribeck.py``), each measured 8 times with
the window 0.5, 1.5, ..., 7.5 s (8 starts along its attractor), give an exponent per point as the
replicates' mean with their standard error. Against the same at ``rtol = 1e-11``, in units of the
combined replicate standard errors: at 1e-7 median 0.62, largest 1.76 (with ``warmup = 2``: 0.54
and 1.43), at 1e-8 0.65 and 2.10, at 1e-9 0.78 and 4.96, at 1e-10 0.46 and 5.62, at 1e-6 0.59 and
3.32 (its mean shift +0.45, 2.5 of its standard errors: a bias). The largest at 1e-9 and 1e-10 is
one point near 0 (2.6 and 3.4 against -0.03 1/s, replicate standard errors 0.35-0.47), which 1e-8
and 1e-7 get right: the exponent there is not monotonic in the tolerance, and a tighter one is
not safer. One run's segment standard error matches the replicates' spread at the median
point but underestimates it up to 4.6x on intermittent motion, so single runs could not tell
these settings apart. At 1e-7 with ``warmup = 2`` the measurement of the sweep's 31 points
(window and exponent) takes 1.92 million right-hand sides, against 3.39 million at 1e-9 with
``warmup = 4`` (``python benches/bench_stribeck.py --ftle``, where the same comparison is made
from 8 starts per point along the transients' ends: 1e-7 largest 1.79, 1e-9 3.22). On the
20 x 8 x 6 grid of that model (151 irregular points; ``tribosweep.bench.ftle_settings`` with its
``axes``) the medians agree as well (0.57 at 1e-7, 0.60 at 1e-9, 0.62 at 1e-12 against 1e-11,
whose own halves give 0.75 and at most 3.46), but at two points with exponents near 0 every loose
tolerance is off by a few 1/s: at 1e-7 -0.6 against 3.7 1/s (7.9 standard errors) and -0.9
against 1.5, at 1e-9 -0.55 against 1.5 (5.3), where 1e-12 agrees with 1e-11 (at most 2.96). Near
0 the exponent is then good to a few 1/s, which does not decide chaos (5 standard errors, against
exponents of 50-130 1/s at the chaotic points).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

import numpy as np

from . import _core
from ._codes import OUTCOME_NAMES, STATUS, STATUS_NAMES
from ._modes import static
from ._settings import DEFAULTS, Integration, Irregular

_DEF = DEFAULTS.irregular

#: Per-point output: name -> (dtype, units, long name); NaN except at irregular points.
IRREGULAR_VARIABLES: dict[str, tuple[str, str, str]] = {
    "irregular_z_min": ("f8", "m", "minimum of z over the measurement window of irregular motion"),
    "irregular_z_max": ("f8", "m", "maximum of z over the measurement window of irregular motion"),
    "irregular_omega": ("f8", "rad s-1", "dominant angular frequency of z in irregular motion (spectral peak)"),
    "irregular_ftle": ("f8", "s-1", "largest finite-time Lyapunov exponent of irregular motion"),
    "irregular_ftle_se": ("f8", "s-1", "standard error of irregular_ftle (spread of its segments)"),
}


def characteristic_sizes(values: Mapping[str, np.ndarray | float]) -> np.ndarray:
    """Characteristic size of each state component, ``(n, 6)`` [m, m/s, m, m/s, rad, rad/s].

    As the core's ``steady::characteristic_sizes``: ``|z_st|`` for ``z`` and ``x``, ``|z_st|/L``
    for ``phi`` (``|z_st|`` if ``L = 0``), those times the torsional frequency for the rates.
    """
    contact = {k: np.asarray(values[k], dtype=np.float64) for k in ("normal_load", "contact_stiffness", "contact_quadratic")}
    arm = np.asarray(values["moment_arm"], dtype=np.float64)
    w = np.asarray(values["omega_torsion"], dtype=np.float64)
    z = np.abs(static(contact)[0])
    z, arm, w = np.broadcast_arrays(np.atleast_1d(z), arm, w)
    phi = np.where(arm > 0, z / np.where(arm > 0, arm, 1.0), z)
    return np.column_stack([z, z * w, z, z * w, phi, phi * w])


def dominant_omega(z: np.ndarray, dt: float) -> np.ndarray:
    """Dominant angular frequency [rad/s] of each row of ``z`` sampled every ``dt`` seconds.

    The mean is removed, the row is Hann-windowed, and the largest bin of its spectrum (DC
    excluded) is refined by a parabola through the logarithms of the bin and its two neighbours
    (exact for a Gaussian peak; for a Hann window the bias is below 2 % of a bin). A row with no
    variation, or a peak at the edge of the spectrum, gives the unrefined bin or NaN.

    Examples
    --------
    >>> t = np.arange(5000) * 1e-4
    >>> w = float(dominant_omega(np.sin(640.37 * t)[None, :], 1e-4)[0])
    >>> abs(w - 640.37) < 0.03 * 2 * np.pi / 0.5  # within 0.03 of a bin
    True
    """
    z = np.atleast_2d(np.asarray(z, dtype=np.float64))
    n = z.shape[1]
    spec = np.abs(np.fft.rfft((z - z.mean(axis=1, keepdims=True)) * np.hanning(n), axis=1))
    spec[:, 0] = 0.0
    k = np.argmax(spec, axis=1)
    out = np.full(z.shape[0], np.nan)
    for i in range(z.shape[0]):
        if not np.all(np.isfinite(z[i])) or spec[i, k[i]] <= 0:
            continue
        shift = 0.0
        if 1 <= k[i] < spec.shape[1] - 1 and spec[i, k[i] - 1] > 0 and spec[i, k[i] + 1] > 0:
            a, b, c = np.log(spec[i, k[i] - 1 : k[i] + 2])
            den = a - 2.0 * b + c
            shift = 0.5 * (a - c) / den if den < 0 else 0.0
        out[i] = 2.0 * math.pi * (k[i] + shift) / (n * dt)
    return out


#: Intermittent motion's cycle by how it is unstable (the core's instability codes): the
#: mechanism of Pomeau-Manneville's types.
INTERMITTENCY: dict[int, str] = {1: ", real and positive: a fold, Pomeau-Manneville type I",
                                 2: ", real and negative: a flip, Pomeau-Manneville type III",
                                 3: ", a complex pair: a torus, Pomeau-Manneville type II"}  # fmt: skip


def stop_reason(summary: Mapping[str, np.ndarray], i: int, t_max: float, block: int | None = None) -> str:
    """Why run ``i`` of a steady-state summary (the core's ``kind="steady"``) is sustained irregular
    motion: outcome ``irregular`` (stationary over three blocks of sections, of ``block`` sections
    each where given, or intermittent: back near one unstable cycle, between bursts, often
    enough) or ``unsettled`` at ``t_max``."""
    period = float(summary["intermittent_period"][i]) if "intermittent_period" in summary else math.nan
    if OUTCOME_NAMES[int(summary["outcome"][i])] != "irregular":
        return f"bounded motion, neither periodic nor decayed by t_max = {t_max:g} s"
    t_end = float(summary["t_end"][i])
    if math.isfinite(period):
        kind = INTERMITTENCY.get(int(summary["intermittent_instability"][i]), "")
        when = (f"by t = {t_end:.3g} s: intermittent, back near one unstable cycle (period {period:.5g} s, largest "
                f"non-trivial Floquet multiplier modulus {float(summary['intermittent_multiplier'][i]):.4g}{kind}) "
                f"{int(summary['intermittent_visits'][i])} times, leaving it in bursts between")  # fmt: skip
    else:
        size = " of" if block is None else f" of {block}"
        when = f"and stationary over three blocks{size} sections by t = {t_end:.3g} s"
    return f"bounded motion, neither periodic nor decayed {when}"


#: Standard errors from 0 at which a point's exponent is decided (:func:`benettin`'s ``min_segments``).
#: Sequential looks at the mean cost little at this distance: under a true exponent of 0 (rates
#: normal about 0) the looks at 10, 11, ..., 39 segments call 0.13 % of the points decided (a
#: Monte Carlo of 200,000 points; tests/test_irregular.py).
FTLE_DECISIVE = 5.0

#: ``propagate(states (2 m, d), tau, rows (m,)) -> (states (2 m, d), ok (2 m,) bool)``: one batched run of
#: length ``tau`` of the bases and copies of the points ``rows`` (indices into the start states).
Propagator = Callable[[np.ndarray, float, np.ndarray], tuple[np.ndarray, np.ndarray]]


def benettin(
    propagate: Propagator,
    y0: np.ndarray,
    scale: np.ndarray,
    *,
    tau: float = _DEF.ftle_tau,
    segments: int = _DEF.ftle_segments,
    warmup: int = _DEF.ftle_warmup,
    d0: float = _DEF.ftle_d0,
    min_segments: int | None = None,
) -> dict[str, np.ndarray]:
    """Largest finite-time Lyapunov exponent of many trajectories by the two-trajectory method.

    Each base state ``y0[i]`` and a copy displaced by ``d0`` (in units of ``scale[i]``, along the
    fixed direction ``(1, -1, 1, -1, ...)/sqrt(d)``) are propagated together, all pairs of all
    points in one ``propagate`` call per segment; after each segment the separation ``d_k``
    (measured in units of ``scale``) is recorded and the copy pulled back to ``d0``.

    Parameters
    ----------
    propagate : callable
        ``propagate(states, tau, rows) -> (states, ok)`` for ``states`` of shape ``(2 m, d)``: the
        bases of the points ``rows`` (indices into ``y0``), then their copies. A row with ``ok``
        false ends its point.
    y0 : array, (n, d)
        Start states.
    scale : array, (n, d) or (d,)
        Characteristic size of each component (> 0).
    tau, segments, warmup, d0
        Segment length [time units of ``propagate``], averaged segments (>= 2), discarded first
        segments (>= 0) and separation (the ``ftle_*`` fields of :class:`tribosweep._settings.Irregular`).
    min_segments : int, optional
        Averaged segments after which a point whose exponent is already at least
        :data:`FTLE_DECISIVE` standard errors from 0 stops (>= 2, capped at ``segments``;
        default ``segments``: every point runs them all). The others run on, to ``segments`` at
        most.

    Returns
    -------
    dict of str to numpy.ndarray
        ``ftle`` and ``ftle_se`` (NaN where a run failed) [1/time], ``rates`` ``(n, segments)``
        (``ln(d_k/d0)/tau`` of each averaged segment; NaN after a point stopped), ``segments``
        (the averaged segments of each point), ``ok`` (bool) and ``y_end`` ``(n, d)``.
    """
    s = Irregular(ftle_tau=tau, ftle_segments=segments, ftle_warmup=warmup, ftle_d0=d0,
                  ftle_min_segments=segments if min_segments is None else min_segments)  # fmt: skip
    tau, segments, warmup, d0 = s.ftle_tau, s.ftle_segments, s.ftle_warmup, s.ftle_d0
    least = min(s.ftle_min_segments, segments)
    y = np.array(y0, dtype=np.float64, ndmin=2)
    n, dim = y.shape
    scale = np.broadcast_to(np.asarray(scale, dtype=np.float64), (n, dim))
    if not np.all(scale > 0):
        raise ValueError("scale must be > 0 in every component")
    u = np.where(np.arange(dim) % 2 == 0, 1.0, -1.0) / math.sqrt(dim)
    pert = y + d0 * scale * u
    rates = np.full((n, segments), np.nan)
    alive = np.all(np.isfinite(y), axis=1)
    running = alive.copy()
    used = np.zeros(n, dtype=np.int64)
    for k in range(warmup + segments):
        idx = np.flatnonzero(alive & running)
        if idx.size == 0:
            break
        states, ok = propagate(np.concatenate([y[idx], pert[idx]]), tau, idx)
        states = np.asarray(states, dtype=np.float64)
        ok = np.asarray(ok, dtype=bool)
        base, copy = states[: idx.size], states[idx.size :]
        sep = (copy - base) / scale[idx]
        d = np.sqrt(np.sum(sep * sep, axis=1))
        good = ok[: idx.size] & ok[idx.size :] & np.isfinite(d) & (d > 0)
        alive[idx[~good]] = False
        idx, base, sep, d = idx[good], base[good], sep[good], d[good]
        if k >= warmup:
            rates[idx, k - warmup] = np.log(d / d0) / tau
            used[idx] = k - warmup + 1
        y[idx] = base
        pert[idx] = base + (d0 / d)[:, None] * sep * scale[idx]
        m = k - warmup + 1
        if least <= m < segments and idx.size:
            r = rates[idx, :m]
            decided = np.abs(r.mean(axis=1)) > FTLE_DECISIVE * r.std(axis=1, ddof=1) / math.sqrt(m)
            running[idx[decided]] = False
    # Over each point's own segments (NaN after it stopped); every live point has at least 2.
    m = np.maximum(used, 2)
    mean = np.nansum(rates, axis=1) / m
    sd = np.sqrt(np.nansum((rates - mean[:, None]) ** 2, axis=1) / (m - 1))
    ftle = np.where(alive, mean, np.nan)
    se = np.where(alive, sd / np.sqrt(m), np.nan)
    return {"ftle": ftle, "ftle_se": se, "rates": rates, "segments": used, "ok": alive, "y_end": y}


def slider_propagator(
    base: Mapping[str, float],
    contact: str,
    friction_law: str,
    names: list[str],
    values: np.ndarray,
    *,
    integrator: str,
    rtol: float,
    threads: int | None,
    record: dict | None = None,
    window: tuple[np.ndarray, np.ndarray] | None = None,
) -> Propagator:
    """A :data:`Propagator` of the slider at the points ``values`` (rows over ``names``).

    ``record``, when given, accumulates ``n_rhs`` (array over the rows of ``values``) and the first
    failure of each row (``record["failure"]``: row -> status name).

    ``window``, when given, is ``(t, z)``: times from the start of the first call (ascending, from
    0) and an array ``(rows of values, t.size)`` into which the bases' ``z`` at those times is
    written. The calls are taken as consecutive segments of one length (as :func:`benettin` makes
    them); a call whose segment holds some of the times samples its runs there, on the
    integrator's interpolant, which moves none of its steps.
    """
    base = {k: float(v) for k, v in base.items()}
    values = np.asarray(values, dtype=np.float64)
    calls = [0]

    def propagate(states: np.ndarray, tau: float, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        k = calls[0]
        calls[0] += 1
        both = np.concatenate([rows, rows])
        # The samples of segment k: floor(t / tau) = k (one at a segment's end is the next one's start).
        here = np.flatnonzero(np.floor(window[0] / tau + 1e-9) == k) if window is not None else np.empty(0, int)
        kw = {"kind": "final"}
        if here.size:
            kw = {"kind": "sampled", "t_eval": np.ascontiguousarray(np.clip(window[0][here] - k * tau, 0.0, tau))}
        res = _core.ensemble(base, contact, friction_law, names, np.ascontiguousarray(values[both]),
                             np.ascontiguousarray(states, dtype=np.float64), float(tau), integrator, float(rtol),
                             threads=threads, **kw)  # fmt: skip
        status = np.asarray(res["status"])
        ok = status == STATUS["success"]
        if here.size:
            window[1][np.ix_(rows, here)] = np.asarray(res["y"])[: rows.size, :, 0]
        if record is not None:
            np.add.at(record["n_rhs"], both, np.asarray(res["n_rhs"], dtype=np.int64))
            for r, st in zip(both[~ok], status[~ok]):
                record["failure"].setdefault(int(r), STATUS_NAMES[int(st)])
        return np.asarray(res["y_end"]), ok

    return propagate


def measure(
    base: Mapping[str, float],
    contact: str,
    friction_law: str,
    point_params: Mapping[str, np.ndarray],
    sel: np.ndarray,
    y_start: np.ndarray,
    *,
    integration: Integration = DEFAULTS.integration,
    settings: Irregular = _DEF,
    threads: int | None = None,
) -> dict[str, np.ndarray]:
    """Measure the irregular motion of the points ``sel`` from their states ``y_start``.

    Parameters
    ----------
    base, contact, friction_law, point_params
        As a sweep chunk's (``tribosweep._chunk.compute_chunk``).
    sel : int array, (m,)
        The points to measure.
    y_start : array, (m, 6)
        Their states where the transient ended.
    integration : Integration
        The runs' integrator (their tolerance is the settings' own ``ftle_rtol``: the window is
        sampled on the exponent's runs).
    settings : Irregular
        Measurement settings.
    threads : int, optional
        Rust threads.

    Returns
    -------
    dict of str to numpy.ndarray, each of length m
        ``IRREGULAR_VARIABLES``, ``status`` (uint8: success, or the first failure), ``reason``
        (empty or what failed) and ``n_rhs``.
    """
    s = settings
    integrator = integration.integrator
    sel = np.asarray(sel, dtype=np.int64)
    m = sel.size
    out = {k: np.full(m, np.nan) for k in IRREGULAR_VARIABLES}
    out["status"] = np.full(m, STATUS["success"], dtype=np.uint8)
    out["reason"] = np.full(m, "", dtype=object)
    out["n_rhs"] = np.zeros(m, dtype=np.int64)
    if m == 0:
        out["reason"] = out["reason"].astype(str)
        return out
    names = sorted(point_params)
    values = np.column_stack([np.asarray(point_params[k], dtype=np.float64)[sel] for k in names])
    n_all = len(next(iter(point_params.values())))
    full = {k: np.full(n_all, float(v)) for k, v in base.items()}
    for k, a in point_params.items():
        full[k] = np.asarray(a, dtype=np.float64)
    scale = characteristic_sizes({k: np.asarray(v)[sel] for k, v in full.items()})

    # The exponent's runs, every point's pair in one call per segment, from the transient's end
    # state; the bases' first segments sample z: the measurement window (one run of the base
    # trajectory serves both; a separate window took 5 % of the Stribeck sweep's right-hand sides).
    # A point runs until its window is sampled, whatever its exponent decided.
    n_samples = int(math.floor(s.window / s.sample_dt + 1e-9)) + 1
    t_eval = np.arange(n_samples) * s.sample_dt
    spans = int(math.floor(t_eval[-1] / s.ftle_tau + 1e-9)) + 1 - s.ftle_warmup
    segments = max(s.ftle_segments, spans)
    z = np.full((m, n_samples), np.nan)
    record = {"n_rhs": np.zeros(m, dtype=np.int64), "failure": {}}
    propagate = slider_propagator(base, contact, friction_law, names, values, integrator=integrator,
                                  rtol=s.ftle_rtol, threads=threads, record=record, window=(t_eval, z))  # fmt: skip
    res = benettin(propagate, np.asarray(y_start, dtype=np.float64), scale, tau=s.ftle_tau, segments=segments,
                   warmup=s.ftle_warmup, d0=s.ftle_d0, min_segments=max(s.ftle_min_segments, spans))  # fmt: skip
    out["n_rhs"] += record["n_rhs"]
    win = np.all(np.isfinite(z), axis=1)
    ok = win & res["ok"]
    for i in np.flatnonzero(~ok):
        st = record["failure"].get(int(i), "non_finite")
        out["status"][i] = STATUS[st]
        what = "the Lyapunov-exponent runs" if win[i] else "the measurement window"
        out["reason"][i] = f"irregular motion: {what} failed ({st})"
    if ok.any():
        out["irregular_z_min"][ok] = z[ok].min(axis=1)
        out["irregular_z_max"][ok] = z[ok].max(axis=1)
        # The spectrum over the half-open window [0, window), the DFT's own period: its first
        # n - 1 samples (by default 5000 of 5001; 5001 has the prime factor 1667, which took
        # numpy's FFT 4.1 ms for the Stribeck sweep's 31 rows against 1.4 ms).
        out["irregular_omega"][ok] = dominant_omega(z[ok][:, : n_samples - 1], s.sample_dt)
        out["irregular_ftle"][ok] = res["ftle"][ok]
        out["irregular_ftle_se"][ok] = res["ftle_se"][ok]
    out["reason"] = out["reason"].astype(str)
    return out
