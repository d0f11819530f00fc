"""The apparatus: from (normal load, arm length, sliding speed) to slider parameters (docs/model.md §7).

The report clamped the pin's arm at several lengths: a shorter arm is stiffer. It measured the
natural frequencies with the pin off the disk (appendix 3 table 1: normal, frictional and
torsional at 5.1 / 8.9 / 12.7 cm; appendix 4 table 2: normal at 5-11 cm). tribosweep fits
least-squares power laws to them on log-log axes (``numpy.linalg.lstsq``, at import) and scales
the seed's frequencies::

    w_i(l) = w_i,seed (l / l_seed)^p_i,      l_seed = 7.2 cm

``l_seed`` is inferred from the seed's normal frequency (its frictional and torsional ones would
imply 7.9 and 9.2 cm on the appendix-3 curves: the seed apparatus is the modified one).
Masses, damping ratios and contact parameters stay at the seed values.

Fitted exponents (``ARM_EXPONENTS``) and largest relative errors of the fit against the table
entries (``ARM_FIT_MAX_REL_ERROR``):

========== ========== ==================================================================
mode        exponent   largest relative error of the fit
========== ========== ==================================================================
normal      -0.683     3.4 % on appendix 4's seven points, 5.7 % on appendix 3's three
frictional  -0.820     2.1 % (appendix 3)
torsional   -0.426     2.2 % (appendix 3)
========== ========== ==================================================================

Cantilever bending would give -1.5 and torsion -0.5; the softening is unexplained (clamp or
base compliance are candidates).

The contact law was identified from loads of 22-93 N (report Table 1) and the arm tables span
5-12.7 cm: points outside are computed and flagged as extrapolation, never refused.
"""

from __future__ import annotations

import math

import numpy as np

from ._model import SliderModel

#: Arm length of the seed configuration [m] (inferred from its normal frequency, docs/model.md §7).
L_SEED: float = 0.072
#: Loads [N] of the contact-law identification (report Table 1): outside is extrapolation.
LOAD_RANGE: tuple[float, float] = (22.0, 93.0)
#: Arm lengths [m] spanned by the report's frequency tables: outside is extrapolation.
ARM_RANGE: tuple[float, float] = (0.05, 0.127)

#: The report's arm-length tables (docs/model.md §7): arm length [m] and frequencies [Hz].
ARM_TABLES: dict[str, dict[str, tuple[float, ...]]] = {
    "appendix3_table1": {
        "arm_length": (0.051, 0.089, 0.127),
        "normal": (66.0, 50.0, 35.0),
        "friction": (69.0, 45.0, 32.5),
        "torsion": (126.0, 102.5, 85.0),
    },
    "appendix4_table2": {
        "arm_length": (0.05, 0.06, 0.07, 0.08, 0.09, 0.10, 0.11),
        "normal": (68.75, 62.50, 56.25, 52.50, 47.50, 43.75, 40.00),
    },
}

#: SliderModel field of each fitted mode.
MODE_FIELDS: dict[str, str] = {"normal": "omega_normal", "friction": "omega_friction", "torsion": "omega_torsion"}


def fit_arm_power_laws() -> dict[str, dict]:
    """Least-squares power laws ``f = c l^p`` to the report's arm-length tables (a line in log-log).

    Normal from both tables, frictional and torsional from appendix 3.

    Returns
    -------
    dict
        Per mode (``normal``, ``friction``, ``torsion``): ``exponent`` ``p``, ``prefactor`` ``c``
        [Hz m^-p], and per table the arrays ``arm_length`` [m], ``measured`` [Hz], ``fitted`` [Hz]
        and ``rel_error`` (``|fitted/measured - 1|``), under ``tables``.
    """
    out = {}
    for mode in MODE_FIELDS:
        tables = {name: t for name, t in ARM_TABLES.items() if mode in t}
        lengths = np.concatenate([np.asarray(t["arm_length"]) for t in tables.values()])
        freqs = np.concatenate([np.asarray(t[mode]) for t in tables.values()])
        # The least-squares line through (log l, log f) in closed form, with the C library's
        # scalar log and correctly rounded sums (math.fsum): np.log on arrays and LAPACK's lstsq
        # pick kernels by CPU, and these exponents scale every arm length's frequencies.
        xs = [math.log(x) for x in lengths.tolist()]
        ys = [math.log(y) for y in freqs.tolist()]
        xm, ym = math.fsum(xs) / len(xs), math.fsum(ys) / len(ys)
        p = math.fsum((x - xm) * (y - ym) for x, y in zip(xs, ys)) / math.fsum((x - xm) ** 2 for x in xs)
        log_c = ym - p * xm
        per_table = {}
        for name, t in tables.items():
            arm = np.asarray(t["arm_length"])
            measured = np.asarray(t[mode])
            fitted = math.exp(log_c) * arm**p
            per_table[name] = {
                "arm_length": arm,
                "measured": measured,
                "fitted": fitted,
                "rel_error": np.abs(fitted / measured - 1.0),
            }
        out[mode] = {"exponent": float(p), "prefactor": math.exp(log_c), "tables": per_table}
    return out


ARM_FIT: dict[str, dict] = fit_arm_power_laws()
#: Fitted exponents ``p_i`` of ``w_i ~ l^p_i`` (about -0.68 normal, -0.82 frictional, -0.43 torsional).
ARM_EXPONENTS: dict[str, float] = {mode: fit["exponent"] for mode, fit in ARM_FIT.items()}
#: Largest relative error of each fit, per mode and table (e.g. ``("normal", "appendix3_table1")``).
ARM_FIT_MAX_REL_ERROR: dict[tuple[str, str], float] = {
    (mode, table): float(t["rel_error"].max()) for mode, fit in ARM_FIT.items() for table, t in fit["tables"].items()
}


def _check_positive(name: str, value, valid: str = "a finite number > 0") -> np.ndarray:
    a = np.asarray(value, dtype=np.float64)
    bad = ~(np.isfinite(a) & (a > 0))
    if bad.any():
        raise ValueError(f"{name} = {float(a[bad].flat[0])!r} is out of range: must be {valid}")
    return a


def arm_frequencies(arm_length, base: SliderModel | None = None) -> dict[str, np.ndarray | float]:
    """Natural frequencies [rad/s] at arm lengths ``arm_length`` [m].

    ``w_i(l) = w_i,base (l / L_SEED)^p_i``: the base model's frequencies are taken to belong to
    the seed arm length 7.2 cm.

    Parameters
    ----------
    arm_length : float or array_like, m
        Arm lengths (finite, > 0).
    base : SliderModel, optional
        Model whose frequencies hold at ``L_SEED`` (default the seed).

    Returns
    -------
    dict
        ``omega_normal``, ``omega_friction``, ``omega_torsion`` (same shape as ``arm_length``).

    Examples
    --------
    >>> w = arm_frequencies(0.072)
    >>> round(w["omega_normal"] / (2 * math.pi), 2)
    55.0
    """
    base = SliderModel() if base is None else base
    arm = _check_positive("arm_length", arm_length)
    ratio = arm / L_SEED
    # The power one element at a time, with the C library's pow: numpy's vectorised power (SIMD
    # kernels chosen by the CPU, e.g. on AVX-512) rounds differently from its scalar path in the
    # last bit, so a sweep's point and apparatus_model() at the same arm length were different
    # models (one ulp of omega_friction at 10.99 cm), with different census samples and, on
    # chaotic runs, different fates, and both moved with the CPU.
    power = np.vectorize(math.pow, otypes=[np.float64])
    out = {}
    for mode, field in MODE_FIELDS.items():
        w = getattr(base, field) * power(ratio, ARM_EXPONENTS[mode])
        # Exactly the base value at l_seed (x**p for x == 1 is exact, kept explicit for clarity).
        w = np.where(ratio == 1.0, getattr(base, field), w)
        out[field] = float(w) if w.ndim == 0 else w
    return out


def load_extrapolated(normal_load) -> np.ndarray:
    """True where a load [N] is outside the contact law's identification range ``LOAD_RANGE``."""
    p = np.asarray(normal_load, dtype=np.float64)
    return (p < LOAD_RANGE[0]) | (p > LOAD_RANGE[1])


def arm_extrapolated(arm_length) -> np.ndarray:
    """True where an arm length [m] is outside the span of the report's tables ``ARM_RANGE``."""
    a = np.asarray(arm_length, dtype=np.float64)
    return (a < ARM_RANGE[0]) | (a > ARM_RANGE[1])


def apparatus_model(
    normal_load: float,
    arm_length: float,
    sliding_speed: float,
    *,
    base: SliderModel | None = None,
) -> SliderModel:
    """The slider of the apparatus at one operating point.

    Parameters
    ----------
    normal_load : float, N
        ``F_st`` (> 0). Outside 22-93 N the contact law is extrapolated (see
        :func:`load_extrapolated`); computed anyway.
    arm_length : float, m
        Clamped arm length (> 0); sets the natural frequencies by the fitted power laws. Outside
        5-12.7 cm the fit is extrapolated (see :func:`arm_extrapolated`).
    sliding_speed : float, m/s
        ``V`` (> 0).
    base : SliderModel, optional
        Everything else (default the seed); its frequencies are those at ``L_SEED``.

    Returns
    -------
    SliderModel

    Raises
    ------
    ValueError
        A non-positive, NaN or infinite argument, naming it, its value and the valid range.

    Examples
    --------
    >>> m = apparatus_model(84.46, 0.072, 0.46)
    >>> m == SliderModel()
    True
    >>> round(apparatus_model(50.0, 0.05, 0.46).omega_normal / (2 * math.pi), 1)
    70.6
    """
    base = SliderModel() if base is None else base
    for name, value in (("normal_load", normal_load), ("arm_length", arm_length), ("sliding_speed", sliding_speed)):
        if np.ndim(value) != 0:
            raise ValueError(f"{name} = {value!r} must be a scalar (use tribosweep.sweep for arrays)")
        _check_positive(name, value)
    w = arm_frequencies(float(arm_length), base)
    return base.replace(normal_load=float(normal_load), sliding_speed=float(sliding_speed), **w)
