"""Branches of periodic orbits and their bifurcations, and two-parameter curves of folds and grazing.

A branch is followed by pseudo-arclength continuation of the shooting problem in one model
parameter (Rust core, ``tribosweep_core::branch``): tangent predictor, Newton corrector on the
monodromy matrix, Floquet multipliers at every point, and the special points located on the
branch by a bracketed secant (or bisection) search: folds of cycles, period doublings,
Neimark-Sacker (torus) points, branch points and grazing, where the orbit first touches contact
loss. With the unilateral law an orbit is a sequence of fixed-mode segments (in contact, in
flight) with the switches as equations, so the branch goes on smoothly through grazing, where a
flight appears or vanishes; a grazing where the branch turns back in the parameter (two cycles
meet and end) is flagged ``parameter_turns``: a non-smooth fold.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import xarray as xr

from . import _checks, _core
from ._codes import STATUS_NAMES, flag_attrs
from ._model import PARAM_LONG_NAMES, PARAM_NAMES, PARAM_UNITS, SliderModel

#: What a point of a branch is, in code order (``point_type``).
POINT_TYPE_NAMES: tuple[str, ...] = tuple(_core.branch_point_type_names())
#: The flag bits of a branch point, lowest first (``flags``, CF ``flag_masks``).
BRANCH_FLAG_NAMES: tuple[str, ...] = tuple(_core.branch_flag_names())
#: Continuation defaults (see :func:`branch`).
DEFAULTS: dict[str, float] = dict(_core.branch_defaults())

_OPTION_RANGES = {
    "rtol": (1e-14, 1e-3),
    "tol": (0.0, 1e-2),
    "ds": (0.0, 1.0),
    "ds_min": (0.0, 1.0),
    "ds_max": (0.0, 1.0),
    "locate_tol": (0.0, 1.0),
    "hopf_amplitude": (0.0, 1.0),
    "max_turn": (0.0, math.pi / 2),
}
_INT_OPTIONS = {"max_points": 2, "max_newton": 2, "n_samples": 16}
_STATE = ["z", "z_dot", "x", "x_dot", "phi", "phi_dot"]
#: What each letter of a bifurcation diagram stands for (its legend).
_LEGEND = {
    "H": "Hopf point (the branch\nleaves steady sliding)",
    "F": "fold of cycles",
    "G": "grazing: the orbit first\ntouches contact loss",
    "G/F": "grazing where the branch\nturns back (non-smooth fold)",
    "PD": "period doubling",
    "NS": "Neimark-Sacker (torus)",
    "BP": "branch point",
}
_LABELS = {"fold": "F", "period_doubling": "PD", "neimark_sacker": "NS", "grazing": "G", "hopf": "H",
           "branch_point": "BP", "end": ""}  # fmt: skip


def _model(model) -> SliderModel:
    if not isinstance(model, SliderModel):
        raise ValueError(f"model = {model!r} must be a tribosweep.SliderModel")
    return model


def _parameter(name: str, arg: str = "parameter") -> str:
    if not isinstance(name, str) or name not in PARAM_NAMES or name == "torsion_sign":
        valid = tuple(n for n in PARAM_NAMES if n != "torsion_sign")
        raise ValueError(f"{arg} = {name!r} is not valid: must be a real SliderModel field other than torsion_sign {valid}")
    return name


def _finite(name: str, value) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} = {value!r} is not a number: must be a finite number") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} = {value!r} is out of range: must be a finite number")
    return v


def _options(opts: Mapping[str, float]) -> dict[str, float]:
    out = {}
    for k, v in opts.items():
        if k in _INT_OPTIONS:
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < _INT_OPTIONS[k]:
                raise ValueError(f"{k} = {v!r} is out of range: must be an integer >= {_INT_OPTIONS[k]}")
            out[k] = float(v)
            continue
        lo, hi = _OPTION_RANGES.get(k, (0.0, math.inf))
        x = _finite(k, v)
        if not lo < x < hi and not (k == "rtol" and x == lo):
            raise ValueError(f"{k} = {v!r} is out of range: must be in ({lo}, {hi})")
        out[k] = x
    if out.get("ds_min", DEFAULTS["ds_min"]) > out.get("ds", DEFAULTS["ds"]):
        raise ValueError(f"ds_min = {out.get('ds_min', DEFAULTS['ds_min'])} is out of range: must be <= ds")
    if out.get("ds", DEFAULTS["ds"]) > out.get("ds_max", DEFAULTS["ds_max"]):
        raise ValueError(f"ds = {out.get('ds', DEFAULTS['ds'])} is out of range: must be <= ds_max")
    return out


def _hopf(model: SliderModel, parameter: str, from_hopf, start, lo: float, hi: float) -> tuple[float, float]:
    """(parameter value, frequency [rad/s]) of the Hopf point a branch starts at."""
    if isinstance(from_hopf, Mapping):
        if parameter != "normal_load" or "normal_load" not in from_hopf or "frequency" not in from_hopf:
            raise ValueError("from_hopf as a dict must be one item of hopf_load(...) and parameter must be 'normal_load'")
        return _finite("from_hopf['normal_load']", from_hopf["normal_load"]), _finite("from_hopf['frequency']",
                                                                                   from_hopf["frequency"])  # fmt: skip
    if from_hopf is True:
        if parameter != "normal_load":
            raise ValueError(f"from_hopf = True needs parameter = 'normal_load' (got {parameter!r}): "
                             "give the Hopf value of the parameter instead (from_hopf=value)")  # fmt: skip
        from ._frequency import hopf_load

        pts = hopf_load(model, (max(lo, 1e-3), hi))
        if not pts:
            raise ValueError(f"from_hopf = True: no Hopf load in [{lo}, {hi}] N")
        h = min(pts, key=lambda d: abs(d["normal_load"] - start))
        return float(h["normal_load"]), float(h["frequency"])
    value = _finite("from_hopf", from_hopf)
    lin = _core.linear_stability(model.values(), model.contact, model.friction_law, [parameter], np.array([[value]]),
                                 threads=1)
    growth, omega = float(lin["growth_rate"][0]), float(lin["linear_frequency"][0])
    if not abs(growth) <= 1e-6 * abs(omega):
        raise ValueError(f"from_hopf = {value!r} is not a Hopf point of {parameter}: the largest growth rate there is "
                         f"{growth:.3e} 1/s (must be within 1e-6 of the frequency {omega:.6g} rad/s)")  # fmt: skip
    return value, omega


def _orbit(orbit) -> tuple[np.ndarray, float]:
    if isinstance(orbit, xr.Dataset):
        try:
            return _checks.state("orbit state0", np.asarray(orbit["state0"].values)), float(orbit["period"])
        except KeyError as e:
            raise ValueError(f"orbit must be a periodic_orbit or branch point Dataset (missing {e})") from None
    try:
        y0, period = orbit
    except (TypeError, ValueError):
        raise ValueError("orbit must be a Dataset with state0 and period, or a (y0, period) pair") from None
    return _checks.state("orbit y0", y0), _checks.positive("orbit period [s]", period)


def branch(
    model: SliderModel,
    parameter: str,
    stop: float,
    *,
    start: float | None = None,
    from_hopf=None,
    orbit=None,
    direction: float | None = None,
    bounds: tuple[float, float] | None = None,
    stop_at: str | None = None,
    **options,
) -> xr.Dataset:
    """A branch of periodic orbits of ``model`` in one parameter, with its bifurcations located.

    Parameters
    ----------
    model : SliderModel
        Bilateral or unilateral contact.
    parameter : str
        The real SliderModel field to continue in (not ``torsion_sign``).
    stop : float
        The parameter value where the branch ends when it gets there (the last point is exactly on it).
    start : float, optional
        Parameter value of the first orbit (default: ``model``'s value, or the Hopf point's).
    from_hopf : True, dict, or float, optional
        Start at a Hopf point of steady sliding: ``True`` (``normal_load`` only: the Hopf load of
        :func:`hopf_load` nearest ``start`` within the bounds), one item of ``hopf_load(...)``, or the
        parameter value of a Hopf point. The branch leaves it on the side where the cycles exist (a
        subcritical Hopf point: where sliding is stable). The first orbit has amplitude
        ``hopf_amplitude |z_st|`` along the critical eigenvector.
    orbit : Dataset or (y0, period), optional
        Start from an orbit at ``start`` instead: a :func:`periodic_orbit` Dataset, one point of a
        branch Dataset, or a state near the orbit with a period guess [s].
    direction : float, optional
        Sign of the first step in the parameter (orbit starts; default towards ``stop``).
    bounds : (float, float), optional
        The branch ends where the parameter leaves ``[low, high]`` (default: between ``start`` and ``stop``).
    stop_at : str, optional
        End at the first located point of this type (a name in ``POINT_TYPE_NAMES``).
    **options
        Continuation settings (defaults in ``tribosweep._branch.DEFAULTS``): ``rtol`` (integration),
        ``tol`` (scaled periodicity residual), ``ds``, ``ds_min``, ``ds_max`` (steps in scaled
        arclength: state by its characteristic sizes, period by the first one, parameter by its
        starting magnitude), ``max_points``, ``max_newton``, ``locate_tol`` (special points, in scaled
        arclength), ``stability_tol``, ``n_samples``, ``hopf_amplitude``, ``max_turn`` [rad],
        ``max_period_ratio``.

    Returns
    -------
    xarray.Dataset
        On dim ``branch_point``: ``parameter``, ``period``, ``omega``, ``A0``, ``A1``, ``z_max``,
        ``min_gap`` (``-max_t zc``: > 0 the pin never leaves the disk, 0 at grazing),
        ``min_law_force``, ``fraction_off_disk``, Floquet multipliers on dim ``multiplier`` (real and
        imaginary parts, modulus and argument; netCDF has no complex type), ``stable``,
        ``n_unstable``, ``point_type`` (``POINT_TYPE_NAMES``), ``flags`` (``BRANCH_FLAG_NAMES``,
        CF ``flag_masks``), ``n_switches``, ``dp_ds``, ``arclength``, ``state0``. Scalar ``status``
        and attribute ``reason`` say how the branch ended; the continuation's tolerances and steps
        are attributes.

    Raises
    ------
    ValueError
        Bad arguments (before any work). A numerical failure ends the branch with ``status`` and ``reason``.

    Examples
    --------
    >>> import tribosweep as ts
    >>> ds = ts.branch(ts.SliderModel(contact="bilateral"), "normal_load", 84.46, from_hopf=True, bounds=(20.0, 84.46))
    >>> round(float(ds.period[-1]) * 1e3, 6), ts.STATUS_NAMES[int(ds.status)]
    (9.702674, 'success')
    """
    model = _model(model)
    parameter = _parameter(parameter)
    stop = _finite("stop", stop)
    opts = _options(options)
    if stop_at is not None and stop_at not in POINT_TYPE_NAMES:
        raise ValueError(f"stop_at = {stop_at!r} is not valid: must be one of {POINT_TYPE_NAMES}")
    if (from_hopf is None) == (orbit is None):
        raise ValueError("give exactly one of from_hopf and orbit")
    if start is not None:
        start = _finite("start", start)
    if bounds is not None:
        lo, hi = _finite("bounds[0]", bounds[0]), _finite("bounds[1]", bounds[1])
        if not lo < hi:
            raise ValueError(f"bounds = {bounds!r}: must have low < high")
    kw: dict = {}
    if from_hopf is not None:
        search = (lo, hi) if bounds is not None else (1.0, 250.0)
        value, omega = _hopf(model, parameter, from_hopf, stop if start is None else start, *search)
        kw["hopf_omega"] = omega
    else:
        value = start if start is not None else float(getattr(model, parameter))
        y0, period = _orbit(orbit)
        kw.update(y0=y0, period=period)
        d = (stop - value) if direction is None else _finite("direction", direction)
        if d == 0:
            raise ValueError(f"direction = {direction!r}: must be nonzero (and stop must differ from start)")
        kw["direction"] = float(np.sign(d))
    if bounds is None:
        lo, hi = min(value, stop), max(value, stop)
        if lo == hi:
            raise ValueError(f"stop = {stop!r} equals the start: give a different stop or bounds")
    if not lo <= value <= hi:
        raise ValueError(f"start = {value!r} is out of range: must be within bounds [{lo}, {hi}]")
    base = model.replace(**{parameter: value})
    out = _core.branch(base.values(), model.contact, model.friction_law, parameter, value, lo, hi,
                       options=opts, stop_at=stop_at, **kw)  # fmt: skip
    settings = DEFAULTS | opts
    attrs = {"parameter": parameter, "parameter_units": PARAM_UNITS[parameter], "stop": stop, "bounds_low": lo,
             "bounds_high": hi, "start": value, "started_from": "hopf" if from_hopf is not None else "orbit",
             "contact": model.contact, "friction_law": model.friction_law, "reason": str(out["reason"]),
             "n_flows": int(out["n_flows"]), "n_rhs": int(out["n_rhs"]),
             "arclength_scales": f"state by the characteristic sizes, period by {out['t_ref']:.9e} s, parameter by "
                                 f"{out['p_ref']:.9e} {PARAM_UNITS[parameter]}"}  # fmt: skip
    attrs |= {f"continuation_{k}": (int(v) if k in _INT_OPTIONS else v) for k, v in settings.items()}
    attrs |= {f"model_{k}": v for k, v in model.values().items() if k != parameter}
    return _dataset(out, "branch_point", parameter, attrs)


def _dataset(out: dict, dim: str, parameter: str, attrs: dict) -> xr.Dataset:
    n = len(out["parameter"])
    mult = np.asarray(out["multipliers_re"]) + 1j * np.asarray(out["multipliers_im"])
    two = (dim, "multiplier")
    units, long = PARAM_UNITS[parameter], PARAM_LONG_NAMES[parameter]

    def v(key, u, text, d=(dim,)):
        return d, np.asarray(out[key]), {"units": u, "long_name": text}

    data = {
        "parameter": v("parameter", units, f"{parameter}: {long}"),
        "period": v("period", "s", "period of the orbit"),
        "omega": ((dim,), 2 * np.pi / np.asarray(out["period"]), {"units": "rad s-1", "long_name": "angular frequency 2 pi / period"}),
        "A0": v("a0", "m", "mean of z"),
        "A1": v("a1", "m", "amplitude of the first harmonic of z"),
        "z_max": v("z_max", "m", "largest z on the orbit"),
        "z_min": v("z_min", "m", "smallest z on the orbit"),
        "min_gap": v("min_gap", "m", "smallest distance to contact loss, -max_t zc(t) (< 0: the pin leaves the disk; 0: grazing)"),
        "min_law_force": v("min_law_force", "N", "smallest total normal force of the contact law in contact"),
        "fraction_off_disk": v("fraction_off_disk", "1", "fraction of the period with the pin off the disk"),
        "floquet_multiplier_real": (two, mult.real, {"units": "1", "long_name": "Floquet multiplier, real part (by modulus descending)"}),
        "floquet_multiplier_imag": (two, mult.imag, {"units": "1", "long_name": "Floquet multiplier, imaginary part"}),
        "floquet_modulus": (two, np.abs(mult), {"units": "1", "long_name": "modulus of the Floquet multiplier"}),
        "floquet_argument": (two, np.angle(mult), {"units": "rad", "long_name": "argument of the Floquet multiplier"}),
        "trivial_multiplier": ((dim,), np.asarray(out["trivial"], dtype=np.int8), {"units": "1", "long_name": "index on multiplier of the trivial multiplier (closest to 1)"}),
        "trivial_error": v("trivial_error", "1", "|rho_trivial - 1|: accuracy check of the monodromy matrix"),
        "stable": ((dim,), np.asarray(out["stable"], dtype=np.int8), {"long_name": "every non-trivial multiplier inside the unit circle", "flag_values": np.array([0, 1], dtype=np.int8), "flag_meanings": "unstable stable"}),
        "n_unstable": v("n_unstable", "1", "non-trivial Floquet multipliers outside the unit circle"),
        "point_type": ((dim,), np.asarray(out["point_type"], dtype=np.uint8), flag_attrs(POINT_TYPE_NAMES, "what the point is")),
        "flags": ((dim,), np.asarray(out["flags"], dtype=np.uint8), {"long_name": "warnings and qualifiers of the point", "flag_masks": np.array([1 << i for i in range(len(BRANCH_FLAG_NAMES))], dtype=np.uint8), "flag_meanings": " ".join(BRANCH_FLAG_NAMES)}),
        "n_switches": v("n_switches", "1", "contact switches per period"),
        "dp_ds": v("dp_ds", units, "parameter component of the unit tangent (per unit of scaled arclength)"),
        "arclength": v("arclength", "1", "scaled arclength along the branch"),
        "newton_iterations": v("newton_iterations", "1", "Newton steps of the point's correction"),
        "residual": v("residual", "1", "scaled periodicity residual"),
        "state0": v("state0", None, "state at t = 0, the phase point zd = 0 [z, zd, x, xd, phi, phid] (SI)", two[:1] + ("state",)),
        "status": ((), np.uint8(out["status"]), flag_attrs(STATUS_NAMES, "how the computation ended (see attribute reason)")),
    }  # fmt: skip
    data["state0"][2].pop("units")
    coords = {dim: (dim, np.arange(n), {"long_name": f"index of the point along the {dim.split('_')[0]}"}),
              "multiplier": ("multiplier", np.arange(6), {"long_name": "index of the Floquet multiplier (by modulus "
                                                                      "descending)"}),
              "state": _STATE}  # fmt: skip
    return xr.Dataset(data, coords=coords, attrs=attrs)


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


def _curve(kind: str, model, x, y, n, orbit, from_hopf, start, direction, options) -> xr.Dataset:
    model = _model(model)
    (xn, x_lo, x_hi), (yn, y_lo, y_hi) = _axis(model, x, "x"), _axis(model, y, "y", arm=True)
    if xn == yn:
        raise ValueError(f"x and y are both {xn!r}: must be two different parameters")
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 2 <= n <= 10_000:
        raise ValueError(f"n = {n!r} is out of range: must be an integer in [2, 10000]")
    if (from_hopf is None) == (orbit is None):
        raise ValueError("give exactly one of from_hopf and orbit")
    opts = _options(options)
    if yn == "arm_length":
        return _arm_curve(kind, model, (xn, x_lo, x_hi), (y_lo, y_hi), n, orbit, from_hopf, start, opts)
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


#: Bisections of the arm length where a curve leaves the window between two slices (see :func:`_arm_curve`).
_ARM_END_BISECTIONS: int = 4
#: Per-point arrays of a raw branch (``_core.branch``) and their trailing shapes.
_RAW_KEYS: dict[str, tuple[tuple[int, ...], str]] = {
    **{k: ((), "f8") for k in ("parameter", "period", "trivial_error", "a0", "a1", "z_max", "z_min", "min_gap",
                                "min_law_force", "fraction_off_disk", "dp_ds", "arclength", "residual")},
    **{k: ((), "u1") for k in ("n_unstable", "point_type", "contact", "flags", "trivial")},
    "stable": ((), "?"), "n_switches": ((), "u4"), "newton_iterations": ((), "u4"),
    **{k: ((6,), "f8") for k in ("state0", "multipliers_re", "multipliers_im")},
}  # fmt: skip


def _arm_curve(kind: str, model: SliderModel, xspec, yspan, n: int, orbit, from_hopf, start, opts) -> xr.Dataset:
    """:func:`fold_curve` / :func:`grazing_curve` over the arm length: each slice from its own Hopf point.

    The arm length moves the three natural frequencies at once (``arm_frequencies``, the model's
    own at ``L_SEED``), so no orbit is carried between slices: at each of ``n`` arm lengths the
    Hopf points of ``x`` in its window are found (:func:`sliding_branch`), the one nearest the
    previous slice's is taken (the first: nearest ``from_hopf``'s value, or ``start``, or the low
    end of ``x``), and the branch from it runs to its first ``kind`` point, as ``branch(...,
    from_hopf=value, stop_at=kind)`` does. A slice with no Hopf point in the window, or whose
    branch leaves the window first, has no point: the curve has left the box there, and between
    such a slice and its neighbour with a point the arm length is bisected ``_ARM_END_BISECTIONS``
    times, so that the curve reaches to 1/16 of a slice spacing from where it leaves the window.
    """
    from . import _apparatus
    from ._hopf import sliding_branch

    xn, x_lo, x_hi = xspec
    if orbit is not None:
        raise ValueError("orbit: with y = 'arm_length' every slice starts at its own Hopf point (the arm length "
                         "moves three natural frequencies at once, so no orbit is carried): give from_hopf instead")  # fmt: skip
    if xn in _apparatus.MODE_FIELDS.values():
        raise ValueError(f"x = {xn!r} is set by arm_length through the apparatus model: it cannot be the other parameter")
    if isinstance(from_hopf, Mapping):
        target = _finite(f"from_hopf[{xn!r}]", from_hopf.get(xn))
    elif from_hopf is True:
        target = x_lo if start is None else _finite("start", start)
    else:
        target = _finite("from_hopf", from_hopf)
    ys = np.linspace(*yspan, n)

    def at(yv: float):
        try:
            return model.replace(**_apparatus.arm_frequencies(float(yv), model))
        except ValueError as e:
            raise ValueError(f"y = ('arm_length', {yspan[0]}, {yspan[1]}): arm_length = {yv:.6g} gives no valid "
                             f"model ({e})") from None  # fmt: skip

    for yv in ys:  # every slice's model is valid before any work
        at(yv)
    contact = "bilateral" if kind == "grazing" else model.contact
    turns = 1 << BRANCH_FLAG_NAMES.index("parameter_turns")
    work = {"status": 0, "n_flows": 0, "n_rhs": 0}

    def slice_at(yv: float, near: float) -> tuple[dict | None, str]:
        """The ``kind`` point at arm length ``yv`` from the Hopf point nearest ``near``, or None and why not."""
        m = at(yv)
        sb = sliding_branch(m, (xn, x_lo, x_hi))
        ok = (sb.is_hopf.values == 1) & (sb.hopf_status.values == 0)
        values, omegas = sb[f"hopf_{xn}"].values[ok], sb.hopf_frequency.values[ok]
        if values.size == 0:
            return None, "no Hopf point"
        i = int(np.argmin(np.abs(values - near)))
        h = float(values[i])
        out = _core.branch(m.replace(**{xn: h}).values(), contact, m.friction_law, xn, h, x_lo, x_hi,
                           hopf_omega=float(omegas[i]), options=opts, stop_at=kind)  # fmt: skip
        work["n_flows"] += int(out["n_flows"])
        work["n_rhs"] += int(out["n_rhs"])
        last = int(out["point_type"][-1]) if len(out["point_type"]) else -1
        hit = last == POINT_TYPE_NAMES.index(kind) or (
            kind == "fold" and last == POINT_TYPE_NAMES.index("grazing") and int(out["flags"][-1]) & turns)
        if not hit:
            work["status"] = max(work["status"], int(out["status"]))
            return None, str(out["reason"])
        return {k: out[k][-1] for k in _RAW_KEYS} | {"y": float(yv), "hopf": h}, ""

    slices: list[tuple[float, dict | None, str]] = []
    for yv in ys:
        pt, why = slice_at(yv, target)
        if pt is not None:
            target = pt["hopf"]
        slices.append((float(yv), pt, why))
    # Where the curve leaves the window between two slices (a slice without a point next to one
    # with), bisect the arm length ENDS times: the curve reaches to 1/2^ENDS of a slice from its end.
    ends = []
    for (ya, pa, _), (yb, pb, _) in zip(slices[:-1], slices[1:]):
        if (pa is None) == (pb is None):
            continue
        (y_in, p_in), y_out = ((ya, pa), yb) if pa is not None else ((yb, pb), ya)
        for _ in range(_ARM_END_BISECTIONS):
            ym = 0.5 * (y_in + y_out)
            pm, _ = slice_at(ym, p_in["hopf"])
            if pm is None:
                y_out = ym
            else:
                y_in, p_in = ym, pm
                ends.append(pm)
    found = sorted([pt for _, pt, _ in slices if pt is not None] + ends, key=lambda f: f["y"])
    gaps = [f"{yv:.6g} ({why})" for yv, pt, why in slices if pt is None]
    status, flows, rhs = work["status"], work["n_flows"], work["n_rhs"]
    merged = {k: np.array([f[k] for f in found], dtype=d).reshape((len(found),) + shape)
              for k, (shape, d) in _RAW_KEYS.items()}  # fmt: skip
    merged["status"] = status
    reason = f"{n - len(gaps)} of {n} arm lengths located their {kind} point"
    if ends:
        reason += f" ({len(ends)} more where the curve leaves the window, by bisection)"
    if gaps:
        reason += "; none at arm_length = " + ", ".join(gaps)
    attrs = {"kind": kind, "x": xn, "y": "arm_length", "x_units": PARAM_UNITS[xn], "y_units": "m",
             "x_bounds_low": x_lo, "x_bounds_high": x_hi, "y_low": float(ys[0]), "y_high": float(ys[-1]), "n": int(n),
             "method": "slice by slice over the arm length (natural frequencies by the apparatus power laws, the "
                       "model's own at 0.072 m): at each, the branch from the Hopf point of x nearest the previous "
                       "slice's, to its first special point",
             "reason": reason, "contact": contact if kind == "grazing" else model.contact,
             "friction_law": model.friction_law, "n_flows": flows, "n_rhs": rhs}  # fmt: skip
    if kind == "grazing":
        attrs["comment"] = ("the contact side's grazing (the pin first leaves the disk), followed with the bilateral law, "
                            "on which that orbit is the same")  # fmt: skip
    attrs |= {f"continuation_{k}": (int(v) if k in _INT_OPTIONS else v) for k, v in (DEFAULTS | opts).items()}
    ds = _dataset(merged, "curve_point", xn, attrs).rename({"parameter": xn})
    ds["arm_length"] = (("curve_point",), np.array([f["y"] for f in found], dtype=np.float64),
                        {"units": "m", "long_name": "arm_length: clamped arm length l"})  # fmt: skip
    ds[f"hopf_{xn}"] = (("curve_point",), np.array([f["hopf"] for f in found], dtype=np.float64),
                        {"units": PARAM_UNITS[xn], "long_name": f"the Hopf point of {xn} the slice's branch starts at"})  # fmt: skip
    return ds


def fold_curve(model: SliderModel, x, y, *, n: int = 11, orbit=None, from_hopf=None, start=None, direction=None,
               **options) -> xr.Dataset:  # fmt: skip
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
        then every slice starts at its own Hopf point (``from_hopf`` only: ``True``, a Hopf item or
        an ``x`` value, the first slice's Hopf point nearest it), and where the curve leaves the
        ``x`` window between two slices its end is located by bisection in the arm length.
    n : int
        Values of ``y`` (evenly spaced over its range; the model's own value is added, except
        for the arm length).
    orbit, from_hopf, start, direction
        Where the first slice's branch starts, as in :func:`branch`.
    **options
        Continuation settings of :func:`branch`.

    Returns
    -------
    xarray.Dataset
        On dim ``curve_point`` (sorted by ``y``): both parameters (named), and the located orbit's
        ``period``, ``A1``, multipliers, ``point_type``, ``flags``...; ``status`` and attribute
        ``reason`` (where and why the curve ended early).
    """
    return _curve("fold", model, x, y, n, orbit, from_hopf, start, direction, options)


def grazing_curve(model: SliderModel, x, y, *, n: int = 11, orbit=None, from_hopf=None, start=None, direction=None,
                  **options) -> xr.Dataset:  # fmt: skip
    """The curve of a grazing point in two parameters: where the orbit first touches contact loss.

    Slice by slice as :func:`fold_curve` (see there), stopping at the first grazing point in ``x``.
    """
    return _curve("grazing", model, x, y, n, orbit, from_hopf, start, direction, options)


def bifurcation_diagram(ds: xr.Dataset, *, amplitude: str = "A1", ax=None):
    """Amplitude against the parameter: stable solid, unstable dashed, special points marked and labelled.

    Parameters
    ----------
    ds : xarray.Dataset
        A :func:`branch` Dataset.
    amplitude : str
        The variable on the vertical axis (``A1``, ``z_max``, ``period``...).
    ax : matplotlib Axes, optional
        Draw into it (default: a new figure).

    Returns
    -------
    matplotlib.figure.Figure
        The legend, right of the axes, names only what is drawn: the stable and unstable lines
        present and each letter marking a special point (H, F, G, G/F, PD, NS, BP).
    """
    if not isinstance(ds, xr.Dataset) or "branch_point" not in ds.dims:
        raise ValueError("ds must be a tribosweep.branch Dataset (dim branch_point)")
    if amplitude not in ds:
        raise ValueError(f"amplitude = {amplitude!r} is not a variable of ds")
    try:
        from matplotlib.figure import Figure
        from matplotlib.lines import Line2D
    except ImportError as e:  # pragma: no cover - exercised only without matplotlib
        raise ImportError("bifurcation_diagram needs matplotlib: pip install 'tribosweep[plot]'") from e
    if ax is None:
        fig = Figure(figsize=(7.5, 4.5), layout="constrained")
        ax = fig.add_subplot()
    else:
        fig = ax.figure
    p = ds.parameter.values
    a = ds[amplitude].values
    units = ds[amplitude].attrs.get("units", "")
    scale, unit = (1e6, "\u00b5m") if units == "m" else (1.0, units)
    stable = ds.stable.values.astype(bool)
    # A segment is stable when both its ends are; runs of equal segments are drawn as one line
    # (so that the dashes show on a dense branch).
    seg = stable[:-1] & stable[1:]
    drawn = set()
    start = 0
    for i in range(1, len(seg) + 1):
        if i == len(seg) or seg[i] != seg[start]:
            solid = bool(seg[start])
            ax.plot(p[start:i + 1], a[start:i + 1] * scale, color="C0" if solid else "C3", ls="-" if solid else "--",
                    lw=1.4)  # fmt: skip
            drawn.add("stable" if solid else "unstable")
            start = i
    turns = 1 << BRANCH_FLAG_NAMES.index("parameter_turns")
    for i, t in enumerate(ds.point_type.values):
        name = POINT_TYPE_NAMES[int(t)]
        if name in ("regular", "end"):
            continue
        label = _LABELS[name]
        if name == "grazing" and int(ds.flags.values[i]) & turns:
            label = "G/F"
        ax.plot(p[i], a[i] * scale, "ko", ms=4)
        ax.annotate(label, (p[i], a[i] * scale), textcoords="offset points", xytext=(4, 4), fontsize=8)
        drawn.add(label)
    name = ds.attrs.get("parameter", "parameter")
    long = PARAM_LONG_NAMES.get(name, name)
    ax.set_xlabel(f"{long} [{ds.attrs.get('parameter_units', '')}]")
    what = ds[amplitude].attrs.get("long_name", amplitude)
    ax.set_ylabel(f"{amplitude}: {what} [{unit}]" if len(what) <= 40 else f"{amplitude} [{unit}]")
    ax.set_title(f"branch of periodic orbits ({ds.attrs.get('contact', '')} contact)", fontsize=10)
    lines = {"stable": ("C0", "-", "stable orbit"), "unstable": ("C3", "--", "unstable orbit")}
    handles = [Line2D([], [], color=c, ls=ls, lw=1.4, label=text) for key, (c, ls, text) in lines.items() if key in drawn]
    handles += [Line2D([], [], color="k", marker="o", ms=4, ls="none", label=f"{letter}: {text}")
                for letter, text in _LEGEND.items() if letter in drawn]  # fmt: skip
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    return fig
