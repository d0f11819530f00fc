"""Stability boundaries over a normal load x arm length box, as curves: Hopf, fold of cycles, grazing,
and (switch law) the onset of sticking.

One Dataset with each kind of curve on its own dimension, the form a sweep stores them in and
``tribosweep boundary`` writes:

- ``hopf_*`` on ``hopf_point``: :func:`tribosweep.hopf_curve`, where steady sliding gains or loses
  stability;
- ``fold_*`` on ``fold_point``: :func:`tribosweep.fold_curve` from each Hopf curve, the first fold
  of the cycles born there (smooth, or a grazing where the branch turns back): where the saddle
  cycle around stable sliding ends;
- ``grazing_*`` on ``grazing_point``: :func:`tribosweep.grazing_curve` from each Hopf curve, where
  those cycles first touch contact loss (the pin first leaves the disk);
- ``stick_*`` on ``stick_point`` (switch law only): :func:`tribosweep.stick_curve` from each Hopf
  curve, where those cycles' slip first reaches the stick band (they gain a stick phase).

The fold, grazing and stick curves are computed slice by slice over the arm lengths that the Hopf curve
spans in the box (``slices`` values), each slice from its own Hopf point; a curve whose point
leaves the load window between two slices ends at the last slice inside.
"""

from __future__ import annotations

import concurrent.futures
import math
import threading

import numpy as np
import xarray as xr

from . import _checks, _curves, _hopf
from ._model import SliderModel

#: Variables of a Hopf curve stored on ``hopf_point``: :func:`hopf_curve`'s name -> the stored name.
HOPF_VARS: dict[str, str] = {
    "curve": "hopf_curve_index", "normal_load": "hopf_normal_load", "arm_length": "hopf_arm_length",
    "frequency": "hopf_frequency", "l1": "hopf_l1", "criticality": "hopf_criticality", "point_type": "hopf_point_type",
    "status": "hopf_status",
}  # fmt: skip
#: Variables of a fold, grazing or stick curve stored on ``<kind>_point`` as ``<kind>_<name>``.
CURVE_VARS: tuple[str, ...] = ("normal_load", "arm_length", "hopf_normal_load", "period", "A1", "min_gap",
                               "min_slip_velocity", "stable", "point_type", "flags")  # fmt: skip
#: The kinds of curve, in drawing order.
CURVE_KINDS: tuple[str, ...] = ("hopf", "fold", "grazing", "stick")
#: Kinds that need the switch friction law (the only one with a stick band).
SWITCH_ONLY: tuple[str, ...] = ("stick",)
_KEEP = ("units", "long_name", "flag_values", "flag_meanings", "flag_masks")
_WHAT = {
    "fold": "first fold of the cycles born at the Hopf curve (smooth, or a grazing where the branch turns back): "
            "the saddle cycle around stable sliding ends there",
    "grazing": "first grazing of the cycles born at the Hopf curve: the orbit first touches contact loss (the pin "
               "first leaves the disk)",
    "stick": "where the slip of the cycles born at the Hopf curve first reaches the stick band: they gain a stick "
             "phase (the onset of stick-slip)",
}  # fmt: skip


def _check_box(name: str, box) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in box)
    except (TypeError, ValueError):
        raise ValueError(f"{name} = {box!r} must be a (low, high) pair of numbers") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo < hi):
        raise ValueError(f"{name} = {box!r} is out of range: must be finite with 0 < low < high")
    return lo, hi


#: Where a Hopf curve leaves the box through a load bound, the end slice of its fold and grazing
#: curves is moved along the curve until its Hopf point lies this fraction of the load window inside.
#: On the bound itself, whether the slice's own Hopf search finds the point is decided by the last
#: bit of the eigenvalues (it differed between an Intel and an AMD EPYC machine: 4 against 7
#: grazing points); 1e-6 of the window is far above rounding and far below any curve's resolution.
END_INSET: float = 1e-6


def _inside_ends(arms: np.ndarray, loads: np.ndarray, x_lo: float, x_hi: float) -> tuple[float, float]:
    """The arm-length span of one Hopf curve for its slices, with ends on a load bound moved inside (``END_INSET``)."""
    order = np.argsort(arms, kind="stable")
    arms, loads = arms[order], loads[order]
    span = x_hi - x_lo
    ends = []
    for i, j in ((0, 1), (arms.size - 1, arms.size - 2)):
        ya, la = float(arms[i]), float(loads[i])
        on_bound = min(abs(la - x_lo), abs(la - x_hi)) <= 1e-9 * span
        dl = abs(float(loads[j]) - la)
        if on_bound and dl > 0.0:
            # Linear along the polyline's end segment: the inset is tiny, so is the curvature error.
            ya += min(END_INSET * span / dl, 0.5) * (float(arms[j]) - ya)
        ends.append(ya)
    return ends[0], ends[1]


def default_kinds(model: SliderModel) -> tuple[str, ...]:
    """Every kind of curve the model can have: the stick curve under the switch law only."""
    return tuple(k for k in CURVE_KINDS if k not in SWITCH_ONLY or model.friction_law == "switch")


def _curve_kinds(curves, model: SliderModel) -> tuple[str, ...]:
    if curves is None:
        return default_kinds(model)
    if isinstance(curves, str):
        curves = (curves,)
    try:
        kinds = tuple(curves)
    except TypeError:
        raise ValueError(f"curves = {curves!r} must be a sequence of names from {CURVE_KINDS}") from None
    bad = [k for k in kinds if k not in CURVE_KINDS]
    if bad or not kinds:
        raise ValueError(f"curves = {curves!r} is not valid: must be a non-empty subset of {CURVE_KINDS}")
    for k in kinds:
        if k in SWITCH_ONLY:
            _checks.switch_law(f"curves = {curves!r}: {k!r}", model.friction_law)
    return tuple(k for k in CURVE_KINDS if k in kinds)


def _stored(ds: xr.Dataset, src: str, dim: str, prefix: str) -> xr.DataArray:
    da = ds[src]
    attrs = {k: v for k, v in da.attrs.items() if k in _KEEP}
    attrs["long_name"] = f"{prefix}: " + str(attrs.get("long_name", src))
    return xr.DataArray(da.values, dims=(dim,), attrs=attrs)


def boundary_curves(
    model: SliderModel,
    normal_load: tuple[float, float] = (10.0, 150.0),
    arm_length: tuple[float, float] = (0.05, 0.127),
    *,
    curves=None,
    slices: int = 12,
    threads: int | None = None,
) -> xr.Dataset:
    """The Hopf, fold-of-cycles, grazing and (switch law) stick curves crossing a normal load x arm length box.

    Parameters
    ----------
    model : SliderModel
        Everything but the load and the arm length; its natural frequencies are those at the seed
        arm length 0.072 m (as in :func:`apparatus_model` and :func:`sweep`). The contact law
        matters for the fold (a unilateral branch turns back at grazing); the grazing curve is
        followed with the bilateral law, on which the grazing orbit is the same. The stick curve
        needs ``friction_law="switch"``.
    normal_load, arm_length : (float, float)
        The box [N], [m]: ``0 < low < high``.
    curves : sequence of str or None
        Which curves: any of ``"hopf"``, ``"fold"``, ``"grazing"``, ``"stick"`` (the others are
        started from the Hopf curves, which are computed in any case). None: all that the model
        can have (``"stick"`` under the switch law only).
    slices : int
        Arm lengths per Hopf curve at which the fold, grazing and stick points are located (>= 2),
        evenly over the arm lengths the Hopf curve spans in the box.
    threads : int or None
        Threads for the continuations (None: one per core). The fold, grazing and stick curves run
        at once and each curve's slices in parallel, with at most ``threads`` branches running at
        any time, so a curve that ends early leaves its cores to the others; the curves are the
        same bit for bit whatever the count. Under the switch law the
        fold curve reads its points off the stick curve's branches (each runs to its stick point,
        past the first fold), and so does the grazing curve where that branch keeps the contact
        closed to its end; the stick curve runs first, then the others: the points are those of
        their own calls, to the last bit.

    Returns
    -------
    xarray.Dataset
        ``hopf_*`` on ``hopf_point`` (``HOPF_VARS``); ``fold_*`` on ``fold_point``,
        ``grazing_*`` on ``grazing_point`` and ``stick_*`` on ``stick_point`` (``CURVE_VARS``, with
        ``<kind>_curve_index``: the Hopf curve it starts from). A curve kind with no point in the
        box has no variables. Attributes ``hopf_curves``, ``<kind>_curves`` say what was found (or
        why not), and ``<kind>_curve_call`` the exact call that reproduces each curve.

    Raises
    ------
    ValueError
        A bad box, ``curves`` or ``slices``, before any work. A continuation that ends early is
        recorded in the attributes, never raised.

    Examples
    --------
    >>> import tribosweep as ts
    >>> ds = ts.boundary_curves(ts.SliderModel(contact="unilateral"), curves=("hopf", "grazing"), slices=3)
    >>> ds.sizes["grazing_point"], round(float(ds.grazing_normal_load[-1]), 3)
    (4, 10.948)
    """
    if not isinstance(model, SliderModel):
        raise ValueError(f"model = {model!r} must be a tribosweep.SliderModel")
    x_lo, x_hi = _check_box("normal_load", normal_load)
    y_lo, y_hi = _check_box("arm_length", arm_length)
    kinds = _curve_kinds(curves, model)
    if isinstance(slices, bool) or not isinstance(slices, (int, np.integer)) or not 2 <= slices <= 1000:
        raise ValueError(f"slices = {slices!r} is out of range: must be an integer in [2, 1000]")
    threads = _checks.threads(threads)
    hopf = _hopf.hopf_curve(model, x=("normal_load", x_lo, x_hi), y=("arm_length", y_lo, y_hi))
    out = xr.Dataset()
    if "hopf" in kinds:
        for src, name in HOPF_VARS.items():
            out[name] = _stored(hopf, src, "hopf_point", "Hopf curve")
    n_curves = int(hopf.sizes.get("hopf_curve", 0))
    out.attrs["hopf_curves"] = (f"{n_curves} Hopf curve(s) in the box, {hopf.sizes['curve_point']} points "
                                "(tribosweep.hopf_curve): steady sliding gains or loses stability across them")  # fmt: skip
    for k in ("continuation_tolerance", "polyline_tolerance", "continuation_step_min", "continuation_step_max"):
        out.attrs[f"hopf_curve_{k}"] = hopf.attrs[k]
    todo = [k for k in kinds if k != "hopf"]
    groups = _groups(todo, model)
    workers = _curves._workers(threads)
    box = ((x_lo, x_hi), (y_lo, y_hi))
    if workers >= 2 and len(todo) >= 2:
        # The groups at once, each with the threads for all its slices, and at most `workers`
        # branches running at any time (`slots`): a curve whose branches end early leaves its cores
        # to the others (the tanh law's grazing branches took 7.9 s on its one thread while the
        # fold curve's thread idled after 0.7 s). Independent, so the same bits. Signals reach the
        # main thread only: on Ctrl-C (or an error) here, the other groups' threads stop at their
        # next branch instead of running their curves to the end.
        stop = threading.Event()
        slots = threading.BoundedSemaphore(workers)
        with concurrent.futures.ThreadPoolExecutor(max_workers=len(groups)) as pool:
            runs = [pool.submit(_group_curves, g, model, hopf, box, slices, workers, stop, slots) for g in groups]
            try:
                done = {k: v for run in runs for k, v in _curves._result(run).items()}
            except BaseException:
                stop.set()
                raise
    else:
        done = {k: v for g in groups for k, v in _group_curves(g, model, hopf, box, slices, workers).items()}
    for kind in todo:
        parts, notes, calls, attrs = done[kind]
        out.attrs |= attrs
        n_pts = sum(p.sizes[f"{kind}_point"] for p in parts)
        if n_pts:
            out = xr.merge([out, xr.concat([p for p in parts if p.sizes[f"{kind}_point"]], dim=f"{kind}_point")],
                           combine_attrs="override")  # fmt: skip
        summary = f"{n_pts} {kind} point(s) in the box ({_WHAT[kind]})"
        out.attrs[f"{kind}_curves"] = summary + ("; " + "; ".join(notes) if notes else "; no Hopf curve to start from")
        out.attrs[f"{kind}_curve_call"] = " | ".join(calls) if calls else "none"
    out.attrs |= {"boundary_normal_load_low": x_lo, "boundary_normal_load_high": x_hi,
                  "boundary_arm_length_low": y_lo, "boundary_arm_length_high": y_hi,
                  "boundary_slices": int(slices), "boundary_contact": model.contact}  # fmt: skip
    return out


def _groups(todo: list[str], model: SliderModel) -> list[tuple[str, ...]]:
    """The curve kinds in groups that run together. Under the switch law the stick curve and the
    others form one, the stick curve first: every branch from a Hopf point runs to its stick point,
    and the fold and grazing curves read their points off those branches where they are theirs
    (:class:`_curves.SharedBranches`)."""
    if model.friction_law == "switch" and "stick" in todo:
        return [("stick",) + tuple(k for k in todo if k != "stick")]
    return [(k,) for k in todo]


def _group_curves(group: tuple[str, ...], model, hopf, box, slices: int, threads: int, stop=None,
                  slots=None) -> dict:  # fmt: skip
    """:func:`_kind_curves` of each kind of ``group`` on ``threads`` threads: the first kind, then
    the others at once, reading the first's branches (see :func:`_groups`); ``slots`` bounds the
    branches running at once across all groups."""
    first, rest = group[0], group[1:]
    shared = _curves.SharedBranches(model.contact) if rest else None
    done = {first: _kind_curves(first, model, hopf, *box, slices, threads, stop, shared, slots)}
    if threads >= 2 and len(rest) >= 2:
        with concurrent.futures.ThreadPoolExecutor(max_workers=len(rest)) as pool:
            runs = [pool.submit(_kind_curves, k, model, hopf, *box, slices, threads, stop, shared, slots) for k in rest]
            done |= {k: _curves._result(run) for k, run in zip(rest, runs)}
    else:
        done |= {k: _kind_curves(k, model, hopf, *box, slices, threads, stop, shared, slots) for k in rest}
    return done


def _kind_curves(kind: str, model, hopf, box_x, box_y, slices: int, threads: int, stop=None, shared=None,
                 slots=None):  # fmt: skip
    """The ``kind`` curves from each Hopf curve of ``hopf``: (parts, notes, calls, attributes).
    ``stop`` set: ends at the next branch (``_curves.Stopped``); ``shared``: see :func:`_group_curves`."""
    (x_lo, x_hi), (y_lo, y_hi) = box_x, box_y
    parts, notes, calls, attrs = [], [], [], {}
    func = {"fold": _curves.fold_curve, "grazing": _curves.grazing_curve, "stick": _curves.stick_curve}[kind]
    for c in range(int(hopf.sizes.get("hopf_curve", 0))):
        on = hopf.curve.values == c
        arms, loads = hopf.arm_length.values[on], hopf.normal_load.values[on]
        a, b = float(arms.min()), float(arms.max())
        if not b - a > 1e-9 * (y_hi - y_lo):
            notes.append(f"Hopf curve {c}: spans no arm lengths")
            continue
        a, b = _inside_ends(arms, loads, x_lo, x_hi)
        start = float(loads[np.argmin(arms)])
        calls.append(f"tribosweep.{func.__name__}(model, x=('normal_load', {x_lo!r}, {x_hi!r}), "
                     f"y=('arm_length', {a!r}, {b!r}), n={int(slices)}, from_hopf={start!r})")  # fmt: skip
        # func's own work (`fold_curve`, `grazing_curve` or `stick_curve`), with the stop event.
        ds = _curves._curve(kind, model, ("normal_load", x_lo, x_hi), ("arm_length", a, b), int(slices), None, start,
                            None, None, {}, threads, stop, shared, slots)  # fmt: skip
        notes.append(f"from Hopf curve {c}: {ds.attrs['reason']}")
        sub = xr.Dataset({f"{kind}_{v}": _stored(ds, v, f"{kind}_point", f"{kind} curve") for v in CURVE_VARS})
        sub[f"{kind}_curve_index"] = xr.DataArray(
            np.full(ds.sizes["curve_point"], c, dtype=np.int32), dims=(f"{kind}_point",),
            attrs={"long_name": f"{kind} curve: index of the Hopf curve it starts from"})  # fmt: skip
        parts.append(sub)
        attrs[f"{kind}_curve_contact"] = ds.attrs["contact"]
        for key in ("continuation_tol", "continuation_locate_tol", "continuation_rtol"):
            attrs[f"{kind}_curve_{key}"] = ds.attrs[key]
    return parts, notes, calls, attrs
