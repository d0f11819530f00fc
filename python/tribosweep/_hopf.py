"""Hopf bifurcations of steady sliding: along one parameter, and as curves in two.

Steady sliding is the equilibrium ``y = 0`` at every parameter value, so following it means
following its spectrum. Where a complex pair crosses the imaginary axis (a Hopf point) the
first Lyapunov coefficient ``l1`` (Kuznetsov's invariant formula, with the slider's analytic
second and third derivatives) tells on which side the small cycle is born:

- ``l1 < 0`` supercritical: a small stable cycle grows out of the point where sliding turns
  unstable;
- ``l1 > 0`` subcritical: an unstable (saddle) cycle surrounds the still stable sliding, and the
  vibration that sets in where sliding turns unstable jumps to a large amplitude (bistability).

Normalisation: ``l1`` scales with the square of the size of the critical eigenvector ``q``; only
its sign is invariant. tribosweep scales ``q`` as the displacements
``[z, zd/w, x, xd/w, L phi, L phid/w]`` (``L phi`` is the twist's displacement of the contact
point) with unit Euclidean norm, so ``l1`` is in m^-2 and the cycle near the Hopf point ``p_H``
is ``y = 2 Re(v q e^(i w t))`` with ``|v|^2 = -a'(p - p_H) / (w l1)``, ``a' = d Re(lambda)/dp``.
The first harmonic of ``z`` on it is ``2 |v| |q_z|``; ``amplitude_squared_slope`` is its square
per unit of ``|p - p_H|``.

The linearisation is taken in contact, so it is the same for the bilateral and the unilateral
contact model (near steady sliding the pin stays on the disk).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import xarray as xr

from . import _apparatus, _core
from ._codes import STATUS_NAMES, flag_attrs
from ._model import PARAM_LONG_NAMES, PARAM_NAMES, PARAM_UNITS, SliderModel

_FLAGS = _core.hopf_flag_names()
#: Criticality names in code order (sign of the first Lyapunov coefficient).
CRITICALITY_NAMES: tuple[str, ...] = tuple(_FLAGS["criticality"])
#: Point types of a Hopf curve in code order.
POINT_TYPE_NAMES: tuple[str, ...] = tuple(_FLAGS["point_type"])
#: How an end of a Hopf curve ended, in code order.
END_STATUS_NAMES: tuple[str, ...] = tuple(_FLAGS["end_status"])
_MODE_NAMES: tuple[str, ...] = tuple(_FLAGS["mode"])
#: Parameters the analysis can move along: every real model field but the discrete torsion sign,
#: and the apparatus' arm length (which sets the three natural frequencies, docs/model.md §7).
HOPF_PARAMETERS: tuple[str, ...] = tuple(n for n in PARAM_NAMES if n != "torsion_sign") + ("arm_length",)
_SCALED_STATE = ("z", "z_dot_over_omega", "x", "x_dot_over_omega", "L_phi", "L_phi_dot_over_omega")
_NORMALISATION = (
    "q scaled as the displacements [z, zd/w, x, xd/w, L phi, L phid/w] with unit Euclidean norm (L: moment arm); "
    "cycle y = 2 Re(v q exp(i w t)) with |v|^2 = -Re(lambda)/(w l1); only the sign of l1 is invariant"
)


def _units(name: str) -> str:
    return "m" if name == "arm_length" else PARAM_UNITS[name]


def _long_name(name: str) -> str:
    return "clamped arm length l" if name == "arm_length" else PARAM_LONG_NAMES[name]


def _inverse_units(units: str) -> str:
    """``"m s-1"`` -> ``"m-1 s"``: every token's exponent negated (``"1"`` stays)."""
    if units == "1":
        return "1"
    out = []
    for tok in units.split():
        base = tok.rstrip("-0123456789")
        exp = int(tok[len(base):] or 1)
        out.append(base if exp == -1 else f"{base}{-exp}")
    return " ".join(out)


def _at(model: SliderModel, name: str, value: float) -> SliderModel:
    """The model with parameter ``name`` at ``value`` (validated)."""
    if name == "arm_length":
        return model.replace(**_apparatus.arm_frequencies(value, model))
    return model.replace(**{name: value})


def _axis(model: SliderModel, name: str) -> tuple:
    """The axis as the core takes it: ``(name, reference, [(field, base, exponent)])``."""
    if name == "arm_length":
        # The model's frequencies belong to the seed arm length, as in apparatus_model(base=model).
        terms = [(field, getattr(model, field), _apparatus.ARM_EXPONENTS[mode])
                 for mode, field in _apparatus.MODE_FIELDS.items()]  # fmt: skip
        return (name, _apparatus.L_SEED, terms)
    return (name, 1.0, [])


def _model(model) -> SliderModel:
    if not isinstance(model, SliderModel):
        raise ValueError(f"model = {model!r} must be a tribosweep.SliderModel")
    return model


def _spec(model: SliderModel, arg: str, spec) -> tuple[str, float, float]:
    """Check a ``(name, low, high)`` parameter range before any work."""
    try:
        name, lo, hi = spec
    except (TypeError, ValueError):
        raise ValueError(f"{arg} = {spec!r} must be a (name, low, high) tuple") from None
    if name not in HOPF_PARAMETERS:
        raise ValueError(f"{arg} = {spec!r}: {name!r} is not a parameter to follow; valid names are {HOPF_PARAMETERS}")
    try:
        lo, hi = float(lo), float(hi)
    except (TypeError, ValueError):
        raise ValueError(f"{arg} = {spec!r}: low and high must be real numbers") from None
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise ValueError(f"{arg} = {spec!r}: low and high must be finite")
    if not lo < hi:
        raise ValueError(f"{arg} = {spec!r}: must have low < high")
    for end, v in (("low", lo), ("high", hi)):
        try:
            _at(model, name, v)
        except ValueError as e:
            raise ValueError(f"{arg} = {spec!r}: the {end} end is outside the valid range of {name}: {e}") from None
    return name, lo, hi


def _int(arg: str, value, low: int, high: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low or (high is not None and value > high):
        rng = f">= {low}" if high is None else f"in [{low}, {high}]"
        raise ValueError(f"{arg} = {value!r} is out of range: must be an integer {rng}")
    return int(value)


def _real(arg: str, value, low: float, high: float, *, low_open: bool = True) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{arg} = {value!r} is not a number: must be in {'(' if low_open else '['}{low}, {high}]") from None
    ok = (v > low if low_open else v >= low) and v <= high and math.isfinite(v)
    if not ok:
        raise ValueError(f"{arg} = {value!r} is out of range: must be in {'(' if low_open else '['}{low}, {high}]")
    return v


def _marks(arg: str, values) -> list[float]:
    if values is None:
        return []
    a = np.atleast_1d(np.asarray(values, dtype=np.float64))
    if a.ndim != 1 or not np.all(np.isfinite(a)):
        raise ValueError(f"{arg} = {values!r} must be a 1-D sequence of finite numbers")
    return [float(v) for v in a]


def _extrapolated(name: str, values: np.ndarray) -> np.ndarray:
    if name == "normal_load":
        return _apparatus.load_extrapolated(values).astype(np.int8)
    if name == "arm_length":
        return _apparatus.arm_extrapolated(values).astype(np.int8)
    return np.zeros(np.shape(values), dtype=np.int8)


def sliding_branch(
    model: SliderModel,
    parameter: tuple[str, float, float] = ("normal_load", 1.0, 250.0),
    *,
    n_points: int = 201,
    tol: float = 1e-13,
) -> xr.Dataset:
    """Steady sliding along one parameter: its eigenvalues, and every Hopf point, classified.

    The eigenvalues of steady sliding are followed by continuity from ``n_points`` uniform
    samples; an interval is halved where they cannot be matched unambiguously, or where a real
    part keeps its sign at both ends but its cubic Hermite interpolant (with the exact derivative
    ``<p, dA/dp q>``) crosses zero inside (two crossings in one cell). Each sign change is located
    by safeguarded Newton to ``tol`` of the range; at each Hopf point the first Lyapunov
    coefficient says whether it is sub- or supercritical.

    Parameters
    ----------
    model : SliderModel
        Everything that does not move.
    parameter : (str, float, float)
        ``(name, low, high)``: a real model field (see ``HOPF_PARAMETERS``; units of the field) or
        ``"arm_length"`` [m] (the natural frequencies follow the apparatus' power laws, with the
        model's own frequencies at the seed arm length 7.2 cm, as ``apparatus_model(base=model)``).
        Both ends must give a valid model.
    n_points : int
        Uniform samples before refinement (>= 3).
    tol : float
        Tolerance of the located parameter, relative to the range (in (0, 1e-3]).

    Returns
    -------
    xarray.Dataset
        Along ``sliding_point`` (coordinate: the parameter): ``pair_growth_rate``, ``frequency`` and
        ``mode`` of each tracked ``pair``, ``growth_rate`` (the largest), ``stable``. Along ``hopf_point``:
        ``hopf_<name>`` (the parameter at the crossing), ``hopf_frequency``, ``l1`` [m-2],
        ``c1_imag``, ``criticality``, ``direction``, ``cycle_side``, ``growth_rate_derivative``,
        ``amplitude_squared_slope``, ``hopf_mode``, ``other_unstable``, ``eigenvector_real`` /
        ``eigenvector_imag`` (scaled, on ``scaled_state``), ``hopf_moment_arm``, ``is_hopf`` (a
        complex pair; otherwise a real eigenvalue through zero), ``extrapolated``,
        ``hopf_status`` and ``hopf_reason``.

    Raises
    ------
    ValueError
        An unknown parameter, ``low >= high``, a non-finite or invalid end, or a bad option
        (the message names the argument, its value and the valid range), before any work.

    Examples
    --------
    >>> import tribosweep as ts
    >>> ds = ts.sliding_branch(ts.SliderModel(), ("normal_load", 1.0, 250.0))
    >>> round(float(ds.hopf_normal_load[0]), 3), ts.CRITICALITY_NAMES[int(ds.criticality[0])]
    (24.904, 'subcritical')
    """
    model = _model(model)
    name, lo, hi = _spec(model, "parameter", parameter)
    n_points = _int("n_points", n_points, 3, 1_000_000)
    tol = _real("tol", tol, 0.0, 1e-3)
    out = _core.sliding_branch(model.values(), model.contact, model.friction_law, _axis(model, name), lo, hi,
                               n_points=n_points, xtol=tol)  # fmt: skip
    ev = out["eigenvalues"]
    units, long = _units(name), _long_name(name)
    mode_attrs = flag_attrs(_MODE_NAMES, "mode of the pair, by eigenvector energy participation")
    labels = out["labels"].astype(np.uint8)
    growth = ev.real
    with np.errstate(invalid="ignore"):
        max_growth = np.nanmax(growth, axis=1)
    value = out["hopf_value"]
    omega = out["hopf_lambda"].imag
    dlam = out["hopf_dlambda"]
    l1 = out["l1"]
    moment_arm = value if name == "moment_arm" else np.full(value.shape, model.moment_arm)
    lscale = np.where(moment_arm > 0, moment_arm, 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.column_stack([np.ones_like(omega), 1 / omega, np.ones_like(omega), 1 / omega, lscale, lscale / omega])
        q = out["eigenvector"] * scale
        h20, h11 = out["h20"] * scale, out["h11"].real * scale
        slope = 4 * np.abs(q[:, 0]) ** 2 * np.abs(dlam.real) / (omega * np.abs(l1))
        side = np.where(np.isfinite(l1) & (l1 != 0), np.where(-dlam.real * l1 > 0, 1, 0), 2).astype(np.uint8)
    per = _inverse_units(units)
    hopf_vars = {
        f"hopf_{name}": (value, {"units": units, "long_name": f"{long} at the crossing"}),
        "hopf_frequency": (omega, {"units": "rad s-1", "long_name": "angular frequency of the critical pair at the crossing"}),
        "l1": (l1, {"units": "m-2", "long_name": "first Lyapunov coefficient", "comment": _NORMALISATION}),
        "c1_imag": (out["c1"].imag, {"units": "m-2 s-1", "long_name": "Im(c1): the small cycle's frequency shift per |v|^2"}),
        "growth_rate_derivative": (dlam.real, {"units": f"s-1 {per}".replace(" 1", "") if per != "1" else "s-1",
                                               "long_name": f"d Re(lambda) / d {name} at the crossing"}),
        "frequency_derivative": (dlam.imag, {"units": f"rad s-1 {per}".replace(" 1", "") if per != "1" else "rad s-1",
                                             "long_name": f"d Im(lambda) / d {name} at the crossing"}),
        "amplitude_squared_slope": (slope, {"units": f"m2 {per}" if per != "1" else "m2",
                                            "long_name": f"squared first harmonic of z on the small cycle per unit |{name} - hopf_{name}|"}),
        "other_unstable": (out["other_unstable"], {"units": "1", "long_name": "other eigenvalues with positive real part (0: the point bounds stable sliding)"}),
        "hopf_moment_arm": (moment_arm, {"units": "m", "long_name": "moment arm L used to scale the eigenvector"}),
    }  # fmt: skip
    data = {k: (("hopf_point",), v, a) for k, (v, a) in hopf_vars.items()}
    data["criticality"] = (("hopf_point",), out["criticality"], flag_attrs(CRITICALITY_NAMES, "sign of l1: subcritical l1 > 0, supercritical l1 < 0"))
    data["direction"] = (("hopf_point",), (dlam.real < 0).astype(np.uint8),
                         flag_attrs(("loses_stability", "gains_stability"), f"the pair as {name} increases"))  # fmt: skip
    data["cycle_side"] = (("hopf_point",), side, flag_attrs(("below", "above", "undetermined"), f"side of hopf_{name} on which the small cycle exists"))
    data["hopf_mode"] = (("hopf_point",), out["mode"].astype(np.uint8), flag_attrs(_MODE_NAMES, "mode of the critical pair"))
    data["is_hopf"] = (("hopf_point",), out["hopf_is_pair"].astype(np.int8),
                       {"long_name": "a complex pair crosses (Hopf); else a real eigenvalue through zero",
                        "flag_values": np.array([0, 1], dtype=np.int8), "flag_meanings": "zero_eigenvalue hopf"})  # fmt: skip
    data["extrapolated"] = (("hopf_point",), _extrapolated(name, value),
                            {"long_name": "outside the identified range (loads 22-93 N, arms 5-12.7 cm)",
                             "flag_values": np.array([0, 1], dtype=np.int8), "flag_meanings": "identified extrapolated"})  # fmt: skip
    data["hopf_status"] = (("hopf_point",), out["status"], flag_attrs(STATUS_NAMES, "status of the location"))
    data["hopf_reason"] = (("hopf_point",), np.array(out["reason"], dtype=object), {"long_name": "why the status is not success (empty if it is)"})
    for part, arr in (("real", q.real), ("imag", q.imag)):
        data[f"eigenvector_{part}"] = (("hopf_point", "scaled_state"), arr,
                                       {"units": "1", "long_name": f"{part} part of the critical eigenvector q (scaled)", "comment": _NORMALISATION})  # fmt: skip
    cm = "centre manifold x = 2 Re(v q) + Re(h20 v^2) + h11 |v|^2 + O(|v|^3) (scaled as q)"
    for key, arr, what in (("h20_real", h20.real, "Re h20"), ("h20_imag", h20.imag, "Im h20"), ("h11", h11, "h11")):
        data[key] = (("hopf_point", "scaled_state"), arr, {"units": "m-1", "long_name": f"{what}: second-order term of the centre manifold", "comment": cm})
    data["pair_growth_rate"] = (("sliding_point", "pair"), growth, {"units": "s-1", "long_name": "real part of the pair's eigenvalue"})
    data["frequency"] = (("sliding_point", "pair"), ev.imag, {"units": "rad s-1", "long_name": "imaginary part of the pair's eigenvalue"})
    data["mode"] = (("sliding_point", "pair"), labels, mode_attrs)
    data["growth_rate"] = (("sliding_point",), max_growth, {"units": "s-1", "long_name": "largest growth rate"})
    data["stable"] = (("sliding_point",), (max_growth < 0).astype(np.int8),
                      {"long_name": "steady sliding is linearly stable", "flag_values": np.array([0, 1], dtype=np.int8),
                       "flag_meanings": "unstable stable"})  # fmt: skip
    coords = {
        name: (("sliding_point",), out["value"], {"units": units, "long_name": long}),
        "pair": ("pair", np.arange(ev.shape[1]), {"long_name": "eigenvalue pair, followed by continuity (order of the first sample)"}),
        "scaled_state": ("scaled_state", list(_SCALED_STATE)),
    }
    attrs = {
        "parameter": name, "parameter_low": lo, "parameter_high": hi, "n_points": n_points,
        "location_tolerance": tol * (hi - lo), "location_tolerance_units": units,
        "normalisation": _NORMALISATION, "contact": "linearised in contact (same for both contact models)",
        "friction_law": model.friction_law, "n_eigenvalue_computations": int(out["n_eig"]),
        "n_jacobian_evaluations": int(out["n_jac"]),
    }  # fmt: skip
    return xr.Dataset(data, coords=coords, attrs=attrs)


def hopf_cycle_guess(branch: xr.Dataset, value: float, *, hopf: int = 0) -> dict:
    """The small cycle the normal form predicts near a Hopf point of :func:`sliding_branch`.

    ``y0 = 2 Re(v q)`` with ``|v|^2 = -a' (value - p_H) / (w l1)`` and the phase that makes
    ``z_dot(0) = 0`` (the phase condition of :func:`periodic_orbit`); the period is ``2 pi / w``
    with ``w`` corrected to first order (``Im lambda'``, ``Im c1``). The relative error of the
    amplitude is of the order of ``|value - p_H|`` (the next term of the normal form).

    Parameters
    ----------
    branch : xarray.Dataset
        Output of :func:`sliding_branch`.
    value : float
        Parameter value near the Hopf point, on the side where the cycle exists (``cycle_side``).
    hopf : int
        Index along ``hopf_point``.

    Returns
    -------
    dict
        ``y0`` (6,) [SI state], ``period`` [s], ``amplitude`` (first harmonic of ``z``) [m].

    Raises
    ------
    ValueError
        ``hopf`` out of range, a point without ``l1``, or ``value`` on the side without a cycle.
    """
    name = branch.attrs["parameter"]
    n = branch.sizes.get("hopf_point", 0)
    if not (isinstance(hopf, (int, np.integer)) and 0 <= hopf < n):
        raise ValueError(f"hopf = {hopf!r} is out of range: the branch has {n} Hopf points")
    pt = branch.isel(hopf_point=hopf)
    p_h, w, l1 = float(pt[f"hopf_{name}"]), float(pt.hopf_frequency), float(pt.l1)
    da = float(pt.growth_rate_derivative)
    if not (math.isfinite(l1) and l1 != 0):
        raise ValueError(f"hopf = {hopf}: l1 = {l1} is not a nonzero number; no cycle prediction")
    v2 = -da * (float(value) - p_h) / (w * l1)
    if not v2 > 0:
        side = "above" if -da * l1 > 0 else "below"
        raise ValueError(f"value = {value!r} is on the side of hopf_{name} = {p_h} without a small cycle (it exists {side})")
    big_l = float(pt.hopf_moment_arm) if float(pt.hopf_moment_arm) > 0 else 1.0
    q = (pt.eigenvector_real.values + 1j * pt.eigenvector_imag.values) * np.array([1, w, 1, w, 1 / big_l, w / big_l])
    d = np.array([1, w, 1, w, 1 / big_l, w / big_l])
    h20 = (pt.h20_real.values + 1j * pt.h20_imag.values) * d
    h11 = pt.h11.values * d
    # Phase: z_dot(0) = 0 to first order (v q_zd imaginary), then corrected for the second-order terms.
    v = math.sqrt(v2) * 1j * abs(q[1]) / q[1]
    zd = lambda v: (2 * v * q[1] + h20[1] * v * v).real + h11[1] * abs(v) ** 2  # noqa: E731
    for _ in range(3):  # Newton on the phase theta of v e^(i theta)
        slope = (2j * v * q[1] + 2j * h20[1] * v * v).real
        v = v * np.exp(-1j * zd(v) / slope)
    y0 = 2 * (v * q).real + (h20 * v * v).real + h11 * abs(v) ** 2
    w_cycle = w + float(pt.frequency_derivative) * (float(value) - p_h) + float(pt.c1_imag) * v2
    return {"y0": y0, "period": 2 * math.pi / w_cycle, "amplitude": 2 * math.sqrt(v2) * abs(q[0])}


def hopf_curve(
    model: SliderModel,
    x: tuple[str, float, float] = ("normal_load", 1.0, 250.0),
    y: tuple[str, float, float] = ("arm_length", 0.05, 0.127),
    *,
    grid: tuple[int, int] = (16, 16),
    step: float | None = None,
    step_min: float = 1e-7,
    step_max: float = 0.05,
    tol: float = 1e-10,
    max_points: int = 5000,
    max_angle: float = 0.1,
    chord_tol: float = 1e-5,
    x_marks: Sequence[float] | None = None,
    y_marks: Sequence[float] | None = None,
) -> xr.Dataset:
    """Every Hopf curve of steady sliding in a box of two parameters, by pseudo-arclength continuation.

    Seeds are the sign changes of a complex pair's real part along the edges of a ``grid`` of
    nodes, located on the edge; a seed on a curve already traced (same frequency) is dropped. From
    each seed the curve ``Re lambda(x, y) = 0`` is followed both ways in box units (each axis
    scaled to [0, 1]): tangent predictor, Newton corrector on the arclength hyperplane, step
    halved on failure (Newton, an ambiguous eigenvalue) and shortened where the tangent turns by
    more than ``max_angle`` or the polyline would bulge from the curve by more than
    ``chord_tol``, down to ``step_min``; grown by 1.5 after easy steps up to ``step_max``. Bautin points (``l1 = 0``),
    double Hopf points (another eigenvalue crosses), requested axis values (``x_marks``,
    ``y_marks``) and box exits are located on the curve; a curve that returns to its seed is
    closed. A curve entirely inside one grid cell is not seen: refine ``grid``.

    Parameters
    ----------
    model : SliderModel
        Everything that does not move.
    x, y : (str, float, float)
        ``(name, low, high)`` of the two parameters (see :func:`sliding_branch`); different, and
        ``arm_length`` cannot be paired with a natural frequency it sets.
    grid : (int, int)
        Seeding nodes per axis (>= 2 each).
    step, step_min, step_max : float
        First, smallest and largest continuation step [box units], ``0 < step_min <= step <= step_max <= 0.5``
        (``step`` defaults to ``min(0.01, step_max)``).
    tol : float
        Newton tolerance [box units], in (0, 1e-4].
    max_points : int
        Largest number of points per curve (>= 10).
    max_angle : float, rad
        Largest turn of the tangent per step, in (0, 1].
    chord_tol : float
        Largest bulge of the curve from the polyline of its points [box units], estimated per step
        as ``h * angle / 8``; in (0, 0.1]. The points themselves are on the curve to ``tol``.
    x_marks, y_marks : sequence of float, optional
        Axis values to locate on the curves (point type ``mark``).

    Returns
    -------
    xarray.Dataset
        Along ``curve_point``: ``curve`` (index along ``hopf_curve``), the two parameters,
        ``frequency``, ``growth_rate`` (the corrector's residual), ``l1``, ``criticality``,
        ``point_type``, ``mode``, ``other_unstable``, ``status``. Along ``hopf_curve``:
        ``start_status`` / ``end_status`` with ``start_reason`` / ``end_reason``, ``n_points``.
        The continuation's tolerance and steps are attributes.

    Raises
    ------
    ValueError
        Unknown or equal parameters, ``low >= high``, non-finite or invalid ends, bad options.

    Examples
    --------
    >>> import tribosweep as ts
    >>> ds = ts.hopf_curve(ts.SliderModel(), x=("normal_load", 10, 100), y=("mu", 0.2, 0.3))
    >>> ds.sizes["hopf_curve"], [ts.END_STATUS_NAMES[int(s)] for s in (ds.start_status[0], ds.end_status[0])]
    (1, ['left_box', 'left_box'])
    """
    model = _model(model)
    xn, xlo, xhi = _spec(model, "x", x)
    yn, ylo, yhi = _spec(model, "y", y)
    if xn == yn:
        raise ValueError(f"x = {x!r} and y = {y!r} name the same parameter: the two must differ")
    freq_fields = set(_apparatus.MODE_FIELDS.values())
    for a, b in ((xn, yn), (yn, xn)):
        if a == "arm_length" and b in freq_fields:
            raise ValueError(f"{b!r} is set by arm_length through the apparatus model: it cannot be the other parameter")
    for corner in ((xlo, ylo), (xlo, yhi), (xhi, ylo), (xhi, yhi)):
        try:
            _at(_at(model, xn, corner[0]), yn, corner[1]) if xn != "arm_length" else _at(_at(model, yn, corner[1]), xn, corner[0])
        except ValueError as e:
            raise ValueError(f"x = {x!r}, y = {y!r}: the corner ({corner[0]}, {corner[1]}) is not a valid model: {e}") from None
    try:
        gx, gy = grid
    except (TypeError, ValueError):
        raise ValueError(f"grid = {grid!r} must be a pair of integers >= 2") from None
    gx, gy = _int("grid[0]", gx, 2, 1000), _int("grid[1]", gy, 2, 1000)
    step_max = _real("step_max", step_max, 0.0, 0.5)
    step = _real("step", min(0.01, step_max) if step is None else step, 0.0, step_max)
    step_min = _real("step_min", step_min, 0.0, step)
    tol = _real("tol", tol, 0.0, 1e-4)
    max_points = _int("max_points", max_points, 10)
    max_angle = _real("max_angle", max_angle, 0.0, 1.0)
    chord_tol = _real("chord_tol", chord_tol, 0.0, 0.1)
    xm, ym = _marks("x_marks", x_marks), _marks("y_marks", y_marks)
    out = _core.hopf_curve(model.values(), model.contact, model.friction_law, _axis(model, xn), _axis(model, yn),
                           (xlo, xhi), (ylo, yhi), grid=(gx, gy), step=step, step_min=step_min, step_max=step_max,
                           tol=tol, max_points=max_points, max_angle=max_angle, chord_tol=chord_tol, x_marks=xm,
                           y_marks=ym)  # fmt: skip
    pt = ("curve_point",)
    data = {
        "curve": (pt, out["curve"], {"long_name": "index of the curve along hopf_curve", "instance_dimension": "hopf_curve"}),
        xn: (pt, out["x"], {"units": _units(xn), "long_name": _long_name(xn)}),
        yn: (pt, out["y"], {"units": _units(yn), "long_name": _long_name(yn)}),
        "frequency": (pt, out["frequency"], {"units": "rad s-1", "long_name": "angular frequency of the critical pair"}),
        "growth_rate": (pt, out["growth_rate"], {"units": "s-1", "long_name": "real part of the critical eigenvalue (corrector residual)"}),
        "l1": (pt, out["l1"], {"units": "m-2", "long_name": "first Lyapunov coefficient", "comment": _NORMALISATION}),
        "criticality": (pt, out["criticality"], flag_attrs(CRITICALITY_NAMES, "sign of l1")),
        "point_type": (pt, out["point_type"], flag_attrs(POINT_TYPE_NAMES, "what the point is")),
        "mode": (pt, out["mode"].astype(np.uint8), flag_attrs(_MODE_NAMES, "mode of the critical pair")),
        "other_unstable": (pt, out["other_unstable"], {"units": "1", "long_name": "other eigenvalues with positive real part"}),
        "status": (pt, out["status"], flag_attrs(STATUS_NAMES, "status of the point (special points: of their location)")),
        "start_status": (("hopf_curve",), out["start_status"], flag_attrs(END_STATUS_NAMES, "how the curve's first point ended it")),
        "end_status": (("hopf_curve",), out["end_status"], flag_attrs(END_STATUS_NAMES, "how the curve's last point ended it")),
        "start_reason": (("hopf_curve",), np.array(out["start_reason"], dtype=object), {"long_name": "why the curve starts where it does"}),
        "end_reason": (("hopf_curve",), np.array(out["end_reason"], dtype=object), {"long_name": "why the curve ends where it does"}),
        "n_points": (("hopf_curve",), out["n_points"], {"units": "1", "long_name": "points of the curve", "sample_dimension": "curve_point"}),
    }  # fmt: skip
    attrs = {
        "x": xn, "y": yn, "x_low": xlo, "x_high": xhi, "y_low": ylo, "y_high": yhi, "seed_grid": [gx, gy],
        "continuation_tolerance": tol, "continuation_step": step, "continuation_step_min": step_min,
        "continuation_step_max": step_max, "continuation_units": "box units: each axis scaled to [0, 1]",
        "max_angle": max_angle, "polyline_tolerance": chord_tol, "max_points": max_points, "n_seeds": int(out["n_seeds"]),
        "n_eigenvalue_computations": int(out["n_eig"]), "n_jacobian_evaluations": int(out["n_jac"]),
        "normalisation": _NORMALISATION, "contact": "linearised in contact (same for both contact models)",
        "friction_law": model.friction_law,
    }  # fmt: skip
    return xr.Dataset(data, attrs=attrs)
