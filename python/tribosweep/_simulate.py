"""Time-domain API: one trajectory (`simulate`) and many in parallel (`ensemble`)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import xarray as xr

from . import _checks, _core, _cycles, _irregular, _settings
from ._codes import OUTCOME_NAMES, STATUS_NAMES, flag_attrs
from ._model import PARAM_LONG_NAMES, PARAM_NAMES, PARAM_UNITS, SliderModel
from ._settings import DEFAULTS

#: Default initial disturbance: z = 1 um, everything else at rest on the static point.
DEFAULT_Y0 = np.array(_settings.DEFAULT_Y0)

#: State components: (name, units, long name).
STATE_VARS: tuple[tuple[str, str, str], ...] = (
    ("z", "m", "normal displacement from the static point (positive away from the disk)"),
    ("z_dot", "m s-1", "normal velocity"),
    ("x", "m", "frictional displacement"),
    ("x_dot", "m s-1", "frictional velocity"),
    ("phi", "rad", "twist of the arm"),
    ("phi_dot", "rad s-1", "twist rate"),
)

_RUN_VARS = {
    "t_reached": ("s", "time reached by the integration"),
    "min_normal_force": ("N", "minimum total normal force at step ends and events"),
    "max_gap": ("m", "largest pin position relative to the disk surface zc = z_st + z (> 0: contact open)"),
    "min_slip_velocity": ("m s-1", "minimum sliding velocity v_r (<= 0: stick-slip)"),
    "max_abs_z": ("m", "largest |z|"),
}
_STAT_VARS = {
    "n_rhs": "right-hand-side evaluations",
    "n_jac": "Jacobian evaluations",
    "n_lu": "LU decompositions",
    "n_accept": "accepted steps",
    "n_reject": "rejected steps",
    "n_events": "located events",
}


def _check_common(model, t_end, method, rtol, atol, t_eval):
    if not isinstance(model, SliderModel):
        raise TypeError(f"model = {model!r} must be a tribosweep.SliderModel")
    t_end = _checks.positive("t_end", t_end)
    return (
        t_end,
        _checks.method(method),
        _checks.rtol(rtol),
        _checks.atol(atol),
        _checks.times("t_eval", t_eval, t_end),
    )


def _status_vars(out: dict, dims: tuple[str, ...]) -> dict:
    v = {
        "status": (dims, np.asarray(out["status"], dtype=np.uint8), flag_attrs(STATUS_NAMES, "status of the computation")),
        "reason": (dims, np.asarray(out["reason"], dtype=str), {"long_name": (
            "reason for a non-success status; with steady=True also how an irregular or slow-approach run ended")}),
    }
    for k, text in _STAT_VARS.items():
        v[k] = (dims, np.asarray(out[k], dtype=np.int64), {"long_name": text, "units": "1"})
    return v


def _run_vars(out: dict, dims: tuple[str, ...]) -> dict:
    v = _status_vars(out, dims)
    for k, (units, text) in _RUN_VARS.items():
        v[k] = (dims, np.asarray(out[k]), {"units": units, "long_name": text})
    return v


def _model_attrs(model: SliderModel, method: str, rtol: float) -> dict:
    attrs = {f"model_{k}": v for k, v in model.values().items()}
    attrs.update(model_contact=model.contact, model_friction_law=model.friction_law, method=method, rtol=rtol)
    return attrs


def simulate(
    model: SliderModel,
    t_end: float,
    *,
    y0: Sequence[float] | None = None,
    method: str = DEFAULTS.integration.integrator,
    rtol: float = DEFAULTS.integration.rtol,
    atol: float | Sequence[float] | None = None,
    t_eval: Sequence[float] | None = None,
    max_steps: int | None = None,
    max_events: int | None = None,
) -> xr.Dataset:
    """Integrate one trajectory of ``model`` from ``t = 0`` to ``t_end``.

    Parameters
    ----------
    model : SliderModel
        The slider.
    t_end : float, s
        End time (> 0).
    y0 : array_like (6,), optional
        Initial state ``[z (m), z_dot (m/s), x (m), x_dot (m/s), phi (rad), phi_dot (rad/s)]``,
        measured from the static point. Default ``DEFAULT_Y0`` (``z = 1 um``).
    method : {"dop853", "dopri5", "rodas4"}
        Integrator: DOP853 (8th order; the default, as in sweeps: on the issue-10 ensemble at rtol
        1e-6 it is 1.4-2.1x faster than Dormand-Prince 5(4) on every lane path, with a fifth of
        its error), Dormand-Prince 5(4), or the stiffly accurate Rosenbrock Rodas4 (for stiff
        friction regularisation).
    rtol : float
        Relative tolerance, in [1e-15, 1).
    atol : float or array_like (6,), optional
        Absolute tolerance per component. Default: ``rtol`` times each component's characteristic
        size (``|z_st|`` for z and x, ``|z_st|/L`` for phi, those times ``omega_torsion`` for rates).
    t_eval : array_like, s, optional
        Increasing output times in ``[0, t_end]``; default: every accepted step.
    max_steps : int, optional
        Step budget (accepted + rejected; default 10^7): beyond it the run ends with status ``max_steps``.
    max_events : int, optional
        Event budget (default 10^7): beyond it the run ends with status ``event_chatter``.

    Returns
    -------
    xarray.Dataset
        Variables ``z, z_dot, x, x_dot, phi, phi_dot`` on dimension ``time``, and the run's
        ``status`` (0 = success; see ``tribosweep.STATUS_NAMES``) with its ``reason`` (for every
        other status, why, with its numbers: the time reached, the step size against its floor and
        the tolerance, the step or event budget; empty for success), work counters, and extremes
        (``min_normal_force``, ``max_gap``, ``min_slip_velocity``) as scalar variables.

    Raises
    ------
    ValueError
        A bad argument, before any work.
    KeyboardInterrupt
        Ctrl-C (SIGINT) stops the integration within about a second, however long it would run.

    Examples
    --------
    >>> import tribosweep as ts
    >>> ds = ts.simulate(ts.SliderModel(), 0.01, t_eval=[0.0, 0.005, 0.01])
    >>> int(ds.status), ds.z.shape
    (0, (3,))
    """
    t_end, method, rtol, atol, t_eval = _check_common(model, t_end, method, rtol, atol, t_eval)
    y0 = _checks.state("y0", DEFAULT_Y0 if y0 is None else y0)
    max_steps = _checks.budget("max_steps", max_steps)
    max_events = _checks.budget("max_events", max_events)
    out = _core.simulate(model.values(), model.contact, model.friction_law, y0, t_end, method, rtol, atol=atol,
                         t_eval=t_eval, max_steps=max_steps, max_events=max_events)
    data = {
        name: (("time",), out["y"][:, i], {"units": units, "long_name": text})
        for i, (name, units, text) in enumerate(STATE_VARS)
    }
    scalar = {k: ((), v[1][0], v[2]) for k, v in _run_vars(out, ("trajectory",)).items()}
    data.update(scalar)
    return xr.Dataset(
        data,
        coords={"time": ("time", out["t"], {"units": "s", "long_name": "time"})},
        attrs=_model_attrs(model, method, rtol),
    )


def ensemble(
    model: SliderModel,
    t_end: float,
    params: dict[str, Sequence[float]],
    *,
    y0: Sequence[float] | Sequence[Sequence[float]] | None = None,
    method: str = DEFAULTS.integration.integrator,
    rtol: float = DEFAULTS.integration.rtol,
    atol: float | Sequence[float] | None = None,
    t_eval: Sequence[float] | None = None,
    threads: int | None = None,
    steady: bool = False,
    periodic_tol: float = DEFAULTS.steady.periodic_tol,
    decay_amplitude: float | None = None,
    max_steps: int | None = None,
    max_events: int | None = None,
    check_cycles: bool = False,
    irregular_block: int = 0,
    approach_periods: int = 0,
) -> xr.Dataset:
    """Integrate many parameter sets of ``model`` in parallel (GIL released, Rust threads).

    Results are bit-identical for any ``threads``; a point that fails gets a status code and a
    reason, and never stops the others.

    Parameters
    ----------
    model : SliderModel
        Base model; ``params`` override some of its real fields per trajectory.
    t_end : float, s
        End time (> 0); with ``steady=True`` the longest simulated time.
    params : dict of str to 1-D array_like
        ``{field name: values}``, all of the same length ``n`` (e.g. ``{"mu": ..., "normal_load": ...}``).
    y0 : array_like (6,) or (n, 6), optional
        Initial state(s); default ``DEFAULT_Y0``.
    method, rtol, atol
        As in :func:`simulate`.
    t_eval : array_like, s, optional
        Output times: adds ``z, ..., phi_dot`` on ``(trajectory, time)``.
    threads : int, optional
        Worker threads; default ``TRIBOSWEEP_THREADS`` or all cores.
    steady : bool
        Run each trajectory to its steady state (decay, periodic cycle, escape, or ``t_end``) and
        return its summary: ``outcome``, ``omega``, harmonics of z, phi, x, minimum normal force,
        fraction of the period off the disk, minimum sliding velocity, and the state where the run
        ended (``z_end, ...``: on the cycle's section for a periodic outcome, a start for shooting).
        A periodic outcome is the run's stop, where its section state repeated to
        ``periodic_tol``: near a slowly attracting cycle about ``periodic_tol / (1 - |mu|)`` from
        it (0.7 % in A1 on the Stribeck sweep), near an unstable one (intermittent motion) not a
        steady state at all. ``check_cycles=True`` checks each such stop as a sweep does. A run
        that reaches ``t_end`` unsettled reports its closest repetition (``nearest_residual``,
        ``nearest_multiplicity``, ``nearest_period``): a slowly attracting cycle not yet worked
        off shows as a residual a little above ``periodic_tol``.
    periodic_tol : float
        Relative repetition tolerance of the Poincare-section state that declares a cycle.
    decay_amplitude : float, m, optional
        Amplitude below which a shrinking motion counts as decayed (default ``1e-3 |z_st|``).
    max_steps, max_events : int, optional
        Per-trajectory step and event budgets, as in :func:`simulate`.
    check_cycles : bool
        With ``steady=True``: shoot from every periodic stop (Floquet multipliers, at ten times
        ``rtol``). A stable orbit is measured by a run started on it, so its quantities are the
        orbit's; from an unstable one the run goes on with the time it has left; a failed check
        leaves the stop, with a reason. Adds ``cycle_verified``. Without it a stop is reported as
        it was (:func:`periodic_orbit` from ``(z_end, ...)`` and ``period`` converges one). An
        unsettled run whose closest repetition is within ``_cycles.NEAREST_TOL`` (1e-2) is shot
        from too: a stable orbit of that period becomes its outcome, ``periodic``, with a reason
        that says so (a slow approach).
    irregular_block : int
        With ``steady=True``: sections per block of the stationarity test that ends sustained
        irregular motion early (outcome ``irregular``, with a reason): three blocks in a row whose
        mean repetition residual agrees to 25 % and is at least 1e-3 of the characteristic sizes,
        and each component's largest excursion to 5 % (or drifts by less). A sweep's transients use
        128 (``DEFAULTS.irregular.transient_block``). 0 (default): such a run goes on to ``t_end``
        (``unsettled``). Transient chaos that settles after three stationary blocks is called
        irregular: the census, many disturbances per point, is what tells such points.
    approach_periods : int
        With ``steady=True``: periods per block of the slow-approach test (a sweep's transients: 10,
        ``DEFAULTS.steady.approach_periods``; 0, the default: off). Once the repetition residual's
        envelope has shrunk three blocks in a row to at most 1e-3, the run shoots from its section
        inside the run (at ten times ``rtol``): a stable orbit of that period ends the run on it,
        measured there (``approach`` true); near an unstable one the run goes on, and its third
        return to the same unstable cycle after bursts ends it as intermittent (outcome
        ``irregular``; ``intermittent_period``, ``intermittent_multiplier``,
        ``intermittent_visits``, ``intermittent_instability``: Pomeau-Manneville's type I for a
        fold, III for a flip, II for a torus).

    Returns
    -------
    xarray.Dataset
        Dimension ``trajectory`` with the overridden parameters as coordinates; per trajectory
        ``status`` and ``reason`` (why the status is not success, with its numbers, as in
        :func:`simulate`; with ``steady=True`` also a run that reached ``t_end`` unsettled).

    Raises
    ------
    ValueError
        A bad argument, before any work.
    KeyboardInterrupt
        Ctrl-C (SIGINT) stops every thread within about a second; the results are discarded.
    """
    t_end, method, rtol, atol, t_eval = _check_common(model, t_end, method, rtol, atol, t_eval)
    names, values = _checks.param_arrays(params, PARAM_NAMES)
    n = values.shape[0]
    y0 = _checks.state("y0", DEFAULT_Y0 if y0 is None else y0, n)
    threads = _checks.threads(threads)
    periodic_tol = _checks.positive("periodic_tol", periodic_tol)
    if decay_amplitude is not None:
        decay_amplitude = _checks.positive("decay_amplitude", decay_amplitude)
    max_steps = _checks.budget("max_steps", max_steps)
    max_events = _checks.budget("max_events", max_events)
    kind = "steady" if steady else ("sampled" if t_eval is not None else "final")
    if steady and t_eval is not None:
        raise ValueError("t_eval cannot be combined with steady=True: a steady run returns a summary")
    if check_cycles and not steady:
        raise ValueError("check_cycles = True needs steady=True: only a run to steady state stops on a cycle")
    irregular_block = _checks.block("irregular_block", irregular_block)
    approach_periods = _checks.approach_periods("approach_periods", approach_periods)
    for name, v in (("irregular_block", irregular_block), ("approach_periods", approach_periods)):
        if v and not steady:
            raise ValueError(f"{name} = {v} needs steady=True: only a run to steady state has these tests")
    shoot_rtol = _cycles.check_rtol(rtol, DEFAULTS.shooting.rtol)

    def run(idx, starts, restart=None, approach=0):
        # Slow-approach checks in the first runs only, as a sweep's transients: a restart goes on
        # from an unstable cycle's neighbourhood to where the run really goes.
        tests = dict(irregular_block=irregular_block, approach_periods=approach, approach_rtol=shoot_rtol,
                     approach_tol=DEFAULTS.shooting.tol) if steady else {}  # fmt: skip
        return _core.ensemble(
            model.values(), model.contact, model.friction_law, names, np.ascontiguousarray(values[idx]),
            np.ascontiguousarray(np.atleast_2d(starts)), t_end, method, rtol, atol=atol, t_eval=t_eval,
            threads=threads, kind=kind, periodic_tol=periodic_tol, decay_amplitude=decay_amplitude, n_fourier=512,
            max_steps=max_steps, max_events=max_events, restart=restart, **tests,
        )  # fmt: skip

    out = run(np.arange(n), y0, approach=approach_periods)
    verified = None
    if check_cycles:
        out, verified = _cycles.check(out, lambda idx, y, p, z1, size: _cycles.shoot(
            model.values(), model.contact, model.friction_law, names, values[idx], y, p, z1, size, rtol=shoot_rtol,
            tol=DEFAULTS.shooting.tol, threads=threads), run, t_end)  # fmt: skip
    if steady:
        # A stationary or intermittent stop is an answer, as in a sweep: say which, and when.
        irregular = np.flatnonzero(np.asarray(out["outcome"]) == OUTCOME_NAMES.index("irregular"))
        if irregular.size:
            out["reason"] = np.asarray(out["reason"], dtype=object)
            for i in irregular:
                out["reason"][i] = _irregular.stop_reason(out, int(i), t_end, irregular_block)
    dims = ("trajectory",)
    coords = {"trajectory": ("trajectory", np.arange(n))}
    for i, k in enumerate(names):
        coords[k] = (dims, values[:, i], {"units": PARAM_UNITS[k], "long_name": PARAM_LONG_NAMES[k]})
    if steady:
        data = _status_vars(out, dims)
        data["outcome"] = (dims, out["outcome"], flag_attrs(OUTCOME_NAMES, "how the run to steady state ended"))
        summary_units = {
            "t_end": ("s", "simulated time when the steady state was recognised"),
            "omega": ("rad s-1", "angular frequency of the fundamental"),
            "period": ("s", "period of the cycle"),
            "z0": ("m", "mean of z over the period"),
            "z_half_range": ("m", "half of z's range over the period (the size of the motion)"),
            "z1_amplitude": ("m", "amplitude of the first harmonic of z"),
            "z2_amplitude": ("m", "amplitude of the second harmonic of z"),
            "z3_amplitude": ("m", "amplitude of the third harmonic of z"),
            "z1_phase": ("rad", "phase of z1 (0 by definition)"),
            "z2_phase": ("rad", "phase theta of z2 relative to z1"),
            "z3_phase": ("rad", "phase of z3 relative to z1"),
            "phi1_amplitude": ("rad", "amplitude of the first harmonic of phi"),
            "phi1_phase": ("rad", "phase of phi1 relative to z1"),
            "x1_amplitude": ("m", "amplitude of the first harmonic of x"),
            "x1_phase": ("rad", "phase of x1 relative to z1"),
            "min_normal_force": ("N", "minimum total normal force (over the period if periodic)"),
            "fraction_off_disk": ("1", "fraction of the period with the pin off the disk (zc > 0)"),
            "min_slip_velocity": ("m s-1", "minimum sliding velocity v_r"),
            "max_gap": ("m", "largest zc = z_st + z over the run"),
            "max_abs_z": ("m", "largest |z| over the run"),
        }
        for k, (units, text) in summary_units.items():
            data[k] = (dims, out[k], {"units": units, "long_name": text})
        data["multiplicity"] = (dims, out["multiplicity"], {"units": "1", "long_name": "section crossings per period"})
        # An unsettled run's closest repetition: a slowly attracting cycle shows as a small residual.
        data["nearest_residual"] = (dims, out["nearest_residual"], {"units": "1", "long_name": (
            "unsettled: the newest section state's smallest repetition residual after 1-8 sections, relative to "
            "each component's amplitude (periodic_tol is its threshold)")})  # fmt: skip
        data["nearest_multiplicity"] = (dims, out["nearest_multiplicity"], {
            "units": "1", "long_name": "unsettled: section crossings of that closest repetition (0: none)"})
        data["nearest_period"] = (dims, out["nearest_period"], {
            "units": "s", "long_name": "unsettled: time over the crossings of that closest repetition"})
        # The stationarity and slow-approach tests' findings (approach_periods, irregular_block).
        data["approach"] = (dims, np.asarray(out["approach"], dtype=bool), {"long_name": (
            "periodic: the run stopped on a slow approach that shooting inside the run converged to a stable orbit, "
            "and its quantities were measured on the orbit")})  # fmt: skip
        data["irregular_residual"] = (dims, out["irregular_residual"], {"units": "1", "long_name": (
            "irregular (stationary): mean repetition residual of the section state over the three stationary "
            "blocks, in characteristic sizes")})  # fmt: skip
        data["intermittent_period"] = (dims, out["intermittent_period"], {"units": "s", "long_name": (
            "intermittent: period of the unstable cycle the laminar phases returned to (NaN elsewhere)")})
        data["intermittent_multiplier"] = (dims, out["intermittent_multiplier"], {"units": "1", "long_name": (
            "intermittent: modulus of that cycle's largest non-trivial Floquet multiplier")})
        data["intermittent_visits"] = (dims, out["intermittent_visits"], {"units": "1", "long_name": (
            "intermittent: returns to that cycle counted, each after a burst (0 elsewhere)")})
        data["intermittent_instability"] = (dims, np.asarray(out["intermittent_instability"], dtype=np.uint8),
                                            flag_attrs(("not_intermittent", "fold", "flip", "torus"), (
                                                "intermittent: how that cycle is unstable (fold, flip, torus: "
                                                "Pomeau-Manneville types I, III, II)")))  # fmt: skip
        if verified is not None:
            data["cycle_verified"] = (dims, np.where(out["outcome"] == _cycles.PERIODIC, verified, -1).astype(np.int8),
                                      flag_attrs(("no_cycle", "not_verified", "verified"), "whether shooting "
                                                 "converged the run's cycle to a stable orbit, on which its "
                                                 "quantities were measured", (-1, 0, 1), "i1"))  # fmt: skip
        for i, (name, units, text) in enumerate(STATE_VARS):
            data[f"{name}_end"] = (dims, out["y_end"][:, i], {
                "units": units, "long_name": f"{text} where the run ended (on the section zd = 0 if periodic)"})
    else:
        data = _run_vars(out, dims)
        for i, (name, units, text) in enumerate(STATE_VARS):
            data[f"{name}_end"] = (dims, out["y_end"][:, i], {"units": units, "long_name": f"{text} at the end"})
        if t_eval is not None:
            coords["time"] = ("time", t_eval, {"units": "s", "long_name": "time"})
            for i, (name, units, text) in enumerate(STATE_VARS):
                data[name] = (("trajectory", "time"), out["y"][:, :, i], {"units": units, "long_name": text})
    attrs = _model_attrs(model, method, rtol)
    attrs["threads"] = -1 if threads is None else threads
    return xr.Dataset(data, coords=coords, attrs=attrs)
