"""Two-parameter curves of special points of periodic orbits: folds of cycles, grazing, and the
onset of sticking (the switch law's cycles first reaching the stick band).

Slice by slice: at each value of the second parameter the one-parameter branch
(:mod:`tribosweep._branch`) locates the special point in the first. Model fields are sliced in the
core (``_core.special_curve``), carrying the orbit from slice to slice; the arm length, which moves
three natural frequencies at once through the apparatus model, is sliced here.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import threading
from collections.abc import Mapping

import numpy as np
import xarray as xr

from . import _checks, _core
from ._branch import (
    _INT_OPTIONS,
    BRANCH_FLAG_NAMES,
    DEFAULTS,
    POINT_TYPE_NAMES,
    _dataset,
    _finite,
    _hopf,
    _model,
    _options,
    _orbit,
    _parameter,
)  # fmt: skip
from ._model import PARAM_LONG_NAMES, PARAM_UNITS, SliderModel


def _axis(model: SliderModel, axis, arg: str, arm: bool = False) -> tuple[str, float, float]:
    try:
        name, lo, hi = axis
    except (TypeError, ValueError):
        raise ValueError(f"{arg} = {axis!r} must be (parameter name, low, high)") from None
    if not (arm and name == "arm_length"):
        name = _parameter(name, f"{arg}[0]")
    lo, hi = _finite(f"{arg}[1]", lo), _finite(f"{arg}[2]", hi)
    if not lo < hi:
        raise ValueError(f"{arg} = {axis!r}: must have low < high")
    if name == "arm_length" and not lo > 0:
        raise ValueError(f"{arg} = {axis!r}: arm lengths must be > 0 [m]")
    return name, lo, hi


class Stopped(Exception):
    """A curve's computation was stopped by its caller's ``stop`` event (the caller raises its own error)."""


def _first_hit(kind: str, out: dict) -> int | None:
    """Index of the first ``kind`` point of a raw branch (a fold: smooth, or a grazing where the
    branch turns back), or None."""
    types = np.asarray(out["point_type"])
    hits = types == POINT_TYPE_NAMES.index(kind)
    if kind == "fold":
        turns = 1 << BRANCH_FLAG_NAMES.index("parameter_turns")
        hits |= (types == POINT_TYPE_NAMES.index("grazing")) & ((np.asarray(out["flags"]) & turns) != 0)
    return int(np.argmax(hits)) if hits.any() else None


class SharedBranches:
    """One branch per arm length and Hopf point for the fold, grazing and stick curves of one
    switch-law box.

    Under the switch law every branch from a Hopf point ends at its first stick point, and up to
    its end a branch does not depend on the point type it is asked to stop at (``stop_at``), but
    for being cut there: the fold curve's branch is the stick curve's, cut at its first fold.
    :func:`_arm_curve` asks here for each branch it needs, keyed by (arm length, Hopf value, Hopf
    frequency) (:meth:`fetch`): the first kind to ask runs its own and stores it, a kind that asks
    while it runs waits for it, and a kind reads its first point off a stored branch where
    :meth:`holds` says that is the point its own branch would locate, to the last bit; elsewhere
    it runs its own. The stick curve runs first: the fold and grazing curves read their slices off
    its branches, and each other's end bisections where the two end at the same arm lengths. The
    Hopf points of each arm length are found once for all the curves too (:meth:`hopf`).

    The grazing curve follows its branches with the bilateral law (:func:`grazing_curve`). A
    unilateral branch is the bilateral one, bit for bit, for as long as it keeps the contact closed
    (it flows the same contact segment, and the bilateral law's test for a grazing, ``min_gap``
    changing sign between two orbits, stays quiet while every orbit is valid): so a branch of either
    law with no grazing point is the other's, which ends where it ends, with the same reason. One
    with a grazing point is not (the unilateral law changes its mode sequence there).
    """

    def __init__(self, contact: str) -> None:
        self._lock = threading.Lock()
        self._runs: dict[tuple[float, float, float], tuple[str, dict]] = {}
        self._pending: dict[tuple[float, float, float], concurrent.futures.Future] = {}
        self._contact = contact
        self._hopf: dict[float, tuple[np.ndarray, np.ndarray]] = {}

    def hopf(self, y: float, find):
        """The Hopf points at arm length ``y``: ``find(y)``, once for all the curves."""
        with self._lock:
            got = self._hopf.get(y)
        if got is None:
            got = find(y)
            with self._lock:
                got = self._hopf.setdefault(y, got)
        return got

    def _law(self, kind: str) -> str:
        return "bilateral" if kind == "grazing" else self._contact

    def holds(self, kind: str, src: str, out: dict) -> bool:
        """Whether ``kind``'s own branch is ``out`` (``src``'s, stopped at its first ``src`` point)
        up to ``kind``'s first point, or to its end where it has none."""
        if out.get("static_scales") and kind != src:
            # Run again on the static scales after a failure further on (``_core.branch``): a
            # branch stopped before that failure keeps the critical mode's scales.
            return False
        grazes = bool((np.asarray(out["point_type"]) == POINT_TYPE_NAMES.index("grazing")).any())
        if grazes and self._law(src) != self._law(kind):
            return False
        # A stop at a stick point is the branch's own end; any other stop cut it short there.
        cut = src != "stick" and _first_hit(src, out) is not None
        return not cut or _first_hit(kind, out) is not None

    def fetch(self, kind: str, key: tuple[float, float, float], run):
        """``kind``'s branch at ``key``: read off the one stored (or running) there where it
        :meth:`holds`, else ``run()`` (stored if first). Read ones count no work (their kind did)."""
        with self._lock:
            got = self._runs.get(key)
            fut = None if got is not None else self._pending.get(key)
            first = got is None and fut is None
            if first:
                fut = self._pending[key] = concurrent.futures.Future()
        if got is None and not first:
            try:
                got = _result(fut)
            except Exception:  # noqa: BLE001 - its kind failed or was stopped: run our own
                got = None
        if got is not None and self.holds(kind, *got):
            return got[1] | {"n_flows": 0, "n_rhs": 0}
        try:
            out = run()
        except BaseException as e:
            if first:
                with self._lock:
                    del self._pending[key]
                fut.set_exception(e)
            raise
        if first:
            with self._lock:
                self._runs[key] = (kind, out)
                del self._pending[key]
            fut.set_result((kind, out))
        return out


def _workers(threads: int | None) -> int:
    """Threads for independent continuations: ``threads``, or the core's default."""
    return _checks.default_threads() if threads is None else threads


def _curve(kind: str, model, x, y, n, orbit, from_hopf, start, direction, options, threads=None,
           stop: threading.Event | None = None, shared: SharedBranches | None = None,
           slots: threading.Semaphore | None = None) -> xr.Dataset:  # fmt: skip
    model = _model(model)
    threads = _checks.threads(threads)
    (xn, x_lo, x_hi), (yn, y_lo, y_hi) = _axis(model, x, "x"), _axis(model, y, "y", arm=True)
    if xn == yn:
        raise ValueError(f"x and y are both {xn!r}: must be two different parameters")
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 2 <= n <= 10_000:
        raise ValueError(f"n = {n!r} is out of range: must be an integer in [2, 10000]")
    if (from_hopf is None) == (orbit is None):
        raise ValueError("give exactly one of from_hopf and orbit")
    if kind == "stick":
        _checks.switch_law("a stick curve", model.friction_law)
    opts = _options(options)
    if model.friction_law == "switch":
        opts.setdefault("max_points", SWITCH_MAX_POINTS)
    if yn == "arm_length":
        if orbit is not None:
            return _arm_orbit_curve(kind, model, (xn, x_lo, x_hi), (y_lo, y_hi), n, orbit, start, direction, opts)
        return _arm_curve(kind, model, (xn, x_lo, x_hi), (y_lo, y_hi), n, from_hopf, start, opts, threads, stop,
                          shared, slots)  # fmt: skip
    y_model = float(getattr(model, yn))
    if not y_lo <= y_model <= y_hi:
        raise ValueError(f"y = {y!r}: the model's {yn} = {y_model} (where the start orbit is) must lie within it")
    kw: dict = {}
    if from_hopf is not None:
        x_value, omega = _hopf(model, xn, from_hopf, x_lo if start is None else start, x_lo, x_hi)
        kw["hopf_omega"] = omega
    else:
        x_value = float(getattr(model, xn)) if start is None else _finite("start", start)
        y0, period = _orbit(orbit)
        kw.update(y0=y0, period=period, direction=1.0 if direction is None else float(np.sign(_finite("direction", direction)) or 1.0))
    if not x_lo <= x_value <= x_hi:
        raise ValueError(f"start = {x_value!r} is out of range: must be within x bounds [{x_lo}, {x_hi}]")
    grid = np.linspace(y_lo, y_hi, n)
    halves = [np.concatenate([[y_model], grid[grid > y_model]]), np.concatenate([[y_model], grid[grid < y_model][::-1]])]
    base = model.replace(**{xn: x_value}).values()
    parts, reasons, status, flows, rhs = [], [], 0, 0, 0
    for ys in halves:
        if ys.size < 2 and parts:
            continue
        out = _core.special_curve(base, model.contact, model.friction_law, kind, xn, x_value, x_lo, x_hi, yn,
                                  np.ascontiguousarray(ys, dtype=np.float64), options=opts, **kw)  # fmt: skip
        parts.append(out)
        reasons.append(str(out["reason"]))
        status = max(status, int(out["status"]))
        flows, rhs = flows + int(out["n_flows"]), rhs + int(out["n_rhs"])
    order_keys = [k for k, val in parts[0].items() if isinstance(val, np.ndarray)]
    merged = {k: np.concatenate([p[k][1:] if i else p[k] for i, p in enumerate(parts)]) for k in order_keys}
    idx = np.argsort(merged["y"], kind="stable")
    merged = {k: val[idx] for k, val in merged.items()}
    merged["status"] = status
    attrs = {"kind": kind, "x": xn, "y": yn, "x_units": PARAM_UNITS[xn], "y_units": PARAM_UNITS[yn],
             "x_bounds_low": x_lo, "x_bounds_high": x_hi, "y_low": y_lo, "y_high": y_hi, "n": int(n),
             "method": "slice by slice: the special point located in x by the one-parameter branch at each y",
             "reason": " | ".join(reasons), "contact": model.contact, "friction_law": model.friction_law,
             "n_flows": flows, "n_rhs": rhs}  # fmt: skip
    if kind == "grazing":
        attrs["comment"] = ("the contact side's grazing (the pin first leaves the disk), followed with the bilateral law, "
                            "on which that orbit is the same")  # fmt: skip
    attrs |= {f"continuation_{k}": (int(v) if k in _INT_OPTIONS else v) for k, v in (DEFAULTS | opts).items()}
    ds = _dataset(merged, "curve_point", xn, attrs)
    ds = ds.rename({"parameter": xn})
    ds[yn] = (("curve_point",), merged["y"], {"units": PARAM_UNITS[yn], "long_name": f"{yn}: {PARAM_LONG_NAMES[yn]}"})
    return ds


#: Under the switch law a curve's branches end at this many points unless ``max_points`` is given
#: (the branch's own default is 1000). On the way to sticking the cycle's motion along the friction
#: direction grows to about ``V / omega`` (0.2 m/s at 400 rad/s: 5e-4 m, some 50 times the static
#: compression); on the static scales a branch took 400-1000 orbits to its stick point, and 1000
#: ended the 6.4 and 12.7 cm slices of the issue-10 box before it. Branches from a Hopf point now
#: scale the friction direction by the critical mode's motion (52-63 orbits where nothing happens on
#: the way, 240-870 through the cascades of special points at 6-6.6 cm), but one that
#: fails runs again on the static scales, which this bound must let finish.
SWITCH_MAX_POINTS: int = 5000

#: Bisections of the arm length where a curve leaves the window between two slices (see :func:`_arm_curve`).
_ARM_END_BISECTIONS: int = 4
#: Per-point arrays of a raw branch (``_core.branch``) and their trailing shapes.
_RAW_KEYS: dict[str, tuple[tuple[int, ...], str]] = {
    **{k: ((), "f8") for k in ("parameter", "period", "trivial_error", "a0", "a1", "z_max", "z_min", "min_gap",
                                "min_law_force", "min_slip_velocity", "fraction_off_disk", "dp_ds", "arclength",
                                "residual")},
    **{k: ((), "u1") for k in ("n_unstable", "point_type", "contact", "flags", "trivial")},
    "stable": ((), "?"), "n_switches": ((), "u4"), "newton_iterations": ((), "u4"),
    **{k: ((6,), "f8") for k in ("state0", "multipliers_re", "multipliers_im")},
}  # fmt: skip


def _nearest(hopfs: tuple[np.ndarray, np.ndarray], near: float) -> tuple[float, float]:
    """The Hopf point of ``hopfs`` (values, frequencies) nearest ``near``: (value, frequency)."""
    values, omegas = hopfs
    i = int(np.argmin(np.abs(values - near)))
    return float(values[i]), float(omegas[i])


#: The main thread waits for a pool's futures in slices this long [s]: a SIGINT that the kernel
#: delivers to another thread (any thread may get a process-directed signal) wakes no blocked
#: wait, and Python runs its handler only once the main thread is back in the interpreter. A wait
#: without a timeout then held Ctrl-C back until the whole computation ended (10.4 s, seen once in
#: test_cancel's boundary_curves case).
WAIT_SLICE: float = 0.05


def _result(fut: concurrent.futures.Future):
    """``fut.result()``, waited for in :data:`WAIT_SLICE` slices so that Ctrl-C reaches the main thread."""
    while True:
        try:
            return fut.result(timeout=WAIT_SLICE)
        except concurrent.futures.TimeoutError:
            continue


def _slices_in_order(ys, hopfs, target: float, run, take, workers: int) -> list[tuple[float, dict | None, str]]:
    """:func:`_arm_curve`'s slices, each from the Hopf point nearest the last point found, with the
    branches on ``workers`` threads: ``(y, point or None, why)`` per slice, as a loop in order gives.

    ``hopfs[k]``: slice ``k``'s Hopf points (values, frequencies); ``run(y, h, omega)`` the branch
    from one (the expensive part, on the threads); ``take(y, h, result)`` its point (a dict with
    ``"hopf"``) or None, and why not. Each slice's Hopf point is first guessed as if every slice
    before it found its point (the usual case) and all guesses run at once; then, in order, each
    slice takes the point the slices before it really lead to, and a guess that proves wrong runs
    again with it. So the result does not depend on ``workers``.
    """
    guess, near = [], target
    for hp in hopfs:
        guess.append(_nearest(hp, near) if hp[0].size else None)
        near = guess[-1][0] if guess[-1] else near
    pool = concurrent.futures.ThreadPoolExecutor(max_workers=workers)
    try:
        runs = [pool.submit(run, yv, *g) if g else None for yv, g in zip(ys, guess)]
        slices: list[tuple[float, dict | None, str]] = []
        for yv, hp, g, fut in zip(ys, hopfs, guess, runs):
            if not hp[0].size:
                slices.append((float(yv), None, "no Hopf point"))
                continue
            h, omega = _nearest(hp, target)
            pt, why = take(yv, h, _result(fut) if (h, omega) == g else run(yv, h, omega))
            if pt is not None:
                target = pt["hopf"]
            slices.append((float(yv), pt, why))
    finally:
        # Guesses proved wrong may still be queued (or, on an exception or Ctrl-C, every slice).
        pool.shutdown(wait=True, cancel_futures=True)
    return slices


def _arm_curve(kind: str, model: SliderModel, xspec, yspan, n: int, from_hopf, start, opts, threads=None,
               stop: threading.Event | None = None, shared: SharedBranches | None = None,
               slots: threading.Semaphore | None = None) -> xr.Dataset:  # fmt: skip
    """:func:`fold_curve` / :func:`grazing_curve` over the arm length: each slice from its own Hopf point.

    The arm length moves the three natural frequencies at once (``arm_frequencies``, the model's
    own at ``L_SEED``). Here no orbit is carried between slices (:func:`_arm_orbit_curve` does
    that, from a given orbit): at each of ``n`` arm lengths the Hopf points of ``x`` in its window are found (:func:`sliding_branch`), the one nearest the
    previous slice's is taken (the first: nearest ``from_hopf``'s value, or ``start``, or the low
    end of ``x``), and the branch from it runs to its first ``kind`` point, as ``branch(...,
    from_hopf=value, stop_at=kind)`` does. A slice with no Hopf point in the window, or whose
    branch leaves the window first, has no point: the curve has left the box there, and between
    such a slice and its neighbour with a point the arm length is bisected ``_ARM_END_BISECTIONS``
    times, so that the curve reaches to 1/16 of a slice spacing from where it leaves the window.

    The slices' branches run on ``threads`` threads (None: one per core) before their Hopf points
    are known for certain: each slice's is guessed as if every earlier slice found its point, and a
    slice whose guess proves wrong once the earlier results are in runs again with the right one. So
    the curve is the one the slices give in order, bit for bit, whatever the thread count. ``stop``
    set (by another thread) ends the curve at its next branch with :class:`Stopped`. ``shared``
    (switch law, the curves of one box): the branches the curves lend each other, the stick curve's
    first (:class:`SharedBranches`); work counts only the branches a curve runs itself.
    ``slots``: at most that many branches run at once, across the curves that share it.
    """
    from ._hopf import sliding_branch

    xn, x_lo, x_hi = xspec
    if isinstance(from_hopf, Mapping):
        target = _finite(f"from_hopf[{xn!r}]", from_hopf.get(xn))
    elif from_hopf is True:
        target = x_lo if start is None else _finite("start", start)
    else:
        target = _finite("from_hopf", from_hopf)
    ys = np.linspace(*yspan, n)
    at = _arm_models(model, xn, yspan, ys)
    contact = "bilateral" if kind == "grazing" else model.contact
    work = {"status": 0, "n_flows": 0, "n_rhs": 0}
    counting = threading.Lock()

    def find_hopf(yv: float) -> tuple[np.ndarray, np.ndarray]:
        sb = sliding_branch(at(yv), (xn, x_lo, x_hi))
        ok = (sb.is_hopf.values == 1) & (sb.hopf_status.values == 0)
        return sb[f"hopf_{xn}"].values[ok], sb.hopf_frequency.values[ok]

    def hopf_points(yv: float) -> tuple[np.ndarray, np.ndarray]:
        """The Hopf points of ``x`` in the window at arm length ``yv`` and their frequencies."""
        return find_hopf(yv) if shared is None else shared.hopf(float(yv), find_hopf)

    def branch_from(yv: float, h: float, omega: float) -> dict:
        def own() -> dict:
            if stop is not None and stop.is_set():
                raise Stopped
            m = at(yv)
            with slots if slots is not None else contextlib.nullcontext():
                if stop is not None and stop.is_set():
                    raise Stopped
                return _core.branch(m.replace(**{xn: h}).values(), contact, m.friction_law, xn, h, x_lo, x_hi,
                                    hopf_omega=omega, options=opts, stop_at=kind)  # fmt: skip

        return own() if shared is None else shared.fetch(kind, (float(yv), float(h), float(omega)), own)

    def take(yv: float, h: float, out: dict) -> tuple[dict | None, str]:
        """A slice's branch result as its first ``kind`` point, or None and why not; counts its work.
        (A branch of its own stops there; one shared with the stick curve goes on to its stick point.)
        The ends' bisections call it from their threads: the counts are sums and maxima, in any order."""
        i = _first_hit(kind, out)
        with counting:
            work["n_flows"] += int(out["n_flows"])
            work["n_rhs"] += int(out["n_rhs"])
            if i is None:
                work["status"] = max(work["status"], int(out["status"]))
        if i is None:
            return None, str(out["reason"])
        return {k: out[k][i] for k in _RAW_KEYS} | {"y": float(yv), "hopf": h}, ""

    def slice_at(yv: float, near: float) -> tuple[dict | None, str]:
        """The ``kind`` point at arm length ``yv`` from the Hopf point nearest ``near``, or None and why not."""
        hopfs = hopf_points(yv)
        if hopfs[0].size == 0:
            return None, "no Hopf point"
        h, omega = _nearest(hopfs, near)
        return take(yv, h, branch_from(yv, h, omega))

    workers = _workers(threads)
    slices = _slices_in_order(ys, [hopf_points(yv) for yv in ys], target, branch_from, take, workers)

    def bisect_end(y_in: float, p_in: dict, y_out: float) -> list[dict]:
        """The points found bisecting ENDS times between a slice with a point and one without."""
        got = []
        for _ in range(_ARM_END_BISECTIONS):
            ym = 0.5 * (y_in + y_out)
            pm, _ = slice_at(ym, p_in["hopf"])
            if pm is None:
                y_out = ym
            else:
                y_in, p_in = ym, pm
                got.append(pm)
        return got

    # Where the curve leaves the window between two slices (a slice without a point next to one
    # with), bisect the arm length ENDS times: the curve reaches to 1/2^ENDS of a slice from its end.
    # Each end's bisections depend on nothing but its two slices: the ends run at once.
    chains = []
    for (ya, pa, _), (yb, pb, _) in zip(slices[:-1], slices[1:]):
        if (pa is None) != (pb is None):
            chains.append((ya, pa, yb) if pa is not None else (yb, pb, ya))
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, min(workers, len(chains)))) as pool:
        runs = [pool.submit(bisect_end, *c) for c in chains]
        try:
            ends = [pt for run in runs for pt in _result(run)]
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
    found = sorted([pt for _, pt, _ in slices if pt is not None] + ends, key=lambda f: f["y"])
    gaps = [f"{yv:.6g} ({why})" for yv, pt, why in slices if pt is None]
    reason = f"{n - len(gaps)} of {n} arm lengths located their {kind} point"
    if ends:
        reason += f" ({len(ends)} more where the curve leaves the window, by bisection)"
    if gaps:
        reason += "; none at arm_length = " + ", ".join(gaps)
    method = ("slice by slice over the arm length (natural frequencies by the apparatus power laws, the model's own "
              "at 0.072 m): at each, the branch from the Hopf point of x nearest the previous slice's, to its first "
              "special point")  # fmt: skip
    ds = _arm_dataset(kind, model, xspec, ys, found, work, reason, method, contact, opts)
    ds[f"hopf_{xn}"] = (("curve_point",), np.array([f["hopf"] for f in found], dtype=np.float64),
                        {"units": PARAM_UNITS[xn], "long_name": f"the Hopf point of {xn} the slice's branch starts at"})  # fmt: skip
    return ds


#: Halvings of a slice step whose orbit did not converge, before the curve is declared ended there.
_ARM_STEP_HALVINGS: int = 3
#: A change of the special point (its ``x`` or A1) between neighbouring slices above this fraction is
#: bisected to tell a steep stretch of the curve from a jump (see ``_arm_orbit_curve``).
_ARM_JUMP: float = 0.02


def _arm_orbit_curve(kind: str, model: SliderModel, xspec, yspan, n: int, orbit, start, direction,
                     opts) -> xr.Dataset:  # fmt: skip
    """:func:`fold_curve` / :func:`grazing_curve` over the arm length from a given orbit, carried slice to slice.

    The orbit belongs to ``model`` at its own arm length (``L_SEED``, 0.072 m: the model's natural
    frequencies) and at ``x = start``: the anchor. At every slice the branch starts at the anchor's
    ``x`` from the previous slice's anchor orbit (Newton corrects it to the new arm length; if it
    does not converge, the slice is reached in halved steps, ``_ARM_STEP_HALVINGS``) and runs to
    its first ``kind`` point. A fold is the first turning point of the family seen from the anchor,
    smooth or a grazing turn: the edge of the family's existence. Where the point moves by more than
    ``_ARM_JUMP`` between neighbours, the step is bisected: on a continuous curve the change halves
    with the step, across a jump (another fold of the branch comes first, as past a cusp) it does
    not; a jump is located to 1/16 of the step and a new ``segment`` begins. The curve ends
    where a slice finds no such point in the window or no anchor orbit, located by bisection
    (``_ARM_END_BISECTIONS``).
    """
    from ._apparatus import L_SEED

    xn, x_lo, x_hi = xspec
    if not yspan[0] <= L_SEED <= yspan[1]:
        raise ValueError(f"y = ('arm_length', {yspan[0]}, {yspan[1]}): must contain the model's own arm length "
                         f"{L_SEED} m, where the orbit is")  # fmt: skip
    x0 = float(getattr(model, xn)) if start is None else _finite("start", start)
    if not x_lo <= x0 <= x_hi:
        raise ValueError(f"start = {x0!r} is out of range: must be within x bounds [{x_lo}, {x_hi}]")
    y0, period = _orbit(orbit)
    d0 = 1.0 if direction is None else float(np.sign(_finite("direction", direction)) or 1.0)
    ys = np.linspace(*yspan, n)
    at = _arm_models(model, xn, yspan, ys)
    work = {"status": 0, "n_flows": 0, "n_rhs": 0}
    turns = 1 << BRANCH_FLAG_NAMES.index("parameter_turns")
    status_of_first = 0

    def run(yv: float, state, per: float) -> tuple[dict | None, str, bool]:
        """(branch at ``yv`` from the anchor to its ``kind`` point, or None; why not; Newton failed)."""
        m = at(yv)
        out = _core.branch(m.replace(**{xn: x0}).values(), model.contact, m.friction_law, xn, x0, x_lo, x_hi,
                           y0=np.ascontiguousarray(state, dtype=np.float64), period=float(per), direction=d0,
                           options=opts, stop_at=kind)  # fmt: skip
        work["n_flows"] += int(out["n_flows"])
        work["n_rhs"] += int(out["n_rhs"])
        if not len(out["parameter"]):
            nonlocal status_of_first
            status_of_first = status_of_first or int(out["status"])
            return None, str(out["reason"]), True
        last, flags = int(out["point_type"][-1]), int(out["flags"][-1])
        if last == POINT_TYPE_NAMES.index(kind) or (
                kind == "fold" and last == POINT_TYPE_NAMES.index("grazing") and flags & turns):  # fmt: skip
            return out, "", False
        return None, f"no {kind} point in the x window ({out['reason']})", False

    def reach(prev: dict, prev_y: float, yv: float) -> tuple[list[tuple[float, dict]], str]:
        """Branches at ``yv`` (and any halved steps before it) from ``prev``; empty and why if it ends."""
        got: list[tuple[float, dict]] = []
        for h in range(_ARM_STEP_HALVINGS + 1):
            target = prev_y + (yv - prev_y) / 2**h
            out, why, newton = run(target, prev["state0"][0], float(prev["period"][0]))
            if out is not None:
                got.append((target, out))
                if target == yv:
                    return got, ""
                more, why = reach(out, target, yv)
                return got + more, why
            if not newton:
                return got, why
        return got, why

    def point(out: dict, yv: float, seg: int) -> dict:
        return {k: out[k][-1] for k in _RAW_KEYS} | {"y": float(yv), "segment": seg}

    def gap(a: dict, b: dict) -> float:
        """Relative change of the special point (its x and its A1) from branch ``a`` to branch ``b``."""
        return max(abs(float(b[k][-1]) - float(a[k][-1])) / max(abs(float(a[k][-1])), abs(float(b[k][-1])), 1e-300)
                   for k in ("parameter", "a1"))  # fmt: skip

    def settle(a: dict, y_a: float, b: dict, y_b: float) -> tuple[list[tuple[float, dict]], tuple[float, float] | None,
                                                                  str]:  # fmt: skip
        """Bisect a large change between neighbours: the points found, and the bracket if it is a jump.

        On a continuous curve the change halves with the step; a jump (another special point comes
        first) keeps its size. A jump: still more than 4 times the halved change after the bisections.
        """
        d0, pts = gap(a, b), []
        for _ in range(_ARM_END_BISECTIONS):
            ym = 0.5 * (y_a + y_b)
            om, _w, _nf = run(ym, a["state0"][0], float(a["period"][0]))
            if om is None:  # continuity not shown: a new segment
                return pts, (y_a, y_b), f"continuity not shown: no orbit of the family at arm_length {ym:.6g} m"
            pts.append((ym, om))
            if gap(a, om) >= gap(om, b):
                b, y_b = om, ym
            else:
                a, y_a = om, ym
        is_jump = gap(a, b) > 4.0 * d0 / 2 ** len(pts)
        return pts, ((y_a, y_b) if is_jump else None), f"another {kind} comes first"

    out, why, _n = run(L_SEED, y0, period)
    found: list[dict] = []
    notes: list[str] = []
    segments = 0
    if out is None:
        work["status"] = max(work["status"], status_of_first)
        notes.append(f"the branch from the orbit at arm_length {L_SEED} m found no {kind} point ({why})")
    else:
        found.append(point(out, L_SEED, 0))
        for side in (ys[ys > L_SEED], ys[ys < L_SEED][::-1]):
            prev, prev_y, seg = out, L_SEED, 0
            for yv in side:
                got, why = reach(prev, prev_y, float(yv))
                for y_new, o_new in got:
                    seg_new = seg
                    if gap(prev, o_new) > _ARM_JUMP:
                        pts, bracket, what = settle(prev, prev_y, o_new, y_new)
                        if bracket is not None:
                            segments += 1
                            seg_new = segments if y_new > L_SEED else -segments
                            y_j = 0.5 * sum(bracket)
                            notes.append(f"jumps between arm_length {min(bracket):.6g} and {max(bracket):.6g} m "
                                         f"({what}; at {float(y_new):.6g} m it is at {xn} = "
                                         f"{float(o_new['parameter'][-1]):.6g})")  # fmt: skip
                        for ym, om in pts:
                            before = bracket is None or (ym - y_j) * (y_new - prev_y) < 0
                            found.append(point(om, ym, seg if before else seg_new))
                    found.append(point(o_new, y_new, seg_new))
                    prev, prev_y, seg = o_new, y_new, seg_new
                if why:
                    y_in, y_out = prev_y, float(yv)
                    for _ in range(_ARM_END_BISECTIONS):
                        ym = 0.5 * (y_in + y_out)
                        o_m, why_m, _nf = run(ym, prev["state0"][0], float(prev["period"][0]))
                        if o_m is None:
                            y_out, why = ym, why_m
                        else:
                            prev, y_in = o_m, ym
                            found.append(point(o_m, ym, seg))
                    notes.append(f"ends between arm_length {min(y_in, y_out):.6g} and {max(y_in, y_out):.6g} m: {why}")
                    break
    found.sort(key=lambda f: f["y"])
    seg_values = np.array([f["segment"] for f in found], dtype=np.int64)
    on_grid = sum(any(f["y"] == y for f in found) for y in ys)
    reason = (f"{on_grid} of {n} arm lengths located their {kind} point, {len(found) - on_grid} more in between "
              "(the model's own arm length, halved steps, bisections)")  # fmt: skip
    if notes:
        reason += "; the curve " + "; ".join(notes)
    method = ("slice by slice over the arm length (natural frequencies by the apparatus power laws, the model's own "
              f"at 0.072 m): at each, the branch from the given orbit's family at {xn} = {x0:.6g} (carried from the "
              f"previous slice) to its first {kind} point")  # fmt: skip
    ds = _arm_dataset(kind, model, xspec, ys, found, work, reason, method, model.contact, opts)
    # Segments renumbered 0, 1, ... in arm-length order: the curve is continuous within one.
    _, seg_order = np.unique(seg_values, return_inverse=True)
    ds["segment"] = (("curve_point",), seg_order.ravel().astype(np.int64),
                     {"units": "1", "long_name": "continuous piece of the curve (it jumps between pieces)"})  # fmt: skip
    return ds


def _arm_models(model: SliderModel, xn: str, yspan, ys):
    """``at(arm_length) -> SliderModel``, with every slice's model checked before any work."""
    from . import _apparatus

    if xn in _apparatus.MODE_FIELDS.values():
        raise ValueError(f"x = {xn!r} is set by arm_length through the apparatus model: it cannot be the other parameter")

    def at(yv: float) -> SliderModel:
        try:
            return model.replace(**_apparatus.arm_frequencies(float(yv), model))
        except ValueError as e:
            raise ValueError(f"y = ('arm_length', {yspan[0]}, {yspan[1]}): arm_length = {yv:.6g} gives no valid "
                             f"model ({e})") from None  # fmt: skip

    for yv in ys:
        at(yv)
    return at


def _arm_dataset(kind, model, xspec, ys, found, work, reason, method, contact, opts) -> xr.Dataset:
    """The Dataset of an arm-length curve from its located points (raw branch points with ``y``)."""
    xn, x_lo, x_hi = xspec
    merged = {k: np.array([f[k] for f in found], dtype=d).reshape((len(found),) + shape)
              for k, (shape, d) in _RAW_KEYS.items()}  # fmt: skip
    merged["status"] = work["status"]
    attrs = {"kind": kind, "x": xn, "y": "arm_length", "x_units": PARAM_UNITS[xn], "y_units": "m",
             "x_bounds_low": x_lo, "x_bounds_high": x_hi, "y_low": float(ys[0]), "y_high": float(ys[-1]),
             "n": int(len(ys)), "method": method, "reason": reason,
             "contact": contact, "friction_law": model.friction_law, "n_flows": work["n_flows"],
             "n_rhs": work["n_rhs"]}  # fmt: skip
    if kind == "grazing" and contact == "bilateral":
        attrs["comment"] = ("the contact side's grazing (the pin first leaves the disk), followed with the bilateral law, "
                            "on which that orbit is the same")  # fmt: skip
    attrs |= {f"continuation_{k}": (int(v) if k in _INT_OPTIONS else v) for k, v in (DEFAULTS | opts).items()}
    ds = _dataset(merged, "curve_point", xn, attrs).rename({"parameter": xn})
    ds["arm_length"] = (("curve_point",), np.array([f["y"] for f in found], dtype=np.float64),
                        {"units": "m", "long_name": "arm_length: clamped arm length l"})  # fmt: skip
    return ds


def fold_curve(model: SliderModel, x, y, *, n: int = 11, orbit=None, from_hopf=None, start=None, direction=None,
               threads: int | None = None, **options) -> xr.Dataset:  # fmt: skip
    """The curve of a fold of cycles in two parameters: the edge of a region where a family of cycles exists.

    Slice by slice: for each of ``n`` values of ``y`` the fold is located in ``x`` by the
    one-parameter branch (:func:`branch` with ``stop_at="fold"``), from an orbit of the previous
    slice carried to the new ``y`` at fixed ``x``. This reuses the branch's detection and location
    (same tolerance) and only first derivatives of the flow; an augmented fold system would need
    second derivatives of the monodromy across contact switches (finite differences there are noisy)
    and has no smooth form at a grazing turn. The price: the curve must be a graph over ``y``. Both
    smooth folds and non-smooth ones (a grazing where the branch turns back, flag
    ``parameter_turns``) count.

    Parameters
    ----------
    model : SliderModel
        The start orbit's model; its ``y`` value must lie in the ``y`` range.
    x, y : (str, float, float)
        The continuation parameter with its window, and the sliced parameter with its range. ``y``
        may be ``"arm_length"`` [m] (the apparatus model, the model's own frequencies at 0.072 m):
        with ``from_hopf`` (``True``, a Hopf item or an ``x`` value) every slice starts at its own
        Hopf point, the one nearest the previous slice's; with ``orbit`` (an orbit of ``model``,
        at 0.072 m) the orbit is carried from slice to slice, so folds of families not born at a
        Hopf point (the bouncing cycle's) are followed too, and the curve ends where the fold
        changes type (grazing turn against smooth fold). Where the curve ends between two slices
        its end is located by bisection in the arm length.
    n : int
        Values of ``y`` (evenly spaced over its range; the model's own value is added, except
        for the arm length).
    orbit, from_hopf, start, direction
        Where the first slice's branch starts, as in :func:`branch`.
    threads : int or None
        Threads for the slices' branches with ``from_hopf`` over the arm length (None: one per core;
        the curve is the same bit for bit whatever the count). Carried orbits go slice by slice.
    **options
        Continuation settings of :func:`branch`.

    Returns
    -------
    xarray.Dataset
        On dim ``curve_point`` (sorted by ``y``): both parameters (named), and the located orbit's
        ``period``, ``A1``, multipliers, ``point_type``, ``flags``...; ``status`` and attribute
        ``reason`` (where and why the curve ended early).
    """
    return _curve("fold", model, x, y, n, orbit, from_hopf, start, direction, options, threads)


def grazing_curve(model: SliderModel, x, y, *, n: int = 11, orbit=None, from_hopf=None, start=None, direction=None,
                  threads: int | None = None, **options) -> xr.Dataset:  # fmt: skip
    """The curve of a grazing point in two parameters: where the orbit first touches contact loss.

    Slice by slice as :func:`fold_curve` (see there), stopping at the first grazing point in ``x``.
    """
    return _curve("grazing", model, x, y, n, orbit, from_hopf, start, direction, options, threads)


def stick_curve(model: SliderModel, x, y, *, n: int = 11, orbit=None, from_hopf=None, start=None, direction=None,
                threads: int | None = None, **options) -> xr.Dataset:  # fmt: skip
    """The onset of stick-slip in two parameters: where the cycle's slip first reaches the stick band.

    Switch law only (``friction_law="switch"``). Slice by slice as :func:`fold_curve` (see there),
    stopping at the first stick point in ``x``: the branch's ``min_slip_velocity`` (the smallest
    ``|v_r|`` in sliding contact over the cycle) falls to the band's half-width ``stick_band``.
    Past it the cycle gains a stick phase, a sliding bifurcation. The stick phase is of finite
    length at once (the force that holds the touching cycle in the band is the kinetic friction,
    below the static bound), so the stick-slip cycle past it is no small change of the pure-slip
    one, and continuation ends there: the curve bounds the pure-slip vibration of the family born
    at the Hopf point. Without ``max_points`` in ``options`` the slices' branches run to
    :data:`SWITCH_MAX_POINTS` points.

    Examples
    --------
    >>> import tribosweep as ts
    >>> m = ts.SliderModel(contact="unilateral", friction_law="switch", mu_static=0.3, sliding_speed=0.2)
    >>> ds = ts.stick_curve(m, x=("normal_load", 10, 150), y=("arm_length", 0.07, 0.09), n=2, from_hopf=True)
    >>> ds.sizes["curve_point"], [round(float(v), 2) for v in ds.normal_load]
    (2, [28.85, 22.54])
    """
    return _curve("stick", model, x, y, n, orbit, from_hopf, start, direction, options, threads)
