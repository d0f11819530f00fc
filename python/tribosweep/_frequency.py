"""Frequency domain: linear stability, Hopf loads, the triple-input describing function, periodic orbits."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import xarray as xr

from . import _checks, _core
from ._codes import INSTABILITY_NAMES, OUTCOME_NAMES, STATUS, STATUS_NAMES, flag_attrs
from ._model import SliderModel

_DEG = 180.0 / np.pi
#: A real Floquet multiplier below ``-1 + FLIP_TOL`` flags a periodic orbit at or past a period
#: doubling (``period_doubling``): within 0.05 of -1 the doubled orbit's shooting matrix
#: ``M^2 - I`` has a singular value below about 0.1 and the period-1 orbit is one small
#: parameter step from losing its stability.
FLIP_TOL = 0.05


def _model(model) -> SliderModel:
    if not isinstance(model, SliderModel):
        raise TypeError(f"model = {model!r} must be a tribosweep.SliderModel")
    return model


def _one(model: SliderModel) -> tuple[list[str], np.ndarray]:
    # A single parameter set through the batch interface: override nothing but mu with itself.
    return ["mu"], np.array([[model.mu]])


def linear_stability(model: SliderModel) -> xr.Dataset:
    """Eigenvalues of steady sliding (the 6x6 Jacobian at the static point, docs/model.md §4).

    Returns
    -------
    xarray.Dataset
        ``eigenvalue`` (complex, 1/s) on dim ``eigenvalue``; per mode (``friction``, ``torsion``,
        ``normal``, labelled by eigenvector participation) ``mode_growth_rate`` [1/s] and
        ``mode_frequency`` [rad/s]; scalars ``growth_rate`` (the largest), ``linear_frequency`` (of
        the least stable mode), ``stable`` and ``normal_mode_frequency`` [Hz] (the wear model's
        ``f``): the names of a sweep's variables.

    Examples
    --------
    >>> import tribosweep as ts
    >>> ds = ts.linear_stability(ts.SliderModel())
    >>> round(float(ds.mode_frequency.sel(mode="torsion")), 2), bool(ds.stable)
    (646.63, True)
    """
    model = _model(model)
    names, values = _one(model)
    out = _core.linear_stability(model.values(), model.contact, model.friction_law, names, values, threads=1)
    return xr.Dataset(
        {
            "eigenvalue_real": (("eigenvalue",), out["eigenvalues"][0].real, {"units": "s-1", "long_name": "real part of the eigenvalue (growth rate)"}),
            "eigenvalue_imag": (("eigenvalue",), out["eigenvalues"][0].imag, {"units": "rad s-1", "long_name": "imaginary part of the eigenvalue (frequency)"}),
            "mode_growth_rate": (("mode",), out["mode_growth_rate"][0], {"units": "s-1", "long_name": "growth rate of the mode (> 0: unstable)"}),
            "mode_frequency": (("mode",), out["mode_frequency"][0], {"units": "rad s-1", "long_name": "angular frequency of the mode"}),
            "growth_rate": ((), out["growth_rate"][0], {"units": "s-1", "long_name": "largest growth rate"}),
            "linear_frequency": ((), out["linear_frequency"][0], {"units": "rad s-1", "long_name": "frequency of the least stable mode"}),
            "stable": ((), bool(out["stable"][0]), {"long_name": "steady sliding is linearly stable"}),
            "normal_mode_frequency": ((), out["normal_mode_frequency"][0], {"units": "Hz", "long_name": "frequency of the normal mode in steady sliding"}),
            "status": ((), np.uint8(out["status"][0]), flag_attrs(STATUS_NAMES, "status of the computation")),
        },
        coords={"mode": ("mode", list(out["mode_names"])), "eigenvalue": ("eigenvalue", np.arange(6))},
    )


def hopf_load(model: SliderModel, load_range: tuple[float, float] = (1.0, 250.0), *, n_grid: int = 400) -> list[dict]:
    """Normal loads [N] where steady sliding changes stability (only ``z_st`` and ``K_s`` follow the load).

    Parameters
    ----------
    model : SliderModel
    load_range : (float, float), N
        Search interval, ``0 < low < high``.
    n_grid : int
        Log-spaced bracketing grid points (a crossing pair closer than the grid spacing can be missed).

    Returns
    -------
    list of dict
        One per crossing: ``normal_load`` [N], ``direction`` (``stable_to_unstable`` or
        ``unstable_to_stable`` as the load increases), ``mode``, ``frequency`` [rad/s],
        ``extrapolated`` (outside the contact law's 22-93 N identification range).

    Examples
    --------
    >>> import tribosweep as ts
    >>> round(ts.hopf_load(ts.SliderModel())[0]["normal_load"], 2)
    24.9
    """
    model = _model(model)
    lo, hi = (_checks.positive("load_range[0]", load_range[0]), _checks.positive("load_range[1]", load_range[1]))
    if not lo < hi:
        raise ValueError(f"load_range = {load_range!r}: must have low < high")
    if not (isinstance(n_grid, int) and n_grid >= 3):
        raise ValueError(f"n_grid = {n_grid!r} is out of range: must be an integer >= 3")
    return _core.hopf_loads(model.values(), model.friction_law, lo, hi, n_grid)


_ROOT_VARS = {
    "omega": ("rad s-1", "angular frequency w of the fundamental"),
    "A0": ("m", "mean of z"),
    "A1": ("m", "amplitude of the first harmonic of z"),
    "A2": ("m", "amplitude of the second harmonic of z"),
    "theta": ("rad", "phase of z2 relative to z1"),
    "phi0": ("rad", "mean twist"),
    "x0": ("m", "mean of x"),
    "phi1_amplitude": ("rad", "amplitude of the first harmonic of phi"),
    "phi1_phase": ("rad", "phase of phi1 relative to z1, in (-pi, pi]"),
    "phi2_amplitude": ("rad", "amplitude of the second harmonic of phi"),
    "phi2_phase": ("rad", "phase of phi2 relative to z1"),
    "x1_amplitude": ("m", "amplitude of the first harmonic of x"),
    "x1_phase": ("rad", "phase of x1 relative to z1, in (-pi, pi]"),
    "z_max": ("m", "largest z of the two-harmonic waveform"),
    "z_min": ("m", "smallest z of the two-harmonic waveform"),
    "third_harmonic_ratio": ("1", "third harmonic of F_z dropped by the describing function, relative to the first two"),
    "residual": ("1", "scaled residual of the harmonic balance at the root"),
}


def describing_function(
    model: SliderModel,
    *,
    omega_range: tuple[float, float] | None = None,
    variant: str = "consistent",
    n_grid: int = 1000,
) -> xr.Dataset:
    """All roots of the triple-input describing function (docs/model.md §5) in a frequency box.

    ``z = A0 + A1 sin(psi) + A2 sin(2 psi + theta)``, ``psi = w t``. The search brackets zeros on a
    grid in ``w`` (with ``A0, A1, A2, theta`` eliminated in closed form), refines them with Newton on
    the five real equations, deduplicates and checks the residual. "No root" is a valid answer;
    near a Hopf load the amplitude goes to 0 and the outcome is ``below_resolution``.

    Parameters
    ----------
    model : SliderModel
    omega_range : (float, float), rad/s, optional
        Search box, default (150, 3000).
    variant : {"consistent", "dead_load"}
        ``consistent``: the fixed-block mean balance implied by the ODE (default); ``dead_load``:
        the report's eq. 46 (mean dynamic contact force zero).
    n_grid : int
        Base grid points (refined near the torsional resonances).

    Returns
    -------
    xarray.Dataset
        Variables on dim ``root`` (sorted by ``omega``): ``omega, A0, A1, A2, theta``, the phasors
        of ``phi`` and ``x``, ``residual``, and flags ``physical`` (``|A0| < |z_st|`` and ``w``
        within 5 % of the torsion mode), ``contact_opens`` (the pin leaves the disk on the
        two-harmonic ``z``: outside the bilateral law's validity), ``third_harmonic_ratio``.
        Attribute ``search_outcome``: ``roots``, ``no_root`` or ``below_resolution``.

    Examples
    --------
    >>> import tribosweep as ts
    >>> ds = ts.describing_function(ts.SliderModel())
    >>> phys = ds.where(ds.physical == 1, drop=True)
    >>> round(float(phys.omega[0]), 3)
    647.559
    """
    model = _model(model)
    w_min, w_max = omega_range if omega_range is not None else (150.0, 3000.0)
    w_min, w_max = _checks.positive("omega_range[0]", w_min), _checks.positive("omega_range[1]", w_max)
    if not w_min < w_max:
        raise ValueError(f"omega_range = {omega_range!r}: must have low < high")
    if variant not in ("consistent", "dead_load"):
        raise ValueError(f"variant = {variant!r} is not valid: must be 'consistent' or 'dead_load'")
    if not (isinstance(n_grid, int) and n_grid >= 10):
        raise ValueError(f"n_grid = {n_grid!r} is out of range: must be an integer >= 10")
    names, values = _one(model)
    out = _core.describing_function(model.values(), model.contact, model.friction_law, names, values, variant=variant,
                                    w_min=w_min, w_max=w_max, n_base=n_grid, threads=1)
    n = int(out["n_roots"][0])
    data = {k: (("root",), out[k][0, :n], {"units": u, "long_name": t}) for k, (u, t) in _ROOT_VARS.items()}
    data["physical"] = (("root",), out["physical"][0, :n], {"long_name": "root near the torsion mode with |A0| < |z_st|", "flag_values": np.array([0, 1], dtype=np.int8), "flag_meanings": "flagged physical"})
    data["contact_opens"] = (("root",), out["contact_opens"][0, :n], {"long_name": "the pin leaves the disk on this root's waveform", "flag_values": np.array([0, 1], dtype=np.int8), "flag_meanings": "closed opens"})
    data["newton_iterations"] = (("root",), out["newton_iterations"][0, :n], {"units": "1", "long_name": "Newton iterations of the polish"})
    return xr.Dataset(
        data,
        coords={"root": ("root", np.arange(n))},
        attrs={"search_outcome": out["search_outcome"][0], "variant": variant, "status": int(out["status"][0]),
               "n_grid": int(out["n_grid"][0]), "omega_min": w_min, "omega_max": w_max},
    )


def periodic_orbit(
    model: SliderModel,
    guess: xr.Dataset | tuple[Sequence[float], float],
    *,
    rtol: float = 1e-11,
    tol: float = 1e-9,
    max_iter: int = 30,
) -> xr.Dataset:
    """Periodic orbit of the full ODE by shooting (phase condition ``zd(0) = 0``), with Floquet multipliers.

    Parameters
    ----------
    model : SliderModel
        Bilateral or unilateral contact (switches are handled with saltation matrices).
    guess : Dataset or (y0, period)
        One root of :func:`describing_function` (``ds.isel(root=i)``), or a state on (or near) the
        orbit ``y0`` (6,) with a period guess [s].
    rtol : float
        Integration tolerance of the shooting.
    tol : float
        Newton tolerance on the scaled periodicity residual.
    max_iter : int
        Newton iterations.

    Returns
    -------
    xarray.Dataset
        ``period`` [s], ``omega``, ``floquet_multipliers`` (complex, by modulus descending) and their
        ``floquet_moduli``, ``stable``, ``instability`` (stable, fold, flip, torus), ``flip_multiplier`` and
        ``period_doubling`` (a real multiplier below ``-1 + FLIP_TOL``), harmonics of z (``A0, A1, A2, A3, theta``), ``z_max``,
        ``contact_opens``, ``fraction_off_disk``, ``min_normal_force``, ``status``, ``reason``, cost.

        When no orbit was found (``status`` other than success: Newton did not converge within
        ``max_iter``, it ended on steady sliding, an integration failed), every value of the orbit is
        NaN (never the last Newton iterate), ``instability`` is ``unknown``, the flags ``stable``,
        ``contact_opens`` and ``period_doubling`` are absent (unset: not known), and ``reason`` says
        why, with its numbers; ``residual``, ``newton_iterations`` and the cost describe the attempt.
    """
    model = _model(model)
    rtol = _checks.rtol(rtol)
    tol = _checks.positive("tol", tol)
    if isinstance(guess, xr.Dataset):
        try:
            root = np.array([float(guess[k]) for k in ("omega", "A0", "A1", "A2", "theta")])
        except (KeyError, TypeError) as e:
            raise ValueError(f"guess must be one root of describing_function (ds.isel(root=i)): {e}") from None
        variant = guess.attrs.get("variant", "consistent")
        out = _core.periodic_orbit(model.values(), model.contact, model.friction_law, root=root, variant=variant,
                                   rtol=rtol, max_iter=max_iter, tol=tol)
    else:
        try:
            y0, period = guess
        except (TypeError, ValueError):
            raise ValueError("guess must be a describing_function root or a (y0, period) pair") from None
        y0 = _checks.state("guess y0", y0)
        period = _checks.positive("guess period", period)
        out = _core.periodic_orbit(model.values(), model.contact, model.friction_law, y0=y0, period=period,
                                   rtol=rtol, max_iter=max_iter, tol=tol)
    mult = np.array(out["multipliers_re"]) + 1j * np.array(out["multipliers_im"])
    scalars = {
        "period": ("s", "period of the orbit"),
        "omega": ("rad s-1", "angular frequency 2 pi / period"),
        "A0": ("m", "mean of z"),
        "A1": ("m", "first harmonic of z"),
        "A2": ("m", "second harmonic of z"),
        "A3": ("m", "third harmonic of z"),
        "theta": ("rad", "phase of z2 relative to z1"),
        "z_max": ("m", "largest z on the orbit"),
        "z_min": ("m", "smallest z on the orbit"),
        "fraction_off_disk": ("1", "fraction of the period with the pin off the disk (zc > 0)"),
        "min_normal_force": ("N", "smallest total normal force"),
        "residual": ("1", "scaled periodicity residual"),
        "trivial_error": ("1", "|rho - 1| of the trivial Floquet multiplier (accuracy check)"),
    }
    data = {k: ((), out[k], {"units": u, "long_name": t}) for k, (u, t) in scalars.items()}
    data["floquet_multiplier_real"] = (("floquet",), mult.real, {"units": "1", "long_name": "Floquet multiplier, real part"})
    data["floquet_multiplier_imag"] = (("floquet",), mult.imag, {"units": "1", "long_name": "Floquet multiplier, imaginary part"})
    data["floquet_moduli"] = (("floquet",), np.array(out["moduli"]), {"units": "1", "long_name": "moduli of the Floquet multipliers"})
    data["state0"] = (("state",), np.array(out["state0"]), {"long_name": "state at t = 0 (zd = 0)"})
    found = out["stable"] is not None  # unset when no orbit was found
    if found:
        data["stable"] = ((), bool(out["stable"]), {"long_name": "every non-trivial multiplier inside the unit circle"})
    data["instability"] = ((), np.uint8(out["instability"]),
                           flag_attrs(INSTABILITY_NAMES, "how the orbit is unstable (its largest non-trivial multiplier)"))
    data["flip_multiplier"] = ((), out["flip_multiplier"], {
        "units": "1", "long_name": "most negative real non-trivial Floquet multiplier (NaN if none)",
        "comment": "near -1 the orbit is close to a period doubling; below -1 it is unstable and the attractor "
                   "nearby has twice the period (see period_doubling)"})
    if found:
        data["period_doubling"] = ((), bool(np.isfinite(out["flip_multiplier"]) and out["flip_multiplier"] < -1.0 + FLIP_TOL), {
            "long_name": f"a real multiplier below -1 + {FLIP_TOL}: at or past a period doubling",
            "comment": "the period-1 orbit is (or is about to be) unstable by a flip; a solve for the doubled orbit is "
                       "ill-conditioned here. Confirm the attractor with a transient."})
        data["contact_opens"] = ((), bool(out["contact_opens"]), {"long_name": "the pin leaves the disk on the orbit"})
    data["status"] = ((), np.uint8(out["status"]), flag_attrs(STATUS_NAMES, "status of the shooting solve"))
    data["reason"] = ((), str(out["reason"]), {"long_name": "why the status is not success (empty if it is)"})
    for k in ("newton_iterations", "n_rhs", "n_accept", "n_reject", "n_switches"):
        data[k] = ((), np.int64(out[k]), {"units": "1", "long_name": k.replace("_", " ")})
    ds = xr.Dataset(data, coords={"floquet": np.arange(6), "state": ["z", "z_dot", "x", "x_dot", "phi", "phi_dot"]})
    ds["floquet_multipliers"] = xr.DataArray(mult, dims=("floquet",))
    return ds


def follow_cycle(
    model: SliderModel,
    *,
    parameter: str = "mu",
    start: float = 0.30,
    step: float = 0.005,
    t_settle: float = 30.0,
    rtol: float = 1e-11,
) -> tuple[xr.Dataset, list[dict]]:
    """A stable cycle of ``model``, found where it is robust and followed to the model's own parameter.

    A cycle that coexists with stable sliding is found unreliably by one transient: the start lands
    near a basin boundary, and the outcome flips with the last bit of a float. This runs a
    transient at ``parameter = start``, where the cycle is the only attractor a small disturbance
    grows into (the seed's bouncing cycle at ``mu = 0.30``, where sliding is unstable), shoots the
    cycle there, and follows it to ``model``'s value in steps of at most ``step`` (natural-parameter
    continuation: each solve starts from the last orbit). The result is the orbit's, not a trajectory's.

    Parameters
    ----------
    model : SliderModel
        The target (usually ``contact="unilateral"``).
    parameter : str
        The real SliderModel field to follow (default ``mu``).
    start : float
        Its value where the cycle is robust.
    step : float
        Largest continuation step (> 0).
    t_settle : float, s
        Longest transient at ``start``.
    rtol : float
        Integration tolerance of the shooting.

    Returns
    -------
    (xarray.Dataset, list of dict)
        The orbit at ``model`` (as :func:`periodic_orbit`) and the path: one dict per step with the
        parameter, ``status``, ``omega``, ``A1`` and ``stable``.

    Raises
    ------
    ValueError
        Bad arguments, or the transient at ``start`` settles on no cycle, or a step fails to converge
        (the message names the parameter value).

    Examples
    --------
    >>> import tribosweep as ts
    >>> orb, path = ts.follow_cycle(ts.SliderModel(contact="unilateral"))
    >>> round(float(orb.omega), 3), bool(orb.stable), len(path)
    (640.371, True, 18)
    """
    from ._model import PARAM_NAMES
    from ._simulate import ensemble

    model = _model(model)
    if parameter not in PARAM_NAMES:
        raise ValueError(f"parameter = {parameter!r} is not valid: must be a real SliderModel field {PARAM_NAMES}")
    step = _checks.positive("step", step)
    t_settle = _checks.positive("t_settle", t_settle)
    target = float(getattr(model, parameter))
    hot = model.replace(**{parameter: float(start)})
    run = ensemble(hot, t_settle, {parameter: [float(start)]}, y0=[0.1e-6, 0, 0, 0, 0, 0], steady=True, rtol=1e-9,
                   method="dop853")  # fmt: skip
    if OUTCOME_NAMES[int(run.outcome[0])] != "periodic":
        raise ValueError(f"start = {start!r}: the transient at {parameter} = {start} settled on no cycle "
                         f"({OUTCOME_NAMES[int(run.outcome[0])]}); choose a start where the cycle is the attractor")  # fmt: skip
    y = np.array([float(run[f"{v}_end"][0]) for v in ("z", "z_dot", "x", "x_dot", "phi", "phi_dot")])
    period = float(run.period[0])
    n = max(1, int(np.ceil(abs(target - start) / step - 1e-9)))
    path = []
    orb = None
    for k in range(n + 1):
        value = target if k == n else float(start) + (target - float(start)) * k / n
        orb = periodic_orbit(model.replace(**{parameter: value}), (y, period), rtol=rtol)
        if int(orb.status) != STATUS["success"]:
            raise ValueError(f"the cycle could not be followed to {parameter} = {value:g}: shooting ended with "
                             f"{STATUS_NAMES[int(orb.status)]} ({orb.reason.item()}); try a smaller step")  # fmt: skip
        path.append({parameter: value, "status": int(orb.status), "omega": float(orb.omega), "A1": float(orb.A1),
                     "stable": bool(orb.stable)})  # fmt: skip
        y, period = orb.state0.values, float(orb.period)
    return orb, path
