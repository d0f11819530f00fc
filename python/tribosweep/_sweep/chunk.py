"""The work of one sweep chunk: a pure, picklable function of its inputs.

:func:`compute_chunk` is the only thing a worker runs. It is a module-level function of plain
data (dicts of floats, strings and 1-D numpy arrays) with no closures and no global state, so
the same call runs in-process, in a ``concurrent.futures`` pool or on a dask cluster, and gives
the same numbers everywhere (apart from the measured ``wall_time``).

The stages (linear, describing function, shooting, transient, census) are in
:mod:`tribosweep._sweep.stages`, one function each; this module holds the strategies' policy.

The strategies combine them, modelling no more than each point needs:

- ``linear``: eigenvalues only; an unstable point is ``unstable_undetermined`` (by choice: this
  strategy simulates nothing, and says so in the point's reason).
- ``tidf``: linear, then the describing function at every point. Stable points: steady sliding,
  with the saddle amplitude when there is a root. Unstable points: a root without contact opening
  is a predicted cycle (``self_excited``, decided by tidf, flagged as a prediction); otherwise
  ``unstable_undetermined``.
- ``shooting``: as ``tidf``, then the orbit of every physical root (its stability and the DF error).
- ``transient``: every point integrated from the disturbance ``y0`` (``irregular`` where it neither
  repeats nor decays).
- ``auto``: linear; at stable points the describing function; shooting only where the disturbance
  is within a factor ``SHOOT_MARGIN`` of the describing function's amplitude (there the DF's error
  matters); a transient only where those cannot decide: unstable sliding (the DF has no cycle
  there: the bifurcation is subcritical), a disturbance at or beyond the saddle, or a failed stage.
  With ``census`` (default on), a stable point with a saddle cycle also gets the attractor
  census (``tribosweep._census``): K disturbances, each run to its attractor, reported as
  fractions with standard errors; ``bistable`` (coexistence) is derived from it.
"""

from __future__ import annotations

import numpy as np

from .. import _wear
from .._codes import REGIME
from .._settings import SweepSettings
from . import stages
from .schema import OPTIONAL_POINT_VARIABLES

#: Analysis strategies of a sweep.
STRATEGIES: tuple[str, ...] = ("auto", "linear", "tidf", "shooting", "transient")


def dynamics(model_values, contact, friction_law, point_params, strategy: str, settings: SweepSettings, *,
             n_points: int) -> dict:  # fmt: skip
    """Regime and cycle of each point by the stages ``strategy`` calls for (everything but wear)."""
    p = stages.Points(model_values, contact, friction_law, point_params, settings, n_points)
    stages.linear(p)
    auto = strategy == "auto"
    if strategy == "linear":
        p.reason[p.out["regime"] == REGIME["unstable_undetermined"]] = (
            "sliding unstable; the motion was not computed (strategy=linear: eigenvalues only, by choice)")
    elif strategy == "transient":
        p.to_transient[:] = True
    else:
        predict = strategy in ("tidf", "shooting")
        roots = stages.describing_function(p, unstable_too=not auto, predict_cycles=predict, escalate=auto)
        stages.shooting(p, roots, every_root=strategy == "shooting", escalate=auto)
    if auto:
        # Where the cheaper models cannot decide: unstable sliding (the describing function has no
        # cycle there: the bifurcation is subcritical), a disturbance at or beyond the saddle, or a
        # failed stage.
        p.to_transient |= ~p.lin_failed & ~p.stable
    stages.transient(p, start_on_mode=auto)
    if auto and settings.census.enabled:
        stages.census(p)
    return p.finish()


def compute_chunk(
    model_values: dict,
    contact: str,
    friction_law: str,
    point_params: dict[str, np.ndarray],
    strategy: str,
    options: dict,
) -> dict[str, np.ndarray]:
    """Compute one chunk of sweep points: pure, deterministic, picklable.

    Parameters
    ----------
    model_values : dict of str to float
        Base parameters (``SliderModel.values()``, SI units).
    contact : {"bilateral", "unilateral"}
        Contact model of the transient runs.
    friction_law : {"constant", "coulomb", "switch"}
        Friction law.
    point_params : dict of str to 1-D numpy.ndarray
        Per-point overrides of real SliderModel fields, all of length ``n``.
    strategy : {"auto", "linear", "tidf", "shooting", "transient"}
        Analysis strategy (see the module docstring).
    options : dict
        The settings as plain data (:meth:`tribosweep._settings.SweepSettings.to_options`, plus
        ``threads``); ``wear`` is ``{"normal_load": N, "sliding_speed": m/s, "frequency_hz": Hz}`` of
        the reference point, optional ``"calibration"``: ``WearCalibration.as_dict()``.

    Returns
    -------
    dict of str to numpy.ndarray
        The per-point variables of ``POINT_VARIABLES`` (and ``wear_rate`` when calibrated), each
        of length ``n``.
    """
    if strategy not in STRATEGIES:
        raise ValueError(f"strategy = {strategy!r} is not valid: must be one of {STRATEGIES}")
    settings = SweepSettings.from_options(options)

    full = {k: np.asarray(v, dtype=np.float64) for k, v in model_values.items()}
    n = len(next(iter(point_params.values())))
    for k, a in point_params.items():
        full[k] = np.asarray(a, dtype=np.float64)
    wear = options.get("wear") or {}

    # With the constant friction law the sliding speed enters neither the equations nor the
    # static point: it only shifts the sliding velocity v_r = V - (xd + s L phid). Every point's
    # dynamics are therefore computed at one speed, the model's own V0, whatever the chunk holds
    # (points that differ only in V share them: in a load x arm x speed sweep this divides the
    # work by the number of speeds); min_slip_velocity is then shifted by V - V0 and the stick-slip
    # test redone. Computing at V0 for every point, not at the first point of the chunk, keeps
    # each result independent of how the sweep is cut into chunks (at V = V0 the shift is an
    # exact 0).
    keys = sorted(point_params)
    if friction_law == "constant" and "sliding_speed" in point_params:
        shared = [k for k in keys if k != "sliding_speed"]
        rows = np.column_stack([np.asarray(point_params[k], dtype=np.float64) for k in shared]) if shared else np.zeros((n, 1))
        _, first, inverse = np.unique(rows, axis=0, return_index=True, return_inverse=True)
        inverse = inverse.ravel()
        v0 = float(model_values["sliding_speed"])
        sub = {k: np.asarray(point_params[k], dtype=np.float64)[first] for k in shared}
        sub["sliding_speed"] = np.full(first.size, v0)
        uniq = dynamics(model_values, contact, friction_law, sub, strategy, settings, n_points=first.size)
        out = {k: v[inverse] for k, v in uniq.items()}
        dv = np.asarray(point_params["sliding_speed"], dtype=np.float64) - v0
        out["min_slip_velocity"] = out["min_slip_velocity"] + dv
        cyc = np.isin(out["regime"], stages.CYCLE_REGIMES)
        off = np.nan_to_num(out["fraction_off_disk"]) > 0
        out["regime"] = np.where(
            cyc & ~(out["min_slip_velocity"] > 0), REGIME["stick_slip"],
            np.where(cyc & off, REGIME["contact_loss"], np.where(cyc, REGIME["self_excited"], out["regime"])),
        ).astype(np.uint8)  # fmt: skip
        # Work done once is shared evenly among the points that share it.
        share = np.bincount(inverse)[inverse]
        out["wall_time"] = out["wall_time"] / share
    else:
        out = dynamics(model_values, contact, friction_law, point_params, strategy, settings, n_points=n)
    out = {k: v.copy() for k, v in out.items()}
    if wear.get("calibration"):
        out.update({k: np.full(n, np.nan) for k in OPTIONAL_POINT_VARIABLES})

    # Wear (MODEL.md §8): only in the mild (steady-sliding) regime.
    mild = out["regime"] == REGIME["steady_sliding"]
    undetermined = out["regime"] == REGIME["failed"]
    out["wear_applicability"][:] = np.where(mild, 0, np.where(undetermined, 2, 1))
    if wear:
        rel = _wear.relative_wear_rate(
            full["normal_load"], full["sliding_speed"], out["normal_mode_frequency"],
            reference_load=wear["normal_load"], reference_speed=wear["sliding_speed"],
            reference_frequency_hz=wear["frequency_hz"],
        )  # fmt: skip
        out["wear_rate_relative"] = np.where(mild, np.broadcast_to(rel, (n,)), np.nan)
        calibration = wear.get("calibration")
        if calibration:
            absolute = _wear.calibrated_wear_rate(
                calibration, full["normal_load"], full["sliding_speed"], out["normal_mode_frequency"]
            )
            out["wear_rate"] = np.where(mild, np.broadcast_to(absolute, (n,)), np.nan)
    return out
