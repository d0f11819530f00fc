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
    "S": "stick: the cycle first\nreaches the stick band",
}
_LABELS = {"fold": "F", "period_doubling": "PD", "neimark_sacker": "NS", "grazing": "G", "hopf": "H",
           "branch_point": "BP", "stick": "S", "end": ""}  # fmt: skip


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
    if abs(growth) <= 1e-6 * abs(omega):
        return value, omega
    # A pair of another mode on the imaginary axis while the least stable one grows: a Hopf point
    # all the same (its cycles are born unstable), as hopf_curve and sliding_branch report them.
    lam = np.asarray(lin["eigenvalues"])[0]
    lam = lam[lam.imag > 0]
    ratio = np.abs(lam.real) / lam.imag if lam.size else np.array([np.inf])
    j = int(np.argmin(ratio))
    if ratio[j] <= 1e-6:
        return value, float(lam[j].imag)
    raise ValueError(f"from_hopf = {value!r} is not a Hopf point of {parameter}: no eigenvalue pair there is on the "
                     f"imaginary axis (within 1e-6 of its frequency); the largest growth rate is {growth:.3e} 1/s at "
                     f"{omega:.6g} rad/s")  # fmt: skip


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
        ``min_law_force``, ``min_slip_velocity``, ``fraction_off_disk``, Floquet multipliers on dim ``multiplier`` (real and
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
    if stop_at == "stick":
        _checks.switch_law("stop_at = 'stick'", model.friction_law)
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
             "arclength_scales": (f"state by the characteristic sizes{_MODE_SCALES if from_hopf is not None and not out['static_scales'] else ''}, period "
                                  f"by {out['t_ref']:.9e} s, parameter by {out['p_ref']:.9e} {PARAM_UNITS[parameter]}"),
             "static_scales": int(bool(out["static_scales"]))}  # fmt: skip
    attrs |= {f"continuation_{k}": (int(v) if k in _INT_OPTIONS else v) for k, v in settings.items()}
    attrs |= {f"model_{k}": v for k, v in model.values().items() if k != parameter}
    return _dataset(out, "branch_point", parameter, attrs)


#: How a branch from a Hopf point scales the state (``_core.branch``; ``static_scales`` = 1: it ran
#: again on the characteristic sizes alone after failing on these).
_MODE_SCALES = (" (x, phi and their rates at least the critical mode's own motion when z moves by |z_st|; "
                "static_scales = 0)")


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
        "min_slip_velocity": v("min_slip_velocity", "m s-1", "smallest sliding speed |v_r| of the contact point in contact (0 where the orbit sticks)"),
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
    law = str(ds.attrs.get("friction_law", "constant"))
    law = "" if law == "constant" else f", {law} friction law"
    ax.set_title(f"branch of periodic orbits ({ds.attrs.get('contact', '')} contact{law})", fontsize=10)
    lines = {"stable": ("C0", "-", "stable orbit"), "unstable": ("C3", "--", "unstable orbit")}
    handles = [Line2D([], [], color=c, ls=ls, lw=1.4, label=text) for key, (c, ls, text) in lines.items() if key in drawn]
    handles += [Line2D([], [], color="k", marker="o", ms=4, ls="none", label=f"{letter}: {text}")
                for letter, text in _LEGEND.items() if letter in drawn]  # fmt: skip
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    return fig
